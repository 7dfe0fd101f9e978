"""A quadrotor (lf3pm.config.QuadrotorConfig) over sampled flat outputs: thrust, attitude and
body rates from the flatness map (cpp/lf3pm/flight/flatness.hpp), the gradients back to the
flat outputs, the poses of its body and of its LiDAR, and how close a flight comes to its
limits."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydantic import ValidationError

from lf3pm import _core
from lf3pm.config import QuadrotorConfig, describe
from lf3pm.errors import Lf3pmError
from lf3pm.flight.mounts import MOUNTS, SensorMount


@dataclass(frozen=True)
class FlightAttitudes:
    """The flatness map at n samples: ``thrust`` (n, N), ``rotation`` (n, 3, 3, body to
    world), ``omega`` (n, 3, body rates in rad/s), ``cos_tilt`` (n)."""

    thrust: np.ndarray
    rotation: np.ndarray
    omega: np.ndarray
    cos_tilt: np.ndarray

    def __len__(self) -> int:
        return len(self.thrust)

    @property
    def tilt(self) -> np.ndarray:
        """The angle between the body's z axis and the vertical (rad)."""
        return np.arccos(np.clip(self.cos_tilt, -1.0, 1.0))


def _rows(name: str, value, n: int | None, width: int | None) -> np.ndarray:
    array = np.ascontiguousarray(value, dtype=np.float64)
    shape = (n,) if width is None else (n, width)
    if array.ndim != len(shape) or (n is not None and array.shape[0] != n) or (width and array.shape[1] != width):
        want = "n" if width is None else f"n x {width}"
        raise Lf3pmError(f"{name} must be {want} (n: the samples), got shape {array.shape}")
    if not np.isfinite(array).all():
        raise Lf3pmError(f"{name} holds NaN or infinite values")
    return array


class Quadrotor(QuadrotorConfig):
    """A quadrotor's mass, drag, limits and mount (SI units; :class:`lf3pm.config.QuadrotorConfig`
    says what each means). ``Quadrotor(mass=2.0, mount="down20")``; a bad value raises
    Lf3pmError in one line."""

    def __init__(self, **values):
        try:
            super().__init__(**values)
        except ValidationError as err:
            raise Lf3pmError(describe(err, "quadrotor")) from None

    @classmethod
    def from_config(cls, config: QuadrotorConfig) -> Quadrotor:
        """The quadrotor of a configuration's quadrotor section."""
        return cls(**config.model_dump())

    @property
    def sensor_mount(self) -> SensorMount:
        """Where it carries its LiDAR (the ``mount`` named)."""
        return MOUNTS[self.mount]

    def _states(self, velocity, acceleration, jerk, yaw, yaw_rate):
        v = _rows("velocity", velocity, None, 3)
        n = len(v)
        return (
            v,
            _rows("acceleration", acceleration, n, 3),
            _rows("jerk", jerk, n, 3),
            _rows("yaw", yaw, n, None),
            _rows("yaw_rate", yaw_rate, n, None),
        )

    def attitudes(self, velocity, acceleration, jerk, yaw, yaw_rate) -> FlightAttitudes:
        """The thrust, attitude and body rates at n samples of the flat outputs' derivatives
        (velocity, acceleration, jerk: n x 3, world frame; yaw and its rate: n). A sample
        with no thrust direction (free fall, upside down) raises Lf3pmError naming it."""
        states = self._states(velocity, acceleration, jerk, yaw, yaw_rate)
        return FlightAttitudes(**_core.flat_attitudes(self.params(), *states))

    def gradients(
        self, velocity, acceleration, jerk, yaw, yaw_rate, *, thrust=None, rotation=None, omega=None, cos_tilt=None
    ) -> dict:
        """The gradients of a cost with respect to velocity, acceleration, jerk (n x 3), yaw
        and yaw_rate (n), from its gradients with respect to the attitudes' members (any
        left out: zero)."""
        states = self._states(velocity, acceleration, jerk, yaw, yaw_rate)
        n = len(states[0])
        return _core.flat_gradients(
            self.params(),
            *states,
            _rows("thrust gradient", np.zeros(n) if thrust is None else thrust, n, None),
            np.ascontiguousarray(np.zeros((n, 3, 3)) if rotation is None else rotation, dtype=np.float64).reshape(
                n, 3, 3
            ),
            _rows("omega gradient", np.zeros((n, 3)) if omega is None else omega, n, 3),
            _rows("cos_tilt gradient", np.zeros(n) if cos_tilt is None else cos_tilt, n, None),
        )

    def body_poses(self, positions, attitudes: FlightAttitudes) -> np.ndarray:
        """The body-to-world matrices (n, 4, 4) at ``positions`` (n x 3) with ``attitudes``."""
        p = _rows("positions", positions, len(attitudes), 3)
        out = np.tile(np.eye(4), (len(p), 1, 1))
        out[:, :3, :3] = attitudes.rotation
        out[:, :3, 3] = p
        return out

    def sensor_poses(self, positions, attitudes: FlightAttitudes) -> np.ndarray:
        """The LiDAR's sensor-to-world matrices (n, 4, 4): the body's poses times the mount."""
        return self.body_poses(positions, attitudes) @ self.sensor_mount.matrix()

    def limit_ratios(self, velocity, attitudes: FlightAttitudes) -> dict:
        """How close the samples come to each limit, as the largest ratio to it (<= 1:
        held): speed / vmax, |omega| / omega_max, tilt / tilt_max, thrust / thrust_max and
        thrust_min / thrust."""
        c = self
        v = _rows("velocity", velocity, len(attitudes), 3)
        return {
            "speed": float(np.max(np.linalg.norm(v, axis=1)) / c.vmax),
            "omega": float(np.max(np.linalg.norm(attitudes.omega, axis=1)) / c.omega_max),
            "tilt": float(np.max(attitudes.tilt) / c.tilt_max),
            "thrust_max": float(np.max(attitudes.thrust) / c.thrust_max),
            "thrust_min": float(c.thrust_min / np.min(attitudes.thrust)),
        }
