"""The :class:`Sensor` record and the ray-direction generators it is built from."""

from __future__ import annotations

import math
from dataclasses import dataclass
from dataclasses import field as dataclass_field

import numpy as np

from lf3pm import libm
from lf3pm.errors import SensorError

from ._returns import ReturnModel

#: Largest scan the helpers build (rays); beyond this a typo in a rate or time
#: would silently allocate gigabytes.
MAX_RAYS = 20_000_000

_UNIT_TOL = 1e-6
_TWO_PI = 2.0 * math.pi


def _is_number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


@dataclass(frozen=True)
class Sensor:
    """A LiDAR model: the rays of one scan plus range limits and noise.

    ``directions`` are K x 3 float64 unit vectors in the sensor frame (x forward,
    y left, z up), C-contiguous, in emission order. Ranges in metres,
    ``horizontal_fov`` in radians (2*pi for spinning sensors). ``returns``: which
    hits give a return (:class:`~lf3pm.sensors.ReturnModel`; None: all of them).
    """

    name: str
    description: str
    directions: np.ndarray
    min_range: float
    max_range: float
    range_noise_sigma: float
    horizontal_fov: float
    approximate: bool
    source: str
    #: Non-repetitive sensors (Livox): the whole recorded azimuth/elevation
    #: pattern, read as a ring buffer, so consecutive scans continue it.
    pattern: np.ndarray | None = dataclass_field(default=None, repr=False, compare=False)
    #: Which hits return (a fitted sensor's; lf3pm.sensors.ReturnModel); None: every hit.
    returns: ReturnModel | None = None

    def __post_init__(self):
        for field in ("name", "description", "source"):
            if not isinstance(getattr(self, field), str):
                raise SensorError(f"sensor {field} must be a string, got {type(getattr(self, field)).__name__}")
        if not self.name.strip():
            raise SensorError("sensor name must not be empty")
        label = f"sensor '{self.name}'"
        if self.returns is not None and not isinstance(self.returns, ReturnModel):
            raise SensorError(f"{label}: returns must be a ReturnModel or None")
        if not isinstance(self.approximate, (bool, np.bool_)):
            raise SensorError(f"{label}: approximate must be a bool")
        object.__setattr__(self, "approximate", bool(self.approximate))

        for field in ("min_range", "max_range", "range_noise_sigma", "horizontal_fov"):
            value = getattr(self, field)
            if not _is_number(value) or not math.isfinite(value):
                raise SensorError(f"{label}: {field} must be a finite number, got {value!r}")
            object.__setattr__(self, field, float(value))
        if self.min_range <= 0:
            raise SensorError(f"{label}: min_range must be positive, got {self.min_range}")
        if self.max_range <= self.min_range:
            raise SensorError(f"{label}: max_range ({self.max_range}) must exceed min_range ({self.min_range})")
        if self.range_noise_sigma < 0:
            raise SensorError(f"{label}: range_noise_sigma must be >= 0, got {self.range_noise_sigma}")
        if not 0 < self.horizontal_fov <= _TWO_PI + 1e-9:
            raise SensorError(f"{label}: horizontal_fov must be in (0, 2*pi] radians, got {self.horizontal_fov}")

        try:
            dirs = np.array(self.directions, dtype=np.float64, order="C", copy=True)
        except (TypeError, ValueError) as exc:
            raise SensorError(f"{label}: directions are not a numeric array ({exc})") from None
        if dirs.ndim != 2 or dirs.shape[1] != 3 or dirs.shape[0] < 1:
            raise SensorError(f"{label}: directions must have shape (K, 3) with K >= 1, got {dirs.shape}")
        if not np.isfinite(dirs).all():
            raise SensorError(f"{label}: directions contain NaN or infinite values")
        err = np.abs(np.linalg.norm(dirs, axis=1) - 1.0)
        if err.max() > _UNIT_TOL:
            bad = int(err.argmax())
            raise SensorError(
                f"{label}: direction {bad} is not a unit vector (|d| = {float(np.linalg.norm(dirs[bad])):.6g})"
            )
        # Read-only: presets are built once and shared (get_sensor), like the sensor itself.
        dirs.setflags(write=False)
        object.__setattr__(self, "directions", dirs)

    @property
    def num_rays(self) -> int:
        """Number of rays in one scan (K)."""
        return int(self.directions.shape[0])

    def scan_directions(self, index: int) -> np.ndarray:
        """The rays of consecutive scan ``index`` (0: ``directions``). A non-repetitive
        pattern goes on where the previous scan stopped, as the real sensor does; a
        spinning sensor repeats its rays."""
        if self.pattern is None or index == 0:
            return self.directions
        return pattern_directions(self.pattern, self.num_rays, index * self.num_rays)

    def angles(self) -> tuple[np.ndarray, np.ndarray]:
        """(azimuth, elevation) of every ray in radians; azimuth in (-pi, pi]."""
        d = self.directions
        return libm.atan2(d[:, 1], d[:, 0]), libm.arcsin(d[:, 2])

    # A numpy array field breaks the generated __eq__/__hash__; define both.
    def __eq__(self, other):
        if not isinstance(other, Sensor):
            return NotImplemented
        return (
            self.name == other.name
            and self.description == other.description
            and self.min_range == other.min_range
            and self.max_range == other.max_range
            and self.range_noise_sigma == other.range_noise_sigma
            and self.horizontal_fov == other.horizontal_fov
            and self.approximate == other.approximate
            and self.source == other.source
            and self.returns == other.returns
            and self.directions.shape == other.directions.shape
            and bool(np.array_equal(self.directions, other.directions))
        )

    def __hash__(self):
        return hash((self.name, self.num_rays, self.min_range, self.max_range))

    def __repr__(self):
        return (
            f"Sensor(name={self.name!r}, num_rays={self.num_rays}, min_range={self.min_range:g}, "
            f"max_range={self.max_range:g}, range_noise_sigma={self.range_noise_sigma:g}, "
            f"horizontal_fov={math.degrees(self.horizontal_fov):g} deg, approximate={self.approximate})"
        )


