"""Ground truth for the metric: how well registration actually recovers a pose.

- :func:`mde` -- the paper's MDE: mean squared error of point-to-plane ICP
  (small_gicp, independent of lf3pm's own code) started from disturbed poses
  (:class:`RegistrationTarget`: the map prepared for it once); :func:`mde_of_points`
  the same registrations of a recorded scan's points.
- :func:`mde_along` -- MDE at every pose of a trajectory and S, their sum.
"""

from lf3pm.validation.mde import MdeResult, RegistrationTarget, mde, mde_of_points
from lf3pm.validation.trajectory_mde import TrajectoryMde, mde_along, pose_seed

__all__ = ["MdeResult", "RegistrationTarget", "TrajectoryMde", "mde", "mde_along", "mde_of_points", "pose_seed"]
