"""The benefit study's Markdown report (DIR/benefit.md), from its summary and the
descriptions of the goals it was judged by (its protocol's ``goals`` section)."""

from __future__ import annotations

import math

from lf3pm.experiments.benefit.records import (
    AT_RISK,
    DEFAULT,
    MEASURES,
    NO_RISK,
    Comparison,
    Effect,
    Failures,
    MapAnalysis,
    Measure,
    Summary,
)

_VERDICT = {True: "yes", False: "no", None: "n/a (one seed)"}


def _share(v) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{100 * v:.0f} %"


def _row(name: str, c: Comparison) -> str:
    if not c.pairs:
        return f"| {name} | 0 | | | | | | | |"
    lo, hi = c.median_ratio_ci95
    beyond = f"{_share(c.share_worse_beyond_noise)}, {_share(c.share_worse_beyond_noise_and_margin)}"
    return (
        f"| {name} | {c.pairs} | {c.median_ratio:.2f} [{lo:.2f}, {hi:.2f}] | {c.wilcoxon_p:.2g} | "
        f"{100 * c.share_worse:.0f} % ({beyond}) | {100 * c.failure_rate_guided:.0f} % / "
        f"{100 * c.failure_rate_unguided:.0f} % | {100 * c.median_length_overhead:+.1f} % | "
        f"{100 * c.median_duration_overhead:+.1f} % | {1000 * c.median_error_guided:.0f} / "
        f"{1000 * c.median_error_unguided:.0f} |"
    )


