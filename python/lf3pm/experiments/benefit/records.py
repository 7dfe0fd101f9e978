"""The benefit study's records and where they are kept: its data model.

A study folder (:class:`StudyFolder`) holds each map's SOLM, each plan's trajectory
CSV, one JSON per replay, one JSON per plan's predictor and ``summary.json``. The
types here are what the study computes, and what its report, figures and tests
read: a :class:`Pair` of start and goal with one :class:`Plan` per guidance; each
plan's replays by one method over the seeds (:class:`SeedReplays`, made of one
:class:`Replay` per seed); the paired statistics (:class:`Comparison`), grouped by
:class:`Measure`; and the whole :class:`Summary`.

Every JSON the study caches carries ``"schema": SCHEMA``; one written by another
version of these records is refused (:class:`StaleRecordError`, naming the file)
rather than read wrongly.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from lf3pm.config import REPLAY_METHODS
from lf3pm.errors import Lf3pmError
from lf3pm.experiments.benefit.protocol import STATISTICS
from lf3pm.experiments.guidance import UNGUIDED, Guidance
from lf3pm.experiments.map_cases import MapCase
from lf3pm.experiments.paired_stats import Comparison
from lf3pm.experiments.replay_tasks import load_replay, replay_json

#: The version of the records' JSON; written in every JSON the study caches.
SCHEMA = 1

#: An APE below this (m, 0.1 mm) is rounding: errors are floored to it before ratios,
#: logarithms and log axes, which need a positive error (the protocol's
#: statistics.ape_floor_m).
APE_FLOOR = STATISTICS.ape_floor_m

#: The names of the groups of pairs over maps (MeasureAnalysis.over_maps, both_succeed,
#: failures); the goals judge the at-risk one.
EVERY_PAIR, AT_RISK, NO_RISK = "every pair", "at risk", "no risk"


def _method(name: str) -> str:
    """A replay method's name as lf3pm.config lists it (the names' one place)."""
    if name not in REPLAY_METHODS:
        raise ImportError(f"the benefit study needs the replay method {name!r}; lf3pm.config lists {REPLAY_METHODS}")
    return name


#: The replay methods the study judges plans by: map localization, and the LIO.
LOCALIZATION = _method("localization")
LIO = _method("lio")
#: The guidance name of the unguided plan, and of the one the study's goal is about
#: (experiments.guidance: the shipped default's).
NONE = UNGUIDED.name
DEFAULT = "default"


class StaleRecordError(Lf3pmError):
    """A study's cached JSON was written by another version of its records (or none)."""


def versioned(data: dict) -> dict:
    """``data`` with the schema version first, as the study writes its JSON."""
    return {"schema": SCHEMA, **data}


def checked(data, path) -> dict:
    """``data`` read from ``path``, without its schema version; a StaleRecordError where
    that is not :data:`SCHEMA`."""
    found = data.get("schema") if isinstance(data, dict) else None
    if found != SCHEMA:
        written = "no schema version" if found is None else f"schema {found!r}"
        raise StaleRecordError(
            f"{path}: written with {written}, this lf3pm reads the benefit study's schema {SCHEMA}; "
            "run the study into a new folder"
        )
    return {k: v for k, v in data.items() if k != "schema"}


def read_json(path) -> dict:
    """A JSON the study cached, its schema version checked (:func:`checked`)."""
    return checked(json.loads(Path(path).read_text(encoding="utf-8")), path)


def write_json(path, data: dict, *, indent=None) -> None:
    """Writes ``data`` with the schema version, atomically."""
    from lf3pm.atomic import atomic_write

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(Path(path)) as fp:
        fp.write(json.dumps(versioned(data), indent=indent).encode())


# --- runs of the LIO ------------------------------------------------------------------


