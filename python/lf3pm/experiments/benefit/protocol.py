"""The benefit study's protocol: every setting that decides its outcome, in one versioned
document (docs/benefit.md, "The protocol").

A :class:`Protocol` holds the pair seed and the replay seeds, the cases (each one's
content and a SHA-256 of them all), the guidance compared with its weights, the LIO's
odometry with each chosen odometry's settings, the replays' and localization's
settings, lf3pm's defaults the plans and replays are made with (SOLM, planner, robot,
scan), the at-risk rule (:class:`RiskRule`), the localization-error fit's sampling
(:class:`LocalizationFit`), the per-pair statistics (:class:`Statistics`), the
analysis over maps (``analysis``: records.AnalysisSettings' fields) and the goals the
study is judged by (:class:`Goals`). The field defaults are the study's constants,
written once here (the at-risk rule's in lf3pm.experiments.risk, whose
:class:`RiskRule` this takes; the per-pair comparison's in
lf3pm.experiments.paired_stats, whose :class:`~lf3pm.experiments.paired_stats.PairedSettings`
:meth:`Statistics.paired` gives): ``analysis``, ``records`` and ``localization_error``
read them from :data:`DEFAULT_PROTOCOL`, and a run judges by its protocol's.

Every run writes its protocol to ``DIR/protocol.yaml`` and its :func:`digest` into
summary.json; ``lf3pm experiment benefit --frozen FILE`` refuses to start where the
protocol it would run differs from FILE's (:func:`check_frozen`), naming the first
field that differs; ``--write-protocol FILE`` writes the protocol a run would use,
to freeze it. ``name`` and ``date`` describe the document and are no part of the
comparison nor of the digest.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import MISSING, asdict, fields
from pathlib import Path
from typing import Any, Literal

from pydantic import Field, ValidationError, model_validator

from lf3pm.config import ConfigError, Section, describe
from lf3pm.experiments.paired_stats import PAIRED, PairedSettings
from lf3pm.experiments.risk import RISK, RiskRule

#: The version of the protocol's schema: a document of another is refused (2: the
#: ``goals`` section added; 1 had none).
VERSION = 2
#: Fields that describe the document rather than the study: not compared, not hashed.
METADATA = ("name", "date")


class ProtocolError(ConfigError):
    """A protocol that cannot be read, or that differs from the one a run would use."""


class Statistics(Section):
    """How plans are compared pair by pair (paired_stats.compare, through
    :meth:`paired`; analysis, records): its first five fields' defaults are
    paired_stats.PairedSettings'."""

    bootstrap_draws: int = Field(
        PAIRED.bootstrap_draws, ge=1, description="Bootstrap resamples of the median ratio's interval."
    )
    bootstrap_seed: int = Field(PAIRED.bootstrap_seed, ge=0, description="The bootstrap's seed.")
    ci_level: float = Field(PAIRED.ci_level, gt=0, lt=1, description="The intervals' confidence level.")
    failure_ape_m: float = Field(PAIRED.failure_ape_m, gt=0, description="An APE above this (m) is a failure.")
    worse_margin_m: float = Field(
        PAIRED.worse_margin_m,
        ge=0,
        description="A guided plan is meaningfully worse beyond seed noise and by more than this (m).",
    )
    ape_floor_m: float = Field(1e-4, gt=0, description="Errors are floored to this (m) before ratios and logs.")
    lio_bound_m: float = Field(0.3, gt=0, description="The LIO's bound along a guided plan (m).")

    def paired(self) -> PairedSettings:
        """The settings paired_stats.compare judges each comparison by."""
        return PairedSettings(
            bootstrap_draws=self.bootstrap_draws,
            bootstrap_seed=self.bootstrap_seed,
            ci_level=self.ci_level,
            failure_ape_m=self.failure_ape_m,
            worse_margin_m=self.worse_margin_m,
        )


def _number(value: float, decimals: int = 0) -> str:
    """``value`` as a goal's key writes it: shortest (``%g``), with at least ``decimals``
    decimals (1.10)."""
    short = f"{value:g}"
    fixed = f"{value:.{decimals}f}"
    return fixed if decimals and float(fixed) == value and len(fixed) > len(short) else short


