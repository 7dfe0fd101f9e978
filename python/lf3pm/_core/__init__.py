"""The compiled core, for the CPU this process runs on.

CMake builds the core once per instruction set in ``LF3PM_ARCH`` (by default
x86-64-v3, AVX2 and FMA, then the portable x86-64 for older CPUs), each as a module
``lf3pm._core.<level>``; this package loads the first one the CPU runs and exposes
its names. Every level but ``native`` computes the same numbers to the last bit
(tests/test_builds.py), so which one loads changes the speed, never a result.
``LF3PM_CORE=<level>`` in the environment asks for one level by name.
"""

import os
from importlib import import_module

from lf3pm._core import cpu_check
from lf3pm.errors import CoreLevelError


def _module_name(arch: str) -> str:
    """The module CMake names for ``-march=arch`` (its C identifier: x86-64-v3 -> x86_64_v3)."""
    return "".join(c if c.isalnum() else "_" for c in arch)


def _choose_level() -> str:
    built = list(cpu_check.levels)
    asked = os.environ.get("LF3PM_CORE", "").strip()
    if asked:
        if asked not in built:
            raise CoreLevelError(
                f"LF3PM_CORE={asked}: this build has the core for {', '.join(built)} "
                "(rebuild with -Ccmake.define.LF3PM_ARCH=...; README, Supported CPUs)"
            )
        if not cpu_check.runs(asked):
            raise CoreLevelError(f"LF3PM_CORE={asked}: this CPU cannot run code built for {asked}")
        return asked
    for arch in built:
        if cpu_check.runs(arch):
            return arch
    raise CoreLevelError(
        f"this CPU runs none of the core's levels ({', '.join(built)}): rebuild with "
        "-Ccmake.define.LF3PM_ARCH=x86-64 (README, Supported CPUs)"
    )


#: The -march level of the core this process loaded.
ARCH = _choose_level()
_level = import_module(f"{__name__}.{_module_name(ARCH)}")
for _name, _value in vars(_level).items():
    if not _name.startswith("__"):
        globals()[_name] = _value
        if isinstance(_value, type):
            # Pickles name the class through this package, so that another process
            # (a cluster node with another CPU) unpickles it into its own level.
            _value.__module__ = __name__
