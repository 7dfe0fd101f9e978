"""Ground truth for the metric: how well registration actually recovers a pose.

- :func:`mde` -- the paper's MDE: mean squared error of point-to-plane ICP
  (small_gicp, independent of lf3pm's own code) started from disturbed poses.
- :func:`mde_along` -- MDE at every pose of a trajectory and S, their sum.
- :func:`replay` -- a planned trajectory (:class:`Motion`) replayed with
  simulated, motion-distorted scans through localization on the prior map,
  a LiDAR-inertial odometry or KISS-ICP, scored by evo's APE / RPE
  (:class:`ReplayResult`; docs/replay.md);
- :func:`replay_seeds` -- :func:`replay` on consecutive seeds, with the medians;
  :func:`replay_bag` -- the stream a replay simulates, as a ROS 2 bag;
- :func:`replay_odometry` -- KISS-ICP along a sampled trajectory (poses
  interpolated linearly), as the Gobi experiment uses it.
"""

from lf3pm.validation.mde import MdeResult, RegistrationTarget, mde
from lf3pm.validation.motion import Motion
from lf3pm.validation.odometry import replay_odometry
from lf3pm.validation.replay import replay, replay_bag, replay_seeds
from lf3pm.validation.replay_result import ReplayResult, ReplaySeries
from lf3pm.validation.trajectory import interpolate_poses, sample_trajectory
from lf3pm.validation.trajectory_mde import TrajectoryMde, mde_along, pose_seed

__all__ = ["MdeResult", "Motion", "RegistrationTarget", "ReplayResult", "ReplaySeries", "replay", "replay_bag",
           "replay_seeds", "TrajectoryMde", "interpolate_poses",
           "mde", "mde_along", "pose_seed", "replay_odometry", "sample_trajectory"]
