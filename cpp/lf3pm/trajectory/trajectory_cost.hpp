// The sampled terms of the trajectory objective (LF-3PM back end): at K + 1
// samples per piece, trapezoid-weighted in time,
//   w_q * q(x, y, yaw)                                 localisability cost (SOLM)
//   W * P(v_lon^2 / vmax_lon^2 - 1), W * P(v_lat^2 / vmax_lat^2 - 1)  (lateral: omni only)
//   W * P(|v|^2 / vmax_norm^2 - 1)                     omni with a speed limit on |v|
//   W * P(omega^2 / wmax^2 - 1)
//   W * P(a_lon^2 / amax_lon^2 - 1), W * P(a_lat^2 / amax_lat^2 - 1)  body-frame acceleration
//   W * P(alpha^2 / alpha_max^2 - 1)                   yaw acceleration alpha = yaw''
//   W * P((R^2 omega^2 - v_lon^2) / vmax_lon^2)        car: turning radius >= R
//   W * P((r_safe + margin - esdf(x, y)) / 0.1 m)      clearance
// with the cubic penalty P(z) = max(z, 0)^3 (C^2); v_lon = xdot cos(yaw) + ydot sin(yaw),
// v_lat = -xdot sin(yaw) + ydot cos(yaw), and a_lon, a_lat the world acceleration in
// the body frame likewise. A cubic's acceleration (and an omni robot's yaw'') is linear
// on each piece, so its largest magnitude is at a piece's end, where a sample lies.
//
// Diff and car robots use the flat output instead: only (x, y) matter, the yaw is
// the direction of travel, yaw = atan2(ydot, xdot), so the nonholonomic equality
// h = xdot sin(yaw) - ydot cos(yaw) = 0 holds exactly (the MINCO's yaw column is
// ignored). With s = |v|^2 and cr = xdot yddot - ydot xddot (omega = cr / s), the
// limits are rational, regular where the robot stands still (eps = (0.01 vmax_lon)^2):
//   W * P(s / vmax_lon^2 - 1)
//   W * P((cr^2 - wmax^2 s^2) / (wmax^2 (s + eps)^2))    |omega| <= wmax
//   W * P((R^2 cr^2 - s^3) / (s + eps)^3)                car: curvature <= 1 / R
//   W * P((|a|^2 - cr^2 / (s + eps)) / amax_lon^2 - 1)    tangential a_lon^2 = |a|^2 - cr^2 / s
//   W * P(cr^2 / ((s + eps) amax_lat^2) - 1)              centripetal a_lat^2 = cr^2 / s
//   W * P(N^2 / ((s + eps)^4 alpha_max^2) - 1)            alpha = N / s^2, N = (v x j) s - 2 cr (v . a)
// The tangential form is exact at rest (where the robot starts and stops: all of a is
// tangential there) and never below the true a_lon^2 elsewhere.
// (Diff robots turn on the spot before and after: trajectory_optimizer.py adds those pieces.)
//
// Diff and car robots start and end at rest on straight end pieces (straight_end.hpp)
// that the optimiser puts first and last (a cubic leaving rest off a straight line
// turns at (a x j) / (2 |a|^2) at once: a yaw-rate jump); between them they keep
// moving, W * P(1 - s / v_min^2) with v_min = 0.1 vmax_lon: near rest the
// regularised limits lose their grip, and a flat output that stops can reverse
// through a cusp, its heading flipping by pi between two samples.
#pragma once

#include <Eigen/Core>

#include "lf3pm/planner/grid_field.hpp"
#include "lf3pm/trajectory/robot_limits.hpp"

namespace lf3pm {

struct CostWeights {
  double w_q = 1.0;           ///< weight of the cost field's integral over time
  double penalty = 1e5;       ///< W: weight of the cubic feasibility penalties
  double esdf_margin = 0.05;  ///< the clearance penalty starts at r_safe + margin
  int samples = 16;           ///< K: samples per piece (K + 1 with both ends)
  /// Omni robots: a radian of yaw travel costs what `turn` seconds of travel cost there,
  /// (w_time + w_q c) per second, in the q term: the front end's price of a turn
  /// (turn_radius / vmax_lon, docs/planner_backend.md); 0: turns are free.
  double turn = 0.0;
  double w_time = 1.0;  ///< the time term's weight rho_T, which prices the turn's time
};

/// The objective's terms (unweighted by nothing: each as it enters the objective).
struct CostTerms {
  double q = 0.0, velocity = 0.0, omega = 0.0, acceleration = 0.0, turn = 0.0, esdf = 0.0;
  double time = 0.0, energy = 0.0;
  double total() const { return q + velocity + omega + acceleration + turn + esdf + time + energy; }
};

class TrajectoryCost {
 public:
  /// `cost` and `esdf` are copied in; an empty field switches its term off.
  TrajectoryCost(GridField cost, GridField esdf, const RobotLimits& robot, const CostWeights& weights);

  const RobotLimits& robot() const { return robot_; }
  const CostWeights& weights() const { return weights_; }

  /// The clearance kept on the first (last) piece: r_safe + margin, or the fixed start's
  /// (goal's) own ESDF value where that is less. A penalty at a fixed end cannot be removed:
  /// beside a wall it was thousands of times the plan's own cost, and the relative stop of
  /// L-BFGS then left plans near their half-speed initial guess (docs/planner_backend.md).
  void keep_ends(double head_x, double head_y, double tail_x, double tail_y);

  /// Add every sampled term of the piecewise cubic (4N x 3 coefficients, N durations)
  /// to `terms`, their partial gradients to grad_c (4N x 3) and grad_t (N).
  void add(const Eigen::MatrixX3d& coef, const Eigen::VectorXd& durations, Eigen::MatrixX3d& grad_c,
           Eigen::VectorXd& grad_t, CostTerms& terms) const;

 private:
  GridField cost_, esdf_;
  RobotLimits robot_;
  CostWeights weights_;
  double head_clearance_, tail_clearance_;  // keep_ends
};

}  // namespace lf3pm
