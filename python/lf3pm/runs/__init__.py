"""Recorded runs, streamed (docs/runs.md): a folder of scans with a poses file (TUM, KITTI
or 4 x 4 matrices; lf3pm.io.run_folder), or a ROS 1 or ROS 2 bag (sqlite3, MCAP) with
PointCloud2 or Livox CustomMsg scans, an IMU and reference poses.

- :class:`Run` -- open a run; :meth:`Run.scans` yields :class:`Scan` one at a time with its
  reference pose interpolated on SE(3) (:class:`PoseTrack`), :meth:`Run.imu`
  :class:`ImuSample`; bad scans raise or are kept as :class:`BadScan`.
- :func:`run_info` -- what a run holds (``lf3pm run info``).
"""

from lf3pm.runs.info import run_info
from lf3pm.runs.records import BadScan, ImuSample, Scan
from lf3pm.runs.run import Run, lidar_to_body
from lf3pm.runs.trajectory import PoseTrack

__all__ = ["BadScan", "ImuSample", "PoseTrack", "Run", "Scan", "lidar_to_body", "run_info"]
