// nanobind bindings of the metric stage (cpp/lf3pm/metric/): its parameters, the metric
// and the evaluations of one pose, many poses and yaw sectors.
#include "lf3pm/metric/metric.hpp"

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>

#include <stdexcept>
#include <utility>
#include <vector>

#include "bindings/numpy.hpp"
#include "lf3pm/metric/evaluator.hpp"
#include "lf3pm/metric/yaw_sectors.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace lf3pm;
using lf3pm::bindings::points_to_numpy;
using lf3pm::bindings::pose_from_matrix;
using lf3pm::bindings::to_numpy;

namespace {

using PointsIn = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using PoseIn = nb::ndarray<const double, nb::shape<4, 4>, nb::c_contig, nb::device::cpu>;
using PosesIn = nb::ndarray<const double, nb::shape<-1, 4, 4>, nb::c_contig, nb::device::cpu>;
using StreamsIn = nb::ndarray<const std::uint64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using MatIn = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;

// Every value of a Metric, once: the class's attributes, its dict and the per-pose columns.
const std::pair<const char*, double Metric::*> kMetricValues[] = {
    {"sigma1", &Metric::sigma1},
    {"xi", &Metric::xi},
    {"q_min", &Metric::q_min},
    {"q_n", &Metric::q_n},
    {"q_max", &Metric::q_max},
    {"zhang", &Metric::zhang},
    {"condition_number", &Metric::condition_number},
    {"cov_trace", &Metric::cov_trace},
    {"step_norm", &Metric::step_norm},
    {"residual_norm", &Metric::residual_norm},
    {"scaled_cov_trace", &Metric::scaled_cov_trace},
};

nb::list least_observable(const Metric& metric);

nb::dict metric_dict(const Metric& metric) {
  nb::dict d;
  d["m"] = metric.m;
  d["n"] = metric.n;
  d["degenerate"] = metric.degenerate;
  for (const auto& [name, value] : kMetricValues) d[name] = metric.*value;
  d["least_observable"] = least_observable(metric);
  return d;
}

nb::list least_observable(const Metric& metric) {
  nb::list out;
  for (int i = 0; i < metric.n; ++i) out.append(metric.least_observable[static_cast<std::size_t>(i)]);
  return out;
}

// A scan's explicit observations as arrays: A (m x dof), b (m), points and sensor_points of
// the scan's hits, row_hit (row -> hit).
nb::dict observations_dict(PoseObservations& o, int dof_) {
  const std::size_t rows = static_cast<std::size_t>(o.observations.b.size());
  const std::size_t dof = static_cast<std::size_t>(dof_);
  std::vector<double> a(rows * dof);
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < dof; ++c) a[r * dof + c] = o.observations.a(r, c);
  nb::dict out;
  out["A"] = to_numpy(std::move(a), {rows, dof});
  out["b"] = to_numpy(std::vector<double>(o.observations.b.data(), o.observations.b.data() + rows), {rows});
  out["points"] = points_to_numpy(o.scan.world_points);
  out["sensor_points"] = points_to_numpy(o.scan.sensor_points);
  out["row_hit"] = to_numpy(std::move(o.observations.hit), {rows});
  return out;
}

// Columns (float64, `shape`) of metrics[i]: a SOLM chunk is thousands of poses, so no list of objects.
nb::dict metric_columns(const std::vector<Metric>& metrics, std::initializer_list<std::size_t> shape) {
  auto column = [&](auto get) {
    std::vector<double> v(metrics.size());
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<double>(get(metrics[i]));
    return to_numpy(std::move(v), shape);
  };
  nb::dict out;
  for (const auto& [name, value] : kMetricValues) out[name] = column([v = value](const Metric& x) { return x.*v; });
  out["m"] = column([](const Metric& x) { return x.m; });
  out["degenerate"] = column([](const Metric& x) { return x.degenerate ? 1.0 : 0.0; });
  return out;
}

std::vector<Pose> poses_from(PosesIn poses) {
  std::vector<Pose> out(poses.shape(0));
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = pose_from_matrix(poses.data() + 16 * i);
  return out;
}

