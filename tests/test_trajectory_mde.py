"""MDE along a trajectory and its sum S."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

import lf3pm
from lf3pm.errors import Lf3pmError
from lf3pm.scenes import build_scene
from lf3pm.validation import RegistrationTarget, mde
from lf3pm.validation.trajectory_mde import mde_along, pose_seed


@pytest.fixture(scope="module")
def boxes():
    scene = build_scene("boxes")
    world = lf3pm.load_map(scene.points)
    return scene, world, RegistrationTarget(world)


def path(z, n=4):
    return np.array([[-1.0 + 0.6 * i, 0.2 * i, z, 0.3 * i] for i in range(n)])


def test_equals_per_pose_mde_calls(boxes):
    scene, world, target = boxes
    poses = path(scene.reference_pose[2], n=3)
    along = mde_along(world, poses, "vlp16", trials=2, seed=11, target=target)
    assert not along.refused and along.evaluated == 3
    single = [mde(world, p, "vlp16", trials=2, seed=pose_seed(11, i), target=target).mde for i, p in enumerate(poses)]
    # small_gicp's parallel reductions reorder sums: equal to rounding, not bitwise.
    assert along.mde == pytest.approx(single, rel=1e-9)
    assert along.s == pytest.approx(sum(single), rel=1e-9)
    assert along.seeds == [pose_seed(11, i) for i in range(3)] and len(set(along.seeds)) == 3


def test_seeds_do_not_depend_on_order(boxes):
    scene, world, target = boxes
    poses = path(scene.reference_pose[2])
    forward = mde_along(world, poses, trials=2, seed=3, target=target)
    # Pose 2 alone, evaluated as pose 2 of the same trajectory: same seed, same MDE.
    assert forward.seeds[2] == pose_seed(3, 2) != pose_seed(4, 2)
    alone = mde(world, poses[2], trials=2, seed=forward.seeds[2], target=target)
    assert alone.mde == pytest.approx(forward.mde[2], rel=1e-9)


@pytest.mark.slow
def test_matches_the_cli(boxes, tmp_path):
    scene, world, target = boxes
    pcd = tmp_path / "boxes.pcd"
    subprocess.run(
        [sys.executable, "-m", "lf3pm.cli", "scene", "boxes", "-o", str(pcd)], check=True, capture_output=True
    )
    poses = path(scene.reference_pose[2], n=2)
    along = mde_along(lf3pm.load_map(pcd), poses, trials=2, seed=0)
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "lf3pm.cli",
            "mde",
            str(pcd),
            "--pose",
            *map(str, poses[1]),
            "--trials",
            "2",
            "--seed",
            str(along.seeds[1]),
            "--json",
        ],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    assert json.loads(out)["mde"] == pytest.approx(along.mde[1], rel=1e-6)


def test_refused_poses_are_reported(boxes):
    scene, world, target = boxes
    poses = path(scene.reference_pose[2], n=3)
    lower, upper = world.bounds
    poses[1] = [upper[0] + 5.0, 0.0, 1.0, 0.0]  # outside the map
    inside = world.points[len(world.points) // 2]
    poses = np.vstack([poses, [*inside, 0.0]])  # inside an obstacle
    result = mde_along(world, poses, trials=2, target=target)
    assert [i for i, _ in result.refused] == [1, 3]
    assert "outside" in result.refused[0][1] and "obstacle" in result.refused[1][1]
    assert math.isnan(result.mde[1]) and math.isnan(result.mde[3]) and result.evaluated == 2
    assert result.s == pytest.approx(result.mde[0] + result.mde[2])
    assert json.dumps(result.to_dict())  # NaN -> null, JSON-ready


def test_bad_input(boxes):
    scene, world, target = boxes
    with pytest.raises(Lf3pmError, match="N >= 1"):
        mde_along(world, np.zeros((0, 4)), target=target)
    with pytest.raises(Lf3pmError, match=r"\(N, 4\)"):
        mde_along(world, [[0.0, 0.0, 1.0]], target=target)
    with pytest.raises(Lf3pmError, match="non-finite"):
        mde_along(world, [[0.0, math.inf, 1.0, 0.0]], target=target)
    with pytest.raises(Lf3pmError, match="trials"):
        mde_along(world, path(1.0), trials=0, target=target)
    other = lf3pm.load_map(world.points[::2])
    with pytest.raises(Lf3pmError, match="another map"):
        mde_along(other, path(1.0), target=target)
