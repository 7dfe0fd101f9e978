#include "lf3pm/surfel_caster.hpp"

#include <algorithm>
#include <cmath>

namespace lf3pm {

namespace {
// Dense per-block distances cost a byte per block; above this many blocks the
// caster walks block by block instead.
constexpr std::int64_t kMaxDistanceBlocks = std::int64_t(1) << 28;

// Exact chessboard (Chebyshev) distance transform on a dense block volume:
// a forward and a backward raster pass with the 26-neighbourhood, unit weights.
std::vector<std::uint8_t> chebyshev_distance(const VoxelGrid& grid) {
  const int nx = grid.blocks_per_axis()[0], ny = grid.blocks_per_axis()[1], nz = grid.blocks_per_axis()[2];
  std::vector<std::uint8_t> d(static_cast<std::size_t>(nx) * ny * nz, 255);
  auto at = [&](int x, int y, int z) -> std::uint8_t& {
    return d[x + static_cast<std::size_t>(nx) * (y + static_cast<std::size_t>(ny) * z)];
  };
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x)
        if (grid.block_at(x, y, z) >= 0) at(x, y, z) = 0;
  auto relax = [&](int x, int y, int z, int sign) {
    int best = at(x, y, z);
    if (best == 0) return;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          // Only neighbours already visited in this pass's raster order.
          const int order = dz * 9 + dy * 3 + dx;
          if (order * sign >= 0) continue;
          const int xx = x + dx, yy = y + dy, zz = z + dz;
          if (xx < 0 || yy < 0 || zz < 0 || xx >= nx || yy >= ny || zz >= nz) continue;
          best = std::min(best, at(xx, yy, zz) + 1);
        }
    at(x, y, z) = static_cast<std::uint8_t>(std::min(best, 255));
  };
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) relax(x, y, z, 1);
  for (int z = nz - 1; z >= 0; --z)
    for (int y = ny - 1; y >= 0; --y)
      for (int x = nx - 1; x >= 0; --x) relax(x, y, z, -1);
  return d;
}
}  // namespace

SurfelCaster::SurfelCaster(const std::vector<Eigen::Vector3d>& centres,
                           const std::vector<Eigen::Vector3d>& normals, const std::vector<float>& radii,
                           double cell_size) {
  Eigen::Vector3d lo = centres.front(), hi = centres.front();
  for (std::size_t i = 0; i < centres.size(); ++i) {
    lo = lo.cwiseMin(centres[i] - Eigen::Vector3d::Constant(radii[i]));
    hi = hi.cwiseMax(centres[i] + Eigen::Vector3d::Constant(radii[i]));
  }
  grid_ = VoxelGrid(lo, hi, cell_size);
  // A disc is listed in every cell its bounding sphere's box touches: a ray then
  // meets the disc in the cell that contains the hit point, which is what lets
  // the walk stop at the first cell whose exit lies beyond the nearest hit.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs;
  pairs.reserve(centres.size() * 2);
  for (std::size_t i = 0; i < centres.size(); ++i) {
    const Eigen::Vector3d r = Eigen::Vector3d::Constant(radii[i]);
    const CellCoord a = grid_.cell_of(centres[i] - r), b = grid_.cell_of(centres[i] + r);
    for (int z = a.z; z <= b.z; ++z)
      for (int y = a.y; y <= b.y; ++y)
        for (int x = a.x; x <= b.x; ++x)
          pairs.emplace_back(grid_.key_of({x, y, z}), static_cast<std::uint32_t>(i));
  }
  grid_.build(pairs);
  const auto& items = grid_.items();
  const Eigen::Vector3d origin = grid_.origin();
  discs_.resize(items.size());
  for (std::size_t k = 0; k < items.size(); ++k) {
    const std::uint32_t i = items[k];
    const Eigen::Vector3d c = centres[i] - origin;
    discs_[k] = {{float(c.x()), float(c.y()), float(c.z())},
                 {float(normals[i].x()), float(normals[i].y()), float(normals[i].z())},
                 radii[i] * radii[i],
                 i};
  }
  slabs_.resize(grid_.occupied_cells());
  const float no_slab = std::numeric_limits<float>::infinity();
  for (std::size_t s = 0; s < slabs_.size(); ++s) {
    const std::uint32_t b = grid_.items_begin(s), e = grid_.items_end(s);
    Eigen::Vector3d n_sum = Eigen::Vector3d::Zero();
    const Eigen::Vector3d n0 = normals[items[b]];
    for (std::uint32_t k = b; k < e; ++k) {
      const Eigen::Vector3d& n = normals[items[k]];
      n_sum += n.dot(n0) >= 0 ? n : Eigen::Vector3d(-n);
    }
    CellSlab slab{{0, 0, 1}, 0, no_slab};
    if (n_sum.norm() > 0.5 * (e - b)) {  // normals roughly agree: a flat-ish cell
      const Eigen::Vector3d n = n_sum.normalized();
      double lo_s = std::numeric_limits<double>::infinity(), hi_s = -lo_s;
      for (std::uint32_t k = b; k < e; ++k) {
        const std::uint32_t i = items[k];
        const double sin_tilt = std::sqrt(std::max(0.0, 1.0 - std::pow(n.dot(normals[i]), 2)));
        const double centre = n.dot(centres[i] - origin);
        const double reach = radii[i] * sin_tilt * 1.001 + 1e-5;
        lo_s = std::min(lo_s, centre - reach);
        hi_s = std::max(hi_s, centre + reach);
      }
      slab = {{float(n.x()), float(n.y()), float(n.z())}, float(0.5 * (lo_s + hi_s)),
              float(0.5 * (hi_s - lo_s) + 1e-4)};
    }
    slabs_[s] = slab;
  }
  const int* nb = grid_.blocks_per_axis();
  if (static_cast<std::int64_t>(nb[0]) * nb[1] * nb[2] <= kMaxDistanceBlocks) block_distance_ = chebyshev_distance(grid_);
  build_top_levels();
}

