"""The benefit study's cases from a YAML file: any map, sensor, zones and pairs.

    lf3pm experiment benefit --cases my_site.yaml -o DIR

A cases file is a mapping with one key, ``cases``: a list of cases, each a mapping::

    cases:
      - name: hall                  # letters, digits, _ . - (the outputs' folder names)
        map: hall.ply               # a map file lf3pm reads (.pcd .ply .las .laz .npy ...)
                                    #   or a run folder (scans at TUM poses, lf3pm.io.run_folder):
                                    #   relative to this file's folder, absolute, or a
                                    #   name in the shared data folder; or scene:NAME
        sensor: vlp16               # a preset, or a sensor YAML (relative to this file)
        space: se2                  # r2 or se2
        res: 0.5                    # SOLM cell (m)
        pairs: 6                    # start/goal pairs drawn (>= 1)
        robots: [omni, diff]        # alternating over the pairs (omni, diff, car)
        zones:
          start: [0, -2, 4, 2]                      # a box: xmin, ymin, xmax, ymax (m)
          goal:                                     # or a polygon and a yaw range
            polygon: [[20, -3], [28, -3], [24, 4]]  #   (x, y) vertices, m (>= 3)
            yaw_deg: [-45, 45]                      #   degrees, se2 only
        bounds: [-5, -10, 35, 10]   # the SOLM's extent (default: the map's)
        min_distance: 15            # start and goal at least this far apart (m)
        both_ways: true             # every other pair runs goal to start

Optional: ``scene_params`` and ``scene_seed`` (``scene:NAME`` maps only; a scene brings
its own zones, which a case's ``zones`` replace by name), ``yaw_bins``, ``yaw_reuse``,
``ray_stride`` (as the solm section's), ``r_safe`` (the robots' clearance beyond the
SOLM's robot radius, m). A zone is a box, a polygon, or a mapping of ``box`` or
``polygon`` with ``yaw_deg`` [lo, hi] (degrees, lo <= hi, at most 360 apart): an SE(2)
pose drawn there faces uniformly in that range, else the pair faces from start to
goal. A scene's zone takes a yaw range alone (``start: {yaw_deg: [-30, 30]}``).

:func:`load_cases` reads a file into :class:`~lf3pm.experiments.map_cases.MapCase`
objects; a bad file raises :class:`~lf3pm.config.ConfigError` in one line naming the
file, the case (by name, else ``#N`` from 1) and the field. The study's own cases are
``cases.yaml`` beside this module (``--quick``: ``quick_cases.yaml``).
"""

from __future__ import annotations

import math
import re
from dataclasses import MISSING, fields
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import Field, ValidationError, field_validator, model_validator

from lf3pm.config import MAX_RES, MAX_SEED, ROBOT_KINDS, ConfigError, Section, SolmConfig, describe
from lf3pm.errors import Lf3pmError
from lf3pm.experiments.data import shared_data_dir
from lf3pm.experiments.map_cases import MapCase
from lf3pm.grid import Space
from lf3pm.limits import clip, excerpt, load_yaml, read_text_file

#: The study's cases (``lf3pm experiment benefit``) and its quick run's (``--quick``).
CASES_FILE = Path(__file__).with_name("cases.yaml")
QUICK_FILE = Path(__file__).with_name("quick_cases.yaml")

#: MapCase's defaults: what a case leaves out (one source for both).
_DEFAULT = {f.name: f.default for f in fields(MapCase) if f.default is not MISSING}


def _solm_limits(name: str) -> dict:
    """The solm section's ge/le limits of its field ``name`` (a case's are the same)."""
    limits = {}
    for item in SolmConfig.model_fields[name].metadata:
        for key in ("ge", "le"):
            if getattr(item, key, None) is not None:
                limits[key] = getattr(item, key)
    return limits


#: A case's name: it names the outputs' folders.
_NAME = r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}"
#: Twice this is the least area of a polygon (m^2), and a box's least width.
_TINY = 1e-9


