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
    checks it against the SOLM's traversable cells).
    """

    name: str
    points: np.ndarray = field(repr=False)
    reference_pose: tuple
    free_radius: float
    description: str
    seed: int
    params: dict
    zones: dict = field(default_factory=dict)

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
) -> Scene:
    """Packs the points into a Scene, after checking that the reference pose is free."""
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
    )
