"""A run folder (scans named by time, TUM poses) read as a map: against the points it was made from."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from lf3pm.errors import MapError
from lf3pm.io import load_points, voxel_downsample
from lf3pm.io.run_folder import POSES_FILE, SCANS_FOLDER, open_run_folder, run_map

VOXEL = 0.1


def _centres(rng, count: int) -> np.ndarray:
    """World points at voxel centres: a voxel's centroid of any of them is exact."""
    cells = np.unique(rng.integers(-60, 60, size=(count, 3)), axis=0)
    return (cells + 0.5) * VOXEL


def _write_run(root, world, poses, times, names=None) -> None:
    """Each pose sees a random half of ``world``, stored in its sensor frame."""
    rng = np.random.default_rng(1)
    (root / SCANS_FOLDER).mkdir(parents=True)
    lines = ["# time tx ty tz qx qy qz qw"]
    for i, (t, (rotation, translation)) in enumerate(zip(times, poses)):
        seen = world[rng.random(len(world)) < 0.5]
        local = (seen - translation) @ rotation.as_matrix()
        name = names[i] if names else f"{t:.6f}.npy"
        np.save(root / SCANS_FOLDER / name, local)
        lines.append(f"{t:.6f} {' '.join(f'{v:.12f}' for v in translation)} {' '.join(map(str, rotation.as_quat()))}")
    (root / POSES_FILE).write_text("\n".join(lines) + "\n")


def _poses(count: int, seed: int = 2):
    rng = np.random.default_rng(seed)
    return [(Rotation.from_rotvec(rng.normal(0, 0.7, 3)), rng.normal(0, 3, 3)) for _ in range(count)]


def test_run_map_is_the_voxels_of_every_scan_in_the_world(tmp_path):
    world = _centres(np.random.default_rng(0), 4000)
    times = 100.0 + 0.5 * np.arange(5)
    _write_run(tmp_path, world, _poses(5), times)
    got = load_points(tmp_path, voxel=VOXEL)
    # every world point is seen by some scan with probability 1 - 2^-5; the seen ones are the map
    assert len(got) > 0.9 * len(world)
    want = voxel_downsample(world, VOXEL)
    index = {tuple(np.floor(p / VOXEL).astype(int)) for p in want}
    assert all(tuple(np.floor(p / VOXEL).astype(int)) in index for p in got)
    assert len(np.unique(np.floor(got / VOXEL), axis=0)) == len(got)  # one point per voxel
    nearest = np.abs((got / VOXEL) - (np.floor(got / VOXEL) + 0.5)).max()
    assert nearest < 1e-9  # each point its voxel's centre: the scans' frames put them back exactly


def test_reducing_in_batches_keeps_every_voxel(tmp_path, monkeypatch):
    """Memory bounded: scans reduced in batches give the voxels of one reduction."""
    import lf3pm.io.run_folder as module

    world = _centres(np.random.default_rng(3), 3000)
    _write_run(tmp_path, world, _poses(6, seed=4), 10.0 + np.arange(6))
    whole = run_map(tmp_path, VOXEL)
    sizes = []
    original = module.voxel_downsample
    monkeypatch.setattr(module, "GATHER_POINTS", 100)
    monkeypatch.setattr(module, "voxel_downsample", lambda p, v: sizes.append(len(p)) or original(p, v))
    np.testing.assert_allclose(run_map(tmp_path, VOXEL), whole, rtol=0, atol=1e-9)
    assert max(sizes) < 2 * len(whole) + 2 * 1500  # the map and about two scans, never all six


def test_poses_match_scans_by_name(tmp_path):
    world = _centres(np.random.default_rng(5), 500)
    _write_run(tmp_path, world, _poses(3), [1.5, 2.0, 2.5])
    run = open_run_folder(tmp_path)
    assert [p.name for p in run.scans] == ["1.500000.npy", "2.000000.npy", "2.500000.npy"]
    np.testing.assert_allclose(run.times, [1.5, 2.0, 2.5])


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda t: t.replace("2.000000 ", "1.000000 ", 1), "time does not increase"),
        (lambda t: t.replace("2.500000 ", "2.600000 ", 1), "2.500000.npy: no pose at its time"),
        (lambda t: t + "3.0 0 0 0 0 0 0 1\n", "3 scans and 4 poses"),
        (lambda t: t + "3.0 0 0 0 0 0 0 2\n", "norm is 2"),
        (lambda t: t + "3.0 0 0 nan 0 0 0 1\n", "8 finite numbers"),
        (lambda t: "# nothing\n", "no poses"),
    ],
)
def test_bad_run_folders_fail_in_one_line(tmp_path, edit, message):
    world = _centres(np.random.default_rng(6), 300)
    _write_run(tmp_path, world, _poses(3), [1.5, 2.0, 2.5])
    poses = tmp_path / POSES_FILE
    poses.write_text(edit(poses.read_text()))
    with pytest.raises(MapError, match=message) as err:
        load_points(tmp_path)
    assert "\n" not in str(err.value)


def test_a_scan_not_named_by_its_time_fails(tmp_path):
    world = _centres(np.random.default_rng(7), 300)
    _write_run(tmp_path, world, _poses(2), [1.0, 2.0], names=["first.npy", "2.000000.npy"])
    with pytest.raises(MapError, match="first.npy: a scan's name is its time"):
        load_points(tmp_path)


def test_a_folder_that_is_no_run_is_no_map(tmp_path):
    with pytest.raises(MapError, match="not a regular file"):
        load_points(tmp_path)
