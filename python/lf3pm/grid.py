"""The regular grid every map-sized array of lf3pm lives on: a SOLM's channels, the
planner's ESDF and cost layers, the ground model's columns, the viewer's squares.

Cell (ix, iy) covers [x0 + ix res, x0 + (ix + 1) res) x [y0 + iy res, y0 + (iy + 1) res)
and is centred at (x0 + (ix + 0.5) res, y0 + (iy + 0.5) res); arrays over it are
indexed [iy, ix] (rows are y). Above the plane a grid has one layer (``Space.R2``),
``yaw_bins`` periodic yaw bins centred on k 2 pi / yaw_bins (``Space.SE2``), the
heights ``z_levels`` (``Space.R3``) or every yaw bin at every height (``Space.R3YAW``:
layer iz * yaw_bins + ib); docs/design.md, "State spaces and grids".

The space names ("r2", "se2", "r3", "r3yaw") are what YAML, the CLI and a SOLM's
attributes on disk hold; in code a space is a :class:`Space` and is compared as one.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, fields

import numpy as np


class Space(str, enum.Enum):
    """A grid's state space; its value is the name YAML, the CLI and stores use (and
    what ``str`` and f-strings print)."""

    R2 = "r2"  #: (x, y): 360-degree LiDARs on ground robots
    SE2 = "se2"  #: (x, y, yaw): ground robots whose sensor sees a limited field of view
    R3 = "r3"  #: (x, y, z): aerial robots, at fixed heights
    R3YAW = "r3yaw"  #: (x, y, z, yaw): quadrotors, at fixed heights, level, each yaw bin

    def __str__(self) -> str:
        return self.value

    def __format__(self, spec: str) -> str:
        return format(self.value, spec)

    @property
    def ground(self) -> bool:
        """A ground robot's space: poses ride a height above the local ground."""
        return self in (Space.R2, Space.SE2)

    @property
    def yawed(self) -> bool:
        """A space with yaw bins (se2, r3yaw)."""
        return self in (Space.SE2, Space.R3YAW)


