"""Scan simulation on maps of known geometry: hits on the surfaces, no
see-through, ranges and noise as specified."""

import numpy as np
import pytest
from analytic_scenes import (
    box_room,
    grid_plane,
    random_directions,
    ray_box_distance,
    rigid_transform,
    spinning_directions,
)
from scipy.spatial import cKDTree

from lf3pm import _core
from lf3pm.config import scan_params
from lf3pm.metric import eval_params

HALF = (4.0, 3.0, 1.5)


@pytest.fixture(scope="module")
def room():
    return _core.MapIndex(box_room(HALF, spacing=0.05))


def pose_at(x, y, z):
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def test_every_ray_in_a_closed_room_hits_a_wall_at_the_right_range(room):
    rng = np.random.default_rng(0)
    dirs = random_directions(rng, 20000)
    origin = np.array([0.7, -0.4, 0.2])
    scan = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(0.1, 100.0))
    assert len(scan["ray"]) == len(dirs)  # nothing escapes: no see-through
    expected = ray_box_distance(origin, dirs, HALF)
    got = np.linalg.norm(scan["sensor_points"], axis=1)
    # Within a centimetre everywhere (edges and corners round off over one disc),
    # and on the wall to rounding away from the edges.
    assert np.max(np.abs(got - expected)) < 0.01
    w = scan["world_points"]
    off_face = np.min(np.abs(np.abs(w) - np.asarray(HALF)), axis=1)
    interior = np.sum(np.abs(np.abs(w) - np.asarray(HALF)) < 0.1, axis=1) == 1
    assert np.max(off_face) < 0.01
    assert np.max(off_face[interior]) < 1e-6


def test_hits_on_a_wall_lie_on_its_plane_and_counts_match_geometry():
    # Wall x = 5, y in [-10, 10], z in [-2, 3], sampled every 5 cm.
    wall = grid_plane((5.0, -10.0, -2.0), (0, 1, 0), (0, 0, 1), 20.0, 5.0, 0.05)
    index = _core.MapIndex(np.ascontiguousarray(wall))
    dirs = spinning_directions(np.arange(-15, 16, 2), 1800)
    scan = _core.simulate_scan(index, pose_at(0, 0, 0), dirs, scan_params(0.5, 100.0))
    w = scan["world_points"]
    assert np.max(np.abs(w[:, 0] - 5.0)) < 0.01
    # Analytic: ray meets the plane x = 5 inside the rectangle. Discs of rim points
    # reach past the last sample by up to their radius (10 cm at a corner).
    with np.errstate(divide="ignore", invalid="ignore"):
        t = 5.0 / dirs[:, 0]
        hit_point = dirs * t[:, None]
    inside = (
        (dirs[:, 0] > 0)
        & (np.abs(hit_point[:, 1]) < 10.0 - 0.01)
        & (hit_point[:, 2] > -2.0 + 0.01)
        & (hit_point[:, 2] < 3.0 - 0.01)
    )
    rim = (
        (dirs[:, 0] > 0)
        & (np.abs(hit_point[:, 1]) < 10.0 + 0.1)
        & (hit_point[:, 2] > -2.0 - 0.1)
        & (hit_point[:, 2] < 3.0 + 0.1)
    )
    hit_rays = np.zeros(len(dirs), bool)
    hit_rays[scan["ray"]] = True
    assert np.all(hit_rays[inside])
    assert not np.any(hit_rays & ~rim)


def test_nothing_is_seen_through_a_wall():
    near = grid_plane((3.0, -5.0, -5.0), (0, 1, 0), (0, 0, 1), 10.0, 10.0, 0.05)
    far = grid_plane((6.0, -8.0, -8.0), (0, 1, 0), (0, 0, 1), 16.0, 16.0, 0.05)
    index = _core.MapIndex(np.ascontiguousarray(np.vstack([near, far])))
    dirs = random_directions(np.random.default_rng(1), 20000)
    dirs = np.ascontiguousarray(dirs[dirs[:, 0] > 0])
    scan = _core.simulate_scan(index, pose_at(0, 0, 0), dirs, scan_params(0.1, 100.0))
    w = scan["world_points"]
    t = 3.0 / dirs[scan["ray"], 0]
    p = dirs[scan["ray"]] * t[:, None]
    behind_near = (np.abs(p[:, 1]) < 4.99) & (np.abs(p[:, 2]) < 4.99)
    assert np.all(np.abs(w[behind_near, 0] - 3.0) < 0.01)


