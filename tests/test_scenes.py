"""Procedural scenes: determinism, a free reference pose, sizes and densities, the
character the validation study relies on (a degenerate wall, a rough meadow), the
planning study's scenes (a tunnel degenerate along its axis beside a structured
detour, structure on one side only for a limited field of view) and their zones, the CLI."""

import math
import re
import subprocess
import sys

import numpy as np
import pytest

import lf3pm
from lf3pm.errors import Lf3pmError
from lf3pm.io import load_points
from lf3pm.scenes import SCENES, Scene, Zone, build_scene, describe_scenes, scene_defaults, scene_names, scene_zones
from lf3pm.scenes.scene import FREE_BAND_HIGH, FREE_BAND_LOW
from lf3pm.validation import RegistrationTarget, mde

NAMES = ["houses", "house_meadow", "meadow", "wall", "gobi", "boxes", "tunnel", "orientation", "corridor", "field"]
#: The flight scenes, registered beside these (tests/test_flight_scenes.py tests them).
FLIGHT = ["drift", "forest", "bridge", "atrium", "open_field"]
#: Scenes with planning-study zones, and whether their zones are clear of structure
#: whatever the layout (boxes may stand in the boxes room's zones).
ZONED = {"houses": True, "boxes": False, "tunnel": True, "orientation": True, "corridor": True, "field": True}
#: (fewest, most) points of the default scene: the most is the budget, the fewest
#: catches a sampler that lost its density.
POINT_BOUNDS = {
    "houses": (0.8e6, 2e6),
    "house_meadow": (1.0e6, 2e6),
    "meadow": (1.0e6, 2e6),
    "wall": (1.0e6, 2e6),
    "gobi": (2.0e6, 4e6),
    "boxes": (0.08e6, 2e6),
    "tunnel": (0.4e6, 2e6),
    "orientation": (0.4e6, 2e6),
    "corridor": (0.3e6, 2e6),
    "field": (0.6e6, 2e6),
}
#: Smaller variants for the different-seed check (same code paths, less time).
SMALL = {
    "house_meadow": {"extent": 15.0},
    "meadow": {"extent": 8.0},
    "gobi": {"length": 150.0, "width": 90.0, "west": 40.0, "warehouse_distance": 80.0},
}


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
    return subprocess.run(
        [sys.executable, "-m", "lf3pm.cli", *map(str, args)], capture_output=True, text=True, timeout=300
    )


def test_registry_names_and_descriptions():
    assert sorted(scene_names()) == sorted(NAMES + FLIGHT) and sorted(SCENES) == sorted(NAMES + FLIGHT)
    described = dict(describe_scenes())
    assert sorted(described) == sorted(NAMES + FLIGHT)
    for name, text in described.items():
        assert "\n" not in text and re.search(r"~[\d.]+ M points by default", text), name


def test_unknown_scene_is_one_line_listing_the_known_names():
    with pytest.raises(Lf3pmError) as err:
        build_scene("jungle")
    message = str(err.value)
    assert "\n" not in message and "jungle" in message
    assert all(name in message for name in NAMES)
    assert build_scene("House-Meadow", extent=15.0).name == "house_meadow"


@pytest.mark.parametrize(
    "kwargs,needle",
    [
        ({"seed": -1}, "seed"),
        ({"seed": 1.5}, "seed"),
        ({"windows": 3}, "no parameter 'windows'"),
        ({"boxes": -2}, "integer"),
        ({"boxes": 2.5}, "integer"),
        ({"spacing": float("nan")}, "finite"),
        ({"ceiling": "yes"}, "true or false"),
        ({"boxes": 400}, "cannot place"),
        ({"free_radius": 5.0}, "free_radius"),
    ],
)
def test_bad_parameters_are_one_line_errors(kwargs, needle):
    with pytest.raises(Lf3pmError) as err:
        build_scene("boxes", **kwargs)
    assert "\n" not in str(err.value) and needle in str(err.value)


