"""What the LIO benches read of a finished benefit study (``lf3pm experiment benefit
-o DIR``): its maps by name and its plan CSVs, each missing one a one-line exit."""

from __future__ import annotations

import argparse
from pathlib import Path

from lf3pm.experiments.benefit import CASES


def study_case(name: str):
    """The study's map case called ``name``."""
    case = next((c for c in CASES if c.name == name), None)
    if case is None:
        raise SystemExit(f"unknown map {name!r}; the study's: {', '.join(c.name for c in CASES)}")
    return case


def study_plan(study: Path, map_name: str, plan: str) -> Path:
    """The CSV of plan ``plan`` (e.g. 00_omni_default) on ``map_name`` in ``study``."""
    csv = Path(study) / "trajectories" / map_name / f"{plan}.csv"
    if not csv.is_file():
        raise SystemExit(f"no plan {csv}: run lf3pm experiment benefit -o {study} first")
    return csv


def study_arguments(description: str) -> argparse.ArgumentParser:
    """A parser with the arguments that name one pair of a study's plans: --study,
    --map, --pair (its prefix, e.g. 00_omni) and --guidance (the guided plan's name)."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--study", type=Path, default=Path("out/benefit3"))
    parser.add_argument("--map", default="gobi")
    parser.add_argument("--pair", default="00_omni", help="the pair's prefix, e.g. 00_omni or 03_diff")
    parser.add_argument("--guidance", default="default")
    return parser