class Zone(Section):
    """A start or goal zone: a box or a polygon (m), and a yaw range (degrees, SE(2))."""

    box: tuple[float, float, float, float] | None = Field(None, description="xmin, ymin, xmax, ymax (m).")
    polygon: tuple[tuple[float, float], ...] | None = Field(None, description="(x, y) vertices (m), 3 or more.")
    yaw_deg: tuple[float, float] | None = Field(None, description="lo, hi (degrees): an SE(2) pose's yaw range.")

    @model_validator(mode="before")
    @classmethod
    def _shorthand(cls, data):
        """A list is a box (4 numbers) or a polygon (a list of [x, y])."""
        if isinstance(data, (list, tuple)):
            return {"polygon": data} if data and isinstance(data[0], (list, tuple)) else {"box": data}
        return data

    @field_validator("box", "yaw_deg", mode="before")
    @classmethod
    def _length(cls, value, info):
        box = info.field_name == "box"
        return _numbers(value, 4 if box else 2, "xmin, ymin, xmax, ymax" if box else "lo, hi in degrees")

    @field_validator("polygon", mode="before")
    @classmethod
    def _vertices(cls, value):
        if isinstance(value, (list, tuple)):
            for vertex in value:
                _numbers(vertex, 2, "x, y", "each vertex ")
        return value

    @model_validator(mode="after")
    def _check(self):
        if self.box is not None and self.polygon is not None:
            raise ValueError("a zone is a box or a polygon, not both")
        if self.box is not None:
            xmin, ymin, xmax, ymax = self.box
            if not (xmax - xmin > _TINY and ymax - ymin > _TINY):
                raise ValueError(f"box must be xmin, ymin, xmax, ymax with xmin < xmax and ymin < ymax, got {self.box}")
        if self.polygon is not None:
            _check_polygon(self.polygon)
        if self.yaw_deg is not None:
            lo, hi = self.yaw_deg
            if not lo <= hi <= lo + 360.0:
                raise ValueError(
                    f"yaw_deg must be lo, hi (degrees) with lo <= hi <= lo + 360, got {list(self.yaw_deg)}"
                )
        return self

    def area(self) -> tuple | None:
        """The box or polygon as MapCase takes it (None: a yaw range alone)."""
        return self.box if self.box is not None else self.polygon


def _numbers(value, count: int, what: str, each: str = "") -> object:
    """ValueError unless the list ``value`` has ``count`` items (pydantic checks each)."""
    if isinstance(value, (list, tuple)) and len(value) != count:
        raise ValueError(f"{each}must be {count} numbers ({what}), got {len(value)}: {excerpt(list(value))}")
    return value


def _check_polygon(polygon) -> None:
    """ValueError unless ``polygon`` has 3 or more vertices, an area and no crossing edges."""
    n = len(polygon)
    if n < 3:
        raise ValueError(f"polygon needs 3 or more [x, y] vertices, got {n}")
    edges = [(polygon[i], polygon[(i + 1) % n]) for i in range(n)]
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue  # the first and last edges share a vertex
            if _cross(*edges[i], *edges[j]):
                raise ValueError(f"polygon's edges {i + 1} and {j + 1} cross (a polygon may not cross itself)")
    twice_area = sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in zip(polygon, polygon[1:] + polygon[:1]))
    if abs(twice_area) <= 2 * _TINY:
        raise ValueError("polygon is degenerate (no area: its vertices lie on a line)")


