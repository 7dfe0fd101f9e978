"""lf3pm: LiDAR perception-aware planning (LF-3PM), open and fast.

Top-level API (imported lazily so that light modules such as :mod:`lf3pm.io`
work without loading the compiled core):

- :func:`lf3pm.load_map` -- read a point-cloud map and precompute its index.
- :func:`lf3pm.evaluate` -- simulate a scan at a pose and compute the metric.
- :func:`lf3pm.get_sensor` / :func:`lf3pm.list_sensors` -- LiDAR models.
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
}

__all__ = sorted(_LAZY) + ["__version__"]


def __getattr__(name):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'lf3pm' has no attribute {name!r}")
    return getattr(import_module(module), name)
