"""Localization on the prior map (localization.py) through replay(): millimetres
on a well-constrained scene, the prior kept along a corridor's axis, the SE(2)
helpers against direct formulas, determinism and pickling."""

import math
import pickle

import numpy as np
import pytest
from analytic_scenes import grid_plane, spinning_directions

import lf3pm
from lf3pm.errors import Lf3pmError
from lf3pm.pose import pose_matrix, se3_exp
from lf3pm.replays.localization import Degeneracy, WheelOdometry, deskew, planar_exp, planar_log, planar_matrix
from lf3pm.replays.motion import Motion
from lf3pm.replays.replay import replay
from lf3pm.scenes import build_scene
from lf3pm.sensors import Sensor
from lf3pm.validation.mde import RegistrationTarget


@pytest.fixture(scope="module")
def boxes():
    world = lf3pm.load_map(build_scene("boxes").points)
    t = np.linspace(0.0, 2.0, 201)
    # 1.6 m at 0.8 m/s through the room, swerving 0.3 m.
    motion = Motion.from_arrays(t, -2 + 0.8 * t, 0.3 * np.sin(t), np.arctan2(0.3 * np.cos(t), 0.8), map=world)
    return world, motion, RegistrationTarget(world)


def test_noise_free_localization_on_a_structured_scene_is_within_a_centimetre(boxes):
    world, motion, target = boxes
    result = replay(world, motion, "vlp16", "localization", target=target, noise=0.0, scale_error=0.0, yaw_noise=0.0)
    assert result.scans == 21 and not result.skipped and not result.degenerate.any()
    # Measured 3.2 mm rmse (5.9 mm max): surfel hits and estimated map normals, not noise.
    assert result.ape["rmse"] < 0.01 and result.ape["max"] < 0.02
    assert result.method == "localization" and result.versions["small_gicp"]
    assert result.params["localization"]["odometry"] == {"scale_error": 0.0, "yaw_noise": 0.0}


@pytest.mark.slow
def test_same_seed_same_result_and_the_result_pickles(boxes):
    world, motion, target = boxes
    a = replay(world, motion, "vlp16", "localization", seed=4, target=target)
    b = replay(world, motion, "vlp16", "localization", seed=4, target=target)
    np.testing.assert_array_equal(a.estimate, b.estimate)  # one registration thread: bit for bit
    c = pickle.loads(pickle.dumps(a))
    np.testing.assert_array_equal(c.estimate, a.estimate)
    assert c.to_dict() == a.to_dict() and c.ape["rmse"] < 0.01
    other = replay(world, motion, "vlp16", "localization", seed=5, target=target)
    assert not np.array_equal(other.estimate, a.estimate)


CORRIDOR_LENGTH, CORRIDOR_WIDTH = 80.0, 4.0


@pytest.fixture(scope="module")
def corridor():
    """Two 80 m walls 4 m apart and a floor, no end within the 20 m range of a
    16-beam, 0.5-degree test sensor: nothing fixes the position along x."""
    s = 0.1
    pts = np.vstack(
        [
            grid_plane((-40, -2, 0), (1, 0, 0), (0, 0, 1), CORRIDOR_LENGTH, 3.0, s),
            grid_plane((-40, 2, 0), (1, 0, 0), (0, 0, 1), CORRIDOR_LENGTH, 3.0, s),
            grid_plane((-40, -2 + s, 0), (1, 0, 0), (0, 1, 0), CORRIDOR_LENGTH, CORRIDOR_WIDTH - 2 * s, s),
        ]
    )
    world = lf3pm.load_map(np.ascontiguousarray(pts))
    sensor = Sensor(
        name="ring16",
        description="16 beams, 720 columns",
        source="test",
        directions=spinning_directions(np.arange(-15, 16, 2), 720),
        min_range=0.3,
        max_range=20.0,
        range_noise_sigma=0.015,
        horizontal_fov=2 * math.pi,
        approximate=False,
    )
    t = np.linspace(0.0, 3.0, 301)
    motion = Motion.from_arrays(t, -1.5 + t, 0.2 * np.sin(t), 0.1 * np.sin(t), map=world)
    return world, sensor, motion


def test_corridor_axis_is_degenerate_and_follows_the_prior(corridor):
    """With a 10 % odometry scale error the estimate runs 10 % ahead along the axis
    (the prior) while registration holds it across the corridor and vertically."""
    world, sensor, motion = corridor
    result = replay(world, motion, sensor, "localization", scale_error=0.1, yaw_noise=0.0)
    assert np.all(result.degenerate_directions == 1)  # the axis, in every scan
    error = result.estimate[:, :3, 3] - result.truth[:, :3, 3]
    travelled = np.r_[0.0, np.cumsum(np.diff(result.truth[:, 0, 3]))]
    np.testing.assert_allclose(error[:, 0], 0.1 * travelled, atol=0.01)
    assert np.max(np.abs(error[:, 1:])) < 0.01
    std = np.array(result.report["largest_std_m"])
    assert np.all(std > result.params["localization"]["degenerate_std"])
    assert result.to_dict()["degenerate_scans"] == result.scans


