"""A sensor fitted from a recorded run's scans (`lf3pm sensors fit`, issue 42 item 4): the
ray pattern, range limits and range noise of the LiDAR that recorded them, written as the
YAML a preset's place takes (docs/sensors.md), and how its simulated scans compare with the
real ones at the reference poses.

- **Spinning** (rings that fill 360 degrees of azimuth): the beams' elevations are the
  peaks of the elevation histogram of each scan's points seen from the sensor's origin;
  peaks closer than :data:`RING_SEPARATION_SHARE` of the histogram's dominant period are
  one beam (beams in pairs of alternating spacing, as the hall run's, have a period of two
  spacings). Scans blurred by motion show extra peaks, so the ring count is the most common
  one over the scans and each beam's elevation the median over the scans that have it. The
  columns per turn come from the azimuth step between neighbouring returns of one beam.
- **Pattern** (anything else: a Livox's non-repetitive pattern): the directions of the
  returns of consecutive scans, in the order recorded, accumulated to
  :data:`PATTERN_SECONDS`; its point rate the returns per second. Rays that returned
  nothing in the run are not in it.
- **Ranges**: the nearest and farthest return over the scans used; the farthest is what
  the site allowed, a lower bound of the sensor's reach.
- **Range noise** (with a map and reference poses): each return's distance to its FAST-LIO
  plane in the map (the metric's association), along its ray (distance / |cos incidence|,
  incidence below 60 degrees), as a robust sigma (1.4826 x MAD). The map's own noise and
  the reference poses' error add to it: an upper bound, unless the map holds the scan,
  which makes it too small (docs/real.md measures the bias).
- **Returns** (with a map): which rays return, as a :class:`~lf3pm.sensors.ReturnModel`:
  the fitted sensor's noise-free simulated scan at each reference pose, and for each ray
  it returns on, whether the real scan returned on that ray (a real return belongs to its
  nearest ray), tabulated over the hit's range (:data:`RANGE_EDGES_M`) and |cos incidence|
  (:data:`COS_EDGES`). Fitted on the scans not compared, so the comparison is held out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from lf3pm.atomic import atomic_write
from lf3pm.audit.scan_audit import finite_ratio
from lf3pm.config import DEFAULTS
from lf3pm.errors import Lf3pmError
from lf3pm.metric import evaluate, evaluate_points
from lf3pm.runs import Run
from lf3pm.scan.scan_simulator import simulate_scan
from lf3pm.sensors import ReturnModel, Sensor, directions_from_angles, spinning_directions

#: Elevation histogram bin (deg) and its Gaussian smoothing (bins).
ELEVATION_BIN_DEG, ELEVATION_SMOOTHING_BINS = 0.02, 2
#: Peaks of the elevation histogram closer than this share of its dominant period are one
#: beam. Measured on the hall run (every 8th of 88 scans): the period is 2.84 degrees (beams
#: in pairs 1.1 and 1.7 degrees apart); 0.3 of it (0.85) gives 64 peaks on 5 of 11 scans and
#: 65-66 on the rest, while 0.5 degrees gives 75-76 and 0.3 degrees 77-115. On uniform
#: layouts (VLP-16, HDL-32E, OS1-64) the period is one spacing and 0.3 of it separates them.
RING_SEPARATION_SHARE = 0.3
#: A peak lower than this share of the median non-empty histogram bin is not a beam.
RING_PROMINENCE = 0.5
#: A scan is spinning when its beams' returns fill this share of 1-degree azimuth bins.
SPINNING_COVERAGE = 0.9
#: Steps between one beam's returns that must be whole multiples of an azimuth step for it
#: to be the sensor's (see azimuth_count).
STEP_MULTIPLE_SHARE = 0.8
#: The directions of a pattern sensor accumulated over this many seconds of scans.
PATTERN_SECONDS = 1.0
#: Incidence cosines below this leave a return out of the range-noise estimate.
MIN_INCIDENCE_COS = 0.5
#: Scans read by default (evenly over the run), and scans compared with their simulation.
DEFAULT_SCANS, COMPARED_SCANS = 20, 5
#: Bins of the return model: range edges (m; the sensor's own limits close the first and
#: last bin) doubling from 1 m, as the hits per range bin fall with range, and |cos
#: incidence| in fifths.
RANGE_EDGES_M = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0)
COS_EDGES = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0)
#: A bin with fewer simulated hits than this takes its range row's share (or, if the row
#: has fewer too, the share over all hits): 200 hits give a share to within 3.5 points.
MIN_BIN_HITS = 200


@dataclass(frozen=True)
class Comparison:
    """One scan's real returns against the fitted sensor's simulated scan at its reference
    pose: rays that returned in both, in the real scan only, in the simulation only (a
    real return belongs to its nearest ray of the fitted pattern), the range residual
    real - simulated over rays in both (median and robust sigma, m), sim_q_n / real_q_n and
    sim_sigma1 / real_sigma1; ``rays``: the sensor's rays in a scan."""

    index: int
    both: int
    real_only: int
    sim_only: int
    residual_median_m: float
    residual_sigma_m: float
    q_n_ratio: float
    sigma1_ratio: float
    rays: int

    @property
    def real_share(self) -> float:
        """Rays the real scan returned on, over the sensor's rays."""
        return (self.both + self.real_only) / self.rays

    @property
    def sim_share(self) -> float:
        """Rays the simulated scan returned on, over the sensor's rays."""
        return (self.both + self.sim_only) / self.rays

    @property
    def share_both(self) -> float:
        """Rays that returned in both, over rays that returned in either."""
        total = self.both + self.real_only + self.sim_only
        return self.both / total if total else math.nan


