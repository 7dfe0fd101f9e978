"""Surface samplers that the scenes are built from.

Every sampler returns an ``(N, 3)`` float64 array of points on one kind of
surface at a given spacing (metres), drawing any randomness from the
``numpy.random.Generator`` it is given, so a scene is a deterministic function
of its seed. Planar man-made surfaces are cell-centred grids with a small
Gaussian jitter (:data:`JITTER`), so that they are samples rather than perfect
grids yet stay planar to a few millimetres; natural surfaces (blades, leaves,
stones, terrain) carry their own shape.

The vectorised samplers (:func:`blades`, :func:`leaves`) take one row of
parameters per instance and sample thousands of instances in one call.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from lf3pm import libm

#: Default jitter (1-sigma, metres) of samples on planar man-made surfaces: in the
#: plane, so the samples are not a perfect grid, and (a third of it) along the
#: normal, so the surface stays planar to a few millimetres.
JITTER = 0.0025

EMPTY = np.zeros((0, 3))

#: The golden angle (radians), for evenly spread spiral (Vogel) samples of a disc.
_GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))


def rot_z(yaw: float) -> np.ndarray:
    """The 3 x 3 rotation by ``yaw`` radians about +z."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def place(points: np.ndarray, yaw: float = 0.0, offset=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Rotates local points by ``yaw`` about +z, then translates them by ``offset``."""
    return points @ rot_z(yaw).T + np.asarray(offset, dtype=float)


def stack(parts) -> np.ndarray:
    """One C-contiguous float64 array of all the (N_i, 3) arrays in ``parts``."""
    parts = [np.asarray(p, dtype=float).reshape(-1, 3) for p in parts]
    return np.ascontiguousarray(np.vstack(parts) if parts else EMPTY)


def unit(v) -> np.ndarray:
    """``v`` (one vector or rows of vectors) scaled to unit length."""
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def random_unit_vectors(rng: np.random.Generator, count: int) -> np.ndarray:
    """``count`` directions drawn uniformly on the unit sphere."""
    return unit(rng.normal(size=(count, 3)))


def rectangle(
    rng: np.random.Generator,
    origin,
    u,
    v,
    size_u: float,
    size_v: float,
    spacing: float,
    jitter: float = JITTER,
    holes=(),
    keep=None,
) -> np.ndarray:
    """Samples the rectangle ``origin + a u + b v``, 0 <= a <= size_u, 0 <= b <= size_v.

    ``u`` and ``v`` are orthonormal. Samples sit at the centres of a grid of
    cells about ``spacing`` wide (edges are never sampled twice by adjacent
    rectangles), jittered by ``jitter`` in the plane and ``jitter / 3`` along
    the normal. ``holes`` are (a0, b0, a1, b1) rectangles in (a, b) that get no
    samples (doors, windows); ``keep(a, b) -> bool array`` trims the outline
    (a gable's triangle).
    """
    u = np.asarray(u, dtype=float)
    v = np.asarray(v, dtype=float)
    nu = max(1, int(round(size_u / spacing)))
    nv = max(1, int(round(size_v / spacing)))
    a = (np.arange(nu) + 0.5) * (size_u / nu)
    b = (np.arange(nv) + 0.5) * (size_v / nv)
    aa, bb = np.meshgrid(a, b, indexing="ij")
    aa, bb = aa.ravel(), bb.ravel()
    mask = np.ones(aa.shape, dtype=bool)
    for a0, b0, a1, b1 in holes:
        mask &= ~((aa > a0) & (aa < a1) & (bb > b0) & (bb < b1))
    if keep is not None:
        mask &= keep(aa, bb)
    aa, bb = aa[mask], bb[mask]
    n = len(aa)
    if jitter > 0:
        aa = aa + rng.normal(0.0, jitter, n)
        bb = bb + rng.normal(0.0, jitter, n)
        off = rng.normal(0.0, jitter / 3.0, n)
    else:
        off = np.zeros(n)
    normal = np.cross(u, v)
    return np.asarray(origin, dtype=float) + aa[:, None] * u + bb[:, None] * v + off[:, None] * normal


