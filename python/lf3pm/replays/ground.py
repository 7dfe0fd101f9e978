"""The ground a wheeled robot drives on, as a smooth (C2) surface z = g(x, y).

A SOLM puts the sensor above the lowest map point of each cell column
(``lf3pm.terrain.column_minimum``). That field is jagged: it steps at every
cell, it reads the top of an obstacle whose inside holds no ground points, and
it is undefined where a column is empty. A replay needs a ground whose second
derivative is bounded, because the sensor's vertical acceleration along a path
is ``v^T Hess(g) v + grad(g) . a``. The surface here is built in four steps:

1. column minimum on a grid of ``cell`` columns over the region the path covers
   (plus a margin for the smoothing);
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
The three parameters are lf3pm.config.GroundConfig's (the ``ground`` section).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lf3pm.config import DEFAULTS, GroundConfig, validated
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Grid
from lf3pm.terrain import column_minimum


@dataclass(frozen=True)
class SmoothGround:
    """A C2 ground surface over an axis-aligned region (see the module docstring).

    ``spline`` is a scipy ``RectBivariateSpline`` in (x, y); ``grid`` the columns'
    grid; ``raw`` the column minimum on it ((ny, nx), NaN off the ground), kept to
    measure the smoothing's deviation; ``config`` the parameters it was built with.
    """

    spline: object
    grid: Grid
    config: GroundConfig
    raw: np.ndarray

    @property
    def region(self) -> tuple:
        """(xmin, ymin, xmax, ymax) of the columns."""
        return self.grid.bounds

    cell = property(lambda self: self.grid.res)
    smoothing = property(lambda self: self.config.smoothing)
    max_step = property(lambda self: self.config.max_step)

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
        return self.height(x, y) - self.raw[self.grid.cell(x, y)]


def smooth_ground(
    points: np.ndarray,
    path_xy: np.ndarray,
    config: GroundConfig = DEFAULTS.ground,
    *,
    cell: float | None = None,
    smoothing: float | None = None,
    max_step: float | None = None,
) -> SmoothGround:
    """The smooth ground under ``path_xy`` (N, 2) from the map ``points`` (M, 3), with
    the ground section ``config``; ``cell``, ``smoothing`` and ``max_step`` given by
    name override its own (validated there).

    Raises Lf3pmError for parameters out of range or when no map point lies under
    the path's region.
    """
    from scipy.interpolate import RectBivariateSpline
    from scipy.ndimage import distance_transform_edt, gaussian_filter
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    given = {"cell": cell, "smoothing": smoothing, "max_step": max_step}
    given = {name: value for name, value in given.items() if value is not None}
    if given:
        config = validated(GroundConfig, "ground", **{**config.model_dump(), **given})
    cell, smoothing, max_step = config.cell, config.smoothing, config.max_step
    path_xy = np.asarray(path_xy, dtype=np.float64)
    # The Gaussian reaches 3 sigma; the spline needs 4 nodes per axis.
    margin = 3.0 * smoothing + 2.0 * cell
    lo, hi = path_xy.min(axis=0) - margin, path_xy.max(axis=0) + margin
    nx, ny = (max(4, int(math.ceil(v))) for v in (hi - lo) / cell)
    grid = Grid.plane(float(lo[0]), float(lo[1]), cell, nx, ny)
    raw = column_minimum(points, grid)
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
    on_path = index[grid.cell(path_xy[:, 0], path_xy[:, 1])]
    # The robot drives on one connected surface: the component under most of the path. A
    # column the floor left empty in a sparse scan reads the ceiling above it, and its own
    # component (the ceiling's) is no ground: it takes the nearest ground column's height.
    surface_label = np.bincount(label[on_path]).argmax()
    ground = (label == surface_label).reshape(ny, nx) & known

    surface = gaussian_filter(
        _nearest_fill(filled, ground, distance_transform_edt), smoothing / cell, mode="nearest", truncate=3.0
    )
    spline = RectBivariateSpline(grid.xs(), grid.ys(), surface.T, kx=3, ky=3, s=0)
    return SmoothGround(spline=spline, grid=grid, config=config, raw=np.where(ground, raw, np.nan))


def _nearest_fill(values: np.ndarray, keep: np.ndarray, distance_transform_edt) -> np.ndarray:
    """``values`` where ``keep``, elsewhere the value of the nearest kept cell."""
    if keep.all():
        return values.copy()
    _, (jj, ii) = distance_transform_edt(~keep, return_indices=True)
    return values[jj, ii]
