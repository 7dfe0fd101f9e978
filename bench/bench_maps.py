"""The casting benchmark's maps: surfaces of different character sampled the way
mobile-mapping maps are (dense ground, denser walls, millimetres of roughness), each
with the sensor positions it is measured from.

Every generator is deterministic per seed and returns (points N x 3 float64, the x-y
positions the sensor stands on, ground height there). Real maps come from
../shared/data (never ../shared/holdout).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

GROUND_STEP = 0.10  # m: ground sampling of every synthetic map
WALL_STEP = 0.05  # m: walls, trunks and vaults
ROUGHNESS = 0.005  # m: Gaussian jitter of every synthetic point


@dataclass(frozen=True)
class BenchMap:
    name: str
    description: str
    build: Callable[[], tuple[np.ndarray, np.ndarray]]  # -> points, sensor x-y positions
    real: bool = False


def _ground(x0, x1, y0, y1, step=GROUND_STEP, z=0.0):
    gx, gy = np.meshgrid(np.arange(x0, x1, step), np.arange(y0, y1, step), indexing="ij")
    return np.c_[gx.ravel(), gy.ravel(), np.full(gx.size, z)]


def _wall(x0, y0, x1, y1, height, step=WALL_STEP):
    """A vertical rectangle from (x0, y0) to (x1, y1), 0..height."""
    length = np.hypot(x1 - x0, y1 - y0)
    s, z = np.meshgrid(np.arange(0.0, length, step) / length, np.arange(0.0, height, step), indexing="ij")
    s, z = s.ravel(), z.ravel()
    return np.c_[x0 + (x1 - x0) * s, y0 + (y1 - y0) * s, z]


def _box(cx, cy, w, d, h, step=WALL_STEP):
    x0, x1, y0, y1 = cx - w / 2, cx + w / 2, cy - d / 2, cy + d / 2
    return [
        _wall(x0, y0, x1, y0, h, step),
        _wall(x0, y1, x1, y1, h, step),
        _wall(x0, y0, x0, y1, h, step),
        _wall(x1, y0, x1, y1, h, step),
    ]


def _finish(parts, seed):
    pts = np.vstack(parts)
    rng = np.random.default_rng(seed)
    return np.ascontiguousarray(pts + rng.normal(scale=ROUGHNESS, size=pts.shape))


def town(seed: int = 0, half: float = 60.0, pitch: float = 24.0):
    """A square street grid 2 half wide: 10 cm ground, buildings with 5 cm walls on a
    `pitch` m grid (the street crossing at the origin). half=60: about 2.6 M points."""
    centres = np.arange(-half + pitch, half - pitch / 2, pitch)
    parts = [_ground(-half, half, -half, half)]
    for cx in centres:
        for cy in centres:
            w, d, h = 10.0 + (cx % 7), 9.0 + (cy % 5), 6.0 + ((cx + cy) % 4)
            parts += _box(cx, cy, w, d, h)
    streets = [(0.0, 0.0), (centres[0] + pitch / 2, 0.3 * half), (0.4 * half, centres[-1] - pitch / 2)]
    return _finish(parts, seed), np.array(streets)


def street(seed: int = 0):
    """A 140 m street between two rows of facades 16 m apart, with side streets every
    35 m: 10 cm ground, 5 cm walls. About 1.9 M points."""
    parts = [_ground(-70.0, 70.0, -25.0, 25.0)]
    for side in (-1.0, 1.0):
        for x0 in np.arange(-70.0, 70.0, 35.0):
            parts.append(_wall(x0 + 4.0, side * 8.0, x0 + 31.0, side * 8.0, 9.0 + (x0 % 5)))
            for x in (x0 + 4.0, x0 + 31.0):  # the facades' returns into the side streets
                parts.append(_wall(x, side * 8.0, x, side * 20.0, 9.0 + (x0 % 5)))
    return _finish(parts, seed), np.array([(0.0, 0.0), (-30.0, 3.0), (45.0, -4.0)])


def forest(seed: int = 0, half: float = 40.0, trunks: int = 400):
    """Thin vertical structure: `trunks` trunks (radius 0.08-0.3 m, 6-14 m tall, 5 cm
    sampling) on 10 cm ground. About 1.6 M points."""
    rng = np.random.default_rng(seed + 1)
    parts = [_ground(-half, half, -half, half)]
    xy = rng.uniform(-half + 1.0, half - 1.0, size=(trunks, 2))
    xy = xy[np.hypot(*xy.T) > 2.0]  # keep the sensor positions free
    for (x, y), r, h in zip(xy, rng.uniform(0.08, 0.3, len(xy)), rng.uniform(6.0, 14.0, len(xy))):
        a, z = np.meshgrid(np.arange(0.0, 2 * np.pi, WALL_STEP / r), np.arange(0.0, h, WALL_STEP), indexing="ij")
        parts.append(np.c_[x + r * np.cos(a).ravel(), y + r * np.sin(a).ravel(), z.ravel()])
    return _finish(parts, seed), np.array([(0.0, 0.0), (1.5, -1.0), (-1.0, 1.5)])


def tunnel(seed: int = 0):
    """lf3pm's tunnel scene (docs/scenes.md): a vaulted tunnel with a structured lane."""
    from lf3pm.scenes import build_scene

    scene = build_scene("tunnel", seed=seed)
    x, y = scene.reference_pose[:2]
    return scene.points, np.array([(x, y), (x + 10.0, y), (x - 10.0, y)])


