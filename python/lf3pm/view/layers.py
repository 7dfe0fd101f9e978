"""What the viewer draws, as plain arrays computed from lf3pm's public objects (a Map, a
Solm, a trajectory's samples, a replay's JSON, an Evaluation): the tests check them
without a browser, and the page only hands them to viser."""

from __future__ import annotations

import math

import numpy as np

from lf3pm.calibration import (
    LOCALIZATION_PACKAGED,
    packaged_calibration,
    predict_localization_error,
)
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Space
from lf3pm.solm import Solm

#: The SOLM channels the page offers, with what the colour bar says of each.
CHANNELS = {
    "q_n": "q_n (no unit, log scale; larger: worse localization)",
    "q_min": "q_min (no unit, log scale)",
    "q_max": "q_max (no unit, log scale)",
    "predicted_error": "predicted localization error (m, log scale)",
}
#: Map points sent to the browser at most (a browser draws a few million points slowly).
MAX_MAP_POINTS = 1_000_000
#: Seed of the map's subsample: the same points on every start.
SUBSAMPLE_SEED = 0
#: Pixels (width, height) of the colour bar, and the values it labels.
COLORBAR_PIXELS = (360, 90)
COLORBAR_TICKS = 4
#: Length (m) of the arrow of the least observable direction at a clicked cell.
ARROW_LENGTH = 2.0


def colormap(values: np.ndarray, lo: float, hi: float, *, log: bool = True, name: str = "viridis") -> np.ndarray:
    """uint8 RGB (N, 3) of ``values`` on matplotlib's ``name`` colour map over [lo, hi]
    (log scale by default); NaN values grey."""
    from matplotlib import colormaps

    v = np.asarray(values, dtype=np.float64)
    with np.errstate(all="ignore"):
        if log:
            v, lo, hi = np.log(v), math.log(lo), math.log(hi)
        t = np.clip((v - lo) / (hi - lo) if hi > lo else np.zeros_like(v), 0.0, 1.0)
    rgb = (colormaps[name](np.nan_to_num(t))[:, :3] * 255).astype(np.uint8)
    rgb[~np.isfinite(v)] = 128
    return rgb


