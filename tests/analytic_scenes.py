"""Point-cloud maps of surfaces with known geometry, for exact checks."""

import numpy as np


def grid_plane(origin, u, v, extent_u, extent_v, spacing):
    """Points on the rectangle origin + a*u + b*v, 0 <= a < extent_u, 0 <= b < extent_v."""
    a = np.arange(0.0, extent_u + 1e-9, spacing)
    b = np.arange(0.0, extent_v + 1e-9, spacing)
    aa, bb = np.meshgrid(a, b, indexing="ij")
    return (
        np.asarray(origin, float) + aa.reshape(-1, 1) * np.asarray(u, float) + bb.reshape(-1, 1) * np.asarray(v, float)
    )


def box_room(half, spacing=0.05):
    """The six faces of the box [-hx, hx] x [-hy, hy] x [-hz, hz] (half = (hx, hy, hz))."""
    hx, hy, hz = half
    ex, ey, ez = np.eye(3)
    faces = [
        grid_plane((-hx, -hy, -hz), ey, ez, 2 * hy, 2 * hz, spacing),
        grid_plane((hx, -hy, -hz), ey, ez, 2 * hy, 2 * hz, spacing),
        grid_plane((-hx, -hy, -hz), ex, ez, 2 * hx, 2 * hz, spacing),
        grid_plane((-hx, hy, -hz), ex, ez, 2 * hx, 2 * hz, spacing),
        grid_plane((-hx, -hy, -hz), ex, ey, 2 * hx, 2 * hy, spacing),
        grid_plane((-hx, -hy, hz), ex, ey, 2 * hx, 2 * hy, spacing),
    ]
    return np.ascontiguousarray(np.unique(np.round(np.vstack(faces), 9), axis=0))


def ray_box_distance(origin, directions, half):
    """Distance from an inside origin along unit directions to the box's boundary."""
    half = np.asarray(half, float)
    with np.errstate(divide="ignore"):
        t = np.where(
            directions > 0,
            (half - origin) / directions,
            np.where(directions < 0, (-half - origin) / directions, np.inf),
        )
    return t.min(axis=1)


def spinning_directions(elevations_deg, azimuths):
    el = np.deg2rad(np.asarray(elevations_deg, float))
    az = np.arange(azimuths) * 2 * np.pi / azimuths
    A, E = np.meshgrid(az, el, indexing="ij")
    return np.ascontiguousarray(
        np.stack([np.cos(E) * np.cos(A), np.cos(E) * np.sin(A), np.sin(E)], axis=-1).reshape(-1, 3)
    )


def random_directions(rng, count):
    d = rng.normal(size=(count, 3))
    return np.ascontiguousarray(d / np.linalg.norm(d, axis=1, keepdims=True))


def rigid_transform(rng):
    """A random 4 x 4 rigid transform."""
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    T = np.eye(4)
    T[:3, :3] = q
    T[:3, 3] = rng.uniform(-50, 50, size=3)
    return T
