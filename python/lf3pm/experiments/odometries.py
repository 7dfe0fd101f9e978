"""The LIO replay's odometries side by side (docs/lio.md, "Two odometries"): every one
fed exactly the same scans and IMU samples through ``replay(..., "lio", odometry=...)``,
as ``lf3pm replay --method lio --odometry`` runs them.

    lf3pm experiment odometries -o DIR [--scenes boxes,houses,gobi,tunnel] [--sensors vlp16,mid70]
    # one odometry's settings against its defaults, over noisy seeds 0-2:
    lf3pm experiment odometries -o DIR --sensors mid70 --odometries genz --seeds 3 \\
        --settings '{"mapping": {"voxel_size": 1.0}}'

Drives (:data:`DRIVES`; 10 Hz motion-distorted scans, 200 Hz BMI088 IMU, the replay
section's rest at the first pose; each from rest, the speed ramped C2 to 1 m/s over 2 s
as a plan starts):

- boxes: the boxes room, a figure of eight between the boxes with the sensor swinging
  +-0.6 rad about the direction of travel (lf3pm.replays.analytic_motion);
- houses: 15 s along the street of the houses scene, yawing at 0.1 rad/s;
- gobi: 8 s out of the reduced gobi's town square, yawing at 0.3 rad/s;
- tunnel: 15 s from the west plaza into the tunnel (degenerate along its axis);
- hall: the boxes scene made a hall, 29 x 29 x 11 m with 40 boxes at 0.1 m spacing,
  25 s (24 m) diagonally across it yawing at 0.02 rad/s: the VLP-16's +15 degree beams
  never reach its ceiling (docs/lio.md, "LIO-SAM in a hall: a tilt"); hall3: the same
  room with a 3 m ceiling. Neither is in the default list.

Each runs noise-free (scans and IMU) and noisy (the sensor's range noise, the BMI088
preset) on seeds 0 .. seeds-1. Per run (one :class:`OdometryRow`): APE translation RMSE
and max, scored at the times each odometry's poses refer to; the best time shift of the
truth (trajectory_metrics.time_offset); the APE after SE(3) alignment; the tilt of the
last pose's up axis; ms per scan of the odometry alone; and how far the estimate strayed
while the sensor stood still for the rest (m; * where it was still moving at the rest's
end: ReplayResult.rest, docs/lio.md "A still sensor").

Writes DIR/odometries.md (the table, with the command and settings) and
DIR/odometries.json (``schema``, the command, the settings and one record per row).
"""

from __future__ import annotations

import json
import shlex
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from lf3pm.atomic import atomic_write
from lf3pm.config import DEFAULT_HEIGHT, DEFAULTS, ODOMETRY_DRIVES, ConfigError, OdometriesConfig, validated
from lf3pm.map import Map, load_map
from lf3pm.replays import registry
from lf3pm.replays.analytic_motion import CurveMotion, Lissajous, TangentHeading, Warp
from lf3pm.replays.lio import Lio
from lf3pm.replays.motion import Motion
from lf3pm.replays.replay import replay
from lf3pm.replays.trajectory_metrics import time_offset
from lf3pm.scenes import build_scene
from lf3pm.sensors import get_sensor

#: The version of odometries.json's records.
SCHEMA = 1
#: Motion samples per second, as a plan's CSV.
RATE = 100.0
#: The variant label of each odometry's own settings, and of the ``settings`` run beside them.
DEFAULT_VARIANT, SETTINGS_VARIANT = "defaults", "settings"


@dataclass(frozen=True)
class OdometryRow:
    """One replay: a drive, a sensor, its data (noise-free or a noisy seed), an odometry
    with its defaults or the given settings. ``skipped``: why it did not run (the
    odometry cannot take the sensor; its numbers are then None). Lengths in m, the time
    shift in s, the tilt in degrees; ``rest_steady``: whether the estimate had stopped
    moving at the rest's end."""

    scene: str
    sensor: str
    data: str
    seed: int
    noisy: bool
    odometry: str
    variant: str
    skipped: str | None = None
    scans: int | None = None
    ape_rmse: float | None = None
    ape_max: float | None = None
    shift_s: float | None = None
    ape_aligned_rmse: float | None = None
    tilt_deg: float | None = None
    ms_per_scan: float | None = None
    rest_drift_m: float | None = None
    rest_steady: bool | None = None
    schema: int = SCHEMA


