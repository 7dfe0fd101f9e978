// The sampled terms of the trajectory objective (LF-3PM back end): at K + 1
// samples per piece, trapezoid-weighted in time,
//   w_q * q(x, y, yaw)                                 localisability cost (SOLM)
//   W * P(v_lon^2 / vmax_lon^2 - 1), W * P(v_lat^2 / vmax_lat^2 - 1)  (lateral: omni only)
//   W * P(omega^2 / wmax^2 - 1)
//   W * P((R^2 omega^2 - v_lon^2) / vmax_lon^2)        car: turning radius >= R
//   W * P(r_safe + margin - esdf(x, y))                clearance
// with the cubic penalty P(z) = max(z, 0)^3 (C^2), and, for diff and car, the
// PHR augmented-Lagrangian term of the nonholonomic equality at the samples
// j = 1..K of every piece (pointwise, not time-weighted):
//   lambda_k h_k + rho / 2 h_k^2,   h = xdot sin(yaw) - ydot cos(yaw).
// v_lon = xdot cos(yaw) + ydot sin(yaw), v_lat = -xdot sin(yaw) + ydot cos(yaw).
#pragma once

#include <Eigen/Core>

#include "lf3pm/grid_field.hpp"
#include "lf3pm/minco.hpp"

namespace lf3pm {

enum class RobotKind { Omni, Diff, Car };

struct RobotLimits {
  RobotKind kind = RobotKind::Omni;
  double vmax_lon = 1.0, vmax_lat = 1.0, wmax = 1.0;
  double min_turn_radius = 0.0;  ///< car only
  double r_safe = 0.5;
  bool nonholonomic() const { return kind != RobotKind::Omni; }
};

struct CostWeights {
  double w_q = 1.0;          ///< weight of the cost field's integral over time
  double penalty = 1e5;      ///< W: weight of the cubic feasibility penalties
  double esdf_margin = 0.05; ///< the clearance penalty starts at r_safe + margin
  int samples = 16;          ///< K: samples per piece (K + 1 with both ends)
};

/// The objective's terms (unweighted by nothing: each as it enters the objective).
struct CostTerms {
  double q = 0.0, velocity = 0.0, omega = 0.0, turn = 0.0, esdf = 0.0, phr = 0.0;
  double time = 0.0, energy = 0.0;
  double total() const { return q + velocity + omega + turn + esdf + phr + time + energy; }
};

class TrajectoryCost {
 public:
  /// `cost` and `esdf` are copied in; an empty field switches its term off.
  TrajectoryCost(GridField cost, GridField esdf, const RobotLimits& robot, const CostWeights& weights);

  const RobotLimits& robot() const { return robot_; }
  const CostWeights& weights() const { return weights_; }
  /// Number of nonholonomic equality samples for N pieces (0 for omni robots).
  int equality_count(int pieces) const { return robot_.nonholonomic() ? pieces * weights_.samples : 0; }

  /// Add every sampled term of the trajectory to `terms`, their partial gradients
  /// to grad_c (4N x 3) and grad_t (N). `lambda` (equality_count entries) and `rho`
  /// are the PHR multipliers and penalty; `h`, if given, receives the equality residuals.
  void add(const MincoS2& minco, const Eigen::VectorXd& lambda, double rho, Eigen::MatrixX3d& grad_c,
           Eigen::VectorXd& grad_t, CostTerms& terms, Eigen::VectorXd* h = nullptr) const;

 private:
  GridField cost_, esdf_;
  RobotLimits robot_;
  CostWeights weights_;
};

}  // namespace lf3pm
