"""A point-cloud map with everything a simulated scan needs, computed once.

``load_map`` reads the file (see :mod:`lf3pm.io`), optionally voxel-downsamples
it, and builds the C++ index: the points sorted by voxel with a k-NN grid, each
point's neighbourhood plane (FAST-LIO's association plane: ``knn`` neighbours,
valid when all lie within ``plane_threshold`` of it and the farthest within
``max_neighbor_distance``) and surfel disc, and the ray caster over the discs.
"""

from __future__ import annotations

import hashlib
import os
import warnings
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from lf3pm import _core
from lf3pm.config import MapConfig, check_threads, validated
from lf3pm.errors import MapError, PoseError
from lf3pm.io import load_points, voxel_downsample

#: The index's defaults (C++ MapParams, through lf3pm.config).
_DEFAULT = MapConfig()


@dataclass(frozen=True)
class Map:
    """An indexed map. ``points`` are in index order (sorted by voxel)."""

    index: _core.MapIndex
    source: str
    sha256: str
    association_params: dict

    @property
    def points(self) -> np.ndarray:
        return self.index.points

    @property
    def size(self) -> int:
        return self.index.size

    @cached_property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned bounding box (lower, upper) of the points."""
        pts = self.index.points
        return pts.min(axis=0), pts.max(axis=0)

    def check_pose(self, matrix: np.ndarray, clearance: float = 0.1) -> None:
        """Raises PoseError when the sensor at ``matrix`` (4 x 4) lies outside the
        map's x-y extent or has a map point closer than ``clearance`` metres."""
        lower, upper = self.bounds
        xy = matrix[:2, 3]
        if np.any(xy < lower[:2]) or np.any(xy > upper[:2]):
            raise PoseError(f"pose x, y = {xy.tolist()} lies outside the map's extent "
                            f"x [{lower[0]:.2f}, {upper[0]:.2f}], y [{lower[1]:.2f}, {upper[1]:.2f}]")
        if clearance > 0:
            _, dist = self.index.nearest(np.ascontiguousarray(matrix[None, :3, 3]), 1, clearance)
            if np.isfinite(dist[0, 0]):
                raise PoseError(f"pose {matrix[:3, 3].tolist()} lies inside an obstacle: a map point "
                                f"is {dist[0, 0]:.3f} m from the sensor (clearance {clearance} m)")

    def describe(self) -> dict:
        lower, upper = self.bounds
        return {
            "source": self.source,
            "sha256": self.sha256,
            "points": self.size,
            "duplicates_removed": self.index.duplicates_removed,
            "cell_size": self.index.cell_size,
            "median_spacing": self.index.median_spacing,
            "bounds": [lower.tolist(), upper.tolist()],
            "memory_mb": round(self.index.memory_bytes / 2**20, 1),
        }


def load_map(source, *, voxel: float | None = None, cell_size: float = _DEFAULT.cell_size,
             knn: int = _DEFAULT.knn, plane_threshold: float = _DEFAULT.plane_threshold,
             max_neighbor_distance: float = _DEFAULT.max_neighbor_distance, threads: int = 0) -> Map:
    """Reads a map file (or takes an N x 3 array) and indexes it.

    ``voxel`` downsamples the map first (one centroid per voxel); ``cell_size``
    0 lets the index choose its voxel edge from the point spacing; the association
    parameters are FAST-LIO's (:class:`lf3pm.config.MapConfig`, which validates them).
    """
    config = validated(MapConfig, "map", voxel=voxel, cell_size=cell_size, knn=knn,
                       plane_threshold=plane_threshold, max_neighbor_distance=max_neighbor_distance)
    threads = check_threads(threads)
    if isinstance(source, (str, os.PathLike)):
        points = load_points(source, voxel=voxel)
        name = os.fspath(source)
    else:
        points = np.asarray(source, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 3:
            raise MapError(f"map array must be N x 3, got shape {points.shape}")
        finite = np.all(np.isfinite(points), axis=1)
        points = points[finite]
        if voxel:
            points = voxel_downsample(points, voxel)
        name = "<array>"
    points = np.ascontiguousarray(points, dtype=np.float64)
    if len(points) < knn:
        raise MapError(f"{name}: the map has {len(points)} points, fewer than knn = {knn}")
    digest = hashlib.sha256(points.tobytes()).hexdigest()
    try:
        index = _core.MapIndex(points, config.core(threads))
    except ValueError as err:
        raise MapError(f"{name}: {err}") from None
    if index.duplicates_removed:
        warnings.warn(f"{name}: {index.duplicates_removed} duplicate points dropped", UserWarning,
                      stacklevel=2)
    return Map(index=index, source=name, sha256=digest,
               association_params=config.association_params())
