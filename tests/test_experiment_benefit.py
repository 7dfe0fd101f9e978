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
    assert c.pairs == 5 and c.median_ratio == pytest.approx(np.median(ratios))
    assert c.share_worse == pytest.approx(0.2)
    assert c.failure_rate_guided == pytest.approx(0.2) and c.failure_rate_unguided == pytest.approx(0.2)
    assert c.median_length_overhead == pytest.approx(0.0) and c.median_duration_overhead == pytest.approx(0.25)
    assert c.wilcoxon_p == pytest.approx(wilcoxon(np.log(guided) - np.log(unguided)).pvalue)
    lo, hi = c.median_ratio_ci95
    assert lo <= c.median_ratio <= hi


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


@pytest.mark.slow
def test_quick_study_end_to_end(tmp_path):
    from lf3pm.experiments.benefit.records import LIO, LOCALIZATION, MEASURES, Measure, read_summary

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
    raw = json.loads((out / "summary.json").read_text())
    summary = read_summary(out / "summary.json")
    assert summary.to_json() == raw or json.dumps(summary.to_json()) == json.dumps(raw)  # NaN != NaN
    # The run's protocol, beside its summary, which carries its digest (test_benefit_protocol.py).
    from lf3pm.experiments.benefit.protocol import read_protocol

    assert read_protocol(out / "protocol.yaml").digest() == raw["protocol_sha256"] == summary.protocol_sha256
    assert f"sha256 {raw['protocol_sha256']}" in (out / "benefit.md").read_text()
    assert len(summary.pairs) == 2 and {p.case for p in summary.pairs} == {"tunnel", "orientation"}
    for pair in summary.pairs:
        assert set(pair.plans) == {"none", "q_n", "q_min", "step_norm", "default"}
        for name, plan in pair.plans.items():
            assert math.isfinite(plan.replays[LOCALIZATION].ape)
            assert (LIO in plan.replays) == (name in ("none", "default"))
            assert plan.q_n_exact is not None and plan.q_n_exact.poses > 0
    assert summary.lio_guidance == ("none", "default")
    # What predicts each replay's error: every channel the planner takes, over the plans replayed so.
    cal = summary.calibration
    assert set(cal[LOCALIZATION]) == set(cal[LIO]) == {"q_n", "q_min", "q_max", "step_norm"}
    assert cal[LOCALIZATION]["q_n"].plans == 10 and cal[LIO]["q_max"].plans == 4
    assert summary.lio_beyond_bound.pairs_replayed == 2
    # Each LIO replay says whether the odometry held still during its rest, and the
    # comparison from steady starts keeps only the seeds where both plans' did.
    lio_plans = [p.plans[n].replays[LIO] for p in summary.pairs for n in ("none", "default")]
    assert all(len(r.rest_steady_per_seed) == 1 for r in lio_plans)
    assert sum(v.replays for v in summary.lio_rest.values()) == len(lio_plans)
    steady_pairs = sum(
        all(p.plans[n].replays[LIO].rest_steady_per_seed[0] for n in ("none", "default")) for p in summary.pairs
    )
    assert summary.compared(Measure(LIO, steady_starts=True)).by_guidance["default"].pairs == steady_pairs
    assert set(raw["comparisons"]) == {m.key for m in MEASURES}
    loc = summary.compared(Measure(LOCALIZATION))
    assert loc.by_guidance["default"].pairs == 2 and set(loc.default_by_map) == {"tunnel", "orientation"}
    # In the tunnel the unguided plans drive through the degenerate passage and the guided
    # ones take the structured lane: guidance must localize better there.
    for pair in (p for p in summary.pairs if p.case == "tunnel"):
        both = pair.both("default", LOCALIZATION)
        assert both[0].ape < both[1].ape
    for name in ("benefit.md", "scatter.png", "ratios.png", "examples/tunnel.png", "examples/orientation.png"):
        assert (out / name).stat().st_size > 0
    # Every JSON the study caches carries the records' schema version.
    predictors = sorted((out / "predictors").rglob("*.json"))
    assert len(predictors) == 10 and all(json.loads(p.read_text())["schema"] == raw["schema"] for p in predictors)
    # A rerun resumes: every replay is on disk, nothing is recomputed.
    replays = sorted((out / "replays").rglob("*.json"))
    stamps = [p.stat().st_mtime_ns for p in replays]
    again = subprocess.run(command + ["--frozen", str(out / "protocol.yaml")], capture_output=True, text=True)
    assert again.returncode == 0 and [p.stat().st_mtime_ns for p in replays] == stamps
    # A variant (the at-risk rule's first form) beside it takes its SOLMs, plans and
    # replays from it (--reuse): every replay linked, none run again, the same records.
    from lf3pm.experiments.benefit.protocol import write_protocol

    base = read_protocol(out / "protocol.yaml")
    rules = tmp_path / "rules.yaml"
    write_protocol(rules, base.model_copy(update={"risk": base.risk.model_copy(update={"median": "all_headings"})}))
    variant = tmp_path / "variant"
    args = ["--rules", str(rules), "--reuse", str(out)]
    reused = subprocess.run(command[:-1] + [str(variant), *args], capture_output=True, text=True)
    assert reused.returncode == 0, reused.stderr[-2000:]
    linked = sorted((variant / "replays").rglob("*.json"))
    assert [p.relative_to(variant) for p in linked] == [p.relative_to(out) for p in replays]
    assert all(a.stat().st_ino == b.stat().st_ino for a, b in zip(linked, replays))
    assert read_protocol(variant / "protocol.yaml").risk.median == "all_headings"
    ours, theirs = read_summary(variant / "summary.json"), read_summary(out / "summary.json")
    assert [p.plans["default"].replays for p in ours.pairs] == [p.plans["default"].replays for p in theirs.pairs]
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
    summary = read_summary(out / "summary.json")
    assert {case: run.odometry for case, run in summary.lio_runs.items()} == {"tunnel": "genz", "orientation": "genz"}
    assert {case: run.label for case, run in summary.lio_runs.items()} == {"tunnel": "lio-genz", "orientation": "lio"}
    assert "## LIO (GenZ-LIO: tunnel, orientation)" in (out / "benefit.md").read_text()
    # A predictor cached by an older version of the records: refused, in one line naming it.
    predictors[0].write_text(json.dumps({"q_n_mean": 0.1, "degenerate_share": 0.0, "poses": 3}))
    stale = subprocess.run(command, capture_output=True, text=True)
    error = stale.stderr.strip().splitlines()[-1]  # after the progress bars
    assert stale.returncode != 0 and error.startswith("lf3pm: error: ") and "Traceback" not in stale.stderr
    assert str(predictors[0]) in error and "schema" in error


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


