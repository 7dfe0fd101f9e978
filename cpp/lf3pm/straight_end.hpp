// A car's first and last piece: straight along its given yaw, from or to rest.
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
// junction, position base + e d and velocity e s; there the curvature may jump
// (C^1 junction), as between a Dubins path's line and arc. The lead-out runs the
// same in reverse time: p(t) = base - e sigma(T - t), from speed s to rest at base.
//
// Free parameters u = (u_alpha, u_s, tau): alpha = a_ref D(u_alpha), s = v_ref D(u_s),
// T = D(tau), with D = duration_from_tau (minco.hpp: C^2, onto (0, inf)).
#pragma once

#include <Eigen/Core>

namespace lf3pm {

class StraightEnd {
 public:
  /// `base`: the rest pose (x, y, yaw); `lead_out`: false for the start (from rest),
  /// true for the goal (to rest); a_ref, v_ref: scales of alpha (m/s^2) and s (m/s).
  StraightEnd(const Eigen::Vector3d& base, bool lead_out, double a_ref, double v_ref);
  StraightEnd() = default;

  /// Parameters u for a piece of length d > 0 ending (lead-in) or starting (lead-out)
  /// at speed s > 0 with constant acceleration (beta = 0).
  Eigen::Vector3d parameters_for(double d, double s) const;
  /// Set the piece from its free parameters u.
  void set(const Eigen::Vector3d& u);

  double duration() const { return t_; }
  /// The piece's coefficients (rows c0..c3, columns x, y, yaw; yaw constant).
  Eigen::Matrix<double, 4, 3> coefficients() const;
  /// Where the spline continues: column 0 position (x, y, yaw), column 1 velocity.
  Eigen::Matrix<double, 3, 2> junction() const;
  /// d(objective)/du from the partial gradients by the piece's coefficients (4 x 3)
  /// and duration, and by the junction state (3 x 2, as the spline's adjoint gives it).
  Eigen::Vector3d gradient(const Eigen::Matrix<double, 4, 3>& grad_c, double grad_t,
                           const Eigen::Matrix<double, 3, 2>& grad_junction) const;

 private:
  Eigen::Vector3d base_ = Eigen::Vector3d::Zero();
  Eigen::Vector2d e_ = Eigen::Vector2d::UnitX();
  bool lead_out_ = false;
  double a_ref_ = 1.0, v_ref_ = 1.0;
  Eigen::Vector3d u_ = Eigen::Vector3d::Zero();
  double alpha_ = 1.0, s_ = 1.0, t_ = 1.0, beta_ = 0.0, d_ = 0.0;
};

}  // namespace lf3pm
