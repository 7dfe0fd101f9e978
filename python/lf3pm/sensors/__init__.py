"""LiDAR sensor models: the ray directions of one scan, range limits and noise.

Conventions: metres, radians, seconds. Sensor frame x forward, y left, z up;
azimuth about +z from +x, elevation up from the x-y plane; a ray direction is
``(cos(el) cos(az), cos(el) sin(az), sin(el))``.

Presets (``list_sensors()`` order; names are case-insensitive and ignore ``-``,
``_`` and spaces, so ``"VLP-16"``, ``"vlp_16"`` and ``"vlp16"`` are the same):

============  ===========================  =====================  ==============
name          aliases                      rays per scan           notes
============  ===========================  =====================  ==============
``vlp16``     vlp-16, puck                 16 x 1800 = 28,800      spinning
``hdl32``     hdl-32e, hdl32e              32 x 2170 = 69,440      spinning
``os1-64``    os1_64, os1, ouster          64 x 1024 = 65,536      spinning
``mid40``     mid-40                       100,000/s x t           recorded pattern
``mid70``     mid-70                       100,000/s x t           recorded pattern
``mid360``    mid-360                      200,000/s x t           approximate
``avia``      Livox Avia                   240,000/s x t           approximate
============  ===========================  =====================  ==============

Spinning sensors emit column by column (all beams at azimuth 0, bottom to top,
then the next azimuth; azimuths 0 to 2*pi exclusive) and take no integration
time. Livox sensors take ``integration_time`` t (default 0.1 s): the scan has
``round(point_rate * t)`` rays. Mid-40/Mid-70 read the bundled recorded patterns
(``patterns/``, MIT, from TATP-233/MuJoCo-LiDAR) as a ring buffer; Mid-360 and
Avia have no recorded pattern here and use a deterministic low-discrepancy
(R2) sequence, uniform in solid angle over the published field of view
(``approximate=True``).

Custom sensors: a YAML file, passed to :func:`get_sensor` as a path or read
with :func:`load_sensor_yaml`. Keys:

- ``name`` (string, required), ``description`` (string, optional)
- ``min_range``, ``max_range`` (metres, required, 0 < min < max)
- ``range_noise_sigma`` (metres, 1-sigma Gaussian range noise, default 0)
- ``return_probability`` (optional; `lf3pm sensors fit` writes it): ``range_edges_m``,
  ``cos_edges`` (|cos incidence|, in [0, 1]) and ``table`` (one row per range bin, a
  probability per cosine bin): the chance that a ray hitting a surface there returns
  (:class:`ReturnModel`); without it every hit returns
- then EITHER a spinning sensor:

  - ``elevations_deg``: list of beam elevations in degrees, in firing order
  - ``azimuth_count``: positive integer, columns per scan
  - ``horizontal_fov_deg``: optional, default 360; a partial field of view is
    centred on +x, swept from -fov/2 to +fov/2 with both edges included

- OR a pattern sensor:

  - ``pattern_file``: ``.npy`` array (N, 2) of azimuth, elevation in radians,
    in emission order; a relative path is relative to the YAML file
  - ``point_rate``: points per second
  - ``integration_time``: seconds per scan (``get_sensor(...,
    integration_time=...)`` overrides it); the scan is the first
    ``round(point_rate * integration_time)`` rows, read as a ring buffer

Example::

    name: my-16-beam
    description: 16 beams, 10 Hz, 0.2 deg columns
    min_range: 0.5
    max_range: 100.0
    range_noise_sigma: 0.015
    elevations_deg: [-15, -13, -11, -9, -7, -5, -3, -1, 1, 3, 5, 7, 9, 11, 13, 15]
    azimuth_count: 1800

Unknown keys, missing keys, wrong types, both or neither form, and a missing or
malformed pattern file raise :class:`~lf3pm.errors.SensorError` with one line
naming the file and the key. See ``docs/sensors.md``.
"""

from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path

from lf3pm.errors import SensorError

from ._model import Sensor, directions_from_angles, spinning_directions, spinning_rings
from ._presets import DEFAULT_INTEGRATION_TIME, PRESET_NAMES, find_preset, presets
from ._returns import ReturnModel
from ._yaml import load_sensor_yaml

__all__ = [
    "ReturnModel",
    "Sensor",
    "SensorError",
    "as_sensor",
    "get_sensor",
    "list_sensors",
    "load_sensor_yaml",
    "PRESET_NAMES",
    "spinning_rings",
    "spinning_directions",
    "directions_from_angles",
    "DEFAULT_INTEGRATION_TIME",
]


def _known() -> str:
    return ", ".join(PRESET_NAMES)


def get_sensor(name_or_path, *, integration_time: float | None = None) -> Sensor:
    """A preset by name (case-insensitive, aliases accepted) or a sensor YAML file.

    ``integration_time`` (seconds) sets the scan length of non-repetitive sensors
    (Livox presets, YAML pattern sensors); spinning sensors reject it.
    Unknown names raise :class:`~lf3pm.errors.SensorError` listing the presets.
    """
    if isinstance(name_or_path, os.PathLike):
        return load_sensor_yaml(name_or_path, integration_time=integration_time)
    if not isinstance(name_or_path, str):
        raise SensorError(f"sensor must be a preset name or a YAML path, got {type(name_or_path).__name__}")
    preset = find_preset(name_or_path)
    if preset is not None:
        return _built_preset(preset.name, integration_time)
    text = name_or_path.strip()
    if text.lower().endswith((".yaml", ".yml")) or "/" in text or os.sep in text or Path(text).expanduser().is_file():
        return load_sensor_yaml(text, integration_time=integration_time)
    raise SensorError(f"unknown sensor '{name_or_path}'; known sensors: {_known()} (or a path to a .yaml sensor file)")


@lru_cache(maxsize=64)
def _built_preset(name: str, integration_time: float | None) -> Sensor:
    """A preset built once per process: building the VLP-16's rays costs 2.4 ms and the
    OS1-64's 10 ms, more than a cast, and Sensor is immutable (read-only directions)."""
    return find_preset(name).build(integration_time)


def as_sensor(sensor) -> Sensor:
    """``sensor`` itself when it is a Sensor, else :func:`get_sensor` of it (a preset name
    or a YAML path)."""
    return sensor if isinstance(sensor, Sensor) else get_sensor(sensor)


def list_sensors() -> list[Sensor]:
    """All presets, in a stable order, each at its default integration time."""
    return [p.build(None) for p in presets()]
