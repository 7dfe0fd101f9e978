"""The benefit study's statistics: each guidance against none (paired_stats), by map,
robot and risk, which SOLM channel predicts each replay's error, the LIO's bound and
the issue's goals, all from the study's records, judged by the protocol's settings
(its ``statistics``, ``analysis`` and ``goals`` sections; their defaults where none is
given)."""

from __future__ import annotations

import math

import numpy as np

from lf3pm.experiments.benefit.protocol import GOALS, STATISTICS, Goals, Statistics
from lf3pm.experiments.benefit.records import (
    APE_FLOOR,
    AT_RISK,
    DEFAULT,
    EVERY_PAIR,
    LIO,
    LOCALIZATION,
    MEASURES,
    NO_RISK,
    NONE,
    AnalysisSettings,
    BeyondBound,
    BeyondPair,
    ChannelFit,
    Comparison,
    Comparisons,
    Effect,
    Equivalence,
    Failures,
    MapAnalysis,
    Measure,
    MeasureAnalysis,
    Pair,
    RestCount,
    RiskSplit,
    SeedReplays,
)
from lf3pm.experiments.paired_stats import (
    binomial_upper,
    compare,
    group_bootstrap,
    mcnemar_exact_p,
    minimum_p,
    sign_test_p,
    tost_t_p,
    wilcoxon_exact_p,
)

#: SOLM channels whose mean along each trajectory the summary records (calibration).
CHANNELS = ("q_n", "q_min", "q_max", "step_norm")

#: The bound the issue sets on the LIO's error along a guided plan (m): the report lists
#: every default-guided plan beyond it, beside its unguided plan, so that where and how
#: often the bound fails is read off the study, not looked for (the protocol's
#: statistics.lio_bound_m).
LIO_BOUND = STATISTICS.lio_bound_m


def paired(pair: Pair, guidance: str, measure: Measure) -> tuple[SeedReplays, SeedReplays] | None:
    """The (guided, unguided) replays of ``pair`` that ``measure`` compares: both plans'
    by its method; with steady starts only the seeds at which both plans' rest was
    steady (None: no such seed, or no rest recorded)."""
    both = pair.both(guidance, measure.method)
    if both is None or not measure.steady_starts:
        return both
    a, b = both
    if a.rest_steady_per_seed is None or b.rest_steady_per_seed is None:
        return None
    keep = [k for k, (x, y) in enumerate(zip(a.rest_steady_per_seed, b.rest_steady_per_seed)) if x and y]
    if not keep:
        return None
    return a.on_seeds(keep), b.on_seeds(keep)


def comparison(pairs: list[Pair], guidance: str, measure: Measure, statistics: Statistics = STATISTICS) -> Comparison:
    """Plans of ``guidance`` against the unguided ones over ``pairs``, by ``measure``,
    judged by ``statistics`` (the protocol's: paired_stats.compare's settings; errors
    floored at ``APE_FLOOR``)."""
    rows = [(pair, both) for pair in pairs if (both := paired(pair, guidance, measure)) is not None]
    if not rows:
        return Comparison(0)
    guided = [pair.plans[guidance] for pair, _ in rows]
    unguided = [pair.plans[NONE] for pair, _ in rows]
    return compare(
        [max(a.ape, APE_FLOOR) for _, (a, _) in rows],
        [max(b.ape, APE_FLOOR) for _, (_, b) in rows],
        guided_length=[p.length_m for p in guided],
        unguided_length=[p.length_m for p in unguided],
        guided_duration=[p.duration_s for p in guided],
        unguided_duration=[p.duration_s for p in unguided],
        guided_seeds=[list(a.ape_per_seed) for _, (a, _) in rows],
        unguided_seeds=[list(b.ape_per_seed) for _, (_, b) in rows],
        settings=statistics.paired(),
    )


def comparisons(
    pairs: list[Pair],
    cases: list[str],
    guidance: list[str],
    lio_guidance: list[str],
    statistics: Statistics = STATISTICS,
) -> dict:
    """summary.comparisons: by each measure (:data:`MEASURES`, by key), every guidance
    its method replayed (``guidance``: all, ``lio_guidance``: the LIO's) against none,
    over all pairs and at risk or not; where the default guidance ran at all, the
    default per map (``cases``' order) and per robot; each judged by ``statistics``
    (:func:`comparison`)."""

    def compared(group: list[Pair], name: str, measure: Measure) -> Comparison:
        return comparison(group, name, measure, statistics)

    risky, safe = [p for p in pairs if p.at_risk], [p for p in pairs if not p.at_risk]
    robots = sorted({p.robot for p in pairs})
    out = {}
    for measure in MEASURES:
        names = guidance if measure.method == LOCALIZATION else lio_guidance
        by_map = by_robot = None
        if DEFAULT in guidance:
            by_map = {case: compared([p for p in pairs if p.case == case], DEFAULT, measure) for case in cases}
            by_robot = {kind: compared([p for p in pairs if p.robot == kind], DEFAULT, measure) for kind in robots}
        out[measure.key] = Comparisons(
            {name: compared(pairs, name, measure) for name in names},
            {name: RiskSplit(compared(risky, name, measure), compared(safe, name, measure)) for name in names},
            by_map,
            by_robot,
        )
    return out


