"""The top-level API (docs/api.md) as a user scripts it: map, evaluation, SOLM
build and query, a plan and its replay, every name from `import lf3pm`."""

import numpy as np
import pytest

import lf3pm


def test_every_public_name_resolves_and_has_a_docstring():
    for name in lf3pm.__all__:
        if name == "__version__":
            continue
        obj = getattr(lf3pm, name)
        assert obj.__doc__ and obj.__doc__.strip(), name
    with pytest.raises(AttributeError):
        lf3pm.no_such_thing  # noqa: B018


@pytest.mark.slow
def test_map_to_replay_from_the_top_level(tmp_path):
    world = lf3pm.load_map(lf3pm.build_scene("boxes").points)
    out = lf3pm.evaluate(world, (0.0, 0.0, 0.5, 0.0), lf3pm.get_sensor("vlp16"), seed=0)
    assert np.isfinite(out.q_n) and out.q_min <= out.q_n <= out.q_max

    grid = lf3pm.make_grid(world, "r2", 0.5)
    lf3pm.build_solm(world, "vlp16", grid, tmp_path / "boxes.zarr", ray_stride=8)
    solm = lf3pm.Solm.open(tmp_path / "boxes.zarr")
    x, y = solm.grid()
    q, gradient = solm.query(x.ravel()[:5], y.ravel()[:5], channel="q_n")
    stored = solm.channel("q_n").ravel()[:5]
    finite = np.isfinite(stored)
    np.testing.assert_allclose(q[finite], stored[finite], rtol=1e-6)  # at cell centres the query is the cell
    assert gradient.shape == (5, 2)

    plan = lf3pm.Planner(solm).plan((-3.0, -3.0, 0.0), (6.2, 2.8, 0.0), robot=lf3pm.Robot("diff", r_safe=0.1))
    assert plan.summary()["trajectory_length_m"] > 10.0
    result = lf3pm.replay(world, plan, "vlp16", "localization", seed=0)
    assert isinstance(result, lf3pm.ReplayResult) and result.ape["rmse"] < 0.05
    # The Plan, its Trajectory and its CSV replay the same motion.
    plan.trajectory.to_csv(tmp_path / "traj.csv")
    again = lf3pm.replay(world, tmp_path / "traj.csv", "vlp16", "localization", seed=0)
    assert again.scans == result.scans
    np.testing.assert_allclose(again.truth[:, :3, 3], result.truth[:, :3, 3], atol=1e-6)
    with pytest.raises(lf3pm.Lf3pmError, match="replay takes"):
        lf3pm.replay(world, 42, "vlp16", "localization")


def test_the_core_refuses_bad_input_with_an_lf3pm_error():
    from lf3pm import _core
    from lf3pm.errors import CoreInputError

    with pytest.raises(CoreInputError, match="nx \\* ny \\* layers") as refused:
        _core.grid_search(np.zeros(3), np.zeros(3, np.uint8), 2, 2, 1, 1.0, 0, 1)
    assert isinstance(refused.value, lf3pm.Lf3pmError) and isinstance(refused.value, ValueError)
