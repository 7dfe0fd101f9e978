"""LiDAR-inertial odometry on simulated scans and IMU samples. Three odometries,
each fed exactly the same scans and IMU samples (docs/lio.md compares them):

- ``genz`` (default): GenZ-LIO (PyPI ``genz-lio``, pinned 0.1.1, GPL-2.0-only), a
  FAST-LIO2-style iterated error-state Kalman filter on a voxel map, run with
  point-to-plane updates only (its point-to-point ones made the estimate lag;
  default_settings), the paper's FAST-LIO2 setting. ``make build`` replaces PyPI's
  wheel by lf3pm's build of its sdist (third_party/genz_lio, 0.1.1+lf3pm.1), whose
  one change lets the initial covariance be set (default_settings);
- ``dlio``: DLIO (Direct LiDAR-Inertial Odometry, UCLA VECTR, MIT) as evalio
  (PyPI ``evalio``, pinned 0.6.1, MIT) compiles it: GICP scan-to-map registration
  with a nonlinear geometric observer, deskewing by IMU integration;
- ``liosam``: LIO-SAM (BSD-3-Clause) as evalio compiles it: LOAM features of a
  ring-organised scan matched to a keyframe map, IMU preintegration in a factor
  graph; spinning sensors only. What the replay does to feed it (a level IMU made
  its start-up NaN, its poses come two scans late and refer to two times) is in
  _lio_worker.LioSam and docs/lio.md, "The third: LIO-SAM".

The default, ``auto``, picks by measurement (docs/lio.md, bench/compare_odometries.py):
DLIO for a spinning sensor (VLP-16: 1-6 mm APE on every structured drive, noise-free
or noisy, where GenZ-LIO gave 1-18 cm and lagged the truth by up to 0.15 s; at lf3pm's
initial covariance GenZ-LIO gives 0.2-1.8 cm without lag, and DLIO is kept: no worse
anywhere but the tunnel), GenZ-LIO for a non-repetitive one (Mid-70: 0.6-2.4 cm on
structured drives where DLIO lost the narrow 0.1 s scans, 0.1-3 m).

Why GenZ-LIO and not RKO-LIO (PyPI ``rko-lio`` 0.4.0, PRBonn; measured with
GenZ-LIO's own defaults, before default_settings): both ran on the same
simulated data (``bench/compare_lio.py``: 10 Hz motion-distorted scans,
200 Hz BMI088 IMU, noise-free / noisy; APE translation RMSE without alignment,
the estimate anchored at the true first pose; ms per scan of the odometry on
one thread, on the shared 2-core machine):

=============================  ===================  ===================  ====================
scenario                       GenZ-LIO 0.1.1       RKO-LIO 0.4.0        RKO-LIO, voxel 0.25
=============================  ===================  ===================  ====================
boxes room, VLP-16, 18 s       0.034 / 0.020 m      0.057 / 0.073 m      0.019 / 0.026 m
                               17 ms                3 ms                 6 ms
reduced gobi, Mid-70, 44 s:    0.59 / 0.98 m        11.5 / 23.4 m        15.0 / 3.2 m
town, 82 deg turn, desert      16 ms                1 ms                 7 ms
reduced gobi, Mid-70, 23 s,    1.28 / 0.68 m        11.4 / 3.1 m         10.0 / 2.5 m
sensor yawing +-69 deg         23-28 ms             2 ms                 13-17 ms
=============================  ===================  ===================  ====================

With the narrow Mid-70 (10,000 rays per 0.1 s scan; consecutive scans fall
on different petals of its rosette) RKO-LIO, a KISS-ICP-style point-to-point
ICP that uses the IMU only for the initial guess, deskewing and a gravity
term, jumps by up to 1.4 m between noise-free scans of a sensor standing still
in the town square; the filter holds such weak directions with the IMU. Both
are deterministic with one thread (bitwise, every run above repeated), neither
crashed; RKO-LIO refused one noisy desert scan (too few ICP keypoints), GenZ-LIO none.
GenZ-LIO with two OpenMP threads gave the same poses, more slowly here. RKO-LIO
is the better kept package (15 releases since 2025, MIT, documentation,
wheels for Python 3.10-3.14; it also prints to stdout, a profile at exit
included); GenZ-LIO has two releases, is GPL-2.0-only and has wheels for
Python 3.8-3.12 only, so its pin carries a Python < 3.13 marker and run_lio
says so on newer Pythons. An odometry off by metres on the paper's sensor
cannot check plans, so accuracy decided.

Conventions (GenZ-LIO 0.1.1, read from its source): IMU rows t, ax, ay, az,
gx, gy, gz in s, m/s^2 (it rescales by 9.81 / |mean accel| at start-up, so g
units would also do) and rad/s, each scan given the samples with t in (previous
scan end, scan end]; per-point times are float32 *offsets* in seconds, rebased
by GenZ-LIO onto the earliest return, so we pass stamps - begin with begin =
the earliest stamp (absolute times in float32 would lose milliseconds); the
pose is the IMU's at the scan end in the odometry frame, which is the IMU frame
while GenZ-LIO initialises (the first 20+ IMU samples, during which it takes
the sensor to be still and estimates gravity and the gyro bias from them).
LiDAR-IMU extrinsic: identity. The estimate is anchored as initial_pose @ P_k,
P_k GenZ-LIO's pose after scan k (identity at the first scan, which is
consumed by the initialisation).

Conventions (evalio 0.6.1's DLIO, read from evalio's binding and DLIO's
deskewing, checked by the time fit of tests/test_lio.py): a LidarMeasurement
stamped at the scan's first return, each return carrying its offset from it
(ns); IMU samples as ImuMeasurement (gyro, accel) in s, rad/s, m/s^2; DLIO
deskews each scan to its median distinct return time and reports the sensor's
pose there, so its estimate refers to that time, not to the scan's end
(LioEstimate.times). It calibrates the IMU biases and gravity over its first
``imu_calib_time`` s (lf3pm: 1 s, inside the replay's rest; DLIO's own 3 s
would run into the motion), during which the sensor must be still. evalio
leaves every parameter it is not given uninitialised, so all are set.

Each odometry runs in a child process (_lio_worker.py): their OpenMP runtimes
would make later forks of the caller hang (shared BUILD-NOTES), and a crash
becomes a clear error here instead of killing the caller.
"""

