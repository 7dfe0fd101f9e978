#include "lf3pm/flight/flight_optimizer.hpp"

#include <stdexcept>

#include "lf3pm/trajectory/time_map.hpp"

namespace lf3pm {

FlightProblem::FlightProblem(FlightCost cost, double rho_t, double w_energy, double yaw_energy,
                             const MincoS3::State& head, const MincoS3::State& tail, const MincoS3::Points& waypoints,
                             const Eigen::VectorXd& durations)
    : cost_(std::move(cost)), rho_t_(rho_t), pieces_(int(durations.size())) {
  if (pieces_ < 1 || waypoints.cols() != pieces_ - 1)
    throw std::invalid_argument("a flight needs N >= 1 durations and N - 1 waypoints");
  if (!(rho_t >= 0) || !(w_energy >= 0) || !(yaw_energy >= 0))
    throw std::invalid_argument("rho_T and the energy weights must be >= 0");
  energy_weights_ << w_energy, w_energy, w_energy, w_energy * yaw_energy;
  minco_.set_conditions(head, tail, pieces_);
  x0_.resize(dimension());
  x0_.head(MincoS3::kDims * (pieces_ - 1)) = Eigen::Map<const Eigen::VectorXd>(waypoints.data(), waypoints.size());
  for (int i = 0; i < pieces_; ++i) {
    if (!(durations(i) > 0)) throw std::invalid_argument("initial durations must be > 0");
    x0_(MincoS3::kDims * (pieces_ - 1) + i) = tau_from_duration(durations(i));
  }
}

void FlightProblem::decode(const Eigen::VectorXd& x) {
  q_ = Eigen::Map<const MincoS3::Points>(x.data(), MincoS3::kDims, pieces_ - 1);
  tau_ = x.tail(pieces_);
  durations_.resize(pieces_);
  for (int i = 0; i < pieces_; ++i) durations_(i) = duration_from_tau(tau_(i));
  minco_.set_parameters(q_, durations_);
}

double FlightProblem::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& g, FlightTerms* terms) {
  decode(x);
  grad_c_.setZero(6 * pieces_, MincoS3::kDims);
  grad_t_.setZero(pieces_);
  double f = cost_.evaluate(minco_.coefficients(), durations_, grad_c_, grad_t_, terms);
  f += minco_.jerk_energy(energy_weights_);
  minco_.add_jerk_energy_gradient(energy_weights_, grad_c_, grad_t_);
  f += rho_t_ * durations_.sum();
  grad_t_.array() += rho_t_;
  minco_.propagate_gradient(grad_c_, grad_t_, grad_q_, grad_T_);
  g.resize(dimension());
  g.head(MincoS3::kDims * (pieces_ - 1)) = Eigen::Map<const Eigen::VectorXd>(grad_q_.data(), grad_q_.size());
  for (int i = 0; i < pieces_; ++i) g(MincoS3::kDims * (pieces_ - 1) + i) = grad_T_(i) * duration_derivative(tau_(i));
  return f;
}

void FlightProblem::trajectory(const Eigen::VectorXd& x, MincoS3::Coefficients& coefficients,
                               Eigen::VectorXd& durations) {
  decode(x);
  coefficients = minco_.coefficients();
  durations = durations_;
}

FlightOutcome optimize_flight(FlightProblem& problem, const LbfgsParams& lbfgs) {
  FlightOutcome out;
  out.x = problem.initial();
  const LbfgsResult r = lbfgs_minimize(
      [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) { return problem.evaluate(x, g); }, out.x, lbfgs);
  out.iterations = r.iterations;
  out.evaluations = r.evaluations;
  out.f = r.f;
  out.status = to_string(r.status);
  out.reason = r.reason;
  Eigen::VectorXd g;
  problem.evaluate(out.x, g, &out.terms);
  return out;
}

}  // namespace lf3pm
