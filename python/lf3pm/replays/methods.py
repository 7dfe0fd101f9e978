"""The replay methods: the :class:`ReplayMethod` interface and :data:`METHODS`, the one
registry of them that ``lf3pm replay``, :func:`lf3pm.replay`, :func:`lf3pm.replay_seeds`
and the studies read (the names are those of ``lf3pm.config.REPLAY_METHODS``).

- ``localization`` (localization.py): registration to the prior map from a wheel-odometry
  prediction, keeping the prediction where registration is degenerate;
- ``lio`` (lio.py): a simulated IMU and the scans through a LiDAR-inertial odometry
  (registry.py: lf3pm's and plugins');
- ``odometry`` (odometry.py): LiDAR-only KISS-ICP.
"""

from __future__ import annotations

from typing import ClassVar, Protocol, runtime_checkable

from lf3pm.errors import Lf3pmError
from lf3pm.replays.lio import Lio
from lf3pm.replays.localization import Localization
from lf3pm.replays.odometry import KissIcpOdometry
from lf3pm.replays.replay_result import MethodRun


@runtime_checkable
class ReplayMethod(Protocol):
    """A state estimator a replay runs. Made from its settings section
    (``from_params``: the section's defaults updated by a caller's keyword parameters),
    or from a whole :class:`lf3pm.config.Config` (``from_config``: its section of it),
    it is prepared once per map (``prepare``: what it keeps of the map across seeds, e.g.
    the localization's registration target; ``prepared`` one made before, checked) and
    run on one seed's scan stream (``run``), which it consumes, giving a
    :class:`MethodRun` (the Estimate, the parameters the replay records under ``name``,
    the library versions). ``rest``: seconds the sensor stands still at the first pose
    before the trajectory (the stream starts with them; scoring starts after).
    ``uses_odometry``: whether it runs one of registry.py's odometries (``--odometry``)."""

    name: ClassVar[str]
    uses_odometry: ClassVar[bool]
    rest: float

    @classmethod
    def from_params(cls, params: dict) -> ReplayMethod: ...

    @classmethod
    def from_config(cls, config) -> ReplayMethod: ...

    def prepare(self, map, threads: int, prepared=None) -> object: ...

    def run(self, scans, motion, sensor, seed: int, *, prepared, threads: int, progress=None) -> MethodRun: ...


#: The replay methods by name.
METHODS: dict[str, type[ReplayMethod]] = {method.name: method for method in (Localization, Lio, KissIcpOdometry)}


def replay_method(name: str | ReplayMethod, params: dict | None = None) -> ReplayMethod:
    """The method ``name`` made from ``params`` (its settings), or ``name`` itself when it
    is a method already made; Lf3pmError for an unknown method or parameter (or
    parameters given to a method already made), ConfigError for a bad value."""
    if not isinstance(name, str):
        if params:
            given = ", ".join(params)
            raise Lf3pmError(f"the {name.name} method is made already: give its settings there, not {given}")
        return name
    if name not in METHODS:
        raise Lf3pmError(f"unknown method {name!r}; use one of {', '.join(METHODS)}")
    return METHODS[name].from_params(dict(params or {}))
