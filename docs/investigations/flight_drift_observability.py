"""Issue 43, item 7: why the first flight study's risk rule called no drift pair at risk
although both LIOs lost 15-56 m along its featureless drift. The drift is a tube with no
surface facing along x, so A's x column (the normals' x components) should be ~0 and q_n
unbounded; the SOLM read 6-9x the map's median. This casts the study's sensor (VLP-16
pitched 20 degrees down, level body) mid-drift and reports where A's x information comes
from, then changes one thing, the plane validity threshold of the association (map section
`plane_threshold`, FAST-LIO's 0.1 m), to see whether that information goes with it.

    .venv/bin/python docs/investigations/flight_drift_observability.py
"""

from __future__ import annotations

import numpy as np

import lf3pm
from lf3pm.flight.mounts import MOUNTS
from lf3pm.pose import pose_matrix
from lf3pm.scenes import build_scene

POSE = (0.0, 0.0, 1.5, 0.0)  # mid-drift, 1.5 m up, looking along +x


def main() -> None:
    sensor_pose = pose_matrix(POSE) @ MOUNTS["down20"].matrix()
    for jitter in (None, 0.0):
        scene = build_scene("drift") if jitter is None else build_scene("drift", jitter=jitter)
        for threshold in (0.1, 0.05, 0.02, 0.01):
            world = lf3pm.load_map(scene.points, plane_threshold=threshold)
            e = lf3pm.evaluate(world, sensor_pose, "vlp16", noise=0.0, observations=True)
            a, hits = e.observations["A"], e.observations["points"]
            nx2 = a[:, 0] ** 2
            top = np.argsort(nx2)[-max(1, len(nx2) // 100) :]
            corner = (np.abs(np.abs(hits[top, 1]) - 2.0) < 0.1) & (hits[top, 2] < 0.3)
            print(
                f"jitter {'scene default' if jitter is None else jitter}, plane_threshold {threshold}: rows {e.m}, "
                f"sigma1 {e.sigma1:.3g}, q_n {e.q_n:.3g}, least observable {np.round(e.least_observable[:3], 2)}; "
                f"sum of n_x^2 {nx2.sum():.2f}, of it the top 1 % of rows {nx2[top].sum() / nx2.sum():.0%} "
                f"(|n_x| {np.abs(a[top, 0]).min():.2f}-{np.abs(a[top, 0]).max():.2f}), "
                f"{corner.mean():.0%} of those at the floor-wall corners"
            )


if __name__ == "__main__":
    main()