from __future__ import annotations

import math
import os
import pickle
import subprocess
import sys
import tempfile
import warnings
from dataclasses import dataclass, field

import numpy as np

from lf3pm.config import ReplayConfig
from lf3pm.errors import Lf3pmError
from lf3pm.pose import pose_matrix
from lf3pm.replays.imu import ImuPreset
from lf3pm.sensors import Sensor, as_sensor, spinning_rings


@dataclass(frozen=True)
class Odometry:
    """A LiDAR-inertial odometry lf3pm runs: its PyPI package and the version
    lf3pm's conventions are checked for (pinned in pyproject.toml), its licence."""

    name: str
    package: str
    version: str
    licence: str


#: The odometries by the name ``run_lio(odometry=...)`` and ``--odometry`` take.
ODOMETRIES = {
    "genz": Odometry("GenZ-LIO", "genz-lio", "0.1.1", "GPL-2.0-only"),
    "dlio": Odometry("DLIO", "evalio", "0.6.1", "MIT (evalio and DLIO)"),
    "liosam": Odometry("LIO-SAM", "evalio", "0.6.1", "BSD-3-Clause (LIO-SAM), MIT (evalio)"),
}
DEFAULT_ODOMETRY = ReplayConfig.model_fields["odometry"].default
#: The sensors docs/lio.md measured an odometry to lose, by odometry and by whether the
#: sensor spins (rings of beams; False: a non-repetitive Livox pattern): what was measured
#: and what to run instead. choose_odometry warns when asked for such a pair.
LOSES = {
    ("dlio", False): "DLIO loses track of a non-repetitive (Livox) sensor, whose 0.1 s scans cover a "
    "part of its pattern (Mid-70: 0.1-3 m APE where GenZ-LIO holds 0.4-4 cm; docs/lio.md, "
    '"Two odometries"): use odometry genz or auto'
}