@pytest.mark.slow
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


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_same_seed_same_points_other_seed_other_points(built, name):
    again = build_scene(name, seed=0)
    assert np.array_equal(again.points, built[name].points)
    small = SMALL.get(name, {})
    a = build_scene(name, seed=1, **small).points
    b = build_scene(name, seed=2, **small).points
    assert len(a) != len(b) or not np.array_equal(a, b)


@pytest.mark.slow
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


@pytest.mark.slow
def test_wall_is_degenerate_or_far_worse_than_houses(built, indexed):
    houses = lf3pm.evaluate(indexed("houses"), built["houses"].reference_pose, "vlp16", noise=0.0)
    wall = lf3pm.evaluate(indexed("wall"), built["wall"].reference_pose, "vlp16", noise=0.0)
    assert not houses.degenerate and houses.m > 10_000
    assert wall.degenerate or wall.q_min > 10.0 * houses.q_min


@pytest.mark.slow
def test_meadow_residuals_scatter_far_more_than_on_houses(built, indexed):
    """Point-to-plane residuals at the true pose (no range noise): millimetres on walls
    and bare ground, scattered by the vegetation's small randomly oriented surfaces."""
    maps = {
        "houses": (indexed("houses"), built["houses"].reference_pose),
        "meadow": (indexed("meadow"), built["meadow"].reference_pose),
    }
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


def ground_points(points, ground_z=0.0, tol=0.02):
    return points[np.abs(points[:, 2] - ground_z) < tol]


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(ZONED))
def test_zones_lie_on_bare_ground(built, name):
    """Every zone is ground of the map (a sample within 0.2 m of each point of a
    0.5 m lattice over it) and, where the layout guarantees it, clear of
    structure by 0.6 m (a robot of radius 0.3 m with 0.3 m to spare)."""
    scene = built[name]
    assert set(scene.zones) >= {"start", "goal"}
    assert scene.zones == scene_zones(name)
    ground = ground_points(scene.points)
    above = scene.points[(scene.points[:, 2] > FREE_BAND_LOW) & (scene.points[:, 2] < FREE_BAND_HIGH)]
    for zone in scene.zones.values():
        assert isinstance(zone, Zone) and zone.xmin < zone.xmax and zone.ymin < zone.ymax
        xs = np.arange(zone.xmin, zone.xmax + 1e-9, 0.5)
        ys = np.arange(zone.ymin, zone.ymax + 1e-9, 0.5)
        lattice = np.array([(x, y) for x in xs for y in ys])
        _, dist = lf3pm.load_map(ground).index.nearest(
            np.ascontiguousarray(np.c_[lattice, np.zeros(len(lattice))]), 1, 0.2
        )
        assert np.all(np.isfinite(dist))
        if ZONED[name]:
            near = (
                (above[:, 0] > zone.xmin - 0.6)
                & (above[:, 0] < zone.xmax + 0.6)
                & (above[:, 1] > zone.ymin - 0.6)
                & (above[:, 1] < zone.ymax + 0.6)
            )
            assert not near.any(), f"{name}: structure in or next to {zone}"
        assert zone.contains((zone.xmin + zone.xmax) / 2, zone.ymin) and not zone.contains(zone.xmax + 0.1, zone.ymin)


def test_zones_follow_the_parameters_and_only_zoned_scenes_have_them():
    short = scene_zones("tunnel", length=40.0)
    assert short["start"].xmax == -26.0 and short["goal"].xmin == 26.0
    assert build_scene("tunnel", length=40.0).zones == short
    assert scene_zones("boxes", room_length=9.0)["goal"].xmax == pytest.approx(6.0 - 0.7)
    assert scene_zones("wall") == {} and build_scene("wall").zones == {}
    with pytest.raises(Lf3pmError):
        scene_zones("tunnel", width=-1.0)


