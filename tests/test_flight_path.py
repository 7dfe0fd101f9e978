"""The flight planner's front end (issue 43, item 3): the 26-connected volume A* against an
independent Dijkstra (scipy) on the same graph, its paths' validity, the turn-limited yaw
dynamic programme against brute force, and plans on an r3yaw SOLM."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

import lf3pm
from lf3pm import _core
from lf3pm.config import DEFAULTS
from lf3pm.errors import Lf3pmError
from lf3pm.planner.flight_path import plan_flight_path, yaw_profile
from lf3pm.scenes import build_scene
from lf3pm.solm import Solm, build_solm, make_grid

SHAPE = (4, 6, 7)  # nz, ny, nx
RES, DZ = 0.5, 0.8


def volume(seed):
    rng = np.random.default_rng(seed)
    cost = rng.uniform(0.0, 3.0, SHAPE)
    free = rng.uniform(size=SHAPE) > 0.25
    free[0, 0, 0] = free[-1, -1, -1] = True
    return cost, free


def edges(cost, free, weight):
    """Every move of the search's graph: (from, to, cost) with the same rules, in float64."""
    nz, ny, nx = SHAPE
    rows, cols, vals = [], [], []
    for z, y, x in itertools.product(range(nz), range(ny), range(nx)):
        if not free[z, y, x]:
            continue
        for dz, dy, dx in itertools.product((-1, 0, 1), repeat=3):
            if not (dx or dy or dz):
                continue
            Z, Y, X = z + dz, y + dy, x + dx
            if not (0 <= Z < nz and 0 <= Y < ny and 0 <= X < nx):
                continue
            box = free[min(z, Z) : max(z, Z) + 1, min(y, Y) : max(y, Y) + 1, min(x, X) : max(x, X) + 1]
            if not box.all():
                continue
            length = math.sqrt((dx * dx + dy * dy) * RES * RES + dz * dz * DZ * DZ)
            rows.append((z * ny + y) * nx + x)
            cols.append((Z * ny + Y) * nx + X)
            vals.append(length * (1 + weight * 0.5 * (cost[z, y, x] + cost[Z, Y, X])))
    n = nz * ny * nx
    return coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()


def search(cost, free, weight, heuristic=True, start=0, goal=None):
    params = _core.SearchParams()
    params.weight, params.heuristic = weight, heuristic
    nz, ny, nx = SHAPE
    goal = nz * ny * nx - 1 if goal is None else goal
    flat = np.ascontiguousarray(np.where(free, cost, 0.0).ravel())
    return _core.volume_search(
        flat, np.ascontiguousarray(free.ravel().astype(np.uint8)), nx, ny, nz, RES, DZ, start, goal, params
    )


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("weight", [0.0, 2.0])
def test_the_volume_search_finds_the_least_cost_path(seed, weight):
    cost, free = volume(seed)
    graph = edges(cost, free, weight)
    reference = dijkstra(graph, indices=0)[-1]
    got = search(cost, free, weight)
    if not np.isfinite(reference):
        assert not got["found"]
        return
    assert got["found"] and got["cost"] == pytest.approx(reference, rel=1e-12)
    assert search(cost, free, weight, heuristic=False)["cost"] == pytest.approx(reference, rel=1e-12)
    path = np.asarray(got["path"])
    assert path[0] == 0 and path[-1] == free.size - 1
    total = sum(graph[a, b] for a, b in zip(path[:-1], path[1:]))  # every step is an edge of the graph
    assert all(graph[a, b] > 0 for a, b in zip(path[:-1], path[1:]))
    assert total == pytest.approx(got["cost"], rel=1e-12)


def test_the_volume_search_refuses_bad_input_and_reports_no_path():
    cost, free = volume(0)
    free[:, 3, :] = False  # a wall across y
    assert not search(cost, free, 1.0)["found"]
    free[0, 0, 0] = False
    with pytest.raises(ValueError, match="start cell is not traversable"):
        search(cost, free, 1.0)
    with pytest.raises(ValueError, match="finite and >= 0"):
        bad = cost.copy()
        bad[1, 1, 1] = -1.0
        free[1, 1, 1] = free[0, 0, 0] = True
        search(bad, free, 1.0)


