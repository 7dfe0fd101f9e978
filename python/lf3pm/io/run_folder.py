"""A recorded run as a folder of scans with their poses, and the map they make together.

    RUN/scans/<name>.pcd     one scan per file, in the sensor frame (any point file lf3pm
                             reads: PCD, PLY, NPY, ...), named by its time in seconds
                             (1630577758.569490.pcd), or by its index (000012.pcd) when
                             RUN/times.txt gives the times
    RUN/times.txt            optional: one time (s) per line, line i the time of scan i
                             and of pose i (KITTI's times.txt)
    RUN/poses_tum.txt        the poses, one of three forms: TUM (time tx ty tz qx qy qz qw
      or poses_kitti.txt     per line, at its own times), KITTI (a 3 x 4 row-major matrix,
      or poses_matrix.txt    12 numbers per line) or a 4 x 4 row-major matrix (16 numbers);
                             the last two at the times of times.txt. Each pose is the
                             tracked frame's (the sensor's, unless a LiDAR-to-body
                             extrinsic says otherwise) in the world: world = R p + t.
                             '#' starts a comment.

This is the one reader of run folders: :mod:`lf3pm.runs` streams such a folder's scans with
poses interpolated to their times, and ``load_points(RUN)`` (lf3pm.io) reads it as a map:
every scan moved to the world at its own pose (one pose per scan, at its time) and the whole
reduced to one point per voxel, so every command that takes a map file takes a run folder
too (``../shared/data/real_hall_run`` is one). Every problem is a RunError (a MapError) in
one line naming the file and line, or the scan.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lf3pm.errors import RunError
from lf3pm.io.voxel import voxel_downsample

SCANS_FOLDER = "scans"
TIMES_FILE = "times.txt"
#: The poses file's name for each form it may take.
POSES_FILES = {"tum": "poses_tum.txt", "kitti": "poses_kitti.txt", "matrix": "poses_matrix.txt"}
POSES_FILE = POSES_FILES["tum"]
#: Numbers per line of each form, and what the line is.
_FORMS = {
    "tum": (8, "time tx ty tz qx qy qz qw"),
    "kitti": (12, "a 3 x 4 row-major pose"),
    "matrix": (16, "a 4 x 4 row-major pose"),
}

#: The voxel (m) of a run's map when none is asked for: a run's scans overlap tens of
#: times over (real_hall_run: 88 scans, 6.9 M points, 1.2 M voxels at 5 cm); 5 cm keeps
#: surfaces far finer than the 0.5 m planes FAST-LIO's association fits to 5 map points.
RUN_MAP_VOXEL = 0.05

#: Scans gathered are reduced once they hold more points than this and the map so far.
GATHER_POINTS = 1_000_000

#: Two stamps closer than this (s) are the same: names keep 6 decimals.
_SAME_TIME = 5e-7

#: |q| may differ from 1, and a rotation matrix from orthonormal, by this much (pose files
#: keep about 9 digits).
_UNIT_TOLERANCE = 1e-3


@dataclass(frozen=True)
class RunFolder:
    """A run folder: its scans (paths, sorted by time) and their ``times`` (s), and its
    poses (``pose_times`` (M,), ``poses`` M x 4 x 4) as its poses file gives them."""

    root: Path
    times: np.ndarray
    scans: tuple[Path, ...]
    pose_times: np.ndarray
    poses: np.ndarray
    poses_file: Path

    def __len__(self) -> int:
        return len(self.scans)

    def scan_poses(self) -> np.ndarray:
        """One pose per scan, the one at its time (N x 4 x 4): what a map of the run is made
        at. RunError when scans and poses differ in number or a scan has no pose at its time."""
        if len(self.times) != len(self.pose_times):
            which = "scans" if len(self.times) > len(self.pose_times) else "poses"
            raise RunError(
                f"{self.root}: {len(self.times)} scans and {len(self.pose_times)} poses; more {which} than the other"
            )
        off = np.flatnonzero(np.abs(self.times - self.pose_times) > _SAME_TIME)
        if off.size:
            i = int(off[0])
            raise RunError(
                f"{self.scans[i]}: no pose at its time; the poses' line {i + 1} is at {self.pose_times[i]:.6f} s"
            )
        return self.poses

    def world_scans(self) -> Iterator[np.ndarray]:
        """Each scan's points in the world frame at its own pose, one scan in memory at a time."""
        from lf3pm.io import load_points

        for path, pose in zip(self.scans, self.scan_poses(), strict=True):
            points = load_points(path)
            yield points @ pose[:3, :3].T + pose[:3, 3]


