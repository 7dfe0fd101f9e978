"""`lf3pm plan` from the command line: a trajectory CSV and PNG on a built SOLM,
and one-line errors for bad requests."""

import subprocess
import sys

import numpy as np
import pytest

import lf3pm
from lf3pm.scenes import build_scene
from lf3pm.solm import build_solm, make_grid


@pytest.fixture(scope="module")
def boxes_solm(tmp_path_factory):
    scene = build_scene("boxes")
    world = lf3pm.load_map(scene.points)
    path = tmp_path_factory.mktemp("plan") / "boxes.zarr"
    build_solm(world, lf3pm.get_sensor("vlp16"), make_grid(world, "r2", 0.5, height=1.0), path, ray_stride=4)
    return path


def run_plan(*args):
    return subprocess.run([sys.executable, "-m", "lf3pm.cli", "plan", *map(str, args)], capture_output=True, text=True)


@pytest.mark.slow
def test_plan_writes_a_100_hz_trajectory_from_start_to_goal_and_a_png(boxes_solm, tmp_path):
    csv, png = tmp_path / "traj.csv", tmp_path / "plan.png"
    done = run_plan(
        "--solm",
        boxes_solm,
        "--start",
        -2.5,
        -2.7,
        0,
        "--goal",
        6.2,
        2.2,
        1.57,
        "--r-safe",
        0.05,
        "--weight",
        3,
        "-o",
        csv,
        "--png",
        png,
    )
    assert done.returncode == 0, done.stderr
    header = csv.read_text().splitlines()[0]
    assert header == "t,x,y,yaw,vx,vy,omega"
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert np.allclose(np.diff(data[:-1, 0]), 0.01)
    assert np.allclose(data[0, 1:4], (-2.5, -2.7, 0.0), atol=1e-6)
    assert np.allclose(data[-1, 1:3], (6.2, 2.2), atol=1e-6)
    assert np.allclose(data[[0, -1], 4:], 0.0, atol=1e-9)  # at rest at both ends
    assert png.stat().st_size > 10_000


@pytest.mark.slow
def test_speed_norm_limit_from_the_command_line(boxes_solm, tmp_path):
    csv = tmp_path / "traj.csv"
    done = run_plan(
        "--solm",
        boxes_solm,
        "--start",
        -2.5,
        -2.7,
        0,
        "--goal",
        6.2,
        2.2,
        1.57,
        "--r-safe",
        0.05,
        "--vmax-norm",
        0.7,
        "-o",
        csv,
    )
    assert done.returncode == 0, done.stderr
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert np.max(np.hypot(data[:, 4], data[:, 5])) <= 1.02 * 0.7


@pytest.mark.slow
def test_the_composite_channel_plans_from_the_command_line(boxes_solm, tmp_path):
    csv = tmp_path / "traj.csv"
    done = run_plan(
        "--solm",
        boxes_solm,
        "--start",
        -2.5,
        -2.7,
        0,
        "--goal",
        6.2,
        2.2,
        1.57,
        "--r-safe",
        0.05,
        "--metric",
        "q_n_q_min",
        "-o",
        csv,
    )
    assert done.returncode == 0, done.stderr
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert np.allclose(data[-1, 1:3], (6.2, 2.2), atol=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize(
    "args, needle",
    [
        (("--start", 50, 50, 0, "--goal", 6.2, 2.2, 0), "outside"),
        (("--start", -4.0, -4.0, 0, "--goal", 6.2, 2.2, 0), "obstacle"),
        (("--start", -2.5, -2.7, 0, "--goal", 6.2, 2.2, 0, "--robot", "tank"), "--robot must be"),
        (("--start", -2.5, -2.7, 0, "--goal", 6.2, 2.2, 0, "--metric", "q_best"), "metric"),
        (("--start", -2.5, -2.7, 0, "--goal", 6.2, 2.2, 0, "--robot", "diff", "--vmax-norm", 1), "omni robots only"),
    ],
)
def test_bad_requests_get_one_line_and_exit_2(boxes_solm, tmp_path, args, needle):
    csv = tmp_path / "traj.csv"
    done = run_plan("--solm", boxes_solm, *args, "-o", csv)
    assert done.returncode == 2
    assert needle in done.stderr and "Traceback" not in done.stderr
    assert not csv.exists()


@pytest.mark.slow
def test_a_missing_solm_is_refused(tmp_path):
    done = run_plan("--solm", tmp_path / "none.zarr", "--start", 0, 0, 0, "--goal", 1, 1, 0, "-o", tmp_path / "t.csv")
    assert done.returncode == 2 and "no such SOLM" in done.stderr


@pytest.mark.slow
def test_plan_predicts_its_localization_error_with_the_fit_given(boxes_solm, tmp_path):
    """The packaged fit and a file whose offset is ln 3 higher: the predicted error along
    the same plan triples (it is the SOLM's time-mean q_n through the fit); a missing file is
    one line, exit 2."""
    import json

    from lf3pm.calibration import LOCALIZATION_PACKAGED, packaged_calibration

    base = packaged_calibration(LOCALIZATION_PACKAGED)
    fit = tmp_path / "fit.json"
    fit.write_text(json.dumps({**base, "a": base["a"] + np.log(3.0)}))
    args = ["--solm", boxes_solm, "--start", -2.5, -2.7, 0, "--goal", 6.2, 2.2, 1.57, "--r-safe", 0.05, "--json"]
    packaged = run_plan(*args, "-o", tmp_path / "a.csv")
    mine = run_plan(*args, "-o", tmp_path / "b.csv", "--calibration", fit)
    assert packaged.returncode == 0 and mine.returncode == 0, packaged.stderr + mine.stderr
    error = json.loads(packaged.stdout)["predicted_localization_error_m"]
    assert error > 0 and json.loads(mine.stdout)["predicted_localization_error_m"] == pytest.approx(3 * error)
    missing = run_plan(*args, "-o", tmp_path / "c.csv", "--calibration", tmp_path / "none.json")
    assert missing.returncode == 2 and "none.json: No such file" in missing.stderr
    assert len(missing.stderr.strip().splitlines()) == 1
