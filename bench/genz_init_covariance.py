"""GenZ-LIO's initial covariance and a still Mid-70 (docs/lio.md, "A still sensor"):
the experiment that isolated why its estimate slides while the sensor stands still.

GenZ-LIO sets FAST-LIO2's initial covariance (identity for position, rotation and
velocity: 1 m, 1 rad, 1 m/s) and seeds its map from the first scan at that
covariance. The python binding cannot change it, so the experiment rebuilds GenZ-LIO
0.1.1 from its sdist with one change, an environment variable that overrides those
nine diagonal entries, and runs both builds on the very same streams.

1. ``dump`` (in lf3pm's venv) writes the streams the replay would feed GenZ-LIO --
   scans, per-point stamps, IMU rows, truth and lf3pm's GenZ-LIO settings -- for the
   benefit study's starts on one map (``--map``, default gobi; the sensor still for the
   rest and 1 s: noise-free, noisy seeds 0 and 1) and for the plans named with --plans
   (the whole replay).
   It needs the study's trajectories (``lf3pm experiment benefit -o out/benefit3``).
2. ``run`` (in any venv with a genz_lio module) replays them: per stream the APE after
   the rest (re-anchored there, as the replay scores it) and the largest drift during
   the rest; per group of still streams the median and largest drift and the number
   of rests still moving (> 0.05 m/s) at their end.

The patched build (GPL-2.0 code, built locally, not part of lf3pm)::

    pip download --no-deps --no-binary :all: genz-lio==0.1.1 && tar xzf genz_lio-0.1.1.tar.gz
    # cpp/genz_lio/core/ImuProcessor.cpp, after the init_P(21, 21) line:
    #   { const char *e = std::getenv("GENZ_INIT_POSE_VAR");
    #     if (e) for (int i : {0, 1, 2, 3, 4, 5, 12, 13, 14}) init_P(i, i) = std::atof(e); }
    python3 -m venv /tmp/gvenv && /tmp/gvenv/bin/pip install "scikit-build-core>=0.11,<0.12" \\
        "pybind11>=2.13,<3" cmeel-eigen cmeel-boost numpy pyyaml typer rich
    P=/tmp/gvenv/lib/python3.11/site-packages; CMAKE_PREFIX_PATH=$P/cmeel.prefix:$P/pybind11/share/cmake \\
        CXXFLAGS=-I$P/cmeel.prefix/include /tmp/gvenv/bin/pip install --no-build-isolation --no-deps genz_lio-0.1.1

    .venv/bin/python bench/genz_init_covariance.py dump /tmp/streams
    .venv/bin/python bench/genz_init_covariance.py dump /tmp/orientation --map orientation --plans
    .venv/bin/python bench/genz_init_covariance.py run /tmp/streams                 # GenZ-LIO from PyPI
    GENZ_INIT_POSE_VAR=1e-4 /tmp/gvenv/bin/python bench/genz_init_covariance.py run /tmp/streams
"""

from __future__ import annotations

import argparse
import glob
import os
import pickle
from pathlib import Path

import numpy as np

#: The replay's rest (replays/replay.py LIO_REST) at 10 scans per second: the scan the
#: trajectory starts at.
REST_SCANS = 20
#: A rest whose estimate still moves faster than this (m/s) at its end is unsteady
#: (replays/replay_result.py REST_SPEED_LIMIT).
SPEED_LIMIT = 0.05
#: The default plans: gobi pair 5's guided plan on the two seeds GenZ-LIO ran away on
#: (8.2 and 27 m), its unguided plan, and pair 0's guided and unguided omni plans.
PLANS = ("05_diff_default:0", "05_diff_default:1", "05_diff_none:0", "00_omni_default:2", "00_omni_none:2")


