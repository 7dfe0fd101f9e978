"""Quintic MINCO in (x, y, z, yaw) (cpp/lf3pm/trajectory/minco_s3.hpp; issue 43, item 3):
its conditions hold, it is the minimum-jerk trajectory (against the KKT system of the
constrained quadratic programme solved densely in float64), and its gradients are those of
the map (q, T) -> c against finite differences."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lf3pm import _core


def basis(t, order):
    return np.array([math.perm(k, order) * t ** (k - order) if k >= order else 0.0 for k in range(6)])


def problem(seed, pieces):
    rng = np.random.default_rng(seed)
    head = rng.normal(size=(4, 3))
    tail = rng.normal(size=(4, 3))
    q = rng.normal(size=(4, pieces - 1)) * 2
    T = rng.uniform(0.5, 2.0, pieces)
    return head, tail, q, T


def coefficients(head, tail, q, T, weights=np.ones(4)):
    return _core.minco_s3(head, tail, q, T, weights)["coefficients"].reshape(len(T), 6, 4)


@pytest.mark.parametrize("pieces", [1, 2, 5])
def test_the_conditions_hold_and_the_junctions_are_c4(pieces):
    head, tail, q, T = problem(pieces, pieces)
    c = coefficients(head, tail, q, T)
    for d in range(3):
        np.testing.assert_allclose(basis(0.0, d) @ c[0], head[:, d], atol=1e-10)
        np.testing.assert_allclose(basis(T[-1], d) @ c[-1], tail[:, d], atol=1e-9)
    for i in range(pieces - 1):
        np.testing.assert_allclose(basis(T[i], 0) @ c[i], q[:, i], atol=1e-9)
        for d in range(5):
            np.testing.assert_allclose(basis(T[i], d) @ c[i], basis(0.0, d) @ c[i + 1], atol=1e-8)


def jerk_hessian(t):
    """The quadratic form of int_0^t (p''')^2 over the six coefficients."""
    H = np.zeros((6, 6))
    for a in range(3, 6):
        for b in range(3, 6):
            fa, fb = math.perm(a, 3), math.perm(b, 3)
            H[a, b] = fa * fb * t ** (a + b - 5) / (a + b - 5)
    return 2 * H


def test_it_is_the_minimum_jerk_trajectory_through_the_waypoints():
    """The quadratic programme: piecewise quintics, C2 at the junctions (no more), through the
    waypoints, with the head and tail states; its KKT system solved densely per dimension
    gives MINCO's coefficients, whose C4 continuity is then the optimality condition."""
    pieces = 4
    head, tail, q, T = problem(11, pieces)
    c = coefficients(head, tail, q, T)
    n = 6 * pieces
    H = np.zeros((n, n))
    for i in range(pieces):
        H[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] = jerk_hessian(T[i])
    for dim in range(4):
        rows, rhs = [], []

        def row(i, t, d, value, j=None):
            r = np.zeros(n)
            r[6 * i : 6 * i + 6] = basis(t, d)
            if j is not None:
                r[6 * j : 6 * j + 6] -= basis(0.0, d)
            rows.append(r)
            rhs.append(value)

        for d in range(3):
            row(0, 0.0, d, head[dim, d])
            row(pieces - 1, T[-1], d, tail[dim, d])
        for i in range(pieces - 1):
            row(i, T[i], 0, q[dim, i])
            for d in range(3):
                row(i, T[i], d, 0.0, i + 1)
        A = np.array(rows)
        kkt = np.block([[H, A.T], [A, np.zeros((len(A), len(A)))]])
        solution = np.linalg.solve(kkt, np.concatenate([np.zeros(n), rhs]))[:n]
        np.testing.assert_allclose(c[:, :, dim].ravel(), solution, rtol=1e-7, atol=1e-7)


def test_the_energy_and_its_gradients_are_those_of_the_map():
    pieces = 3
    head, tail, q, T = problem(5, pieces)
    w = np.array([1.0, 1.0, 2.0, 0.5])
    rng = np.random.default_rng(2)
    gc = rng.normal(size=(6 * pieces, 4))
    gt = rng.normal(size=pieces)
    out = _core.minco_s3(head, tail, q, T, w, gc, gt)

    def cost(q_, T_):
        """A linear cost of the coefficients and durations, plus the weighted jerk energy."""
        o = _core.minco_s3(head, tail, q_, T_, w)
        return float(np.sum(gc * o["coefficients"]) + gt @ T_), o["jerk_energy"]

    h = 1e-6
    for i in range(4):
        for j in range(pieces - 1):
            up, dn = q.copy(), q.copy()
            up[i, j] += h
            dn[i, j] -= h
            assert out["grad_q"][i, j] == pytest.approx((cost(up, T)[0] - cost(dn, T)[0]) / (2 * h), rel=1e-6, abs=1e-6)
    for i in range(pieces):
        up, dn = T.copy(), T.copy()
        up[i] += h
        dn[i] -= h
        assert out["grad_T"][i] == pytest.approx((cost(q, up)[0] - cost(q, dn)[0]) / (2 * h), rel=1e-6, abs=1e-6)
    # The energy's partial gradients: by c (the quadratic form) and by T (the integrand at T).
    c = out["coefficients"]
    e = out["jerk_energy"]
    total = 0.0
    for i in range(pieces):
        total += sum(
            w[d] * c[6 * i : 6 * i + 6, d] @ (0.5 * jerk_hessian(T[i])) @ c[6 * i : 6 * i + 6, d] for d in range(4)
        )
    assert e == pytest.approx(total, rel=1e-12)
    for i in range(pieces):
        H = jerk_hessian(T[i])
        for d in range(4):
            np.testing.assert_allclose(
                out["energy_grad_c"][6 * i : 6 * i + 6, d], w[d] * H @ c[6 * i : 6 * i + 6, d], rtol=1e-10, atol=1e-9
            )
        jerk = np.array([basis(T[i], 3) @ c[6 * i : 6 * i + 6, d] for d in range(4)])
        assert out["energy_grad_t"][i] == pytest.approx(float(w @ jerk**2), rel=1e-10)
