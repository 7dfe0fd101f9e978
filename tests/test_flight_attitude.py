"""The guidance at the planned attitude (issue 43, item 2; lf3pm.planner.flight_attitude):
its casts against lf3pm.evaluate at the same sensor poses, the corrected layer against its
definition, and plans that use it."""

from __future__ import annotations

import math

import numpy as np
import pytest

import lf3pm
from lf3pm.errors import Lf3pmError
from lf3pm.flight import Quadrotor
from lf3pm.planner.flight_attitude import PRIOR_WEIGHT, AttitudeGuidance, interpolation_nodes
from lf3pm.planner.flight_plan import FlightPlanner, guidance_field, guidance_layer
from lf3pm.replays.flight_motion import FlightMotion
from lf3pm.scenes import build_scene
from lf3pm.solm import Solm, build_solm, make_grid


@pytest.fixture(scope="module")
def tilted_room(tmp_path_factory):
    """The boxes room's r3yaw SOLM for a VLP-16 pitched 20 degrees down, noise-free."""
    world = lf3pm.load_map(build_scene("boxes").points)
    grid = make_grid(world, "r3yaw", 1.0, bounds=(-6.0, -6.0, 6.0, 6.0), yaw_bins=4, z_levels=(1.0, 2.5))
    path = tmp_path_factory.mktemp("attitude") / "boxes.zarr"
    build_solm(world, "vlp16", grid, path, noise=0.0, mount="down20", tile=6)
    solm = Solm.open(path)
    return world, solm, AttitudeGuidance(solm, world, guidance_layer(solm, lf3pm.config.DEFAULTS.guidance), 1.0), path


def banked(yaw: float, roll: float) -> np.ndarray:
    """Body to world: yaw about z, then a roll about the body's x axis."""
    c, s = math.cos(yaw), math.sin(yaw)
    r = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    cr, sr = math.cos(roll), math.sin(roll)
    return r @ np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])


def test_the_attitude_ratio_is_the_metric_tilted_over_level_as_evaluate_gives_them(tilted_room):
    """At three poses: the ratio equals q_n of lf3pm.evaluate at the tilted sensor pose over
    q_n at the level one (the SOLM's sensor and mount, no noise),
    to 1e-9; a level body gives exactly 1."""
    from lf3pm.flight.mounts import MOUNTS

    world, _, attitude, _ = tilted_room
    positions = np.array([[-2.0, -1.5, 1.5], [1.0, 2.0, 2.0], [3.0, -3.0, 2.4]])
    yaws = np.array([0.3, 2.0, -1.2])
    rotations = np.stack([banked(y, 0.4) for y in yaws])
    got = attitude.ratios(positions, rotations, yaws)
    mount = MOUNTS["down20"].matrix()
    for p, r, yaw, ratio in zip(positions, rotations, yaws, got):
        q = []
        for rotation in (r, banked(yaw, 0.0)):
            body = np.eye(4)
            body[:3, :3], body[:3, 3] = rotation, p
            q.append(lf3pm.evaluate(world, body @ mount, "vlp16", noise=0.0).q_n)
        assert ratio == pytest.approx(q[0] / q[1], rel=1e-9)
        assert abs(ratio - 1.0) > 1e-3  # the tilt does change the view
    level = np.stack([banked(y, 0.0) for y in yaws])
    np.testing.assert_array_equal(attitude.ratios(positions, level, yaws), np.ones(3))


