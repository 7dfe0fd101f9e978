#include "lf3pm/map/map_index.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "lf3pm/common/parallel.hpp"
#include "lf3pm/common/random.hpp"

namespace lf3pm {

namespace {

constexpr int kMaxKnn = 32;
// Cells holding about this many points on a surface balance the cost of the
// 27-cell k-NN search against the cost of walking empty cells along a ray.
constexpr double kPointsPerCell = 12.0;

// Points of the map searched at a time by the spacing estimate: its coarse grid then
// needs about 70 MB whatever the map's size (one grid over every point, with the copy
// it was built from, took about 70 bytes a point: 4 GB for 60 M points).
constexpr std::size_t kSpacingChunk = std::size_t(1) << 20;

// Median distance from a point to its nearest other point, estimated on a seeded
// sample: for each sample, the nearest point of different coordinates within four
// coarse cells, found chunk by chunk (the nearest over the map is the least of the
// chunks' nearest). `lo`, `hi`: the points' bounding box.
double estimate_spacing(const double* xyz, std::size_t n, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                        int threads) {
  auto point = [xyz](std::size_t i) { return Eigen::Vector3d(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]); };
  const Eigen::Vector3d ext = (hi - lo).cwiseMax(1.0);
  // Surface-like data: N points over roughly the largest face of the box.
  const double area = std::max({ext.x() * ext.y(), ext.x() * ext.z(), ext.y() * ext.z()});
  double cell = std::max(0.02, 4.0 * std::sqrt(area / n));
  const double volume_cap = std::cbrt(ext.prod() / (1 << 26)) * 8.0;  // keep the provisional grid small
  cell = std::max(cell, volume_cap);
  const std::size_t samples = std::min<std::size_t>(n, 4000);
  std::vector<Eigen::Vector3d> queries(samples);
  for (std::size_t s = 0; s < samples; ++s) queries[s] = point(splitmix64(s) % n);
  const double reach = 4.0 * cell;
  std::vector<double> nearest_sq(samples, std::numeric_limits<double>::infinity());
  std::vector<Eigen::Vector3d> chunk;
  for (std::size_t begin = 0; begin < n; begin += kSpacingChunk) {
    const std::size_t end = std::min(n, begin + kSpacingChunk);
    chunk.resize(end - begin);
    for (std::size_t i = begin; i < end; ++i) chunk[i - begin] = point(i);
    const PointGrid coarse(chunk, cell);  // drops exact duplicates: at most one result equals q
    parallel_for(samples, 256, threads, [&](std::size_t b, std::size_t e) {
      std::uint32_t idx[2];
      double d2[2];
      for (std::size_t s = b; s < e; ++s) {
        const int found = coarse.nearest(queries[s], 2, reach, idx, d2);
        for (int j = 0; j < found; ++j)
          if (coarse.points()[idx[j]] != queries[s]) {
            nearest_sq[s] = std::min(nearest_sq[s], d2[j]);
            break;
          }
      }
    });
  }
  std::vector<double> nn(samples);
  for (std::size_t s = 0; s < samples; ++s) nn[s] = std::isfinite(nearest_sq[s]) ? std::sqrt(nearest_sq[s]) : reach;
  std::nth_element(nn.begin(), nn.begin() + samples / 2, nn.end());
  return std::max(nn[samples / 2], 1e-4);
}

}  // namespace

