#include "lf3pm/planner/graph_search.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>

#include "lf3pm/planner/open_list.hpp"

namespace lf3pm {

namespace {

constexpr double kSqrt2 = 1.41421356237309504880;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Per state, one byte: the move that reached it (kNoMove before) and a closed bit.
constexpr std::uint8_t kClosed = 0x80;
constexpr std::uint8_t kNoMove = 0x7F;

struct Move {
  int dx, dy, dk;
  double length;  // x-y length + turn length, metres
};

std::vector<Move> make_moves(const SearchGrid& g, const SearchParams& p) {
  std::vector<int> turns{0};
  if (g.layers > 1) turns.push_back(1);
  if (g.layers > 2) turns.push_back(-1);  // with 2 bins, +1 and -1 reach the same bin
  std::vector<Move> moves;
  for (int dk : turns) {
    const double turn = dk != 0 ? p.turn_length : 0.0;
    if (dk != 0) moves.push_back({0, 0, dk, turn});
    if (dk != 0 && !p.turn_while_moving) continue;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0) continue;
        moves.push_back({dx, dy, dk, (dx != 0 && dy != 0 ? kSqrt2 : 1.0) * g.res + turn});
      }
  }
  return moves;
}

// Cost-to-go from a cell to the goal's cell in the x-y relaxation (header), by
// a backward Dijkstra from the goal's cell that runs only as far as asked:
// cells close in order of cost-to-go, so asking for a cell resumes the pass
// until that cell is closed, and cells farther from the goal than any cell
// asked for are never expanded. +inf: the cell cannot reach the goal's cell.
class RelaxedCostToGo {
 public:
  RelaxedCostToGo(const double* cell_cost, const std::uint8_t* cell_open, const SearchGrid& g, double weight,
                  std::uint32_t goal_cell)
      : cost_(cell_cost),
        open_(cell_open),
        nx_(g.nx),
        ny_(g.ny),
        weight_(weight),
        to_go_(std::size_t(g.nx) * g.ny, kInf),
        closed_(std::size_t(g.nx) * g.ny, 0) {
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (dx != 0 || dy != 0) steps_.push_back({dx, dy, 0, (dx != 0 && dy != 0 ? kSqrt2 : 1.0) * g.res});
    to_go_[goal_cell] = 0.0;
    frontier_.push(goal_cell, 0.0, 0.0);
  }

  double operator()(std::uint32_t cell) {
    while (!closed_[cell] && !frontier_.empty()) close_next();
    return to_go_[cell];
  }

  std::uint64_t expanded() const { return expanded_; }

 private:
  void close_next() {
    const std::uint32_t c = frontier_.pop();
    if (closed_[c]) return;  // a stale entry (lazy deletion)
    closed_[c] = 1;
    ++expanded_;
    const int y = int(c / std::uint32_t(nx_)), x = int(c - std::uint32_t(y) * nx_);
    for (const Move& st : steps_) {
      const int x2 = x + st.dx, y2 = y + st.dy;
      if (x2 < 0 || x2 >= nx_ || y2 < 0 || y2 >= ny_) continue;
      const std::uint32_t t = std::uint32_t(y2) * nx_ + x2;
      if (!open_[t] || closed_[t]) continue;
      // Both corner cells open in some layer: weaker than the search's rule
      // (open in the source layer), so every search step has its x-y step here.
      if (st.dx != 0 && st.dy != 0 && (!open_[std::uint32_t(y) * nx_ + x2] || !open_[std::uint32_t(y2) * nx_ + x]))
        continue;
      const double d = to_go_[c] + st.length * (1.0 + weight_ * 0.5 * (cost_[c] + cost_[t]));
      if (d < to_go_[t]) {
        to_go_[t] = d;
        frontier_.push(t, d, 0.0);
      }
    }
  }

  const double* cost_;
  const std::uint8_t* open_;
  int nx_, ny_;
  double weight_;
  std::vector<Move> steps_;
  std::vector<double> to_go_;
  std::vector<std::uint8_t> closed_;
  OpenList frontier_;
  std::uint64_t expanded_ = 0;
};

