"""Recorded runs made for tests: a folder of scans (NPY, named by time) with TUM poses, and a
replay's bag (`lf3pm replay --bag`'s writer)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
from analytic_scenes import box_room

import lf3pm
from lf3pm.pose import pose_matrix
from lf3pm.replays.bag import write_bag
from lf3pm.replays.motion import Motion
from lf3pm.scan.scan_simulator import simulate_scan
from lf3pm.scan.scans import ScanStream
from lf3pm.sensors import get_sensor


def write_run(folder, scans, poses, stamps):
    """A run folder: scan i (points in the LiDAR frame) recorded at ``stamps[i]`` at the
    planar pose ``poses[i]`` = (x, y, yaw), in TUM form. Returns the folder."""
    (folder / "scans").mkdir(parents=True)
    lines = []
    for points, (x, y, yaw), t in zip(scans, poses, stamps, strict=True):
        np.save(folder / "scans" / f"{t:.1f}.npy", np.asarray(points, dtype=np.float64))
        lines.append(f"{t:.1f} {x!r} {y!r} 0 0 0 {math.sin(yaw / 2)!r} {math.cos(yaw / 2)!r}")
    (folder / "poses_tum.txt").write_text("\n".join(lines) + "\n")
    return folder


def pillar_room():
    """A 12 x 8 x 3 m box room with a pillar (so no symmetry), indexed."""
    pillar = box_room((0.3, 0.3, 1.5), spacing=0.1) + [2.5, 1.5, 0.0]
    return lf3pm.load_map(np.unique(np.round(np.vstack([box_room((6.0, 4.0, 1.5), 0.1), pillar]), 9), axis=0))


def simulated_run(folder, world, poses, stamps, sensor="vlp16"):
    """Noise-free scans of ``sensor`` on ``world`` at ``poses`` (x, y, yaw) written as a run
    folder; returns (folder, the scans' hits in the world, N x 3)."""
    model = get_sensor(sensor)
    scans = [
        simulate_scan(world, pose_matrix((x, y, 0.0, yaw)), model.directions, model.min_range, model.max_range)
        for x, y, yaw in poses
    ]
    write_run(folder, [s.sensor_points for s in scans], poses, stamps)
    return folder, np.vstack([s.world_points for s in scans])


def stream_bag(world, folder, *, moving: bool, noise: float | None, sensor="vlp16"):
    """A replay's ROS 2 bag of ``sensor`` over 0.4 s at 10 Hz (moving at 1 m/s or standing),
    as `lf3pm replay --bag` writes it; returns (path, stream)."""
    t = np.linspace(0.0, 0.4, 41)
    speed = 1.0 if moving else 0.0
    motion = Motion.from_arrays(
        t,
        -1.0 + speed * t,
        0 * t,
        0.1 * speed * t,
        np.full_like(t, speed),
        0 * t,
        np.full_like(t, 0.1 * speed),
        map=world,
    )
    stream = ScanStream(world, motion, get_sensor(sensor), rate=10.0, seed=4, noise=noise)
    imu_t = np.arange(0.0, 0.4 + 1e-9, 0.01)
    imu = SimpleNamespace(t=imu_t, accel=np.tile([0.0, 0.0, 9.81], (len(imu_t), 1)), gyro=np.zeros((len(imu_t), 3)))
    path = folder / "stream.bag"
    write_bag(path, stream, imu, truth_rate=100.0)
    return path, stream
