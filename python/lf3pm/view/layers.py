"""What the viewer draws, as plain arrays computed from lf3pm's public objects (a Map, a
Solm, a trajectory's samples, a flight, a replay's JSON, an Evaluation, a recorded run's
scans and their audit): the tests check them without a browser, and the page only hands
them to viser."""

from __future__ import annotations

import html
import math
import numbers

import numpy as np

from lf3pm.calibration import predict
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Space
from lf3pm.prediction import predicted_error_along, solm_fit
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
#: An r3 or r3yaw slice's cells are drawn as up to SLICE_SUBDIVISION² small squares each
#: (squares face the camera: a cell-wide one seen from the side would stand like a wall),
#: MAX_SLICE_POINTS at most in all.
SLICE_SUBDIVISION, MAX_SLICE_POINTS = 4, 500_000
#: Pixels (width, height) of the colour bar, and the values it labels.
COLORBAR_PIXELS = (360, 90)
COLORBAR_TICKS = 4
#: Length (m) of the arrow of the least observable direction at a clicked cell.
ARROW_LENGTH = 2.0
#: What a recorded run's audited scans can be coloured by: {choice: (the audit record's
#: field, what the colour bar says of it)}.
RUN_QUANTITIES = {
    "real error": ("error_m", "real registration error against the reference (m, log scale)"),
    "predicted localization error": ("predicted_error_m", "predicted localization error (m, log scale)"),
    "tracking error": ("tracking_error_m", "map localization tracking error along the run (m, log scale)"),
    "q_n of the real scan": ("real_q_n", "q_n of the real scan (no unit, log scale; larger: worse)"),
}
#: The colour map of the audited scans: the replays' errors' (plasma), not the SOLM's.
RUN_COLORMAP = "plasma"
#: A flight's tube: its radius (m), the vertices of each ring and the metres between rings.
TUBE_RADIUS, TUBE_SIDES, TUBE_STEP_M = 0.08, 12, 0.1
#: Metres along a flight between two of the body's frames drawn on its tube.
FRAME_EVERY_M = 1.0


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


def solm_values(solm: Solm, channel: str, layer: int | None = None, *, yaw_bin: int | None = None) -> np.ndarray:
    """One (ny, nx) layer of ``channel`` (CHANNELS): an R² SOLM as stored; SE(2) at yaw bin
    ``layer``, or its minimum over yaw when ``layer`` is None (the best heading at each
    cell: what an omni robot that may turn can have); R3 at height level ``layer`` (0 when
    None); R3 x yaw at height level ``layer`` (0 when None), its minimum over yaw
    (Solm.over_yaw) or, given ``yaw_bin``, that bin. ``predicted_error`` is the
    localization error predicted from q_n by the SOLM's fit (lf3pm.prediction.solm_fit: the
    one it was built with, else the packaged one)."""
    if channel not in CHANNELS:
        raise Lf3pmError(f"unknown channel {channel!r}; the viewer shows {', '.join(CHANNELS)}")
    source = "q_n" if channel == "predicted_error" else channel
    g = solm.grid_spec
    if g.space is Space.R3YAW:
        level = int(layer or 0)
        if yaw_bin is None:
            data = solm.over_yaw(source)[0][level].astype(np.float64)
        else:
            data = solm.channel(source)[level * g.yaw_bins + int(yaw_bin)].astype(np.float64)
        return predicted_error(data, solm_fit(solm)) if channel == "predicted_error" else data
    data = solm.channel(source).astype(np.float64)
    if data.ndim == 3:
        if layer is None and g.space is Space.SE2:
            with np.errstate(all="ignore"):
                finite = np.where(np.isfinite(data), data, np.inf)
                data = np.min(finite, axis=0)
                data[~np.isfinite(data)] = np.nan
        else:
            data = data[int(layer or 0)]
    return predicted_error(data, solm_fit(solm)) if channel == "predicted_error" else data


