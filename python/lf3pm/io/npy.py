"""NumPy files: .npy holding an (N, >=3) array; .npz holding one named ``points``, or just one."""

from __future__ import annotations

import zipfile
from typing import BinaryIO

import numpy as np

from lf3pm.errors import MapError
from lf3pm.io._common import reading


def read_npy(path: str) -> np.ndarray:
    """Reads the first three columns of an (N, 3) or (N, >=3) .npy array as float64 (N, 3).

    The file is memory-mapped, so the only full copy made is the float64 result.
    """
    # Unlike np.load, open_memmap accepts only the .npy format: never a pickle.
    with reading(path, ".npy"):
        array = np.lib.format.open_memmap(path, mode="r")
    return _xyz(path, array)


def read_npz(path: str) -> np.ndarray:
    """Reads the array named ``points`` of a .npz archive, or its only array if it has one."""
    with reading(path, ".npz"):
        # np.load would read any content that is not a zip archive as .npy or pickle.
        if not zipfile.is_zipfile(path):
            raise MapError(f"{path}: corrupt or truncated .npz file (not a zip archive)")
        with np.load(path, allow_pickle=False) as archive:
            names = archive.files
            if "points" in names:
                array = archive["points"]
            elif len(names) == 1:
                array = archive[names[0]]
            elif not names:
                raise MapError(f"{path}: the .npz holds no arrays")
            else:
                raise MapError(f"{path}: the .npz holds arrays {', '.join(names)}; "
                               f"expected one named 'points' or exactly one array")
    return _xyz(path, array)


def _xyz(path: str, array: np.ndarray) -> np.ndarray:
    if array.dtype.kind not in "iuf":
        raise MapError(f"{path}: the array holds {array.dtype} values, expected real numbers")
    if array.ndim != 2 or array.shape[1] < 3:
        raise MapError(f"{path}: expected an N x 3 (or N x >=3) array, got shape {array.shape}")
    # np.array copies (also out of a memory map) and drops the columns after z.
    return np.array(array[:, :3], dtype=np.float64, order="C")


def write_npy(fp: BinaryIO, points: np.ndarray) -> None:
    """Writes the float64 (N, 3) array as .npy."""
    np.save(fp, points, allow_pickle=False)


def write_npz(fp: BinaryIO, points: np.ndarray) -> None:
    """Writes the float64 (N, 3) array as a .npz holding one array named ``points``."""
    np.savez(fp, points=points)
