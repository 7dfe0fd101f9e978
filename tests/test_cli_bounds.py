"""Every parameter is validated once (lf3pm.config) before it reaches the core: a
negative or over-64-bit seed used to be a nanobind TypeError traceback, `--threads -1`
an OpenMP abort asking for 927 GB; each hostile value is now one line naming its flag."""

import numpy as np
import pytest
from typer.testing import CliRunner

from lf3pm.cli import app
from lf3pm.scenes import build_scene


@pytest.fixture(scope="module")
def boxes(tmp_path_factory):
    path = tmp_path_factory.mktemp("bounds") / "boxes.npy"
    np.save(path, build_scene("boxes").points)
    return str(path)


@pytest.mark.parametrize(
    "command",
    [
        ["evaluate", "{map}", "--pose", "0", "0", "0.5", "0"],
        ["mde", "{map}", "--pose", "0", "0", "0.5", "0", "--trials", "1"],
    ],
)
@pytest.mark.parametrize(
    "option", [["--threads", "-1"], ["--threads", "100000"], ["--seed", "-1"], ["--seed", str(2**64)]]
)
def test_out_of_range_seed_and_threads_exit_2(boxes, command, option):
    done = CliRunner().invoke(app, [part.format(map=boxes) for part in command] + option)
    assert done.exit_code == 2, done.output
    lines = done.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"lf3pm: error: {option[0]} must be "), done.output
    assert "than or equal to" in lines[0], done.output


EVAL = ["evaluate", "{map}", "--pose", "0", "0", "0.5", "0"]
MDE = ["mde", "{map}", "--pose", "0", "0", "0.5", "0", "--trials", "1"]
SOLM = ["solm", "build", "{map}", "-o", "{tmp}/x.zarr"]


@pytest.mark.parametrize(
    "command, options, message",
    [
        (EVAL, ["--noise", "inf"], "--noise must be finite"),
        (EVAL, ["--scan-voxel", "-1"], "--scan-voxel must be greater than or equal to 0"),
        (EVAL, ["--scan-voxel", "nan"], "--scan-voxel must be finite"),
        (EVAL, ["--dof", "4"], "--dof must be 3 or 6, got 4"),
        (EVAL, ["--w1", "1"], "--w1 must be less than 1"),
        (EVAL, ["--association", "nearest"], "--association must be 'knn' or 'surfel'"),
        (EVAL, ["--knn", "0"], "--knn must be greater than or equal to 3"),
        (MDE, ["--noise", "nan"], "--noise must be finite"),
        (MDE, ["--sigma-t", "nan"], "--sigma-t must be finite"),
        (MDE, ["--sigma-t", "1e9"], "mde.sigma_t 1e+09 m is larger than the map"),
        (MDE, ["--trials", "0"], "--trials must be greater than or equal to 1"),
        (SOLM, ["--noise", "nan"], "--noise must be finite"),
        (SOLM, ["--height", "nan"], "--height must be finite"),
        (SOLM, ["--height", "-1"], "--height must be greater than 0"),
        (SOLM, ["--bounds", "0", "0", "inf", "1"], "--bounds must be finite"),
        (SOLM, ["--res", "1e-6"], "more than 10,000,000"),
        (SOLM, ["--res", "1e-3"], "96,540,399 poses"),
        (SOLM, ["--space", "r3", "--res", "1e-6"], "raise --max-cells"),
        (SOLM, ["--space", "se2", "--yaw-bins", "100000"], "--yaw-bins must be less than or equal to 3600"),
        (SOLM, ["--space", "se2", "--yaw-bins", "3600", "--res", "0.05"], "x 3600), more than 10,000,000"),
        (SOLM, ["--space", "x2"], "--space must be 'r2', 'se2', 'r3' or 'r3yaw'"),
        (SOLM, ["--robot-radius", "nan"], "--robot-radius must be finite"),
        (SOLM, ["--ray-stride", "0"], "--ray-stride must be greater than or equal to 1"),
    ],
)
def test_hostile_numbers_are_one_line_errors(boxes, tmp_path, command, options, message):
    done = CliRunner().invoke(app, [part.format(map=boxes, tmp=tmp_path) for part in command] + options)
    assert done.exit_code == 2, done.output
    lines = [line for line in done.output.splitlines() if line.startswith("lf3pm: error:")]
    assert len(lines) == 1 and message in lines[0], done.output
    assert not (tmp_path / "x.zarr").exists()


def test_a_robot_slower_than_a_millimetre_per_second_is_refused():
    from lf3pm.config import MIN_LIMIT
    from lf3pm.errors import Lf3pmError
    from lf3pm.trajectory.robots import Robot

    with pytest.raises(Lf3pmError, match="robot.vmax_lon must be greater than or equal to 0.001"):
        Robot(vmax_lon=1e-9)
    assert Robot(vmax_lon=MIN_LIMIT, vmax_lat=MIN_LIMIT).vmax_norm == MIN_LIMIT