def box(
    rng: np.random.Generator,
    center,
    size,
    yaw: float,
    spacing: float,
    jitter: float = JITTER,
    top: bool = True,
    bottom: bool = False,
) -> np.ndarray:
    """Samples the faces of a box standing on its base.

    ``center`` = (x, y, z of the base), ``size`` = (length along the box's x,
    width along its y, height), turned by ``yaw`` about +z. The four sides are
    always sampled, the top and the bottom when asked.
    """
    lx, ly, lz = (float(s) for s in size)
    ex, ey, ez = np.eye(3)
    x0, y0 = -lx / 2, -ly / 2
    faces = [
        rectangle(rng, (x0, y0, 0.0), ex, ez, lx, lz, spacing, jitter),
        rectangle(rng, (x0, -y0, 0.0), ex, ez, lx, lz, spacing, jitter),
        rectangle(rng, (x0, y0, 0.0), ey, ez, ly, lz, spacing, jitter),
        rectangle(rng, (-x0, y0, 0.0), ey, ez, ly, lz, spacing, jitter),
    ]
    if top:
        faces.append(rectangle(rng, (x0, y0, lz), ex, ey, lx, ly, spacing, jitter))
    if bottom:
        faces.append(rectangle(rng, (x0, y0, 0.0), ex, ey, lx, ly, spacing, jitter))
    return place(stack(faces), yaw, center)


def cylinder(
    rng: np.random.Generator, base, radius: float, height: float, spacing: float, jitter: float = JITTER
) -> np.ndarray:
    """Samples the side of a vertical cylinder (a trunk, a column, a pier) of ``radius``
    rising ``height`` from ``base`` = (x, y, z) on a grid about ``spacing`` apart around it
    and up it, turned at random, jittered by ``jitter`` along the surface and a third of
    it along the radius."""
    nu = max(3, int(round(2.0 * math.pi * radius / spacing)))
    nv = max(1, int(round(height / spacing)))
    angle = (np.arange(nu) + 0.5) * (2.0 * math.pi / nu) + rng.uniform(0.0, 2.0 * math.pi)
    z = (np.arange(nv) + 0.5) * (height / nv)
    aa, zz = (g.ravel() for g in np.meshgrid(angle, z, indexing="ij"))
    r = np.full(aa.size, float(radius))
    if jitter > 0:
        aa = aa + rng.normal(0.0, jitter, aa.size) / radius
        zz = zz + rng.normal(0.0, jitter, aa.size)
        r = r + rng.normal(0.0, jitter / 3.0, aa.size)
    return np.asarray(base, dtype=float) + np.stack([r * np.cos(aa), r * np.sin(aa), zz], axis=1)


def smoothstep(t):
    """0 below 0, 1 above 1, and a C1 ramp between."""
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


