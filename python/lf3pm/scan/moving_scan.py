"""A scan taken while the sensor moves along a trajectory (motion distortion).

A real LiDAR fires its rays one after another over the scan period (a spinning
sensor turn by turn in azimuth, a Livox sensor along its pattern) while the
robot moves, and reports each return in the sensor frame of its own firing
time. Here the K rays of a scan, in the sensor's emission order, fire evenly
over the period: ray i at fraction

    f_i = (i + 1) / K

of the period, the last ray at the scan's reference time ``end`` and the first
one ray interval after the previous scan's last. Ray i is cast from the pose
at end - (1 - f_i) * period; before the trajectory's first time the sensor
stands at its first pose (and after the last at the last).

KISS-ICP (``register_frame(points, timestamps)`` with ``data.deskew``) takes
these per-ray points and f_i as timestamps: it rescales the timestamps to
[0, 1] by their minimum and maximum and moves a point of timestamp s by
exp((s - 1) log(delta)), delta being its last frame-to-frame motion; its pose
is then the sensor's at the latest timestamp, ``end`` here. Rescaling moves a
point by at most (1 - f_min) * speed * period when the first rays get no return.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lf3pm import _core
from lf3pm.config import DEFAULTS, scan_params
from lf3pm.errors import Lf3pmError


@dataclass(frozen=True)
class MovingScan:
    """The hits of one moving scan, in emission order.

    ``end`` (s): the scan's reference time, its last ray's; ``period`` (s): the
    rays fire over (end - period, end]; ``points`` (H, 3): each hit in the
    sensor frame of its own firing (what the sensor reports); ``timestamps``
    (H,): firing time as a fraction of the period, in (0, 1], increasing;
    ``reference`` (4, 4): the sensor-to-world pose at ``end``;
    ``reference_points`` (H, 3): the hits in that frame (a perfectly deskewed
    scan); ``world_points`` (H, 3); ``ray`` (H,): index of the sensor ray.
    """

    end: float
    period: float
    points: np.ndarray
    timestamps: np.ndarray
    reference: np.ndarray
    reference_points: np.ndarray
    world_points: np.ndarray
    ray: np.ndarray

    @property
    def stamps(self) -> np.ndarray:
        """Absolute firing time of each hit (s), non-decreasing."""
        return self.end - (1.0 - self.timestamps) * self.period


def firing_fractions(count: int) -> np.ndarray:
    """Firing time of each of ``count`` rays, in emission order, as a fraction of
    the scan period: (i + 1) / count (evenly spaced, the last at 1)."""
    if count < 1:
        raise Lf3pmError(f"a scan needs at least one ray, got {count}")
    return np.arange(1, count + 1, dtype=np.float64) / count


def simulate_moving_scan(
    index: _core.MapIndex,
    motion,
    end: float,
    period: float,
    directions,
    min_range: float,
    max_range: float,
    *,
    noise: float = 0.0,
    seed: int = DEFAULTS.scan.seed,
    stream: int = 0,
    threads: int = DEFAULTS.scan.threads,
    returns=None,
) -> MovingScan:
    """The scan whose rays (``directions`` (K, 3), emission order) fire over
    (end - period, end] while the sensor follows ``motion`` (anything with
    ``pose(times) -> (n, 4, 4)`` that holds the end poses outside its span:
    lf3pm.replays.motion.Motion, lf3pm.trajectory.sampling.LinearMotion).
    Noise and ``returns`` as :func:`lf3pm.scan.scan_simulator.simulate_scan`'s: ray k gets the same
    range noise (and return draw) under the same seed and stream whatever the motion.
    """
    if not (np.isfinite(period) and period > 0):
        raise Lf3pmError(f"the scan period must be > 0 s, got {period}")
    directions = np.ascontiguousarray(directions, dtype=np.float64)
    fractions = firing_fractions(len(directions))
    ray_poses = np.ascontiguousarray(motion.pose(end - (1.0 - fractions) * period))
    scan = _core.simulate_moving_scan(
        index,
        ray_poses,
        directions,
        scan_params(min_range, max_range, noise=noise, seed=seed, stream=stream, threads=threads, returns=returns),
    )
    reference = ray_poses[-1]  # the last ray fires at the reference time
    world = scan["world_points"]
    return MovingScan(
        end=float(end),
        period=float(period),
        points=scan["sensor_points"],
        timestamps=fractions[scan["ray"]],
        reference=reference,
        reference_points=(world - reference[:3, 3]) @ reference[:3, :3],
        world_points=world,
        ray=scan["ray"],
    )
