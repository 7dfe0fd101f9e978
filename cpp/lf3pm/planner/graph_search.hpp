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
// per-cell perception cost of the two end states.
//
// Heuristic, SE(2): h(x, y, k) = D(x, y) + rho * (1 + lambda * c_min) * |k - k_goal|_cyclic,
// c_min the least cost of a traversable state, D the exact cost-to-go to the
// goal's cell in an x-y relaxation: an 8-connected grid of cells, a cell open
// if any of its yaw states is traversable and costing m = the least cost of
// those states, a diagonal step allowed when both corner cells are open, and
// a step a -> b costing l * (1 + lambda * (m_a + m_b) / 2). D comes from a
// backward Dijkstra from the goal's cell, run lazily: it resumes only when A*
// asks for a cell it has not closed yet. R^2: D would be the exact cost-to-go,
// computed by a backward search as costly as the forward one, so h is the
// octile distance * res * (1 + lambda * c_min) instead (graph_search.cpp).
// Why h is admissible and consistent (closed states are final):
//   - every search edge a -> b projects onto a relaxed step (or no x-y step)
//     between the same cells: its end cells and, for a diagonal, its corner
//     cells are traversable in some layer;
//   - its cost splits as l * (1 + lambda * (c_a + c_b) / 2)
//     + rho |dk| (1 + lambda * (c_a + c_b) / 2), and c >= m >= c_min, so
//     it is at least the relaxed step's cost plus rho |dk| (1 + lambda c_min);
//   - D obeys the triangle inequality over relaxed steps, and the cyclic
//     yaw distance drops by at most |dk|: h(a) <= cost(a, b) + h(b)
//     (consistency), and with h(goal) = 0, summing along any path gives
//     h <= the true cost-to-go (admissibility). D = +inf (the relaxation
//     cannot reach the goal) prunes the state.
// The octile form follows from the same split (a step of length l costs at
// least l * (1 + lambda * c_min), and the octile distance drops by at most l).
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
  bool heuristic = true;          ///< false: Dijkstra (A* with h = 0, no backward pass)
};

struct SearchResult {
  bool found = false;
  double cost = 0.0;
  std::vector<std::uint32_t> path;     ///< state indices, start to goal
  std::uint64_t expanded = 0;          ///< states closed
  std::uint64_t pushed = 0;            ///< heap insertions
  std::size_t heap_peak = 0;           ///< largest heap size (entries of 16 bytes)
  std::uint64_t relaxed_expanded = 0;  ///< SE(2) A*: cells the heuristic's backward pass closed
};

/// Least-cost path from `start` to `goal` (state indices). `cost` and
/// `traversable` hold one value per state; costs of traversable states must be
/// finite and >= 0 (checked). Throws std::invalid_argument on bad input.
SearchResult grid_search(const double* cost, const std::uint8_t* traversable, const SearchGrid& grid,
                         std::uint32_t start, std::uint32_t goal, const SearchParams& params);

/// The heuristic grid_search uses, for every state (+inf: the goal is
/// unreachable even in the x-y relaxation); of `params` only weight and
/// turn_length matter. For tests and inspection; same input checks.
std::vector<double> search_heuristic(const double* cost, const std::uint8_t* traversable, const SearchGrid& grid,
                                     std::uint32_t goal, const SearchParams& params);

}  // namespace lf3pm
