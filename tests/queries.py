"""Seeded random planning queries on a Planner's map, shared by the planning tests."""

import numpy as np


def random_queries(planner, seed: int, count: int):
    """``count`` seeded (start, goal) pairs 3 m or more apart on cells 0.3 m clear of
    obstacles, with random yaws (as bench/bench_random_queries.py draws them)."""
    g = planner.esdf
    ys, xs = np.nonzero(g.traversable(0.3))
    rng = np.random.default_rng(seed)
    while count:
        i, j = rng.choice(len(xs), 2, replace=False)
        start = (g.x0 + (xs[i] + 0.5) * g.res, g.y0 + (ys[i] + 0.5) * g.res, rng.uniform(-np.pi, np.pi))
        goal = (g.x0 + (xs[j] + 0.5) * g.res, g.y0 + (ys[j] + 0.5) * g.res, rng.uniform(-np.pi, np.pi))
        if np.hypot(start[0] - goal[0], start[1] - goal[1]) >= 3:
            count -= 1
            yield start, goal
