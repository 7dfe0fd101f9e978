"""The replay's ROS 2 bag (bag.py): it opens with rosbags, with the right message
counts, stamps and point fields, and replaces nothing."""

from types import SimpleNamespace

import numpy as np
import pytest
from analytic_scenes import grid_plane
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

import lf3pm
from lf3pm.errors import Lf3pmError
from lf3pm.replays.bag import cloud_dtype, write_bag
from lf3pm.replays.motion import Motion
from lf3pm.scan.scans import ScanStream
from lf3pm.sensors import get_sensor, spinning_rings

TYPES = get_typestore(Stores.ROS2_HUMBLE)


@pytest.fixture(scope="module")
def room():
    """A 20 x 20 m floor with a wall along x = 6, and a 1 s drive along x."""
    pts = np.vstack(
        [
            grid_plane((-10, -10, 0), (1, 0, 0), (0, 1, 0), 20, 20, 0.1),
            grid_plane((6, -10, 0.1), (0, 1, 0), (0, 0, 1), 20, 3, 0.1),
        ]
    )
    world = lf3pm.load_map(np.ascontiguousarray(pts))
    t = np.linspace(0.0, 1.0, 101)
    return world, Motion.from_arrays(t, t, 0 * t, 0.2 * t, np.ones_like(t), 0 * t, np.full_like(t, 0.2), map=world)


def imu_samples(t0, t1, rate=200.0):
    t = np.arange(t0, t1 + 1e-9, 1.0 / rate)
    return SimpleNamespace(t=t, accel=np.tile([0.0, 0.0, 9.81], (len(t), 1)), gyro=np.zeros((len(t), 3)))


def messages(path, topic):
    with Reader(path) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        return [(stamp, TYPES.deserialize_cdr(raw, c.msgtype)) for c, stamp, raw in reader.messages(conns)]


@pytest.mark.slow
@pytest.mark.parametrize("sensor, layout", [("vlp16", "velodyne"), ("os1-64", "ouster"), ("mid70", "velodyne")])
def test_bag_counts_stamps_and_points(room, tmp_path, sensor, layout):
    world, motion = room
    scans = ScanStream(world, motion, get_sensor(sensor), rate=10.0, seed=2)
    imu = imu_samples(0.0, 1.0)
    path = tmp_path / "out.bag"
    info = write_bag(path, scans, imu)
    assert info["point_layout"] == layout and sorted(p.name for p in tmp_path.iterdir()) == ["out.bag"]
    with Reader(path) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    meta = (path / "metadata.yaml").read_text()
    assert "storage_identifier: sqlite3" in meta and "version: 8" in meta
    assert counts == {"/points": 11, "/imu": 201, "/ground_truth": 101, "/tf": 101, "/tf_static": 1}
    assert counts == info["topics"]
    # Scan 0 starts one period before t0 = 0: the bag's clock puts that at 1 s.
    offset = info["clock_offset_s"]
    assert offset == pytest.approx(1.1)
    clouds = messages(path, "/points")
    for k, (logged, msg) in enumerate(clouds):
        end = scans.times[k]
        start_ns = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        assert start_ns == round((end - 0.1 + offset) * 1e9) and logged == round((end + offset) * 1e9)
        assert msg.header.frame_id == "lidar" and msg.width == scans.hits[k] > 1000
        record = np.frombuffer(msg.data.tobytes(), dtype=cloud_dtype(layout))
        scan = scans[k]
        np.testing.assert_allclose(np.column_stack([record["x"], record["y"], record["z"]]), scan.points, atol=1e-5)
        offsets = record["t"] * 1e-9 if layout == "ouster" else record["time"].astype(float)
        np.testing.assert_allclose(offsets, scan.stamps - (end - 0.1), atol=1e-6)
        assert offsets.min() > 0 and offsets.max() <= 0.1 + 1e-6
        rings = spinning_rings(scans.sensor)
        expected = 0 if rings is None else rings[scan.ray]  # 0 is the lowest beam
        np.testing.assert_array_equal(record["ring"], expected)
    stamps = [logged for logged, _ in messages(path, "/imu")]
    assert stamps == [round((t + offset) * 1e9) for t in imu.t]
    truth = messages(path, "/ground_truth")
    logged, odom = truth[50]
    assert logged == round((0.5 + offset) * 1e9) and odom.child_frame_id == "base_link"
    p = motion.position([0.5])[0]
    assert [odom.pose.pose.position.x, odom.pose.pose.position.y, odom.pose.pose.position.z] == pytest.approx(p)
    assert odom.pose.pose.orientation.z == pytest.approx(np.sin(0.05)) and odom.twist.twist.angular.z == pytest.approx(
        0.2
    )
    # The body frame's forward speed: 1 m/s along x, turned by yaw 0.1.
    assert odom.twist.twist.linear.x == pytest.approx(np.cos(0.1), abs=1e-6)
    static = messages(path, "/tf_static")[0][1].transforms
    assert [(s.header.frame_id, s.child_frame_id) for s in static] == [("base_link", "lidar"), ("base_link", "imu")]


def test_bag_replaces_nothing(room, tmp_path):
    world, motion = room
    scans = ScanStream(world, motion, get_sensor("mid70"))
    existing = tmp_path / "old.bag"
    existing.write_text("keep")
    with pytest.raises(Lf3pmError, match="exists"):
        write_bag(existing, scans, imu_samples(0, 1))
    assert existing.read_text() == "keep"
    with pytest.raises(Lf3pmError, match="does not exist"):
        write_bag(tmp_path / "no" / "such.bag", scans, imu_samples(0, 1))