def test_the_yaw_profile_is_the_brute_force_optimum_under_the_turn_limit():
    rng = np.random.default_rng(3)
    n, bins = 6, 4
    step = 2 * math.pi / bins
    for trial in range(20):
        costs = rng.uniform(0, 2, (n, bins))
        costs[rng.uniform(size=(n, bins)) < 0.15] = np.inf
        lengths = rng.uniform(0.5, 1.5, n - 1)
        max_turns = rng.integers(0, 2, n - 1)
        goal = None if trial % 2 else int(rng.integers(bins))
        got = yaw_profile(costs, lengths, step, 0, goal, max_turns, 0.7, 2.0)
        best, best_seq = np.inf, None
        for seq in itertools.product(range(bins), repeat=n - 1):
            b = (0, *seq)
            if goal is not None and b[-1] != goal:
                continue
            turns = [min((b[i + 1] - b[i]) % bins, (b[i] - b[i + 1]) % bins) for i in range(n - 1)]
            if any(t > m for t, m in zip(turns, max_turns)):
                continue
            total = sum(
                lengths[i] * 2.0 * 0.5 * (costs[i, b[i]] + costs[i + 1, b[i + 1]]) + 0.7 * turns[i] * step
                for i in range(n - 1)
            )
            if total < best:
                best, best_seq = total, b
        if not np.isfinite(best):
            assert got is None
            continue
        turns = [min((got[i + 1] - got[i]) % bins, (got[i] - got[i + 1]) % bins) for i in range(n - 1)]
        total = sum(
            lengths[i] * 2.0 * 0.5 * (costs[i, got[i]] + costs[i + 1, got[i + 1]]) + 0.7 * turns[i] * step
            for i in range(n - 1)
        )
        assert total == pytest.approx(best, rel=1e-12), (got, best_seq)
        assert all(t <= m for t, m in zip(turns, max_turns))


@pytest.fixture(scope="module")
def flight_solm(tmp_path_factory):
    world = lf3pm.load_map(build_scene("boxes").points)
    grid = make_grid(world, "r3yaw", 1.0, bounds=(-4.0, -4.0, 4.0, 4.0), yaw_bins=8, z_levels=(1.0, 2.0, 3.0))
    path = tmp_path_factory.mktemp("flight") / "boxes.zarr"
    build_solm(world, "vlp16", grid, path, noise=0.0, mount="top", tile=4)
    return Solm.open(path)


def test_a_flight_path_on_an_r3yaw_solm_stays_in_free_cells_and_turns_within_the_limit(flight_solm):
    g = flight_solm.grid_spec
    free = np.isfinite(flight_solm.channel("q_n")).reshape(3, 8, g.ny, g.nx).any(axis=1)
    iz, iy, ix = np.argwhere(free)[[0, -1]].T
    start = (g.xs()[ix[0]], g.ys()[iy[0]], g.z_levels[iz[0]], 0.3)
    goal = (g.xs()[ix[1]], g.ys()[iy[1]], g.z_levels[iz[1]])
    path = plan_flight_path(flight_solm, start, goal)
    assert np.allclose(path.positions[0], start[:3]) and np.allclose(path.positions[-1], goal)
    assert path.yaws[0] == pytest.approx(0.3)
    assert free[tuple(path.cells.T)].all()
    steps = np.abs(np.diff(path.cells, axis=0))
    assert steps.max() <= 1 and (steps.sum(axis=1) > 0).all()
    # The yaw turns no faster than omega_max at full speed (bins, so to half a bin).
    q = DEFAULTS.quadrotor
    lengths = np.linalg.norm(np.diff(path.positions, axis=0), axis=1)
    turns = np.abs(np.diff(path.yaws))[1:]
    assert (turns <= q.omega_max * lengths[1:] / q.vmax + 1e-9).all()
    # Without guidance the path is no longer than the weighted one.
    unguided = plan_flight_path(
        flight_solm, start, goal, guidance=DEFAULTS.guidance.model_copy(update={"metric": "none"})
    )
    assert unguided.length <= path.length + 1e-9


def test_a_flight_plan_refuses_what_it_cannot_fly(flight_solm, tmp_path):
    with pytest.raises(Lf3pmError, match="outside the SOLM's grid"):
        plan_flight_path(flight_solm, (40.0, 0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    with pytest.raises(Lf3pmError, match=r"\(x, y, z, yaw\)"):
        plan_flight_path(flight_solm, (0.0, 0.0, 1.0), (0.0, 0.0, 1.0))
    world = lf3pm.load_map(build_scene("boxes").points)
    r2 = make_grid(world, "r2", 2.0, bounds=(-2.0, -2.0, 2.0, 2.0))
    build_solm(world, "vlp16", r2, tmp_path / "r2.zarr", noise=0.0)
    with pytest.raises(Lf3pmError, match="needs an r3yaw SOLM"):
        plan_flight_path(Solm.open(tmp_path / "r2.zarr"), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
