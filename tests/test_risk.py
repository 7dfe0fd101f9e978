"""The benefit study's at-risk rule (experiments/risk.py), decided from the unguided
plan and its SOLM alone, on SOLMs and plans built for it."""

import math

import numpy as np
import pytest

from lf3pm.experiments.risk import AT_RISK_SHARE, RISK_FACTOR, at_risk, map_median, risk_share
from lf3pm.solm.grid import SolmGrid


class FakeSolm:
    """A SOLM's reading interface over arrays: q_n and the degenerate mask."""

    def __init__(self, grid, q_n, degenerate):
        self.grid_spec, self._channels = grid, {"q_n": q_n, "degenerate": degenerate}

    def channel(self, name):
        return self._channels[name]


class Line:
    """A trajectory along y = ``y`` from x = 0 to x = 10 at 1 m/s, heading ``yaw``."""

    def __init__(self, y, yaw=0.0):
        self.y, self.yaw = y, yaw

    def sample(self, rate):
        t = np.arange(0.0, 10.0 + 1e-9, 1.0 / rate)
        return {"t": t, "x": t, "y": np.full_like(t, self.y), "yaw": np.full_like(t, self.yaw)}


@pytest.fixture
def r2():
    """10 x 10 cells of 1 m, q_n 1 everywhere but row y in [7, 8) where cells x in [2, 5)
    predict 20x the median and the cell at x in [5, 6) is degenerate."""
    grid = SolmGrid("r2", 0.0, 0.0, 1.0, 10, 10)
    q = np.ones((10, 10))
    q[7, 2:5] = RISK_FACTOR * 2.0
    q[0, 0] = np.nan  # not evaluated
    degenerate = np.zeros((10, 10), bool)
    degenerate[7, 5] = True
    return FakeSolm(grid, q, degenerate)


def test_a_plan_through_the_bad_cells_is_at_risk_and_one_beside_them_is_not(r2):
    assert map_median(r2) == 1.0
    through = risk_share(r2, Line(7.5))  # x in [2, 6): 4 m of 10 at risk (samples 20..59 of 101)
    assert through == pytest.approx(40 / 101)
    assert at_risk(through)
    beside = risk_share(r2, Line(5.5))
    assert beside == 0.0 and not at_risk(beside)


def test_the_threshold_is_relative_to_the_map_median(r2):
    """Below RISK_FACTOR x the median a cell is not at risk; scaling the whole map does not change the verdict."""
    r2.channel("q_n")[7, 2:5] = 0.99 * RISK_FACTOR
    assert risk_share(r2, Line(7.5)) == pytest.approx(10 / 101)  # the degenerate cell only
    scaled = FakeSolm(r2.grid_spec, r2.channel("q_n") * 1e3, r2.channel("degenerate"))
    assert risk_share(scaled, Line(7.5)) == risk_share(r2, Line(7.5))
    assert not at_risk(AT_RISK_SHARE - 1e-9) and at_risk(AT_RISK_SHARE)


def test_se2_uses_the_plans_yaw_and_the_best_heading_as_the_maps_median():
    """The same place is at risk facing one way and safe facing the other (the nearest yaw
    bin, periodic); on a map where three headings of four are bad everywhere, the map's
    median is the best heading's, so the bad ones are at risk."""
    grid = SolmGrid("se2", 0.0, 0.0, 1.0, 10, 10, yaw_bins=4)
    q = np.full((4, 10, 10), RISK_FACTOR * 1.5)
    q[0] = 1.0
    q[2] = math.inf  # facing -x: degenerate by q_n = inf
    solm = FakeSolm(grid, q, np.zeros((4, 10, 10), bool))
    assert map_median(solm) == 1.0
    assert risk_share(solm, Line(3.5, yaw=math.pi / 2)) == 1.0
    assert risk_share(solm, Line(3.5, yaw=math.pi)) == 1.0
    assert risk_share(solm, Line(3.5, yaw=-math.pi + 0.3)) == 1.0
    assert risk_share(solm, Line(3.5, yaw=0.0)) == 0.0
    assert risk_share(solm, Line(3.5, yaw=2 * math.pi - 0.2)) == 0.0


def test_grid_cells_are_the_nearest_and_clamped():
    grid = SolmGrid("se2", -1.0, 2.0, 0.5, 4, 6, yaw_bins=8)
    k, iy, ix = grid.cell([-1.0, -0.76, 5.0], [2.0, 2.49, -3.0], [0.0, 0.4, -0.4])
    np.testing.assert_array_equal(ix, [0, 0, 3])
    np.testing.assert_array_equal(iy, [0, 0, 0])
    np.testing.assert_array_equal(k, [0, 1, 7])
    r3 = SolmGrid("r3", 0.0, 0.0, 1.0, 2, 2, z_levels=(0.5, 1.0, 1.5))
    assert r3.cell(0.5, 0.5, 1.2)[0] == 1
