"""How close do a benefit study's plans pass to the map's points, in the robot body's height band?

The planner keeps the body (radius ``--robot-radius``) plus ``r_safe`` off the SOLM's
occupancy layer (docs/solm.md, "Occupancy layer"); before that layer its ESDF came from the
coarse obstacle mask, which probes the body at cell centres only and missed thin obstacles
between them (on the gobi's 1 m cells, plans passed 1-5 cm from bushes). This bench checks
a study's plans against the map itself: for every plan CSV, sampled at 10 Hz, the smallest
horizontal distance from the sensor's axis to a map point between 0.8 m below the sensor
(the floor clearance for the default 1 m height) and the sensor, and lists the plans that
come closer than ``--radius``::

    .venv/bin/python bench/plan_clearance.py --study out/b2
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree
from study_inputs import study_case

from lf3pm.config import DEFAULT_HEIGHT, DEFAULTS
from lf3pm.experiments.map_cases import load_case_map
from lf3pm.replays.motion import Motion


def clearance(motion: Motion, points: np.ndarray, tree: cKDTree, search: float) -> float:
    """Smallest horizontal distance (m) from the sensor's axis, every 0.1 s, to a point of the
    body's height band; inf when none lies within ``search``."""
    band = DEFAULT_HEIGHT - DEFAULTS.solm.floor_clearance
    best = np.inf
    for c in motion.pose(np.arange(motion.t0, motion.t1, 0.1))[:, :3, 3]:
        near = points[tree.query_ball_point(c[:2], search)]
        near = near[(near[:, 2] > c[2] - band) & (near[:, 2] <= c[2])]
        if len(near):
            best = min(best, float(np.min(np.hypot(near[:, 0] - c[0], near[:, 1] - c[1]))))
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--study", type=Path, default=Path("out/benefit3"))
    parser.add_argument("--radius", type=float, default=DEFAULTS.solm.robot_radius)
    args = parser.parse_args()
    folder = args.study / "trajectories"
    if not folder.is_dir():
        raise SystemExit(f"no {folder}: run lf3pm experiment benefit -o {args.study} first")
    print(f"| map | plans | closer than {args.radius:g} m | closest (m) | plans |")
    print("|---|---|---|---|---|")
    for map_dir in sorted(p for p in folder.iterdir() if p.is_dir()):
        world, _ = load_case_map(study_case(map_dir.name))
        tree = cKDTree(world.points[:, :2])
        found = {
            csv.stem: clearance(Motion.from_csv(csv, world), world.points, tree, 2 * args.radius)
            for csv in sorted(map_dir.glob("*.csv"))
        }
        close = sorted((d, name) for name, d in found.items() if d < args.radius)
        print(
            f"| {map_dir.name} | {len(found)} | {len(close)} | {min(found.values()):.2f} | "
            f"{', '.join(f'{n} {d:.2f}' for d, n in close[:8])}{' ...' if len(close) > 8 else ''} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
