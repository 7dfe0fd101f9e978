"""Where along a plan the LIO's error grows, and in which direction, against what the
metric says of each view (docs/lio.md, "Drift along the view's weakest direction").

For the guided and the unguided plan of one benefit-study pair, one replay seed: per
second of the plan, the LIO's error vector (estimate - truth, world frame), the
sensor's yaw, q_n and q_max, and the weakest eigenvalue of the view's information
matrix A^T A (x, y, z, roll, pitch, yaw; translation first, world frame) with the
horizontal direction of its eigenvector. It needs the study's trajectories
(``lf3pm experiment benefit -o out/benefit3``)::

    .venv/bin/python bench/lio_weak_direction.py                     # gobi pair 0, omni, seed 2
    .venv/bin/python bench/lio_weak_direction.py --map corridor --pair 03_omni --seed 0
    .venv/bin/python bench/lio_weak_direction.py --odometry dlio --seed 0   # the same streams, DLIO
"""

from __future__ import annotations

import math

import numpy as np
from study_inputs import study_arguments, study_case, study_plan

import lf3pm
from lf3pm.errors import PoseError
from lf3pm.experiments.map_cases import load_case_map


def main() -> None:
    parser = study_arguments(__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=2)
    parser.add_argument("--odometry", default="auto", help="genz, dlio or auto (lf3pm replay's --odometry)")
    args = parser.parse_args()
    case = study_case(args.map)
    world, _ = load_case_map(case)
    for guidance in (args.guidance, "none"):
        csv = study_plan(args.study, args.map, f"{args.pair}_{guidance}")
        result = lf3pm.replay(world, csv, case.sensor, "lio", args.seed, threads=1, odometry=args.odometry)
        error = result.estimate[:, :3, 3] - result.truth[:, :3, 3]
        print(
            f"\n{args.map} {args.pair} {guidance}, seed {args.seed}, odometry {args.odometry}: "
            f"LIO APE {result.ape['rmse']:.3f} m\n"
        )
        print(
            "| t (s) | error x, y, z (m) | sensor yaw (deg) | q_n | q_max | weakest eigenvalue | its direction (deg) |"
        )
        print("|---|---|---|---|---|---|---|")
        every = max(1, int(round(result.params["rate"])))
        for k in range(0, len(result.times), every):
            pose = result.truth[k]
            row = (
                f"| {result.times[k]:.0f} | {error[k, 0]:+.3f}, {error[k, 1]:+.3f}, {error[k, 2]:+.3f} | "
                f"{math.degrees(math.atan2(pose[1, 0], pose[0, 0])):.0f} |"
            )
            try:
                view = lf3pm.evaluate(world, pose, case.sensor, observations=True)
            except PoseError:  # the sensor within clearance of a map point (a bush beside the route)
                print(f"{row} too close to the map | | | |", flush=True)
                continue
            a = np.asarray(view.observations["A"])
            values, vectors = np.linalg.eigh(a.T @ a)
            weak = vectors[:, 0]
            print(
                f"{row} {view.q_n:.3f} | {view.q_max:.1f} | {values[0]:.3g} | "
                f"{math.degrees(math.atan2(weak[1], weak[0])) % 180:.0f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
