"""Predictions only inside the support of their fit: the range of the predictor the fit
saw. Outside it the prediction is None (null in JSON) and `lf3pm evaluate` says why."""

import json
import subprocess
import sys

import numpy as np
import pytest
from analytic_scenes import box_room, grid_plane
from shared_data import shared_file

import lf3pm
from lf3pm.calibration import (
    LOCALIZATION_PACKAGED,
    PACKAGED,
    fit_on_q_n,
    packaged_calibration,
    predict,
    support,
    withheld_reason,
)
from lf3pm.io import write_points

#: calibration_applies' keywords for a query made as the shipped localization fit was.
FIT_CONDITIONS = {
    "sensor": "mid70",
    "dof": 6,
    "association": "knn",
    "scan_voxel": 0.0,
    "noise_is_default": True,
    "w1": 0.5,
}


def test_the_localization_fit_stores_its_support_and_predicts_only_inside_it():
    rng = np.random.default_rng(2)
    q = np.exp(rng.uniform(-5, 0, 120))
    ape = 0.1 * q * np.exp(rng.normal(scale=0.3, size=120))
    fit = fit_on_q_n(np.repeat(["a", "b", "c"], 40), q, ape, provenance={"sensors": ["mid70"], "w1": 0.5})
    assert support(fit) == (q.min(), q.max())  # the samples' own values, not a log round trip
    assert predict(fit, q.min()) is not None
    assert predict(fit, q.max()) is not None
    for outside in (q.min() * 0.99, q.max() * 1.01, 0.0, np.inf, np.nan):
        assert predict(fit, outside) is None
    assert withheld_reason(fit, float(q.max()), **FIT_CONDITIONS) is None
    reason = withheld_reason(fit, 816.0, **FIT_CONDITIONS)
    assert reason.startswith("q_n 816 is outside") and f"{q.min():.3g} to {q.max():.3g}" in reason


def test_the_mde_fit_predicts_only_inside_the_q_n_it_saw():
    cal = packaged_calibration(PACKAGED)
    lo, hi = support(cal)
    assert (lo, hi) == tuple(cal["q_n_range"])
    assert predict(cal, lo) is not None and predict(cal, hi) is not None
    assert predict(cal, lo / 2) is None and predict(cal, hi * 2) is None


def test_the_shipped_fits_say_why_they_predict_nothing():
    error_fit, mde_fit = packaged_calibration(LOCALIZATION_PACKAGED), packaged_calibration(PACKAGED)
    assert support(error_fit) == tuple(error_fit["q_n_range"])
    lo, hi = support(error_fit)
    inside = float(np.sqrt(lo * hi))
    assert withheld_reason(error_fit, inside, **FIT_CONDITIONS) is None
    assert withheld_reason(error_fit, inside, **{**FIT_CONDITIONS, "sensor": "os1-64"}) == (
        "not fitted for this query: sensor os1-64, fitted for mid70, vlp16 only"
    )
    assert "range noise set" in withheld_reason(error_fit, inside, **{**FIT_CONDITIONS, "noise_is_default": False})
    assert "scan_voxel 0.2" in withheld_reason(error_fit, inside, **{**FIT_CONDITIONS, "scan_voxel": 0.2})
    assert withheld_reason(error_fit, np.inf, **FIT_CONDITIONS) == "q_n is infinite: the pose is degenerate"
    assert "fitted for vlp16 only" in withheld_reason(mde_fit, 1e-2, **FIT_CONDITIONS)
    assert withheld_reason(None, 1.0, **FIT_CONDITIONS) == "no fit is shipped with this lf3pm"


def box_far_ahead(half: float, distance: float) -> np.ndarray:
    """A cube of edge 2 * ``half`` m ``distance`` m ahead of a Mid-70 at the origin (facing
    +x), and a wall behind it that it does not see: few hits, a large q_n."""
    return np.vstack(
        [box_room((half,) * 3, 0.05) + (distance, 0.0, 0.0), grid_plane((-3, -2, -1), (0, 1, 0), (0, 0, 1), 4, 2, 0.1)]
    )


def test_evaluate_withholds_the_localization_error_beyond_the_fits_q_n():
    lo, hi = support(packaged_calibration(LOCALIZATION_PACKAGED))
    near = lf3pm.evaluate(lf3pm.load_map(box_far_ahead(1.0, 15.0)), (0, 0, 0, 0), "mid70")
    far = lf3pm.evaluate(lf3pm.load_map(box_far_ahead(0.5, 30.0)), (0, 0, 0, 0), "mid70")
    assert lo <= near.q_n <= hi and near.predicted_localization_error_m is not None
    assert far.q_n > hi and not far.degenerate
    assert far.predicted_localization_error_m is None and far.predicted_localization_error_interval_m is None


@pytest.mark.slow
def test_evaluate_cli_prints_null_and_the_reason(tmp_path):
    path = tmp_path / "far_box.pcd"
    write_points(path, box_far_ahead(0.5, 30.0))
    args = [sys.executable, "-m", "lf3pm.cli", "evaluate", str(path), "--pose", "0", "0", "0", "0", "--sensor", "mid70"]
    done = subprocess.run([*args, "--json"], check=False, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    assert out["predicted_localization_error_m"] is None
    assert out["predicted_localization_error_withheld"].startswith(f"q_n {out['q_n']:.3g} is outside the range")
    assert out["predicted_mde"] is None and "sensor mid70" in out["predicted_mde_withheld"]
    table = subprocess.run(args, check=False, capture_output=True, text=True, timeout=300)
    assert (
        "predicted localization error withheld: " + out["predicted_localization_error_withheld"]
        in table.stdout.splitlines()
    )


def test_a_sparse_real_scan_gets_no_prediction_far_outside_the_fit():
    """Issue 39's case: a Mid-70 in the corner of the PCL room scan (one 360-degree scan,
    sparse at range) gets 37 hits and q_n 760; the fit's line would say 144 m."""
    world = lf3pm.load_map(shared_file("indoor_pcl_room_scan1.pcd"))
    res = lf3pm.evaluate(world, (-9.2, -0.7, 0.0, -1.01), "mid70")
    assert res.hits < 100 and res.q_n > 100 * support(packaged_calibration(LOCALIZATION_PACKAGED))[1]
    assert res.predicted_localization_error_m is None
