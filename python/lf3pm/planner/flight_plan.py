"""A quadrotor's perception-aware flight on an r3yaw SOLM (issue 43, item 3): the front end
(lf3pm.planner.flight_path), then the back end, a quintic MINCO in (x, y, z, yaw) minimised
by L-BFGS (cpp/lf3pm/flight/flight_optimizer.hpp) on

    integral of (rho_T + w_q q(x, y, z, yaw) + feasibility penalties) dt + jerk energy,

w_q = weight * rho_T as for ground robots (a median cell then costs as the front end
charges it), the penalties on speed, body rate, tilt and thrust through the flatness map,
and on clearance through a 3-D ESDF of the map (:func:`flight_esdf`). The limits are
penalties, so the optimum may pass them slightly: time is then stretched uniformly (every
coefficient c_k / s^k over durations s T, the same path flown slower) until every limit
holds on samples at ``check_rate`` Hz, as for ground robots."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from lf3pm import _core
from lf3pm.config import DEFAULTS, GuidanceConfig, QuadrotorConfig
from lf3pm.errors import Lf3pmError
from lf3pm.flight import Quadrotor
from lf3pm.planner.cost_map import CostLayer, cost_from_values
from lf3pm.planner.flight_attitude import ATTITUDE_ROUNDS, AttitudeGuidance, sample_rate
from lf3pm.planner.flight_path import FlightPath, clear_moves, plan_flight_path
from lf3pm.trajectory.trajectory import CSV_RATE

#: Samples a second on which the limits are checked (as for ground robots).
CHECK_RATE = 1000.0
#: Edge of the flight ESDF's voxels (m).
ESDF_RES = 0.2
#: Relative precision of the time scaling's factor (a 50 m flight: 18 ms longer at most).
SCALE_TOLERANCE = 1e-3
#: Samples a second of the time scaling's bisection (the result is then checked at CHECK_RATE).
SEARCH_RATE = 100.0
#: Most rounds of the guidance at the planned attitude a plan may ask for.
MAX_ATTITUDE_ROUNDS = 10
#: Weight of the yaw's jerk against the position's in the energy.
YAW_ENERGY = 0.1


@dataclass(frozen=True)
class FlightTrajectory:
    """A quintic trajectory of (x, y, z, yaw): ``coefficients`` (N, 6, 4), piece k of
    dimension d being sum_j c[k, j, d] t^j on [0, durations[k]]."""

    coefficients: np.ndarray
    durations: np.ndarray

    @property
    def duration(self) -> float:
        return float(self.durations.sum())

    def sample(self, rate: float = CSV_RATE) -> dict:
        """Samples every 1 / rate s and at the end (none within half a step before it): t,
        position (n, 3), velocity, acceleration, jerk (n, 3), yaw and yaw_rate (n)."""
        ends = np.concatenate([[0.0], np.cumsum(self.durations)])
        grid = np.arange(0.0, ends[-1], 1.0 / rate)
        # No sample within half a step of the end, which is sampled itself: a gap of almost
        # nothing there would make a spline through the samples ring (FlightMotion.from_samples).
        t = np.append(grid[grid < ends[-1] - 0.5 / rate], ends[-1])
        piece = np.clip(np.searchsorted(ends, t, side="right") - 1, 0, len(self.durations) - 1)
        tau = t - ends[piece]
        c = self.coefficients[piece]  # (n, 6, 4)
        out = {"t": t}
        for order, name in enumerate(("position", "velocity", "acceleration", "jerk")):
            # Horner's rule: products and sums in a fixed order, the same on every CPU
            # (einsum's and power's vector kernels differ with it).
            value = math.perm(5, order) * c[:, 5]
            for k in range(4, order - 1, -1):
                value = value * tau[:, None] + math.perm(k, order) * c[:, k]
            out[name] = value[:, :3]
            if order == 0:
                out["yaw"] = value[:, 3]
            if order == 1:
                out["yaw_rate"] = value[:, 3]
        return out

    def time_scaled(self, factor: float) -> FlightTrajectory:
        """The same path flown ``factor`` times slower: p(t / factor)."""
        powers = factor ** -np.arange(6)
        return FlightTrajectory(self.coefficients * powers[None, :, None], self.durations * factor)

    def csv_bytes(self, quad: Quadrotor, rate: float = CSV_RATE) -> bytes:
        """Samples at ``rate`` Hz as CSV: t, x, y, z, yaw, vx, vy, vz, yaw_rate, the body's
        attitude quaternion qw, qx, qy, qz (body to world), thrust (N) and the acceleration
        ax, ay, az, to 17 digits."""
        import io

        from scipy.spatial.transform import Rotation

        s = self.sample(rate)
        att = quad.attitudes(s["velocity"], s["acceleration"], s["jerk"], s["yaw"], s["yaw_rate"])
        xyzw = Rotation.from_matrix(att.rotation).as_quat()
        columns = [s["t"], *s["position"].T, s["yaw"], *s["velocity"].T, s["yaw_rate"], xyzw[:, 3], *xyzw[:, :3].T]
        buf = io.StringIO()
        header = "t,x,y,z,yaw,vx,vy,vz,yaw_rate,qw,qx,qy,qz,thrust,ax,ay,az"
        # Every digit of a double, and the acceleration: a replay rebuilds the flight from
        # position, velocity and acceleration at each sample (FlightMotion.from_samples) and
        # differentiates it once more for the body rates; nine digits put them 1 rad/s off.
        table = np.column_stack([*columns, att.thrust, *s["acceleration"].T])
        np.savetxt(buf, table, delimiter=",", fmt="%.17g", header=header, comments="")
        return buf.getvalue().encode()


@dataclass(frozen=True)
class FlightPlan:
    """A planned flight: the front end's ``path``, the ``trajectory``, the ``time_scale``
    applied after optimisation, the largest ratio to each limit on the 1 kHz samples
    (``limits``; clearance: r_safe over the least distance to the map), the objective's
    sampled ``terms``, the optimiser's iterations, status and reason, the ``objective`` at
    its optimum (before time scaling), the ``planner``
    (:data:`PLANNERS`), the seconds each stage took and, per round of the guidance at the
    planned attitude, what the attitude changed (``attitude``:
    lf3pm.planner.flight_attitude.AttitudeGuidance.correct's summaries)."""

    path: FlightPath
    trajectory: FlightTrajectory
    time_scale: float
    limits: dict
    terms: dict
    iterations: int
    status: str
    reason: str
    objective: float = math.nan
    planner: str = "joint"
    seconds: dict = field(default_factory=dict)
    attitude: list = field(default_factory=list)

    def summary(self) -> dict:
        """JSON-ready figures of the plan."""
        samples = self.trajectory.sample(CSV_RATE)
        return {
            "duration_s": self.trajectory.duration,
            "trajectory_length_m": float(np.linalg.norm(np.diff(samples["position"], axis=0), axis=1).sum()),
            "path_length_m": self.path.length,
            "time_scale": self.time_scale,
            "limits": self.limits,
            "terms": self.terms,
            "iterations": self.iterations,
            "status": self.status,
            "reason": self.reason,
            "objective": self.objective,
            "planner": self.planner,
            "attitude_rounds": self.attitude,
            **{f"{name}_s": value for name, value in self.seconds.items()},
        }


def flight_esdf(points: np.ndarray, lower, upper, res: float = ESDF_RES) -> _core.VolumeField:
    """The distance (m) from each voxel centre of edge ``res`` over the box [lower, upper] to
    the nearest map point's voxel, less half a voxel diagonal (a point anywhere in its voxel),
    as a VolumeField."""
    from scipy.ndimage import distance_transform_edt

    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    shape = np.maximum(np.ceil((upper - lower) / res).astype(int), 1)
    inside = np.all((points >= lower) & (points < lower + shape * res), axis=1)
    index = np.floor((points[inside] - lower) / res).astype(int)
    free = np.ones(shape[::-1], dtype=bool)  # (z, y, x)
    free[index[:, 2], index[:, 1], index[:, 0]] = False
    distance = distance_transform_edt(free, sampling=res) - 0.5 * math.sqrt(3) * res
    return _core.VolumeField(
        np.ascontiguousarray(distance.ravel()),
        int(shape[0]),
        int(shape[1]),
        int(shape[2]),
        1,
        float(lower[0]),
        float(lower[1]),
        float(lower[2] + 0.5 * res),
        float(res),
        float(res),
    )


def guidance_layer(solm, guidance: GuidanceConfig) -> CostLayer:
    """The r3yaw SOLM's cost layer as the back end reads it: the guidance channel over its
    median, to its power, capped (lf3pm.planner.cost_map), unevaluated cells at the cap."""
    metric = guidance.metric
    values = np.zeros(solm.grid_spec.shape) if metric == "none" else solm.channel(metric)
    degenerate = np.asarray(solm.channel("degenerate")).astype(bool)
    return cost_from_values(values, metric, degenerate=degenerate, power=guidance.power)


def guidance_field(solm, guidance: GuidanceConfig, cost: np.ndarray | None = None) -> _core.VolumeField:
    """The guidance layer (:func:`guidance_layer`, or ``cost`` of its shape in its place) as
    the VolumeField the back end interpolates."""
    g = solm.grid_spec
    cost = guidance_layer(solm, guidance).filled if cost is None else cost
    levels = np.asarray(g.z_levels, dtype=np.float64)
    dz = float(np.diff(levels).mean()) if len(levels) > 1 else g.res
    return _core.VolumeField(
        np.ascontiguousarray(cost.ravel(), dtype=np.float64),
        g.nx,
        g.ny,
        len(levels),
        g.yaw_bins,
        g.x0,
        g.y0,
        float(levels[0]),
        g.res,
        dz,
    )


def initial_guess(path: FlightPath, piece_length: float, vmax: float):
    """Waypoints (4 x (N - 1)) every ``piece_length`` metres along the front-end path (its
    yaw unwrapped) and durations at half the speed limit."""
    points = np.column_stack([path.positions, path.yaws])
    along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path.positions, axis=0), axis=1))])
    pieces = max(1, round(along[-1] / piece_length))
    at = np.linspace(0.0, along[-1], pieces + 1)
    knots = np.column_stack([np.interp(at, along, points[:, d]) for d in range(4)])
    lengths = np.maximum(np.linalg.norm(np.diff(knots[:, :3], axis=0), axis=1), 0.1)
    return knots[1:-1].T.copy(), np.maximum(lengths / (0.5 * vmax), 0.5)


