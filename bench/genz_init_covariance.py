"""GenZ-LIO's initial covariance and a still Mid-70 (docs/lio.md, "A still sensor"):
the experiment that isolated why its estimate slid while the sensor stood still, and
the check of lf3pm's fix, both covariances in one run.

GenZ-LIO starts at FAST-LIO2's initial covariance (variance 1 for position, rotation
and velocity: 1 m, 1 rad, 1 m/s) and seeds its voxel map from the first scan at that
covariance. lf3pm's build of it (third_party/genz_lio, installed by ``make build``)
lets the GenZ-LIO setting ``initial_covariance.pose_variance`` change it; lf3pm's
default is lio.GENZ_INIT_POSE_VARIANCE (1e-4). Unset (1), the build reproduces PyPI's
wheel to the millimetre (gobi pair 5's guided plan, seeds 0 and 1: 8.172 and
27.463 m with either).

On one benefit-study map (``--map``, default gobi), with each variance:

1. each pair's start, the sensor still for the replay's rest (lf3pm.replay_rest:
   the LIO on the rest alone, as every replay starts), noise-free and noisy (seeds 0
   and 1): per group the median and largest drift of the estimate from the still
   truth and how many rests ended moving (unsteady, > REST_SPEED_LIMIT); and per
   start its q_n (the view's predicted weakness), to see where the slides remain;
2. the plans named with ``--plans`` (NAME:SEED), the whole replay: APE, the rest, and the
   error every 5 s.

``--variances`` replaces the two. ``--plans-only`` skips part 1; ``--map-file`` and
``--trajectories`` take the plans from another folder (a gobi experiment's). It needs the
study's trajectories (``lf3pm experiment benefit -o out/benefit3``)::

    .venv/bin/python bench/genz_init_covariance.py
    .venv/bin/python bench/genz_init_covariance.py --map orientation --plans 00_omni_default:0
    .venv/bin/python bench/genz_init_covariance.py --plans-only --map-file out/gobi_full/map.npy \
        --trajectories out/gobi_full/trajectories --plans none:1 --variances 1 0.1 0.01 1e-3 1e-4
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr
from study_inputs import study_case

import lf3pm
from lf3pm.experiments.map_cases import load_case_map
from lf3pm.replays.lio import GENZ_INIT_POSE_VARIANCE
from lf3pm.replays.motion import Motion
from lf3pm.replays.replay import replay_rest

#: GenZ-LIO's own initial variance, then lf3pm's.
VARIANCES = (1.0, GENZ_INIT_POSE_VARIANCE)
#: The default plans: gobi pair 5's guided plan on the two seeds GenZ-LIO ran away on
#: (8.2 and 27 m at its own covariance), its unguided plan, and pair 0's guided and
#: unguided omni plans.
PLANS = ("05_diff_default:0", "05_diff_default:1", "05_diff_none:0", "00_omni_default:2", "00_omni_none:2")
#: (label, seed, noise-free) of the still rests at each start.
RESTS = (("noise-free", 0, True), ("noisy", 0, False), ("noisy", 1, False))


def still_starts(world, folder: Path):
    """Per pair (its number, a still Motion at its unguided plan's first pose)."""
    for csv in sorted(folder.glob("*_none.csv")):
        x, y, yaw = (float(v) for v in csv.read_text().splitlines()[1].split(",")[1:4])
        t = np.array([0.0, 0.5])
        yield (
            csv.name[:2],
            Motion.from_arrays(
                t, np.full(2, x), np.full(2, y), np.full(2, yaw), 0 * t, 0 * t, 0 * t, map=world, height=1.0
            ),
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--study", type=Path, default=Path("out/benefit3"))
    parser.add_argument("--map", default="gobi", help="a benefit-study map with the Mid-70 (gobi, orientation, ...)")
    parser.add_argument("--plans", nargs="*", default=list(PLANS), help="NAME:SEED of the study's plans on that map")
    parser.add_argument("--variances", nargs="+", type=float, default=list(VARIANCES))
    parser.add_argument("--plans-only", action="store_true", help="skip the still starts")
    parser.add_argument("--map-file", type=Path, help="the plans' map, instead of the study's --map")
    parser.add_argument("--trajectories", type=Path, help="the plans' folder, instead of the study's")
    args = parser.parse_args()
    case = study_case(args.map)
    folder = args.trajectories or args.study / "trajectories" / args.map
    if not folder.is_dir():
        raise SystemExit(f"no trajectories in {folder}: run lf3pm experiment benefit -o {args.study} first")
    world = lf3pm.load_map(args.map_file) if args.map_file else load_case_map(case)[0]
    if not args.plans_only:
        still_rests(world, case.sensor, folder, args.map, args.variances)
    replay_plans(world, case.sensor, folder, args.plans, args.variances)


def still_rests(world, sensor, folder: Path, map_name: str, variances) -> None:
    """Part 1: the still starts at each variance."""
    starts = list(still_starts(world, folder))
    q_n = np.array([lf3pm.evaluate(world, m.pose(0.0)[0], sensor).q_n for _, m in starts])

    print(f"{map_name}, {sensor}: {len(starts)} starts held still for the replay's rest\n")
    print("| initial variance | rests | drift median / max (m) | unsteady | Spearman(q_n, drift) |")
    print("|---|---|---|---|---|")
    for variance in variances:
        setting = {"initial_covariance": {"pose_variance": variance}}
        for label in ("noise-free", "noisy"):
            rests = [
                (
                    k,
                    replay_rest(
                        world,
                        motion,
                        sensor,
                        seed,
                        threads=1,
                        **({"noise": 0.0, "imu_noise": False} if exact else {}),
                        **setting,
                    ),
                )
                for k, (_, motion) in enumerate(starts)
                for name, seed, exact in RESTS
                if name == label
            ]
            drift = np.array([r["drift_m"] for _, r in rests])
            rho = spearmanr(q_n[[k for k, _ in rests]], drift).statistic
            print(
                f"| {variance:g} | {label} {len(rests)} | {np.median(drift):.3f} / {drift.max():.3f} | "
                f"{sum(not r['steady'] for _, r in rests)} | {rho:.2f} |",
                flush=True,
            )


def replay_plans(world, sensor, folder: Path, plans, variances) -> None:
    """Part 2: the whole replay of each plan at each variance."""
    print("\n| plan:seed | initial variance | APE rmse (m) | rest drift (m) | rest speed (m/s) | error every 5 s (m) |")
    print("|---|---|---|---|---|---|")
    for plan in plans:
        name, seed = plan.split(":")
        for variance in variances:
            result = lf3pm.replay(
                world,
                folder / f"{name}.csv",
                sensor,
                "lio",
                int(seed),
                threads=1,
                initial_covariance={"pose_variance": variance},
            )
            error = np.linalg.norm(result.estimate[:, :3, 3] - result.truth[:, :3, 3], axis=1)
            every = int(round(5 * result.params["rate"]))
            print(
                f"| {plan} | {variance:g} | {result.ape['rmse']:.3f} | {result.rest['drift_m']:.3f} | "
                f"{result.rest['speed_mps']:.3f} | {' '.join(f'{e:.2f}' for e in error[::every])} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