def nearest_level(grid, z) -> int:
    """The index of the height level of ``grid`` (an r3 or r3yaw SOLM's) nearest ``z`` (m,
    the map's frame). Lf3pmError when ``z`` is not a finite number, lies outside the levels'
    cells (half a spacing beyond the lowest and the highest level; one level alone: half
    the cell edge) or the grid has no levels (a ground robot's)."""
    if grid.space.ground:
        raise Lf3pmError(f"a height picks a level of an r3 or r3yaw SOLM; this one is {grid.space} (ground robots)")
    if not (isinstance(z, numbers.Real) and not isinstance(z, bool) and math.isfinite(z)):
        raise Lf3pmError(f"the height must be a finite number (m), got {z!r}")
    levels = np.asarray(grid.z_levels, dtype=np.float64)
    ordered = np.sort(levels)
    below = 0.5 * (ordered[1] - ordered[0]) if len(ordered) > 1 else 0.5 * grid.res
    above = 0.5 * (ordered[-1] - ordered[-2]) if len(ordered) > 1 else 0.5 * grid.res
    if not ordered[0] - below <= z <= ordered[-1] + above:
        raise Lf3pmError(
            f"height {z:g} m is outside the SOLM's {len(levels)} level(s), {ordered[0]:.2f} to {ordered[-1]:.2f} m: "
            f"choose one from {ordered[0] - below:.2f} to {ordered[-1] + above:.2f} m"
        )
    return int(np.argmin(np.abs(levels - z)))


def predicted_error(q_n: np.ndarray, fit: dict | None) -> np.ndarray:
    """The localization error (m) ``fit`` predicts at each q_n; NaN where q_n is unknown,
    degenerate or outside the fit's range. Lf3pmError when there is no fit."""
    if fit is None:
        raise Lf3pmError("no localization-error fit: the predicted error is not available")
    centre = np.vectorize(lambda q: (predict(fit, q) or (np.nan,))[0], otypes=[float])
    return centre(np.asarray(q_n, dtype=np.float64))


def solm_layer(solm: Solm, channel: str, layer: int | None = None, *, yaw_bin: int | None = None) -> dict:
    """The SOLM as coloured squares (``layer``, ``yaw_bin``: :func:`solm_values`), over the
    ground or, for r3 and r3yaw, at the level's height: ``centres`` (K, 3) float32 just above
    each evaluated cell's ground or at the level, ``colors`` (K, 3) uint8, ``values`` (K,),
    the colour range ``lo``, ``hi`` (the 2nd and 98th percentiles) and the cell edge
    ``res``."""
    values = solm_values(solm, channel, layer, yaw_bin=yaw_bin)
    g = solm.grid_spec
    ys, xs = np.meshgrid(g.ys(), g.xs(), indexing="ij")
    if not g.space.ground:  # its levels are heights in the map's frame
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


