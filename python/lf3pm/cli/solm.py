"""`lf3pm solm build|view|export`: Static Observation Loss Maps."""

from __future__ import annotations

from pathlib import Path

import typer

from lf3pm.cli._common import (
    CONFIG_OPTION,
    app,
    check_output,
    configure,
    console,
    err_console,
    map_loading,
    option,
    progress_bar,
    section_paths,
    user_errors,
)

solm_app = typer.Typer(help="Static Observation Loss Maps: build, view, export.", no_args_is_help=True)
app.add_typer(solm_app, name="solm")


@solm_app.command("build")
def solm_build(
    map_path: Path = typer.Argument(..., metavar="MAP", help="Point-cloud map."),
    out: Path = typer.Option(..., "-o", "--out", help="Output Zarr store (resumed if it exists)."),
    config: Path | None = CONFIG_OPTION,
    sensor: str | None = option("sensor"),
    space: str | None = option("solm.space"),
    res: float | None = option("solm.res"),
    yaw_bins: int | None = option("solm.yaw_bins"),
    yaw_reuse: bool | None = option("solm.yaw_reuse", "--yaw-reuse/--no-yaw-reuse"),
    ray_stride: int | None = option("solm.ray_stride"),
    height: float | None = option("solm.height"),
    bounds: tuple[float, float, float, float] | None = option("solm.bounds"),
    robot_radius: float | None = option("solm.robot_radius"),
    seed: int | None = option("scan.seed"),
    noise: float | None = option("scan.noise"),
    threads: int | None = option("scan.threads"),
    max_cells: int | None = option("solm.max_cells"),
    mount: str | None = option("quadrotor.mount"),
    engine: str = typer.Option(
        "local", help="local (this machine, --threads) or ray (one task per tile on a Ray cluster; docs/scale.md)."
    ),
    address: str | None = typer.Option(
        None,
        metavar="HOST:PORT",
        help="The Ray cluster's head (`ray start --head`; default: a local cluster on this machine's cores).",
    ),
    crop: bool = typer.Option(
        False, help="local: build each tile on its own crop of the map (exact; the ray engine always does)."
    ),
    crop_above: int | None = option("solm.crop_above"),
    calibration: str | None = option(
        "prediction.calibration",
        metavar="FIT.json",
        help="A localization-error fit from `lf3pm audit --calibrate`, stored with the SOLM for the error "
        "that plans and the viewer predict on it (default: the packaged fit).",
    ),
):
    """Evaluate the metric over a grid and store it (chunked Zarr, resumable)."""
    with user_errors():
        paths = {
            "sensor": "sensor",
            "calibration": "prediction.calibration",
            **section_paths("scan", "seed", "noise", "threads"),
            **section_paths("quadrotor", "mount"),
            **section_paths(
                "solm",
                "space",
                "res",
                "yaw_bins",
                "yaw_reuse",
                "ray_stride",
                "height",
                "bounds",
                "robot_radius",
                "max_cells",
                "crop_above",
            ),
        }
        cfg = configure(config, locals(), paths)
        check_output(out, folder=True)
        from lf3pm.map import load_map_points
        from lf3pm.sensors import get_sensor
        from lf3pm.solm import build_solm, make_grid

        lidar = get_sensor(cfg.sensor)
        with map_loading() as progress:
            world = load_map_points(map_path, cfg.map, threads=cfg.scan.threads, progress=progress)
            grid = make_grid(world, config=cfg.solm)
            if engine == "local" and not crop and world.size <= cfg.solm.crop_above:
                progress(f"indexing {world.size:,} points of {map_path}")
                world = world.indexed(cfg.scan.threads)  # what build_solm would do, here with its line
        with progress_bar() as step:

            def advance(cells, total):
                step(f"SOLM {grid.space} {grid.shape} cells", total, cells)

            result = build_solm(
                world, lidar, grid, out, cfg, crop=crop, engine=engine, address=address, progress=advance
            )
        if result["on_crops"] and engine == "local" and not crop:
            err_console.print(
                f"{map_path}: {world.size:,} points, more than --crop-above "
                f"{cfg.solm.crop_above:,}: built tile by tile on crops",
                highlight=False,
            )
        console.print(
            f"{out}: {grid.space} grid {grid.shape} at {grid.res} m; tiles built now "
            f"{result['built_now']} of {result['tiles']}; complete: {result['complete']}"
        )


@solm_app.command("view")
def solm_view(
    store: Path = typer.Argument(..., metavar="OUT.zarr"),
    png: Path = typer.Option(..., "-o", "--out", help="PNG to write."),
    channel: str = typer.Option("q_n", help="Channel to draw."),
    reduce: str = typer.Option("mean", help="min, mean or max over yaw bins / z levels."),
    map_path: Path | None = typer.Option(None, "--map", help="Draw this map's top view under it."),
):
    """Heat map of a SOLM channel over the map's top view."""
    with user_errors():
        from lf3pm.io import load_points
        from lf3pm.solm import Solm
        from lf3pm.solm.figures import heat_map

        check_output(png)
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

        check_output(folder, folder=True, parents=True)
        written = export_ros(Solm.open(store), folder, reduce=reduce)
        console.print(f"wrote {len(written)} files to {folder}")
