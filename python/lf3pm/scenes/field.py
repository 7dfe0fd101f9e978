"""``field``: an open field with one structured edge, for limited fields of view.

Bare flat ground, ``field_length`` metres along x, and along its +y side,
``edge_offset`` metres from the x axis, a row of low buildings (recessed
windows, doors, gaps between them) with containers in front, from the field's
west end to ``edge_end``; beyond that, and everywhere else, the map ends in
open ground. The study's route crosses the field along x, from a start zone
near its west end to a goal zone past the row's east end. A forward-looking
LiDAR (a Livox Mid-70, 70 degrees) heading along x sees the row ahead-left
only while some of it lies within 35 degrees of its heading, i.e. more than
``edge_offset / tan 35`` (about 26 m) ahead: past ``edge_end - 26`` it sees
ground alone and observes z, roll and pitch but not x, y or yaw. It stays
localized by turning towards the row (an omnidirectional robot) or by driving
close along it (any robot). Unlike ``orientation`` (structure behind the
start), the structure here runs beside the route and ends before the goal.
"""

from __future__ import annotations

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.buildings import facade_openings, footprint_sides, wall
from lf3pm.scenes.geometry import Heightfield, box, heightfield_points, place, stack
from lf3pm.scenes.scene import Scene, Zone, check_seed, finish, require, resolve_params

NAME = "field"
DESCRIPTION = (
    "Structure on one edge: a row of low buildings and containers 18 m to the side of "
    "a 100 m field of bare flat ground, ending 20 m before its east end; walls 5 cm, ground "
    "10 cm; ~0.83 M points by default."
)
DEFAULTS = {
    "field_length": 100.0,  # m along x, centred on x = 0
    "field_width": 44.0,  # m of ground along y, from -field_width/2 to field_width/2
    "edge_offset": 18.0,  # m, the x axis to the row's fronts (at y = edge_offset)
    "edge_end": 20.0,  # m, x where the row ends (it starts at the field's west end)
    "building_height": 5.0,  # m, mean (each one 0.75-1.25 times)
    "containers": 5,  # standing in front of the row
    "wall_spacing": 0.05,  # m
    "ground_spacing": 0.10,  # m
    "jitter": 0.0025,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 3.0,  # m
}

#: Building widths along the row and depths (m), and the gaps between them (m).
WIDTH = (8.0, 16.0)
DEPTH = (6.0, 10.0)
GAP = (2.0, 6.0)
#: A shipping container, 20 ft (m): length, width, height.
CONTAINER = (6.06, 2.44, 2.59)


def zones(params: dict) -> dict:
    """The study's zones: ``start`` 8-14 m from the field's west end, ``goal`` 8-14 m from
    its east end, both within 5 m of the x axis."""
    half = params["field_length"] / 2
    return {"start": Zone(-half + 8.0, -5.0, -half + 14.0, 5.0), "goal": Zone(half - 14.0, -5.0, half - 8.0, 5.0)}


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the field scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    half, edge = p["field_length"] / 2, p["edge_offset"]
    require(p["field_length"] >= 60.0, NAME, "field_length must be >= 60 m")
    require(
        12.0 <= edge <= p["field_width"] / 2 - 2.0,
        NAME,
        "edge_offset must be >= 12 m (clear of the zones) and the fronts 2 m inside the field",
    )
    require(
        -half + 20.0 <= p["edge_end"] <= half - 14.0,
        NAME,
        "edge_end must lie at least 20 m from the field's west end and before the goal zone",
    )
    require(2.5 <= p["building_height"] <= 20.0, NAME, "building_height must be 2.5-20 m")
    require(p["wall_spacing"] > 0 and p["ground_spacing"] > 0, NAME, "spacings must be > 0")
    rng = np.random.default_rng(seed)
    s, j = p["wall_spacing"], p["jitter"]

    parts, x, spans = [], -half, []
    while True:
        width = rng.uniform(*WIDTH)
        if x + width > p["edge_end"]:
            break
        depth = rng.uniform(*DEPTH)
        height = p["building_height"] * rng.uniform(0.75, 1.25)
        parts.append(_building(rng, (x + width / 2, edge + depth / 2, 0.0), width, depth, height, s, j))
        spans.append((x, x + width))
        x += width + rng.uniform(*GAP)
    require(len(spans) >= 2, NAME, "the row holds fewer than two buildings: make edge_end larger")
    parts += _containers(rng, p)
    half_w = p["field_width"] / 2

    def on_ground(px, py):
        inside = np.zeros(np.shape(px), bool)
        for x0, x1 in spans:
            inside |= (px > x0) & (px < x1) & (py > edge)
        return ~inside

    parts.append(
        heightfield_points(
            rng, Heightfield.flat(), (-half, half), (-half_w, half_w), p["ground_spacing"], j, keep=on_ground
        )
    )
    return finish(NAME, DESCRIPTION, seed, p, stack(parts), zones=zones(p))


def _building(
    rng: np.random.Generator, centre, width: float, depth: float, height: float, s: float, j: float
) -> np.ndarray:
    """Four walls (front facing -y) with a door and recessed windows, no roof (a ground
    sensor does not see it and a roof would put SOLM cells on it)."""
    storeys = max(1, int(height // 2.8))
    parts = [
        wall(
            rng,
            start,
            end,
            0.0,
            height,
            s,
            j,
            facade_openings(rng, length, storeys, door=side == 0, recess_fraction=0.7),
        )
        for side, start, end, length in footprint_sides(width, depth)
    ]
    return place(stack(parts), 0.0, centre)


def _containers(rng: np.random.Generator, p: dict) -> list:
    """``containers`` containers in front of the row, 1-3 m before the fronts, at random
    x along it, turned by up to 10 degrees; no two overlap."""
    length, width, height = CONTAINER
    x_lo, x_hi = -p["field_length"] / 2 + length / 2 + 1.0, p["edge_end"] - length / 2 - 1.0
    parts, taken = [], []
    for _ in range(p["containers"]):
        for _attempt in range(100):
            x = rng.uniform(x_lo, x_hi)
            if all(abs(x - other) > length + 1.0 for other in taken):
                break
        else:
            require(False, NAME, f"cannot place {p['containers']} containers in front of the row; use fewer")
        taken.append(x)
        y = p["edge_offset"] - rng.uniform(1.0, 3.0) - width / 2
        parts.append(
            box(rng, (x, y, 0.0), (length, width, height), rng.uniform(-0.17, 0.17), p["wall_spacing"], p["jitter"])
        )
    return parts
