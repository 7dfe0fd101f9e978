"""A scalar field on a regular (x, y) grid, optionally with periodic yaw layers.

The trajectory optimiser's cost map (a SOLM channel) and ESDF, interpolated by the C++
core; and the same interpolation in numpy (:func:`axis_weights`, :func:`bilinear`) for
the fields it cannot take (a SOLM's channels hold NaN where no pose was evaluated, R3
levels are not periodic). Geometry follows
the SOLM: cell (i, j) is centred at (x0 + (i + 0.5) res, y0 + (j + 0.5) res); yaw
layer k of ``values`` shaped (yaw_bins, ny, nx) is centred on k 2 pi / yaw_bins.
Interpolation is bilinear (trilinear with yaw, periodic), clamped at the borders.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from lf3pm.errors import Lf3pmError
from lf3pm.grid import Grid


@dataclass(frozen=True)
class GridField:
    """Values (ny, nx) or (yaw_bins, ny, nx), finite float64, with origin (x0, y0) and cell size res."""

    values: np.ndarray
    x0: float
    y0: float
    res: float
    _core: object = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        values = np.ascontiguousarray(self.values, dtype=np.float64)
        if values.ndim not in (2, 3) or 0 in values.shape:
            raise Lf3pmError(f"a grid field must be (ny, nx) or (yaw_bins, ny, nx), got shape {values.shape}")
        if not np.isfinite(values).all():
            raise Lf3pmError("grid field values must be finite (fill NaN cells first)")
        if not all(math.isfinite(v) for v in (self.x0, self.y0, self.res)) or self.res <= 0:
            raise Lf3pmError(
                f"grid field geometry must be finite with res > 0, got x0={self.x0}, y0={self.y0}, res={self.res}"
            )
        from lf3pm import _core

        object.__setattr__(self, "values", values)
        object.__setattr__(self, "_core", _core.GridField(values, float(self.x0), float(self.y0), float(self.res)))

    @classmethod
    def on(cls, grid: Grid, values) -> GridField:
        """``values`` over the cells of ``grid``."""
        return cls(values, grid.x0, grid.y0, grid.res)

    @property
    def grid(self) -> Grid:
        """The R2 grid of the values' cells."""
        ny, nx = self.values.shape[-2:]
        return Grid.plane(self.x0, self.y0, self.res, nx, ny)

    @property
    def yaw_bins(self) -> int:
        """Yaw layers (1 for an (x, y) field)."""
        return self.values.shape[0] if self.values.ndim == 3 else 1

    def sample(self, x, y, yaw=0.0):
        """Interpolated values at the points and gradients (..., 3): d/dx, d/dy, d/dyaw."""
        x, y, yaw = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (x, y, yaw)))
        shape = x.shape
        value, grad = self._core.sample(*(np.ascontiguousarray(v).ravel() for v in (x, y, yaw)))
        return value.reshape(shape), grad.reshape(shape + (3,))


def axis_weights(v, origin: float, res: float, n: int):
    """Linear interpolation between the centres of ``n`` cells along one axis (cell i
    centred at origin + (i + 0.5) res), positions clamped to the end centres: (inside,
    i0, i1, t) with the value (1 - t) a[i0] + t a[i1], and inside 1 where the position
    lies between centres, 0 where clamped (its derivative there is 0)."""
    f = (np.asarray(v, dtype=np.float64) - origin) / res - 0.5
    if n < 2:
        zero = np.zeros_like(f)
        index = np.zeros(f.shape, dtype=np.int64)
        return zero, index, index, zero
    inside = ((f >= 0) & (f <= n - 1)).astype(np.float64)
    f = np.clip(f, 0.0, n - 1)
    i0 = np.minimum(np.floor(f).astype(np.int64), n - 2)
    return inside, i0, i0 + 1, f - i0


def bilinear(values, x, y, x0: float, y0: float, res: float, layer=None):
    """Bilinear interpolation of ``values`` (ny, nx), or of layer ``layer`` (an index per
    point) of ``values`` (layers, ny, nx), at (x, y), clamped to the border centres:
    (value, d/dx, d/dy)."""
    inx, ix0, ix1, tx = axis_weights(x, x0, res, values.shape[-1])
    iny, iy0, iy1, ty = axis_weights(y, y0, res, values.shape[-2])
    at = (lambda iy, ix: values[iy, ix]) if layer is None else (lambda iy, ix: values[layer, iy, ix])
    v00, v01, v10, v11 = at(iy0, ix0), at(iy0, ix1), at(iy1, ix0), at(iy1, ix1)
    value = (1 - ty) * ((1 - tx) * v00 + tx * v01) + ty * ((1 - tx) * v10 + tx * v11)
    ddx = ((1 - ty) * (v01 - v00) + ty * (v11 - v10)) / res * inx
    ddy = ((1 - tx) * (v10 - v00) + tx * (v11 - v01)) / res * iny
    return value, ddx, ddy
