"""What ``lf3pm view`` is given, read and checked before anything is served: the map, a
SOLM of that map, planned trajectories and replays, and a free port. Every problem is
one Lf3pmError line."""

from __future__ import annotations

import errno
import json
import numbers
import os
import socket
import stat
from dataclasses import dataclass, field
from pathlib import Path

from lf3pm.config import DEFAULTS
from lf3pm.errors import Lf3pmError
from lf3pm.map import Map, load_map
from lf3pm.solm import Solm
from lf3pm.trajectory.trajectory import read_csv
from lf3pm.view.layers import replay_tracks

#: The largest replay JSON read (bytes): a long LIO replay with its per-scan positions is
#: a few MB; a device or a runaway file is refused before it is read.
MAX_REPLAY_BYTES = 256 * 2**20


@dataclass
class ViewInputs:
    """The map (indexed), its SOLM or None, plans as {name: trajectory samples (read_csv's
    columns)} and replays as {name: replay_tracks(...)}."""

    world: Map
    solm: Solm | None = None
    plans: dict = field(default_factory=dict)
    replays: dict = field(default_factory=dict)


def load_view_inputs(
    map_path, solm_path=None, plan_paths=(), replay_paths=(), threads: int = DEFAULTS.scan.threads
) -> ViewInputs:
    """Reads and checks everything the viewer shows: a missing or unreadable file, a SOLM
    built on another map (its recorded map hash differs from this map's), a malformed
    trajectory CSV or a replay JSON that is not what ``lf3pm replay --json`` writes (a
    field missing or not numbers: the message names the file and the field) raise
    Lf3pmError. ``plan_paths`` and ``replay_paths`` are lists of paths, or one path."""
    if isinstance(map_path, (str, os.PathLike)) and not Path(map_path).exists():
        raise Lf3pmError(f"{map_path}: no such map file")
    plan_paths, replay_paths = _paths(plan_paths, "plan"), _paths(replay_paths, "replay")
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
    return ViewInputs(world, solm, plans, replays)


def _name(path, kind: str) -> str:
    return f"{kind} {Path(path).stem}"


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
    """The text of a replay JSON: a regular file (checked before it is opened: opening a
    FIFO waits for a writer) of at most MAX_REPLAY_BYTES."""
    info = os.stat(path)
    if not stat.S_ISREG(info.st_mode):
        raise Lf3pmError(f"{path}: not a regular file (a replay JSON is one)")
    if info.st_size > MAX_REPLAY_BYTES:
        raise Lf3pmError(f"{path}: {info.st_size:,} bytes, more than a replay JSON's {MAX_REPLAY_BYTES:,}")
    with open(path, "rb") as fp:
        return fp.read(MAX_REPLAY_BYTES + 1).decode("utf-8")


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
