"""``forest``: trunks under a canopy, for flights.

Gently undulating ground, ``length`` metres along x and ``width`` across, carries
trees at seeded positions (on average ``trees_per_100m2``, their trunks at least
``TRUNK_GAP`` apart): each a vertical cylinder of radius 0.12-0.35 m (bark: 1 cm
jitter) rising to the centre of its crown, an ellipsoid of scattered points
(``crown_density`` per m^2 of its surface, in its outer shell) ``canopy_height``
metres up, give or take 15 %. The crowns overlap into a noisy layer whose underside
stays ``CANOPY_FLOOR`` (4 m) or more above the clearings' level, so between the
ground and the canopy only trunks stand: the flight space. Under the canopy a scan
sees the ground (z, roll, pitch), the trunks (vertical cylinders: x, y and yaw) and
the scattering crowns. The start volume hovers near the west edge, the goal near
the east edge, each over a level clearing (as is the origin) that no trunk enters.
"""

from __future__ import annotations

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.geometry import (
    Heightfield,
    cylinder,
    ellipsoid_area,
    heightfield_points,
    random_unit_vectors,
    stack,
)
from lf3pm.scenes.scene import VOLUME_CLEARANCE, Scene, Volume, check_seed, finish, require, resolve_params

NAME = "forest"
DESCRIPTION = (
    "Flight under a canopy: 50 x 30 m of undulating ground with trunks (0.12-0.35 m, 2 m "
    "apart or more) under a noisy layer of crowns from 4 m up; start and goal volumes "
    "at the west and east edges; bark 10 cm, ground 20 cm; ~0.24 M points by default."
)
DEFAULTS = {
    "length": 50.0,  # m along x, centred on the origin
    "width": 30.0,  # m along y, centred on the origin
    "trees_per_100m2": 8.0,  # mean density (fewer where the gap or the clearings forbid)
    "canopy_height": 7.5,  # m, mean height of the crowns' centres (each 0.85-1.15 times)
    "crown_radius": 2.8,  # m, mean horizontal semi-axis (vertical: half of it)
    "crown_density": 25.0,  # points per m^2 of crown surface
    "relief": 0.3,  # m, amplitude of the ground's undulation
    "trunk_spacing": 0.10,  # m, around and up a trunk
    "ground_spacing": 0.20,  # m
    "sensor_height": 1.0,  # m
    "free_radius": 1.5,  # m
}

#: Trunk radii (m), drawn uniformly.
TRUNK_RADIUS = (0.12, 0.35)
#: Least distance (m) between two trunks' axes.
TRUNK_GAP = 2.0
#: Jitter (m, 1-sigma) of bark and ground samples along the surface (a third across it).
NATURAL_JITTER = 0.01
#: Lowest allowed underside of a crown (m above the clearings).
CANOPY_FLOOR = 4.0


