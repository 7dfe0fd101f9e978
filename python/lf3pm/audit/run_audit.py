"""Audit a recorded run against a map, scan by scan (lf3pm.runs streams it)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

from lf3pm.audit.record import ScanAudit
from lf3pm.audit.scan_audit import audit_scan
from lf3pm.audit.self_map import SelfMap
from lf3pm.audit.summary import AuditSummary, summarize
from lf3pm.audit.tracks import has_imu, lio_odometries, track_lio, track_localization, track_odometry
from lf3pm.config import DEFAULTS, Config
from lf3pm.errors import Lf3pmError, RunError
from lf3pm.map import Map, as_map
from lf3pm.runs import BadScan, Run
from lf3pm.sensors import Sensor, as_sensor
from lf3pm.validation import RegistrationTarget


@dataclass(frozen=True)
class RunAudit:
    """An audit of a run: one :class:`ScanAudit` per audited scan, the run's bad scans
    (skipped, with the line saying why), the :class:`AuditSummary`, the time spent
    (``metric_seconds``: the real and simulated metric with the prediction, over every
    audited scan; ``registration_seconds``: the registrations; ``map_seconds``: building
    each scan's map, for a map from the run itself) and what produced it; ``tracks``: map
    localization and KISS-ICP along the whole run (lf3pm.audit.tracks), or none, with
    ``tracks_withheld`` saying why, then the LiDAR-inertial odometries along it, or none,
    with ``lio_withheld`` saying why."""

    run: str
    map: dict
    sensor: str
    every: int
    records: tuple
    bad_scans: tuple
    summary: AuditSummary
    metric_seconds: float
    registration_seconds: float
    params: dict = field(default_factory=dict)
    map_seconds: float = 0.0
    tracks: tuple = ()
    tracks_withheld: str | None = None
    lio_withheld: str | None = None

    def to_dict(self) -> dict:
        """JSON-ready: the per-scan records, the bad scans and the summary."""
        scans = len(self.records)
        return {
            "run": self.run,
            "map": self.map,
            "sensor": self.sensor,
            "every": self.every,
            "params": self.params,
            "timing": {
                "metric_seconds": self.metric_seconds,
                "registration_seconds": self.registration_seconds,
                "metric_scans_per_second": _rate(scans, self.metric_seconds),
                "registration_scans_per_second": _rate(scans, self.registration_seconds),
                "map_seconds": self.map_seconds,
                "tracks_seconds": math.fsum(t.seconds for t in self.tracks),
            },
            "tracks": [t.to_dict() for t in self.tracks],
            "tracks_withheld": self.tracks_withheld,
            "lio_withheld": self.lio_withheld,
            "summary": self.summary.to_dict(),
            "bad_scans": [{"index": b.index, "name": b.name, "reason": b.reason} for b in self.bad_scans],
            "scans": [r.to_dict() for r in self.records],
        }


#: The phases an audit's progress names (and a LiDAR-inertial odometry's: :func:`lio_phase`).
AUDITING, TRACKING_PHASE, ODOMETRY_PHASE = "auditing scans", "localization along the run", "KISS-ICP along the run"


def lio_phase(odometry: str) -> str:
    """The progress phase of the LiDAR-inertial ``odometry`` (its key) along the run."""
    from lf3pm.replays import registry

    return f"{registry.odometry(odometry).name} along the run"


def _tracks_withheld(register: bool, track: bool, own: bool) -> str | None:
    if not track:
        return "not asked for"
    if not register:
        return "registrations left out"
    if own:
        return "a map from the run itself is built per audited scan; tracking needs one map"
    return None


def _lio_withheld(tracks_withheld: str | None, odometries: tuple, run, config: Config) -> str | None:
    if tracks_withheld is not None:
        return tracks_withheld
    if not odometries:
        return "none asked for"
    if not has_imu(run, config):
        return "the run has no IMU"
    return None


def _phase(progress, phase: str):
    return None if progress is None else (lambda done, total: progress(done, total, phase))


def _rate(count: int, seconds: float) -> float | None:
    return count / seconds if seconds > 0 else None


def audit_run(
    run,
    map: Map | SelfMap | str,
    sensor: Sensor | str = DEFAULTS.sensor,
    config: Config | None = None,
    *,
    every: int = 1,
    register: bool = True,
    track: bool = True,
    lio: Sequence[str] | None = None,
    progress: Callable[[int, int | None, str], None] | None = None,
) -> RunAudit:
    """Audits every ``every``-th scan (by its index in the run, bad scans counted) of the
    recorded ``run`` (a path, read with ``config``'s run section, bad scans skipped and
    kept) against ``map`` (in the frame of the run's reference poses; a :class:`SelfMap`:
    each scan against the run's own scans outside its window) at its reference pose:
    :func:`lf3pm.audit.audit_scan` with ``sensor`` (a preset, a YAML file or a Sensor) and
    ``config``'s scan, metric and mde sections. ``register=False`` leaves
    the registrations out. ``track``: map localization and KISS-ICP along the whole run
    as well (:mod:`lf3pm.audit.tracks`; each scan's errors into its record), not with
    registrations left out or a map from the run itself; with them, where the run has an
    IMU, the LiDAR-inertial odometries ``lio`` names (registered names; None: every one
    that takes ``sensor``'s scans; empty: none) along it (:func:`lf3pm.audit.tracks.track_lio`;
    each scan's errors into its record's ``lio_errors_m``; a failed odometry's track says
    why, and the audit goes on). ``progress(read, total, phase)``
    is called after each scan read in each phase (total: the run's scans, None where
    unknown). A run without reference poses, or whose scans are all bad,
    raises RunError; an unknown odometry in ``lio``, Lf3pmError, before any scan is read."""
    config = DEFAULTS if config is None else config
    if not (isinstance(every, int) and every >= 1):
        raise Lf3pmError(f"every must be a whole number >= 1, got {every!r}")
    sensor = as_sensor(sensor)
    odometries = lio_odometries(sensor, lio)
    own = isinstance(map, SelfMap)
    map = map if own else as_map(map)
    records: list[ScanAudit] = []
    map_seconds = 0.0
    with Run(run, config.run, skip_bad=True) as opened:
        _check_poses(opened)
        total = opened.scan_count()
        target = RegistrationTarget(map, threads=config.scan.threads) if register and not own else None
        first = None
        seen = 0
        for scan in opened.scans():
            if scan.index % every == 0:
                first = scan.stamp if first is None else first
                world = map
                if own:  # this scan's map, and its registration target, without the scans near it
                    began = time.perf_counter()
                    world = map.around(scan.stamp)
                    target = RegistrationTarget(world, threads=config.scan.threads) if register else None
                    map_seconds += time.perf_counter() - began
                records.append(
                    audit_scan(world, scan, sensor, config, target=target, first_stamp=first, register=register)
                )
            seen = scan.index + 1
            if progress is not None:
                progress(seen, total, AUDITING)
        bad: tuple[BadScan, ...] = tuple(opened.bad_scans)
    if not records:
        raise RunError(f"{run}: no scan to audit ({len(bad)} bad, every {every})")
    tracks, withheld = (), _tracks_withheld(register, track, own)
    lio_withheld = _lio_withheld(withheld, odometries, run, config)
    if withheld is None:
        tracks = (
            track_localization(run, map, sensor, config, target=target, progress=_phase(progress, TRACKING_PHASE)),
            track_odometry(run, sensor, config, progress=_phase(progress, ODOMETRY_PHASE)),
        )
        if lio_withheld is None:
            tracks += tuple(
                track_lio(run, name, sensor, config, progress=_phase(progress, lio_phase(name))) for name in odometries
            )
        records = [
            replace(
                r,
                tracking_error_m=tracks[0].error_at(r.stamp),
                odometry_error_m=tracks[1].error_at(r.stamp),
                lio_errors_m=tuple((t.method, t.error_at(r.stamp)) for t in tracks[2:]),
            )
            for r in records
        ]
    return RunAudit(
        run=str(run),
        map=map.describe(),
        sensor=sensor.name,
        every=every,
        records=tuple(records),
        bad_scans=bad,
        summary=summarize(records),
        metric_seconds=math.fsum(r.metric_seconds for r in records),
        registration_seconds=math.fsum(r.registration_seconds for r in records) if register else 0.0,
        params={
            "scan_voxel": config.scan.scan_voxel,
            "seed": config.scan.seed,
            "noise": config.scan.noise_for(sensor),
            "dof": config.metric.dof,
            "w1": config.metric.w1,
            "association": config.metric.association,
            "starts": config.mde.trials if register else 0,
            "sigma_t": config.mde.sigma_t,
            "sigma_r_deg": config.mde.sigma_r,
            "max_correspondence_distance": config.mde.max_correspondence_distance,
            "max_iterations": config.mde.max_iterations,
            "registration": "small_gicp PLANE_ICP" if register else None,
            **(map.config.map.association_params() if own else map.association_params),
        },
        map_seconds=map_seconds,
        tracks=tracks,
        tracks_withheld=withheld,
        lio_withheld=lio_withheld,
    )


def check_run(run, config: Config | None = None) -> None:
    """RunError in one line when ``run`` cannot be audited before any scan is read: it
    cannot be opened (config's run section), or it has no reference poses."""
    with Run(run, (DEFAULTS if config is None else config).run) as opened:
        _check_poses(opened)


def _check_poses(run: Run) -> None:
    if run.reference is None:
        raise RunError(f"{run.path}: the run has no reference poses: an audit measures each scan at its pose")
