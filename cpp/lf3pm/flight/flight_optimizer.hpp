// The flight back end: the whole objective over a quintic MINCO in (x, y, z, yaw),
// minimised by L-BFGS (lbfgs.hpp).
//
// Decision vector x = [q_1..q_{N-1} (4 each: x, y, z, yaw), tau_1..tau_N], durations
// T_i = duration_from_tau(tau_i) (time_map.hpp: T > 0 without bounds);
//   J(x) = sampled terms (flight_cost.hpp) + rho_T * total time + jerk energy (weighted
//          per dimension: w_energy for x, y, z and w_energy * yaw_energy for the yaw).
#pragma once

#include <Eigen/Core>
#include <string>

#include "lf3pm/flight/flight_cost.hpp"
#include "lf3pm/trajectory/lbfgs.hpp"
#include "lf3pm/trajectory/minco_s3.hpp"

namespace lf3pm {

class FlightProblem {
 public:
  /// head/tail: (x, y, z, yaw) position, velocity, acceleration; initial waypoints
  /// (4 x (N - 1)) and durations (N, > 0) give x0.
  FlightProblem(FlightCost cost, double rho_t, double w_energy, double yaw_energy, const MincoS3::State& head,
                const MincoS3::State& tail, const MincoS3::Points& waypoints, const Eigen::VectorXd& durations);

  int pieces() const { return pieces_; }
  int dimension() const { return MincoS3::kDims * (pieces_ - 1) + pieces_; }
  const Eigen::VectorXd& initial() const { return x0_; }

  /// Objective at x, gradient into g; the sampled terms into `terms` if given.
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& g, FlightTerms* terms = nullptr);
  /// The trajectory's coefficients (6N x 4) and durations (N) at x.
  void trajectory(const Eigen::VectorXd& x, MincoS3::Coefficients& coefficients, Eigen::VectorXd& durations);

 private:
  void decode(const Eigen::VectorXd& x);
  FlightCost cost_;
  double rho_t_;
  Eigen::Vector4d energy_weights_;
  int pieces_;
  MincoS3 minco_;
  Eigen::VectorXd x0_;
  MincoS3::Points q_, grad_q_;
  Eigen::VectorXd tau_, durations_, grad_t_, grad_T_;
  MincoS3::Coefficients grad_c_;
};

struct FlightOutcome {
  Eigen::VectorXd x;
  int iterations = 0;
  int evaluations = 0;
  double f = 0.0;  ///< the objective at x
  std::string status, reason;
  FlightTerms terms;
};

/// Minimise from problem.initial() with L-BFGS.
FlightOutcome optimize_flight(FlightProblem& problem, const LbfgsParams& lbfgs);

}  // namespace lf3pm