def lio_beyond_bound(pairs: list[Pair], bound: float = LIO_BOUND) -> BeyondBound:
    """The pairs whose default-guided plan's LIO APE (median over seeds) exceeds
    ``bound`` m, with the unguided plan's, among the pairs with both replayed."""
    both = [(p, b) for p in pairs if (b := p.both(DEFAULT, LIO)) is not None]
    beyond = tuple(
        BeyondPair(p.case, p.number, p.robot, p.at_risk, guided.ape, unguided.ape)
        for p, (guided, unguided) in both
        if guided.ape > bound
    )
    return BeyondBound(bound, len(both), beyond)


def calibration(pairs: list[Pair]) -> dict:
    """How each channel's mean along a trajectory predicts the APE of each replay method
    ({method: {channel: ChannelFit}}), over every plan replayed so: Spearman rho pooled
    and within maps (mean), and the slope b of log APE = a + b log(mean channel) (pooled
    least squares): the power at which the channel's cost ratios track APE ratios."""
    from scipy.stats import spearmanr

    out = {}
    for method in (LOCALIZATION, LIO):
        for channel in CHANNELS:
            rows = [
                (pair.case, plan.solm_mean[channel], plan.replays[method].ape)
                for pair in pairs
                for plan in pair.plans.values()
                if method in plan.replays and plan.solm_mean.get(channel, 0) > 0
            ]
            if len(rows) < 3:
                continue
            case, q, ape = (np.array(c) for c in zip(*rows))
            ape = np.maximum(ape.astype(float), APE_FLOOR)
            within = [
                spearmanr(q[case == c], ape[case == c])[0]
                for c in np.unique(case)
                if np.sum(case == c) >= 5 and np.ptp(ape[case == c]) > 0
            ]
            slope = np.polyfit(np.log(q.astype(float)), np.log(ape), 1)[0]
            out.setdefault(method, {})[channel] = ChannelFit(
                plans=len(rows),
                spearman_pooled=float(spearmanr(q, ape)[0]),
                spearman_within_mean=float(np.nanmean(within)) if within else math.nan,
                log_log_slope=float(slope),
            )
    return out


def rest_counts(pairs: list[Pair]) -> dict[str, RestCount]:
    """Per map: LIO replays in all, and those whose rest was not steady (the odometry
    moved while the sensor stood still)."""
    counts: dict = {}
    for pair in pairs:
        replays, unsteady = counts.get(pair.case, (0, 0))
        for plan in pair.plans.values():
            lio = plan.replays.get(LIO)
            flags = lio.rest_steady_per_seed if lio is not None and lio.rest_steady_per_seed is not None else ()
            replays += len(flags)
            unsteady += sum(not f for f in flags)
        counts[pair.case] = (replays, unsteady)
    return {case: RestCount(*c) for case, c in counts.items()}


