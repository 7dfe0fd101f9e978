"""`lf3pm plan`: a perception-aware trajectory on a SOLM."""

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
    print_warning,
    user_errors,
)
from lf3pm.errors import Lf3pmError
from lf3pm.planner.flight_attitude import ATTITUDE_ROUNDS

#: Where each option of plan lives in the config.
PLAN_PATHS = {
    "robot": "robot.kind",
    "calibration": "prediction.calibration",
    "metric": "guidance.metric",
    "weight": "guidance.weight",
    "power": "guidance.power",
    "turn_radius": "guidance.turn_radius",
    **{
        name: f"robot.{name}"
        for name in (
            "vmax_lon",
            "vmax_lat",
            "vmax_norm",
            "wmax",
            "amax_lon",
            "amax_lat",
            "alpha_max",
            "min_turn_radius",
            "r_safe",
        )
    },
}


@app.command()
def plan(
    solm_path: Path = typer.Option(
        ..., "--solm", metavar="S.zarr", help="A built r2 or se2 SOLM (an r3yaw one for --robot quadrotor)."
    ),
    start: tuple[float, float, float] = typer.Option(..., help="Start X Y YAW (m, rad)."),
    goal: tuple[float, float, float] = typer.Option(..., help="Goal X Y YAW (m, rad)."),
    out: Path = typer.Option(
        ...,
        "-o",
        "--out",
        metavar="TRAJ.csv",
        help="Trajectory at 100 Hz: t,x,y,yaw,vx,vy,omega (world frame); a quadrotor's "
        "t,x,y,z,yaw,vx,vy,vz,yaw_rate,qw,qx,qy,qz,thrust,ax,ay,az.",
    ),
    config: Path | None = CONFIG_OPTION,
    robot: str | None = typer.Option(
        None,
        "--robot",
        help="omni, diff or car (ground robots; config robot.kind, default omni) or quadrotor (an r3yaw SOLM; "
        "config section quadrotor; docs/flight.md).",
    ),
    start_z: float | None = typer.Option(None, metavar="Z", help="Quadrotor: the start's height (m)."),
    goal_z: float | None = typer.Option(None, metavar="Z", help="Quadrotor: the goal's height (m)."),
    mount: str | None = option("quadrotor.mount"),
    flight_planner: str = typer.Option(
        "joint",
        "--planner",
        help="Quadrotor: joint (position and yaw on the SOLM), velocity_yaw (minimum time, yaw along the "
        "velocity, no perception) or yaw_only (that flight, its yaw alone on the SOLM); docs/flight.md.",
    ),
    attitude_rounds: int = typer.Option(
        ATTITUDE_ROUNDS,
        help="Quadrotor, joint: rounds of the guidance at the planned attitude (the SOLM cast level, corrected "
        "along the flight and optimised again; 0: level only).",
    ),
    metric: str | None = option("guidance.metric"),
    weight: float | None = option("guidance.weight"),
    power: float | None = option("guidance.power"),
    turn_radius: float | None = option("guidance.turn_radius"),
    vmax_lon: float | None = option("robot.vmax_lon"),
    vmax_lat: float | None = option("robot.vmax_lat"),
    vmax_norm: float | None = option("robot.vmax_norm", with_default=False),
    wmax: float | None = option("robot.wmax"),
    amax_lon: float | None = option("robot.amax_lon"),
    amax_lat: float | None = option("robot.amax_lat"),
    alpha_max: float | None = option("robot.alpha_max"),
    min_turn_radius: float | None = option("robot.min_turn_radius"),
    r_safe: float | None = option("robot.r_safe"),
    calibration: str | None = option(
        "prediction.calibration",
        metavar="FIT.json",
        help="The localization-error fit for the plan's predicted error (default: the SOLM's, else the packaged "
        "one); `lf3pm audit --calibrate` writes one from your own run.",
    ),
    png: Path | None = typer.Option(None, metavar="P.png", help="Path and trajectory over the SOLM."),
    map_path: Path | None = typer.Option(None, "--map", help="Map drawn under unknown cells in the PNG."),
    as_json: bool = typer.Option(False, "--json", help="Print the plan's summary as JSON."),
):
    """Plan a perception-aware trajectory on a SOLM (graph search, then MINCO + L-BFGS)."""
    with user_errors():
        flying = robot == "quadrotor"
        if flying:
            robot = None  # the quadrotor section holds what flies
        cfg = configure(config, locals(), {**PLAN_PATHS, "mount": "quadrotor.mount"})
        check_output(out)
        check_output(png)
        if attitude_rounds and not (flying and flight_planner == "joint"):
            raise Lf3pmError("--attitude-rounds applies to --robot quadrotor with --planner joint")
        if flying:
            flight = (start_z, goal_z, flight_planner, attitude_rounds)
            _plan_flight(cfg, solm_path, start, goal, flight, out, map_path, as_json)
            return
        if start_z is not None or goal_z is not None:
            raise Lf3pmError("--start-z and --goal-z are a quadrotor's (--robot quadrotor)")
        from lf3pm.planner.plan import Planner
        from lf3pm.prediction import predicted_error_along, solm_fit
        from lf3pm.solm import Solm
        from lf3pm.trajectory.robots import Robot

        vehicle, guidance = Robot.from_config(cfg.robot), cfg.guidance
        metric = guidance.metric
        solm = Solm.open(solm_path)
        result = Planner(solm, cfg.planner).plan(start, goal, robot=vehicle, guidance=guidance)
        # All or none: the figure first (the likelier to fail), then the CSV; a CSV that
        # cannot be written takes the new figure with it.
        if png is not None:
            from lf3pm.map import load_map
            from lf3pm.planner.figures import plans_figure

            points = None
            if map_path is not None:
                with map_loading() as progress:
                    points = load_map(map_path, progress=progress).points
            plans_figure(
                solm,
                {metric: result},
                png,
                map_points=points,
                title=f"{vehicle.kind} plan guided by {metric} over the SOLM (dotted: front-end path)",
            )
        try:
            result.trajectory.to_csv(out)
        except Lf3pmError:
            if png is not None:
                png.unlink(missing_ok=True)
            raise
        summary = result.summary()
        error, withheld = predicted_error_along(
            solm, result.trajectory.sample(), solm_fit(solm, cfg.prediction.calibration)
        )
        summary |= {"predicted_localization_error_m": error, "predicted_localization_error_withheld": withheld}
        for line in summary["warnings"]:
            print_warning(f"{out}: {line}")
        if as_json:
            print(json.dumps(summary, indent=1))
        else:
            console.print(
                f"{out}: {summary['duration_s']:.1f} s, {summary['trajectory_length_m']:.1f} m "
                f"(front-end path {summary['path_length_m']:.1f} m); search "
                f"{summary['search_s'] * 1e3:.0f} ms, optimisation "
                f"{summary['optimize_s'] * 1e3:.0f} ms; predicted localization error "
                + (f"{error * 100:.1f} cm" if error is not None else f"withheld: {withheld}")
            )


