"""The ``lf3pm`` command line."""

from __future__ import annotations

import json
import math
import os
from contextlib import contextmanager
from pathlib import Path
from typing import Optional, Tuple

import numpy as np
import typer
from rich import box
from rich.console import Console
from rich.table import Table

from lf3pm.atomic import atomic_write, check_replaceable
from lf3pm.config import Config, help_with_default, load_config
from lf3pm.errors import Lf3pmError

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="LiDAR perception-aware planning: where will LiDAR localization hold?")
console = Console()
err_console = Console(stderr=True)


@contextmanager
def user_errors():
    """Turns user-input errors into one line on stderr and exit status 2."""
    try:
        yield
    except Lf3pmError as err:
        err_console.print(f"[bold red]lf3pm: error:[/] {err}", highlight=False, soft_wrap=True)
        raise typer.Exit(2) from None


def option(path: str, *names: str, help: str | None = None, **kwargs):
    """The option for config parameter ``path`` (lf3pm.config): None unless given, so that
    ``--config FILE.yaml`` and then the default apply; its help names the default."""
    return typer.Option(None, *names, help=help_with_default(path, help), **kwargs)


CONFIG_OPTION = typer.Option(None, "--config", metavar="FILE.yaml", exists=False,
                             help="Parameters from a YAML file (config/*.yaml; flags given override it).")


def configure(config_file: Path | None, given: dict, paths: dict) -> Config:
    """The command's configuration: ``config_file``, then the options ``given`` (by
    parameter name; None: not given), each at its config path ``paths[name]``."""
    overrides = {paths[name]: value for name, value in given.items() if name in paths}
    flags = {paths[name]: "--" + name.replace("_", "-") for name in paths}
    return load_config(config_file, overrides, flags)


def section_paths(section: str, *names: str) -> dict:
    """{option: "section.option"} for options named as their config parameters."""
    return {name: f"{section}.{name}" for name in names}


#: Where each option of evaluate and mde lives in the config.
SCAN_PATHS = {"sensor": "sensor", "seed": "scan.seed", "noise": "scan.noise", "scan_voxel": "scan.scan_voxel",
              "threads": "scan.threads"}
MAP_PATHS = {"map_voxel": "map.voxel", "knn": "map.knn", "plane_threshold": "map.plane_threshold",
             "max_neighbor_distance": "map.max_neighbor_distance"}


def map_options(config: Config) -> dict:
    """load_map's keywords from the config."""
    m = config.map
    return {"voxel": m.voxel, "cell_size": m.cell_size, "knn": m.knn, "plane_threshold": m.plane_threshold,
            "max_neighbor_distance": m.max_neighbor_distance, "threads": config.scan.threads}


def scan_options(config: Config) -> dict:
    """The scan keywords of evaluate, mde and build_solm from the config."""
    s = config.scan
    return {"seed": s.seed, "noise": s.noise, "scan_voxel": s.scan_voxel, "threads": s.threads}


@app.command()
def evaluate(
    map_path: Path = typer.Argument(..., metavar="MAP", help="Point-cloud map (.pcd .ply .las .laz .npy .npz)."),
    pose: Tuple[float, float, float, float] = typer.Option(..., help="Sensor pose X Y Z YAW (m, rad)."),
    config: Optional[Path] = CONFIG_OPTION,
    sensor: Optional[str] = option("sensor", help="Sensor preset name or YAML file (see `lf3pm sensors`)."),
    seed: Optional[int] = option("scan.seed"),
    noise: Optional[float] = option("scan.noise"),
    dof: Optional[int] = option("metric.dof"),
    w1: Optional[float] = option("metric.w1"),
    scan_voxel: Optional[float] = option("scan.scan_voxel"),
    association: Optional[str] = option("metric.association"),
    map_voxel: Optional[float] = option("map.voxel"),
    knn: Optional[int] = option("map.knn"),
    plane_threshold: Optional[float] = option("map.plane_threshold"),
    max_neighbor_distance: Optional[float] = option("map.max_neighbor_distance"),
    threads: Optional[int] = option("scan.threads"),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    save_observations: Optional[Path] = typer.Option(None, metavar="OBS.npz",
                                                     help="Write A, b and the simulated points."),
):
    """Simulate the scan at one pose and print the LF-3PM metric and baselines."""
    with user_errors():
        cfg = configure(config, locals(), {**SCAN_PATHS, **MAP_PATHS, "dof": "metric.dof", "w1": "metric.w1",
                                           "association": "metric.association"})
        from lf3pm.metric import evaluate as run_evaluate
        from lf3pm.map import load_map

        if save_observations is not None:
            check_replaceable(save_observations)
        world = load_map(map_path, **map_options(cfg))
        result = run_evaluate(world, pose, cfg.sensor, **scan_options(cfg), dof=cfg.metric.dof, w1=cfg.metric.w1,
                              association=cfg.metric.association, observations=save_observations is not None)
        if save_observations is not None:
            obs = result.observations
            with atomic_write(save_observations) as fp:
                np.savez(fp, A=obs["A"], b=obs["b"], points=obs["points"],
                         sensor_points=obs["sensor_points"], row_hit=obs["row_hit"],
                         pose=np.asarray(result.pose))
        out = result.to_dict()
        out["map"] = world.describe()
        if as_json:
            print(json.dumps(out))
            return
        print_evaluation(out)


