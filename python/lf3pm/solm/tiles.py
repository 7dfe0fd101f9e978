"""One SOLM tile: its poses, masks and metric, computed from a map (the whole map or
the tile's crop) and written into the store. The engines (build.py: here, or on a Ray
cluster: cluster.py) only decide where each tile is computed.

A tile's crop is exact (docs/scale.md): a pose p of the tile sees only hits h with
|h - p| <= R (the sensor's maximum range). The hit lies on a disc of centre c and
radius r <= r_max = max(min(3 cell, d_nb), 0.75 spacing), so |c - p| <= R + r_max; the disc's plane and
radius come from c's k nearest points within d_nb (the association's neighbour gate),
and k-NN association at h reads points within d_nb of h. Every point the tile's
results depend on therefore lies within R + r_max + d_nb of a pose, horizontally too;
the crop keeps every point within that margin of the tile's poses in x and y, and
points it holds with cut-off neighbourhoods lie farther than R + r_max, where no ray
of the tile reaches their discs. The crop is indexed in the whole map's frame
(MapFrame: the same grid origins, cell size and spacing), so each of those values
is computed by the same float operations: the tile is bitwise the whole map's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lf3pm import _core
from lf3pm.config import DEFAULTS, MetricConfig, ScanConfig, SolmConfig, core_struct, scan_params
from lf3pm.grid import Space
from lf3pm.map import Map, MapPoints
from lf3pm.sensors import ReturnModel
from lf3pm.solm.grid import SolmGrid
from lf3pm.solm.ray_thinning import thin_rays
from lf3pm.solm.store import CHANNELS, chunk_path, writing
from lf3pm.solm.yaw_reuse import sector_layout
from lf3pm.terrain import body_blocked


@dataclass(frozen=True)
class TileJob:
    """Everything a tile needs besides its map; plain data, so that it travels to cluster workers."""

    grid: SolmGrid
    tile: int
    rays: np.ndarray  # the sensor's directions, or its sector rays under yaw reuse
    sector_half_width: int | None  # yaw reuse: sectors summed on each side of a bin; None: off
    ray_weight: float
    min_range: float
    max_range: float
    noise: float
    seed: int
    returns: ReturnModel | None  # the sensor's: which hits return
    mount: tuple | None  # r3yaw: the sensor-to-body 4 x 4 (lf3pm.flight.mounts), rows as tuples
    yaw_once: bool  # r3yaw: every yaw bin of a cell from the cast at bin 0 (yaw_invariant)
    metric: MetricConfig
    robot_radius: float
    floor_clearance: float

    def params(self, threads: int) -> _core.EvalParams:
        """The core's evaluation parameters, with ``threads`` workers."""
        scan = scan_params(
            self.min_range, self.max_range, noise=self.noise, seed=self.seed, threads=threads, returns=self.returns
        )
        return self.metric.core(scan, self.ray_weight)

    def slices(self, ty: int, tx: int) -> tuple[slice, slice]:
        """The tile's (y, x) cell slices."""
        grid, t = self.grid, self.tile
        return slice(ty * t, min(grid.ny, (ty + 1) * t)), slice(tx * t, min(grid.nx, (tx + 1) * t))

    def ground(self, ground: np.ndarray | None, ty: int, tx: int) -> np.ndarray | None:
        """The tile's part of the grid's ground heights (None for aerial grids)."""
        return None if ground is None else ground[self.slices(ty, tx)]

    def bounds(self, ty: int, tx: int) -> tuple[float, float, float, float]:
        """x-y extent (xmin, ymin, xmax, ymax) of the tile's poses (its cell centres)."""
        ys, xs = self.slices(ty, tx)
        cx, cy = self.grid.xs()[xs], self.grid.ys()[ys]
        return float(cx[0]), float(cy[0]), float(cx[-1]), float(cy[-1])


