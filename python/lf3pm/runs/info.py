"""What a recorded run holds: its sources, scans, IMU and poses (``lf3pm run info``)."""

from __future__ import annotations

import numpy as np

from lf3pm.runs.run import Run


def _span(first: float | None, last: float | None) -> dict | None:
    if first is None:
        return None
    return {"first_s": first, "last_s": last, "duration_s": last - first}


def run_info(run: Run) -> dict:
    """A summary of ``run``, read through once (one scan in memory at a time): its source
    (:meth:`Run.describe`), the scans read and skipped (each with its reason; ``run`` is
    read with skip_bad), their time span, points per scan (min, median, max), whether they
    carry per-point times (all, some or none of them), the IMU's sample count and mean
    rate, and the reference poses' count and span."""
    skip_bad, run.skip_bad = run.skip_bad, True
    try:
        counts, timed, stamps = [], 0, []
        for scan in run.scans():
            counts.append(len(scan.points))
            timed += scan.times is not None
            stamps.append(scan.stamp)
        bad = [{"index": b.index, "name": b.name, "reason": b.reason} for b in run.bad_scans]
    finally:
        run.skip_bad = skip_bad
    imu_count, imu_first, imu_last = 0, None, None
    for sample in run.imu():
        imu_count += 1
        imu_first = sample.stamp if imu_first is None else imu_first
        imu_last = sample.stamp
    imu_span = _span(imu_first, imu_last)
    reference = run.reference
    return {
        "source": run.describe(),
        "scans": len(counts),
        "bad_scans": bad,
        "scans_span": _span(stamps[0], stamps[-1]) if stamps else None,
        "points_per_scan": (
            {"min": int(min(counts)), "median": float(np.median(counts)), "max": int(max(counts))} if counts else None
        ),
        "point_times": "none" if not timed else "all" if timed == len(counts) else "some",
        "imu": {
            "samples": imu_count,
            "span": imu_span,
            "rate_hz": (imu_count - 1) / imu_span["duration_s"] if imu_span and imu_span["duration_s"] > 0 else None,
        },
        "poses": None
        if reference is None
        else {"count": len(reference), "span": _span(*reference.span), "from": reference.name},
    }