@dataclass(frozen=True, eq=False)
class Heightfield:
    """Terrain height z = h(x, y): a sum of plane waves, flattened on round pads.

    Build one with :meth:`random`, add level pads with :meth:`with_pad` (where a
    town or a house stands), then evaluate it on arrays of x and y.
    """

    wave_vectors: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    amplitudes: np.ndarray = field(default_factory=lambda: np.zeros(0))
    phases: np.ndarray = field(default_factory=lambda: np.zeros(0))
    offset: float = 0.0
    pads: tuple = ()

    @classmethod
    def flat(cls) -> Heightfield:
        return cls()

    @classmethod
    def random(
        cls, rng: np.random.Generator, amplitude: float, wavelengths: tuple[float, float], waves: int = 12
    ) -> Heightfield:
        """Random smooth terrain: ``waves`` plane waves with wavelengths log-uniform in
        ``wavelengths`` (m), scaled so that the height has standard deviation
        ``amplitude / sqrt(2)`` (that of one sine of that amplitude).
        """
        lo, hi = wavelengths
        lam = libm.exp(rng.uniform(math.log(lo), math.log(hi), waves))
        direction = rng.uniform(0.0, 2.0 * math.pi, waves)
        k = (2.0 * math.pi / lam)[:, None] * np.stack([np.cos(direction), np.sin(direction)], axis=1)
        amp = lam / lam.sum() * rng.uniform(0.5, 1.5, waves)  # longer waves are higher
        amp *= amplitude / math.sqrt(np.sum(amp**2))
        return cls(k, amp, rng.uniform(0.0, 2.0 * math.pi, waves))

    def plus(self, other: Heightfield) -> Heightfield:
        """The sum of two wave sets (pads and offset of ``self``)."""
        return Heightfield(
            np.vstack([self.wave_vectors, other.wave_vectors]),
            np.concatenate([self.amplitudes, other.amplitudes]),
            np.concatenate([self.phases, other.phases]),
            self.offset,
            self.pads,
        )

    def with_pad(self, x: float, y: float, radius: float, blend: float, level: float | None = None) -> Heightfield:
        """Level terrain within ``radius`` of (x, y) at ``level`` (default: the height
        there), blending back to the terrain over the next ``blend`` metres."""
        if level is None:
            level = float(self(np.array([x]), np.array([y]))[0])
        return Heightfield(
            self.wave_vectors,
            self.amplitudes,
            self.phases,
            self.offset,
            self.pads + ((float(x), float(y), float(radius), float(blend), level),),
        )

    def shifted_to_zero_at(self, x: float, y: float) -> Heightfield:
        """The same terrain moved vertically so that h(x, y) = 0."""
        h = float(self(np.array([x]), np.array([y]))[0])
        pads = tuple((px, py, r, b, lv - h) for px, py, r, b, lv in self.pads)
        return Heightfield(self.wave_vectors, self.amplitudes, self.phases, self.offset - h, pads)

    def __call__(self, x, y) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        h = np.full(np.broadcast(x, y).shape, self.offset)
        for (kx, ky), a, p in zip(self.wave_vectors, self.amplitudes, self.phases):
            h += a * np.cos(kx * x + ky * y + p)
        for px, py, radius, blend, level in self.pads:
            w = smoothstep((np.hypot(x - px, y - py) - radius) / max(blend, 1e-9))
            h = level + w * (h - level)
        return h


def heightfield_points(
    rng: np.random.Generator, terrain: Heightfield, x_range, y_range, spacing: float, jitter: float = JITTER, keep=None
) -> np.ndarray:
    """Samples the terrain over x_range x y_range on a jittered grid of ``spacing``.

    ``keep(x, y) -> bool array`` drops samples (under a building, say).
    """
    (x0, x1), (y0, y1) = x_range, y_range
    nx = max(1, int(round((x1 - x0) / spacing)))
    ny = max(1, int(round((y1 - y0) / spacing)))
    xs = x0 + (np.arange(nx) + 0.5) * ((x1 - x0) / nx)
    ys = y0 + (np.arange(ny) + 0.5) * ((y1 - y0) / ny)
    xx, yy = np.meshgrid(xs, ys, indexing="ij")
    xx, yy = xx.ravel(), yy.ravel()
    if jitter > 0:
        xx = xx + rng.normal(0.0, jitter, xx.size)
        yy = yy + rng.normal(0.0, jitter, yy.size)
    if keep is not None:
        mask = keep(xx, yy)
        xx, yy = xx[mask], yy[mask]
    zz = terrain(xx, yy)
    if jitter > 0:
        zz = zz + rng.normal(0.0, jitter / 3.0, zz.size)
    return np.stack([xx, yy, zz], axis=1)


def _direction(theta, phi):
    """Unit vectors at polar angle ``theta`` from +z and azimuth ``phi``."""
    st = np.sin(theta)
    return np.stack([st * np.cos(phi), st * np.sin(phi), np.cos(theta)], axis=-1)