def volumes(params: dict) -> dict:
    """The flight's volumes (``xmin, ymin, zmin, xmax, ymax, zmax``): ``start`` 2-5 m in from
    the west edge, ``goal`` 2-5 m in from the east edge, both within 2 m of the x axis and
    1-2.5 m above the (level) ground there."""
    half = params["length"] / 2
    return {
        "start": (-half + 2.0, -2.0, 1.0, -half + 5.0, 2.0, 2.5),
        "goal": (half - 5.0, -2.0, 1.0, half - 2.0, 2.0, 2.5),
    }


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the forest scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    half_x, half_y = p["length"] / 2, p["width"] / 2
    require(p["length"] >= 20.0 and p["width"] >= 10.0, NAME, "the forest must be >= 20 m long and >= 10 m wide")
    require(p["trees_per_100m2"] <= 20.0, NAME, "trees_per_100m2 must be <= 20 (trunks 2 m apart)")
    require(p["relief"] <= 1.0, NAME, "relief must be <= 1 m")
    require(p["crown_radius"] >= 0.5, NAME, "crown_radius must be >= 0.5 m")
    lowest = p["canopy_height"] * 0.85 - 0.5 * p["crown_radius"] * 1.2 * 1.2
    require(
        lowest >= CANOPY_FLOOR,
        NAME,
        f"the crowns would reach down to {lowest:.1f} m: raise canopy_height or lower crown_radius",
    )
    require(p["trunk_spacing"] > 0 and p["ground_spacing"] > 0, NAME, "spacings must be > 0")
    rng = np.random.default_rng(seed)
    boxes = {key: Volume(*box) for key, box in volumes(p).items()}
    # Level clearings under the volumes and at the origin, blending into the undulation.
    terrain = Heightfield.random(rng, p["relief"], (8.0, 30.0), waves=8)
    for key in ("start", "goal"):
        cx, cy, _ = boxes[key].centre
        terrain = terrain.with_pad(cx, cy, 3.5, 4.0, level=0.0)
    terrain = terrain.with_pad(0.0, 0.0, p["free_radius"] + 0.5, 3.0, level=0.0)

    trees = _trees(rng, p, boxes)
    parts = []
    for x, y, radius, crown_z, crown in trees:
        base_z = float(terrain(np.array([x]), np.array([y]))[0]) - 0.1
        parts.append(cylinder(rng, (x, y, base_z), radius, crown_z - base_z, p["trunk_spacing"], NATURAL_JITTER))
        parts.append(_crown(rng, (x, y, crown_z), crown, p["crown_density"]))

    def open_ground(gx, gy):
        keep = np.ones(np.shape(gx), bool)
        for x, y, radius, _, _ in trees:
            keep &= np.hypot(gx - x, gy - y) > radius
        return keep

    parts.append(
        heightfield_points(
            rng, terrain, (-half_x, half_x), (-half_y, half_y), p["ground_spacing"], NATURAL_JITTER, keep=open_ground
        )
    )
    return finish(NAME, DESCRIPTION, seed, p, stack(parts), volumes=volumes(p))


def _trees(rng: np.random.Generator, p: dict, boxes: dict) -> list:
    """(x, y, trunk radius, crown centre height, crown semi-axes) of each tree: positions
    drawn uniformly (a Poisson number around the mean density) and kept when at least
    TRUNK_GAP from every kept trunk, clear of the volumes by VOLUME_CLEARANCE and of the
    reference pose's free radius, with a margin."""
    half_x, half_y = p["length"] / 2, p["width"] / 2
    count = rng.poisson(p["trees_per_100m2"] * p["length"] * p["width"] / 100.0)
    xy = np.column_stack(
        [rng.uniform(-half_x + 0.5, half_x - 0.5, count), rng.uniform(-half_y + 0.5, half_y - 0.5, count)]
    )
    radius = rng.uniform(*TRUNK_RADIUS, count)
    height = p["canopy_height"] * rng.uniform(0.85, 1.15, count)
    crown = p["crown_radius"] * rng.uniform(0.8, 1.2, count)
    vertical = 0.5 * crown * rng.uniform(0.8, 1.2, count)
    trees = []
    for k in range(count):
        x, y, r = xy[k, 0], xy[k, 1], radius[k]
        # A trunk spans every height: its axis's horizontal distance from each volume.
        if any(box.distance([(x, y, box.centre[2])])[0] < r + VOLUME_CLEARANCE + 0.1 for box in boxes.values()):
            continue
        if np.hypot(x, y) < r + p["free_radius"] + 0.1:
            continue
        if any(np.hypot(x - tx, y - ty) < TRUNK_GAP for tx, ty, *_ in trees):
            continue
        trees.append((x, y, r, height[k], (crown[k], crown[k], vertical[k])))
    return trees


def _crown(rng: np.random.Generator, centre, radii, density: float) -> np.ndarray:
    """Points scattered in the outer shell of an ellipsoidal crown (between 0.74 and 1
    times its semi-axes in every direction), ``density`` per m^2 of its surface."""
    radii = np.asarray(radii, dtype=float)
    count = max(10, int(round(density * ellipsoid_area(*radii))))
    depth = np.sqrt(rng.uniform(0.55, 1.0, count))
    return np.asarray(centre, dtype=float) + random_unit_vectors(rng, count) * radii * depth[:, None]
