"""Benchmark (issue 43, item 9): what an r3yaw SOLM of each flight study map costs to build,
per sensor on its mount (a VLP-16 pitched 20 degrees down, a Mid-360 on top, a VLP-16 on
its side), exact and with `--ray-stride 4` (the study's approximation), and that
approximation's error.

Per map (the flight study's grids: lf3pm.experiments.flight, its default protocol) and
sensor, in one run: the cells the build evaluates (free of the map by the SOLM's robot
radius; every yaw bin, or one cast a cell where the mount makes yaw a permutation of the
rays: `yaw_once`), the seconds a cell costs on the given threads, exact and thinned, on
`--positions` free cells drawn over the whole grid (every bin of each), the thinned build's
q_n error against exact (median, 95th percentile, Spearman over cells x bins; noise-free on
both sides, so the error is the approximation's alone; how many cells x bins are degenerate
on one side only, which the error leaves out), and the whole build's wall time
extrapolated: measured threads, 16 cores and 100 Ray workers (perfect scaling, plus 9 % for
the tiles' crops as docs/scale.md measured). `--full` also builds each map's study SOLM
(the protocol's sensor, mount and stride) through `lf3pm.build_solm` and prints its
measured time beside the extrapolation.

    .venv/bin/python bench/bench_flight_solm.py [--maps drift,forest] [--positions 24] [--full]
        [--markdown out/bench_flight_solm.md]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from common import chosen_maps
from scipy.stats import spearmanr

import lf3pm
from lf3pm import _core
from lf3pm.config import DEFAULTS
from lf3pm.experiments.flight import FlightProtocol
from lf3pm.experiments.flight.study import map_grid
from lf3pm.flight.mounts import MOUNTS
from lf3pm.scenes import build_scene
from lf3pm.solm import build_solm
from lf3pm.solm.tiles import make_job, pose_matrices
from lf3pm.terrain import body_blocked

#: (sensor, mount) as issue 43 names them.
SENSORS = (("vlp16", "down20"), ("mid360", "top"), ("vlp16", "side"))
STRIDE = 4
#: Overhead of building on crops across workers (docs/scale.md: 32-cell tiles).
CROP_OVERHEAD = 1.09


def free_cells(world, grid) -> np.ndarray:
    """(x, y, z) of the grid's cells free of the map by the SOLM's robot radius."""
    levels, _ = grid.layer_poses()
    zs = np.unique(levels)
    yy, xx = np.meshgrid(grid.ys(), grid.xs(), indexing="ij")
    cells = np.array([(x, y, z) for z in zs for x, y in zip(xx.ravel(), yy.ravel())])
    radius = DEFAULTS.solm.robot_radius
    blocked = body_blocked(world, cells[:, 0], cells[:, 1], cells[:, 2], cells[:, 2], radius)
    return cells[~blocked]


def timed_casts(world, grid, cells, sensor, mount, stride, threads):
    """(q_n per cell x bin, seconds a cell on ``threads``, yaw_once) for ``cells``."""
    scan = DEFAULTS.scan.model_copy(update={"noise": 0.0})
    layout = DEFAULTS.solm.model_copy(update={"ray_stride": stride})
    job = make_job(lf3pm.get_sensor(sensor), grid, scan, DEFAULTS.metric, layout, MOUNTS[mount].matrix())
    bins = 1 if job.yaw_once else grid.yaw_bins
    yaws = 2 * np.pi * np.arange(bins) / grid.yaw_bins
    x, y, z = (np.repeat(cells[:, k], bins) for k in range(3))
    poses = np.ascontiguousarray(pose_matrices(x, y, z, np.tile(yaws, len(cells))) @ np.asarray(job.mount))
    streams = np.arange(len(poses), dtype=np.uint64)
    began = time.perf_counter()
    res = _core.evaluate_many(world.index, poses, streams, job.rays, job.params(threads))
    seconds = time.perf_counter() - began
    q = res["q_n"].reshape(len(cells), bins)
    return (np.repeat(q, grid.yaw_bins // bins, axis=1) if job.yaw_once else q), seconds / len(cells), job.yaw_once


def hms(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


def run_map(case, protocol, positions: int, threads: int, full: bool) -> list[dict]:
    world = lf3pm.load_map(build_scene(case.scene).points, threads=threads)
    grid = map_grid(world, case, protocol.yaw_bins)
    free = free_cells(world, grid)
    rng = np.random.default_rng(0)
    sample = free[rng.choice(len(free), size=min(positions, len(free)), replace=False)]
    rows = []
    timed_casts(world, grid, sample[:2], *SENSORS[0], 1, threads)  # warm-up: the map's index paged in
    for sensor, mount in SENSORS:
        exact, exact_s, once = timed_casts(world, grid, sample, sensor, mount, 1, threads)
        thinned, thinned_s, _ = timed_casts(world, grid, sample, sensor, mount, STRIDE, threads)
        both = np.isfinite(exact) & np.isfinite(thinned) & (exact > 0)
        one_sided = int(np.sum(np.isfinite(exact) != np.isfinite(thinned)))  # degenerate on one side only
        rel = np.abs(thinned[both] / exact[both] - 1.0)
        row = {
            "map": case.scene,
            "sensor": f"{sensor} {mount}",
            "cells": len(free),
            "bins": grid.yaw_bins,
            "yaw_once": once,
            "exact_cell_s": exact_s,
            "thinned_cell_s": thinned_s,
            "error": (float(np.median(rel)), float(np.percentile(rel, 95))),
            "spearman": float(spearmanr(thinned[both], exact[both]).statistic),
            "one_sided": (one_sided, exact.size),
        }
        if full and (sensor, mount) == (protocol.sensor, protocol.mount):
            with tempfile.TemporaryDirectory() as folder:
                began = time.perf_counter()
                build_solm(
                    world, sensor, grid, Path(folder) / "s.zarr", mount=mount, ray_stride=STRIDE, threads=threads
                )
                row["measured_build_s"] = time.perf_counter() - began
        rows.append(row)
    return rows


def header(threads: int) -> str:
    return (
        f"| map | sensor, mount | free cells x bins | exact: a cell, {threads} threads / whole build on {threads}, "
        f"16 cores, 100 Ray workers | `--ray-stride 4`: a cell / whole build on {threads}, 16, 100 | q_n error of "
        "stride 4: median / p95, Spearman; cells x bins degenerate on one side only |\n|---|---|---|---|---|---|"
    )


def format_row(r: dict, threads: int) -> str:
    def build(cell_s):
        total = cell_s * r["cells"]  # seconds on `threads` threads
        cores = [total, total * threads / 16 * CROP_OVERHEAD, total * threads / 100 * CROP_OVERHEAD]
        return " / ".join(hms(s) for s in cores)

    measured = f" (measured: {hms(r['measured_build_s'])})" if "measured_build_s" in r else ""
    casts = "1 cast (yaw_once)" if r["yaw_once"] else f"{r['bins']} casts"
    return (
        f"| {r['map']} | {r['sensor']} | {r['cells']:,} x {r['bins']}, {casts} | {r['exact_cell_s'] * 1e3:.0f} ms: "
        f"{build(r['exact_cell_s'])} | {r['thinned_cell_s'] * 1e3:.0f} ms "
        f"({r['exact_cell_s'] / r['thinned_cell_s']:.1f}x faster): {build(r['thinned_cell_s'])}{measured} | "
        f"{r['error'][0]:.1%} / {r['error'][1]:.1%}, {r['spearman']:.3f}; {r['one_sided'][0]} of {r['one_sided'][1]} |"
    )


def main() -> None:
    protocol = FlightProtocol()
    names = [case.scene for case in protocol.maps]
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", default=",".join(names), help=f"comma-separated, of {', '.join(names)}")
    parser.add_argument("--positions", type=int, default=24, help="free cells timed per map and sensor")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--full", action="store_true", help="also build each map's study SOLM and time it")
    parser.add_argument("--markdown", type=Path, help="also write the table here")
    args = parser.parse_args()
    chosen = chosen_maps(parser, args.maps, names)
    print(header(args.threads))
    lines = []
    for case in protocol.maps:
        if case.scene in chosen:
            for row in run_map(case, protocol, args.positions, args.threads, args.full):
                lines.append(format_row(row, args.threads))
                print(lines[-1], flush=True)
    if args.markdown:
        args.markdown.parent.mkdir(parents=True, exist_ok=True)
        args.markdown.write_text("\n".join([header(args.threads), *lines]) + "\n")


if __name__ == "__main__":
    main()
