"""Buildings: walls with door and window openings, pitched and flat roofs.

A building is sampled in its own frame (footprint centred on the origin, front
wall at y = -depth / 2 facing -y, base at z = 0) and then placed with a yaw and
an offset. Openings are holes in the wall samples; a recessed opening also gets
its reveals (sill, lintel, jambs) and a back plane (the pane or the door leaf)
``recess`` metres behind the wall face.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lf3pm.scenes.geometry import JITTER, place, rectangle, stack

#: Floor-to-floor height of a storey (m).
STOREY = 2.8


@dataclass(frozen=True)
class Opening:
    """A door or window in a wall: along-wall span [u0, u1], height span [v0, v1]
    above the wall's base (m); ``recess`` > 0 sets its back plane that far behind
    the face, 0 leaves a plain hole."""

    u0: float
    v0: float
    u1: float
    v1: float
    recess: float = 0.0


def footprint_sides(width: float, depth: float):
    """The four walls of a width x depth footprint centred on the origin, counter-
    clockwise from the front (y = -depth/2): (side, start, end, length)."""
    hw, hd = width / 2, depth / 2
    corners = [(-hw, -hd), (hw, -hd), (hw, hd), (-hw, hd)]
    for side in range(4):
        yield side, corners[side], corners[(side + 1) % 4], width if side % 2 == 0 else depth


def wall(
    rng: np.random.Generator,
    start,
    end,
    base_z: float,
    height: float,
    spacing: float,
    jitter: float = JITTER,
    openings=(),
    top=None,
) -> np.ndarray:
    """Samples a vertical wall from ``start`` to ``end`` (x, y), ``height`` above ``base_z``.

    Recesses go to the left of the direction of travel (into a building whose
    footprint runs counter-clockwise). ``top(u) -> height`` trims the upper edge
    (a gable).
    """
    start = np.asarray(start, dtype=float)
    delta = np.asarray(end, dtype=float) - start
    length = float(np.hypot(*delta))
    u = np.array([delta[0] / length, delta[1] / length, 0.0])
    ez = np.array([0.0, 0.0, 1.0])
    inward = np.array([-u[1], u[0], 0.0])
    origin = np.array([start[0], start[1], base_z])
    keep = None if top is None else (lambda a, b: b < top(a))
    parts = [
        rectangle(
            rng,
            origin,
            u,
            ez,
            length,
            height,
            spacing,
            jitter,
            holes=[(o.u0, o.v0, o.u1, o.v1) for o in openings],
            keep=keep,
        )
    ]
    for o in openings:
        if o.recess <= 0:
            continue
        w, h, d = o.u1 - o.u0, o.v1 - o.v0, o.recess
        corner = origin + o.u0 * u + o.v0 * ez
        parts += [
            rectangle(rng, corner, u, inward, w, d, spacing, jitter),  # sill
            rectangle(rng, corner + h * ez, u, inward, w, d, spacing, jitter),  # lintel
            rectangle(rng, corner, inward, ez, d, h, spacing, jitter),  # jamb
            rectangle(rng, corner + w * u, inward, ez, d, h, spacing, jitter),  # jamb
            rectangle(rng, corner + d * inward, u, ez, w, h, spacing, jitter),  # pane / leaf
        ]
    return stack(parts)


def facade_openings(
    rng: np.random.Generator,
    length: float,
    storeys: int,
    door: bool,
    recess_fraction: float,
    window_pitch: float = 2.6,
    door_size=(1.0, 2.1),
    window_sill: float = 0.9,
    door_at: float | None = None,
) -> list[Opening]:
    """Doors and windows for a wall ``length`` long: one door on the ground floor if
    asked (its left edge ``door_at`` metres along the wall, else at random),
    windows about every ``window_pitch`` metres on each storey; a fraction
    ``recess_fraction`` of the windows is recessed 10-20 cm, the rest are holes."""
    openings = []
    door_span = None
    if door and length > door_size[0] + 1.0:
        u0 = rng.uniform(0.5, length - door_size[0] - 0.5) if door_at is None else door_at
        door_span = (u0 - 0.3, u0 + door_size[0] + 0.3)
        openings.append(Opening(u0, 0.0, u0 + door_size[0], door_size[1], 0.0))
    count = int((length - 0.8) // window_pitch)
    for storey in range(storeys):
        for i in range(count):
            width = rng.uniform(0.9, 1.4)
            height = rng.uniform(1.1, 1.4)
            centre = (i + 0.5) * length / count
            u0, u1 = centre - width / 2, centre + width / 2
            if storey == 0 and door_span and u1 > door_span[0] and u0 < door_span[1]:
                continue
            sill = window_sill + storey * STOREY
            recess = rng.uniform(0.1, 0.2) if rng.random() < recess_fraction else 0.0
            openings.append(Opening(u0, sill, u1, sill + height, recess))
    return openings


def house(
    rng: np.random.Generator,
    centre,
    yaw: float,
    width: float,
    depth: float,
    storeys: int,
    pitch: float,
    spacing: float,
    jitter: float = JITTER,
    recess_fraction: float = 0.5,
    eave_overhang: float = 0.4,
    gable_overhang: float = 0.3,
    door_x: float | None = None,
) -> np.ndarray:
    """Samples a house with a pitched roof: four walls with a door in the front
    wall (centred at local x = ``door_x``, else at random) and windows on every
    wall, gables on the two x ends, two roof planes with overhangs, the ridge
    along x. ``centre`` = (x, y, base z)."""
    eave = storeys * STOREY + 0.3
    rise = math.tan(pitch)
    ridge = eave + depth / 2 * rise
    hw, hd = width / 2, depth / 2
    parts = []
    for side, start, end, length in footprint_sides(width, depth):
        door_at = None if door_x is None else door_x - 0.5 + hw
        openings = facade_openings(
            rng, length, storeys, door=side == 0, recess_fraction=recess_fraction, door_at=door_at
        )
        if side % 2 == 0:
            parts.append(wall(rng, start, end, 0.0, eave, spacing, jitter, openings))
        else:

            def gable(u, d=depth):
                return eave + (d / 2 - np.abs(u - d / 2)) * rise

            parts.append(wall(rng, start, end, 0.0, ridge, spacing, jitter, openings, top=gable))
    ex = np.array([1.0, 0.0, 0.0])
    slope = (hd + eave_overhang) / math.cos(pitch)
    low = eave - eave_overhang * rise
    x0 = -hw - gable_overhang
    span = width + 2 * gable_overhang
    parts.append(
        rectangle(
            rng,
            (x0, -hd - eave_overhang, low),
            ex,
            (0.0, math.cos(pitch), math.sin(pitch)),
            span,
            slope,
            spacing,
            jitter,
        )
    )
    parts.append(
        rectangle(
            rng,
            (x0, hd + eave_overhang, low),
            ex,
            (0.0, -math.cos(pitch), math.sin(pitch)),
            span,
            slope,
            spacing,
            jitter,
        )
    )
    return place(stack(parts), yaw, centre)


def flat_building(
    rng: np.random.Generator,
    centre,
    yaw: float,
    width: float,
    depth: float,
    height: float,
    spacing: float,
    jitter: float = JITTER,
    storeys: int | None = None,
    recess_fraction: float = 0.5,
    roof_spacing: float | None = None,
    doors=None,
    window_pitch: float = 2.6,
    window_sill: float = 0.9,
) -> np.ndarray:
    """Samples a flat-roofed building: four walls of ``height`` with a door in the
    front wall (or the given front ``doors``, a list of Openings) and windows on
    every storey (see :func:`facade_openings`), and the roof at ``roof_spacing``
    (default ``spacing``)."""
    if storeys is None:
        storeys = max(1, int(height // STOREY))
    hw, hd = width / 2, depth / 2
    parts = []
    for side, start, end, length in footprint_sides(width, depth):
        if side == 0 and doors is not None:
            openings = list(doors)
        else:
            openings = facade_openings(
                rng,
                length,
                storeys,
                door=side == 0,
                recess_fraction=recess_fraction,
                window_pitch=window_pitch,
                window_sill=window_sill,
            )
        parts.append(wall(rng, start, end, 0.0, height, spacing, jitter, openings))
    parts.append(
        rectangle(
            rng, (-hw, -hd, height), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), width, depth, roof_spacing or spacing, jitter
        )
    )
    return place(stack(parts), yaw, centre)
