"""Benchmark: SE(2) SOLM cells by sector Grams (`--yaw-reuse`) against exact
per-yaw evaluation, Livox Mid-70, 36 yaw bins, on the houses and meadow scenes.
Prints the time ratio and the error of q_min, q_n, q_max (median and 95th
percentile of the relative error, Spearman rank correlation).

    .venv/bin/python bench/bench_solm_yaw_reuse.py [--positions 6]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.stats import spearmanr

import lf3pm
from lf3pm import _core
from lf3pm.metric import eval_params
from lf3pm.pose import pose_matrix
from lf3pm.scenes import build_scene
from lf3pm.solm.yaw_reuse import sector_layout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--positions", type=int, default=6)
    parser.add_argument("--bins", type=int, default=36)
    args = parser.parse_args()
    sensor = lf3pm.get_sensor("mid70")
    rays, half = sector_layout(sensor, args.bins)
    for name in ("houses", "meadow"):
        scene = build_scene(name)
        world = lf3pm.load_map(scene.points)
        rng = np.random.default_rng(0)
        xy = rng.uniform(-1.5, 1.5, size=(args.positions, 2))
        positions = np.ascontiguousarray(np.c_[xy, np.full(len(xy), scene.reference_pose[2])])
        streams = np.arange(len(positions), dtype=np.uint64)
        t = time.perf_counter()
        fast = _core.evaluate_yaw_sectors(
            world.index,
            positions,
            streams,
            rays,
            args.bins,
            half,
            eval_params(sensor.min_range, sensor.max_range, noise=0.02, threads=2),
        )
        fast_s = time.perf_counter() - t
        poses = np.ascontiguousarray(
            np.array(
                [pose_matrix((x, y, z, 2 * np.pi * k / args.bins)) for x, y, z in positions for k in range(args.bins)]
            )
        )
        t = time.perf_counter()
        exact = _core.evaluate_many(
            world.index,
            poses,
            np.arange(len(poses), dtype=np.uint64),
            sensor.directions,
            eval_params(sensor.min_range, sensor.max_range, noise=0.02, threads=2),
        )
        exact_s = time.perf_counter() - t
        print(
            f"{name}: {len(poses)} cells x bins; exact {exact_s:.2f} s, sector Grams {fast_s:.2f} s, "
            f"ratio {exact_s / fast_s:.1f}x ({len(rays)} rays per sector, {2 * half + 1} sectors per bin)"
        )
        for q in ("q_min", "q_n", "q_max"):
            rel = np.abs(fast[q].ravel() / exact[q] - 1)
            rho = spearmanr(fast[q].ravel(), exact[q]).statistic
            print(
                f"  {q}: relative error median {np.median(rel):.3f}, p95 {np.percentile(rel, 95):.3f}; "
                f"Spearman {rho:.3f}"
            )


if __name__ == "__main__":
    main()
