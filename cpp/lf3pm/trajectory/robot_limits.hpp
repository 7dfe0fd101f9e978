// A ground robot's kind and kinematic limits: the one place that defines their defaults.
#pragma once

namespace lf3pm {

enum class RobotKind { Omni, Diff, Car };

/// A ground robot's kinematic limits (SI units). These defaults are the project's
/// only ones: python/lf3pm/planner/robots.py and the CLI read them from here.
struct RobotLimits {
  RobotKind kind = RobotKind::Omni;
  double vmax_lon = 1.0, vmax_lat = 1.0;  ///< body-frame speed limits, m/s (lateral: omni only)
  double wmax = 1.0;                      ///< yaw rate, rad/s
  double amax_lon = 2.0, amax_lat = 2.0;  ///< body-frame acceleration limits, m/s^2
  double alpha_max = 3.0;                 ///< yaw acceleration, rad/s^2
  double min_turn_radius = 0.0;           ///< car only
  double vmax_norm = 0.0;  ///< omni: limit on the speed |v| (0: none; planner/robots.py gives omni robots max(vmax_lon,
                           ///< vmax_lat), derived from these)
  double r_safe = 0.3;     ///< clearance kept from obstacles beyond the SOLM's robot radius, m
  bool nonholonomic() const { return kind != RobotKind::Omni; }
  /// Diff and car robots leave and reach rest on straight pieces (straight_end.hpp): a car
  /// along its given yaws, a diff robot along the direction it turned to on the spot.
  bool straight_ends() const { return nonholonomic(); }
  /// A diff robot turns on the spot before and after its trajectory (trajectory_optimizer.py adds those
  /// pieces), so the heading of its straight ends is free.
  bool turns_on_the_spot() const { return kind == RobotKind::Diff; }
};

}  // namespace lf3pm
