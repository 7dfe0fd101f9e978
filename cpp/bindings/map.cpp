// nanobind bindings of the map stage (cpp/lf3pm/map/): its parameters, the map index, plane fits.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/tuple.h>

#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

#include "bindings/numpy.hpp"
#include "lf3pm/map/map_index.hpp"
#include "lf3pm/map/plane_fit.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace lf3pm;
using lf3pm::bindings::points_to_numpy;
using lf3pm::bindings::to_numpy;

static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "points are viewed as packed N x 3 doubles");

void bind_map(nb::module_& m) {
  using PointsIn = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;

  nb::class_<MapParams>(m, "MapParams", "Map indexing and FAST-LIO association parameters (the defaults).")
      .def(nb::init<>())
      .def_rw("cell_size", &MapParams::cell_size, "Voxel edge of the k-NN grid (m); 0 = from the point spacing.")
      .def_rw("knn", &MapParams::knn, "Neighbours per association plane (FAST-LIO NUM_MATCH_POINTS).")
      .def_rw("plane_threshold", &MapParams::plane_threshold,
              "Plane validity: every neighbour within this of the plane (m).")
      .def_rw("max_neighbor_distance", &MapParams::max_neighbor_distance,
              "The k-th neighbour must lie within this of the hit (m; FAST-LIO sqrt 5).")
      .def_rw("threads", &MapParams::threads, "Worker threads (0 = all cores).");

  // A frame travels to other processes (cluster builds), so it pickles as its eight numbers.
  using FrameState = std::tuple<double, double, double, double, double, double, double, double>;
  auto frame_state = [](const MapFrame& f) {
    return FrameState{f.point_lower.x(),  f.point_lower.y(),  f.point_lower.z(), f.caster_lower.x(),
                      f.caster_lower.y(), f.caster_lower.z(), f.cell_size,       f.median_spacing};
  };
  nb::class_<MapFrame>(m, "MapFrame", "The frame of a map's index, in which an index of its crop matches it.")
      .def_ro("cell_size", &MapFrame::cell_size)
      .def_ro("median_spacing", &MapFrame::median_spacing)
      .def("__getstate__", frame_state)
      .def("__setstate__",
           [](MapFrame& f, const FrameState& s) {
             new (&f) MapFrame{{std::get<0>(s), std::get<1>(s), std::get<2>(s)},
                               {std::get<3>(s), std::get<4>(s), std::get<5>(s)},
                               std::get<6>(s),
                               std::get<7>(s)};
           })
      .def("__eq__", [frame_state](const MapFrame& a, const MapFrame& b) { return frame_state(a) == frame_state(b); });

  m.def(
      "largest_disc",
      [](const MapFrame& frame, const MapParams& params) {
        return largest_disc(frame.cell_size, frame.median_spacing, params);
      },
      nb::arg("frame"), nb::arg("params"),
      "The widest disc (m) an index of this frame makes with these parameters' neighbour gate.");
  m.def(
      "map_frame",
      [](PointsIn pts, const MapParams& params) {
        const double* data = pts.data();
        const std::size_t n = pts.shape(0);
        nb::gil_scoped_release release;
        return map_frame(data, n, params);
      },
      "points"_a, "params"_a = MapParams(),
      "The frame MapIndex(points, params) would have, without building the index.");

  nb::class_<MapIndex>(m, "MapIndex", "Per-map precomputation: voxel k-NN grid, point planes, surfel caster.")
      .def(
          "__init__",
          [](MapIndex* self, PointsIn pts, const MapParams& params, const MapFrame* frame) {
            const double* data = pts.data();
            const std::size_t n = pts.shape(0);
            nb::gil_scoped_release release;
            new (self) MapIndex(data, n, params, frame);
          },
          "points"_a, "params"_a = MapParams(), "frame"_a.none() = nb::none(),
          "The index of points (N x 3); in `frame` (another index's), an index of that map's crop.")
      .def_prop_ro("frame", &MapIndex::frame)
      .def_prop_ro("size", &MapIndex::size)
      .def_prop_ro("duplicates_removed", &MapIndex::duplicates_removed)
      .def_prop_ro("cell_size", &MapIndex::cell_size)
      .def_prop_ro("median_spacing", &MapIndex::median_spacing)
      .def_prop_ro("memory_bytes", &MapIndex::memory_bytes)
      // A read-only view of the index's own points (Vector3d is three packed doubles), kept
      // alive by the index: a SOLM build crops them once per tile, so no copy per call.
      .def_prop_ro(
          "points",
          [](const MapIndex& self) {
            return nb::ndarray<nb::numpy, const double, nb::shape<-1, 3>>(self.points().front().data(),
                                                                          {self.size(), 3}, nb::handle());
          },
          "Map points in index order (sorted by voxel), float64 N x 3, read-only.", nb::rv_policy::reference_internal)
      .def_prop_ro(
          "normals",
          [](const MapIndex& self) {
            std::vector<Eigen::Vector3d> v(self.size());
            for (std::size_t i = 0; i < v.size(); ++i) v[i] = self.normal(i);
            return points_to_numpy(v);
          },
          nb::rv_policy::move)
      .def_prop_ro(
          "disc_radius",
          [](const MapIndex& self) {
            std::vector<float> v(self.size());
            for (std::size_t i = 0; i < v.size(); ++i) v[i] = self.disc_radius(i);
            return to_numpy(std::move(v), {self.size()});
          },
          nb::rv_policy::move)
      .def(
          "nearest",
          [](const MapIndex& self, PointsIn q, int k, double max_distance) {
            const std::size_t n = q.shape(0);
            std::vector<std::int64_t> idx(n * k, -1);
            std::vector<double> dist(n * k, std::numeric_limits<double>::infinity());
            const double* data = q.data();
            {
              nb::gil_scoped_release release;
              std::vector<std::uint32_t> id(k);
              std::vector<double> d2(k);
              for (std::size_t i = 0; i < n; ++i) {
                const int f = self.grid().nearest(Eigen::Vector3d(data + 3 * i), k, max_distance, id.data(), d2.data());
                for (int j = 0; j < f; ++j) {
                  idx[i * k + j] = id[j];
                  dist[i * k + j] = std::sqrt(d2[j]);
                }
              }
            }
            return nb::make_tuple(to_numpy(std::move(idx), {n, std::size_t(k)}),
                                  to_numpy(std::move(dist), {n, std::size_t(k)}));
          },
          "queries"_a, "k"_a, "max_distance"_a,
          "k nearest map points (index order) within max_distance: (indices, distances), -1/inf when missing.");

  m.def(
      "fit_planes",
      [](nb::ndarray<const double, nb::shape<-1, -1, 3>, nb::c_contig, nb::device::cpu> sets) {
        const std::size_t m = sets.shape(0), n = sets.shape(1);
        std::vector<double> normals(3 * m), centroids(3 * m), max_distance(m);
        const double* data = sets.data();
        std::vector<Eigen::Vector3d> pts(n);
        for (std::size_t i = 0; i < m; ++i) {
          for (std::size_t j = 0; j < n; ++j) pts[j] = Eigen::Vector3d(data + 3 * (i * n + j));
          const Plane p = fit_plane(pts.data(), static_cast<int>(n));
          for (int a = 0; a < 3; ++a) {
            normals[3 * i + a] = p.normal[a];
            centroids[3 * i + a] = p.centroid[a];
          }
          max_distance[i] = p.max_distance;
        }
        return nb::make_tuple(to_numpy(std::move(normals), {m, 3}), to_numpy(std::move(centroids), {m, 3}),
                              to_numpy(std::move(max_distance), {m}));
      },
      "point_sets"_a,
      "PCA plane of each of M sets of N points (M x N x 3): (normals M x 3, centroids M x 3, "
      "largest |distance| of a set's points to its plane, M).");
}
