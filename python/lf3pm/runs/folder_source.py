"""A run recorded as a folder of scans with a poses file (lf3pm.io.run_folder, the one
reader of such folders), read one scan at a time."""

from __future__ import annotations

import warnings
from collections.abc import Iterator

import numpy as np

from lf3pm.errors import MapError, RunError
from lf3pm.io.run_folder import TIMES_FILE, open_run_folder
from lf3pm.runs.records import ImuSample


class FolderSource:
    """A run folder's scans (in the order of their times; a folder gives no per-point times)
    and poses; it has no IMU."""

    kind = "folder"

    def __init__(self, path):
        self.folder = open_run_folder(path)

    def close(self) -> None:
        """Nothing held open: a folder's files are opened per scan."""

    def describe(self) -> dict:
        """The folder's kind, its scans folder, poses file and times file (or None)."""
        times = self.folder.root / TIMES_FILE
        return {
            "kind": self.kind,
            "scans_folder": str(self.folder.scans[0].parent),
            "poses_file": str(self.folder.poses_file),
            "times_file": str(times) if times.is_file() else None,
        }

    def scan_names(self) -> list[str]:
        """The name each scan has (its file), without reading them."""
        return [str(path) for path in self.folder.scans]

    def raw_scans(self) -> Iterator[tuple[int, str, tuple | RunError]]:
        """(index, file, (stamp, points, None) or the RunError that scan is) per scan file."""
        from lf3pm.io import load_points

        for index, (stamp, path) in enumerate(zip(self.folder.times, self.folder.scans)):
            try:
                with warnings.catch_warnings():
                    # NaN points are dropped by the run as a bag's are, without a warning per scan.
                    warnings.simplefilter("ignore", UserWarning)
                    points = load_points(path)
            except MapError as err:
                yield index, str(path), RunError(str(err))
                continue
            yield index, str(path), (float(stamp), points, None)

    def imu(self) -> Iterator[ImuSample]:
        """A folder holds no IMU."""
        return iter(())

    def poses(self) -> tuple[np.ndarray, np.ndarray, str]:
        """(times, poses N x 4 x 4, the poses file) as the poses file gives them."""
        return self.folder.pose_times, self.folder.poses, str(self.folder.poses_file)
