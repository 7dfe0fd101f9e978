"""Reference poses and their SE(3) interpolation to any time within them."""

from __future__ import annotations

import numpy as np

from lf3pm.errors import RunError


class PoseTrack:
    """Reference poses: ``times`` (N,) strictly increasing (s) and ``poses`` (N x 4 x 4,
    world-from-body). :meth:`at` interpolates on SE(3): the rotation by slerp, the
    translation linearly, between the two poses around a time; a time outside the poses'
    span, or between two poses more than ``max_gap`` s apart, has no pose."""

    def __init__(self, times, poses, max_gap: float, name: str = "poses"):
        self.times = np.asarray(times, dtype=np.float64)
        self.poses = np.asarray(poses, dtype=np.float64)
        self.max_gap = float(max_gap)
        self.name = name
        if self.times.ndim != 1 or self.poses.shape != (len(self.times), 4, 4) or not len(self.times):
            raise RunError(f"{name}: poses are N times and N x 4 x 4 matrices, N >= 1")
        steps = np.flatnonzero(np.diff(self.times) <= 0)
        if steps.size:
            i = int(steps[0]) + 1
            raise RunError(f"{name}: pose {i} at {self.times[i]:.9f} s is not after pose {i - 1}")

    def __len__(self) -> int:
        return len(self.times)

    @property
    def span(self) -> tuple[float, float]:
        """The first and last pose's times (s)."""
        return float(self.times[0]), float(self.times[-1])

    def at(self, t: float) -> np.ndarray:
        """The pose (4 x 4) at time ``t`` (s); a pose's own time gives that pose exactly.
        RunError (one line) outside the span or inside a gap longer than ``max_gap``."""
        from scipy.spatial.transform import Rotation, Slerp

        first, last = self.span
        if not first <= t <= last:
            raise RunError(f"no pose at {t:.6f} s: {self.name} span {first:.6f} to {last:.6f} s")
        i = int(np.searchsorted(self.times, t, side="right")) - 1
        if self.times[i] == t:
            return self.poses[i].copy()
        t0, t1 = self.times[i], self.times[i + 1]
        if t1 - t0 > self.max_gap:
            raise RunError(
                f"no pose at {t:.6f} s: {self.name} has no pose from {t0:.6f} to {t1:.6f} s, "
                f"{t1 - t0:.3f} s, longer than max_pose_gap {self.max_gap:g} s"
            )
        alpha = (t - t0) / (t1 - t0)
        pair = self.poses[i : i + 2]
        pose = np.eye(4)
        pose[:3, :3] = Slerp([0.0, 1.0], Rotation.from_matrix(pair[:, :3, :3]))([alpha]).as_matrix()[0]
        pose[:3, 3] = (1 - alpha) * pair[0, :3, 3] + alpha * pair[1, :3, 3]
        return pose
