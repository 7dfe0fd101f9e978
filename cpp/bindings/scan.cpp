// nanobind bindings of the scan stage (cpp/lf3pm/scan/): its parameters and the scan simulator.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/vector.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "bindings/numpy.hpp"
#include "lf3pm/scan/scan_simulator.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace lf3pm;
using lf3pm::bindings::points_to_numpy;
using lf3pm::bindings::pose_from_matrix;
using lf3pm::bindings::to_numpy;

namespace {

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

void bind_scan(nb::module_& m) {
  using PointsIn = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
  using PoseIn = nb::ndarray<const double, nb::shape<4, 4>, nb::c_contig, nb::device::cpu>;
  using PosesIn = nb::ndarray<const double, nb::shape<-1, 4, 4>, nb::c_contig, nb::device::cpu>;

  nb::class_<ReturnModel>(m, "ReturnModel", "Return probability over (range, |cos incidence|) bins; empty: all return.")
      .def(nb::init<>())
      .def(
          "__init__",
          [](ReturnModel* self, std::vector<double> range_edges, std::vector<double> cos_edges,
             std::vector<double> probability) {
            new (self) ReturnModel{std::move(range_edges), std::move(cos_edges), std::move(probability)};
            self->check();
          },
          "range_edges"_a, "cos_edges"_a, "probability"_a)
      .def_ro("range_edges", &ReturnModel::range_edges, "Range bin edges (m), ascending.")
      .def_ro("cos_edges", &ReturnModel::cos_edges, "|cos incidence| bin edges, ascending in [0, 1].")
      .def_ro("probability", &ReturnModel::probability, "(range bins) x (cosine bins), row-major.")
      .def("at", &ReturnModel::at, "range"_a, "cos"_a, "The probability of a return from such a hit.");

  nb::class_<ScanParams>(m, "ScanParams", "Scan simulation parameters (the defaults).")
      .def(nb::init<>())
      .def_rw("min_range", &ScanParams::min_range, "Nearer first hits give no return (they still block the ray), m.")
      .def_rw("max_range", &ScanParams::max_range, "m.")
      .def_rw("noise_sigma", &ScanParams::noise_sigma, "Gaussian range noise, 1 sigma (m).")
      .def_rw("seed", &ScanParams::seed, "Seed of the range noise.")
      .def_rw("stream", &ScanParams::stream, "Independent noise stream (per pose) under one seed.")
      .def_rw("scan_voxel", &ScanParams::scan_voxel, "Keep the first hit per voxel of this edge (m; 0 = off).")
      .def_rw("threads", &ScanParams::threads, "Worker threads (0 = all cores).")
      .def_rw("returns", &ScanParams::returns, "Which hits return (ReturnModel; empty: all).");

  m.def(
      "simulate_scan",
      [](const MapIndex& map, PoseIn pose, PointsIn dirs, const ScanParams& params) {
        const Pose ps = pose_from_matrix(pose.data());
        SimulatedScan scan;
        {
          nb::gil_scoped_release release;
          scan = simulate_scan(map, ps, dirs.data(), dirs.shape(0), params);
        }
        return scan_dict(std::move(scan));
      },
      "map"_a, "pose"_a, "directions"_a, "params"_a,
      "Simulated scan at a 4x4 sensor-to-world pose: dict of sensor_points, world_points, surfel, ray.");

  m.def(
      "simulate_moving_scan",
      [](const MapIndex& map, PosesIn ray_poses, PointsIn dirs, const ScanParams& params) {
        const std::size_t n = dirs.shape(0);
        if (ray_poses.shape(0) != n)
          throw std::invalid_argument("one pose per ray: got " + std::to_string(ray_poses.shape(0)) + " poses for " +
                                      std::to_string(n) + " rays");
        std::vector<Pose> poses(n);
        for (std::size_t k = 0; k < n; ++k) poses[k] = pose_from_matrix(ray_poses.data() + 16 * k);
        SimulatedScan scan;
        {
          nb::gil_scoped_release release;
          scan = simulate_scan(map, poses.data(), dirs.data(), n, params);
        }
        return scan_dict(std::move(scan));
      },
      "map"_a, "ray_poses"_a, "directions"_a, "params"_a,
      "Simulated scan of a moving sensor: ray k cast from the 4x4 sensor-to-world pose ray_poses[k] "
      "(K x 4 x 4, one per direction). Dict as simulate_scan's; sensor_points in each ray's own frame, "
      "noise per ray as simulate_scan's.");

  m.def(
      "scan_of_points",
      [](PoseIn pose, PointsIn points, const ScanParams& params) {
        const Pose ps = pose_from_matrix(pose.data());
        SimulatedScan scan;
        {
          nb::gil_scoped_release release;
          scan = scan_of_points(ps, points.data(), points.shape(0), params);
        }
        return scan_dict(std::move(scan));
      },
      "pose"_a, "points"_a, "params"_a,
      "A recorded scan (N x 3 sensor-frame points) as a scan's hits at a 4x4 sensor-to-world pose, "
      "downsampled by params.scan_voxel as simulated hits are: dict as simulate_scan's (surfel none, "
      "ray the point's index).");
}
