"""The trajectory back end (the C++ trajectory/): a robot's kind and limits
(:class:`Robot`), piecewise-polynomial trajectories (:class:`Trajectory`, CSV at
100 Hz), MINCO + L-BFGS optimisation with penalties (:func:`optimize_trajectory`;
docs/planner_backend.md), and sampling a trajectory's poses (:func:`sample_trajectory`)."""

from lf3pm.trajectory.robots import Robot
from lf3pm.trajectory.sampling import interpolate_poses, sample_trajectory
from lf3pm.trajectory.trajectory import Trajectory
from lf3pm.trajectory.trajectory_optimizer import OptimizeResult, make_problem, optimize_trajectory

__all__ = [
    "OptimizeResult",
    "Robot",
    "Trajectory",
    "interpolate_poses",
    "make_problem",
    "optimize_trajectory",
    "sample_trajectory",
]
