"""The replay's motion (motion.py) and the smooth ground under it (ground.py):
exact on a planner's cubic, C2, above the true ground within a stated bound."""

import numpy as np
import pytest
from analytic_scenes import grid_plane
from scipy.interpolate import CubicSpline

import lf3pm
from lf3pm.config import DEFAULT_HEIGHT
from lf3pm.errors import Lf3pmError
from lf3pm.replays.ground import smooth_ground
from lf3pm.replays.motion import Motion, quintic_hermite
from lf3pm.terrain import body_blocked
from lf3pm.trajectory.trajectory import Trajectory, read_csv


@pytest.fixture(scope="module")
def floor():
    """A flat floor at z = 0.2 m, 40 x 40 m around the origin."""
    return lf3pm.load_map(np.ascontiguousarray(grid_plane((-20, -20, 0.2), (1, 0, 0), (0, 1, 0), 40, 40, 0.2)))


@pytest.fixture(scope="module")
def spline():
    """A C2 cubic spline in x, y, yaw with knots that fall between 100 Hz samples."""
    knots = np.array([0.0, 1.234, 2.5, 3.817, 5.0])
    values = np.array([[0, 0, 0], [1.2, 0.5, 0.4], [2.0, 1.5, 1.2], [3.5, 1.0, 0.5], [4.0, 2.0, 0.9]])
    return CubicSpline(knots, values, bc_type="clamped")


def trajectory_of(spline) -> Trajectory:
    """The spline as lf3pm's Trajectory (pieces in ascending powers)."""
    c = spline.c  # (4, pieces, 3), descending powers
    return Trajectory(coefficients=np.transpose(c[::-1], (1, 0, 2)).copy(), durations=np.diff(spline.x))


def test_motion_reproduces_the_planner_cubic(floor, spline, tmp_path):
    csv = tmp_path / "traj.csv"
    trajectory_of(spline).to_csv(csv)
    motion = Motion.from_csv(csv, floor)
    assert motion.t0 == 0.0 and motion.t1 == pytest.approx(5.0) and motion.height == DEFAULT_HEIGHT
    t = np.random.default_rng(0).uniform(0, 5, 2000)
    # Within a piece, more than a sample from a knot, the motion is the cubic to the
    # CSV's 9 significant digits (1e-8 m, so 1e-6 m/s and 1e-4 m/s^2 over 10 ms);
    # near a knot it departs by about jerk jump * h^3.
    far = np.min(np.abs(t[:, None] - spline.x[None, :]), axis=1) > 0.021
    for order, get, tol_far, tol_near in (
        (0, motion.position, 1e-7, 1e-5),
        (1, motion.velocity, 1e-5, 2e-3),
        (2, motion.acceleration, 2e-3, 0.3),
    ):
        exact = spline(t, order)
        got = get(t)
        assert np.max(np.abs(got[far, :2] - exact[far, :2])) < tol_far
        assert np.max(np.abs(got[:, :2] - exact[:, :2])) < tol_near
    np.testing.assert_allclose(motion.yaw(t)[far], spline(t)[far, 2], atol=1e-7)
    np.testing.assert_allclose(motion.yaw_rate(t)[far], spline(t, 1)[far, 2], atol=1e-5)
    np.testing.assert_allclose(motion.position(t)[:, 2], 0.2 + DEFAULT_HEIGHT, atol=1e-9)  # flat floor
    pose = motion.pose(t[:3])
    np.testing.assert_allclose(pose[:, :3, 3], motion.position(t[:3]))
    np.testing.assert_allclose(np.arctan2(pose[:, 1, 0], pose[:, 0, 0]), motion.yaw(t[:3]), atol=1e-12)


def test_quintic_hermite_matches_scipys_bernstein_construction():
    from scipy.interpolate import BPoly

    rng = np.random.default_rng(7)
    t = np.cumsum(np.r_[0.3, rng.uniform(0.005, 0.05, 400)])
    p, v, a = rng.normal(size=(3, len(t)))
    ours = quintic_hermite(t, p, v, a)
    reference = BPoly.from_derivatives(t, np.column_stack([p, v, a]))
    inside = np.sort(rng.uniform(t[0], t[-1], 2000))
    for k, scale in enumerate((1.0, 1.0 / 0.005, 1.0 / 0.005**2)):
        # Both are float64 polynomials on intervals of h >= 5 ms: a k-th derivative carries
        # rounding of about eps x value scale / h^k.
        np.testing.assert_allclose(ours(inside, k), reference(inside, k), rtol=0, atol=1e-12 * scale)
        # Each piece at its own right end (a PPoly at a knot reads the next piece).
        ends = [np.polyval(np.polyder(ours.c[:, i], k), h) for i, h in enumerate(np.diff(t))]
        np.testing.assert_allclose(ends, (p, v, a)[k][1:], rtol=0, atol=1e-12 * scale)


