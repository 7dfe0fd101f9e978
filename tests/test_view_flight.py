"""`lf3pm view` in flight (issue 43, item 8): an r3yaw SOLM as a slice at a chosen height
(the nearest level, its minimum over yaw or one bin), flights as tubes with the body's
axes along them, replays of flights as 3-D tracks, bad input in one line, and the page in
headless Chromium."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from browser import needs_chromium

import lf3pm
from lf3pm.errors import Lf3pmError
from lf3pm.flight import MOUNTS, Quadrotor
from lf3pm.io import write_points
from lf3pm.planner.flight_plan import FlightTrajectory
from lf3pm.pose import pose_matrix
from lf3pm.scenes import build_scene
from lf3pm.solm import Solm, build_solm, make_grid
from lf3pm.view import free_port, layers, load_view_inputs, read_flight_csv, serve
from lf3pm.view.app import plane_point

BOUNDS = (-2.0, -2.0, 2.0, 2.0)
LEVELS = (1.0, 2.0)
BINS = 4
#: The test flight: rest to rest in a straight line, T seconds, turning its yaw.
START, GOAL, T, TURN = np.array([-1.5, -1.5, 1.0]), np.array([1.5, 1.5, 2.0]), 3.0, 0.5


def rest_to_rest() -> FlightTrajectory:
    """One quintic piece from START to GOAL in T s, at rest at both ends (10 s^3 - 15 s^4
    + 6 s^5 of the way at s = t / T), the yaw turning by TURN the same way: it accelerates
    along the line in its first half and brakes in its second."""
    c = np.zeros((1, 6, 4))
    c[0, 0, :3] = START
    delta = np.r_[GOAL - START, TURN]
    c[0, 3], c[0, 4], c[0, 5] = 10 * delta / T**3, -15 * delta / T**4, 6 * delta / T**5
    return FlightTrajectory(c, np.array([T]))


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The boxes scene as a map file, a noise-free r3yaw SOLM of it (VLP-16 on down20, two
    levels, 4 yaw bins, every 8th ray), an r2 SOLM, and the test flight's CSV as `lf3pm
    plan --robot quadrotor` writes it."""
    d = tmp_path_factory.mktemp("view_flight")
    write_points(d / "map.npy", build_scene("boxes").points)
    world = lf3pm.load_map(d / "map.npy")
    grid = make_grid(world, "r3yaw", 1.0, bounds=BOUNDS, yaw_bins=BINS, z_levels=LEVELS)
    build_solm(world, "vlp16", grid, d / "r3yaw.zarr", noise=0.0, mount="down20", tile=2, ray_stride=8)
    build_solm(world, "vlp16", make_grid(world, "r2", 2.0, bounds=BOUNDS), d / "r2.zarr", noise=0.0, ray_stride=8)
    (d / "flight.csv").write_bytes(rest_to_rest().csv_bytes(Quadrotor()))
    return d, world


@pytest.fixture(scope="module")
def app(site):
    d, _ = site
    inputs = load_view_inputs(d / "map.npy", d / "r3yaw.zarr", flights=[d / "flight.csv"])
    viewer = serve(inputs, port=free_port(), z=2.2)
    yield viewer
    viewer.stop()


