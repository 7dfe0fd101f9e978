#include "lf3pm/trajectory_optimizer.hpp"

#include <stdexcept>

namespace lf3pm {

TrajectoryProblem::TrajectoryProblem(TrajectoryCost cost, double rho_t, double w_energy,
                                     const Eigen::Matrix<double, 3, 2>& head, const Eigen::Matrix<double, 3, 2>& tail,
                                     const Eigen::Matrix3Xd& waypoints, const Eigen::VectorXd& durations)
    : cost_(std::move(cost)), rho_t_(rho_t), w_energy_(w_energy), pieces_(static_cast<int>(durations.size())) {
  if (pieces_ < 1 || waypoints.cols() != pieces_ - 1)
    throw std::invalid_argument("trajectory: N durations need N-1 intermediate waypoints");
  if ((durations.array() <= 0.0).any()) throw std::invalid_argument("trajectory: durations must be positive");
  minco_.set_conditions(head, tail, pieces_);
  cost_.set_end_headings(head(2, 0), tail(2, 0));
  x0_.resize(dimension());
  x0_.head(3 * (pieces_ - 1)) = Eigen::Map<const Eigen::VectorXd>(waypoints.data(), 3 * (pieces_ - 1));
  for (int i = 0; i < pieces_; ++i) x0_(3 * (pieces_ - 1) + i) = tau_from_duration(durations(i));
}

void TrajectoryProblem::decode(const Eigen::VectorXd& x) {
  if (x.size() != dimension()) throw std::invalid_argument("decision vector has the wrong size");
  q_ = Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, pieces_ - 1);
  tau_ = x.tail(pieces_);
  durations_.resize(pieces_);
  for (int i = 0; i < pieces_; ++i) durations_(i) = duration_from_tau(tau_(i));
  minco_.set_parameters(q_, durations_);
}

double TrajectoryProblem::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& g, CostTerms* terms) {
  decode(x);
  CostTerms t;
  grad_c_.setZero(4 * pieces_, 3);
  grad_t_.setZero(pieces_);
  cost_.add(minco_, grad_c_, grad_t_, t);
  t.energy = w_energy_ * minco_.energy();
  minco_.add_energy_gradient(w_energy_, grad_c_, grad_t_);
  t.time = rho_t_ * durations_.sum();
  grad_t_.array() += rho_t_;
  minco_.propagate_gradient(grad_c_, grad_t_, grad_q_, grad_T_);
  g.resize(dimension());
  g.head(3 * (pieces_ - 1)) = Eigen::Map<const Eigen::VectorXd>(grad_q_.data(), 3 * (pieces_ - 1));
  for (int i = 0; i < pieces_; ++i) g(3 * (pieces_ - 1) + i) = grad_T_(i) * duration_derivative(tau_(i));
  if (terms) *terms = t;
  return t.total();
}

void TrajectoryProblem::trajectory(const Eigen::VectorXd& x, Eigen::MatrixX3d& coefficients,
                                   Eigen::VectorXd& durations) {
  decode(x);
  coefficients = minco_.coefficients();
  durations = durations_;
}

OptimizeOutcome optimize(TrajectoryProblem& problem, const LbfgsParams& lbfgs) {
  OptimizeOutcome out;
  out.x = problem.initial();
  const Objective f = [&problem](const Eigen::VectorXd& x, Eigen::VectorXd& g) { return problem.evaluate(x, g); };
  const LbfgsResult r = lbfgs_minimize(f, out.x, lbfgs);
  out.iterations = r.iterations;
  out.evaluations = r.evaluations;
  out.status = to_string(r.status);
  Eigen::VectorXd g;
  problem.evaluate(out.x, g, &out.terms);
  return out;
}

}  // namespace lf3pm
