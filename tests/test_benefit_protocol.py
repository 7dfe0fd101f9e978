"""The benefit study's protocol (experiments/benefit/protocol.py): today's is the one
frozen in config/benefit_protocol.yaml, `--frozen` refuses any run whose protocol
differs in one line naming the field, before any work, a protocol round-trips, and a
run judges by its protocol's statistics and goals."""

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from lf3pm.cli import app
from lf3pm.experiments.benefit import protocol as protocols
from lf3pm.experiments.benefit.protocol import ProtocolError, read_protocol, write_protocol
from lf3pm.experiments.benefit.study import StudySettings, study_protocol

FROZEN = Path(__file__).resolve().parents[1] / "config" / "benefit_protocol.yaml"
#: The frozen run's settings: lf3pm's defaults, a pair seed never drawn before the run
#: and the LIO on the default's and the unguided plans only.
FROZEN_RUN = StudySettings.of(pair_seed=20261205, lio="default")


def test_the_frozen_protocol_is_todays_defaults_at_its_pair_seed():
    """The protocol a run builds with lf3pm's cases, guidance, replay settings and
    constants, at the frozen pair seed and LIO plans, is config/benefit_protocol.yaml's;
    a change to any of them must be a new frozen protocol, made on purpose."""
    frozen, current = read_protocol(FROZEN), study_protocol(FROZEN_RUN)
    assert protocols.compared(frozen, current) is None, protocols.compared(frozen, current)
    assert frozen.digest() == current.digest() and frozen.version == protocols.VERSION == 2
    assert f"sha256 of its content (name and date aside): {frozen.digest()}" in FROZEN.read_text()


def test_the_module_constants_are_the_protocols_defaults():
    """The constants the study's modules keep read the protocol's defaults (one source);
    the per-pair statistics' defaults are paired_stats' (which the protocol's give it)."""
    from lf3pm.experiments import paired_stats, risk
    from lf3pm.experiments.benefit import analysis, localization_error, records

    p = protocols.DEFAULT_PROTOCOL
    assert (risk.RISK_FACTOR, risk.AT_RISK_SHARE, risk.RISK_RATE) == (p.risk.factor, p.risk.share, p.risk.rate)
    assert (p.risk.factor, p.risk.share, p.risk.rate, p.risk.median) == (10.0, 0.1, 10.0, "best_heading")
    assert (localization_error.FIT_RATE, localization_error.MIN_PLANS) == (1.0, 10)
    assert analysis.LIO_BOUND == p.statistics.lio_bound_m == 0.3
    assert records.APE_FLOOR == p.statistics.ape_floor_m == 1e-4
    assert p.statistics.paired() == paired_stats.PAIRED == paired_stats.PairedSettings()
    assert (p.statistics.failure_ape_m, p.statistics.worse_margin_m, p.statistics.ci_level) == (1.0, 0.01, 0.95)
    assert p.goals == protocols.GOALS == analysis.GOALS


def _default_protocol(tmp_path) -> Path:
    """The protocol a default run builds, written (the frozen file's when in step)."""
    path = tmp_path / "default.yaml"
    write_protocol(path, study_protocol())
    return path


def _changed(tmp_path, path: str, value) -> Path:
    """The default run's protocol (config/benefit_protocol.yaml's, whose own test is
    the one above) with the field at dotted ``path`` set to ``value``."""
    data = yaml.safe_load(_default_protocol(tmp_path).read_text())
    *head, last = path.split(".")
    node = data
    for key in head:
        node = node[int(key)] if isinstance(node, list) else node[key]
    if isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value
    out = tmp_path / "frozen.yaml"
    out.write_text(yaml.safe_dump(data, sort_keys=False))
    return out


