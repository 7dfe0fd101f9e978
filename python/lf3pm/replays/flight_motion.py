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
#: How far (rad) a flight CSV's attitudes may lie from the flatness map's (FlightMotion.from_csv).
ATTITUDE_TOLERANCE = 1e-3


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
    def from_samples(
        cls, t, position, yaw, *, velocity=None, yaw_rate=None, acceleration=None, quadrotor: Quadrotor | None = None
    ):
        """The flight through samples at times ``t`` (n,) s of ``position`` (n, 3) and ``yaw``
        (n,), as `lf3pm plan --robot quadrotor` writes them at 100 Hz, so that the attitude,
        its rates and the IMU follow from the flatness map as for the planned pieces. With
        ``velocity`` and ``acceleration`` (n, 3): between two samples the quintic with their
        position, velocity and acceleration (a planned flight's piece itself, wherever two
        samples share a piece); the yaw the cubic with its ``yaw_rate`` (n,) at both. Without
        them: quintic splines through every sample, at rest at both ends (as a planned flight
        is), whose third derivative is less exact near the ends. A sample closer than a tenth
        of the median step to the one before it is left out (the end kept): such a gap makes
        a spline ring. A planned flight's CSV comes back within 1e-6 m, 1e-3 rad of attitude
        and 1e-3 rad/s of body rate (tests/test_flight_replay.py, test_flight_attitude.py)."""
        from scipy.interpolate import BPoly, PPoly, make_interp_spline

        t = np.asarray(t, dtype=np.float64)
        n = len(t) if t.ndim == 1 else -1
        p = np.asarray(position, dtype=np.float64)
        psi = np.asarray(yaw, dtype=np.float64)
        given = {"velocity": velocity, "acceleration": acceleration, "yaw_rate": yaw_rate}
        derivatives = {k: np.asarray(v, dtype=np.float64) for k, v in given.items() if v is not None}
        shapes = {"velocity": (n, 3), "acceleration": (n, 3), "yaw_rate": (n,)}
        if n < 6 or p.shape != (n, 3) or psi.shape != (n,) or any(v.shape != shapes[k] for k, v in derivatives.items()):
            raise Lf3pmError(
                f"a flight's samples are times (n,), positions (n, 3) and yaws (n,) with n >= 6 (velocities "
                f"and accelerations (n, 3), yaw rates (n,) if given), got shapes {t.shape}, {p.shape} and {psi.shape}"
            )
        if not all(np.all(np.isfinite(a)) for a in (t, p, psi, *derivatives.values())):
            raise Lf3pmError("a flight's samples must be finite")
        step = np.diff(t)
        if np.any(step <= 0):
            raise Lf3pmError("a flight's sample times must increase strictly")
        keep = np.append(step >= 0.1 * np.median(step), True)  # sample i kept unless t[i+1] is too near
        keep[0] = True
        t, p, psi = t[keep], p[keep], np.unwrap(psi[keep])
        derivatives = {k: v[keep] for k, v in derivatives.items()}
        if len(t) < 6:
            raise Lf3pmError("a flight needs at least 6 samples a tenth of the median step apart")
        if len(derivatives) == 3:
            v, a, w = derivatives["velocity"], derivatives["acceleration"], derivatives["yaw_rate"]
            columns = [BPoly.from_derivatives(t, np.column_stack([p[:, k], v[:, k], a[:, k]])) for k in range(3)]
            position_ = PPoly.from_bernstein_basis(BPoly(np.stack([c.c for c in columns], axis=-1), columns[0].x))
            heading = PPoly.from_bernstein_basis(BPoly.from_derivatives(t, np.column_stack([psi, w])))
            return cls(position_, heading, t0=t[0], t1=t[-1], quadrotor=quadrotor)

        def spline(values):  # one column: PPoly.from_spline takes scalar splines only
            rest = [(1, 0.0), (2, 0.0)]
            return PPoly.from_spline(make_interp_spline(t, values, k=5, bc_type=(rest, rest)))

        columns = [spline(p[:, k]) for k in range(3)]
        flat = PPoly(np.stack([c.c for c in columns], axis=-1), columns[0].x)
        return cls(flat, spline(psi), t0=t[0], t1=t[-1], quadrotor=quadrotor)

    @classmethod
    def from_csv(cls, path, *, quadrotor: Quadrotor | None = None):
        """The flight in a CSV as `lf3pm plan --robot quadrotor` writes it (the columns
        :data:`FLIGHT_CSV_COLUMNS` at least; :meth:`from_samples`, with its velocities,
        accelerations and yaw rates where the CSV has them all). Where it holds the attitude
        (qw, qx, qy, qz), the flatness map of ``quadrotor`` must give it back within
        :data:`ATTITUDE_TOLERANCE` rad: another mass or drag than the plan's is refused. Lf3pmError in one line naming
        the file for a bad one."""
        from lf3pm.trajectory.trajectory import read_csv

        header = set(csv_header(path))
        derived = ("vx", "vy", "vz", "yaw_rate", "ax", "ay", "az")
        derived = derived if set(derived) <= header else ()
        attitude = ("qw", "qx", "qy", "qz") if {"qw", "qx", "qy", "qz"} <= header else ()
        s = read_csv(path, (*FLIGHT_CSV_COLUMNS, *derived, *attitude))  # one read of the file
        extra = {}
        if derived:
            extra = {
                "velocity": np.column_stack([s["vx"], s["vy"], s["vz"]]),
                "acceleration": np.column_stack([s["ax"], s["ay"], s["az"]]),
                "yaw_rate": s["yaw_rate"],
            }
        try:
            flight = cls.from_samples(
                s["t"], np.column_stack([s["x"], s["y"], s["z"]]), s["yaw"], quadrotor=quadrotor, **extra
            )
        except Lf3pmError as err:
            raise Lf3pmError(f"{path}: {err}") from None
        if attitude:
            cosine = _quaternion_cosines(flight.attitudes(s["t"]).rotation, s)
            worst = float(np.degrees(2 * np.arccos(np.clip(cosine.min(), 0.0, 1.0))))
            if worst > np.degrees(ATTITUDE_TOLERANCE):
                raise Lf3pmError(
                    f"{path}: its attitudes differ from this quadrotor's flatness map by up to {worst:.2g} deg: "
                    "fly it with the plan's quadrotor section (mass, drag_h, drag_v)"
                )
        return flight

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


def csv_header(path) -> list[str]:
    """The column names of a CSV's first line."""
    with open(path, "rb") as fp:
        return [name.strip() for name in fp.readline(1 << 16).decode("utf-8", "replace").split(",")]


def _quaternion_cosines(rotations: np.ndarray, q: dict) -> np.ndarray:
    """|<q(R), q>| per sample: the cosine of half the angle between each rotation and the
    CSV's unit quaternion (qw, qx, qy, qz), up to the quaternion's sign."""
    from scipy.spatial.transform import Rotation

    xyzw = Rotation.from_matrix(rotations).as_quat()
    given = np.column_stack([q["qx"], q["qy"], q["qz"], q["qw"]])
    given /= np.linalg.norm(given, axis=1, keepdims=True)
    return np.abs(np.sum(xyzw * given, axis=1))
