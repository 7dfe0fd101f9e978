"""The continuous motion of a ground robot's sensor along a planned trajectory.

``lf3pm plan`` writes t, x, y, yaw, vx, vy, omega at 100 Hz, exact samples of
a piecewise-cubic (MINCO) trajectory. Between two samples x, y and yaw are
quintic Hermite polynomials matching the value, the rate and the second
derivative at both samples (``quintic_hermite``), so the motion is
C2 and an accelerometer is defined everywhere. The second derivatives at the
samples are the second-order finite differences of the given rates
(``numpy.gradient``, exact for the quadratic rates of a cubic piece), so the
motion equals the planner's cubic exactly wherever the three samples around an
interval's ends lie in one piece; near a piece joint it departs by about
jerk jump x (sample spacing)^3 (micrometres at 100 Hz). For diff and car
robots the yaw is the direction of travel (not a cubic): the Hermite
polynomials follow it to the same order.

The sensor's height is ``height`` above the smooth ground under the path
(ground.py): z = g(x, y) + height, its rate and its acceleration by the chain
rule, held as a quintic Hermite polynomial in time through their exact values
every 10 ms (and at the samples), so that the motion is C2 in z too and a scan
needs no ground spline per ray. The robot stays level (roll = pitch = 0) and the sensor frame is the
body frame. Before t0 and after t1 the sensor rests at the end poses.
"""

from __future__ import annotations

import numpy as np

from lf3pm.config import DEFAULT_HEIGHT, DEFAULTS, MAX_TRAJECTORY_SECONDS, GroundConfig
from lf3pm.errors import Lf3pmError, PoseError
from lf3pm.map import Map
from lf3pm.pose import pose_matrices
from lf3pm.replays.ground import SmoothGround, smooth_ground
from lf3pm.trajectory.sampling import check_trajectory

#: Knots per second of the height polynomial (besides the samples): the CSV's rate.
Z_KNOT_RATE = 100.0


def quintic_hermite(t, p, v, a):
    """The piecewise quintic (scipy ``PPoly``, power basis) through values ``p``, rates
    ``v`` and second derivatives ``a`` at the increasing knots ``t``. Closed form per
    interval: scipy's ``BPoly.from_derivatives`` (then ``PPoly.from_bernstein_basis``)
    builds the same polynomials one interval at a time in Python: 0.39 s against 0.46 ms
    for a 60 s plan's 6,001 knots, values equal to 1e-13 m (bench/bench_motion.py;
    tests/test_motion.py checks the two agree)."""
    from scipy.interpolate import PPoly

    t, p, v, a = (np.asarray(c, dtype=np.float64) for c in (t, p, v, a))
    h = np.diff(t)
    # The start fixes the terms up to s^2; what that quadratic misses at the interval's end
    # in value, rate and acceleration (d, dv, da, scaled by h) fixes h^3 c3, h^4 c4 and
    # h^5 c5 through a 3 x 3 system solved by hand. PPoly rows: highest power first.
    d = p[1:] - p[:-1] - v[:-1] * h - 0.5 * a[:-1] * h * h
    dv = (v[1:] - v[:-1] - a[:-1] * h) * h
    da = (a[1:] - a[:-1]) * h * h
    c = np.empty((6, len(h)))
    c[0] = (6.0 * d - 3.0 * dv + 0.5 * da) / h**5
    c[1] = (-15.0 * d + 7.0 * dv - da) / h**4
    c[2] = (10.0 * d - 4.0 * dv + 0.5 * da) / h**3
    c[3], c[4], c[5] = 0.5 * a[:-1], v[:-1], p[:-1]
    return PPoly(c, t)


