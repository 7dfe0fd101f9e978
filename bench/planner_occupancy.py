"""What the planner's ESDF on the SOLM's occupancy layer costs, against one on the coarse obstacle mask.

For every SOLM of a benefit study: the occupancy layer's grid, the time to build the
planner's ESDF on it (``Esdf.from_solm``: ~0.1 m cells, less the robot radius) and on the
SOLM's own obstacle and unknown masks (the field before the layer), best of three, and the
SOLM cells each leaves traversable at ``--r-safe``::

    .venv/bin/python bench/planner_occupancy.py --study out/b3
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--study", type=Path, default=Path("out/b3"))
    parser.add_argument("--r-safe", type=float, default=DEFAULTS.robot.r_safe)
    args = parser.parse_args()
    stores = sorted((args.study / "solm").glob("*.zarr"))
    if not stores:
        raise SystemExit(f"no SOLMs in {args.study / 'solm'}: run lf3pm experiment benefit -o {args.study} first")
    print(
        f"| map | SOLM cells | occupancy cells (k) | ESDF on occupancy (s) | on the obstacle mask (s) | ratio "
        f"| traversable at r_safe {args.r_safe:g}: occupancy / mask |"
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
            f"| {fine.traversable(args.r_safe).sum():,} / {coarse.traversable(args.r_safe).sum():,} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
