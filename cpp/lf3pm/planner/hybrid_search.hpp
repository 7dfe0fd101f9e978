// The planner's front end for cars: a Hybrid-A*-style forward search (Dolgov et
// al. 2008) over continuous poses, so that a car's path leaves the start and
// reaches the goal along their yaws, turning no tighter than R and never reversing.
//
// Moves: from a pose, three primitives of one length (`step`, default sqrt 2 res:
// far enough to leave a cell): an arc of radius R to the left, a straight, an arc
// to the right (arcs at most a quarter turn, so a small R still moves on), forwards
// only. States: the ESDF's x-y cells times `yaw_bins` yaw bins; each keeps the
// continuous pose of the cheapest arrival (a successor landing in its parent's
// state is dropped). The goal is reached exactly by an analytic expansion: the
// shortest forward Dubins path (dubins.hpp) from an expanded pose to the goal,
// accepted when collision-free; it is tried on the first expansion, every
// `analytic_every` expansions after, and at every expansion within 4 R + step of
// the goal. The search keeps the cheapest complete path and stops when no open
// state can beat it (f = g + h >= its cost) or when the open list runs out.
//
// Cost of a move: sum over its samples of ds (1 + weight c(x, y, yaw)) (midpoint
// rule), c the trajectory optimiser's cost field (the filled cost layer,
// interpolated): the grid front end's length * (1 + weight c) and the back end's
// time-weighted cost at constant speed. Collision: every sample (spacing at most
// `sample_step`, ends included) lies on the grid with ESDF >= `clearance`.
//
// Heuristic, h = max((1 + weight c_min) Dubins(p, goal), G(cell of p)):
//   - Dubins(p, goal) ignores obstacles: no forward path of turning radius >= R
//     is shorter (Dubins' theorem), and every metre costs at least 1 + weight
//     c_min, c_min the least cost value (interpolation never goes below it);
//   - G ignores heading: D / kappa - slack, D the 8-connected octile cost to
//     the goal's cell (diagonals need no corner cells) through cells where a sample
//     could be collision-free (the bilinear ESDF reaches `clearance` somewhere in the
//     cell: at a corner of one of its quadrants), kappa = sqrt(4 - 2
//     sqrt 2) the most an octile distance exceeds the Euclidean one (at 22.5
//     degrees), and sqrt 2 res for the start and goal lying off their cell centres.
//     Each relaxed step costs l (1 + weight m), m the least cost any sample in
//     either cell can read (the 3 x 3 centres around it, any layer), and the slack
//     is sqrt 2 res (1 + weight max m). G is a lower bound of a path's cost (up to
//     the samples' spacing) rather than a proven one: tests compare h with found
//     costs (docs/planner_frontend.md).
// The closed set on cells x bins makes the search resolution-complete, not complete
// or optimal: a pruned pose may have led somewhere a kept one cannot.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lf3pm/planner/dubins.hpp"
#include "lf3pm/planner/grid_field.hpp"

namespace lf3pm {

struct HybridParams {
  double radius = 0.5;       ///< R: the car's least turning radius (m), > 0
  double weight = 1.0;       ///< lambda: perception cost against length
  double clearance = 0.0;    ///< least ESDF value at every sample (m)
  int yaw_bins = 72;         ///< closed set: yaw bins per x-y cell
  double step = 0.0;         ///< primitive length (m); 0: sqrt 2 res
  double sample_step = 0.0;  ///< collision and cost sample spacing (m); 0: res / 4
  int analytic_every = 5;    ///< try a Dubins path to the goal every this many expansions
  std::uint64_t max_expansions = 2'000'000;
  bool heuristic = true;  ///< false: h = 0 (uniform-cost search), for tests
  /// epsilon >= 1: f = g + epsilon h (weighted A*: a path within epsilon of the lattice's
  /// best, found far sooner on large maps; sqrt(4 - 2 sqrt 2) undoes G's kappa).
  double heuristic_weight = 1.0;
};

struct HybridResult {
  bool found = false;
  std::string reason;                 ///< why not found
  std::vector<PathSegment> segments;  ///< from the start pose, merged where the curvature repeats
  double length = 0.0;                ///< metres
  double cost = 0.0;                  ///< sum of ds (1 + weight c)
  std::uint64_t expanded = 0;         ///< states closed
  std::uint64_t analytic_tries = 0;   ///< Dubins paths to the goal traced
  std::uint64_t relaxed_cells = 0;    ///< x-y cells the heuristic's backward pass reached
};

/// Least-cost forward path from `start` to `goal`. `esdf`: one layer, the clearance every
/// sample must keep; `cells`: the search's x-y grid, one layer whose value in each cell is
/// at least the ESDF anywhere in it (the heuristic's open cells), or nullptr: the ESDF's
/// own grid and values (an ESDF finer than the search's cells needs a bound);
/// `cost`: one layer or periodic yaw layers on the search's grid, or nullptr (no
/// perception cost).
/// Throws std::invalid_argument on bad input (radius, bins, mismatched grids, a start or
/// goal off the grid or closer than `clearance` to an obstacle).
HybridResult hybrid_search(const GridField& esdf, const GridField* cells, const GridField* cost, const Pose2& start,
                           const Pose2& goal, const HybridParams& params);

/// h at each of `poses` for `goal` (same arguments): for tests.
std::vector<double> hybrid_heuristic(const GridField& esdf, const GridField* cells, const GridField* cost,
                                     const std::vector<Pose2>& poses, const Pose2& goal, const HybridParams& params);

/// Poses every `spacing` metres (and at each segment's end) along `segments` from
/// `start`, integrated exactly; yaw continuous (unwrapped).
std::vector<Pose2> sample_segments(const Pose2& start, const std::vector<PathSegment>& segments, double spacing);

}  // namespace lf3pm
