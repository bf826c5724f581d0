"""Shared fixtures: the real data beside the repository (skipped cleanly when absent), a
reference GCC-PHAT written independently of hearsee's, a camera capture that hangs and a
full disk (a file size limit)."""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Callable, Iterator
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


@pytest.fixture
def count_calls(monkeypatch):
    """``calls = count_calls(module, "name")`` wraps ``module.name`` so that every call is
    recorded (an entry appended to ``calls``) and then made as before."""

    def count(owner, name: str) -> list:
        calls: list = []
        real = getattr(owner, name)

        def counted(*args, **kwargs):
            calls.append(1)
            return real(*args, **kwargs)

        monkeypatch.setattr(owner, name, counted)
        return calls

    return count


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
def file_size_limit():
    """``with file_size_limit(n):`` the process cannot grow a file beyond ``n`` bytes (the
    write fails with EFBIG, "File too large", as a full disk fails it with ENOSPC): a real
    failure part way through a write, whoever writes. Skipped where there is no
    RLIMIT_FSIZE / SIGXFSZ."""
    resource = pytest.importorskip("resource")
    import signal

    if not hasattr(resource, "RLIMIT_FSIZE") or not hasattr(signal, "SIGXFSZ"):
        pytest.skip("no file size limit on this system")

    @contextlib.contextmanager
    def limit(n: int) -> Iterator[None]:
        soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
        old = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # (else the signal kills us)
        resource.setrlimit(resource.RLIMIT_FSIZE, (n, hard))
        try:
            yield
        finally:
            resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
            signal.signal(signal.SIGXFSZ, old)

    return limit


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


class HangingCapture:
    """A camera capture (OpenCV's read/get/set/release) whose reads block until ``go`` is set
    (by the test), then deliver ``frame_for(n)`` for the n-th read (1-based); ``reads`` and
    ``released`` count the calls. A device that opened and then delivers nothing."""

    def __init__(self, frame_for: Callable[[int], np.ndarray]) -> None:
        self.frame_for = frame_for
        self.go = threading.Event()
        self.reads = 0
        self.released = 0

    def read(self) -> tuple[bool, np.ndarray]:
        self.reads += 1
        self.go.wait(10.0)
        return True, self.frame_for(self.reads)

    def get(self, prop: int) -> float:
        return 30.0

    def set(self, prop: int, value: float) -> bool:
        return True

    def release(self) -> None:
        self.released += 1


@pytest.fixture
def hanging_capture():
    """``hanging_capture(frame_for)`` -> a :class:`HangingCapture`; every one made is let go
    (``go`` set) when the test ends, so that no read thread outlives it."""
    made: list[HangingCapture] = []

    def make(frame_for: Callable[[int], np.ndarray]) -> HangingCapture:
        made.append(HangingCapture(frame_for))
        return made[-1]

    yield make
    for cap in made:
        cap.go.set()


def _mjpeg_avi(path: Path, frames: list[np.ndarray], fps: float, dropped=()) -> Path:
    """An MJPEG AVI of ``frames`` at ``fps`` whose frames ``dropped`` are empty chunks, as
    capture tools record a dropped frame (the frame slot is kept, with no picture)."""
    import struct

    import cv2

    def chunk(tag: bytes, data: bytes) -> bytes:
        return tag + struct.pack("<I", len(data)) + data + (b"\0" if len(data) % 2 else b"")

    def lst(kind: bytes, data: bytes) -> bytes:
        return b"LIST" + struct.pack("<I", len(data) + 4) + kind + data

    h, w = frames[0].shape[:2]
    jpgs = [b"" if k in dropped else cv2.imencode(".jpg", f)[1].tobytes()
            for k, f in enumerate(frames)]
    n = len(frames)
    avih = struct.pack("<IIIIIIIIII4I", int(round(1e6 / fps)), 0, 0, 0x10, n, 0, 1, 0, w, h,
                       0, 0, 0, 0)
    strh = b"vidsMJPG" + struct.pack("<IHHIIIIIIIIhhhh", 0, 0, 0, 0, 1000,
                                     int(round(fps * 1000)), 0, n, 0, 0xFFFFFFFF, 0, 0, 0, w, h)
    strf = struct.pack("<IiiHH4sIiiII", 40, w, h, 1, 24, b"MJPG", w * h * 3, 0, 0, 0, 0)
    hdrl = lst(b"hdrl", chunk(b"avih", avih)
               + lst(b"strl", chunk(b"strh", strh) + chunk(b"strf", strf)))
    movi, idx, off = b"", b"", 4
    for j in jpgs:
        c = chunk(b"00dc", j)
        idx += b"00dc" + struct.pack("<III", 0x10 if j else 0, off, len(j))
        movi, off = movi + c, off + len(c)
    body = b"AVI " + hdrl + lst(b"movi", movi) + chunk(b"idx1", idx)
    path.write_bytes(b"RIFF" + struct.pack("<I", len(body)) + body)
    return path


@pytest.fixture(scope="session")
def mjpeg_avi() -> Callable[..., Path]:
    """``mjpeg_avi(path, frames, fps, dropped=())``: writes a hand-built MJPEG AVI whose frames
    ``dropped`` are empty chunks (a capture tool's dropped frames; OpenCV's writer cannot make
    them) and returns its path."""
    return _mjpeg_avi
