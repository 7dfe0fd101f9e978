"""Benchmark: the floor of an exact site build. On random free cells of the gobi scene
(VLP-16 at 1 m, noise-free, one thread, in one run): Embree (embreex) only casting each
cell's rays on the surfel mesh of bench_evaluate.py, against lf3pm's cast and its exact
cell (cast, association, metric); and the whole gobi R² SOLM at 0.2 m (660,000 cells)
that each rate implies on N cores, at perfect scaling; each row's ratio to Embree's
casting (the baseline).

    .venv/bin/python bench/bench_site_floor.py [--cells 24] [--cores 2]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from bench_evaluate import embree_scene

import lf3pm
from lf3pm import _core
from lf3pm.config import MetricConfig, ScanConfig, scan_params
from lf3pm.experiments.free_poses import random_free_poses
from lf3pm.pose import pose_matrix
from lf3pm.scenes import build_scene

GOBI_CELLS = 669_521  # the gobi scene's R² grid at 0.2 m (docs/solm.md)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=24)
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    world = lf3pm.load_map(build_scene("gobi", seed=args.seed).points, threads=0)
    sensor = lf3pm.get_sensor("vlp16")
    lo, hi = world.bounds
    cells = random_free_poses(
        world, args.cells, np.random.default_rng(args.seed), sensor_height=1.0, region=(lo[0], lo[1], hi[0], hi[1])
    )
    poses = [pose_matrix((x, y, z, 0.0)) for x, y, z in np.asarray(cells)[:, :3]]
    scene = embree_scene(world)
    if scene is None:
        raise SystemExit("needs embreex: pip install embreex")
    cast_params = scan_params(sensor.min_range, sensor.max_range, threads=1)
    eval_params = MetricConfig().core(ScanConfig(noise=0.0, threads=1).core(sensor))
    times = {"embree": 0.0, "cast": 0.0, "cell": 0.0}
    for pose in poses:
        dirs = (sensor.directions @ pose[:3, :3].T).astype(np.float32)
        origins = np.repeat(pose[None, :3, 3], len(dirs), axis=0).astype(np.float32)
        scene.run(origins, dirs, output=1)  # the BVH is built outside the timing
        for name, run in (
            ("embree", lambda: scene.run(origins, dirs, output=1)),
            ("cast", lambda: _core.simulate_scan(world.index, pose, sensor.directions, cast_params)),
            ("cell", lambda: _core.evaluate(world.index, pose, sensor.directions, eval_params)),
        ):
            best = np.inf
            for _ in range(3):
                t = time.perf_counter()
                run()
                best = min(best, time.perf_counter() - t)
            times[name] += best / len(poses)
    print(f"gobi: {world.size:,} points, {len(poses)} random free cells, VLP-16 ({sensor.num_rays:,} rays), one thread")
    print(f"| per cell, one core | ms | / Embree | whole gobi R² 0.2 m on {args.cores} cores |\n|---|---|---|---|")
    for label, key in (
        ("Embree casting alone (the floor)", "embree"),
        ("lf3pm casting alone", "cast"),
        ("lf3pm exact cell (cast, association, metric)", "cell"),
    ):
        minutes = GOBI_CELLS * times[key] / args.cores / 60
        print(f"| {label} | {times[key] * 1e3:.1f} | {times[key] / times['embree']:.2f}x | {minutes:.0f} min |")


if __name__ == "__main__":
    main()
