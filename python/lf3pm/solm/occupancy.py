"""The SOLM's occupancy layer: where the map holds a point a ground robot's body
could hit, on a grid finer than the SOLM's cells, for the planner's ESDF.

The SOLM's cells are as coarse as the metric's cost allows (0.25-1.5 m); its
``obstacle`` mask says where the body at a cell's centre touches the map (a pose
the robot cannot take, so not evaluated). The planner needs more: a plan must keep
its body off every point, also a thin pole or a bush's stem between two centres,
which a centre probe misses (on the gobi's 1 m cells a third of the benefit
study's plans passed 1-5 cm from bush points). So the store also holds, on cells
of ``res / k`` (the solm section's occupancy_res or a little less, k an integer so that each SOLM cell
splits into k x k), which cells hold a map point in the body's height band above
the local ground; the ESDF of that grid less the robot radius is the body's
clearance (planner/esdf.py).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import minimum_filter

from lf3pm.config import DEFAULTS, SolmConfig
from lf3pm.solm.grid import SolmGrid
from lf3pm.terrain import column_minimum, occupied_cells

#: The defaults of the solm section's occupancy_res and max_occupancy_cells.
OCCUPANCY_RES = DEFAULTS.solm.occupancy_res
MAX_OCCUPANCY_CELLS = DEFAULTS.solm.max_occupancy_cells


def occupancy_factor(grid: SolmGrid, solm: SolmConfig = DEFAULTS.solm) -> int:
    """k: occupancy cells per SOLM cell and axis, the most up to res / occupancy_res
    that keeps the grid within max_occupancy_cells (at least 1). Closed form: the
    largest k with nx ny k^2 <= max_occupancy_cells is isqrt(max // (nx ny))."""
    wanted = math.ceil(grid.res / solm.occupancy_res - 1e-9)
    fitting = math.isqrt(solm.max_occupancy_cells // (grid.nx * grid.ny))
    return max(1, min(wanted, fitting))


def grid_occupancy(
    points: np.ndarray,
    grid: SolmGrid,
    ground: np.ndarray,
    robot_radius: float,
    floor_clearance: float,
    solm: SolmConfig = DEFAULTS.solm,
) -> np.ndarray:
    """(ny k, nx k) bool: the occupancy cells holding a map point in the body's height
    band, from ``floor_clearance`` above the local ground to ``robot_radius`` above the
    sensor. The local ground of an occupancy cell is the lowest point within the robot
    radius of it (a window of occupancy cells), not below the lowest ground of its SOLM
    cell (``ground``, (ny, nx), inf where unknown): on a slope the ground a cell away
    stays ground, while a pole or a wall stands on the ground beside it."""
    k = occupancy_factor(grid, solm)
    fine = grid.refined(k)
    coarse = np.kron(ground, np.ones((k, k)))
    lowest = column_minimum(points, fine)
    window = 2 * math.ceil(robot_radius / fine.res) + 1
    local = minimum_filter(lowest, size=window, mode="nearest")  # inf where the window is empty
    floor = np.where(np.isfinite(local), np.maximum(local, coarse), coarse)
    return occupied_cells(points, fine, floor + floor_clearance, floor + grid.height + robot_radius)
