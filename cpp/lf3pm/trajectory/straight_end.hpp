// A diff or car robot's first and last piece: straight along a given yaw, from or to rest.
//
// A cubic piece leaving rest turns at (a x j) / (2 |a|^2) from its first instant
// (a, j: its acceleration and jerk there) while its speed is zero, so a car
// (turning radius >= R, no turning on the spot) can leave or reach rest with a
// bounded curvature only along a straight line. Penalties on the MINCO's end
// pieces only got close to that (docs/planner_backend.md); this makes it exact:
//   car trajectory = straight lead-in | MINCO spline | straight lead-out,
// each end piece base + e sigma(t), e = (cos yaw, sin yaw), with a scalar cubic
//   sigma(t) = alpha t^2 + beta t^3,  sigma(0) = sigma'(0) = 0,
//   sigma(T) = d = (alpha T^2 + s T) / 3,  sigma'(T) = s  (beta = s / (3 T^2) - 2 alpha / (3 T)).
// With alpha > 0 and s > 0, sigma' = t (2 alpha + 3 beta t) > 0 on (0, T]: the
// car moves forwards only, its heading at rest is exactly e (acceleration
// 2 alpha e) and the piece has no curvature at all. The spline continues from the
// junction, position base + e d, velocity e s and acceleration e sigma''(T) =
// e (2 s / T - 2 alpha): a C^2 junction (the spline takes all three as its head
// conditions, minco.hpp), so the curvature and the yaw rate are continuous and zero
// there. The lead-out runs the same in reverse time: p(t) = base - e sigma(T - t),
// from speed s to rest at base.
//
// Free parameters u = (u_alpha, u_s, tau[, yaw]): alpha = a_ref D(u_alpha), s = v_ref D(u_s),
// T = D(tau), with D = duration_from_tau (minco.hpp: C^2, onto (0, inf)); with a free
// heading (a diff robot, which turns on the spot to it) also u_yaw: yaw = yaw0 +
// (pi / 2) tanh(u_yaw), within a quarter turn of the initial heading yaw0 (the path's
// first or last direction), so that the optimiser never turns it round and meets the
// path in a cusp.
#pragma once

#include <Eigen/Core>

namespace lf3pm {

class StraightEnd {
 public:
  /// `base`: the rest pose (x, y, yaw: the initial heading); `lead_out`: false for the
  /// start (from rest), true for the goal (to rest); a_ref, v_ref: scales of alpha (m/s^2)
  /// and s (m/s); `free_heading`: the heading is a parameter too.
  StraightEnd(const Eigen::Vector3d& base, bool lead_out, double a_ref, double v_ref, bool free_heading = false);
  StraightEnd() = default;

  /// Number of free parameters: 3, or 4 with a free heading.
  int parameters() const { return free_heading_ ? 4 : 3; }
  /// Parameters u for a piece of length d > 0 ending (lead-in) or starting (lead-out)
  /// at speed s > 0 with constant acceleration (beta = 0), along the current heading.
  Eigen::VectorXd parameters_for(double d, double s) const;
  /// Set the piece from its free parameters u (parameters() of them).
  void set(const Eigen::VectorXd& u);

  double duration() const { return t_; }
  /// The piece's coefficients (rows c0..c3, columns x, y, yaw; yaw constant).
  Eigen::Matrix<double, 4, 3> coefficients() const;
  /// Where the spline continues: columns position (x, y, yaw), velocity, acceleration.
  Eigen::Matrix3d junction() const;
  /// d(objective)/du from the partial gradients by the piece's coefficients (4 x 3)
  /// and duration, and by the junction state (3 x 3, as the spline's adjoint gives it).
  /// (The yaw column only unwraps a flat output's heading: it carries no gradient.)
  Eigen::VectorXd gradient(const Eigen::Matrix<double, 4, 3>& grad_c, double grad_t,
                           const Eigen::Matrix3d& grad_junction) const;

 private:
  Eigen::Vector3d base_ = Eigen::Vector3d::Zero();
  Eigen::Vector2d e_ = Eigen::Vector2d::UnitX();
  bool lead_out_ = false, free_heading_ = false;
  double a_ref_ = 1.0, v_ref_ = 1.0;
  Eigen::Vector3d u_ = Eigen::Vector3d::Zero();
  double alpha_ = 1.0, s_ = 1.0, t_ = 1.0, beta_ = 0.0, d_ = 0.0;
  double heading0_ = 0.0, u_heading_ = 0.0;
  static constexpr double kHeadingRange = 1.5707963267948966;  // pi / 2
};

}  // namespace lf3pm