def site(seed: int = 0):
    """A site of about 10 M points: the town's street grid over 220 m x 220 m."""
    return town(seed, half=110.0, pitch=30.0)


def ground_height(points: np.ndarray, xy) -> float:
    """The ground under xy: the 5th percentile of the heights of the points within 1.5 m."""
    near = points[np.hypot(points[:, 0] - xy[0], points[:, 1] - xy[1]) < 1.5]
    return float(np.percentile(near[:, 2], 5)) if len(near) else float(points[:, 2].min())


def free_positions(points: np.ndarray, count: int = 3, clearance: float = 0.4, step: float = 0.5) -> np.ndarray:
    """`count` x-y positions of a real map where a sensor 0.5-1 m above the ground has
    `clearance` m of free space: on a `step` m lattice over the map's central half, the
    ones nearest the centre, at least 3 m apart, over ground (ground_height) seen by 10 points."""
    from scipy.spatial import cKDTree

    tree = cKDTree(points)
    lo, hi = np.percentile(points[:, :2], [25, 75], axis=0)
    centre = 0.5 * (lo + hi)
    gx, gy = np.meshgrid(np.arange(lo[0], hi[0], step), np.arange(lo[1], hi[1], step), indexing="ij")
    candidates = np.c_[gx.ravel(), gy.ravel()]
    candidates = candidates[np.argsort(np.hypot(*(candidates - centre).T), kind="stable")]
    chosen = []
    reach = 1.5 + np.ptp(points[:, 2])  # a ball holding every point within 1.5 m in x-y
    for xy in candidates:
        column = points[tree.query_ball_point([xy[0], xy[1], np.median(points[:, 2])], reach)]
        if np.count_nonzero(np.hypot(column[:, 0] - xy[0], column[:, 1] - xy[1]) < 1.5) < 10:
            continue
        ground = ground_height(column, xy)
        probes = [(xy[0], xy[1], ground + h) for h in (0.5, 1.0)]
        if min(tree.query(probes)[0]) >= clearance and all(np.hypot(*(xy - c)) >= 3.0 for c in chosen):
            chosen.append(xy)
            if len(chosen) == count:
                break
    return np.array(chosen)


def real_map(file: str):
    def build():
        from lf3pm.experiments.data import shared_data_dir
        from lf3pm.io import load_points

        points = load_points(str(shared_data_dir() / file))
        return points, free_positions(points)

    return build


MAPS = {
    m.name: m
    for m in (
        BenchMap("town", "120 m street grid, 10 cm ground, 5 cm walls", town),
        BenchMap("street", "140 m street, 10 cm ground, 5 cm facades", street),
        BenchMap("tunnel", "lf3pm's tunnel scene", tunnel),
        BenchMap("forest", "400 trunks on 10 cm ground", forest),
        BenchMap("room", "indoor_pcl_room_scan1 (real)", real_map("indoor_pcl_room_scan1.pcd"), True),
        BenchMap(
            "urban64", "outdoor_urban64 scan (real)", real_map("outdoor_urban64_2021-10-26-16-21-29-468.pcd"), True
        ),
        BenchMap("site", "220 m street grid, 10 M points", site),
    )
}
