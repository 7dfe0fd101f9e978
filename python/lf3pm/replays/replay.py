"""``replay``: a planned trajectory replayed with simulated sensors through a state
estimator (a replay method: methods.py), scored against the truth (docs/replay.md).

One scan stream (scans.py) along one motion (a ground robot's, motion.py, or a
quadrotor's flight, flight_motion.py) feeds the method, which starts at the true first
pose; every method's run becomes a :class:`ReplayResult`.
"""

from __future__ import annotations

import math
import os

from lf3pm.config import DEFAULTS, ReplayConfig, ScanConfig, validated
from lf3pm.errors import Lf3pmError
from lf3pm.map import Map, as_map
from lf3pm.replays.flight_motion import FlightMotion
from lf3pm.replays.lio import Lio
from lf3pm.replays.methods import METHODS as _METHODS
from lf3pm.replays.methods import ReplayMethod, replay_method
from lf3pm.replays.motion import Motion, RestFirst
from lf3pm.replays.replay_result import ReplayResult, ReplaySeries, estimate_times, median_figures, rest_motion
from lf3pm.scan.scans import ScanStream
from lf3pm.sensors import Sensor, get_sensor, spinning_rings
from lf3pm.validation.mde import RegistrationTarget

#: The replay methods' names (methods.METHODS holds the methods).
METHODS = tuple(_METHODS)


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


