"""Trajectory error metrics, computed by the evo package (``evo.core``), so that
our numbers are the ones the odometry community reports. Trajectories are
(N, 4, 4) sensor-to-world matrices, reference P_i and estimate Q_i, paired by
index (the same times).

- APE (absolute pose error), translation part: e_i = |trans(P_i^-1 Q_i)|
  = |t(Q_i) - t(P_i)| (evo ``APE(PoseRelation.translation_part)``); with
  ``align`` after evo's SE(3) Umeyama alignment of the estimated positions
  onto the reference (``PosePath3D.align``, no scale); evo refuses it (and
  the figures are NaN) when the reference positions lie on a line, where the
  alignment is not unique.
- RPE (relative pose error) over index pairs (i, j):
  E_ij = (P_i^-1 P_j)^-1 (Q_i^-1 Q_j); translation |trans(E_ij)| (m), rotation
  angle(rot(E_ij)) (deg) (evo ``RPE``, consecutive pairs): a delta in frames
  pairs (0, d), (d, 2d), ...; a delta in metres walks along the reference and
  closes a pair as soon as its path length reaches delta, the next starting
  there. Pairs are taken from the reference (evo's ``pairs_from_reference``),
  so that every estimate of one truth is scored on the same pairs.
- Statistics of e: evo's rmse, mean, median, max, min, std (population), plus
  the count.
"""

from __future__ import annotations

import math

import numpy as np

from lf3pm.errors import Lf3pmError


def error_stats(errors) -> dict:
    """rmse, mean, median, max, min, std (population) and count of ``errors``
    (NaN statistics for none)."""
    e = np.asarray(errors, dtype=np.float64)
    if e.size == 0:
        return {k: math.nan for k in ("rmse", "mean", "median", "max", "min", "std")} | {"count": 0}
    return {
        "rmse": float(np.sqrt(np.mean(e * e))),
        "mean": float(np.mean(e)),
        "median": float(np.median(e)),
        "max": float(np.max(e)),
        "min": float(np.min(e)),
        "std": float(np.std(e)),
        "count": int(e.size),
    }


def _statistics(metric) -> dict:
    """evo's statistics of a processed metric, as floats, with the count."""
    stats = metric.get_all_statistics()
    return {k: float(stats[k]) for k in ("rmse", "mean", "median", "max", "min", "std")} | {
        "count": int(len(metric.error))
    }


def _trajectories(reference, estimate):
    from evo.core.trajectory import PoseTrajectory3D

    ref = np.asarray(reference, dtype=np.float64)
    est = np.asarray(estimate, dtype=np.float64)
    if ref.ndim != 3 or ref.shape[1:] != (4, 4) or ref.shape != est.shape:
        raise Lf3pmError(f"trajectories must be two (N, 4, 4) arrays of equal N, got {ref.shape} and {est.shape}")
    if len(ref) < 2:
        raise Lf3pmError(f"trajectory metrics need at least 2 poses, got {len(ref)}")
    if not (np.all(np.isfinite(ref)) and np.all(np.isfinite(est))):
        raise Lf3pmError("trajectory metrics need finite poses")
    stamps = np.arange(len(ref), dtype=np.float64)
    return (
        PoseTrajectory3D(poses_se3=list(ref), timestamps=stamps),
        PoseTrajectory3D(poses_se3=list(est), timestamps=stamps),
    )


