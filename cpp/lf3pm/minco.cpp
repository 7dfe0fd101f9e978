#include "lf3pm/minco.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lf3pm {

void BandedSystem::reset(int n, int lower, int upper) {
  n_ = n;
  lower_ = lower;
  upper_ = upper;
  band_.assign(std::size_t(lower + upper + 1) * n, 0.0);
}

void BandedSystem::factorize() {
  for (int k = 0; k < n_; ++k) {
    const int last_row = std::min(k + lower_, n_ - 1), last_col = std::min(k + upper_, n_ - 1);
    const double pivot = (*this)(k, k);
    for (int i = k + 1; i <= last_row; ++i) {
      double& l = (*this)(i, k);
      if (l == 0.0) continue;
      l /= pivot;
      for (int j = k + 1; j <= last_col; ++j) (*this)(i, j) -= l * (*this)(k, j);
    }
  }
}

void BandedSystem::solve(Eigen::MatrixX3d& b) const {
  for (int j = 0; j < n_; ++j)  // L y = b (unit diagonal)
    for (int i = j + 1; i <= std::min(j + lower_, n_ - 1); ++i)
      if ((*this)(i, j) != 0.0) b.row(i) -= (*this)(i, j) * b.row(j);
  for (int j = n_ - 1; j >= 0; --j) {  // U x = y
    b.row(j) /= (*this)(j, j);
    for (int i = std::max(0, j - upper_); i < j; ++i)
      if ((*this)(i, j) != 0.0) b.row(i) -= (*this)(i, j) * b.row(j);
  }
}

void BandedSystem::solve_transposed(Eigen::MatrixX3d& b) const {
  for (int j = 0; j < n_; ++j) {  // U^T y = b
    b.row(j) /= (*this)(j, j);
    for (int i = j + 1; i <= std::min(j + upper_, n_ - 1); ++i)
      if ((*this)(j, i) != 0.0) b.row(i) -= (*this)(j, i) * b.row(j);
  }
  for (int j = n_ - 1; j >= 0; --j)  // L^T x = y
    for (int i = std::max(0, j - lower_); i < j; ++i)
      if ((*this)(j, i) != 0.0) b.row(i) -= (*this)(j, i) * b.row(j);
}

void MincoS2::set_conditions(const Eigen::Matrix<double, 3, 2>& head, const Eigen::Matrix<double, 3, 2>& tail,
                             int pieces) {
  if (pieces < 1) throw std::invalid_argument("a trajectory needs at least one piece");
  n_ = pieces;
  head_ = head;
  tail_ = tail;
}

void MincoS2::set_parameters(const Eigen::Matrix3Xd& q, const Eigen::VectorXd& durations) {
  if (q.cols() != n_ - 1 || durations.size() != n_)
    throw std::invalid_argument("MINCO needs N-1 waypoints and N durations");
  t1_ = durations;
  t2_ = t1_.cwiseProduct(t1_);
  t3_ = t2_.cwiseProduct(t1_);
  a_.reset(4 * n_, 4, 4);
  coef_.setZero(4 * n_, 3);
  a_(0, 0) = 1.0;
  a_(1, 1) = 1.0;
  coef_.row(0) = head_.col(0).transpose();
  coef_.row(1) = head_.col(1).transpose();
  for (int i = 0; i < n_ - 1; ++i) {
    const int r = 4 * i + 2, c = 4 * i;
    a_(r, c + 2) = 2.0;  // acceleration continuity
    a_(r, c + 3) = 6.0 * t1_(i);
    a_(r, c + 6) = -2.0;
    for (int k : {1, 2}) {  // position = waypoint, position continuity
      a_(r + k, c) = 1.0;
      a_(r + k, c + 1) = t1_(i);
      a_(r + k, c + 2) = t2_(i);
      a_(r + k, c + 3) = t3_(i);
    }
    a_(r + 2, c + 4) = -1.0;
    coef_.row(r + 1) = q.col(i).transpose();
    a_(r + 3, c + 1) = 1.0;  // velocity continuity
    a_(r + 3, c + 2) = 2.0 * t1_(i);
    a_(r + 3, c + 3) = 3.0 * t2_(i);
    a_(r + 3, c + 5) = -1.0;
  }
  const int r = 4 * n_ - 2, c = 4 * (n_ - 1), last = n_ - 1;
  a_(r, c) = 1.0;
  a_(r, c + 1) = t1_(last);
  a_(r, c + 2) = t2_(last);
  a_(r, c + 3) = t3_(last);
  a_(r + 1, c + 1) = 1.0;
  a_(r + 1, c + 2) = 2.0 * t1_(last);
  a_(r + 1, c + 3) = 3.0 * t2_(last);
  coef_.row(r) = tail_.col(0).transpose();
  coef_.row(r + 1) = tail_.col(1).transpose();
  a_.factorize();
  a_.solve(coef_);
}

