// LF-3PM trajectory back end: the full objective over the MINCO parameters,
// minimised by L-BFGS.
//
// Decision vector x = [q_1..q_{N-1} (3 each: x, y, yaw), tau_1..tau_N], durations
// T_i = duration_from_tau(tau_i) (GCOPTER's C^2 map, so T > 0 without bounds);
// for diff and car robots, then 3 parameters of each straight end piece (straight_end.hpp:
// lead-in, lead-out), whose junction states (position, velocity, acceleration) become the
// spline's head and tail, and the spline's first and last waypoints are not parameters.
//   J(x) = sampled terms (trajectory_cost.hpp) + rho_T * total time + w_e * energy
// No equality is left to enforce: the flat output satisfies the nonholonomic one
// exactly (trajectory_cost.hpp) and the straight end pieces the rest headings,
// so there is no PHR outer loop (the paper's; docs/planner_backend.md has the
// measurements behind dropping it).
#pragma once

#include <Eigen/Core>
#include <string>

#include "lf3pm/trajectory/lbfgs.hpp"
#include "lf3pm/trajectory/minco.hpp"
#include "lf3pm/trajectory/straight_end.hpp"
#include "lf3pm/trajectory/trajectory_cost.hpp"

namespace lf3pm {

class TrajectoryProblem {
 public:
  /// head/tail: (x, y, yaw) position in column 0, velocity in column 1 (diff and car: at
  /// rest, the yaw its straight end piece runs along); initial intermediate
  /// waypoints (3 x (N-1)) and durations (N, > 0; N >= 3 with straight ends) give x0.
  TrajectoryProblem(TrajectoryCost cost, double rho_t, double w_energy, const Eigen::Matrix<double, 3, 2>& head,
                    const Eigen::Matrix<double, 3, 2>& tail, const Eigen::Matrix3Xd& waypoints,
                    const Eigen::VectorXd& durations);

  /// MINCO pieces (a diff or car trajectory has two more: its straight ends).
  int pieces() const { return pieces_; }
  /// Intermediate waypoints that are parameters (with straight ends the spline places its
  /// first and last itself, to join them with continuous acceleration).
  int free_waypoints() const { return pieces_ - 1 - (straight_ends_ ? 2 : 0); }
  /// Parameters: free waypoints (3 each), taus, and each straight end's (3; a diff robot's
  /// 4, with its heading).
  int dimension() const { return 3 * free_waypoints() + pieces_ + (straight_ends_ ? 2 * end_parameters() : 0); }
  int end_parameters() const { return cost_.robot().turns_on_the_spot() ? 4 : 3; }
  const Eigen::VectorXd& initial() const { return x0_; }
  const TrajectoryCost& cost() const { return cost_; }

  /// Objective at x, gradient into g; its terms into `terms` if given.
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& g, CostTerms* terms = nullptr);
  /// The whole trajectory's coefficients (4M x 3) and durations (M) at x.
  void trajectory(const Eigen::VectorXd& x, Eigen::MatrixX3d& coefficients, Eigen::VectorXd& durations);

 private:
  void decode(const Eigen::VectorXd& x);
  TrajectoryCost cost_;
  double rho_t_, w_energy_;
  int pieces_;
  bool straight_ends_;
  StraightEnd lead_in_, lead_out_;
  MincoS2 minco_;
  Eigen::VectorXd x0_;
  // Work buffers reused by every evaluation; *_all_ span the whole trajectory.
  Eigen::Matrix3Xd q_, grad_q_;
  Eigen::VectorXd tau_, durations_, grad_T_, durations_all_, grad_t_all_;
  Eigen::MatrixX3d coef_all_, grad_c_all_, grad_c_;
};

struct OptimizeOutcome {
  Eigen::VectorXd x;
  int iterations = 0;   ///< L-BFGS iterations
  int evaluations = 0;  ///< objective evaluations
  std::string status;   ///< L-BFGS's status
  std::string reason;   ///< and why it stopped (LbfgsResult::reason)
  CostTerms terms;      ///< at the solution
};

/// The trajectory optimiser's L-BFGS: lbfgs.hpp's defaults but a relative decrease of
/// 1e-4 over 10 iterations ends it (delta, past), since the sampled objective stops
/// improving the plan long before 1e-9. Over 3 iterations the test stopped it on plateaus
/// early in the descent: 14.1 s instead of 7.9 s after 21 iterations, an unguided diff plan
/// through the boxes room at 34.3 s instead of 18.2 s (docs/planner_backend.md, "Stopping").
inline LbfgsParams trajectory_lbfgs() {
  LbfgsParams p;
  p.delta = 1e-4;
  p.past = 10;
  return p;
}

/// Restarts of L-BFGS when it stalls with a limit exceeded (see optimize).
constexpr int kRestarts = 3;

/// Minimise from problem.initial() with L-BFGS; where it stalls while the feasibility
/// penalties still hold over 0.1 % of the objective, restart it there with a tenth of the
/// tolerance, up to kRestarts times. Iterations and evaluations are summed over rounds.
OptimizeOutcome optimize(TrajectoryProblem& problem, const LbfgsParams& lbfgs);

}  // namespace lf3pm
