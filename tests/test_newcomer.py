"""What a new user meets first: a SOLM build that warns when stray points leave most of
its grid empty, a line while a map loads, and the demo's closing command, runnable as
printed."""

import os
import shlex
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from analytic_scenes import box_room

import lf3pm
from lf3pm.io import write_points
from lf3pm.map import load_map_points
from lf3pm.solm.build import stray_points_warning

#: A 10 x 8 x 3 m room and four points about 400 m away, as a map read with a few
#: strays (the BALM hall's reach 400 m).
ROOM = box_room((5.0, 4.0, 1.5), 0.05) + (0.0, 0.0, 1.5)
STRAYS = np.array([[400.0, 3.0, 1.0], [398.0, -2.0, 0.5], [-20.0, 395.0, 2.0], [3.0, 400.0, 1.0]])


def run_cli(*args, env=None):
    return subprocess.run(
        [sys.executable, "-m", "lf3pm.cli", *map(str, args)],
        check=False,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )


def test_a_build_on_a_map_with_stray_points_says_which_bounds_skip_its_empty_grid(tmp_path):
    world = load_map_points(np.vstack([ROOM, STRAYS]))
    grid = lf3pm.make_grid(world, "r2", 1.0)
    with pytest.warns(UserWarning) as caught:
        lf3pm.build_solm(world, "vlp16", grid, tmp_path / "s.zarr", max_tiles=0)
    (line,) = [str(w.message) for w in caught if "stray points" in str(w.message)]
    assert "\n" not in line
    assert line.startswith(f"101 of the SOLM grid's {grid.nx * grid.ny:,} x-y cells hold a map point")
    assert "holds all but 4 of the 107,206 points" in line
    suggested = [float(v) for v in line.split("--bounds ")[1].split(" (")[0].split()]
    assert suggested == [-5.0, -4.0, 6.0, 5.0]  # the room's cells on the grid from x0 = -20, y0 = -4
    bounded = lf3pm.make_grid(world, "r2", 1.0, bounds=suggested)
    assert bounded.nx * bounded.ny == 11 * 9 and stray_points_warning(world.points, bounded) is None


def test_maps_without_strays_build_without_the_warning(tmp_path):
    """The room alone, and a real single scan whose points thin out to 120 m but are no
    strays (the percentile box covers most of its grid)."""
    world = load_map_points(ROOM)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lf3pm.build_solm(world, "vlp16", lf3pm.make_grid(world, "r2", 0.5), tmp_path / "r.zarr", max_tiles=0)
    from shared_data import shared_file

    scan = load_map_points(shared_file("outdoor_urban64_2021-10-26-16-21-29-468.pcd"))
    assert stray_points_warning(scan.points, lf3pm.make_grid(scan, "r2", 0.5)) is None


@pytest.mark.slow
def test_solm_build_prints_the_warning_with_the_bounds(tmp_path):
    path = tmp_path / "room_and_strays.pcd"
    write_points(path, np.vstack([ROOM, STRAYS]))
    done = run_cli("solm", "build", path, "-o", tmp_path / "s.zarr", "--res", "5", "--ray-stride", "4")
    assert done.returncode == 0, done.stderr
    assert "x-y cells hold a map point: stray points stretch it over x [-20, 400]" in done.stderr
    # the cells of 5 m from (-20, -4) that hold the room, its walls at x = 5 and y = 4 too
    assert "--bounds -5 -4 10 6 (the 0.5 and 99.5 percentiles" in done.stderr


def test_load_map_reports_each_phase():
    seen = []
    world = lf3pm.load_map(ROOM, progress=seen.append)
    assert seen == ["reading the map array", f"indexing {world.size:,} points of <array>"]


@pytest.mark.slow
def test_commands_that_load_a_map_show_a_line_on_a_terminal_only(tmp_path):
    """On a terminal (FORCE_COLOR makes Rich treat the pipe as one) the line says which
    phase runs; elsewhere nothing is added, and an error stays one line."""
    path = tmp_path / "room.pcd"
    write_points(path, ROOM)
    terminal = {**os.environ, "FORCE_COLOR": "1", "COLUMNS": "300"}
    shown = run_cli("evaluate", path, "--pose", "0", "0", "1", "0", "--json", env=terminal)
    assert shown.returncode == 0, shown.stderr
    assert f"indexing {len(ROOM):,} points of {path}" in shown.stderr
    built = run_cli("solm", "build", path, "-o", tmp_path / "r.zarr", "--res", "4", "--ray-stride", "4", env=terminal)
    assert built.returncode == 0 and f"reading {path}" in built.stderr and "indexing" in built.stderr
    plain = run_cli("evaluate", path, "--pose", "0", "0", "1", "0", "--json")
    assert plain.returncode == 0 and "indexing" not in plain.stderr
    missing = run_cli("evaluate", tmp_path / "absent.pcd", "--pose", "0", "0", "1", "0")
    assert missing.returncode == 2 and len(missing.stderr.strip().splitlines()) == 1


@pytest.mark.slow
def test_the_demos_view_command_runs_as_printed(tmp_path, monkeypatch):
    from lf3pm.demo import cli_command, view_command

    repo = Path(__file__).resolve().parents[1]
    monkeypatch.chdir(repo)
    printed = view_command(Path("out/gobi"))
    argv = shlex.split(printed)
    assert argv[1:3] == ["view", "out/gobi/map.npy"] and argv[0] == cli_command()
    # lf3pm where it is on PATH, else the path of the one beside this Python (.venv/bin/lf3pm)
    assert argv[0] == "lf3pm" or Path(argv[0]).resolve() == (Path(sys.executable).parent / "lf3pm").resolve()
    assert subprocess.run([*argv[:2], "--help"], check=False, capture_output=True, timeout=120).returncode == 0