def map_cloud(points: np.ndarray, max_points: int = MAX_MAP_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """(points as float32, uint8 RGB by height): all of them, or a seeded random
    ``max_points`` of a larger map (the page says how many of how many)."""
    if len(points) > max_points:
        keep = np.sort(np.random.default_rng(SUBSAMPLE_SEED).choice(len(points), max_points, replace=False))
        points = points[keep]
    z = points[:, 2]
    lo, hi = np.percentile(z, [1, 99]) if len(z) else (0.0, 1.0)
    return points.astype(np.float32), colormap(z, lo, max(hi, lo + 1e-6), log=False, name="turbo")


def solm_values(solm: Solm, channel: str, layer: int | None = None) -> np.ndarray:
    """One (ny, nx) layer of ``channel`` (CHANNELS): an R² SOLM as stored; SE(2) at yaw bin
    ``layer``, or its minimum over yaw when ``layer`` is None (the best heading at each
    cell: what an omni robot that may turn can have); R3 at height level ``layer`` (0 when
    None). ``predicted_error`` is the packaged fit of localization error on q_n."""
    if channel not in CHANNELS:
        raise Lf3pmError(f"unknown channel {channel!r}; the viewer shows {', '.join(CHANNELS)}")
    data = solm.channel("q_n" if channel == "predicted_error" else channel).astype(np.float64)
    if data.ndim == 3:
        if layer is None and solm.grid_spec.space is Space.SE2:
            with np.errstate(all="ignore"):
                finite = np.where(np.isfinite(data), data, np.inf)
                data = np.min(finite, axis=0)
                data[~np.isfinite(data)] = np.nan
        else:
            data = data[int(layer or 0)]
    return predicted_error(data) if channel == "predicted_error" else data


def predicted_error(q_n: np.ndarray) -> np.ndarray:
    """The localization error (m) the packaged fit predicts at each q_n; NaN where q_n is
    unknown or degenerate. Lf3pmError when lf3pm ships no fit."""
    fit = packaged_calibration(LOCALIZATION_PACKAGED)
    if fit is None:
        raise Lf3pmError("no packaged localization-error fit: the predicted error is not available")
    predict = np.vectorize(lambda q: (predict_localization_error(fit, q) or (np.nan,))[0], otypes=[float])
    return predict(np.asarray(q_n, dtype=np.float64))


def solm_layer(solm: Solm, channel: str, layer: int | None = None) -> dict:
    """The SOLM as coloured squares over the ground: ``centres`` (K, 3) float32 just above
    each evaluated cell's ground, ``colors`` (K, 3) uint8, ``values`` (K,), the colour
    range ``lo``, ``hi`` (the 2nd and 98th percentiles) and the cell edge ``res``."""
    values = solm_values(solm, channel, layer)
    g = solm.grid_spec
    ys, xs = np.meshgrid(g.ys(), g.xs(), indexing="ij")
    if g.space is Space.R3:  # its levels are heights in the map's frame
        z = np.full(values.shape, g.z_levels[int(layer or 0)])
    else:
        ground = solm.channel("ground_z").astype(np.float64)
        z = np.where(np.isfinite(ground), ground, 0.0) + 0.05
    shown = np.isfinite(values) & (values > 0)
    v = values[shown]
    lo, hi = np.percentile(v, [2, 98]) if len(v) else (1.0, 2.0)
    hi = max(hi, lo * 1.0001)
    return {
        "centres": np.c_[xs[shown], ys[shown], z[shown]].astype(np.float32),
        "colors": colormap(v, lo, hi),
        "values": v,
        "lo": float(lo),
        "hi": float(hi),
        "res": g.res,
    }


def colorbar_image(lo: float, hi: float, label: str, pixels: tuple = COLORBAR_PIXELS) -> np.ndarray:
    """An RGB image (rows, columns, 3) of the log colour bar from ``lo`` to ``hi`` with its
    label and COLORBAR_TICKS values from end to end, ``pixels`` (width, height) large.
    The end values are aligned inwards, so that every label lies inside the image."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from matplotlib.ticker import NullLocator

    fig = plt.figure(figsize=(pixels[0] / 100, pixels[1] / 100), dpi=100)
    ax = fig.add_axes((0.04, 0.42, 0.92, 0.25))
    bar = fig.colorbar(plt.cm.ScalarMappable(norm=LogNorm(lo, hi), cmap="viridis"), cax=ax, orientation="horizontal")
    ticks = np.geomspace(lo, hi, COLORBAR_TICKS)
    bar.set_ticks(ticks, labels=[f"{t:.3g}" for t in ticks])
    ax.xaxis.set_minor_locator(NullLocator())  # LogNorm's minor labels crowd and overflow the ends
    ax.tick_params(labelsize=7)
    first, *_, last = ax.get_xticklabels()
    first.set_horizontalalignment("left")
    last.set_horizontalalignment("right")
    ax.set_title(label, fontsize=7)
    fig.canvas.draw()
    image = np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy()
    plt.close(fig)
    return image


def polyline(x: np.ndarray, y: np.ndarray, z: np.ndarray | float) -> np.ndarray:
    """Line segments (N - 1, 2, 3) float32 through the points (x, y, z)."""
    p = np.c_[x, y, np.broadcast_to(z, np.shape(x))].astype(np.float32)
    return np.stack([p[:-1], p[1:]], axis=1)


def footprints(samples: dict, radius: float, every_s: float = 1.0, sides: int = 24) -> np.ndarray:
    """Segments (K, 2, 3) of the robot's footprint (a circle of ``radius`` with a heading
    tick) every ``every_s`` seconds of a trajectory's samples (t, x, y, yaw, z optional)."""
    t = samples["t"]
    at = np.searchsorted(t, np.arange(t[0], t[-1] + 1e-9, every_s))
    a = np.linspace(0.0, 2 * np.pi, sides + 1)
    segments = []
    for i in np.minimum(at, len(t) - 1):
        x, y, yaw = samples["x"][i], samples["y"][i], samples["yaw"][i]
        z = samples["z"][i] if "z" in samples else 0.0
        ring = polyline(x + radius * np.cos(a), y + radius * np.sin(a), z)
        tick = polyline(np.array([x, x + radius * math.cos(yaw)]), np.array([y, y + radius * math.sin(yaw)]), z)
        segments += [ring, tick]
    return np.concatenate(segments) if segments else np.zeros((0, 2, 3), np.float32)


def path_length(x: np.ndarray, y: np.ndarray) -> float:
    return float(np.hypot(np.diff(x), np.diff(y)).sum())


