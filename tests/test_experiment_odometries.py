"""`lf3pm experiment odometries` end to end, at a reduced size: one short drive of the boxes
room, the VLP-16, noise-free, two odometries; bad options are one line and exit 2."""

import json
import math

import pytest
from typer.testing import CliRunner

from lf3pm.cli import app
from lf3pm.config import ODOMETRY_DRIVES
from lf3pm.experiments import odometries
from lf3pm.replays import registry
from lf3pm.sensors import get_sensor

#: Two of the registered odometries that take a spinning sensor's scans.
TWO = [name for name, adapter in registry.odometries().items() if adapter.runs_on(get_sensor("vlp16"))][:2]


def test_the_drives_are_the_configurations():
    assert tuple(odometries.DRIVES) == ODOMETRY_DRIVES


@pytest.mark.slow
def test_a_short_noise_free_drive_writes_the_table_and_records(tmp_path):
    out = tmp_path / "odometries"
    args = ["experiment", "odometries", "-o", str(out), "--scenes", "boxes", "--sensors", "vlp16"]
    args += ["--odometries", ",".join(TWO), "--seeds", "0", "--seconds", "1.5"]
    done = CliRunner().invoke(app, args)
    assert done.exit_code == 0, done.output

    record = json.loads((out / "odometries.json").read_text())
    assert record["schema"] == odometries.SCHEMA
    assert record["settings"]["scenes"] == ["boxes"] and record["settings"]["seconds"] == 1.5
    assert record["command"].startswith("lf3pm experiment odometries -o ")
    rows = [odometries.OdometryRow(**row) for row in record["rows"]]
    assert [(r.scene, r.sensor, r.data, r.odometry) for r in rows] == [
        ("boxes", "vlp16", "noise-free", name) for name in TWO
    ]
    for row in rows:
        assert row.schema == odometries.SCHEMA and row.skipped is None and not row.noisy
        assert 14 <= row.scans <= 17  # the scans scored: 1.5 s of the figure of eight at 10 Hz
        numbers = (row.ape_rmse, row.ape_max, row.ape_aligned_rmse, row.tilt_deg, row.ms_per_scan, row.rest_drift_m)
        assert all(math.isfinite(x) for x in numbers), row
        assert 0 < row.ape_rmse <= row.ape_max < 0.05, row  # noise-free: centimetres at most
        assert row.ape_aligned_rmse < 0.05 and row.tilt_deg < 1.0 and row.rest_drift_m < 0.05, row
        assert abs(row.shift_s) < 0.05, row

    table = (out / "odometries.md").read_text()
    assert record["command"] in table
    body = [line for line in table.splitlines() if line.startswith("| boxes |")]
    assert [line.split(" | ")[3] for line in body] == TWO
    assert not list(out.glob(".*.tmp"))


@pytest.mark.parametrize(
    "option, value, text",
    [
        ("--scenes", "nowhere", "--scenes must be"),
        ("--odometries", "nothing", "unknown odometry 'nothing'"),
        ("--settings", "{bad", "--settings is not JSON"),
    ],
)
def test_a_bad_option_is_one_line_and_exit_2(tmp_path, option, value, text):
    done = CliRunner().invoke(app, ["experiment", "odometries", "-o", str(tmp_path / "o"), option, value])
    lines = [line for line in done.output.splitlines() if line.strip()]
    assert done.exit_code == 2 and len(lines) == 1, done.output
    assert lines[0].startswith("lf3pm: error:") and text in lines[0], done.output
    assert not (tmp_path / "o" / "odometries.json").exists()


def test_a_sensor_an_odometry_cannot_take_is_a_row_without_numbers(tmp_path):
    """An odometry that needs rings on a non-repetitive sensor: n/a in the table, no replay run."""
    mid70 = get_sensor("mid70")
    spinning_only = [name for name, adapter in registry.odometries().items() if not adapter.runs_on(mid70)]
    if not spinning_only:
        pytest.skip("every registered odometry takes the Mid-70")
    only = spinning_only[:1]
    rows = odometries.run(tmp_path, scenes=["boxes"], sensors=["mid70"], odometries=only, seeds=0, seconds=0.5)
    assert len(rows) == 1 and rows[0].skipped and rows[0].ape_rmse is None
    assert "n/a (" in (tmp_path / "odometries.md").read_text()
