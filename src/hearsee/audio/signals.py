"""Source signals for simulation and tests.

White noise here; synthetic voices, WAV loading/resampling and recording validation are added
alongside (see the module's functions). Amplitudes are dimensionless, sample rates in Hz.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["white_noise"]


def white_noise(duration_s: float, fs: float, rng: np.random.Generator | int | None = None) -> NDArray:
    """Unit-variance Gaussian white noise of ``duration_s`` seconds at ``fs`` Hz."""
    rng = np.random.default_rng(rng)
    return rng.standard_normal(int(round(duration_s * fs)))
