#include "lf3pm/plane_fit.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace lf3pm {

Plane fit_plane(const Eigen::Vector3d* points, int count) {
  Plane plane;
  if (count <= 0) return plane;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < count; ++i) mean += points[i];
  mean /= count;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d d = points[i] - mean;
    cov.noalias() += d * d.transpose();
  }
  // The iterative solver, not computeDirect: the closed form loses the smallest
  // eigenvector's accuracy exactly when the points are nearly planar.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  plane.normal = eig.eigenvectors().col(0).normalized();
  plane.centroid = mean;
  double worst = 0.0;
  for (int i = 0; i < count; ++i)
    worst = std::max(worst, std::abs(plane.normal.dot(points[i] - mean)));
  plane.max_distance = worst;
  return plane;
}

}  // namespace lf3pm
