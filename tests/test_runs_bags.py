"""Recorded runs from ROS bags (lf3pm.runs): small bags written with rosbags' writers (ROS 1,
ROS 2 sqlite3 and MCAP) read back exactly as written, bad messages in one line each."""

from __future__ import annotations

import json

import numpy as np
import pytest
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_typestore
from scipy.spatial.transform import Rotation

from lf3pm.config import RunConfig
from lf3pm.errors import RunError
from lf3pm.runs import Run
from lf3pm.runs.livox import livox_types
from lf3pm.runs.pointcloud2 import DATATYPES

# Times in integer ns, at today's order of stamps (where float64 seconds keep 0.24 us).
T0 = 1_700_000_000 * 10**9
SCAN_TIMES = tuple(T0 + k * 10**8 for k in (1, 2, 3))
POSE_TIMES = [T0 + k * 5 * 10**7 for k in range(9)]
IMU_TIMES = [T0 + k * 5 * 10**6 for k in range(80)]
#: Point layouts: PointCloud2 fields (name, PointField datatype) after x y z float32, or Livox.
LAYOUTS = {
    "ouster": [("t", 6)],
    "velodyne": [("time", 7)],
    "hesai": [("timestamp", 8)],
    "none": [],
    "livox": "livox_ros_driver",
    "livox2": "livox_ros_driver2",
}
POSE_TYPES = {
    "odometry": "nav_msgs/msg/Odometry",
    "pose": "geometry_msgs/msg/PoseStamped",
    "path": "nav_msgs/msg/Path",
}


def typestore(ros1: bool):
    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    store.register(livox_types())
    return store


def ns(t) -> int:
    """A time in ns: an int is one already, a float (a small one) is in seconds."""
    return t if isinstance(t, int) else round(t * 1e9)


def seconds(t: int) -> float:
    """A time in ns as the reader gives it in seconds (lf3pm.runs.pointcloud2.stamp_seconds)."""
    return t // 10**9 + t % 10**9 * 1e-9


