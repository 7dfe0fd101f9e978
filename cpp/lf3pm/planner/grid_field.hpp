// A regular grid of values over (x, y), optionally with periodic yaw layers,
// interpolated bilinearly (trilinearly with yaw) with its gradient. Used for
// the SOLM cost and the ESDF in trajectory optimisation.
//
// Conventions are the SOLM's (python/lf3pm/solm/reader.py): cell (i, j) has its
// centre at (x0 + (i + 0.5) res, y0 + (j + 0.5) res); yaw layer k is centred on
// k * 2 pi / layers. Positions beyond the outermost cell centres are clamped to
// them, and the gradient across a clamped axis is zero.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace lf3pm {

class GridField {
 public:
  GridField() = default;
  /// values[(k * ny + j) * nx + i] is the value at yaw layer k, row j (y), column i (x); layers >= 1.
  GridField(std::vector<double> values, int nx, int ny, int layers, double x0, double y0, double res);

  int nx() const { return nx_; }
  int ny() const { return ny_; }
  int layers() const { return layers_; }
  bool empty() const { return values_.empty(); }
  double x0() const { return x0_; }
  double y0() const { return y0_; }
  double res() const { return res_; }
  /// The stored value at yaw layer k, row j (y), column i (x).
  double at(int k, int j, int i) const { return values_[(std::size_t(k) * ny_ + j) * nx_ + i]; }

  /// Value at (x, y, yaw); `grad` receives (d/dx, d/dy, d/dyaw). Yaw is ignored with one layer.
  double sample(double x, double y, double yaw, Eigen::Vector3d& grad) const;

 private:
  std::vector<double> values_;
  int nx_ = 0, ny_ = 0, layers_ = 1;
  double x0_ = 0.0, y0_ = 0.0, res_ = 1.0;
};

}  // namespace lf3pm
