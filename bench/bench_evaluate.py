"""Benchmark: one full evaluation (cast + associate + metric) of a VLP-16 scan
(1800 x 16 rays) on a map of over 2 million points, on one core.

Ours: lf3pm's fused C++ pipeline. Baselines, in the same run: the same hits
associated the way a Python user would (scipy cKDTree 5-NN, NumPy plane fits,
NumPy metric from A); and Embree (embreex, one thread) only casting the same rays on
a mesh of the same surfaces at the map's own resolution: one square of two triangles
per map point, in its plane, as wide as its disc (so the mesh holds 2 triangles per
point). Prints ms per scan, rays per second and the ratios.

    .venv/bin/python bench/bench_evaluate.py [--repeat 20]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.spatial import cKDTree

from baseline_pipeline import association_and_metric

import lf3pm
from lf3pm import _core
from lf3pm.metric import eval_params
from lf3pm.config import scan_params


def town_map(seed: int = 0) -> np.ndarray:
    """A 120 m square street grid: ground every 10 cm, 16 buildings with walls
    every 5 cm, 5 mm of surface roughness. About 2.6 million points."""
    rng = np.random.default_rng(seed)
    g = np.arange(-60.0, 60.0, 0.1)
    gx, gy = np.meshgrid(g, g, indexing="ij")
    parts = [np.c_[gx.ravel(), gy.ravel(), np.zeros(gx.size)]]
    for cx in (-36.0, -12.0, 12.0, 36.0):
        for cy in (-36.0, -12.0, 12.0, 36.0):
            w, d, h = 10.0 + (cx % 7), 9.0 + (cy % 5), 6.0 + ((cx + cy) % 4)
            a = np.arange(0.0, 1.0, 0.05 / w)
            b = np.arange(0.0, 1.0, 0.05 / d)
            z = np.arange(0.0, h, 0.05)
            for (x0, y0, x1, y1, s) in ((cx - w / 2, cy - d / 2, cx + w / 2, cy - d / 2, a),
                                        (cx - w / 2, cy + d / 2, cx + w / 2, cy + d / 2, a),
                                        (cx - w / 2, cy - d / 2, cx - w / 2, cy + d / 2, b),
                                        (cx + w / 2, cy - d / 2, cx + w / 2, cy + d / 2, b)):
                ss, zz = np.meshgrid(s, z, indexing="ij")
                parts.append(np.c_[x0 + (x1 - x0) * ss.ravel(), y0 + (y1 - y0) * ss.ravel(), zz.ravel()])
    pts = np.vstack(parts)
    return np.ascontiguousarray(pts + rng.normal(scale=0.005, size=pts.shape))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()

    points = town_map()
    t = time.perf_counter()
    world = lf3pm.load_map(points, threads=0)
    build_s = time.perf_counter() - t
    sensor = lf3pm.get_sensor("vlp16")
    pose = np.eye(4)
    pose[:3, 3] = (0.0, 0.0, 1.8)
    args_core = (world.index, pose, sensor.directions)

    def timed(**kwargs):
        params = eval_params(sensor.min_range, sensor.max_range, **kwargs)
        times = []
        for _ in range(args.repeat):
            t = time.perf_counter()
            out = _core.evaluate(*args_core, params)
            times.append(time.perf_counter() - t)
        return float(np.median(times)), out

    ours_s, res = timed(threads=1)
    variants = {
        "k-NN association (default), 2 threads": timed(threads=2)[0],
        "surfel association, 1 thread": timed(threads=1, association="surfel")[0],
        "k-NN, scan voxel 0.5 m (FAST-LIO filter_size_surf), 1 thread":
            timed(threads=1, scan_voxel=0.5)[0],
    }
    one_thread = scan_params(sensor.min_range, sensor.max_range, threads=1)
    scan = _core.simulate_scan(*args_core, one_thread)
    cast = []
    for _ in range(args.repeat):
        t = time.perf_counter()
        _core.simulate_scan(*args_core, one_thread)
        cast.append(time.perf_counter() - t)
    tree = cKDTree(world.points)
    base = []
    for _ in range(max(3, args.repeat // 5)):
        t = time.perf_counter()
        q_base = association_and_metric(tree, world.points, scan["world_points"], pose[:3, 3])
        base.append(time.perf_counter() - t)

    cast_s, base_s = np.median(cast), np.median(base)
    rays = sensor.num_rays
    print(f"map: {world.size:,} points, index built in {build_s:.2f} s "
          f"({world.index.memory_bytes / 2**20:.0f} MiB), cell {world.index.cell_size:.3f} m")
    print(f"scan: {rays:,} rays, {res.hits:,} hits, {res.metric.m:,} observation rows")
    print(f"ours, one core: {ours_s * 1e3:.2f} ms per scan ({rays / ours_s / 1e6:.2f} M rays/s); "
          f"casting alone {cast_s * 1e3:.2f} ms")
    for name, seconds in variants.items():
        print(f"  {name}: {seconds * 1e3:.2f} ms per scan")
    print(f"baseline association + metric (cKDTree + NumPy), after our cast: {base_s * 1e3:.1f} ms")
    print(f"ratio, baseline association+metric / ours end to end: {base_s / ours_s:.1f}x")
    print(f"q_n ours {res.metric.q_n:.6g} vs baseline (k-NN association) {q_base:.6g}")
    embree_s, agree = embree_cast(world, pose, sensor, scan, args.repeat)
    if embree_s is not None:
        print(f"Embree casting alone (embreex, 1 thread, {2 * world.size:,} triangles): {embree_s * 1e3:.2f} ms; "
              f"hits within 5 cm of ours: {agree:.1%}")
        print(f"ratio, ours end to end / Embree casting: {ours_s / embree_s:.2f}x; "
              f"our casting / Embree casting: {cast_s / embree_s:.2f}x")


def embree_cast(world, pose, sensor, scan, repeat: int):
    """Median seconds for Embree to cast the scan's rays on a surfel mesh, and the share of
    our hits it finds within 5 cm; (None, None) without embreex (pip install embreex)."""
    try:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
    except ImportError:
        print("Embree baseline skipped: pip install embreex")
        return None, None
    centres, normals = world.points, world.index.normals
    radius = world.index.disc_radius.astype(np.float64)[:, None]
    # Two unit vectors in each point's plane.
    helper = np.where(np.abs(normals[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    u = np.cross(normals, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(normals, u)
    a, b = u * radius, v * radius
    corners = [centres - a - b, centres + a - b, centres + a + b, centres - a + b]
    triangles = np.concatenate([np.stack([corners[0], corners[1], corners[2]], axis=1),
                                np.stack([corners[0], corners[2], corners[3]], axis=1)]).astype(np.float32)
    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, triangles)
    dirs = (sensor.directions @ pose[:3, :3].T).astype(np.float32)
    origins = np.repeat(pose[None, :3, 3], len(dirs), axis=0).astype(np.float32)
    scene.run(origins, dirs, output=1)  # builds the BVH
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = scene.run(origins, dirs, output=1)
        times.append(time.perf_counter() - t)
    distance = np.where(out["geomID"] >= 0, out["tfar"], np.inf)
    ours = np.linalg.norm(scan["sensor_points"], axis=1)
    agree = float(np.mean(np.abs(distance[scan["ray"]] - ours) < 0.05))
    return float(np.median(times)), agree


if __name__ == "__main__":
    main()