def replay(
    map: Map | str,
    motion_or_csv,
    sensor: Sensor | str = DEFAULTS.sensor,
    method: str | ReplayMethod = DEFAULTS.replay.method,
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
    """Replays a trajectory with ``method`` and scores it.

    ``method``: a name of methods.METHODS, made from ``params``, or a method made
    already (e.g. ``METHODS[name].from_config(config)``, ``Localization(section)``).
    ``map``: a Map or a map file. ``motion_or_csv``: a :class:`Motion`, the
    CSV ``lf3pm plan`` writes, or a planner Trajectory or Plan (the sensor
    ``height`` m above the smooth ground), or a quadrotor's :class:`FlightMotion`.
    ``sensor``: a preset name, YAML file or Sensor. ``seed``: the scans' range
    noise (scan k: stream k), the wheel odometry's and the IMU's noise.
    ``rate``: scans per second. ``noise``: range noise sigma (m; default the
    sensor's). ``target``: the map prepared for registration (localization),
    reusable across replays of one map. ``threads``: scan simulation (0 = all
    cores). ``progress(done, total)`` is called after each scan. ``params``:
    the method's settings over their defaults (methods.py: the ``localization`` and
    ``kiss_icp`` sections' fields; lio: the ``replay`` section's imu_rate, imu_preset,
    imu_noise and rest, then run_lio's: ``odometry`` and the odometry's settings).
    Raises Lf3pmError for bad input.
    """
    chosen = replay_method(method, params)
    map, sensor, motion, scans, first = _stream(map, motion_or_csv, sensor, chosen, seed, rate, height, noise, threads)
    common = {
        "rate": float(scans.rate),
        "seed": int(seed),
        "noise": scans.noise,
        "noise_stream": "scan index",
        **_motion_params(motion),
        "span_s": [motion.t0, motion.t1],
    }
    prepared = chosen.prepare(map, threads, target)
    run, method_params, versions = chosen.run(
        scans, motion, sensor, seed, prepared=prepared, threads=threads, progress=progress
    )
    return ReplayResult.from_run(
        run,
        method=chosen.name,
        sensor=sensor.name,
        seed=int(seed),
        scans=scans,
        first=first,
        params={**common, chosen.name: method_params},
        map_sha256=map.sha256,
        versions=versions,
        replay=_replay_section(chosen),
    )


def replay_seeds(
    map: Map | str,
    motion_or_csv,
    sensor: Sensor | str = DEFAULTS.sensor,
    method: str | ReplayMethod = DEFAULTS.replay.method,
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
    chosen = replay_method(method, params)
    run = validated(ReplayConfig, "replay", method=chosen.name, seeds=seeds, rate=rate, height=height)
    validated(ScanConfig, "scan", noise=noise, seed=seed, threads=threads)
    map = as_map(map, threads)
    motion = _motion(motion_or_csv, map, run.height)
    target = chosen.prepare(map, threads)  # the map prepared once for every seed
    results = []
    for s in range(seed, seed + run.seeds):
        tick = None if progress is None else (lambda done, total, s=s: progress(s, done, total))
        results.append(
            replay(
                map,
                motion,
                sensor,
                chosen,
                s,
                rate=run.rate,
                height=run.height,
                noise=noise,
                target=target,
                threads=threads,
                progress=tick,
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
    lio: Lio | None = None,
    progress=None,
) -> dict:
    """Writes the stream a replay of seed ``seed`` simulates (scans, the IMU of the lio
    method ``lio``, None: the defaults', and the truth) as a ROS 2 bag at ``path``
    (bag.py); returns what write_bag says."""
    from lf3pm.replays.bag import write_bag

    map = as_map(map, threads)
    motion = _motion(motion_or_csv, map, height)
    if isinstance(motion, FlightMotion):  # the bag's truth and frames are a level robot's
        raise Lf3pmError("replay_bag writes ground robots' replays only, not a flight's")
    scans = ScanStream(map, motion, resolve_sensor(sensor, rate), rate=rate, seed=seed, noise=noise, threads=threads)
    imu = (lio or Lio()).imu(motion, seed)
    return write_bag(path, scans, imu, progress=progress)


def _motion_params(motion) -> dict:
    """What a replay records of its motion: a flight's quadrotor (its mount too), or a
    ground robot's sensor height and smooth ground."""
    quadrotor = getattr(motion, "quadrotor", None)
    if quadrotor is not None:
        return {"flight": {"quadrotor": quadrotor.model_dump()}}
    return {
        "height": motion.height,
        "ground": {
            "cell": motion.ground.cell,
            "smoothing": motion.ground.smoothing,
            "max_step": motion.ground.max_step,
        },
    }


def _motion(source, map: Map, height: float) -> Motion | FlightMotion:
    """The motion of a Motion or a FlightMotion (itself), a trajectory CSV, a planner
    Trajectory or a Plan (its trajectory sampled at 100 Hz, as `lf3pm plan` writes its
    CSV)."""
    if isinstance(source, (Motion, FlightMotion)):
        return source
    if isinstance(source, (str, os.PathLike)):
        return Motion.from_csv(source, map, height=height)
    trajectory = getattr(source, "trajectory", source)  # a Plan carries its Trajectory
    if not callable(getattr(trajectory, "sample", None)):
        raise Lf3pmError(
            "replay takes a Motion, a FlightMotion, a trajectory CSV, a Trajectory or a Plan, "
            f"got {type(source).__name__}"
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
    lio = Lio.from_params(params)
    if not lio.rest > 0:
        raise Lf3pmError("replay_rest needs a rest before the trajectory (rest > 0 s)")
    _, sensor, motion, scans, first = _stream(
        map, motion_or_csv, sensor, lio, seed, rate, height, noise, threads, rest_only=True
    )
    run = lio.run(scans, motion, sensor, seed, prepared=None, threads=threads).estimate
    times, truth = estimate_times(run, scans)
    return rest_motion(times[: first + 1], truth[: first + 1], run.poses[: first + 1], lio.settings)


def _replay_section(method: ReplayMethod) -> ReplayConfig:
    """The replay section a method runs with (the lio method's own: its rest's limits),
    else the defaults'."""
    settings = getattr(method, "settings", None)
    return settings if isinstance(settings, ReplayConfig) else DEFAULTS.replay


def _stream(map, motion_or_csv, sensor, method: ReplayMethod, seed, rate, height, noise, threads, rest_only=False):
    """(Map, Sensor, motion, ScanStream, index of the trajectory's first scan) of a replay,
    the arguments validated; the motion starts with the method's rest."""
    run = validated(ReplayConfig, "replay", method=method.name, rate=rate, height=height)
    noise = validated(ScanConfig, "scan", noise=noise, seed=seed, threads=threads).noise
    map = as_map(map)
    sensor = resolve_sensor(sensor, run.rate)
    motion = _motion(motion_or_csv, map, run.height)
    first = 0
    if method.rest > 0:
        motion = RestFirst(motion, method.rest, rest_only=rest_only)
        first = int(math.floor(method.rest * run.rate + 1e-9))  # the scans before the trajectory starts
    scans = ScanStream(map, motion, sensor, rate=run.rate, seed=seed, noise=noise, threads=threads)
    return map, sensor, motion, scans, first
