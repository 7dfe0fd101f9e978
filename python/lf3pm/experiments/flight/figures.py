"""The flight study's figure: the joint planner's error against each baseline's, pair by
pair (from summary.json alone)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from lf3pm.solm.figures import save_figure

#: APE below this (m) is drawn at it, so that log axes hold every pair.
APE_FLOOR = 1e-3
_MARKERS = "osD^vP*X"
_BASELINES = (("a_m", "(a) velocity_yaw"), ("b_m", "(b) yaw_only"))


def scatter_figure(summary: dict, path: Path) -> None:
    """APE of (c) against (a) and against (b), one row of panels per odometry, log-log, a
    marker per map, filled for at-risk pairs and hollow for the others; below the diagonal
    the joint planner localizes better, below the dotted line by more than half."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pairs = summary["pairs"]
    odometries = list(dict.fromkeys(p["odometry"] for p in pairs))
    maps = list(dict.fromkeys(p["map"] for p in pairs))
    values = [max(p[k], APE_FLOOR) for p in pairs for k in ("a_m", "b_m", "c_m")]
    lo, hi = min(values) / 1.5, max(values) * 1.5
    fig, axes = plt.subplots(len(odometries), 2, figsize=(8.0, 3.9 * len(odometries)), dpi=110, squeeze=False)
    for row, odometry in enumerate(odometries):
        for column, (key, name) in enumerate(_BASELINES):
            ax = axes[row][column]
            ax.plot([lo, hi], [lo, hi], "k-", lw=0.8)
            ax.plot([lo, hi], [lo / 2, hi / 2], "k:", lw=0.8)
            for number, m in enumerate(maps):
                for risk, fill in (("at_risk", True), ("no_risk", False)):
                    pts = np.array(
                        [
                            (p[key], p["c_m"])
                            for p in pairs
                            if (p["odometry"], p["map"], p["risk"]) == (odometry, m, risk)
                        ]
                    ).reshape(-1, 2)
                    if not len(pts):
                        continue
                    colour = f"C{number}"
                    ax.scatter(
                        np.maximum(pts[:, 0], APE_FLOOR),
                        np.maximum(pts[:, 1], APE_FLOOR),
                        s=22,
                        marker=_MARKERS[number % len(_MARKERS)],
                        facecolors=colour if fill else "none",
                        edgecolors=colour,
                        label=f"{m}{' (at risk)' if fill else ''}",
                    )
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlim(lo, hi)
            ax.set_ylim(lo, hi)
            ax.set_aspect("equal")
            ax.set_xlabel(f"APE rmse, {name} (m)")
            ax.set_ylabel("APE rmse, (c) joint (m)")
            ax.set_title(f"{odometry}: (c) against {name}", fontsize=9)
        axes[row][0].legend(fontsize=7, loc="upper left")
    fig.suptitle(
        f"{summary['protocol']}: each point a pair (median over seeds); below the solid line (c) localizes better, "
        "below the dotted line by half",
        fontsize=8,
    )
    fig.tight_layout()
    save_figure(fig, Path(path))