class Goals(Section):
    """The goals the study is judged by (analysis.goal; docs/benefit.md, "The
    protocol"): the judged guidance (``analysis.guidance``) against none, each goal by
    every measure (localization, LIO, LIO from steady starts) but the length overhead.
    Each goal's key in summary.json's ``goal`` is named from its threshold
    (:meth:`described`)."""

    at_risk_ratio_max: float = Field(
        0.3, gt=0, description="At risk: the median APE ratio (guided / none) over pairs at most this."
    )
    at_risk_p_below: float = Field(
        0.01, gt=0, lt=1, description="At risk: the Wilcoxon signed-rank p over pairs below this."
    )
    no_risk_ratio_low: float = Field(0.95, gt=0, description="No risk: the median APE ratio at least this.")
    no_risk_ratio_high: float = Field(1.05, gt=0, description="No risk: the median APE ratio at most this.")
    no_risk_ci_upper_max: float = Field(
        1.10, gt=0, description="No risk: the median ratio's interval (statistics.ci_level) ends at most here."
    )
    no_risk_worse_max_share: float = Field(
        0.10,
        ge=0,
        le=1,
        description="No risk: the share of pairs meaningfully worse (beyond seed noise and by more than "
        "statistics.worse_margin_m) at most this (not judged with one seed).",
    )
    length_overhead_max: float = Field(
        0.15, ge=0, description="The median path length overhead (guided / none - 1, every pair) at most this."
    )
    map_ci_upper_below: float = Field(
        1.0,
        gt=0,
        description="Over the at-risk maps: the geometric-mean ratio's interval (analysis.level; maps, then "
        "pairs, resampled) ends below this.",
    )
    map_p_max: float = Field(
        0.01,
        gt=0,
        lt=1,
        description="Over the at-risk maps: the exact Wilcoxon signed-rank and sign tests of the maps' log "
        "ratios, each at p at most this.",
    )

    @model_validator(mode="after")
    def _ordered(self):
        if self.no_risk_ratio_low > self.no_risk_ratio_high:
            raise ValueError(
                f"no_risk_ratio_low {self.no_risk_ratio_low:g} exceeds no_risk_ratio_high {self.no_risk_ratio_high:g}"
            )
        return self

    def keys(self) -> dict[str, str]:
        """Each goal (by name) and its key in summary.json's ``goal``, named from its
        threshold; after ``<measure>_`` for those judged by measure (all but
        ``length_overhead``)."""
        share = self.no_risk_worse_max_share
        return {
            "at_risk_ratio": f"at_risk_ratio_at_most_{_number(self.at_risk_ratio_max)}",
            "at_risk_p": f"at_risk_wilcoxon_p_below_{_number(self.at_risk_p_below)}",
            "maps_ci_upper": f"at_risk_maps_ci_upper_below_{_number(self.map_ci_upper_below)}",
            "maps_wilcoxon_p": f"at_risk_maps_wilcoxon_p_at_most_{_number(self.map_p_max)}",
            "maps_sign_p": f"at_risk_maps_sign_p_at_most_{_number(self.map_p_max)}",
            "no_risk_ratio": (
                f"no_risk_ratio_within_{_number(self.no_risk_ratio_low)}_{_number(self.no_risk_ratio_high)}"
            ),
            "no_risk_ci_upper": f"no_risk_ci_upper_at_most_{_number(self.no_risk_ci_upper_max, 2)}",
            "no_risk_worse": f"no_risk_worse_on_at_most_{_number(100 * share)}pct",
            "length_overhead": f"length_overhead_at_most_{_number(100 * self.length_overhead_max)}pct",
        }

    def described(self) -> dict[str, str]:
        """Each goal's key (:meth:`keys`) and what it says, with its threshold."""
        texts = {
            "at_risk_ratio": f"at risk: the median APE ratio over pairs at most {self.at_risk_ratio_max:g}",
            "at_risk_p": f"at risk: the Wilcoxon signed-rank p over pairs below {self.at_risk_p_below:g}",
            "maps_ci_upper": (
                f"over the at-risk maps: the geometric-mean ratio's interval ends below {self.map_ci_upper_below:g}"
            ),
            "maps_wilcoxon_p": f"over the at-risk maps: the exact Wilcoxon p at most {self.map_p_max:g}",
            "maps_sign_p": f"over the at-risk maps: the exact sign test's p at most {self.map_p_max:g}",
            "no_risk_ratio": (
                f"no risk: the median APE ratio within [{self.no_risk_ratio_low:g}, {self.no_risk_ratio_high:g}]"
            ),
            "no_risk_ci_upper": (
                f"no risk: the median ratio's interval ends at most at {_number(self.no_risk_ci_upper_max, 2)}"
            ),
            "no_risk_worse": (
                f"no risk: meaningfully worse (beyond seed noise and the worse margin) on at most "
                f"{_number(100 * self.no_risk_worse_max_share)} % of the pairs"
            ),
            "length_overhead": (
                f"the median length overhead (every pair) at most {_number(100 * self.length_overhead_max)} %"
            ),
        }
        return {key: texts[name] for name, key in self.keys().items()}


