"""The benefit study's cases from a YAML file (lf3pm.experiments.benefit.case_file): the
repository's files hold exactly the cases the study ran before, boxes draw the pairs
they drew, polygons and yaw ranges are honoured, a user's own map runs, and every bad
file is one line naming the file, the case and the field (exit 2 from the CLI)."""

import copy
import math
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from lf3pm.config import ConfigError
from lf3pm.experiments.benefit import cases as builtin
from lf3pm.experiments.benefit.case_file import CASES_FILE, QUICK_FILE, load_cases
from lf3pm.experiments.benefit.study import _draw, _yaw
from lf3pm.experiments.data import shared_data_dir
from lf3pm.experiments.map_cases import MapCase, in_polygon, zone_box
from lf3pm.grid import Grid, Space

# The study's cases as lf3pm.experiments.benefit.cases held them in Python (743613d), before
# they moved to python/lf3pm/experiments/benefit/cases.yaml: the same values draw the same pairs.
_REDUCED_GOBI = {
    "length": 115.0,
    "width": 90.0,
    "west": 25.0,
    "town_radius": 25.0,
    "warehouse_distance": 60.0,
    "buildings": 4,
    "stones": 150,
}
EXPECTED_CASES = (
    MapCase(
        "tunnel",
        "scene:tunnel",
        "vlp16",
        Space.R2,
        0.5,
        8,
        ray_stride=4,
        scene_params={"length": 40.0},
        both_ways=True,
        min_distance=30.0,
    ),
    MapCase(
        "orientation", "scene:orientation", "mid70", Space.SE2, 1.0, 8, yaw_reuse=True, ray_stride=4, min_distance=20.0
    ),
    MapCase(
        "gobi",
        "scene:gobi",
        "mid70",
        Space.SE2,
        1.0,
        8,
        yaw_reuse=True,
        ray_stride=2,
        scene_params=_REDUCED_GOBI,
        bounds=(-15.0, -30.0, 55.0, 30.0),
        zones={"start": (-8.0, -8.0, 8.0, 8.0), "goal": (30.0, -20.0, 45.0, 20.0)},
        min_distance=25.0,
    ),
    MapCase("houses", "scene:houses", "vlp16", Space.R2, 0.5, 8, ray_stride=4, both_ways=True, min_distance=20.0),
    MapCase(
        "boxes", "scene:boxes", "vlp16", Space.R2, 0.25, 6, ray_stride=4, both_ways=True, min_distance=8.0, r_safe=0.2
    ),
    MapCase(
        "street",
        "outdoor_urban64_2021-10-26-16-21-29-468.pcd",
        "vlp16",
        Space.R2,
        1.5,
        6,
        ray_stride=4,
        bounds=(-30.0, -30.0, 30.0, 30.0),
        zones={"start": (-25.0, -25.0, -15.0, -15.0), "goal": (0.0, -25.0, 15.0, -15.0)},
        both_ways=True,
        min_distance=15.0,
    ),
    MapCase(
        "room",
        "indoor_pcl_room_scan1.pcd",
        "vlp16",
        Space.R2,
        0.25,
        4,
        ray_stride=4,
        bounds=(-3.0, -2.5, 8.5, 3.5),
        zones={"start": (1.3, -0.6, 2.3, 0.6), "goal": (4.8, 0.6, 5.9, 1.9)},
        both_ways=True,
        min_distance=2.5,
        r_safe=0.1,
    ),
    MapCase(
        "corridor",
        "scene:corridor",
        "mid70",
        Space.SE2,
        0.5,
        8,
        yaw_reuse=True,
        ray_stride=4,
        both_ways=True,
        min_distance=30.0,
    ),
    MapCase("field", "scene:field", "mid70", Space.SE2, 1.0, 8, yaw_reuse=True, ray_stride=4, min_distance=60.0),
    MapCase(
        "houses_mid40",
        "scene:houses",
        "mid40",
        Space.SE2,
        1.0,
        6,
        yaw_reuse=True,
        ray_stride=4,
        both_ways=True,
        min_distance=20.0,
    ),
    MapCase(
        "boxes_mid40",
        "scene:boxes",
        "mid40",
        Space.SE2,
        0.25,
        6,
        yaw_reuse=True,
        ray_stride=4,
        both_ways=True,
        min_distance=8.0,
        r_safe=0.2,
    ),
    MapCase(
        "urban_mid40",
        "outdoor_urban64_2021-10-26-16-21-29-468.pcd",
        "mid40",
        Space.SE2,
        2.0,
        8,
        yaw_reuse=True,
        ray_stride=2,
        bounds=(-50.0, 10.0, 0.0, 45.0),
        zones={"start": (-18.0, 27.0, -12.0, 31.0), "goal": (-40.0, 27.0, -36.0, 31.0)},
        yaw_ranges={"goal": (math.radians(150), math.radians(210))},
        min_distance=15.0,
    ),
    MapCase(
        "hall_scan",
        "real_hall_run/scans/1630577758.569490.pcd",
        "mid40",
        Space.SE2,
        0.5,
        8,
        yaw_reuse=True,
        ray_stride=2,
        bounds=(-12.0, -9.0, 7.0, 12.0),
        zones={"start": (0.5, -6.5, 3.5, -2.5), "goal": (-9.0, -6.5, -6.5, -4.5)},
        min_distance=6.0,
    ),
    MapCase(
        "hall",
        "real_hall_run",
        "mid40",
        Space.SE2,
        0.5,
        6,
        yaw_reuse=True,
        ray_stride=2,
        bounds=(-22.0, -12.0, 7.0, 18.5),
        zones={"start": (-4.0, 2.0, -1.0, 5.0), "goal": (-6.8, -7.8, -5.2, -5.8)},
        yaw_ranges={"goal": (math.radians(150), math.radians(210))},
        min_distance=5.0,
    ),
)
EXPECTED_QUICK = (
    MapCase(
        "tunnel",
        "scene:tunnel",
        "vlp16",
        Space.R2,
        0.5,
        1,
        ray_stride=4,
        scene_params={"length": 20.0, "pillars": 8},
        both_ways=True,
        min_distance=20.0,
    ),
    MapCase(
        "orientation",
        "scene:orientation",
        "mid70",
        Space.SE2,
        2.0,
        1,
        yaw_bins=12,
        yaw_reuse=True,
        ray_stride=4,
        min_distance=20.0,
    ),
)