void SurfelCaster::build_top_levels() {
  const int* nb = grid_.blocks_per_axis();
  int w = nb[0], hgt = nb[1];
  std::vector<std::int32_t> level(static_cast<std::size_t>(w) * hgt, 0);
  for (int y = 0; y < hgt; ++y)
    for (int x = 0; x < w; ++x)
      for (int z = nb[2] - 1; z >= 0; --z)
        if (grid_.block_at(x, y, z) >= 0) {
          level[x + static_cast<std::size_t>(w) * y] = z + 1;
          break;
        }
  top_levels_.push_back(level);
  top_width_.push_back(w);
  while (w > 1 || hgt > 1) {
    const int w2 = (w + 1) / 2, h2 = (hgt + 1) / 2;
    std::vector<std::int32_t> up(static_cast<std::size_t>(w2) * h2, 0);
    const auto& down = top_levels_.back();
    for (int y = 0; y < hgt; ++y)
      for (int x = 0; x < w; ++x) {
        auto& v = up[x / 2 + static_cast<std::size_t>(w2) * (y / 2)];
        v = std::max(v, down[x + static_cast<std::size_t>(w) * y]);
      }
    top_levels_.push_back(std::move(up));
    top_width_.push_back(w2);
    w = w2;
    hgt = h2;
  }
}

namespace {
// Axis of the smallest of three values, without branches: the DDA's next axis
// is data-dependent and mispredicted branches cost more than the walk itself.
inline int min_axis(const double* t) {
  static constexpr int kAxis[8] = {2, 1, 2, 1, 2, 2, 0, 0};  // index: x<y, x<z, y<z bits
  const int code = (int(t[0] < t[1]) << 2) | (int(t[0] < t[2]) << 1) | int(t[1] < t[2]);
  return kAxis[code];
}
}  // namespace

