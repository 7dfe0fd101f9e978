"""The paper's Gobi experiment: plan from inside the town to the warehouse with a
Livox Mid-70 on an omnidirectional robot, guided by q_n, q_min, |dx*| (the
``step_norm`` channel), the shipped default and no metric; compare the
trajectories by S, the sum of MDE along them (the paper's figure of merit), by
localization against the map (the deployment a SOLM is for) and by a
LiDAR-inertial odometry (the paper's FAST-LIO2 setting), both replayed on
simulated scans (docs/replay.md, docs/lio.md).

    lf3pm experiment gobi -o DIR [--reduced]

Writes DIR/summary.json (keyed by guidance), DIR/gobi.md (the table),
DIR/trajectories.png (over the q_n SOLM), DIR/along.png (MDE, localization and
LIO error along each trajectory), DIR/trajectories/<guidance>.csv, and keeps
DIR/solm.zarr and DIR/replays/ (a rerun resumes them).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from lf3pm.atomic import atomic_write
from lf3pm.config import DEFAULTS
from lf3pm.experiments.guidance import GUIDANCE, UNGUIDED
from lf3pm.experiments.map_cases import MapCase, build_case_solm, case_source
from lf3pm.experiments.replay_tasks import ReplayTask, load_replay, replay_json, replay_summary, run_replays, write_plan
from lf3pm.io import write_points
from lf3pm.map import load_map
from lf3pm.planner.plan import Planner
from lf3pm.replays.lio import Lio
from lf3pm.replays.localization import Localization
from lf3pm.scenes.gobi import REDUCED as REDUCED_SCENE
from lf3pm.sensors import get_sensor
from lf3pm.solm import Solm
from lf3pm.trajectory.robots import Robot
from lf3pm.trajectory.sampling import sample_trajectory
from lf3pm.validation import RegistrationTarget
from lf3pm.validation.trajectory_mde import mde_along

PAPER = "paper (its Gobi figure): S = 43.66 guided by q_n against 64.98 by q_min"
#: The replay methods the study compares (lf3pm.replays.methods), by their names.
METHODS = (Localization.name, Lio.name)


@dataclass(frozen=True)
class GobiSetup:
    """Everything the experiment depends on; recorded in summary.json."""

    scene_params: dict
    solm_res: float = 1.0
    yaw_bins: int = DEFAULTS.solm.yaw_bins
    ray_stride: int = 2
    margin: float = 15.0  # m of SOLM west of the town centre and each side of the route
    half_width: float = 30.0  # m of SOLM north and south of the route
    goal_offset: float = 20.0  # m west of the warehouse centre (its west face is 12 m west)
    mde_every: float = 1.0  # s between MDE poses
    mde_trials: int = 5
    replay_seeds: int = 3  # per plan and method
    workers: int = 2  # replay processes
    seed: int = DEFAULTS.gobi.seed


FULL = GobiSetup(scene_params={})
#: A smaller desert (115 x 90 m, warehouse 60 m east, 4 buildings) for the demo.
REDUCED = GobiSetup(
    scene_params=REDUCED_SCENE,
    mde_every=2.0,
    mde_trials=3,
    replay_seeds=2,
)


def map_case(setup: GobiSetup) -> MapCase:
    """The experiment's map as a MapCase (scene, SOLM bounds and resolution)."""
    from lf3pm.scenes import scene_defaults

    params = {**scene_defaults("gobi"), **setup.scene_params}
    goal_x = params["warehouse_distance"] - setup.goal_offset
    return MapCase(
        "gobi",
        "scene:gobi",
        "mid70",
        "se2",
        setup.solm_res,
        yaw_bins=setup.yaw_bins,
        yaw_reuse=True,
        ray_stride=setup.ray_stride,
        scene_params=dict(setup.scene_params),
        scene_seed=setup.seed,
        bounds=(-setup.margin, -setup.half_width, goal_x + setup.margin, setup.half_width),
    )


