"""The SOLM grid: which poses a Static Observation Loss Map is evaluated at.

Spaces (docs/design.md, "State spaces and grids"; lf3pm.grid.Space):
- ``R2``: (y, x) cells, yaw 0: for 360-degree LiDARs;
- ``SE2``: (yaw, y, x), K yaw bins centred on k * 2 pi / K: for limited fields of view;
- ``R3``: (z, y, x) for aerial robots, at fixed heights;
- ``R3YAW``: (z * yaw, y, x) for quadrotors: every yaw bin at every height (layer
  iz * yaw_bins + ib), the body level and the sensor on its mount (lf3pm.flight).
Ground robots (R2, SE2) keep the sensor ``height`` above the local ground under
each cell (terrain following): the lowest map point in the cell's column.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lf3pm.config import DEFAULT_HEIGHT, DEFAULTS, SolmConfig, validated
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Grid, Space
from lf3pm.map import Map


@dataclass(frozen=True)
class SolmGrid(Grid):
    """A SOLM's grid (lf3pm.grid.Grid) and the sensor's ``height`` above the local
    ground (ground robots). Stored whole as the store's ``grid`` attribute."""

    height: float = DEFAULT_HEIGHT


def make_grid(
    world: Map,
    space: Space | str | None = None,
    res: float | None = None,
    *,
    config: SolmConfig = DEFAULTS.solm,
    bounds=None,
    yaw_bins: int | None = None,
    height: float | None = None,
    z_levels=None,
    max_cells: int | None = None,
) -> SolmGrid:
    """The grid of the solm section ``config`` over its ``bounds`` (xmin, ymin, xmax,
    ymax; default the map's extent). The grid parameters given (not None) override the
    section's and are validated by it: ``make_grid(world, config=config.solm)`` and
    ``make_grid(world, "se2", 1.0, yaw_bins=12)`` are both the usual calls. ``z_levels``
    (R3, R3YAW): the heights, default every ``res`` from the map's floor plus ``height`` up.
    Lf3pmError when the grid would hold more than ``max_cells`` poses (at most
    lf3pm.config.MAX_CELLS_CEILING) or when a cell would be wider than the grid (``res``
    above the larger side of the bounds)."""
    if not isinstance(config, SolmConfig):
        raise Lf3pmError(f"make_grid's config is an lf3pm.config.SolmConfig, got {type(config).__name__}")
    given = dict(space=space, res=res, bounds=bounds, yaw_bins=yaw_bins, height=height, max_cells=max_cells)
    given = {name: value for name, value in given.items() if value is not None}
    if given:
        config = validated(SolmConfig, "solm", **{**config.model_dump(), **given})
    res, height, yaw_bins = config.res, config.height, config.yaw_bins
    space = config.space
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
    aerial = not space.ground
    along = max(xmax - xmin, ymax - ymin, upper[2] - lower[2] - height if aerial else 0.0) / res
    if along > config.max_cells:
        raise Lf3pmError(
            f"the grid would hold more than {config.max_cells:,} poses ({along:.3g} cells along one "
            f"axis at res {res:g} m): use a coarser --res or smaller --bounds, or raise --max-cells"
        )
    nx, ny = math.ceil((xmax - xmin) / res), math.ceil((ymax - ymin) / res)
    layers = yaw_bins if space is Space.SE2 else 1
    if aerial:
        layers = len(z_levels) if z_levels is not None else max(0, math.ceil((upper[2] - lower[2] - height) / res))
        layers *= yaw_bins if space is Space.R3YAW else 1
    cells = nx * ny * max(layers, 1)
    if cells > config.max_cells:
        raise Lf3pmError(
            f"the grid would hold {cells:,} poses ({nx} x {ny} x {max(layers, 1)}), more than "
            f"{config.max_cells:,}: use a coarser --res or smaller --bounds, or raise --max-cells"
        )
    levels = ()
    if aerial:
        if z_levels is None:
            z_levels = np.arange(lower[2] + height, upper[2], res)
        levels = tuple(float(z) for z in z_levels)
        if not all(math.isfinite(z) for z in levels):
            raise Lf3pmError(f"z levels must be finite, got {levels}")
        if not levels:
            raise Lf3pmError(f"an {space} grid needs at least one z level")
    yaw_bins = yaw_bins if space.yawed else 1
    return SolmGrid(space, xmin, ymin, float(res), nx, ny, yaw_bins, levels, float(height))
