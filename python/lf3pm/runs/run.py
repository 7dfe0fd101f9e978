"""A recorded run, streamed: its scans with their reference poses, its IMU samples."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from lf3pm.config import DEFAULTS, RunConfig
from lf3pm.errors import RunError
from lf3pm.runs.records import BadScan, ImuSample, Scan
from lf3pm.runs.trajectory import PoseTrack


def lidar_to_body(config: RunConfig) -> np.ndarray:
    """The body-from-LiDAR transform (4 x 4) of the configuration's extrinsic."""
    from scipy.spatial.transform import Rotation

    pose = np.eye(4)
    if config.lidar_quaternion is not None:
        pose[:3, :3] = Rotation.from_quat(config.lidar_quaternion).as_matrix()
    elif config.lidar_rpy is not None:
        pose[:3, :3] = Rotation.from_euler("xyz", config.lidar_rpy, degrees=True).as_matrix()
    pose[:3, 3] = config.lidar_translation
    return pose


def open_source(path: Path, config: RunConfig):
    """The source that reads ``path``: a bag (ROS 1 or 2) or a run folder."""
    from lf3pm.io.run_folder import is_run_folder
    from lf3pm.runs.bag_source import BagSource, is_bag
    from lf3pm.runs.folder_source import FolderSource

    if is_bag(path):
        return BagSource(path, config.scans_topic, config.imu_topic, config.poses_topic)
    if is_run_folder(path):
        return FolderSource(path)
    if not path.exists():
        raise RunError(f"{path}: no such file or folder")
    raise RunError(
        f"{path}: not a run (a folder with scans/ and a poses file, a ROS 1 .bag, or a ROS 2 bag folder "
        "with its metadata.yaml)"
    )


class Run:
    """A recorded run (docs/runs.md): a folder of scans with a poses file, or a ROS 1 or
    ROS 2 bag, read as the ``run`` section of the configuration says (topics, the
    LiDAR-to-body extrinsic, the LiDAR's time offset, the longest pose gap).

    :meth:`scans` yields the scans in the order recorded, one decoded at a time, so memory
    stays at a few scans whatever the run's length; :meth:`imu` the IMU samples;
    :attr:`reference` holds the reference poses (world-from-body: the frame the poses
    track; for a folder whose poses are the sensor's, the LiDAR with the default identity
    extrinsic). A bad scan (no points, no pose at its time, a stamp not after the last,
    a field missing) raises a RunError in one line naming it, or with ``skip_bad`` is
    skipped and kept in :attr:`bad_scans` with that line. Use it as a context manager, or
    :meth:`close` it (a bag stays open while it is read)."""

    def __init__(self, source=None, config: RunConfig = DEFAULTS.run, *, skip_bad: bool = False):
        path = source if source is not None else config.source
        if path is None:
            raise RunError("no run given: pass its path (or set run.source)")
        self.path = Path(path)
        self.config = config
        self.skip_bad = skip_bad
        self.body_from_lidar = lidar_to_body(config)
        self.bad_scans: list[BadScan] = []
        self.source = open_source(self.path, config)
        self._reference: PoseTrack | None = None
        self._read_poses = False

    def __enter__(self) -> Run:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Closes the bag (a folder holds nothing open)."""
        self.source.close()

    def describe(self) -> dict:
        """What the source is: its kind and, for a bag, its topics and those read."""
        return {"path": str(self.path), **self.source.describe()}

    def scan_names(self) -> list[str]:
        """The name of each of the run's scans in order, bad ones counted, without reading
        them: a folder's scan files, a bag's "<scans topic> message <i>" (:attr:`Scan.name`)."""
        return self.source.scan_names()

    def scan_count(self) -> int:
        """The run's scans without reading them (bad ones counted)."""
        return len(self.scan_names())

    @property
    def reference(self) -> PoseTrack | None:
        """The reference poses (world-from-body), read on first use; None when the run has none."""
        if not self._read_poses:
            got = self.source.poses()
            self._reference = None if got is None else PoseTrack(*got[:2], self.config.max_pose_gap, got[2])
            self._read_poses = True
        return self._reference

    def pose_at(self, t: float) -> np.ndarray:
        """The reference pose (world-from-body, 4 x 4) at time ``t`` (s), interpolated on
        SE(3); RunError where there is none (outside the poses, in a long gap, no poses)."""
        if self.reference is None:
            raise RunError(f"{self.path}: the run has no reference poses")
        return self.reference.at(t)

    def lidar_pose_at(self, t: float) -> np.ndarray:
        """World-from-LiDAR (4 x 4) at time ``t``: the reference pose times the extrinsic."""
        return self.pose_at(t) @ self.body_from_lidar

    def scans(self) -> Iterator[Scan]:
        """The scans (:class:`lf3pm.runs.Scan`) in the order recorded, each with its pose
        when the run has poses. Restarts :attr:`bad_scans`."""
        self.bad_scans = []
        offset = self.config.lidar_time_offset
        reference = self.reference  # unreadable poses fail the run, not each scan
        previous = -np.inf
        for index, name, got in self.source.raw_scans():
            try:
                if isinstance(got, RunError):
                    raise got
                stamp, points, times = got
                stamp += offset
                if not stamp > previous:
                    raise RunError(f"{name}: stamp {stamp:.9f} s is not after the previous scan's {previous:.9f} s")
                keep = np.isfinite(points).all(axis=1) & points.any(axis=1)
                if not keep.any():
                    what = f"all {len(points)} are NaN or at the origin" if len(points) else "it holds none"
                    raise RunError(f"{name}: no usable point ({what})")
                pose = None
                if reference is not None:
                    try:
                        pose = reference.at(stamp) @ self.body_from_lidar
                    except RunError as err:
                        raise RunError(f"{name}: {err}") from None
                previous = stamp
            except RunError as err:
                if not self.skip_bad:
                    raise
                self.bad_scans.append(BadScan(index, name, str(err)))
                continue
            if not keep.all():
                points = points[keep]
                times = None if times is None else times[keep]
            yield Scan(index, name, stamp, np.ascontiguousarray(points), times, pose)

    def imu(self) -> Iterator[ImuSample]:
        """The IMU samples in the order recorded (none for a run without an IMU)."""
        return self.source.imu()
