#include "lf3pm/trajectory_optimizer.hpp"

#include <algorithm>
#include <stdexcept>

namespace lf3pm {

TrajectoryProblem::TrajectoryProblem(TrajectoryCost cost, double rho_t, double w_energy,
                                     const Eigen::Matrix<double, 3, 2>& head, const Eigen::Matrix<double, 3, 2>& tail,
                                     const Eigen::Matrix3Xd& waypoints, const Eigen::VectorXd& durations)
    : cost_(std::move(cost)),
      rho_t_(rho_t),
      w_energy_(w_energy),
      pieces_(static_cast<int>(durations.size())),
      straight_ends_(cost_.robot().straight_ends()),
      head_(head),
      tail_(tail) {
  if (pieces_ < 1 || waypoints.cols() != pieces_ - 1)
    throw std::invalid_argument("trajectory: N durations need N-1 intermediate waypoints");
  if ((durations.array() <= 0.0).any()) throw std::invalid_argument("trajectory: durations must be positive");
  minco_.set_conditions(head, tail, pieces_);
  x0_.resize(dimension());
  x0_.head(3 * (pieces_ - 1)) = Eigen::Map<const Eigen::VectorXd>(waypoints.data(), 3 * (pieces_ - 1));
  for (int i = 0; i < pieces_; ++i) x0_(3 * (pieces_ - 1) + i) = tau_from_duration(durations(i));
  if (straight_ends_) {
    // Initially each straight end covers a quarter of the way to its neighbouring
    // waypoint, reaching a quarter of the top speed.
    const double v = cost_.robot().vmax_lon, a_ref = 0.2 * v, v_ref = 0.5 * v;
    lead_in_ = StraightEnd(head.col(0), false, a_ref, v_ref);
    lead_out_ = StraightEnd(tail.col(0), true, a_ref, v_ref);
    const Eigen::Vector2d next = pieces_ > 1 ? Eigen::Vector2d(waypoints.block<2, 1>(0, 0)) : tail.block<2, 1>(0, 0);
    const Eigen::Vector2d prev =
        pieces_ > 1 ? Eigen::Vector2d(waypoints.block<2, 1>(0, pieces_ - 2)) : head.block<2, 1>(0, 0);
    const double d_in = std::max(0.25 * (next - head.block<2, 1>(0, 0)).norm(), 1e-3);
    const double d_out = std::max(0.25 * (tail.block<2, 1>(0, 0) - prev).norm(), 1e-3);
    x0_.segment<3>(dimension() - 6) = lead_in_.parameters_for(d_in, 0.25 * v);
    x0_.tail<3>() = lead_out_.parameters_for(d_out, 0.25 * v);
  }
}

void TrajectoryProblem::decode(const Eigen::VectorXd& x) {
  if (x.size() != dimension()) throw std::invalid_argument("decision vector has the wrong size");
  const int n = pieces_, off = straight_ends_ ? 1 : 0, all = n + 2 * off;
  q_ = Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, n - 1);
  tau_ = x.segment(3 * (n - 1), n);
  durations_.resize(n);
  for (int i = 0; i < n; ++i) durations_(i) = duration_from_tau(tau_(i));
  if (straight_ends_) {
    lead_in_.set(x.segment<3>(dimension() - 6));
    lead_out_.set(x.tail<3>());
    minco_.set_conditions(lead_in_.junction(), lead_out_.junction(), n);
  }
  minco_.set_parameters(q_, durations_);
  coef_all_.resize(4 * all, 3);
  durations_all_.resize(all);
  coef_all_.middleRows(4 * off, 4 * n) = minco_.coefficients();
  durations_all_.segment(off, n) = durations_;
  if (straight_ends_) {
    coef_all_.topRows<4>() = lead_in_.coefficients();
    coef_all_.bottomRows<4>() = lead_out_.coefficients();
    durations_all_(0) = lead_in_.duration();
    durations_all_(all - 1) = lead_out_.duration();
  }
}

double TrajectoryProblem::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& g, CostTerms* terms) {
  decode(x);
  const int n = pieces_, off = straight_ends_ ? 1 : 0, all = n + 2 * off;
  CostTerms t;
  grad_c_all_.setZero(4 * all, 3);
  grad_t_all_.setZero(all);
  cost_.add(coef_all_, durations_all_, grad_c_all_, grad_t_all_, t);
  t.energy = w_energy_ * acceleration_energy(coef_all_, durations_all_);
  add_acceleration_energy_gradient(w_energy_, coef_all_, durations_all_, grad_c_all_, grad_t_all_);
  t.time = rho_t_ * durations_all_.sum();
  grad_t_all_.array() += rho_t_;
  // The spline's share reaches its waypoints, durations and (a car) its head and tail.
  grad_c_ = grad_c_all_.middleRows(4 * off, 4 * n);
  const Eigen::VectorXd grad_t = grad_t_all_.segment(off, n);
  Eigen::Matrix<double, 3, 2> grad_head, grad_tail;
  minco_.propagate_gradient(grad_c_, grad_t, grad_q_, grad_T_, &grad_head, &grad_tail);
  g.resize(dimension());
  g.head(3 * (n - 1)) = Eigen::Map<const Eigen::VectorXd>(grad_q_.data(), 3 * (n - 1));
  for (int i = 0; i < n; ++i) g(3 * (n - 1) + i) = grad_T_(i) * duration_derivative(tau_(i));
  if (straight_ends_) {
    g.segment<3>(dimension() - 6) = lead_in_.gradient(grad_c_all_.topRows<4>(), grad_t_all_(0), grad_head);
    g.tail<3>() = lead_out_.gradient(grad_c_all_.bottomRows<4>(), grad_t_all_(all - 1), grad_tail);
  }
  if (terms) *terms = t;
  return t.total();
}

void TrajectoryProblem::trajectory(const Eigen::VectorXd& x, Eigen::MatrixX3d& coefficients,
                                   Eigen::VectorXd& durations) {
  decode(x);
  coefficients = coef_all_;
  durations = durations_all_;
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
