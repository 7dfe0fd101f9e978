"""lf3pm: LiDAR perception-aware planning (LF-3PM), open and fast.

Top-level API (docs/api.md; imported lazily so that light modules such as
:mod:`lf3pm.io` work without loading the compiled core):

- :func:`lf3pm.load_map` -- read a point-cloud map and precompute its index.
- :func:`lf3pm.evaluate` -- simulate a scan at a pose and compute the metric.
- :func:`lf3pm.get_sensor` / :func:`lf3pm.list_sensors` -- LiDAR models.
- :func:`lf3pm.make_grid`, :func:`lf3pm.build_solm`, :class:`lf3pm.Solm` -- build a
  Static Observation Loss Map over a grid (:class:`lf3pm.Grid`, its space a
  :class:`lf3pm.Space`), then open, read and query it.
- :class:`lf3pm.Planner`, :class:`lf3pm.Robot` -- plan trajectories on a SOLM.
- :func:`lf3pm.replay` -- replay a trajectory through localization, a LIO or an
  odometry on simulated scans and score it (:class:`lf3pm.ReplayResult`);
  :func:`lf3pm.replay_seeds` on consecutive seeds with the medians (``lf3pm replay``).
- :func:`lf3pm.build_scene` -- procedural test maps.
"""

from importlib import import_module

__version__ = "0.1.0"

_LAZY = {
    "Map": "lf3pm.map",
    "load_map": "lf3pm.map",
    "evaluate": "lf3pm.metric",
    "Evaluation": "lf3pm.metric",
    "get_sensor": "lf3pm.sensors",
    "list_sensors": "lf3pm.sensors",
    "Sensor": "lf3pm.sensors",
    "Solm": "lf3pm.solm",
    "SolmGrid": "lf3pm.solm",
    "Grid": "lf3pm.grid",
    "Space": "lf3pm.grid",
    "make_grid": "lf3pm.solm",
    "build_solm": "lf3pm.solm",
    "Planner": "lf3pm.planner.plan",
    "Plan": "lf3pm.planner.plan",
    "Robot": "lf3pm.trajectory.robots",
    "replay": "lf3pm.replays.replay",
    "replay_seeds": "lf3pm.replays.replay",
    "ReplayResult": "lf3pm.replays.replay_result",
    "build_scene": "lf3pm.scenes",
    "Lf3pmError": "lf3pm.errors",
}

__all__ = sorted(_LAZY) + ["__version__"]


def __getattr__(name):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'lf3pm' has no attribute {name!r}")
    return getattr(import_module(module), name)


def __dir__():
    return __all__
