"""Where a ground robot can stand: the ground under each column of a map, and
whether a robot body there would touch the map. Shared by SOLM masks and the
experiments' pose sampling."""

from __future__ import annotations

import numpy as np

from lf3pm.map import Map


#: Points binned at a time by column_minimum: its temporaries stay near 50 MB, not
#: three times the map (a 60 M-point map's bins took 2.9 GB at once).
_CHUNK = 1 << 20


def column_minimum(points: np.ndarray, x0: float, y0: float, cell: float, nx: int, ny: int) -> np.ndarray:
    """Lowest z of the points in each (ny, nx) column of edge ``cell`` from (x0, y0);
    inf where a column holds no point."""
    ground = np.full((ny, nx), np.inf)
    for start in range(0, len(points), _CHUNK):
        part = points[start:start + _CHUNK]
        ij = np.floor((part[:, :2] - [x0, y0]) / cell).astype(np.int64)
        inside = (ij[:, 0] >= 0) & (ij[:, 0] < nx) & (ij[:, 1] >= 0) & (ij[:, 1] < ny)
        np.minimum.at(ground, (ij[inside, 1], ij[inside, 0]), part[inside, 2])
    return ground


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
