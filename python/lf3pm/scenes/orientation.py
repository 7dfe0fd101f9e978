"""``orientation``: structure on one side of open flat ground, for limited fields of view.

A building front faces +x from ``facade_distance`` metres behind the origin:
two storeys of recessed windows, a recessed entrance behind the origin and
projecting bays, with cars (boxes) parked along it. In front of it lies bare
flat ground, out to ``open_length`` metres past the origin, and nothing else:
the map ends there. A sensor that sees only that ground observes z, roll and
pitch but not x, y or yaw, so a forward-looking LiDAR (a Livox Mid-70, 70
degrees) on a robot driving away from the building localizes only while it
faces back towards it. The building has no roof and no floor (a ground sensor
sees neither; a roof would put SOLM cells on it) and no openings into it.
"""

from __future__ import annotations

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.buildings import Opening, facade_openings, wall
from lf3pm.scenes.geometry import Heightfield, box, heightfield_points, stack
from lf3pm.scenes.scene import Scene, Zone, check_seed, finish, require, resolve_params

NAME = "orientation"
DESCRIPTION = (
    "Structure on one side: a 44 m two-storey building front (recessed windows, bays, "
    "parked cars) 8 m behind the origin, bare flat ground 50 m out in front, nothing "
    "else; walls 5 cm, ground 10 cm; ~0.64 M points by default."
)
DEFAULTS = {
    "facade_distance": 8.0,  # m from the origin back to the building front (at x = -facade_distance)
    "facade_length": 44.0,  # m, along y, centred on y = 0
    "facade_height": 6.5,  # m (two storeys)
    "building_depth": 10.0,  # m, behind the front
    "bays": 2,  # bays projecting from the front
    "bay_depth": 1.5,  # m
    "cars": 4,  # parked along the front
    "open_length": 50.0,  # m of ground in front of the origin (x up to open_length)
    "ground_width": 50.0,  # m, along y, centred on y = 0
    "wall_spacing": 0.05,  # m
    "ground_spacing": 0.10,  # m
    "jitter": 0.0025,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 3.0,  # m
}

#: Half the width of the entrance's recess and of the strip kept clear of cars before it (m).
ENTRANCE_HALF = 1.0
CAR_CLEAR = 3.0
#: Length of a parking slot along the front (m).
CAR_SLOT = 5.4


def zones(params: dict) -> dict:
    """The study's zones: ``start`` by the building (2-10 m in front of it, the origin
    inside), ``goal`` out in the open, 24-34 m past the origin (32-42 m from the
    front at the defaults), both within 6 m (start) and 8 m (goal) of the centre line."""
    return {"start": Zone(-2.0, -6.0, 2.0, 6.0), "goal": Zone(24.0, -8.0, 34.0, 8.0)}


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the orientation scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    xf, length, height = -p["facade_distance"], p["facade_length"], p["facade_height"]
    bay = p["bay_depth"]
    require(length >= 20.0, NAME, "facade_length must be >= 20 m")
    require(height >= 3.0, NAME, "facade_height must be >= 3 m")
    require(p["building_depth"] >= 2.0, NAME, "building_depth must be >= 2 m")
    require(0.3 <= bay <= 3.0, NAME, "bay_depth must be 0.3-3 m")
    require(p["bays"] <= 4, NAME, "bays must be 0-4")
    # Cars (1.9 m wide) stand 1.2 m in front of the bays; they and the front must clear the free radius.
    require(
        p["facade_distance"] - bay - 3.1 >= p["free_radius"],
        NAME,
        "facade_distance is too small: the cars would stand within free_radius of the origin",
    )
    require(p["open_length"] >= 36.0, NAME, "open_length must be >= 36 m (the goal zone ends at 34 m)")
    require(p["ground_width"] >= 16.0, NAME, "ground_width must be >= 16 m (the goal zone is 16 m wide)")
    require(p["wall_spacing"] > 0 and p["ground_spacing"] > 0, NAME, "spacings must be > 0")
    rng = np.random.default_rng(seed)
    s, j = p["wall_spacing"], p["jitter"]
    storeys = 2 if height >= 5.6 else 1

    bays = _bay_spans(rng, p)
    parts = [_front(rng, p, bays, storeys)]
    # The building's sides and back, plain: only their corners are ever in view.
    back = xf - p["building_depth"]
    for start, end in (
        ((xf, length / 2), (back, length / 2)),
        ((back, length / 2), (back, -length / 2)),
        ((back, -length / 2), (xf, -length / 2)),
    ):
        parts.append(wall(rng, start, end, 0.0, height, s, j))
    parts += _cars(rng, p, xf + bay + 1.2)

    def on_ground(x, y):
        inside_bay = np.zeros(np.shape(x), bool)
        for y0, y1 in bays:
            inside_bay |= (x < xf + bay) & (y > y0) & (y < y1)
        return ~inside_bay

    half_w = p["ground_width"] / 2
    parts.append(
        heightfield_points(
            rng, Heightfield.flat(), (xf, p["open_length"]), (-half_w, half_w), p["ground_spacing"], j, keep=on_ground
        )
    )
    return finish(NAME, DESCRIPTION, seed, p, stack(parts), zones=zones(p))


