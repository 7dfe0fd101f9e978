"""The flat map of a nonholonomic robot (cpp/lf3pm/trajectory/travel_heading.hpp), bound as
_core.travel_heading and used by both the trajectory cost and Trajectory: yaw is the
direction of travel, omega its rate, with their limits at rest."""

import numpy as np

from lf3pm import _core


def piece(c1, c2, c3, c0=(0.0, 0.0)):
    """One cubic piece (1, 4, 3) with x, y coefficients and no yaw column."""
    c = np.zeros((1, 4, 3))
    c[0, :, :2] = [c0, c1, c2, c3]
    return c


def heading(c, tau, duration):
    tau = np.atleast_1d(np.asarray(tau, dtype=np.float64))
    return _core.travel_heading(np.repeat(c, len(tau), axis=0), tau, np.full(len(tau), duration))


def velocity(c, t):
    return c[0, 1, :2] + 2 * c[0, 2, :2] * t + 3 * c[0, 3, :2] * t**2


def test_moving_yaw_is_the_direction_of_travel_and_omega_its_derivative():
    rng = np.random.default_rng(0)
    for _ in range(20):
        c = piece(*rng.normal(size=(3, 2)))
        t = rng.uniform(0.2, 0.8, size=8)
        yaw, omega = heading(c, t, 1.0)
        v = np.array([velocity(c, x) for x in t])
        np.testing.assert_allclose(np.cos(yaw), v[:, 0] / np.linalg.norm(v, axis=1), atol=1e-12)
        np.testing.assert_allclose(np.sin(yaw), v[:, 1] / np.linalg.norm(v, axis=1), atol=1e-12)
        h = 1e-6
        ahead, behind = heading(c, t + h, 1.0)[0], heading(c, t - h, 1.0)[0]
        difference = np.angle(np.exp(1j * (ahead - behind))) / (2 * h)
        # Central difference: error O(h^2 yaw''') plus rounding eps/h ~ 1e-10 relative.
        np.testing.assert_allclose(omega, difference, rtol=1e-5, atol=1e-6)


def test_at_rest_the_limits_of_a_start_and_a_stop():
    # Starting from rest: v = a t + j t^2 / 2, so yaw -> atan2(a), omega -> (a x j) / (2 |a|^2).
    c = piece((0.0, 0.0), (0.5, 0.1), (-0.1, 0.3))
    yaw0, omega0 = heading(c, 0.0, 2.0)
    yaw_t, _ = heading(c, 1e-7, 2.0)
    np.testing.assert_allclose(yaw0, yaw_t, atol=1e-6)
    a, j = 2 * c[0, 2, :2], 6 * c[0, 3, :2]
    np.testing.assert_allclose(omega0, (a[0] * j[1] - a[1] * j[0]) / (2 * a @ a), rtol=1e-15)
    t, h = 1e-3, 1e-6  # the rate just after the start tends to the limit, O(t)
    ahead, behind = heading(c, t + h, 2.0)[0], heading(c, t - h, 2.0)[0]
    np.testing.assert_allclose(omega0, (ahead - behind) / (2 * h), rtol=1e-2)
    # Coming to rest at T: reversed in time, the robot moves along -a.
    T = 2.0
    end = piece(-(2 * c[0, 2, :2] * T + 3 * c[0, 3, :2] * T**2), c[0, 2, :2], c[0, 3, :2])
    assert np.allclose(velocity(end, T), 0.0, atol=1e-15)
    yaw_T, _ = heading(end, T, T)
    yaw_before, _ = heading(end, T - 1e-7, T)
    np.testing.assert_allclose(np.angle(np.exp(1j * (yaw_T - yaw_before))), 0.0, atol=1e-6)


def test_rest_is_judged_relative_to_the_piece_not_in_absolute_units():
    # The same motion at 1e-10 m/s: the heading is the same at every instant,
    # the ends at rest included (an absolute threshold on |v|^2 would call it all rest).
    c = piece((0.0, 0.0), (0.5, 0.1), (-0.1, 0.3))
    tau = np.linspace(0.0, 2.0, 41)
    yaw, omega = heading(c, tau, 2.0)
    small_yaw, small_omega = heading(1e-10 * c, tau, 2.0)
    np.testing.assert_allclose(small_yaw, yaw, atol=1e-12)
    np.testing.assert_allclose(small_omega, omega, rtol=1e-9)
