"""SOLM build throughput: the local engine against the Ray engine at 1 and 2 workers.

Builds one grid in the town of the Gobi scene (220 x 120 m; r2, VLP-16, 0.5 m) five ways: the local engine
on the whole map's index, the local engine on per-tile crops, and the Ray engine (one
task per tile, each indexing its crop) on a local cluster of 1 and of 2 CPUs. Prints
tiles per second, cells per second, the ratio to the local whole-map build at one
thread, the peak memory of the crops against the whole index, and checks that every
store is bitwise the local one.

    .venv/bin/python bench/bench_solm_cluster.py [--res 0.5] [--tile 16]
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

import lf3pm
from lf3pm.config import ScanConfig, SolmConfig
from lf3pm.solm import build_solm, make_grid
from lf3pm.solm.store import CHANNELS
from lf3pm.solm.tiles import crop_margin, make_job


def stores_equal(a: Path, b: Path) -> bool:
    import zarr

    ga, gb = zarr.open_group(str(a), mode="r"), zarr.open_group(str(b), mode="r")
    return all(ga[n][...].tobytes() == gb[n][...].tobytes() for n in CHANNELS + ("obstacle", "done"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", type=float, default=0.5)
    parser.add_argument("--tile", type=int, default=16)
    parser.add_argument("--size", type=float, default=16.0, help="Grid edge (m), centred on the town.")
    args = parser.parse_args()
    import ray

    world = lf3pm.load_map(lf3pm.build_scene("gobi").points)
    sensor = lf3pm.get_sensor("vlp16")
    cx, cy, h = 0.0, 0.0, args.size / 2
    grid = make_grid(world, "r2", args.res, bounds=(cx - h, cy - h, cx + h, cy + h))
    job = make_job(sensor, grid, ScanConfig(noise=0.0), solm=SolmConfig(tile=args.tile))
    crop = world.crop(job.bounds(0, 0), crop_margin(job, world))
    tiles = int(np.ceil(grid.ny / args.tile) * np.ceil(grid.nx / args.tile))
    print(
        f"map: {world.size:,} points, index {world.index.memory_bytes / 2**20:.0f} MiB; grid {grid.shape} "
        f"at {args.res} m, {tiles} tiles of {args.tile} x {args.tile} cells"
    )
    print(
        f"one tile's crop (margin {crop_margin(job, world):.1f} m): {crop.size:,} points, "
        f"index {crop.index.memory_bytes / 2**20:.0f} MiB"
    )
    runs = {}
    with tempfile.TemporaryDirectory() as tmp:

        def timed(name, **kwargs):
            out = Path(tmp) / f"{name}.zarr"
            t = time.perf_counter()
            build_solm(world, sensor, grid, out, noise=0.0, tile=args.tile, **kwargs)
            runs[name] = (time.perf_counter() - t, out)

        timed("local, whole map, 1 thread", threads=1)
        timed("local, whole map, 2 threads", threads=2)
        timed("local, tile crops, 1 thread", threads=1, crop=True)
        for workers in (1, 2):
            ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False, configure_logging=False)
            timed(f"ray, {workers} worker{'s' * (workers > 1)}", engine="ray")
            ray.shutdown()
        base_s, base_out = runs["local, whole map, 1 thread"]
        print("| engine | s | tiles/s | cells/s | speed-up vs local 1 thread | store bitwise local |")
        print("|---|---|---|---|---|---|")
        for name, (seconds, out) in runs.items():
            print(
                f"| {name} | {seconds:.1f} | {tiles / seconds:.2f} | {grid.nx * grid.ny / seconds:.0f} | "
                f"{base_s / seconds:.2f}x | {stores_equal(base_out, out)} |"
            )
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