def _bay_spans(rng: np.random.Generator, p: dict) -> list:
    """(y0, y1) of the bays, 4-6 m wide, apart from each other and from the
    entrance's strip and the front's ends by at least 2 m, sorted by y."""
    half = p["facade_length"] / 2
    spans = []
    for _ in range(p["bays"]):
        width = rng.uniform(4.0, 6.0)
        for _attempt in range(200):
            y0 = rng.uniform(-half + 2.0, half - 2.0 - width)
            clear_of_entrance = y0 > CAR_CLEAR or y0 + width < -CAR_CLEAR
            if clear_of_entrance and all(y0 > b + 2.0 or y0 + width < a - 2.0 for a, b in spans):
                break
        else:
            require(False, NAME, f"cannot place {p['bays']} bays on the front; use fewer or a longer front")
        spans.append((y0, y0 + width))
    return sorted(spans)


def _front(rng: np.random.Generator, p: dict, bays: list, storeys: int) -> np.ndarray:
    """The building front from y = -L/2 to L/2 (drawn towards +y, so that wall() puts
    recesses into the building): recessed windows on every storey, a recessed
    entrance at y = 0, and the bays with their sides."""
    xf, half, height, bay = -p["facade_distance"], p["facade_length"] / 2, p["facade_height"], p["bay_depth"]
    s, j = p["wall_spacing"], p["jitter"]
    parts = []
    edges = [-half] + [y for span in bays for y in span] + [half]
    for k in range(len(edges) - 1):
        y0, y1 = edges[k], edges[k + 1]
        x = xf + bay if k % 2 else xf  # odd segments are the bays' fronts
        openings = facade_openings(rng, y1 - y0, storeys, door=False, recess_fraction=1.0)
        if y0 < 0.0 < y1 and x == xf:  # the entrance, set 0.4 m into the front
            entrance = Opening(-y0 - ENTRANCE_HALF, 0.0, -y0 + ENTRANCE_HALF, 2.4, 0.4)
            openings = [
                o for o in openings if o.u1 < entrance.u0 - 0.3 or o.u0 > entrance.u1 + 0.3 or o.v0 > entrance.v1 + 0.3
            ]  # no ground-floor window over the entrance
            openings.append(entrance)
        parts.append(wall(rng, (x, y0), (x, y1), 0.0, height, s, j, openings))
    for y0, y1 in bays:  # the bays' sides
        parts.append(wall(rng, (xf, y0), (xf + bay, y0), 0.0, height, s, j))
        parts.append(wall(rng, (xf + bay, y1), (xf, y1), 0.0, height, s, j))
    return stack(parts)


def _cars(rng: np.random.Generator, p: dict, x_back: float) -> list:
    """Cars (boxes 4.2-4.8 x 1.7-1.9 x 1.4-1.6 m) parked along the front, their backs
    at ``x_back``, in slots CAR_SLOT metres long either side of the strip before the
    entrance (``cars`` of them drawn at random), shifted by up to 0.2 m and turned
    by up to 3 degrees, so that neighbours never touch."""
    half = p["facade_length"] / 2
    per_side = int((half - 1.0 - CAR_CLEAR) // CAR_SLOT)
    slots = [side * (CAR_CLEAR + (k + 0.5) * CAR_SLOT) for side in (-1.0, 1.0) for k in range(per_side)]
    require(p["cars"] <= len(slots), NAME, f"cars must be at most {len(slots)} (the front's parking slots)")
    parts = []
    for k in sorted(rng.choice(len(slots), size=p["cars"], replace=False)):
        size = np.array([rng.uniform(4.2, 4.8), rng.uniform(1.7, 1.9), rng.uniform(1.4, 1.6)])
        y = slots[k] + rng.uniform(-0.2, 0.2)
        yaw = np.pi / 2 + rng.uniform(-0.05, 0.05)  # the car's length along y
        parts.append(box(rng, (x_back + size[1] / 2, y, 0.0), size, yaw, p["wall_spacing"], p["jitter"]))
    return parts
