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


def format_pose(pose) -> str:
    """``(x, y, yaw)`` with two decimals, for messages."""
    return "(" + ", ".join(f"{float(v):.2f}" for v in pose) + ")"
