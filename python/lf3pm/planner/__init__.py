"""Perception-aware planning on a SOLM: the front end and the plan.

- :mod:`~lf3pm.planner.esdf` (signed distance field), :mod:`~lf3pm.planner.cost_map`
  (perception cost layer), :mod:`~lf3pm.planner.graph_search` (A* / Dijkstra on the
  grid) and :mod:`~lf3pm.planner.hybrid_search` (forward Dubins primitives, cars),
  :mod:`~lf3pm.planner.shortcut` (the path's corners);
- :class:`Planner` (:mod:`~lf3pm.planner.plan`): front end, then the back end of
  :mod:`lf3pm.trajectory` (MINCO + L-BFGS), used by ``lf3pm plan``.
"""

from lf3pm.planner.plan import Plan, Planner

__all__ = ["Plan", "Planner"]
