"""Hostile input (issue 39): every size, count and resolution is bounded where it enters,
a config or sensor file is read only when it is a small regular file with a bounded
YAML expansion, user text is printed verbatim, warnings are one line, and outputs are
checked before any work. Each bad input is one line on stderr and exit 2 within
seconds from the CLI, and an Lf3pmError from the API."""

import importlib.util
import math
import os
import subprocess
import sys
import time

import numpy as np
import pytest
from typer.testing import CliRunner

import lf3pm
from lf3pm.cli import app
from lf3pm.config import (
    MAX_CELL_SIZE,
    MAX_CELLS_CEILING,
    MAX_LIMIT,
    MAX_RES,
    MAX_TRAJECTORY_SECONDS,
    ConfigError,
    load_config,
)
from lf3pm.errors import Lf3pmError, SensorError
from lf3pm.limits import EXCERPT, MAX_TEXT_BYTES, MAX_TRAJECTORY_BYTES, MAX_YAML_DEPTH, MAX_YAML_NODES
from lf3pm.scenes import build_scene
from lf3pm.sensors import load_sensor_yaml
from lf3pm.sensors._model import MAX_RAYS
from lf3pm.solm import make_grid
from lf3pm.solm.grid import SolmGrid
from lf3pm.solm.occupancy import MAX_OCCUPANCY_CELLS, OCCUPANCY_RES, occupancy_factor

#: An error line quoting a value keeps to this many characters whatever the value.
SHORT = 400


@pytest.fixture(scope="module")
def boxes(tmp_path_factory):
    path = tmp_path_factory.mktemp("hostile") / "boxes.npy"
    np.save(path, build_scene("boxes").points)
    return path


def one_line_error(done, text: str, within: float | None = None, started: float | None = None) -> str:
    """The error line of a CliRunner result: exit 2, one line on stderr, holding ``text``."""
    assert done.exit_code == 2, done.output
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lf3pm: error: ") and text in lines[0], done.stderr[:2000]
    if within is not None:
        assert time.monotonic() - started < within
    return lines[0]


def invoke(*args):
    """(result, start time) of the CLI on ``args``."""
    started = time.monotonic()
    return CliRunner().invoke(app, [str(a) for a in args]), started


def run_cli(*args, timeout=120):
    """The CLI in a subprocess (warnings are printed there, not recorded by pytest)."""
    return subprocess.run(
        [sys.executable, "-m", "lf3pm.cli", *map(str, args)], capture_output=True, text=True, timeout=timeout
    )


def alias_bomb(levels: int = 9) -> str:
    """YAML of nine levels of nine aliases: 9^9 values once expanded, in 300 bytes."""
    items = ["&a0 [x, x, x, x, x, x, x, x, x]"]
    for k in range(1, levels):
        items.append(f"&a{k} [" + ", ".join([f"*a{k - 1}"] * 9) + "]")
    return "scan:\n  noise: [" + ", ".join(items) + "]\n"


# --- resource limits -----------------------------------------------------------------


@pytest.mark.parametrize(
    "options, text",
    [
        (["--res", "1e9"], f"--res must be less than or equal to {MAX_RES:g}"),  # spun forever
        (["--res", "1e7"], f"--res must be less than or equal to {MAX_RES:g}"),  # 54 s for one cell
        (["--res", "50"], "res 50 m is wider than the grid"),
        (["--res", "1e-300"], "more than 10,000,000 poses"),
        (["--res", "5e-324"], "more than 10,000,000 poses"),
        (
            ["--max-cells", str(10 * MAX_CELLS_CEILING)],
            f"--max-cells must be less than or equal to {MAX_CELLS_CEILING}",
        ),
        (["--space", "r3", "--res", "1e-300"], "raise --max-cells"),
    ],
)
def test_solm_sizes_are_bounded_in_the_cli(boxes, tmp_path, options, text):
    done, started = invoke("solm", "build", boxes, "-o", tmp_path / "x.zarr", *options)
    one_line_error(done, text, within=20, started=started)
    assert not (tmp_path / "x.zarr").exists()


