import sys
from pathlib import Path

# Test helpers (reference implementations, scene builders) live beside the tests.
sys.path.insert(0, str(Path(__file__).parent))


import pytest


@pytest.fixture(scope="session")
def boxes_planner(tmp_path_factory):
    """A Planner on the ``boxes`` scene's r2 SOLM (0.5 m cells, thinned scans), built once."""
    import subprocess

    from lf3pm.planner import Planner
    from lf3pm.solm.reader import Solm

    tmp = tmp_path_factory.mktemp("boxes")
    for args in (
        ["scene", "boxes", "-o", tmp / "boxes.pcd"],
        ["solm", "build", tmp / "boxes.pcd", "-o", tmp / "boxes.zarr", "--res", "0.5", "--ray-stride", "4"],
    ):
        subprocess.run([sys.executable, "-m", "lf3pm.cli", *map(str, args)], check=True, capture_output=True)
    return Planner(Solm.open(tmp / "boxes.zarr"))


@pytest.fixture(scope="session")
def orientation_planner(tmp_path_factory):
    """A Planner on the orientation scene's SE(2) Mid-70 SOLM (1 m cells, 36 bins, thinned
    scans), built once."""
    from lf3pm.map import load_map
    from lf3pm.planner import Planner
    from lf3pm.scenes import build_scene
    from lf3pm.sensors import get_sensor
    from lf3pm.solm import Solm, build_solm, make_grid

    world = load_map(build_scene("orientation").points)
    grid = make_grid(world, "se2", 1.0, yaw_bins=36)
    path = tmp_path_factory.mktemp("orientation") / "s.zarr"
    build_solm(world, get_sensor("mid70"), grid, path, yaw_reuse=True, ray_stride=8)
    return Planner(Solm.open(path))


@pytest.fixture(scope="session")
def study_boxes_planner(tmp_path_factory):
    """A Planner on the benefit study's ``boxes`` case (0.25 m cells: the room's halves join
    through gaps that leave the body 0.28 m on each side), built as the study builds it."""
    from lf3pm.experiments.benefit import CASES
    from lf3pm.experiments.map_cases import build_case_solm
    from lf3pm.planner import Planner
    from lf3pm.solm.reader import Solm

    case = next(c for c in CASES if c.name == "boxes")
    return Planner(Solm.open(build_case_solm(case, tmp_path_factory.mktemp("study") / "boxes.zarr")))


@pytest.fixture
def mounted(tmp_path):
    """mount(options) -> a fresh tmpfs mounted with ``options`` (root only; skips otherwise),
    unmounted afterwards."""
    import os
    import subprocess

    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    points = []

    def mount(options):
        point = tmp_path / f"mnt{len(points)}"
        point.mkdir()
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(point)], capture_output=True)
        if done.returncode != 0:
            pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")
        points.append(point)
        return point

    yield mount
    for point in points:
        subprocess.run(["umount", str(point)], check=False)
