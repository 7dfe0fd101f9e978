"""Perception-aware planning on a SOLM.

- Front end: :mod:`~lf3pm.planner.esdf` (signed distance field),
  :mod:`~lf3pm.planner.cost_map` (perception cost layer),
  :mod:`~lf3pm.planner.graph_search` (A* / Dijkstra).
- Back end: :class:`Robot` (omni, diff, car and their limits), :class:`GridField`
  (a cost map or ESDF on a regular grid), :func:`optimize_trajectory` (MINCO +
  L-BFGS with penalties; no PHR loop: docs/planner_backend.md says why) giving a
  :class:`Trajectory`.
- Both: :class:`Planner` (:mod:`~lf3pm.planner.plan`), used by ``lf3pm plan``.
"""

from importlib import import_module

# Imported lazily, as lf3pm's top level is: lf3pm.config reads Robot from
# lf3pm.planner.robots without loading the planner (which reads the config).
_LAZY = {
    "GridField": "lf3pm.planner.grid_field",
    "OptimizeResult": "lf3pm.planner.trajectory_optimizer",
    "make_problem": "lf3pm.planner.trajectory_optimizer",
    "optimize_trajectory": "lf3pm.planner.trajectory_optimizer",
    "Plan": "lf3pm.planner.plan",
    "Planner": "lf3pm.planner.plan",
    "Robot": "lf3pm.planner.robots",
    "Trajectory": "lf3pm.planner.trajectory",
}
__all__ = sorted(_LAZY)


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module 'lf3pm.planner' has no attribute {name!r}")
    return getattr(import_module(_LAZY[name]), name)
