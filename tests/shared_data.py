"""The shared data folder for tests that read real maps: $LF3PM_DATA, else ../shared/data
beside the repository (lf3pm.experiments.data); a test whose file is absent skips, saying so."""

from pathlib import Path

import pytest

from lf3pm.experiments.data import shared_data_dir


def shared_file(name: str) -> Path:
    """The path of ``name`` in the shared data folder; skips the calling test when it is absent."""
    path = shared_data_dir() / name
    if not path.is_file():
        pytest.skip(f"{path} is absent: set LF3PM_DATA to the shared data folder (docs: README)")
    return path
