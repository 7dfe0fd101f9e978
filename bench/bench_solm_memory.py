"""Peak memory of a SOLM build: the whole map indexed against tile by tile on crops.

Synthetic sites of 10, 30 and 60 M points (a 1 km x 1 km rolling ground with 400
buildings; the point spacing sets the count) written as .npy; for each, `lf3pm solm
build` of one 32 x 32-cell tile (0.5 m, VLP-16) in the site's centre, run under
/usr/bin/time -v, once indexing the whole map and once on crops (`--crop`). Prints the
peak resident memory, the wall time and the map's own size in memory (24 bytes a point),
and the ratio of the crops' peak to the whole index's (the baseline) where both ran.

    .venv/bin/python bench/bench_solm_memory.py [--millions 10 30 60] [--skip-whole-above 30]
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SITE = 1000.0  # m, edge of the square site


def site_points(millions: float, seed: int = 0) -> np.ndarray:
    """About ``millions`` M points: ground (80 %) and building walls (20 %) of a 1 km site."""
    rng = np.random.default_rng(seed)
    n = int(millions * 1e6)
    ground_n, walls_n = int(0.8 * n), n - int(0.8 * n)
    xy = rng.uniform(-SITE / 2, SITE / 2, size=(ground_n, 2))
    z = 1.5 * np.sin(xy[:, 0] / 60.0) * np.cos(xy[:, 1] / 45.0) + rng.normal(scale=0.01, size=ground_n)
    centres = rng.uniform(-SITE / 2 + 20, SITE / 2 - 20, size=(400, 2))
    sizes = rng.uniform(8, 25, size=(400, 2))
    b = rng.integers(0, 400, walls_n)
    side = rng.integers(0, 4, walls_n)
    t = rng.uniform(-0.5, 0.5, walls_n)
    half = sizes[b] / 2
    along = np.where(side < 2, t * sizes[b, 0], t * sizes[b, 1])
    wx = np.where(side < 2, along, np.where(side == 2, -half[:, 0], half[:, 0]))
    wy = np.where(side < 2, np.where(side == 0, -half[:, 1], half[:, 1]), along)
    walls = np.c_[centres[b, 0] + wx, centres[b, 1] + wy, rng.uniform(0, 8, walls_n)]
    return np.ascontiguousarray(np.vstack([np.c_[xy, z], walls]))


def run(map_path: Path, out: Path, extra: list[str]) -> tuple[float, float]:
    """(peak RSS in GiB, wall seconds) of one build of the central tile."""
    h = 8.0  # 16 m: one 32-cell tile at 0.5 m
    cmd = [
        "/usr/bin/time",
        "-v",
        sys.executable,
        "-m",
        "lf3pm.cli",
        "solm",
        "build",
        str(map_path),
        "-o",
        str(out),
        "--res",
        "0.5",
        "--bounds",
        str(-h),
        str(-h),
        str(h),
        str(h),
        "--noise",
        "0",
        *extra,
    ]
    start = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(done.stderr[-2000:])
    kib = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr).group(1))
    return kib / 2**20, wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--millions", type=float, nargs="+", default=[10, 30, 60])
    parser.add_argument(
        "--skip-whole-above", type=float, default=30.0, help="Do not index maps of more million points whole."
    )
    args = parser.parse_args()
    print("| map points | map array GiB | whole index: peak GiB | s | crops: peak GiB | s | peak crops / whole |")
    print("|---|---|---|---|---|---|---|")
    for millions in args.millions:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "site.npy"
            points = site_points(millions)
            np.save(path, points)
            size = points.nbytes / 2**30
            del points
            whole, whole_rss = ("-", "-"), None
            if millions <= args.skip_whole_above:
                rss, wall = run(path, Path(tmp) / "whole.zarr", ["--crop-above", str(10**9)])
                whole, whole_rss = (f"{rss:.2f}", f"{wall:.0f}"), rss
            rss, wall = run(path, Path(tmp) / "crops.zarr", ["--crop"])
            ratio = "-" if whole_rss is None else f"{rss / whole_rss:.2f}x"
            print(
                f"| {millions:g} M | {size:.2f} | {whole[0]} | {whole[1]} | {rss:.2f} | {wall:.0f} | {ratio} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