// The header's heuristic h(cell, k). SE(2): relaxed x-y cost-to-go plus the yaw
// term. R^2: the octile bound instead, though there the relaxation would be
// exact: its backward pass is a Dijkstra as costly as the search it guides
// (measured on bench/bench_graph_search.py's 1000 x 1000 map: 0.14 s against
// octile A*'s 0.13 s corner to corner, 0.035 s against 0.012 s over 27 m).
// From 2 yaw bins up the relaxation wins (4 bins corner to corner: 0.18 s
// against 1.6 s; 36 bins: 0.9 s against 32 s).
class Heuristic {
 public:
  Heuristic(const double* cost, const std::uint8_t* traversable, const SearchGrid& g, std::uint32_t goal,
            const SearchParams& p, double c_min)
      : nx_(g.nx),
        layers_(g.layers),
        goal_x_(int(goal / std::uint32_t(g.layers) % std::uint32_t(g.nx))),
        goal_y_(int(goal / std::uint32_t(g.layers) / std::uint32_t(g.nx))),
        goal_k_(int(goal % std::uint32_t(g.layers))),
        res_(g.res),
        edge_factor_(1.0 + p.weight * c_min),
        turn_(p.turn_length * edge_factor_) {
    if (g.layers == 1) return;
    const std::size_t cells = std::size_t(g.nx) * g.ny;
    cell_cost_.assign(cells, kInf);
    cell_open_.assign(cells, 0);
    for (std::size_t c = 0; c < cells; ++c)
      for (int k = 0; k < g.layers; ++k) {
        const std::size_t s = c * g.layers + k;
        if (!traversable[s]) continue;
        cell_open_[c] = 1;
        cell_cost_[c] = std::min(cell_cost_[c], cost[s]);
      }
    to_go_.emplace(cell_cost_.data(), cell_open_.data(), g, p.weight, goal / std::uint32_t(g.layers));
  }

  double operator()(int x, int y, int k) {
    if (!to_go_) {
      const int ax = std::abs(x - goal_x_), ay = std::abs(y - goal_y_);
      const double octile = (std::max(ax, ay) - std::min(ax, ay)) + kSqrt2 * std::min(ax, ay);
      return octile * res_ * edge_factor_;
    }
    const int dk = std::abs(k - goal_k_);
    return (*to_go_)(std::uint32_t(y) * nx_ + x) + turn_ * std::min(dk, layers_ - dk);
  }

  std::uint64_t relaxed_expanded() const { return to_go_ ? to_go_->expanded() : 0; }

 private:
  int nx_, layers_;
  int goal_x_, goal_y_, goal_k_;
  double res_;
  double edge_factor_;                    // 1 + lambda * c_min: the least cost of a metre
  double turn_;                           // the least cost of one yaw step
  std::vector<double> cell_cost_;         // per cell, the least cost of its traversable states
  std::vector<std::uint8_t> cell_open_;   // per cell, 1 if any of its states is traversable
  std::optional<RelaxedCostToGo> to_go_;  // SE(2) only
};

// Throws on bad input; returns c_min, the smallest cost of a traversable state.
double check_input(const double* cost, const std::uint8_t* traversable, const SearchGrid& grid, std::uint32_t start,
                   std::uint32_t goal, const SearchParams& params) {
  if (grid.nx < 1 || grid.ny < 1 || grid.layers < 1 || !(grid.res > 0))
    throw std::invalid_argument("grid needs nx, ny, layers >= 1 and res > 0");
  const std::uint64_t n = std::uint64_t(grid.nx) * grid.ny * grid.layers;
  if (n >= std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("grid too large: at most 2^32 - 1 states");
  if (start >= n || goal >= n) throw std::invalid_argument("start or goal index outside the grid");
  if (!(params.weight >= 0) || !(params.turn_length >= 0) || !std::isfinite(params.weight) ||
      !std::isfinite(params.turn_length))
    throw std::invalid_argument("weight and turn length must be finite and >= 0");
  if (!traversable[start] || !traversable[goal]) throw std::invalid_argument("start or goal not traversable");
  double c_min = kInf;
  for (std::uint64_t s = 0; s < n; ++s) {
    if (!traversable[s]) continue;
    if (!(cost[s] >= 0) || !std::isfinite(cost[s]))
      throw std::invalid_argument("cost must be finite and >= 0 at every traversable state");
    c_min = std::min(c_min, cost[s]);
  }
  return c_min;
}

}  // namespace

