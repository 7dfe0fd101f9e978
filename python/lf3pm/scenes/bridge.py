"""``bridge``: the underside of a girder bridge over open water, for flights.

A canal ``span`` metres wide runs along y between two vertical quay walls (at
x = -+span/2, facing the water, ``river_width`` long); its water, from the quay
walls' foot at z = 0 up, returns nothing, so the map holds no point on it. A
bridge crosses it along x at the banks' level: a deck slab ``deck_width`` wide
whose underside lies ``deck_height`` above the water, carried by ``girders``
concrete beams (0.5 m wide, ``girder_depth`` deep) that rest on the quay walls
and on the piers, tied by diaphragms (cross-beams between the girders) at the
ends, over the piers and about every ``diaphragm_pitch`` metres. ``spans`` - 1
piers stand in the water, each two round columns under a cap beam; parapets line
the deck, and the banks beyond the quay walls are flat ground at the deck's top.
Under the deck a scan sees only the deck, the girders, the diaphragms, the piers
and the quay walls: nothing below it and nothing to either side but the quay
walls. The start volume hovers under the deck at its west end, the goal under its
east end.
"""

from __future__ import annotations

import numpy as np

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.scenes.geometry import Heightfield, box, cylinder, heightfield_points, rectangle, stack
from lf3pm.scenes.scene import Scene, check_seed, finish, require, resolve_params

NAME = "bridge"
DESCRIPTION = (
    "Flight under a bridge: a 60 m girder bridge (deck, 4 girders, diaphragms, 2 piers) "
    "over water that returns nothing, between quay walls; start and goal volumes under "
    "its two ends; walls 10 cm, ground 20 cm; ~0.27 M points by default."
)
DEFAULTS = {
    "span": 60.0,  # m, quay wall to quay wall along x (the bridge's length), centred on the origin
    "spans": 3,  # spans of the bridge (spans - 1 piers)
    "deck_width": 12.0,  # m along y
    "deck_height": 8.0,  # m, water to the deck's underside
    "deck_thickness": 0.3,  # m
    "girders": 4,
    "girder_depth": 1.2,  # m below the deck
    "diaphragm_pitch": 10.0,  # m, largest spacing of the diaphragms along a span
    "river_width": 30.0,  # m, the quay walls' length along y (the map's width)
    "bank_depth": 8.0,  # m of bank beyond each quay wall
    "wall_spacing": 0.10,  # m
    "ground_spacing": 0.20,  # m, the deck's top and the banks
    "jitter": 0.0025,  # m
    "sensor_height": 1.0,  # m above the water
    "free_radius": 2.0,  # m
}

#: Girder width (m); the outer girders' axes lie this far inside the deck's edges (m).
GIRDER_WIDTH = 0.5
GIRDER_EDGE = 1.5
#: Diaphragm thickness along x and depth below the deck (m).
DIAPHRAGM = (0.2, 0.8)
#: Pier columns' radius (m); cap beam length along x and depth (m).
COLUMN_RADIUS = 0.6
CAP = (1.6, 1.0)
#: Parapet height and thickness (m).
PARAPET = (1.0, 0.3)


def volumes(params: dict) -> dict:
    """The flight's volumes (``xmin, ymin, zmin, xmax, ymax, zmax``): ``start`` under the
    deck 2-5 m from the west quay wall, ``goal`` 2-5 m from the east one, both within 2 m
    of the bridge's axis and 2-5 m above the water."""
    half = params["span"] / 2
    return {
        "start": (-half + 2.0, -2.0, 2.0, -half + 5.0, 2.0, 5.0),
        "goal": (half - 5.0, -2.0, 2.0, half - 2.0, 2.0, 5.0),
    }


def piers(params: dict) -> list:
    """(x of the pier, ((x, y) of each column)) for every pier."""
    half, spans = params["span"] / 2, params["spans"]
    offset = params["deck_width"] / 4
    xs = [-half + k * params["span"] / spans for k in range(1, spans)]
    return [(x, ((x, -offset), (x, offset))) for x in xs]