class LocalizationFit(Section):
    """The localization-error fit (lf3pm.experiments.benefit.localization_error)."""

    rate: float = Field(1.0, gt=0, le=1000, description="Poses per second at which q_n is evaluated.")
    min_plans: int = Field(10, ge=1, description="Fewest plans without a degenerate pose a fit is made from.")


class GuidanceEntry(Section):
    """One guidance compared with none (lf3pm.experiments.guidance.Guidance)."""

    name: str
    channel: str
    power: float
    weight: float


class Lio(Section):
    """The LIO replays: which plans, which odometry (per map: the one chosen for its
    sensor), each chosen odometry's settings (lf3pm's defaults with the configuration's
    replay.odometries over them) and version (lf3pm's build where it has one) and the
    rest limits that judge its rests."""

    plans: Literal["all", "default"] = "all"
    odometry: str = "auto"
    chosen: dict[str, str] = {}
    settings: dict[str, dict[str, Any]] = {}
    versions: dict[str, str] = {}
    rest_window: float = 0.5
    rest_speed_limit: float = 0.05


class Protocol(Section):
    """The benefit study's whole configuration (module docstring)."""

    version: int = VERSION
    name: str = "benefit study"
    date: str = ""
    pair_seed: int = 0
    seeds: int = 3
    #: Each case's fields that differ from MapCase's defaults (:func:`case_content`), in
    #: order (a case's pairs are drawn from its index), and their digest.
    cases: list[dict[str, Any]] = []
    cases_sha256: str = ""
    guidance: list[GuidanceEntry] = []
    lio: Lio = Lio()
    replay: dict[str, Any] = {}
    localization: dict[str, Any] = {}
    defaults: dict[str, dict[str, Any]] = {}
    risk: RiskRule = RiskRule()
    localization_fit: LocalizationFit = LocalizationFit()
    statistics: Statistics = Statistics()
    #: The analysis at the level of the map and of failures (records.AnalysisSettings, its
    #: fields by name: bootstrap, level, failure APE, equivalence margins and alpha, the
    #: tail's largest share, the guidance judged); empty: its defaults.
    analysis: dict[str, Any] = {}
    #: The goals the study is judged by (analysis.goal).
    goals: Goals = Goals()

    def content(self) -> dict:
        """What is compared and hashed: the document less :data:`METADATA`, as JSON."""
        return {k: v for k, v in self.model_dump(mode="json").items() if k not in METADATA}

    def settle(self, benefit, given: set[str] = frozenset()):
        """The benefit section ``benefit`` (lf3pm.config.BenefitConfig) with what this
        protocol settles (replay seeds, pair seed, the LIO's plans and odometry) where
        it holds lf3pm's default and its name is not in ``given`` (flags set): a run
        with ``--frozen FILE`` alone runs FILE's protocol, and one given another value
        is refused by the protocol check."""
        from lf3pm.config import DEFAULTS

        settled = {
            "seeds": self.seeds,
            "pair_seed": self.pair_seed,
            "lio": self.lio.plans,
            "odometry": self.lio.odometry,
        }
        unset = {
            k: v for k, v in settled.items() if k not in given and getattr(benefit, k) == getattr(DEFAULTS.benefit, k)
        }
        return benefit.model_copy(update=unset)

    def digest(self) -> str:
        """SHA-256 of the canonical JSON of :meth:`content`."""
        return hashlib.sha256(canonical(self.content()).encode()).hexdigest()

    def to_yaml(self) -> str:
        import yaml

        head = (
            f"# The benefit study's protocol (lf3pm.experiments.benefit.protocol, version {self.version}).\n"
            f"# sha256 of its content (name and date aside): {self.digest()}\n"
        )
        return head + yaml.safe_dump(self.model_dump(mode="json"), sort_keys=False, width=100)


