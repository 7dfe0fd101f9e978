"""``tunnel``: a featureless tunnel beside a structured detour, for planning studies.

A straight tunnel runs along x through the origin (two smooth walls, the
floor, a ceiling) and, parallel to it on its +y side behind a solid block, an
open-air lane with structure: pilasters, niches and side openings in its
walls, two rows of pillars, crates along the walls. Both open at each end onto
a plaza of bare flat ground, behind a portal wall that faces the plaza; the
tunnel's walls and ceiling stick out of the portal by ``mouth_length`` and end
there in free edges. Beyond the plazas the map ends. From inside the tunnel a
scan therefore sees the walls, the floor, the ceiling and, through the mouths,
bare ground: no surface faces along the axis (a portal wall meeting the
mouth's rim would be hit head-on by rays grazing the walls), and only the
plane fits at the wall-floor and wall-ceiling corners tilt a little towards
it, so point-to-plane registration is degenerate along x in practice
(docs/scenes.md has the figures). In the lane and on the plazas the position
is fixed. From the start zone in front of one mouth to the goal zone in front
of the other, the lane is 5-15 % longer than the tunnel.
"""

from __future__ import annotations

import math

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.buildings import Opening, wall
from lf3pm.scenes.geometry import Heightfield, box, heightfield_points, rectangle, stack
from lf3pm.scenes.scene import Scene, Zone, check_seed, finish, require, resolve_params

NAME = "tunnel"
DESCRIPTION = (
    "Degenerate along x: a 60 m tunnel (smooth walls, floor, ceiling) and, 8 m beside it, "
    "an open lane with pilasters, niches, pillars and crates, between two bare plazas; "
    "walls 5 cm, ground 10 cm; ~0.62 M points by default."
)
DEFAULTS = {
    "length": 60.0,  # m, tunnel and lane along x, centred on the origin
    "width": 4.0,  # m, the tunnel's inside, y from -width/2 to width/2
    "height": 3.0,  # m, walls (and the ceiling) of the tunnel and the lane
    "ceiling": True,
    "mouth_length": 2.0,  # m the tunnel sticks out of the portal walls into each plaza
    "detour_offset": 8.0,  # m, tunnel axis to the lane's centre line
    "detour_width": 7.0,  # m, the lane between its walls
    "plaza_depth": 12.0,  # m of bare ground beyond each portal
    "pillars": 16,  # in two rows along the lane
    "crates": 10,  # along the lane's walls
    "feature_pitch": 4.0,  # m, mean spacing of pilasters, niches and openings along a lane wall
    "wall_spacing": 0.05,  # m
    "ground_spacing": 0.10,  # m
    "jitter": 0.0025,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 1.5,  # m
}

#: m of plaza ground beyond the tunnel's and the lane's outer walls, across y.
PLAZA_MARGIN = 3.0
#: Pillar section (m, square) and the rows' distance from the lane's centre line (m).
PILLAR = 0.5
PILLAR_ROW = 1.6
#: Crate sizes (along the wall, across, height), m: a pallet, a crate, a cabinet, a bin.
_CRATES = np.array([[1.2, 0.8, 1.0], [1.0, 1.0, 0.8], [1.6, 0.6, 1.8], [0.8, 0.6, 0.9]])


def zones(params: dict) -> dict:
    """The study's zones for the (resolved) parameters: ``start`` in front of the
    tunnel's west mouth, ``goal`` in front of its east mouth, 6-10 m out, within
    1.5 m of the axis."""
    half = params["length"] / 2
    return {"start": Zone(-half - 10.0, -1.5, -half - 6.0, 1.5), "goal": Zone(half + 6.0, -1.5, half + 10.0, 1.5)}


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the tunnel scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    half, w, h = p["length"] / 2, p["width"], p["height"]
    lane_in = p["detour_offset"] - p["detour_width"] / 2  # y of the lane's inner wall
    lane_out = p["detour_offset"] + p["detour_width"] / 2
    require(p["length"] >= 20.0, NAME, "length must be >= 20 m")
    require(w >= 2.0 and p["free_radius"] < w / 2, NAME, "width must be >= 2 m and exceed twice free_radius")
    require(h > 2.5, NAME, "height must exceed 2.5 m (the free band)")
    require(
        p["detour_width"] >= 6.5,
        NAME,
        "detour_width must be >= 6.5 m (crates, pillars and a clear lane 2.5 m wide between them)",
    )
    require(
        lane_in >= w / 2 + 1.0,
        NAME,
        "detour_offset is too small: the block between the tunnel and the lane must be >= 1 m thick",
    )
    require(p["plaza_depth"] >= 11.0, NAME, "plaza_depth must be >= 11 m (the zones lie 6-10 m out)")
    require(p["mouth_length"] <= 4.0, NAME, "mouth_length must be <= 4 m (the zones start 6 m out)")
    require(p["feature_pitch"] >= 1.5, NAME, "feature_pitch must be >= 1.5 m")
    require(p["wall_spacing"] > 0 and p["ground_spacing"] > 0, NAME, "spacings must be > 0")
    rng = np.random.default_rng(seed)
    s, j = p["wall_spacing"], p["jitter"]
    ex, ey = np.eye(3)[:2]

    # The tunnel: sheets that end in free edges beyond the portals, so that no surface
    # facing along the axis meets a mouth's rim, where rays from inside graze it.
    tube = half + p["mouth_length"]
    parts = [
        wall(rng, (-tube, -w / 2), (tube, -w / 2), 0.0, h, s, j),
        wall(rng, (-tube, w / 2), (tube, w / 2), 0.0, h, s, j),
    ]
    if p["ceiling"]:
        parts.append(rectangle(rng, (-tube, -w / 2, h), ex, ey, 2 * tube, w, s, j))
    # Portal walls at x = -+length/2 across the plazas' width, facing them; the lane opens
    # in them, the tunnel passes through them.
    y_lo, y_hi = -w / 2 - PLAZA_MARGIN, lane_out + PLAZA_MARGIN
    for x in (-half, half):
        for a, b in ((y_lo, -w / 2), (w / 2, lane_in), (lane_out, y_hi)):
            parts.append(wall(rng, (x, a), (x, b), 0.0, h, s, j))

    # The lane's walls: the inner one drawn towards -x, the outer one towards +x, so that
    # wall() puts their recesses outside the lane.
    lane_walls = []  # (y of the wall, +1 or -1 towards the lane, x spans of its features)
    for y_wall, along, outer in ((lane_in, -1.0, False), (lane_out, 1.0, True)):
        openings, pilasters, taken = _wall_features(rng, p, outer)
        parts.append(wall(rng, (-along * half, y_wall), (along * half, y_wall), 0.0, h, s, j, openings))
        into_lane = -along
        for u0, u1 in pilasters:
            x = -along * half + along * (u0 + u1) / 2
            parts.append(box(rng, (x, y_wall + into_lane * 0.15, 0.0), (u1 - u0, 0.3, h), 0.0, s, j))
        spans = [tuple(sorted((-along * half + along * a, -along * half + along * b))) for a, b in taken]
        lane_walls.append((y_wall, into_lane, spans))
    parts += _pillars(rng, p, half)
    parts += _crates(rng, p, half, lane_walls)

    def on_ground(x, y):
        plaza = np.abs(x) >= half
        tunnel = np.abs(y) < w / 2
        lane = (y > lane_in) & (y < lane_out)
        return plaza | tunnel | lane

    parts.append(
        heightfield_points(
            rng,
            Heightfield.flat(),
            (-half - p["plaza_depth"], half + p["plaza_depth"]),
            (y_lo, y_hi),
            p["ground_spacing"],
            j,
            keep=on_ground,
        )
    )
    return finish(NAME, DESCRIPTION, seed, p, stack(parts), zones=zones(p))