def test_motion_in_unix_time_equals_the_motion_from_zero(floor, spline):
    s = trajectory_of(spline).sample(100.0)
    rates = (s["vx"], s["vy"], s["omega"])
    at_zero = Motion.from_arrays(s["t"], s["x"], s["y"], s["yaw"], *rates, map=floor)
    offset = 1.7e9  # s: a stamp of 2023; float64 keeps 2.4e-7 s there
    in_unix = Motion.from_arrays(s["t"] + offset, s["x"], s["y"], s["yaw"], *rates, map=floor)
    times = np.linspace(0.0, s["t"][-1], 157)
    # Positions move by the rounding of the stamps times the speed (< 2 m/s): well under 1e-5 m.
    np.testing.assert_allclose(in_unix.pose(times + offset), at_zero.pose(times), rtol=0, atol=1e-5)


def test_motion_is_c2_and_its_derivatives_agree(floor, spline):
    s = trajectory_of(spline).sample(100.0)
    motion = Motion.from_arrays(s["t"], s["x"], s["y"], s["yaw"], s["vx"], s["vy"], s["omega"], map=floor)
    # Continuity at every sample, the knots included: no jump in the acceleration.
    ts = s["t"][1:-1]
    for get in (motion.position, motion.velocity, motion.acceleration):
        assert np.max(np.abs(get(ts + 1e-9) - get(ts - 1e-9))) < 1e-6
    # Central differences of the position and velocity give the velocity and acceleration.
    t, h = np.linspace(0.1, 4.9, 97), 1e-5
    np.testing.assert_allclose(
        (motion.position(t + h) - motion.position(t - h)) / (2 * h), motion.velocity(t), atol=1e-6
    )
    np.testing.assert_allclose(
        (motion.velocity(t + h) - motion.velocity(t - h)) / (2 * h), motion.acceleration(t), atol=1e-4
    )
    # At rest outside the span.
    np.testing.assert_allclose(motion.position([-1.0]), motion.position([0.0]))
    assert np.all(motion.velocity([-1.0, 6.0]) == 0) and np.all(motion.yaw_rate([6.0]) == 0)


def terrain(x, y):
    """Rolling ground: 0.3 m bumps about 19 m long."""
    return 0.3 * np.sin(x / 3.0) * np.cos(y / 4.0)


@pytest.fixture(scope="module")
def rough():
    """Rolling ground sampled every 0.1 m with 2 cm of jitter, and a 1 x 1 x 1.5 m
    box at x in [4, 5], y in [0.4, 1.4] standing on it, with no ground under it."""
    rng = np.random.default_rng(1)
    g = np.mgrid[-10:10:0.1, -6:6:0.1].reshape(2, -1).T
    box = (g[:, 0] >= 4) & (g[:, 0] <= 5) & (g[:, 1] >= 0.4) & (g[:, 1] <= 1.4)
    ground = np.column_stack([g[~box], terrain(*g[~box].T) + rng.uniform(-0.02, 0.02, (~box).sum())])
    base = terrain(4.5, 0.9)
    u = np.arange(0, 1.0001, 0.05)
    top = np.array([(4 + a, 0.4 + b, base + 1.5) for a in u for b in u])
    sides = np.array(
        [
            (x, y, base + h)
            for h in np.arange(0, 1.5001, 0.05)
            for a in u
            for x, y in ((4 + a, 0.4), (4 + a, 1.4), (4, 0.4 + a), (5, 0.4 + a))
        ]
    )
    return lf3pm.load_map(np.ascontiguousarray(np.vstack([ground, top, sides])))


def test_smooth_ground_stays_near_the_true_ground_beside_an_obstacle(rough):
    """At 1.5 m/s along y = 0 (0.4 m from the box's side) the sensor rides within
    5 cm of its height above the true ground (measured 2.3 cm), its vertical
    acceleration stays under 0.3 m/s^2 (measured 0.08) and its body (0.1 m
    above the ground to the sensor, 0.3 m radius) never touches the map. With
    the box top taken for ground (max_step 100 m) the first two would fail:
    10.5 cm and 1.06 m/s^2."""
    t = np.linspace(0, 12, 1201)
    x, y = -9 + 1.5 * t, np.zeros_like(t)
    motion = Motion.from_arrays(t, x, y, np.zeros_like(t), np.full_like(t, 1.5), 0 * t, 0 * t, map=rough)
    p = motion.position(t)
    # z is held as a polynomial in time through g(x(t), y(t)) + height every 10 ms.
    between = np.random.default_rng(2).uniform(0, 12, 500)
    q = motion.position(between)
    np.testing.assert_allclose(q[:, 2], motion.ground.height(q[:, 0], q[:, 1]) + DEFAULT_HEIGHT, atol=1e-7)
    height_above_ground = p[:, 2] - terrain(x, y)
    assert np.max(np.abs(height_above_ground - DEFAULT_HEIGHT)) < 0.05
    assert np.max(np.abs(motion.acceleration(t)[:, 2])) < 0.3
    assert not body_blocked(rough, x, y, terrain(x, y) + 0.4, p[:, 2], 0.3).any()
    # The box top is no ground: without that rule its columns would lift the path.
    deviation = motion.ground.deviation(x, y)
    assert np.nanmax(np.abs(deviation)) < 0.05