def test_min_and_max_range(room):
    dirs = random_directions(np.random.default_rng(2), 2000)
    origin = np.zeros(3)
    # Walls are 1.5 to ~5.2 m away.
    none = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(0.1, 1.4))
    assert len(none["ray"]) == 0
    blocked = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(6.0, 100.0))
    assert len(blocked["ray"]) == 0  # walls nearer than min_range block, never reveal
    some = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(2.5, 3.5))
    r = np.linalg.norm(some["sensor_points"], axis=1)
    assert len(r) > 0 and r.min() >= 2.5 and r.max() <= 3.5
    expected = ray_box_distance(origin, dirs, HALF)
    clearly_inside = np.nonzero((expected >= 2.5 + 0.01) & (expected <= 3.5 - 0.01))[0]
    assert set(clearly_inside) <= set(some["ray"])  # every ray whose wall is in range returns
    assert np.all((expected[some["ray"]] > 2.49) & (expected[some["ray"]] < 3.51))


def test_range_noise_is_gaussian_and_seeded(room):
    dirs = random_directions(np.random.default_rng(3), 30000)
    origin = np.array([0.1, 0.2, 0.3])
    clean = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(0.1, 100.0))
    a = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(0.1, 100.0, noise=0.02, seed=7))
    b = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(0.1, 100.0, noise=0.02, seed=7, threads=1))
    c = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(0.1, 100.0, noise=0.02, seed=8))
    np.testing.assert_array_equal(a["sensor_points"], b["sensor_points"])  # any thread count
    assert not np.array_equal(a["sensor_points"], c["sensor_points"])
    err = np.linalg.norm(a["sensor_points"], axis=1) - np.linalg.norm(clean["sensor_points"], axis=1)
    assert abs(np.std(err) - 0.02) < 0.001 and abs(np.mean(err)) < 0.001


def test_knn_matches_brute_force():
    rng = np.random.default_rng(4)
    pts = np.ascontiguousarray(np.vstack([box_room(HALF, 0.1), rng.uniform(-4, 4, size=(3000, 3))]))
    index = _core.MapIndex(pts)
    queries = np.ascontiguousarray(rng.uniform(-4.5, 4.5, size=(2000, 3)))
    idx, dist = index.nearest(queries, 5, 2.0)
    ref_d, _ = cKDTree(index.points).query(queries, k=5)
    ref_d = np.where(ref_d <= 2.0, ref_d, np.inf)
    np.testing.assert_allclose(dist, ref_d, rtol=1e-12)
    found = idx >= 0
    np.testing.assert_allclose(
        np.linalg.norm(index.points[idx[found]] - np.repeat(queries, 5, 0).reshape(-1, 5, 3)[found], axis=1),
        dist[found],
        rtol=1e-12,
    )


def test_rigid_motion_of_map_and_pose_leaves_the_metric_unchanged():
    rng = np.random.default_rng(6)
    pts = np.vstack([box_room(HALF, 0.05), rng.uniform(-3.5, 3.5, size=(2000, 3))])
    dirs = spinning_directions(np.arange(-15, 16, 2), 900)
    pose = pose_at(0.5, -0.3, 0.1)
    params = eval_params(0.1, 100.0, noise=0.01, seed=3)
    base = _core.evaluate(_core.MapIndex(np.ascontiguousarray(pts)), pose, dirs, params).metric
    for _ in range(3):
        T = rigid_transform(rng)
        moved = (pts @ T[:3, :3].T) + T[:3, 3]
        got = _core.evaluate(
            _core.MapIndex(np.ascontiguousarray(moved)), np.ascontiguousarray(T @ pose), dirs, params
        ).metric
        assert got.m == pytest.approx(base.m, rel=2e-3)
        for key in ("sigma1", "q_min", "q_n", "q_max"):
            assert getattr(got, key) == pytest.approx(getattr(base, key), rel=2e-3), key


