"""Building a SOLM: evaluate the metric at every cell of a grid, tile by tile,
resumable (see store.py)."""

from __future__ import annotations

import numbers
import os
import warnings
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from lf3pm import __version__
from lf3pm.calibration import localization_fit
from lf3pm.config import Config, configured
from lf3pm.errors import Lf3pmError, StorageError
from lf3pm.flight.mounts import MOUNTS
from lf3pm.grid import Space
from lf3pm.map import Map, MapPoints
from lf3pm.sensors import Sensor, as_sensor
from lf3pm.solm.grid import SolmGrid
from lf3pm.solm.occupancy import grid_occupancy, occupancy_factor
from lf3pm.solm.store import (
    CHANNELS,
    check_new_store,
    chunk_path,
    open_or_create,
    read_array,
    tiles_shape,
    writing,
)
from lf3pm.solm.tiles import compute_tile, crop_margin, make_job, write_tile
from lf3pm.terrain import column_minimum

#: Engines that compute the tiles: here (local) or as Ray tasks (cluster.py).
ENGINES = ("local", "ray")
#: Percentiles of x and of y whose box :func:`stray_points_warning` suggests as bounds.
STRAY_PERCENTILES = (0.5, 99.5)
#: Points per pass of that check (and the most it takes its percentiles from), so
#: that it holds a few MB beside a map of any size.
STRAY_CHUNK = 1_000_000


