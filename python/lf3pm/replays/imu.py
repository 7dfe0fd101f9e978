"""A simulated IMU along a motion: accelerometer and gyroscope with white noise
and bias random walk from a datasheet-like preset (docs/lio.md).

Gravity: g_world = (0, 0, -GRAVITY), GRAVITY = 9.81 m/s^2 (also the g that
converts a datasheet's micro-g, and the flatness map's). At sample time t_k the IMU,
of orientation R (IMU to world), reads

    accel_k = R^T (a_world - g_world) + b_a(t_k) + n_a,k    (specific force, m/s^2)
    gyro_k  = omega_imu               + b_g(t_k) + n_g,k    (rad/s)

so a level IMU at rest reads accel (0, 0, +9.81). On a ground robot the IMU frame
is the sensor frame: R is the motion's pose, a_world the sensor's acceleration and
omega_imu = R^T (0, 0, yaw_rate) (the robot is level: roll = pitch = 0). In a
flight (flight_motion.py) the IMU is the body's, at its origin: R, a_world and
omega_imu are the flatness map's exact attitude, acceleration and body rates, and
the LiDAR sits in its frame at the mount (ImuSamples.extrinsic, which the LIOs are
given).

Noise, per axis, from a continuous-time model sampled at ``rate`` f = 1/dt
(the conventions of Kalibr and of the IMU noise model in most VIO/LIO work):

- white noise of density N (units/sqrt(Hz)): n_k ~ N(0, sigma_w^2),
  sigma_w = N * sqrt(f) (a sample averages the noise over the bandwidth f/2);
- bias random walk of density K (units/s/sqrt(Hz)): b(t_0) = 0 (biases
  calibrated at start-up), b(t_{k+1}) = b(t_k) + sigma_b w_k, sigma_b = K *
  sqrt(dt), so that Var b(t) = K^2 (t - t_0).

Preset ``bmi088`` (the default): the Bosch BMI088 6-axis IMU, a MEMS part Livox
builds into its Avia and Horizon LiDARs and that drones and ground robots carry.
Bosch datasheet BST-BMI088-DS001, typical values:

- accelerometer noise density 175 micro-g/sqrt(Hz): N_a = 175e-6 * 9.81 =
  1.717e-3 m/s^2/sqrt(Hz); at 200 Hz sigma_w = 1.717e-3 * sqrt(200) = 0.0243 m/s^2;
- gyroscope noise density 0.014 deg/s/sqrt(Hz): N_g = 2.443e-4 rad/s/sqrt(Hz);
  at 200 Hz sigma_w = 2.443e-4 * sqrt(200) = 3.46e-3 rad/s;
- the datasheet gives no in-run bias instability or random walk, only the
  offsets' temperature coefficients: 0.2 mg/K (accelerometer) and 0.015
  deg/s/K (gyroscope). The random walks are sized (an assumption, stated as
  such) so that over 10 minutes the bias wanders, at one sigma, as far as a
  1 K temperature change moves it: K = TCO * 1 K / sqrt(600 s), i.e.
  K_a = 1.962e-3 / 24.49 = 8.01e-5 m/s^3/sqrt(Hz) and K_g = 2.618e-4 / 24.49 =
  1.069e-5 rad/s^2/sqrt(Hz); at 200 Hz sigma_b = K / sqrt(200) = 5.66e-6 m/s^2
  and 7.56e-7 rad/s per sample. These sit inside the range Allan-variance
  studies report for consumer MEMS IMUs (1e-5 to 1e-3 and 1e-6 to 1e-4).

Seeding: the four noise streams (accelerometer white and bias, gyroscope white
and bias) are children of SeedSequence([seed, IMU_STREAM]), a tag no other
stream in lf3pm uses; the scans' range noise comes from the C++ core's own
generator. The same seed and rate give the same noise whatever the motion.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from lf3pm.config import DEFAULTS
from lf3pm.errors import Lf3pmError

#: Magnitude of gravity, m/s^2: g_world = (0, 0, -GRAVITY).
GRAVITY = 9.81
#: SeedSequence tag of the IMU noise ("IMU" in ASCII).
IMU_STREAM = 0x494D55
#: Most samples one simulation makes: beyond this a typo in a rate would exhaust memory.
MAX_SAMPLES = 20_000_000


@dataclass(frozen=True)
class ImuPreset:
    """An IMU noise model: densities of the white noise (``*_noise_density``,
    m/s^2/sqrt(Hz) and rad/s/sqrt(Hz)) and of the bias random walk
    (``*_bias_random_walk``, m/s^3/sqrt(Hz) and rad/s^2/sqrt(Hz)); ``source``
    says where the numbers come from."""

    name: str
    description: str
    accel_noise_density: float
    gyro_noise_density: float
    accel_bias_random_walk: float
    gyro_bias_random_walk: float
    source: str

    def sigmas(self, rate: float) -> dict:
        """The discrete-time standard deviations at ``rate`` Hz: white noise per
        sample (density * sqrt(rate)) and bias step per sample (density / sqrt(rate))."""
        root = math.sqrt(rate)
        return {
            "accel_white": self.accel_noise_density * root,
            "gyro_white": self.gyro_noise_density * root,
            "accel_bias_step": self.accel_bias_random_walk / root,
            "gyro_bias_step": self.gyro_bias_random_walk / root,
        }


_TEN_MINUTES = 600.0
PRESETS = {
    "bmi088": ImuPreset(
        name="bmi088",
        description="Bosch BMI088 MEMS IMU (in the Livox Avia and Horizon)",
        accel_noise_density=175e-6 * GRAVITY,
        gyro_noise_density=math.radians(0.014),
        accel_bias_random_walk=0.2e-3 * GRAVITY / math.sqrt(_TEN_MINUTES),
        gyro_bias_random_walk=math.radians(0.015) / math.sqrt(_TEN_MINUTES),
        source="Bosch BMI088 datasheet BST-BMI088-DS001 (typical): accelerometer 175 ug/sqrt(Hz), gyroscope "
        "0.014 deg/s/sqrt(Hz); bias random walks sized from the offset temperature coefficients "
        "(0.2 mg/K, 0.015 deg/s/K) as a 1 K change in 10 minutes (assumption)",
    ),
}
DEFAULT_PRESET = "bmi088"


def get_imu_preset(preset: str | ImuPreset) -> ImuPreset:
    """The preset of that name (case-insensitive), or ``preset`` itself if it is one."""
    if isinstance(preset, ImuPreset):
        return preset
    key = str(preset).strip().lower().replace("-", "").replace("_", "")
    if key not in PRESETS:
        raise Lf3pmError(f"unknown IMU preset {preset!r}; known: {', '.join(PRESETS)}")
    return PRESETS[key]


@dataclass(frozen=True)
class ImuSamples:
    """IMU samples on the motion's clock.

    ``t`` (K,) s, increasing; ``accel`` (K, 3) specific force in m/s^2 in the
    IMU frame, (0, 0, +9.81) when level at rest; ``gyro`` (K, 3) rad/s in the IMU
    frame. ``accel_bias`` and ``gyro_bias`` (K, 3): the biases the samples carry
    (zero without noise); ``preset`` (the noise model), ``seed``, ``rate``,
    ``noise``: how they were made. ``extrinsic`` (4, 4): the LiDAR's pose in the
    IMU frame (identity on a ground robot, whose IMU frame is the sensor's; a
    flight's mount).
    """

    t: np.ndarray = field(repr=False)
    accel: np.ndarray = field(repr=False)
    gyro: np.ndarray = field(repr=False)
    accel_bias: np.ndarray = field(repr=False)
    gyro_bias: np.ndarray = field(repr=False)
    preset: ImuPreset
    seed: int
    rate: float
    noise: bool
    extrinsic: np.ndarray = field(default_factory=lambda: np.eye(4), repr=False)

    def __len__(self) -> int:
        return len(self.t)


def sample_times(t0: float, t1: float, rate: float) -> np.ndarray:
    """t0 + k / rate for k = 0, 1, ... while <= t1 (t1 included when on the grid)."""
    count = int(math.floor((t1 - t0) * rate + 1e-9)) + 1
    if count > MAX_SAMPLES:
        raise Lf3pmError(f"{count} IMU samples at {rate:g} Hz over {t1 - t0:g} s: more than {MAX_SAMPLES}")
    return t0 + np.arange(count) / rate


def simulate_imu(
    motion,
    *,
    rate: float = DEFAULTS.replay.imu_rate,
    preset: str | ImuPreset = DEFAULT_PRESET,
    seed: int = DEFAULTS.scan.seed,
    noise: bool = DEFAULTS.replay.imu_noise,
) -> ImuSamples:
    """IMU samples every 1/``rate`` s over [motion.t0, motion.t1] (module
    docstring for the model). ``motion`` needs t0, t1 and either
    imu_states(t) and extrinsic (a flight: FlightMotion) or acceleration(t),
    yaw_rate(t) and pose(t) (a ground robot: Motion). ``noise`` False:
    the exact specific force and angular rate. Raises Lf3pmError for a bad
    rate, preset or seed, a motion shorter than one sample interval or one
    that returns malformed or non-finite values.
    """
    if isinstance(rate, bool) or not isinstance(rate, numbers.Real) or not (math.isfinite(rate) and rate > 0):
        raise Lf3pmError(f"the IMU rate must be a number > 0 Hz, got {rate!r}")
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise Lf3pmError(f"the IMU seed must be an integer >= 0, got {seed!r}")
    model = get_imu_preset(preset)
    rate, t0, t1 = float(rate), float(motion.t0), float(motion.t1)
    if not (math.isfinite(t0) and math.isfinite(t1) and t1 - t0 >= 1.0 / rate):
        raise Lf3pmError(f"the motion spans [{t0:g}, {t1:g}] s: shorter than one IMU interval (1/{rate:g} s)")
    t = sample_times(t0, t1, rate)
    rotation, accel_world, gyro, extrinsic = _imu_motion(motion, t)
    gravity_world = np.array([0.0, 0.0, -GRAVITY])
    # R^T v for each sample: v @ R (row vectors).
    accel = np.einsum("kij,ki->kj", rotation, accel_world - gravity_world)
    accel_bias = np.zeros_like(accel)
    gyro_bias = np.zeros_like(gyro)
    if noise:
        s = model.sigmas(rate)
        streams = [np.random.default_rng(child) for child in np.random.SeedSequence([int(seed), IMU_STREAM]).spawn(4)]
        accel_bias = _random_walk(streams[1], len(t), s["accel_bias_step"])
        gyro_bias = _random_walk(streams[3], len(t), s["gyro_bias_step"])
        accel = accel + accel_bias + s["accel_white"] * streams[0].standard_normal((len(t), 3))
        gyro = gyro + gyro_bias + s["gyro_white"] * streams[2].standard_normal((len(t), 3))
    return ImuSamples(
        t=t,
        accel=accel,
        gyro=gyro,
        accel_bias=accel_bias,
        gyro_bias=gyro_bias,
        preset=model,
        seed=int(seed),
        rate=rate,
        noise=bool(noise),
        extrinsic=extrinsic,
    )


def _imu_motion(motion, t: np.ndarray) -> tuple:
    """The IMU's orientation (K, 3, 3), its acceleration (K, 3, world) and rates (K, 3,
    IMU frame) at ``t``, and the LiDAR's pose in its frame (4, 4), checked: a flight's
    from its imu_states, a ground robot's from its sensor's pose and yaw rate."""
    k = len(t)
    states = getattr(motion, "imu_states", None)
    if states is not None:
        rotation, accel_world, gyro = (np.asarray(a, dtype=np.float64) for a in states(t))
        extrinsic = np.array(motion.extrinsic, dtype=np.float64)
    else:
        accel_world = np.asarray(motion.acceleration(t), dtype=np.float64)
        yaw_rate = np.asarray(motion.yaw_rate(t), dtype=np.float64)
        if yaw_rate.shape != (k,):
            raise Lf3pmError("the motion returned arrays of the wrong shape for the IMU sample times")
        gyro = np.zeros((k, 3))
        gyro[:, 2] = yaw_rate  # in the world frame until checked
        rotation = np.asarray(motion.pose(t), dtype=np.float64)[..., :3, :3]
        extrinsic = np.eye(4)
    if accel_world.shape != (k, 3) or gyro.shape != (k, 3) or rotation.shape != (k, 3, 3):
        raise Lf3pmError("the motion returned arrays of the wrong shape for the IMU sample times")
    if not (np.all(np.isfinite(accel_world)) and np.all(np.isfinite(gyro)) and np.all(np.isfinite(rotation))):
        raise Lf3pmError("the motion returned non-finite accelerations, rates or poses")
    if extrinsic.shape != (4, 4) or not np.all(np.isfinite(extrinsic)):
        raise Lf3pmError(f"the motion's extrinsic must be a finite 4 x 4 matrix, got shape {extrinsic.shape}")
    if states is None:
        gyro = np.einsum("kij,ki->kj", rotation, gyro)  # R^T (0, 0, yaw rate): into the sensor frame
    return rotation, accel_world, gyro, extrinsic


def _random_walk(rng: np.random.Generator, count: int, step: float) -> np.ndarray:
    """(count, 3) random walk from 0 with N(0, step^2) steps per sample."""
    walk = np.zeros((count, 3))
    np.cumsum(step * rng.standard_normal((count - 1, 3)), axis=0, out=walk[1:])
    return walk