def replay_tracks(replay: dict) -> dict:
    """The truth and the estimate of a replay as segments, the estimate's coloured by its
    error: ``truth`` (N-1, 2, 3), ``estimate`` (N-1, 2, 3), ``colors`` (N-1, 2, 3) uint8,
    ``errors`` (N,) m, ``lo``/``hi`` (m), ``rest``: what a LIO did while the sensor stood
    still before the trajectory (replay_result.rest_motion; empty for other methods).
    ``replay``: what ``lf3pm replay --json`` writes (its first run is shown), or a study's
    replay record (its positions once a second). Lf3pmError, naming the field, when a
    field is missing or not what those write: the truth finite numbers, the estimate and
    errors numbers or null (a lost estimate), errors >= 0, ``rest`` an object."""
    if not isinstance(replay, dict):
        raise Lf3pmError("the replay JSON is not an object")
    runs = replay.get("runs")
    run = runs[0] if isinstance(runs, list) and runs else replay
    if not isinstance(run, dict):
        raise Lf3pmError(f"the replay JSON's runs[0] must be an object, got {type(run).__name__}")
    keys = [
        ("truth_xyz", "estimate_xyz", "errors"),
        ("truth_xyz_every_second", "estimate_xyz_every_second", "errors_every_second"),
    ]
    names = next((k for k in keys if all(name in run for name in k)), None)
    if names is None:
        raise Lf3pmError("the replay JSON holds no true and estimated positions (write it with `lf3pm replay --json`)")
    truth, estimate, errors = (
        _numbers(run[name], name, width, nulls=name != names[0]) for name, width in zip(names, (3, 3, None))
    )
    if not (len(truth) == len(estimate) == len(errors)):
        raise Lf3pmError(
            f"the replay JSON's {', '.join(names)} differ in length ({len(truth)}, {len(estimate)}, {len(errors)})"
        )
    if len(truth) < 2:
        raise Lf3pmError("the replay JSON holds fewer than 2 scans")
    known = errors[np.isfinite(errors)]
    if np.any(known < 0):
        raise Lf3pmError(f"the replay JSON's {names[2]} must be >= 0 (distances), got {known.min():g}")
    rest = run.get("rest") or {}
    if not (
        isinstance(rest, dict)
        and (not rest or (isinstance(rest.get("steady"), bool) and _is_number(rest.get("speed_mps"))))
    ):
        raise Lf3pmError(
            "the replay JSON's rest must be an object with steady (true or false) and speed_mps "
            f"(a number), got {repr(rest)[:60]}"
        )
    lo = max(float(known.min()), 1e-3) if known.size else 1e-3
    hi = max(float(known.max()), 2e-3) if known.size else 2e-3
    colors = colormap(errors, lo, hi, name="plasma")
    return {
        "truth": polyline(*truth.T),
        "estimate": polyline(*estimate.T),
        "colors": np.stack([colors[:-1], colors[1:]], axis=1),
        "errors": errors,
        "lo": lo,
        "hi": hi,
        "rest": dict(rest),
    }


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _numbers(value, name: str, width: int | None, *, nulls: bool) -> np.ndarray:
    """A replay JSON's field ``name`` as floats: a list of numbers (``width`` None) or of
    [x, y, z] (``width`` 3); null is NaN where ``nulls``, else every value must be finite.
    Lf3pmError naming the field and the first bad entry otherwise."""
    if not isinstance(value, list):
        raise Lf3pmError(f"the replay JSON's {name} must be a list, got {type(value).__name__}")
    what = ("a number" if width is None else "[x, y, z] of numbers") + (" or null" if nulls else "")
    for i, row in enumerate(value):
        items = [row] if width is None else row if isinstance(row, list) and len(row) == width else None
        if items is None or not all(_is_number(v) or (nulls and v is None) for v in items):
            raise Lf3pmError(f"the replay JSON's {name}[{i}] must be {what}, got {repr(row)[:40]}")
    a = np.array(value, dtype=np.float64).reshape(len(value), *(() if width is None else (width,)))
    if not nulls and not np.isfinite(a).all():
        raise Lf3pmError(f"the replay JSON's {name} must be finite, got {a[~np.isfinite(a)][0]}")
    return a


def replay_caption(name: str, tracks: dict) -> str:
    """The viewer's line for a replay (replay_tracks' ``tracks``): its error range and
    colours, and a warning when a LIO entered the trajectory already moving."""
    lo, hi = tracks["lo"] * 100, tracks["hi"] * 100
    text = (
        f"{name}: error {lo:.1f}-{hi:.1f} cm (estimate coloured from dark, {lo:.1f} cm, to yellow, "
        f"{hi:.1f} cm; truth grey)."
    )
    rest = tracks["rest"]
    if rest and not rest["steady"]:
        text += (
            f" **The odometry was already moving at {rest['speed_mps']:.2f} m/s before the trajectory "
            "started: this error measures its start, not the trajectory.**"
        )
    return text


def weak_directions(observations: dict, position: np.ndarray) -> dict:
    """The least observable translations at a pose from its observations (A, m x 6): the
    eigenvectors of the translation block of AᵀA once rotation is marginalised out (its
    Schur complement), as ``arrows`` (3, 2, 3) from ``position``, each ARROW_LENGTH times
    the weakest eigenvalue's square root over its own, and ``eigenvalues`` ascending."""
    a = np.asarray(observations["A"], dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 6 or len(a) < 6:
        raise Lf3pmError("the least observable directions need 6-DoF observations with at least 6 rows")
    h = a.T @ a
    schur = h[:3, :3] - h[:3, 3:] @ np.linalg.pinv(h[3:, 3:]) @ h[3:, :3]
    values, vectors = np.linalg.eigh(schur)
    values = np.maximum(values, 1e-12)
    lengths = ARROW_LENGTH * np.sqrt(values[0] / values)
    p = np.asarray(position, dtype=np.float32)
    arrows = np.stack(
        [np.stack([p, p + (length * vectors[:, k]).astype(np.float32)]) for k, length in enumerate(lengths)]
    )
    return {"arrows": arrows, "eigenvalues": values, "directions": vectors.T}
