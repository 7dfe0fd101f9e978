// Differential flatness of a quadrotor (GCOPTER's FlatnessMap is the reference for the
// interface; the derivation here is ours): from the flat outputs' derivatives, velocity v,
// acceleration a, jerk j (world frame) and yaw psi with its rate, to the thrust, attitude and
// body rates the flight needs.
//
//   thrust vector  T = m (a + g e3) + D v,   f = |T|,   z_B = T / f
//   its rate       T' = m j + D a,           z_B' = (I - z_B z_B^T) T' / f
//   attitude       R = R_tilt(z_B) Rz(psi), R_tilt the smallest rotation taking e3 to
//                  z_B = (za, zb, zc) (the Hopf fibration: regular everywhere but upside
//                  down, zc = -1); with s = 1 + zc,
//                  R_tilt = [[1 - za^2/s, -za zb/s, za], [-za zb/s, 1 - zb^2/s, zb], [-za, -zb, zc]]
//   body rates     omega = vee(R^T R'):
//                  wx = sin(psi) za' - cos(psi) zb' - (za sin(psi) - zb cos(psi)) zc' / s
//                  wy = cos(psi) za' + sin(psi) zb' - (za cos(psi) + zb sin(psi)) zc' / s
//                  wz = (zb za' - za zb') / s + psi'
//   tilt           cos(tilt) = zc (the angle between z_B and the vertical)
// At level R = Rz(psi): psi is the heading. backward() propagates gradients of any cost of
// (f, R, omega, cos tilt) to (v, a, j, psi, psi') by forward-mode automatic
// differentiation of the same expressions (Eigen's AutoDiffScalar), so both directions
// are one code path; tests/test_flatness.py checks both against finite differences.
#pragma once

#include <Eigen/Core>

#include "lf3pm/flight/quadrotor.hpp"

namespace lf3pm {

/// The flat outputs' derivatives at one instant.
struct FlatState {
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();
  Eigen::Vector3d jerk = Eigen::Vector3d::Zero();
  double yaw = 0.0;
  double yaw_rate = 0.0;
};

/// What the quadrotor does at that instant.
struct FlatAttitude {
  double thrust = 0.0;                                     ///< f, N
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< body to world
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();         ///< body rates, rad/s
  double cos_tilt = 1.0;                                   ///< z_B . e3
};

/// Gradients of a cost with respect to a FlatAttitude's members.
struct AttitudeGradient {
  double thrust = 0.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Zero();
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  double cos_tilt = 0.0;
};

/// Gradients with respect to a FlatState's members.
struct FlatGradient {
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();
  Eigen::Vector3d jerk = Eigen::Vector3d::Zero();
  double yaw = 0.0;
  double yaw_rate = 0.0;
};

class FlatnessMap {
 public:
  explicit FlatnessMap(const QuadrotorParams& params = {});
  const QuadrotorParams& params() const { return params_; }

  /// The attitude of `state`; false (and `out` untouched) where the map is singular: no
  /// thrust (free fall, f = 0) or the body upside down (zc = -1).
  bool forward(const FlatState& state, FlatAttitude* out) const;
  /// d cost / d state from d cost / d attitude at `state` (zero where forward() fails).
  FlatGradient backward(const FlatState& state, const AttitudeGradient& grad) const;

 private:
  QuadrotorParams params_;
};

}  // namespace lf3pm
