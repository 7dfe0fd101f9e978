"""APE / RPE through evo (trajectory_metrics.py) against values worked out by hand."""

import math

import numpy as np
import pytest

from lf3pm.errors import Lf3pmError
from lf3pm.pose import pose_matrix
from lf3pm.replays.trajectory_metrics import ape_translation, error_stats, rpe


def straight(n=11, step=1.0):
    return np.stack([pose_matrix((i * step, 0.0, 1.0, 0.0)) for i in range(n)])


def arc(n=11):
    """Poses along a quarter circle of radius 5 m, heading along it."""
    a = np.linspace(0.0, math.pi / 2, n)
    return np.stack([pose_matrix((5 * math.sin(t), 5 * (1 - math.cos(t)), 1.0, t)) for t in a])


def test_identity_has_zero_errors():
    ref = arc()
    ape = ape_translation(ref, ref)
    assert ape["rmse"] == 0 and ape["max"] == 0 and ape["count"] == 11
    r = rpe(ref, ref)
    assert r["pairs"] == 10 and r["translation"]["max"] < 1e-12 and r["rotation_deg"]["max"] < 1e-6


def test_constant_offset():
    ref = arc()
    est = ref.copy()
    est[:, :3, 3] += [0.3, 0.4, 0.0]  # 0.5 m everywhere
    ape = ape_translation(ref, est)
    assert ape["rmse"] == pytest.approx(0.5) and ape["median"] == pytest.approx(0.5)
    assert ape["std"] == pytest.approx(0.0, abs=1e-12) and ape["errors"] == pytest.approx([0.5] * 11)
    # A constant offset leaves every relative motion intact; alignment removes it.
    assert rpe(ref, est)["translation"]["max"] == pytest.approx(0.0, abs=1e-12)
    aligned = ape_translation(ref, est, align=True)
    assert aligned["max"] == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(np.asarray(aligned["alignment"])[:3, 3], [-0.3, -0.4, 0.0], atol=1e-9)


def test_rotation_drift():
    """The estimate turns by d = 1 degree more than the truth at every 1 m step:
    pose i sits at the same place, with heading i * d."""
    d = math.radians(1.0)
    ref = straight()
    est = np.stack([pose_matrix((i, 0.0, 1.0, i * d)) for i in range(11)])
    r1 = rpe(ref, est, delta=1)
    # By hand: P_i^-1 P_j moves (1, 0, 0); Q_i^-1 Q_j moves Rz(-i d) (1, 0, 0) and turns by d,
    # so the rotation error is d and the translation error |Rz(-i d) e_x - e_x| = 2 sin(i d / 2).
    assert r1["rotation_deg"]["max"] == pytest.approx(1.0, rel=1e-9)
    expected = [2 * math.sin(i * d / 2) for i in range(10)]
    assert r1["translation"]["rmse"] == pytest.approx(math.sqrt(np.mean(np.square(expected))), rel=1e-9)
    # evo's consecutive pairs of 2 frames: (0, 2), (2, 4), ..., (8, 10).
    r2 = rpe(ref, est, delta=2)
    assert r2["pairs"] == 5 and r2["rotation_deg"]["mean"] == pytest.approx(2.0, rel=1e-9)
    assert ape_translation(ref, est)["max"] == pytest.approx(0.0, abs=1e-12)


def test_rpe_pairs_by_path():
    """Steps of 0.4 m: a 1 m pair closes after 3 steps, so pairs (0, 3) and (3, 6);
    a 10 % scale error makes each 1.2 m pair 0.12 m too long."""
    ref = straight(n=7, step=0.4)
    est = ref.copy()
    est[:, 0, 3] *= 1.1
    r = rpe(ref, est, delta=1.0, unit="m")
    assert r["pairs"] == 2 and r["translation"]["mean"] == pytest.approx(0.12)
    # Pairs come from the reference: an estimate twice as long gets the same pairs.
    est[:, 0, 3] *= 2
    assert rpe(ref, est, delta=1.0, unit="m")["pairs"] == 2
    short = rpe(ref[:2], est[:2], delta=1.0, unit="m")
    assert short["pairs"] == 0 and math.isnan(short["translation"]["rmse"])


def test_alignment_recovers_a_known_transform():
    rng = np.random.default_rng(3)
    points = rng.normal(size=(50, 3)) * [10, 5, 1]
    T = pose_matrix((1.0, -2.0, 0.5, 0.7))
    T[:3, :3] = T[:3, :3] @ np.array([[1, 0, 0], [0, math.cos(0.2), -math.sin(0.2)], [0, math.sin(0.2), math.cos(0.2)]])
    moved = points @ T[:3, :3].T + T[:3, 3]
    ref = np.stack([pose_matrix((*p, 0.0)) for p in moved])
    est = np.stack([pose_matrix((*p, 0.0)) for p in points])
    ape = ape_translation(ref, est, align=True)
    assert ape["max"] < 1e-9 and ape_translation(ref, est)["max"] > 1.0
    np.testing.assert_allclose(ape["alignment"], T, atol=1e-9)


def test_collinear_reference_has_no_aligned_figure():
    ref = straight()
    est = ref.copy()
    est[:, 1, 3] += 0.1
    aligned = ape_translation(ref, est, align=True)
    assert math.isnan(aligned["rmse"]) and aligned["alignment"] is None and "line" in aligned["note"]
    assert ape_translation(ref, est)["rmse"] == pytest.approx(0.1)


def test_error_stats_and_bad_input():
    s = error_stats([3.0, 4.0])
    assert s["rmse"] == pytest.approx(math.sqrt(12.5)) and s["std"] == pytest.approx(0.5) and s["count"] == 2
    assert math.isnan(error_stats([])["mean"])
    with pytest.raises(Lf3pmError, match="equal N"):
        ape_translation(straight(3), straight(4))
    with pytest.raises(Lf3pmError, match="at least 2"):
        rpe(straight(1), straight(1))
    with pytest.raises(Lf3pmError, match="integer"):
        rpe(straight(), straight(), delta=1.5)
    with pytest.raises(Lf3pmError, match="unit"):
        rpe(straight(), straight(), unit="s")
