"""The map's frame (what a crop's index takes from its whole map): the median point
spacing, estimated chunk by chunk without a grid over the whole map, against a
straightforward float64 reference."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from lf3pm import _core
from lf3pm.config import MapConfig

MASK = (1 << 64) - 1


def splitmix64(x: int) -> int:
    x = (x + 0x9E3779B97F4A7C15) & MASK
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & MASK
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & MASK
    return x ^ (x >> 31)


def reference_spacing(points: np.ndarray) -> float:
    """map_index.cpp's estimate written plainly: for 4000 seeded samples, the distance to
    the nearest point of other coordinates within four coarse cells; their median."""
    n = len(points)
    lo, hi = points.min(axis=0), points.max(axis=0)
    ext = np.maximum(hi - lo, 1.0)
    area = max(ext[0] * ext[1], ext[0] * ext[2], ext[1] * ext[2])
    cell = max(0.02, 4.0 * np.sqrt(area / n), np.cbrt(np.prod(ext) / (1 << 26)) * 8.0)
    samples = points[[splitmix64(s) % n for s in range(min(n, 4000))]]
    distinct = np.unique(points, axis=0)
    dist, _ = cKDTree(distinct).query(samples, k=2, distance_upper_bound=4.0 * cell)
    nearest = np.where(dist[:, 0] > 0, dist[:, 0], dist[:, 1])  # the sample itself is at 0
    nearest = np.where(np.isfinite(nearest), nearest, 4.0 * cell)
    return max(float(np.sort(nearest)[len(nearest) // 2]), 1e-4)


@pytest.mark.slow
@pytest.mark.parametrize("n", [3000, 1_300_000])
def test_median_spacing_matches_reference(n):
    """Also across the estimate's 2^20-point chunks, with exact duplicates in other chunks
    than their originals and lattice ties."""
    rng = np.random.default_rng(3)
    side = int(np.sqrt(n * 0.8))
    g = np.arange(side) * 0.05
    lattice = np.stack(np.meshgrid(g, g, [0.0], indexing="ij"), -1).reshape(-1, 3)
    noisy = rng.uniform(0, side * 0.05, size=(n - len(lattice) - n // 10, 3)) * [1, 1, 0.02]
    points = np.vstack([lattice, noisy])
    points = np.vstack([points, points[rng.integers(0, len(points), n // 10)]])
    points = np.ascontiguousarray(points[rng.permutation(len(points))])
    frame = _core.map_frame(points, MapConfig().core(0))
    assert frame.median_spacing == pytest.approx(reference_spacing(points), rel=1e-12)
    assert frame.__getstate__()[:3] == tuple(points.min(axis=0))  # the k-NN grid's lower corner


def test_frame_equals_the_index_frame():
    points = np.random.default_rng(4).uniform(0, 20, size=(20_000, 3)) * [1, 1, 0.05]
    params = MapConfig().core(0)
    assert _core.map_frame(points, params) == _core.MapIndex(points, params).frame
