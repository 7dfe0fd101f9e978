"""Custom sensors described in a YAML file (schema: see :mod:`lf3pm.sensors`)."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import yaml

from lf3pm.errors import SensorError
from lf3pm.limits import clip, excerpt, load_yaml, read_text_file

from ._model import MAX_RAYS, Sensor, _is_number, pattern_directions, ray_count, spinning_directions
from ._returns import ReturnModel

_COMMON_KEYS = ("name", "description", "min_range", "max_range", "range_noise_sigma", "return_probability")
_SPINNING_KEYS = ("elevations_deg", "azimuth_count", "horizontal_fov_deg")
_PATTERN_KEYS = ("pattern_file", "point_rate", "integration_time")
ALLOWED_KEYS = _COMMON_KEYS + _SPINNING_KEYS + _PATTERN_KEYS
#: The longest sensor name: a label for tables and messages, not a description.
MAX_NAME = 64


class _Reader:
    """Typed access to the keys of one YAML mapping, with one-line errors."""

    def __init__(self, path: Path, data: dict):
        self.path = path
        self.data = data

    def fail(self, key: str, message: str):
        raise SensorError(f"sensor file {self.path}: key '{key}' {message}")

    def has(self, key: str) -> bool:
        return key in self.data

    def string(self, key: str, default: str | None = None) -> str:
        if key not in self.data:
            if default is None:
                self.fail(key, "is missing")
            return default
        value = self.data[key]
        if not isinstance(value, str):
            self.fail(key, f"must be a string, got {_type(value)}")
        if not value.strip():
            self.fail(key, "must not be empty")
        return value

    def number(
        self, key: str, default: float | None = None, *, positive: bool = False, non_negative: bool = False
    ) -> float:
        if key not in self.data:
            if default is None:
                self.fail(key, "is missing")
            return default
        value = self.data[key]
        if not _is_number(value):
            self.fail(key, f"must be a number, got {_type(value)}")
        value = float(value)
        if not math.isfinite(value):
            self.fail(key, f"must be finite, got {value}")
        if positive and value <= 0:
            self.fail(key, f"must be positive, got {value:g}")
        if non_negative and value < 0:
            self.fail(key, f"must be >= 0, got {value:g}")
        return value

    def integer(self, key: str, *, minimum: int = 1) -> int:
        if key not in self.data:
            self.fail(key, "is missing")
        value = self.data[key]
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            self.fail(key, f"must be an integer, got {_type(value)}")
        if value < minimum:
            self.fail(key, f"must be >= {minimum}, got {value}")
        return int(value)

    def number_list(self, key: str) -> list[float]:
        if key not in self.data:
            self.fail(key, "is missing")
        value = self.data[key]
        if not isinstance(value, list):
            self.fail(key, f"must be a list of numbers, got {_type(value)}")
        if not value:
            self.fail(key, "must not be empty")
        out = []
        for i, item in enumerate(value):
            if not _is_number(item) or not math.isfinite(float(item)):
                self.fail(key, f"item {i} must be a finite number, got {excerpt(item)}")
            out.append(float(item))
        return out


def _type(value) -> str:
    return "null" if value is None else type(value).__name__


def _read_mapping(path: Path) -> dict:
    text = read_text_file(path, "sensor file", SensorError)
    try:
        data = load_yaml(text, f"sensor file {path}", SensorError)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        problem = clip(getattr(exc, "problem", None) or "syntax error")
        raise SensorError(f"sensor file {path}: invalid YAML{where} ({problem})") from None
    if not isinstance(data, dict):
        raise SensorError(f"sensor file {path}: expected a mapping of keys (name, min_range, ...), got {_type(data)}")
    return data


def load_sensor_yaml(path, *, integration_time: float | None = None) -> Sensor:
    """Reads a custom sensor from a YAML file.

    ``integration_time`` (seconds) overrides the file's ``integration_time`` for the
    pattern form; the elevation form does not accept it. Every problem raises
    :class:`~lf3pm.errors.SensorError` with a one-line message naming the file and key.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise SensorError(f"sensor file path must be a string or path, got {_type(path)}")
    path = Path(path).expanduser()
    data = _read_mapping(path)
    r = _Reader(path, data)

    for key in data:
        if not isinstance(key, str) or key not in ALLOWED_KEYS:
            raise SensorError(f"sensor file {path}: unknown key {excerpt(key)} (allowed: {', '.join(ALLOWED_KEYS)})")

    spinning = [k for k in _SPINNING_KEYS if k in data]
    pattern = [k for k in _PATTERN_KEYS if k in data]
    if spinning and pattern:
        raise SensorError(
            f"sensor file {path}: key '{pattern[0]}' cannot be combined with key '{spinning[0]}' "
            "(use either elevations_deg + azimuth_count or pattern_file + point_rate + "
            "integration_time)"
        )
    if not spinning and not pattern:
        raise SensorError(
            f"sensor file {path}: key 'elevations_deg' (with 'azimuth_count') or key "
            "'pattern_file' (with 'point_rate' and 'integration_time') is missing"
        )

    name = r.string("name")
    if len(name) > MAX_NAME:
        r.fail("name", f"must be at most {MAX_NAME} characters, got {len(name):,}: put the rest in 'description'")
    min_range = r.number("min_range", positive=True)
    max_range = r.number("max_range", positive=True)
    if max_range <= min_range:
        r.fail("max_range", f"({max_range:g}) must exceed min_range ({min_range:g})")
    sigma = r.number("range_noise_sigma", 0.0, non_negative=True)
    source = f"custom sensor file {path}"

    if spinning:
        if integration_time is not None:
            raise SensorError(
                f"sensor file {path}: integration_time applies only to the pattern_file form, "
                "not to a spinning sensor (elevations_deg)"
            )
        elevations = r.number_list("elevations_deg")
        for i, e in enumerate(elevations):
            if not -90.0 <= e <= 90.0:
                r.fail("elevations_deg", f"item {i} must lie in [-90, 90] degrees, got {e:g}")
        azimuth_count = r.integer("azimuth_count")
        fov_deg = r.number("horizontal_fov_deg", 360.0, positive=True)
        if fov_deg > 360.0:
            r.fail("horizontal_fov_deg", f"must be at most 360, got {fov_deg:g}")
        if len(elevations) * azimuth_count > MAX_RAYS:
            r.fail("azimuth_count", f"gives {len(elevations) * azimuth_count} rays, more than the limit of {MAX_RAYS}")
        fov = math.radians(fov_deg)
        dirs = spinning_directions(np.radians(elevations), azimuth_count, fov)
        default_description = (
            f"Custom spinning sensor '{name}': {len(elevations)} beams x {azimuth_count} "
            f"columns over {fov_deg:g} deg ({dirs.shape[0]} rays)."
        )
    else:
        pattern_name = r.string("pattern_file")
        pattern_path = Path(pattern_name).expanduser()
        if not pattern_path.is_absolute():
            pattern_path = path.parent / pattern_path
        if not pattern_path.exists():
            r.fail("pattern_file", f"names {pattern_path}, which does not exist")
        if not pattern_path.is_file():
            r.fail("pattern_file", f"names {pattern_path}, which is not a regular file")
        try:
            # Memory-mapped: its shape is checked before a row is read.
            pattern = np.load(pattern_path, mmap_mode="r", allow_pickle=False)
        except (OSError, ValueError, EOFError) as exc:
            reason = f" ({exc.strerror})" if isinstance(exc, OSError) and exc.strerror else ""
            r.fail("pattern_file", f"names {pattern_path}, which is not a readable numeric .npy array{reason}")
        if (
            not isinstance(pattern, np.ndarray)
            or pattern.ndim != 2
            or pattern.shape[1] != 2
            or pattern.shape[0] < 1
            or not np.issubdtype(pattern.dtype, np.number)
        ):
            r.fail(
                "pattern_file",
                f"names {pattern_path}, which must hold an (N, 2) numeric array of "
                f"azimuth/elevation in radians, got shape {getattr(pattern, 'shape', None)}",
            )
        if pattern.shape[0] > MAX_RAYS:
            r.fail(
                "pattern_file",
                f"names {pattern_path}, which holds {pattern.shape[0]:,} rays, more than the limit of {MAX_RAYS:,}",
            )
        pattern = np.asarray(pattern, dtype=np.float64)
        if not np.isfinite(pattern).all():
            r.fail("pattern_file", f"names {pattern_path}, which holds NaN or infinite angles")
        point_rate = r.number("point_rate", positive=True)
        t_file = r.number("integration_time", positive=True)
        t = t_file if integration_time is None else integration_time
        count = ray_count(point_rate, t, f"sensor file {path}")
        dirs = pattern_directions(pattern, count)
        # Horizontal extent actually covered by the pattern's azimuths.
        az = np.mod(pattern[:, 0] + math.pi, 2.0 * math.pi) - math.pi
        span = float(az.max() - az.min())
        fov = 2.0 * math.pi if span > 2.0 * math.pi - 1e-3 else max(span, 1e-6)
        default_description = (
            f"Custom pattern sensor '{name}': {count} rays from {pattern_path.name} "
            f"({t:g} s at {point_rate:g} points/s)."
        )

    description = r.string("description", default_description)
    returns = _returns(r) if r.has("return_probability") else None
    return Sensor(
        name=name,
        description=description,
        directions=dirs,
        min_range=min_range,
        max_range=max_range,
        range_noise_sigma=sigma,
        horizontal_fov=fov,
        approximate=False,
        source=source,
        returns=returns,
    )


def _returns(r: _Reader) -> ReturnModel:
    """The ``return_probability`` mapping: range_edges_m, cos_edges and table (a list of
    rows, one per range bin, each a value per cosine bin)."""
    value = r.data["return_probability"]
    keys = ("range_edges_m", "cos_edges", "table")
    if not isinstance(value, dict) or set(value) != set(keys):
        r.fail("return_probability", f"must be a mapping of {', '.join(keys)}")
    table = value["table"]
    if not isinstance(table, list) or not all(isinstance(row, list) for row in table):
        r.fail("return_probability", "table must be a list of rows (one per range bin)")
    inner = _Reader(r.path, value)
    try:
        return ReturnModel(inner.number_list("range_edges_m"), inner.number_list("cos_edges"), table)
    except SensorError as err:
        raise SensorError(f"sensor file {r.path}: key {err}") from None
