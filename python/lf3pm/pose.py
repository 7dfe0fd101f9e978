"""Poses: sensor-to-world rigid transforms from the forms users type.

Accepted forms (DESIGN.md conventions, metres and radians, yaw about +z):
``(x, y, z, yaw)``, ``(x, y, z, qw, qx, qy, qz)`` or a 4 x 4 homogeneous matrix.
"""

from __future__ import annotations

import numpy as np

from lf3pm.errors import PoseError


def pose_matrix(pose) -> np.ndarray:
    """Returns the 4 x 4 float64 sensor-to-world matrix of ``pose``."""
    arr = np.asarray(pose, dtype=np.float64)
    if arr.shape == (4, 4):
        matrix = arr.copy()
    elif arr.shape == (4,):
        x, y, z, yaw = arr
        matrix = np.eye(4)
        c, s = np.cos(yaw), np.sin(yaw)
        matrix[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
        matrix[:3, 3] = (x, y, z)
    elif arr.shape == (7,):
        matrix = np.eye(4)
        q = arr[3:]
        norm = np.linalg.norm(q)
        if not np.isfinite(norm) or norm < 1e-12:
            raise PoseError(f"pose quaternion {q.tolist()} has no direction")
        matrix[:3, :3] = quaternion_to_rotation(q / norm)
        matrix[:3, 3] = arr[:3]
    else:
        raise PoseError(
            f"a pose is x y z yaw, x y z qw qx qy qz or a 4x4 matrix, got shape {arr.shape}")
    if not np.all(np.isfinite(matrix)):
        raise PoseError(f"pose has non-finite values: {arr.ravel().tolist()}")
    rotation = matrix[:3, :3]
    if not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6) or np.linalg.det(rotation) < 0:
        raise PoseError("pose rotation is not a proper rotation matrix")
    return np.ascontiguousarray(matrix)


def quaternion_to_rotation(q) -> np.ndarray:
    """Rotation matrix of the unit quaternion (qw, qx, qy, qz)."""
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])
