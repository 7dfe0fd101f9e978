"""Hostile storage and misuse: a disk that fills, fails or vanishes under a long write, a
corrupt store, bad arguments to the public API and to the viewer. Each ends in one
Lf3pmError line (exit status 2 from the CLI) that names the file or chunk, within
seconds; an interrupted SOLM build resumes to the store an uninterrupted build writes."""

from __future__ import annotations

import errno
import json
import os
import shutil
import socket
import sqlite3
import subprocess
import sys
import time
import urllib.request
from types import SimpleNamespace

import numpy as np
import pytest
import zarr
from typer.testing import CliRunner

import lf3pm
from lf3pm.cli import app as cli
from lf3pm.errors import CorruptStoreError, Lf3pmError, StorageError
from lf3pm.io import write_points
from lf3pm.scenes import build_scene
from lf3pm.solm import Solm, build_solm, make_grid
from lf3pm.view import check_host, check_port, free_port, load_view_inputs, serve

BOUNDS = (-3.5, -3.5, 3.5, 3.5)
#: The test grid at tile 4 has 2 x 2 tiles, built in the order (0, 0), (0, 1), (1, 0), (1, 1).
TILE = 4
START, GOAL = ["-3", "3", "0"], ["3", "3", "0"]  # the row clear of boxes, y = 3


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The boxes scene as a map file, its indexed map, its SE(2) grid and the store an
    uninterrupted build writes (Mid-70, 8 yaw bins, tile 4)."""
    d = tmp_path_factory.mktemp("hostile")
    write_points(d / "map.npy", build_scene("boxes").points)
    world = lf3pm.load_map(d / "map.npy")
    grid = make_grid(world, "se2", 1.0, bounds=BOUNDS, yaw_bins=8, height=1.0)
    build_solm(world, "mid70", grid, d / "solm.zarr", tile=TILE)
    return SimpleNamespace(dir=d, world=world, grid=grid, store=d / "solm.zarr")


def one_line(err: BaseException) -> str:
    text = str(err)
    assert "\n" not in text, text
    return text


def cli_error(done, *texts):
    """The CLI's run ended in exit status 2 and one error line holding every text."""
    assert done.exit_code == 2, done.output
    lines = [line for line in done.output.splitlines() if line.startswith("lf3pm: error:")]
    assert len(lines) == 1, done.output
    assert "Traceback" not in done.output
    for text in texts:
        assert text in lines[0], lines[0]
    return lines[0]


def same_store(a, b) -> None:
    """Every array of the two stores is bitwise equal (NaN where NaN), and so are the attributes."""
    ga, gb = zarr.open_group(str(a), mode="r"), zarr.open_group(str(b), mode="r")
    assert sorted(ga.array_keys()) == sorted(gb.array_keys())
    for name in ga.array_keys():
        x, y = ga[name][...], gb[name][...]
        assert x.dtype == y.dtype and np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name
    assert {k: v for k, v in ga.attrs.items() if k != "map_source"} == {
        k: v for k, v in gb.attrs.items() if k != "map_source"
    }


@pytest.fixture
def failing_write(monkeypatch):
    """fail(key, errno, times=1): zarr's writes of the store key ending in ``key`` (say
    "q_max/c/0/1/0") fail with that OSError (the first ``times`` times), as a full or
    failing disk makes them fail; every other write goes through."""
    import zarr.storage._local as local

    real = local._put

    def fail(key, code, times=1):
        left = [times]

        def put(path, value, exclusive=False):
            if str(path).endswith(key) and left[0] > 0:
                left[0] -= 1
                raise OSError(code, os.strerror(code))
            return real(path, value, exclusive=exclusive)

        monkeypatch.setattr(local, "_put", put)

    yield fail
    monkeypatch.setattr(local, "_put", real)


# -- storage faults mid-write -------------------------------------------------------------


@pytest.mark.slow
def test_a_full_disk_mid_build_is_one_line_and_the_rerun_resumes_identically(site, tmp_path, failing_write):
    out = tmp_path / "s.zarr"
    failing_write("q_max/c/0/1/0", errno.ENOSPC)  # the third tile's q_max
    with pytest.raises(StorageError) as caught:
        build_solm(site.world, "mid70", site.grid, out, tile=TILE)
    text = one_line(caught.value)
    for part in (
        f"{out}/q_max/c/0/1/0",
        "No space left on device",
        "2 of 4 tiles finished and kept",
        f"lf3pm solm build {site.world.source} -o {out}",
        "resume",
    ):
        assert part in text, text
    assert zarr.open_group(str(out), mode="r")["done"][...].tolist() == [[1, 1], [0, 0]]
    again = build_solm(site.world, "mid70", site.grid, out, tile=TILE)
    assert again["built_now"] == 2 and again["complete"]
    same_store(out, site.store)


