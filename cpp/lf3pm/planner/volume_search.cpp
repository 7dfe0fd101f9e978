#include "lf3pm/planner/volume_search.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "lf3pm/planner/open_list.hpp"

namespace lf3pm {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Step {
  int dx, dy, dz;
  double length;
};

std::vector<Step> steps(const VolumeGrid& g) {
  std::vector<Step> out;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (dx || dy || dz)
          out.push_back({dx, dy, dz, std::sqrt((dx * dx + dy * dy) * g.res * g.res + dz * dz * g.dz * g.dz)});
  return out;
}

void check(const double* cost, const std::uint8_t* traversable, const VolumeGrid& g, std::uint32_t start,
           std::uint32_t goal, double& c_min) {
  if (g.nx < 1 || g.ny < 1 || g.nz < 1) throw std::invalid_argument("the volume needs at least one cell");
  if (!(g.res > 0) || !(g.dz > 0)) throw std::invalid_argument("the volume's cell edge and level spacing must be > 0");
  const std::size_t n = std::size_t(g.nx) * g.ny * g.nz;
  if (n >= std::size_t(0xFFFFFFFFu)) throw std::invalid_argument("the volume has too many cells");
  if (start >= n || goal >= n) throw std::invalid_argument("start or goal outside the volume");
  if (!traversable[start]) throw std::invalid_argument("the start cell is not traversable");
  if (!traversable[goal]) throw std::invalid_argument("the goal cell is not traversable");
  c_min = kInf;
  for (std::size_t i = 0; i < n; ++i) {
    if (!traversable[i]) continue;
    if (!(cost[i] >= 0) || !std::isfinite(cost[i]))
      throw std::invalid_argument("costs of traversable cells must be finite and >= 0");
    c_min = std::min(c_min, cost[i]);
  }
}

}  // namespace

SearchResult volume_search(const double* cost, const std::uint8_t* traversable, const VolumeGrid& g,
                           std::uint32_t start, std::uint32_t goal, const SearchParams& params,
                           const std::uint8_t* move_free) {
  double c_min = 0.0;
  check(cost, traversable, g, start, goal, c_min);
  if (!(params.weight >= 0) || !std::isfinite(params.weight)) throw std::invalid_argument("weight must be >= 0");
  const std::size_t n = std::size_t(g.nx) * g.ny * g.nz;
  const std::vector<Step> moves = steps(g);
  const double lambda = params.weight;
  const double h_scale = params.heuristic ? 1.0 + lambda * c_min : 0.0;
  const int gx = int(goal % g.nx), gy = int(goal / g.nx % g.ny), gz = int(goal / (std::size_t(g.nx) * g.ny));
  auto heuristic = [&](int x, int y, int z) {
    const double ex = (x - gx) * g.res, ey = (y - gy) * g.res, ez = (z - gz) * g.dz;
    return h_scale * std::sqrt(ex * ex + ey * ey + ez * ez);
  };
  auto at = [&](int x, int y, int z) { return (std::size_t(z) * g.ny + y) * g.nx + x; };
  std::vector<double> best(n, kInf);
  std::vector<std::uint32_t> parent(n, 0xFFFFFFFFu);
  std::vector<std::uint8_t> closed(n, 0);
  OpenList open;
  SearchResult out;
  best[start] = 0.0;
  {
    const int x = int(start % g.nx), y = int(start / g.nx % g.ny), z = int(start / (std::size_t(g.nx) * g.ny));
    open.push(start, heuristic(x, y, z), heuristic(x, y, z));
  }
  ++out.pushed;
  while (!open.empty()) {
    out.heap_peak = std::max(out.heap_peak, open.size());
    const std::uint32_t s = open.pop();
    if (closed[s]) continue;  // a stale entry
    closed[s] = 1;
    ++out.expanded;
    if (s == goal) break;
    const int x = int(s % g.nx), y = int(s / g.nx % g.ny), z = int(s / (std::size_t(g.nx) * g.ny));
    for (int mi = 0; mi < kVolumeMoves; ++mi) {
      const Step& m = moves[mi];
      if (move_free != nullptr && !move_free[std::size_t(s) * kVolumeMoves + mi]) continue;
      const int nx = x + m.dx, ny = y + m.dy, nz = z + m.dz;
      if (nx < 0 || ny < 0 || nz < 0 || nx >= g.nx || ny >= g.ny || nz >= g.nz) continue;
      // Every cell of the box the move spans.
      bool free = true;
      for (int cz = std::min(z, nz); free && cz <= std::max(z, nz); ++cz)
        for (int cy = std::min(y, ny); free && cy <= std::max(y, ny); ++cy)
          for (int cx = std::min(x, nx); free && cx <= std::max(x, nx); ++cx) free = traversable[at(cx, cy, cz)] != 0;
      if (!free) continue;
      const std::size_t t = at(nx, ny, nz);
      if (closed[t]) continue;
      const double step = m.length * (1.0 + lambda * 0.5 * (cost[s] + cost[t]));
      const double through = best[s] + step;
      if (through < best[t]) {
        best[t] = through;
        parent[t] = s;
        const double h = heuristic(nx, ny, nz);
        open.push(static_cast<std::uint32_t>(t), through + h, h);
        ++out.pushed;
      }
    }
  }
  if (!closed[goal]) return out;
  out.found = true;
  out.cost = best[goal];
  for (std::uint32_t s = goal; s != 0xFFFFFFFFu; s = parent[s]) out.path.push_back(s);
  std::reverse(out.path.begin(), out.path.end());
  return out;
}

}  // namespace lf3pm
