"""Planning on random queries: how many plans meet every limit, and how fast.

20 seeded random (start, goal) pairs, 3 m or more apart, on traversable cells of the
`boxes` scene's SOLM (0.5 m cells), with random start and goal yaws, for an omni, a
diff or a car robot (0.5 m turning radius), the default limits otherwise. A plan
counts as feasible when its 100 Hz samples meet the test suite's checks
(tests/kinematics.py: speed, yaw-rate, acceleration and yaw-acceleration limits
within 2 %, no sideways motion for diff and car, R |omega| - |v| within 2 % of vmax),
clearance >= r_safe, and the start and goal yaws within 0.01 rad. Queries with no
path (the front end says so) are replaced by new draws and counted. Builds the SOLM
in a temporary folder unless --solm names one.

    .venv/bin/python bench/bench_random_queries.py [--robot car] [--seed 0] [--solm boxes.zarr]
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
from kinematics import kinematic_checks  # noqa: E402

from lf3pm.errors import Lf3pmError  # noqa: E402
from lf3pm.planner import Planner  # noqa: E402
from lf3pm.solm.reader import Solm  # noqa: E402
from lf3pm.trajectory import Robot  # noqa: E402


def build_boxes(folder: Path) -> Path:
    """The `boxes` scene's SOLM, as tests/test_plan.py builds it."""
    for args in (
        ["scene", "boxes", "-o", folder / "boxes.pcd"],
        ["solm", "build", folder / "boxes.pcd", "-o", folder / "boxes.zarr", "--res", "0.5", "--ray-stride", "4"],
    ):
        subprocess.run([sys.executable, "-m", "lf3pm.cli", *map(str, args)], check=True, capture_output=True)
    return folder / "boxes.zarr"


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
    print(
        f"{kind}, seed {seed}: {feasible}/{queries} plans meet every limit; {no_path} queries had no plan; "
        f"median plan time {1e3 * np.median(times):.0f} ms"
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
        run(build_boxes(Path(folder)), args.robot, args.seed)


if __name__ == "__main__":
    main()
