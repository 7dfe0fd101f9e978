"""LiDAR-inertial odometries along a recorded run (lf3pm.audit.tracks.track_lio; issue 42,
item 2). A noise-free stream with its IMU, written as `lf3pm replay --bag` writes it, audited
with the LIO tracks on: each odometry holds what the replay tests demand of it on the same
kind of stream, and its track is run_lio's estimate on the bag's scans and IMU, pose for
pose. The IMU moved from the body to the LiDAR matches the LiDAR's own motion; a crashing
odometry is a track with a one-line message; bad options are one line and exit 2."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

import lf3pm
from lf3pm.audit import audit_run
from lf3pm.audit import tracks as tracks_module
from lf3pm.audit.tracks import has_imu, imu_in_lidar_frame, lio_odometries, track_lio
from lf3pm.cli import app
from lf3pm.config import DEFAULTS, configured
from lf3pm.replays.lio import run_lio
from lf3pm.runs import ImuSample, Run

#: APE rmse bounds (m) the replay tests demand of each odometry on a noise-free VLP-16
#: stream from rest: GenZ-LIO and DLIO on this very drive, 2 cm (tests/test_lio.py,
#: test_noise_free_drive_from_rest_holds_centimetres_with_no_lag); LIO-SAM, which that
#: test does not run, 10 cm on the room's figure of eight
#: (test_liosam_tracks_the_figure_of_eight_at_its_median_return_times).
BOUNDS = {"genz": 0.02, "dlio": 0.02, "liosam": 0.1}
REST = DEFAULTS.replay.rest  # s: the lio replay's rest, 2 s


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    """(bag, town): tests/test_lio.py's straight drive out of the reduced gobi's town
    square (8 s, the speed ramping to 1 m/s) after the replay's 2 s rest, VLP-16,
    noise-free scans and IMU, as `lf3pm replay --bag` writes a stream (true poses at 100 Hz)."""
    pytest.importorskip("genz_lio", reason="genz-lio has wheels for Python 3.8-3.12 only")
    pytest.importorskip("evalio", reason="evalio (DLIO, LIO-SAM) is not installed: pip install 'lf3pm[lio]'")
    from test_lio import town_drive

    from lf3pm.experiments.gobi import REDUCED
    from lf3pm.replays.bag import write_bag
    from lf3pm.replays.imu import simulate_imu
    from lf3pm.replays.motion import RestFirst
    from lf3pm.scan.scans import ScanStream
    from lf3pm.scenes import build_scene
    from lf3pm.sensors import get_sensor

    town = lf3pm.load_map(build_scene("gobi", seed=REDUCED.seed, **REDUCED.scene_params).points)
    motion = RestFirst(town_drive(town, 0.0), REST)
    stream = ScanStream(town, motion, get_sensor("vlp16"), noise=0.0, threads=1)
    path = tmp_path_factory.mktemp("lio") / "drive.bag"
    write_bag(path, stream, simulate_imu(motion, noise=False))
    return path, town


def recorded_stream(path):
    """The bag's good scans as run_lio takes them (points in time order, absolute times,
    ending at their last point) and its whole IMU, read here without lf3pm.audit."""
    with Run(path, skip_bad=True) as run:
        scans = []
        for scan in run.scans():
            stamps = scan.stamp + scan.times
            order = np.argsort(stamps, kind="stable")
            scans.append(SimpleNamespace(end=stamps[order][-1], points=scan.points[order], stamps=stamps[order]))
        samples = list(run.imu())
    imu = SimpleNamespace(
        t=np.array([s.stamp for s in samples]),
        accel=np.array([s.linear_acceleration for s in samples]),
        gyro=np.array([s.angular_velocity for s in samples]),
    )
    return scans, imu


@pytest.mark.slow
def test_each_lio_along_a_replay_bag_holds_what_the_replay_demands_and_is_run_lio_on_its_scans(drive):
    """Every registered odometry runs on the VLP-16 (the default), each within its replay
    bound against the true poses, at the times its poses refer to; each track is run_lio on
    the bag's scans and IMU from the identity, anchored at the true pose at its first
    pose's time, bit for bit; each audited scan's record carries every track's error."""
    path, town = drive
    config = configured(None, ("mde", "scan"), "the test", trials=1, threads=1)
    result = audit_run(path, town, "vlp16", config, every=50)
    assert result.lio_withheld is None
    lio = result.tracks[2:]
    assert tuple(t.method for t in lio) == lio_odometries("vlp16") == ("genz", "dlio", "liosam")
    scans, imu = recorded_stream(path)
    with Run(path) as run:
        for track in lio:
            assert track.message is None and track.skipped == 0, track.message
            assert len(track.stamps) == len(scans) == 100
            # All but GenZ-LIO's last pose, at the last scan's end: its float32 point time
            # lies a nanosecond past the truth's last pose.
            assert track.ape["count"] >= len(scans) - 1
            assert track.ape["rmse"] < BOUNDS[track.method], (track.method, track.ape)
            direct = run_lio(scans, imu, "vlp16", initial_pose=np.eye(4), odometry=track.method)
            poses = run.lidar_pose_at(direct.times[0]) @ direct.poses
            np.testing.assert_array_equal(track.poses, poses)
            for k, at in enumerate(direct.times):
                if math.isfinite(track.errors_m[k]):
                    assert track.errors_m[k] == np.linalg.norm(poses[k, :3, 3] - run.lidar_pose_at(at)[:3, 3])
    for record in result.records:
        got = dict(record.lio_errors_m)
        assert list(got) == ["genz", "dlio", "liosam"]
        np.testing.assert_equal([got[t.method] for t in lio], [t.error_at(record.stamp) for t in lio])  # NaN: NaN
    described = result.to_dict()
    assert [t["method"] for t in described["tracks"]][2:] == ["genz", "dlio", "liosam"]
    assert described["scans"][0]["lio_errors_m"][0][0] == "genz"


