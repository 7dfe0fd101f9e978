"""Child process of lf3pm.replays.lio: runs one LiDAR-inertial odometry (GenZ-LIO,
or DLIO or LIO-SAM from evalio, or a plugin's) on the scans the parent streams to it, so
that the odometry's OpenMP runtime, its console output and a crash stay out of the
caller's process, and so that lf3pm (BSD) never imports GenZ-LIO (GPL-2.0-only) itself.

Run as a script: ``python _lio_worker.py REPLY_FD``; lf3pm's own odometries run without
importing lf3pm. Protocol, pickled objects: on stdin ("config", worker, key,
sensor_range, threads, settings, lidar, paths, install), then ("scan", points, begin, end,
offsets, imu) per scan and ("done", imu) with the IMU samples after the last scan; on
REPLY_FD ("ready", version) or ("error", message), then one ("poses", [(pose, time,
status), ...], seconds) per scan and one after "done": the poses the odometry finished
with that message, in scan order, each with the time it refers to (GenZ-LIO and DLIO one
per scan; LIO-SAM two scans late, the last two at "done"). ``worker``: "module:Class" of
the class to run (lf3pm.replays.adapters: the interface), this module's own classes by
``lf3pm.replays._lio_worker``; ``paths``: the parent's sys.path, where a plugin's module
is found; ``install``: what to do when it does not import. ``lidar``: {"beams": the
beams' elevations (rad), lowest first, or None for a non-repetitive sensor; "columns":
rays per beam and scan; "extrinsic": the LiDAR's pose in the IMU's frame (4 x 4 nested
lists; the identity where the IMU samples are in the LiDAR's frame, a flight's mount
where they are the body's)}. Every pose a worker returns is the LiDAR's.
"""

import importlib
import os
import pickle
import sys
import time
from collections import deque
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

_GENZ_SECTIONS = ("preprocess", "mapping", "adaptive_voxelization", "hybrid_metric", "noise_model")


class GenZ:
    """GenZ-LIO (PyPI genz-lio): its pose is the LiDAR's at the scan's end (its IMU state
    times the extrinsic, FAST-LIO's extrinsic_r and extrinsic_t: the LiDAR in the IMU's
    frame)."""

    def __init__(self, sensor_range, threads, settings, lidar):
        import genz_lio

        self.version = genz_lio.__version__
        config = genz_lio.Config()
        config.max_threads = int(threads)
        # One Livox-type stream (no Velodyne timestamp guard: the times given are exact).
        config.preprocess.lidar_type = genz_lio.LidarType.LIVOX
        config.preprocess.blind_min, config.preprocess.blind_max = sensor_range
        config.preprocess.point_filter_num = 1
        extrinsic = np.asarray(lidar["extrinsic"], dtype=np.float64)
        config.mapping.extrinsic_r, config.mapping.extrinsic_t = extrinsic[:3, :3], extrinsic[:3, 3]
        for section, values in settings.items():
            if section == "initial_covariance":
                self._initial_covariance(dict(values))
                continue
            if section not in _GENZ_SECTIONS:
                raise ValueError(f"unknown GenZ-LIO parameter section {section!r}; known: {', '.join(_GENZ_SECTIONS)}")
            target = getattr(config, section)
            for name, value in dict(values).items():
                if name.startswith("_") or not hasattr(target, name):
                    raise ValueError(f"unknown GenZ-LIO parameter {section}.{name}")
                setattr(target, name, value)
        self.odometry = genz_lio.GenZLIO(config)

    @staticmethod
    def _initial_covariance(values):
        """lf3pm's build of GenZ-LIO (third_party/genz_lio) reads the variance of position,
        rotation and velocity at its start from the environment when it initialises."""
        unknown = sorted(set(values) - {"pose_variance"})
        if unknown:
            raise ValueError(
                f"unknown GenZ-LIO parameter(s) initial_covariance.{', '.join(unknown)}; known: pose_variance"
            )
        variance = float(values.get("pose_variance", 1.0))
        if not variance > 0:
            raise ValueError(f"initial_covariance.pose_variance must be > 0, got {variance}")
        os.environ["GENZ_LIO_INIT_POSE_VARIANCE"] = repr(variance)

    def scan(self, points, begin, end, offsets, imu):
        if len(imu) == 0:
            return [(None, end, "skipped: no IMU samples")]  # GenZ-LIO cannot propagate without them
        seeded = self.odometry.map_size > 0
        result = self.odometry.register_scan(points, begin, end, imu, timestamps=offsets)
        if not self.odometry.initialized:
            status = "initializing"
        elif not result.valid:
            status = "skipped: too few points"
        elif not seeded:
            status = "map seeded"
        elif result.update_rejected:
            status = "rejected"
        elif result.plane_matches + result.point_matches == 0:
            status = "no matches"
        else:
            status = "ok"
        return [(np.array(self.odometry.lidar_pose), end, status)]

    def finish(self, imu):
        return []


