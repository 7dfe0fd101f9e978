"""Benchmark: the planner's ESDF on the SOLM's occupancy layer against one on the coarse obstacle mask.

For each SOLM: the occupancy layer's grid, the time to build the planner's ESDF on it
(``Esdf.from_solm``: ~0.1 m cells, less the robot radius; ours) and on the SOLM's own
obstacle and unknown masks (the baseline: the field before the layer), best of three,
their ratio, and the SOLM cells each leaves traversable at ``--r-safe``. Without
``--solm`` it builds the `boxes` scene's SOLM in a temporary folder (about a minute);
BENCHMARK.md's figures are the benefit study's nine SOLMs::

    .venv/bin/python bench/bench_planner_occupancy.py
    .venv/bin/python bench/bench_planner_occupancy.py --solm STUDY/solm/*.zarr
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from common import build_boxes_solm

from lf3pm.config import DEFAULTS
from lf3pm.planner.esdf import Esdf, solm_masks
from lf3pm.solm import Solm


def best_time(build) -> tuple[float, object]:
    """Best of three wall times (s) of ``build()`` and its result."""
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        out = build()
        times.append(time.perf_counter() - t0)
    return min(times), out


def coarse_esdf(solm: Solm) -> Esdf:
    """The field on the SOLM's own masks (a cell blocked when any yaw bin is)."""
    g = solm.grid_spec
    obstacle, unknown = solm_masks(solm)
    return Esdf.from_mask(obstacle, g.x0, g.y0, g.res, unknown=unknown)


def report(stores: list[Path], r_safe: float) -> None:
    print(
        f"| map | SOLM cells | occupancy cells (k) | ESDF on occupancy (s) | on the obstacle mask (s, baseline) "
        f"| ratio | traversable at r_safe {r_safe:g}: occupancy / mask |"
    )
    print("|---|---|---|---|---|---|---|")
    for path in stores:
        solm = Solm.open(path)
        g = solm.grid_spec
        occupied, k = solm.occupancy()
        fine_s, fine = best_time(lambda: Esdf.from_solm(solm))
        coarse_s, coarse = best_time(lambda: coarse_esdf(solm))
        print(
            f"| {path.stem} | {g.nx} x {g.ny} of {g.res:g} m | {occupied.shape[1]} x {occupied.shape[0]} ({k}) "
            f"| {fine_s:.2f} | {coarse_s:.3f} | {fine_s / coarse_s:.0f}x "
            f"| {fine.traversable(r_safe).sum():,} / {coarse.traversable(r_safe).sum():,} |",
            flush=True,
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--solm", type=Path, nargs="+", help="SOLM stores (default: build the boxes scene's)")
    parser.add_argument("--r-safe", type=float, default=DEFAULTS.robot.r_safe)
    args = parser.parse_args()
    if args.solm:
        report(sorted(args.solm), args.r_safe)
        return
    with tempfile.TemporaryDirectory() as folder:
        report([build_boxes_solm(Path(folder))], args.r_safe)


if __name__ == "__main__":
    main()