def _plan(guidance, ape=None, lio=None, steady=None, length=10.0, csv="unused.csv"):
    """A typed plan with a localization replay of APE ``ape`` and LIO replays of APEs
    ``lio`` (one per seed, their rests steady or not as ``steady`` says)."""
    from lf3pm.experiments.benefit.records import LIO, LOCALIZATION, Plan, SeedReplays

    replays = {}
    if ape is not None:
        replays[LOCALIZATION] = SeedReplays(ape, (ape,), 0.0, 10)
    if lio is not None:
        rests = tuple(steady) if steady is not None else None
        replays[LIO] = SeedReplays(float(np.median(lio)), tuple(lio), 0.0, 10, rests)
    return Plan(guidance, csv, length, length, {}, {}, replays)


def _pair(number, plans, case="m", robot="omni", at_risk=False):
    from lf3pm.experiments.benefit.records import Pair

    return Pair(case, number, robot, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), 0.0, at_risk, {p.guidance: p for p in plans})


def test_localization_error_fit_counts_its_own_phase(tmp_path):
    """The fit's progress is a phase of its own (restarted at zero, one step per plan),
    not a continuation of the replays' count; saved predictors are read, not recomputed."""
    from types import SimpleNamespace

    from lf3pm.experiments.benefit.localization_error import localization_error_fit
    from lf3pm.experiments.benefit.records import Predictor, StudyFolder, write_json

    case = SimpleNamespace(name="m", sensor="vlp16")
    pairs = [_pair(k, [_plan(g, ape=0.01) for g in ("none", "default")]) for k in range(2)]
    for pair in pairs:
        for name in pair.plans:
            write_json(
                StudyFolder(tmp_path).predictor("m", pair.number, name),
                {"q_n_mean": 0.1, "degenerate_share": 0.0, "poses": 10},
            )
    calls = []
    _, predictors = localization_error_fit(
        tmp_path,
        [case],
        pairs,
        seeds=1,
        pair_seed=0,
        step=lambda label, total, advance=1, restart=False: calls.append((total, advance, restart)),
    )
    assert calls[0] == (4, 0, True)
    assert sum(advance for _, advance, _ in calls) == 4 and not any(restart for *_, restart in calls[1:])
    assert (tmp_path / "localization_error.json").is_file()
    assert predictors[("m", 1, "default")] == Predictor(0.1, 0.0, 10)


