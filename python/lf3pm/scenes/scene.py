"""The Scene record, and the parameter checking and finishing shared by the builders."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from lf3pm.errors import Lf3pmError

#: The band above the ground at the reference pose that must be empty within
#: ``free_radius``: from this height (m) ...
FREE_BAND_LOW = 0.2
#: ... up to this one (m).
FREE_BAND_HIGH = 2.5
#: The flight scenes' start and goal volumes keep this far (m) from the map: no map
#: point lies within this distance of any point of the box.
VOLUME_CLEARANCE = 0.6


class Zone(NamedTuple):
    """An axis-aligned rectangle of the ground, metres: xmin <= x <= xmax, ymin <= y <= ymax."""

    xmin: float
    ymin: float
    xmax: float
    ymax: float

    def contains(self, x, y):
        """Whether (x, y) lies in the zone (arrays broadcast)."""
        return (
            (np.asarray(x) >= self.xmin)
            & (np.asarray(x) <= self.xmax)
            & (np.asarray(y) >= self.ymin)
            & (np.asarray(y) <= self.ymax)
        )


class Volume(NamedTuple):
    """An axis-aligned box of space, metres: xmin <= x <= xmax, ymin <= y <= ymax,
    zmin <= z <= zmax."""

    xmin: float
    ymin: float
    zmin: float
    xmax: float
    ymax: float
    zmax: float

    @property
    def centre(self) -> tuple:
        """(x, y, z) of the box's centre."""
        return ((self.xmin + self.xmax) / 2, (self.ymin + self.ymax) / 2, (self.zmin + self.zmax) / 2)

    def contains(self, x, y, z):
        """Whether (x, y, z) lies in the box (arrays broadcast)."""
        x, y, z = (np.asarray(a) for a in (x, y, z))
        return (
            (x >= self.xmin)
            & (x <= self.xmax)
            & (y >= self.ymin)
            & (y <= self.ymax)
            & (z >= self.zmin)
            & (z <= self.zmax)
        )

    def distance(self, points) -> np.ndarray:
        """The Euclidean distance (m) from each row of the N x 3 ``points`` to the
        nearest point of the box (0 inside it)."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        lower = np.array([self.xmin, self.ymin, self.zmin])
        upper = np.array([self.xmax, self.ymax, self.zmax])
        return np.linalg.norm(np.maximum(np.maximum(lower - points, points - upper), 0.0), axis=1)


@dataclass(frozen=True, eq=False)
class Scene:
    """A procedural test scene: a point-cloud map and a known free sensor pose.

    points: N x 3 float64, C-contiguous, read-only. reference_pose: (x, y, z,
    yaw) = (0, 0, sensor_height above the ground at the origin, 0).
    free_radius: no map point lies within this horizontal distance (m) of the
    reference pose's x, y between ``FREE_BAND_LOW`` and ``FREE_BAND_HIGH``
    above the ground there. params: every parameter the scene was built with,
    defaults included. zones: named ground rectangles (:class:`Zone`) that
    planning studies draw start and goal positions from (docs/scenes.md says
    which pairs; a drawn position can still fall on an obstacle, so a study
    checks it against the SOLM's traversable cells). volumes: named boxes of free
    space (:class:`Volume`) that flights start and end in (the flight scenes':
    ``start`` and ``goal``); no map point lies within ``VOLUME_CLEARANCE`` of one.
    """

    name: str
    points: np.ndarray = field(repr=False)
    reference_pose: tuple
    free_radius: float
    description: str
    seed: int
    params: dict
    zones: dict = field(default_factory=dict)
    volumes: dict = field(default_factory=dict)

    @property
    def size(self) -> int:
        return len(self.points)

    @property
    def ground_z(self) -> float:
        """Height of the ground under the reference pose."""
        return float(self.reference_pose[2] - self.params["sensor_height"])


def check_seed(seed) -> int:
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise Lf3pmError(f"seed must be an integer >= 0, got {seed!r}")
    return int(seed)


def resolve_params(scene: str, defaults: dict, given: dict) -> dict:
    """``defaults`` updated by ``given``, each value checked against its default's type:
    integers stay integers >= 0, numbers are finite and >= 0, flags are bools."""
    unknown = sorted(set(given) - set(defaults))
    if unknown:
        raise Lf3pmError(
            f"scene {scene!r} has no parameter {unknown[0]!r}; its parameters: {', '.join(sorted(defaults))}"
        )
    params = dict(defaults)
    for key, value in given.items():
        default = defaults[key]
        if isinstance(default, bool):
            ok = isinstance(value, (bool, np.bool_))
            value = bool(value) if ok else value
        elif isinstance(default, numbers.Integral):
            ok = isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= 0
            value = int(value) if ok else value
        else:
            ok = isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value) and value >= 0
            value = float(value) if ok else value
        if not ok:
            kind = (
                "true or false"
                if isinstance(default, bool)
                else "an integer >= 0"
                if isinstance(default, numbers.Integral)
                else "a finite number >= 0"
            )
            raise Lf3pmError(f"scene {scene!r}: parameter {key!r} must be {kind}, got {value!r}")
        params[key] = value
    return params


def require(condition: bool, scene: str, message: str) -> None:
    """Raises a one-line Lf3pmError about ``scene`` unless ``condition`` holds."""
    if not condition:
        raise Lf3pmError(f"scene {scene!r}: {message}")


def free_band_violations(points: np.ndarray, x: float, y: float, ground_z: float, radius: float) -> np.ndarray:
    """The points within ``radius`` (horizontally) of (x, y) between
    ground_z + FREE_BAND_LOW and ground_z + FREE_BAND_HIGH."""
    near = np.hypot(points[:, 0] - x, points[:, 1] - y) < radius
    z = points[:, 2] - ground_z
    return points[near & (z >= FREE_BAND_LOW) & (z <= FREE_BAND_HIGH)]


def mow(points: np.ndarray, x: float, y: float, radius: float, ground, height: float) -> np.ndarray:
    """Drops the points within ``radius`` of (x, y) more than ``height`` above the
    terrain ``ground`` (a mowed patch)."""
    near = np.hypot(points[:, 0] - x, points[:, 1] - y) < radius
    high = points[:, 2] - ground(points[:, 0], points[:, 1]) > height
    return points[~(near & high)]


def finish(
    name: str,
    description: str,
    seed: int,
    params: dict,
    points: np.ndarray,
    ground_z: float = 0.0,
    zones: dict | None = None,
    volumes: dict | None = None,
) -> Scene:
    """Packs the points into a Scene, after checking that the reference pose and the
    ``volumes`` (name -> (xmin, ymin, zmin, xmax, ymax, zmax)) are free."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    require(params["sensor_height"] > 0, name, "sensor_height must be > 0")
    radius = params["free_radius"]
    bad = free_band_violations(points, 0.0, 0.0, ground_z, radius)
    if len(bad):
        closest = float(np.hypot(bad[:, 0], bad[:, 1]).min())
        require(
            False,
            name,
            f"free_radius {radius:g} m is too large: {len(bad)} points of the scene "
            f"lie within it (the closest {closest:.2f} m from the origin)",
        )
    volumes = {key: Volume(*map(float, box)) for key, box in (volumes or {}).items()}
    for key, volume in volumes.items():
        gap = float(volume.distance(points).min()) if len(points) else math.inf
        require(
            gap >= VOLUME_CLEARANCE,
            name,
            f"the {key} volume {tuple(volume)} is not free: a map point lies {gap:.2f} m from it "
            f"(at least {VOLUME_CLEARANCE:g} m needed); change the parameters",
        )
    points.setflags(write=False)
    pose = (0.0, 0.0, float(ground_z + params["sensor_height"]), 0.0)
    zones = {key: Zone(*map(float, rect)) for key, rect in (zones or {}).items()}
    return Scene(
        name=name,
        points=points,
        reference_pose=pose,
        free_radius=float(radius),
        description=description,
        seed=seed,
        params=dict(params),
        zones=zones,
        volumes=volumes,
    )