RayHit SurfelCaster::cast(const Eigen::Vector3d& origin_world, const Eigen::Vector3d& dir,
                          double max_range) const {
  RayHit result;
  if (discs_.empty()) return result;
  constexpr int B = VoxelGrid::kBlockSize;
  const double h = grid_.cell_size();
  const double hb = h * B;
  const double inv_h = 1.0 / h, inv_hb = 1.0 / hb;
  const Eigen::Vector3d o = origin_world - grid_.origin();  // grid-relative
  const Eigen::Vector3d extent = grid_.upper() - grid_.origin();
  const int* cells = grid_.cells_per_axis();
  const double inf = std::numeric_limits<double>::infinity();

  // Clip [0, max_range] to the grid box.
  double t0 = 0.0, t1 = max_range;
  double inv[3];
  int step[3];
  for (int a = 0; a < 3; ++a) {
    if (std::abs(dir[a]) < 1e-12) {
      if (o[a] < 0.0 || o[a] > extent[a]) return result;
      inv[a] = inf;
      step[a] = 0;
      continue;
    }
    inv[a] = 1.0 / dir[a];
    step[a] = dir[a] > 0 ? 1 : -1;
    double ta = (0.0 - o[a]) * inv[a], tb = (extent[a] - o[a]) * inv[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 >= t1) return result;

  // Parametric distance to the next face along axis a, from integer coordinate i
  // of a lattice with spacing s.
  auto next_face = [&](int a, int i, double s) {
    if (step[a] == 0) return inf;
    return ((i + (step[a] > 0 ? 1 : 0)) * s - o[a]) * inv[a];
  };

  const float of[3] = {float(o.x()), float(o.y()), float(o.z())};
  const float df[3] = {float(dir.x()), float(dir.y()), float(dir.z())};
  const float t_min_hit = 1e-6f;
  float best = std::numeric_limits<float>::infinity();
  std::uint32_t best_id = kNoHit;

  // Outer walk over 4x4x4 blocks; inner walk over the cells of occupied blocks.
  int block[3];
  double bt_max[3], bt_delta[3];
  for (int a = 0; a < 3; ++a) bt_delta[a] = step[a] == 0 ? inf : hb * std::abs(inv[a]);
  // Within (D - 1) blocks of any point of an empty block at distance D all
  // blocks are empty: the ray may advance that far along its largest axis.
  const double jump_per_block = hb / std::max({std::abs(dir[0]), std::abs(dir[1]), std::abs(dir[2])});
  const int* nb = grid_.blocks_per_axis();
  auto start_blocks_at = [&](double t) {
    const Eigen::Vector3d p = o + t * dir;
    for (int a = 0; a < 3; ++a) {
      block[a] = std::clamp(static_cast<int>(std::floor(p[a] * inv_hb)), 0, nb[a] - 1);
      bt_max[a] = std::max(next_face(a, block[a], hb), t);
    }
  };
  start_blocks_at(t0);
  double tb_enter = t0;
  for (;;) {
    const std::int32_t blk = grid_.block_at(block[0], block[1], block[2]);
    if (blk < 0 && !block_distance_.empty()) {
      const int dist = block_distance_[block[0] + static_cast<std::size_t>(nb[0]) *
                                                      (block[1] + static_cast<std::size_t>(nb[1]) * block[2])];
      if (dist >= 2) {
        tb_enter += (dist - 1) * jump_per_block;
        if (tb_enter >= t1) break;
        start_blocks_at(tb_enter);
        continue;
      }
    }
    if (blk < 0) {
      const double t_next = height_field_exit(o, dir, inv, block, tb_enter);
      if (t_next > tb_enter) {
        tb_enter = t_next;
        if (tb_enter >= t1) break;
        start_blocks_at(tb_enter);
        continue;
      }
    }
    const double tb_exit = std::min(bt_max[0], std::min(bt_max[1], bt_max[2]));
    if (blk >= 0) {
      int cell[3];
      double t_max[3], t_delta[3];
      const Eigen::Vector3d p = o + tb_enter * dir;
      for (int a = 0; a < 3; ++a) {
        cell[a] = std::clamp(static_cast<int>(std::floor(p[a] * inv_h)) - block[a] * B, 0, B - 1);
        t_max[a] = std::max(next_face(a, block[a] * B + cell[a], h), tb_enter);
        t_delta[a] = step[a] == 0 ? inf : h * std::abs(inv[a]);
      }
      double t_enter = tb_enter;
      for (;;) {
        const double t_exit = std::min(std::min(t_max[0], t_max[1]), std::min(t_max[2], tb_exit));
        const std::int64_t slot = grid_.slot_in_block(blk, cell[0], cell[1], cell[2]);
        if (slot >= 0) {
          const CellSlab& slab = slabs_[slot];
          const float base = slab.n[0] * of[0] + slab.n[1] * of[1] + slab.n[2] * of[2] - slab.d;
          const float rate = slab.n[0] * df[0] + slab.n[1] * df[1] + slab.n[2] * df[2];
          const float s0 = base + rate * float(t_enter), s1 = base + rate * float(t_exit);
          // Infinite h (cells with disagreeing normals) never rejects.
          if (!((s0 > slab.h && s1 > slab.h) || (s0 < -slab.h && s1 < -slab.h))) {
            for (std::uint32_t k = grid_.items_begin(slot), e = grid_.items_end(slot); k < e; ++k) {
              const PackedDisc& disc = discs_[k];
              const float denom = disc.n[0] * df[0] + disc.n[1] * df[1] + disc.n[2] * df[2];
              if (std::abs(denom) < 1e-7f) continue;  // ray in the disc's plane
              const float num = disc.n[0] * (disc.c[0] - of[0]) + disc.n[1] * (disc.c[1] - of[1]) +
                                disc.n[2] * (disc.c[2] - of[2]);
              const float t = num / denom;
              if (!(t > t_min_hit) || t >= best) continue;
              const float qx = of[0] + t * df[0] - disc.c[0];
              const float qy = of[1] + t * df[1] - disc.c[1];
              const float qz = of[2] + t * df[2] - disc.c[2];
              if (qx * qx + qy * qy + qz * qz <= disc.r2) {
                best = t;
                best_id = disc.id;
              }
            }
          }
        }
        if (best <= t_exit || t_exit >= t1) goto done;
        const int a = min_axis(t_max);
        if (t_max[a] >= tb_exit) break;  // leaving the block
        cell[a] += step[a];
        if (static_cast<unsigned>(cell[a]) >= static_cast<unsigned>(B)) break;
        t_enter = t_max[a];
        t_max[a] += t_delta[a];
      }
    }
    if (best <= tb_exit || tb_exit >= t1) break;
    const int a = min_axis(bt_max);
    block[a] += step[a];
    if (static_cast<unsigned>(block[a]) >= static_cast<unsigned>(nb[a])) break;
    tb_enter = bt_max[a];
    bt_max[a] += bt_delta[a];
  }
done:
  if (best_id != kNoHit && best <= max_range) {
    result.range = best;
    result.surfel = best_id;
  }
  return result;
}

double SurfelCaster::height_field_exit(const Eigen::Vector3d& o, const Eigen::Vector3d& dir,
                                       const double* inv, const int* block, double t) const {
  // The largest tile around the block whose every column tops out at or below
  // the block: the ray is free until it leaves the tile sideways or sinks to
  // the tile's top.
  int level = -1;
  for (std::size_t L = 0; L < top_levels_.size(); ++L) {
    const int tx = block[0] >> L, ty = block[1] >> L;
    if (top_levels_[L][tx + static_cast<std::size_t>(top_width_[L]) * ty] > block[2]) break;
    level = static_cast<int>(L);
  }
  if (level < 0) return t;
  const double hb = grid_.cell_size() * VoxelGrid::kBlockSize;
  const double tile = hb * static_cast<double>(1 << level);
  const int tile_xy[2] = {block[0] >> level, block[1] >> level};
  double t_exit = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 2; ++a) {
    if (std::abs(dir[a]) < 1e-12) continue;
    const double face = (tile_xy[a] + (dir[a] > 0 ? 1 : 0)) * tile;
    t_exit = std::min(t_exit, (face - o[a]) * inv[a]);
  }
  const int top = top_levels_[level][tile_xy[0] + static_cast<std::size_t>(top_width_[level]) * tile_xy[1]];
  if (dir[2] < -1e-12) t_exit = std::min(t_exit, (top * hb - o[2]) * inv[2]);
  return t_exit;
}

std::size_t SurfelCaster::memory_bytes() const {
  return grid_.memory_bytes() + discs_.size() * sizeof(PackedDisc) + slabs_.size() * sizeof(CellSlab);
}

}  // namespace lf3pm
