"""The predicted localization error calibrated on a recorded run (lf3pm audit --calibrate;
issue 42, item 5): the fit is the run's own numbers by a float64 reference, the file it
writes is what evaluate, solm build and plan read with --calibration, and the audit ranks
the expected MDE (on q_n) against the registrations' MDE."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from recorded_runs import pillar_room, simulated_run
from typer.testing import CliRunner

import lf3pm
from lf3pm.audit import audit_run
from lf3pm.audit.calibrate import calibrate_run
from lf3pm.calibration import localization_fit, predict
from lf3pm.cli import app
from lf3pm.config import DEFAULTS, Config, configured
from lf3pm.errors import Lf3pmError
from lf3pm.prediction import predicted_error_along
from lf3pm.solm import Solm, build_solm, make_grid

#: Twelve scans across the room, turning: poses of different q_n.
POSES = [(-4.0 + 0.7 * i, -2.0 + 0.2 * i, 0.2 * i) for i in range(12)]  # clear of the pillar
STAMPS = [round(0.5 * i, 1) for i in range(12)]


@pytest.fixture(scope="module")
def audited(tmp_path_factory):
    """(run folder, the room, the audit with registrations from 2 starts, no tracks)."""
    room = pillar_room()
    folder, _ = simulated_run(tmp_path_factory.mktemp("calibrate"), room, POSES, STAMPS)
    config = configured(DEFAULTS, ("mde",), "the test", trials=2)
    return folder, room, audit_run(folder, room, "vlp16", config, track=False)


def test_the_calibration_is_the_runs_own_offset_under_the_shipped_slope(audited):
    """a = median(ln error - b ln sim_q_n) over the scans, the factor exp(a - a_shipped),
    the interval the residuals' 10-90 % quantiles: recomputed here in float64."""
    _, _, audit = audited
    base = localization_fit()
    fit = calibrate_run(audit, base, DEFAULTS, against="error_m", command="lf3pm audit x")
    q = np.array([r.sim_q_n for r in audit.records])
    error = np.array([r.error_m for r in audit.records])
    assert np.all(np.isfinite(q)) and np.all(error > 0)
    residual = np.log(error) - base["b"] * np.log(q)
    a = float(np.median(residual))
    assert fit["a"] == pytest.approx(a, rel=1e-12) and fit["b"] == base["b"]
    assert fit["factor"] == pytest.approx(math.exp(a - base["a"]), rel=1e-12)
    lo, hi = np.quantile(residual - a, [0.1, 0.9])
    assert (fit["log_lo"], fit["log_hi"]) == pytest.approx((lo, hi), rel=1e-12)
    assert fit["run_q_n_range"] == [q.min(), q.max()] and fit["samples"] == 12
    assert fit["q_n_range"] == [min(q.min(), base["q_n_range"][0]), max(q.max(), base["q_n_range"][1])]
    assert fit["provenance"]["sensors"] == ["vlp16"] and fit["provenance"]["error"].startswith("error_m: ")
    assert sum(v["scans"] for v in fit["validation"].values()) == 12
    with pytest.raises(Lf3pmError, match="cannot calibrate on tracking_error_m: the audit has none"):
        calibrate_run(audit, base, DEFAULTS)


def test_evaluate_solm_and_plan_predict_with_the_runs_fit(audited, tmp_path):
    """The file the audit writes: evaluate at a scan's pose predicts exp(a + b ln q_n);
    a SOLM built with it stores it, and the error predicted along a trajectory uses it."""
    _, room, audit = audited
    fit = calibrate_run(audit, localization_fit(), DEFAULTS, against="error_m")
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(fit))
    config = Config(prediction={"calibration": str(path)})
    record = audit.records[len(audit.records) // 2]
    res = lf3pm.evaluate(room, np.array(record.pose), "vlp16", config)
    assert res.q_n == record.sim_q_n  # the audit's simulated scan, the same seed
    assert res.predicted_localization_error_m == pytest.approx(predict(fit, res.q_n)[0], rel=1e-12)
    assert res.predicted_localization_error_withheld is None
    other = lf3pm.evaluate(room, np.array(record.pose), "mid70", config)
    assert "sensor mid70, fitted for vlp16 only" in other.predicted_localization_error_withheld

    grid = make_grid(room, "r2", 1.0, bounds=(-4.0, -2.0, 4.0, 2.0), height=1.5)  # the scans, 1.5 m above the floor
    store = tmp_path / "room.zarr"
    build_solm(room, "vlp16", grid, store, config, ray_stride=4)
    solm = Solm.open(store)
    assert solm.attrs["calibration"] == fit
    samples = {"x": np.linspace(-3, 3, 61), "y": np.zeros(61), "yaw": np.zeros(61)}
    q_n = solm.query(samples["x"], samples["y"])[0]
    mean = float(np.mean(q_n[np.isfinite(q_n)]))
    error, withheld = predicted_error_along(solm, samples, fit)
    expected = predict(fit, mean)
    assert (error, withheld) == ((expected[0], None) if expected else (None, withheld))
    if expected is None:
        assert withheld.startswith("q_n ") and "outside the range" in withheld


def test_the_audit_ranks_the_expected_mde_against_the_registrations(audited):
    _, _, audit = audited
    packaged = lf3pm.calibration.packaged_calibration()
    for r in audit.records:  # vlp16 at its default noise: the packaged MDE fit applies where q_n is in range
        expected = predict(packaged, r.sim_q_n)
        assert (r.predicted_mde, r.predicted_mde_withheld is None) == (
            (expected[0], True) if expected else (r.predicted_mde, False)
        )
    names = {(c.prediction, c.real_error) for c in audit.summary.correlations}
    assert ("predicted_mde", "mde") in names and ("real_q_n", "mde") in names
    assert "mde" in audit.summary.inside_interval


@pytest.mark.slow
def test_the_cli_writes_the_fit_and_reads_it_back(audited, tmp_path):
    folder, room, _ = audited
    map_path = tmp_path / "room.npy"
    np.save(map_path, room.points)
    fit_path, out = tmp_path / "fit.json", tmp_path / "out"
    args = ["audit", str(folder), "--map", str(map_path), "--starts", "2", "--no-track"]
    done = CliRunner().invoke(app, [*args, "--calibrate", str(fit_path), "--calibrate-on", "error_m", "-o", str(out)])
    assert done.exit_code == 0, done.output
    fit = json.loads(fit_path.read_text())
    assert fit["samples"] == 12 and "--calibrate" in fit["provenance"]["command"]
    assert "calibrated on 12 scans" in done.stdout and f"wrote {fit_path}" in done.stdout
    assert "## The predicted localization error calibrated on this run" in (out / "report.md").read_text()
    again = CliRunner().invoke(app, [*args, "--no-registration", "--calibration", str(fit_path), "--json"])
    assert again.exit_code == 0, again.output
    scans = json.loads(again.stdout)["scans"]
    assert any(s["predicted_error_m"] is not None for s in scans)
    for s in scans:
        if s["predicted_error_m"] is not None:
            assert s["predicted_error_m"] == pytest.approx(predict(fit, s["sim_q_n"])[0], rel=1e-12)
    bad = CliRunner().invoke(app, [*args, "--calibrate", str(fit_path), "--calibrate-on", "nonsense"])
    assert bad.exit_code == 2 and "--calibrate-on must be one of tracking_error_m, error_m, spread_m" in bad.output
    missing = CliRunner().invoke(app, [*args, "--calibration", str(tmp_path / "none.json")])
    assert missing.exit_code == 2 and "none.json: No such file" in missing.output
    assert len(missing.output.strip().splitlines()) == 1