def test_the_nodes_are_those_the_back_end_interpolates_from(tilted_room):
    """interpolation_nodes' nodes and weights reproduce the guidance field's value
    (VolumeField.sample) at 200 random samples, inside the grid and beyond its edges, to
    1e-12, on a random layer."""
    world, solm, _, _ = tilted_room
    g = solm.grid_spec
    rng = np.random.default_rng(3)
    cost = rng.uniform(0.0, 2.0, g.shape)
    field = guidance_field(solm, lf3pm.config.DEFAULTS.guidance, cost)
    p = np.column_stack([rng.uniform(-7, 7, 200), rng.uniform(-7, 7, 200), rng.uniform(0.5, 3.0, 200)])
    yaws = rng.uniform(-7, 7, 200)
    got, _ = field.sample(p, yaws)
    nodes, weights = interpolation_nodes(g, p, yaws)
    np.testing.assert_allclose(np.sum(cost.ravel()[nodes] * weights, axis=1), got, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(weights.sum(axis=1), 1.0, rtol=1e-12)


def test_the_correction_weighs_each_node_s_samples_against_the_flight_s_mean(tilted_room):
    """A hovering sample (ratio 1) leaves the layer as it was, bit for bit. One banked
    sample: its ratio is the flight's mean, so every node's uncapped cost is multiplied by
    it to the guidance power, then capped. Two banked samples far apart: a node interpolated
    from the first alone with weight w takes exp((w log r1 + PRIOR_WEIGHT m) / (w +
    PRIOR_WEIGHT)), m the mean log ratio; a node neither touches takes exp(m)."""
    world, solm, _, _ = tilted_room
    layer = guidance_layer(solm, lf3pm.config.DEFAULTS.guidance)
    level = np.where(
        np.isnan(layer.cost), layer.cap, np.minimum(AttitudeGuidance(solm, world, layer, 2.0).uncapped, layer.cap)
    )
    quad = Quadrotor(mount="down20")
    zero = np.zeros((1, 3))
    hover = {"position": np.array([[1.0, 2.0, 2.5]]), "velocity": zero, "acceleration": zero, "jerk": zero}
    hover |= {"yaw": np.array([2.0]), "yaw_rate": np.zeros(1)}
    cost, summary = AttitudeGuidance(solm, world, layer, 2.0).correct(hover, quad)
    np.testing.assert_array_equal(cost, level)
    assert summary["samples"] == 1 and summary["ratio_median"] == 1.0

    def expected(attitude, log_ratio):
        out = np.minimum(attitude.uncapped * np.exp(2.0 * log_ratio), layer.cap)
        return np.where(np.isnan(layer.cost), layer.cap, out)

    attitude = AttitudeGuidance(solm, world, layer, 2.0)
    sideways = dict(hover, position=np.array([[1.3, 2.2, 2.1]]), acceleration=np.array([[0.0, 4.0, 0.0]]))
    cost, summary = attitude.correct(sideways, quad)
    att = quad.attitudes(zero, sideways["acceleration"], zero, [2.0], [0.0])
    r1 = attitude.ratios(sideways["position"], att.rotation, np.array([2.0]))[0]
    assert abs(r1 - 1.0) > 1e-3 and summary["ratio_median"] == pytest.approx(r1, rel=1e-12)
    np.testing.assert_allclose(cost, expected(attitude, math.log(r1)), rtol=1e-12)

    attitude = AttitudeGuidance(solm, world, layer, 2.0)
    two = {k: np.concatenate([v, v]) for k, v in sideways.items()}
    two["position"] = np.array([[1.3, 2.2, 2.1], [-4.2, -3.1, 1.2]])
    two["acceleration"] = np.array([[0.0, 4.0, 0.0], [3.0, 0.0, 0.0]])
    cost, _ = attitude.correct(two, quad)
    att = quad.attitudes(np.zeros((2, 3)), two["acceleration"], np.zeros((2, 3)), two["yaw"], np.zeros(2))
    r = attitude.ratios(two["position"], att.rotation, two["yaw"])
    mean = float(np.mean(np.log(r)))
    nodes, weights = interpolation_nodes(solm.grid_spec, two["position"], two["yaw"])
    only_first = [
        (n, w) for n, w in zip(nodes[0], weights[0]) if w > 0 and n not in nodes[1] and not np.isnan(layer.cost.flat[n])
    ]
    node, w = only_first[0]
    log_node = (w * math.log(r[0]) + PRIOR_WEIGHT * mean) / (w + PRIOR_WEIGHT)
    assert cost.flat[node] == pytest.approx(
        min(attitude.uncapped.flat[node] * math.exp(2.0 * log_node), layer.cap), rel=1e-12
    )
    untouched = np.setdiff1d(np.flatnonzero(~np.isnan(layer.cost.ravel())), nodes.ravel())
    np.testing.assert_allclose(cost.ravel()[untouched], expected(attitude, mean).ravel()[untouched], rtol=1e-12)


def test_a_plan_corrected_for_its_attitude_still_holds_its_limits(tilted_room, tmp_path):
    """With a round at the planned attitude: one summary per round, limits held on 1 kHz
    samples, rest at both ends; without: no round and the level plan. Bad rounds: one line."""
    world, solm, _, _ = tilted_room
    planner = FlightPlanner(solm, world, quadrotor=Quadrotor(mount="down20"))
    start, goal = (-5.5, -5.5, 1.0, 0.0), (5.5, 5.5, 2.5)
    level = planner.plan(start, goal, attitude_rounds=0)
    corrected = planner.plan(start, goal, attitude_rounds=2)
    assert level.attitude == [] and len(corrected.attitude) == 2
    assert corrected.attitude[0]["samples"] > 20
    # The rounds did optimise on the corrected field: another flight.
    assert np.abs(corrected.trajectory.coefficients - level.trajectory.coefficients).max() > 1e-6
    for plan in (level, corrected):
        assert max(plan.limits.values()) <= 1.0 + 1e-9
        s = plan.trajectory.sample(100.0)
        np.testing.assert_allclose(s["position"][[0, -1]], [start[:3], goal], atol=1e-9)
    for bad in (-1, 11, 1.5):
        with pytest.raises(Lf3pmError, match="attitude_rounds"):
            planner.plan(start, goal, attitude_rounds=bad)
    with pytest.raises(Lf3pmError, match="attitude_rounds apply to the joint planner, not yaw_only"):
        planner.plan(start, goal, planner="yaw_only", attitude_rounds=1)
    # Its CSV (17 digits) flies back as the plan: many pieces, time-scaled.
    path = tmp_path / "flight.csv"
    path.write_bytes(corrected.trajectory.csv_bytes(planner.quad))
    read = FlightMotion.from_csv(path, quadrotor=planner.quad)
    truth = FlightMotion.from_pieces(
        corrected.trajectory.coefficients, corrected.trajectory.durations, quadrotor=planner.quad
    )
    t = np.linspace(0.0, corrected.trajectory.duration, 50001)
    np.testing.assert_allclose(read.position(t), truth.position(t), atol=1e-6)
    a, b = read.attitudes(t), truth.attitudes(t)
    angle = np.arccos(np.clip((np.einsum("nij,nij->n", a.rotation, b.rotation) - 1.0) / 2.0, -1.0, 1.0))
    assert angle.max() < 1e-3 and np.abs(a.omega - b.omega).max() < 1e-3
    heavy = Quadrotor(mount="down20", mass=2.0)
    with pytest.raises(Lf3pmError, match="fly it with the plan's quadrotor section"):
        FlightMotion.from_csv(path, quadrotor=heavy)
    from lf3pm.planner.plan import Planner

    with pytest.raises(Lf3pmError, match=r"this one is r3yaw \(flights: lf3pm.planner.flight_plan.plan_flight\)"):
        Planner(solm)


def test_lf3pm_plan_says_what_each_attitude_round_changed(tilted_room, tmp_path):
    from typer.testing import CliRunner

    from lf3pm.cli import app

    world, _, _, store = tilted_room
    np.save(tmp_path / "boxes.npy", world.points)
    args = [
        "plan",
        "--robot",
        "quadrotor",
        "--mount",
        "down20",
        "--solm",
        str(store),
        "--map",
        str(tmp_path / "boxes.npy"),
    ]
    args += ["-o", str(tmp_path / "f.csv"), "--start", "-5.5", "-5.5", "0", "--goal", "5.5", "5.5", "0"]
    done = CliRunner().invoke(app, [*args, "--start-z", "1", "--goal-z", "2.5", "--attitude-rounds", "1"])
    assert done.exit_code == 0, done.output
    assert "attitude round 1: the guidance at the flown attitude over level, median" in done.output
    bad = CliRunner().invoke(app, [*args, "--start-z", "1", "--goal-z", "2.5", "--attitude-rounds", "11"])
    assert bad.exit_code != 0 and "attitude_rounds" in bad.output and "Traceback" not in bad.output
    for other in (["--planner", "velocity_yaw"], ["--robot", "omni"]):
        done = CliRunner().invoke(app, [*args, "--start-z", "1", "--goal-z", "2.5", "--attitude-rounds", "1", *other])
        assert (
            done.exit_code != 0 and "--attitude-rounds applies to --robot quadrotor with --planner joint" in done.output
        )
