"""A run recorded as a ROS 1 bag or a ROS 2 bag (sqlite3 or MCAP storage), read with the
``rosbags`` package one message at a time."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from lf3pm.errors import RunError
from lf3pm.runs.livox import MESSAGES as LIVOX_MESSAGES
from lf3pm.runs.livox import decode_custom_msg, livox_types
from lf3pm.runs.pointcloud2 import decode_pointcloud2, stamp_seconds
from lf3pm.runs.records import ImuSample

POINTCLOUD2 = "sensor_msgs/msg/PointCloud2"
#: The message types each stream is read from.
SCAN_TYPES = (POINTCLOUD2, *LIVOX_MESSAGES)
IMU_TYPES = ("sensor_msgs/msg/Imu",)
POSE_TYPES = ("nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseStamped", "nav_msgs/msg/Path")

#: |q| of a recorded pose may differ from 1 by this much.
_UNIT_TOLERANCE = 1e-3


def is_bag(path) -> bool:
    """Whether ``path`` is a ROS 1 bag (a .bag file) or a ROS 2 bag (a folder with metadata.yaml)."""
    path = Path(path)
    return (path.is_file() and path.suffix == ".bag") or (path.is_dir() and (path / "metadata.yaml").is_file())


def _any_reader(path: Path, typestore):
    """rosbags' AnyReader of the bag ``path``, not yet open. AnyReader takes a path ending in
    .bag for ROS 1, but `lf3pm replay --bag out.bag` writes a ROS 2 folder so named: a
    folder is made a ROS 2 reader here as AnyReader.__init__ would (rosbags is pinned)."""
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    if not (path.is_dir() and path.suffix == ".bag"):
        return AnyReader([path], default_typestore=typestore)
    reader = AnyReader.__new__(AnyReader)
    reader.paths, reader.is2, reader.stack, reader.connections = [path], True, None, []
    reader.default_typestore, reader.typestore = typestore, get_typestore(Stores.EMPTY)
    reader.readers = [Reader(path)]
    return reader


class BagSource:
    """A bag's scans, IMU and reference poses, each from its topic: the one given by name,
    or with none given the one topic of the stream's types (SCAN_TYPES, IMU_TYPES,
    POSE_TYPES; no IMU or pose topic is no IMU or no poses). Close it when done."""

    def __init__(self, path, scans_topic: str | None, imu_topic: str | None, poses_topic: str | None):
        from rosbags.highlevel import AnyReaderError
        from rosbags.highlevel.anyreader import ReaderErrors
        from rosbags.typesys import Stores, get_typestore

        self.path = Path(path)
        # A bag recorded without message definitions (ROS 2 Humble's sqlite3 bags) is read
        # with Humble's types and Livox's.
        typestore = get_typestore(Stores.ROS2_HUMBLE)
        typestore.register(livox_types())
        try:
            self._reader = _any_reader(self.path, typestore)
            self._reader.open()
        except (AnyReaderError, *ReaderErrors, OSError, ValueError, KeyError) as err:
            raise RunError(
                f"{self.path}: not a readable bag ({str(err).splitlines()[0] if str(err) else err!r})"
            ) from None
        self.topics = {name: (info.msgtype, info.msgcount) for name, info in sorted(self._reader.topics.items())}
        self.kind = f"ROS 2 bag, {self._storage()} storage" if self.path.is_dir() else "ROS 1 bag"
        try:
            self.scans_topic = self._topic(scans_topic, SCAN_TYPES, "scans", required=True)
            self.imu_topic = self._topic(imu_topic, IMU_TYPES, "imu", required=False)
            self.poses_topic = self._topic(poses_topic, POSE_TYPES, "poses", required=False)
        except RunError:
            self.close()
            raise

    def _storage(self) -> str:
        files = {p.suffix for p in self.path.iterdir()}
        return "MCAP" if ".mcap" in files else "sqlite3" if ".db3" in files else "unknown"

    def close(self) -> None:
        self._reader.close()

    def _listing(self, names) -> str:
        return ", ".join(f"{name} ({self.topics[name][0]})" for name in names) or "none"

    def _topic(self, given: str | None, types: tuple[str, ...], what: str, required: bool) -> str | None:
        if given is not None:
            if given not in self.topics:
                raise RunError(f"{self.path}: no topic {given}; its topics: {self._listing(self.topics)}")
            if self.topics[given][0] not in types:
                raise RunError(f"{self.path}: {given} is a {self.topics[given][0]}, not a {' or '.join(types)}")
            return given
        found = [name for name, (kind, _) in self.topics.items() if kind in types]
        if len(found) > 1:
            raise RunError(
                f"{self.path}: {len(found)} {what} topics, {self._listing(found)}; choose one (--{what}-topic)"
            )
        if not found and required:
            raise RunError(
                f"{self.path}: no {what} topic ({' or '.join(types)}); its topics: {self._listing(self.topics)}"
            )
        return found[0] if found else None

    def describe(self) -> dict:
        """The bag's kind, every topic's type and message count, and the topics read."""
        return {
            "kind": self.kind,
            "topics": {name: {"type": kind, "messages": count} for name, (kind, count) in self.topics.items()},
            "scans_topic": self.scans_topic,
            "imu_topic": self.imu_topic,
            "poses_topic": self.poses_topic,
        }

    def scan_names(self) -> list[str]:
        """The name each scan message has (:meth:`_messages`), without reading them."""
        return [message_name(self.scans_topic, i) for i in range(self.topics[self.scans_topic][1])]

    def _messages(self, topic: str) -> Iterator[tuple[int, str, object]]:
        """(index, "topic message i", message) of ``topic`` in the bag's order; a message that
        does not deserialize is a RunError in its place."""
        from rosbags.highlevel import AnyReaderError

        connections = [c for c in self._reader.connections if c.topic == topic]
        for index, (connection, _, raw) in enumerate(self._reader.messages(connections=connections)):
            name = message_name(topic, index)
            try:
                yield index, name, self._reader.deserialize(raw, connection.msgtype)
            except (AnyReaderError, ValueError, IndexError, KeyError) as err:
                yield index, name, RunError(f"{name}: does not deserialize as {connection.msgtype} ({err})")

    def raw_scans(self) -> Iterator[tuple[int, str, tuple | RunError]]:
        """(index, name, (stamp, points, times) or the RunError that scan is) per scan message."""
        kind = self.topics[self.scans_topic][0]
        for index, name, msg in self._messages(self.scans_topic):
            if isinstance(msg, RunError):
                yield index, name, msg
                continue
            try:
                yield index, name, decode_pointcloud2(msg, name) if kind == POINTCLOUD2 else decode_custom_msg(msg)
            except RunError as err:
                yield index, name, err

    def imu(self) -> Iterator[ImuSample]:
        """The IMU's samples; RunError for a message that does not deserialize or goes back in time."""
        if self.imu_topic is None:
            return
        previous = -np.inf
        for _, name, msg in self._messages(self.imu_topic):
            if isinstance(msg, RunError):
                raise msg
            stamp = stamp_seconds(msg.header.stamp)
            if stamp < previous:
                raise RunError(f"{name}: stamp {stamp:.9f} s is before the previous sample's {previous:.9f} s")
            previous = stamp
            w, a = msg.angular_velocity, msg.linear_acceleration
            yield ImuSample(stamp, np.array([w.x, w.y, w.z]), np.array([a.x, a.y, a.z]))

    def poses(self) -> tuple[np.ndarray, np.ndarray, str] | None:
        """(times, world-from-body poses N x 4 x 4, topic) of the poses topic, or None.
        Odometry gives its pose (the child frame's in the header's), PoseStamped its pose,
        a Path the poses of its last message (a path is republished whole as it grows)."""
        if self.poses_topic is None:
            return None
        kind = self.topics[self.poses_topic][0]
        stamped = []  # (stamp, pose message, name)
        for _, name, msg in self._messages(self.poses_topic):
            if isinstance(msg, RunError):
                raise msg
            if kind == "nav_msgs/msg/Path":
                stamped = [(p.header.stamp, p.pose, f"{name} pose {i}") for i, p in enumerate(msg.poses)]
            else:
                stamped.append((msg.header.stamp, msg.pose.pose if kind.endswith("Odometry") else msg.pose, name))
        if not stamped:
            raise RunError(f"{self.path}: {self.poses_topic} holds no poses")
        times = np.array([stamp_seconds(s) for s, _, _ in stamped])
        poses = np.tile(np.eye(4), (len(stamped), 1, 1))
        quaternions = np.array(
            [[p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w] for _, p, _ in stamped]
        )
        for (_, _, name), q in zip(stamped, quaternions):
            if abs(np.linalg.norm(q) - 1.0) > _UNIT_TOLERANCE:
                raise RunError(f"{name}: the orientation's norm is {np.linalg.norm(q):.6g}, not 1")
        from scipy.spatial.transform import Rotation

        poses[:, :3, :3] = Rotation.from_quat(quaternions).as_matrix()
        poses[:, :3, 3] = [[p.position.x, p.position.y, p.position.z] for _, p, _ in stamped]
        steps = np.flatnonzero(np.diff(times) <= 0)
        if steps.size:
            i = int(steps[0]) + 1
            raise RunError(
                f"{stamped[i][2]}: stamp {times[i]:.9f} s is not after the previous pose's {times[i - 1]:.9f} s"
            )
        return times, poses, self.poses_topic


def message_name(topic: str, index: int) -> str:
    """How a run names the ``index``-th message of ``topic`` (in errors, bad scans, audits)."""
    return f"{topic} message {index}"
