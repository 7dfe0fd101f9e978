"""Why the LIO does worse along the Gobi experiment's guided plan (docs/gobi.md): one
change at a time, the default-guided plan's positions and timing with the unguided
plan's yaw profile, and the unguided plan with the default's yaw (each yaw taken at
the same fraction of the path), replayed by the LIO (Mid-70, GenZ-LIO) on 3 seeds.

    .venv/bin/python -m lf3pm experiment gobi -o out/gobi_full     # the plans
    .venv/bin/python bench/lio_yaw_swap.py [out/gobi_full]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import lf3pm
from lf3pm.experiments.gobi import FULL, map_case
from lf3pm.experiments.map_cases import load_case_map
from lf3pm.replays.motion import Motion
from lf3pm.trajectory.trajectory import read_csv

SEEDS = 3


def path_fraction(s: dict) -> np.ndarray:
    """Arc length along the trajectory, 0 at the start and 1 at the end."""
    length = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(s["x"]), np.diff(s["y"])))])
    return length / length[-1]


def with_yaw(world, positions: dict, headings: dict) -> Motion:
    """``positions``' path and timing with ``headings``' yaw at the same path fraction."""
    yaw = np.interp(path_fraction(positions), path_fraction(headings), np.unwrap(headings["yaw"]))
    return Motion.from_arrays(
        positions["t"],
        positions["x"],
        positions["y"],
        yaw,
        positions["vx"],
        positions["vy"],
        np.gradient(yaw, positions["t"]),
        map=world,
        height=1.0,
    )


def main() -> None:
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "out/gobi_full") / "trajectories"
    world, _ = load_case_map(map_case(FULL))
    plans = {name: read_csv(folder / f"{name}.csv") for name in ("none", "default")}
    cases = {
        "none": ("none", "none"),
        "default": ("default", "default"),
        "none positions, default yaw": ("none", "default"),
        "default positions, none yaw": ("default", "none"),
    }
    for label, (positions, headings) in cases.items():
        motion = with_yaw(world, plans[positions], plans[headings])
        errors = [lf3pm.replay(world, motion, "mid70", "lio", seed=seed).ape["rmse"] for seed in range(SEEDS)]
        print(f"{label:30s} LIO APE per seed {np.round(errors, 3)} median {np.median(errors):.3f} m", flush=True)


if __name__ == "__main__":
    main()
