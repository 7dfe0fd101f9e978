"""``house_meadow``: one house on a meadow.

A two-storey pitched-roof house (door, windows, recesses) stands on a level
pad in the meadow of :mod:`lf3pm.scenes.meadow` (grass tufts, weeds, bushes
on gently uneven ground), its front wall ``house_distance`` metres from the
reference pose, facing it. A bare strip 0.4 m wide runs along the walls and
a path leads from the reference pose's mowed patch to the door; a few bushes
grow beside the house.
"""

from __future__ import annotations

import math

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.buildings import house
from lf3pm.scenes.geometry import heightfield_points, stack
from lf3pm.scenes.meadow import meadow_terrain
from lf3pm.scenes.scene import Scene, check_seed, finish, mow, require, resolve_params
from lf3pm.scenes.vegetation import BUSH_REACH, bushes, meadow_cover

NAME = "house_meadow"
DESCRIPTION = (
    "One two-storey house on a 44 x 44 m meadow (grass tufts, weeds, bushes), its front "
    "wall 4 m from the origin; walls 5 cm, ground 10 cm, blades and leaves "
    "1.2-1.5 cm; ~1.8 M points by default."
)
DEFAULTS = {
    "extent": 22.0,  # m, half-width of the square
    "house_distance": 4.0,  # m from the origin to the front wall (at y = house_distance)
    "house_width": 11.0,  # m, along x
    "house_depth": 8.0,  # m, along y
    "storeys": 2,
    "relief": 0.25,  # m, amplitude of the meadow's undulation
    "ground_spacing": 0.10,  # m
    "wall_spacing": 0.05,  # m
    "jitter": 0.0025,  # m
    "tufts_per_m2": 6.0,
    "blades_per_tuft": 9.0,
    "weeds_per_m2": 0.3,
    "bushes_per_100m2": 1.5,
    "mowed_height": 0.15,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 2.5,  # m
}


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the house_meadow scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    w, d, dist = p["house_width"], p["house_depth"], p["house_distance"]
    require(w >= 4.0 and d >= 4.0, NAME, "the house must be at least 4 x 4 m")
    require(1 <= p["storeys"] <= 3, NAME, "storeys must be 1..3")
    require(p["extent"] >= max(w / 2, dist + d) + 3.0, NAME, "extent is too small for the house")
    require(dist > p["free_radius"], NAME, "house_distance must exceed free_radius")
    require(p["mowed_height"] < 0.2, NAME, "mowed_height must be < 0.2 m (the free band starts there)")
    require(p["ground_spacing"] > 0 and p["wall_spacing"] > 0, NAME, "spacings must be > 0")
    rng = np.random.default_rng(seed)
    r = p["free_radius"]
    cy = dist + d / 2
    pad = math.hypot(w, d) / 2 + 1.0
    terrain = meadow_terrain(rng, p["relief"], [(0.0, cy, pad, 4.0), (0.0, 0.0, r + 1.0, 4.0)])
    base = float(terrain(np.array([0.0]), np.array([cy]))[0])
    door_x = rng.uniform(-w / 2 + 1.5, w / 2 - 1.5)

    def in_house(x, y, margin):
        return (np.abs(x) < w / 2 + margin) & (np.abs(y - cy) < d / 2 + margin)

    def on_path(x, y):
        return (np.abs(x - door_x * np.clip(y / dist, 0.0, 1.0)) < 0.6) & (y > 0.0) & (y < dist)

    def keep(x, y):
        return ~in_house(x, y, 0.4) & ~on_path(x, y)

    def bush_keep(x, y):
        return keep(x, y) & ~in_house(x, y, BUSH_REACH + 0.4) & (np.hypot(x, y) > r + BUSH_REACH)

    e = (-p["extent"], p["extent"])
    cover = meadow_cover(
        rng,
        terrain,
        e,
        e,
        keep,
        p["tufts_per_m2"],
        p["blades_per_tuft"],
        p["weeds_per_m2"],
        p["bushes_per_100m2"],
        bush_keep=bush_keep,
    )
    # A few bushes planted along the back and the sides of the house.
    beside = np.array(
        [
            [rng.uniform(-w / 2, w / 2), cy + d / 2 + 1.6],
            [rng.uniform(-w / 2, w / 2), cy + d / 2 + 1.6],
            [-w / 2 - 1.6, cy + rng.uniform(-d / 2, d / 2)],
            [w / 2 + 1.6, cy + rng.uniform(-d / 2, d / 2)],
        ]
    )
    cover = stack([cover, bushes(rng, terrain, beside, radius=(0.4, 0.8))])
    cover = mow(cover, 0.0, 0.0, r + 0.6, terrain, p["mowed_height"])
    pitch = math.radians(rng.uniform(30.0, 40.0))
    building = house(
        rng, (0.0, cy, base), 0.0, w, d, p["storeys"], pitch, p["wall_spacing"], p["jitter"], door_x=door_x
    )  # front wall at y = dist, facing the origin
    ground = heightfield_points(rng, terrain, e, e, p["ground_spacing"], 0.01)
    return finish(NAME, DESCRIPTION, seed, p, stack([ground, cover, building]))
