"""SOLM builds: cells equal evaluate(), resumption is exact, queries and masks."""

import hashlib
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import lf3pm
from lf3pm import _core
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Grid
from lf3pm.io import write_points
from lf3pm.metric import eval_params
from lf3pm.planner.esdf import Esdf
from lf3pm.pose import pose_matrix
from lf3pm.scenes import build_scene
from lf3pm.solm import Solm, build_solm, make_grid
from lf3pm.solm.occupancy import grid_occupancy, occupancy_factor
from lf3pm.solm.ray_thinning import thin_rays
from lf3pm.terrain import column_minimum, occupied_cells

BOUNDS = (-3.5, -3.5, 3.5, 3.5)


@pytest.fixture(scope="module")
def boxes():
    scene = build_scene("boxes")
    return scene, lf3pm.load_map(scene.points), lf3pm.get_sensor("vlp16")


@pytest.fixture(scope="module")
def built(boxes, tmp_path_factory):
    _, world, sensor = boxes
    grid = make_grid(world, "se2", 1.0, bounds=BOUNDS, yaw_bins=4, height=1.0)
    path = tmp_path_factory.mktemp("solm") / "full.zarr"
    build_solm(world, sensor, grid, path, tile=3)
    return path, grid


def store_digest(path: Path) -> str:
    h = hashlib.sha256()
    for f in sorted(p for p in path.rglob("*") if p.is_file()):
        h.update(str(f.relative_to(path)).encode())
        h.update(f.read_bytes())
    return h.hexdigest()


@pytest.mark.slow
def test_a_cell_equals_evaluate_at_its_centre(boxes, built):
    _, world, sensor = boxes
    path, grid = built
    solm = Solm.open(path)
    x, y, yaw = solm.grid()
    q = solm.channel("q_n")
    ground = solm.channel("ground_z")
    k, iy, ix = np.argwhere(np.isfinite(q))[5]
    cell = np.ravel_multi_index((k, iy, ix), q.shape)
    pose = pose_matrix((x[k, iy, ix], y[k, iy, ix], ground[iy, ix] + 1.0, yaw[k, iy, ix]))
    ref = _core.evaluate(
        world.index,
        pose,
        sensor.directions,
        eval_params(sensor.min_range, sensor.max_range, noise=sensor.range_noise_sigma, seed=0, stream=int(cell)),
    )
    assert q[k, iy, ix] == pytest.approx(ref.metric.q_n, rel=1e-6)  # stored as float32


def test_a_sensor_that_loses_returns_builds_cells_that_lose_them_as_evaluate_does(boxes, tmp_path):
    """A fitted sensor's return model reaches the SOLM's casts: a cell equals evaluate with
    the same model and noise stream, differs from the cell of the sensor that returns
    every hit, and the store records the model."""
    from dataclasses import replace

    from lf3pm.sensors import ReturnModel

    _, world, vlp16 = boxes
    sensor = replace(vlp16, returns=ReturnModel((0.1, 100.0), (0.0, 1.0), [[0.5]]))
    grid = make_grid(world, "r2", 1.0, bounds=(-1.5, -1.5, 1.5, 1.5), height=1.0)
    lossy, full = tmp_path / "lossy.zarr", tmp_path / "full.zarr"
    build_solm(world, sensor, grid, lossy, tile=4)
    build_solm(world, vlp16, grid, full, tile=4)
    solm = Solm.open(lossy)
    assert solm.attrs["sensor_returns"] == sensor.returns.to_yaml()
    x, y = solm.grid()
    q, ground = solm.channel("q_n"), solm.channel("ground_z")
    iy, ix = np.argwhere(np.isfinite(q))[3]
    cell = np.ravel_multi_index((iy, ix), q.shape)
    pose = pose_matrix((x[iy, ix], y[iy, ix], ground[iy, ix] + 1.0, 0.0))
    limits = (vlp16.min_range, vlp16.max_range)
    params = eval_params(*limits, noise=vlp16.range_noise_sigma, seed=0, stream=int(cell), returns=sensor.returns)
    ref = _core.evaluate(world.index, pose, sensor.directions, params)
    assert q[iy, ix] == pytest.approx(ref.metric.q_n, rel=1e-6)  # stored as float32
    assert ref.hits < 0.6 * _core.evaluate(world.index, pose, sensor.directions, eval_params(*limits)).hits
    assert Solm.open(full).channel("q_n")[iy, ix] != q[iy, ix]


@pytest.mark.slow
def test_resume_after_interruption_is_bitwise_identical(boxes, built, tmp_path):
    _, world, sensor = boxes
    path, grid = built
    partial = tmp_path / "resumed.zarr"
    first = build_solm(world, sensor, grid, partial, tile=3, max_tiles=2)
    assert not first["complete"]
    with pytest.raises(Lf3pmError, match="unfinished"):
        Solm.open(partial)
    second = build_solm(world, sensor, grid, partial, tile=3)
    assert second["complete"] and second["built_now"] == first["tiles"] - 2
    assert store_digest(partial) == store_digest(path)


