#include "lf3pm/flight/flight_cost.hpp"

#include <cmath>
#include <stdexcept>

namespace lf3pm {

namespace {

// P(z) = max(z, 0)^3 and its derivative.
inline double cubic(double z, double& dz) {
  if (z <= 0.0) {
    dz = 0.0;
    return 0.0;
  }
  dz = 3.0 * z * z;
  return z * z * z;
}

constexpr double kClearanceScale = 0.1;  // m: the clearance penalty's unit

}  // namespace

FlightCost::FlightCost(const QuadrotorParams& params, const QuadrotorLimits& limits, const FlightWeights& weights,
                       VolumeField guidance, VolumeField esdf)
    : flatness_(params), limits_(limits), weights_(weights), guidance_(std::move(guidance)), esdf_(std::move(esdf)) {
  if (!(limits.vmax > 0) || !(limits.omega_max > 0) || !(limits.tilt_max > 0) || !(limits.tilt_max < M_PI / 2))
    throw std::invalid_argument("flight limits: vmax, omega_max > 0 and tilt_max in (0, pi / 2)");
  if (!(limits.thrust_max > limits.thrust_min) || !(limits.thrust_min >= 0))
    throw std::invalid_argument("flight limits: 0 <= thrust_min < thrust_max");
  if (weights.samples < 1) throw std::invalid_argument("at least one sample per piece");
}

double FlightCost::evaluate(const MincoS3::Coefficients& c, const Eigen::VectorXd& T, MincoS3::Coefficients& grad_c,
                            Eigen::VectorXd& grad_t, FlightTerms* terms) const {
  const int n = int(T.size()), k = weights_.samples;
  const double cos_tilt_max = std::cos(limits_.tilt_max);
  const double f_mid = 0.5 * (limits_.thrust_max + limits_.thrust_min);
  const double f_half = 0.5 * (limits_.thrust_max - limits_.thrust_min);
  const double w = weights_.penalty;
  FlightTerms local;
  double total = 0.0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix<double, 6, 4> ci = c.middleRows<6>(6 * i);
    const double step = T(i) / k;
    for (int j = 0; j <= k; ++j) {
      const double t = j * step;
      const double weight = (j == 0 || j == k) ? 0.5 : 1.0;  // trapezoid
      // Derivatives 0..4 of (x, y, z, yaw) at t.
      Eigen::Matrix<double, 5, 4> d;
      for (int order = 0; order < 5; ++order) d.row(order) = quintic_basis(t, order) * ci;
      FlatState s;
      s.velocity = d.row(1).head<3>().transpose();
      s.acceleration = d.row(2).head<3>().transpose();
      s.jerk = d.row(3).head<3>().transpose();
      s.yaw = d(0, 3);
      s.yaw_rate = d(1, 3);
      const Eigen::Vector3d p = d.row(0).head<3>().transpose();
      FlatAttitude at;
      if (!flatness_.forward(s, &at)) throw std::invalid_argument("a trajectory sample has no thrust direction");
      AttitudeGradient ga;
      double f = 0.0, dz = 0.0;
      Eigen::Vector3d g_p = Eigen::Vector3d::Zero(), g_v = Eigen::Vector3d::Zero();
      double g_yaw = 0.0;
      // Speed.
      const double speed = cubic(s.velocity.squaredNorm() / (limits_.vmax * limits_.vmax) - 1.0, dz);
      f += w * speed, local.speed += weight * step * speed;
      g_v += w * dz * 2.0 * s.velocity / (limits_.vmax * limits_.vmax);
      // Body rate.
      const double omega = cubic(at.omega.squaredNorm() / (limits_.omega_max * limits_.omega_max) - 1.0, dz);
      f += w * omega, local.omega += weight * step * omega;
      ga.omega = w * dz * 2.0 * at.omega / (limits_.omega_max * limits_.omega_max);
      // Tilt.
      const double tilt = cubic((cos_tilt_max - at.cos_tilt) / (1.0 - cos_tilt_max), dz);
      f += w * tilt, local.tilt += weight * step * tilt;
      ga.cos_tilt = -w * dz / (1.0 - cos_tilt_max);
      // Thrust.
      const double off = (at.thrust - f_mid) / f_half;
      const double thrust = cubic(off * off - 1.0, dz);
      f += w * thrust, local.thrust += weight * step * thrust;
      ga.thrust = w * dz * 2.0 * off / f_half;
      // Clearance.
      if (!esdf_.empty()) {
        Eigen::Vector4d g;
        const double dist = esdf_.sample(p, 0.0, g);
        const double clear = cubic((weights_.r_safe + weights_.esdf_margin - dist) / kClearanceScale, dz);
        f += w * clear, local.clearance += weight * step * clear;
        g_p -= w * dz / kClearanceScale * g.head<3>();
      }
      // Guidance.
      if (!guidance_.empty() && weights_.w_q != 0.0) {
        Eigen::Vector4d g;
        const double q = guidance_.sample(p, s.yaw, g);
        f += weights_.w_q * q, local.guidance += weight * step * q;
        g_p += weights_.w_q * g.head<3>();
        g_yaw += weights_.w_q * g(3);
      }
      // Yaw along the velocity.
      if (weights_.w_heading != 0.0) {
        const double sn = std::sin(s.yaw), cs = std::cos(s.yaw);
        const double lateral = s.velocity.x() * sn - s.velocity.y() * cs;
        f += weights_.w_heading * lateral * lateral, local.heading += weight * step * lateral * lateral;
        const double k2 = 2.0 * weights_.w_heading * lateral;
        g_v.x() += k2 * sn;
        g_v.y() -= k2 * cs;
        g_yaw += k2 * (s.velocity.x() * cs + s.velocity.y() * sn);
      }
      total += weight * step * f;
      // Back to the flat outputs' derivatives, then to the coefficients and T.
      // Inside every limit the penalties' gradients are zero: no backward pass (most samples).
      const bool penalised = ga.thrust != 0.0 || ga.cos_tilt != 0.0 || !ga.omega.isZero();
      const FlatGradient gf = penalised ? flatness_.backward(s, ga) : FlatGradient{};
      Eigen::Matrix<double, 4, 4> g_d = Eigen::Matrix<double, 4, 4>::Zero();  // by derivative order 0..3, dims
      g_d.row(0) << g_p.transpose(), g_yaw + gf.yaw;
      g_d.row(1) << (g_v + gf.velocity).transpose(), gf.yaw_rate;
      g_d.row(2) << gf.acceleration.transpose(), 0.0;
      g_d.row(3) << gf.jerk.transpose(), 0.0;
      const double scale = weight * step;
      for (int order = 0; order < 4; ++order)
        grad_c.middleRows<6>(6 * i) += scale * quintic_basis(t, order).transpose() * g_d.row(order);
      // T_i moves the sample (t = j T_i / K) and scales its time weight.
      double along = 0.0;
      for (int order = 0; order < 4; ++order) along += g_d.row(order).dot(d.row(order + 1));
      grad_t(i) += weight / k * f + scale * along * double(j) / k;
    }
  }
  if (terms) *terms = local;
  return total;
}

}  // namespace lf3pm