def within_limits(trajectory: FlightTrajectory, quad: Quadrotor, esdf, r_safe: float, rate: float = CHECK_RATE):
    """The trajectory stretched uniformly in time until speed, body rate, tilt and thrust
    hold on samples at ``rate`` Hz: (trajectory, factor, the largest ratio to each limit,
    clearance r_safe / least distance). Flown s times slower, the speed falls as 1 / s and
    the body rate, the tilt and the thrust's departure from hover about as fast or faster,
    so s = the largest ratio nearly always holds (else it doubles); bisection on samples at
    :data:`SEARCH_RATE` Hz then finds the least factor to :data:`SCALE_TOLERANCE`, and the
    factor grows by that tolerance until the samples at ``rate`` Hz hold too."""

    def ratios(traj, hz):
        s = traj.sample(hz)
        att = quad.attitudes(s["velocity"], s["acceleration"], s["jerk"], s["yaw"], s["yaw_rate"])
        return quad.limit_ratios(s["velocity"], att), s

    def holds(factor, hz):
        return max(ratios(trajectory.time_scaled(factor), hz)[0].values()) <= 1.0

    factor = 1.0
    current, s = ratios(trajectory, rate)
    if max(current.values()) > 1.0:
        # A hair above the largest ratio: at exactly that factor the speed lands on its limit
        # give or take rounding.
        low, high = 1.0, max(current.values()) * (1.0 + SCALE_TOLERANCE)
        while not holds(high, SEARCH_RATE):
            low, high = high, 2.0 * high
            if high > 1e3:
                raise Lf3pmError("no time scaling brings the flight within its limits (check thrust_min/max)")
        while high - low > SCALE_TOLERANCE * low:
            mid = 0.5 * (low + high)
            low, high = (low, mid) if holds(mid, SEARCH_RATE) else (mid, high)
        factor = high
        while True:
            current, s = ratios(trajectory.time_scaled(factor), rate)
            if max(current.values()) <= 1.0:
                break
            factor *= 1.0 + SCALE_TOLERANCE
        trajectory = trajectory.time_scaled(factor)
    distance, _ = esdf.sample(np.ascontiguousarray(s["position"]), np.zeros(len(s["t"])))
    current["clearance"] = float(r_safe / max(distance.min(), 1e-9))
    return trajectory, factor, current


