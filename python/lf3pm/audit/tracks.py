"""Localization and odometry along a recorded run (issue 42, item 2), each scan's estimate
against its reference pose:

- **map localization, tracking**: every scan registered to the map from the previous
  estimate (:func:`lf3pm.replays.localization.register_to_map`, the registration and
  degeneracy remapping `lf3pm replay --method localization` runs, with the localization
  section's settings), the first scan from its reference pose, as a replay starts at the
  true first pose. A recorded run has no wheel odometry to predict with, so each scan is
  first registered coarsely from the last estimate (a wider correspondence cutoff,
  :data:`COARSE_CORRESPONDENCE_M`, and more iterations, :data:`COARSE_ITERATIONS`), then
  as the localization section says. Scans are registered as recorded (not deskewed);
- **LiDAR-only odometry**: KISS-ICP (the kiss_icp section's settings, deskewing with the
  points' times where the run has them) anchored at the first scan's reference pose;
- **LiDAR-inertial odometries**, where the run has an IMU: each odometry ``lf3pm replay
  --method lio`` runs (GenZ-LIO, DLIO, LIO-SAM, a plugin's: :func:`lio_odometries`)
  through :func:`lf3pm.replays.lio.run_lio` on the recorded stream (:func:`track_lio`).

The run is read once per track, a scan at a time; a track keeps one pose per scan."""

from __future__ import annotations

import itertools
import math
import time
import warnings
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from lf3pm.config import DEFAULTS, Config
from lf3pm.errors import Lf3pmError, RunError, one_line
from lf3pm.map import Map
from lf3pm.replays.trajectory_metrics import error_stats
from lf3pm.runs import Run
from lf3pm.sensors import Sensor, as_sensor
from lf3pm.validation import RegistrationTarget

#: The tracks' names (Track.method).
TRACKING, ODOMETRY = "localization", "kiss-icp"

# The coarse registration before the localization section's, without a motion prediction.
# Measured on the real hall run (88 scans 0.5 s apart, a carrier turning up to 30 degrees
# between scans; map: the run's scans), with the 1 m cutoff alone: from a constant-velocity
# prediction the registration stopped unconverged at scan 31 (prior 25 degrees off) and the
# track was lost (APE rmse 10 m); from the last estimate it lost scans 29-31 and 34-35 (up
# to 1.1 m) and found them again. A 3 m, 60-iteration stage first, from the last estimate,
# tracks every scan (rmse 4 mm, largest 13 mm; from a constant-velocity prediction it still
# lost 3 scans, up to 2.9 m).
COARSE_CORRESPONDENCE_M = 3.0
COARSE_ITERATIONS = 60


@dataclass(frozen=True)
class Track:
    """An estimator along the run: per scan (bad scans left out) its ``stamps``, the
    estimated ``poses`` (world-from-LiDAR, 4 x 4) and ``errors_m``, the distance of each
    from the scan's reference position; ``skipped`` scans the estimator kept at its
    prediction, ``seconds`` spent estimating, the ``params`` it ran with; ``message``: one
    line where the estimator failed or lost track (its errors there NaN), else None."""

    method: str
    stamps: np.ndarray
    poses: np.ndarray
    errors_m: np.ndarray
    skipped: int
    seconds: float
    params: dict = field(default_factory=dict)
    message: str | None = None

    @property
    def ape(self) -> dict:
        """The translation errors' statistics (rmse, mean, median, max, min, std, count; m)
        over the scans with an error (NaN where the track lost them)."""
        return error_stats(self.errors_m[np.isfinite(self.errors_m)])

    def error_at(self, stamp: float) -> float:
        """The error at the scan recorded at ``stamp`` (NaN where the track has none)."""
        at = np.flatnonzero(self.stamps == stamp)
        return float(self.errors_m[at[0]]) if at.size else float("nan")

    def to_dict(self) -> dict:
        """JSON-ready: what ran and its APE (None where it has none; the per-scan errors are in
        the scans' records)."""
        return {
            "method": self.method,
            "scans": len(self.stamps),
            "skipped": self.skipped,
            "seconds": self.seconds,
            "ape_m": {k: None if isinstance(v, float) and not math.isfinite(v) else v for k, v in self.ape.items()},
            "params": self.params,
            "message": self.message,
        }


