"""Evaluate one pose: simulate the LiDAR scan on the map, build FAST-LIO
point-to-plane observations and compute the LF-3PM metric and baselines."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field


from lf3pm import _core
from lf3pm.calibration import calibration_applies, packaged_calibration, predict_mde
from lf3pm.errors import Lf3pmError, finite_number
from lf3pm.map import Map, load_map
from lf3pm.pose import pose_matrix
from lf3pm.sensors import Sensor, get_sensor

#: Metric fields, in the order tables print them.
METRIC_FIELDS = ("sigma1", "xi", "q_min", "q_n", "q_max", "zhang", "condition_number", "cov_trace",
                 "step_norm", "residual_norm", "scaled_cov_trace")


@dataclass(frozen=True)
class Evaluation:
    """The metric at one pose, with what produced it.

    ``q = inf`` and ``degenerate = True`` when the observations cannot fix the
    pose (fewer than n + 1 rows or a rank-deficient A). ``m`` is the number of
    observation rows: q scales with 1/sqrt(m), so compare q at equal sensor and
    downsampling settings only.
    """

    sigma1: float
    xi: float
    q_min: float
    q_n: float
    q_max: float
    zhang: float
    condition_number: float
    cov_trace: float
    step_norm: float
    residual_norm: float
    scaled_cov_trace: float
    m: int
    n: int
    degenerate: bool
    rays: int
    hits: int
    predicted_mde: float | None
    predicted_mde_interval: list | None
    pose: list
    sensor: str
    params: dict
    observations: dict | None = field(default=None, repr=False)

    def to_dict(self) -> dict:
        """JSON-ready dict: infinite values (degenerate poses) become None; no arrays."""
        out = asdict(self)
        out.pop("observations")
        return {k: _json_number(v) for k, v in out.items()}


def _json_number(value):
    return None if isinstance(value, float) and not math.isfinite(value) else value


def evaluate(map: Map | str, pose, sensor: Sensor | str = "vlp16", *, seed: int = 0,
             noise: float | None = None, dof: int = 6, w1: float = 0.5, w2: float = 0.5,
             scan_voxel: float = 0.0, association: str = "knn", threads: int = 0,
             observations: bool = False, clearance: float = 0.1) -> Evaluation:
    """Simulates ``sensor`` at ``pose`` on ``map`` and returns the metric.

    pose: (x, y, z, yaw), (x, y, z, qw, qx, qy, qz) or a 4 x 4 sensor-to-world
    matrix. noise: Gaussian range noise sigma in metres (default: the sensor's),
    drawn from ``seed``. dof: 6 (SE(3)) or 3 (x, y, yaw). scan_voxel: keep the
    first hit per voxel of this edge, like FAST-LIO's scan downsampling (0 =
    off). association: "knn" (default) is FAST-LIO's: the k nearest map points of
    every hit and their plane; "surfel" reuses the precomputed plane of the map
    point the ray hit (faster, but its residuals are smaller: see docs/metric.md). With
    observations=True the result carries A (m x dof), b (m) and the hit points.
    predicted_mde (with a 10-90 % interval) comes from the packaged calibration
    (see lf3pm.calibration) when the query matches the conditions it was fitted
    under (its sensor, default noise, dof 6, k-NN association, no scan
    downsampling), else None.
    A pose outside the map's x-y extent or within ``clearance`` m of a map point
    raises PoseError.
    """
    if not isinstance(map, Map):
        map = load_map(map)
    if not isinstance(sensor, Sensor):
        sensor = get_sensor(sensor)
    matrix = pose_matrix(pose)
    map.check_pose(matrix, clearance)
    if dof not in (3, 6):
        raise Lf3pmError(f"dof must be 3 or 6, got {dof}")
    if association not in ("surfel", "knn"):
        raise Lf3pmError(f"association must be 'surfel' or 'knn', got {association!r}")
    if not (w1 > 0 and w2 > 0 and abs(w1 + w2 - 1.0) < 1e-9):
        raise Lf3pmError(f"metric weights must be positive and sum to 1, got w1={w1}, w2={w2}")
    sigma = finite_number("range noise", sensor.range_noise_sigma if noise is None else noise, low=0.0)
    scan_voxel = finite_number("scan voxel", scan_voxel, low=0.0)
    try:
        raw = _core.evaluate(map.index, matrix, sensor.directions, sensor.min_range,
                             sensor.max_range, noise=sigma, seed=int(seed), scan_voxel=scan_voxel,
                             dof=dof, association=association, w1=w1, w2=w2, threads=threads,
                             observations=observations)
    except ValueError as err:
        raise Lf3pmError(str(err)) from None
    calibration = packaged_calibration()
    prediction = None
    if calibration_applies(calibration, sensor=sensor.name, dof=dof, association=association,
                           scan_voxel=scan_voxel, noise_is_default=noise is None, w1=w1):
        prediction = predict_mde(calibration, raw[calibration["predictor"]])
    obs = None
    if observations:
        obs = {key: raw.pop(key) for key in ("A", "b", "points", "sensor_points", "row_hit")}
    params = {"seed": int(seed), "noise": sigma, "dof": dof, "w1": w1, "w2": w2,
              "scan_voxel": scan_voxel, "association": association, "map_sha256": map.sha256,
              **map.association_params}
    return Evaluation(**{k: raw[k] for k in METRIC_FIELDS}, m=raw["m"], n=raw["n"],
                      degenerate=raw["degenerate"], rays=raw["rays"], hits=raw["hits"],
                      predicted_mde=prediction[0] if prediction else None,
                      predicted_mde_interval=list(prediction[1:]) if prediction else None,
                      pose=matrix.tolist(), sensor=sensor.name, params=params, observations=obs)
