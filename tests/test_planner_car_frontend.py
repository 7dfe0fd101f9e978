"""The car front end: forward Dubins paths against known lengths and a numeric
search over every word, and the Hybrid-A* search on seeded random box mazes
(exact ends, curvature <= 1/R, forward only, clear of obstacles, its cost
against lower bounds and the grid search's, the heuristic against found costs)."""

import functools
import itertools
import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from lf3pm.errors import Lf3pmError
from lf3pm.planner.esdf import Esdf
from lf3pm.planner.graph_search import search_path
from lf3pm.planner.hybrid_search import dubins_path, sample_segments, search_car_path, search_heuristic

R = 0.5
KAPPA = math.sqrt(4 - 2 * math.sqrt(2))  # most an octile distance exceeds the Euclidean one


def wrap(a):
    return np.angle(np.exp(1j * np.asarray(a)))


def end_of(start, segments):
    return sample_segments(start, segments, 0.05)[-1]


@pytest.mark.parametrize(
    "goal,length",
    [
        ((3.0, 0.0, 0.0), 3.0),  # straight ahead
        ((0.0, 0.0, 0.0), 0.0),  # already there
        ((R, R, math.pi / 2), math.pi / 2 * R),  # quarter turn left
        ((R, -R, -math.pi / 2), math.pi / 2 * R),  # quarter turn right
        ((0.0, 2 * R, math.pi), math.pi * R),  # U-turn
        ((-1.5, 2 * R, math.pi), math.pi * R + 1.5),  # U-turn, then straight back
        ((-1e-3, 0.0, 0.0), 2 * math.pi * R + 1e-3),  # just behind: a full circle
    ],
)
def test_dubins_lengths_of_known_cases(goal, length):
    d = dubins_path((0.0, 0.0, 0.0), goal, R)
    assert d["length"] == pytest.approx(length, abs=1e-9)
    np.testing.assert_allclose(end_of((0, 0, 0), d["segments"])[:2], goal[:2], atol=1e-9)


def word_residual(word, start, goal, radius):
    """Distance from the goal after segments of lengths u along a word (an independent
    integration of the unicycle, by small steps for CCC words' checks too)."""
    kind = {"L": 1 / radius, "R": -1 / radius, "S": 0.0}

    def end(u):
        x, y, th = start
        for letter, length in zip(word, u):
            k = kind[letter]
            if k == 0:
                x, y = x + length * math.cos(th), y + length * math.sin(th)
            else:
                x, y = (
                    x + (math.sin(th + k * length) - math.sin(th)) / k,
                    y + (math.cos(th) - math.cos(th + k * length)) / k,
                )
                th += k * length
        return np.array([x - goal[0], y - goal[1], math.sin(th - goal[2]), 1 - math.cos(th - goal[2])])

    return end


def numeric_shortest(start, goal, radius, rng):
    """The shortest word found by least squares from many starting lengths: an
    upper bound of the true Dubins length, independent of the geometric code."""
    best = math.inf
    for word in ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL"):
        f = word_residual(word, start, goal, radius)
        for _ in range(12):
            u0 = rng.uniform(0, 2 * math.pi * radius, 3)
            r = least_squares(f, u0, bounds=(0, np.inf), xtol=1e-14, ftol=1e-14, gtol=1e-14)
            if np.max(np.abs(f(r.x))) < 1e-9:
                best = min(best, float(np.sum(r.x)))
    return best


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(8))
def test_dubins_is_the_shortest_word_and_reaches_the_goal(seed):
    rng = np.random.default_rng(seed)
    start, goal = rng.uniform(-2, 2, 3), rng.uniform(-2, 2, 3)
    radius = rng.uniform(0.3, 1.5)
    d = dubins_path(start, goal, radius)
    end = end_of(start, d["segments"])
    np.testing.assert_allclose(end[:2], goal[:2], atol=1e-9)
    assert abs(wrap(end[2] - goal[2])) < 1e-9
    assert d["length"] == pytest.approx(min(d["words"].values()))
    assert d["length"] <= numeric_shortest(start, goal, radius, rng) + 1e-7
    assert d["length"] >= math.hypot(*(goal[:2] - start[:2])) - 1e-12


