#include "lf3pm/trajectory/minco_s3.hpp"

#include <stdexcept>

namespace lf3pm {

Eigen::Matrix<double, 1, 6> quintic_basis(double t, int order) {
  Eigen::Matrix<double, 1, 6> out = Eigen::Matrix<double, 1, 6>::Zero();
  for (int k = order; k < 6; ++k) {
    double factor = 1.0;
    for (int j = 0; j < order; ++j) factor *= k - j;
    double power = 1.0;
    for (int j = 0; j < k - order; ++j) power *= t;
    out(k) = factor * power;
  }
  return out;
}

void MincoS3::set_conditions(const State& head, const State& tail, int pieces) {
  if (pieces < 1) throw std::invalid_argument("a trajectory needs at least one piece");
  n_ = pieces;
  head_ = head;
  tail_ = tail;
  rows_.clear();
  for (int d = 0; d < 3; ++d) rows_.push_back({0, d, false, false, Source::Head});
  for (int i = 0; i < n_ - 1; ++i) {
    rows_.push_back({i, 3, true, true, Source::Zero});
    rows_.push_back({i, 4, true, true, Source::Zero});
    rows_.push_back({i, 0, true, false, Source::Waypoint});
    for (int d = 0; d < 3; ++d) rows_.push_back({i, d, true, true, Source::Zero});
  }
  for (int d = 0; d < 3; ++d) rows_.push_back({n_ - 1, d, true, false, Source::Tail});
}

void MincoS3::set_parameters(const Points& q, const Eigen::VectorXd& durations) {
  if (q.cols() != n_ - 1 || durations.size() != n_)
    throw std::invalid_argument("MINCO needs N - 1 waypoints and N durations");
  for (int i = 0; i < n_; ++i)
    if (!(durations(i) > 0.0)) throw std::invalid_argument("MINCO's durations must be > 0");
  t_ = durations;
  a_.reset(6 * n_, 6, 6);
  coef_.setZero(6 * n_, kDims);
  for (int r = 0; r < 6 * n_; ++r) {
    const Row& row = rows_[r];
    const int c = 6 * row.piece;
    const Eigen::Matrix<double, 1, 6> at = quintic_basis(row.at_end ? t_(row.piece) : 0.0, row.order);
    for (int k = 0; k < 6; ++k)
      if (at(k) != 0.0) a_(r, c + k) = at(k);
    if (row.continuity) a_(r, c + 6 + row.order) = -quintic_basis(0.0, row.order)(row.order);
    switch (row.source) {
      case Source::Head:
        coef_.row(r) = head_.col(row.order).transpose();
        break;
      case Source::Tail:
        coef_.row(r) = tail_.col(row.order).transpose();
        break;
      case Source::Waypoint:
        coef_.row(r) = q.col(row.piece).transpose();
        break;
      case Source::Zero:
        break;
    }
  }
  a_.factorize();
  a_.solve(coef_);
}

namespace {

// int_0^T (p''')^2 dt of one coordinate of a quintic with coefficients c3, c4, c5, and its
// partial derivatives by them and by T.
struct JerkIntegral {
  double value, d3, d4, d5, dt;
};

JerkIntegral jerk_integral(double c3, double c4, double c5, double t) {
  // p''' = 6 c3 + 24 c4 t + 60 c5 t^2.
  const double t2 = t * t, t3 = t2 * t, t4 = t3 * t, t5 = t4 * t;
  JerkIntegral j;
  j.value = 36 * c3 * c3 * t + 144 * c3 * c4 * t2 + (192 * c4 * c4 + 240 * c3 * c5) * t3 + 720 * c4 * c5 * t4 +
            720 * c5 * c5 * t5;
  j.d3 = 72 * c3 * t + 144 * c4 * t2 + 240 * c5 * t3;
  j.d4 = 144 * c3 * t2 + 384 * c4 * t3 + 720 * c5 * t4;
  j.d5 = 240 * c3 * t3 + 720 * c4 * t4 + 1440 * c5 * t5;
  const double p = 6 * c3 + 24 * c4 * t + 60 * c5 * t2;  // the integrand at T
  j.dt = p * p;
  return j;
}

}  // namespace

double MincoS3::jerk_energy(const Eigen::Vector4d& w) const {
  double e = 0.0;
  for (int i = 0; i < n_; ++i)
    for (int d = 0; d < kDims; ++d)
      e += w(d) * jerk_integral(coef_(6 * i + 3, d), coef_(6 * i + 4, d), coef_(6 * i + 5, d), t_(i)).value;
  return e;
}

void MincoS3::add_jerk_energy_gradient(const Eigen::Vector4d& w, Coefficients& grad_c, Eigen::VectorXd& grad_t) const {
  for (int i = 0; i < n_; ++i)
    for (int d = 0; d < kDims; ++d) {
      const JerkIntegral j = jerk_integral(coef_(6 * i + 3, d), coef_(6 * i + 4, d), coef_(6 * i + 5, d), t_(i));
      grad_c(6 * i + 3, d) += w(d) * j.d3;
      grad_c(6 * i + 4, d) += w(d) * j.d4;
      grad_c(6 * i + 5, d) += w(d) * j.d5;
      grad_t(i) += w(d) * j.dt;
    }
}

void MincoS3::propagate_gradient(Coefficients& grad_c, const Eigen::VectorXd& grad_t, Points& grad_q,
                                 Eigen::VectorXd& grad_T) const {
  a_.solve_transposed(grad_c);  // the adjoint G = A^-T dK/dc
  grad_q.setZero(kDims, n_ - 1);
  grad_T = grad_t;
  for (int r = 0; r < 6 * n_; ++r) {
    const Row& row = rows_[r];
    if (row.source == Source::Waypoint) grad_q.col(row.piece) = grad_c.row(r).transpose();
    if (!row.at_end) continue;
    // d(row . c)/dT_i: the next derivative of piece i at its end.
    const int i = row.piece;
    const Eigen::Matrix<double, 1, kDims> rate = quintic_basis(t_(i), row.order + 1) * coef_.middleRows<6>(6 * i);
    grad_T(i) -= grad_c.row(r).dot(rate);
  }
}

}  // namespace lf3pm
