"""`lf3pm experiment table1` end to end, at a reduced size."""

import json
import math

import pytest

from lf3pm.experiments import table1


@pytest.mark.slow
def test_table1_writes_summary_table_and_figure(tmp_path):
    summary = table1.run(tmp_path, poses=1, trials=2)
    on_disk = json.loads((tmp_path / "summary.json").read_text())
    assert set(on_disk) == {"houses", "house_meadow", "meadow", "wall"}
    for scene, entry in on_disk.items():
        for key in ("q_min", "q_n", "q_max", "mde"):
            assert math.isfinite(entry[key]) and entry[key] > 0, (scene, key)
        assert entry["q_min"] <= entry["q_n"] <= entry["q_max"]
        assert set(entry["by_sensor"]) == {"mid70", "vlp16"}
        assert entry["params"]["trials"] == 2
    # The degenerate wall is the worst scene by MDE for both sensors.
    for sensor in ("mid70", "vlp16"):
        wall = summary["wall"]["by_sensor"][sensor]["mde"]
        assert all(wall > summary[s]["by_sensor"][sensor]["mde"] for s in ("houses", "meadow"))
    assert "| wall | vlp16 |" in (tmp_path / "table1.md").read_text()
    assert (tmp_path / "table1.png").stat().st_size > 10_000
