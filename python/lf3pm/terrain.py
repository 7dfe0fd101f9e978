"""Where a ground robot can stand: the ground under each column of a map, and
whether a robot body there would touch the map. Shared by SOLM masks and the
experiments' pose sampling."""

from __future__ import annotations

import numpy as np

from lf3pm.grid import Grid
from lf3pm.map import Map

#: Points binned at a time by column_minimum: its temporaries stay near 50 MB, not
#: three times the map (a 60 M-point map's bins took 2.9 GB at once).
_CHUNK = 1 << 20


def _binned(points: np.ndarray, grid: Grid):
    """Chunk by chunk, the (row, column, z) of the points inside the columns of ``grid``."""
    for start in range(0, len(points), _CHUNK):
        part = points[start : start + _CHUNK]
        ix, iy = grid.columns(part[:, 0], part[:, 1])
        inside = grid.holds(ix, iy)
        yield iy[inside], ix[inside], part[inside, 2]


def column_minimum(points: np.ndarray, grid: Grid) -> np.ndarray:
    """Lowest z of the points in each column (cell) of ``grid``, (ny, nx); inf where a
    column holds no point."""
    ground = np.full(grid.plane_shape, np.inf)
    for j, i, z in _binned(points, grid):
        np.minimum.at(ground, (j, i), z)
    return ground


def occupied_cells(points: np.ndarray, grid: Grid, bottom: np.ndarray, top: np.ndarray) -> np.ndarray:
    """(ny, nx) bool: the columns of ``grid`` that hold a map point between ``bottom``
    and ``top`` ((ny, nx) arrays, metres; inf or NaN: never). Exact: a point off every
    column's centre (a thin pole, a bush's stem) still marks its own."""
    occupied = np.zeros(grid.plane_shape, bool)
    for j, i, z in _binned(points, grid):
        hit = (z >= bottom[j, i]) & (z <= top[j, i])
        occupied[j[hit], i[hit]] = True
    return occupied


def body_blocked(world: Map, x, y, z_low, z_high, radius: float) -> np.ndarray:
    """Whether a map point lies within ``radius`` of the robot body, a vertical
    segment from ``z_low`` to ``z_high`` at (x, y), probed at its ends and middle
    (arrays broadcast together; a radius of 0 blocks nothing)."""
    x, y, z_low, z_high = np.broadcast_arrays(*(np.asarray(v, float) for v in (x, y, z_low, z_high)))
    blocked = np.zeros(x.shape, bool)
    if radius <= 0 or x.size == 0:
        return blocked
    for frac in (0.0, 0.5, 1.0):
        probes = np.stack([x.ravel(), y.ravel(), (z_low + frac * (z_high - z_low)).ravel()], axis=1)
        _, dist = world.index.nearest(np.ascontiguousarray(probes), 1, radius)
        blocked |= np.isfinite(dist[:, 0]).reshape(x.shape)
    return blocked