def report(summary: Summary, goals) -> str:
    """The Markdown tables of a summary; ``goals``: the protocol's goals section
    (protocol.Goals) its goals were judged by, which says what each is with its
    threshold (:func:`goal_lines`)."""
    p = summary.parameters
    header = (
        "| guidance | pairs | median APE ratio [95 % CI] | Wilcoxon p | worse (beyond seed noise, "
        f"and by > {100 * p.worse_margin_m:g} cm) | "
        "failures guided / none "
        f"(APE > {p.failure_ape_m:g} m) | length overhead | duration overhead | median APE (mm) "
        "guided / none |\n|---|---|---|---|---|---|---|---|---|"
    )
    specs = "; ".join(f"{g.name}: {g.channel} to the power {g.power:g}, weight {g.weight:g}" for g in summary.guided)
    lines = [
        "# Benefit study: localization along guided and unguided plans",
        "",
        f"{len(summary.pairs)} pairs on {len(summary.cases)} maps, {summary.seeds} seed(s) per "
        f"replay, pair seed {summary.pair_seed}. Guidance: {specs}. Runtime "
        f"{summary.runtime_s / 60:.0f} min (this invocation; a resumed study counts only its own "
        f"part), replays {summary.replay_cpu_s / 60:.0f} CPU-minutes in all.",
        "",
        *(
            []
            if summary.protocol_sha256 is None
            else [f'Protocol: protocol.yaml, sha256 {summary.protocol_sha256} (docs/benefit.md, "The protocol").', ""]
        ),
        *([] if summary.map_analysis is None else headline_lines(summary.map_analysis)),
        "## Localization (registration to the prior map from wheel odometry)",
        "",
        header,
    ]
    localization, lio, steady = MEASURES

    def rows(measure: Measure) -> list[str]:
        by_guidance = summary.compared(measure).by_guidance
        return [_row(g.name, by_guidance[g.name]) for g in summary.guided if g.name in by_guidance]

    lines += rows(localization)
    if rows(lio):
        lines += ["", f"## LIO ({summary.odometry_line()})", "", header] + rows(lio)
    rest = summary.lio_rest
    if any(v.replays for v in rest.values()):
        counts = ", ".join(f"{name} {v.unsteady} of {v.replays}" for name, v in rest.items() if v.replays)
        lines += [
            "",
            f"## LIO from steady starts (rest speed at most {p.rest_speed_limit_mps:g} m/s before both plans)",
            "",
            "LIO replays whose odometry moved while the sensor stood still for its rest (faster than "
            f"{p.rest_speed_limit_mps:g} m/s at the rest's end), per map: {counts}. Below, each pair keeps the "
            "seeds on which both plans started steady; a pair with none is left out.",
            "",
            header,
        ]
        lines += rows(steady)
    for measure in MEASURES:
        c = summary.compared(measure)
        if c.default_by_map is not None:
            lines += [
                "",
                f"## Default guidance against none, per map, per robot and at risk ({measure.title})",
                "",
                header.replace("| guidance |", "| pairs of |"),
            ]
            lines += [_row(name, x) for name, x in c.default_by_map.items()]
            lines += [_row(f"{kind} robot", x) for kind, x in c.default_by_robot.items()]
            risk = (
                f"at risk (SOLM: >= {100 * p.at_risk_share:.0f} % of the unguided plan's poses degenerate or "
                f"q_n >= {p.risk_factor:g} x the map's median)"
            )
            default = c.by_risk[DEFAULT]
            lines += [_row(risk, default.at_risk), _row("no risk", default.no_risk)]
    for measure in MEASURES:
        by_risk = summary.compared(measure).by_risk
        if by_risk:
            lines += [
                "",
                f"## Every guidance against none, at risk and no risk ({measure.title})",
                "",
                header.replace("| guidance |", "| guidance, pairs |"),
            ]
            lines += [
                _row(f"{name}, {label}", x)
                for name, split in by_risk.items()
                for x, label in ((split.at_risk, "at risk"), (split.no_risk, "no risk"))
                if x.pairs
            ]
    beyond = summary.lio_beyond_bound
    if beyond.pairs_replayed:
        lines += [
            "",
            f"## Default-guided plans whose LIO error exceeds {beyond.bound_m:g} m "
            f"({len(beyond.pairs)} of {beyond.pairs_replayed} pairs)",
            "",
        ]
        if beyond.pairs:
            lines += [
                "| map | pair | robot | at risk | LIO APE guided (m) | LIO APE none (m) |",
                "|---|---|---|---|---|---|",
            ]
            lines += [
                f"| {b.case} | {b.pair} | {b.robot} | {'yes' if b.at_risk else 'no'} | "
                f"{b.guided_m:.2f} | {b.unguided_m:.2f} |"
                for b in beyond.pairs
            ]
    for measure, title in ((localization, "localization error"), (lio, "the LIO's error")):
        cal = summary.calibration.get(measure.method)
        if not cal:
            continue
        lines += [
            "",
            f"## Which channel predicts {title} (every plan's mean along its trajectory)",
            "",
            "| channel | plans | Spearman rho pooled | mean rho within maps | slope of log APE on log channel |",
            "|---|---|---|---|---|",
        ]
        lines += [
            f"| {ch} | {c.plans} | {c.spearman_pooled:.2f} | {c.spearman_within_mean:.2f} | {c.log_log_slope:.2f} |"
            for ch, c in cal.items()
        ]
    fit = summary.localization_error
    if fit.fitted:
        lo, hi = fit.interval_factors
        lines += [
            "",
            "## Predicted localization error (lf3pm evaluate's predicted_localization_error_m)",
            "",
            f"log APE = {fit.a:.2f} + {fit.b:.2f} log q_n over {fit.samples} plans without a "
            f"degenerate pose (q_n exact, once per second); 10-90 % interval x{lo:.2f} to x{hi:.2f}. "
            "Each map left out of the fit in turn and predicted:",
            "",
            "| map left out | plans | inside the interval | Spearman within the map | median factor |",
            "|---|---|---|---|---|",
        ]
        for name, v in fit.validation.items():
            rho = "n/a" if v.spearman_within_map is None else f"{v.spearman_within_map:.2f}"
            lines += [f"| {name} | {v.plans} | {100 * v.share_inside_interval:.0f} % | {rho} | {v.median_factor:.2f} |"]
    if summary.goal:
        lines += goal_lines(summary.goal, goals.described())
    if summary.map_analysis is not None:
        lines += map_sections(summary.map_analysis, summary)
    lines += ["", redrawn_line(summary)]
    return "\n".join(lines) + "\n"


def goal_lines(verdicts: dict, described: dict[str, str]) -> list[str]:
    """The goals' section: each goal judged by measure as a row (what it is, with its
    threshold: ``described``, by the goal's key after the measure's), one column a
    measure; the others (the length overhead) a line each; a verdict whose key is not
    described, by its key's words."""
    measures = sorted(MEASURES, key=lambda m: -len(m.key))
    table: dict[str, dict[str, bool | None]] = {}
    columns, alone, other = [], [], []
    for key, verdict in verdicts.items():
        measure = next(
            (m for m in measures if key.startswith(f"{m.key}_") and key[len(m.key) + 1 :] in described), None
        )
        if measure is not None:
            table.setdefault(key[len(measure.key) + 1 :], {})[measure.key] = verdict
            columns += [m for m in MEASURES if m == measure and m not in columns]
        elif key in described:
            alone.append((described[key], verdict))
        else:
            other.append(f"{key.replace('_', ' ')}: {_VERDICT[verdict]}")
    columns = [m for m in MEASURES if m in columns]
    lines = ["", f"## Goals ({DEFAULT} guidance against none; the protocol's goals section)", ""]
    if table:
        lines += [
            "| goal | " + " | ".join(m.title for m in columns) + " |",
            "|---|" + "---|" * len(columns),
        ]
        lines += [
            f"| {described[name]} | " + " | ".join(_VERDICT[row[m.key]] if m.key in row else "" for m in columns) + " |"
            for name in described
            if (row := table.get(name))
        ]
    if alone or other:
        lines += [""] if table else []
        lines += [f"{text[:1].upper()}{text[1:]}: {_VERDICT[verdict]}." for text, verdict in alone]
        lines += [f"Other goals: {'; '.join(other)}."] if other else []
    return lines


