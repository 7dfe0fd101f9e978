"""`lf3pm sensors fit` (lf3pm.audit.sensor_fit; issue 42, item 4): a sensor fitted from a
recorded run gives back the sensor that recorded it. Scans simulated in a closed room, so
that every ray returns: the beams' elevations to the histogram's resolution, the columns
exactly, the range noise drawn, and simulated scans at the reference poses that match the
real ones ray for ray; a Livox's pattern read back in the order recorded."""

from __future__ import annotations

import json

import numpy as np
import pytest
from recorded_runs import pillar_room, write_run
from typer.testing import CliRunner

import lf3pm
from lf3pm.audit.sensor_fit import ELEVATION_BIN_DEG, fit_sensor, fitted_sensor, write_sensor
from lf3pm.cli import app
from lf3pm.pose import pose_matrix
from lf3pm.scan.scan_simulator import simulate_scan
from lf3pm.sensors import get_sensor

POSES = [(-3.0 + 0.5 * i, -1.0 + 0.2 * i, 0.3 * i) for i in range(6)]  # clear of the pillar
STAMPS = [round(0.1 * i, 1) for i in range(6)]


def scanned_run(folder, world, sensor, noise=0.0, returns=None):
    """A run folder of ``sensor``'s scans at POSES (range noise ``noise``, the hits that
    return by ``returns``, seed 0, one stream per scan); returns the folder."""
    scans = [
        simulate_scan(
            world,
            pose_matrix((x, y, 0.0, yaw)),
            sensor.directions,
            sensor.min_range,
            sensor.max_range,
            noise=noise,
            stream=k,
            returns=returns,
        ).sensor_points
        for k, (x, y, yaw) in enumerate(POSES)
    ]
    return write_run(folder, scans, POSES, STAMPS)


@pytest.fixture(scope="module")
def room():
    return pillar_room()


@pytest.mark.parametrize("preset", ["vlp16", "os1-64"])
def test_a_spinning_sensor_is_fitted_back_from_its_scans(preset, room, tmp_path):
    sensor = get_sensor(preset)
    folder = scanned_run(tmp_path / "run", room, sensor)
    fit = fit_sensor(folder, room)
    _, el = sensor.angles()
    beams = np.unique(np.round(np.degrees(el), 6))
    assert fit.kind == "spinning" and fit.ring_counts == (len(beams),) * len(POSES)
    # A peak is a histogram bin's centre: within half a bin of the beam.
    np.testing.assert_allclose(fit.yaml["elevations_deg"], beams, atol=ELEVATION_BIN_DEG / 2 + 1e-3)
    assert fit.yaml["azimuth_count"] == sensor.num_rays // len(beams)
    assert sensor.min_range <= fit.yaml["min_range"] and fit.yaml["max_range"] <= sensor.max_range
    assert fit.yaml["range_noise_sigma"] < 1e-3  # noise-free scans on the map they were cast on
    assert set(np.ravel(fit.yaml["return_probability"]["table"])) == {1.0}  # every hit returned
    for c in fit.comparisons:  # the same rays return, at the same ranges
        assert c.share_both > 0.99 and abs(c.residual_median_m) < 1e-3
        assert c.q_n_ratio == pytest.approx(1.0, rel=0.05)
    path = tmp_path / "fitted.yaml"
    write_sensor(fit, path)
    loaded = get_sensor(str(path))
    np.testing.assert_array_equal(loaded.directions, fitted_sensor(fit).directions)
    assert loaded.num_rays == sensor.num_rays


def test_the_range_noise_is_the_noise_the_scans_were_drawn_with(room, tmp_path):
    """VLP-16 scans with 1 cm range noise against the exact room: the point-to-plane
    distance over |cos incidence| is the range error, its robust sigma 1 cm (over some
    10^5 returns the MAD's own error is under 1 %; corners and the pillar's edges, whose
    k-NN planes are not the surface, are what the tolerance allows for)."""
    folder = scanned_run(tmp_path / "run", room, get_sensor("vlp16"), noise=0.01)
    fit = fit_sensor(folder, room)
    assert fit.yaml["range_noise_sigma"] == pytest.approx(0.01, rel=0.1) and fit.noise_returns > 100_000


