"""The benefit study's Markdown report (DIR/benefit.md), from its summary alone."""

from __future__ import annotations

import math

from lf3pm.experiments.benefit.records import DEFAULT, MEASURES, Comparison, Measure, Summary

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


def report(summary: Summary) -> str:
    """The Markdown tables of a summary."""
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
        lines += [
            "",
            "Goal (issue): "
            + "; ".join(f"{k.replace('_', ' ')}: {_VERDICT[v]}" for k, v in summary.goal.items())
            + ".",
        ]
    return "\n".join(lines) + "\n"
