"""Benchmark suite: one full evaluation (cast + associate + metric) against Embree
casting the same rays, on maps of different character (bench_maps.py), per sensor and
sensor height, on one core.

Per map, sensor and height, at each of the map's sensor positions, in one run and
interleaved (ours, then Embree, round after round; medians):
  cast         lf3pm's surfel caster alone (no range noise);
  association  k-NN association, plane fits, observation rows and their Gram
               (the full evaluation less the cast and the metric);
  metric       q_min/q_n/q_max and the baselines from the Gram (eigen-decompositions);
  evaluate     the core's full evaluation; api: what lf3pm.evaluate(map, pose, "name")
               spends outside the core (timed with the core's call answering at once);
  Embree       embreex (Embree 4, one thread) casting the same rays on a mesh of the
               same surfaces at the map's own resolution: one square of two triangles
               per map point, centred on it, in its neighbourhood plane, as wide as its
               disc (2 triangles per point; Embree's hits lie within 5 cm of ours for the
               share printed as "agree": its squares are not our discs).
Ratios are ours / Embree's: they carry over between machines, the times do not.

    .venv/bin/python bench/bench_evaluate.py [--maps town,street] [--sensors vlp16]
        [--heights 0.5,1.0] [--repeat 10] [--markdown out/bench_evaluate.md]

Embree from `pip install embreex` (`make bench` installs it); real maps from
../shared/data (LF3PM_DATA), skipped when absent.
"""

from __future__ import annotations

import argparse
import importlib
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from bench_maps import MAPS, ground_height
from common import chosen_maps

import lf3pm
from lf3pm import _core
from lf3pm.config import MetricConfig, ScanConfig, scan_params
from lf3pm.pose import pose_matrix

SENSORS = ("vlp16", "os1-64", "mid70")
HEIGHTS = (0.5, 1.0)


