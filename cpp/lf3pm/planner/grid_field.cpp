#include "lf3pm/planner/grid_field.hpp"

#include <cmath>
#include <stdexcept>

namespace lf3pm {

namespace {

struct Axis {
  int i0, i1;
  double t;       // weight of i1
  double inside;  // 1 inside the centres' span, 0 where clamped (no gradient)
};

// Linear interpolation between cell centres along an axis of n cells.
Axis axis(double v, double origin, double res, int n) {
  if (n == 1) return {0, 0, 0.0, 0.0};
  const double f = (v - origin) / res - 0.5;
  if (f <= 0.0) return {0, 1, 0.0, f == 0.0 ? 1.0 : 0.0};
  if (f >= n - 1) return {n - 2, n - 1, 1.0, f == n - 1 ? 1.0 : 0.0};
  const int i = std::min(static_cast<int>(f), n - 2);
  return {i, i + 1, f - i, 1.0};
}

}  // namespace

GridField::GridField(std::vector<double> values, int nx, int ny, int layers, double x0, double y0, double res)
    : values_(std::move(values)), nx_(nx), ny_(ny), layers_(layers), x0_(x0), y0_(y0), res_(res) {
  if (nx < 1 || ny < 1 || layers < 1 || values_.size() != std::size_t(nx) * ny * layers)
    throw std::invalid_argument("grid field: values do not match layers x ny x nx");
  if (!(res > 0.0)) throw std::invalid_argument("grid field: resolution must be positive");
}

double GridField::sample(double x, double y, double yaw, Eigen::Vector3d& grad) const {
  const Axis ax = axis(x, x0_, res_, nx_), ay = axis(y, y0_, res_, ny_);
  int k0 = 0, k1 = 0;
  double tk = 0.0, step = 1.0;
  if (layers_ > 1) {
    step = 2.0 * M_PI / layers_;
    const double f = yaw / step;
    const double fl = std::floor(f);
    tk = f - fl;
    k0 = static_cast<int>(fl - layers_ * std::floor(fl / layers_));  // periodic: wraps any unwrapped yaw
    if (k0 >= layers_) k0 -= layers_;
    k1 = k0 + 1 == layers_ ? 0 : k0 + 1;
  }
  auto plane = [&](int k, double& dx, double& dy) {
    const double v00 = at(k, ay.i0, ax.i0), v01 = at(k, ay.i0, ax.i1);
    const double v10 = at(k, ay.i1, ax.i0), v11 = at(k, ay.i1, ax.i1);
    dx = ((1 - ay.t) * (v01 - v00) + ay.t * (v11 - v10)) / res_ * ax.inside;
    dy = ((1 - ax.t) * (v10 - v00) + ax.t * (v11 - v01)) / res_ * ay.inside;
    return (1 - ay.t) * ((1 - ax.t) * v00 + ax.t * v01) + ay.t * ((1 - ax.t) * v10 + ax.t * v11);
  };
  double adx, ady, bdx = 0.0, bdy = 0.0;
  const double a = plane(k0, adx, ady);
  const double b = layers_ > 1 ? plane(k1, bdx, bdy) : a;
  grad << (1 - tk) * adx + tk * bdx, (1 - tk) * ady + tk * bdy, layers_ > 1 ? (b - a) / step : 0.0;
  return (1 - tk) * a + tk * b;
}

}  // namespace lf3pm