double MincoS2::energy() const { return acceleration_energy(coef_, t1_); }

double acceleration_energy(const Eigen::MatrixX3d& coef, const Eigen::VectorXd& durations) {
  double e = 0.0;
  for (Eigen::Index i = 0; i < durations.size(); ++i) {
    const Eigen::RowVector3d c2 = coef.row(4 * i + 2), c3 = coef.row(4 * i + 3);
    const double t = durations(i);
    e += 4.0 * c2.squaredNorm() * t + 12.0 * c2.dot(c3) * t * t + 12.0 * c3.squaredNorm() * t * t * t;
  }
  return e;
}

void add_acceleration_energy_gradient(double weight, const Eigen::MatrixX3d& coef, const Eigen::VectorXd& durations,
                                      Eigen::MatrixX3d& grad_c, Eigen::VectorXd& grad_t) {
  for (Eigen::Index i = 0; i < durations.size(); ++i) {
    const Eigen::RowVector3d c2 = coef.row(4 * i + 2), c3 = coef.row(4 * i + 3);
    const double t = durations(i), t2 = t * t;
    grad_c.row(4 * i + 2) += weight * (8.0 * t * c2 + 12.0 * t2 * c3);
    grad_c.row(4 * i + 3) += weight * (12.0 * t2 * c2 + 24.0 * t2 * t * c3);
    grad_t(i) += weight * (4.0 * c2.squaredNorm() + 24.0 * c2.dot(c3) * t + 36.0 * c3.squaredNorm() * t2);
  }
}

void MincoS2::propagate_gradient(Eigen::MatrixX3d& grad_c, const Eigen::VectorXd& grad_t, Eigen::Matrix3Xd& grad_q,
                                 Eigen::VectorXd& grad_T, Eigen::Matrix<double, 3, 2>* grad_head,
                                 Eigen::Matrix<double, 3, 2>* grad_tail) const {
  a_.solve_transposed(grad_c);  // the adjoint: G = A^-T dK/dc
  const Eigen::MatrixX3d& g = grad_c;
  // The head and tail conditions are the right-hand side's first and last two rows.
  if (grad_head) *grad_head << g.row(0).transpose(), g.row(1).transpose();
  if (grad_tail) *grad_tail << g.row(4 * n_ - 2).transpose(), g.row(4 * n_ - 1).transpose();
  grad_q.resize(3, n_ - 1);
  grad_T = grad_t;
  for (int i = 0; i < n_; ++i) {
    const Eigen::RowVector3d c1 = coef_.row(4 * i + 1), c2 = coef_.row(4 * i + 2), c3 = coef_.row(4 * i + 3);
    const Eigen::RowVector3d vel = c1 + 2.0 * t1_(i) * c2 + 3.0 * t2_(i) * c3;  // d(position row)/dT
    const Eigen::RowVector3d acc = 2.0 * c2 + 6.0 * t1_(i) * c3;                // d(velocity row)/dT
    if (i < n_ - 1) {
      const int r = 4 * i + 2;
      grad_q.col(i) = g.row(r + 1).transpose();
      grad_T(i) -= 6.0 * g.row(r).dot(c3) + (g.row(r + 1) + g.row(r + 2)).dot(vel) + g.row(r + 3).dot(acc);
    } else {
      const int r = 4 * n_ - 2;
      grad_T(i) -= g.row(r).dot(vel) + g.row(r + 1).dot(acc);
    }
  }
}

double duration_from_tau(double tau) {
  return tau > 0.0 ? (0.5 * tau + 1.0) * tau + 1.0 : 1.0 / ((0.5 * tau - 1.0) * tau + 1.0);
}

double tau_from_duration(double duration) {
  return duration > 1.0 ? std::sqrt(2.0 * duration - 1.0) - 1.0 : 1.0 - std::sqrt(2.0 / duration - 1.0);
}

double duration_derivative(double tau) {
  if (tau > 0.0) return tau + 1.0;
  const double den = (0.5 * tau - 1.0) * tau + 1.0;
  return (1.0 - tau) / (den * den);
}

}  // namespace lf3pm
