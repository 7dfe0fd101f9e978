"""What a run of the study may take from another study folder, made under another protocol.

A sensitivity analysis runs a variant of a frozen protocol (one setting changed,
config/benefit_protocol_variants/); most of its maps, plans and replays are then the
frozen run's. ``lf3pm experiment benefit --frozen V -o OUT --reuse DIR`` links into OUT
what DIR holds and V would compute the same way, case by case:

- the SOLM, where the case (content and place in the list: its pairs' seed) and lf3pm's
  defaults (SOLM, scan, planner, robot) are the same;
- beyond that, where the pair seed and the guidance are the same too, the plans'
  trajectories and each replay whose settings are the same: map localization's
  (``replay`` and ``localization`` sections), the LIO's (its odometry on that map, that
  odometry's settings and version, the replay section and the rest limits), and the
  localization-error fit's predictors (its sampling);

never a replay made under other settings. The run then plans again: a plan that comes
out otherwise replaces its trajectory and drops the replays linked for it
(replay_tasks.write_plan), so a linked replay is only ever scored for the plan it was
made of. Files are hard links (SOLM stores copies): the source is never changed.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from lf3pm.experiments.benefit.protocol import Protocol, read_protocol
from lf3pm.experiments.benefit.records import LIO, LOCALIZATION, StudyFolder


def reusable(theirs: Protocol, ours: Protocol) -> dict[str, set[str]]:
    """Per case of ``ours``: what it may take from a folder run under ``theirs``: any of
    "solm", "plans", LOCALIZATION, LIO, "predictors" (the module's docstring)."""
    if theirs.defaults != ours.defaults:  # the SOLMs and plans of every case are made otherwise
        return {}
    theirs_cases = {c["name"]: (i, c) for i, c in enumerate(theirs.model_dump(mode="json")["cases"])}
    ours_dump = ours.model_dump(mode="json")
    same_plans = (theirs.pair_seed, theirs.guidance) == (ours.pair_seed, ours.guidance)
    same_replay = theirs.replay == ours.replay
    out = {}
    for index, case in enumerate(ours_dump["cases"]):
        name = case["name"]
        if theirs_cases.get(name) != (index, case):
            continue
        parts = {"solm"}
        if same_plans:
            parts.add("plans")
            if same_replay and theirs.localization == ours.localization:
                parts.add(LOCALIZATION)
            if same_replay and _same_lio(theirs, ours, name):
                parts.add(LIO)
            if theirs.localization_fit == ours.localization_fit:
                parts.add("predictors")
        out[name] = parts
    return out


def _same_lio(theirs: Protocol, ours: Protocol, case: str) -> bool:
    """Whether the LIO replays ``case`` the same way under both protocols."""
    a, b = theirs.lio, ours.lio
    odometry = b.chosen.get(case)
    if odometry is None or a.chosen.get(case) != odometry:
        return False
    same = (a.rest_window, a.rest_speed_limit) == (b.rest_window, b.rest_speed_limit)
    return same and all(getattr(a, k).get(odometry) == getattr(b, k).get(odometry) for k in ("settings", "versions"))


def link_reusable(source: Path, ours: Protocol, folder: StudyFolder, lio_labels: dict[str, str]) -> dict[str, set[str]]:
    """Links into ``folder`` what the study folder ``source`` holds that a run under
    ``ours`` may take (:func:`reusable`; ``lio_labels``: each case's LIO replay label),
    leaving whatever ``folder`` holds already. Returns what was taken, per case.
    Raises ProtocolError (via read_protocol) when ``source`` has no readable protocol."""
    theirs_folder = StudyFolder(Path(source))
    theirs = read_protocol(theirs_folder.root / "protocol.yaml")
    taken = reusable(theirs, ours)
    for case, parts in taken.items():
        if "solm" in parts:  # copied, not linked: a store that resumes writes into its files
            _link_tree(theirs_folder.solm(case), folder.solm(case), copy=True)
        if "plans" in parts:
            _link_tree(theirs_folder.trajectories(case), folder.trajectories(case))
        labels = [label for part, label in ((LOCALIZATION, LOCALIZATION), (LIO, lio_labels[case])) if part in parts]
        replays = theirs_folder.replays(case)
        for label in labels:
            for path in replays.glob(f"*_{label}_*.json") if replays.is_dir() else ():
                _link(path, folder.replays(case) / path.name)
        if "predictors" in parts:
            _link_tree(theirs_folder.root / "predictors" / case, folder.root / "predictors" / case)
    return taken


def _link_tree(source: Path, target: Path, copy: bool = False) -> None:
    """Links (or copies) every file under ``source`` to the same place under ``target``
    (none that exists)."""
    if not source.is_dir():
        return
    for path in sorted(source.rglob("*")):
        if path.is_file():
            _link(path, target / path.relative_to(source), copy)


def _link(source: Path, target: Path, copy: bool = False) -> None:
    """A hard link ``target`` to ``source`` (a copy across file systems, or with ``copy``)."""
    if target.exists():
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    if copy:
        shutil.copy2(source, target)
        return
    try:
        os.link(source, target)
    except OSError:
        shutil.copy2(source, target)
