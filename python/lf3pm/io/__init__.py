"""Point-cloud map files: read and write x, y, z; voxel-downsample.

Formats, chosen by the file suffix: PCD (``.pcd``, ascii / binary /
binary_compressed), PLY (``.ply``), LAS and LAZ (``.las``, ``.laz``) and NumPy
(``.npy``, ``.npz``); and a recorded run's folder of scans with their poses, read
as the map they make (:mod:`lf3pm.io.run_folder`). Readers return a C-contiguous float64 ``(N, 3)`` array;
every problem with a file raises :class:`lf3pm.errors.MapError` with one line
that names the file.
"""

from lf3pm.io._dispatch import SUPPORTED_SUFFIXES, load_points, write_points
from lf3pm.io.voxel import voxel_downsample

__all__ = ["SUPPORTED_SUFFIXES", "load_points", "voxel_downsample", "write_points"]
