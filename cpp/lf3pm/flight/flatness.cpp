#include "lf3pm/flight/flatness.hpp"

#include <cmath>
#include <stdexcept>
#include <unsupported/Eigen/AutoDiff>

namespace lf3pm {

namespace {

// The map's inputs: v, a, j (3 each), psi, psi'.
constexpr int kInputs = 11;
using Grad = Eigen::Matrix<double, kInputs, 1>;
using Dual = Eigen::AutoDiffScalar<Grad>;

template <typename S>
struct Attitude {
  S thrust, cos_tilt;
  S r[3][3];
  S w[3];
};

// The expressions of the header, for S = double or Dual. False where singular.
template <typename S>
bool flat_map(const QuadrotorParams& p, const S v[3], const S a[3], const S j[3], const S& psi, const S& dpsi,
              Attitude<S>* out) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const double drag[3] = {p.drag_h, p.drag_h, p.drag_v};
  S t[3], dt[3];
  for (int i = 0; i < 3; ++i) {
    t[i] = p.mass * a[i] + drag[i] * v[i];
    dt[i] = p.mass * j[i] + drag[i] * a[i];
  }
  t[2] += p.mass * p.gravity;
  const S f = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
  if (!(f > 0.0)) return false;
  S z[3], dz[3];
  for (int i = 0; i < 3; ++i) z[i] = t[i] / f;
  const S along = z[0] * dt[0] + z[1] * dt[1] + z[2] * dt[2];
  for (int i = 0; i < 3; ++i) dz[i] = (dt[i] - z[i] * along) / f;
  const S s = 1.0 + z[2];
  if (!(s > 0.0)) return false;
  const S tilt[3][3] = {{1.0 - z[0] * z[0] / s, -z[0] * z[1] / s, z[0]},
                        {-z[0] * z[1] / s, 1.0 - z[1] * z[1] / s, z[1]},
                        {-z[0], -z[1], z[2]}};
  const S c = cos(psi), sn = sin(psi);
  for (int r = 0; r < 3; ++r) {  // R = R_tilt Rz(psi)
    out->r[r][0] = tilt[r][0] * c + tilt[r][1] * sn;
    out->r[r][1] = -tilt[r][0] * sn + tilt[r][1] * c;
    out->r[r][2] = tilt[r][2];
  }
  out->w[0] = sn * dz[0] - c * dz[1] - (z[0] * sn - z[1] * c) * dz[2] / s;
  out->w[1] = c * dz[0] + sn * dz[1] - (z[0] * c + z[1] * sn) * dz[2] / s;
  out->w[2] = (z[1] * dz[0] - z[0] * dz[1]) / s + dpsi;
  out->thrust = f;
  out->cos_tilt = z[2];
  return true;
}

}  // namespace

FlatnessMap::FlatnessMap(const QuadrotorParams& params) : params_(params) {
  if (!(params.mass > 0.0) || !(params.gravity > 0.0))
    throw std::invalid_argument("a quadrotor's mass and gravity must be positive");
  if (!(params.drag_h >= 0.0) || !(params.drag_v >= 0.0))
    throw std::invalid_argument("a quadrotor's drag coefficients must be >= 0");
}

bool FlatnessMap::forward(const FlatState& s, FlatAttitude* out) const {
  Attitude<double> at;
  if (!flat_map<double>(params_, s.velocity.data(), s.acceleration.data(), s.jerk.data(), s.yaw, s.yaw_rate, &at))
    return false;
  out->thrust = at.thrust;
  out->cos_tilt = at.cos_tilt;
  for (int r = 0; r < 3; ++r) {
    out->omega[r] = at.w[r];
    for (int c = 0; c < 3; ++c) out->rotation(r, c) = at.r[r][c];
  }
  return true;
}

FlatGradient FlatnessMap::backward(const FlatState& s, const AttitudeGradient& g) const {
  Dual v[3], a[3], j[3];
  for (int i = 0; i < 3; ++i) {
    v[i] = Dual(s.velocity[i], kInputs, i);
    a[i] = Dual(s.acceleration[i], kInputs, 3 + i);
    j[i] = Dual(s.jerk[i], kInputs, 6 + i);
  }
  const Dual psi(s.yaw, kInputs, 9), dpsi(s.yaw_rate, kInputs, 10);
  Attitude<Dual> at;
  FlatGradient out;
  if (!flat_map<Dual>(params_, v, a, j, psi, dpsi, &at)) return out;
  Grad total = g.thrust * at.thrust.derivatives() + g.cos_tilt * at.cos_tilt.derivatives();
  for (int r = 0; r < 3; ++r) {
    total += g.omega[r] * at.w[r].derivatives();
    for (int c = 0; c < 3; ++c) total += g.rotation(r, c) * at.r[r][c].derivatives();
  }
  out.velocity = total.segment<3>(0);
  out.acceleration = total.segment<3>(3);
  out.jerk = total.segment<3>(6);
  out.yaw = total[9];
  out.yaw_rate = total[10];
  return out;
}

}  // namespace lf3pm