def slice_points(layer: dict) -> tuple[np.ndarray, np.ndarray, float]:
    """A level's squares (:func:`solm_layer`'s ``layer``) as k x k points a cell (k up to
    SLICE_SUBDIVISION, fewer where more than MAX_SLICE_POINTS would be drawn), so that the
    slice lies flat seen from any side: (points (K k², 3) float32, their colours, the
    points' edge res / k)."""
    cells = max(len(layer["centres"]), 1)
    k = max(1, min(SLICE_SUBDIVISION, math.isqrt(MAX_SLICE_POINTS // cells)))
    edge = layer["res"] / k
    offsets = (np.arange(k) + 0.5) * edge - 0.5 * layer["res"]
    dx, dy = np.meshgrid(offsets, offsets)
    shift = np.c_[dx.ravel(), dy.ravel(), np.zeros(k * k)].astype(np.float32)
    points = (layer["centres"][:, None] + shift[None]).reshape(-1, 3)
    return points, np.repeat(layer["colors"], k * k, axis=0), float(edge)


def colorbar_image(
    lo: float, hi: float, label: str, pixels: tuple = COLORBAR_PIXELS, *, name: str = "viridis"
) -> np.ndarray:
    """An RGB image (rows, columns, 3) of the log colour bar from ``lo`` to ``hi`` with its
    label and COLORBAR_TICKS values from end to end, ``pixels`` (width, height) large, of
    matplotlib's colour map ``name``. The end values are aligned inwards, so that every
    label lies inside the image."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from matplotlib.ticker import NullLocator

    fig = plt.figure(figsize=(pixels[0] / 100, pixels[1] / 100), dpi=100)
    ax = fig.add_axes((0.04, 0.42, 0.92, 0.25))
    bar = fig.colorbar(plt.cm.ScalarMappable(norm=LogNorm(lo, hi), cmap=name), cax=ax, orientation="horizontal")
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


# -- flights ---------------------------------------------------------------------------


def flight_samples(flight, quadrotor=None, rate: float | None = None) -> dict:
    """A planned flight (lf3pm.planner.flight_plan's FlightPlan or FlightTrajectory) as the
    viewer draws it, the columns of its CSV: t, x, y, z, yaw (n,) at ``rate`` Hz (default
    its CSV's, lf3pm.trajectory.trajectory.CSV_RATE) and the
    body's attitude ``wxyz`` (n, 4; body to world) from the flatness map
    (lf3pm.flight.Quadrotor.attitudes of ``quadrotor``, default Quadrotor())."""
    from scipy.spatial.transform import Rotation

    from lf3pm.flight import Quadrotor
    from lf3pm.planner.flight_plan import FlightPlan, FlightTrajectory
    from lf3pm.trajectory.trajectory import CSV_RATE

    trajectory = flight.trajectory if isinstance(flight, FlightPlan) else flight
    if not isinstance(trajectory, FlightTrajectory):
        raise Lf3pmError(f"a flight is a FlightPlan, a FlightTrajectory or a CSV's path, got {type(flight).__name__}")
    s = trajectory.sample(CSV_RATE if rate is None else rate)
    quad = quadrotor if quadrotor is not None else Quadrotor()
    attitudes = quad.attitudes(s["velocity"], s["acceleration"], s["jerk"], s["yaw"], s["yaw_rate"])
    xyzw = Rotation.from_matrix(attitudes.rotation).as_quat()
    x, y, z = s["position"].T
    return {"t": s["t"], "x": x, "y": y, "z": z, "yaw": s["yaw"], "wxyz": np.c_[xyzw[:, 3], xyzw[:, :3]]}


def flight_positions(samples: dict) -> np.ndarray:
    """(n, 3) float64 positions of a flight's samples."""
    return np.c_[samples["x"], samples["y"], samples["z"]]


def _along(points: np.ndarray) -> np.ndarray:
    """Metres along the polyline ``points`` (n, 3) at each point."""
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])


def tube(points, radius: float = TUBE_RADIUS, sides: int = TUBE_SIDES, step: float = TUBE_STEP_M) -> tuple:
    """A tube of ``radius`` along the polyline ``points`` (n, 3) as a triangle mesh:
    ``vertices`` (k sides, 3) float32, a ring of ``sides`` every ``step`` metres along it
    (k rings, both ends included), and ``faces`` (2 (k - 1) sides, 3) uint32, wound
    outwards. Each ring is carried from the last by parallel transport, so that the tube
    does not twist where the path turns. Empty arrays when the polyline is shorter than
    ``step`` (a hover)."""
    p = np.asarray(points, dtype=np.float64)
    along = _along(p)
    if along[-1] < step:
        return np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32)
    at = np.linspace(0.0, along[-1], math.ceil(along[-1] / step) + 1)
    centres = np.column_stack([np.interp(at, along, p[:, d]) for d in range(3)])
    tangents = np.gradient(centres, axis=0)
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    normals = np.empty_like(centres)
    first = np.eye(3)[np.argmin(np.abs(tangents[0]))]  # the axis least along the path
    normals[0] = np.cross(tangents[0], first)
    normals[0] /= np.linalg.norm(normals[0])
    for k in range(1, len(centres)):
        n = normals[k - 1] - (normals[k - 1] @ tangents[k]) * tangents[k]
        normals[k] = n / np.linalg.norm(n)
    binormals = np.cross(tangents, normals)
    angle = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    rings = centres[:, None] + radius * (
        np.cos(angle)[None, :, None] * normals[:, None] + np.sin(angle)[None, :, None] * binormals[:, None]
    )
    i, j = np.meshgrid(np.arange(len(centres) - 1), np.arange(sides), indexing="ij")
    a, b = i * sides + j, i * sides + (j + 1) % sides
    c, d = a + sides, b + sides
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([b, d, c], -1).reshape(-1, 3)])
    return rings.reshape(-1, 3).astype(np.float32), faces.astype(np.uint32)


