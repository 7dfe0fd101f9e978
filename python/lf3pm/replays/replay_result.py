"""The result of one replay, the same for every method (localization, lio,
odometry): truth and estimate per scan, per-scan flags, the errors (evo) and
everything needed to reproduce it. Plain arrays, dicts and strings only, so it
pickles (a study runs replays in worker processes)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar, NamedTuple

import numpy as np

from lf3pm.config import DEFAULTS, ReplayConfig, Section, validated
from lf3pm.errors import Lf3pmError
from lf3pm.replays.trajectory_metrics import ape_translation, rpe


@dataclass(frozen=True)
class Estimate:
    """What an estimator made of a scan stream: ``poses`` (M, 4, 4) at ``times``
    (M,; None: the scans' ends), ``hits`` (M,) per scan, ``skipped`` scan indices
    it did not use, ``seconds`` spent estimating (not simulating),
    ``degenerate_directions`` (M,) where it tracks them, ``report``: anything else
    it said."""

    poses: np.ndarray
    hits: np.ndarray
    skipped: list
    seconds: float
    degenerate_directions: np.ndarray | None = None
    report: dict = field(default_factory=dict)
    times: np.ndarray | None = None


class MethodRun(NamedTuple):
    """What a replay method's run gives: the Estimate, the parameters the replay records
    under the method's name, and the versions of the libraries it used."""

    estimate: Estimate
    params: dict
    versions: dict


class SectionMethod:
    """A replay method (lf3pm.replays.methods.ReplayMethod) whose settings are one section
    of the configuration, ``section`` by its name in :class:`lf3pm.config.Config`: made
    from it (``from_config``) or from its defaults updated by keyword parameters
    (``from_params``). No rest, no odometry of the registry."""

    name: ClassVar[str]
    section: ClassVar[str]
    rest = 0.0
    uses_odometry = False

    def __init__(self, settings: Section | None = None):
        self.settings = getattr(DEFAULTS, self.section) if settings is None else settings

    @classmethod
    def from_params(cls, params: dict):
        return cls(method_settings(cls.name, getattr(DEFAULTS, cls.section), params))

    @classmethod
    def from_config(cls, config):
        return cls(getattr(config, cls.section))


def method_settings(method: str, defaults: Section, params: dict) -> Section:
    """``defaults`` (a replay method's settings section) updated by ``params``: Lf3pmError
    naming an unknown parameter and the known ones, ConfigError a bad value."""
    known = type(defaults).model_fields
    unknown = sorted(set(params) - set(known))
    if unknown:
        raise Lf3pmError(f"unknown parameter(s) for {method}: {', '.join(unknown)}; known: {', '.join(known)}")
    return validated(type(defaults), method, **{**defaults.model_dump(), **params})


def library_versions(*packages: str) -> dict:
    """Installed versions of lf3pm, evo (the metrics) and ``packages``."""
    from importlib.metadata import PackageNotFoundError, version

    out = {}
    for name in ("lf3pm", "evo", *packages):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = None
    return out


@dataclass(frozen=True)
class ReplayResult:
    """A replay of ``method`` with ``sensor`` under ``seed``.

    ``times`` (M,): the times the estimate refers to (s; the scans' ends, but for
    an odometry that estimates each scan at another time, DLIO's and LIO-SAM's median return
    time); ``truth``, ``estimate`` (M, 4, 4): sensor-to-world poses there; ``hits`` (M,): returns per scan;
    ``skipped``: indices of the scans the estimator did not use (too few
    points; the estimate kept its prediction); ``degenerate_directions`` (M,):
    per scan, the directions in which registration was degenerate and the
    estimate followed its prior (localization; zeros for the others).
    ``ape``: APE translation without alignment (the estimate starts at the
    true first pose, the headline number); ``ape_aligned`` after the SE(3)
    Umeyama alignment; ``rpe_frame`` over one scan, ``rpe_metre`` over 1 m of
    path. ``seconds_per_scan``: wall time split into "simulate" (the scans) and
    "estimate" (the method). ``params``: every parameter of the run;
    ``versions``: lf3pm and the libraries that produced the estimate and the
    metrics; ``report``: what the estimator itself said (e.g. a lost track);
    ``rest``: after a rest before the trajectory (the LIO's), what the estimate did
    while the sensor stood still (:func:`rest_motion`; empty without a rest).
    """

    method: str
    sensor: str
    seed: int
    times: np.ndarray = field(repr=False)
    truth: np.ndarray = field(repr=False)
    estimate: np.ndarray = field(repr=False)
    hits: np.ndarray = field(repr=False)
    skipped: list
    degenerate_directions: np.ndarray = field(repr=False)
    ape: dict
    ape_aligned: dict
    rpe_frame: dict
    rpe_metre: dict
    seconds_per_scan: dict
    params: dict
    map_sha256: str
    versions: dict
    report: dict = field(default_factory=dict)
    rest: dict = field(default_factory=dict)

    @classmethod
    def evaluate(cls, *, times, truth, estimate, degenerate_directions=None, **fields) -> ReplayResult:
        """The result with its metrics computed from ``truth`` and ``estimate``."""
        truth, estimate = np.asarray(truth, float), np.asarray(estimate, float)
        directions = (
            np.zeros(len(truth), np.int8)
            if degenerate_directions is None
            else np.asarray(degenerate_directions, np.int8)
        )
        return cls(
            times=np.asarray(times, float),
            truth=truth,
            estimate=estimate,
            degenerate_directions=directions,
            ape=ape_translation(truth, estimate),
            ape_aligned=ape_translation(truth, estimate, align=True),
            rpe_frame=rpe(truth, estimate, delta=1, unit="frames"),
            rpe_metre=rpe(truth, estimate, delta=1.0, unit="m"),
            **fields,
        )

    @classmethod
    def from_run(
        cls, run: Estimate, *, scans, first: int = 0, replay: ReplayConfig = DEFAULTS.replay, **fields
    ) -> ReplayResult:
        """The result of ``run`` on the ScanStream ``scans`` (its times, truth and
        simulation time), scored from scan ``first`` on (earlier scans: a rest before the
        trajectory, for the estimator to initialise), the estimate re-anchored there to
        the true pose (an odometry's frame is arbitrary; what it did while the robot stood
        still is not the trajectory's, but is reported: ``rest``, :func:`rest_motion` with
        the replay section ``replay``)."""
        count, keep = len(scans), slice(first, None)
        directions = run.degenerate_directions
        times, truth = estimate_times(run, scans)
        estimate = run.poses[keep]
        rest = {}
        if first:
            rest = rest_motion(times[: first + 1], truth[: first + 1], run.poses[: first + 1], replay)
            estimate = truth[first] @ np.linalg.inv(estimate[0]) @ estimate
        return cls.evaluate(
            times=times[keep],
            truth=truth[keep],
            estimate=estimate,
            hits=run.hits[keep],
            skipped=[k - first for k in run.skipped if k >= first],
            degenerate_directions=None if directions is None else directions[keep],
            seconds_per_scan={"simulate": scans.seconds / count, "estimate": run.seconds / count},
            report=dict(run.report),
            rest=rest,
            **fields,
        )

    @property
    def scans(self) -> int:
        return len(self.times)

    @property
    def degenerate(self) -> np.ndarray:
        """Per scan (M,): whether any direction was degenerate."""
        return self.degenerate_directions > 0

    @property
    def errors(self) -> np.ndarray:
        """Per scan (M,): the translation error |t(estimate) - t(truth)| (m)."""
        return np.asarray(self.ape["errors"])

    def to_dict(self, trajectories: bool = False) -> dict:
        """JSON-ready summary (NaN as None, per-pose error lists dropped); with
        ``trajectories`` also the times, the x y z of truth and estimate and the
        per-scan errors."""
        out = {
            "method": self.method,
            "sensor": self.sensor,
            "seed": self.seed,
            "scans": self.scans,
            "skipped": [int(k) for k in self.skipped],
            "degenerate_scans": int(np.count_nonzero(self.degenerate)),
            "degenerate_directions": self.degenerate_directions.tolist(),
            "ape": _clean(self.ape),
            "ape_aligned": _clean(self.ape_aligned),
            "rpe_frame": _clean(self.rpe_frame),
            "rpe_metre": _clean(self.rpe_metre),
            "seconds_per_scan": _clean(self.seconds_per_scan),
            "scans_per_second": _clean(self.scans_per_second),
            "params": _clean(self.params),
            "map_sha256": self.map_sha256,
            "versions": dict(self.versions),
            "report": _clean(self.report),
            "rest": _clean(self.rest),
        }
        if trajectories:
            out["times"] = self.times.tolist()
            out["truth_xyz"] = self.truth[:, :3, 3].tolist()
            out["estimate_xyz"] = self.estimate[:, :3, 3].tolist()
            out["errors"] = self.errors.tolist()
        return out

    @property
    def scans_per_second(self) -> dict:
        """Throughput: scans per second of simulation, of estimation and of both."""
        s = self.seconds_per_scan

        def inverse(x):
            return 1.0 / x if x > 0 else math.inf

        return {
            "simulate": inverse(s["simulate"]),
            "estimate": inverse(s["estimate"]),
            "total": inverse(s["simulate"] + s["estimate"]),
        }


def estimate_times(run: Estimate, scans) -> tuple[np.ndarray, np.ndarray]:
    """The times ``run``'s poses refer to on the ScanStream ``scans`` (the scans' ends,
    unless the estimator gives its own: DLIO's and LIO-SAM's median return times) and the true poses
    there."""
    if run.times is None or np.array_equal(run.times, scans.times):
        return scans.times, scans.truth
    times = np.asarray(run.times, float)
    return times, scans.motion.pose(times)


def rest_motion(times, truth, poses, replay: ReplayConfig = DEFAULTS.replay) -> dict:
    """What an estimate did while the sensor stood still: ``times`` (n,), ``truth`` and
    ``poses`` (n, 4, 4) of the rest's scans and the first of the trajectory, the
    estimate anchored at the true first pose. ``drift_m``: its largest distance from
    the truth; ``speed_mps``: its mean speed over the replay section ``replay``'s
    last ``rest_window`` s; ``steady``: that speed at most its ``rest_speed_limit``
    (faster hands the trajectory a velocity error: its APE then measures the odometry's
    start, not the trajectory)."""
    times = np.asarray(times, float)
    estimate = truth[0] @ np.linalg.inv(poses[0]) @ poses
    drift = np.linalg.norm(estimate[:, :3, 3] - truth[:, :3, 3], axis=1)
    back = int(np.searchsorted(times, times[-1] - replay.rest_window - 1e-9))
    span = times[-1] - times[back]
    speed = float(np.linalg.norm(estimate[-1, :3, 3] - estimate[back, :3, 3]) / span) if span > 0 else 0.0
    return {
        "seconds": float(times[-1] - times[0]),
        "drift_m": float(drift.max()),
        "speed_mps": speed,
        "steady": bool(speed <= replay.rest_speed_limit),
    }


def _clean(value):
    """JSON-ready: dicts recursively without per-pose lists, numpy arrays as
    lists and scalars as Python numbers, non-finite floats as None."""
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items() if k not in ("errors", "alignment")}
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


