"""Benchmark: replanning a quadrotor's 50 m flight from a new start (issue 43, item 3): the
flight planner's front end and back end (C++ L-BFGS on the C++ objective) against the same
search with scipy's L-BFGS-B driving that objective through Python callbacks, from the same
initial guess, with the same stopping rule (relative decrease below 1e-4 over 10 iterations,
or a small gradient).

The tunnel scene (84 m), an r3yaw SOLM of its straight (VLP-16 on top, 1 m cells, two
levels, 8 yaw bins; built once, not timed) and one FlightPlanner (ESDF and guidance field
built once, timed apart): each replan flies from a start 50 m from the goal, 10 starts
across the tunnel's width and height. One thread. Prints both medians, their ratio, and
the flights' lengths and durations.

    .venv/bin/python bench/bench_flight_replan.py [--starts 10]
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy.optimize import minimize  # noqa: E402

import lf3pm  # noqa: E402
from lf3pm.planner.flight_path import plan_flight_path  # noqa: E402
from lf3pm.planner.flight_plan import FlightPlanner, initial_guess  # noqa: E402
from lf3pm.scenes import build_scene  # noqa: E402
from lf3pm.solm import Solm, build_solm, make_grid  # noqa: E402

GOAL = (25.0, 0.0, 1.5, 0.0)


def scipy_replan(planner: FlightPlanner, start, goal, delta: float = 1e-4, past: int = 10) -> tuple[float, int]:
    """The same search and initial guess, then scipy L-BFGS-B on the C++ objective (no time
    scaling): (objective, iterations)."""
    path = plan_flight_path(
        planner.solm,
        start,
        goal,
        guidance=planner.guidance,
        quadrotor=planner.quad,
        esdf=planner.esdf,
        move_free=planner.move_free,
    )
    q, T = initial_guess(path, 2.0, planner.quad.vmax)
    head, tail = np.zeros((4, 3)), np.zeros((4, 3))
    head[:, 0] = [*path.positions[0], path.yaws[0]]
    tail[:, 0] = [*path.positions[-1], path.yaws[-1]]
    problem = planner.problem(planner.guidance.weight, 0.0, head, tail, q, T, 1.0, 1e-2)
    history = []

    def objective(x):
        f, g, _ = problem.evaluate(x)
        return f, np.asarray(g)

    def stop(intermediate_result):
        history.append(intermediate_result.fun)
        if len(history) > past and history[-past - 1] - history[-1] <= delta * max(1.0, abs(history[-1])):
            raise StopIteration

    result = minimize(
        objective,
        np.asarray(problem.initial),
        jac=True,
        method="L-BFGS-B",
        callback=stop,
        options={"maxiter": 10_000, "gtol": 1e-6},
    )
    return float(result.fun), int(result.nit)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--starts", type=int, default=10)
    args = parser.parse_args()
    world = lf3pm.load_map(build_scene("tunnel").points, threads=1)
    grid = make_grid(world, "r3yaw", 1.0, bounds=(-30.0, -3.0, 30.0, 3.0), yaw_bins=8, z_levels=(1.0, 2.0))
    with tempfile.TemporaryDirectory() as tmp:
        store = Path(tmp) / "tunnel.zarr"
        t = time.perf_counter()
        build_solm(world, "vlp16", grid, store, noise=0.0, mount="top", threads=2)
        print(f"tunnel r3yaw SOLM {grid.shape}: {time.perf_counter() - t:.1f} s (not timed below)")
        planner = FlightPlanner(Solm.open(store), world.points)
        print(f"planner set-up (ESDF, guidance field): {planner.setup_s * 1e3:.0f} ms, once")
        rng = np.random.default_rng(0)
        ours, core, theirs, lengths = [], [], [], []
        for _ in range(args.starts):
            start = (-25.0, rng.uniform(-1.5, 1.5), rng.choice([1.0, 2.0]), rng.uniform(-np.pi, np.pi))
            t = time.perf_counter()
            plan = planner.plan(start, GOAL)
            ours.append(time.perf_counter() - t)
            core.append(plan.seconds["search"] + plan.seconds["optimize"])
            objective = plan.objective
            t = time.perf_counter()
            f, iterations = scipy_replan(planner, start, GOAL)
            theirs.append(time.perf_counter() - t)
            lengths.append((plan.summary()["trajectory_length_m"], plan.trajectory.duration, plan.iterations))
            lengths[-1] += (iterations, objective, f)
    ours_ms, theirs_ms = 1e3 * np.median(ours), 1e3 * np.median(theirs)
    length = np.median([x[0] for x in lengths])
    duration = np.median([x[1] for x in lengths])
    core_ms = 1e3 * np.median(core)
    rows = np.array([x[2:] for x in lengths], dtype=float)
    print(f"{args.starts} replans of a {length:.1f} m flight ({duration:.1f} s; median), one thread:")
    print(
        f"  lf3pm replan (front end + C++ L-BFGS + time scaling to the limits at 1 kHz) {ours_ms:.0f} ms "
        f"(max {1e3 * max(ours):.0f} ms); goal: under 100 ms"
    )
    print(
        f"  front end + C++ L-BFGS {core_ms:.0f} ms ({np.median(rows[:, 0]):.0f} iterations, objective "
        f"{np.median(rows[:, 2]):.2f})"
    )
    print(
        f"  front end + scipy L-BFGS-B on the same objective {theirs_ms:.0f} ms ({np.median(rows[:, 1]):.0f} "
        f"iterations, objective {np.median(rows[:, 3]):.2f})"
    )
    print(f"  ratio scipy / lf3pm (front end + optimiser) {theirs_ms / core_ms:.1f}x")


if __name__ == "__main__":
    main()
