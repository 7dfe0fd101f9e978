"""Running the flight study (lf3pm.experiments.flight.protocol): per map, its r3yaw SOLM,
its pairs, the three planners' flights, which pairs are at risk (from plan (a) and the SOLM
alone), then every replay. Everything lands in the output folder as it is made (SOLMs,
``plans.jsonl``, ``replays.jsonl``), each record written whole, so an interrupted run
resumes where it stopped and a finished one re-reads its records."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

import lf3pm
from lf3pm.errors import Lf3pmError
from lf3pm.experiments.flight.protocol import FlightMap, FlightProtocol
from lf3pm.flight import Quadrotor
from lf3pm.planner.flight_plan import FlightPlanner, FlightTrajectory
from lf3pm.scenes import build_scene

#: The planners by their study letters (docs/flight.md).
LETTERS = dict(zip(("velocity_yaw", "yaw_only", "joint"), "abc"))


def map_grid(world, case: FlightMap, yaw_bins: int):
    """The r3yaw grid of ``case`` over ``world``."""
    from lf3pm.scenes import scene_volumes
    from lf3pm.solm import make_grid

    if case.bounds is not None:
        bounds = case.bounds
    else:
        boxes = list(scene_volumes(case.scene).values())
        bounds = (
            min(b.xmin for b in boxes) - case.margin,
            min(b.ymin for b in boxes) - case.margin,
            max(b.xmax for b in boxes) + case.margin,
            max(b.ymax for b in boxes) + case.margin,
        )
    levels = tuple(np.arange(case.z_min, case.z_max + 1e-9, case.level_step))
    return make_grid(world, "r3yaw", case.res, bounds=bounds, yaw_bins=yaw_bins, z_levels=levels)


def pairs_of(case: FlightMap, seed: int) -> list[tuple]:
    """``case.pairs`` (start, goal) pairs: start (x, y, z, yaw) in the start volume, goal
    (x, y, z) in the goal volume, every second pair the other way round; seeded."""
    from lf3pm.scenes import scene_volumes

    volumes = scene_volumes(case.scene)
    if not {"start", "goal"} <= set(volumes):
        raise Lf3pmError(f"scene {case.scene!r} has no start and goal volumes: not a flight scene")
    rng = np.random.default_rng([seed, sum(map(ord, case.scene))])
    out = []
    for k in range(case.pairs):
        a, b = (volumes["start"], volumes["goal"]) if k % 2 == 0 else (volumes["goal"], volumes["start"])
        p = [rng.uniform(lo, hi) for lo, hi in ((a.xmin, a.xmax), (a.ymin, a.ymax), (a.zmin, a.zmax))]
        q = [rng.uniform(lo, hi) for lo, hi in ((b.xmin, b.xmax), (b.ymin, b.ymax), (b.zmin, b.zmax))]
        out.append(((*p, float(math.atan2(q[1] - p[1], q[0] - p[0]))), tuple(q)))
    return out


def at_risk(solm, trajectory: FlightTrajectory, rule) -> tuple[bool, float]:
    """Whether a pair is at risk from its plan (a) on its SOLM (module docstring of the
    protocol): (at risk, the share of the plan's poses at risk)."""
    s = trajectory.sample(rule.rate)
    g = solm.grid_spec
    k, iy, ix = g.cell(s["position"][:, 0], s["position"][:, 1], s["position"][:, 2], yaw=s["yaw"])
    q = solm.channel("q_n")[k, iy, ix]
    degenerate = solm.channel("degenerate")[k, iy, ix].astype(bool)
    best, _ = solm.over_yaw("q_n")
    median = float(np.nanmedian(best))
    risky = degenerate | (np.nan_to_num(q, nan=np.inf) >= rule.factor * median)
    share = float(np.mean(risky))
    return share >= rule.share, share


def report_folder(out) -> tuple[dict, list[Path]]:
    """Analyses a study folder again from its frozen protocol and records alone (what
    `lf3pm experiment flight --report-only` does) and writes its report; returns the
    summary and the paths written."""
    from lf3pm.experiments.flight.analysis import analyse, write_report

    out = Path(out)
    frozen = out / "protocol.json"
    if not frozen.is_file():
        raise Lf3pmError(f"{out} holds no flight study (no protocol.json)")
    try:
        protocol = FlightProtocol.model_validate(json.loads(frozen.read_text()))
        records = [_records(out / name) for name in ("plans.jsonl", "replays.jsonl")]
    except ValueError as err:  # JSON or the protocol's validation
        first = str(err).splitlines()[0]
        raise Lf3pmError(f"{out}: unreadable study records or protocol ({first})") from None
    summary = analyse(*records, protocol)
    return summary, write_report(summary, out)


def code_version() -> str:
    """The git commit of the lf3pm checkout that runs (``-dirty`` with uncommitted changes),
    or the package's version outside a checkout."""
    import subprocess

    try:
        done = subprocess.run(
            ["git", "-C", str(Path(lf3pm.__file__).parent), "describe", "--always", "--dirty", "--abbrev=12"],
            capture_output=True,
            text=True,
            timeout=10,
        )
    except (OSError, subprocess.SubprocessError):
        done = None
    return done.stdout.strip() if done is not None and done.returncode == 0 else f"lf3pm {lf3pm.__version__}"


def _now() -> str:
    from datetime import datetime, timezone

    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def _records(path: Path) -> list[dict]:
    """The records of a .jsonl file; a last line without its newline (cut by a crash while
    it was written) is not a record."""
    if not path.exists():
        return []
    lines = path.read_text().split("\n")[:-1]  # the fragment after the last newline dropped
    return [json.loads(line) for line in lines if line.strip()]


def _heal(path: Path) -> None:
    """Cuts off a line a crash left unfinished, so that records appended after it stay
    readable."""
    if path.exists():
        data = path.read_bytes()
        if data and not data.endswith(b"\n"):
            path.write_bytes(data[: data.rfind(b"\n") + 1])


def _append(path: Path, record: dict) -> None:
    """One record as one line, written whole (a crash leaves the earlier lines intact)."""
    with open(path, "a") as fp:
        fp.write(json.dumps(record) + "\n")
        fp.flush()


def run_study(out, protocol: FlightProtocol, *, progress=None) -> dict:
    """Runs (or resumes) ``protocol`` into the folder ``out`` and returns its analysis
    (lf3pm.experiments.flight.analysis.analyse). ``progress(stage, done, total)``."""
    from lf3pm.experiments.flight.analysis import analyse
    from lf3pm.flight.mounts import MOUNTS
    from lf3pm.replays.flight_motion import FlightMotion
    from lf3pm.solm import Solm, build_solm

    out = Path(out)
    (out / "solm").mkdir(parents=True, exist_ok=True)
    frozen = out / "protocol.json"
    if frozen.exists():
        # Read back through the protocol's type: a field added since, at its default, is
        # the same protocol.
        try:
            earlier = FlightProtocol.model_validate(json.loads(frozen.read_text()))
        except ValueError:
            raise Lf3pmError(f"{frozen} is not a flight protocol; choose another folder") from None
        if earlier.model_dump(mode="json") != protocol.model_dump(mode="json"):
            raise Lf3pmError(f"{out} holds a run of another protocol ({frozen}); choose another folder")
    else:
        frozen.write_text(json.dumps(protocol.model_dump(mode="json"), indent=1))
    # Which code ran (or resumed) the study, one line per start.
    _append(out / "runs.jsonl", {"started_utc": _now(), "code": code_version()})
    if protocol.mount not in MOUNTS:
        raise Lf3pmError(f"unknown mount {protocol.mount!r}; use one of {', '.join(MOUNTS)}")
    quad = Quadrotor(mount=protocol.mount)
    plans_path, replays_path = out / "plans.jsonl", out / "replays.jsonl"
    for path in (plans_path, replays_path):
        _heal(path)
    plans = {(r["map"], r["pair"], r["planner"]): r for r in _records(plans_path)}
    replays = {(r["map"], r["pair"], r["planner"], r["odometry"], r["seed"]) for r in _records(replays_path)}
    for case in protocol.maps:
        scene = build_scene(case.scene)
        world = lf3pm.load_map(scene.points, threads=protocol.threads)
        store = out / "solm" / f"{case.scene}.zarr"
        build_solm(
            world,
            protocol.sensor,
            map_grid(world, case, protocol.yaw_bins),
            store,
            mount=protocol.mount,
            ray_stride=protocol.ray_stride,
            threads=protocol.threads,
            progress=(lambda d, t, c=case.scene: progress(f"SOLM {c}", d, t)) if progress else None,
        )
        solm = Solm.open(store)
        planner = FlightPlanner(solm, world, quadrotor=quad, threads=protocol.threads)
        for k, (start, goal) in enumerate(pairs_of(case, protocol.pair_seed)):
            for name in LETTERS:
                key = (case.scene, k, name)
                if key not in plans:
                    record = {"map": case.scene, "pair": k, "planner": name, "start": start, "goal": goal}
                    try:
                        rounds = protocol.attitude_rounds if name == "joint" else 0
                        plan = planner.plan(start, goal, planner=name, attitude_rounds=rounds)
                    except Lf3pmError as err:
                        record["error"] = str(err)
                    else:
                        record |= plan.summary()
                        record["coefficients"] = plan.trajectory.coefficients.tolist()
                        record["durations"] = plan.trajectory.durations.tolist()
                        if name == "velocity_yaw":
                            record["at_risk"], record["risk_share"] = at_risk(solm, plan.trajectory, protocol.risk)
                    _append(plans_path, record)
                    plans[key] = record
            if progress:
                progress(f"plans {case.scene}", k + 1, case.pairs)
        total = case.pairs * 3 * len(protocol.odometries) * protocol.seeds
        done = 0
        for k in range(case.pairs):
            for name in LETTERS:
                plan = plans[(case.scene, k, name)]
                for odometry in protocol.odometries:
                    for seed in range(protocol.seeds):
                        done += 1
                        key = (case.scene, k, name, odometry, seed)
                        if key in replays or "error" in plan:
                            continue
                        record = {"map": case.scene, "pair": k, "planner": name, "odometry": odometry, "seed": seed}
                        motion = FlightMotion.from_pieces(
                            np.asarray(plan["coefficients"]), np.asarray(plan["durations"]), quadrotor=quad
                        )
                        try:
                            result = lf3pm.replay(
                                world,
                                motion,
                                protocol.sensor,
                                "lio",
                                seed=seed,
                                odometry=odometry,
                                threads=protocol.threads,
                            )
                        except Lf3pmError as err:
                            record["error"] = str(err)
                        else:
                            record |= {"ape_m": result.ape["rmse"], "lost": len(result.report.get("lost", []))}
                        _append(replays_path, record)
                        replays.add(key)
                        if progress:
                            progress(f"replays {case.scene}", done, total)
    return analyse(_records(plans_path), _records(replays_path), protocol)
