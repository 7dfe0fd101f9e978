"""The lio replay method and the CLI's --bag, against a stand-in IMU simulation and
odometry (the real ones: lf3pm.replays.imu.simulate_imu, lf3pm.replays.lio.run_lio):
what they are given, what the result keeps, and the bag they feed."""

import json
import sys
from dataclasses import dataclass, field

import numpy as np
import pytest
from rosbags.rosbag2 import Reader
from typer.testing import CliRunner

import lf3pm
from lf3pm.cli import app
from lf3pm.config import DEFAULTS
from lf3pm.errors import Lf3pmError
from lf3pm.replays import lio
from lf3pm.replays.motion import Motion
from lf3pm.replays.replay import replay, replay_rest
from lf3pm.scenes import build_scene


@dataclass(frozen=True)
class FakeImu:
    t: np.ndarray
    accel: np.ndarray
    gyro: np.ndarray


@dataclass(frozen=True)
class FakeEstimate:
    times: np.ndarray
    poses: np.ndarray
    package: str = "fake-lio"
    version: str = "9.9"
    lost_track: bool = False
    skipped: list = field(default_factory=list)
    per_scan_inliers: np.ndarray = field(default_factory=lambda: np.arange(3))


calls = {}


def simulate_imu(motion, *, rate=200.0, preset="fake", seed=0, noise=True):
    calls["imu"] = {"rate": rate, "seed": seed, "noise": noise}
    t = np.arange(motion.t0, motion.t1 + 1e-9, 1.0 / rate)
    return FakeImu(t=t, accel=np.tile([0.0, 0.0, 9.81], (len(t), 1)), gyro=np.zeros((len(t), 3)))


class Clock:
    """A stand-in for time.perf_counter that moves only when told to."""

    now = 0.0

    @classmethod
    def perf_counter(cls):
        return cls.now


#: Seconds the stand-in clock moves per scan simulated, and per scan the fake LIO estimates.
SIMULATE_S, ESTIMATE_S = 2.0, 0.5


#: How far the fake LIO's estimate moves along x per scan (m), the rest's scans included.
DRIFT_PER_SCAN = 0.001


def run_lio(scans, imu, sensor, *, initial_pose, **params):
    """Consumes every scan (each taking ESTIMATE_S on the stand-in clock besides its
    simulation); returns the truth shifted along x by DRIFT_PER_SCAN per scan."""
    calls["lio"] = {"params": params, "initial_pose": initial_pose, "imu_samples": len(imu.t)}
    ends = []
    for scan in scans:
        ends.append(scan.end)
        Clock.now += ESTIMATE_S
    ends = np.array(ends)
    poses = scans.truth.copy()
    poses[:, 0, 3] += DRIFT_PER_SCAN * np.arange(len(poses))
    return FakeEstimate(times=ends, poses=poses, skipped=[3, len(ends) - 2])


@pytest.fixture
def fake_lio(monkeypatch):
    """The lio method (lf3pm.replays.lio.Lio) with the stand-in IMU and odometry."""
    monkeypatch.setattr(lio, "simulate_imu", simulate_imu)
    monkeypatch.setattr(lio, "run_lio", run_lio)
    calls.clear()
    # Simulating a scan takes SIMULATE_S on the stand-in clock, which the stream and the
    # lio method read.
    scans_module = sys.modules["lf3pm.scan.scans"]
    for module in (scans_module, lio):
        monkeypatch.setattr(module, "time", Clock)
    for name in ("simulate_moving_scan", "simulate_scan"):
        monkeypatch.setattr(scans_module, name, _taking(getattr(scans_module, name)))


def _taking(simulate):
    def timed(*args, **kwargs):
        Clock.now += SIMULATE_S
        return simulate(*args, **kwargs)

    return timed


@pytest.fixture(scope="module")
def boxes():
    world = lf3pm.load_map(build_scene("boxes").points)
    t = np.linspace(0.0, 1.0, 101)
    return world, Motion.from_arrays(t, -2 + 0.8 * t, 0 * t, 0 * t, map=world)


