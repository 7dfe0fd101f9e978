"""An audit's figures: its errors and predictions along the run, and the run's path over the
map seen from above, coloured by real error."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from lf3pm.atomic import atomic_write

#: Map points drawn at most in the view from above (a random subset, fixed seed).
MAP_POINTS_DRAWN = 200_000


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> None:
    plt = _pyplot()
    try:
        fig.tight_layout()
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=110)
        with atomic_write(path) as fp:
            fp.write(buf.getvalue())
    finally:
        plt.close(fig)


def _column(records, name: str) -> np.ndarray:
    return np.array([getattr(r, name) for r in records], dtype=np.float64)


def _logged(records, name: str) -> np.ndarray:
    """A column for a log axis: zeros (an odometry's anchored first scan) left as gaps."""
    values = _column(records, name)
    return np.where(values > 0, values, np.nan)


def along_run_figure(records, path: Path) -> None:
    """Top: the real errors (against the reference, the converged poses' spread, map
    localization and KISS-ICP along the run where they ran) and the
    predicted localization error with its [10 %, 90 %] band, in m against time; middle: q_n
    of the recorded and of the simulated scan, and the recorded scan's q_min and q_max;
    bottom: the simulated/real q_n ratio. Log scales; a missing value leaves a gap."""
    plt = _pyplot()
    t = _column(records, "time_s")
    fig, (top, middle, bottom) = plt.subplots(3, 1, figsize=(9, 8.5), sharex=True)
    top.plot(t, _logged(records, "error_m"), "o-", ms=3, label="real error against the reference (mean over starts)")
    top.plot(t, _logged(records, "spread_m"), "s-", ms=3, label="spread of the converged registrations (RMS)")
    for name, style, label in (
        ("tracking_error_m", "d-", "map localization along the run"),
        ("odometry_error_m", "x:", "KISS-ICP along the run"),
    ):
        if np.isfinite(_column(records, name)).any():
            top.plot(t, _logged(records, name), style, ms=3, label=label)
    predicted = _column(records, "predicted_error_m")
    if np.isfinite(predicted).any():
        top.plot(t, predicted, "k--", label="predicted localization error")
        top.fill_between(
            t,
            _column(records, "predicted_error_lo_m"),
            _column(records, "predicted_error_hi_m"),
            color="0.8",
            label="predicted 10-90 %",
        )
    else:
        top.text(0.01, 0.04, "predicted localization error withheld on every scan", transform=top.transAxes)
    top.set_yscale("log")
    top.set_ylabel("error (m)")
    top.legend(fontsize=8, loc="best")
    top.set_title("Registration errors and predictions along the run")
    middle.plot(t, _column(records, "real_q_n"), "o-", ms=3, label="q_n, recorded scan")
    middle.plot(t, _column(records, "sim_q_n"), "^-", ms=3, label="q_n, simulated scan")
    middle.plot(t, _column(records, "real_q_min"), ":", label="q_min, recorded scan")
    middle.plot(t, _column(records, "real_q_max"), ":", label="q_max, recorded scan")
    middle.set_yscale("log")
    middle.set_ylabel("metric")
    middle.legend(fontsize=8, loc="upper right")
    bottom.plot(t, _column(records, "q_n_ratio"), "o-", ms=3, color="C3")
    bottom.axhline(1.0, color="0.5", lw=0.8)
    bottom.set_yscale("log")
    bottom.set_ylabel("q_n simulated / recorded")
    bottom.set_xlabel("time since the first audited scan (s)")
    _save(fig, path)


def path_figure(records, map_points: np.ndarray, path: Path) -> None:
    """The map's points from above (grey, a random subset, the view clipped to the run and
    the central 99 % of the map, so that a few far points do not shrink it) and each
    audited scan's position, coloured by its real error against the reference (log
    scale); the first scan ringed."""
    from matplotlib.colors import LogNorm

    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8.5, 7))
    points = np.asarray(map_points)
    if len(points) > MAP_POINTS_DRAWN:
        points = points[np.random.default_rng(0).choice(len(points), MAP_POINTS_DRAWN, replace=False)]
    x, y, error = _column(records, "x"), _column(records, "y"), _column(records, "error_m")
    lower = np.minimum(np.quantile(points[:, :2], 0.005, axis=0), [x.min(), y.min()]) - 2.0
    upper = np.maximum(np.quantile(points[:, :2], 0.995, axis=0), [x.max(), y.max()]) + 2.0
    ax.scatter(points[:, 0], points[:, 1], s=0.2, c="0.75", linewidths=0, rasterized=True)
    ax.plot(x, y, "-", color="0.3", lw=0.8)
    good = np.isfinite(error) & (error > 0)
    if good.any():
        lo, hi = error[good].min(), error[good].max()
        drawn = ax.scatter(
            x[good],
            y[good],
            c=error[good],
            s=36,
            cmap="viridis",
            edgecolors="k",
            linewidths=0.4,
            norm=LogNorm(vmin=lo, vmax=max(hi, lo * 1.0001)),
            zorder=3,
        )
        fig.colorbar(drawn, ax=ax, shrink=0.8, label="real registration error against the reference (m)")
    if (~good).any():
        ax.scatter(x[~good], y[~good], marker="x", c="r", s=30, zorder=3, label="no error (registration failed or off)")
        ax.legend(fontsize=8, loc="upper right")
    ax.scatter(x[:1], y[:1], s=160, facecolors="none", edgecolors="r", linewidths=1.5, zorder=4)
    ax.set_xlim(lower[0], upper[0])
    ax.set_ylim(lower[1], upper[1])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("The run over the map from above, coloured by real error\n(red ring: the first audited scan)")
    _save(fig, path)
