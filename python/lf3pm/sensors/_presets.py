"""Built-in sensor presets, from the manufacturers' published figures.

Where a figure is not on the datasheet (a blind zone, a 1-sigma noise derived
from a +-accuracy), the ``source`` string of the preset says so.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from lf3pm.errors import SensorError

from ._model import Sensor, band_directions, pattern_directions, ray_count, spinning_directions

PATTERN_DIR = Path(__file__).resolve().parent / "patterns"
DEFAULT_INTEGRATION_TIME = 0.1  # s: one 10 Hz frame, the Livox default


@dataclass(frozen=True)
class _Preset:
    name: str
    aliases: tuple[str, ...]
    build: Callable[[float | None], Sensor]
    non_repetitive: bool


def _no_integration_time(name: str, integration_time: float | None) -> None:
    if integration_time is not None:
        raise SensorError(
            f"sensor '{name}' is a spinning sensor that repeats every revolution; "
            "integration_time applies only to non-repetitive (Livox or pattern-file) sensors"
        )


def _spinning(
    name: str,
    description: str,
    elevations_deg,
    azimuth_count: int,
    min_range: float,
    max_range: float,
    sigma: float,
    source: str,
) -> Callable[[float | None], Sensor]:
    def build(integration_time: float | None) -> Sensor:
        _no_integration_time(name, integration_time)
        dirs = spinning_directions(np.radians(np.asarray(elevations_deg, dtype=np.float64)), azimuth_count)
        return Sensor(
            name=name,
            description=description,
            directions=dirs,
            min_range=min_range,
            max_range=max_range,
            range_noise_sigma=sigma,
            horizontal_fov=2.0 * math.pi,
            approximate=False,
            source=source,
        )

    return build


@cache
def load_pattern(filename: str) -> np.ndarray:
    """A bundled Livox pattern file as a read-only (N, 2) float64 azimuth/elevation array."""
    path = PATTERN_DIR / filename
    try:
        data = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise SensorError(f"bundled scan pattern {path} cannot be read ({exc})") from None
    data = np.ascontiguousarray(data, dtype=np.float64)
    if data.ndim != 2 or data.shape[1] != 2 or data.shape[0] < 1 or not np.isfinite(data).all():
        raise SensorError(f"bundled scan pattern {path} is not a finite (N, 2) array")
    data.setflags(write=False)
    return data


def _livox_pattern(
    name: str,
    description: str,
    filename: str,
    point_rate: float,
    fov_deg: float,
    min_range: float,
    max_range: float,
    sigma: float,
    source: str,
) -> Callable[[float | None], Sensor]:
    def build(integration_time: float | None) -> Sensor:
        t = DEFAULT_INTEGRATION_TIME if integration_time is None else integration_time
        count = ray_count(point_rate, t, f"sensor '{name}'")
        pattern = load_pattern(filename)
        dirs = pattern_directions(pattern, count)
        return Sensor(
            name=name,
            description=f"{description} {count} rays ({t:g} s at {point_rate:g} points/s).",
            directions=dirs,
            min_range=min_range,
            max_range=max_range,
            range_noise_sigma=sigma,
            horizontal_fov=math.radians(fov_deg),
            approximate=False,
            source=source,
            pattern=pattern,
        )

    return build


def _livox_band(
    name: str,
    description: str,
    point_rate: float,
    az_deg: tuple[float, float],
    el_deg: tuple[float, float],
    min_range: float,
    max_range: float,
    sigma: float,
    source: str,
) -> Callable[[float | None], Sensor]:
    def build(integration_time: float | None) -> Sensor:
        t = DEFAULT_INTEGRATION_TIME if integration_time is None else integration_time
        count = ray_count(point_rate, t, f"sensor '{name}'")
        az0, az1 = (math.radians(a) for a in az_deg)
        el0, el1 = (math.radians(e) for e in el_deg)
        dirs = band_directions(count, az0, az1, el0, el1)
        return Sensor(
            name=name,
            description=f"{description} {count} rays ({t:g} s at {point_rate:g} points/s).",
            directions=dirs,
            min_range=min_range,
            max_range=max_range,
            range_noise_sigma=sigma,
            horizontal_fov=az1 - az0,
            approximate=True,
            source=source,
        )

    return build


VLP16_ELEVATIONS_DEG = tuple(float(e) for e in range(-15, 16, 2))  # 16 beams, 2 deg apart
HDL32_ELEVATIONS_DEG = tuple(float(x) for x in np.linspace(-92.0 / 3.0, 32.0 / 3.0, 32))  # -30.67..+10.67, 4/3 deg
OS1_64_ELEVATIONS_DEG = tuple(float(x) for x in np.linspace(-22.5, 22.5, 64))  # uniform beam spacing

_PRESETS: tuple[_Preset, ...] = (
    _Preset(
        "vlp16",
        ("vlp-16", "puck"),
        _spinning(
            "vlp16",
            "Velodyne VLP-16 (Puck): 16 beams from -15 to +15 deg every 2 deg, 1800 columns per turn "
            "(0.2 deg at 10 Hz), 28,800 rays per scan. Beams listed bottom to top within each column "
            "(the real firing order interleaves them).",
            VLP16_ELEVATIONS_DEG,
            1800,
            0.5,
            100.0,
            0.015,
            "Velodyne VLP-16 datasheet: 16 channels, 30 deg vertical FoV (+-15 deg), 2 deg vertical "
            "resolution, 0.1-0.4 deg horizontal resolution (0.2 deg at 600 rpm = 10 Hz), range up to 100 m, "
            "range accuracy +-3 cm typical. sigma 0.015 m reads +-3 cm as a 2-sigma bound (assumption). "
            "min_range 0.5 m is an assumed blind zone (not on the datasheet).",
        ),
        False,
    ),
    _Preset(
        "hdl32",
        ("hdl-32", "hdl32e", "hdl-32e"),
        _spinning(
            "hdl32",
            "Velodyne HDL-32E: 32 beams from -30.67 to +10.67 deg (1.33 deg spacing), 2170 columns per turn "
            "(about 0.166 deg at 10 Hz), 69,440 rays per scan. Beams listed bottom to top within each column.",
            HDL32_ELEVATIONS_DEG,
            2170,
            1.0,
            100.0,
            0.01,
            "Velodyne HDL-32E datasheet: 32 channels, +10.67 to -30.67 deg vertical FoV, 1.33 deg vertical "
            "resolution, about 0.16 deg horizontal resolution at 10 Hz (about 695,000 points/s / 32 beams / "
            "10 Hz = 2170 columns), range up to 100 m, accuracy < +-2 cm. sigma 0.01 m reads +-2 cm as a "
            "2-sigma bound (assumption). min_range 1 m is an assumed blind zone.",
        ),
        False,
    ),
    _Preset(
        "os1-64",
        ("os1_64", "os1", "ouster"),
        _spinning(
            "os1-64",
            "Ouster OS1-64 (uniform beam spacing): 64 beams evenly over -22.5..+22.5 deg, 1024 columns "
            "per turn (1024x10 mode), 65,536 rays per scan. Per-beam azimuth offsets of the real sensor are "
            "not modelled (each column shares one azimuth). Beams listed bottom to top within each column.",
            OS1_64_ELEVATIONS_DEG,
            1024,
            0.3,
            120.0,
            0.015,
            "Ouster OS1-64 datasheet: 64 channels, 45 deg vertical FoV (+22.5 to -22.5 deg) with uniform "
            "beam spacing, horizontal resolution 512/1024/2048 columns at 10 or 20 Hz (1024x10 used), "
            "range 0.3 to 120 m as used here. sigma 0.015 m is a representative value chosen for this model: "
            "the datasheet gives range- and reflectivity-dependent precision, not one sigma.",
        ),
        False,
    ),
    _Preset(
        "mid40",
        ("mid-40",),
        _livox_pattern(
            "mid40",
            "Livox Mid-40: non-repetitive rosette scan in a 38.4 deg circular field of view around +x, "
            "rays from the recorded Mid-40 scan pattern (bundled mid40.npy, read as a ring buffer);",
            "mid40.npy",
            100_000.0,
            38.4,
            0.1,
            130.0,
            0.02,
            "Livox Mid-40/Mid-100 specifications and user manual: 38.4 deg circular FoV, 100,000 points/s, "
            "detection range 90 m @ 10 % / 130 m @ 20 % reflectivity (130 m used), range precision 2 cm "
            "(1 sigma, used as sigma 0.02 m). min_range 0.1 m is assumed (no blind zone is stated in those "
            "figures). Scan pattern: mid40.npy from GitHub TATP-233/MuJoCo-LiDAR (MIT), commit 22c0826.",
        ),
        True,
    ),
    _Preset(
        "mid70",
        ("mid-70",),
        _livox_pattern(
            "mid70",
            "Livox Mid-70: non-repetitive rosette scan in a 70.4 deg circular field of view around +x, "
            "rays from the recorded Mid-70 scan pattern (bundled mid70.npy, read as a ring buffer);",
            "mid70.npy",
            100_000.0,
            70.4,
            0.05,
            130.0,
            0.02,
            "Livox Mid-70 specifications and user manual: 70.4 deg circular FoV, 100,000 points/s, "
            "minimal detection range 0.05 m, detection range 90 m @ 10 % / 130 m @ 20 % reflectivity "
            "(130 m used), range random error 2 cm (1 sigma @ 20 m, used as sigma 0.02 m). Scan pattern: "
            "mid70.npy from GitHub TATP-233/MuJoCo-LiDAR (MIT), commit 22c0826.",
        ),
        True,
    ),
    _Preset(
        "mid360",
        ("mid-360",),
        _livox_band(
            "mid360",
            "Livox Mid-360, APPROXIMATE pattern: no recorded Mid-360 pattern is bundled, so rays are a "
            "deterministic low-discrepancy sequence (R2 / generalised golden ratio) uniform in solid angle "
            "over the published field of view, 360 deg horizontal x -7..+52 deg vertical; the real "
            "pattern's density and its evolution over time differ;",
            200_000.0,
            (0.0, 360.0),
            (-7.0, 52.0),
            0.1,
            70.0,
            0.02,
            "Livox Mid-360 specifications and user manual: FoV 360 deg horizontal x -7 to 52 deg vertical, "
            "200,000 points/s, 10 Hz typical frame rate, close-proximity blind zone 0.1 m, detection range "
            "40 m @ 10 % / 70 m @ 80 % reflectivity (70 m used), range precision 2 cm (1 sigma, used as "
            "sigma 0.02 m). Beam layout modelled, not measured.",
        ),
        True,
    ),
    _Preset(
        "avia",
        (),
        _livox_band(
            "avia",
            "Livox Avia, APPROXIMATE pattern: no recorded Avia pattern is bundled, so rays are a "
            "deterministic low-discrepancy sequence (R2 / generalised golden ratio) uniform in solid angle "
            "over the published non-repetitive field of view, 70.4 deg horizontal x 77.2 deg vertical "
            "centred on +x (azimuth and elevation ranges); the real rosette is denser at the centre;",
            240_000.0,
            (-35.2, 35.2),
            (-38.6, 38.6),
            1.0,
            190.0,
            0.02,
            "Livox Avia specifications: non-repetitive scanning FoV 70.4 x 77.2 deg, 240,000 points/s "
            "(first return), detection range 190 m @ 10 % reflectivity (190 m used), range precision "
            "2 cm (1 sigma, used as sigma 0.02 m). min_range 1 m as used by this model. Beam layout "
            "modelled, not measured.",
        ),
        True,
    ),
)

PRESET_NAMES: tuple[str, ...] = tuple(p.name for p in _PRESETS)


def _normalise(name: str) -> str:
    return "".join(ch for ch in name.strip().lower() if ch not in " -_")


_LOOKUP: dict[str, _Preset] = {}
for _p in _PRESETS:
    for _key in (_p.name, *_p.aliases):
        _LOOKUP[_normalise(_key)] = _p
del _p, _key


_MAKERS = ("velodyne", "ouster", "livox")


def find_preset(name: str) -> _Preset | None:
    """The preset called ``name`` (case-, space-, '-' and '_'-insensitive, maker prefix
    allowed: "Velodyne VLP-16", "Livox Mid-70"), or None."""
    key = _normalise(name)
    if key in _LOOKUP:
        return _LOOKUP[key]
    for maker in _MAKERS:
        if key.startswith(maker) and key[len(maker) :] in _LOOKUP:
            return _LOOKUP[key[len(maker) :]]
    return None


def presets() -> tuple[_Preset, ...]:
    return _PRESETS