def test_tunnel_is_empty_inside_and_its_lane_is_clear_down_the_middle(built):
    scene = built["tunnel"]
    p, pts = scene.params, scene.points
    h, w = p["height"], p["width"]
    inside = (np.abs(pts[:, 1]) < w / 2 - 0.05) & (pts[:, 2] > 0.05) & (pts[:, 2] < h - 0.05)
    assert not inside.any()  # no structure in the tunnel, not even at its mouths
    lane = (np.abs(pts[:, 1] - p["detour_offset"]) < 1.2) & (pts[:, 2] > FREE_BAND_LOW)
    assert not lane.any()  # 2.4 m free between the pillar rows
    # The lane has structure: pillars and crates (nothing of them within 1.2 m of the lane's
    # centre line) and features in its walls.
    off_wall = np.abs(pts[:, 1] - p["detour_offset"]) < p["detour_width"] / 2 - 0.05
    assert np.count_nonzero(off_wall & (pts[:, 2] > 0.1) & (np.abs(pts[:, 0]) < p["length"] / 2)) > 20_000
    # Beyond the portals nothing stands higher than the ground within range of the
    # tunnel's axis, but the tunnel's own free ends.
    half = p["length"] / 2
    beyond = (np.abs(pts[:, 0]) > half + p["mouth_length"] + 0.01) & (pts[:, 2] > 0.05)
    assert not beyond.any()


@pytest.mark.slow
def test_tunnel_is_degenerate_along_its_axis_and_the_lane_is_not(built, indexed):
    """Mid-tunnel the weakest direction of the Gram is x, 10 times weaker than
    anywhere in the lane, and registration from 0.3 m starts slides along x;
    in the lane it returns to within a centimetre."""
    world, p = indexed("tunnel"), built["tunnel"].params
    tunnel = lf3pm.evaluate(world, (0.0, 0.0, 1.0, 0.0), "vlp16", noise=0.0, observations=True)
    lane = lf3pm.evaluate(world, (0.0, p["detour_offset"], 1.0, 0.0), "vlp16", noise=0.0)
    A = tunnel.observations["A"]
    _, vectors = np.linalg.eigh(A.T @ A)
    assert abs(vectors[0, 0]) > 0.99  # the weakest direction is translation along x
    assert tunnel.degenerate or tunnel.sigma1 < lane.sigma1 / 10
    assert tunnel.degenerate or tunnel.q_n > 8 * lane.q_n
    target = RegistrationTarget(world, threads=2)
    slide = mde(world, (0.0, 0.0, 1.0, 0.0), "vlp16", trials=6, sigma_t=0.3, target=target, threads=2)
    hold = mde(world, (0.0, p["detour_offset"], 1.0, 0.0), "vlp16", trials=6, sigma_t=0.3, target=target, threads=2)
    assert max(slide.translation_errors) > 0.25 and max(hold.translation_errors) < 0.01


@pytest.mark.slow
def test_tunnel_portal_at_the_mouth_would_fix_the_axis():
    """Why the tunnel sticks out of its portals: with the portal walls meeting the
    mouths' rims (mouth_length 0), rays grazing the walls hit the rims head-on and
    registration recovers x from 0.3 m starts to a few centimetres."""
    scene = build_scene("tunnel", mouth_length=0.0)
    world = lf3pm.load_map(scene.points)
    result = mde(world, (0.0, 0.0, 1.0, 0.0), "vlp16", trials=6, sigma_t=0.3, threads=2)
    assert max(result.translation_errors) < 0.1


def test_orientation_scene_localizes_facing_the_building_only(built, indexed):
    """A Mid-70 in the goal zone sees only bare ground facing away from the building
    (every hit on the ground, x, y and yaw unobservable) and the building facing it."""
    world, scene = indexed("orientation"), built["orientation"]
    goal = scene.zones["goal"]
    x, y = (goal.xmin + goal.xmax) / 2, (goal.ymin + goal.ymax) / 2
    back = lf3pm.evaluate(world, (x, y, 1.0, math.pi), "mid70", noise=0.0)
    away = lf3pm.evaluate(world, (x, y, 1.0, 0.0), "mid70", noise=0.0, observations=True)
    assert np.all(np.abs(away.observations["points"][:, 2]) < 0.02)
    assert away.degenerate or away.q_n > 10 * back.q_n
    assert away.degenerate or away.sigma1 < back.sigma1 / 10
    assert back.m > 5_000 and not back.degenerate


