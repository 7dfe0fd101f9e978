// The flight planner's front end: A* over a volume of cells (nz levels of ny x nx cells),
// 26-connected, for a quadrotor on an r3yaw SOLM reduced over yaw (Solm.over_yaw).
//
// States are cells indexed (z * ny + y) * nx + x, the layout of a (nz, ny, nx) array. A
// move steps by -1, 0 or +1 along each axis (26 moves); its length is the Euclidean
// length of the step, l = sqrt((dx res)^2 + (dy res)^2 + (dz dz_res)^2), and its cost
// l * (1 + lambda * (c_a + c_b) / 2) with c the per-cell perception cost. A move needs
// every cell of the box it spans traversable (up to 8 cells), so that a path never cuts
// an obstacle's edge or corner, and, where the caller gives them, its own flag in
// `move_free` (cell * 26 + m, moves m in the order dz, dy, dx = -1..1 with x fastest, the
// null move skipped): a thin wall between two free cell centres is no cell of either.
//
// Heuristic: h = |goal - cell| (Euclidean, metres) * (1 + lambda * c_min), c_min the least
// cost of a traversable cell. Consistent: a move of length l costs at least
// l * (1 + lambda * c_min), and the Euclidean distance to the goal drops by at most l
// (triangle inequality); with h(goal) = 0 it is admissible, so the path is optimal.
#pragma once

#include <cstdint>

#include "lf3pm/planner/graph_search.hpp"

namespace lf3pm {

/// A volume of nx x ny x nz cells: edge `res` in x and y, level spacing `dz`, metres.
struct VolumeGrid {
  int nx = 0;
  int ny = 0;
  int nz = 0;
  double res = 1.0;
  double dz = 1.0;
};

/// Least-cost path from `start` to `goal` (cell indices); `cost` and `traversable` hold
/// one value per cell, costs of traversable cells finite and >= 0 (checked). Of `params`:
/// weight (lambda) and heuristic (false: Dijkstra). Throws std::invalid_argument on bad input.
SearchResult volume_search(const double* cost, const std::uint8_t* traversable, const VolumeGrid& grid,
                           std::uint32_t start, std::uint32_t goal, const SearchParams& params,
                           const std::uint8_t* move_free = nullptr);

/// Moves per cell in `move_free`.
constexpr int kVolumeMoves = 26;

}  // namespace lf3pm
