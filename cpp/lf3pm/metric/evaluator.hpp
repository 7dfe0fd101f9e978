// One pose's evaluation, end to end: simulate the scan, associate its hits,
// accumulate the Gram of [A | b] and compute the metric.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "lf3pm/map/map_index.hpp"
#include "lf3pm/metric/metric.hpp"
#include "lf3pm/metric/observations.hpp"
#include "lf3pm/scan/scan_simulator.hpp"

namespace lf3pm {

struct EvalParams {
  ScanParams scan;
  int dof = 6;
  Association association = Association::Knn;  // FAST-LIO's, as everywhere (docs/metric.md)
  MetricWeights weights;
  // Each simulated ray stands for this many rays of the full pattern (thinned
  // SOLM builds): the Gram and the row count are scaled by it before the metric,
  // which makes the metric of the thinned scan an estimate of the full scan's.
  double ray_weight = 1.0;
};

struct PoseEvaluation {
  Metric metric;
  std::int64_t rays = 0;  // sensor rays cast
  std::int64_t hits = 0;  // rays with a return (after scan downsampling)
};

/// One pose's explicit observations with the scan they came from (for export and tests).
struct PoseObservations {
  SimulatedScan scan;
  Observations observations;
};

/// Simulates the scan at `pose` and computes its metric; given `observations`, also fills
/// in that same scan and its explicit observations.
PoseEvaluation evaluate_pose(const MapIndex& map, const Pose& pose, const double* directions, std::size_t count,
                             const EvalParams& params, PoseObservations* observations = nullptr);

/// The metric of a scan's hits at `pose` (what evaluate_pose does once it has its scan):
/// association, Gram and metric; `rays` is what PoseEvaluation reports as cast.
PoseEvaluation evaluate_scan(const MapIndex& map, const Pose& pose, SimulatedScan scan, std::int64_t rays,
                             const EvalParams& params, PoseObservations* observations = nullptr);

/// The metric of a recorded scan: `count` sensor-frame points (x, y, z, row-major) at
/// `pose`, downsampled and evaluated as a simulated scan's hits are (scan_of_points, then
/// evaluate_scan). Needs k-NN association (no ray hit a map point); rays = count.
PoseEvaluation evaluate_points(const MapIndex& map, const Pose& pose, const double* points, std::size_t count,
                               const EvalParams& params, PoseObservations* observations = nullptr);

/// The metric of an accumulated Gram, scaled by params.ray_weight.
Metric weighted_metric(const GramAccumulator& gram, const EvalParams& params);

/// The Gram of [A | b] of a scan and its row count; deterministic for any thread count.
GramAccumulator scan_gram(const MapIndex& map, const Pose& pose, const SimulatedScan& scan, const EvalParams& params);

Observations scan_observations(const MapIndex& map, const Pose& pose, const SimulatedScan& scan,
                               const EvalParams& params);

/// Many poses in parallel (one thread per pose; params.scan.threads is the pool
/// size). Pose i draws its noise from stream streams[i], so a pose's result does
/// not depend on which batch it was evaluated in.
std::vector<PoseEvaluation> evaluate_poses(const MapIndex& map, const std::vector<Pose>& poses,
                                           const std::vector<std::uint64_t>& streams, const double* directions,
                                           std::size_t count, const EvalParams& params);

}  // namespace lf3pm
