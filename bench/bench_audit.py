"""Benchmark: the metric part of `lf3pm audit` on a real recorded run (issue 42, item 8)
against the same work done with Open3D, SciPy and NumPy directly.

Per audited scan of the real hall run (64 beams, 75-90 k points a scan; its map: the run's
88 scans, 1.2 M points at 5 cm), in one run and interleaved (ours, then the baseline, scan
after scan, each after PAUSE_S idle):

  ours       lf3pm.audit.audit_scan without registration: the recorded points' metric
             (FAST-LIO association on the map), the os1-64 simulated scan there and its
             metric, the predicted error (what `lf3pm audit --no-registration` does a scan);
  baseline   the recorded points to the world, 5-NN from a SciPy cKDTree of the map, PCA
             planes and the metric in NumPy (bench/baseline_pipeline.association_and_metric),
             and the simulated scan by Open3D casting the os1-64's rays on a mesh of the map
             at its own resolution (a square per 10 cm voxel), then the same association.

The ratio baseline / ours carries over between machines, the times do not. q_n of the
recorded scan is printed from both (the same association, so nearly the same number).

    .venv/bin/python bench/bench_audit.py [--every 8] [--threads 2]

The run from ../shared/data/real_hall_run (LF3PM_DATA), skipped when absent.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
from baseline_pipeline import BaselinePipeline, association_and_metric, voxel_mesh

import lf3pm
from lf3pm.audit import audit_scan
from lf3pm.config import DEFAULTS, configured
from lf3pm.runs import Run
from lf3pm.sensors import get_sensor

VOXEL_MESH = 0.1
#: Idle time before each timed part: the other part's worker threads spin on after it
#: (measured at d1f6839: ours 0.13 s a scan right after the baseline, 0.10 s after 0.5 s
#: idle or right after itself), which would charge one pipeline for the other's threads.
PAUSE_S = 0.5


def hall_run() -> Path | None:
    root = Path(os.environ.get("LF3PM_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"))
    run = root / "real_hall_run"
    return run if (run / "poses_tum.txt").is_file() else None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--every", type=int, default=8, help="audit every N-th scan (default 8: 11 scans)")
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    run = hall_run()
    if run is None:
        print("real_hall_run not found under ../shared/data (LF3PM_DATA): skipped")
        return
    config = configured(DEFAULTS, ("scan",), "the benchmark", threads=args.threads)
    sensor = get_sensor("os1-64")
    world = lf3pm.load_map(run, threads=args.threads)
    t = time.perf_counter()
    vertices, triangles = voxel_mesh(world.index.points, world.index.normals, VOXEL_MESH)
    baseline = BaselinePipeline(
        world.index.points, vertices, triangles, sensor.directions, sensor.min_range, sensor.max_range, args.threads
    )
    setup = time.perf_counter() - t
    print(f"{run.name}: map {world.size:,} points; baseline set-up (mesh, Open3D scene, cKDTree) {setup:.1f} s")
    ours_s, base_s, rows = [], [], []
    with Run(run) as opened:
        for scan in opened.scans():
            if scan.index % args.every:
                continue
            time.sleep(PAUSE_S)
            t = time.perf_counter()
            record = audit_scan(world, scan, sensor, config, register=False)
            ours_s.append(time.perf_counter() - t)
            time.sleep(PAUSE_S)
            t = time.perf_counter()
            points = scan.points @ scan.pose[:3, :3].T + scan.pose[:3, 3]
            real = association_and_metric(baseline.tree, world.index.points, points, scan.pose[:3, 3], args.threads)
            baseline.q_n(scan.pose)
            base_s.append(time.perf_counter() - t)
            rows.append((scan.index, len(scan.points), record.real_q_n, real))
    for index, points, ours_q, base_q in rows:
        print(f"  scan {index:2d}: {points:,} points; the recorded scan's q_n ours {ours_q:.4f}, baseline {base_q:.4f}")
    ours, base = np.median(ours_s), np.median(base_s)
    print(f"metric part, median over {len(rows)} scans ({args.threads} threads):")
    print(f"  ours     {ours:.3f} s a scan ({1 / ours:.1f} scans/s)")
    print(f"  baseline {base:.3f} s a scan ({1 / base:.2f} scans/s)")
    print(f"  ratio baseline / ours {base / ours:.1f}x")


if __name__ == "__main__":
    main()
