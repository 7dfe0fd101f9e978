"""PCD files (Point Cloud Library) through pypcd4: ascii, binary and binary_compressed."""

from __future__ import annotations

from typing import BinaryIO

import numpy as np
from pypcd4 import Encoding, PointCloud
from pypcd4.pypcd4 import MetaData

from lf3pm.errors import MapError
from lf3pm.io._common import reading, stack_xyz

#: Records of a binary PCD read at a time (pypcd4 reads the whole data section, then
#: the x, y, z copy doubles it).
_CHUNK_RECORDS = 1 << 20


def read_pcd(path: str) -> np.ndarray:
    """Reads the fields named x, y and z of a PCD file as a float64 (N, 3) array.

    Other fields, of any type and count (intensity, ring, timestamp, ...), are
    skipped: the records are decoded by the header's field layout, never by
    assuming 3 or 4 floats per point. Binary files are read in chunks of records
    straight into the result; ascii and binary_compressed ones through pypcd4.
    """
    _check_declared_size(path)
    with reading(path, "PCD"):
        with open(path, "rb") as fp:
            metadata, data_offset = _header(fp)
        if metadata.data == Encoding.BINARY:
            return _read_binary(path, metadata, data_offset)
        cloud = PointCloud.from_path(path)
    # A one-point ascii PCD parses (np.loadtxt) to a 0-d array.
    records = np.atleast_1d(cloud.pc_data)
    _check_xyz(path, records.dtype, cloud.metadata)
    # pypcd4 returns whatever records a short binary data section holds.
    if len(records) != cloud.metadata.points:
        raise MapError(
            f"{path}: truncated or corrupt PCD file: the header declares "
            f"{cloud.metadata.points} points, the data section holds {len(records)}"
        )
    return stack_xyz(records["x"], records["y"], records["z"])


def _header(fp) -> tuple[MetaData, int]:
    """The parsed header of an open PCD file and the offset of its data section."""
    lines = []
    for raw in fp:
        line = raw.decode("utf-8").strip()
        if not line or line.startswith("#"):
            continue
        lines.append(line)
        if line.startswith("DATA"):
            break
    return MetaData.parse_header(lines), fp.tell()


def _check_xyz(path: str, dtype: np.dtype, metadata: MetaData) -> None:
    missing = [axis for axis in "xyz" if axis not in (dtype.names or ())]
    if missing:
        raise MapError(f"{path}: the PCD has no {'/'.join(missing)} field (fields: {' '.join(metadata.fields)})")


def _read_binary(path: str, metadata: MetaData, offset: int) -> np.ndarray:
    """x, y, z of a binary PCD's records, a chunk of records at a time (its size is
    checked by _check_declared_size)."""
    dtype = metadata.build_dtype()
    _check_xyz(path, dtype, metadata)
    total = metadata.points
    xyz = np.empty((total, 3), dtype=np.float64)
    for start in range(0, total, _CHUNK_RECORDS):
        count = min(_CHUNK_RECORDS, total - start)
        records = np.fromfile(path, dtype=dtype, count=count, offset=offset + start * dtype.itemsize)
        if len(records) != count:
            raise MapError(
                f"{path}: truncated or corrupt PCD file: the header declares "
                f"{total} points, the data section holds {start + len(records)}"
            )
        for axis, name in enumerate("xyz"):
            xyz[start : start + count, axis] = records[name]
    return xyz


#: How many times its compressed size an LZF block can grow (a 3-byte back-reference
#: copies at most 264 bytes: 88; with margin), so a binary_compressed header cannot make
#: the reader allocate gigabytes from a small file.
_LZF_MAX_RATIO = 100


def _check_declared_size(path: str) -> None:
    """Refuses a PCD whose header declares more data than the file can hold, before any
    of it is allocated (a 180 KB file claiming `COUNT 1 1 1000000000` used to grow past
    5 GB). Headers it cannot parse are left to pypcd4's own errors."""
    try:
        with open(path, "rb") as fp:
            head = fp.read(65536)
            size = fp.seek(0, 2)
    except OSError:
        return  # reading() reports it
    fields, offset = {}, 0
    for raw in head.split(b"\n"):
        offset += len(raw) + 1
        words = raw.decode("ascii", "replace").split()
        if not words or words[0].startswith("#"):
            continue
        fields[words[0].upper()] = words[1:]
        if words[0].upper() == "DATA":
            break
    else:
        return
    try:
        sizes = [int(v) for v in fields["SIZE"]]
        counts = [int(v) for v in fields.get("COUNT", ["1"] * len(sizes))]
        points = int(fields["POINTS"][0]) if "POINTS" in fields else int(fields["WIDTH"][0]) * int(fields["HEIGHT"][0])
        encoding = fields["DATA"][0].lower()
    except (KeyError, IndexError, ValueError):
        return
    if len(sizes) != len(counts) or min(sizes + counts + [points]) < 0:
        return
    record, values, left = sum(a * b for a, b in zip(sizes, counts)), sum(counts), size - offset
    if encoding == "binary":
        need, what = points * record, f"{points * record:,} bytes of data"
    elif encoding == "ascii":
        need, what = points * values * 2, f"{points * values:,} values"  # a digit and a separator each
    elif encoding == "binary_compressed":
        need, what = points * record // _LZF_MAX_RATIO, f"{points * record:,} bytes once decompressed"
    else:
        return
    if need > left:
        raise MapError(
            f"{path}: truncated or corrupt PCD file: its header declares {points:,} points "
            f"({what}), more than the {left:,} bytes after the header can hold"
        )


def write_pcd(fp: BinaryIO, points: np.ndarray, encoding: str = "binary") -> None:
    """Writes float32 fields x, y, z with ``encoding`` "ascii", "binary" or "binary_compressed".

    pypcd4 falls back to binary (and says so in the header) when the
    compressed data would not be smaller.
    """
    PointCloud.from_xyz_points(points).save(fp, encoding=Encoding(encoding))