@dataclass(frozen=True)
class SensorFit:
    """A fitted sensor: ``kind`` (spinning or pattern), ``yaml`` (the keys written; a
    pattern sensor's ``pattern_file`` is named on writing), ``pattern`` ((N, 2) azimuth,
    elevation in radians, pattern sensors), what it was fitted from (``scans``,
    ``points``, per scan ``ring_counts``), ``noise_returns`` (returns the range noise was
    estimated from; 0 without a map), ``return_scans`` (the scans the return model was
    fitted on; 0: none fitted) and the per-scan :class:`Comparison` s."""

    kind: str
    yaml: dict
    scans: int
    points: int
    pattern: np.ndarray | None = None
    ring_counts: tuple = ()
    noise_returns: int = 0
    return_scans: int = 0
    comparisons: tuple = field(default_factory=tuple)

    def to_dict(self) -> dict:
        """JSON-ready: the YAML keys and how they were found."""
        return {
            "kind": self.kind,
            "yaml": dict(self.yaml),
            "scans": self.scans,
            "points": self.points,
            "pattern_rays": None if self.pattern is None else len(self.pattern),
            "ring_counts": list(self.ring_counts),
            "noise_returns": self.noise_returns,
            "return_scans": self.return_scans,
            "comparisons": [
                {**c.__dict__, "share_both": c.share_both, "real_share": c.real_share, "sim_share": c.sim_share}
                for c in self.comparisons
            ],
        }


def elevations_deg(points: np.ndarray) -> np.ndarray:
    """Each point's elevation (deg) seen from the sensor's origin."""
    return np.degrees(np.arctan2(points[:, 2], np.hypot(points[:, 0], points[:, 1])))


