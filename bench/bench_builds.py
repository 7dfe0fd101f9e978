"""Benchmark: the pinned builds of the core (x86-64-v3, the default; x86-64, the portable
fallback) against -march=native with Eigen vectorised and contractions on, on the same
machine, in one run.

Builds the native core once into build/bench-native (CMake, about a minute on 2 cores;
reused while up to date), then times each build in a child process on the same work:
indexing the 3.36 M-point town of bench_maps.py (plane fits), one VLP-16 scan on it
(casting alone, and cast + k-NN association + metric, one thread), 64 R2 SOLM cells of
the gobi scene (Mid-70, 2 threads) and the 206 m trajectory of bench_planner_backend.py
(omni and car). Prints a table of medians (the best of --rounds interleaved runs) and each
build's time relative to native, and whether the build's numbers equal the pinned
default's (they cannot for native).

    .venv/bin/python bench/bench_builds.py [--repeat 15] [--rounds 2]
"""

from __future__ import annotations

import argparse
import importlib.abc
import importlib.util
import json
import os
import subprocess
import sys
import sysconfig
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NATIVE_BUILD = ROOT / "build" / "bench-native"
LEVELS = ("x86-64-v3", "x86-64", "native")


def build_native() -> None:
    """Configure (once) and build the core with LF3PM_ARCH=native into NATIVE_BUILD."""
    if not (NATIVE_BUILD / "build.ninja").exists():
        subprocess.run(
            [
                "cmake",
                "-S",
                str(ROOT),
                "-B",
                str(NATIVE_BUILD),
                "-G",
                "Ninja",
                "-DLF3PM_ARCH=native",
                f"-DPython_EXECUTABLE={sys.executable}",
                "-DCMAKE_BUILD_TYPE=Release",
            ],
            check=True,
            stdout=subprocess.DEVNULL,
        )
    start = time.perf_counter()
    subprocess.run(["cmake", "--build", str(NATIVE_BUILD)], check=True, stdout=subprocess.DEVNULL)
    print(f"native core built in {NATIVE_BUILD.relative_to(ROOT)} ({time.perf_counter() - start:.0f} s)")


class _BuildFolder(importlib.abc.MetaPathFinder):
    """Finds lf3pm._core's compiled modules in one build folder (the native benchmark build)."""

    def __init__(self, folder: Path):
        self.suffix = sysconfig.get_config_var("EXT_SUFFIX")
        self.folder = folder

    def find_spec(self, name, path=None, target=None):
        prefix = "lf3pm._core."
        candidate = self.folder / (name[len(prefix) :] + self.suffix)
        if name.startswith(prefix) and candidate.exists():
            return importlib.util.spec_from_file_location(name, candidate)
        return None


