"""MDE ground truth (small_gicp point-to-plane ICP from disturbed starts)."""

import numpy as np
import pytest

import lf3pm
from lf3pm.errors import Lf3pmError, PoseError
from lf3pm.pose import se3_exp, se3_log
from lf3pm.scenes import build_scene
from lf3pm.validation import RegistrationTarget, mde


@pytest.mark.parametrize("seed", range(5))
def test_se3_log_inverts_exp(seed):
    rng = np.random.default_rng(seed)
    xi = rng.normal(size=6) * [1, 1, 1, 0.5, 0.5, 0.5]
    np.testing.assert_allclose(se3_log(se3_exp(xi)), xi, atol=1e-10)
    np.testing.assert_allclose(se3_log(se3_exp(xi * 1e-9)), xi * 1e-9, atol=1e-15)


@pytest.fixture(scope="module")
def houses():
    scene = build_scene("houses")
    world = lf3pm.load_map(scene.points)
    return scene, world, RegistrationTarget(world)


@pytest.mark.slow
def test_noise_free_scan_from_the_true_pose_has_near_zero_mde(houses):
    scene, world, target = houses
    res = mde(world, scene.reference_pose, "vlp16", trials=3, sigma_t=0.0, sigma_r=0.0, noise=0.0, target=target)
    # A sub-millimetre floor remains: small_gicp fits its own normals (10 neighbours).
    assert res.mde < 1e-5 and res.trials == 3 and len(res.errors) == 3


@pytest.mark.slow
def test_wall_is_worse_than_houses(houses):
    scene, world, target = houses
    good = mde(world, scene.reference_pose, "vlp16", trials=6, seed=1, target=target)
    wall_scene = build_scene("wall")
    bad = mde(lf3pm.load_map(wall_scene.points), wall_scene.reference_pose, "vlp16", trials=6, seed=1)
    assert bad.mde > 100 * good.mde


@pytest.mark.slow
def test_seeded_and_reported(houses):
    scene, world, target = houses
    a = mde(world, scene.reference_pose, trials=4, seed=7, target=target)
    b = mde(world, scene.reference_pose, trials=4, seed=7, target=target)
    # small_gicp's parallel reductions reorder sums: equal to rounding, not bitwise.
    assert a.errors == pytest.approx(b.errors, rel=1e-9) and a.params["seed"] == 7 and a.params["sigma_t"] == 0.1


def test_bad_input(houses):
    scene, world, target = houses
    lower, upper = world.bounds
    with pytest.raises(PoseError, match="outside"):
        mde(world, (upper[0] + 10, 0, 1, 0), target=target)
    x, y, z = world.points[len(world.points) // 2]
    with pytest.raises(PoseError, match="obstacle"):
        mde(world, (x, y, z, 0), target=target)
    with pytest.raises(Lf3pmError, match="trials"):
        mde(world, scene.reference_pose, trials=0, target=target)