def choose_odometry(odometry: str, sensor: Sensor) -> str:
    """The odometry run for ``odometry`` (a key of ODOMETRIES or "auto") and
    ``sensor``: "auto" is DLIO for a spinning sensor, GenZ-LIO for a
    non-repetitive (Livox) one (module docstring). Raises Lf3pmError for an
    unknown name; warns (once) for a pair of LOSES."""
    spinning = spinning_rings(sensor) is not None
    if odometry == "auto":
        return "dlio" if spinning else "genz"
    if (odometry, spinning) in LOSES:
        # Attributed here, not to the caller: the CLI's early check and run_lio then warn once.
        warnings.warn(f"{sensor.name} with {odometry}: {LOSES[odometry, spinning]}", stacklevel=1)
    if odometry not in ODOMETRIES:
        raise Lf3pmError(f"unknown odometry {odometry!r}; use one of auto, {', '.join(ODOMETRIES)}")
    if not runs_on(odometry, sensor):
        raise Lf3pmError(
            f"{odometry} needs a spinning sensor (rings of beams); the {sensor.name} has none: use genz or dlio"
        )
    return odometry


#: Odometries that organise each scan by rings (LIO-SAM's range image).
RING_ODOMETRIES = ("liosam",)


def runs_on(odometry: str, sensor: Sensor) -> bool:
    """Whether ``odometry`` (a key of ODOMETRIES) can take ``sensor``'s scans."""
    return odometry not in RING_ODOMETRIES or spinning_rings(sensor) is not None


_WORKER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_lio_worker.py")
#: Factor on the IMU noise variances the filter is told (imu_noise_model). With
#: the exact ones it trusted the IMU over its biased matches in the open desert
#: and drifted (bench/compare_lio.py gobi_turn, noise-free: 8.2 m RMSE; x100:
#: 0.59 m). GenZ-LIO's defaults (made for real IMUs) did as well in the gobi but
#: left the IMU timing a flat optimum in the boxes room (docs/lio.md).
NOISE_INFLATION = 100.0
#: GenZ-LIO's variance of position, rotation and velocity at its start (m^2, rad^2,
#: (m/s)^2) in lf3pm's build of it (third_party/genz_lio). GenZ-LIO's own, FAST-LIO2's
#: 1 (1 m, 1 rad, 1 m/s), seeds its voxel map's planes at that uncertainty: their
#: 3-sigma gates then take wrong matches and a still Mid-70's estimate slides 9-53 cm
#: (median; up to 6 m) and carries that velocity into the trajectory (docs/lio.md,
#: "A still sensor"). The odometry's frame is its first pose, which the replay anchors
#: at the truth, so that pose is known; what is not is the tilt from gravity, which the
#: IMU's 20 still samples fix to about a milliradian, and the velocity of a sensor held
#: still: 1e-4 (1 cm, 0.01 rad, 0.01 m/s) bounds both. Chosen by that argument, not tuned.
GENZ_INIT_POSE_VARIANCE = 1e-4
#: The version lf3pm's build of GenZ-LIO reports; PyPI's wheel (GenZ-LIO's initial
#: covariance) reports ODOMETRIES["genz"].version and runs with a warning.
GENZ_LF3PM_BUILD = "0.1.1+lf3pm.1"
#: Scan statuses that mean the odometry used the scan.
TRACKING = ("ok", "map seeded")


@dataclass(frozen=True)
class LioEstimate:
    """The odometry's estimate per scan: ``poses`` (M, 4, 4) sensor-to-world at
    ``times`` (M,) (GenZ-LIO: each scan's end; DLIO and LIO-SAM: each scan's median return
    time), anchored so that the odometry's first pose is the true initial one.
    ``status[k]``: "initializing" (the odometry is still taking the IMU for a still
    one's), "map seeded", "ok", "rejected" (the filter rolled the update back), "no
    matches" (no scan point matched the map: lost track), or "skipped: ..."
    (not usable). ``lost`` lists the scans whose status is not "ok", "map
    seeded" or "initializing". ``seconds_per_scan``: the odometry's mean time
    per scan. ``messages``: the odometry's own console output and lf3pm's
    warnings.
    """

    times: np.ndarray = field(repr=False)
    poses: np.ndarray = field(repr=False)
    status: list = field(repr=False)
    lost: list
    seconds_per_scan: float
    odometry: str
    package: str
    version: str
    params: dict
    messages: list = field(repr=False)

    def to_dict(self) -> dict:
        """JSON-ready summary (no per-scan arrays)."""
        return {
            "odometry": self.odometry,
            "package": self.package,
            "version": self.version,
            "scans": len(self.times),
            "lost": list(self.lost),
            "seconds_per_scan": self.seconds_per_scan,
            "params": self.params,
            "messages": list(self.messages),
        }


