"""Outputs that cannot be written are one line and exit 2, leave no temporary file, and a
command's outputs are all or none (`plan` used to keep its CSV when its PNG failed)."""

import numpy as np
import pytest
from typer.testing import CliRunner

import lf3pm
from lf3pm.cli import app

START, GOAL = ["-3", "-3", "0"], ["6.2", "2.8", "0"]


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    folder = tmp_path_factory.mktemp("outputs")
    world = lf3pm.load_map(lf3pm.build_scene("boxes").points)
    lf3pm.build_solm(world, "vlp16", lf3pm.make_grid(world, "r2", 0.5), folder / "boxes.zarr", ray_stride=8)
    return str(folder / "boxes.zarr")


def one_line_error(done, text):
    assert done.exit_code == 2, done.output
    lines = [line for line in done.output.splitlines() if line.startswith("lf3pm: error:")]
    assert len(lines) == 1 and text in lines[0], done.output


def plan(store, csv, png):
    return CliRunner().invoke(
        app,
        [
            "plan",
            "--solm",
            store,
            "--start",
            *START,
            "--goal",
            *GOAL,
            "--robot",
            "diff",
            "--r-safe",
            "0.1",
            "-o",
            str(csv),
            "--png",
            str(png),
        ],
    )


@pytest.mark.slow
def test_plan_writes_both_outputs_or_neither(store, tmp_path):
    missing = tmp_path / "missing"
    one_line_error(plan(store, tmp_path / "a.csv", missing / "a.png"), "cannot write the file")
    one_line_error(plan(store, missing / "b.csv", tmp_path / "b.png"), "cannot write the file")
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # no output, no temporary file
    done = plan(store, tmp_path / "c.csv", tmp_path / "c.png")
    assert done.exit_code == 0, done.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.csv", "c.png"]
    assert np.loadtxt(tmp_path / "c.csv", delimiter=",", skiprows=1).shape[1] == 7


def test_figures_and_exports_into_missing_folders_are_one_line(store, tmp_path):
    one_line_error(
        CliRunner().invoke(app, ["solm", "view", store, "-o", str(tmp_path / "no" / "q.png")]), "cannot write the file"
    )
    (tmp_path / "file").write_text("x")
    one_line_error(
        CliRunner().invoke(app, ["solm", "export", store, str(tmp_path / "file" / "ros")]), "cannot create the folder"
    )
    one_line_error(CliRunner().invoke(app, ["solm", "view", store, "-o", str(tmp_path)]), "is a directory")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_writes_onto_read_only_storage_are_one_line(store, tmp_path, mounted):
    """A real read-only mount (root can write into chmod 555 folders, so those prove nothing):
    every writing command says so in one line, exit 2, and leaves nothing."""
    ro = mounted("ro,size=1m")
    runner = CliRunner()
    world = tmp_path / "boxes.npy"
    np.save(world, lf3pm.build_scene("boxes").points)
    for args in (
        ["scene", "boxes", "-o", str(ro / "x.pcd")],
        ["evaluate", str(world), "--pose", "0", "0", "1", "0", "--save-observations", str(ro / "o.npz")],
        ["solm", "view", store, "-o", str(ro / "v.png")],
    ):
        one_line_error(runner.invoke(app, args), "Read-only file system")
    one_line_error(plan(store, ro / "t.csv", tmp_path / "p.png"), "Read-only file system")
    one_line_error(plan(store, tmp_path / "t.csv", ro / "p.png"), "Read-only file system")
    assert list(ro.iterdir()) == [] and sorted(p.name for p in tmp_path.iterdir()) == ["boxes.npy", "mnt0"]


def test_a_full_disk_is_one_line_and_leaves_nothing(store, mounted):
    full = mounted("size=64k")
    (full / "filler").write_bytes(b"\0" * 60_000)
    done = CliRunner().invoke(app, ["scene", "boxes", "-o", str(full / "x.pcd")])
    one_line_error(done, "No space left on device")
    assert [p.name for p in full.iterdir()] == ["filler"]


def test_a_config_that_is_not_text_is_one_line(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_bytes(np.random.default_rng(0).integers(0, 256, 300, dtype=np.uint8).tobytes())
    one_line_error(CliRunner().invoke(app, ["config", "--config", str(bad)]), "not UTF-8 text")