def test_ground_errors(floor):
    with pytest.raises(Lf3pmError, match="smoothing"):
        smooth_ground(floor.points, np.zeros((2, 2)), smoothing=0.0)
    with pytest.raises(Lf3pmError, match="no map point"):
        smooth_ground(floor.points, np.array([[100.0, 100.0], [101.0, 100.0]]))


def test_trajectory_leaving_the_map_is_refused(floor):
    t = np.array([0.0, 1.0, 2.0])
    with pytest.raises(Lf3pmError, match=r"leaves the map at t = 2 s"):
        Motion.from_arrays(t, [0.0, 10.0, 25.0], [0.0, 0.0, 0.0], [0.0] * 3, map=floor)
    with pytest.raises(Lf3pmError, match="height"):
        Motion.from_arrays(t, [0.0, 1.0, 2.0], [0.0] * 3, [0.0] * 3, map=floor, height=-1.0)


@pytest.mark.parametrize(
    "text, match",
    [
        ("", "empty file"),
        ("t,x,y,yaw,vx,vy\n0,0,0,0,0,0\n1,1,0,0,0,0\n", "lacks the column"),
        ("t,x,y,yaw,vx,vy,omega\n0,0,0,0,0,0,0\n1,1,0,0,0,0\n", r":3: 6 fields"),
        ("t,x,y,yaw,vx,vy,omega\n0,0,0,0,0,0,0\n1,one,0,0,0,0,0\n", r":3: a field is not a number"),
        ("t,x,y,yaw,vx,vy,omega\n0,0,0,0,0,0,0\n1,nan,0,0,0,0,0\n", r":3: x is not finite"),
        ("t,x,y,yaw,vx,vy,omega\n0,0,0,0,0,0,0\n1,inf,0,0,0,0,0\n", r":3: x is not finite"),
        ("t,x,y,yaw,vx,vy,omega\n0,0,0,0,0,0,0\n", "1 sample"),
        ("t,x,y,yaw,vx,vy,omega\n0,0,0,0,0,0,0\n1,1,0,0,0,0,0\n1,2,0,0,0,0,0\n", r":4: time 1 does not follow 1"),
    ],
)
def test_bad_csv(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(Lf3pmError, match=match):
        read_csv(path)


def test_csv_columns_in_any_order(tmp_path):
    path = tmp_path / "ok.csv"
    path.write_text("x,t,y,yaw,vx,vy,omega,extra\n1,0,2,0,0,0,0,9\n3,1,4,0,0,0,0,9\n")
    s = read_csv(path)
    assert s["t"].tolist() == [0, 1] and s["x"].tolist() == [1, 3] and "extra" not in s
    with pytest.raises(Lf3pmError, match="cannot read"):
        read_csv(tmp_path / "missing.csv")


def test_a_sparse_floor_under_a_ceiling_is_driven_on_not_the_ceiling():
    """A hall scanned sparsely: a floor at z = 0 with a few 0.25 m columns left empty along
    the path, a ceiling at 5 m over everything. An empty floor column reads the ceiling (its
    lowest point); it is no ground (its component, the ceiling's, lies under few path
    samples), so the sensor keeps its height over the floor. Before, those columns were
    ground and the sensor rose towards the ceiling (the real hall of real_hall_run: 5 m)."""
    floor = grid_plane((-10, -5, 0.0), (1, 0, 0), (0, 1, 0), 20, 10, 0.1)
    holes = np.zeros(len(floor), bool)
    for x in (-3.0, 0.0, 3.0):  # 0.6 m of floor missing under the path every 3 m: whole columns
        holes |= (np.abs(floor[:, 0] - x) < 0.3) & (np.abs(floor[:, 1]) < 0.3)
    ceiling = grid_plane((-10, -5, 5.0), (1, 0, 0), (0, 1, 0), 20, 10, 0.2)
    world = lf3pm.load_map(np.ascontiguousarray(np.vstack([floor[~holes], ceiling])))
    t = np.linspace(0, 10, 1001)
    motion = Motion.from_arrays(t, -5 + t, 0 * t, 0 * t, np.ones_like(t), 0 * t, 0 * t, map=world)
    assert np.max(np.abs(motion.position(t)[:, 2] - DEFAULT_HEIGHT)) < 0.01