class Messages:
    """Builds each message type of a run with ``store``'s classes."""

    def __init__(self, store, ros1: bool):
        self.T, self.ros1 = store.types, ros1

    def header(self, t: float, frame: str = "lidar"):
        stamp = self.T["builtin_interfaces/msg/Time"](sec=ns(t) // 10**9, nanosec=ns(t) % 10**9)
        extra = {"seq": 0} if self.ros1 else {}
        return self.T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame, **extra)

    def cloud(self, t: float, points: np.ndarray, layout: str, extra=None, *, fields=None, bigendian=False):
        """A PointCloud2 of ``points`` with ``layout``'s time field holding ``extra``."""
        names = [("x", 7), ("y", 7), ("z", 7)] + LAYOUTS[layout] if fields is None else fields
        dtype = np.dtype([(n, DATATYPES[k]) for n, k in names])
        record = np.zeros(len(points), dtype)
        for axis, name in enumerate("xyz"):
            if name in dtype.names:
                record[name] = points[:, axis]
        for name, _ in LAYOUTS.get(layout, []):
            record[name] = extra
        offsets = [dtype.fields[n][1] for n, _ in names]
        return self.T["sensor_msgs/msg/PointCloud2"](
            header=self.header(t),
            height=1,
            width=len(record),
            fields=[
                self.T["sensor_msgs/msg/PointField"](name=n, offset=o, datatype=k, count=1)
                for (n, k), o in zip(names, offsets)
            ],
            is_bigendian=bigendian,
            point_step=dtype.itemsize,
            row_step=dtype.itemsize * len(record),
            data=np.frombuffer(record.tobytes(), dtype=np.uint8),
            is_dense=False,
        )

    def livox(self, package: str, t: float, points: np.ndarray, offsets: np.ndarray):
        point = self.T[f"{package}/msg/CustomPoint"]
        return self.T[f"{package}/msg/CustomMsg"](
            header=self.header(t),
            timebase=ns(t),
            point_num=len(points),
            lidar_id=0,
            rsvd=np.zeros(3, np.uint8),
            points=[
                point(
                    offset_time=int(o), x=float(p[0]), y=float(p[1]), z=float(p[2]), reflectivity=1, tag=0, line=i % 6
                )
                for i, (p, o) in enumerate(zip(points, offsets))
            ],
        )

    def imu(self, t: float, w, a):
        vector = self.T["geometry_msgs/msg/Vector3"]
        return self.T["sensor_msgs/msg/Imu"](
            header=self.header(t, "imu"),
            orientation=self.T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
            orientation_covariance=np.full(9, -1.0),
            angular_velocity=vector(x=w[0], y=w[1], z=w[2]),
            angular_velocity_covariance=np.zeros(9),
            linear_acceleration=vector(x=a[0], y=a[1], z=a[2]),
            linear_acceleration_covariance=np.zeros(9),
        )

    def pose(self, position, quaternion):
        return self.T["geometry_msgs/msg/Pose"](
            position=self.T["geometry_msgs/msg/Point"](x=position[0], y=position[1], z=position[2]),
            orientation=self.T["geometry_msgs/msg/Quaternion"](
                x=quaternion[0], y=quaternion[1], z=quaternion[2], w=quaternion[3]
            ),
        )

    def odometry(self, t, position, quaternion):
        return self.T["nav_msgs/msg/Odometry"](
            header=self.header(t, "map"),
            child_frame_id="base_link",
            pose=self.T["geometry_msgs/msg/PoseWithCovariance"](
                pose=self.pose(position, quaternion), covariance=np.zeros(36)
            ),
            twist=self.T["geometry_msgs/msg/TwistWithCovariance"](
                twist=self.T["geometry_msgs/msg/Twist"](
                    linear=self.T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
                    angular=self.T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
                ),
                covariance=np.zeros(36),
            ),
        )

    def pose_stamped(self, t, position, quaternion):
        return self.T["geometry_msgs/msg/PoseStamped"](
            header=self.header(t, "map"), pose=self.pose(position, quaternion)
        )

    def path(self, t, stamped):
        return self.T["nav_msgs/msg/Path"](header=self.header(t, "map"), poses=stamped)


def write_bag(path, storage: str, topics: dict[str, str], messages: list[tuple[str, float, object]]):
    """A bag at ``path`` in ``storage`` (ros1, sqlite3, mcap) of ``messages`` (topic,
    log time, message) on ``topics`` ({topic: type})."""
    ros1 = storage == "ros1"
    store = typestore(ros1)
    if ros1:
        writer = Writer1(path)
    else:
        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=8 if storage == "sqlite3" else 9, storage_plugin=plugin)
    with writer:
        connections = {topic: writer.add_connection(topic, kind, typestore=store) for topic, kind in topics.items()}
        for topic, t, msg in sorted(messages, key=lambda m: m[1]):
            kind = topics[topic]
            raw = store.serialize_ros1(msg, kind) if ros1 else store.serialize_cdr(msg, kind)
            writer.write(connections[topic], ns(t), raw)


def bag_path(tmp_path, storage):
    return tmp_path / ("run.bag" if storage == "ros1" else f"run_{storage}")


def truth(seed=0):
    """Scans (points as float32 values, a NaN and an origin point in the second), their
    raw time fields per layout, IMU samples and reference poses."""
    rng = np.random.default_rng(seed)
    points = [rng.normal(0, 5, (40 + 5 * k, 3)).astype(np.float32).astype(np.float64) for k in range(3)]
    points[1][3] = np.nan
    points[1][7] = 0.0
    offsets = [np.sort(rng.integers(0, 99_000_000, len(p))) for p in points]  # ns within the scan
    imu = [(t, rng.normal(0, 1, 3), rng.normal(0, 1, 3)) for t in IMU_TIMES]
    rotations = Rotation.from_rotvec(rng.normal(0, 0.5, (len(POSE_TIMES), 3)))
    poses = [(t, rng.normal(0, 3, 3), q) for t, q in zip(POSE_TIMES, rotations.as_quat())]
    return points, offsets, imu, poses


