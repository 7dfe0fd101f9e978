"""Does a guided plan swing its sensor into space the odometry has not mapped yet?
(docs/lio.md, "Drift along the view's weakest direction")

For plans of one benefit-study pair, the noise-free scans the LIO replay feeds its
odometry, taken in order: per second, the share of a scan's returns that fall in
0.5 m voxels some earlier scan of the same plan already hit (what an odometry's own
map can hold there at best), over all returns and over the returns more than 0.3 m
above the sensor's ground level (sensor height minus 1 m: walls, vegetation, stones,
the structure that pins x, y and yaw), and how many returns that is. It needs the
study's trajectories (``lf3pm experiment benefit -o DIR``)::

    .venv/bin/python bench/lio_unseen_view.py --study out/b2                       # gobi pair 0
    .venv/bin/python bench/lio_unseen_view.py --study out/tune20 --pair 03_diff --guidance m1w1
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from study_inputs import study_arguments, study_case, study_plan

import lf3pm
from lf3pm.config import DEFAULT_HEIGHT
from lf3pm.experiments.map_cases import load_case_map
from lf3pm.replays.motion import Motion
from lf3pm.scan.scans import ScanStream

VOXEL = 0.5  # m, an odometry map's cell
ABOVE_GROUND = 0.3  # m, a return counted as structure


def seen_shares(world, csv: Path, sensor) -> list[tuple]:
    """(t, share seen, structure returns, their share seen) once per second."""
    stream = ScanStream(world, Motion.from_csv(csv, world), sensor, noise=0.0)
    every = int(round(stream.rate))
    seen: set = set()
    rows = []
    for k in range(len(stream)):
        points = stream[k].world_points
        keys = [tuple(v) for v in np.floor(points / VOXEL).astype(np.int64)]
        if k % every == 0 and seen:
            hit = np.array([key in seen for key in keys])
            tall = points[:, 2] > stream.truth[k][2, 3] - DEFAULT_HEIGHT + ABOVE_GROUND
            rows.append((stream.times[k], hit.mean(), int(tall.sum()), hit[tall].mean() if tall.any() else np.nan))
        seen.update(keys)
    return rows


def main() -> None:
    args = study_arguments(__doc__.split("\n\n")[0]).parse_args()
    case = study_case(args.map)
    world, _ = load_case_map(case)
    sensor = lf3pm.get_sensor(case.sensor)
    for guidance in (args.guidance, "none"):
        rows = seen_shares(world, study_plan(args.study, args.map, f"{args.pair}_{guidance}"), sensor)
        print(f"\n{args.map} {args.pair} {guidance}: returns in voxels of earlier scans (noise-free)\n")
        print("| t (s) | share seen | structure returns | their share seen |")
        print("|---|---|---|---|")
        for t, share, tall, tall_share in rows:
            print(f"| {t:.0f} | {share:.2f} | {tall} | {tall_share:.2f} |")
        shares = np.array([r[1] for r in rows])
        print(
            f"\nlowest share seen {shares.min():.2f} (t = {rows[int(shares.argmin())][0]:.0f} s), "
            f"median {np.median(shares):.2f}"
        )


if __name__ == "__main__":
    main()
