"""lf3pm.evaluate and `lf3pm evaluate`: fields, observations, errors."""

import json
import subprocess
import sys

import numpy as np
import pytest
from analytic_scenes import box_room, grid_plane
from reference_metric import reference_metric
from shared_data import shared_file

import lf3pm
from lf3pm import _core
from lf3pm.errors import Lf3pmError, MapError, PoseError, SensorError
from lf3pm.io import write_points


def metric_of_rows(A, b):
    """The metric of explicit rows: NumPy Gram, then the core's Gram path."""
    M = np.hstack([A, b[:, None]])
    return _core.metric_from_gram(M.T @ M, len(b)).as_dict()


REQUIRED = ("sigma1", "xi", "q_min", "q_n", "q_max", "m")


@pytest.fixture(scope="module")
def room_file(tmp_path_factory):
    """A room with a few boxes on the floor (not degenerate), as a PCD file."""
    rng = np.random.default_rng(0)
    parts = [box_room((5.0, 4.0, 1.5), 0.05)]
    for cx, cy in rng.uniform(-3.5, 3.5, size=(4, 2)):
        parts.append(box_room((0.4, 0.3, 0.5), 0.05) + (cx, cy, -1.0))
    path = tmp_path_factory.mktemp("maps") / "room.pcd"
    write_points(path, np.vstack(parts))
    return path


def run_cli(*args):
    return subprocess.run(
        [sys.executable, "-m", "lf3pm.cli", *map(str, args)], capture_output=True, text=True, timeout=300
    )


def test_python_api_fields_and_observations_match_the_reference(room_file):
    world = lf3pm.load_map(room_file)
    res = lf3pm.evaluate(world, (0.2, -0.1, 0.0, 0.3), "vlp16", seed=1, observations=True)
    assert res.m > 1000 and not res.degenerate
    A, b = res.observations["A"], res.observations["b"]
    assert A.shape == (res.m, 6) and b.shape == (res.m,) and A.dtype == np.float64
    # The fused pipeline (rows never materialised) equals the metric of its rows...
    rows = metric_of_rows(A, b)
    for key in ("sigma1", "xi", "q_min", "q_n", "q_max"):
        assert getattr(res, key) == pytest.approx(rows[key], rel=1e-9)
    # ...and on a subset small enough for the m x m definition, the definition.
    sub = np.random.default_rng(0).choice(res.m, size=400, replace=False)
    ref = reference_metric(A[sub], b[sub])
    fast = metric_of_rows(A[sub], b[sub])
    for key in ("sigma1", "xi", "q_min", "q_n", "q_max"):
        assert fast[key] == pytest.approx(ref[key], rel=1e-9)
    assert res.q_min <= res.q_n <= res.q_max


def test_same_seed_same_result_other_seed_differs(room_file):
    world = lf3pm.load_map(room_file)
    a = lf3pm.evaluate(world, (0, 0, 0, 0), seed=5)
    b = lf3pm.evaluate(world, (0, 0, 0, 0), seed=5, threads=1)
    c = lf3pm.evaluate(world, (0, 0, 0, 0), seed=6)
    assert a.to_dict() == b.to_dict()
    assert a.q_n != c.q_n


def test_planar_dof_uses_three_columns(room_file):
    res = lf3pm.evaluate(room_file, (0, 0, 0, 0), dof=3, noise=0.0, observations=True)
    assert res.n == 3 and res.observations["A"].shape == (res.m, 3)


def test_a_corridor_without_ends_is_degenerate_not_a_crash():
    # A wall and a floor longer than the sensor's range: translation along them is
    # unobservable, so A is rank-deficient. They do not touch: k-NN planes fitted
    # across a crease tilt arbitrarily (as FAST-LIO's do) and break the symmetry.
    wall = grid_plane((3.0, -200.0, -0.5), (0, 1, 0), (0, 0, 1), 400.0, 3.5, 0.1)
    floor = grid_plane((-5.0, -200.0, -1.0), (1, 0, 0), (0, 1, 0), 7.5, 400.0, 0.1)
    res = lf3pm.evaluate(np.ascontiguousarray(np.vstack([wall, floor])), (0.0, 0.0, 0.0, 0.0), "vlp16", noise=0.0)
    assert res.m > 1000
    assert res.degenerate and res.q_n == np.inf and res.to_dict()["q_n"] is None