def time_field(layout: str, t: float, offsets: np.ndarray):
    """What ``layout``'s time field holds for offsets (ns) after stamp ``t``, and the times
    (s, relative to the stamp) the reader must give back."""
    if layout == "ouster":
        return offsets.astype(np.uint32), offsets.astype(np.uint32).astype(np.float64) * 1e-9
    if layout == "velodyne":
        field = (offsets * 1e-9).astype(np.float32)
        return field, field.astype(np.float64)
    if layout == "hesai":
        stamp = seconds(t)
        field = stamp + offsets * 1e-9
        return field, field - stamp
    if layout in ("livox", "livox2"):
        return offsets, offsets * 1e-9
    return None, None


def write_run(tmp_path, storage, layout, pose_kind):
    """A bag of the truth (one scan layout, one pose message type) and the truth."""
    store = typestore(storage == "ros1")
    make = Messages(store, storage == "ros1")
    points, offsets, imu, poses = truth()
    scan_type = f"{LAYOUTS[layout]}/msg/CustomMsg" if layout.startswith("livox") else "sensor_msgs/msg/PointCloud2"
    topics = {"/lidar": scan_type, "/imu": "sensor_msgs/msg/Imu", "/reference": POSE_TYPES[pose_kind]}
    messages, expected_times = [], []
    for t, p, o in zip(SCAN_TIMES, points, offsets):
        field, want = time_field(layout, t, o)
        expected_times.append(want)
        msg = make.livox(LAYOUTS[layout], t, p, o) if layout.startswith("livox") else make.cloud(t, p, layout, field)
        messages.append(("/lidar", t + 10**8, msg))
    messages += [("/imu", t, make.imu(t, w, a)) for t, w, a in imu]
    if pose_kind == "path":
        stamped = [make.pose_stamped(t, p, q) for t, p, q in poses]
        # a path republished as it grows: only the last, whole one counts
        messages += [("/reference", POSE_TIMES[-1] - 10**8, make.path(POSE_TIMES[-1], stamped[:3]))]
        messages += [("/reference", POSE_TIMES[-1], make.path(POSE_TIMES[-1], stamped))]
    else:
        build = make.odometry if pose_kind == "odometry" else make.pose_stamped
        messages += [("/reference", t, build(t, p, q)) for t, p, q in poses]
    path = bag_path(tmp_path, storage)
    write_bag(path, storage, topics, messages)
    return path, points, expected_times, imu, poses


def pose_matrix(position, quaternion) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3] = Rotation.from_quat(quaternion).as_matrix()
    pose[:3, 3] = position
    return pose


CASES = [
    ("ros1", "ouster", "odometry"),
    ("ros1", "livox", "path"),
    ("ros1", "hesai", "pose"),
    ("sqlite3", "velodyne", "pose"),
    ("sqlite3", "livox2", "odometry"),
    ("sqlite3", "none", "path"),
    ("mcap", "hesai", "odometry"),
    ("mcap", "livox", "pose"),
    ("mcap", "ouster", "path"),
    ("mcap", "velodyne", "odometry"),
]


