"""``open_field``: a flat open field whose one structured side shows only from altitude.

Bare flat ground, ``field_length`` metres along x. Along its +y side an earth berm
(a trapezoid: ``berm_height`` high, a crest ``berm_crest`` wide whose front edge
lies ``berm_distance`` from the x axis, slopes of ``berm_slope`` run per rise)
runs the field's whole length and ends in free edges at its ends, so its
cross-section is the same everywhere and nothing of it faces along x. Behind it a
building (``facade_length`` long, ``building_height`` high, ``building_depth``
deep, a flat roof) turns its front to the field at y = ``facade_distance``:
storeys of recessed windows, pilasters between bays and a recessed entrance. The
berm stands close in front of it, high enough that from near the x axis at low
altitude (up to about 3 m at the defaults; the builder checks the start and goal
volumes) every line of sight to the building passes through the berm: a scan sees
flat ground and the berm, which fix z, y, roll, pitch and yaw but not x. Higher up
the facade's upper part shows over the berm's crest and fixes x too (from 8 m on
the axis, what lies above 4.4 m). The start volume hovers near the field's west
end, the goal near its east end, both low, on the x axis. The map's top is the
building's (8 m): an R3 grid meant to fly higher needs its z levels given.
"""

from __future__ import annotations

import math

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.buildings import Opening, footprint_sides, wall
from lf3pm.scenes.geometry import Heightfield, box, heightfield_points, place, rectangle, stack
from lf3pm.scenes.scene import Scene, check_seed, finish, require, resolve_params

NAME = "open_field"
DESCRIPTION = (
    "Flight over open ground: a 90 m field whose one side is a building facade hidden "
    "behind a 6 m berm below about 3 m of altitude and visible above; start and goal "
    "volumes low at its two ends; walls 10 cm, ground 20 cm; ~0.26 M points by default."
)
DEFAULTS = {
    "field_length": 90.0,  # m along x, centred on the origin
    "field_front": 15.0,  # m of ground on the -y side of the x axis
    "berm_distance": 15.0,  # m, the x axis to the front edge of the berm's crest
    "berm_height": 6.0,  # m
    "berm_crest": 2.0,  # m, the crest's width
    "berm_slope": 1.5,  # m of run per m of rise, both slopes
    "facade_distance": 27.0,  # m, the x axis to the building's front
    "facade_length": 60.0,  # m along x, centred on the origin
    "building_height": 8.0,  # m, storeys of 2.8 m (rounded); hidden from the volumes
    "building_depth": 10.0,  # m
    "bay": 6.0,  # m, pilaster to pilaster along the front
    "wall_spacing": 0.10,  # m
    "ground_spacing": 0.20,  # m: the field, the berm, the roof
    "jitter": 0.0025,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 3.0,  # m
}

#: Pilaster section (m): along the front, out of it.
PILASTER = (0.4, 0.3)
#: Windows: width, height and sill above each storey's floor (m); storey height (m).
WINDOW = (1.4, 1.3, 0.9)
STOREY = 2.8
#: The entrance in the middle bay: width, height, recess (m).
ENTRANCE = (2.4, 2.4, 1.0)
#: m of ground behind the building.
BACK_MARGIN = 3.0


