"""Evaluate one pose: simulate the LiDAR scan on the map, build FAST-LIO
point-to-plane observations and compute the LF-3PM metric and baselines."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from lf3pm import _core
from lf3pm.calibration import calibration_applies, localization_fit, packaged_calibration, predict, withheld_reason
from lf3pm.config import DEFAULTS, Config, MetricConfig, configured, scan_params
from lf3pm.errors import Lf3pmError
from lf3pm.map import Map, as_map
from lf3pm.pose import pose_matrix
from lf3pm.sensors import Sensor, as_sensor

#: Metric fields, in the order tables print them.
METRIC_FIELDS = (
    "sigma1",
    "xi",
    "q_min",
    "q_n",
    "q_max",
    "zhang",
    "condition_number",
    "cov_trace",
    "step_norm",
    "residual_norm",
    "scaled_cov_trace",
)


@dataclass(frozen=True)
class Evaluation:
    """The metric at one pose, with what produced it.

    ``q = inf`` and ``degenerate = True`` when the observations cannot fix the
    pose (fewer than n + 1 rows or a rank-deficient A). ``m`` is the number of
    observation rows: q scales with 1/sqrt(m), so compare q at equal sensor and
    downsampling settings only. ``least_observable``: the unit eigenvector of AᵀA's
    smallest eigenvalue (n entries: translation, then rotation, in the world frame;
    its largest entry positive), the direction the observations fix worst.
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
    least_observable: list
    rays: int
    hits: int
    predicted_mde: float | None
    predicted_mde_interval: list | None
    predicted_localization_error_m: float | None
    predicted_localization_error_interval_m: list | None
    predicted_mde_withheld: str | None
    predicted_localization_error_withheld: str | None
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


def eval_params(
    min_range: float,
    max_range: float,
    *,
    dof: int = DEFAULTS.metric.dof,
    association: str = DEFAULTS.metric.association,
    w1: float = DEFAULTS.metric.w1,
    ray_weight: float = 1.0,
    **scan,
) -> _core.EvalParams:
    """The core's EvalParams (values as given: lf3pm.config validates what users set);
    ``scan``: :func:`lf3pm.scan.scan_simulator.scan_params`'s keywords."""
    return MetricConfig.model_construct(dof=dof, association=association, w1=w1).core(
        scan_params(min_range, max_range, **scan), ray_weight
    )


def evaluate(
    map: Map | str,
    pose,
    sensor: Sensor | str = DEFAULTS.sensor,
    config: Config | None = None,
    *,
    observations: bool = False,
    **parameters,
) -> Evaluation:
    """Simulates ``sensor`` at ``pose`` on ``map`` and returns the metric, with the scan
    and metric sections of ``config`` (lf3pm.config.Config; default: the defaults),
    whose fields may also be given by name (``seed=3, dof=3``; validated there).

    pose: (x, y, z, yaw), (x, y, z, qw, qx, qy, qz) or a 4 x 4 sensor-to-world
    matrix. noise: Gaussian range noise sigma in metres (default: the sensor's),
    drawn from ``seed``. dof: 6 (SE(3)) or 3 (x, y, yaw). w1: the metric's weight
    (w2 = 1 - w1). scan_voxel: keep the first hit per voxel of this edge, like
    FAST-LIO's scan downsampling (0 = off). association: "knn" (default) is
    FAST-LIO's: the k nearest map points of every hit and their plane; "surfel"
    reuses the precomputed plane of the map point the ray hit (faster, but its
    residuals are smaller: see docs/metric.md). With observations=True the result
    carries A (m x dof), b (m) and the hit points.
    predicted_mde (with a 10-90 % interval) comes from the packaged fit on q_n
    (see lf3pm.calibration) when the query matches the conditions it was fitted
    under (its sensor, default noise, dof 6, k-NN association, no scan
    downsampling), else None; likewise predicted_localization_error_m (with a
    10-90 % interval, m): the APE of map localization expected along a trajectory
    through poses like this one, fitted on the benefit study's plans (its
    sensors; None at a degenerate pose), or the prediction section's
    ``calibration`` (a fit on your own run: `lf3pm audit --calibrate`). Either is None too outside the range of
    the predictor its fit saw; ``predicted_*_withheld`` says why a prediction is
    None, in one line (docs/validation.md), and is None where it is given.
    A pose outside the map's x-y extent or within the scan section's ``clearance`` m of
    a map point raises PoseError.
    """
    config = configured(config, ("scan", "metric"), "evaluate", **parameters)
    scan, metric = config.scan, config.metric
    map, sensor = as_map(map), as_sensor(sensor)
    matrix = pose_matrix(pose)
    map.check_pose(matrix, scan.clearance)
    params = metric.core(scan.core(sensor))
    obs = None
    if observations:
        result, obs = _core.evaluate_with_observations(map.index, matrix, sensor.directions, params)
    else:
        result = _core.evaluate(map.index, matrix, sensor.directions, params)
    return _evaluation(map, matrix, sensor.name, scan.noise is None, scan.noise_for(sensor), config, result, obs)