def _wall_features(rng: np.random.Generator, p: dict, outer: bool):
    """Features along one lane wall, in the wall's own coordinate u (0 at its start):
    the openings to cut (niches, pilaster slots; on the outer wall also side
    openings), the pilasters' (u0, u1) spans and every feature's span (crates keep
    clear of them)."""
    length = p["length"]
    openings, pilasters, taken = [], [], []
    u = rng.uniform(0.5, 1.5) * p["feature_pitch"] / 2
    while True:
        kind = rng.choice(["pilaster", "niche", "opening"] if outer else ["pilaster", "niche"])
        width = 0.4 if kind == "pilaster" else rng.uniform(1.0, 2.0)
        if u + width > length - 1.0:
            break
        if kind == "pilaster":  # a slot in the wall that the pilaster's back face fills
            openings.append(Opening(u, 0.0, u + width, p["height"], 0.0))
            pilasters.append((u, u + width))
        elif kind == "niche":
            openings.append(Opening(u, 0.4, u + width, 2.2, rng.uniform(0.3, 0.5)))
        else:
            openings.append(Opening(u, 0.0, u + width, 2.2, 0.0))
        taken.append((u - 0.2, u + width + 0.2))
        u += width + rng.uniform(0.6, 1.4) * p["feature_pitch"]
    return openings, pilasters, taken


def _pillars(rng: np.random.Generator, p: dict, half: float) -> list:
    """Square pillars in two rows PILLAR_ROW either side of the lane's centre line,
    at random x at least 3 m apart within a row."""
    parts = []
    rows = {-1.0: (p["pillars"] + 1) // 2, 1.0: p["pillars"] // 2}
    for side, count in rows.items():
        span = 2 * half - 4.0
        require(count * 3.0 <= span, NAME, f"cannot place {p['pillars']} pillars 3 m apart; use fewer")
        # Sorted uniform draws pushed apart: gaps of 3 m plus a random share of the slack.
        slack = span - count * 3.0
        xs = -half + 2.0 + np.sort(rng.uniform(0.0, slack, count)) + 3.0 * np.arange(count) + 1.5
        for x in xs:
            parts.append(
                box(
                    rng,
                    (x, p["detour_offset"] + side * PILLAR_ROW, 0.0),
                    (PILLAR, PILLAR, p["height"]),
                    rng.choice([0.0, math.pi / 4]),
                    p["wall_spacing"],
                    p["jitter"],
                )
            )
    return parts


def _crates(rng: np.random.Generator, p: dict, half: float, lane_walls: list) -> list:
    """Crates standing against the lane's walls (``lane_walls``: y of the wall, the
    sign towards the lane, the x spans of its features), clear of the features and
    of each other, turned by up to 5 degrees."""
    parts = []
    taken = [list(spans) for _, _, spans in lane_walls]
    for _ in range(p["crates"]):
        size = _CRATES[rng.integers(len(_CRATES))] * rng.uniform(0.9, 1.1)
        side = int(rng.integers(2))
        y_wall, into_lane, _ = lane_walls[side]
        for _attempt in range(200):
            x = rng.uniform(-half + 1.5 + size[0] / 2, half - 1.5 - size[0] / 2)
            span = (x - size[0] / 2 - 0.2, x + size[0] / 2 + 0.2)
            if all(span[1] < a or span[0] > b for a, b in taken[side]):
                break
        else:
            require(False, NAME, f"cannot place {p['crates']} crates along the lane; use fewer")
        taken[side].append(span)
        y = y_wall + into_lane * (size[1] / 2 + 0.1)
        parts.append(box(rng, (x, y, 0.0), size, rng.uniform(-0.087, 0.087), p["wall_spacing"], p["jitter"]))
    return parts
