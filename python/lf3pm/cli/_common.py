"""What every command shares: the app, the consoles, one-line errors, options that read
their defaults from lf3pm.config, the progress bar and the line shown while a map loads."""

from __future__ import annotations

import os
import secrets
import stat
import warnings
from contextlib import contextmanager
from pathlib import Path

import typer
from rich.console import Console
from rich.text import Text

from lf3pm.atomic import check_replaceable
from lf3pm.config import DEFAULTS, Config, help_with_default, load_config
from lf3pm.errors import Lf3pmError, one_line, one_line_warning

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="LiDAR perception-aware planning: where will LiDAR localization hold?",
)
# No markup: what the consoles print holds paths, names and values as the user gave them,
# and Rich would take "[red]" in a path or "[nan, 0.0]" in a message for a tag and drop it.
console = Console(markup=False)
err_console = Console(stderr=True, markup=False)


def print_warning(text) -> None:
    """``lf3pm: warning: TEXT`` on stderr, one line, TEXT verbatim."""
    err_console.print(
        Text.assemble(("lf3pm: warning:", "bold yellow"), " ", one_line(text)), highlight=False, soft_wrap=True
    )


@contextmanager
def one_line_warnings():
    """Python warnings (a map's dropped points, an odometry's caveat) printed as one line
    each while the block runs."""
    previous = warnings.formatwarning
    warnings.formatwarning = one_line_warning
    try:
        yield
    finally:
        warnings.formatwarning = previous


@contextmanager
def user_errors():
    """Turns user-input errors into one line on stderr and exit status 2; warnings are
    one line each (:func:`one_line_warnings`)."""
    try:
        with one_line_warnings():
            yield
    except Lf3pmError as err:
        print_error(err)
        raise typer.Exit(2) from None


def print_error(text) -> None:
    """``lf3pm: error: TEXT`` on stderr, one line, TEXT verbatim."""
    err_console.print(
        Text.assemble(("lf3pm: error:", "bold red"), " ", one_line(text)), highlight=False, soft_wrap=True
    )


def check_output(path: Path | None, *, folder: bool = False, parents: bool = False, new: bool = False) -> None:
    """Raises Lf3pmError when ``path`` could not be written, so that a command fails in a
    second, not after its work. A file (the default) is replaced whole: nothing or a
    regular file there, in an existing folder. A ``folder`` is written into: an existing
    folder, or one created in an existing folder (with ``parents``: under the nearest
    existing one). ``new``: nothing may be there yet. A file is created and removed where
    the output would go, so that permissions, a read-only mount and a missing folder are
    all found as they are now. None: no output asked for."""
    if path is None:
        return
    path = Path(path)
    if os.path.lexists(path):
        if new:
            raise Lf3pmError(
                f"{path} exists: lf3pm writes it as a new folder and replaces nothing; remove it or choose another name"
            )
        if folder and not path.is_dir():
            raise Lf3pmError(f"{path}: cannot write into the folder: it is not a folder; choose another name")
        if not folder:
            check_replaceable(path)
        where, failure = (path, "cannot write into the folder") if folder else (path.parent, "cannot write the file")
    else:
        where = path.parent
        while parents and not os.path.lexists(where) and where != where.parent:
            where = where.parent
        failure = f"cannot create the folder (cannot write in {where})" if folder else "cannot write the file"
        if not os.path.lexists(where):
            raise Lf3pmError(f"{path}: {failure}: {where} does not exist; create it first")
        if not where.is_dir():
            raise Lf3pmError(f"{path}: {failure}: {where} is not a folder; choose another place")
    _probe(path, where, failure)


def _probe(path: Path, where: Path, failure: str) -> None:
    """Creates and removes a file in the folder ``where``; Lf3pmError ``path: failure
    (why)`` if it cannot."""
    probe = where / f".lf3pm-probe-{secrets.token_hex(4)}"
    try:
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, stat.S_IRUSR | stat.S_IWUSR))
    except OSError as err:
        raise Lf3pmError(f"{path}: {failure} ({err.strerror or err}): choose a writable place") from None
    os.remove(probe)


def option(path: str, *names: str, help: str | None = None, with_default: bool = True, **kwargs):
    """The option for config parameter ``path`` (lf3pm.config): None unless given, so that
    ``--config FILE.yaml`` and then the default apply; its help is the parameter's
    description (``help``: a command's own text, where the parameter means more there)
    with its default (not ``with_default``: a default derived from other parameters,
    which the description states)."""
    if not with_default:
        section, _, name = path.rpartition(".")
        help = help or type(getattr(DEFAULTS, section) if section else DEFAULTS).model_fields[name].description
    return typer.Option(None, *names, help=help_with_default(path, help) if with_default else help, **kwargs)


CONFIG_OPTION = typer.Option(
    None,
    "--config",
    metavar="FILE.yaml",
    exists=False,
    help="Parameters from a YAML file (config/*.yaml; flags given override it).",
)


def configure(config_file: Path | None, given: dict, paths: dict) -> Config:
    """The command's configuration: ``config_file``, then the options ``given`` (by
    parameter name; None: not given), each at its config path ``paths[name]``."""
    overrides = {paths[name]: value for name, value in given.items() if name in paths}
    flags = {paths[name]: "--" + name.replace("_", "-") for name in paths}
    config = load_config(config_file, overrides, flags)
    if config.prediction.calibration is not None:  # a bad fit file fails now, not after the work
        from lf3pm.calibration import localization_fit

        localization_fit(config.prediction.calibration)
    return config


def section_paths(section: str, *names: str) -> dict:
    """{option: "section.option"} for options named as their config parameters."""
    return {name: f"{section}.{name}" for name in names}


#: Where each option of evaluate and mde lives in the config.
SCAN_PATHS = {
    "sensor": "sensor",
    "seed": "scan.seed",
    "noise": "scan.noise",
    "scan_voxel": "scan.scan_voxel",
    "threads": "scan.threads",
}
MAP_PATHS = {
    "map_voxel": "map.voxel",
    "knn": "map.knn",
    "plane_threshold": "map.plane_threshold",
    "max_neighbor_distance": "map.max_neighbor_distance",
}


@contextmanager
def progress_bar():
    """A rich progress bar on stderr; yields step(label, total, advance=1, restart=False)
    (restart: a new phase, counted from zero). The bar appears at the first step, so that
    an error before any work is its one line alone."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    # The label holds paths (`writing OUT.bag`): shown as text, not markup.
    bar = Progress(
        TextColumn("{task.description}", style="progress.description", markup=False),
        BarColumn(),
        "{task.completed}/{task.total}",
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=err_console,
    )
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


@contextmanager
def map_loading():
    """Yields the ``progress`` callback of lf3pm.map.load_map (and load_map_points): on a
    terminal, a line on stderr with a spinner, the phase (reading the file, indexing its
    points) and the time elapsed, erased when the block ends so that an error after it is
    its one line alone; nothing elsewhere."""
    if not err_console.is_terminal:  # a stopped Progress still ends its (empty) line there
        yield lambda text: None
        return
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    line = Progress(
        SpinnerColumn(),
        TextColumn("{task.description}", markup=False),
        TimeElapsedColumn(),
        console=err_console,
        transient=True,
    )
    task = None

    def phase(text):
        nonlocal task
        if task is None:
            line.start()
            task = line.add_task(text, total=None)
        else:
            line.update(task, description=text, refresh=True)  # now: a phase may end before the next tick

    try:
        yield phase
    finally:
        if task is not None:
            line.stop()
