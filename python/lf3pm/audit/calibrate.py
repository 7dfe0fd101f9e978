"""The predicted localization error calibrated on a user's own recorded run (issue 42, item
5; ``lf3pm audit --calibrate``): the shipped fit's slope kept, its offset and interval
refitted so that the q_n of the simulated scan at each scan's reference pose (what
``lf3pm evaluate``, a SOLM and a plan compute for that sensor) predicts the run's real
error there; validated by leaving out contiguous segments of the run
(lf3pm.calibration.calibrate_factor). The file it writes is what the prediction
section's ``calibration`` (``--calibration``) reads."""

from __future__ import annotations

from lf3pm import __version__
from lf3pm.audit.run_audit import RunAudit
from lf3pm.audit.summary import REAL_ERRORS
from lf3pm.calibration import calibrate_factor
from lf3pm.config import Config
from lf3pm.errors import Lf3pmError

#: The real errors a run can be calibrated on: the localization error the shipped fit
#: predicts is map localization's, so the default is the tracking error along the run.
CALIBRATION_ERRORS = ("tracking_error_m", "error_m", "spread_m")
DEFAULT_CALIBRATION_ERROR = CALIBRATION_ERRORS[0]


def calibrate_run(
    audit: RunAudit, base: dict, config: Config, *, against: str = DEFAULT_CALIBRATION_ERROR, command: str = ""
) -> dict:
    """``base`` (a localization-error fit) recalibrated on ``audit``'s scans: sim_q_n against
    the real error ``against`` (one of :data:`CALIBRATION_ERRORS`), under the scan and
    metric settings of ``config`` the audit ran with (recorded as the fit's conditions).
    Lf3pmError in one line when the audit lacks that error or has too few scans."""
    if against not in CALIBRATION_ERRORS:
        raise Lf3pmError(f"--calibrate-on must be one of {', '.join(CALIBRATION_ERRORS)}, got {against!r}")
    records = audit.records
    if not any(getattr(r, against) == getattr(r, against) for r in records):  # all NaN
        raise Lf3pmError(
            f"cannot calibrate on {against}: the audit has none (tracking_error_m needs the tracks, "
            "error_m and spread_m the registrations)"
        )
    metric = config.metric
    return calibrate_factor(
        base,
        [r.sim_q_n for r in records],
        [getattr(r, against) for r in records],
        provenance={
            "command": command,
            "run": audit.run,
            "map": audit.map,
            "sensors": [audit.sensor],
            "predictor": "q_n of the simulated scan at each scan's reference pose",
            "error": f"{against}: {REAL_ERRORS[against]}",
            "base": base["provenance"].get("command", ""),
            "base_a": base["a"],
            "w1": metric.w1,
            "conditions": {
                "dof": metric.dof,
                "association": metric.association,
                "scan_voxel": config.scan.scan_voxel,
                "noise_is_default": config.scan.noise is None,
            },
            "lf3pm_version": __version__,
        },
    )
