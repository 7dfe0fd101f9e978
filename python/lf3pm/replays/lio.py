"""LiDAR-inertial odometry on simulated scans and IMU samples: :func:`run_lio` feeds
one registered odometry (registry.py: GenZ-LIO, DLIO, LIO-SAM or a plugin's) exactly the
same scans and IMU samples, and :class:`Lio` is the ``lio`` replay method around it.
docs/lio.md compares the odometries and says why lf3pm ships these.

Each odometry runs in a child process (_lio_worker.py): their OpenMP runtimes would make
later forks of the caller hang (shared BUILD-NOTES), a crash becomes a clear error here
instead of killing the caller, and GenZ-LIO (GPL-2.0-only) is never imported by lf3pm.
The estimate is anchored as initial_pose @ inv(P_0) @ P_k, P_k the odometry's pose after
scan k.
"""

from __future__ import annotations

import itertools
import math
import os
import pickle
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field

import numpy as np

from lf3pm.config import DEFAULTS, ReplayConfig, validated
from lf3pm.errors import Lf3pmError
from lf3pm.pose import pose_matrix
from lf3pm.replays import registry
from lf3pm.replays.adapters import Odometry
from lf3pm.replays.imu import simulate_imu
from lf3pm.replays.replay_result import Estimate, MethodRun, library_versions
from lf3pm.sensors import Sensor, as_sensor, spinning_rings

DEFAULT_ODOMETRY = DEFAULTS.replay.odometry
_WORKER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_lio_worker.py")
#: Scan statuses that mean the odometry used the scan.
TRACKING = ("ok", "map seeded")


def choose_odometry(odometry: str, sensor: Sensor) -> str:
    """The key of the odometry run for ``odometry`` (a registered one or auto) on
    ``sensor`` (registry.choose_odometry)."""
    return registry.choose_odometry(odometry, sensor).key


def runs_on(odometry: str, sensor: Sensor) -> bool:
    """Whether the registered ``odometry`` can take ``sensor``'s scans."""
    return registry.odometry(odometry).runs_on(sensor)


