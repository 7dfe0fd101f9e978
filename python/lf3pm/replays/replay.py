"""``replay``: a planned trajectory replayed with simulated sensors through a
state estimator, scored against the truth (docs/replay.md).

One scan stream (scans.py) along one motion (motion.py) feeds the method:

- ``localization``: registration to the prior map from a wheel-odometry
  prediction, keeping the prediction where registration is degenerate
  (localization.py) -- the deployment a SOLM is made for;
- ``lio``: a simulated IMU (imu.py) and the scans through a LiDAR-inertial
  odometry from PyPI (lio.py);
- ``odometry``: LiDAR-only KISS-ICP (odometry.py).

Every method starts at the true first pose and returns a :class:`ReplayResult`.
"""

from __future__ import annotations

import math
import os
import time

from lf3pm.config import DEFAULTS, REPLAY_METHODS, ReplayConfig, ScanConfig, validated
from lf3pm.errors import Lf3pmError
from lf3pm.map import Map, as_map
from lf3pm.replays.localization import (
    DEGENERATE_STD,
    MAX_CORRESPONDENCE_DISTANCE,
    MAX_ITERATIONS,
    MIN_POINTS,
    SCAN_VOXEL,
    WheelOdometry,
    localization_params,
    localize,
)
from lf3pm.replays.motion import Motion, RestFirst
from lf3pm.replays.odometry import kiss_icp_params, run_kiss_icp
from lf3pm.replays.replay_result import (
    Estimate,
    ReplayResult,
    ReplaySeries,
    estimate_times,
    library_versions,
    median_figures,
    rest_motion,
)
from lf3pm.scan.scans import ScanStream
from lf3pm.sensors import Sensor, get_sensor, spinning_rings
from lf3pm.validation.mde import RegistrationTarget

METHODS = REPLAY_METHODS

#: Seconds the sensor stands still at the first pose before a ``lio`` replay's trajectory
#: (scored from the trajectory's start): GenZ-LIO, like FAST-LIO2, initialises gravity and
#: the IMU biases from its first samples as those of a still sensor, as a robot starts.
#: Without it, a plan that turns on the spot at once put 1.0-1.2 m of error into the first
#: 1.5 s of the reduced Gobi scene (0.3-0.4 m for one that drove straight off).
LIO_REST = 2.0

#: Each method's parameters and defaults (docs/replay.md says why).
METHOD_PARAMS = {
    "localization": {
        "scale_error": WheelOdometry.scale_error,
        "yaw_noise": WheelOdometry.yaw_noise,
        "scan_voxel": SCAN_VOXEL,
        "degenerate_std": DEGENERATE_STD,
        "remap": True,
        "max_correspondence_distance": MAX_CORRESPONDENCE_DISTANCE,
        "max_iterations": MAX_ITERATIONS,
        "min_points": MIN_POINTS,
        "registration_threads": 1,
    },
    "odometry": {
        "voxel_size": DEFAULTS.kiss_icp.voxel_size,
        "min_points": DEFAULTS.kiss_icp.min_points,
        "deskew": True,
    },
    "lio": {
        "imu_rate": DEFAULTS.replay.imu_rate,
        "imu_preset": None,
        "imu_noise": DEFAULTS.replay.imu_noise,
        "rest": LIO_REST,
    },
}


def resolve_sensor(sensor: Sensor | str, rate: float) -> Sensor:
    """The sensor of a replay at ``rate`` Hz: a non-repetitive (Livox or pattern)
    sensor integrates over one period, 1 / rate s; a spinning sensor keeps its
    columns (its model is one revolution whatever the rate)."""
    if isinstance(sensor, Sensor):
        return sensor
    base = get_sensor(sensor)
    if spinning_rings(base) is not None or not (math.isfinite(rate) and rate > 0):
        return base
    return get_sensor(sensor, integration_time=1.0 / rate)


