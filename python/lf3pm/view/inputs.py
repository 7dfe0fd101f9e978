"""What ``lf3pm view`` is given, read and checked before anything is served: the map, a
SOLM of that map, planned trajectories, flights, replays, a recorded run and its audit,
and a free port. Every problem is one Lf3pmError line. A recorded run's scans are read later, one at
a time, when the page shows one (:func:`read_scan`)."""

from __future__ import annotations

import errno
import json
import math
import numbers
import os
import socket
import stat
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lf3pm.config import DEFAULTS, RunConfig
from lf3pm.errors import Lf3pmError, RunError
from lf3pm.map import Map, load_map
from lf3pm.runs import Run, Scan
from lf3pm.solm import Solm
from lf3pm.trajectory.trajectory import read_csv
from lf3pm.view.layers import flight_samples, replay_tracks

#: The largest replay JSON read (bytes): a long LIO replay with its per-scan positions is
#: a few MB; a device or a runaway file is refused before it is read.
MAX_REPLAY_BYTES = 256 * 2**20
#: The largest audit JSON read (bytes): a scan's record is about 2 kB, so this is over
#: 100,000 audited scans.
MAX_AUDIT_BYTES = 256 * 2**20
#: The fields of an audit's scan record the viewer reads as numbers (null: not computed;
#: a field missing, as in an audit written before it existed, is not computed either).
AUDIT_NUMBERS = (
    "error_m",
    "error_max_m",
    "spread_m",
    "tracking_error_m",
    "predicted_error_m",
    "predicted_error_lo_m",
    "predicted_error_hi_m",
    "real_q_n",
    "sim_q_n",
    "q_n_ratio",
)
#: The fields of a scan record that say, in one line, why a part was not computed.
AUDIT_REASONS = ("predicted_error_withheld", "registration_error", "sim_error")
#: The columns of a flight CSV the viewer reads (`lf3pm plan --robot quadrotor` writes
#: them among others): time, the body's position and yaw, its attitude (body to world).
FLIGHT_COLUMNS = ("t", "x", "y", "z", "yaw", "qw", "qx", "qy", "qz")
#: How far from 1 a flight CSV's quaternion's norm may be (its 17 written digits are far nearer).
QUATERNION_TOLERANCE = 1e-3


@dataclass
class RunInputs:
    """A recorded run and its audit, as the viewer draws them.

    ``path``: the run whose scans are shown, read with the run section ``config``; None
    where only an audit was given and the run it names is not found (``unreadable`` says
    so, in one line). ``path_xyz``: (K, 3) the LiDAR's positions along the run's reference
    poses (world-from-body times the extrinsic), or along the audited scans' poses without
    the run. ``records``: the audit's per-scan records in its order (``index``, ``name``,
    ``stamp``, ``pose`` a 4 x 4 array, AUDIT_NUMBERS as floats, NaN where not computed,
    AUDIT_REASONS as text or None); empty without an audit. ``audit``: the audit JSON's
    path; ``sensor``, ``params``: the audit's sensor and parameters (None, {} without).
    ``scans``: the run's scans, bad ones counted (None without the run)."""

    path: Path | None
    config: RunConfig
    path_xyz: np.ndarray
    records: list = field(default_factory=list)
    audit: Path | None = None
    sensor: str | None = None
    params: dict = field(default_factory=dict)
    scans: int | None = None
    unreadable: str | None = None


@dataclass
class ViewInputs:
    """The map (indexed), its SOLM or None, plans as {name: trajectory samples (read_csv's
    columns)}, replays as {name: replay_tracks(...)}, a recorded run and flights as {name:
    samples (:func:`read_flight_csv`'s)}."""

    world: Map
    solm: Solm | None = None
    plans: dict = field(default_factory=dict)
    replays: dict = field(default_factory=dict)
    run: RunInputs | None = None
    flights: dict = field(default_factory=dict)


