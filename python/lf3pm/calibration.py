"""Calibrations from the metric to errors in metres, so that a metric answers in
units a user understands, not against an arbitrary threshold:

- expected MDE (registration error from disturbed starts at one pose, the correlation
  study's ground truth), fitted by `lf3pm experiment correlation`;
- expected localization error (APE of map localization along a trajectory, the benefit
  study's replays), fitted by `lf3pm experiment benefit`, or on a user's own recorded run
  by `lf3pm audit --calibrate` (:func:`calibrate_factor`).

Each is a least-squares line log error = a + b log q_n (:func:`fit_on_q_n`) with an
interval from the 10-90 % quantiles of its residuals, stored as JSON with its provenance
(the packaged ones in ``lf3pm/calibration_data/``) and applied by :func:`predict`. A fit
increasing in q_n ranks poses exactly as q_n does, on any map. The MDE fit used to be a
monotone step fit on step_norm, the correlation study's best within-map predictor (0.57
against q_n's 0.26, and 0.56 with step_norm from a scan independent of the MDE's, so no
shared noise draw explains it); on 32 held-out poses of 4 real maps the project never saw
it ranked worse than q_n (within maps 0.36 against 0.57, issue 42), so it is on q_n now
(docs/validation.md). Each holds for the conditions it was fitted under (sensor, range
noise, disturbance size, map density): :func:`calibration_applies`.

Both predict only inside their :func:`support`, the range of q_n the fit saw: beyond it
the line is not measured. :func:`withheld_reason` says why a query gets no prediction.
"""

from __future__ import annotations

import json
import math
from functools import lru_cache
from importlib import resources
from pathlib import Path

import numpy as np

from lf3pm.errors import Lf3pmError

#: Quantiles of the residuals that bound the reported interval.
INTERVAL_QUANTILES = (0.1, 0.9)
#: The packaged expected-MDE fit (from `lf3pm experiment correlation`).
PACKAGED = "vlp16.json"
#: The packaged localization-error fit (from `lf3pm experiment benefit`).
LOCALIZATION_PACKAGED = "localization_error.json"


def support(calibration: dict) -> tuple[float, float]:
    """The lowest and highest q_n among the samples ``calibration`` was fitted on."""
    lo, hi = calibration["q_n_range"]
    return float(lo), float(hi)


def _supported(calibration: dict, value: float) -> bool:
    lo, hi = support(calibration)
    return math.isfinite(value) and lo <= value <= hi


@lru_cache(maxsize=2)
def packaged_calibration(name: str = PACKAGED) -> dict | None:
    """A calibration shipped with lf3pm: expected MDE (fitted by `lf3pm experiment
    correlation`) or, with LOCALIZATION_PACKAGED, expected localization error
    (fitted by `lf3pm experiment benefit`); None while it has not been fitted (the
    study that fits it evaluates poses before its fit exists)."""
    path = resources.files("lf3pm").joinpath("calibration_data", name)
    return json.loads(path.read_text()) if path.is_file() else None


def localization_fit(path: str | None = None) -> dict | None:
    """The localization-error fit at ``path`` (:func:`load_calibration`; the prediction
    section's ``calibration``), or the packaged one when None."""
    if path is None:
        return packaged_calibration(LOCALIZATION_PACKAGED)
    path = Path(path)
    try:
        stamp = path.stat().st_mtime_ns
    except OSError:
        stamp = None  # load_calibration says why in one line
    return _loaded(str(path.resolve()), stamp)


@lru_cache(maxsize=8)
def _loaded(path: str, stamp: int | None) -> dict:
    return load_calibration(path)


def calibration_applies(
    calibration: dict, *, sensor: str, dof: int, association: str, scan_voxel: float, noise_is_default: bool, w1: float
) -> bool:
    """Whether a query was evaluated under the conditions the calibration was fitted
    in (its sensor or sensors, its w1, and :data:`FIT_CONDITIONS` unless its provenance's
    ``conditions`` say otherwise: dof 6, k-NN association, no scan downsampling, default
    noise)."""
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


