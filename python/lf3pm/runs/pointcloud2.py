"""sensor_msgs/PointCloud2 decoded with NumPy from its fields, offsets and point step."""

from __future__ import annotations

import numpy as np

from lf3pm.errors import RunError

#: PointField datatypes (sensor_msgs/PointField constants) as little-endian NumPy types.
DATATYPES = {1: "i1", 2: "u1", 3: "<i2", 4: "<u2", 5: "<i4", 6: "<u4", 7: "<f4", 8: "<f8"}

#: The per-point time fields of the common drivers, in the order looked for: the name,
#: the factor to seconds and whether it is absolute (else relative to the header stamp).
#: Ouster: ``t`` uint32 ns; Velodyne: ``time`` float32 s; Hesai: ``timestamp`` float64 s.
TIME_FIELDS = {"t": (1e-9, False), "time": (1.0, False), "timestamp": (1.0, True)}


def stamp_seconds(stamp) -> float:
    """A builtin_interfaces/Time (ROS 1's time too, as rosbags reads it) in seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


def decode_pointcloud2(msg, name: str) -> tuple[float, np.ndarray, np.ndarray | None]:
    """(stamp (s), points N x 3 float64, per-point times (s) relative to the stamp or None)
    of a PointCloud2 ``msg`` (``name`` its topic and index, for errors). Every point is
    returned, NaN ones too (the run drops them). RunError in one line for a big-endian
    cloud, a missing x, y or z, a field of an unknown type or data shorter than its size."""
    stamp = stamp_seconds(msg.header.stamp)
    if msg.is_bigendian:
        raise RunError(f"{name}: a big-endian PointCloud2; lf3pm reads little-endian clouds only")
    fields = {field.name: field for field in msg.fields}
    missing = [axis for axis in "xyz" if axis not in fields]
    if missing:
        raise RunError(f"{name}: the PointCloud2 has no field {missing[0]} (its fields: {', '.join(fields) or 'none'})")
    time_field = next((field for field in TIME_FIELDS if field in fields), None)
    wanted = ["x", "y", "z"] + ([time_field] if time_field else [])
    for field in wanted:
        if fields[field].datatype not in DATATYPES:
            raise RunError(f"{name}: field {field} has the unknown PointField datatype {fields[field].datatype}")
        if fields[field].offset + np.dtype(DATATYPES[fields[field].datatype]).itemsize > msg.point_step:
            raise RunError(f"{name}: field {field} ends past the point step {msg.point_step}")
    dtype = np.dtype(
        {
            "names": wanted,
            "formats": [DATATYPES[fields[f].datatype] for f in wanted],
            "offsets": [fields[f].offset for f in wanted],
            "itemsize": msg.point_step,
        }
    )
    data = np.asarray(msg.data, dtype=np.uint8)
    width, height, row = msg.width * msg.point_step, msg.height, msg.row_step
    if row < width or data.size < row * (height - 1) + width:
        raise RunError(f"{name}: {data.size} bytes of data, short of {msg.height} rows of {msg.width} points")
    if height and row != width:  # rows padded: keep each row's points
        data = np.lib.stride_tricks.as_strided(data, (height, width), (row, 1))
    records = np.ascontiguousarray(data).reshape(-1)[: height * width].view(dtype)
    points = np.stack([records[axis].astype(np.float64) for axis in "xyz"], axis=1)
    if time_field is None:
        return stamp, points, None
    scale, absolute = TIME_FIELDS[time_field]
    times = records[time_field].astype(np.float64) * scale
    return stamp, points, times - stamp if absolute else times
