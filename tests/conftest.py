"""Shared fixtures: the real data beside the repository (skipped cleanly when absent) and a
reference GCC-PHAT written independently of hearsee's."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
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


@pytest.fixture
def deny_reading(monkeypatch):
    """``deny_reading("open")`` makes that ``pathlib.Path`` method raise PermissionError, as for
    a file without read permission (the tests run as root, where chmod does not stop reads)."""

    def deny(method: str) -> None:
        def denied(self, *args, **kwargs):
            raise PermissionError(13, "Permission denied", str(self))

        monkeypatch.setattr(Path, method, denied)

    return deny


def _reference_gcc_phat(a, b, fs: float, max_lag_s: float, interp: int = 256) -> float:
    """Textbook whole-signal GCC-PHAT, ``t_a - t_b`` in seconds, interpolated by zero padding
    the spectrum ``interp`` times: the ground-truth check of delays the tests simulate."""
    n = len(a) + len(b)
    G = np.fft.rfft(a, n) * np.conj(np.fft.rfft(b, n))
    G /= np.abs(G) + 1e-12
    cc = np.fft.irfft(G, n * interp)
    m = int(np.ceil(max_lag_s * fs * interp))
    cc = np.concatenate([cc[-m:], cc[: m + 1]])
    return (np.argmax(cc) - m) / (interp * fs)


@pytest.fixture(scope="session")
def gcc_phat_ref():
    """The reference GCC-PHAT ``(a, b, fs, max_lag_s, interp=256) -> seconds``."""
    return _reference_gcc_phat


@pytest.fixture
def unraisable():
    """The exceptions Python could only report as "Exception ignored in" (``sys.unraisablehook``:
    e.g. one raised while a generator is closed at garbage collection) during the test, listed
    instead of printed (pytest turns them into a warning issued after the test)."""
    import gc
    import sys

    seen: list = []
    old = sys.unraisablehook
    sys.unraisablehook = lambda u: seen.append(u.exc_value)
    try:
        yield seen
    finally:
        gc.collect()
        sys.unraisablehook = old