def ape_translation(reference, estimate, *, align: bool = False) -> dict:
    """APE translation statistics (m) of ``estimate`` against ``reference``, with
    the per-pose "errors"; with ``align`` the estimate is first moved by evo's
    Umeyama SE(3) alignment of its positions onto the reference's (the 4 x 4
    transform applied is returned as "alignment")."""
    from evo.core import geometry, metrics

    ref, est = _trajectories(reference, estimate)
    T = np.eye(4)
    if align:
        try:
            rotation, translation, _ = est.align(ref, correct_scale=False)
        except geometry.GeometryException:
            # Reference positions on a line (or a point): the alignment is not unique
            # and evo refuses it; there is no aligned figure to report.
            return {
                **error_stats([]),
                "aligned": True,
                "alignment": None,
                "errors": [],
                "note": "no unique SE(3) alignment: the reference positions lie on a line",
            }
        T[:3, :3], T[:3, 3] = rotation, translation
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    return {
        **_statistics(ape),
        "aligned": bool(align),
        "alignment": T.tolist(),
        "errors": [float(e) for e in ape.error],
    }


def rpe(reference, estimate, *, delta: float = 1, unit: str = "frames") -> dict:
    """RPE translation (m) and rotation (deg) statistics over the pairs of ``delta``
    frames (unit="frames") or metres of reference path (unit="m"). With no pair
    (a path shorter than delta) the statistics are NaN."""
    from evo.core import filters, metrics

    if unit == "frames":
        if int(delta) != delta or delta < 1:
            raise Lf3pmError(f"an RPE delta in frames must be an integer >= 1, got {delta}")
        evo_unit, delta = metrics.Unit.frames, int(delta)
    elif unit == "m":
        if not (math.isfinite(delta) and delta > 0):
            raise Lf3pmError(f"an RPE delta in metres must be > 0, got {delta}")
        evo_unit, delta = metrics.Unit.meters, float(delta)
    else:
        raise Lf3pmError(f"RPE delta unit must be 'frames' or 'm', got {unit!r}")
    ref, est = _trajectories(reference, estimate)
    out = {"delta": delta, "unit": unit}
    for key, relation in (
        ("translation", metrics.PoseRelation.translation_part),
        ("rotation_deg", metrics.PoseRelation.rotation_angle_deg),
    ):
        metric = metrics.RPE(relation, delta=delta, delta_unit=evo_unit, all_pairs=False, pairs_from_reference=True)
        try:
            metric.process_data((ref, est))
        except filters.FilterException:
            metric.error = np.array([])  # evo refuses a trajectory without a single pair
        out[key] = _statistics(metric) if len(metric.error) else error_stats([])
        out["pairs"] = int(len(metric.error))
    return out


#: The time shifts :func:`time_offset` tries (s): +-0.3 s in 5 ms steps.
TIME_SHIFTS = np.round(np.arange(-300, 301, 5) * 1e-3, 3)


def time_offset(times, estimate, truth_at) -> dict:
    """How far in time an estimate is from the truth it is scored against: the shift
    tau of :data:`TIME_SHIFTS` that minimises the translation RMSE between the
    estimate at ``times`` and ``truth_at(times + tau)`` ((n,) -> (n, 4, 4) poses).
    A negative offset is an estimate that lags the truth (it is where the sensor was
    -offset s earlier). Returns offset (s), rmse at that shift and rmse at zero (m).
    A replay whose clocks agree has its minimum at 0 within the 5 ms grid; a
    clearly lower rmse elsewhere is a timing fault (docs/lio.md)."""
    t = np.asarray(times, dtype=np.float64)
    q = np.asarray(estimate, dtype=np.float64)[:, :3, 3]
    if t.ndim != 1 or len(t) < 2 or q.shape != (len(t), 3):
        raise Lf3pmError(
            f"time_offset needs times (n,) and poses (n, 4, 4), n >= 2; got {t.shape} and {np.shape(estimate)}"
        )
    rmse = np.array(
        [math.sqrt(np.mean(np.sum((q - np.asarray(truth_at(t + tau))[:, :3, 3]) ** 2, axis=1))) for tau in TIME_SHIFTS]
    )
    best = int(np.argmin(rmse))
    return {
        "offset": float(TIME_SHIFTS[best]),
        "rmse": float(rmse[best]),
        "rmse_at_zero": float(rmse[np.flatnonzero(TIME_SHIFTS == 0)[0]]),
    }
