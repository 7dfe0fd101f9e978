#include "lf3pm/point_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lf3pm {

PointGrid::PointGrid(const std::vector<Eigen::Vector3d>& points, double cell_size) {
  Eigen::Vector3d lo = points.front(), hi = points.front();
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  grid_ = VoxelGrid(lo, hi, cell_size);
  std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    pairs[i] = {grid_.key_of(grid_.cell_of(points[i])), static_cast<std::uint32_t>(i)};
  // Equal points share a cell: sort each cell's run by coordinates, keep the first.
  std::sort(pairs.begin(), pairs.end());
  auto coords_less = [&](const auto& a, const auto& b) {
    const Eigen::Vector3d &p = points[a.second], &q = points[b.second];
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return a.second < b.second;
  };
  std::size_t kept = 0;
  for (std::size_t b = 0; b < pairs.size();) {
    std::size_t e = b;
    while (e < pairs.size() && pairs[e].first == pairs[b].first) ++e;
    std::sort(pairs.begin() + b, pairs.begin() + e, coords_less);
    for (std::size_t i = b; i < e; ++i)
      if (i == b || points[pairs[i].second] != points[pairs[kept - 1].second]) pairs[kept++] = pairs[i];
    b = e;
  }
  duplicates_removed_ = pairs.size() - kept;
  pairs.resize(kept);
  grid_.build(pairs);
  // Store the points in cell order: a cell's items are then the index range
  // [items_begin, items_end) itself, and a search reads memory linearly.
  order_ = grid_.items();
  points_.resize(order_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) points_[i] = points[order_[i]];
}

namespace {
// Keeps the k smallest (distance, index) pairs, sorted ascending.
struct KBest {
  int k, size = 0;
  double* d;
  std::uint32_t* id;
  double worst() const { return size < k ? std::numeric_limits<double>::infinity() : d[k - 1]; }
  void offer(double dist, std::uint32_t index) {
    if (size == k && dist >= d[k - 1]) return;
    int pos = size < k ? size++ : k - 1;
    while (pos > 0 && d[pos - 1] > dist) {
      d[pos] = d[pos - 1];
      id[pos] = id[pos - 1];
      --pos;
    }
    d[pos] = dist;
    id[pos] = index;
  }
};
}  // namespace

int PointGrid::nearest(const Eigen::Vector3d& q, int k, double max_distance, std::uint32_t* idx,
                       double* sq_dist) const {
  if (k <= 0 || points_.empty()) return 0;
  const double h = grid_.cell_size();
  const double max_sq = max_distance * max_distance;
  const CellCoord c = grid_.cell_of(q);
  // Distance from q to the nearest face of its own cell: shells of Chebyshev
  // radius L around the cell then cover every point closer than L*h + margin.
  const Eigen::Vector3d f = (q - grid_.origin()) / h;
  double margin = std::numeric_limits<double>::infinity();
  const int cxyz[3] = {c.x, c.y, c.z};
  double frac[3];  // position of q inside its cell, in cells
  for (int a = 0; a < 3; ++a) {
    frac[a] = f[a] - cxyz[a];
    margin = std::min(margin, std::min(frac[a], 1.0 - frac[a]) * h);
  }
  margin = std::max(margin, 0.0);
  KBest best{k, 0, sq_dist, idx};
  const int max_shell = static_cast<int>(std::ceil(max_distance / h)) + 1;
  for (int L = 0; L <= max_shell; ++L) {
    for (int dz = -L; dz <= L; ++dz)
      for (int dy = -L; dy <= L; ++dy) {
        const bool face = (std::abs(dz) == L || std::abs(dy) == L);
        for (int dx = -L; dx <= L; dx += (face ? 1 : 2 * L)) {
          const CellCoord n{c.x + dx, c.y + dy, c.z + dz};
          // Skip a cell whose nearest point to q is farther than the current k-th.
          const double gx = std::max({0.0, dx - frac[0], frac[0] - 1 - dx}) * h;
          const double gy = std::max({0.0, dy - frac[1], frac[1] - 1 - dy}) * h;
          const double gz = std::max({0.0, dz - frac[2], frac[2] - 1 - dz}) * h;
          const double gap2 = gx * gx + gy * gy + gz * gz;
          if (gap2 <= max_sq && gap2 < best.worst() && grid_.contains(n)) {
            const std::int64_t slot = grid_.cell_slot(n);
            if (slot >= 0) {
              for (std::uint32_t i = grid_.items_begin(slot), e = grid_.items_end(slot); i < e; ++i) {
                const double d2 = (points_[i] - q).squaredNorm();
                if (d2 <= max_sq) best.offer(d2, i);
              }
            }
          }
          if (L == 0) break;
        }
      }
    const double covered = L * h + margin;
    if (best.size == k && best.worst() <= covered * covered) break;
    if (covered >= max_distance) break;
  }
  return best.size;
}

}  // namespace lf3pm
