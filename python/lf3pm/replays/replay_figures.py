"""The replay's picture: the translation error along the trajectory for each
seed, and a top view of the truth and the estimates over the map."""

from __future__ import annotations

import io

import numpy as np

from lf3pm.atomic import atomic_write


def seed_label(result) -> str:
    """A seed's legend entry: its APE, and where a LIO entered the trajectory already moving
    (an unsteady rest: ReplayResult.rest), that speed, as the CLI warns."""
    label = f"seed {result.seed}: APE rmse {result.ape['rmse']:.3g} m"
    if result.rest and not result.rest["steady"]:
        label += f" (LIO entered moving at {result.rest['speed_mps']:.2f} m/s)"
    return label


def replay_figure(results: list, path, *, map_points: np.ndarray | None = None, title: str | None = None) -> None:
    """Writes a PNG of ``results`` (ReplayResults of one trajectory, one per seed):
    left, |t(estimate) - t(truth)| against time per seed, degenerate scans
    dotted and skipped scans crossed; right, the map's points near the path
    (dark: 0.1 m columns holding a map point 0.15-2 m above their lowest one,
    obstacles at robot height; light grey: ground; white: no map point), the
    truth (black) and each seed's estimate."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 5.2), gridspec_kw={"width_ratios": [1.2, 1]})
    colours = plt.cm.tab10(np.arange(len(results)) % 10)
    for r, colour in zip(results, colours):
        t = r.times - r.times[0]
        left.plot(t, r.errors, "-", color=colour, lw=1.2, label=seed_label(r))
        bad = r.degenerate
        if bad.any():
            left.plot(t[bad], r.errors[bad], ".", color=colour, ms=5)
        if r.skipped:
            left.plot(t[r.skipped], r.errors[r.skipped], "x", color=colour, ms=6)
    first = results[0]
    left.set_xlabel("time since the first scan (s)")
    left.set_ylabel("translation error |t_est - t_true| (m)")
    marks = "; dots: degenerate scans" if any(r.degenerate.any() for r in results) else ""
    marks += "; crosses: skipped scans" if any(r.skipped for r in results) else ""
    left.set_title(f"{first.method}, {first.sensor}: error along the trajectory{marks}", fontsize=9)
    left.set_ylim(bottom=0)
    left.grid(alpha=0.3)
    left.legend(fontsize=8)

    truth = first.truth[:, :3, 3]
    estimates = [r.estimate[:, :3, 3] for r in results]
    xy = np.vstack([truth[:, :2], *[e[:, :2] for e in estimates]])
    margin = max(2.0, 0.1 * float(np.max(np.ptp(xy, axis=0))))
    lo, hi = xy.min(axis=0) - margin, xy.max(axis=0) + margin
    if map_points is not None and len(map_points):
        extent, occupied, known = _obstacles(map_points, lo, hi)
        image = np.where(occupied, 0.25, np.where(known, 0.93, 1.0))
        right.imshow(image, origin="lower", extent=extent, cmap="gray", vmin=0.0, vmax=1.0, interpolation="nearest")
    right.plot(truth[:, 0], truth[:, 1], "-", color="k", lw=2.2, label="truth")
    for r, e, colour in zip(results, estimates, colours):
        right.plot(e[:, 0], e[:, 1], "-", color=colour, lw=1.0, label=f"estimate, seed {r.seed}")
    right.plot(truth[0, 0], truth[0, 1], "o", color="k", ms=6)
    right.plot(truth[-1, 0], truth[-1, 1], "*", color="k", ms=11)
    right.set_xlim(lo[0], hi[0])
    right.set_ylim(lo[1], hi[1])
    right.set_aspect("equal")
    right.set_xlabel("x (m)")
    right.set_ylabel("y (m)")
    right.set_title("top view: truth and estimates over the map (o start, * goal)", fontsize=9)
    right.legend(fontsize=8, loc="best")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    with atomic_write(path) as fp:
        fp.write(buf.getvalue())


def _obstacles(points: np.ndarray, lo, hi, cell: float = 0.1, band=(0.15, 2.0)):
    """(extent, occupied, known), (ny, nx) images over [lo, hi] in columns of
    ``cell``: known where a column holds a map point, occupied where one lies
    within ``band`` above the column's lowest point (a ceiling is no obstacle)."""
    nx, ny = (int(np.ceil(v)) for v in (np.asarray(hi) - lo) / cell)
    ij = np.floor((points[:, :2] - lo) / cell).astype(np.int64)
    inside = (ij[:, 0] >= 0) & (ij[:, 0] < nx) & (ij[:, 1] >= 0) & (ij[:, 1] < ny)
    ij, z = ij[inside], points[inside, 2]
    low = np.full((ny, nx), np.inf)
    np.minimum.at(low, (ij[:, 1], ij[:, 0]), z)
    above = z - low[ij[:, 1], ij[:, 0]]
    hit = (above > band[0]) & (above <= band[1])
    occupied = np.zeros((ny, nx), bool)
    occupied[ij[hit, 1], ij[hit, 0]] = True
    return (lo[0], lo[0] + nx * cell, lo[1], lo[1] + ny * cell), occupied, np.isfinite(low)