@dataclass(frozen=True)
class Grid:
    """``nx`` x ``ny`` square cells of edge ``res`` from the corner (x0, y0), and the
    layers above them (module docstring). ``space`` may be given by its name."""

    space: Space
    x0: float
    y0: float
    res: float
    nx: int
    ny: int
    yaw_bins: int = 1
    z_levels: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "space", Space(self.space))

    @classmethod
    def plane(cls, x0: float, y0: float, res: float, nx: int, ny: int) -> Grid:
        """An R2 grid: cells only."""
        return cls(Space.R2, x0, y0, res, nx, ny)

    @property
    def origin(self) -> tuple[float, float]:
        """(x0, y0): the corner of cell (0, 0)."""
        return self.x0, self.y0

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the cells' squares."""
        return self.x0, self.y0, self.x0 + self.nx * self.res, self.y0 + self.ny * self.res

    @property
    def plane_shape(self) -> tuple[int, int]:
        """(ny, nx): the shape of an array over the cells."""
        return self.ny, self.nx

    @property
    def shape(self) -> tuple:
        """Shape of an array over every pose: (ny, nx), (yaw_bins, ny, nx), (nz, ny, nx) or
        (nz * yaw_bins, ny, nx) (r3yaw: layer iz * yaw_bins + ib)."""
        if self.space is Space.R2:
            return self.plane_shape
        layers = {Space.SE2: self.yaw_bins, Space.R3: len(self.z_levels)}.get(
            self.space, len(self.z_levels) * self.yaw_bins
        )
        return (layers, self.ny, self.nx)

    @property
    def layers(self) -> int:
        """Layers above each cell: 1, the yaw bins or the z levels."""
        return 1 if self.space is Space.R2 else self.shape[0]

    def flat(self) -> Grid:
        """The R2 grid of the same cells (no layers)."""
        return Grid.plane(self.x0, self.y0, self.res, self.nx, self.ny)

    def refined(self, k: int) -> Grid:
        """The R2 grid of the same extent whose cells split each of these into k x k."""
        return Grid.plane(self.x0, self.y0, self.res / k, self.nx * k, self.ny * k)

    def xs(self) -> np.ndarray:
        """x of the cell centres, (nx,)."""
        return self.x0 + (np.arange(self.nx) + 0.5) * self.res

    def ys(self) -> np.ndarray:
        """y of the cell centres, (ny,)."""
        return self.y0 + (np.arange(self.ny) + 0.5) * self.res

    def yaws(self) -> np.ndarray:
        """Centres of the yaw bins, (yaw_bins,)."""
        return np.arange(self.yaw_bins) * 2 * math.pi / self.yaw_bins

    def layer_poses(self) -> tuple[np.ndarray, np.ndarray]:
        """(z, yaw) of every layer of an aerial grid (r3: yaw 0; r3yaw: layer iz *
        yaw_bins + ib at z_levels[iz] and yaw bin ib), arrays of shape (layers,)."""
        levels = np.asarray(self.z_levels, dtype=np.float64)
        if self.space is Space.R3YAW:
            return np.repeat(levels, self.yaw_bins), np.tile(self.yaws(), len(levels))
        return levels, np.zeros(len(levels))

    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """(x, y) of every cell centre, arrays of shape (ny, nx)."""
        return tuple(np.meshgrid(self.xs(), self.ys()))

    def centre(self, ix, iy) -> tuple:
        """(x, y) of the centre of cell (ix, iy) (integers or integer arrays)."""
        return self.x0 + (ix + 0.5) * self.res, self.y0 + (iy + 0.5) * self.res

    def columns(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """(ix, iy) of the cells holding (x, y), unclamped (off the grid: outside 0 .. n - 1)."""
        ix = np.floor((np.asarray(x, float) - self.x0) / self.res).astype(np.int64)
        iy = np.floor((np.asarray(y, float) - self.y0) / self.res).astype(np.int64)
        return ix, iy

    def holds(self, ix, iy):
        """Whether cell (ix, iy) lies on the grid."""
        return (ix >= 0) & (ix < self.nx) & (iy >= 0) & (iy < self.ny)

    def cell_of(self, x: float, y: float) -> tuple[int, int] | None:
        """(ix, iy) of the cell that holds the point (x, y), or None off the grid."""
        ix, iy = int(np.floor((x - self.x0) / self.res)), int(np.floor((y - self.y0) / self.res))
        return (ix, iy) if 0 <= ix < self.nx and 0 <= iy < self.ny else None

    def cell(self, x, y, third=None, yaw=None) -> tuple:
        """Index of the cell nearest to each (x, y[, yaw or z]), clamped to the grid,
        as an index tuple into an array of :attr:`shape`: (iy, ix) for R2, (k, iy, ix)
        otherwise (SE2: the nearest yaw bin, periodic; R3: the nearest level; R3YAW:
        ``third`` the height and ``yaw`` the yaw, k = iz * yaw_bins + ib)."""
        ix = np.clip(np.floor((np.asarray(x, float) - self.x0) / self.res).astype(int), 0, self.nx - 1)
        iy = np.clip(np.floor((np.asarray(y, float) - self.y0) / self.res).astype(int), 0, self.ny - 1)
        if self.space is Space.R2:
            return iy, ix
        step = 2 * math.pi / self.yaw_bins
        if self.space is Space.SE2:
            k = np.round(np.mod(np.asarray(0.0 if third is None else third, float), 2 * math.pi) / step)
            return np.broadcast_to(k.astype(int) % self.yaw_bins, ix.shape), iy, ix
        levels = np.asarray(self.z_levels, float)
        z = np.asarray(levels[0] if third is None else third, float)
        k = np.argmin(np.abs(z[..., None] - levels), axis=-1)
        if self.space is Space.R3YAW:
            b = np.round(np.mod(np.asarray(0.0 if yaw is None else yaw, float), 2 * math.pi) / step)
            k = k * self.yaw_bins + b.astype(int) % self.yaw_bins
        return np.broadcast_to(k, ix.shape), iy, ix

    def same_cells(self, other: Grid) -> bool:
        """Whether ``other`` has these cells (origin, edge and counts; layers aside)."""
        return (self.x0, self.y0, self.res, self.nx, self.ny) == (other.x0, other.y0, other.res, other.nx, other.ny)

    def to_dict(self) -> dict:
        """The fields as JSON values (the space by its name, the levels as a list)."""
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d["space"] = self.space.value
        d["z_levels"] = list(self.z_levels)
        return d
