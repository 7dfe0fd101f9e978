"""`lf3pm experiment correlation` at a reduced size, and its free-pose sampler."""

import csv
import json

import numpy as np
import pytest
from scipy.stats import spearmanr
from shared_data import shared_file

import lf3pm
from lf3pm.experiments import correlation
from lf3pm.experiments.free_poses import GroundGrid, random_free_poses
from lf3pm.scenes import build_scene


def test_free_poses_are_free_and_at_sensor_height():
    scene = build_scene("boxes")
    world = lf3pm.load_map(scene.points)
    rng = np.random.default_rng(0)
    lower, upper = world.bounds
    poses = random_free_poses(world, 10, rng, sensor_height=1.0, region=(lower[0], lower[1], upper[0], upper[1]))
    assert len(poses) == 10
    ground = GroundGrid(world)
    probes = np.array([p[:3] for p in poses])
    _, dist = world.index.nearest(np.ascontiguousarray(probes), 1, 0.5)
    assert np.all(np.isinf(dist))
    for x, y, z, _ in poses:
        assert abs(z - (ground.height(x, y) + 1.0)) < 1e-9


@pytest.mark.slow
def test_correlation_study_writes_summary_csv_and_scatter(tmp_path):
    for name in correlation.REAL_MAPS:  # the study reads them
        shared_file(name)
    summary = correlation.run(tmp_path, poses_per_map=3, trials=1, bootstrap=20)
    on_disk = json.loads((tmp_path / "summary.json").read_text())
    assert set(on_disk["predictors"]) == set(correlation.PREDICTORS)
    for p in on_disk["predictors"].values():
        assert -1 <= p["rho"] <= 1 and p["ci"][0] <= p["ci"][1]
        assert len(p["within"]) == len(on_disk["params"]["maps"]) == 8
    assert on_disk["params"]["poses"] >= 20
    assert summary["best_within_map"] in correlation.PREDICTORS
    rows = list(csv.DictReader((tmp_path / "poses.csv").open()))
    assert len(rows) == on_disk["params"]["poses"] and "mde" in rows[0]
    # The summary's rho is Spearman's rho of the CSV's columns, each predictor signed
    # so that larger = worse.
    mde = np.array([float(r["mde"]) for r in rows])
    for name, sign in correlation.PREDICTORS.items():
        x = sign * np.array([float(r[name]) for r in rows])
        assert on_disk["predictors"][name]["rho"] == pytest.approx(spearmanr(x, mde).statistic, abs=1e-12)
    assert (tmp_path / "scatter.png").stat().st_size > 10_000


@pytest.mark.slow
def test_analysis_ranks_predictors_on_records_made_for_it():
    """Hand-made records on two maps: q_n ranks MDE exactly, zhang exactly backwards
    (it is negated, so it ranks exactly too), q_min ranks it exactly pooled but
    backwards within each map; the rest is noise. rho, the within-map means and the
    best predictors follow."""
    rng = np.random.default_rng(3)
    records = []
    for map_name, offset in (("a", 0.0), ("b", 10.0)):
        for k in range(12):
            mde = offset + k
            records.append(
                {
                    "map": map_name,
                    "mde": mde,
                    "q_n": mde,
                    "zhang": -mde,
                    "q_min": offset - k,
                    **{name: rng.normal() for name in correlation.PREDICTORS if name not in ("q_n", "zhang", "q_min")},
                }
            )
    summary = correlation.analyse(records, 200, np.random.default_rng(0))
    p = summary["predictors"]
    assert p["q_n"]["rho"] == pytest.approx(1.0) and p["zhang"]["rho"] == pytest.approx(1.0)
    assert p["q_n"]["within"] == pytest.approx({"a": 1.0, "b": 1.0})
    assert p["q_min"]["within_mean_rho"] == pytest.approx(-1.0) and p["q_min"]["rho"] > 0.4
    assert p["q_n"]["ci"] == pytest.approx([1.0, 1.0])
    assert summary["best_within_map"] in ("q_n", "zhang") and summary["best_pooled"] in ("q_n", "zhang")
