"""What the LIO benches read of a finished benefit study (``lf3pm experiment benefit
-o DIR``): its maps by name and its plan CSVs, each missing one a one-line exit."""

from __future__ import annotations

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