#: The flight planners (docs/flight.md, "Baselines"): joint position and yaw on the SOLM
#: (lf3pm's), GCOPTER-style minimum time with the yaw along the velocity (no perception),
#: and that flight with only its yaw optimised on the SOLM (the EAROL / AWARE idea).
PLANNERS = ("joint", "velocity_yaw", "yaw_only")
#: Weight of the yaw-along-velocity term of the baselines (per (m/s)^2 of lateral speed in
#: the heading's frame: at 3 m/s a crosswise heading costs 90 s of flight a second).
W_HEADING = 10.0


class FlightPlanner:
    """Flights on one r3yaw SOLM over its map: the ESDF and the guidance field are built
    once, so that replanning from a new start costs only the search and the optimisation.
    ``world_points``: the map (N x 3), or the Map itself (lf3pm.load_map; its index serves
    the casts of the guidance at the planned attitude, else the points are indexed when a
    plan first needs them); the guidance and quadrotor sections as in :func:`plan_flight`;
    ``threads``: the workers of those casts (0: every core)."""

    def __init__(
        self,
        solm,
        world_points,
        *,
        guidance: GuidanceConfig = DEFAULTS.guidance,
        quadrotor: QuadrotorConfig = DEFAULTS.quadrotor,
        threads: int = DEFAULTS.scan.threads,
    ):
        from lf3pm.map import Map

        self.threads = threads
        self._attitude = None  # AttitudeGuidance, made when a plan first asks for rounds
        self.world = world_points if isinstance(world_points, Map) else None
        world_points = world_points.points if self.world is not None else world_points
        self._points = world_points
        self.solm, self.guidance = solm, guidance
        self.quad = quadrotor if isinstance(quadrotor, Quadrotor) else Quadrotor.from_config(quadrotor)
        began = time.perf_counter()
        g = solm.grid_spec
        levels = np.asarray(g.z_levels)
        x0, y0, x1, y1 = g.bounds
        margin = 1.0
        self.esdf = flight_esdf(
            np.asarray(world_points, dtype=np.float64),
            (x0 - margin, y0 - margin, levels.min() - margin),
            (x1 + margin, y1 + margin, levels.max() + margin),
        )
        self.layer = guidance_layer(solm, guidance)
        self.field = guidance_field(solm, guidance, self.layer.filled)
        self.r_safe = float(solm.attrs.get("robot_radius", _core.FlightWeights().r_safe))
        # The ESDF is conservative by half a voxel diagonal (flight_esdf); the front end's
        # cells are checked exactly by the SOLM, so its moves ask the voxels' own distance:
        # a wall across a move still stops it, a wall half a voxel nearer than exact does not.
        self.front_clearance = max(0.0, self.r_safe - 0.5 * math.sqrt(3) * ESDF_RES)
        self.move_free = clear_moves(solm, self.esdf, self.front_clearance)
        self.setup_s = time.perf_counter() - began

    def problem(self, w_q: float, w_heading: float, head, tail, q, T, rho_T: float, w_energy: float, field=None):
        """The back end's objective (a C++ FlightProblem) with guidance weight ``w_q``,
        heading weight ``w_heading``, head and tail states (4 x 3), initial waypoints (4 x
        (N - 1)) and durations (N) on this planner's fields (``field``: another guidance
        field in place of the level one)."""
        weights = _core.FlightWeights()
        weights.w_q, weights.w_heading, weights.r_safe = w_q, w_heading, self.r_safe
        return _core.FlightProblem(
            self.quad.params(),
            self.quad.limits(),
            weights,
            self.field if field is None else field,
            self.esdf,
            rho_T,
            w_energy,
            YAW_ENERGY,
            head,
            tail,
            q,
            T,
        )

    def plan(
        self,
        start,
        goal,
        *,
        planner: str = "joint",
        rho_T: float = 1.0,
        w_energy: float = 1e-2,
        piece_length: float = 2.0,
        check_rate: float = CHECK_RATE,
        attitude_rounds: int = ATTITUDE_ROUNDS,
    ) -> FlightPlan:
        """A flight from ``start`` (x, y, z, yaw) to ``goal`` (x, y, z[, yaw]) by
        ``planner`` (:func:`plan_flight`)."""
        if planner not in PLANNERS:
            raise Lf3pmError(f"unknown flight planner {planner!r}; use one of {', '.join(PLANNERS)}")
        if attitude_rounds and planner != "joint":
            raise Lf3pmError(f"attitude_rounds apply to the joint planner, not {planner}")
        if not (isinstance(attitude_rounds, int) and 0 <= attitude_rounds <= MAX_ATTITUDE_ROUNDS):
            raise Lf3pmError(
                f"attitude_rounds must be an integer in [0, {MAX_ATTITUDE_ROUNDS}], got {attitude_rounds!r}"
            )
        began = time.perf_counter()
        guidance, quad = self.guidance, self.quad
        perceptive = planner == "joint"
        front = guidance if perceptive else guidance.model_copy(update={"metric": "none"})
        path = plan_flight_path(self.solm, start, goal, guidance=front, quadrotor=quad, move_free=self.move_free)
        searched = time.perf_counter()
        waypoints, durations = initial_guess(path, piece_length, quad.vmax)
        if not perceptive:
            waypoints[3] = _heading_yaws(path, waypoints)
        head, tail = np.zeros((4, 3)), np.zeros((4, 3))
        head[:, 0] = [*path.positions[0], path.yaws[0]]
        tail[:, 0] = [*path.positions[-1], path.yaws[-1]]

        def problem(w_q, w_heading, q, T, field=None):
            return self.problem(w_q, w_heading, head, tail, q, T, rho_T, w_energy, field)

        w_q = guidance.weight * rho_T if guidance.metric != "none" else 0.0
        flight = problem(w_q if perceptive else 0.0, 0.0 if perceptive else W_HEADING, waypoints, durations)
        out = flight.optimize(_core.trajectory_lbfgs())
        x = np.asarray(out["x"])
        if planner == "yaw_only":
            flight, x, out = _yaw_only(problem, w_q, flight, x)
        trajectory = _trajectory(flight, x)
        optimized = time.perf_counter()
        rounds = []
        if perceptive and w_q > 0 and attitude_rounds:
            attitude = self.attitude_guidance()
            for _ in range(attitude_rounds):
                # The attitude as flown: after the time scaling that the limits will ask for.
                flown, _, _ = within_limits(trajectory, quad, self.esdf, self.r_safe, SEARCH_RATE)
                cost, summary = attitude.correct(flown.sample(sample_rate(self.solm.grid_spec, quad.vmax)), quad)
                q, T = _waypoints(x, trajectory.durations)
                flight = problem(w_q, 0.0, q, T, guidance_field(self.solm, guidance, cost))
                out = flight.optimize(_core.trajectory_lbfgs())
                x = np.asarray(out["x"])
                trajectory = _trajectory(flight, x)
                rounds.append(summary)
        corrected = time.perf_counter()
        trajectory, factor, limits = within_limits(trajectory, quad, self.esdf, self.r_safe, check_rate)
        return FlightPlan(
            path=path,
            trajectory=trajectory,
            time_scale=factor,
            limits=limits,
            terms=dict(out["terms"]),
            iterations=int(out["iterations"]),
            status=str(out["status"]),
            reason=str(out["reason"]),
            objective=float(out["f"]),
            planner=planner,
            seconds={"search": searched - began, "optimize": optimized - searched, "attitude": corrected - optimized},
            attitude=rounds,
        )

    def attitude_guidance(self) -> AttitudeGuidance:
        """A fresh correction of this planner's guidance layer at the planned attitude (the
        map indexed and the sensor's rays and uncapped layer made on first use, then kept)."""
        from lf3pm.map import load_map

        if self._attitude is None:
            if self.world is None:
                self.world = load_map(self._points)
            self._attitude = AttitudeGuidance(self.solm, self.world, self.layer, self.guidance.power, self.threads)
        self._attitude.start()
        return self._attitude


