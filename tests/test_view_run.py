"""`lf3pm view --run RUN --audit A.json`: a recorded run and its audit over the map. The
inputs read and checked, the audited scans' colours, a scan's record text, its real
points put in the world by its pose (against a float64 reference) beside the simulated
scan the audit measured, one scan read by streaming, bad input in one line, and the page
served with the run (its actions called directly, no browser)."""

from __future__ import annotations

import json
import math
import urllib.request
from types import SimpleNamespace

import numpy as np
import pytest
from recorded_runs import pillar_room, simulated_run
from typer.testing import CliRunner

import lf3pm
from lf3pm.audit import audit_run
from lf3pm.cli import app as cli
from lf3pm.errors import Lf3pmError
from lf3pm.io import write_points
from lf3pm.pose import pose_matrix
from lf3pm.view import free_port, layers, load_run_inputs, load_view_inputs, read_scan, serve

#: The run: (x, y, yaw) of six scans a second apart across the room; every other one audited.
POSES = [(-3.0 + i, 0.4 * math.sin(i), 0.2 * i) for i in range(6)]
STAMPS = [float(i) for i in range(6)]
EVERY = 2


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The room's map file, a noise-free VLP-16 run through it (a folder of scans with TUM
    poses) and its audit without registrations, as `lf3pm audit -o` writes audit.json."""
    d = tmp_path_factory.mktemp("view_run")
    world = pillar_room()
    write_points(d / "map.npy", world.points)
    run, _ = simulated_run(d / "run", world, POSES, STAMPS)
    audit = audit_run(run, world, "vlp16", every=EVERY, register=False)
    (d / "audit.json").write_text(json.dumps(audit.to_dict()))
    return SimpleNamespace(dir=d, world=world, run=run, audit=audit.to_dict())


def write_audit_json(site, path, change):
    """A copy of the site's audit JSON with ``change(audit)`` applied; returns its path."""
    audit = json.loads(json.dumps(site.audit))
    change(audit)
    path.write_text(json.dumps(audit))
    return path


def reference_pose(i: int) -> np.ndarray:
    x, y, yaw = POSES[i]
    return pose_matrix((x, y, 0.0, yaw))


def test_the_run_and_its_audit_are_read(site):
    run = load_run_inputs(site.run, site.dir / "audit.json")
    assert run.path == site.run and run.scans == len(POSES) and run.sensor == "vlp16"
    # The path: the LiDAR along the reference poses (the run's extrinsic is the identity).
    np.testing.assert_allclose(run.path_xyz, [(x, y, 0.0) for x, y, _ in POSES], atol=1e-12)
    assert [r["index"] for r in run.records] == list(range(0, len(POSES), EVERY))
    for record, written in zip(run.records, site.audit["scans"], strict=True):
        np.testing.assert_array_equal(record["pose"], written["pose"])
        assert math.isnan(record["error_m"])  # null: no registrations in this audit
        assert record["predicted_error_m"] == written["predicted_error_m"]
        assert record["q_n_ratio"] == written["q_n_ratio"]
    assert run.params["seed"] == site.audit["params"]["seed"]
    # The audit alone: the run it names (written as it was given: here an absolute path).
    alone = load_run_inputs(audit_path=site.dir / "audit.json")
    assert alone.path == site.run and alone.unreadable is None
    np.testing.assert_array_equal(alone.path_xyz, run.path_xyz)
    # The run alone: its path, no records.
    bare = load_run_inputs(site.run)
    assert bare.records == [] and bare.sensor is None
    np.testing.assert_array_equal(bare.path_xyz, run.path_xyz)


def moved_run(tmp_path):
    """A change to an audit: its run audited at another path, since gone (moved here)."""

    def change(audit):
        for scan in audit["scans"]:
            scan["name"] = scan["name"].replace(audit["run"], str(tmp_path / "gone"))
        audit["run"] = str(tmp_path / "gone")

    return change


