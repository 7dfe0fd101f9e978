"""``python -m lf3pm.cli``: the CLI."""

from lf3pm.cli import main

main()
