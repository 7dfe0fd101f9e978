"""`lf3pm experiment flight`: the flight study (lf3pm.experiments.flight; docs/flight.md)."""

from __future__ import annotations

from pathlib import Path

import typer

from lf3pm.cli._common import check_output, console, progress_bar, user_errors
from lf3pm.cli.experiment import experiment_app


@experiment_app.command("flight")
def experiment_flight(
    out: Path = typer.Option(..., "-o", "--out", help="Output folder (an interrupted study resumes there)."),
    quick: bool = typer.Option(False, help="One small map (atrium), two pairs, one odometry, one seed."),
    protocol_path: Path | None = typer.Option(
        None,
        "--protocol",
        metavar="PROTOCOL.yaml",
        help="The study's protocol (maps, pairs, sensor, mount, odometries, seeds, risk rule; docs/flight.md); "
        "default: the package's.",
    ),
    write_protocol: Path | None = typer.Option(None, metavar="FILE.yaml", help="Write the protocol and stop."),
    report_only: bool = typer.Option(
        False, help="Analyse the study in --out again from its frozen protocol and records; plan and replay nothing."
    ),
):
    """Quadrotor flights by three planners on the same SOLMs and pairs, judged by LIO replays:
    velocity_yaw (a), yaw_only (b) and joint (c) (docs/flight.md)."""
    with user_errors():
        from lf3pm.errors import Lf3pmError
        from lf3pm.experiments.flight import FlightProtocol, load_protocol, report_folder, run_study, write_report

        if report_only:
            if quick or protocol_path is not None or write_protocol is not None:
                raise Lf3pmError("--report-only reads the protocol frozen in --out: give no other protocol")
            summary, paths = report_folder(out)
            console.print(f"{out}: {', '.join(p.name for p in paths)} written again from its records")
            return

        if quick and protocol_path is not None:
            raise Lf3pmError("--quick and --protocol are two protocols: give one")
        protocol = (
            load_protocol(protocol_path) if protocol_path else (FlightProtocol.quick() if quick else FlightProtocol())
        )
        if write_protocol is not None:
            import yaml

            from lf3pm.atomic import atomic_write

            with atomic_write(write_protocol) as fp:
                fp.write(yaml.safe_dump(protocol.model_dump(mode="json"), sort_keys=False).encode())
            console.print(f"wrote {write_protocol}")
            return
        check_output(out, folder=True)
        with progress_bar() as step:
            seen = {"stage": None, "done": 0}

            def advance(stage, done, total):
                new = stage != seen["stage"]
                step(stage, total, done if new else done - seen["done"], restart=new)
                seen.update(stage=stage, done=done)

            summary = run_study(out, protocol, progress=advance)
        paths = write_report(summary, out)
        console.print(
            f"{out}: {', '.join(p.name for p in paths)}; worst limit ratio {summary['worst_limit_ratio']:.3f}"
        )