def test_an_audit_whose_run_is_elsewhere_is_shown_without_points(site, tmp_path):
    moved = write_audit_json(site, tmp_path / "a.json", moved_run(tmp_path))
    run = load_run_inputs(audit_path=moved)
    assert run.path is None and "give --run RUN to show the scans' points" in run.unreadable
    assert str(tmp_path / "gone") in run.unreadable
    np.testing.assert_array_equal(run.path_xyz, [r["pose"][:3, 3] for r in run.records])
    with pytest.raises(Lf3pmError, match="give --run"):
        read_scan(run, 0)
    # The run given elsewhere, its scans' names under another path: matched relative to it.
    given = load_run_inputs(site.run, moved)
    assert given.path == site.run and len(given.records) == 3


def test_the_scans_are_coloured_by_the_chosen_quantity_and_missing_values_are_grey(site, tmp_path):
    def errors(audit):
        for scan, error in zip(audit["scans"], (0.01, None, 0.1), strict=True):
            scan["error_m"] = error

    run = load_run_inputs(site.run, write_audit_json(site, tmp_path / "a.json", errors))
    markers = layers.scan_markers(run.records, "real error")
    assert (markers["lo"], markers["hi"], markers["known"]) == (0.01, 0.1, 2)
    from matplotlib import colormaps

    plasma = (colormaps[layers.RUN_COLORMAP]([0.0, 1.0])[:, :3] * 255).astype(np.uint8)
    np.testing.assert_array_equal(markers["colors"][[0, 2]], plasma)
    np.testing.assert_array_equal(markers["colors"][1], [128, 128, 128])
    np.testing.assert_allclose(markers["positions"], [r["pose"][:3, 3] for r in run.records])
    assert markers["positions"].dtype == np.float32
    predicted = layers.scan_markers(run.records, "predicted localization error")
    values = np.array([r["predicted_error_m"] for r in site.audit["scans"]])
    np.testing.assert_array_equal(predicted["values"], values)
    assert (predicted["lo"], predicted["hi"]) == (values.min(), values.max())
    np.testing.assert_array_equal(
        predicted["colors"], layers.colormap(values, values.min(), values.max(), name=layers.RUN_COLORMAP)
    )
    tracking = layers.scan_markers(run.records, "tracking error")  # none tracked: every scan grey
    assert tracking["known"] == 0 and (tracking["colors"] == 128).all()
    # The page opens on a quantity the audit has: no registrations, so not the real error.
    assert layers.first_known_quantity(load_run_inputs(site.run, site.dir / "audit.json").records) == (
        "predicted localization error"
    )
    with pytest.raises(Lf3pmError, match="unknown quantity 'sigma'"):
        layers.scan_markers(run.records, "sigma")


def test_a_scan_record_reads_as_its_numbers(site):
    records = load_run_inputs(audit_path=site.dir / "audit.json").records
    record = dict(records[1], error_m=0.0123, error_max_m=0.02, spread_m=0.004, tracking_error_m=0.031)
    record.update(name="<b>scan</b>", predicted_error_m=math.nan, predicted_error_withheld="a q_n outside the fit")
    text = layers.scan_record_text(record)
    written = site.audit["scans"][1]
    assert text.startswith(f"**Scan 2** `&lt;b&gt;scan&lt;/b&gt;`, stamp {written['stamp']:.3f} s")
    assert f"- pose ({POSES[2][0]:.2f}, {POSES[2][1]:.2f}, 0.00) m, yaw {math.degrees(POSES[2][2]):.0f}°" in text
    assert "- real error 1.2 cm (largest 2.0 cm, spread 0.4 cm)" in text
    assert "- tracking error 3.1 cm" in text
    assert "- predicted localization error withheld (a q_n outside the fit)" in text
    assert (
        f"- q_n real {written['real_q_n']:.4g}, simulated {written['sim_q_n']:.4g}, "
        f"simulated / real {written['q_n_ratio']:.4g}" in text
    )
    untouched = layers.scan_record_text(records[0])
    assert "real error not computed (no registration in this audit)" in untouched
    lo, hi = site.audit["scans"][0]["predicted_error_lo_m"], site.audit["scans"][0]["predicted_error_hi_m"]
    assert f"({lo * 100:.1f} cm to {hi * 100:.1f} cm)" in untouched


