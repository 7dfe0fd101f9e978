#include "lf3pm/map/plane_fit.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace lf3pm {

namespace {

// Below this ratio of the two nonzero eigenvalues of (C - lambda_min I) the
// points are nearly collinear (or the two smallest eigenvalues nearly equal):
// the normal is then ill-conditioned and left to the iterative solver, which
// also keeps the old normals of degenerate neighbourhoods (isolated points,
// pairs, exact lines) exactly as they were.
constexpr double kMinSeparation = 1e-4;
// Above this bound on mu1 / mu2 (see below) the first eigenvector is already
// accurate to about 1e-12 rad and needs no refinement.
constexpr double kRefineBelow = 1e-2;

// Unit eigenvector of the smallest eigenvalue of the symmetric positive
// semi-definite matrix c, or false when that eigenvalue is not well separated.
//
// The iterative solver costs about 250 ns here, most of the fit. Instead: the
// smallest root of the characteristic polynomial by Newton's method, then the
// eigenvector as the largest cross product of two rows of c - lambda I (each
// is orthogonal to both rows, which span the other two eigenvectors). About
// 90 ns, and within 1e-9 rad of numpy.linalg.eigh wherever the separation
// check passes (tests/test_association.py).
bool smallest_eigenvector(const Eigen::Matrix3d& c, Eigen::Vector3d* v) {
  const double scale = c.cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) return false;
  const Eigen::Matrix3d a = c / scale;  // entries in [-1, 1]: the cubic cannot overflow
  // det(lambda I - a) = lambda^3 - t lambda^2 + s lambda - d.
  const double t = a.trace();
  const double s = a(0, 0) * a(1, 1) - a(0, 1) * a(0, 1) + a(0, 0) * a(2, 2) - a(0, 2) * a(0, 2) + a(1, 1) * a(2, 2) -
                   a(1, 2) * a(1, 2);
  const double d = a.determinant();
  // From 0 (no root lies below it): left of its smallest root the cubic is
  // increasing and concave, so the iterates rise monotonically to the root;
  // they stop rising once rounding dominates.
  double lambda = 0.0;
  for (int it = 0; it < 64; ++it) {
    const double f = ((lambda - t) * lambda + s) * lambda - d;
    const double df = (3.0 * lambda - 2.0 * t) * lambda + s;
    const double next = lambda - f / df;
    if (!(next > lambda)) break;
    lambda = next;
  }
  for (int pass = 0;; ++pass) {
    const Eigen::Matrix3d m = a - lambda * Eigen::Matrix3d::Identity();
    const Eigen::Vector3d c01 = m.row(0).cross(m.row(1)), c02 = m.row(0).cross(m.row(2)),
                          c12 = m.row(1).cross(m.row(2));
    const double n01 = c01.squaredNorm(), n02 = c02.squaredNorm(), n12 = c12.squaredNorm();
    const Eigen::Vector3d& best = n01 >= n02 ? (n01 >= n12 ? c01 : c12) : (n02 >= n12 ? c02 : c12);
    const double best_sq = std::max({n01, n02, n12});
    // |cross| >= mu1 mu2 / sqrt(3) and |m|^2 = mu1^2 + mu2^2 for the nonzero
    // eigenvalues mu1 <= mu2 of m: the ratio bounds mu1 / mu2 from below.
    const double m_sq = m.squaredNorm();
    if (!(best_sq > kMinSeparation * kMinSeparation * m_sq * m_sq)) return false;
    *v = best / std::sqrt(best_sq);
    // The error of lambda (from the cubic's coefficients) reaches the vector
    // amplified by about (mu2 / mu1)^2: negligible for a patch of a surface, but
    // elongated sets get one Rayleigh-quotient step, which leaves only rounding.
    if (pass == 1 || best_sq > kRefineBelow * kRefineBelow * m_sq * m_sq) return true;
    lambda = v->dot(a * *v);
  }
}

}  // namespace

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
  if (count < 3 || !smallest_eigenvector(cov, &plane.normal)) {
    // The iterative solver, not computeDirect: the closed form loses the smallest
    // eigenvector's accuracy exactly when the points are nearly planar.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    plane.normal = eig.eigenvectors().col(0).normalized();
  }
  plane.centroid = mean;
  double worst = 0.0;
  for (int i = 0; i < count; ++i) worst = std::max(worst, std::abs(plane.normal.dot(points[i] - mean)));
  plane.max_distance = worst;
  return plane;
}

}  // namespace lf3pm
