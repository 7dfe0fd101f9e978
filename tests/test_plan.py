"""Planning on a real SOLM (the ``boxes`` scene): the optimised trajectory meets the
robot's limits on 100 Hz samples, for omni, diff and car robots."""

import subprocess
import sys

import numpy as np
import pytest

from lf3pm.planner import Planner, Robot
from lf3pm.solm.reader import Solm

from kinematics import assert_kinematics_hold, body_speeds

START, GOAL = (-2.5, -2.7, 0.0), (6.2, 2.2, 1.57)


@pytest.fixture(scope="module")
def planner(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("plan")
    for args in (["scene", "boxes", "-o", tmp / "boxes.pcd"],
                 ["solm", "build", tmp / "boxes.pcd", "-o", tmp / "boxes.zarr", "--res", "0.5", "--ray-stride", "4"]):
        subprocess.run([sys.executable, "-m", "lf3pm.cli", *map(str, args)], check=True, capture_output=True)
    return Planner(Solm.open(tmp / "boxes.zarr"))


@pytest.mark.parametrize("kind", ["omni", "diff", "car"])
def test_plan_on_boxes_is_feasible(planner, kind):
    robot = Robot(kind, min_turn_radius=0.5 if kind == "car" else 0.0, r_safe=0.05)
    plan = planner.plan(START, GOAL, robot=robot, metric="q_n", weight=3.0)
    traj = plan.trajectory
    s = assert_kinematics_hold(traj, robot)
    clearance = planner.esdf.distance(s["x"], s["y"])[0]
    assert np.min(clearance) >= robot.r_safe
    # It starts and ends on the exact start and goal poses, at rest.
    np.testing.assert_allclose([s["x"][0], s["y"][0]], START[:2], atol=1e-9)
    np.testing.assert_allclose([s["x"][-1], s["y"][-1]], GOAL[:2], atol=1e-9)
    assert abs(np.angle(np.exp(1j * (s["yaw"][0] - START[2])))) < 1e-2
    assert abs(np.angle(np.exp(1j * (s["yaw"][-1] - GOAL[2])))) < 1e-2


def test_a_car_turns_round_at_both_ends(planner):
    """The start yaw points away from the goal and the goal yaw back toward the start:
    the car front end's path loops at both ends, forwards only, and the trajectory
    follows it within every limit (a grid path here gave a cusp: reversing at ~0 speed)."""
    robot = Robot("car", min_turn_radius=0.5, r_safe=0.05)
    start, goal = (START[0], START[1], 3.6), (GOAL[0], GOAL[1], -2.6)  # 3.6: opposite the goal
    plan = planner.plan(start, goal, robot=robot, metric="q_n", weight=3.0)
    turned = np.sum(plan.path.segments[:, 0] * plan.path.segments[:, 1])
    assert abs(turned) > np.pi  # more than a U-turn in all (main's grid front end: 850 rad/s at 0 m/s)
    s = assert_kinematics_hold(plan.trajectory, robot)
    assert np.min(planner.esdf.distance(s["x"], s["y"])[0]) >= robot.r_safe
    _, v_lon, _ = body_speeds(plan.trajectory)
    assert np.min(v_lon) > -1e-9  # never reverses
    assert abs(np.angle(np.exp(1j * (s["yaw"][0] - start[2])))) < 1e-9
    assert abs(np.angle(np.exp(1j * (s["yaw"][-1] - goal[2])))) < 1e-9
    summary = plan.summary()
    assert summary["path_length_m"] == pytest.approx(plan.path.length) and summary["search_s"] >= 0
