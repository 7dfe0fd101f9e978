// LF-3PM trajectory back end: the full objective over the MINCO parameters,
// minimised by L-BFGS.
//
// Decision vector x = [q_1..q_{N-1} (3 each: x, y, yaw), tau_1..tau_N], durations
// T_i = duration_from_tau(tau_i) (GCOPTER's C^2 map, so T > 0 without bounds);
// for a car, then 3 parameters of each straight end piece (straight_end.hpp: lead-in,
// lead-out), whose junction states become the spline's head and tail.
//   J(x) = sampled terms (trajectory_cost.hpp) + rho_T * total time + w_e * energy
// No equality is left to enforce: the flat output satisfies the nonholonomic one
// exactly (trajectory_cost.hpp) and the straight end pieces the car's rest headings,
// so there is no PHR outer loop (the paper's; docs/planner_backend.md has the
// measurements behind dropping it).
#pragma once

#include <Eigen/Core>
#include <string>

#include "lf3pm/lbfgs.hpp"
#include "lf3pm/minco.hpp"
#include "lf3pm/straight_end.hpp"
#include "lf3pm/trajectory_cost.hpp"

namespace lf3pm {

class TrajectoryProblem {
 public:
  /// head/tail: (x, y, yaw) position in column 0, velocity in column 1 (a car: at
  /// rest, the yaw its straight end piece runs along); initial intermediate
  /// waypoints (3 x (N-1)) and durations (N, > 0) give x0.
  TrajectoryProblem(TrajectoryCost cost, double rho_t, double w_energy, const Eigen::Matrix<double, 3, 2>& head,
                    const Eigen::Matrix<double, 3, 2>& tail, const Eigen::Matrix3Xd& waypoints,
                    const Eigen::VectorXd& durations);

  /// MINCO pieces (a car's trajectory has two more: its straight ends).
  int pieces() const { return pieces_; }
  int dimension() const { return 3 * (pieces_ - 1) + pieces_ + (straight_ends_ ? 6 : 0); }
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
  Eigen::Matrix<double, 3, 2> head_, tail_;
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
  int iterations = 0;        ///< L-BFGS iterations
  int evaluations = 0;       ///< objective evaluations
  std::string status;        ///< L-BFGS's status
  CostTerms terms;           ///< at the solution
};

/// Minimise from problem.initial() with L-BFGS.
OptimizeOutcome optimize(TrajectoryProblem& problem, const LbfgsParams& lbfgs);

}  // namespace lf3pm
