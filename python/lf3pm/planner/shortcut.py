"""Any-angle shortcutting of a grid path (the back end's initial guess).

The front end's path is a staircase of 45 and 90 degree corners; a spline through
it must brake at every corner and, for diff and car robots, turn on the spot or
swing wide of the path. Replacing runs of cells by straight segments (greedy line
of sight, as in Theta*) gives the optimiser an initial guess it can follow at speed.
A segment replaces a run only when it keeps ``clearance`` from obstacles at every
sample and costs no more than the run under the front end's own edge cost, so
shortcutting never trades localisability for length:

    integral of (1 + weight * c(x, y, yaw)) (ds + turn_radius |d yaw|)

(ds: x-y arc length; the turn term is the front end's rho * |dk| per yaw step,
planner/graph_search.py). The yaw along a path is what the trajectory will have:

- ``yaw="interpolate"`` (omni robots on an SE(2) SOLM): the front end chose a
  yaw per cell, and the back end starts from the kept waypoints' yaws,
  interpolated linearly between them (trajectory/trajectory_optimizer.py); a segment is costed
  at those interpolated yaws and the run at its cells' own;
- ``yaw="travel"`` (diff and car robots, and any robot on an R2 SOLM): the yaw is
  the direction of travel of each segment, and turns cost nothing extra.
"""

from __future__ import annotations

import numpy as np

from lf3pm import libm
from lf3pm.config import DEFAULTS
from lf3pm.errors import Lf3pmError
from lf3pm.grid_field import GridField

YAW_MODES = ("travel", "interpolate")


def shortcut_path(
    points,
    esdf: GridField,
    clearance: float,
    cost: GridField | None = None,
    weight: float = 0.0,
    step: float | None = None,
    *,
    yaw: str = "travel",
    turn_radius: float = DEFAULTS.guidance.turn_radius,
) -> np.ndarray:
    """Indices (M,) of the waypoints kept from the path ``points`` (K, 3: x, y, yaw
    unwrapped; K >= 2), first and last included.

    From each kept waypoint, the farthest later one reachable by a straight segment
    whose ESDF samples (every ``step``, default esdf.res / 4) are all >= ``clearance``
    and whose cost (module docstring; ``yaw`` says which yaws it is costed at) is at
    most the replaced run's.
    """
    if yaw not in YAW_MODES:
        raise Lf3pmError(f"shortcut yaw mode must be one of {', '.join(YAW_MODES)}, got {yaw!r}")
    pts = np.asarray(points, dtype=np.float64)
    if len(pts) <= 2:
        return np.arange(len(pts))
    step = esdf.res / 4 if step is None else step
    turn = turn_radius if yaw == "interpolate" else 0.0
    # Cumulative cost along the input path, so any run's cost is a difference.
    run = np.concatenate(
        [[0.0], np.cumsum([_segment_cost(a, b, cost, weight, step, yaw, turn) for a, b in zip(pts[:-1], pts[1:])])]
    )
    out, i = [0], 0
    while i < len(pts) - 1:
        j = i + 1
        for k in range(i + 2, len(pts)):
            if not _line_clear(pts[i], pts[k], esdf, clearance, step):
                break
            if _segment_cost(pts[i], pts[k], cost, weight, step, yaw, turn) <= run[k] - run[i] + 1e-9:
                j = k
        out.append(j)
        i = j
    return np.array(out)


def _samples(a, b, step):
    """Points every ``step`` (or closer) from a to b, both included: x, y and the
    linearly interpolated yaw."""
    n = max(2, int(np.ceil(np.hypot(*(b[:2] - a[:2])) / step)) + 1)
    t = np.linspace(0.0, 1.0, n)
    return a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])


def _line_clear(a, b, esdf: GridField, clearance: float, step: float) -> bool:
    x, y, _ = _samples(a, b, step)
    return bool(np.all(esdf.sample(x, y)[0] >= clearance))


def _segment_cost(a, b, cost: GridField | None, weight: float, step: float, yaw: str, turn: float) -> float:
    """(length + turn * |yaw change|) * (1 + weight * mean c) along the straight segment
    a -> b (trapezoid rule), c taken at the interpolated yaw or the direction of travel."""
    length = float(np.hypot(*(b[:2] - a[:2]))) + turn * abs(float(b[2] - a[2]))
    if cost is None or weight == 0.0 or length == 0.0:
        return length
    x, y, heading = _samples(a, b, step)
    if yaw == "travel":
        heading = libm.atan2(b[1] - a[1], b[0] - a[0])
    c = cost.sample(x, y, heading)[0]
    return length * (1.0 + weight * float(np.mean(0.5 * (c[1:] + c[:-1]))))