def goal(comparisons: dict[str, Comparisons], maps: MapAnalysis | None = None, goals: Goals = GOALS) -> dict:
    """The goals (the protocol's ``goals``: protocol.Goals) for the default guidance,
    each True or False, keyed as :meth:`~protocol.Goals.keys` names them (after the
    measure's key): on the at-risk pairs a median APE ratio of at most
    ``at_risk_ratio_max`` with Wilcoxon p below ``at_risk_p_below``; over the at-risk
    maps (``maps``: :func:`analyse`'s, for the guidance it judges) a geometric-mean
    ratio whose interval ends below ``map_ci_upper_below``, with the exact Wilcoxon and
    sign tests over maps each at p at most ``map_p_max``; on the other pairs a median
    ratio within [``no_risk_ratio_low``, ``no_risk_ratio_high``] whose interval ends at
    most at ``no_risk_ci_upper_max``, and meaningfully worse (beyond seed noise and by
    more than the statistics' worse margin) on at most ``no_risk_worse_max_share`` of
    them; each by every measure; a median length overhead of at most
    ``length_overhead_max``. None where a goal cannot be judged: seed noise needs two
    seeds."""
    names, out = goals.keys(), {}
    for measure in MEASURES:
        split = comparisons[measure.key].by_risk.get(DEFAULT)
        if split is None:
            continue
        risky, safe, key = split.at_risk, split.no_risk, measure.key
        if risky.pairs:
            out[f"{key}_{names['at_risk_ratio']}"] = risky.median_ratio <= goals.at_risk_ratio_max
            out[f"{key}_{names['at_risk_p']}"] = bool(risky.wilcoxon_p < goals.at_risk_p_below)
        over = _at_risk_over_maps(maps, measure)
        if over is not None:
            out[f"{key}_{names['maps_ci_upper']}"] = bool(over.ci[1] < goals.map_ci_upper_below)
            out[f"{key}_{names['maps_wilcoxon_p']}"] = bool(over.wilcoxon_p <= goals.map_p_max)
            out[f"{key}_{names['maps_sign_p']}"] = bool(over.sign_p <= goals.map_p_max)
        if safe.pairs:
            low, high = goals.no_risk_ratio_low, goals.no_risk_ratio_high
            out[f"{key}_{names['no_risk_ratio']}"] = low <= safe.median_ratio <= high
            out[f"{key}_{names['no_risk_ci_upper']}"] = safe.median_ratio_ci95[1] <= goals.no_risk_ci_upper_max
            worse = safe.share_worse_beyond_noise_and_margin
            judged = bool(worse <= goals.no_risk_worse_max_share) if math.isfinite(worse) else None
            out[f"{key}_{names['no_risk_worse']}"] = judged
    overall = comparisons[Measure(LOCALIZATION).key].by_guidance.get(DEFAULT)
    if overall is not None and overall.pairs:
        out[names["length_overhead"]] = overall.median_length_overhead <= goals.length_overhead_max
    return out


def _at_risk_over_maps(maps: MapAnalysis | None, measure: Measure) -> Effect | None:
    """The effect over the at-risk maps by ``measure`` in ``maps`` (None: not analysed,
    or no at-risk map)."""
    if maps is None or maps.settings.guidance != DEFAULT or measure.key not in maps.by_measure:
        return None
    found = [e for e in maps.by_measure[measure.key].over_maps if e.name == AT_RISK and e.maps]
    return found[0] if found else None


# --- at the level of the map ----------------------------------------------------------


def _rows(pairs: list[Pair], guidance: str, measure: Measure) -> list[tuple[Pair, SeedReplays, SeedReplays]]:
    return [(p, *both) for p in pairs if (both := paired(p, guidance, measure)) is not None]


def _ratio(guided: SeedReplays, unguided: SeedReplays) -> float:
    return max(guided.ape, APE_FLOOR) / max(unguided.ape, APE_FLOOR)


def _by_map(rows, cases: list[str]) -> dict[str, list[float]]:
    """The ratios of ``rows`` grouped by map, in ``cases``' order (maps without a row left out)."""
    groups = {case: [_ratio(a, b) for p, a, b in rows if p.case == case] for case in cases}
    return {case: r for case, r in groups.items() if r}


def map_effect(name: str, ratios: list[float], s: AnalysisSettings) -> Effect:
    """One map's (or one map and robot's) effect: its pairs resampled."""
    ratio, ci = group_bootstrap([ratios], draws=s.bootstrap_draws, seed=s.bootstrap_seed, level=s.level)
    return Effect(name, 1, len(ratios), ratio, ci)


def over_maps(name: str, groups: dict[str, list[float]], s: AnalysisSettings) -> Effect:
    """The effect over maps (``groups``: each map's ratios): maps then pairs resampled,
    the maps' log ratios tested (exact Wilcoxon and sign tests)."""
    if not groups:
        return Effect(name, 0, 0, math.nan, (math.nan, math.nan))
    values = list(groups.values())
    ratio, ci = group_bootstrap(values, draws=s.bootstrap_draws, seed=s.bootstrap_seed, level=s.level)
    logs = [float(np.mean(np.log(r))) for r in values]
    return Effect(
        name,
        len(values),
        sum(len(r) for r in values),
        ratio,
        ci,
        wilcoxon_exact_p(logs),
        sign_test_p(logs),
        minimum_p(len(values)),
        sum(v < 0 for v in logs),
    )