def frame_samples(samples: dict, every_m: float = FRAME_EVERY_M) -> np.ndarray:
    """The indices of a flight's samples at which its body's axes are drawn: the first
    sample, the first to reach each further ``every_m`` metres along the path, and the
    last."""
    along = _along(flight_positions(samples))
    marks = np.arange(0.0, along[-1], every_m)
    return np.unique(np.r_[0, np.searchsorted(along, marks), len(along) - 1])


def tilts(wxyz: np.ndarray) -> np.ndarray:
    """The angle (rad) between the body's z axis (the thrust) and the vertical at each
    attitude ``wxyz`` (n, 4, unit quaternions body to world)."""
    q = np.asarray(wxyz, dtype=np.float64)
    return np.arccos(np.clip(1.0 - 2.0 * (q[:, 1] ** 2 + q[:, 2] ** 2), -1.0, 1.0))


def flight_summary(samples: dict) -> dict:
    """A flight's ``length_m`` (along its path), ``duration_s``, ``top_speed_mps`` (from its
    positions) and ``largest_tilt_deg`` (from its attitudes)."""
    p = flight_positions(samples)
    step = np.linalg.norm(np.diff(p, axis=0), axis=1)
    return {
        "length_m": float(step.sum()),
        "duration_s": float(samples["t"][-1] - samples["t"][0]),
        "top_speed_mps": float(np.max(step / np.diff(samples["t"]))),
        "largest_tilt_deg": float(np.degrees(tilts(samples["wxyz"]).max())),
    }


def flight_predicted_error(solm: Solm, samples: dict, fit: dict | None) -> tuple[float | None, str | None]:
    """(error, withheld): lf3pm.prediction.predicted_error_along along a flight at its own
    heights and yaws (``samples`` with x, y, z and yaw); (None, None) without a fit."""
    return (None, None) if fit is None else predicted_error_along(solm, samples, fit)


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


# -- a recorded run and its audit ------------------------------------------------------


def scan_markers(records: list, quantity: str) -> dict:
    """The audited scans as markers coloured by ``quantity`` (RUN_QUANTITIES): ``positions``
    (N, 3) float32 of the LiDAR at each scan's reference pose, ``values`` (N,) the field
    (NaN: not computed), ``colors`` (N, 3) uint8 on RUN_COLORMAP's log scale from ``lo``
    to ``hi`` (the smallest and largest positive value; 1 to 2 when none is known), grey
    where the value is missing (or not positive: the scale is logarithmic), and ``known``:
    how many are coloured. ``records``: RunInputs'."""
    if quantity not in RUN_QUANTITIES:
        raise Lf3pmError(f"unknown quantity {quantity!r}; the scans are coloured by {', '.join(RUN_QUANTITIES)}")
    key = RUN_QUANTITIES[quantity][0]
    values = np.array([r[key] for r in records], dtype=np.float64)
    known = values[np.isfinite(values) & (values > 0)]
    lo, hi = (float(known.min()), float(known.max())) if known.size else (1.0, 2.0)
    hi = max(hi, lo * 1.0001)  # one value alone still spans a colour bar
    return {
        "positions": np.array([r["pose"][:3, 3] for r in records], dtype=np.float32).reshape(-1, 3),
        "values": values,
        "colors": colormap(values, lo, hi, name=RUN_COLORMAP),
        "lo": lo,
        "hi": hi,
        "known": int(known.size),
    }


