"""Calibration from a predictor to expected MDE, so that a metric answers in
units a user understands (registration error), not against an arbitrary
threshold.

A calibration is a monotone (isotonic) regression of log MDE on log predictor,
fitted on the correlation study's poses, with an interval from the spread of
the residuals in bins of the predictor. It is stored as JSON in the package
(``lf3pm/calibration_data/``) with its provenance, and applied by
:func:`predict_mde`. It holds for the conditions it was fitted under (sensor,
range noise, disturbance size, map density): see docs/validation.md.
"""

from __future__ import annotations

import json
import math
from functools import lru_cache
from importlib import resources

import numpy as np
from scipy.optimize import isotonic_regression

#: Quantiles of the residuals that bound the reported interval.
INTERVAL_QUANTILES = (0.1, 0.9)
#: Bins of the predictor over which the residual spread is measured.
INTERVAL_BINS = 5
PACKAGED = "vlp16.json"


def fit_calibration(predictor: np.ndarray, mde: np.ndarray, *, name: str, provenance: dict) -> dict:
    """Isotonic fit of log MDE on log ``predictor`` (both positive and finite)."""
    keep = np.isfinite(predictor) & np.isfinite(mde) & (predictor > 0) & (mde > 0)
    x, y = np.log(predictor[keep]), np.log(mde[keep])
    order = np.argsort(x)
    x, y = x[order], y[order]
    fitted = isotonic_regression(y, increasing=True).x
    residual = y - fitted
    edges = np.quantile(x, np.linspace(0, 1, INTERVAL_BINS + 1))
    bins = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (x >= lo) & (x <= hi)
        q_lo, q_hi = np.quantile(residual[sel], INTERVAL_QUANTILES)
        bins.append({"log_x_max": float(hi), "log_lo": float(q_lo), "log_hi": float(q_hi)})
    return {"predictor": name, "log_x": x.tolist(), "log_mde": fitted.tolist(), "interval_bins": bins,
            "interval_quantiles": list(INTERVAL_QUANTILES), "samples": int(keep.sum()),
            "provenance": provenance}


def predict_mde(calibration: dict, value: float) -> tuple[float, float, float] | None:
    """(expected MDE, low, high) at predictor ``value``; None when not positive and
    finite. Beyond the fitted range the end values hold (a monotone fit cannot
    extrapolate honestly)."""
    if not (math.isfinite(value) and value > 0):
        return None
    lx = math.log(value)
    centre = float(np.interp(lx, calibration["log_x"], calibration["log_mde"]))
    band = next((b for b in calibration["interval_bins"] if lx <= b["log_x_max"]),
                calibration["interval_bins"][-1])
    return math.exp(centre), math.exp(centre + band["log_lo"]), math.exp(centre + band["log_hi"])


@lru_cache(maxsize=1)
def packaged_calibration() -> dict:
    """The calibration shipped with lf3pm (fitted by `lf3pm experiment correlation`)."""
    text = resources.files("lf3pm").joinpath("calibration_data", PACKAGED).read_text()
    return json.loads(text)


def calibration_applies(calibration: dict, *, sensor: str, dof: int, association: str,
                        scan_voxel: float, noise_is_default: bool, w1: float) -> bool:
    """Whether a query was evaluated under the conditions the calibration was fitted in."""
    p = calibration["provenance"]
    return (sensor == p["sensor"] and dof == 6 and association == "knn" and scan_voxel == 0
            and noise_is_default and abs(w1 - p["w1"]) < 1e-12)