def make_job(
    sensor,
    grid: SolmGrid,
    scan: ScanConfig = DEFAULTS.scan,
    metric: MetricConfig = DEFAULTS.metric,
    solm: SolmConfig = DEFAULTS.solm,
    mount: np.ndarray | None = None,
) -> TileJob:
    """The job of a build with these sections (build_solm): the sensor's rays, thinned by
    the solm section's ``ray_stride`` and, under ``yaw_reuse``, laid out in yaw sectors;
    the noise the scan section's or the sensor's; ``mount`` (r3yaw): the sensor-to-body
    4 x 4, the body level at each cell's height and yaw."""
    sectors = sector_layout(sensor, grid.yaw_bins) if solm.yaw_reuse else None
    rays, ray_weight = thin_rays(sensor.directions if sectors is None else sectors[0], solm.ray_stride)
    mount = None if mount is None or grid.space is not Space.R3YAW else np.asarray(mount, dtype=np.float64)
    return TileJob(
        grid=grid,
        tile=solm.tile,
        rays=rays,
        sector_half_width=None if sectors is None else sectors[1],
        ray_weight=ray_weight,
        min_range=float(sensor.min_range),
        max_range=float(sensor.max_range),
        noise=float(scan.noise_for(sensor)),
        seed=int(scan.seed),
        returns=sensor.returns,
        mount=None if mount is None else tuple(map(tuple, mount)),
        yaw_once=grid.space is Space.R3YAW and yaw_invariant(rays, grid.yaw_bins, mount),
        metric=metric,
        robot_radius=float(solm.robot_radius),
        floor_clearance=float(solm.floor_clearance),
    )


def yaw_invariant(rays: np.ndarray, yaw_bins: int, mount: np.ndarray | None) -> bool:
    """Whether turning the body by one yaw bin only permutes the sensor's rays in the world:
    the mount keeps the sensor on the body's vertical axis and its z axis vertical, and the
    rays turned by 2 pi / yaw_bins about z are the rays themselves (a 360-degree spinning
    sensor whose columns the bins divide). Then every bin of a cell sees the same hits and
    one cast gives them all (the Gram summed in another order: docs/flight.md measures it)."""
    if mount is not None:
        m = np.asarray(mount)
        if np.abs(m[:2, 3]).max() > 0 or np.abs(m[:3, 2] - [0, 0, 1]).max() > 1e-12:
            return False
    from scipy.spatial import cKDTree

    a = 2 * np.pi / yaw_bins
    turn = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    if mount is not None:  # the rays as the body carries them
        rays = rays @ np.asarray(mount)[:3, :3].T
    gap, _ = cKDTree(rays).query(rays @ turn.T)
    return bool(gap.max() < 1e-9)


def crop_margin(job: TileJob, world: Map | MapPoints) -> float:
    """How far (x, y) beyond a tile's poses its crop must reach to be exact (module docstring)."""
    neighbour = float(world.association_params["max_neighbor_distance"])
    disc = _core.largest_disc(world.frame, core_struct(_core.MapParams(), max_neighbor_distance=neighbour))
    return job.max_range + disc + neighbour


