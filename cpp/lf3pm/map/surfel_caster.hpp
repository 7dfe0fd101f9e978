// Ray casting against a point-cloud map treated as a set of surfels (discs).
//
// Each map point carries a disc: centred on the point, in the plane of its
// neighbourhood, with a radius that reaches its neighbours. A ray's hit is its
// nearest disc intersection, so a hit on a sampled wall lies on the wall's plane
// (no voxel snapping), a hit on grass carries the grass's roughness, and a
// surface sampled at the map's density is never seen through (discs overlap).
// The discs are found by a voxel walk (Amanatides-Woo) over 4^3-cell blocks and,
// in occupied blocks, over cells; each disc is listed in the cells its own
// bounding box touches. Each occupied cell keeps a slab bounding its discs so
// that rays grazing flat ground reject most cells without testing a disc, and
// its discs in contiguous groups of eight tested together (disc_group.hpp).
// Empty space is skipped two ways, whichever goes farther: a max-mipmap of the
// highest disc point per block column (height-field ray marching) lets a ray
// above every disc of a tile cross the whole tile in one step, down to the
// ground's discs for rays skimming terrain; and each empty block knows its
// Chebyshev distance to the nearest occupied block (for rising rays: the
// nearest at its height or above), so a ray in open space jumps that far at
// once.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <vector>

#include "lf3pm/map/disc_group.hpp"
#include "lf3pm/map/voxel_grid.hpp"

namespace lf3pm {

inline constexpr std::uint32_t kNoHit = std::numeric_limits<std::uint32_t>::max();

struct RayHit {
  double range = std::numeric_limits<double>::infinity();  // along the unit direction
  std::uint32_t surfel = kNoHit;                           // map point index, kNoHit if none
};

class SurfelCaster {
 public:
  SurfelCaster() = default;
  /// Discs at `centres` with unit `normals` and `radii`, for a map indexed with
  /// cells of edge `cell_size` (the caster walks somewhat larger cells).
  /// `lower`: the discs' lower corner (default: their boxes'; a crop passes its map's).
  SurfelCaster(const std::vector<Eigen::Vector3d>& centres, const std::vector<Eigen::Vector3d>& normals,
               const std::vector<float>& radii, double cell_size, const Eigen::Vector3d* lower = nullptr);

  /// Nearest disc hit of the ray origin + s * direction (unit) with 0 < s <= max_range.
  RayHit cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double max_range) const;

  const VoxelGrid& grid() const { return grid_; }
  const Eigen::Vector3d& lower() const { return lower_; }
  std::size_t memory_bytes() const;

 private:
  struct Cell {  // every disc of the cell lies within |n.x - d| <= h
    float n[3];
    float d;
    float h;
    std::uint32_t first_group, groups;  // its discs: groups_[first_group, first_group + groups)
  };

  struct Ray;  // a ray's per-cast constants (surfel_caster.cpp)

  /// Max-mipmap of the per-column disc tops `level` (x fastest).
  void build_top_levels(std::vector<float> level);
  /// Where a ray at parameter t, at height z in block column (bx, by), leaves
  /// the largest tile of columns it overflies (t itself when it overflies none).
  double height_field_exit(const Ray& ray, int bx, int by, double z, double t) const;

  // Discs and slabs are in float coordinates relative to this corner (the
  // discs' lower corner less one map cell), not to the walk grid's origin, so
  // the hits' float rounding does not depend on the walk's cell size.
  Eigen::Vector3d frame_origin_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d lower_ = Eigen::Vector3d::Zero();
  VoxelGrid grid_;
  std::vector<Cell> cells_;        // per occupied cell
  std::vector<DiscGroup> groups_;  // centres relative to the grid origin
  // Per block (x fastest): Chebyshev distance in blocks to the nearest occupied
  // block, capped at 255; empty when the grid is too large to afford it.
  std::vector<std::uint8_t> block_distance_;
  // The same to the nearest occupied block at the same z or above, for rays
  // that never descend.
  std::vector<std::uint8_t> block_distance_up_;
  // top_levels_[top_offset_[L] + tx + ty * top_width_[L]]: the highest disc
  // point (grid-relative z, rounded up) over the 2^L x 2^L block columns of tile
  // (tx, ty); level 0 is one column. Disc (not block or cell) precision lets a
  // ray skimming the ground skip everything down to the ground's discs, which
  // it would otherwise walk cell by cell for metres. One array: a lookup per
  // level, no pointer chase.
  std::vector<float> top_levels_;
  std::vector<std::size_t> top_offset_;
  std::vector<int> top_width_;
};

}  // namespace lf3pm
