"""Figures of the benefit study, from its summary and folder alone."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np

from lf3pm.config import COMPOSITE_CHANNELS
from lf3pm.experiments.benefit.records import (
    APE_FLOOR,
    DEFAULT,
    LIO,
    LOCALIZATION,
    NONE,
    Measure,
    StudyFolder,
    Summary,
    read_replay,
)
from lf3pm.solm.figures import save_figure

_MARKERS = "osD^vP*X"


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _errors(summary: Summary, guidance: str, method: str) -> list[tuple[str, float, float]]:
    """(map, unguided APE, guided APE) of every pair replayed both ways by ``method``."""
    out = []
    for pair in summary.pairs:
        both = pair.both(guidance, method)
        if both is not None:
            out.append((pair.case, both[1].ape, both[0].ape))
    return out


def scatter_figure(summary: Summary, path: Path) -> None:
    """APE of each guided plan against its unguided twin, log-log, one panel per
    guidance, a row for localization and one for the LIO (the guidances it replayed);
    below the diagonal guidance helped."""
    plt = _plt()
    names = [g.name for g in summary.guided]
    lio_compared = summary.compared(Measure(LIO)).by_guidance
    rows_of_panels = [
        [(name, LOCALIZATION) for name in names],
        [(name, LIO) for name in names if name in lio_compared],
    ]
    rows_of_panels = [row for row in rows_of_panels if row]
    columns = max(len(row) for row in rows_of_panels)
    fig, axes = plt.subplots(
        len(rows_of_panels), columns, figsize=(3.6 * columns, 3.9 * len(rows_of_panels)), dpi=110, squeeze=False
    )
    cases = [c.name for c in summary.cases]
    for ax in axes.flat:
        ax.set_visible(False)
    panels = [
        (axes[r][k], guidance, method)
        for r, row in enumerate(rows_of_panels)
        for k, (guidance, method) in enumerate(row)
    ]
    for ax, guidance, method in panels:
        ax.set_visible(True)
        rows = _errors(summary, guidance, method)
        values = [v for _, a, b in rows for v in (a, b)] or [1e-3, 1.0]
        lo, hi = max(min(values) / 1.5, APE_FLOOR), max(values) * 1.5
        ax.plot([lo, hi], [lo, hi], "k-", lw=0.8)
        ax.plot([lo, hi], [lo / 2, hi / 2], "k:", lw=0.8)
        for number, case in enumerate(cases):
            pts = np.array([(a, b) for c, a, b in rows if c == case]).reshape(-1, 2)
            ax.scatter(
                np.maximum(pts[:, 0], lo),
                np.maximum(pts[:, 1], lo),
                s=18,
                marker=_MARKERS[number % len(_MARKERS)],
                label=case,
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(lo, hi)
        ax.set_ylim(lo, hi)
        ax.set_aspect("equal")
        ax.set_xlabel("APE rmse, no guidance (m)")
        ax.set_ylabel(f"APE rmse, {guidance} (m)")
        c = summary.compared(Measure(method)).by_guidance[guidance]
        ratio = f"median ratio {c.median_ratio:.2f}" if c.pairs else "no pairs"
        ax.set_title(f"{method}: {guidance}\n{ratio}", fontsize=9)
    axes[0][0].legend(fontsize=7, loc="upper left")
    # Wrapped to the figure's width: one column of panels (a single guidance) is narrow.
    title = (
        "Each point a start/goal pair; below the solid line guidance localizes better, below the dotted line by half"
    )
    fig.suptitle(textwrap.fill(title, width=int(14 * 3.6 * columns)), fontsize=9)
    fig.tight_layout()
    save_figure(fig, Path(path))


def ratio_figure(summary: Summary, path: Path) -> None:
    """Per map, the ratio APE(default) / APE(none) of every pair (localization and LIO,
    the legend naming the LIO's odometry per map)."""
    if not any(g.name == DEFAULT for g in summary.guidance):
        return
    plt = _plt()
    cases = [c.name for c in summary.cases]
    fig, ax = plt.subplots(figsize=(max(6, 1.3 * len(cases)), 4), dpi=110)
    labels = {LOCALIZATION: LOCALIZATION, LIO: f"LIO ({summary.odometry_line()})"}
    for offset, method, colour in ((-0.15, LOCALIZATION, "tab:blue"), (0.15, LIO, "tab:orange")):
        rows = _errors(summary, DEFAULT, method)
        for number, case in enumerate(cases):
            r = np.array([b / max(a, APE_FLOOR) for c, a, b in rows if c == case])
            if r.size:
                ax.scatter(
                    np.full(r.size, number + offset),
                    r,
                    s=16,
                    color=colour,
                    label=labels[method] if number == 0 else None,
                )
                ax.plot([number + offset - 0.1, number + offset + 0.1], [np.median(r)] * 2, color=colour, lw=2)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_yscale("log")
    ax.set_xticks(range(len(cases)), cases)
    ax.set_ylabel("APE ratio, default guidance / none")
    ax.set_title("Below 1: guidance localizes better (bars: medians)", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, Path(path))


def example_figures(summary: Summary, folder: StudyFolder) -> None:
    """For each map, its first pair's unguided and default trajectories over the SOLM, and
    their localization error along the way (seed 0)."""
    from lf3pm.solm import Solm
    from lf3pm.solm.figures import draw_heat_map
    from lf3pm.trajectory.trajectory import read_csv

    plt = _plt()
    folder.examples.mkdir(parents=True, exist_ok=True)
    default = next((g for g in summary.guidance if g.name == DEFAULT), None)
    for case in summary.cases:
        pair = next((p for p in summary.pairs if p.case == case.name), None)
        if pair is None or default is None or DEFAULT not in pair.plans:
            continue
        solm = Solm.open(folder.solm(case.name))
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 9), dpi=110, gridspec_kw={"height_ratios": [3, 1]})
        # A composite cost channel is no SOLM channel: drawn over its first part.
        draw_heat_map(
            fig, top, solm, channel=COMPOSITE_CHANNELS.get(default.channel, (default.channel,))[0], reduce="min"
        )
        for name, colour in ((NONE, "white"), (DEFAULT, "tab:red")):
            plan = pair.plans[name]
            t, x, y, yaw = (read_csv(folder.root / plan.csv)[k] for k in ("t", "x", "y", "yaw"))
            every = max(1, len(t) // 30)
            label = f"{name}: {plan.length_m:.0f} m"
            localization = plan.replays.get(LOCALIZATION)
            if localization is not None:
                label += f", localization APE {100 * localization.ape:.1f} cm"
                first = read_replay(folder.replay(case.name, pair.number, name, LOCALIZATION, 0))
                bottom.plot(
                    first.times_every_second,
                    first.errors_every_second,
                    color="k" if name == NONE else colour,
                    label=f"{name} (seed 0)",
                )
            top.plot(x, y, "-", color=colour, lw=1.6, label=label, zorder=4)
            top.quiver(
                x[::every],
                y[::every],
                np.cos(yaw[::every]),
                np.sin(yaw[::every]),
                color=colour,
                scale=28,
                width=0.003,
                zorder=5,
            )
        top.legend(loc="best", fontsize=8, facecolor="0.6")
        top.set_title(f"{case.name}: pair {pair.number} ({pair.robot}, {case.sensor}), heading ticks", fontsize=9)
        bottom.set_xlabel("time (s)")
        bottom.set_ylabel("localization error (m)")
        bottom.legend(fontsize=8)
        fig.tight_layout()
        save_figure(fig, folder.examples / f"{case.name}.png")


def forest_figure(summary: Summary, path: Path) -> None:
    """The analysis at the level of the map (summary.map_analysis) as a forest plot: one
    panel per measure; each map's geometric-mean APE ratio with its interval (at-risk
    maps in red), each robot's beside it, and the effects over maps (diamonds) below."""
    analysed = summary.map_analysis
    if analysed is None:
        return
    plt = _plt()
    measures = [m for m in (Measure(LOCALIZATION), Measure(LIO)) if m.key in analysed.by_measure]
    risky = {p.case for p in summary.pairs if p.at_risk}
    first = analysed.by_measure[measures[0].key]
    rows = len(first.by_map) + len(first.over_maps) + 1
    fig, axes = plt.subplots(1, len(measures), figsize=(5.2 * len(measures), 0.36 * rows + 1.4), dpi=110, squeeze=False)
    for ax, measure in zip(axes[0], measures):
        m = analysed.by_measure[measure.key]
        robots = {e.name: e for e in m.by_map_robot}
        labels = []
        y = 0
        for e in m.by_map:
            colour = "tab:red" if e.name in risky else "tab:blue"
            ax.errorbar(e.ratio, y, xerr=[[e.ratio - e.ci[0]], [e.ci[1] - e.ratio]], fmt="o", color=colour, capsize=3)
            for offset, robot, marker in ((-0.22, "diff", "v"), (0.22, "omni", "^")):
                r = robots.get(f"{e.name}, {robot}")
                if r is not None:
                    ax.plot(r.ratio, y + offset, marker, color=colour, ms=4, alpha=0.55)
            labels.append(f"{e.name} ({e.pairs})")
            y += 1
        y += 1
        labels.append("")
        for e in m.over_maps:
            if e.pairs:
                ax.errorbar(
                    e.ratio, y, xerr=[[e.ratio - e.ci[0]], [e.ci[1] - e.ratio]], fmt="D", color="k", capsize=3, ms=6
                )
            labels.append(f"over maps: {e.name} ({e.maps} maps)")
            y += 1
        ax.axvline(1.0, color="k", lw=0.8)
        ax.set_xscale("log")
        ax.set_yticks(range(len(labels)), labels, fontsize=8)
        ax.invert_yaxis()
        ax.set_xlabel(f"geometric-mean APE ratio, {analysed.settings.guidance} / none")
        ax.set_title(f"{measure.title}: {100 * analysed.settings.level:g} % intervals", fontsize=9)
    fig.suptitle("Red: maps with pairs at risk; triangles: the diff (v) and omni (^) robots' effects", fontsize=9)
    fig.tight_layout()
    save_figure(fig, Path(path))
