"""Benchmark: SOLM cells per second on the gobi scene, lf3pm against the
pipeline a user would write today, on 2 cores, in one run.

1. Exact, noise-free VLP-16 cells: ours (evaluate_many, all cells in parallel)
   against Open3D RaycastingScene (Embree) + cKDTree + NumPy (bench/baseline_pipeline.py)
   on a mesh at the map's own resolution (a square per 10 cm voxel, what a user would
   build); prints cells/s, the ratio and the q_n agreement, and the same baseline on the
   disc-matched hexagon mesh (4 triangles per point), which agrees with us more closely.
2. Thinned scans (--ray-stride K): cells/s and the relative error of q_n against
   exact cells (median and 95th percentile), with the sensor's range noise.
3. SE(2), Mid-70, 36 yaw bins: exact per bin and by sector Grams (--yaw-reuse),
   per cell, against the R² VLP-16 time.

    .venv/bin/python bench/bench_solm.py [--cells 48] [--threads 2]
Needs open3d (`make bench` installs it, and Debian's libusb-1.0-0 it loads).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from baseline_pipeline import BaselinePipeline, association_and_metric, surfel_mesh, voxel_mesh

import lf3pm
from lf3pm import _core
from lf3pm.config import scan_params
from lf3pm.experiments.free_poses import random_free_poses
from lf3pm.metric import eval_params
from lf3pm.scenes import build_scene
from lf3pm.solm.ray_thinning import thin_rays
from lf3pm.solm.tiles import pose_matrices
from lf3pm.solm.yaw_reuse import sector_layout


def relative_error(a, b) -> tuple[float, float]:
    e = np.abs(np.asarray(a) / np.asarray(b) - 1.0)
    e = e[np.isfinite(e)]
    return float(np.median(e)), float(np.percentile(e, 95))


#: Voxel edge (m) of the baseline's mesh: the gobi map's own point spacing is 5 to 12 cm.
VOXEL_MESH = 0.1


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=48)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    scene = build_scene("gobi", seed=args.seed)
    world = lf3pm.load_map(scene.points, threads=args.threads)
    vlp16, mid70 = lf3pm.get_sensor("vlp16"), lf3pm.get_sensor("mid70")
    lo, hi = world.bounds
    cells = np.array(
        random_free_poses(
            world, args.cells, np.random.default_rng(args.seed), sensor_height=1.0, region=(lo[0], lo[1], hi[0], hi[1])
        )
    )
    poses = pose_matrices(cells[:, 0], cells[:, 1], cells[:, 2], np.zeros(len(cells)))
    streams = np.arange(len(cells), dtype=np.uint64)
    print(f"gobi: {world.size:,} points; {len(cells)} random free cells; {args.threads} threads")

    def ours(directions, sensor, noise, weight=1.0, at=poses):
        t = time.perf_counter()
        res = _core.evaluate_many(
            world.index,
            at,
            streams[: len(at)],
            directions,
            eval_params(
                sensor.min_range, sensor.max_range, noise=noise, seed=args.seed, threads=args.threads, ray_weight=weight
            ),
        )
        return res, (time.perf_counter() - t) / len(at)

    # 1. Exact cells against the baseline.
    exact, ours_s = ours(vlp16.directions, vlp16, 0.0)
    t = time.perf_counter()
    # The baseline a user would build: a mesh at the map's own resolution (a square per
    # 10 cm voxel); the disc-matched hexagon mesh (4 triangles per point) only checks
    # that the two pipelines agree on the same geometry.
    vertices, triangles = voxel_mesh(world.index.points, world.index.normals, VOXEL_MESH)
    baseline = BaselinePipeline(
        world.index.points,
        vertices,
        triangles,
        vlp16.directions,
        vlp16.min_range,
        vlp16.max_range,
        threads=args.threads,
    )
    setup_s = time.perf_counter() - t
    base_cells = poses[: max(4, len(poses) // 4)]
    t = time.perf_counter()
    q_base = np.array([baseline.q_n(p) for p in base_cells])
    base_s = (time.perf_counter() - t) / len(base_cells)
    cast_share = baseline.cast_seconds / (base_s * len(base_cells))
    med, worst = relative_error(q_base, exact["q_n"][: len(base_cells)])
    hexagons = BaselinePipeline(
        world.index.points,
        *surfel_mesh(world.index.points, world.index.normals, world.index.disc_radius),
        vlp16.directions,
        vlp16.min_range,
        vlp16.max_range,
        threads=args.threads,
    )
    t = time.perf_counter()
    q_hex = np.array([hexagons.q_n(p) for p in base_cells])
    hex_s = (time.perf_counter() - t) / len(base_cells)
    hex_med, hex_worst = relative_error(q_hex, exact["q_n"][: len(base_cells)])
    # The same association and metric on our hits: agreement of the numerics alone.
    q_same_hits = []
    for p in base_cells:
        scan = _core.simulate_scan(
            world.index, p, vlp16.directions, scan_params(vlp16.min_range, vlp16.max_range, threads=args.threads)
        )
        q_same_hits.append(
            association_and_metric(baseline.tree, world.index.points, scan["world_points"], p[:3, 3], args.threads)
        )
    same_med, same_worst = relative_error(q_same_hits, exact["q_n"][: len(base_cells)])
    print(f"\n1. exact VLP-16 cells, noise-free ({vlp16.num_rays} rays)")
    print(
        f"   baseline (Open3D + cKDTree + NumPy) on a {VOXEL_MESH * 100:g} cm voxel mesh ({len(triangles):,} "
        f"triangles, set-up {setup_s:.1f} s): {1 / base_s:.2f} cells/s, {100 * cast_share:.0f} % of it casting"
    )
    print(f"   ours: {1 / ours_s:.1f} cells/s   ratio {base_s / ours_s:.1f}x")
    print(f"   q_n baseline vs ours: median rel. diff {med:.4f}, 95th percentile {worst:.4f} (voxel squares vs discs)")
    print(
        f"   the same baseline on the disc-matched hexagon mesh ({4 * world.size:,} triangles): "
        f"{1 / hex_s:.2f} cells/s; q_n vs ours median {hex_med:.4f}, p95 {hex_worst:.4f}"
    )
    print(
        f"   q_n of the baseline's association + metric on our hits vs ours: median {same_med:.2e}, "
        f"p95 {same_worst:.2e}"
    )

    # 2. Thinned scans against exact, with range noise as in a SOLM build.
    noisy, noisy_s = ours(vlp16.directions, vlp16, vlp16.range_noise_sigma)
    print(
        f"\n2. thinned VLP-16 scans, noise {vlp16.range_noise_sigma} m "
        f"(exact: {1 / noisy_s:.1f} cells/s; gobi at 0.2 m is 660,000 cells)"
    )
    for stride in (2, 4, 8, 16, 32):
        directions, weight = thin_rays(vlp16.directions, stride)
        res, s = ours(directions, vlp16, vlp16.range_noise_sigma, weight)
        med, p95 = relative_error(res["q_n"], noisy["q_n"])
        print(
            f"   --ray-stride {stride:2d}: {len(directions):5d} rays, {1 / s:7.1f} cells/s "
            f"({noisy_s / s:4.1f}x), ratio to baseline {base_s / s:6.1f}x, "
            f"q_n rel. error median {med:.3f} p95 {p95:.3f}"
        )
    other_noise = _core.evaluate_many(
        world.index,
        poses,
        streams + len(poses),
        vlp16.directions,
        eval_params(
            vlp16.min_range, vlp16.max_range, noise=vlp16.range_noise_sigma, seed=args.seed, threads=args.threads
        ),
    )
    med, p95 = relative_error(other_noise["q_n"], noisy["q_n"])
    print(f"   noise floor (exact cells, other noise streams): median {med:.3f} p95 {p95:.3f}")

    # 3. SE(2) with a Mid-70: 36 yaw bins per cell.
    bins, few = 36, poses[: max(4, len(poses) // 6)]
    positions = np.ascontiguousarray(few[:, :3, 3])
    t = time.perf_counter()
    yaw_poses = np.concatenate(
        [
            pose_matrices(positions[:, 0], positions[:, 1], positions[:, 2], np.full(len(few), 2 * np.pi * k / bins))
            for k in range(bins)
        ]
    )
    _core.evaluate_many(
        world.index,
        yaw_poses,
        np.arange(len(yaw_poses), dtype=np.uint64),
        mid70.directions,
        eval_params(mid70.min_range, mid70.max_range, noise=mid70.range_noise_sigma, threads=args.threads),
    )
    se2_exact_s = (time.perf_counter() - t) / len(few)
    rays, half = sector_layout(mid70, bins)
    t = time.perf_counter()
    _core.evaluate_yaw_sectors(
        world.index,
        positions,
        np.arange(len(few), dtype=np.uint64),
        rays,
        bins,
        half,
        eval_params(mid70.min_range, mid70.max_range, noise=mid70.range_noise_sigma, threads=args.threads),
    )
    se2_reuse_s = (time.perf_counter() - t) / len(few)
    print(f"\n3. SE(2), Mid-70, {bins} yaw bins, per (x, y) cell")
    print(f"   exact per bin: {se2_exact_s * 1e3:.0f} ms ({se2_exact_s / noisy_s:.1f}x the R² VLP-16 cell)")
    print(
        f"   sector Grams (--yaw-reuse): {se2_reuse_s * 1e3:.0f} ms ({se2_reuse_s / noisy_s:.1f}x the R² VLP-16 cell)"
    )


if __name__ == "__main__":
    main()