def drive(world: Map, start, turn_rate: float, seconds: float) -> Motion:
    """From rest at ``start`` (x, y, yaw): the speed ramps (C2) to 1 m/s over 2 s, the yaw
    turns at up to ``turn_rate`` rad/s with the same ramp (the yaw is the heading); the
    sensor DEFAULT_HEIGHT above the ground."""
    t = np.arange(0.0, seconds + 1e-9, 1.0 / RATE)
    v = Warp(0.0, 2.0, seconds, 1.0)(t)[1]  # never reaches its ramp down
    w = turn_rate * v

    def integral(f):
        return np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(t))])

    yaw = start[2] + integral(w)
    vx, vy = v * np.cos(yaw), v * np.sin(yaw)
    return Motion.from_arrays(
        t, start[0] + integral(vx), start[1] + integral(vy), yaw, vx, vy, w, map=world, height=DEFAULT_HEIGHT
    )


def figure_of_eight(world: Map, seconds: float | None = None) -> Motion:
    """The boxes room's figure of eight (tests/test_lio.py's, from rest), cut after
    ``seconds`` (None: whole, 4.5 s)."""
    curve = Lissajous((5.5, -0.5, 1.0), (1.2, 0.9, 0.0), (0.5, 1.0, 1.0))
    analytic = CurveMotion(Warp(0.0, 1.0, 2.5, 1.0), curve, TangentHeading(curve, swing=0.6, swing_rate=2.0))
    end = analytic.t1 if seconds is None else min(analytic.t1, analytic.t0 + seconds)
    t = np.arange(analytic.t0, end + 1e-9, 1.0 / RATE)
    p, v = analytic.position(t), analytic.velocity(t)
    return Motion.from_arrays(
        t, p[:, 0], p[:, 1], analytic.yaw(t), v[:, 0], v[:, 1], analytic.yaw_rate(t), map=world, height=DEFAULT_HEIGHT
    )


def _boxes(seconds):
    world = load_map(build_scene("boxes").points)
    return world, figure_of_eight(world, seconds)


def _straight(scene: str, start, turn_rate: float, length: float, **scene_params):
    def make(seconds):
        world = load_map(build_scene(scene, **scene_params).points)
        return world, drive(world, start, turn_rate, length if seconds is None else min(length, seconds))

    return make


def _gobi(seconds):
    from lf3pm.experiments.gobi import REDUCED

    return _straight("gobi", (0.0, 0.0, 0.0), 0.3, 8.0, seed=REDUCED.seed, **REDUCED.scene_params)(seconds)


def _hall(height: float):
    room = {"room_length": 29.0, "room_width": 29.0, "room_height": height, "boxes": 40, "spacing": 0.1}
    return _straight("boxes", (-6.0, -11.0, 0.785), 0.02, 25.0, **room)


#: Each drive's name -> (its label in the table, seconds (None: whole) -> (map, motion)).
DRIVES = {
    "boxes": ("boxes", _boxes),
    "houses": ("houses", _straight("houses", (-20.0, 0.0, 0.0), 0.1, 15.0)),
    "gobi": ("gobi town", _gobi),
    "tunnel": ("tunnel", _straight("tunnel", (-38.0, 0.0, 0.0), 0.0, 15.0)),
    "hall": ("hall", _hall(11.0)),
    "hall3": ("hall3", _hall(3.0)),
}
assert tuple(DRIVES) == ODOMETRY_DRIVES, "lf3pm.config.ODOMETRY_DRIVES names these drives"


def chosen_odometries(config: OdometriesConfig) -> tuple[str, ...]:
    """The odometries ``config`` compares (every registered one where it names none);
    ConfigError for one the registry does not hold."""
    known = registry.odometries()
    names = config.odometries or tuple(known)
    for name in names:
        if name not in known:
            raise ConfigError(f"unknown odometry {name!r}; use one of {', '.join(known)}")
    return tuple(names)


def command(out: Path, config: OdometriesConfig, odometries: tuple[str, ...]) -> str:
    """The command that runs ``config`` into ``out``."""
    parts = ["lf3pm", "experiment", "odometries", "-o", str(out)]
    parts += ["--scenes", ",".join(config.scenes), "--sensors", ",".join(config.sensors)]
    parts += ["--odometries", ",".join(odometries), "--seeds", str(config.seeds)]
    if config.seconds is not None:
        parts += ["--seconds", f"{config.seconds:g}"]
    if config.settings:
        parts += ["--settings", json.dumps(config.settings)]
    return shlex.join(parts)


