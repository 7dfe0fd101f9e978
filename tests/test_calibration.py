"""The calibrations on q_n: expected MDE and localization error, intervals around the fit,
applied only where they hold; a fit recalibrated on a user's run and read back."""

import json

import numpy as np
import pytest

import lf3pm
from lf3pm.calibration import (
    LOCALIZATION_PACKAGED,
    calibrate_factor,
    load_calibration,
    localization_fit,
    packaged_calibration,
    predict,
    support,
)
from lf3pm.config import Config
from lf3pm.errors import Lf3pmError
from lf3pm.scenes import build_scene


def test_the_packaged_mde_fit_ranks_poses_as_q_n_does():
    """Issue 42: predicted_mde must rank poses at least as well as q_n on maps its fit did
    not use; a fit increasing in q_n ranks them exactly as q_n, on any map."""
    cal = packaged_calibration()
    assert cal["predictor"] == "q_n" and cal["b"] > 0
    q = np.geomspace(*support(cal), 50)
    centres = [predict(cal, v)[0] for v in q]
    assert np.all(np.diff(centres) > 0)  # strictly increasing: the same order, no ties
    assert all(lo <= c <= hi for c, lo, hi in (predict(cal, v) for v in q))
    assert predict(cal, np.inf) is None and predict(cal, 0.0) is None
    for key in ("command", "sensor", "poses", "trials", "sigma_t", "lf3pm_version"):
        assert key in cal["provenance"]
    assert set(cal["validation"]) == set(cal["provenance"]["maps"])


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
    from lf3pm.calibration import fit_on_q_n

    rng = np.random.default_rng(1)
    q = np.exp(rng.uniform(-6, -1, 300))
    ape = 2.0 * q**0.8 * np.exp(rng.normal(scale=0.3, size=300))
    maps = np.repeat(["a", "b", "c"], 100)
    fit = fit_on_q_n(maps, q, ape, provenance={"sensors": ["vlp16"], "w1": 0.5})
    assert fit["b"] == pytest.approx(0.8, abs=0.05) and fit["a"] == pytest.approx(np.log(2.0), abs=0.2)
    assert fit["samples"] == 300 and set(fit["validation"]) == {"a", "b", "c"}
    held = fit["validation"].values()
    assert 0.7 <= np.mean([h["share_inside_interval"] for h in held]) <= 0.9
    assert all(h["spearman_within_map"] > 0.9 for h in held)
    centre, lo, hi = predict(fit, 0.01)
    assert lo < centre < hi and centre == pytest.approx(2.0 * 0.01**0.8, rel=0.2)
    assert predict(fit, np.inf) is None and predict(fit, 0.0) is None


def test_evaluate_reports_the_localization_error_only_for_the_fits_sensors():
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


def _base() -> dict:
    """A localization-error fit as the benefit study writes one: error = 0.1 q_n."""
    return {"predictor": "q_n", "a": np.log(0.1), "b": 1.0, "log_lo": -0.5, "log_hi": 0.5, "q_n_range": [1e-3, 10.0]}


def test_a_run_three_times_worse_than_the_fit_is_recalibrated_by_three():
    """Errors 3 x 0.1 q_n times lognormal noise (sigma 0.3) on 100 scans: the factor is 3
    (the median's standard error is about 1.25 * 0.3 / 10 in log), the slope kept, the
    recalibrated interval holds about 80 % of each left-out segment (20 scans: binomial sd
    9 %), the shipped one far fewer."""
    rng = np.random.default_rng(4)
    q = np.exp(rng.uniform(-4, -1, 100))
    error = 0.3 * q * np.exp(rng.normal(scale=0.3, size=100))
    fit = calibrate_factor(_base(), q, error, provenance={"sensors": ["os1-64"], "w1": 0.5})
    assert fit["factor"] == pytest.approx(3.0, rel=0.15) and fit["b"] == 1.0
    assert fit["run_q_n_range"] == [q.min(), q.max()] and fit["samples"] == 100
    assert fit["q_n_range"] == [1e-3, 10.0]  # the shipped fit's, which holds the run's
    segments = fit["validation"].values()
    assert len(segments) == 5 and all(s["scans"] == 20 for s in segments)
    assert 0.6 <= np.mean([s["share_inside_interval"] for s in segments]) <= 0.95
    assert np.mean([s["shipped"]["share_inside_interval"] for s in segments]) < 0.3
    assert fit["shipped"]["median_factor"] == pytest.approx(3.0, rel=0.2)
    centre, lo, hi = predict(fit, 0.1)
    assert lo < centre < hi and centre == pytest.approx(0.03, rel=0.15)
    with pytest.raises(Lf3pmError, match="at least 10 scans"):
        calibrate_factor(_base(), q[:9], error[:9], provenance={})


def test_a_calibration_file_is_read_back_or_refused_in_one_line(tmp_path):
    path = tmp_path / "cal.json"
    fit = calibrate_factor(_base(), np.geomspace(0.01, 1, 20), np.geomspace(0.002, 0.2, 20), provenance={"w1": 0.5})
    path.write_text(json.dumps(fit))
    assert load_calibration(path) == json.loads(path.read_text())
    assert localization_fit(str(path)) == load_calibration(path)
    assert localization_fit() == packaged_calibration(LOCALIZATION_PACKAGED)
    with pytest.raises(Lf3pmError, match=r"calibration .*missing.json: No such file"):
        load_calibration(tmp_path / "missing.json")
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(Lf3pmError, match="not JSON"):
        load_calibration(tmp_path / "bad.json")
    (tmp_path / "mde.json").write_text(json.dumps({**fit, "predictor": "step_norm"}))
    with pytest.raises(Lf3pmError, match="not a localization-error fit on q_n \\(predictor 'step_norm'"):
        load_calibration(tmp_path / "mde.json")


def test_evaluate_predicts_with_the_calibration_it_is_given(tmp_path):
    """The same pose with the packaged fit and with a file whose offset is ln 2 higher (and
    a range covering the query): the prediction and its interval double."""
    base = packaged_calibration(LOCALIZATION_PACKAGED)
    path = tmp_path / "run.json"
    path.write_text(json.dumps({**base, "a": base["a"] + np.log(2.0)}))
    scene = build_scene("boxes")
    world = lf3pm.load_map(scene.points)
    packaged = lf3pm.evaluate(world, scene.reference_pose, "vlp16")
    mine = lf3pm.evaluate(world, scene.reference_pose, "vlp16", Config(prediction={"calibration": str(path)}))
    assert mine.predicted_localization_error_m == pytest.approx(2 * packaged.predicted_localization_error_m)
    assert mine.predicted_localization_error_interval_m == pytest.approx(
        [2 * v for v in packaged.predicted_localization_error_interval_m]
    )
