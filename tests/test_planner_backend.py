"""Trajectory back end: MINCO, L-BFGS, the objective's gradient, and optimised trajectories."""

import math

import numpy as np
import pytest
from kinematics import assert_kinematics_hold

from lf3pm import _core
from lf3pm.errors import Lf3pmError
from lf3pm.grid_field import GridField
from lf3pm.trajectory import Robot, Trajectory, make_problem, optimize_trajectory

RES, X0, Y0 = 0.25, -5.0, -10.0
NX, NY = 140, 80


def _centres():
    xs = X0 + (np.arange(NX) + 0.5) * RES
    ys = Y0 + (np.arange(NY) + 0.5) * RES
    return np.meshgrid(xs, ys)


def _smooth_se2_cost(seed=0, bins=8):
    rng = np.random.default_rng(seed)
    x, y = _centres()
    layers = []
    for k in range(bins):
        a, b, c = rng.uniform(0.2, 0.6, 3)
        layers.append(2.0 + np.sin(a * x + k) * np.cos(b * y) + 0.3 * np.sin(c * (x + y)))
    return GridField(np.stack(layers), X0, Y0, RES)


def _esdf_with_disc(cx, cy, radius):
    x, y = _centres()
    return GridField(np.hypot(x - cx, y - cy) - radius, X0, Y0, RES)


def _straight(goal=(20.0, 0.0), yaw=0.0, n=21):
    t = np.linspace(0.0, 1.0, n)
    return np.column_stack([t * goal[0], t * goal[1], np.full(n, yaw)])


def _bend(n=41):
    """A 20 m path that turns by about 50 degrees."""
    s = np.linspace(0.0, 20.0, n)
    y = 4.0 / (1.0 + np.exp(-(s - 10.0) / 2.0))
    yaw = np.arctan2(np.gradient(y, s), 1.0)
    return np.column_stack([s, y, yaw])


def _coefficient_value(c, t, order):
    return sum(c[k] * math.factorial(k) / math.factorial(k - order) * t ** (k - order) for k in range(order, 4))


# --- MINCO ---------------------------------------------------------------------------


def test_minco_continuity_and_boundary_conditions():
    rng = np.random.default_rng(1)
    n = 6
    head = np.array([[0.0, 0.3], [0.0, -0.2], [0.1, 0.05]])
    tail = np.array([[10.0, 0.5], [2.0, 0.0], [1.0, -0.1]])
    q = np.column_stack([np.linspace(1, 9, n - 1), rng.normal(size=n - 1), rng.normal(size=n - 1)])
    durations = rng.uniform(0.3, 2.5, n)
    coef, energy = _core.minco_s2(head, tail, q, durations)
    assert coef.shape == (n, 4, 3) and energy > 0
    for i in range(n - 1):
        for order in range(3):  # position, velocity and acceleration continuous (C^2)
            np.testing.assert_allclose(
                _coefficient_value(coef[i], durations[i], order), _coefficient_value(coef[i + 1], 0.0, order), atol=1e-9
            )
        np.testing.assert_allclose(_coefficient_value(coef[i], durations[i], 0), q[i], atol=1e-9)
    np.testing.assert_allclose(_coefficient_value(coef[0], 0.0, 0), head[:, 0], atol=1e-12)
    np.testing.assert_allclose(_coefficient_value(coef[0], 0.0, 1), head[:, 1], atol=1e-12)
    np.testing.assert_allclose(_coefficient_value(coef[-1], durations[-1], 0), tail[:, 0], atol=1e-9)
    np.testing.assert_allclose(_coefficient_value(coef[-1], durations[-1], 1), tail[:, 1], atol=1e-9)
    # The energy is the integral of the squared acceleration (checked by quadrature).
    quad = 0.0
    for i in range(n):
        t, w = np.polynomial.legendre.leggauss(6)
        t = 0.5 * durations[i] * (t + 1)
        acc = np.array([_coefficient_value(coef[i], ti, 2) for ti in t])
        quad += 0.5 * durations[i] * np.sum(w * np.sum(acc**2, axis=1))
    assert energy == pytest.approx(quad, rel=1e-10)


