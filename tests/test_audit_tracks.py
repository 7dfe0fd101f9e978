"""Localization and odometry along a recorded run (lf3pm.audit.tracks; issue 42, item 2).
On a map made of the run's own noise-free hits, tracking from the previous estimate finds
every reference pose to float32 round-off; KISS-ICP along a run is the replay's KISS-ICP
on the same scans; the audit carries each scan's errors and says when it ran no track."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from recorded_runs import pillar_room, simulated_run
from typer.testing import CliRunner

import lf3pm
from lf3pm.audit import SelfMap, audit_run
from lf3pm.audit.tracks import ODOMETRY, TRACKING, track_localization, track_odometry
from lf3pm.cli import app
from lf3pm.config import DEFAULTS, configured
from lf3pm.replays.odometry import run_kiss_icp
from lf3pm.runs import Run

#: A drive through the room that turns: 0.4 m and 0.05 rad a scan, so each scan's prior
#: (the last estimate) lies that far off.
POSES = [(-3.0 + 0.4 * i, 0.025 * i, 0.05 * i) for i in range(8)]
STAMPS = [round(0.1 * i, 1) for i in range(8)]  # as the scans are named


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    """(run folder, the room's map, a map of the run's own hits)."""
    room = pillar_room()
    folder, hits = simulated_run(tmp_path_factory.mktemp("drive"), room, POSES, STAMPS)
    return folder, room, lf3pm.load_map(np.unique(np.round(hits, 9), axis=0))


def test_tracking_on_a_map_of_the_runs_own_hits_finds_every_reference_pose(drive):
    """Every point of every scan is a map point, so the point-to-plane residual vanishes at
    the reference pose, a fixed point the registration converges to from the prior. What is
    left is the points' float32 storage: 2^-24 of the room's ranges (< 8 m) is 5e-7 m."""
    folder, _, own_hits = drive
    whole = configured(DEFAULTS, ("localization",), "the test", scan_voxel=0.0)  # every point a map point
    track = track_localization(folder, own_hits, "vlp16", whole)
    assert track.method == TRACKING and track.skipped == 0 and len(track.errors_m) == 8
    assert np.array_equal(track.stamps, STAMPS)
    assert track.errors_m.max() < 8.0 * 2.0**-24 * 4  # a few float32 steps at 8 m
    assert track.ape["count"] == 8 and track.error_at(0.3) == track.errors_m[3] and math.isnan(track.error_at(9.0))


def test_kiss_icp_along_a_run_is_the_replays_kiss_icp_on_its_scans(drive):
    folder, _, _ = drive
    config = configured(DEFAULTS, ("kiss_icp", "scan"), "the test", voxel_size=0.25, threads=1)
    track = track_odometry(folder, "vlp16", config)
    with Run(folder) as run:
        scans = [SimpleNamespace(points=s.points, timestamps=np.empty(0), pose=s.pose) for s in run.scans()]
    direct = run_kiss_icp(scans, lf3pm.sensors.get_sensor("vlp16"), scans[0].pose, config.kiss_icp, threads=1)
    # The same code path: equal but for TBB's reduction order, which a test run after another
    # test's multi-threaded KISS-ICP in this process cannot fix (run_kiss_icp: KISS-ICP keeps
    # the first thread limit a process sets); that order moves poses at 1e-16 relative, so
    # 1e-12 m over a few metres of 8 scans is far above it and far below any real difference.
    assert track.method == ODOMETRY
    np.testing.assert_allclose(track.poses, direct.poses, rtol=0, atol=1e-12)
    assert track.errors_m[0] == 0.0  # anchored at the first reference pose


@pytest.mark.slow
def test_the_audit_carries_each_scans_track_errors_or_says_why_it_has_none(drive):
    folder, room, _ = drive
    config = configured(DEFAULTS, ("mde",), "the test", trials=2)
    audit = audit_run(folder, room, "vlp16", config, every=3)
    tracking, odometry = audit.tracks
    assert [r.index for r in audit.records] == [0, 3, 6]
    for record in audit.records:
        assert record.tracking_error_m == tracking.error_at(record.stamp)
        assert record.odometry_error_m == odometry.error_at(record.stamp)
    described = audit.to_dict()
    assert [t["method"] for t in described["tracks"]] == [TRACKING, ODOMETRY] and described["tracks_withheld"] is None
    assert audit.lio_withheld == "the run has no IMU" and all(r.lio_errors_m == () for r in audit.records)
    assert any(c.real_error == "tracking_error_m" and c.scans == 3 for c in audit.summary.correlations)
    alone = audit_run(folder, room, "vlp16", config, every=3, register=False)
    assert alone.tracks == () and alone.tracks_withheld == alone.lio_withheld == "registrations left out"
    assert math.isnan(alone.records[0].tracking_error_m)
    own = audit_run(folder, SelfMap.of_run(folder, configured(config, ("run",), "t", exclude_window=0.0)), every=3)
    assert own.tracks == () and "tracking needs one map" in own.tracks_withheld == own.lio_withheld


@pytest.mark.slow  # the CLI's first import: over 2 s on 2 cores
def test_the_cli_says_each_tracks_ape(drive, tmp_path):
    folder, room, _ = drive
    np.save(tmp_path / "room.npy", room.points)
    args = ["audit", str(folder), "--map", str(tmp_path / "room.npy"), "--every", "4", "--starts", "1"]
    got = CliRunner().invoke(app, args)
    assert got.exit_code == 0, got.output
    assert "localization along the run: APE rmse" in got.stdout and "kiss-icp along the run: APE rmse" in got.stdout
    got = CliRunner().invoke(app, [*args, "--no-track", "--json"])
    assert got.exit_code == 0 and '"tracks_withheld": "not asked for"' in got.stdout, got.output
