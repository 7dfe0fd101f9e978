#include "lf3pm/trajectory/lbfgs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

namespace lf3pm {

namespace {

/// What a line search found: a step, or none and how far f moved over its trials.
struct SearchOutcome {
  bool found = false;
  double f_moved = 0.0;  ///< max |f(x0 + step d) - f0| over the trials
};

// Lewis & Overton (2013): bisect a bracket [lo, hi] on the step until the weak
// Wolfe conditions hold, doubling the step while no upper end is known.
SearchOutcome weak_wolfe_search(const Objective& f, const Eigen::VectorXd& x0, double f0, const Eigen::VectorXd& g0,
                                const Eigen::VectorXd& d, double& step, Eigen::VectorXd& x, double& fx,
                                Eigen::VectorXd& g, const LbfgsParams& p, int& evaluations) {
  SearchOutcome out;
  const double dg0 = g0.dot(d);
  if (!(dg0 < 0.0)) return out;
  double lo = 0.0, hi = std::numeric_limits<double>::infinity();
  for (int k = 0; k < p.max_linesearch; ++k) {
    x = x0 + step * d;
    fx = f(x, g);
    ++evaluations;
    out.f_moved = std::max(out.f_moved, std::isfinite(fx) ? std::abs(fx - f0) : fx);
    if (!std::isfinite(fx) || fx > f0 + p.armijo * step * dg0) {
      hi = step;
    } else if (g.dot(d) < p.wolfe * dg0) {
      lo = step;
    } else {
      out.found = true;
      return out;
    }
    step = std::isinf(hi) ? 2.0 * step : 0.5 * (lo + hi);
    if (step < p.min_step || step > p.max_step) break;
  }
  return out;
}

template <typename... Values>
std::string format(const char* pattern, Values... values) {
  char text[256];
  std::snprintf(text, sizeof text, pattern, values...);
  return text;
}

}  // namespace

LbfgsResult lbfgs_minimize(const Objective& f, Eigen::VectorXd& x, const LbfgsParams& p) {
  if (p.memory < 1) throw std::invalid_argument("lbfgs: memory must be >= 1");
  const Eigen::Index n = x.size();
  const int m = p.memory;
  Eigen::MatrixXd s_hist(n, m), y_hist(n, m);
  std::vector<double> rho(m), alpha(m);
  std::vector<double> past_f(std::max(p.past, 1));

  LbfgsResult res;
  Eigen::VectorXd g(n), x_prev(n), g_prev(n), d(n);
  res.f = f(x, g);
  res.evaluations = 1;
  if (!std::isfinite(res.f)) throw std::invalid_argument("lbfgs: objective is not finite at the start");
  past_f[0] = res.f;

  auto converged = [&] {
    const double bound = p.g_epsilon * std::max(1.0, x.norm());
    if (g.norm() > bound) return false;
    res.reason = format("gradient: |g| = %.3g <= g_epsilon max(1, |x|) = %.3g", g.norm(), bound);
    return true;
  };
  if (converged()) {
    res.gradient_norm = g.norm();
    return res;
  }
  d = -g;
  double step = 1.0 / d.norm();  // first step: unit length in x
  int stored = 0, next = 0;      // ring buffer of correction pairs; `next` is the slot to fill
  for (int k = 1;; ++k) {
    x_prev = x;
    g_prev = g;
    const double f_prev = res.f;
    const SearchOutcome search = weak_wolfe_search(f, x_prev, f_prev, g_prev, d, step, x, res.f, g, p, res.evaluations);
    if (!search.found) {
      // Keep the better of the last trial and the start of the search.
      if (!(res.f < f_prev)) {
        x = x_prev;
        g = g_prev;
        res.f = f_prev;
      }
      const double promised = -g_prev.dot(d);
      const double rounding = std::sqrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(f_prev));
      if (search.f_moved <= rounding && promised <= 2.0 * search.f_moved) {
        res.status = LbfgsStatus::Converged;
        res.reason = format(
            "float precision: over the line search f changed by at most %.3g, within rounding "
            "(<= sqrt(eps) max(1, |f|) = %.3g), and by no less than the %.3g decrease the step "
            "promised",
            search.f_moved, rounding, promised);
      } else {
        res.status = LbfgsStatus::LineSearchFailed;
        res.reason = format(
            "no step met the Wolfe conditions: f changed by up to %.3g over the search "
            "(rounding stays within %.3g) against a promised decrease of %.3g",
            search.f_moved, rounding, promised);
      }
      break;
    }
    res.iterations = k;
    if (converged()) break;
    if (p.past > 0) {
      if (k >= p.past && (past_f[k % p.past] - res.f) <= p.delta * std::max(1.0, std::abs(res.f))) {
        res.status = LbfgsStatus::Stalled;
        res.reason = format("f fell by %.3g over the last %d iterations, <= delta max(1, |f|)",
                            past_f[k % p.past] - res.f, p.past);
        break;
      }
      past_f[k % p.past] = res.f;
    }
    if (p.max_iterations > 0 && k >= p.max_iterations) {
      res.status = LbfgsStatus::MaxIterations;
      res.reason = format("reached %d iterations", p.max_iterations);
      break;
    }
    // Cautious update (Li & Fukushima): keep the pair only with enough curvature,
    // which preserves a positive definite inverse Hessian on non-convex costs.
    const Eigen::VectorXd s = x - x_prev, y = g - g_prev;
    const double sy = s.dot(y);
    if (sy > 1e-6 * s.squaredNorm() * g_prev.norm()) {
      s_hist.col(next) = s;
      y_hist.col(next) = y;
      rho[next] = 1.0 / sy;
      next = (next + 1) % m;
      stored = std::min(stored + 1, m);
    }
    const int newest = (next + m - 1) % m;
    // Two-loop recursion: d = -H g.
    d = -g;
    for (int i = 0; i < stored; ++i) {
      const int j = (newest + m - i) % m;
      alpha[j] = rho[j] * s_hist.col(j).dot(d);
      d -= alpha[j] * y_hist.col(j);
    }
    if (stored > 0) d *= 1.0 / (rho[newest] * y_hist.col(newest).squaredNorm());
    for (int i = stored - 1; i >= 0; --i) {
      const int j = (newest + m - i) % m;
      const double beta = rho[j] * y_hist.col(j).dot(d);
      d += (alpha[j] - beta) * s_hist.col(j);
    }
    step = 1.0;
  }
  res.gradient_norm = g.norm();
  return res;
}

const char* to_string(LbfgsStatus status) {
  switch (status) {
    case LbfgsStatus::Converged:
      return "converged";
    case LbfgsStatus::Stalled:
      return "stalled";
    case LbfgsStatus::MaxIterations:
      return "max_iterations";
    case LbfgsStatus::LineSearchFailed:
      return "line_search_failed";
  }
  return "unknown";
}

}  // namespace lf3pm