@pytest.mark.parametrize("seed", range(6))
def test_dubins_lengths_are_symmetric_and_scale_with_r(seed):
    rng = np.random.default_rng(100 + seed)
    a, b = rng.uniform(-2, 2, 3), rng.uniform(-2, 2, 3)
    length = dubins_path(a, b, R)["length"]
    mirror = np.array([1.0, -1.0, -1.0])  # reflect in the x axis: left and right swap
    assert dubins_path(a * mirror, b * mirror, R)["length"] == pytest.approx(length, rel=1e-9)
    # Driven backwards in time: from the goal turned round to the start turned round.
    back = np.array([0.0, 0.0, math.pi])
    assert dubins_path(b + back, a + back, R)["length"] == pytest.approx(length, rel=1e-9)
    scale = np.array([3.0, 3.0, 1.0])
    assert dubins_path(a * scale, b * scale, 3 * R)["length"] == pytest.approx(3 * length, rel=1e-9)


def menger_curvature(p):
    """Curvature of the circle through each three consecutive points."""
    a, b, c = p[:-2, :2], p[1:-1, :2], p[2:, :2]
    ab, bc, ca = np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1), np.linalg.norm(a - c, axis=1)
    cross = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]
    return 2 * np.abs(cross) / (ab * bc * ca)


def assert_forward_and_bounded(poses, radius):
    """Curvature <= 1/R from the positions alone; the yaw points along the motion."""
    assert np.max(menger_curvature(poses)) <= (1 + 1e-6) / radius
    step = np.diff(poses[:, :2], axis=0)
    ds = np.linalg.norm(step, axis=1)
    assert np.all(ds > 0)
    # The chord's direction lies halfway between the yaws at its ends (arcs and straights).
    assert np.max(np.abs(wrap(np.arctan2(step[:, 1], step[:, 0]) - 0.5 * (poses[1:, 2] + poses[:-1, 2])))) < 1e-9
    # A chord ds of a circle of radius R turns the yaw by 2 asin(ds / 2R): no more.
    assert np.all(np.abs(np.diff(poses[:, 2])) <= 2 * np.arcsin(np.minimum(ds / (2 * radius), 1)) + 1e-9)


@pytest.mark.parametrize("seed", range(6))
def test_dubins_samples_keep_the_turning_radius(seed):
    rng = np.random.default_rng(200 + seed)
    start, goal = rng.uniform(-2, 2, 3), rng.uniform(-2, 2, 3)
    d = dubins_path(start, goal, R)
    poses = sample_segments(start, d["segments"][d["segments"][:, 1] > 0], 0.03)
    np.testing.assert_allclose(poses[0], start, atol=0)
    assert_forward_and_bounded(poses, R)


RES = 0.2


def box_maze(seed, nx=45, ny=35, boxes=9):
    """Seeded random boxes in a walled field of RES cells (x0 = y0 = 0)."""
    rng = np.random.default_rng(seed)
    mask = np.zeros((ny, nx), bool)
    mask[0, :] = mask[-1, :] = mask[:, 0] = mask[:, -1] = True
    for _ in range(boxes):
        w, h = rng.integers(2, 7, 2)
        x, y = rng.integers(1, nx - w), rng.integers(1, ny - h)
        mask[y : y + h, x : x + w] = True
    cost = np.abs(np.sin(np.arange(nx) * 0.3)[None, :] + np.cos(np.arange(ny) * 0.2)[:, None]) + 0.2
    return Esdf.from_mask(mask, 0.0, 0.0, RES), cost


def random_free_pose(esdf, rng, clearance):
    while True:
        x, y = rng.uniform(0, esdf.nx * RES), rng.uniform(0, esdf.ny * RES)
        if esdf.distance(x, y)[0] >= clearance + 0.3:
            return np.array([x, y, rng.uniform(-math.pi, math.pi)])


CLEARANCE = 0.1


@functools.lru_cache(maxsize=1)
def queries(count=8):
    """The first ``count`` seeded random queries with a forward path (a random pose may
    face a wall too closely to turn away from it)."""
    out = []
    for seed in itertools.count():
        esdf, cost = box_maze(seed)
        rng = np.random.default_rng(seed)
        start, goal = random_free_pose(esdf, rng, CLEARANCE), random_free_pose(esdf, rng, CLEARANCE)
        try:
            search_car_path(cost, esdf, start, goal, radius=R, weight=1.0, clearance=CLEARANCE)
        except Lf3pmError:
            continue
        out.append((esdf, cost, start, goal))
        if len(out) == count:
            return out


