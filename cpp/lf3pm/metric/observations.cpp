#include "lf3pm/metric/observations.hpp"

namespace lf3pm {

bool associate_hit(const MapIndex& map, const Eigen::Vector3d& w, std::uint32_t surfel, Association mode,
                   Eigen::Vector3d* normal, Eigen::Vector3d* centroid) {
  if (mode == Association::Surfel) {
    if (!map.plane_valid(surfel)) return false;
    *normal = map.normal(surfel);
    *centroid = map.centroid(surfel);
    return true;
  }
  Plane plane;
  if (!map.associate(w, &plane)) return false;
  *normal = plane.normal;
  *centroid = plane.centroid;
  return true;
}

Eigen::MatrixXd GramAccumulator::gram() const {
  Eigen::MatrixXd g(n_ + 1, n_ + 1);
  for (int i = 0; i <= n_; ++i)
    for (int j = i; j <= n_; ++j) g(i, j) = g(j, i) = gram_(i, j);
  return g;
}

}  // namespace lf3pm