def failures(name: str, rows, threshold: float) -> Failures:
    """The paired failure table of ``rows`` (APE > ``threshold``) and McNemar's exact p."""
    g = [a.ape > threshold for _, a, _ in rows]
    u = [b.ape > threshold for _, _, b in rows]
    both = sum(x and y for x, y in zip(g, u))
    guided_only = sum(x and not y for x, y in zip(g, u))
    unguided_only = sum(y and not x for x, y in zip(g, u))
    neither = len(rows) - both - guided_only - unguided_only
    p = mcnemar_exact_p(guided_only, unguided_only)
    return Failures(name, threshold, both, guided_only, unguided_only, neither, p)


def no_harm(rows, cases: list[str], s: AnalysisSettings) -> Equivalence | None:
    """The pre-set equivalence test on ``rows`` (the no-risk pairs): the geometric-mean
    ratio's 1 - 2 alpha interval (maps, then pairs) inside the margins; the tail: pairs
    whose guided mean APE over seeds exceeds the unguided one by more than twice the
    standard error of the difference, their share's one-sided upper bound at most
    ``tail_max_share`` (not judged where no pair has two seeds a side)."""
    groups = _by_map(rows, cases)
    if not groups:
        return None
    values = list(groups.values())
    ratio, ci = group_bootstrap(
        values, draws=s.bootstrap_draws, seed=s.bootstrap_seed, level=1 - 2 * s.equivalence_alpha
    )
    flags = []
    for _, a, b in rows:
        x, y = np.asarray(a.ape_per_seed, float), np.asarray(b.ape_per_seed, float)
        if min(x.size, y.size) >= 2:
            se = math.sqrt(x.var(ddof=1) / x.size + y.var(ddof=1) / y.size)
            flags.append(bool(x.mean() - y.mean() > 2.0 * se))
    worse, n = sum(flags), len(flags)
    upper = binomial_upper(worse, n, 1 - s.equivalence_alpha)
    return Equivalence(
        s.equivalence_low,
        s.equivalence_high,
        s.equivalence_alpha,
        len(values),
        sum(len(r) for r in values),
        ratio,
        ci,
        bool(s.equivalence_low < ci[0] and ci[1] < s.equivalence_high),
        bool(ci[1] < s.equivalence_high),
        tost_t_p([float(np.mean(np.log(r))) for r in values], s.equivalence_low, s.equivalence_high),
        n,
        worse,
        worse / n if n else math.nan,
        upper,
        s.tail_max_share,
        bool(upper <= s.tail_max_share) if n else None,
    )


def measure_analysis(pairs: list[Pair], cases: list[str], measure: Measure, s: AnalysisSettings) -> MeasureAnalysis:
    """One measure's analysis at the level of the map (records.MeasureAnalysis)."""
    rows = _rows(pairs, s.guidance, measure)
    robots = sorted({p.robot for p, _, _ in rows})
    risky = [r for r in rows if r[0].at_risk]
    safe = [r for r in rows if not r[0].at_risk]
    ok = [r for r in rows if r[1].ape <= s.failure_ape_m and r[2].ape <= s.failure_ape_m]
    by_map = _by_map(rows, cases)
    by_map_robot = [
        map_effect(f"{case}, {robot}", ratios, s)
        for case in by_map
        for robot in robots
        if (ratios := [_ratio(a, b) for p, a, b in rows if p.case == case and p.robot == robot])
    ]
    groups = [(EVERY_PAIR, rows), (AT_RISK, risky), (NO_RISK, safe)]
    groups += [(f"{robot} robot", [r for r in rows if r[0].robot == robot]) for robot in robots]
    return MeasureAnalysis(
        by_map=tuple(map_effect(case, ratios, s) for case, ratios in by_map.items()),
        by_map_robot=tuple(by_map_robot),
        over_maps=tuple(over_maps(name, _by_map(g, cases), s) for name, g in groups),
        both_succeed=tuple(over_maps(name, _by_map([r for r in g if r in ok], cases), s) for name, g in groups[:3]),
        failures=tuple(failures(name, g, s.failure_ape_m) for name, g in groups[:3]),
        failures_by_map=tuple(
            failures(case, [r for r in rows if r[0].case == case], s.failure_ape_m) for case in by_map
        ),
        no_harm=no_harm(safe, cases, s),
        at_risk_by_map=tuple(map_effect(case, ratios, s) for case, ratios in _by_map(risky, cases).items()),
    )


def analyse(pairs: list[Pair], cases: list[str], settings: AnalysisSettings | None = None) -> MapAnalysis | None:
    """The analysis at the level of the map and of failures for every measure
    (:data:`MEASURES`) that replayed the judged guidance (None where none did)."""
    s = settings or AnalysisSettings()
    out = {m.key: measure_analysis(pairs, cases, m, s) for m in MEASURES if _rows(pairs, s.guidance, m)}
    return MapAnalysis(s, out) if out else None
