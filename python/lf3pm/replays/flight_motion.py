"""A quadrotor's flight as a replay's motion (docs/odometry_replay.md, "Replays in flight").

The flight is given by its flat outputs (docs/flight.md): the body's position p(t) and its
yaw psi(t), each a callable ``f(t, nu)`` that gives its nu-th derivative at an array of
times: scipy's PPoly, BPoly and CubicSpline are such callables, and a vector-valued one
gives p's three axes at once. A planner's MINCO output, N polynomial pieces of x, y, z and
yaw, goes through :meth:`FlightMotion.from_pieces`. p must be C3 (its jerk sets the body
rates) and psi C1.

At time t the flatness map (:meth:`lf3pm.flight.Quadrotor.attitudes`) of v, a, j, psi and
psi' gives the body's attitude R(t) and body rates omega(t), exactly, at every time asked
for (one per ray of a moving scan); the LiDAR's pose is the body's pose times the
quadrotor's mount. Before t0 and after t1 the body hovers at its end position and yaw
(v = a = j = 0, psi' = 0, so R = Rz(psi)): a flight that starts and ends at hover is
continuous there, as a replay's rest before it needs.

The IMU sits at the body's origin with the body's axes: :meth:`FlightMotion.imu_states`
gives simulate_imu (imu.py) the exact R, p'' and omega, and :attr:`FlightMotion.extrinsic`
the LiDAR's pose in the IMU's frame, which the LIOs are given (lio.run_lio).
"""

from __future__ import annotations

import numpy as np

from lf3pm.errors import Lf3pmError
from lf3pm.flight import FlightAttitudes, Quadrotor

#: Samples per second at which :meth:`FlightMotion.limit_ratios` checks a flight.
LIMIT_RATE = 100.0
#: The columns a flight's CSV needs (lf3pm.planner.flight_plan.FlightTrajectory.csv_bytes
#: writes these and more): whether a trajectory CSV is a flight is said by its ``z``.
FLIGHT_CSV_COLUMNS = ("t", "x", "y", "z", "yaw")


