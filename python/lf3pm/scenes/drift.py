"""``drift``: a featureless mine drift beside a structured gallery, for flights.

Two parallel passages run along x through a rock mass between two highwalls
(vertical rock faces across y at x = -+length/2, facing out) that stand on the
floor of an open pit. The drift, through the origin, has a constant cross-section:
smooth vertical walls and a semicircular arched back, the floor, nothing else; its
walls and back stick ``mouth_length`` out of each highwall and end in free edges
there (as the ``tunnel`` scene's do), so that from inside it no surface faces
along the axis: a scan sees the tube and, through its mouths, bare pit floor, and
point-to-plane registration slides along x. The gallery, ``gallery_offset`` beside
it, is wider and flat-roofed, with a row of pillars down its middle, niches in both
walls and blind cross-cuts (short side passages ending in a face) off its outer
wall. The pit floor (``bench_depth`` deep) lies in front of both mouths; the start
volume hovers in front of the drift's west mouth, the goal in front of its east
one. The passages meet only on the pit floor: a flight takes the drift (the
shortest way) or the gallery. The rock's top is not sampled: the map, and an R3
grid over it, end at the highwalls' top.
"""

from __future__ import annotations

import math

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.buildings import Opening, wall
from lf3pm.scenes.geometry import Heightfield, box, heightfield_points, rectangle, stack
from lf3pm.scenes.scene import Scene, check_seed, finish, require, resolve_params

NAME = "drift"
DESCRIPTION = (
    "Flight, degenerate along x: a 60 m mine drift (smooth walls, arched back) beside a "
    "gallery with pillars, niches and cross-cuts, between two highwalls on a pit floor; "
    "start and goal volumes at its mouths; walls 10 cm, ground 20 cm; ~0.27 M points by default."
)
DEFAULTS = {
    "length": 60.0,  # m, highwall to highwall along x, centred on the origin
    "width": 4.0,  # m, the drift's inside (the back's radius is width / 2)
    "wall_height": 2.5,  # m, the drift's vertical walls; the back's crown is width / 2 higher
    "mouth_length": 2.0,  # m the drift sticks out of each highwall, 0-4
    "gallery_offset": 10.0,  # m, the drift's axis to the gallery's centre line
    "gallery_width": 7.0,  # m
    "gallery_height": 4.5,  # m, floor to its flat roof
    "pillars": 8,  # down the gallery's centre line
    "cross_cuts": 4,  # blind side passages off the gallery's outer wall
    "feature_pitch": 5.0,  # m, mean spacing of the niches along a gallery wall
    "highwall_height": 8.0,  # m
    "bench_depth": 12.0,  # m of pit floor beyond each highwall (>= 11)
    "wall_spacing": 0.10,  # m
    "ground_spacing": 0.20,  # m
    "jitter": 0.0025,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 1.5,  # m (the reference pose is mid-drift)
}

#: Cross-cut size (m): width along the gallery, depth into the rock, height.
CROSS_CUT = (2.5, 4.0, 3.0)
#: Pillar side (m): square, drawn between these.
PILLAR = (0.8, 1.2)
#: m of pit floor beyond the passages' outermost walls, across y.
MARGIN = 3.0


def volumes(params: dict) -> dict:
    """The flight's volumes (``xmin, ymin, zmin, xmax, ymax, zmax``): ``start`` 6-9 m out of
    the drift's west mouth, ``goal`` 6-9 m out of its east one, both within 1.5 m of its
    axis and 1-2.5 m above the pit floor."""
    half = params["length"] / 2
    return {
        "start": (-half - 9.0, -1.5, 1.0, -half - 6.0, 1.5, 2.5),
        "goal": (half + 6.0, -1.5, 1.0, half + 9.0, 1.5, 2.5),
    }


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the drift scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    half, w, hw = p["length"] / 2, p["width"], p["wall_height"]
    g_in = p["gallery_offset"] - p["gallery_width"] / 2  # y of the gallery's inner wall
    g_out = p["gallery_offset"] + p["gallery_width"] / 2
    require(p["length"] >= 20.0, NAME, "length must be >= 20 m")
    require(w >= 2.0 and p["free_radius"] < w / 2, NAME, "width must be >= 2 m and exceed twice free_radius")
    require(hw >= 1.5, NAME, "wall_height must be >= 1.5 m")
    require(p["mouth_length"] <= 4.0, NAME, "mouth_length must be <= 4 m (the volumes start 6 m out)")
    require(g_in >= w / 2 + 1.5, NAME, "gallery_offset is too small: the rock between the passages must be >= 1.5 m")
    require(p["gallery_width"] >= 5.0, NAME, "gallery_width must be >= 5 m (pillars and a lane either side)")
    require(
        CROSS_CUT[2] + 0.5 <= p["gallery_height"] < p["highwall_height"] and w / 2 + hw < p["highwall_height"],
        NAME,
        "the gallery must be >= 3.5 m high and both passages lower than the highwalls",
    )
    require(p["bench_depth"] >= 11.0, NAME, "bench_depth must be >= 11 m (the volumes lie 6-9 m out)")
    require(p["feature_pitch"] >= 2.0, NAME, "feature_pitch must be >= 2 m")
    require(p["wall_spacing"] > 0 and p["ground_spacing"] > 0, NAME, "spacings must be > 0")
    rng = np.random.default_rng(seed)
    s, j = p["wall_spacing"], p["jitter"]
    ex, ey, ez = np.eye(3)

    tube = half + p["mouth_length"]
    parts = [_drift_shell(rng, p, tube)]

    # The highwalls across the map's width, with the passages' outlines cut out.
    y_lo, y_hi = -w / 2 - MARGIN, g_out + CROSS_CUT[1] + MARGIN

    def rock(a, b):
        y, z = y_lo + a, b
        in_drift = (np.abs(y) < w / 2) & (z < hw + np.sqrt(np.maximum(w * w / 4 - y * y, 0.0)))
        in_gallery = (y > g_in) & (y < g_out) & (z < p["gallery_height"])
        return ~(in_drift | in_gallery)

    for x in (-half, half):
        parts.append(rectangle(rng, (x, y_lo, 0.0), ey, ez, y_hi - y_lo, p["highwall_height"], s, j, keep=rock))

    # The gallery: its inner wall drawn towards -x and its outer one towards +x, so that
    # wall() puts their recesses (niches, cross-cuts) into the rock.
    gh = p["gallery_height"]
    for y_wall, along, outer in ((g_in, -1.0, False), (g_out, 1.0, True)):
        openings = _gallery_openings(rng, p, outer)
        parts.append(wall(rng, (-along * half, y_wall), (along * half, y_wall), 0.0, gh, s, j, openings))
    parts.append(rectangle(rng, (-half, g_in, gh), ex, ey, 2 * half, g_out - g_in, s, j))
    parts += _pillars(rng, p)

    def floor(x, y):
        bench = np.abs(x) >= half
        drift = (np.abs(y) < w / 2) & (np.abs(x) < tube)
        gallery = (y > g_in) & (y < g_out)
        return bench | drift | gallery

    parts.append(
        heightfield_points(
            rng,
            Heightfield.flat(),
            (-half - p["bench_depth"], half + p["bench_depth"]),
            (y_lo, y_hi),
            p["ground_spacing"],
            j,
            keep=floor,
        )
    )
    return finish(NAME, DESCRIPTION, seed, p, stack(parts), volumes=volumes(p))


