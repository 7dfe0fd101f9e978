// FAST-LIO point-to-plane observations: rows of A and b = -h for hits of a scan.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "lf3pm/map/map_index.hpp"

namespace lf3pm {

/// Explicit observations of a simulated scan (for export and tests).
struct Observations {
  Eigen::MatrixXd a;               // m x dof
  Eigen::VectorXd b;               // m
  std::vector<std::uint32_t> hit;  // row -> index into the scan's hits
};

enum class Association {
  Surfel,  // the precomputed plane of the map point the ray hit (no k-NN query)
  Knn,     // FAST-LIO exactly: k-NN of the hit in the map, plane fitted on the fly
};

/// Observation of one world point w against plane (u, q) seen from sensor
/// position t: row = [u^T, ((w - t) x u)^T] (6-DoF) or [u_x, u_y, ((w - t) x u)_z]
/// (x, y, yaw); returns h = u^T (w - q) (so b = -h).
inline double observation_row(const Eigen::Vector3d& w, const Eigen::Vector3d& u, const Eigen::Vector3d& q,
                              const Eigen::Vector3d& t, int dof, double* row) {
  const Eigen::Vector3d lever = (w - t).cross(u);
  if (dof == 6) {
    row[0] = u.x();
    row[1] = u.y();
    row[2] = u.z();
    row[3] = lever.x();
    row[4] = lever.y();
    row[5] = lever.z();
  } else {
    row[0] = u.x();
    row[1] = u.y();
    row[2] = lever.z();
  }
  return u.dot(w - q);
}

/// Associates world point w (a hit on map point `surfel`); false if rejected.
bool associate_hit(const MapIndex& map, const Eigen::Vector3d& w, std::uint32_t surfel, Association mode,
                   Eigen::Vector3d* normal, Eigen::Vector3d* centroid);

/// Running Gram of [A | b] (upper triangle accumulated, symmetric on output).
class GramAccumulator {
 public:
  explicit GramAccumulator(int dof) : n_(dof) { gram_.setZero(); }
  void add(const double* row, double b) {
    double x[7];
    for (int i = 0; i < n_; ++i) x[i] = row[i];
    x[n_] = b;
    for (int i = 0; i <= n_; ++i)
      for (int j = i; j <= n_; ++j) gram_(i, j) += x[i] * x[j];
    ++rows_;
  }
  void merge(const GramAccumulator& other) {
    gram_ += other.gram_;
    rows_ += other.rows_;
  }
  std::int64_t rows() const { return rows_; }
  /// The (n+1) x (n+1) symmetric Gram.
  Eigen::MatrixXd gram() const;

 private:
  int n_;
  Eigen::Matrix<double, 7, 7> gram_;
  std::int64_t rows_ = 0;
};

}  // namespace lf3pm
