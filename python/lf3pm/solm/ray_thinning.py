"""Thinned scans for fast SOLM builds: cast a subset of the sensor's rays and
let each stand for the rays left out.

A Gram is a sum over rays, so the Gram of every K-th azimuth column, scaled by
the ratio of ray counts, estimates the full scan's Gram; the C++ metric scales
by ``ray_weight`` (EvalParams). Whole azimuth columns are kept, so a spinning
LiDAR keeps all its rings; a non-repetitive pattern (Livox), whose rays all have
distinct azimuths, keeps every K-th ray in azimuth order. The error against
full scans is measured in bench/bench_solm.py and tests/test_solm.py.
"""

from __future__ import annotations

import numpy as np

from lf3pm import libm
from lf3pm.errors import Lf3pmError


def thin_rays(directions: np.ndarray, stride: int) -> tuple[np.ndarray, float]:
    """(every ``stride``-th azimuth column of ``directions``, rays each kept ray stands for)."""
    if stride < 1:
        raise Lf3pmError(f"ray stride must be >= 1, got {stride}")
    if stride == 1:
        return directions, 1.0
    azimuth = np.round(libm.atan2(directions[:, 1], directions[:, 0]), 9)
    _, column = np.unique(azimuth, return_inverse=True)
    kept = np.ascontiguousarray(directions[column % stride == 0])
    if len(kept) == 0:
        raise Lf3pmError(f"ray stride {stride} leaves no rays of the sensor's {len(directions)}")
    return kept, len(directions) / len(kept)