def run_lio(
    scans, imu, sensor: Sensor | str, *, initial_pose, odometry: str = DEFAULT_ODOMETRY, threads: int = 1, **params
) -> LioEstimate:
    """The LiDAR-inertial ``odometry`` (a key of ODOMETRIES, or "auto":
    :func:`choose_odometry`) on ``scans`` (each
    with ``end`` s, ``points`` (H, 3) in the sensor frame at their firing times
    and ``stamps`` (H,) absolute firing times, non-decreasing, <= end; ends
    increasing) and ``imu`` (ImuSamples: t, accel, gyro on the same clock,
    covering the first scan's end). ``sensor`` gives the range limits.
    ``initial_pose`` (a pose lf3pm.pose accepts): the true pose at the first
    scan; the sensor must be still while the odometry initialises (GenZ-LIO:
    the first 20 IMU samples; DLIO: the first ``imu_calib_time`` s).
    ``threads``: the odometry's OpenMP threads (1: deterministic). ``params``
    over :func:`default_settings`: GenZ-LIO's by section, e.g.
    ``mapping={"voxel_size": 0.25}``; DLIO's by name, e.g. ``vf_res=0.5``.
    Raises Lf3pmError for malformed input, an unknown odometry or setting, a
    missing or other version of the odometry's package, or its crash.
    """
    sensor = as_sensor(sensor)
    odometry = choose_odometry(odometry, sensor)
    origin = pose_matrix(initial_pose)
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise Lf3pmError(f"threads must be an integer >= 1, got {threads!r}")
    t, rows = _imu_rows(imu)
    scans = list(scans)
    if not scans:
        raise Lf3pmError("run_lio needs at least one scan")
    ends = np.array([_scan_end(scan, k) for k, scan in enumerate(scans)])
    if np.any(np.diff(ends) <= 0):
        k = int(np.argmax(np.diff(ends) <= 0)) + 1
        raise Lf3pmError(f"scan ends must increase: scan {k} ends at {ends[k]} s, scan {k - 1} at {ends[k - 1]} s")
    if t[0] > ends[0]:
        raise Lf3pmError(f"the IMU starts at {t[0]} s, after the first scan's end {ends[0]} s")
    settings = _settings(odometry, sensor, imu, params)
    still = settings["imu_calib_time"] if odometry == "dlio" else 0.0
    messages = _rest_warning(t, rows, max(ends[0], t[0] + still))
    bounds = np.searchsorted(t, ends, side="right")

    with tempfile.TemporaryFile() as log:
        reply_read, reply_write = os.pipe()
        try:
            child = subprocess.Popen(
                [sys.executable, _WORKER, str(reply_write)],
                stdin=subprocess.PIPE,
                stdout=log,
                stderr=subprocess.STDOUT,
                pass_fds=(reply_write,),
                env=dict(os.environ, OMP_NUM_THREADS=str(threads)),
            )
        finally:
            os.close(reply_write)
        with os.fdopen(reply_read, "rb") as replies:
            times, poses, status, seconds, version = _drive(
                child, replies, log, scans, ends, t, rows, bounds, sensor, threads, odometry, settings
            )
        log.seek(0)
        messages += [line for line in log.read().decode(errors="replace").splitlines() if line.strip()]

    estimate = origin @ np.linalg.inv(poses[0]) @ poses
    lost = [k for k, s in enumerate(status) if s not in TRACKING + ("initializing",)]
    spec = ODOMETRIES[odometry]
    used = {"threads": threads, "blind_min": sensor.min_range, "blind_max": sensor.max_range}
    if odometry == "genz":
        if version != GENZ_LF3PM_BUILD:  # PyPI's build ignores the initial covariance it is given
            settings = {**settings, "initial_covariance": {"pose_variance": 1.0}}
            messages.insert(
                0,
                f"lf3pm: genz-lio {version} is not lf3pm's build ({GENZ_LF3PM_BUILD}), so it "
                "starts at GenZ-LIO's own initial covariance (1 m, 1 rad): a still narrow-view "
                "sensor's estimate slides before it moves (docs/lio.md, 'A still sensor'); "
                "`make build` installs lf3pm's (third_party/genz_lio)",
            )
            warnings.warn(messages[0], stacklevel=2)
        used |= {"lidar_type": "livox", "overrides": settings}
    else:
        used["settings"] = settings
    return LioEstimate(
        times=times,
        poses=estimate,
        status=status,
        lost=lost,
        seconds_per_scan=float(np.mean(seconds)),
        odometry=spec.name,
        package=spec.package,
        version=version,
        params=used,
        messages=messages,
    )


