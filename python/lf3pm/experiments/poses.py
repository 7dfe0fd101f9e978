"""Free sensor poses around a scene's reference pose, for experiments."""

from __future__ import annotations

import math

import numpy as np

from lf3pm.scenes import Scene


def poses_around_reference(scene: Scene, count: int, seed: int) -> list[tuple]:
    """``count`` poses (x, y, z, yaw): the reference position at yaws 0, 90,
    180 and 270 degrees, then random positions on the level free pad around it
    (within 60 % of the scene's free radius) with random yaws. Seeded."""
    x0, y0, z0, _ = scene.reference_pose
    poses = [(x0, y0, z0, k * math.pi / 2) for k in range(min(count, 4))]
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x504F53]))
    while len(poses) < count:
        r = 0.6 * scene.free_radius * math.sqrt(rng.uniform())
        a = rng.uniform(0, 2 * math.pi)
        poses.append((x0 + r * math.cos(a), y0 + r * math.sin(a), z0, rng.uniform(-math.pi, math.pi)))
    return poses
