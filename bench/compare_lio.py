"""Comparison behind lf3pm.replays.lio's choice: GenZ-LIO 0.1.1 (through
run_lio, as the replay uses it) and RKO-LIO 0.4.0 (an adapter below) on the
same simulated scans and IMU samples.

Scenarios (10 Hz motion-distorted scans, 200 Hz BMI088 IMU, each from rest to
rest; motions from tests/analytic_motion.py):

- boxes: the boxes room, VLP-16, an 18 s figure of eight (tangent heading);
- gobi_turn: the reduced gobi scene, Mid-70, 44 s from the town square east
  between the buildings and an 82 deg left turn out into the desert;
- gobi_yaw: the reduced gobi scene, Mid-70, 23 s east through the town with
  the sensor yawing +-69 deg about the direction of travel (an omni robot).

Each runs noise-free (scans and IMU) and noisy (the sensor's range noise, the
BMI088 preset, seed 0). Printed per run: APE translation RMSE and max (no
alignment, the estimate anchored at the true first pose), ms per scan of the
odometry alone (one thread), scans the odometry lost or refused, and whether a
second run gave bitwise the same poses. RKO-LIO is run with its default voxel
(1 m) and with 0.25 m. RKO-LIO is not an lf3pm dependency:

    .venv/bin/pip install rko-lio==0.4.0      # for this comparison only
    .venv/bin/python bench/compare_lio.py [--scenarios boxes gobi_turn gobi_yaw]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.ndimage import gaussian_filter1d

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from analytic_motion import CurveMotion, Lissajous, TangentHeading, Warp  # noqa: E402

import lf3pm  # noqa: E402
from lf3pm.experiments.free_poses import GroundGrid  # noqa: E402
from lf3pm.replays.imu import simulate_imu  # noqa: E402
from lf3pm.replays.lio import run_lio  # noqa: E402
from lf3pm.replays.trajectory_metrics import ape_translation  # noqa: E402
from lf3pm.scan.moving_scan import simulate_moving_scan  # noqa: E402
from lf3pm.scenes import build_scene  # noqa: E402
from lf3pm.sensors import get_sensor  # noqa: E402
from lf3pm.trajectory.sampling import LinearMotion  # noqa: E402

PERIOD = 0.1
GOBI = dict(length=115.0, width=90.0, west=25.0, town_radius=25.0, warehouse_distance=60.0, buildings=4, stones=150)


@dataclass(frozen=True)
class Scan:
    end: float
    points: np.ndarray
    stamps: np.ndarray


class GroundSpline:
    """A natural cubic spline through x-y waypoints (parameter: chord length in
    m) at ``height`` above the ground, smoothed over about 3 m."""

    def __init__(self, xy, ground: GroundGrid, height=1.0):
        xy = np.asarray(xy, dtype=np.float64)
        u = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))]
        self.length = float(u[-1])
        self.xy = CubicSpline(u, xy, bc_type="natural")
        grid = np.linspace(0.0, self.length, int(self.length / 0.25) + 1)
        z = gaussian_filter1d([ground.height(x, y) for x, y in self.xy(grid)], 12.0, mode="nearest")
        self.z = CubicSpline(grid, z + height, bc_type="natural")

    def __call__(self, u, nu):
        u = np.clip(u, 0.0, self.length)
        return np.column_stack([self.xy(u, nu), self.z(u, nu)])


def scenario(name):
    """(map, motion, sensor) of a scenario (module docstring)."""
    if name == "boxes":
        world = lf3pm.load_map(build_scene("boxes").points, threads=1)
        curve = Lissajous((5.5, -0.5, 1.0), (1.2, 0.9, 0.0), (0.5, 1.0, 1.0))
        return world, CurveMotion(Warp(1.0, 2.0, 12.0, 1.0), curve, TangentHeading(curve)), get_sensor("vlp16")
    world = lf3pm.load_map(build_scene("gobi", **GOBI).points, threads=1)
    if name == "gobi_turn":
        xy, swing, rate = [(0, 0), (8, 2.5), (18, 3.5), (26, 8), (30, 18), (32, 30), (33, 40)], 0.0, 0.0
    else:
        xy, swing, rate = [(0, 0), (10, 2.5), (20, 3.0), (28, 5.0)], 1.2, 0.5
    curve = GroundSpline(xy, GroundGrid(world))
    speed = 1.5
    motion = CurveMotion(
        Warp(1.0, 2.0, curve.length / speed - 2.0, speed), curve, TangentHeading(curve, swing=swing, swing_rate=rate)
    )
    return world, motion, get_sensor("mid70")


def make_scans(world, motion, sensor, noise):
    t, poses = motion.samples(1000.0)
    scans = []
    for k in range(int(math.floor((motion.t1 - motion.t0) / PERIOD + 1e-9))):
        end = motion.t0 + (k + 1) * PERIOD
        s = simulate_moving_scan(
            world.index,
            LinearMotion(t, poses),
            end,
            PERIOD,
            sensor.scan_directions(k),
            sensor.min_range,
            sensor.max_range,
            noise=noise,
            seed=0,
            stream=k,
            threads=1,
        )
        scans.append(Scan(end, s.points, end - (1.0 - s.timestamps) * PERIOD))
    return scans


def genz(scans, imu, sensor, first, threads=1):
    """GenZ-LIO through run_lio: (poses, ms per scan, lost scans)."""
    estimate = run_lio(scans, imu, sensor, initial_pose=first, odometry="genz", threads=threads)
    return estimate.poses, 1e3 * estimate.seconds_per_scan, len(estimate.lost)


def rko(scans, imu, sensor, first, voxel_size=1.0):
    """RKO-LIO 0.4.0: IMU samples (absolute ns; RKO-LIO reads time 0 as "no scan
    yet", hence the 1 s offset) up to each scan's end, then the scan with
    absolute per-point ns; deskewed to end_time_ns. (poses, ms per scan, scans
    it refused with an exception)."""
    from rko_lio import LIO
    from rko_lio.config import LIOConfig

    lio = LIO(
        LIOConfig(voxel_size=voxel_size, max_range=sensor.max_range, min_range=sensor.min_range, max_num_threads=1)
    )
    origin = min(imu.t[0], scans[0].stamps.min())

    def ns(t):
        return np.round((np.asarray(t) - origin) * 1e9).astype(np.int64) + 1_000_000_000

    j, poses, refused, seconds = 0, [], 0, 0.0
    for scan in scans:
        while j < len(imu.t) and imu.t[j] <= scan.end:
            lio.add_imu_measurement(imu.accel[j], imu.gyro[j], int(ns(imu.t[j])))
            j += 1
        start = time.perf_counter()
        try:
            lio.register_scan(
                scan.points, ns(scan.stamps), start_time_ns=int(ns(scan.stamps[0])), end_time_ns=int(ns(scan.end))
            )
        except Exception:  # noqa: BLE001 -- RKO-LIO raises InputError / RuntimeError on a scan it cannot use
            refused += 1
        seconds += time.perf_counter() - start
        poses.append(np.array(lio.pose()))
    poses = np.array(poses)
    return first @ np.linalg.inv(poses[0]) @ poses, 1e3 * seconds / len(scans), refused


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", nargs="+", default=["boxes", "gobi_turn", "gobi_yaw"])
    args = parser.parse_args()
    try:
        import rko_lio  # noqa: F401

        have_rko = True
    except ImportError:
        have_rko = False
        print("rko-lio is not installed (pip install rko-lio==0.4.0): GenZ-LIO only")
    backends = [("genz-lio", genz, {})]
    if have_rko:
        backends += [("rko-lio", rko, {}), ("rko-lio voxel 0.25", rko, {"voxel_size": 0.25})]
    print(
        f"{'scenario':10} {'odometry':19} {'data':6} {'rmse m':>7} {'max m':>7} {'ms/scan':>8} {'lost':>5} {'same':>5}"
    )
    for name in args.scenarios:
        world, motion, sensor = scenario(name)
        first_time = motion.t0 + PERIOD
        first = motion.pose(np.array([first_time]))[0]
        for noisy in (False, True):
            scans = make_scans(world, motion, sensor, sensor.range_noise_sigma if noisy else 0.0)
            imu = simulate_imu(motion, noise=noisy, seed=0)
            truth = motion.pose(np.array([s.end for s in scans]))
            for label, run, kwargs in backends:
                poses, ms, lost = run(scans, imu, sensor, first, **kwargs)
                same = np.array_equal(poses, run(scans, imu, sensor, first, **kwargs)[0])
                ape = ape_translation(truth, poses)
                print(
                    f"{name:10} {label:19} {'noisy' if noisy else 'clean':6} {ape['rmse']:7.3f} "
                    f"{ape['max']:7.3f} {ms:8.1f} {lost:5d} {str(same):>5}",
                    flush=True,
                )
        if name == "gobi_yaw":
            # Two OpenMP threads: faster, still deterministic?
            poses, ms, _ = genz(scans, imu, sensor, first, threads=2)
            same = np.array_equal(poses, genz(scans, imu, sensor, first, threads=2)[0])
            print(
                f"{name:10} {'genz-lio 2 threads':19} {'noisy':6} "
                f"{ape_translation(truth, poses)['rmse']:7.3f} {'':7} {ms:8.1f} {'':5} {str(same):>5}"
            )


if __name__ == "__main__":
    main()
