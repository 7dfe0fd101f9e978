#include "lf3pm/flight/volume_field.hpp"

#include <cmath>
#include <stdexcept>

namespace lf3pm {

namespace {

// Linear interpolation between the centres of n cells along one axis (centre i at
// origin + i step): the two indices, the weight of the upper one, and the derivative
// factor (0 where clamped).
struct Axis {
  int i0, i1;
  double t, inside;
};

Axis axis(double v, double origin, double step, int n) {
  if (n < 2) return {0, 0, 0.0, 0.0};
  double f = (v - origin) / step;
  const double inside = (f >= 0.0 && f <= n - 1) ? 1.0 : 0.0;
  f = std::fmin(std::fmax(f, 0.0), double(n - 1));
  const int i0 = std::min(int(std::floor(f)), n - 2);
  return {i0, i0 + 1, f - i0, inside};
}

}  // namespace

VolumeField::VolumeField(std::vector<double> values, int nx, int ny, int nz, int bins, double x0, double y0, double z0,
                         double res, double dz)
    : values_(std::move(values)),
      nx_(nx),
      ny_(ny),
      nz_(nz),
      bins_(bins),
      x0_(x0),
      y0_(y0),
      z0_(z0),
      res_(res),
      dz_(dz) {
  if (nx < 1 || ny < 1 || nz < 1 || bins < 1) throw std::invalid_argument("a volume field needs at least one cell");
  if (!(res > 0) || !(dz > 0)) throw std::invalid_argument("a volume field's res and dz must be > 0");
  if (values_.size() != std::size_t(nx) * ny * nz * bins)
    throw std::invalid_argument("a volume field needs nx * ny * nz * bins values");
  for (double v : values_)
    if (!std::isfinite(v)) throw std::invalid_argument("a volume field's values must be finite");
}

double VolumeField::sample(const Eigen::Vector3d& p, double yaw, Eigen::Vector4d& grad) const {
  const Axis ax = axis(p.x(), x0_ + 0.5 * res_, res_, nx_);
  const Axis ay = axis(p.y(), y0_ + 0.5 * res_, res_, ny_);
  const Axis az = axis(p.z(), z0_, dz_, nz_);
  // Yaw: periodic, bin b centred on b * step.
  const double step = 2.0 * M_PI / bins_;
  double fb = std::fmod(yaw, 2.0 * M_PI);
  if (fb < 0) fb += 2.0 * M_PI;
  fb /= step;
  const int b0 = int(std::floor(fb)) % bins_, b1 = (b0 + 1) % bins_;
  const double tb = bins_ > 1 ? fb - std::floor(fb) : 0.0;
  double value = 0.0;
  grad.setZero();
  const int zs[2] = {az.i0, az.i1}, bs[2] = {b0, b1}, ys[2] = {ay.i0, ay.i1}, xs[2] = {ax.i0, ax.i1};
  const double wz[2] = {1 - az.t, az.t}, wb[2] = {1 - tb, tb}, wy[2] = {1 - ay.t, ay.t}, wx[2] = {1 - ax.t, ax.t};
  const double sz[2] = {-1.0, 1.0};
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 2; ++c)
        for (int d = 0; d < 2; ++d) {
          const double v = at(zs[a], bs[b], ys[c], xs[d]);
          value += wz[a] * wb[b] * wy[c] * wx[d] * v;
          grad[0] += wz[a] * wb[b] * wy[c] * sz[d] * v;
          grad[1] += wz[a] * wb[b] * sz[c] * wx[d] * v;
          grad[2] += sz[a] * wb[b] * wy[c] * wx[d] * v;
          grad[3] += wz[a] * sz[b] * wy[c] * wx[d] * v;
        }
  grad[0] *= ax.inside / res_;
  grad[1] *= ay.inside / res_;
  grad[2] *= az.inside / dz_;
  grad[3] *= bins_ > 1 ? 1.0 / step : 0.0;
  return value;
}

}  // namespace lf3pm
