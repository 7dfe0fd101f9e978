"""``houses``: a block of pitched-roof houses along a street, on flat ground.

Two rows of lots face each other across a street along x (the reference pose
stands in it, at the origin), with cross streets between the lots. Each house
has 1-2 storeys, a door in the front wall, windows on every wall (holes in
the wall samples, some of them recessed with their reveals and pane) and a
pitched roof with overhangs.
"""

from __future__ import annotations

import math

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.buildings import house
from lf3pm.scenes.geometry import Heightfield, heightfield_points, stack
from lf3pm.scenes.scene import Scene, Zone, check_seed, finish, require, resolve_params

NAME = "houses"
DESCRIPTION = (
    "A block of 6 pitched-roof houses (doors, windows, recesses) along a 10 m street "
    "on flat ground, 70 x 70 m; walls 5 cm, ground 10 cm; ~1.4 M points by default."
)
DEFAULTS = {
    "houses": 6,  # 1..6 lots filled (two rows of three)
    "street_width": 10.0,  # m, the street along x through the origin
    "lot_pitch": 20.0,  # m between the lots' centres along x
    "extent": 35.0,  # m, half-width of the square of ground
    "wall_spacing": 0.05,  # m, walls and roofs
    "ground_spacing": 0.10,  # m
    "jitter": 0.0025,  # m, 1-sigma, in the plane (a third of it along the normal)
    "recess_fraction": 0.5,  # share of the windows that are recessed
    "sensor_height": 1.0,  # m above the ground
    "free_radius": 3.0,  # m
}


def zones(params: dict) -> dict:
    """The study's zones, in the street (2 m clear of its edges, whatever the
    layout): ``start`` 15-25 m west of the origin, ``goal`` 5-15 m east of it."""
    half = params["street_width"] / 2 - 2.0
    return {"start": Zone(-25.0, -half, -15.0, half), "goal": Zone(5.0, -half, 15.0, half)}


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the houses scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    require(1 <= p["houses"] <= 6, NAME, f"houses must be 1..6, got {p['houses']}")
    require(p["lot_pitch"] >= 14.0, NAME, "lot_pitch must be >= 14 m (houses are up to 12 m wide)")
    require(
        p["extent"] >= 1.5 * p["lot_pitch"] + 2.0 and p["extent"] >= p["street_width"] / 2 + 12.0,
        NAME,
        "extent is too small for the block",
    )
    require(p["wall_spacing"] > 0 and p["ground_spacing"] > 0, NAME, "spacings must be > 0")
    require(p["street_width"] >= 5.0, NAME, "street_width must be >= 5 m")
    rng = np.random.default_rng(seed)

    shift = rng.uniform(-0.2, 0.2) * p["lot_pitch"]  # the origin is not in front of a house's middle
    lots = [(col, row) for row in (1, -1) for col in (-1, 0, 1)]
    filled = sorted(rng.choice(len(lots), size=p["houses"], replace=False))
    parts = []
    for i in filled:
        col, row = lots[i]
        width = rng.uniform(8.0, 12.0)
        depth = rng.uniform(7.0, 10.0)
        setback = rng.uniform(0.0, 2.0)
        storeys = int(rng.integers(1, 3))
        pitch = math.radians(rng.uniform(25.0, 42.0))
        x = col * p["lot_pitch"] + shift + rng.uniform(-1.0, 1.0)
        y = row * (p["street_width"] / 2 + setback + depth / 2)
        yaw = 0.0 if row > 0 else math.pi  # the front wall faces the street
        parts.append(
            house(
                rng,
                (x, y, 0.0),
                yaw,
                width,
                depth,
                storeys,
                pitch,
                p["wall_spacing"],
                p["jitter"],
                p["recess_fraction"],
            )
        )
    e = p["extent"]
    parts.append(heightfield_points(rng, Heightfield.flat(), (-e, e), (-e, e), p["ground_spacing"], p["jitter"]))
    return finish(NAME, DESCRIPTION, seed, p, stack(parts), zones=zones(p))
