"""The localization error predicted along a trajectory on a SOLM: the fit's predictor, the
time mean of q_n along the trajectory (as the benefit study fitted it:
experiments/benefit/localization_error.py), read from the SOLM at the trajectory's samples.

Which fit: the one given (the prediction section's ``calibration``, a fit on a user's own
run from `lf3pm audit --calibrate`), else the one the SOLM was built with (`lf3pm solm build
--calibration` stores it), else the packaged one."""

from __future__ import annotations

import numpy as np

from lf3pm.calibration import FIT_CONDITIONS, localization_fit, predict, withheld_reason


def solm_fit(solm, path: str | None = None) -> dict | None:
    """The localization-error fit for predictions on ``solm``: the file at ``path``, else
    the SOLM's stored one, else the packaged one (None where none is shipped)."""
    if path is not None:
        return localization_fit(path)
    return solm.attrs.get("calibration") or localization_fit()


def predicted_error_along(solm, samples: dict, fit: dict | None) -> tuple[float | None, str | None]:
    """(error, withheld): the localization error (m) ``fit`` predicts along a trajectory's
    ``samples`` (x, y, yaw arrays evenly spaced in time, and z on an r3 or r3yaw SOLM: a
    flight's heights) from the time mean of ``solm``'s q_n over the samples where it is
    known; or None and why, in one line. A fit made for another sensor, association or w1
    than the SOLM's is withheld as `lf3pm evaluate` withholds it."""
    q_n = solm.query(samples["x"], samples["y"], yaw=samples["yaw"], z=samples.get("z"))[0]
    if np.isinf(q_n).any():
        return None, "the plan passes a degenerate pose (q_n infinite): localization follows the odometry there"
    known = q_n[np.isfinite(q_n)]
    if not known.size:
        return None, "the SOLM has no q_n along the plan"
    mean = float(np.mean(known))
    attrs = solm.attrs
    # A SOLM records its sensor, association and w1; it is built at the sensor's noise,
    # without scan downsampling, at dof 6.
    conditions = {**FIT_CONDITIONS, "sensor": attrs["sensor"], "association": attrs["association"], "w1": attrs["w1"]}
    withheld = withheld_reason(fit, mean, **conditions)
    if withheld is not None:
        return None, withheld
    return predict(fit, mean)[0], None
