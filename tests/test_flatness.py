"""The quadrotor's flatness map (cpp/lf3pm/flight/flatness.hpp; issue 43, item 1) on flights
whose attitude is known in closed form (hover, steady acceleration, steady wind, a level
turn), its body rates against finite differences of its own attitude along a smooth
flight, its gradients against finite differences of the map, and the LiDAR's pose on
each mount."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lf3pm.errors import Lf3pmError
from lf3pm.flight import MOUNTS, Quadrotor

G = 9.81


def rz(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def still(n):
    return np.zeros((n, 3))


def test_hovering_the_thrust_carries_the_weight_and_the_yaw_is_the_heading():
    quad = Quadrotor()
    yaw = np.array([0.0, 0.7, -2.5, math.pi])
    rate = np.array([0.0, 0.3, -1.0, 2.0])
    at = quad.attitudes(still(4), still(4), still(4), yaw, rate)
    np.testing.assert_allclose(at.thrust, quad.mass * G, rtol=1e-15)
    for k in range(4):
        np.testing.assert_allclose(at.rotation[k], rz(yaw[k]), atol=1e-15)
    np.testing.assert_allclose(at.omega, np.column_stack([np.zeros(4), np.zeros(4), rate]), atol=1e-15)
    assert np.all(at.cos_tilt == 1.0) and np.all(at.tilt == 0.0)


@pytest.mark.parametrize("yaw", [0.0, 0.8, -2.0])
def test_a_steady_acceleration_tilts_the_thrust_into_it_whatever_the_heading(yaw):
    """a along x without drag: thrust m sqrt(a^2 + g^2), tilt atan(a / g), the body's z axis
    in the x-z plane; flying forward (yaw 0) the nose goes down."""
    quad = Quadrotor(drag_h=0.0, drag_v=0.0)
    a = np.array([[2.0, 0.0, 0.0]])
    at = quad.attitudes(still(1), a, still(1), [yaw], [0.0])
    assert at.thrust[0] == pytest.approx(quad.mass * math.hypot(2.0, G), rel=1e-14)
    assert at.tilt[0] == pytest.approx(math.atan2(2.0, G), rel=1e-12)
    np.testing.assert_allclose(at.rotation[0][:, 2], np.array([2.0, 0.0, G]) / math.hypot(2.0, G), atol=1e-15)
    r = at.rotation[0]
    np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-14)
    assert np.linalg.det(r) == pytest.approx(1.0, abs=1e-14)
    if yaw == 0.0:
        assert r[2, 0] < 0  # the body's x axis points down: nose down


def test_in_a_steady_wind_the_quadrotor_leans_into_the_drag():
    """At 2 m/s along y, no acceleration: the thrust balances weight and drag, the tilt is
    atan(drag_h v / (m g)) towards the motion."""
    quad = Quadrotor(drag_h=0.4)
    v = np.array([[0.0, 2.0, 0.0]])
    at = quad.attitudes(v, still(1), still(1), [0.0], [0.0])
    assert at.tilt[0] == pytest.approx(math.atan2(0.8, quad.mass * G), rel=1e-12)
    assert at.rotation[0][1, 2] > 0  # z_B leans towards +y


def test_a_level_turn_banks_by_the_centripetal_acceleration_and_turns_at_its_rate():
    """A circle of radius 4 m at 2 m/s, heading along the velocity, no drag: bank
    atan(u^2 / (r g)), and the body turns about the world's vertical at u / r: omega_B =
    (u / r) R^T e3, constant in size."""
    quad = Quadrotor(drag_h=0.0, drag_v=0.0)
    r, u = 4.0, 2.0
    w = u / r
    t = np.linspace(0.0, 3.0, 7)
    phase = w * t
    v = u * np.column_stack([-np.sin(phase), np.cos(phase), np.zeros_like(t)])
    a = u * w * np.column_stack([-np.cos(phase), -np.sin(phase), np.zeros_like(t)])
    j = u * w * w * np.column_stack([np.sin(phase), -np.cos(phase), np.zeros_like(t)])
    yaw = phase + math.pi / 2
    at = quad.attitudes(v, a, j, yaw, np.full_like(t, w))
    np.testing.assert_allclose(at.tilt, math.atan2(u * u / r, G), rtol=1e-12)
    expected = w * np.einsum("kji,j->ki", at.rotation, [0.0, 0.0, 1.0])
    np.testing.assert_allclose(at.omega, expected, atol=1e-12)


def _polynomial_flight(t):
    """A smooth flight with drag: position a quintic in each axis, yaw a cubic; returns
    (v, a, j, yaw, yaw_rate) at times t."""
    c = np.array(
        [[0.0, 1.2, 0.5, -0.3, 0.08, -0.006], [0.0, -0.4, 0.9, 0.2, -0.1, 0.01], [1.0, 0.3, -0.6, 0.25, -0.03, 0.0]]
    )
    y = np.array([0.2, 0.9, -0.5, 0.12])

    def derivative(coef, order):
        p = np.polynomial.Polynomial(coef)
        return p.deriv(order)(t) if order else p(t)

    v = np.column_stack([derivative(c[i], 1) for i in range(3)])
    a = np.column_stack([derivative(c[i], 2) for i in range(3)])
    j = np.column_stack([derivative(c[i], 3) for i in range(3)])
    return v, a, j, derivative(y, 0), derivative(y, 1)


def test_the_body_rates_are_the_rate_of_the_attitude_itself():
    """omega = vee(R^T dR/dt), dR/dt by central differences of the map's own attitude
    (h = 1e-4 s: truncation h^2 |R'''| / 6 ~ 1e-8, rounding 1e-16 / h ~ 1e-12)."""
    quad = Quadrotor(drag_h=0.5, drag_v=0.2)
    t = np.linspace(0.1, 3.0, 25)
    h = 1e-4
    at = quad.attitudes(*_polynomial_flight(t))
    ahead = quad.attitudes(*_polynomial_flight(t + h)).rotation
    behind = quad.attitudes(*_polynomial_flight(t - h)).rotation
    skew = np.einsum("kji,kjl->kil", at.rotation, (ahead - behind) / (2 * h))
    vee = np.column_stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]])
    np.testing.assert_allclose(at.omega, vee, atol=1e-6)
    assert np.max(np.linalg.norm(at.omega, axis=1)) > 0.3  # the flight turns


def test_the_gradients_are_those_of_the_map():
    """A random linear cost of (thrust, R, omega, cos tilt): its gradients with respect to
    v, a, j, yaw, yaw rate against central differences (h = 1e-6: error ~ h^2 |f'''| + 1e-16 / h)."""
    quad = Quadrotor(drag_h=0.5, drag_v=0.2)
    rng = np.random.default_rng(7)
    t = np.array([0.3, 1.1, 2.4])
    state = list(_polynomial_flight(t))
    n = len(t)
    weights = {
        "thrust": rng.normal(size=n),
        "rotation": rng.normal(size=(n, 3, 3)),
        "omega": rng.normal(size=(n, 3)),
        "cos_tilt": rng.normal(size=n),
    }

    def cost(s):
        at = quad.attitudes(*s)
        return (
            weights["thrust"] * at.thrust
            + np.einsum("kij,kij->k", weights["rotation"], at.rotation)
            + np.einsum("ki,ki->k", weights["omega"], at.omega)
            + weights["cos_tilt"] * at.cos_tilt
        )

    got = quad.gradients(*state, **weights)
    h = 1e-6
    for index, name in enumerate(("velocity", "acceleration", "jerk", "yaw", "yaw_rate")):
        columns = range(3) if state[index].ndim == 2 else [None]
        for col in columns:
            up = [s.copy() for s in state]
            down = [s.copy() for s in state]
            if col is None:
                up[index] += h
                down[index] -= h
                numeric = (cost(up) - cost(down)) / (2 * h)
                np.testing.assert_allclose(got[name], numeric, rtol=1e-6, atol=1e-7)
            else:
                up[index][:, col] += h
                down[index][:, col] -= h
                numeric = (cost(up) - cost(down)) / (2 * h)
                np.testing.assert_allclose(got[name][:, col], numeric, rtol=1e-6, atol=1e-7)


def test_the_lidar_follows_the_body_on_its_mount():
    """At hover with yaw psi the body is Rz(psi) at the position; the down20 LiDAR looks
    20 degrees below the heading, the side-mounted one spins about the body's x axis."""
    p = np.array([[1.0, 2.0, 3.0]])
    yaw = 0.6
    for name, mount in MOUNTS.items():
        quad = Quadrotor(mount=name)
        at = quad.attitudes(still(1), still(1), still(1), [yaw], [0.0])
        pose = quad.sensor_poses(p, at)[0]
        np.testing.assert_allclose(pose[:3, 3], p[0] + rz(yaw) @ np.asarray(mount.translation), atol=1e-15)
        forward, spin = pose[:3, 0], pose[:3, 2]
        if name == "down20":
            assert math.degrees(math.asin(-forward[2])) == pytest.approx(20.0, abs=1e-12)
            assert math.atan2(forward[1], forward[0]) == pytest.approx(yaw, abs=1e-12)
        if name == "side":
            np.testing.assert_allclose(spin, rz(yaw)[:, 0], atol=1e-15)
        if name == "top":
            np.testing.assert_allclose(pose[:3, :3], rz(yaw), atol=1e-15)


def test_limits_are_reported_and_bad_input_is_one_line():
    quad = Quadrotor()
    v = np.array([[1.5, 0.0, 0.0]])
    at = quad.attitudes(v, still(1), still(1), [0.0], [0.0])
    ratios = quad.limit_ratios(v, at)
    assert ratios["speed"] == pytest.approx(0.5) and ratios["thrust_min"] < 1 and ratios["tilt"] < 1
    free_fall = np.array([[0.0, 0.0, -G]])
    with pytest.raises(Lf3pmError, match="sample 0: no thrust direction") as err:
        Quadrotor(drag_h=0.0, drag_v=0.0).attitudes(still(1), free_fall, still(1), [0.0], [0.0])
    assert "\n" not in str(err.value)
    with pytest.raises(Lf3pmError, match="acceleration must be n x 3"):
        quad.attitudes(still(2), still(1), still(2), [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(Lf3pmError, match="hover thrust"):
        Quadrotor(mass=5.0)
    with pytest.raises(Lf3pmError, match="mount"):
        Quadrotor(mount="belly")
