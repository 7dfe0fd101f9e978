"""The LIO replay's odometries side by side (docs/lio.md, "Two odometries"): every
one fed exactly the same scans and IMU samples through ``lf3pm.replay(...,
"lio", odometry=...)``, as ``lf3pm replay --method lio --odometry`` runs them.

Drives (10 Hz motion-distorted scans, 200 Hz BMI088 IMU, 2 s at rest first; each
from rest, speed ramped C2 to 1 m/s over 2 s as a plan starts):

- boxes: the boxes room, a figure of eight between the boxes with the sensor
  swinging +-0.6 rad about the direction of travel (tests/analytic_motion.py);
- houses: 15 s along the street of the houses scene, yawing at 0.1 rad/s;
- gobi town: 8 s out of the reduced gobi's town square, yawing at 0.3 rad/s;
- tunnel: 15 s from the west plaza into the tunnel (degenerate along its axis);
- hall: the boxes scene made a hall, 29 x 29 x 11 m with 40 boxes at 0.1 m spacing,
  25 s (24 m) diagonally across it yawing at 0.02 rad/s: the VLP-16's +15 degree beams
  never reach its ceiling (docs/lio.md, "LIO-SAM in a hall: a tilt"); hall3: the same
  room with a 3 m ceiling. Neither is in the default list (--scenes hall hall3).

Each runs noise-free (scans and IMU) and noisy (the sensor's range noise, the
BMI088 preset, seed 0). Printed per run: APE translation RMSE and max, scored at
the times each odometry's poses refer to, the best time shift of the truth
(trajectory_metrics.time_offset), ms per scan of the odometry alone, and how far the
estimate strayed while the sensor stood still for the rest (m; * where it was still
moving at the rest's end: ReplayResult.rest, docs/lio.md "A still sensor").

    .venv/bin/python bench/compare_odometries.py [--scenes boxes houses gobi tunnel]
    # one odometry's settings against its defaults, over noisy seeds 0-2:
    .venv/bin/python bench/compare_odometries.py --sensors mid70 --odometries genz --seeds 3 \
        --settings '{"mapping": {"voxel_size": 1.0}}'
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from analytic_motion import CurveMotion, Lissajous, TangentHeading, Warp  # noqa: E402

import lf3pm  # noqa: E402
from lf3pm.experiments.gobi import REDUCED  # noqa: E402
from lf3pm.replays.lio import ODOMETRIES, runs_on  # noqa: E402
from lf3pm.replays.motion import Motion  # noqa: E402
from lf3pm.replays.trajectory_metrics import time_offset  # noqa: E402
from lf3pm.scenes import build_scene  # noqa: E402
from lf3pm.sensors import get_sensor  # noqa: E402

RATE = 100.0  # motion samples per second, as a plan's CSV


def drive(world, start, turn_rate: float, seconds: float) -> Motion:
    """From rest at ``start`` (x, y, yaw): the speed ramps (C2) to 1 m/s over 2 s,
    the yaw turns at up to ``turn_rate`` rad/s with the same ramp (the yaw is the
    heading); sensor 1 m above the ground."""
    t = np.arange(0.0, seconds + 1e-9, 1.0 / RATE)
    v = Warp(0.0, 2.0, seconds, 1.0)(t)[1]  # never reaches its ramp down
    w = turn_rate * v

    def integral(f):
        return np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(t))])

    yaw = start[2] + integral(w)
    vx, vy = v * np.cos(yaw), v * np.sin(yaw)
    return Motion.from_arrays(
        t, start[0] + integral(vx), start[1] + integral(vy), yaw, vx, vy, w, map=world, height=1.0
    )


def figure_of_eight(world) -> Motion:
    """The boxes room's figure of eight (tests/test_lio.py's, from rest)."""
    curve = Lissajous((5.5, -0.5, 1.0), (1.2, 0.9, 0.0), (0.5, 1.0, 1.0))
    analytic = CurveMotion(Warp(0.0, 1.0, 2.5, 1.0), curve, TangentHeading(curve, swing=0.6, swing_rate=2.0))
    t = np.arange(analytic.t0, analytic.t1 + 1e-9, 1.0 / RATE)
    p, v = analytic.position(t), analytic.velocity(t)
    return Motion.from_arrays(
        t, p[:, 0], p[:, 1], analytic.yaw(t), v[:, 0], v[:, 1], analytic.yaw_rate(t), map=world, height=1.0
    )


def scenarios(names):
    """(name, map, motion) of each drive asked for."""
    for name in names:
        if name == "boxes":
            world = lf3pm.load_map(build_scene("boxes").points)
            yield name, world, figure_of_eight(world)
        elif name == "houses":
            world = lf3pm.load_map(build_scene("houses").points)
            yield name, world, drive(world, (-20.0, 0.0, 0.0), 0.1, 15.0)
        elif name == "gobi":
            world = lf3pm.load_map(build_scene("gobi", seed=REDUCED.seed, **REDUCED.scene_params).points)
            yield "gobi town", world, drive(world, (0.0, 0.0, 0.0), 0.3, 8.0)
        elif name in ("hall", "hall3"):
            height = 11.0 if name == "hall" else 3.0
            world = lf3pm.load_map(
                build_scene(
                    "boxes", room_length=29.0, room_width=29.0, room_height=height, boxes=40, spacing=0.1
                ).points
            )
            yield name, world, drive(world, (-6.0, -11.0, 0.785), 0.02, 25.0)
        elif name == "tunnel":
            world = lf3pm.load_map(build_scene("tunnel").points)
            yield name, world, drive(world, (-38.0, 0.0, 0.0), 0.0, 15.0)
        else:
            raise SystemExit(f"unknown scene {name!r}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["boxes", "houses", "gobi", "tunnel"])
    parser.add_argument("--sensors", nargs="+", default=["vlp16", "mid70"])
    parser.add_argument("--odometries", nargs="+", default=list(ODOMETRIES), choices=list(ODOMETRIES))
    parser.add_argument("--seeds", type=int, default=1, help="Noisy runs on seeds 0 .. N-1.")
    parser.add_argument(
        "--settings",
        type=json.loads,
        default=None,
        help="Odometry settings (JSON) run beside the defaults, e.g. GenZ-LIO's by section.",
    )
    args = parser.parse_args()
    variants = [("defaults", {})] + ([("settings", args.settings)] if args.settings else [])
    columns = [(odometry, label, settings) for odometry in args.odometries for label, settings in variants]
    print(
        f"{'scene':10s} {'sensor':7s} {'data':10s}"
        + "".join(
            f" | {odometry + (' ' + label if args.settings else '') + ' APE rmse/max (m)':>34s} {'shift s':>7s}"
            f" {'aligned':>7s} {'tilt':>5s} {'ms/scan':>7s} {'rest m':>7s}"
            for odometry, label, _ in columns
        )
    )
    for scene, world, motion in scenarios(args.scenes):
        for sensor in args.sensors:
            runs = [("noise-free", 0, {"noise": 0.0, "imu_noise": False})]
            runs += [(f"noisy s{seed}" if args.seeds > 1 else "noisy", seed, {}) for seed in range(args.seeds)]
            for label, seed, noise in runs:
                row = f"{scene:10s} {sensor:7s} {label:10s}"
                for odometry, _, settings in columns:
                    if not runs_on(odometry, get_sensor(sensor)):
                        row += f" | {'n/a (no rings)':>34s} {'':7s} {'':7s} {'':5s} {'':7s} {'':7s}"
                        continue
                    result = lf3pm.replay(
                        world, motion, sensor, "lio", seed=seed, odometry=odometry, **noise, **settings
                    )
                    shift = time_offset(result.times, result.estimate, motion.pose)["offset"]
                    rest = f"{result.rest['drift_m']:.3f}" + ("" if result.rest["steady"] else "*")
                    up = result.estimate[-1, :3, 2] @ result.truth[-1, :3, 2]
                    tilt = np.degrees(np.arccos(np.clip(up, -1.0, 1.0)))
                    row += (
                        f" | {result.ape['rmse']:20.3f} / {result.ape['max']:9.3f} {shift:+7.3f} "
                        f"{result.ape_aligned['rmse']:7.3f} {tilt:5.2f} "
                        f"{result.seconds_per_scan['estimate'] * 1e3:7.1f} {rest:>7s}"
                    )
                print(row, flush=True)


if __name__ == "__main__":
    main()
