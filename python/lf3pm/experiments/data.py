"""Where the real maps live: the shared data folder."""

from __future__ import annotations

import os
from pathlib import Path

#: The repository's root (for the default location of the shared data).
REPO = Path(__file__).resolve().parents[3]


def shared_data_dir() -> Path:
    """The shared data folder: $LF3PM_DATA, else ../shared/data beside the repository."""
    return Path(os.environ.get("LF3PM_DATA", REPO.parent / "shared" / "data"))
