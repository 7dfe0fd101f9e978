"""The SOLM's occupancy layer: where the map holds a point a ground robot's body
could hit, on a grid finer than the SOLM's cells, for the planner's ESDF.

The SOLM's cells are as coarse as the metric's cost allows (0.25-1.5 m); its
``obstacle`` mask says where the body at a cell's centre touches the map (a pose
the robot cannot take, so not evaluated). The planner needs more: a plan must keep
its body off every point, also a thin pole or a bush's stem between two centres,
which a centre probe misses (on the gobi's 1 m cells a third of the benefit
study's plans passed 1-5 cm from bush points). So the store also holds, on cells
of ``res / k`` (OCCUPANCY_RES or a little less, k an integer so that each SOLM cell
splits into k x k), which cells hold a map point in the body's height band above
the local ground; the ESDF of that grid less the robot radius is the body's
clearance (planner/esdf.py).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import minimum_filter

from lf3pm.solm.grid import SolmGrid
from lf3pm.terrain import column_minimum, occupied_cells

#: Target edge of an occupancy cell (m): a pole's position is known to within it.
OCCUPANCY_RES = 0.1
#: Most occupancy cells: the ESDF over them then builds in ~3 s and 0.5 GB; larger
#: grids get coarser occupancy cells (down to the SOLM's own).
MAX_OCCUPANCY_CELLS = 1 << 20


def occupancy_factor(grid: SolmGrid) -> int:
    """k: occupancy cells per SOLM cell and axis, the most up to res / OCCUPANCY_RES
    that keeps the grid within MAX_OCCUPANCY_CELLS (at least 1). Closed form: the
    largest k with nx ny k^2 <= MAX_OCCUPANCY_CELLS is isqrt(MAX // (nx ny))."""
    wanted = math.ceil(grid.res / OCCUPANCY_RES - 1e-9)
    fitting = math.isqrt(MAX_OCCUPANCY_CELLS // (grid.nx * grid.ny))
    return max(1, min(wanted, fitting))


def grid_occupancy(
    points: np.ndarray, grid: SolmGrid, ground: np.ndarray, robot_radius: float, floor_clearance: float
) -> np.ndarray:
    """(ny k, nx k) bool: the occupancy cells holding a map point in the body's height
    band, from ``floor_clearance`` above the local ground to ``robot_radius`` above the
    sensor. The local ground of an occupancy cell is the lowest point within the robot
    radius of it (a window of occupancy cells), not below the lowest ground of its SOLM
    cell (``ground``, (ny, nx), inf where unknown): on a slope the ground a cell away
    stays ground, while a pole or a wall stands on the ground beside it."""
    k = occupancy_factor(grid)
    cell = grid.res / k
    coarse = np.kron(ground, np.ones((k, k)))
    lowest = column_minimum(points, grid.x0, grid.y0, cell, grid.nx * k, grid.ny * k)
    window = 2 * math.ceil(robot_radius / cell) + 1
    local = minimum_filter(lowest, size=window, mode="nearest")  # inf where the window is empty
    floor = np.where(np.isfinite(local), np.maximum(local, coarse), coarse)
    return occupied_cells(points, grid.x0, grid.y0, cell, floor + floor_clearance, floor + grid.height + robot_radius)
