"""The pipeline a Python user would write today to evaluate LF-3PM at a pose,
used as the baseline of the benchmarks: Open3D RaycastingScene (Embree) casting
against a mesh of the map, scipy cKDTree 5-NN association, NumPy plane fits and
the metric by SVD."""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial import cKDTree


def surfel_mesh(centres: np.ndarray, normals: np.ndarray, radii: np.ndarray):
    """A hexagon (4 triangles) per map point in its neighbourhood plane: the
    same surface model lf3pm casts against (discs), as a mesh Embree can take,
    so the two pipelines see the same geometry and can agree on q."""
    helper = np.where(np.abs(normals[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    u = np.cross(normals, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(normals, u)
    angles = np.arange(6) * np.pi / 3
    # Circumscribe the disc: the hexagon's inner radius equals the disc radius.
    scale = (radii / np.cos(np.pi / 6))[:, None, None]
    ring = np.cos(angles)[None, :, None] * u[:, None] + np.sin(angles)[None, :, None] * v[:, None]
    vertices = (centres[:, None] + scale * ring).reshape(-1, 3).astype(np.float32)
    fan = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]], np.uint32)
    triangles = (np.arange(len(centres), dtype=np.uint32)[:, None, None] * 6 + fan).reshape(-1, 3)
    return vertices, triangles


def voxel_mesh(points: np.ndarray, normals: np.ndarray, voxel: float = 0.1):
    """The mesh a user would build at the map's own resolution: one square (2 triangles)
    per occupied voxel of edge ``voxel``, at its points' centroid, in the plane of their
    mean normal, 1.5 voxel edges wide so that neighbouring squares overlap and the surface
    has no holes."""
    keys = np.floor(points / voxel).astype(np.int64)
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    centres = np.zeros((len(counts), 3))
    np.add.at(centres, inverse, points)
    centres /= counts[:, None]
    # Normals are unoriented: align each to its voxel's first before averaging.
    first = np.zeros((len(counts), 3))
    first[inverse[::-1]] = normals[::-1]
    signed = normals * np.sign(np.sum(normals * first[inverse], axis=1, keepdims=True) + 1e-12)
    mean = np.zeros((len(counts), 3))
    np.add.at(mean, inverse, signed)
    mean /= np.linalg.norm(mean, axis=1, keepdims=True)
    helper = np.where(np.abs(mean[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    u = np.cross(mean, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(mean, u)
    half = 0.75 * voxel
    corners = np.stack([centres + half * (su * u + sv * v) for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))], axis=1)
    vertices = corners.reshape(-1, 3).astype(np.float32)
    quad = np.array([[0, 1, 2], [0, 2, 3]], np.uint32)
    triangles = (np.arange(len(centres), dtype=np.uint32)[:, None, None] * 4 + quad).reshape(-1, 3)
    return vertices, triangles


class BaselinePipeline:
    """Open3D casting + cKDTree association + NumPy metric (noise-free scans)."""

    def __init__(self, map_points, vertices, triangles, directions, min_range, max_range, threads=2):
        import open3d as o3d

        self.scene = o3d.t.geometry.RaycastingScene(nthreads=threads)
        self.scene.add_triangles(o3d.core.Tensor(vertices), o3d.core.Tensor(triangles))
        self.o3c = o3d.core
        self.tree = cKDTree(map_points)
        self.map_points = map_points
        self.directions = directions
        self.min_range, self.max_range = min_range, max_range
        self.threads = threads
        self.cast_seconds = 0.0  # accumulated, to split the baseline's time

    def q_n(self, pose: np.ndarray) -> float:
        """q_n of the noise-free scan at the 4x4 ``pose``."""
        dirs = self.directions @ pose[:3, :3].T
        origin = np.broadcast_to(pose[:3, 3], dirs.shape)
        rays = np.hstack([origin, dirs]).astype(np.float32)
        start = time.perf_counter()
        t = self.scene.cast_rays(self.o3c.Tensor(rays))["t_hit"].numpy().astype(np.float64)
        self.cast_seconds += time.perf_counter() - start
        ok = np.isfinite(t) & (t >= self.min_range) & (t <= self.max_range)
        hits = pose[:3, 3] + dirs[ok] * t[ok, None]
        return association_and_metric(self.tree, self.map_points, hits, pose[:3, 3], self.threads)


def association_and_metric(
    tree: cKDTree, map_points: np.ndarray, hits: np.ndarray, position: np.ndarray, workers: int = 1
) -> float:
    """FAST-LIO association as a NumPy user writes it (5-NN, PCA planes, the
    0.1 m validity and sqrt(5) m gates), then q_n by SVD of A."""
    dist, idx = tree.query(hits, k=5, workers=workers)
    nb = map_points[idx]  # (m, 5, 3)
    centroid = nb.mean(axis=1)
    cov = np.einsum("mki,mkj->mij", nb - centroid[:, None], nb - centroid[:, None])
    _, vecs = np.linalg.eigh(cov)
    normal = vecs[:, :, 0]
    off = np.abs(np.einsum("mkj,mj->mk", nb - centroid[:, None], normal)).max(axis=1)
    ok = (dist[:, -1] <= np.sqrt(5.0)) & (off <= 0.1)
    u, w, c = normal[ok], hits[ok], centroid[ok]
    A = np.hstack([u, np.cross(w - position, u)])
    b = -np.einsum("mj,mj->m", u, w - c)
    s = np.linalg.svd(A, compute_uv=False)
    dx, *_ = np.linalg.lstsq(A, b, rcond=None)
    r = np.linalg.norm(A @ dx - b)
    xi = np.linalg.norm(dx) + r / s[-1]
    M = np.hstack([xi * A, b[:, None]])
    g = np.linalg.eigvalsh(M.T @ M)
    return float(np.sqrt(0.5 * g[1] + 0.5) / s[-1])
