"""`lf3pm run info`: what a recorded run holds (lf3pm.runs)."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from lf3pm.cli._common import CONFIG_OPTION, app, configure, option, section_paths, user_errors

run_app = typer.Typer(help="Recorded runs: folders of scans with poses, ROS 1 and ROS 2 bags.", no_args_is_help=True)
app.add_typer(run_app, name="run")


@run_app.command("info")
def info(
    run: Path = typer.Argument(
        ..., metavar="RUN", help="A folder of scans with a poses file, a ROS 1 .bag or a ROS 2 bag folder."
    ),
    config: Path | None = CONFIG_OPTION,
    scans_topic: str | None = option("run.scans_topic"),
    imu_topic: str | None = option("run.imu_topic"),
    poses_topic: str | None = option("run.poses_topic"),
    max_pose_gap: float | None = option("run.max_pose_gap"),
    lidar_time_offset: float | None = option("run.lidar_time_offset"),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
):
    """Print what a recorded run holds (docs/runs.md).

    The run is read through once: its sources, topics, scans (count, time span, points per
    scan, per-point times), IMU rate, reference poses and the scans it could not use."""
    with user_errors():
        from lf3pm.runs import Run, run_info

        paths = section_paths("run", "scans_topic", "imu_topic", "poses_topic", "max_pose_gap", "lidar_time_offset")
        cfg = configure(config, locals(), paths)
        with Run(run, cfg.run, skip_bad=True) as opened:
            summary = run_info(opened)
        if as_json:
            print(json.dumps(summary))
            return
        print_info(summary)


def _span(span: dict | None) -> str:
    if span is None:
        return "-"
    return f"{span['first_s']:.6f} to {span['last_s']:.6f} s ({span['duration_s']:.3f} s)"


def print_info(summary: dict) -> None:
    """The summary of :func:`lf3pm.runs.run_info` as lines of text."""
    source = summary["source"]
    print(f"run: {source['path']} ({source['kind']})")
    for key in ("scans_folder", "poses_file", "times_file"):
        if key in source:
            print(f"  {key.replace('_', ' ')}: {source[key] or '-'}")
    for name, topic in source.get("topics", {}).items():
        used = [what for what in ("scans", "imu", "poses") if source.get(f"{what}_topic") == name]
        print(f"  topic {name}: {topic['type']}, {topic['messages']} messages{' (' + used[0] + ')' if used else ''}")
    points = summary["points_per_scan"]
    print(f"scans: {summary['scans']}, {_span(summary['scans_span'])}")
    if points:
        print(f"  points per scan: min {points['min']}, median {points['median']:g}, max {points['max']}")
    print(f"  per-point times: {summary['point_times']}")
    imu = summary["imu"]
    rate = f", {imu['rate_hz']:.1f} Hz, {_span(imu['span'])}" if imu["rate_hz"] else ""
    print(f"imu: {imu['samples']} samples{rate}")
    poses = summary["poses"]
    print(f"poses: {poses['count']} from {poses['from']}, {_span(poses['span'])}" if poses else "poses: none")
    for bad in summary["bad_scans"]:
        print(f"bad scan: {bad['reason']}")
    if summary["bad_scans"]:
        print(f"{len(summary['bad_scans'])} bad scans skipped")
