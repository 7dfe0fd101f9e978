"""The benefit study's analysis at the level of the map (issue 41, items 3-5): the
two-stage bootstrap, the tests over maps, McNemar's exact test, the equivalence test,
the records as JSON Lines and the report regenerated from them alone, each checked on a
case whose answer is known or against committed records."""

from __future__ import annotations

import json
import math
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from lf3pm.experiments import paired_stats
from lf3pm.experiments.benefit import analysis
from lf3pm.experiments.benefit.records import (
    LOCALIZATION,
    AnalysisSettings,
    Measure,
    Pair,
    Plan,
    Redraw,
    SeedReplays,
    StaleRecordError,
    StudyFolder,
    read_jsonl,
    read_records,
    write_records,
)
from lf3pm.experiments.benefit.regenerate import regenerate
from lf3pm.experiments.benefit.report import redrawn_line

ROOT = Path(__file__).resolve().parents[1]
FIXTURE = ROOT / "tests" / "data" / "benefit_records"
ISSUE39 = ROOT / "results" / "benefit_issue39"
RESULT = ROOT / "results" / "benefit"  # protocol 2's frozen run: the study's result
FAST = AnalysisSettings(bootstrap_draws=400)


def _synthetic_groups(true_logs, pairs: int, noise: float, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [np.exp(mu + noise * rng.standard_normal(pairs)) for mu in true_logs]


def test_two_stage_bootstrap_covers_the_true_effect_over_maps():
    # Maps' true log ratios drawn around a known centre: over 60 replications the 95 %
    # interval over maps covers the centre about 95 % of the time, and each map's
    # interval its own true ratio.
    centre, covered, map_covered, maps_seen = math.log(0.5), 0, 0, 0
    for k in range(60):
        rng = np.random.default_rng(k)
        true_logs = centre + 0.4 * rng.standard_normal(8)
        groups = _synthetic_groups(true_logs, 8, 0.3, 1000 + k)
        ratio, (lo, hi) = paired_stats.group_bootstrap(groups, draws=400, seed=0, level=0.95)
        assert lo <= ratio <= hi
        covered += lo <= math.exp(centre) <= hi
        for mu, g in zip(true_logs, groups):
            _, (a, b) = paired_stats.group_bootstrap([g], draws=400, seed=0, level=0.95)
            map_covered += a <= math.exp(mu) <= b
            maps_seen += 1
    assert covered >= 50  # 60 x 0.95 = 57; the percentile bootstrap on 8 maps runs a little narrow
    assert map_covered / maps_seen >= 0.8


def test_group_bootstrap_is_seeded_and_weighs_maps_equally():
    groups = [np.full(20, 0.1), np.full(2, 1.0)]
    a = paired_stats.group_bootstrap(groups, draws=300, seed=3, level=0.95)
    assert a == paired_stats.group_bootstrap(groups, draws=300, seed=3, level=0.95)
    assert a[0] == pytest.approx(math.sqrt(0.1))  # each map once, however many pairs


def test_tests_over_maps_and_their_least_p():
    four_below = np.log([0.1, 0.5, 0.2, 0.9])
    assert paired_stats.minimum_p(4) == 0.125
    assert paired_stats.sign_test_p(four_below) == pytest.approx(0.125)
    assert paired_stats.wilcoxon_exact_p(four_below) == pytest.approx(0.125)
    assert paired_stats.minimum_p(8) == pytest.approx(0.0078125)


def test_mcnemar_is_the_exact_binomial_on_discordant_pairs():
    from scipy.stats import binomtest

    # both fail 7, guided only 1, unguided only 23, neither 1
    assert paired_stats.mcnemar_exact_p(1, 23) == pytest.approx(binomtest(1, 24, 0.5).pvalue)
    assert paired_stats.mcnemar_exact_p(1, 23) == pytest.approx(2 * sum(math.comb(24, k) for k in (0, 1)) / 2**24)
    assert paired_stats.mcnemar_exact_p(0, 0) == 1.0


def test_tost_and_the_binomial_upper_bound():
    rng = np.random.default_rng(0)
    near_one = 0.02 * rng.standard_normal(10)
    assert paired_stats.tost_t_p(near_one, 0.9, 1 / 0.9) < 0.001
    assert paired_stats.tost_t_p(near_one + math.log(1.3), 0.9, 1 / 0.9) > 0.5
    from scipy.stats import beta

    assert paired_stats.binomial_upper(2, 30, 0.95) == pytest.approx(beta.ppf(0.95, 3, 28))
    assert paired_stats.binomial_upper(0, 0, 0.95) != paired_stats.binomial_upper(0, 0, 0.95)  # NaN


def _plan(name: str, apes: list[float]) -> Plan:
    replays = SeedReplays(float(np.median(apes)), tuple(apes), 0.0, 10)
    return Plan(name, f"{name}.csv", 10.0, 10.0, {}, {}, {LOCALIZATION: replays})


def _pairs(table: dict[str, list[tuple[list[float], list[float], bool, str]]]) -> list[Pair]:
    out = []
    for case, rows in table.items():
        for number, (guided, unguided, risky, robot) in enumerate(rows):
            plans = {"none": _plan("none", unguided), "default": _plan("default", guided)}
            out.append(Pair(case, number, robot, (0, 0, 0), (1, 0, 0), 0.5 if risky else 0.0, risky, plans))
    return out


def test_failures_are_a_paired_table_and_the_ratio_where_both_succeed():
    pairs = _pairs(
        {
            "a": [([0.1], [2.0], True, "omni"), ([3.0], [2.0], True, "diff"), ([0.1], [0.2], True, "omni")],
            "b": [([1.5], [5.0], True, "omni"), ([0.01], [0.01], False, "diff")],
        }
    )
    m = analysis.measure_analysis(pairs, ["a", "b"], Measure(LOCALIZATION), FAST)
    every = m.failures[0]
    assert (every.both, every.guided_only, every.unguided_only, every.neither) == (2, 0, 1, 2)
    assert every.mcnemar_p == 1.0
    assert [f.name for f in m.failures_by_map] == ["a", "b"]
    assert (m.failures_by_map[0].both, m.failures_by_map[0].unguided_only) == (1, 1)
    succeed = m.both_succeed[0]  # only a's third pair and b's second
    assert (succeed.maps, succeed.pairs) == (2, 2)
    assert succeed.ratio == pytest.approx(math.sqrt(0.5 * 1.0))


def test_map_effects_recover_a_set_ratio_and_flag_the_maps_that_gain_nothing():
    rng = np.random.default_rng(7)
    truth = {"helped": 0.2, "flat": 1.0, "also": 0.4}
    table = {}
    for case, r in truth.items():
        noise = 0.1 * rng.standard_normal(8)
        noise -= noise.mean()  # each map's geometric-mean ratio is exactly its set ratio
        rows = []
        for k in range(8):
            unguided = float(np.exp(rng.normal(-3, 0.5)))
            rows.append(([unguided * r * float(np.exp(noise[k]))], [unguided], r < 1, "omni" if k % 2 else "diff"))
        table[case] = rows
    m = analysis.measure_analysis(_pairs(table), list(truth), Measure(LOCALIZATION), FAST)
    for e in m.by_map:
        assert e.ratio == pytest.approx(truth[e.name]) and e.ci[0] <= truth[e.name] <= e.ci[1], e
    assert [e.name for e in m.by_map if e.gains_nothing] == ["flat"]
    assert {e.name for e in m.by_map_robot} == {f"{c}, {r}" for c in truth for r in ("diff", "omni")}
    at_risk = next(e for e in m.over_maps if e.name == "at risk")
    assert (at_risk.maps, at_risk.minimum_p) == (2, 0.5)
    no_harm = m.no_harm
    assert no_harm.maps == 1 and no_harm.equivalent and no_harm.not_worse
    assert no_harm.tail_pairs == 0 and no_harm.tail_no_harm is None  # one seed: the tail cannot be judged


def test_the_tail_is_judged_with_seeds():
    rows = [([0.010, 0.011, 0.012], [0.010, 0.011, 0.012], False, "omni")] * 30
    rows += [([0.050, 0.051, 0.052], [0.010, 0.011, 0.012], False, "omni")]
    m = analysis.measure_analysis(_pairs({"a": rows}), ["a"], Measure(LOCALIZATION), FAST)
    e = m.no_harm
    assert (e.tail_pairs, e.tail_worse) == (31, 1)
    assert e.tail_upper == pytest.approx(paired_stats.binomial_upper(1, 31, 0.95))
    assert e.tail_no_harm is (e.tail_upper <= 0.10)


def test_records_are_json_lines_with_the_schema(tmp_path):
    summary = read_records(FIXTURE)
    write_records(StudyFolder(tmp_path), summary)
    lines = (tmp_path / "pairs.jsonl").read_text().splitlines()
    assert all(json.loads(line)["schema"] == 1 for line in lines)
    assert tuple(Pair.from_json(d) for d in read_jsonl(tmp_path / "pairs.jsonl")) == summary.pairs
    (tmp_path / "pairs.jsonl").write_text(lines[0].replace('"schema": 1', '"schema": 0') + "\n")
    with pytest.raises(StaleRecordError, match="pairs.jsonl:1"):
        read_jsonl(tmp_path / "pairs.jsonl")


def test_redrawn_pairs_are_listed():
    summary = read_records(FIXTURE)
    assert "not recorded" in redrawn_line(summary)
    assert redrawn_line(replace(summary, redrawn=())) == "Redrawn pairs: none (every draw was planned)."
    line = redrawn_line(replace(summary, redrawn=(Redraw("room", 2, "default could not plan it: x"),)))
    assert line == "Redrawn pairs: 1 draws replaced (room draw 2: default could not plan it: x)."


@pytest.mark.slow
def test_report_regenerates_from_the_committed_records_byte_for_byte(tmp_path):
    regenerate(FIXTURE, tmp_path)
    assert (tmp_path / "benefit.md").read_bytes() == (FIXTURE / "benefit.md").read_bytes()
    assert (tmp_path / "summary.json").read_bytes() == (FIXTURE / "summary.json").read_bytes()
    assert (tmp_path / "maps.png").is_file()


#: Every published run of the study under results/ with its records (the sensitivity
#: analyses' runs in results/benefit_variants/ too).
PUBLISHED = sorted(path.parent for path in (ROOT / "results").rglob("pairs.jsonl"))
VARIANTS = ROOT / "results" / "benefit_variants"


@pytest.mark.slow
@pytest.mark.parametrize("published", PUBLISHED, ids=[str(p.relative_to(ROOT / "results")) for p in PUBLISHED])
def test_a_published_report_and_summary_come_out_of_its_records(tmp_path, published):
    """Each results/ folder's report, summary and the figures it publishes are what its
    records (and its protocol, where it has one) give, byte for byte: every figure traced
    to the records. The study's result publishes every figure; a variant its map-level one."""
    assert ISSUE39 in PUBLISHED and RESULT in PUBLISHED and VARIANTS / "risk_all_headings" in PUBLISHED
    for name in ("summary.json", "pairs.jsonl", "replays.jsonl", "protocol.yaml"):
        if (published / name).exists():
            shutil.copyfile(published / name, tmp_path / name)
    regenerate(tmp_path)
    figures = ("maps.png",) if published.parent == VARIANTS else ("ratios.png", "scatter.png", "maps.png")
    for name in ("benefit.md", "summary.json", *figures):
        assert (tmp_path / name).read_bytes() == (published / name).read_bytes(), name


@pytest.mark.slow  # the CLI's first import: over 2 s on 2 cores
def test_benefit_report_without_records_is_one_line(tmp_path):
    from typer.testing import CliRunner

    from lf3pm.cli import app

    done = CliRunner().invoke(app, ["experiment", "benefit-report", str(tmp_path)])
    assert done.exit_code == 2, done.output
    lines = done.output.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith(f"lf3pm: error: {tmp_path}: no summary.json (a benefit study's records")


def test_the_report_says_what_each_goal_is_with_the_protocols_threshold():
    """The goals' section: one row a goal judged by measure, in the protocol's words and
    thresholds (other goals, other words), the length overhead a line; a verdict the
    goals do not describe is still shown, by its key."""
    from lf3pm.experiments.benefit.protocol import GOALS, Goals
    from lf3pm.experiments.benefit.report import goal_lines

    summary = read_records(FIXTURE)
    text = "\n".join(goal_lines(summary.goal, GOALS.described()))
    assert "| goal | localization | LIO | LIO, steady starts |" in text
    assert "| at risk: the median APE ratio over pairs at most 0.3 | yes | yes | yes |" in text
    assert "The median length overhead (every pair) at most 15 %: yes." in text
    other = Goals(at_risk_ratio_max=0.25, length_overhead_max=0.1)
    verdicts = {k.replace("at_most_0.3", "at_most_0.25").replace("15pct", "10pct"): v for k, v in summary.goal.items()}
    text = "\n".join(goal_lines(verdicts, other.described()))
    assert "| at risk: the median APE ratio over pairs at most 0.25 | yes | yes | yes |" in text
    assert "The median length overhead (every pair) at most 10 %: yes." in text
    text = "\n".join(goal_lines({**verdicts, "some_other_goal": False}, other.described()))
    assert "Other goals: some other goal: no." in text


@pytest.mark.slow
def test_regenerate_judges_by_the_folders_protocol(tmp_path):
    """benefit-report takes the statistics and goals of the folder's protocol.yaml: other
    goals, other keys and words; another failure line, other failure rates."""
    from lf3pm.experiments.benefit.protocol import DEFAULT_PROTOCOL, Goals, Statistics, write_protocol

    for name in ("summary.json", "pairs.jsonl"):
        shutil.copyfile(FIXTURE / name, tmp_path / name)
    rules = DEFAULT_PROTOCOL.model_copy(
        update={"goals": Goals(map_p_max=0.5), "statistics": Statistics(failure_ape_m=1e-3, bootstrap_draws=200)}
    )
    write_protocol(tmp_path / "protocol.yaml", rules)
    summary = regenerate(tmp_path)
    assert summary.goal["localization_at_risk_maps_sign_p_at_most_0.5"] is True
    assert "| over the at-risk maps: the exact sign test's p at most 0.5 |" in (tmp_path / "benefit.md").read_text()
    before = read_records(FIXTURE).compared(Measure(LOCALIZATION)).by_guidance["default"]
    after = summary.compared(Measure(LOCALIZATION)).by_guidance["default"]
    assert after.failure_rate_unguided > before.failure_rate_unguided


def _figure(value: float) -> str:
    """A ratio as the README writes it: two decimals, two significant digits below 0.1."""
    return f"{value:.2f}" if value >= 0.1 else f"{value:#.2g}"


def _interval(entry: dict, digits=_figure) -> str:
    return f"{digits(entry['ratio'])} [{digits(entry['ci'][0])}, {digits(entry['ci'][1])}]"


def test_the_readme_states_the_published_result_as_its_records_give_it():
    """Every figure of the README's study paragraph is results/benefit/summary.json's
    (protocol 2's frozen run), formatted as written: a rerun or a new result that changes
    a figure fails here until the README says it."""
    readme = " ".join((ROOT / "README.md").read_text().split())
    summary = json.loads((RESULT / "summary.json").read_text())
    protocol = (RESULT / "protocol.yaml").read_text()
    assert summary["protocol_sha256"] in protocol and summary["pair_seed"] == 20261205
    maps = summary["map_analysis"]
    loc, lio = maps["localization"], maps["lio"]

    def group(rows, name):
        return next(row for row in rows if row["name"] == name)

    at_risk = group(loc["over_maps"], "at risk")
    per_map = ", ".join(_figure(row["ratio"]) for row in loc["at_risk_by_map"][:-1])
    last = _figure(loc["at_risk_by_map"][-1]["ratio"])
    lio_risk, lio_none = group(lio["over_maps"], "at risk"), group(lio["over_maps"], "no risk")
    failures = group(lio["failures"], "at risk")
    both = group(lio["both_succeed"], "at risk")
    stated = [
        f"44 pairs on {at_risk['maps']} maps came out at risk",
        f"is {per_map} and {last} (in that order)",
        f"over the 8 maps **{_interval(at_risk)}**",
        f"{at_risk['maps_below_1']} of 8 maps below 1, Wilcoxon p over maps {at_risk['wilcoxon_p']:.2g}",
        f"Under the LIO, {_interval(lio_risk)} over maps (p {lio_risk['wilcoxon_p']:.2g})",
        f"failed (APE > 1 m) on {failures['both'] + failures['unguided_only']} of 44 pairs, the guided "
        f"one's on {failures['both'] + failures['guided_only']} (McNemar p {failures['mcnemar_p']:.0e}",
        f"where both held ({both['pairs']} pairs) {_interval(both)}",
        f"localization ({_interval(group(loc['over_maps'], 'no risk'))})",
        f"hurt the LIO: {_interval(lio_none)}**, worse beyond seed noise on {lio['no_harm']['tail_worse']} "
        f"of {lio['no_harm']['tail_pairs']} pairs",
    ]
    assert at_risk["pairs"] == 44 and at_risk["maps"] == 8
    for text in stated:
        assert text.replace("e-0", "e-") in readme, text