def load_view_inputs(
    map_path,
    solm_path=None,
    plan_paths=(),
    replay_paths=(),
    threads: int = DEFAULTS.scan.threads,
    *,
    run_path=None,
    audit_path=None,
    run_config: RunConfig = DEFAULTS.run,
    flights=(),
    quadrotor=None,
) -> ViewInputs:
    """Reads and checks everything the viewer shows: a missing or unreadable file, a SOLM
    built on another map (its recorded map hash differs from this map's), a malformed
    trajectory or flight CSV, a replay JSON that is not what ``lf3pm replay --json`` writes
    (a field missing or not numbers: the message names the file and the field) or flights
    over a ground robot's SOLM raise Lf3pmError. ``plan_paths`` and ``replay_paths`` are
    lists of paths, or one path. ``run_path`` and ``audit_path``: a recorded run and its
    audit (:func:`load_run_inputs`, read before the map, which takes longer). ``flights``:
    flight CSVs (:func:`read_flight_csv`), planned flights (FlightPlan, FlightTrajectory:
    their attitudes from ``quadrotor``, an lf3pm.flight.Quadrotor, default its defaults),
    or one of them."""
    if isinstance(map_path, (str, os.PathLike)) and not Path(map_path).exists():
        raise Lf3pmError(f"{map_path}: no such map file")
    plan_paths, replay_paths = _paths(plan_paths, "plan"), _paths(replay_paths, "replay")
    flights = _flights(flights, quadrotor)
    run = None
    if run_path is not None or audit_path is not None:
        run = load_run_inputs(run_path, audit_path, run_config)
    world = load_map(map_path, threads=threads)
    solm = None
    if solm_path is not None:
        solm = Solm.open(solm_path)
        built_on = solm.attrs.get("map_sha256")
        if built_on is not None and built_on != world.sha256:
            raise Lf3pmError(
                f"{solm_path} was built on another map than {map_path} "
                f"(map hash {built_on[:12]}…, this map's {world.sha256[:12]}…)"
            )
        if flights and solm.grid_spec.space.ground:
            raise Lf3pmError(
                f"{solm_path} is an {solm.grid_spec.space} SOLM (ground robots): a flight is shown over an r3yaw "
                "SOLM (`lf3pm solm build --space r3yaw`) or an r3 one, or without one"
            )
    plans = {_name(p, "plan"): read_csv(p) for p in plan_paths}
    replays = {}
    for path in replay_paths:
        try:
            replay = json.loads(_read_replay(path))
        except FileNotFoundError:
            raise Lf3pmError(f"{path}: no such replay file") from None
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
            raise Lf3pmError(f"{path}: not a replay JSON ({err.__class__.__name__})") from None
        if not isinstance(replay, dict):
            raise Lf3pmError(f"{path}: not a replay JSON (expected an object)")
        try:
            replays[_name(path, "replay")] = replay_tracks(replay)
        except Lf3pmError as err:
            raise Lf3pmError(f"{path}: {err}") from None
    return ViewInputs(world, solm, plans, replays, run, flights)


def _name(path, kind: str) -> str:
    return f"{kind} {Path(path).stem}"


def _flights(given, quadrotor) -> dict:
    """{name: samples} of flight CSVs' paths and planned flights (load_view_inputs)."""
    if isinstance(given, (str, os.PathLike)) or not isinstance(given, (list, tuple)):
        given = [given]
    out = {}
    for k, flight in enumerate(given):
        if isinstance(flight, (str, os.PathLike)):
            out[_name(flight, "flight")] = read_flight_csv(flight)
        else:
            out[f"flight {k + 1}"] = flight_samples(flight, quadrotor)
    return out


def read_flight_csv(path) -> dict:
    """A flight CSV as `lf3pm plan --robot quadrotor` writes it: a header naming at least
    FLIGHT_COLUMNS (any order, others ignored), then one row of numbers per sample. Returns
    t, x, y, z, yaw (n,) and the body's attitude ``wxyz`` (n, 4, body to world, normalised).
    Lf3pmError, naming the line: not a regular file of at most
    lf3pm.limits.MAX_TRAJECTORY_BYTES, a missing column, a row of the wrong length, a field
    that is not a finite number, fewer than 2 rows, times that do not increase strictly, a
    quaternion whose norm is not 1."""
    from lf3pm.trajectory.trajectory import read_csv

    columns = read_csv(path, FLIGHT_COLUMNS, what="flight")
    table = np.column_stack([columns[c] for c in FLIGHT_COLUMNS])
    wxyz = table[:, 5:9]
    norm = np.linalg.norm(wxyz, axis=1)
    off = np.flatnonzero(np.abs(norm - 1.0) > QUATERNION_TOLERANCE)
    if off.size:
        r = off[0]
        raise Lf3pmError(
            f"{path}: sample {r + 1}: qw, qx, qy, qz is no rotation (norm {norm[r]:.4g}, a rotation's is 1)"
        )
    return {
        **{c: table[:, k].copy() for k, c in enumerate(FLIGHT_COLUMNS[:5])},
        "wxyz": wxyz / norm[:, None],
    }


def _paths(given, kind: str) -> list:
    """``given`` as a list of paths (one path alone is a list of one)."""
    if isinstance(given, (str, os.PathLike)):
        return [given]
    try:
        paths = list(given)
    except TypeError:
        raise Lf3pmError(f"the {kind} files must be a list of paths, got {type(given).__name__}") from None
    bad = next((p for p in paths if not isinstance(p, (str, os.PathLike))), None)
    if bad is not None:
        raise Lf3pmError(f"the {kind} files must be paths, got {type(bad).__name__}")
    return paths