class _Evalio:
    """An odometry as evalio compiles it (``PIPELINE``, in evalio.pipelines), fed by
    :meth:`_cloud`: each scan a LidarMeasurement stamped at its first return, the returns
    carrying their offsets from it (ns) and the fields of ``_DTYPE``. evalio leaves unset
    parameters uninitialised: every parameter is set, the settings over its defaults."""

    PIPELINE = ""
    LABEL = ""
    #: Settings that are not the pipeline's parameters (the subclass takes them out).
    EXTRA = ()
    _DTYPE = np.dtype([("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("t", "<u4")])

    def __init__(self, sensor_range, threads, settings, lidar):
        import evalio
        from evalio import pipelines, types
        from evalio._cpp import helpers

        self.types, self.helpers = types, helpers
        pipeline = getattr(pipelines, self.PIPELINE)
        self.version = f"{evalio.__version__} ({self.LABEL} {pipeline.version()})"
        self.pipeline = pipeline()
        defaults = pipeline.default_params()
        unknown = sorted(set(settings) - set(defaults) - set(self.EXTRA))
        if unknown:
            known = ", ".join([*self.EXTRA, *sorted(defaults)])
            raise ValueError(f"unknown {self.LABEL} parameter(s) {', '.join(unknown)}; known: {known}")
        self.defaults = dict(defaults)
        self.fields = _fields(helpers, self._DTYPE)

    def _cloud(self, points, offsets):
        """The scan as ``_DTYPE`` rows: its points and their offsets (ns)."""
        data = np.empty(len(points), self._DTYPE)
        data["x"], data["y"], data["z"] = points.T
        data["t"] = np.round(offsets * 1e9).astype(np.uint32)
        return data

    def finish(self, imu):
        return []


class Dlio(_Evalio):
    """DLIO (Direct LiDAR-Inertial Odometry) as evalio compiles it. DLIO deskews each
    scan to its median return time; the state it reports after the scan is its base
    frame's there, which evalio makes the IMU's (the LiDAR at the extrinsic in it), so
    the LiDAR's pose is that state times the extrinsic."""

    PIPELINE, LABEL = "DLIO", "DLIO"

    def __init__(self, sensor_range, threads, settings, lidar):
        super().__init__(sensor_range, threads, settings, lidar)
        types = self.types
        self.settings = {**self.defaults, **settings}
        self.pipeline.set_params(self.settings)
        self.pipeline.set_imu_params(types.ImuParams(gravity=np.array([0.0, 0.0, 9.81])))
        self.extrinsic = np.asarray(lidar["extrinsic"], dtype=np.float64)
        self.pipeline.set_imu_T_lidar(_se3(types, Rotation.from_matrix(self.extrinsic[:3, :3]), self.extrinsic[:3, 3]))
        self.pipeline.initialize()
        self.first_imu = None

    def scan(self, points, begin, end, offsets, imu):
        types = self.types
        if self.first_imu is None and len(imu):
            self.first_imu = float(imu[0, 0])
        _add_imu(self.pipeline, types, imu)
        if len(points) == 0:
            return [(None, end, "skipped: too few points")]
        data = self._cloud(points, offsets)
        self.pipeline.add_lidar(_measurement(self.helpers, types, self.fields, data, begin))
        estimates = self.pipeline.saved_estimates()
        median = _median_time(begin, data["t"])  # DLIO's scan time
        if not estimates:
            return [(None, median, "skipped: no estimate")]
        _, se3 = estimates[-1]
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = se3.rot.to_mat(), se3.trans
        pose = pose @ self.extrinsic
        # DLIO takes the IMU for still while it calibrates (imu_calib_time s from its first sample).
        calibrating = self.first_imu is None or median < self.first_imu + self.settings["imu_calib_time"]
        return [(pose, median, "initializing" if calibrating else "ok")]


@dataclass
class _Queued:
    """A scan LIO-SAM has not reported yet: the time its pose refers to, its status,
    whether LIO-SAM was given it, its last return and the rotation from its first
    return to ``time``."""

    time: float | None
    status: str
    given: bool
    last: float | None = None
    turn: np.ndarray | None = None


class LioSam(_Evalio):
    """LIO-SAM as evalio compiles it: LOAM edge and plane features of a ring-organised
    scan, matched to a keyframe map, in a factor graph with IMU preintegration (GTSAM).

    Each scan is a LidarMeasurement stamped at its first return, each return carrying
    its offset from it (ns) and its ring (the beam nearest its elevation). LIO-SAM
    deskews a scan's rotation only (its translation deskew is commented out in its
    source), so the position it registers is the scan's mean and refers to the median
    return time (fitted: +0.05 s from the first return at 10 Hz, docs/lio.md), its
    rotation to the first return: the replay carries the rotation on to the median
    time by the scan's gyro samples (``_turn``, as LIO-SAM's deskewing integrates
    them), so that each pose refers to one time. LIO-SAM processes a scan once two more
    have arrived (its cloud queue), so a pose comes two scans late; ``finish`` gives it
    the IMU samples after the last scan and two empty scans, a scan period apart
    (never processed themselves), to flush the last two.

    Its initialisation divides by |e_z x a| (the still accelerometer's tilt from the
    vertical), NaN for an exactly level IMU, which a noise-free replay on flat ground
    or a hover gives: lf3pm declares the IMU turned TILT about x from where it is (the
    LiDAR's frame, or a flight's body at the extrinsic), rotates the samples into that
    declared frame (exact) and turns the estimated declared-IMU poses back into the
    LiDAR's (the gyro's turn over a scan too, by the extrinsic). Gravity points down
    (evalio's ``ImuParams.down``): with it up, LIO-SAM took the still accelerometer for a
    2 g bias and reset its preintegration every scan."""

    PIPELINE, LABEL, EXTRA = "LioSAM", "LIO-SAM", ("imu_densities",)
    _DTYPE = np.dtype([("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("t", "<u4"), ("ring", "u1")])
    TILT = np.radians(1.0)

    def __init__(self, sensor_range, threads, settings, lidar):
        if not lidar.get("beams"):
            raise ValueError("LIO-SAM needs a spinning sensor (rings of beams); use genz for a Livox one")
        super().__init__(sensor_range, threads, settings, lidar)
        types = self.types
        settings = dict(settings)
        noise = settings.pop("imu_densities", {})
        self.pipeline.set_params({**self.defaults, "numberOfCores": int(threads), **settings})
        self.pipeline.set_imu_params(types.ImuParams(gravity=np.array([0.0, 0.0, -9.81]), **noise))
        self.pipeline.set_lidar_params(
            types.LidarParams(
                num_rows=len(lidar["beams"]),
                num_columns=lidar["columns"],
                min_range=sensor_range[0],
                max_range=sensor_range[1],
            )
        )
        extrinsic = np.asarray(lidar["extrinsic"], dtype=np.float64)
        tilt = Rotation.from_rotvec([self.TILT, 0.0, 0.0])  # the declared IMU's axes in the IMU's
        self.imu_R_declared = tilt.as_matrix()
        # The LiDAR in the declared IMU's frame: rotation and translation.
        self.lidar_in_declared = (self.imu_R_declared.T @ extrinsic[:3, :3], self.imu_R_declared.T @ extrinsic[:3, 3])
        self.lidar_R_imu = extrinsic[:3, :3].T
        declared = tilt.inv() * Rotation.from_matrix(extrinsic[:3, :3])
        self.pipeline.set_imu_T_lidar(_se3(types, declared, self.lidar_in_declared[1]))
        self.pipeline.initialize()
        self.beams = np.asarray(lidar["beams"], float)
        self.queue = []  # _Queued, in scan order
        self.pose = None  # the pose of the last scan LIO-SAM processed (None: none yet)
        self.imu_span = None  # (first, last) IMU time given
        self.begins = deque(maxlen=2)  # the stamps of the last two scans given

    def scan(self, points, begin, end, offsets, imu):
        self._add_imu(imu)
        if len(points) == 0:  # not given to LIO-SAM, which reads a scan's last return
            self.queue.append(_Queued(begin, "skipped: too few points", False))
            return self._report()
        data = self._cloud(points, offsets)
        elevation = np.arctan2(points[:, 2], np.hypot(points[:, 0], points[:, 1]))
        data["ring"] = np.abs(elevation[:, None] - self.beams[None, :]).argmin(axis=1)
        self.pipeline.add_lidar(_measurement(self.helpers, self.types, self.fields, data, begin))
        self.begins.append(begin)
        median = _median_time(begin, data["t"])
        # LIO-SAM drops a scan whose time span the IMU samples do not cover.
        status = (
            "ok"
            if self.imu_span is not None and self.imu_span[0] <= begin
            else "skipped: no IMU samples before the scan"
        )
        turn = self.lidar_R_imu @ _turn(imu, begin, median) @ self.lidar_R_imu.T  # the IMU's turn, in the LiDAR's frame
        self.queue.append(_Queued(median, status, True, begin + offsets[-1], turn))
        return self._report()

    def finish(self, imu):
        self._add_imu(imu)
        results = []
        if any(queued.given for queued in self.queue):
            # A scan period apart: LIO-SAM gives the scan it processes the newest stamp,
            # and its IMU graph failed (underdetermined) on one a millisecond later.
            period = self.begins[-1] - self.begins[-2] if len(self.begins) > 1 else 0.1
            for j in (1, 2):
                stamp = self.types.Stamp.from_sec(EPOCH + self.begins[-1] + j * period)
                self.pipeline.add_lidar(self.types.LidarMeasurement(stamp))
                self.queue.append(_Queued(None, "flush", True))
                results += self._report()
        return results + self._report(flush=True)

    def _add_imu(self, imu):
        if not len(imu):
            return
        first = imu[0, 0] if self.imu_span is None else self.imu_span[0]
        self.imu_span = (first, imu[-1, 0])
        rotated = imu.copy()
        rotated[:, 1:7] = (imu[:, 1:7].reshape(-1, 2, 3) @ self.imu_R_declared).reshape(-1, 6)  # R^T v per row
        _add_imu(self.pipeline, self.types, rotated)

    def _report(self, flush=False):
        """The scans whose pose is known now: LIO-SAM processes its oldest queued scan
        when a third is given (``flush``: report the rest at the pose it holds)."""
        given = [k for k, queued in enumerate(self.queue) if queued.given]
        processed = given[0] if len(given) >= 3 else None
        results = []
        for k, queued in enumerate(list(self.queue)):
            if k == processed and queued.status == "ok":
                if self.imu_span[1] < queued.last - 1e-6:
                    queued.status = "skipped: no IMU samples after the scan"  # LIO-SAM drops it
                else:
                    queued.status = "ok" if self.pose is not None else "map seeded"
                    self.pose = self._estimate()
                    self.pose[:3, :3] = self.pose[:3, :3] @ queued.turn
            elif queued.given and k != processed and not flush:
                break
            if queued.time is not None:  # not one of finish's empty scans
                results.append((self.pose, queued.time, queued.status))
            self.queue.pop(0)
        return results

    def _estimate(self):
        """LIO-SAM's LiDAR pose (4, 4) after the scan it processed last (evalio reports
        the declared IMU's)."""
        _, se3 = self.pipeline.saved_estimates()[-1]
        rotation, translation = self.lidar_in_declared
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = se3.rot.to_mat() @ rotation, se3.rot.to_mat() @ translation + se3.trans
        return pose


def _se3(types, rotation, translation):
    """evalio's SE3 of a scipy Rotation and a translation (3,)."""
    qx, qy, qz, qw = rotation.as_quat()
    return types.SE3(types.SO3(qx=qx, qy=qy, qz=qz, qw=qw), np.array(translation, dtype=np.float64))


def _turn(imu, begin, end):
    """The rotation (3, 3) of the body from ``begin`` to ``end`` by the gyro rows of
    ``imu`` (t, accel, gyro), each rate held over the interval up to its sample."""
    if not len(imu):
        return np.eye(3)
    t, gyro = imu[:, 0], imu[:, 4:7]
    lower = np.concatenate([[t[0] - (t[1] - t[0]) if len(t) > 1 else t[0]], t[:-1]])
    spans = np.clip(np.minimum(t, end) - np.maximum(lower, begin), 0.0, None)
    turn = Rotation.identity()
    for step in Rotation.from_rotvec(gyro * spans[:, None]):
        turn = turn * step  # body-frame increments compose on the right
    return turn.as_matrix()


def _median_time(begin, nanoseconds):
    """A scan's median distinct return time (s) from its first return ``begin`` and the
    returns' offsets from it (ns)."""
    unique = np.unique(nanoseconds)
    return begin + unique[len(unique) // 2] * 1e-9


def _fields(helpers, dtype):
    """evalio's description of the structured array ``dtype``'s fields."""
    kinds = {"<f8": helpers.DataType.FLOAT64, "<u4": helpers.DataType.UINT32, "|u1": helpers.DataType.UINT8}
    return [
        helpers.Field(name=name, datatype=kinds[dtype.fields[name][0].str], offset=dtype.fields[name][1])
        for name in dtype.names
    ]


#: Added to every time given to evalio, whose stamps are unsigned (a replay's rest
#: starts before t = 0: those times wrapped around and DLIO diverged to 1e26 m).
EPOCH = 1e4


def _add_imu(pipeline, types, imu):
    for row in imu:
        pipeline.add_imu(types.ImuMeasurement(types.Stamp.from_sec(EPOCH + row[0]), row[4:7].copy(), row[1:4].copy()))


def _measurement(helpers, types, fields, data, begin):
    meta = helpers.PointCloudMetadata(
        stamp=types.Stamp.from_sec(EPOCH + begin),
        width=len(data),
        height=1,
        point_step=data.itemsize,
        row_step=data.nbytes,
        is_bigendian=0,
        is_dense=1,
    )
    return helpers.pc2_to_evalio(meta, fields, data.tobytes())


def _worker_class(spec, paths):
    """The class "module:Class" names: this module's own, or one imported with the
    parent's sys.path."""
    module, _, name = spec.partition(":")
    if module == "lf3pm.replays._lio_worker":
        return globals()[name]
    sys.path.extend(path for path in paths if path not in sys.path)
    target = importlib.import_module(module)
    for part in name.split("."):
        target = getattr(target, part)
    return target


def main(reply_fd: int) -> None:
    requests = sys.stdin.buffer
    replies = open(reply_fd, "wb")

    def send(message):
        pickle.dump(message, replies, protocol=pickle.HIGHEST_PROTOCOL)
        replies.flush()

    _, worker, odometry, sensor_range, threads, settings, lidar, paths, install = pickle.load(requests)
    try:
        backend = _worker_class(worker, paths)(sensor_range, threads, settings, lidar)
    except ImportError as err:
        send(("error", f"the {odometry} odometry is not installed ({err}): {install}"))
        return
    except (ValueError, TypeError) as err:
        send(("error", str(err)))
        return
    send(("ready", backend.version))
    previous = np.eye(4)

    def held(results):
        """The results with a skipped scan's missing pose replaced by the last one."""
        nonlocal previous
        out = []
        for pose, at, status in results:
            previous = previous if pose is None else pose
            out.append((previous, at, status))
        return out

    while True:
        message = pickle.load(requests)
        start = time.perf_counter()
        if message[0] == "done":
            send(("poses", held(backend.finish(message[1])), time.perf_counter() - start))
            return
        _, points, begin, end, offsets, imu = message
        try:
            results = backend.scan(points, begin, end, offsets, imu)
        except (ValueError, RuntimeError) as err:
            send(("error", f"{odometry} refused the scan ending at {end:.6f} s: {err}"))
            return
        send(("poses", held(results), time.perf_counter() - start))


if __name__ == "__main__":
    main(int(sys.argv[1]))
