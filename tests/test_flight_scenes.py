"""Flight scenes (docs/scenes.md, "Flight scenes"): deterministic per seed, quick to build
and a few hundred thousand points, start and goal volumes free of the map by the clearance,
and what makes each scene what it is: a drift whose straight section has the same smooth
cross-section everywhere (degenerate along its axis, unlike its gallery), trunks under a
noisy canopy, a bridge with nothing under its deck but its piers, an empty atrium void
from the ground floor to the top, a building hidden behind a berm at low altitude only."""

import math
import re
import subprocess
import sys
import time

import numpy as np
import pytest
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

import lf3pm
from lf3pm.errors import Lf3pmError
from lf3pm.scenes import (
    VOLUME_CLEARANCE,
    Volume,
    atrium,
    bridge,
    build_scene,
    describe_scenes,
    forest,
    scene_defaults,
    scene_names,
    scene_volumes,
    scene_zones,
)
from lf3pm.scenes.scene import finish

FLIGHT = ["drift", "forest", "bridge", "atrium", "open_field"]


@pytest.fixture(scope="module")
def built():
    """Every flight scene with its defaults and seed 0, built once."""
    return {name: build_scene(name) for name in FLIGHT}


def free_gap(points: np.ndarray, volume: Volume) -> float:
    """The distance from the volume to the nearest map point (inf when none lies near),
    found with a k-d tree: the points within the clearance of the box lie
    within its half-diagonal plus the clearance of its centre; their exact distance to
    the box is the norm of how far each lies outside it along each axis."""
    lower, upper = np.array(volume[:3]), np.array(volume[3:])
    centre, half_diagonal = (lower + upper) / 2, np.linalg.norm(upper - lower) / 2
    near = points[cKDTree(points).query_ball_point(centre, half_diagonal + VOLUME_CLEARANCE)]
    if len(near) == 0:
        return math.inf
    outside = np.maximum(np.maximum(lower - near, near - upper), 0.0)
    return float(np.linalg.norm(outside, axis=1).min())


def circle_centre(xy: np.ndarray) -> np.ndarray:
    """The centre of the least-squares circle through the points ``xy`` (Kasa's fit,
    linear in the centre; unbiased where the points cover only part of the circle)."""
    design = np.column_stack([2 * xy, np.ones(len(xy))])
    (a, b, _), *_ = np.linalg.lstsq(design, (xy**2).sum(axis=1), rcond=None)
    return np.array([a, b])


def weakest(result) -> tuple[np.ndarray, float]:
    """The weakest direction (unit 6-vector: x, y, z, roll, pitch, yaw) of an evaluation's
    Gram and its singular value."""
    A = result.observations["A"]
    values, vectors = np.linalg.eigh(A.T @ A)
    return vectors[:, 0], math.sqrt(max(values[0], 0.0))


@pytest.mark.parametrize("name", FLIGHT)
def test_record_and_size(built, name):
    scene = built[name]
    pts = scene.points
    assert name in scene_names() and scene.name == name and scene.seed == 0
    assert pts.dtype == np.float64 and pts.flags.c_contiguous and not pts.flags.writeable
    assert np.isfinite(pts).all() and scene.params == scene_defaults(name)
    assert 150_000 <= scene.size <= 400_000  # cheap for an R3 SOLM
    stated = float(re.search(r"~([\d.]+) M points", dict(describe_scenes())[name]).group(1)) * 1e6
    assert abs(scene.size - stated) <= 0.05 * stated
    extent = np.ptp(pts, axis=0)
    assert np.all(extent[:2] >= 15.0) and np.all(extent <= 100.0)  # tens of metres
    assert scene.zones == {} and scene_zones(name) == {}


@pytest.mark.parametrize("name", FLIGHT)
def test_same_seed_same_points_other_seed_other_points_quickly(built, name):
    start = time.perf_counter()
    again = build_scene(name, seed=0)
    assert time.perf_counter() - start < 5.0  # about 0.1 s on a 2-core machine
    assert np.array_equal(again.points, built[name].points)
    a, b = build_scene(name, seed=1).points, build_scene(name, seed=2).points
    assert len(a) != len(b) or not np.array_equal(a, b)