@dataclass(frozen=True)
class LioRun:
    """The odometry the LIO replays of one map run, and the label of their JSONs:
    ``lio`` for the odometry the sensor's auto choice picks, else ``lio-<odometry>``;
    with settings other than lf3pm's, ``lio-<odometry>.<digest of them>`` (each odometry
    and each of its settings keeps its own replays in one study folder)."""

    odometry: str
    label: str

    @classmethod
    def of(cls, odometry: str, auto: str, options: dict | None = None) -> LioRun:
        """The run of ``odometry`` where auto's choice is ``auto``, given ``options``
        (settings that differ from lf3pm's) beyond its name."""
        if options:
            digest = hashlib.sha256(json.dumps(options, sort_keys=True).encode()).hexdigest()[:8]
            return cls(odometry, f"{LIO}-{odometry}.{digest}")
        return cls(odometry, LIO if odometry == auto else f"{LIO}-{odometry}")


def replay_label(method: str, lio_run: LioRun) -> str:
    """The label of ``method``'s replay JSONs on a map whose LIO runs as ``lio_run``."""
    return lio_run.label if method == LIO else method


# --- the folder -----------------------------------------------------------------------


@dataclass(frozen=True)
class StudyFolder:
    """Where a study keeps what it computes, under ``root``."""

    root: Path

    def solm(self, case: str) -> Path:
        return self.root / "solm" / f"{case}.zarr"

    def trajectories(self, case: str) -> Path:
        return self.root / "trajectories" / case

    def replays(self, case: str) -> Path:
        return self.root / "replays" / case

    def replay(self, case: str, pair: int, guidance: str, label: str, seed: int) -> Path:
        """One replay's JSON (replay_tasks.replay_task); ``label``: :func:`replay_label`."""
        return replay_json(self.replays(case), plan_prefix(pair, guidance), label, seed)

    def predictor(self, case: str, pair: int, guidance: str) -> Path:
        return self.root / "predictors" / case / f"{pair:02d}_{guidance}.json"

    @property
    def summary(self) -> Path:
        return self.root / "summary.json"

    @property
    def report(self) -> Path:
        return self.root / "benefit.md"

    @property
    def pair_records(self) -> Path:
        """pairs.jsonl: one :class:`Pair` a line (:func:`write_records`)."""
        return self.root / "pairs.jsonl"

    @property
    def replay_records(self) -> Path:
        """replays.jsonl: one :class:`Replay` a line, with its plan, method and seed."""
        return self.root / "replays.jsonl"

    @property
    def forest(self) -> Path:
        return self.root / "maps.png"

    @property
    def examples(self) -> Path:
        return self.root / "examples"


def plan_prefix(pair: int, guidance: str) -> str:
    """The name shared by a plan's replays (replay_tasks.replay_json)."""
    return f"{pair:02d}_{guidance}_"


# --- replays --------------------------------------------------------------------------


@dataclass(frozen=True)
class Replay:
    """What the study reads of one replay (one seed): its APE rmse, the share of
    degenerate scans, the scans, its CPU seconds, whether the LIO held still during its
    rest (None: no rest, map localization) and its error once per second."""

    ape_rmse: float
    degenerate_share: float
    scans: int
    seconds: float
    rest_steady: bool | None
    times_every_second: tuple[float, ...] = ()
    errors_every_second: tuple[float, ...] = ()


def read_replay(path) -> Replay:
    """One replay's JSON (written by replay_tasks.replay_task): the one place the study
    reads replays."""
    raw = load_replay(path)
    rest = raw.get("rest")
    return Replay(
        ape_rmse=raw["ape_rmse"],
        degenerate_share=raw["degenerate_share"],
        scans=raw["scans"],
        seconds=raw["seconds"],
        rest_steady=None if rest is None else bool(rest["steady"]),
        times_every_second=tuple(raw.get("times_every_second", ())),
        errors_every_second=tuple(raw.get("errors_every_second", ())),
    )


