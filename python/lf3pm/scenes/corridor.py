"""``corridor``: a bare corridor beside a suite of furnished rooms, for planning studies.

A building between two open courtyards. Through it run, side by side along x,
a corridor with smooth walls and a ceiling and, on its +y side behind a wall
without doors, a suite of rooms opening into one another through doorways in
their partitions and into the courtyards through doorways in the suite's end
walls; each room has a ceiling and furniture along its walls (desks, cabinets,
shelves). The corridor's walls and ceiling stick out of the building's end
walls by ``mouth_length`` and end there in free edges; the courtyards are bare
flat ground and the map ends beyond them (their far sides are open). From
inside the corridor a scan sees two walls, the floor, the ceiling and, through
the ends, bare ground: nothing faces along x, so point-to-plane registration is
degenerate along the corridor (as in ``tunnel``, whose lane is open-air). In the
rooms every partition and piece of furniture fixes x. From the start zone in
the west courtyard to the goal zone in the east one, the way through the rooms
is a few metres longer than the corridor and passes ``rooms - 1`` doorways.
"""

from __future__ import annotations

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.buildings import Opening, wall
from lf3pm.scenes.geometry import Heightfield, box, heightfield_points, rectangle, stack
from lf3pm.scenes.scene import Scene, Zone, check_seed, finish, require, resolve_params

NAME = "corridor"
DESCRIPTION = (
    "Degenerate along x: a 40 m corridor (smooth walls, floor, ceiling) beside a suite of 8 "
    "furnished rooms joined by doorways, between two bare courtyards; walls 5 cm, ground 10 cm; "
    "~0.44 M points by default."
)
DEFAULTS = {
    "length": 40.0,  # m, the building along x, centred on the origin
    "width": 2.4,  # m, the corridor's inside, y from -width/2 to width/2
    "height": 2.7,  # m, walls and ceilings
    "mouth_length": 1.5,  # m the corridor sticks out of the building's end walls
    "rooms": 8,  # in the suite, equal lengths along x
    "room_depth": 5.0,  # m, across y
    "doorway": 2.0,  # m wide, 2.1 m high, in every partition and end wall of the suite
    "furniture": 3,  # pieces per room
    "courtyard_depth": 12.0,  # m of bare ground beyond each end wall
    "wall_spacing": 0.05,  # m
    "ground_spacing": 0.10,  # m
    "jitter": 0.0025,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 1.0,  # m
}

#: Thickness of the wall between the corridor and the rooms (m).
SEPARATING_WALL = 0.2
#: m of courtyard ground beyond the building's sides, across y.
COURTYARD_MARGIN = 3.0
#: Height of the doorways (m).
DOOR_HEIGHT = 2.1
#: Furniture sizes (along the wall, across, height), m: a desk, a cabinet, a shelf, a table.
_FURNITURE = np.array([[1.6, 0.8, 0.75], [0.9, 0.45, 2.0], [1.2, 0.4, 1.8], [1.2, 1.2, 0.75]])


