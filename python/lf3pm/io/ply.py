"""PLY files through plyfile: the x, y, z properties of the vertex element."""

from __future__ import annotations

from typing import BinaryIO

import numpy as np
from plyfile import PlyData, PlyElement

from lf3pm.errors import MapError
from lf3pm.io._common import reading, stack_xyz


def read_ply(path: str) -> np.ndarray:
    """Reads the vertex x, y, z of an ascii or binary PLY file as a float64 (N, 3) array."""
    with reading(path, "PLY"):
        ply = PlyData.read(path)
    if "vertex" not in ply:
        raise MapError(f"{path}: the PLY has no vertex element")
    vertex = ply["vertex"]
    names = [prop.name for prop in vertex.properties]
    missing = [axis for axis in "xyz" if axis not in names]
    if missing:
        raise MapError(f"{path}: the PLY vertex has no {'/'.join(missing)} property (properties: {' '.join(names)})")
    return stack_xyz(vertex["x"], vertex["y"], vertex["z"])


def write_ply(fp: BinaryIO, points: np.ndarray) -> None:
    """Writes a binary little-endian PLY with float32 vertex x, y, z."""
    vertex = np.empty(len(points), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
    vertex["x"], vertex["y"], vertex["z"] = points.T
    PlyData([PlyElement.describe(vertex, "vertex")], text=False, byte_order="<").write(fp)