std::vector<std::uint64_t> streams_from(StreamsIn streams, std::size_t expected) {
  if (streams.shape(0) != expected) throw std::invalid_argument("streams must hold one value per pose");
  return {streams.data(), streams.data() + expected};
}

}  // namespace

void bind_metric(nb::module_& m) {
  nb::enum_<Association>(m, "Association", "How a hit is associated with a map plane.")
      .value("surfel", Association::Surfel, "The precomputed plane of the map point the ray hit (faster).")
      .value("knn", Association::Knn, "FAST-LIO: the k nearest map points of the hit and their plane.");

  nb::class_<MetricWeights>(m, "MetricWeights", "q = sqrt(w1 lambda + w2) / sigma1, w2 = 1 - w1.")
      .def(nb::init<>())
      .def_rw("w1", &MetricWeights::w1)
      .def_prop_ro("w2", &MetricWeights::w2);

  nb::class_<EvalParams>(m, "EvalParams", "One pose's evaluation: scan, association and metric (the defaults).")
      .def(nb::init<>())
      .def_rw("scan", &EvalParams::scan)
      .def_rw("dof", &EvalParams::dof, "6 (SE(3)) or 3 (x, y, yaw).")
      .def_rw("association", &EvalParams::association)
      .def_rw("weights", &EvalParams::weights)
      .def_rw("ray_weight", &EvalParams::ray_weight,
              "Each ray stands for this many rays of the full pattern (thinned SOLM builds), >= 1.");

  auto metric = nb::class_<Metric>(m, "Metric", "The LF-3PM metric and the classic baselines of one pose.")
                    .def_ro("m", &Metric::m, "Observation rows.")
                    .def_ro("n", &Metric::n, "State dimension.")
                    .def_ro("degenerate", &Metric::degenerate)
                    .def("as_dict", &metric_dict, "Every value in a dict.");
  for (const auto& [name, value] : kMetricValues) metric.def_ro(name, value);
  metric.def_prop_ro("least_observable", &least_observable,
                     "Unit eigenvector of A^T A's smallest eigenvalue (n entries; largest entry positive).");

  nb::class_<PoseEvaluation>(m, "PoseEvaluation", "The metric at one pose with its ray and hit counts.")
      .def_ro("metric", &PoseEvaluation::metric)
      .def_ro("rays", &PoseEvaluation::rays, "Sensor rays cast.")
      .def_ro("hits", &PoseEvaluation::hits, "Rays with a return (after scan downsampling).");

  m.def(
      "evaluate",
      [](const MapIndex& map, PoseIn pose, PointsIn dirs, const EvalParams& params) {
        const Pose ps = pose_from_matrix(pose.data());
        nb::gil_scoped_release release;
        return evaluate_pose(map, ps, dirs.data(), dirs.shape(0), params);
      },
      "map"_a, "pose"_a, "directions"_a, "params"_a,
      "Scan, associate and compute the metric at one 4x4 sensor-to-world pose.");

  m.def(
      "evaluate_with_observations",
      [](const MapIndex& map, PoseIn pose, PointsIn dirs, const EvalParams& params) {
        const Pose ps = pose_from_matrix(pose.data());
        PoseObservations o;
        PoseEvaluation evaluation;
        {
          nb::gil_scoped_release release;
          evaluation = evaluate_pose(map, ps, dirs.data(), dirs.shape(0), params, &o);
        }
        return nb::make_tuple(evaluation, observations_dict(o, params.dof));
      },
      "map"_a, "pose"_a, "directions"_a, "params"_a,
      "evaluate() and the explicit observations of the same scan: (PoseEvaluation, dict of A (m x dof), "
      "b (m), points and sensor_points of the scan's hits, row_hit (row -> hit)).");

  m.def(
      "evaluate_points",
      [](const MapIndex& map, PoseIn pose, PointsIn points, const EvalParams& params, bool with_observations) {
        const Pose ps = pose_from_matrix(pose.data());
        PoseObservations o;
        PoseEvaluation evaluation;
        {
          nb::gil_scoped_release release;
          evaluation =
              evaluate_points(map, ps, points.data(), points.shape(0), params, with_observations ? &o : nullptr);
        }
        if (!with_observations) return nb::make_tuple(evaluation, nb::none());
        return nb::make_tuple(evaluation, observations_dict(o, params.dof));
      },
      "map"_a, "pose"_a, "points"_a, "params"_a, "observations"_a = false,
      "The metric of a recorded scan: sensor-frame points (N x 3) at a 4x4 sensor-to-world pose, "
      "downsampled (params.scan.scan_voxel) and evaluated as a simulated scan's hits are (k-NN "
      "association): (PoseEvaluation, the observations dict as evaluate_with_observations' or None).");

  m.def(
      "evaluate_many",
      [](const MapIndex& map, PosesIn poses, StreamsIn streams, PointsIn dirs, const EvalParams& params) {
        const std::vector<Pose> ps = poses_from(poses);
        const std::vector<std::uint64_t> st = streams_from(streams, ps.size());
        std::vector<PoseEvaluation> res;
        {
          nb::gil_scoped_release release;
          res = evaluate_poses(map, ps, st, dirs.data(), dirs.shape(0), params);
        }
        std::vector<Metric> metrics(res.size());
        std::vector<double> hits(res.size());
        for (std::size_t i = 0; i < res.size(); ++i) metrics[i] = res[i].metric, hits[i] = double(res[i].hits);
        nb::dict out = metric_columns(metrics, {res.size()});
        out["hits"] = to_numpy(std::move(hits));
        return out;
      },
      "map"_a, "poses"_a, "streams"_a, "directions"_a, "params"_a,
      "evaluate() at many 4x4 poses in parallel (params.scan.threads); pose i uses noise stream "
      "streams[i]. Returns a dict of per-pose float64 columns: every Metric value and hits.");

  m.def(
      "evaluate_yaw_sectors",
      [](const MapIndex& map, PointsIn positions, StreamsIn streams, PointsIn sector_rays, int bins, int half_width,
         const EvalParams& params) {
        const std::size_t np = positions.shape(0);
        const std::vector<std::uint64_t> st = streams_from(streams, np);
        std::vector<Eigen::Vector3d> pos(np);
        for (std::size_t i = 0; i < np; ++i) pos[i] = Eigen::Vector3d(positions.data() + 3 * i);
        std::vector<Metric> res;
        {
          nb::gil_scoped_release release;
          res = evaluate_yaw_sectors(map, pos, st, sector_rays.data(), sector_rays.shape(0), bins, half_width, params);
        }
        return metric_columns(res, {np, static_cast<std::size_t>(bins)});
      },
      "map"_a, "positions"_a, "streams"_a, "sector_rays"_a, "bins"_a, "half_width"_a, "params"_a,
      "SE(2) metric at every yaw bin from one scan per yaw sector (sums of sector Grams). "
      "Returns per-position, per-bin float64 columns of every Metric value.");

  m.def(
      "metric_from_gram",
      [](MatIn gram, std::int64_t rows, const MetricWeights& weights) {
        const std::size_t k = gram.shape(0);
        if (gram.shape(1) != k) throw std::invalid_argument("the Gram must be square");
        Eigen::MatrixXd g(k, k);
        for (std::size_t i = 0; i < k; ++i)
          for (std::size_t j = 0; j < k; ++j) g(i, j) = gram(i, j);
        return metric_from_gram(g, rows, weights);
      },
      "gram"_a, "m"_a, "weights"_a = MetricWeights(), "Metric from the Gram [A b]^T [A b] of m rows (4x4 or 7x7).");

  m.def(
      "gram",
      [](MatIn a, nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu> b) {
        const std::size_t rows = a.shape(0), n = a.shape(1);
        if ((n != 3 && n != 6) || b.shape(0) != rows)
          throw std::invalid_argument("A must be m x 3 or m x 6, b of length m");
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