def print_evaluation(out: dict) -> None:
    table = Table(title=f"LF-3PM metric, sensor {out['sensor']}", show_header=True)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    for key in ("q_min", "q_n", "q_max", "sigma1", "xi", "zhang", "condition_number", "cov_trace",
                "step_norm", "residual_norm", "scaled_cov_trace"):
        value = out[key]
        table.add_row(key, "inf" if value is None else f"{value:.6g}")
    if out["predicted_mde"] is not None:
        lo, hi = out["predicted_mde_interval"]
        table.add_row("predicted MDE", f"{out['predicted_mde']:.3g} [{lo:.2g}, {hi:.2g}]")
    if out["predicted_localization_error_m"] is not None:
        lo, hi = out["predicted_localization_error_interval_m"]
        table.add_row("predicted localization error (m)",
                      f"{out['predicted_localization_error_m']:.3g} [{lo:.2g}, {hi:.2g}]")
    table.add_row("rows m", str(out["m"]))
    table.add_row("hits / rays", f"{out['hits']} / {out['rays']}")
    table.add_row("degenerate", str(out["degenerate"]))
    console.print(table)


@app.command()
def mde(
    map_path: Path = typer.Argument(..., metavar="MAP", help="Point-cloud map."),
    pose: Tuple[float, float, float, float] = typer.Option(..., help="True sensor pose X Y Z YAW (m, rad)."),
    config: Optional[Path] = CONFIG_OPTION,
    sensor: Optional[str] = option("sensor", help="Sensor preset name or YAML file."),
    trials: Optional[int] = option("mde.trials"),
    sigma_t: Optional[float] = option("mde.sigma_t"),
    sigma_r: Optional[float] = option("mde.sigma_r"),
    noise: Optional[float] = option("scan.noise"),
    seed: Optional[int] = option("scan.seed", help="Seed of the scan noise and the disturbances."),
    scan_voxel: Optional[float] = option("scan.scan_voxel"),
    threads: Optional[int] = option("scan.threads"),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
):
    """MDE: mean squared error of point-to-plane ICP (small_gicp) from disturbed starts."""
    with user_errors():
        cfg = configure(config, locals(), {**SCAN_PATHS, "trials": "mde.trials", "sigma_t": "mde.sigma_t",
                                           "sigma_r": "mde.sigma_r"})
        from lf3pm.validation import mde as run_mde
        from lf3pm.map import load_map

        world = load_map(map_path, **map_options(cfg))
        result = run_mde(world, pose, cfg.sensor, trials=cfg.mde.trials, sigma_t=cfg.mde.sigma_t,
                         sigma_r_deg=cfg.mde.sigma_r, **scan_options(cfg))
        out = result.to_dict()
        if as_json:
            print(json.dumps(out))
            return
        table = Table(title=f"MDE, sensor {result.sensor}, {result.trials} trials")
        table.add_column("quantity")
        table.add_column("value", justify="right")
        table.add_row("MDE", f"{result.mde:.6g}")
        table.add_row("median translation error (m)", f"{np.median(result.translation_errors):.4g}")
        table.add_row("median rotation error (deg)", f"{np.median(result.rotation_errors_deg):.4g}")
        table.add_row("converged", f"{result.converged} / {result.trials}")
        table.add_row("scan points", str(result.hits))
        console.print(table)


@app.command("config")
def show_config(config: Optional[Path] = typer.Option(None, "--config", metavar="FILE.yaml",
                                                      help="Show this file's parameters merged with the defaults.")):
    """Print every parameter and its value (the defaults, or FILE.yaml's) as YAML for --config."""
    with user_errors():
        from lf3pm.config import to_yaml

        print(to_yaml(load_config(config)), end="")