def poses_files(path) -> list[Path]:
    """The poses files (POSES_FILES) in the folder ``path``."""
    return [Path(path) / name for name in POSES_FILES.values() if (Path(path) / name).is_file()]


def is_run_folder(path) -> bool:
    """Whether ``path`` is a folder holding a scans folder and a poses file."""
    path = Path(path)
    return path.is_dir() and (path / SCANS_FOLDER).is_dir() and bool(poses_files(path))


def open_run_folder(path) -> RunFolder:
    """The run folder ``path`` (the module's docstring), its files checked: one poses file;
    times strictly increasing; finite numbers; unit quaternions and rotations; each scan
    named by its time, or by an index into times.txt. Raises RunError in one line naming
    the file and line or scan."""
    root = Path(path)
    if not is_run_folder(root):
        raise RunError(
            f"{os.fspath(root)}: not a run folder (needs a {SCANS_FOLDER}/ folder and one of "
            f"{', '.join(POSES_FILES.values())})"
        )
    found = poses_files(root)
    if len(found) > 1:
        raise RunError(f"{root}: more than one poses file ({', '.join(p.name for p in found)}); keep one")
    poses_file = found[0]
    form = next(form for form, name in POSES_FILES.items() if name == poses_file.name)
    times_path = root / TIMES_FILE
    listed = read_times(times_path) if times_path.is_file() else None
    if form == "tum":
        pose_times, poses = read_tum(poses_file)
    else:
        if listed is None:
            raise RunError(f"{poses_file}: {form} poses have no times; put one per line in {times_path}")
        poses = read_matrices(poses_file, form)
        if len(poses) != len(listed):
            raise RunError(f"{poses_file}: {len(poses)} poses and {len(listed)} times in {TIMES_FILE}")
        pose_times = listed
    stamps = [(_scan_time(scan, listed, times_path), scan) for scan in sorted((root / SCANS_FOLDER).iterdir())]
    if not stamps:
        raise RunError(f"{root / SCANS_FOLDER}: no scans")
    stamps.sort(key=lambda pair: pair[0])
    return RunFolder(root, np.array([t for t, _ in stamps]), tuple(s for _, s in stamps), pose_times, poses, poses_file)


def _scan_time(scan: Path, listed: np.ndarray | None, times_path: Path) -> float:
    """A scan's time: its name, or the line of times.txt its name's index gives."""
    if listed is None:
        try:
            stamp = float(scan.stem)
        except ValueError:
            stamp = math.nan
        if not math.isfinite(stamp):
            raise RunError(f"{scan}: a scan's name is its time in seconds (e.g. 1630577758.569490.pcd)")
        return stamp
    if not scan.stem.isdigit():
        raise RunError(f"{scan}: with {times_path.name}, a scan's name is its index (e.g. 000012.pcd)")
    index = int(scan.stem)
    if index >= len(listed):
        raise RunError(f"{scan}: index {index}, but {times_path} has {len(listed)} times")
    return float(listed[index])


