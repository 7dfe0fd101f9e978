"""Benchmark: planning on random queries: how many plans meet every limit, and how fast,
against the same planner with its front end searching without its heuristic.

20 seeded random (start, goal) pairs, 3 m or more apart, on traversable cells of the
`boxes` scene's SOLM (0.5 m cells), with random start and goal yaws, for an omni, a
diff or a car robot (0.5 m turning radius), the default limits otherwise. A plan
counts as feasible when its 100 Hz samples meet every limit within 2 % (the checks of
tests/kinematics.py, copied here: speed, yaw-rate, acceleration and yaw-acceleration
limits, no sideways motion for diff and car, R |omega| - |v| within 2 % of vmax),
clearance >= r_safe, and the start and goal yaws within 0.01 rad. Queries with no
path (the front end says so) are replaced by new draws and counted. Each query is
planned twice: by the planner as shipped (ours) and with the front end's heuristic off
(``Planner.plan(heuristic=False)``: uniform-cost search, Dijkstra on the grid, the
baseline); printed: the feasible count and the median plan time of each, and their
ratio. Builds the SOLM in a temporary folder unless --solm names one.

    .venv/bin/python bench/bench_random_queries.py [--robot car] [--seed 0] [--solm boxes.zarr]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from common import build_boxes_solm

from lf3pm.errors import Lf3pmError
from lf3pm.planner import Planner
from lf3pm.solm.reader import Solm
from lf3pm.trajectory import Robot


def kinematic_checks(trajectory, robot, slack: float = 0.02, rate: float = 100.0):
    """(samples, {check: passed}) for every limit of ``robot`` on ``rate`` Hz samples, as
    tests/kinematics.py checks them: speeds (body frame and, if set, |v|), yaw rate,
    body-frame accelerations and yaw acceleration (central differences of the sampled yaw
    rate) within ``slack``; no sideways motion (|h| < 1e-3 m/s) for diff and car; the car's
    turning radius within ``slack`` of its top speed."""
    s = trajectory.sample(rate)
    c, si = np.cos(s["yaw"]), np.sin(s["yaw"])
    v_lon, v_lat = s["vx"] * c + s["vy"] * si, -s["vx"] * si + s["vy"] * c
    lim = 1 + slack
    out = {
        "v_lon": np.max(np.abs(v_lon)) <= lim * robot.vmax_lon,
        "omega": np.max(np.abs(s["omega"])) <= lim * robot.wmax,
        "a_lon": np.max(np.abs(s["ax"] * c + s["ay"] * si)) <= lim * robot.amax_lon,
        "a_lat": np.max(np.abs(-s["ax"] * si + s["ay"] * c)) <= lim * robot.amax_lat,
        "alpha": np.max(np.abs(np.gradient(s["omega"], s["t"]))) <= lim * robot.alpha_max,
    }
    if robot.kind == "omni":
        out["v_lat"] = np.max(np.abs(v_lat)) <= lim * robot.vmax_lat
        if robot.vmax_norm is not None:
            out["speed"] = np.max(np.hypot(s["vx"], s["vy"])) <= lim * robot.vmax_norm
    else:
        out["sideways"] = np.max(np.abs(v_lat)) < 1e-3
    if robot.kind == "car":  # R |omega| <= |v_lon|
        out["turn"] = np.max(robot.min_turn_radius * np.abs(s["omega"]) - np.abs(v_lon)) <= slack * robot.vmax_lon
    return s, {name: bool(ok) for name, ok in out.items()}


def checks(plan, start, goal, robot, esdf) -> dict:
    s, out = kinematic_checks(plan.trajectory, robot)
    yaw_error = [abs(np.angle(np.exp(1j * (s["yaw"][i] - pose[2])))) for i, pose in ((0, start), (-1, goal))]
    out["clearance"] = bool(np.min(esdf.distance(s["x"], s["y"])[0]) >= robot.r_safe)
    out["end yaws"] = max(yaw_error) < 1e-2
    return out


def run(solm_path: Path, kind: str, seed: int, queries: int = 20) -> None:
    planner = Planner(Solm.open(solm_path))
    robot = Robot(kind, min_turn_radius=0.5 if kind == "car" else 0.0, r_safe=0.05)
    g = planner.esdf
    ys, xs = np.nonzero(g.traversable(0.3))
    rng = np.random.default_rng(seed)
    done = no_path = 0
    feasible = {"ours": 0, "baseline": 0}
    times = {"ours": [], "baseline": []}
    failures = []
    while done < queries:
        i, j = rng.choice(len(xs), 2, replace=False)
        start = (g.x0 + (xs[i] + 0.5) * g.res, g.y0 + (ys[i] + 0.5) * g.res, rng.uniform(-np.pi, np.pi))
        goal = (g.x0 + (xs[j] + 0.5) * g.res, g.y0 + (ys[j] + 0.5) * g.res, rng.uniform(-np.pi, np.pi))
        if np.hypot(start[0] - goal[0], start[1] - goal[1]) < 3:
            continue
        t0 = time.perf_counter()
        try:
            plan = planner.plan(start, goal, robot=robot, metric="q_n", weight=1.0)
        except Lf3pmError as error:
            no_path += 1
            print(f"no plan: {error}")
            continue
        times["ours"].append(time.perf_counter() - t0)
        done += 1
        result = checks(plan, start, goal, robot, g)
        if all(result.values()):
            feasible["ours"] += 1
        else:
            failures.append((done, [name for name, ok in result.items() if not ok]))
        t0 = time.perf_counter()
        try:
            plan = planner.plan(start, goal, robot=robot, metric="q_n", weight=1.0, heuristic=False)
        except Lf3pmError as error:
            print(f"query {done}: no plan without the heuristic: {error}")
            continue
        times["baseline"].append(time.perf_counter() - t0)
        feasible["baseline"] += all(checks(plan, start, goal, robot, g).values())
    ours, base = (1e3 * np.median(times[k]) for k in ("ours", "baseline"))
    print(
        f"{kind}, seed {seed}: {feasible['ours']}/{queries} plans meet every limit; {no_path} queries had no plan; "
        f"median plan time {ours:.0f} ms"
    )
    print(
        f"  baseline, front end without its heuristic: {feasible['baseline']}/{len(times['baseline'])} plans meet "
        f"every limit; median plan time {base:.0f} ms; baseline / ours {base / ours:.2f}x"
    )
    for number, names in failures:
        print(f"  query {number}: misses {', '.join(names)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", choices=("omni", "diff", "car"), default="car")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--solm", type=Path, default=None, help="the boxes SOLM (default: build one)")
    args = parser.parse_args()
    if args.solm is not None:
        run(args.solm, args.robot, args.seed)
        return
    with tempfile.TemporaryDirectory() as folder:
        run(build_boxes_solm(Path(folder)), args.robot, args.seed)


if __name__ == "__main__":
    main()
