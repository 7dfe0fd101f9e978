// Least-squares plane through a few points (the FAST-LIO association plane).
#pragma once

#include <Eigen/Core>

namespace lf3pm {

struct Plane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit; sign arbitrary
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double max_distance = 0.0;  // largest |distance| of the fitted points to the plane
};

/// Plane of smallest squared orthogonal distance (PCA) through points[0..count).
/// FAST-LIO fits a*x + b*y + c*z + 1 = 0 instead, which fails for planes through
/// the origin; PCA has no such blind spot and gives the same plane otherwise.
Plane fit_plane(const Eigen::Vector3d* points, int count);

}  // namespace lf3pm
