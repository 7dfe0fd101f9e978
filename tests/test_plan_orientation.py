"""The orientation plan survives to the trajectory: shortcutting keeps the front
end's yaws for omni robots on SE(2) costs, the back end starts from them, and an
omni robot whose sensor sees structure only behind it travels facing backwards."""

import math

import numpy as np
import pytest

from lf3pm.errors import Lf3pmError
from lf3pm.grid_field import GridField
from lf3pm.planner import Planner
from lf3pm.planner.shortcut import shortcut_path
from lf3pm.solm.grid import SolmGrid
from lf3pm.trajectory import Robot

BINS, RES, NX, NY = 36, 0.5, 80, 24


class FieldSolm:
    """A SOLM stand-in: an open field (no obstacle, no unknown cell) whose q_n
    depends on the yaw only: q(yaw) = 1 + 2 (1 + cos yaw), lowest (1) facing -x,
    where the structure is, highest (5) facing +x, the open ground."""

    def __init__(self):
        self.grid_spec = SolmGrid("se2", 0.0, 0.0, RES, NX, NY, yaw_bins=BINS)
        self.attrs = {"robot_radius": 0.3}
        yaws = np.arange(BINS) * 2 * math.pi / BINS
        self._q = np.broadcast_to((1 + 2 * (1 + np.cos(yaws)))[:, None, None], (BINS, NY, NX)).copy()

    def channel(self, name):
        return self._q if name in ("q_n", "q_min", "step_norm") else np.zeros((BINS, NY, NX))

    def occupancy(self):
        return np.zeros((NY, NX), bool), 1


def backwards_share(samples) -> float:
    """Share of the samples facing within 0.5 rad of -x."""
    return float(np.mean(np.abs(np.angle(np.exp(1j * (samples["yaw"] - math.pi)))) < 0.5))


@pytest.fixture(scope="module")
def planner():
    return Planner(FieldSolm())


def test_omni_travels_facing_the_structure_behind_it(planner):
    plan = planner.plan((2.0, 6.0, 0.0), (36.0, 6.0, 0.0), robot=Robot("omni", r_safe=0.05), metric="q_n", weight=1.0)
    s = plan.trajectory.sample(100.0)
    assert np.ptp(s["x"]) > 30
    # The front end turns round and back; the trajectory keeps that plan.
    front = np.asarray(plan.path.poses)
    moving = np.hypot(*np.diff(front[:, :2], axis=0).T) > 0  # x-y steps, not turns on the spot
    assert np.all(np.abs(np.angle(np.exp(1j * (front[1:][moving, 2] - math.pi)))) < 0.5)
    assert backwards_share(s) > 0.7
    unguided = planner.plan((2.0, 6.0, 0.0), (36.0, 6.0, 0.0), robot=Robot("omni", r_safe=0.05), metric="none")
    assert backwards_share(unguided.trajectory.sample(100.0)) < 0.05


def test_the_turn_price_decides_whether_turning_round_pays(planner):
    # Facing -x instead of +x saves at most weight * (5 - 1) / 3 per metre (cost q / median q,
    # median 3), under 46 m over these 34 m; turning the sensor by pi / 2 or more and back
    # costs at least pi * turn_radius * (1 + 1/3) of path: 84 m at 20 m, so it never pays.
    # At the default radius (2 m: at most 34 m for turning round and back) it does.
    ends, robot = ((2.0, 6.0, 0.0), (36.0, 6.0, 0.0)), Robot("omni", r_safe=0.05)
    priced = planner.plan(*ends, robot=robot, metric="q_n", weight=1.0, turn_radius=20.0)
    yaw = priced.trajectory.sample(100.0)["yaw"]
    assert np.max(np.abs(np.angle(np.exp(1j * yaw)))) < math.pi / 2
    assert backwards_share(planner.plan(*ends, robot=robot, metric="q_n", weight=1.0).trajectory.sample(100.0)) > 0.7


class WeakDirectionSolm(FieldSolm):
    """The field with its yaw dependence in q_max only (the weakest direction): q_n,
    q_min and step_norm are the same at every yaw."""

    def channel(self, name):
        if name == "q_max":
            return self._q
        return np.ones_like(self._q) if name in ("q_n", "q_min", "step_norm") else np.zeros_like(self._q)


def test_q_max_guidance_reads_its_own_channel():
    planner, ends = Planner(WeakDirectionSolm()), ((2.0, 6.0, 0.0), (36.0, 6.0, 0.0))
    robot = Robot("omni", r_safe=0.05)
    assert backwards_share(planner.plan(*ends, robot=robot, metric="q_max", weight=1.0).trajectory.sample(100.0)) > 0.7
    assert backwards_share(planner.plan(*ends, robot=robot, metric="q_n", weight=1.0).trajectory.sample(100.0)) < 0.05


