"""Trajectories for evaluation: a time series of ground-robot poses (x, y, z, yaw),
checked, interpolated and resampled at a constant interval.

Interpolation is linear in x, y, z and in the unwrapped yaw (yaw never jumps by
2 pi between samples), which is what a planner's densely sampled output needs.
"""

from __future__ import annotations

import numpy as np

from lf3pm.errors import Lf3pmError


def check_trajectory(t, poses) -> tuple[np.ndarray, np.ndarray]:
    """(t, poses) as float64 arrays of shapes (N,) and (N, 4), checked: at least
    two samples, finite, strictly increasing times. Raises Lf3pmError otherwise."""
    t = np.asarray(t, dtype=np.float64)
    poses = np.asarray(poses, dtype=np.float64)
    if t.ndim != 1 or poses.ndim != 2 or poses.shape != (len(t), 4):
        raise Lf3pmError(
            f"a trajectory is times (N,) and poses (N, 4) of x y z yaw, got shapes {t.shape} and {poses.shape}"
        )
    if len(t) < 2:
        raise Lf3pmError(f"a trajectory needs at least 2 poses, got {len(t)}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(poses))):
        raise Lf3pmError("the trajectory has non-finite times or poses")
    if np.any(np.diff(t) <= 0):
        bad = int(np.argmax(np.diff(t) <= 0))
        raise Lf3pmError(
            f"trajectory times must increase strictly: t[{bad + 1}] = {t[bad + 1]} follows t[{bad}] = {t[bad]}"
        )
    return t, poses


def interpolate_poses(t, poses, times) -> np.ndarray:
    """Poses (len(times), 4) at ``times`` (within [t[0], t[-1]]) by linear
    interpolation of x, y, z and the unwrapped yaw; the yaw returned is unwrapped."""
    t, poses = check_trajectory(t, poses)
    times = np.asarray(times, dtype=np.float64)
    if times.size and (times.min() < t[0] - 1e-9 or times.max() > t[-1] + 1e-9):
        raise Lf3pmError(f"interpolation times leave the trajectory's span [{t[0]}, {t[-1]}]")
    yaw = np.unwrap(poses[:, 3])
    columns = [np.interp(times, t, poses[:, k]) for k in range(3)] + [np.interp(times, t, yaw)]
    return np.column_stack(columns)


def sample_trajectory(t, x, y, yaw, *, every: float = 1.0, by: str = "time", z=0.0) -> tuple[np.ndarray, np.ndarray]:
    """Samples the trajectory (t, x, y, yaw) at a constant interval.

    by="time": at t[0] + k * every seconds; by="distance": every ``every``
    metres of horizontal path length (x-y, piecewise linear between the given
    samples), starting at the first pose. The last given pose is included only
    when it falls on the grid. ``z`` is a constant sensor height or an array
    like ``x`` (e.g. ground + sensor height), interpolated like x and y.
    Returns (times (N,), poses (N, 4) of x y z yaw).
    """
    x = np.asarray(x, dtype=np.float64)
    z = np.broadcast_to(np.asarray(z, dtype=np.float64), x.shape)
    t, poses = check_trajectory(t, np.column_stack([x, y, z, yaw]) if x.ndim == 1 else x)
    if not (np.isfinite(every) and every > 0):
        raise Lf3pmError(f"the sampling interval must be > 0, got {every}")
    if by == "time":
        # The small tolerance keeps the end when the span is a multiple of `every`.
        times = t[0] + every * np.arange(int(np.floor((t[-1] - t[0]) / every + 1e-9)) + 1)
    elif by == "distance":
        arc = np.r_[0.0, np.cumsum(np.hypot(np.diff(poses[:, 0]), np.diff(poses[:, 1])))]
        marks = every * np.arange(int(np.floor(arc[-1] / every + 1e-9)) + 1)
        # Arc length is non-decreasing; a robot turning in place keeps the first time there.
        keep = np.r_[True, np.diff(arc) > 0]
        times = np.interp(marks, arc[keep], t[keep])
    else:
        raise Lf3pmError(f"sample by 'time' or 'distance', got {by!r}")
    return times, interpolate_poses(t, poses, np.minimum(times, t[-1]))


class LinearMotion:
    """Poses between samples (t (N,), poses (N, 4) of x y z yaw) by
    :func:`interpolate_poses`, held at the end poses outside [t0, t1]: the
    sampled trajectories ``mde_along`` and ``replay_odometry`` take, with the
    ``t0``, ``t1`` and ``pose(times)`` of :class:`lf3pm.replays.motion.Motion`."""

    def __init__(self, t, poses):
        self.samples, self.poses = check_trajectory(t, poses)
        self.t0, self.t1 = float(self.samples[0]), float(self.samples[-1])

    def pose(self, times) -> np.ndarray:
        """Sensor-to-world matrices (n, 4, 4) at ``times``."""
        from lf3pm.pose import pose_matrices

        times = np.clip(np.atleast_1d(np.asarray(times, dtype=np.float64)), self.t0, self.t1)
        return pose_matrices(interpolate_poses(self.samples, self.poses, times))