@pytest.mark.slow
def test_a_store_from_other_parameters_is_refused(boxes, built):
    _, world, sensor = boxes
    path, grid = built
    with pytest.raises(Lf3pmError, match="other parameters"):
        build_solm(world, sensor, grid, path, tile=3, robot_radius=0.5)


def test_query_interpolates_and_its_gradient_matches_finite_differences(built):
    solm = Solm.open(built[0])
    rng = np.random.default_rng(0)
    q = solm.channel("q_n")
    for _ in range(20):
        x, y, yaw = rng.uniform(-2.5, 2.5), rng.uniform(-2.5, 2.5), rng.uniform(-np.pi, np.pi)
        value, grad = solm.query(x, y, yaw)
        if not np.isfinite(value):
            continue
        h = 1e-6
        num = [
            (solm.query(x + h, y, yaw)[0] - solm.query(x - h, y, yaw)[0]) / (2 * h),
            (solm.query(x, y + h, yaw)[0] - solm.query(x, y - h, yaw)[0]) / (2 * h),
            (solm.query(x, y, yaw + h)[0] - solm.query(x, y, yaw - h)[0]) / (2 * h),
        ]
        np.testing.assert_allclose(grad, num, rtol=1e-4, atol=1e-9)
    # At a cell centre the query returns the cell; yaw is periodic.
    xs, ys, yaws = solm.grid()
    k, iy, ix = np.argwhere(np.isfinite(q))[0]
    assert solm.query(xs[k, iy, ix], ys[k, iy, ix], yaws[k, iy, ix])[0] == pytest.approx(q[k, iy, ix])
    cx, cy = xs[k, iy, ix], ys[k, iy, ix]
    assert np.isfinite(solm.query(cx, cy, 0.3)[0])
    assert solm.query(cx, cy, 0.3)[0] == pytest.approx(solm.query(cx, cy, 0.3 + 2 * np.pi)[0])


@pytest.mark.slow
def test_masks_mark_boxes_as_obstacles_and_the_free_pad_as_free(boxes, tmp_path):
    scene, world, sensor = boxes
    grid = make_grid(world, "r2", 0.5, bounds=(-4, -4, 8, 4), height=1.0)
    path = tmp_path / "r2.zarr"
    build_solm(world, sensor, grid, path, noise=0.0)
    solm = Solm.open(path)
    obstacle = solm.channel("obstacle")
    x, y = solm.grid()
    centre = np.argmin(np.hypot(x, y))  # the reference pose is free
    assert obstacle.ravel()[centre] == 0 and np.isfinite(solm.channel("q_n").ravel()[centre])
    # Cells against the room's walls are obstacles, and obstacles are not evaluated.
    assert obstacle[:, 0].all() and np.isnan(solm.channel("q_n")[obstacle == 1]).all()
    # r2 queries: bilinear, gradient (d/dx, d/dy) against central differences.
    value, grad = solm.query(0.37, -0.21)
    h = 1e-6
    num = [
        (solm.query(0.37 + h, -0.21)[0] - solm.query(0.37 - h, -0.21)[0]) / (2 * h),
        (solm.query(0.37, -0.21 + h)[0] - solm.query(0.37, -0.21 - h)[0]) / (2 * h),
    ]
    assert np.isfinite(value) and grad.shape == (2,)
    np.testing.assert_allclose(grad, num, rtol=1e-4)


@pytest.mark.parametrize("res", [1.0, 0.25])
def test_occupied_cells_equal_a_cell_by_cell_reference(res):
    rng = np.random.default_rng(11)
    points = np.column_stack([rng.uniform(-1, 4, 3000), rng.uniform(-1, 3, 3000), rng.uniform(-0.5, 2.5, 3000)])
    nx, ny = int(3 / res), int(2 / res)
    bottom = rng.uniform(0.0, 1.0, (ny, nx))
    top = bottom + rng.uniform(0.0, 0.8, (ny, nx))
    bottom[0, 0] = np.inf  # an unknown cell is never occupied
    occupied = occupied_cells(points, Grid.plane(0.0, 0.0, res, nx, ny), bottom, top)
    reference = np.zeros_like(occupied)
    for j, i in np.ndindex(*occupied.shape):
        inside = (
            (points[:, 0] >= i * res)
            & (points[:, 0] < (i + 1) * res)
            & (points[:, 1] >= j * res)
            & (points[:, 1] < (j + 1) * res)
        )
        reference[j, i] = np.any(inside & (points[:, 2] >= bottom[j, i]) & (points[:, 2] <= top[j, i]))
    np.testing.assert_array_equal(occupied, reference)
    assert occupied.any() and not occupied[0, 0]


