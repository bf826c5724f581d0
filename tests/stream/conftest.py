"""Fixtures of the stream tests: a fake live camera, a fading source."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest


def _nothing() -> None:
    return None


@pytest.fixture
def fake_camera(monkeypatch: pytest.MonkeyPatch) -> Callable[..., None]:
    """Install a fake ``cv2.VideoCapture`` (any index opens, reporting ``fps`` frames/s, 30
    unless given, and ``size`` for any other property): call ``fake_camera(n_frames,
    before_read=..., on_frame=..., on_end=..., fps=..., size=...)``. Each ``read()``
    calls ``before_read``; the first ``n_frames`` reads then call ``on_frame`` and return a
    grey 80x60 image, later ones call ``on_end`` and fail (the camera has stopped)."""
    import cv2

    def install(n_frames: int = 5, before_read: Callable[[], None] = _nothing,
                on_frame: Callable[[], None] = _nothing,
                on_end: Callable[[], None] = _nothing, fps: float = 30.0,
                size: float = 30.0) -> None:
        class FakeCap:
            def __init__(self, index: int) -> None:
                self.n = 0

            def isOpened(self) -> bool:
                return True

            def get(self, prop: int) -> float:
                return fps if prop == cv2.CAP_PROP_FPS else size

            def read(self) -> tuple[bool, np.ndarray | None]:
                before_read()
                self.n += 1
                if self.n > n_frames:
                    on_end()
                    return False, None
                on_frame()
                return True, np.full((60, 80, 3), 100, np.uint8)

            def release(self) -> None:
                pass

        monkeypatch.setattr(cv2, "VideoCapture", FakeCap)

    return install


@pytest.fixture
def fading_source() -> Callable[[float], tuple]:
    """``fading_source(gain)`` -> (three-mic MicArray, recording (3, n) at 16 kHz): white noise
    from azimuth 40 deg, 2 m, free field, for 5 s -- full level for the first second, then
    ``gain`` times it -- over the same sensor noise."""
    from hearsee.audio.arrays import MicArray
    from hearsee.audio.propagation import simulate_free_field
    from hearsee.geometry import sph_to_cart

    def make(gain: float) -> tuple:
        fs = 16000
        arr = MicArray.from_preset("three-mic")
        x = np.random.default_rng(31).standard_normal(5 * fs)
        x[fs:] *= gain
        y = simulate_free_field(x, fs, arr, sph_to_cart(np.radians(40.0), 0.0, 2.0),
                                snr_db=200, rng=1)
        return arr, y + 0.1 * np.random.default_rng(5).standard_normal(y.shape)

    return make