def volumes(params: dict) -> dict:
    """The flight's volumes (``xmin, ymin, zmin, xmax, ymax, zmax``): ``start`` 5-9 m in from
    the field's west end, ``goal`` 5-9 m in from its east end, both within 2 m of the x
    axis and 1-2.5 m above the ground."""
    half = params["field_length"] / 2
    return {
        "start": (-half + 5.0, -2.0, 1.0, -half + 9.0, 2.0, 2.5),
        "goal": (half - 9.0, -2.0, 1.0, half - 5.0, 2.0, 2.5),
    }


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the open field scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    half, hb = p["field_length"] / 2, p["berm_height"]
    run = hb * p["berm_slope"]
    foot_front = p["berm_distance"] - run
    foot_back = p["berm_distance"] + p["berm_crest"] + run
    yf, hf, depth = p["facade_distance"], p["building_height"], p["building_depth"]
    require(p["field_length"] >= 40.0, NAME, "field_length must be >= 40 m")
    require(p["field_front"] >= 5.0, NAME, "field_front must be >= 5 m")
    require(hb >= 1.0 and p["berm_slope"] >= 0.5, NAME, "berm_height must be >= 1 m and berm_slope >= 0.5")
    require(foot_front >= 4.0, NAME, "the berm's front foot must lie >= 4 m from the x axis (clear of the volumes)")
    require(foot_back + 1.0 <= yf, NAME, "the building's front must stand >= 1 m behind the berm's back foot")
    require(
        p["facade_length"] <= p["field_length"] - 4.0 and p["facade_length"] >= 2 * p["bay"],
        NAME,
        "facade_length must be >= two bays and 4 m shorter than the field",
    )
    storeys = _storeys(p)
    require(
        WINDOW[2] + (storeys - 1) * STOREY + WINDOW[1] <= hf - 0.1,
        NAME,
        f"building_height must leave 0.1 m above its top windows ({storeys} storeys of {STOREY:g} m)",
    )
    # The sight line over the crest's front edge from the volumes' farthest, highest
    # edge (y = ymin, z = zmax) passes lowest over the building's front.
    _, y_eye, _, _, _, z_eye = volumes(p)["start"]
    over = z_eye + (hb - z_eye) * (yf - y_eye) / (p["berm_distance"] - y_eye)
    require(
        hf <= over,
        NAME,
        f"building_height {hf:g} m would show over the berm from the volumes (hidden up to {over:.2f} m)",
    )
    require(p["bay"] >= 4.0, NAME, "bay must be >= 4 m")
    require(depth >= 4.0, NAME, "building_depth must be >= 4 m")
    require(p["wall_spacing"] > 0 and p["ground_spacing"] > 0, NAME, "spacings must be > 0")
    rng = np.random.default_rng(seed)
    g, j = p["ground_spacing"], p["jitter"]
    ex, ey = np.eye(3)[:2]
    length = p["field_length"]

    # The berm: front slope, crest, back slope, each a sheet the field's length.
    slope = math.hypot(run, hb)
    parts = [
        rectangle(rng, (-half, foot_front, 0.0), ex, np.array([0.0, run, hb]) / slope, length, slope, g, j),
        rectangle(rng, (-half, p["berm_distance"], hb), ex, ey, length, p["berm_crest"], g, j),
        rectangle(rng, (-half, foot_back - run, hb), ex, np.array([0.0, run, -hb]) / slope, length, slope, g, j),
    ]
    parts.append(_building(rng, p))
    y_back = yf + depth + BACK_MARGIN
    half_facade = p["facade_length"] / 2

    def open_ground(x, y):
        under_berm = (y > foot_front) & (y < foot_back)
        under_building = (np.abs(x) < half_facade) & (y > yf) & (y < yf + depth)
        return ~(under_berm | under_building)

    parts.append(
        heightfield_points(rng, Heightfield.flat(), (-half, half), (-p["field_front"], y_back), g, j, keep=open_ground)
    )
    return finish(NAME, DESCRIPTION, seed, p, stack(parts), volumes=volumes(p))


def _storeys(p: dict) -> int:
    """The building's storeys: its height over STOREY, rounded."""
    return max(1, round(p["building_height"] / STOREY))


def _building(rng: np.random.Generator, p: dict) -> np.ndarray:
    """The building in its own frame (footprint centred on the origin, front at
    y = -depth/2), placed with its front at y = facade_distance: a front of bays
    between pilasters, two recessed windows per bay and storey, a recessed entrance
    in the middle bay; plain sides and back; a flat roof."""
    s, g, j = p["wall_spacing"], p["ground_spacing"], p["jitter"]
    length, depth, height = p["facade_length"], p["building_depth"], p["building_height"]
    bays = max(2, int(round(length / p["bay"])))
    bay = length / bays
    width, tall, sill = WINDOW
    openings = []
    for k in range(bays):
        for storey in range(_storeys(p)):
            for centre in (bay / 4, 3 * bay / 4):
                u0 = k * bay + centre - width / 2
                v0 = storey * STOREY + sill
                if storey == 0 and k == bays // 2:
                    continue  # the entrance's bay
                openings.append(Opening(u0, v0, u0 + width, v0 + tall, rng.uniform(0.1, 0.25)))
    door = (bays // 2 + 0.5) * bay - ENTRANCE[0] / 2
    openings.append(Opening(door, 0.0, door + ENTRANCE[0], ENTRANCE[1], ENTRANCE[2]))
    parts = []
    for side, start, end, _ in footprint_sides(length, depth):
        parts.append(wall(rng, start, end, 0.0, height, s, j, openings if side == 0 else ()))
    for k in range(1, bays):
        parts.append(
            box(
                rng,
                (-length / 2 + k * bay, -depth / 2 - PILASTER[1] / 2, 0.0),
                (PILASTER[0], PILASTER[1], height),
                0.0,
                s,
                j,
            )
        )
    parts.append(rectangle(rng, (-length / 2, -depth / 2, height), np.eye(3)[0], np.eye(3)[1], length, depth, g, j))
    return place(stack(parts), 0.0, (0.0, p["facade_distance"] + depth / 2, 0.0))