def test_which_rays_return_is_fitted_back_and_simulated_scans_lose_as_many(room, tmp_path):
    """OS1-64 scans that lose returns by range and incidence (a known table): the fitted
    table, applied to the hits of a scan it was not fitted on, expects as many returns as
    the truth does (within 4 binomial sigma of the scan's hits plus the table's 0.001
    rounding), and on the compared scans (left out of the fit) the simulated sensor returns
    on as many rays as the real one, within 5 points; without --returns, every hit returns."""
    from lf3pm.audit.sensor_fit import COS_EDGES
    from lf3pm.sensors import ReturnModel

    os1 = get_sensor("os1-64")
    # The room's hits lie 2.9 to 10.4 m away: two range bins, each with its own incidence law.
    truth = ReturnModel(
        (os1.min_range, 4.0, os1.max_range), COS_EDGES, [[0.3, 0.4, 0.5, 0.6, 0.7], [0.1, 0.2, 0.3, 0.4, 0.5]]
    )
    folder = scanned_run(tmp_path / "run", room, os1, returns=truth)
    fit = fit_sensor(folder, room)
    sensor = fitted_sensor(fit)
    assert fit.return_scans == 1 and len(fit.comparisons) == 5
    hits = simulate_scan(room, pose_matrix((0.5, 0.5, 0.0, 1.0)), os1.directions, os1.min_range, os1.max_range)
    rng = np.linalg.norm(hits.sensor_points, axis=1)
    cos = np.abs(np.einsum("ij,ij->i", hits.world_points - [0.5, 0.5, 0.0], room.index.normals[hits.surfel])) / rng
    p = truth.at(rng, cos)
    assert abs(sensor.returns.at(rng, cos).sum() - p.sum()) < 4 * np.sqrt((p * (1 - p)).sum()) + 0.001 * len(p)
    for c in fit.comparisons:
        assert abs(c.real_share - c.sim_share) < 0.05
    assert fit_sensor(folder, room, returns=False).comparisons[0].sim_share > 0.99


def test_a_livox_pattern_is_read_back_in_the_order_recorded(room, tmp_path):
    """Mid-70 scans of 0.1 s, each the next 10,000 rays of the pattern: the fitted pattern is
    the returns' directions scan after scan (float64 points: to 1e-12), its rate the returns
    per second."""
    mid70 = get_sensor("mid70", integration_time=0.6)
    rays = mid70.directions.reshape(6, 10_000, 3)
    scans = [
        simulate_scan(room, pose_matrix((x, y, 0.0, yaw)), rays[k], mid70.min_range, mid70.max_range).sensor_points
        for k, (x, y, yaw) in enumerate(POSES)
    ]
    folder = write_run(tmp_path / "run", scans, POSES, STAMPS)
    fit = fit_sensor(folder, room)
    cloud = np.vstack(scans)
    expected = np.column_stack(
        [np.arctan2(cloud[:, 1], cloud[:, 0]), np.arcsin(cloud[:, 2] / np.linalg.norm(cloud, axis=1))]
    )
    assert fit.kind == "pattern"
    np.testing.assert_allclose(fit.pattern, expected, atol=1e-12)
    assert fit.yaml["integration_time"] == pytest.approx(0.1)
    assert fit.yaml["point_rate"] == pytest.approx(len(cloud) / 0.6, abs=0.1)
    written = write_sensor(fit, tmp_path / "mine.yaml")
    assert [p.name for p in written] == ["mine.yaml", "mine_pattern.npy"]
    loaded = get_sensor(str(tmp_path / "mine.yaml"))
    assert loaded.num_rays == round(fit.yaml["point_rate"] * 0.1)


def test_the_cli_writes_a_sensor_that_works_as_a_preset_and_refuses_bad_input(room, tmp_path):
    folder = scanned_run(tmp_path / "run", room, get_sensor("vlp16"))
    map_path = tmp_path / "room.npy"
    np.save(map_path, room.points)
    out = tmp_path / "mine.yaml"
    done = CliRunner().invoke(app, ["sensors", "fit", str(folder), "--map", str(map_path), "-o", str(out), "--json"])
    assert done.exit_code == 0, done.output
    got = json.loads(done.stdout)
    assert got["kind"] == "spinning" and got["yaml"]["azimuth_count"] == 1800 and got["written"] == [str(out)]
    res = lf3pm.evaluate(room, (0.0, 0.0, 0.0, 0.0), str(out))
    assert res.hits > 0 and res.sensor == "fitted"
    one = write_run(tmp_path / "one", [np.ones((10, 3))], POSES[:1], STAMPS[:1])
    bad = CliRunner().invoke(app, ["sensors", "fit", str(one), "-o", str(tmp_path / "x.yaml")])
    assert bad.exit_code == 2 and "a fit needs at least 2" in bad.output
    missing = CliRunner().invoke(
        app, ["sensors", "fit", str(folder), "--map", str(tmp_path / "no.npy"), "-o", str(out)]
    )
    assert missing.exit_code == 2 and len(missing.output.strip().splitlines()) == 1
    listed = CliRunner().invoke(app, ["sensors"])
    assert listed.exit_code == 0 and "vlp16" in listed.stdout


def test_a_sensor_is_fitted_from_a_replay_bag(room, tmp_path):
    """The bag `lf3pm replay --bag` writes (PointCloud2 with per-point times, a VLP-16
    standing in the room, noise-free): the VLP-16's beams and columns, and its simulated
    scans at the bag's true poses return on the same rays."""
    from recorded_runs import stream_bag

    path, _ = stream_bag(room, tmp_path, moving=False, noise=None)
    fit = fit_sensor(path, room)
    assert fit.kind == "spinning" and len(fit.yaml["elevations_deg"]) == 16 and fit.yaml["azimuth_count"] == 1800
    assert all(c.share_both > 0.99 for c in fit.comparisons)