def trapezoid_cost(poses, esdf, cost, weight):
    from lf3pm.grid_field import GridField

    c = GridField(cost, esdf.x0, esdf.y0, esdf.res).sample(poses[:, 0], poses[:, 1])[0]
    ds = np.linalg.norm(np.diff(poses[:, :2], axis=0), axis=1)
    return float(np.sum(ds * (1 + weight * 0.5 * (c[1:] + c[:-1]))))


@pytest.mark.parametrize("case", range(8))
def test_hybrid_paths_are_exact_forward_bounded_and_clear(case):
    esdf, cost, start, goal = queries()[case]
    path = search_car_path(cost, esdf, start, goal, radius=R, weight=1.0, clearance=CLEARANCE)
    np.testing.assert_allclose(path.poses[0], start, atol=0)
    np.testing.assert_allclose(path.poses[-1, :2], goal[:2], atol=0)
    assert abs(wrap(path.poses[-1, 2] - goal[2])) < 1e-12
    # The sampled integration itself lands on the goal (the exact end is no patch).
    end = sample_segments(start, path.segments, 0.05)[-1]
    np.testing.assert_allclose(end[:2], goal[:2], atol=1e-9)
    assert path.length == pytest.approx(path.segments[:, 1].sum()) and np.all(path.segments[:, 1] > 0)
    assert set(np.round(np.abs(path.segments[:, 0]) * R, 12)) <= {0.0, 1.0}
    assert_forward_and_bounded(path.poses, R)
    dense = sample_segments(start, path.segments, 0.01)
    # Samples every res / 4 = 0.05 m keep the clearance; between them the bilinear
    # field (slope <= sqrt 2) can dip by at most sqrt 2 * 0.025 m.
    assert np.min(esdf.distance(dense[:, 0], dense[:, 1])[0]) >= CLEARANCE - math.sqrt(2) * 0.025
    assert path.cost == pytest.approx(trapezoid_cost(dense, esdf, cost, 1.0), rel=2e-3)


@pytest.mark.parametrize("case", range(8))
def test_hybrid_cost_is_bounded_by_dubins_and_the_grid_search(case):
    esdf, cost, start, goal = queries()[case]
    weight = 1.0
    path = search_car_path(cost, esdf, start, goal, radius=R, weight=weight, clearance=CLEARANCE)
    unit = 1 + weight * cost.min()
    assert path.cost >= unit * dubins_path(start, goal, R)["length"] - 1e-9
    # The grid search over cells at least the clearance from obstacles: a car's path is a
    # restriction of it up to the octile metric (at most KAPPA longer than a straight line)
    # and the start and goal lying off their cell centres.
    grid = search_path(cost, esdf, esdf, start, goal, weight=weight, r_safe=CLEARANCE)
    assert path.cost >= grid.cost / KAPPA - 2 * RES * (1 + weight * cost.max())


@pytest.mark.slow
@pytest.mark.parametrize("case", range(8))
def test_heuristic_never_exceeds_found_costs_to_go(case):
    esdf, cost, start, goal = queries()[case]
    rng = np.random.default_rng(300 + case)
    poses = np.array([random_free_pose(esdf, rng, CLEARANCE) for _ in range(6)] + [start])
    h = search_heuristic(cost, esdf, poses, goal, radius=R, weight=1.0, clearance=CLEARANCE)
    for pose, bound in zip(poses, h):
        # The least cost any of several searches finds is an upper bound of the true cost-to-go.
        found = []
        for kw in (dict(), dict(heuristic=False), dict(yaw_bins=144, step=0.15, sample_step=0.03)):
            try:
                found.append(
                    search_car_path(cost, esdf, pose, goal, radius=R, weight=1.0, clearance=CLEARANCE, **kw).cost
                )
            except Lf3pmError:
                pass
        if found:
            assert bound <= min(found) + 1e-9


