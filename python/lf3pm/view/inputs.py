"""What ``lf3pm view`` is given, read and checked before anything is served: the map, a
SOLM of that map, planned trajectories and replays, and a free port. Every problem is
one Lf3pmError line."""

from __future__ import annotations

import errno
import json
import socket
from dataclasses import dataclass, field
from pathlib import Path

from lf3pm.config import DEFAULTS
from lf3pm.errors import Lf3pmError
from lf3pm.map import Map, load_map
from lf3pm.solm import Solm
from lf3pm.trajectory.trajectory import read_csv
from lf3pm.view.layers import replay_tracks


@dataclass
class ViewInputs:
    """The map (indexed), its SOLM or None, plans as {name: trajectory samples (read_csv's
    columns)} and replays as {name: replay_tracks(...)}."""

    world: Map
    solm: Solm | None = None
    plans: dict = field(default_factory=dict)
    replays: dict = field(default_factory=dict)


def load_view_inputs(map_path, solm_path=None, plan_paths=(), replay_paths=(),
                     threads: int = DEFAULTS.scan.threads) -> ViewInputs:
    """Reads and checks everything the viewer shows: a missing or unreadable file, a SOLM
    built on another map (its recorded map hash differs from this map's), a malformed
    trajectory CSV or a replay JSON without positions raise Lf3pmError."""
    if not Path(map_path).exists():
        raise Lf3pmError(f"{map_path}: no such map file")
    world = load_map(map_path, threads=threads)
    solm = None
    if solm_path is not None:
        solm = Solm.open(solm_path)
        built_on = solm.attrs.get("map_sha256")
        if built_on is not None and built_on != world.sha256:
            raise Lf3pmError(f"{solm_path} was built on another map than {map_path} "
                             f"(map hash {built_on[:12]}…, this map's {world.sha256[:12]}…)")
    plans = {_name(p, "plan"): read_csv(p) for p in plan_paths}
    replays = {}
    for path in replay_paths:
        try:
            replay = json.loads(Path(path).read_text(encoding="utf-8"))
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


def check_port(host: str, port: int) -> None:
    """Raises Lf3pmError when ``port`` on ``host`` cannot be listened on (in use, not
    ours to take, or not an address of this machine)."""
    if not 0 < port < 65536:
        raise Lf3pmError(f"port must be between 1 and 65535, got {port}")
    try:
        with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM) as s:
            s.bind((host, port))
    except OSError as err:
        why = "is in use" if err.errno == errno.EADDRINUSE else f"cannot be used ({err.strerror})"
        raise Lf3pmError(f"port {port} on {host} {why}: choose another with --port") from None


def free_port(host: str = "127.0.0.1") -> int:
    """A port on ``host`` free at the time of the call."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return s.getsockname()[1]
