"""Checks of a trajectory's kinematic limits on 100 Hz samples, shared by the
back-end and end-to-end planning tests (bench/bench_random_queries.py has its own copy:
nothing under bench/ imports tests/)."""

import numpy as np


def body_speeds(trajectory, rate: float = 100.0):
    """(samples, v_lon, v_lat) at ``rate`` Hz; v in the body frame."""
    s = trajectory.sample(rate)
    c, si = np.cos(s["yaw"]), np.sin(s["yaw"])
    return s, s["vx"] * c + s["vy"] * si, -s["vx"] * si + s["vy"] * c


def kinematic_checks(trajectory, robot, slack: float = 0.02, rate: float = 100.0):
    """(samples, {check: passed}) for every limit of ``robot`` on ``rate`` Hz samples: speeds
    (body frame and, if set, |v|), yaw rate, body-frame accelerations and yaw acceleration
    within ``slack``; no sideways motion (|h| < 1e-3 m/s) for diff and car; the car's
    turning radius within ``slack`` of its top speed. The yaw acceleration is taken by
    central differences of the sampled yaw rate, as a tracking controller would see it
    (a jump in the yaw rate fails it)."""
    s, v_lon, v_lat = body_speeds(trajectory, rate)
    c, si = np.cos(s["yaw"]), np.sin(s["yaw"])
    lim = 1 + slack
    out = {
        "v_lon": np.max(np.abs(v_lon)) <= lim * robot.vmax_lon,
        "omega": np.max(np.abs(s["omega"])) <= lim * robot.wmax,
        "a_lon": np.max(np.abs(s["ax"] * c + s["ay"] * si)) <= lim * robot.amax_lon,
        "a_lat": np.max(np.abs(-s["ax"] * si + s["ay"] * c)) <= lim * robot.amax_lat,
        "alpha": np.max(np.abs(np.gradient(s["omega"], s["t"]))) <= lim * robot.alpha_max,
    }
    if robot.kind == "omni":
        out["v_lat"] = np.max(np.abs(v_lat)) <= lim * robot.vmax_lat
        if robot.vmax_norm is not None:
            out["speed"] = np.max(np.hypot(s["vx"], s["vy"])) <= lim * robot.vmax_norm
    else:
        out["sideways"] = np.max(np.abs(v_lat)) < 1e-3  # |h|: no sideways motion
    if robot.kind == "car":  # R |omega| <= |v_lon|
        out["turn"] = np.max(robot.min_turn_radius * np.abs(s["omega"]) - np.abs(v_lon)) <= slack * robot.vmax_lon
    return s, {name: bool(ok) for name, ok in out.items()}


def assert_kinematics_hold(trajectory, robot, slack: float = 0.02):
    """Asserts every check of :func:`kinematic_checks`; returns the samples."""
    s, checks = kinematic_checks(trajectory, robot, slack)
    assert all(checks.values()), {name: ok for name, ok in checks.items() if not ok}
    return s