def _histogram(elevation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    from scipy.ndimage import gaussian_filter1d

    edges = np.arange(-90.0, 90.0 + ELEVATION_BIN_DEG, ELEVATION_BIN_DEG)
    counts, _ = np.histogram(elevation, bins=edges)
    return gaussian_filter1d(counts.astype(np.float64), ELEVATION_SMOOTHING_BINS), (edges[:-1] + edges[1:]) / 2


def dominant_period_deg(elevation: np.ndarray) -> float:
    """The lag (deg, 0.2-10) of the highest autocorrelation peak of the elevation histogram:
    a spinning sensor's beam spacing (or the period of its spacing pattern); NaN if none."""
    from scipy.signal import find_peaks

    smoothed, _ = _histogram(elevation)
    x = smoothed - smoothed.mean()
    lags = int(10.0 / ELEVATION_BIN_DEG)
    ac = np.array([np.dot(x[: len(x) - k], x[k:]) for k in range(lags)])
    peaks, _ = find_peaks(ac)
    peaks = peaks[peaks >= int(0.2 / ELEVATION_BIN_DEG)]
    return float(peaks[np.argmax(ac[peaks])] * ELEVATION_BIN_DEG) if len(peaks) else math.nan


def ring_peaks(elevation: np.ndarray, separation_deg: float) -> np.ndarray:
    """The elevations (deg, ascending) of the peaks of one scan's elevation histogram at
    least ``separation_deg`` apart."""
    from scipy.signal import find_peaks

    smoothed, centres = _histogram(elevation)
    floor = RING_PROMINENCE * np.median(smoothed[smoothed > 0]) if np.any(smoothed > 0) else 0.0
    peaks, _ = find_peaks(smoothed, distance=max(1, round(separation_deg / ELEVATION_BIN_DEG)), prominence=floor)
    return centres[peaks]


def fit_rings(elevations: list[np.ndarray]) -> tuple[np.ndarray, tuple]:
    """The beams' elevations (deg, ascending) from scans' point elevations, and each scan's
    ring count: the most common count (the smallest among ties) and, per beam, the median
    elevation over the scans with that count."""
    period = dominant_period_deg(np.concatenate(elevations))
    if not math.isfinite(period):
        raise Lf3pmError("no ring structure in the scans' elevations: not a spinning sensor")
    rings = [ring_peaks(e, RING_SEPARATION_SHARE * period) for e in elevations]
    counts = tuple(len(r) for r in rings)
    values, freq = np.unique(counts, return_counts=True)
    mode = int(values[np.argmax(freq)])
    if mode < 2:
        raise Lf3pmError("fewer than 2 rings found in the scans' elevations: not a spinning sensor")
    return np.median(np.array([r for r in rings if len(r) == mode]), axis=0), counts


def azimuth_count(points: list[np.ndarray], rings_deg: np.ndarray) -> int:
    """Columns per turn: 360 degrees over the azimuth step between neighbouring returns of
    one beam: the median of the steps no larger than 1.5 times their lower quartile, so
    that gaps of missing returns do not count, or the largest of its halves, thirds and
    quarters that :data:`STEP_MULTIPLE_SHARE` of the steps are whole multiples of (to a
    quarter step): a sensor that loses most returns has gaps as its lower quartile."""
    half = np.min(np.diff(rings_deg)) / 2 if len(rings_deg) > 1 else 1.0
    steps = []
    for p in points:
        el = elevations_deg(p)
        ring = np.searchsorted((rings_deg[1:] + rings_deg[:-1]) / 2, el)
        near = np.abs(el - rings_deg[ring]) < half
        az = np.degrees(np.arctan2(p[near, 1], p[near, 0]))
        for r in np.unique(ring[near]):
            a = np.sort(az[ring[near] == r])
            d = np.diff(a)
            steps.append(d[d > 1e-6])
    d = np.concatenate(steps) if steps else np.empty(0)
    if not len(d):
        raise Lf3pmError("no two returns of one beam: cannot find the azimuth step")
    step = float(np.median(d[d <= 1.5 * np.percentile(d, 25)]))
    for fraction in range(1, 5):
        multiple = d / (step / fraction)
        if np.mean(np.abs(multiple - np.round(multiple)) < 0.25) >= STEP_MULTIPLE_SHARE:
            return round(360.0 * fraction / step)
    return round(360.0 / step)


def is_spinning(points: list[np.ndarray]) -> bool:
    """Whether the scans' returns fill :data:`SPINNING_COVERAGE` of 1-degree azimuth bins
    (median over the scans)."""
    shares = []
    for p in points:
        az = np.degrees(np.arctan2(p[:, 1], p[:, 0]))
        shares.append(len(np.unique(np.floor(az).astype(int))) / 360.0)
    return float(np.median(shares)) >= SPINNING_COVERAGE


def range_noise(world, pose: np.ndarray, points: np.ndarray, config) -> np.ndarray:
    """Each return's range error against the map along its ray (m): the point-to-plane
    distance of its FAST-LIO association over |cos incidence|, for incidences below 60
    degrees."""
    obs = evaluate_points(world, pose, points, config, observations=True).observations
    rays = obs["points"][obs["row_hit"]] - pose[:3, 3]
    rays /= np.linalg.norm(rays, axis=1, keepdims=True)
    cos = np.abs(np.einsum("ij,ij->i", obs["A"][:, :3], rays))
    keep = cos >= MIN_INCIDENCE_COS
    return obs["b"][keep] / cos[keep]


def robust_sigma(values: np.ndarray) -> float:
    """1.4826 times the median absolute deviation (NaN when empty)."""
    if not len(values):
        return math.nan
    return float(1.4826 * np.median(np.abs(values - np.median(values))))


def fit_pattern(points: list[np.ndarray], stamps: list[float]) -> tuple[np.ndarray, float, float]:
    """A pattern sensor from consecutive scans: the (azimuth, elevation) of their returns in
    the order recorded, up to :data:`PATTERN_SECONDS` of scans, the returns per second and
    the scan period (s: the median time between scans)."""
    if len(stamps) < 2:
        raise Lf3pmError("a pattern sensor needs at least 2 consecutive scans (their period)")
    period = float(np.median(np.diff(stamps)))
    if not period > 0:
        raise Lf3pmError("the scans' stamps do not increase: no scan period")
    used = points[: max(1, round(PATTERN_SECONDS / period))]
    cloud = np.vstack(used)
    pattern = np.column_stack(
        [np.arctan2(cloud[:, 1], cloud[:, 0]), np.arcsin(cloud[:, 2] / np.linalg.norm(cloud, axis=1))]
    )
    return pattern, len(cloud) / (len(used) * period), period


def _chosen(count: int, wanted: int) -> np.ndarray:
    """``wanted`` indices spread evenly over ``count`` (all when fewer)."""
    return np.unique(np.linspace(0, count - 1, min(wanted, count)).round().astype(int))


def fit_sensor(
    run,
    world=None,
    config=None,
    *,
    scans: int = DEFAULT_SCANS,
    name: str | None = None,
    returns: bool = True,
    progress=None,
):
    """The :class:`SensorFit` of ``run`` (a path or lf3pm.runs.Run; bad scans skipped) from
    ``scans`` scans spread over it; ``world``: a Map (or lf3pm.audit.SelfMap) in the frame of
    the run's reference poses for the range noise, the return model (``returns``) and the
    comparison (None: none of them);
    ``config``: the scan and metric sections for the association (default: the defaults).
    ``progress(done, total)`` after each scan read and compared."""
    config = DEFAULTS if config is None else config
    opened = run if isinstance(run, Run) else Run(run, config.run, skip_bad=True)
    try:
        wanted = set(_chosen(opened.scan_count(), scans).tolist())
        read = [s for s in opened.scans() if s.index in wanted]
        source = str(opened.path)
    finally:
        if opened is not run:
            opened.close()
    if len(read) < 2:
        raise Lf3pmError(f"{source}: {len(read)} usable scans among those read; a fit needs at least 2")
    points = [s.points for s in read]
    ranges = np.concatenate([np.linalg.norm(p, axis=1) for p in points])
    keys = {
        "name": name or "fitted",
        "min_range": math.floor(ranges.min() * 100) / 100 or 0.01,
        "max_range": math.ceil(ranges.max() * 100) / 100,
    }
    if is_spinning(points):
        kind, pattern = "spinning", None
        rings, counts = fit_rings([elevations_deg(p) for p in points])
        keys |= {"elevations_deg": [round(float(e), 3) for e in rings], "azimuth_count": azimuth_count(points, rings)}
        shape = f"{len(rings)} beams over {rings[0]:.2f} to {rings[-1]:.2f} deg, {keys['azimuth_count']} columns"
    else:
        kind, counts = "pattern", ()
        pattern, rate, period = fit_pattern(points, [s.stamp for s in read])
        keys |= {"point_rate": round(rate, 1), "integration_time": round(period, 6)}
        shape = f"a pattern of {len(pattern)} returns, {rate:.0f} returns/s, {period:.3f} s scans"
    posed = [s for s in read if s.pose is not None]
    residuals = []
    if world is not None:
        if not posed:
            raise Lf3pmError(f"{source}: no scan has a reference pose; the range noise needs them (or no --map)")
        for k, s in enumerate(posed):
            residuals.append(range_noise(_map_for(world, s), s.pose, s.points, config))
            if progress:
                progress(k + 1, len(posed))
        sigma = robust_sigma(np.concatenate(residuals))
        keys["range_noise_sigma"] = round(sigma, 4)
    keys["description"] = (
        f"fitted by lf3pm sensors fit from {len(read)} scans of {source}: {shape}; ranges "
        f"{keys['min_range']:g}-{keys['max_range']:g} m as returned there"
        + (
            f"; range noise {keys['range_noise_sigma']:g} m against the map"
            if world is not None
            else "; no map: no range noise"
        )
    )
    fit = SensorFit(kind, keys, len(read), int(sum(len(p) for p in points)), pattern, counts, sum(map(len, residuals)))
    if world is None:
        return fit
    chosen = [posed[i] for i in _chosen(len(posed), COMPARED_SCANS)]
    if returns:
        # Fitted on the scans not compared (on all of them when every scan is compared).
        others = [s for s in posed if all(s is not c for c in chosen)] or posed
        model = fit_returns(fitted_sensor(fit), [(_map_for(world, s), s) for s in others])
        keys = {**fit.yaml, "return_probability": model.to_yaml()}
        fit = SensorFit(**{**fit.__dict__, "yaml": keys, "return_scans": len(others)})
    sensor = fitted_sensor(fit)
    comparisons = tuple(compare(sensor, _map_for(world, s), s, config) for s in chosen)
    return SensorFit(**{**fit.__dict__, "comparisons": comparisons})


def _map_for(world, scan):
    """The map a scan is measured against: the world, or a SelfMap's map around it."""
    return world.around(scan.stamp) if hasattr(world, "around") else world


def fitted_sensor(fit: SensorFit):
    """The lf3pm Sensor of ``fit`` (as its YAML will load)."""
    y = fit.yaml
    if fit.kind == "spinning":
        directions = spinning_directions(np.radians(y["elevations_deg"]), y["azimuth_count"])
    else:
        count = round(y["point_rate"] * y["integration_time"])
        rows = fit.pattern[np.arange(count) % len(fit.pattern)]
        directions = directions_from_angles(rows[:, 0], rows[:, 1])
    return Sensor(
        name=y["name"],
        description=y["description"],
        directions=directions,
        min_range=y["min_range"],
        max_range=y["max_range"],
        range_noise_sigma=y.get("range_noise_sigma", 0.0),
        horizontal_fov=2 * math.pi if fit.kind == "spinning" else float(np.ptp(fit.pattern[:, 0])),
        approximate=False,
        source="fitted from a recorded run",
        returns=ReturnModel(**_renamed(y["return_probability"])) if "return_probability" in y else None,
    )


def _renamed(keys: dict) -> dict:
    """ReturnModel's arguments from the YAML's return_probability mapping."""
    return {"range_edges_m": keys["range_edges_m"], "cos_edges": keys["cos_edges"], "probability": keys["table"]}


def real_rays(sensor, points: np.ndarray) -> dict:
    """The real returns by ray: each return belongs to the nearest of ``sensor``'s rays, and a
    ray keeps the nearest of its returns; {ray: range}."""
    from scipy.spatial import cKDTree

    real_range = np.linalg.norm(points, axis=1)
    nearest = cKDTree(sensor.directions).query(points / real_range[:, None])[1]
    order = np.lexsort((real_range, nearest))
    rays, first = np.unique(nearest[order], return_index=True)
    return dict(zip(rays.tolist(), real_range[order][first].tolist()))


def fit_returns(sensor, scans) -> ReturnModel:
    """The return model of ``sensor`` (without one) from ``scans``, (map, scan) pairs of
    scans with reference poses: over the rays its noise-free simulated scan returns on,
    the share the real scan returned on too, per (range, |cos incidence|) bin."""
    ranges, coses, returned = [], [], []
    for world, scan in scans:
        pose = np.asarray(scan.pose, dtype=np.float64)
        simulated = simulate_scan(world, pose, sensor.directions, sensor.min_range, sensor.max_range)
        real = real_rays(sensor, scan.points)
        rays = sensor.directions[simulated.ray] @ pose[:3, :3].T
        normals = world.index.normals[simulated.surfel]
        ranges.append(np.linalg.norm(simulated.sensor_points, axis=1))
        coses.append(np.abs(np.einsum("ij,ij->i", rays, normals)))
        returned.append(np.isin(simulated.ray, list(real)))
    edges = [e for e in RANGE_EDGES_M if sensor.min_range < e < sensor.max_range]
    range_edges = (sensor.min_range, *edges, sensor.max_range)
    r = np.searchsorted(range_edges[1:-1], np.concatenate(ranges), side="right")
    c = np.searchsorted(COS_EDGES[1:-1], np.concatenate(coses), side="right")
    hit = np.concatenate(returned)
    shape = (len(range_edges) - 1, len(COS_EDGES) - 1)
    hits = np.zeros(shape)
    back = np.zeros(shape)
    np.add.at(hits, (r, c), 1)
    np.add.at(back, (r, c), hit)
    overall = back.sum() / hits.sum() if hits.sum() else 1.0
    row = np.where(hits.sum(1) >= MIN_BIN_HITS, back.sum(1) / np.maximum(hits.sum(1), 1), overall)
    table = np.where(hits >= MIN_BIN_HITS, back / np.maximum(hits, 1), row[:, None])
    return ReturnModel(range_edges, COS_EDGES, np.round(table, 3).tolist())


def compare(sensor, world, scan, config) -> Comparison:
    """The real returns of ``scan`` against ``sensor``'s noise-free simulated scan at the
    scan's reference pose on ``world`` (see :class:`Comparison`; the sensor's returns drawn
    with the scan section's seed)."""
    pose = np.asarray(scan.pose, dtype=np.float64)
    simulated = simulate_scan(
        world,
        pose,
        sensor.directions,
        sensor.min_range,
        sensor.max_range,
        seed=config.scan.seed,
        returns=sensor.returns,
    )
    real_by_ray = real_rays(sensor, scan.points)
    sim_range = np.linalg.norm(simulated.sensor_points, axis=1)
    sim_by_ray = dict(zip(np.asarray(simulated.ray).tolist(), sim_range.tolist()))
    both = sorted(set(real_by_ray) & set(sim_by_ray))
    residual = np.array([real_by_ray[r] - sim_by_ray[r] for r in both])
    real = evaluate_points(world, pose, scan.points, config)
    sim = evaluate(world, pose, sensor, config)
    return Comparison(
        index=scan.index,
        both=len(both),
        real_only=len(real_by_ray) - len(both),
        sim_only=len(sim_by_ray) - len(both),
        residual_median_m=float(np.median(residual)) if len(residual) else math.nan,
        residual_sigma_m=robust_sigma(residual),
        q_n_ratio=finite_ratio(sim.q_n, real.q_n),
        sigma1_ratio=finite_ratio(sim.sigma1, real.sigma1),
        rays=sensor.num_rays,
    )


def write_sensor(fit: SensorFit, path) -> list:
    """Writes ``fit`` as a sensor YAML at ``path`` (a pattern sensor's directions beside it
    as ``<stem>_pattern.npy``), each file atomically; returns the paths written."""
    from pathlib import Path

    import yaml

    path = Path(path)
    keys = dict(fit.yaml)
    written = []
    if fit.kind == "pattern":
        pattern_path = path.with_name(f"{path.stem}_pattern.npy")
        with atomic_write(pattern_path) as fp:
            np.save(fp, fit.pattern)
        keys["pattern_file"] = pattern_path.name
        written.append(pattern_path)
    with atomic_write(path) as fp:
        fp.write(yaml.safe_dump(keys, sort_keys=False).encode())
    return [path, *written]