def stray_points_warning(points: np.ndarray, grid: SolmGrid) -> str | None:
    """One line when a few stray points make most of ``grid`` empty: most of its x-y
    cells hold no map point, and the box of STRAY_PERCENTILES of the points' x and y
    (on an even sample of at most STRAY_CHUNK) covers less than half of it. The line
    names the grid cells that hold that box as the ``--bounds`` to build with
    instead; None otherwise."""
    origin, res = np.array(grid.origin), grid.res
    end = np.array(grid.bounds[2:])
    lo, hi = np.percentile(points[:: max(1, len(points) // STRAY_CHUNK), :2], STRAY_PERCENTILES, axis=0)
    if np.prod(np.clip(np.minimum(hi, end) - np.maximum(lo, origin), 0, None)) >= 0.5 * np.prod(end - origin):
        return None
    box_lo = origin + np.floor((lo - origin) / res) * res
    box_hi = origin + (np.floor((hi - origin) / res) + 1) * res  # the cells holding the box, a point on its edge too
    filled, outside = np.zeros(grid.ny * grid.nx, bool), 0
    for first in range(0, len(points), STRAY_CHUNK):
        xy = points[first : first + STRAY_CHUNK, :2]
        outside += int(np.count_nonzero(np.any((xy < box_lo) | (xy > box_hi), axis=1)))
        ix, iy = grid.columns(xy[:, 0], xy[:, 1])
        inside = grid.holds(ix, iy)
        filled[iy[inside] * grid.nx + ix[inside]] = True
    if filled.sum() >= filled.size / 2:
        return None
    bounds = " ".join(f"{round(v, 6):g}" for v in (*box_lo, *box_hi))
    x0, y0, x1, y1 = (round(float(v), 6) for v in (*origin, *end))
    return (
        f"{filled.sum():,} of the SOLM grid's {filled.size:,} x-y cells hold a map point: stray points stretch "
        f"it over x [{x0:g}, {x1:g}], y [{y0:g}, {y1:g}]; --bounds {bounds} (the {STRAY_PERCENTILES[0]:g} "
        f"and {STRAY_PERCENTILES[1]:g} percentiles of x and y, in whole cells) holds all but "
        f"{outside:,} of the {len(points):,} points and skips the empty cells"
    )


#: The sections of the configuration a build reads.
SECTIONS = ("scan", "metric", "solm", "quadrotor")
#: The solm section's parameters that make the grid (make_grid), which a build takes whole.
GRID_FIELDS = ("space", "res", "yaw_bins", "height", "bounds", "max_cells")


def build_solm(
    world: Map | MapPoints,
    sensor: Sensor | str,
    grid: SolmGrid,
    out: Path,
    config: Config | None = None,
    *,
    max_tiles: int | None = None,
    crop: bool = False,
    engine: str = "local",
    address: str | None = None,
    progress=None,
    **parameters,
) -> dict:
    """Builds (or resumes) the SOLM of ``world`` (a Map, or MapPoints: a map not indexed
    whole, built on crops) for ``sensor`` (a Sensor or a preset name) on ``grid``
    (make_grid) into the Zarr store ``out``, with the scan, metric and solm sections of
    ``config`` (lf3pm.config.Config; default: the defaults), whose fields may also be
    given by name (``seed=3, ray_stride=4``; lf3pm.config.configured). Cell c (linear index
    over the channel's shape) uses noise stream c, so results do not depend on tiling or
    resumption. An r3yaw grid's poses are a level body at each height and yaw bin carrying
    the sensor on the quadrotor section's ``mount``; where turning the body by a bin only
    permutes the rays (a level 360-degree sensor on the body's axis: tiles.yaw_invariant)
    each cell is cast once for all its bins (attribute ``yaw_once``). Of the solm
    section: ``yaw_reuse`` (SE2 only) scans each yaw sector once
    and sums sector Grams per bin (yaw_reuse.py): about 2F+1 times faster, approximate
    (docs/solm.md); ``ray_stride`` K casts every K-th azimuth column of the pattern and
    scales the Gram up (ray_thinning.py): about K times faster, approximate; ``tile`` is
    the tile (and Zarr chunk) edge in cells; MapPoints of at most ``crop_above`` points
    are indexed whole, unless ``crop``, and larger ones are built on crops.
    ``max_tiles`` stops after that many tiles (for tests of resumption). ``crop``:
    compute each tile on its own crop of the map (tiles.py; the store is bitwise the
    same). ``engine``: "local" (this process, the scan section's ``threads`` workers) or
    "ray" (one Ray task per tile on the cluster at ``address``, None: a local one; each
    task indexes only its tile's crop; cluster.py)."""
    if not isinstance(world, (Map, MapPoints)):
        raise Lf3pmError(f"build_solm needs a map (lf3pm.load_map), got {type(world).__name__}")
    if not isinstance(grid, SolmGrid):
        raise Lf3pmError(f"build_solm needs a grid (lf3pm.make_grid), got {type(grid).__name__}")
    if not isinstance(out, (str, os.PathLike)):
        raise Lf3pmError(f"the SOLM store to build is a path, got {type(out).__name__}")
    if progress is not None and not callable(progress):
        raise Lf3pmError(f"progress must be a function (cells, total), got {type(progress).__name__}")
    if max_tiles is not None and not (_integer(max_tiles) and max_tiles >= 0):
        raise Lf3pmError(f"max_tiles must be None or an integer >= 0, got {max_tiles!r}")
    grid_given = [name for name in GRID_FIELDS if name in parameters]
    if grid_given:
        raise Lf3pmError(
            f"build_solm takes {grid_given[0]} from its grid: give it to make_grid (lf3pm.make_grid), not to build_solm"
        )
    config = configured(config, SECTIONS, "build_solm", **parameters)
    scan, metric, layout = config.scan, config.metric, config.solm
    if engine not in ENGINES:
        raise Lf3pmError(f"unknown engine {engine!r}; use one of {', '.join(ENGINES)}")
    sensor = as_sensor(sensor)
    tile = layout.tile
    if layout.yaw_reuse and grid.space is not Space.SE2:
        raise Lf3pmError("yaw reuse applies to se2 grids only")
    hint = stray_points_warning(world.points, grid)
    if hint is not None:
        warnings.warn(hint, UserWarning, stacklevel=2)
    aerial_yaw = grid.space is Space.R3YAW
    mount = MOUNTS[config.quadrotor.mount] if aerial_yaw else None
    job = make_job(sensor, grid, scan, metric, layout, None if mount is None else mount.matrix())
    attrs = {
        "lf3pm_version": __version__,
        "grid": grid.to_dict(),
        "sensor": sensor.name,
        "sensor_rays": sensor.num_rays,
        "sensor_returns": None if sensor.returns is None else sensor.returns.to_yaml(),
        # r3yaw: the body level at each cell's height and yaw, the sensor on this mount.
        "mount": None if mount is None else {"name": mount.name, "matrix": mount.matrix().tolist()},
        "yaw_once": job.yaw_once,
        "noise": job.noise,
        "seed": scan.seed,
        "w1": metric.w1,
        "w2": 1.0 - metric.w1,
        "association": metric.association,
        "robot_radius": job.robot_radius,
        "floor_clearance": job.floor_clearance,
        "map_sha256": world.sha256,
        "map_source": world.source,
        "channels": list(CHANNELS),
        "noise_stream": "linear cell index over the channel shape (yaw reuse: 2D cell index * yaw_bins + sector)",
        "tile": tile,
        "yaw_reuse": layout.yaw_reuse,
        "ray_stride": layout.ray_stride,
        # The localization-error fit that predictions on this SOLM use (lf3pm.prediction).
        "calibration": localization_fit(config.prediction.calibration) if config.prediction.calibration else None,
    }
    ground_robot = grid.space.ground
    if ground_robot:
        attrs["occupancy_factor"] = occupancy_factor(grid, layout)
    if engine == "ray":
        from lf3pm.solm.cluster import connect

        check_new_store(out)
        connect(address)  # an unreachable cluster fails before the store is touched
    ground = column_minimum(world.points, grid) if ground_robot else None
    group = open_or_create(out, attrs, grid.shape, ground_robot, tile)
    done = read_array(group, "done")
    ty_n, tx_n = tiles_shape(grid.ny, grid.nx, tile)
    kept = int(np.count_nonzero(done))
    todo = [(ty, tx) for ty in range(ty_n) for tx in range(tx_n) if not done[ty, tx]]
    if max_tiles is not None:
        todo = todo[:max_tiles]
    total = grid.layers * grid.ny * grid.nx
    out = Path(out)

    depth = 0  # storing() blocks open: the outermost says what was kept (the Ray engine nests them)

    @contextmanager
    def storing(where: Path):
        """A write into the store (``where``: the chunk or array written). A storage fault
        stops the build in one line: the file, the finished tiles kept, how to resume."""
        nonlocal depth
        if not (out / "zarr.json").is_file():  # zarr would recreate the folders of a chunk it writes
            raise StorageError(
                f"{out}/zarr.json: the store vanished during the build (removed, or its disk "
                f"unmounted); nothing of it is kept: remove what is left at {out}, then run "
                f"`lf3pm solm build {world.source} -o {out}` with the same options again"
            )
        depth += 1
        try:
            with writing(where):
                yield
        except StorageError as err:
            if depth > 1:
                raise
            raise StorageError(
                f"{err}; the build stopped with {kept} of {ty_n * tx_n} tiles finished and kept "
                f"in {out}: free space or fix the storage, then run `lf3pm solm build "
                f"{world.source} -o {out}` with the same options (or the same build_solm call) "
                "again to resume it"
            ) from None
        finally:
            depth -= 1

    if ground_robot:
        occupied = grid_occupancy(world.points, grid, ground, job.robot_radius, job.floor_clearance, layout)
        with storing(out / "ground_z"):
            group["ground_z"][...] = np.where(np.isfinite(ground), ground, np.nan).astype(np.float32)
        with storing(out / "occupied"):
            group["occupied"][...] = occupied.astype(np.uint8)

    def finished(ty, tx, cells):
        nonlocal kept
        with storing(chunk_path(group, "done", (0, 0))):
            group["done"][ty, tx] = 1  # last: the tile counts only once all its data are on disk
        kept += 1
        if progress:
            progress(cells, total)

    if engine == "ray":
        from lf3pm.solm.cluster import build_tiles

        with storing(out):  # a worker's StorageError keeps its class through Ray (cluster.py)
            build_tiles(world, job, todo, ground, Path(out), finished)
    else:
        if isinstance(world, MapPoints) and not crop and world.size <= layout.crop_above:
            world = world.indexed(scan.threads)  # small enough to index whole: faster than crops
        crop = crop or isinstance(world, MapPoints)
        margin = crop_margin(job, world) if crop else None
        for ty, tx in todo:
            where = world.crop(job.bounds(ty, tx), margin, scan.threads) if crop else world
            arrays = compute_tile(where, job, ty, tx, job.ground(ground, ty, tx), scan.threads)
            with storing(out):
                cells = write_tile(group, job, ty, tx, arrays)
            finished(ty, tx, cells)
    return {
        "tiles": ty_n * tx_n,
        "built_now": len(todo),
        "complete": kept == ty_n * tx_n,
        "on_crops": engine == "ray" or bool(crop),
    }


def _integer(value) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)