def _errors(poses: np.ndarray, reference: np.ndarray) -> np.ndarray:
    return np.linalg.norm(poses[:, :3, 3] - reference[:, :3, 3], axis=1)


def track_localization(
    run,
    map: Map,
    sensor: Sensor | str = DEFAULTS.sensor,
    config: Config | None = None,
    *,
    target: RegistrationTarget | None = None,
    progress: Callable[[int, int | None], None] | None = None,
) -> Track:
    """Map localization tracking along ``run`` on ``map`` (module docstring); ``sensor``'s
    range noise judges degeneracy; ``target``: the map prepared for registration (built
    here when None). ``progress(read, total)`` after each scan."""
    from lf3pm.replays.localization import localization_params, register_to_map

    config = DEFAULTS if config is None else config
    settings, sigma = config.localization, as_sensor(sensor).range_noise_sigma
    widened = {"max_correspondence_distance": COARSE_CORRESPONDENCE_M, "max_iterations": COARSE_ITERATIONS}
    coarse = settings.model_copy(update={**widened, "remap": False})
    target = RegistrationTarget(map, threads=config.scan.threads) if target is None else target
    stamps, poses, reference, skipped, seconds = [], [], [], 0, 0.0
    with Run(run, config.run, skip_bad=True) as opened:
        total = opened.scan_count()
        for scan in opened.scans():
            began = time.perf_counter()
            prior = poses[-1] if poses else scan.pose
            near = register_to_map(scan.points, prior, target, sigma, coarse)
            found = register_to_map(scan.points, near.pose, target, sigma, settings)
            seconds += time.perf_counter() - began
            skipped += found.skipped
            stamps.append(scan.stamp)
            poses.append(found.pose)
            reference.append(scan.pose)
            if progress is not None:
                progress(scan.index + 1, total)
    poses_array = np.asarray(poses).reshape(-1, 4, 4)
    params = localization_params(settings)
    del params["odometry"]  # the simulated wheel odometry's settings: a recorded run has none
    params["prior"] = "the last estimate (no wheel odometry), registered coarsely first"
    params["coarse"] = {"max_correspondence_distance": COARSE_CORRESPONDENCE_M, "max_iterations": COARSE_ITERATIONS}
    return Track(
        TRACKING,
        np.asarray(stamps),
        poses_array,
        _errors(poses_array, np.asarray(reference).reshape(-1, 4, 4)),
        skipped,
        seconds,
        params,
    )


def track_odometry(
    run,
    sensor: Sensor | str = DEFAULTS.sensor,
    config: Config | None = None,
    *,
    progress: Callable[[int, int | None], None] | None = None,
) -> Track:
    """KISS-ICP along ``run`` (module docstring) with ``sensor``'s range limits.
    ``progress(read, total)`` after each scan."""
    from lf3pm.replays.odometry import kiss_icp_params, run_kiss_icp

    config = DEFAULTS if config is None else config
    sensor = as_sensor(sensor)
    stamps, reference = [], []
    with Run(run, config.run, skip_bad=True) as opened:
        total = opened.scan_count()

        def scans():  # the run's scans as KISS-ICP takes them, keeping their stamps and poses
            for scan in opened.scans():
                stamps.append(scan.stamp)
                reference.append(scan.pose)
                times = np.empty(0) if scan.times is None else np.asarray(scan.times, dtype=np.float64)
                yield SimpleNamespace(points=scan.points, timestamps=times)
                if progress is not None:
                    progress(scan.index + 1, total)

        # Anchored at the identity, then at the first reference pose: I @ X is X exactly.
        estimate = run_kiss_icp(scans(), sensor, np.eye(4), config.kiss_icp, threads=config.scan.threads)
    if not reference:
        raise RunError(f"{run}: no scan to run the odometry on")
    poses = reference[0] @ np.asarray(estimate.poses).reshape(-1, 4, 4)
    params = {"min_points": config.kiss_icp.min_points, "kiss_icp": kiss_icp_params(sensor, config.kiss_icp)}
    return Track(
        ODOMETRY,
        np.asarray(stamps),
        poses,
        _errors(poses, np.asarray(reference).reshape(-1, 4, 4)),
        len(estimate.skipped),
        estimate.seconds,
        params,
    )