@dataclass(frozen=True)
class SeedReplays:
    """A plan's replays by one method over the seeds: the median APE rmse, each seed's,
    the median share of degenerate scans and the first seed's scans; for the LIO whether
    each seed's rest was steady (replay_result.rest_motion; None: not recorded)."""

    ape: float
    ape_per_seed: tuple[float, ...]
    degenerate_share: float
    scans: int
    rest_steady_per_seed: tuple[bool, ...] | None = None

    @classmethod
    def of(cls, runs: list[Replay]) -> SeedReplays:
        apes = [r.ape_rmse for r in runs]
        rests = [r.rest_steady for r in runs]
        return cls(
            ape=float(np.median(apes)),
            ape_per_seed=tuple(apes),
            degenerate_share=float(np.median([r.degenerate_share for r in runs])),
            scans=runs[0].scans,
            rest_steady_per_seed=None if None in rests else tuple(rests),
        )

    def on_seeds(self, keep: list[int]) -> SeedReplays:
        """The same replays on the seeds ``keep`` only."""
        apes = tuple(self.ape_per_seed[k] for k in keep)
        rests = None if self.rest_steady_per_seed is None else tuple(self.rest_steady_per_seed[k] for k in keep)
        return replace(self, ape=float(np.median(apes)), ape_per_seed=apes, rest_steady_per_seed=rests)

    def to_json(self) -> dict:
        out = {"ape": self.ape, "ape_per_seed": list(self.ape_per_seed), "degenerate_share": self.degenerate_share}
        if self.rest_steady_per_seed is not None:
            out["rest_steady_per_seed"] = list(self.rest_steady_per_seed)
        out["scans"] = self.scans
        return out

    @classmethod
    def from_json(cls, d: dict) -> SeedReplays:
        rests = d.get("rest_steady_per_seed")
        return cls(
            d["ape"],
            tuple(d["ape_per_seed"]),
            d["degenerate_share"],
            d["scans"],
            None if rests is None else tuple(rests),
        )


# --- plans and pairs ------------------------------------------------------------------


@dataclass(frozen=True)
class Predictor:
    """q_n along a plan (lf3pm.evaluate at its poses; localization_error.py):
    its time mean over the non-degenerate poses, the share of degenerate ones, the count."""

    q_n_mean: float
    degenerate_share: float
    poses: int

    def to_json(self) -> dict:
        return asdict(self)

    @classmethod
    def from_json(cls, d: dict) -> Predictor:
        return cls(d["q_n_mean"], d["degenerate_share"], d["poses"])


@dataclass(frozen=True)
class Plan:
    """One guidance's plan of a pair: its trajectory CSV (relative to the study folder),
    length, duration, limit ratios (Plan.summary's violations), each SOLM channel's mean
    along it; its replays by method and its exact q_n, once known."""

    guidance: str
    csv: str
    length_m: float
    duration_s: float
    violations: Mapping[str, float]
    solm_mean: Mapping[str, float]
    replays: Mapping[str, SeedReplays] = field(default_factory=dict)
    q_n_exact: Predictor | None = None

    def to_json(self) -> dict:
        out = {
            "csv": self.csv,
            "length_m": self.length_m,
            "duration_s": self.duration_s,
            "violations": dict(self.violations),
            "solm_mean": dict(self.solm_mean),
        }
        out.update({method: r.to_json() for method, r in self.replays.items()})
        if self.q_n_exact is not None:
            out["q_n_exact"] = self.q_n_exact.to_json()
        return out

    @classmethod
    def from_json(cls, guidance: str, d: dict) -> Plan:
        return cls(
            guidance,
            d["csv"],
            d["length_m"],
            d["duration_s"],
            dict(d["violations"]),
            dict(d["solm_mean"]),
            {m: SeedReplays.from_json(d[m]) for m in (LOCALIZATION, LIO) if m in d},
            Predictor.from_json(d["q_n_exact"]) if "q_n_exact" in d else None,
        )


@dataclass(frozen=True)
class Pair:
    """A start/goal pair of a map (``number``: its index among the map's pairs), the
    robot that drives it, whether it is at risk (experiments/risk.py: the share of its
    unguided plan's poses at risk) and its plans by guidance name, the unguided first."""

    case: str
    number: int
    robot: str
    start: tuple[float, float, float]
    goal: tuple[float, float, float]
    risk_share: float
    at_risk: bool
    plans: Mapping[str, Plan]

    def both(self, guidance: str, method: str) -> tuple[SeedReplays, SeedReplays] | None:
        """The (guided, unguided) replays by ``method`` of the plans ``guidance`` and
        none, where both exist."""
        guided, unguided = self.plans.get(guidance), self.plans[NONE]
        if guided is None or method not in guided.replays or method not in unguided.replays:
            return None
        return guided.replays[method], unguided.replays[method]

    def to_json(self) -> dict:
        return {
            "case": self.case,
            "pair": self.number,
            "robot": self.robot,
            "start": list(self.start),
            "goal": list(self.goal),
            "risk_share": self.risk_share,
            "at_risk": self.at_risk,
            "plans": {name: plan.to_json() for name, plan in self.plans.items()},
        }

    @classmethod
    def from_json(cls, d: dict) -> Pair:
        return cls(
            d["case"],
            d["pair"],
            d["robot"],
            tuple(d["start"]),
            tuple(d["goal"]),
            d["risk_share"],
            d["at_risk"],
            {name: Plan.from_json(name, p) for name, p in d["plans"].items()},
        )