#: The conditions of a fit's queries that its provenance may record (as ``conditions``), and
#: their values where it does not (the packaged fits were made under these).
FIT_CONDITIONS = {"dof": 6, "association": "knn", "scan_voxel": 0.0, "noise_is_default": True}


def _mismatch(calibration: dict, *, sensor, dof, association, scan_voxel, noise_is_default, w1) -> str | None:
    """The first condition of a query that differs from the fit's, in words; None if none."""
    p = calibration["provenance"]
    fitted = {**FIT_CONDITIONS, **p.get("conditions", {})}
    sensors = p["sensors"] if "sensors" in p else [p["sensor"]]
    if sensor not in sensors:
        return f"sensor {sensor}, fitted for {', '.join(sensors)} only"
    if dof != fitted["dof"]:
        return f"dof {dof}, fitted at dof {fitted['dof']}"
    if association != fitted["association"]:
        return f"association {association}, fitted with {fitted['association']}"
    if abs(scan_voxel - fitted["scan_voxel"]) >= 1e-12:
        at = f"scan_voxel {fitted['scan_voxel']:g}" if fitted["scan_voxel"] else "without scan downsampling"
        return f"scan_voxel {scan_voxel:g}, fitted {at}"
    if noise_is_default != fitted["noise_is_default"]:
        return (
            "range noise set, fitted at the sensor's default"
            if fitted["noise_is_default"]
            else ("the sensor's default range noise, fitted with noise set")
        )
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


def fit_on_q_n(groups, q_n, error, *, provenance: dict, counted: str = "plans") -> dict:
    """The error predicted from q_n: a least-squares fit of log error = a + b log q_n over
    samples (``groups`` (n,) the map each was taken on, ``q_n`` (n,), ``error`` (n,) in its
    unit), with the 10-90 % quantiles of the residuals as the interval. ``validation``:
    the same fit with each group left out, judged on that group's samples (``counted``:
    their number, named after what a sample is; share inside the interval, Spearman rho
    within the group, median factor between predicted and measured)."""
    q_n, keep, x, y = _logs(q_n, error)
    groups = np.asarray(groups)[keep]

    def fit(sel):
        b, a = np.polyfit(x[sel], y[sel], 1)
        return _line(a, b, x[sel], y[sel])

    validation = {}
    for name in sorted(set(groups.tolist())):
        held = groups == name
        if held.all() or held.sum() < 2:
            continue
        validation[name] = {counted: int(held.sum()), **_judged(fit(~held), x[held], y[held])}
    return {
        **_header(fit(np.ones(len(x), bool)), x),
        "q_n_range": [float(q_n[keep].min()), float(q_n[keep].max())],
        "validation": validation,
        "provenance": provenance,
    }


def _logs(q_n, error) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(q_n as float64, which pairs are kept: both finite and positive, ln q_n and ln error
    of those)."""
    q_n, error = np.asarray(q_n, float), np.asarray(error, float)
    keep = np.isfinite(q_n) & np.isfinite(error) & (q_n > 0) & (error > 0)
    return q_n, keep, np.log(q_n[keep]), np.log(error[keep])


def _line(a: float, b: float, x: np.ndarray, y: np.ndarray) -> dict:
    """The line ln error = a + b ln q_n with its interval: the 10-90 % quantiles of the
    residuals of the samples (``x``, ``y``: logs) it was fitted on."""
    lo, hi = np.quantile(y - (a + b * x), INTERVAL_QUANTILES)
    return {"a": float(a), "b": float(b), "log_lo": float(lo), "log_hi": float(hi)}


def _header(line: dict, x: np.ndarray) -> dict:
    """What every fit on q_n begins with: its predictor, ``line``, the interval's quantiles
    and its sample count."""
    return {"predictor": "q_n", **line, "interval_quantiles": list(INTERVAL_QUANTILES), "samples": int(len(x))}


def _judged(line: dict, x: np.ndarray, y: np.ndarray) -> dict:
    """How the fit ``line`` (a, b, log_lo, log_hi) predicts samples it was not fitted on
    (``x`` log q_n, ``y`` log error): the share inside its interval, Spearman rho of q_n
    with the error (None where a side is constant), the median factor between predicted and
    measured."""
    from scipy.stats import spearmanr

    centre = line["a"] + line["b"] * x
    inside = (y >= centre + line["log_lo"]) & (y <= centre + line["log_hi"])
    rho = spearmanr(x, y).statistic if np.ptp(x) > 0 and np.ptp(y) > 0 else math.nan
    return {
        "share_inside_interval": float(np.mean(inside)),
        "spearman_within_map": None if not math.isfinite(rho) else float(rho),
        "median_factor": float(math.exp(np.median(np.abs(y - centre)))),
    }


def predict(calibration: dict, q_n: float) -> tuple[float, float, float] | None:
    """(expected error, low, high) at ``q_n``, in the unit of the error ``calibration`` was
    fitted on (:func:`fit_on_q_n`); None when q_n is not finite (a degenerate pose:
    localization there follows odometry) or lies outside the fit's :func:`support`."""
    if not _supported(calibration, q_n):
        return None
    centre = calibration["a"] + calibration["b"] * math.log(q_n)
    return (math.exp(centre), math.exp(centre + calibration["log_lo"]), math.exp(centre + calibration["log_hi"]))


