"""Many replays of planned trajectories, in worker processes, each saved as it ends.

A task is a :class:`ReplayTask`. A worker loads each
map (and prepares it for registration) once; a replay's summary is written
atomically to its JSON path, so an interrupted experiment resumes by skipping
the tasks whose JSON exists. Workers use the spawn start method: small_gicp,
the simulator and the LIO's own child process use threads, and forking after
OpenMP hangs (shared BUILD-NOTES).
"""

from __future__ import annotations

import glob
import json
import re
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path
from typing import NamedTuple

import numpy as np

from lf3pm.atomic import atomic_write
from lf3pm.errors import Lf3pmError
from lf3pm.experiments.map_cases import load_case_map

#: The version of the replay records replay_task writes ("schema" in each); load_replay
#: refuses another. 2: the first with a schema (records of lf3pm before it have none).
SCHEMA = 2


class ReplayRecordError(Lf3pmError):
    """A cached replay record written by another schema."""


class ReplayTask(NamedTuple):
    """One replay of an experiment: the plan's CSV on the case's map by ``method`` with
    ``seed``, its JSON written to ``path``; ``options``: further replay arguments (the
    LIO's odometry)."""

    case: object
    csv: str
    method: str
    seed: int
    path: Path
    options: dict = {}


def replay_json(replays: Path, prefix: str, method: str, seed: int) -> Path:
    """Where an experiment keeps one replay (replay_task's JSON) of the plan that
    ``prefix`` names in the folder ``replays``."""
    return replays / f"{prefix}{method}_{seed}.json"


def write_plan(trajectory, csv: Path, replays: Path, prefix: str) -> None:
    """Writes ``trajectory`` to ``csv``. Where another plan was written there before (a
    changed default, planner or map), first deletes the replays made of it (their
    :func:`replay_json` paths): an experiment resumes by skipping replays that exist,
    and must never score an old plan's replay as the new one's."""
    data = trajectory.csv_bytes()
    if csv.exists() and csv.read_bytes() != data:
        stale = re.compile(re.escape(prefix) + r"[a-z]+(?:-[\w.]+)?_\d+\.json")  # method[-odometry]_seed
        for path in replays.glob(f"{glob.escape(prefix)}*.json"):
            if stale.fullmatch(path.name):
                path.unlink()
    csv.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(csv) as fp:
        fp.write(data)


def run_replays(tasks: list, workers: int, step) -> None:
    """Runs the tasks whose JSON is missing, ``workers`` at a time, calling
    step(label, total, advance=1, restart=False) as they end. A JSON of another schema
    (SCHEMA) is refused in one line (load_replay) before any replay runs."""
    for task in tasks:
        if task.path.exists():
            load_replay(task.path)
    todo = [(replay_task, t) for t in tasks if not t.path.exists()]
    label = f"replays ({len(tasks) - len(todo)} of {len(tasks)} done before)"
    step(label, len(todo), 0, restart=True)
    if not todo:
        return
    if workers == 1:
        for job in todo:
            _run(job)
            step(label, len(todo))
        return
    # Spawned workers start with Python's warning format (file:line, source line): the
    # study's own is one line (lf3pm.errors.one_line_warning).
    with ProcessPoolExecutor(
        max_workers=workers, mp_context=get_context("spawn"), initializer=_one_line_warnings
    ) as pool:
        for _ in pool.map(_run, todo):
            step(label, len(todo))


def _one_line_warnings() -> None:
    import warnings

    from lf3pm.errors import one_line_warning

    warnings.formatwarning = one_line_warning


def _run(job) -> None:
    function, task = job
    function(task)


def load_replay(path) -> dict:
    """A finished replay's summary (replay_task's JSON); ReplayRecordError for one written
    by another schema (an older lf3pm's: delete it to replay it again)."""
    record = json.loads(open(path, encoding="utf-8").read())
    schema = record.get("schema") if isinstance(record, dict) else None
    if schema != SCHEMA:
        raise ReplayRecordError(
            f"{path}: a replay record of schema {schema if schema is not None else 'none (before schemas)'}, "
            f"not {SCHEMA}: delete it (or its folder) to replay it with this lf3pm"
        )
    return record


def replay_summary(runs: list) -> dict:
    """One plan's replays (load_replay records, one per seed): the median APE rmse over
    seeds, each seed's, and the median share of degenerate scans; for LIO replays
    whether each seed's rest was steady (replay_result.rest_motion)."""
    apes = [r["ape_rmse"] for r in runs]
    out = {
        "ape": float(np.median(apes)),
        "ape_per_seed": apes,
        "degenerate_share": float(np.median([r["degenerate_share"] for r in runs])),
    }
    if all("rest" in r for r in runs):  # the LIO's: was the odometry still while the sensor was?
        out["rest_steady_per_seed"] = [bool(r["rest"]["steady"]) for r in runs]
    return out


_MAPS: dict = {}  # per process: case name -> (Map, registration target)


def replay_task(task) -> None:
    """One replay: APE (rmse, median, max), scans, the share of degenerate scans,
    seconds, and once per second the error and the true and estimated positions,
    written atomically as JSON."""
    from lf3pm.replays.replay import replay

    case, csv, method, seed, path, options = task
    world, target = _case_map(case)
    result = replay(world, csv, case.sensor, method, seed, target=target, threads=1, **options)
    errors = np.asarray(result.errors)
    every = max(1, int(round(result.params["rate"])))
    record = {
        "schema": SCHEMA,
        "ape_rmse": result.ape["rmse"],
        "ape_median": result.ape["median"],
        "ape_max": result.ape["max"],
        "scans": result.scans,
        "degenerate_share": float(np.mean(result.degenerate)),
        "seconds": float(sum(result.seconds_per_scan.values()) * result.scans),
        "times_every_second": (result.times[::every] - result.times[0]).tolist(),
        "errors_every_second": errors[::every].tolist(),
        # the paths too, for `lf3pm view --replay`
        "truth_xyz_every_second": result.truth[::every, :3, 3].tolist(),
        "estimate_xyz_every_second": result.estimate[::every, :3, 3].tolist(),
    }
    if result.rest:
        record["rest"] = result.rest
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path) as fp:
        fp.write(json.dumps(record).encode())


def _case_map(case):
    """The case's (Map, registration target), loaded once per process."""
    from lf3pm.validation.mde import RegistrationTarget

    if case.name not in _MAPS:
        world, _ = load_case_map(case)
        _MAPS[case.name] = (world, RegistrationTarget(world, threads=1))
    return _MAPS[case.name]