#: The protocol's defaults: the study's constants (risk, statistics, the fit's sampling, goals).
DEFAULT_PROTOCOL = Protocol()
STATISTICS = DEFAULT_PROTOCOL.statistics
FIT = DEFAULT_PROTOCOL.localization_fit
GOALS = DEFAULT_PROTOCOL.goals


def canonical(data) -> str:
    """JSON with sorted keys and no spaces: the same bytes for the same content."""
    return json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=False, default=_plain)


def _plain(value):
    if hasattr(value, "value"):  # an Enum (Space)
        return value.value
    if isinstance(value, tuple):
        return list(value)
    raise TypeError(f"{type(value).__name__} is not JSON")


def case_content(case) -> dict:
    """A MapCase's fields that differ from MapCase's defaults (a field added later with
    a default that keeps the old behaviour leaves the digest as it was), as JSON."""
    out = {}
    for f in fields(case):
        value = getattr(case, f.name)
        if f.default is not MISSING:
            default = f.default
        elif f.default_factory is not MISSING:
            default = f.default_factory()
        else:
            out[f.name] = value  # a field without a default: always stated
            continue
        if value != default:
            out[f.name] = value
    plain = json.loads(canonical(out))
    return {"name": plain.pop("name"), **plain} if "name" in plain else plain


def cases_digest(cases) -> str:
    """SHA-256 of the cases' canonical content, in their order (a case's pairs are drawn
    from its index)."""
    return hashlib.sha256(canonical([case_content(c) for c in cases]).encode()).hexdigest()


#: The replay section's rest limits: the LIO's (Lio), not the replays' in general.
_REST = ("rest_window", "rest_speed_limit")


def build(
    *,
    cases,
    guidance,
    pair_seed: int,
    seeds: int,
    lio: str,
    odometry: str,
    chosen: dict[str, str],
    replay,
    risk: RiskRule = RISK,
    statistics: Statistics = STATISTICS,
    localization_fit: LocalizationFit = FIT,
    analysis: dict | None = None,
    goals: Goals = GOALS,
    name: str = DEFAULT_PROTOCOL.name,
    date: str = "",
) -> Protocol:
    """The protocol of a run with these settings: ``cases`` (MapCases), ``guidance``
    (Guidance, without none), ``chosen`` (the odometry the LIO runs on each case, for
    ``odometry``: study.lio_run), ``replay`` (the replay section whose odometries'
    settings and rest limits the LIO runs with; its other settings are lf3pm's defaults,
    which the replays run with), ``analysis`` (records.AnalysisSettings' fields)."""
    from lf3pm.config import DEFAULTS
    from lf3pm.replays import registry

    keys = sorted(set(chosen.values()))
    sections = registry.settings(replay.odometries)
    fixed = DEFAULTS.replay.model_dump(mode="json")
    return Protocol(
        name=name,
        date=date,
        pair_seed=pair_seed,
        seeds=seeds,
        cases=[case_content(case) for case in cases],
        cases_sha256=cases_digest(cases),
        guidance=[GuidanceEntry(**asdict(g)) for g in guidance],
        lio=Lio(
            plans=lio,
            odometry=odometry,
            chosen=dict(chosen),
            settings={key: sections[key].model_dump(mode="json") for key in keys},
            versions={key: _version(registry.odometry(key)) for key in keys},
            rest_window=replay.rest_window,
            rest_speed_limit=replay.rest_speed_limit,
        ),
        replay={k: v for k, v in fixed.items() if k not in ("method", "seeds", "odometry", "odometries", *_REST)},
        localization=DEFAULTS.localization.model_dump(mode="json"),
        defaults={s: getattr(DEFAULTS, s).model_dump(mode="json") for s in ("solm", "planner", "robot", "scan")},
        risk=risk,
        statistics=statistics,
        localization_fit=localization_fit,
        goals=goals,
        analysis=dict(analysis or {}),
    )


