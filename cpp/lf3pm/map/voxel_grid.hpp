// Sparse voxel grid: which cells of a regular 3D grid hold items, and which items.
//
// Two levels: blocks of 4x4x4 cells, found through a dense 2D array of block
// columns (x, y) that each store only the z-range of blocks they occupy (terrain
// maps are wide and thin, so this stays small where a dense 3D array would
// not), and per occupied block a 64-bit occupancy mask whose prefix popcount
// indexes a compact list of occupied cells. A lookup is three array reads and a
// popcount, no hashing; empty blocks let a ray skip 4 cells at once. The items
// of a cell are a contiguous range of one array (CSR), so a k-NN search or a ray
// test walks memory linearly.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

namespace lf3pm {

struct CellCoord {
  int x, y, z;
};

class VoxelGrid {
 public:
  static constexpr int kBlockBits = 2;
  static constexpr int kBlockSize = 1 << kBlockBits;  // cells per block edge

  VoxelGrid() = default;

  /// Grid of cubic cells of edge `cell_size` covering [lower, upper] with one
  /// cell of margin. Throws std::invalid_argument when the extent needs too
  /// many block columns.
  VoxelGrid(const Eigen::Vector3d& lower, const Eigen::Vector3d& upper, double cell_size);

  /// Fills the grid from (cell key, item) pairs (keys from key_of). The pairs
  /// are sorted in place by (key, item) and the items stored in that order.
  void build(std::vector<std::pair<std::uint64_t, std::uint32_t>>& cell_item_pairs);

  double cell_size() const { return cell_size_; }
  const Eigen::Vector3d& origin() const { return origin_; }
  Eigen::Vector3d upper() const;
  const int* cells_per_axis() const { return cells_; }
  const int* blocks_per_axis() const { return nblocks_; }

  /// Cell containing p (may lie outside the grid; see contains()).
  CellCoord cell_of(const Eigen::Vector3d& p) const;
  bool contains(const CellCoord& c) const {
    return c.x >= 0 && c.y >= 0 && c.z >= 0 && c.x < cells_[0] && c.y < cells_[1] && c.z < cells_[2];
  }
  /// Sort key of an in-grid cell, as used by build().
  std::uint64_t key_of(const CellCoord& c) const;

  /// Index of the block with block coordinates (bx, by, bz) in the grid, or -1 if empty.
  std::int32_t block_at(int bx, int by, int bz) const {
    const Column& col = columns_[bx + static_cast<std::int64_t>(nblocks_[0]) * by];
    if (bz < col.lo || bz >= col.hi) return -1;
    return block_ids_[col.offset + (bz - col.lo)];
  }
  /// Compact index of cell (local lx, ly, lz in 0..3) of block `block`, or -1 when empty.
  std::int64_t slot_in_block(std::int32_t block, int lx, int ly, int lz) const {
    const Block& b = blocks_[block];
    const int local = lx | (ly << 2) | (lz << 4);
    if (!((b.mask >> local) & 1ull)) return -1;
    return static_cast<std::int64_t>(b.first_cell) + __builtin_popcountll(b.mask & ((1ull << local) - 1ull));
  }
  /// Compact index of cell c (in the grid), or -1 when empty.
  std::int64_t cell_slot(const CellCoord& c) const {
    const std::int32_t b = block_at(c.x >> kBlockBits, c.y >> kBlockBits, c.z >> kBlockBits);
    return b < 0 ? -1 : slot_in_block(b, c.x & 3, c.y & 3, c.z & 3);
  }

  /// Items of all cells of block `block`: [first, second). Contiguous because
  /// build() orders items block by block.
  std::pair<std::uint32_t, std::uint32_t> block_items(std::int32_t block) const {
    const Block& b = blocks_[block];
    return {cell_start_[b.first_cell], cell_start_[b.first_cell + __builtin_popcountll(b.mask)]};
  }

  /// Items of the cell with compact index `slot`: [items_begin, items_end).
  std::uint32_t items_begin(std::int64_t slot) const { return cell_start_[slot]; }
  std::uint32_t items_end(std::int64_t slot) const { return cell_start_[slot + 1]; }
  const std::vector<std::uint32_t>& items() const { return items_; }
  std::size_t occupied_cells() const { return cell_start_.empty() ? 0 : cell_start_.size() - 1; }
  /// Frees the item lists, for an owner that copied them into its own layout;
  /// the cell lookup stays, the items_* accessors must not be used afterwards.
  void drop_items() {
    std::vector<std::uint32_t>().swap(cell_start_);
    std::vector<std::uint32_t>().swap(items_);
  }
  std::size_t memory_bytes() const;

 private:
  struct Column {
    std::uint32_t offset = 0;     // into block_ids_
    std::int32_t lo = 0, hi = 0;  // occupied z-range of blocks [lo, hi)
  };
  struct Block {
    std::uint64_t mask = 0;        // bit (x + 4y + 16z): cell occupied
    std::uint32_t first_cell = 0;  // compact index of the block's first occupied cell
  };

  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  double cell_size_ = 1.0;
  double inv_cell_ = 1.0;
  int cells_[3] = {0, 0, 0};
  int nblocks_[3] = {0, 0, 0};
  std::vector<Column> columns_;          // dense over (bx, by)
  std::vector<std::int32_t> block_ids_;  // per column z-range: index into blocks_, or -1
  std::vector<Block> blocks_;
  std::vector<std::uint32_t> cell_start_;  // CSR offsets into items_
  std::vector<std::uint32_t> items_;
};

}  // namespace lf3pm
