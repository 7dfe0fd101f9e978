"""`lf3pm view`: the map, its SOLM, plans, flights, replays and a recorded run in 3D in the browser."""

from __future__ import annotations

import time
from pathlib import Path

import typer

from lf3pm.cli._common import CONFIG_OPTION, app, configure, console, one_line_warnings, option, user_errors
from lf3pm.view.app import DEFAULT_HOST, DEFAULT_PORT


@app.command("view")
def view(
    map_path: Path = typer.Argument(..., metavar="MAP", help="Point-cloud map."),
    solm: Path | None = typer.Option(None, metavar="S.zarr", help="A SOLM of this map."),
    plan: list[Path] = typer.Option([], metavar="T.csv", help="A trajectory CSV (`lf3pm plan`; repeat)."),
    flight: list[Path] = typer.Option(
        [], metavar="F.csv", help="A flight CSV (`lf3pm plan --robot quadrotor`; repeat): a tube with the body's axes."
    ),
    replay: list[Path] = typer.Option([], metavar="R.json", help="A replay (`lf3pm replay --json`; repeat)."),
    run: Path | None = typer.Option(
        None, metavar="RUN", help="A recorded run (as `lf3pm audit` reads it): its path and its scans over the map."
    ),
    audit: Path | None = typer.Option(
        None,
        metavar="A.json",
        help="Its audit (`lf3pm audit -o DIR`: DIR/audit.json): the scans coloured by error; alone, the run it names.",
    ),
    z: float | None = typer.Option(
        None, "--z", metavar="Z", help="Height (m) of the r3 or r3yaw SOLM's slice shown first: its nearest level."
    ),
    port: int = typer.Option(DEFAULT_PORT, help="Port to serve the page on."),
    host: str = typer.Option(DEFAULT_HOST, help="Address to serve on (0.0.0.0: every interface)."),
    config: Path | None = CONFIG_OPTION,
    robot: str | None = option("robot.kind", help="Robot that plans between clicked poses: omni, diff or car."),
    threads: int | None = option("scan.threads"),
):
    """Serve an interactive 3D view (viser) of the map, the SOLM, plans, flights, replays and a recorded run; Ctrl-C
    stops it."""
    with user_errors():
        cfg = configure(config, locals(), {"robot": "robot.kind", "threads": "scan.threads"})
        from lf3pm.trajectory.robots import Robot
        from lf3pm.view import check_host, check_port, load_view_inputs, serve

        check_host(host)
        check_port(host, port)
        with console.status("reading and indexing the map, reading the SOLM, plans, flights, replays and the run"):
            inputs = load_view_inputs(
                map_path,
                solm,
                plan,
                replay,
                threads=cfg.scan.threads,
                run_path=run,
                audit_path=audit,
                run_config=cfg.run,
                flights=flight,
            )
        with console.status("preparing the page"):
            viewer = serve(
                inputs,
                host=host,
                port=port,
                robot=Robot.from_config(cfg.robot),
                guidance=cfg.guidance,
                planner=cfg.planner,
                z=z,
            )
    shown = "localhost" if host in ("127.0.0.1", "0.0.0.0") else host
    console.print(f"lf3pm view: http://{shown}:{port}  (Ctrl-C stops it)", highlight=False)
    try:
        with one_line_warnings():
            while True:
                time.sleep(1.0)
    except KeyboardInterrupt:
        viewer.stop()
        console.print("lf3pm view: stopped", highlight=False)