@pytest.mark.parametrize("storage, layout, pose_kind", CASES, ids=["-".join(c) for c in CASES])
def test_a_bag_reads_back_as_written(tmp_path, storage, layout, pose_kind):
    """Points (NaN and origin points dropped), per-point times in each driver's convention,
    stamps, IMU samples and reference poses come back exactly; a scan at a pose's time
    gets that pose times the extrinsic."""
    path, points, times, imu, poses = write_run(tmp_path, storage, layout, pose_kind)
    config = RunConfig(lidar_translation=(0.1, 0.2, 0.3), lidar_rpy=(0.0, 0.0, 90.0))
    with Run(path, config) as run:
        scans = list(run.scans())
        samples = list(run.imu())
        reference = run.reference
        described = run.describe()
    assert described["scans_topic"] == "/lidar" and described["poses_topic"] == "/reference"
    kinds = {"ros1": "ROS 1 bag", "sqlite3": "ROS 2 bag, sqlite3 storage", "mcap": "ROS 2 bag, MCAP storage"}
    assert described["kind"] == kinds[storage]
    assert [s.stamp for s in scans] == [seconds(t) for t in SCAN_TIMES]
    extrinsic = np.array([[0, -1, 0, 0.1], [1, 0, 0, 0.2], [0, 0, 1, 0.3], [0, 0, 0, 1.0]])
    for scan, p, want, t in zip(scans, points, times, SCAN_TIMES):
        keep = np.isfinite(p).all(axis=1) & p.any(axis=1)
        np.testing.assert_array_equal(scan.points, p[keep])
        if want is None:
            assert scan.times is None
        else:
            np.testing.assert_array_equal(scan.times, want[keep])
        np.testing.assert_allclose(scan.pose, pose_matrix(*poses[POSE_TIMES.index(t)][1:]) @ extrinsic, atol=1e-12)
    assert len(scans[1].points) == len(points[1]) - 2
    assert len(samples) == len(imu)
    for sample, (_, w, a) in zip(samples, imu):
        np.testing.assert_array_equal(sample.angular_velocity, w)
        np.testing.assert_array_equal(sample.linear_acceleration, a)
    assert len(reference) == len(poses)
    for pose, (_, position, quaternion) in zip(reference.poses, poses):
        np.testing.assert_array_equal(pose, pose_matrix(position, quaternion))


def test_a_replay_bag_reads_with_its_true_poses(tmp_path):
    """`lf3pm replay --bag`'s ROS 2 folder (named *.bag): its scans with their Velodyne-style
    point times, its IMU and its ground truth (/ground_truth, the sensor's pose: the bag's
    extrinsics are identity) come back as written."""
    from types import SimpleNamespace

    from analytic_scenes import grid_plane

    import lf3pm
    from lf3pm.replays.bag import write_bag as write_replay_bag
    from lf3pm.replays.motion import Motion
    from lf3pm.scan.scans import ScanStream
    from lf3pm.sensors import get_sensor

    pts = np.vstack(
        [
            grid_plane((-10, -10, 0), (1, 0, 0), (0, 1, 0), 20, 20, 0.25),
            grid_plane((6, -10, 0.1), (0, 1, 0), (0, 0, 1), 20, 3, 0.25),
        ]
    )
    world = lf3pm.load_map(np.ascontiguousarray(pts))
    t = np.linspace(0.0, 0.5, 51)
    motion = Motion.from_arrays(t, t, 0 * t, 0.2 * t, np.ones_like(t), 0 * t, np.full_like(t, 0.2), map=world)
    stream = ScanStream(world, motion, get_sensor("vlp16"), rate=10.0, seed=2)
    imu_t = np.arange(0.0, 0.5 + 1e-9, 0.01)
    imu = SimpleNamespace(t=imu_t, accel=np.tile([0.0, 0.0, 9.81], (len(imu_t), 1)), gyro=np.zeros((len(imu_t), 3)))
    path = tmp_path / "out.bag"
    info = write_replay_bag(path, stream, imu, truth_rate=100.0)
    offset = info["clock_offset_s"]
    with Run(path, skip_bad=True) as run:
        described = run.describe()
        scans = list(run.scans())
        samples = list(run.imu())
        reference = run.reference
        (bad,) = run.bad_scans
    assert described["kind"] == "ROS 2 bag, sqlite3 storage"
    assert (described["scans_topic"], described["imu_topic"], described["poses_topic"]) == (
        "/points",
        "/imu",
        "/ground_truth",
    )
    # The first scan begins (its stamp) a period before the trajectory and its truth do.
    assert bad.index == 0 and bad.reason.startswith("/points message 0: no pose at 1.000000 s: /ground_truth span")
    assert len(scans) == len(stream) - 1 and len(samples) == len(imu_t) and len(reference) == 51
    for scan in scans:
        simulated = stream[scan.index]
        begin = simulated.end - simulated.period
        np.testing.assert_array_equal(scan.points, simulated.points.astype(np.float32).astype(np.float64))
        np.testing.assert_allclose(scan.times, simulated.stamps - begin, rtol=0, atol=1e-6)  # float32 s
        assert scan.stamp == pytest.approx(begin + offset, abs=1e-9)
        np.testing.assert_allclose(scan.pose, motion.pose(begin)[0], rtol=0, atol=1e-9)  # a truth sample's time
    np.testing.assert_allclose(reference.times - offset, np.linspace(0.0, 0.5, 51), atol=1e-9)
    np.testing.assert_allclose(reference.poses[:, :3, 3], motion.position(reference.times - offset), atol=1e-9)


