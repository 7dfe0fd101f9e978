#include "lf3pm/map/surfel_caster.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lf3pm {

namespace {
// The walk's cells are this much larger than the map's (k-NN) cells: with discs
// tested eight at a time a cell's discs cost less than the steps that smaller
// cells would add (town benchmark, ms per scan: 1x ~13, 1.5x 10.8, 2x 10.0,
// 2.5x 10.4; disc copies per point fall with the cell size).
constexpr double kWalkCellScale = 2.0;
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

// Chebyshev distance to the nearest occupied block at the same height or above:
// all a ray that never descends can reach. Rays rising over streets then jump
// to the buildings instead of creeping along at their distance to the ground.
// A shortest path to such a block can always rise monotonically, so layers are
// solved top-down: seeds from the layer above (one diagonal step up), then an
// exact 2D chessboard transform (forward and backward 8-neighbour passes).
std::vector<std::uint8_t> upward_chebyshev_distance(const VoxelGrid& grid) {
  const int nx = grid.blocks_per_axis()[0], ny = grid.blocks_per_axis()[1], nz = grid.blocks_per_axis()[2];
  std::vector<std::uint8_t> d(static_cast<std::size_t>(nx) * ny * nz, 255);
  auto at = [&](int x, int y, int z) -> std::uint8_t& {
    return d[x + static_cast<std::size_t>(nx) * (y + static_cast<std::size_t>(ny) * z)];
  };
  auto relax = [&](int x, int y, int z, int dx, int dy, int dz) {
    const int xx = x + dx, yy = y + dy;
    if (xx < 0 || yy < 0 || xx >= nx || yy >= ny) return;
    at(x, y, z) = static_cast<std::uint8_t>(std::min<int>(at(x, y, z), at(xx, yy, z + dz) + 1));
  };
  for (int z = nz - 1; z >= 0; --z) {
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        if (grid.block_at(x, y, z) >= 0) at(x, y, z) = 0;
        if (z + 1 < nz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) relax(x, y, z, dx, dy, 1);
      }
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        relax(x, y, z, -1, -1, 0);
        relax(x, y, z, 0, -1, 0);
        relax(x, y, z, 1, -1, 0);
        relax(x, y, z, -1, 0, 0);
      }
    for (int y = ny - 1; y >= 0; --y)
      for (int x = nx - 1; x >= 0; --x) {
        relax(x, y, z, 1, 1, 0);
        relax(x, y, z, 0, 1, 0);
        relax(x, y, z, -1, 1, 0);
        relax(x, y, z, 1, 0, 0);
      }
  }
  return d;
}
}  // namespace