@app.command()
def sensors():
    """List the LiDAR presets."""
    from lf3pm.sensors import list_sensors

    table = Table(title="LiDAR presets (a YAML file also works: see docs/sensors.md)")
    for col in ("name", "rays", "range (m)", "noise (m)", "h-FoV (deg)", "model"):
        table.add_column(col)
    for s in list_sensors():
        table.add_row(s.name, str(s.num_rays), f"{s.min_range:g}-{s.max_range:g}",
                      f"{s.range_noise_sigma:g}", f"{math.degrees(s.horizontal_fov):.1f}",
                      ("approximation of " if s.approximate else "") + s.description.split(":")[0])
    console.print(table)


@app.command()
def info(map_path: Path = typer.Argument(..., metavar="MAP"),
         map_voxel: Optional[float] = typer.Option(None, help="Voxel-downsample the map first (m).")):
    """Load and index a map; print its size, extent and index statistics."""
    with user_errors():
        from lf3pm.map import load_map

        console.print_json(json.dumps(load_map(map_path, voxel=map_voxel).describe()))


@app.command()
def scene(
    name: Optional[str] = typer.Argument(None, metavar="NAME", help="Scene name (see --list)."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", metavar="MAP.pcd",
                                          help="Map file to write (format by suffix; .pcd is binary)."),
    seed: Optional[int] = option("scene.seed", help="Seed of the scene's randomness (0 to 2^63 - 1)."),
    list_scenes: bool = typer.Option(False, "--list", help="List the scenes and exit."),
):
    """Build a procedural test scene (houses, meadow, gobi, ...) and write it as a map."""
    with user_errors():
        seed = configure(None, locals(), {"seed": "scene.seed"}).scene.seed
        from lf3pm.scenes import build_scene, describe_scenes, scene_defaults, scene_names

        if list_scenes:
            table = Table(title="Scenes (`lf3pm scene NAME -o MAP.pcd`; see docs/scenes.md)")
            table.add_column("name")
            table.add_column("description")
            for scene_name, description in describe_scenes():
                table.add_row(scene_name, description)
            console.print(table)
            return
        if name is None:
            raise Lf3pmError(f"missing scene NAME; one of: {', '.join(scene_names())} (or --list)")
        scene_defaults(name)  # an unknown name fails here, before anything else
        if output is None:
            raise Lf3pmError("missing -o/--output MAP.pcd: the file to write the scene to")
        from lf3pm.io import SUPPORTED_SUFFIXES, write_points

        if output.suffix.lower() not in SUPPORTED_SUFFIXES:
            raise Lf3pmError(f"{output}: unknown suffix {output.suffix or '(none)'}; "
                             f"supported: {' '.join(SUPPORTED_SUFFIXES)}")
        built = build_scene(name, seed=seed)
        write_points(output, built.points)
        x, y, z, yaw = built.reference_pose
        console.print(f"{built.name}: {built.size:,} points (seed {seed}) -> {output}", highlight=False)
        console.print(f"reference pose x y z yaw: {x:g} {y:g} {z:g} {yaw:g}  "
                      f"(free radius {built.free_radius:g} m)", highlight=False)


experiment_app = typer.Typer(help="Reproducible experiments (tables, figures, summary.json).",
                              no_args_is_help=True)
app.add_typer(experiment_app, name="experiment")


@experiment_app.command("table1")
def experiment_table1(
    out: Path = typer.Option(..., "-o", "--out", help="Output folder."),
    poses: Optional[int] = option("table1.poses"),
    trials: Optional[int] = option("table1.trials"),
    seed: Optional[int] = option("table1.seed"),
):
    """The paper's Table I: q_min, q_n, q_max and MDE on houses, house_meadow, meadow, wall."""
    with user_errors():
        from lf3pm.experiments import table1

        study = configure(None, locals(), section_paths("table1", "poses", "trials", "seed")).table1
        with progress_bar() as step:
            table1.run(out, poses=study.poses, trials=study.trials, seed=study.seed, progress=step)
        console.print((out / "table1.md").read_text())
        console.print(f"wrote {out / 'summary.json'}, {out / 'table1.md'}, {out / 'table1.png'}")


