"""Does pricing the sensor's turns keep the LIO's error along guided omni plans?

In the benefit study's tuning run the default-guided omni plans in the gobi swing the
Mid-70 by 90 degrees and more at 0.5-1 rad/s to face the town, and the LIO's error
jumps by 10-25 cm during the swing (localization gains a few mm). The front end prices
a turn as the arc a point ``turn_radius`` metres from the axis travels (0.5 m: a 90
degree swing costs 0.8 m of path). This replans every omni pair of the SE(2) maps of a
finished study (its pairs, SOLMs and unguided replays) with the default guidance at
several turn radii, one change only, and replays each plan by the LIO and by map
localization (seed 0, as the study's first seed).

    .venv/bin/lf3pm experiment benefit -o out/tune_lio --pair-seed 1 --seeds 1 --lio all \\
        --guidance n1w1=q_n:1:1 --guidance n1w3=q_n:1:3      # the study (pairs, SOLMs)
    .venv/bin/python bench/lio_turn_cost.py out/tune_lio out/turn_cost 2     # 2 seeds
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from lf3pm.config import DEFAULTS
from lf3pm.experiments.benefit import CASES
from lf3pm.experiments.replay_tasks import load_replay, replay_json, run_replays, write_plan

METHODS = ("lio", "localization")
#: One change at a time from the default guided plan: the front end's turn price
#: (turn_radius, m) and the yaw rate the plan may use (wmax, rad/s; the robot's is 1).
VARIANTS = {
    "none": {"metric": "none"},
    "default": {},
    "turn 2 m": {"turn_radius": 2.0},
    "turn 5 m": {"turn_radius": 5.0},
    "wmax 0.3": {"wmax": 0.3},
    "wmax 0.5": {"wmax": 0.5},
}


def yaw_swept(csv: Path) -> float:
    """Total turn of the sensor along a plan CSV (degrees)."""
    yaw = np.loadtxt(csv, delimiter=",", skiprows=1)[:, 3]
    return float(np.degrees(np.sum(np.abs(np.diff(np.unwrap(yaw))))))


def plan_variant(planner, pair: dict, variant: dict):
    from lf3pm.trajectory.robots import Robot

    g, v = DEFAULTS.guidance, dict(variant)
    robot = Robot("omni", wmax=v.pop("wmax", DEFAULTS.robot.wmax))
    return planner.plan(
        pair["start"], pair["goal"], robot=robot, metric=v.pop("metric", g.metric), weight=g.weight, power=g.power, **v
    )


def main() -> None:
    from lf3pm.planner.plan import Planner
    from lf3pm.solm import Solm

    study, out, seeds = Path(sys.argv[1]), Path(sys.argv[2]), int(sys.argv[3]) if len(sys.argv) > 3 else 2
    summary = json.loads((study / "summary.json").read_text())
    cases = {c.name: c for c in CASES if c.space == "se2"}
    pairs = [p for p in summary["pairs"] if p["case"] in cases and p["robot"] == "omni"]
    tasks, rows = [], []
    for name in cases:
        mine = [p for p in pairs if p["case"] == name]
        planner = Planner(Solm.open(study / "solm" / f"{name}.zarr"))
        for p in mine:
            for label, variant in VARIANTS.items():
                plan = plan_variant(planner, p, variant)
                tag = f"{p['pair']:02d}_{label.replace(' ', '')}_"
                csv = out / "trajectories" / name / f"{tag[:-1]}.csv"
                write_plan(plan.trajectory, csv, out / "replays" / name, tag)
                rows.append((p, label, csv, plan.summary()["trajectory_length_m"]))
                tasks += [
                    (cases[name], str(csv), method, seed, replay_json(out / "replays" / name, tag, method, seed))
                    for method in METHODS
                    for seed in range(seeds)
                ]
        print(f"{name}: {len(mine)} omni pairs planned", flush=True)
    run_replays(tasks, 2, lambda *a, **k: None)

    def ape(p, label, method):
        tag = f"{p['pair']:02d}_{label.replace(' ', '')}_"
        return float(
            np.median(
                [
                    load_replay(replay_json(out / "replays" / p["case"], tag, method, s))["ape_rmse"]
                    for s in range(seeds)
                ]
            )
        )

    print(f"\nMedian over {seeds} seeds; ratios to the unguided plan of the same pair.\n")
    print(
        "| map | pair | plan | swept (deg) | max yaw rate (rad/s) | length (m) | LIO APE (m) | LIO ratio | "
        "localization APE (mm) | localization ratio |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    ratios = {label: {m: [] for m in METHODS} for label in VARIANTS}
    for p, label, csv, length in rows:
        got = {m: ape(p, label, m) for m in METHODS}
        for m in METHODS:
            ratios[label][m].append(got[m] / ape(p, "none", m))
        rate = np.max(np.abs(np.loadtxt(csv, delimiter=",", skiprows=1)[:, 6]))
        print(
            f"| {p['case']} | {p['pair']} | {label} | {yaw_swept(csv):.0f} | {rate:.2f} | {length:.1f} | "
            f"{got['lio']:.3f} | {ratios[label]['lio'][-1]:.2f} | {1000 * got['localization']:.1f} | "
            f"{ratios[label]['localization'][-1]:.2f} |"
        )
    print("\n| plan | pairs | LIO ratio: median, worst | localization ratio: median, worst |")
    print("|---|---|---|---|")
    for label in VARIANTS:
        r = ratios[label]
        print(
            f"| {label} | {len(r['lio'])} | {np.median(r['lio']):.2f}, {np.max(r['lio']):.2f} | "
            f"{np.median(r['localization']):.2f}, {np.max(r['localization']):.2f} |"
        )


if __name__ == "__main__":
    main()
