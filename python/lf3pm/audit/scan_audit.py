"""Audit one recorded scan at its reference pose: the metric of its real points, the metric
and prediction of the simulated scan there, and real registration from disturbed starts."""

from __future__ import annotations

import math
import time

import numpy as np

from lf3pm.audit.record import ScanAudit
from lf3pm.config import Config
from lf3pm.errors import Lf3pmError
from lf3pm.libm import arccos
from lf3pm.map import Map
from lf3pm.metric import Evaluation, evaluate, evaluate_points
from lf3pm.runs import Scan
from lf3pm.sensors import Sensor
from lf3pm.validation import RegistrationTarget, mde_of_points


def audit_scan(
    map: Map,
    scan: Scan,
    sensor: Sensor,
    config: Config,
    *,
    target: RegistrationTarget | None = None,
    first_stamp: float | None = None,
    register: bool = True,
) -> ScanAudit:
    """The audit of ``scan`` (with its ``pose``) on ``map``: the scan, metric and mde
    sections of ``config`` (scan_voxel, the metric's settings, the mde section's starts,
    sigmas and seed), ``sensor`` for the simulated scan and the prediction. ``target``:
    the map prepared for registration once (built here when None). ``register=False``
    leaves registration out. A part that fails on bad input (a simulated pose the map
    refuses, a scan too small to register) is recorded with its one line, not raised."""
    if scan.pose is None:
        raise Lf3pmError(f"scan {scan.name} has no reference pose")
    pose = np.asarray(scan.pose, dtype=np.float64)
    out = {
        "index": scan.index,
        "name": scan.name,
        "stamp": scan.stamp,
        "time_s": scan.stamp - (scan.stamp if first_stamp is None else first_stamp),
        "x": float(pose[0, 3]),
        "y": float(pose[1, 3]),
        "z": float(pose[2, 3]),
        "yaw": math.atan2(pose[1, 0], pose[0, 0]),
        "points": len(scan.points),
        "pose": tuple(tuple(float(v) for v in row) for row in pose),
    }
    began = time.perf_counter()
    real = evaluate_points(map, pose, scan.points, config)
    out.update(_metric("real", real), hits=real.hits)
    try:
        simulated = evaluate(map, pose, sensor, config)
    except Lf3pmError as err:
        out["sim_error"] = str(err)
    else:
        out.update(_metric("sim", simulated), sim_hits=simulated.hits)
        out["q_n_ratio"] = finite_ratio(simulated.q_n, real.q_n)
        out["direction_angle_deg"] = _angle(real.least_observable, simulated.least_observable)
        if simulated.predicted_localization_error_m is not None:
            lo, hi = simulated.predicted_localization_error_interval_m
            out.update(predicted_error_m=simulated.predicted_localization_error_m)
            out.update(predicted_error_lo_m=lo, predicted_error_hi_m=hi)
        out["predicted_error_withheld"] = simulated.predicted_localization_error_withheld
        if simulated.predicted_mde is not None:
            lo, hi = simulated.predicted_mde_interval
            out.update(predicted_mde=simulated.predicted_mde, predicted_mde_lo=lo, predicted_mde_hi=hi)
        out["predicted_mde_withheld"] = simulated.predicted_mde_withheld
    out["metric_seconds"] = time.perf_counter() - began
    if register:
        began = time.perf_counter()
        out.update(_registration(map, pose, scan.points, config, target, sensor.name))
        out["registration_seconds"] = time.perf_counter() - began
    return ScanAudit(**out)


def _metric(prefix: str, e: Evaluation) -> dict:
    return {
        f"{prefix}_m": e.m,
        f"{prefix}_q_min": e.q_min,
        f"{prefix}_q_n": e.q_n,
        f"{prefix}_q_max": e.q_max,
        f"{prefix}_sigma1": e.sigma1,
        f"{prefix}_degenerate": e.degenerate,
        f"{prefix}_least_observable": tuple(e.least_observable),
        f"{prefix}_residual_rms_m": e.residual_norm / math.sqrt(e.m) if e.m > 0 else math.nan,
    }


def _angle(a, b) -> float:
    """The angle (deg, 0-90) between two unit directions, whatever their signs."""
    cos = min(abs(float(np.dot(a, b))), 1.0)
    return math.degrees(math.acos(cos)) if len(a) == len(b) and len(a) else math.nan


def finite_ratio(a: float, b: float) -> float:
    """a / b, NaN unless both are finite and b > 0."""
    return a / b if math.isfinite(a) and math.isfinite(b) and b > 0 else math.nan


def _registration(map: Map, pose, points, config: Config, target, sensor: str) -> dict:
    try:
        result = mde_of_points(map, pose, points, config, sensor_name=sensor, target=target)
    except Lf3pmError as err:
        return {"registration_error": str(err)}
    flags = np.asarray(result.converged_trials, dtype=bool)
    t_err = np.asarray(result.translation_errors, dtype=np.float64)
    r_err = np.asarray(result.rotation_errors_deg, dtype=np.float64)
    out = {
        "starts": result.trials,
        "converged": result.converged,
        "translation_errors_m": tuple(result.translation_errors),
        "rotation_errors_deg": tuple(result.rotation_errors_deg),
        "converged_starts": tuple(bool(f) for f in flags),
        "mde": result.mde,
    }
    if not flags.any():
        out["registration_error"] = f"none of {result.trials} registrations converged"
        return out
    spread_m, spread_deg = spread(np.asarray(result.registered, dtype=np.float64)[flags])
    out.update(
        error_m=float(t_err[flags].mean()),
        error_max_m=float(t_err[flags].max()),
        rotation_error_deg=float(r_err[flags].mean()),
        rotation_error_max_deg=float(r_err[flags].max()),
        spread_m=spread_m,
        spread_deg=spread_deg,
    )
    return out


def spread(poses: np.ndarray) -> tuple[float, float]:
    """How far poses (K x 4 x 4) lie from each other, whatever the truth: the RMS distance
    of their positions from their mean (m) and the RMS angle of their rotations from their
    chordal mean (the rotation nearest the mean of the matrices; deg)."""
    t = poses[:, :3, 3]
    spread_m = float(np.sqrt(np.mean(np.sum((t - t.mean(axis=0)) ** 2, axis=1))))
    u, _, vt = np.linalg.svd(poses[:, :3, :3].mean(axis=0))
    mean = u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt
    angles = arccos((np.einsum("ij,kij->k", mean, poses[:, :3, :3]) - 1.0) / 2.0)
    return spread_m, float(np.degrees(np.sqrt(np.mean(np.square(angles)))))