@pytest.mark.parametrize("name", FLIGHT)
def test_start_and_goal_volumes_are_free_and_apart(built, name):
    """No map point within VOLUME_CLEARANCE of any point of either box (checked with a
    k-d tree, apart from the builder's own check), the boxes inside the map's extent,
    large enough to draw from and their centres 10 m apart or more."""
    scene = built[name]
    assert set(scene.volumes) == {"start", "goal"} and scene.volumes == scene_volumes(name)
    lower, upper = scene.points.min(axis=0), scene.points.max(axis=0)
    for volume in scene.volumes.values():
        assert free_gap(scene.points, volume) >= VOLUME_CLEARANCE
        assert np.all(np.array(volume[:3]) > lower) and np.all(np.array(volume[3:]) < upper)
        assert min(volume.xmax - volume.xmin, volume.ymax - volume.ymin, volume.zmax - volume.zmin) >= 1.5
        assert volume.contains(*volume.centre) and not volume.contains(volume.xmax + 0.1, *volume.centre[1:])
    start, goal = (np.array(scene.volumes[k].centre) for k in ("start", "goal"))
    assert np.linalg.norm(goal - start) >= 10.0


def test_a_volume_too_close_to_the_map_is_a_one_line_error():
    plane = np.column_stack([np.repeat(np.arange(-50, 51) * 0.1, 101), np.tile(np.arange(-50, 51) * 0.1, 101)])
    points = np.column_stack([plane, np.zeros(len(plane))])
    params = {"sensor_height": 1.0, "free_radius": 1.0}
    ok = finish("test", "", 0, params, points, volumes={"start": (-1, -1, 0.6, 1, 1, 2)})
    assert ok.volumes["start"] == Volume(-1.0, -1.0, 0.6, 1.0, 1.0, 2.0)
    with pytest.raises(Lf3pmError) as err:
        finish("test", "", 0, params, points, volumes={"start": (-1, -1, 0.5, 1, 1, 2)})
    assert "\n" not in str(err.value) and "start volume" in str(err.value) and "0.50 m" in str(err.value)


def test_volumes_follow_the_parameters():
    assert scene_volumes("drift", length=40.0)["goal"].xmin == 26.0
    assert build_scene("drift", length=40.0).volumes == scene_volumes("drift", length=40.0)
    assert scene_volumes("atrium", storeys=5)["goal"].zmin == 4 * 4.0 + 1.5
    assert scene_volumes("wall") == {} and build_scene("boxes").volumes == {}
    with pytest.raises(Lf3pmError):
        scene_volumes("bridge", span=-1.0)
    # The open field's building stays hidden from the volumes whatever the parameters.
    with pytest.raises(Lf3pmError, match="would show over the berm"):
        build_scene("open_field", building_height=9.0)


def test_drift_straight_section_is_one_smooth_cross_section(built):
    """Every point of the drift's walls and back lies within a centimetre of the same
    cross-section (vertical walls, a semicircular back) from one free end to the other;
    slice after slice along it holds the same points over that section; nothing stands
    inside."""
    scene = built["drift"]
    p, pts = scene.params, scene.points
    r, hw = p["width"] / 2, p["wall_height"]
    tube = p["length"] / 2 + p["mouth_length"]
    highwalls = np.abs(np.abs(pts[:, 0]) - p["length"] / 2) < 0.02
    shell = pts[(np.abs(pts[:, 0]) < tube) & (np.abs(pts[:, 1]) < r + 0.05) & (pts[:, 2] > 0.02) & ~highwalls]
    y, z = shell[:, 1], shell[:, 2]
    to_wall = np.abs(np.abs(y) - r)
    to_back = np.abs(np.hypot(y, z - hw) - r)
    assert np.all(np.where(z > hw, to_back, to_wall) < 0.01)
    assert np.all(z < hw + r + 0.01)
    # Slices 2 m long hold the same points over the section: the same counts in each
    # 0.5 m of its arc length (up the +y wall, over the back, down the -y wall).
    arc = np.where(z > hw, hw + r * np.arctan2(z - hw, y), np.where(y > 0, z, 2 * hw + math.pi * r - z))
    edges, bins = np.arange(-tube, tube + 1e-9, 2.0), np.arange(0.0, 2 * hw + math.pi * r + 0.5, 0.5)
    table = np.array(
        [np.histogram(arc[(shell[:, 0] >= a) & (shell[:, 0] < b)], bins)[0] for a, b in zip(edges[:-1], edges[1:])]
    )
    typical = np.median(table, axis=0)
    assert len(table) >= 30 and typical.min() > 50 and np.all(np.abs(table - typical) <= 1 + 0.02 * typical)
    inside = (np.abs(pts[:, 0]) < tube) & (np.abs(pts[:, 1]) < r - 0.05) & (pts[:, 2] > 0.05)
    assert not np.any(inside & (pts[:, 2] < hw + np.sqrt(np.maximum(r * r - pts[:, 1] ** 2, 0.0)) - 0.05))