def test_a_slope_is_ground_and_a_pole_on_it_is_not():
    # A 25 % grade on 1 m cells: each SOLM cell's ground rises 0.25 m across it, more than
    # the floor clearance (0.2 m) above its lowest point, yet none of it is an obstacle.
    xs = np.arange(0.0, 8.001, 0.05)
    slope = np.array([(x, y, 0.25 * x) for x in xs for y in np.arange(-2.0, 2.001, 0.05)])
    pole = np.array([(4.55, 0.35, 0.25 * 4.55 + z) for z in np.arange(0.3, 1.2, 0.05)])
    world = lf3pm.load_map(np.vstack([slope, pole]))
    grid = make_grid(world, "r2", 1.0, bounds=(0, -2, 8, 2), height=1.0)
    ground = column_minimum(world.points, grid)
    occupied = grid_occupancy(world.points, grid, ground, 0.3, 0.2)
    k = occupancy_factor(grid)
    assert {tuple(c) for c in np.argwhere(occupied)} == {(int((0.35 + 2) * k), int(4.55 * k))}


def test_the_planner_keeps_the_body_off_thin_poles_between_cell_centres(tmp_path):
    # A floor and poles at random spots, most more than the robot radius from every
    # centre of a 1 m grid (the obstacle mask, probing the body at centres, misses
    # them): wherever the planner's ESDF says the body is clear, no pole is within the radius.
    rng = np.random.default_rng(7)
    xs = np.arange(-3.0, 3.001, 0.1)
    floor = np.array([(x, y, 0.0) for x in xs for y in xs])
    spots = rng.uniform(-2.8, 2.8, (8, 2))
    poles = np.array([(px, py, z) for px, py in spots for z in np.arange(0.3, 1.5, 0.05)])
    world, sensor = lf3pm.load_map(np.vstack([floor, poles])), lf3pm.get_sensor("vlp16")
    radius = 0.3
    grid = make_grid(world, "r2", 1.0, bounds=(-3, -3, 3, 3), height=1.0)
    build_solm(world, sensor, grid, tmp_path / "s.zarr", noise=0.0, robot_radius=radius, ray_stride=8)
    solm = Solm.open(tmp_path / "s.zarr")
    occupied, k = solm.occupancy()
    assert k == 10 and occupied.shape == (60, 60)
    # Each pole marks exactly the occupancy cell it stands in; the floor marks none.
    cells = {(int(np.floor((py + 3) * k)), int(np.floor((px + 3) * k))) for px, py in spots}
    assert {tuple(c) for c in np.argwhere(occupied)} == cells
    esdf = Esdf.from_solm(solm)
    px, py = rng.uniform(-3, 3, (2, 20000))
    clearance = esdf.distance(px, py)[0]
    true = np.min(np.hypot(px[:, None] - spots[:, 0], py[:, None] - spots[:, 1]), axis=1) - radius
    assert np.all(clearance <= true + 1e-9)
    assert np.mean(clearance >= 0) > 0.3  # and it leaves room to move


@pytest.mark.parametrize(
    "kwargs,needle",
    [
        ({"bounds": (100, 100, 110, 110)}, "outside"),
        ({"res": 0.0}, "solm.res must be greater than 0"),
        ({"space": "se3"}, "solm.space must be"),
    ],
)
def test_bad_grids_are_refused(boxes, kwargs, needle):
    _, world, _ = boxes
    args = {"space": "r2", "res": 1.0, **kwargs}
    with pytest.raises(Lf3pmError, match=needle):
        make_grid(world, args.pop("space"), args.pop("res"), **args)


