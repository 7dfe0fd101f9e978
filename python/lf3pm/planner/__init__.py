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

from lf3pm.planner.grid_field import GridField
from lf3pm.planner.plan import Plan, Planner
from lf3pm.planner.robots import Robot
from lf3pm.planner.trajectory import Trajectory
from lf3pm.planner.trajectory_optimizer import OptimizeResult, make_problem, optimize_trajectory

__all__ = ["GridField", "OptimizeResult", "Plan", "Planner", "Robot", "Trajectory", "make_problem",
           "optimize_trajectory"]
