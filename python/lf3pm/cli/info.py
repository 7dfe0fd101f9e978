"""`lf3pm config`, `info` and `scene`: parameters, maps, scenes."""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.table import Table

from lf3pm.cli._common import app, check_output, configure, console, map_loading, option, user_errors
from lf3pm.config import load_config
from lf3pm.errors import Lf3pmError


@app.command("config")
def show_config(
    config: Path | None = typer.Option(
        None, "--config", metavar="FILE.yaml", help="Show this file's parameters merged with the defaults."
    ),
):
    """Print every parameter and its value (the defaults, or FILE.yaml's) as YAML for --config."""
    with user_errors():
        from lf3pm.config import to_yaml
        from lf3pm.replays import registry

        loaded = load_config(config)
        registry.check_name(loaded.replay.odometry)  # a plugin's name too (an entry point)
        # Every registered odometry's settings (a plugin's too), the file's over lf3pm's.
        print(to_yaml(registry.with_settings(loaded, config)), end="")


@app.command()
def info(
    map_path: Path = typer.Argument(..., metavar="MAP"),
    map_voxel: float | None = option("map.voxel"),
):
    """Load and index a map; print its size, extent and index statistics."""
    with user_errors():
        from lf3pm.map import load_map

        settings = configure(None, locals(), {"map_voxel": "map.voxel"}).map
        with map_loading() as progress:
            world = load_map(map_path, settings, progress=progress)
        console.print_json(json.dumps(world.describe()))


@app.command()
def scene(
    name: str | None = typer.Argument(None, metavar="NAME", help="Scene name (see --list)."),
    output: Path | None = typer.Option(
        None, "-o", "--output", metavar="MAP.pcd", help="Map file to write (format by suffix; .pcd is binary)."
    ),
    seed: int | None = option("scene.seed"),
    list_scenes: bool = typer.Option(False, "--list", help="List the scenes and exit."),
):
    """Build a procedural test scene (houses, meadow, gobi, ...) and write it as a map."""
    with user_errors():
        seed = configure(None, locals(), {"seed": "scene.seed"}).scene.seed
        from lf3pm.scenes import VOLUME_CLEARANCE, build_scene, describe_scenes, scene_defaults, scene_names

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
            raise Lf3pmError(
                f"{output}: unknown suffix {output.suffix or '(none)'}; supported: {' '.join(SUPPORTED_SUFFIXES)}"
            )
        check_output(output)
        built = build_scene(name, seed=seed)
        write_points(output, built.points)
        x, y, z, yaw = built.reference_pose
        console.print(f"{built.name}: {built.size:,} points (seed {seed}) -> {output}", highlight=False)
        console.print(
            f"reference pose x y z yaw: {x:g} {y:g} {z:g} {yaw:g}  (free radius {built.free_radius:g} m)",
            highlight=False,
        )
        for key, box in built.volumes.items():
            console.print(
                f"{key} volume x y z: {box.xmin:g}..{box.xmax:g} {box.ymin:g}..{box.ymax:g} "
                f"{box.zmin:g}..{box.zmax:g}  (no map point within {VOLUME_CLEARANCE:g} m)",
                highlight=False,
            )
