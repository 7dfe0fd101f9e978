#include "lf3pm/metric/metric.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace lf3pm {

namespace {
// A^T A is treated as singular below this fraction of its largest eigenvalue:
// float64 Gram rounding alone reaches ~1e-16 of it, so smaller values are noise.
constexpr double kRankTolerance = 1e-12;
}  // namespace

Metric metric_from_gram(const Eigen::MatrixXd& gram, std::int64_t m, const MetricWeights& weights) {
  const int n = static_cast<int>(gram.rows()) - 1;
  if (gram.rows() != gram.cols() || (n != 3 && n != 6))
    throw std::invalid_argument("the Gram of [A|b] must be 4x4 or 7x7");
  if (!gram.allFinite()) throw std::invalid_argument("non-finite observations (NaN or Inf in A or b)");
  if (!(weights.w1 > 0 && weights.w1 < 1)) throw std::invalid_argument("the metric weight w1 must lie in (0, 1)");

  const double inf = std::numeric_limits<double>::infinity();
  Metric out;
  out.m = m;
  out.n = n;
  const Eigen::MatrixXd ata = gram.topLeftCorner(n, n);
  const Eigen::VectorXd atb = gram.col(n).head(n);
  const double btb = gram(n, n);

  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(ata);
  const Eigen::VectorXd e = eig.eigenvalues();  // ascending
  const double e_min = std::max(e(0), 0.0), e_max = std::max(e(n - 1), 0.0);
  out.zhang = e(0);
  out.sigma1 = std::sqrt(e_min);
  out.residual_norm = std::sqrt(std::max(btb, 0.0));
  {
    const Eigen::VectorXd weakest = eig.eigenvectors().col(0);
    Eigen::Index largest = 0;
    weakest.cwiseAbs().maxCoeff(&largest);
    const double sign = weakest(largest) < 0 ? -1.0 : 1.0;
    for (int i = 0; i < n; ++i) out.least_observable[static_cast<std::size_t>(i)] = sign * weakest(i);
  }
  if (m < n + 1 || e_max <= 0.0 || e_min <= kRankTolerance * e_max) {
    out.degenerate = true;
    out.xi = out.q_min = out.q_n = out.q_max = inf;
    out.condition_number = out.cov_trace = out.step_norm = out.scaled_cov_trace = inf;
    return out;
  }
  out.degenerate = false;
  const Eigen::MatrixXd& v = eig.eigenvectors();
  const Eigen::VectorXd dx = v * (v.transpose() * atb).cwiseQuotient(e);
  const double r2 = std::max(btb - atb.dot(dx), 0.0);
  out.step_norm = dx.norm();
  out.residual_norm = std::sqrt(r2);
  out.xi = out.step_norm + out.residual_norm / out.sigma1;
  out.condition_number = std::sqrt(e_max / e_min);
  out.cov_trace = e.cwiseInverse().sum();
  out.scaled_cov_trace = m > n ? out.cov_trace * r2 / static_cast<double>(m - n) : inf;

  // Non-zero eigenvalues of Phi = xi^2 A A^T + b b^T are those of M^T M with
  // M = [xi A | b]; Phi's other m - n - 1 eigenvalues are zero.
  Eigen::MatrixXd gm(n + 1, n + 1);
  gm.topLeftCorner(n, n) = out.xi * out.xi * ata;
  gm.col(n).head(n) = out.xi * atb;
  gm.row(n).head(n) = out.xi * atb.transpose();
  gm(n, n) = btb;
  const Eigen::VectorXd g = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(gm, Eigen::EigenvaluesOnly).eigenvalues();
  const double lambda_1 = m > n + 1 ? 0.0 : std::max(g(0), 0.0);
  const double lambda_n = std::max(g(1), 0.0);  // lambda_{m-n+1}
  const double lambda_m = std::max(g(n), 0.0);
  auto q = [&](double lambda) { return std::sqrt(weights.w1 * lambda + weights.w2()) / out.sigma1; };
  out.q_min = q(lambda_1);
  out.q_n = q(lambda_n);
  out.q_max = q(lambda_m);
  return out;
}

}  // namespace lf3pm
