"""The registry of the lio replay's odometries: lf3pm's own (genz.py, dlio.py, liosam.py)
and those other packages register through the entry-point group ``lf3pm.odometries``
(``name = "module:Adapter"``, an :class:`lf3pm.replays.adapters.Odometry` subclass whose
``key`` is ``name``; docs/api.md has a complete example). Everything that takes an
odometry's name (``lf3pm replay --odometry``, ``lf3pm config``, ``replay``,
``replay_seeds``, the studies) looks it up here, and each odometry's settings in a
configuration (``replay.odometries``, by name) are validated here by its settings section.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from importlib.metadata import entry_points

from lf3pm.config import Config, ConfigError, Section
from lf3pm.errors import Lf3pmError
from lf3pm.replays.adapters import Odometry
from lf3pm.replays.dlio import Dlio
from lf3pm.replays.genz import GenZ
from lf3pm.replays.liosam import LioSam
from lf3pm.sensors import Sensor, spinning_rings

#: The entry-point group third-party odometries register in.
GROUP = "lf3pm.odometries"
#: The name that picks lf3pm's odometry for the sensor (Odometry.auto_for).
AUTO = "auto"
#: The attributes an adapter must set (Odometry's docstrings say what each is).
REQUIRED = ("key", "name", "package", "version", "licence", "worker")

_BUILTIN = (GenZ, Dlio, LioSam)
_loaded: dict[str, type[Odometry]] | None = None


class PluginError(Lf3pmError):
    """An odometry plugin that cannot be imported or is not an Odometry adapter."""


def register(adapter) -> type[Odometry]:
    """Adds ``adapter`` (an Odometry subclass) to this process's registry under its
    ``key``, as an entry point does; PluginError naming it for anything else or a name
    taken."""
    source = f"{getattr(adapter, '__module__', '?')}:{getattr(adapter, '__qualname__', repr(adapter))}"
    _add(odometries(), adapter, source)
    return adapter


def odometries() -> dict[str, type[Odometry]]:
    """Every registered odometry by its key: lf3pm's, then the entry points' (loaded on
    the first call). PluginError for a plugin that does not import or fit."""
    global _loaded
    if _loaded is None:
        registry = {adapter.key: adapter for adapter in _BUILTIN}
        for point in entry_points(group=GROUP):
            source = f"{point.name} ({point.value})"
            try:
                adapter = point.load()
            except Exception as err:  # any failure of third-party code: one line naming it
                raise PluginError(f"odometry plugin {source} does not import: {type(err).__name__}: {err}") from None
            _add(registry, adapter, source)
            if adapter.key != point.name:
                raise PluginError(f"odometry plugin {source}: its key is {adapter.key!r}, not its entry point's name")
        _loaded = registry
    return _loaded


def _add(registry: dict, adapter, source: str) -> None:
    problem = _problem(adapter)
    if problem is None and registry.get(adapter.key, adapter) is not adapter:
        problem = f"the name {adapter.key!r} is taken by {registry[adapter.key].__module__}"
    if problem:
        raise PluginError(f"odometry plugin {source}: {problem}")
    registry[adapter.key] = adapter


def names() -> tuple[str, ...]:
    """The names ``--odometry`` takes: auto, then each registered odometry."""
    return (AUTO, *odometries())


def check_name(name: str, where: str = "replay.odometry") -> str:
    """``name`` if it names an odometry or auto, else ConfigError naming ``where`` and the choices."""
    choices = names()
    if name not in choices:
        listed = ", ".join(repr(n) for n in choices[:-1]) + f" or {choices[-1]!r}"
        raise ConfigError(f"{where} must be {listed}, got {name!r}")
    return name


def settings(given: Mapping[str, Mapping], where: str = "replay.odometries") -> dict[str, Section]:
    """Every registered odometry's settings section by its name: lf3pm's defaults with
    what ``given`` (a configuration's ``replay.odometries``) sets for it over them.
    ConfigError in one line naming ``where.<name>`` (and the field) for a name no
    odometry has or a value its section refuses."""
    registry = odometries()
    unknown = [name for name in given if name not in registry]
    if unknown:
        raise ConfigError(f"{where}: {unknown[0]!r} is no odometry; odometries: {', '.join(registry)}")
    sections = {}
    for name, adapter in registry.items():
        values = given.get(name, {})
        if not isinstance(values, Mapping):
            raise ConfigError(f"{where}.{name} must be a mapping of settings, got {values!r}")
        try:
            sections[name] = adapter.settings(dict(values))
        except Lf3pmError as err:
            text = str(err)
            raise ConfigError(f"{where}.{text}" if text.startswith(f"{name}.") else f"{where}.{name}: {text}") from None
    return sections


def changed_settings(name: str, given: Mapping) -> dict:
    """Of the settings ``given`` for the odometry ``name``, those that differ from lf3pm's
    defaults (what a replay records and passes on: a configuration that states a default
    runs and records as one that leaves it out)."""
    adapter = odometry(name)
    default = adapter.settings({}).model_dump()
    return {
        key: value for key, value in adapter.settings(dict(given)).model_dump().items() if default.get(key) != value
    }


def with_settings(config: Config, path=None) -> Config:
    """``config`` with every registered odometry's settings in ``replay.odometries``
    (lf3pm's defaults under what it gives), as ``lf3pm config`` shows them; ConfigError
    (prefixed by ``path``, the YAML file, when given) as :func:`settings`."""
    try:
        sections = settings(config.replay.odometries)
    except ConfigError as err:
        raise ConfigError(f"{path}: {err}" if path is not None else str(err)) from None
    shown = {name: section.model_dump(mode="json") for name, section in sections.items()}
    return config.model_copy(update={"replay": config.replay.model_copy(update={"odometries": shown})})


def odometry(name: str) -> type[Odometry]:
    """The registered odometry ``name`` (not auto); Lf3pmError for an unknown one."""
    registry = odometries()
    if name not in registry:
        raise Lf3pmError(f"unknown odometry {name!r}; use one of {', '.join(names())}")
    return registry[name]


def choose_odometry(name: str, sensor: Sensor) -> type[Odometry]:
    """The odometry run for ``name`` (a registered one or auto) on ``sensor``: auto is
    lf3pm's for that kind of sensor (Odometry.auto_for). Lf3pmError for an unknown name
    or a sensor the odometry cannot take; warns for a pair the odometry is known to lose."""
    spinning = spinning_rings(sensor) is not None
    if name == AUTO:
        return next(adapter for adapter in _BUILTIN if spinning in adapter.auto_for)
    adapter = odometry(name)
    if spinning in adapter.loses:
        # Attributed here, not to the caller: the CLI's early check and run_lio then warn once.
        warnings.warn(f"{sensor.name} with {name}: {adapter.loses[spinning]}", stacklevel=1)
    if not adapter.runs_on(sensor):
        others = " or ".join(a.key for a in odometries().values() if a.runs_on(sensor))
        raise Lf3pmError(f"{name} needs a spinning sensor (rings of beams); the {sensor.name} has none: use {others}")
    return adapter


def _problem(adapter) -> str | None:
    """What keeps ``adapter`` from being an Odometry adapter (None: nothing)."""
    if not (isinstance(adapter, type) and issubclass(adapter, Odometry)):
        return f"{adapter!r} is not a subclass of lf3pm.replays.adapters.Odometry"
    missing = [name for name in REQUIRED if not isinstance(getattr(adapter, name, None), str)]
    if missing:
        return f"{adapter.__qualname__} does not set {', '.join(missing)} (strings)"
    if ":" not in adapter.worker:
        return f"{adapter.__qualname__}.worker must be 'module:Class', got {adapter.worker!r}"
    return None
