"""The planner's ESDF: never above the exact signed distance to the blocked squares
(brute force over every square, at seeded random points anywhere in the plane, as
read by Python and by the optimiser's GridField), and not far below it."""

import numpy as np
import pytest

import lf3pm.planner.esdf as esdf_module
from lf3pm.grid_field import GridField
from lf3pm.planner.esdf import Esdf


def box_distance(cells, x0, y0, res, px, py):
    """(points,) distance from each point to the nearest of the closed squares at
    the (iy, ix) ``cells``; +inf when there are none."""
    if len(cells) == 0:
        return np.full(px.shape, np.inf)
    lo_x, lo_y = x0 + cells[:, 1] * res, y0 + cells[:, 0] * res
    dx = np.maximum(np.maximum(lo_x[None] - px[:, None], px[:, None] - lo_x[None] - res), 0.0)
    dy = np.maximum(np.maximum(lo_y[None] - py[:, None], py[:, None] - lo_y[None] - res), 0.0)
    return np.hypot(dx, dy).min(axis=1)


def signed_distance(blocked, x0, y0, res, px, py):
    """Exact signed distance to the union of blocked squares in the plane: outside,
    the distance to it; inside, minus the distance to what is not blocked (the free
    squares and everything beyond the grid)."""
    ny, nx = blocked.shape
    outside = box_distance(np.argwhere(blocked), x0, y0, res, px, py)
    to_edge = np.minimum.reduce([px - x0, x0 + nx * res - px, py - y0, y0 + ny * res - py])
    inside = np.minimum(box_distance(np.argwhere(~blocked), x0, y0, res, px, py), np.maximum(to_edge, 0.0))
    return np.where(outside > 0, outside, -inside)


def query_points(rng, shape, x0, y0, res):
    """Points over the grid and a cell beyond it, near and exactly on grid
    vertices, exactly on centres and on cell edges, in metres."""
    ny, nx = shape
    vx, vy = rng.integers(0, nx + 1, 600), rng.integers(0, ny + 1, 600)
    cx, cy = rng.integers(0, nx, 300) + 0.5, rng.integers(0, ny, 300) + 0.5
    u = np.concatenate(
        [rng.uniform(-1, nx + 1, 3000), vx + rng.normal(0, 0.03, 600), vx[:200], cx, rng.integers(0, nx + 1, 300)]
    )
    v = np.concatenate(
        [rng.uniform(-1, ny + 1, 3000), vy + rng.normal(0, 0.03, 600), vy[:200], cy, rng.uniform(0, ny, 300)]
    )
    return x0 + u * res, y0 + v * res


def random_mask(rng):
    ny, nx = rng.integers(1, 13, 2)
    return rng.random((ny, nx)) < rng.uniform(0.05, 0.6)


@pytest.mark.parametrize("seed", range(12))
def test_field_never_exceeds_the_exact_signed_distance(seed):
    rng = np.random.default_rng(seed)
    mask = random_mask(rng)
    unknown = (rng.random(mask.shape) < 0.1) & ~mask
    x0, y0, res = rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(0.1, 2.0)
    px, py = query_points(rng, mask.shape, x0, y0, res)
    for policy in ("obstacle", "free"):
        esdf = Esdf.from_mask(mask, x0, y0, res, unknown=unknown, unknown_policy=policy)
        blocked = mask | unknown if policy == "obstacle" else mask
        exact = signed_distance(blocked, x0, y0, res, px, py)
        value = esdf.distance(px, py)[0]
        assert np.all(value <= exact + 1e-9)
        if np.isfinite(esdf.values).all():  # the optimiser's view of the same values
            sampled = GridField(esdf.values, x0, y0, res).sample(px, py)[0]
            assert np.all(sampled <= exact + 1e-9)
        np.testing.assert_array_equal(esdf.traversable(0.0), ~blocked & (esdf.values >= 0.0))
        ix, iy = rng.integers(0, mask.shape[1]), rng.integers(0, mask.shape[0])
        at_centre = esdf.distance(x0 + (ix + 0.5) * res, y0 + (iy + 0.5) * res)[0]
        assert at_centre == pytest.approx(esdf.values[iy, ix])