@pytest.mark.parametrize("head_acc, tail_acc", [(True, False), (False, True), (True, True)])
def test_minco_with_acceleration_conditions(head_acc, tail_acc):
    """An end with its acceleration given frees its neighbouring junction's waypoint; the
    spline is C^2 and meets every condition (which fix its coefficients)."""
    rng = np.random.default_rng(4)
    n = 5
    head = np.array([[0.0, 0.3, 0.2], [0.0, -0.2, -0.4], [0.1, 0.05, 0.0]])
    tail = np.array([[10.0, 0.5, -0.3], [2.0, 0.0, 0.6], [1.0, -0.1, 0.0]])
    free = n - 1 - head_acc - tail_acc
    q = np.column_stack([np.linspace(2, 8, free), rng.normal(size=free), rng.normal(size=free)])
    durations = rng.uniform(0.3, 2.5, n)
    coef, _ = _core.minco_s2(
        np.ascontiguousarray(head[:, : 3 if head_acc else 2]),
        np.ascontiguousarray(tail[:, : 3 if tail_acc else 2]),
        q,
        durations,
    )
    for i in range(n - 1):
        for order in range(3):
            np.testing.assert_allclose(
                _coefficient_value(coef[i], durations[i], order), _coefficient_value(coef[i + 1], 0.0, order), atol=1e-9
            )
    junctions = [i for i in range(n - 1) if not (head_acc and i == 0) and not (tail_acc and i == n - 2)]
    for k, i in enumerate(junctions):
        np.testing.assert_allclose(_coefficient_value(coef[i], durations[i], 0), q[k], atol=1e-9)
    for order in range(3 if head_acc else 2):
        np.testing.assert_allclose(_coefficient_value(coef[0], 0.0, order), head[:, order], atol=1e-9)
    for order in range(3 if tail_acc else 2):
        np.testing.assert_allclose(_coefficient_value(coef[-1], durations[-1], order), tail[:, order], atol=1e-9)


def test_trajectory_evaluate_is_continuous_and_keeps_boundaries(tmp_path):
    result = optimize_trajectory(_bend(), None, None, Robot("omni"), rho_T=1.0, samples=8)
    traj = result.trajectory
    junctions = np.cumsum(traj.durations)[:-1]
    p_before, v_before = traj.evaluate(junctions - 1e-9)
    p_after, v_after = traj.evaluate(junctions + 1e-9)
    np.testing.assert_allclose(p_before, p_after, atol=1e-6)
    np.testing.assert_allclose(v_before, v_after, atol=1e-6)
    p, v = traj.evaluate([0.0, traj.duration])
    np.testing.assert_allclose(p[0], _bend()[0], atol=1e-9)
    np.testing.assert_allclose(p[1][:2], _bend()[-1][:2], atol=1e-9)
    np.testing.assert_allclose(v, 0.0, atol=1e-9)
    path = tmp_path / "traj.csv"
    traj.to_csv(path)
    lines = path.read_text().splitlines()
    assert lines[0] == "t,x,y,yaw,vx,vy,omega"
    rows = np.loadtxt(path, delimiter=",", skiprows=1)
    assert rows.shape[1] == 7 and rows[-1, 0] == pytest.approx(traj.duration)
    assert len(rows) == pytest.approx(traj.duration * 100, abs=2)


# --- L-BFGS ----------------------------------------------------------------------------


def test_lbfgs_rosenbrock():
    def rosen(x):
        f = np.sum(100 * (x[1:] - x[:-1] ** 2) ** 2 + (1 - x[:-1]) ** 2)
        g = np.zeros_like(x)
        g[:-1] = -400 * x[:-1] * (x[1:] - x[:-1] ** 2) - 2 * (1 - x[:-1])
        g[1:] += 200 * (x[1:] - x[:-1] ** 2)
        return f, g

    params = _core.LbfgsParams()
    params.g_epsilon = 1e-10
    r = _core.lbfgs_minimize(rosen, np.array([-1.2, 1.0, -0.5, 0.8]), params)
    assert r["status"] == "converged"
    np.testing.assert_allclose(r["x"], 1.0, atol=1e-6)


def _convex_quadratic():
    rng = np.random.default_rng(2)
    m = rng.normal(size=(30, 30))
    a = m @ m.T + 0.5 * np.eye(30)  # condition number 214
    b = rng.normal(size=30)
    return a, b, lambda x: (0.5 * x @ a @ x - b @ x, a @ x - b)


