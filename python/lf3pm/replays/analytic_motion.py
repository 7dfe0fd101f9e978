"""Closed-form C2 motions (the IMU and LIO tests', `lf3pm experiment odometries`'
figure of eight; docs/lio.md): a level sensor whose position
p(t) = C(u(t)) follows a curve C at a path parameter u(t) that stands still,
speeds up smoothly, cruises and slows down to rest again, and whose yaw is a
closed-form function of u. Derivatives by the chain rule, exact.
"""

import numpy as np

from lf3pm.pose import pose_matrices


def _smootherstep(tau):
    """h(tau) = 6 tau^5 - 15 tau^4 + 10 tau^3, its integral and its derivative on
    [0, 1]: a speed ramp with zero acceleration at both ends."""
    h = tau**3 * (10 + tau * (-15 + 6 * tau))
    integral = tau**4 * (2.5 + tau * (-3 + tau))
    dh = 30 * tau**2 * (1 - tau) ** 2
    return h, integral, dh


class Warp:
    """u(t): 0 until ``rest``, a smooth ramp to rate ``speed`` over ``ramp`` s,
    ``cruise`` s at that rate, a ramp back to 0 and ``rest`` s still. Returns
    u, du/dt, d2u/dt2."""

    def __init__(self, rest, ramp, cruise, speed):
        self.rest, self.ramp, self.cruise, self.speed = float(rest), float(ramp), float(cruise), float(speed)
        self.t1 = 2 * (self.rest + self.ramp) + self.cruise
        self.length = self.speed * (self.ramp + self.cruise)

    def __call__(self, t):
        t = np.asarray(t, dtype=np.float64)
        v, T = self.speed, self.ramp
        s = np.clip(t - self.rest, 0.0, self.t1 - 2 * self.rest)  # time since the start of the move
        up = np.clip(s / T, 0.0, 1.0)
        down = np.clip((s - T - self.cruise) / T, 0.0, 1.0)
        h_up, i_up, d_up = _smootherstep(up)
        h_dn, i_dn, d_dn = _smootherstep(1.0 - down)
        cruising = np.clip(s - T, 0.0, self.cruise)
        u = v * T * i_up + v * cruising + v * T * (0.5 - i_dn)
        moving = (t > self.rest) & (t < self.t1 - self.rest)
        rate = np.where(s <= T, v * h_up, np.where(down > 0, v * h_dn, v))
        accel = np.where(s <= T, v * d_up / T, np.where(down > 0, -v * d_dn / T, 0.0))
        return u, np.where(moving, rate, 0.0), np.where(moving, accel, 0.0)


class CurveMotion:
    """A level sensor at ``curve(u(t))`` with yaw ``heading(u(t))``.

    curve(u, nu) -> (n, 3): the position (nu = 0) and its first and second
    derivatives in u; heading(u, nu) -> (n,): the yaw and its derivative in u.
    """

    def __init__(self, warp, curve, heading, t0=0.0):
        self.warp, self.curve, self.heading = warp, curve, heading
        self.t0 = float(t0)
        self.t1 = self.t0 + warp.t1

    def _u(self, t):
        return self.warp(np.atleast_1d(np.asarray(t, dtype=np.float64)) - self.t0)

    def position(self, t):
        u, _, _ = self._u(t)
        return self.curve(u, 0)

    def velocity(self, t):
        u, du, _ = self._u(t)
        return self.curve(u, 1) * du[:, None]

    def acceleration(self, t):
        u, du, ddu = self._u(t)
        return self.curve(u, 2) * (du**2)[:, None] + self.curve(u, 1) * ddu[:, None]

    def yaw(self, t):
        u, _, _ = self._u(t)
        return self.heading(u, 0)

    def yaw_rate(self, t):
        u, du, _ = self._u(t)
        return self.heading(u, 1) * du

    def pose(self, t):
        return pose_matrices(np.column_stack([self.position(t), self.yaw(t)]))

    def samples(self, per_second=1000.0):
        """(t (N,), poses (N, 4) of x y z yaw) every 1/per_second s over the span."""
        t = np.linspace(self.t0, self.t1, int(round((self.t1 - self.t0) * per_second)) + 1)
        return t, np.column_stack([self.position(t), self.yaw(t)])


class Lissajous:
    """C(u) = centre + (ax sin(wx u + px), ay sin(wy u + py), az sin(wz u)): a smooth
    closed curve (a figure of eight for wy = 2 wx)."""

    def __init__(self, centre, amplitude, omega, phase=(0.0, 0.0, 0.0)):
        self.c, self.a = np.asarray(centre, float), np.asarray(amplitude, float)
        self.w, self.p = np.asarray(omega, float), np.asarray(phase, float)

    def __call__(self, u, nu):
        arg = np.outer(u, self.w) + self.p
        if nu == 0:
            return self.c + self.a * np.sin(arg)
        if nu == 1:
            return self.a * self.w * np.cos(arg)
        return -self.a * self.w**2 * np.sin(arg)


class TangentHeading:
    """Yaw = the direction of travel along ``curve`` (a diff-drive robot), plus
    ``swing`` sin(``swing_rate`` u) (an omnidirectional robot turning its sensor
    while it moves) and ``spin`` u. Unwrapped."""

    def __init__(self, curve, swing=0.0, swing_rate=0.0, spin=0.0):
        self.curve, self.swing, self.swing_rate, self.spin = curve, swing, swing_rate, spin

    def __call__(self, u, nu):
        u = np.asarray(u, dtype=np.float64)
        d1, d2 = self.curve(u, 1), self.curve(u, 2)
        extra_rate = self.swing * self.swing_rate * np.cos(self.swing_rate * u) + self.spin
        if nu == 1:
            return (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / (d1[:, 0] ** 2 + d1[:, 1] ** 2) + extra_rate
        # Unwrap along u from 0: the tangent angle at u0 = 0 plus the integrated turn, by unwrapping
        # atan2 over a fine grid that covers the queried u.
        grid = np.linspace(0.0, max(float(np.max(u)), 1e-9), 20001)
        g1 = self.curve(grid, 1)
        angle = np.unwrap(np.arctan2(g1[:, 1], g1[:, 0]))
        base = np.arctan2(d1[:, 1], d1[:, 0])
        near = np.interp(u, grid, angle)
        tangent = base + 2 * np.pi * np.round((near - base) / (2 * np.pi))
        return tangent + self.swing * np.sin(self.swing_rate * u) + self.spin * u
