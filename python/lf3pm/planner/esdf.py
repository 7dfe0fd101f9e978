"""Euclidean signed distance field (ESDF) over a SOLM's x-y grid.

Values, in metres, per cell centre: outside blocked cells, the distance to the
nearest blocked cell's centre minus half a cell (so a free cell next to a wall
reads res/2: the distance to the wall's cell edge along an axis); inside, minus
the distance to the nearest free cell's centre plus half a cell. Computed with
scipy's exact Euclidean distance transform. With no blocked cell the field is
+inf everywhere (-inf when every cell is blocked).

Unknown cells (no map point in the column: the robot cannot know the ground
there) are blocked by default, ``unknown="obstacle"``: the field then keeps the
robot away from them like from an obstacle and they are not traversable.
``unknown="free"`` treats them as free ground.

A SOLM's obstacle mask already holds every cell whose robot body (of the
build's ``robot_radius``) would touch the map, so ``r_safe`` in
:meth:`Esdf.traversable` is an extra margin on top of it.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import distance_transform_edt

from lf3pm.errors import Lf3pmError

UNKNOWN_POLICIES = ("obstacle", "free")


class Esdf:
    """Signed distance field on the cells x0 + (i + 0.5) res, y0 + (j + 0.5) res.

    Attributes: ``x0, y0, res, nx, ny``; ``values`` (ny, nx) float64 metres;
    ``obstacle`` and ``unknown`` (ny, nx) bool masks; ``unknown_policy``.
    """

    def __init__(self, values, obstacle, unknown, x0: float, y0: float, res: float,
                 unknown_policy: str = "obstacle"):
        self.values = np.asarray(values, dtype=np.float64)
        self.obstacle = np.asarray(obstacle, dtype=bool)
        self.unknown = np.asarray(unknown, dtype=bool)
        self.ny, self.nx = self.values.shape
        self.x0, self.y0, self.res = float(x0), float(y0), float(res)
        self.unknown_policy = unknown_policy

    @classmethod
    def from_mask(cls, mask, x0: float, y0: float, res: float, *, unknown=None,
                  unknown_policy: str = "obstacle") -> "Esdf":
        """The field of the (ny, nx) obstacle ``mask`` (True = obstacle), with an
        optional (ny, nx) ``unknown`` mask handled by ``unknown_policy``."""
        mask = np.asarray(mask, dtype=bool)
        if mask.ndim != 2 or mask.size == 0:
            raise Lf3pmError(f"an ESDF needs a non-empty 2-D obstacle mask, got shape {mask.shape}")
        if not (res > 0 and np.isfinite(res)):
            raise Lf3pmError(f"ESDF cell size must be > 0, got {res}")
        if unknown_policy not in UNKNOWN_POLICIES:
            raise Lf3pmError(f"unknown-cell policy must be one of {', '.join(UNKNOWN_POLICIES)}, "
                             f"got {unknown_policy!r}")
        unknown = np.zeros_like(mask) if unknown is None else np.asarray(unknown, dtype=bool)
        if unknown.shape != mask.shape:
            raise Lf3pmError(f"unknown mask shape {unknown.shape} differs from obstacle mask {mask.shape}")
        blocked = mask | unknown if unknown_policy == "obstacle" else mask
        if not blocked.any():
            values = np.full(mask.shape, np.inf)
        elif blocked.all():
            values = np.full(mask.shape, -np.inf)
        else:
            outside = distance_transform_edt(~blocked) * res
            inside = distance_transform_edt(blocked) * res
            values = np.where(blocked, 0.5 * res - inside, outside - 0.5 * res)
        return cls(values, mask, unknown, x0, y0, res, unknown_policy)

    @classmethod
    def from_solm(cls, solm, *, unknown_policy: str = "obstacle") -> "Esdf":
        """The field of a SOLM's obstacle and unknown masks (se2: a cell is blocked
        when any yaw bin is; the robot body is round, so all bins agree)."""
        g = solm.grid_spec
        if g.space not in ("r2", "se2"):
            raise Lf3pmError(f"the planner needs an r2 or se2 SOLM, got {g.space}")
        obstacle = np.asarray(solm.channel("obstacle")).astype(bool)
        unknown = np.asarray(solm.channel("unknown")).astype(bool)
        if obstacle.ndim == 3:
            obstacle, unknown = obstacle.any(axis=0), unknown.any(axis=0)
        return cls.from_mask(obstacle, g.x0, g.y0, g.res, unknown=unknown,
                             unknown_policy=unknown_policy)

    def distance(self, x, y):
        """Bilinear interpolation between cell centres at (x, y), vectorised:
        (distance, gradient) with the gradient's last axis d/dx, d/dy. Positions
        outside the centres are clamped to the border (zero gradient across it)."""
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        v = self.values
        if not np.isfinite(v[0, 0]):  # no free or no blocked cell: a constant field
            shape = np.broadcast(x, y).shape
            return np.full(shape, v[0, 0]), np.zeros(shape + (2,))
        inx, ix, tx = _axis(x, self.x0, self.res, self.nx)
        iny, iy, ty = _axis(y, self.y0, self.res, self.ny)
        ix1, iy1 = np.minimum(ix + 1, self.nx - 1), np.minimum(iy + 1, self.ny - 1)
        v00, v01, v10, v11 = v[iy, ix], v[iy, ix1], v[iy1, ix], v[iy1, ix1]
        value = (1 - ty) * ((1 - tx) * v00 + tx * v01) + ty * ((1 - tx) * v10 + tx * v11)
        ddx = ((1 - ty) * (v01 - v00) + ty * (v11 - v10)) / self.res * inx
        ddy = ((1 - tx) * (v10 - v00) + tx * (v11 - v01)) / self.res * iny
        return value, np.stack([ddx, ddy], axis=-1)

    def traversable(self, r_safe: float = 0.0) -> np.ndarray:
        """(ny, nx) bool: cells not blocked whose value is at least ``r_safe`` metres."""
        if not (r_safe >= 0):
            raise Lf3pmError(f"r_safe must be >= 0, got {r_safe}")
        blocked = self.obstacle | (self.unknown & (self.unknown_policy == "obstacle"))
        return (self.values >= r_safe) & ~blocked

    def blocked_reason(self, ix: int, iy: int, r_safe: float = 0.0) -> str | None:
        """Why cell (ix, iy) is not traversable, or None when it is."""
        if self.obstacle[iy, ix]:
            return "inside an obstacle"
        if self.unknown[iy, ix] and self.unknown_policy == "obstacle":
            return "on unknown ground (no map under the cell)"
        if self.values[iy, ix] < r_safe:
            return (f"{self.values[iy, ix]:.2f} m from an obstacle or unknown ground, "
                    f"closer than r_safe = {r_safe:g} m")
        return None


def _axis(v, origin: float, res: float, n: int):
    """Lower cell index, weight of the upper one, and 1 inside / 0 where clamped,
    for linear interpolation between the centres of n cells along one axis."""
    f = (v - origin) / res - 0.5
    inside = ((f >= 0) & (f <= n - 1)).astype(np.float64) if n > 1 else np.zeros_like(f)
    f = np.clip(f, 0.0, max(n - 1, 0))
    i = np.floor(f).astype(np.int64)
    return inside, np.minimum(i, max(n - 1, 0)), f - i
