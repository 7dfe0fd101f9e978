"""What every command shares: the app, the consoles, one-line errors, options that read
their defaults from lf3pm.config, and the progress bar."""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

import typer
from rich.console import Console

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
