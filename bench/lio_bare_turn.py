"""Does a turn cost the LIO more over bare ground than in view of structure? (docs/lio.md)

The benefit study's guided diff plans on the ``field`` scene bend towards the row of
buildings and back, and some of them end farther off under the LIO than the straight
unguided plans. This isolates the turn: one straight drive along y = 4 m from x = -30 to
x = 40 (1 m/s, C2 speed ramps of 2 s, from and to rest), the Mid-70 at 1 m, heading east;
facing east it sees the row until x = 0 and bare ground after it. Only the yaw differs:

- ``straight``: yaw 0 all the way;
- ``S-turn in view``: 0 -> +25 deg (towards the row) -> 0 over 10 m centred at x = -15,
  with the row in view throughout;
- ``S-turn over bare ground``: the same turn centred at x = 25, past the row's end.

Each is replayed by the LIO (the Mid-70's default odometry) noise-free (range noise 0,
exact IMU) and with default noise on seeds 0-2: APE rmse, and the error at the end.

    .venv/bin/python bench/lio_bare_turn.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from analytic_motion import Warp  # noqa: E402

import lf3pm  # noqa: E402
from lf3pm.experiments.benefit import CASES as STUDY_MAPS  # noqa: E402
from lf3pm.experiments.map_cases import load_case_map  # noqa: E402
from lf3pm.replays.motion import Motion  # noqa: E402

Y, X0, X1, SPEED, RAMP_S = 4.0, -30.0, 40.0, 1.0, 2.0
TURN_DEG, TURN_LENGTH = 25.0, 10.0
VARIANTS = {"straight": None, "S-turn in view": -15.0, "S-turn over bare ground": 25.0}
SEEDS = (0, 1, 2)


def distance_profile(dt: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """(t, s): distance along the drive from rest to rest, the speed ramped by a quintic
    smoothstep over RAMP_S at both ends (continuous acceleration)."""
    warp = Warp(0.0, RAMP_S, (X1 - X0) / SPEED - RAMP_S, SPEED)
    t = np.arange(0.0, warp.t1 + dt / 2, dt)
    return t, warp(t)[0]


def motion(world, centre: float | None) -> Motion:
    """The drive with an S-turn of TURN_DEG centred at x = ``centre`` (None: no turn)."""
    t, s = distance_profile()
    x = X0 + s
    yaw = np.zeros_like(x)
    if centre is not None:
        phase = np.clip((x - centre) / TURN_LENGTH + 0.5, 0.0, 1.0)
        yaw = np.radians(TURN_DEG) * np.sin(np.pi * phase) ** 2
    return Motion.from_arrays(t, x, np.full_like(x, Y), yaw, map=world, height=1.0)


def main() -> None:
    world, _ = load_case_map(next(case for case in STUDY_MAPS if case.name == "field"))
    print("| variant | noise-free APE / end error (m) | default noise, seeds 0-2: APE (m) | end error (m) |")
    print("|---|---|---|---|")
    for label, centre in VARIANTS.items():
        m = motion(world, centre)
        exact = lf3pm.replay(world, m, "mid70", "lio", seed=0, noise=0.0, imu_noise=False)
        noisy = [lf3pm.replay(world, m, "mid70", "lio", seed=seed) for seed in SEEDS]
        apes = " / ".join(f"{r.ape['rmse']:.3f}" for r in noisy)
        ends = " / ".join(f"{r.errors[-1]:.3f}" for r in noisy)
        print(f"| {label} | {exact.ape['rmse']:.3f} / {exact.errors[-1]:.3f} | {apes} | {ends} |", flush=True)


if __name__ == "__main__":
    main()