def compute_tile(
    world: Map, job: TileJob, ty: int, tx: int, ground: np.ndarray | None, threads: int
) -> dict[str, np.ndarray]:
    """The tile's channels and masks, each of shape (layers, tile rows, tile columns).

    ``world``: the whole map or the tile's crop; ``ground``: the tile's ground heights
    (rows, columns; NaN where unknown) for ground robots, else None.
    """
    grid = job.grid
    ys_, xs_ = job.slices(ty, tx)
    yy, xx = np.meshgrid(grid.ys()[ys_], grid.xs()[xs_], indexing="ij")
    layer_shape = (grid.layers,) + yy.shape
    ground_robot = ground is not None
    if ground_robot:
        g = np.broadcast_to(ground, layer_shape)
        z = g + grid.height
        unknown = ~np.isfinite(g)
        yaw = np.broadcast_to(grid.yaws()[:, None, None], layer_shape)
    else:
        levels, yaws = grid.layer_poses()
        z = np.broadcast_to(levels[:, None, None], layer_shape)
        unknown = np.zeros(layer_shape, bool)
        yaw = np.broadcast_to(yaws[:, None, None], layer_shape)
    X, Y = np.broadcast_to(xx, layer_shape), np.broadcast_to(yy, layer_shape)
    obstacle = np.zeros(layer_shape, bool)
    known = ~unknown
    low = z if not ground_robot else np.minimum(z, g + job.floor_clearance + job.robot_radius)
    obstacle[known] = body_blocked(world, X[known], Y[known], low[known], z[known], job.robot_radius)
    valid = ~unknown & ~obstacle
    cell_index = np.ravel_multi_index(
        np.meshgrid(np.arange(grid.layers), np.arange(grid.ny)[ys_], np.arange(grid.nx)[xs_], indexing="ij"),
        (grid.layers, grid.ny, grid.nx),
    )
    values = {name: np.full(layer_shape, np.nan, np.float32) for name in CHANNELS}
    degenerate = np.zeros(layer_shape, np.uint8)
    params = job.params(threads)
    if valid.any() and job.sector_half_width is not None:
        # Validity depends on x, y only: every bin of a cell is valid or none is.
        cell2d = valid[0]
        positions = np.ascontiguousarray(np.stack([xx[cell2d], yy[cell2d], z[0][cell2d]], axis=1))
        res = _core.evaluate_yaw_sectors(
            world.index,
            positions,
            cell_index[0][cell2d].astype(np.uint64),
            job.rays,
            grid.yaw_bins,
            job.sector_half_width,
            params,
        )
        for name in CHANNELS:
            values[name][:, cell2d] = res[name].T
        degenerate[:, cell2d] = res["degenerate"].T.astype(np.uint8)
    elif valid.any():
        # Under yaw_once only bin 0 of each height is cast; its values fill the other bins.
        cast = valid & (np.arange(grid.layers) % grid.yaw_bins == 0)[:, None, None] if job.yaw_once else valid
        poses = pose_matrices(X[cast], Y[cast], z[cast], yaw[cast])
        if job.mount is not None:
            poses = np.ascontiguousarray(poses @ np.asarray(job.mount))
        res = _core.evaluate_many(world.index, poses, cell_index[cast].astype(np.uint64), job.rays, params)
        for name in CHANNELS:
            values[name][cast] = res[name]
        degenerate[cast] = res["degenerate"].astype(np.uint8)
        if job.yaw_once:
            for array in (*values.values(), degenerate):
                shaped = array.reshape(-1, grid.yaw_bins, *array.shape[1:])
                shaped[:] = shaped[:, :1]
    return {
        **values,
        "obstacle": obstacle.astype(np.uint8),
        "unknown": unknown.astype(np.uint8),
        "degenerate": degenerate,
    }


def write_tile(group, job: TileJob, ty: int, tx: int, arrays: dict[str, np.ndarray]) -> int:
    """Writes a tile's arrays into the store's chunks (not its done flag); returns its cell
    count. A failed write (a full disk, an I/O error) is a StorageError naming the chunk."""
    ys_, xs_ = job.slices(ty, tx)
    r2 = job.grid.space is Space.R2
    region = (slice(None),) * (0 if r2 else 1) + (ys_, xs_)
    chunk = (0,) * (0 if r2 else 1) + (ty, tx)  # a tile is one chunk of every array
    for name, values in arrays.items():
        with writing(chunk_path(group, name, chunk)):
            group[name][region] = values[0] if r2 else values
    return int(np.prod(next(iter(arrays.values())).shape))


def pose_matrices(x, y, z, yaw) -> np.ndarray:
    """(n, 4, 4) sensor-to-world matrices of ground poses (x, y, z, yaw)."""
    n = len(x)
    T = np.zeros((n, 4, 4))
    c, s = np.cos(yaw), np.sin(yaw)
    T[:, 0, 0], T[:, 0, 1], T[:, 1, 0], T[:, 1, 1] = c, -s, s, c
    T[:, 2, 2] = T[:, 3, 3] = 1.0
    T[:, 0, 3], T[:, 1, 3], T[:, 2, 3] = x, y, z
    return np.ascontiguousarray(T)
