"""``meadow``: gently uneven open ground covered with grass, weeds and bushes.

Grass grows in tufts (about 9 blades, 6-30 cm high, splayed and drooping),
weeds are rosettes of broad leaves or stems with leaves, bushes are leafy
canopies 0.6-1.8 m across. The ground undulates by about +-25 cm over 6-30 m
with 3 cm bumps over 1-3 m. The reference pose stands on a mowed patch (grass
below 15 cm, level ground) of radius ``free_radius``.
"""

from __future__ import annotations

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.geometry import Heightfield, heightfield_points, stack
from lf3pm.scenes.scene import Scene, check_seed, finish, mow, require, resolve_params
from lf3pm.scenes.vegetation import BUSH_REACH, meadow_cover

NAME = "meadow"
DESCRIPTION = (
    "Open meadow, 44 x 44 m, gently uneven (+-25 cm), covered with grass tufts, weeds and "
    "bushes (many small randomly oriented surfaces sampled every 1.2-1.5 cm); ground 10 cm; "
    "~1.7 M points by default."
)
DEFAULTS = {
    "extent": 22.0,  # m, half-width of the square
    "relief": 0.25,  # m, amplitude of the undulation
    "ground_spacing": 0.10,  # m
    "tufts_per_m2": 6.0,
    "blades_per_tuft": 9.0,
    "weeds_per_m2": 0.3,
    "bushes_per_100m2": 1.5,
    "mowed_height": 0.15,  # m, grass height on the patch around the reference pose
    "sensor_height": 1.0,  # m above the ground
    "free_radius": 2.5,  # m
}


def meadow_terrain(rng: np.random.Generator, relief: float, pads) -> Heightfield:
    """Undulating meadow ground, level on the given pads (x, y, radius, blend), 0 at the origin."""
    terrain = Heightfield.random(rng, relief, (6.0, 30.0)).plus(Heightfield.random(rng, min(0.03, relief), (1.0, 3.0)))
    for x, y, radius, blend in pads:
        terrain = terrain.with_pad(x, y, radius, blend)
    return terrain.shifted_to_zero_at(0.0, 0.0)


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the meadow scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    require(p["extent"] > p["free_radius"] + 2.0, NAME, "extent must exceed free_radius + 2 m")
    require(p["ground_spacing"] > 0, NAME, "ground_spacing must be > 0")
    require(p["mowed_height"] < 0.2, NAME, "mowed_height must be < 0.2 m (the free band starts there)")
    rng = np.random.default_rng(seed)
    r = p["free_radius"]
    terrain = meadow_terrain(rng, p["relief"], [(0.0, 0.0, r + 1.0, 4.0)])
    e = (-p["extent"], p["extent"])

    def bush_keep(x, y):
        return np.hypot(x, y) > r + BUSH_REACH

    cover = meadow_cover(
        rng,
        terrain,
        e,
        e,
        None,
        p["tufts_per_m2"],
        p["blades_per_tuft"],
        p["weeds_per_m2"],
        p["bushes_per_100m2"],
        bush_keep=bush_keep,
    )
    cover = mow(cover, 0.0, 0.0, r + 0.6, terrain, p["mowed_height"])
    ground = heightfield_points(rng, terrain, e, e, p["ground_spacing"], 0.01)
    return finish(NAME, DESCRIPTION, seed, p, stack([ground, cover]))
