"""Euclidean signed distance field (ESDF) over a SOLM's x-y grid, conservative.

The obstacle geometry B is the union of the blocked cells as closed squares,
and s(p) the exact signed distance: outside B the distance to it; inside minus
the distance to what is not blocked. ``values`` holds one number per cell
centre, in metres; :meth:`Esdf.distance` interpolates them bilinearly between
centres and clamps beyond the outermost ones (as the optimiser's GridField
does). The guarantee, for every point p of the plane (on or off the grid):

    interpolated field(p) <= s(p)

so a clearance read from the field is never more than the true one. Inside B
the values measure to the grid's free cells only (beyond the grid the map says
nothing), which can only lower them. With no blocked cell the field is +inf
everywhere, and -inf when every cell is blocked.

How (lengths in cells; a lattice of k = 8 points per cell and axis, h = 1/k):

1. Exact s on the lattice. The point of an axis-aligned square with lattice
   corners nearest to a lattice point is its per-axis clamp, itself a lattice
   point, so scipy's exact EDT between the lattice points in B (on a blocked
   square) and the others gives s exactly there, and likewise inside. Cell
   centres are lattice points (k is even): their exact values are v.
2. Interpolation error. On each lattice square S (side h, within one cell),
   field - s = (field - J) + (J - s), J being the bilinear interpolation of s
   from S's corners. The first is bilinear, so largest at a corner of S; the
   second is at most a bound gap_S:
   - S in a free cell: s(p) = |p - b| for b a nearest point of B. When b is the
     projection onto a square's edge, s is linear over S: no gap. Else b is a
     grid vertex; at a corner of S the cone's gap is (2 - sqrt 2)/4 h, and
     otherwise b lies max(h, m) or more from S (m: a lower bound of s over S),
     where the cone curves by at most 1 / max(h, m); the bilinear weights then
     give gap_S <= h^2 / (4 max(h, m)), which covers both.
   - S in a blocked cell: 0 when the corners' nearest free points (scipy's
     feature transform) lie in one rectangle R of free cells (s is then at least
     minus the distance to R, a convex function that J of s does not exceed);
     else h / sqrt 2, s being 1-Lipschitz (this is where the distance to the
     free cells switches sides: a convex kink bilinear interpolation overshoots).
   So the field v - d, for a correction d >= 0 per centre, is conservative iff at
   every lattice point q between the centres interp(d)(q) >= need(q) :=
   interp(v)(q) - s(q) + the largest gap_S of the squares touching q.
3. The correction. d = the largest need over each centre's interpolation cells
   is feasible. Blocked centres then start one cell lower still, and each
   centre is raised to the highest value the constraints allow, free ones
   first (the 2 x 2 parity classes share no interpolation cell, so a class moves
   at once). At a convex corner of B the four centres around it have exact
   values summing to 1.21 cells while the field there, their mean, must be <= 0;
   this puts that loss in the blocked centre, so free centres (what
   :meth:`Esdf.traversable` reads) stay near their exact values.
4. Beyond the outermost centres the field is clamped to them, and s does not
   decrease along the clamp (B lies in the grid, and a border row's free cells
   span it up to the edge), so the bound carries over.

Measured against a brute force (bench/bench_esdf.py, seeded masks, in cells; the
field it replaced, and what that one let plans do: docs/planner_frontend.md):
its pessimism 0.05-0.5 from an obstacle averages 0.21 on scattered boxes and
0.24 on random cells (corners dominate; 0.03-0.06 along a straight wall), and
0.03-0.1 on free centres (at most 0.39). Building it costs ~100 bytes and
~0.4 us per lattice point (0.35 s and 100 MB on 60 x 236 cells); above 2^21
lattice points k drops (6, 4, then 2: 2.7 s and 500 MB on 1000 x 1000 cells),
which keeps the bound and loosens it.

Unknown cells (no map point in the column: the robot cannot know the ground
there) are blocked by default, ``unknown="obstacle"``: the field then keeps the
robot away from them like from an obstacle and they are not traversable.
``unknown="free"`` treats them as free ground.

A SOLM's obstacle mask holds the cells whose square holds a map point in the
robot body's height band (wherever in the square: a thin pole off the centre
still blocks). :meth:`Esdf.from_solm` subtracts the build's ``robot_radius``
from the field, so its values are the body's clearance, never more than the
true one, and ``r_safe`` in :meth:`Esdf.traversable` is a margin beyond the body.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.ndimage import distance_transform_edt, maximum_filter

from lf3pm.config import UNKNOWN_POLICIES
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Grid
from lf3pm.grid_field import GridField, bilinear

_FAR = 1.0e3  # metres: the clamp of +-inf values in grid_field()


_SUPERSAMPLE = 8  # lattice points per cell and axis (even: centres lie on it)
_MAX_LATTICE = 1 << 21  # points (~100 bytes each at the peak); fewer per cell, down to 2, beyond
_BLOCKED_HEADSTART = 1.0  # cells blocked centres start below what they need (step 3)


class Esdf:
    """Signed distance field over the cells of an R2 :class:`lf3pm.grid.Grid`.

    Attributes: ``grid`` (and its ``x0, y0, res, nx, ny``); ``values`` (ny, nx) float64 metres at the
    cells' centres, the clearance of a round body of ``body_radius`` (the distance
    less the radius); ``obstacle`` and ``unknown`` (ny, nx) bool masks;
    ``unknown_policy``; ``field_res``, the edge of the cells the field itself is
    interpolated between: ``res``, or finer when built from a SOLM's occupancy
    (:meth:`from_solm`), whose values at the centres are then samples of it.
    """

    def __init__(
        self,
        values,
        obstacle,
        unknown,
        x0: float,
        y0: float,
        res: float,
        unknown_policy: str = "obstacle",
        body_radius: float = 0.0,
        field=None,
    ):
        self.body_radius = float(body_radius)
        self.obstacle = np.asarray(obstacle, dtype=bool)
        self.unknown = np.asarray(unknown, dtype=bool)
        ny, nx = self.obstacle.shape
        self.grid = Grid.plane(float(x0), float(y0), float(res), nx, ny)
        self.unknown_policy = unknown_policy
        # The field: (values, cell edge) on a grid from (x0, y0); the centres' values by default.
        self._field, self.field_res = (np.asarray(values, dtype=np.float64), self.res) if field is None else field
        self.values = np.asarray(values, dtype=np.float64) if field is None else self.distance(*self.centres())[0]

    @classmethod
    def from_mask(
        cls,
        mask,
        x0: float,
        y0: float,
        res: float,
        *,
        unknown=None,
        unknown_policy: str = "obstacle",
        body_radius: float = 0.0,
    ) -> Esdf:
        """The field of the (ny, nx) obstacle ``mask`` (True = obstacle), with an
        optional (ny, nx) ``unknown`` mask handled by ``unknown_policy``, for a round
        body of ``body_radius`` (its values are the distance less the radius)."""
        mask = np.asarray(mask, dtype=bool)
        if mask.ndim != 2 or mask.size == 0:
            raise Lf3pmError(f"an ESDF needs a non-empty 2-D obstacle mask, got shape {mask.shape}")
        if not (res > 0 and np.isfinite(res)):
            raise Lf3pmError(f"ESDF cell size must be > 0, got {res}")
        if not (body_radius >= 0 and np.isfinite(body_radius)):
            raise Lf3pmError(f"body radius must be a number >= 0 m, got {body_radius}")
        if unknown_policy not in UNKNOWN_POLICIES:
            raise Lf3pmError(
                f"unknown-cell policy must be one of {', '.join(UNKNOWN_POLICIES)}, got {unknown_policy!r}"
            )
        unknown = np.zeros_like(mask) if unknown is None else np.asarray(unknown, dtype=bool)
        if unknown.shape != mask.shape:
            raise Lf3pmError(f"unknown mask shape {unknown.shape} differs from obstacle mask {mask.shape}")
        blocked = mask | unknown if unknown_policy == "obstacle" else mask
        if not blocked.any():
            values = np.full(mask.shape, np.inf)
        elif blocked.all():
            values = np.full(mask.shape, -np.inf)
        else:
            values = _conservative_values(blocked) * res - body_radius
        return cls(values, mask, unknown, x0, y0, res, unknown_policy, body_radius)

    @classmethod
    def from_solm(cls, solm, *, unknown_policy: str = "obstacle") -> Esdf:
        """The body's clearance on a SOLM: the field of its occupancy layer (the
        cells, k times finer than the SOLM's, holding a map point in the body's
        height band) and, by ``unknown_policy``, its unknown cells, less its robot
        radius. The SOLM's own cells are not traversable where its ``obstacle`` mask
        is set (se2: in any yaw bin; the body is round, so all bins agree)."""
        g = solm.grid_spec
        if not g.space.ground:
            raise Lf3pmError(f"the planner needs an r2 or se2 SOLM, got {g.space}")
        obstacle, unknown = solm_masks(solm)
        if unknown_policy not in UNKNOWN_POLICIES:
            raise Lf3pmError(
                f"unknown-cell policy must be one of {', '.join(UNKNOWN_POLICIES)}, got {unknown_policy!r}"
            )
        occupied, k = solm.occupancy()
        radius = float(solm.attrs["robot_radius"])
        cells = g.refined(k)
        fine = cls.from_mask(
            occupied,
            cells.x0,
            cells.y0,
            cells.res,
            unknown=np.kron(unknown, np.ones((k, k), bool)),
            unknown_policy=unknown_policy,
            body_radius=radius,
        )
        return cls(None, obstacle, unknown, g.x0, g.y0, g.res, unknown_policy, radius, field=(fine.values, fine.res))

    x0 = property(lambda self: self.grid.x0)
    y0 = property(lambda self: self.grid.y0)
    res = property(lambda self: self.grid.res)
    nx = property(lambda self: self.grid.nx)
    ny = property(lambda self: self.grid.ny)

    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """(x, y) of the cells' centres, arrays of shape (ny, nx)."""
        return self.grid.centres()

    def distance(self, x, y):
        """Bilinear interpolation of the field at (x, y), vectorised: (clearance,
        gradient) with the gradient's last axis d/dx, d/dy. Positions outside the
        field's centres are clamped to its border (zero gradient across it)."""
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        v = self._field
        if not np.isfinite(v[0, 0]):  # no free or no blocked cell: a constant field
            shape = np.broadcast(x, y).shape
            return np.full(shape, v[0, 0]), np.zeros(shape + (2,))
        value, ddx, ddy = bilinear(v, x, y, self.x0, self.y0, self.field_res)
        return value, np.stack([ddx, ddy], axis=-1)

    def grid_field(self) -> GridField:
        """The field as a :class:`GridField` for the C++ core (same interpolation),
        +-inf (no blocked or no free cell) clamped to +-1 km: the core needs finite
        values, and beyond that distance clearance never matters."""
        return GridField(np.clip(self._field, -_FAR, _FAR), self.x0, self.y0, self.field_res)

    @cached_property
    def cell_bounds(self) -> GridField | None:
        """A GridField on the cells whose value in each is at least the field anywhere
        in it (the hybrid search's open cells), or None when the field lives on the
        cells themselves. Within a cell the field interpolates the field centres in
        it and those one beyond: the bound is their largest. Built once per field."""
        if self.field_res == self.res:
            return None
        k = round(self.res / self.field_res)
        near = maximum_filter(self._field, size=3, mode="nearest")
        bound = near.reshape(self.ny, k, self.nx, k).max(axis=(1, 3))
        return GridField.on(self.grid, np.clip(bound, -_FAR, _FAR))

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
            return self.clearance_reason(self.values[iy, ix], r_safe)
        return None

    def clearance_reason(self, clearance: float, r_safe: float) -> str:
        """Why a point whose field reads ``clearance`` is closer than ``r_safe``."""
        within = (
            f"the robot radius {self.body_radius:g} m + {r_safe:g} m"
            if self.body_radius > 0
            else f"r_safe {r_safe:g} m"
        )
        return (
            f"{max(clearance + self.body_radius, 0.0):.2f} m from an obstacle or unknown ground, closer than {within}"
        )


