"""Benchmark: the front end's grid search on a seeded synthetic map.

r2, 1000 x 1000 cells: ours, Dijkstra and A* (octile heuristic), and
scipy.sparse.csgraph.dijkstra on the same explicit graph (8-connected, no
corner cutting, edge cost length * (1 + lambda * mean cell cost)); scipy
solves single-source shortest paths to every cell, ours stops at the goal.
se2, 1000 x 1000 x 36: ours, A* (heuristic: the x-y relaxation's cost-to-go
from a lazy backward pass, plus the yaw term) and Dijkstra. Two routes: corner
to corner (Dijkstra closes nearly every state) and a quarter of the map across
the middle (about 27 m at 1000 cells).
Prints time, expansions (A* se2 also the x-y cells its backward pass closed),
peak memory, and Dijkstra / A*.
Car (Hybrid-A*, turning radius 0.5 m, 72 yaw bins, clearance 0.1 m): on the same
map (its ESDF from the obstacle mask), both routes with the start and goal yaws
of the se2 runs, against r2 A* on the cells at that clearance; and on the
``boxes`` scene (SOLM built on the fly unless --boxes names one), seeded random
queries, against r2 A* on the same SOLM.

    .venv/bin/python bench/bench_graph_search.py [--size 1000] [--bins 36] [--no-se2] [--car-only]
                                                 [--boxes S.zarr]
"""

from __future__ import annotations

import argparse
import math
import resource
import tempfile
import time
from pathlib import Path

import numpy as np
from common import build_boxes_solm
from scipy.ndimage import gaussian_filter
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from lf3pm.errors import Lf3pmError
from lf3pm.grid import Grid
from lf3pm.planner.cost_map import cost_from_solm
from lf3pm.planner.esdf import Esdf
from lf3pm.planner.graph_search import search_path
from lf3pm.planner.hybrid_search import search_car_path

RES = 0.1
WEIGHT = 1.0