# --- comparisons ----------------------------------------------------------------------


@dataclass(frozen=True)
class Measure:
    """What judges a plan: a replay method's error, with ``steady_starts`` on the seeds
    at which both plans' LIO held still during its rest only (replay_result.rest_motion:
    where it did not, the LIO entered the plan moving and its APE measures that start,
    not the plan; docs/lio.md, "A still sensor")."""

    method: str
    steady_starts: bool = False

    @property
    def key(self) -> str:
        """Its name in summary.json."""
        return f"{self.method}_steady" if self.steady_starts else self.method

    @property
    def title(self) -> str:
        """Its name in the report."""
        name = self.method if self.method == LOCALIZATION else self.method.upper()
        return f"{name}, steady starts" if self.steady_starts else name


#: The measures the study compares plans by, in the report's order.
MEASURES = (Measure(LOCALIZATION), Measure(LIO), Measure(LIO, steady_starts=True))


@dataclass(frozen=True)
class RiskSplit:
    """A comparison on the pairs at risk and on the others."""

    at_risk: Comparison
    no_risk: Comparison

    def to_json(self) -> dict:
        return {"at_risk": self.at_risk.to_json(), "no_risk": self.no_risk.to_json()}

    @classmethod
    def from_json(cls, d: dict) -> RiskSplit:
        return cls(Comparison.from_json(d["at_risk"]), Comparison.from_json(d["no_risk"]))


@dataclass(frozen=True)
class Comparisons:
    """Every guidance against none by one measure: over all pairs, split by risk, and
    (where the default guidance ran) the default per map and per robot."""

    by_guidance: Mapping[str, Comparison]
    by_risk: Mapping[str, RiskSplit]
    default_by_map: Mapping[str, Comparison] | None = None
    default_by_robot: Mapping[str, Comparison] | None = None

    #: Keys of summary.json's comparisons beside the guidance names.
    GROUPS = ("by_risk", "default_by_map", "default_by_robot")

    def to_json(self) -> dict:
        out = {name: c.to_json() for name, c in self.by_guidance.items()}
        out["by_risk"] = {name: s.to_json() for name, s in self.by_risk.items()}
        if self.default_by_map is not None:
            out["default_by_map"] = {name: c.to_json() for name, c in self.default_by_map.items()}
            out["default_by_robot"] = {name: c.to_json() for name, c in self.default_by_robot.items()}
        return out

    @classmethod
    def from_json(cls, d: dict) -> Comparisons:
        def group(key):
            return {k: Comparison.from_json(v) for k, v in d[key].items()} if key in d else None

        return cls(
            {k: Comparison.from_json(v) for k, v in d.items() if k not in cls.GROUPS},
            {k: RiskSplit.from_json(v) for k, v in d["by_risk"].items()},
            group("default_by_map"),
            group("default_by_robot"),
        )


# --- what else the summary holds ------------------------------------------------------


@dataclass(frozen=True)
class RestCount:
    """A map's LIO replays, and those whose odometry moved while the sensor stood still."""

    replays: int = 0
    unsteady: int = 0


@dataclass(frozen=True)
class ChannelFit:
    """How one SOLM channel's mean along a plan predicts a replay method's APE: Spearman
    rho pooled and within maps (mean), and the slope of log APE on log channel."""

    plans: int
    spearman_pooled: float
    spearman_within_mean: float
    log_log_slope: float


