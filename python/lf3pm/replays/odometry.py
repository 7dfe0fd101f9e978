"""LiDAR-only odometry on the replay's scans: KISS-ICP (the PyPI package
``kiss-icp``, an odometry independent of lf3pm's own code).

:func:`run_kiss_icp` feeds a scan stream (scans.py) to KISS-ICP frame by
frame; :func:`replay_odometry` replays a sampled trajectory (poses
interpolated linearly between samples) through it and scores the estimate
(trajectory_metrics.py). With motion distortion (the default) the rays of scan
k fire over the 1/rate s that end at its time, each from the pose at its own
firing time, and KISS-ICP deskews them from per-point timestamps
(moving_scan.py); without, every scan is taken at a single pose and KISS-ICP's
deskewing is off. The estimate is anchored at the true first pose:
estimate_k = T_0 K_k, with K_k KISS-ICP's pose of scan k relative to its first
frame, compared with the true pose at scan k's time (its last ray).
"""

from __future__ import annotations

import math
import time

import numpy as np

from lf3pm.config import DEFAULTS
from lf3pm.errors import Lf3pmError
from lf3pm.map import Map, as_map
from lf3pm.pose import pose_matrix
from lf3pm.replays.replay_result import Estimate, ReplayResult, library_versions
from lf3pm.scan.scans import ScanStream
from lf3pm.sensors import Sensor, as_sensor
from lf3pm.trajectory.sampling import LinearMotion


def kiss_icp_config(
    sensor: Sensor,
    *,
    voxel_size: float = DEFAULTS.kiss_icp.voxel_size,
    deskew: bool = False,
    threads: int = DEFAULTS.scan.threads,
):
    """KISS-ICP configuration for ``sensor``: its range limits, ``deskew`` (on
    for motion-distorted scans with per-point timestamps), ``voxel_size`` for
    the local map (KISS-ICP's own choice for outdoor 100 m LiDARs is 1 m;
    smaller suits rooms)."""
    from kiss_icp.config import KISSConfig
    from kiss_icp.config.config import DataConfig, MappingConfig, RegistrationConfig

    return KISSConfig(
        data=DataConfig(max_range=sensor.max_range, min_range=sensor.min_range, deskew=bool(deskew)),
        mapping=MappingConfig(voxel_size=float(voxel_size)),
        registration=RegistrationConfig(max_num_threads=int(threads)),
    )


def run_kiss_icp(
    scans,
    sensor: Sensor,
    initial_pose,
    *,
    voxel_size: float = DEFAULTS.kiss_icp.voxel_size,
    deskew: bool = True,
    min_points: int = DEFAULTS.kiss_icp.min_points,
    threads: int = DEFAULTS.scan.threads,
    progress=None,
) -> Estimate:
    """KISS-ICP over ``scans`` (MovingScan objects, e.g. a ScanStream), anchored
    at ``initial_pose`` (4 x 4, the true pose of the first scan). A scan with
    fewer than ``min_points`` hits is not given to KISS-ICP (its estimate stays
    where it was). ``progress``, if given, is called as progress(done, total).
    The Estimate's seconds are those spent in KISS-ICP."""
    from kiss_icp.kiss_icp import KissICP

    if not (math.isfinite(voxel_size) and voxel_size > 0):
        raise Lf3pmError(f"the KISS-ICP voxel size must be > 0, got {voxel_size}")
    if min_points < 1:
        raise Lf3pmError(f"min_points must be >= 1, got {min_points}")
    odometry = KissICP(kiss_icp_config(sensor, voxel_size=voxel_size, deskew=deskew, threads=threads))
    anchor = np.asarray(initial_pose, dtype=np.float64)
    estimate = np.empty((len(scans), 4, 4))
    hits = np.zeros(len(scans), dtype=np.int64)
    skipped, seconds = [], 0.0
    for k, scan in enumerate(scans):
        hits[k] = len(scan.points)
        start = time.perf_counter()
        if len(scan.points) < min_points:
            skipped.append(k)
        else:
            # KISS-ICP rescales the timestamps by their spread, which one point lacks.
            stamps = scan.timestamps if deskew and len(scan.points) > 1 else np.empty(0)
            odometry.register_frame(np.ascontiguousarray(scan.points, dtype=np.float64), stamps)
        seconds += time.perf_counter() - start
        estimate[k] = anchor @ odometry.last_pose
        if progress is not None:
            progress(k + 1, len(scans))
    return Estimate(poses=estimate, hits=hits, skipped=skipped, seconds=seconds)


def replay_odometry(
    map: Map | str,
    t,
    poses,
    sensor: Sensor | str = DEFAULTS.sensor,
    *,
    rate: float = DEFAULTS.replay.rate,
    seed: int = DEFAULTS.scan.seed,
    noise: float | None = DEFAULTS.scan.noise,
    voxel_size: float = DEFAULTS.kiss_icp.voxel_size,
    min_points: int = DEFAULTS.kiss_icp.min_points,
    motion_distortion: bool = True,
    deskew: bool | None = None,
    threads: int = DEFAULTS.scan.threads,
    progress=None,
) -> ReplayResult:
    """Replays the trajectory (t (N,), poses (N, 4) of x y z yaw, z absolute,
    interpolated linearly) on ``map`` with simulated ``sensor`` scans at
    ``rate`` Hz through KISS-ICP.

    Scans are taken at t[0] + k / rate up to t[-1]. noise: range noise sigma in
    metres (default: the sensor's). ``motion_distortion``: each ray cast from
    the pose at its own firing time (scan k's rays spread over the 1/rate s
    ending at its time); False: each scan at one pose. ``deskew``: KISS-ICP's
    deskewing from the per-point timestamps (default: on exactly when
    ``motion_distortion`` is). Others as :func:`run_kiss_icp`.
    Raises Lf3pmError for a malformed trajectory, a pose outside the map's x-y
    extent or bad parameters.
    """
    map, sensor = as_map(map), as_sensor(sensor)
    motion = LinearMotion(t, poses)
    # The map's x-y box is convex, so checking the given poses covers the interpolated ones.
    for pose in motion.poses:
        map.check_pose(pose_matrix(pose), clearance=0.0)
    scans = ScanStream(
        map, motion, sensor, rate=rate, seed=seed, noise=noise, distortion=motion_distortion, threads=threads
    )
    deskew = bool(motion_distortion) if deskew is None else bool(deskew)
    run = run_kiss_icp(
        scans,
        sensor,
        scans.truth[0],
        voxel_size=voxel_size,
        deskew=deskew,
        min_points=min_points,
        threads=threads,
        progress=progress,
    )
    params = {
        "rate": float(rate),
        "seed": int(seed),
        "noise_stream": "scan index",
        "noise": scans.noise,
        "min_points": min_points,
        "motion_distortion": bool(motion_distortion),
        "kiss_icp": kiss_icp_params(sensor, voxel_size, deskew),
    }
    return ReplayResult.from_run(
        run,
        method="odometry",
        sensor=sensor.name,
        seed=int(seed),
        scans=scans,
        params=params,
        map_sha256=map.sha256,
        versions=library_versions("kiss-icp"),
    )


def kiss_icp_params(sensor: Sensor, voxel_size: float, deskew: bool) -> dict:
    """The KISS-ICP settings a replay records."""
    return {
        "voxel_size": float(voxel_size),
        "max_range": sensor.max_range,
        "min_range": sensor.min_range,
        "deskew": bool(deskew),
    }