CHANGES = [
    ("pair_seed", 7, "protocol.pair_seed: frozen 7, this run 0"),
    ("risk.factor", 9.0, "protocol.risk.factor: frozen 9.0, this run 10.0"),
    ("risk.median", "all_headings", 'protocol.risk.median: frozen "all_headings", this run "best_heading"'),
    ("guidance.3.weight", 2.0, "protocol.guidance[3].weight: frozen 2.0, this run 3.0"),
    ("lio.settings.genz.noise_inflation", 50.0, "protocol.lio.settings.genz.noise_inflation: frozen 50.0, this run"),
    ("lio.rest_speed_limit", 0.1, "protocol.lio.rest_speed_limit: frozen 0.1, this run 0.05"),
    ("statistics.lio_bound_m", 0.5, "protocol.statistics.lio_bound_m: frozen 0.5, this run 0.3"),
    ("analysis.equivalence_low", 0.8, "protocol.analysis.equivalence_low: frozen 0.8, this run 0.9"),
    ("goals.map_p_max", 0.05, "protocol.goals.map_p_max: frozen 0.05, this run 0.01"),
    ("cases.7.sensor", "vlp16", 'protocol.cases[7].sensor: frozen "vlp16", this run "mid70"'),
    ("cases_sha256", "0" * 64, "protocol.cases_sha256: frozen"),
]


@pytest.mark.parametrize(("path", "value", "line"), CHANGES, ids=[c[0] for c in CHANGES])
def test_frozen_refuses_a_run_whose_protocol_differs(tmp_path, path, value, line):
    """One line naming the first field that differs with both values, exit 2, and
    nothing made: not even the output folder."""
    out = tmp_path / "out"
    given = ["--pair-seed", "0"]  # given: a frozen file settles only what no flag sets (test below)
    done = CliRunner().invoke(
        app, ["experiment", "benefit", "-o", str(out), *given, "--frozen", str(_changed(tmp_path, path, value))]
    )
    assert done.exit_code == 2, done.output
    lines = [line for line in done.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("lf3pm: error: ") and line in lines[0], done.output
    assert not out.exists()


def test_the_run_itself_refuses_before_any_work(tmp_path):
    """study.run checks the frozen protocol before it makes its folder."""
    from lf3pm.experiments.benefit import study

    with pytest.raises(ProtocolError, match=r"protocol\.seeds: frozen 5, this run 3"):
        study.run(tmp_path / "out", frozen=_changed(tmp_path, "seeds", 5))
    assert not (tmp_path / "out").exists()


def test_a_setting_given_to_the_run_is_in_its_protocol(tmp_path):
    """The CLI's and the configuration's settings make the run's protocol: --pair-seed and
    an odometry's settings (replay.odometries) differ from the frozen one; --write-protocol
    writes the protocol that then passes --frozen."""
    config = tmp_path / "c.yaml"
    config.write_text("replay:\n  odometries:\n    genz:\n      noise_inflation: 10.0\n")
    written = tmp_path / "p.yaml"
    args = ["experiment", "benefit", "--pair-seed", "11", "--config", str(config)]
    done = CliRunner().invoke(app, [*args, "--write-protocol", str(written)])
    assert done.exit_code == 0, done.output
    p = read_protocol(written)
    assert p.pair_seed == 11 and p.lio.settings["genz"]["noise_inflation"] == 10.0
    done = CliRunner().invoke(app, [*args, "--write-protocol", str(tmp_path / "q.yaml"), "--frozen", str(written)])
    assert done.exit_code == 0, done.output
    done = CliRunner().invoke(
        app, ["experiment", "benefit", "--write-protocol", str(tmp_path / "r.yaml"), "--frozen", str(written)]
    )  # the pair seed from the frozen file, the odometry's settings not (a configuration's)
    assert done.exit_code == 2, done.output
    assert "protocol.lio.settings.genz.noise_inflation: frozen 10.0, this run 100.0" in done.output


def test_the_protocol_round_trips(tmp_path):
    p = study_protocol(StudySettings.of(quick=True), date="2026-12-05")
    write_protocol(tmp_path / "protocol.yaml", p)
    back = read_protocol(tmp_path / "protocol.yaml")
    assert back == p and back.digest() == p.digest() and back.to_yaml() == p.to_yaml()
    assert p.seeds == 1 and [c["name"] for c in p.cases] == ["tunnel", "orientation"]
    # name and date describe the document: no part of the comparison nor of the digest
    renamed = p.model_copy(update={"name": "another", "date": "2030-01-01"})
    assert protocols.compared(p, renamed) is None and renamed.digest() == p.digest()


@pytest.mark.parametrize(
    ("text", "error"),
    [
        ("version: 3\n", "a protocol of version 3, not 2"),
        ("version: 1\n", "a protocol of version 1, not 2 (version 1 has no goals section: write it again"),
        ("version: 2\nrisk:\n  factr: 9\n", "protocol.risk.factr"),
        ("version: 2\nrisk:\n  factor: -1\n", "protocol.risk.factor"),
        ("version: 2\ngoals:\n  no_risk_ratio_low: 1.2\n", "no_risk_ratio_low 1.2 exceeds no_risk_ratio_high 1.05"),
        ("- 1\n", "a mapping of its fields"),
        ("version: [\n", "not YAML"),
    ],
)
def test_a_bad_protocol_file_is_one_line_naming_it(tmp_path, text, error):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ProtocolError, match=None) as err:
        read_protocol(path)
    assert error in str(err.value) and str(path) in str(err.value) and "\n" not in str(err.value)


