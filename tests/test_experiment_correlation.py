"""`lf3pm experiment correlation` at a reduced size, and its free-pose sampler."""

import csv
import json

import numpy as np

import lf3pm
from lf3pm.experiments import correlation
from lf3pm.experiments.free_poses import GroundGrid, random_free_poses
from lf3pm.scenes import build_scene


def test_free_poses_are_free_and_at_sensor_height():
    scene = build_scene("boxes")
    world = lf3pm.load_map(scene.points)
    rng = np.random.default_rng(0)
    lower, upper = world.bounds
    poses = random_free_poses(world, 10, rng, sensor_height=1.0,
                              region=(lower[0], lower[1], upper[0], upper[1]))
    assert len(poses) == 10
    ground = GroundGrid(world)
    probes = np.array([p[:3] for p in poses])
    _, dist = world.index.nearest(np.ascontiguousarray(probes), 1, 0.5)
    assert np.all(np.isinf(dist))
    for x, y, z, _ in poses:
        assert abs(z - (ground.height(x, y) + 1.0)) < 1e-9


def test_correlation_study_writes_summary_csv_and_scatter(tmp_path):
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
    assert (tmp_path / "scatter.png").stat().st_size > 10_000
