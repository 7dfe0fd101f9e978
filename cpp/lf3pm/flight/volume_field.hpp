// A regular grid of values over (x, y, z) with optional periodic yaw bins at each height,
// interpolated linearly along each axis with its gradient: an r3yaw SOLM's cost layer
// (layer iz * bins + ib, python/lf3pm/solm/reader.py) and, with one bin, the 3-D ESDF of a
// flight. Cell (ix, iy) is centred at (x0 + (ix + 0.5) res, y0 + (iy + 0.5) res), level iz at
// z0 + iz dz, bin ib at ib 2 pi / bins; positions beyond the outermost centres are clamped
// to them, and the gradient across a clamped axis is zero.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace lf3pm {

class VolumeField {
 public:
  VolumeField() = default;
  /// values[((iz * bins + ib) * ny + iy) * nx + ix]; every count >= 1, res and dz > 0.
  VolumeField(std::vector<double> values, int nx, int ny, int nz, int bins, double x0, double y0, double z0, double res,
              double dz);

  bool empty() const { return values_.empty(); }
  /// The value at (x, y, z, yaw); `grad` receives (d/dx, d/dy, d/dz, d/dyaw).
  double sample(const Eigen::Vector3d& p, double yaw, Eigen::Vector4d& grad) const;

 private:
  double at(int iz, int ib, int iy, int ix) const {
    return values_[((std::size_t(iz) * bins_ + ib) * ny_ + iy) * nx_ + ix];
  }
  std::vector<double> values_;
  int nx_ = 0, ny_ = 0, nz_ = 0, bins_ = 1;
  double x0_ = 0.0, y0_ = 0.0, z0_ = 0.0, res_ = 1.0, dz_ = 1.0;
};

}  // namespace lf3pm