def blades(rng: np.random.Generator, base, length, width, tilt, azimuth, bend, spacing: float = 0.01) -> np.ndarray:
    """Samples grass blades (or thin stems): narrow bent strips, one row of parameters each.

    base: (B, 3) foot points; length, width (m); tilt: polar angle of the foot's
    direction from vertical; azimuth: its heading; bend: the extra tilt gained
    from foot to tip (a blade drooping under its weight). Each blade gets about
    length / spacing samples staggered across its width (left, right, left...),
    so any few neighbours span a plane: the blade's own, twisted at random.
    """
    base = np.asarray(base, dtype=float).reshape(-1, 3)
    length, width, tilt, azimuth, bend = (
        np.broadcast_to(np.asarray(a, dtype=float), (len(base),)) for a in (length, width, tilt, azimuth, bend)
    )
    if len(base) == 0:
        return EMPTY
    counts = np.maximum(3, np.round(length / spacing).astype(np.int64))
    blade = np.repeat(np.arange(len(base)), counts)
    first = np.cumsum(counts) - counts
    k = np.arange(blade.size) - first[blade]
    n = counts[blade]
    s = (k + 0.5) / n  # fraction along the blade
    L, th, ph, bd = length[blade], tilt[blade], azimuth[blade], bend[blade]
    # Midpoint rule for the integral of a direction whose tilt grows linearly with s.
    centre = base[blade] + (s * L)[:, None] * _direction(th + 0.5 * bd * s, ph)
    tangent = _direction(th + bd * s, ph)
    side = np.stack([-np.sin(ph), np.cos(ph), np.zeros_like(ph)], axis=-1)
    twist = rng.uniform(-0.7, 0.7, len(base))[blade]
    across = np.cos(twist)[:, None] * side + np.sin(twist)[:, None] * np.cross(side, tangent)
    # Staggered across the width, narrowing towards the tip.
    offset = np.where(k % 2 == 0, 1.0, -1.0) * width[blade] / 3.0 * (1.0 - 0.6 * s)
    return centre + offset[:, None] * across


def leaves(
    rng: np.random.Generator, centre, normal, semi_major, semi_minor, spacing: float = 0.01, cup: float = 0.25
) -> np.ndarray:
    """Samples leaves: small ellipses, one row of parameters each.

    centre (L, 3), normal (L, 3) (need not be unit), semi-axes (m). Samples
    are a Vogel spiral (evenly spread, about ``spacing`` apart, at least 4 per
    leaf) with the major axis turned at random in the leaf's plane and the
    leaf cupped by up to ``cup`` times its size along its normal.
    """
    centre = np.asarray(centre, dtype=float).reshape(-1, 3)
    nl = len(centre)
    if nl == 0:
        return EMPTY
    normal = unit(np.broadcast_to(np.asarray(normal, dtype=float), (nl, 3)))
    a = np.broadcast_to(np.asarray(semi_major, dtype=float), (nl,))
    b = np.broadcast_to(np.asarray(semi_minor, dtype=float), (nl,))
    # An in-plane basis (e1, e2) turned at random about the normal.
    helper = np.where(np.abs(normal[:, 2:3]) < 0.9, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]))
    e1 = unit(np.cross(normal, helper))
    e2 = np.cross(normal, e1)
    turn = rng.uniform(0.0, 2.0 * math.pi, nl)
    e1, e2 = (
        np.cos(turn)[:, None] * e1 + np.sin(turn)[:, None] * e2,
        -np.sin(turn)[:, None] * e1 + np.cos(turn)[:, None] * e2,
    )
    counts = np.maximum(4, np.round(math.pi * a * b / spacing**2).astype(np.int64))
    leaf = np.repeat(np.arange(nl), counts)
    first = np.cumsum(counts) - counts
    k = np.arange(leaf.size) - first[leaf]
    r = np.sqrt((k + 0.5) / counts[leaf])
    t = k * _GOLDEN_ANGLE
    curl = rng.uniform(-cup, cup, nl)[leaf] * a[leaf]
    return (
        centre[leaf]
        + (a[leaf] * r * np.cos(t))[:, None] * e1[leaf]
        + (b[leaf] * r * np.sin(t))[:, None] * e2[leaf]
        + (curl * r * r)[:, None] * normal[leaf]
    )


