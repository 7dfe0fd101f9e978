"""Procedural scenes: determinism, a free reference pose, sizes and densities, the
character the validation study relies on (a degenerate wall, a rough meadow), the CLI."""

import re
import subprocess
import sys

import numpy as np
import pytest

import lf3pm
from lf3pm.errors import Lf3pmError
from lf3pm.io import load_points
from lf3pm.scenes import SCENES, Scene, build_scene, describe_scenes, scene_defaults, scene_names
from lf3pm.scenes.scene import FREE_BAND_HIGH, FREE_BAND_LOW

NAMES = ["houses", "house_meadow", "meadow", "wall", "gobi", "boxes"]
#: (fewest, most) points of the default scene: the most is the budget, the fewest
#: catches a sampler that lost its density.
POINT_BOUNDS = {"houses": (0.8e6, 2e6), "house_meadow": (1.0e6, 2e6), "meadow": (1.0e6, 2e6),
                "wall": (1.0e6, 2e6), "gobi": (2.0e6, 4e6), "boxes": (0.08e6, 2e6)}
#: Smaller variants for the different-seed check (same code paths, less time).
SMALL = {"house_meadow": {"extent": 15.0}, "meadow": {"extent": 8.0},
         "gobi": {"length": 150.0, "width": 90.0, "west": 40.0, "warehouse_distance": 80.0}}


@pytest.fixture(scope="module")
def built():
    """Every scene with its defaults and seed 0, built once."""
    return {name: build_scene(name) for name in NAMES}


@pytest.fixture(scope="module")
def indexed(built):
    """Indexed maps, loaded on first use."""
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = lf3pm.load_map(built[name].points)
        return cache[name]
    return get


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "lf3pm.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def test_registry_names_and_descriptions():
    assert sorted(scene_names()) == sorted(NAMES) and sorted(SCENES) == sorted(NAMES)
    described = dict(describe_scenes())
    assert sorted(described) == sorted(NAMES)
    for name, text in described.items():
        assert "\n" not in text and re.search(r"~[\d.]+ M points by default", text), name


def test_unknown_scene_is_one_line_listing_the_known_names():
    with pytest.raises(Lf3pmError) as err:
        build_scene("forest")
    message = str(err.value)
    assert "\n" not in message and "forest" in message
    assert all(name in message for name in NAMES)
    assert build_scene("House-Meadow", extent=15.0).name == "house_meadow"


@pytest.mark.parametrize("kwargs,needle", [
    ({"seed": -1}, "seed"),
    ({"seed": 1.5}, "seed"),
    ({"windows": 3}, "no parameter 'windows'"),
    ({"boxes": -2}, "integer"),
    ({"boxes": 2.5}, "integer"),
    ({"spacing": float("nan")}, "finite"),
    ({"ceiling": "yes"}, "true or false"),
    ({"boxes": 400}, "cannot place"),
    ({"free_radius": 5.0}, "free_radius"),
])
def test_bad_parameters_are_one_line_errors(kwargs, needle):
    with pytest.raises(Lf3pmError) as err:
        build_scene("boxes", **kwargs)
    assert "\n" not in str(err.value) and needle in str(err.value)


@pytest.mark.parametrize("name", NAMES)
def test_scene_record(built, name):
    scene = built[name]
    assert isinstance(scene, Scene) and scene.name == name and scene.seed == 0
    pts = scene.points
    assert pts.dtype == np.float64 and pts.ndim == 2 and pts.shape[1] == 3
    assert pts.flags.c_contiguous and not pts.flags.writeable
    assert np.isfinite(pts).all()
    assert scene.params == scene_defaults(name)
    height = scene.params["sensor_height"]
    assert height == 1.0
    assert scene.reference_pose == (0.0, 0.0, scene.ground_z + height, 0.0)
    assert scene.description == dict(describe_scenes())[name]


@pytest.mark.parametrize("name", NAMES)
def test_same_seed_same_points_other_seed_other_points(built, name):
    again = build_scene(name, seed=0)
    assert np.array_equal(again.points, built[name].points)
    small = SMALL.get(name, {})
    a = build_scene(name, seed=1, **small).points
    b = build_scene(name, seed=2, **small).points
    assert len(a) != len(b) or not np.array_equal(a, b)


@pytest.mark.parametrize("name", NAMES)
def test_reference_pose_is_free_and_above_ground(built, name):
    scene = built[name]
    pts = scene.points
    x, y, z, _ = scene.reference_pose
    assert scene.free_radius >= 1.0
    near = pts[np.hypot(pts[:, 0] - x, pts[:, 1] - y) < scene.free_radius]
    above = near[:, 2] - scene.ground_z
    assert not np.any((above >= FREE_BAND_LOW) & (above <= FREE_BAND_HIGH))
    # The ground is there, under the sensor, and the sensor is above all of it.
    under = near[np.hypot(near[:, 0] - x, near[:, 1] - y) < 0.5]
    assert np.count_nonzero(np.abs(under[:, 2] - scene.ground_z) < 0.05) > 10
    assert np.all(near[near[:, 2] < z, 2] < scene.ground_z + FREE_BAND_LOW)


@pytest.mark.parametrize("name", NAMES)
def test_point_counts_within_bounds_and_as_described(built, name):
    count = built[name].size
    low, high = POINT_BOUNDS[name]
    assert low <= count <= high
    stated = float(re.search(r"~([\d.]+) M points", built[name].description).group(1)) * 1e6
    assert abs(count - stated) <= 0.1 * stated


