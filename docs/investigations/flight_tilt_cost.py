"""Issue 43, item 2: what a SOLM at level attitude costs a quadrotor, whose LiDAR tilts with
the body as it accelerates. For random free positions and yaws in each scene, q_n of the
sensor at the attitude a flight forces (lf3pm.flight: the flatness map at a velocity and
acceleration drawn within the default limits) against q_n at level attitude (what an r3yaw
SOLM stores), as the relative error |q_tilted - q_level| / q_level.

Two regimes per mount: "cruise" (speed up to vmax, acceleration up to 1 m/s^2: the tilt
of steady flight and gentle turns) and "limit" (the acceleration's tilt drawn up to the
tilt limit, 0.5 rad). Noise-free casts (seed-independent), seed 0 for the draws.

    .venv/bin/python docs/investigations/flight_tilt_cost.py [--poses 60]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

import lf3pm
from lf3pm.errors import PoseError
from lf3pm.flight import Quadrotor
from lf3pm.scenes import build_scene

MOUNTS = (("top", "mid360"), ("down20", "avia"), ("side", "vlp16"))
SCENES = ("tunnel", "boxes", "houses")
G = 9.81


def draw_state(rng, quad: Quadrotor, regime: str):
    """A velocity and an acceleration within the limits: (v, a)."""
    v = rng.normal(size=3)
    v *= rng.uniform(0, quad.vmax) / np.linalg.norm(v)
    if regime == "cruise":
        a = rng.normal(size=3)
        a *= rng.uniform(0, 1.0) / np.linalg.norm(a)
    else:  # a horizontal acceleration whose tilt is uniform up to the limit
        tilt = rng.uniform(0, quad.tilt_max)
        heading = rng.uniform(0, 2 * math.pi)
        a = G * math.tan(tilt) * np.array([math.cos(heading), math.sin(heading), 0.0])
    return v, a


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--poses", type=int, default=60, help="free poses per scene, mount and regime")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    print("scene   mount   sensor  regime   poses  tilt_med(deg)  err_median  err_p95")
    for scene_name in SCENES:
        scene = build_scene(scene_name)
        world = lf3pm.load_map(scene.points)
        lower, upper = world.bounds
        for mount, sensor_name in MOUNTS:
            quad = Quadrotor(mount=mount)
            sensor = lf3pm.get_sensor(sensor_name)
            for regime in ("cruise", "limit"):
                errors, tilts = [], []
                while len(errors) < args.poses:
                    p = rng.uniform(lower, upper)
                    p[2] = rng.uniform(lower[2] + 1.0, min(upper[2] - 0.5, lower[2] + 4.0))
                    yaw = rng.uniform(0, 2 * math.pi)
                    v, a = draw_state(rng, quad, regime)
                    zero = np.zeros((1, 3))
                    tilted = quad.attitudes(v[None], a[None], zero, [yaw], [0.0])
                    level = quad.attitudes(zero, zero, zero, [yaw], [0.0])
                    try:
                        q = [
                            lf3pm.evaluate(
                                world, quad.sensor_poses(p[None], att)[0], sensor, noise=0.0, clearance=0.5
                            ).q_n
                            for att in (tilted, level)
                        ]
                    except PoseError:
                        continue
                    if not all(math.isfinite(x) and x > 0 for x in q):
                        continue
                    errors.append(abs(q[0] - q[1]) / q[1])
                    tilts.append(math.degrees(tilted.tilt[0]))
                e = np.array(errors)
                print(
                    f"{scene_name:7s} {mount:7s} {sensor_name:7s} {regime:7s} {len(e):6d} {np.median(tilts):13.1f} "
                    f"{np.median(e):11.3f} {np.percentile(e, 95):8.3f}"
                )


if __name__ == "__main__":
    main()