def _settings(odometry: str, sensor: Sensor, imu, params: dict) -> dict:
    """The odometry's settings: lf3pm's defaults, then ``params`` (GenZ-LIO's merged
    field by field within each section)."""
    if odometry == "dlio":
        return {**DLIO_SETTINGS, **params}
    if odometry == "liosam":
        return {**LIOSAM_SETTINGS, "imu_densities": imu_densities(imu), **params}
    for section, values in params.items():
        if not isinstance(values, dict):
            raise Lf3pmError(
                f"GenZ-LIO settings go by section, e.g. mapping={{'voxel_size': 0.5}}; got {section}={values!r}"
            )
    overrides = {section: dict(values) for section, values in default_settings(sensor).items()}
    overrides["noise_model"] = imu_noise_model(imu)
    for section, values in params.items():
        overrides[section] = {**overrides.get(section, {}), **values}
    return overrides


#: lf3pm's DLIO settings (DLIO's own for the rest): ``imu_calib_time`` 1 s, inside
#: the replay's 2 s rest (DLIO's 3 s would take the start of the motion for a
#: still sensor's IMU).
DLIO_SETTINGS = {"imu_calib_time": 1.0}
#: lf3pm's LIO-SAM settings (evalio's defaults for the rest): ``mappingProcessInterval``
#: 0, every scan matched to the map (LIO-SAM's 0.15 s skips every other 10 Hz scan,
#: which then repeats the pose before it).
LIOSAM_SETTINGS = {"mappingProcessInterval": 0.0}


def default_settings(sensor: Sensor) -> dict:
    """lf3pm's GenZ-LIO settings for ``sensor`` (GenZ-LIO's own for the rest), by
    section; what a caller passes to run_lio overrides them field by field.

    - ``hybrid_metric.enable = False``: point-to-plane residuals only, FAST-LIO2's
      (the paper's). GenZ-LIO's point-to-point residuals drag each scan towards
      where the map's points were sampled from earlier poses: on the demo's
      straight drive out of the gobi town (noise-free, VLP-16) they made the
      estimate lag the truth by 0.15 s (0.155 m RMSE; 0.010 m and no lag without
      them), on a turning Mid-70 drive 0.56 m against 0.010 m (docs/lio.md,
      "The start-of-motion lag").
    - ``mapping.voxel_size`` stays GenZ-LIO's 1 m for every sensor. 0.5 m for the
      Livox Mid-70 held noise-free scans of a still sensor better (its 0.1 s scans at
      1 m jumped 10 cm in the gobi town before the lag was fixed) but let the filter
      run away at 1.7-4.4 m/s from the end of the rest with noisy scans and IMU: on the
      houses street seed 0 17 m RMSE against 0.7 cm at 1 m, on a benefit-study diff
      plan in the gobi 1.1-9.6 m against 2.6-5.1 cm (0.75 m: still 1.7 m on one of two
      seeds). The price: in the tunnel scene, degenerate along its axis, 11-27 cm
      instead of 3-5 cm (bench/compare_odometries.py --settings, docs/lio.md).
    - ``initial_covariance.pose_variance`` GENZ_INIT_POSE_VARIANCE instead of
      GenZ-LIO's 1 (a setting of lf3pm's build of GenZ-LIO only, third_party/genz_lio).
    """
    return {"hybrid_metric": {"enable": False}, "initial_covariance": {"pose_variance": GENZ_INIT_POSE_VARIANCE}}