#: (key, table header, value) of each figure a replay reports per seed: the CLI's table
#: and JSON, and lf3pm.replay_seeds's medians.
FIGURES = (
    ("ape_rmse", "APE", lambda r: r.ape["rmse"]),
    ("ape_max", "APE max", lambda r: r.ape["max"]),
    ("ape_aligned_rmse", "aligned", lambda r: r.ape_aligned["rmse"]),
    ("rpe_scan_rmse", "RPE scan", lambda r: r.rpe_frame["translation"]["rmse"]),
    ("rpe_scan_deg_rmse", "RPE deg", lambda r: r.rpe_frame["rotation_deg"]["rmse"]),
    ("rpe_metre_rmse", "RPE 1 m", lambda r: r.rpe_metre["translation"]["rmse"]),
    ("degenerate_scans", "degen", lambda r: int(r.degenerate.sum())),
    ("skipped_scans", "skip", lambda r: len(r.skipped)),
    ("scans_per_second", "scans/s", lambda r: r.scans_per_second["total"]),
)
#: The FIGURES in metres.
METRE_FIGURES = {"ape_rmse", "ape_max", "ape_aligned_rmse", "rpe_scan_rmse", "rpe_metre_rmse"}


def median_figures(results) -> dict:
    """Median over seeds of each of FIGURES (None where no seed has it)."""
    out = {}
    for key, _, get in FIGURES:
        values = np.array([get(r) for r in results], dtype=float)
        values = values[np.isfinite(values)]
        out[key] = float(np.median(values)) if len(values) else None
    return out


@dataclass(frozen=True)
class ReplaySeries:
    """Replays of one trajectory on consecutive seeds: ``results`` (one ReplayResult per
    seed) and ``median``, each of FIGURES' median over them."""

    results: list
    median: dict

    def to_dict(self, trajectories: bool = False) -> dict:
        """JSON-ready: each run's :meth:`ReplayResult.to_dict` (with ``trajectories`` its
        times, true and estimated positions and errors too) and the medians."""
        return {
            "seeds": [r.seed for r in self.results],
            "runs": [r.to_dict(trajectories) for r in self.results],
            "median": self.median,
        }