def _read_replay(path) -> str:
    """The text of a replay JSON (:func:`_read_json`)."""
    return _read_json(path, "replay", MAX_REPLAY_BYTES)


def _read_json(path, kind: str, limit: int) -> str:
    """The text of a ``kind`` JSON: a regular file (checked before it is opened: opening a
    FIFO waits for a writer) of at most ``limit`` bytes."""
    info = os.stat(path)
    if not stat.S_ISREG(info.st_mode):
        raise Lf3pmError(f"{path}: not a regular file (a {kind} JSON is one)")
    if info.st_size > limit:
        raise Lf3pmError(f"{path}: {info.st_size:,} bytes, more than a {kind} JSON's {limit:,}")
    with open(path, "rb") as fp:
        return fp.read(limit + 1).decode("utf-8")


# -- a recorded run and its audit ------------------------------------------------------


def load_run_inputs(run_path=None, audit_path=None, config: RunConfig = DEFAULTS.run) -> RunInputs:
    """A recorded run (``run_path``: what ``lf3pm audit`` reads, opened with ``config``, a
    run section) and its audit (``audit_path``: the JSON ``lf3pm audit --json`` prints and
    ``-o DIR`` writes as DIR/audit.json), either alone. Without ``run_path`` the run is
    the one the audit names (its ``run`` field, relative to the current folder) where that
    exists; otherwise the scans' records are shown without their points (``unreadable``
    says that --run is needed). Lf3pmError in one line: a missing file, an audit JSON that
    is not an audit (the field named), a run that cannot be opened or has no reference
    poses, an audited scan that is not in the run (same index, same name relative to the
    run's path)."""
    audit = _read_audit(audit_path) if audit_path is not None else None
    unreadable = None
    if run_path is None:
        named = Path(audit["run"])
        if named.exists():
            run_path = named
        else:
            unreadable = f"the run the audit names, {named}, is not found: give --run RUN to show the scans' points"
    if run_path is None:
        return RunInputs(
            None,
            config,
            np.array([r["pose"][:3, 3] for r in audit["scans"]]),
            audit["scans"],
            Path(audit_path),
            audit["sensor"],
            audit["params"],
            unreadable=unreadable,
        )
    with Run(run_path, config) as run:
        if run.reference is None:
            raise RunError(f"{run.path}: the run has no reference poses: its path cannot be drawn")
        lidar = run.reference.poses @ run.body_from_lidar
        names = run.scan_names()
    if audit is not None:
        for record in audit["scans"]:
            i = record["index"]
            if i >= len(names) or _scan_key(names[i], run_path) != _scan_key(record["name"], audit["run"]):
                raise Lf3pmError(
                    f"{audit_path}: its scan {record['name']} (index {i}) is not in the run {run_path} "
                    f"({f'its scan {i} is {names[i]}' if i < len(names) else f'{len(names)} scans'}): "
                    "an audit of another run?"
                )
    return RunInputs(
        Path(run_path),
        config,
        lidar[:, :3, 3],
        [] if audit is None else audit["scans"],
        None if audit_path is None else Path(audit_path),
        None if audit is None else audit["sensor"],
        {} if audit is None else audit["params"],
        len(names),
    )


def _scan_key(name: str, run_path) -> str:
    """A scan's name relative to its run's path: a folder's scans are named by their file
    under the run's path as it was given, which the audit may have been given otherwise
    (relative, absolute, from another folder). A bag's names do not hold the path."""
    try:
        return Path(name).relative_to(Path(run_path)).as_posix()
    except ValueError:
        return name


