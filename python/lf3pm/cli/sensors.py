"""`lf3pm sensors`: the LiDAR presets, and `lf3pm sensors fit`: a sensor from a recorded run."""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer
from rich.table import Table

from lf3pm.cli._common import (
    CONFIG_OPTION,
    MAP_PATHS,
    app,
    check_output,
    configure,
    console,
    map_loading,
    option,
    progress_bar,
    section_paths,
    user_errors,
)

sensors_app = typer.Typer(
    help="LiDAR models: `lf3pm sensors` lists the presets, `lf3pm sensors fit` fits one from a recorded run."
)
app.add_typer(sensors_app, name="sensors")


@sensors_app.callback(invoke_without_command=True)
def sensors(ctx: typer.Context):
    """List the LiDAR presets (`lf3pm sensors fit --help`: a sensor from your own run)."""
    if ctx.invoked_subcommand is not None:
        return
    from lf3pm.sensors import list_sensors

    table = Table(title="LiDAR presets (a YAML file also works: see docs/sensors.md)")
    for col in ("name", "rays", "range (m)", "noise (m)", "h-FoV (deg)", "model"):
        table.add_column(col)
    for s in list_sensors():
        table.add_row(
            s.name,
            str(s.num_rays),
            f"{s.min_range:g}-{s.max_range:g}",
            f"{s.range_noise_sigma:g}",
            f"{math.degrees(s.horizontal_fov):.1f}",
            ("approximation of " if s.approximate else "") + s.description.split(":")[0],
        )
    console.print(table)


@sensors_app.command("fit")
def fit(
    run: Path = typer.Argument(
        ..., metavar="RUN", help="A recorded run: a folder of scans (with a poses file for --map), or a bag."
    ),
    out: Path = typer.Option(..., "-o", "--out", metavar="SENSOR.yaml", help="The fitted sensor's YAML."),
    map_path: Path | None = typer.Option(
        None,
        "--map",
        metavar="MAP",
        help="A map in the frame of the run's poses, for the range noise and the comparison with simulated scans; "
        "'self': the run's own scans, each scan's without those within --exclude-window of it.",
    ),
    scans: int = typer.Option(20, min=2, metavar="N", help="Scans read, spread evenly over the run."),
    name: str = typer.Option("fitted", help="The sensor's name in the YAML."),
    returns: bool = typer.Option(
        True,
        "--returns/--no-returns",
        help="With --map: fit which rays return (return_probability over range and incidence; docs/sensors.md).",
    ),
    config: Path | None = CONFIG_OPTION,
    exclude_window: float | None = option("run.exclude_window", metavar="SECONDS"),
    scans_topic: str | None = option("run.scans_topic"),
    poses_topic: str | None = option("run.poses_topic"),
    threads: int | None = option("scan.threads"),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object: the fit and the comparison."),
):
    """Fit a sensor (ray pattern, range limits, range noise, which rays return) from a
    recorded run's scans and write it as a YAML that works wherever a preset does
    (docs/sensors.md)."""
    with user_errors():
        paths = {
            **MAP_PATHS,
            "threads": "scan.threads",
            **section_paths("run", "scans_topic", "poses_topic", "exclude_window"),
        }
        cfg = configure(config, locals(), paths)
        from lf3pm.audit import SELF, SelfMap
        from lf3pm.audit.sensor_fit import fit_sensor, write_sensor
        from lf3pm.map import load_map

        check_output(out)
        world = None
        if map_path is not None:
            with map_loading() as loading:
                if str(map_path) == SELF:
                    world = SelfMap.of_run(run, cfg, progress=lambda d, t: loading(f"reading the run: scan {d}"))
                else:
                    world = load_map(map_path, cfg.map, threads=cfg.scan.threads, progress=loading)
        with progress_bar() as step:
            fitted = fit_sensor(
                run,
                world,
                cfg,
                scans=scans,
                name=name,
                returns=returns,
                progress=lambda d, t: step("range noise and comparison", t, 1),
            )
        written = write_sensor(fitted, out)
        if as_json:
            print(json.dumps({**fitted.to_dict(), "written": [str(p) for p in written]}))
            return
        say = lambda text: console.print(text, highlight=False, soft_wrap=True)  # noqa: E731
        say(fitted.yaml["description"])
        if fitted.return_scans:
            say(f"return probability fitted on {fitted.return_scans} scans, the scans below left out")
        for c in fitted.comparisons:
            say(
                f"scan {c.index}: rays returning real {c.real_share:.1%}, simulated {c.sim_share:.1%}; "
                f"{c.share_both:.0%} of rays returned in both (real only {c.real_only}, simulated only {c.sim_only}); "
                f"range real - simulated {c.residual_median_m:+.3f} m (sigma {c.residual_sigma_m:.3f}); "
                f"q_n simulated/real {c.q_n_ratio:.3g}, sigma1 {c.sigma1_ratio:.3g}"
            )
        if world is None:
            say("no --map: range noise not estimated (0 written) and no comparison with simulated scans")
        say(f"wrote {', '.join(map(str, written))}")
