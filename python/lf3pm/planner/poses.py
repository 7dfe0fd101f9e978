"""Planar poses (x, y, yaw) as the planner's public functions take and report them."""

from __future__ import annotations

import numpy as np

from lf3pm.errors import Lf3pmError


def as_pose(value, name: str) -> np.ndarray:
    """``value`` as a float64 array (3,) x, y, yaw, or a one-line error naming ``name``."""
    pose = np.asarray(value, dtype=np.float64).reshape(-1)
    if pose.shape != (3,) or not np.isfinite(pose).all():
        raise Lf3pmError(f"{name} must be three finite numbers X Y YAW, got {value!r}")
    return pose


def grid_cell(grid, x: float, y: float) -> tuple[int, int] | None:
    """(ix, iy) of the cell of ``grid`` (x0, y0, res, nx, ny: an Esdf, a SolmGrid) that holds
    (x, y), or None when (x, y) lies off the grid."""
    ix, iy = int(np.floor((x - grid.x0) / grid.res)), int(np.floor((y - grid.y0) / grid.res))
    return (ix, iy) if 0 <= ix < grid.nx and 0 <= iy < grid.ny else None


def cell_on_grid(grid, name: str, pose) -> tuple[int, int]:
    """:func:`grid_cell` of ``pose``'s x, y, or a one-line error naming ``name`` and the grid's extent."""
    cell = grid_cell(grid, float(pose[0]), float(pose[1]))
    if cell is None:
        raise Lf3pmError(
            f"{name} {format_pose(pose)} lies outside the grid x [{grid.x0:.2f}, "
            f"{grid.x0 + grid.nx * grid.res:.2f}], y [{grid.y0:.2f}, {grid.y0 + grid.ny * grid.res:.2f}]"
        )
    return cell


def format_pose(pose) -> str:
    """``(x, y, yaw)`` with two decimals, for messages."""
    return "(" + ", ".join(f"{float(v):.2f}" for v in pose) + ")"
