#include "lf3pm/metric/yaw_sectors.hpp"

#include <cmath>
#include <stdexcept>

#include "lf3pm/common/parallel.hpp"

namespace lf3pm {

std::vector<Metric> evaluate_yaw_sectors(const MapIndex& map, const std::vector<Eigen::Vector3d>& positions,
                                         const std::vector<std::uint64_t>& streams, const double* sector_rays,
                                         std::size_t count, int bins, int half_width, const EvalParams& params) {
  if (bins < 1 || half_width < 0 || 2 * half_width + 1 > bins)
    throw std::invalid_argument("need bins >= 1 and 0 <= 2 * half_width + 1 <= bins");
  if (streams.size() != positions.size()) throw std::invalid_argument("one noise stream per position");
  std::vector<Metric> out(positions.size() * bins);
  parallel_for(positions.size(), 1, params.scan.threads, [&](std::size_t b, std::size_t e) {
    std::vector<GramAccumulator> sector(bins, GramAccumulator(params.dof));
    for (std::size_t i = b; i < e; ++i) {
      EvalParams one = params;
      one.scan.threads = 1;
      for (int j = 0; j < bins; ++j) {
        const double yaw = 2.0 * M_PI * j / bins;
        Pose pose;
        pose.rotation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        pose.position = positions[i];
        one.scan.stream = streams[i] * static_cast<std::uint64_t>(bins) + j;
        const SimulatedScan scan = simulate_scan(map, pose, sector_rays, count, one.scan);
        sector[j] = scan_gram(map, pose, scan, one);
      }
      for (int k = 0; k < bins; ++k) {
        GramAccumulator total(params.dof);
        for (int o = -half_width; o <= half_width; ++o) total.merge(sector[((k + o) % bins + bins) % bins]);
        out[i * bins + k] = weighted_metric(total, params);
      }
    }
  });
  return out;
}

}  // namespace lf3pm