def dump(out: Path, study: Path, plans, map_name: str) -> None:
    from lf3pm.experiments.benefit import CASES
    from lf3pm.experiments.map_cases import load_case_map
    from lf3pm.replays.imu import simulate_imu
    from lf3pm.replays.lio import _imu_rows, _settings
    from lf3pm.replays.motion import Motion, RestFirst
    from lf3pm.scan.scans import ScanStream
    from lf3pm.sensors import get_sensor

    case = next(c for c in CASES if c.name == map_name)
    world, _ = load_case_map(case)
    sensor = get_sensor(case.sensor)
    folder = study / "trajectories" / map_name
    out.mkdir(parents=True, exist_ok=True)

    def save(name, motion, seed, noisy):
        scans = ScanStream(world, motion, sensor, seed=seed, threads=0, **({} if noisy else {"noise": 0.0}))
        imu = simulate_imu(motion, seed=seed, noise=noisy)
        t, rows = _imu_rows(imu)
        stream = {"scans": [(np.asarray(s.points, np.float64), np.asarray(s.stamps), float(s.end)) for s in scans],
                  "t": t, "rows": rows, "truth": scans.truth, "range": (sensor.min_range, sensor.max_range),
                  "settings": _settings("genz", sensor, imu, {})}
        with open(out / f"{name}.pkl", "wb") as fp:
            pickle.dump(stream, fp)

    for csv in sorted(folder.glob("*_none.csv")):  # each pair's start, still for the rest and 1 s
        first = csv.read_text().splitlines()[1].split(",")
        t = np.array([0.0, 1.0])
        x, y, yaw = (np.full(2, float(v)) for v in first[1:4])
        still = RestFirst(Motion.from_arrays(t, x, y, yaw, 0 * t, 0 * t, 0 * t, map=world, height=1.0), 2.0)
        for seed, noisy in ((0, False), (0, True), (1, True)):
            save(f"still_{'noisy' if noisy else 'exact'}_{csv.name[:2]}_{seed}", still, seed, noisy)
    for plan in plans:
        name, seed = plan.split(":")
        motion = RestFirst(Motion.from_csv(folder / f"{name}.csv", world, height=1.0), 2.0)
        save(f"plan_{name}_{seed}", motion, int(seed), True)
    print(f"wrote {len(list(out.glob('*.pkl')))} streams to {out}")


def run(folder: Path) -> None:
    import genz_lio

    print(f"GenZ-LIO {genz_lio.__version__}, GENZ_INIT_POSE_VAR={os.environ.get('GENZ_INIT_POSE_VAR', 'unset')}")
    groups: dict = {}
    for path in sorted(glob.glob(str(folder / "*.pkl"))):
        with open(path, "rb") as fp:
            stream = pickle.load(fp)
        # As replays/_lio_worker.GenZ configures it, written out: this step runs in a venv
        # that has a rebuilt genz_lio and no lf3pm.
        config = genz_lio.Config()
        config.max_threads = 1
        config.preprocess.lidar_type = genz_lio.LidarType.LIVOX
        config.preprocess.blind_min, config.preprocess.blind_max = stream["range"]
        config.preprocess.point_filter_num = 1
        for section, values in stream["settings"].items():
            for key, value in values.items():
                setattr(getattr(config, section), key, value)
        odometry = genz_lio.GenZLIO(config)
        t, rows, before, poses = stream["t"], stream["rows"], 0, []
        for points, stamps, end in stream["scans"]:  # as replays/_lio_worker.py feeds it
            upto = int(np.searchsorted(t, end, side="right"))
            odometry.register_scan(np.ascontiguousarray(points), float(stamps[0]), end,
                                   np.column_stack([t[before:upto], rows[before:upto]]),
                                   timestamps=stamps - stamps[0])
            before = upto
            poses.append(np.array(odometry.lidar_pose))
        poses, truth, k = np.array(poses), stream["truth"], REST_SCANS
        whole = truth[0] @ np.linalg.inv(poses[0]) @ poses
        drift = np.linalg.norm(whole[: k + 1, :3, 3] - truth[: k + 1, :3, 3], axis=1).max()
        speed = np.linalg.norm(whole[k, :3, 3] - whole[k - 5, :3, 3]) / 0.5
        name = Path(path).stem
        if name.startswith("plan_"):
            after = truth[k] @ np.linalg.inv(poses[k]) @ poses[k:]
            error = np.linalg.norm(after[:, :3, 3] - truth[k:, :3, 3], axis=1)
            print(f"{name}: APE rmse {np.sqrt(np.mean(error**2)):.3f} m, max {error.max():.3f} m; "
                  f"rest drift {drift:.3f} m, {speed:.3f} m/s at its end", flush=True)
        else:
            groups.setdefault(name.split("_")[1], []).append((drift, speed))
    for label, rows in groups.items():
        drift = np.array([r[0] for r in rows])
        unsteady = sum(r[1] > SPEED_LIMIT for r in rows)
        print(f"still, {'noise-free' if label == 'exact' else 'noisy'}: {len(rows)} rests, drift median "
              f"{np.median(drift):.3f} m, max {drift.max():.3f} m, {unsteady} unsteady")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="step", required=True)
    d = sub.add_parser("dump", help="write the streams (lf3pm's venv)")
    d.add_argument("out", type=Path)
    d.add_argument("--study", type=Path, default=Path("out/benefit3"))
    d.add_argument("--map", default="gobi", help="a benefit-study map with the Mid-70 (gobi, orientation, ...)")
    d.add_argument("--plans", nargs="*", default=list(PLANS), help="NAME:SEED of the study's plans on that map")
    r = sub.add_parser("run", help="replay them through the genz_lio importable here")
    r.add_argument("folder", type=Path)
    args = parser.parse_args()
    if args.step == "dump":
        dump(args.out, args.study, args.plans, args.map)
    else:
        run(args.folder)


if __name__ == "__main__":
    main()
