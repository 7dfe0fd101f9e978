"""The scan simulator (cpp/lf3pm/scan/scan_simulator.hpp): a sensor's rays cast from one
pose on a map's surfels, with seeded range noise. (A moving sensor, one pose per ray:
lf3pm.scan.moving_scan.)"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lf3pm import _core
from lf3pm.config import DEFAULTS, scan_params
from lf3pm.map import Map


@dataclass(frozen=True)
class SimulatedScan:
    """The returns of one scan, in emission order (rays without a return dropped):
    ``sensor_points`` and ``world_points`` (H, 3), the ``surfel`` (map point index) each
    hit and the ``ray`` (index into the directions) it came from."""

    sensor_points: np.ndarray
    world_points: np.ndarray
    surfel: np.ndarray
    ray: np.ndarray

    def __len__(self) -> int:
        return len(self.ray)


def simulate_scan(
    map: Map,
    pose: np.ndarray,
    directions: np.ndarray,
    min_range: float,
    max_range: float,
    *,
    noise: float = 0.0,
    seed: int = DEFAULTS.scan.seed,
    stream: int = 0,
    scan_voxel: float = DEFAULTS.scan.scan_voxel,
    threads: int = DEFAULTS.scan.threads,
    returns=None,
) -> SimulatedScan:
    """The scan of rays ``directions`` (N, 3, sensor frame) from the 4 x 4 sensor-to-world
    ``pose``; range noise sigma ``noise`` from noise stream (``seed``, ``stream``, ray);
    ``returns``: the sensor's ReturnModel (None: every hit returns)."""
    raw = _core.simulate_scan(
        map.index,
        np.ascontiguousarray(pose, dtype=np.float64),
        np.ascontiguousarray(directions, dtype=np.float64),
        scan_params(
            min_range,
            max_range,
            noise=noise,
            seed=seed,
            stream=stream,
            scan_voxel=scan_voxel,
            threads=threads,
            returns=returns,
        ),
    )
    return SimulatedScan(**raw)
