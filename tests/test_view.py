"""`lf3pm view`: the arrays the page draws, the checks before serving, the page's actions
through the library, and the page itself in headless Chromium."""

from __future__ import annotations

import json
import math
import socket
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from browser import needs_chromium

import lf3pm
from lf3pm.errors import Lf3pmError
from lf3pm.io import write_points
from lf3pm.scenes import build_scene
from lf3pm.solm import Solm, build_solm, make_grid
from lf3pm.view import check_port, free_port, layers, load_view_inputs, serve

BOUNDS = (-3.5, -3.5, 3.5, 3.5)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The boxes scene written as a map file, an SE(2) SOLM of it (Mid-70, 8 yaw bins)
    and a trajectory CSV across it."""
    d = tmp_path_factory.mktemp("view")
    points = build_scene("boxes").points
    write_points(d / "map.npy", points)
    world = lf3pm.load_map(d / "map.npy")
    grid = make_grid(world, "se2", 1.0, bounds=BOUNDS, yaw_bins=8, height=1.0)
    build_solm(world, "mid70", grid, d / "solm.zarr", tile=4)
    samples = np.c_[np.linspace(0, 6, 61), np.linspace(-3, 3, 61), np.zeros(61), np.zeros((61, 4))]
    np.savetxt(d / "plan.csv", samples, delimiter=",", header="t,x,y,yaw,vx,vy,omega", comments="")
    return d, world


def test_colormap_spans_the_range_and_greys_what_is_unknown():
    rgb = layers.colormap(np.array([1.0, 10.0, 100.0, np.nan]), 1.0, 100.0)
    from matplotlib import colormaps

    viridis = (colormaps["viridis"]([0.0, 0.5, 1.0])[:, :3] * 255).astype(np.uint8)
    np.testing.assert_array_equal(rgb[:3], viridis)  # log scale: 10 is half way
    np.testing.assert_array_equal(rgb[3], [128, 128, 128])


def test_a_large_map_is_subsampled_with_a_seed():
    points = np.random.default_rng(0).normal(size=(5000, 3))
    shown, colors = layers.map_cloud(points, max_points=1000)
    again, _ = layers.map_cloud(points, max_points=1000)
    assert len(shown) == len(colors) == 1000 and shown.dtype == np.float32
    np.testing.assert_array_equal(shown, again)
    assert len(layers.map_cloud(points, max_points=10_000)[0]) == 5000


@pytest.mark.slow
def test_the_solm_layer_is_the_channel_min_over_yaw_or_one_bin(site):
    d, _ = site
    solm = Solm.open(d / "solm.zarr")
    q = solm.channel("q_n").astype(np.float64)
    with np.errstate(all="ignore"):
        expected = np.where(np.isfinite(q), q, np.inf).min(axis=0)
    expected[~np.isfinite(expected)] = np.nan
    np.testing.assert_array_equal(layers.solm_values(solm, "q_n"), expected)
    np.testing.assert_array_equal(layers.solm_values(solm, "q_n", 3), q[3])
    layer = layers.solm_layer(solm, "q_n")
    assert len(layer["centres"]) == np.count_nonzero(np.isfinite(expected) & (expected > 0)) > 0
    assert layer["lo"] <= np.median(layer["values"]) <= layer["hi"]
    from lf3pm.calibration import LOCALIZATION_PACKAGED, packaged_calibration, predict

    fit = packaged_calibration(LOCALIZATION_PACKAGED)
    error = layers.solm_values(solm, "predicted_error")
    iy, ix = np.argwhere(np.isfinite(expected))[0]
    assert error[iy, ix] == pytest.approx(predict(fit, expected[iy, ix])[0])
    with pytest.raises(Lf3pmError, match="unknown channel"):
        layers.solm_values(solm, "sigma")


def test_replay_tracks_read_both_replay_formats_and_refuse_one_without_positions():
    truth = np.c_[np.arange(5.0), np.zeros(5), np.ones(5)]
    run = {"truth_xyz": truth.tolist(), "estimate_xyz": (truth + 0.1).tolist(), "errors": [0.0, 0.1, 0.2, 0.3, 0.4]}
    tracks = layers.replay_tracks({"runs": [run]})
    assert tracks["truth"].shape == tracks["estimate"].shape == tracks["colors"].shape == (4, 2, 3)
    assert tracks["hi"] == pytest.approx(0.4)
    study = {
        "truth_xyz_every_second": run["truth_xyz"],
        "estimate_xyz_every_second": run["estimate_xyz"],
        "errors_every_second": run["errors"],
    }
    np.testing.assert_array_equal(layers.replay_tracks(study)["estimate"], tracks["estimate"])
    assert tracks["rest"] == {}  # a LIO replay's rest comes along (the viewer warns when unsteady)
    rest = {"seconds": 2.0, "drift_m": 0.9, "speed_mps": 3.4, "steady": False}
    unsteady = layers.replay_tracks({**study, "rest": rest})
    assert unsteady["rest"] == rest
    assert "already moving at 3.40 m/s" in layers.replay_caption("r", unsteady)
    assert "moving" not in layers.replay_caption("r", layers.replay_tracks({**study, "rest": {**rest, "steady": True}}))
    assert layers.replay_caption("r", tracks).startswith("r: error 0.1-40.0 cm")
    with pytest.raises(Lf3pmError, match="no true and estimated positions"):
        layers.replay_tracks({"ape_rmse": 0.1})


@pytest.mark.slow
def test_what_lf3pm_replay_json_writes_is_shown(site, tmp_path):
    d, _ = site
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "lf3pm",
            "replay",
            str(d / "plan.csv"),
            "--map",
            str(d / "map.npy"),
            "--sensor",
            "vlp16",
            "--method",
            "localization",
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    (tmp_path / "replay.json").write_text(run.stdout)
    tracks = load_view_inputs(d / "map.npy", replay_paths=[tmp_path / "replay.json"]).replays["replay replay"]
    result = json.loads(run.stdout)["runs"][0]
    assert len(tracks["truth"]) == result["scans"] - 1
    assert tracks["hi"] == pytest.approx(max(result["ape"]["max"], 2e-3))


def test_the_weakest_direction_of_a_corridor_is_along_it():
    """Planes facing y and z only (a corridor along x): x is unobserved."""
    rng = np.random.default_rng(1)
    rows = []
    for _ in range(300):
        u = np.array([0.0, 1.0, 0.0]) if rng.random() < 0.5 else np.array([0.0, 0.0, 1.0])
        w = rng.uniform(-5, 5, 3)
        rows.append(np.r_[u, np.cross(w, u)])
    weak = layers.weak_directions({"A": np.array(rows)}, np.zeros(3))
    assert abs(weak["directions"][0][0]) > 0.99
    assert np.linalg.norm(np.diff(weak["arrows"][0], axis=0)) == pytest.approx(layers.ARROW_LENGTH)
    assert weak["eigenvalues"][0] < 1e-6 * weak["eigenvalues"][1]


@pytest.mark.slow
def test_inputs_are_checked_before_anything_is_served(site, tmp_path):
    d, _ = site
    with pytest.raises(Lf3pmError, match="no such map file"):
        load_view_inputs(tmp_path / "missing.npy")
    other = tmp_path / "other.npy"
    write_points(other, build_scene("boxes").points + [0.0, 0.0, 0.01])
    with pytest.raises(Lf3pmError, match="built on another map"):
        load_view_inputs(other, d / "solm.zarr")
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"ape_rmse": 1.0}))
    with pytest.raises(Lf3pmError, match="bad.json.*no true and estimated positions"):
        load_view_inputs(d / "map.npy", replay_paths=[bad])
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        with pytest.raises(Lf3pmError, match="in use"):
            check_port("127.0.0.1", taken.getsockname()[1])


@pytest.mark.slow
def test_the_cli_refuses_bad_input_in_one_line_with_status_2(site, tmp_path):
    d, _ = site
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        for args in ([str(tmp_path / "missing.npy")], [str(d / "map.npy"), "--port", str(taken.getsockname()[1])]):
            run = subprocess.run(
                [sys.executable, "-m", "lf3pm", "view", *args], capture_output=True, text=True, timeout=120
            )
            assert run.returncode == 2, run.stderr
            assert len(run.stderr.strip().splitlines()) == 1 and "Traceback" not in run.stderr


@pytest.fixture(scope="module")
def app(site):
    d, _ = site
    inputs = load_view_inputs(d / "map.npy", d / "solm.zarr", [d / "plan.csv"])
    viewer = serve(inputs, port=free_port())
    yield viewer
    viewer.stop()


def test_a_clicked_cell_is_evaluated_at_its_best_yaw(app):
    out = app.inspect(np.array([1.0, 0.5]))
    solm = app.inputs.solm
    yaws = solm.grid_spec.yaws()
    best = yaws[np.nanargmin(solm.query(np.full(len(yaws), 1.0), np.full(len(yaws), 0.5), yaw=yaws)[0])]
    assert out["pose"][3] == pytest.approx(best)
    expected = lf3pm.evaluate(app.inputs.world, out["pose"], "mid70")
    assert out["q_n"] == expected.q_n and out["hits"] == expected.hits
    assert "q_n" in app.status


def test_plans_between_clicked_poses_with_and_without_guidance(app):
    app._guarded(app.plan_between)
    assert app.status.startswith("error: set a start and a goal")
    app._start, app._goal = np.array([-3.0, 3.0]), np.array([3.0, 3.0])  # the row clear of boxes, y = 3
    out = app.plan_between()
    assert set(out) == {"default guidance", "none (shortest)"}
    for summary in out.values():
        assert summary["trajectory_length_m"] >= 6.0 - 0.1
        assert summary["predicted_error_m"] is None or summary["predicted_error_withheld"] is None
        assert summary["predicted_error_m"] is None or summary["predicted_error_m"] > 0


@pytest.mark.slow
@needs_chromium
def test_the_page_shows_the_scene_in_a_real_browser(app, tmp_path):
    """Headless Chromium (software WebGL) loads the page; its screenshot is not blank
    and shows the SOLM's colours (viridis)."""
    from browser import screenshot
    from matplotlib import colormaps

    palette = (colormaps["viridis"](np.linspace(0, 1, 32))[:, :3] * 255).astype(int)

    def solm_share(image):
        pixels = image[::4, : image.shape[1] * 2 // 3 : 4].reshape(-1, 3).astype(int)  # left of the panel
        near = np.min(np.abs(pixels[:, None, :] - palette[None]).sum(axis=2), axis=1) < 24
        saturated = pixels.max(axis=1) - pixels.min(axis=1) > 40  # not grey or white
        return float(np.mean(near & saturated))

    app.map_ceiling.value = 2.0  # under the boxes room's ceiling, as a user would cut it
    image = screenshot(
        f"http://127.0.0.1:{app.server.get_port()}/",
        tmp_path / "page.png",
        seconds=60,
        ready=lambda img: solm_share(img) > 0.01,
    )
    assert image.std() > 10, "blank page"
    assert solm_share(image) > 0.01, "the SOLM's colours are not on the page"


def test_turning_the_ring_at_the_start_sets_its_yaw(app):
    app.mode.value = "set the start"
    app._clicked(SimpleNamespace(ray_origin=(1.0, 1.0, 10.0), ray_direction=(0.0, 0.0, -1.0), client=None))
    assert app._start == pytest.approx([1.0, 1.0], abs=1e-6)
    ring = app._rings["start"]
    ring.wxyz = (math.cos(math.radians(91) / 2), 0.0, 0.0, math.sin(math.radians(91) / 2))
    app._ring_turned("start", ring)
    assert app.start_yaw.value == 90.0  # the slider's 5° step
    app.start_yaw.value = -45.0
    app._draw_ends()
    w, _, _, z = ring.wxyz
    assert math.degrees(2 * math.atan2(z, w)) == pytest.approx(-45.0)
    app.mode.value = "inspect a cell"


def test_an_r3_solm_is_shown_and_inspected_level_by_level(site, tmp_path):
    """An R3 SOLM stores no ground: its layer sits at the level's height, and a clicked
    cell is evaluated there."""
    d, world = site
    grid = make_grid(world, "r3", 1.0, bounds=BOUNDS, z_levels=[0.5, 1.5])
    build_solm(world, "vlp16", grid, tmp_path / "r3.zarr", ray_stride=8)
    solm = Solm.open(tmp_path / "r3.zarr")
    layer = layers.solm_layer(solm, "q_n", 1)
    assert len(layer["centres"]) > 0 and np.all(layer["centres"][:, 2] == np.float32(1.5))
    viewer = serve(load_view_inputs(d / "map.npy", tmp_path / "r3.zarr"), port=free_port())
    try:
        viewer.height.value = 1.5
        assert viewer.inspect(np.array([0.0, 0.0]))["pose"][2] == 1.5
    finally:
        viewer.stop()


@pytest.mark.parametrize("lo, hi", [(0.029, 0.12), (0.0021, 0.93), (12.5, 12345.6), (1.0, 1.0001)])
def test_the_colour_bar_labels_fit_inside_it(lo, hi):
    """Its end values are aligned inwards: no label is cut at the image's edges (LogNorm's
    own minor labels were: "3x10^-2" at 0.029 lost its left half)."""
    image = layers.colorbar_image(lo, hi, layers.CHANNELS["q_n"])
    assert image.shape == (*layers.COLORBAR_PIXELS[::-1], 3)
    for column in (image[:, 0], image[:, -1]):
        assert column.min(axis=1).min() > 160, "a label is cut at the edge"


def test_the_first_view_looks_at_the_plans_and_replays(app, site):
    """Not at the middle of the map: at what was given to look at, from the south and above."""
    samples = app.inputs.plans["plan plan"]
    (x0, y0), (x1, y1) = app.focus_bounds()
    assert (x0, y0, x1, y1) == (samples["x"].min(), samples["y"].min(), samples["x"].max(), samples["y"].max())
    look = np.asarray(app.server.initial_camera.look_at)
    eye = np.asarray(app.server.initial_camera.position)
    span = max(x1 - x0, y1 - y0, 10.0)
    # The plan's middle, a little right of it so that the panel does not cover it (the map's
    # middle is 2 m west of it).
    assert look[:2] == pytest.approx([0.5 * (x0 + x1) + 0.1 * span, 0.5 * (y0 + y1)])
    assert eye[1] < look[1] and eye[2] > look[2] + 1.0
