"""LAS and LAZ files through laspy (LAZ through the lazrs backend)."""

from __future__ import annotations

import os
from typing import BinaryIO

import laspy
import numpy as np

from lf3pm.errors import MapError
from lf3pm.io._common import reading, stack_xyz

_LAZ_BACKEND = laspy.LazBackend.LazrsParallel
#: Points decoded at a time.
_CHUNK_POINTS = 1 << 20

# LAS stores coordinates as int32 counts of a per-axis scale; keep a margin below 2**31 - 1.
_INT32_REACH = 2**31 - 2
_FINEST_SCALE = 1e-6  # one micrometre, finer than any LiDAR


def read_las(path: str) -> np.ndarray:
    """Reads the scaled (real-world) x, y, z of a .las or .laz file as a float64 (N, 3) array."""
    with reading(path, "LAS/LAZ"), laspy.open(path, laz_backend=_LAZ_BACKEND) as reader:
        header = reader.header
        # laspy only logs when an uncompressed file ends early, so compare sizes first.
        if not header.are_points_compressed:
            data_bytes = os.path.getsize(path) - header.offset_to_point_data
            stored = data_bytes // header.point_format.size
            if stored < header.point_count:
                raise MapError(
                    f"{path}: truncated LAS file: the header declares "
                    f"{header.point_count} points, the file holds {max(stored, 0)}"
                )
        # Chunk by chunk into the result: the whole record array beside it cost two to
        # three times the coordinates.
        xyz = np.empty((header.point_count, 3), dtype=np.float64)
        start = 0
        for chunk in reader.chunk_iterator(_CHUNK_POINTS):
            end = start + len(chunk)
            if end > len(xyz):
                raise MapError(f"{path}: corrupt LAS file: more points than its header declares")
            xyz[start:end] = stack_xyz(chunk.x, chunk.y, chunk.z)
            start = end
    if start != len(xyz):
        raise MapError(f"{path}: truncated LAS/LAZ file: the header declares {len(xyz)} points, the file holds {start}")
    return xyz


def write_las(fp: BinaryIO, points: np.ndarray) -> None:
    """Writes an uncompressed LAS 1.4 file, point format 0 (see :func:`_las_data`)."""
    _las_data(points).write(fp, do_compress=False)


def write_laz(fp: BinaryIO, points: np.ndarray) -> None:
    """Writes a LAZ (lazrs-compressed LAS 1.4) file, point format 0."""
    _las_data(points).write(fp, do_compress=True, laz_backend=_LAZ_BACKEND)


def _las_data(points: np.ndarray) -> laspy.LasData:
    """Packs finite, non-empty ``points`` with per-axis offset at the centre of the cloud.

    The scale is the finest power of ten, down to 1 µm, at which the cloud's half
    extent still fits in int32, so coordinates round trip within scale / 2.
    """
    low, high = points.min(axis=0), points.max(axis=0)
    header = laspy.LasHeader(point_format=0, version="1.4")
    header.offsets = (low + high) / 2
    finest_fitting = (high - low) / 2 / _INT32_REACH
    header.scales = 10.0 ** np.ceil(np.log10(np.maximum(finest_fitting, _FINEST_SCALE)))
    las = laspy.LasData(header)
    las.x, las.y, las.z = points[:, 0], points[:, 1], points[:, 2]
    return las
