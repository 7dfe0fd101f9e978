"""NumPy files: .npy holding an (N, >=3) array; .npz holding one named ``points``, or just one."""

from __future__ import annotations

import zipfile
from typing import BinaryIO

import numpy as np

from lf3pm.errors import MapError
from lf3pm.io._common import reading

#: Rows of a .npy read at a time.
_CHUNK_ROWS = 1 << 20


def read_npy(path: str) -> np.ndarray:
    """Reads the first three columns of an (N, 3) or (N, >=3) .npy array as float64 (N, 3).

    The header is read through a memory map (numpy's parser: never a pickle), the data
    in chunks of rows straight into the result, so the only full copy made is the
    float64 result (copying through one map of the whole file kept its pages resident
    beside the copy: twice the map at the peak).
    """
    with reading(path, ".npy"):
        array = np.lib.format.open_memmap(path, mode="r")
    _check(path, array)  # before any data are read
    if not array.flags.c_contiguous:
        return _xyz(path, array)  # Fortran order: rare, copied as numpy reads it
    rows, columns = array.shape
    dtype, offset = array.dtype, array.offset
    del array
    out = np.empty((rows, 3), dtype=np.float64)
    for start in range(0, rows, _CHUNK_ROWS):
        count = min(_CHUNK_ROWS, rows - start)
        with reading(path, ".npy"):
            part = np.fromfile(
                path, dtype=dtype, count=count * columns, offset=offset + start * columns * dtype.itemsize
            )
        out[start : start + count] = part.reshape(count, columns)[:, :3]
    return out


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
                raise MapError(
                    f"{path}: the .npz holds arrays {', '.join(names)}; "
                    f"expected one named 'points' or exactly one array"
                )
    return _xyz(path, array)


def _xyz(path: str, array: np.ndarray) -> np.ndarray:
    _check(path, array)
    # np.array copies (also out of a memory map) and drops the columns after z.
    return np.array(array[:, :3], dtype=np.float64, order="C")


def _check(path: str, array: np.ndarray) -> None:
    if array.dtype.kind not in "iuf":
        raise MapError(f"{path}: the array holds {array.dtype} values, expected real numbers")
    if array.ndim != 2 or array.shape[1] < 3:
        raise MapError(f"{path}: expected an N x 3 (or N x >=3) array, got shape {array.shape}")


def write_npy(fp: BinaryIO, points: np.ndarray) -> None:
    """Writes the float64 (N, 3) array as .npy."""
    np.save(fp, points, allow_pickle=False)


def write_npz(fp: BinaryIO, points: np.ndarray) -> None:
    """Writes the float64 (N, 3) array as a .npz holding one array named ``points``."""
    np.savez(fp, points=points)