def zones(params: dict) -> dict:
    """The study's zones: ``start`` in the west courtyard, ``goal`` in the east one, 5-9 m
    out from the end walls, in front of the corridor's mouths (within half its width of
    its axis), so that the shortest way between them is the corridor."""
    half, w = params["length"] / 2, params["width"]
    return {"start": Zone(-half - 9.0, -w / 2, -half - 5.0, w / 2), "goal": Zone(half + 5.0, -w / 2, half + 9.0, w / 2)}


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the corridor scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    half, w, h = p["length"] / 2, p["width"], p["height"]
    require(p["length"] >= 20.0, NAME, "length must be >= 20 m")
    require(w >= 2.0 and p["free_radius"] < w / 2, NAME, "width must be >= 2 m and exceed twice free_radius")
    require(h > 2.5, NAME, "height must exceed 2.5 m (the free band)")
    require(p["rooms"] >= 2, NAME, "rooms must be >= 2")
    require(p["length"] / p["rooms"] >= 4.0, NAME, "rooms must be at least 4 m long: use fewer rooms")
    require(p["room_depth"] >= 4.0, NAME, "room_depth must be >= 4 m")
    require(1.2 <= p["doorway"] <= p["room_depth"] - 1.0, NAME, "doorway must be 1.2 m to room_depth - 1 m")
    require(p["courtyard_depth"] >= 10.0, NAME, "courtyard_depth must be >= 10 m (the zones lie 5-9 m out)")
    require(p["mouth_length"] <= 4.0, NAME, "mouth_length must be <= 4 m (the zones start 5 m out)")
    require(p["wall_spacing"] > 0 and p["ground_spacing"] > 0, NAME, "spacings must be > 0")
    rng = np.random.default_rng(seed)
    s, j = p["wall_spacing"], p["jitter"]
    ex, ey = np.eye(3)[:2]
    room_lo = w / 2 + SEPARATING_WALL  # y of the rooms' corridor-side wall
    room_hi = room_lo + p["room_depth"]

    # The corridor: sheets ending in free edges beyond the end walls (see tunnel.py).
    tube = half + p["mouth_length"]
    parts = [
        wall(rng, (-tube, -w / 2), (tube, -w / 2), 0.0, h, s, j),
        wall(rng, (-tube, w / 2), (tube, w / 2), 0.0, h, s, j),
        rectangle(rng, (-tube, -w / 2, h), ex, ey, 2 * tube, w, s, j),
    ]
    # The suite: its two long walls, a ceiling, partitions and end walls with doorways.
    parts += [
        wall(rng, (-half, room_lo), (half, room_lo), 0.0, h, s, j),
        wall(rng, (-half, room_hi), (half, room_hi), 0.0, h, s, j),
        rectangle(rng, (-half, room_lo, h), ex, ey, 2 * half, p["room_depth"], s, j),
    ]
    room_length = p["length"] / p["rooms"]
    doorways = []
    for k in range(p["rooms"] + 1):
        x = -half + k * room_length
        u0 = rng.uniform(0.5, p["room_depth"] - 0.5 - p["doorway"])
        doorways.append((room_lo + u0, room_lo + u0 + p["doorway"]))
        door = Opening(u0, 0.0, u0 + p["doorway"], DOOR_HEIGHT, 0.0)
        parts.append(wall(rng, (x, room_lo), (x, room_hi), 0.0, h, s, j, [door]))
    for k in range(p["rooms"]):
        parts += _furniture(rng, p, -half + k * room_length, room_length, room_lo, room_hi, doorways[k : k + 2])
    # The building's end walls beside the corridor's mouths, facing the courtyards.
    y_lo, y_hi = -w / 2 - COURTYARD_MARGIN, room_hi + COURTYARD_MARGIN
    for x in (-half, half):
        for a, b in ((y_lo, -w / 2), (w / 2, room_lo), (room_hi, y_hi)):
            parts.append(wall(rng, (x, a), (x, b), 0.0, h, s, j))

    def on_ground(x, y):
        courtyard = np.abs(x) >= half
        corridor = np.abs(y) < w / 2
        rooms = (y > room_lo) & (y < room_hi)
        return courtyard | corridor | rooms

    parts.append(
        heightfield_points(
            rng,
            Heightfield.flat(),
            (-half - p["courtyard_depth"], half + p["courtyard_depth"]),
            (y_lo, y_hi),
            p["ground_spacing"],
            j,
            keep=on_ground,
        )
    )
    return finish(NAME, DESCRIPTION, seed, p, stack(parts), zones=zones(p))


def _furniture(
    rng: np.random.Generator, p: dict, x0: float, length: float, y_lo: float, y_hi: float, doorways: list
) -> list:
    """``furniture`` pieces against the long walls of the room from ``x0`` to ``x0 + length``,
    clear of each other and 0.6 m (a robot's radius and clearance) clear of the band between its two doorways
    (``doorways``: the (y0, y1) spans of the doorways at its west and east ends), so the
    room stays passable; a piece that finds no place is left out."""
    parts, taken = [], {y_lo: [], y_hi: []}
    path_lo = min(d[0] for d in doorways) - 0.6
    path_hi = max(d[1] for d in doorways) + 0.6
    for _ in range(p["furniture"]):
        size = _FURNITURE[rng.integers(len(_FURNITURE))] * rng.uniform(0.9, 1.1)
        y_wall = y_lo if rng.random() < 0.5 else y_hi
        inward = 1.0 if y_wall == y_lo else -1.0
        depth_span = sorted((y_wall, y_wall + inward * (size[1] + 0.05)))
        if depth_span[1] > path_lo and depth_span[0] < path_hi:
            continue  # it would block the way between the doorways
        for _attempt in range(50):
            x = rng.uniform(x0 + 0.3 + size[0] / 2, x0 + length - 0.3 - size[0] / 2)
            span = (x - size[0] / 2 - 0.2, x + size[0] / 2 + 0.2)
            if all(span[1] < a or span[0] > b for a, b in taken[y_wall]):
                taken[y_wall].append(span)
                y = y_wall + inward * (size[1] / 2 + 0.05)
                parts.append(box(rng, (x, y, 0.0), size, 0.0, p["wall_spacing"], p["jitter"]))
                break
    return parts