@experiment_app.command("correlation")
def experiment_correlation(
    out: Path = typer.Option(..., "-o", "--out", help="Output folder."),
    poses_per_map: Optional[int] = option("correlation.poses_per_map"),
    trials: Optional[int] = option("correlation.trials"),
    sensor: Optional[str] = option("sensor"),
    bootstrap: Optional[int] = option("correlation.bootstrap"),
    seed: Optional[int] = option("correlation.seed"),
):
    """Spearman correlation of each predictor with MDE, pooled and within maps."""
    with user_errors():
        from lf3pm.experiments import correlation

        cfg = configure(None, locals(), {"sensor": "sensor", **section_paths(
            "correlation", "poses_per_map", "trials", "bootstrap", "seed")})
        study = cfg.correlation
        with progress_bar() as step:
            summary = correlation.run(out, poses_per_map=study.poses_per_map, trials=study.trials, sensor=cfg.sensor,
                                      seed=study.seed, bootstrap=study.bootstrap, progress=step)
        table = Table(title=f"Spearman rho with MDE ({summary['params']['poses']} poses)")
        for col in ("predictor", "pooled rho", "95% CI", "mean within-map rho", "95% CI"):
            table.add_column(col)
        for name, p in summary["predictors"].items():
            table.add_row(name, f"{p['rho']:.2f}", f"[{p['ci'][0]:.2f}, {p['ci'][1]:.2f}]",
                          f"{p['within_mean_rho']:.2f}",
                          f"[{p['within_mean_ci'][0]:.2f}, {p['within_mean_ci'][1]:.2f}]")
        console.print(table)
        console.print(f"best within maps: {summary['best_within_map']}; best pooled: "
                      f"{summary['best_pooled']}; wrote {out}/summary.json, poses.csv, scatter.png")


@experiment_app.command("gobi")
def experiment_gobi(
    out: Path = typer.Option(..., "-o", "--out", help="Output folder (its SOLM and replays resume on a rerun)."),
    reduced: bool = typer.Option(False, help="A smaller desert (115 x 90 m; the demo's)."),
    seeds: Optional[int] = option("gobi.seeds"),
    seed: Optional[int] = option("gobi.seed"),
):
    """Town -> warehouse guided by q_n, q_min, |dx*|, the default and none; S, localization and LIO."""
    with user_errors():
        from dataclasses import replace

        study = configure(None, locals(), section_paths("gobi", "seeds", "seed")).gobi
        from lf3pm.experiments import gobi

        setup = replace(gobi.REDUCED if reduced else gobi.FULL, seed=study.seed)
        if study.seeds is not None:
            setup = replace(setup, replay_seeds=study.seeds)
        with progress_bar() as step:
            gobi.run(out, setup, progress=step)
        console.print((out / "gobi.md").read_text())
        console.print(f"wrote {out}/summary.json, gobi.md, trajectories.png, along.png, trajectories/")


@experiment_app.command("benefit")
def experiment_benefit(
    out: Path = typer.Option(..., "-o", "--out", help="Output folder (an interrupted study resumes there)."),
    quick: bool = typer.Option(False, help="Two small maps, two pairs each, one seed (a few minutes)."),
    seeds: Optional[int] = option("benefit.seeds"),
    workers: Optional[int] = option("benefit.workers"),
    pair_seed: Optional[int] = option("benefit.pair_seed"),
    guidance: Optional[list[str]] = typer.Option(
        None, metavar="NAME=CHANNEL:POWER:WEIGHT",
        help="Compare these instead of q_n, q_min, step_norm and the default (repeat; a tuning run)."),
    lio: Optional[str] = option("benefit.lio"),
):
    """Guided against unguided plans on several maps, judged by localization and LIO replays."""
    with user_errors():
        from lf3pm.experiments import benefit

        study = configure(None, locals(), section_paths("benefit", "seeds", "workers", "pair_seed", "lio")).benefit
        from lf3pm.experiments.guidance import parse_guidance

        candidates = [parse_guidance(g) for g in guidance] if guidance else None
        with progress_bar() as step:
            benefit.run(out, quick=quick, seeds=study.seeds, workers=study.workers, pair_seed=study.pair_seed,
                        guidance=candidates, lio=study.lio, progress=step)
        console.print((out / "benefit.md").read_text())
        console.print(f"wrote {out}/summary.json, benefit.md, scatter.png, ratios.png, examples/")


#: Where each option of plan lives in the config.
PLAN_PATHS = {"robot": "robot.kind", "metric": "guidance.metric", "weight": "guidance.weight",
              "power": "guidance.power", **{name: f"robot.{name}" for name in (
                  "vmax_lon", "vmax_lat", "vmax_norm", "wmax", "amax_lon", "amax_lat", "alpha_max",
                  "min_turn_radius", "r_safe")}}


