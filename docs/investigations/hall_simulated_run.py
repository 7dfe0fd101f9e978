"""Issue 42: a simulated run of the hall map, where the truth is exact. The os1-64 preset's
scans (its default 1.5 cm range noise, one noise stream per scan) cast at the real run's
reference poses on the map made of the real run's scans, written as a run folder with those
poses, then audited against that map. Run from the repository root:

    .venv/bin/python docs/investigations/hall_simulated_run.py /tmp/hall_sim
    .venv/bin/lf3pm audit /tmp/hall_sim --map ../shared/data/real_hall_run --sensor os1-64 \\
        --every 2 --scan-voxel 0.1 --starts 10 --no-track --json -o /tmp/hall_sim/out > /tmp/hall_sim/audit.json
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import numpy as np

import lf3pm
from lf3pm.runs import Run
from lf3pm.scan.scan_simulator import simulate_scan

RUN = Path(__file__).resolve().parents[3] / "shared" / "data" / "real_hall_run"


def main(out: Path) -> None:
    sensor = lf3pm.get_sensor("os1-64")
    world = lf3pm.load_map(RUN, threads=2)
    (out / "scans").mkdir(parents=True, exist_ok=True)
    shutil.copyfile(RUN / "poses_tum.txt", out / "poses_tum.txt")
    with Run(RUN) as run:
        for k, scan in enumerate(run.scans()):
            cast = simulate_scan(
                world,
                scan.pose,
                sensor.directions,
                sensor.min_range,
                sensor.max_range,
                noise=sensor.range_noise_sigma,
                stream=k,
            )
            np.save(out / "scans" / f"{scan.stamp:.6f}.npy", cast.sensor_points)
    print(f"wrote {k + 1} simulated scans to {out}")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
