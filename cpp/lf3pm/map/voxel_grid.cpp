#include "lf3pm/map/voxel_grid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace lf3pm {

namespace {
// 2^27 block columns of 12 bytes is 1.5 GiB; larger extents must be cropped or
// indexed with a coarser cell.
constexpr std::int64_t kMaxColumns = std::int64_t(1) << 27;
}  // namespace

VoxelGrid::VoxelGrid(const Eigen::Vector3d& lower, const Eigen::Vector3d& upper, double cell_size)
    : cell_size_(cell_size), inv_cell_(1.0 / cell_size) {
  if (!(cell_size > 0.0) || !std::isfinite(cell_size))
    throw std::invalid_argument("voxel grid cell size must be positive");
  if (!lower.allFinite() || !upper.allFinite()) throw std::invalid_argument("voxel grid bounds must be finite");
  origin_ = lower - Eigen::Vector3d::Constant(cell_size);
  for (int a = 0; a < 3; ++a) {
    const double extent = upper[a] - origin_[a] + cell_size;
    const double blocks = std::max(1.0, std::ceil(extent * inv_cell_ / kBlockSize));
    if (blocks > double(1 << 24)) throw std::invalid_argument("map extent too large for the cell size");
    nblocks_[a] = static_cast<int>(blocks);
    cells_[a] = nblocks_[a] * kBlockSize;
  }
  const std::int64_t columns = static_cast<std::int64_t>(nblocks_[0]) * nblocks_[1];
  if (columns > kMaxColumns)
    throw std::invalid_argument("map extent too large for cell size " + std::to_string(cell_size) +
                                " m: crop the map or use a coarser cell");
  columns_.assign(static_cast<std::size_t>(columns), Column{});
}

Eigen::Vector3d VoxelGrid::upper() const {
  return origin_ + cell_size_ * Eigen::Vector3d(cells_[0], cells_[1], cells_[2]);
}

CellCoord VoxelGrid::cell_of(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d f = (p - origin_) * inv_cell_;
  return {static_cast<int>(std::floor(f.x())), static_cast<int>(std::floor(f.y())),
          static_cast<int>(std::floor(f.z()))};
}

std::uint64_t VoxelGrid::key_of(const CellCoord& c) const {
  // Column-major over blocks, then z-block, then the cell within the block, so
  // sorting by key groups a column's blocks and a block's cells in mask order.
  const std::uint64_t column = static_cast<std::uint64_t>(c.x >> kBlockBits) +
                               static_cast<std::uint64_t>(nblocks_[0]) * static_cast<std::uint64_t>(c.y >> kBlockBits);
  const std::uint64_t block =
      column * static_cast<std::uint64_t>(nblocks_[2]) + static_cast<std::uint64_t>(c.z >> kBlockBits);
  const std::uint64_t local = static_cast<std::uint64_t>((c.x & 3) | ((c.y & 3) << 2) | ((c.z & 3) << 4));
  return (block << 6) | local;
}

void VoxelGrid::build(std::vector<std::pair<std::uint64_t, std::uint32_t>>& pairs) {
  std::sort(pairs.begin(), pairs.end());
  std::fill(columns_.begin(), columns_.end(), Column{});
  blocks_.clear();
  block_ids_.clear();
  cell_start_.clear();
  items_.resize(pairs.size());
  // Pass 1: cells and blocks in key order; remember each block's (column, z).
  std::vector<std::pair<std::uint64_t, std::int32_t>> block_keys;  // (column * nbz + z, block)
  std::uint64_t last_key = ~std::uint64_t(0), last_block = ~std::uint64_t(0);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const std::uint64_t key = pairs[i].first;
    items_[i] = pairs[i].second;
    if (key == last_key) continue;
    last_key = key;
    const std::uint64_t block = key >> 6;
    if (block != last_block) {
      last_block = block;
      Block fresh;
      fresh.first_cell = static_cast<std::uint32_t>(cell_start_.size());
      block_keys.emplace_back(block, static_cast<std::int32_t>(blocks_.size()));
      blocks_.push_back(fresh);
    }
    blocks_.back().mask |= 1ull << (key & 63u);
    cell_start_.push_back(static_cast<std::uint32_t>(i));
  }
  cell_start_.push_back(static_cast<std::uint32_t>(pairs.size()));
  // Pass 2: per column, the z-range of its blocks and their ids.
  const std::uint64_t nbz = static_cast<std::uint64_t>(nblocks_[2]);
  for (std::size_t j = 0; j < block_keys.size();) {
    const std::uint64_t column = block_keys[j].first / nbz;
    std::size_t end = j;
    while (end < block_keys.size() && block_keys[end].first / nbz == column) ++end;
    Column& col = columns_[column];
    col.lo = static_cast<std::int32_t>(block_keys[j].first % nbz);
    col.hi = static_cast<std::int32_t>(block_keys[end - 1].first % nbz) + 1;
    col.offset = static_cast<std::uint32_t>(block_ids_.size());
    block_ids_.resize(block_ids_.size() + (col.hi - col.lo), -1);
    for (std::size_t k = j; k < end; ++k)
      block_ids_[col.offset + (block_keys[k].first % nbz) - col.lo] = block_keys[k].second;
    j = end;
  }
}

std::size_t VoxelGrid::memory_bytes() const {
  return columns_.size() * sizeof(Column) + block_ids_.size() * sizeof(std::int32_t) + blocks_.size() * sizeof(Block) +
         cell_start_.size() * sizeof(std::uint32_t) + items_.size() * sizeof(std::uint32_t);
}

}  // namespace lf3pm
