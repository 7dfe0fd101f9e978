"""LF-3PM trajectory back end: front-end waypoints to a feasible, localisable trajectory.

The trajectory is a cubic MINCO (minimum acceleration) in (x, y, yaw) with zero
velocity at both ends; its free intermediate waypoints and piece durations
(T = GCOPTER's C^2 map of a free tau) minimise, with L-BFGS in C++,

    sum over samples of (w_q q(x, y, yaw) + feasibility penalties) dt
        + rho_T * total time + w_energy * acceleration energy,

Diff and car robots use the flat output: (x, y) only, the yaw follows the
direction of travel, so there is no lateral motion at all. Both leave and reach
rest on straight pieces, which the C++ problem puts around the spline and joins
to it with continuous acceleration (so the yaw rate never jumps): a car's run
along its start and goal yaw, a diff robot's along the path's first and last
direction, to and from which it turns on the spot (pieces added after
optimisation). docs/planner_backend.md has the math, and why there is no PHR
augmented-Lagrangian loop.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from lf3pm import _core, libm
from lf3pm.errors import Lf3pmError
from lf3pm.grid_field import GridField
from lf3pm.trajectory.robots import Robot
from lf3pm.trajectory.trajectory import Trajectory

#: The objective's weights as the C++ core defines them (trajectory_cost.hpp CostWeights):
#: the penalty weight W, K samples per piece and the clearance margin, read once from there.
DEFAULT_WEIGHTS = _core.CostWeights()
ESDF_MARGIN = DEFAULT_WEIGHTS.esdf_margin
#: Samples per second on which every limit is checked and enforced (:func:`within_limits`):
#: a tracking controller's rate; CSV_RATE's samples (100 Hz) are a subset of them.
LIMIT_CHECK_RATE = 1000.0


@dataclass(frozen=True)
class OptimizeResult:
    """An optimised trajectory and how it was found.

    ``status``: L-BFGS's (converged, stalled, max_iterations, line_search_failed) and
    ``reason``, why it stopped, with the numbers that decided it (lbfgs.hpp).
    ``terms``: the objective's terms at the optimiser's solution (q, velocity, omega,
    acceleration, turn, esdf, time, energy, total), before ``time_scale``: the uniform
    stretch of time (>= 1) that brought every limit inside (:func:`within_limits`).
    ``violations`` of the returned trajectory on samples at ``check_rate`` Hz:
    max_v_lon_ratio, max_v_lat_ratio (omni), max_speed_ratio (omni with vmax_norm),
    max_omega_ratio, max_a_lon_ratio, max_a_lat_ratio (body-frame acceleration), max_alpha_ratio
    (yaw acceleration, from central differences of the sampled yaw rate) (<= 1 is within
    the limit), max_turn_excess (car: max(R |omega|
    - |v_lon|) in m/s), max_h (|xdot sin yaw - ydot cos yaw|, m/s; diff and car)
    and min_clearance (ESDF - r_safe, m). Time scaling changes neither of the last two
    nor the car's turn excess in sign: those are the path's geometry.
    """

    trajectory: Trajectory
    iterations: int
    evaluations: int
    status: str
    reason: str
    terms: dict
    violations: dict
    wall_time: float
    time_scale: float = 1.0

    @property
    def limited_by(self) -> str | None:
        """The limit the trajectory presses hardest against, as its ratio's name in
        ``violations`` (e.g. ``max_omega_ratio``); None when it has none (no ratio)."""
        ratios = {k: v for k, v in self.violations.items() if k in _SPEED_RATIOS + _ACCELERATION_RATIOS}
        return max(ratios, key=ratios.get) if ratios else None


def make_problem(
    waypoints,
    cost: GridField | None,
    esdf: GridField | None,
    robot: Robot,
    *,
    w_q: float = 1.0,
    rho_T: float = 1.0,
    w_energy: float = 1e-3,
    penalty: float = DEFAULT_WEIGHTS.penalty,
    esdf_margin: float = ESDF_MARGIN,
    samples: int = DEFAULT_WEIGHTS.samples,
    piece_length: float = 2.0,
    corners: bool = False,
    turn_price: float = 0.0,
):
    """The C++ objective (``lf3pm._core.TrajectoryProblem``) and its initial guess from
    front-end waypoints (K, 3: x, y, yaw), K >= 2. Arguments as in :func:`optimize_trajectory`."""
    wp = np.asarray(waypoints, dtype=np.float64)
    if wp.ndim != 2 or wp.shape[1] != 3 or len(wp) < 2:
        raise Lf3pmError(f"waypoints must be a (K, 3) array of x, y, yaw with K >= 2, got shape {wp.shape}")
    if not np.isfinite(wp).all():
        raise Lf3pmError("waypoints must be finite")
    if not isinstance(robot, Robot):
        raise Lf3pmError("robot must be an lf3pm.Robot")
    for name, field in (("cost", cost), ("esdf", esdf)):
        if field is not None and not isinstance(field, GridField):
            raise Lf3pmError(f"{name} must be a GridField or None")
    if esdf is not None and esdf.yaw_bins != 1:
        raise Lf3pmError("the ESDF must be an (ny, nx) field")
    for name, value in (
        ("w_q", w_q),
        ("rho_T", rho_T),
        ("w_energy", w_energy),
        ("penalty", penalty),
        ("esdf_margin", esdf_margin),
        ("turn_price", turn_price),
    ):
        if not (math.isfinite(value) and value >= 0):
            raise Lf3pmError(f"{name} must be a non-negative number, got {value!r}")
    if not (isinstance(samples, int) and samples >= 1):
        raise Lf3pmError(f"samples per piece must be an integer >= 1, got {samples!r}")
    if not (math.isfinite(piece_length) and piece_length > 0):
        raise Lf3pmError(f"piece_length must be positive, got {piece_length!r}")

    points, durations = _initial_guess(wp, robot, piece_length, corners)
    head = np.zeros((3, 2))
    tail = np.zeros((3, 2))
    head[:, 0], tail[:, 0] = points[0], points[-1]
    if robot.kind == "diff":
        # The yaw column only unwraps the direction of travel (Trajectory.flat): start it
        # on the first and end it on the last direction of travel, near the given yaws.
        head[2, 0], tail[2, 0] = points[1, 2], points[-2, 2]
    weights = _core.CostWeights()
    weights.w_q, weights.penalty, weights.esdf_margin, weights.samples = w_q, penalty, esdf_margin, samples
    weights.turn, weights.w_time = (turn_price, rho_T) if robot.kind == "omni" else (0.0, rho_T)
    return _core.TrajectoryProblem(
        cost._core if cost is not None else None,
        esdf._core if esdf is not None else None,
        robot.limits(),
        weights,
        rho_T,
        w_energy,
        head,
        tail,
        np.ascontiguousarray(points[1:-1]),
        durations,
    )


def _initial_guess(wp: np.ndarray, robot: Robot, piece_length: float, corners: bool):
    """Knots along the path and piece durations at half speed. Arc length u counts yaw at
    0.5 m/rad for omni robots (turns on the spot get pieces too); diff and car robots move
    in (x, y) only, their yaw the direction of travel. ``corners``: every waypoint is a
    knot (a shortcut path's corners), longer segments split into pieces of at most
    piece_length; otherwise the path is resampled evenly at about piece_length."""
    wp = wp.copy()
    wp[:, 2] = np.unwrap(wp[:, 2])
    step = np.hypot(*np.diff(wp[:, :2], axis=0).T)
    if robot.nonholonomic:
        wp[1:-1, 2] = _travel_yaw(wp)
    else:
        step = np.hypot(step, 0.5 * np.diff(wp[:, 2]))
    keep = np.concatenate([[True], step > 1e-9])
    wp, u = wp[keep], np.concatenate([[0.0], np.cumsum(step[step > 1e-9])])
    if len(wp) < 2:
        raise Lf3pmError(
            "start and goal coincide in x and y: nothing to optimise"
            if robot.nonholonomic
            else "start and goal coincide: nothing to optimise"
        )
    if corners:
        splits = np.maximum(1, np.ceil(np.diff(u) / piece_length).astype(int))
        knots = np.concatenate(
            [np.linspace(a, b, k, endpoint=False) for a, b, k in zip(u[:-1], u[1:], splits)] + [u[-1:]]
        )
    else:
        knots = np.linspace(0.0, u[-1], max(1, math.ceil(u[-1] / piece_length)) + 1)
    if robot.nonholonomic:
        # Diff and car splines join straight ends and place their own first and last interior
        # waypoints (cpp/lf3pm/trajectory/trajectory_optimizer.hpp): a knot halfway along the first and
        # the last piece gives them those, and leaves the path's own knots as parameters.
        knots = np.unique(np.concatenate([knots, [0.5 * knots[1], 0.5 * (knots[-2] + knots[-1])]]))
    points = np.column_stack([np.interp(knots, u, wp[:, d]) for d in range(3)])
    dist = np.hypot(*np.diff(points[:, :2], axis=0).T)
    turn = np.zeros(len(dist)) if robot.nonholonomic else np.abs(np.diff(points[:, 2]))
    durations = np.maximum(np.maximum(dist / (0.5 * robot.vmax_lon), turn / (0.5 * robot.wmax)), 0.1)
    return points, durations


def _travel_yaw(wp: np.ndarray) -> np.ndarray:
    """Direction of travel at the interior waypoints (mean of the adjacent segments'),
    unwrapped from the start's yaw."""
    d = np.diff(wp[:, :2], axis=0)
    heading = libm.atan2(d[:, 1], d[:, 0])
    heading = np.unwrap(np.concatenate([[wp[0, 2]], heading]))[1:]
    return 0.5 * (heading[1:] + heading[:-1])


def _turn_in_place(x: float, y: float, yaw0: float, yaw1: float, wmax: float, alpha_max: float):
    """A cubic piece (4, 3) turning on the spot from yaw0 to yaw1 at rest at both ends,
    and its duration T: the shortest whose peak rate 1.5 |yaw1 - yaw0| / T and peak
    acceleration 6 |yaw1 - yaw0| / T^2 (at both ends) keep within wmax and alpha_max."""
    delta = yaw1 - yaw0
    T = max(1.5 * abs(delta) / wmax, math.sqrt(6.0 * abs(delta) / alpha_max))
    c = np.zeros((4, 3))
    c[0] = (x, y, yaw0)
    c[2, 2], c[3, 2] = 3 * delta / T**2, -2 * delta / T**3
    return c, T


def _with_turns(trajectory: Trajectory, start_yaw: float, goal_yaw: float, wmax: float, alpha_max: float) -> Trajectory:
    """Diff robots: turn on the spot from start_yaw to the trajectory's first heading and
    from its last heading to goal_yaw (the shorter way round)."""
    # Unwrap the flat pieces (through their yaw column) to within half a turn of start_yaw.
    c = trajectory.coefficients.copy()
    c[:, 0, 2] += 2 * np.pi * np.round((start_yaw - trajectory.evaluate(0.0)[0][0, 2]) / (2 * np.pi))
    trajectory = Trajectory(c, trajectory.durations, trajectory.flat)
    (p0, p1), _ = trajectory.evaluate([0.0, trajectory.duration])
    coefficients, durations = [trajectory.coefficients], [trajectory.durations]
    flat = [np.asarray(trajectory.flat)]
    if abs(p0[2] - start_yaw) > 1e-9:
        c, T = _turn_in_place(p0[0], p0[1], start_yaw, p0[2], wmax, alpha_max)
        coefficients.insert(0, c[None]), durations.insert(0, [T]), flat.insert(0, [False])
    last = goal_yaw + 2 * np.pi * np.round((p1[2] - goal_yaw) / (2 * np.pi))
    if abs(last - p1[2]) > 1e-9:
        c, T = _turn_in_place(p1[0], p1[1], p1[2], last, wmax, alpha_max)
        coefficients.append(c[None]), durations.append([T]), flat.append([False])
    return Trajectory(
        np.concatenate(coefficients), np.concatenate(durations).astype(np.float64), np.concatenate(flat).astype(bool)
    )


#: The C++ optimiser's L-BFGS defaults (trajectory_optimizer.hpp), written there once.
_LBFGS = _core.trajectory_lbfgs()


def optimize_trajectory(
    waypoints,
    cost: GridField | None,
    esdf: GridField | None,
    robot: Robot,
    *,
    w_q: float = 1.0,
    rho_T: float = 1.0,
    w_energy: float = 1e-3,
    penalty: float = DEFAULT_WEIGHTS.penalty,
    esdf_margin: float = ESDF_MARGIN,
    samples: int = DEFAULT_WEIGHTS.samples,
    piece_length: float = 2.0,
    corners: bool = False,
    turn_price: float = 0.0,
    g_epsilon: float = _LBFGS.g_epsilon,
    rel_cost_tol: float = _LBFGS.delta,
    max_iterations: int = _LBFGS.max_iterations,
    check_rate: float = LIMIT_CHECK_RATE,
) -> OptimizeResult:
    """Optimise a trajectory through the front end's waypoints (K, 3: x, y, yaw).

    ``cost``: the localisability cost (a SOLM channel; None to leave it out), weighted
    by ``w_q`` and integrated over time; ``esdf``: the obstacle distance field (None: no
    clearance term); ``rho_T``: weight of the total time; ``w_energy``: weight of the
    acceleration energy; ``penalty``: weight W of the cubic penalties on the velocity,
    yaw rate, speed norm, turning radius and clearance limits (clearance penalised
    from r_safe + esdf_margin); ``samples``: K samples per piece; ``corners``: every
    waypoint is a knot of the initial guess (a shortcut path's corners; otherwise the
    path is resampled evenly); ``turn_price`` (omni robots; s per rad): a radian of yaw
    travel costs what this many seconds of travel cost there, (rho_T + w_q c) each, the
    front end's turn_radius / vmax_lon (0: turns are free); ``piece_length``:
    metres per piece in the initial guess. L-BFGS stops at ||g|| <= g_epsilon
    max(1, ||x||), when the objective fell by less than ``rel_cost_tol`` (relative)
    over 10 iterations, or after ``max_iterations`` (0: none). The limits are penalties
    in the objective, so the solution may pass them slightly: time is then stretched
    uniformly until every limit holds on samples at ``check_rate`` Hz
    (:func:`within_limits`). Single-threaded.
    """
    start = time.perf_counter()
    problem = make_problem(
        waypoints,
        cost,
        esdf,
        robot,
        w_q=w_q,
        rho_T=rho_T,
        w_energy=w_energy,
        penalty=penalty,
        esdf_margin=esdf_margin,
        samples=samples,
        piece_length=piece_length,
        corners=corners,
        turn_price=turn_price,
    )
    lbfgs = _core.trajectory_lbfgs()
    lbfgs.g_epsilon, lbfgs.delta, lbfgs.max_iterations = g_epsilon, rel_cost_tol, max_iterations
    out = problem.optimize(lbfgs)
    coefficients, durations = problem.trajectory(out["x"])
    trajectory = Trajectory(coefficients, durations, np.ones(len(durations), bool) if robot.nonholonomic else None)
    if robot.kind == "diff":
        wp = np.asarray(waypoints, dtype=np.float64)
        trajectory = _with_turns(trajectory, wp[0, 2], wp[-1, 2], robot.wmax, robot.alpha_max)
    trajectory, scale, violations = within_limits(trajectory, robot, esdf, check_rate)
    return OptimizeResult(
        trajectory,
        out["iterations"],
        out["evaluations"],
        out["status"],
        out["reason"],
        dict(out["terms"]),
        violations,
        time.perf_counter() - start,
        scale,
    )


#: Violation ratios that time scaling by k divides by k (speeds and rates) and by k^2
#: (accelerations); the other entries are geometry, which it leaves alone.
_SPEED_RATIOS = ("max_v_lon_ratio", "max_v_lat_ratio", "max_speed_ratio", "max_omega_ratio")
_ACCELERATION_RATIOS = ("max_a_lon_ratio", "max_a_lat_ratio", "max_alpha_ratio")
#: Rounds of :func:`within_limits`: the first stretch brings the sampled maxima to 1 but
#: for where the samples fall on the stretched trajectory, a second mends that residue.
_STRETCH_ROUNDS = 4
#: Relative margin of each stretch over the ratios it answers: their float rounding.
_STRETCH_MARGIN = 1e-12


def stretch_factor(violations: dict) -> float:
    """The uniform time stretch (>= 1) that brings every speed, rate and acceleration
    ratio of ``violations`` to at most 1: max(1, r_v, r_omega, sqrt(r_a), sqrt(r_alpha))."""
    return max(
        [1.0]
        + [violations[k] for k in _SPEED_RATIOS if k in violations]
        + [math.sqrt(violations[k]) for k in _ACCELERATION_RATIOS if k in violations]
    )


def within_limits(trajectory: Trajectory, robot: Robot, esdf: GridField | None, rate: float = LIMIT_CHECK_RATE):
    """(trajectory, factor, violations): ``trajectory`` stretched uniformly in time by the
    least factor (>= 1) that brings every speed, rate and acceleration limit inside on
    samples at ``rate`` Hz, and its :func:`check_limits` there. The path is unchanged, so
    are clearance and a car's turning radius (geometric: a stretch cannot mend them)."""
    total = 1.0
    for _ in range(_STRETCH_ROUNDS):
        violations = check_limits(trajectory, robot, esdf, rate)
        factor = stretch_factor(violations)
        if factor <= 1.0:
            return trajectory, total, violations
        factor *= 1.0 + _STRETCH_MARGIN
        trajectory, total = trajectory.time_scaled(factor), total * factor
    return trajectory, total, check_limits(trajectory, robot, esdf, rate)


def check_limits(trajectory: Trajectory, robot: Robot, esdf: GridField | None, rate: float = LIMIT_CHECK_RATE) -> dict:
    """Worst constraint values on samples at ``rate`` Hz (see :class:`OptimizeResult`)."""
    s = trajectory.sample(rate)
    c, si = np.cos(s["yaw"]), np.sin(s["yaw"])
    v_lon = s["vx"] * c + s["vy"] * si
    v_lat = -s["vx"] * si + s["vy"] * c
    a_lon = s["ax"] * c + s["ay"] * si
    a_lat = -s["ax"] * si + s["ay"] * c
    # The yaw acceleration as a tracking controller sees it: central differences of the
    # sampled yaw rate (a jump in the rate shows up as a spike).
    alpha = np.gradient(s["omega"], s["t"]) if len(s["t"]) > 1 else np.zeros(1)
    out = {
        "max_v_lon_ratio": float(np.max(np.abs(v_lon)) / robot.vmax_lon),
        "max_omega_ratio": float(np.max(np.abs(s["omega"])) / robot.wmax),
        "max_a_lon_ratio": float(np.max(np.abs(a_lon)) / robot.amax_lon),
        "max_a_lat_ratio": float(np.max(np.abs(a_lat)) / robot.amax_lat),
        "max_alpha_ratio": float(np.max(np.abs(alpha)) / robot.alpha_max),
    }
    if robot.nonholonomic:
        out["max_h"] = float(np.max(np.abs(v_lat)))
    else:
        out["max_v_lat_ratio"] = float(np.max(np.abs(v_lat)) / robot.vmax_lat)
    if robot.vmax_norm is not None:
        out["max_speed_ratio"] = float(np.max(np.hypot(s["vx"], s["vy"])) / robot.vmax_norm)
    if robot.kind == "car":
        out["max_turn_excess"] = float(max(np.max(robot.min_turn_radius * np.abs(s["omega"]) - np.abs(v_lon)), 0.0))
    if esdf is not None:
        out["min_clearance"] = float(np.min(esdf.sample(s["x"], s["y"])[0]) - robot.r_safe)
    return out