def _typed(case: MapCase) -> list:
    """A case's values with their types (30 and 30.0 would draw alike, but say so)."""
    return [(name, value, type(value)) for name, value in vars(case).items()]


def test_a_run_folder_is_a_map(site):
    """A recorded run's folder (scans at TUM poses) beside the file or in the shared data."""
    (site / "run" / "scans").mkdir(parents=True)
    np.save(site / "run" / "scans" / "1.000000.npy", np.eye(3))
    (site / "run" / "poses_tum.txt").write_text("1.0 0 0 0 0 0 0 1\n")
    local, shared = load_cases(_write(site, [_case(map="run"), _case(name="b", map="real_hall_run")]))
    assert local.source == str(site / "run") and shared.source == "real_hall_run"
    assert (shared_data_dir() / shared.source / "poses_tum.txt").is_file()


def test_repository_cases_are_the_cases_the_study_ran():
    files = ((CASES_FILE, EXPECTED_CASES, builtin.CASES), (QUICK_FILE, EXPECTED_QUICK, builtin.QUICK))
    for path, expected, loaded in files:
        read = load_cases(path, check_files=False)
        assert read == expected == loaded
        assert [_typed(c) for c in read] == [_typed(c) for c in expected]
    from lf3pm.scenes.gobi import REDUCED

    assert builtin.CASES[2].scene_params == REDUCED  # the file's copy of the demo's desert


def _old_draw(planner, zone, robot, rng, tries: int = 200):
    """study._draw as it was before polygons (743613d)."""
    free, grid = planner.esdf.traversable(robot.r_safe), planner.esdf.grid
    xmin, ymin, xmax, ymax = zone
    for _ in range(tries):
        cell = grid.cell_of(rng.uniform(xmin, xmax), rng.uniform(ymin, ymax))
        if cell is not None and free[cell[1], cell[0]]:
            return grid.centre(*cell)
    return None


def _planner(res: float = 0.5, seed: int = 0):
    grid = Grid.plane(-10.0, -10.0, res, int(20 / res), int(20 / res))
    free = np.random.default_rng(seed).random((grid.ny, grid.nx)) > 0.7
    esdf = SimpleNamespace(grid=grid, traversable=lambda r_safe: free)
    return SimpleNamespace(esdf=esdf)