@app.command()
def plan(
    solm_path: Path = typer.Option(..., "--solm", metavar="S.zarr", help="A built r2 or se2 SOLM."),
    start: Tuple[float, float, float] = typer.Option(..., help="Start X Y YAW (m, rad)."),
    goal: Tuple[float, float, float] = typer.Option(..., help="Goal X Y YAW (m, rad)."),
    out: Path = typer.Option(..., "-o", "--out", metavar="TRAJ.csv",
                             help="Trajectory at 100 Hz: t,x,y,yaw,vx,vy,omega (world frame)."),
    config: Optional[Path] = CONFIG_OPTION,
    robot: Optional[str] = option("robot.kind", help="omni, diff (differential drive) or car."),
    metric: Optional[str] = option("guidance.metric", help="SOLM channel guiding the plan: q_n, q_min, "
                                                           "step_norm or none."),
    weight: Optional[float] = option("guidance.weight", help="lambda: an edge through cells of cost c costs "
                                                             "length (1 + lambda c); a median cell has c = 1 "
                                                             "(docs/benefit.md)."),
    power: Optional[float] = option("guidance.power", help="Exponent applied to the channel (over its median) "
                                                           "before the weight (docs/benefit.md)."),
    vmax_lon: Optional[float] = option("robot.vmax_lon", help="Longitudinal speed limit (m/s)."),
    vmax_lat: Optional[float] = option("robot.vmax_lat", help="Lateral speed limit (m/s; omni)."),
    vmax_norm: Optional[float] = typer.Option(
        None, help="Limit on the speed |v| (m/s; omni; default max(vmax-lon, vmax-lat), inf: none)."),
    wmax: Optional[float] = option("robot.wmax", help="Yaw rate limit (rad/s)."),
    amax_lon: Optional[float] = option("robot.amax_lon", help="Longitudinal (tangential) acceleration limit (m/s^2)."),
    amax_lat: Optional[float] = option("robot.amax_lat", help="Lateral (centripetal) acceleration limit (m/s^2)."),
    alpha_max: Optional[float] = option("robot.alpha_max", help="Yaw acceleration limit (rad/s^2)."),
    min_turn_radius: Optional[float] = option("robot.min_turn_radius", help="Minimum turning radius (m; car)."),
    r_safe: Optional[float] = option("robot.r_safe", help="Clearance beyond the SOLM's robot radius (m)."),
    png: Optional[Path] = typer.Option(None, metavar="P.png", help="Path and trajectory over the SOLM."),
    map_path: Optional[Path] = typer.Option(None, "--map", help="Map drawn under unknown cells in the PNG."),
    as_json: bool = typer.Option(False, "--json", help="Print the plan's summary as JSON."),
):
    """Plan a perception-aware trajectory on a SOLM (graph search, then MINCO + L-BFGS)."""
    with user_errors():
        cfg = configure(config, locals(), PLAN_PATHS)
        from lf3pm.planner.plan import Planner
        from lf3pm.solm import Solm

        from lf3pm.planner.robots import Robot

        vehicle, guidance = Robot.from_config(cfg.robot), cfg.guidance
        metric = guidance.metric
        solm = Solm.open(solm_path)
        result = Planner(solm).plan(start, goal, robot=vehicle, metric=metric, weight=guidance.weight,
                                    power=guidance.power)
        # All or none: the figure first (the likelier to fail), then the CSV; a CSV that
        # cannot be written takes the new figure with it.
        if png is not None:
            from lf3pm.map import load_map
            from lf3pm.planner.figures import plans_figure

            check_replaceable(out)
            points = load_map(map_path).points if map_path is not None else None
            plans_figure(solm, {metric: result}, png, map_points=points,
                         title=f"{vehicle.kind} plan guided by {metric} over the SOLM (dotted: front-end path)")
        try:
            result.trajectory.to_csv(out)
        except Lf3pmError:
            if png is not None:
                png.unlink(missing_ok=True)
            raise
        summary = result.summary()
        if as_json:
            print(json.dumps(summary, indent=1))
        else:
            console.print(f"{out}: {summary['duration_s']:.1f} s, {summary['trajectory_length_m']:.1f} m "
                          f"(front-end path {summary['path_length_m']:.1f} m); search "
                          f"{summary['search_s'] * 1e3:.0f} ms, optimisation "
                          f"{summary['optimize_s'] * 1e3:.0f} ms")