def test_lbfgs_convex_quadratic_converges_to_what_float_precision_allows():
    a, b, fun = _convex_quadratic()
    params = _core.LbfgsParams()
    params.g_epsilon, params.delta = 1e-12, 0.0  # below what rounding lets |g| reach here
    r = _core.lbfgs_minimize(fun, np.zeros(30), params)
    assert r["status"] == "converged" and r["reason"].startswith("float precision"), r["reason"]
    # f = x'Ax/2 - b'x in float64 is exact to within n eps (|x|'|A||x|/2 + |b|'|x|) (Higham, dot
    # products); no x whose excess (x - x*)'A(x - x*)/2 is smaller can be told from x* by f.
    x_star = np.linalg.solve(a, b)
    rounding = (
        30 * np.finfo(float).eps * (0.5 * np.abs(x_star) @ np.abs(a) @ np.abs(x_star) + np.abs(b) @ np.abs(x_star))
    )
    e = r["x"] - x_star
    assert 0.5 * e @ a @ e <= rounding
    assert np.linalg.norm(e) <= np.sqrt(2 * rounding / np.linalg.eigvalsh(a)[0])


def test_lbfgs_convex_quadratic_meets_a_gradient_tolerance_above_rounding():
    a, b, fun = _convex_quadratic()
    params = _core.LbfgsParams()
    params.g_epsilon, params.delta = 1e-5, 0.0
    r = _core.lbfgs_minimize(fun, np.zeros(30), params)
    assert r["status"] == "converged" and r["reason"].startswith("gradient"), r["reason"]
    assert r["gradient_norm"] <= 1e-5 * max(1.0, np.linalg.norm(r["x"]))
    # |x - x*| <= |A^-1| |g|
    assert np.linalg.norm(r["x"] - np.linalg.solve(a, b)) <= r["gradient_norm"] / np.linalg.eigvalsh(a)[0]


def test_lbfgs_line_search_that_sees_f_change_is_still_a_failure():
    # A gradient that contradicts f (f = |x|^2 / 2, its minimum at 0, "gradient" x + 1):
    # every step along -g raises f by far more than rounding.
    r = _core.lbfgs_minimize(lambda x: (0.5 * x @ x, x + 1.0), np.zeros(4))
    assert r["status"] == "line_search_failed" and r["reason"].startswith("no step"), r["reason"]


# --- The objective's gradient ----------------------------------------------------------


@pytest.mark.parametrize(
    "kind, vmax_norm, turn_price",
    [("omni", None, 0.0), ("omni", 0.4, 0.0), ("omni", None, 2.5), ("diff", None, 0.0), ("car", None, 0.0)],
)
def test_objective_gradient_matches_finite_differences(kind, vmax_norm, turn_price):
    rng = np.random.default_rng(3)
    robot = Robot(
        kind,
        vmax_lon=0.6,
        vmax_lat=0.3,
        wmax=0.05,
        min_turn_radius=30.0 if kind == "car" else 0.0,
        r_safe=1.0,
        vmax_norm=vmax_norm,
        amax_lon=0.05,
        amax_lat=0.02,
        alpha_max=0.002,
    )
    problem = make_problem(
        _bend(),
        _smooth_se2_cost(),
        _esdf_with_disc(10.0, 2.0, 1.0),
        robot,
        w_q=1.3,
        rho_T=0.7,
        w_energy=0.05,
        penalty=50.0,
        samples=6,
        piece_length=3.0,
        turn_price=turn_price,
    )
    if turn_price:  # the turns' price is in the q term
        free = make_problem(
            _bend(),
            _smooth_se2_cost(),
            _esdf_with_disc(10.0, 2.0, 1.0),
            robot,
            w_q=1.3,
            rho_T=0.7,
            w_energy=0.05,
            penalty=50.0,
            samples=6,
            piece_length=3.0,
        )
        assert problem.details(problem.initial)["q"] > 1.01 * free.details(problem.initial)["q"]
    x = problem.initial + rng.normal(size=problem.dimension) * 0.1
    taus = slice(3 * (problem.pieces - 1), 4 * problem.pieces - 1)
    x[taus] -= 1.0  # shorter durations than the initial guess: limits violated
    if kind != "omni":
        # The straight ends add their parameters; the spline places its first and last waypoints.
        # (a diff robot's heading too: it turns on the spot to it).
        end = 4 if kind == "diff" else 3
        assert problem.dimension == 3 * (problem.pieces - 3) + problem.pieces + 2 * end
        x[-2 * end :] += (
            [2.0, 2.0, -1.0, 0.3] if kind == "diff" else [2.0, 2.0, -1.0]
        ) * 2  # faster, shorter straight ends: over the speed limit there
    terms = problem.details(x)
    active = ["q", "velocity", "omega", "acceleration", "esdf", "time", "energy"]
    active += ["turn"] if kind == "car" else []
    assert all(terms[name] != 0 for name in active), terms
    if vmax_norm is not None:  # the |v| limit adds to the velocity penalty
        box = make_problem(
            _bend(),
            _smooth_se2_cost(),
            _esdf_with_disc(10.0, 2.0, 1.0),
            Robot(
                kind,
                vmax_lon=0.6,
                vmax_lat=0.3,
                wmax=0.05,
                r_safe=1.0,
                amax_lon=0.05,
                amax_lat=0.02,
                alpha_max=0.002,
                vmax_norm=math.inf,
            ),
            w_q=1.3,
            rho_T=0.7,
            w_energy=0.05,
            penalty=50.0,
            samples=6,
            piece_length=3.0,
        )
        assert terms["velocity"] > 1.01 * box.details(x)["velocity"]
    _, grad = problem.evaluate(x)
    step = 1e-6
    fd = np.array(
        [
            (problem.evaluate(x + step * e)[0] - problem.evaluate(x - step * e)[0]) / (2 * step)
            for e in np.eye(problem.dimension)
        ]
    )
    assert np.linalg.norm(fd - grad) / np.linalg.norm(grad) <= 1e-5


