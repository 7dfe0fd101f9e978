// Map points sorted by voxel, with bounded-radius k-nearest-neighbour search.
//
// Our own grid search rather than a kd-tree (nanoflann/small_gicp): every query
// here is a k = 5 search that FAST-LIO gates at a few metres, on surface-like
// data; the grid answers it from the 27 cells around the query with no tree
// descent, and the same grid geometry serves the ray caster.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "lf3pm/map/voxel_grid.hpp"

namespace lf3pm {

class PointGrid {
 public:
  PointGrid() = default;
  /// Indexes `points` with cubic cells of edge `cell_size`; the points are
  /// reordered by cell (order() maps new index -> input index) and exact
  /// duplicates are dropped (a duplicate would count twice among k neighbours).
  /// `lower`: the grid's lower corner (default: the points'; a crop passes its map's).
  PointGrid(const std::vector<Eigen::Vector3d>& points, double cell_size, const Eigen::Vector3d* lower = nullptr);

  /// Up to k nearest points to q within max_distance, nearest first (equal
  /// distances by index). Returns the count found; idx/sq_dist receive them.
  int nearest(const Eigen::Vector3d& q, int k, double max_distance, std::uint32_t* idx, double* sq_dist) const;

  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  const std::vector<std::uint32_t>& order() const { return order_; }
  std::size_t duplicates_removed() const { return duplicates_removed_; }
  const VoxelGrid& grid() const { return grid_; }
  const Eigen::Vector3d& lower() const { return lower_; }

 private:
  std::vector<Eigen::Vector3d> points_;
  std::vector<std::uint32_t> order_;
  std::size_t duplicates_removed_ = 0;
  Eigen::Vector3d lower_ = Eigen::Vector3d::Zero();
  VoxelGrid grid_;
};

}  // namespace lf3pm
