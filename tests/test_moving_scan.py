"""Scans of a moving sensor (motion distortion): each ray cast from the pose at
its own firing time, checked against straight-line motion past a known plane and
against KISS-ICP's own deskewing."""

import numpy as np
import pytest
from analytic_scenes import grid_plane
from kiss_icp.preprocess import Preprocessor

from lf3pm import _core
from lf3pm.config import scan_params
from lf3pm.errors import Lf3pmError
from lf3pm.pose import pose_matrices, pose_matrix
from lf3pm.scan.moving_scan import firing_fractions, simulate_moving_scan
from lf3pm.sensors import get_sensor
from lf3pm.trajectory.sampling import LinearMotion

PERIOD = 0.1
WALL_X = 10.0


@pytest.fixture(scope="module")
def wall():
    """The plane x = 10, 40 m wide and 20 m high, sampled every 10 cm."""
    return _core.MapIndex(
        np.ascontiguousarray(grid_plane((WALL_X, -20.0, -10.0), (0, 1, 0), (0, 0, 1), 40.0, 20.0, 0.1))
    )


@pytest.fixture(scope="module")
def mid70():
    return get_sensor("mid70")


def scan_along(index, sensor, start, end, noise=0.0, seed=3, stream=2):
    """The scan ending at t = 1 s while the sensor goes from pose ``start`` (x y z yaw)
    at t = 1 - PERIOD to ``end`` at t = 1 at constant velocity."""
    t = np.array([1.0 - PERIOD, 1.0])
    motion = LinearMotion(t, np.array([start, end], dtype=float))
    return simulate_moving_scan(
        index,
        motion,
        1.0,
        PERIOD,
        sensor.directions,
        sensor.min_range,
        sensor.max_range,
        noise=noise,
        seed=seed,
        stream=stream,
    )


def test_firing_fractions():
    assert firing_fractions(4) == pytest.approx([0.25, 0.5, 0.75, 1.0])
    with pytest.raises(Lf3pmError, match="at least one ray"):
        firing_fractions(0)


def test_pose_matrices_match_pose_matrix():
    poses = np.array([[1.0, -2.0, 0.5, 0.3], [0.0, 0.0, 0.0, -3.0]])
    np.testing.assert_allclose(pose_matrices(poses), [pose_matrix(p) for p in poses], atol=1e-15)


def test_at_rest_the_moving_scan_is_the_static_scan(wall, mid70):
    pose = [0.0, 1.0, 0.5, 0.2]
    moving = scan_along(wall, mid70, pose, pose, noise=0.02)
    static = _core.simulate_scan(
        wall,
        pose_matrix(pose),
        mid70.directions,
        scan_params(mid70.min_range, mid70.max_range, noise=0.02, seed=3, stream=2),
    )
    assert len(moving.ray) > 1000
    np.testing.assert_array_equal(moving.ray, static["ray"])  # same rays, same noise
    np.testing.assert_array_equal(moving.points, static["sensor_points"])
    np.testing.assert_array_equal(moving.world_points, static["world_points"])
    np.testing.assert_allclose(moving.reference_points, static["sensor_points"], atol=1e-12)
    np.testing.assert_array_equal(moving.reference, pose_matrix(pose))


def test_timestamps_are_firing_fractions_increasing_in_firing_order(wall, mid70):
    scan = scan_along(wall, mid70, [0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0])
    assert np.all(np.diff(scan.ray) > 0)  # emission order
    np.testing.assert_array_equal(scan.timestamps, (scan.ray + 1) / mid70.num_rays)
    assert scan.timestamps.min() > 0 and scan.timestamps.max() <= 1 and np.all(np.diff(scan.timestamps) > 0)


def test_straight_motion_towards_a_plane(wall, mid70):
    """At v = (3, 4, 0) m/s (0.5 m per scan) each hit lies on the wall in the world
    (noise along the ray only); a point fired at fraction f was measured from
    v (1 - f) PERIOD behind the reference pose, so the reported point sits that much
    ahead of its position in the reference frame."""
    v = np.array([3.0, 4.0, 0.0])
    start = np.r_[-v * PERIOD, 0.0]
    sigma = 0.02
    scan = scan_along(wall, mid70, start, [0.0, 0.0, 0.0, 0.0], noise=sigma)
    assert len(scan.ray) > 0.9 * mid70.num_rays
    # A range error e moves a hit by e along its ray, so off the plane by at most |e|.
    assert np.max(np.abs(scan.world_points[:, 0] - WALL_X)) < 5 * sigma
    behind = (1.0 - scan.timestamps)[:, None] * PERIOD * v
    np.testing.assert_allclose(scan.points - scan.reference_points, behind, atol=1e-9)
    np.testing.assert_array_equal(scan.reference, np.eye(4))
    # The rays were fired from positions v_x * PERIOD = 0.3 m apart in x (less a ray interval).
    assert np.ptp(scan.world_points[:, 0] - scan.points[:, 0]) == pytest.approx(v[0] * PERIOD, rel=1e-3)


def test_turning_in_place(wall, mid70):
    """Yaw rate 2 rad/s at a fixed position: ray f was fired from a heading
    2 (1 - f) PERIOD short of the reference one."""
    rate = 2.0
    scan = scan_along(wall, mid70, [0.0, 0.0, 0.0, -rate * PERIOD], [0.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(scan.world_points[:, 0], WALL_X, atol=1e-9)
    angle = -rate * PERIOD * (1.0 - scan.timestamps)
    c, s = np.cos(angle), np.sin(angle)
    p = scan.points
    expected = np.column_stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1], p[:, 2]])
    np.testing.assert_allclose(scan.reference_points, expected, atol=1e-9)


@pytest.mark.parametrize("start", [[-0.3, -0.4, 0.0, 0.0], [0.0, 0.0, 0.0, -0.2]])
def test_kiss_icp_deskewing_recovers_the_reference_frame(wall, mid70, start):
    """KISS-ICP, given the reported points, our timestamps and the true motion of
    one scan period, moves every point to where it lies in the reference frame
    (to its rescaling of the timestamps by their spread: f_min of one period)."""
    scan = scan_along(wall, mid70, start, [0.0, 0.0, 0.0, 0.0], noise=0.02)
    delta = np.linalg.inv(pose_matrix(start))  # scan-to-scan motion, previous -> current
    deskewed = Preprocessor(1000.0, 0.0, True, 1).preprocess(scan.points, scan.timestamps, delta)
    error = np.linalg.norm(deskewed - scan.reference_points, axis=1)
    bound = scan.timestamps.min() * (0.5 + abs(start[3]) * np.linalg.norm(scan.points, axis=1)) + 1e-9
    assert np.all(error <= bound)
    # The correction is not trivial: raw points are up to 0.5 m (or 0.2 rad) off.
    raw = np.linalg.norm(scan.points - scan.reference_points, axis=1)
    assert raw.max() > 100 * error.max()


def test_bad_period(wall, mid70):
    with pytest.raises(Lf3pmError, match="period"):
        simulate_moving_scan(wall, LinearMotion([0.0, 1.0], [[0, 0, 0, 0]] * 2), 1.0, 0.0, mid70.directions, 0.1, 100.0)
    with pytest.raises(ValueError, match="one pose per ray"):
        _core.simulate_moving_scan(
            wall, np.broadcast_to(np.eye(4), (3, 4, 4)).copy(), mid70.directions[:2], scan_params(0.1, 100.0)
        )