def _bad_run(tmp_path, scans: dict, storage="mcap"):
    """A bag whose /lidar messages are ``scans`` (time -> message) with poses over 10.0-10.5 s."""
    store = typestore(storage == "ros1")
    make = Messages(store, storage == "ros1")
    messages = [("/lidar", t, msg(make, t)) for t, msg in scans.items()]
    messages += [("/odom", 10 + k * 0.1, make.odometry(10 + k * 0.1, (k, 0, 0), (0, 0, 0, 1))) for k in range(6)]
    path = bag_path(tmp_path, storage)
    write_bag(path, storage, {"/lidar": "sensor_msgs/msg/PointCloud2", "/odom": "nav_msgs/msg/Odometry"}, messages)
    return path


def _cloud(n=10, **kwargs):
    return lambda make, t: make.cloud(t, np.ones((n, 3)), "none", **kwargs)


def test_bad_scans_are_one_line_each_and_skipped_on_request(tmp_path):
    """No field z, big-endian, NaN-only, empty, outside the poses, a stamp going back: each
    scan stops the run with its line, or with skip_bad is kept with it and the run goes on."""
    nan_only = lambda make, t: make.cloud(t, np.full((4, 3), np.nan), "none")  # noqa: E731
    scans = {
        10.05: _cloud(),
        10.1: _cloud(fields=[("x", 7), ("y", 7), ("intensity", 7)]),
        10.15: _cloud(bigendian=True),
        10.2: nan_only,
        10.25: _cloud(n=0),
        10.3: _cloud(),
        10.7: _cloud(),
    }
    path = _bad_run(tmp_path, scans)
    with Run(path, skip_bad=True) as run:
        good = [s.stamp for s in run.scans()]
        reasons = [b.reason for b in run.bad_scans]
    assert good == pytest.approx([10.05, 10.3], abs=1e-9)
    expected = [
        "/lidar message 1: the PointCloud2 has no field z (its fields: x, y, intensity)",
        "/lidar message 2: a big-endian PointCloud2",
        "/lidar message 3: no usable point (all 4 are NaN or at the origin)",
        "/lidar message 4: no usable point (it holds none)",
        "/lidar message 6: no pose at 10.700000 s",
    ]
    assert len(reasons) == len(expected)
    for reason, start in zip(reasons, expected):
        assert reason.startswith(start) and "\n" not in reason
    with Run(path) as run, pytest.raises(RunError, match="message 1: the PointCloud2 has no field z"):
        list(run.scans())


def test_a_stamp_going_back_is_a_bad_scan(tmp_path):
    make_early = lambda make, t: make.cloud(t - 0.2, np.ones((3, 3)), "none")  # noqa: E731
    path = _bad_run(tmp_path, {10.1: _cloud(), 10.2: _cloud(), 10.3: make_early})
    with Run(path, skip_bad=True) as run:
        assert len(list(run.scans())) == 2
        (bad,) = run.bad_scans
    assert bad.reason.startswith("/lidar message 2: stamp 10.100000000 s is not after the previous scan's 10.2")


