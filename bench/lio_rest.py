"""A still sensor through the LIO replay (docs/lio.md, "A still sensor"): what each
odometry's estimate does while the sensor stands still, the known answer being
that it does not move.

Part 1, rests: on each map, ``--poses`` seeded free poses (sensor 1 m above the
ground, random yaw); at each, the replay's 2 s rest and one more second still
(lf3pm.replay_rest: the LIO on the rest alone, as every replay starts), both
odometries, noise-free (scans and IMU) and noisy (the sensor's range noise, the
BMI088 preset, seeds 0..``--seeds``-1). Printed per map, sensor, odometry and noise:
the median and largest drift of the estimate from the truth, and how many rests
ended moving faster than REST_SPEED_LIMIT (unsteady).

Part 2, identical scans (``--identical``): GenZ-LIO fed the first noise-free scan
of a still sensor again and again, with the still IMU: nothing changes between
scans, so any motion of the estimate is the odometry's own. Printed: the
estimate's rotation and translation after each of its first LiDAR updates, and the
standard deviation of its rotation state just before the first one.

    .venv/bin/python bench/lio_rest.py [--maps gobi boxes orientation corridor field] [--poses 6] [--seeds 2]
        [--odometries genz dlio]
    .venv/bin/python bench/lio_rest.py --identical
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import lf3pm  # noqa: E402
from lf3pm.experiments.benefit import CASES  # noqa: E402
from lf3pm.experiments.free_poses import random_free_poses  # noqa: E402
from lf3pm.experiments.gobi import REDUCED  # noqa: E402
from lf3pm.replays.motion import Motion  # noqa: E402
from lf3pm.replays.replay import replay_rest  # noqa: E402
from lf3pm.scenes import build_scene  # noqa: E402

#: Seconds the sensor stays still after the replay's rest (the "trajectory").
STILL = 1.0


def load(name: str):
    """(Map, sensor preset, region to draw poses in) of a study map, or the boxes room."""
    if name == "boxes":
        world = lf3pm.load_map(build_scene("boxes").points)
        lower, upper = world.bounds
        return world, "mid70", (lower[0] + 1, lower[1] + 1, upper[0] - 1, upper[1] - 1)
    if name == "gobi":
        world = lf3pm.load_map(build_scene("gobi", seed=REDUCED.seed, **REDUCED.scene_params).points)
        return world, "mid70", (-10.0, -10.0, 10.0, 10.0)  # the town square, where plans start
    case = next(c for c in CASES if c.name == name)
    from lf3pm.experiments.map_cases import load_case_map

    world, _ = load_case_map(case)
    lower, upper = world.bounds
    return world, case.sensor, case.bounds or (lower[0] + 2, lower[1] + 2, upper[0] - 2, upper[1] - 2)


def still(world, pose) -> Motion:
    t = np.linspace(0.0, STILL, 11)
    x, y, _, yaw = pose
    return Motion.from_arrays(
        t,
        np.full_like(t, x),
        np.full_like(t, y),
        np.full_like(t, yaw),
        np.zeros_like(t),
        np.zeros_like(t),
        np.zeros_like(t),
        map=world,
        height=1.0,
    )


def rests(maps, poses: int, seeds: int, odometries) -> None:
    print("| map | sensor | odometry | noise | rests | drift median / max (m) | unsteady |")
    print("|---|---|---|---|---|---|---|")
    for name in maps:
        world, sensor, region = load(name)
        picked = random_free_poses(world, poses, np.random.default_rng(7), sensor_height=1.0, region=region)
        for odometry in odometries:
            for noisy in (False, True):
                rows = [
                    replay_rest(
                        world,
                        still(world, p),
                        sensor,
                        seed,
                        odometry=odometry,
                        **({} if noisy else {"noise": 0.0, "imu_noise": False}),
                    )
                    for p in picked
                    for seed in (range(seeds) if noisy else [0])
                ]
                drift = np.array([r["drift_m"] for r in rows])
                unsteady = sum(not r["steady"] for r in rows)
                print(
                    f"| {name} | {sensor} | {odometry} | {'noisy' if noisy else 'none'} | {len(rows)} | "
                    f"{np.median(drift):.3f} / {drift.max():.3f} | {unsteady} |",
                    flush=True,
                )


def identical(scans_fed: int = 8) -> None:
    """GenZ-LIO on one noise-free scan of a still Mid-70, repeated, in the boxes room."""
    from scipy.spatial.transform import Rotation

    from lf3pm.replays._lio_worker import GenZ
    from lf3pm.replays.imu import simulate_imu
    from lf3pm.replays.lio import _imu_rows, _settings
    from lf3pm.replays.motion import RestFirst
    from lf3pm.scan.scans import ScanStream
    from lf3pm.sensors import get_sensor

    world, _, region = load("boxes")
    sensor = get_sensor("mid70")
    print("| pose | first updates: rotation (deg), translation (m) | rotation sigma before (rad) |")
    print("|---|---|---|")
    for pose in random_free_poses(world, 4, np.random.default_rng(7), sensor_height=1.0, region=region):
        motion = RestFirst(still(world, pose), 2.0)
        scans = ScanStream(world, motion, sensor, seed=0, noise=0.0, threads=1)
        imu = simulate_imu(motion, seed=0, noise=False)
        t, rows = _imu_rows(imu)
        # Configured as the replay's worker configures it, lf3pm's settings included.
        odometry = GenZ((sensor.min_range, sensor.max_range), 1, _settings("genz", sensor, imu, {})).odometry
        scan, before, moves, sigma = scans[0], 0, [], math.nan
        for k in range(scans_fed):
            end = float(scans.times[k])
            stamps = np.asarray(scan.stamps) - scan.end + end
            upto = int(np.searchsorted(t, end, side="right"))
            if odometry.map_size > 0 and math.isnan(sigma):
                sigma = float(np.sqrt(np.diag(np.asarray(odometry.covariance))[3:6]).max())  # the rotation block
            seeded = odometry.map_size > 0
            odometry.register_scan(
                np.ascontiguousarray(scan.points, dtype=np.float64),
                float(stamps[0]),
                end,
                np.column_stack([t[before:upto], rows[before:upto]]),
                timestamps=stamps - stamps[0],
            )
            before = upto
            if seeded:
                p = np.asarray(odometry.lidar_pose)
                moves.append(
                    f"{np.degrees(np.linalg.norm(Rotation.from_matrix(p[:3, :3]).as_rotvec())):.2f}, "
                    f"{np.linalg.norm(p[:3, 3]):.3f}"
                )
        label = f"({pose[0]:.1f}, {pose[1]:.1f}, yaw {math.degrees(pose[3]):.0f} deg)"
        print(f"| {label} | {'; '.join(moves[:4])} | {sigma:.2f} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--maps", nargs="+", default=["gobi", "boxes", "orientation", "corridor", "field"])
    parser.add_argument("--poses", type=int, default=6)
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--odometries", nargs="+", default=["genz", "dlio"], choices=["genz", "dlio"])
    parser.add_argument("--identical", action="store_true", help="part 2 only")
    args = parser.parse_args()
    if args.identical:
        identical()
    else:
        rests(args.maps, args.poses, args.seeds, args.odometries)


if __name__ == "__main__":
    main()