def run(out: Path, setup: GobiSetup = FULL, *, progress=None) -> dict:
    """Runs the experiment into ``out`` and returns the summary."""
    out = Path(out)
    (out / "trajectories").mkdir(parents=True, exist_ok=True)
    step = progress or (lambda label, total, advance=1, restart=False: None)
    guidance = (UNGUIDED,) + GUIDANCE
    case = map_case(setup)
    source, _ = case_source(case)
    world = load_map(source)
    # The map beside its SOLM, to look at both: `lf3pm view DIR/map.npy --solm DIR/solm.zarr`.
    write_points(out / "map.npy", source)
    goal = (case.bounds[2] - setup.margin, 0.0, 0.0)
    start = (0.0, 0.0, 0.0)  # the town square (the scene's free reference pose)
    step(f"SOLM se2 at {setup.solm_res} m, Mid-70", 1, 0, restart=True)
    solm = Solm.open(build_case_solm(case, out / "solm.zarr", world))
    planner = Planner(solm)
    robot = Robot("omni")
    step("planning and MDE along the plans", len(guidance), 0, restart=True)
    target = RegistrationTarget(world)
    ground = solm.channel("ground_z")
    mid70 = get_sensor("mid70")
    results, plans, tasks = {}, {}, []
    for g in guidance:
        plan = planner.plan(start, goal, robot=robot, metric=g.channel, weight=g.weight, power=g.power)
        plans[g.name] = plan
        csv = out / "trajectories" / f"{g.name}.csv"
        write_plan(plan.trajectory, csv, out / "replays", f"{g.name}_")
        samples = plan.trajectory.sample(100.0)
        z = _ground_under(ground, solm, samples["x"], samples["y"]) + solm.grid_spec.height
        times, poses = sample_trajectory(
            samples["t"], samples["x"], samples["y"], samples["yaw"], every=setup.mde_every, z=z
        )
        along = mde_along(world, poses, mid70, trials=setup.mde_trials, seed=setup.seed, target=target)
        results[g.name] = {
            **plan.summary(),
            "guidance": asdict(g),
            "S": along.s,
            "mde_poses": len(poses),
            "mde_refused": len(along.refused),
            "mde": _finite_list(along.mde),
            "mde_times": times.tolist(),
        }
        tasks += [
            ReplayTask(case, str(csv), method, seed, replay_json(out / "replays", f"{g.name}_", method, seed))
            for method in METHODS
            for seed in range(setup.replay_seeds)
        ]
        step("planning and MDE along the plans", len(guidance))
    run_replays(tasks, setup.workers, step)
    for name, result in results.items():
        for method in METHODS:
            runs = [load_replay(replay_json(out / "replays", f"{name}_", method, s)) for s in range(setup.replay_seeds)]
            result[method] = {
                **replay_summary(runs),
                "times": runs[0]["times_every_second"],
                "errors": runs[0]["errors_every_second"],
            }
    summary = {
        "experiment": "gobi",
        "setup": asdict(setup),
        "start": start,
        "goal": goal,
        "sensor": "mid70",
        "robot": robot.model_dump(),
        "map_points": world.size,
        "map_sha256": world.sha256,
        "paper": PAPER,
        "results": results,
        "finding": _finding(results),
    }
    with atomic_write(out / "summary.json") as fp:
        fp.write(json.dumps(summary, indent=1).encode())
    with atomic_write(out / "gobi.md") as fp:
        fp.write(_table(summary).encode())
    _figures(out, solm, world, plans, results)
    return summary


def _ground_under(ground: np.ndarray, solm: Solm, x, y) -> np.ndarray:
    """Ground height of the SOLM cell under each (x, y) (column minimum of the map)."""
    iy, ix = solm.grid_spec.cell(x, y)[-2:]
    z = ground[iy, ix].astype(np.float64)
    return np.where(np.isfinite(z), z, np.nanmedian(ground))


def _finite_list(values) -> list:
    return [float(v) if np.isfinite(v) else None for v in values]


