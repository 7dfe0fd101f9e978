"""Child process of lf3pm.validation.lio: runs GenZ-LIO on the scans the parent
streams to it, so that the odometry's OpenMP runtime, its console output and a
crash stay out of the caller's process.

Run as a script (no lf3pm import): ``python _lio_worker.py REPLY_FD``.
Protocol, pickled objects: on stdin ("config", sensor_range, threads, overrides),
then ("scan", points, begin, end, offsets, imu) per scan and ("done",);
on REPLY_FD ("ready", version) or ("error", message), then per scan
("pose", pose, status, seconds).
"""

import pickle
import sys
import time

import numpy as np

_SECTIONS = ("preprocess", "mapping", "adaptive_voxelization", "hybrid_metric", "noise_model")


def configure(genz, sensor_range, threads, overrides):
    """GenZ-LIO's Config for this sensor: blind zone from its range limits, one
    Livox-type stream (no Velodyne timestamp guard: the times given are exact),
    identity extrinsic, ``threads`` OpenMP threads; then ``overrides``
    {section: {field: value}}."""
    config = genz.Config()
    config.max_threads = int(threads)
    config.preprocess.lidar_type = genz.LidarType.LIVOX
    config.preprocess.blind_min, config.preprocess.blind_max = sensor_range
    config.preprocess.point_filter_num = 1
    for section, values in overrides.items():
        if section not in _SECTIONS:
            raise ValueError(f"unknown GenZ-LIO parameter section {section!r}; known: {', '.join(_SECTIONS)}")
        target = getattr(config, section)
        for name, value in dict(values).items():
            if name.startswith("_") or not hasattr(target, name):
                raise ValueError(f"unknown GenZ-LIO parameter {section}.{name}")
            setattr(target, name, value)
    return config


def main(reply_fd: int) -> None:
    requests = sys.stdin.buffer
    replies = open(reply_fd, "wb")

    def send(message):
        pickle.dump(message, replies, protocol=pickle.HIGHEST_PROTOCOL)
        replies.flush()

    _, sensor_range, threads, overrides = pickle.load(requests)
    try:
        import genz_lio as genz
    except ImportError as err:
        send(("error", f"genz-lio is not installed ({err}); it has wheels for Python 3.8-3.12 only"))
        return
    try:
        odometry = genz.GenZLIO(configure(genz, sensor_range, threads, overrides))
    except (ValueError, TypeError) as err:
        send(("error", str(err)))
        return
    send(("ready", genz.__version__))
    while True:
        message = pickle.load(requests)
        if message[0] == "done":
            return
        _, points, begin, end, offsets, imu = message
        start = time.perf_counter()
        if len(imu) == 0:
            status = "skipped: no IMU samples"  # GenZ-LIO cannot propagate without them
        else:
            seeded = odometry.map_size > 0
            try:
                result = odometry.register_scan(points, begin, end, imu, timestamps=offsets)
            except (ValueError, RuntimeError) as err:
                send(("error", f"GenZ-LIO refused the scan ending at {end:.6f} s: {err}"))
                return
            if not odometry.initialized:
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
        seconds = time.perf_counter() - start
        send(("pose", np.array(odometry.lidar_pose), status, seconds))


if __name__ == "__main__":
    main(int(sys.argv[1]))