def imu_noise_model(imu) -> dict:
    """GenZ-LIO's IMU process noise for samples made by simulate_imu: their
    preset at their rate, variances times NOISE_INFLATION; empty (GenZ-LIO's
    defaults) for other IMU data.

    GenZ-LIO (IKFoM) adds (dt F_w) Q (dt F_w)^T per IMU step, so a white noise
    of per-sample sigma enters as a variance sigma^2 (acc_cov, gyr_cov) and a
    random walk of density K as K^2 * rate (b_acc_cov, b_gyr_cov).
    """
    preset, rate = getattr(imu, "preset", None), getattr(imu, "rate", None)
    if not isinstance(preset, ImuPreset) or rate is None:
        return {}
    sigma = preset.sigmas(float(rate))
    exact = {
        "acc_cov": sigma["accel_white"] ** 2,
        "gyr_cov": sigma["gyro_white"] ** 2,
        "b_acc_cov": (sigma["accel_bias_step"] * rate) ** 2,
        "b_gyr_cov": (sigma["gyro_bias_step"] * rate) ** 2,
    }
    # A noiseless preset says nothing about a real IMU: GenZ-LIO's defaults stay for those terms.
    return {key: NOISE_INFLATION * value for key, value in exact.items() if value > 0}


def imu_densities(imu) -> dict:
    """LIO-SAM's IMU noise (evalio's ImuParams: GTSAM's continuous-time densities) for
    samples made by simulate_imu: their preset's; empty (evalio's defaults) for other
    IMU data and for a noiseless preset's zero terms."""
    preset = getattr(imu, "preset", None)
    if not isinstance(preset, ImuPreset):
        return {}
    densities = {
        "accel": preset.accel_noise_density,
        "gyro": preset.gyro_noise_density,
        "accel_bias": preset.accel_bias_random_walk,
        "gyro_bias": preset.gyro_bias_random_walk,
    }
    return {key: value for key, value in densities.items() if value > 0}


def _drive(child, replies, log, scans, ends, t, rows, bounds, sensor, threads, odometry, settings):
    """Streams the scans to the worker and collects its poses and their times."""

    def request(message):
        try:
            pickle.dump(message, child.stdin, protocol=pickle.HIGHEST_PROTOCOL)
            child.stdin.flush()
        except BrokenPipeError:
            pass  # the worker died; reading its reply says how

    def reply(where):
        try:
            answer = pickle.load(replies)
        except (EOFError, pickle.UnpicklingError):
            code = child.wait()
            log.seek(0)
            tail = " | ".join(log.read().decode(errors="replace").strip().splitlines()[-3:])
            how = f"signal {-code}" if code < 0 else f"exit status {code}"
            raise Lf3pmError(f"{spec.name} crashed ({how}) {where}" + (f": {tail}" if tail else "")) from None
        if answer[0] == "error":
            child.wait()
            raise Lf3pmError(answer[1])
        return answer

    spec = ODOMETRIES[odometry]
    try:
        request(
            (
                "config",
                odometry,
                (float(sensor.min_range), float(sensor.max_range)),
                threads,
                settings,
                lidar_geometry(sensor),
            )
        )
        _, version = reply("while starting")
        version = version.split()[0]
        if version.split("+")[0] != spec.version:
            raise Lf3pmError(
                f"{spec.package} {version} is installed; lf3pm's conventions are checked for {spec.version}"
            )
        results, seconds = [], []
        for k, scan in enumerate(scans):
            points, stamps = _scan_arrays(scan, k, ends[k])
            begin = float(stamps[0]) if len(stamps) else float(ends[k])
            lo = bounds[k - 1] if k else 0
            request(
                (
                    "scan",
                    points,
                    begin,
                    float(ends[k]),
                    stamps - begin,
                    np.column_stack([t[lo : bounds[k]], rows[lo : bounds[k]]]),
                )
            )
            _, done, spent = reply(f"at scan {k} (ending at {ends[k]:g} s)")
            results += done
            seconds.append(spent)
        request(("done", np.column_stack([t[bounds[-1] :], rows[bounds[-1] :]])))
        _, done, spent = reply("after the last scan")
        results += done
        seconds[-1] += spent
        child.stdin.close()
        child.wait()
        if len(results) != len(scans):
            raise Lf3pmError(f"{spec.name} returned {len(results)} poses for {len(scans)} scans")
        poses, times, status = zip(*results)
        return np.array(times), np.array(poses), list(status), seconds, version
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()


