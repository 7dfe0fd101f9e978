"""``wall``: the degenerate case, one long straight wall on flat ground.

A free-standing wall (both faces and its top) runs along x, longer than twice
a VLP-16's 100 m range, so from anywhere near the middle a scan sees a plane
(the wall) and another plane (the ground) and nothing that fixes the position
along the wall: translation along x is unobservable.
"""

from __future__ import annotations

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.geometry import Heightfield, heightfield_points, rectangle, stack
from lf3pm.scenes.scene import Scene, check_seed, finish, require, resolve_params

NAME = "wall"
DESCRIPTION = (
    "Degenerate: one straight wall 240 m long, 3 m high, 4 m from the origin, on flat "
    "ground 240 x 35 m (translation along the wall unobservable); wall 5 cm, ground 10 cm; "
    "~1.4 M points by default."
)
DEFAULTS = {
    "length": 240.0,  # m, along x, centred on the origin
    "height": 3.0,  # m
    "thickness": 0.3,  # m
    "distance": 4.0,  # m from the origin to the wall's near face (at y = distance)
    "ground_front": 25.0,  # m of ground on the origin's side (y from -ground_front)
    "ground_back": 6.0,  # m of ground behind the wall
    "wall_spacing": 0.05,  # m
    "ground_spacing": 0.10,  # m
    "jitter": 0.0025,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 2.5,  # m
}


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the wall scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    require(p["length"] > 0 and p["height"] > 0, NAME, "length and height must be > 0")
    require(p["wall_spacing"] > 0 and p["ground_spacing"] > 0, NAME, "spacings must be > 0")
    require(p["ground_front"] > p["distance"], NAME, "ground_front must exceed distance")
    rng = np.random.default_rng(seed)
    half, d, t, h = p["length"] / 2, p["distance"], p["thickness"], p["height"]
    ex, ey, ez = np.eye(3)
    s, j = p["wall_spacing"], p["jitter"]
    parts = [
        rectangle(rng, (-half, d, 0.0), ex, ez, 2 * half, h, s, j),  # near face
        rectangle(rng, (-half, d + t, 0.0), ex, ez, 2 * half, h, s, j),  # far face
        rectangle(rng, (-half, d, h), ex, ey, 2 * half, t, s, j),  # top
    ]
    if t > 0:
        parts += [rectangle(rng, (x, d, 0.0), ey, ez, t, h, s, j) for x in (-half, half)]

    def off_wall(x, y):
        return (y < d) | (y > d + t)

    parts.append(
        heightfield_points(
            rng,
            Heightfield.flat(),
            (-half, half),
            (-p["ground_front"], d + t + p["ground_back"]),
            p["ground_spacing"],
            j,
            keep=off_wall,
        )
    )
    return finish(NAME, DESCRIPTION, seed, p, stack(parts))
