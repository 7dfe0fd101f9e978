"""Benchmark: odometry replay (simulated scans + KISS-ICP) on the gobi scene.

Prints the replay time per scan (scan simulation and KISS-ICP separately) and
the APE / RPE of a straight drive of about 100 m through the town with the
VLP-16 and the Mid-70 and across the open desert with the Mid-70, each three
ways: scans at one pose (no motion distortion, deskewing off), motion-distorted
scans with KISS-ICP's deskewing (the default) and motion-distorted scans
without it, with the ratios of the time per scan and of the APE rmse to the
first. Before that, the cost of simulating one scan both ways, timed
alternately (median over the first 100 scans of the town drive). Each drive follows
the terrain at the scene's sensor height and runs at
1 m/s, 10 Hz. The town drive is the straight line through the origin, of the
headings tried, with the most room around it; the desert drive runs along
y = 50 m.

    .venv/bin/python bench/bench_odometry_replay.py [--length 100] [--speed 1.0] [--seed 0]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import lf3pm
from lf3pm import _core
from lf3pm.config import scan_params
from lf3pm.experiments.free_poses import GroundGrid
from lf3pm.pose import pose_matrix
from lf3pm.replays.odometry import replay_odometry
from lf3pm.scan.moving_scan import simulate_moving_scan
from lf3pm.scenes import build_scene
from lf3pm.sensors import get_sensor
from lf3pm.trajectory.sampling import LinearMotion, interpolate_poses


def drive(ground: GroundGrid, start, heading: float, length: float, speed: float, height: float):
    """(t, poses) of a straight drive, sampled every 0.5 m, z = ground + height."""
    s = np.arange(0.0, length + 1e-9, 0.5)
    x = start[0] + s * math.cos(heading)
    y = start[1] + s * math.sin(heading)
    z = np.array([ground.height(a, b) for a, b in zip(x, y)]) + height
    return s / speed, np.column_stack([x, y, z, np.full_like(s, heading)])


def room(world, poses, height: float) -> float:
    """Smallest distance (m) from the drive's axis 1.5 m and 2.5 m above the ground
    (above stones and plants) to a map point, capped at 5 m."""
    probes = np.concatenate([poses[:, :3] + [0.0, 0.0, dz - height] for dz in (1.5, 2.5)])
    _, dist = world.index.nearest(np.ascontiguousarray(probes), 1, 5.0)
    return float(np.min(np.where(np.isfinite(dist[:, 0]), dist[:, 0], 5.0)))


#: (label, motion_distortion, deskew) of the replays run on every drive.
MODES = (("one pose per scan", False, False), ("distorted + deskew", True, True), ("distorted, no deskew", True, False))


def simulation_cost(world, sensor_name: str, t, poses, rate: float = 10.0, scans: int = 100) -> None:
    """Median time of one scan at one pose and of the same scan motion-distorted,
    timed alternately over the first ``scans`` scans of the drive (t, poses)."""
    sensor = get_sensor(sensor_name)
    times = t[0] + np.arange(scans) / rate
    times = times[times <= t[-1]]
    truth = interpolate_poses(t, poses, times)
    motion = LinearMotion(t, poses)
    still, moving = [], []
    for k in range(len(times)):
        dirs = sensor.scan_directions(k)
        start = time.perf_counter()
        _core.simulate_scan(
            world.index,
            pose_matrix(truth[k]),
            dirs,
            scan_params(sensor.min_range, sensor.max_range, noise=sensor.range_noise_sigma, stream=k),
        )
        still.append(time.perf_counter() - start)
        start = time.perf_counter()
        simulate_moving_scan(
            world.index,
            motion,
            times[k],
            1.0 / rate,
            dirs,
            sensor.min_range,
            sensor.max_range,
            noise=sensor.range_noise_sigma,
            stream=k,
        )
        moving.append(time.perf_counter() - start)
    a, b = 1e3 * np.median(still), 1e3 * np.median(moving)
    print(
        f"scan simulation, {sensor_name} ({sensor.num_rays} rays): one pose {a:.2f} ms, "
        f"motion-distorted {b:.2f} ms, x{b / a:.2f}"
    )


def report(label: str, result, wall: float) -> None:
    sps = result.seconds_per_scan
    print(
        f"{label}: {result.scans} scans, skipped {len(result.skipped)}, "
        f"{1e3 * (sps['simulate'] + sps['estimate']):.1f} ms/scan "
        f"(simulate {1e3 * sps['simulate']:.1f}, KISS-ICP {1e3 * sps['estimate']:.1f}), wall {wall:.1f} s"
    )
    ape, aligned = result.ape, result.ape_aligned
    print(
        f"  APE t (m): rmse {ape['rmse']:.3f} mean {ape['mean']:.3f} median {ape['median']:.3f} "
        f"max {ape['max']:.3f}; Umeyama-aligned rmse {aligned['rmse']:.3f}"
    )
    end = result.estimate[-1, :3, 3] - result.truth[-1, :3, 3]
    print(
        f"  final error (m) {np.round(end, 3).tolist()}, "
        f"RPE/frame t rmse {result.rpe_frame['translation']['rmse']:.4f} m "
        f"r rmse {result.rpe_frame['rotation_deg']['rmse']:.3f} deg, "
        f"RPE/m t rmse {result.rpe_metre['translation']['rmse']:.4f} m"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--length", type=float, default=100.0)
    parser.add_argument("--speed", type=float, default=1.0)
    parser.add_argument("--voxel", type=float, default=1.0, help="KISS-ICP voxel size (m)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the range noise")
    args = parser.parse_args()
    scene = build_scene("gobi")
    world = lf3pm.load_map(scene.points)
    height = scene.params["sensor_height"]
    ground = GroundGrid(world)
    half = args.length / 2

    best = None
    for deg in range(0, 180, 5):
        h = math.radians(deg)
        t, poses = drive(ground, (-half * math.cos(h), -half * math.sin(h)), h, args.length, args.speed, height)
        clear = room(world, poses, height)
        if best is None or clear > best[0]:
            best = (clear, deg, t, poses)
    clear, deg, t_town, town = best
    print(f"town drive: heading {deg} deg through the origin, {clear:.2f} m clear of the map")
    t_desert, desert = drive(ground, (-half, 50.0), 0.0, args.length, args.speed, height)
    print(f"desert drive: along y = 50 m, {room(world, desert, height):.2f} m clear of the map")

    for sensor in ("vlp16", "mid70"):
        simulation_cost(world, sensor, t_town, town)
    for label, sensor, t, poses in (
        ("town", "vlp16", t_town, town),
        ("town", "mid70", t_town, town),
        ("desert", "mid70", t_desert, desert),
    ):
        baseline = None
        for mode, distortion, deskew in MODES:
            start = time.perf_counter()
            result = replay_odometry(
                world,
                t,
                poses,
                sensor,
                voxel_size=args.voxel,
                seed=args.seed,
                motion_distortion=distortion,
                deskew=deskew,
            )
            report(f"{label}, {sensor}, {mode}", result, time.perf_counter() - start)
            sps = result.seconds_per_scan
            cost = (sps["simulate"], sps["simulate"] + sps["estimate"], result.ape["rmse"])
            if baseline is None:
                baseline = cost
            else:
                print(
                    f"  vs one pose per scan: simulate x{cost[0] / baseline[0]:.2f}, "
                    f"simulate + KISS-ICP x{cost[1] / baseline[1]:.2f}, APE rmse x{cost[2] / baseline[2]:.2f}"
                )


if __name__ == "__main__":
    main()