def embree_scene(world):
    """Embree's scene of the map's surfels (see the module docstring), or None without embreex."""
    try:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
    except ImportError:
        return None
    centres, normals = world.points, world.index.normals
    radius = world.index.disc_radius.astype(np.float64)[:, None]
    helper = np.where(np.abs(normals[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    u = np.cross(normals, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    a, b = u * radius, np.cross(normals, u) * radius
    corners = [centres - a - b, centres + a - b, centres + a + b, centres - a + b]
    triangles = np.concatenate(
        [np.stack([corners[0], corners[1], corners[2]], axis=1), np.stack([corners[0], corners[2], corners[3]], axis=1)]
    ).astype(np.float32)
    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, triangles)
    return scene


def api_overhead(world, pose, sensor_name: str, result) -> float:
    """Seconds lf3pm.evaluate(world, pose, sensor_name) spends outside the core: the call
    timed with the core's evaluate answering at once (with `result`)."""
    module = importlib.import_module("lf3pm.metric")
    core = module._core
    module._core = SimpleNamespace(evaluate=lambda *args: result)
    try:
        t = time.perf_counter()
        lf3pm.evaluate(world, pose, sensor_name, noise=0.0, threads=1)
        return time.perf_counter() - t
    finally:
        module._core = core


def measure(world, scene, sensor, pose: np.ndarray, repeat: int) -> dict:
    """Median seconds of each stage at one pose (see the module docstring)."""
    directions = sensor.directions
    cast_params = scan_params(sensor.min_range, sensor.max_range, threads=1)
    eval_params = MetricConfig().core(ScanConfig(noise=0.0, threads=1).core(sensor))
    api_pose = np.asarray(pose)
    dirs32 = (directions @ pose[:3, :3].T).astype(np.float32)
    origins = np.repeat(pose[None, :3, 3], len(directions), axis=0).astype(np.float32)
    scan = _core.simulate_scan(world.index, pose, directions, cast_params)
    gram_result = _core.evaluate_with_observations(world.index, pose, directions, eval_params)[1]
    gram = _core.gram(gram_result["A"], gram_result["b"])
    times = {k: [] for k in ("cast", "evaluate", "metric", "api", "embree")}
    if scene is not None:
        scene.run(origins, dirs32, output=1)  # builds the BVH outside the timing
    for _ in range(repeat):
        t0 = time.perf_counter()
        _core.simulate_scan(world.index, pose, directions, cast_params)
        t1 = time.perf_counter()
        result = _core.evaluate(world.index, pose, directions, eval_params)
        t2 = time.perf_counter()
        _core.metric_from_gram(gram, result.metric.m)
        t3 = time.perf_counter()
        t4 = t3 + api_overhead(world, api_pose, sensor.name, result)
        times["cast"].append(t1 - t0)
        times["evaluate"].append(t2 - t1)
        times["metric"].append(t3 - t2)
        times["api"].append(t4 - t3)
        if scene is not None:
            t5 = time.perf_counter()
            out = scene.run(origins, dirs32, output=1)
            times["embree"].append(time.perf_counter() - t5)
    med = {k: float(np.median(v)) if v else float("nan") for k, v in times.items()}
    med["association"] = med["evaluate"] - med["cast"] - med["metric"]
    med["hits"] = int(result.hits)
    med["rays"] = len(directions)
    med["agree"] = float("nan")
    if scene is not None:
        distance = np.where(out["geomID"] >= 0, out["tfar"], np.inf)
        ours = np.linalg.norm(scan["sensor_points"], axis=1)
        med["agree"] = float(np.mean(np.abs(distance[scan["ray"]] - ours) < 0.05))
    return med


def run_map(name: str, sensors, heights, repeat: int) -> list[dict]:
    spec = MAPS[name]
    try:
        points, positions = spec.build()
    except FileNotFoundError as exc:
        print(f"{name}: skipped ({exc})")
        return []
    t = time.perf_counter()
    world = lf3pm.load_map(points, threads=0)
    index_s = time.perf_counter() - t
    scene = embree_scene(world)
    if scene is None:
        print("Embree baseline skipped: pip install embreex")
    print(
        f"{name}: {world.size:,} points, indexed in {index_s:.1f} s ({world.index.memory_bytes / 2**20:.0f} MiB)",
        flush=True,
    )
    rows = []
    for sensor_name in sensors:
        sensor = lf3pm.get_sensor(sensor_name)
        for height in heights:
            per_pose = [
                measure(
                    world, scene, sensor, pose_matrix((x, y, ground_height(world.points, (x, y)) + height, 0.0)), repeat
                )
                for x, y in positions
            ]
            keys = ("cast", "association", "metric", "evaluate", "api", "embree")
            row = {k: float(np.sum([p[k] for p in per_pose])) for k in keys}
            row.update(
                map=name,
                points=world.size,
                sensor=sensor_name,
                height=height,
                poses=len(per_pose),
                rays=sum(p["rays"] for p in per_pose),
                hits=sum(p["hits"] for p in per_pose),
                agree=float(np.mean([p["agree"] for p in per_pose])),
            )
            rows.append(row)
            print(format_row(row), flush=True)
    return rows


HEADER = (
    "| map | points | sensor | height (m) | hits / rays | cast (ms) | association (ms) | metric (µs) | "
    "Embree (ms) | cast / Embree | evaluate / Embree | api overhead (ms) | agree |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
)


def format_row(r: dict) -> str:
    n = r["poses"]
    return (
        f"| {r['map']} | {r['points'] / 1e6:.2f} M | {r['sensor']} | {r['height']:.1f} | "
        f"{r['hits'] / r['rays']:.0%} of {r['rays'] // n:,} | {r['cast'] / n * 1e3:.1f} | "
        f"{r['association'] / n * 1e3:.1f} | {r['metric'] / n * 1e6:.0f} | {r['embree'] / n * 1e3:.1f} | "
        f"**{r['cast'] / r['embree']:.2f}×** | **{r['evaluate'] / r['embree']:.2f}×** | "
        f"{r['api'] / n * 1e3:.2f} | {r['agree']:.1%} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", default=",".join(MAPS), help=f"comma-separated, of {', '.join(MAPS)}")
    parser.add_argument("--sensors", default=",".join(SENSORS))
    parser.add_argument("--heights", default=",".join(map(str, HEIGHTS)), help="sensor heights above ground (m)")
    parser.add_argument("--repeat", type=int, default=10)
    parser.add_argument("--markdown", type=Path, help="also write the table here")
    args = parser.parse_args()
    maps = chosen_maps(parser, args.maps, MAPS)
    heights = [float(h) for h in args.heights.split(",")]
    print(HEADER)
    rows = [row for name in maps for row in run_map(name, args.sensors.split(","), heights, args.repeat)]
    worst_cast = max(rows, key=lambda r: r["cast"] / r["embree"])
    worst_eval = max(rows, key=lambda r: r["evaluate"] / r["embree"])
    summary = (
        f"\nworst cast / Embree {worst_cast['cast'] / worst_cast['embree']:.2f}x "
        f"({worst_cast['map']}, {worst_cast['sensor']} at {worst_cast['height']} m); "
        f"worst evaluate / Embree {worst_eval['evaluate'] / worst_eval['embree']:.2f}x "
        f"({worst_eval['map']}, {worst_eval['sensor']} at {worst_eval['height']} m); "
        f"api overhead at most {max(r['api'] / r['poses'] for r in rows) * 1e3:.2f} ms"
    )
    print(summary)
    if args.markdown:
        args.markdown.parent.mkdir(parents=True, exist_ok=True)
        args.markdown.write_text("\n".join([HEADER, *map(format_row, rows)]) + "\n" + summary + "\n")


if __name__ == "__main__":
    main()
