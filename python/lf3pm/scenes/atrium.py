"""``atrium``: a multi-storey atrium around a central void, for flights.

A square building, ``size`` metres across inside its outer walls and ``storeys``
storeys of ``storey_height`` metres, is open in its middle: a square void
``void`` metres across rises from the ground floor through every floor to the
open sky. Around it each upper floor is a gallery (a slab ``slab_thickness``
thick, its edge along the void lined by a solid balustrade 1.1 m high), and the
roof slab covers the galleries, with a balustrade of its own; round columns
stand 0.8 m back from the void's edges, through every storey, at its corners and
evenly between. The outer walls have windows on every storey (half of them
recessed) and a door in the middle of each wall on the ground floor. The void
holds nothing: the start volume hovers at its bottom, the goal at its top, above
the highest gallery's balustrade and below the roof. A flight up the void sees
the galleries' undersides, edges and balustrades, the columns and, through each
storey, the outer walls; near the top, the roof's edge and the sky.
"""

from __future__ import annotations

import math

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.buildings import Opening, footprint_sides, wall
from lf3pm.scenes.geometry import Heightfield, box, cylinder, heightfield_points, rectangle, stack
from lf3pm.scenes.scene import Scene, check_seed, finish, require, resolve_params

NAME = "atrium"
DESCRIPTION = (
    "Flight up a shaft: a 4-storey building 20 m square around an 8 m void open to the sky "
    "(galleries, balustrades, columns, windows); start volume at the void's bottom, goal at "
    "its top; walls 10 cm, slabs 20 cm; ~0.25 M points by default."
)
DEFAULTS = {
    "size": 20.0,  # m, inside the outer walls (square, centred on the origin)
    "void": 8.0,  # m, the central void (square)
    "storeys": 4,  # the ground floor and storeys - 1 galleries; the roof on top
    "storey_height": 4.0,  # m, floor to floor
    "slab_thickness": 0.3,  # m
    "columns_per_side": 3,  # along each side of the void, corners included
    "window_pitch": 3.0,  # m, about one window this often on every storey
    "recess_fraction": 0.5,  # share of recessed windows
    "wall_spacing": 0.10,  # m: walls, columns, balustrades, slab edges
    "ground_spacing": 0.20,  # m: floors, slab undersides, the roof
    "jitter": 0.0025,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 2.5,  # m
}

#: Balustrade height and thickness (m).
BALUSTRADE = (1.1, 0.15)
#: Column radius (m) and how far back from the void's edge its axis stands (m).
COLUMN_RADIUS = 0.3
COLUMN_SETBACK = 0.8
#: Door (width, height) and window (width, height, sill) in the outer walls (m).
DOOR = (2.0, 2.5)
WINDOW = (1.4, 1.6, 1.0)


