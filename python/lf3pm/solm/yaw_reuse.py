"""The representative ray set for SE(2) builds by sector Grams (see the C++
yaw_sectors.hpp): the sensor's pattern folded into one yaw sector."""

from __future__ import annotations

import math

import numpy as np

from lf3pm import libm
from lf3pm.errors import Lf3pmError
from lf3pm.sensors import Sensor


def sector_layout(sensor: Sensor, bins: int) -> tuple[np.ndarray, int]:
    """(rays of one sector centred on azimuth 0, half width in sectors).

    The field of view spans 2 F + 1 sectors; every pattern ray is rotated into
    the central sector by a multiple of the sector width (its elevation kept),
    and one ray in 2 F + 1 is kept, so a yaw bin summing its 2 F + 1 sectors
    sees about as many rays as the real scan."""
    width = 2 * math.pi / bins
    half = max(0, round(sensor.horizontal_fov / (2 * width) - 0.5))
    if 2 * half + 1 >= bins:
        raise Lf3pmError(
            f"sector reuse needs a field of view narrower than the {bins} yaw bins "
            f"(sensor {sensor.name} spans {math.degrees(sensor.horizontal_fov):.0f} deg)"
        )
    d = sensor.directions
    azimuth = libm.atan2(d[:, 1], d[:, 0])
    folded = azimuth - np.round(azimuth / width) * width
    horizontal = np.hypot(d[:, 0], d[:, 1])
    rays = np.stack([horizontal * np.cos(folded), horizontal * np.sin(folded), d[:, 2]], axis=1)
    return np.ascontiguousarray(rays[:: 2 * half + 1]), half