@dataclass(frozen=True)
class BeyondPair:
    """A pair whose default-guided plan's LIO APE exceeds the bound, with its unguided plan's."""

    case: str
    pair: int
    robot: str
    at_risk: bool
    guided_m: float
    unguided_m: float


@dataclass(frozen=True)
class BeyondBound:
    """The default-guided plans whose LIO APE exceeds ``bound_m``, among the
    ``pairs_replayed`` pairs whose default and unguided plans the LIO replayed."""

    bound_m: float
    pairs_replayed: int
    pairs: tuple[BeyondPair, ...]

    def to_json(self) -> dict:
        return {
            "bound_m": self.bound_m,
            "pairs_replayed": self.pairs_replayed,
            "pairs": [asdict(p) for p in self.pairs],
        }

    @classmethod
    def from_json(cls, d: dict) -> BeyondBound:
        return cls(d["bound_m"], d["pairs_replayed"], tuple(BeyondPair(**p) for p in d["pairs"]))


@dataclass(frozen=True)
class MapValidation:
    """The localization-error fit made without one map, judged on that map's plans."""

    plans: int
    share_inside_interval: float
    spearman_within_map: float | None
    median_factor: float


@dataclass(frozen=True)
class ErrorFit:
    """The localization error predicted from q_n (calibration.fit_on_q_n's
    JSON, ``data``, as written to localization_error.json); ``a`` is None where too few
    plans were left to fit (a quick run)."""

    data: Mapping

    @property
    def fitted(self) -> bool:
        return "a" in self.data

    @property
    def a(self) -> float:
        return self.data["a"]

    @property
    def b(self) -> float:
        return self.data["b"]

    @property
    def interval_factors(self) -> tuple[float, float]:
        """The 10-90 % interval of the residuals, as factors on the prediction."""
        return math.exp(self.data["log_lo"]), math.exp(self.data["log_hi"])

    @property
    def samples(self) -> int:
        return self.data["samples"]

    @property
    def validation(self) -> dict[str, MapValidation]:
        return {name: MapValidation(**v) for name, v in self.data.get("validation", {}).items()}


@dataclass(frozen=True)
class Parameters:
    """The constants the study judged by, for the report: failure APE and worse margin
    (paired_stats), the at-risk rule (risk), the LIO's rest speed limit (the replay section's)."""

    failure_ape_m: float
    worse_margin_m: float
    at_risk_share: float
    risk_factor: float
    rest_speed_limit_mps: float


@dataclass(frozen=True)
class AnalysisSettings:
    """The settings of the analysis at the level of the map and of failures
    (analysis.analyse; docs/benefit.md, "How the study is analysed"), written once here
    with their defaults: the bootstrap's resamples and seed, the intervals' level; the
    APE beyond which a replay counts as failed (the LIO diverged); the no-harm
    equivalence margins on the geometric-mean ratio and its alpha (TOST: the
    1 - 2 alpha interval inside the margins); the largest share of no-risk pairs worse
    beyond seed noise that still counts as no harm; the guidance judged."""

    bootstrap_draws: int = 2000
    bootstrap_seed: int = 0
    level: float = 0.95
    failure_ape_m: float = 1.0
    equivalence_low: float = 0.9
    equivalence_high: float = 1 / 0.9
    equivalence_alpha: float = 0.05
    tail_max_share: float = 0.10
    guidance: str = DEFAULT


@dataclass(frozen=True)
class Effect:
    """The geometric-mean APE ratio (guided / unguided) of a group of pairs, with its
    bootstrap interval: one map (resampling its pairs), or several maps (resampling
    maps, then pairs within each: each map weighs the same); over maps also the exact
    Wilcoxon and sign tests of the maps' log ratios, the least p they can reach with
    that many maps and how many maps' ratios are below 1."""

    name: str
    maps: int
    pairs: int
    ratio: float
    ci: tuple[float, float]
    wilcoxon_p: float = math.nan
    sign_p: float = math.nan
    minimum_p: float = math.nan
    maps_below_1: int = 0

    @property
    def gains_nothing(self) -> bool:
        """Its interval reaches 1 (or it has no pairs): no gain shown."""
        return not self.pairs or not self.ci[1] < 1.0

    @classmethod
    def from_json(cls, d: dict) -> Effect:
        return cls(**{**d, "ci": tuple(d["ci"])})


