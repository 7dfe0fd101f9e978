"""The ``lf3pm`` command (and ``python -m lf3pm``): the CLI, behind a check that the
compiled core loads, so that a core that cannot run here is one line, not a traceback."""

import sys

from lf3pm.errors import CoreLevelError


def main() -> None:
    """Console-script entry point."""
    try:
        from lf3pm.cli import main as cli
    except CoreLevelError as err:
        print(f"lf3pm: error: {err}", file=sys.stderr)
        sys.exit(2)
    cli()


if __name__ == "__main__":
    main()
