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

import time

import numpy as np

from lf3pm.config import DEFAULTS, KissIcpConfig, validated
from lf3pm.map import Map, as_map
from lf3pm.pose import pose_matrix
from lf3pm.replays.replay_result import (
    Estimate,
    MethodRun,
    ReplayResult,
    SectionMethod,
    library_versions,
)
from lf3pm.scan.scans import ScanStream
from lf3pm.sensors import Sensor, as_sensor
from lf3pm.trajectory.sampling import LinearMotion


def kiss_icp_config(sensor: Sensor, settings: KissIcpConfig = DEFAULTS.kiss_icp, threads: int = DEFAULTS.scan.threads):
    """KISS-ICP configuration for ``sensor``: its range limits, ``settings.deskew`` (on
    for motion-distorted scans with per-point timestamps), ``settings.voxel_size`` for
    the local map (KISS-ICP's own choice for outdoor 100 m LiDARs is 1 m; smaller suits
    rooms)."""
    from kiss_icp.config import KISSConfig
    from kiss_icp.config.config import DataConfig, MappingConfig, RegistrationConfig

    return KISSConfig(
        data=DataConfig(max_range=sensor.max_range, min_range=sensor.min_range, deskew=bool(settings.deskew)),
        mapping=MappingConfig(voxel_size=float(settings.voxel_size)),
        registration=RegistrationConfig(max_num_threads=int(threads)),
    )


def run_kiss_icp(
    scans,
    sensor: Sensor,
    initial_pose,
    settings: KissIcpConfig = DEFAULTS.kiss_icp,
    *,
    threads: int = DEFAULTS.scan.threads,
    progress=None,
) -> Estimate:
    """KISS-ICP with ``settings`` over ``scans`` (MovingScan objects, e.g. a ScanStream,
    or any iterable of objects with ``points`` and ``timestamps``, read one at a time),
    anchored at ``initial_pose`` (4 x 4, the true pose of the first scan). A scan with
    fewer than ``settings.min_points`` hits is not given to KISS-ICP (its estimate stays
    where it was). ``progress``, if given, is called as progress(done, total) (total
    None for an iterable without a length). The Estimate's seconds are those spent in
    KISS-ICP. ``threads`` holds for the first KISS-ICP a process builds only: its
    Registration sets TBB's thread limit once, in a static global_control, so a later call
    with other ``threads`` runs with the first one's (measured: threads=1 after a threads=0
    run gives poses that differ at 4e-16 between two calls, from TBB's reduction order)."""
    from kiss_icp.kiss_icp import KissICP

    odometry = KissICP(kiss_icp_config(sensor, settings, threads))
    min_points, deskew = settings.min_points, settings.deskew
    anchor = np.asarray(initial_pose, dtype=np.float64)
    total = len(scans) if hasattr(scans, "__len__") else None
    estimate, hits, skipped, seconds = [], [], [], 0.0
    for k, scan in enumerate(scans):
        hits.append(len(scan.points))
        start = time.perf_counter()
        if len(scan.points) < min_points:
            skipped.append(k)
        else:
            # KISS-ICP rescales the timestamps by their spread, which one point lacks.
            stamps = scan.timestamps if deskew and len(scan.points) > 1 else np.empty(0)
            odometry.register_frame(np.ascontiguousarray(scan.points, dtype=np.float64), stamps)
        seconds += time.perf_counter() - start
        estimate.append(anchor @ odometry.last_pose)
        if progress is not None:
            progress(k + 1, total)
    poses = np.asarray(estimate, dtype=np.float64).reshape(-1, 4, 4)
    return Estimate(poses=poses, hits=np.asarray(hits, dtype=np.int64), skipped=skipped, seconds=seconds)


class KissIcpOdometry(SectionMethod):
    """The ``odometry`` replay method (lf3pm.replays.methods.ReplayMethod): KISS-ICP with
    ``settings`` (a KissIcpConfig) on the replay's scans."""

    name = "odometry"
    section = "kiss_icp"

    def prepare(self, map, threads: int, prepared=None):
        return None

    def run(self, scans, motion, sensor: Sensor, seed: int, *, prepared, threads: int, progress=None) -> MethodRun:
        run = run_kiss_icp(scans, sensor, scans.truth[0], self.settings, threads=threads, progress=progress)
        params = {"min_points": self.settings.min_points, "kiss_icp": kiss_icp_params(sensor, self.settings)}
        return MethodRun(run, params, library_versions("kiss-icp"))


def replay_odometry(
    map: Map | str,
    t,
    poses,
    sensor: Sensor | str = DEFAULTS.sensor,
    *,
    rate: float = DEFAULTS.replay.rate,
    seed: int = DEFAULTS.scan.seed,
    noise: float | None = DEFAULTS.scan.noise,
    kiss_icp: KissIcpConfig = DEFAULTS.kiss_icp,
    voxel_size: float | None = None,
    min_points: int | None = None,
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
    ``motion_distortion`` is). ``kiss_icp``: KISS-ICP's section, ``voxel_size`` and
    ``min_points`` (None: the section's) over it. Others as :func:`run_kiss_icp`.
    Raises Lf3pmError for a malformed trajectory, a pose outside the map's x-y
    extent or bad parameters.
    """
    given = {"voxel_size": voxel_size, "min_points": min_points}
    deskew = bool(motion_distortion) if deskew is None else bool(deskew)
    settings = validated(
        KissIcpConfig,
        "kiss_icp",
        **{**kiss_icp.model_dump(), **{k: v for k, v in given.items() if v is not None}, "deskew": deskew},
    )
    map, sensor = as_map(map), as_sensor(sensor)
    motion = LinearMotion(t, poses)
    # The map's x-y box is convex, so checking the given poses covers the interpolated ones.
    for pose in motion.poses:
        map.check_pose(pose_matrix(pose), clearance=0.0)
    scans = ScanStream(
        map, motion, sensor, rate=rate, seed=seed, noise=noise, distortion=motion_distortion, threads=threads
    )
    run = run_kiss_icp(scans, sensor, scans.truth[0], settings, threads=threads, progress=progress)
    params = {
        "rate": float(rate),
        "seed": int(seed),
        "noise_stream": "scan index",
        "noise": scans.noise,
        "min_points": settings.min_points,
        "motion_distortion": bool(motion_distortion),
        "kiss_icp": kiss_icp_params(sensor, settings),
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


def kiss_icp_params(sensor: Sensor, settings: KissIcpConfig) -> dict:
    """The KISS-ICP settings a replay records."""
    return {
        "voxel_size": float(settings.voxel_size),
        "max_range": sensor.max_range,
        "min_range": sensor.min_range,
        "deskew": bool(settings.deskew),
    }
