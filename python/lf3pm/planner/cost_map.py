"""Perception cost layer: a SOLM channel made into a non-negative per-cell cost.

Normalisation, so that one weight lambda means the same trade-off on any map:
the channel is divided by its median over the evaluated cells (finite values;
se2: over every yaw bin), so a typical cell costs 1 and an edge through it
costs length * (1 + lambda). The median is robust to the long upper tail q
has near degenerate places; a median of 0 falls back to the mean, and an
all-zero channel gives zero cost.

Cap: degenerate cells (q = +inf, or flagged ``degenerate`` in the SOLM) and
finite values above it get the cap, the 99th percentile of the normalised
finite values (``cap_percentile``), so one extreme cell cannot dominate a path
and the layer stays finite. Cells the SOLM did not evaluate (obstacles,
unknown ground: NaN) stay NaN in ``cost`` and hold the cap in ``filled``, the
finite array the trajectory optimiser interpolates.

Transform: the normalised channel is raised to ``power`` (before the cap), so that
the cost can separate a near-degenerate view from a good one as strongly as
localization error does (docs/benefit.md measures which channel and power do).

Composite ``q_n_q_min``: per cell the larger of q_n / median(q_n) and q_min /
median(q_min). q_n predicts the error of localization against the map; q_min is the
view's weakest direction (1 / sqrt of the smallest eigenvalue of A^T A), along which an
odometry, which has only its own map, drifts (docs/lio.md, "Drift along the view's
weakest direction"). A cell is as costly as the worse of the two says.

Channel ``none`` gives zero cost: the planner then finds shortest paths.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lf3pm import libm
from lf3pm.config import COMPOSITE_CHANNELS, COST_CHANNELS, DEFAULTS
from lf3pm.errors import Lf3pmError


@dataclass(frozen=True)
class CostLayer:
    """``cost``: float64 of the channel's shape, >= 0, NaN where not evaluated;
    ``filled``: the same with NaN replaced by ``cap`` (finite everywhere);
    ``scale``: the divisor applied to the channel; ``cap``: the largest cost."""

    channel: str
    cost: np.ndarray
    filled: np.ndarray
    scale: float
    cap: float


def cost_from_values(
    values,
    channel: str = DEFAULTS.guidance.metric,
    *,
    degenerate=None,
    power: float = DEFAULTS.guidance.power,
    cap_percentile: float = 99.0,
) -> CostLayer:
    """The cost layer of one channel's array (NaN: not evaluated, +inf: degenerate);
    ``degenerate`` optionally flags more cells to cap; ``power``: the exponent applied
    to the normalised values."""
    if channel not in COST_CHANNELS:
        raise Lf3pmError(f"unknown cost channel {channel!r}; use one of {', '.join(COST_CHANNELS)}")
    if not 0 < cap_percentile <= 100:
        raise Lf3pmError(f"cap percentile must be in (0, 100], got {cap_percentile}")
    if not (isinstance(power, (int, float)) and math.isfinite(power) and 0 < power <= 10):
        raise Lf3pmError(f"cost power must be a number in (0, 10], got {power!r}")
    values = np.asarray(values, dtype=np.float64)
    if channel == "none":
        zeros = np.zeros(values.shape)
        return CostLayer(channel, zeros, zeros.copy(), 1.0, 0.0)
    finite = np.isfinite(values)
    if degenerate is not None:
        finite &= ~np.asarray(degenerate, dtype=bool)
    if not finite.any():
        raise Lf3pmError(f"channel {channel} has no finite value to normalise by")
    if np.any(values[finite] < 0) or np.any(values == -np.inf):
        raise Lf3pmError(f"channel {channel} has negative values; a cost must be >= 0")
    scale = float(np.median(values[finite]))
    if scale <= 0:
        scale = float(np.mean(values[finite]))
    if scale <= 0:
        scale = 1.0  # all zero: no place is better than another
    cost = np.where(finite, libm.power(values / scale, power), np.inf)
    cap = float(np.percentile(cost[finite], cap_percentile))
    cost = np.minimum(cost, cap)
    cost[np.isnan(values)] = np.nan
    return CostLayer(channel, cost, np.where(np.isnan(cost), cap, cost), scale, cap)


def cost_from_solm(
    solm,
    channel: str = DEFAULTS.guidance.metric,
    *,
    power: float = DEFAULTS.guidance.power,
    cap_percentile: float = 99.0,
) -> CostLayer:
    """The cost layer of ``solm``'s ``channel`` (shape (ny, nx) for r2, (yaw_bins,
    ny, nx) for se2), raised to ``power``, with the SOLM's degenerate mask capped."""
    if not solm.grid_spec.space.ground:
        raise Lf3pmError(f"the planner needs an r2 or se2 SOLM, got {solm.grid_spec.space}")
    if channel == "none":
        return cost_from_values(np.zeros(solm.grid_spec.shape), "none")
    if channel not in COST_CHANNELS:
        raise Lf3pmError(f"unknown cost channel {channel!r}; use one of {', '.join(COST_CHANNELS)}")
    degenerate = np.asarray(solm.channel("degenerate")).astype(bool)
    if channel in COMPOSITE_CHANNELS:
        values = np.maximum.reduce(
            [relative_to_median(solm.channel(part), part, degenerate) for part in COMPOSITE_CHANNELS[channel]]
        )
    else:
        values = solm.channel(channel)
    return cost_from_values(values, channel, degenerate=degenerate, power=power, cap_percentile=cap_percentile)


def relative_to_median(values, channel: str, degenerate=None) -> np.ndarray:
    """``values`` divided by the scale cost_from_values normalises them by (their median
    over the finite, non-degenerate cells); NaN and +inf kept."""
    scale = cost_from_values(values, channel, degenerate=degenerate, power=1.0).scale
    return np.asarray(values, dtype=np.float64) / scale
