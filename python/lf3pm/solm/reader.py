"""Reading a SOLM: channels, cell coordinates, interpolated queries."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from lf3pm.errors import Lf3pmError
from lf3pm.grid_field import axis_weights, bilinear
from lf3pm.solm.grid import SolmGrid
from lf3pm.solm.store import CHANNELS, MASKS


class Solm:
    """A built Static Observation Loss Map (see :func:`Solm.open`)."""

    def __init__(self, group, grid: SolmGrid):
        self._group = group
        self.grid_spec = grid
        self.attrs = dict(group.attrs)

    @classmethod
    def open(cls, path) -> "Solm":
        """Opens the store at ``path`` (read-only); an incomplete build is an error."""
        import zarr

        path = Path(path)
        if not path.exists():
            raise Lf3pmError(f"{path}: no such SOLM store")
        try:
            group = zarr.open_group(str(path), mode="r")
            spec = dict(group.attrs["grid"])
        except Exception as err:  # noqa: BLE001 - any unreadable store is refused the same way
            raise Lf3pmError(f"{path} is not a SOLM store ({err.__class__.__name__})") from None
        if not np.all(group["done"][...]):
            raise Lf3pmError(f"{path} is an unfinished build: run the same `lf3pm solm build` again "
                             "to resume it")
        spec["z_levels"] = tuple(spec["z_levels"])
        return cls(group, SolmGrid(**spec))

    @property
    def channels(self) -> tuple:
        return CHANNELS + MASKS

    def channel(self, name: str) -> np.ndarray:
        """The stored array of channel ``name`` (NaN where not evaluated)."""
        if name not in self.channels and name != "ground_z":
            raise Lf3pmError(f"unknown channel {name!r}; channels: {', '.join(self.channels)}")
        return self._group[name][...]

    def occupancy(self) -> tuple[np.ndarray, int]:
        """The occupancy layer of a ground robot's SOLM (occupancy.py): a (ny k, nx k)
        bool array, True where a cell holds a map point in the body's height band, and k."""
        k = self.attrs.get("occupancy_factor")
        if k is None:
            raise Lf3pmError("this SOLM has no occupancy layer, which the planner needs to keep the robot off "
                             "thin obstacles (an older build, or an r3 grid): build it again "
                             "into a new store")
        return self._group["occupied"][...].astype(bool), int(k)

    def grid(self) -> tuple:
        """Cell-centre coordinates as arrays of the channels' shape: (x, y) for r2,
        (x, y, yaw) for se2, (x, y, z) for r3."""
        g = self.grid_spec
        if g.space == "r2":
            y, x = np.meshgrid(g.ys(), g.xs(), indexing="ij")
            return x, y
        third = g.yaws() if g.space == "se2" else np.asarray(g.z_levels)
        t, y, x = np.meshgrid(third, g.ys(), g.xs(), indexing="ij")
        return x, y, t

    def query(self, x, y, yaw=0.0, channel: str = "q_n", *, z=None):
        """Trilinear interpolation of ``channel`` at (x, y, yaw) (se2: yaw periodic)
        or (x, y, z) (r3), vectorised; returns (value, gradient) with the gradient's
        last axis d/dx, d/dy, d/dyaw (or d/dz; r2: d/dx, d/dy). Positions are
        clamped to the grid's cell centres."""
        g = self.grid_spec
        data = self.channel(channel).astype(np.float64)
        x, y = np.asarray(x, float), np.asarray(y, float)
        if g.space == "r2":
            data = data[None]  # one layer: the same code, no third axis
            k0 = k1 = np.zeros(np.broadcast(x, y).shape, dtype=np.int64)
            tk, step, fk = 0.0, 1.0, 0.0
        elif g.space == "se2":
            step = 2 * math.pi / g.yaw_bins
            f = np.mod(np.asarray(yaw, float), 2 * math.pi) / step
            ik = np.floor(f).astype(int)
            tk = f - ik
            k0, k1 = ik % g.yaw_bins, (ik + 1) % g.yaw_bins
            fk = 1.0 if g.yaw_bins > 1 else 0.0
        else:
            levels = np.asarray(g.z_levels)
            zz = np.asarray(z if z is not None else levels[0], float)
            dz = levels[1] - levels[0] if len(levels) > 1 else 1.0
            fk, k0, k1, tk = axis_weights(zz, levels[0] - 0.5 * dz, dz, len(levels))
            step = dz

        def plane(k):
            return bilinear(data, x, y, g.x0, g.y0, g.res, layer=k)

        a, ax, ay = plane(k0)
        b, bx, by = plane(k1)
        value = (1 - tk) * a + tk * b
        grad = np.stack([(1 - tk) * ax + tk * bx, (1 - tk) * ay + tk * by, (b - a) / step * fk], axis=-1)
        return value, (grad[..., :2] if g.space == "r2" else grad)