def test_a_long_gap_in_the_poses_is_no_pose(tmp_path):
    path = _bad_run(tmp_path, {10.25: _cloud()})
    with (
        Run(path, RunConfig(max_pose_gap=0.05)) as run,
        pytest.raises(
            RunError, match="no pose from 10.200000 to 10.300000 s, 0.100 s, longer than max_pose_gap 0.05 s"
        ),
    ):
        next(run.scans())


def test_topics_are_chosen_by_name_or_by_being_the_only_one(tmp_path):
    store = typestore(False)
    make = Messages(store, False)
    path = tmp_path / "two"
    cloud = make.cloud(10.0, np.ones((3, 3)), "none")
    write_bag(
        path,
        "mcap",
        {"/a": "sensor_msgs/msg/PointCloud2", "/b": "sensor_msgs/msg/PointCloud2", "/imu": "sensor_msgs/msg/Imu"},
        [("/a", 10.0, cloud), ("/b", 10.0, cloud)],
    )
    with pytest.raises(RunError, match=r"2 scans topics, /a \(sensor_msgs/msg/PointCloud2\), /b .*--scans-topic"):
        Run(path)
    with pytest.raises(RunError, match=r"no topic /c; its topics: /a .*, /b .*, /imu \(sensor_msgs/msg/Imu\)"):
        Run(path, RunConfig(scans_topic="/c"))
    with pytest.raises(RunError, match="/imu is a sensor_msgs/msg/Imu, not a sensor_msgs/msg/PointCloud2"):
        Run(path, RunConfig(scans_topic="/imu"))
    with Run(path, RunConfig(scans_topic="/b")) as run:
        assert run.describe()["scans_topic"] == "/b" and run.reference is None
        assert len(list(run.scans())) == 1 and list(run.imu()) == []


def test_iterating_a_bag_holds_a_few_scans_at_most(tmp_path):
    """Peak memory while reading 60 scans of 20,000 points stays under ten scans' worth (a
    scan's message, its decoding and the storage's chunk), a sixth of the run."""
    import tracemalloc

    store = typestore(False)
    make = Messages(store, False)
    rng = np.random.default_rng(0)
    points = rng.normal(0, 5, (20_000, 3))
    offsets = rng.random(20_000).astype(np.float32)
    path = tmp_path / "long"
    write_bag(
        path,
        "mcap",
        {"/lidar": "sensor_msgs/msg/PointCloud2"},
        [("/lidar", 10 + 0.1 * k, make.cloud(10 + 0.1 * k, points, "velodyne", offsets)) for k in range(60)],
    )
    scan_bytes = 20_000 * 4 * 8  # float64 points and times
    with Run(path) as run:
        tracemalloc.start()
        count = sum(1 for _ in run.scans())
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    assert count == 60 and peak < 10 * scan_bytes, peak


def test_poses_going_back_in_time_fail_the_run(tmp_path):
    """A pose topic out of order is no run (even skipping bad scans): one line naming the message."""
    make = Messages(typestore(False), False)
    path = tmp_path / "back"
    messages = [("/lidar", 10.1, make.cloud(10.1, np.ones((3, 3)), "none"))]
    messages += [
        ("/pose", 10 + k * 0.1, make.pose_stamped(t, (0, 0, 0), (0, 0, 0, 1))) for k, t in enumerate((10.0, 10.2, 10.1))
    ]
    write_bag(
        path, "mcap", {"/lidar": "sensor_msgs/msg/PointCloud2", "/pose": "geometry_msgs/msg/PoseStamped"}, messages
    )
    with (
        Run(path, skip_bad=True) as run,
        pytest.raises(RunError, match=r"^/pose message 2: stamp 10.100000000 s is not after"),
    ):
        list(run.scans())


