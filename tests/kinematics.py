"""Checks of a trajectory's kinematic limits on 100 Hz samples, shared by the
back-end and end-to-end planning tests."""

import numpy as np


def body_speeds(trajectory):
    """(samples, v_lon, v_lat) at 100 Hz; v in the body frame."""
    s = trajectory.sample(100.0)
    c, si = np.cos(s["yaw"]), np.sin(s["yaw"])
    return s, s["vx"] * c + s["vy"] * si, -s["vx"] * si + s["vy"] * c


def assert_kinematics_hold(trajectory, robot, slack: float = 0.02):
    """Speed (body-frame and, if set, |v|) and yaw-rate limits within ``slack``; no sideways motion (|h| < 1e-3 m/s)
    for diff and car; the car's turning radius within ``slack`` of its top speed."""
    s, v_lon, v_lat = body_speeds(trajectory)
    assert np.max(np.abs(v_lon)) <= (1 + slack) * robot.vmax_lon
    assert np.max(np.abs(s["omega"])) <= (1 + slack) * robot.wmax
    if robot.kind == "omni":
        assert np.max(np.abs(v_lat)) <= (1 + slack) * robot.vmax_lat
        if robot.vmax_norm is not None:
            assert np.max(np.hypot(s["vx"], s["vy"])) <= (1 + slack) * robot.vmax_norm
    else:
        assert np.max(np.abs(v_lat)) < 1e-3  # |h|: no sideways motion
    if robot.kind == "car":  # R |omega| <= |v_lon|
        assert np.max(robot.min_turn_radius * np.abs(s["omega"]) - np.abs(v_lon)) <= slack * robot.vmax_lon
    return s
