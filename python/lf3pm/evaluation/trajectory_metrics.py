"""Trajectory error metrics in the conventions of the evo package (implemented
here; evo is not a dependency). Trajectories are (N, 4, 4) sensor-to-world
matrices, reference P_i and estimate Q_i, paired by index.

- APE (absolute pose error), translation part: e_i = |trans(P_i^-1 Q_i)|
  = |t(Q_i) - t(P_i)|; optionally after the SE(3) Umeyama alignment of the
  estimate onto the reference.
- RPE (relative pose error) over index pairs (i, j):
  E_ij = (P_i^-1 P_j)^-1 (Q_i^-1 Q_j); translation |trans(E_ij)| (m), rotation
  angle(rot(E_ij)) (deg). Pairs: j = i + delta frames for every i, or, for a
  delta in metres, evo's non-overlapping path segments: walking along the
  reference, a pair closes as soon as the path length since its start reaches
  delta, and the next one starts there.
- Statistics of e: rmse = sqrt(mean e^2), mean, median, max, min, std.
"""

from __future__ import annotations

import math

import numpy as np

from lf3pm.errors import Lf3pmError


def error_stats(errors) -> dict:
    """rmse, mean, median, max, min, std (population) and count of ``errors``."""
    e = np.asarray(errors, dtype=np.float64)
    if e.size == 0:
        nan = math.nan
        return {"rmse": nan, "mean": nan, "median": nan, "max": nan, "min": nan, "std": nan,
                "count": 0}
    return {"rmse": float(np.sqrt(np.mean(e * e))), "mean": float(np.mean(e)),
            "median": float(np.median(e)), "max": float(np.max(e)), "min": float(np.min(e)),
            "std": float(np.std(e)), "count": int(e.size)}


def _check_pair(reference, estimate) -> tuple[np.ndarray, np.ndarray]:
    ref = np.asarray(reference, dtype=np.float64)
    est = np.asarray(estimate, dtype=np.float64)
    if ref.ndim != 3 or ref.shape[1:] != (4, 4) or ref.shape != est.shape:
        raise Lf3pmError(f"trajectories must be two (N, 4, 4) arrays of equal N, "
                         f"got {ref.shape} and {est.shape}")
    if len(ref) < 2:
        raise Lf3pmError(f"trajectory metrics need at least 2 poses, got {len(ref)}")
    return ref, est


def umeyama_alignment(source, target) -> np.ndarray:
    """The rigid transform T (4 x 4, no scale) minimising sum |target_i - T source_i|^2
    over point pairs (N, 3) (Umeyama 1991, scale fixed to 1)."""
    src = np.asarray(source, dtype=np.float64)
    dst = np.asarray(target, dtype=np.float64)
    if src.shape != dst.shape or src.ndim != 2 or src.shape[1] != 3 or len(src) < 2:
        raise Lf3pmError(f"alignment needs two (N, 3) point sets, N >= 2, got {src.shape} and {dst.shape}")
    mu_s, mu_d = src.mean(axis=0), dst.mean(axis=0)
    cov = (dst - mu_d).T @ (src - mu_s) / len(src)
    u, _, vt = np.linalg.svd(cov)
    # The sign fix keeps a proper rotation when the best orthogonal map would reflect.
    s = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        s[2, 2] = -1.0
    T = np.eye(4)
    T[:3, :3] = u @ s @ vt
    T[:3, 3] = mu_d - T[:3, :3] @ mu_s
    return T


def rotation_angle(R) -> float:
    """Angle (rad) of the rotation matrix R; atan2 keeps small angles exact."""
    sin_part = 0.5 * math.hypot(R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1])
    return math.atan2(sin_part, (np.trace(R) - 1.0) / 2.0)


def ape_translation(reference, estimate, *, align: bool = False) -> dict:
    """APE translation statistics (m) of ``estimate`` against ``reference``; with
    ``align`` the estimate is first moved by the Umeyama SE(3) alignment of its
    positions onto the reference's (the transform is returned as "alignment")."""
    ref, est = _check_pair(reference, estimate)
    T = umeyama_alignment(est[:, :3, 3], ref[:, :3, 3]) if align else np.eye(4)
    positions = est[:, :3, 3] @ T[:3, :3].T + T[:3, 3]
    errors = np.linalg.norm(positions - ref[:, :3, 3], axis=1)
    return {**error_stats(errors), "aligned": bool(align), "alignment": T.tolist(),
            "errors": errors.tolist()}


def pairs_by_frames(count: int, delta: int) -> list[tuple[int, int]]:
    """(i, i + delta) for every i."""
    if delta < 1:
        raise Lf3pmError(f"RPE delta must be >= 1 frame, got {delta}")
    return [(i, i + delta) for i in range(count - delta)]


def pairs_by_path(positions, delta: float) -> list[tuple[int, int]]:
    """Non-overlapping pairs that each span at least ``delta`` metres of path (evo's
    filter_pairs_by_path without all_pairs)."""
    if not delta > 0:
        raise Lf3pmError(f"RPE delta must be > 0 m, got {delta}")
    steps = np.linalg.norm(np.diff(np.asarray(positions, dtype=np.float64), axis=0), axis=1)
    ids, path = [0], 0.0
    for i, step in enumerate(steps, start=1):
        path += float(step)
        if path >= delta:
            ids.append(i)
            path = 0.0
    return list(zip(ids, ids[1:]))


def rpe(reference, estimate, *, delta: float = 1, unit: str = "frames") -> dict:
    """RPE translation (m) and rotation (deg) statistics over the pairs of ``delta``
    frames (unit="frames") or metres of reference path (unit="m")."""
    ref, est = _check_pair(reference, estimate)
    if unit == "frames":
        if int(delta) != delta:
            raise Lf3pmError(f"an RPE delta in frames must be an integer, got {delta}")
        pairs = pairs_by_frames(len(ref), int(delta))
    elif unit == "m":
        pairs = pairs_by_path(ref[:, :3, 3], float(delta))
    else:
        raise Lf3pmError(f"RPE delta unit must be 'frames' or 'm', got {unit!r}")
    t_err, r_err = [], []
    for i, j in pairs:
        E = np.linalg.inv(np.linalg.inv(ref[i]) @ ref[j]) @ (np.linalg.inv(est[i]) @ est[j])
        t_err.append(float(np.linalg.norm(E[:3, 3])))
        r_err.append(math.degrees(rotation_angle(E[:3, :3])))
    return {"delta": delta, "unit": unit, "pairs": len(pairs), "translation": error_stats(t_err),
            "rotation_deg": error_stats(r_err)}
