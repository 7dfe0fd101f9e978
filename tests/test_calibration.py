"""The MDE calibration: monotone, intervals around the fit, applied only where it holds."""

import numpy as np
import pytest

import lf3pm
from lf3pm.calibration import fit_calibration, packaged_calibration, predict_mde, support
from lf3pm.scenes import build_scene


def test_fit_is_monotone_and_intervals_bracket_it():
    rng = np.random.default_rng(0)
    x = np.exp(rng.uniform(-8, -1, 400))
    y = x**2 * np.exp(rng.normal(scale=0.5, size=400))
    cal = fit_calibration(x, y, name="step_norm", provenance={})
    values = [predict_mde(cal, v) for v in np.geomspace(*support(cal), 50)]
    centres = [v[0] for v in values]
    assert all(b >= a for a, b in zip(centres, centres[1:]))
    assert all(lo <= c <= hi for c, lo, hi in values)
    assert predict_mde(cal, np.inf) is None and predict_mde(cal, 0.0) is None
    # Recovers the trend: two decades apart in x, about four in MDE.
    assert predict_mde(cal, 1e-2)[0] / predict_mde(cal, 1e-3)[0] == pytest.approx(100, rel=0.6)


def test_packaged_calibration_has_provenance():
    cal = packaged_calibration()
    assert cal["predictor"] in (
        "q_min",
        "q_n",
        "q_max",
        "zhang",
        "condition_number",
        "cov_trace",
        "step_norm",
        "scaled_cov_trace",
    )
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


def test_localization_error_fit_recovers_a_power_law_and_validates_by_map():
    """APE = 2 q_n^0.8 times lognormal noise on three maps: the fit recovers a and b, its
    10-90 % interval holds about 80 % of the held-out maps' plans (binomial sd 2.3 % over
    300, plus the spread of quantiles estimated from 200), and the prediction is None
    where q_n is not positive and finite."""
    from lf3pm.calibration import fit_localization_error, predict_localization_error

    rng = np.random.default_rng(1)
    q = np.exp(rng.uniform(-6, -1, 300))
    ape = 2.0 * q**0.8 * np.exp(rng.normal(scale=0.3, size=300))
    maps = np.repeat(["a", "b", "c"], 100)
    fit = fit_localization_error(maps, q, ape, provenance={"sensors": ["vlp16"], "w1": 0.5})
    assert fit["b"] == pytest.approx(0.8, abs=0.05) and fit["a"] == pytest.approx(np.log(2.0), abs=0.2)
    assert fit["samples"] == 300 and set(fit["validation"]) == {"a", "b", "c"}
    held = fit["validation"].values()
    assert 0.7 <= np.mean([h["share_inside_interval"] for h in held]) <= 0.9
    assert all(h["spearman_within_map"] > 0.9 for h in held)
    centre, lo, hi = predict_localization_error(fit, 0.01)
    assert lo < centre < hi and centre == pytest.approx(2.0 * 0.01**0.8, rel=0.2)
    assert predict_localization_error(fit, np.inf) is None and predict_localization_error(fit, 0.0) is None


def test_evaluate_reports_the_localization_error_only_for_the_fits_sensors():
    from lf3pm.calibration import LOCALIZATION_PACKAGED

    fit = packaged_calibration(LOCALIZATION_PACKAGED)
    scene = build_scene("boxes")
    world = lf3pm.load_map(scene.points)
    res = lf3pm.evaluate(world, scene.reference_pose, "vlp16")
    assert "vlp16" in fit["provenance"]["sensors"]
    lo, hi = res.predicted_localization_error_interval_m
    assert 0 < lo <= res.predicted_localization_error_m <= hi < 1.0
    assert res.to_dict()["predicted_localization_error_m"] == res.predicted_localization_error_m
    assert lf3pm.evaluate(world, scene.reference_pose, "os1-64").predicted_localization_error_m is None
    assert lf3pm.evaluate(world, scene.reference_pose, "vlp16", noise=0.05).predicted_localization_error_m is None
