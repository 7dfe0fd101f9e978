"""SOLM pictures: a heat map over the map's top view, and ROS map_server exports."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from lf3pm.atomic import atomic_write
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Space
from lf3pm.solm.reader import Solm

REDUCTIONS = ("min", "mean", "max")


def reduced(solm: Solm, channel: str, reduce: str) -> np.ndarray:
    """The channel as one (ny, nx) layer: r2 as stored, se2/r3 reduced over layers."""
    data = solm.channel(channel).astype(np.float64)
    if data.ndim == 2:
        return data
    if reduce not in REDUCTIONS:
        raise Lf3pmError(f"reduce must be one of {', '.join(REDUCTIONS)}")
    finite = np.where(np.isfinite(data), data, np.nan)
    with np.errstate(all="ignore"):
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return getattr(np, f"nan{reduce}")(finite, axis=0)


def heat_map(
    solm: Solm, path: Path, *, channel: str = "q_n", reduce: str = "mean", map_points: np.ndarray | None = None
) -> None:
    """Writes a PNG of ``channel`` (log colour scale) over the map's top view."""
    fig, ax = new_figure()
    draw_heat_map(fig, ax, solm, channel=channel, reduce=reduce, map_points=map_points)
    save_figure(fig, Path(path))


def new_figure():
    """A figure and axes sized for a map view (Agg backend: no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=(9, 7), dpi=110)


def draw_heat_map(
    fig, ax, solm: Solm, *, channel: str = "q_n", reduce: str = "mean", map_points: np.ndarray | None = None
) -> None:
    """Draws ``channel`` (log colour scale), the obstacles in black and, under
    unknown cells, the map's points, with a colour bar and axis labels."""
    from matplotlib.colors import LogNorm

    g = solm.grid_spec
    layer = reduced(solm, channel, reduce)
    xmin, ymin, xmax, ymax = g.bounds
    extent = (xmin, xmax, ymin, ymax)
    if map_points is not None:
        step = max(1, len(map_points) // 300_000)
        ax.scatter(
            map_points[::step, 0], map_points[::step, 1], s=0.1, c="0.75", linewidths=0, zorder=0
        )  # under the heat map: shows through unknown cells only
    positive = layer[np.isfinite(layer) & (layer > 0)]
    norm = LogNorm(positive.min(), positive.max()) if len(positive) and channel.startswith("q") else None
    image = ax.imshow(
        np.ma.masked_invalid(layer),
        origin="lower",
        extent=extent,
        cmap="viridis_r" if channel.startswith("q") else "viridis",
        norm=norm,
        interpolation="nearest",
        zorder=1,
    )
    blocked = solm.channel("obstacle")
    blocked = blocked.max(axis=0) if blocked.ndim == 3 else blocked
    ax.imshow(
        np.ma.masked_equal(blocked, 0),
        origin="lower",
        extent=extent,
        cmap="Greys",
        vmin=0,
        vmax=1,
        interpolation="nearest",
        zorder=2,
    )
    fig.colorbar(
        image,
        ax=ax,
        label=f"{channel} (lower = better localization)" if channel.startswith("q") else channel,
        shrink=0.85,
    )
    over = {Space.SE2: "yaw", Space.R3: "z", Space.R3YAW: "yaw and z"}
    how = "" if g.space is Space.R2 else f", {reduce} over {over[g.space]}"
    ax.set_title(
        f"SOLM {channel}{how}: {g.space}, {g.res} m, sensor {solm.attrs['sensor']} (black: obstacle, blank: unknown)",
        fontsize=9,
    )
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal")


def export_ros(solm: Solm, folder: Path, *, reduce: str = "mean") -> list[Path]:
    """ROS map_server pairs per channel: an 8-bit PNG (0 = best, 255 = worst or
    invalid, log scale for q) and its YAML (image, resolution, origin,
    thresholds; the value range in a comment)."""
    import matplotlib.pyplot as plt

    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise Lf3pmError(f"{folder}: cannot create the folder ({err.strerror or err})") from None
    g = solm.grid_spec
    written = []
    for channel in ("q_min", "q_n", "q_max", "sigma1", "m"):
        layer = reduced(solm, channel, reduce)
        ok = np.isfinite(layer) & (layer > 0)
        values = np.log(layer) if channel.startswith("q") else layer
        lo, hi = (values[ok].min(), values[ok].max()) if ok.any() else (0.0, 1.0)
        scaled = np.where(ok, (values - lo) / max(hi - lo, 1e-12), 1.0)
        if not channel.startswith("q"):
            scaled = np.where(ok, 1.0 - scaled, 1.0)  # sigma1 and m: larger is better
        pixels = np.round(255 * (1.0 - scaled)).astype(np.uint8)  # map_server: dark = occupied
        png = folder / f"{channel}.png"
        with atomic_write(png) as fp:
            plt.imsave(fp, pixels[::-1], cmap="gray", vmin=0, vmax=255, format="png")
        yaml = folder / f"{channel}.yaml"
        text = (
            f"# lf3pm SOLM channel {channel} ({'log ' if channel.startswith('q') else ''}range "
            f"{lo:.6g} .. {hi:.6g} mapped to white .. black), sensor {solm.attrs['sensor']}\n"
            f"image: {png.name}\nresolution: {g.res}\norigin: [{g.x0}, {g.y0}, 0.0]\n"
            "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
        )
        with atomic_write(yaml) as fp:
            fp.write(text.encode())
        written += [png, yaml]
    return written


def save_figure(fig, path: Path, *, tight: bool = True) -> None:
    """Writes ``fig`` to ``path`` atomically (its format from the suffix; an OSError
    becomes one line) and closes it; ``tight``: apply tight_layout first."""
    import matplotlib.pyplot as plt

    path = Path(path)
    try:
        if tight:
            fig.tight_layout()
        with atomic_write(path) as fp:
            fig.savefig(fp, format=path.suffix.lstrip(".").lower() or "png")
    finally:
        plt.close(fig)
