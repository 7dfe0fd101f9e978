"""Planner front end: cost layer, and A* / Dijkstra against scipy's Dijkstra
on the same explicit graph; the A* heuristic against exact costs-to-go."""

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

import lf3pm
from lf3pm import _core
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Grid, Space
from lf3pm.planner.cost_map import cost_from_solm, cost_from_values
from lf3pm.planner.esdf import Esdf
from lf3pm.planner.graph_search import search_path
from lf3pm.scenes import build_scene
from lf3pm.solm import Solm, build_solm, make_grid


def explicit_graph(cost, trav, res, weight, turn_length, turn_while_moving):
    """The search graph written out edge by edge (independent of the C++ code):
    8-connected x-y moves without corner cutting, turns to the neighbouring
    periodic yaw bins, optionally combined with a move."""
    layers, ny, nx = cost.shape
    k, y, x = np.meshgrid(np.arange(layers), np.arange(ny), np.arange(nx), indexing="ij")
    turns = [0] + ([1] if layers > 1 else []) + ([-1] if layers > 2 else [])
    rows, cols, weights = [], [], []
    for dk in turns:
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                if (dx, dy, dk) == (0, 0, 0) or (dk and (dx or dy) and not turn_while_moving):
                    continue
                x2, y2, k2 = x + dx, y + dy, (k + dk) % layers
                ok = (x2 >= 0) & (x2 < nx) & (y2 >= 0) & (y2 < ny) & trav
                x2c, y2c = np.clip(x2, 0, nx - 1), np.clip(y2, 0, ny - 1)
                ok &= trav[k2, y2c, x2c]
                if dx and dy:
                    ok &= trav[k, y, x2c] & trav[k, y2c, x]
                length = math.hypot(dx, dy) * res + (turn_length if dk else 0.0)
                w = length * (1 + weight * 0.5 * (cost[k, y, x] + cost[k2, y2c, x2c]))
                src = np.ravel_multi_index((k, y, x), cost.shape)[ok]
                dst = np.ravel_multi_index((k2, y2c, x2c), cost.shape)[ok]
                rows.append(src), cols.append(dst), weights.append(w[ok])
    n = cost.size
    return csr_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))


def random_maze(seed, layers, ny=14, nx=17, blocked=0.3):
    rng = np.random.default_rng(seed)
    free2d = rng.random((ny, nx)) >= blocked
    trav = np.broadcast_to(free2d, (layers, ny, nx)).copy()
    cost = rng.random((layers, ny, nx)) * 3.0
    free = np.argwhere(free2d)
    s, g = free[rng.choice(len(free), 2, replace=False)]
    return cost, trav, (s[1], s[0], rng.integers(layers)), (g[1], g[0], rng.integers(layers))


def grid(nx, ny, res=0.5, x0=-2.0, y0=1.0):
    return Grid.plane(x0, y0, res, nx, ny)


def world(g, cell, layers):
    ix, iy, k = cell
    return (g.x0 + (ix + 0.5) * g.res, g.y0 + (iy + 0.5) * g.res, k * 2 * math.pi / layers)


def check_path(path, trav, cost, g, weight, turn_length):
    """Connected through legal moves, only traversable cells, and its cost
    recomputed edge by edge equals the reported one."""
    layers = trav.shape[0]
    cells = path.cells
    assert all(trav[k, iy, ix] for ix, iy, k in cells)
    total = 0.0
    for (x1, y1, k1), (x2, y2, k2) in zip(cells[:-1], cells[1:]):
        dx, dy = x2 - x1, y2 - y1
        dk = min((k2 - k1) % layers, (k1 - k2) % layers)
        assert max(abs(dx), abs(dy)) <= 1 and dk <= 1 and (dx, dy, dk) != (0, 0, 0)
        if dx and dy:  # no corner cutting
            assert trav[k1, y1, x2] and trav[k1, y2, x1]
        length = math.hypot(dx, dy) * g.res + dk * turn_length
        total += length * (1 + weight * 0.5 * (cost[k1, y1, x1] + cost[k2, y2, x2]))
    assert total == pytest.approx(path.cost, rel=1e-12, abs=1e-12)
    np.testing.assert_allclose(path.poses[:, 0], g.x0 + (cells[:, 0] + 0.5) * g.res)
    assert path.length == pytest.approx(np.hypot(*np.diff(path.poses[:, :2], axis=0).T).sum())


