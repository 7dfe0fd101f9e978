"""MDE along a trajectory and its sum S, the paper's figure of merit for a
planned path: S = sum_i MDE(pose_i) over poses sampled at a constant time
interval (see :func:`lf3pm.trajectory.sampling.sample_trajectory`).

Pose i uses the seed :func:`pose_seed` (seed, i) for both its scan noise and its
disturbances, so each per-pose MDE equals ``mde(map, pose_i, seed=pose_seed(seed, i))``
whatever the order of evaluation or the thread count.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from lf3pm.config import DEFAULTS, Config, configured
from lf3pm.errors import Lf3pmError
from lf3pm.map import Map, as_map
from lf3pm.sensors import Sensor, as_sensor
from lf3pm.validation.mde import RegistrationTarget, mde


def pose_seed(seed: int, index: int) -> int:
    """The seed of pose ``index`` of a trajectory evaluated with ``seed`` (a 32-bit
    integer drawn from SeedSequence([seed, index]): base seeds do not overlap)."""
    return int(np.random.SeedSequence([int(seed), int(index)]).generate_state(1)[0])


@dataclass(frozen=True)
class TrajectoryMde:
    """Per-pose MDE along a trajectory and S, their sum.

    ``mde[i]`` is NaN where pose i was refused (inside an obstacle, outside the
    map, a scan with too few hits); ``refused`` lists (i, reason) for those.
    ``s`` sums the evaluated poses only, so compare S between trajectories only
    when neither has refused poses.
    """

    s: float
    mde: list  # per pose, NaN where refused
    seeds: list  # per pose, as passed to mde()
    refused: list  # (index, one-line reason)
    translation_error_median: list  # per pose, m (NaN where refused)
    converged: list  # per pose, trials small_gicp reported converged (0 where refused)
    hits: list  # per pose, scan points (0 where refused)
    poses: list  # (N, 4) x y z yaw
    sensor: str
    params: dict = field(default_factory=dict)

    @property
    def evaluated(self) -> int:
        return len(self.mde) - len(self.refused)

    def to_dict(self) -> dict:
        """JSON-ready dict (NaN becomes None)."""

        def clean(value):
            if isinstance(value, float) and not math.isfinite(value):
                return None
            if isinstance(value, (list, tuple)):
                return [clean(v) for v in value]
            return value

        return {k: clean(v) for k, v in asdict(self).items()}


def mde_along(
    map: Map | str,
    poses,
    sensor: Sensor | str = DEFAULTS.sensor,
    config: Config | None = None,
    *,
    target: RegistrationTarget | None = None,
    progress=None,
    **parameters,
) -> TrajectoryMde:
    """MDE (see :func:`lf3pm.validation.mde`) at each of ``poses`` ((N, 4) x y z
    yaw, sampled by the caller at a constant time interval) and S, their sum, with the
    scan and mde sections of ``config`` (default: the defaults), whose fields may also
    be given by name (validated there).

    The map is prepared for registration once (or ``target`` is reused). Pose i
    is evaluated with seed ``pose_seed(seed, i)``. Poses that cannot be
    evaluated are reported in ``refused``, never dropped silently. ``progress``,
    if given, is called as progress(done, total) after each pose.
    """
    # Checked once here (the sections): inside the loop they would refuse every pose one by one.
    config = configured(config, ("scan", "mde"), "mde_along", **parameters)
    scan, disturbance = config.scan, config.mde
    seed, threads = scan.seed, scan.threads
    map, sensor = as_map(map), as_sensor(sensor)
    poses = np.asarray(poses, dtype=np.float64)
    if poses.ndim != 2 or poses.shape[1] != 4 or len(poses) < 1:
        raise Lf3pmError(f"poses must be an (N, 4) array of x y z yaw with N >= 1, got shape {poses.shape}")
    if not np.all(np.isfinite(poses)):
        raise Lf3pmError("poses contain non-finite values")
    target = RegistrationTarget.for_map(map, target, threads)

    values, seeds, refused, t_med, converged, hits = [], [], [], [], [], []
    for i, pose in enumerate(poses):
        pose_s = pose_seed(seed, i)
        seeds.append(pose_s)
        try:
            result = mde(map, pose, sensor, config, target=target, seed=pose_s)
        except Lf3pmError as err:
            refused.append((i, str(err)))
            values.append(math.nan)
            t_med.append(math.nan)
            converged.append(0)
            hits.append(0)
        else:
            values.append(result.mde)
            t_med.append(float(np.median(result.translation_errors)))
            converged.append(result.converged)
            hits.append(result.hits)
        if progress is not None:
            progress(i + 1, len(poses))
    evaluated = [v for v in values if math.isfinite(v)]
    params = {
        "seed": int(seed),
        "pose_seed": "SeedSequence([seed, index]).generate_state(1)[0]",
        "trials": disturbance.trials,
        "noise": scan.noise_for(sensor),
        "sigma_t": disturbance.sigma_t,
        "sigma_r_deg": disturbance.sigma_r,
        "scan_voxel": scan.scan_voxel,
        "max_correspondence_distance": disturbance.max_correspondence_distance,
        "max_iterations": disturbance.max_iterations,
        "clearance": scan.clearance,
        "registration": "small_gicp PLANE_ICP",
        "map_sha256": map.sha256,
    }
    return TrajectoryMde(
        s=float(np.sum(evaluated)) if evaluated else math.nan,
        mde=values,
        seeds=seeds,
        refused=refused,
        translation_error_median=t_med,
        converged=converged,
        hits=hits,
        poses=poses.tolist(),
        sensor=sensor.name,
        params=params,
    )
