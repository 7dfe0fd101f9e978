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
    c = compare(
        guided,
        unguided,
        guided_length=[11, 10, 12, 10, 10],
        unguided_length=[10] * 5,
        guided_duration=[10] * 5,
        unguided_duration=[8] * 5,
    )
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
    # A pair with one seed on a side is left out of the share, not counted either way.
    assert worse_beyond_noise(guided + [[0.5]], unguided + [[0.1, 0.1]]) == pytest.approx(1 / 3)


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
    assert parse_guidance("weak=q_max:1:3").channel == "q_max"
    for text in ("cube", "x=q_x:1:1", "x=none:1:1", "x=q_n:0:1", "x=q_n:1:-1", "x=q_n:a:1"):
        with pytest.raises(Lf3pmError):
            parse_guidance(text)


def test_quick_study_end_to_end(tmp_path):
    out = tmp_path / "benefit"
    bad = subprocess.run(
        [sys.executable, "-m", "lf3pm.cli", "experiment", "benefit", "--quick", "--lio", "some", "-o", str(out)],
        capture_output=True,
        text=True,
    )
    assert bad.returncode == 2 and "--lio must be 'all' or 'default'" in bad.stderr and not out.exists()
    # The LIO on the default's and the unguided plans only (the full study replays every plan).
    command = [
        sys.executable,
        "-m",
        "lf3pm.cli",
        "experiment",
        "benefit",
        "--quick",
        "--lio",
        "default",
        "-o",
        str(out),
    ]
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
    # What predicts each replay's error: every channel the planner takes, over the plans replayed so.
    cal = summary["calibration"]
    assert set(cal["localization"]) == set(cal["lio"]) == {"q_n", "q_min", "q_max", "step_norm"}
    assert cal["localization"]["q_n"]["plans"] == 10 and cal["lio"]["q_max"]["plans"] == 4
    assert summary["lio_beyond_bound"]["pairs_replayed"] == 2
    # Each LIO replay says whether the odometry held still during its rest, and the
    # comparison from steady starts keeps only the seeds where both plans' did.
    lio_plans = [p["plans"][n]["lio"] for p in summary["pairs"] for n in ("none", "default")]
    assert all(len(plan["rest_steady_per_seed"]) == 1 for plan in lio_plans)
    assert sum(v["replays"] for v in summary["lio_rest"].values()) == len(lio_plans)
    steady_pairs = sum(
        all(p["plans"][n]["lio"]["rest_steady_per_seed"][0] for n in ("none", "default")) for p in summary["pairs"]
    )
    assert summary["comparisons"]["lio_steady"]["default"]["pairs"] == steady_pairs
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
    # Another odometry in the same folder: only the LIO replays it changes are run (GenZ-LIO
    # on the tunnel's VLP-16, beside DLIO's; on the Mid-70 map GenZ-LIO is auto's anyway).
    bad = subprocess.run(command + ["--odometry", "fastlio"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--odometry must be" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1
    other = subprocess.run(command + ["--odometry", "genz"], capture_output=True, text=True)
    assert other.returncode == 0, other.stderr[-2000:]
    assert [p.stat().st_mtime_ns for p in replays] == stamps
    added = sorted(set((out / "replays").rglob("*.json")) - set(replays))
    assert [p.name for p in added] == ["00_default_lio-genz_0.json", "00_none_lio-genz_0.json"]
    assert all(p.parent.name == "tunnel" for p in added)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["lio_odometry"] == {"tunnel": "genz", "orientation": "genz"}
    assert "## LIO (GenZ-LIO: tunnel, orientation)" in (out / "benefit.md").read_text()


def test_a_changed_plan_drops_the_replays_made_of_the_old_one(tmp_path):
    from lf3pm.experiments.replay_tasks import write_plan
    from lf3pm.trajectory.trajectory import Trajectory

    def line(speed):  # one cubic piece along x, 2 s
        c = np.zeros((1, 4, 3))
        c[0, 1, 0] = speed
        return Trajectory(c, np.array([2.0]))

    csv, replays = tmp_path / "trajectories" / "00_omni_default.csv", tmp_path / "replays"
    replays.mkdir()
    names = [
        "00_default_localization_0.json",
        "00_default_lio_2.json",
        "00_default_lio-genz_0.json",  # this plan's
        "00_default_x_lio_0.json",
        "01_default_lio_0.json",
        "00_none_lio_0.json",
    ]  # others'
    write_plan(line(1.0), csv, replays, "00_default_")
    for name in names:
        (replays / name).write_text("{}")
    write_plan(line(1.0), csv, replays, "00_default_")  # the same plan again: replays kept
    assert sorted(p.name for p in replays.iterdir()) == sorted(names)
    write_plan(line(0.5), csv, replays, "00_default_")  # another plan: its old replays go
    assert sorted(p.name for p in replays.iterdir()) == sorted(names[3:])
    assert csv.read_bytes() == line(0.5).csv_bytes()


def test_a_lio_replay_saved_without_its_rest_gets_it_added(tmp_path, monkeypatch):
    """Replays saved before the rest was recorded: run_replays adds it (replay_rest on the
    rest alone) and keeps the rest of the record; a localization replay is left alone."""
    import importlib

    from lf3pm.experiments import replay_tasks

    replay_module = importlib.import_module("lf3pm.replays.replay")  # lf3pm.replays.replay is the function
    from lf3pm.experiments.benefit import QUICK

    rest = {"seconds": 2.0, "drift_m": 0.3, "speed_mps": 0.2, "steady": False}
    calls = []
    monkeypatch.setattr(replay_module, "replay_rest", lambda *a, **k: calls.append((a, k)) or rest)
    monkeypatch.setattr(replay_tasks, "_case_map", lambda case: ("map", None))
    monkeypatch.setattr(replay_tasks, "replay_task", lambda task: pytest.fail(f"replayed {task}"))
    old = {"ape_rmse": 0.5, "scans": 10}
    lio, localization = tmp_path / "00_none_lio_1.json", tmp_path / "00_none_localization_1.json"
    for path in (lio, localization):
        path.write_text(json.dumps(old))
    tasks = [
        replay_tasks.ReplayTask(QUICK[1], "plan.csv", "lio", 1, lio, {"odometry": "genz"}),
        replay_tasks.ReplayTask(QUICK[1], "plan.csv", "localization", 1, localization),
    ]
    replay_tasks.run_replays(tasks, 1, lambda *a, **k: None)
    assert json.loads(lio.read_text()) == {**old, "rest": rest}
    assert json.loads(localization.read_text()) == old
    assert calls == [(("map", "plan.csv", QUICK[1].sensor, 1), {"threads": 1, "odometry": "genz"})]
    replay_tasks.run_replays(tasks, 1, lambda *a, **k: None)  # nothing left to do
    assert len(calls) == 1


def test_localization_error_fit_counts_its_own_phase(tmp_path):
    """The fit's progress is a phase of its own (restarted at zero, one step per plan),
    not a continuation of the replays' count; saved predictors are read, not recomputed."""
    from types import SimpleNamespace

    from lf3pm.experiments.localization_error import localization_error_fit

    case = SimpleNamespace(name="m", sensor="vlp16")
    records = [
        {
            "case": "m",
            "pair": k,
            "plans": {g: {"csv": "unused.csv", "localization": {"ape": 0.01}} for g in ("none", "default")},
        }
        for k in range(2)
    ]
    for pair in records:
        for name in pair["plans"]:
            path = tmp_path / "predictors" / "m" / f"{pair['pair']:02d}_{name}.json"
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps({"q_n_mean": 0.1, "degenerate_share": 0.0, "poses": 10}))
    calls = []
    localization_error_fit(
        tmp_path,
        [case],
        records,
        seeds=1,
        pair_seed=0,
        step=lambda label, total, advance=1, restart=False: calls.append((total, advance, restart)),
    )
    assert calls[0] == (4, 0, True)
    assert sum(advance for _, advance, _ in calls) == 4 and not any(restart for *_, restart in calls[1:])
    assert (tmp_path / "localization_error.json").is_file()


def test_goal_is_not_judged_without_seed_noise():
    """With one seed per replay "worse beyond seed noise" is NaN: the goal on it is None
    (the report says n/a), not a failure; with seeds it is judged."""
    from lf3pm.experiments.benefit import STEADY, _goal

    def comparisons(worse):
        safe = {
            "pairs": 10,
            "median_ratio": 1.0,
            "median_ratio_ci95": (0.97, 1.03),
            "share_worse_beyond_noise_and_margin": worse,
        }
        by_risk = {"by_risk": {"default": {"no_risk": safe}}}
        return {
            "localization": {**by_risk, "default": {"pairs": 10, "median_length_overhead": 0.01}},
            "lio": by_risk,
            STEADY: by_risk,
        }

    assert _goal(comparisons(math.nan))["lio_no_risk_worse_on_at_most_10pct"] is None
    assert _goal(comparisons(0.05))["lio_no_risk_worse_on_at_most_10pct"] is True
    assert _goal(comparisons(0.2))["localization_no_risk_worse_on_at_most_10pct"] is False


def test_lio_beyond_bound_lists_the_default_plans_past_it():
    """Only pairs with both plans replayed by the LIO count; a default-guided plan past the
    bound is listed with its unguided plan's error, one within it is not."""
    from lf3pm.experiments.benefit import LIO_BOUND, lio_beyond_bound

    def pair(number, guided, unguided, lio=True):
        plans = {"none": {"lio": {"ape": unguided}}, "default": {"lio": {"ape": guided}}}
        if not lio:
            plans = {name: {} for name in plans}
        return {"case": "m", "pair": number, "robot": "omni", "at_risk": False, "plans": plans}

    out = lio_beyond_bound([pair(0, LIO_BOUND + 0.01, 0.05), pair(1, LIO_BOUND - 0.01, 2.0), pair(2, 5.0, 5.0, False)])
    assert out["pairs_replayed"] == 2 and out["bound_m"] == LIO_BOUND
    assert [(b["pair"], b["guided_m"], b["unguided_m"]) for b in out["pairs"]] == [(0, LIO_BOUND + 0.01, 0.05)]
