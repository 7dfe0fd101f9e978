// Simulated LiDAR scans on a point-cloud map: a pose (or one pose per ray, for a
// moving sensor) and the sensor's ray directions in, the hit points out
// (emission order, rays without a return dropped).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <unordered_set>
#include <vector>

#include "lf3pm/common/pose.hpp"
#include "lf3pm/map/map_index.hpp"
#include "lf3pm/scan/return_model.hpp"

namespace lf3pm {

struct ScanParams {
  double min_range = 0.0;  // nearer first hits give no return (they still block the ray)
  double max_range = 100.0;
  double noise_sigma = 0.0;  // Gaussian range noise (m), 1 sigma
  std::uint64_t seed = 0;
  std::uint64_t stream = 0;  // independent noise per pose under one seed
  double scan_voxel = 0.0;   // keep the first hit per voxel of this edge (sensor frame); 0 = off
  int threads = 0;           // 0 = all cores
  ReturnModel returns;       // which hits return (drawn per ray like the noise); empty: all
};

struct SimulatedScan {
  std::vector<Eigen::Vector3d> sensor_points;  // in the sensor frame
  std::vector<Eigen::Vector3d> world_points;
  std::vector<std::uint32_t> surfel;  // map point hit
  std::vector<std::uint32_t> ray;     // index of the sensor ray
};

/// directions: `count` unit vectors (x, y, z) in the sensor frame, row-major.
SimulatedScan simulate_scan(const MapIndex& map, const Pose& pose, const double* directions, std::size_t count,
                            const ScanParams& params);

/// A scan taken while the sensor moves (motion distortion): ray k is cast from
/// ray_poses[k], the sensor pose at its firing time (`count` poses). sensor_points
/// are then each in its own ray's sensor frame (what the sensor measured), and
/// scan_voxel keys on those. The noise of ray k is the same as in simulate_scan.
SimulatedScan simulate_scan(const MapIndex& map, const Pose* ray_poses, const double* directions, std::size_t count,
                            const ScanParams& params);

/// The scan_voxel downsampling of a scan's hits: keeps a sensor-frame point when it is the
/// first in its voxel of edge `edge` (0 = keep every point). Simulated and recorded scans
/// share it.
class FirstPerVoxel {
 public:
  explicit FirstPerVoxel(double edge) : edge_(edge) {}
  bool keep(const Eigen::Vector3d& p);

 private:
  double edge_;
  std::unordered_set<std::uint64_t> kept_;
};

/// A recorded scan as a scan's hits: `count` sensor-frame points (x, y, z, row-major) seen
/// from `pose`, downsampled by params.scan_voxel as a simulated scan's hits are (no range
/// limits applied: they are what the sensor returned). surfel is kNoHit (no ray hit a map
/// point), ray the point's index.
SimulatedScan scan_of_points(const Pose& pose, const double* points, std::size_t count, const ScanParams& params);

}  // namespace lf3pm