@pytest.mark.slow
def test_a_failed_done_flag_loses_only_its_tile(site, tmp_path, failing_write):
    """The done flag is written last: a tile whose data were written but whose flag was not
    is recomputed, and the store still ends as an uninterrupted build's."""
    out = tmp_path / "s.zarr"
    build_solm(site.world, "mid70", site.grid, out, tile=TILE, max_tiles=1)
    failing_write("done/c/0/0", errno.ENOSPC)
    with pytest.raises(StorageError, match=r"done/c/0/0: cannot write .*1 of 4 tiles finished"):
        build_solm(site.world, "mid70", site.grid, out, tile=TILE)
    assert build_solm(site.world, "mid70", site.grid, out, tile=TILE)["built_now"] == 3
    same_store(out, site.store)


@pytest.mark.slow
def test_an_io_error_on_the_ground_layer_is_one_line(site, tmp_path, failing_write):
    failing_write("ground_z/c/0/0", errno.EIO)
    with pytest.raises(StorageError) as caught:
        build_solm(site.world, "mid70", site.grid, tmp_path / "s.zarr", tile=TILE)
    text = one_line(caught.value)
    assert "ground_z: cannot write (Input/output error)" in text and "0 of 4 tiles" in text, text
    assert build_solm(site.world, "mid70", site.grid, tmp_path / "s.zarr", tile=TILE)["complete"]
    same_store(tmp_path / "s.zarr", site.store)


@pytest.mark.slow
def test_a_store_that_vanishes_mid_build_is_one_line_and_not_recreated(site, tmp_path):
    out = tmp_path / "gone" / "s.zarr"
    out.parent.mkdir()

    def vanish(cells, total):
        shutil.rmtree(out.parent)

    started = time.monotonic()
    with pytest.raises(StorageError) as caught:
        build_solm(site.world, "mid70", site.grid, out, tile=TILE, progress=vanish)
    assert time.monotonic() - started < 30
    assert f"{out}/zarr.json: the store vanished during the build" in one_line(caught.value)
    assert not out.parent.exists()  # zarr would have recreated the folders of the next chunk


@pytest.mark.slow
def test_the_cli_build_stops_in_one_line_and_resumes(site, tmp_path, failing_write):
    out = tmp_path / "cli.zarr"
    args = [
        "solm",
        "build",
        str(site.dir / "map.npy"),
        "-o",
        str(out),
        "--sensor",
        "mid70",
        "--space",
        "se2",
        "--res",
        "1",
        "--yaw-bins",
        "8",
        "--height",
        "1",
        "--bounds",
        *map(str, BOUNDS),
    ]
    failing_write("q_n/c/0/0/0", errno.ENOSPC)
    cli_error(
        CliRunner().invoke(cli, args),
        f"{out}/q_n/c/0/0/0",
        "No space left on device",
        "0 of 1 tiles finished",
        "lf3pm solm build",
    )
    failing_write("nothing", errno.ENOSPC)
    done = CliRunner().invoke(cli, args)
    assert done.exit_code == 0 and "complete: True" in done.output, done.output


@pytest.mark.slow
def test_a_build_onto_a_really_full_disk_resumes_bit_identically(site, tmp_path, mounted):
    """A real full file system (tmpfs, root only): the build stops in one line, and once
    space is freed the rerun completes to the store built on an ample disk."""
    disk = mounted("size=1m")
    reference = tmp_path / "reference.zarr"
    build_solm(site.world, "mid70", site.grid, reference, tile=TILE)
    (disk / "filler").write_bytes(b"\0" * (1024 * 1024 - 120 * 1024))
    with pytest.raises(StorageError, match="No space left on device") as caught:
        build_solm(site.world, "mid70", site.grid, disk / "s.zarr", tile=TILE)
    one_line(caught.value)
    (disk / "filler").unlink()
    assert build_solm(site.world, "mid70", site.grid, disk / "s.zarr", tile=TILE)["complete"]
    same_store(disk / "s.zarr", reference)


