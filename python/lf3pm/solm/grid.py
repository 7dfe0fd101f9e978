"""The SOLM grid: which poses a Static Observation Loss Map is evaluated at.

Spaces (docs/design.md, "State spaces and grids"):
- ``r2``: (y, x) cells, yaw 0: for 360-degree LiDARs;
- ``se2``: (yaw, y, x), K yaw bins centred on k * 2 pi / K: for limited fields of view;
- ``r3``: (z, y, x) for aerial robots, at fixed heights.
Ground robots (r2, se2) keep the sensor ``height`` above the local ground under
each cell (terrain following): the lowest map point in the cell's column.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from lf3pm.config import DEFAULT_HEIGHT, SolmConfig, validated
from lf3pm.errors import Lf3pmError
from lf3pm.map import Map


@dataclass(frozen=True)
class SolmGrid:
    """Cell centres: x = x0 + (i + 0.5) res, y likewise; yaw bins or z levels."""

    space: str
    x0: float
    y0: float
    res: float
    nx: int
    ny: int
    yaw_bins: int = 1
    z_levels: tuple = ()
    height: float = DEFAULT_HEIGHT

    @property
    def shape(self) -> tuple:
        """Array shape of a channel: (ny, nx), (yaw_bins, ny, nx) or (nz, ny, nx)."""
        if self.space == "r2":
            return (self.ny, self.nx)
        return (self.yaw_bins if self.space == "se2" else len(self.z_levels), self.ny, self.nx)

    @property
    def layers(self) -> int:
        return 1 if self.space == "r2" else self.shape[0]

    def xs(self) -> np.ndarray:
        return self.x0 + (np.arange(self.nx) + 0.5) * self.res

    def ys(self) -> np.ndarray:
        return self.y0 + (np.arange(self.ny) + 0.5) * self.res

    def yaws(self) -> np.ndarray:
        return np.arange(self.yaw_bins) * 2 * math.pi / self.yaw_bins

    def cell(self, x, y, third=None) -> tuple:
        """Index of the cell nearest to each (x, y[, yaw or z]), clamped to the grid,
        as an index tuple into a channel's array: (iy, ix) for r2, (k, iy, ix)
        otherwise (se2: the nearest yaw bin, periodic; r3: the nearest level)."""
        ix = np.clip(np.floor((np.asarray(x, float) - self.x0) / self.res).astype(int), 0, self.nx - 1)
        iy = np.clip(np.floor((np.asarray(y, float) - self.y0) / self.res).astype(int), 0, self.ny - 1)
        if self.space == "r2":
            return iy, ix
        if self.space == "se2":
            step = 2 * math.pi / self.yaw_bins
            k = np.round(np.mod(np.asarray(0.0 if third is None else third, float), 2 * math.pi) / step)
            return np.broadcast_to(k.astype(int) % self.yaw_bins, ix.shape), iy, ix
        levels = np.asarray(self.z_levels, float)
        z = np.asarray(levels[0] if third is None else third, float)
        k = np.argmin(np.abs(z[..., None] - levels), axis=-1)
        return np.broadcast_to(k, ix.shape), iy, ix

    def to_dict(self) -> dict:
        d = asdict(self)
        d["z_levels"] = list(self.z_levels)
        return d


_DEFAULT = SolmConfig()
#: The most poses a grid may hold unless the caller raises ``max_cells`` (`lf3pm solm
#: build --max-cells`): 10 M poses are hours of scans on a workstation, and a typo in
#: --res (1e-6 for 1e-1) should be refused at once, not run out of memory.
MAX_CELLS = _DEFAULT.max_cells


def make_grid(
    world: Map,
    space: str = _DEFAULT.space,
    res: float = _DEFAULT.res,
    *,
    bounds=None,
    yaw_bins: int = _DEFAULT.yaw_bins,
    height: float = _DEFAULT.height,
    z_levels=None,
    max_cells: int = MAX_CELLS,
) -> SolmGrid:
    """The grid over ``bounds`` (xmin, ymin, xmax, ymax; default the map's extent);
    Lf3pmError when it would hold more than ``max_cells`` poses (at most
    lf3pm.config.MAX_CELLS_CEILING) or when a cell would be wider than the grid
    (``res`` above the larger side of the bounds). The parameters are validated by
    :class:`lf3pm.config.SolmConfig`."""
    config = validated(
        SolmConfig, "solm", space=space, res=res, bounds=bounds, yaw_bins=yaw_bins, height=height, max_cells=max_cells
    )
    space, res, height, yaw_bins = config.space, config.res, config.height, config.yaw_bins
    lower, upper = world.bounds
    bounds = config.bounds or (lower[0], lower[1], upper[0], upper[1])
    xmin, ymin, xmax, ymax = (float(b) for b in bounds)
    if not (xmin < xmax and ymin < ymax):
        raise Lf3pmError(f"bounds {bounds} are empty: need xmin < xmax and ymin < ymax")
    if xmax <= lower[0] or xmin >= upper[0] or ymax <= lower[1] or ymin >= upper[1]:
        raise Lf3pmError(
            f"bounds {bounds} lie outside the map's extent "
            f"x [{lower[0]:.2f}, {upper[0]:.2f}], y [{lower[1]:.2f}, {upper[1]:.2f}]"
        )
    span = max(xmax - xmin, ymax - ymin)
    if res > span:
        raise Lf3pmError(
            f"res {res:g} m is wider than the grid ({span:g} m along its longer side): one cell "
            "would cover it all; use a --res below that"
        )
    # One axis first, in floats: at a res of 1e-300 m its count would not even convert to an int.
    along = max(xmax - xmin, ymax - ymin, upper[2] - lower[2] - height if space == "r3" else 0.0) / res
    if along > config.max_cells:
        raise Lf3pmError(
            f"the grid would hold more than {config.max_cells:,} poses ({along:.3g} cells along one "
            f"axis at res {res:g} m): use a coarser --res or smaller --bounds, or raise --max-cells"
        )
    nx, ny = math.ceil((xmax - xmin) / res), math.ceil((ymax - ymin) / res)
    layers = yaw_bins if space == "se2" else 1
    if space == "r3":
        layers = len(z_levels) if z_levels is not None else max(0, math.ceil((upper[2] - lower[2] - height) / res))
    cells = nx * ny * max(layers, 1)
    if cells > config.max_cells:
        raise Lf3pmError(
            f"the grid would hold {cells:,} poses ({nx} x {ny} x {max(layers, 1)}), more than "
            f"{config.max_cells:,}: use a coarser --res or smaller --bounds, or raise --max-cells"
        )
    levels = ()
    if space == "r3":
        if z_levels is None:
            z_levels = np.arange(lower[2] + height, upper[2], res)
        levels = tuple(float(z) for z in z_levels)
        if not all(math.isfinite(z) for z in levels):
            raise Lf3pmError(f"z levels must be finite, got {levels}")
        if not levels:
            raise Lf3pmError("an r3 grid needs at least one z level")
    return SolmGrid(space, xmin, ymin, float(res), nx, ny, yaw_bins if space == "se2" else 1, levels, float(height))
