// nanobind bindings of the front ends' grid searches (cpp/lf3pm/planner/graph_search.hpp,
// volume_search.hpp).
#include "lf3pm/planner/graph_search.hpp"

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>

#include <optional>
#include <vector>

#include "bindings/numpy.hpp"
#include "lf3pm/planner/volume_search.hpp"

namespace nb = nanobind;
using namespace nb::literals;

namespace {

// A search's result as the dict both searches return.
nb::dict search_dict(lf3pm::SearchResult&& r) {
  nb::dict out;
  out["found"] = r.found;
  out["cost"] = r.cost;
  out["path"] = lf3pm::bindings::to_numpy(std::move(r.path));
  out["expanded"] = r.expanded;
  out["pushed"] = r.pushed;
  out["heap_peak"] = r.heap_peak;
  return out;
}

}  // namespace

void bind_graph_search(nb::module_& m) {
  nb::class_<lf3pm::SearchParams>(m, "SearchParams", "Grid search parameters (the defaults).")
      .def(nb::init<>())
      .def_rw("weight", &lf3pm::SearchParams::weight, "lambda: perception cost against length.")
      .def_rw("turn_length", &lf3pm::SearchParams::turn_length, "rho: metres of travel charged per yaw step.")
      .def_rw("turn_while_moving", &lf3pm::SearchParams::turn_while_moving,
              "Also x-y steps combined with one yaw step.")
      .def_rw("heuristic", &lf3pm::SearchParams::heuristic, "False: Dijkstra (A* with h = 0).");

  using Flat = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
  using Mask = nb::ndarray<const std::uint8_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
  m.def(
      "grid_search",
      [](Flat cost, Mask traversable, int nx, int ny, int layers, double res, std::uint32_t start, std::uint32_t goal,
         const lf3pm::SearchParams& params) {
        const std::size_t n = std::size_t(nx) * std::size_t(ny) * std::size_t(layers);
        if (cost.shape(0) != n || traversable.shape(0) != n)
          throw std::invalid_argument("cost and traversable need nx * ny * layers values");
        lf3pm::SearchGrid grid{nx, ny, layers, res};
        lf3pm::SearchResult r;
        {
          nb::gil_scoped_release release;
          r = lf3pm::grid_search(cost.data(), traversable.data(), grid, start, goal, params);
        }
        const auto relaxed = r.relaxed_expanded;
        nb::dict out = search_dict(std::move(r));
        out["relaxed_expanded"] = relaxed;
        return out;
      },
      "cost"_a.noconvert(), "traversable"_a.noconvert(), "nx"_a, "ny"_a, "layers"_a, "res"_a, "start"_a, "goal"_a,
      "params"_a = lf3pm::SearchParams(),
      "A* (heuristic=True) or Dijkstra over nx x ny x layers states (flat float64 cost, uint8 traversable, "
      "index (y * nx + x) * layers + k: yaw innermost; layers > 1 are periodic yaw bins). Returns a dict: found, cost, "
      "path "
      "(uint32 state indices), expanded, pushed, heap_peak, relaxed_expanded (cells the SE(2) heuristic's backward "
      "pass closed).");
  m.def(
      "volume_search",
      [](Flat cost, Mask traversable, int nx, int ny, int nz, double res, double dz, std::uint32_t start,
         std::uint32_t goal, const lf3pm::SearchParams& params, std::optional<Mask> move_free) {
        const std::size_t n = std::size_t(nx) * std::size_t(ny) * std::size_t(nz);
        if (cost.shape(0) != n || traversable.shape(0) != n)
          throw std::invalid_argument("cost and traversable need nx * ny * nz values");
        if (move_free && move_free->shape(0) != n * lf3pm::kVolumeMoves)
          throw std::invalid_argument("move_free needs 26 values per cell");
        const lf3pm::VolumeGrid grid{nx, ny, nz, res, dz};
        lf3pm::SearchResult r;
        {
          nb::gil_scoped_release release;
          r = lf3pm::volume_search(cost.data(), traversable.data(), grid, start, goal, params,
                                   move_free ? move_free->data() : nullptr);
        }
        return search_dict(std::move(r));
      },
      "cost"_a.noconvert(), "traversable"_a.noconvert(), "nx"_a, "ny"_a, "nz"_a, "res"_a, "dz"_a, "start"_a, "goal"_a,
      "params"_a = lf3pm::SearchParams(), "move_free"_a = nb::none(),
      "A* (heuristic=True) or Dijkstra over nx x ny x nz cells, 26-connected (flat float64 cost, uint8 traversable, "
      "index (z * ny + y) * nx + x; move_free: optional uint8, 26 per cell, moves in dz, dy, dx order). Returns a "
      "dict: found, cost, path (uint32 cell indices), expanded, pushed, heap_peak.");
  m.def(
      "search_heuristic",
      [](Flat cost, Mask traversable, int nx, int ny, int layers, double res, std::uint32_t goal,
         const lf3pm::SearchParams& params) {
        const std::size_t n = std::size_t(nx) * std::size_t(ny) * std::size_t(layers);
        if (cost.shape(0) != n || traversable.shape(0) != n)
          throw std::invalid_argument("cost and traversable need nx * ny * layers values");
        lf3pm::SearchGrid grid{nx, ny, layers, res};
        std::vector<double> h;
        {
          nb::gil_scoped_release release;
          h = lf3pm::search_heuristic(cost.data(), traversable.data(), grid, goal, params);
        }
        return lf3pm::bindings::to_numpy(std::move(h));
      },
      "cost"_a.noconvert(), "traversable"_a.noconvert(), "nx"_a, "ny"_a, "layers"_a, "res"_a, "goal"_a,
      "params"_a = lf3pm::SearchParams(),
      "grid_search's A* heuristic at every state (same layout and arguments; +inf where the goal is unreachable "
      "even in the x-y relaxation). For tests and inspection.");
}