def test_grid_field_interpolation_and_gradient():
    cost = _smooth_se2_cost(bins=6)
    xs, ys = np.array([1.3, 7.77, 20.0]), np.array([-2.1, 3.3, 5.5])
    yaws = np.array([0.3, -2.0, 7.5])  # unwrapped yaw is wrapped by the field
    value, grad = cost.sample(xs, ys, yaws)
    step = 1e-6
    for axis in range(3):
        d = np.zeros(3)
        d[axis] = step
        hi, _ = cost.sample(xs + d[0], ys + d[1], yaws + d[2])
        lo, _ = cost.sample(xs - d[0], ys - d[1], yaws - d[2])
        np.testing.assert_allclose((hi - lo) / (2 * step), grad[:, axis], rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(cost.sample(xs, ys, yaws + 2 * np.pi)[0], value, rtol=1e-12)
    # At a cell centre the value is the stored one; beyond the border it is clamped.
    assert cost.sample(X0 + 2.5 * RES, Y0 + 3.5 * RES, 0.0)[0] == pytest.approx(cost.values[0, 3, 2])
    assert cost.sample(X0 - 50, Y0 + 0.5 * RES, 0.0)[0] == pytest.approx(cost.values[0, 0, 0])


# --- Optimised trajectories ------------------------------------------------------------


@pytest.mark.parametrize("kind", ["omni", "diff", "car"])
def test_optimised_trajectory_is_feasible(kind):
    robot = Robot(kind, vmax_lon=1.0, vmax_lat=0.5, wmax=0.8, min_turn_radius=2.0 if kind == "car" else 0.0, r_safe=0.5)
    # An obstacle 0.6 m beside the path's middle: closer than r_safe + its radius.
    esdf = _esdf_with_disc(10.0, 0.6 + 2.0 + 0.0, 1.5)
    result = optimize_trajectory(_bend(), _smooth_se2_cost(), esdf, robot, w_q=0.5, rho_T=2.0, piece_length=1.5)
    s = assert_kinematics_hold(result.trajectory, robot)
    assert np.min(esdf.sample(s["x"], s["y"])[0]) >= robot.r_safe
    assert result.violations["min_clearance"] >= 0
    assert result.trajectory.duration < 0.8 * sum(np.hypot(*np.diff(_bend()[:, :2], axis=0).T)) / 0.5


def test_car_leaves_and_reaches_rest_straight_along_the_given_yaws():
    # The start and goal yaws are 40 degrees off the path's direction: the car must
    # still leave and arrive along them, with no yaw rate at rest (turning radius).
    path = _bend()
    path[0, 2], path[-1, 2] = 0.7, -0.7
    robot = Robot("car", vmax_lon=1.0, wmax=0.8, min_turn_radius=2.0, r_safe=0.5)
    traj = optimize_trajectory(path, None, None, robot, rho_T=2.0, piece_length=1.5).trajectory
    assert traj.pieces >= 3 and np.all(traj.flat)
    for piece, yaw in ((0, 0.7), (-1, -0.7)):
        c, normal = traj.coefficients[piece], np.array([-np.sin(yaw), np.cos(yaw)])
        np.testing.assert_allclose(c[1:, :2] @ normal, 0.0, atol=1e-12)  # moves along e only
    (p0, p1), (v0, v1) = traj.evaluate([0.0, traj.duration])
    assert p0[2] == pytest.approx(0.7, abs=1e-12) and p1[2] == pytest.approx(-0.7, abs=1e-12)
    np.testing.assert_allclose([v0, v1], 0.0, atol=1e-9)  # at rest, no yaw rate
    s = assert_kinematics_hold(traj, robot)
    np.testing.assert_allclose([s["x"][-1], s["y"][-1]], path[-1, :2], atol=1e-9)
    # Between its straight ends the car keeps moving (no cusp where it could reverse).
    inner = (s["t"] > traj.durations[0] + 1e-9) & (s["t"] < traj.duration - traj.durations[-1] - 1e-9)
    assert np.min(np.hypot(s["vx"], s["vy"])[inner]) > 0.09 * robot.vmax_lon


def test_flat_heading_at_rest_is_the_limit_of_the_direction_of_travel():
    # A flat piece from rest: p = a t^2 / 2 + j t^3 / 6. At t = 0 the heading is a's
    # direction and the yaw rate (a x j) / (2 |a|^2), the limits of atan2(v) and
    # (v x a) / |v|^2 (exact, where rounding would decide from the coefficients).
    a, j = np.array([0.6, -0.2]), np.array([-0.5, 0.9])
    c = np.zeros((1, 4, 3))
    c[0, 2, :2], c[0, 3, :2] = a / 2, j / 6
    traj = Trajectory(c, np.array([2.0]), np.array([True]))
    p, v = traj.evaluate([0.0, 1e-4])
    assert p[0, 2] == pytest.approx(math.atan2(a[1], a[0]), abs=1e-12)
    assert v[0, 2] == pytest.approx((a[0] * j[1] - a[1] * j[0]) / (2 * a @ a), rel=1e-12)
    assert v[1, 2] == pytest.approx(v[0, 2], rel=1e-3)  # and continuous with its neighbourhood
    # Into rest (the piece reversed in time) the heading is -a's direction.
    back = np.zeros((1, 4, 3))
    T = 2.0
    for k in range(4):  # p(T - t) expanded in t
        back[0, :, :2] += c[0, k, :2] * np.array([[math.comb(k, m) * T ** (k - m) * (-1) ** m] for m in range(4)])
    p, v = Trajectory(back, np.array([T]), np.array([True])).evaluate([T])
    assert p[0, 2] == pytest.approx(math.atan2(-a[1], -a[0]), abs=1e-9)


def test_speed_norm_limit_holds_where_box_limits_allow_diagonal_motion():
    # Time-weighted with equal box limits, an omni robot yaws 45 degrees to move at
    # sqrt(2) vmax; a limit on |v| removes that. (The path's yaw is off the direction of
    # travel: at exactly 0 the box limits' yaw gradient vanishes by symmetry.)
    path = _straight(yaw=0.3)
    box = Robot("omni", vmax_lon=1.0, vmax_lat=1.0, wmax=1.0, r_safe=0.5, vmax_norm=math.inf)
    fast = optimize_trajectory(path, None, None, box, rho_T=5.0, rel_cost_tol=1e-6)
    s = fast.trajectory.sample(100.0)
    assert np.max(np.hypot(s["vx"], s["vy"])) > 1.2
    normed = Robot("omni", vmax_lon=1.0, vmax_lat=1.0, wmax=1.0, r_safe=0.5, vmax_norm=1.0)
    result = optimize_trajectory(path, None, None, normed, rho_T=5.0, rel_cost_tol=1e-6)
    assert_kinematics_hold(result.trajectory, normed)
    assert 0.95 <= result.violations["max_speed_ratio"] <= 1.02
    assert result.trajectory.duration > fast.trajectory.duration


def test_obstacle_on_the_straight_line_is_avoided():
    esdf = _esdf_with_disc(10.0, 0.3, 1.0)  # the straight line passes 0.3 m from its centre
    result = optimize_trajectory(_straight(), None, esdf, Robot("omni", r_safe=0.5), rho_T=1.0)
    s = result.trajectory.sample(100.0)
    assert np.min(esdf.sample(s["x"], s["y"])[0]) >= 0.5


def test_trajectory_moves_to_the_low_cost_side():
    x, y = _centres()
    cost = GridField(3.0 + 2.0 * np.tanh(y / 2.0), X0, Y0, RES)  # high for y > 0, low for y < 0
    result = optimize_trajectory(_straight(), cost, None, Robot("diff"), w_q=2.0, rho_T=1.0)
    s = result.trajectory.sample(100.0)
    assert np.mean(s["y"]) < -0.2 and np.mean(s["y"] < 0) > 0.8
    # The same with the field mirrored moves to the other side.
    mirrored = GridField(cost.values[::-1].copy(), X0, -Y0 - NY * RES, RES)
    s = optimize_trajectory(_straight(), mirrored, None, Robot("diff"), w_q=2.0, rho_T=1.0).trajectory.sample()
    assert np.mean(s["y"]) > 0.2


# --- Bad input -------------------------------------------------------------------------


def test_bad_input_raises_lf3pm_error():
    cost = _smooth_se2_cost()
    with pytest.raises(Lf3pmError, match="K >= 2"):
        optimize_trajectory(_straight()[:1], cost, None, Robot())
    bad = _straight()
    bad[3, 1] = np.nan
    with pytest.raises(Lf3pmError, match="finite"):
        optimize_trajectory(bad, cost, None, Robot())
    values = cost.values.copy()
    values[0, 0, 0] = np.inf
    with pytest.raises(Lf3pmError, match="finite"):
        GridField(values, X0, Y0, RES)
    with pytest.raises(Lf3pmError, match="res > 0"):
        GridField(cost.values, X0, Y0, -1.0)
    with pytest.raises(Lf3pmError, match="vmax_lon"):
        Robot("omni", vmax_lon=-1.0)
    with pytest.raises(Lf3pmError, match="r_safe"):
        Robot("diff", r_safe=-0.1)
    with pytest.raises(Lf3pmError, match="kind"):
        Robot("tank")
    with pytest.raises(Lf3pmError, match="omni robots only"):
        Robot("diff", vmax_norm=1.0)
    with pytest.raises(Lf3pmError, match="vmax_norm"):
        Robot("omni", vmax_norm=0.0)
    with pytest.raises(Lf3pmError, match="start and goal coincide"):
        optimize_trajectory(np.zeros((3, 3)), cost, None, Robot())
    with pytest.raises(Lf3pmError, match="rho_T"):
        optimize_trajectory(_straight(), cost, None, Robot(), rho_T=-1.0)


def test_trajectory_sample_rate_must_be_positive():
    traj = Trajectory(np.zeros((1, 4, 3)), np.ones(1))
    with pytest.raises(Lf3pmError):
        traj.sample(0.0)


def test_the_numpy_interpolation_is_the_cores():
    """lf3pm.grid_field.bilinear (Esdf.distance, Solm.query: fields with NaN the core does
    not take) and the core's GridField interpolate alike, values and gradients, inside the
    grid and clamped beyond it."""
    from lf3pm.grid_field import bilinear

    rng = np.random.default_rng(5)
    values = rng.normal(size=(7, 9))
    field = GridField(values, -1.0, 2.0, 0.5)
    x, y = rng.uniform(-2.0, 4.5, 500), rng.uniform(1.0, 6.5, 500)
    core_value, core_grad = field.sample(x, y)
    value, ddx, ddy = bilinear(values, x, y, -1.0, 2.0, 0.5)
    np.testing.assert_allclose(value, core_value, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.stack([ddx, ddy], -1), core_grad[:, :2], rtol=0, atol=1e-12)
