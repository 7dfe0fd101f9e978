"""The scan stream of a replay: one simulated scan every 1/rate s along a motion.

Scan k ends at t_k = t0 + k / rate (its last ray) and its rays fire evenly over
(t_k - 1/rate, t_k], each cast from the pose at its own firing time
(moving_scan.py), so scan 0 is taken at rest before t0. Each return carries
Gaussian range noise (the sensor's sigma unless ``noise`` is given) from noise
stream k of ``seed``: scan k is the same whichever consumer asks for it and in
which order, so localization, KISS-ICP, the LIO and the bag writer all see
exactly the same scans. Scans are simulated when asked for (a VLP-16 scan is
0.7 MB; a long replay would not fit in memory) and the time spent is summed.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np

from lf3pm.config import DEFAULTS
from lf3pm.errors import Lf3pmError
from lf3pm.map import Map
from lf3pm.scan.moving_scan import MovingScan, firing_fractions, simulate_moving_scan
from lf3pm.scan.scan_simulator import simulate_scan
from lf3pm.sensors import Sensor

#: Most scans one replay simulates: beyond this a typo in a rate or a time
#: would run for hours.
MAX_SCANS = 100_000


class ScanStream(Sequence):
    """Scans of ``sensor`` on ``map`` along ``motion`` (anything with t0, t1 and
    pose(times), see moving_scan.py), a sequence of :class:`MovingScan` whose
    ``end``, ``points`` and ``stamps`` (absolute firing times) are what an
    odometry consumes. ``distortion=False`` casts every ray of a scan from the
    pose at its end instead. ``truth`` (M, 4, 4) holds the pose at each
    scan's end, ``times`` (M,) the ends; ``seconds`` the simulation time so far
    and ``hits`` (M,) the returns of each scan simulated so far (-1: not yet)."""

    def __init__(
        self,
        map: Map,
        motion,
        sensor: Sensor,
        *,
        rate: float = DEFAULTS.replay.rate,
        seed: int = DEFAULTS.scan.seed,
        noise: float | None = DEFAULTS.scan.noise,
        distortion: bool = True,
        threads: int = DEFAULTS.scan.threads,
    ):
        if not (math.isfinite(rate) and rate > 0):
            raise Lf3pmError(f"the scan rate must be > 0 Hz, got {rate}")
        self.noise = sensor.range_noise_sigma if noise is None else float(noise)
        if not (math.isfinite(self.noise) and self.noise >= 0):
            raise Lf3pmError(f"range noise must be >= 0 m, got {noise}")
        span = motion.t1 - motion.t0
        count = int(math.floor(span * rate + 1e-9)) + 1
        if count < 2:
            raise Lf3pmError(f"the trajectory spans {span:g} s: fewer than 2 scans at {rate:g} Hz")
        if count > MAX_SCANS:
            raise Lf3pmError(f"{count} scans at {rate:g} Hz over {span:g} s: more than {MAX_SCANS}")
        self.map, self.motion, self.sensor = map, motion, sensor
        self.rate, self.period, self.seed = float(rate), 1.0 / float(rate), int(seed)
        self.distortion, self.threads = bool(distortion), int(threads)
        self.times = motion.t0 + np.arange(count) / self.rate
        self.truth = motion.pose(self.times)
        self.seconds = 0.0
        self.hits = np.full(count, -1, dtype=np.int64)

    def __len__(self) -> int:
        return len(self.times)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(len(self)))]
        k = int(k) + (len(self) if k < 0 else 0)
        if not 0 <= k < len(self):
            raise IndexError(f"scan {k} of {len(self)}")
        start = time.perf_counter()
        s = self.sensor
        directions = s.scan_directions(k)
        if self.distortion:
            scan = simulate_moving_scan(
                self.map.index,
                self.motion,
                self.times[k],
                self.period,
                directions,
                s.min_range,
                s.max_range,
                noise=self.noise,
                seed=self.seed,
                stream=k,
                threads=self.threads,
                returns=s.returns,
            )
        else:
            raw = simulate_scan(
                self.map,
                self.truth[k],
                directions,
                s.min_range,
                s.max_range,
                noise=self.noise,
                seed=self.seed,
                stream=k,
                threads=self.threads,
                returns=s.returns,
            )
            scan = MovingScan(
                end=float(self.times[k]),
                period=self.period,
                points=raw.sensor_points,
                timestamps=firing_fractions(len(directions))[raw.ray],
                reference=self.truth[k],
                reference_points=raw.sensor_points,
                world_points=raw.world_points,
                ray=raw.ray,
            )
        self.seconds += time.perf_counter() - start
        self.hits[k] = len(scan.points)
        return scan