@pytest.mark.slow
def test_cli_json_and_saved_observations(room_file, tmp_path):
    obs = tmp_path / "obs.npz"
    out = run_cli(
        "evaluate",
        room_file,
        "--pose",
        "-0.5",
        "0.5",
        "0.2",
        "-1.0",
        "--seed",
        "3",
        "--json",
        "--save-observations",
        obs,
    )
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    for key in REQUIRED:
        assert key in data
    saved = np.load(obs)
    assert saved["A"].shape == (data["m"], 6) and saved["b"].shape == (data["m"],)
    assert saved["points"].shape[1] == 3 and len(saved["points"]) == data["hits"]
    assert data["q_n"] == pytest.approx(metric_of_rows(saved["A"], saved["b"])["q_n"], rel=1e-9)
    api = lf3pm.evaluate(room_file, (-0.5, 0.5, 0.2, -1.0), seed=3)
    assert api.q_n == data["q_n"]


@pytest.mark.slow
def test_cli_table(room_file):
    out = run_cli("evaluate", room_file, "--pose", "0", "0", "0", "0")
    assert out.returncode == 0 and "q_n" in out.stdout and "q_min" in out.stdout


@pytest.mark.slow
def test_cli_sensors_lists_presets():
    out = run_cli("sensors")
    assert out.returncode == 0
    for name in ("vlp16", "hdl32", "os1-64", "mid70", "mid360", "avia"):
        assert name in out.stdout


@pytest.mark.slow
@pytest.mark.parametrize(
    "args,needle",
    [
        (("evaluate", "missing.pcd", "--pose", "0", "0", "0", "0"), "no such file"),
        (("evaluate", "{room}", "--pose", "50", "0", "0", "0"), "outside"),
        (("evaluate", "{room}", "--pose", "0", "0", "0", "0", "--sensor", "nosuch"), "unknown sensor"),
        (("evaluate", "{room}", "--pose", "0", "0", "0", "0", "--dof", "4"), "dof"),
        (("evaluate", "{room}", "--pose", "0", "0", "0", "0", "--noise", "-1"), "noise"),
        (
            ("evaluate", "{room}", "--pose", "0", "0", "0", "0", "--save-observations", "/nonexistent/o.npz"),
            "cannot write",
        ),
        (("evaluate", "{bad}", "--pose", "0", "0", "0", "0"), "unknown suffix"),
    ],
)
def test_cli_bad_input_is_one_line_and_nonzero(room_file, tmp_path, args, needle):
    bad = tmp_path / "map.xyz"
    bad.write_text("1 2 3\n")
    args = [a.format(room=room_file, bad=bad) for a in args]
    out = run_cli(*args)
    assert out.returncode != 0
    assert "Traceback" not in out.stderr
    lines = [line for line in out.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and needle in lines[0].lower(), out.stderr


def test_api_errors_are_lf3pm_errors(room_file):
    with pytest.raises(PoseError):
        lf3pm.evaluate(room_file, (0, 0, np.nan, 0))
    with pytest.raises(SensorError):
        lf3pm.evaluate(room_file, (0, 0, 0, 0), "nosuch")
    with pytest.raises(MapError):
        lf3pm.load_map(np.zeros((3, 3)))
    with pytest.raises(Lf3pmError):
        lf3pm.evaluate(room_file, (0, 0, 0, 0), association="icp")


def test_real_map_indoor_scan():
    path = shared_file("indoor_pcl_room_scan1.pcd")
    with pytest.warns(UserWarning, match="duplicate"):
        world = lf3pm.load_map(path)
    res = lf3pm.evaluate(world, (2.0, 1.0, 0.0, 0.0), "vlp16", seed=0)
    assert res.m > 10000 and np.isfinite(res.q_n)
    with pytest.raises(PoseError, match="obstacle"):  # the scanner's own returns at 0.1 m
        lf3pm.evaluate(world, (0, 0, 0, 0), "vlp16")
