// nanobind module lf3pm._core.<level> (LF3PM_MODULE; one per instruction set, CMakeLists.txt):
// a thin layer over the C++ core, one binding file per stage (map, scan, metric, graph
// search, car search, trajectory, flight); no logic here. lf3pm._core loads the one the CPU runs.
#include <nanobind/nanobind.h>

#include <stdexcept>

namespace nb = nanobind;

void bind_map(nb::module_& m);
void bind_scan(nb::module_& m);
void bind_metric(nb::module_& m);
void bind_graph_search(nb::module_& m);
void bind_hybrid_search(nb::module_& m);
void bind_trajectory(nb::module_& m);
void bind_flight(nb::module_& m);

NB_MODULE(LF3PM_MODULE, m) {
  m.doc() = "lf3pm C++ core: map index, surfel ray casting, FAST-LIO observations, LF-3PM metric, planner";
  m.attr("arch") = LF3PM_ARCH;  // the -march it was built with
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
  bind_map(m);
  bind_scan(m);
  bind_metric(m);
  bind_graph_search(m);
  bind_hybrid_search(m);
  bind_trajectory(m);
  bind_flight(m);
}