@pytest.mark.slow
def test_cli_unwritable_output_and_unknown_sensor_leave_no_store(boxes, tmp_path):
    scene, _, _ = boxes
    map_path = tmp_path / "boxes.pcd"
    write_points(map_path, scene.points)
    # A regular file where a folder should be: writing fails as on a read-only
    # or full disk, even for root (which permissions do not stop).
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("")
    for extra, needle in (
        (["-o", str(blocker / "s.zarr")], "cannot write"),
        (["-o", str(tmp_path / "s.zarr"), "--sensor", "nosuch"], "unknown sensor"),
        (["-o", str(tmp_path / "s.zarr"), "--res", "0"], "--res must be greater than 0"),
    ):
        out = subprocess.run(
            [sys.executable, "-m", "lf3pm.cli", "solm", "build", str(map_path), "--res", "2", *extra],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert out.returncode == 2 and needle in out.stderr and "Traceback" not in out.stderr, out.stderr
    assert not (tmp_path / "s.zarr").exists() and blocker.is_file()


@pytest.mark.slow
def test_se2_yaw_reuse_is_close_to_exact_per_yaw_evaluation(boxes, tmp_path):
    _, world, _ = boxes
    mid70 = lf3pm.get_sensor("mid70")
    # 36 bins: the Mid-70's 70 degrees span 7 sectors of 10 degrees (with 12 bins the
    # 3 summed sectors span 90 degrees, and the p95 error reaches 49 %).
    grid = make_grid(world, "se2", 0.5, bounds=(-0.75, -0.75, 0.75, 0.75), yaw_bins=36, height=1.0)
    build_solm(world, mid70, grid, tmp_path / "exact.zarr", noise=0.0)
    build_solm(world, mid70, grid, tmp_path / "reuse.zarr", noise=0.0, yaw_reuse=True)
    exact = Solm.open(tmp_path / "exact.zarr").channel("q_n")
    reuse = Solm.open(tmp_path / "reuse.zarr").channel("q_n")
    ok = np.isfinite(exact) & np.isfinite(reuse)
    assert ok.sum() > 200
    rel = np.abs(reuse[ok] / exact[ok] - 1)
    # Measured on houses and meadow (Mid-70, 36 bins): median 5-11 %, p95 12-18 %.
    assert np.median(rel) < 0.2 and np.percentile(rel, 95) < 0.4
    with pytest.raises(Lf3pmError, match="se2"):
        build_solm(world, mid70, make_grid(world, "r2", 1.0), tmp_path / "r2.zarr", yaw_reuse=True)


def test_thinned_rays_keep_whole_azimuth_columns_and_their_weight():
    vlp16 = lf3pm.get_sensor("vlp16")
    kept, weight = thin_rays(vlp16.directions, 4)
    azimuths = np.round(np.arctan2(kept[:, 1], kept[:, 0]), 9)
    _, per_column = np.unique(azimuths, return_counts=True)
    assert np.all(per_column == 16)  # every ring survives
    assert len(per_column) == 1800 // 4 and weight == pytest.approx(4.0)
    assert thin_rays(vlp16.directions, 1)[1] == 1.0
    with pytest.raises(Lf3pmError, match="stride"):
        thin_rays(vlp16.directions, 0)


def test_ray_weight_equals_casting_each_ray_that_many_times(boxes):
    _, world, sensor = boxes
    pose = pose_matrix((0.5, -0.5, 1.0, 0.3))[None]
    dirs = np.ascontiguousarray(sensor.directions[::7])
    args = (world.index, pose, np.zeros(1, np.uint64))
    tripled = _core.evaluate_many(
        *args, np.ascontiguousarray(np.repeat(dirs, 3, axis=0)), eval_params(sensor.min_range, sensor.max_range)
    )
    weighted = _core.evaluate_many(*args, dirs, eval_params(sensor.min_range, sensor.max_range, ray_weight=3.0))
    for name in ("q_min", "q_n", "q_max", "sigma1", "m"):
        assert weighted[name][0] == pytest.approx(tripled[name][0], rel=1e-9)


def test_thinned_build_is_close_to_exact(boxes, built, tmp_path):
    _, world, sensor = boxes
    path, grid = built
    build_solm(world, sensor, grid, tmp_path / "thin.zarr", ray_stride=4)
    exact = Solm.open(path).channel("q_n")
    thin = Solm.open(tmp_path / "thin.zarr")
    assert thin.attrs["ray_stride"] == 4
    q = thin.channel("q_n")
    ok = np.isfinite(exact) & np.isfinite(q)
    rel = np.abs(q[ok] / exact[ok] - 1)
    # Measured on gobi (bench/bench_solm.py, stride 4): median 1.8 %, p95 4.4 %.
    assert ok.sum() > 50 and np.median(rel) < 0.05 and np.percentile(rel, 95) < 0.15


@pytest.mark.slow
def test_the_same_map_by_another_path_resumes_the_build(boxes, tmp_path, monkeypatch):
    scene, _, sensor = boxes
    write_points(tmp_path / "boxes.pcd", scene.points)
    monkeypatch.chdir(tmp_path)
    relative, absolute = lf3pm.load_map("boxes.pcd"), lf3pm.load_map(tmp_path / "boxes.pcd")
    assert relative.source != absolute.source and relative.sha256 == absolute.sha256
    grid = make_grid(relative, "r2", 1.0, bounds=BOUNDS)
    first = build_solm(relative, sensor, grid, tmp_path / "s.zarr", tile=3, max_tiles=1)
    second = build_solm(absolute, sensor, grid, tmp_path / "s.zarr", tile=3)
    assert not first["complete"] and second["complete"] and second["built_now"] == first["tiles"] - 1