def scipy_cost(cost, trav, g, s, t, weight, turn_length, turn_while_moving):
    """Least cost from cell s to cell t (x, y, k) by scipy's Dijkstra on the explicit graph."""
    dist = dijkstra(
        explicit_graph(cost, trav, g.res, weight, turn_length, turn_while_moving),
        indices=np.ravel_multi_index((s[2], s[1], s[0]), cost.shape),
    )
    return dist[np.ravel_multi_index((t[2], t[1], t[0]), cost.shape)]


@pytest.mark.parametrize("layers,turn_while_moving", [(1, True), (2, True), (6, True), (6, False)])
@pytest.mark.parametrize("seed", range(6))
def test_cost_equals_scipy_dijkstra_on_random_mazes(seed, layers, turn_while_moving):
    cost, trav, s, t = random_maze(seed, layers)
    g = grid(cost.shape[2], cost.shape[1])
    weight, turn_radius = [0.0, 1.0, 4.0][seed % 3], 0.3
    turn_length = turn_radius * 2 * math.pi / layers
    expected = scipy_cost(cost, trav, g, s, t, weight, turn_length, turn_while_moving)
    kwargs = dict(weight=weight, turn_radius=turn_radius, turn_while_moving=turn_while_moving)
    start, goal = world(g, s, layers), world(g, t, layers)
    arr = cost[0] if layers == 1 else cost
    if not np.isfinite(expected):
        with pytest.raises(Lf3pmError, match="unreachable"):
            search_path(arr, trav, g, start, goal, **kwargs)
        return
    astar = search_path(arr, trav, g, start, goal, **kwargs)
    dij = search_path(arr, trav, g, start, goal, heuristic=False, **kwargs)
    assert astar.cost == pytest.approx(expected, rel=1e-9)
    assert dij.cost == pytest.approx(expected, rel=1e-9)
    assert astar.expanded <= dij.expanded
    assert tuple(astar.cells[0]) == tuple(s) and tuple(astar.cells[-1]) == tuple(t)
    check_path(astar, trav, cost, g, weight, turn_length)
    check_path(dij, trav, cost, g, weight, turn_length)


def random_se2(seed, layers, ny=9, nx=11):
    """Costs and traversability that differ between yaw bins (the heuristic's
    x-y relaxation then differs from every bin), and two traversable states."""
    rng = np.random.default_rng(seed)
    trav = rng.random((layers, ny, nx)) >= 0.25
    cost = rng.random((layers, ny, nx)) * 3.0
    free = np.argwhere(trav)
    (sk, sy, sx), (gk, gy, gx) = free[rng.choice(len(free), 2, replace=False)]
    return cost, trav, (sx, sy, sk), (gx, gy, gk)


SE2_CASES = [(1, True), (2, True), (3, False), (6, True), (6, False)]


@pytest.mark.parametrize("layers,turn_while_moving", SE2_CASES)
@pytest.mark.parametrize("seed", range(8))
def test_astar_equals_dijkstra_and_scipy_on_random_se2_costs(seed, layers, turn_while_moving):
    cost, trav, s, t = random_se2(seed, layers)
    g = grid(cost.shape[2], cost.shape[1])
    weight, turn_radius = [0.0, 1.0, 4.0, 0.5][seed % 4], [0.0, 0.3, 1.0][seed % 3]
    turn_length = turn_radius * 2 * math.pi / layers
    expected = scipy_cost(cost, trav, g, s, t, weight, turn_length, turn_while_moving)
    kwargs = dict(weight=weight, turn_radius=turn_radius, turn_while_moving=turn_while_moving)
    start, goal = world(g, s, layers), world(g, t, layers)
    assert np.isfinite(expected)  # a quarter of the states blocked leaves these grids connected
    astar = search_path(cost, trav, g, start, goal, **kwargs)
    dij = search_path(cost, trav, g, start, goal, heuristic=False, **kwargs)
    assert astar.cost == pytest.approx(expected, rel=1e-9)
    assert dij.cost == pytest.approx(expected, rel=1e-9)
    assert astar.expanded <= dij.expanded
    check_path(astar, trav, cost, g, weight, turn_length)


