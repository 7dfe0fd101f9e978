#include "lf3pm/trajectory/minco.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lf3pm {

void MincoS2::set_conditions(const State& head, const State& tail, int pieces, bool head_acceleration,
                             bool tail_acceleration) {
  if (pieces < 1) throw std::invalid_argument("a trajectory needs at least one piece");
  n_ = pieces;
  head_acc_ = head_acceleration;
  tail_acc_ = tail_acceleration;
  if (free_waypoints() < 0 || (head_acc_ && tail_acc_ && n_ < 3))
    throw std::invalid_argument("MINCO: too few pieces for the acceleration conditions");
  head_ = head;
  tail_ = tail;
  if (!head_acc_) head_.col(2).setZero();
  if (!tail_acc_) tail_.col(2).setZero();
  rows_.clear();
  rows_.push_back({Kind::HeadPosition, 0, -1});
  rows_.push_back({Kind::HeadVelocity, 0, -1});
  if (head_acc_) rows_.push_back({Kind::HeadAcceleration, 0, -1});
  int waypoint = 0;
  for (int i = 0; i < n_ - 1; ++i) {
    const bool freed_head = head_acc_ && i == 0, freed_tail = tail_acc_ && i == n_ - 2;
    rows_.push_back({Kind::AccelerationContinuity, i, -1});
    if (freed_tail) {  // no waypoint row: velocity first keeps the pivots non-zero
      rows_.push_back({Kind::VelocityContinuity, i, -1});
      rows_.push_back({Kind::PositionContinuity, i, -1});
      continue;
    }
    if (!freed_head) rows_.push_back({Kind::Waypoint, i, waypoint++});
    rows_.push_back({Kind::PositionContinuity, i, -1});
    rows_.push_back({Kind::VelocityContinuity, i, -1});
  }
  rows_.push_back({Kind::TailPosition, n_ - 1, -1});
  rows_.push_back({Kind::TailVelocity, n_ - 1, -1});
  if (tail_acc_) rows_.push_back({Kind::TailAcceleration, n_ - 1, -1});
}

void MincoS2::set_conditions(const Eigen::Matrix<double, 3, 2>& head, const Eigen::Matrix<double, 3, 2>& tail,
                             int pieces) {
  State h = State::Zero(), t = State::Zero();
  h.leftCols<2>() = head;
  t.leftCols<2>() = tail;
  set_conditions(h, t, pieces);
}

void MincoS2::set_parameters(const Eigen::Matrix3Xd& q, const Eigen::VectorXd& durations) {
  if (q.cols() != free_waypoints() || durations.size() != n_)
    throw std::invalid_argument("MINCO needs its free waypoints and N durations");
  t1_ = durations;
  t2_ = t1_.cwiseProduct(t1_);
  t3_ = t2_.cwiseProduct(t1_);
  a_.reset(4 * n_, 4, 4);
  coef_.setZero(4 * n_, 3);
  for (int r = 0; r < 4 * n_; ++r) {
    const Row& row = rows_[r];
    const int i = row.piece, c = 4 * i;
    const double t = t1_(i), t2 = t2_(i), t3 = t3_(i);
    // Position, velocity and acceleration of piece i at its end, as rows over its coefficients.
    auto position_end = [&] { a_(r, c) = 1.0, a_(r, c + 1) = t, a_(r, c + 2) = t2, a_(r, c + 3) = t3; };
    auto velocity_end = [&] { a_(r, c + 1) = 1.0, a_(r, c + 2) = 2.0 * t, a_(r, c + 3) = 3.0 * t2; };
    auto acceleration_end = [&] { a_(r, c + 2) = 2.0, a_(r, c + 3) = 6.0 * t; };
    switch (row.kind) {
      case Kind::HeadPosition:
        a_(r, 0) = 1.0, coef_.row(r) = head_.col(0).transpose();
        break;
      case Kind::HeadVelocity:
        a_(r, 1) = 1.0, coef_.row(r) = head_.col(1).transpose();
        break;
      case Kind::HeadAcceleration:
        a_(r, 2) = 2.0, coef_.row(r) = head_.col(2).transpose();
        break;
      case Kind::AccelerationContinuity:
        acceleration_end(), a_(r, c + 6) = -2.0;
        break;
      case Kind::Waypoint:
        position_end(), coef_.row(r) = q.col(row.waypoint).transpose();
        break;
      case Kind::PositionContinuity:
        position_end(), a_(r, c + 4) = -1.0;
        break;
      case Kind::VelocityContinuity:
        velocity_end(), a_(r, c + 5) = -1.0;
        break;
      case Kind::TailPosition:
        position_end(), coef_.row(r) = tail_.col(0).transpose();
        break;
      case Kind::TailVelocity:
        velocity_end(), coef_.row(r) = tail_.col(1).transpose();
        break;
      case Kind::TailAcceleration:
        acceleration_end(), coef_.row(r) = tail_.col(2).transpose();
        break;
    }
  }
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
                                 Eigen::VectorXd& grad_T, State* grad_head, State* grad_tail) const {
  a_.solve_transposed(grad_c);  // the adjoint: G = A^-T dK/dc
  const Eigen::MatrixX3d& g = grad_c;
  if (grad_head) grad_head->setZero();
  if (grad_tail) grad_tail->setZero();
  grad_q.setZero(3, free_waypoints());
  grad_T = grad_t;
  for (int r = 0; r < 4 * n_; ++r) {
    const Row& row = rows_[r];
    const int i = row.piece;
    const Eigen::RowVector3d c1 = coef_.row(4 * i + 1), c2 = coef_.row(4 * i + 2), c3 = coef_.row(4 * i + 3);
    // d(row . c)/dT_i: the end position's rate is the end velocity, and so on.
    const Eigen::RowVector3d vel = c1 + 2.0 * t1_(i) * c2 + 3.0 * t2_(i) * c3, acc = 2.0 * c2 + 6.0 * t1_(i) * c3;
    switch (row.kind) {
      case Kind::HeadPosition:
        if (grad_head) grad_head->col(0) = g.row(r).transpose();
        break;
      case Kind::HeadVelocity:
        if (grad_head) grad_head->col(1) = g.row(r).transpose();
        break;
      case Kind::HeadAcceleration:
        if (grad_head) grad_head->col(2) = g.row(r).transpose();
        break;
      case Kind::AccelerationContinuity:
        grad_T(i) -= 6.0 * g.row(r).dot(c3);
        break;
      case Kind::Waypoint:
        grad_q.col(row.waypoint) = g.row(r).transpose(), grad_T(i) -= g.row(r).dot(vel);
        break;
      case Kind::PositionContinuity:
        grad_T(i) -= g.row(r).dot(vel);
        break;
      case Kind::VelocityContinuity:
        grad_T(i) -= g.row(r).dot(acc);
        break;
      case Kind::TailPosition:
        if (grad_tail) grad_tail->col(0) = g.row(r).transpose();
        grad_T(i) -= g.row(r).dot(vel);
        break;
      case Kind::TailVelocity:
        if (grad_tail) grad_tail->col(1) = g.row(r).transpose();
        grad_T(i) -= g.row(r).dot(acc);
        break;
      case Kind::TailAcceleration:
        if (grad_tail) grad_tail->col(2) = g.row(r).transpose();
        grad_T(i) -= 6.0 * g.row(r).dot(c3);
        break;
    }
  }
}

}  // namespace lf3pm
