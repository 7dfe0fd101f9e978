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

Both predict only inside their :func:`support`, the range of the predictor the
fit saw: beyond it the MDE fit would repeat its end value and the localization
fit extrapolate its line, neither measured. :func:`withheld_reason` says why a
query gets no prediction.
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
    return {
        "predictor": name,
        "log_x": x.tolist(),
        "log_mde": fitted.tolist(),
        "interval_bins": bins,
        "interval_quantiles": list(INTERVAL_QUANTILES),
        "samples": int(keep.sum()),
        "provenance": provenance,
    }


def support(calibration: dict) -> tuple[float, float]:
    """The lowest and highest predictor value among the samples ``calibration`` was
    fitted on (an MDE calibration or a localization-error fit)."""
    if "q_n_range" in calibration:
        lo, hi = calibration["q_n_range"]
        return float(lo), float(hi)
    return math.exp(calibration["log_x"][0]), math.exp(calibration["log_x"][-1])


def _supported(calibration: dict, value: float) -> bool:
    lo, hi = support(calibration)
    return math.isfinite(value) and lo <= value <= hi


def predict_mde(calibration: dict, value: float) -> tuple[float, float, float] | None:
    """(expected MDE, low, high) at predictor ``value``; None outside the fit's
    :func:`support` (a monotone fit cannot extrapolate honestly) or where ``value``
    is not finite."""
    if not _supported(calibration, value):
        return None
    lx = math.log(value)
    centre = float(np.interp(lx, calibration["log_x"], calibration["log_mde"]))
    band = next((b for b in calibration["interval_bins"] if lx <= b["log_x_max"]), calibration["interval_bins"][-1])
    return math.exp(centre), math.exp(centre + band["log_lo"]), math.exp(centre + band["log_hi"])


@lru_cache(maxsize=2)
def packaged_calibration(name: str = PACKAGED) -> dict | None:
    """A calibration shipped with lf3pm: expected MDE (fitted by `lf3pm experiment
    correlation`) or, with LOCALIZATION_PACKAGED, expected localization error
    (fitted by `lf3pm experiment benefit`); None while it has not been fitted (the
    study that fits it evaluates poses before its fit exists)."""
    path = resources.files("lf3pm").joinpath("calibration_data", name)
    return json.loads(path.read_text()) if path.is_file() else None


def calibration_applies(
    calibration: dict, *, sensor: str, dof: int, association: str, scan_voxel: float, noise_is_default: bool, w1: float
) -> bool:
    """Whether a query was evaluated under the conditions the calibration was fitted
    in (its sensor or sensors, default noise, dof 6, k-NN association, no scan
    downsampling, its w1)."""
    return (
        _mismatch(
            calibration,
            sensor=sensor,
            dof=dof,
            association=association,
            scan_voxel=scan_voxel,
            noise_is_default=noise_is_default,
            w1=w1,
        )
        is None
    )


def _mismatch(calibration: dict, *, sensor, dof, association, scan_voxel, noise_is_default, w1) -> str | None:
    """The first condition of a query that differs from the fit's, in words; None if none."""
    p = calibration["provenance"]
    sensors = p["sensors"] if "sensors" in p else [p["sensor"]]
    if sensor not in sensors:
        return f"sensor {sensor}, fitted for {', '.join(sensors)} only"
    if dof != 6:
        return f"dof {dof}, fitted at dof 6"
    if association != "knn":
        return f"association {association}, fitted with knn"
    if scan_voxel != 0:
        return f"scan_voxel {scan_voxel:g}, fitted without scan downsampling"
    if not noise_is_default:
        return "range noise set, fitted at the sensor's default"
    if abs(w1 - p["w1"]) >= 1e-12:
        return f"w1 {w1:g}, fitted at w1 {p['w1']:g}"
    return None


def withheld_reason(calibration: dict | None, value: float, **conditions) -> str | None:
    """Why ``calibration`` (a packaged one: None when not shipped) gives no prediction
    at predictor ``value`` for a query evaluated under ``conditions``
    (:func:`calibration_applies`' keywords), in one line; None when it gives one."""
    if calibration is None:
        return "no fit is shipped with this lf3pm"
    mismatch = _mismatch(calibration, **conditions)
    if mismatch is not None:
        return f"not fitted for this query: {mismatch}"
    return unsupported_reason(calibration, value)


def unsupported_reason(calibration: dict, value: float) -> str | None:
    """Why ``calibration`` gives no prediction at predictor ``value`` whatever the query's
    conditions (a degenerate pose, a value outside its :func:`support`), in one line;
    None when the value is inside it."""
    name = calibration["predictor"]
    if not math.isfinite(value):
        return f"{name} is infinite: the pose is degenerate"
    if not _supported(calibration, value):
        lo, hi = support(calibration)
        return (
            f"{name} {value:.3g} is outside the range the fit was made on ({lo:.3g} to {hi:.3g}, "
            f"{calibration['samples']} samples): not extrapolated"
        )
    return None


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
        validation[name] = {
            "plans": int(held.sum()),
            "share_inside_interval": float(np.mean(inside)),
            "spearman_within_map": None if not math.isfinite(rho) else float(rho),
            "median_factor": float(math.exp(np.median(np.abs(y[held] - centre)))),
        }
    return {
        "predictor": "q_n",
        **fit(np.ones(len(x), bool)),
        "interval_quantiles": list(INTERVAL_QUANTILES),
        "samples": int(len(x)),
        "q_n_range": [float(q_n[keep].min()), float(q_n[keep].max())],
        "validation": validation,
        "provenance": provenance,
    }


def predict_localization_error(calibration: dict, q_n: float) -> tuple[float, float, float] | None:
    """(expected localization error, low, high) in m at ``q_n``; None when q_n is not
    finite (a degenerate pose: localization there follows odometry) or lies outside
    the fit's :func:`support` (``q_n_range``)."""
    if not _supported(calibration, q_n):
        return None
    centre = calibration["a"] + calibration["b"] * math.log(q_n)
    return (math.exp(centre), math.exp(centre + calibration["log_lo"]), math.exp(centre + calibration["log_hi"]))