def plan_flight(
    solm,
    world_points: np.ndarray,
    start,
    goal,
    *,
    planner: str = "joint",
    guidance: GuidanceConfig = DEFAULTS.guidance,
    quadrotor: QuadrotorConfig = DEFAULTS.quadrotor,
    rho_T: float = 1.0,
    w_energy: float = 1e-2,
    piece_length: float = 2.0,
    check_rate: float = CHECK_RATE,
    attitude_rounds: int = ATTITUDE_ROUNDS,
) -> FlightPlan:
    """A flight on ``solm`` (r3yaw) over the map ``world_points`` (N x 3, for the ESDF, or
    the Map) from
    ``start`` (x, y, z, yaw) to ``goal`` (x, y, z[, yaw]), at rest at both ends, with the
    guidance and quadrotor sections (module docstring), by ``planner`` (:data:`PLANNERS`):
    ``joint`` optimises position and yaw on the guidance; ``velocity_yaw`` takes the
    shortest front-end path and no guidance, the yaw held along the velocity; ``yaw_only``
    is that flight with its yaw waypoints alone then optimised on the guidance (positions
    and durations kept, then time-scaled to the limits). ``attitude_rounds``: the joint
    flight is then corrected for the attitude it flies at and optimised again, so many
    times (lf3pm.planner.flight_attitude; 0: the level SOLM only). Single-threaded but for
    those casts (every core). After rounds, ``iterations``, ``status`` and ``objective``
    are the last round's (on the corrected field). Replanning on one SOLM:
    :class:`FlightPlanner`."""
    planner_ = FlightPlanner(solm, world_points, guidance=guidance, quadrotor=quadrotor)
    plan = planner_.plan(
        start,
        goal,
        planner=planner,
        rho_T=rho_T,
        w_energy=w_energy,
        piece_length=piece_length,
        check_rate=check_rate,
        attitude_rounds=attitude_rounds,
    )
    return FlightPlan(**{**plan.__dict__, "seconds": {"setup": planner_.setup_s, **plan.seconds}})