def test_drift_is_degenerate_along_its_axis_and_its_gallery_is_not(built):
    """Mid-drift a VLP-16's weakest direction is translation along x, 10 times weaker than
    in the gallery, whose pillars, niches and cross-cuts stand in its way."""
    scene = built["drift"]
    p, world = scene.params, lf3pm.load_map(scene.points)
    drift = lf3pm.evaluate(world, (0.0, 0.0, 1.5, 0.0), "vlp16", noise=0.0, observations=True)
    gallery = lf3pm.evaluate(world, (0.0, p["gallery_offset"] + 2.0, 1.5, 0.0), "vlp16", noise=0.0, observations=True)
    direction, sigma = weakest(drift)
    assert abs(direction[0]) > 0.99
    assert sigma < weakest(gallery)[1] / 10
    # The gallery's features: pillars on its centre line, cross-cuts beyond its outer wall.
    pts = scene.points
    g_out = p["gallery_offset"] + p["gallery_width"] / 2
    on_line = np.abs(pts[:, 1] - p["gallery_offset"]) < 0.4
    assert np.count_nonzero(on_line & (pts[:, 2] > 0.1) & (pts[:, 2] < p["gallery_height"] - 0.1)) > 5_000
    assert np.count_nonzero((pts[:, 1] > g_out + 1.0) & (np.abs(pts[:, 0]) < p["length"] / 2)) > 5_000