def _plan_flight(cfg, solm_path, start, goal, flight, out, map_path, as_json) -> None:
    """`lf3pm plan --robot quadrotor`: a flight on an r3yaw SOLM (lf3pm.planner.flight_plan);
    ``flight``: (start height, goal height, planner, attitude rounds)."""
    from lf3pm.atomic import atomic_write
    from lf3pm.flight import Quadrotor
    from lf3pm.map import load_map
    from lf3pm.planner.flight_plan import plan_flight
    from lf3pm.solm import Solm

    start_z, goal_z, planner, attitude_rounds = flight
    if start_z is None or goal_z is None:
        raise Lf3pmError("a quadrotor's plan needs --start-z and --goal-z (m)")
    solm = Solm.open(solm_path)
    source = map_path if map_path is not None else solm.attrs.get("map_source")
    if not source or not Path(str(source)).exists():
        raise Lf3pmError(f"the flight's clearance needs the map: give --map (the SOLM names {source!r})")
    with map_loading() as progress:
        world = load_map(source, progress=progress)
    quad = Quadrotor.from_config(cfg.quadrotor)
    flight = plan_flight(
        solm,
        world,
        (start[0], start[1], start_z, start[2]),
        (goal[0], goal[1], goal_z, goal[2]),
        planner=planner,
        guidance=cfg.guidance,
        quadrotor=quad,
        attitude_rounds=attitude_rounds,
    )
    with atomic_write(out) as fp:
        fp.write(flight.trajectory.csv_bytes(quad))
    summary = flight.summary()
    if as_json:
        print(json.dumps(summary, indent=1))
        return
    worst = max(summary["limits"], key=summary["limits"].get)
    console.print(
        f"{out}: {summary['duration_s']:.1f} s, {summary['trajectory_length_m']:.1f} m (front-end path "
        f"{summary['path_length_m']:.1f} m); search {summary['search_s'] * 1e3:.0f} ms, optimisation "
        f"{summary['optimize_s'] * 1e3:.0f} ms; closest to its limit: {worst} at "
        f"{summary['limits'][worst]:.0%}",
        highlight=False,
    )
    for k, r in enumerate(summary["attitude_rounds"], 1):
        console.print(
            f"attitude round {k}: the guidance at the flown attitude over level, median {r['ratio_median']:.3f} "
            f"over {r['samples']} samples; {r['changed_over_10_percent']:.0%} changed by more than 10 %",
            highlight=False,
        )
