"""Vegetation on a terrain: grass tufts, weeds and bushes.

This is what makes point-to-plane residuals scatter: many small surfaces
(blades 5-30 cm long, leaves 2-16 cm) in random orientations, each sampled
more densely (1.2-1.5 cm) than the gaps between them, so a k-nearest-neighbour
plane is sometimes one blade's plane and sometimes a plane across several
blades, a blade and the ground, or a bush's leaves.
"""

from __future__ import annotations

import math

import numpy as np

from lf3pm.scenes.geometry import EMPTY, Heightfield, blades, bush, leaves, stack, unit

#: Sample spacing within a leaf (m).
LEAF_SPACING = 0.012
#: Sample spacing along a grass blade or a stem (m).
BLADE_SPACING = 0.015
#: How far (m) a bush of the default size range reaches from its centre.
BUSH_REACH = 1.1


def scatter(rng: np.random.Generator, count: int, x_range, y_range, keep=None) -> np.ndarray:
    """``count`` uniform positions (x, y) in the rectangle, less those ``keep`` rejects."""
    xy = np.column_stack([rng.uniform(*x_range, count), rng.uniform(*y_range, count)])
    if keep is not None and len(xy):
        xy = xy[keep(xy[:, 0], xy[:, 1])]
    return xy


def grass_tufts(
    rng: np.random.Generator,
    terrain: Heightfield,
    xy,
    blades_per_tuft: float = 9.0,
    height=(0.06, 0.30),
    spacing: float = BLADE_SPACING,
) -> np.ndarray:
    """Tufts of grass at the positions ``xy``: a Poisson number of blades each,
    rising from within 4 cm of the tuft's centre, splayed outwards (0-55 degrees
    from vertical) and drooping, as long as the tuft is high (heights uniform
    in ``height``), give or take 40%."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    if len(xy) == 0:
        return EMPTY
    counts = np.maximum(1, rng.poisson(blades_per_tuft, len(xy)))
    tuft = np.repeat(np.arange(len(xy)), counts)
    n = tuft.size
    tuft_height = rng.uniform(*height, len(xy))[tuft]
    r = 0.04 * np.sqrt(rng.uniform(0.0, 1.0, n))
    a = rng.uniform(0.0, 2.0 * math.pi, n)
    x = xy[tuft, 0] + r * np.cos(a)
    y = xy[tuft, 1] + r * np.sin(a)
    base = np.column_stack([x, y, terrain(x, y) - 0.01])
    length = tuft_height * rng.uniform(0.6, 1.4, n)
    tilt = np.radians(rng.uniform(0.0, 55.0, n))
    azimuth = a + rng.normal(0.0, 0.5, n)  # splayed away from the tuft's centre
    bend = np.radians(rng.uniform(0.0, 40.0, n))
    width = rng.uniform(0.004, 0.012, n)
    return blades(rng, base, length, width, tilt, azimuth, bend, spacing)


def weeds(rng: np.random.Generator, terrain: Heightfield, xy, spacing: float = LEAF_SPACING) -> np.ndarray:
    """Weeds at the positions ``xy``, half of them rosettes (5-9 broad leaves
    lying 10-50 degrees off the ground) and half tall weeds (a stem 25-80 cm
    with 3-8 leaves in random orientations along it)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    if len(xy) == 0:
        return EMPTY
    ground = terrain(xy[:, 0], xy[:, 1])
    rosette = rng.random(len(xy)) < 0.5
    parts = []
    # Rosettes.
    rxy, rz = xy[rosette], ground[rosette]
    counts = rng.integers(5, 10, len(rxy))
    w = np.repeat(np.arange(len(rxy)), counts)
    size = rng.uniform(0.03, 0.08, w.size)
    heading = rng.uniform(0.0, 2.0 * math.pi, w.size)
    lift = np.radians(rng.uniform(10.0, 50.0, w.size))
    out = np.column_stack([np.cos(heading) * np.cos(lift), np.sin(heading) * np.cos(lift), np.sin(lift)])
    centre = np.column_stack([rxy[w], rz[w] + 0.01]) + out * size[:, None]
    side = np.column_stack([-np.sin(heading), np.cos(heading), np.zeros(w.size)])
    parts.append(leaves(rng, centre, np.cross(out, side), size, size * rng.uniform(0.3, 0.6, w.size), spacing))
    # Tall weeds: a stem and leaves along it.
    txy, tz = xy[~rosette], ground[~rosette]
    m = len(txy)
    if m:
        length = rng.uniform(0.25, 0.8, m)
        tilt = np.radians(rng.uniform(0.0, 15.0, m))
        azimuth = rng.uniform(0.0, 2.0 * math.pi, m)
        base = np.column_stack([txy, tz - 0.01])
        parts.append(
            blades(
                rng,
                base,
                length,
                rng.uniform(0.003, 0.007, m),
                tilt,
                azimuth,
                np.radians(rng.uniform(0.0, 20.0, m)),
                BLADE_SPACING,
            )
        )
        counts = rng.integers(3, 9, m)
        s = np.repeat(np.arange(m), counts)
        frac = rng.uniform(0.2, 1.0, s.size)
        axis = np.column_stack([np.sin(tilt) * np.cos(azimuth), np.sin(tilt) * np.sin(azimuth), np.cos(tilt)])
        size = rng.uniform(0.02, 0.06, s.size)
        direction = unit(rng.normal(size=(s.size, 3)) * [1.0, 1.0, 0.4])
        centre = base[s] + (frac * length[s])[:, None] * axis[s] + direction * size[:, None]
        parts.append(
            leaves(rng, centre, rng.normal(size=(s.size, 3)), size, size * rng.uniform(0.3, 0.6, s.size), spacing)
        )
    return stack(parts)