def test_forest_trunks_under_a_noisy_canopy_over_ground(built):
    """Between the ground and the canopy stand only vertical cylinders of varying
    radius, 50 or more of them, some between start and goal; above 4 m a noisy layer of
    crown points covers most of the forest; ground lies under all of it."""
    scene = built["forest"]
    p, pts = scene.params, scene.points
    low = pts[(pts[:, 2] > 1.0) & (pts[:, 2] < 1.5)]
    high = pts[(pts[:, 2] > 3.0) & (pts[:, 2] < 3.5)]
    # Cylinders: each trunk's points at 1 m lie on a circle about its centre ...
    tree = cKDTree(low[:, :2])
    count, label = connected_components(tree.sparse_distance_matrix(tree, 0.2))
    assert count >= 50
    centres, radii = np.array([circle_centre(low[label == k, :2]) for k in range(count)]), []
    for k in range(count):
        ring = np.hypot(*(low[label == k, :2] - centres[k]).T)
        assert np.std(ring) < 0.02
        radii.append(ring.mean())
    # ... and upright: the same circle 2 m higher (each point at 3 m over a point at 1 m,
    # give or take the bark's jitter, around the same centre).
    assert np.all(tree.query(high[:, :2])[0] < 0.05)
    above = cKDTree(centres).query(high[:, :2])[1]
    assert np.unique(above).size == count
    shift = [np.linalg.norm(circle_centre(high[above == k, :2]) - centres[k]) for k in range(count)]
    assert max(shift) < 0.01
    assert min(radii) > forest.TRUNK_RADIUS[0] - 0.03 and max(radii) < forest.TRUNK_RADIUS[1] + 0.03
    assert max(radii) - min(radii) > 0.12
    # Nothing but trunks from above the ground up to the canopy.
    band = pts[(pts[:, 2] > 1.0) & (pts[:, 2] < forest.CANOPY_FLOOR)]  # above the ground's highest
    assert np.all(cKDTree(centres).query(band[:, :2])[0] < forest.TRUNK_RADIUS[1] + 0.05)
    start, goal = scene.volumes["start"], scene.volumes["goal"]
    between = (centres[:, 0] > start.xmax) & (centres[:, 0] < goal.xmin) & (np.abs(centres[:, 1]) < 3.0)
    assert start.xmax < -p["length"] / 2 + 6.0 and goal.xmin > p["length"] / 2 - 6.0
    assert np.count_nonzero(between) >= 3
    # The canopy: a layer over most of the forest, far rougher than the ground.
    inside = (np.abs(pts[:, 0]) < p["length"] / 2) & (np.abs(pts[:, 1]) < p["width"] / 2)
    canopy = pts[inside & (pts[:, 2] > forest.CANOPY_FLOOR)]
    canopy = canopy[cKDTree(centres).query(canopy[:, :2])[0] > forest.TRUNK_RADIUS[1] + 0.05]
    covered = np.unique(np.floor(canopy[:, :2] / 2.0).astype(int), axis=0)
    assert len(covered) > 0.8 * (p["length"] / 2.0) * (p["width"] / 2.0)
    assert np.ptp(canopy[:, 2]) > 3.0
    ground = pts[inside & (np.abs(pts[:, 2]) < 2 * p["relief"])]

    def roughness(layer):
        """Median over a sample of the spread (m) of each point's 10 nearest neighbours
        along their least direction: about the jitter on a surface."""
        _, nearest = cKDTree(layer).query(layer[:: max(1, len(layer) // 500)], 10)
        return np.median([math.sqrt(np.linalg.eigvalsh(np.cov(layer[i].T))[0]) for i in nearest])

    assert roughness(canopy) > 0.03 and roughness(canopy) > 10 * roughness(ground)
    grid = np.unique(np.floor(ground[:, :2]).astype(int), axis=0)
    assert len(grid) > 0.95 * p["length"] * p["width"]


def test_bridge_has_nothing_under_its_deck_but_its_piers(built):
    """Over the water (between the quay walls) every point below the girders belongs to a
    pier, and beside the deck there is nothing at all; a VLP-16 under the deck at the start
    sees nothing lower than the girders but piers and quay walls."""
    scene = built["bridge"]
    p, pts = scene.params, scene.points
    half, dw = p["span"] / 2, p["deck_width"]
    bottom = p["deck_height"] - p["girder_depth"]
    water = np.abs(pts[:, 0]) < half - 0.05

    def on_pier(q):
        near = np.zeros(len(q), bool)
        for x, columns in bridge.piers(p):
            for cx, cy in columns:
                near |= np.hypot(q[:, 0] - cx, q[:, 1] - cy) < bridge.COLUMN_RADIUS + 0.05
            cap = (np.abs(q[:, 0] - x) < bridge.CAP[0] / 2 + 0.05) & (np.abs(q[:, 1]) < dw / 2 - 0.45)
            near |= cap & (q[:, 2] > bottom - bridge.CAP[1] - 0.05)
        return near

    below = pts[water & (pts[:, 2] < bottom - 0.01)]
    assert len(below) > 1_000 and np.all(on_pier(below))
    assert not np.any(water & (np.abs(pts[:, 1]) > dw / 2 + 0.05) & (pts[:, 2] < p["deck_height"] + 2))
    # Nothing at water level but the piers' and the quay walls' feet.
    assert np.all(on_pier(pts[water & (pts[:, 2] < 0.5)]))
    world = lf3pm.load_map(pts)
    x, y, z = scene.volumes["start"].centre
    hits = lf3pm.evaluate(world, (x, y, z, 0.0), "vlp16", noise=0.0, observations=True).observations["points"]
    low = hits[hits[:, 2] < bottom - 0.15]
    assert len(hits) > 5_000 and np.all(on_pier(low) | (np.abs(low[:, 0]) > half - 0.15))


def test_atrium_void_is_empty_from_bottom_to_top(built):
    """The void holds no point above the ground floor; every storey has its gallery slab
    and a balustrade on all four sides of the void; the start volume lies below the first
    gallery, the goal above the highest balustrade, and the shaft between them is free."""
    scene = built["atrium"]
    p, pts = scene.params, scene.points
    hv, h = p["void"] / 2, p["storey_height"]
    ring = np.maximum(np.abs(pts[:, 0]), np.abs(pts[:, 1]))
    assert not np.any((ring < hv - 0.05) & (pts[:, 2] > 0.1))
    annulus = p["size"] ** 2 - p["void"] ** 2
    for level in range(1, p["storeys"] + 1):
        z = level * h
        slab = (np.abs(pts[:, 2] - z) < 0.02) & (ring > hv + 0.3)
        assert np.count_nonzero(slab) == pytest.approx(annulus / p["ground_spacing"] ** 2, rel=0.1)
        rail = (ring > hv) & (ring < hv + atrium.BALUSTRADE[1] + 0.02) & (pts[:, 2] > z + 0.1)
        rail &= pts[:, 2] < z + atrium.BALUSTRADE[0] + 0.01
        for side in (pts[:, 0] > hv, pts[:, 0] < -hv, pts[:, 1] > hv, pts[:, 1] < -hv):
            assert np.count_nonzero(rail & side) > 500
    start, goal = scene.volumes["start"], scene.volumes["goal"]
    assert start.zmax < h - p["slab_thickness"] - VOLUME_CLEARANCE
    assert goal.zmin > (p["storeys"] - 1) * h + atrium.BALUSTRADE[0]
    shaft = Volume(start.xmin, start.ymin, start.zmin, goal.xmax, goal.ymax, goal.zmax)
    assert free_gap(pts, shaft) >= VOLUME_CLEARANCE


def test_open_field_building_hidden_low_and_visible_high(built):
    """The berm has the same cross-section all along the field. Every sight line from the
    start and goal volumes and from the line between them, up to their top, to any point
    of the building passes below the berm's crest (judged against the berm's own
    points); from 8 m up, on the same line, part of the facade shows. A VLP-16 at 1.75 m
    sees no point of the building and is weakest along x; at 8 m it sees the facade and
    x is 5 times better fixed."""
    scene = built["open_field"]
    p, pts = scene.params, scene.points
    run = p["berm_height"] * p["berm_slope"]
    foot = (p["berm_distance"] - run, p["berm_distance"] + p["berm_crest"] + run)
    half = p["field_length"] / 2
    berm = pts[(pts[:, 1] > foot[0]) & (pts[:, 1] < foot[1]) & (np.abs(pts[:, 0]) < half - 0.5)]
    edges = np.arange(foot[0], foot[1] + 1e-9, 0.25)

    def profile(points):
        """The highest point in each 0.25 m band of y."""
        top = np.full(len(edges) - 1, -np.inf)
        np.maximum.at(top, np.clip(np.digitize(points[:, 1], edges) - 1, 0, len(top) - 1), points[:, 2])
        return top

    west, east = profile(berm[berm[:, 0] < 0]), profile(berm[berm[:, 0] >= 0])
    assert np.all(np.abs(west - east) < 0.02) and west.max() > p["berm_height"] - 0.05
    # The berm's height at each band's centre, taken low: the least of the band's and its
    # neighbours' highest points, so that a line found below it is below the berm.
    height = np.minimum(np.minimum(west, np.roll(west, 1)), np.roll(west, -1))[1:-1]
    ys = ((edges[:-1] + edges[1:]) / 2)[1:-1]
    front = p["facade_distance"]
    building = pts[(pts[:, 1] > front - 0.35) & (pts[:, 2] > 0.05)]
    building = building[:: max(1, len(building) // 4_000)]

    def blocked(eyes, targets):
        """Whether each sight line (eye x target) passes below the berm somewhere."""
        out = np.empty((len(eyes), len(targets)), bool)
        for i, (_, ey, ez) in enumerate(eyes):
            t = (ys[None, :] - ey) / (targets[:, 1:2] - ey)  # where the line crosses each y
            z = ez + t * (targets[:, 2:3] - ez)
            out[i] = np.any(z < height[None, :] - 0.02, axis=1)
        return out

    start, goal = scene.volumes["start"], scene.volumes["goal"]
    eyes = [
        (x, y, z)
        for x in np.linspace(start.xmin, goal.xmax, 9)
        for y in (start.ymin, 0.0, start.ymax)
        for z in (start.zmin, start.zmax)
    ]
    assert blocked(eyes, building).all()
    facade = building[building[:, 1] < front + 0.3]  # the front, its pilasters and its recesses
    high = blocked([(0.0, y, 8.0) for y in (start.ymin, 0.0, start.ymax)], facade)
    assert np.all(np.mean(~high, axis=1) > 0.2)
    world = lf3pm.load_map(pts)
    low = lf3pm.evaluate(world, (0.0, 0.0, 1.75, 0.0), "vlp16", noise=0.0, observations=True)
    up = lf3pm.evaluate(world, (0.0, 0.0, 8.0, 0.0), "vlp16", noise=0.0, observations=True)
    assert not np.any(low.observations["points"][:, 1] > foot[1])
    assert np.count_nonzero(up.observations["points"][:, 1] > p["facade_distance"] - 0.35) > 500
    direction, sigma = weakest(low)
    assert abs(direction[0]) > 0.99 and weakest(up)[1] > 5 * sigma


@pytest.mark.slow
def test_cli_writes_a_flight_scene_and_prints_its_volumes(tmp_path):
    out = tmp_path / "bridge.npy"
    result = subprocess.run(
        [sys.executable, "-m", "lf3pm.cli", "scene", "bridge", "-o", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    assert "start volume x y z: -28..-25 -2..2 2..5  (no map point within 0.6 m)" in result.stdout
    assert "goal volume x y z: 25..28 -2..2 2..5" in result.stdout
    assert np.load(out).shape == (build_scene("bridge").size, 3)