def __getattr__(name):
    """ODOMETRIES (the registered odometries by key) and LOSES ((key, spinning): the
    warning), read from the registry when asked for: the names callers that index by key
    used before registry.py (the benefit study, tests/test_hostile_inputs.py)."""
    if name == "ODOMETRIES":
        return dict(registry.odometries())
    if name == "LOSES":
        return {
            (key, spinning): text
            for key, adapter in registry.odometries().items()
            for spinning, text in adapter.loses.items()
        }
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
    """The LiDAR-inertial ``odometry`` (a registered one, or "auto":
    registry.choose_odometry) on ``scans`` (each with ``end`` s, ``points`` (H, 3) in the
    sensor frame at their firing times and ``stamps`` (H,) absolute firing times,
    non-decreasing, <= end; ends increasing) and ``imu`` (ImuSamples: t, accel, gyro on
    the same clock, covering the first scan's end; or an iterable of such chunks in time
    order, in the LiDAR's frame). Where the IMU is not at the LiDAR (a flight's, in the
    body), ``imu.extrinsic`` (ImuSamples') gives the LiDAR's pose in the IMU's frame, and
    the odometry is told it (Odometry.takes_extrinsic). Both are streamed: a scan is
    taken when the odometry is ready for it and the IMU samples up to its end with it, so
    memory stays at a few scans (ends checked as they come). ``sensor`` gives the range
    limits.
    ``initial_pose`` (a pose lf3pm.pose accepts): the true pose at the first scan; the
    sensor must be still while the odometry initialises (Odometry.still_for).
    ``threads``: the odometry's OpenMP threads (1: deterministic). ``params``: the
    odometry's settings over lf3pm's (its Settings section): GenZ-LIO's by section, e.g.
    ``mapping={"voxel_size": 0.25}``; DLIO's by name, e.g. ``vf_res=0.5``.
    Raises Lf3pmError for malformed input, an unknown odometry or setting, a
    missing or other version of the odometry's package, or its crash.
    """
    sensor = as_sensor(sensor)
    adapter = registry.choose_odometry(odometry, sensor)
    origin = pose_matrix(initial_pose)
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise Lf3pmError(f"threads must be an integer >= 1, got {threads!r}")
    samples = _ImuRows(imu)
    extrinsic = _imu_extrinsic(imu)
    if not adapter.takes_extrinsic and not np.array_equal(extrinsic, np.eye(4)):
        raise Lf3pmError(
            f"{adapter.name} takes no LiDAR-IMU extrinsic, and these IMU samples are not in the LiDAR's "
            "frame (a flight's IMU is the body's): run one that does (genz, dlio, liosam)"
        )
    scans = iter(scans)
    first = next(scans, None)
    if first is None:
        raise Lf3pmError("run_lio needs at least one scan")
    first_end = _scan_end(first, 0)
    if samples.first > first_end:
        raise Lf3pmError(f"the IMU starts at {samples.first} s, after the first scan's end {first_end} s")
    settings = adapter.worker_settings(adapter.settings(params), sensor, imu)
    messages = _rest_warning(*samples.window(max(first_end, samples.first + adapter.still_for(settings))))

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
            lidar = {**lidar_geometry(sensor), "extrinsic": extrinsic.tolist()}
            times, poses, status, seconds, version = _drive(
                child, replies, log, itertools.chain([first], scans), samples, sensor, lidar, threads, adapter, settings
            )
        log.seek(0)
        messages += [line for line in log.read().decode(errors="replace").splitlines() if line.strip()]

    estimate = origin @ np.linalg.inv(poses[0]) @ poses
    lost = [k for k, s in enumerate(status) if s not in TRACKING + ("initializing",)]
    used = {"threads": threads, "blind_min": sensor.min_range, "blind_max": sensor.max_range}
    if not np.array_equal(extrinsic, np.eye(4)):
        used["extrinsic"] = extrinsic.tolist()
    used |= adapter.recorded(settings, version, messages)
    return LioEstimate(
        times=times,
        poses=estimate,
        status=status,
        lost=lost,
        seconds_per_scan=float(np.mean(seconds)),
        odometry=adapter.name,
        package=adapter.package,
        version=version,
        params=used,
        messages=messages,
    )


def _drive(child, replies, log, scans, samples, sensor, lidar, threads, spec: type[Odometry], settings):
    """Streams the scans, each with the IMU samples (``samples``: _ImuRows) after the
    previous scan's end up to its own, to the worker (``lidar``: what it is told of the
    LiDAR) and collects its poses and their times."""

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

    try:
        request(
            (
                "config",
                spec.worker,
                spec.key,
                (float(sensor.min_range), float(sensor.max_range)),
                threads,
                settings,
                lidar,
                list(sys.path),
                spec.install_hint(),
            )
        )
        _, version = reply("while starting")
        version = version.split()[0]
        if version.split("+")[0] != spec.version:
            raise Lf3pmError(
                f"{spec.package} {version} is installed; lf3pm's conventions are checked for {spec.version}"
            )
        results, seconds, previous = [], [], None
        for k, scan in enumerate(scans):
            end = _scan_end(scan, k)
            if previous is not None and not end > previous:
                raise Lf3pmError(f"scan ends must increase: scan {k} ends at {end} s, scan {k - 1} at {previous} s")
            points, stamps = _scan_arrays(scan, k, end)
            begin = float(stamps[0]) if len(stamps) else end
            request(("scan", points, begin, end, stamps - begin, samples.until(end)))
            _, done, spent = reply(f"at scan {k} (ending at {end:g} s)")
            results += done
            seconds.append(spent)
            previous = end
        request(("done", samples.rest()))
        _, done, spent = reply("after the last scan")
        results += done
        seconds[-1] += spent
        child.stdin.close()
        child.wait()
        if len(results) != len(seconds):
            raise Lf3pmError(f"{spec.name} returned {len(results)} poses for {len(seconds)} scans")
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


