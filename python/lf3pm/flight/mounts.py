"""Where a quadrotor carries its LiDAR: the sensor's pose in the body frame (x forward,
y left, z up along the thrust), by the names the configuration takes (quadrotor.mount)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SensorMount:
    """The sensor-to-body transform: ``rotation`` (3 x 3) and ``translation`` (m)."""

    name: str
    description: str
    rotation: tuple
    translation: tuple

    def matrix(self) -> np.ndarray:
        """The 4 x 4 sensor-to-body matrix."""
        out = np.eye(4)
        out[:3, :3] = self.rotation
        out[:3, 3] = self.translation
        return out


def _pitch(angle: float) -> tuple:
    """Rotation about the body's y axis by ``angle`` (rad): positive turns x towards -z."""
    c, s = math.cos(angle), math.sin(angle)
    return ((c, 0.0, s), (0.0, 1.0, 0.0), (-s, 0.0, c))


#: The mounts by name (config SENSOR_MOUNTS). Offsets are those of a 350-450 mm frame.
MOUNTS = {
    m.name: m
    for m in (
        SensorMount("top", "a Mid-360 on top, level", _pitch(0.0), (0.0, 0.0, 0.10)),
        SensorMount(
            "down20",
            "a forward LiDAR pitched 20 degrees down (EAROL's)",
            _pitch(math.radians(20.0)),
            (0.12, 0.0, -0.05),
        ),
        SensorMount(
            "side", "a VLP-16 on its side, its spin axis along the body's x", _pitch(math.pi / 2), (0.0, 0.0, 0.08)
        ),
    )
}
