"""The ground a wheeled robot drives on, as a smooth (C2) surface z = g(x, y).

A SOLM puts the sensor above the lowest map point of each cell column
(``lf3pm.terrain.column_minimum``). That field is jagged: it steps at every
cell, it reads the top of an obstacle whose inside holds no ground points, and
it is undefined where a column is empty. A replay needs a ground whose second
derivative is bounded, because the sensor's vertical acceleration along a path
is ``v^T Hess(g) v + grad(g) . a``. The surface here is built in four steps:

1. column minimum on a ``cell`` grid over the region the path covers (plus a
   margin for the smoothing);
2. ground = the cells reached by steps of at most ``max_step`` between
   neighbouring columns from the columns under most of the path (a plateau behind
   a wall -- a box top, a roof -- is no ground, nor is the ceiling a column reads
   where a sparse scan left its floor empty: their columns take the value of the
   nearest ground column, as do empty columns);
3. a Gaussian of standard deviation ``smoothing`` (m): the wheels and the
   suspension average the ground over the robot's footprint, and the Gaussian
   bounds the curvature (about step / smoothing^2 for a step of that height);
4. a bicubic interpolating spline (scipy ``RectBivariateSpline``, C2) through
   the smoothed grid, which gives g and its first and second derivatives.

The Gaussian rounds the ground off: on a hump or a dip the surface departs
from the column minimum. ``deviation`` measures by how much along the path,
so a caller can state what the sensor's height above the map really was.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lf3pm.errors import Lf3pmError
from lf3pm.terrain import column_minimum

#: Column grid (m): several map points per column for maps sampled every 5-10 cm.
GROUND_CELL = 0.25
#: Gaussian sigma (m): half the footprint of a small wheeled base (about 1 m).
GROUND_SMOOTHING = 0.5
#: Largest height change between neighbouring columns that is still ground (m):
#: a 0.25 m cell rising 0.25 m is a 45 degree slope, steeper than a wheeled
#: robot drives; a box side or a wall jumps by more.
GROUND_MAX_STEP = 0.25


@dataclass(frozen=True)
class SmoothGround:
    """A C2 ground surface over an axis-aligned region (see the module docstring).

    ``spline`` is a scipy ``RectBivariateSpline`` in (x, y); ``region`` is
    (xmin, ymin, xmax, ymax) of its grid; ``raw`` the column minimum on that grid
    ((ny, nx), NaN off the ground), kept to measure the smoothing's deviation.
    """

    spline: object
    region: tuple
    cell: float
    smoothing: float
    max_step: float
    raw: np.ndarray

    def height(self, x, y) -> np.ndarray:
        """g(x, y) for arrays x, y of equal shape."""
        return self.spline.ev(np.asarray(x, float), np.asarray(y, float))

    def derivatives(self, x, y) -> tuple[np.ndarray, ...]:
        """g, g_x, g_y, g_xx, g_xy, g_yy at (x, y)."""
        x, y = np.asarray(x, float), np.asarray(y, float)
        ev = self.spline.ev
        return (ev(x, y), ev(x, y, dx=1), ev(x, y, dy=1), ev(x, y, dx=2), ev(x, y, dx=1, dy=1), ev(x, y, dy=2))

    def deviation(self, x, y) -> np.ndarray:
        """g(x, y) minus the column minimum of the cell under each (x, y) (NaN
        where that column is not ground): positive where the sensor rides higher
        above the map than asked, negative lower."""
        x0, y0 = self.region[:2]
        ny, nx = self.raw.shape
        i = np.clip(np.floor((np.asarray(x, float) - x0) / self.cell).astype(int), 0, nx - 1)
        j = np.clip(np.floor((np.asarray(y, float) - y0) / self.cell).astype(int), 0, ny - 1)
        return self.height(x, y) - self.raw[j, i]


def smooth_ground(
    points: np.ndarray,
    path_xy: np.ndarray,
    *,
    cell: float = GROUND_CELL,
    smoothing: float = GROUND_SMOOTHING,
    max_step: float = GROUND_MAX_STEP,
) -> SmoothGround:
    """The smooth ground under ``path_xy`` (N, 2) from the map ``points`` (M, 3).

    Raises Lf3pmError for non-positive parameters or when no map point lies
    under the path's region.
    """
    from scipy.interpolate import RectBivariateSpline
    from scipy.ndimage import distance_transform_edt, gaussian_filter
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    for name, value in (("ground cell", cell), ("ground smoothing", smoothing), ("ground max step", max_step)):
        if not (math.isfinite(value) and value > 0):
            raise Lf3pmError(f"the {name} must be > 0 m, got {value}")
    path_xy = np.asarray(path_xy, dtype=np.float64)
    # The Gaussian reaches 3 sigma; the spline needs 4 nodes per axis.
    margin = 3.0 * smoothing + 2.0 * cell
    lo, hi = path_xy.min(axis=0) - margin, path_xy.max(axis=0) + margin
    nx, ny = (max(4, int(math.ceil(v))) for v in (hi - lo) / cell)
    x0, y0 = float(lo[0]), float(lo[1])
    raw = column_minimum(points, x0, y0, cell, nx, ny)
    known = np.isfinite(raw)
    if not known.any():
        raise Lf3pmError("no map point lies under the trajectory: there is no ground to drive on")
    filled = _nearest_fill(raw, known, distance_transform_edt)

    # Ground: the columns the path reaches by small steps (4-neighbour graph).
    index = np.arange(nx * ny).reshape(ny, nx)
    pairs = [
        (index[:, :-1], index[:, 1:], np.abs(np.diff(filled, axis=1))),
        (index[:-1, :], index[1:, :], np.abs(np.diff(filled, axis=0))),
    ]
    rows = np.concatenate([a[d <= max_step] for a, _, d in pairs])
    cols = np.concatenate([b[d <= max_step] for _, b, d in pairs])
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(nx * ny, nx * ny))
    _, label = connected_components(graph, directed=False)
    ij = np.floor((path_xy - lo) / cell).astype(int)
    on_path = index[np.clip(ij[:, 1], 0, ny - 1), np.clip(ij[:, 0], 0, nx - 1)]
    # The robot drives on one connected surface: the component under most of the path. A
    # column the floor left empty in a sparse scan reads the ceiling above it, and its own
    # component (the ceiling's) is no ground: it takes the nearest ground column's height.
    surface_label = np.bincount(label[on_path]).argmax()
    ground = (label == surface_label).reshape(ny, nx) & known

    surface = gaussian_filter(
        _nearest_fill(filled, ground, distance_transform_edt), smoothing / cell, mode="nearest", truncate=3.0
    )
    xs = x0 + (np.arange(nx) + 0.5) * cell
    ys = y0 + (np.arange(ny) + 0.5) * cell
    spline = RectBivariateSpline(xs, ys, surface.T, kx=3, ky=3, s=0)
    return SmoothGround(
        spline=spline,
        region=(x0, y0, x0 + nx * cell, y0 + ny * cell),
        cell=float(cell),
        smoothing=float(smoothing),
        max_step=float(max_step),
        raw=np.where(ground, raw, np.nan),
    )


def _nearest_fill(values: np.ndarray, keep: np.ndarray, distance_transform_edt) -> np.ndarray:
    """``values`` where ``keep``, elsewhere the value of the nearest kept cell."""
    if keep.all():
        return values.copy()
    _, (jj, ii) = distance_transform_edt(~keep, return_indices=True)
    return values[jj, ii]