namespace {

void check_params(const MapParams& params, std::size_t count) {
  if (params.knn < 3 || params.knn > kMaxKnn) throw std::invalid_argument("knn must be between 3 and 32");
  if (!(params.plane_threshold > 0) || !(params.max_neighbor_distance > 0))
    throw std::invalid_argument("plane_threshold and max_neighbor_distance must be positive");
  if (count < static_cast<std::size_t>(params.knn)) throw std::invalid_argument("the map has fewer points than knn");
  if (count >= std::size_t(0xFFFFFFFEu)) throw std::invalid_argument("the map has too many points");
}

void check_finite(const double* xyz, std::size_t count) {
  for (std::size_t i = 0; i < 3 * count; ++i)
    if (!std::isfinite(xyz[i])) throw std::invalid_argument("the map has non-finite coordinates");
}

std::vector<Eigen::Vector3d> read_points(const double* xyz, std::size_t count) {
  check_finite(xyz, count);
  std::vector<Eigen::Vector3d> input(count);
  for (std::size_t i = 0; i < count; ++i) input[i] = Eigen::Vector3d(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  return input;
}

// The frame of `count` finite points (x, y, z rows), read in place: nothing of the
// map's size is allocated, so a map too large to index whole has its frame computed.
MapFrame frame_of(const double* xyz, std::size_t count, const MapParams& params) {
  Eigen::Vector3d lo(xyz[0], xyz[1], xyz[2]), hi = lo;
  for (std::size_t i = 1; i < count; ++i) {
    const Eigen::Vector3d p(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  MapFrame f;
  f.median_spacing = estimate_spacing(xyz, count, lo, hi, params.threads);
  f.cell_size =
      params.cell_size > 0 ? params.cell_size : std::clamp(f.median_spacing * std::sqrt(kPointsPerCell), 0.05, 4.0);
  f.point_lower = lo;
  // One cell more than the widest disc: float rounding of the radii never crosses it.
  f.caster_lower =
      f.point_lower - Eigen::Vector3d::Constant(largest_disc(f.cell_size, f.median_spacing, params) + f.cell_size);
  return f;
}

}  // namespace

double largest_disc(double cell_size, double median_spacing, const MapParams& params) {
  return std::max(0.75 * median_spacing, std::min(3.0 * cell_size, params.max_neighbor_distance));
}

MapFrame map_frame(const double* xyz, std::size_t count, const MapParams& params) {
  check_params(params, count);
  check_finite(xyz, count);
  return frame_of(xyz, count, params);
}

MapIndex::MapIndex(const double* xyz, std::size_t count, const MapParams& params, const MapFrame* frame)
    : params_(params) {
  check_params(params, count);
  std::vector<Eigen::Vector3d> input = read_points(xyz, count);
  const int threads = params.threads;
  const MapFrame own = frame != nullptr ? *frame : frame_of(xyz, count, params);
  if (!(own.cell_size > 0 && own.median_spacing > 0)) throw std::invalid_argument("invalid map frame");
  median_spacing_ = own.median_spacing;
  cell_size_ = own.cell_size;
  grid_ = PointGrid(input, cell_size_, &own.point_lower);
  input.clear();
  input.shrink_to_fit();

  const auto& pts = grid_.points();
  const std::size_t n = pts.size();
  normals_.resize(n);
  centroids_.resize(n);
  valid_.resize(n);
  radii_.resize(n);
  const int k = params.knn;
  const double smallest_radius = 0.75 * median_spacing_;
  const double largest_radius = largest_disc(cell_size_, median_spacing_, params);
  parallel_for(n, 4096, threads, [&](std::size_t b, std::size_t e) {
    std::uint32_t idx[kMaxKnn];
    double d2[kMaxKnn];
    Eigen::Vector3d nb[kMaxKnn];
    for (std::size_t i = b; i < e; ++i) {
      const int found = grid_.nearest(pts[i], k, params.max_neighbor_distance, idx, d2);
      for (int j = 0; j < found; ++j) nb[j] = pts[idx[j]];
      const Plane plane = fit_plane(nb, found);
      normals_[i] = plane.normal;
      centroids_[i] = plane.centroid;
      valid_[i] = (found == k && plane.max_distance <= params.plane_threshold) ? 1 : 0;
      // The disc reaches the farthest of the k neighbours, so neighbouring discs
      // overlap and a sampled surface has no holes; never smaller than the
      // typical spacing (isolated points), never larger than three cells: a
      // disc is listed in every cell it touches, and sparse clutter with
      // metre-wide discs would otherwise multiply the caster's memory.
      const double reach = found > 1 ? std::sqrt(d2[found - 1]) : median_spacing_;
      radii_[i] = static_cast<float>(std::clamp(reach, smallest_radius, largest_radius));
    }
  });
  // The caster's corner comes from the frame, not from the discs: a crop's edge discs
  // are wider (their neighbours are cut off), and the crop must share the corner.
  caster_ = SurfelCaster(pts, normals_, radii_, cell_size_, &own.caster_lower);
}

bool MapIndex::associate(const Eigen::Vector3d& w, Plane* plane) const {
  std::uint32_t idx[kMaxKnn];
  double d2[kMaxKnn];
  Eigen::Vector3d nb[kMaxKnn];
  const int k = params_.knn;
  const int found = grid_.nearest(w, k, params_.max_neighbor_distance, idx, d2);
  if (found < k) return false;
  for (int j = 0; j < k; ++j) nb[j] = grid_.points()[idx[j]];
  *plane = fit_plane(nb, k);
  return plane->max_distance <= params_.plane_threshold;
}

std::size_t MapIndex::memory_bytes() const {
  const std::size_t n = size();
  return n * (3 * sizeof(Eigen::Vector3d) + sizeof(std::uint32_t) + 1 + sizeof(float)) + grid_.grid().memory_bytes() +
         caster_.memory_bytes();
}

}  // namespace lf3pm
