// MINCO for s = 2 (minimum acceleration): a piecewise-cubic trajectory in
// (x, y, yaw) fixed by its head and tail position + velocity (optionally + acceleration),
// the free intermediate waypoints and the N piece durations T_i.
//
// Piece i: p_i(t) = c_i0 + c_i1 t + c_i2 t^2 + c_i3 t^3, t in [0, T_i]. The 4N
// coefficients solve one banded linear system A(T) c = b(q, head, tail):
//   head              p_0(0) = position, p_0'(0) = velocity [, p_0''(0) = acceleration]
//   per junction i    p_i''(T_i) = p_{i+1}''(0), p_i(T_i) = q_{i+1},
//                     p_i(T_i) = p_{i+1}(0),     p_i'(T_i) = p_{i+1}'(0)
//   tail              p_{N-1}(T) = position, p_{N-1}'(T) = velocity [, p_{N-1}''(T) = acceleration]
// An end with its acceleration given frees the waypoint of the junction next to it (the
// first or the last), which the spline then places itself: the count of conditions stays
// 4N. (With the last junction's waypoint freed, its rows run acceleration, velocity,
// position continuity.) This row order keeps every pivot non-zero, so the LU needs no
// pivoting (tested against a dense solve).
// The minimiser of sum_i int ||p_i''||^2 dt under those conditions is exactly
// this C^2 cubic spline, so (q, T) is a complete, unconstrained parametrisation.
// Gradients of any cost K(c, T) reach (q, T) through one adjoint solve
// A^T G = dK/dc: dK/dq = G at the waypoint rows, dK/dT_i -= G^T (dA/dT_i) c.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "lf3pm/trajectory/banded_system.hpp"

namespace lf3pm {

/// Cubic MINCO (GCOPTER's MINCO_S2NU class) in three dimensions (x, y, yaw).
class MincoS2 {
 public:
  using State = Eigen::Matrix<double, 3, 3>;  ///< columns: position, velocity, acceleration

  /// Head/tail conditions: column 0 position, column 1 velocity, column 2 acceleration
  /// (used only where `head_acceleration` / `tail_acceleration`); `pieces` >= 1, and
  /// enough pieces for the freed waypoints (free_waypoints() >= 0).
  void set_conditions(const State& head, const State& tail, int pieces, bool head_acceleration = false,
                      bool tail_acceleration = false);
  /// Position and velocity conditions only.
  void set_conditions(const Eigen::Matrix<double, 3, 2>& head, const Eigen::Matrix<double, 3, 2>& tail, int pieces);
  /// Free intermediate waypoints (3 x free_waypoints()) and durations (N, all > 0): solves for the coefficients.
  void set_parameters(const Eigen::Matrix3Xd& waypoints, const Eigen::VectorXd& durations);

  int pieces() const { return n_; }
  /// Waypoints that are parameters: N - 1, less one per end with its acceleration given.
  int free_waypoints() const { return n_ - 1 - int(head_acc_) - int(tail_acc_); }
  const Eigen::VectorXd& durations() const { return t1_; }
  /// 4N x 3 coefficients; rows 4i..4i+3 are c_i0..c_i3 of piece i.
  const Eigen::MatrixX3d& coefficients() const { return coef_; }

  /// sum_i int_0^T_i ||p_i''(t)||^2 dt.
  double energy() const;
  /// Total gradients by the free waypoints (3 x free_waypoints()) and durations from the
  /// partial gradients by coefficients (consumed: overwritten by the adjoint) and by
  /// durations; if given, also by the head and tail conditions (3 x 3: position, velocity,
  /// acceleration; the last column is zero where no acceleration is given).
  void propagate_gradient(Eigen::MatrixX3d& grad_c, const Eigen::VectorXd& grad_t, Eigen::Matrix3Xd& grad_q,
                          Eigen::VectorXd& grad_T, State* grad_head = nullptr, State* grad_tail = nullptr) const;

 private:
  // One condition row: what it states and for which piece (a junction's rows: its left piece).
  enum class Kind {
    HeadPosition,
    HeadVelocity,
    HeadAcceleration,
    AccelerationContinuity,
    Waypoint,
    PositionContinuity,
    VelocityContinuity,
    TailPosition,
    TailVelocity,
    TailAcceleration
  };
  struct Row {
    Kind kind;
    int piece;
    int waypoint;  // column of q for Waypoint rows
  };
  int n_ = 0;
  bool head_acc_ = false, tail_acc_ = false;
  State head_ = State::Zero(), tail_ = State::Zero();
  std::vector<Row> rows_;
  Eigen::VectorXd t1_, t2_, t3_;
  BandedSystem a_;
  Eigen::MatrixX3d coef_;
};

/// sum_i int_0^T_i ||p_i''(t)||^2 dt of any piecewise cubic (4N x 3 coefficients, N durations).
double acceleration_energy(const Eigen::MatrixX3d& coef, const Eigen::VectorXd& durations);
/// Add weight * d(energy)/dc to grad_c (4N x 3) and weight * d(energy)/dT (partial) to grad_t.
void add_acceleration_energy_gradient(double weight, const Eigen::MatrixX3d& coef, const Eigen::VectorXd& durations,
                                      Eigen::MatrixX3d& grad_c, Eigen::VectorXd& grad_t);

}  // namespace lf3pm
