"""Issue 42: real-noise degenerate variants of real_hall_run, written under $OUT/<variant>/.

World frame = the run's reference frame (poses_tum.txt). Planes fitted on all 88 scans
(every 5th point) in the world frame (geom*.py in /tmp/degenerate):
  floor:  z = 0.0451 x - 0.0062 y - 1.5663               (rms 1.3 cm)
  wall A: x =   6.6962 + 0.00848 y - 0.05533 z            (rms 2.1 cm)
  wall B: x = -22.2328 + 0.00780 y - 0.04089 z            (rms 2.4 cm)
The two walls are parallel within ~1 degree, 28.9 m apart, running along world y.
Band along the walls: -8 <= y <= 13 m (world), which excludes the cross walls at
y ~ 15.0 and 18.3 m and the hall's far end at negative y; the trajectory is y in 0..11.

corridor: points within +-0.3 m of wall A or wall B, or within +-0.2 m of the floor,
          and inside the band.
floor:    points within +-0.2 m of the floor and inside the band.
floor_strict: points within +-0.05 m of the floor, inside the band, and more than 1 m from
          both wall planes (drops the walls' bottom strip that 'floor' keeps).
corridor_thin: as corridor with +-0.05 m slabs around both walls and the floor (added
          after 'corridor' kept structure within its +-0.3 m wall slabs: pilasters, recesses).
Usage, from the repository root (the variants go to $OUT, default /tmp/degenerate):

    .venv/bin/python docs/investigations/hall_corridor_variants.py [variant ...]   (default: all four)
    for v in corridor corridor_thin floor floor_strict; do
      .venv/bin/lf3pm audit /tmp/degenerate/$v --map self --sensor os1-64 --every 2 --scan-voxel 0.1 \
          --starts 10 --json -o /tmp/degenerate/$v/out > /tmp/degenerate/$v/audit.json
    done

Kept points go back to each scan's sensor frame, saved as scans/<stamp>.npy (float64);
poses_tum.txt is copied from the original run.
"""

import os
import shutil
import sys
from pathlib import Path

import numpy as np

from lf3pm.runs import Run

SRC = Path(__file__).resolve().parents[3] / "shared" / "data" / "real_hall_run"
OUT = Path(os.environ.get("OUT", "/tmp/degenerate"))
Y_BAND = (-8.0, 13.0)
WALL_HALF, FLOOR_HALF = 0.3, 0.2


def unit_dist(p, n, d):
    """signed distance of points p to plane n.x + d = 0 (n normalised here)"""
    n = np.asarray(n, float)
    s = np.linalg.norm(n)
    return (p @ n + d) / s


def floor_d(p):  # z - (a x + b y + c) = 0
    return unit_dist(p, [-0.0451, 0.0062, 1.0], 1.5663)


def wallA_d(p):  # x - (6.6962 + 0.00848 y - 0.05533 z) = 0
    return unit_dist(p, [1.0, -0.00848, 0.05533], -6.6962)


def wallB_d(p):
    return unit_dist(p, [1.0, -0.00780, 0.04089], 22.2328)


def masks(w):
    band = (w[:, 1] >= Y_BAND[0]) & (w[:, 1] <= Y_BAND[1])
    floor = np.abs(floor_d(w)) <= FLOOR_HALF
    walls = (np.abs(wallA_d(w)) <= WALL_HALF) | (np.abs(wallB_d(w)) <= WALL_HALF)
    strict = (np.abs(floor_d(w)) <= 0.05) & (np.abs(wallA_d(w)) > 1.0) & (np.abs(wallB_d(w)) > 1.0)
    thin = (np.abs(floor_d(w)) <= 0.05) | (np.abs(wallA_d(w)) <= 0.05) | (np.abs(wallB_d(w)) <= 0.05)
    return {
        "corridor_thin": band & thin,
        "corridor": band & (floor | walls),
        "floor": band & floor,
        "floor_strict": band & strict,
    }


def main():
    variants = sys.argv[1:] or ["corridor", "floor", "floor_strict", "corridor_thin"]
    for v in variants:
        (OUT / v / "scans").mkdir(parents=True, exist_ok=True)
        shutil.copyfile(SRC / "poses_tum.txt", OUT / v / "poses_tum.txt")
    stats = {v: [] for v in variants}
    with Run(SRC) as run:
        for s in run.scans():
            T = s.pose
            pts = np.asarray(s.points, dtype=np.float64)
            w = pts @ T[:3, :3].T + T[:3, 3]
            for v, m in masks(w).items():
                if v not in variants:
                    continue
                np.save(OUT / v / "scans" / f"{s.stamp:.6f}.npy", pts[m])
                stats[v].append((len(pts), int(m.sum())))
    for v in variants:
        a = np.array(stats[v])
        print(
            f"{v}: {len(a)} scans, points kept per scan median {np.median(a[:, 1]):.0f} "
            f"(min {a[:, 1].min()}, max {a[:, 1].max()}) of median {np.median(a[:, 0]):.0f}"
        )


if __name__ == "__main__":
    main()
