"""One benefit-study pair planned again under other guidance, replayed by the LIO and by
map localization (docs/benefit.md, "Channel, with the LIO: q_max").

Plans the pair's start and goal on the study's own SOLM with each ``--guidance``
(NAME=CHANNEL:POWER:WEIGHT, as ``lf3pm experiment benefit`` takes it) and prints the
APE of each replay seed. It needs the study (``lf3pm experiment benefit -o out/benefit3``)::

    .venv/bin/python bench/lio_replan_channels.py      # gobi pair 0: q_n w3 against q_max w1, w3
    .venv/bin/python bench/lio_replan_channels.py --map corridor --pair 2 --guidance x=q_max:1:3
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from study_inputs import study_case

import lf3pm
from lf3pm.experiments.guidance import parse_guidance
from lf3pm.experiments.map_cases import load_case_map


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--study", type=Path, default=Path("out/benefit3"))
    parser.add_argument("--map", default="gobi")
    parser.add_argument("--pair", type=int, default=0)
    parser.add_argument(
        "--guidance", action="append", help="NAME=CHANNEL:POWER:WEIGHT (default: q_n:1:3, q_max:1:1, q_max:1:3)"
    )
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--out", type=Path, default=Path("out/lio_replan_channels"))
    args = parser.parse_args()
    from lf3pm.planner.plan import Planner
    from lf3pm.solm import Solm
    from lf3pm.trajectory.robots import Robot

    case = study_case(args.map)
    summary = args.study / "summary.json"
    if not summary.is_file():
        raise SystemExit(f"no {summary}: run lf3pm experiment benefit -o {args.study} first")
    pair = next(
        (p for p in json.loads(summary.read_text())["pairs"] if p["case"] == args.map and p["pair"] == args.pair), None
    )
    if pair is None:
        raise SystemExit(f"{args.study} has no pair {args.pair} on {args.map}")
    guidance = [parse_guidance(g) for g in args.guidance or ("q_n=q_n:1:3", "q_max_w1=q_max:1:1", "q_max_w3=q_max:1:3")]
    world, _ = load_case_map(case)
    planner = Planner(Solm.open(args.study / "solm" / f"{args.map}.zarr"))
    print(f"{args.map} pair {args.pair} ({pair['robot']}), APE RMSE per seed 0..{args.seeds - 1}\n")
    print("| guidance | length (m) | LIO (m) | localization (mm) |")
    print("|---|---|---|---|")
    for g in guidance:
        plan = planner.plan(
            pair["start"], pair["goal"], robot=Robot(pair["robot"]), metric=g.channel, weight=g.weight, power=g.power
        )
        csv = args.out / args.map / f"{args.pair:02d}_{g.name}.csv"
        csv.parent.mkdir(parents=True, exist_ok=True)
        plan.trajectory.to_csv(csv)
        runs = {
            method: [
                lf3pm.replay(world, csv, case.sensor, method, seed, threads=1).ape["rmse"] for seed in range(args.seeds)
            ]
            for method in ("lio", "localization")
        }
        print(
            f"| {g.name} ({g.channel}, power {g.power:g}, weight {g.weight:g}) | "
            f"{plan.summary()['trajectory_length_m']:.1f} | {', '.join(f'{a:.3f}' for a in runs['lio'])} | "
            f"{', '.join(f'{1000 * a:.1f}' for a in runs['localization'])} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
