"""Benchmark: `lf3pm replay` speed per method, and localization accuracy.

1. Speed. A diff-drive plan across the `boxes` scene (SOLM r2 at 0.5 m, VLP-16,
   start (-3, -3), goal (6.2, 2.8): about 11 m in 14 s, 143 scans at 10 Hz),
   replayed once per method. Printed per method: ms per scan for simulating
   the scans and for estimating, scans per second (both together) and the
   real-time factor, sensor rate / scans per second (above 1: slower than the
   sensor), with the APE. The baseline is the scan simulation alone (the
   stream every method consumes): the ratio says what the method adds.
2. Localization APE: the plan above (seeds 0-2, VLP-16 noise, default wheel
   odometry), and along an 80 m corridor (two walls 4 m apart and a floor, no
   end wall; 10 m straight down it at 1 m/s), whose axis is degenerate, with
   and without solution remapping.

    .venv/bin/python bench/bench_replay.py [--seeds 3] [--methods localization odometry lio]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import lf3pm
from lf3pm.errors import Lf3pmError
from lf3pm.planner.plan import Planner
from lf3pm.replays.motion import Motion
from lf3pm.replays.replay import METHODS, replay
from lf3pm.scan.scans import ScanStream
from lf3pm.scenes import build_scene
from lf3pm.solm import Solm, build_solm, make_grid
from lf3pm.trajectory.robots import Robot
from lf3pm.validation.mde import RegistrationTarget


def boxes_plan(folder: str):
    """(map, Motion) of the diff-drive plan across the boxes scene."""
    world = lf3pm.load_map(build_scene("boxes").points)
    store = f"{folder}/boxes.zarr"
    build_solm(world, lf3pm.get_sensor("vlp16"), make_grid(world, "r2", 0.5), store)
    plan = Planner(Solm.open(store)).plan(
        (-3.0, -3.0, 0.0), (6.2, 2.8, 0.0), robot=Robot("diff", r_safe=0.1), metric="q_n", weight=1.0
    )
    s = plan.trajectory.sample(100.0)
    return world, Motion.from_arrays(s["t"], s["x"], s["y"], s["yaw"], s["vx"], s["vy"], s["omega"], map=world)


def corridor():
    """(map, Motion): 80 m walls 4 m apart and a floor; 10 m along the axis at 1 m/s."""

    def plane(origin, u, v, a, b, step=0.1):
        ua, vb = np.meshgrid(np.arange(0, a + 1e-9, step), np.arange(0, b + 1e-9, step), indexing="ij")
        return np.asarray(origin) + ua.reshape(-1, 1) * np.asarray(u) + vb.reshape(-1, 1) * np.asarray(v)

    pts = np.vstack(
        [
            plane((-40, -2, 0), (1, 0, 0), (0, 0, 1), 80, 3),
            plane((-40, 2, 0), (1, 0, 0), (0, 0, 1), 80, 3),
            plane((-40, -1.9, 0), (1, 0, 0), (0, 1, 0), 80, 3.8),
        ]
    )
    world = lf3pm.load_map(np.ascontiguousarray(pts))
    t = np.linspace(0.0, 10.0, 1001)
    return world, Motion.from_arrays(t, -5 + t, 0.2 * np.sin(t), 0.1 * np.sin(t), map=world)


def speed(world, motion, methods, seed: int) -> None:
    stream = ScanStream(world, motion, lf3pm.get_sensor("vlp16"), seed=seed)
    start = time.perf_counter()
    for _scan in stream:
        pass
    baseline = (time.perf_counter() - start) / len(stream)
    print(
        f"\nboxes plan: {motion.t1 - motion.t0:.1f} s, {len(stream)} VLP-16 scans at 10 Hz; "
        f"baseline (scan simulation alone) {1e3 * baseline:.1f} ms/scan, {1 / baseline:.1f} scans/s"
    )
    print(
        f"{'method':<13} {'simulate ms':>11} {'estimate ms':>11} {'scans/s':>8} {'real-time factor':>16} "
        f"{'x baseline':>10} {'APE rmse m':>10}"
    )
    target = RegistrationTarget(world)
    for method in methods:
        try:
            r = replay(world, motion, "vlp16", method, seed, target=target if method == "localization" else None)
        except Lf3pmError as err:
            print(f"{method:<13} not run: {err}")
            continue
        sps = r.seconds_per_scan
        per_scan = sps["simulate"] + sps["estimate"]
        print(
            f"{method:<13} {1e3 * sps['simulate']:>11.1f} {1e3 * sps['estimate']:>11.1f} {1 / per_scan:>8.1f} "
            f"{10.0 * per_scan:>16.2f} {per_scan / baseline:>10.2f} {r.ape['rmse']:>10.4f}"
        )


def accuracy(world, motion, seeds: int, label: str, **params) -> None:
    target = RegistrationTarget(world)
    for remap in (True, False) if label.startswith("corridor") else (True,):
        rows = []
        for seed in range(seeds):
            r = replay(world, motion, "vlp16", "localization", seed, target=target, remap=remap, **params)
            along = np.abs(r.estimate[-1, 0, 3] - r.truth[-1, 0, 3])
            rows.append((r.ape["rmse"], r.ape["max"], along, int(r.degenerate.sum()), r.scans))
        a = np.array(rows)
        print(
            f"{label} remap {str(remap):<5} APE rmse {' / '.join(f'{v:.4f}' for v in a[:, 0])} m, "
            f"max {' / '.join(f'{v:.4f}' for v in a[:, 1])} m, final |x error| "
            f"{' / '.join(f'{v:.3f}' for v in a[:, 2])} m, degenerate scans {int(a[0, 3])}/{int(a[0, 4])}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS)
    args = parser.parse_args()
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        world, motion = boxes_plan(folder)
    speed(world, motion, args.methods, seed=0)
    print(
        f"\nlocalization APE, seeds 0-{args.seeds - 1} (VLP-16 noise, wheel odometry 2 % scale, "
        f"{0.01:g} rad/sqrt(s) yaw):"
    )
    accuracy(world, motion, args.seeds, "boxes")
    world, motion = corridor()
    accuracy(world, motion, args.seeds, "corridor")
    accuracy(world, motion, 1, "corridor, 10 % odometry scale error", scale_error=0.1)


if __name__ == "__main__":
    main()
