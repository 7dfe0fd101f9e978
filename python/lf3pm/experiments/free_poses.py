"""Random free sensor poses on a map, for experiments: the sensor at a fixed
height above the local ground, clear of every map point around it."""

from __future__ import annotations

import math

import numpy as np

from lf3pm.grid import Grid
from lf3pm.map import Map
from lf3pm.terrain import body_blocked, column_minimum

#: Horizontal cell (m) of the ground-height grid.
GROUND_CELL = 0.5


class GroundGrid:
    """Lowest map point per 0.5 m x 0.5 m column: the ground under a position."""

    def __init__(self, world: Map):
        lower, upper = world.bounds
        nx, ny = np.floor((upper[:2] - lower[:2]) / GROUND_CELL).astype(int) + 1
        self.grid = Grid.plane(lower[0], lower[1], GROUND_CELL, int(nx), int(ny))
        self.z = column_minimum(world.points, self.grid)

    def height(self, x: float, y: float) -> float:
        """Ground z under (x, y), or inf where the map has no point in that column."""
        cell = self.grid.cell_of(x, y)
        if cell is None:
            return math.inf
        return float(self.z[cell[1], cell[0]])


def random_free_poses(
    world: Map,
    count: int,
    rng: np.random.Generator,
    *,
    sensor_height: float,
    region: tuple[float, float, float, float],
    clearance: float = 0.5,
    max_tries: int = 200,
) -> list[tuple]:
    """``count`` poses (x, y, z, yaw) uniform over ``region`` (xmin, ymin, xmax,
    ymax) with random yaw, z = local ground + ``sensor_height``; a pose is kept
    only where the map has ground and no point lies within ``clearance`` of the
    sensor or of the body below it (checked down to ``clearance`` + 0.1 m above
    the ground)."""
    ground = GroundGrid(world)
    xmin, ymin, xmax, ymax = region
    poses = []
    for _ in range(count * max_tries):
        if len(poses) == count:
            break
        x, y = rng.uniform(xmin, xmax), rng.uniform(ymin, ymax)
        g = ground.height(x, y)
        if not math.isfinite(g):
            continue
        z = g + sensor_height
        if not body_blocked(world, x, y, min(z, g + clearance + 0.1), z, clearance):
            poses.append((x, y, z, rng.uniform(-math.pi, math.pi)))
    return poses
