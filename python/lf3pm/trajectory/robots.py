"""A robot for trajectory optimisation: the configuration's robot section
(lf3pm.config.RobotConfig: kind, limits and their defaults, read from the C++ core's
``RobotLimits``) with what the planner asks of it.
"""

from __future__ import annotations

import math

from pydantic import ValidationError

from lf3pm import _core
from lf3pm.config import RobotConfig, describe
from lf3pm.errors import Lf3pmError


class Robot(RobotConfig):
    """A ground robot's kind and limits (SI units; :class:`lf3pm.config.RobotConfig` says
    what each means). ``Robot("diff", vmax_lon=0.5)``; a bad value raises Lf3pmError in one line."""

    def __init__(self, kind: str | None = None, /, **limits):
        if kind is not None:
            if "kind" in limits:
                raise Lf3pmError("robot kind given twice")
            limits["kind"] = kind
        try:
            super().__init__(**limits)
        except ValidationError as err:
            raise Lf3pmError(describe(err, "robot")) from None

    @classmethod
    def from_config(cls, config: RobotConfig) -> Robot:
        """The robot of a configuration's robot section."""
        return cls(**config.model_dump())

    @property
    def nonholonomic(self) -> bool:
        """True for diff and car robots (no lateral velocity)."""
        return self.kind != "omni"

    def limits(self) -> _core.RobotLimits:
        """The C++ core's limits struct for this robot."""
        out = _core.RobotLimits()
        out.kind = getattr(_core.RobotKind, self.kind)
        for name in ("vmax_lon", "vmax_lat", "wmax", "amax_lon", "amax_lat", "alpha_max", "min_turn_radius", "r_safe"):
            setattr(out, name, float(getattr(self, name)))
        out.vmax_norm = float(self.vmax_norm) if self.vmax_norm is not None and math.isfinite(self.vmax_norm) else 0.0
        return out
