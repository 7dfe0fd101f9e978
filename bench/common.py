"""What several benchmarks share: the `boxes` scene's SOLM, built in a folder; the maps a
`--maps` option chose."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path


def build_boxes_solm(folder: Path) -> Path:
    """The `boxes` scene's SOLM (r2, 0.5 m cells, VLP-16, ray stride 4), as tests/test_plan.py
    builds it, in ``folder``; about a minute on 2 cores. Returns the store's path."""
    folder = Path(folder)
    for args in (
        ["scene", "boxes", "-o", folder / "boxes.pcd"],
        ["solm", "build", folder / "boxes.pcd", "-o", folder / "boxes.zarr", "--res", "0.5", "--ray-stride", "4"],
    ):
        subprocess.run([sys.executable, "-m", "lf3pm.cli", *map(str, args)], check=True, capture_output=True)
    return folder / "boxes.zarr"


def chosen_maps(parser, given: str, known) -> list[str]:
    """The comma-separated map names of ``given``, each one of ``known`` (else the parser's
    one-line error)."""
    chosen = given.split(",")
    unknown = [m for m in chosen if m not in known]
    if unknown:
        parser.error(f"unknown map(s) {', '.join(unknown)}; known: {', '.join(known)}")
    return chosen