SurfelCaster::SurfelCaster(const std::vector<Eigen::Vector3d>& centres, const std::vector<Eigen::Vector3d>& normals,
                           const std::vector<float>& radii, double cell_size, const Eigen::Vector3d* lower) {
  Eigen::Vector3d lo = centres.front(), hi = centres.front();
  for (std::size_t i = 0; i < centres.size(); ++i) {
    lo = lo.cwiseMin(centres[i] - Eigen::Vector3d::Constant(radii[i]));
    hi = hi.cwiseMax(centres[i] + Eigen::Vector3d::Constant(radii[i]));
  }
  if (lower != nullptr) {
    if ((lo.array() < lower->array()).any()) throw std::invalid_argument("discs lie below the caster's lower corner");
    lo = *lower;
  }
  lower_ = lo;
  frame_origin_ = lo - Eigen::Vector3d::Constant(cell_size);
  grid_ = VoxelGrid(lo, hi, cell_size * kWalkCellScale);
  // A disc is listed in every cell its bounding box touches: a ray then meets
  // the disc in the cell that contains the hit point, which is what lets the
  // walk stop at the first cell whose exit lies beyond the nearest hit. The box
  // of a disc is thin along its normal (r sqrt(1 - n_a^2) per axis), so a
  // ground or wall disc lands in one layer of cells, not the two or three its
  // bounding sphere touches: fewer copies, fewer occupied cells to walk. The
  // margin covers the float rounding of hit points.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs;
  pairs.reserve(centres.size() * 2);
  // Highest disc point per block column (grid-relative, rounded up to float).
  const int nbx = grid_.blocks_per_axis()[0], nby = grid_.blocks_per_axis()[1];
  std::vector<float> column_top(static_cast<std::size_t>(nbx) * nby, 0.0f);
  for (std::size_t i = 0; i < centres.size(); ++i) {
    const Eigen::Vector3d& n = normals[i];
    const Eigen::Vector3d r = radii[i] * (Eigen::Vector3d::Ones() - n.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt() +
                              Eigen::Vector3d::Constant(1e-4 + 1e-3 * radii[i]);
    const CellCoord a = grid_.cell_of(centres[i] - r), b = grid_.cell_of(centres[i] + r);
    for (int z = a.z; z <= b.z; ++z)
      for (int y = a.y; y <= b.y; ++y)
        for (int x = a.x; x <= b.x; ++x) pairs.emplace_back(grid_.key_of({x, y, z}), static_cast<std::uint32_t>(i));
    const double top = centres[i].z() - grid_.origin().z() + r.z();
    float top_f = static_cast<float>(top);
    if (top_f < top) top_f = std::nextafter(top_f, std::numeric_limits<float>::infinity());
    for (int y = a.y >> VoxelGrid::kBlockBits; y <= b.y >> VoxelGrid::kBlockBits; ++y)
      for (int x = a.x >> VoxelGrid::kBlockBits; x <= b.x >> VoxelGrid::kBlockBits; ++x) {
        float& t = column_top[x + static_cast<std::size_t>(nbx) * y];
        t = std::max(t, top_f);
      }
  }
  grid_.build(pairs);
  const auto& items = grid_.items();
  const Eigen::Vector3d origin = frame_origin_;
  cells_.resize(grid_.occupied_cells());
  std::size_t total_groups = 0;
  for (std::size_t s = 0; s < cells_.size(); ++s)
    total_groups += (grid_.items_end(s) - grid_.items_begin(s) + DiscGroup::kLanes - 1) / DiscGroup::kLanes;
  groups_.reserve(total_groups);
  const float no_slab = std::numeric_limits<float>::infinity();
  for (std::size_t s = 0; s < cells_.size(); ++s) {
    const std::uint32_t b = grid_.items_begin(s), e = grid_.items_end(s);
    Cell& cell = cells_[s];
    cell.first_group = static_cast<std::uint32_t>(groups_.size());
    cell.groups = (e - b + DiscGroup::kLanes - 1) / DiscGroup::kLanes;
    groups_.resize(groups_.size() + cell.groups, DiscGroup{});  // zero normals: padding lanes never hit
    for (std::uint32_t k = b; k < e; ++k) {
      const std::uint32_t i = items[k];
      DiscGroup& g = groups_[cell.first_group + (k - b) / DiscGroup::kLanes];
      const int lane = static_cast<int>((k - b) % DiscGroup::kLanes);
      const Eigen::Vector3d c = centres[i] - origin;
      g.cx[lane] = float(c.x());
      g.cy[lane] = float(c.y());
      g.cz[lane] = float(c.z());
      g.nx[lane] = float(normals[i].x());
      g.ny[lane] = float(normals[i].y());
      g.nz[lane] = float(normals[i].z());
      g.r2[lane] = radii[i] * radii[i];
      g.id[lane] = i;
    }
    Eigen::Vector3d n_sum = Eigen::Vector3d::Zero();
    const Eigen::Vector3d n0 = normals[items[b]];
    for (std::uint32_t k = b; k < e; ++k) {
      const Eigen::Vector3d& n = normals[items[k]];
      n_sum += n.dot(n0) >= 0 ? n : Eigen::Vector3d(-n);
    }
    cell.n[0] = 0;
    cell.n[1] = 0;
    cell.n[2] = 1;
    cell.d = 0;
    cell.h = no_slab;
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
      cell.n[0] = float(n.x());
      cell.n[1] = float(n.y());
      cell.n[2] = float(n.z());
      cell.d = float(0.5 * (lo_s + hi_s));
      cell.h = float(0.5 * (hi_s - lo_s) + 1e-4);
    }
  }
  grid_.drop_items();  // the groups hold the ids
  const int* nb = grid_.blocks_per_axis();
  if (static_cast<std::int64_t>(nb[0]) * nb[1] * nb[2] <= kMaxDistanceBlocks) {
    block_distance_ = chebyshev_distance(grid_);
    block_distance_up_ = upward_chebyshev_distance(grid_);
  }
  build_top_levels(std::move(column_top));
}