@dataclass(frozen=True)
class Failures:
    """A paired binary outcome, the replay failed (APE > ``threshold_m``), over some
    pairs: both failed, the guided plan only, the unguided only, neither; McNemar's
    exact p on the discordant pairs."""

    name: str
    threshold_m: float
    both: int
    guided_only: int
    unguided_only: int
    neither: int
    mcnemar_p: float

    @property
    def pairs(self) -> int:
        return self.both + self.guided_only + self.unguided_only + self.neither


@dataclass(frozen=True)
class Equivalence:
    """ "No harm" as a pre-set equivalence test on the no-risk pairs: the geometric-mean
    ratio over maps with its 1 - 2 alpha two-stage bootstrap interval, inside
    [low, high] or not (TOST by interval inclusion: guidance changes nothing), its upper
    end below ``high`` or not (non-inferiority: guidance does no harm, it may help), the
    two one-sided t tests over the maps' log ratios (p, a check); the tail: the share of pairs worse beyond seed noise
    and its one-sided upper bound against ``tail_max_share`` (None: one seed, no seed
    noise to judge by)."""

    low: float
    high: float
    alpha: float
    maps: int
    pairs: int
    ratio: float
    ci: tuple[float, float]
    equivalent: bool
    not_worse: bool
    tost_p_over_maps: float
    tail_pairs: int
    tail_worse: int
    tail_share: float
    tail_upper: float
    tail_max_share: float
    tail_no_harm: bool | None

    @classmethod
    def from_json(cls, d: dict) -> Equivalence:
        return cls(**{**d, "ci": tuple(d["ci"])})


@dataclass(frozen=True)
class MeasureAnalysis:
    """One measure's analysis at the level of the map (the default guidance against
    none): each map's effect, each map and robot's, over maps for every pair, at risk,
    no risk and per robot; the same where both plans succeeded; failures overall, at
    risk, no risk and per map; the no-harm test; each map's effect on its at-risk pairs."""

    by_map: tuple[Effect, ...]
    by_map_robot: tuple[Effect, ...]
    over_maps: tuple[Effect, ...]
    both_succeed: tuple[Effect, ...]
    failures: tuple[Failures, ...]
    failures_by_map: tuple[Failures, ...]
    no_harm: Equivalence | None
    at_risk_by_map: tuple[Effect, ...] = ()

    def to_json(self) -> dict:
        return asdict(self)

    @classmethod
    def from_json(cls, d: dict) -> MeasureAnalysis:
        def effects(key):
            return tuple(Effect.from_json(e) for e in d[key])

        return cls(
            effects("by_map"),
            effects("by_map_robot"),
            effects("over_maps"),
            effects("both_succeed"),
            tuple(Failures(**f) for f in d["failures"]),
            tuple(Failures(**f) for f in d["failures_by_map"]),
            None if d["no_harm"] is None else Equivalence.from_json(d["no_harm"]),
            effects("at_risk_by_map") if "at_risk_by_map" in d else (),  # summaries before 2026-12-05
        )


@dataclass(frozen=True)
class MapAnalysis:
    """The analysis at the level of the map, by measure key, with its settings."""

    settings: AnalysisSettings
    by_measure: Mapping[str, MeasureAnalysis]

    def to_json(self) -> dict:
        return {"settings": asdict(self.settings), **{k: m.to_json() for k, m in self.by_measure.items()}}

    @classmethod
    def from_json(cls, d: dict) -> MapAnalysis:
        return cls(
            AnalysisSettings(**d["settings"]),
            {k: MeasureAnalysis.from_json(v) for k, v in d.items() if k != "settings"},
        )


@dataclass(frozen=True)
class Redraw:
    """A draw of a pair that was replaced (study.plan_pairs): its map, the draw's number
    among the map's draws and why (an end with no free cell, ends too close, a guidance
    that could not plan it)."""

    case: str
    draw: int
    reason: str