def test_solm_sizes_are_bounded_in_the_api(boxes):
    world = lf3pm.load_map(boxes)
    with pytest.raises(ConfigError, match="solm.res must be less than or equal to"):
        make_grid(world, "r2", 1e12)
    with pytest.raises(Lf3pmError, match="wider than the grid"):
        make_grid(world, "r2", 500.0)
    with pytest.raises(Lf3pmError, match="more than 10,000,000 poses"):
        make_grid(world, "r2", 5e-324)
    with pytest.raises(ConfigError, match="solm.max_cells must be less than or equal to"):
        make_grid(world, "r2", 0.5, max_cells=10**12)
    span = float(max(world.bounds[1][:2] - world.bounds[0][:2]))
    assert make_grid(world, "r2", span).shape == (1, 1)  # one cell over the whole map is still a grid


def test_the_knn_voxel_is_bounded(boxes, tmp_path):
    # 20 m: 49 s for one evaluate on the boxes room (2 s at its own 0.16 m); 1e12 m: no planes.
    config = tmp_path / "c.yaml"
    config.write_text("map: {cell_size: 20.0}\n")
    done, started = invoke("evaluate", boxes, "--pose", "0", "0", "1", "0", "--config", config)
    one_line_error(done, f"map.cell_size must be less than or equal to {MAX_CELL_SIZE:g}", within=20, started=started)
    with pytest.raises(ConfigError, match="map.cell_size must be less than or equal to"):
        lf3pm.load_map(boxes, cell_size=1e12)


def test_a_replay_is_bounded_in_time(boxes, tmp_path):
    # A CSV whose last stamp is 1e7 s filled 12 GB with the motion's ground knots, without end.
    csv = tmp_path / "long.csv"
    csv.write_text(f"t,x,y,yaw,vx,vy,omega\n0,0,0,0,0,0,0\n{MAX_TRAJECTORY_SECONDS + 1:g},0.1,0,0,0,0,0\n")
    done, started = invoke("replay", csv, "--map", tmp_path / "missing.npy")  # refused before the map is read
    one_line_error(
        done, f"more than {MAX_TRAJECTORY_SECONDS:g} s, the longest lf3pm replays", within=20, started=started
    )
    with open(csv, "ab") as fp:
        fp.truncate(MAX_TRAJECTORY_BYTES + 1)  # sparse: no disk used
    for path, text in (("/dev/zero", "not a regular file"), (csv, f"larger than {MAX_TRAJECTORY_BYTES:,} bytes")):
        done, started = invoke("replay", path, "--map", tmp_path / "missing.npy")  # /dev/zero: read without end
        one_line_error(done, text, within=20, started=started)


def test_robot_limits_are_bounded(tmp_path):
    # 1e12 m/s and friends gave a 6e6 s trajectory; refused before the SOLM is opened.
    for flag in ("--vmax-lon", "--vmax-lat", "--wmax", "--amax-lon", "--amax-lat", "--alpha-max"):
        done, started = invoke(
            "plan",
            "--solm",
            tmp_path / "missing.zarr",
            "--start",
            "0",
            "0",
            "0",
            "--goal",
            "1",
            "1",
            "0",
            "-o",
            tmp_path / "t.csv",
            flag,
            "1e12",
        )
        one_line_error(done, f"{flag} must be less than or equal to {MAX_LIMIT:g}", within=20, started=started)
    from lf3pm.trajectory.robots import Robot

    with pytest.raises(Lf3pmError, match="less than or equal to"):
        Robot("omni", vmax_lon=1e12)


def test_the_occupancy_factor_is_closed_form():
    # The largest k <= res / OCCUPANCY_RES with nx ny k^2 within the limit, as the old
    # count-down loop found it, for every small grid; and at once for res 1e9 m.
    for res in (0.05, 0.1, 0.25, 0.5, 1.0, 1.5, 13.7):
        for n in (1, 7, 100, 1024, 1025, 5000):
            k = occupancy_factor(SolmGrid("r2", 0.0, 0.0, res, n, n + 3))
            wanted = max(1, math.ceil(res / OCCUPANCY_RES - 1e-9))
            assert 1 <= k <= wanted
            assert k == 1 or n * (n + 3) * k * k <= MAX_OCCUPANCY_CELLS
            assert k == wanted or n * (n + 3) * (k + 1) ** 2 > MAX_OCCUPANCY_CELLS
    started = time.monotonic()
    assert occupancy_factor(SolmGrid("r2", 0.0, 0.0, 1e9, 1, 1)) == math.isqrt(MAX_OCCUPANCY_CELLS)
    assert time.monotonic() - started < 0.1


