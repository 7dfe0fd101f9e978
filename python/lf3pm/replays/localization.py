"""Localization on a prior map, the deployment a SOLM is made for: every scan
is registered to the map (small_gicp point-to-plane ICP) from a prediction by
wheel odometry, and where the registration is degenerate the estimate keeps
the prediction in the poorly constrained directions.

Per scan k (scans.py; scan k ends at t_k, its rays fire over the period before):

1. **Wheel odometry.** The increment of the base over the scan's period is the
   true planar increment (dx, dy, dyaw) from t_{k-1} to t_k in the frame of
   t_{k-1}, with the translation scaled by (1 + ``scale_error``) and the yaw
   increment plus N(0, ``yaw_noise``^2 * period): a wheel radius off by a
   fixed fraction and a heading that random-walks (defaults in
   :class:`WheelOdometry`). The prior is the last estimate composed with this
   increment; scan 0 starts at the true first pose.
2. **Deskewing.** Each return is moved from the frame of its firing time to
   the frame of t_k assuming the odometry's increment is a constant twist over
   the period (what KISS-ICP and most LiDAR odometries assume), then the scan
   is voxel-downsampled (``scan_voxel``, one centroid per voxel, small_gicp).
3. **Registration.** small_gicp ``PLANE_ICP`` against the map prepared once
   (:class:`lf3pm.validation.mde.RegistrationTarget`: points, normals, k-d
   tree; pass ``target`` to reuse it across replays), from the prior.
4. **Degeneracy and solution remapping** (Zhang, Kaess & Singh, ICRA 2016).
   small_gicp returns the final Gauss-Newton Hessian H = sum J^T J in its
   tangent order [rotation (3), translation (3)] for T <- T exp(delta) (its
   optimizer's right update, checked in its source). With the rotations scaled
   by the scan's RMS range L (a rotation of a rad moves a typical point by
   L a metres), every eigenvector v of the scaled H is a direction of motion in
   metres, and sigma / sqrt(lambda_v) is the standard deviation that range
   noise of sigma (the sensor's) leaves in it. A direction is degenerate when
   that deviation exceeds ``degenerate_std``. The registration's correction
   delta = log(prior^-1 T_reg) is projected onto the well-constrained
   eigenvectors (Zhang's remapping, applied to the converged correction since
   small_gicp's iterations are closed) and the estimate is prior exp(P delta):
   it follows the prior along degenerate directions and the map across them.
   With ``remap=False`` the registration is taken as it is (and the
   degeneracy still reported).

**In flight** (a motion that moves in 6 DOF, ``spatial``: flight_motion.py) steps 1
and 2 are spatial: the odometry's increment is the true SE(3) increment T_{k-1}^-1 T_k
with its translation scaled by (1 + ``scale_error``) and its rotation turned about the
vertical by the same heading noise (an odometry such as a visual-inertial one, whose
scale and heading drift), and each return is deskewed by that increment's constant
twist: exp((f - 1) xi) for the firing fraction f. Steps 3 and 4 are 6 DOF for either.

A scan with fewer than ``min_points`` points after downsampling, or whose
registration keeps fewer inliers, is skipped: the estimate is the prior.
Registration runs on ``registration_threads`` threads (1: small_gicp reduces in
parallel, so only one thread is bit-for-bit reproducible; a study runs
replays in parallel processes instead).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass

import numpy as np

from lf3pm.config import DEFAULTS, LocalizationConfig
from lf3pm.errors import Lf3pmError
from lf3pm.pose import se3_exp, se3_log
from lf3pm.replays.replay_result import Estimate, MethodRun, SectionMethod, library_versions
from lf3pm.sensors import Sensor
from lf3pm.validation.mde import RegistrationTarget

_NOISE_TAG = 0x0D0E  # wheel-odometry noise: its own stream of the replay's seed


@dataclass(frozen=True)
class WheelOdometry:
    """The odometry that predicts each registration.

    ``scale_error``: fractional error of the travelled distance (a wheel radius
    off by 2 % -- tyre wear, pressure and load change a wheel's effective radius
    by one to a few per cent -- makes every distance 2 % long). ``yaw_noise``
    (rad/sqrt(s)): density of the heading's random walk (wheel slip and an
    uncertain track width; 0.01 rad/sqrt(s) lets the heading wander by 0.6 deg
    in 3 s and 4.4 deg in a minute, 1 sigma, as unaided wheel odometry of small
    differential-drive robots does).
    """

    scale_error: float = DEFAULTS.localization.scale_error
    yaw_noise: float = DEFAULTS.localization.yaw_noise

    def __post_init__(self):
        if not (math.isfinite(self.scale_error) and self.scale_error > -1):
            raise Lf3pmError(f"the odometry scale error must be > -1, got {self.scale_error}")
        if not (math.isfinite(self.yaw_noise) and self.yaw_noise >= 0):
            raise Lf3pmError(f"the odometry yaw noise must be >= 0 rad/sqrt(s), got {self.yaw_noise}")

    def increments(self, truth: np.ndarray, period: float, seed: int) -> np.ndarray:
        """Measured planar increments (M - 1, 3) of dx, dy (frame of the earlier
        pose) and dyaw between consecutive true poses ``truth`` (M, 4, 4)."""
        rng = np.random.default_rng(np.random.SeedSequence([int(seed), _NOISE_TAG]))
        yaw = np.arctan2(truth[:, 1, 0], truth[:, 0, 0])
        step = truth[1:, :2, 3] - truth[:-1, :2, 3]
        c, s = np.cos(yaw[:-1]), np.sin(yaw[:-1])
        local = np.column_stack([c * step[:, 0] + s * step[:, 1], -s * step[:, 0] + c * step[:, 1]])
        turn = np.angle(np.exp(1j * np.diff(yaw)))
        noise = rng.normal(size=len(turn)) * self.yaw_noise * math.sqrt(period)
        return np.column_stack([local * (1.0 + self.scale_error), turn + noise])

    def spatial_increments(self, truth: np.ndarray, period: float, seed: int) -> np.ndarray:
        """Measured SE(3) increments (M - 1, 4, 4) between consecutive true poses ``truth``
        (M, 4, 4) of a flight (module docstring): T_{k-1}^-1 T_k, its translation scaled by
        (1 + scale_error), its rotation turned about the world's vertical by the heading
        noise :meth:`increments` draws (the same stream)."""
        from scipy.spatial.transform import Rotation

        rng = np.random.default_rng(np.random.SeedSequence([int(seed), _NOISE_TAG]))
        steps = np.linalg.inv(truth[:-1]) @ truth[1:]
        noise = rng.normal(size=len(steps)) * self.yaw_noise * math.sqrt(period)
        up = truth[:-1, 2, :3]  # R^T e3: the vertical in the earlier pose's frame
        steps[:, :3, :3] = Rotation.from_rotvec(up * noise[:, None]).as_matrix() @ steps[:, :3, :3]
        steps[:, :3, 3] *= 1.0 + self.scale_error
        return steps


def planar_exp(twist, s) -> tuple[np.ndarray, np.ndarray]:
    """exp(s xi) in SE(2) for the twist xi = (ux, uy, theta) and fractions s (n,):
    rotation angles (n,) and translations (n, 2)."""
    ux, uy, theta = twist
    phi = np.asarray(s, float) * theta
    small = np.abs(phi) < 1e-9
    safe = np.where(small, 1.0, phi)
    a = np.where(small, 1.0 - phi**2 / 6.0, np.sin(safe) / safe)  # sin(phi) / phi
    b = np.where(small, phi / 2.0, (1.0 - np.cos(safe)) / safe)  # (1 - cos(phi)) / phi
    su, sv = np.asarray(s, float) * ux, np.asarray(s, float) * uy
    return phi, np.column_stack([a * su - b * sv, b * su + a * sv])


def planar_log(dx: float, dy: float, dyaw: float) -> tuple[float, float, float]:
    """The twist (ux, uy, theta) whose planar_exp at s = 1 is the increment."""
    if abs(dyaw) < 1e-9:
        return dx, dy, dyaw
    a, b = math.sin(dyaw) / dyaw, (1.0 - math.cos(dyaw)) / dyaw
    det = a * a + b * b
    return (a * dx + b * dy) / det, (-b * dx + a * dy) / det, dyaw


def deskew(points: np.ndarray, fractions: np.ndarray, twist) -> np.ndarray:
    """Returns (H, 3) in the frame of the scan's end, each point having been
    reported in the frame of its firing at ``fractions`` (H,) of a period over
    which the sensor moved by the constant planar ``twist``."""
    phi, t = planar_exp(twist, fractions - 1.0)
    c, s = np.cos(phi), np.sin(phi)
    x, y = points[:, 0], points[:, 1]
    return np.column_stack([c * x - s * y + t[:, 0], s * x + c * y + t[:, 1], points[:, 2]])


def spatial_deskew(points: np.ndarray, fractions: np.ndarray, increment: np.ndarray) -> np.ndarray:
    """Returns (H, 3) in the frame of the scan's end, each point having been reported in
    the frame of its firing at ``fractions`` (H,) of a period over which the sensor moved
    by the SE(3) ``increment`` (4, 4) at a constant twist xi: exp((f - 1) xi) p."""
    from scipy.spatial.transform import Rotation

    xi = se3_log(increment)
    rho, phi = xi[:3], xi[3:]
    s = np.asarray(fractions, dtype=np.float64) - 1.0
    # exp(s xi) = (R(s phi), V(s phi) s rho), V = I + a K + b K^2 with K = hat(s phi):
    # a = (1 - cos th) / th^2 and b = (th - sin th) / th^3, by their series where th is small.
    theta = np.abs(s) * np.linalg.norm(phi)
    small = theta < 1e-4
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    b = np.where(small, 1.0 / 6.0 - theta**2 / 120.0, (safe - np.sin(safe)) / safe**3)
    k_rho = np.cross(phi, rho)
    kk_rho = np.cross(phi, k_rho)
    t = s[:, None] * rho + (a * s**2)[:, None] * k_rho + (b * s**3)[:, None] * kk_rho
    return Rotation.from_rotvec(s[:, None] * phi).apply(points) + t


def planar_matrix(dx: float, dy: float, dyaw: float) -> np.ndarray:
    """4 x 4 transform of a planar increment."""
    T = np.eye(4)
    c, s = math.cos(dyaw), math.sin(dyaw)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:2, 3] = dx, dy
    return T


@dataclass(frozen=True)
class Degeneracy:
    """The directions of one registration: ``std`` (6,) the deviation range noise
    leaves along each eigenvector (m, ascending information), ``vectors`` (6, 6)
    the eigenvectors (columns, scaled tangent space [L rotation, translation]),
    ``scale`` L (m), ``degenerate`` (6,) bools."""

    std: np.ndarray
    vectors: np.ndarray
    scale: float
    degenerate: np.ndarray

    @property
    def count(self) -> int:
        return int(np.count_nonzero(self.degenerate))

    def remap(self, correction: np.ndarray) -> np.ndarray:
        """The tangent correction [rotation, translation] (6,) with its components
        along the degenerate eigenvectors removed."""
        D = np.r_[np.full(3, self.scale), np.ones(3)]
        keep = self.vectors[:, ~self.degenerate]
        return (keep @ (keep.T @ (D * correction))) / D


def degeneracy(H: np.ndarray, points: np.ndarray, sigma: float, bound: float) -> Degeneracy:
    """Eigen-analysis of small_gicp's Hessian ``H`` (6 x 6, [rotation,
    translation]) for the registered ``points`` (n, 3, sensor frame) under range
    noise ``sigma``; a direction is degenerate when its deviation exceeds ``bound``."""
    scale = float(np.sqrt(np.mean(np.sum(points * points, axis=1)))) if len(points) else 1.0
    D_inv = np.r_[np.full(3, 1.0 / scale), np.ones(3)]
    Hs = H * D_inv[:, None] * D_inv[None, :]
    values, vectors = np.linalg.eigh(0.5 * (Hs + Hs.T))
    with np.errstate(divide="ignore"):
        std = np.where(values > 0, sigma / np.sqrt(np.maximum(values, 1e-300)), math.inf)
    return Degeneracy(std=std, vectors=vectors, scale=scale, degenerate=std > bound)


@dataclass(frozen=True)
class Registered:
    """One scan registered to the map (:func:`register_to_map`): its estimated ``pose``
    (the prior where ``skipped``), whether small_gicp ``converged``, how many
    ``directions`` were degenerate and the ``largest_std`` range noise leaves (m; NaN
    where skipped)."""

    pose: np.ndarray
    skipped: bool
    converged: bool = False
    directions: int = 0
    largest_std: float = math.nan


def register_to_map(
    points: np.ndarray, prior: np.ndarray, target: RegistrationTarget, sigma: float, settings: LocalizationConfig
) -> Registered:
    """Steps 2 (the downsampling) to 4 of the module docstring for one scan's ``points``
    (n, 3, sensor frame, deskewed) from ``prior`` (4 x 4 world-from-sensor) on ``target``,
    under range noise ``sigma``: what :func:`localize` does per scan, and the audit of a
    recorded run along it (lf3pm.audit.tracks). Skipped (the prior kept) below
    ``settings.min_points`` points or inliers."""
    import small_gicp

    min_points = settings.min_points
    if settings.scan_voxel > 0 and len(points):
        source = small_gicp.voxelgrid_sampling(np.ascontiguousarray(points), settings.scan_voxel, num_threads=1)
    else:
        source = small_gicp.PointCloud(np.ascontiguousarray(points))
    if source.size() < min_points:
        return Registered(prior, skipped=True)
    result = target.align(
        source, prior, settings.max_correspondence_distance, settings.max_iterations, int(settings.registration_threads)
    )
    if result.num_inliers < min_points:
        return Registered(prior, skipped=True)
    found = degeneracy(np.asarray(result.H), source.points()[:, :3], sigma, settings.degenerate_std)
    T = np.asarray(result.T_target_source)
    if settings.remap and found.count:
        twist = se3_log(np.linalg.inv(prior) @ T)  # (translation, rotation)
        kept = found.remap(np.r_[twist[3:], twist[:3]])  # small_gicp's order
        T = prior @ se3_exp(np.r_[kept[3:], kept[:3]])
    return Registered(T, False, bool(result.converged), found.count, float(found.std[0]))


def localize(
    scans,
    target: RegistrationTarget,
    sensor: Sensor,
    settings: LocalizationConfig = DEFAULTS.localization,
    *,
    seed: int = DEFAULTS.scan.seed,
    progress=None,
) -> Estimate:
    """Localizes along ``scans`` (a ScanStream: its ``truth`` gives the start and
    the wheel odometry's true increments, planar, or spatial where its motion is a
    flight's) on the prepared map ``target``
    (module docstring) with ``settings``. ``progress``, if given, is called as
    progress(done, total). Returns the Estimate with per-scan degenerate directions and
    a report of the registrations (converged count, the largest deviation per scan)."""
    odometry = WheelOdometry(settings.scale_error, settings.yaw_noise)
    count = len(scans)
    truth = scans.truth
    spatial = bool(getattr(scans.motion, "spatial", False))
    steps = (odometry.spatial_increments if spatial else odometry.increments)(truth, scans.period, seed)
    sigma = sensor.range_noise_sigma
    estimate = np.empty((count, 4, 4))
    hits = np.zeros(count, dtype=np.int64)
    directions = np.zeros(count, dtype=np.int8)
    worst = np.full(count, math.nan)
    skipped, converged, seconds = [], 0, 0.0
    for k, scan in enumerate(scans):
        hits[k] = len(scan.points)
        start = time.perf_counter()
        if spatial:
            step = np.eye(4) if k == 0 else steps[k - 1]
            prior = truth[0] if k == 0 else estimate[k - 1] @ step
            points = spatial_deskew(scan.points, scan.timestamps, step)
        else:
            step = (0.0, 0.0, 0.0) if k == 0 else tuple(steps[k - 1])
            prior = truth[0] if k == 0 else estimate[k - 1] @ planar_matrix(*step)
            points = deskew(scan.points, scan.timestamps, planar_log(*step))
        found = register_to_map(points, prior, target, sigma, settings)
        estimate[k] = found.pose
        if found.skipped:
            skipped.append(k)
        else:
            converged += found.converged
            directions[k], worst[k] = found.directions, found.largest_std
        seconds += time.perf_counter() - start
        if progress is not None:
            progress(k + 1, count)
    report = {
        "registered": count - len(skipped),
        "converged": converged,
        "largest_std_m": worst.tolist(),
        "sigma": sigma,
    }
    return Estimate(
        poses=estimate, hits=hits, skipped=skipped, seconds=seconds, degenerate_directions=directions, report=report
    )


def localization_params(settings: LocalizationConfig) -> dict:
    """The settings a localization replay records."""
    odometry = WheelOdometry(settings.scale_error, settings.yaw_noise)
    recorded = settings.model_dump(exclude={"scale_error", "yaw_noise", "registration_threads"})
    return {"odometry": asdict(odometry), **recorded, "registration": "small_gicp PLANE_ICP"}


class Localization(SectionMethod):
    """The ``localization`` replay method (lf3pm.replays.methods.ReplayMethod): the map
    prepared for registration once, then :func:`localize` with ``settings`` (a
    LocalizationConfig)."""

    name = "localization"
    section = "localization"

    def prepare(self, map, threads: int, prepared: RegistrationTarget | None = None) -> RegistrationTarget:
        return RegistrationTarget.for_map(map, prepared, threads)

    def run(self, scans, motion, sensor: Sensor, seed: int, *, prepared, threads: int, progress=None) -> MethodRun:
        run = localize(scans, prepared, sensor, self.settings, seed=seed, progress=progress)
        return MethodRun(run, localization_params(self.settings), library_versions("small_gicp"))
