#include "lf3pm/scan/scan_simulator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_set>

#include "lf3pm/common/parallel.hpp"
#include "lf3pm/common/random.hpp"

namespace lf3pm {
namespace {

// The scan of both overloads: pose_of(k) is the sensor pose ray k is cast from.
template <typename PoseOf>
SimulatedScan simulate(const MapIndex& map, PoseOf pose_of, const double* directions, std::size_t count,
                       const ScanParams& params) {
  if (!(params.max_range > params.min_range) || params.min_range < 0)
    throw std::invalid_argument("ranges must satisfy 0 <= min_range < max_range");
  if (!(params.noise_sigma >= 0)) throw std::invalid_argument("range noise sigma must be >= 0");
  params.returns.check();
  std::vector<double> range(count);
  std::vector<std::uint32_t> hit(count);
  parallel_for(count, 2048, params.threads, [&](std::size_t b, std::size_t e) {
    // Rays are cast one ahead of their refinement: the hit point's plane is in
    // two arrays of map size, mostly not in cache, and prefetching it while the
    // next ray is cast hides that latency.
    auto refine = [&](std::size_t k, const Eigen::Vector3d& d, const RayHit& h) {
      const Eigen::Vector3d& t = pose_of(k).position;
      hit[k] = h.surfel;
      if (h.surfel == kNoHit) return;
      // Refine the float range of the caster in float64 on the disc's own plane,
      // so a hit on a planar surface lies on it to rounding.
      const Eigen::Vector3d& n = map.normal(h.surfel);
      const double denom = n.dot(d);
      double s = std::abs(denom) > 1e-9 ? n.dot(map.points()[h.surfel] - t) / denom : h.range;
      if (!(std::abs(s - h.range) < 1e-3)) s = h.range;
      if (s < params.min_range) {
        hit[k] = kNoHit;  // blocked below the minimum range: no return
        return;
      }
      // The return is decided on the true range and incidence (d and n are unit vectors).
      if (!params.returns.empty() &&
          !ray_returns(params.returns.at(s, std::abs(denom)), params.seed, params.stream, k)) {
        hit[k] = kNoHit;
        return;
      }
      if (params.noise_sigma > 0) s += params.noise_sigma * normal_sample(params.seed, params.stream, k);
      if (s < params.min_range || s > params.max_range) hit[k] = kNoHit;
      range[k] = s;
    };
    Eigen::Vector3d pending_d;
    RayHit pending;
    for (std::size_t k = b; k < e; ++k) {
      const Pose& pose = pose_of(k);
      const Eigen::Vector3d d = pose.rotation * Eigen::Vector3d(directions + 3 * k);
      const RayHit h = map.caster().cast(pose.position, d, params.max_range);
      if (h.surfel != kNoHit) {
        __builtin_prefetch(&map.normal(h.surfel));
        __builtin_prefetch(&map.points()[h.surfel]);
      }
      if (k > b) refine(k - 1, pending_d, pending);
      pending_d = d;
      pending = h;
    }
    if (e > b) refine(e - 1, pending_d, pending);
  });
  SimulatedScan scan;
  const std::size_t hits = count - static_cast<std::size_t>(std::count(hit.begin(), hit.end(), kNoHit));
  scan.sensor_points.reserve(hits);
  scan.world_points.reserve(hits);
  scan.surfel.reserve(hits);
  scan.ray.reserve(hits);
  FirstPerVoxel voxels(params.scan_voxel);
  for (std::size_t k = 0; k < count; ++k) {
    if (hit[k] == kNoHit) continue;
    const Eigen::Vector3d p = range[k] * Eigen::Vector3d(directions + 3 * k);
    if (!voxels.keep(p)) continue;
    const Pose& pose = pose_of(k);
    scan.sensor_points.push_back(p);
    scan.world_points.push_back(pose.rotation * p + pose.position);
    scan.surfel.push_back(hit[k]);
    scan.ray.push_back(static_cast<std::uint32_t>(k));
  }
  return scan;
}

bool finite(const Pose& pose) { return pose.rotation.allFinite() && pose.position.allFinite(); }

}  // namespace

bool FirstPerVoxel::keep(const Eigen::Vector3d& p) {
  if (!(edge_ > 0)) return true;
  const auto q = [&](double v) { return static_cast<std::uint64_t>(std::floor(v / edge_) + (1 << 20)) & 0x1FFFFFu; };
  const std::uint64_t key = q(p.x()) | (q(p.y()) << 21) | (q(p.z()) << 42);
  return kept_.insert(key).second;
}

SimulatedScan scan_of_points(const Pose& pose, const double* points, std::size_t count, const ScanParams& params) {
  if (!finite(pose)) throw std::invalid_argument("the pose is not finite");
  SimulatedScan scan;
  FirstPerVoxel voxels(params.scan_voxel);
  for (std::size_t k = 0; k < count; ++k) {
    const Eigen::Vector3d p(points + 3 * k);
    if (!p.allFinite()) throw std::invalid_argument("point " + std::to_string(k) + " is not finite");
    if (!voxels.keep(p)) continue;
    scan.sensor_points.push_back(p);
    scan.world_points.push_back(pose.rotation * p + pose.position);
    scan.surfel.push_back(kNoHit);
    scan.ray.push_back(static_cast<std::uint32_t>(k));
  }
  return scan;
}

SimulatedScan simulate_scan(const MapIndex& map, const Pose& pose, const double* directions, std::size_t count,
                            const ScanParams& params) {
  if (!finite(pose)) throw std::invalid_argument("the pose is not finite");
  return simulate(map, [&](std::size_t) -> const Pose& { return pose; }, directions, count, params);
}

SimulatedScan simulate_scan(const MapIndex& map, const Pose* ray_poses, const double* directions, std::size_t count,
                            const ScanParams& params) {
  for (std::size_t k = 0; k < count; ++k)
    if (!finite(ray_poses[k])) throw std::invalid_argument("the pose of ray " + std::to_string(k) + " is not finite");
  return simulate(map, [&](std::size_t k) -> const Pose& { return ray_poses[k]; }, directions, count, params);
}

}  // namespace lf3pm
