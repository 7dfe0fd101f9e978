"""The tables `lf3pm replay` prints: each seed's figures and their medians, and what the
odometry did at rest before the trajectory."""

from __future__ import annotations

import math

from rich import box
from rich.table import Table

from lf3pm.cli._common import console, print_warning
from lf3pm.config import DEFAULTS, ReplayConfig


def print_series(series, settings: ReplayConfig = DEFAULTS.replay) -> None:
    """The figures of each seed and their medians, translations in mm (in metres eleven
    columns of 0.00xxx do not fit 80 characters); the rest judged by the replay section
    ``settings``."""
    from lf3pm.replays.replay_result import FIGURES

    first = series.results[0]
    odometry = first.report.get("odometry")
    method = f"{first.method} ({odometry})" if odometry else first.method
    table = Table(
        title=f"replay: {method}, {first.sensor}, {first.scans} scans at "
        f"{first.params['rate']:g} Hz (rmse in mm; RPE deg per scan)",
        box=box.SIMPLE_HEAD,
        collapse_padding=True,
        pad_edge=False,
    )
    table.add_column("seed")
    for _, header, _ in FIGURES:
        table.add_column(header, justify="right")

    for r in series.results:
        table.add_row(str(r.seed), *(format_figure(key, get(r)) for key, _, get in FIGURES))
    if len(series.results) > 1:
        table.add_row("median", *(format_figure(key, series.median[key]) for key, _, _ in FIGURES))
    console.print(table)
    print_rest(series.results, settings)


def format_figure(key: str, value) -> str:
    """One cell of the replay table: metres in mm, three significant digits, whole numbers
    from 1000 up (a failed run's 27463 mm, not 2.75e+04, which the 80-column table cuts)."""
    from lf3pm.replays.replay_result import METRE_FIGURES

    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    value = value * 1000.0 if key in METRE_FIGURES else value
    if isinstance(value, int):
        return str(value)
    return f"{value:.0f}" if abs(value) >= 1000 else f"{value:.3g}"


def print_rest(results, settings: ReplayConfig = DEFAULTS.replay) -> None:
    """What the LIO did while the sensor stood still before the trajectory, per seed,
    and a warning for each seed that entered the trajectory moving (faster than the
    replay section's rest_speed_limit)."""
    rested = [r for r in results if r.rest]
    if not rested:
        return
    moves = ", ".join(f"seed {r.seed} {1000 * r.rest['drift_m']:.0f} mm" for r in rested)
    console.print(
        f"rest ({rested[0].rest['seconds']:g} s still before the trajectory; APE re-anchored after it): "
        f"the estimate moved at most {moves}",
        highlight=False,
    )
    for r in rested:
        if not r.rest["steady"]:
            print_warning(
                f"seed {r.seed}: the odometry still moved at {r.rest['speed_mps']:.2f} m/s at the end of "
                f"the rest (> {settings.rest_speed_limit:g} m/s): it entered the trajectory with a velocity "
                'error, so this APE measures its start, not the trajectory (docs/lio.md, "A still '
                'sensor")'
            )
