"""SOLM builds on a Ray cluster: one task per tile (docs/scale.md).

Each task crops the map to what its tile can see (tiles.py) and indexes only that, so a
worker's memory is bounded by the crop, not the map; the map's points travel once,
through Ray's shared object store, and the driver needs no index of its own (MapPoints).
A task writes its tile's chunks into the Zarr store
(a path every node can reach) and the driver then sets the tile's done flag, so a tile
counts only once its data are on disk: a killed worker's task is retried by Ray and
rewrites the same chunks, and an interrupted build resumes where it stopped. The store
is bitwise the store a local build writes.
"""

from __future__ import annotations

import socket
from pathlib import Path

from lf3pm.errors import Lf3pmError
from lf3pm.map import Map, MapPoints, crop_points
from lf3pm.solm.tiles import TileJob, compute_tile, crop_margin, write_tile

#: Times Ray reruns a tile whose worker died (Ray's own default for tasks).
RETRIES = 3
#: Seconds to wait for a cluster's head before calling it unreachable.
CONNECT_TIMEOUT = 5.0


def connect(address: str | None) -> None:
    """Joins the Ray cluster at ``address`` ("host:port" of its head; None: start a
    local one on this machine's cores), unless this process already has. Raises
    Lf3pmError, in one line, when Ray is missing or the head does not answer."""
    try:
        import ray
    except ImportError:
        raise Lf3pmError("the ray engine needs Ray: pip install 'lf3pm[cluster]'") from None
    if ray.is_initialized():
        return
    if address is not None and address != "auto":
        host, _, port = address.rpartition(":")
        if not host or not port.isdigit():
            raise Lf3pmError(f"--address must be HOST:PORT of a Ray head (`ray start --head`), got {address!r}")
        try:
            socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT).close()
        except OSError as err:
            raise Lf3pmError(f"no Ray head answers at {address} ({err.strerror or err})") from None
    try:
        ray.init(address=address, include_dashboard=False, log_to_driver=False, configure_logging=False)
    except Exception as err:  # noqa: BLE001 - Ray raises many kinds; each is one line here
        raise Lf3pmError(
            f"cannot join the Ray cluster at {address or 'a new local one'}: "
            f"{str(err).splitlines()[0] if str(err) else type(err).__name__}"
        ) from None


def build_tiles(world: Map | MapPoints, job: TileJob, todo: list, ground, out: Path, finished) -> None:
    """Computes the tiles ``todo`` as Ray tasks (one CPU each) that write into the store
    ``out``; calls ``finished(ty, tx, cells)`` as each completes."""
    import ray

    remote = ray.remote(num_cpus=1, max_retries=RETRIES)(solm_tile)
    # The points and the job (its rays are 0.7 MB for a VLP-16) go to the object store
    # once; each task then carries only its tile's indices and ground heights.
    points, shared_job = ray.put(world.points), ray.put(job)
    margin = crop_margin(job, world)
    store = str(Path(out).resolve())
    tile_of = {
        remote.remote(
            points,
            world.frame,
            world.association_params,
            world.source,
            world.sha256,
            shared_job,
            ty,
            tx,
            job.ground(ground, ty, tx),
            margin,
            store,
        ): (ty, tx)
        for ty, tx in todo
    }
    pending = list(tile_of)
    while pending:
        # Whatever finished within a second: one wait per batch, not one per tile.
        ready, pending = ray.wait(pending, num_returns=len(pending), timeout=1.0)
        for ref in ready:
            ty, tx = tile_of[ref]
            try:
                cells = ray.get(ref)
            except ray.exceptions.RayError as err:
                # A worker's own error (a full disk under its chunks: StorageError) keeps its
                # class, so that the build says what it kept and how to resume, as a local one does.
                cause = getattr(err, "cause", None)
                kind = type(cause) if isinstance(cause, Lf3pmError) else Lf3pmError
                text = str(cause) if isinstance(cause, Lf3pmError) else _first_line(err)
                raise kind(f"tile ({ty}, {tx}) failed on the cluster: {text}") from None
            finished(ty, tx, cells)


def solm_tile(
    points,
    frame,
    association_params: dict,
    source: str,
    sha256: str,
    job: TileJob,
    ty: int,
    tx: int,
    ground,
    margin: float,
    store: str,
) -> int:
    """One tile on a worker: crop, index, compute, write its chunks; returns its cell count."""
    import zarr

    crop = crop_points(
        points, frame, association_params, job.bounds(ty, tx), margin, source=source, sha256=sha256, threads=1
    )
    arrays = compute_tile(crop, job, ty, tx, ground, threads=1)
    return write_tile(zarr.open_group(store, mode="r+"), job, ty, tx, arrays)


def _first_line(err: Exception) -> str:
    lines = [line for line in str(err).splitlines() if line.strip()]
    return lines[-1] if lines else type(err).__name__
