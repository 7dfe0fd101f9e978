"""Odometry replay: simulated scans along a trajectory, fed to KISS-ICP (the
PyPI package ``kiss-icp``, an odometry independent of lf3pm's own code), and
the estimate compared with the truth by APE and RPE (trajectory_metrics.py).

Scans: one every 1/``rate`` s, poses interpolated from the given time series.
With motion distortion (the default) the rays of scan k fire over the 1/rate s
that end at its time, each from the pose at its own firing time, and KISS-ICP
deskews them from per-point timestamps (moving_scan.py); without, every scan is
taken at a single pose and KISS-ICP's deskewing is off. Scan k uses noise
stream k of ``seed``. The estimate is anchored at the true first pose:
estimate_k = T_0 K_k, with K_k KISS-ICP's pose of scan k relative to its first
frame, compared with the true pose at scan k's time (its last ray).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from lf3pm import _core
from lf3pm.errors import Lf3pmError
from lf3pm.evaluation.moving_scan import simulate_moving_scan
from lf3pm.evaluation.trajectory import check_trajectory, interpolate_poses
from lf3pm.evaluation.trajectory_metrics import ape_translation, rpe
from lf3pm.map import Map, load_map
from lf3pm.pose import pose_matrix
from lf3pm.sensors import Sensor, get_sensor

#: Most scans one replay simulates: beyond this a typo in a rate or a time
#: would run for hours.
MAX_SCANS = 100_000


@dataclass(frozen=True)
class OdometryResult:
    """A replay: true and estimated poses per scan, the errors and what produced them.

    ``truth`` and ``estimate`` are (M, 4, 4) sensor-to-world matrices at
    ``times``. ``skipped`` lists the scans with fewer than ``min_points`` hits:
    KISS-ICP did not see them and kept its last estimate. ``ape`` is without
    alignment (the estimate starts at the true first pose), ``ape_aligned``
    after the SE(3) Umeyama alignment; ``rpe_frame`` uses a delta of one scan,
    ``rpe_metre`` one metre of path. ``seconds_per_scan`` splits the wall time
    into scan simulation and KISS-ICP.
    """

    times: np.ndarray = field(repr=False)
    truth: np.ndarray = field(repr=False)
    estimate: np.ndarray = field(repr=False)
    hits: np.ndarray = field(repr=False)
    skipped: list
    ape: dict
    ape_aligned: dict
    rpe_frame: dict
    rpe_metre: dict
    seconds_per_scan: dict
    sensor: str
    params: dict

    @property
    def scans(self) -> int:
        return len(self.times)

    def to_dict(self, trajectories: bool = False) -> dict:
        """JSON-ready summary (per-pose error lists dropped, NaN as None); with
        ``trajectories`` the times and x y z of truth and estimate as well."""
        def clean(value):
            if isinstance(value, dict):
                return {k: clean(v) for k, v in value.items() if k not in ("errors", "alignment")}
            if isinstance(value, float) and not math.isfinite(value):
                return None
            return value
        out = {"scans": self.scans, "skipped": list(self.skipped), "ape": clean(self.ape),
               "ape_aligned": clean(self.ape_aligned), "rpe_frame": clean(self.rpe_frame),
               "rpe_metre": clean(self.rpe_metre), "seconds_per_scan": clean(self.seconds_per_scan),
               "sensor": self.sensor, "params": self.params}
        if trajectories:
            out["times"] = self.times.tolist()
            out["truth_xyz"] = self.truth[:, :3, 3].tolist()
            out["estimate_xyz"] = self.estimate[:, :3, 3].tolist()
        return out


def kiss_icp_config(sensor: Sensor, *, voxel_size: float = 1.0, deskew: bool = False, threads: int = 0):
    """KISS-ICP configuration for ``sensor``: its range limits, ``deskew`` (on
    for motion-distorted scans with per-point timestamps), ``voxel_size`` for
    the local map (KISS-ICP's own choice for outdoor 100 m LiDARs is 1 m;
    smaller suits rooms)."""
    from kiss_icp.config import KISSConfig
    from kiss_icp.config.config import DataConfig, MappingConfig, RegistrationConfig

    return KISSConfig(data=DataConfig(max_range=sensor.max_range, min_range=sensor.min_range, deskew=bool(deskew)),
                      mapping=MappingConfig(voxel_size=float(voxel_size)),
                      registration=RegistrationConfig(max_num_threads=int(threads)))


def replay_odometry(map: Map | str, t, poses, sensor: Sensor | str = "vlp16", *, rate: float = 10.0,
                    seed: int = 0, noise: float | None = None, voxel_size: float = 1.0,
                    min_points: int = 100, motion_distortion: bool = True, deskew: bool | None = None,
                    threads: int = 0, progress=None) -> OdometryResult:
    """Replays the trajectory (t (N,), poses (N, 4) of x y z yaw, z absolute) on
    ``map`` with simulated ``sensor`` scans at ``rate`` Hz through KISS-ICP.

    Scans are taken at t[0] + k / rate up to t[-1]. noise: range noise sigma in
    metres (default: the sensor's). A scan with fewer than ``min_points`` hits
    is not given to KISS-ICP (its estimate stays where it was) and is listed in
    ``skipped``. ``motion_distortion``: each ray cast from the pose at its own
    firing time (scan k's rays spread over the 1/rate s ending at its time);
    False: each scan at one pose. ``deskew``: KISS-ICP's deskewing from the
    per-point timestamps (default: on exactly when ``motion_distortion`` is).
    ``progress``, if given, is called as progress(done, total).
    Raises Lf3pmError for a malformed trajectory, a pose outside the map's x-y
    extent or bad parameters.
    """
    from kiss_icp.kiss_icp import KissICP

    if not isinstance(map, Map):
        map = load_map(map)
    if not isinstance(sensor, Sensor):
        sensor = get_sensor(sensor)
    t, poses = check_trajectory(t, poses)
    if not (math.isfinite(rate) and rate > 0):
        raise Lf3pmError(f"the scan rate must be > 0 Hz, got {rate}")
    if not (math.isfinite(voxel_size) and voxel_size > 0):
        raise Lf3pmError(f"the KISS-ICP voxel size must be > 0, got {voxel_size}")
    if min_points < 1:
        raise Lf3pmError(f"min_points must be >= 1, got {min_points}")
    sigma = sensor.range_noise_sigma if noise is None else float(noise)
    if not sigma >= 0:
        raise Lf3pmError(f"range noise must be >= 0, got {noise}")
    count = int(math.floor((t[-1] - t[0]) * rate + 1e-9)) + 1
    if count < 2:
        raise Lf3pmError(f"the trajectory spans {t[-1] - t[0]:g} s: fewer than 2 scans at {rate} Hz")
    if count > MAX_SCANS:
        raise Lf3pmError(f"{count} scans at {rate} Hz over {t[-1] - t[0]:g} s: more than {MAX_SCANS}")
    # The map's x-y box is convex, so checking the given poses covers the interpolated ones.
    for pose in poses:
        map.check_pose(pose_matrix(pose), clearance=0.0)

    times = t[0] + np.arange(count) / rate
    truth = np.stack([pose_matrix(p) for p in interpolate_poses(t, poses, np.minimum(times, t[-1]))])
    deskew = bool(motion_distortion) if deskew is None else bool(deskew)
    odometry = KissICP(kiss_icp_config(sensor, voxel_size=voxel_size, deskew=deskew, threads=threads))
    estimate = np.empty_like(truth)
    hits = np.zeros(count, dtype=np.int64)
    skipped, sim_time, reg_time = [], 0.0, 0.0
    for k in range(count):
        start = time.perf_counter()
        if motion_distortion:
            scan = simulate_moving_scan(map.index, t, poses, times[k], 1.0 / rate, sensor.scan_directions(k),
                                        sensor.min_range, sensor.max_range, noise=sigma, seed=seed, stream=k,
                                        threads=threads)
            # KISS-ICP rescales the timestamps by their spread, which one point lacks.
            points, stamps = scan.points, scan.timestamps if len(scan.ray) > 1 else np.empty(0)
        else:
            scan = _core.simulate_scan(map.index, truth[k], sensor.scan_directions(k), sensor.min_range,
                                       sensor.max_range, noise=sigma, seed=int(seed), stream=k,
                                       threads=threads)
            points = scan["sensor_points"]
            stamps = np.empty(0)  # no per-point times: KISS-ICP leaves the scan as it is
        points = np.ascontiguousarray(points, dtype=np.float64)
        sim_time += time.perf_counter() - start
        hits[k] = len(points)
        start = time.perf_counter()
        if len(points) < min_points:
            skipped.append(k)
        else:
            odometry.register_frame(points, stamps)
        reg_time += time.perf_counter() - start
        estimate[k] = truth[0] @ odometry.last_pose
        if progress is not None:
            progress(k + 1, count)

    params = {"rate": rate, "seed": int(seed), "noise_stream": "scan index", "noise": sigma,
              "min_points": min_points, "motion_distortion": bool(motion_distortion),
              "map_sha256": map.sha256,
              "kiss_icp": {"voxel_size": voxel_size, "max_range": sensor.max_range,
                           "min_range": sensor.min_range, "deskew": deskew,
                           "version": _kiss_icp_version()}}
    return OdometryResult(times=times, truth=truth, estimate=estimate, hits=hits, skipped=skipped,
                          ape=ape_translation(truth, estimate),
                          ape_aligned=ape_translation(truth, estimate, align=True),
                          rpe_frame=rpe(truth, estimate, delta=1, unit="frames"),
                          rpe_metre=rpe(truth, estimate, delta=1.0, unit="m"),
                          seconds_per_scan={"simulate": sim_time / count, "register": reg_time / count},
                          sensor=sensor.name, params=params)


def _kiss_icp_version() -> str:
    from importlib.metadata import version

    return version("kiss-icp")
