"""One audited scan: what lf3pm predicts at its reference pose and how real registration went."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields

NAN = math.nan


@dataclass(frozen=True)
class ScanAudit:
    """The audit of one recorded scan at its reference pose (``pose``: world-from-LiDAR).

    ``real_*``: the metric of the recorded points against the map (lf3pm.metric.evaluate_points:
    FAST-LIO association, the code ``lf3pm evaluate`` runs on a simulated scan's hits);
    ``sim_*``: the metric of the sensor's simulated scan there (lf3pm.metric.evaluate), with
    ``q_n_ratio`` = sim_q_n / real_q_n; ``*_residual_rms_m``: the RMS point-to-plane misfit
    left after the least-squares step (residual_norm / sqrt(m)), the term that sets q_n
    beside sigma1; ``direction_angle_deg``: the angle between the real and the simulated
    least observable directions (0-90, sign-free); ``predicted_error_m`` and its [10 %, 90 %] interval:
    the predicted localization error ``lf3pm evaluate --json`` ships for that pose (None,
    with ``predicted_error_withheld`` saying why, where it is withheld); ``predicted_mde`` and
    its interval likewise: the expected MDE ``lf3pm evaluate`` ships (in ``mde``'s unit).

    Registration (lf3pm.validation.mde_of_points: ``lf3pm mde``'s starts and small_gicp
    point-to-plane ICP, on the recorded points): per start the translation error (m) and
    rotation error (deg) against the reference pose and whether it converged; over the
    converged starts ``error_m`` (the mean translation error: the real error against the
    reference), ``error_max_m``, ``rotation_error_deg`` (mean), ``rotation_error_max_deg``,
    and ``spread_m`` / ``spread_deg``: the RMS distance of the converged poses from their
    mean (translation; rotation from their chordal mean), which does not depend on the
    reference pose's own error. ``mde``: the mean squared twist error over every start, as
    ``lf3pm mde`` reports it. ``tracking_error_m`` and ``odometry_error_m``: at this scan,
    the error against the reference of map localization tracking along the whole run and of
    KISS-ICP along it (lf3pm.audit.tracks); ``lio_errors_m``: (odometry, error) for each
    LiDAR-inertial odometry along it (in the JSON, not the CSV). ``*_error`` fields (text)
    say why a part could not be computed.
    A quantity that could not be computed (a degenerate pose's q, no converged start) is NaN.
    """

    index: int
    name: str
    stamp: float
    time_s: float = NAN  # since the first scan audited
    x: float = NAN
    y: float = NAN
    z: float = NAN
    yaw: float = NAN
    points: int = 0
    hits: int = 0
    real_m: int = 0
    real_q_min: float = NAN
    real_q_n: float = NAN
    real_q_max: float = NAN
    real_sigma1: float = NAN
    real_degenerate: bool = False
    real_least_observable: tuple = ()
    real_residual_rms_m: float = NAN
    sim_hits: int = 0
    sim_m: int = 0
    sim_q_min: float = NAN
    sim_q_n: float = NAN
    sim_q_max: float = NAN
    sim_sigma1: float = NAN
    sim_degenerate: bool = False
    sim_least_observable: tuple = ()
    sim_residual_rms_m: float = NAN
    sim_error: str | None = None
    q_n_ratio: float = NAN
    direction_angle_deg: float = NAN
    predicted_error_m: float = NAN
    predicted_error_lo_m: float = NAN
    predicted_error_hi_m: float = NAN
    predicted_error_withheld: str | None = None
    predicted_mde: float = NAN
    predicted_mde_lo: float = NAN
    predicted_mde_hi: float = NAN
    predicted_mde_withheld: str | None = None
    starts: int = 0
    converged: int = 0
    translation_errors_m: tuple = ()
    rotation_errors_deg: tuple = ()
    converged_starts: tuple = ()
    mde: float = NAN
    error_m: float = NAN
    error_max_m: float = NAN
    rotation_error_deg: float = NAN
    rotation_error_max_deg: float = NAN
    spread_m: float = NAN
    spread_deg: float = NAN
    registration_error: str | None = None
    tracking_error_m: float = NAN
    odometry_error_m: float = NAN
    lio_errors_m: tuple = ()  # (odometry, error) per LiDAR-inertial odometry along the run
    metric_seconds: float = NAN
    registration_seconds: float = NAN
    pose: tuple = field(default=(), repr=False)  # 4 x 4 rows

    def to_dict(self) -> dict:
        """JSON-ready: tuples as lists, non-finite numbers as None."""
        return {k: _json(v) for k, v in asdict(self).items()}

    def row(self) -> dict:
        """The CSV row: every scalar field (lists and the 4 x 4 pose left out, the least
        observable directions as one column per entry)."""
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name.endswith("least_observable"):
                for i, v in enumerate(value):
                    out[f"{f.name}_{i}"] = v
            elif not isinstance(value, tuple):
                out[f.name] = value
        return out


def _json(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, (tuple, list)):
        return [_json(v) for v in value]
    return value


#: The CSV columns of a ScanAudit (least observable directions: six entries each).
def csv_columns() -> list[str]:
    out = []
    for f in fields(ScanAudit):
        if f.name.endswith("least_observable"):
            out += [f"{f.name}_{i}" for i in range(6)]
        elif f.type != "tuple":
            out.append(f.name)
    return out