def test_a_folder_made_under_another_protocol_is_refused(tmp_path):
    """Replays made under one protocol are never mixed with another's: the run refuses
    the folder in one line; another odometry (labelled apart) is welcome."""
    from lf3pm.experiments.benefit import study

    out = tmp_path / "out"
    write_protocol(out / "protocol.yaml", study_protocol(StudySettings.of(quick=True, pair_seed=3)))
    with pytest.raises(ProtocolError, match=r"made under another protocol \(protocol\.pair_seed: the folder's 3"):
        study.run(out, StudySettings.of(quick=True))
    assert sorted(p.name for p in out.iterdir()) == ["protocol.yaml"]
    other = study_protocol(StudySettings.of(quick=True, pair_seed=3, odometry="genz"))
    protocols.check_folder(out / "protocol.yaml", other)  # no error


def test_the_cases_digest_is_their_content():
    """A case's digest changes with its content, not with a field added at its default."""
    from dataclasses import replace

    from lf3pm.experiments.benefit.cases import CASES

    base = protocols.cases_digest(CASES)
    assert protocols.cases_digest(CASES) == base
    assert protocols.cases_digest((replace(CASES[0], min_distance=29.0), *CASES[1:])) != base
    assert protocols.cases_digest(CASES[::-1]) != base  # a case's pairs are drawn from its index


def test_the_risk_rules_first_form_is_a_setting():
    """median all_headings: the map's median over every cell and heading (the rule as
    first written), against best_heading (each cell's best)."""
    from lf3pm.experiments.risk import map_median, risk_share
    from lf3pm.solm.grid import SolmGrid

    class Solm:
        grid_spec = SolmGrid("se2", 0.0, 0.0, 1.0, 10, 10, yaw_bins=4)
        q = np.full((4, 10, 10), 15.0)
        q[0] = 1.0

        def channel(self, name):
            return self.q if name == "q_n" else np.zeros((4, 10, 10), bool)

    class Line:
        def sample(self, rate):
            t = np.arange(0.0, 10.0 + 1e-9, 1.0 / rate)
            return {"t": t, "x": t, "y": np.full_like(t, 3.5), "yaw": np.full_like(t, math.pi / 2)}

    first = protocols.RiskRule(median="all_headings")
    assert map_median(Solm()) == 1.0 and map_median(Solm(), first.median) == 15.0
    assert risk_share(Solm(), Line()) == 1.0 and risk_share(Solm(), Line(), rule=first) == 0.0


def test_the_variants_are_protocols_this_lf3pm_runs():
    """config/benefit_protocol_variants: each earlier setting as a protocol, differing
    from the frozen one where it says; the risk rule's by --rules, GenZ-LIO's by a
    configuration's replay.odometries."""
    from lf3pm.config import DEFAULTS

    folder = FROZEN.parent / "benefit_protocol_variants"
    frozen = study_protocol(FROZEN_RUN)  # config/benefit_protocol.yaml's (the first test)
    variants = {path.stem: read_protocol(path) for path in sorted(folder.glob("*.yaml"))}
    assert set(variants) >= {"risk_all_headings", "corridor_vlp16", "corridor_first_zones", "genz_voxels_0_5"}
    for name, variant in variants.items():
        assert protocols.compared(frozen, variant) is not None, name
    rule = variants["risk_all_headings"]
    assert study_protocol(StudySettings(FROZEN_RUN.benefit, rules=rule)).digest() == rule.digest()
    voxels = DEFAULTS.replay.model_copy(update={"odometries": {"genz": {"mapping": {"voxel_size": 0.5}}}})
    assert study_protocol(StudySettings(FROZEN_RUN.benefit, voxels)).digest() == variants["genz_voxels_0_5"].digest()
    for name, variant in variants.items():  # each differs from the frozen one in one setting
        assert (variant.pair_seed, variant.seeds, variant.lio.plans) == (20261205, 3, "default"), name