def core_heuristic(cost, trav, res, goal, weight, turn_length):
    """The core's A* heuristic at every state, as a (layers, ny, nx) array."""
    layers, ny, nx = cost.shape
    flat_cost = np.ascontiguousarray(np.moveaxis(cost, 0, -1)).ravel()
    flat_trav = np.ascontiguousarray(np.moveaxis(trav, 0, -1), dtype=np.uint8).ravel()
    gx, gy, gk = goal
    params = _core.SearchParams()
    params.weight, params.turn_length = weight, turn_length
    h = _core.search_heuristic(flat_cost, flat_trav, nx, ny, layers, res, (gy * nx + gx) * layers + gk, params)
    return np.moveaxis(h.reshape(ny, nx, layers), -1, 0)


def exact_cost_to_go(graph, goal, shape):
    """Cost from every state to ``goal`` (ix, iy, k): scipy's Dijkstra from the
    goal on the reversed graph."""
    gx, gy, gk = goal
    return dijkstra(graph.T.tocsr(), indices=np.ravel_multi_index((gk, gy, gx), shape)).reshape(shape)


@pytest.mark.parametrize("layers,turn_while_moving", SE2_CASES)
@pytest.mark.parametrize("seed", range(6))
def test_heuristic_is_admissible_and_consistent(seed, layers, turn_while_moving):
    """h(s) <= the exact cost-to-go (scipy's Dijkstra from the goal on the
    reversed graph) at every state, and h(a) <= c(a, b) + h(b) on every edge."""
    cost, trav, _, t = random_se2(100 + seed, layers)
    res, weight, turn_length = 0.5, [0.0, 1.0, 4.0][seed % 3], [0.0, 0.2, 0.7][seed % 3]
    graph = explicit_graph(cost, trav, res, weight, turn_length, turn_while_moving)
    to_go = exact_cost_to_go(graph, t, cost.shape)
    h = core_heuristic(cost, trav, res, t, weight, turn_length)
    assert h[t[2], t[1], t[0]] == 0.0
    assert np.all(h[trav] <= to_go[trav] * (1 + 1e-12))
    assert np.isfinite(to_go[trav]).sum() > 0.5 * trav.sum()  # most states reach the goal: a real check
    edges = graph.tocoo()
    ha, hb = h.ravel()[edges.row], h.ravel()[edges.col]
    assert np.all((ha <= edges.data + hb + 1e-12) | np.isinf(hb))


@pytest.mark.parametrize("seed", range(4))
def test_heuristic_is_exact_when_yaw_does_not_matter(seed):
    """Equal yaw bins and free turns: the se2 cost-to-go is the x-y one, which
    the heuristic's relaxation computes exactly."""
    cost, trav, _, t = random_maze(200 + seed, 4)
    cost[:] = cost[0]
    graph = explicit_graph(cost, trav, 0.5, 1.0, 0.0, True)
    to_go = exact_cost_to_go(graph, t, cost.shape)
    h = core_heuristic(cost, trav, 0.5, t, 1.0, 0.0)
    reach = np.isfinite(to_go)
    assert reach[trav].sum() > 20
    np.testing.assert_allclose(h[reach], to_go[reach], rtol=1e-12)
    assert np.all(np.isinf(h[trav & ~reach]))


def test_some_random_mazes_are_solved():
    """Guards the maze test above against only ever checking unreachable goals."""
    solved = 0
    for seed in range(6):
        cost, trav, s, t = random_maze(seed, 1)
        d = dijkstra(
            explicit_graph(cost, trav, 0.5, 1.0, 0.0, True), indices=np.ravel_multi_index((0, s[1], s[0]), cost.shape)
        )
        solved += np.isfinite(d[np.ravel_multi_index((0, t[1], t[0]), cost.shape)])
    assert solved >= 4


