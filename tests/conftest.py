"""Shared fixtures: the real data beside the repository (skipped cleanly when absent)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def shared_data_dir() -> Path:
    """``$HEARSEE_SHARED_DATA`` or ``../shared/data`` next to the repository."""
    env = os.environ.get("HEARSEE_SHARED_DATA")
    return Path(env) if env else REPO.parent / "shared" / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Path of the shared real data; skips the test where it is not present."""
    d = shared_data_dir()
    if not d.is_dir():
        pytest.skip(f"shared data not present at {d}")
    return d