def _case(d: dict) -> MapCase:
    d = dict(d)
    d["robots"] = tuple(d["robots"])
    if d["bounds"] is not None:
        d["bounds"] = tuple(d["bounds"])
    if d["zones"] is not None:
        d["zones"] = {k: tuple(v) for k, v in d["zones"].items()}
    return MapCase(**d)


@dataclass(frozen=True)
class Summary:
    """A whole study: its setup, every pair with its plans and replays, the comparisons
    by measure and what the report adds (rest counts, calibration, the LIO's bound, the
    goal, the localization-error fit)."""

    seeds: int
    pair_seed: int
    runtime_s: float
    lio_guidance: tuple[str, ...]
    lio_runs: Mapping[str, LioRun]
    odometry_names: Mapping[str, str]
    replay_cpu_s: float
    parameters: Parameters
    cases: tuple[MapCase, ...]
    guidance: tuple[Guidance, ...]
    pairs: tuple[Pair, ...]
    comparisons: Mapping[str, Comparisons]
    lio_rest: Mapping[str, RestCount]
    calibration: Mapping[str, Mapping[str, ChannelFit]]
    lio_beyond_bound: BeyondBound
    goal: Mapping[str, bool | None]
    localization_error: ErrorFit
    #: The analysis at the level of the map (None: a summary written before it).
    map_analysis: MapAnalysis | None = None
    #: The draws of pairs replaced (None: a run that did not count them).
    redrawn: tuple[Redraw, ...] | None = None
    #: The SHA-256 of the protocol it ran under (protocol.Protocol.digest; DIR/protocol.yaml);
    #: None: a summary written before protocols.
    protocol_sha256: str | None = None

    def compared(self, measure: Measure) -> Comparisons:
        return self.comparisons[measure.key]

    @property
    def guided(self) -> tuple[Guidance, ...]:
        """The guidance compared with none."""
        return tuple(g for g in self.guidance if g.name != NONE)

    def odometry_line(self) -> str:
        """Which odometry ran the LIO replays of which maps, e.g. "DLIO: tunnel, houses;
        GenZ-LIO: gobi"."""
        maps: dict = {}
        for case, run in self.lio_runs.items():
            maps.setdefault(self.odometry_names[run.odometry], []).append(case)
        return "; ".join(f"{name}: {', '.join(cases)}" for name, cases in maps.items())

    def to_json(self) -> dict:
        p = self.parameters
        return versioned(
            {
                "experiment": "benefit",
                "seeds": self.seeds,
                "pair_seed": self.pair_seed,
                "runtime_s": self.runtime_s,
                "lio_guidance": list(self.lio_guidance),
                "lio_odometry": {case: run.odometry for case, run in self.lio_runs.items()},
                "lio_labels": {case: run.label for case, run in self.lio_runs.items()},
                "odometry_names": dict(self.odometry_names),
                "replay_cpu_s": self.replay_cpu_s,
                "failure_ape_m": p.failure_ape_m,
                "worse_margin_m": p.worse_margin_m,
                "at_risk_share": p.at_risk_share,
                "risk_factor": p.risk_factor,
                "rest_speed_limit_mps": p.rest_speed_limit_mps,
                "cases": [asdict(c) for c in self.cases],
                "guidance": [asdict(g) for g in self.guidance],
                "pairs": [pair.to_json() for pair in self.pairs],
                "comparisons": {key: c.to_json() for key, c in self.comparisons.items()},
                "lio_rest": {case: asdict(c) for case, c in self.lio_rest.items()},
                "calibration": {m: {ch: asdict(f) for ch, f in fits.items()} for m, fits in self.calibration.items()},
                "lio_beyond_bound": self.lio_beyond_bound.to_json(),
                "goal": dict(self.goal),
                "localization_error": dict(self.localization_error.data),
                **({} if self.map_analysis is None else {"map_analysis": self.map_analysis.to_json()}),
                **({} if self.redrawn is None else {"redrawn": [asdict(r) for r in self.redrawn]}),
                **({} if self.protocol_sha256 is None else {"protocol_sha256": self.protocol_sha256}),
            }
        )

    @classmethod
    def from_json(cls, data: dict, path) -> Summary:
        d = checked(data, path)
        labels = d["lio_labels"]
        return cls(
            seeds=d["seeds"],
            pair_seed=d["pair_seed"],
            runtime_s=d["runtime_s"],
            lio_guidance=tuple(d["lio_guidance"]),
            lio_runs={case: LioRun(odometry, labels[case]) for case, odometry in d["lio_odometry"].items()},
            odometry_names=dict(d["odometry_names"]),
            replay_cpu_s=d["replay_cpu_s"],
            parameters=Parameters(
                d["failure_ape_m"], d["worse_margin_m"], d["at_risk_share"], d["risk_factor"], d["rest_speed_limit_mps"]
            ),
            cases=tuple(_case(c) for c in d["cases"]),
            guidance=tuple(Guidance(**g) for g in d["guidance"]),
            pairs=tuple(Pair.from_json(p) for p in d["pairs"]),
            comparisons={key: Comparisons.from_json(c) for key, c in d["comparisons"].items()},
            lio_rest={case: RestCount(**c) for case, c in d["lio_rest"].items()},
            calibration={m: {ch: ChannelFit(**f) for ch, f in fits.items()} for m, fits in d["calibration"].items()},
            lio_beyond_bound=BeyondBound.from_json(d["lio_beyond_bound"]),
            goal=dict(d["goal"]),
            localization_error=ErrorFit(d["localization_error"]),
            map_analysis=MapAnalysis.from_json(d["map_analysis"]) if "map_analysis" in d else None,
            redrawn=tuple(Redraw(**r) for r in d["redrawn"]) if "redrawn" in d else None,
            protocol_sha256=d.get("protocol_sha256"),
        )