def corridors():
    """Start and goal joined by a straight middle corridor (row 5, length 20
    cells) and two equal detours through rows 1 and 9."""
    trav = np.zeros((11, 21), bool)
    trav[[1, 5, 9], :] = True
    trav[1:10, 0] = trav[1:10, 20] = True
    return trav, grid(21, 11, res=1.0, x0=0.0, y0=0.0)


@pytest.mark.parametrize("cheap_row", [1, 9])
def test_a_low_cost_corridor_beats_a_high_cost_one_of_equal_length(cheap_row):
    trav, g = corridors()
    trav[5, 1:20] = False  # only the two equal detours remain
    cost = np.full(trav.shape, 3.0)
    cost[cheap_row] = 0.1
    path = search_path(cost, trav, g, (0.5, 5.5, 0.0), (20.5, 5.5, 0.0), weight=1.0)
    rows = set(path.cells[:, 1]) - {2, 3, 4, 5, 6, 7, 8}
    assert rows == {cheap_row}


def test_lambda_trades_length_against_perception_cost():
    trav, g = corridors()
    cost = np.full(trav.shape, 0.1)
    cost[5, 1:20] = 5.0  # the short corridor is expensive to localise in
    kwargs = dict(start=(0.5, 5.5, 0.0), goal=(20.5, 5.5, 0.0))
    short = search_path(cost, trav, g, weight=0.0, **kwargs)
    assert short.length == pytest.approx(20.0) and 5 in short.cells[1:-1, 1]
    careful = search_path(cost, trav, g, weight=1.0, **kwargs)
    assert careful.length > 25.0 and 5 not in careful.cells[1:-1, 1]


def test_cost_layer_is_normalised_capped_and_scale_free():
    rng = np.random.default_rng(5)
    q = rng.lognormal(size=(4, 10, 10))
    q[0, 0, 0], q[1, 2, 3] = np.inf, np.nan
    layer = cost_from_values(q, "q_n")
    finite = np.isfinite(q)
    assert np.median(q[finite] / layer.scale) == pytest.approx(1.0)
    assert layer.cost[0, 0, 0] == layer.cap == pytest.approx(np.percentile(q[finite] / layer.scale, 99))
    assert np.isnan(layer.cost[1, 2, 3]) and layer.filled[1, 2, 3] == layer.cap
    assert np.isfinite(layer.filled).all() and (layer.filled >= 0).all() and layer.filled.max() == layer.cap
    np.testing.assert_allclose(cost_from_values(10 * q, "q_n").filled, layer.filled)
    assert not cost_from_values(q, "none").filled.any()
    with pytest.raises(Lf3pmError, match="unknown cost channel"):
        cost_from_values(q, "q_mean")
    with pytest.raises(Lf3pmError, match="no finite value"):
        cost_from_values(np.full((2, 2), np.nan))


def test_composite_cost_is_the_worse_of_its_parts_each_relative_to_its_median():
    rng = np.random.default_rng(6)
    q_n, q_min = rng.lognormal(size=(2, 3, 8, 8))
    q_n[0, 0, 0], q_min[0, 1, 1], q_n[1, 2, 2] = np.inf, np.inf, np.nan
    q_min[1, 2, 2] = np.nan
    degenerate = np.zeros(q_n.shape, bool)
    degenerate[2, 3, 3] = True
    arrays = {"q_n": q_n, "q_min": q_min, "degenerate": degenerate}
    solm = SimpleNamespace(grid_spec=SimpleNamespace(space=Space.SE2), channel=arrays.__getitem__)
    layer = cost_from_solm(solm, "q_n_q_min")
    usable = np.isfinite(q_n) & np.isfinite(q_min) & ~degenerate
    # float64 reference: each part over its own median of usable-for-it cells, the larger taken
    worse = np.maximum(
        q_n / np.median(q_n[np.isfinite(q_n) & ~degenerate]), q_min / np.median(q_min[np.isfinite(q_min) & ~degenerate])
    )
    expected = np.minimum(worse / np.median(worse[usable]), layer.cap)
    np.testing.assert_allclose(layer.cost[usable], expected[usable], rtol=1e-12)
    assert layer.cost[0, 0, 0] == layer.cost[0, 1, 1] == layer.cost[2, 3, 3] == layer.cap
    assert np.isnan(layer.cost[1, 2, 2]) and layer.filled[1, 2, 2] == layer.cap
    # below the cap, never cheaper (before the final normalisation) than either part alone
    uncapped = usable & (layer.cost < layer.cap)
    for part in ("q_n", "q_min"):
        alone = cost_from_solm(solm, part).cost[uncapped]
        assert (layer.cost[uncapped] * layer.scale >= alone * (1 - 1e-12)).all()


