"""Robot kinds and their kinematic limits for trajectory optimisation.

The defaults are the C++ core's (``RobotLimits`` in cpp/lf3pm/trajectory/robot_limits.hpp),
read from it here, so that the library, the CLI and the experiments share them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from lf3pm import _core
from lf3pm.errors import Lf3pmError

KINDS = ("omni", "diff", "car")

_LIMITS = _core.RobotLimits()


#: The smallest speed, yaw rate or acceleration limit a Robot takes (m/s, rad/s, m/s^2,
#: rad/s^2): slower is no robot, and its trajectories would be too long to sample.
MIN_LIMIT = 1e-3


@dataclass(frozen=True)
class Robot:
    """A ground robot's kind and limits (SI units).

    ``kind``: ``omni`` (holonomic: body-frame longitudinal and lateral speed limits),
    ``diff`` (differential drive: no lateral motion) or ``car`` (diff plus a minimum
    turning radius ``min_turn_radius``, |omega| <= |v_lon| / R). ``vmax_norm``
    (omni only) also limits the speed |v| itself, by default to max(vmax_lon,
    vmax_lat) (``inf``: no such limit): with only the body-frame limits an omni
    robot is fastest moving diagonally (sqrt(vmax_lon^2 + vmax_lat^2)), which a
    time-weighted planner exploits by yawing 45 degrees off its path. ``r_safe`` is
    the clearance the trajectory keeps from obstacles (ESDF >= r_safe) beyond the
    SOLM's robot radius. ``amax_lon`` and ``amax_lat`` limit the acceleration in the
    body frame (diff and car: tangential and centripetal), ``alpha_max`` the yaw
    acceleration, so that a real base can track the trajectory.
    """

    kind: str = "omni"
    vmax_lon: float = _LIMITS.vmax_lon
    vmax_lat: float = _LIMITS.vmax_lat
    wmax: float = _LIMITS.wmax
    amax_lon: float = _LIMITS.amax_lon
    amax_lat: float = _LIMITS.amax_lat
    alpha_max: float = _LIMITS.alpha_max
    min_turn_radius: float = _LIMITS.min_turn_radius
    r_safe: float = _LIMITS.r_safe
    vmax_norm: float | None = None

    def __post_init__(self):
        if self.kind not in KINDS:
            raise Lf3pmError(f"robot kind must be one of {', '.join(KINDS)}, got {self.kind!r}")
        for name in ("vmax_lon", "vmax_lat", "wmax", "amax_lon", "amax_lat", "alpha_max"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise Lf3pmError(f"robot {name} must be a positive number, got {value!r}")
            if value < MIN_LIMIT:
                # 1e-9 m/s would make a 10 m plan 300 years long, sampled at 100 Hz.
                raise Lf3pmError(f"robot {name} must be at least {MIN_LIMIT:g} (SI units), got {value:g}")
        for name in ("min_turn_radius", "r_safe"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise Lf3pmError(f"robot {name} must be a non-negative number, got {value!r}")
        if self.vmax_norm is not None:
            if self.kind != "omni":
                raise Lf3pmError(f"a speed-norm limit applies to omni robots only, not {self.kind!r}")
            if not (isinstance(self.vmax_norm, (int, float)) and not math.isnan(self.vmax_norm)
                    and self.vmax_norm > 0):
                raise Lf3pmError(f"robot vmax_norm must be a positive number (inf: none), got {self.vmax_norm!r}")
        elif self.kind == "omni":
            # A base's wheels limit its speed, not only its body-frame components: with the
            # box alone a time-weighted plan yaws 45 degrees off its path to go sqrt(2) faster.
            object.__setattr__(self, "vmax_norm", float(max(self.vmax_lon, self.vmax_lat)))
        if self.kind != "car" and self.min_turn_radius > 0:
            raise Lf3pmError(f"a minimum turning radius applies to car robots only, not {self.kind!r}")

    @property
    def nonholonomic(self) -> bool:
        """True for diff and car robots (no lateral velocity)."""
        return self.kind != "omni"

    def limits(self) -> "_core.RobotLimits":
        """The C++ core's limits struct for this robot."""
        out = _core.RobotLimits()
        out.kind = getattr(_core.RobotKind, self.kind)
        for name in ("vmax_lon", "vmax_lat", "wmax", "amax_lon", "amax_lat", "alpha_max", "min_turn_radius",
                     "r_safe"):
            setattr(out, name, float(getattr(self, name)))
        out.vmax_norm = float(self.vmax_norm) if self.vmax_norm is not None and math.isfinite(self.vmax_norm) else 0.0
        return out