@pytest.fixture(scope="module")
def drive():
    """A 1 s Mid-70 scan stream and IMU samples on a floor with a wall (as tests/test_bag.py)."""
    from analytic_scenes import grid_plane

    from lf3pm.replays.motion import Motion
    from lf3pm.scan.scans import ScanStream
    from lf3pm.sensors import get_sensor

    pts = np.vstack(
        [
            grid_plane((-10, -10, 0), (1, 0, 0), (0, 1, 0), 20, 20, 0.1),
            grid_plane((6, -10, 0.1), (0, 1, 0), (0, 0, 1), 20, 3, 0.1),
        ]
    )
    world = lf3pm.load_map(np.ascontiguousarray(pts))
    t = np.linspace(0.0, 1.0, 101)
    motion = Motion.from_arrays(t, t, 0 * t, 0.2 * t, np.ones_like(t), 0 * t, np.full_like(t, 0.2), map=world)
    imu_t = np.arange(0.0, 1.0 + 1e-9, 1 / 200)
    imu = SimpleNamespace(t=imu_t, accel=np.tile([0.0, 0.0, 9.81], (len(imu_t), 1)), gyro=np.zeros((len(imu_t), 3)))
    return ScanStream(world, motion, get_sensor("mid70"), rate=10.0, seed=2), imu


def test_a_bag_whose_disk_fills_is_one_line_and_leaves_nothing(drive, tmp_path, monkeypatch):
    """sqlite says "database or disk is full" in its own error class, not an OSError."""
    from rosbags.rosbag2 import Writer

    from lf3pm.replays.bag import write_bag

    def full(self, *args, **kwargs):
        raise sqlite3.OperationalError("database or disk is full")

    monkeypatch.setattr(Writer, "write", full)
    with pytest.raises(StorageError) as caught:
        write_bag(tmp_path / "run.bag", *drive)
    text = one_line(caught.value)
    assert f"{tmp_path / 'run.bag'}: cannot write the bag (database or disk is full)" in text
    assert "run the replay with --bag again" in text and list(tmp_path.iterdir()) == []


def test_a_bag_onto_a_really_full_disk_is_one_line(drive, mounted):
    from lf3pm.replays.bag import write_bag

    disk = mounted("size=256k")
    with pytest.raises(StorageError, match="cannot write the bag") as caught:
        write_bag(disk / "run.bag", *drive)
    one_line(caught.value)
    assert list(disk.iterdir()) == []