def fibonacci_sphere(count: int) -> np.ndarray:
    """``count`` nearly evenly spread unit vectors (a Fibonacci lattice)."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    t = k * _GOLDEN_ANGLE
    return np.stack([r * np.cos(t), r * np.sin(t), z], axis=1)


def ellipsoid_area(a: float, b: float, c: float) -> float:
    """Surface area of the ellipsoid with semi-axes a, b, c (Knud Thomsen, within ~1%)."""
    p = 1.6075
    return 4.0 * math.pi * (((a * b) ** p + (a * c) ** p + (b * c) ** p) / 3.0) ** (1.0 / p)


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """A uniformly random 3 x 3 rotation."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1.0
    return q


def stone(
    rng: np.random.Generator, centre, radii, spacing: float = 0.04, roughness: float = 0.12, yaw: float | None = None
) -> np.ndarray:
    """Samples a stone: an ellipsoid surface with smooth random bumps.

    ``radii`` are the semi-axes, turned by ``yaw`` about +z (a stone lying on
    its flat side), or at random in 3-D when ``yaw`` is None; the radius along
    each direction is scaled by 1 + a few low-frequency waves over the sphere
    whose amplitudes sum to about ``roughness``.
    """
    radii = np.asarray(radii, dtype=float)
    count = max(12, int(round(ellipsoid_area(*radii) / spacing**2)))
    d = fibonacci_sphere(count)
    waves = 5
    freq = random_unit_vectors(rng, waves) * rng.uniform(1.5, 4.0, waves)[:, None]
    amp = rng.uniform(0.3, 1.0, waves)
    amp *= roughness / amp.sum()
    scale = 1.0 + np.cos(d @ freq.T + rng.uniform(0.0, 2.0 * math.pi, waves)) @ amp
    local = d * radii * scale[:, None]
    rotation = random_rotation(rng) if yaw is None else rot_z(yaw)
    return local @ rotation.T + np.asarray(centre, dtype=float)


def bush(
    rng: np.random.Generator,
    centre,
    radii,
    leaves_per_m2: float = 120.0,
    leaf_size=(0.015, 0.04),
    spacing: float = 0.01,
    branches: int = 6,
) -> np.ndarray:
    """Samples a bush: leaves filling the outer shell of an ellipsoidal canopy, and branches.

    centre: the canopy's centre; radii (rx, ry, rz). Leaves sit mostly near the
    canopy surface (the inner half of the volume is nearly empty, as in a real
    bush), facing outwards with a large random spread; their number is
    ``leaves_per_m2`` times the canopy's surface area. A few branches rise from
    the foot of the bush (below the centre by rz) into the canopy.
    """
    centre = np.asarray(centre, dtype=float)
    radii = np.asarray(radii, dtype=float)
    count = max(10, int(round(leaves_per_m2 * ellipsoid_area(*radii))))
    d = random_unit_vectors(rng, count)
    depth = rng.uniform(0.55, 1.0, count) ** 0.5
    position = centre + d * radii * depth[:, None]
    normal = unit(d + 1.2 * random_unit_vectors(rng, count))
    major = rng.uniform(*leaf_size, count)
    minor = major * rng.uniform(0.35, 0.7, count)
    parts = [leaves(rng, position, normal, major, minor, spacing)]
    if branches:
        foot = centre - np.array([0.0, 0.0, radii[2]])
        feet = foot + np.column_stack([rng.normal(0.0, 0.05, (branches, 2)), np.zeros(branches)])
        tips = centre + random_unit_vectors(rng, branches) * radii * 0.7
        tips[:, 2] = np.maximum(tips[:, 2], centre[2])
        delta = tips - feet
        length = np.linalg.norm(delta, axis=1)
        tilt = libm.arccos(delta[:, 2] / length)
        azimuth = libm.atan2(delta[:, 1], delta[:, 0])
        parts.append(
            blades(rng, feet, length, rng.uniform(0.008, 0.02, branches), tilt, azimuth, 0.0, spacing=2 * spacing)
        )
    return stack(parts)
