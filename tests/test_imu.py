"""The simulated IMU: noise-free samples integrated by a plain strapdown scheme
give the trajectory back; the noise has the preset's statistics."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from lf3pm.errors import Lf3pmError
from lf3pm.replays.analytic_motion import CurveMotion, Lissajous, TangentHeading, Warp
from lf3pm.replays.imu import GRAVITY, ImuPreset, get_imu_preset, simulate_imu


def figure_eight(cruise=25.0, swing=0.6):
    """A 30 s figure of eight (4 x 2 m, up to ~2 m/s, height +-0.2 m) with the
    sensor yawing +-0.6 rad about the direction of travel, from rest to rest."""
    curve = Lissajous((0.0, 0.0, 1.0), (4.0, 2.0, 0.2), (0.5, 1.0, 0.7))
    return CurveMotion(Warp(0.5, 2.0, cruise, 1.0), curve, TangentHeading(curve, swing=swing, swing_rate=0.8))


def strapdown(imu, p0, v0, r0):
    """Float64 strapdown integration: orientation by the exponential of the
    trapezoidal gyro increment, velocity by the trapezoid on world acceleration,
    position by the exact integral of a linearly varying acceleration."""
    dt = np.diff(imu.t)
    g = np.array([0.0, 0.0, -GRAVITY])
    rotations = [r0]
    for k in range(len(dt)):
        increment = 0.5 * (imu.gyro[k] + imu.gyro[k + 1]) * dt[k]
        rotations.append(rotations[-1] @ Rotation.from_rotvec(increment).as_matrix())
    accel_world = np.einsum("kij,kj->ki", np.array(rotations), imu.accel) + g
    p, v = [np.asarray(p0, float)], np.asarray(v0, float)
    for k in range(len(dt)):
        a0, a1 = accel_world[k], accel_world[k + 1]
        p.append(p[-1] + v * dt[k] + (2 * a0 + a1) * dt[k] ** 2 / 6)
        v = v + 0.5 * (a0 + a1) * dt[k]
    return np.array(p), np.array(rotations)


def test_noise_free_strapdown_reproduces_the_trajectory_within_1cm_over_30s():
    motion = figure_eight()
    assert motion.t1 - motion.t0 == pytest.approx(30.0)
    imu = simulate_imu(motion, rate=200.0, noise=False)
    assert len(imu) == 6001 and imu.t[-1] == pytest.approx(motion.t1)
    t0 = np.array([motion.t0])
    positions, rotations = strapdown(imu, motion.position(t0)[0], motion.velocity(t0)[0], motion.pose(t0)[0, :3, :3])
    error = np.linalg.norm(positions - motion.position(imu.t), axis=1)
    assert error.max() < 0.01
    heading = np.arctan2(rotations[:, 1, 0], rotations[:, 0, 0])
    assert np.abs(np.angle(np.exp(1j * (heading - motion.yaw(imu.t))))).max() < 1e-4
    # The path is not trivial: it travels tens of metres and turns.
    assert np.sum(np.linalg.norm(np.diff(motion.position(imu.t), axis=0), axis=1)) > 30.0
    assert np.ptp(motion.yaw(imu.t)) > 3.0


def test_level_at_rest_reads_gravity_up_and_no_rotation():
    imu = simulate_imu(figure_eight(), noise=False)
    still = imu.t < 0.5
    np.testing.assert_allclose(imu.accel[still], np.tile([0.0, 0.0, GRAVITY], (still.sum(), 1)), atol=1e-12)
    np.testing.assert_allclose(imu.gyro[still], 0.0, atol=1e-12)
    assert not np.any(imu.accel_bias) and not np.any(imu.gyro_bias)


def test_white_noise_has_the_preset_sigma():
    motion = figure_eight()
    clean = simulate_imu(motion, noise=False)
    noisy = simulate_imu(motion, seed=5)
    sigmas = get_imu_preset("bmi088").sigmas(200.0)
    for name, bias, sigma in (
        ("accel", noisy.accel_bias, sigmas["accel_white"]),
        ("gyro", noisy.gyro_bias, sigmas["gyro_white"]),
    ):
        white = getattr(noisy, name) - getattr(clean, name) - bias
        n = white.size
        assert abs(white.std() - sigma) < 4 * sigma / math.sqrt(2 * n), name
        assert np.all(np.abs(white.mean(axis=0)) < 4 * sigma / math.sqrt(len(white))), name
        lag1 = np.mean(white[1:] * white[:-1]) / white.var()
        assert abs(lag1) < 4 / math.sqrt(n), name


def rest(seconds):
    """A sensor standing still for ``seconds``."""
    curve = Lissajous((0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    return CurveMotion(Warp(seconds / 2, 1.0, 0.0, 0.0), curve, lambda u, nu: np.zeros_like(u))


def test_bias_random_walk_grows_as_the_preset_says():
    preset = get_imu_preset("bmi088")
    motion = rest(4.0)
    span = motion.t1 - motion.t0
    ends = {"accel": [], "gyro": []}
    for seed in range(300):
        imu = simulate_imu(motion, seed=seed)
        ends["accel"].append(imu.accel_bias[-1])
        ends["gyro"].append(imu.gyro_bias[-1])
        assert not np.any(imu.accel_bias[0]) and not np.any(imu.gyro_bias[0])
    steps = np.diff(imu.gyro_bias, axis=0)
    assert abs(steps.std() - preset.sigmas(200.0)["gyro_bias_step"]) < 4 * steps.std() / math.sqrt(2 * steps.size)
    for name, density in (("accel", preset.accel_bias_random_walk), ("gyro", preset.gyro_bias_random_walk)):
        end = np.array(ends[name])  # 300 seeds x 3 axes of b(t1), each N(0, K^2 (t1 - t0))
        expected = density**2 * span
        assert abs(np.mean(end**2) - expected) < 4 * expected * math.sqrt(2 / end.size), name


def test_preset_sigmas_at_200_hz():
    s = get_imu_preset("BMI-088").sigmas(200.0)
    assert s["accel_white"] == pytest.approx(0.02428, rel=1e-3)
    assert s["gyro_white"] == pytest.approx(3.456e-3, rel=1e-3)
    assert s["accel_bias_step"] == pytest.approx(5.664e-6, rel=1e-3)
    assert s["gyro_bias_step"] == pytest.approx(7.557e-7, rel=1e-3)


def test_noise_is_seeded_and_the_same_whatever_the_motion():
    a, b = figure_eight(), figure_eight(swing=0.0)
    first, again, other = simulate_imu(a, seed=1), simulate_imu(a, seed=1), simulate_imu(a, seed=2)
    np.testing.assert_array_equal(first.accel, again.accel)
    np.testing.assert_array_equal(first.gyro, again.gyro)
    assert not np.allclose(first.gyro, other.gyro)
    noise_a = simulate_imu(a, seed=1).gyro - simulate_imu(a, noise=False).gyro
    noise_b = simulate_imu(b, seed=1).gyro - simulate_imu(b, noise=False).gyro
    np.testing.assert_allclose(noise_a, noise_b, atol=1e-15)


def test_a_custom_preset_scales_the_noise():
    zero = ImuPreset("ideal", "no noise", 0.0, 0.0, 0.0, 0.0, "test")
    motion = figure_eight()
    np.testing.assert_array_equal(
        simulate_imu(motion, preset=zero, seed=3).accel, simulate_imu(motion, noise=False).accel
    )


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"rate": 0.0}, "rate"),
        ({"rate": float("nan")}, "rate"),
        ({"rate": "200"}, "rate"),
        ({"seed": -1}, "seed"),
        ({"seed": 1.5}, "seed"),
        ({"preset": "adxl"}, "unknown IMU preset"),
        ({"rate": 1e9}, "more than"),
    ],
)
def test_bad_arguments_raise_one_line(kwargs, message):
    with pytest.raises(Lf3pmError, match=message):
        simulate_imu(figure_eight(), **kwargs)


def test_too_short_a_motion_is_refused():
    with pytest.raises(Lf3pmError, match="shorter than one IMU interval"):
        simulate_imu(rest(0.0), rate=0.1)
