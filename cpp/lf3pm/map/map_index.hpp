// Everything a scan needs from a map, computed once per map: the points sorted
// by voxel with a k-NN grid, every point's neighbourhood plane (FAST-LIO's
// association plane, reused for hits on that point) and its surfel disc, and
// the ray caster over those discs.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "lf3pm/map/plane_fit.hpp"
#include "lf3pm/map/point_grid.hpp"
#include "lf3pm/map/surfel_caster.hpp"

namespace lf3pm {

struct MapParams {
  double cell_size = 0.0;                       // voxel edge (m); 0 = chosen from the point spacing
  int knn = 5;                                  // FAST-LIO NUM_MATCH_POINTS
  double plane_threshold = 0.1;                 // FAST-LIO: every neighbour within 0.1 m of the plane
  double max_neighbor_distance = 2.2360679775;  // FAST-LIO: 5th neighbour within sqrt(5) m
  int threads = 0;                              // 0 = all cores
};

/// What an index takes from its whole map beyond its own points: an index of a crop
/// built in its map's frame holds, for every point whose k nearest neighbours lie in
/// the crop, the very planes and discs of the whole map's index, and casts rays that
/// stay in the crop to the very same hits (the grids share their origins, so every
/// float operation is the same; docs/scale.md).
struct MapFrame {
  Eigen::Vector3d point_lower = Eigen::Vector3d::Zero();   // the k-NN grid's lower corner
  Eigen::Vector3d caster_lower = Eigen::Vector3d::Zero();  // the surfel caster's lower corner
  double cell_size = 0.0;
  double median_spacing = 0.0;
};

/// The frame an index of these points would have, without building the index (a map
/// too large to index whole is built tile by tile in it). Throws as MapIndex does.
MapFrame map_frame(const double* xyz, std::size_t count, const MapParams& params);

/// The widest disc an index of a frame with this cell size and median spacing makes
/// (m): three cells or the neighbour gate, never narrower than the smallest disc (0.75
/// of the median spacing). A crop of the map reaching this far beyond a tile's rays
/// holds every disc they can hit (python/lf3pm/solm/tiles.py).
double largest_disc(double cell_size, double median_spacing, const MapParams& params);

class MapIndex {
 public:
  /// Builds the index of `points` (N x 3, finite, N >= knn), in its own frame or, given
  /// `frame`, in that of the map it is cut from (every point must lie above the frame's
  /// lower corners). Throws std::invalid_argument on bad input.
  MapIndex(const double* xyz, std::size_t count, const MapParams& params, const MapFrame* frame = nullptr);

  const MapParams& params() const { return params_; }
  double cell_size() const { return cell_size_; }
  double median_spacing() const { return median_spacing_; }
  /// This index's frame: an index of a crop built with it matches this one (MapFrame).
  MapFrame frame() const { return {grid_.lower(), caster_.lower(), cell_size_, median_spacing_}; }
  std::size_t size() const { return grid_.points().size(); }
  std::size_t duplicates_removed() const { return grid_.duplicates_removed(); }

  /// Points in index order (sorted by voxel); order()[i] is the input index of point i.
  const std::vector<Eigen::Vector3d>& points() const { return grid_.points(); }
  const std::vector<std::uint32_t>& order() const { return grid_.order(); }
  const PointGrid& grid() const { return grid_; }
  const SurfelCaster& caster() const { return caster_; }

  /// Neighbourhood plane of point i (its k nearest map points, itself included).
  const Eigen::Vector3d& normal(std::uint32_t i) const { return normals_[i]; }
  const Eigen::Vector3d& centroid(std::uint32_t i) const { return centroids_[i]; }
  bool plane_valid(std::uint32_t i) const { return valid_[i] != 0; }
  float disc_radius(std::uint32_t i) const { return radii_[i]; }

  /// FAST-LIO association of an arbitrary world point: its k nearest map points
  /// and their plane; false when too few neighbours are near or the plane is invalid.
  bool associate(const Eigen::Vector3d& w, Plane* plane) const;

  std::size_t memory_bytes() const;

 private:
  MapParams params_;
  double cell_size_ = 0.0;
  double median_spacing_ = 0.0;
  PointGrid grid_;
  std::vector<Eigen::Vector3d> normals_;
  std::vector<Eigen::Vector3d> centroids_;
  std::vector<std::uint8_t> valid_;
  std::vector<float> radii_;
  SurfelCaster caster_;
};

}  // namespace lf3pm