class FlightMotion:
    """A quadrotor's flight along the flat outputs ``position`` (``position(t, nu)`` -> (n, 3),
    nu = 0..3) and ``yaw`` (``yaw(t, nu)`` -> (n,), nu = 0, 1) over [``t0``, ``t1``] s
    (default: a piecewise polynomial's first and last breakpoints), flown by ``quadrotor``
    (its mass, drag and mount; default :class:`lf3pm.flight.Quadrotor`'s). Times in
    seconds, world frame, z up; every method takes an array of times (module docstring).
    Raises Lf3pmError for a span or flat outputs that cannot be evaluated."""

    #: It moves in six degrees of freedom: localization predicts and deskews its scans in
    #: SE(3), not in the plane (localization.py).
    spatial = True

    def __init__(self, position, yaw, *, t0=None, t1=None, quadrotor: Quadrotor | None = None):
        self._position, self._yaw = position, yaw
        self.quadrotor = Quadrotor() if quadrotor is None else quadrotor
        self.t0 = _end(t0, position, 0, "t0")
        self.t1 = _end(t1, position, -1, "t1")
        if not (np.isfinite(self.t0) and np.isfinite(self.t1) and self.t1 > self.t0):
            raise Lf3pmError(f"a flight needs finite times t0 < t1, got {self.t0} and {self.t1}")
        self.attitudes(np.array([self.t0, self.t1]))  # the flat outputs' shapes and thrust, checked once

    @classmethod
    def from_pieces(cls, coefficients, durations, *, start: float = 0.0, quadrotor: Quadrotor | None = None):
        """The flight of N polynomial pieces as MINCO gives them: ``coefficients`` (N, K, 4),
        piece i being sum_k c[i, k] tau^k for tau in [0, durations[i]], columns x, y, z and
        yaw (as :class:`lf3pm.trajectory.Trajectory`'s (N, 4, 3) are x, y and yaw);
        ``durations`` (N,) s; the first piece starting at ``start`` s."""
        from scipy.interpolate import PPoly

        c = np.asarray(coefficients, dtype=np.float64)
        d = np.asarray(durations, dtype=np.float64)
        if c.ndim != 3 or c.shape[2] != 4 or d.shape != (c.shape[0],) or c.shape[0] < 1:
            raise Lf3pmError(
                f"a flight's pieces are coefficients (N, K, 4) of x, y, z, yaw and durations (N,), "
                f"got shapes {c.shape} and {d.shape}"
            )
        if not (np.all(np.isfinite(c)) and np.all(np.isfinite(d)) and np.all(d > 0)):
            raise Lf3pmError("a flight's coefficients must be finite and its durations > 0")
        breaks = float(start) + np.concatenate([[0.0], np.cumsum(d)])
        power = np.transpose(c[:, ::-1, :], (1, 0, 2))  # PPoly's rows: highest power first
        return cls(PPoly(power[..., :3], breaks), PPoly(power[..., 3], breaks), quadrotor=quadrotor)

    @classmethod
    def from_samples(cls, t, position, yaw, *, quadrotor: Quadrotor | None = None):
        """The flight through samples at times ``t`` (n,) s of ``position`` (n, 3) and ``yaw``
        (n,), as `lf3pm plan --robot quadrotor` writes them at 100 Hz: quintic splines
        through every sample (the yaw unwrapped), at rest at both ends (velocity and
        acceleration zero there, as a planned flight is), so that the attitude, its rates
        and the IMU follow from the flatness map as for the planned pieces. A planned flight
        sampled at 100 Hz comes back within 1e-6 m and 1e-3 rad of attitude of its pieces
        (tests/test_flight_replay.py)."""
        from scipy.interpolate import PPoly, make_interp_spline

        t = np.asarray(t, dtype=np.float64)
        p = np.asarray(position, dtype=np.float64)
        psi = np.asarray(yaw, dtype=np.float64)
        if t.ndim != 1 or len(t) < 6 or p.shape != (len(t), 3) or psi.shape != (len(t),):
            raise Lf3pmError(
                f"a flight's samples are times (n,), positions (n, 3) and yaws (n,) with n >= 6, "
                f"got shapes {t.shape}, {p.shape} and {psi.shape}"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p)) and np.all(np.isfinite(psi))):
            raise Lf3pmError("a flight's samples must be finite")
        if np.any(np.diff(t) <= 0):
            raise Lf3pmError("a flight's sample times must increase strictly")

        def spline(values):  # one column: PPoly.from_spline takes scalar splines only
            ends = [(1, 0.0), (2, 0.0)]
            return PPoly.from_spline(make_interp_spline(t, values, k=5, bc_type=(ends, ends)))

        columns = [spline(p[:, k]) for k in range(3)]
        position = PPoly(np.stack([c.c for c in columns], axis=-1), columns[0].x)
        return cls(position, spline(np.unwrap(psi)), t0=t[0], t1=t[-1], quadrotor=quadrotor)

    @classmethod
    def from_csv(cls, path, *, quadrotor: Quadrotor | None = None):
        """The flight in a CSV as `lf3pm plan --robot quadrotor` writes it (the columns
        :data:`FLIGHT_CSV_COLUMNS` at least; :meth:`from_samples`); Lf3pmError in one line
        naming the file for a bad one."""
        from lf3pm.trajectory.trajectory import read_csv

        s = read_csv(path, FLIGHT_CSV_COLUMNS)
        try:
            return cls.from_samples(s["t"], np.column_stack([s["x"], s["y"], s["z"]]), s["yaw"], quadrotor=quadrotor)
        except Lf3pmError as err:
            raise Lf3pmError(f"{path}: {err}") from None

    def _outputs(self, t) -> tuple:
        """p, v, a, j (n, 3) and psi, psi' (n,) at ``t``, clamped to [t0, t1] (hovering outside)."""
        t = np.atleast_1d(np.asarray(t, dtype=np.float64))
        clamped = np.clip(t, self.t0, self.t1)
        inside = ((t >= self.t0) & (t <= self.t1)).astype(np.float64)
        p, v, a, j = (_values(self._position, clamped, nu, (len(t), 3), "position") for nu in range(4))
        psi, rate = (_values(self._yaw, clamped, nu, (len(t),), "yaw") for nu in range(2))
        moving = inside[:, None]
        return p, v * moving, a * moving, j * moving, psi, rate * inside

    def position(self, t) -> np.ndarray:
        """The body's origin (n, 3): the flat output p."""
        return self._outputs(t)[0]

    def velocity(self, t) -> np.ndarray:
        """dp/dt (n, 3)."""
        return self._outputs(t)[1]

    def acceleration(self, t) -> np.ndarray:
        """d^2p/dt^2 (n, 3)."""
        return self._outputs(t)[2]

    def yaw(self, t) -> np.ndarray:
        """The flat output psi (n,): the heading at level flight."""
        return self._outputs(t)[4]

    def yaw_rate(self, t) -> np.ndarray:
        """d psi / dt (n,)."""
        return self._outputs(t)[5]

    def attitudes(self, t) -> FlightAttitudes:
        """The flatness map at ``t``: thrust, body-to-world rotation, body rates, cos tilt."""
        _, v, a, j, psi, rate = self._outputs(t)
        return self.quadrotor.attitudes(v, a, j, psi, rate)

    def body_pose(self, t) -> np.ndarray:
        """Body-to-world matrices (n, 4, 4)."""
        p, v, a, j, psi, rate = self._outputs(t)
        return self.quadrotor.body_poses(p, self.quadrotor.attitudes(v, a, j, psi, rate))

    def pose(self, t) -> np.ndarray:
        """The LiDAR's sensor-to-world matrices (n, 4, 4): the body's pose times the mount."""
        return self.body_pose(t) @ self.extrinsic

    @property
    def extrinsic(self) -> np.ndarray:
        """The LiDAR's pose in the IMU's (= body's) frame (4, 4): the quadrotor's mount."""
        return self.quadrotor.sensor_mount.matrix()

    def imu_states(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """What an IMU at the body's origin, its axes the body's, senses at ``t``: the
        body-to-world rotation (n, 3, 3), the origin's acceleration (n, 3, world frame) and
        the body rates omega (n, 3, body frame), all from the flatness map."""
        _, v, a, j, psi, rate = self._outputs(t)
        attitudes = self.quadrotor.attitudes(v, a, j, psi, rate)
        return attitudes.rotation, a, attitudes.omega

    def limit_ratios(self, rate: float = LIMIT_RATE) -> dict:
        """How close the flight comes to the quadrotor's limits, sampled at ``rate`` Hz
        (the span's ends included): :meth:`lf3pm.flight.Quadrotor.limit_ratios`."""
        t = np.append(np.arange(self.t0, self.t1, 1.0 / rate), self.t1)
        _, v, a, j, psi, psi_rate = self._outputs(t)
        return self.quadrotor.limit_ratios(v, self.quadrotor.attitudes(v, a, j, psi, psi_rate))


def _end(given, position, k: int, name: str) -> float:
    """``given``, else the first (k = 0) or last (k = -1) breakpoint of a piecewise polynomial."""
    if given is not None:
        return float(given)
    breaks = getattr(position, "x", None)
    if breaks is None:
        raise Lf3pmError(f"give the flight's {name}: its position is not a piecewise polynomial with breakpoints x")
    return float(np.asarray(breaks, dtype=np.float64)[k])


def _values(f, t: np.ndarray, nu: int, shape: tuple, name: str) -> np.ndarray:
    """``f(t, nu)`` as floats of ``shape``, checked."""
    try:
        out = np.asarray(f(t, nu), dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise Lf3pmError(f"the flight's {name}(t, {nu}) cannot be evaluated: {err}") from None
    if out.shape != shape:
        raise Lf3pmError(f"the flight's {name}(t, {nu}) must have shape {shape} for {len(t)} times, got {out.shape}")
    if not np.all(np.isfinite(out)):
        raise Lf3pmError(f"the flight's {name}(t, {nu}) is not finite")
    return out
