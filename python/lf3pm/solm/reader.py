"""Reading a SOLM: channels, cell coordinates, interpolated queries."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from lf3pm.errors import CorruptStoreError, Lf3pmError
from lf3pm.grid import Space
from lf3pm.grid_field import axis_weights, bilinear
from lf3pm.solm.grid import SolmGrid
from lf3pm.solm.store import CHANNELS, MASKS, QUOTED, read_array


class Solm:
    """A built Static Observation Loss Map (see :func:`Solm.open`)."""

    def __init__(self, group, grid: SolmGrid):
        self._group = group
        self.grid_spec = grid
        self.attrs = dict(group.attrs)

    @classmethod
    def open(cls, path) -> Solm:
        """Opens the store at ``path`` (read-only); an incomplete build is an error, and so
        is a store whose metadata or chunks do not decode (CorruptStoreError, naming the
        file; also when a channel is read later)."""
        import zarr

        if not isinstance(path, (str, os.PathLike)):
            raise Lf3pmError(f"a SOLM store is a path, got {type(path).__name__}")
        path = Path(path)
        if not path.exists():
            raise Lf3pmError(f"{path}: no such SOLM store")
        try:
            group = zarr.open_group(str(path), mode="r")
            spec = dict(group.attrs["grid"])
        except Exception as err:  # noqa: BLE001 - any unreadable store is refused the same way
            raise Lf3pmError(f"{path} is not a SOLM store ({err.__class__.__name__})") from None
        if not np.all(read_array(group, "done")):
            raise Lf3pmError(f"{path} is an unfinished build: run the same `lf3pm solm build` again to resume it")
        try:
            spec["z_levels"] = tuple(spec["z_levels"])
            grid = SolmGrid(**spec)
        except Exception as err:  # noqa: BLE001 - attributes edited into any shape
            raise CorruptStoreError(
                f"{path / 'zarr.json'}: the SOLM's grid attribute is malformed "
                f"({err.__class__.__name__}); build the store again"
            ) from None
        return cls(group, grid)

    @property
    def channels(self) -> tuple:
        return CHANNELS + MASKS

    def channel(self, name: str) -> np.ndarray:
        """The stored array of channel ``name`` (NaN where not evaluated)."""
        if not isinstance(name, str) or (name not in self.channels and name != "ground_z"):
            raise Lf3pmError(f"unknown channel {repr(name)[:QUOTED]}; channels: {', '.join(self.channels)}")
        return read_array(self._group, name)

    def occupancy(self) -> tuple[np.ndarray, int]:
        """The occupancy layer of a ground robot's SOLM (occupancy.py): a (ny k, nx k)
        bool array, True where a cell holds a map point in the body's height band, and k."""
        k = self.attrs.get("occupancy_factor")
        if k is None:
            raise Lf3pmError(
                "this SOLM has no occupancy layer, which the planner needs to keep the robot off "
                "thin obstacles (an older build, or an r3 grid): build it again "
                "into a new store"
            )
        return read_array(self._group, "occupied").astype(bool), int(k)

    def grid(self) -> tuple:
        """Cell-centre coordinates as arrays of the channels' shape: (x, y) for r2,
        (x, y, yaw) for se2, (x, y, z) for r3, (x, y, z, yaw) for r3yaw."""
        g = self.grid_spec
        if g.space is Space.R2:
            y, x = np.meshgrid(g.ys(), g.xs(), indexing="ij")
            return x, y
        if g.space is Space.R3YAW:
            z, yaw = g.layer_poses()
            k, y, x = np.meshgrid(np.arange(g.layers), g.ys(), g.xs(), indexing="ij")
            return x, y, z[k], yaw[k]
        third = g.yaws() if g.space is Space.SE2 else np.asarray(g.z_levels)
        t, y, x = np.meshgrid(third, g.ys(), g.xs(), indexing="ij")
        return x, y, t

    def over_yaw(self, channel: str = "q_n") -> tuple[np.ndarray, np.ndarray]:
        """An r3yaw SOLM's ``channel`` at its best yaw: (the minimum over the yaw bins, the
        yaw of that bin in radians), each of shape (nz, ny, nx); NaN where no bin was
        evaluated (obstacles)."""
        g = self.grid_spec
        if g.space is not Space.R3YAW:
            raise Lf3pmError(f"over_yaw needs an r3yaw SOLM, this one is {g.space}")
        data = self.channel(channel).reshape(len(g.z_levels), g.yaw_bins, g.ny, g.nx)
        evaluated = np.isfinite(data).any(axis=1)
        best = np.argmin(np.where(np.isfinite(data), data, np.inf), axis=1)
        low = np.where(evaluated, np.take_along_axis(data, best[:, None], axis=1)[:, 0], np.nan)
        return low, np.where(evaluated, g.yaws()[best], np.nan)

    def query(self, x, y, yaw=0.0, channel: str = "q_n", *, z=None):
        """Interpolation of ``channel`` at (x, y, yaw) (se2: yaw periodic), (x, y, z) (r3)
        or (x, y, z, yaw) (r3yaw: linear in each, yaw periodic), vectorised; returns
        (value, gradient) with the gradient's last axis d/dx, d/dy and d/dyaw (se2), d/dz
        (r3) or d/dz, d/dyaw (r3yaw); r2: d/dx, d/dy. Positions are clamped to the grid's
        cell centres. The coordinates must be finite numbers of shapes that broadcast
        together (else Lf3pmError)."""
        g = self.grid_spec
        x, y, yaw, *z = _coordinates(x=x, y=y, yaw=yaw, **({} if z is None else {"z": z}))
        data = self.channel(channel).astype(np.float64)
        if g.space is Space.R3YAW:
            return _query_r3yaw(g, data, x, y, yaw, z[0] if z else np.float64(g.z_levels[0]))
        if g.space is Space.R2:
            data = data[None]  # one layer: the same code, no third axis
            k0 = k1 = np.zeros(np.broadcast(x, y).shape, dtype=np.int64)
            tk, step, fk = 0.0, 1.0, 0.0
        elif g.space is Space.SE2:
            fk, k0, k1, tk, step = _yaw_weights(yaw, g.yaw_bins)
        else:
            levels = np.asarray(g.z_levels)
            zz = z[0] if z else np.float64(levels[0])
            dz = levels[1] - levels[0] if len(levels) > 1 else 1.0
            fk, k0, k1, tk = axis_weights(zz, levels[0] - 0.5 * dz, dz, len(levels))
            step = dz

        def plane(k):
            return bilinear(data, x, y, g.x0, g.y0, g.res, layer=k)

        a, ax, ay = plane(k0)
        b, bx, by = plane(k1)
        value = (1 - tk) * a + tk * b
        grad = np.stack([(1 - tk) * ax + tk * bx, (1 - tk) * ay + tk * by, (b - a) / step * fk], axis=-1)
        return value, (grad[..., :2] if g.space is Space.R2 else grad)