def test_boxes_draw_as_before_and_no_yaw_range_draws_nothing():
    planner, robot = _planner(), SimpleNamespace(r_safe=0.3)
    for zone in ((-8.0, -8.0, 8.0, 8.0), (1.3, -0.6, 2.3, 0.6), (-25.0, -25.0, -15.0, -15.0), (5.0, 5.0, 9.0, 9.5)):
        old, new = np.random.default_rng(4), np.random.default_rng(4)
        for _ in range(20):
            assert _draw(planner, zone, robot, new) == _old_draw(planner, zone, robot, old)
        assert new.random() == old.random()  # the streams stayed together
    rng = np.random.default_rng(1)
    before = rng.bit_generator.state
    assert _yaw(EXPECTED_CASES[1], "start", 0.25, rng) == 0.25 and rng.bit_generator.state == before


def test_polygon_zones_and_yaw_ranges_are_honoured():
    planner, robot = _planner(res=0.05), SimpleNamespace(r_safe=0.3)
    triangle = ((0.0, 0.0), (6.0, 0.0), (0.0, 6.0))
    rng = np.random.default_rng(2)
    drawn = [_draw(planner, triangle, robot, rng) for _ in range(200)]
    assert all(p is not None for p in drawn)
    # Cell centres of points inside: within half a cell of the triangle (x + y <= 6).
    assert all(x >= 0 and y >= 0 and x + y <= 6.0 + 0.05 for x, y in drawn)
    assert max(x + y for x, y in drawn) > 5.0 and sum(x + y > 6.0 - 0.05 for x, y in drawn) < 10
    case = MapCase("c", "scene:orientation", "mid70", "se2", 1.0, 1, yaw_ranges={"goal": (-0.5, 0.25)})
    yaws = [_yaw(case, "goal", 9.0, rng) for _ in range(200)]
    assert all(-0.5 <= y <= 0.25 for y in yaws) and max(yaws) - min(yaws) > 0.6
    assert _yaw(case, "start", 9.0, rng) == 9.0
    assert in_polygon(triangle, 1.0, 1.0) and not in_polygon(triangle, 4.0, 4.0)


BASE = {
    "name": "a",
    "map": "site.npy",
    "sensor": "vlp16",
    "space": "r2",
    "res": 0.5,
    "pairs": 1,
    "zones": {"start": [0, 0, 1, 1], "goal": [5, 5, 6, 6]},
}


def _case(**changes) -> dict:
    case = copy.deepcopy(BASE)
    for key, value in changes.items():
        if value is None:
            case.pop(key)
        else:
            case[key] = value
    return case


@pytest.fixture
def site(tmp_path):
    np.save(tmp_path / "site.npy", np.zeros((10, 3)))
    (tmp_path / "bad_sensor.yaml").write_text("name: x\n")
    return tmp_path


def _write(folder, cases) -> str:
    path = folder / "cases.yaml"
    path.write_text(yaml.safe_dump({"cases": cases}) if isinstance(cases, list) else cases)
    return str(path)


def test_a_good_file_resolves_maps_sensors_zones_and_yaw_ranges(site):
    (site / "my_sensor.yaml").write_text(
        "name: mine\nmin_range: 0.5\nmax_range: 50\nelevations_deg: [-10, 0, 10]\nazimuth_count: 360\n"
    )
    cases = load_cases(
        _write(
            site,
            [
                _case(
                    space="se2",
                    sensor="my_sensor.yaml",
                    zones={
                        "start": {"polygon": [[0, 0], [2, 0], [1, 2]], "yaw_deg": [-90, 90]},
                        "goal": [5, 5, 6, 6],
                    },
                    robots=["diff", "car"],
                ),
                _case(name="b", map="scene:tunnel", zones={"goal": {"yaw_deg": [0, 0]}}, space="se2"),
            ],
        )
    )
    first, second = cases
    assert first.source == str(site / "site.npy") and first.sensor == str(site / "my_sensor.yaml")
    assert first.zones == {"start": ((0.0, 0.0), (2.0, 0.0), (1.0, 2.0)), "goal": (5.0, 5.0, 6.0, 6.0)}
    assert first.yaw_ranges == {"start": (-math.pi / 2, math.pi / 2)} and first.robots == ("diff", "car")
    assert first.space is Space.SE2 and first.pairs == 1
    assert second.source == "scene:tunnel" and second.zones is None and second.yaw_ranges == {"goal": (0.0, 0.0)}


