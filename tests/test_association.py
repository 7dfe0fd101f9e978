"""FAST-LIO association pieces against float64 references: the fast
smallest-eigenvector plane fit against numpy.linalg.eigh, and the grid k-NN
against a brute-force search, ties included."""

import numpy as np
import pytest

from lf3pm import _core


def random_rotations(rng, m):
    q, _ = np.linalg.qr(rng.normal(size=(m, 3, 3)))
    return q


def eigh_planes(sets):
    centred = sets - sets.mean(axis=1, keepdims=True)
    w, v = np.linalg.eigh(np.einsum("mki,mkj->mij", centred, centred))
    return v[:, :, 0], w


def angle(a, b):
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.abs(np.sum(a * b, axis=1)))


@pytest.mark.slow
@pytest.mark.parametrize("k", [3, 5, 12])
@pytest.mark.parametrize(
    "extent", [(0.1, 0.1, 0.005), (0.1, 0.1, 0.0), (0.1, 0.01, 0.001), (0.1, 1e-3, 1e-5), (0.1, 0.1, 0.1)]
)
def test_fit_plane_matches_eigh(k, extent):
    """Nearly planar, exactly planar, elongated, nearly collinear and isotropic
    sets, far from the origin: normals within 1e-9 rad wherever the two smallest
    eigenvalues are separated, centroids and plane distances to rounding."""
    rng = np.random.default_rng(k)
    m = 20000
    local = rng.normal(size=(m, k, 3)) * np.asarray(extent)
    sets = np.einsum("mij,mkj->mki", random_rotations(rng, m), local) + rng.uniform(-50, 50, size=(m, 1, 3))
    normals, centroids, max_distance = _core.fit_planes(np.ascontiguousarray(sets))
    ref, w = eigh_planes(sets)
    separated = (w[:, 1] - w[:, 0]) > 1e-6 * w[:, 2]
    assert angle(normals, ref)[separated].max() < 1e-9
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-15)
    np.testing.assert_allclose(centroids, sets.mean(axis=1), rtol=0, atol=1e-12)
    ref_dist = np.abs(np.einsum("mkj,mj->mk", sets - centroids[:, None], normals)).max(axis=1)
    np.testing.assert_allclose(max_distance, ref_dist, rtol=0, atol=1e-12)


def test_fit_plane_degenerate_sets():
    """Exact lines, a repeated point and two points: any normal across the line
    (distance 0), never NaN."""
    t = np.linspace(0.0, 1.0, 5)[:, None]
    line = np.array([1.0, 2.0, 3.0]) + t * np.array([0.3, -0.2, 0.5])
    axis_line = t * np.array([1.0, 0.0, 0.0])
    same = np.repeat([[1.0, 2.0, 3.0]], 5, axis=0)
    normals, _, max_distance = _core.fit_planes(np.ascontiguousarray([line, axis_line, same]))
    assert np.all(np.isfinite(normals))
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert np.all(max_distance < 1e-12)
    pair, _, d = _core.fit_planes(np.ascontiguousarray([[[0.0, 0, 0], [1.0, 1, 0]]]))
    assert abs(pair[0] @ np.array([1.0, 1, 0])) < 1e-12 and d[0] < 1e-12


def test_knn_ties_go_to_the_smaller_index():
    """On an exact lattice many neighbours are equally far: the k nearest are the
    first k by (distance, index), whatever order the cells are visited in.
    Dyadic coordinates keep every squared distance exact, so the brute force
    sees the same ties."""
    g = np.arange(-8, 9) * 0.125
    pts = np.ascontiguousarray(np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3))
    index = _core.MapIndex(pts)
    rng = np.random.default_rng(2)
    queries = np.ascontiguousarray(
        np.vstack([index.points[rng.integers(0, index.size, 300)], rng.integers(-80, 81, size=(300, 3)) / 64.0])
    )
    for k, radius in ((5, 2.0), (12, 0.25), (1, 1.0)):
        idx, dist = index.nearest(queries, k, radius)
        d = np.linalg.norm(index.points[None, :, :] - queries[:, None, :], axis=2)
        for qi in range(len(queries)):
            order = np.lexsort((np.arange(index.size), d[qi]))[:k]
            order = order[d[qi, order] <= radius]
            np.testing.assert_array_equal(idx[qi, : len(order)], order)
            np.testing.assert_array_equal(dist[qi, : len(order)], d[qi, order])


def test_knn_in_sparse_regions_matches_brute_force():
    # A dense patch sets a small cell; sparse points around it put most
    # neighbours many cells away, where the search switches to whole blocks.
    from scipy.spatial import cKDTree

    from lf3pm import _core

    rng = np.random.default_rng(21)
    dense = rng.uniform(-0.5, 0.5, size=(20000, 3)) * [1, 1, 0.01]
    sparse = rng.uniform(-15, 15, size=(4000, 3))
    index = _core.MapIndex(np.ascontiguousarray(np.vstack([dense, sparse])))
    queries = np.ascontiguousarray(rng.uniform(-16, 16, size=(3000, 3)))
    for k, radius in ((5, 2.236), (1, 4.0), (8, 3.0)):
        idx, dist = index.nearest(queries, k, radius)
        ref, _ = cKDTree(index.points).query(queries, k=k)
        ref = np.where(ref.reshape(len(queries), k) <= radius, ref.reshape(len(queries), k), np.inf)
        np.testing.assert_allclose(dist, ref, rtol=1e-12)
