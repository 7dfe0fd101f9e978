"""The ``lf3pm`` command line: one module per command or command group, each a few
lines over the library (lf3pm.__main__ runs :func:`main` behind the core check)."""

from lf3pm.cli import evaluate, experiment, info, plan, replay, solm, view  # noqa: F401  (they register their commands)
from lf3pm.cli._common import app


def main() -> None:
    """The CLI."""
    app()


__all__ = ["app", "main"]