#: Contiguous segments of a run that :func:`calibrate_factor` leaves out one at a time.
CALIBRATION_SEGMENTS = 5


def calibrate_factor(base: dict, q_n, error, *, provenance: dict, segments: int = CALIBRATION_SEGMENTS) -> dict:
    """``base`` (a localization-error fit) recalibrated on one recorded run: its slope b
    kept (a run spans too narrow a range of q_n to fit one), its offset a and 10-90 %
    interval refitted on the run's samples (``q_n`` and ``error`` in time order; non-finite
    or non-positive pairs left out). ``q_n_range`` spans ``base``'s and the run's
    (``run_q_n_range``): the slope that carries the run's offset across it was measured
    over ``base``'s. ``factor``: how much the run's errors exceed ``base``'s prediction (exp
    of the offsets' difference). Validated
    by leaving out each of ``segments`` contiguous segments in turn (neighbouring scans see
    the same place): ``validation`` per segment, the recalibrated fit and ``base`` judged on
    it (:func:`_judged`). Raises Lf3pmError below 2 samples per segment."""
    q_n, keep, x, y = _logs(q_n, error)
    if len(x) < 2 * segments:
        raise Lf3pmError(f"calibrating needs at least {2 * segments} scans with a finite q_n and error, got {len(x)}")
    b = base["b"]

    def fit(sel):
        return _line(float(np.median(y[sel] - b * x[sel])), b, x[sel], y[sel])

    validation = {}
    for k, held in enumerate(np.array_split(np.arange(len(x)), segments)):
        sel = np.ones(len(x), bool)
        sel[held] = False
        validation[f"segment {k + 1}"] = {
            "scans": int(len(held)),
            **_judged(fit(sel), x[held], y[held]),
            "shipped": _judged(base, x[held], y[held]),
        }
    line = fit(np.ones(len(x), bool))
    return {
        **_header(line, x),
        "q_n_range": [min(float(q_n[keep].min()), support(base)[0]), max(float(q_n[keep].max()), support(base)[1])],
        "run_q_n_range": [float(q_n[keep].min()), float(q_n[keep].max())],
        "factor": math.exp(line["a"] - base["a"]),
        "shipped": _judged(base, x, y),
        "validation": validation,
        "provenance": provenance,
    }


def load_calibration(path) -> dict:
    """A localization-error fit written by `lf3pm audit --calibrate` (or the benefit study's
    localization_error.json); Lf3pmError in one line if it is missing or not such a fit."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except OSError as err:
        raise Lf3pmError(f"calibration {path}: {err.strerror or err}") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise Lf3pmError(f"calibration {path}: not JSON ({err})") from None
    needed = ("a", "b", "log_lo", "log_hi", "q_n_range", "samples", "provenance")
    missing = [k for k in needed if not isinstance(data, dict) or k not in data]
    if missing or data.get("predictor") != "q_n":
        what = f"no {', '.join(missing)}" if missing else f"predictor {data.get('predictor')!r}, not q_n"
        raise Lf3pmError(f"calibration {path}: not a localization-error fit on q_n ({what})")
    return data