def test_the_slice_is_the_nearest_level_at_its_best_yaw_or_one_bin(site):
    d, _ = site
    solm = Solm.open(d / "r3yaw.zarr")
    g = solm.grid_spec
    assert [layers.nearest_level(g, z) for z in (0.5, 1.0, 1.49, 1.51, 2.0, 2.5)] == [0, 0, 0, 1, 1, 1]
    low, _ = solm.over_yaw("q_n")
    assert np.isfinite(low).sum() > 10
    for level in (0, 1):
        np.testing.assert_array_equal(layers.solm_values(solm, "q_n", level), low[level])
        q = solm.channel("q_n")[level * BINS + 2]
        np.testing.assert_array_equal(layers.solm_values(solm, "q_n", level, yaw_bin=2), q)
    layer = layers.solm_layer(solm, "q_n", 1)
    shown = np.isfinite(low[1]) & (low[1] > 0)
    assert len(layer["centres"]) == shown.sum() and np.all(layer["centres"][:, 2] == np.float32(2.0))
    np.testing.assert_array_equal(np.sort(layer["values"]), np.sort(low[1][shown]))
    from lf3pm.calibration import LOCALIZATION_PACKAGED, packaged_calibration

    fit = packaged_calibration(LOCALIZATION_PACKAGED)
    # (Every 8th ray puts q_n outside the fit's range here: the prediction's own test is
    # test_view.py's; this one checks that the minimum over yaw is what it is given.)
    np.testing.assert_array_equal(
        layers.solm_values(solm, "predicted_error", 1), layers.predicted_error(low[1].astype(np.float64), fit)
    )
    # Each cell drawn as k x k small squares over its own square, at the level's height.
    points, colors, size = layers.slice_points(layer)
    k = layers.SLICE_SUBDIVISION
    assert points.shape == (k * k * len(layer["centres"]), 3) and len(colors) == len(points) and size == 1.0 / k
    cells = points.reshape(-1, k * k, 3)
    assert np.all(np.abs(cells - layer["centres"][:, None]).max(axis=1)[:, :2] == pytest.approx(0.5 - 0.5 / k))
    assert np.all(points[:, 2] == np.float32(2.0))


@pytest.mark.parametrize("z", [0.49, 2.51, float("nan"), "2"])
def test_a_height_outside_the_levels_is_refused(site, z):
    d, _ = site
    with pytest.raises(Lf3pmError, match="outside the SOLM's 2 level|finite number"):
        layers.nearest_level(Solm.open(d / "r3yaw.zarr").grid_spec, z)


def test_the_page_shows_the_level_nearest_the_height_given_and_the_yaw_chosen(app):
    """serve(z=2.2) opens on level 2 (z = 2 m), its minimum over yaw; the slider moves to
    the other level and the yaw slider picks one bin, as the r3yaw layers give them."""
    solm = app.inputs.solm
    assert app.height.value == 2.0 and app.level_text.content.startswith("Level 2 of 2: z = 2.00 m, the minimum")

    def shown():
        cells = app.solm_node.points.reshape(-1, layers.SLICE_SUBDIVISION**2, 3)[:, 0]
        return np.unique(cells[:, 2]), len(cells)

    low, _ = solm.over_yaw("q_n")
    assert shown() == ([2.0], np.count_nonzero(np.isfinite(low[1]) & (low[1] > 0)))
    app.height.value = 1.0
    app._solm_changed()
    assert shown() == ([1.0], np.count_nonzero(np.isfinite(low[0]) & (low[0] > 0)))
    app.min_yaw.value = False
    app.layer.value = 90.0
    app._solm_changed()
    assert "yaw bin 1 (90°)" in app.level_text.content
    expected = layers.solm_layer(solm, "q_n", 0, yaw_bin=1)
    np.testing.assert_array_equal(app.solm_node.colors[:: layers.SLICE_SUBDIVISION**2], expected["colors"])
    app.min_yaw.value = True
    app.height.value = 2.0
    app._solm_changed()


