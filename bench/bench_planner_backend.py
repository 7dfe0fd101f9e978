"""Benchmark: the trajectory back end (C++ L-BFGS) against scipy's L-BFGS-B
driving the same C++ objective and gradient through Python callbacks, with the
same stopping rule: relative decrease of the objective
below rel_cost_tol over 3 iterations (a scipy callback), or a small gradient (ours:
||g|| <= 1e-6 max(1, ||x||); scipy: its max-norm gtol 1e-6).

A ~200 m front-end path (a seeded wave) on a synthetic, seeded cost field and an
ESDF of random discs; omni (box and |v| limits) and diff robots; one thread. Prints both wall times,
their ratio and both final objective values.

    .venv/bin/python bench/bench_planner_backend.py [--repeats 3] [--rel-cost-tol 1e-4]
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import math  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy import ndimage  # noqa: E402
from scipy.optimize import minimize  # noqa: E402

from lf3pm import _core  # noqa: E402
from lf3pm.grid_field import GridField  # noqa: E402
from lf3pm.trajectory import Robot, make_problem  # noqa: E402


def scenario(seed: int = 0):
    """Front-end waypoints along y = 10 sin(x / 30), x in [0, 200] m, a cost field in
    [1, 5] (smoothed noise, 0.5 m cells) and the ESDF of 60 random discs off the path."""
    rng = np.random.default_rng(seed)
    res, x0, y0, nx, ny = 0.5, -20.0, -40.0, 480, 160
    noise = ndimage.gaussian_filter(rng.normal(size=(ny, nx)), 8)
    cost = GridField(1 + 4 * (noise - noise.min()) / np.ptp(noise), x0, y0, res)
    xs, ys = x0 + (np.arange(nx) + 0.5) * res, y0 + (np.arange(ny) + 0.5) * res
    X, Y = np.meshgrid(xs, ys)
    occupied = np.zeros((ny, nx), bool)
    for _ in range(60):
        cx, cy, r = rng.uniform(0, 200), rng.uniform(-35, 35), rng.uniform(0.5, 2.0)
        if abs(cy - 10 * np.sin(cx / 30)) > r + 2:
            occupied |= (X - cx) ** 2 + (Y - cy) ** 2 < r * r
    esdf = GridField(ndimage.distance_transform_edt(~occupied) * res, x0, y0, res)
    t = np.linspace(0, 200, 201)
    waypoints = np.column_stack([t, 10 * np.sin(t / 30), np.arctan(np.cos(t / 30) / 3)])
    return waypoints, cost, esdf


def ours(problem, tol):
    params = _core.trajectory_lbfgs()
    params.delta = tol
    out = problem.optimize(params)
    return out["terms"]["total"], out["iterations"]


def scipy_baseline(problem, tol):
    """scipy's L-BFGS-B (memory 8) on the same objective and stopping rule."""
    history = []

    def stop(intermediate_result):
        history.append(intermediate_result.fun)
        if len(history) > 3 and history[-4] - history[-1] <= tol * max(1.0, abs(history[-1])):
            raise StopIteration

    r = minimize(
        problem.evaluate,
        problem.initial.copy(),
        jac=True,
        method="L-BFGS-B",
        callback=stop,
        options={"maxcor": 8, "maxiter": 100000, "maxfun": 1000000, "ftol": 0.0, "gtol": 1e-6},
    )
    return problem.details(r.x)["total"], r.nit


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--rel-cost-tol", type=float, default=1e-4)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    waypoints, cost, esdf = scenario(args.seed)
    print(
        f"path ~{np.sum(np.hypot(*np.diff(waypoints[:, :2], axis=0).T)):.0f} m, seed {args.seed}, "
        f"rel_cost_tol {args.rel_cost_tol}, one thread"
    )
    robots = {
        "omni box": Robot("omni", vmax_lon=1.5, vmax_lat=1.0, wmax=1.0, vmax_norm=math.inf),
        "omni": Robot("omni", vmax_lon=1.5, vmax_lat=1.0, wmax=1.0),
        "diff": Robot("diff", vmax_lon=1.5, wmax=1.0),
        "car": Robot("car", vmax_lon=1.5, wmax=1.0, min_turn_radius=2.0),
    }
    for kind, robot in robots.items():
        problem = make_problem(waypoints, cost, esdf, robot, samples=16, piece_length=2.0)
        row = {}
        for name, fn in (("ours (C++ L-BFGS)", ours), ("scipy L-BFGS-B", scipy_baseline)):
            times = []
            for _ in range(args.repeats):
                start = time.perf_counter()
                f, iterations = fn(problem, args.rel_cost_tol)
                times.append(time.perf_counter() - start)
            row[name] = min(times)
            print(
                f"{kind:8s} {name:18s} {1e3 * min(times):9.1f} ms  objective {f:9.3f}  "
                f"iterations {iterations:6d}  ({problem.dimension} variables)"
            )
        ours_t, base_t = row["ours (C++ L-BFGS)"], row["scipy L-BFGS-B"]
        print(f"{kind:8s} speed-up {base_t / ours_t:.1f}x (scipy / ours)")


if __name__ == "__main__":
    main()
