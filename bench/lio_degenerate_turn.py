"""Why the LIO fails on the orientation scene's plans, guided or not (docs/lio.md).

1. The benefit study's guided omni plans (pairs 0 and 4, seeds 0 and 1), one change at
   a time: as planned; with the yaw they reach after 4 s held from the start (no start
   turn); a turn in place at rest to that yaw first, then the plan.
2. Isolated: a Mid-70 on a robot that stands still and turns in place, 20 m out from
   the building, replayed by the LIO (GenZ-LIO, the Mid-70's default) noise-free and
   with default noise (seed 0), starting from a view of bare ground or of the building;
   the same IMU stream integrated by a float64 strapdown (tests/test_imu.py) as the
   check that the stream itself is exact under the turn.

    .venv/bin/python -m lf3pm experiment benefit -o out/benefit     # the plans (part 1)
    .venv/bin/python bench/lio_degenerate_turn.py [out/benefit]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import lf3pm
from lf3pm.experiments.benefit import CASES as STUDY_MAPS
from lf3pm.experiments.map_cases import load_case_map
from lf3pm.replays.imu import simulate_imu
from lf3pm.replays.motion import Motion
from lf3pm.trajectory.trajectory import read_csv

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_imu import strapdown  # noqa: E402  (the suite's float64 reference)

#: The guided omni plans of part 1 and the time by which their start turn is done (s).
PLANS = ("00_omni_default", "04_omni_default")
SETTLED_S = 4.0
#: (start yaw, end yaw) in radians: yaw 0 faces open ground, about pi the building.
TURNS = {
    "ground in view, no turn": (0.0, 0.0),
    "ground in view, turn to the building": (0.0, -2.8),
    "building in view, turn to ground": (-2.8, 0.0),
    "building in view, turn 46 deg within view": (-2.8, -2.0),
}
TURN_S, HOLD_S = 6.0, 4.0


def smooth(a: float, b: float, count: int) -> np.ndarray:
    """``count`` samples from a to b on a cosine profile (zero rate at both ends)."""
    return a + (b - a) * (0.5 - 0.5 * np.cos(np.linspace(0.0, np.pi, count)))


def plan_variants(world, csv: Path) -> dict:
    """Part 1's three motions of one plan."""
    s = read_csv(csv)
    t, x, y, vx, vy = (np.asarray(s[k], float) for k in ("t", "x", "y", "vx", "vy"))
    yaw = np.unwrap(np.asarray(s["yaw"], float))
    settled = yaw[int(np.searchsorted(t, SETTLED_S))]
    held = np.where(t < SETTLED_S, settled, yaw)
    count = int(abs(settled - yaw[0]) / 0.5 * 100) + 1  # in place at 0.5 rad/s on average, 100 Hz
    first = np.linspace(0.0, (count - 1) / 100, count)
    arrays = {
        "as planned": (t, x, y, yaw, vx, vy),
        "no start turn": (t, x, y, held, vx, vy),
        "turn in place first": (
            np.concatenate([first, first[-1] + 0.01 + t]),
            np.concatenate([np.full(count, x[0]), x]),
            np.concatenate([np.full(count, y[0]), y]),
            np.concatenate([smooth(yaw[0], settled, count), held]),
            np.concatenate([np.zeros(count), vx]),
            np.concatenate([np.zeros(count), vy]),
        ),
    }
    return {
        label: Motion.from_arrays(tt, xx, yy, ww, ux, uy, np.gradient(ww, tt), map=world, height=1.0)
        for label, (tt, xx, yy, ww, ux, uy) in arrays.items()
    }


def turn_in_place(world, yaw0: float, yaw1: float) -> Motion:
    """Still at (20, 0) while the yaw goes from yaw0 to yaw1 (cosine profile over TURN_S),
    then HOLD_S still."""
    t = np.arange(0.0, TURN_S + HOLD_S, 0.01)
    s = np.clip(t / TURN_S, 0.0, 1.0)
    yaw = yaw0 + (yaw1 - yaw0) * (0.5 - 0.5 * np.cos(np.pi * s))
    still = np.zeros_like(t)
    return Motion.from_arrays(t, still + 20.0, still, yaw, still, still, np.gradient(yaw, t), map=world, height=1.0)


def main() -> None:
    world, _ = load_case_map(next(case for case in STUDY_MAPS if case.name == "orientation"))
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "out/benefit") / "trajectories" / "orientation"
    if folder.is_dir():
        for name in PLANS:
            for label, motion in plan_variants(world, folder / f"{name}.csv").items():
                ape = [lf3pm.replay(world, motion, "mid70", "lio", seed=seed).ape["rmse"] for seed in (0, 1)]
                print(f"{name} {label:20s} LIO APE seeds 0, 1: {ape[0]:.3f} {ape[1]:.3f} m", flush=True)
    else:
        print(f"{folder} not found: part 1 skipped (run the benefit study first)")
    print("| start view, motion | strapdown of the IMU (max, m) | LIO APE noise-free (m) | LIO APE default noise (m) |")
    print("|---|---:|---:|---:|")
    for label, (yaw0, yaw1) in TURNS.items():
        motion = turn_in_place(world, yaw0, yaw1)
        imu = simulate_imu(motion, noise=False)
        positions, _ = strapdown(
            imu, motion.position(imu.t[0])[0], motion.velocity(imu.t[0])[0], motion.pose(imu.t[0])[0][:3, :3]
        )
        drift = np.abs(positions - motion.position(imu.t)).max()
        ape = [lf3pm.replay(world, motion, "mid70", "lio", seed=0, noise=noise).ape["rmse"] for noise in (0.0, None)]
        print(f"| {label} | {drift:.1e} | {ape[0]:.3f} | {ape[1]:.3f} |", flush=True)


if __name__ == "__main__":
    main()