def read_summary(path) -> Summary:
    """A study's summary.json (refused, naming the file, where its schema is not ours)."""
    return Summary.from_json(json.loads(Path(path).read_text(encoding="utf-8")), path)


def write_summary(path, summary: Summary) -> None:
    from lf3pm.atomic import atomic_write

    with atomic_write(Path(path)) as fp:
        fp.write(json.dumps(summary.to_json(), indent=1).encode())


# --- records as JSON Lines ------------------------------------------------------------


def _jsonl(path, rows) -> None:
    from lf3pm.atomic import atomic_write

    with atomic_write(Path(path)) as fp:
        fp.write("".join(json.dumps(versioned(row)) + "\n" for row in rows).encode())


def replay_rows(folder: StudyFolder, summary: Summary):
    """Each replay of the summary's plans found in ``folder`` as one record: its map,
    pair, guidance, method, label, seed and :class:`Replay`'s fields."""
    for pair in summary.pairs:
        for name, plan in pair.plans.items():
            for method, seeds in plan.replays.items():
                label = replay_label(method, summary.lio_runs[pair.case])
                for seed in range(len(seeds.ape_per_seed)):
                    path = folder.replay(pair.case, pair.number, name, label, seed)
                    if path.exists():
                        head = {"case": pair.case, "pair": pair.number, "guidance": name, "method": method}
                        yield {**head, "label": label, "seed": seed, **asdict(read_replay(path))}


def write_records(folder: StudyFolder, summary: Summary) -> None:
    """pairs.jsonl (one :class:`Pair` a line) and, where the folder holds the replays'
    JSONs, replays.jsonl (one replay a line); each line with the schema version."""
    _jsonl(folder.pair_records, (pair.to_json() for pair in summary.pairs))
    rows = list(replay_rows(folder, summary))
    if rows:
        _jsonl(folder.replay_records, rows)


def read_jsonl(path) -> list[dict]:
    """The records of a JSON Lines file, each line's schema checked (:func:`checked`)."""
    lines = Path(path).read_text(encoding="utf-8").splitlines()
    return [checked(json.loads(line), f"{path}:{k + 1}") for k, line in enumerate(lines) if line.strip()]


def read_records(root) -> Summary:
    """A study's records: summary.json's setup with the pairs of pairs.jsonl (the pairs
    are the record; the summary's statistics are recomputed from them)."""
    folder = StudyFolder(Path(root))
    summary = read_summary(folder.summary)
    return replace(summary, pairs=tuple(Pair.from_json(d) for d in read_jsonl(folder.pair_records)))