def _yaw_weights(yaw, bins: int):
    """Linear interpolation between periodic yaw bins centred on k 2 pi / bins, as
    axis_weights gives it along an axis: (1 or 0 with one bin, k0, k1, t, the bin width)."""
    step = 2 * math.pi / bins
    f = np.mod(yaw, 2 * math.pi) / step
    k = np.floor(f).astype(int)
    return (1.0 if bins > 1 else 0.0), k % bins, (k + 1) % bins, f - k, step


def _query_r3yaw(g, data, x, y, yaw, z):
    """Solm.query on an r3yaw grid: bilinear in (x, y) on the four layers around (z,
    yaw), linear between them in z and periodic yaw."""
    levels = np.asarray(g.z_levels)
    dz = levels[1] - levels[0] if len(levels) > 1 else 1.0
    fz, z0, z1, tz = axis_weights(z, levels[0] - 0.5 * dz, dz, len(levels))
    fb, b0, b1, tb, step = _yaw_weights(yaw, g.yaw_bins)

    def plane(iz, b):
        return bilinear(data, x, y, g.x0, g.y0, g.res, layer=iz * g.yaw_bins + b)

    corners = {(i, j): plane(iz, b) for i, iz in enumerate((z0, z1)) for j, b in enumerate((b0, b1))}
    wz, wb = (1 - tz, tz), (1 - tb, tb)
    value = sum(wz[i] * wb[j] * corners[i, j][0] for i in (0, 1) for j in (0, 1))
    gx = sum(wz[i] * wb[j] * corners[i, j][1] for i in (0, 1) for j in (0, 1))
    gy = sum(wz[i] * wb[j] * corners[i, j][2] for i in (0, 1) for j in (0, 1))
    along_z = sum(wb[j] * (corners[1, j][0] - corners[0, j][0]) for j in (0, 1)) / dz * fz
    along_yaw = sum(wz[i] * (corners[i, 1][0] - corners[i, 0][0]) for i in (0, 1)) / step * fb
    return value, np.stack([gx, gy, along_z, along_yaw], axis=-1)


def _coordinates(**named) -> list[np.ndarray]:
    """The query's coordinates as float arrays, in the order given: Lf3pmError naming the
    first that is not numbers or not finite, or when their shapes do not broadcast."""
    arrays = []
    for name, value in named.items():
        try:
            a = np.asarray(value)
        except ValueError:  # ragged nesting
            a = np.asarray(None)
        if a.dtype.kind not in "biuf":  # None, strings, objects and complex numbers are no coordinates
            raise Lf3pmError(f"Solm.query: {name} must be a number or an array of numbers, got {repr(value)[:QUOTED]}")
        a = a.astype(np.float64)
        if not np.isfinite(a).all():
            raise Lf3pmError(f"Solm.query: {name} must be finite, got {a[~np.isfinite(a)].flat[0]}")
        arrays.append(a)
    try:
        np.broadcast(*arrays)
    except ValueError:
        shapes = ", ".join(f"{name} {a.shape}" for name, a in zip(named, arrays))
        raise Lf3pmError(f"Solm.query: the coordinates' shapes do not broadcast together ({shapes})") from None
    return arrays