def evaluate_points(
    map: Map | str,
    pose,
    points,
    config: Config | None = None,
    *,
    sensor_name: str = "recorded",
    observations: bool = False,
    **parameters,
) -> Evaluation:
    """The metric of a recorded scan: ``points`` (N x 3, the sensor frame, as
    lf3pm.runs.Scan.points) seen from ``pose`` on ``map``, each point an observation
    associated with the map as FAST-LIO does, through the code :func:`evaluate` runs on
    a simulated scan's hits (the core's evaluate_scan: scan downsampling by the scan
    section's ``scan_voxel``, k-NN association, Gram, metric), with the scan and metric
    sections of ``config`` (fields also by name). Nothing is simulated and no range
    limit applied; ``rays`` is the number of points given, ``hits`` those kept.

    ``sensor_name`` only labels the result, and the predictions are made for it as
    :func:`evaluate` makes them (the default "recorded" matches no fit, so they are
    withheld, saying why); params' ``noise`` is None (the scan's own). The pose is not
    checked against the map (a recorded pose is where the sensor was)."""
    config = configured(config, ("scan", "metric"), "evaluate", **parameters)
    if config.metric.association != "knn":
        raise Lf3pmError("a recorded scan's points are associated by k-NN (metric.association knn)")
    map = as_map(map)
    matrix = pose_matrix(pose)
    cloud = np.asarray(points, dtype=np.float64)
    if cloud.ndim != 2 or cloud.shape[1] != 3 or not np.isfinite(cloud).all():
        raise Lf3pmError(f"a scan's points must be a finite N x 3 array, got shape {cloud.shape}")
    # Only the scan section's scan_voxel and threads apply: nothing is cast.
    recorded = scan_params(0.0, math.inf, scan_voxel=config.scan.scan_voxel, threads=config.scan.threads)
    params = config.metric.core(recorded)
    result, obs = _core.evaluate_points(map.index, matrix, np.ascontiguousarray(cloud), params, observations)
    return _evaluation(map, matrix, sensor_name, True, None, config, result, obs)


def _evaluation(
    map: Map,
    matrix,
    sensor_name: str,
    noise_is_default: bool,
    noise: float | None,
    config: Config,
    result,
    obs: dict | None,
) -> Evaluation:
    """The Evaluation of a core result (simulated or recorded scan): the metric, the
    predictions for ``sensor_name`` and what produced them."""
    scan, metric = config.scan, config.metric
    values = result.metric.as_dict()
    conditions = {
        "sensor": sensor_name,
        "dof": metric.dof,
        "association": metric.association,
        "scan_voxel": scan.scan_voxel,
        "noise_is_default": noise_is_default,
        "w1": metric.w1,
    }
    q_n = values["q_n"]
    calibration = packaged_calibration()
    prediction = None
    if calibration is not None and calibration_applies(calibration, **conditions):
        prediction = predict(calibration, q_n)
    fit = localization_fit(config.prediction.calibration)
    error = predict(fit, q_n) if fit is not None and calibration_applies(fit, **conditions) else None
    recorded = {
        "seed": scan.seed,
        "noise": noise,
        "dof": metric.dof,
        "w1": metric.w1,
        "scan_voxel": scan.scan_voxel,
        "association": metric.association,
        "map_sha256": map.sha256,
        **map.association_params,
    }
    return Evaluation(
        **{k: values[k] for k in METRIC_FIELDS},
        m=values["m"],
        n=values["n"],
        degenerate=values["degenerate"],
        least_observable=values["least_observable"],
        rays=result.rays,
        hits=result.hits,
        predicted_mde=prediction[0] if prediction else None,
        predicted_mde_interval=list(prediction[1:]) if prediction else None,
        predicted_localization_error_m=error[0] if error else None,
        predicted_localization_error_interval_m=list(error[1:]) if error else None,
        predicted_mde_withheld=withheld_reason(calibration, q_n, **conditions),
        predicted_localization_error_withheld=withheld_reason(fit, q_n, **conditions),
        pose=matrix.tolist(),
        sensor=sensor_name,
        params=recorded,
        observations=obs,
    )
