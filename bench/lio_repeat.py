"""Is an odometry reproducible run to run? The same replay (same plan, seed and stream)
run several times; prints each run's APE and how far its poses are from the first run's
(docs/lio.md, "Known limits"). It needs the study's plans
(``lf3pm experiment benefit -o out/benefit3``)::

    .venv/bin/python bench/lio_repeat.py                                   # DLIO: houses, tunnel
    .venv/bin/python bench/lio_repeat.py --odometry genz --plan gobi/00_omni_default
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from study_inputs import study_case, study_plan

import lf3pm
from lf3pm.experiments.map_cases import load_case_map


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--study", type=Path, default=Path("out/benefit3"))
    parser.add_argument(
        "--plan",
        action="append",
        help="MAP/PLAN of the study's trajectories (default: houses/00_omni_default and tunnel/00_omni_default)",
    )
    parser.add_argument("--odometry", default="dlio")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(f"{args.odometry}, seed {args.seed}, {args.runs} runs of each stream\n")
    print("| plan | sensor | APE per run (mm) | largest position difference from run 1 (mm) |")
    print("|---|---|---|---|")
    for name in args.plan or ("houses/00_omni_default", "tunnel/00_omni_default"):
        map_name, _, plan = name.partition("/")
        case, csv = study_case(map_name), study_plan(args.study, map_name, plan)
        world, _ = load_case_map(case)
        runs = [
            lf3pm.replay(world, csv, case.sensor, "lio", args.seed, threads=1, odometry=args.odometry)
            for _ in range(args.runs)
        ]
        apes = ", ".join(f"{1000 * r.ape['rmse']:.3f}" for r in runs)
        apart = ", ".join(
            f"{1000 * np.abs(r.estimate[:, :3, 3] - runs[0].estimate[:, :3, 3]).max():.2f}" for r in runs[1:]
        )
        print(f"| {name} | {case.sensor} | {apes} | {apart} |", flush=True)


if __name__ == "__main__":
    main()
