"""What an audit's scans say together: how each prediction ranks the scans by real error,
how often the real error falls inside the predicted interval, the simulated/real metric
ratio and the scans where the prediction is furthest off."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from lf3pm.audit.record import ScanAudit, _json

#: The predictions ranked against real errors: ScanAudit field -> what it is.
PREDICTIONS = {
    "real_q_n": "q_n of the recorded scan",
    "real_q_min": "q_min of the recorded scan",
    "real_q_max": "q_max of the recorded scan",
    "predicted_error_m": "predicted localization error (m)",
    "predicted_mde": "predicted MDE (the mde's unit)",
    "sim_q_n": "q_n of the simulated scan",
}
#: The real errors: ScanAudit field -> what it is.
REAL_ERRORS = {
    "error_m": "registration error against the reference (mean over converged starts, m)",
    "spread_m": "spread of the converged registrations (RMS, m)",
    "tracking_error_m": "map localization tracking along the run from the previous estimate, its error here (m)",
    "mde": "MDE over the disturbed starts (lf3pm mde's: mean squared twist error)",
}
#: Each predicted interval and the real error it predicts: (centre, low, high) fields -> the
#: real errors it is judged against (the localization error against each real error in
#: metres, the MDE against the MDE).
INTERVALS = {
    ("predicted_error_m", "predicted_error_lo_m", "predicted_error_hi_m"): (
        "error_m",
        "spread_m",
        "tracking_error_m",
    ),
    ("predicted_mde", "predicted_mde_lo", "predicted_mde_hi"): ("mde",),
}
#: How many scans the summary lists where the prediction is furthest off.
FURTHEST_OFF = 5
#: The rank correlations' intervals: a moving-block bootstrap over the scans in time order
#: (neighbouring scans see the same place, so scans are not independent), blocks of about
#: n^(1/3) scans (Hall, Horowitz & Jing 1995), this many draws, this seed, 95 %.
BLOCK_DRAWS, BLOCK_SEED, BLOCK_LEVEL = 2000, 0, 0.95


@dataclass(frozen=True)
class Correlation:
    """Spearman's rank correlation of one prediction with one real error over the scans
    where both are finite (``rho`` NaN below three such scans or with a constant side),
    with its 95 % interval from a moving-block bootstrap (``ci_low``, ``ci_high``; blocks
    of ``block`` consecutive scans: :func:`block_interval`)."""

    prediction: str
    real_error: str
    rho: float
    scans: int
    ci_low: float = math.nan
    ci_high: float = math.nan
    block: int = 0


@dataclass(frozen=True)
class OffScan:
    """A scan where the predicted error is furthest from the real one: ``log_ratio`` is
    ln(predicted / real error against the reference)."""

    index: int
    name: str
    stamp: float
    x: float
    y: float
    z: float
    yaw: float
    predicted_error_m: float
    error_m: float
    log_ratio: float


@dataclass(frozen=True)
class AuditSummary:
    """The summary of an audit's scans (see the module docstring). ``inside_interval``:
    per real error (:data:`INTERVALS`), the share of scans (with a prediction and that
    error) whose error lies within its predicted [10 %, 90 %] interval, with
    ``inside_scans`` such scans;
    ``ratio_*``: sim_q_n / real_q_n over the scans where both are finite (median, 10 %
    and 90 % quantiles)."""

    scans: int
    correlations: tuple
    inside_interval: dict
    inside_scans: dict
    ratio_scans: int
    ratio_median: float
    ratio_p10: float
    ratio_p90: float
    furthest_off: tuple

    def to_dict(self) -> dict:
        return _json_tree(asdict(self))

    def rho(self, prediction: str, real_error: str) -> float:
        """The rank correlation of ``prediction`` with ``real_error`` (ScanAudit field names)."""
        return next(c.rho for c in self.correlations if (c.prediction, c.real_error) == (prediction, real_error))


def _json_tree(value):
    if isinstance(value, dict):
        return {k: _json_tree(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_tree(v) for v in value]
    return _json(value)


def spearman(a, b) -> tuple[float, int]:
    """Spearman's rho of ``a`` and ``b`` over the pairs where both are finite, and their
    number; rho is NaN below three pairs or when a side is constant."""
    from scipy.stats import spearmanr

    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    keep = np.isfinite(a) & np.isfinite(b)
    n = int(keep.sum())
    if n < 3 or np.ptp(a[keep]) == 0 or np.ptp(b[keep]) == 0:
        return math.nan, n
    return float(spearmanr(a[keep], b[keep]).statistic), n


def block_interval(a, b, draws: int = BLOCK_DRAWS, seed: int = BLOCK_SEED, level: float = BLOCK_LEVEL):
    """The percentile interval of Spearman's rho of ``a`` and ``b`` (in time order; pairs
    with a non-finite side left out) under a moving-block bootstrap: each draw joins blocks
    of ``round(n ** (1/3))`` consecutive pairs starting at uniform places until it holds n
    pairs. Draws with a constant side are left out. Returns (low, high, block); NaN
    bounds below three pairs or when fewer than half the draws give a rho."""
    from scipy.stats import rankdata

    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    keep = np.isfinite(a) & np.isfinite(b)
    a, b = a[keep], b[keep]
    n = len(a)
    if n < 3:
        return math.nan, math.nan, 0
    block = max(1, round(n ** (1 / 3)))
    rng = np.random.default_rng(seed)
    starts = rng.integers(0, n - block + 1, size=(draws, -(-n // block)))
    index = (starts[:, :, None] + np.arange(block)).reshape(draws, -1)[:, :n]
    ra, rb = rankdata(a[index], axis=1), rankdata(b[index], axis=1)
    ra -= ra.mean(axis=1, keepdims=True)
    rb -= rb.mean(axis=1, keepdims=True)
    norm = np.sqrt((ra * ra).sum(axis=1) * (rb * rb).sum(axis=1))
    valid = norm > 0
    if valid.sum() < draws / 2:
        return math.nan, math.nan, block
    rho = (ra * rb).sum(axis=1)[valid] / norm[valid]
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(rho, [tail, 100 - tail])
    return float(low), float(high), block


def summarize(records: Sequence[ScanAudit]) -> AuditSummary:
    """The summary of ``records`` (one per audited scan)."""
    column = {
        name: np.array([getattr(r, name) for r in records], dtype=np.float64)
        for name in {*PREDICTIONS, *REAL_ERRORS, *(f for fields in INTERVALS for f in fields), "q_n_ratio"}
    }
    correlations = []
    for real in REAL_ERRORS:
        for prediction in PREDICTIONS:
            rho, n = spearman(column[prediction], column[real])
            low, high, block = block_interval(column[prediction], column[real])
            correlations.append(Correlation(prediction, real, rho, n, low, high, block))
    inside, inside_scans = {}, {}
    for (_, low, high), reals in INTERVALS.items():
        lo, hi = column[low], column[high]
        for real in reals:
            error = column[real]
            keep = np.isfinite(lo) & np.isfinite(hi) & np.isfinite(error)
            inside_scans[real] = int(keep.sum())
            within = (error[keep] >= lo[keep]) & (error[keep] <= hi[keep])
            inside[real] = float(within.mean()) if keep.any() else math.nan
    ratio = column["q_n_ratio"][np.isfinite(column["q_n_ratio"])]
    quantiles = np.quantile(ratio, [0.5, 0.1, 0.9]) if len(ratio) else [math.nan] * 3
    return AuditSummary(
        scans=len(records),
        correlations=tuple(correlations),
        inside_interval=inside,
        inside_scans=inside_scans,
        ratio_scans=int(len(ratio)),
        ratio_median=float(quantiles[0]),
        ratio_p10=float(quantiles[1]),
        ratio_p90=float(quantiles[2]),
        furthest_off=tuple(furthest_off(records)),
    )


def furthest_off(records: Sequence[ScanAudit], count: int = FURTHEST_OFF) -> list[OffScan]:
    """The ``count`` scans with the largest |ln(predicted / real error against the
    reference)|, largest first (scans without both left out)."""
    off = []
    for r in records:
        if r.predicted_error_m > 0 and r.error_m > 0 and math.isfinite(r.predicted_error_m * r.error_m):
            ratio = math.log(r.predicted_error_m / r.error_m)
            off.append(OffScan(r.index, r.name, r.stamp, r.x, r.y, r.z, r.yaw, r.predicted_error_m, r.error_m, ratio))
    off.sort(key=lambda o: (-abs(o.log_ratio), o.index))
    return off[:count]
