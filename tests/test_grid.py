"""One grid type (lf3pm.grid): its arithmetic, its space as an enum, the SOLM's grid
attribute on disk, no grid-space name compared as a string in code, and the entry
points that take their configuration sections whole giving what their keywords give."""

import ast
import math
from pathlib import Path

import numpy as np
import pytest

import lf3pm
from lf3pm.config import DEFAULTS, ConfigError, GuidanceConfig, load_config
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Grid, Space
from lf3pm.solm import SolmGrid, build_solm, make_grid

ROOT = Path(__file__).resolve().parents[1] / "python" / "lf3pm"
NAMES = {space.value for space in Space}


def test_a_space_is_its_name_at_the_boundary():
    assert Space("se2") is Space.SE2 and f"{Space.R3}" == "r3" and str(Space.R2) == "r2"
    assert [s.ground for s in Space] == [True, True, False, False]
    assert [s.yawed for s in Space] == [False, True, False, True]
    with pytest.raises(ValueError):
        Space("r4")


def test_grid_cells_centres_and_bounds():
    g = Grid("se2", -1.0, 2.0, 0.5, 4, 6, yaw_bins=8)
    assert g.space is Space.SE2 and g.shape == (8, 6, 4) and g.plane_shape == (6, 4) and g.layers == 8
    assert g.bounds == (-1.0, 2.0, 1.0, 5.0) and g.origin == (-1.0, 2.0)
    assert g.cell_of(-0.99, 2.01) == (0, 0) and g.cell_of(0.99, 4.99) == (3, 5) and g.cell_of(1.0, 3.0) is None
    assert g.centre(1, 2) == (-0.25, 3.25)
    x, y = g.centres()
    assert x.shape == (6, 4) and (x[0, 1], y[2, 0]) == (-0.25, 3.25)
    k, iy, ix = g.cell(np.array([-5.0, 0.2]), np.array([2.2, 99.0]), np.array([2 * math.pi - 0.1, math.pi / 4]))
    assert (k.tolist(), iy.tolist(), ix.tolist()) == ([0, 1], [0, 5], [0, 2])
    fine = g.refined(4)
    assert fine.space is Space.R2 and (fine.res, fine.nx, fine.ny) == (0.125, 16, 24) and fine.bounds == g.bounds
    assert g.flat().same_cells(fine.refined(1)) is False and g.flat().same_cells(Grid.plane(-1.0, 2.0, 0.5, 4, 6))
    ix, iy = g.columns([-1.5, 0.1], [2.1, 2.1])
    assert g.holds(ix, iy).tolist() == [False, True]


def test_the_store_attribute_reads_and_writes_the_space_by_name():
    spec = {"space": "r3", "x0": 0.0, "y0": 0.0, "res": 1.0, "nx": 2, "ny": 3, "yaw_bins": 1}
    spec |= {"z_levels": [0.5, 1.5], "height": 1.0}
    grid = SolmGrid(**{**spec, "z_levels": tuple(spec["z_levels"])})
    assert grid.space is Space.R3 and grid.shape == (2, 3, 2)
    assert grid.to_dict() == spec and list(grid.to_dict()) == list(spec)  # the same keys, in the same order


def test_no_grid_space_name_is_compared_as_a_string():
    """Code compares lf3pm.grid.Space members; the names stay where YAML, the CLI and
    stores hold them (by AST: a comparison with "r2", "se2" or "r3", or a tuple of them)."""
    found = []
    for path in sorted(ROOT.rglob("*.py")):
        where = path.relative_to(ROOT).as_posix()
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.Compare):
                continue
            for side in [node.left, *node.comparators]:
                items = side.elts if isinstance(side, (ast.Tuple, ast.List, ast.Set)) else [side]
                if any(isinstance(i, ast.Constant) and i.value in NAMES for i in items):
                    found.append(f"{where}:{node.lineno}")
    assert not found, "grid spaces compared as strings: " + ", ".join(found)


@pytest.fixture(scope="module")
def boxes():
    return lf3pm.load_map(lf3pm.build_scene("boxes").points)


@pytest.mark.slow
def test_sections_whole_give_what_their_fields_by_name_give(boxes, tmp_path):
    se2 = load_config(overrides={"solm.space": "se2", "solm.res": 1.0, "solm.yaw_bins": 8})
    assert make_grid(boxes, config=se2.solm) == make_grid(boxes, "se2", 1.0, yaw_bins=8)
    config = load_config(overrides={"solm.res": 0.5, "solm.ray_stride": 8, "scan.seed": 3})
    grid = make_grid(boxes, config=config.solm)
    assert grid == make_grid(boxes, "r2", 0.5)
    build_solm(boxes, "vlp16", grid, tmp_path / "whole.zarr", config)
    build_solm(boxes, "vlp16", grid, tmp_path / "named.zarr", seed=3, ray_stride=8)
    whole, named = lf3pm.Solm.open(tmp_path / "whole.zarr"), lf3pm.Solm.open(tmp_path / "named.zarr")
    assert whole.attrs == {**named.attrs, "map_source": whole.attrs["map_source"]}
    for channel in whole.channels:
        assert whole.channel(channel).tobytes() == named.channel(channel).tobytes(), channel
    with pytest.raises(Lf3pmError, match="takes res from its grid"):
        build_solm(boxes, "vlp16", grid, tmp_path / "x.zarr", res=2.0)
    with pytest.raises(ConfigError, match="solm.ray_stride must be greater than or equal to 1"):
        build_solm(boxes, "vlp16", grid, tmp_path / "x.zarr", config, ray_stride=0)

    planner = lf3pm.Planner(whole)
    ends, robot = ((-3.0, -3.0, 0.0), (6.2, 2.8, 0.0)), lf3pm.Robot("diff", r_safe=0.1)
    guided = planner.plan(*ends, robot=robot, guidance=GuidanceConfig(weight=1.0, turn_radius=1.0))
    named_plan = planner.plan(*ends, robot=robot, weight=1.0, turn_radius=1.0)
    assert guided.trajectory.sample(10.0)["x"].tobytes() == named_plan.trajectory.sample(10.0)["x"].tobytes()
    with pytest.raises(ConfigError, match="guidance.weight"):
        planner.plan(*ends, weight=-1.0)

    evaluated = lf3pm.evaluate(boxes, (0.0, 0.0, 0.5, 0.0), "vlp16", config)
    assert evaluated.q_n == lf3pm.evaluate(boxes, (0.0, 0.0, 0.5, 0.0), "vlp16", seed=3).q_n
    assert DEFAULTS.solm.tile == 32 and whole.attrs["tile"] == 32
