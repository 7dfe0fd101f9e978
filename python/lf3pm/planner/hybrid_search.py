"""The planner's front end for cars: a forward-only Hybrid-A* search.

A grid path ignores heading and curvature, so a car whose start or goal yaw
points away from it would need a loop the back end's local optimiser cannot
find. This search (C++ core, cpp/lf3pm/planner/hybrid_search.hpp, which states the
moves, the analytic Dubins expansion and the heuristic) keeps continuous poses
and moves forwards only along arcs of the car's turning radius R and straights,
so its path leaves the start and reaches the goal exactly along their yaws.
Move cost: the grid front end's length * (1 + weight * c), integrated over
samples of the back end's cost field; every sample keeps ESDF >= ``clearance``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from lf3pm import _core
from lf3pm.config import core_struct
from lf3pm.errors import Lf3pmError
from lf3pm.grid_field import GridField
from lf3pm.planner.cost_map import CostLayer
from lf3pm.planner.esdf import Esdf
from lf3pm.planner.poses import as_pose, cell_on_grid, format_pose


@dataclass(frozen=True)
class HybridPath:
    """A car's forward path from start to goal.

    ``poses``: (N, 3) x, y, yaw sampled along it (yaw continuous, unwrapped from
    the start's; the first and last pose are the start and goal, the goal's yaw
    up to whole turns); ``segments``: (K, 2) signed curvature (1/m, + left) and
    length (m) of its arcs and straights from the start; ``length``: metres;
    ``cost``: sum of ds (1 + weight c); ``expanded``: states closed;
    ``analytic_tries``: Dubins paths to the goal traced; ``relaxed_cells``: x-y
    cells the heuristic's backward pass reached; ``time``: search seconds.
    """

    poses: np.ndarray
    segments: np.ndarray
    length: float
    cost: float
    expanded: int
    analytic_tries: int
    relaxed_cells: int
    time: float


def dubins_path(start, goal, radius: float) -> dict:
    """The shortest forward path of turning radius ``radius`` between two poses (no
    obstacles): a dict of length, word (e.g. ``LSR``), segments (3, 2) and the length
    of each of the six words (inf where one does not exist)."""
    _radius(radius)
    return _core.dubins_path(as_pose(start, "start"), as_pose(goal, "goal"), float(radius))


def sample_segments(start, segments, spacing: float = 0.05) -> np.ndarray:
    """Poses (N, 3) every ``spacing`` metres and at each segment's end along
    ``segments`` (K, 2: signed curvature, length) from ``start``."""
    if not (math.isfinite(spacing) and spacing > 0):
        raise Lf3pmError(f"sample spacing must be positive, got {spacing}")
    seg = np.ascontiguousarray(np.asarray(segments, dtype=np.float64).reshape(-1, 2))
    return _core.sample_segments(as_pose(start, "start"), seg, float(spacing))


#: The search's defaults (C++ HybridParams, written there once).
_DEFAULT = _core.HybridParams()


def search_car_path(
    cost,
    esdf: Esdf,
    start,
    goal,
    *,
    radius: float,
    weight: float = _DEFAULT.weight,
    clearance: float = _DEFAULT.clearance,
    yaw_bins: int = _DEFAULT.yaw_bins,
    step: float = _DEFAULT.step,
    sample_step: float = _DEFAULT.sample_step,
    spacing: float = 0.05,
    analytic_every: int = _DEFAULT.analytic_every,
    max_expansions: int = _DEFAULT.max_expansions,
    heuristic: bool = _DEFAULT.heuristic,
    heuristic_weight: float = _DEFAULT.heuristic_weight,
    esdf_field: GridField | None = None,
) -> HybridPath:
    """Least-cost forward path of a car of turning radius ``radius`` from ``start`` to
    ``goal`` (x, y, yaw), exactly.

    ``cost``: a :class:`CostLayer` (its ``filled`` array), a :class:`GridField` on the
    ESDF's grid, or None (length only). ``esdf``: the planner's :class:`Esdf`; every
    sample keeps ``esdf.distance >= clearance`` (``esdf_field``: its values as a
    GridField, if already built). ``weight``: lambda. ``yaw_bins``: yaw bins per cell
    of the closed set; ``step``: primitive length (0: sqrt 2 res); ``sample_step``:
    collision and cost sample spacing (0: res / 4); ``spacing``: of the returned poses;
    ``analytic_every``: expansions between tries of a Dubins path to the goal;
    ``heuristic=False``: uniform-cost search (tests); ``heuristic_weight`` epsilon >= 1:
    weighted A* (f = g + epsilon h), a path within epsilon of the best the search can
    find, far sooner on large maps; ``max_expansions``: give up after so many.
    """
    _radius(radius)
    start, goal = as_pose(start, "start"), as_pose(goal, "goal")
    if not (math.isfinite(weight) and weight >= 0):
        raise Lf3pmError(f"weight must be finite and >= 0, got {weight}")
    if not (math.isfinite(clearance)):
        raise Lf3pmError(f"clearance must be finite, got {clearance}")
    if not (isinstance(yaw_bins, (int, np.integer)) and yaw_bins >= 4):
        raise Lf3pmError(f"yaw_bins must be an integer >= 4, got {yaw_bins!r}")
    for name, value in (("step", step), ("sample_step", sample_step)):
        if not (math.isfinite(value) and value >= 0):
            raise Lf3pmError(f"{name} must be >= 0 (0: default), got {value}")
    if not (math.isfinite(spacing) and spacing > 0):
        raise Lf3pmError(f"spacing must be positive, got {spacing}")
    if not (math.isfinite(heuristic_weight) and heuristic_weight >= 1):
        raise Lf3pmError(f"heuristic_weight must be >= 1, got {heuristic_weight}")
    if not (isinstance(max_expansions, (int, np.integer)) and max_expansions >= 1):
        raise Lf3pmError(f"max_expansions must be an integer >= 1, got {max_expansions!r}")
    if not (isinstance(analytic_every, (int, np.integer)) and analytic_every >= 1):
        raise Lf3pmError(f"analytic_every must be an integer >= 1, got {analytic_every!r}")
    if esdf_field is None:
        esdf_field = esdf.grid_field()
    cost_field = _cost_field(cost, esdf)
    for name, pose in (("start", start), ("goal", goal)):
        _check_end(name, pose, esdf, esdf_field, clearance)
    t0 = time.perf_counter()
    params = core_struct(
        _core.HybridParams(),
        radius=float(radius),
        weight=float(weight),
        clearance=float(clearance),
        yaw_bins=int(yaw_bins),
        step=float(step),
        sample_step=float(sample_step),
        analytic_every=int(analytic_every),
        max_expansions=int(max_expansions),
        heuristic=bool(heuristic),
        heuristic_weight=float(heuristic_weight),
    )
    cells = esdf.cell_bounds
    out = _core.hybrid_search(
        esdf_field._core,
        None if cells is None else cells._core,
        None if cost_field is None else cost_field._core,
        start,
        goal,
        params,
    )
    elapsed = time.perf_counter() - t0
    if not out["found"]:
        raise Lf3pmError(
            f"no forward path of turning radius {radius:g} m from start {format_pose(start)} to goal "
            f"{format_pose(goal)} keeps {clearance:g} m"
            + (f" beyond the robot radius {esdf.body_radius:g} m" if esdf.body_radius else "")
            + f" from obstacles: {out['reason']}"
        )
    segments = np.asarray(out["segments"], dtype=np.float64).reshape(-1, 2)
    poses = sample_segments(start, segments, spacing)
    # Exact ends: the integration lands on the goal up to round-off.
    poses[-1, :2] = goal[:2]
    poses[-1, 2] = goal[2] + 2 * math.pi * round((poses[-1, 2] - goal[2]) / (2 * math.pi))
    return HybridPath(
        poses,
        segments,
        float(out["length"]),
        float(out["cost"]),
        int(out["expanded"]),
        int(out["analytic_tries"]),
        int(out["relaxed_cells"]),
        elapsed,
    )


def search_heuristic(
    cost,
    esdf: Esdf,
    poses,
    goal,
    *,
    radius: float,
    weight: float = _DEFAULT.weight,
    clearance: float = _DEFAULT.clearance,
    yaw_bins: int = _DEFAULT.yaw_bins,
) -> np.ndarray:
    """:func:`search_car_path`'s heuristic at each of ``poses`` (N, 3) (+inf: pruned), for tests."""
    _radius(radius)
    field = esdf.grid_field()
    cost_field = _cost_field(cost, esdf)
    q = np.ascontiguousarray(np.asarray(poses, dtype=np.float64).reshape(-1, 3))
    params = core_struct(
        _core.HybridParams(),
        radius=float(radius),
        weight=float(weight),
        clearance=float(clearance),
        yaw_bins=int(yaw_bins),
    )
    cells = esdf.cell_bounds
    return _core.hybrid_heuristic(
        field._core,
        None if cells is None else cells._core,
        None if cost_field is None else cost_field._core,
        q,
        as_pose(goal, "goal"),
        params,
    )


