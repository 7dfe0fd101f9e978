"""PCD files (Point Cloud Library) through pypcd4: ascii, binary and binary_compressed."""

from __future__ import annotations

from typing import BinaryIO

import numpy as np
from pypcd4 import Encoding, PointCloud

from lf3pm.errors import MapError
from lf3pm.io._common import reading, stack_xyz


def read_pcd(path: str) -> np.ndarray:
    """Reads the fields named x, y and z of a PCD file as a float64 (N, 3) array.

    Other fields, of any type and count (intensity, ring, timestamp, ...), are
    skipped: the records are decoded by the header's field layout, never by
    assuming 3 or 4 floats per point.
    """
    with reading(path, "PCD"):
        cloud = PointCloud.from_path(path)
    # A one-point ascii PCD parses (np.loadtxt) to a 0-d array.
    records = np.atleast_1d(cloud.pc_data)
    names = records.dtype.names or ()
    missing = [axis for axis in "xyz" if axis not in names]
    if missing:
        raise MapError(f"{path}: the PCD has no {'/'.join(missing)} field "
                       f"(fields: {' '.join(cloud.metadata.fields)})")
    # pypcd4 returns whatever records a short binary data section holds.
    if len(records) != cloud.metadata.points:
        raise MapError(f"{path}: truncated or corrupt PCD file: the header declares "
                       f"{cloud.metadata.points} points, the data section holds {len(records)}")
    return stack_xyz(records["x"], records["y"], records["z"])


def write_pcd(fp: BinaryIO, points: np.ndarray, encoding: str = "binary") -> None:
    """Writes float32 fields x, y, z with ``encoding`` "ascii", "binary" or "binary_compressed".

    pypcd4 falls back to binary (and says so in the header) when the
    compressed data would not be smaller.
    """
    PointCloud.from_xyz_points(points).save(fp, encoding=Encoding(encoding))
