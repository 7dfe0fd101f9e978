"""Helpers shared by the format readers: one-line errors and the (N, 3) layout."""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np

from lf3pm.errors import MapError


@contextmanager
def reading(path: str, kind: str):
    """Re-raises what a library throws while parsing ``path`` as a one-line MapError.

    Libraries report a corrupt or truncated file with many unrelated exception
    types (ValueError, struct.error, zipfile.BadZipFile, lazrs.LazrsError,
    pydantic's ValidationError, ...), so anything but our own MapError is caught;
    keep the guarded block to the library calls.
    """
    try:
        yield
    except MapError:
        raise
    except OSError as err:
        raise MapError(f"{path}: cannot read the file ({err.strerror or err})") from err
    except Exception as err:
        raise MapError(f"{path}: corrupt or truncated {kind} file ({_first_line(err)})") from err


def _first_line(err: Exception) -> str:
    lines = str(err).strip().splitlines()
    return lines[0] if lines else type(err).__name__


def stack_xyz(x, y, z) -> np.ndarray:
    """Copies three coordinate columns of any numeric type into a C-contiguous float64 (N, 3) array.

    Filling a preallocated array column by column makes exactly one copy of the
    coordinates, whatever the source layout (structured records, memory maps).
    """
    xyz = np.empty((len(x), 3), dtype=np.float64)
    xyz[:, 0] = x
    xyz[:, 1] = y
    xyz[:, 2] = z
    return xyz
