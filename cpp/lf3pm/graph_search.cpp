#include "lf3pm/graph_search.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace lf3pm {

namespace {

constexpr double kSqrt2 = 1.41421356237309504880;
// Per state, one byte: the move that reached it (kNoMove before) and a closed bit.
constexpr std::uint8_t kClosed = 0x80;
constexpr std::uint8_t kNoMove = 0x7F;

struct Move {
  int dx, dy, dk;
  double length;  // x-y length + turn length, metres
};

// Open-list entry. f and h are stored as the bit patterns of non-negative
// double / float, which order like the values: integer compares, no NaN branch.
struct Entry {
  std::uint64_t f;
  std::uint32_t h;  // tie-break: among equal f, expand the state nearer the goal first
  std::uint32_t state;
};

inline bool before(const Entry& a, const Entry& b) { return (a.f < b.f) | ((a.f == b.f) & (a.h < b.h)); }

// A 4-ary min-heap with lazy deletion (stale entries are skipped when popped):
// half the depth of a binary heap, and branch-free choice among the children.
class OpenList {
 public:
  bool empty() const { return heap_.empty(); }
  std::size_t size() const { return heap_.size(); }

  void push(std::uint32_t state, double f, double h) {
    Entry e{bits(f), bits(float(h)), state};
    std::size_t i = heap_.size();
    heap_.push_back(e);
    while (i > 0) {
      const std::size_t parent = (i - 1) / 4;
      if (!before(e, heap_[parent])) break;
      heap_[i] = heap_[parent];
      i = parent;
    }
    heap_[i] = e;
  }

  std::uint32_t pop() {
    const std::uint32_t top = heap_[0].state;
    const Entry last = heap_.back();
    heap_.pop_back();
    const std::size_t n = heap_.size();
    if (n == 0) return top;
    std::size_t i = 0;
    for (;;) {
      const std::size_t first = 4 * i + 1;
      if (first >= n) break;
      std::size_t best = first;
      const std::size_t end = std::min(first + 4, n);
      for (std::size_t c = first + 1; c < end; ++c) best = before(heap_[c], heap_[best]) ? c : best;
      if (!before(heap_[best], last)) break;
      heap_[i] = heap_[best];
      i = best;
    }
    heap_[i] = last;
    return top;
  }

 private:
  static std::uint64_t bits(double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  }
  static std::uint32_t bits(float v) {
    std::uint32_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  }
  std::vector<Entry> heap_;
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

}  // namespace

SearchResult grid_search(const double* cost, const std::uint8_t* traversable, const SearchGrid& grid,
                         std::uint32_t start, std::uint32_t goal, const SearchParams& params) {
  if (grid.nx < 1 || grid.ny < 1 || grid.layers < 1 || !(grid.res > 0))
    throw std::invalid_argument("grid needs nx, ny, layers >= 1 and res > 0");
  const std::uint64_t plane = std::uint64_t(grid.nx) * grid.ny;
  const std::uint64_t n = plane * grid.layers;
  if (n >= std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("grid too large: at most 2^32 - 1 states");
  if (start >= n || goal >= n) throw std::invalid_argument("start or goal index outside the grid");
  if (!(params.weight >= 0) || !(params.turn_length >= 0) || !std::isfinite(params.weight) ||
      !std::isfinite(params.turn_length))
    throw std::invalid_argument("weight and turn length must be finite and >= 0");
  if (!traversable[start] || !traversable[goal]) throw std::invalid_argument("start or goal not traversable");

  double c_min = std::numeric_limits<double>::infinity();
  for (std::uint64_t s = 0; s < n; ++s) {
    if (!traversable[s]) continue;
    if (!(cost[s] >= 0) || !std::isfinite(cost[s]))
      throw std::invalid_argument("cost must be finite and >= 0 at every traversable state");
    c_min = std::min(c_min, cost[s]);
  }

  const std::vector<Move> moves = make_moves(grid, params);
  const int nx = grid.nx, ny = grid.ny, layers = grid.layers;
  // (x, y, k) of a state index (y * nx + x) * layers + k: two divisions.
  auto decode = [&](std::uint32_t s, int& x, int& y, int& k) {
    const std::uint32_t cell = s / std::uint32_t(layers), row = cell / std::uint32_t(nx);
    k = int(s - cell * std::uint32_t(layers));
    y = int(row);
    x = int(cell - row * std::uint32_t(nx));
  };
  auto index = [&](int x, int y, int k) {
    return std::uint32_t((std::uint64_t(y) * nx + x) * layers + k);
  };
  int gx, gy, gk;
  decode(goal, gx, gy, gk);
  const double h_scale = params.heuristic ? 1.0 + params.weight * c_min : 0.0;
  auto heuristic = [&](int x, int y, int k) {
    const int ax = std::abs(x - gx), ay = std::abs(y - gy);
    const int dk = std::abs(k - gk);
    const double octile = (std::max(ax, ay) - std::min(ax, ay)) + kSqrt2 * std::min(ax, ay);
    return (octile * grid.res + params.turn_length * std::min(dk, layers - dk)) * h_scale;
  };

  SearchResult out;
  std::vector<double> g(n, std::numeric_limits<double>::infinity());
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
        g[t] = gt;
        state[t] = std::uint8_t(m);
        const double h = heuristic(x2, y2, k2);
        push(t, gt + h, h);
      }
    }
  }
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

}  // namespace lf3pm