void SurfelCaster::build_top_levels(std::vector<float> level) {
  int w = grid_.blocks_per_axis()[0], hgt = grid_.blocks_per_axis()[1];
  top_levels_.clear();
  top_offset_.clear();
  top_width_.clear();
  for (;;) {
    top_offset_.push_back(top_levels_.size());
    top_width_.push_back(w);
    top_levels_.insert(top_levels_.end(), level.begin(), level.end());
    if (w == 1 && hgt == 1) break;
    const int w2 = (w + 1) / 2, h2 = (hgt + 1) / 2;
    std::vector<float> up(static_cast<std::size_t>(w2) * h2, 0.0f);
    for (int y = 0; y < hgt; ++y)
      for (int x = 0; x < w; ++x) {
        auto& v = up[x / 2 + static_cast<std::size_t>(w2) * (y / 2)];
        v = std::max(v, level[x + static_cast<std::size_t>(w) * y]);
      }
    level.swap(up);
    w = w2;
    hgt = h2;
  }
}

// Everything about a ray that the walk reads but never changes. The walk keeps
// its state in plain scalars (one per axis, no arrays indexed by a runtime
// axis, nothing captured by reference) so that the compiler holds it in
// registers; indexing a stored array by the step axis forced a store and a
// reload on every step.
struct SurfelCaster::Ray {
  double ox, oy, oz;  // origin, grid-relative
  double dx, dy, dz;  // unit direction
  double ix, iy, iz;  // 1 / direction (infinite along an axis the ray is parallel to)
  int sx, sy, sz;     // step per axis: -1, 0 or 1
};

namespace {
// One Amanatides-Woo walker over a lattice: the current index per axis and the
// ray parameter of the next face crossing per axis.
struct Dda {
  int x, y, z;
  double tx, ty, tz;
};

// Next face along one axis of a lattice of spacing s, from index i.
inline double next_face(int i, int step, double s, double o, double inv, double t) {
  if (step == 0) return std::numeric_limits<double>::infinity();
  return std::max(((i + (step > 0 ? 1 : 0)) * s - o) * inv, t);
}

// Steps the walker across its nearest face; returns that face's parameter. The
// axis is chosen without branches (the next axis is data-dependent and a
// mispredicted branch costs more than the step): x on a strict minimum, else y
// when strictly below z, else z.
inline double advance(Dda& w, int sx, int sy, int sz, double dtx, double dty, double dtz) {
  const bool ax = w.tx < w.ty && w.tx < w.tz;
  const bool ay = !ax && w.ty < w.tz;
  const bool az = !ax && !ay;
  const double t = ax ? w.tx : (ay ? w.ty : w.tz);
  w.x += ax ? sx : 0;
  w.y += ay ? sy : 0;
  w.z += az ? sz : 0;
  w.tx += ax ? dtx : 0.0;
  w.ty += ay ? dty : 0.0;
  w.tz += az ? dtz : 0.0;
  return t;
}
}  // namespace