def test_a_clicked_cell_is_evaluated_on_the_mount_at_the_level_and_its_best_yaw(app):
    """The level shown (2 m), the yaw bin of the least q_n there, the LiDAR on the SOLM's
    mount: lf3pm.evaluate at that sensor pose. A click meets the slice, not the ground."""
    solm = app.inputs.solm
    assert plane_point(np.array([0.5, -0.5, 12.0]), np.array([0.0, 0.5, -1.0]), 2.0) == pytest.approx([0.5, 4.5])
    assert plane_point(np.array([0.5, -0.5, 12.0]), np.array([0.0, 0.5, 1.0]), 2.0) is None
    out = app.inspect(np.array([0.5, -0.5]))
    yaws = solm.grid_spec.yaws()
    values = solm.query(np.full(BINS, 0.5), np.full(BINS, -0.5), yaws, z=np.full(BINS, 2.0))[0]
    assert out["pose"] == pytest.approx((0.5, -0.5, 2.0, yaws[np.nanargmin(values)]))
    expected = lf3pm.evaluate(app.inputs.world, pose_matrix(out["pose"]) @ MOUNTS["down20"].matrix(), "vlp16")
    assert out["q_n"] == expected.q_n and out["hits"] == expected.hits
    assert "on its mount down20" in app.status
    # An oblique click on the slice at 2 m inspects the cell it meets there.
    app._clicked(SimpleNamespace(ray_origin=(0.5, -4.5, 10.0), ray_direction=(0.0, 0.5, -1.0), client=None))
    assert app.status.startswith("**Cell** (0.50, -0.50)") and "at z = 2.00 m" in app.status


def test_a_flight_csv_is_read_and_drawn_as_a_tube_with_the_body_axes(site, app):
    d, _ = site
    table = np.genfromtxt(d / "flight.csv", delimiter=",", names=True)
    flight = read_flight_csv(d / "flight.csv")
    for column in ("t", "x", "y", "z", "yaw"):
        np.testing.assert_array_equal(flight[column], table[column])
    np.testing.assert_allclose(flight["wxyz"], np.c_[table["qw"], table["qx"], table["qy"], table["qz"]], atol=1e-8)
    tube, axes = app.flight_nodes["flight flight"]
    length = float(np.linalg.norm(GOAL - START))
    rings = int(np.ceil(length / layers.TUBE_STEP_M)) + 1
    assert tube.vertices.shape == (rings * layers.TUBE_SIDES, 3)
    assert tube.faces.shape == (2 * (rings - 1) * layers.TUBE_SIDES, 3)
    # Every vertex lies a tube's radius from the line.
    u = (GOAL - START) / length
    off = tube.vertices - START
    assert np.linalg.norm(off - np.outer(off @ u, u), axis=1) == pytest.approx(layers.TUBE_RADIUS, rel=1e-4)
    # The body's axes at the start, every metre along and at the end: the CSV's attitudes.
    at = layers.frame_samples(flight)
    assert len(at) == int(length // layers.FRAME_EVERY_M) + 2
    along = np.linalg.norm(np.c_[flight["x"], flight["y"], flight["z"]][at] - START, axis=1)
    assert along[1:-1] == pytest.approx(np.arange(1, len(at) - 1) * layers.FRAME_EVERY_M, abs=0.03)
    np.testing.assert_allclose(axes.batched_positions, np.c_[flight["x"], flight["y"], flight["z"]][at], atol=1e-6)
    np.testing.assert_allclose(axes.batched_wxyzs, flight["wxyz"][at], atol=1e-6)
    # They tilt into the acceleration: the thrust (body z) is m (a + g e3) + D v (flatness,
    # docs/flight.md), leaning forwards while the flight speeds up and backwards while it
    # brakes, level at rest.
    w, x, y, z = np.asarray(axes.batched_wxyzs, dtype=np.float64).T
    thrust = np.c_[2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)]
    s = flight["t"][at] / T
    delta = GOAL - START
    v = np.outer(30 * s**2 - 60 * s**3 + 30 * s**4, delta) / T
    a = np.outer(60 * s - 180 * s**2 + 120 * s**3, delta) / T**2
    quad = Quadrotor()
    force = quad.mass * (a + [0, 0, 9.81]) + v * [quad.drag_h, quad.drag_h, quad.drag_v]
    np.testing.assert_allclose(thrust, force / np.linalg.norm(force, axis=1, keepdims=True), atol=1e-4)
    lean = thrust @ np.r_[u[:2] / np.linalg.norm(u[:2]), 0.0]  # towards the goal, horizontally
    assert lean[0] == pytest.approx(0, abs=1e-6) and lean[-1] == pytest.approx(0, abs=1e-6)
    assert lean.max() > 0.2 and lean.min() < -0.2  # about 12 degrees and more, forwards and backwards
    assert "flight flight: 4.4 m, 3.0 s, top speed 2.7 m/s" in app.flight_text.content


