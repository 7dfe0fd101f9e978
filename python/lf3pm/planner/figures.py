"""Plans drawn over the SOLM heat map: grid paths dotted, trajectories solid."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from lf3pm.solm.figures import draw_heat_map, new_figure, save_figure
from lf3pm.solm.reader import Solm

COLOURS = {"q_n": "tab:red", "q_min": "tab:orange", "step_norm": "tab:purple", "default": "tab:green", "none": "white"}


def plans_figure(
    solm: Solm,
    plans: dict,
    path: Path,
    *,
    channel: str = "q_n",
    map_points: np.ndarray | None = None,
    labels: dict | None = None,
    title: str | None = None,
) -> None:
    """Writes a PNG of ``plans`` ({name: Plan}) over ``channel`` (min over yaw for se2)."""
    fig, ax = new_figure()
    draw_heat_map(fig, ax, solm, channel=channel, reduce="min", map_points=map_points)
    for name, plan in plans.items():
        colour = COLOURS.get(name, "tab:cyan")
        samples = plan.trajectory.sample(10.0)
        ax.plot(plan.path.poses[:, 0], plan.path.poses[:, 1], ":", color=colour, lw=0.8, zorder=3)
        ax.plot(samples["x"], samples["y"], "-", color=colour, lw=1.6, zorder=4, label=(labels or {}).get(name, name))
        # Heading ticks every few seconds show the yaw the optimiser chose.
        every = max(1, len(samples["x"]) // 25)
        ax.quiver(
            samples["x"][::every],
            samples["y"][::every],
            np.cos(samples["yaw"][::every]),
            np.sin(samples["yaw"][::every]),
            color=colour,
            scale=40,
            width=0.002,
            zorder=5,
        )
    ends = next(iter(plans.values())).trajectory.sample(10.0)
    ax.plot(ends["x"][0], ends["y"][0], "o", color="k", mec="w", zorder=6)
    ax.plot(ends["x"][-1], ends["y"][-1], "*", color="k", mec="w", ms=12, zorder=6)
    ax.legend(loc="lower right", fontsize=8, facecolor="0.6")
    if title:
        ax.set_title(title, fontsize=9)
    save_figure(fig, Path(path))
