"""Benchmark: the planner's ESDF against the exact signed distance to the blocked
squares, old (distance between cell centres minus half a cell) and ours
(conservative, planner/esdf.py), both interpolated bilinearly.

Seeded masks of two kinds: "cells" (each cell blocked with a random probability
of 5-50 %, many corners) and "boxes" (five rectangles of 1-5 cells on 24 x 30).
At uniform random points between the centres, the exact distance comes from a
brute force over every square. Prints, in cells: the largest optimism (field
minus exact; ours must be <= 0), the pessimism (exact minus field) by distance
band, and the free centres' pessimism (negative: optimism); then build times on 60 x 236 cells
(the Gobi experiment's size) and 1000 x 1000, the ratio, and the peak resident memory.

    .venv/bin/python bench/bench_esdf.py [--masks 30] [--points 40000]
"""

from __future__ import annotations

import argparse
import resource
import time

import numpy as np
from scipy.ndimage import distance_transform_edt

from lf3pm.planner.esdf import Esdf

BANDS = ((0.0, 0.05), (0.05, 0.5), (0.5, 1.0), (1.0, 2.0), (2.0, 4.0))


def old_values(blocked):
    """The field before: distance between centres, minus (inside plus) half a cell."""
    return np.where(blocked, 0.5 - distance_transform_edt(blocked), distance_transform_edt(~blocked) - 0.5)


def exact_distance(blocked, px, py, chunk=4000):
    """Signed distance in cells to the union of blocked unit squares (inside: to the
    free squares or beyond the grid), by brute force."""
    ny, nx = blocked.shape
    out = np.empty(px.shape)
    for a in range(0, px.size, chunk):
        x, y = px[a : a + chunk, None], py[a : a + chunk, None]

        def nearest(cells):
            if len(cells) == 0:
                return np.full(x.shape[0], np.inf)
            dx = np.maximum(np.maximum(cells[:, 1] - x, x - cells[:, 1] - 1), 0)
            dy = np.maximum(np.maximum(cells[:, 0] - y, y - cells[:, 0] - 1), 0)
            return np.hypot(dx, dy).min(axis=1)

        outside = nearest(np.argwhere(blocked))
        edge = np.minimum.reduce([x[:, 0], nx - x[:, 0], y[:, 0], ny - y[:, 0]])
        inside = np.minimum(nearest(np.argwhere(~blocked)), np.maximum(edge, 0))
        out[a : a + chunk] = np.where(outside > 0, outside, -inside)
    return out


def mask(kind: str, rng):
    if kind == "cells":
        shape = rng.integers(2, 16, 2)
        return rng.random(shape) < rng.uniform(0.05, 0.5)
    blocked = np.zeros((24, 30), bool)
    for _ in range(5):
        y, x = rng.integers(0, 24), rng.integers(0, 30)
        blocked[y : y + rng.integers(1, 6), x : x + rng.integers(1, 6)] = True
    return blocked


def interpolate(values, px, py):
    return Esdf(values, np.zeros(values.shape, bool), np.zeros(values.shape, bool), 0.0, 0.0, 1.0).distance(px, py)[0]


def accuracy(kind: str, masks: int, points: int):
    rng = np.random.default_rng(0)
    optimism = {"old": [-np.inf, -np.inf], "ours": [-np.inf, -np.inf]}  # outside, inside obstacles
    bands = {(name, band): [] for name in optimism for band in BANDS}
    centres = {name: [] for name in optimism}
    for _ in range(masks):
        blocked = mask(kind, rng)
        if blocked.all() or not blocked.any():
            continue
        ny, nx = blocked.shape
        px, py = rng.uniform(0.5, nx - 0.5, points), rng.uniform(0.5, ny - 0.5, points)
        exact = exact_distance(blocked, px, py)
        cy, cx = np.mgrid[0:ny, 0:nx] + 0.5
        at_centres = exact_distance(blocked, cx.ravel(), cy.ravel()).reshape(blocked.shape)
        for name, values in (("old", old_values(blocked)), ("ours", Esdf.from_mask(blocked, 0.0, 0.0, 1.0).values)):
            error = interpolate(values, px, py) - exact
            for side, where in enumerate((exact > 0, exact <= 0)):
                if where.any():
                    optimism[name][side] = max(optimism[name][side], error[where].max())
            for lo, hi in BANDS:
                bands[name, (lo, hi)].append(-error[(exact >= lo) & (exact < hi)])
            centres[name].append((at_centres - values)[~blocked])
    print(
        f"{kind}: largest optimism (field - exact), cells, outside / inside obstacles: "
        f"old {optimism['old'][0]:+.3f} / {optimism['old'][1]:+.3f}, "
        f"ours {optimism['ours'][0]:+.2e} / {optimism['ours'][1]:+.2e}"
    )
    print("  pessimism (exact - field), cells, by exact distance: mean / median / max (old | ours)")
    for lo, hi in BANDS:
        cols = []
        for name in optimism:
            p = np.concatenate(bands[name, (lo, hi)])
            cols.append(f"{p.mean():+.3f} / {np.median(p):+.3f} / {p.max():+.3f}" if p.size else "no points")
        print(f"  [{lo:4.2f}, {hi:4.2f}): " + " | ".join(cols))
    for name in optimism:
        p = np.concatenate(centres[name])
        print(
            f"  free centres, {name}: mean {p.mean():+.3f}, median {np.median(p):+.3f}, "
            f"min {p.min():+.3f}, max {p.max():+.3f}"
        )


def timing(shape, repeat):
    rng = np.random.default_rng(1)
    blocked = np.zeros(shape, bool)
    for _ in range(blocked.size // 350):
        y, x = rng.integers(0, shape[0]), rng.integers(0, shape[1])
        blocked[y : y + rng.integers(1, 6), x : x + rng.integers(1, 6)] = True
    times = {}
    for name, build in (("old", lambda: old_values(blocked)), ("ours", lambda: Esdf.from_mask(blocked, 0, 0, 1.0))):
        start = time.perf_counter()
        for _ in range(repeat):
            build()
        times[name] = (time.perf_counter() - start) / repeat
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"build on {shape[0]} x {shape[1]}: old {times['old'] * 1e3:.1f} ms, ours {times['ours'] * 1e3:.0f} ms, "
        f"ours / old = {times['ours'] / times['old']:.0f}; peak resident so far {peak:.0f} MB"
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--masks", type=int, default=30)
    parser.add_argument("--points", type=int, default=40000)
    args = parser.parse_args()
    for kind in ("cells", "boxes"):
        accuracy(kind, args.masks, args.points)
    timing((60, 236), 3)
    timing((1000, 1000), 1)


if __name__ == "__main__":
    main()
