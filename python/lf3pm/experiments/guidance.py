"""The guidance the experiments compare: how a plan weighs the SOLM."""

from __future__ import annotations

import math
from dataclasses import dataclass

from lf3pm.config import COST_CHANNELS, DEFAULTS
from lf3pm.errors import Lf3pmError


@dataclass(frozen=True)
class Guidance:
    """A way to plan: a SOLM ``channel`` raised to ``power`` with trade-off ``weight``
    (Planner.plan's metric, power and weight)."""

    name: str
    channel: str
    power: float = 1.0
    weight: float = 1.0


def parse_guidance(text: str) -> Guidance:
    """``NAME=CHANNEL:POWER:WEIGHT`` (e.g. ``cube=q_n:3:1``) as a Guidance."""
    try:
        name, spec = text.split("=", 1)
        channel, power, weight = spec.split(":")
        g = Guidance(name.strip(), channel.strip(), float(power), float(weight))
    except ValueError:
        raise Lf3pmError(f"guidance {text!r}: expected NAME=CHANNEL:POWER:WEIGHT, e.g. cube=q_n:3:1") from None
    if not g.name or g.channel not in COST_CHANNELS or g.channel == "none":
        guided = ", ".join(c for c in COST_CHANNELS if c != "none")
        raise Lf3pmError(f"guidance {text!r}: channel must be one of {guided}")
    if not (math.isfinite(g.power) and 0 < g.power <= 10 and math.isfinite(g.weight) and g.weight >= 0):
        raise Lf3pmError(f"guidance {text!r}: power must be in (0, 10] and weight finite and >= 0")
    return g


UNGUIDED = Guidance("none", "none", 1.0, 0.0)
#: The guidance compared with ``none``: each SOLM channel as it is, then the shipped default.
GUIDANCE = (
    Guidance("q_n", "q_n"),
    Guidance("q_min", "q_min"),
    Guidance("step_norm", "step_norm"),
    Guidance("default", DEFAULTS.guidance.metric, DEFAULTS.guidance.power, DEFAULTS.guidance.weight),
)
