"""`lf3pm replay`: a planned trajectory replayed through a state estimator on simulated
sensors (lf3pm.replay_seeds), its figures per seed, a PNG and a ROS 2 bag."""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer
from rich import box
from rich.table import Table

from lf3pm.cli._common import (
    CONFIG_OPTION,
    app,
    check_output,
    configure,
    console,
    map_loading,
    option,
    print_warning,
    progress_bar,
    user_errors,
)
from lf3pm.config import DEFAULTS, MAX_TRAJECTORY_SECONDS, ReplayConfig
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
    """Replay a planned trajectory with simulated sensors through a state estimator; APE / RPE (evo)."""
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
        samples = read_trajectory(trajectory)
        with map_loading() as progress:
            world = load_map(map_path, threads=scan.threads, progress=progress)
        motion = Motion.from_arrays(
            *(samples[c] for c in ("t", "x", "y", "yaw", "vx", "vy", "omega")),
            map=world,
            height=run.height,
            ground=cfg.ground,
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


def read_trajectory(path: Path) -> dict:
    """The columns of a trajectory CSV (Motion.from_csv's input; read_csv bounds the file),
    refused in one line when it lasts longer than MAX_TRAJECTORY_SECONDS, before the map
    is read (Motion refuses it too, after)."""
    from lf3pm.trajectory.trajectory import read_csv

    samples = read_csv(path)
    duration = float(samples["t"][-1] - samples["t"][0])
    if duration > MAX_TRAJECTORY_SECONDS:
        raise Lf3pmError(
            f"{path}: the trajectory lasts {duration:g} s, more than {MAX_TRAJECTORY_SECONDS:g} s, the "
            "longest lf3pm replays: replay a part of it (its rows within an hour)"
        )
    return samples


def print_series(series, settings: ReplayConfig = DEFAULTS.replay) -> None:
    """The figures of each seed and their medians, translations in mm (in metres eleven
    columns of 0.00xxx do not fit 80 characters); the rest judged by the replay section
    ``settings``."""
    from lf3pm.replays.replay_result import FIGURES

    first = series.results[0]
    odometry = first.report.get("odometry")
    method = f"{first.method} ({odometry})" if odometry else first.method
    table = Table(
        title=f"replay: {method}, {first.sensor}, {first.scans} scans at "
        f"{first.params['rate']:g} Hz (rmse in mm; RPE deg per scan)",
        box=box.SIMPLE_HEAD,
        collapse_padding=True,
        pad_edge=False,
    )
    table.add_column("seed")
    for _, header, _ in FIGURES:
        table.add_column(header, justify="right")

    for r in series.results:
        table.add_row(str(r.seed), *(format_figure(key, get(r)) for key, _, get in FIGURES))
    if len(series.results) > 1:
        table.add_row("median", *(format_figure(key, series.median[key]) for key, _, _ in FIGURES))
    console.print(table)
    print_rest(series.results, settings)


def format_figure(key: str, value) -> str:
    """One cell of the replay table: metres in mm, three significant digits, whole numbers
    from 1000 up (a failed run's 27463 mm, not 2.75e+04, which the 80-column table cuts)."""
    from lf3pm.replays.replay_result import METRE_FIGURES

    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    value = value * 1000.0 if key in METRE_FIGURES else value
    if isinstance(value, int):
        return str(value)
    return f"{value:.0f}" if abs(value) >= 1000 else f"{value:.3g}"


def print_rest(results, settings: ReplayConfig = DEFAULTS.replay) -> None:
    """What the LIO did while the sensor stood still before the trajectory, per seed,
    and a warning for each seed that entered the trajectory moving (faster than the
    replay section's rest_speed_limit)."""
    rested = [r for r in results if r.rest]
    if not rested:
        return
    moves = ", ".join(f"seed {r.seed} {1000 * r.rest['drift_m']:.0f} mm" for r in rested)
    console.print(
        f"rest ({rested[0].rest['seconds']:g} s still before the trajectory; APE re-anchored after it): "
        f"the estimate moved at most {moves}",
        highlight=False,
    )
    for r in rested:
        if not r.rest["steady"]:
            print_warning(
                f"seed {r.seed}: the odometry still moved at {r.rest['speed_mps']:.2f} m/s at the end of "
                f"the rest (> {settings.rest_speed_limit:g} m/s): it entered the trajectory with a velocity "
                'error, so this APE measures its start, not the trajectory (docs/lio.md, "A still '
                'sensor")'
            )
