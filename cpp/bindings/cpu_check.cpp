// nanobind module lf3pm._core.cpu_check: which core levels this build has and which
// of them the CPU runs. Compiled for the compiler's default instruction set (never
// for a level), so that it loads on any CPU of the architecture.
#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <sstream>
#include <string>
#include <vector>

namespace nb = nanobind;
using namespace nb::literals;

namespace {

std::vector<std::string> built_levels() {
  std::vector<std::string> out;
  std::stringstream list(LF3PM_ARCH_LIST);
  for (std::string arch; std::getline(list, arch, ',');) out.push_back(arch);
  return out;
}

// True when the CPU runs code built with -march=`arch`. Only the x86-64
// micro-architecture levels are checked; any other value (native, generic, an ARM
// architecture) was chosen for this machine by whoever built it.
bool cpu_runs(const std::string& arch) {
#if defined(__x86_64__) || defined(_M_X64)
  __builtin_cpu_init();
#if defined(LF3PM_CPU_LEVEL_NAMES)
  if (arch == "x86-64-v2") return __builtin_cpu_supports("x86-64-v2");
  if (arch == "x86-64-v3") return __builtin_cpu_supports("x86-64-v3");
  if (arch == "x86-64-v4") return __builtin_cpu_supports("x86-64-v4");
#else  // compilers without the level names: the features each level adds
  const bool v2 =
      __builtin_cpu_supports("popcnt") && __builtin_cpu_supports("sse4.2") && __builtin_cpu_supports("ssse3");
  const bool v3 =
      v2 && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2");
  if (arch == "x86-64-v2") return v2;
  if (arch == "x86-64-v3") return v3;
  if (arch == "x86-64-v4")
    return v3 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
           __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq");
#endif
#endif
  (void)arch;
  return true;
}

}  // namespace

NB_MODULE(cpu_check, m) {
  m.doc() = "The core levels this build has (preferred first) and which of them this CPU runs";
  m.attr("levels") = built_levels();
  m.def("runs", &cpu_runs, "arch"_a, "True when this CPU runs code built with -march=ARCH.");
}