RayHit SurfelCaster::cast(const Eigen::Vector3d& origin_world, const Eigen::Vector3d& dir, double max_range) const {
  RayHit result;
  if (groups_.empty()) return result;
  constexpr int B = VoxelGrid::kBlockSize;
  const double h = grid_.cell_size();
  const double hb = h * B;
  const double inv_h = 1.0 / h, inv_hb = 1.0 / hb;
  const Eigen::Vector3d o = origin_world - grid_.origin();  // grid-relative
  const Eigen::Vector3d extent = grid_.upper() - grid_.origin();
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
  const Ray ray{o.x(), o.y(), o.z(), dir.x(), dir.y(), dir.z(), inv[0], inv[1], inv[2], step[0], step[1], step[2]};
  const int sx = ray.sx, sy = ray.sy, sz = ray.sz;

  const Eigen::Vector3d o_frame = origin_world - frame_origin_;
  const float of[3] = {float(o_frame.x()), float(o_frame.y()), float(o_frame.z())};
  const float df[3] = {float(ray.dx), float(ray.dy), float(ray.dz)};
  const float t_min_hit = 1e-6f;
  float best = std::numeric_limits<float>::infinity();
  std::uint32_t best_id = kNoHit;

  const double dbx = sx == 0 ? inf : hb * std::abs(ray.ix), dby = sy == 0 ? inf : hb * std::abs(ray.iy),
               dbz = sz == 0 ? inf : hb * std::abs(ray.iz);
  const double dcx = sx == 0 ? inf : h * std::abs(ray.ix), dcy = sy == 0 ? inf : h * std::abs(ray.iy),
               dcz = sz == 0 ? inf : h * std::abs(ray.iz);
  // Within (D - 1) blocks of any point of an empty block at distance D all
  // blocks are empty: the ray may advance that far along its largest axis.
  const double jump_per_block = hb / std::max({std::abs(ray.dx), std::abs(ray.dy), std::abs(ray.dz)});
  const int* nb = grid_.blocks_per_axis();
  const int nbx = nb[0], nby = nb[1], nbz = nb[2];
  // The walker over blocks, (re)started at parameter t.
  const auto blocks_at = [ray, inv_hb, hb, nbx, nby, nbz](double t) {
    Dda w;
    w.x = std::clamp(static_cast<int>(std::floor((ray.ox + t * ray.dx) * inv_hb)), 0, nbx - 1);
    w.y = std::clamp(static_cast<int>(std::floor((ray.oy + t * ray.dy) * inv_hb)), 0, nby - 1);
    w.z = std::clamp(static_cast<int>(std::floor((ray.oz + t * ray.dz) * inv_hb)), 0, nbz - 1);
    w.tx = next_face(w.x, ray.sx, hb, ray.ox, ray.ix, t);
    w.ty = next_face(w.y, ray.sy, hb, ray.oy, ray.iy, t);
    w.tz = next_face(w.z, ray.sz, hb, ray.oz, ray.iz, t);
    return w;
  };
  const std::uint8_t* distance = block_distance_.empty() ? nullptr
                                 : ray.dz >= 0.0         ? block_distance_up_.data()
                                                         : block_distance_.data();
  Dda bw = blocks_at(t0);
  double tb_enter = t0;
  for (;;) {
    // Above every column of a tile the ray crosses the tile at once; failing
    // that, in an empty block it jumps by the block's Chebyshev distance. The
    // dense distance (0 when occupied) is read before the sparse block lookup,
    // whose two dependent loads then serve occupied blocks only.
    double t_next = height_field_exit(ray, bw.x, bw.y, ray.oz + tb_enter * ray.dz, tb_enter);
    int dist = 0;
    if (distance) {
      dist = distance[bw.x + static_cast<std::size_t>(nbx) * (bw.y + static_cast<std::size_t>(nby) * bw.z)];
      if (dist >= 2) t_next = std::max(t_next, tb_enter + (dist - 1) * jump_per_block);
    }
    if (t_next > tb_enter) {
      tb_enter = t_next;
      if (tb_enter >= t1) break;
      bw = blocks_at(tb_enter);
      continue;
    }
    const std::int32_t blk = dist == 0 ? grid_.block_at(bw.x, bw.y, bw.z) : -1;
    const double tb_exit = std::min(bw.tx, std::min(bw.ty, bw.tz));
    if (blk >= 0) {
      const double px = ray.ox + tb_enter * ray.dx, py = ray.oy + tb_enter * ray.dy, pz = ray.oz + tb_enter * ray.dz;
      Dda cw;
      cw.x = std::clamp(static_cast<int>(std::floor(px * inv_h)) - bw.x * B, 0, B - 1);
      cw.y = std::clamp(static_cast<int>(std::floor(py * inv_h)) - bw.y * B, 0, B - 1);
      cw.z = std::clamp(static_cast<int>(std::floor(pz * inv_h)) - bw.z * B, 0, B - 1);
      cw.tx = next_face(bw.x * B + cw.x, sx, h, ray.ox, ray.ix, tb_enter);
      cw.ty = next_face(bw.y * B + cw.y, sy, h, ray.oy, ray.iy, tb_enter);
      cw.tz = next_face(bw.z * B + cw.z, sz, h, ray.oz, ray.iz, tb_enter);
      double t_enter = tb_enter;
      for (;;) {
        const double t_exit = std::min(std::min(cw.tx, cw.ty), std::min(cw.tz, tb_exit));
        const std::int64_t slot = grid_.slot_in_block(blk, cw.x, cw.y, cw.z);
        if (slot >= 0) {
          const Cell& cell = cells_[slot];
          const float base = cell.n[0] * of[0] + cell.n[1] * of[1] + cell.n[2] * of[2] - cell.d;
          const float rate = cell.n[0] * df[0] + cell.n[1] * df[1] + cell.n[2] * df[2];
          const float s0 = base + rate * float(t_enter), s1 = base + rate * float(t_exit);
          // Infinite h (cells with disagreeing normals) never rejects.
          if (!((s0 > cell.h && s1 > cell.h) || (s0 < -cell.h && s1 < -cell.h)))
            nearest_disc_hit(&groups_[cell.first_group], cell.groups, of, df, t_min_hit, best, best_id);
        }
        if (best <= t_exit || t_exit >= t1) goto done;
        if (t_exit >= tb_exit) break;  // leaving the block
        t_enter = advance(cw, sx, sy, sz, dcx, dcy, dcz);
        if (static_cast<unsigned>(cw.x | cw.y | cw.z) >= static_cast<unsigned>(B)) break;
      }
    }
    if (best <= tb_exit || tb_exit >= t1) break;
    tb_enter = advance(bw, sx, sy, sz, dbx, dby, dbz);
    if (static_cast<unsigned>(bw.x) >= static_cast<unsigned>(nbx) ||
        static_cast<unsigned>(bw.y) >= static_cast<unsigned>(nby) ||
        static_cast<unsigned>(bw.z) >= static_cast<unsigned>(nbz))
      break;
  }
done:
  if (best_id != kNoHit && best <= max_range) {
    result.range = best;
    result.surfel = best_id;
  }
  return result;
}

