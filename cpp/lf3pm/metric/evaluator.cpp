#include "lf3pm/metric/evaluator.hpp"

#include <cmath>
#include <stdexcept>

#include "lf3pm/common/parallel.hpp"

namespace lf3pm {

namespace {
// Hits are reduced in fixed blocks and the block Grams summed in order, so the
// result is bitwise the same for every thread count.
constexpr std::size_t kGramBlock = 1024;

void check_dof(int dof) {
  if (dof != 3 && dof != 6) throw std::invalid_argument("dof must be 3 (x, y, yaw) or 6 (SE(3))");
}
}  // namespace

GramAccumulator scan_gram(const MapIndex& map, const Pose& pose, const SimulatedScan& scan, const EvalParams& params) {
  check_dof(params.dof);
  const std::size_t hits = scan.world_points.size();
  const std::size_t blocks = (hits + kGramBlock - 1) / kGramBlock;
  std::vector<GramAccumulator> partial(blocks, GramAccumulator(params.dof));
  parallel_for(blocks, 1, params.scan.threads, [&](std::size_t bb, std::size_t be) {
    double row[6];
    Eigen::Vector3d u, q;
    for (std::size_t blk = bb; blk < be; ++blk) {
      const std::size_t end = std::min(hits, (blk + 1) * kGramBlock);
      for (std::size_t j = blk * kGramBlock; j < end; ++j) {
        const Eigen::Vector3d& w = scan.world_points[j];
        if (!associate_hit(map, w, scan.surfel[j], params.association, &u, &q)) continue;
        const double h = observation_row(w, u, q, pose.position, params.dof, row);
        partial[blk].add(row, -h);
      }
    }
  });
  GramAccumulator total(params.dof);
  for (const auto& p : partial) total.merge(p);
  return total;
}

Observations scan_observations(const MapIndex& map, const Pose& pose, const SimulatedScan& scan,
                               const EvalParams& params) {
  check_dof(params.dof);
  const std::size_t hits = scan.world_points.size();
  std::vector<double> rows;
  std::vector<double> bs;
  Observations obs;
  double row[6];
  Eigen::Vector3d u, q;
  for (std::size_t j = 0; j < hits; ++j) {
    const Eigen::Vector3d& w = scan.world_points[j];
    if (!associate_hit(map, w, scan.surfel[j], params.association, &u, &q)) continue;
    const double h = observation_row(w, u, q, pose.position, params.dof, row);
    rows.insert(rows.end(), row, row + params.dof);
    bs.push_back(-h);
    obs.hit.push_back(static_cast<std::uint32_t>(j));
  }
  const Eigen::Index m = static_cast<Eigen::Index>(bs.size());
  obs.a = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(rows.data(), m,
                                                                                                   params.dof);
  obs.b = Eigen::Map<const Eigen::VectorXd>(bs.data(), m);
  return obs;
}

Metric weighted_metric(const GramAccumulator& gram, const EvalParams& params) {
  if (!(params.ray_weight >= 1.0)) throw std::invalid_argument("ray_weight must be >= 1");
  if (params.ray_weight == 1.0) return metric_from_gram(gram.gram(), gram.rows(), params.weights);
  return metric_from_gram(gram.gram() * params.ray_weight,
                          std::llround(static_cast<double>(gram.rows()) * params.ray_weight), params.weights);
}

PoseEvaluation evaluate_scan(const MapIndex& map, const Pose& pose, SimulatedScan scan, std::int64_t rays,
                             const EvalParams& params, PoseObservations* observations) {
  const GramAccumulator gram = scan_gram(map, pose, scan, params);
  PoseEvaluation out;
  out.metric = weighted_metric(gram, params);
  out.rays = rays;
  out.hits = static_cast<std::int64_t>(scan.world_points.size());
  if (observations != nullptr) {
    observations->observations = scan_observations(map, pose, scan, params);
    observations->scan = std::move(scan);
  }
  return out;
}

PoseEvaluation evaluate_pose(const MapIndex& map, const Pose& pose, const double* directions, std::size_t count,
                             const EvalParams& params, PoseObservations* observations) {
  return evaluate_scan(map, pose, simulate_scan(map, pose, directions, count, params.scan),
                       static_cast<std::int64_t>(count), params, observations);
}

PoseEvaluation evaluate_points(const MapIndex& map, const Pose& pose, const double* points, std::size_t count,
                               const EvalParams& params, PoseObservations* observations) {
  if (params.association != Association::Knn)
    throw std::invalid_argument("a recorded scan's points are associated by k-NN (no ray hit a map point)");
  return evaluate_scan(map, pose, scan_of_points(pose, points, count, params.scan), static_cast<std::int64_t>(count),
                       params, observations);
}

std::vector<PoseEvaluation> evaluate_poses(const MapIndex& map, const std::vector<Pose>& poses,
                                           const std::vector<std::uint64_t>& streams, const double* directions,
                                           std::size_t count, const EvalParams& params) {
  if (streams.size() != poses.size()) throw std::invalid_argument("one noise stream per pose");
  std::vector<PoseEvaluation> out(poses.size());
  parallel_for(poses.size(), 1, params.scan.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      EvalParams one = params;
      one.scan.threads = 1;
      one.scan.stream = streams[i];
      out[i] = evaluate_pose(map, poses[i], directions, count, one);
    }
  });
  return out;
}

}  // namespace lf3pm