def test_an_atomic_write_that_fails_keeps_the_old_file(tmp_path, monkeypatch):
    from lf3pm.atomic import atomic_write

    path = tmp_path / "kept.csv"
    path.write_text("old")

    def no_space(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", no_space)
    expected = r"kept.csv: cannot write the file \(No space left on device\); the existing file is left as it was$"
    with pytest.raises(StorageError, match=expected), atomic_write(path) as fp:
        fp.write(b"new")
    assert path.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["kept.csv"]


# -- corrupt stores -----------------------------------------------------------------------


def corrupt_copy(site, tmp_path, how: str):
    """A copy of the reference store damaged ``how``; returns it and the file damaged."""
    store = tmp_path / f"{how}.zarr"
    shutil.copytree(site.store, store)
    target = {
        "garbled chunk": "q_n/c/0/0/1",
        "truncated chunk": "q_n/c/0/1/1",
        "garbled metadata": "q_n/zarr.json",
        "missing metadata": "q_n/zarr.json",
        "garbled done": "done/c/0/0",
    }[how]
    path = store / target
    if how == "truncated chunk":
        path.write_bytes(path.read_bytes()[:7])
    elif how == "missing metadata":
        path.unlink()
    else:
        path.write_bytes(np.random.default_rng(0).integers(0, 256, 40, dtype=np.uint8).tobytes())
    return store, path


@pytest.mark.parametrize("how", ["garbled chunk", "truncated chunk", "garbled metadata", "missing metadata"])
def test_a_corrupt_channel_is_one_line_naming_its_file(site, tmp_path, how):
    store, damaged = corrupt_copy(site, tmp_path, how)
    solm = Solm.open(store)
    started = time.monotonic()
    with pytest.raises(CorruptStoreError) as caught:
        solm.query(0.0, 0.0)
    text = one_line(caught.value)
    assert text.startswith(f"{damaged}:") and "the store was not changed" in text
    assert f"lf3pm solm build {site.world.source} -o {store}" in text
    assert time.monotonic() - started < 10
    assert np.isfinite(solm.channel("q_min")).any()  # the other channels still read


def test_a_corrupt_done_flag_is_one_line_when_opened_and_when_resumed(site, tmp_path):
    store, damaged = corrupt_copy(site, tmp_path, "garbled done")
    with pytest.raises(CorruptStoreError, match=f"^{damaged}: a corrupt chunk of the SOLM's done"):
        Solm.open(store)
    with pytest.raises(CorruptStoreError, match=f"^{damaged}:"):
        build_solm(site.world, "mid70", site.grid, store, tile=TILE)


def test_lf3pm_plan_on_a_corrupt_chunk_is_one_line(site, tmp_path):
    store, damaged = corrupt_copy(site, tmp_path, "garbled chunk")
    done = CliRunner().invoke(
        cli, ["plan", "--solm", str(store), "--start", *START, "--goal", *GOAL, "-o", str(tmp_path / "t.csv")]
    )
    cli_error(done, str(damaged), "corrupt chunk", "build it again")
    assert not (tmp_path / "t.csv").exists()


@pytest.mark.slow
def test_the_viewer_shows_a_corrupt_chunk_in_the_page_and_keeps_serving(site, tmp_path, capfd):
    store, damaged = corrupt_copy(site, tmp_path, "garbled chunk")
    viewer = serve(load_view_inputs(site.dir / "map.npy", store), port=0)
    try:
        assert viewer.error_text.visible and str(damaged) in viewer.error_text.content
        assert f"lf3pm view: error: {damaged}" in capfd.readouterr().err
        page = urllib.request.urlopen(f"http://127.0.0.1:{viewer.port}/", timeout=10)
        assert page.status == 200  # still serving
        # A fault met later, by a page action: shown, and the page goes on.
        (store / "q_min/c/0/0/0").write_bytes(b"garbage")
        viewer.channel.value = "q_min"
        assert viewer.status.startswith(f"error: {store / 'q_min/c/0/0/0'}: a corrupt chunk")
        assert urllib.request.urlopen(f"http://127.0.0.1:{viewer.port}/", timeout=10).status == 200
        viewer.channel.value = "q_max"  # a sound channel draws, and its action's error is cleared
        assert "q_min/c/0/0/0" not in viewer.error_text.content
    finally:
        viewer.stop()


@pytest.mark.slow
def test_lf3pm_view_on_a_corrupt_chunk_serves_and_says_so_in_one_line(site, tmp_path):
    store, damaged = corrupt_copy(site, tmp_path, "garbled chunk")
    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "lf3pm", "view", str(site.dir / "map.npy"), "--solm", str(store), "--port", str(port)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            try:
                if urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=2).status == 200:
                    break
            except OSError:
                time.sleep(0.5)
        else:
            pytest.fail("lf3pm view did not serve")
        time.sleep(1.0)
        assert proc.poll() is None  # still serving
    finally:
        proc.terminate()
        _, err = proc.communicate(timeout=30)
    errors = [line for line in err.splitlines() if "error" in line]
    assert len(errors) == 1 and str(damaged) in errors[0] and "Traceback" not in err, err


# -- API misuse ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "args, kwargs, message",
    [
        ((float("nan"), 0.0), {}, "x must be finite, got nan"),
        ((0.0, float("inf")), {}, "y must be finite, got inf"),
        ((0.0, 0.0, float("nan")), {}, "yaw must be finite"),
        (("1.0", 0.0), {}, "x must be a number or an array of numbers, got '1.0'"),
        ((None, 0.0), {}, "x must be a number"),
        (({}, 0.0), {}, "x must be a number"),
        ((1j, 0.0), {}, "x must be a number"),
        (([[1.0], [1.0, 2.0]], 0.0), {}, "x must be a number"),
        (([1.0, 2.0], [1.0, 2.0, 3.0]), {}, "shapes do not broadcast together (x (2,), y (3,), yaw ())"),
        ((0.0, 0.0), {"channel": ["q_n"]}, "unknown channel ['q_n']"),
        ((0.0, 0.0), {"channel": None}, "unknown channel None"),
    ],
)
def test_bad_queries_are_lf3pm_errors(site, args, kwargs, message):
    solm = Solm.open(site.store)
    with pytest.raises(Lf3pmError) as caught:
        solm.query(*args, **kwargs)
    assert message in one_line(caught.value)


def test_good_queries_still_answer(site):
    solm = Solm.open(site.store)
    value, grad = solm.query(np.array([0.0, 1.0]), np.array([0.5, 0.5]), yaw=np.array([0.0, 7.0]))
    assert value.shape == (2,) and grad.shape == (2, 3) and np.isfinite(value).any()
    assert solm.query(0, 0, True)[0] == solm.query(0.0, 0.0, 1.0)[0]  # integers and booleans are numbers


