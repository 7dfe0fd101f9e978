"""The flight planner's front end on an r3yaw SOLM (issue 43, item 3): a 3-D A* over the
SOLM's cells (26-connected, cpp/lf3pm/planner/volume_search.hpp) on length plus the
guidance cost at each cell's best yaw, then the yaw along that path by dynamic
programming over the yaw bins, as fast as the quadrotor may turn.

Given the map's ESDF (lf3pm.planner.flight_plan.flight_esdf), a move is also allowed only
where its segment between the cell centres keeps ``move_clearance`` from the map's points
(sampled every ESDF voxel or finer): a thin wall between two free cell centres (the corner
of a room, 1 m cells) is in neither cell.

Costs as the ground planner's (lf3pm.planner.cost_map): the guidance channel over its
median, to the guidance section's power, capped; a move of length l between cells of costs
c_a, c_b costs l (1 + weight (c_a + c_b) / 2), each cell at its least cost over yaw.

Yaw: along the path's n cells, bins b_0..b_{n-1} minimising
  sum_i l_i weight (c_i(b_i) + c_{i+1}(b_{i+1})) / 2 + turn_radius |b_{i+1} - b_i|_cyclic step
with |b_{i+1} - b_i|_cyclic step <= omega_max l_i / vmax: the body turns no faster than its
body-rate limit allows at full speed (a level body's yaw rate is its body rate). The start's
bin is the one nearest its yaw, the goal's the one nearest a given goal yaw (else free).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lf3pm import _core
from lf3pm.config import DEFAULTS, GuidanceConfig, QuadrotorConfig
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Space
from lf3pm.planner.cost_map import cost_from_values


@dataclass(frozen=True)
class FlightPath:
    """A front-end flight path: ``positions`` (n, 3) (cell centres between the exact start
    and goal), ``yaws`` (n) (bin centres between the start's and a given goal's yaw),
    ``cells`` (n, 3) as (iz, iy, ix), the search's ``cost``, its ``length`` (m) and the
    cells it ``expanded``."""

    positions: np.ndarray
    yaws: np.ndarray
    cells: np.ndarray
    cost: float
    length: float
    expanded: int


def yaw_profile(
    costs, lengths, step: float, start_bin: int, goal_bin: int | None, max_turns, turn: float, weight: float
):
    """The yaw bins along a path by dynamic programming (module docstring): ``costs`` (n,
    bins; +inf where a bin was not evaluated), ``lengths`` (n - 1) of the moves, ``step``
    the bin width (rad), ``max_turns`` (n - 1) the most bins each move may turn, ``turn``
    the cost per radian of turn. Returns the bins (n), or None when no turn-limited yaw
    reaches the goal's bin."""
    costs = np.asarray(costs, dtype=np.float64)
    n, bins = costs.shape
    total = np.full(bins, np.inf)
    total[start_bin] = 0.0
    back = np.zeros((n, bins), dtype=np.int64)
    offsets = np.arange(bins)
    for i in range(n - 1):
        reach = int(max_turns[i])
        best = np.full(bins, np.inf)
        for d in range(-min(reach, bins // 2), min(reach, bins // 2) + 1):
            source = (offsets - d) % bins
            step_cost = lengths[i] * weight * 0.5 * (costs[i, source] + costs[i + 1]) + turn * abs(d) * step
            candidate = total[source] + step_cost
            better = candidate < best
            best[better] = candidate[better]
            back[i + 1, better] = source[better]
        total = best
    if goal_bin is not None:
        total = np.where(offsets == goal_bin, total, np.inf)
    if not np.isfinite(total.min()):
        return None
    out = np.empty(n, dtype=np.int64)
    out[-1] = int(np.argmin(total))
    for i in range(n - 1, 0, -1):
        out[i - 1] = back[i, out[i]]
    return out


#: Samples along a move's segment for its clearance check (both ends included).
MOVE_SAMPLES = 9


def free_volume(solm) -> np.ndarray:
    """(nz, ny, nx) bool: the cells of an r3yaw SOLM evaluated at some yaw (no obstacle)."""
    g = solm.grid_spec
    return np.isfinite(solm.channel("q_n")).reshape(len(g.z_levels), g.yaw_bins, g.ny, g.nx).any(axis=1)


def level_spacing(g) -> float:
    """The spacing of an aerial grid's levels (its cell edge with one level)."""
    return float(np.diff(g.z_levels).mean()) if len(g.z_levels) > 1 else g.res


def clear_moves(solm, esdf, clearance: float) -> np.ndarray:
    """uint8 (cells * 26): whether each move's segment from a free cell's centre of the r3yaw
    ``solm`` keeps ``clearance`` on the ESDF, moves in the search's order (dz, dy, dx =
    -1..1, x fastest)."""
    g = solm.grid_spec
    traversable = free_volume(solm)
    dz = level_spacing(g)
    iz, iy, ix = np.nonzero(traversable)
    centres = np.column_stack([g.xs()[ix], g.ys()[iy], np.asarray(g.z_levels, dtype=np.float64)[iz]])
    out = np.zeros((traversable.size, 26), dtype=np.uint8)
    rows = np.ravel_multi_index((iz, iy, ix), traversable.shape)
    fractions = np.linspace(0.0, 1.0, MOVE_SAMPLES)
    moves = [(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1) if (a, b, c) != (0, 0, 0)]
    for m, (mz, my, mx) in enumerate(moves):
        step = np.array([mx * g.res, my * g.res, mz * dz])
        points = (centres[:, None, :] + fractions[None, :, None] * step).reshape(-1, 3)
        distance, _ = esdf.sample(np.ascontiguousarray(points), np.zeros(len(points)))
        out[rows, m] = (distance.reshape(len(centres), MOVE_SAMPLES) >= clearance).all(axis=1)
    return np.ascontiguousarray(out.ravel())


def plan_flight_path(
    solm,
    start,
    goal,
    *,
    guidance: GuidanceConfig = DEFAULTS.guidance,
    quadrotor: QuadrotorConfig = DEFAULTS.quadrotor,
    esdf=None,
    move_clearance: float | None = None,
    move_free: np.ndarray | None = None,
) -> FlightPath:
    """The front-end path on ``solm`` (an r3yaw Solm) from ``start`` (x, y, z, yaw) to
    ``goal`` (x, y, z[, yaw]) with the guidance section (metric, weight, power,
    turn_radius) and the quadrotor's limits (vmax, omega_max); ``esdf`` (a VolumeField,
    None: no check) and ``move_clearance`` (m; None: 0) for the moves' segments, or their flags
    ``move_free`` computed once (:func:`clear_moves`; a replanner's). A start or goal outside
    the grid, in an obstacle cell, or with no path between them is an Lf3pmError in one line."""
    g = solm.grid_spec
    if g.space is not Space.R3YAW:
        raise Lf3pmError(f"the flight planner needs an r3yaw SOLM (lf3pm solm build --space r3yaw), got {g.space}")
    start = np.asarray(start, dtype=np.float64)
    goal = np.asarray(goal, dtype=np.float64)
    if (
        start.shape != (4,)
        or goal.shape not in ((3,), (4,))
        or not (np.isfinite(start).all() and np.isfinite(goal).all())
    ):
        raise Lf3pmError("a flight starts at (x, y, z, yaw) and ends at (x, y, z) or (x, y, z, yaw), finite numbers")
    nz, bins = len(g.z_levels), g.yaw_bins
    degenerate = np.asarray(solm.channel("degenerate")).astype(bool)
    metric = guidance.metric
    values = np.zeros(g.shape) if metric == "none" else solm.channel(metric)
    layer = cost_from_values(values, metric, degenerate=degenerate, power=guidance.power)
    # Where the SOLM evaluated the pose (not an obstacle), whatever the guidance channel.
    evaluated = np.isfinite(solm.channel("q_n")).reshape(nz, bins, g.ny, g.nx)
    per_bin = np.where(evaluated, layer.cost.reshape(nz, bins, g.ny, g.nx), np.inf)
    traversable = evaluated.any(axis=1)  # free_volume, from the channel read once
    volume = np.where(traversable, np.min(per_bin, axis=1), 0.0)
    cells = []
    for name, point in (("start", start), ("goal", goal)):
        ix, iy = g.columns(point[0], point[1])
        k, _, _ = g.cell(point[0], point[1], point[2])
        iz = int(k) // bins
        inside = g.holds(ix, iy) and min(g.z_levels) - g.res <= point[2] <= max(g.z_levels) + g.res
        if not inside:
            raise Lf3pmError(f"the {name} {tuple(round(float(v), 3) for v in point[:3])} lies outside the SOLM's grid")
        if not traversable[iz, iy, ix]:
            raise Lf3pmError(f"the {name} {tuple(round(float(v), 3) for v in point[:3])} lies in an obstacle cell")
        cells.append((iz * g.ny + int(iy)) * g.nx + int(ix))
    dz = level_spacing(g)
    if move_free is None and esdf is not None:
        move_free = clear_moves(solm, esdf, move_clearance or 0.0)
    params = _core.SearchParams()
    params.weight = float(guidance.weight)
    result = _core.volume_search(
        np.ascontiguousarray(volume.ravel()),
        np.ascontiguousarray(traversable.ravel().astype(np.uint8)),
        g.nx,
        g.ny,
        nz,
        g.res,
        dz,
        cells[0],
        cells[1],
        params,
        move_free,
    )
    if not result["found"]:
        raise Lf3pmError("no flight path between the start and the goal through the SOLM's free cells")
    path = np.asarray(result["path"], dtype=np.int64)
    iz, rest = np.divmod(path, g.ny * g.nx)
    iy, ix = np.divmod(rest, g.nx)
    levels = np.asarray(g.z_levels, dtype=np.float64)
    positions = np.column_stack([g.xs()[ix], g.ys()[iy], levels[iz]])
    positions[0], positions[-1] = start[:3], goal[:3]
    lengths = np.linalg.norm(np.diff(positions, axis=0), axis=1)
    step = 2 * math.pi / bins
    costs = per_bin[iz, :, iy, ix]
    max_turns = np.floor(quadrotor.omega_max * lengths / quadrotor.vmax / step + 1e-9).astype(np.int64)
    start_bin = int(round((start[3] % (2 * math.pi)) / step)) % bins
    goal_bin = int(round((goal[3] % (2 * math.pi)) / step)) % bins if goal.shape == (4,) else None
    chosen = yaw_profile(costs, lengths, step, start_bin, goal_bin, max_turns, guidance.turn_radius, guidance.weight)
    if chosen is None:
        raise Lf3pmError(
            "no yaw along the path turns slowly enough for omega_max and reaches the goal's yaw; "
            "raise quadrotor.omega_max or leave the goal's yaw free"
        )
    yaws = np.unwrap(chosen * step)
    yaws += 2 * math.pi * round((start[3] - yaws[0]) / (2 * math.pi))
    yaws[0] = start[3]
    if goal.shape == (4,):
        yaws[-1] = yaws[-1] + math.remainder(goal[3] - yaws[-1], 2 * math.pi)
    return FlightPath(
        positions=positions,
        yaws=yaws,
        cells=np.column_stack([iz, iy, ix]),
        cost=float(result["cost"]),
        length=float(lengths.sum()),
        expanded=int(result["expanded"]),
    )