def test_wall_scene_densities_and_length(built):
    """Wall 5 cm, ground 10 cm, and longer than twice a VLP-16's 100 m range."""
    scene = built["wall"]
    p = scene.params
    pts = scene.points
    face = pts[(np.abs(pts[:, 1] - p["distance"]) < 0.01) & (pts[:, 2] > 0.01)]
    assert len(face) == pytest.approx(p["length"] * p["height"] / 0.05**2, rel=0.02)
    assert np.ptp(face[:, 0]) > 2 * 100.0
    assert np.std(face[:, 1] - p["distance"]) < 0.002  # planar to a millimetre or so
    ground = pts[(np.abs(pts[:, 2]) < 0.01) & (pts[:, 1] < p["distance"] - 0.01)]
    front = p["distance"] + p["ground_front"]
    assert len(ground) == pytest.approx(p["length"] * front / 0.10**2, rel=0.02)


def local_rise(points, cell=2.0):
    """The largest height difference among the points of one cell x cell column."""
    key = np.floor(points[:, :2] / cell).astype(np.int64)
    order = np.lexsort((key[:, 1], key[:, 0]))
    key, z = key[order], points[order, 2]
    starts = np.flatnonzero(np.r_[True, np.any(key[1:] != key[:-1], axis=1)])
    return float(np.max(np.maximum.reduceat(z, starts) - np.minimum.reduceat(z, starts)))


def test_gobi_is_large_uneven_with_a_distant_warehouse(built):
    pts = built["gobi"].points
    lower, upper = pts.min(axis=0), pts.max(axis=0)
    assert upper[0] - lower[0] >= 200 and upper[1] - lower[1] >= 100
    ground = pts[np.hypot(pts[:, 0], pts[:, 1]) > 45.0]
    assert np.ptp(ground[:, 2]) > 2.0  # the terrain's relief
    r = np.hypot(pts[:, 0], pts[:, 1])
    # The warehouse's 9 m walls stand more than 80 m away; between the town
    # (within 40 m) and 80 m there is nothing taller than a stone or a bush.
    assert local_rise(pts[r > 80.0]) > 8.0
    assert local_rise(pts[(r > 45.0) & (r < 80.0)]) < 3.0


def test_wall_is_degenerate_or_far_worse_than_houses(built, indexed):
    houses = lf3pm.evaluate(indexed("houses"), built["houses"].reference_pose, "vlp16", noise=0.0)
    wall = lf3pm.evaluate(indexed("wall"), built["wall"].reference_pose, "vlp16", noise=0.0)
    assert not houses.degenerate and houses.m > 10_000
    assert wall.degenerate or wall.q_min > 10.0 * houses.q_min


def test_meadow_residuals_scatter_far_more_than_on_houses(built, indexed):
    """Point-to-plane residuals at the true pose (no range noise): millimetres on walls
    and bare ground, scattered by the vegetation's small randomly oriented surfaces."""
    maps = {"houses": (indexed("houses"), built["houses"].reference_pose),
            "meadow": (indexed("meadow"), built["meadow"].reference_pose)}
    bare = build_scene("meadow", tufts_per_m2=0.0, weeds_per_m2=0.0, bushes_per_100m2=0.0)
    maps["bare"] = (lf3pm.load_map(bare.points), bare.reference_pose)
    over_1cm, p90 = {}, {}
    for name, (world, pose) in maps.items():
        result = lf3pm.evaluate(world, pose, "vlp16", noise=0.0, observations=True)
        b = np.abs(result.observations["b"])
        assert result.m > 5_000
        over_1cm[name], p90[name] = np.mean(b > 0.01), np.percentile(b, 90)
    assert over_1cm["meadow"] > 3.0 * over_1cm["houses"]
    assert p90["meadow"] > 4.0 * p90["houses"]
    assert over_1cm["meadow"] > 5.0 * over_1cm["bare"]  # the plants, not the ground


def test_cli_writes_a_readable_pcd(tmp_path):
    out = tmp_path / "boxes.pcd"
    result = run_cli("scene", "boxes", "-o", out, "--seed", "3")
    assert result.returncode == 0, result.stderr
    assert "reference pose" in result.stdout and "0 0 1 0" in result.stdout
    points = load_points(out)
    expected = build_scene("boxes", seed=3).points
    assert points.shape == expected.shape
    assert np.allclose(points, expected, atol=1e-5)  # PCD stores float32


def test_cli_list_names_every_scene():
    result = run_cli("scene", "--list")
    assert result.returncode == 0
    for name in NAMES:
        assert name in result.stdout


@pytest.mark.parametrize("args,needle", [
    (("scene", "forest", "-o", "{tmp}/x.pcd"), "unknown scene"),
    (("scene", "boxes"), "missing -o"),
    (("scene", "-o", "{tmp}/x.pcd"), "missing scene name"),
    (("scene", "boxes", "-o", "{tmp}/x.xyz"), "unknown suffix"),
])
def test_cli_bad_input_is_one_line_exit_2(tmp_path, args, needle):
    result = run_cli(*[a.format(tmp=tmp_path) for a in args])
    assert result.returncode == 2
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and needle in lines[0].lower(), result.stderr
    assert not list(tmp_path.iterdir())