def _p(v: float) -> str:
    return "n/a" if not math.isfinite(v) else f"{v:.2g}"


def _ratio(e: Effect) -> str:
    if not e.pairs:
        return "n/a"
    return f"{e.ratio:.3g} [{e.ci[0]:.3g}, {e.ci[1]:.3g}]"


def _failure_row(f: Failures) -> str:
    return (
        f"| {f.name} | {f.pairs} | {f.both} | {f.guided_only} | {f.unguided_only} | {f.neither} | {_p(f.mcnemar_p)} |"
    )


def _pairs(n: int) -> str:
    return f"{n} pair" if n == 1 else f"{n} pairs"


def headline_lines(a: MapAnalysis) -> list[str]:
    """The study's result in a few lines per measure, at the level of the map: each
    at-risk map's effect on its at-risk pairs and their effect over maps, the same where
    both plans succeed, failures apart, and the no-risk pairs' no-harm test."""
    s = a.settings
    measures = {m.key: m for m in MEASURES}
    lines = [f"## Headline: at the level of the map ({s.guidance} guidance against none)", ""]
    for key, m in a.by_measure.items():
        over = {e.name: e for e in m.over_maps}
        both = {e.name: e for e in m.both_succeed}
        fails = {f.name: f for f in m.failures}
        risky, safe = over.get(AT_RISK), over.get(NO_RISK)
        text = [f"**{measures[key].title[:1].upper()}{measures[key].title[1:]}.**"]
        if risky is not None and risky.pairs:
            each = ", ".join(f"{e.name} {_ratio(e)}" for e in m.at_risk_by_map)
            text.append(
                f"At risk ({_pairs(risky.pairs)} on {risky.maps} maps), the APE ratio per map: {each}; over the "
                f"maps {_ratio(risky)}, {risky.maps_below_1} of {risky.maps} maps below 1, Wilcoxon p over maps "
                f"{_p(risky.wilcoxon_p)} (the least {risky.maps} maps allow: {_p(risky.minimum_p)})."
            )
            if AT_RISK in both:
                text.append(
                    f"Where both plans succeed (APE at most {s.failure_ape_m:g} m; {_pairs(both[AT_RISK].pairs)}): "
                    f"{_ratio(both[AT_RISK])}."
                )
            if AT_RISK in fails:
                f = fails[AT_RISK]
                text.append(
                    f"Failures at risk: both {f.both}, {s.guidance} only {f.guided_only}, none only "
                    f"{f.unguided_only}, neither {f.neither} (McNemar p {_p(f.mcnemar_p)})."
                )
        else:
            text.append("No pair at risk.")
        if safe is not None and safe.pairs:
            text.append(f"No risk ({_pairs(safe.pairs)} on {safe.maps} maps): {_ratio(safe)}")
            if m.no_harm is not None:
                e = m.no_harm
                text[-1] += (
                    f"; equivalent within [{e.low:.2f}, {e.high:.2f}]: {'yes' if e.equivalent else 'no'}, "
                    f"not worse: {'yes' if e.not_worse else 'no'}"
                )
            text[-1] += "."
        lines += [" ".join(text), ""]
    return lines


