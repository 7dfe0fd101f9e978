// MINCO for s = 3 (minimum jerk; GCOPTER's MINCO_S3NU is the reference for the object, the
// code is ours): a piecewise-quintic trajectory in D = 4 dimensions, a quadrotor's flat
// outputs (x, y, z, yaw), fixed by its head and tail position, velocity and acceleration,
// the N - 1 intermediate waypoints q and the N piece durations T_i.
//
// Piece i: p_i(t) = sum_k c_ik t^k, k = 0..5, t in [0, T_i]. The 6N coefficients solve one
// banded system A(T) c = b(q, head, tail) of rows, in this order (which keeps every pivot of
// a factorisation without pivoting non-zero):
//   head             p_0(0), p_0'(0), p_0''(0) = the head's position, velocity, acceleration
//   per junction i   p_i'''(T_i) = p_{i+1}'''(0), p_i''''(T_i) = p_{i+1}''''(0),
//                    p_i(T_i) = q_i, p_i(T_i) = p_{i+1}(0), p_i'(T_i) = p_{i+1}'(0),
//                    p_i''(T_i) = p_{i+1}''(0)
//   tail             p_{N-1}(T), p_{N-1}'(T), p_{N-1}''(T) = the tail's
// The minimiser of sum_i int ||p_i'''||^2 dt under the head, tail and waypoints is exactly
// this C^4 quintic spline, so (q, T) parametrise minimum-jerk trajectories completely.
// Gradients of any cost K(c, T) reach (q, T) through one adjoint solve A^T G = dK/dc:
// dK/dq_i = G at the waypoint rows, dK/dT_i -= sum over piece i's end rows of G_r . (the
// next derivative of p_i at T_i).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "lf3pm/trajectory/banded_system.hpp"

namespace lf3pm {

class MincoS3 {
 public:
  static constexpr int kDims = 4;
  using Coefficients = Eigen::Matrix<double, Eigen::Dynamic, kDims>;  ///< 6N x 4: rows 6i..6i+5 are c_i0..c_i5
  using Points = Eigen::Matrix<double, kDims, Eigen::Dynamic>;        ///< one column per waypoint
  using State = Eigen::Matrix<double, kDims, 3>;                      ///< columns: position, velocity, acceleration

  /// Head and tail conditions and the piece count (>= 1).
  void set_conditions(const State& head, const State& tail, int pieces);
  /// The N - 1 intermediate waypoints (4 x (N - 1)) and N durations (> 0): solves for c.
  void set_parameters(const Points& waypoints, const Eigen::VectorXd& durations);

  int pieces() const { return n_; }
  const Eigen::VectorXd& durations() const { return t_; }
  const Coefficients& coefficients() const { return coef_; }

  /// sum_i int_0^T_i sum_d w_d (p_i,d'''(t))^2 dt with per-dimension weights w.
  double jerk_energy(const Eigen::Vector4d& weights) const;
  /// Adds the energy's partial gradients by c and T (weighted as jerk_energy) to grad_c, grad_t.
  void add_jerk_energy_gradient(const Eigen::Vector4d& weights, Coefficients& grad_c, Eigen::VectorXd& grad_t) const;
  /// Total gradients by the waypoints (4 x (N - 1)) and the durations from the partial
  /// gradients by c (consumed: overwritten by the adjoint) and by T.
  void propagate_gradient(Coefficients& grad_c, const Eigen::VectorXd& grad_t, Points& grad_q,
                          Eigen::VectorXd& grad_T) const;

 private:
  // One row of A: derivative `order` of piece `piece` at its end (or, for a head row, at 0),
  // minus that of the next piece at 0 for continuity rows; the right side as `source`.
  enum class Source { Head, Tail, Waypoint, Zero };
  struct Row {
    int piece, order;
    bool at_end, continuity;
    Source source;
  };
  int n_ = 0;
  State head_ = State::Zero(), tail_ = State::Zero();
  std::vector<Row> rows_;
  Eigen::VectorXd t_;
  BandedSystem a_;
  Coefficients coef_;
};

/// d^order/dt^order of t^k at t, k = 0..5 (zero below order): the row a piece's
/// derivative is evaluated with.
Eigen::Matrix<double, 1, 6> quintic_basis(double t, int order);

}  // namespace lf3pm
