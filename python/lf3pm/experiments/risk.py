"""Which start/goal pairs are "at risk": decided from the unguided plan and its SOLM
alone, before any replay, so that the benefit study's populations do not depend on
the replays they are then judged by.

A pose of a trajectory is at risk when its SOLM cell (the nearest one, at the
pose's yaw for SE(2)) is degenerate or predicts an error far above the map's:
q_n at least :data:`RISK_FACTOR` times the map's median q_n. On an SE(2) SOLM
the map's median is that of each cell's best heading (the minimum over yaw):
what the map offers a robot free to choose where it looks. Over every cell and
heading, a map that is mostly open would call its own bad views typical (the
benefit study's orientation scene: median 2.29 over all headings, 0.10 over the
best ones, its unguided plans 2.3-2.4 and 0.4-0.5 m APE). Localization APE
follows q_n with slope 1.03 in log-log over the benefit study's 320 plans
(results/benefit_issue39/summary.json, "calibration"; within a map the rank
correlation is weaker, 0.51 on average), so such a pose is predicted to localize an
order of magnitude worse than the map's typical place. A pair is at risk when
at least :data:`AT_RISK_SHARE` of its unguided plan's poses are.

The rule's settings are a :class:`RiskRule`, the benefit study's protocol's ``risk``
(lf3pm.experiments.benefit.protocol); the constants below are its defaults, and each
function takes another rule (``median="all_headings"``: the median over every cell
and heading, the rule's first form).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field

from lf3pm.config import Section
from lf3pm.grid import Space


class RiskRule(Section):
    """Which pairs are at risk, from the unguided plan and its SOLM alone
    (lf3pm.experiments.risk): a pose is at risk when its cell is degenerate or its q_n
    is at least ``factor`` times the map's median; a pair when ``share`` of its
    unguided plan's poses (sampled at ``rate`` Hz) are."""

    factor: float = Field(10.0, gt=0, description="A pose is at risk at q_n >= factor x the map's median q_n.")
    share: float = Field(0.1, gt=0, le=1, description="A pair is at risk when this share of its poses is.")
    rate: float = Field(10.0, gt=0, le=1000, description="Poses per second of trajectory the rule looks at.")
    median: Literal["best_heading", "all_headings"] = Field(
        "best_heading",
        description="The map's median on an SE(2) SOLM: over each cell's best heading (the minimum over "
        "yaw), or over every cell and heading (the rule's first form).",
    )


#: The rule's defaults (the benefit study's protocol's ``risk``).
RISK = RiskRule()

#: A pose is at risk at q_n >= RISK_FACTOR x the map's median q_n (or degenerate).
RISK_FACTOR = RISK.factor
#: A pair is at risk when this share of its unguided plan's poses is.
AT_RISK_SHARE = RISK.share
#: Poses per second of trajectory the rule looks at.
RISK_RATE = RISK.rate


def map_median(solm, median: str = RISK.median) -> float:
    """The map's median q_n over its evaluated, non-degenerate cells; on an SE(2)
    SOLM over each cell's best heading (``median`` best_heading, module docstring) or
    over every cell and heading (all_headings)."""
    q = np.asarray(solm.channel("q_n"), dtype=np.float64)
    q = np.where(np.isfinite(q) & ~np.asarray(solm.channel("degenerate")).astype(bool), q, np.inf)
    if solm.grid_spec.space is Space.SE2 and median == "best_heading":
        q = q.min(axis=0)
    q = q[np.isfinite(q)]
    return float(np.median(q)) if q.size else float("nan")


def risk_share(solm, trajectory, *, rule: RiskRule = RISK) -> float:
    """The share of ``trajectory``'s poses (sampled at ``rule.rate`` Hz) that are at risk
    on ``solm`` by ``rule`` (module docstring)."""
    s = trajectory.sample(rule.rate)
    cell = solm.grid_spec.cell(s["x"], s["y"], s["yaw"] if solm.grid_spec.space is Space.SE2 else None)
    q = np.asarray(solm.channel("q_n"), dtype=np.float64)[cell]
    degenerate = np.asarray(solm.channel("degenerate")).astype(bool)[cell]
    risky = degenerate | (q >= rule.factor * map_median(solm, rule.median))  # NaN (not evaluated): not at risk
    return float(np.mean(risky))


def at_risk(share: float, rule: RiskRule = RISK) -> bool:
    """Whether a pair whose unguided plan has ``share`` of its poses at risk is at risk."""
    return share >= rule.share