def test_the_variants_inputs_give_the_variants():
    """config/benefit_protocol_variants/inputs: the cases files and configurations the
    variants are run with (docs/benefit.md's table) give each variant's protocol."""
    from lf3pm.config import load_config
    from lf3pm.experiments.benefit.case_file import load_cases

    folder = FROZEN.parent / "benefit_protocol_variants"
    for name in ("corridor_vlp16", "corridor_first_zones"):
        cases = load_cases(folder / "inputs" / f"cases_{name}.yaml", check_files=False)
        made = study_protocol(StudySettings(FROZEN_RUN.benefit, cases=cases))
        assert made.digest() == read_protocol(folder / f"{name}.yaml").digest(), name
    for name in ("genz_voxels_0_5", "genz_own_covariance"):
        config = load_config(folder / "inputs" / f"{name}.config.yaml")
        made = study_protocol(StudySettings(FROZEN_RUN.benefit, config.replay))
        assert made.digest() == read_protocol(folder / f"{name}.yaml").digest(), name


def test_frozen_alone_runs_the_frozen_protocol(tmp_path):
    """`--frozen FILE` takes FILE's seeds, pair seed and LIO plans where no flag says
    otherwise; a flag that does is refused, naming the field."""
    out = tmp_path / "p.yaml"
    result = CliRunner().invoke(app, ["experiment", "benefit", "--frozen", str(FROZEN), "--write-protocol", str(out)])
    assert result.exit_code == 0, result.output
    assert read_protocol(out).digest() == read_protocol(FROZEN).digest()
    args = ["experiment", "benefit", "--frozen", str(FROZEN), "--pair-seed", "0", "--write-protocol", str(out)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2 and "protocol.pair_seed: frozen 20261205, this run 0" in result.output, result.output


def test_a_run_judges_by_its_protocols_statistics(tmp_path, monkeypatch):
    """A protocol with other statistics is run with them, not refused: the run gets past
    its checks and writes them into its protocol.yaml (stopped there: no map is built);
    only another APE floor, which the records and figures fix, is refused before any work."""
    from lf3pm.experiments.benefit import study

    class Stop(Exception):
        pass

    def stop(*args, **kwargs):
        raise Stop

    monkeypatch.setattr(study, "build_case_solm", stop)
    other = protocols.Statistics(bootstrap_draws=500, ci_level=0.9, failure_ape_m=2.0, worse_margin_m=0.02)
    rules = protocols.DEFAULT_PROTOCOL.model_copy(update={"statistics": other})
    with pytest.raises(Stop):
        study.run(tmp_path / "out", StudySettings.of(quick=True, rules=rules))
    assert read_protocol(tmp_path / "out" / "protocol.yaml").statistics == other
    floor = rules.model_copy(update={"statistics": other.model_copy(update={"ape_floor_m": 1e-3})})
    with pytest.raises(ProtocolError, match=r"protocol\.statistics\.ape_floor_m: this lf3pm floors errors at 0\.0001"):
        study.run(tmp_path / "floor", StudySettings.of(quick=True, rules=floor))
    assert not (tmp_path / "floor").exists()


def test_the_goals_keys_and_texts_are_named_from_their_thresholds():
    """summary.json's goal keys and the report's words carry each threshold: the
    defaults' keys are those the committed outputs hold; other thresholds, other keys."""
    keys = protocols.GOALS.keys()
    assert keys["no_risk_ci_upper"] == "no_risk_ci_upper_at_most_1.10"
    assert keys["length_overhead"] == "length_overhead_at_most_15pct"
    assert keys["maps_ci_upper"] == "at_risk_maps_ci_upper_below_1"
    other = protocols.Goals(at_risk_ratio_max=0.5, no_risk_ci_upper_max=1.125, map_p_max=0.05, length_overhead_max=0.2)
    described = other.described()
    assert described["at_risk_ratio_at_most_0.5"] == "at risk: the median APE ratio over pairs at most 0.5"
    assert "no_risk_ci_upper_at_most_1.125" in described and "length_overhead_at_most_20pct" in described
    assert described["at_risk_maps_sign_p_at_most_0.05"].endswith("at most 0.05")
    assert len(described) == len(other.keys()) == 9