def _cost_field(cost, esdf: Esdf) -> GridField | None:
    if cost is None or isinstance(cost, GridField):
        field = cost
    elif isinstance(cost, CostLayer):
        field = None if cost.channel == "none" else GridField.on(esdf.grid, cost.filled)
    else:
        field = GridField.on(esdf.grid, np.asarray(cost, dtype=np.float64))
    if field is not None:
        if not field.grid.same_cells(esdf.grid):
            raise Lf3pmError(f"cost grid {field.values.shape} does not match the ESDF's ({esdf.ny}, {esdf.nx})")
        if np.any(field.values < 0):
            raise Lf3pmError("cost must be >= 0")
    return field


def _check_end(name: str, pose, esdf: Esdf, field: GridField, clearance: float) -> None:
    x, y = float(pose[0]), float(pose[1])
    ix, iy = cell_on_grid(esdf.grid, name, pose)
    d = float(field.sample(x, y)[0])
    if d < clearance:
        reason = esdf.blocked_reason(ix, iy) or esdf.clearance_reason(d, clearance)
        raise Lf3pmError(f"{name} {format_pose(pose)} is {reason}")


def _radius(radius) -> None:
    if not (isinstance(radius, (int, float, np.floating)) and math.isfinite(radius) and radius > 0):
        raise Lf3pmError(f"a car's turning radius must be a positive number, got {radius!r}")
