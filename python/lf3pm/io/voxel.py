"""Voxel-grid downsampling: one point per occupied voxel, at the centroid of its points."""

from __future__ import annotations

import math

import numpy as np

from lf3pm.errors import MapError

# Beyond 2**53 cells along an axis, float64 cell indices are no longer exact integers.
_MAX_CELLS_PER_AXIS = 2.0**53


def check_voxel(voxel) -> float:
    """Returns ``voxel`` as a float, or raises MapError unless it is a finite number > 0."""
    try:
        size = float(voxel)
    except (TypeError, ValueError):
        size = math.nan
    if not (size > 0 and math.isfinite(size)):
        raise MapError(f"voxel size must be a finite number > 0, got {voxel!r}")
    return size


def voxel_downsample(points, voxel: float) -> np.ndarray:
    """Keeps one point per occupied voxel: the centroid of the points that fall in it.

    The voxels are the cells of a grid of edge ``voxel`` anchored at the origin:
    cell ``(i, j, k)`` spans ``[i*voxel, (i+1)*voxel)`` along x and likewise along
    y and z. ``points`` is a finite ``(N, 3)`` array. Returns a C-contiguous
    float64 ``(M, 3)`` array sorted by cell index (i, then j, then k), so the
    same input always gives the same output. Raises MapError when ``voxel`` is
    not > 0, ``points`` is not ``(N, 3)``, holds NaN/Inf, or is too wide for a
    grid that fine.
    """
    size = check_voxel(voxel)
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise MapError(f"points must be an N x 3 array, got shape {points.shape}")
    if len(points) == 0:
        return np.empty((0, 3), dtype=np.float64)

    cells = points / size
    np.floor(cells, out=cells)
    low = cells.min(axis=0)
    high = cells.max(axis=0)
    extent = high - low + 1
    # min/max propagate NaN and Inf, so one test on them covers every point.
    if not (np.isfinite(extent).all() and extent.max() <= _MAX_CELLS_PER_AXIS):
        if not np.isfinite(points).all():
            raise MapError("points must be finite to be voxel-downsampled")
        raise MapError(f"voxel size {size:g} is too small for a cloud this wide (over 2^53 cells along one axis)")
    cells -= low

    if math.prod(extent.tolist()) < 2.0**63:
        # Fast path: one int64 key per cell, ordered like the (i, j, k) rows.
        _, nj, nk = extent.astype(np.int64).tolist()
        key = cells[:, 0].astype(np.int64)
        key *= nj
        key += cells[:, 1].astype(np.int64)
        key *= nk
        key += cells[:, 2].astype(np.int64)
        _, inverse = np.unique(key, return_inverse=True)
    else:
        _, inverse = np.unique(cells.astype(np.int64), axis=0, return_inverse=True)
    # numpy 2.0.0 returned the inverse of an axis=0 unique with an extra dimension.
    inverse = inverse.reshape(-1)

    counts = np.bincount(inverse)
    centroids = np.empty((len(counts), 3), dtype=np.float64)
    for axis in range(3):
        centroids[:, axis] = np.bincount(inverse, weights=points[:, axis], minlength=len(counts))
        centroids[:, axis] /= counts
    return centroids