def test_yaw_aware_shortcut_keeps_the_turns_and_never_costs_more():
    solm = FieldSolm()
    cost = GridField(solm.channel("q_n") / 3.0, 0.0, 0.0, RES)
    esdf = GridField(np.full((NY, NX), 100.0), 0.0, 0.0, RES)
    # A staircase that turns round on the spot first, then moves along +x facing -x.
    x = np.r_[np.full(18, 1.25), np.arange(1.25, 15.0, 0.5)]
    yaw = np.r_[np.arange(18) * 2 * math.pi / BINS, np.full(len(x) - 18, math.pi)]
    y = np.full(len(x), 6.25) + 0.5 * (np.arange(len(x)) % 2) * (x > 1.25)
    path = np.column_stack([x, y, yaw])
    for mode, weight in (("interpolate", 1.0), ("interpolate", 5.0), ("travel", 1.0)):
        keep = shortcut_path(path, esdf, 0.1, cost, weight, yaw=mode)
        assert keep[0] == 0 and keep[-1] == len(path) - 1 and np.all(np.diff(keep) > 0)
        kept = path[keep]
        if mode == "interpolate":
            # The turn round survives: yaw pi from the first metres on.
            assert kept[1, 2] == pytest.approx(math.pi, abs=0.2)
        for a, b in zip(keep[:-1], keep[1:]):  # each segment costs no more than its run
            run = sum(_cost(path[k], path[k + 1], cost, weight, mode) for k in range(a, b))
            assert _cost(path[a], path[b], cost, weight, mode) <= run + 1e-9


def _cost(a, b, cost, weight, mode, step=RES / 4):
    """The shortcut's functional, by hand: (length + 0.5 |dyaw|) (1 + weight mean c)."""
    n = max(2, int(math.ceil(math.hypot(*(b[:2] - a[:2])) / step)) + 1)
    t = np.linspace(0, 1, n)
    x, y = a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])
    if mode == "travel":
        yaw, turn = np.full(n, math.atan2(b[1] - a[1], b[0] - a[0])), 0.0
    else:
        yaw, turn = a[2] + t * (b[2] - a[2]), 0.5 * abs(b[2] - a[2])
    length = math.hypot(*(b[:2] - a[:2])) + turn
    if length == 0:
        return 0.0
    c = cost.sample(x, y, yaw)[0]
    return length * (1 + weight * np.mean(0.5 * (c[1:] + c[:-1])))


def _densify(poses, step=0.05):
    """The path's poses with points every ``step`` (x-y, yaw at 0.5 m/rad) between them."""
    out = [poses[0]]
    for a, b in zip(poses[:-1], poses[1:]):
        n = max(1, int(math.ceil(max(math.hypot(*(b[:2] - a[:2])), 0.5 * abs(b[2] - a[2])) / step)))
        out += list(a + np.linspace(0, 1, n + 1)[1:, None] * (b - a))
    return np.array(out)


@pytest.mark.slow
@pytest.mark.parametrize("weight", [1.0, 5.0])
def test_trajectory_keeps_the_front_ends_cost_on_random_se2_queries(orientation_planner, weight):
    """The front end's objective, integral of (1 + weight c) (ds + 0.5 |d yaw|) with c the
    cost layer at the pose's yaw, is at most 5 % higher along the trajectory than along the
    front-end path, on random queries whose start and goal yaws are their cells' cheapest
    (a given yaw that is not the cheapest costs a turn either way)."""
    planner = orientation_planner
    layer = planner.cost_layer("q_n")
    g = planner.esdf
    cost = GridField(layer.filled, g.x0, g.y0, g.res)
    bins = layer.filled.shape[0]

    def objective(x, y, yaw):
        ds = np.hypot(np.diff(x), np.diff(y)) + 0.5 * np.abs(np.diff(yaw))
        c = cost.sample(x, y, yaw)[0]
        return float(np.sum(ds * (1 + weight * 0.5 * (c[1:] + c[:-1]))))

    ys, xs = np.nonzero(g.traversable(0.3))
    rng = np.random.default_rng(0)
    ratios = []
    while len(ratios) < 10:
        i, j = rng.choice(len(xs), 2, replace=False)
        if math.hypot(xs[i] - xs[j], ys[i] - ys[j]) * g.res < 8:
            continue
        start, goal = (
            (
                g.x0 + (xs[k] + 0.5) * g.res,
                g.y0 + (ys[k] + 0.5) * g.res,
                2 * math.pi / bins * np.argmin(layer.filled[:, ys[k], xs[k]]),
            )
            for k in (i, j)
        )
        try:
            plan = planner.plan(start, goal, robot=Robot("omni"), metric="q_n", weight=weight)
        except Lf3pmError:  # a cell behind the building, cut off from the open ground
            continue
        front = np.array(plan.path.poses, float)
        front[0], front[-1] = start, goal
        front[:, 2] = np.unwrap(front[:, 2])
        front = _densify(front)
        s = plan.trajectory.sample(100.0)
        ratios.append(objective(s["x"], s["y"], s["yaw"]) / objective(front[:, 0], front[:, 1], front[:, 2]))
    assert max(ratios) <= 1.05, ratios
