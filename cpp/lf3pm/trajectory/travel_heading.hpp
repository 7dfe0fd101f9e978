#pragma once
// The flat map of a nonholonomic ground robot: its yaw is the direction of travel,
// yaw = atan2(ydot, xdot), turning at omega = (v x a) / |v|^2. Used by the trajectory
// cost (its gradient) and, bound, by Python's Trajectory (sampled yaw and omega), so
// that both read one rule at rest.
#include <Eigen/Core>
#include <cmath>

namespace lf3pm {

/// A piece's velocity scale |c1| + 2 |c2| T + 3 |c3| T^2 (x, y only): a bound on its
/// speed, against which "at rest" is judged.
inline double velocity_scale(const Eigen::Vector2d& c1, const Eigen::Vector2d& c2, const Eigen::Vector2d& c3,
                             double duration) {
  return c1.norm() + 2.0 * c2.norm() * duration + 3.0 * c3.norm() * duration * duration;
}

/// At rest: |v| at most 1e-6 of the piece's velocity scale, where rounding, not the
/// motion, would decide the direction of v.
inline bool at_rest(const Eigen::Vector2d& v, double scale) {
  const double floor = 1e-6 * scale;
  return v.squaredNorm() <= floor * floor;
}

/// The heading and its rate at one instant.
struct TravelHeading {
  double yaw = 0.0;
  double omega = 0.0;
  bool rest = false;
  /// The vector whose direction is the heading, up to sign: v, or a at rest.
  /// d yaw / d u = (-u_y, u_x) / |u|^2 (zero where u is).
  Eigen::Vector2d u = Eigen::Vector2d::Zero();
};

/// Heading from velocity v, acceleration a and jerk j. At rest its limits: the robot
/// starts moving along a and comes to rest moving along -a (``into_rest``: the second
/// half of a piece), turning at (a x j) / (2 |a|^2) (from v = a t + j t^2 / 2; into
/// rest, in reverse time).
inline TravelHeading travel_heading(const Eigen::Vector2d& v, const Eigen::Vector2d& a, const Eigen::Vector2d& j,
                                    bool into_rest, double scale) {
  TravelHeading h;
  h.rest = at_rest(v, scale);
  h.u = h.rest ? a : v;
  const double sign = h.rest && into_rest ? -1.0 : 1.0;
  h.yaw = std::atan2(sign * h.u(1), sign * h.u(0));
  if (h.rest) {
    const double a2 = a.squaredNorm();
    h.omega = a2 > 0.0 ? (a(0) * j(1) - a(1) * j(0)) / (2.0 * a2) : 0.0;
  } else {
    h.omega = (v(0) * a(1) - v(1) * a(0)) / v.squaredNorm();
  }
  return h;
}

}  // namespace lf3pm