def lidar_geometry(sensor: Sensor) -> dict:
    """What a ring-organised odometry (LIO-SAM) needs of ``sensor``: its beams'
    elevations (rad), lowest first, and rays per beam and scan; beams None for a
    sensor without rings (Livox)."""
    rings = spinning_rings(sensor)
    if rings is None:
        return {"beams": None, "columns": None}
    _, elevation = sensor.angles()
    beams = int(rings.max()) + 1
    return {"beams": np.sort(elevation[:beams]).tolist(), "columns": sensor.num_rays // beams}


def _imu_rows(imu) -> tuple[np.ndarray, np.ndarray]:
    """(t (K,), accel and gyro (K, 6)) of ``imu``, checked."""
    try:
        t = np.asarray(imu.t, dtype=np.float64)
        accel = np.asarray(imu.accel, dtype=np.float64)
        gyro = np.asarray(imu.gyro, dtype=np.float64)
    except (AttributeError, TypeError, ValueError):
        raise Lf3pmError("imu must have t (K,), accel (K, 3) and gyro (K, 3) (lf3pm ImuSamples)") from None
    if t.ndim != 1 or len(t) < 2 or accel.shape != (len(t), 3) or gyro.shape != (len(t), 3):
        raise Lf3pmError(
            f"imu needs t (K,), accel (K, 3), gyro (K, 3) with K >= 2, got shapes "
            f"{t.shape}, {accel.shape}, {gyro.shape}"
        )
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(accel)) and np.all(np.isfinite(gyro))):
        raise Lf3pmError("imu has non-finite values")
    if np.any(np.diff(t) <= 0):
        raise Lf3pmError("imu times must increase strictly")
    return t, np.hstack([accel, gyro])


def _scan_end(scan, k) -> float:
    try:
        end = float(scan.end)
    except (AttributeError, TypeError, ValueError):
        raise Lf3pmError(f"scan {k} has no numeric 'end' (scans need end, points, stamps)") from None
    if not math.isfinite(end):
        raise Lf3pmError(f"scan {k} ends at a non-finite time {end}")
    return end


def _scan_arrays(scan, k, end) -> tuple[np.ndarray, np.ndarray]:
    """The scan's points (H, 3) and stamps (H,), checked."""
    try:
        points = np.ascontiguousarray(scan.points, dtype=np.float64)
        stamps = np.ascontiguousarray(scan.stamps, dtype=np.float64)
    except (AttributeError, TypeError, ValueError):
        raise Lf3pmError(f"scan {k} needs points (H, 3) and stamps (H,)") from None
    if points.ndim != 2 or points.shape[1] != 3 or stamps.shape != (len(points),):
        raise Lf3pmError(f"scan {k}: points must be (H, 3) and stamps (H,), got {points.shape} and {stamps.shape}")
    if not (np.all(np.isfinite(points)) and np.all(np.isfinite(stamps))):
        raise Lf3pmError(f"scan {k} has non-finite points or stamps")
    if len(stamps) and (np.any(np.diff(stamps) < 0) or stamps[-1] > end + 1e-9):
        raise Lf3pmError(f"scan {k}: stamps must be non-decreasing and <= its end {end} s")
    return points, stamps


def _rest_warning(t, rows, end) -> list:
    """A warning when the IMU moves while the odometry initialises (its first 21
    samples and those up to ``end``: the first scan's end, or the end of DLIO's
    calibration), during which it takes the IMU to be still."""
    window = rows[: max(21, int(np.searchsorted(t, end, side="right")))]
    spread = np.ptp(window[:, :3], axis=0).max()
    rate = np.abs(window[:, 3:]).max()
    if spread > 1.0 or rate > 0.05:
        return [
            f"lf3pm: the IMU is not still during the odometry's initialisation (accel spread "
            f"{spread:.2f} m/s^2, |gyro| up to {rate:.3f} rad/s): its gravity and bias estimates start wrong"
        ]
    return []