@app.command("replay")
def replay_command(
    trajectory: Path = typer.Argument(..., metavar="TRAJ.csv", help="Trajectory CSV as `lf3pm plan` writes it."),
    map_path: Path = typer.Option(..., "--map", metavar="MAP", help="Point-cloud map the trajectory runs on."),
    config: Optional[Path] = CONFIG_OPTION,
    sensor: Optional[str] = option("sensor", help="Sensor preset name or YAML file."),
    method: Optional[str] = option("replay.method"),
    odometry: Optional[str] = option("replay.odometry"),
    seeds: Optional[int] = option("replay.seeds", help="Runs seeds SEED .. SEED+N-1 and reports each and the median."),
    seed: Optional[int] = option("scan.seed", help="First seed (range noise, odometry and IMU noise)."),
    height: Optional[float] = option("replay.height"),
    rate: Optional[float] = option("replay.rate"),
    noise: Optional[float] = option("scan.noise"),
    threads: Optional[int] = option("scan.threads", help="Scan simulation threads (0 = all cores)."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    png: Optional[Path] = typer.Option(None, metavar="P.png", help="Error along the trajectory and a top view."),
    bag: Optional[Path] = typer.Option(None, metavar="OUT.bag",
                                       help="ROS 2 bag (directory) of the first seed's simulated stream."),
):
    """Replay a planned trajectory with simulated sensors through a state estimator; APE / RPE (evo)."""
    with user_errors():
        cfg = configure(config, locals(), {"sensor": "sensor", "method": "replay.method",
                                           "odometry": "replay.odometry", "seeds": "replay.seeds",
                                           "seed": "scan.seed", "height": "replay.height", "rate": "replay.rate",
                                           "noise": "scan.noise", "threads": "scan.threads"})
        from lf3pm.validation.replay import lio_modules, resolve_sensor

        method, seeds, height, rate = cfg.replay.method, cfg.replay.seeds, cfg.replay.height, cfg.replay.rate
        seed, noise, threads = cfg.scan.seed, cfg.scan.noise, cfg.scan.threads
        sensor = cfg.sensor
        lidar = resolve_sensor(sensor, rate)
        if png is not None:
            check_replaceable(png)
        if bag is not None:
            if os.path.lexists(bag):
                raise Lf3pmError(f"{bag} exists: a bag is a new directory and lf3pm replaces nothing there")
            lio_modules("--bag (it carries the simulated IMU)")
        if method == "lio":
            lio_modules()
        elif odometry is not None:
            raise Lf3pmError(f"--odometry applies to --method lio, not {method}")
        options = {"odometry": cfg.replay.odometry} if method == "lio" else {}
        from lf3pm.validation.motion import Motion
        from lf3pm.validation.replay import METHOD_PARAMS, replay, simulated_imu
        from lf3pm.map import load_map
        from lf3pm.planner.trajectory import read_csv

        samples = read_csv(trajectory)
        world = load_map(map_path, threads=threads)
        motion = Motion.from_arrays(samples["t"], samples["x"], samples["y"], samples["yaw"], samples["vx"],
                                    samples["vy"], samples["omega"], map=world, height=height)
        target = None
        if method == "localization":
            from lf3pm.validation.mde import RegistrationTarget

            target = RegistrationTarget(world, threads=threads)
        results = []
        with progress_bar() as step:
            for s in range(seed, seed + seeds):
                label = f"{method} replay, seed {s}"
                step(label, None, 0, restart=True)
                results.append(replay(world, motion, lidar, method, s, rate=rate, noise=noise, target=target,
                                      threads=threads, progress=lambda done, total: step(label, total), **options))
            bag_info = None
            if bag is not None:
                from lf3pm.validation.bag import write_bag
                from lf3pm.validation.scans import ScanStream

                scans = ScanStream(world, motion, lidar, rate=rate, seed=seed, noise=noise, threads=threads)
                imu = simulated_imu(motion, seed, METHOD_PARAMS["lio"])
                step(f"writing {bag}", len(scans), 0, restart=True)
                bag_info = write_bag(bag, scans, imu, progress=lambda done, total: step(f"writing {bag}", total))
        if png is not None:
            from lf3pm.validation.replay_figures import replay_figure

            replay_figure(results, png, map_points=world.points,
                          title=f"lf3pm replay {trajectory.name}: {method}"
                          + (f" ({results[0].report.get('odometry')})" if options else "")
                          + f", {lidar.name}, {rate:g} Hz")
        summary = _replay_medians(results)
        if as_json:
            print(json.dumps({"trajectory": str(trajectory), "map": str(map_path), "method": method, **options,
                              "sensor": lidar.name, "seeds": [r.seed for r in results],
                              "runs": [r.to_dict() for r in results], "median": summary,
                              "png": None if png is None else str(png), "bag": bag_info}))
            return
        _print_replay(results, summary)
        if png is not None:
            console.print(f"wrote {png}", highlight=False)
        if bag_info is not None:
            counts = ", ".join(f"{topic} {n}" for topic, n in bag_info["topics"].items())
            console.print(f"wrote {bag} (ROS 2 bag, sqlite3, {bag_info['point_layout']} points): {counts}",
                          highlight=False)


#: (JSON key, table header, value) of each figure the replay reports per seed.
_REPLAY_COLUMNS = (("ape_rmse", "APE", lambda r: r.ape["rmse"]), ("ape_max", "APE max", lambda r: r.ape["max"]),
                   ("ape_aligned_rmse", "aligned", lambda r: r.ape_aligned["rmse"]),
                   ("rpe_scan_rmse", "RPE scan", lambda r: r.rpe_frame["translation"]["rmse"]),
                   ("rpe_scan_deg_rmse", "RPE deg", lambda r: r.rpe_frame["rotation_deg"]["rmse"]),
                   ("rpe_metre_rmse", "RPE 1 m", lambda r: r.rpe_metre["translation"]["rmse"]),
                   ("degenerate_scans", "degen", lambda r: int(r.degenerate.sum())),
                   ("skipped_scans", "skip", lambda r: len(r.skipped)),
                   ("scans_per_second", "scans/s", lambda r: r.scans_per_second["total"]))
#: The figures of _REPLAY_COLUMNS in metres (the JSON keeps metres; the table shows mm).
_REPLAY_METRES = {"ape_rmse", "ape_max", "ape_aligned_rmse", "rpe_scan_rmse", "rpe_metre_rmse"}


def _replay_medians(results) -> dict:
    """Median over seeds of each reported figure (None where no seed has it)."""
    out = {}
    for key, _, get in _REPLAY_COLUMNS:
        values = np.array([get(r) for r in results], dtype=float)
        values = values[np.isfinite(values)]
        out[key] = float(np.median(values)) if len(values) else None
    return out


def _print_replay(results, summary: dict) -> None:
    first = results[0]
    odometry = first.report.get("odometry") if first.method == "lio" else None
    method = f"{first.method} ({odometry})" if odometry else first.method
    table = Table(title=f"replay: {method}, {first.sensor}, {first.scans} scans at "
                        f"{first.params['rate']:g} Hz (rmse in mm; RPE deg per scan)", box=box.SIMPLE_HEAD,
                  collapse_padding=True, pad_edge=False)
    table.add_column("seed")
    for _, header, _ in _REPLAY_COLUMNS:
        table.add_column(header, justify="right")
    show = lambda v: "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else (
        str(v) if isinstance(v, int) else f"{v:.3g}")
    # Translations in mm: in metres eleven columns of 0.00xxx do not fit 80 characters.
    mm = lambda key, v: v * 1000.0 if v is not None and key in _REPLAY_METRES else v
    for r in results:
        table.add_row(str(r.seed), *(show(mm(key, get(r))) for key, _, get in _REPLAY_COLUMNS))
    if len(results) > 1:
        table.add_row("median", *(show(mm(key, summary[key])) for key, _, _ in _REPLAY_COLUMNS))
    console.print(table)


