"""Building a SOLM: evaluate the metric at every cell of a grid, tile by tile,
resumable (see store.py)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from lf3pm import __version__, _core
from lf3pm.config import MetricConfig, ScanConfig, SolmConfig, validated
from lf3pm.errors import Lf3pmError
from lf3pm.map import Map
from lf3pm.sensors import Sensor, get_sensor
from lf3pm.solm.grid import SolmGrid
from lf3pm.solm.store import CHANNELS, TILE, open_or_create, tiles_shape
from lf3pm.solm.ray_thinning import thin_rays
from lf3pm.solm.yaw_reuse import sector_layout
from lf3pm.terrain import body_blocked, column_minimum

_SCAN, _METRIC, _SOLM = ScanConfig(), MetricConfig(), SolmConfig()


def build_solm(world: Map, sensor: Sensor, grid: SolmGrid, out: Path, *, seed: int = _SCAN.seed,
               noise: float | None = _SCAN.noise, robot_radius: float = _SOLM.robot_radius,
               floor_clearance: float = 0.2, association: str = _METRIC.association, w1: float = _METRIC.w1,
               threads: int = _SCAN.threads, yaw_reuse: bool = _SOLM.yaw_reuse, ray_stride: int = _SOLM.ray_stride,
               tile: int = TILE, max_tiles: int | None = None, progress=None) -> dict:
    """Builds (or resumes) the SOLM of ``world`` for ``sensor`` (a Sensor or a preset
    name) on ``grid`` into the Zarr store ``out``. Cell c (linear index over the
    channel's shape) uses noise stream c, so results do not depend on tiling or resumption.
    ``yaw_reuse`` (se2 only) scans each yaw sector once and sums sector Grams
    per bin (yaw_reuse.py): about 2F+1 times faster, approximate (docs/solm.md).
    ``ray_stride`` K casts every K-th azimuth column of the pattern and scales
    the Gram up (ray_thinning.py): about K times faster, approximate.
    ``tile`` is the tile (and Zarr chunk) edge in cells; ``max_tiles`` stops
    after that many tiles (for tests of resumption). The parameters are validated
    by lf3pm.config's ScanConfig, MetricConfig and SolmConfig."""
    scan = validated(ScanConfig, "scan", noise=noise, seed=seed, threads=threads)
    metric = validated(MetricConfig, "metric", association=association, w1=w1)
    layout = validated(SolmConfig, "solm", robot_radius=robot_radius, yaw_reuse=yaw_reuse, ray_stride=ray_stride)
    seed, threads, association, w1 = scan.seed, scan.threads, metric.association, metric.w1
    robot_radius, yaw_reuse, ray_stride = layout.robot_radius, layout.yaw_reuse, layout.ray_stride
    if isinstance(sensor, str):
        sensor = get_sensor(sensor)
    sigma = scan.noise_for(sensor)
    if not (math.isfinite(floor_clearance) and floor_clearance >= 0):
        raise Lf3pmError(f"floor clearance must be a number >= 0 m, got {floor_clearance}")
    if tile < 1:
        raise Lf3pmError(f"tile must be >= 1, got {tile}")
    ground_robot = grid.space != "r3"
    if yaw_reuse and grid.space != "se2":
        raise Lf3pmError("yaw reuse applies to se2 grids only")
    sectors = sector_layout(sensor, grid.yaw_bins) if yaw_reuse else None
    if sectors is not None:
        sector_rays, ray_weight = thin_rays(sectors[0], ray_stride)
    else:
        directions, ray_weight = thin_rays(sensor.directions, ray_stride)
    params = metric.core(scan.core(sensor), ray_weight)
    attrs = {"lf3pm_version": __version__, "grid": grid.to_dict(), "sensor": sensor.name,
             "sensor_rays": sensor.num_rays, "noise": sigma, "seed": int(seed),
             "w1": w1, "w2": 1.0 - w1, "association": association, "robot_radius": robot_radius,
             "floor_clearance": floor_clearance, "map_sha256": world.sha256,
             "map_source": world.source, "channels": list(CHANNELS),
             "noise_stream": "linear cell index over the channel shape (yaw reuse: "
                             "2D cell index * yaw_bins + sector)", "tile": tile,
             "yaw_reuse": bool(yaw_reuse), "ray_stride": int(ray_stride)}
    ground = (column_minimum(world.points, grid.x0, grid.y0, grid.res, grid.nx, grid.ny)
              if ground_robot else None)
    group = open_or_create(out, attrs, grid.shape, ground_robot, tile)
    if ground_robot:
        group["ground_z"][...] = np.where(np.isfinite(ground), ground, np.nan).astype(np.float32)
    done = group["done"][...]
    ty_n, tx_n = tiles_shape(grid.ny, grid.nx, tile)
    todo = [(ty, tx) for ty in range(ty_n) for tx in range(tx_n) if not done[ty, tx]]
    if max_tiles is not None:
        todo = todo[:max_tiles]
    xs, ys = grid.xs(), grid.ys()
    for ty, tx in todo:
        ys_ = slice(ty * tile, min(grid.ny, (ty + 1) * tile))
        xs_ = slice(tx * tile, min(grid.nx, (tx + 1) * tile))
        yy, xx = np.meshgrid(ys[ys_], xs[xs_], indexing="ij")
        layer_shape = (grid.layers,) + yy.shape
        if ground_robot:
            g = np.broadcast_to(ground[ys_, xs_], layer_shape)
            z = g + grid.height
            unknown = ~np.isfinite(g)
            yaw = np.broadcast_to(grid.yaws()[:, None, None], layer_shape)
        else:
            z = np.broadcast_to(np.asarray(grid.z_levels)[:, None, None], layer_shape)
            unknown = np.zeros(layer_shape, bool)
            yaw = np.zeros(layer_shape)
        X, Y = np.broadcast_to(xx, layer_shape), np.broadcast_to(yy, layer_shape)
        obstacle = np.zeros(layer_shape, bool)
        known = ~unknown
        low = z if not ground_robot else np.minimum(z, g + floor_clearance + robot_radius)
        obstacle[known] = body_blocked(world, X[known], Y[known], low[known], z[known], robot_radius)
        valid = ~unknown & ~obstacle
        cell_index = np.ravel_multi_index(
            np.meshgrid(np.arange(grid.layers), np.arange(grid.ny)[ys_], np.arange(grid.nx)[xs_],
                        indexing="ij"), (grid.layers, grid.ny, grid.nx))
        values = {name: np.full(layer_shape, np.nan, np.float32) for name in CHANNELS}
        degenerate = np.zeros(layer_shape, np.uint8)
        if valid.any() and sectors is not None:
            # Validity depends on x, y only: every bin of a cell is valid or none is.
            cell2d = valid[0]
            positions = np.ascontiguousarray(np.stack([xx[cell2d], yy[cell2d], z[0][cell2d]], axis=1))
            res = _core.evaluate_yaw_sectors(world.index, positions,
                                             cell_index[0][cell2d].astype(np.uint64), sector_rays,
                                             grid.yaw_bins, sectors[1], params)
            for name in CHANNELS:
                values[name][:, cell2d] = res[name].T
            degenerate[:, cell2d] = res["degenerate"].T.astype(np.uint8)
        elif valid.any():
            poses = _pose_matrices(X[valid], Y[valid], z[valid], yaw[valid])
            res = _core.evaluate_many(world.index, poses, cell_index[valid].astype(np.uint64),
                                      directions, params)
            for name in CHANNELS:
                values[name][valid] = res[name]
            degenerate[valid] = res["degenerate"].astype(np.uint8)
        region = (slice(None),) * (0 if grid.space == "r2" else 1) + (ys_, xs_)
        squeeze = (lambda a: a[0]) if grid.space == "r2" else (lambda a: a)
        for name in CHANNELS:
            group[name][region] = squeeze(values[name])
        group["obstacle"][region] = squeeze(obstacle.astype(np.uint8))
        group["unknown"][region] = squeeze(unknown.astype(np.uint8))
        group["degenerate"][region] = squeeze(degenerate)
        group["done"][ty, tx] = 1  # last: the tile counts only once all its data are on disk
        if progress:
            progress(int(np.prod(layer_shape)), grid.layers * grid.ny * grid.nx)
    return {"tiles": ty_n * tx_n, "built_now": len(todo),
            "complete": bool(group["done"][...].all())}


def _pose_matrices(x, y, z, yaw) -> np.ndarray:
    n = len(x)
    T = np.zeros((n, 4, 4))
    c, s = np.cos(yaw), np.sin(yaw)
    T[:, 0, 0], T[:, 0, 1], T[:, 1, 0], T[:, 1, 1] = c, -s, s, c
    T[:, 2, 2] = T[:, 3, 3] = 1.0
    T[:, 0, 3], T[:, 1, 3], T[:, 2, 3] = x, y, z
    return np.ascontiguousarray(T)