def build(seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds the bridge scene (see the module docstring); ``params`` override DEFAULTS."""
    seed = check_seed(seed)
    p = resolve_params(NAME, DEFAULTS, params)
    half, dw, dh, dt = p["span"] / 2, p["deck_width"], p["deck_height"], p["deck_thickness"]
    bottom = dh - p["girder_depth"]  # the girders' underside
    top = dh + dt  # the deck's top, and the banks'
    require(p["span"] >= 20.0, NAME, "span must be >= 20 m")
    require(p["spans"] >= 1 and p["span"] / p["spans"] >= 12.0, NAME, "spans must be >= 1 and each >= 12 m long")
    require(dw >= 6.0 and p["river_width"] >= dw + 4.0, NAME, "deck_width must be >= 6 m and the river 4 m wider")
    require(p["girders"] >= 2, NAME, "girders must be >= 2")
    require(
        0.5 <= p["girder_depth"] <= 3.0 and 0.1 <= dt <= 1.0,
        NAME,
        "girder_depth must be 0.5-3 m and deck_thickness 0.1-1 m",
    )
    require(bottom >= 6.0, NAME, "deck_height must leave the girders' underside >= 6 m above the water")
    require(p["diaphragm_pitch"] >= 3.0, NAME, "diaphragm_pitch must be >= 3 m")
    require(p["bank_depth"] >= 2.0, NAME, "bank_depth must be >= 2 m")
    require(p["wall_spacing"] > 0 and p["ground_spacing"] > 0, NAME, "spacings must be > 0")
    rng = np.random.default_rng(seed)
    s, j = p["wall_spacing"], p["jitter"]
    ex, ey, ez = np.eye(3)
    hr = p["river_width"] / 2

    pitch = (dw - 2 * GIRDER_EDGE) / (p["girders"] - 1)
    girder_y = [-dw / 2 + GIRDER_EDGE + k * pitch for k in range(p["girders"])]
    gw = GIRDER_WIDTH
    parts = []
    # The deck: its underside between the girders, its edges, its top at the banks'
    # spacing (only a flight over it sees it) and parapets.
    holes = [(0.0, y - gw / 2 + dw / 2, 2 * half, y + gw / 2 + dw / 2) for y in girder_y]
    parts.append(rectangle(rng, (-half, -dw / 2, dh), ex, ey, 2 * half, dw, s, j, holes=holes))
    for y in (-dw / 2, dw / 2):
        parts.append(rectangle(rng, (-half, y, dh), ex, ez, 2 * half, dt, s, j))
        inner = y - np.sign(y) * PARAPET[1] / 2
        parts.append(box(rng, (0.0, inner, top), (2 * half, PARAPET[1], PARAPET[0]), 0.0, s, j))
    # The girders: two sides and the underside, quay wall to quay wall.
    for y in girder_y:
        parts.append(box(rng, (0.0, y, bottom), (2 * half, gw, p["girder_depth"]), 0.0, s, j, top=False, bottom=True))
    parts += _diaphragms(rng, p, girder_y, pitch)
    # The piers: two columns from the water up to a cap beam under the girders.
    for x, columns in piers(p):
        cap_z = bottom - CAP[1]
        for cx, cy in columns:
            parts.append(cylinder(rng, (cx, cy, 0.0), COLUMN_RADIUS, cap_z, s, j))
        parts.append(box(rng, (x, 0.0, cap_z), (CAP[0], dw - 1.0, CAP[1]), 0.0, s, j, top=False, bottom=True))
    # The quay walls, water to bank, but where the deck's end meets them.
    for x in (-half, half):
        parts.append(
            rectangle(
                rng,
                (x, -hr, 0.0),
                ey,
                ez,
                2 * hr,
                top,
                s,
                j,
                holes=[(hr - dw / 2, dh, hr + dw / 2, top + 1.0)],
            )
        )
    # The banks, level with the deck's top; the water between them returns nothing.
    for x0, x1 in ((-half - p["bank_depth"], -half), (half, half + p["bank_depth"])):
        bank = heightfield_points(rng, Heightfield.flat(), (x0, x1), (-hr, hr), p["ground_spacing"], j)
        parts.append(bank + np.array([0.0, 0.0, top]))
    parts.append(
        heightfield_points(rng, Heightfield.flat(), (-half, half), (-dw / 2, dw / 2), p["ground_spacing"], j)
        + np.array([0.0, 0.0, top])
    )
    return finish(NAME, DESCRIPTION, seed, p, stack(parts), volumes=volumes(p))


def _diaphragms(rng: np.random.Generator, p: dict, girder_y: list, pitch: float) -> list:
    """Diaphragms between each pair of neighbouring girders: 0.5 m in from each end,
    over each pier and evenly between, at most ``diaphragm_pitch`` apart."""
    half, span = p["span"] / 2, p["span"] / p["spans"]
    stations = [-half + 0.5, half - 0.5]
    per_span = int(np.ceil(span / p["diaphragm_pitch"]))
    for k in range(p["spans"]):
        x0 = -half + k * span
        stations += [x0 + i * span / per_span for i in range(1, per_span)]
        if k:
            stations.append(x0)
    gap = pitch - GIRDER_WIDTH
    z = p["deck_height"] - DIAPHRAGM[1]
    return [
        box(
            rng,
            (x, (a + b) / 2, z),
            (DIAPHRAGM[0], gap, DIAPHRAGM[1]),
            0.0,
            p["wall_spacing"],
            p["jitter"],
            top=False,
            bottom=True,
        )
        for x in sorted(stations)
        for a, b in zip(girder_y[:-1], girder_y[1:])
    ]
