"""`lf3pm replay` from the command line: a table, one JSON object, a PNG, and one
line with exit status 2 for every kind of bad input."""

import json

import numpy as np
import pytest
from scipy.interpolate import CubicSpline
from typer.testing import CliRunner

import lf3pm
from lf3pm.cli import app
from lf3pm.scenes import build_scene
from lf3pm.trajectory.trajectory import Trajectory

runner = CliRunner()


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The boxes scene as a map file and a 2 s trajectory across it (CSV)."""
    folder = tmp_path_factory.mktemp("replay")
    np.save(folder / "boxes.npy", build_scene("boxes").points)
    spline = CubicSpline([0.0, 1.0, 2.0], [[-2.0, 0.0, 0.0], [-1.2, 0.3, 0.3], [-0.4, 0.4, 0.0]], bc_type="clamped")
    Trajectory(coefficients=np.transpose(spline.c[::-1], (1, 0, 2)).copy(), durations=np.diff(spline.x)).to_csv(
        folder / "traj.csv"
    )
    return folder


def replay(*args):
    return runner.invoke(app, ["replay", *map(str, args)])


@pytest.mark.slow
def test_json_with_two_seeds_and_a_png(files, tmp_path):
    png = tmp_path / "replay.png"
    done = replay(files / "traj.csv", "--map", files / "boxes.npy", "--seeds", 2, "--seed", 3, "--json", "--png", png)
    assert done.exit_code == 0, done.output
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["method"] == "localization" and out["seeds"] == [3, 4] and len(out["runs"]) == 2
    run = out["runs"][0]
    assert run["scans"] == 21 and run["ape"]["rmse"] < 0.02 and run["params"]["rate"] == 10.0
    assert out["median"]["ape_rmse"] == pytest.approx(np.median([r["ape"]["rmse"] for r in out["runs"]]))
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # A script gets what the CLI gets: lf3pm.replay_seeds on the same input, the same figures.
    series = lf3pm.replay_seeds(str(files / "boxes.npy"), str(files / "traj.csv"), seeds=2, seed=3)
    assert [r.seed for r in series.results] == [3, 4]
    timing = "scans_per_second"  # wall time: differs from run to run
    assert {k: v for k, v in series.median.items() if k != timing} == pytest.approx(
        {k: v for k, v in out["median"].items() if k != timing}
    )
    assert [r.ape["rmse"] for r in series.results] == pytest.approx([r["ape"]["rmse"] for r in out["runs"]])


def test_table_for_odometry(files):
    done = replay(
        files / "traj.csv", "--map", files / "boxes.npy", "--method", "odometry", "--sensor", "mid70", "--rate", 5
    )
    assert done.exit_code == 0, done.output
    assert "replay: odometry, mid70, 11 scans at 5 Hz" in done.stdout and "APE" in done.stdout


@pytest.mark.slow
def test_the_methods_settings_come_from_the_config_file(files, tmp_path):
    """--config FILE.yaml sets the method's section (here localization's), which the run
    records and uses: the same figures as the API given the same settings."""
    config = tmp_path / "loc.yaml"
    config.write_text("localization: {scan_voxel: 0.3, yaw_noise: 0.02, max_iterations: 20}\n")
    done = replay(files / "traj.csv", "--map", files / "boxes.npy", "--config", config, "--json")
    assert done.exit_code == 0, done.output
    run = json.loads(done.stdout.strip().splitlines()[-1])["runs"][0]
    recorded = run["params"]["localization"]
    assert (recorded["scan_voxel"], recorded["odometry"]["yaw_noise"], recorded["max_iterations"]) == (0.3, 0.02, 20)
    same = lf3pm.replay(
        str(files / "boxes.npy"), str(files / "traj.csv"), scan_voxel=0.3, yaw_noise=0.02, max_iterations=20
    )
    assert run["ape"]["rmse"] == same.ape["rmse"]


BAD_CSV = {
    "malformed": "t,x,y,yaw,vx,vy,omega\n0,-2,0,0,0,0,0\n1,-1,zero,0,0,0,0\n",
    "missing": "t,x,y,yaw\n0,-2,0,0\n1,-1,0,0\n",
    "nonfinite": "t,x,y,yaw,vx,vy,omega\n0,-2,0,0,0,0,0\n1,-1,nan,0,0,0,0\n",
    "decreasing": "t,x,y,yaw,vx,vy,omega\n0,-2,0,0,0,0,0\n1,-1,0,0,0,0,0\n0.5,-0.5,0,0,0,0,0\n",
    "outside": "t,x,y,yaw,vx,vy,omega\n0,-2,0,0,0,0,0\n1,50,0,0,0,0,0\n",
}


@pytest.mark.parametrize(
    "kind, match",
    [
        ("malformed", "not a number"),
        ("missing", "lacks the column"),
        ("nonfinite", "y is not finite"),
        ("decreasing", "increase strictly"),
        ("outside", "leaves the map"),
    ],
)
def test_bad_trajectories(files, tmp_path, kind, match):
    csv = tmp_path / f"{kind}.csv"
    csv.write_text(BAD_CSV[kind])
    done = replay(csv, "--map", files / "boxes.npy")
    assert done.exit_code == 2 and match in done.stderr and len(done.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize(
    "args, match",
    [
        (["--method", "slam"], "--method must be 'localization', 'lio' or 'odometry'"),
        (["--sensor", "hdl-64"], "unknown sensor"),
        (["--rate", "0"], "--rate"),
        (["--rate", "nan"], "--rate"),
        (["--seeds", "0"], "--seeds"),
        (["--height", "-1"], "--height"),
        (["--method", "lio", "--odometry", "fastlio"], "--odometry must be 'auto', 'genz', 'dlio' or 'liosam'"),
        (["--method", "lio", "--odometry", "liosam", "--sensor", "mid70"], "liosam needs a spinning sensor"),
        (["--odometry", "dlio"], "--odometry applies to --method lio, not localization"),
    ],
)
def test_bad_options(files, args, match):
    done = replay(files / "traj.csv", "--map", files / "boxes.npy", *args)
    assert done.exit_code == 2 and match in done.stderr and len(done.stderr.strip().splitlines()) == 1


def test_outputs_replace_only_regular_files(files, tmp_path):
    done = replay(files / "traj.csv", "--map", files / "boxes.npy", "--png", tmp_path)
    assert done.exit_code == 2 and "is a directory" in done.stderr
    existing = tmp_path / "old.bag"
    existing.mkdir()
    done = replay(files / "traj.csv", "--map", files / "boxes.npy", "--bag", existing)
    assert done.exit_code == 2 and "exists" in done.stderr


@pytest.mark.slow
@pytest.mark.parametrize("odometry, name", [("dlio", "DLIO"), ("liosam", "LIO-SAM")])
def test_lio_with_an_evalio_odometry_in_json(files, odometry, name):
    """`--method lio --odometry dlio|liosam`: the 2 s boxes trajectory after the LIO's
    rest, noise-free, through DLIO or LIO-SAM; the JSON names the odometry and its
    package's version."""
    pytest.importorskip("evalio", reason="evalio (DLIO, LIO-SAM) is not installed: pip install 'lf3pm[lio]'")
    done = replay(
        files / "traj.csv",
        "--map",
        files / "boxes.npy",
        "--method",
        "lio",
        "--odometry",
        odometry,
        "--noise",
        0,
        "--json",
    )
    assert done.exit_code == 0, done.output
    out = json.loads(done.stdout.strip().splitlines()[-1])
    run = out["runs"][0]
    assert out["odometry"] == odometry and run["versions"]["evalio"] == "0.6.1"
    assert run["ape"]["rmse"] < 0.05 and run["report"]["odometry"] == name


def test_table_cells_stay_readable_for_failed_runs():
    from lf3pm.cli.replay_table import format_figure

    assert format_figure("ape_rmse", 27.4634) == "27463"  # mm; 2.75e+04 would be cut at 80 columns
    assert format_figure("ape_rmse", 0.0123) == "12.3"
    assert format_figure("scans_per_second", 13.04) == "13"
    assert format_figure("skipped_scans", 3) == "3"
    assert format_figure("ape_aligned_rmse", float("nan")) == "-" and format_figure("ape_rmse", None) == "-"


def test_a_seed_that_entered_moving_says_so_in_the_figure_legend():
    from types import SimpleNamespace

    from lf3pm.replays.replay_figures import seed_label

    run = SimpleNamespace(seed=1, ape={"rmse": 8.172}, rest={"steady": False, "speed_mps": 3.39})
    assert seed_label(run) == "seed 1: APE rmse 8.17 m (LIO entered moving at 3.39 m/s)"
    assert seed_label(SimpleNamespace(seed=0, ape={"rmse": 0.026}, rest={})) == "seed 0: APE rmse 0.026 m"
