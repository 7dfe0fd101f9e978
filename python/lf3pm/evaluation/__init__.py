"""Ground truth for the metric: how well registration actually recovers a pose.

- :func:`mde` -- the paper's MDE: mean squared error of point-to-plane ICP
  (small_gicp, independent of lf3pm's own code) started from disturbed poses.
- :func:`mde_along` -- MDE at every pose of a trajectory and S, their sum.
- :func:`replay_odometry` -- simulated scans along a trajectory through KISS-ICP,
  with APE / RPE against the truth (docs/odometry_replay.md); the scans are
  motion-distorted (moving_scan.py) unless asked otherwise.
"""

from lf3pm.evaluation.mde import MdeResult, RegistrationTarget, mde
from lf3pm.evaluation.odometry import replay_odometry
from lf3pm.evaluation.replay_result import ReplayResult
from lf3pm.evaluation.trajectory import interpolate_poses, sample_trajectory
from lf3pm.evaluation.trajectory_mde import TrajectoryMde, mde_along, pose_seed

__all__ = ["MdeResult", "RegistrationTarget", "ReplayResult", "TrajectoryMde", "interpolate_poses",
           "mde", "mde_along", "pose_seed", "replay_odometry", "sample_trajectory"]