def map_sections(a: MapAnalysis, summary: Summary) -> list[str]:
    """The analysis at the level of the map, of failures and of no harm (analysis.analyse)."""
    s = a.settings
    level = f"{100 * s.level:g} %"
    lines = [
        "",
        f"## At the level of the map ({s.guidance} guidance against none)",
        "",
        "Each map's effect is the geometric mean of its pairs' APE ratios (guided / none) with a "
        f"{level} interval from {s.bootstrap_draws} bootstrap resamples of its pairs (seed {s.bootstrap_seed}); "
        "over maps each map weighs the same: the geometric mean of the maps' effects, its interval from "
        "resampling maps, then pairs within each map drawn. The Wilcoxon signed-rank and sign tests are "
        "exact, over the maps' log ratios (one value a map): with n maps neither can give a p below 2 / 2^n "
        "(column 'least p'). Figure: maps.png.",
    ]
    measures = {m.key: m for m in MEASURES}
    for key, m in a.by_measure.items():
        title = measures[key].title
        robots = sorted({e.name.split(", ")[-1] for e in m.by_map_robot})
        by_robot = {e.name: e for e in m.by_map_robot}
        lines += [
            "",
            f"### Per map ({title})",
            "",
            "| map | pairs | ratio [CI] | " + " | ".join(f"{r} robot" for r in robots) + " | gain shown |",
            "|---|---|---|" + "---|" * len(robots) + "---|",
        ]
        for e in m.by_map:
            cells = [_ratio(by_robot[f"{e.name}, {r}"]) if f"{e.name}, {r}" in by_robot else "" for r in robots]
            gain = "no" if e.gains_nothing else "yes"
            lines.append(f"| {e.name} | {e.pairs} | {_ratio(e)} | " + " | ".join(cells) + f" | {gain} |")
        lines += [
            "",
            f"Over maps ({title}); 'both succeed': the pairs where both plans' APE is at most "
            f"{s.failure_ape_m:g} m, the ratio of accuracy apart from failures:",
            "",
            "| pairs of | maps | pairs | ratio [CI] | Wilcoxon p over maps | sign p | least p | maps below 1 |",
            "|---|---|---|---|---|---|---|---|",
        ]
        rows = [(e.name, e) for e in m.over_maps] + [(f"{e.name}, both succeed", e) for e in m.both_succeed]
        lines += [
            f"| {name} | {e.maps} | {e.pairs} | {_ratio(e)} | {_p(e.wilcoxon_p)} | {_p(e.sign_p)} | "
            f"{_p(e.minimum_p)} | {e.maps_below_1} of {e.maps} |"
            for name, e in rows
        ]
        nothing = [e.name for e in m.by_map if e.gains_nothing]
        lines += ["", f"Maps where no gain is shown (interval reaching 1): {', '.join(nothing) or 'none'}."]
        lines += [
            "",
            f"Failures (APE > {s.failure_ape_m:g} m) as a paired outcome ({title}); McNemar's exact test on the "
            "pairs where one plan fails and the other does not:",
            "",
            f"| pairs of | pairs | both fail | {s.guidance} only fails | none only fails | neither | McNemar p |",
            "|---|---|---|---|---|---|---|",
        ]
        lines += [_failure_row(f) for f in m.failures + m.failures_by_map]
    eq = [(measures[key].title, m.no_harm) for key, m in a.by_measure.items() if m.no_harm is not None]
    if eq:
        first = eq[0][1]
        inner = f"{100 * (1 - 2 * first.alpha):g} %"
        lines += [
            "",
            "## No harm on the no-risk pairs (pre-set equivalence test)",
            "",
            f"The geometric-mean ratio over the no-risk maps with its {inner} interval (maps, then pairs, "
            f"resampled): equivalent where it lies inside [{first.low:.2f}, {first.high:.2f}] (TOST at alpha "
            f"{first.alpha:g}), not worse where its upper end is below {first.high:.2f} (non-inferiority); the "
            "t-test TOST over the maps' log ratios as a check. The tail: the share of pairs whose guided "
            "mean APE over seeds exceeds the unguided one by more than twice the standard error of the "
            f"difference, its one-sided {100 * (1 - first.alpha):g} % upper bound at most "
            f"{100 * first.tail_max_share:g} % for no harm (n/a: one seed, no seed noise to judge by).",
            "",
            f"| measure | maps | pairs | ratio [{inner} CI] | equivalent | not worse | TOST p over maps | "
            "worse beyond seed noise (upper bound) | tail no harm |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for title, e in eq:
            tail = "n/a" if not e.tail_pairs else f"{e.tail_worse} of {e.tail_pairs} ({_share(e.tail_upper)})"
            lines.append(
                f"| {title} | {e.maps} | {e.pairs} | {e.ratio:.3g} [{e.ci[0]:.3g}, {e.ci[1]:.3g}] | "
                f"{'yes' if e.equivalent else 'no'} | {'yes' if e.not_worse else 'no'} | {_p(e.tost_p_over_maps)} | "
                f"{tail} | {_VERDICT[e.tail_no_harm]} |"
            )
    return lines


def redrawn_line(summary: Summary) -> str:
    """The draws of pairs replaced because they could not be planned, listed."""
    if summary.redrawn is None:
        return "Redrawn pairs: not recorded (a run before they were counted)."
    if not summary.redrawn:
        return "Redrawn pairs: none (every draw was planned)."
    listed = "; ".join(f"{r.case} draw {r.draw}: {r.reason}" for r in summary.redrawn)
    return f"Redrawn pairs: {len(summary.redrawn)} draws replaced ({listed})."