def test_the_python_wrapper_returns_the_core_scan():
    import lf3pm
    from lf3pm.pose import pose_matrix
    from lf3pm.scan.scan_simulator import simulate_scan
    from lf3pm.scenes import build_scene

    world = lf3pm.load_map(build_scene("boxes").points)
    vlp16 = lf3pm.get_sensor("vlp16")
    pose = pose_matrix((0.0, 0.0, 0.5, 0.3))
    scan = simulate_scan(world, pose, vlp16.directions, vlp16.min_range, vlp16.max_range, noise=0.01, seed=4, stream=2)
    raw = _core.simulate_scan(
        world.index, pose, vlp16.directions, scan_params(vlp16.min_range, vlp16.max_range, noise=0.01, seed=4, stream=2)
    )
    assert len(scan) == len(raw["ray"]) > 10000
    for name in ("sensor_points", "world_points", "surfel", "ray"):
        np.testing.assert_array_equal(getattr(scan, name), raw[name])


@pytest.mark.slow
def test_every_hit_is_the_nearest_disc_a_float64_brute_force_finds():
    """The caster's walk, slabs and skips only prune: each ray's hit is the nearest of
    all the map's discs, found here by testing every disc in float64. Rays on a disc's
    rim can go either way in float32, so a hit must lie between the nearest disc hit
    strictly inside its rim and the nearest within a rim widened by the rounding.
    The map mixes what the caster's shortcuts are built for: 10 cm ground grazed from
    0.5 m, walls, and a dense clutter blob (thousands of discs in a few cells)."""
    rng = np.random.default_rng(7)
    g = np.arange(-6.0, 6.0, 0.1)
    gx, gy = np.meshgrid(g, g, indexing="ij")
    ground = np.c_[gx.ravel(), gy.ravel(), np.zeros(gx.size)]
    ys, zs = np.meshgrid(np.arange(-6.0, 6.0, 0.05), np.arange(0.0, 1.0, 0.05), indexing="ij")
    wall = np.c_[np.full(ys.size, 5.0), ys.ravel(), zs.ravel()]
    blob = rng.normal([1.5, 0.5, 0.4], 0.15, size=(4000, 3))
    pts = np.vstack([ground, wall, blob]) + rng.normal(scale=0.003, size=(len(ground) + len(wall) + len(blob), 3))
    index = _core.MapIndex(np.ascontiguousarray(pts))
    origin = np.array([-1.0, -0.5, 0.5])
    dirs = random_directions(rng, 3000)
    dirs[:1500, 2] = -np.abs(dirs[:1500, 2]) * 0.15  # half of them graze the ground
    dirs = np.ascontiguousarray(dirs / np.linalg.norm(dirs, axis=1, keepdims=True))
    scan = _core.simulate_scan(index, pose_at(*origin), dirs, scan_params(1e-3, 50.0, threads=1))
    ours = np.full(len(dirs), np.inf)
    ours[scan["ray"]] = np.linalg.norm(scan["sensor_points"], axis=1)

    c, n, r2 = index.points, index.normals, index.disc_radius.astype(np.float64) ** 2
    inside, widened = np.full(len(dirs), np.inf), np.full(len(dirs), np.inf)
    for chunk in np.array_split(np.arange(len(dirs)), 30):
        d = dirs[chunk]
        denom = d @ n.T
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((c - origin) * n).sum(axis=1)[None, :] / denom
        q2 = ((origin[None, None, :] + t[..., None] * d[:, None, :] - c[None]) ** 2).sum(axis=2)
        valid = (np.abs(denom) >= 1e-7) & (t > 1e-3)
        inside[chunk] = np.where(valid & (q2 <= r2 * (1 - 1e-4)), t, np.inf).min(axis=1)
        widened[chunk] = np.where(valid & (q2 <= r2 * (1 + 1e-4)), t, np.inf).min(axis=1)
    tol = 1e-4 + 1e-6 * np.where(np.isfinite(ours), ours, 0)
    assert np.all(np.isfinite(inside) <= np.isfinite(ours))  # a disc hit inside its rim is never missed
    ok = (ours >= widened - tol) & (ours <= inside + tol)
    assert ok.all(), f"{(~ok).sum()} of {len(dirs)} rays off the brute force"
    assert np.isfinite(ours[:1500]).mean() > 0.5  # most grazing rays meet the ground (some leave it first)


def _returns(table, range_edges=(0.1, 2.0, 3.0, 100.0), cos_edges=(0.0, 0.5, 1.0)):
    from lf3pm.sensors import ReturnModel

    return ReturnModel(range_edges, cos_edges, table)


