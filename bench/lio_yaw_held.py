"""Investigation (issue 41, docs/benefit.md "Result"), not a benchmark: is the LIO's harm
on the frozen run's no-risk pairs the guided plans' turning?

1. Per no-risk pair, the default-guided plan's swept yaw beyond the unguided plan's, and
   the LIO's APE ratio (guided / none), for GenZ-LIO's maps and DLIO's apart.
2. One change: omni pairs' default-guided plans replayed under the LIO with their
   positions and timing kept and their yaw held at the start's (an omni base may hold any
   yaw; the CSV's velocities are in the world frame), beside the plan as it was (the
   control, which must give the study's APE), seeds 0-2, the study's odometry and options.

    .venv/bin/python bench/lio_yaw_held.py --study out/frozen gobi:4 gobi:6 urban_mid40:4 urban_mid40:6
"""

import argparse
import json
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from lf3pm.config import DEFAULTS
from lf3pm.experiments.benefit.case_file import load_cases
from lf3pm.experiments.benefit.study import lio_options, lio_run
from lf3pm.experiments.replay_tasks import _case_map
from lf3pm.replays.replay import replay

CASES = Path(__file__).resolve().parents[1] / "python/lf3pm/experiments/benefit/cases.yaml"


def turning(study: Path) -> None:
    rows = []
    for line in open(study / "pairs.jsonl"):
        pair = json.loads(line)
        if pair["at_risk"]:
            continue
        swept = {}
        for name in ("none", "default"):
            samples = np.loadtxt(study / pair["plans"][name]["csv"], delimiter=",", skiprows=1)
            swept[name] = np.degrees(np.abs(np.diff(np.unwrap(samples[:, 3]))).sum())
        lio = pair["plans"]["default"]["lio"]["ape"] / pair["plans"]["none"]["lio"]["ape"]
        rows.append((pair["case"], swept["default"] - swept["none"], lio))
    genz = {c.name for c in load_cases(CASES) if lio_run(c, "auto").odometry == "genz"}
    for odometry, keep in (("GenZ-LIO", True), ("DLIO", False)):
        sel = [r for r in rows if (r[0] in genz) == keep]
        extra, ratio = np.array([r[1] for r in sel]), np.array([r[2] for r in sel])
        rho, p = spearmanr(extra, np.log(ratio))
        big = extra > 45
        print(
            f"{odometry}: {len(sel)} no-risk pairs, extra swept yaw median {np.median(extra):.0f} deg; "
            f"Spearman(extra yaw, log LIO ratio) {rho:.2f} (p {p:.2g}); LIO ratio median "
            f"{np.median(ratio[big]):.2f} where the guided plan sweeps > 45 deg more ({big.sum()} pairs), "
            f"{np.median(ratio[~big]):.2f} elsewhere ({(~big).sum()})"
        )


def yaw_held(study: Path, specs: list[str], out: Path) -> None:
    cases = {c.name: c for c in load_cases(CASES)}
    out.mkdir(parents=True, exist_ok=True)
    for spec in specs:
        name, number = spec.split(":")
        case = cases[name]
        run = lio_run(case, "auto", DEFAULTS.replay)
        given = {"odometry": run.odometry, **lio_options(run.odometry, DEFAULTS.replay)}
        world, target = _case_map(case)
        planned = study / "trajectories" / name / f"{int(number):02d}_omni_default.csv"
        head, *rows = planned.read_text().splitlines()
        rows = [r.split(",") for r in rows]
        held = out / f"{name}_{number}_yaw_held.csv"
        held.write_text("\n".join([head] + [",".join(r[:3] + [rows[0][3]] + r[4:6] + ["0"]) for r in rows]) + "\n")
        unguided = [
            json.loads((study / "replays" / name / f"{int(number):02d}_none_lio_{s}.json").read_text())["ape_rmse"]
            for s in range(3)
        ]
        for label, csv in (("as planned", planned), ("yaw held", held)):
            apes = [
                replay(world, str(csv), case.sensor, "lio", s, target=target, threads=1, **given).ape["rmse"]
                for s in range(3)
            ]
            print(
                f"{name} omni pair {number}, default {label}: LIO APE {[round(1e3 * a, 1) for a in apes]} mm "
                f"(median {1e3 * np.median(apes):.1f}); unguided {1e3 * np.median(unguided):.1f} mm",
                flush=True,
            )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--study", type=Path, required=True)
    parser.add_argument("--out", type=Path, default=Path("out/lio_yaw_held"))
    parser.add_argument("pairs", nargs="*", help="MAP:PAIR of omni pairs to replay with the yaw held")
    args = parser.parse_args()
    turning(args.study)
    yaw_held(args.study, args.pairs, args.out)