def test_a_cached_json_of_another_schema_is_refused_in_one_line(tmp_path):
    from lf3pm.experiments.benefit.records import SCHEMA, StaleRecordError, read_json, read_summary

    for name, data in (("none.json", {"a": 1}), ("old.json", {"schema": 0}), ("new.json", {"schema": SCHEMA + 1})):
        path = tmp_path / name
        path.write_text(json.dumps(data))
        with pytest.raises(StaleRecordError) as error:
            read_json(path)
        message = str(error.value)
        assert str(path) in message and "\n" not in message and isinstance(error.value, Lf3pmError)
    with pytest.raises(StaleRecordError, match="summary.json"):
        (tmp_path / "summary.json").write_text(json.dumps({"experiment": "benefit", "pairs": []}))
        read_summary(tmp_path / "summary.json")


def test_steady_starts_keep_the_seeds_at_which_both_plans_rest_was_steady():
    """By the LIO from steady starts a pair keeps the seeds whose rest was steady before
    both of its plans (the median over those); a pair with none, or no rest recorded, is
    left out; the plain LIO measure keeps every seed."""
    from lf3pm.experiments.benefit.analysis import comparison, paired
    from lf3pm.experiments.benefit.records import LIO, Measure

    steady, lio = Measure(LIO, steady_starts=True), Measure(LIO)
    kept = _pair(
        0,
        [
            _plan("none", lio=[0.4, 0.2, 9.0], steady=[True, True, False]),
            _plan("default", lio=[0.1, 0.3, 0.05], steady=[True, True, True]),
        ],
    )
    guided, unguided = paired(kept, "default", steady)
    assert guided.ape_per_seed == (0.1, 0.3) and guided.ape == pytest.approx(0.2)
    assert unguided.ape_per_seed == (0.4, 0.2) and unguided.ape == pytest.approx(0.3)
    assert paired(kept, "default", lio)[1].ape_per_seed == (0.4, 0.2, 9.0)
    none_steady = _pair(1, [_plan("none", lio=[0.4], steady=[False]), _plan("default", lio=[0.1], steady=[True])])
    no_rest = _pair(2, [_plan("none", lio=[0.4]), _plan("default", lio=[0.1])])
    assert paired(none_steady, "default", steady) is None and paired(no_rest, "default", steady) is None
    assert comparison([kept, none_steady, no_rest], "default", steady).pairs == 1
    assert comparison([kept, none_steady, no_rest], "default", lio).pairs == 3


def test_goal_is_not_judged_without_seed_noise():
    """With one seed per replay "worse beyond seed noise" is NaN: the goal on it is None
    (the report says n/a), not a failure; with seeds it is judged."""
    from lf3pm.experiments.benefit.analysis import goal
    from lf3pm.experiments.benefit.records import MEASURES, Comparison, Comparisons, RiskSplit

    def comparisons(worse):
        safe = Comparison(
            10, median_ratio=1.0, median_ratio_ci95=(0.97, 1.03), share_worse_beyond_noise_and_margin=worse
        )
        split = {"default": RiskSplit(Comparison(0), safe)}
        overall = {"default": Comparison(10, median_length_overhead=0.01)}
        return {m.key: Comparisons(overall, split) for m in MEASURES}

    assert goal(comparisons(math.nan))["lio_no_risk_worse_on_at_most_10pct"] is None
    assert goal(comparisons(0.05))["lio_no_risk_worse_on_at_most_10pct"] is True
    assert goal(comparisons(0.2))["localization_no_risk_worse_on_at_most_10pct"] is False
    assert goal(comparisons(0.05))["length_overhead_at_most_15pct"] is True


def test_lio_beyond_bound_lists_the_default_plans_past_it():
    """Only pairs with both plans replayed by the LIO count; a default-guided plan past the
    bound is listed with its unguided plan's error, one within it is not."""
    from lf3pm.experiments.benefit.analysis import LIO_BOUND, lio_beyond_bound

    def pair(number, guided, unguided, lio=True):
        if not lio:
            return _pair(number, [_plan("none"), _plan("default")])
        return _pair(number, [_plan("none", lio=[unguided]), _plan("default", lio=[guided])])

    out = lio_beyond_bound([pair(0, LIO_BOUND + 0.01, 0.05), pair(1, LIO_BOUND - 0.01, 2.0), pair(2, 5.0, 5.0, False)])
    assert out.pairs_replayed == 2 and out.bound_m == LIO_BOUND
    assert [(b.pair, b.guided_m, b.unguided_m) for b in out.pairs] == [(0, LIO_BOUND + 0.01, 0.05)]