def _rows(path, width: int, what: str, noun: str = "poses") -> tuple[np.ndarray, list[int]]:
    """The lines of ``path`` (comments and blank lines aside) as rows of ``width`` finite
    numbers, with their line numbers."""
    rows, numbers = [], []
    with open(path, encoding="utf-8", errors="replace") as fp:
        for number, line in enumerate(fp, start=1):
            text = line.split("#", 1)[0].strip()
            if not text:
                continue
            try:
                values = [float(v) for v in text.replace(",", " ").split()]
            except ValueError:
                values = []
            if len(values) != width or not all(math.isfinite(v) for v in values):
                raise RunError(f"{path}:{number}: a line is {width} finite number{'s' * (width > 1)} ({what})")
            rows.append(values)
            numbers.append(number)
    if not rows:
        raise RunError(f"{path}: no {noun}")
    return np.array(rows), numbers


def _increasing(path, times: np.ndarray, numbers: list[int]) -> None:
    steps = np.flatnonzero(np.diff(times) <= 0)
    if steps.size:
        raise RunError(f"{path}:{numbers[int(steps[0]) + 1]}: time does not increase from the line before")


def read_times(path) -> np.ndarray:
    """The times (s) of a times file: one per line, strictly increasing."""
    data, numbers = _rows(path, 1, "a time in seconds", "times")
    _increasing(path, data[:, 0], numbers)
    return data[:, 0]


def read_tum(path) -> tuple[np.ndarray, np.ndarray]:
    """(times (N,), poses (N x 4 x 4)) of a TUM file (time tx ty tz qx qy qz qw per line)."""
    from scipy.spatial.transform import Rotation

    data, numbers = _rows(path, 8, _FORMS["tum"][1])
    for row, number in zip(data, numbers):
        norm = float(np.linalg.norm(row[4:]))
        if abs(norm - 1.0) > _UNIT_TOLERANCE:
            raise RunError(f"{path}:{number}: the quaternion's norm is {norm:.6g}, not 1")
    _increasing(path, data[:, 0], numbers)
    poses = np.tile(np.eye(4), (len(data), 1, 1))
    poses[:, :3, :3] = Rotation.from_quat(data[:, 4:8]).as_matrix()
    poses[:, :3, 3] = data[:, 1:4]
    return data[:, 0], poses


def read_matrices(path, form: str) -> np.ndarray:
    """The poses (N x 4 x 4) of a KITTI (``form`` "kitti": 3 x 4 row-major per line) or
    4 x 4 (``form`` "matrix") file; each rotation orthonormal, a 4 x 4's last row 0 0 0 1."""
    width, what = _FORMS[form]
    data, numbers = _rows(path, width, what)
    poses = np.tile(np.eye(4), (len(data), 1, 1))
    poses[:, : width // 4] = data.reshape(-1, width // 4, 4)
    for pose, number in zip(poses, numbers):
        if np.abs(pose[3] - (0, 0, 0, 1)).max() > 0:
            raise RunError(f"{path}:{number}: a 4 x 4 pose's last row is 0 0 0 1")
        rotation = pose[:3, :3]
        if np.abs(rotation @ rotation.T - np.eye(3)).max() > _UNIT_TOLERANCE or np.linalg.det(rotation) < 0:
            raise RunError(f"{path}:{number}: the rotation is not orthonormal and right-handed")
    return poses


def run_map(path, voxel: float | None = None) -> np.ndarray:
    """The map of the run folder ``path``: its scans in the world, one point per ``voxel``
    (default RUN_MAP_VOXEL). Memory stays at a few scans and the map: the scans gathered
    are reduced whenever they outgrow the map so far; a voxel's point is then the centroid
    of its points' partial centroids (within the voxel, as the single pass's is)."""
    voxel = RUN_MAP_VOXEL if voxel is None else voxel
    run = open_run_folder(path)
    reduced = np.empty((0, 3))
    gathered, size = [], 0
    for points in run.world_scans():
        gathered.append(voxel_downsample(points, voxel))
        size += len(gathered[-1])
        if size > max(len(reduced), GATHER_POINTS):
            reduced = voxel_downsample(np.concatenate([reduced, *gathered]), voxel)
            gathered, size = [], 0
    return voxel_downsample(np.concatenate([reduced, *gathered]), voxel)
