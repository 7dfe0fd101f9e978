// LF-3PM trajectory back end: the full objective over the MINCO parameters and
// the PHR augmented-Lagrangian outer loop around L-BFGS.
//
// Decision vector x = [q_1..q_{N-1} (3 each: x, y, yaw), tau_1..tau_N], durations
// T_i = duration_from_tau(tau_i) (GCOPTER's C^2 map, so T > 0 without bounds).
//   J(x) = sampled terms (trajectory_cost.hpp) + rho_T * sum T_i + w_e * energy
// For diff and car robots the nonholonomic equality h = 0 at the samples is
// enforced by PHR: minimise J with multipliers lambda and penalty rho, then
// lambda += rho h, rho = min(beta rho, rho_max), until max |h| <= tol_h.
#pragma once

#include <Eigen/Core>
#include <string>

#include "lf3pm/lbfgs.hpp"
#include "lf3pm/minco.hpp"
#include "lf3pm/trajectory_cost.hpp"

namespace lf3pm {

struct PhrParams {
  double rho0 = 1.0;       ///< initial penalty
  double beta = 10.0;      ///< penalty growth per outer iteration
  double rho_max = 1e6;    ///< penalty cap
  double tol_h = 1e-4;     ///< stop when max |h| at the samples is below (m/s)
  int max_outer = 12;
};

class TrajectoryProblem {
 public:
  /// head/tail: (x, y, yaw) position in column 0, velocity in column 1; initial
  /// intermediate waypoints (3 x (N-1)) and durations (N, > 0) give x0.
  TrajectoryProblem(TrajectoryCost cost, double rho_t, double w_energy, const Eigen::Matrix<double, 3, 2>& head,
                    const Eigen::Matrix<double, 3, 2>& tail, const Eigen::Matrix3Xd& waypoints,
                    const Eigen::VectorXd& durations);

  int pieces() const { return pieces_; }
  int dimension() const { return 3 * (pieces_ - 1) + pieces_; }
  int equality_count() const { return cost_.equality_count(pieces_); }
  const Eigen::VectorXd& initial() const { return x0_; }
  const TrajectoryCost& cost() const { return cost_; }

  /// PHR state used by evaluate().
  void set_multipliers(const Eigen::VectorXd& lambda, double rho);
  const Eigen::VectorXd& multipliers() const { return lambda_; }
  double rho() const { return rho_; }

  /// Objective at x, gradient into g; `terms` and `h` (equality residuals) if given.
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& g, CostTerms* terms = nullptr,
                  Eigen::VectorXd* h = nullptr);
  /// The trajectory's coefficients (4N x 3) and durations at x.
  void trajectory(const Eigen::VectorXd& x, Eigen::MatrixX3d& coefficients, Eigen::VectorXd& durations);

 private:
  void decode(const Eigen::VectorXd& x);
  TrajectoryCost cost_;
  double rho_t_, w_energy_;
  int pieces_;
  MincoS2 minco_;
  Eigen::VectorXd x0_, lambda_;
  double rho_ = 0.0;
  // Work buffers reused by every evaluation.
  Eigen::Matrix3Xd q_, grad_q_;
  Eigen::VectorXd tau_, durations_, grad_t_, grad_T_;
  Eigen::MatrixX3d grad_c_;
};

struct OptimizeOutcome {
  Eigen::VectorXd x;
  int iterations = 0;        ///< L-BFGS iterations, all outer loops together
  int evaluations = 0;       ///< objective evaluations
  int outer_iterations = 0;
  std::string status;        ///< the last L-BFGS status
  double max_h = 0.0;        ///< max |h| at the samples (0 for omni)
  CostTerms terms;           ///< at the solution, with the last multipliers
};

/// Minimise from problem.initial(): L-BFGS alone for omni robots, inside the PHR loop otherwise.
OptimizeOutcome optimize(TrajectoryProblem& problem, const PhrParams& phr, const LbfgsParams& lbfgs);

}  // namespace lf3pm
