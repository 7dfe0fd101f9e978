"""The benefit study: its paired statistics against scipy and by hand, guidance
parsing, and `lf3pm experiment benefit --quick` end to end."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from scipy.stats import wilcoxon

from lf3pm.errors import Lf3pmError
from lf3pm.experiments.guidance import parse_guidance
from lf3pm.experiments.paired_stats import compare, median_ratio_ci, worse_beyond_noise


def test_paired_comparison_by_hand():
    guided = np.array([0.01, 0.02, 0.5, 0.04, 2.0])
    unguided = np.array([0.1, 0.01, 1.0, 0.4, 4.0])
    c = compare(guided, unguided, guided_length=[11, 10, 12, 10, 10], unguided_length=[10] * 5,
                guided_duration=[10] * 5, unguided_duration=[8] * 5)
    ratios = guided / unguided  # 0.1, 2, 0.5, 0.1, 0.5
    assert c["pairs"] == 5 and c["median_ratio"] == pytest.approx(np.median(ratios))
    assert c["share_worse"] == pytest.approx(0.2)
    assert c["failure_rate_guided"] == pytest.approx(0.2) and c["failure_rate_unguided"] == pytest.approx(0.2)
    assert c["median_length_overhead"] == pytest.approx(0.0) and c["median_duration_overhead"] == pytest.approx(0.25)
    assert c["wilcoxon_p"] == pytest.approx(wilcoxon(np.log(guided) - np.log(unguided)).pvalue)
    lo, hi = c["median_ratio_ci95"]
    assert lo <= c["median_ratio"] <= hi


def test_worse_beyond_noise_needs_a_difference_larger_than_the_seeds_spread():
    # Pair 1: worse by 0.02 with a spread of 0.001 (beyond noise); pair 2: worse by 0.002
    # with a spread of 0.01 (within it); pair 3: better.
    guided = [[0.051, 0.052, 0.050], [0.03, 0.02, 0.04], [0.01, 0.011, 0.012]]
    unguided = [[0.031, 0.030, 0.032], [0.028, 0.018, 0.038], [0.1, 0.2, 0.15]]
    assert worse_beyond_noise(guided, unguided) == pytest.approx(1 / 3)
    assert math.isnan(worse_beyond_noise([[0.1]], [[0.2]]))  # one seed: no spread to compare with


def test_bootstrap_interval_is_seeded_and_covers_the_median():
    rng = np.random.default_rng(0)
    ratios = np.exp(rng.normal(-1.0, 0.5, 60))
    a, b = median_ratio_ci(ratios, seed=3), median_ratio_ci(ratios, seed=3)
    assert a == b and a[0] < np.median(ratios) < a[1]
    assert median_ratio_ci(ratios, seed=4) != a
    # A narrower interval with more pairs from the same distribution.
    wide = np.subtract(*median_ratio_ci(ratios[:15], seed=3)[::-1])
    assert np.subtract(*a[::-1]) < wide


def test_bad_comparisons_and_guidance_are_one_line_errors():
    with pytest.raises(Lf3pmError, match="positive"):
        compare([0.0, 1.0], [1.0, 1.0])
    with pytest.raises(Lf3pmError, match="equal-length"):
        compare([1.0], [1.0, 2.0])
    assert parse_guidance("cube=q_min:3:2").power == 3.0
    for text in ("cube", "x=q_x:1:1", "x=q_n:0:1", "x=q_n:1:-1", "x=q_n:a:1"):
        with pytest.raises(Lf3pmError):
            parse_guidance(text)


def test_quick_study_end_to_end(tmp_path):
    out = tmp_path / "benefit"
    bad = subprocess.run([sys.executable, "-m", "lf3pm.cli", "experiment", "benefit", "--quick", "--lio", "some",
                          "-o", str(out)], capture_output=True, text=True)
    assert bad.returncode == 2 and "--lio must be 'all' or 'default'" in bad.stderr and not out.exists()
    # The LIO on the default's and the unguided plans only (the full study replays every plan).
    command = [sys.executable, "-m", "lf3pm.cli", "experiment", "benefit", "--quick", "--lio", "default", "-o", str(out)]
    run = subprocess.run(command, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["pairs"]) == 2 and {p["case"] for p in summary["pairs"]} == {"tunnel", "orientation"}
    for pair in summary["pairs"]:
        assert set(pair["plans"]) == {"none", "q_n", "q_min", "step_norm", "default"}
        for name, plan in pair["plans"].items():
            assert math.isfinite(plan["localization"]["ape"])
            assert ("lio" in plan) == (name in ("none", "default"))
    assert summary["lio_guidance"] == ["none", "default"]
    loc = summary["comparisons"]["localization"]
    assert loc["default"]["pairs"] == 2 and set(loc["default_by_map"]) == {"tunnel", "orientation"}
    # In the tunnel the unguided plans drive through the degenerate passage and the guided
    # ones take the structured lane: guidance must localize better there.
    tunnel = [p for p in summary["pairs"] if p["case"] == "tunnel"]
    for pair in tunnel:
        assert pair["plans"]["default"]["localization"]["ape"] < pair["plans"]["none"]["localization"]["ape"]
    for name in ("benefit.md", "scatter.png", "ratios.png", "examples/tunnel.png", "examples/orientation.png"):
        assert (out / name).stat().st_size > 0
    # A rerun resumes: every replay is on disk, nothing is recomputed.
    replays = sorted((out / "replays").rglob("*.json"))
    stamps = [p.stat().st_mtime_ns for p in replays]
    again = subprocess.run(command, capture_output=True, text=True)
    assert again.returncode == 0 and [p.stat().st_mtime_ns for p in replays] == stamps


def test_a_changed_plan_drops_the_replays_made_of_the_old_one(tmp_path):
    from lf3pm.experiments.replay_tasks import write_plan
    from lf3pm.trajectory.trajectory import Trajectory

    def line(speed):  # one cubic piece along x, 2 s
        c = np.zeros((1, 4, 3))
        c[0, 1, 0] = speed
        return Trajectory(c, np.array([2.0]))

    csv, replays = tmp_path / "trajectories" / "00_omni_default.csv", tmp_path / "replays"
    replays.mkdir()
    names = ["00_default_localization_0.json", "00_default_lio_2.json",    # this plan's
             "00_default_x_lio_0.json", "01_default_lio_0.json", "00_none_lio_0.json"]  # others'
    write_plan(line(1.0), csv, replays, "00_default_")
    for name in names:
        (replays / name).write_text("{}")
    write_plan(line(1.0), csv, replays, "00_default_")  # the same plan again: replays kept
    assert sorted(p.name for p in replays.iterdir()) == sorted(names)
    write_plan(line(0.5), csv, replays, "00_default_")  # another plan: its old replays go
    assert sorted(p.name for p in replays.iterdir()) == sorted(names[2:])
    assert csv.read_bytes() == line(0.5).csv_bytes()