@contextmanager
def progress_bar():
    """A rich progress bar on stderr; yields step(label, total, advance=1, restart=False)
    (restart: a new phase, counted from zero). The bar appears at the first step, so that
    an error before any work is its one line alone."""
    from rich.progress import BarColumn, Progress, TimeElapsedColumn, TimeRemainingColumn

    bar = Progress("[progress.description]{task.description}", BarColumn(), "{task.completed}/{task.total}",
                   TimeElapsedColumn(), TimeRemainingColumn(), console=err_console)
    task = None

    def step(label, total, advance=1, restart=False):
        nonlocal task
        if task is None:
            bar.start()
            task = bar.add_task(label, total=total)
        elif restart:
            bar.reset(task, total=total, description=label)
        bar.update(task, description=label, total=total, advance=advance)

    try:
        yield step
    finally:
        if task is not None:
            bar.stop()


solm_app = typer.Typer(help="Static Observation Loss Maps: build, view, export.", no_args_is_help=True)
app.add_typer(solm_app, name="solm")


@solm_app.command("build")
def solm_build(
    map_path: Path = typer.Argument(..., metavar="MAP", help="Point-cloud map."),
    out: Path = typer.Option(..., "-o", "--out", help="Output Zarr store (resumed if it exists)."),
    config: Optional[Path] = CONFIG_OPTION,
    sensor: Optional[str] = option("sensor", help="Sensor preset name or YAML file."),
    space: Optional[str] = option("solm.space"),
    res: Optional[float] = option("solm.res"),
    yaw_bins: Optional[int] = option("solm.yaw_bins"),
    yaw_reuse: Optional[bool] = option("solm.yaw_reuse", "--yaw-reuse/--no-yaw-reuse"),
    ray_stride: Optional[int] = option("solm.ray_stride"),
    height: Optional[float] = option("solm.height"),
    bounds: Optional[Tuple[float, float, float, float]] = option("solm.bounds"),
    robot_radius: Optional[float] = option("solm.robot_radius"),
    seed: Optional[int] = option("scan.seed"),
    noise: Optional[float] = option("scan.noise"),
    threads: Optional[int] = option("scan.threads"),
    max_cells: Optional[int] = option("solm.max_cells"),
    engine: str = typer.Option("local", help="local (this machine, --threads) or ray (one task per tile on a "
                                             "Ray cluster; docs/scale.md)."),
    address: Optional[str] = typer.Option(None, metavar="HOST:PORT",
                                          help="The Ray cluster's head (`ray start --head`; default: a local "
                                               "cluster on this machine's cores)."),
    crop: bool = typer.Option(False, help="local: build each tile on its own crop of the map (exact; the "
                                          "ray engine always does)."),
    crop_above: Optional[int] = option("solm.crop_above"),
):
    """Evaluate the metric over a grid and store it (chunked Zarr, resumable)."""
    with user_errors():
        paths = {"sensor": "sensor", "seed": "scan.seed", "noise": "scan.noise", "threads": "scan.threads",
                 **{name: f"solm.{name}" for name in ("space", "res", "yaw_bins", "yaw_reuse", "ray_stride",
                                                      "height", "bounds", "robot_radius", "max_cells",
                                                      "crop_above")}}
        cfg = configure(config, locals(), paths)
        from lf3pm.map import load_map_points
        from lf3pm.sensors import get_sensor
        from lf3pm.solm import build_solm, make_grid

        grid_config = cfg.solm
        lidar = get_sensor(cfg.sensor)
        world = load_map_points(map_path, **map_options(cfg))
        # A local build of a map small enough indexes it whole; otherwise each tile is built
        # on its own crop (the same store, bitwise).
        if engine == "local" and not crop and world.size <= grid_config.crop_above:
            world = world.indexed(cfg.scan.threads)
        elif engine == "local" and not crop:
            err_console.print(f"{map_path}: {world.size:,} points, more than --crop-above "
                              f"{grid_config.crop_above:,}: building tile by tile on crops", highlight=False)
        grid = make_grid(world, grid_config.space, grid_config.res, bounds=grid_config.bounds,
                         yaw_bins=grid_config.yaw_bins, height=grid_config.height, max_cells=grid_config.max_cells)
        with progress_bar() as step:
            def advance(cells, total):
                step(f"SOLM {grid.space} {grid.shape} cells", total, cells)

            result = build_solm(world, lidar, grid, out, seed=cfg.scan.seed, noise=cfg.scan.noise,
                                robot_radius=grid_config.robot_radius, yaw_reuse=grid_config.yaw_reuse,
                                ray_stride=grid_config.ray_stride, threads=cfg.scan.threads,
                                association=cfg.metric.association, w1=cfg.metric.w1, crop=crop,
                                engine=engine, address=address, progress=advance)
        console.print(f"{out}: {grid.space} grid {grid.shape} at {grid.res} m; tiles built now "
                      f"{result['built_now']} of {result['tiles']}; complete: {result['complete']}")