def child(level: str, repeat: int) -> None:
    """Times the work with the core of `level` and prints one JSON line."""
    if level == "native":
        sys.meta_path.insert(0, _BuildFolder(NATIVE_BUILD))
    os.environ["LF3PM_CORE"] = level
    import hashlib

    import numpy as np
    from bench_maps import town
    from bench_planner_backend import scenario

    import lf3pm
    from lf3pm import _core
    from lf3pm.config import scan_params
    from lf3pm.experiments.free_poses import random_free_poses
    from lf3pm.metric import eval_params
    from lf3pm.solm.tiles import pose_matrices
    from lf3pm.trajectory import Robot, make_problem

    assert _core.ARCH == level, _core.ARCH
    digest = hashlib.sha256()

    def median(fn, times=repeat):
        seconds = []
        for _ in range(times):
            start = time.perf_counter()
            out = fn()
            seconds.append(time.perf_counter() - start)
        return float(np.median(seconds)), out

    points, _ = town()
    out = {"level": level}
    out["index"], world = median(lambda: lf3pm.load_map(points, threads=1), max(1, repeat // 5))
    sensor = lf3pm.get_sensor("vlp16")
    pose = np.eye(4)
    pose[:3, 3] = (0.0, 0.0, 1.8)
    one_thread = scan_params(sensor.min_range, sensor.max_range, threads=1)
    out["cast"], _ = median(lambda: _core.simulate_scan(world.index, pose, sensor.directions, one_thread))
    params = eval_params(sensor.min_range, sensor.max_range, threads=1)
    out["evaluate"], res = median(lambda: _core.evaluate(world.index, pose, sensor.directions, params))
    digest.update(np.float64(res.metric.q_n).tobytes())

    gobi = lf3pm.load_map(lf3pm.build_scene("gobi").points)
    mid70 = lf3pm.get_sensor("mid70")
    poses = np.array(
        random_free_poses(gobi, 64, np.random.default_rng(0), sensor_height=1.0, region=(-40.0, -40.0, 40.0, 40.0))
    )
    matrices = pose_matrices(*poses.T)
    streams = np.arange(len(matrices), dtype=np.uint64)
    cells = eval_params(mid70.min_range, mid70.max_range, threads=2)
    out["solm"], many = median(
        lambda: _core.evaluate_many(gobi.index, matrices, streams, mid70.directions, cells), max(1, repeat // 5)
    )
    digest.update(np.ascontiguousarray(many["q_n"]).tobytes())

    waypoints, cost, esdf = scenario(0)
    for kind, robot in (
        ("omni", Robot("omni", vmax_lon=1.5, vmax_lat=1.0, wmax=1.0)),
        ("car", Robot("car", vmax_lon=1.5, wmax=1.0, min_turn_radius=2.0)),
    ):
        problem = make_problem(waypoints, cost, esdf, robot, samples=16, piece_length=2.0)
        lbfgs = _core.trajectory_lbfgs()
        out[kind], result = median(lambda: problem.optimize(lbfgs), max(3, repeat // 3))
        out[f"{kind}_evaluations"] = result["evaluations"]
        digest.update(np.asarray(result["x"]).tobytes())
    out["digest"] = digest.hexdigest()[:16]
    print(json.dumps(out))


COLUMNS = (
    ("index", "index (1 thread)"),
    ("cast", "VLP-16 cast"),
    ("evaluate", "VLP-16 evaluate"),
    ("solm", "64 gobi cells (Mid-70, 2 threads)"),
    ("omni", "trajectory omni"),
    ("car", "trajectory car"),
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--child", choices=LEVELS, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child, args.repeat)
        return
    build_native()
    # Each build runs in `--rounds` interleaved child processes and keeps its best median
    # per column, so that a slow spell of a shared machine does not favour one build.
    rows = {}
    for _ in range(args.rounds):
        for level in LEVELS:
            run = subprocess.run(
                [sys.executable, __file__, "--child", level, "--repeat", str(args.repeat)],
                check=True,
                capture_output=True,
                text=True,
                cwd=Path(__file__).parent,
            )
            row = json.loads(run.stdout.strip().splitlines()[-1])
            best = rows.setdefault(level, row)
            for key, _ in COLUMNS:
                if row[key] < best[key]:
                    best[key] = row[key]
                    if f"{key}_evaluations" in row:
                        best[f"{key}_evaluations"] = row[f"{key}_evaluations"]
    native = rows["native"]
    print(f"| build | {' | '.join(title for _, title in COLUMNS)} | same numbers as x86-64-v3 |")
    print("|---" * (len(COLUMNS) + 2) + "|")
    for level, row in rows.items():
        cells = [f"{1e3 * row[key]:.1f} ms ({row[key] / native[key]:.2f}x)" for key, _ in COLUMNS]
        for i, (key, _) in enumerate(COLUMNS):
            if f"{key}_evaluations" in row:  # L-BFGS's path differs with the last bits: per evaluation too
                per = row[key] / row[f"{key}_evaluations"]
                ratio = per / (native[key] / native[f"{key}_evaluations"])
                cells[i] += f", {row[f'{key}_evaluations']} evaluations, {1e6 * per:.0f} us each ({ratio:.2f}x)"
        same = "yes" if row["digest"] == rows["x86-64-v3"]["digest"] else "no"
        print(f"| {level} | {' | '.join(cells)} | {same} |")
    print("(time relative to native in brackets)")


if __name__ == "__main__":
    main()