#: IMU samples handed to an odometry at a time (run_lio reads them as it needs them).
IMU_CHUNK = 512
#: Seconds of IMU read past the last scan's end (LIO-SAM flushes its last scans on them).
IMU_AFTER_LAST_SCAN = 1.0


def lio_odometries(sensor: Sensor | str = DEFAULTS.sensor, names: Iterable[str] | None = None) -> tuple[str, ...]:
    """The odometries (registry keys) an audit runs along a run with an IMU: those
    ``names`` gives (registered names or auto, each once), or with None every registered
    one that takes ``sensor``'s scans. Lf3pmError in one line for an unknown name or an
    odometry that cannot take the sensor's scans."""
    from lf3pm.replays import registry

    sensor = as_sensor(sensor)
    if names is None:
        return tuple(key for key, adapter in registry.odometries().items() if adapter.runs_on(sensor))
    if isinstance(names, str):
        names = (names,)
    keys: list[str] = []
    for name in names:
        key = registry.choose_odometry(name, sensor).key
        keys += [] if key in keys else [key]
    return tuple(keys)


def has_imu(run, config: Config | None = None) -> bool:
    """Whether ``run`` (read with ``config``'s run section) has IMU samples (two at least)."""
    with Run(run, (DEFAULTS if config is None else config).run) as opened:
        samples = iter(opened.imu())
        return next(samples, None) is not None and next(samples, None) is not None


def imu_in_lidar_frame(rows: np.ndarray, body_from_lidar: np.ndarray, before=None, after=None) -> np.ndarray:
    """IMU rows (t, accel, gyro: K x 7, in the body frame, the IMU's) as an IMU at the
    LiDAR would read them, in the LiDAR's axes: with R, r the LiDAR's rotation and
    position in the body frame (``body_from_lidar``), gyro R^T w and specific force
    R^T (a + dw/dt x r + w x (w x r)), dw/dt by central differences of the gyro over the
    neighbouring samples (``before`` and ``after``: the rows either side of these, where
    there are any). The identity extrinsic returns ``rows`` as they are."""
    rotation, lever = body_from_lidar[:3, :3], body_from_lidar[:3, 3]
    if np.array_equal(rotation, np.eye(3)) and not lever.any():
        return rows
    accel, gyro = rows[:, 1:4], rows[:, 4:7]
    if lever.any():
        around = [r for r in (before, rows, after) if r is not None]
        joined = np.vstack([np.atleast_2d(r) for r in around])
        start = 1 if before is not None else 0
        if len(joined) > 1:
            rate = np.gradient(joined[:, 4:7], joined[:, 0], axis=0)[start : start + len(rows)]
        else:
            rate = np.zeros_like(gyro)
        accel = accel + np.cross(rate, lever) + np.cross(gyro, np.cross(gyro, lever))
    return np.column_stack([rows[:, 0], accel @ rotation, gyro @ rotation])  # R^T v, row by row


