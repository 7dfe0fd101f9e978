"""Recorded runs (lf3pm.runs): folders in TUM, KITTI and 4 x 4 form, SE(3) interpolation
against a hand-made case, bad input in one line, lazy iteration, and `lf3pm run info`."""

from __future__ import annotations

import itertools
import json
import weakref

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

from lf3pm.cli import app
from lf3pm.config import RunConfig
from lf3pm.errors import RunError
from lf3pm.io.run_folder import POSES_FILES, SCANS_FOLDER, TIMES_FILE
from lf3pm.runs import PoseTrack, Run, run
from lf3pm.runs.records import ImuSample

TIMES = [100.0, 100.5, 101.0, 101.5]


def _poses(count: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    poses = np.tile(np.eye(4), (count, 1, 1))
    poses[:, :3, :3] = Rotation.from_rotvec(rng.normal(0, 0.7, (count, 3))).as_matrix()
    poses[:, :3, 3] = rng.normal(0, 3, (count, 3))
    return poses


def write_folder(root, form: str, *, by_index: bool, poses=None, times=TIMES, points=None) -> tuple:
    """A run folder in ``form`` (tum, kitti, matrix) with scans named by time or index."""
    poses = _poses(len(times)) if poses is None else poses
    rng = np.random.default_rng(1)
    (root / SCANS_FOLDER).mkdir(parents=True)
    scans = []
    for i, t in enumerate(times):
        scan = rng.normal(0, 4, (30 + i, 3)) if points is None else points[i]
        np.save(root / SCANS_FOLDER / (f"{i:06d}.npy" if by_index else f"{t:.6f}.npy"), scan)
        scans.append(scan)
    if by_index or form != "tum":
        (root / TIMES_FILE).write_text("".join(f"{t:.9f}\n" for t in times))
    if form == "tum":
        quats = Rotation.from_matrix(poses[:, :3, :3]).as_quat()
        lines = [f"{t:.9f} {' '.join(f'{v:.17g}' for v in (*p[:3, 3], *q))}" for t, p, q in zip(times, poses, quats)]
        poses = poses.copy()
        poses[:, :3, :3] = Rotation.from_quat(quats).as_matrix()  # what the file's quaternions give
    else:
        rows = poses[:, :3] if form == "kitti" else poses
        lines = [" ".join(f"{v:.17g}" for v in row.reshape(-1)) for row in rows]
    (root / POSES_FILES[form]).write_text("# a comment\n" + "\n".join(lines) + "\n")
    return scans, poses


@pytest.mark.parametrize("form, by_index", [("tum", False), ("tum", True), ("kitti", True), ("matrix", True)])
def test_a_folder_run_reads_its_scans_at_their_poses(tmp_path, form, by_index):
    """Each form gives the scans in time order with the pose written for each; the extrinsic
    (rpy in degrees) multiplies it on the right."""
    scans, poses = write_folder(tmp_path, form, by_index=by_index)
    with Run(tmp_path, RunConfig(lidar_translation=(1.0, 0.0, 0.0), lidar_rpy=(90.0, 0.0, 0.0))) as run:
        got = list(run.scans())
        assert run.describe()["poses_file"].endswith(POSES_FILES[form])
        assert list(run.imu()) == []
    extrinsic = np.array([[1, 0, 0, 1.0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
    assert [s.stamp for s in got] == TIMES
    for scan, points, pose in zip(got, scans, poses):
        np.testing.assert_array_equal(scan.points, points)
        assert scan.times is None
        np.testing.assert_allclose(scan.pose, pose @ extrinsic, rtol=0, atol=1e-12)


def test_tum_poses_at_other_times_are_interpolated(tmp_path):
    """Poses at 0.25 s steps, scans between them: each scan's pose is the track's at its time."""
    pose_times = np.arange(99.75, 102.0, 0.25)
    write_folder(tmp_path, "tum", by_index=True, poses=_poses(len(pose_times), 3), times=list(pose_times))
    # the same folder's scans retimed: times.txt for scans, the TUM file for poses
    (tmp_path / TIMES_FILE).write_text("".join(f"{t + 0.1:.9f}\n" for t in pose_times))
    with Run(tmp_path, RunConfig(max_pose_gap=0.3), skip_bad=True) as run:
        got = list(run.scans())
        track = run.reference
        assert [b.index for b in run.bad_scans] == [len(pose_times) - 1]  # past the last pose
    for scan in got:
        np.testing.assert_array_equal(scan.pose, track.at(scan.stamp))


def test_se3_interpolation_is_slerp_and_linear_translation():
    """A constant-rate turn about z with a constant-velocity translation: the midpoint and
    the quarter point are exact; a pose's own time is that pose; outside and across a long
    gap there is none."""
    poses = np.tile(np.eye(4), (3, 1, 1))
    poses[1, :3, :3] = Rotation.from_euler("z", 90, degrees=True).as_matrix()
    poses[1, :3, 3] = (2.0, 4.0, 6.0)
    poses[2, :3, 3] = (0.0, 0.0, 100.0)
    track = PoseTrack([0.0, 2.0, 10.0], poses, max_gap=5.0, name="hand-made")
    for t, yaw in ((1.0, 45.0), (0.5, 22.5)):
        want = np.eye(4)
        want[:3, :3] = Rotation.from_euler("z", yaw, degrees=True).as_matrix()
        want[:3, 3] = np.array([2.0, 4.0, 6.0]) * t / 2
        np.testing.assert_allclose(track.at(t), want, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(track.at(2.0), poses[1])
    with pytest.raises(RunError, match=r"no pose at 10.500000 s: hand-made span 0.000000 to 10.000000 s"):
        track.at(10.5)
    with pytest.raises(RunError, match=r"no pose from 2.000000 to 10.000000 s, 8.000 s, longer than max_pose_gap 5 s"):
        track.at(3.0)
    with pytest.raises(RunError, match="pose 1 at 0.000000000 s is not after pose 0"):
        PoseTrack([0.0, 0.0], poses[:2], max_gap=1.0)


@pytest.mark.parametrize(
    "form, edit, message",
    [
        ("tum", lambda t: t.replace("100.500000000 ", "100.500000000 x", 1), r"poses_tum.txt:3: a line is 8 finite"),
        ("tum", lambda t: t.replace("100.500000000 ", "99.000000000 ", 1), r"poses_tum.txt:3: time does not increase"),
        ("kitti", lambda t: t + "1 2 3\n", r"poses_kitti.txt:6: a line is 12 finite numbers \(a 3 x 4"),
        ("matrix", lambda t: t + " ".join(["1"] * 16) + "\n", r"poses_matrix.txt:6: a 4 x 4 pose's last row"),
        ("kitti", lambda t: t + " ".join(["2"] * 12) + "\n", r"poses_kitti.txt:6: the rotation is not orthonormal"),
    ],
)
def test_bad_pose_lines_fail_in_one_line(tmp_path, form, edit, message):
    write_folder(tmp_path, form, by_index=form != "tum")
    poses = tmp_path / POSES_FILES[form]
    poses.write_text(edit(poses.read_text()))
    with pytest.raises(RunError, match=message) as err:
        Run(tmp_path).reference  # noqa: B018
    assert "\n" not in str(err.value)


def test_bad_folders_fail_in_one_line(tmp_path):
    write_folder(tmp_path / "a", "kitti", by_index=True)
    (tmp_path / "a" / TIMES_FILE).unlink()
    with pytest.raises(RunError, match="kitti poses have no times; put one per line in"):
        Run(tmp_path / "a")
    write_folder(tmp_path / "b", "tum", by_index=True)
    np.save(tmp_path / "b" / SCANS_FOLDER / "000009.npy", np.ones((3, 3)))
    with pytest.raises(RunError, match=r"000009.npy: index 9, but .*times.txt has 4 times"):
        Run(tmp_path / "b")
    write_folder(tmp_path / "c", "tum", by_index=False)
    (tmp_path / "c" / POSES_FILES["kitti"]).write_text("")
    with pytest.raises(RunError, match="more than one poses file"):
        Run(tmp_path / "c")
    with pytest.raises(RunError, match="not a run"):
        Run(tmp_path)


def test_a_bad_scan_file_is_skipped_with_its_line(tmp_path):
    """NaN-only and empty scans: each one line naming its file; the run goes on past them."""
    points = [np.ones((3, 3)), np.full((3, 3), np.nan), np.ones((3, 3)), np.zeros((3, 3))]
    write_folder(tmp_path, "tum", by_index=False, points=points)
    with Run(tmp_path, skip_bad=True) as run:
        assert [s.index for s in run.scans()] == [0, 2]
        reasons = [b.reason for b in run.bad_scans]
    assert reasons[0].endswith("100.500000.npy: no finite points (all 3 have a NaN or infinite coordinate)")
    assert reasons[1].endswith("101.500000.npy: no usable point (all 3 are NaN or at the origin)")
    with pytest.raises(RunError, match="100.500000.npy: no finite points"):
        list(Run(tmp_path).scans())


class _EndlessSource:
    """A source of endless scans of 1000 points, each array watched by a weak reference."""

    kind = "endless"

    def __init__(self):
        self.refs = []

    @property
    def alive(self) -> int:
        return sum(ref() is not None for ref in self.refs)

    def raw_scans(self):
        for index in itertools.count():
            points = np.ones((1000, 3))
            self.refs.append(weakref.ref(points))
            yield index, f"scan {index}", (float(index), points, None)

    def imu(self):
        return iter([ImuSample(0.0, np.zeros(3), np.zeros(3))])

    def poses(self):
        return None

    def close(self):
        pass


def test_scans_are_read_lazily_and_let_go(tmp_path, monkeypatch):
    """An endless run yields its scans one at a time: no scan is read ahead, and while
    a thousand go by at most two are alive (the one yielded and the one being read)."""
    source = _EndlessSource()
    monkeypatch.setattr(run, "open_source", lambda path, config: source)
    most, last = 0, None
    for scan in itertools.islice(Run(tmp_path).scans(), 1000):
        most, last = max(most, source.alive), scan.index
    assert last == 999 and most <= 2


def test_run_info_reports_a_folder_run(tmp_path):
    write_folder(tmp_path, "tum", by_index=False)
    done = CliRunner().invoke(app, ["run", "info", str(tmp_path), "--json"])
    assert done.exit_code == 0, done.output
    info = json.loads(done.output)
    assert info["scans"] == 4 and info["points_per_scan"] == {"min": 30, "median": 31.5, "max": 33}
    assert info["point_times"] == "none" and info["imu"]["samples"] == 0
    assert info["poses"]["count"] == 4 and info["poses"]["span"]["duration_s"] == 1.5
    text = CliRunner().invoke(app, ["run", "info", str(tmp_path)])
    assert text.exit_code == 0 and "scans: 4, 100.000000 to 101.500000 s (1.500 s)" in text.output


def test_run_info_refuses_bad_input_in_one_line(tmp_path):
    for args in ([str(tmp_path / "none")], [str(tmp_path)], [str(tmp_path), "--max-pose-gap", "-1"]):
        done = CliRunner().invoke(app, ["run", "info", *args])
        assert done.exit_code == 2 and len(done.output.strip().splitlines()) == 1, done.output


def test_run_info_on_the_real_hall_run():
    """The real hall run (../shared/data/real_hall_run, GPL data read in place): 88 scans
    over 43.5 s, each at its own TUM pose, no per-point times, no IMU."""
    from shared_data import shared_file

    root = shared_file("real_hall_run/poses_tum.txt").parent
    done = CliRunner().invoke(app, ["run", "info", str(root), "--json"])
    assert done.exit_code == 0, done.output
    info = json.loads(done.output)
    assert info["scans"] == 88 and info["bad_scans"] == []
    assert info["poses"]["count"] == 88
    assert info["poses"]["span"]["first_s"] == pytest.approx(1630577758.569490, abs=1e-6)
    assert info["poses"]["span"]["last_s"] == pytest.approx(1630577802.068132, abs=1e-6)
    assert info["scans_span"] == info["poses"]["span"]
    assert info["point_times"] == "none" and info["imu"]["samples"] == 0
