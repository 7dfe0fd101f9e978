#include "lf3pm/straight_end.hpp"

#include <cmath>

#include "lf3pm/minco.hpp"

namespace lf3pm {

StraightEnd::StraightEnd(const Eigen::Vector3d& base, bool lead_out, double a_ref, double v_ref)
    : base_(base), e_(std::cos(base(2)), std::sin(base(2))), lead_out_(lead_out), a_ref_(a_ref), v_ref_(v_ref) {
  set(parameters_for(1.0, v_ref));
}

Eigen::Vector3d StraightEnd::parameters_for(double d, double s) const {
  const double t = 2.0 * d / s, alpha = s / (2.0 * t);  // sigma = alpha t^2: d = s T / 2
  return {tau_from_duration(alpha / a_ref_), tau_from_duration(s / v_ref_), tau_from_duration(t)};
}

void StraightEnd::set(const Eigen::Vector3d& u) {
  u_ = u;
  alpha_ = a_ref_ * duration_from_tau(u(0));
  s_ = v_ref_ * duration_from_tau(u(1));
  t_ = duration_from_tau(u(2));
  beta_ = s_ / (3.0 * t_ * t_) - 2.0 * alpha_ / (3.0 * t_);
  d_ = (alpha_ * t_ * t_ + s_ * t_) / 3.0;
}

Eigen::Matrix<double, 4, 3> StraightEnd::coefficients() const {
  // Along e: lead-in (0, 0, alpha, beta); lead-out, sigma(T - t) expanded in t and
  // negated: (-d, s, alpha - s / T, beta).
  const Eigen::Vector4d k = lead_out_ ? Eigen::Vector4d(-d_, s_, alpha_ - s_ / t_, beta_)
                                      : Eigen::Vector4d(0.0, 0.0, alpha_, beta_);
  Eigen::Matrix<double, 4, 3> c = Eigen::Matrix<double, 4, 3>::Zero();
  c.row(0) = base_.transpose();
  for (int r = 0; r < 4; ++r) c.block<1, 2>(r, 0) += k(r) * e_.transpose();
  return c;
}

Eigen::Matrix<double, 3, 2> StraightEnd::junction() const {
  Eigen::Matrix<double, 3, 2> j = Eigen::Matrix<double, 3, 2>::Zero();
  j.col(0) = base_;
  j.block<2, 1>(0, 0) += (lead_out_ ? -d_ : d_) * e_;
  j.block<2, 1>(0, 1) = s_ * e_;
  return j;
}

Eigen::Vector3d StraightEnd::gradient(const Eigen::Matrix<double, 4, 3>& grad_c, double grad_t,
                                      const Eigen::Matrix<double, 3, 2>& grad_junction) const {
  // Everything moves along e only (the yaw column is fixed): project the partials on e.
  Eigen::Vector4d gk;
  for (int r = 0; r < 4; ++r) gk(r) = grad_c.block<1, 2>(r, 0).dot(e_.transpose());
  const double gjp = grad_junction.block<2, 1>(0, 0).dot(e_), gjv = grad_junction.block<2, 1>(0, 1).dot(e_);
  const double t = t_, t2 = t * t, t3 = t2 * t;
  // Partials of beta and d by (alpha, s, T).
  const Eigen::Vector3d dbeta(-2.0 / (3.0 * t), 1.0 / (3.0 * t2), -2.0 * s_ / (3.0 * t3) + 2.0 * alpha_ / (3.0 * t2));
  const Eigen::Vector3d dd(t2 / 3.0, t / 3.0, (2.0 * alpha_ * t + s_) / 3.0);
  Eigen::Vector3d g = gk(3) * dbeta + Eigen::Vector3d(0.0, gjv, grad_t);
  if (lead_out_) {
    // k = (-d, s, alpha - s / T, beta); junction position base - e d.
    g += -(gk(0) + gjp) * dd + Eigen::Vector3d(gk(2), gk(1) - gk(2) / t, gk(2) * s_ / t2);
  } else {
    // k = (0, 0, alpha, beta); junction position base + e d.
    g += gjp * dd + Eigen::Vector3d(gk(2), 0.0, 0.0);
  }
  // Through the positive maps alpha = a_ref D(u0), s = v_ref D(u1), T = D(u2).
  return {g(0) * a_ref_ * duration_derivative(u_(0)), g(1) * v_ref_ * duration_derivative(u_(1)),
          g(2) * duration_derivative(u_(2))};
}

}  // namespace lf3pm