def _drift_shell(rng: np.random.Generator, p: dict, tube: float) -> np.ndarray:
    """The drift's walls and arched back from x = -tube to tube: one grid over the
    cross-section's arc length and x, the same at every x, jittered along the
    surface and a third of it along its normal."""
    r, hw, s, j = p["width"] / 2, p["wall_height"], p["wall_spacing"], p["jitter"]
    arc = math.pi * r
    total = 2 * hw + arc
    nt, nx = max(1, int(round(total / s))), max(1, int(round(2 * tube / s)))
    t = (np.arange(nt) + 0.5) * (total / nt)
    x = -tube + (np.arange(nx) + 0.5) * (2 * tube / nx)
    tt, xx = (g.ravel() for g in np.meshgrid(t, x, indexing="ij"))
    n = tt.size
    if j > 0:
        tt = np.clip(tt + rng.normal(0.0, j, n), 0.0, total)
        xx = xx + rng.normal(0.0, j, n)
        off = rng.normal(0.0, j / 3.0, n)
    else:
        off = np.zeros(n)
    # Arc length t: up the +y wall, over the back from +y to -y, down the -y wall.
    theta = (tt - hw) / r
    on_back = (tt > hw) & (tt < hw + arc)
    y = np.where(tt <= hw, r + off, np.where(on_back, (r + off) * np.cos(theta), -r - off))
    z = np.where(tt <= hw, tt, np.where(on_back, hw + (r + off) * np.sin(theta), total - tt))
    return np.stack([xx, y, z], axis=1)


def _gallery_openings(rng: np.random.Generator, p: dict, outer: bool) -> list:
    """Openings along one gallery wall, in the wall's own coordinate u (0 at its start):
    niches (1-2 m wide, 0.4-0.8 m deep, 0.5-2.5 m above the floor) about every
    ``feature_pitch`` metres and, on the outer wall, ``cross_cuts`` cross-cuts
    (recessed openings as deep as a cross-cut: the recess's sill, lintel, jambs and
    back are its floor, roof, sides and face) spread evenly along it."""
    length = p["length"]
    openings, taken = [], []
    if outer:
        count = p["cross_cuts"]
        width, depth, height = CROSS_CUT
        require(count * (width + 4.0) <= length - 4.0, NAME, f"cannot fit {count} cross-cuts; use fewer")
        pitch = length / max(count, 1)
        for k in range(count):
            u = (k + 0.5) * pitch + rng.uniform(-0.25, 0.25) * (pitch - width - 2.0) - width / 2
            openings.append(Opening(u, 0.0, u + width, height, depth))
            taken.append((u - 0.5, u + width + 0.5))
    u = rng.uniform(0.3, 1.0) * p["feature_pitch"]
    while u < length - 3.0:
        width = rng.uniform(1.0, 2.0)
        if u + width < length - 1.0 and all(u + width < a or u > b for a, b in taken):
            openings.append(Opening(u, 0.5, u + width, 2.5, rng.uniform(0.4, 0.8)))
        u += width + rng.uniform(0.6, 1.4) * p["feature_pitch"]
    return openings


def _pillars(rng: np.random.Generator, p: dict) -> list:
    """``pillars`` square pillars, floor to roof, down the gallery's centre line at
    random x at least 4 m apart, square to it or turned 45 degrees."""
    count, half = p["pillars"], p["length"] / 2
    span = 2 * half - 6.0
    require(count * 4.0 <= span, NAME, f"cannot place {count} pillars 4 m apart; use fewer")
    xs = -half + 3.0 + np.sort(rng.uniform(0.0, span - count * 4.0, count)) + 4.0 * np.arange(count) + 2.0
    return [
        box(
            rng,
            (x, p["gallery_offset"], 0.0),
            (side, side, p["gallery_height"]),
            rng.choice([0.0, math.pi / 4]),
            p["wall_spacing"],
            p["jitter"],
            top=False,
        )
        for x, side in zip(xs, rng.uniform(*PILLAR, count))
    ]
