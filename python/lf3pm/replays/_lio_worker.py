"""Child process of lf3pm.replays.lio: runs one LiDAR-inertial odometry (GenZ-LIO,
or DLIO from evalio) on the scans the parent streams to it, so that the odometry's
OpenMP runtime, its console output and a crash stay out of the caller's process.

Run as a script (no lf3pm import): ``python _lio_worker.py REPLY_FD``.
Protocol, pickled objects: on stdin ("config", odometry, sensor_range, threads,
settings), then ("scan", points, begin, end, offsets, imu) per scan and ("done",);
on REPLY_FD ("ready", version) or ("error", message), then per scan
("pose", pose, time, status, seconds): the pose and the time it refers to.
"""

import os
import pickle
import sys
import time

import numpy as np

_GENZ_SECTIONS = ("preprocess", "mapping", "adaptive_voxelization", "hybrid_metric", "noise_model")


class GenZ:
    """GenZ-LIO (PyPI genz-lio): its pose is the IMU's at the scan's end."""

    def __init__(self, sensor_range, threads, settings):
        import genz_lio

        self.version = genz_lio.__version__
        config = genz_lio.Config()
        config.max_threads = int(threads)
        # One Livox-type stream (no Velodyne timestamp guard: the times given are exact).
        config.preprocess.lidar_type = genz_lio.LidarType.LIVOX
        config.preprocess.blind_min, config.preprocess.blind_max = sensor_range
        config.preprocess.point_filter_num = 1
        for section, values in settings.items():
            if section == "initial_covariance":
                self._initial_covariance(dict(values))
                continue
            if section not in _GENZ_SECTIONS:
                raise ValueError(f"unknown GenZ-LIO parameter section {section!r}; known: "
                                 f"{', '.join(_GENZ_SECTIONS)}")
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
            raise ValueError(f"unknown GenZ-LIO parameter(s) initial_covariance.{', '.join(unknown)}; "
                             "known: pose_variance")
        variance = float(values.get("pose_variance", 1.0))
        if not variance > 0:
            raise ValueError(f"initial_covariance.pose_variance must be > 0, got {variance}")
        os.environ["GENZ_LIO_INIT_POSE_VARIANCE"] = repr(variance)

    def scan(self, points, begin, end, offsets, imu):
        if len(imu) == 0:
            return None, end, "skipped: no IMU samples"  # GenZ-LIO cannot propagate without them
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
        return np.array(self.odometry.lidar_pose), end, status


class Dlio:
    """DLIO (Direct LiDAR-Inertial Odometry) as evalio compiles it. Each scan is a
    LidarMeasurement stamped at its first return, the returns carrying their offsets
    from it (ns); DLIO deskews the scan to its median return time and its pose is the
    sensor's there (the state it reports after the scan)."""

    _DTYPE = np.dtype([("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("t", "<u4")])
    #: Added to every time given to evalio, whose stamps are unsigned (a replay's rest
    #: starts before t = 0: those times wrapped around and DLIO diverged to 1e26 m).
    EPOCH = 1e4

    def __init__(self, sensor_range, threads, settings):
        import evalio
        from evalio import pipelines, types
        from evalio._cpp import helpers

        self.types, self.helpers = types, helpers
        self.version = f"{evalio.__version__} (DLIO {pipelines.DLIO.version()})"
        self.pipeline = pipelines.DLIO()
        unknown = sorted(set(settings) - set(pipelines.DLIO.default_params()))
        if unknown:
            raise ValueError(f"unknown DLIO parameter(s) {', '.join(unknown)}; known: "
                             f"{', '.join(sorted(pipelines.DLIO.default_params()))}")
        # evalio leaves unset fields uninitialised: every parameter is set.
        self.settings = {**pipelines.DLIO.default_params(), **settings}
        self.pipeline.set_params(self.settings)
        self.pipeline.set_imu_params(types.ImuParams(gravity=np.array([0.0, 0.0, 9.81])))
        self.pipeline.set_imu_T_lidar(types.SE3.identity())
        self.pipeline.initialize()
        kinds = {"x": helpers.DataType.FLOAT64, "y": helpers.DataType.FLOAT64, "z": helpers.DataType.FLOAT64,
                 "t": helpers.DataType.UINT32}
        self.fields = [helpers.Field(name=n, datatype=kinds[n], offset=self._DTYPE.fields[n][1]) for n in kinds]
        self.first_imu = None

    def scan(self, points, begin, end, offsets, imu):
        types = self.types
        if self.first_imu is None and len(imu):
            self.first_imu = float(imu[0, 0])
        for row in imu:
            self.pipeline.add_imu(types.ImuMeasurement(types.Stamp.from_sec(self.EPOCH + row[0]), row[4:7].copy(),
                                                       row[1:4].copy()))
        nanoseconds = np.round(offsets * 1e9).astype(np.uint32)
        if len(points) == 0:
            return None, end, "skipped: too few points"
        data = np.empty(len(points), self._DTYPE)
        data["x"], data["y"], data["z"] = points.T
        data["t"] = nanoseconds
        meta = self.helpers.PointCloudMetadata(stamp=types.Stamp.from_sec(self.EPOCH + begin), width=len(data),
                                               height=1, point_step=data.itemsize, row_step=data.nbytes,
                                               is_bigendian=0, is_dense=1)
        self.pipeline.add_lidar(self.helpers.pc2_to_evalio(meta, self.fields, data.tobytes()))
        estimates = self.pipeline.saved_estimates()
        unique = np.unique(nanoseconds)
        median = begin + unique[len(unique) // 2] * 1e-9  # DLIO's scan time: its median distinct return time
        if not estimates:
            return None, median, "skipped: no estimate"
        _, se3 = estimates[-1]
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = se3.rot.to_mat(), se3.trans
        # DLIO takes the IMU for still while it calibrates (imu_calib_time s from its first sample).
        calibrating = self.first_imu is None or median < self.first_imu + self.settings["imu_calib_time"]
        return pose, median, "initializing" if calibrating else "ok"


BACKENDS = {"genz": GenZ, "dlio": Dlio}


def main(reply_fd: int) -> None:
    requests = sys.stdin.buffer
    replies = open(reply_fd, "wb")

    def send(message):
        pickle.dump(message, replies, protocol=pickle.HIGHEST_PROTOCOL)
        replies.flush()

    _, odometry, sensor_range, threads, settings = pickle.load(requests)
    try:
        backend = BACKENDS[odometry](sensor_range, threads, settings)
    except ImportError as err:
        send(("error", f"the {odometry} odometry is not installed ({err}); pip install 'lf3pm[lio]' "
                       "(wheels for Python 3.8-3.12)"))
        return
    except (ValueError, TypeError) as err:
        send(("error", str(err)))
        return
    send(("ready", backend.version))
    previous = np.eye(4)
    while True:
        message = pickle.load(requests)
        if message[0] == "done":
            return
        _, points, begin, end, offsets, imu = message
        start = time.perf_counter()
        try:
            pose, at, status = backend.scan(points, begin, end, offsets, imu)
        except (ValueError, RuntimeError) as err:
            send(("error", f"{odometry} refused the scan ending at {end:.6f} s: {err}"))
            return
        previous = previous if pose is None else pose  # a skipped scan keeps the last pose
        send(("pose", previous, at, status, time.perf_counter() - start))


if __name__ == "__main__":
    main(int(sys.argv[1]))
