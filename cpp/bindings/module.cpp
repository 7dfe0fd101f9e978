// nanobind module lf3pm._core: a thin layer over the C++ core (no logic here).
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "bindings/numpy.hpp"
#include "lf3pm/metric/evaluator.hpp"
#include "lf3pm/map/map_index.hpp"
#include "lf3pm/metric/metric.hpp"
#include "lf3pm/common/parallel.hpp"
#include "lf3pm/map/plane_fit.hpp"
#include "lf3pm/scan/scan_simulator.hpp"
#include "lf3pm/metric/yaw_sectors.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace lf3pm;
using lf3pm::bindings::points_to_numpy;
using lf3pm::bindings::to_numpy;

namespace {

using PointsIn = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using MatIn = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using PosesIn = nb::ndarray<const double, nb::shape<-1, 4, 4>, nb::c_contig, nb::device::cpu>;

Pose pose_from_matrix(const double* m) {
  Pose p;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) p.rotation(r, c) = m[4 * r + c];
    p.position[r] = m[4 * r + 3];
  }
  return p;
}

Association association_from(const std::string& name) {
  if (name == "surfel") return Association::Surfel;
  if (name == "knn") return Association::Knn;
  throw std::invalid_argument("association must be 'surfel' or 'knn'");
}

EvalParams eval_params(double min_range, double max_range, double noise, std::uint64_t seed,
                       std::uint64_t stream, double scan_voxel, int dof, const std::string& association,
                       double w1, double w2, int threads) {
  EvalParams p;
  p.scan.min_range = min_range;
  p.scan.max_range = max_range;
  p.scan.noise_sigma = noise;
  p.scan.seed = seed;
  p.scan.stream = stream;
  p.scan.scan_voxel = scan_voxel;
  p.scan.threads = resolve_threads(threads);
  p.dof = dof;
  p.association = association_from(association);
  p.weights = {w1, w2};
  return p;
}

nb::dict metric_dict(const Metric& m) {
  nb::dict d;
  d["m"] = m.m;
  d["n"] = m.n;
  d["degenerate"] = m.degenerate;
  d["sigma1"] = m.sigma1;
  d["xi"] = m.xi;
  d["q_min"] = m.q_min;
  d["q_n"] = m.q_n;
  d["q_max"] = m.q_max;
  d["zhang"] = m.zhang;
  d["condition_number"] = m.condition_number;
  d["cov_trace"] = m.cov_trace;
  d["step_norm"] = m.step_norm;
  d["residual_norm"] = m.residual_norm;
  d["scaled_cov_trace"] = m.scaled_cov_trace;
  return d;
}

const char* kScanArgsDoc =
    "min_range/max_range in metres, noise: Gaussian range sigma (m), seed/stream: noise "
    "random stream, scan_voxel: keep the first hit per voxel (0 = off), dof: 6 or 3, "
    "association: 'knn' (FAST-LIO k-NN plane at each hit) or 'surfel' (precomputed plane of the hit map point), "
    "w1/w2: metric weights, threads: 0 = all cores.";

// A simulated scan as the dict simulate_scan and simulate_moving_scan return.
nb::dict scan_dict(SimulatedScan&& scan) {
  nb::dict out;
  out["sensor_points"] = points_to_numpy(scan.sensor_points);
  out["world_points"] = points_to_numpy(scan.world_points);
  const std::size_t h = scan.surfel.size();
  out["surfel"] = to_numpy(std::move(scan.surfel), {h});
  out["ray"] = to_numpy(std::move(scan.ray), {h});
  return out;
}

}  // namespace

// Planner bindings live in their own files of cpp/bindings/ (one per concept).
void bind_planner(nb::module_& m);