def test_one_scan_is_read_by_streaming_to_it(site, monkeypatch):
    """The scans after the one asked for are never read; its points are the file's."""
    import lf3pm.io

    run = load_run_inputs(site.run)
    read, load_points = [], lf3pm.io.load_points
    monkeypatch.setattr(lf3pm.io, "load_points", lambda path, *a, **k: read.append(path) or load_points(path, *a, **k))
    scan = read_scan(run, 2)
    assert scan.index == 2 and len(read) == 3
    np.testing.assert_array_equal(scan.points, np.load(site.run / "scans" / "2.0.npy"))
    with pytest.raises(Lf3pmError, match="no scan 6 \\(6 scans\\)"):
        read_scan(run, 6)


@pytest.mark.parametrize(
    "case, message",
    [
        ("no audit file", "missing.json: no such audit file"),
        ("not JSON", "not an audit JSON (JSONDecodeError)"),
        ("a replay", "not an audit JSON (write one with `lf3pm audit RUN --map MAP -o DIR`: DIR/audit.json): no scans"),
        ("bad pose", "scans[1].pose must be 4 x 4 numbers"),
        ("bad number", "scans[0].error_m must be a number or null, got '0.1'"),
        ("another run", "its scan "),
        ("no run", "no such file or folder"),
    ],
)
def test_bad_input_is_one_line(site, tmp_path, case, message):
    audit, run = site.dir / "audit.json", site.run
    if case == "no audit file":
        audit = tmp_path / "missing.json"
    elif case == "not JSON":
        audit = tmp_path / "broken.json"
        audit.write_text('{"scans": [')
    elif case == "a replay":
        audit = tmp_path / "replay.json"
        audit.write_text(json.dumps({"runs": [{"truth_xyz": [[0, 0, 0]]}]}))
    elif case == "bad pose":
        audit = write_audit_json(site, tmp_path / "a.json", lambda a: a["scans"][1].update(pose=[[1, 0, 0, 0]] * 3))
    elif case == "bad number":
        audit = write_audit_json(site, tmp_path / "a.json", lambda a: a["scans"][0].update(error_m="0.1"))
    elif case == "another run":  # a run of four scans named otherwise
        run, _ = simulated_run(tmp_path / "other", site.world, POSES[:4], [10.0 + t for t in STAMPS[:4]])
    else:
        run = tmp_path / "no_run"
    with pytest.raises(Lf3pmError) as raised:
        load_run_inputs(run, audit)
    line = str(raised.value)
    assert message in line and "\n" not in line, line
    if case == "another run":
        assert "(index 0) is not in the run" in line and "an audit of another run?" in line


def test_the_cli_refuses_an_audit_of_another_run_in_one_line_with_status_2(site, tmp_path):
    other, _ = simulated_run(tmp_path / "other", site.world, POSES[:2], [10.0, 11.0])
    args = ["view", str(site.dir / "map.npy"), "--run", str(other), "--audit", str(site.dir / "audit.json")]
    got = CliRunner().invoke(cli, [*args, "--port", str(free_port())])
    assert got.exit_code == 2, got.output
    lines = got.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lf3pm: error:") and "is not in the run" in lines[0]


@pytest.fixture(scope="module")
def page(site):
    viewer = serve(
        load_view_inputs(site.dir / "map.npy", run_path=site.run, audit_path=site.dir / "audit.json"), port=0
    )
    yield viewer
    viewer.stop()


def test_the_page_shows_the_run_and_its_first_scan(page, site):
    assert page.mode.value == "choose a scan"
    assert page.status.startswith("**Scan 0**") and "the simulated scan of vlp16 there" in page.status
    assert urllib.request.urlopen(f"http://127.0.0.1:{page.port}/", timeout=10).status == 200
    markers = layers.scan_markers(page.inputs.run.records, page.run_quantity.value)
    np.testing.assert_array_equal(page._markers.colors, markers["colors"])
    page.run_quantity.value = "q_n of the real scan"
    q_n = np.array([r["real_q_n"] for r in site.audit["scans"]])
    np.testing.assert_array_equal(
        page._markers.colors, layers.scan_markers(page.inputs.run.records, "q_n of the real scan")["colors"]
    )
    assert len(set(map(tuple, page._markers.colors))) == len(np.unique(q_n))  # each its own colour
    (x0, y0), (x1, y1) = page.focus_bounds()
    assert (x0, x1) == (POSES[0][0], POSES[-1][0])


