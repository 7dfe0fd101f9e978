"""The flight study (issue 43, item 7; lf3pm.experiments.flight): its pairs, its analysis on
records whose answer is known, its protocol file, and the quick run end to end."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from lf3pm.cli import app
from lf3pm.errors import Lf3pmError
from lf3pm.experiments.flight import FlightMap, FlightProtocol, analyse, load_protocol
from lf3pm.experiments.flight.study import pairs_of
from lf3pm.scenes import scene_volumes


def test_pairs_are_seeded_inside_the_volumes_and_alternate_direction():
    case = FlightMap(scene="drift", pairs=6)
    pairs = pairs_of(case, 3)
    assert pairs == pairs_of(case, 3) and pairs != pairs_of(case, 4)
    volumes = scene_volumes("drift")
    for k, (start, goal) in enumerate(pairs):
        a, b = (volumes["start"], volumes["goal"]) if k % 2 == 0 else (volumes["goal"], volumes["start"])
        assert a.contains(*start[:3]) and b.contains(*goal)
    with pytest.raises(Lf3pmError, match="no start and goal volumes"):
        pairs_of(FlightMap(scene="boxes"), 0)


def records(ratios_c_over_a, risk):
    """Plans and replays of one map whose joint plan's error is the given ratio of plan
    (a)'s (1 m), (b)'s 0.8 m, two seeds each."""
    plans, replays = [], []
    for k, r in enumerate(ratios_c_over_a):
        for name, error, duration in (("velocity_yaw", 1.0, 10.0), ("yaw_only", 0.8, 10.5), ("joint", r, 11.0)):
            record = {"map": "m", "pair": k, "planner": name, "duration_s": duration, "limits": {"speed": 0.9}}
            if name == "velocity_yaw":
                record["at_risk"] = risk[k]
            plans.append(record)
            for seed in (0, 1):
                replays.append({"map": "m", "pair": k, "planner": name, "odometry": "o", "seed": seed, "ape_m": error})
    return plans, replays


def test_the_analysis_compares_the_joint_plans_with_each_baseline_on_each_risk_group():
    ratios = [0.2, 0.3, 0.4, 1.0, 1.0]
    plans, replays = records(ratios, [True, True, True, False, False])
    replays.append({"map": "m", "pair": 0, "planner": "joint", "odometry": "o", "seed": 2, "error": "lost"})
    protocol = FlightProtocol(maps=[FlightMap(scene="m")], odometries=["o"])
    summary = analyse(plans, replays, protocol)
    risky = summary["maps"]["m"]["o"]["at_risk"]
    assert risky["pairs"] == 3 and risky["c_vs_a"]["median_ratio"] == pytest.approx(0.3)
    assert risky["c_vs_b"]["median_ratio"] == pytest.approx(0.3 / 0.8)
    assert risky["time_overhead_c_over_a"] == pytest.approx(0.1)
    assert summary["maps"]["m"]["o"]["no_risk"]["c_vs_a"]["median_ratio"] == pytest.approx(1.0)
    assert summary["maps"]["all"] == summary["maps"]["m"] and summary["worst_limit_ratio"] == pytest.approx(0.9)
    assert summary["maps"]["m"]["o"]["all"]["pairs"] == 5
    assert len(summary["failures"]) == 1  # apart from accuracy


def test_a_protocol_file_is_read_and_refused_in_one_line(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text("name: mine\nseeds: 2\nmaps: [{scene: forest, pairs: 3}]\n")
    protocol = load_protocol(path)
    assert protocol.seeds == 2 and protocol.maps[0].scene == "forest" and protocol.maps[0].pairs == 3
    path.write_text("seeds: -1\n")
    with pytest.raises(Lf3pmError, match="seeds") as err:
        load_protocol(path)
    assert "\n" not in str(err.value)


@pytest.mark.slow
def test_the_quick_study_runs_end_to_end_and_resumes(tmp_path):
    """The quick protocol (atrium, 2 pairs, GenZ-LIO, one seed): every plan within its limits,
    every replay recorded, the report written; run again it replays nothing."""
    pytest.importorskip("genz_lio", reason="genz-lio has wheels for Python 3.8-3.12 only")
    out = tmp_path / "flight"
    done = CliRunner().invoke(app, ["experiment", "flight", "--quick", "-o", str(out)])
    assert done.exit_code == 0, done.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["worst_limit_ratio"] <= 1.0 + 1e-9 and not summary["planning_failures"]
    replays = (out / "replays.jsonl").read_text().splitlines()
    assert len(replays) == 2 * 3
    assert all(np.isfinite(json.loads(line).get("ape_m", np.nan)) for line in replays)
    assert "| atrium | genz |" in (out / "report.md").read_text()
    assert (out / "scatter.png").read_bytes()[:4] == b"\x89PNG" and len(summary["pairs"]) == 2
    plans = [json.loads(line) for line in (out / "plans.jsonl").read_text().splitlines()]
    assert all(r["attitude_rounds"] == [] for r in plans)  # the protocol's default: level guidance
    # A protocol frozen before a field existed is the same protocol at that field's default;
    # a record cut by a crash is cut off and redone.
    frozen = json.loads((out / "protocol.json").read_text())
    del frozen["attitude_rounds"]
    (out / "protocol.json").write_text(json.dumps(frozen))
    with open(out / "replays.jsonl", "a") as fp:
        fp.write('{"map": "atrium", "pair"')
    again = CliRunner().invoke(app, ["experiment", "flight", "--quick", "-o", str(out)])
    assert again.exit_code == 0 and (out / "replays.jsonl").read_text().splitlines() == replays
    runs = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    assert len(runs) == 2 and all(r["code"] for r in runs)
    report = (out / "report.md").read_text()
    (out / "report.md").unlink()
    rewritten = CliRunner().invoke(app, ["experiment", "flight", "--report-only", "-o", str(out)])
    assert rewritten.exit_code == 0 and (out / "report.md").read_text() == report
    empty = CliRunner().invoke(app, ["experiment", "flight", "--report-only", "-o", str(tmp_path)])
    assert empty.exit_code != 0 and "no protocol.json" in empty.output
    both = CliRunner().invoke(app, ["experiment", "flight", "--report-only", "--quick", "-o", str(out)])
    assert both.exit_code != 0 and "give no other protocol" in both.output
    (out / "plans.jsonl").write_text("{not json\n")
    broken = CliRunner().invoke(app, ["experiment", "flight", "--report-only", "-o", str(out)])
    assert broken.exit_code != 0 and "unreadable study records" in broken.output and "Traceback" not in broken.output


@pytest.mark.parametrize("run", ["flight_issue43", "flight_issue43_v2"])
def test_the_published_flight_studies_reanalyse_to_their_reports(run, tmp_path):
    """results/RUN's report.md and summary.json are what `--report-only` writes from its
    published records and frozen protocol, byte for byte."""
    import shutil

    published = Path(__file__).resolve().parents[1] / "results" / run
    folder = tmp_path / run
    shutil.copytree(published, folder)
    done = CliRunner().invoke(app, ["experiment", "flight", "--report-only", "-o", str(folder)])
    assert done.exit_code == 0, done.output
    for name in ("report.md", "summary.json"):
        assert (folder / name).read_bytes() == (published / name).read_bytes(), name