BAD = [
    ("unknown field", [_case(colour="red")], "case a: colour is not a parameter lf3pm knows"),
    ("missing map", [_case(map="nowhere.pcd")], "case a: map: no file nowhere.pcd beside the cases file"),
    ("not a map file", [_case(map="site.txt")], "case a: map: site.txt is no map file lf3pm reads"),
    ("unknown sensor", [_case(sensor="vlp99")], "case a: sensor: unknown sensor 'vlp99'; presets: vlp16"),
    ("bad sensor file", [_case(sensor="bad_sensor.yaml")], "case a: sensor: sensor file"),
    (
        "degenerate polygon",
        [_case(zones={"start": [[0, 0], [1, 1], [2, 2]], "goal": [5, 5, 6, 6]})],
        "case a: zones.start: polygon is degenerate",
    ),
    (
        "crossing polygon",
        [_case(zones={"start": [[0, 0], [1, 1], [1, 0], [0, 1]], "goal": [5, 5, 6, 6]})],
        "case a: zones.start: polygon's edges 1 and 3 cross",
    ),
    (
        "two vertices",
        [_case(zones={"start": [[0, 0], [1, 1]], "goal": [5, 5, 6, 6]})],
        "case a: zones.start: polygon needs 3 or more",
    ),
    (
        "vertex of three numbers",
        [_case(zones={"start": [[0, 0, 1], [1, 1], [0, 1]], "goal": [5, 5, 6, 6]})],
        "case a: zones.start.polygon: each vertex must be 2 numbers (x, y)",
    ),
    (
        "inverted box",
        [_case(zones={"start": [0, 0, 1, 1], "goal": [6, 5, 5, 6]})],
        "case a: zones.goal: box must be xmin, ymin, xmax, ymax with xmin < xmax",
    ),
    (
        "box of three numbers",
        [_case(zones={"start": [0, 0, 1], "goal": [5, 5, 6, 6]})],
        "case a: zones.start.box: must be 4 numbers",
    ),
    ("zone outside bounds", [_case(bounds=[-1, -1, 5.5, 10])], "case a: zones.goal: (5, 5, 6, 6) is not inside bounds"),
    (
        "yaw range in r2",
        [_case(zones={"start": {"box": [0, 0, 1, 1], "yaw_deg": [0, 90]}, "goal": [5, 5, 6, 6]})],
        "case a: zones.start.yaw_deg: a yaw range needs space se2",
    ),
    (
        "yaw range reversed",
        [_case(space="se2", zones={"start": {"box": [0, 0, 1, 1], "yaw_deg": [90, 0]}, "goal": [5, 5, 6, 6]})],
        "case a: zones.start: yaw_deg must be lo, hi (degrees)",
    ),
    (
        "a map file's zone without area",
        [_case(space="se2", zones={"start": {"yaw_deg": [0, 90]}, "goal": [5, 5, 6, 6]})],
        "case a: zones.start: a map file's zone needs a box or a polygon",
    ),
    ("no zones", [_case(zones=None)], "case a: zones.start: a map file needs its start and goal zones"),
    ("unknown zone", [_case(zones={**BASE["zones"], "middle": [0, 0, 1, 1]})], "case a: zones.middle is not a"),
    ("pairs 0", [_case(pairs=0)], "case a: pairs must be greater than or equal to 1"),
    ("duplicate names", [_case(), _case()], "case a (#2): name is the name of case #1 too"),
    ("no name", [_case(name=None)], "case #1: name Field required"),
    ("name not a folder", [_case(name="a/b")], "case a/b: name: must be 1 to 64 letters"),
    ("unknown robot", [_case(robots=["tank"])], "case a: robots must be 'omni', 'diff' or 'car', got 'tank'"),
    ("r3", [_case(space="r3")], "case a: space must be 'r2' or 'se2'"),
    ("negative res", [_case(res=-1)], "case a: res must be greater than 0"),
    ("unknown scene", [_case(map="scene:castle", zones=None)], "case a: map: unknown scene 'castle'"),
    (
        "unknown scene parameter",
        [_case(map="scene:tunnel", zones=None, scene_params={"colour": 1})],
        "case a: scene_params: scene 'tunnel' has no parameter 'colour'",
    ),
    ("scene parameters of a file", [_case(scene_params={"length": 1})], "case a: scene_params: only a scene:NAME"),
    ("second case", [_case(), _case(name="b", pairs="many")], "case b: pairs must be a valid integer"),
    ("not a mapping", "[1, 2]", "a cases file is a mapping with a list of cases under 'cases'"),
    ("no cases", "cases: []", "cases List should have at least 1 item"),
    ("unknown key", yaml.safe_dump({"cases": [BASE], "other": 1}), "other is not a parameter lf3pm knows"),
]