def first_known_quantity(records: list) -> str:
    """The first of RUN_QUANTITIES that some record has (an audit without registrations
    has no real error): the colour the page opens with."""
    for quantity, (key, _) in RUN_QUANTITIES.items():
        if any(math.isfinite(r[key]) for r in records):
            return quantity
    return next(iter(RUN_QUANTITIES))


def nearest_scan(positions: np.ndarray, origin, direction) -> int | None:
    """The marker (row of ``positions``, N x 3) nearest a click's ray from ``origin`` along
    ``direction``, among those in front of it; None when none is."""
    u = np.asarray(direction, dtype=np.float64)
    u = u / np.linalg.norm(u)
    d = np.asarray(positions, dtype=np.float64) - np.asarray(origin, dtype=np.float64)
    along = d @ u
    off = np.linalg.norm(d - along[:, None] * u, axis=1)
    off[along <= 0] = np.inf
    return int(np.argmin(off)) if np.isfinite(off).any() else None


def world_points(points: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """A scan's ``points`` (N x 3, the LiDAR frame) in the world, float64: ``pose``
    (world-from-LiDAR, 4 x 4) applied to each."""
    pose = np.asarray(pose, dtype=np.float64)
    return np.asarray(points, dtype=np.float64) @ pose[:3, :3].T + pose[:3, 3]


def scan_record_text(record: dict) -> str:
    """The panel's Markdown for an audited scan (a record of RunInputs): its index, name
    and stamp, its pose, the real, tracking and predicted localization errors, q_n of the
    real and the simulated scan and their ratio; what was not computed says so (and why,
    where the audit says)."""
    x, y, z = record["pose"][:3, 3]
    yaw = math.degrees(math.atan2(record["pose"][1, 0], record["pose"][0, 0]))
    real = (
        f"real error {_cm(record['error_m'])} (largest {_cm(record['error_max_m'])}, spread {_cm(record['spread_m'])})"
        if math.isfinite(record["error_m"])
        else f"real error not computed{_why(record['registration_error'] or 'no registration in this audit')}"
    )
    predicted = (
        f"predicted localization error {_cm(record['predicted_error_m'])} "
        f"({_cm(record['predicted_error_lo_m'])} to {_cm(record['predicted_error_hi_m'])})"
        if math.isfinite(record["predicted_error_m"])
        else f"predicted localization error withheld{_why(record['predicted_error_withheld'] or record['sim_error'])}"
    )
    tracking = (
        f"tracking error {_cm(record['tracking_error_m'])}"
        if math.isfinite(record["tracking_error_m"])
        else "tracking error not computed (no tracking along the run in this audit)"
    )
    return "\n".join(
        [
            f"**Scan {record['index']}** `{html.escape(record['name'])}`, stamp {record['stamp']:.3f} s",
            f"- pose ({x:.2f}, {y:.2f}, {z:.2f}) m, yaw {yaw:.0f}°",
            f"- {real}",
            f"- {tracking}",
            f"- {predicted}",
            f"- q_n real {_g(record['real_q_n'])}, simulated {_g(record['sim_q_n'])}, "
            f"simulated / real {_g(record['q_n_ratio'])}" + _why(record["sim_error"]),
        ]
    )


def run_scan_text(scan) -> str:
    """The panel's Markdown for a scan of a run shown without an audit (a
    lf3pm.runs.Scan): its index, name, stamp, points and pose."""
    x, y, z = scan.pose[:3, 3]
    return "\n".join(
        [
            f"**Scan {scan.index}** `{html.escape(scan.name)}`, stamp {scan.stamp:.3f} s, {len(scan.points):,} points",
            f"- pose ({x:.2f}, {y:.2f}, {z:.2f}) m (no audit given: no errors or predictions)",
        ]
    )


def _cm(metres: float) -> str:
    return f"{metres * 100:.1f} cm" if math.isfinite(metres) else "not computed"


def _g(value: float) -> str:
    return f"{value:.4g}" if math.isfinite(value) else "not computed"


def _why(reason: str | None) -> str:
    return f" ({html.escape(reason)})" if reason else ""