def check_method(method: str, params: dict) -> dict:
    """The method's parameters: its defaults updated by ``params``. Raises
    Lf3pmError for an unknown method or parameter."""
    if method not in METHODS:
        raise Lf3pmError(f"unknown method {method!r}; use one of {', '.join(METHODS)}")
    defaults = METHOD_PARAMS[method]
    unknown = sorted(set(params) - set(defaults))
    if unknown and method != "lio":  # the LIO passes the rest to run_lio
        raise Lf3pmError(f"unknown parameter(s) for {method}: {', '.join(unknown)}; known: {', '.join(defaults)}")
    return {**defaults, **params}


def replay(
    map: Map | str,
    motion_or_csv,
    sensor: Sensor | str = DEFAULTS.sensor,
    method: str = DEFAULTS.replay.method,
    seed: int = DEFAULTS.scan.seed,
    *,
    rate: float = DEFAULTS.replay.rate,
    height: float = DEFAULTS.replay.height,
    noise: float | None = DEFAULTS.scan.noise,
    target: RegistrationTarget | None = None,
    threads: int = DEFAULTS.scan.threads,
    progress=None,
    **params,
) -> ReplayResult:
    """Replays a trajectory with ``method`` (module docstring) and scores it.

    ``map``: a Map or a map file. ``motion_or_csv``: a :class:`Motion`, the
    CSV ``lf3pm plan`` writes, or a planner Trajectory or Plan (the sensor
    ``height`` m above the smooth ground).
    ``sensor``: a preset name, YAML file or Sensor. ``seed``: the scans' range
    noise (scan k: stream k), the wheel odometry's and the IMU's noise.
    ``rate``: scans per second. ``noise``: range noise sigma (m; default the
    sensor's). ``target``: the map prepared for registration (localization),
    reusable across replays of one map. ``threads``: scan simulation (0 = all
    cores). ``progress(done, total)`` is called after each scan. ``params``:
    the method's own (``METHOD_PARAMS``; lio passes unknown ones to run_lio).
    Raises Lf3pmError for bad input.
    """
    params = check_method(method, params)
    map, sensor, motion, scans, first = _stream(
        map, motion_or_csv, sensor, method, seed, rate, height, noise, threads, params
    )
    rate = scans.rate
    common = {
        "rate": float(rate),
        "seed": int(seed),
        "noise": scans.noise,
        "noise_stream": "scan index",
        "height": motion.height,
        "ground": {
            "cell": motion.ground.cell,
            "smoothing": motion.ground.smoothing,
            "max_step": motion.ground.max_step,
        },
        "span_s": [motion.t0, motion.t1],
    }
    if method == "localization":
        target = RegistrationTarget.for_map(map, target, threads)
        odometry = WheelOdometry(params["scale_error"], params["yaw_noise"])
        settings = {
            k: params[k]
            for k in (
                "scan_voxel",
                "degenerate_std",
                "remap",
                "max_correspondence_distance",
                "max_iterations",
                "min_points",
            )
        }
        run = localize(
            scans,
            target,
            sensor,
            odometry=odometry,
            seed=seed,
            threads=params["registration_threads"],
            progress=progress,
            **settings,
        )
        method_params = localization_params(odometry, **settings)
        versions = library_versions("small_gicp")
    elif method == "odometry":
        run = run_kiss_icp(
            scans,
            sensor,
            scans.truth[0],
            voxel_size=params["voxel_size"],
            deskew=params["deskew"],
            min_points=params["min_points"],
            threads=threads,
            progress=progress,
        )
        method_params = {
            "min_points": params["min_points"],
            "kiss_icp": kiss_icp_params(sensor, params["voxel_size"], params["deskew"]),
        }
        versions = library_versions("kiss-icp")
    else:
        run, method_params, versions = _lio(scans, motion, sensor, seed, params)
    return ReplayResult.from_run(
        run,
        method=method,
        sensor=sensor.name,
        seed=int(seed),
        scans=scans,
        first=first,
        params={**common, method: method_params},
        map_sha256=map.sha256,
        versions=versions,
    )


