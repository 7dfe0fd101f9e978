"""``gobi``: a large stony desert with a small town and a distant warehouse.

The terrain undulates smoothly (wavelengths 25-150 m, amplitude ``relief``)
with 5 cm ripples over 1.5-6 m, and is level on two pads: the town's around
the origin and the warehouse's. The town is a ring of flat-roofed and
pitched-roof buildings around a square (the reference pose stands in it);
the warehouse, a large box with roller doors, stands ``warehouse_distance``
metres east. Hundreds of stones (noisy ellipsoids lying flat, 5 cm to over
1 m) are strewn over the ground, and around part of them grow weeds, grass
tufts and bushes. The map spans x from -``west`` to ``length`` - ``west``
and y from -``width`` / 2 to ``width`` / 2.
"""

from __future__ import annotations

import math

import numpy as np

from lf3pm import libm
from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.buildings import Opening, flat_building, house
from lf3pm.scenes.geometry import Heightfield, heightfield_points, stack, stone
from lf3pm.scenes.scene import Scene, check_seed, finish, require, resolve_params
from lf3pm.scenes.vegetation import bushes, grass_tufts, weeds

NAME = "gobi"
DESCRIPTION = (
    "Gobi desert 220 x 120 m, uneven (+-1.5 m), a town of 6 buildings around the origin, "
    "a warehouse 110 m east, 400 stones, weeds and bushes by some stones; ground 12 cm, "
    "walls and stones 4-5 cm; ~3.2 M points by default."
)
DEFAULTS = {
    "length": 220.0,  # m along x
    "width": 120.0,  # m along y
    "west": 60.0,  # m of desert west of the origin
    "relief": 1.5,  # m, amplitude of the terrain
    "buildings": 6,  # 1..8 in the town
    "town_radius": 40.0,  # m, level pad of the town
    "warehouse_distance": 110.0,  # m from the origin to the warehouse's centre
    "stones": 400,
    "vegetated_fraction": 0.35,  # share of the stones with plants around them
    "ground_spacing": 0.12,  # m
    "wall_spacing": 0.05,  # m
    "roof_spacing": 0.10,  # m, flat roofs (invisible from the ground)
    "stone_spacing": 0.04,  # m
    "jitter": 0.0025,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 3.0,  # m
}

#: Warehouse footprint and height (m).
#: A smaller desert (115 x 90 m, warehouse 60 m east, 4 buildings): the demo's
#: (experiments/gobi.py REDUCED) and the benefit study's gobi map.
REDUCED = {
    "length": 115.0,
    "width": 90.0,
    "west": 25.0,
    "town_radius": 25.0,
    "warehouse_distance": 60.0,
    "buildings": 4,
    "stones": 150,
}
_WAREHOUSE = (40.0, 24.0, 9.0)


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the gobi scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    x_range = (-p["west"], p["length"] - p["west"])
    y_range = (-p["width"] / 2, p["width"] / 2)
    wl, wd, wh = _WAREHOUSE
    reach = math.hypot(wl, wd) / 2
    require(1 <= p["buildings"] <= 8, NAME, f"buildings must be 1..8, got {p['buildings']}")
    require(p["town_radius"] >= 25.0, NAME, "town_radius must be >= 25 m")
    require(
        p["warehouse_distance"] >= p["town_radius"] + reach + 10.0,
        NAME,
        "warehouse_distance is too small: the warehouse would stand in the town",
    )
    require(
        x_range[1] >= p["warehouse_distance"] + reach + 5.0 and y_range[1] >= reach + 20.0,
        NAME,
        "the desert is too small for the warehouse (raise length or width)",
    )
    require(
        p["west"] >= p["town_radius"] and y_range[1] >= p["town_radius"],
        NAME,
        "the desert is too small for the town (raise west or width)",
    )
    require(
        min(p["ground_spacing"], p["wall_spacing"], p["roof_spacing"], p["stone_spacing"]) > 0,
        NAME,
        "spacings must be > 0",
    )
    rng = np.random.default_rng(seed)
    s, j = p["wall_spacing"], p["jitter"]

    # Warehouse position first: the terrain gets a pad there.
    wx = p["warehouse_distance"]
    wy = rng.uniform(-0.5, 0.5) * max(0.0, y_range[1] - reach - 20.0)
    terrain = Heightfield.random(rng, p["relief"], (25.0, 150.0)).plus(Heightfield.random(rng, 0.05, (1.5, 6.0)))
    terrain = terrain.with_pad(0.0, 0.0, p["town_radius"], 25.0)
    terrain = terrain.with_pad(wx, wy, reach + 5.0, 20.0).shifted_to_zero_at(0.0, 0.0)
    warehouse_level = float(terrain(np.array([wx]), np.array([wy]))[0])

    obstacles = [(wx, wy, reach)]  # (x, y, radius) kept clear of stones
    parts = []
    # The town: buildings in a ring around a square, their fronts facing it, each
    # in its own sector of the ring.
    sector = 2.0 * math.pi / p["buildings"]
    turn = rng.uniform(0.0, 2.0 * math.pi)
    for i in range(p["buildings"]):
        width, depth = rng.uniform(7.0, 13.0), rng.uniform(6.0, 9.0)
        radius = math.hypot(width, depth) / 2
        for _attempt in range(2000):
            dist = rng.uniform(p["free_radius"] + radius + 4.0, p["town_radius"] - radius - 2.0)
            angle = turn + (i + rng.uniform(-0.3, 0.3)) * sector
            x, y = dist * math.cos(angle), dist * math.sin(angle)
            if all(math.hypot(x - ox, y - oy) > radius + orad + 4.0 for ox, oy, orad in obstacles):
                break
        else:
            require(
                False, NAME, f"cannot place {p['buildings']} buildings in the town; use fewer or a larger town_radius"
            )
        obstacles.append((x, y, radius))
        yaw = angle - math.pi / 2 + rng.normal(0.0, 0.15)
        storeys = int(rng.integers(1, 3))
        if rng.random() < 0.3:
            parts.append(
                house(
                    rng,
                    (x, y, 0.0),
                    yaw,
                    width,
                    depth,
                    storeys,
                    math.radians(rng.uniform(20.0, 30.0)),
                    s,
                    j,
                    recess_fraction=0.3,
                )
            )
        else:
            parts.append(
                flat_building(
                    rng,
                    (x, y, 0.0),
                    yaw,
                    width,
                    depth,
                    storeys * 2.8 + 0.6,
                    s,
                    j,
                    storeys=storeys,
                    recess_fraction=0.3,
                    roof_spacing=p["roof_spacing"],
                )
            )
    # The warehouse: two closed roller doors (recessed 20 cm) and a door, windows high up.
    doors = [
        Opening(6.0, 0.0, 10.5, 5.0, 0.2),
        Opening(wl - 10.5, 0.0, wl - 6.0, 5.0, 0.2),
        Opening(wl / 2 - 0.5, 0.0, wl / 2 + 0.5, 2.1, 0.0),
    ]
    parts.append(
        flat_building(
            rng,
            (wx, wy, warehouse_level),
            math.atan2(wy, wx) - math.pi / 2,
            wl,
            wd,
            wh,
            s,
            j,
            storeys=1,
            recess_fraction=0.0,
            roof_spacing=p["roof_spacing"],
            doors=doors,
            window_pitch=6.0,
            window_sill=6.0,
        )
    )
    parts.append(stones_and_plants(rng, terrain, p, x_range, y_range, obstacles))
    parts.append(heightfield_points(rng, terrain, x_range, y_range, p["ground_spacing"], 0.01))
    return finish(NAME, DESCRIPTION, seed, p, stack(parts))


