"""Loading and writing point clouds, the format chosen by the file suffix."""

from __future__ import annotations

import os
import warnings
from importlib import import_module

import numpy as np

from lf3pm.atomic import atomic_write
from lf3pm.errors import MapError
from lf3pm.io.voxel import check_voxel, voxel_downsample

# suffix -> (module, reader, writer). Modules load on first use: pypcd4, plyfile
# and laspy together take about 0.2 s to import.
_FORMATS = {
    ".las": ("las", "read_las", "write_las"),
    ".laz": ("las", "read_las", "write_laz"),
    ".npy": ("npy", "read_npy", "write_npy"),
    ".npz": ("npy", "read_npz", "write_npz"),
    ".pcd": ("pcd", "read_pcd", "write_pcd"),
    ".ply": ("ply", "read_ply", "write_ply"),
}

#: File suffixes that :func:`load_points` and :func:`write_points` accept (case-insensitive).
SUPPORTED_SUFFIXES = tuple(_FORMATS)

#: Values of ``write_points(..., encoding=...)`` for PCD files; "binary" is the default.
PCD_ENCODINGS = ("ascii", "binary", "binary_compressed")


def load_points(path, voxel: float | None = None) -> np.ndarray:
    """Reads the x, y, z coordinates of a point-cloud file.

    The format follows the suffix (see ``SUPPORTED_SUFFIXES``). Returns a
    C-contiguous float64 ``(N, 3)`` array. Points with a NaN or infinite
    coordinate are dropped, with a UserWarning that says how many. With
    ``voxel`` (> 0) the cloud is then reduced to one point per voxel, the
    centroid of its points (:func:`lf3pm.io.voxel_downsample`).

    ``path`` may also be a run folder (a scans folder and a TUM, KITTI or 4 x 4 poses
    file, :mod:`lf3pm.io.run_folder`): its scans in the world frame at their poses, one
    point per ``voxel`` (default ``RUN_MAP_VOXEL``).

    Raises MapError, with one line that names the file, when the file is
    missing, has an unknown suffix, is corrupt or truncated, holds an array of
    the wrong shape, holds no points or no finite point, or ``voxel`` is not > 0.
    """
    name = os.fspath(path)
    if voxel is not None:
        check_voxel(voxel)
    if not os.path.exists(name):
        raise MapError(f"{name}: no such file")
    if os.path.isdir(name):
        from lf3pm.io.run_folder import is_run_folder, run_map

        if is_run_folder(name):
            return run_map(name, voxel)
    if not os.path.isfile(name):
        raise MapError(f"{name}: not a regular file")
    module, reader, _ = _format(name)
    points = getattr(module, reader)(name)

    total = len(points)
    if total == 0:
        raise MapError(f"{name}: the file holds no points")
    finite = np.isfinite(points).all(axis=1)
    kept = int(np.count_nonzero(finite))
    if kept == 0:
        raise MapError(f"{name}: no finite points (all {total} have a NaN or infinite coordinate)")
    if kept < total:
        warnings.warn(
            f"{name}: dropped {total - kept} of {total} points with a NaN or infinite coordinate",
            category=UserWarning,
            stacklevel=2,
        )
        points = points[finite]
    if voxel is not None:
        points = voxel_downsample(points, voxel)
    return points


def write_points(path, points, encoding: str | None = None) -> None:
    """Writes finite ``(N, 3)`` points (N >= 1) to ``path`` in the format its suffix names.

    ``encoding`` chooses the PCD data encoding (``PCD_ENCODINGS``; default
    "binary") and must be None for other formats. PCD and PLY store float32,
    LAS/LAZ integers on a per-axis step of at most 1 µm for clouds up to about
    4 km wide, .npy/.npz float64. The data go to a temporary file beside
    ``path`` that then replaces it, so no reader ever sees a partial file.
    Raises MapError for an unknown suffix or encoding, unusable points, or a
    failed write.
    """
    name = os.fspath(path)
    module, _, writer = _format(name)
    options = {}
    if encoding is not None:
        if writer != "write_pcd":
            raise MapError(f"{name}: an encoding can only be chosen for .pcd files")
        if encoding not in PCD_ENCODINGS:
            raise MapError(f"{name}: unknown PCD encoding {encoding!r}; use one of {', '.join(PCD_ENCODINGS)}")
        options["encoding"] = encoding
    points = np.ascontiguousarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise MapError(f"{name}: points must be an N x 3 array, got shape {points.shape}")
    if len(points) == 0:
        raise MapError(f"{name}: no points to write")
    if not np.isfinite(points).all():
        raise MapError(f"{name}: points to write must all be finite")
    with atomic_write(name, MapError) as fp:
        getattr(module, writer)(fp, points, **options)


def _format(name: str):
    """The module, reader name and writer name for ``name``'s suffix, or a MapError."""
    suffix = os.path.splitext(name)[1].lower()
    if suffix not in _FORMATS:
        raise MapError(f"{name}: unknown suffix {suffix or '(none)'}; supported: {' '.join(SUPPORTED_SUFFIXES)}")
    module, reader, writer = _FORMATS[suffix]
    return import_module(f"lf3pm.io.{module}"), reader, writer