def spin(times, angle, rate, acceleration):
    """A level body turning in place about z (yaw ``angle`` + ``rate`` t + acceleration
    t^2 / 2): its IMU's rows (t, accel, gyro) in the body frame."""
    yaw_rate = rate + acceleration * times
    rows = np.zeros((len(times), 7))
    rows[:, 0], rows[:, 3], rows[:, 6] = times, 9.81, yaw_rate
    return rows, angle + rate * times + 0.5 * acceleration * times**2, yaw_rate


def test_the_imu_moved_to_the_lidar_reads_the_lidars_own_motion():
    """The body turns in place with a constant yaw acceleration; the LiDAR sits 0.3 m
    off its axis, turned and tilted. What an IMU at the LiDAR reads, in the LiDAR's axes,
    from its world trajectory p(t) = Rz(yaw) r (p'' = yaw'' Rz' r + yaw'^2 Rz'' r, gravity
    added, turned by the LiDAR's world rotation): the moved samples, to round-off
    (central differences of a linearly rising yaw rate are exact). Handed out in chunks
    of any size, the same samples."""
    alpha, lever = 1.5, np.array([0.3, -0.1, 0.2])
    turn = Rotation.from_euler("zyx", [90.0, 0.0, 10.0], degrees=True).as_matrix()
    body_from_lidar = np.eye(4)
    body_from_lidar[:3, :3], body_from_lidar[:3, 3] = turn, lever
    times = np.arange(0.0, 1.0, 0.005)
    rows, yaw, yaw_rate = spin(times, 0.2, 0.4, alpha)
    moved = imu_in_lidar_frame(rows, body_from_lidar)
    for k in (0, 57, len(times) - 1):
        c, s = math.cos(yaw[k]), math.sin(yaw[k])
        first = np.array([[-s, -c, 0.0], [c, -s, 0.0], [0.0, 0.0, 0.0]])  # dRz/dyaw
        second = np.array([[-c, s, 0.0], [-s, -c, 0.0], [0.0, 0.0, 0.0]])
        acceleration = alpha * first @ lever + yaw_rate[k] ** 2 * second @ lever
        world_from_lidar = Rotation.from_euler("z", yaw[k]).as_matrix() @ turn
        np.testing.assert_allclose(moved[k, 1:4], world_from_lidar.T @ (acceleration + [0, 0, 9.81]), atol=1e-12)
        np.testing.assert_allclose(moved[k, 4:7], turn.T @ [0.0, 0.0, yaw_rate[k]], atol=1e-15)
    assert moved[:, 0].tolist() == times.tolist()
    assert imu_in_lidar_frame(rows, np.eye(4)) is rows  # the identity: the samples as recorded

    samples = [ImuSample(r[0], r[4:7], r[1:4]) for r in rows]
    for size in (1, 7, 1000):
        kept = {"samples": 0, "repeated": 0}
        original, tracks_module.IMU_CHUNK = tracks_module.IMU_CHUNK, size
        try:
            chunks = list(tracks_module._imu_chunks(samples, body_from_lidar, -1.0, lambda t: False, kept))
        finally:
            tracks_module.IMU_CHUNK = original
        joined = np.column_stack([np.concatenate([getattr(c, n) for c in chunks]) for n in ("t", "accel", "gyro")])
        np.testing.assert_allclose(joined, moved, rtol=0, atol=1e-12)
        assert kept == {"samples": len(times), "repeated": 0}


