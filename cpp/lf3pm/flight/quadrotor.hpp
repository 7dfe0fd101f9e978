// A quadrotor's physical parameters and flight limits: the one place that defines their
// defaults (python/lf3pm/flight/quadrotor.py and the CLI read them from here).
#pragma once

namespace lf3pm {

/// Translational dynamics m a = f z_B - m g e3 - D v, D = diag(drag_h, drag_h, drag_v):
/// thrust f along the body's z axis, linear drag in the world frame (rotor drag at the
/// speeds a LiDAR-carrying quadrotor flies; GCOPTER's FlatnessMap has the same linear
/// terms plus a parasitic one this model leaves out).
struct QuadrotorParams {
  double mass = 1.5;      ///< kg (a 250-450 mm frame with a Mid-360 or VLP-16)
  double gravity = 9.81;  ///< m/s^2
  double drag_h = 0.3;    ///< horizontal linear drag, N per m/s
  double drag_v = 0.3;    ///< vertical linear drag, N per m/s
};

/// Limits a planned flight keeps at every instant (sampled at 1 kHz in the tests).
struct QuadrotorLimits {
  double vmax = 3.0;         ///< speed |v|, m/s
  double omega_max = 3.0;    ///< body rate |omega|, rad/s (a LiDAR's deskew degrades beyond)
  double tilt_max = 0.5;     ///< angle between the body's z axis and the vertical, rad (29 deg)
  double thrust_min = 5.0;   ///< N: rotors keep spinning (hover at 1.5 kg: 14.7 N)
  double thrust_max = 30.0;  ///< N
};

}  // namespace lf3pm