@pytest.mark.parametrize("cases, expected", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_case_files_are_one_line_naming_case_and_field(site, cases, expected):
    path = _write(site, cases)
    with pytest.raises(ConfigError) as err:
        load_cases(path)
    text = str(err.value)
    assert text.startswith(f"{path}: {expected}") and "\n" not in text, text


def test_cli_bad_case_file_exits_2_with_one_line(site):
    from lf3pm.cli import app

    out = site / "out"
    path = _write(site, [_case(zones={"start": [[0, 0], [1, 1], [2, 2]], "goal": [5, 5, 6, 6]})])
    done = CliRunner().invoke(app, ["experiment", "benefit", "--cases", path, "-o", str(out)])
    assert done.exit_code == 2, done.output
    lines = done.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"lf3pm: error: {path}: case a: zones.start: polygon"), lines
    assert not out.exists()
    missing = CliRunner().invoke(app, ["experiment", "benefit", "--cases", str(site / "no.yaml"), "-o", str(out)])
    assert missing.exit_code == 2 and "cannot read the cases file" in missing.output


def test_cli_checks_the_repository_cases_maps_before_any_work(tmp_path, monkeypatch):
    from lf3pm.cli import app

    monkeypatch.setenv("LF3PM_DATA", str(tmp_path))  # no shared data: the real maps are nowhere
    out = tmp_path / "out"
    done = CliRunner().invoke(app, ["experiment", "benefit", "-o", str(out)])
    assert done.exit_code == 2, done.output
    assert done.output.startswith(f"lf3pm: error: {CASES_FILE}: case street: map: no file outdoor_urban64")
    assert not out.exists()


def _user_site(folder):
    """A user's own map (the boxes room as a PLY file) and a cases file beside it: one
    case, one pair, R2, a polygon start zone."""
    from lf3pm.io import write_points
    from lf3pm.scenes import build_scene

    write_points(folder / "site.ply", build_scene("boxes").points)
    case = {
        "name": "site",
        "map": "site.ply",
        "sensor": "vlp16",
        "space": "r2",
        "res": 0.5,
        "pairs": 1,
        "robots": ["omni"],
        "ray_stride": 8,
        "r_safe": 0.1,
        "zones": {"start": [[-3.3, -3.0], [-1.8, -3.0], [-1.8, 3.0], [-3.3, 3.0]], "goal": [5.8, -3.3, 7.3, 3.3]},
        "min_distance": 6.0,
    }
    return _write(folder, [case])


@pytest.mark.slow
def test_a_users_own_map_runs_end_to_end(tmp_path):
    from lf3pm.experiments.benefit.records import LOCALIZATION, read_summary

    path = _user_site(tmp_path)
    out = tmp_path / "out"
    command = [sys.executable, "-m", "lf3pm.cli", "experiment", "benefit", "--quick", "--cases", path]
    command += ["--lio", "default", "--guidance", "g=q_n:1:1", "-o", str(out)]
    run = subprocess.run(command, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    summary = read_summary(out / "summary.json")
    assert [c.name for c in summary.cases] == ["site"] and summary.cases[0].source == str(tmp_path / "site.ply")
    (pair,) = summary.pairs
    assert pair.case == "site" and pair.robot == "omni" and set(pair.plans) == {"none", "g"}
    for end, pose in (("start", pair.start), ("goal", pair.goal)):  # a cell centre: within half a cell
        xmin, ymin, xmax, ymax = zone_box(summary.cases[0].zones[end])
        assert xmin - 0.25 <= pose[0] <= xmax + 0.25 and ymin - 0.25 <= pose[1] <= ymax + 0.25, (end, pose)
    assert all(math.isfinite(plan.replays[LOCALIZATION].ape) for plan in pair.plans.values())