def test_bound_holds_on_a_coarser_lattice_and_on_one_row_or_column(monkeypatch):
    # Large grids get fewer lattice points per cell; thin grids interpolate along one axis.
    rng = np.random.default_rng(20)
    for shape, max_lattice in (((9, 11), 500), ((9, 11), 3000), ((1, 15), 1 << 22), ((13, 1), 1 << 22)):
        monkeypatch.setattr(esdf_module, "_MAX_LATTICE", max_lattice)
        mask = rng.random(shape) < 0.3
        mask.flat[0], mask.flat[-1] = True, False
        px, py = query_points(rng, shape, 0.0, 0.0, 1.0)
        value = Esdf.from_mask(mask, 0.0, 0.0, 1.0).distance(px, py)[0]
        assert np.all(value <= signed_distance(mask, 0.0, 0.0, 1.0, px, py) + 1e-9)


def test_field_is_tight():
    # A field one cell lower would miss every bound here.
    rng = np.random.default_rng(30)
    centres_free, near = [], []
    for _ in range(10):
        mask = random_mask(rng)
        if mask.all() or not mask.any():
            continue
        ny, nx = mask.shape
        esdf = Esdf.from_mask(mask, 0.0, 0.0, 1.0)
        cy, cx = np.mgrid[0:ny, 0:nx] + 0.5
        exact = signed_distance(mask, 0.0, 0.0, 1.0, cx.ravel(), cy.ravel()).reshape(mask.shape)
        centres_free.append((exact - esdf.values)[~mask])
        px, py = rng.uniform(0.5, nx - 0.5, 3000), rng.uniform(0.5, ny - 0.5, 3000)
        exact = signed_distance(mask, 0.0, 0.0, 1.0, px, py)
        keep = (exact > 0) & (exact < 2.0)
        near.append(exact[keep] - esdf.distance(px[keep], py[keep])[0])
    centres_free, near = np.concatenate(centres_free), np.concatenate(near)
    assert centres_free.max() < 0.4 and centres_free.mean() < 0.15
    assert near.mean() < 0.25 and np.median(near) < 0.2


def test_a_straight_wall_is_almost_exact():
    mask = np.zeros((12, 16), bool)
    mask[:, :5] = True
    esdf = Esdf.from_mask(mask, 0.0, 0.0, 0.5)
    y = np.linspace(2.0, 4.0, 50)  # away from the grid's top and bottom rows
    for x in (2.6, 2.75, 3.3, 4.1):
        value = esdf.distance(np.full_like(y, x), y)[0]
        assert np.all(value <= x - 2.5 + 1e-12) and np.all(value > x - 2.5 - 0.02)


def test_field_without_obstacles_is_infinite():
    esdf = Esdf.from_mask(np.zeros((3, 4), bool), 0, 0, 1.0)
    value, grad = esdf.distance([0.3, 2.0], [1.0, 1.5])
    assert np.all(value == np.inf) and np.all(grad == 0) and esdf.traversable(5.0).all()
    esdf = Esdf.from_mask(np.ones((3, 4), bool), 0, 0, 1.0)
    value, grad = esdf.distance([0.3, 2.0], [1.0, 1.5])
    assert np.all(value == -np.inf) and np.all(grad == 0) and not esdf.traversable().any()


def test_bilinear_gradient_matches_finite_differences():
    rng = np.random.default_rng(4)
    mask = rng.random((15, 20)) < 0.15
    esdf = Esdf.from_mask(mask, -1.0, 2.0, 0.4)
    x = rng.uniform(-1.0 + 0.2, -1.0 + 20 * 0.4 - 0.2, 50)
    y = rng.uniform(2.0 + 0.2, 2.0 + 15 * 0.4 - 0.2, 50)
    value, grad = esdf.distance(x, y)
    h = 1e-6
    num = np.stack(
        [
            (esdf.distance(x + h, y)[0] - esdf.distance(x - h, y)[0]) / (2 * h),
            (esdf.distance(x, y + h)[0] - esdf.distance(x, y - h)[0]) / (2 * h),
        ],
        axis=-1,
    )
    assert value.shape == (50,) and grad.shape == (50, 2)
    np.testing.assert_allclose(grad, num, atol=1e-5)
    assert np.abs(grad).max() > 0.1  # the field is not flat where sampled
