"""The ``lf3pm`` command line: one module per command or command group, each a few
lines over the library (lf3pm.__main__ runs :func:`main` behind the core check)."""

import sys

from lf3pm.cli import (  # noqa: F401  (they register their commands)
    audit,
    evaluate,
    experiment,
    experiment_flight,
    info,
    plan,
    replay,
    run,
    sensors,
    solm,
    view,
)
from lf3pm.cli._common import app, print_error


def main() -> None:
    """The CLI. A command line click cannot parse (an unknown command or option, a value
    of the wrong type) is one line and exit 2, as every other bad input is, not click's
    usage box."""
    import typer

    command = typer.main.get_command(app)
    try:
        code = command.main(prog_name="lf3pm", standalone_mode=False)
    except typer.Abort:  # Ctrl-C at a prompt
        sys.exit(130)
    except typer.TyperException as err:  # typer's own click's ClickException, UsageError, ...
        where = err.ctx.command_path if getattr(err, "ctx", None) is not None else "lf3pm"
        print_error(f"{err.format_message()} (`{where} --help` lists what it takes)")
        sys.exit(getattr(err, "exit_code", 2))
    sys.exit(code if isinstance(code, int) else 0)


__all__ = ["app", "main"]