def test_heuristic_is_the_dubins_bound_in_the_open():
    esdf = Esdf.from_mask(np.pad(np.zeros((30, 40), bool), 1, constant_values=True), 0.0, 0.0, RES)
    goal = np.array([4.0, 3.0, 1.0])
    rng = np.random.default_rng(7)
    poses = np.column_stack([rng.uniform(2, 6, 20), rng.uniform(2, 4, 20), rng.uniform(-3, 3, 20)])
    cost = np.full((32, 42), 0.5)
    h = search_heuristic(cost, esdf, poses, goal, radius=R, weight=2.0, clearance=CLEARANCE)
    expected = [2.0 * max(dubins_path(p, goal, R)["length"], 0.0) for p in poses]
    np.testing.assert_allclose(h, expected, rtol=1e-12)


def test_a_goal_facing_back_is_reached_with_a_loop():
    esdf = Esdf.from_mask(np.pad(np.zeros((30, 50), bool), 1, constant_values=True), 0.0, 0.0, RES)
    start, goal = (2.0, 3.0, 0.0), (6.0, 3.0, math.pi)  # the goal's yaw points back at the start
    path = search_car_path(None, esdf, start, goal, radius=R, clearance=CLEARANCE)
    turned = np.sum(path.segments[:, 0] * path.segments[:, 1])
    assert abs(turned) == pytest.approx(math.pi, abs=1e-9)  # it turns round, forwards only
    assert path.length == pytest.approx(dubins_path(start, goal, R)["length"], rel=1e-9)
    assert_forward_and_bounded(path.poses, R)


def test_a_start_facing_a_wall_loops_in_a_corridor():
    # A 2 m wide corridor: the car faces its wall and must turn round to reach the goal behind it.
    mask = np.ones((22, 60), bool)
    mask[6:16, 1:59] = False
    esdf = Esdf.from_mask(mask, 0.0, 0.0, RES)
    start, goal = (6.0, 2.2, math.pi / 2), (1.5, 2.2, math.pi)
    path = search_car_path(None, esdf, start, goal, radius=R, clearance=CLEARANCE)
    dense = sample_segments(start, path.segments, 0.01)
    assert np.min(esdf.distance(dense[:, 0], dense[:, 1])[0]) >= CLEARANCE - 0.04
    assert_forward_and_bounded(path.poses, R)


@pytest.fixture(scope="module")
def walled():
    mask = np.zeros((20, 20), bool)
    mask[8:12, 8:12] = True
    mask[0, :] = mask[-1, :] = mask[:, 0] = mask[:, -1] = True
    return Esdf.from_mask(mask, 0.0, 0.0, RES)


@pytest.mark.parametrize(
    "kwargs,needle",
    [
        (dict(radius=0.0), "turning radius must be a positive number"),
        (dict(radius=float("nan")), "turning radius must be a positive number"),
        (dict(radius=-1.0), "turning radius must be a positive number"),
        (dict(radius=R, start=(2.0, 2.0, 0.0)), "start (2.00, 2.00, 0.00) is inside an obstacle"),
        (dict(radius=R, goal=(9.0, 1.0, 0.0)), "goal (9.00, 1.00, 0.00) lies outside the grid"),
        (dict(radius=R, start=(0.3, 1.0, 0.0)), "closer than r_safe 0.1 m"),
        (dict(radius=R, yaw_bins=2), "yaw_bins must be an integer >= 4"),
        (dict(radius=R, start=(1.0, 1.0, float("inf"))), "start must be three finite numbers"),
        # Heading straight into the wall 0.4 m ahead, with nowhere to turn: no forward path.
        (dict(radius=2.0, start=(1.0, 3.0, math.pi)), "no forward path of turning radius 2 m"),
    ],
)
def test_errors_are_one_line(walled, kwargs, needle):
    args = dict(start=(1.0, 1.0, 0.0), goal=(3.0, 3.0, 0.0), clearance=CLEARANCE) | kwargs
    with pytest.raises(Lf3pmError) as err:
        search_car_path(None, walled, **args)
    assert needle in str(err.value) and "\n" not in str(err.value)


def test_an_enclosed_goal_is_unreachable(walled):
    mask = np.zeros((20, 20), bool)
    mask[5:15, 5] = mask[5:15, 14] = mask[5, 5:15] = mask[14, 5:15] = True
    esdf = Esdf.from_mask(mask, 0.0, 0.0, RES)
    with pytest.raises(Lf3pmError, match="no chain of cells clear of obstacles joins start and goal"):
        search_car_path(None, esdf, (0.5, 0.5, 0.0), (2.0, 2.0, 0.0), radius=0.2, clearance=CLEARANCE)
