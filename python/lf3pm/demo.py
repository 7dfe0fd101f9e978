"""`make demo`: the main job end to end, then the metric on real maps.

1. A reduced Gobi scene (115 x 90 m): its Mid-70 SE(2) SOLM, plans from the
   town to the warehouse guided by q_n, q_min, |dx*|, the shipped default and
   none, the MDE along each and localization and LIO replays along them
   (lf3pm.experiments.gobi), in out/gobi/.
2. The LF-3PM metric at a few poses on the real maps in ../shared/data.
out/report.md gathers both; figures are PNGs in out/ and out/gobi/.

    python -m lf3pm.demo --out out
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import shutil
import sys
import time
from pathlib import Path

import numpy as np

from lf3pm.atomic import atomic_write
from lf3pm.experiments.data import shared_data_dir
from lf3pm.map import load_map
from lf3pm.metric import evaluate
from lf3pm.sensors import get_sensor

#: (map file, sensor, poses x y z yaw). Both maps are single scans in their
#: sensor frame. The room scan holds a cluster of returns within 0.2 m of its
#: origin (the scanner's own mount), so its poses keep clear of it.
DEMO_CASES = [
    (
        "indoor_pcl_room_scan1.pcd",
        "vlp16",
        [(1.0, 0.5, 0.0, 0.0), (2.0, 1.0, 0.0, 0.0), (-1.5, 1.5, 0.0, 1.57), (4.0, 0.5, 0.0, 3.14)],
    ),
    (
        "outdoor_urban64_2021-10-26-16-21-29-468.pcd",
        "os1-64",
        [(0.0, 0.0, 0.0, 0.0), (8.0, 0.0, 0.0, 0.0), (-10.0, 0.5, 0.0, 0.0)],
    ),
]


def plot_scan(path: Path, world, result, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from lf3pm.solm.figures import save_figure

    pts = world.points
    step = max(1, len(pts) // 200_000)
    hits = result.observations["points"]
    fig, ax = plt.subplots(figsize=(9, 6), dpi=110)
    from matplotlib.lines import Line2D

    ax.scatter(pts[::step, 0], pts[::step, 1], s=0.2, c="0.6", linewidths=0)
    sc = ax.scatter(hits[:, 0], hits[:, 1], s=0.6, c=hits[:, 2], cmap="viridis", linewidths=0)
    fig.colorbar(sc, ax=ax, label="hit z (m)", shrink=0.8)
    pose = np.asarray(result.pose)
    ax.plot(pose[0, 3], pose[1, 3], "r*", ms=14)
    handles = [
        Line2D([], [], ls="", marker="o", ms=4, color="0.6", label="map"),
        Line2D([], [], ls="", marker="o", ms=4, color="tab:green", label="simulated hits"),
        Line2D([], [], ls="", marker="*", ms=10, color="r", label="sensor"),
    ]
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title, fontsize=10)
    ax.legend(handles=handles, loc="upper right", fontsize=8)
    save_figure(fig, path)


def main() -> None:
    parser = argparse.ArgumentParser(description="lf3pm demo")
    parser.add_argument("--out", type=Path, default=Path("out"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    gobi_report = demo_gobi(args.out / "gobi")
    data = shared_data_dir()
    rows, records = [], []
    for filename, sensor_name, poses in DEMO_CASES:
        t = time.perf_counter()
        world = load_map(data / filename)
        index_s = time.perf_counter() - t
        sensor = get_sensor(sensor_name)
        print(f"{filename}: {world.size:,} points indexed in {index_s:.2f} s; sensor {sensor.name}")
        for i, pose in enumerate(poses):
            t = time.perf_counter()
            res = evaluate(world, pose, sensor, seed=0, observations=(i == 0))
            ms = (time.perf_counter() - t) * 1e3
            if i == 0:
                png = args.out / f"scan_{Path(filename).stem}.png"
                plot_scan(
                    png, world, res, f"{filename}: {sensor.name} scan at {pose}, q_n = {res.q_n:.4g}, m = {res.m}"
                )
            rows.append((filename, sensor.name, pose, res, ms))
            records.append({"map": filename, "pose": list(pose), "ms": ms, **res.to_dict()})
    header = (
        "| map | sensor | pose x y z yaw | m | sigma1 | q_min | q_n | q_max | "
        "cond | ms |\n|---|---|---|---|---|---|---|---|---|---|"
    )
    lines = [header] + [
        f"| {f} | {s} | {' '.join(f'{v:g}' for v in p)} | {r.m} | {r.sigma1:.4g} | {r.q_min:.4g} | "
        f"{r.q_n:.4g} | {r.q_max:.4g} | {r.condition_number:.4g} | {ms:.1f} |"
        for f, s, p, r, ms in rows
    ]
    table = "\n".join(lines)
    print(table)
    report = args.out / "report.md"
    with atomic_write(report) as fp:
        fp.write(
            (
                "# lf3pm demo\n\n## 1. Perception-aware planning on a reduced Gobi scene\n\n"
                + gobi_report.split("\n", 1)[1]
                + "\nFigures: gobi/trajectories.png (plans over the SOLM), gobi/along.png (MDE, "
                "localization and LIO error along them), gobi/solm_q_n.png.\n\n"
                "## 2. The LF-3PM metric on real maps\n\n"
                "Noise: each sensor's range noise, seed 0; association: FAST-LIO k-NN (k = 5); "
                "w1 = w2 = 0.5; no scan downsampling.\n\n" + table + "\n"
            ).encode()
        )
    with atomic_write(args.out / "report.json") as fp:
        fp.write(json.dumps(records, indent=1).encode())
    print(
        f"wrote {report}, {args.out / 'report.json'}, figures in {args.out}/ and {args.out / 'gobi'}/ "
        f"in {time.perf_counter() - started:.0f} s"
    )
    print(f"look at them in 3D (docs/view.md): {view_command(args.out / 'gobi')}")


def view_command(gobi: Path) -> str:
    """The `lf3pm view` command line of the demo's Gobi outputs in ``gobi``, runnable as
    printed from the folder the demo ran in (:func:`cli_command`)."""
    return (
        cli_command()
        + " "
        + shlex.join(
            [
                "view",
                str(gobi / "map.npy"),
                "--solm",
                str(gobi / "solm.zarr"),
                "--plan",
                str(gobi / "trajectories/default.csv"),
                "--plan",
                str(gobi / "trajectories/none.csv"),
                "--replay",
                str(gobi / "replays/default_localization_0.json"),
            ]
        )
    )


def cli_command() -> str:
    """How to run this Python's `lf3pm` from the current folder: ``lf3pm`` where that is
    the one on PATH, else its path (``.venv/bin/lf3pm`` after `make`, which puts nothing
    on PATH), else ``python -m lf3pm``."""
    beside = Path(sys.executable).parent / "lf3pm"  # not resolved: a venv's python is a link out of it
    found = shutil.which("lf3pm")
    if found is not None and Path(found).resolve() == beside.resolve():
        return "lf3pm"
    if beside.is_file():
        relative = os.path.relpath(beside)
        return shlex.quote(relative if os.sep in relative else os.path.join(os.curdir, relative))
    return f"{shlex.quote(sys.executable)} -m lf3pm"


def demo_gobi(out: Path) -> str:
    """The reduced Gobi experiment from scratch (its SOLM and replays redone); returns its table."""
    import shutil

    from lf3pm.experiments import gobi
    from lf3pm.solm import Solm
    from lf3pm.solm.figures import heat_map

    for stale in ("solm.zarr", "replays"):
        shutil.rmtree(out / stale, ignore_errors=True)
    t = time.perf_counter()
    gobi.run(out, gobi.REDUCED, progress=_print_phases())
    heat_map(Solm.open(out / "solm.zarr"), out / "solm_q_n.png", channel="q_n", reduce="min")
    print(f"reduced Gobi experiment in {time.perf_counter() - t:.0f} s -> {out}/")
    table = (out / "gobi.md").read_text()
    print(table)
    return table


def _print_phases():
    """A progress callback printing each new phase once (the demo runs without a terminal bar)."""
    seen = set()

    def step(label, total, advance=1, restart=False):
        if label not in seen:
            seen.add(label)
            print(f"  {label}", flush=True)

    return step


if __name__ == "__main__":
    main()