def _cross(p, q, r, s) -> bool:
    """Whether segments pq and rs meet."""

    def side(a, b, c):
        v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        return (v > 0) - (v < 0)

    def within(a, b, c):  # c on the line ab: within its box
        return min(a[0], b[0]) <= c[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= c[1] <= max(a[1], b[1])

    d1, d2, d3, d4 = side(r, s, p), side(r, s, q), side(p, q, r), side(p, q, s)
    if d1 * d2 < 0 and d3 * d4 < 0:
        return True
    return any(
        d == 0 and within(a, b, c) for d, a, b, c in ((d1, r, s, p), (d2, r, s, q), (d3, p, q, r), (d4, p, q, s))
    )


class Zones(Section):
    """The start and goal zones."""

    start: Zone | None = None
    goal: Zone | None = None


class Case(Section):
    """One case of a cases file (the module's docstring)."""

    name: str = Field(description="The case's name (folder names).")
    map: str = Field(min_length=1, description="A map file or scene:NAME.")
    sensor: str = Field(min_length=1, description="A sensor preset or sensor YAML file.")
    space: Literal["r2", "se2"] = Field(description="r2 or se2.")
    res: float = Field(gt=0, le=MAX_RES, description="SOLM cell (m).")
    pairs: int = Field(ge=1, le=10_000, description="Start/goal pairs drawn.")
    robots: tuple[Literal[ROBOT_KINDS], ...] = Field(_DEFAULT["robots"], min_length=1)  # type: ignore[valid-type]
    yaw_bins: int = Field(_DEFAULT["yaw_bins"], **_solm_limits("yaw_bins"))
    yaw_reuse: bool = _DEFAULT["yaw_reuse"]
    ray_stride: int = Field(_DEFAULT["ray_stride"], **_solm_limits("ray_stride"))
    scene_params: dict[str, Any] = Field(default_factory=dict, description="A scene's parameters (scene: maps).")
    scene_seed: int = Field(_DEFAULT["scene_seed"], ge=0, le=MAX_SEED)
    bounds: tuple[float, float, float, float] | None = None
    zones: Zones | None = None
    min_distance: float = Field(_DEFAULT["min_distance"], ge=0)
    both_ways: bool = _DEFAULT["both_ways"]
    r_safe: float = Field(_DEFAULT["r_safe"], ge=0, le=100)

    @field_validator("name", mode="before")
    @classmethod
    def _name(cls, value):
        if isinstance(value, str) and not re.fullmatch(_NAME, value):
            raise ValueError(
                "must be 1 to 64 letters, digits, _ . or - (a folder name), not starting with _ . -, "
                f"got {excerpt(value)}"
            )
        return value

    @field_validator("bounds", mode="before")
    @classmethod
    def _bounds(cls, value):
        return _numbers(value, 4, "xmin, ymin, xmax, ymax")

    @model_validator(mode="after")
    def _check(self):
        scene = self.map.startswith("scene:")
        if not scene:
            for name in ("scene_params", "scene_seed"):
                if name in self.model_fields_set:
                    raise ValueError(f"{name}: only a scene:NAME map takes scene parameters")
        if self.bounds is not None:
            xmin, ymin, xmax, ymax = self.bounds
            if not (xmin < xmax and ymin < ymax):
                raise ValueError(
                    f"bounds must be xmin, ymin, xmax, ymax with xmin < xmax and ymin < ymax, got {list(self.bounds)}"
                )
        for end in ("start", "goal"):
            zone = getattr(self.zones, end) if self.zones is not None else None
            if zone is None:
                if not scene:
                    raise ValueError(f"zones.{end}: a map file needs its start and goal zones (a box or a polygon)")
                continue
            if zone.yaw_deg is not None and Space(self.space) is not Space.SE2:
                raise ValueError(f"zones.{end}.yaw_deg: a yaw range needs space se2 (this case plans in {self.space})")
            if zone.area() is None and not scene:
                raise ValueError(f"zones.{end}: a map file's zone needs a box or a polygon")
        return self


class CasesFile(Section):
    """A cases file: its list of cases."""

    cases: list[dict] = Field(min_length=1, description="The cases (each a mapping).")


def load_cases(path, *, check_files: bool = True) -> tuple[MapCase, ...]:
    """The cases of the YAML file ``path`` as MapCase objects (the module's docstring).
    Map and sensor files are found relative to the file's folder (a map also by name in
    the shared data folder); ``check_files``: refuse a map that is nowhere (off: the
    repository's own cases load where the shared data are absent, and fail when run).
    Raises ConfigError in one line naming the file, case and field."""
    path = Path(path)
    text = read_text_file(path, "cases file", ConfigError)
    try:
        data = load_yaml(text, path, ConfigError)
    except yaml.YAMLError as err:
        raise ConfigError(f"{path}: not YAML ({clip(str(err).splitlines()[0])})") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: a cases file is a mapping with a list of cases under 'cases', got {excerpt(data)}")
    try:
        listed = CasesFile.model_validate(data).cases
    except ValidationError as err:
        raise ConfigError(f"{path}: {describe(err)}") from None
    out, seen = [], {}
    for number, raw in enumerate(listed, start=1):
        given = raw.get("name")
        label = f"case {given}" if isinstance(given, str) and given else f"case #{number}"
        try:
            case = Case.model_validate(raw)
        except ValidationError as err:
            raise ConfigError(f"{path}: {label}: {describe(err)}") from None
        if case.name in seen:
            raise ConfigError(f"{path}: {label} (#{number}): name is the name of case #{seen[case.name]} too")
        seen[case.name] = number
        try:
            out.append(_map_case(case, path.parent, check_files))
        except (Lf3pmError, ValueError) as err:
            raise ConfigError(f"{path}: {label}: {err}") from None
    return tuple(out)


def _map_case(case: Case, folder: Path, check_files: bool) -> MapCase:
    """``case`` as a MapCase, its map, sensor and zones checked (ValueError 'field: ...')."""
    zones = {end: getattr(case.zones, end) for end in ("start", "goal")} if case.zones else {}
    zones = {end: zone for end, zone in zones.items() if zone is not None}
    areas = {end: zone.area() for end, zone in zones.items() if zone.area() is not None}
    yaw_ranges = {
        end: (math.radians(zone.yaw_deg[0]), math.radians(zone.yaw_deg[1]))
        for end, zone in zones.items()
        if zone.yaw_deg is not None
    }
    if case.map.startswith("scene:"):
        source = case.map
        scene_areas = _scene_zones(case)
        areas_checked = {**scene_areas, **areas}
    else:
        source = _map_file(case.map, folder, check_files)
        areas_checked = areas
    if case.bounds is not None:
        for end, area in areas_checked.items():
            _inside(end, area, case.bounds)
    return MapCase(
        case.name,
        source,
        _sensor(case.sensor, folder),
        case.space,
        case.res,
        case.pairs,
        robots=tuple(case.robots),
        yaw_bins=case.yaw_bins,
        yaw_reuse=case.yaw_reuse,
        ray_stride=case.ray_stride,
        scene_params=dict(case.scene_params),
        scene_seed=case.scene_seed,
        bounds=case.bounds,
        zones=areas or None,
        min_distance=case.min_distance,
        both_ways=case.both_ways,
        r_safe=case.r_safe,
        yaw_ranges=yaw_ranges or None,
    )


def _scene_zones(case: Case) -> dict:
    """The scene's own zones (checking its name and parameters)."""
    from lf3pm.scenes import scene_names, scene_zones

    name = case.map.split(":", 1)[1]
    if name.strip().lower().replace("-", "_") not in scene_names():
        raise ValueError(f"map: unknown scene {name!r}; known scenes: {', '.join(scene_names())}")
    try:
        return {end: tuple(zone) for end, zone in scene_zones(name, **case.scene_params).items()}
    except Lf3pmError as err:
        raise ValueError(f"scene_params: {err}") from None


def _map_file(text: str, folder: Path, check: bool) -> str:
    """What MapCase reads the map from: an absolute path (a file beside the cases file,
    or given absolute), or a name in the shared data folder (as given)."""
    from lf3pm.io import SUPPORTED_SUFFIXES
    from lf3pm.io.run_folder import is_run_folder

    path = Path(text).expanduser()
    local = path if path.is_absolute() else folder / path
    if is_run_folder(local):
        return str(local.resolve())
    if is_run_folder(shared_data_dir() / text):
        return text
    if not text.lower().endswith(SUPPORTED_SUFFIXES):
        raise ValueError(
            f"map: {text} is no map file lf3pm reads (suffixes: {' '.join(SUPPORTED_SUFFIXES)}), "
            "no run folder (scans/ and poses_tum.txt) nor scene:NAME"
        )
    if local.is_file():
        return str(local.resolve())
    if (shared_data_dir() / text).is_file() or not check:
        return text
    raise ValueError(
        f"map: no file {text} beside the cases file ({folder}) or in the shared data folder ({shared_data_dir()})"
    )


def _sensor(text: str, folder: Path) -> str:
    """A preset's name as given, or a sensor YAML's absolute path (checked)."""
    from lf3pm.errors import SensorError
    from lf3pm.sensors import PRESET_NAMES, load_sensor_yaml
    from lf3pm.sensors._presets import find_preset

    if find_preset(text) is not None:
        return text
    path = Path(text).expanduser()
    local = path if path.is_absolute() else folder / path
    if not local.is_file():
        raise ValueError(f"sensor: unknown sensor {text!r}; presets: {', '.join(PRESET_NAMES)}, or a sensor YAML file")
    try:
        load_sensor_yaml(local)
    except SensorError as err:
        raise ValueError(f"sensor: {err}") from None
    return str(local.resolve())


def _inside(end: str, area, bounds) -> None:
    """ValueError unless zone ``end``'s box or polygon lies within ``bounds``."""
    from lf3pm.experiments.map_cases import zone_box

    xmin, ymin, xmax, ymax = zone_box(area)
    bx0, by0, bx1, by1 = bounds
    if xmin < bx0 or ymin < by0 or xmax > bx1 or ymax > by1:
        raise ValueError(
            f"zones.{end}: ({xmin:g}, {ymin:g}, {xmax:g}, {ymax:g}) is not inside bounds "
            f"({bx0:g}, {by0:g}, {bx1:g}, {by1:g})"
        )
