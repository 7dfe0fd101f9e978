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
    return CliRunner().invoke(app, ["plan", "--solm", store, "--start", *START, "--goal", *GOAL, "--robot", "diff",
                                    "--r-safe", "0.1", "-o", str(csv), "--png", str(png)])


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
    one_line_error(CliRunner().invoke(app, ["solm", "view", store, "-o", str(tmp_path / "no" / "q.png")]),
                   "cannot write the file")
    (tmp_path / "file").write_text("x")
    one_line_error(CliRunner().invoke(app, ["solm", "export", store, str(tmp_path / "file" / "ros")]),
                   "cannot create the folder")
    one_line_error(CliRunner().invoke(app, ["solm", "view", store, "-o", str(tmp_path)]), "is a directory")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]
