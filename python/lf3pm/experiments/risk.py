"""Which start/goal pairs are "at risk": decided from the unguided plan and its SOLM
alone, before any replay, so that the benefit study's populations do not depend on
the replays they are then judged by.

A pose of a trajectory is at risk when its SOLM cell (the nearest one, at the
pose's yaw for SE(2)) is degenerate or predicts an error far above the map's:
q_n at least :data:`RISK_FACTOR` times the map's median q_n. Localization APE
follows q_n with slope 0.97 in log-log over the benefit study's 240 plans
(docs/benefit.md, "Calibration"), so such a pose is predicted to localize an
order of magnitude worse than the map's typical place. A pair is at risk when
at least :data:`AT_RISK_SHARE` of its unguided plan's poses are.
"""

from __future__ import annotations

import numpy as np

#: A pose is at risk at q_n >= RISK_FACTOR x the map's median q_n (or degenerate).
RISK_FACTOR = 10.0
#: A pair is at risk when this share of its unguided plan's poses is.
AT_RISK_SHARE = 0.1
#: Poses per second of trajectory the rule looks at.
RISK_RATE = 10.0


def map_median(solm) -> float:
    """The map's median q_n over its evaluated, non-degenerate cells (as the cost
    layer normalises it, planner/cost_map.py)."""
    q = np.asarray(solm.channel("q_n"), dtype=np.float64)
    ok = np.isfinite(q) & ~np.asarray(solm.channel("degenerate")).astype(bool)
    return float(np.median(q[ok])) if ok.any() else float("nan")


def risk_share(solm, trajectory, *, rate: float = RISK_RATE) -> float:
    """The share of ``trajectory``'s poses (sampled at ``rate`` Hz) that are at risk
    on ``solm`` (module docstring)."""
    s = trajectory.sample(rate)
    cell = solm.grid_spec.cell(s["x"], s["y"], s["yaw"] if solm.grid_spec.space == "se2" else None)
    q = np.asarray(solm.channel("q_n"), dtype=np.float64)[cell]
    degenerate = np.asarray(solm.channel("degenerate")).astype(bool)[cell]
    risky = degenerate | (q >= RISK_FACTOR * map_median(solm))  # NaN (not evaluated): not at risk
    return float(np.mean(risky))


def at_risk(share: float) -> bool:
    """Whether a pair whose unguided plan has ``share`` of its poses at risk is at risk."""
    return share >= AT_RISK_SHARE