@pytest.mark.parametrize("path", [3, None, 2.5])
def test_opening_a_store_that_is_not_a_path_is_an_lf3pm_error(path):
    with pytest.raises(Lf3pmError, match="a SOLM store is a path"):
        Solm.open(path)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"world": "map.npy"}, "build_solm needs a map"),
        ({"world": np.zeros((10, 3))}, "build_solm needs a map"),
        ({"grid": None}, "build_solm needs a grid"),
        ({"out": 5}, "the SOLM store to build is a path"),
        ({"tile": "four"}, "solm.tile must be a valid integer"),
        ({"tile": 2.5}, "solm.tile must be a valid integer"),
        ({"tile": 10**12}, "solm.tile must be less than or equal to 1024"),
        ({"tile": 0}, "solm.tile must be greater than or equal to 1"),
        ({"max_tiles": -1}, "max_tiles must be None or an integer >= 0"),
        ({"max_tiles": "2"}, "max_tiles must be None"),
        ({"floor_clearance": "a"}, "solm.floor_clearance must be a valid number"),
        ({"yaw_bins": 12}, "build_solm takes yaw_bins from its grid: give it to make_grid"),
        ({"yaw_bin": 12}, "build_solm has no parameter 'yaw_bin'"),
        ({"progress": 3}, "progress must be a function"),
    ],
)
def test_bad_build_arguments_are_lf3pm_errors_before_anything_is_written(site, tmp_path, change, message):
    kwargs = {"world": site.world, "sensor": "mid70", "grid": site.grid, "out": tmp_path / "x.zarr", **change}
    with pytest.raises(Lf3pmError) as caught:
        build_solm(kwargs.pop("world"), kwargs.pop("sensor"), kwargs.pop("grid"), kwargs.pop("out"), **kwargs)
    assert message in one_line(caught.value)
    assert list(tmp_path.iterdir()) == []


def test_bad_bag_arguments_are_lf3pm_errors(drive, tmp_path):
    from lf3pm.replays.bag import write_bag

    with pytest.raises(Lf3pmError, match="a bag is written to a path, got int"):
        write_bag(5, *drive)
    with pytest.raises(Lf3pmError, match="ground truth rate must be > 0 Hz, got 'fast'"):
        write_bag(tmp_path / "b.bag", *drive, truth_rate="fast")


def test_bad_viewer_input_lists_are_lf3pm_errors(site):
    with pytest.raises(Lf3pmError, match="the plan files must be a list of paths, got int"):
        load_view_inputs(site.dir / "map.npy", plan_paths=5)
    with pytest.raises(Lf3pmError, match="the replay files must be paths, got int"):
        load_view_inputs(site.dir / "map.npy", replay_paths=[3])


# -- viewer misuse ------------------------------------------------------------------------


@pytest.fixture(scope="module")
def inputs(site):
    return load_view_inputs(site.dir / "map.npy")


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"host": "bad.invalid"}, "host 'bad.invalid' is not an address of this machine"),
        ({"host": "192.0.2.1"}, "host '192.0.2.1' is not an address of this machine"),  # TEST-NET: never ours
        ({"host": 5}, "host must be a name or an address, got int"),
        ({"port": -5}, "port must be between 1 and 65535, got -5"),
        ({"port": 70000}, "port must be between 1 and 65535, got 70000"),
        ({"port": "8080"}, "port must be an integer from 1 to 65535, got '8080'"),
        ({"port": 8080.0}, "port must be an integer"),
        ({"port": True}, "port must be an integer"),
        ({"robot": "omni"}, "robot must be an lf3pm.Robot"),
        ({"sensor": "no-such-lidar"}, "no-such-lidar"),
    ],
)
def test_bad_serve_arguments_are_lf3pm_errors_within_seconds(inputs, kwargs, message):
    started = time.monotonic()
    with pytest.raises(Lf3pmError) as caught:
        serve(inputs, **{"port": free_port(), **kwargs})
    assert message in one_line(caught.value)
    assert time.monotonic() - started < 5


def test_serve_needs_the_viewers_inputs():
    with pytest.raises(Lf3pmError, match="serve needs the viewer's inputs"):
        serve("map.npy")


def test_a_port_in_use_is_refused_and_port_0_takes_any_free_one(inputs):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(Lf3pmError, match=f"^port {port} on 127.0.0.1 is in use: choose another port$"):
            serve(inputs, port=port)
        with pytest.raises(Lf3pmError, match="in use"):
            check_port("127.0.0.1", port)
    viewer = serve(inputs, port=0)
    try:
        assert viewer.port > 0 and urllib.request.urlopen(f"http://127.0.0.1:{viewer.port}/", timeout=10).status == 200
    finally:
        viewer.stop()


