#include "lf3pm/trajectory/trajectory_optimizer.hpp"

#include <algorithm>
#include <stdexcept>

#include "lf3pm/trajectory/time_map.hpp"

namespace lf3pm {

TrajectoryProblem::TrajectoryProblem(TrajectoryCost cost, double rho_t, double w_energy,
                                     const Eigen::Matrix<double, 3, 2>& head, const Eigen::Matrix<double, 3, 2>& tail,
                                     const Eigen::Matrix3Xd& waypoints, const Eigen::VectorXd& durations)
    : cost_(std::move(cost)),
      rho_t_(rho_t),
      w_energy_(w_energy),
      pieces_(static_cast<int>(durations.size())),
      straight_ends_(cost_.robot().straight_ends()) {
  if (pieces_ < 1 || waypoints.cols() != pieces_ - 1)
    throw std::invalid_argument("trajectory: N durations need N-1 intermediate waypoints");
  if (straight_ends_ && pieces_ < 3)
    throw std::invalid_argument("trajectory: straight ends need a spline of at least 3 pieces");
  if ((durations.array() <= 0.0).any()) throw std::invalid_argument("trajectory: durations must be positive");
  // With straight ends the spline's head and tail take the junctions' accelerations too,
  // and place its first and last waypoints itself (minco.hpp): those are not parameters.
  cost_.keep_ends(head(0, 0), head(1, 0), tail(0, 0), tail(1, 0));
  const int skip = straight_ends_ ? 1 : 0, free = free_waypoints();
  if (straight_ends_) {
    minco_.set_conditions(MincoS2::State::Zero(), MincoS2::State::Zero(), pieces_, true, true);
  } else {
    minco_.set_conditions(head, tail, pieces_);
  }
  x0_.resize(dimension());
  for (int k = 0; k < free; ++k) x0_.segment<3>(3 * k) = waypoints.col(k + skip);
  for (int i = 0; i < pieces_; ++i) x0_(3 * free + i) = tau_from_duration(durations(i));
  if (straight_ends_) {
    // Initially each straight end covers a quarter of the way to its neighbouring
    // waypoint, reaching a quarter of the top speed.
    const double v = cost_.robot().vmax_lon, a_ref = 0.2 * v, v_ref = 0.5 * v;
    // A diff robot turns on the spot at both ends, so its straight ends may point anywhere;
    // a car's run along its given yaws.
    const bool free_heading = cost_.robot().turns_on_the_spot();
    lead_in_ = StraightEnd(head.col(0), false, a_ref, v_ref, free_heading);
    lead_out_ = StraightEnd(tail.col(0), true, a_ref, v_ref, free_heading);
    const Eigen::Vector2d next = waypoints.block<2, 1>(0, 0), prev = waypoints.block<2, 1>(0, pieces_ - 2);
    const double d_in = std::max(0.25 * (next - head.block<2, 1>(0, 0)).norm(), 1e-3);
    const double d_out = std::max(0.25 * (tail.block<2, 1>(0, 0) - prev).norm(), 1e-3);
    const int e = lead_in_.parameters();
    x0_.segment(dimension() - 2 * e, e) = lead_in_.parameters_for(d_in, 0.25 * v);
    x0_.tail(e) = lead_out_.parameters_for(d_out, 0.25 * v);
  }
}

void TrajectoryProblem::decode(const Eigen::VectorXd& x) {
  if (x.size() != dimension()) throw std::invalid_argument("decision vector has the wrong size");
  const int n = pieces_, off = straight_ends_ ? 1 : 0, all = n + 2 * off;
  const int free = free_waypoints();
  q_ = Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, free);
  tau_ = x.segment(3 * free, n);
  durations_.resize(n);
  for (int i = 0; i < n; ++i) durations_(i) = duration_from_tau(tau_(i));
  if (straight_ends_) {
    const int e = lead_in_.parameters();
    lead_in_.set(x.segment(dimension() - 2 * e, e));
    lead_out_.set(x.tail(e));
    minco_.set_conditions(lead_in_.junction(), lead_out_.junction(), n, true, true);
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
  MincoS2::State grad_head, grad_tail;
  minco_.propagate_gradient(grad_c_, grad_t, grad_q_, grad_T_, &grad_head, &grad_tail);
  const int free = free_waypoints();
  g.resize(dimension());
  g.head(3 * free) = Eigen::Map<const Eigen::VectorXd>(grad_q_.data(), 3 * free);
  for (int i = 0; i < n; ++i) g(3 * free + i) = grad_T_(i) * duration_derivative(tau_(i));
  if (straight_ends_) {
    const int e = lead_in_.parameters();
    g.segment(dimension() - 2 * e, e) = lead_in_.gradient(grad_c_all_.topRows<4>(), grad_t_all_(0), grad_head);
    g.tail(e) = lead_out_.gradient(grad_c_all_.bottomRows<4>(), grad_t_all_(all - 1), grad_tail);
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
  LbfgsParams params = lbfgs;
  Eigen::VectorXd g;
  for (int round = 0;; ++round) {
    const LbfgsResult r = lbfgs_minimize(f, out.x, params);
    out.iterations += r.iterations;
    out.evaluations += r.evaluations;
    out.status = to_string(r.status);
    out.reason = r.reason;
    problem.evaluate(out.x, g, &out.terms);
    // The relative-decrease test can stop L-BFGS in a narrow valley of the cubic
    // penalties with a limit still exceeded; then restart it there, with fresh
    // curvature pairs and a tenth of the tolerance (at most kRestarts times).
    const CostTerms& t = out.terms;
    const double penalties = t.velocity + t.omega + t.acceleration + t.turn + t.esdf;
    if (r.status != LbfgsStatus::Stalled || round == kRestarts || penalties <= 1e-3 * std::abs(t.total())) break;
    params.delta *= 0.1;
  }
  return out;
}

}  // namespace lf3pm
