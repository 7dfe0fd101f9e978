"""Planning on a real SOLM (the ``boxes`` scene): the optimised trajectory meets the
robot's limits on 100 Hz samples, for omni, diff and car robots."""

import subprocess
import sys

import numpy as np
import pytest

from lf3pm.planner import Planner, Robot
from lf3pm.solm.reader import Solm

from kinematics import assert_kinematics_hold

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