def _finding(results: dict) -> dict:
    lowest = {
        key: min(results, key=lambda m: results[m][key] if key == "S" else results[m][key]["ape"])
        for key in ("S",) + METHODS
    }
    return {
        "S_lowest": lowest["S"],
        "localization_lowest": lowest["localization"],
        "lio_lowest": lowest["lio"],
        "default_below_none": {
            key: (results["default"]["S"] < results["none"]["S"])
            if key == "S"
            else (results["default"][key]["ape"] < results["none"][key]["ape"])
            for key in ("S",) + METHODS
        },
    }


def _table(summary: dict) -> str:
    seeds = summary["setup"]["replay_seeds"]
    lines = [
        "# Gobi experiment (Mid-70, omnidirectional robot)",
        "",
        f"Start {summary['start']} (town square), goal {summary['goal']} (west of the warehouse). "
        f"{summary['paper']}. APE: rmse of the translation error, median over {seeds} seed(s) "
        "(each seed's in brackets: a difference within their spread is no difference).",
        "",
        "| guidance | length (m) | duration (s) | S (sum of MDE) | MDE poses | localization APE (m) "
        "| degenerate scans | LIO APE (m) | LIO rests steady |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in summary["results"].items():
        loc, lio = r["localization"], r["lio"]
        steady = lio.get("rest_steady_per_seed")
        rests = "n/a" if steady is None else f"{sum(steady)} of {len(steady)}"
        lines.append(
            f"| {name} | {r['trajectory_length_m']:.1f} | {r['duration_s']:.1f} | {r['S']:.4g} | "
            f"{r['mde_poses'] - r['mde_refused']} | {_seeds(loc)} | "
            f"{100 * loc['degenerate_share']:.0f} % | {_seeds(lio)} | {rests} |"
        )
    f = summary["finding"]
    below = ", ".join(f"{k}: {'yes' if v else 'no'}" for k, v in f["default_below_none"].items())
    lines += [
        "",
        f"Lowest S: {f['S_lowest']}; lowest localization APE: {f['localization_lowest']}; lowest LIO "
        f"APE: {f['lio_lowest']}. Default guidance below none by {below}. LIO rests steady: seeds on "
        "which the odometry held still while the sensor stood at the start before the plan (docs/replay.md, "
        '"What the rest reports"); an unsteady one enters the plan moving.',
        "",
    ]
    return "\n".join(lines)


def _seeds(replays: dict) -> str:
    """The median APE and, over several seeds, each seed's."""
    each = replays["ape_per_seed"]
    spread = f" ({', '.join(f'{v:.3g}' for v in each)})" if len(each) > 1 else ""
    return f"{replays['ape']:.3g}{spread}"


def _figures(out: Path, solm: Solm, world, plans: dict, results: dict) -> None:
    import matplotlib.pyplot as plt

    from lf3pm.planner.figures import COLOURS, plans_figure
    from lf3pm.solm.figures import save_figure

    plans_figure(
        solm,
        plans,
        out / "trajectories.png",
        map_points=world.points,
        labels={
            m: f"{m}: localization APE {100 * results[m]['localization']['ape']:.1f} cm, "
            f"LIO {results[m]['lio']['ape']:.2f} m"
            for m in plans
        },
        title="Trajectories over the Mid-70 SOLM (q_n, min over yaw); dotted: grid paths",
    )
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), dpi=110, sharex=True)
    for name, r in results.items():
        colour = "k" if name == "none" else COLOURS[name]
        axes[0].plot(
            r["mde_times"], [np.nan if v is None else v for v in r["mde"]], "o-", ms=3, color=colour, label=name
        )
        for ax, method in zip(axes[1:], METHODS):
            ax.plot(r[method]["times"], r[method]["errors"], color=colour, label=name)
    axes[0].set_yscale("log")
    axes[0].set_ylabel("MDE")
    axes[0].legend(fontsize=8)
    axes[1].set_ylabel("localization error (m)")
    axes[2].set_ylabel("LIO error (m)")
    axes[2].set_xlabel("time along the trajectory (s; replays: seed 0)")
    save_figure(fig, out / "along.png")
