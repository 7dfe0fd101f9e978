"""Issue 42, goal 1 on the real hall run: do `lf3pm audit`'s registration errors agree with
small_gicp run independently on the same scans, from the same starts, against the same map?

The independent side does not go through lf3pm's registration code: small_gicp's own
preprocessing (`preprocess_points`: voxel downsampling and normals), its `align` on NumPy
arrays, and the starts drawn by the rule docs/validation.md states (numpy's SeedSequence
[seed, 0x4D4445], truth @ exp(twist), twist ~ N(0, sigma) per axis, translation then
rotation), with the exponential taken by scipy's expm. Run from the repository root:

    .venv/bin/python docs/investigations/hall_registration_check.py

Prints, per scan, the mean translation error over converged starts of each, and their ratio.
With ``--same-points`` the independent side registers the points lf3pm keeps (its first
point per 0.1 m voxel of the sensor frame) instead of small_gicp's voxel centroids: the one
change that isolates the preprocessing.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import small_gicp
from scipy.linalg import expm

import lf3pm
from lf3pm.audit import audit_scan
from lf3pm.config import DEFAULTS, configured
from lf3pm.runs import Run

RUN = Path(__file__).resolve().parents[3] / "shared" / "data" / "real_hall_run"
EVERY, STARTS, SCAN_VOXEL, SEED = 8, 10, 0.1, 0


def hat(twist: np.ndarray) -> np.ndarray:
    """The 4 x 4 matrix of an se(3) twist (translation, rotation)."""
    v, w = twist[:3], twist[3:]
    m = np.zeros((4, 4))
    m[:3, :3] = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]
    m[:3, 3] = v
    return m


def independent(map_points, tree_target, scan_points, truth, config) -> float:
    mde = config.mde
    if "--same-points" in sys.argv:
        from lf3pm import _core
        from lf3pm.config import scan_params

        kept = _core.scan_of_points(truth, scan_points, scan_params(0.0, math.inf, scan_voxel=SCAN_VOXEL))
        source = small_gicp.PointCloud(np.ascontiguousarray(kept["sensor_points"]))
    else:
        source, _ = small_gicp.preprocess_points(scan_points, downsampling_resolution=SCAN_VOXEL, num_threads=2)
    rng = np.random.default_rng(np.random.SeedSequence([SEED, 0x4D4445]))
    sigmas = np.r_[np.full(3, mde.sigma_t), np.full(3, math.radians(mde.sigma_r))]
    target, tree = tree_target
    errors = []
    for _ in range(STARTS):
        start = truth @ expm(hat(rng.normal(size=6) * sigmas))
        result = small_gicp.align(
            target,
            source,
            tree,
            init_T_target_source=start,
            registration_type="PLANE_ICP",
            max_correspondence_distance=mde.max_correspondence_distance,
            max_iterations=mde.max_iterations,
            num_threads=2,
        )
        if result.converged:
            errors.append(np.linalg.norm((np.linalg.inv(truth) @ result.T_target_source)[:3, 3]))
    return float(np.mean(errors)) if errors else math.nan


def main() -> None:
    config = configured(DEFAULTS, ("scan", "mde"), "check", scan_voxel=SCAN_VOXEL, trials=STARTS, seed=SEED, threads=2)
    world = lf3pm.load_map(RUN, threads=2)
    # small_gicp's own target: the map's points, its own normals (10 neighbours) and tree.
    target = small_gicp.preprocess_points(world.points, downsampling_resolution=1e-3, num_neighbors=10, num_threads=2)
    ratios = []
    print("scan  audit error_m  independent  ratio")
    with Run(RUN) as run:
        for scan in run.scans():
            if scan.index % EVERY:
                continue
            ours = audit_scan(world, scan, lf3pm.get_sensor("os1-64"), config).error_m
            theirs = independent(world.points, target, scan.points, scan.pose, config)
            ratios.append(theirs / ours)
            print(f"{scan.index:4d}  {ours * 1e3:9.2f} mm  {theirs * 1e3:8.2f} mm  {ratios[-1]:.3f}")
    r = np.array(ratios)
    print(
        f"ratio independent / audit: median {np.median(r):.3f}, range {r.min():.3f}-{r.max():.3f}; "
        f"within 20 %: {np.sum(np.abs(r - 1) <= 0.2)} of {len(r)} scans"
    )


if __name__ == "__main__":
    main()
