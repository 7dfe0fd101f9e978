"""Poses: sensor-to-world rigid transforms from the forms users type.

Accepted forms (docs/design.md, Conventions: metres and radians, yaw about +z):
``(x, y, z, yaw)``, ``(x, y, z, qw, qx, qy, qz)`` or a 4 x 4 homogeneous matrix.
"""

from __future__ import annotations

import math

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
        raise PoseError(f"a pose is x y z yaw, x y z qw qx qy qz or a 4x4 matrix, got shape {arr.shape}")
    if not np.all(np.isfinite(matrix)):
        raise PoseError(f"pose has non-finite values: {arr.ravel().tolist()}")
    rotation = matrix[:3, :3]
    if not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6) or np.linalg.det(rotation) < 0:
        raise PoseError("pose rotation is not a proper rotation matrix")
    return np.ascontiguousarray(matrix)


def pose_matrices(poses) -> np.ndarray:
    """(M, 4, 4) sensor-to-world matrices of (M, 4) poses x y z yaw, as
    ``pose_matrix`` of each row (unchecked: for many poses at once)."""
    poses = np.asarray(poses, dtype=np.float64)
    c, s = np.cos(poses[:, 3]), np.sin(poses[:, 3])
    out = np.zeros((len(poses), 4, 4))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = c, -s, s, c
    out[:, 2, 2] = out[:, 3, 3] = 1.0
    out[:, :3, 3] = poses[:, :3]
    return out


def quaternion_to_rotation(q) -> np.ndarray:
    """Rotation matrix of the unit quaternion (qw, qx, qy, qz)."""
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _hat(v) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _left_jacobian(phi) -> np.ndarray:
    """V(phi) of SE(3): t = V rho maps the translation part of a twist."""
    theta = np.linalg.norm(phi)
    K = _hat(phi)
    if theta < 1e-8:
        return np.eye(3) + 0.5 * K + K @ K / 6.0
    return np.eye(3) + (1 - np.cos(theta)) / theta**2 * K + (theta - np.sin(theta)) / theta**3 * K @ K


def se3_exp(xi) -> np.ndarray:
    """4 x 4 transform of the twist xi = (rho, phi) (translation first, then rotation)."""
    xi = np.asarray(xi, dtype=np.float64)
    rho, phi = xi[:3], xi[3:]
    theta = np.linalg.norm(phi)
    K = _hat(phi)
    if theta < 1e-8:
        R = np.eye(3) + K + K @ K / 2.0
    else:
        R = np.eye(3) + np.sin(theta) / theta * K + (1 - np.cos(theta)) / theta**2 * K @ K
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = _left_jacobian(phi) @ rho
    return T


def se3_log(T) -> np.ndarray:
    """Twist (rho, phi) of the 4 x 4 transform T: the inverse of se3_exp."""
    R, t = T[:3, :3], T[:3, 3]
    cos_theta = np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)
    theta = math.acos(cos_theta)
    if theta < 1e-8:
        phi = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    elif np.pi - theta < 1e-6:
        # Near pi the antisymmetric part vanishes: take the axis from R + I.
        axis = np.sqrt(np.maximum((np.diag(R) + 1.0) / 2.0, 0.0))
        signs = np.sign(np.array([1.0, R[0, 1] + R[1, 0], R[0, 2] + R[2, 0]]))
        phi = theta * axis * np.where(signs == 0, 1.0, signs)
    else:
        phi = theta / (2 * np.sin(theta)) * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return np.concatenate([np.linalg.solve(_left_jacobian(phi), t), phi])
