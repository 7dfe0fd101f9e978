// The sampled terms of the trajectory objective (LF-3PM back end): at K + 1
// samples per piece, trapezoid-weighted in time,
//   w_q * q(x, y, yaw)                                 localisability cost (SOLM)
//   W * P(v_lon^2 / vmax_lon^2 - 1), W * P(v_lat^2 / vmax_lat^2 - 1)  (lateral: omni only)
//   W * P(|v|^2 / vmax_norm^2 - 1)                     omni with a speed limit on |v|
//   W * P(omega^2 / wmax^2 - 1)
//   W * P((R^2 omega^2 - v_lon^2) / vmax_lon^2)        car: turning radius >= R
//   W * P(r_safe + margin - esdf(x, y))                clearance
// with the cubic penalty P(z) = max(z, 0)^3 (C^2); v_lon = xdot cos(yaw) + ydot sin(yaw),
// v_lat = -xdot sin(yaw) + ydot cos(yaw).
//
// Diff and car robots use the flat output instead: only (x, y) matter, the yaw is
// the direction of travel, yaw = atan2(ydot, xdot), so the nonholonomic equality
// h = xdot sin(yaw) - ydot cos(yaw) = 0 holds exactly (the MINCO's yaw column is
// ignored). With s = |v|^2 and cr = xdot yddot - ydot xddot (omega = cr / s), the
// limits are rational, regular where the robot stands still (eps = (0.1 vmax_lon)^2):
//   W * P(s / vmax_lon^2 - 1)
//   W * P((cr^2 - wmax^2 s^2) / (wmax^2 (s + eps)^2))    |omega| <= wmax
//   W * P((R^2 cr^2 - s^3) / (s + eps)^3)                car: curvature <= 1 / R
// (Diff robots turn on the spot before and after: optimizer.py adds those pieces.)
//
// A car starts and ends at rest along the given yaws, on straight end pieces
// (straight_end.hpp) that the optimiser puts first and last; between them it keeps
// moving, W * P(1 - s / v_min^2) with v_min = 0.1 vmax_lon: near rest the
// regularised limits lose their grip, and a flat output that stops can reverse
// through a cusp, its heading flipping by pi between two samples.
#pragma once

#include <Eigen/Core>

#include "lf3pm/grid_field.hpp"

namespace lf3pm {

enum class RobotKind { Omni, Diff, Car };

struct RobotLimits {
  RobotKind kind = RobotKind::Omni;
  double vmax_lon = 1.0, vmax_lat = 1.0, wmax = 1.0;
  double min_turn_radius = 0.0;  ///< car only
  double vmax_norm = 0.0;        ///< omni: limit on the speed |v| (0: none)
  double r_safe = 0.5;
  bool nonholonomic() const { return kind != RobotKind::Omni; }
  /// A car with a turning radius: it must leave and reach rest straight along its given yaws.
  bool straight_ends() const { return kind == RobotKind::Car && min_turn_radius > 0.0; }
};

struct CostWeights {
  double w_q = 1.0;          ///< weight of the cost field's integral over time
  double penalty = 1e5;      ///< W: weight of the cubic feasibility penalties
  double esdf_margin = 0.05; ///< the clearance penalty starts at r_safe + margin
  int samples = 16;          ///< K: samples per piece (K + 1 with both ends)
};

/// The objective's terms (unweighted by nothing: each as it enters the objective).
struct CostTerms {
  double q = 0.0, velocity = 0.0, omega = 0.0, turn = 0.0, esdf = 0.0;
  double time = 0.0, energy = 0.0;
  double total() const { return q + velocity + omega + turn + esdf + time + energy; }
};

class TrajectoryCost {
 public:
  /// `cost` and `esdf` are copied in; an empty field switches its term off.
  TrajectoryCost(GridField cost, GridField esdf, const RobotLimits& robot, const CostWeights& weights);

  const RobotLimits& robot() const { return robot_; }
  const CostWeights& weights() const { return weights_; }

  /// Add every sampled term of the piecewise cubic (4N x 3 coefficients, N durations)
  /// to `terms`, their partial gradients to grad_c (4N x 3) and grad_t (N).
  void add(const Eigen::MatrixX3d& coef, const Eigen::VectorXd& durations, Eigen::MatrixX3d& grad_c,
           Eigen::VectorXd& grad_t, CostTerms& terms) const;

 private:
  GridField cost_, esdf_;
  RobotLimits robot_;
  CostWeights weights_;
};

}  // namespace lf3pm
