"""Livox's own scan message, livox_ros_driver/CustomMsg and livox_ros_driver2/CustomMsg:
their definitions (shipped in ``msg/``, written from the drivers' public field lists) and
their decoding."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np

from lf3pm.runs.pointcloud2 import stamp_seconds

#: The ROS packages that define CustomMsg, each with its own copy of the same fields.
PACKAGES = ("livox_ros_driver", "livox_ros_driver2")
MESSAGES = tuple(f"{package}/msg/CustomMsg" for package in PACKAGES)
_MSG = Path(__file__).with_name("msg")


@cache
def livox_types() -> dict:
    """The rosbags type definitions of both packages' CustomMsg and CustomPoint, for
    ``Typestore.register``."""
    from rosbags.typesys import get_types_from_msg

    types = {}
    for package in PACKAGES:
        for message in ("CustomPoint", "CustomMsg"):
            text = (_MSG / package / f"{message}.msg").read_text(encoding="utf-8")
            types.update(get_types_from_msg(text, f"{package}/msg/{message}"))
    return types


def decode_custom_msg(msg) -> tuple[float, np.ndarray, np.ndarray]:
    """(stamp (s), points N x 3 float64, per-point times (s) relative to the stamp) of a
    CustomMsg: a point's time is the timebase plus its offset_time (ns)."""
    stamp_ns = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
    count = len(msg.points)
    points = np.fromiter((v for p in msg.points for v in (p.x, p.y, p.z)), dtype=np.float32, count=3 * count).reshape(
        count, 3
    )
    offsets = np.fromiter((p.offset_time for p in msg.points), dtype=np.int64, count=count)
    # In integer ns first: a float64 of an absolute time in ns keeps only 0.25 us.
    times = (offsets + (int(msg.timebase) - stamp_ns)).astype(np.float64) * 1e-9
    return stamp_seconds(msg.header.stamp), points.astype(np.float64), times
