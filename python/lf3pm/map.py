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
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from lf3pm import _core
from lf3pm.config import DEFAULTS, MapConfig, check_threads, validated
from lf3pm.errors import MapError, PoseError
from lf3pm.io import load_points, voxel_downsample


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

    def check_pose(self, matrix: np.ndarray, clearance: float = DEFAULTS.scan.clearance) -> None:
        """Raises PoseError when the sensor at ``matrix`` (4 x 4) lies outside the
        map's x-y extent or has a map point closer than ``clearance`` metres."""
        lower, upper = self.bounds
        xy = matrix[:2, 3]
        if np.any(xy < lower[:2]) or np.any(xy > upper[:2]):
            raise PoseError(
                f"pose x, y = {xy.tolist()} lies outside the map's extent "
                f"x [{lower[0]:.2f}, {upper[0]:.2f}], y [{lower[1]:.2f}, {upper[1]:.2f}]"
            )
        if clearance > 0:
            _, dist = self.index.nearest(np.ascontiguousarray(matrix[None, :3, 3]), 1, clearance)
            if np.isfinite(dist[0, 0]):
                raise PoseError(
                    f"pose {matrix[:3, 3].tolist()} lies inside an obstacle: a map point "
                    f"is {dist[0, 0]:.3f} m from the sensor (clearance {clearance} m)"
                )

    @property
    def frame(self) -> _core.MapFrame:
        """The frame of the map's index (in which its crops are indexed)."""
        return self.index.frame

    def crop(self, bounds, margin: float, threads: int = DEFAULTS.scan.threads) -> Map:
        """The points within ``margin`` m (in x, y) of ``bounds`` (xmin, ymin, xmax,
        ymax), indexed in this map's frame: a point whose k nearest neighbours all lie
        in the crop has this map's plane and disc there, and a ray that stays within
        the crop hits what it hits here (see :func:`crop_points`)."""
        return crop_points(
            self.points,
            self.frame,
            self.association_params,
            bounds,
            margin,
            source=self.source,
            sha256=self.sha256,
            threads=threads,
        )

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


def crop_points(
    points: np.ndarray,
    frame: _core.MapFrame,
    association_params: dict,
    bounds,
    margin: float,
    *,
    source: str,
    sha256: str,
    threads: int = DEFAULTS.scan.threads,
) -> Map:
    """The crop (bounds grown by ``margin`` in x and y, every z) of a map's ``points``
    (in its index order), indexed in the map's ``frame`` with its association
    parameters. The crop keeps the points' order, and its grids share the map's
    origins and cell size, so its index repeats the map's float operations. The
    result carries the whole map's source and hash: a SOLM tile built on it belongs
    to the whole map's store."""
    xmin, ymin, xmax, ymax = bounds
    keep = (
        (points[:, 0] >= xmin - margin)
        & (points[:, 0] <= xmax + margin)
        & (points[:, 1] >= ymin - margin)
        & (points[:, 1] <= ymax + margin)
    )
    return _indexed(np.ascontiguousarray(points[keep]), frame, association_params, source, sha256, threads)


def _indexed(points, frame, association_params: dict, source: str, sha256: str, threads: int) -> Map:
    """``points`` indexed in ``frame``, as a Map of the map ``source`` (a crop or the whole)."""
    config = MapConfig(**association_params)
    if len(points) < config.knn:
        raise MapError(f"{source}: {len(points)} points, fewer than knn = {config.knn}")
    try:
        index = _core.MapIndex(points, config.core(threads), frame)
    except ValueError as err:
        raise MapError(f"{source}: {err}") from None
    return Map(index=index, source=source, sha256=sha256, association_params=dict(association_params))


def as_map(map, threads: int = DEFAULTS.scan.threads) -> Map:
    """``map`` itself when it is a Map, else the map :func:`load_map` reads from it (a
    file, or an N x 3 array): what every entry point taking "a Map or a map file" does."""
    return map if isinstance(map, Map) else load_map(map, threads=threads)