def replay_seeds(
    map: Map | str,
    motion_or_csv,
    sensor: Sensor | str = DEFAULTS.sensor,
    method: str = DEFAULTS.replay.method,
    seeds: int = DEFAULTS.replay.seeds,
    seed: int = DEFAULTS.scan.seed,
    *,
    rate: float = DEFAULTS.replay.rate,
    height: float = DEFAULTS.replay.height,
    noise: float | None = DEFAULTS.scan.noise,
    threads: int = DEFAULTS.scan.threads,
    progress=None,
    **params,
) -> ReplaySeries:
    """:func:`replay` on seeds ``seed`` .. ``seed + seeds - 1`` (what ``lf3pm replay
    --seeds`` runs): the map, the motion and the registration target prepared once, and
    the median of each reported figure. ``progress(seed, done, total)`` after each scan."""
    run = validated(ReplayConfig, "replay", method=method, seeds=seeds, rate=rate, height=height)
    validated(ScanConfig, "scan", noise=noise, seed=seed, threads=threads)
    map = as_map(map, threads)
    motion = _motion(motion_or_csv, map, run.height)
    target = RegistrationTarget(map, threads=threads) if method == "localization" else None
    results = []
    for s in range(seed, seed + run.seeds):
        tick = None if progress is None else (lambda done, total, s=s: progress(s, done, total))
        results.append(
            replay(
                map,
                motion,
                sensor,
                method,
                s,
                rate=run.rate,
                height=run.height,
                noise=noise,
                target=target,
                threads=threads,
                progress=tick,
                **params,
            )
        )
    return ReplaySeries(results=results, median=median_figures(results))


def replay_bag(
    path,
    map: Map | str,
    motion_or_csv,
    sensor: Sensor | str = DEFAULTS.sensor,
    *,
    seed: int = DEFAULTS.scan.seed,
    rate: float = DEFAULTS.replay.rate,
    height: float = DEFAULTS.replay.height,
    noise: float | None = DEFAULTS.scan.noise,
    threads: int = DEFAULTS.scan.threads,
    progress=None,
) -> dict:
    """Writes the stream a replay of seed ``seed`` simulates (scans, the IMU of the lio
    method, the truth) as a ROS 2 bag at ``path`` (bag.py); returns what write_bag says."""
    from lf3pm.replays.bag import write_bag

    lio_modules("a bag (it carries the simulated IMU)")
    map = as_map(map, threads)
    motion = _motion(motion_or_csv, map, height)
    scans = ScanStream(map, motion, resolve_sensor(sensor, rate), rate=rate, seed=seed, noise=noise, threads=threads)
    imu = simulated_imu(motion, seed, METHOD_PARAMS["lio"])
    return write_bag(path, scans, imu, progress=progress)


def _motion(source, map: Map, height: float) -> Motion:
    """The Motion of a Motion, a trajectory CSV, a planner Trajectory or a Plan (its
    trajectory sampled at 100 Hz, as `lf3pm plan` writes its CSV)."""
    if isinstance(source, Motion):
        return source
    if isinstance(source, (str, os.PathLike)):
        return Motion.from_csv(source, map, height=height)
    trajectory = getattr(source, "trajectory", source)  # a Plan carries its Trajectory
    if not callable(getattr(trajectory, "sample", None)):
        raise Lf3pmError(
            f"replay takes a Motion, a trajectory CSV, a Trajectory or a Plan, got {type(source).__name__}"
        )
    s = trajectory.sample()  # at the CSV's rate (planner.trajectory.CSV_RATE)
    return Motion.from_arrays(s["t"], s["x"], s["y"], s["yaw"], s["vx"], s["vy"], s["omega"], map=map, height=height)


