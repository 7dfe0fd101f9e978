"""MDE (paper eq. MDE): the mean over N disturbed starts of the squared norm of
the registration error log(T_gt^-1 T_regi)^v.

The simulated noisy scan at the true pose T_gt is registered against the map by
small_gicp's point-to-plane ICP, started from T_gt disturbed by a random twist
(translation sigma_t per axis, rotation sigma_r per axis, body frame). small_gicp
is a registration independent of lf3pm's own association and metric, so MDE
checks the metric rather than repeating it.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from lf3pm import _core
from lf3pm.config import DEFAULTS, Config, configured, scan_params
from lf3pm.errors import Lf3pmError
from lf3pm.map import Map, as_map
from lf3pm.pose import pose_matrix, se3_exp, se3_log
from lf3pm.scan.scan_simulator import simulate_scan
from lf3pm.sensors import Sensor, as_sensor


class RegistrationTarget:
    """The map prepared once for small_gicp: points with normals and a k-d tree."""

    def __init__(self, map: Map, normal_neighbors: int = 10, threads: int = DEFAULTS.scan.threads):
        import small_gicp

        self.map_sha256 = map.sha256
        self.cloud = small_gicp.PointCloud(np.ascontiguousarray(map.points))
        workers = threads or _default_threads()
        self.tree = small_gicp.KdTree(self.cloud, num_threads=workers)
        small_gicp.estimate_normals(self.cloud, self.tree, num_neighbors=normal_neighbors, num_threads=workers)

    @classmethod
    def for_map(
        cls, map: Map, target: RegistrationTarget | None = None, threads: int = DEFAULTS.scan.threads
    ) -> RegistrationTarget:
        """``target`` checked to be ``map``'s (Lf3pmError if it was prepared from another
        map), or a new one when None."""
        if target is None:
            return cls(map, threads=threads)
        if target.map_sha256 != map.sha256:
            raise Lf3pmError("the registration target was prepared from another map")
        return target

    def align(self, source, start: np.ndarray, max_correspondence_distance: float, max_iterations: int, threads: int):
        """small_gicp point-to-plane ICP of ``source`` (a small_gicp PointCloud, sensor
        frame) to this map from ``start`` (4 x 4): small_gicp's RegistrationResult."""
        import small_gicp

        return small_gicp.align(
            self.cloud,
            source,
            self.tree,
            init_T_target_source=start,
            registration_type="PLANE_ICP",
            max_correspondence_distance=max_correspondence_distance,
            max_iterations=max_iterations,
            num_threads=threads,
        )


def _default_threads() -> int:
    import os

    return os.cpu_count() or 1


@dataclass(frozen=True)
class MdeResult:
    """MDE at one pose, with every trial's error and the parameters used."""

    mde: float  # mean of |log(T_gt^-1 T_regi)|^2 (m^2 and rad^2 mixed, as in the paper)
    trials: int
    errors: list  # per trial |log(...)|^2
    translation_errors: list  # per trial |t error| (m)
    rotation_errors_deg: list  # per trial |rotation error| (deg)
    converged: int  # trials small_gicp reported as converged
    hits: int  # points in the registered scan
    pose: list
    sensor: str
    params: dict = field(default_factory=dict)
    registered: list = field(default_factory=list, repr=False)  # per trial the 4 x 4 registered pose
    converged_trials: list = field(default_factory=list, repr=False)  # per trial small_gicp's converged flag

    def to_dict(self) -> dict:
        """JSON-ready dict, without the registered poses and per-trial flags."""
        out = asdict(self)
        out.pop("registered")
        out.pop("converged_trials")
        return out


def mde(
    map: Map | str,
    pose,
    sensor: Sensor | str = DEFAULTS.sensor,
    config: Config | None = None,
    *,
    target: RegistrationTarget | None = None,
    **parameters,
) -> MdeResult:
    """MDE of point-to-plane registration at ``pose`` (see module docstring), with the
    scan and mde sections of ``config`` (lf3pm.config.Config; default: the defaults),
    whose fields may also be given by name (``trials=5, seed=3``; validated there).

    The scan is simulated with the scan section's range noise (default: the sensor's)
    from its ``seed``; the disturbances (the mde section's sigmas, ``trials`` of them)
    are drawn from an independent stream of the same seed. ``target`` reuses a prepared
    map across calls. A pose within the scan section's ``clearance`` of a map point
    raises PoseError.
    """
    config = configured(config, ("scan", "mde"), "mde", **parameters)
    scan_config = config.scan
    map, sensor = as_map(map), as_sensor(sensor)
    _check_disturbance(map, config.mde.sigma_t)
    truth = pose_matrix(pose)
    map.check_pose(truth, scan_config.clearance)
    target = RegistrationTarget.for_map(map, target, scan_config.threads)
    scan = simulate_scan(
        map,
        truth,
        sensor.directions,
        sensor.min_range,
        sensor.max_range,
        noise=scan_config.noise_for(sensor),
        seed=scan_config.seed,
        scan_voxel=scan_config.scan_voxel,
        threads=scan_config.threads,
        returns=sensor.returns,
    )
    return _registered(map, truth, scan.sensor_points, config, target, sensor.name, scan_config.noise_for(sensor))


