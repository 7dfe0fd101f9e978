"""The localization error `lf3pm evaluate` predicts, fitted on the benefit study's plans.

For every plan of the study, q_n is evaluated exactly (``lf3pm.evaluate`` with its
defaults: the full sensor, its range noise, seed 0) at the trajectory's poses once
per second, the same predictor a user gets from ``lf3pm evaluate``; the SOLMs the
plans were made on thin their rays, which raises q_n (a VLP-16 in the houses street:
x1.2 at stride 2, x1.65 at stride 4), so their values are not used. A plan's
predictor is the time mean of q_n; plans that pass a degenerate pose (q_n infinite:
localization follows the odometry there) are left out of the fit. The fit
(lf3pm.calibration.fit_on_q_n) relates it to the plan's localization
APE, the median over the replay seeds, and is validated map by map on maps it did
not use. Per-plan values are kept in DIR/predictors/ so that a rerun resumes.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from lf3pm.atomic import atomic_write
from lf3pm.calibration import fit_on_q_n
from lf3pm.config import DEFAULT_HEIGHT, MetricConfig
from lf3pm.errors import Lf3pmError
from lf3pm.experiments.benefit.protocol import FIT, LocalizationFit
from lf3pm.experiments.benefit.records import LOCALIZATION, Pair, Predictor, StudyFolder, read_json, write_json

#: Poses per second of trajectory at which q_n is evaluated (the protocol's default:
#: ``protocol.localization_fit``).
FIT_RATE = FIT.rate
#: Fewest plans without a degenerate pose a fit is made from.
MIN_PLANS = FIT.min_plans


def plan_predictor(world, csv, sensor: str, *, rate: float = FIT_RATE, height: float = DEFAULT_HEIGHT) -> Predictor:
    """q_n at the trajectory CSV's poses every 1/``rate`` s: its time mean over the
    non-degenerate poses, the share of degenerate ones and the count."""
    from lf3pm.metric import evaluate
    from lf3pm.replays.motion import Motion

    motion = Motion.from_csv(csv, world, height=height)
    poses = motion.pose(np.arange(motion.t0, motion.t1 + 1e-9, 1.0 / rate))
    values = []
    for pose in poses:
        try:
            values.append(evaluate(world, pose, sensor, threads=0).q_n)
        except Lf3pmError:  # a pose too close to the map (the robot's footprint grazes a wall)
            continue
    q = np.asarray(values, float)
    finite = np.isfinite(q)
    return Predictor(
        q_n_mean=float(np.mean(q[finite])) if finite.any() else math.nan,
        degenerate_share=float(np.mean(~finite)) if len(q) else math.nan,
        poses=int(len(q)),
    )


def localization_error_fit(
    out: Path, cases, pairs: list[Pair], *, seeds: int, pair_seed: int, step=None, fit: LocalizationFit = FIT
) -> tuple[dict, dict[tuple[str, int, str], Predictor]]:
    """The fit over the study's plans (``pairs``, with their replays), written to
    DIR/localization_error.json, and each plan's predictor by (map, pair number,
    guidance); ``fit``: the protocol's sampling (``rate``) and fewest plans."""
    settings = fit
    by_name = {case.name: case for case in cases}
    folder = StudyFolder(Path(out))
    maps, q_n, ape, sensors, worlds, predictors = [], [], [], set(), {}, {}
    plans = [(pair, name, plan) for pair in pairs for name, plan in pair.plans.items() if LOCALIZATION in plan.replays]
    if step is not None:
        step("q_n along the plans (localization-error fit)", len(plans), 0, restart=True)
    for pair, name, plan in plans:
        case = by_name[pair.case]
        path = folder.predictor(case.name, pair.number, name)
        if path.exists():
            predictor = Predictor.from_json(read_json(path))
        else:
            if case.name not in worlds:
                from lf3pm.experiments.map_cases import load_case_map

                worlds = {case.name: load_case_map(case)[0]}  # one map in memory at a time
            predictor = plan_predictor(worlds[case.name], folder.root / plan.csv, case.sensor, rate=settings.rate)
            write_json(path, predictor.to_json())
        if step is not None:
            step("q_n along the plans (localization-error fit)", len(plans))
        predictors[(pair.case, pair.number, name)] = predictor
        if predictor.degenerate_share == 0:
            maps.append(case.name)
            q_n.append(predictor.q_n_mean)
            ape.append(plan.replays[LOCALIZATION].ape)
            sensors.add(case.sensor)
    provenance = {
        "command": f"lf3pm experiment benefit (seeds={seeds}, pair_seed={pair_seed})",
        "sensors": sorted(sensors),
        "maps": sorted(set(maps)),
        "w1": MetricConfig().w1,
        "predictor": f"time mean of q_n at {settings.rate:g} Hz along a trajectory (lf3pm.evaluate "
        "defaults), plans with a degenerate pose left out",
        "error": "APE rmse of map localization (docs/replay.md: small_gicp from wheel odometry "
        "with 2 % scale error and 0.01 rad/sqrt(s) yaw noise), median over seeds",
    }
    if len(ape) < settings.min_plans:  # a quick run: nothing to fit
        fit = {"predictor": "q_n", "samples": len(ape), "provenance": provenance}
    else:
        fit = fit_on_q_n(maps, q_n, ape, provenance=provenance)
    with atomic_write(Path(out) / "localization_error.json") as fp:
        fp.write(json.dumps(fit, indent=1).encode())
    return fit, predictors
