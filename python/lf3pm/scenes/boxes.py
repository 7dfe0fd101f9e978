"""``boxes``: a lab room with boxes of several sizes on the floor.

Like the paper's real-world test: a closed room (walls, floor, ceiling, a
recessed door) with cardboard-box-like obstacles of five sizes, some stacked,
turned at random, kept clear of the reference pose. The room spans x from
-``room_length`` / 3 to 2 ``room_length`` / 3 and y symmetric about 0.
"""

from __future__ import annotations

import math

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.buildings import Opening, wall
from lf3pm.scenes.geometry import box, rectangle, stack
from lf3pm.scenes.scene import Scene, Zone, check_seed, finish, require, resolve_params

NAME = "boxes"
DESCRIPTION = (
    "Lab room 12 x 8 x 3 m (walls, floor, ceiling, a door) with 12 boxes of five sizes "
    "(0.3-1.2 m, some stacked); surfaces 5 cm; ~0.14 M points by default."
)
DEFAULTS = {
    "room_length": 12.0,  # m, along x
    "room_width": 8.0,  # m, along y
    "room_height": 3.0,  # m
    "boxes": 12,
    "stack_fraction": 0.25,  # share of the boxes with a smaller box on top
    "ceiling": True,
    "spacing": 0.05,  # m
    "jitter": 0.0025,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 1.2,  # m
}

#: Box sizes (length, width, height), m: a shoebox, moving boxes, a crate, a tall box.
_SIZES = np.array([[0.4, 0.3, 0.3], [0.6, 0.4, 0.4], [0.8, 0.6, 0.6], [1.2, 0.8, 0.8], [0.5, 0.5, 1.2]])


def zones(params: dict) -> dict:
    """The study's zones: strips 1.5 m deep along the room's two short walls, 0.7 m
    clear of the walls (boxes may stand in them: a study keeps the traversable cells)."""
    L, W = params["room_length"], params["room_width"]
    x0, x1, y0, y1 = -L / 3, 2 * L / 3, -W / 2, W / 2
    return {"start": Zone(x0 + 0.7, y0 + 0.7, x0 + 2.2, y1 - 0.7), "goal": Zone(x1 - 2.2, y0 + 0.7, x1 - 0.7, y1 - 0.7)}


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the boxes scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    L, W, H = p["room_length"], p["room_width"], p["room_height"]
    require(L >= 3.0 and W >= 3.0, NAME, "the room must be at least 3 x 3 m")
    require(H > 2.5, NAME, "room_height must exceed 2.5 m (the free band)")
    require(p["spacing"] > 0, NAME, "spacing must be > 0")
    require(W / 2 > p["free_radius"] and L / 3 > p["free_radius"], NAME, "free_radius does not fit in the room")
    rng = np.random.default_rng(seed)
    s, j = p["spacing"], p["jitter"]
    x0, x1, y0, y1 = -L / 3, 2 * L / 3, -W / 2, W / 2
    # Clockwise, so that wall() recesses (to its left) go away from the room.
    corners = [(x0, y0), (x0, y1), (x1, y1), (x1, y0)]
    parts = []
    for side in range(4):
        start, end = corners[side], corners[(side + 1) % 4]
        openings = []
        if side == 2:  # a closed door, 5 cm into the wall
            u0 = rng.uniform(0.5, L - 1.5)
            openings = [Opening(u0, 0.0, u0 + 1.0, 2.1, 0.05)]
        parts.append(wall(rng, start, end, 0.0, H, s, j, openings))
    ex, ey = np.eye(3)[:2]
    parts.append(rectangle(rng, (x0, y0, 0.0), ex, ey, L, W, s, j))
    if p["ceiling"]:
        parts.append(rectangle(rng, (x0, y0, H), ex, ey, L, W, s, j))

    placed = []  # (x, y, radius)
    for _ in range(p["boxes"]):
        size = _SIZES[rng.integers(len(_SIZES))] * rng.uniform(0.9, 1.1)
        radius = 0.5 * math.hypot(size[0], size[1])
        for _attempt in range(200):
            x = rng.uniform(x0 + radius + 0.2, x1 - radius - 0.2)
            y = rng.uniform(y0 + radius + 0.2, y1 - radius - 0.2)
            clear_of_pose = math.hypot(x, y) > p["free_radius"] + radius + 0.1
            clear_of_boxes = all(math.hypot(x - bx, y - by) > radius + br + 0.4 for bx, by, br in placed)
            if clear_of_pose and clear_of_boxes:
                break
        else:
            require(False, NAME, f"cannot place {p['boxes']} boxes in the room; use fewer boxes or a larger room")
        yaw = rng.uniform(0.0, math.pi)
        placed.append((x, y, radius))
        parts.append(box(rng, (x, y, 0.0), size, yaw, s, j))
        if size[2] < 1.0 and rng.random() < p["stack_fraction"]:
            top = size * rng.uniform(0.5, 0.8)
            top[2] = min(top[2], H - size[2] - 0.3)
            parts.append(box(rng, (x, y, size[2]), top, yaw + rng.uniform(-0.3, 0.3), s, j))
    return finish(NAME, DESCRIPTION, seed, p, stack(parts), zones=zones(p))