def load_map(
    source,
    config: MapConfig = DEFAULTS.map,
    *,
    threads: int = DEFAULTS.scan.threads,
    progress: Callable[[str], None] | None = None,
    **parameters,
) -> Map:
    """Reads a map file (or takes an N x 3 array) and indexes it, with the map section
    ``config`` (:class:`lf3pm.config.MapConfig`), whose fields may also be given by
    name (validated there).

    ``voxel`` downsamples the map first (one centroid per voxel); ``cell_size``
    0 lets the index choose its voxel edge from the point spacing; the association
    parameters are FAST-LIO's. ``progress``, if given, is called with what is being
    done as each phase starts (reading the file, indexing its points): a large map
    takes tens of seconds.
    """
    points = load_map_points(source, config, threads=threads, progress=progress, **parameters)
    if progress is not None:
        progress(f"indexing {points.size:,} points of {points.source}")
    return points.indexed(threads)


@dataclass(frozen=True)
class MapPoints:
    """A map read but not indexed whole: its points (as read), the frame its index would
    have and its hash. A SOLM build takes it tile by tile, each tile on its indexed
    :meth:`crop`, with the very results of the whole map's index (lf3pm.solm.tiles), so
    a map too large to index whole still builds, and a build's driver holds no index."""

    points: np.ndarray
    frame: _core.MapFrame
    source: str
    sha256: str
    association_params: dict

    @property
    def size(self) -> int:
        return len(self.points)

    @cached_property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned bounding box (lower, upper) of the points."""
        return self.points.min(axis=0), self.points.max(axis=0)

    def indexed(self, threads: int = DEFAULTS.scan.threads) -> Map:
        """The whole map indexed (in its frame: the index :func:`load_map` builds)."""
        whole = _indexed(self.points, self.frame, self.association_params, self.source, self.sha256, threads)
        if whole.index.duplicates_removed:
            warnings.warn(
                f"{self.source}: {whole.index.duplicates_removed} duplicate points dropped", UserWarning, stacklevel=3
            )
        return whole

    def crop(self, bounds, margin: float, threads: int = DEFAULTS.scan.threads) -> Map:
        """As :meth:`Map.crop`."""
        return crop_points(
            self.points,
            self.frame,
            self.association_params,
            bounds,
            margin,
            source=self.source,
            sha256=self.sha256,
            threads=threads,
        )


def _sha256(points: np.ndarray) -> str:
    """The hash of a C-contiguous array's bytes, read in place (``tobytes`` would copy the map)."""
    return hashlib.sha256(memoryview(points).cast("B")).hexdigest()


def load_map_points(
    source,
    config: MapConfig = DEFAULTS.map,
    *,
    threads: int = DEFAULTS.scan.threads,
    progress: Callable[[str], None] | None = None,
    **parameters,
) -> MapPoints:
    """Reads a map as :func:`load_map` does, without indexing it whole (:class:`MapPoints`);
    its hash is load_map's, so a SOLM store accepts either."""
    if not isinstance(config, MapConfig):
        raise MapError(f"a map's config is an lf3pm.config.MapConfig, got {type(config).__name__}")
    if parameters:
        config = validated(MapConfig, "map", **{**config.model_dump(), **parameters})
    voxel = config.voxel
    threads = check_threads(threads)
    if progress is not None:
        progress(f"reading {os.fspath(source) if isinstance(source, (str, os.PathLike)) else 'the map array'}")
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
    if len(points) < config.knn:
        raise MapError(f"{name}: the map has {len(points)} points, fewer than knn = {config.knn}")
    try:
        frame = _core.map_frame(points, config.core(threads))
    except ValueError as err:
        raise MapError(f"{name}: {err}") from None
    return MapPoints(
        points=points, frame=frame, source=name, sha256=_sha256(points), association_params=config.association_params()
    )