def test_a_sensor_pattern_is_bounded_before_it_is_read(tmp_path):
    # A header claiming more rays than MAX_RAYS over a sparse file: refused from its shape,
    # without reading 320 MB.
    pattern = tmp_path / "huge.npy"
    with open(pattern, "wb") as fp:
        np.lib.format.write_array_header_1_0(fp, {"descr": "<f8", "fortran_order": False, "shape": (MAX_RAYS + 1, 2)})
        fp.truncate(fp.tell() + 16 * (MAX_RAYS + 1))
    sensor = tmp_path / "s.yaml"
    sensor.write_text(
        f"name: huge\nmin_range: 0.5\nmax_range: 100\npattern_file: {pattern}\n"
        "point_rate: 100000\nintegration_time: 0.1\n"
    )
    started = time.monotonic()
    with pytest.raises(SensorError, match=f"more than the limit of {MAX_RAYS:,}"):
        load_sensor_yaml(sensor)
    assert time.monotonic() - started < 5
    sensor.write_text(
        "name: " + "n" * 1000 + "\nmin_range: 0.5\nmax_range: 100\nelevations_deg: [0]\nazimuth_count: 10\n"
    )
    with pytest.raises(SensorError, match="'name' must be at most 64 characters, got 1,000"):
        load_sensor_yaml(sensor)


# --- config files ----------------------------------------------------------------------


def config_error(*config) -> str:
    done, started = invoke("config", "--config", *config)
    return one_line_error(done, "", within=20, started=started)


@pytest.mark.slow
def test_a_config_that_is_not_a_regular_file_is_refused_at_once(tmp_path):
    # /dev/zero was read without end (+2.7 GB in 8 s); a FIFO would wait for a writer.
    assert "/dev/zero: the config is a device, FIFO or socket, not a regular file" in config_error("/dev/zero")
    assert "the config is a directory" in config_error(tmp_path)
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    done = run_cli("config", "--config", fifo, timeout=60)
    assert done.returncode == 2 and "not a regular file" in done.stderr and len(done.stderr.splitlines()) == 1
    with pytest.raises(ConfigError, match="not a regular file"):
        load_config("/dev/zero")


