"""lf3pm audit --map self (lf3pm.audit.SelfMap, issue 42 item 3): each audited scan's map is
the run's other scans at their reference poses, without those within the exclusion window;
the audit measures each scan against exactly that map; bad windows are one line, exit 2."""

from __future__ import annotations

import json

import numpy as np
import pytest
from analytic_scenes import grid_plane
from recorded_runs import pillar_room, simulated_run, write_run
from typer.testing import CliRunner

from lf3pm.audit import SelfMap, audit_run
from lf3pm.cli import app
from lf3pm.config import DEFAULTS, ConfigError, configured
from lf3pm.errors import RunError
from lf3pm.io.voxel import voxel_downsample
from lf3pm.metric import evaluate_points
from lf3pm.runs import Run


@pytest.fixture
def patches(tmp_path):
    """Six scans 1 s apart, each a flat 2 x 2 m patch 10 m further along x than the last:
    whose patches a map holds says which scans it holds."""
    patch = grid_plane((0.0, -1.0, -1.0), np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0]), 2.0, 2.0, 0.1)
    poses = [(10.0 * i, 0.0, 0.0) for i in range(6)]
    return write_run(tmp_path / "run", [patch] * 6, poses, [float(i) for i in range(6)])


def within(window: float):
    """lf3pm's defaults with the run section's exclusion window at ``window`` s."""
    return configured(DEFAULTS, ("run",), "the audit", exclude_window=window)


def patches_in(world) -> set[int]:
    return {int(round(x / 10.0)) for x in np.unique(np.round(world.points[:, 0], 3))}


def test_each_scans_map_leaves_out_the_scans_within_the_window(patches):
    own = SelfMap.of_run(patches, within(1.5))
    assert own.left_out(2.0).tolist() == [False, True, True, True, False, False]
    assert patches_in(own.around(2.0)) == {0, 4, 5}
    assert patches_in(own.around(0.0)) == {2, 3, 4, 5}
    alone = SelfMap.of_run(patches, within(0.0))  # the scan itself only
    assert patches_in(alone.around(3.0)) == {0, 1, 2, 4, 5}
    assert len(alone.whole()) == sum(len(c) for c in alone.clouds)  # the patches do not overlap
    assert own.describe() == {"source": "self", "run": str(patches), "scans": 6, "exclude_window_s": 1.5, "voxel": 0.05}


def test_a_window_that_leaves_no_scan_or_is_negative_is_one_line(patches):
    with pytest.raises(RunError, match=r"every scan lies within 3 s of the scan at 2\.000000 s: no map is left"):
        SelfMap.of_run(patches, within(3.0))  # scans at 0-5 s: the one at 2 s has none beyond 3 s
    with pytest.raises(ConfigError, match="run.exclude_window"):
        within(-1.0)


@pytest.fixture(scope="module")
def room_run(tmp_path_factory):
    """Five noise-free VLP-16 scans of a box room with a pillar, 1 s apart along x."""
    poses = [(x, 0.0, 0.0) for x in (-3.0, -2.0, -1.0, 0.0, 1.0)]
    return simulated_run(tmp_path_factory.mktemp("room"), pillar_room(), poses, [0.0, 1.0, 2.0, 3.0, 4.0])[0]


def test_the_audit_measures_each_scan_against_its_own_map(room_run):
    """Each record's recorded-scan metric is evaluate_points on that scan's map: the run's
    other scans outside the window, nothing else."""
    own = SelfMap.of_run(room_run, within(1.0))
    result = audit_run(room_run, own, "vlp16", every=2, register=False)
    assert [r.index for r in result.records] == [0, 2, 4] and result.map["source"] == "self"
    assert result.map_seconds > 0
    with Run(room_run) as run:
        scans = {s.index: s for s in run.scans()}
    for record in result.records:
        scan = scans[record.index]
        alone = evaluate_points(own.around(scan.stamp), scan.pose, scan.points)
        assert (record.real_q_n, record.real_sigma1) == (alone.q_n, alone.sigma1)
    around = own.around(2.0)
    kept = np.concatenate([own.clouds[i] for i in (0, 4)])
    assert np.array_equal(np.sort(around.points, axis=0), np.sort(voxel_downsample(kept, 0.05), axis=0))


@pytest.mark.slow  # the CLI's first import: over 2 s on 2 cores
def test_the_cli_audits_against_the_run_itself_and_refuses_bad_windows(room_run, tmp_path):
    args = ["audit", str(room_run), "--map", "self", "--exclude-window", "1", "--every", "2", "--no-registration"]
    got = CliRunner().invoke(app, [*args, "--json"])
    assert got.exit_code == 0, got.output
    audit = json.loads(got.stdout)
    assert audit["map"] == {"source": "self", "run": str(room_run), "scans": 5, "exclude_window_s": 1.0, "voxel": 0.05}
    assert len(audit["scans"]) == 3 and audit["timing"]["map_seconds"] > 0
    got = CliRunner().invoke(app, [*args, "-o", str(tmp_path / "out")])
    assert got.exit_code == 0, got.output
    assert "each audited scan's without the scans within 1 s of it" in (tmp_path / "out" / "report.md").read_text()
    for window, message in (("10", "no map is left"), ("-1", "--exclude-window")):
        got = CliRunner().invoke(app, ["audit", str(room_run), "--map", "self", "--exclude-window", window])
        lines = got.stderr.strip().splitlines()
        assert got.exit_code == 2 and len(lines) == 1 and message in lines[0], got.stderr