@pytest.fixture(scope="module")
def blocked_map():
    mask = np.zeros((10, 12), bool)
    mask[:, 6] = True  # a wall splitting the map in two
    mask[2, 2] = True
    unknown = np.zeros_like(mask)
    unknown[7, 2] = True
    return Esdf.from_mask(mask, 0.0, 0.0, 1.0, unknown=unknown), np.ones((10, 12))


@pytest.mark.parametrize(
    "start,goal,needle",
    [
        ((-0.5, 3.5, 0.0), (3.5, 3.5, 0.0), "start .* lies outside the grid"),
        ((3.5, 3.5, 0.0), (3.5, 10.5, 0.0), "goal .* lies outside the grid"),
        ((2.5, 2.5, 0.0), (3.5, 4.5, 0.0), "start .* is inside an obstacle"),
        ((3.5, 4.5, 0.0), (2.5, 7.5, 0.0), "goal .* is on unknown ground"),
        ((3.5, 2.5, 0.0), (3.5, 5.5, 0.0), "start .* closer than r_safe 1.2 m"),
        ((1.5, 4.5, 0.0), (9.5, 4.5, 0.0), "goal .* is unreachable from start"),
        ((float("nan"), 4.5, 0.0), (9.5, 4.5, 0.0), "start must be three finite numbers"),
    ],
)
def test_user_errors_are_one_line(blocked_map, start, goal, needle):
    esdf, cost = blocked_map
    with pytest.raises(Lf3pmError, match=needle) as err:
        search_path(cost, esdf, esdf, start, goal, r_safe=1.2 if "r_safe" in needle else 0.0)
    assert "\n" not in str(err.value)


def test_a_plain_mask_names_the_blocked_cell_generically(blocked_map):
    esdf, cost = blocked_map
    with pytest.raises(Lf3pmError, match="start .* is not traversable"):
        search_path(cost, esdf.traversable(), esdf, (2.5, 2.5, 0.0), (3.5, 4.5, 0.0))
    bad = cost.copy()
    bad[4, 4] = np.nan
    with pytest.raises(Lf3pmError, match="finite and >= 0 on traversable cells"):
        search_path(bad, esdf, esdf, (1.5, 4.5, 0.0), (3.5, 4.5, 0.0))


def test_start_equal_to_goal_is_a_one_cell_path(blocked_map):
    esdf, cost = blocked_map
    path = search_path(cost, esdf, esdf, (1.5, 4.5, 0.3), (1.7, 4.2, 0.3))
    assert path.cells.shape == (1, 3) and path.cost == 0.0 and path.length == 0.0


@pytest.mark.slow
def test_plans_on_a_built_solm(tmp_path):
    scene = build_scene("boxes")
    world_map, sensor = lf3pm.load_map(scene.points), lf3pm.get_sensor("vlp16")
    g = make_grid(world_map, "se2", 1.0, bounds=(-3.5, -3.5, 3.5, 3.5), yaw_bins=4)
    build_solm(world_map, sensor, g, tmp_path / "s.zarr")
    solm = Solm.open(tmp_path / "s.zarr")
    esdf, layer = Esdf.from_solm(solm), cost_from_solm(solm, "q_n")
    assert layer.cost.shape == (4, 7, 7) and esdf.values.shape == (7, 7)
    free = np.argwhere(esdf.traversable())
    (sy, sx), (gy, gx) = free[0], free[-1]
    path = search_path(
        layer, esdf, g, (g.x0 + sx + 0.5, g.y0 + sy + 0.5, 0.0), (g.x0 + gx + 0.5, g.y0 + gy + 0.5, math.pi)
    )
    assert path.cells[-1, 2] == 2 and np.isfinite(path.cost)
    assert esdf.traversable()[path.cells[:, 1], path.cells[:, 0]].all()
