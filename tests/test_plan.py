"""Planning on a real SOLM (the ``boxes`` scene): the optimised trajectory meets the
robot's limits on 100 Hz samples, for omni, diff and car robots."""

import numpy as np
import pytest
from kinematics import assert_kinematics_hold, body_speeds
from queries import random_queries

from lf3pm.errors import Lf3pmError
from lf3pm.planner import Planner
from lf3pm.solm.reader import Solm
from lf3pm.trajectory import Robot

START, GOAL = (-2.5, -2.7, 0.0), (6.2, 2.2, 1.57)


@pytest.fixture
def planner(boxes_planner):
    return boxes_planner


@pytest.mark.slow
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


@pytest.mark.slow
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
    assert summary["path_length_m"] == pytest.approx(plan.path.length)
    assert summary["duration_s"] == pytest.approx(plan.trajectory.duration) and summary["iterations"] > 0
    fine = plan.trajectory.sample(1000.0)  # the summary samples at 100 Hz: the same length within 0.1 %
    length = np.hypot(np.diff(fine["x"]), np.diff(fine["y"])).sum()
    assert summary["trajectory_length_m"] == pytest.approx(length, rel=1e-3)
    assert summary["trajectory_length_m"] >= np.hypot(goal[0] - start[0], goal[1] - start[1])
    # Clearance is kept; the turning radius, a penalty on the path's geometry, is said
    # when it is missed at all (here by under 2 % of the top speed: assert_kinematics_hold).
    assert all("min_turn_radius" in w for w in summary["warnings"])
    assert bool(summary["warnings"]) == (summary["violations"]["max_turn_excess"] > 0)


def test_a_plan_inside_r_safe_says_so(planner):
    """The optimiser keeps clearance by a penalty: a plan that ends up inside r_safe is
    reported with how far, and one whose body reaches the map says it touches."""
    from dataclasses import replace

    plan = planner.plan(START, GOAL, robot=Robot("omni", r_safe=0.05), metric="none")
    assert plan.warnings() == [] and plan.optimization.violations["min_clearance"] >= 0

    def with_clearance(c):
        violations = {**plan.optimization.violations, "min_clearance": c}
        return replace(plan, optimization=replace(plan.optimization, violations=violations))

    assert with_clearance(-0.03).warnings() == [
        "the trajectory comes 0.03 m inside r_safe (0.05 m): the body passes 0.02 m from the map"
    ]
    assert with_clearance(-0.08).summary()["warnings"] == [
        "the trajectory comes 0.08 m inside r_safe (0.05 m): it touches the map"
    ]


@pytest.mark.parametrize("kind", ["omni", "diff", "car"])
def test_random_queries_meet_every_limit(planner, kind):
    """Speeds, accelerations, yaw rate and yaw acceleration (by central differences of
    the sampled yaw rate) within 2 % on 100 Hz samples, clearance kept, for random
    queries with the default limits (bench/bench_random_queries.py runs more seeds)."""
    robot = Robot(kind, min_turn_radius=0.5 if kind == "car" else 0.0, r_safe=0.05)
    for start, goal in random_queries(planner, seed=0, count=6):
        try:
            plan = planner.plan(start, goal, robot=robot, metric="q_n", weight=1.0)
        except Lf3pmError:  # a car may have no forward path (a start facing a wall)
            assert kind == "car"
            continue
        s = assert_kinematics_hold(plan.trajectory, robot)
        assert np.min(planner.esdf.distance(s["x"], s["y"])[0]) >= robot.r_safe


def test_csv_velocities_are_the_derivatives_of_its_positions(planner, tmp_path):
    """What `lf3pm plan` writes: 100 Hz rows whose vx, vy, omega are the central
    differences of x, y, yaw, to within h times the acceleration limit (the
    difference's error where the acceleration has a kink between pieces)."""
    for kind in ("omni", "diff"):
        robot = Robot(kind, r_safe=0.05)
        plan = planner.plan(START, GOAL, robot=robot, metric="q_n", weight=1.0)
        plan.trajectory.to_csv(tmp_path / "t.csv")
        t, x, y, yaw, vx, vy, omega = np.loadtxt(tmp_path / "t.csv", delimiter=",", skiprows=1).T
        assert np.allclose(np.diff(t[:-1]), 0.01, atol=1e-9) and t[-1] == pytest.approx(plan.trajectory.duration)
        for p, v, limit in ((x, vx, robot.amax_lon), (y, vy, robot.amax_lon), (np.unwrap(yaw), omega, robot.alpha_max)):
            fd = (p[2:] - p[:-2]) / (t[2:] - t[:-2])
            assert np.max(np.abs(fd[:-1] - v[1:-2])) <= 0.01 * limit


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["omni", "car"])
def test_plans_keep_the_body_off_thin_poles_between_cell_centres(tmp_path, kind):
    """Poles 0.1 m beside the straight line through a row of 1 m cells' centres, and
    more than the robot radius (0.3 m) from every centre: the SOLM's obstacle mask
    leaves their cells free, so only the occupancy layer keeps the plan off them (a
    plan from the mask alone drove straight through). Every 100 Hz sample keeps the
    radius plus r_safe from every pole."""
    import lf3pm
    from lf3pm.solm import build_solm, make_grid

    xs = np.arange(0.0, 16.001, 0.1)
    floor = np.array([(x, y, 0.0) for x in xs for y in np.arange(-3.0, 3.001, 0.1)])
    poles_xy = np.array([(4.0, 0.4), (8.0, 0.6), (12.0, 0.4)])
    poles = np.array([(px, py, z) for px, py in poles_xy for z in np.arange(0.3, 1.5, 0.05)])
    world = lf3pm.load_map(np.vstack([floor, poles]))
    grid = make_grid(world, "r2", 1.0, bounds=(0, -3, 16, 3), height=1.0)
    build_solm(world, "vlp16", grid, tmp_path / "poles.zarr", noise=0.0, ray_stride=8)
    solm = Solm.open(tmp_path / "poles.zarr")
    assert not solm.channel("obstacle").any()  # the centres' body probes miss every pole
    robot = Robot(kind, min_turn_radius=0.5 if kind == "car" else 0.0, r_safe=0.05)
    plan = Planner(solm).plan((0.5, 0.5, 0.0), (15.5, 0.5, 0.0), robot=robot, metric="none")
    s = assert_kinematics_hold(plan.trajectory, robot)
    gap = np.min(np.hypot(s["x"][:, None] - poles_xy[:, 0], s["y"][:, None] - poles_xy[:, 1]))
    assert gap >= solm.attrs["robot_radius"] + robot.r_safe
    # A start 0.14 m from a pole, in a cell whose centre is clear: refused, not planned from.
    with pytest.raises(Lf3pmError, match=r"start .* closer than the robot radius 0.3 m"):
        Planner(solm).plan((3.9, 0.5, 0.0), (15.5, 0.5, 0.0), robot=robot, metric="none")