def bushes(
    rng: np.random.Generator, terrain: Heightfield, xy, radius=(0.3, 0.9), spacing: float = LEAF_SPACING
) -> np.ndarray:
    """Bushes at the positions ``xy``: canopies ``radius`` wide (uniform in the
    range), 0.6-1.2 times as high as wide, resting on the ground."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    parts = []
    for x, y in xy:
        r = rng.uniform(*radius)
        radii = np.array([r * rng.uniform(0.8, 1.2), r * rng.uniform(0.8, 1.2), r * rng.uniform(0.6, 1.2)])
        z = float(terrain(np.array([x]), np.array([y]))[0])
        parts.append(bush(rng, (x, y, z + radii[2] * 0.9), radii, spacing=spacing))
    if not parts:
        return EMPTY
    points = stack(parts)
    return points[points[:, 2] > terrain(points[:, 0], points[:, 1]) - 0.02]


def meadow_cover(
    rng: np.random.Generator,
    terrain: Heightfield,
    x_range,
    y_range,
    keep=None,
    tufts_per_m2: float = 6.0,
    blades_per_tuft: float = 9.0,
    weeds_per_m2: float = 0.3,
    bushes_per_100m2: float = 1.5,
    bush_keep=None,
) -> np.ndarray:
    """Grass tufts, weeds and bushes scattered uniformly over the rectangle.

    ``keep(x, y) -> bool array`` says where vegetation may grow; bushes also
    need ``bush_keep`` (default ``keep``), tested at their centres.
    """
    area = (x_range[1] - x_range[0]) * (y_range[1] - y_range[0])
    tufts = scatter(rng, rng.poisson(tufts_per_m2 * area), x_range, y_range, keep)
    weed_xy = scatter(rng, rng.poisson(weeds_per_m2 * area), x_range, y_range, keep)
    bush_xy = scatter(rng, rng.poisson(bushes_per_100m2 * area / 100.0), x_range, y_range, bush_keep or keep)
    return stack(
        [grass_tufts(rng, terrain, tufts, blades_per_tuft), weeds(rng, terrain, weed_xy), bushes(rng, terrain, bush_xy)]
    )