def mde_of_points(
    map: Map | str,
    pose,
    points,
    config: Config | None = None,
    *,
    sensor_name: str = "recorded",
    target: RegistrationTarget | None = None,
    **parameters,
) -> MdeResult:
    """MDE of a recorded scan: ``points`` (N x 3, the sensor frame, as lf3pm.runs.Scan.points)
    registered against ``map`` from the disturbed starts around ``pose`` that :func:`mde`
    draws (same seed, same draws), by the same registration. The points are downsampled by
    the scan section's ``scan_voxel`` as a simulated scan's hits are (lf3pm._core.scan_of_points,
    the simulator's own filter); nothing is simulated, and ``pose`` is the reference the
    errors are measured against (not checked against the map). ``sensor_name`` labels the result."""
    config = configured(config, ("scan", "mde"), "mde", **parameters)
    map = as_map(map)
    _check_disturbance(map, config.mde.sigma_t)
    truth = pose_matrix(pose)
    cloud = np.asarray(points, dtype=np.float64)
    if cloud.ndim != 2 or cloud.shape[1] != 3 or not np.isfinite(cloud).all():
        raise Lf3pmError(f"a scan's points must be a finite N x 3 array, got shape {cloud.shape}")
    params = scan_params(0.0, math.inf, scan_voxel=config.scan.scan_voxel, threads=config.scan.threads)
    kept = _core.scan_of_points(truth, np.ascontiguousarray(cloud), params)["sensor_points"]
    target = RegistrationTarget.for_map(map, target, config.scan.threads)
    return _registered(map, truth, kept, config, target, sensor_name, None)


def _check_disturbance(map: Map, sigma_t: float) -> None:
    # A start disturbed by more than the map is across is no registration problem, and
    # small_gicp would grind through it for minutes.
    extent = max(float(np.max(map.bounds[1] - map.bounds[0])), 1.0)
    if sigma_t > extent:
        raise Lf3pmError(
            f"mde.sigma_t {sigma_t:g} m is larger than the map ({extent:.3g} m across): "
            "no registration starts that far off"
        )


def _registered(
    map: Map, truth: np.ndarray, points: np.ndarray, config: Config, target, sensor: str, noise
) -> MdeResult:
    """The registrations of a scan's sensor-frame ``points`` from disturbed starts around
    ``truth`` (what :func:`mde` and :func:`mde_of_points` share)."""
    import small_gicp

    scan_config, disturbance = config.scan, config.mde
    trials, sigma_t, sigma_r_deg = disturbance.trials, disturbance.sigma_t, disturbance.sigma_r
    max_correspondence_distance, max_iterations = disturbance.max_correspondence_distance, disturbance.max_iterations
    seed, threads, scan_voxel = scan_config.seed, scan_config.threads, scan_config.scan_voxel
    if len(points) < 10:
        raise Lf3pmError(f"the scan at this pose has only {len(points)} hits: nothing to register")
    source = small_gicp.PointCloud(np.ascontiguousarray(points))

    # Disturbances from their own stream, so changing `trials` keeps earlier draws.
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0x4D4445]))
    sigmas = np.r_[np.full(3, sigma_t), np.full(3, math.radians(sigma_r_deg))]
    errors, t_err, r_err, converged, finals, flags = [], [], [], 0, [], []
    truth_inv = np.linalg.inv(truth)
    for _ in range(trials):
        start = truth @ se3_exp(rng.normal(size=6) * sigmas)
        result = target.align(source, start, max_correspondence_distance, max_iterations, threads or _default_threads())
        twist = se3_log(truth_inv @ result.T_target_source)
        errors.append(float(twist @ twist))
        t_err.append(float(np.linalg.norm((truth_inv @ result.T_target_source)[:3, 3])))
        r_err.append(float(math.degrees(np.linalg.norm(twist[3:]))))
        converged += bool(result.converged)
        finals.append(np.asarray(result.T_target_source, dtype=np.float64).tolist())
        flags.append(bool(result.converged))
    params = {
        "seed": int(seed),
        "noise": noise,
        "sigma_t": sigma_t,
        "sigma_r_deg": sigma_r_deg,
        "scan_voxel": scan_voxel,
        "max_correspondence_distance": max_correspondence_distance,
        "max_iterations": max_iterations,
        "registration": "small_gicp PLANE_ICP",
        "map_sha256": map.sha256,
    }
    return MdeResult(
        mde=float(np.mean(errors)),
        trials=trials,
        errors=errors,
        translation_errors=t_err,
        rotation_errors_deg=r_err,
        converged=converged,
        hits=len(points),
        pose=truth.tolist(),
        sensor=sensor,
        params=params,
        registered=finals,
        converged_trials=flags,
    )
