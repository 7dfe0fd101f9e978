#include "lf3pm/trajectory/straight_end.hpp"

#include <cmath>
#include <stdexcept>

#include "lf3pm/trajectory/minco.hpp"
#include "lf3pm/trajectory/time_map.hpp"

namespace lf3pm {

StraightEnd::StraightEnd(const Eigen::Vector3d& base, bool lead_out, double a_ref, double v_ref, bool free_heading)
    : base_(base),
      e_(std::cos(base(2)), std::sin(base(2))),
      lead_out_(lead_out),
      free_heading_(free_heading),
      a_ref_(a_ref),
      v_ref_(v_ref),
      heading0_(base(2)) {
  set(parameters_for(1.0, v_ref));
}

Eigen::VectorXd StraightEnd::parameters_for(double d, double s) const {
  const double t = 2.0 * d / s, alpha = s / (2.0 * t);  // sigma = alpha t^2: d = s T / 2
  Eigen::VectorXd u(parameters());
  u.head<3>() << tau_from_duration(alpha / a_ref_), tau_from_duration(s / v_ref_), tau_from_duration(t);
  if (free_heading_) u(3) = std::atanh((base_(2) - heading0_) / kHeadingRange);
  return u;
}

void StraightEnd::set(const Eigen::VectorXd& u) {
  if (u.size() != parameters()) throw std::invalid_argument("straight end: wrong number of parameters");
  u_ = u.head<3>();
  if (free_heading_) {
    base_(2) = heading0_ + kHeadingRange * std::tanh(u(3));
    e_ << std::cos(base_(2)), std::sin(base_(2));
    u_heading_ = u(3);
  }
  alpha_ = a_ref_ * duration_from_tau(u(0));
  s_ = v_ref_ * duration_from_tau(u(1));
  t_ = duration_from_tau(u(2));
  beta_ = s_ / (3.0 * t_ * t_) - 2.0 * alpha_ / (3.0 * t_);
  d_ = (alpha_ * t_ * t_ + s_ * t_) / 3.0;
}

Eigen::Matrix<double, 4, 3> StraightEnd::coefficients() const {
  // Along e: lead-in (0, 0, alpha, beta); lead-out, sigma(T - t) expanded in t and
  // negated: (-d, s, alpha - s / T, beta).
  const Eigen::Vector4d k =
      lead_out_ ? Eigen::Vector4d(-d_, s_, alpha_ - s_ / t_, beta_) : Eigen::Vector4d(0.0, 0.0, alpha_, beta_);
  Eigen::Matrix<double, 4, 3> c = Eigen::Matrix<double, 4, 3>::Zero();
  c.row(0) = base_.transpose();
  for (int r = 0; r < 4; ++r) c.block<1, 2>(r, 0) += k(r) * e_.transpose();
  return c;
}

Eigen::Matrix3d StraightEnd::junction() const {
  Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
  j.col(0) = base_;
  j.block<2, 1>(0, 0) += (lead_out_ ? -d_ : d_) * e_;
  j.block<2, 1>(0, 1) = s_ * e_;
  // sigma''(T) = 2 alpha + 6 beta T = 2 s / T - 2 alpha; the lead-out runs it backwards in time
  // (p = base - e sigma(T - t), whose second derivative is -e sigma'').
  j.block<2, 1>(0, 2) = (lead_out_ ? -1.0 : 1.0) * (2.0 * s_ / t_ - 2.0 * alpha_) * e_;
  return j;
}

Eigen::VectorXd StraightEnd::gradient(const Eigen::Matrix<double, 4, 3>& grad_c, double grad_t,
                                      const Eigen::Matrix3d& grad_junction) const {
  // Everything moves along e only: project the partials on e (and on its normal n for the
  // heading, since de/dyaw = n).
  const Eigen::Vector2d n(-e_(1), e_(0));
  Eigen::Vector4d gk, gn;
  for (int r = 0; r < 4; ++r) {
    gk(r) = grad_c.block<1, 2>(r, 0).dot(e_.transpose());
    gn(r) = grad_c.block<1, 2>(r, 0).dot(n.transpose());
  }
  const double sign =
      lead_out_ ? -1.0 : 1.0;  // the lead-out's junction sits at base - e d, its acceleration -e sigma''
  const double gjp = grad_junction.block<2, 1>(0, 0).dot(e_), gjv = grad_junction.block<2, 1>(0, 1).dot(e_);
  const double gja = sign * grad_junction.block<2, 1>(0, 2).dot(e_);
  const double t = t_, t2 = t * t, t3 = t2 * t;
  // Partials of beta, d and the junction acceleration sigma''(T) by (alpha, s, T).
  const Eigen::Vector3d dbeta(-2.0 / (3.0 * t), 1.0 / (3.0 * t2), -2.0 * s_ / (3.0 * t3) + 2.0 * alpha_ / (3.0 * t2));
  const Eigen::Vector3d dd(t2 / 3.0, t / 3.0, (2.0 * alpha_ * t + s_) / 3.0);
  const Eigen::Vector3d dacc(-2.0, 2.0 / t, -2.0 * s_ / t2);
  Eigen::Vector3d g = gk(3) * dbeta + gja * dacc + Eigen::Vector3d(0.0, gjv, grad_t);
  // k: the coefficients along e, lead-in (0, 0, alpha, beta), lead-out (-d, s, alpha - s / T, beta).
  Eigen::Vector4d k(0.0, 0.0, alpha_, beta_);
  if (lead_out_) {
    k.head<3>() << -d_, s_, alpha_ - s_ / t;
    g += -(gk(0) + gjp) * dd + Eigen::Vector3d(gk(2), gk(1) - gk(2) / t, gk(2) * s_ / t2);
  } else {
    g += gjp * dd + Eigen::Vector3d(gk(2), 0.0, 0.0);
  }
  // Through the positive maps alpha = a_ref D(u0), s = v_ref D(u1), T = D(u2).
  Eigen::VectorXd out(parameters());
  out.head<3>() << g(0) * a_ref_ * duration_derivative(u_(0)), g(1) * v_ref_ * duration_derivative(u_(1)),
      g(2) * duration_derivative(u_(2));
  if (free_heading_) {
    // Turning e turns every offset along it: coefficients k e, junction (+-d, s, +-sigma'') e.
    const double acc = 2.0 * s_ / t - 2.0 * alpha_;
    const double g_yaw = gn.dot(k) + grad_junction.block<2, 1>(0, 0).dot(n) * sign * d_ +
                         grad_junction.block<2, 1>(0, 1).dot(n) * s_ +
                         grad_junction.block<2, 1>(0, 2).dot(n) * sign * acc;
    const double th = std::tanh(u_heading_);
    out(3) = g_yaw * kHeadingRange * (1.0 - th * th);
  }
  return out;
}

}  // namespace lf3pm
