"""Replays of planned trajectories (docs/replay.md; plural: :func:`lf3pm.replay` is the
function): a trajectory as a continuous :class:`Motion` over the map's ground (or a
quadrotor's :class:`FlightMotion`, its LiDAR at the flatness map's attitude), the
simulated stream (scans, IMU) along it, and a state estimator on it, a replay method
(methods.py: localization on the prior map, localization.py; a LiDAR-inertial odometry,
lio.py, one of registry.py's; KISS-ICP, odometry.py), scored by evo's APE / RPE
(:class:`ReplayResult`).

- :func:`replay` one seed; :func:`replay_seeds` consecutive seeds with the medians;
  :func:`replay_bag` the simulated stream as a ROS 2 bag;
- :func:`replay_odometry` KISS-ICP along a sampled trajectory (poses interpolated
  linearly), as the Gobi experiment uses it.
"""

from lf3pm.replays.flight_motion import FlightMotion
from lf3pm.replays.motion import Motion
from lf3pm.replays.odometry import replay_odometry
from lf3pm.replays.replay import replay, replay_bag, replay_seeds
from lf3pm.replays.replay_result import ReplayResult, ReplaySeries

__all__ = [
    "FlightMotion",
    "Motion",
    "ReplayResult",
    "ReplaySeries",
    "replay",
    "replay_bag",
    "replay_odometry",
    "replay_seeds",
]
