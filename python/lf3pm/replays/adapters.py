"""The interface of a LiDAR-inertial odometry the ``lio`` replay runs: an
:class:`Odometry` adapter in lf3pm's process, and the worker-side class it names, which
runs in a child process (_lio_worker.py) on the scans and IMU samples lio.run_lio
streams to it.

An adapter says what the odometry is (its PyPI package and the version lf3pm's
conventions are checked for, its licence), the sensors it runs on, its settings (a
:class:`lf3pm.config.Section`), the still time its initialisation needs and what a
replay records of its settings. lf3pm's own (genz.py, dlio.py, liosam.py) and a third
party's (the entry-point group ``lf3pm.odometries``: registry.py, docs/api.md) are
registered the same way.

The worker-side class (``worker``: "module:Class") is constructed in the child as
``Class(sensor_range, threads, settings, lidar)`` (``lidar``: the sensor's rings and the
LiDAR's pose in the IMU's frame) and called ``scan(points, begin, end,
offsets, imu)`` per scan and ``finish(imu)`` once (_lio_worker.py says what each gets
and returns). Only the child imports it: GenZ-LIO is GPL-2.0-only and lf3pm (BSD) runs
it in that separate process only.
"""

from __future__ import annotations

from typing import ClassVar

from lf3pm.config import Section, validated
from lf3pm.sensors import Sensor, spinning_rings

#: The module of lf3pm's own worker-side classes (the worker's script itself).
WORKER_MODULE = "lf3pm.replays._lio_worker"


class NoSettings(Section):
    """An odometry without settings of lf3pm's."""


class Odometry:
    """A LiDAR-inertial odometry the lio replay runs (module docstring). Subclasses set
    the class attributes and override the hooks that differ from these defaults."""

    #: The name ``--odometry`` and ``replay(odometry=...)`` take (the registry's key).
    key: ClassVar[str]
    #: Its name in reports and figures, e.g. "GenZ-LIO".
    name: ClassVar[str]
    #: The PyPI package that provides it and the version lf3pm's conventions are checked for.
    package: ClassVar[str]
    version: ClassVar[str]
    licence: ClassVar[str]
    #: "module:Class" of the worker-side class.
    worker: ClassVar[str]
    #: What to do when the worker cannot import it (None: pip install its package).
    install: ClassVar[str | None] = None
    #: Its settings: lf3pm's defaults, overridden by what a caller passes to run_lio.
    Settings: ClassVar[type[Section]] = NoSettings
    #: Whether it needs a spinning sensor (rings of beams: a range image).
    needs_rings: ClassVar[bool] = False
    #: What it loses, by whether the sensor spins: a warning naming what was measured
    #: and what to run instead (choose_odometry warns when asked for such a pair).
    loses: ClassVar[dict] = {}
    #: The sensors ``auto`` picks it for, by whether they spin (lf3pm's own only).
    auto_for: ClassVar[tuple] = ()
    #: Whether its worker places the LiDAR where ``lidar["extrinsic"]`` says (the LiDAR's
    #: pose in the IMU's frame): without it, run_lio refuses IMU samples that are not in
    #: the LiDAR's frame (a flight's, from the body).
    takes_extrinsic: ClassVar[bool] = False

    @classmethod
    def install_hint(cls) -> str:
        return cls.install or f"pip install {cls.package}"

    @classmethod
    def runs_on(cls, sensor: Sensor) -> bool:
        """Whether it can take ``sensor``'s scans."""
        return not cls.needs_rings or spinning_rings(sensor) is not None

    @classmethod
    def settings(cls, params: dict) -> Section:
        """Its settings section: lf3pm's defaults updated by ``params`` (ConfigError
        naming ``<key>.<name>`` for a bad one)."""
        return validated(cls.Settings, cls.key, **params)

    @classmethod
    def worker_settings(cls, settings: Section, sensor: Sensor, imu) -> dict:
        """What the worker-side class is given as its settings (picklable)."""
        return settings.model_dump()

    @classmethod
    def still_for(cls, settings: dict) -> float:
        """Seconds from the first IMU sample during which it takes the sensor to be still
        (besides its first 21 samples and the first scan), for lf3pm's warning."""
        return 0.0

    @classmethod
    def recorded(cls, settings: dict, version: str, messages: list) -> dict:
        """What a replay records of the settings it ran with (``version``: what the
        worker reported; ``messages``: lf3pm's notes, which it may add to)."""
        return {"settings": settings}


class EvalioOdometry(Odometry):
    """An odometry as evalio (PyPI ``evalio``, MIT) compiles it: its parameters by name
    (evalio's ``default_params()``, which the worker checks), lf3pm's over them."""

    package = "evalio"
    version = "0.6.1"
    install = "pip install 'lf3pm[lio]'"
