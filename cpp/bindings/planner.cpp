// nanobind bindings of the planner kernels (graph search, car search, trajectory optimisation).
// Each kernel adds a `bind_<kernel>(m)` call here; the kernels live in cpp/lf3pm/.
#include <nanobind/nanobind.h>

namespace nb = nanobind;

void bind_graph_search(nb::module_& m);
void bind_hybrid_search(nb::module_& m);
void bind_trajectory(nb::module_& m);

void bind_planner(nb::module_& m) {
  bind_graph_search(m);
  bind_hybrid_search(m);
  bind_trajectory(m);
}