def test_compare_judges_by_its_settings():
    """paired_stats.compare takes its settings whole (the benefit study: its protocol's
    statistics): the failure line, the worse margin and the bootstrap are its, not
    constants of the module."""
    from lf3pm.experiments.benefit.protocol import Statistics
    from lf3pm.experiments.paired_stats import PAIRED, PairedSettings

    guided, unguided = [0.5, 1.5, 0.2, 2.5], [1.2, 3.0, 0.1, 2.0]
    seeds_g = [[0.50, 0.51, 0.49], [1.5, 1.5, 1.5], [0.200, 0.201, 0.199], [2.5, 2.6, 2.4]]
    seeds_u = [[1.2, 1.2, 1.2], [3.0, 3.0, 3.0], [0.100, 0.101, 0.099], [2.0, 2.1, 1.9]]
    default = compare(guided, unguided, guided_seeds=seeds_g, unguided_seeds=seeds_u)
    assert default == compare(guided, unguided, guided_seeds=seeds_g, unguided_seeds=seeds_u, settings=PAIRED)
    assert (default.failure_rate_guided, default.failure_rate_unguided) == (0.5, 0.75)
    assert default.share_worse_beyond_noise_and_margin == 0.5  # worse by 0.1 m and by 0.5 m
    other = PairedSettings(bootstrap_draws=300, bootstrap_seed=5, ci_level=0.5, failure_ape_m=2.2, worse_margin_m=0.2)
    c = compare(guided, unguided, guided_seeds=seeds_g, unguided_seeds=seeds_u, settings=other)
    assert (c.failure_rate_guided, c.failure_rate_unguided) == (0.25, 0.25)
    assert c.share_worse_beyond_noise_and_margin == 0.25  # the 0.1 m one is within the margin now
    ratios = np.asarray(guided) / np.asarray(unguided)
    assert c.median_ratio_ci95 == median_ratio_ci(ratios, draws=300, level=0.5, seed=5) != default.median_ratio_ci95
    # The protocol's statistics give compare its settings, their defaults paired_stats'.
    assert Statistics(failure_ape_m=2.2, worse_margin_m=0.2).paired().failure_ape_m == 2.2
    assert Statistics().paired() == PAIRED


def test_goal_reads_its_thresholds_and_judges_the_at_risk_maps():
    """The goals' thresholds are the protocol's (goals), named into the keys; over the
    at-risk maps the interval's upper end and the tests over maps are judged too."""
    from lf3pm.experiments.benefit.analysis import AT_RISK, goal
    from lf3pm.experiments.benefit.protocol import Goals
    from lf3pm.experiments.benefit.records import (
        MEASURES,
        AnalysisSettings,
        Comparison,
        Comparisons,
        Effect,
        MapAnalysis,
        MeasureAnalysis,
        RiskSplit,
    )

    risky = Comparison(10, median_ratio=0.4, median_ratio_ci95=(0.2, 0.6), wilcoxon_p=0.002)
    safe = Comparison(10, median_ratio=1.06, median_ratio_ci95=(0.97, 1.08), share_worse_beyond_noise_and_margin=0.1)
    overall = {"default": Comparison(20, median_length_overhead=0.18)}
    comparisons = {m.key: Comparisons(overall, {"default": RiskSplit(risky, safe)}) for m in MEASURES}
    over = Effect(AT_RISK, 4, 32, 0.08, (0.04, 0.2), 0.125, 0.125, 0.125, 4)
    analysed = MeasureAnalysis((), (), (Effect("every pair", 9, 64, 0.3, (0.1, 0.7)), over), (), (), (), None)
    maps = MapAnalysis(AnalysisSettings(), {"localization": analysed})
    out = goal(comparisons, maps)
    assert out["localization_at_risk_ratio_at_most_0.3"] is False and out["lio_at_risk_wilcoxon_p_below_0.01"]
    assert out["localization_at_risk_maps_ci_upper_below_1"] is True
    assert out["localization_at_risk_maps_wilcoxon_p_at_most_0.01"] is False
    assert out["localization_at_risk_maps_sign_p_at_most_0.01"] is False
    assert "lio_at_risk_maps_ci_upper_below_1" not in out  # the LIO not analysed over maps here
    assert out["localization_no_risk_ratio_within_0.95_1.05"] is False
    assert out["length_overhead_at_most_15pct"] is False
    lenient = Goals(at_risk_ratio_max=0.5, no_risk_ratio_high=1.1, length_overhead_max=0.2, map_p_max=0.2)
    out = goal(comparisons, maps, lenient)
    assert out["localization_at_risk_ratio_at_most_0.5"] is True
    assert out["localization_no_risk_ratio_within_0.95_1.1"] is True
    assert out["localization_at_risk_maps_sign_p_at_most_0.2"] is True
    assert out["length_overhead_at_most_20pct"] is True
    assert set(out) <= {f"{m.key}_{k}" for m in MEASURES for k in lenient.described()} | set(lenient.described())
