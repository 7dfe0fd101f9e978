"""The replayed sensor stream as a ROS 2 bag (written with the ``rosbags``
package), so that FAST-LIO2 or any ROS odometry runs on exactly what lf3pm
replayed.

Layout (docs/replay.md):

- storage sqlite3, rosbag2 format version 8: sqlite3 is the storage every
  ROS 2 distribution reads without an extra plugin (Humble's default; MCAP
  needs ``rosbag2_storage_mcap`` there), and version 8 is the oldest rosbags
  writes, the closest to what Humble expects;
- ``/points`` sensor_msgs/PointCloud2, frame ``lidar``, one message per scan:
  each return in the sensor frame of its own firing time (the motion-distorted
  scan a driver publishes), header stamp = the scan's start (end - period),
  per-point time relative to it, message logged at the scan's end. Fields in
  the convention FAST-LIO2's preprocess reads for the sensor type:
  Velodyne-style (x y z intensity float32, ring uint16, time float32 seconds;
  FAST-LIO ``lidar_type: 2``, ``timestamp_unit: 0``) for spinning sensors and
  for Livox sensors (ring 0: FAST-LIO reads Livox's own CustomMsg, not a
  PointCloud2, so these go through its Velodyne handler, which needs no ring
  once times are given); Ouster-style (x y z intensity float32, t uint32 ns,
  reflectivity uint16, ring uint8, ambient uint16, range uint32 mm;
  ``lidar_type: 3``, ``timestamp_unit: 3``) for the OS1. Ring 0 is the lowest
  beam. No reflectance is simulated: intensity is a constant.
- ``/imu`` sensor_msgs/Imu, frame ``imu``: angular velocity (rad/s) and
  specific force (m/s^2) as simulated; no orientation (covariance[0] = -1, as
  REP 145 says for an IMU without one);
- ``/ground_truth`` nav_msgs/Odometry, frame ``map``, child ``base_link``: the
  true sensor pose and its twist in the body frame, at ``truth_rate`` Hz;
- ``/tf`` map -> base_link at the same times; ``/tf_static`` (transient-local
  durability, so a late subscriber gets it) base_link -> lidar and
  base_link -> imu, both identity (sensor frame = body frame = IMU frame).

Clock: ROS time = t - (earliest time in the bag) + 1 s, so that the bag starts
at 1 s (scan 0 begins one period before the trajectory does; ROS reads a zero
stamp as "no time"). The offset is stored in the bag's custom data
(``lf3pm_clock_offset_s``).
"""

from __future__ import annotations

import math
import numbers
import os
import secrets
import shutil
import sqlite3

import numpy as np

from lf3pm.errors import Lf3pmError, StorageError
from lf3pm.sensors import Sensor, spinning_rings

#: Ground truth rate (Hz): the planner's CSV rate.
TRUTH_RATE = 100.0
INTENSITY = 100.0
FRAMES = {"world": "map", "body": "base_link", "lidar": "lidar", "imu": "imu"}
_FLOAT32, _UINT8, _UINT16, _UINT32 = 7, 2, 4, 6
_NUMPY = {_FLOAT32: "<f4", _UINT8: "u1", _UINT16: "<u2", _UINT32: "<u4"}


def point_layout(sensor: Sensor) -> str:
    """ "ouster" for Ouster sensors, else "velodyne" (module docstring)."""
    return "ouster" if sensor.name.lower().startswith("os") and spinning_rings(sensor) is not None else "velodyne"


def _fields(layout: str) -> list[tuple[str, int]]:
    if layout == "ouster":
        return [
            ("x", _FLOAT32),
            ("y", _FLOAT32),
            ("z", _FLOAT32),
            ("intensity", _FLOAT32),
            ("t", _UINT32),
            ("reflectivity", _UINT16),
            ("ring", _UINT8),
            ("ambient", _UINT16),
            ("range", _UINT32),
        ]
    return [
        ("x", _FLOAT32),
        ("y", _FLOAT32),
        ("z", _FLOAT32),
        ("intensity", _FLOAT32),
        ("ring", _UINT16),
        ("time", _FLOAT32),
    ]


def cloud_dtype(layout: str) -> np.dtype:
    """The packed little-endian point record of ``layout``."""
    return np.dtype([(name, _NUMPY[kind]) for name, kind in _fields(layout)])


