#include "lf3pm/trajectory_cost.hpp"

#include <cmath>
#include <stdexcept>

namespace lf3pm {

namespace {

// W * max(z, 0)^3 into `sum`; returns its derivative by z.
inline double cubic_penalty(double z, double weight, double& sum) {
  if (z <= 0.0) return 0.0;
  sum += weight * z * z * z;
  return 3.0 * weight * z * z;
}

}  // namespace

TrajectoryCost::TrajectoryCost(GridField cost, GridField esdf, const RobotLimits& robot, const CostWeights& weights)
    : cost_(std::move(cost)), esdf_(std::move(esdf)), robot_(robot), weights_(weights) {
  if (weights_.samples < 1) throw std::invalid_argument("samples per piece must be >= 1");
}

void TrajectoryCost::add(const MincoS2& minco, const Eigen::VectorXd& lambda, double rho, Eigen::MatrixX3d& grad_c,
                         Eigen::VectorXd& grad_t, CostTerms& terms, Eigen::VectorXd* h) const {
  const int n = minco.pieces(), k_max = weights_.samples;
  if (lambda.size() != equality_count(n)) throw std::invalid_argument("one multiplier per equality sample needed");
  if (h) h->resize(equality_count(n));
  const Eigen::MatrixX3d& coef = minco.coefficients();
  const double w = weights_.penalty;
  // Speed limits are penalised relative to the limit (z = v^2 / vmax^2 - 1), so that
  // the same weight allows the same relative excess on every limit.
  const double ilon2 = 1.0 / (robot_.vmax_lon * robot_.vmax_lon), ilat2 = 1.0 / (robot_.vmax_lat * robot_.vmax_lat);
  const double iw2 = 1.0 / (robot_.wmax * robot_.wmax), r2 = robot_.min_turn_radius * robot_.min_turn_radius;
  const double clearance = robot_.r_safe + weights_.esdf_margin;
  const bool car = robot_.kind == RobotKind::Car && robot_.min_turn_radius > 0.0;
  Eigen::Vector3d field_grad;

  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix<double, 4, 3> c = coef.middleRows<4>(4 * i);
    const double dur = minco.durations()(i), dt = dur / k_max;
    Eigen::Matrix<double, 4, 3> gc = Eigen::Matrix<double, 4, 3>::Zero();
    double gt = 0.0;
    for (int j = 0; j <= k_max; ++j) {
      const double alpha = double(j) / k_max, t = alpha * dur;
      const Eigen::Vector4d b0(1.0, t, t * t, t * t * t), b1(0.0, 1.0, 2.0 * t, 3.0 * t * t),
          b2(0.0, 0.0, 2.0, 6.0 * t);
      const Eigen::Vector3d p = c.transpose() * b0, v = c.transpose() * b1, a = c.transpose() * b2;
      const double cy = std::cos(p(2)), sy = std::sin(p(2));
      const double v_lon = v(0) * cy + v(1) * sy, v_lat = -v(0) * sy + v(1) * cy;

      // Integrand f(p, v) and its gradients by p and v.
      CostTerms f;
      Eigen::Vector3d gp = Eigen::Vector3d::Zero(), gv = Eigen::Vector3d::Zero();
      if (!cost_.empty() && weights_.w_q != 0.0) {
        f.q = weights_.w_q * cost_.sample(p(0), p(1), p(2), field_grad);
        gp += weights_.w_q * field_grad;
      }
      // d v_lon / d(xdot, ydot, yaw) = (cos, sin | v_lat); d v_lat = (-sin, cos | -v_lon).
      double d = 2.0 * v_lon * ilon2 * cubic_penalty(v_lon * v_lon * ilon2 - 1.0, w, f.velocity);
      gv(0) += d * cy, gv(1) += d * sy, gp(2) += d * v_lat;
      if (!robot_.nonholonomic()) {
        d = 2.0 * v_lat * ilat2 * cubic_penalty(v_lat * v_lat * ilat2 - 1.0, w, f.velocity);
        gv(0) -= d * sy, gv(1) += d * cy, gp(2) -= d * v_lon;
      }
      gv(2) += 2.0 * v(2) * iw2 * cubic_penalty(v(2) * v(2) * iw2 - 1.0, w, f.omega);
      if (car) {
        d = ilon2 * cubic_penalty((r2 * v(2) * v(2) - v_lon * v_lon) * ilon2, w, f.turn);
        gv(2) += d * 2.0 * r2 * v(2);
        gv(0) -= d * 2.0 * v_lon * cy, gv(1) -= d * 2.0 * v_lon * sy, gp(2) -= d * 2.0 * v_lon * v_lat;
      }
      if (!esdf_.empty()) {
        const double dist = esdf_.sample(p(0), p(1), 0.0, field_grad);
        d = cubic_penalty(clearance - dist, w, f.esdf);
        gp(0) -= d * field_grad(0), gp(1) -= d * field_grad(1);
      }

      // Trapezoid weight wt = dt (dt / 2 at the ends); t = alpha T moves with T.
      const double wt = (j == 0 || j == k_max) ? 0.5 * dt : dt;
      const double sum = f.q + f.velocity + f.omega + f.turn + f.esdf;
      terms.q += wt * f.q, terms.velocity += wt * f.velocity, terms.omega += wt * f.omega;
      terms.turn += wt * f.turn, terms.esdf += wt * f.esdf;
      gc.noalias() += wt * (b0 * gp.transpose() + b1 * gv.transpose());
      gt += sum * wt / dur + wt * alpha * (gp.dot(v) + gv.dot(a));

      if (robot_.nonholonomic() && j >= 1) {
        const int idx = i * k_max + j - 1;
        const double hk = v(0) * sy - v(1) * cy;
        if (h) (*h)(idx) = hk;
        terms.phr += lambda(idx) * hk + 0.5 * rho * hk * hk;
        const double dl = lambda(idx) + rho * hk;
        // dh/d(xdot, ydot) = (sin, -cos), dh/dyaw = v_lon.
        const Eigen::Vector3d hp(0.0, 0.0, dl * v_lon), hv(dl * sy, -dl * cy, 0.0);
        gc.noalias() += b0 * hp.transpose() + b1 * hv.transpose();
        gt += alpha * (hp.dot(v) + hv.dot(a));
      }
    }
    grad_c.middleRows<4>(4 * i) += gc;
    grad_t(i) += gt;
  }
}

}  // namespace lf3pm
