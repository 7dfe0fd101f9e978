"""What a run yields: scans, IMU samples and the scans it could not use."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Scan:
    """One LiDAR scan of a run.

    ``points``: N x 3 float64 in the LiDAR frame, as recorded (no extrinsic applied; NaN and
    no-return points at the origin dropped). ``stamp``: its time (s) on the poses' clock
    (the recorded stamp plus ``run.lidar_time_offset``). ``times``: each point's time (s)
    relative to ``stamp``, or None when the source has none. ``pose``: world-from-LiDAR
    (4 x 4) at ``stamp`` (the reference pose interpolated there, times the extrinsic), or
    None when the run has no poses. ``index``: its place among the run's scans, bad ones
    counted; ``name``: its file, or its topic and index."""

    index: int
    name: str
    stamp: float
    points: np.ndarray
    times: np.ndarray | None
    pose: np.ndarray | None


@dataclass(frozen=True)
class ImuSample:
    """One sensor_msgs/Imu message: ``stamp`` (s), ``angular_velocity`` (rad/s) and
    ``linear_acceleration`` (m/s^2, specific force), each (3,) in the IMU's frame."""

    stamp: float
    angular_velocity: np.ndarray
    linear_acceleration: np.ndarray


@dataclass(frozen=True)
class BadScan:
    """A scan the run skipped (``Run(..., skip_bad=True)``), with the one line saying why."""

    index: int
    name: str
    reason: str