def replay_rest(
    map: Map | str,
    motion_or_csv,
    sensor: Sensor | str = DEFAULTS.sensor,
    seed: int = DEFAULTS.scan.seed,
    *,
    rate: float = DEFAULTS.replay.rate,
    height: float = DEFAULTS.replay.height,
    noise: float | None = DEFAULTS.scan.noise,
    threads: int = DEFAULTS.scan.threads,
    **params,
) -> dict:
    """What the LIO does while the sensor stands still before the trajectory: the
    ``rest`` that :func:`replay` with method lio and the same arguments reports,
    for the cost of the rest alone (the same scans, IMU samples and estimates: the
    stream up to the trajectory's start does not depend on what follows, and the
    odometry only looks back). Raises Lf3pmError for bad input or a zero rest."""
    params = check_method("lio", params)
    if not params["rest"] > 0:
        raise Lf3pmError("replay_rest needs a rest before the trajectory (rest > 0 s)")
    _, sensor, motion, scans, first = _stream(
        map, motion_or_csv, sensor, "lio", seed, rate, height, noise, threads, params, rest_only=True
    )
    run, _, _ = _lio(scans, motion, sensor, seed, params)
    times, truth = estimate_times(run, scans)
    return rest_motion(times[: first + 1], truth[: first + 1], run.poses[: first + 1])


def _stream(map, motion_or_csv, sensor, method, seed, rate, height, noise, threads, params, rest_only=False):
    """(Map, Sensor, motion, ScanStream, index of the trajectory's first scan) of a replay,
    the arguments validated; the LIO's motion starts with its rest."""
    run = validated(ReplayConfig, "replay", method=method, rate=rate, height=height)
    noise = validated(ScanConfig, "scan", noise=noise, seed=seed, threads=threads).noise
    map = as_map(map)
    sensor = resolve_sensor(sensor, run.rate)
    motion = _motion(motion_or_csv, map, run.height)
    first = 0
    if method == "lio" and params["rest"] > 0:
        motion = RestFirst(motion, params["rest"], rest_only=rest_only)
        first = int(math.floor(params["rest"] * run.rate + 1e-9))  # the scans before the trajectory starts
    scans = ScanStream(map, motion, sensor, rate=run.rate, seed=seed, noise=noise, threads=threads)
    return map, sensor, motion, scans, first


def lio_modules(needed_by: str = "method lio"):
    """(simulate_imu, run_lio), or Lf3pmError (naming what ``needed_by`` them)
    when the IMU simulation or the LIO is not available."""
    try:
        from lf3pm.replays.imu import simulate_imu
        from lf3pm.replays.lio import run_lio
    except ImportError as err:
        raise Lf3pmError(f"{needed_by} is not available: {err}") from None
    return simulate_imu, run_lio


def simulated_imu(motion: Motion, seed: int, params: dict):
    """The IMU stream of a replay (the same for the LIO and the bag)."""
    simulate_imu, _ = lio_modules()
    options = {"rate": float(params["imu_rate"]), "seed": int(seed), "noise": bool(params["imu_noise"])}
    if params["imu_preset"] is not None:
        options["preset"] = params["imu_preset"]
    return simulate_imu(motion, **options)


def _lio(scans: ScanStream, motion: Motion, sensor: Sensor, seed: int, params: dict):
    _, run_lio = lio_modules()
    imu = simulated_imu(motion, seed, params)
    extra = {k: v for k, v in params.items() if k not in METHOD_PARAMS["lio"]}
    simulated_before, start = scans.seconds, time.perf_counter()
    try:
        out = run_lio(scans, imu, sensor, initial_pose=scans.truth[0], **extra)
    except ImportError as err:
        raise Lf3pmError(f"method lio is not available: {err}") from None
    # run_lio pulls the scans, so their simulation happened inside it.
    seconds = time.perf_counter() - start - (scans.seconds - simulated_before)
    report = {k: v for k, v in _fields(out).items() if k not in ("times", "poses")}
    name = str(report.get("package", "lio"))
    run = Estimate(
        poses=out.poses,
        hits=scans.hits.copy(),
        skipped=list(report.pop("skipped", [])),
        seconds=seconds,
        report=report,
        times=getattr(out, "times", None),
    )
    method_params = {"imu": {k: params[k] for k in METHOD_PARAMS["lio"]}, "options": extra}
    return run, method_params, {**library_versions(), name: report.get("version")}


def _fields(out) -> dict:
    """The public attributes of run_lio's result."""
    from dataclasses import asdict, is_dataclass

    if is_dataclass(out):
        return asdict(out)
    return {k: v for k, v in vars(out).items() if not k.startswith("_")}