NB_MODULE(_core, m) {
  m.doc() = "lf3pm C++ core: map index, surfel ray casting, FAST-LIO observations, LF-3PM metric, planner";
  // The one exception translator: the core's std::invalid_argument (bad input) becomes
  // lf3pm.errors.CoreInputError, an Lf3pmError (one line in the CLI) and a ValueError.
  static nb::object input_error = nb::module_::import_("lf3pm.errors").attr("CoreInputError");
  nb::register_exception_translator(
      [](const std::exception_ptr& error, void* type) {
        try {
          std::rethrow_exception(error);
        } catch (const std::invalid_argument& e) {
          PyErr_SetString(static_cast<PyObject*>(type), e.what());
        }
      },
      input_error.ptr());
  bind_planner(m);

  nb::class_<MapIndex>(m, "MapIndex", "Per-map precomputation: voxel k-NN grid, point planes, surfel caster.")
      .def("__init__",
           [](MapIndex* self, PointsIn pts, double cell_size, int knn, double plane_threshold,
              double max_neighbor_distance, int threads) {
             MapParams p;
             p.cell_size = cell_size;
             p.knn = knn;
             p.plane_threshold = plane_threshold;
             p.max_neighbor_distance = max_neighbor_distance;
             p.threads = threads;
             const double* data = pts.data();
             const std::size_t n = pts.shape(0);
             nb::gil_scoped_release release;
             new (self) MapIndex(data, n, p);
           },
           "points"_a, "cell_size"_a = 0.0, "knn"_a = 5, "plane_threshold"_a = 0.1,
           "max_neighbor_distance"_a = 2.2360679775, "threads"_a = 0)
      .def_prop_ro("size", &MapIndex::size)
      .def_prop_ro("duplicates_removed", &MapIndex::duplicates_removed)
      .def_prop_ro("cell_size", &MapIndex::cell_size)
      .def_prop_ro("median_spacing", &MapIndex::median_spacing)
      .def_prop_ro("memory_bytes", &MapIndex::memory_bytes)
      .def_prop_ro("points", [](const MapIndex& self) { return points_to_numpy(self.points()); },
                   "Map points in index order (sorted by voxel), float64 N x 3.", nb::rv_policy::move)
      .def_prop_ro("normals", [](const MapIndex& self) {
             std::vector<Eigen::Vector3d> v(self.size());
             for (std::size_t i = 0; i < v.size(); ++i) v[i] = self.normal(i);
             return points_to_numpy(v);
           }, nb::rv_policy::move)
      .def_prop_ro("disc_radius", [](const MapIndex& self) {
             std::vector<float> v(self.size());
             for (std::size_t i = 0; i < v.size(); ++i) v[i] = self.disc_radius(i);
             return to_numpy(std::move(v), {self.size()});
           }, nb::rv_policy::move)
      .def("nearest",
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
           "k nearest map points (index order) within max_distance: (indices, distances), -1/inf when missing.")
      .def("cast",
           [](const MapIndex& self, nb::ndarray<const double, nb::shape<3>, nb::device::cpu> origin,
              PointsIn dirs, double max_range) {
             const Eigen::Vector3d o(origin(0), origin(1), origin(2));
             const std::size_t n = dirs.shape(0);
             std::vector<double> range(n);
             std::vector<std::int64_t> id(n);
             const double* d = dirs.data();
             {
               nb::gil_scoped_release release;
               for (std::size_t i = 0; i < n; ++i) {
                 const RayHit h = self.caster().cast(o, Eigen::Vector3d(d + 3 * i), max_range);
                 range[i] = h.range;
                 id[i] = h.surfel == kNoHit ? -1 : std::int64_t(h.surfel);
               }
             }
             return nb::make_tuple(to_numpy(std::move(range), {n}), to_numpy(std::move(id), {n}));
           },
           "origin"_a, "directions"_a, "max_range"_a,
           "Raw surfel casting (world frame): (range, hit point index or -1); range is inf on a miss.");

  m.def("fit_planes",
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

  m.def("simulate_scan",
        [](const MapIndex& map, nb::ndarray<const double, nb::shape<4, 4>, nb::c_contig, nb::device::cpu> pose,
           PointsIn dirs, double min_range, double max_range, double noise, std::uint64_t seed,
           std::uint64_t stream, double scan_voxel, int threads) {
          const EvalParams p = eval_params(min_range, max_range, noise, seed, stream, scan_voxel, 6, "surfel",
                                           0.5, 0.5, threads);
          const Pose ps = pose_from_matrix(pose.data());
          const double* d = dirs.data();
          const std::size_t n = dirs.shape(0);
          SimulatedScan scan;
          {
            nb::gil_scoped_release release;
            scan = simulate_scan(map, ps, d, n, p.scan);
          }
          return scan_dict(std::move(scan));
        },
        "map"_a, "pose"_a, "directions"_a, "min_range"_a, "max_range"_a, "noise"_a = 0.0, "seed"_a = 0,
        "stream"_a = 0, "scan_voxel"_a = 0.0, "threads"_a = 0,
        "Simulated scan at a 4x4 sensor-to-world pose: dict of sensor_points, world_points, surfel, ray.");

  m.def("simulate_moving_scan",
        [](const MapIndex& map, PosesIn ray_poses, PointsIn dirs, double min_range, double max_range, double noise,
           std::uint64_t seed, std::uint64_t stream, double scan_voxel, int threads) {
          const std::size_t n = dirs.shape(0);
          if (ray_poses.shape(0) != n)
            throw std::invalid_argument("one pose per ray: got " + std::to_string(ray_poses.shape(0)) +
                                        " poses for " + std::to_string(n) + " rays");
          const EvalParams p = eval_params(min_range, max_range, noise, seed, stream, scan_voxel, 6, "surfel",
                                           0.5, 0.5, threads);
          std::vector<Pose> poses(n);
          for (std::size_t k = 0; k < n; ++k) poses[k] = pose_from_matrix(ray_poses.data() + 16 * k);
          const double* d = dirs.data();
          SimulatedScan scan;
          {
            nb::gil_scoped_release release;
            scan = simulate_scan(map, poses.data(), d, n, p.scan);
          }
          return scan_dict(std::move(scan));
        },
        "map"_a, "ray_poses"_a, "directions"_a, "min_range"_a, "max_range"_a, "noise"_a = 0.0, "seed"_a = 0,
        "stream"_a = 0, "scan_voxel"_a = 0.0, "threads"_a = 0,
        "Simulated scan of a moving sensor: ray k cast from the 4x4 sensor-to-world pose ray_poses[k] "
        "(K x 4 x 4, one per direction). Dict as simulate_scan's; sensor_points in each ray's own frame, "
        "noise per ray as simulate_scan's.");

  m.def("evaluate",
        [](const MapIndex& map, nb::ndarray<const double, nb::shape<4, 4>, nb::c_contig, nb::device::cpu> pose,
           PointsIn dirs, double min_range, double max_range, double noise, std::uint64_t seed,
           std::uint64_t stream, double scan_voxel, int dof, const std::string& association, double w1,
           double w2, int threads, bool observations) {
          const EvalParams p = eval_params(min_range, max_range, noise, seed, stream, scan_voxel, dof,
                                           association, w1, w2, threads);
          const Pose ps = pose_from_matrix(pose.data());
          const double* d = dirs.data();
          const std::size_t n = dirs.shape(0);
          SimulatedScan scan;
          GramAccumulator gram(dof);
          Observations obs;
          Metric metric;
          {
            nb::gil_scoped_release release;
            scan = simulate_scan(map, ps, d, n, p.scan);
            gram = scan_gram(map, ps, scan, p);
            metric = metric_from_gram(gram.gram(), gram.rows(), p.weights);
            if (observations) obs = scan_observations(map, ps, scan, p);
          }
          nb::dict out = metric_dict(metric);
          out["rays"] = n;
          out["hits"] = scan.world_points.size();
          if (observations) {
            const std::size_t rows = static_cast<std::size_t>(obs.b.size());
            std::vector<double> a(rows * dof);
            for (std::size_t r = 0; r < rows; ++r)
              for (int c = 0; c < dof; ++c) a[r * dof + c] = obs.a(r, c);
            out["A"] = to_numpy(std::move(a), {rows, std::size_t(dof)});
            out["b"] = to_numpy(std::vector<double>(obs.b.data(), obs.b.data() + rows), {rows});
            out["points"] = points_to_numpy(scan.world_points);
            out["sensor_points"] = points_to_numpy(scan.sensor_points);
            out["row_hit"] = to_numpy(std::move(obs.hit), {rows});
          }
          return out;
        },
        "map"_a, "pose"_a, "directions"_a, "min_range"_a, "max_range"_a, "noise"_a = 0.0, "seed"_a = 0,
        "stream"_a = 0, "scan_voxel"_a = 0.0, "dof"_a = 6, "association"_a = "knn", "w1"_a = 0.5,
        "w2"_a = 0.5, "threads"_a = 0, "observations"_a = false,
        (std::string("Scan, associate and compute the metric at one 4x4 pose. ") + kScanArgsDoc).c_str());

  m.def("evaluate_many",
        [](const MapIndex& map, PosesIn poses, nb::ndarray<const std::uint64_t, nb::ndim<1>, nb::c_contig,
           nb::device::cpu> streams, PointsIn dirs, double min_range, double max_range, double noise,
           std::uint64_t seed, double scan_voxel, int dof, const std::string& association, double w1,
           double w2, int threads, double ray_weight) {
          EvalParams p = eval_params(min_range, max_range, noise, seed, 0, scan_voxel, dof,
                                     association, w1, w2, threads);
          p.ray_weight = ray_weight;
          const std::size_t np = poses.shape(0);
          if (streams.shape(0) != np) throw std::invalid_argument("streams must hold one value per pose");
          std::vector<Pose> ps(np);
          for (std::size_t i = 0; i < np; ++i) ps[i] = pose_from_matrix(poses.data() + 16 * i);
          const std::vector<std::uint64_t> st(streams.data(), streams.data() + np);
          const double* d = dirs.data();
          const std::size_t n = dirs.shape(0);
          std::vector<PoseEvaluation> res;
          {
            nb::gil_scoped_release release;
            res = evaluate_poses(map, ps, st, d, n, p);
          }
          // Columns, not a list of dicts: a SOLM chunk is thousands of poses.
          auto column = [&](auto field) {
            std::vector<double> v(np);
            for (std::size_t i = 0; i < np; ++i) v[i] = static_cast<double>(field(res[i]));
            return to_numpy(std::move(v), {np});
          };
          nb::dict out;
          out["sigma1"] = column([](const PoseEvaluation& r) { return r.metric.sigma1; });
          out["xi"] = column([](const PoseEvaluation& r) { return r.metric.xi; });
          out["q_min"] = column([](const PoseEvaluation& r) { return r.metric.q_min; });
          out["q_n"] = column([](const PoseEvaluation& r) { return r.metric.q_n; });
          out["q_max"] = column([](const PoseEvaluation& r) { return r.metric.q_max; });
          out["step_norm"] = column([](const PoseEvaluation& r) { return r.metric.step_norm; });
          out["m"] = column([](const PoseEvaluation& r) { return r.metric.m; });
          out["hits"] = column([](const PoseEvaluation& r) { return r.hits; });
          out["degenerate"] = column([](const PoseEvaluation& r) { return r.metric.degenerate ? 1.0 : 0.0; });
          return out;
        },
        "map"_a, "poses"_a, "streams"_a, "directions"_a, "min_range"_a, "max_range"_a, "noise"_a = 0.0,
        "seed"_a = 0, "scan_voxel"_a = 0.0, "dof"_a = 6, "association"_a = "knn", "w1"_a = 0.5,
        "w2"_a = 0.5, "threads"_a = 0, "ray_weight"_a = 1.0,
        "evaluate() at many 4x4 poses in parallel; pose i uses noise stream streams[i]. "
        "ray_weight: each ray stands for that many rays of the full pattern (thinned builds). "
        "Returns a dict of per-pose columns (float64).");

  m.def("evaluate_yaw_sectors",
        [](const MapIndex& map, PointsIn positions, nb::ndarray<const std::uint64_t, nb::ndim<1>, nb::c_contig,
           nb::device::cpu> streams, PointsIn sector_rays, int bins, int half_width, double min_range,
           double max_range, double noise, std::uint64_t seed, double scan_voxel, int dof,
           const std::string& association, double w1, double w2, int threads, double ray_weight) {
          EvalParams p = eval_params(min_range, max_range, noise, seed, 0, scan_voxel, dof,
                                     association, w1, w2, threads);
          p.ray_weight = ray_weight;
          const std::size_t np = positions.shape(0);
          if (streams.shape(0) != np) throw std::invalid_argument("streams must hold one value per position");
          std::vector<Eigen::Vector3d> pos(np);
          for (std::size_t i = 0; i < np; ++i) pos[i] = Eigen::Vector3d(positions.data() + 3 * i);
          const std::vector<std::uint64_t> st(streams.data(), streams.data() + np);
          std::vector<Metric> res;
          {
            nb::gil_scoped_release release;
            res = evaluate_yaw_sectors(map, pos, st, sector_rays.data(), sector_rays.shape(0), bins,
                                       half_width, p);
          }
          const std::size_t nb_ = static_cast<std::size_t>(bins);
          auto column = [&](auto field) {
            std::vector<double> v(res.size());
            for (std::size_t i = 0; i < res.size(); ++i) v[i] = static_cast<double>(field(res[i]));
            return to_numpy(std::move(v), {np, nb_});
          };
          nb::dict out;
          out["sigma1"] = column([](const Metric& m) { return m.sigma1; });
          out["q_min"] = column([](const Metric& m) { return m.q_min; });
          out["q_n"] = column([](const Metric& m) { return m.q_n; });
          out["q_max"] = column([](const Metric& m) { return m.q_max; });
          out["step_norm"] = column([](const Metric& m) { return m.step_norm; });
          out["m"] = column([](const Metric& m) { return m.m; });
          out["degenerate"] = column([](const Metric& m) { return m.degenerate ? 1.0 : 0.0; });
          return out;
        },
        "map"_a, "positions"_a, "streams"_a, "sector_rays"_a, "bins"_a, "half_width"_a, "min_range"_a,
        "max_range"_a, "noise"_a = 0.0, "seed"_a = 0, "scan_voxel"_a = 0.0, "dof"_a = 6,
        "association"_a = "knn", "w1"_a = 0.5, "w2"_a = 0.5, "threads"_a = 0, "ray_weight"_a = 1.0,
        "SE(2) metric at every yaw bin from one scan per yaw sector (sums of sector Grams). "
        "Returns per-position, per-bin columns.");

  m.def("metric_from_gram",
        [](MatIn gram, std::int64_t rows, double w1, double w2) {
          const std::size_t k = gram.shape(0);
          if (gram.shape(1) != k) throw std::invalid_argument("the Gram must be square");
          Eigen::MatrixXd g(k, k);
          for (std::size_t i = 0; i < k; ++i)
            for (std::size_t j = 0; j < k; ++j) g(i, j) = gram(i, j);
          return metric_dict(metric_from_gram(g, rows, {w1, w2}));
        },
        "gram"_a, "m"_a, "w1"_a = 0.5, "w2"_a = 0.5,
        "Metric from the Gram [A b]^T [A b] of m rows (4x4 or 7x7).");

  m.def("gram",
        [](MatIn a, nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu> b) {
          const std::size_t rows = a.shape(0), n = a.shape(1);
          if ((n != 3 && n != 6) || b.shape(0) != rows) throw std::invalid_argument("A must be m x 3 or m x 6, b of length m");
          GramAccumulator acc(static_cast<int>(n));
          for (std::size_t r = 0; r < rows; ++r) acc.add(a.data() + r * n, b(r));
          const Eigen::MatrixXd g = acc.gram();
          std::vector<double> flat(g.size());
          for (std::size_t i = 0; i <= n; ++i)
            for (std::size_t j = 0; j <= n; ++j) flat[i * (n + 1) + j] = g(i, j);
          return to_numpy(std::move(flat), {n + 1, n + 1});
        },
        "A"_a, "b"_a, "Gram [A b]^T [A b] accumulated as the core does.");
}
