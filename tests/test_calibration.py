"""The MDE calibration: monotone, intervals around the fit, applied only where it holds."""

import numpy as np
import pytest

import lf3pm
from lf3pm.calibration import fit_calibration, packaged_calibration, predict_mde
from lf3pm.scenes import build_scene


def test_fit_is_monotone_and_intervals_bracket_it():
    rng = np.random.default_rng(0)
    x = np.exp(rng.uniform(-8, -1, 400))
    y = x**2 * np.exp(rng.normal(scale=0.5, size=400))
    cal = fit_calibration(x, y, name="step_norm", provenance={})
    values = [predict_mde(cal, v) for v in np.exp(np.linspace(-9, 0, 50))]
    centres = [v[0] for v in values]
    assert all(b >= a for a, b in zip(centres, centres[1:]))
    assert all(lo <= c <= hi for c, lo, hi in values)
    assert predict_mde(cal, np.inf) is None and predict_mde(cal, 0.0) is None
    # Recovers the trend: two decades apart in x, about four in MDE.
    assert predict_mde(cal, 1e-2)[0] / predict_mde(cal, 1e-3)[0] == pytest.approx(100, rel=0.6)


def test_packaged_calibration_has_provenance():
    cal = packaged_calibration()
    assert cal["predictor"] in ("q_min", "q_n", "q_max", "zhang", "condition_number", "cov_trace",
                                "step_norm", "scaled_cov_trace")
    for key in ("command", "sensor", "poses", "trials", "sigma_t", "lf3pm_version"):
        assert key in cal["provenance"]


def test_evaluate_reports_predicted_mde_only_where_the_calibration_holds():
    scene = build_scene("boxes")
    world = lf3pm.load_map(scene.points)
    res = lf3pm.evaluate(world, scene.reference_pose, "vlp16")
    lo, hi = res.predicted_mde_interval
    assert 0 < lo <= res.predicted_mde <= hi
    assert "predicted_mde" in res.to_dict()
    assert lf3pm.evaluate(world, scene.reference_pose, "mid70").predicted_mde is None
    assert lf3pm.evaluate(world, scene.reference_pose, "vlp16", noise=0.05).predicted_mde is None