def test_corridor_is_degenerate_along_its_axis_and_the_rooms_are_not(built, indexed):
    """Mid-corridor the weakest direction of a VLP-16's Gram is x, and a Mid-70 looking
    down the corridor is degenerate or 4 times worse than one facing a partition in a
    room (0.35 against 0.065 at the defaults: the corners' plane fits and the mouths'
    free edges keep it from degenerating); nothing stands in the corridor."""
    world, p = indexed("corridor"), built["corridor"].params
    room_y = p["width"] / 2 + 0.2 + p["room_depth"] / 2
    room_x = p["length"] / p["rooms"] / 2  # the centre of the room east of x = 0
    corridor = lf3pm.evaluate(world, (0.0, 0.0, 1.0, 0.0), "vlp16", noise=0.0, observations=True)
    _, vectors = np.linalg.eigh(corridor.observations["A"].T @ corridor.observations["A"])
    assert abs(vectors[0, 0]) > 0.99
    along = lf3pm.evaluate(world, (0.0, 0.0, 1.0, 0.0), "mid70", noise=0.0)
    room = lf3pm.evaluate(world, (room_x, room_y, 1.0, 0.0), "mid70", noise=0.0)
    assert not room.degenerate and (along.degenerate or along.q_n > 4 * room.q_n)
    # Nothing stands inside the corridor.
    pts = built["corridor"].points
    inside = (np.abs(pts[:, 1]) < p["width"] / 2 - 0.05) & (pts[:, 2] > 0.05) & (pts[:, 2] < p["height"] - 0.05)
    assert not inside.any()


def test_field_localizes_past_the_row_only_facing_back_towards_it(built, indexed):
    """A Mid-70 in the goal zone (past the row's end) sees only ground facing along
    the route (x, y and yaw unobservable) and the row facing back towards it; at the
    start it sees the row ahead."""
    world, scene = indexed("field"), built["field"]
    goal, start = scene.zones["goal"], scene.zones["start"]
    x, y = (goal.xmin + goal.xmax) / 2, (goal.ymin + goal.ymax) / 2
    ahead = lf3pm.evaluate(world, (x, y, 1.0, 0.0), "mid70", noise=0.0, observations=True)
    back = lf3pm.evaluate(world, (x, y, 1.0, math.radians(150.0)), "mid70", noise=0.0)
    assert np.all(np.abs(ahead.observations["points"][:, 2]) < 0.02)
    assert ahead.degenerate or ahead.q_n > 10 * back.q_n
    assert not back.degenerate
    at_start = lf3pm.evaluate(
        world, ((start.xmin + start.xmax) / 2, 0.0, 1.0, 0.0), "mid70", noise=0.0, observations=True
    )
    assert not at_start.degenerate and np.count_nonzero(at_start.observations["points"][:, 2] > 0.3) > 100


@pytest.mark.slow
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
    for name in NAMES + FLIGHT:
        assert name in result.stdout


@pytest.mark.slow
@pytest.mark.parametrize(
    "args,needle",
    [
        (("scene", "jungle", "-o", "{tmp}/x.pcd"), "unknown scene"),
        (("scene", "boxes"), "missing -o"),
        (("scene", "-o", "{tmp}/x.pcd"), "missing scene name"),
        (("scene", "boxes", "-o", "{tmp}/x.xyz"), "unknown suffix"),
    ],
)
def test_cli_bad_input_is_one_line_exit_2(tmp_path, args, needle):
    result = run_cli(*[a.format(tmp=tmp_path) for a in args])
    assert result.returncode == 2
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and needle in lines[0].lower(), result.stderr
    assert not list(tmp_path.iterdir())