def solm_masks(solm) -> tuple[np.ndarray, np.ndarray]:
    """A SOLM's (ny, nx) obstacle and unknown masks (se2: set when any yaw bin is)."""
    obstacle = np.asarray(solm.channel("obstacle")).astype(bool)
    unknown = np.asarray(solm.channel("unknown")).astype(bool)
    if obstacle.ndim == 3:
        obstacle, unknown = obstacle.any(axis=0), unknown.any(axis=0)
    return obstacle, unknown


def _conservative_values(blocked: np.ndarray) -> np.ndarray:
    """Centre values, in cells, whose bilinear interpolation never exceeds the
    signed distance to the blocked squares (the module's steps 1 to 3)."""
    ny, nx = blocked.shape
    k = _SUPERSAMPLE
    while k > 2 and (k * nx + 1) * (k * ny + 1) > _MAX_LATTICE:
        k -= 2
    lattice, nearest_free = _lattice_distance(blocked, k)
    hull = _Hull(ny, nx, k)
    exact = lattice[k // 2 :: k, k // 2 :: k]
    on_hull = np.ix_(hull.y.index, hull.x.index)
    s = lattice[on_hull]
    h = 1.0 / k
    # Step 2's gap per lattice square (each lies in the cell of its lower corner).
    in_blocked = blocked[np.ix_(hull.y.index[:-1] // k, hull.x.index[:-1] // k)]
    shared = _shared_free_rectangle(blocked, nearest_free[0][on_hull], nearest_free[1][on_hull], k)
    m = np.maximum(h, _corners(s, np.minimum) - h / np.sqrt(2.0))
    gap = np.where(in_blocked, np.where(shared, 0.0, h / np.sqrt(2.0)), h * h / (4.0 * m))
    need = hull.interpolate(exact) - s + _corners(np.pad(gap, 1), np.maximum)
    # Step 3: a feasible start, then each parity class raised as far as it can go.
    correction = hull.centre_max(hull.cell_max(need)) + np.where(blocked, _BLOCKED_HEADSTART, 0.0)
    for movable in (~blocked, blocked):  # one round each: further rounds change nothing
        for parity in ((0, 0), (0, 1), (1, 0), (1, 1)):
            correction = _raise_class(correction, need, hull, parity, movable)
    return exact - correction


def _corners(a: np.ndarray, op) -> np.ndarray:
    """``op`` over the four corners of each square between neighbouring points."""
    return op(op(a[:-1, :-1], a[:-1, 1:]), op(a[1:, :-1], a[1:, 1:]))


def _lattice_distance(blocked: np.ndarray, k: int):
    """Exact signed distance, in cells, at the (k ny + 1, k nx + 1) lattice points
    (y0 + j / k, x0 + i / k), inside to the grid's free squares; and, per point,
    the (row, column) lattice index of a nearest free point."""
    ny, nx = blocked.shape
    sub = np.pad(np.repeat(np.repeat(blocked, k, axis=0), k, axis=1), 1, mode="edge")
    # the lattice squares around each point (the edge padding repeats in-grid ones)
    around = [sub[dy : dy + k * ny + 1, dx : dx + k * nx + 1] for dy in (0, 1) for dx in (0, 1)]
    in_blocked = np.logical_or.reduce(around)
    in_free = ~np.logical_and.reduce(around)
    outside = distance_transform_edt(~in_blocked) / k
    inside, nearest_free = distance_transform_edt(~in_free, return_indices=True)
    return np.where(in_blocked, -inside / k, outside), nearest_free


def _shared_free_rectangle(blocked: np.ndarray, rows, cols, k: int) -> np.ndarray:
    """Per square between neighbouring points, whether the nearest free points of
    its four corners lie in one rectangle of free cells; ``rows`` and ``cols``
    hold, per point, the lattice row and column of its nearest free point."""
    ny, nx = blocked.shape
    count = np.pad(blocked.cumsum(axis=0).cumsum(axis=1), ((1, 0), (1, 0)))  # blocked cells below-left
    shared = np.zeros((rows.shape[0] - 1, rows.shape[1] - 1), dtype=bool)
    for r0, r1, r_ok in _covering_cells(_corners(rows, np.minimum), _corners(rows, np.maximum), k, ny):
        for c0, c1, c_ok in _covering_cells(_corners(cols, np.minimum), _corners(cols, np.maximum), k, nx):
            r0, r1 = np.clip(r0, 0, ny - 1), np.clip(r1, 0, ny - 1)
            c0, c1 = np.clip(c0, 0, nx - 1), np.clip(c1, 0, nx - 1)
            inside = count[r1 + 1, c1 + 1] - count[r0, c1 + 1] - count[r1 + 1, c0] + count[r0, c0]
            shared |= r_ok & c_ok & (inside == 0)
    return shared


def _covering_cells(lo, hi, k: int, n: int):
    """The cell ranges [first, last] whose closed extent covers the lattice interval
    [lo, hi], each with whether it lies in the n cells: twice the same range, or
    the cells either side of the grid line the interval is on."""
    first, last = lo // k, -(-hi // k) - 1
    options = ((np.minimum(first, last), last), (first, np.maximum(first, last)))
    return [(a, b, (a >= 0) & (b <= n - 1)) for a, b in options]


@dataclass(frozen=True)
class _HullAxis:
    """Along one axis, the lattice points from the first to the last centre: their
    lattice ``index``, ``lower`` and ``upper`` centre and the upper one's weight
    ``t``. One centre gives two equal points (a square of zero width)."""

    n: int
    k: int
    index: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    t: np.ndarray

    @classmethod
    def of(cls, n: int, k: int) -> _HullAxis:
        if n == 1:
            zero = np.zeros(2, dtype=np.int64)
            return cls(n, k, np.full(2, k // 2), zero, zero, np.zeros(2))
        steps = np.arange((n - 1) * k + 1)
        lower = np.minimum(steps // k, n - 2)
        return cls(n, k, k // 2 + steps, lower, lower + 1, (steps - lower * k) / k)

    def cell_max(self, a: np.ndarray, axis: int) -> np.ndarray:
        """Per interpolation cell, the maximum over its closed run of lattice points."""
        a = np.moveaxis(a, axis, 0)
        if self.n == 1:
            out = a.max(axis=0, keepdims=True)
        else:
            runs = a[:-1].reshape((self.n - 1, self.k) + a.shape[1:]).max(axis=1)
            out = np.maximum(runs, a[self.k :: self.k])  # each run's closing line
        return np.moveaxis(out, 0, axis)

    def centre_max(self, g: np.ndarray, axis: int) -> np.ndarray:
        """Per centre, the maximum over the (one or two) interpolation cells beside it."""
        if self.n == 1:
            return g
        g = np.moveaxis(g, axis, 0)
        pad = np.full((1,) + g.shape[1:], -np.inf)
        g = np.concatenate([pad, g, pad])
        return np.moveaxis(np.maximum(g[:-1], g[1:]), 0, axis)

    def parity_weight(self, parity: int):
        """Per lattice point, its centre of the given index parity and that one's weight."""
        on_lower = self.lower % 2 == parity
        weight = np.where(on_lower, 1 - self.t, 0.0) + np.where(self.upper % 2 == parity, self.t, 0.0)
        return np.where(on_lower, self.lower, self.upper), weight


class _Hull:
    """The lattice points between the centres, and bilinear interpolation there."""

    def __init__(self, ny: int, nx: int, k: int):
        self.y, self.x = _HullAxis.of(ny, k), _HullAxis.of(nx, k)

    def interpolate(self, v: np.ndarray) -> np.ndarray:
        y, x = self.y, self.x
        along_x = v[:, x.lower] * (1 - x.t) + v[:, x.upper] * x.t  # separable: rows first
        return along_x[y.lower] * (1 - y.t)[:, None] + along_x[y.upper] * y.t[:, None]

    def cell_max(self, a: np.ndarray) -> np.ndarray:
        return self.x.cell_max(self.y.cell_max(a, 0), 1)

    def centre_max(self, g: np.ndarray) -> np.ndarray:
        return self.x.centre_max(self.y.centre_max(g, 0), 1)


def _raise_class(correction, need, hull: _Hull, parity, movable) -> np.ndarray:
    """Lowers the correction of the ``movable`` centres of the given (row, column)
    index parity to the least that keeps interpolate(correction) >= need at every
    lattice point. Each interpolation cell has exactly one centre of a parity
    class, so the whole class moves at once."""
    (rows, wy), (cols, wx) = hull.y.parity_weight(parity[0]), hull.x.parity_weight(parity[1])
    weight = wy[:, None] * wx[None, :]
    others = hull.interpolate(correction) - weight * correction[np.ix_(rows, cols)]
    with np.errstate(divide="ignore", invalid="ignore"):
        least = np.where(weight > 0, (need - others) / weight, -np.inf)
    least = hull.centre_max(hull.cell_max(least))
    selected = np.zeros(correction.shape, dtype=bool)
    selected[parity[0] :: 2, parity[1] :: 2] = True
    return np.where(selected & movable, np.minimum(correction, least), correction)