@pytest.mark.slow
def test_a_crashing_lio_is_a_track_with_its_line_and_no_error(drive, tmp_path, monkeypatch):
    """The odometry's worker dying (SIGSEGV, as a segfault would) is a track whose errors
    are all NaN and whose message says so in one line; nothing raises."""
    import lf3pm.replays.lio as lio

    path, _ = drive
    worker = tmp_path / "crash.py"
    worker.write_text("import os, signal\nprint('about to crash', flush=True)\nos.kill(os.getpid(), signal.SIGSEGV)\n")
    monkeypatch.setattr(lio, "_WORKER", str(worker))
    track = track_lio(path, "genz", "vlp16")
    assert track.message == "GenZ-LIO failed: GenZ-LIO crashed (signal 11) while starting: about to crash"
    assert np.isnan(track.errors_m).all() and track.ape["count"] == 0 and math.isnan(track.error_at(track.stamps[0]))
    assert track.to_dict()["message"] == track.message


@pytest.mark.slow  # the CLI's first import: over 2 s on 2 cores
def test_the_cli_says_each_lios_ape_and_refuses_unknown_names_in_one_line(drive, tmp_path):
    path, town = drive
    np.save(tmp_path / "town.npy", town.points)
    runner = CliRunner()
    base = ["audit", str(path), "--map", str(tmp_path / "town.npy"), "--sensor", "vlp16"]
    got = runner.invoke(app, [*base, "--lio", "fastlio"])
    assert got.exit_code == 2 and got.stdout == ""
    assert got.stderr == "lf3pm: error: unknown odometry 'fastlio'; use one of auto, genz, dlio, liosam\n"
    got = runner.invoke(app, [*base, "--lio", "genz", "--no-lio"])
    assert got.exit_code == 2 and got.stderr == "lf3pm: error: --lio and --no-lio: give one of them\n"
    out = tmp_path / "out"
    got = runner.invoke(app, [*base, "--every", "50", "--starts", "1", "--lio", "genz", "--lio", "auto", "-o", out])
    assert got.exit_code == 0, got.output
    assert "genz along the run: APE rmse" in got.stdout and "dlio along the run: APE rmse" in got.stdout
    assert "liosam along the run" not in got.stdout  # auto is DLIO for a spinning sensor
    assert "--lio genz --lio auto" in (out / "report.md").read_text()


def test_lio_tracks_are_withheld_without_an_imu_or_when_none_is_asked_for(tmp_path):
    """A run folder has no IMU: the audit says so and runs no LIO (its other tracks run);
    --no-lio's empty choice says none was asked for."""
    from recorded_runs import pillar_room, simulated_run

    room = pillar_room()
    folder, _ = simulated_run(
        tmp_path / "run", room, [(-3.0 + 0.4 * i, 0.0, 0.05 * i) for i in range(4)], [0.0, 0.1, 0.2, 0.3]
    )
    assert not has_imu(folder)
    config = configured(None, ("mde",), "the test", trials=1)
    result = audit_run(folder, room, "vlp16", config, every=4)
    assert result.lio_withheld == "the run has no IMU" and len(result.tracks) == 2
    assert result.records[0].lio_errors_m == () and result.to_dict()["lio_withheld"] == "the run has no IMU"
    none = audit_run(folder, room, "vlp16", config, every=4, lio=())
    assert none.lio_withheld == "none asked for"
    assert audit_run(folder, room, "vlp16", config, every=4, register=False).lio_withheld == "registrations left out"