def run(
    out: Path,
    config: OdometriesConfig = DEFAULTS.odometries,
    *,
    progress=None,
    **parameters,
) -> list[OdometryRow]:
    """Replays the drives of the odometries section ``config`` (its fields also by name,
    validated there) through each odometry and writes odometries.md and odometries.json
    to ``out``; returns the rows. ``progress(label, total)`` after each replay."""
    if parameters:
        config = validated(OdometriesConfig, "odometries", **{**config.model_dump(), **parameters})
    odometries = chosen_odometries(config)
    sensors = {name: get_sensor(name) for name in config.sensors}
    variants = [(DEFAULT_VARIANT, {})] + ([(SETTINGS_VARIANT, dict(config.settings))] if config.settings else [])
    data = [("noise-free", 0, False)]
    data += [(f"noisy s{seed}" if config.seeds > 1 else "noisy", seed, True) for seed in range(config.seeds)]
    total = len(config.scenes) * len(sensors) * len(data) * len(odometries) * len(variants)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for scene in config.scenes:
        label, make = DRIVES[scene]
        world, motion = make(config.seconds)
        for sensor_name, sensor in sensors.items():
            for data_label, seed, noisy in data:
                noise = {} if noisy else {"noise": 0.0, "imu_noise": False}
                for odometry in odometries:
                    for variant, settings in variants:
                        where = dict(scene=label, sensor=sensor_name, data=data_label, seed=seed, noisy=noisy)
                        where.update(odometry=odometry, variant=variant)
                        if not registry.odometry(odometry).runs_on(sensor):
                            rows.append(OdometryRow(**where, skipped="no rings"))
                        else:
                            result = replay(
                                world, motion, sensor, Lio.name, seed=seed, odometry=odometry, **noise, **settings
                            )
                            rows.append(_row(where, result, motion))
                        if progress:
                            progress(f"{label} / {sensor_name} / {data_label} / {odometry} {variant}", total)
    _write(out, config, odometries, rows)
    return rows


def _row(where: dict, result, motion: Motion) -> OdometryRow:
    """The row of one replay's result."""
    up = result.estimate[-1, :3, 2] @ result.truth[-1, :3, 2]
    rest = result.rest or {}
    return OdometryRow(
        **where,
        scans=int(result.scans),
        ape_rmse=float(result.ape["rmse"]),
        ape_max=float(result.ape["max"]),
        shift_s=float(time_offset(result.times, result.estimate, motion.pose)["offset"]),
        ape_aligned_rmse=float(result.ape_aligned["rmse"]),
        tilt_deg=float(np.degrees(np.arccos(np.clip(up, -1.0, 1.0)))),
        ms_per_scan=float(result.seconds_per_scan["estimate"] * 1e3),
        rest_drift_m=float(rest["drift_m"]) if "drift_m" in rest else None,
        rest_steady=bool(rest["steady"]) if "steady" in rest else None,
    )


COLUMNS = (
    "scene",
    "sensor",
    "data",
    "odometry",
    "APE rmse (m)",
    "APE max (m)",
    "shift (s)",
    "aligned (m)",
    "tilt (deg)",
    "ms/scan",
    "rest (m)",
)


def table(rows: list[OdometryRow], variants: bool) -> str:
    """The rows as a Markdown table (``variants``: the odometry's column names its variant)."""
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "|".join("---" for _ in COLUMNS) + "|"]
    for row in rows:
        name = f"{row.odometry} {row.variant}" if variants else row.odometry
        if row.skipped:
            cells = [f"n/a ({row.skipped})"] + [""] * 6
        else:
            rest = "" if row.rest_drift_m is None else f"{row.rest_drift_m:.3f}" + ("" if row.rest_steady else "*")
            cells = [
                f"{row.ape_rmse:.3f}",
                f"{row.ape_max:.3f}",
                f"{row.shift_s:+.3f}",
                f"{row.ape_aligned_rmse:.3f}",
                f"{row.tilt_deg:.2f}",
                f"{row.ms_per_scan:.1f}",
                rest,
            ]
        lines.append("| " + " | ".join([row.scene, row.sensor, row.data, name, *cells]) + " |")
    return "\n".join(lines)


def _write(out: Path, config: OdometriesConfig, odometries: tuple[str, ...], rows: list[OdometryRow]) -> None:
    run_command = command(out, config, odometries)
    settings = config.model_dump(mode="json")
    text = "\n".join(
        [
            "# The LIO replay's odometries side by side",
            "",
            f"    {run_command}",
            "",
            f"Settings (the odometries section): `{json.dumps(settings)}`; the replay section's defaults "
            f"(rest {DEFAULTS.replay.rest:g} s, {DEFAULTS.replay.rate:g} Hz scans, "
            f"{DEFAULTS.replay.imu_rate:g} Hz IMU).",
            "",
            table(rows, variants=bool(config.settings)),
            "",
            "APE: translation, scored at the times each odometry's poses refer to; shift: the best time shift "
            "of the truth; aligned: the APE after SE(3) alignment; tilt: the last pose's up axis against the "
            "truth's; ms/scan: the odometry alone; rest: how far the estimate strayed while the sensor stood "
            "still (* still moving at the rest's end).",
            "",
        ]
    )
    record = {"schema": SCHEMA, "command": run_command, "settings": settings, "rows": [asdict(r) for r in rows]}
    with atomic_write(out / "odometries.json") as fp:
        fp.write(json.dumps(record, indent=1).encode())
    with atomic_write(out / "odometries.md") as fp:
        fp.write(text.encode())