def volumes(params: dict) -> dict:
    """The flight's volumes (``xmin, ymin, zmin, xmax, ymax, zmax``): ``start`` at the void's
    bottom, 1-2.5 m above the ground floor, ``goal`` at its top, 1.5-3 m above the highest
    gallery's floor; both within 1.5 m of the void's axis."""
    top = (params["storeys"] - 1) * params["storey_height"]
    return {
        "start": (-1.5, -1.5, 1.0, 1.5, 1.5, 2.5),
        "goal": (-1.5, -1.5, top + 1.5, 1.5, 1.5, top + 3.0),
    }


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the atrium scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    size, void, h, t = p["size"], p["void"], p["storey_height"], p["slab_thickness"]
    require(p["storeys"] >= 2, NAME, "storeys must be >= 2 (a ground floor and a gallery)")
    require(void >= 2 * p["free_radius"] and void >= 5.0, NAME, "void must be >= 5 m and >= twice free_radius")
    require(size >= void + 2 * (COLUMN_SETBACK + COLUMN_RADIUS + 1.5), NAME, "size leaves the galleries too shallow")
    require(h >= 3.6 and 0.1 <= t <= 1.0, NAME, "storey_height must be >= 3.6 m and slab_thickness 0.1-1 m")
    require(p["columns_per_side"] >= 2, NAME, "columns_per_side must be >= 2 (the void's corners)")
    require(p["window_pitch"] >= WINDOW[0] + 0.6, NAME, f"window_pitch must be >= {WINDOW[0] + 0.6:g} m")
    require(p["recess_fraction"] <= 1.0, NAME, "recess_fraction must be <= 1")
    require(p["wall_spacing"] > 0 and p["ground_spacing"] > 0, NAME, "spacings must be > 0")
    rng = np.random.default_rng(seed)
    s, g, j = p["wall_spacing"], p["ground_spacing"], p["jitter"]
    ex, ey, ez = np.eye(3)
    half, hv = size / 2, void / 2
    roof = p["storeys"] * h
    hole = [(half - hv, half - hv, half + hv, half + hv)]

    parts = [heightfield_points(rng, Heightfield.flat(), (-half, half), (-half, half), g, j)]
    for level in range(1, p["storeys"] + 1):
        z = level * h
        # The slab around the void: its top (a gallery's floor, or the roof), its
        # underside (the ceiling below), its edge along the void and the balustrade.
        parts.append(rectangle(rng, (-half, -half, z), ex, ey, size, size, g, j, holes=hole))
        parts.append(rectangle(rng, (-half, -half, z - t), ex, ey, size, size, g, j, holes=hole))
        for _, start, end, length in footprint_sides(void, void):
            parts.append(wall(rng, start, end, z - t, t, s, j))
            mid = ((start[0] + end[0]) / 2, (start[1] + end[1]) / 2)
            yaw = math.atan2(end[1] - start[1], end[0] - start[0])
            back = BALUSTRADE[1] / 2  # its centre line half its thickness outside the void
            centre = (mid[0] + back * math.sin(yaw), mid[1] - back * math.cos(yaw), z)
            parts.append(box(rng, centre, (length, BALUSTRADE[1], BALUSTRADE[0]), yaw, s, j))
    # Columns through every storey on a square set back from the void's edges.
    ring = hv + COLUMN_SETBACK
    spots = set()
    for a in np.linspace(-ring, ring, p["columns_per_side"]):
        for b in (-ring, ring):
            spots |= {(round(float(a), 9), round(b, 9)), (round(b, 9), round(float(a), 9))}
    for x, y in sorted(spots):
        parts.append(cylinder(rng, (x, y, 0.0), COLUMN_RADIUS, roof - t, s, j))
    # The outer walls, walked clockwise so that wall() recesses the windows outwards.
    for _, start, end, length in footprint_sides(size, size):
        parts.append(wall(rng, end, start, 0.0, roof, s, j, _openings(rng, p, length)))
    return finish(NAME, DESCRIPTION, seed, p, stack(parts), volumes=volumes(p))


def _openings(rng: np.random.Generator, p: dict, length: float) -> list[Opening]:
    """A door in the middle of the wall on the ground floor and windows about every
    ``window_pitch`` metres on every storey (not over the door), a share
    ``recess_fraction`` of them recessed 10-20 cm."""
    u_door = (length - DOOR[0]) / 2
    openings = [Opening(u_door, 0.0, u_door + DOOR[0], DOOR[1], 0.0)]
    count = max(1, int(length // p["window_pitch"]))
    width, height, sill = WINDOW
    for storey in range(p["storeys"]):
        for i in range(count):
            u0 = (i + 0.5) * length / count - width / 2
            base = storey * p["storey_height"] + sill
            if storey == 0 and u0 < u_door + DOOR[0] + 0.3 and u0 + width > u_door - 0.3:
                continue
            recess = rng.uniform(0.1, 0.2) if rng.random() < p["recess_fraction"] else 0.0
            openings.append(Opening(u0, base, u0 + width, base + height, recess))
    return openings