def _imu_chunks(samples: Iterable, body_from_lidar: np.ndarray, since: float, stop, kept: dict):
    """The run's IMU ``samples`` (ImuSample) as run_lio's chunks (t, accel, gyro) in the
    LiDAR frame (:func:`imu_in_lidar_frame`): from the last sample at or before ``since``
    (the first scan's first point) up to the first at which ``stop(t)``; a sample not
    after the one before is left out (counted in ``kept["repeated"]``)."""
    pending: list = []  # read, not handed out yet
    before, last = None, -math.inf  # the last row handed out, the last time read
    for sample in samples:
        t = float(sample.stamp)
        if not t > last:
            kept["repeated"] += 1
            continue
        last = t
        row = np.concatenate([[t], sample.linear_acceleration, sample.angular_velocity]).astype(np.float64)
        if t <= since:
            pending = [row]
            continue
        pending.append(row)
        if stop(t):
            break
        if len(pending) > IMU_CHUNK:  # the newest one kept back: the derivative of the last needs it
            chunk = np.array(pending[:-1])
            yield _chunk(imu_in_lidar_frame(chunk, body_from_lidar, before, pending[-1]), kept)
            before, pending = chunk[-1], pending[-1:]
    if pending:
        yield _chunk(imu_in_lidar_frame(np.array(pending), body_from_lidar, before, None), kept)


def _chunk(rows: np.ndarray, kept: dict) -> SimpleNamespace:
    kept["samples"] += len(rows)
    return SimpleNamespace(t=rows[:, 0], accel=rows[:, 1:4], gyro=rows[:, 4:7])