def _imu_extrinsic(imu) -> np.ndarray:
    """The LiDAR's pose in the IMU's frame (4, 4) that ``imu`` carries (ImuSamples'
    ``extrinsic``), else the identity (IMU data in the LiDAR's frame, as run_lio's chunks
    are). Raises Lf3pmError for one that is not a rigid transform."""
    value = getattr(imu, "extrinsic", None)
    if value is None:
        return np.eye(4)
    try:
        matrix = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        matrix = np.empty(0)
    rigid = (
        matrix.shape == (4, 4)
        and np.all(np.isfinite(matrix))
        and np.allclose(matrix[:3, :3].T @ matrix[:3, :3], np.eye(3), atol=1e-9)
        and np.linalg.det(matrix[:3, :3]) > 0
        and np.array_equal(matrix[3], [0.0, 0.0, 0.0, 1.0])
    )
    if not rigid:
        raise Lf3pmError("the IMU's extrinsic must be a 4 x 4 rigid transform (the LiDAR's pose in the IMU's frame)")
    return matrix


class _ImuRows:
    """run_lio's IMU samples, handed out in time order: t and the rows (accel, gyro) of
    ``imu`` (ImuSamples, or an iterable of such chunks, read as they are needed and
    checked as they come: times strictly increasing across chunks). Holds the samples
    read and not yet handed out; ``first``: the first sample's time."""

    def __init__(self, imu):
        if hasattr(imu, "t") or not hasattr(imu, "__iter__") or isinstance(imu, (str, bytes)):
            self._chunks = iter([_imu_rows(imu)])
        else:
            self._chunks = (_imu_rows(chunk, minimum=0) for chunk in imu)
        self.t, self.rows, self._last, self._done = np.empty(0), np.empty((0, 6)), -np.inf, False
        self._read(lambda: len(self.t) < 2)
        if len(self.t) < 2:
            raise Lf3pmError(f"imu needs at least 2 samples, got {len(self.t)}")
        self.first = float(self.t[0])

    def _read(self, wanted) -> None:
        """Reads chunks while ``wanted()`` and the IMU has more."""
        while not self._done and wanted():
            chunk = next(self._chunks, None)
            if chunk is None:
                self._done = True
                break
            t, rows = chunk
            if not len(t):
                continue
            if t[0] <= self._last:
                raise Lf3pmError("imu times must increase strictly")
            self._last = t[-1]
            if len(self.t):
                t, rows = np.concatenate([self.t, t]), np.vstack([self.rows, rows])
            self.t, self.rows = t, rows

    def window(self, end: float) -> tuple[np.ndarray, np.ndarray, float]:
        """(t, rows, end) of the samples up to ``end`` and at least the first 21 (none handed out yet)."""
        self._read(lambda: len(self.t) < 21 or self.t[-1] <= end)
        return self.t, self.rows, end

    def until(self, end: float) -> np.ndarray:
        """The rows (t, accel, gyro) up to ``end`` not handed out yet, handed out."""
        self._read(lambda: not len(self.t) or self.t[-1] <= end)
        k = int(np.searchsorted(self.t, end, side="right"))
        out = np.column_stack([self.t[:k], self.rows[:k]])
        self.t, self.rows = self.t[k:], self.rows[k:]
        return out

    def rest(self) -> np.ndarray:
        """Every row not handed out yet."""
        self._read(lambda: True)
        return self.until(np.inf)