double SurfelCaster::height_field_exit(const Ray& ray, int bx, int by, double z, double t) const {
  // The largest tile around the column whose every disc lies below the ray's
  // height z: the ray is free until it leaves the tile sideways or sinks to the
  // tile's top.
  int level = -1;
  for (std::size_t L = 0; L < top_offset_.size(); ++L) {
    const int tx = bx >> L, ty = by >> L;
    if (top_levels_[top_offset_[L] + tx + static_cast<std::size_t>(top_width_[L]) * ty] > z) break;
    level = static_cast<int>(L);
  }
  if (level < 0) return t;
  const double tile = grid_.cell_size() * VoxelGrid::kBlockSize * static_cast<double>(1 << level);
  const int tx = bx >> level, ty = by >> level;
  double t_exit = std::numeric_limits<double>::infinity();
  if (ray.sx != 0) t_exit = std::min(t_exit, ((tx + (ray.sx > 0 ? 1 : 0)) * tile - ray.ox) * ray.ix);
  if (ray.sy != 0) t_exit = std::min(t_exit, ((ty + (ray.sy > 0 ? 1 : 0)) * tile - ray.oy) * ray.iy);
  const double top = top_levels_[top_offset_[level] + tx + static_cast<std::size_t>(top_width_[level]) * ty];
  if (ray.dz < -1e-12) t_exit = std::min(t_exit, (top - ray.oz) * ray.iz);
  return t_exit;
}

std::size_t SurfelCaster::memory_bytes() const {
  return grid_.memory_bytes() + groups_.size() * sizeof(DiscGroup) + cells_.size() * sizeof(Cell) +
         2 * block_distance_.size() + top_levels_.size() * sizeof(float);
}

}  // namespace lf3pm