def test_run_info_on_a_bag(tmp_path):
    """`lf3pm run info --json` on a ROS 2 bag: every topic with its type and count, the ones
    read, the scans' points and span, per-point times, the IMU's rate and the poses' span."""
    from typer.testing import CliRunner

    from lf3pm.cli import app

    path, points, *_ = write_run(tmp_path, "sqlite3", "ouster", "odometry")
    done = CliRunner().invoke(app, ["run", "info", str(path), "--json"])
    assert done.exit_code == 0, done.output
    info = json.loads(done.output)
    assert info["source"]["topics"] == {
        "/imu": {"type": "sensor_msgs/msg/Imu", "messages": 80},
        "/lidar": {"type": "sensor_msgs/msg/PointCloud2", "messages": 3},
        "/reference": {"type": "nav_msgs/msg/Odometry", "messages": 9},
    }
    assert info["source"]["kind"] == "ROS 2 bag, sqlite3 storage"
    assert info["scans"] == 3 and info["points_per_scan"] == {"min": 40, "median": 43.0, "max": 50}
    assert info["point_times"] == "all" and info["scans_span"]["duration_s"] == pytest.approx(0.2, abs=1e-6)
    assert info["imu"]["samples"] == 80 and info["imu"]["rate_hz"] == pytest.approx(200.0, rel=1e-6)
    assert info["poses"]["count"] == 9 and info["poses"]["span"]["duration_s"] == pytest.approx(0.4, abs=1e-6)
    unknown = CliRunner().invoke(app, ["run", "info", str(path), "--imu-topic", "/nope"])
    assert unknown.exit_code == 2 and "no topic /nope; its topics: /imu (sensor_msgs/msg/Imu)" in unknown.output


def test_a_file_that_is_no_bag_fails_in_one_line(tmp_path):
    (tmp_path / "broken.bag").write_bytes(b"#ROSBAG V2.0\nnot a bag")
    with pytest.raises(RunError, match=r"broken.bag: not a readable bag \(") as err:
        Run(tmp_path / "broken.bag")
    assert "\n" not in str(err.value)


def test_a_bag_without_message_definitions_reads_with_the_shipped_ones(tmp_path):
    """A ROS 2 sqlite3 bag recorded without message definitions (Humble's) is read with
    Humble's types and the Livox definitions shipped in lf3pm.runs: the same scans and poses."""
    import sqlite3

    path, points, times, _, poses = write_run(tmp_path, "sqlite3", "livox2", "odometry")
    with Run(path) as run:
        before = [(s.points, s.times, s.pose) for s in run.scans()]
    database = sqlite3.connect(next(path.glob("*.db3")))
    database.execute("DELETE FROM message_definitions")
    database.commit()
    database.close()
    with Run(path) as run:
        after = [(s.points, s.times, s.pose) for s in run.scans()]
    assert len(after) == len(before) == 3
    for got, want in zip(after, before):
        for a, b in zip(got, want):
            np.testing.assert_array_equal(a, b)


def test_an_organised_cloud_with_padded_rows_reads_row_by_row():
    """height 2, each row padded by 8 bytes past its points: the rows' points, in order."""
    from types import SimpleNamespace

    from lf3pm.runs.pointcloud2 import decode_pointcloud2

    grid = np.arange(2 * 3 * 3, dtype=np.float32).reshape(2, 3, 3)
    rows = [row.tobytes() + bytes(8) for row in grid]
    field = lambda name, offset: SimpleNamespace(name=name, offset=offset, datatype=7, count=1)  # noqa: E731
    msg = SimpleNamespace(
        header=SimpleNamespace(stamp=SimpleNamespace(sec=5, nanosec=0)),
        height=2,
        width=3,
        fields=[field("x", 0), field("y", 4), field("z", 8)],
        is_bigendian=False,
        point_step=12,
        row_step=44,
        data=np.frombuffer(b"".join(rows), np.uint8),
    )
    stamp, points, times = decode_pointcloud2(msg, "organised")
    assert stamp == 5.0 and times is None
    np.testing.assert_array_equal(points, grid.reshape(-1, 3))