class Motion:
    """A C2 sensor trajectory (see the module docstring). Times in seconds,
    world frame, z up; every method takes an array of times and clamps it to
    [t0, t1] (rates and accelerations are zero outside).

    Build it with :meth:`from_csv` or :meth:`from_arrays`.
    """

    def __init__(self, t, x, y, yaw, vx, vy, omega, ground: SmoothGround, height: float):
        t, _ = check_trajectory(t, np.column_stack([x, y, np.zeros_like(np.asarray(x, float)), yaw]))
        if t[-1] - t[0] > MAX_TRAJECTORY_SECONDS:  # the height's knots every 10 ms would fill memory
            raise Lf3pmError(
                f"the trajectory lasts {t[-1] - t[0]:g} s, more than {MAX_TRAJECTORY_SECONDS:g} s, "
                "the longest lf3pm replays: replay a part of it"
            )
        channels = [np.asarray(c, dtype=np.float64) for c in (x, y, np.unwrap(np.asarray(yaw, float)))]
        rates = [np.asarray(c, dtype=np.float64) for c in (vx, vy, omega)]
        if any(r.shape != t.shape or not np.all(np.isfinite(r)) for r in rates):
            raise Lf3pmError("the trajectory's rates must be finite, one per sample")
        edge = 2 if len(t) > 2 else 1
        self._polys = [quintic_hermite(t, p, v, np.gradient(v, t, edge_order=edge)) for p, v in zip(channels, rates)]
        self.t0, self.t1 = float(t[0]), float(t[-1])
        self.samples = t
        self.ground = ground
        self.height = float(height)
        self._polys.insert(2, self._height_poly())  # channels x, y, z, yaw
        self._rates = [poly.derivative(1) for poly in self._polys]
        self._accels = [poly.derivative(2) for poly in self._polys]

    def _height_poly(self):
        """z(t) = g(x(t), y(t)) + height as a quintic Hermite polynomial through its
        exact value, rate and acceleration (chain rule) at the samples and every
        10 ms between: C2, within about (10 ms)^6 z^(6) of the composition, and
        as fast to evaluate as x and y (a ground spline per ray is not)."""
        grid = self.t0 + np.arange(int(np.floor((self.t1 - self.t0) * Z_KNOT_RATE)) + 1) / Z_KNOT_RATE
        knots = np.unique(np.concatenate([self.samples, grid]))
        # Knots closer than rounding merge; the tolerance follows the span, not the clock
        # (stamps in Unix time would otherwise merge every knot).
        merge = max(1e-9 * max(1.0, self.t1 - self.t0), 64 * np.finfo(float).eps * max(abs(self.t0), abs(self.t1)))
        knots = knots[np.r_[True, np.diff(knots) > merge]]
        knots[-1] = self.t1
        (x, y), (vx, vy), (ax, ay) = (
            [p(knots) for p in polys[:2]]
            for polys in (self._polys, [q.derivative(1) for q in self._polys], [q.derivative(2) for q in self._polys])
        )
        g, gx, gy, gxx, gxy, gyy = self.ground.derivatives(x, y)
        z_rate = gx * vx + gy * vy
        z_accel = gxx * vx * vx + 2.0 * gxy * vx * vy + gyy * vy * vy + gx * ax + gy * ay
        return quintic_hermite(knots, g + self.height, z_rate, z_accel)

    @classmethod
    def from_arrays(
        cls,
        t,
        x,
        y,
        yaw,
        vx=None,
        vy=None,
        omega=None,
        *,
        map: Map,
        height: float = DEFAULT_HEIGHT,
        ground: GroundConfig = DEFAULTS.ground,
    ) -> Motion:
        """The motion through the samples (t, x, y, yaw) with rates (vx, vy, omega)
        (default: those of a cubic spline through the samples), the sensor
        ``height`` above the smooth ground of ``map`` (ground.py, with the ground
        section ``ground``). Raises Lf3pmError for a malformed trajectory, a bad height
        or a sample outside the map's x-y extent."""
        t, poses = check_trajectory(t, np.column_stack([x, y, np.zeros(np.shape(x)), yaw]))
        if not (np.isfinite(height) and height > 0):
            raise Lf3pmError(f"the sensor height must be > 0 m, got {height}")
        lower, upper = map.bounds
        outside = np.any((poses[:, :2] < lower[:2]) | (poses[:, :2] > upper[:2]), axis=1)
        if outside.any():
            k = int(np.argmax(outside))
            raise PoseError(
                f"the trajectory leaves the map at t = {t[k]:g} s: x, y = "
                f"{poses[k, 0]:.3f}, {poses[k, 1]:.3f} outside x [{lower[0]:.2f}, {upper[0]:.2f}], "
                f"y [{lower[1]:.2f}, {upper[1]:.2f}]"
            )
        if vx is None or vy is None or omega is None:
            from scipy.interpolate import CubicSpline

            yaw_unwrapped = np.unwrap(poses[:, 3])
            vx, vy, omega = (CubicSpline(t, c)(t, 1) for c in (poses[:, 0], poses[:, 1], yaw_unwrapped))
        surface = smooth_ground(map.points, poses[:, :2], ground)
        return cls(t, poses[:, 0], poses[:, 1], poses[:, 3], vx, vy, omega, surface, height)

    @classmethod
    def from_csv(cls, path, map: Map, height: float = DEFAULT_HEIGHT, ground: GroundConfig = DEFAULTS.ground) -> Motion:
        """The motion of the CSV ``lf3pm plan`` writes (t,x,y,yaw,vx,vy,omega), as
        :meth:`from_arrays`. Raises Lf3pmError for a file that cannot be read or
        is malformed."""
        from lf3pm.trajectory.trajectory import read_csv

        s = read_csv(path)
        return cls.from_arrays(
            s["t"], s["x"], s["y"], s["yaw"], s["vx"], s["vy"], s["omega"], map=map, height=height, ground=ground
        )

    def _clamped(self, t) -> tuple[np.ndarray, np.ndarray]:
        t = np.atleast_1d(np.asarray(t, dtype=np.float64))
        return np.clip(t, self.t0, self.t1), (t >= self.t0) & (t <= self.t1)

    def _channels(self, t, order: int) -> np.ndarray:
        """x, y, z, yaw (n, 4) or their ``order``-th derivative."""
        tc, inside = self._clamped(t)
        polys = (self._polys, self._rates, self._accels)[order]
        out = np.empty((len(tc), 4))
        for k, p in enumerate(polys):
            out[:, k] = p(tc)
        if order:
            out[~inside] = 0.0
        return out

    def position(self, t) -> np.ndarray:
        """Sensor origin (n, 3) in the world."""
        return self._channels(t, 0)[:, :3]

    def velocity(self, t) -> np.ndarray:
        """d position / dt (n, 3)."""
        return self._channels(t, 1)[:, :3]

    def acceleration(self, t) -> np.ndarray:
        """d^2 position / dt^2 (n, 3)."""
        return self._channels(t, 2)[:, :3]

    def yaw(self, t) -> np.ndarray:
        """Heading about +z (n,), unwrapped (continuous)."""
        return self._channels(t, 0)[:, 3]

    def yaw_rate(self, t) -> np.ndarray:
        """d yaw / dt (n,)."""
        return self._channels(t, 1)[:, 3]

    def pose(self, t) -> np.ndarray:
        """Sensor-to-world matrices (n, 4, 4), level."""
        return pose_matrices(self._channels(t, 0))


class RestFirst:
    """``motion`` preceded by ``seconds`` at rest at its first pose (what a LiDAR-inertial
    odometry needs to initialise: it takes the first IMU samples for a still sensor's).
    The same methods as :class:`Motion`; t0 is ``seconds`` earlier. ``rest_only``: end
    where the motion starts (the rest alone, as the full stream begins)."""

    def __init__(self, motion, seconds: float, *, rest_only: bool = False):
        if not (np.isfinite(seconds) and seconds >= 0):
            raise Lf3pmError(f"the rest before the motion must be >= 0 s, got {seconds}")
        self.motion, self.rest = motion, float(seconds)
        self.t0, self.t1 = motion.t0 - self.rest, (motion.t0 if rest_only else motion.t1)

    def __getattr__(self, name):
        # position, velocity, ... clamp to the motion's own span: at rest before it.
        return getattr(self.motion, name)
