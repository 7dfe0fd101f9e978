"""The planner's front end: a least-cost grid path through a SOLM.

A* over the SOLM's cells (r2: one layer; se2: periodic yaw bins), in the C++
core (cpp/lf3pm/planner/graph_search.hpp, which states the moves and the heuristic).
Edge cost between neighbouring states a, b:

    (l + rho * |dk|) * (1 + weight * (c_a + c_b) / 2)

l: x-y length in metres (res or res * sqrt 2); |dk|: yaw steps (0 or 1);
rho = turn_radius * 2 pi / yaw_bins: the arc a point ``turn_radius`` metres
from the rotation axis travels in one yaw step; c: the cost layer
(:mod:`lf3pm.planner.cost_map`); weight: lambda. ``heuristic=False`` is
Dijkstra (the paper's breadth-first search), with the same optimal cost.
A*'s heuristic (se2): the exact cost-to-go of an x-y relaxation (each cell
costing its cheapest yaw bin), from a lazy backward Dijkstra, plus the least
cost of the remaining yaw steps; r2: the octile distance times the least cost
of a metre.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from lf3pm import _core, libm
from lf3pm.config import DEFAULTS, core_struct
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Grid
from lf3pm.planner.cost_map import CostLayer
from lf3pm.planner.esdf import Esdf
from lf3pm.planner.poses import cell_on_grid, format_pose


@dataclass(frozen=True)
class GraphPath:
    """A grid path from start to goal.

    ``cells``: (K, 3) int64 (ix, iy, yaw bin; 0 for r2); ``poses``: (K, 3) x, y,
    yaw at the cell centres (se2: bin centres, unwrapped along the path; r2:
    direction of travel, the start's and goal's yaw at the ends); ``length``:
    x-y length in metres; ``cost``: the path's cost; ``expanded``: states closed;
    ``heap_peak``: largest open list; ``relaxed_expanded``: x-y cells closed by
    the se2 heuristic's backward pass (0 for r2 and Dijkstra); ``time``:
    search seconds, the backward pass included.
    """

    cells: np.ndarray
    poses: np.ndarray
    length: float
    cost: float
    expanded: int
    heap_peak: int
    relaxed_expanded: int
    time: float


def search_path(
    cost,
    traversable,
    grid: Grid | Esdf,
    start,
    goal,
    *,
    weight: float = 1.0,
    heuristic: bool = True,
    r_safe: float = 0.0,
    turn_radius: float = DEFAULTS.guidance.turn_radius,
    turn_while_moving: bool = True,
) -> GraphPath:
    """Least-cost path from ``start`` to ``goal`` (x, y, yaw), snapped to their cells.

    ``cost``: a :class:`CostLayer` (its ``filled`` array is used) or an array of
    shape (ny, nx) (r2) or (yaw_bins, ny, nx) (se2). ``traversable``: a bool
    array of shape (ny, nx) or the cost's shape, or an :class:`Esdf` whose
    cells at least ``r_safe`` metres from blocked ones are traversable (errors
    then say why a start or goal is blocked). ``grid``: the cells' :class:`Grid` (a
    SolmGrid), or an :class:`Esdf` on them. ``weight``: lambda.
    """
    values = cost.filled if isinstance(cost, CostLayer) else np.asarray(cost, dtype=np.float64)
    g = grid.grid if isinstance(grid, Esdf) else grid
    if not isinstance(g, Grid):
        raise Lf3pmError(f"search_path needs the cells' lf3pm.grid.Grid, got {type(grid).__name__}")
    nx, ny, res = int(g.nx), int(g.ny), float(g.res)
    if values.ndim == 2:
        values = values[None]
    if values.ndim != 3 or values.shape[1:] != (ny, nx):
        raise Lf3pmError(f"cost shape {values.shape} does not match the grid ({ny}, {nx})")
    layers = values.shape[0]
    esdf = traversable if isinstance(traversable, Esdf) else None
    mask = esdf.traversable(r_safe) if esdf is not None else np.asarray(traversable, dtype=bool)
    if mask.shape not in ((ny, nx), values.shape, (1, ny, nx)):
        raise Lf3pmError(f"traversable shape {mask.shape} does not match the cost {values.shape}")
    mask = np.broadcast_to(mask.reshape((-1, ny, nx)), values.shape)
    if not (weight >= 0 and math.isfinite(weight)):
        raise Lf3pmError(f"weight must be finite and >= 0, got {weight}")
    if not (turn_radius >= 0 and math.isfinite(turn_radius)):
        raise Lf3pmError(f"turn radius must be finite and >= 0, got {turn_radius}")
    bad = mask & ~(np.isfinite(values) & (values >= 0))
    if bad.any():
        k, iy, ix = np.argwhere(bad)[0]
        raise Lf3pmError(
            f"cost must be finite and >= 0 on traversable cells; cell ({ix}, {iy}, bin {k}) holds {values[k, iy, ix]}"
        )

    step = 2 * math.pi / layers
    ends = [_locate(name, pose, g, layers, step) for name, pose in (("start", start), ("goal", goal))]
    for (name, pose), (ix, iy, k) in zip((("start", start), ("goal", goal)), ends):
        if not mask[k, iy, ix]:
            reason = esdf.blocked_reason(ix, iy, r_safe) if esdf is not None else None
            raise Lf3pmError(
                f"{name} {format_pose(pose)} is "
                + (reason or "not traversable (an obstacle, unknown ground, or closer than r_safe to one)")
            )
        # The plan ends on the exact pose, not on its cell's centre: it must be clear too.
        if esdf is not None and (clear := float(esdf.distance(pose[0], pose[1])[0])) < r_safe:
            raise Lf3pmError(f"{name} {format_pose(pose)} is {esdf.clearance_reason(clear, r_safe)}")
    # The core indexes states (y * nx + x) * layers + k (yaw innermost, for locality).
    flat_cost = np.ascontiguousarray(np.moveaxis(values, 0, -1)).ravel()
    flat_mask = np.ascontiguousarray(np.moveaxis(mask, 0, -1), dtype=np.uint8).ravel()
    index = [(iy * nx + ix) * layers + k for ix, iy, k in ends]
    t0 = time.perf_counter()
    params = core_struct(
        _core.SearchParams(),
        weight=float(weight),
        turn_length=float(turn_radius) * step,
        turn_while_moving=bool(turn_while_moving),
        heuristic=bool(heuristic),
    )
    out = _core.grid_search(flat_cost, flat_mask, nx, ny, layers, res, index[0], index[1], params)
    elapsed = time.perf_counter() - t0
    if not out["found"]:
        raise Lf3pmError(
            f"goal {format_pose(goal)} is unreachable from start {format_pose(start)}: no traversable path joins them"
        )
    path = np.asarray(out["path"], dtype=np.int64)
    cell, k = np.divmod(path, layers)
    iy, ix = np.divmod(cell, nx)
    cells = np.stack([ix, iy, k], axis=1)
    x, y = g.centre(ix, iy)
    return GraphPath(
        cells,
        np.stack([x, y, _yaws(x, y, k, step, layers, start, goal)], axis=1),
        float(np.hypot(np.diff(x), np.diff(y)).sum()),
        float(out["cost"]),
        int(out["expanded"]),
        int(out["heap_peak"]),
        int(out["relaxed_expanded"]),
        elapsed,
    )


def _locate(name, pose, g, layers, step):
    """(ix, iy, yaw bin) of a pose, or a one-line error when it is off the grid."""
    pose = tuple(float(v) for v in pose)
    if len(pose) != 3 or not all(math.isfinite(v) for v in pose):
        raise Lf3pmError(f"{name} must be three finite numbers x, y, yaw, got {pose}")
    x, y, yaw = pose
    ix, iy = cell_on_grid(g, name, pose)
    return ix, iy, round(yaw / step) % layers


def _yaws(x, y, k, step, layers, start, goal):
    """Yaw per pose: se2 bin centres unwrapped and shifted by whole turns to lie
    near the start's yaw; r2 direction of travel with the start's and goal's yaw
    at the ends."""
    if layers > 1:
        yaw = np.unwrap(k * step)
        return yaw + 2 * math.pi * round((float(start[2]) - yaw[0]) / (2 * math.pi))
    yaw = np.empty(len(x))
    if len(x) > 1:
        yaw[:-1] = libm.atan2(np.diff(y), np.diff(x))
    yaw[0], yaw[-1] = float(start[2]), float(goal[2])
    return yaw