@solm_app.command("view")
def solm_view(
    store: Path = typer.Argument(..., metavar="OUT.zarr"),
    png: Path = typer.Option(..., "-o", "--out", help="PNG to write."),
    channel: str = typer.Option("q_n", help="Channel to draw."),
    reduce: str = typer.Option("mean", help="min, mean or max over yaw bins / z levels."),
    map_path: Optional[Path] = typer.Option(None, "--map", help="Draw this map's top view under it."),
):
    """Heat map of a SOLM channel over the map's top view."""
    with user_errors():
        from lf3pm.io import load_points
        from lf3pm.solm import Solm
        from lf3pm.solm.figures import heat_map

        solm = Solm.open(store)
        points = load_points(map_path) if map_path else None
        heat_map(solm, png, channel=channel, reduce=reduce, map_points=points)
        console.print(f"wrote {png}")


@solm_app.command("export")
def solm_export(
    store: Path = typer.Argument(..., metavar="OUT.zarr"),
    folder: Path = typer.Argument(..., metavar="DIR"),
    reduce: str = typer.Option("mean", help="min, mean or max over yaw bins / z levels."),
):
    """ROS map_server PNG + YAML per channel."""
    with user_errors():
        from lf3pm.solm import Solm
        from lf3pm.solm.figures import export_ros

        written = export_ros(Solm.open(store), folder, reduce=reduce)
        console.print(f"wrote {len(written)} files to {folder}")


def main() -> None:
    """The CLI (the `lf3pm` command runs it through lf3pm.__main__)."""
    app()


if __name__ == "__main__":
    main()
