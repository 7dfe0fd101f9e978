"""SOLM storage: a Zarr group, chunked and compressed, written tile by tile.

Layout: one array per channel (float32; NaN where a cell was not evaluated:
unknown ground or an obstacle) and per mask (uint8), ``ground_z`` and
``occupied`` (occupancy.py, on cells ``occupancy_factor`` times finer) for ground
robots, and ``done``, one flag per tile set only after the tile's data are
written. An interrupted build (Ctrl-C or kill -9) therefore loses at most the
tile in flight, and a rerun recomputes exactly the tiles without a flag. The
group's attributes hold the grid, sensor, parameters, map hash and version; a
store built from another map or with other parameters is refused, never mixed.
"""

from __future__ import annotations

import math
import os
import shutil
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from lf3pm.errors import CorruptStoreError, Lf3pmError, StorageError

CHANNELS = ("q_min", "q_n", "q_max", "sigma1", "step_norm", "m")
MASKS = ("obstacle", "unknown", "degenerate")
#: Characters of an underlying error quoted in a one-line message.
QUOTED = 80


def tiles_shape(ny: int, nx: int, tile: int) -> tuple[int, int]:
    return math.ceil(ny / tile), math.ceil(nx / tile)


#: Attributes that record where the inputs came from but not what they are: a map is
#: identified by its hash (map_sha256), so the same map by another path resumes the build;
#: the localization-error fit stored for predictions changes no cell.
PROVENANCE = {"map_source", "calibration"}


def check_new_store(path: Path) -> None:
    """Raises Lf3pmError when a store could not be created at ``path``: its folder does not
    exist, is not a folder, or is not writable."""
    path = Path(path)
    if path.exists():
        return
    parent = path.parent
    if not parent.exists():
        raise Lf3pmError(f"output folder {parent} does not exist")
    if not parent.is_dir():
        raise Lf3pmError(f"cannot write {path}: {parent} is not a folder")
    if not os.access(parent, os.W_OK):
        raise Lf3pmError(f"cannot write {path}: output folder {parent} is read-only")


def open_or_create(path: Path, attrs: dict, shape: tuple, ground: bool, tile: int):
    """The store at ``path``: created when absent, else checked against ``attrs``
    (every attribute but the PROVENANCE ones must be equal)."""
    import zarr

    path = Path(path)
    if path.exists():
        try:
            group = zarr.open_group(str(path), mode="r+")
        except Exception as err:  # noqa: BLE001 - any unreadable store is refused the same way
            raise Lf3pmError(f"{path} exists and is not a SOLM store ({err.__class__.__name__})") from None
        old = dict(group.attrs)
        differ = sorted(k for k in (set(old) | set(attrs)) - PROVENANCE if old.get(k) != attrs.get(k))
        if differ:
            raise Lf3pmError(
                f"{path} was built from another map or with other parameters "
                f"(differs in: {', '.join(differ)}); remove it or choose another output"
            )
        group.attrs.update({k: v for k, v in attrs.items() if k in PROVENANCE})  # the latest build's
        return group
    check_new_store(path)
    try:
        group = zarr.open_group(str(path), mode="w")
        group.attrs.update(attrs)
        chunks = (tile, tile) if len(shape) == 2 else (shape[0], tile, tile)
        for name in CHANNELS:
            group.create_array(name, shape=shape, chunks=chunks, dtype="float32", fill_value=np.nan)
        for name in MASKS:
            group.create_array(name, shape=shape, chunks=chunks, dtype="uint8", fill_value=0)
        if ground:
            group.create_array("ground_z", shape=shape[-2:], chunks=(tile, tile), dtype="float32", fill_value=np.nan)
            k = int(attrs["occupancy_factor"])
            group.create_array(
                "occupied",
                shape=(shape[-2] * k, shape[-1] * k),
                chunks=(tile * k, tile * k),
                dtype="uint8",
                fill_value=0,
            )
        tiles = tiles_shape(*shape[-2:], tile)
        group.create_array("done", shape=tiles, chunks=tiles, dtype="uint8", fill_value=0)
        group["done"][...] = np.zeros(tiles, np.uint8)
    except OSError as err:
        shutil.rmtree(path, ignore_errors=True)  # never leave a half-created store
        raise StorageError(
            f"{path}: cannot create the store ({_quote(err)}); nothing was kept: free space or "
            "fix the storage, then run the build again"
        ) from None
    return group


def store_root(group) -> Path:
    """The folder of the store that ``group`` was opened from."""
    return Path(getattr(group.store, "root", str(group.store)))


def chunk_path(group, name: str, coords: tuple) -> Path:
    """The file of chunk ``coords`` (chunk indices) of array ``name``: zarr's default chunk
    key encoding (c/i/j/...), which every lf3pm store is created with."""
    return store_root(group) / name / "c" / Path(*(str(int(c)) for c in coords))


def _quote(err: BaseException) -> str:
    """The first line of ``err``, at most QUOTED characters: the cause a one-line error adds."""
    text = (getattr(err, "strerror", None) or str(err) or err.__class__.__name__).splitlines()[0]
    return text if len(text) <= QUOTED else text[: QUOTED - 1] + "…"


@contextmanager
def writing(path: Path):
    """Turns an OSError under the block (a write to ``path``: a chunk or a folder of a
    store) into a one-line StorageError that names it."""
    try:
        yield
    except OSError as err:
        raise StorageError(f"{path}: cannot write ({_quote(err)})") from None


def read_array(group, name: str) -> np.ndarray:
    """Array ``name`` of the store ``group`` whole. Unreadable metadata or a chunk that
    does not decode is a CorruptStoreError, an OSError a StorageError, each naming the
    file (the failing chunk found by reading chunk by chunk) and saying what to do."""
    root = store_root(group)
    rebuild = (
        f"the store was not changed; build it again (remove {root}, then run `lf3pm solm build "
        f"{group.attrs.get('map_source', 'MAP')} -o {root}` with its options)"
    )
    try:
        array = group[name]
    except OSError as err:
        raise StorageError(
            f"{root / name}: cannot read the SOLM's {name} ({_quote(err)}); {rebuild} once the storage is sound"
        ) from None
    except KeyError:
        raise CorruptStoreError(
            f"{root / name / 'zarr.json'}: the SOLM's {name} is missing (no metadata); {rebuild}"
        ) from None
    except Exception as err:  # noqa: BLE001 - zarr reports unreadable metadata by JSON or value errors
        raise CorruptStoreError(
            f"{root / name / 'zarr.json'}: the SOLM's {name} has unreadable metadata "
            f"({err.__class__.__name__}: {_quote(err)}); {rebuild}"
        ) from None
    try:
        return array[...]
    except Exception as err:  # noqa: BLE001 - codecs report a chunk that does not decode by any error class
        where = _failing_chunk(group, array, name) or root / name
        if isinstance(err, OSError):
            raise StorageError(
                f"{where}: cannot read the SOLM's {name} ({_quote(err)}); {rebuild} once the storage is sound"
            ) from None
        raise CorruptStoreError(
            f"{where}: a corrupt chunk of the SOLM's {name} ({err.__class__.__name__}: {_quote(err)}); {rebuild}"
        ) from None


def _failing_chunk(group, array, name: str) -> Path | None:
    """The file of the first chunk of ``array`` that cannot be read, or None."""
    for coords in np.ndindex(*array.cdata_shape):
        region = tuple(slice(c * n, (c + 1) * n) for c, n in zip(coords, array.chunks))
        try:
            array[region]
        except Exception:  # noqa: BLE001 - any failure marks the chunk
            return chunk_path(group, name, coords)
    return None