def test_remapping_keeps_the_prior_only_along_degenerate_directions():
    """A Hessian with no information along x: the remapped correction drops its x
    part and keeps the others; in the scaled space rotations count L metres."""
    H = np.diag([4.0, 4.0, 4.0, 0.0, 9.0, 9.0]) * 1e4
    found = Degeneracy(
        std=np.zeros(6), vectors=np.eye(6), scale=2.0, degenerate=np.array([False, False, False, True, False, False])
    )
    correction = np.array([0.01, -0.02, 0.03, 0.5, -0.1, 0.2])
    np.testing.assert_allclose(found.remap(correction), [0.01, -0.02, 0.03, 0.0, -0.1, 0.2])
    from lf3pm.replays.localization import degeneracy

    d = degeneracy(H, np.array([[2.0, 0, 0], [0, 2.0, 0]]), sigma=0.01, bound=0.01)
    assert d.scale == pytest.approx(2.0) and d.count == 1
    assert d.std[0] == math.inf and np.abs(d.vectors[:, 0]) == pytest.approx([0, 0, 0, 1, 0, 0])
    # Rotations scaled by L = 2 m: information 4e4 / L^2 = 1e4, so 0.01 / sqrt(1e4) = 1e-4 m.
    assert sorted(d.std[1:]) == pytest.approx([0.01 / 300] * 2 + [1e-4] * 3)


def test_planar_helpers_against_direct_formulas():
    twist = planar_log(0.3, -0.1, 0.4)
    phi, t = planar_exp(twist, np.array([1.0, 0.5]))
    assert phi[0] == pytest.approx(0.4) and t[0] == pytest.approx([0.3, -0.1])
    # Half the twist twice is the whole increment.
    half = planar_matrix(t[1, 0], t[1, 1], phi[1])
    np.testing.assert_allclose(half @ half, planar_matrix(0.3, -0.1, 0.4), atol=1e-12)
    # The planar exponential is SE(3)'s for a twist about z.
    ux, uy, th = twist
    np.testing.assert_allclose(se3_exp([ux, uy, 0, 0, 0, th]), planar_matrix(0.3, -0.1, 0.4), atol=1e-12)
    # A point reported at fraction f moves to the end frame by exp((f - 1) xi).
    p = np.array([[1.0, 2.0, 0.5]])
    moved = deskew(p, np.array([0.25]), twist)
    phi, t = planar_exp(twist, np.array([-0.75]))
    T = planar_matrix(t[0, 0], t[0, 1], phi[0])
    np.testing.assert_allclose(moved[0], (T @ np.r_[p[0], 1.0])[:3], atol=1e-12)
    np.testing.assert_allclose(deskew(p, np.array([1.0]), twist), p)


def test_wheel_odometry_increments():
    truth = np.stack([pose_matrix((0, 0, 1, 0.5)), pose_matrix((1.0, 1.0, 1.2, 0.7))])
    step = WheelOdometry(scale_error=0.1, yaw_noise=0.0).increments(truth, 0.1, seed=0)[0]
    c, s = math.cos(0.5), math.sin(0.5)
    assert step[:2] == pytest.approx(1.1 * np.array([c + s, -s + c])) and step[2] == pytest.approx(0.2)
    noisy = [WheelOdometry(0.0, 0.01).increments(truth, 0.25, seed=k)[0, 2] - 0.2 for k in range(400)]
    assert np.std(noisy) == pytest.approx(0.01 * 0.5, rel=0.15)  # density * sqrt(period)
    with pytest.raises(Lf3pmError, match="yaw noise"):
        WheelOdometry(yaw_noise=-1.0)


def test_bad_parameters(boxes):
    world, motion, target = boxes
    with pytest.raises(Lf3pmError, match="unknown parameter"):
        replay(world, motion, "vlp16", "localization", target=target, voxel=1.0)
    with pytest.raises(Lf3pmError, match="unknown method"):
        replay(world, motion, "vlp16", "slam")
    with pytest.raises(Lf3pmError, match="localization.degenerate_std must be greater than 0"):
        replay(world, motion, "vlp16", "localization", target=target, degenerate_std=0.0)
    other = lf3pm.load_map(build_scene("boxes").points[::2])
    with pytest.raises(Lf3pmError, match="another map"):
        replay(other, motion, "vlp16", "localization", target=target)
