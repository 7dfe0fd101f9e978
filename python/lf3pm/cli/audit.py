"""`lf3pm audit`: a recorded run against its map, scan by scan (lf3pm.audit, docs/real.md)."""

from __future__ import annotations

import json
import shlex
from pathlib import Path

import typer

from lf3pm.cli._common import (
    CONFIG_OPTION,
    MAP_PATHS,
    SCAN_PATHS,
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


@app.command()
def audit(
    ctx: typer.Context,
    run: Path = typer.Argument(
        ..., metavar="RUN", help="A recorded run with reference poses: a folder of scans with a poses file, or a bag."
    ),
    map_path: Path = typer.Option(
        ...,
        "--map",
        metavar="MAP",
        help="The map, in the frame of the run's poses; 'self': the run's own scans at their poses, "
        "each scan's map without the scans within --exclude-window of it (a file named self: ./self).",
    ),
    exclude_window: float | None = option("run.exclude_window", metavar="SECONDS"),
    config: Path | None = CONFIG_OPTION,
    sensor: str | None = option("sensor", help="The sensor of the simulated scans and predictions (preset or YAML)."),
    every: int | None = typer.Option(
        None, min=1, metavar="N", help="Audit every N-th scan (by its index in the run; default: 1)."
    ),
    starts: int | None = option("mde.trials", "--starts", help="Disturbed registration starts per scan."),
    seed: int | None = option("scan.seed", help="Seed of the simulated scans' noise and the starts."),
    noise: float | None = option("scan.noise", help="Range noise of the simulated scans (m; default: the sensor's)."),
    scan_voxel: float | None = option("scan.scan_voxel"),
    map_voxel: float | None = option("map.voxel"),
    knn: int | None = option("map.knn"),
    plane_threshold: float | None = option("map.plane_threshold"),
    max_neighbor_distance: float | None = option("map.max_neighbor_distance"),
    threads: int | None = option("scan.threads"),
    scans_topic: str | None = option("run.scans_topic"),
    poses_topic: str | None = option("run.poses_topic"),
    max_pose_gap: float | None = option("run.max_pose_gap"),
    lidar_time_offset: float | None = option("run.lidar_time_offset"),
    registration: bool = typer.Option(True, help="Register each scan (--no-registration: the metric part only)."),
    track: bool = typer.Option(
        True,
        help="Map localization, KISS-ICP and the LIOs (--lio) along the whole run too (with registration and a "
        "map file).",
    ),
    lio: list[str] | None = typer.Option(
        None,
        "--lio",
        metavar="NAME",
        help="A LiDAR-inertial odometry along the run, where it has an IMU (repeatable; genz, dlio, liosam, a "
        "plugin's or auto; default: every one that takes the sensor's scans).",
    ),
    no_lio: bool = typer.Option(False, "--no-lio", help="No LiDAR-inertial odometry along the run."),
    calibration: str | None = option("prediction.calibration", metavar="FIT.json"),
    calibrate: Path | None = typer.Option(
        None,
        "--calibrate",
        metavar="FIT.json",
        help="Fit the predicted localization error on this run (the simulated scans' q_n against "
        "--calibrate-on) and write it here, for --calibration of evaluate, solm build, plan and audit.",
    ),
    calibrate_on: str = typer.Option(
        "tracking_error_m",
        metavar="ERROR",
        help="The real error --calibrate fits: tracking_error_m (map localization along the run, what the "
        "shipped fit predicts), error_m or spread_m (the registrations from disturbed starts).",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object: per-scan records and the summary."),
    out: Path | None = typer.Option(
        None, "-o", "--out", metavar="DIR", help="Write audit.csv, audit.json, report.md and figures here."
    ),
):
    """Audit a recorded run against a map: per scan at its reference pose, the metric of the
    real scan and of the simulated one, the predicted localization error, and real
    registration from disturbed starts (lf3pm mde's), with their rank correlations."""
    with user_errors():
        paths = {
            **SCAN_PATHS,
            **MAP_PATHS,
            "starts": "mde.trials",
            "calibration": "prediction.calibration",
            **section_paths("run", "scans_topic", "poses_topic", "max_pose_gap", "lidar_time_offset", "exclude_window"),
        }
        cfg = configure(config, locals(), paths)
        from lf3pm.atomic import atomic_write
        from lf3pm.audit import SELF, SelfMap, audit_run, check_run, write_audit
        from lf3pm.audit.calibrate import CALIBRATION_ERRORS, calibrate_run
        from lf3pm.audit.tracks import lio_odometries
        from lf3pm.calibration import localization_fit
        from lf3pm.errors import Lf3pmError
        from lf3pm.map import load_map
        from lf3pm.sensors import as_sensor

        check_output(out, folder=True, parents=True)
        check_output(calibrate)
        if calibrate is not None and calibrate_on not in CALIBRATION_ERRORS:
            raise Lf3pmError(f"--calibrate-on must be one of {', '.join(CALIBRATION_ERRORS)}, got {calibrate_on!r}")
        chosen = as_sensor(cfg.sensor)
        if lio and no_lio:
            raise Lf3pmError("--lio and --no-lio: give one of them")
        odometries = lio_odometries(chosen, () if no_lio else (lio or None))
        check_run(run, cfg)
        if str(map_path) == SELF:
            with map_loading() as loading:
                world = SelfMap.of_run(
                    run,
                    cfg,
                    progress=lambda done, total: loading(f"reading the run for its map: scan {done} of {total or '?'}"),
                )
        else:
            with map_loading() as loading:
                world = load_map(map_path, cfg.map, threads=cfg.scan.threads, progress=loading)
        with progress_bar() as step:
            read, phases = [0], []

            def progress(done: int, total: int | None, phase: str) -> None:
                new = phase not in phases  # a new pass over the run
                if new:
                    phases.append(phase)
                    read[0] = 0
                step(phase, total, advance=done - read[0], restart=new and len(phases) > 1)
                read[0] = done  # bad scans skipped count as read

            result = audit_run(
                run,
                world,
                chosen,
                cfg,
                register=registration,
                track=track,
                lio=odometries,
                progress=progress,
                **({} if every is None else {"every": every}),
            )
        fit = None
        if calibrate is not None:
            base = localization_fit()
            fit = calibrate_run(result, base, cfg, against=calibrate_on, command=command_line(ctx))
            with atomic_write(calibrate) as fp:
                fp.write(json.dumps(fit, indent=1).encode())
        if out is not None:
            drawn = world.whole() if isinstance(world, SelfMap) else world.points  # the map under the path
            write_audit(result, out, drawn, command_line(ctx), calibration=fit)
        if as_json:
            print(json.dumps({**result.to_dict(), **({} if fit is None else {"calibration": fit})}))
            return
        print_summary(result, out)
        if fit is not None:
            print_calibration(fit, calibrate)


def print_summary(result, out: Path | None) -> None:
    """A few lines: scans, timing, the rank correlations with the real error, the ratio."""
    s = result.summary
    timing = result.to_dict()["timing"]
    say = lambda text: console.print(text, highlight=False, soft_wrap=True)  # noqa: E731
    say(f"audited {len(result.records)} scans of {result.run} (every {result.every}), {len(result.bad_scans)} bad")
    say(
        f"metric {result.metric_seconds:.1f} s ({_n(timing['metric_scans_per_second'])} scans/s), "
        f"registration {result.registration_seconds:.1f} s ({_n(timing['registration_scans_per_second'])} scans/s)"
    )
    for c in s.correlations:
        if not c.scans:  # a prediction withheld, or an error not measured, on every scan
            continue
        interval = f"[{_n(c.ci_low)}, {_n(c.ci_high)}]"
        say(f"spearman {c.prediction} ~ {c.real_error}: {_n(c.rho)} {interval} ({c.scans} scans)")
    for real, share in s.inside_interval.items():
        if not s.inside_scans[real]:
            continue
        say(f"{real} inside the predicted interval: {_n(share)} of {s.inside_scans[real]} scans")
    say(f"q_n simulated/recorded: median {_n(s.ratio_median)} [10 % {_n(s.ratio_p10)}, 90 % {_n(s.ratio_p90)}]")
    for t in result.tracks:
        ape = t.ape
        say(f"{t.method} along the run: APE rmse {_n(ape['rmse'])} m, median {_n(ape['median'])}, max {_n(ape['max'])}")
        if t.message:
            say(f"{t.method}: {t.message}")
    if result.lio_withheld and result.lio_withheld != result.tracks_withheld:
        say(f"LiDAR-inertial odometry not run: {result.lio_withheld}")
    for bad in result.bad_scans:
        say(f"bad scan: {bad.reason}")
    if out is not None:
        say(f"wrote {out}/ (audit.csv, audit.json, report.md, along_run.png, path.png)")


def print_calibration(fit: dict, path: Path) -> None:
    """A few lines: the factor on the shipped fit and how each predicts the run's segments."""
    say = lambda text: console.print(text, highlight=False, soft_wrap=True)  # noqa: E731
    shipped, held = fit["shipped"], fit["validation"].values()
    inside = sum(v["share_inside_interval"] * v["scans"] for v in held) / sum(v["scans"] for v in held)
    factor = sorted(v["median_factor"] for v in held)[len(held) // 2]
    say(
        f"calibrated on {fit['samples']} scans: errors {_n(fit['factor'])} times the shipped fit's; shipped fit: "
        f"{_n(shipped['share_inside_interval'] * 100)} % inside its interval, median factor "
        f"{_n(shipped['median_factor'])}; recalibrated, each of {len(held)} segments left out: "
        f"{_n(inside * 100)} % inside, median factor {_n(factor)} (median segment)"
    )
    say(f"wrote {path} (use it with --calibration)")


def command_line(ctx: typer.Context) -> str:
    """The command as given, rebuilt from its parsed parameters (those left at their
    default left out), for the report."""
    parts = ["lf3pm", "audit"]
    for param in ctx.command.params:
        value = ctx.params.get(param.name)
        if param.param_type_name == "argument":
            parts.append(str(value))
        elif value is None or value == param.default:
            continue
        elif isinstance(value, bool):
            parts.append(param.opts[0] if value else param.secondary_opts[0])
        elif isinstance(value, (list, tuple)):  # a repeatable option: once per value
            for item in value:
                parts += [param.opts[0], str(item)]
        else:
            parts += [param.opts[-1] if param.opts[-1].startswith("--") else param.opts[0], str(value)]
    return " ".join(shlex.quote(p) for p in parts)


def _n(value) -> str:
    return "-" if value is None or value != value else f"{value:.3g}"
