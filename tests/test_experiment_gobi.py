"""The Gobi experiment end to end on a coarse, reduced setup: every guidance is
planned, evaluated by S and replayed, written, and the trajectories respect the map."""

import json
from dataclasses import replace

import numpy as np
import pytest

from lf3pm.experiments import gobi
from lf3pm.solm import Solm


@pytest.mark.slow
def test_reduced_gobi_experiment_writes_every_guidance(tmp_path):
    setup = replace(gobi.REDUCED, solm_res=2.0, yaw_bins=18, mde_every=6.0, mde_trials=2, ray_stride=4, replay_seeds=1)
    summary = gobi.run(tmp_path, setup)
    assert set(summary["results"]) == {"q_n", "q_min", "step_norm", "default", "none"}
    assert json.loads((tmp_path / "summary.json").read_text())["results"].keys() == summary["results"].keys()
    solm = Solm.open(tmp_path / "solm.zarr")
    blocked = solm.channel("obstacle").max(axis=0)
    g = solm.grid_spec
    for metric, result in summary["results"].items():
        assert result["S"] > 0 and result["mde_poses"] >= 3
        for method in ("localization", "lio"):
            assert np.isfinite(result[method]["ape"]) and len(result[method]["errors"]) > 20
        assert len(result["lio"]["rest_steady_per_seed"]) == 1  # whether the LIO held still before the plan
        data = np.loadtxt(tmp_path / "trajectories" / f"{metric}.csv", delimiter=",", skiprows=1)
        assert np.allclose(data[0, 1:3], summary["start"][:2]) and np.allclose(data[-1, 1:3], summary["goal"][:2])
        ix = ((data[:, 1] - g.x0) / g.res).astype(int)
        iy = ((data[:, 2] - g.y0) / g.res).astype(int)
        assert not blocked[iy, ix].any(), f"the {metric} trajectory crosses an obstacle cell"
    table = (tmp_path / "gobi.md").read_text()
    assert "| default |" in table and "LIO rests steady" in table
    for name in ("trajectories.png", "along.png"):
        assert (tmp_path / name).stat().st_size > 10_000
