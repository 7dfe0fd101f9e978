"""`lf3pm replay`: a planned trajectory replayed through a state estimator on simulated
sensors (lf3pm.replay_seeds), its figures per seed, a PNG and a ROS 2 bag."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from lf3pm.cli._common import (
    CONFIG_OPTION,
    app,
    check_output,
    configure,
    console,
    map_loading,
    option,
    progress_bar,
    user_errors,
)
from lf3pm.cli.replay_table import print_series
from lf3pm.config import DEFAULTS, MAX_TRAJECTORY_SECONDS
from lf3pm.errors import Lf3pmError

#: Where each option of replay lives in the config.
REPLAY_PATHS = {
    "sensor": "sensor",
    "method": "replay.method",
    "odometry": "replay.odometry",
    "seeds": "replay.seeds",
    "seed": "scan.seed",
    "height": "replay.height",
    "rate": "replay.rate",
    "noise": "scan.noise",
    "threads": "scan.threads",
    "mount": "quadrotor.mount",
}


@app.command("replay")
def replay_command(
    trajectory: Path = typer.Argument(..., metavar="TRAJ.csv", help="Trajectory CSV as `lf3pm plan` writes it."),
    map_path: Path = typer.Option(..., "--map", metavar="MAP", help="Point-cloud map the trajectory runs on."),
    config: Path | None = CONFIG_OPTION,
    sensor: str | None = option("sensor"),
    method: str | None = option("replay.method"),
    odometry: str | None = option("replay.odometry"),
    seeds: int | None = option("replay.seeds"),
    seed: int | None = option("scan.seed", help="First seed (range noise, odometry and IMU noise)."),
    height: float | None = option("replay.height"),
    rate: float | None = option("replay.rate"),
    noise: float | None = option("scan.noise"),
    threads: int | None = option("scan.threads"),
    mount: str | None = option("quadrotor.mount", help="A flight's LiDAR mount (top, down20, side)."),
    as_json: bool = typer.Option(
        False,
        "--json",
        help="Print one JSON object (each run with its true and "
        "estimated positions and errors: what `lf3pm view --replay` shows).",
    ),
    png: Path | None = typer.Option(None, metavar="P.png", help="Error along the trajectory and a top view."),
    bag: Path | None = typer.Option(
        None, metavar="OUT.bag", help="ROS 2 bag (directory) of the first seed's simulated stream."
    ),
):
    """Replay a planned trajectory (a ground robot's or a quadrotor's flight) with simulated sensors through a
    state estimator; APE / RPE (evo)."""
    with user_errors():
        cfg = configure(config, locals(), REPLAY_PATHS)
        from lf3pm.map import load_map
        from lf3pm.replays import registry
        from lf3pm.replays.lio import Lio
        from lf3pm.replays.methods import METHODS
        from lf3pm.replays.motion import Motion
        from lf3pm.replays.replay import replay_bag, replay_seeds, resolve_sensor

        check_output(png)
        check_output(bag, folder=True, new=True)
        run, scan = cfg.replay, cfg.scan
        lidar = resolve_sensor(cfg.sensor, run.rate)
        # The method and its odometry checked before the map loads: a name, a pair of
        # odometry and sensor refused or warned about.
        registry.check_name(run.odometry, "--odometry" if odometry is not None else "replay.odometry")
        registry.with_settings(cfg, config)  # the odometries' settings, checked by their sections
        chosen = METHODS[run.method].from_config(cfg)  # its settings: the configuration's
        options = {}
        if chosen.uses_odometry:
            options = {"odometry": run.odometry}
            registry.choose_odometry(run.odometry, lidar)
        elif odometry is not None:
            lio = next(name for name, m in METHODS.items() if m.uses_odometry)
            raise Lf3pmError(f"--odometry applies to --method {lio}, not {run.method}")
        samples = read_trajectory(trajectory, cfg.quadrotor)
        if bag is not None and not isinstance(samples, dict):
            raise Lf3pmError("--bag writes ground robots' replays only, not a flight's")
        with map_loading() as progress:
            world = load_map(map_path, threads=scan.threads, progress=progress)
        motion = (
            samples
            if not isinstance(samples, dict)
            else Motion.from_arrays(
                *(samples[c] for c in ("t", "x", "y", "yaw", "vx", "vy", "omega")),
                map=world,
                height=run.height,
                ground=cfg.ground,
            )
        )
        common = {"rate": run.rate, "height": run.height, "noise": scan.noise, "threads": scan.threads}
        with progress_bar() as step:
            series = replay_seeds(
                world,
                motion,
                lidar,
                chosen,
                run.seeds,
                scan.seed,
                **common,
                progress=lambda s, done, total: step(f"{run.method} replay, seed {s}", total, restart=done == 1),
            )
            bag_info = (
                None
                if bag is None
                else replay_bag(
                    bag,
                    world,
                    motion,
                    lidar,
                    seed=scan.seed,
                    **common,
                    lio=Lio.from_config(cfg),  # the IMU the configuration's lio replay simulates
                    progress=lambda done, total: step(f"writing {bag}", total, restart=done == 1),
                )
            )
        results = series.results
        if png is not None:
            from lf3pm.replays.replay_figures import replay_figure

            replay_figure(
                results,
                png,
                map_points=world.points,
                title=f"lf3pm replay {trajectory.name}: {run.method}"
                + (f" ({results[0].report.get('odometry')})" if options else "")
                + f", {lidar.name}, {run.rate:g} Hz",
            )
        if as_json:
            print(
                json.dumps(
                    {
                        "trajectory": str(trajectory),
                        "map": str(map_path),
                        "method": run.method,
                        **options,
                        "sensor": lidar.name,
                        **series.to_dict(trajectories=True),
                        "png": None if png is None else str(png),
                        "bag": bag_info,
                    }
                )
            )
            return
        print_series(series, run)
        if png is not None:
            console.print(f"wrote {png}", highlight=False)
        if bag_info is not None:
            counts = ", ".join(f"{topic} {n}" for topic, n in bag_info["topics"].items())
            console.print(
                f"wrote {bag} (ROS 2 bag, sqlite3, {bag_info['point_layout']} points): {counts}", highlight=False
            )


def read_trajectory(path: Path, quadrotor=DEFAULTS.quadrotor):
    """The columns of a ground robot's trajectory CSV (Motion.from_csv's input; read_csv
    bounds the file), or the FlightMotion of a flight's (its header names z) flown by
    ``quadrotor`` (config section), refused in one line when it lasts longer than
    MAX_TRAJECTORY_SECONDS, before the map is read (Motion refuses it too, after)."""
    from lf3pm.limits import MAX_TRAJECTORY_BYTES, check_file
    from lf3pm.replays.flight_motion import FlightMotion, csv_header
    from lf3pm.trajectory.trajectory import read_csv

    check_file(path, "trajectory", limit=MAX_TRAJECTORY_BYTES)
    if "z" in csv_header(path):
        from lf3pm.flight import Quadrotor

        samples = FlightMotion.from_csv(path, quadrotor=Quadrotor.from_config(quadrotor))
        duration = samples.t1 - samples.t0
    else:
        samples = read_csv(path)
        duration = float(samples["t"][-1] - samples["t"][0])
    if duration > MAX_TRAJECTORY_SECONDS:
        raise Lf3pmError(
            f"{path}: the trajectory lasts {duration:g} s, more than {MAX_TRAJECTORY_SECONDS:g} s, the "
            "longest lf3pm replays: replay a part of it (its rows within an hour)"
        )
    return samples
