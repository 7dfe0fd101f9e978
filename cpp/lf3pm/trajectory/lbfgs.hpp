// Limited-memory BFGS with a Lewis-Overton weak-Wolfe line search.
//
// Why our own: no C++ L-BFGS is packaged on PyPI or Debian that we could link
// cleanly (LBFGS-Lite and LBFGSpp are header-only files to vendor), and scipy's
// L-BFGS-B must call back into Python for every evaluation, so it cannot run
// inside the C++ planner. bench/bench_planner_backend.py (206 m, 101 pieces, one
// thread, acceleration limits) measured 32.9 ms (omni) against 56.2 ms for scipy
// L-BFGS-B with Python callbacks on the same objective (1.7x), and on par for diff
// and car (19.8 vs 18.5 ms, 19.3 vs 19.1 ms; BENCHMARK.md). The objective dominates.
//
// The Lewis-Overton search (bisection on a bracket, doubling until one exists)
// asks only for the weak Wolfe conditions, which keeps it robust on objectives
// whose gradient is merely continuous (penalties switching on, clamped grids).
//
// Convergence at float precision. Near a minimum the decrease a step promises
// (-g.d, twice the quadratic model's for d = -H g) falls below the rounding error
// of f itself; no trial then passes the sufficient-decrease test, because f no
// longer changes in its trailing bits but by rounding. A failed search is that, and
// reported as convergence, when f moved over all its trials by no more than
// sqrt(eps) max(1, |f|) (its trailing half: the rounding of an objective summing up
// to ~1e7 terms of |f|'s size, or cancelling that much, stays below it, while a step
// that really changes f moves it further) and the promised decrease is no larger
// than what f moved by rounding. Anything else, a search that saw f change and still
// found no step (a wrong gradient, a kink), stays a failure.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>

namespace lf3pm {

struct LbfgsParams {
  int memory = 8;           ///< stored correction pairs
  double g_epsilon = 1e-6;  ///< stop when ||g|| <= g_epsilon * max(1, ||x||)
  int past = 3;             ///< stop when f fell by less than delta * max(1, |f|) over `past` iterations
  double delta = 1e-9;
  int max_iterations = 0;  ///< 0: no limit
  int max_linesearch = 64;
  double armijo = 1e-4;  ///< sufficient decrease coefficient
  double wolfe = 0.9;    ///< curvature coefficient (weak Wolfe)
  double min_step = 1e-20;
  double max_step = 1e20;
};

enum class LbfgsStatus { Converged, Stalled, MaxIterations, LineSearchFailed };

struct LbfgsResult {
  LbfgsStatus status = LbfgsStatus::Converged;
  std::string reason;  ///< why it stopped, with the numbers that decided it
  int iterations = 0;
  int evaluations = 0;
  double f = 0.0;
  double gradient_norm = 0.0;
};

/// f(x, g): the objective's value at x, its gradient written into g (same size as x).
using Objective = std::function<double(const Eigen::VectorXd& x, Eigen::VectorXd& g)>;

/// Minimise f from x (updated in place to the best point found).
LbfgsResult lbfgs_minimize(const Objective& f, Eigen::VectorXd& x, const LbfgsParams& params = {});

const char* to_string(LbfgsStatus status);

}  // namespace lf3pm