def test_a_config_larger_than_the_limit_is_refused(tmp_path):
    big = tmp_path / "big.yaml"
    big.write_text("# padding\n" * (MAX_TEXT_BYTES // 10 + 1))
    assert f"larger than {MAX_TEXT_BYTES:,} bytes" in config_error(big)
    big.write_text("# padding\n" * (MAX_TEXT_BYTES // 10 - 1))
    assert CliRunner().invoke(app, ["config", "--config", str(big)]).exit_code == 0  # just below: read


@pytest.mark.parametrize(
    "text, message",
    [
        (alias_bomb(), f"aliases expand to more than {MAX_YAML_NODES:,} values"),
        ("scan: &a {noise: [*a]}\n", "an alias inside the node it names"),
        ("scan: {noise: " + "[" * 400 + "]" * 400 + "}\n", f"nested deeper than {MAX_YAML_DEPTH} levels"),
        ("1: 2\n", "key 1 is not a parameter name"),
    ],
)
def test_yaml_beyond_the_limits_is_one_short_line(tmp_path, text, message):
    config = tmp_path / "c.yaml"
    config.write_text(text)
    line = config_error(config)  # the bomb: 17 s and a 226 MB line before
    assert message in line and len(line) < SHORT
    with pytest.raises(ConfigError, match=message):
        load_config(config)


@pytest.mark.slow
def test_errors_quote_a_short_excerpt_of_a_value(tmp_path):
    config = tmp_path / "c.yaml"
    for value in (
        '"' + "x" * 100_000 + '"',
        "[" + ", ".join(["[1, 2, 3]"] * 10_000) + "]",
        "{" + ", ".join(f"k{i}: {i}" for i in range(10_000)) + "}",
    ):
        config.write_text(f"scan:\n  noise: {value}\n")
        line = config_error(config)
        assert line.startswith(f"lf3pm: error: {config}: scan.noise must be") and len(line) < SHORT, line[:SHORT]
    config.write_text("scan:\n  ? " + "k" * 10_000 + "\n  : 1\n")  # an explicit key: no length limit
    assert "characters) is not a parameter" in config_error(config)
    assert EXCERPT < SHORT


def test_sensor_files_are_read_within_the_same_limits(tmp_path, boxes):
    sensor = tmp_path / "s.yaml"
    sensor.write_text(alias_bomb().replace("scan:\n  noise:", "elevations_deg:"))
    for path, message in ((sensor, "aliases expand to more than"), ("/dev/zero", "not a regular file")):
        with pytest.raises(SensorError, match=message):
            load_sensor_yaml(path)
        done, started = invoke("evaluate", boxes, "--pose", "0", "0", "1", "0", "--sensor", path)
        assert len(one_line_error(done, message, within=20, started=started)) < SHORT
    sensor.write_text(
        "name: s\nmin_range: 0.5\nmax_range: 100\nazimuth_count: 10\nelevations_deg: ["
        + ", ".join(["0"] * 1000)
        + ', "'
        + "y" * 10_000
        + '"]\n'
    )
    with pytest.raises(SensorError, match="item 1000 must be a finite number") as err:
        load_sensor_yaml(sensor)
    assert len(str(err.value)) < SHORT


# --- markup in paths -------------------------------------------------------------------


def test_paths_and_values_are_printed_verbatim(boxes, tmp_path):
    # Rich markup took "[red]" for a tag and "[nan, ...]" too: both vanished.
    one_line_error(invoke("info", "bad/[red]map.pcd")[0], "bad/[red]map.pcd: no such file")
    one_line_error(
        invoke("evaluate", boxes, "--pose", "nan", "0", "1", "0")[0], "pose has non-finite values: [nan, 0.0, 1.0, 0.0]"
    )
    one_line_error(invoke("config", "--config", tmp_path / "[bold]c.yaml")[0], "[bold]c.yaml: cannot read")
    one_line_error(invoke("info", tmp_path / "two\nlines.npy")[0], "two\\nlines.npy: no such file")


def test_a_bad_host_is_named_as_the_host(boxes):
    line = one_line_error(invoke("view", boxes, "--host", "bad.invalid")[0], "host 'bad.invalid' is not an address")
    assert "--port" not in line and "0.0.0.0" in line


# --- warnings format -------------------------------------------------------------------


@pytest.mark.slow
def test_warnings_are_one_line_without_source(tmp_path):
    points = build_scene("boxes").points.copy()
    points[:3] = np.nan
    path = tmp_path / "[yellow]nan.npy"
    np.save(path, points)
    done = run_cli("info", path)
    assert done.returncode == 0, done.stderr
    assert done.stderr.splitlines() == [
        f"lf3pm: warning: {path}: dropped 3 of {len(points)} points with a NaN or infinite coordinate"
    ]


@pytest.mark.slow
@pytest.mark.skipif(importlib.util.find_spec("evalio") is None, reason="the LIO is not installed")
def test_an_odometry_on_a_sensor_it_loses_is_warned_in_one_line(boxes):
    done = run_cli(
        "replay", "missing.csv", "--map", boxes, "--method", "lio", "--odometry", "dlio", "--sensor", "mid70"
    )
    warning, error = done.stderr.splitlines()
    assert warning.startswith("lf3pm: warning: mid70 with dlio: DLIO loses track") and "docs/lio.md" in warning
    assert error.startswith("lf3pm: error: missing.csv") and done.returncode == 2


def test_the_odometry_warnings_come_from_one_table():
    pytest.importorskip("lf3pm.replays.lio")
    from lf3pm.replays.lio import LOSES, ODOMETRIES, choose_odometry
    from lf3pm.sensors import get_sensor, spinning_rings

    assert {odometry for odometry, _ in LOSES} <= set(ODOMETRIES)
    mid70, vlp16 = get_sensor("mid70"), get_sensor("vlp16")
    with pytest.warns(UserWarning, match="mid70 with dlio: DLIO loses track"):
        assert choose_odometry("dlio", mid70) == "dlio"
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for odometry in ODOMETRIES:
            for sensor in (mid70, vlp16):
                spinning = spinning_rings(sensor) is not None
                if (odometry, spinning) not in LOSES and (spinning or odometry != "liosam"):
                    choose_odometry(odometry, sensor)  # no warning for a pair the docs do not flag
        choose_odometry("auto", mid70)


# --- outputs checked early -------------------------------------------------------------


@pytest.fixture
def blocked(tmp_path):
    """A regular file where a folder should be: no output can go under it, even for root."""
    path = tmp_path / "file"
    path.write_text("")
    return path


def test_outputs_are_checked_before_any_input_is_read(blocked, tmp_path):
    # The inputs do not exist: an error about the output proves it came first.
    missing = tmp_path / "missing"
    for args in (
        ["replay", missing / "t.csv", "--map", missing / "m.npy", "--png", blocked / "r.png"],
        ["replay", missing / "t.csv", "--map", missing / "m.npy", "--bag", blocked / "r.bag"],
        ["solm", "build", missing / "m.npy", "-o", blocked / "s.zarr"],
        ["solm", "view", missing / "s.zarr", "-o", blocked / "v.png"],
        [
            "plan",
            "--solm",
            missing / "s.zarr",
            "--start",
            "0",
            "0",
            "0",
            "--goal",
            "1",
            "1",
            "0",
            "-o",
            blocked / "t.csv",
        ],
        [
            "plan",
            "--solm",
            missing / "s.zarr",
            "--start",
            "0",
            "0",
            "0",
            "--goal",
            "1",
            "1",
            "0",
            "-o",
            tmp_path / "t.csv",
            "--png",
            blocked / "p.png",
        ],
        ["evaluate", missing / "m.npy", "--pose", "0", "0", "1", "0", "--save-observations", blocked / "o.npz"],
        ["experiment", "table1", "-o", blocked / "deeper" / "out"],
        ["scene", "boxes", "-o", blocked / "b.pcd"],
    ):
        done, started = invoke(*args)
        one_line_error(done, f"{blocked} is not a folder", within=20, started=started)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_outputs_into_missing_or_existing_places(tmp_path, boxes):
    missing = tmp_path / "missing"
    one_line_error(invoke("scene", "boxes", "-o", missing / "b.pcd")[0], f"{missing} does not exist; create it")
    (tmp_path / "old.bag").mkdir()
    one_line_error(
        invoke("replay", "t.csv", "--map", boxes, "--bag", tmp_path / "old.bag")[0],
        "old.bag exists: lf3pm writes it as a new folder",
    )
    # A folder to be created with its parents passes (its probe removed), then the next check fails.
    done = CliRunner().invoke(app, ["experiment", "table1", "-o", str(tmp_path / "a" / "b"), "--poses", "0"])
    assert done.exit_code == 2 and "--poses must be" in done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.bag"]


def test_a_read_only_output_fails_before_the_work(tmp_path, boxes):
    """The probe: a read-only mount (root writes into chmod 555 folders) is found at once."""
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    mount = tmp_path / "ro"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=1m", "tmpfs", str(mount)], capture_output=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")
    try:
        for args in (
            ["replay", tmp_path / "t.csv", "--map", boxes, "--png", mount / "r.png"],
            ["replay", tmp_path / "t.csv", "--map", boxes, "--bag", mount / "r.bag"],
            ["solm", "build", boxes, "-o", mount / "s.zarr"],
            ["experiment", "benefit", "-o", mount / "b"],
        ):
            done, started = invoke(*args)
            one_line_error(done, "Read-only file system", within=20, started=started)
        assert list(mount.iterdir()) == []
    finally:
        subprocess.run(["umount", str(mount)], check=False)


# --- command lines click cannot parse ----------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize(
    "args, text",
    [
        (["plann"], "No such command 'plann'"),
        (["solm", "build", "m.pcd", "-o", "s.zarr", "--max-cells", "abc"], "Invalid value for '--max-cells'"),
        (["plan", "--solm", "s.zarr"], "Missing option"),
    ],
)
def test_a_command_line_that_does_not_parse_is_one_line(args, text):
    """Not click's usage box (five lines and a frame): one line naming what is wrong and the
    command whose --help lists what it takes, exit 2."""
    done = run_cli(*args)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lf3pm: error: ") and text in lines[0], done.stderr
    assert "--help` lists what it takes" in lines[0]
