"""Planar poses (x, y, yaw) as the planner's public functions take and report them."""

from __future__ import annotations

import numpy as np

from lf3pm.errors import Lf3pmError
from lf3pm.grid import Grid


def as_pose(value, name: str) -> np.ndarray:
    """``value`` as a float64 array (3,) x, y, yaw, or a one-line error naming ``name``."""
    pose = np.asarray(value, dtype=np.float64).reshape(-1)
    if pose.shape != (3,) or not np.isfinite(pose).all():
        raise Lf3pmError(f"{name} must be three finite numbers X Y YAW, got {value!r}")
    return pose


def cell_on_grid(grid: Grid, name: str, pose) -> tuple[int, int]:
    """(ix, iy) of the cell of ``grid`` holding ``pose``'s x, y, or a one-line error naming
    ``name`` and the grid's extent."""
    cell = grid.cell_of(float(pose[0]), float(pose[1]))
    if cell is None:
        xmin, ymin, xmax, ymax = grid.bounds
        raise Lf3pmError(
            f"{name} {format_pose(pose)} lies outside the grid x [{xmin:.2f}, {xmax:.2f}], y [{ymin:.2f}, {ymax:.2f}]"
        )
    return cell


def format_pose(pose) -> str:
    """``(x, y, yaw)`` with two decimals, for messages."""
    return "(" + ", ".join(f"{float(v):.2f}" for v in pose) + ")"
