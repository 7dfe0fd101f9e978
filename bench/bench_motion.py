"""Benchmark: building a replay's motion (replays/motion.py) from a plan's 100 Hz samples.

Every replay (and every predictor along a plan in the benefit study) builds the sensor's
C2 motion: quintic Hermite polynomials through the samples for x, y and yaw, and for the
height every 10 ms. The baseline is scipy's ``BPoly.from_derivatives`` then
``PPoly.from_bernstein_basis`` (what motion.py used), ours the closed form
``quintic_hermite``. Printed: seconds per construction of each, their ratio, and the largest
difference of value, rate and acceleration between the two at 10,000 random times. Then
``Motion.from_arrays`` whole (ground included) on a straight 60 s drive over a flat map.

    .venv/bin/python bench/bench_motion.py [--seconds 60] [--repeats 3]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.interpolate import BPoly, PPoly

import lf3pm
from lf3pm.replays.motion import Motion, quintic_hermite


def best_of(repeats: int, fn) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeats):
        started = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - started)
    return min(times), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="plan duration (100 Hz samples)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    t = np.arange(int(args.seconds * 100) + 1) / 100.0
    # A smooth drive with a turn: values, rates and accelerations of a known curve.
    p, v, a = np.sin(0.3 * t) * 10, 3 * np.cos(0.3 * t), -0.9 * np.sin(0.3 * t)
    base_s, base = best_of(
        args.repeats, lambda: PPoly.from_bernstein_basis(BPoly.from_derivatives(t, np.column_stack([p, v, a])))
    )
    ours_s, ours = best_of(args.repeats, lambda: quintic_hermite(t, p, v, a))
    at = rng.uniform(t[0], t[-1], 10_000)
    diffs = [float(np.max(np.abs(base(at, k) - ours(at, k)))) for k in range(3)]
    print(f"{len(t)} knots ({args.seconds:g} s at 100 Hz), best of {args.repeats}\n")
    print("| construction | s | ratio |")
    print("|---|---|---|")
    print(f"| scipy BPoly.from_derivatives + from_bernstein_basis (baseline) | {base_s:.4f} | 1 |")
    print(f"| quintic_hermite (closed form) | {ours_s:.5f} | {base_s / ours_s:.0f}x faster |")
    print(f"\nlargest difference: value {diffs[0]:.1e} m, rate {diffs[1]:.1e} m/s, acceleration {diffs[2]:.1e} m/s^2")
    xs, ys = np.meshgrid(np.arange(-5.0, 5.0 + args.seconds, 0.5), np.arange(-5.0, 5.1, 0.5))
    world = lf3pm.load_map(np.column_stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)]))
    zero = np.zeros_like(t)
    motion_s, _ = best_of(
        args.repeats, lambda: Motion.from_arrays(t, t, zero, zero, np.ones_like(t), zero, zero, map=world)
    )
    print(f"Motion.from_arrays, straight {args.seconds:g} s drive (ground fit included): {motion_s:.3f} s")


if __name__ == "__main__":
    main()