def directions_from_angles(azimuth, elevation) -> np.ndarray:
    """Unit ray directions (K x 3 float64) from azimuth/elevation arrays in radians."""
    az = np.asarray(azimuth, dtype=np.float64).reshape(-1)
    el = np.asarray(elevation, dtype=np.float64).reshape(-1)
    cos_el = np.cos(el)
    dirs = np.empty((az.size, 3), dtype=np.float64)
    dirs[:, 0] = cos_el * np.cos(az)
    dirs[:, 1] = cos_el * np.sin(az)
    dirs[:, 2] = np.sin(el)
    return dirs


def spinning_azimuths(azimuth_count: int, horizontal_fov: float = _TWO_PI) -> np.ndarray:
    """Column azimuths of a spinning sensor, in emission order.

    Full turn: ``2*pi*j/count`` for j = 0..count-1 (0 to 2*pi exclusive). A partial
    field of view is centred on +x with both edges included, swept from -fov/2 to
    +fov/2 (a single column looks along +x).
    """
    if horizontal_fov >= _TWO_PI - 1e-12:
        return _TWO_PI * np.arange(azimuth_count, dtype=np.float64) / azimuth_count
    if azimuth_count == 1:
        return np.zeros(1)
    return np.linspace(-0.5 * horizontal_fov, 0.5 * horizontal_fov, azimuth_count)


def spinning_directions(elevations, azimuth_count: int, horizontal_fov: float = _TWO_PI) -> np.ndarray:
    """Directions of a spinning multi-beam sensor, column by column.

    All beams (in the order of ``elevations``, radians) at the first azimuth, then
    all beams at the next azimuth, and so on; K = len(elevations) * azimuth_count.
    """
    el = np.asarray(elevations, dtype=np.float64).reshape(-1)
    az = spinning_azimuths(int(azimuth_count), float(horizontal_fov))
    if el.size * az.size > MAX_RAYS:
        raise SensorError(f"scan of {el.size * az.size} rays exceeds the limit of {MAX_RAYS}")
    return directions_from_angles(np.repeat(az, el.size), np.tile(el, az.size))


# Roberts' R2 sequence: additive recurrence with the plastic number, the
# 2-D generalisation of the golden ratio. Every prefix is well spread, so a
# longer integration time adds rays between the earlier ones, never repeats them.
_PLASTIC = 1.324717957244746025960908854
_R2 = (1.0 / _PLASTIC, 1.0 / _PLASTIC**2)


def r2_sequence(n: int) -> tuple[np.ndarray, np.ndarray]:
    """First ``n`` points of the R2 low-discrepancy sequence in [0, 1)^2."""
    i = np.arange(n, dtype=np.float64)
    u = np.mod(0.5 + _R2[0] * i, 1.0)
    v = np.mod(0.5 + _R2[1] * i, 1.0)
    return u, v


def band_directions(n: int, az_min: float, az_max: float, el_min: float, el_max: float) -> np.ndarray:
    """``n`` deterministic non-repetitive rays uniform in solid angle over a band.

    Azimuth uniform in [az_min, az_max), sin(elevation) uniform in
    [sin(el_min), sin(el_max)] (equal area), points taken from the R2 sequence in
    emission order.
    """
    u, v = r2_sequence(n)
    az = az_min + (az_max - az_min) * u
    z_lo, z_hi = math.sin(el_min), math.sin(el_max)
    el = libm.arcsin(z_lo + (z_hi - z_lo) * v)
    return directions_from_angles(az, el)


def ray_count(point_rate: float, integration_time: float, what: str) -> int:
    """Rays in one scan of ``point_rate`` points/s over ``integration_time`` s."""
    if not _is_number(integration_time) or not math.isfinite(integration_time) or integration_time <= 0:
        raise SensorError(f"{what}: integration_time must be a positive number of seconds, got {integration_time!r}")
    count = int(round(float(point_rate) * float(integration_time)))
    if count < 1:
        raise SensorError(f"{what}: integration_time {integration_time:g} s gives no rays at {point_rate:g} points/s")
    if count > MAX_RAYS:
        raise SensorError(
            f"{what}: integration_time {integration_time:g} s gives {count} rays, more than the limit of {MAX_RAYS}"
        )
    return count


def pattern_directions(pattern: np.ndarray, count: int, start: int = 0) -> np.ndarray:
    """``count`` rays of an (N, 2) azimuth/elevation pattern from ray ``start``, read as a ring buffer."""
    idx = (start + np.arange(count)) % pattern.shape[0]
    rows = pattern[idx]
    return directions_from_angles(rows[:, 0], rows[:, 1])


def spinning_rings(sensor: Sensor) -> np.ndarray | None:
    """Ring (beam) index of every ray (K,) of a spinning sensor, 0 for its lowest
    beam; None for a sensor whose rays do not come in columns of one set of
    beams (Livox patterns). A spinning sensor lists its rays column by column,
    the beams of a column sharing one azimuth."""
    azimuth, elevation = sensor.angles()
    same = np.abs(np.remainder(azimuth - azimuth[0] + np.pi, 2 * np.pi) - np.pi) < 1e-9
    beams = int(np.argmin(same)) if not same.all() else len(same)
    if sensor.num_rays % beams:
        return None
    columns = elevation.reshape(-1, beams)
    if not np.allclose(columns, columns[0], atol=1e-9):
        return None
    return np.tile(np.argsort(np.argsort(columns[0], kind="stable"), kind="stable"), len(columns))