def _read_audit(path) -> dict:
    """An audit JSON, checked: ``run`` and ``sensor`` text, ``params`` an object (or
    absent), ``scans`` a non-empty list of records, each read as :class:`RunInputs`
    describes (index a whole number >= 0, name text, stamp a number, pose 4 x 4 finite
    numbers); Lf3pmError naming the file and the field otherwise."""
    try:
        audit = json.loads(_read_json(path, "audit", MAX_AUDIT_BYTES))
    except FileNotFoundError:
        raise Lf3pmError(f"{path}: no such audit file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise Lf3pmError(f"{path}: not an audit JSON ({err.__class__.__name__})") from None
    what = "not an audit JSON (write one with `lf3pm audit RUN --map MAP -o DIR`: DIR/audit.json)"
    if not isinstance(audit, dict) or not isinstance(audit.get("scans"), list) or not audit["scans"]:
        raise Lf3pmError(f"{path}: {what}: no scans")
    for key in ("run", "sensor"):
        if not isinstance(audit.get(key), str):
            raise Lf3pmError(f"{path}: {what}: its {key} must be text, got {repr(audit.get(key))[:40]}")
    params = audit.get("params") or {}
    if not isinstance(params, dict):
        raise Lf3pmError(f"{path}: {what}: its params must be an object, got {type(params).__name__}")
    try:
        records = [_audit_record(record, i) for i, record in enumerate(audit["scans"])]
    except Lf3pmError as err:
        raise Lf3pmError(f"{path}: {what}: {err}") from None
    return {"run": audit["run"], "sensor": audit["sensor"], "params": params, "scans": records}


def _audit_record(record, i: int) -> dict:
    """One scan record of an audit, read as :class:`RunInputs` describes."""
    if not isinstance(record, dict):
        raise Lf3pmError(f"scans[{i}] must be an object, got {type(record).__name__}")
    index, name, stamp = record.get("index"), record.get("name"), record.get("stamp")
    if not (isinstance(index, int) and not isinstance(index, bool) and index >= 0):
        raise Lf3pmError(f"scans[{i}].index must be a whole number >= 0, got {repr(index)[:40]}")
    if not isinstance(name, str):
        raise Lf3pmError(f"scans[{i}].name must be text, got {repr(name)[:40]}")
    if not (_is_number(stamp) and math.isfinite(stamp)):
        raise Lf3pmError(f"scans[{i}].stamp must be a number, got {repr(stamp)[:40]}")
    pose = record.get("pose")
    rows = pose if isinstance(pose, list) and len(pose) == 4 else []
    if not (rows and all(isinstance(r, list) and len(r) == 4 and all(map(_is_number, r)) for r in rows)):
        raise Lf3pmError(f"scans[{i}].pose must be 4 x 4 numbers (rows), got {repr(pose)[:40]}")
    pose = np.array(pose, dtype=np.float64)
    if not np.isfinite(pose).all():
        raise Lf3pmError(f"scans[{i}].pose must be finite")
    out = {"index": index, "name": name, "stamp": float(stamp), "pose": pose}
    for key in AUDIT_NUMBERS:
        value = record.get(key)
        if value is not None and not _is_number(value):
            raise Lf3pmError(f"scans[{i}].{key} must be a number or null, got {repr(value)[:40]}")
        out[key] = math.nan if value is None else float(value)
    for key in AUDIT_REASONS:
        value = record.get(key)
        if value is not None and not isinstance(value, str):
            raise Lf3pmError(f"scans[{i}].{key} must be text or null, got {repr(value)[:40]}")
        out[key] = value
    return out


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def read_scan(run: RunInputs, index: int) -> Scan:
    """Scan ``index`` of ``run`` (its index among the run's scans, bad ones counted),
    streamed to: the scans before it are read one at a time and dropped, so that memory
    holds one scan whatever the run's length. Lf3pmError in one line: no run to read
    (RunInputs' ``unreadable``), the scan is bad (why), or the run holds no such scan."""
    if run.path is None:
        raise Lf3pmError(run.unreadable or "no run given: give --run RUN to show the scans' points")
    with Run(run.path, run.config, skip_bad=True) as opened:
        for scan in opened.scans():
            if scan.index == index:
                return scan
            if scan.index > index:
                break
        bad = next((b for b in opened.bad_scans if b.index == index), None)
    raise RunError(bad.reason if bad is not None else f"{run.path}: no scan {index} ({run.scans} scans)")


def check_host(host: str) -> None:
    """Raises Lf3pmError when this machine cannot listen on ``host``: not a string, a
    name that does not resolve, an address that is not one of this machine's."""
    if not isinstance(host, str):
        raise Lf3pmError(f"host must be a name or an address, got {type(host).__name__}")
    try:
        _bind(host, 0)
    except OSError as err:
        raise Lf3pmError(
            f"host {host!r} is not an address of this machine ({err.strerror or err}): use "
            "127.0.0.1 (this machine only), 0.0.0.0 (every interface) or one of its "
            "addresses"
        ) from None


def check_port(host: str, port: int) -> None:
    """Raises Lf3pmError when ``port`` on ``host`` cannot be listened on: not an integer
    from 1 to 65535, in use, not ours to take, or ``host`` is not an address of this
    machine (:func:`check_host`)."""
    if not (isinstance(port, numbers.Integral) and not isinstance(port, bool)):
        raise Lf3pmError(f"port must be an integer from 1 to 65535, got {port!r}")
    if not 0 < port < 65536:
        raise Lf3pmError(f"port must be between 1 and 65535, got {port}")
    check_host(host)
    try:
        _bind(host, int(port))
    except OSError as err:
        why = "is in use" if err.errno == errno.EADDRINUSE else f"cannot be used ({err.strerror or err})"
        raise Lf3pmError(f"port {port} on {host} {why}: choose another port") from None


def _bind(host: str, port: int) -> None:
    with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, port))


def free_port(host: str = "127.0.0.1") -> int:
    """A port on ``host`` free at the time of the call."""
    check_host(host)
    with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return s.getsockname()[1]
