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
  points' times where the run has them) anchored at the first scan's reference pose.

The run is read once per track, a scan at a time; a track keeps one pose per scan."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from lf3pm.config import DEFAULTS, Config
from lf3pm.errors import RunError
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
    prediction, ``seconds`` spent estimating, the ``params`` it ran with."""

    method: str
    stamps: np.ndarray
    poses: np.ndarray
    errors_m: np.ndarray
    skipped: int
    seconds: float
    params: dict = field(default_factory=dict)

    @property
    def ape(self) -> dict:
        """The translation errors' statistics (rmse, mean, median, max, min, std, count; m)."""
        return error_stats(self.errors_m)

    def error_at(self, stamp: float) -> float:
        """The error at the scan recorded at ``stamp`` (NaN where the track has none)."""
        at = np.flatnonzero(self.stamps == stamp)
        return float(self.errors_m[at[0]]) if at.size else float("nan")

    def to_dict(self) -> dict:
        """JSON-ready: what ran and its APE (the per-scan errors are in the scans' records)."""
        return {
            "method": self.method,
            "scans": len(self.stamps),
            "skipped": self.skipped,
            "seconds": self.seconds,
            "ape_m": self.ape,
            "params": self.params,
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
