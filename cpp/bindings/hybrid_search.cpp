// nanobind bindings of the car front end (cpp/lf3pm/planner/hybrid_search.hpp, dubins.hpp).
#include "lf3pm/planner/hybrid_search.hpp"

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <vector>

#include "bindings/numpy.hpp"
#include "lf3pm/planner/dubins.hpp"
#include "lf3pm/planner/grid_field.hpp"

namespace nb = nanobind;
using namespace nb::literals;

namespace {

using Poses = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;

lf3pm::Pose2 pose(nb::handle h) {
  const auto t = nb::cast<std::vector<double>>(h);
  if (t.size() != 3) throw std::invalid_argument("a pose is three numbers x, y, yaw");
  return {t[0], t[1], t[2]};
}

using lf3pm::bindings::to_numpy;

std::vector<lf3pm::PathSegment> segments_from(
    nb::ndarray<const double, nb::shape<-1, 2>, nb::c_contig, nb::device::cpu> a) {
  std::vector<lf3pm::PathSegment> s(a.shape(0));
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = {a(i, 0), a(i, 1)};
  return s;
}

}  // namespace

void bind_hybrid_search(nb::module_& m) {
  using lf3pm::HybridParams;
  nb::class_<HybridParams>(m, "HybridParams", "Hybrid-A* car search parameters (the defaults).")
      .def(nb::init<>())
      .def_rw("radius", &HybridParams::radius, "R: the car's least turning radius (m), > 0.")
      .def_rw("weight", &HybridParams::weight, "lambda: perception cost against length.")
      .def_rw("clearance", &HybridParams::clearance, "Least ESDF value at every sample (m).")
      .def_rw("yaw_bins", &HybridParams::yaw_bins, "Closed set: yaw bins per x-y cell.")
      .def_rw("step", &HybridParams::step, "Primitive length (m); 0: sqrt 2 res.")
      .def_rw("sample_step", &HybridParams::sample_step, "Collision and cost sample spacing (m); 0: res / 4.")
      .def_rw("analytic_every", &HybridParams::analytic_every,
              "Try a Dubins path to the goal every this many expansions.")
      .def_rw("max_expansions", &HybridParams::max_expansions)
      .def_rw("heuristic", &HybridParams::heuristic, "False: h = 0 (uniform-cost search).")
      .def_rw("heuristic_weight", &HybridParams::heuristic_weight, "epsilon >= 1 of f = g + epsilon h.");

  m.def(
      "dubins_path",
      [](nb::handle from, nb::handle to, double radius) {
        if (!(radius > 0.0)) throw std::invalid_argument("the turning radius must be positive");
        const auto words = lf3pm::dubins_words(pose(from), pose(to), radius);
        const lf3pm::DubinsPath best = lf3pm::dubins_shortest(pose(from), pose(to), radius);
        std::vector<double> seg;
        for (const auto& s : best.segments) seg.insert(seg.end(), {s.curvature, s.length});
        nb::dict lengths;
        for (int w = 0; w < 6; ++w) lengths[lf3pm::dubins_word_names()[w]] = words[w].length;
        nb::dict out;
        out["length"] = best.length;
        out["word"] = lf3pm::dubins_word_names()[best.word];
        out["segments"] = to_numpy(std::move(seg), {3, 2});
        out["words"] = lengths;
        return out;
      },
      "start"_a, "goal"_a, "radius"_a,
      "Shortest forward path of turning radius `radius` between two poses (x, y, yaw). Returns a dict: length, word, "
      "segments (3 x 2: signed curvature, length), words (length of each of the six words; inf where none).");
  m.def(
      "sample_segments",
      [](nb::handle start, nb::ndarray<const double, nb::shape<-1, 2>, nb::c_contig, nb::device::cpu> segments,
         double spacing) {
        const auto poses = lf3pm::sample_segments(pose(start), segments_from(segments), spacing);
        std::vector<double> flat;
        for (const auto& p : poses) flat.insert(flat.end(), {p.x, p.y, p.yaw});
        return to_numpy(std::move(flat), {poses.size(), 3});
      },
      "start"_a, "segments"_a, "spacing"_a,
      "Poses (N x 3, yaw unwrapped) every `spacing` metres and at each segment's end along segments (K x 2: signed "
      "curvature, length) from `start`, integrated exactly.");
  m.def(
      "hybrid_search",
      [](const lf3pm::GridField& esdf, const lf3pm::GridField* cells, const lf3pm::GridField* cost, nb::handle start,
         nb::handle goal, const HybridParams& p) {
        const lf3pm::Pose2 a = pose(start), b = pose(goal);
        lf3pm::HybridResult r;
        {
          nb::gil_scoped_release release;
          r = lf3pm::hybrid_search(esdf, cells, cost, a, b, p);
        }
        std::vector<double> seg;
        for (const auto& s : r.segments) seg.insert(seg.end(), {s.curvature, s.length});
        const std::size_t k = r.segments.size();
        nb::dict out;
        out["found"] = r.found;
        out["reason"] = r.reason;
        out["segments"] = to_numpy(std::move(seg), {k, 2});
        out["length"] = r.length;
        out["cost"] = r.cost;
        out["expanded"] = r.expanded;
        out["analytic_tries"] = r.analytic_tries;
        out["relaxed_cells"] = r.relaxed_cells;
        return out;
      },
      "esdf"_a, "cells"_a.none(), "cost"_a.none(), "start"_a, "goal"_a, "params"_a,
      "Hybrid-A* forward search for a car (cpp/lf3pm/planner/hybrid_search.hpp) on GridField ESDF, the search's cells "
      "(a GridField bounding the ESDF per cell, or None: the ESDF's) and cost (or None). Returns "
      "a dict: found, reason, segments (K x 2: signed curvature, length, from the start), length, cost, expanded, "
      "analytic_tries, relaxed_cells.");
  m.def(
      "hybrid_heuristic",
      [](const lf3pm::GridField& esdf, const lf3pm::GridField* cells, const lf3pm::GridField* cost, Poses poses,
         nb::handle goal, const HybridParams& p) {
        std::vector<lf3pm::Pose2> q(poses.shape(0));
        for (std::size_t i = 0; i < q.size(); ++i) q[i] = {poses(i, 0), poses(i, 1), poses(i, 2)};
        auto h = lf3pm::hybrid_heuristic(esdf, cells, cost, q, pose(goal), p);
        return to_numpy(std::move(h));
      },
      "esdf"_a, "cells"_a.none(), "cost"_a.none(), "poses"_a, "goal"_a, "params"_a,
      "hybrid_search's heuristic at each pose (N x 3), for tests (+inf: pruned).");
}
