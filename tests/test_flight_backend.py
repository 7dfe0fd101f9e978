"""The flight back end (issue 43, item 3): the volume field against a float64 reference, the
objective's gradient against finite differences with every term active, and an optimised
flight."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lf3pm import _core
from lf3pm.flight import Quadrotor
from lf3pm.planner.flight_plan import CHECK_RATE, FlightTrajectory, plan_flight
from lf3pm.scenes import build_scene
from lf3pm.solm import Solm, build_solm, make_grid


def field(seed, bins):
    rng = np.random.default_rng(seed)
    nx, ny, nz = 5, 4, 3
    values = rng.uniform(0, 2, (nz, bins, ny, nx))
    return values, _core.VolumeField(values.ravel(), nx, ny, nz, bins, -1.0, 2.0, 0.5, 0.5, 0.8)


def reference(values, p, yaw):
    """Linear interpolation per axis, written out: centres x -0.75 + 0.5 i, y 2.25 + 0.5 j,
    z 0.5 + 0.8 k (clamped), yaw periodic over the bins."""
    nz, bins, ny, nx = values.shape

    def weights(v, origin, step, n):
        f = np.clip((v - origin) / step, 0, n - 1)
        i0 = min(int(math.floor(f)), n - 2) if n > 1 else 0
        return (i0, i0 + 1, f - i0) if n > 1 else (0, 0, 0.0)

    x0, x1, tx = weights(p[0], -0.75, 0.5, nx)
    y0, y1, ty = weights(p[1], 2.25, 0.5, ny)
    z0, z1, tz = weights(p[2], 0.5, 0.8, nz)
    f = (yaw % (2 * math.pi)) / (2 * math.pi / bins)
    b0 = int(math.floor(f)) % bins
    tb = f - math.floor(f) if bins > 1 else 0.0
    total = 0.0
    for iz, wz in ((z0, 1 - tz), (z1, tz)):
        for ib, wb in ((b0, 1 - tb), ((b0 + 1) % bins, tb)):
            for iy, wy in ((y0, 1 - ty), (y1, ty)):
                for ix, wx in ((x0, 1 - tx), (x1, tx)):
                    total += wz * wb * wy * wx * values[iz, ib, iy, ix]
    return total


@pytest.mark.parametrize("bins", [1, 6])
def test_the_volume_field_interpolates_linearly_with_its_gradient(bins):
    values, f = field(1, bins)
    rng = np.random.default_rng(2)
    points = np.column_stack([rng.uniform(-1.2, 1.8, 40), rng.uniform(1.8, 4.5, 40), rng.uniform(0.0, 2.6, 40)])
    yaws = rng.uniform(-7, 7, 40)
    got, grad = f.sample(points, yaws)
    for k in range(40):
        assert got[k] == pytest.approx(reference(values, points[k], yaws[k]), rel=1e-12, abs=1e-12)
    h = 1e-6
    for axis in range(4):
        up, dn = points.copy(), points.copy()
        yu, yd = yaws.copy(), yaws.copy()
        if axis < 3:
            up[:, axis] += h
            dn[:, axis] -= h
        else:
            yu += h
            yd -= h
        numeric = (f.sample(up, yu)[0] - f.sample(dn, yd)[0]) / (2 * h)
        inside = np.abs(numeric - grad[:, axis]) < 1e-5  # away from the kinks between cells
        assert inside.mean() > 0.9
    if bins == 1:
        assert np.all(grad[:, 3] == 0.0)


def problem(quad, guidance, esdf, pieces=4, seed=0):
    rng = np.random.default_rng(seed)
    head = np.zeros((4, 3))
    tail = np.zeros((4, 3))
    tail[:, 0] = [6.0, 2.0, 1.5, 1.0]
    head[:, 0] = [0.0, 0.0, 1.0, 0.0]
    line = np.linspace(head[:, 0], tail[:, 0], pieces + 1)[1:-1].T
    waypoints = line + rng.normal(scale=0.3, size=line.shape)
    weights = _core.FlightWeights()
    return _core.FlightProblem(
        quad.params(),
        quad.limits(),
        weights,
        guidance,
        esdf,
        1.0,
        1e-2,
        0.5,
        head,
        tail,
        waypoints,
        np.full(pieces, 0.8),
    )


def test_the_objective_gradient_is_that_of_the_objective():
    """Short pieces push speed, thrust, tilt and body rate past their limits, the ESDF's
    clearance term is active near its low values: every term contributes, and the gradient
    by waypoints and taus matches central differences (h = 1e-6)."""
    quad = Quadrotor(thrust_max=16.0)  # hover takes 14.7 N: climbing and braking exceed it
    _, guidance = field(3, 6)
    values = np.random.default_rng(4).uniform(0.0, 0.6, (3, 1, 4, 5))
    esdf = _core.VolumeField(values.ravel(), 5, 4, 3, 1, -1.0, -1.0, 0.5, 2.0, 0.8)
    p = problem(quad, guidance, esdf)
    x = p.initial
    f, g, terms = p.evaluate(x)
    assert all(terms[name] > 0 for name in ("speed", "omega", "thrust", "tilt", "clearance", "guidance"))
    h = 1e-6
    numeric = np.empty_like(x)
    for i in range(len(x)):
        up, dn = x.copy(), x.copy()
        up[i] += h
        dn[i] -= h
        numeric[i] = (p.evaluate(up)[0] - p.evaluate(dn)[0]) / (2 * h)
    np.testing.assert_allclose(g, numeric, rtol=2e-5, atol=1e-6 * max(1.0, np.abs(numeric).max()))


def test_time_scaling_flies_the_same_path_slower():
    rng = np.random.default_rng(8)
    traj = FlightTrajectory(rng.normal(size=(3, 6, 4)), np.array([1.0, 0.7, 1.3]))
    slow = traj.time_scaled(2.5)
    a, b = traj.sample(100.0), slow.sample(40.0)  # the same instants of the path
    np.testing.assert_allclose(b["position"], a["position"], atol=1e-12)
    np.testing.assert_allclose(b["velocity"], a["velocity"] / 2.5, atol=1e-12)
    np.testing.assert_allclose(b["yaw_rate"], a["yaw_rate"] / 2.5, atol=1e-12)


@pytest.fixture(scope="module")
def boxes_flight(tmp_path_factory):
    import lf3pm

    world = lf3pm.load_map(build_scene("boxes").points)
    grid = make_grid(world, "r3yaw", 1.0, bounds=(-6.0, -6.0, 6.0, 6.0), yaw_bins=8, z_levels=(1.0, 2.0, 3.0))
    path = tmp_path_factory.mktemp("flight") / "boxes.zarr"
    build_solm(world, "vlp16", grid, path, noise=0.0, mount="top", tile=6)
    return world, Solm.open(path), path


def test_a_planned_flight_holds_every_limit_and_keeps_clear_of_the_map(boxes_flight):
    """From outside the boxes room's corner at 1 m to the opposite corner at 3 m: on samples
    at 1 kHz speed, body rate, tilt and thrust within their limits (time scaling, as for
    ground robots), every sample at least the SOLM's robot radius from a map point (k-d tree
    over the map), at rest at both ends, there exactly."""
    from scipy.spatial import cKDTree

    world, solm, _ = boxes_flight
    start, goal = (-5.5, -5.5, 1.0, 0.0), (5.5, 5.5, 3.0)
    plan = plan_flight(solm, world.points, start, goal)
    quad = Quadrotor()
    s = plan.trajectory.sample(CHECK_RATE)
    att = quad.attitudes(s["velocity"], s["acceleration"], s["jerk"], s["yaw"], s["yaw_rate"])
    ratios = quad.limit_ratios(s["velocity"], att)
    assert max(ratios.values()) <= 1.0 + 1e-9, ratios
    distance, _ = cKDTree(world.points).query(s["position"])
    assert distance.min() >= solm.attrs["robot_radius"]
    np.testing.assert_allclose(s["position"][0], start[:3], atol=1e-9)
    np.testing.assert_allclose(s["position"][-1], goal, atol=1e-9)
    assert np.abs(s["velocity"][[0, -1]]).max() < 1e-9
    assert plan.limits["clearance"] <= 1.0 and plan.status in ("converged", "stalled")


def test_lf3pm_plan_flies_a_quadrotor_and_refuses_what_it_cannot(boxes_flight, tmp_path):
    from typer.testing import CliRunner

    from lf3pm.cli import app

    world, _, store = boxes_flight
    map_path = tmp_path / "boxes.npy"
    np.save(map_path, world.points)
    out = tmp_path / "flight.csv"
    args = ["plan", "--robot", "quadrotor", "--solm", str(store), "--map", str(map_path), "-o", str(out)]
    args += ["--start", "-5.5", "-5.5", "0", "--goal", "5.5", "5.5", "0.5"]
    done = CliRunner().invoke(app, [*args, "--start-z", "1", "--goal-z", "2", "--json"])
    assert done.exit_code == 0, done.output
    import json

    summary = json.loads(done.stdout)
    assert max(summary["limits"].values()) <= 1.0 + 1e-9
    rows = np.loadtxt(out, delimiter=",", skiprows=1)
    assert out.read_text().splitlines()[0] == "t,x,y,z,yaw,vx,vy,vz,yaw_rate,qw,qx,qy,qz,thrust,ax,ay,az"
    np.testing.assert_allclose(rows[-1, 1:5], [5.5, 5.5, 2.0, 0.5], atol=1e-6)
    missing = CliRunner().invoke(app, args)
    assert missing.exit_code == 2 and "--start-z and --goal-z" in missing.output
    ground = CliRunner().invoke(app, [*args[:2], "omni", *args[3:], "--start-z", "1", "--goal-z", "2"])
    assert ground.exit_code == 2 and len(ground.output.strip().splitlines()) == 1


def test_the_baseline_planners_hold_the_yaw_along_the_velocity_or_optimise_it_alone(boxes_flight):
    """velocity_yaw: the heading follows the horizontal velocity (median within 1 degree where
    faster than 0.5 m/s); yaw_only: the same positions (its samples on velocity_yaw's path to
    1e-6 m, its durations that path's, time-scaled), a different yaw; both within the limits."""
    world, solm, _ = boxes_flight
    start, goal = (-5.5, -5.5, 1.0, 0.0), (5.5, 5.5, 2.0)
    a = plan_flight(solm, world.points, start, goal, planner="velocity_yaw")
    b = plan_flight(solm, world.points, start, goal, planner="yaw_only")
    s = a.trajectory.sample(100.0)
    speed = np.linalg.norm(s["velocity"][:, :2], axis=1)
    heading = np.arctan2(s["velocity"][:, 1], s["velocity"][:, 0])
    error = np.abs(np.angle(np.exp(1j * (s["yaw"] - heading))))[speed > 0.5]
    assert np.degrees(np.median(error)) < 1.0
    # The same path: b's trajectory is a's positions under a (uniform) time scaling.
    ratio = b.trajectory.duration / a.trajectory.duration
    sb = b.trajectory.sample(100.0 / ratio)
    n = min(len(s["t"]), len(sb["t"])) - 1
    np.testing.assert_allclose(sb["position"][:n], s["position"][:n], atol=1e-6)
    assert np.abs(sb["yaw"][:n] - s["yaw"][:n]).max() > 0.1
    for plan in (a, b):
        assert max(plan.limits.values()) <= 1.0 + 1e-9 and plan.planner in ("velocity_yaw", "yaw_only")
    with pytest.raises(Exception, match="unknown flight planner"):
        plan_flight(solm, world.points, start, goal, planner="gcopter")