def test_a_hover_has_no_tube_and_its_axes_at_both_ends():
    n = 50
    hover = {"t": np.linspace(0, 1, n), "x": np.zeros(n), "y": np.zeros(n), "z": np.ones(n)}
    vertices, faces = layers.tube(layers.flight_positions(hover))
    assert vertices.shape == (0, 3) and faces.shape == (0, 3)
    assert list(layers.frame_samples(hover)) == [0, n - 1]


def test_a_planned_flight_is_drawn_with_the_quadrotors_attitudes(site):
    """A FlightTrajectory (or a FlightPlan) given to the library: its samples and attitudes
    (Quadrotor.attitudes) are those its CSV holds."""
    d, _ = site
    from_csv = read_flight_csv(d / "flight.csv")
    given = load_view_inputs(d / "map.npy", flights=rest_to_rest()).flights["flight 1"]
    for column in ("t", "x", "y", "z", "yaw", "wxyz"):
        np.testing.assert_allclose(given[column], from_csv[column], atol=1e-8)
    summary = layers.flight_summary(given)
    assert summary["length_m"] == pytest.approx(np.linalg.norm(GOAL - START), rel=1e-6)
    assert summary["duration_s"] == T and summary["top_speed_mps"] == pytest.approx(
        1.875 * np.linalg.norm(GOAL - START) / T, rel=1e-3
    )
    with pytest.raises(Lf3pmError, match="a flight is a FlightPlan"):
        load_view_inputs(d / "map.npy", flights=[42])


def test_a_replay_of_a_flight_is_drawn_in_3d(site):
    """A replay's truth and estimate keep their heights (the LiDAR's positions in flight)."""
    d, _ = site
    t = np.linspace(0, 1, 11)
    truth = START + np.outer(t, GOAL - START)
    replay = {"truth_xyz": truth.tolist(), "estimate_xyz": (truth + 0.01).tolist(), "errors": [0.01] * len(t)}
    (d / "flight_replay.json").write_text(json.dumps({"runs": [replay]}))
    viewer = serve(
        load_view_inputs(d / "map.npy", d / "r3yaw.zarr", replay_paths=[d / "flight_replay.json"]), port=free_port()
    )
    try:
        tracks = viewer.inputs.replays["replay flight_replay"]
        np.testing.assert_allclose(tracks["truth"][:, 0], truth[:-1], atol=1e-6)
        np.testing.assert_allclose(tracks["estimate"][:, 1], truth[1:] + 0.01, atol=1e-6)
    finally:
        viewer.stop()


def write(path, text: str):
    path.write_text(text)
    return path


