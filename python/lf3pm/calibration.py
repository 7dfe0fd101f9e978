"""Calibrations from the metric to errors in metres, so that a metric answers in
units a user understands, not against an arbitrary threshold:

- expected MDE (registration error from disturbed starts at one pose, the
  correlation study's ground truth): below;
- expected localization error (APE of map localization along a trajectory, the
  benefit study's replays) from q_n: :func:`fit_localization_error`.

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
#: The packaged localization-error fit (from `lf3pm experiment benefit`).
LOCALIZATION_PACKAGED = "localization_error.json"


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


@lru_cache(maxsize=2)
def packaged_calibration(name: str = PACKAGED) -> dict | None:
    """A calibration shipped with lf3pm: expected MDE (fitted by `lf3pm experiment
    correlation`) or, with LOCALIZATION_PACKAGED, expected localization error
    (fitted by `lf3pm experiment benefit`); None while it has not been fitted (the
    study that fits it evaluates poses before its fit exists)."""
    path = resources.files("lf3pm").joinpath("calibration_data", name)
    return json.loads(path.read_text()) if path.is_file() else None


def calibration_applies(calibration: dict, *, sensor: str, dof: int, association: str,
                        scan_voxel: float, noise_is_default: bool, w1: float) -> bool:
    """Whether a query was evaluated under the conditions the calibration was fitted
    in (its sensor or sensors, default noise, dof 6, k-NN association, no scan
    downsampling, its w1)."""
    p = calibration["provenance"]
    sensors = p["sensors"] if "sensors" in p else [p["sensor"]]
    return (sensor in sensors and dof == 6 and association == "knn" and scan_voxel == 0
            and noise_is_default and abs(w1 - p["w1"]) < 1e-12)


def fit_localization_error(maps, q_n, ape, *, provenance: dict) -> dict:
    """The localization error predicted from q_n: a least-squares fit of log APE =
    a + b log q_n over trajectories (``maps`` (n,) their map names, ``q_n`` (n,)
    the time mean of q_n along each, ``ape`` (n,) its localization APE, m), with
    the 10-90 % quantiles of the residuals as the interval. ``validation``: the
    same fit with each map left out, judged on that map's trajectories (share
    inside the interval, Spearman rho within the map, median factor between
    predicted and measured)."""
    from scipy.stats import spearmanr

    maps = np.asarray(maps)
    q_n, ape = np.asarray(q_n, float), np.asarray(ape, float)
    keep = np.isfinite(q_n) & np.isfinite(ape) & (q_n > 0) & (ape > 0)
    maps, x, y = maps[keep], np.log(q_n[keep]), np.log(ape[keep])

    def fit(sel):
        b, a = np.polyfit(x[sel], y[sel], 1)
        lo, hi = np.quantile(y[sel] - (a + b * x[sel]), INTERVAL_QUANTILES)
        return {"a": float(a), "b": float(b), "log_lo": float(lo), "log_hi": float(hi)}

    validation = {}
    for name in sorted(set(maps.tolist())):
        held = maps == name
        if held.all() or held.sum() < 2:
            continue
        f = fit(~held)
        centre = f["a"] + f["b"] * x[held]
        inside = (y[held] >= centre + f["log_lo"]) & (y[held] <= centre + f["log_hi"])
        rho = spearmanr(x[held], y[held]).statistic if np.ptp(x[held]) > 0 else math.nan
        validation[name] = {"plans": int(held.sum()), "share_inside_interval": float(np.mean(inside)),
                            "spearman_within_map": None if not math.isfinite(rho) else float(rho),
                            "median_factor": float(math.exp(np.median(np.abs(y[held] - centre))))}
    return {"predictor": "q_n", **fit(np.ones(len(x), bool)), "interval_quantiles": list(INTERVAL_QUANTILES),
            "samples": int(len(x)), "q_n_range": [float(math.exp(x.min())), float(math.exp(x.max()))],
            "validation": validation, "provenance": provenance}


def predict_localization_error(calibration: dict, q_n: float) -> tuple[float, float, float] | None:
    """(expected localization error, low, high) in m at ``q_n``; None when q_n is not
    positive and finite (a degenerate pose: localization there follows odometry)."""
    if not (math.isfinite(q_n) and q_n > 0):
        return None
    centre = calibration["a"] + calibration["b"] * math.log(q_n)
    return (math.exp(centre), math.exp(centre + calibration["log_lo"]),
            math.exp(centre + calibration["log_hi"]))