def _trajectory(flight, x: np.ndarray) -> FlightTrajectory:
    coefficients, durations = flight.trajectory(x)
    return FlightTrajectory(np.asarray(coefficients).reshape(-1, 6, 4), np.asarray(durations))


def _waypoints(x: np.ndarray, durations) -> tuple[np.ndarray, np.ndarray]:
    """The inner waypoints (4 x (N - 1)) of the flight at ``x`` whose N pieces last
    ``durations``, and those durations."""
    n = len(durations)
    return x[: 4 * (n - 1)].reshape(n - 1, 4).T.copy(), np.asarray(durations)


def _heading_yaws(path: FlightPath, waypoints: np.ndarray) -> np.ndarray:
    """Yaws along the direction of travel at the initial waypoints (unwrapped from the
    start's yaw): the baselines' initial guess."""
    knots = np.vstack([path.positions[0], waypoints[:3].T, path.positions[-1]])
    direction = np.diff(knots, axis=0)
    yaw = np.arctan2(direction[:, 1], direction[:, 0])
    inner = np.unwrap(np.concatenate([[path.yaws[0]], yaw[1:]]))[1:]
    return inner


def _yaw_only(problem, w_q: float, flight, x: np.ndarray):
    """The yaw waypoints of the flight at ``x`` optimised on the guidance with positions and
    durations held (scipy L-BFGS-B over the C++ objective; the baseline is not timed):
    (problem, x, outcome)."""
    from scipy.optimize import minimize

    q, durations = _waypoints(x, flight.trajectory(x)[1])
    n = len(durations)
    yawing = problem(w_q, 0.0, q, durations)
    free = np.arange(3, 4 * (n - 1), 4)  # each waypoint's yaw (x holds them column by column)
    base = np.asarray(yawing.initial).copy()

    def objective(z):
        full = base.copy()
        full[free] = z
        f, grad, _ = yawing.evaluate(full)
        return f, np.asarray(grad)[free]

    result = minimize(objective, base[free], jac=True, method="L-BFGS-B", options={"maxiter": 500})
    full = base.copy()
    full[free] = result.x
    _, _, terms = yawing.evaluate(full)
    outcome = {
        "terms": terms,
        "iterations": int(result.nit),
        "status": "converged" if result.success else "stalled",
        "reason": str(result.message),
        "f": float(result.fun),
    }
    return yawing, full, outcome
