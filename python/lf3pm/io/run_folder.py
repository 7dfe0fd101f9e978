"""A recorded run as a folder of scans with their poses, and the map they make together.

    RUN/poses_tum.txt        one line per scan: time tx ty tz qx qy qz qw (TUM; '#' starts
                             a comment): the sensor's pose in the world, world = R p + t
    RUN/scans/<time>.pcd     the scan taken at that time, in the sensor frame (any point
                             file lf3pm reads), named by its time in seconds

``load_points(RUN)`` (lf3pm.io) reads such a folder as a map: every scan moved to the
world at its pose and the whole reduced to one point per voxel, so every command that
takes a map file takes a run folder too (``../shared/data/real_hall_run`` is one).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lf3pm.errors import MapError
from lf3pm.io.voxel import voxel_downsample

POSES_FILE = "poses_tum.txt"
SCANS_FOLDER = "scans"

#: The voxel (m) of a run's map when none is asked for: a run's scans overlap tens of
#: times over (real_hall_run: 88 scans, 6.9 M points, 1.2 M voxels at 5 cm); 5 cm keeps
#: surfaces far finer than the 0.5 m planes FAST-LIO's association fits to 5 map points.
RUN_MAP_VOXEL = 0.05

#: Scans gathered are reduced once they hold more points than this and the map so far.
GATHER_POINTS = 1_000_000

#: Two stamps closer than this (s) are the same: names keep 6 decimals.
_SAME_TIME = 5e-7

#: |q| may differ from 1 by this much (TUM files keep about 9 digits).
_UNIT_TOLERANCE = 1e-3


@dataclass(frozen=True)
class RunFolder:
    """A run folder's scans (paths, sorted by time), their times (s) and poses (N x 4 x 4)."""

    root: Path
    times: np.ndarray
    poses: np.ndarray
    scans: tuple[Path, ...]

    def __len__(self) -> int:
        return len(self.scans)

    def world_scans(self) -> Iterator[np.ndarray]:
        """Each scan's points in the world frame, one scan in memory at a time."""
        from lf3pm.io import load_points

        for path, pose in zip(self.scans, self.poses, strict=True):
            points = load_points(path)
            yield points @ pose[:3, :3].T + pose[:3, 3]


def is_run_folder(path) -> bool:
    """Whether ``path`` is a folder holding a poses file and a scans folder."""
    path = Path(path)
    return path.is_dir() and (path / POSES_FILE).is_file() and (path / SCANS_FOLDER).is_dir()


def open_run_folder(path) -> RunFolder:
    """The run folder ``path`` (the module's docstring), its poses checked: stamps strictly
    increasing, unit quaternions, finite; every scan with a pose at its time and every
    pose with its scan. Raises MapError in one line naming the file and line or scan."""
    root = Path(path)
    if not is_run_folder(root):
        raise MapError(f"{os.fspath(root)}: not a run folder (needs {POSES_FILE} and a {SCANS_FOLDER}/ folder)")
    times, poses = read_tum(root / POSES_FILE)
    scans = sorted((p for p in (root / SCANS_FOLDER).iterdir() if p.is_file()), key=lambda p: p.name)
    by_time = {}
    for scan in scans:
        try:
            stamp = float(scan.stem)
        except ValueError:
            raise MapError(f"{scan}: a scan's name is its time in seconds (e.g. 1630577758.569490.pcd)") from None
        by_time[scan] = stamp
    ordered = sorted(by_time, key=by_time.get)
    stamps = np.array([by_time[s] for s in ordered])
    if len(stamps) != len(times):
        which = "scans" if len(stamps) > len(times) else "poses"
        raise MapError(f"{root}: {len(stamps)} scans and {len(times)} poses; more {which} than the other")
    off = np.flatnonzero(np.abs(stamps - times) > _SAME_TIME)
    if off.size:
        i = int(off[0])
        raise MapError(f"{ordered[i]}: no pose at its time; the poses' line {i + 1} is at {times[i]:.6f} s")
    return RunFolder(root, times, poses, tuple(ordered))


def read_tum(path) -> tuple[np.ndarray, np.ndarray]:
    """(times (N,), poses (N x 4 x 4)) of a TUM file (time tx ty tz qx qy qz qw per line)."""
    from scipy.spatial.transform import Rotation

    rows, numbers = [], []
    with open(path, encoding="utf-8", errors="replace") as fp:
        for number, line in enumerate(fp, start=1):
            text = line.split("#", 1)[0].strip()
            if not text:
                continue
            fields = text.replace(",", " ").split()
            try:
                values = [float(v) for v in fields]
            except ValueError:
                values = []
            if len(values) != 8 or not all(math.isfinite(v) for v in values):
                raise MapError(f"{path}:{number}: a TUM line is 8 finite numbers (time tx ty tz qx qy qz qw)")
            norm = math.sqrt(sum(v * v for v in values[4:]))
            if abs(norm - 1.0) > _UNIT_TOLERANCE:
                raise MapError(f"{path}:{number}: the quaternion's norm is {norm:.6g}, not 1")
            rows.append(values)
            numbers.append(number)
    if not rows:
        raise MapError(f"{path}: no poses")
    data = np.array(rows)
    steps = np.flatnonzero(np.diff(data[:, 0]) <= 0)
    if steps.size:
        raise MapError(f"{path}:{numbers[int(steps[0]) + 1]}: time does not increase from the line before")
    poses = np.tile(np.eye(4), (len(data), 1, 1))
    poses[:, :3, :3] = Rotation.from_quat(data[:, 4:8]).as_matrix()
    poses[:, :3, 3] = data[:, 1:4]
    return data[:, 0], poses


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