def test_a_port_taken_after_the_check_is_refused_not_moved(inputs, monkeypatch):
    """Between check_port and viser's bind another program may take the port: viser would
    then serve on the next one; serve refuses instead and stops what it started."""
    import lf3pm.view.app as view_app

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        monkeypatch.setattr(view_app, "check_port", lambda host, port: None)
        with pytest.raises(Lf3pmError, match=f"port {port} on 127.0.0.1 is in use"):
            serve(inputs, port=port)
        with pytest.raises(OSError):  # nothing serves on the next port
            urllib.request.urlopen(f"http://127.0.0.1:{port + 1}/", timeout=2)


def test_check_host_accepts_this_machines_addresses():
    check_host("127.0.0.1")
    check_host("0.0.0.0")
    with pytest.raises(Lf3pmError, match="not an address of this machine"):
        free_port("bad.invalid")


def replay_json(tmp_path, name, **changes):
    run = {
        "truth_xyz": [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
        "estimate_xyz": [[0.0, 0.0, 0.0], [1.0, 0.1, 0.0], [2.0, 0.2, 0.0]],
        "errors": [0.0, 0.1, 0.2],
    }
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps({"runs": [{**run, **changes}]}))
    return path


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"errors": ["0.0", "0.1", "0.2"]}, "errors[0] must be a number or null, got '0.0'"),
        ({"errors": "small"}, "errors must be a list, got str"),
        ({"errors": [0.0, -0.1, 0.2]}, "errors must be >= 0"),
        ({"truth_xyz": [[0, 0], [1, 0, 0], [2, 0, 0]]}, "truth_xyz[0] must be [x, y, z] of numbers, got [0, 0]"),
        ({"truth_xyz": [[0, 0, None], [1, 0, 0], [2, 0, 0]]}, "truth_xyz[0] must be [x, y, z] of numbers"),
        ({"estimate_xyz": [[0, 0, 0], [1, 0, "x"], [2, 0, 0]]}, "estimate_xyz[1] must be [x, y, z] of numbers or null"),
        ({"errors": [0.0, 0.1]}, "differ in length (3, 3, 2)"),
        ({"rest": {"steady": "no"}}, "rest must be an object with steady"),
    ],
)
def test_a_bad_replay_json_is_one_line_naming_the_file_and_field(site, tmp_path, changes, message):
    path = replay_json(tmp_path, "bad", **changes)
    with pytest.raises(Lf3pmError) as caught:
        load_view_inputs(site.dir / "map.npy", replay_paths=[path])
    text = one_line(caught.value)
    assert text.startswith(f"{path}: the replay JSON's ") and message in text, text


def test_a_replay_json_with_a_lost_estimate_is_shown(site, tmp_path):
    path = replay_json(
        tmp_path, "lost", estimate_xyz=[[0, 0, 0], [None, None, None], [2, 0, 0]], errors=[0.0, None, 0.2]
    )
    tracks = load_view_inputs(site.dir / "map.npy", replay_paths=path).replays["replay lost"]
    assert np.isnan(tracks["errors"][1]) and tracks["hi"] == pytest.approx(0.2)


def test_a_replay_that_is_not_a_regular_file_is_refused_before_it_is_read(site, tmp_path):
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    started = time.monotonic()
    with pytest.raises(Lf3pmError, match="pipe.json: not a regular file"):
        load_view_inputs(site.dir / "map.npy", replay_paths=[fifo])
    assert time.monotonic() - started < 5


@pytest.mark.slow
def test_lf3pm_view_refuses_a_bad_replay_json_and_a_bad_host_in_one_line(site, tmp_path):
    bad = replay_json(tmp_path, "strings", errors=["x", "y", "z"])
    for args, text in (
        ([str(site.dir / "map.npy"), "--replay", str(bad)], "errors[0] must be a number"),
        ([str(site.dir / "map.npy"), "--host", "bad.invalid"], "bad.invalid"),
    ):
        started = time.monotonic()
        run = subprocess.run(
            [sys.executable, "-m", "lf3pm", "view", *args, "--port", str(free_port())],
            check=False,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert run.returncode == 2, run.stderr
        assert len(run.stderr.strip().splitlines()) == 1 and text in run.stderr, run.stderr
        assert time.monotonic() - started < 60