def synthetic_map(size: int, seed: int = 0):
    """Random discs as obstacles (about a fifth of the area), a smooth positive
    cost field, and the start and goal corners kept free."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:size, 0:size]
    blocked = np.zeros((size, size), bool)
    count = max(1, round(200 * (size / 1000) ** 2))
    for cx, cy, r in zip(rng.integers(0, size, count), rng.integers(0, size, count), rng.integers(5, 30, count)):
        x0, x1, y0, y1 = max(cx - r, 0), min(cx + r + 1, size), max(cy - r, 0), min(cy + r + 1, size)
        blocked[y0:y1, x0:x1] |= np.hypot(xx[y0:y1, x0:x1] - cx, yy[y0:y1, x0:x1] - cy) <= r
    blocked[:40, :40] = blocked[-40:, -40:] = False
    cost = gaussian_filter(rng.random((size, size)), 8)
    cost = 0.2 + 3.0 * (cost - cost.min()) / (cost.max() - cost.min())
    angle = 2 * math.pi * gaussian_filter(rng.random((size, size)), 20) * 10
    return ~blocked, cost, angle


def explicit_graph(cost, trav):
    """The same graph as the C++ search, written out as a CSR matrix."""
    ny, nx = cost.shape
    y, x = np.mgrid[0:ny, 0:nx]
    rows, cols, weights = [], [], []
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dx == 0 and dy == 0:
                continue
            x2, y2 = np.clip(x + dx, 0, nx - 1), np.clip(y + dy, 0, ny - 1)
            ok = trav & (x + dx == x2) & (y + dy == y2) & trav[y2, x2]
            if dx and dy:
                ok &= trav[y, x2] & trav[y2, x]
            w = math.hypot(dx, dy) * RES * (1 + WEIGHT * 0.5 * (cost + cost[y2, x2]))
            rows.append((y * nx + x)[ok]), cols.append((y2 * nx + x2)[ok]), weights.append(w[ok])
    n = cost.size
    return csr_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def routes(trav) -> dict:
    """Start and goal poses (x, y, yaw) per route name; the mid-map ones on the
    free cells nearest to (0.5, 0.5) and (0.75, 0.6) of the map."""
    n = trav.shape[0]
    free = np.argwhere(trav)

    def near(fx, fy, yaw):
        iy, ix = free[np.argmin(np.hypot(free[:, 0] - fy * n, free[:, 1] - fx * n))]
        return ((ix + 0.5) * RES, (iy + 0.5) * RES, yaw)

    corner = ((1.05, 1.05, 0.0), ((n - 10.5) * RES, (n - 10.5) * RES, math.pi))
    return {"corner to corner": corner, "mid-map": (near(0.5, 0.5, 0.0), near(0.75, 0.6, 0.5 * math.pi))}


CAR_R, CAR_CLEARANCE = 0.5, 0.1


def car_row(name, cost, esdf, start, goal, epsilon: float = 1.0) -> None:
    """One car query: Hybrid-A* (heuristic weight epsilon) against r2 A* on the cells at
    the same clearance."""
    try:
        car = search_car_path(
            cost, esdf, start, goal, radius=CAR_R, weight=WEIGHT, clearance=CAR_CLEARANCE, heuristic_weight=epsilon
        )
    except Lf3pmError as err:
        print(f"car {name}, epsilon {epsilon}: {err}")
        return
    grid = search_path(cost, esdf, esdf, start, goal, weight=WEIGHT, r_safe=CAR_CLEARANCE)
    print(
        f"car {name}, epsilon {epsilon}: hybrid {car.time:.3f} s, {car.expanded} expanded "
        f"(+ {car.relaxed_cells} x-y cells "
        f"backward), {car.analytic_tries} Dubins tries, length {car.length:.2f} m, cost {car.cost:.3f}; "
        f"r2 A* {grid.time:.3f} s, length {grid.length:.2f} m, cost {grid.cost:.3f}; "
        f"hybrid / r2 A* {car.time / grid.time:.1f}x time, {car.cost / grid.cost:.3f}x cost"
    )


def boxes_solm(path: str | None):
    from lf3pm.solm.reader import Solm

    if path:
        return Solm.open(path)
    return Solm.open(build_boxes_solm(Path(tempfile.mkdtemp())))


def car_cases(trav, cost, angle, boxes: str | None) -> None:
    n = trav.shape[0]
    esdf = Esdf.from_mask(~trav, 0.0, 0.0, RES)
    print(f"car: turning radius {CAR_R} m, 72 yaw bins, clearance {CAR_CLEARANCE} m, lambda {WEIGHT}")
    for route, (start, goal) in routes(esdf.traversable(CAR_CLEARANCE + 0.3)).items():
        # Corner to corner, epsilon = 1 gives up after 2 M expansions (G's 1 / kappa leaves
        # ~8 % of slack over 140 m); weighted A* with 1.2 finds a path within 2 %.
        for epsilon in (1.2,) if route == "corner to corner" else (1.0, 1.2):
            car_row(f"{n} x {n} {route}", cost, esdf, start, goal, epsilon)
    solm = boxes_solm(boxes)
    esdf = Esdf.from_solm(solm)
    layer = cost_from_solm(solm, "q_n")
    free = np.argwhere(esdf.traversable(0.3))
    rng = np.random.default_rng(0)
    total_car = total_grid = 0.0
    count = 0
    while count < 20:
        (iy, ix), (jy, jx) = free[rng.choice(len(free), 2, replace=False)]
        a = (esdf.x0 + (ix + 0.5) * esdf.res, esdf.y0 + (iy + 0.5) * esdf.res, rng.uniform(-math.pi, math.pi))
        b = (esdf.x0 + (jx + 0.5) * esdf.res, esdf.y0 + (jy + 0.5) * esdf.res, rng.uniform(-math.pi, math.pi))
        if math.hypot(a[0] - b[0], a[1] - b[1]) < 3:
            continue
        try:
            car = search_car_path(layer, esdf, a, b, radius=CAR_R, weight=WEIGHT, clearance=CAR_CLEARANCE)
        except Lf3pmError:  # facing a wall too closely to turn away: no forward path
            continue
        grid = search_path(layer, esdf, esdf, a, b, weight=WEIGHT, r_safe=CAR_CLEARANCE)
        total_car, total_grid, count = total_car + car.time, total_grid + grid.time, count + 1
    print(
        f"car boxes ({esdf.nx} x {esdf.ny} cells of {esdf.res} m), 20 random queries: hybrid "
        f"{1e3 * total_car / count:.2f} ms, r2 A* {1e3 * total_grid / count:.2f} ms per query, "
        f"{total_car / total_grid:.1f}x"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=1000)
    parser.add_argument("--bins", type=int, default=36)
    parser.add_argument("--no-se2", action="store_true")
    parser.add_argument("--car-only", action="store_true", help="only the car (Hybrid-A*) cases")
    parser.add_argument("--boxes", help="a built boxes SOLM (default: build one, about a minute)")
    args = parser.parse_args()
    n = args.size
    trav, cost, angle = synthetic_map(n)
    grid = Grid.plane(0.0, 0.0, RES, n, n)
    print(f"map {n} x {n}, res {RES} m, {100 * (1 - trav.mean()):.1f} % blocked, lambda {WEIGHT}")
    if args.car_only:
        car_cases(trav, cost, angle, args.boxes)
        return

    t = time.perf_counter()
    graph = explicit_graph(cost, trav)
    build_s = time.perf_counter() - t
    t = time.perf_counter()
    dist = dijkstra(graph, indices=10 * n + 10)
    scipy_s = time.perf_counter() - t
    del graph
    print(
        f"r2 scipy csgraph.dijkstra from the first corner: {scipy_s:.2f} s (graph build {build_s:.2f} s "
        f"not counted), cost to the other {dist[(n - 11) * n + (n - 11)]:.4f}"
    )
    for route, (start, goal) in routes(trav).items():
        p = {}
        for name, heuristic in (("Dijkstra", False), ("A*", True)):
            p[name] = search_path(cost, trav, grid, start, goal, weight=WEIGHT, heuristic=heuristic)
            print(
                f"r2 {route}, ours {name:8s}: {p[name].time:.3f} s, {p[name].expanded} expanded, "
                f"cost {p[name].cost:.4f}, scipy / ours {scipy_s / p[name].time:.1f}x"
            )
        print(
            f"r2 {route}: Dijkstra / A* {p['Dijkstra'].time / p['A*'].time:.2f}x time, "
            f"{p['Dijkstra'].expanded / p['A*'].expanded:.1f}x expanded"
        )
    if args.no_se2:
        car_cases(trav, cost, angle, args.boxes)
        return

    bins = args.bins
    yaw = np.arange(bins)[:, None, None] * 2 * math.pi / bins
    # Perception cost depends on heading: better when facing a direction that varies over the map.
    cost3 = cost[None] * (1.0 + 0.5 * np.cos(yaw - angle[None]))
    print(
        f"se2 {n} x {n} x {bins} = {cost3.size / 1e6:.0f} M states, turn radius 0.5 m; "
        f"process peak RSS before {peak_mb():.0f} MB"
    )
    for route, (start, goal) in routes(trav).items():
        p = {}
        for name, heuristic in (("A*", True), ("Dijkstra", False)):
            t = time.perf_counter()
            p[name] = q = search_path(cost3, trav, grid, start, goal, weight=WEIGHT, heuristic=heuristic)
            wall = time.perf_counter() - t
            # g and the state byte per state, the heap; A*: the x-y pass's two doubles and two bytes per cell.
            core_mb = (cost3.size * 9 + q.heap_peak * 16 + (n * n * 18 if heuristic else 0)) / 2**20
            relaxed = f" (+ {q.relaxed_expanded} x-y cells backward)" if heuristic else ""
            print(
                f"se2 {route}, ours {name:8s}: {q.time:.2f} s search ({wall:.2f} s with input checks), "
                f"{q.expanded} expanded{relaxed}, cost {q.cost:.4f}, heap peak {q.heap_peak}, "
                f"search memory {core_mb:.0f} MB, "
                f"process peak RSS {peak_mb():.0f} MB"
            )
        print(
            f"se2 {route}: Dijkstra / A* {p['Dijkstra'].time / p['A*'].time:.1f}x time, "
            f"{p['Dijkstra'].expanded / p['A*'].expanded:.1f}x expanded"
        )
    car_cases(trav, cost, angle, args.boxes)


if __name__ == "__main__":
    main()