def track_lio(
    run,
    odometry: str,
    sensor: Sensor | str = DEFAULTS.sensor,
    config: Config | None = None,
    *,
    progress: Callable[[int, int | None], None] | None = None,
) -> Track:
    """The LiDAR-inertial ``odometry`` (a registered one) along ``run`` with its IMU,
    through :func:`lf3pm.replays.lio.run_lio` as the lio replay runs it: the replay
    section's settings for it (``replay.odometries``), one thread (deterministic);
    ``sensor``'s range limits (and rings, for LIO-SAM).

    Scans as recorded (bad ones left out): points in the LiDAR frame, each at its
    absolute time (stamp + its time; a run without point times: every point at the
    scan's stamp), in time order; a scan ends at its last point's time (one not after
    the previous scan's end is left out). The IMU as recorded, taken to be at the body
    frame the reference poses track, turned into the LiDAR frame with the run's
    extrinsic (:func:`imu_in_lidar_frame`): the odometries take the IMU in the LiDAR's
    frame, as the replay simulates it. Both are streamed, a few scans in memory. The
    estimate, run from the identity, is anchored at the reference LiDAR pose at its
    first pose's time; each pose's error is against the reference interpolated at the
    time the pose refers to (GenZ-LIO: the scan's end; DLIO, LIO-SAM: its median return
    time); NaN where the odometry lost the scan or the reference has no pose. A failure
    (a crash, input it refuses) gives a track with every error NaN and ``message``
    saying why, in one line. ``progress(read, total)`` after each scan."""
    from lf3pm.replays import registry
    from lf3pm.replays.lio import run_lio

    config = DEFAULTS if config is None else config
    sensor = as_sensor(sensor)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # run_lio warns where the odometry is known to lose such a sensor
        adapter = registry.choose_odometry(odometry, sensor)
    options = registry.changed_settings(adapter.key, config.replay.odometries.get(adapter.key, {}))
    stamps, references, ends = [], [], []
    kept = {"samples": 0, "repeated": 0, "scans_without_point_times": 0, "scans_left_out": 0}
    state = {"done": False}
    with Run(run, config.run, skip_bad=True) as opened, Run(run, config.run) as imu_run:
        total = opened.scan_count()
        body_from_lidar = opened.body_from_lidar

        def scans() -> Iterator[SimpleNamespace]:
            for scan in opened.scans():
                fed = _lio_scan(scan, ends[-1] if ends else -math.inf, kept)
                if fed is not None:
                    stamps.append(scan.stamp)
                    references.append(scan.pose)
                    ends.append(fed.end)
                    yield fed
                if progress is not None:
                    progress(scan.index + 1, total)
            state["done"] = True

        def stop(t: float) -> bool:  # the IMU read far enough past the last scan
            return state["done"] and t > ends[-1] + IMU_AFTER_LAST_SCAN

        began = time.perf_counter()
        estimate, message, stream, imu = None, None, scans(), None
        try:
            first = next(stream, None)
            if first is None:
                raise RunError(f"{run}: no scan to run the odometry on")
            imu = _imu_chunks(imu_run.imu(), body_from_lidar, float(first.stamps[0]), stop, kept)
            fed = itertools.chain([first], stream)
            estimate = run_lio(fed, imu, sensor, initial_pose=np.eye(4), odometry=adapter.key, **options)
        except Exception as err:  # any failure of the odometry or its input: one line, and the audit goes on
            text = str(err) if isinstance(err, Lf3pmError) else f"{type(err).__name__}: {err}"
            message = one_line(f"{adapter.name} failed: {text}")
        finally:  # before the runs close
            stream.close()
            if imu is not None:
                imu.close()
        seconds = time.perf_counter() - began
        count = len(stamps)
        params = {"odometry": adapter.name, "threads": 1, "options": options}
        params["imu"] = {
            "frame": "the body frame of the reference poses, turned into the LiDAR's by run.lidar_* (lever arm "
            "with dw/dt by central differences)",
            "body_from_lidar": body_from_lidar.tolist(),
            "samples": kept["samples"],
            "repeated_stamps_left_out": kept["repeated"],
        }
        params["scans"] = {
            "without_point_times": kept["scans_without_point_times"],
            "left_out_end_not_after_previous": kept["scans_left_out"],
        }
        if estimate is None:
            poses = np.full((count, 4, 4), np.nan)
            errors = np.full(count, np.nan)
            return Track(adapter.key, np.asarray(stamps), poses, errors, count, seconds, params, message)
        anchor = _reference_at(opened, estimate.times[0])
        anchor = references[0] if anchor is None else anchor
        poses = anchor @ estimate.poses
        errors = np.full(count, np.nan)
        for k, at in enumerate(estimate.times):
            reference = _reference_at(opened, at)
            if reference is not None:
                errors[k] = float(np.linalg.norm(poses[k, :3, 3] - reference[:3, 3]))
        errors[estimate.lost] = np.nan
    if estimate.lost:
        k = estimate.lost[0]
        message = one_line(
            f"{adapter.name} lost {len(estimate.lost)} of {count} scans (first at {stamps[k]:.6f} s: "
            f"{estimate.status[k]})"
        )
    params |= {
        "package": estimate.package,
        "version": estimate.version,
        "seconds_per_scan": estimate.seconds_per_scan,
        "pose_times": "the odometry's own (GenZ-LIO: each scan's end; DLIO, LIO-SAM: its median return time)",
        "settings": estimate.params,
        "notes": [m for m in estimate.messages if m.startswith("lf3pm:")],
    }
    return Track(
        adapter.key,
        np.asarray(stamps),
        poses,
        errors,
        len(estimate.lost),
        estimate.seconds_per_scan * count,
        params,
        message,
    )


def _lio_scan(scan, previous_end: float, kept: dict) -> SimpleNamespace | None:
    """The scan as run_lio takes it (points in time order, absolute times, its end: the last
    point's time), or None where it does not end after ``previous_end``."""
    if scan.times is None:
        kept["scans_without_point_times"] += 1
        stamps = np.full(len(scan.points), scan.stamp)
        points = scan.points
    else:
        stamps = scan.stamp + np.asarray(scan.times, dtype=np.float64)
        points = scan.points
        if np.any(np.diff(stamps) < 0):
            order = np.argsort(stamps, kind="stable")
            stamps, points = stamps[order], points[order]
    end = float(stamps[-1])
    if not end > previous_end:
        kept["scans_left_out"] += 1
        return None
    return SimpleNamespace(end=end, points=points, stamps=stamps)


def _reference_at(run: Run, t: float) -> np.ndarray | None:
    """The reference LiDAR pose at ``t`` (None where the run has none)."""
    try:
        return run.lidar_pose_at(float(t))
    except RunError:
        return None