def test_bad_flight_csvs_and_ground_solms_are_one_line_errors(site, tmp_path):
    d, _ = site
    head = "t,x,y,z,yaw,qw,qx,qy,qz"
    bad = {
        "lacks the column(s) qw": "t,x,y,z,yaw,qx,qy,qz\n0,0,0,0,0,0,0,0\n1,0,0,0,0,0,0,0\n",
        "a field is not a number": f"{head}\n0,0,0,1,0,1,0,0,0\n1,zero,0,1,0,1,0,0,0\n",
        ":3: 8 fields": f"{head}\n0,0,0,1,0,1,0,0,0\n1,0,0,1,0,1,0,0\n",
        "1 sample": f"{head}\n0,0,0,1,0,1,0,0,0\n",
        "times must increase": f"{head}\n0,0,0,1,0,1,0,0,0\n0,1,0,1,0,1,0,0,0\n",
        "z is not finite": f"{head}\n0,0,0,nan,0,1,0,0,0\n1,0,0,1,0,1,0,0,0\n",
        "is no rotation": f"{head}\n0,0,0,1,0,1,0,0,0\n1,0,0,1,0,0.5,0,0,0\n",
        "empty file": "",
    }
    for message, text in bad.items():
        with pytest.raises(Lf3pmError, match=re.escape(message)) as err:
            read_flight_csv(write(tmp_path / "bad.csv", text))
        assert "\n" not in str(err.value)
    with pytest.raises(Lf3pmError, match="cannot read the flight"):
        read_flight_csv(tmp_path / "missing.csv")
    with pytest.raises(Lf3pmError, match="r2 SOLM .ground robots.: a flight is shown over an r3yaw"):
        load_view_inputs(d / "map.npy", d / "r2.zarr", flights=[d / "flight.csv"])
    inputs = load_view_inputs(d / "map.npy", d / "r3yaw.zarr")
    with pytest.raises(Lf3pmError, match="height 3 m is outside the SOLM's 2 level"):
        serve(inputs, port=free_port(), z=3.0)
    with pytest.raises(Lf3pmError, match="a height picks a level of an r3 or r3yaw SOLM: give one"):
        serve(load_view_inputs(d / "map.npy"), port=free_port(), z=1.0)


@pytest.mark.slow
def test_the_cli_refuses_bad_flight_input_in_one_line_with_status_2(site, tmp_path):
    d, _ = site
    malformed = write(tmp_path / "malformed.csv", "t,x,y,z\n0,0,0,1\n1,1,0,1\n")
    cases = {
        "a flight is shown over an r3yaw": ["--solm", str(d / "r2.zarr"), "--flight", str(d / "flight.csv")],
        "lacks the column(s) yaw, qw": ["--flight", str(malformed)],
        "height 7 m is outside": ["--solm", str(d / "r3yaw.zarr"), "--z", "7", "--flight", str(d / "flight.csv")],
    }
    for message, args in cases.items():
        run = subprocess.run(
            [sys.executable, "-m", "lf3pm", "view", str(d / "map.npy"), *args, "--port", str(free_port())],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert run.returncode == 2, run.stderr
        assert len(run.stderr.strip().splitlines()) == 1 and message in run.stderr


@pytest.mark.slow
@needs_chromium
def test_the_page_shows_the_slice_and_the_flight_in_a_real_browser(app, tmp_path):
    """Headless Chromium (software WebGL): the slice's colours (viridis) and the body's z
    axes (blue) are on the page, the slice at 1 m and the flight climbing from it."""
    from browser import screenshot
    from matplotlib import colormaps

    palette = (colormaps["viridis"](np.linspace(0, 1, 32))[:, :3] * 255).astype(int)

    def shares(image):
        pixels = image[::2, : image.shape[1] * 2 // 3 : 2].reshape(-1, 3).astype(int)  # left of the panel
        near = np.min(np.abs(pixels[:, None, :] - palette[None]).sum(axis=2), axis=1) < 24
        saturated = pixels.max(axis=1) - pixels.min(axis=1) > 40
        blue = (pixels[:, 2] > 150) & (pixels[:, 0] < 30) & (pixels[:, 1] < 30)
        return float(np.mean(near & saturated)), float(np.mean(blue))

    app.map_ceiling.value = 2.9  # under the boxes room's ceiling
    app.height.value = 1.0  # the flight climbs from this level to the next
    app._solm_changed()
    image = screenshot(
        f"http://127.0.0.1:{app.server.get_port()}/",
        tmp_path / "page.png",
        seconds=60,
        ready=lambda img: shares(img)[0] > 0.01 and shares(img)[1] > 2e-4,
    )
    slice_share, axes_share = shares(image)
    assert slice_share > 0.01, "the slice's colours are not on the page"
    # Pure blue: none of the map's colours (turbo) is; about 5e-4 of the pixels here.
    assert axes_share > 2e-4, "the body's axes are not on the page"
