"""Car planning on random queries: how many plans meet every limit.

20 seeded random (start, goal) pairs, 3 m or more apart, on traversable cells of the
`boxes` scene's SOLM (0.5 m cells), with random start and goal yaws; a car with a
0.5 m turning radius. A plan counts as feasible when its 100 Hz samples meet the
test suite's checks (tests/kinematics.py: speed and yaw-rate limits within 2 %,
no sideways motion, R |omega| - |v| within 2 % of vmax), clearance >= r_safe, and
the start and goal yaws within 0.01 rad. Queries with no forward path (the front
end says so) are replaced by new draws and counted. Builds the SOLM in a temporary
folder unless --solm names one.

    .venv/bin/python bench/bench_car_queries.py [--seed 0] [--solm boxes.zarr]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from kinematics import body_speeds  # noqa: E402

from lf3pm.errors import Lf3pmError  # noqa: E402
from lf3pm.planner import Planner, Robot  # noqa: E402
from lf3pm.solm.reader import Solm  # noqa: E402


def build_boxes(folder: Path) -> Path:
    """The `boxes` scene's SOLM, as tests/test_plan.py builds it."""
    for args in (["scene", "boxes", "-o", folder / "boxes.pcd"],
                 ["solm", "build", folder / "boxes.pcd", "-o", folder / "boxes.zarr", "--res", "0.5",
                  "--ray-stride", "4"]):
        subprocess.run([sys.executable, "-m", "lf3pm.cli", *map(str, args)], check=True, capture_output=True)
    return folder / "boxes.zarr"


def checks(plan, start, goal, robot, esdf) -> dict:
    s, v_lon, v_lat = body_speeds(plan.trajectory)
    yaw_error = [abs(np.angle(np.exp(1j * (s["yaw"][i] - pose[2])))) for i, pose in ((0, start), (-1, goal))]
    return {"v_lon": np.max(np.abs(v_lon)) <= 1.02 * robot.vmax_lon,
            "omega": np.max(np.abs(s["omega"])) <= 1.02 * robot.wmax,
            "sideways": np.max(np.abs(v_lat)) < 1e-3,
            "turn": np.max(robot.min_turn_radius * np.abs(s["omega"]) - np.abs(v_lon)) <= 0.02 * robot.vmax_lon,
            "clearance": np.min(esdf.distance(s["x"], s["y"])[0]) >= robot.r_safe,
            "end yaws": max(yaw_error) < 1e-2}


def run(solm_path: Path, seed: int, queries: int = 20) -> None:
    planner = Planner(Solm.open(solm_path))
    robot = Robot("car", min_turn_radius=0.5, r_safe=0.05)
    g = planner.esdf
    ys, xs = np.nonzero(g.traversable(0.3))
    rng = np.random.default_rng(seed)
    feasible = done = no_path = 0
    failures, times = [], []
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
        times.append(time.perf_counter() - t0)
        done += 1
        result = checks(plan, start, goal, robot, g)
        if all(result.values()):
            feasible += 1
        else:
            failures.append((done, [name for name, ok in result.items() if not ok]))
    print(f"seed {seed}: {feasible}/{queries} plans meet every limit; {no_path} queries had no plan; "
          f"median plan time {1e3 * np.median(times):.0f} ms")
    for number, names in failures:
        print(f"  query {number}: misses {', '.join(names)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--solm", type=Path, default=None, help="the boxes SOLM (default: build one)")
    args = parser.parse_args()
    if args.solm is not None:
        run(args.solm, args.seed)
        return
    with tempfile.TemporaryDirectory() as folder:
        run(build_boxes(Path(folder)), args.seed)


if __name__ == "__main__":
    main()
