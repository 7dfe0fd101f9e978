// The planner's front end: A* (or Dijkstra) over a SOLM grid of layers.
//
// States are the cells of an (ny x nx) grid times `layers` yaw bins, indexed
// (y * nx + x) * layers + k: yaw innermost, so that the states a move reaches
// lie a few cache lines apart (a SOLM channel is (yaw, y, x): the caller
// transposes it; with the yaw outermost an SE(2) search spent its time in cache
// misses). One layer is the R^2 planner; several are periodic yaw bins. Moves:
//   - 8-connected x-y steps within a layer (length res or res * sqrt 2); a
//     diagonal step needs both cells it passes between (in the source layer)
//     traversable, so a path never cuts an obstacle's corner;
//   - turns in place to the neighbouring yaw bins (k +- 1 mod layers);
//   - optionally x-y steps combined with one yaw step.
// Edge cost: (l + rho * |dk|) * (1 + lambda * (c_a + c_b) / 2), l the x-y
// length in metres, rho the turn length in metres charged per yaw step, c the
// per-cell perception cost of the two end states. The heuristic
//   h = (octile distance + rho * cyclic yaw-bin distance) * (1 + lambda * c_min),
// c_min the smallest cost of a traversable state, never exceeds the cost of any
// edge sequence (each edge's l and |dk| are at least the drop of the octile and
// yaw distances), so it is admissible and consistent: closed states are final.
#pragma once

#include <cstdint>
#include <vector>

namespace lf3pm {

/// Grid shape: nx x ny cells of edge `res` metres, `layers` yaw bins (1: R^2).
struct SearchGrid {
  int nx = 0;
  int ny = 0;
  int layers = 1;
  double res = 1.0;
};

struct SearchParams {
  double weight = 1.0;            ///< lambda: perception cost against length
  double turn_length = 0.0;       ///< rho: metres of travel charged per yaw step
  bool turn_while_moving = true;  ///< also x-y steps combined with one yaw step
  bool heuristic = true;          ///< false: Dijkstra (A* with h = 0)
};

struct SearchResult {
  bool found = false;
  double cost = 0.0;
  std::vector<std::uint32_t> path;  ///< state indices, start to goal
  std::uint64_t expanded = 0;       ///< states closed
  std::uint64_t pushed = 0;         ///< heap insertions
  std::size_t heap_peak = 0;        ///< largest heap size (entries of 16 bytes)
};

/// Least-cost path from `start` to `goal` (state indices). `cost` and
/// `traversable` hold one value per state; costs of traversable states must be
/// finite and >= 0 (checked). Throws std::invalid_argument on bad input.
SearchResult grid_search(const double* cost, const std::uint8_t* traversable, const SearchGrid& grid,
                         std::uint32_t start, std::uint32_t goal, const SearchParams& params);

}  // namespace lf3pm
