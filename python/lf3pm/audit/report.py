"""An audit's files (``lf3pm audit -o DIR``): the per-scan CSV, the whole audit as JSON (what
``--json`` prints; `lf3pm view --audit` reads it), the Markdown report with the summary and
the command, and the figures; each written atomically."""

from __future__ import annotations

import csv
import io
import json
import math
from collections import Counter
from pathlib import Path

import numpy as np

from lf3pm.atomic import atomic_write
from lf3pm.audit.figures import along_run_figure, path_figure
from lf3pm.audit.record import csv_columns
from lf3pm.audit.run_audit import RunAudit
from lf3pm.audit.self_map import SELF
from lf3pm.audit.summary import BLOCK_DRAWS, BLOCK_SEED, INTERVALS, PREDICTIONS, REAL_ERRORS

#: The files of an audit folder.
CSV, JSON, REPORT, ALONG_RUN, PATH = "audit.csv", "audit.json", "report.md", "along_run.png", "path.png"


def write_audit(audit: RunAudit, folder, map_points, command: str = "", calibration: dict | None = None) -> list[Path]:
    """Writes ``audit`` into ``folder`` (created if missing): audit.csv (one row per audited
    scan), audit.json (``audit.to_dict()``), report.md (the summary, the bad scans and ``command``), along_run.png and
    path.png (over ``map_points``, N x 3). Returns the paths written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=csv_columns(), lineterminator="\n")
    writer.writeheader()
    for record in audit.records:
        writer.writerow({k: _cell(v) for k, v in record.row().items()})
    written = [folder / CSV, folder / JSON, folder / REPORT, folder / ALONG_RUN, folder / PATH]
    with atomic_write(written[0]) as fp:
        fp.write(text.getvalue().encode())
    with atomic_write(written[1]) as fp:
        fp.write(json.dumps(audit.to_dict()).encode())
    with atomic_write(written[2]) as fp:
        fp.write(report_text(audit, command, calibration).encode())
    along_run_figure(audit.records, written[3])
    path_figure(audit.records, map_points, written[4])
    return written


def _cell(value):
    if isinstance(value, float):
        return "" if math.isnan(value) else repr(value)
    return "" if value is None else value


def _num(value, fmt: str = ".3g") -> str:
    return "-" if value is None or (isinstance(value, float) and not math.isfinite(value)) else format(value, fmt)


def _map_line(described: dict) -> str:
    if described["source"] == SELF:
        return (
            f"- map: the run's own {described['scans']} scans at their reference poses ({described['voxel']:g} m "
            f"voxels), each audited scan's without the scans within {described['exclude_window_s']:g} s of it"
        )
    return f"- map: {described['source']} ({described['points']} points, sha256 {described['sha256'][:12]})"


def report_text(audit: RunAudit, command: str = "", calibration: dict | None = None) -> str:
    """The Markdown report of ``audit``."""
    s, records = audit.summary, audit.records
    timing = audit.to_dict()["timing"]
    lines = [
        f"# Audit of {audit.run}",
        "",
        f"Command: `{command}`" if command else "",
        "",
        _map_line(audit.map),
        f"- sensor (simulated scans, predictions): {audit.sensor}",
        f"- scans audited: {len(records)} (every {audit.every}), bad scans skipped: {len(audit.bad_scans)}",
        f"- settings: {', '.join(f'{k} {v}' for k, v in audit.params.items())}",
        f"- time: metric part {audit.metric_seconds:.1f} s ({_num(timing['metric_scans_per_second'])} scans/s), "
        f"registration {audit.registration_seconds:.1f} s ({_num(timing['registration_scans_per_second'])} scans/s)"
        + (f", each scan's map {audit.map_seconds:.1f} s" if audit.map_seconds else ""),
    ]
    if _same_path(audit.map["source"], audit.run):
        lines.append(
            "- **the map is made of this run's own scans: each scan is registered against a map that contains it**, "
            "which shrinks the real errors and the recorded scan's q_n (docs/real.md)"
        )
    lines += ["", "## Rank correlation (Spearman) of each prediction with each real error", ""]
    lines.append("| prediction | " + " | ".join(REAL_ERRORS) + " |")
    lines.append("|---|" + "---|" * len(REAL_ERRORS))
    for prediction, label in PREDICTIONS.items():
        cells = []
        for real in REAL_ERRORS:
            c = next(c for c in s.correlations if (c.prediction, c.real_error) == (prediction, real))
            interval = f"[{_num(c.ci_low, '+.2f')}, {_num(c.ci_high, '+.2f')}]"
            cells.append(f"{_num(c.rho, '+.2f')} {interval} ({c.scans} scans)")
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    lines += ["", "Real errors: " + "; ".join(f"`{k}`: {v}" for k, v in REAL_ERRORS.items()) + "."]
    blocks = sorted({c.block for c in s.correlations if c.block})
    lines += [
        "",
        f"Intervals: 95 %, a moving-block bootstrap over the scans in time order ({BLOCK_DRAWS} draws, seed "
        f"{BLOCK_SEED}, blocks of {', '.join(map(str, blocks)) or '-'} scans): neighbouring scans are not independent.",
        "",
    ]
    lines += ["## Real error inside the predicted [10 %, 90 %] interval", ""]
    for (centre, _, _), reals in INTERVALS.items():
        for real in reals:
            share = _num(s.inside_interval[real], ".0%")
            lines.append(f"- `{real}` inside `{centre}`'s: {share} of {s.inside_scans[real]} scans")
        withheld = Counter(getattr(r, f"{centre.removesuffix('_m')}_withheld") for r in records)
        for reason, count in withheld.most_common():
            if reason:
                lines.append(f"- `{centre}` withheld on {count} scans: {reason}")
    lines += ["", "## Along the run (every scan)", ""]
    for t in audit.tracks:
        ape = t.ape
        lines.append(
            f"- {t.method}: APE against the reference rmse {_num(ape['rmse'])} m, median {_num(ape['median'])} m, "
            f"max {_num(ape['max'])} m over {ape['count']} scans ({t.skipped} kept at the prediction; "
            f"{t.seconds:.1f} s)" + (f"; {t.message}" if t.message else "")
        )
    if audit.tracks_withheld:
        lines.append(f"- not run: {audit.tracks_withheld}")
    if audit.lio_withheld and audit.lio_withheld != audit.tracks_withheld:
        lines.append(f"- LiDAR-inertial odometry not run: {audit.lio_withheld}")
    lines += [
        "",
        "## Simulated / recorded q_n",
        "",
        f"Median {_num(s.ratio_median)}, 10 % {_num(s.ratio_p10)}, 90 % {_num(s.ratio_p90)} "
        f"over {s.ratio_scans} scans.",
        "",
        *_simulated_against_recorded(records),
        "",
        "## Scans where the prediction is furthest off",
        "",
    ]
    if s.furthest_off:
        lines.append("| scan | time (s) | x | y | z | yaw (rad) | predicted (m) | real (m) | ln(predicted/real) |")
        lines.append("|---|---|---|---|---|---|---|---|---|")
        for o in s.furthest_off:
            lines.append(
                f"| {o.index} {Path(o.name).name} | {o.stamp:.3f} | {o.x:.3f} | {o.y:.3f} | {o.z:.3f} | {o.yaw:.3f} "
                f"| {_num(o.predicted_error_m)} | {_num(o.error_m)} | {o.log_ratio:+.2f} |"
            )
    else:
        lines.append("None: no scan has both a prediction and a real error.")
    if calibration is not None:
        lines += ["", *_calibration_lines(calibration)]
    problems = [(r.index, r.name, r.sim_error) for r in records if r.sim_error]
    problems += [(r.index, r.name, r.registration_error) for r in records if r.registration_error]
    lines += ["", "## Bad scans and failed parts", ""]
    if not audit.bad_scans and not problems:
        lines.append("None.")
    for bad in audit.bad_scans:
        lines.append(f"- scan {bad.index} skipped: {bad.reason}")
    for index, _, reason in problems:
        lines.append(f"- scan {index}: {reason}")
    lines += [
        "",
        "## Files",
        "",
        f"- `{CSV}`: one row per audited scan (lf3pm.audit.ScanAudit's fields)",
        f"- `{ALONG_RUN}`: errors and predictions along the run",
        f"- `{PATH}`: the run over the map from above, coloured by real error",
        "",
    ]
    return "\n".join(lines)


def _median(records, name: str) -> float:
    values = np.array([getattr(r, name) for r in records], dtype=np.float64)
    values = values[np.isfinite(values)]
    return float(np.median(values)) if len(values) else math.nan


def _calibration_lines(fit: dict) -> list[str]:
    """The run's calibration (lf3pm.audit.calibrate): the factor on the shipped fit, and the
    shipped and recalibrated fits judged on each segment left out."""
    shipped = fit["shipped"]
    lines = [
        "## The predicted localization error calibrated on this run (`--calibrate`)",
        "",
        f"Fitted on {fit['samples']} scans ({fit['provenance']['error']}; predictor: "
        f"{fit['provenance']['predictor']}): the run's errors are **{_num(fit['factor'])} times** what the "
        f"shipped fit predicts (its slope {fit['b']:.3g} kept; interval factors "
        f"{_num(math.exp(fit['log_lo']))} to {_num(math.exp(fit['log_hi']))}). Over the whole run the shipped fit "
        f"holds {_num(shipped['share_inside_interval'], '.0%')} of the scans inside its interval, median factor "
        f"{_num(shipped['median_factor'])} between predicted and real.",
        "",
        "Each segment of the run left out in turn, fitted on the others:",
        "",
        "| segment | scans | inside, recalibrated | median factor, recalibrated | inside, shipped | "
        "median factor, shipped |",
        "|---|---|---|---|---|---|",
    ]
    for name, v in fit["validation"].items():
        lines.append(
            f"| {name} | {v['scans']} | {_num(v['share_inside_interval'], '.0%')} | {_num(v['median_factor'])} | "
            f"{_num(v['shipped']['share_inside_interval'], '.0%')} | {_num(v['shipped']['median_factor'])} |"
        )
    return lines


def _simulated_against_recorded(records) -> list[str]:
    """Medians over scans of what sets the two q_n apart: sigma1, the misfit left after
    the least-squares step, the hits, and the angle between the least observable directions."""
    angles = np.array([r.direction_angle_deg for r in records], dtype=np.float64)
    angles = angles[np.isfinite(angles)]
    within = f"{np.mean(angles <= 20.0):.0%}" if len(angles) else "-"
    return [
        "| median over scans | recorded | simulated |",
        "|---|---|---|",
        f"| hits (after scan_voxel) | {_num(_median(records, 'hits'), '.0f')} "
        f"| {_num(_median(records, 'sim_hits'), '.0f')} |",
        f"| sigma1 | {_num(_median(records, 'real_sigma1'))} | {_num(_median(records, 'sim_sigma1'))} |",
        f"| RMS misfit after the step (m) | {_num(_median(records, 'real_residual_rms_m'))} "
        f"| {_num(_median(records, 'sim_residual_rms_m'))} |",
        "",
        f"Angle between the least observable directions: median {_num(_median(records, 'direction_angle_deg'), '.1f')} "
        f"deg, within 20 deg on {within} of {len(angles)} scans.",
    ]


def _same_path(a: str, b: str) -> bool:
    try:
        return Path(a).resolve() == Path(b).resolve()
    except OSError:
        return False