def _version(adapter) -> str:
    """The version an odometry's replays run with: lf3pm's build of it where it has one."""
    return str(getattr(adapter, "build", None) or adapter.version)


def first_difference(frozen, current, path: str = "protocol") -> tuple[str, Any, Any] | None:
    """(dotted path, frozen value, current value) of the first place two protocols'
    contents (or parts of them) differ, in the frozen one's order; None where equal."""
    if isinstance(frozen, dict) and isinstance(current, dict):
        for key in list(frozen) + [k for k in current if k not in frozen]:
            if key not in current or key not in frozen:
                return (f"{path}.{key}", frozen.get(key, "(absent)"), current.get(key, "(absent)"))
            found = first_difference(frozen[key], current[key], f"{path}.{key}")
            if found:
                return found
        return None
    if isinstance(frozen, list) and isinstance(current, list):
        for i, (a, b) in enumerate(zip(frozen, current)):
            found = first_difference(a, b, f"{path}[{i}]")
            if found:
                return found
        if len(frozen) != len(current):
            return (f"{path} (length)", len(frozen), len(current))
        return None
    if _same(frozen, current):
        return None
    return (path, frozen, current)


def _same(a, b) -> bool:
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return a == b or (math.isnan(a) and math.isnan(b))
    return a == b


def _shown(value) -> str:
    return json.dumps(value) if isinstance(value, (str, dict, list)) else str(value)


def compared(frozen: Protocol, current: Protocol, what: str = "frozen", other: str = "this run") -> str | None:
    """One line naming the first field where ``current`` differs from ``frozen`` (None:
    the same), e.g. ``protocol.risk.factor: frozen 10.0, this run 9.0``."""
    found = first_difference(frozen.content(), current.content())
    if found is None:
        return None
    path, a, b = found
    return f"{path}: {what} {_shown(a)}, {other} {_shown(b)}"


def check_frozen(frozen: Protocol, current: Protocol, path) -> None:
    """ProtocolError in one line where ``current`` is not the protocol frozen in ``path``."""
    line = compared(frozen, current)
    if line is not None:
        raise ProtocolError(f"{line} (--frozen {path}: this run's protocol differs; nothing was run)")


def read_protocol(path) -> Protocol:
    """The protocol of a YAML file; ProtocolError in one line naming the file otherwise."""
    from lf3pm.limits import load_yaml, read_text_file

    text = read_text_file(path, "protocol", ProtocolError)
    try:
        import yaml

        data = load_yaml(text, path, ProtocolError)
    except yaml.YAMLError as err:
        raise ProtocolError(f"{path}: not YAML ({str(err).splitlines()[0]})") from None
    if not isinstance(data, dict):
        raise ProtocolError(f"{path}: a protocol is a mapping of its fields")
    if data.get("version") != VERSION:
        again = (
            " (version 1 has no goals section: write it again with --write-protocol)"
            if data.get("version") == 1
            else ""
        )
        raise ProtocolError(f"{path}: a protocol of version {data.get('version')!r}, not {VERSION}{again}")
    try:
        return Protocol(**data)
    except ValidationError as err:
        raise ProtocolError(f"{path}: {describe(err, 'protocol')}") from None


def write_protocol(path, protocol: Protocol) -> None:
    """``protocol`` as YAML at ``path`` (atomically)."""
    from lf3pm.atomic import atomic_write

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(Path(path)) as fp:
        fp.write(protocol.to_yaml().encode())


def check_folder(path, protocol: Protocol) -> None:
    """ProtocolError in one line where the study folder's protocol.yaml (``path``) was
    written under another protocol than ``protocol`` (the LIO's odometry and its
    settings aside: its replays are labelled apart, docs/benefit.md); none there: the
    folder is new or older than protocols."""
    if not Path(path).exists():
        return
    before = read_protocol(path)
    same_lio = {"lio": protocol.lio}
    line = compared(before.model_copy(update=same_lio), protocol, "the folder's", "this run")
    if line is not None:
        raise ProtocolError(
            f"{Path(path).parent} was made under another protocol ({line}): use another folder rather than mix them"
        )
