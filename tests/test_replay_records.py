"""The replay records the studies cache (experiments/replay_tasks.py) carry their schema
version, and one of another schema (an older lf3pm's, or none) is refused in one line
naming the file, before any replay runs: never migrated, never read as the new kind."""

import json

import pytest

from lf3pm.experiments.replay_tasks import SCHEMA, ReplayRecordError, ReplayTask, load_replay, run_replays


@pytest.mark.parametrize("data", [{"ape_rmse": 0.1}, {"schema": SCHEMA - 1, "ape_rmse": 0.1}, {"schema": SCHEMA + 1}])
def test_a_record_of_another_schema_is_refused_in_one_line(tmp_path, data):
    path = tmp_path / "default_lio_0.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ReplayRecordError) as refused:
        load_replay(path)
    message = str(refused.value)
    assert str(path) in message and f"not {SCHEMA}" in message and "\n" not in message
    # A study resuming over it stops before it replays anything.
    steps = []
    with pytest.raises(ReplayRecordError):
        run_replays([ReplayTask(None, "plan.csv", "lio", 0, path)], 1, lambda *a, **k: steps.append(a))
    assert steps == []


def test_a_record_of_this_schema_reads_back(tmp_path):
    path = tmp_path / "default_localization_0.json"
    path.write_text(json.dumps({"schema": SCHEMA, "ape_rmse": 0.01}))
    assert load_replay(path) == {"schema": SCHEMA, "ape_rmse": 0.01}
