"""Planning on a SOLM: trajectory optimisation (MINCO + L-BFGS + PHR back end).

- :class:`Robot` -- robot kind (omni, diff, car) and its limits.
- :class:`GridField` -- a cost map or ESDF on a regular grid (optional periodic yaw).
- :func:`optimize_trajectory` -- front-end waypoints to an optimised :class:`Trajectory`.
"""

from lf3pm.planner.grid import GridField
from lf3pm.planner.optimizer import OptimizeResult, make_problem, optimize_trajectory
from lf3pm.planner.robots import Robot
from lf3pm.planner.trajectory import Trajectory

__all__ = ["GridField", "OptimizeResult", "Robot", "Trajectory", "make_problem", "optimize_trajectory"]
