// The LF-3PM perturbation-induced observation-loss metric and classic baselines,
// computed from the Gram of [A | b] (never the m x m matrix Phi): see docs/design.md.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

namespace lf3pm {

/// q = sqrt(w1 lambda + w2) / sigma1 with w2 = 1 - w1 (the paper's weights sum to one).
struct MetricWeights {
  double w1 = 0.5;
  double w2() const { return 1.0 - w1; }
};

struct Metric {
  std::int64_t m = 0;  // observation rows
  int n = 6;           // state dimension (6: SE(3), 3: x, y, yaw)
  bool degenerate = true;
  double sigma1 = 0.0;  // smallest singular value of A
  double xi = 0.0;      // |dx*| + |r| / sigma1
  double q_min = 0.0, q_n = 0.0, q_max = 0.0;
  // Baselines.
  double zhang = 0.0;             // smallest eigenvalue of A^T A (Zhang et al. 2016)
  double condition_number = 0.0;  // sigma_max / sigma_min of A
  double cov_trace = 0.0;         // trace((A^T A)^-1)
  double step_norm = 0.0;         // |dx*|, least-squares step at the true pose
  double residual_norm = 0.0;     // |r| = |A dx* - b|
  double scaled_cov_trace = 0.0;  // trace((A^T A)^-1) * |r|^2 / (m - n)
  // The least observable direction: the unit eigenvector of A^T A's smallest eigenvalue
  // (first n entries: translation, then rotation; its largest entry positive).
  std::array<double, 6> least_observable{};
};

/// Metric from the Gram G = [A b]^T [A b] ((n+1) x (n+1), n = 3 or 6) of m rows.
/// Fewer than n + 1 rows or a rank-deficient A give degenerate = true and
/// infinite q (never NaN). Throws std::invalid_argument for a non-finite G or
/// invalid weights.
Metric metric_from_gram(const Eigen::MatrixXd& gram, std::int64_t m, const MetricWeights& weights);

}  // namespace lf3pm
