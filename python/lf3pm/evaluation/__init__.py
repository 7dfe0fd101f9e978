"""Ground truth for the metric: how well registration actually recovers a pose.

- :func:`mde` -- the paper's MDE: mean squared error of point-to-plane ICP
  (small_gicp, independent of lf3pm's own code) started from disturbed poses.
"""

from lf3pm.evaluation.mde import MdeResult, RegistrationTarget, mde

__all__ = ["MdeResult", "RegistrationTarget", "mde"]