def _imu_rows(imu, minimum: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """(t (K,), accel and gyro (K, 6)) of ``imu``, checked (K >= ``minimum``)."""
    try:
        t = np.asarray(imu.t, dtype=np.float64)
        accel = np.asarray(imu.accel, dtype=np.float64)
        gyro = np.asarray(imu.gyro, dtype=np.float64)
    except (AttributeError, TypeError, ValueError):
        raise Lf3pmError("imu must have t (K,), accel (K, 3) and gyro (K, 3) (lf3pm ImuSamples)") from None
    if t.ndim != 1 or len(t) < minimum or accel.shape != (len(t), 3) or gyro.shape != (len(t), 3):
        raise Lf3pmError(
            f"imu needs t (K,), accel (K, 3), gyro (K, 3) with K >= {minimum}, got shapes "
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


#: The lio method's own parameters it records (ReplayConfig's); with REST_PARAMS, the
#: replay section's it takes by name: the rest are run_lio's (the odometry and its settings).
IMU_PARAMS = ("imu_rate", "imu_preset", "imu_noise", "rest")
REST_PARAMS = ("rest_window", "rest_speed_limit")


class Lio:
    """The ``lio`` replay method (lf3pm.replays.methods.ReplayMethod): the sensor stands
    still for ``settings.rest`` s at the first pose (RestFirst), then the simulated IMU
    (imu.py) and the scans go through :func:`run_lio` with ``options`` (the odometry and
    its settings), over the settings ``settings.odometries`` gives the odometry run
    (those that differ from lf3pm's: registry.changed_settings)."""

    name = "lio"
    uses_odometry = True

    def __init__(self, settings: ReplayConfig = DEFAULTS.replay, options: dict | None = None):
        self.settings = settings
        self.options = dict(options or {})

    @classmethod
    def from_params(cls, params: dict) -> Lio:
        """The method of ``params``: IMU_PARAMS over the replay section's defaults, the rest
        for run_lio (an odometry's name checked against the registry here)."""
        own = {k: v for k, v in params.items() if k in IMU_PARAMS + REST_PARAMS}
        options = {k: v for k, v in params.items() if k not in IMU_PARAMS + REST_PARAMS}
        named = options.get("odometry")
        if named is not None:
            registry.check_name(named)
        return cls(validated(ReplayConfig, "replay", **{**DEFAULTS.replay.model_dump(), **own}), options)

    @classmethod
    def from_config(cls, config) -> Lio:
        """The method of a whole configuration: its replay section, its odometry and the
        odometries' settings (checked by their sections: registry.settings)."""
        registry.settings(config.replay.odometries)
        return cls(config.replay, {"odometry": registry.check_name(config.replay.odometry)})

    @property
    def rest(self) -> float:
        return self.settings.rest

    def prepare(self, map, threads: int, prepared=None):
        return None

    def imu(self, motion, seed: int):
        """The IMU stream of a replay (the same for the LIO and the bag)."""
        s = self.settings
        options = {"rate": float(s.imu_rate), "seed": int(seed), "noise": bool(s.imu_noise)}
        if s.imu_preset is not None:
            options["preset"] = s.imu_preset
        return simulate_imu(motion, **options)

    def run(self, scans, motion, sensor: Sensor, seed: int, *, prepared, threads: int, progress=None) -> MethodRun:
        imu = self.imu(motion, seed)
        options = self.odometry_options(sensor)
        simulated_before, start = scans.seconds, time.perf_counter()
        out = run_lio(scans, imu, sensor, initial_pose=scans.truth[0], **options)
        # run_lio pulls the scans, so their simulation happened inside it.
        seconds = time.perf_counter() - start - (scans.seconds - simulated_before)
        report = {k: v for k, v in _fields(out).items() if k not in ("times", "poses")}
        name = str(report.get("package", self.name))
        run = Estimate(
            poses=out.poses,
            hits=scans.hits.copy(),
            skipped=list(report.pop("skipped", [])),
            seconds=seconds,
            report=report,
            times=getattr(out, "times", None),
        )
        imu_params = {k: getattr(self.settings, k) for k in IMU_PARAMS}
        params = {"imu": imu_params, "options": options}
        return MethodRun(run, params, {**library_versions(), name: report.get("version")})

    def odometry_options(self, sensor: Sensor) -> dict:
        """run_lio's options on ``sensor``: ``options``, over the settings the replay
        section gives the odometry run there that differ from lf3pm's."""
        given = self.settings.odometries
        if not given:
            return dict(self.options)
        key = registry.choose_odometry(self.options.get("odometry", DEFAULT_ODOMETRY), sensor).key
        options = dict(self.options)
        for name, value in registry.changed_settings(key, given.get(key, {})).items():
            options.setdefault(name, value)
        return options


def _fields(out) -> dict:
    """The public attributes of run_lio's result."""
    from dataclasses import asdict, is_dataclass

    if is_dataclass(out):
        return asdict(out)
    return {k: v for k, v in vars(out).items() if not k.startswith("_")}
