"""Issue 43, item 2: what the guidance at the planned attitude (lf3pm.planner.flight_attitude)
does to the joint flights of the first flight study (results/flight_issue43/: its maps,
SOLMs and pairs). For 0, 1 and 2 rounds: the planning time, the flight time, and the
guidance cost the flight meets at the attitude it flies at (the level layer interpolated at
each sample, times the sample's cast ratio tilted / level to the guidance power, averaged
over samples at two per cell edge at the speed limit), which the rounds should lower.

    .venv/bin/python docs/investigations/flight_attitude_rounds.py --solm DIR/solm [--pairs 6]

DIR: the first flight study's run folder (lf3pm experiment flight --protocol
results/flight_issue43/protocol.yaml -o DIR), whose SOLM stores this reuses.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import lf3pm
from lf3pm.experiments.flight.protocol import load_protocol
from lf3pm.experiments.flight.study import pairs_of
from lf3pm.flight import Quadrotor
from lf3pm.planner.flight_attitude import sample_rate
from lf3pm.planner.flight_plan import FlightPlanner
from lf3pm.scenes import build_scene
from lf3pm.solm import Solm

RESULTS = Path(__file__).resolve().parents[2] / "results" / "flight_issue43"


def flown_cost(planner: FlightPlanner, trajectory) -> float:
    """Mean guidance cost over the flight's samples at the attitude flown."""
    quad = planner.quad
    s = trajectory.sample(sample_rate(planner.solm.grid_spec, quad.vmax))
    att = quad.attitudes(s["velocity"], s["acceleration"], s["jerk"], s["yaw"], s["yaw_rate"])
    ratio = planner.attitude_guidance().ratios(s["position"], att.rotation, s["yaw"])
    level, _ = planner.field.sample(np.ascontiguousarray(s["position"]), np.ascontiguousarray(s["yaw"]))
    cost = np.minimum(level * np.power(np.nan_to_num(ratio, nan=1.0), planner.guidance.power), planner.layer.cap)
    return float(np.mean(cost))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--solm", type=Path, required=True, help="the first study's SOLM folder")
    parser.add_argument("--pairs", type=int, default=6, help="pairs per map")
    args = parser.parse_args()
    protocol = load_protocol(RESULTS / "protocol.yaml")
    quad = Quadrotor(mount=protocol.mount)
    rows = []
    print("map         pair  rounds  plan_s  flight_s  flown_cost  change_vs_0")
    for case in protocol.maps:
        solm = Solm.open(args.solm / f"{case.scene}.zarr")
        planner = FlightPlanner(solm, lf3pm.load_map(build_scene(case.scene).points), quadrotor=quad)
        for k, (start, goal) in enumerate(pairs_of(case, protocol.pair_seed)[: args.pairs]):
            base = None
            for rounds in (0, 1, 2):
                began = time.perf_counter()
                plan = planner.plan(start, goal, attitude_rounds=rounds)
                seconds = time.perf_counter() - began
                cost = flown_cost(planner, plan.trajectory)
                base = cost if base is None else base
                rows.append({"map": case.scene, "pair": k, "rounds": rounds, "plan_s": seconds, "cost": cost})
                print(
                    f"{case.scene:11s} {k:4d} {rounds:7d} {seconds:7.2f} {plan.trajectory.duration:9.1f} "
                    f"{cost:11.4f} {cost / base - 1:+12.1%}"
                )
    for rounds in (1, 2):
        change = [
            r["cost"] / b["cost"] - 1
            for r in rows
            for b in rows
            if r["rounds"] == rounds and b["rounds"] == 0 and (r["map"], r["pair"]) == (b["map"], b["pair"])
        ]
        seconds = [r["plan_s"] for r in rows if r["rounds"] == rounds]
        print(
            f"{rounds} round(s): flown cost change median {np.median(change):+.1%} "
            f"(min {np.min(change):+.1%}, max {np.max(change):+.1%}), planning {np.median(seconds):.2f} s median"
        )
    print(json.dumps({"rows": rows}))


if __name__ == "__main__":
    main()
