"""The fast metric (Gram of [A|b]) against the float64 reference from the definitions."""

import numpy as np
import pytest
from reference_metric import reference_metric

from lf3pm import _core

KEYS = ("sigma1", "xi", "q_min", "q_n", "q_max", "zhang", "condition_number", "cov_trace", "step_norm", "residual_norm")


def weights(w1):
    out = _core.MetricWeights()
    out.w1 = w1
    return out


def fast_metric(A, b, w1=0.5):
    return _core.metric_from_gram(
        _core.gram(np.ascontiguousarray(A), np.ascontiguousarray(b)), len(b), weights(w1)
    ).as_dict()


def lidar_like(rng, m, n, lever=20.0):
    """Rows like point-to-plane observations: unit normals and lever arms."""
    u = rng.normal(size=(m, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    w = rng.uniform(-lever, lever, size=(m, 3))
    rows = np.hstack([u, np.cross(w, u)])
    if n == 3:
        rows = rows[:, [0, 1, 5]]
    return rows


def ill_conditioned(rng, m, n, cond):
    """A with singular values spread log-uniformly over [1, cond]."""
    q1, _ = np.linalg.qr(rng.normal(size=(m, n)))
    q2, _ = np.linalg.qr(rng.normal(size=(n, n)))
    s = np.logspace(0, np.log10(cond), n)
    return q1 @ np.diag(s) @ q2.T


CASES = []
for seed in range(8):
    for n in (3, 6):
        CASES.append(("random", seed, n, 50 + 37 * seed))
        CASES.append(("lidar", seed, n, 200 + 100 * seed))
        CASES.append(("ill", seed, n, 40 + 10 * seed))
    CASES.append(("minimal", seed, 6, 7))  # m = n + 1: lambda_1 is not zero
    CASES.append(("minimal", seed, 3, 4))


@pytest.mark.slow
@pytest.mark.parametrize("kind,seed,n,m", CASES)
def test_fast_metric_matches_reference(kind, seed, n, m):
    rng = np.random.default_rng(seed)
    if kind == "random" or kind == "minimal":
        A = rng.normal(size=(m, n))
    elif kind == "lidar":
        A = lidar_like(rng, m, n)
    else:
        A = ill_conditioned(rng, m, n, cond=10.0 ** (1 + seed % 3))
    b = rng.normal(scale=0.05, size=m) + A @ rng.normal(scale=0.01, size=n)
    w1 = 0.2 + 0.1 * (seed % 6)
    ref = reference_metric(A, b, w1, 1 - w1)
    got = fast_metric(A, b, w1)
    assert not got["degenerate"]
    for key in KEYS:
        assert got[key] == pytest.approx(ref[key], rel=1e-9), key


def test_q_ordering_and_zhang_relation():
    rng = np.random.default_rng(3)
    A = lidar_like(rng, 500, 6)
    b = rng.normal(scale=0.02, size=500)
    got = fast_metric(A, b)
    assert got["q_min"] <= got["q_n"] <= got["q_max"]
    # q_min = sqrt(w2) / sigma1 when m > n + 1: Zhang's factor up to scale.
    assert got["q_min"] == pytest.approx(np.sqrt(0.5) / np.sqrt(got["zhang"]), rel=1e-12)


def test_adding_rows_never_raises_q_min():
    rng = np.random.default_rng(11)
    A = lidar_like(rng, 300, 6)
    b = rng.normal(scale=0.03, size=300)
    previous = fast_metric(A[:20], b[:20])
    for end in range(40, 301, 20):
        now = fast_metric(A[:end], b[:end])
        assert now["sigma1"] >= previous["sigma1"] * (1 - 1e-12)
        assert now["q_min"] <= previous["q_min"] * (1 + 1e-12)
        previous = now


def test_grams_of_disjoint_rows_add():
    rng = np.random.default_rng(5)
    A = lidar_like(rng, 400, 6)
    b = rng.normal(size=400)
    g = _core.gram(A, b)
    g_split = _core.gram(A[:150].copy(), b[:150].copy()) + _core.gram(A[150:].copy(), b[150:].copy())
    np.testing.assert_allclose(g, g_split, rtol=1e-12)
    M = np.hstack([A, b[:, None]])
    np.testing.assert_allclose(g, M.T @ M, rtol=1e-12)


@pytest.mark.parametrize("m", [0, 1, 5, 6])
def test_too_few_rows_are_degenerate_not_nan(m):
    rng = np.random.default_rng(m)
    A = rng.normal(size=(m, 6))
    b = rng.normal(size=m)
    got = fast_metric(A, b) if m else _core.metric_from_gram(np.zeros((7, 7)), 0).as_dict()
    assert got["degenerate"]
    for key in ("q_min", "q_n", "q_max"):
        assert got[key] == np.inf


def test_rank_deficient_is_degenerate():
    # A wall: every normal along x; translation along y, z is unobservable.
    rng = np.random.default_rng(2)
    m = 200
    u = np.tile([1.0, 0.0, 0.0], (m, 1))
    w = rng.uniform(-5, 5, size=(m, 3))
    A = np.hstack([u, np.cross(w, u)])
    got = fast_metric(A, rng.normal(scale=0.01, size=m))
    assert got["degenerate"] and got["q_n"] == np.inf
    assert not np.isnan(list(v for k, v in got.items() if isinstance(v, float))).any()


def test_non_finite_input_is_an_error():
    g = np.eye(7)
    g[0, 0] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        _core.metric_from_gram(g, 100)


@pytest.mark.parametrize("w1", [0.0, 1.0, -0.5, np.nan])
def test_bad_weights_are_an_error(w1):
    with pytest.raises(ValueError, match="w1"):
        _core.metric_from_gram(np.eye(7), 100, weights(w1))