def test_a_shown_scan_is_its_points_at_its_pose_beside_the_audit_s_simulated_scan(page, site):
    out = page.show_scan(1)
    record = site.audit["scans"][1]
    assert out["record"]["index"] == record["index"] == 2 and page.scan_choice.value == 1
    reference = np.load(site.run / "scans" / "2.0.npy") @ reference_pose(2)[:3, :3].T + reference_pose(2)[:3, 3]
    np.testing.assert_allclose(out["real"], reference, rtol=0, atol=1e-12)
    drawn = page._scan_nodes[0].points  # what the browser gets: float32
    assert drawn.dtype == np.float32
    np.testing.assert_allclose(drawn, reference, rtol=0, atol=1e-5)
    params = site.audit["params"]
    simulated = lf3pm.evaluate(
        site.world,
        np.array(record["pose"]),
        "vlp16",
        observations=True,
        seed=params["seed"],
        noise=params["noise"],
        scan_voxel=params["scan_voxel"],
    )
    np.testing.assert_array_equal(out["simulated"], simulated.observations["points"])
    assert simulated.q_n == record["sim_q_n"]  # the scan the audit measured
    # The run is the noise-free scan of the same sensor: the real points lie where the
    # simulated ones do, within the simulated scan's range noise.
    from scipy.spatial import cKDTree

    gap = cKDTree(out["real"]).query(out["simulated"])[0]
    assert np.median(gap) < 3 * params["noise"]
    assert (
        page.status.startswith("**Scan 2**") and f"its {len(reference):,} points at its reference pose" in page.status
    )


def test_a_click_chooses_the_scan_nearest_its_ray(page, site):
    x, y, _ = POSES[4]
    page._clicked(SimpleNamespace(ray_origin=(x, y, 10.0), ray_direction=(0.0, 0.0, -1.0), client=None))
    assert page.scan_choice.value == 2 and page.status.startswith("**Scan 4**")
    page.status = ""
    page._clicked(SimpleNamespace(ray_origin=(x + 0.1, y, 10.0), ray_direction=(0.0, 0.0, -1.0), client=None))
    assert page.status.startswith("**Scan 4**")  # the slider stays: drawn again all the same
    page._guarded(page._clicked, SimpleNamespace(ray_origin=(x, y, 10.0), ray_direction=(0.0, 0.0, 1.0), client=None))
    assert page.status == "error: no audited scan in front of that click"
    assert layers.nearest_scan(np.zeros((1, 3)), (0.0, 0.0, 1.0), (0.0, 0.0, 1.0)) is None


def test_a_run_without_an_audit_and_an_audit_without_its_run_are_served(site, tmp_path):
    bare = serve(load_view_inputs(site.dir / "map.npy", run_path=site.run), port=0)
    try:
        assert bare.mode.value == "inspect a cell" and bare.run_quantity is None
        bare.scan_choice.value = 3
        assert bare.status.startswith("**Scan 3**") and "no audit given" in bare.status
        reference = np.load(site.run / "scans" / "3.0.npy") @ reference_pose(3)[:3, :3].T + reference_pose(3)[:3, 3]
        np.testing.assert_allclose(bare.show_scan(3)["real"], reference, rtol=0, atol=1e-12)
    finally:
        bare.stop()
    moved = write_audit_json(site, tmp_path / "a.json", moved_run(tmp_path))
    alone = serve(load_view_inputs(site.dir / "map.npy", audit_path=moved), port=0)
    try:
        assert alone.status.startswith("error: the run the audit names") and "give --run RUN" in alone.status
        assert alone.error_text.visible and alone.scan_text.content.startswith("**Scan 0**")
    finally:
        alone.stop()
