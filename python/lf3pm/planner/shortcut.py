"""Any-angle shortcutting of an 8-connected grid path (the back end's initial guess).

The front end's path is a staircase of 45 and 90 degree corners; a spline through
it must brake at every corner and, for diff and car robots, turn on the spot or
swing wide of the path. Replacing runs of cells by straight segments (greedy line
of sight, as in Theta*) gives the optimiser an initial guess it can follow at speed.
A segment replaces a run only when it keeps ``clearance`` from obstacles at every
sample and costs no more than the run under the front end's own edge cost
length * (1 + weight * c), so shortcutting never trades localisability for length.
"""

from __future__ import annotations

import numpy as np

from lf3pm.planner.grid import GridField


def shortcut_path(points, esdf: GridField, clearance: float, cost: GridField | None = None,
                  weight: float = 0.0, step: float | None = None) -> np.ndarray:
    """Indices (M,) of the corners kept from the polyline ``points`` (K, >= 2), first and last included.

    From each corner, the farthest later point reachable by a straight segment whose
    ESDF samples (every ``step``, default esdf.res / 4) are all >= ``clearance`` and whose
    cost integral is at most the replaced run's.
    """
    pts = np.asarray(points, dtype=np.float64)[:, :2]
    if len(pts) <= 2:
        return np.arange(len(pts))
    step = esdf.res / 4 if step is None else step
    # Cumulative cost along the input path, so any run's cost is a difference.
    run = np.concatenate([[0.0], np.cumsum([_segment_cost(a, b, cost, weight, step)
                                            for a, b in zip(pts[:-1], pts[1:])])])
    out, i = [0], 0
    while i < len(pts) - 1:
        j = i + 1
        for k in range(i + 2, len(pts)):
            if not _line_clear(pts[i], pts[k], esdf, clearance, step):
                break
            if _segment_cost(pts[i], pts[k], cost, weight, step) <= run[k] - run[i] + 1e-9:
                j = k
        out.append(j)
        i = j
    return np.array(out)


def _samples(a, b, step):
    n = max(2, int(np.ceil(np.hypot(*(b - a)) / step)) + 1)
    t = np.linspace(0.0, 1.0, n)
    return a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])


def _line_clear(a, b, esdf: GridField, clearance: float, step: float) -> bool:
    x, y = _samples(a, b, step)
    return bool(np.all(esdf.sample(x, y)[0] >= clearance))


def _segment_cost(a, b, cost: GridField | None, weight: float, step: float) -> float:
    """length * (1 + weight * mean c) along the segment (trapezoid rule)."""
    length = float(np.hypot(*(b - a)))
    if cost is None or weight == 0.0 or length == 0.0:
        return length
    x, y = _samples(a, b, step)
    c = cost.sample(x, y, np.arctan2(b[1] - a[1], b[0] - a[0]))[0]
    return length * (1.0 + weight * float(np.mean(0.5 * (c[1:] + c[:-1]))))