def test_a_return_model_drops_exactly_the_hits_its_table_and_draws_say(room):
    """Return probabilities of 0 and 1 by range and incidence: the rays kept are exactly those
    whose bin holds 1, computed in float64 from the full scan's ranges and the walls' normals
    (the box room's are the axes); a table of ones is no model at all; a probability of 0.3
    keeps a seeded, thread-independent 30 % of the hits (binomial: within 5 sigma), whose
    noisy ranges are those of the full scan (the draws are independent of the noise)."""
    dirs = random_directions(np.random.default_rng(5), 30000)
    origin = np.array([0.4, -0.6, 0.1])
    full = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(0.1, 100.0, noise=0.01, seed=3))
    ones = _core.simulate_scan(
        room, pose_at(*origin), dirs, scan_params(0.1, 100.0, noise=0.01, seed=3, returns=_returns([[1, 1]] * 3))
    )
    for name in ("sensor_points", "ray", "surfel"):
        np.testing.assert_array_equal(ones[name], full[name])
    clean = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(0.1, 100.0))
    rng = np.linalg.norm(clean["sensor_points"], axis=1)
    normal = np.abs(np.abs(clean["world_points"]) - np.asarray(HALF)).argmin(axis=1)  # the wall's axis
    cos = np.abs(dirs[clean["ray"], normal])
    model = _returns([[1, 0], [0, 1], [1, 1]])
    away = np.min(np.abs(np.abs(clean["world_points"]) - np.asarray(HALF)), axis=1) < 1e-6
    corner = np.sum(np.abs(np.abs(clean["world_points"]) - np.asarray(HALF)) < 0.1, axis=1) > 1
    exact = away & ~corner & (np.abs(rng - 2.0) > 1e-6) & (np.abs(rng - 3.0) > 1e-6) & (np.abs(cos - 0.5) > 1e-6)
    kept = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(0.1, 100.0, returns=model))
    expected = clean["ray"][(model.at(rng, cos) == 1) & exact]
    got = np.intersect1d(kept["ray"], clean["ray"][exact])
    np.testing.assert_array_equal(got, expected)
    assert 0 < len(expected) < exact.sum()

    third = _returns([[0.3, 0.3]] * 3)
    a = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(0.1, 100.0, noise=0.01, seed=3, returns=third))
    b = _core.simulate_scan(
        room, pose_at(*origin), dirs, scan_params(0.1, 100.0, noise=0.01, seed=3, threads=1, returns=third)
    )
    c = _core.simulate_scan(room, pose_at(*origin), dirs, scan_params(0.1, 100.0, noise=0.01, seed=4, returns=third))
    np.testing.assert_array_equal(a["ray"], b["ray"])
    assert not np.array_equal(a["ray"], c["ray"])
    n = len(full["ray"])
    assert abs(len(a["ray"]) - 0.3 * n) < 5 * np.sqrt(n * 0.3 * 0.7)
    np.testing.assert_array_equal(a["sensor_points"], full["sensor_points"][np.isin(full["ray"], a["ray"])])


def test_a_bad_return_table_is_refused_in_one_line(tmp_path):
    from lf3pm.errors import SensorError
    from lf3pm.sensors import get_sensor

    with pytest.raises(SensorError, match="must increase"):
        _returns([[1, 1]] * 3, range_edges=(0.1, 3.0, 2.0, 100.0))
    with pytest.raises(SensorError, match=r"in \[0, 1\]"):
        _returns([[1, 1.5]] * 3)
    with pytest.raises(SensorError, match="3 rows"):
        _returns([[1, 1]] * 2)
    path = tmp_path / "s.yaml"
    path.write_text(
        "name: s\nmin_range: 0.1\nmax_range: 50\nelevations_deg: [0]\nazimuth_count: 8\n"
        "return_probability: {range_edges_m: [0.1, 50], cos_edges: [0, 1], table: [[0.5]]}\n"
    )
    assert get_sensor(str(path)).returns == _returns([[0.5]], (0.1, 50.0), (0.0, 1.0))
    path.write_text(path.read_text().replace("[[0.5]]", "[[2]]"))
    with pytest.raises(SensorError, match=r"s\.yaml: key return_probability: every probability") as err:
        get_sensor(str(path))
    assert "\n" not in str(err.value)