def write_bag(path, scans, imu, *, truth_rate: float = TRUTH_RATE, progress=None) -> dict:
    """Writes ``scans`` (a ScanStream: its motion gives the ground truth) and
    ``imu`` (ImuSamples: t, accel, gyro) as a ROS 2 bag directory at ``path``
    (module docstring). The bag is written next to ``path`` and renamed into
    place when complete; an existing ``path`` is never replaced. Returns the
    message count per topic and the clock offset. A storage fault while writing (a full
    disk, an I/O error, the folder gone) is a one-line StorageError; nothing of the bag
    is left behind."""
    from rosbags.interfaces import (
        Qos,
        QosDurability,
        QosHistory,
        QosLiveliness,
        QosReliability,
        QosTime,
    )
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.rosbag2.errors import WriterError
    from rosbags.typesys import Stores, get_typestore

    if not isinstance(path, (str, os.PathLike)):
        raise Lf3pmError(f"a bag is written to a path, got {type(path).__name__}")
    path = os.path.abspath(os.fspath(path))
    if os.path.lexists(path):
        raise Lf3pmError(f"{path} exists: a bag is a new directory and lf3pm replaces nothing there")
    if not (isinstance(truth_rate, numbers.Real) and math.isfinite(truth_rate) and truth_rate > 0):
        raise Lf3pmError(f"the ground truth rate must be > 0 Hz, got {truth_rate!r}")
    parent = os.path.dirname(path)
    if not os.path.isdir(parent):
        raise Lf3pmError(f"{path}: the folder {parent} does not exist")
    motion, sensor = scans.motion, scans.sensor
    truth_times = motion.t0 + np.arange(math.floor((motion.t1 - motion.t0) * truth_rate + 1e-9) + 1) / truth_rate
    imu_t = np.asarray(imu.t, dtype=np.float64)
    earliest = min(scans.times[0] - scans.period, truth_times[0], imu_t[0] if len(imu_t) else math.inf)
    offset = 1.0 - earliest
    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    layout = point_layout(sensor)
    rings = spinning_rings(sensor)
    # Written in a private folder under the bag's own name (its files are named after
    # it), then moved into place.
    workdir = os.path.join(parent, f".{os.path.basename(path)}.{secrets.token_hex(4)}.tmp")
    temporary = os.path.join(workdir, os.path.basename(path))
    counts = {"/points": 0, "/imu": 0, "/ground_truth": 0, "/tf": 0, "/tf_static": 0}

    def stamp(t: float):
        ns = round((t + offset) * 1e9)
        return ns, T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)

    def header(t: float, frame: str):
        ns, s = stamp(t)
        return ns, T["std_msgs/msg/Header"](stamp=s, frame_id=frame)

    def vec(v):
        return T["geometry_msgs/msg/Vector3"](x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def quat_yaw(yaw):
        return T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))

    identity = T["geometry_msgs/msg/Transform"](translation=vec((0, 0, 0)), rotation=quat_yaw(0.0))
    latched = Qos(
        QosHistory.KEEP_LAST,
        1,
        QosReliability.RELIABLE,
        QosDurability.TRANSIENT_LOCAL,
        QosTime(0, 0),
        QosTime(0, 0),
        QosLiveliness.AUTOMATIC,
        QosTime(0, 0),
        False,
    )
    try:
        os.mkdir(workdir)
        writer = Writer(temporary, version=8, storage_plugin=StoragePlugin.SQLITE3)
        writer.open()
        try:
            conn = {
                topic: writer.add_connection(
                    topic, kind, typestore=ts, **({"offered_qos_profiles": [latched]} if topic == "/tf_static" else {})
                )
                for topic, kind in (
                    ("/points", "sensor_msgs/msg/PointCloud2"),
                    ("/imu", "sensor_msgs/msg/Imu"),
                    ("/ground_truth", "nav_msgs/msg/Odometry"),
                    ("/tf", "tf2_msgs/msg/TFMessage"),
                    ("/tf_static", "tf2_msgs/msg/TFMessage"),
                )
            }

            def put(topic, ns, msg):
                writer.write(conn[topic], ns, ts.serialize_cdr(msg, msg.__msgtype__))
                counts[topic] += 1

            ns, h = header(earliest, FRAMES["body"])
            static = [
                T["geometry_msgs/msg/TransformStamped"](header=h, child_frame_id=FRAMES[c], transform=identity)
                for c in ("lidar", "imu")
            ]
            put("/tf_static", ns, T["tf2_msgs/msg/TFMessage"](transforms=static))

            fields = [
                T["sensor_msgs/msg/PointField"](name=n, offset=o, datatype=k, count=1)
                for (n, k), o in zip(
                    _fields(layout),
                    np.cumsum([0] + [np.dtype(_NUMPY[k]).itemsize for _, k in _fields(layout)])[:-1].tolist(),
                )
            ]
            dtype = cloud_dtype(layout)
            for k in range(len(scans)):
                scan = scans[k]
                begin = scan.end - scan.period
                record = np.zeros(len(scan.points), dtype)
                for axis, name in enumerate("xyz"):
                    record[name] = scan.points[:, axis]
                record["intensity"] = INTENSITY
                ring = rings[scan.ray] if rings is not None else 0
                offset_s = scan.stamps - begin
                if layout == "ouster":
                    record["t"] = np.round(offset_s * 1e9).astype(np.uint32)
                    record["ring"] = ring
                    record["range"] = np.round(np.linalg.norm(scan.points, axis=1) * 1e3).astype(np.uint32)
                else:
                    record["time"] = offset_s
                    record["ring"] = ring
                _, h = header(begin, FRAMES["lidar"])
                msg = T["sensor_msgs/msg/PointCloud2"](
                    header=h,
                    height=1,
                    width=len(record),
                    fields=fields,
                    is_bigendian=False,
                    point_step=dtype.itemsize,
                    row_step=dtype.itemsize * len(record),
                    data=np.frombuffer(record.tobytes(), dtype=np.uint8),
                    is_dense=True,
                )
                put("/points", stamp(scan.end)[0], msg)
                if progress is not None:
                    progress(k + 1, len(scans))

            unknown = np.zeros(9)
            unknown[0] = -1.0
            for t, a, g in zip(imu_t, np.asarray(imu.accel, float), np.asarray(imu.gyro, float)):
                ns, h = header(t, FRAMES["imu"])
                put(
                    "/imu",
                    ns,
                    T["sensor_msgs/msg/Imu"](
                        header=h,
                        orientation=quat_yaw(0.0),
                        orientation_covariance=unknown,
                        angular_velocity=vec(g),
                        angular_velocity_covariance=np.zeros(9),
                        linear_acceleration=vec(a),
                        linear_acceleration_covariance=np.zeros(9),
                    ),
                )

            position, velocity = motion.position(truth_times), motion.velocity(truth_times)
            yaw, rate = motion.yaw(truth_times), motion.yaw_rate(truth_times)
            for t, p, v, psi, w in zip(truth_times, position, velocity, yaw, rate):
                ns, h = header(t, FRAMES["world"])
                c, s = math.cos(psi), math.sin(psi)
                body_v = (c * v[0] + s * v[1], -s * v[0] + c * v[1], v[2])
                pose = T["geometry_msgs/msg/Pose"](
                    position=T["geometry_msgs/msg/Point"](x=float(p[0]), y=float(p[1]), z=float(p[2])),
                    orientation=quat_yaw(psi),
                )
                put(
                    "/ground_truth",
                    ns,
                    T["nav_msgs/msg/Odometry"](
                        header=h,
                        child_frame_id=FRAMES["body"],
                        pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
                        twist=T["geometry_msgs/msg/TwistWithCovariance"](
                            twist=T["geometry_msgs/msg/Twist"](linear=vec(body_v), angular=vec((0.0, 0.0, w))),
                            covariance=np.zeros(36),
                        ),
                    ),
                )
                moved = T["geometry_msgs/msg/Transform"](translation=vec(p), rotation=quat_yaw(psi))
                put(
                    "/tf",
                    ns,
                    T["tf2_msgs/msg/TFMessage"](
                        transforms=[
                            T["geometry_msgs/msg/TransformStamped"](
                                header=h, child_frame_id=FRAMES["body"], transform=moved
                            )
                        ]
                    ),
                )
            writer.set_custom_data("lf3pm_clock_offset_s", repr(float(offset)))
            writer.set_custom_data("lf3pm_point_layout", layout)
        finally:
            writer.close()
        os.rename(temporary, path)
    except (OSError, sqlite3.Error, WriterError) as err:
        # sqlite reports a full disk as its own error ("database or disk is full").
        cause = (getattr(err, "strerror", None) or str(err) or err.__class__.__name__).splitlines()[0]
        raise StorageError(
            f"{path}: cannot write the bag ({cause}); no bag is kept (its partial folder is "
            "removed): free space or fix the storage, then run the replay with --bag again"
        ) from None
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    return {
        "topics": counts,
        "clock_offset_s": float(offset),
        "point_layout": layout,
        "storage": "sqlite3",
        "version": 8,
    }