def stones_and_plants(
    rng: np.random.Generator, terrain: Heightfield, p: dict, x_range, y_range, obstacles
) -> np.ndarray:
    """The stones, strewn uniformly off the buildings and the free radius, partly buried,
    and the plants around a fraction of them."""
    count = p["stones"]
    size = np.clip(libm.exp(rng.normal(math.log(0.18), 0.6, count)), 0.05, 1.3)
    x = rng.uniform(*x_range, count)
    y = rng.uniform(*y_range, count)
    clear = np.hypot(x, y) > p["free_radius"] + size + 2.5
    for ox, oy, orad in obstacles:
        clear &= np.hypot(x - ox, y - oy) > orad + size + 1.5
    x, y, size = x[clear], y[clear], size[clear]
    parts = []
    for sx, sy, r in zip(x, y, size):
        radii = r * np.array([rng.uniform(0.9, 1.3), rng.uniform(0.6, 1.0), rng.uniform(0.35, 0.7)])
        ground = float(terrain(np.array([sx]), np.array([sy]))[0])
        centre = (sx, sy, ground + radii[2] * rng.uniform(-0.2, 0.4))
        parts.append(stone(rng, centre, radii, p["stone_spacing"], yaw=rng.uniform(0.0, math.pi)))
    points = stack(parts)
    points = points[points[:, 2] > terrain(points[:, 0], points[:, 1]) - 0.02]

    # Plants around a fraction of the stones (their shelter).
    planted = rng.random(len(x)) < p["vegetated_fraction"]
    px, py, pr = x[planted], y[planted], size[planted]

    def around(n_per, lo, hi):
        counts = rng.poisson(n_per, len(px))
        k = np.repeat(np.arange(len(px)), counts)
        dist = pr[k] + rng.uniform(lo, hi, k.size)
        angle = rng.uniform(0.0, 2.0 * math.pi, k.size)
        return np.column_stack([px[k] + dist * np.cos(angle), py[k] + dist * np.sin(angle)])

    tufts = around(6.0, 0.05, 1.2)
    weed_xy = around(2.5, 0.05, 0.9)
    bush_xy = around(0.3, 0.6, 1.2)
    return stack(
        [
            points,
            grass_tufts(rng, terrain, tufts, blades_per_tuft=7.0, height=(0.05, 0.25)),
            weeds(rng, terrain, weed_xy),
            bushes(rng, terrain, bush_xy, radius=(0.3, 0.7)),
        ]
    )