SearchResult grid_search(const double* cost, const std::uint8_t* traversable, const SearchGrid& grid,
                         std::uint32_t start, std::uint32_t goal, const SearchParams& params) {
  const double c_min = check_input(cost, traversable, grid, start, goal, params);
  const std::uint64_t n = std::uint64_t(grid.nx) * grid.ny * grid.layers;
  const std::vector<Move> moves = make_moves(grid, params);
  const int nx = grid.nx, ny = grid.ny, layers = grid.layers;
  // (x, y, k) of a state index (y * nx + x) * layers + k: two divisions.
  auto decode = [&](std::uint32_t s, int& x, int& y, int& k) {
    const std::uint32_t cell = s / std::uint32_t(layers), row = cell / std::uint32_t(nx);
    k = int(s - cell * std::uint32_t(layers));
    y = int(row);
    x = int(cell - row * std::uint32_t(nx));
  };
  auto index = [&](int x, int y, int k) { return std::uint32_t((std::uint64_t(y) * nx + x) * layers + k); };
  std::optional<Heuristic> h_of;  // none: Dijkstra
  if (params.heuristic) h_of.emplace(cost, traversable, grid, goal, params, c_min);
  auto heuristic = [&](int x, int y, int k) { return h_of ? (*h_of)(x, y, k) : 0.0; };

  SearchResult out;
  std::vector<double> g(n, kInf);
  std::vector<std::uint8_t> state(n, kNoMove);
  OpenList open;
  auto push = [&](std::uint32_t s, double f, double h) {
    open.push(s, f, h);
    ++out.pushed;
    out.heap_peak = std::max(out.heap_peak, open.size());
  };

  g[start] = 0.0;
  {
    int sx, sy, sk;
    decode(start, sx, sy, sk);
    const double h = heuristic(sx, sy, sk);
    if (h == kInf) {  // not even the relaxation reaches the goal
      out.relaxed_expanded = h_of->relaxed_expanded();
      return out;
    }
    push(start, h, h);
  }
  while (!open.empty()) {
    const std::uint32_t s = open.pop();
    if (state[s] & kClosed) continue;  // a stale entry (lazy deletion)
    state[s] |= kClosed;
    ++out.expanded;
    if (s == goal) break;
    int x, y, k;
    decode(s, x, y, k);
    const double gs = g[s], cs = cost[s];
    for (std::size_t m = 0; m < moves.size(); ++m) {
      const Move& mv = moves[m];
      const int x2 = x + mv.dx, y2 = y + mv.dy;
      if (x2 < 0 || x2 >= nx || y2 < 0 || y2 >= ny) continue;
      int k2 = k + mv.dk;
      k2 += k2 < 0 ? layers : (k2 >= layers ? -layers : 0);
      const std::uint32_t t = index(x2, y2, k2);
      if (!traversable[t] || (state[t] & kClosed)) continue;
      if (mv.dx != 0 && mv.dy != 0) {
        if (!traversable[index(x2, y, k)] || !traversable[index(x, y2, k)]) continue;
      }
      const double gt = gs + mv.length * (1.0 + params.weight * 0.5 * (cs + cost[t]));
      if (gt < g[t]) {
        const double h = heuristic(x2, y2, k2);
        if (h == kInf) continue;  // t cannot reach the goal
        g[t] = gt;
        state[t] = std::uint8_t(m);
        push(t, gt + h, h);
      }
    }
  }
  if (h_of) out.relaxed_expanded = h_of->relaxed_expanded();
  if (!(state[goal] & kClosed)) return out;

  out.found = true;
  out.cost = g[goal];
  for (std::uint32_t s = goal;;) {
    out.path.push_back(s);
    if (s == start) break;
    const Move& mv = moves[state[s] & ~kClosed];
    int x, y, k;
    decode(s, x, y, k);
    s = index(x - mv.dx, y - mv.dy, (k - mv.dk + layers) % layers);
  }
  std::reverse(out.path.begin(), out.path.end());
  return out;
}

std::vector<double> search_heuristic(const double* cost, const std::uint8_t* traversable, const SearchGrid& grid,
                                     std::uint32_t goal, const SearchParams& params) {
  const double c_min = check_input(cost, traversable, grid, goal, goal, params);
  Heuristic h(cost, traversable, grid, goal, params, c_min);
  std::vector<double> out(std::size_t(grid.nx) * grid.ny * grid.layers);
  std::size_t s = 0;
  for (int y = 0; y < grid.ny; ++y)
    for (int x = 0; x < grid.nx; ++x)
      for (int k = 0; k < grid.layers; ++k) out[s++] = h(x, y, k);
  return out;
}

}  // namespace lf3pm