def test_lio_dispatch(fake_lio, boxes):
    world, motion = boxes
    result = replay(world, motion, "vlp16", "lio", seed=7, imu_rate=100.0, window=3)
    assert calls["imu"] == {"rate": 100.0, "seed": 7, "noise": True}
    # The IMU covers the rest the LIO gets before the motion (replay.rest) and the 1 s of motion.
    assert calls["lio"]["params"] == {"window": 3}
    assert calls["lio"]["imu_samples"] == round(DEFAULTS.replay.rest * 100.0) + 101
    np.testing.assert_array_equal(calls["lio"]["initial_pose"], result.truth[0])
    # Scored from the trajectory's start, re-anchored there: the drift counts from that scan.
    drift = 0.001 * np.arange(len(result.truth))
    assert result.method == "lio" and result.ape["rmse"] == pytest.approx(np.sqrt(np.mean(drift**2)))
    # Scan 3 lies in the rest, the one before last in the trajectory: indices count from its start.
    assert result.skipped == [len(result.truth) - 2] and result.versions["fake-lio"] == "9.9"
    assert result.report["lost_track"] is False and result.hits.min() > 1000
    # The simulation inside run_lio is counted as simulation, not as estimation.
    assert result.seconds_per_scan == pytest.approx({"simulate": SIMULATE_S, "estimate": ESTIMATE_S})
    assert result.params["lio"]["options"] == {"window": 3}
    assert json.loads(json.dumps(result.to_dict()))["report"]["per_scan_inliers"] == [0, 1, 2]


def test_cli_bag_and_lio(fake_lio, boxes, tmp_path):
    world, _ = boxes
    np.save(tmp_path / "boxes.npy", world.points)
    csv = tmp_path / "traj.csv"
    t = np.linspace(0.0, 1.0, 101)
    rows = np.column_stack([t, -2 + 0.8 * t, 0 * t, 0 * t, np.full_like(t, 0.8), 0 * t, 0 * t])
    np.savetxt(csv, rows, delimiter=",", header="t,x,y,yaw,vx,vy,omega", comments="")
    bag = tmp_path / "out.bag"
    done = CliRunner().invoke(
        app, ["replay", str(csv), "--map", str(tmp_path / "boxes.npy"), "--method", "lio", "--bag", str(bag), "--json"]
    )
    assert done.exit_code == 0, done.output
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["runs"][0]["method"] == "lio" and out["bag"]["topics"]["/points"] == 11
    with Reader(bag) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    assert counts == {"/points": 11, "/imu": 201, "/ground_truth": 101, "/tf": 101, "/tf_static": 1}


@pytest.mark.slow
@pytest.mark.parametrize("per_scan, steady", [(0.001, True), (0.01, False)])
def test_the_rest_reports_what_the_odometry_did_while_the_sensor_stood_still(
    fake_lio, boxes, monkeypatch, tmp_path, per_scan, steady
):
    """The estimate moving per_scan m every 0.1 s scan of the 2 s rest: drift 20 per_scan
    at the rest's end, speed 10 per_scan m/s (0.01 m/s: steady; 0.1 m/s: above
    the replay section's rest_speed_limit), and the CLI warns about the second only; a
    limit set in the section judges the rest by it."""
    monkeypatch.setattr(sys.modules[__name__], "DRIFT_PER_SCAN", per_scan)
    world, motion = boxes
    result = replay(world, motion, "vlp16", "lio", seed=0)
    scans = round(DEFAULTS.replay.rest * 10)
    assert result.rest["drift_m"] == pytest.approx(per_scan * scans)
    assert result.rest["speed_mps"] == pytest.approx(per_scan * 10)
    assert result.rest["steady"] is steady and (per_scan * 10 <= DEFAULTS.replay.rest_speed_limit) is steady
    lenient = replay(world, motion, "vlp16", "lio", seed=0, rest_speed_limit=1.0)
    assert lenient.rest["steady"] and lenient.rest["speed_mps"] == result.rest["speed_mps"]
    assert json.loads(json.dumps(result.to_dict()))["rest"] == result.rest
    assert replay(world, motion, "vlp16", "localization", seed=0).rest == {}  # no rest there
    assert replay_rest(world, motion, "vlp16", seed=0) == result.rest
    with pytest.raises(Lf3pmError, match="needs a rest"):
        replay_rest(world, motion, "vlp16", rest=0.0)

    np.save(tmp_path / "boxes.npy", world.points)
    csv = tmp_path / "traj.csv"
    t = np.linspace(0.0, 1.0, 101)
    rows = np.column_stack([t, -2 + 0.8 * t, 0 * t, 0 * t, np.full_like(t, 0.8), 0 * t, 0 * t])
    np.savetxt(csv, rows, delimiter=",", header="t,x,y,yaw,vx,vy,omega", comments="")
    done = CliRunner().invoke(app, ["replay", str(csv), "--map", str(tmp_path / "boxes.npy"), "--method", "lio"])
    assert done.exit_code == 0, done.output
    text = " ".join(done.output.split())
    assert f"seed 0 {1000 * per_scan * scans:.0f} mm" in text
    assert ("entered the trajectory with a velocity error" in text) is not steady
