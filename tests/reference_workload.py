"""A fixed workload whose every number is written to one .npz, so that two runs can be
compared bit for bit (tests/test_builds.py runs it once per core level):

- two procedural scenes with terrain, stones and vegetation (their points);
- poses evaluated on a procedural town with a spinning and a Livox sensor, range noise
  on (the core's seeded Gaussian draws), with their observation rows;
- an R2 SOLM and an SE(2) SOLM built with sector Grams, every channel;
- plans for an omni, a diff and a car robot on the R2 SOLM, their trajectories sampled;
- L-BFGS on the Rosenbrock function.

Usage: python tests/reference_workload.py OUT.npz
"""

import sys
import tempfile
from pathlib import Path

import numpy as np

import lf3pm
from lf3pm import _core
from lf3pm.solm import Solm, build_solm, make_grid

POSES = [(-8.0, -6.0, 1.5, 0.3), (0.0, 0.0, 1.2, 1.9), (6.5, 4.0, 1.0, -2.4), (12.0, -9.0, 2.0, 0.0)]
BOUNDS = (-3.5, -3.5, 3.5, 3.5)


def scenes(out: dict) -> None:
    out["scene/meadow"] = lf3pm.build_scene("meadow", seed=3, extent=8.0).points
    out["scene/gobi"] = lf3pm.build_scene(
        "gobi", seed=3, ground_spacing=0.5, wall_spacing=0.3, roof_spacing=0.5, stone_spacing=0.1
    ).points


def evaluations(out: dict) -> None:
    world = lf3pm.load_map(lf3pm.build_scene("houses", seed=1).points)
    for sensor in ("vlp16", "mid70"):
        for i, pose in enumerate(POSES):
            res = lf3pm.evaluate(world, pose, sensor, seed=7 + i, observations=True)
            key = f"evaluate/{sensor}/{i}"
            values = [getattr(res, f) for f in lf3pm.metric.METRIC_FIELDS] + [res.m, res.hits]
            out[f"{key}/metric"] = np.array(values + list(res.least_observable))
            for name, value in res.observations.items():
                out[f"{key}/{name}"] = np.asarray(value)


def solms_and_plans(out: dict, folder: Path) -> None:
    world = lf3pm.load_map(lf3pm.build_scene("boxes").points)
    r2 = folder / "r2.zarr"
    build_solm(world, lf3pm.get_sensor("vlp16"), make_grid(world, "r2", 0.5, bounds=BOUNDS), r2, tile=5)
    se2 = folder / "se2.zarr"
    build_solm(
        world, lf3pm.get_sensor("mid70"), make_grid(world, "se2", 1.0, bounds=BOUNDS, yaw_bins=12), se2, yaw_reuse=True
    )
    for name, path in (("r2", r2), ("se2", se2)):
        solm = Solm.open(path)
        for channel in solm.channels:
            out[f"solm/{name}/{channel}"] = np.asarray(solm.channel(channel))
    planner = lf3pm.Planner(Solm.open(r2))
    for kind in ("omni", "diff", "car"):
        robot = lf3pm.Robot(kind, r_safe=0.1, min_turn_radius=1.0 if kind == "car" else 0.0)
        plan = planner.plan((-3.0, -3.0, 0.0), (3.0, 2.8, 1.2), robot=robot)
        out[f"plan/{kind}/path"] = plan.path.poses
        out[f"plan/{kind}/coefficients"] = plan.trajectory.coefficients
        out[f"plan/{kind}/durations"] = plan.trajectory.durations
        samples = plan.trajectory.sample(20.0)
        out[f"plan/{kind}/samples"] = np.stack([samples[k] for k in sorted(samples)])


def rosenbrock(out: dict) -> None:
    def f(x):
        g = np.zeros_like(x)
        g[:-1] = -400 * x[:-1] * (x[1:] - x[:-1] ** 2) - 2 * (1 - x[:-1])
        g[1:] += 200 * (x[1:] - x[:-1] ** 2)
        return float(np.sum(100 * (x[1:] - x[:-1] ** 2) ** 2 + (1 - x[:-1]) ** 2)), g

    r = _core.lbfgs_minimize(f, np.array([-1.2, 1.0, -0.5, 0.8, 0.3]))
    out["lbfgs/x"] = r["x"]
    out["lbfgs/f"] = np.array([r["f"], r["iterations"], r["evaluations"]])


def main(path: str) -> None:
    out = {}
    scenes(out)
    evaluations(out)
    with tempfile.TemporaryDirectory() as folder:
        solms_and_plans(out, Path(folder))
    rosenbrock(out)
    out["arch"] = np.array(_core.ARCH)
    np.savez(path, **out)


if __name__ == "__main__":
    main(sys.argv[1])
