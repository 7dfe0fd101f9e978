"""Benchmark: the SOLM build's two approximations against exact cells on every map of the
casting suite (bench_maps.py): `--ray-stride K` (R², VLP-16) and `--yaw-reuse` (SE(2),
Mid-70, 36 yaw bins). Per map, in one run: the speed-up of each and the relative error of
q_n against exact cells (median, 95th percentile) and, for yaw reuse, the Spearman rank
correlation over positions x bins. Noise-free scans on both sides, so the error is the
approximation's alone.

    .venv/bin/python bench/bench_solm_approximations.py [--maps town,street] [--positions 8]
        [--markdown out/bench_solm_approximations.md]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from bench_maps import MAPS, ground_height
from common import chosen_maps
from scipy.spatial import cKDTree
from scipy.stats import spearmanr

import lf3pm
from lf3pm import _core
from lf3pm.metric import eval_params
from lf3pm.pose import pose_matrix
from lf3pm.solm.ray_thinning import thin_rays
from lf3pm.solm.yaw_reuse import sector_layout

HEIGHT = 1.0  # m above the ground
STRIDES = (2, 4, 16)
BINS = 36
CLEARANCE = 0.4  # m of free space around every position


def positions(points: np.ndarray, base: np.ndarray, count: int, seed: int = 0) -> np.ndarray:
    """`count` sensor positions (x, y, z) within 2 m of the map's positions, HEIGHT above the
    ground, each with CLEARANCE of free space."""
    rng = np.random.default_rng(seed)
    tree = cKDTree(points)
    out = []
    for attempt in range(50 * count):
        x, y = base[attempt % len(base)] + rng.uniform(-2.0, 2.0, 2)
        z = ground_height(points, (x, y)) + HEIGHT
        if tree.query([x, y, z])[0] >= CLEARANCE:
            out.append((x, y, z))
            if len(out) == count:
                break
    return np.ascontiguousarray(out)


def relative_error(approx: np.ndarray, exact: np.ndarray) -> tuple[float, float]:
    rel = np.abs(approx / exact - 1.0)
    return float(np.median(rel)), float(np.percentile(rel, 95))


def timed(fn):
    t = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t


def run_map(name: str, count: int, threads: int) -> dict:
    points, base = MAPS[name].build()
    world = lf3pm.load_map(points, threads=0)
    xyz = positions(world.points, base, count)
    row = {"map": name, "positions": len(xyz)}

    vlp16 = lf3pm.get_sensor("vlp16")
    poses = np.ascontiguousarray([pose_matrix((x, y, z, 0.0)) for x, y, z in xyz])
    streams = np.arange(len(poses), dtype=np.uint64)
    params = eval_params(vlp16.min_range, vlp16.max_range, threads=threads)
    exact, exact_s = timed(lambda: _core.evaluate_many(world.index, poses, streams, vlp16.directions, params))
    for k in STRIDES:
        rays, weight = thin_rays(vlp16.directions, k)
        thinned = eval_params(vlp16.min_range, vlp16.max_range, threads=threads, ray_weight=weight)
        approx, s = timed(lambda: _core.evaluate_many(world.index, poses, streams, rays, thinned))
        row[f"stride{k}"] = (*relative_error(approx["q_n"], exact["q_n"]), exact_s / s)

    mid70 = lf3pm.get_sensor("mid70")
    rays, half = sector_layout(mid70, BINS)
    params = eval_params(mid70.min_range, mid70.max_range, threads=threads)
    sectors, fast_s = timed(lambda: _core.evaluate_yaw_sectors(world.index, xyz, streams, rays, BINS, half, params))
    yaw_poses = np.ascontiguousarray(
        [pose_matrix((x, y, z, 2 * np.pi * b / BINS)) for x, y, z in xyz for b in range(BINS)]
    )
    exact, exact_s = timed(
        lambda: _core.evaluate_many(
            world.index, yaw_poses, np.arange(len(yaw_poses), dtype=np.uint64), mid70.directions, params
        )
    )
    fast = sectors["q_n"].ravel()
    row["yaw_reuse"] = (
        *relative_error(fast, exact["q_n"]),
        exact_s / fast_s,
        float(spearmanr(fast, exact["q_n"]).statistic),
    )
    row["se2_cell_s"] = exact_s / len(xyz) * threads  # one core's seconds for a cell's 36 exact scans
    row["se2_rays"] = BINS * mid70.num_rays
    return row


HEADER = (
    "| map | positions | stride 2: q_n error median / p95, speed-up | stride 4 | stride 16 | "
    "yaw reuse: q_n error median / p95, speed-up, Spearman | exact SE(2) cell, 1 core (36 x 10,000 rays) |\n"
    "|---|---|---|---|---|---|---|"
)


def format_row(r: dict) -> str:
    strides = " | ".join(
        f"{r[f'stride{k}'][0]:.1%} / {r[f'stride{k}'][1]:.1%}, {r[f'stride{k}'][2]:.1f}×" for k in STRIDES
    )
    y = r["yaw_reuse"]
    return (
        f"| {r['map']} | {r['positions']} | {strides} | {y[0]:.1%} / {y[1]:.1%}, {y[2]:.1f}×, {y[3]:.2f} | "
        f"{r['se2_cell_s'] * 1e3:.0f} ms ({r['se2_cell_s'] / r['se2_rays'] * 1e9:.0f} ns a ray) |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", default=",".join(MAPS), help=f"comma-separated, of {', '.join(MAPS)}")
    parser.add_argument("--positions", type=int, default=8)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--markdown", type=Path, help="also write the table here")
    args = parser.parse_args()
    maps = chosen_maps(parser, args.maps, MAPS)
    print(HEADER)
    rows = []
    for name in maps:
        rows.append(run_map(name, args.positions, args.threads))
        print(format_row(rows[-1]), flush=True)
    if args.markdown:
        args.markdown.parent.mkdir(parents=True, exist_ok=True)
        args.markdown.write_text("\n".join([HEADER, *map(format_row, rows)]) + "\n")


if __name__ == "__main__":
    main()
