"""Sound propagation from a point source to microphones.

Free field: exact fractional delays applied in the frequency domain (a linear phase on an
FFT zero-padded past the longest delay, so nothing wraps around), 1/r spherical spreading, near
and far field alike. Rooms: pyroomacoustics' image-source model (see :func:`simulate_room`).

Frames: ``source`` and ``mics`` must be given in the same frame, metres.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
from numpy.typing import ArrayLike, NDArray

from hearsee.audio.arrays import MicArray
from hearsee.errors import AudioInputError, GeometryError

__all__ = ["add_noise", "delay_signals", "simulate_free_field"]


def _mic_positions(mics: MicArray | ArrayLike) -> NDArray:
    if isinstance(mics, MicArray):
        return mics.positions
    p = np.asarray(mics, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3:
        raise GeometryError(f"microphone positions must be N x 3, got shape {p.shape}")
    return p


def delay_signals(signal: ArrayLike, delays_s: ArrayLike, fs: float, gains: ArrayLike = 1.0,
                  n_out: int | None = None) -> NDArray:
    """Delay one signal by several (fractional) delays at once.

    Parameters
    ----------
    signal : array (n,)
        The source waveform.
    delays_s : array (n_ch,)
        Non-negative delays in seconds (any real value, not restricted to whole samples).
    fs : float
        Sample rate in Hz.
    gains : float or array (n_ch,)
        Amplitude factor per channel.
    n_out : int, optional
        Output length in samples (default: ``n``).

    Returns
    -------
    array (n_ch, n_out)
        ``y[k](t) = gains[k] * signal(t - delays_s[k])`` with band-limited interpolation.
    """
    x = np.asarray(signal, dtype=float)
    if x.ndim != 1:
        raise AudioInputError(f"signal must be one-dimensional, got shape {x.shape}")
    d = np.atleast_1d(np.asarray(delays_s, dtype=float))
    if np.any(d < 0) or not np.all(np.isfinite(d)):
        raise GeometryError("delays must be finite and non-negative")
    n_out = len(x) if n_out is None else int(n_out)
    n_fft = sfft.next_fast_len(len(x) + int(np.ceil(d.max() * fs)) + 1, real=True)
    X = sfft.rfft(x, n_fft)
    f = np.arange(X.shape[0]) / n_fft  # cycles per sample
    phase = np.exp(-2j * np.pi * f[None, :] * (d[:, None] * fs))
    Y = X[None, :] * phase
    # keep the Nyquist bin real so that odd fractional delays stay real-valued signals
    if n_fft % 2 == 0:
        Y[:, -1] = Y[:, -1].real
    y = sfft.irfft(Y, n_fft, axis=-1)[:, :n_out]
    return y * np.broadcast_to(np.asarray(gains, dtype=float), d.shape)[:, None]


def add_noise(x: ArrayLike, snr_db: float | None, rng: np.random.Generator | int | None = None,
              reference_power: float | None = None) -> NDArray:
    """Add uncorrelated white Gaussian sensor noise at ``snr_db`` per channel.

    The SNR is relative to ``reference_power`` (default: the mean power of ``x`` over all
    channels). ``snr_db=None`` returns a copy of ``x``.
    """
    y = np.array(x, dtype=float)
    if snr_db is None:
        return y
    rng = np.random.default_rng(rng)
    p = float(np.mean(y**2)) if reference_power is None else float(reference_power)
    if p <= 0:
        raise AudioInputError("cannot set an SNR for a silent signal")
    sigma = np.sqrt(p / 10 ** (snr_db / 10.0))
    return y + sigma * rng.standard_normal(y.shape)


def simulate_free_field(
    signal: ArrayLike,
    fs: float,
    mics: MicArray | ArrayLike,
    source: ArrayLike,
    snr_db: float | None = None,
    rng: np.random.Generator | int | None = None,
    speed_of_sound: float | None = None,
    far_field: bool = False,
) -> NDArray:
    """Record ``signal`` emitted at ``source`` with microphones at ``mics`` in free field.

    Parameters
    ----------
    signal : array (n,)
        Source waveform at 1 m from the source.
    fs : float
        Sample rate in Hz.
    mics : MicArray or array (n_mics, 3)
        Microphone positions, metres (same frame as ``source``).
    source : array (3,)
        Source position, metres. With ``far_field=True`` only its direction is used: a plane
        wave with equal amplitudes at all microphones.
    snr_db : float, optional
        Per-channel SNR of added white sensor noise (relative to the mean received power).
    speed_of_sound : float, optional
        Defaults to the MicArray's value or 343 m/s.

    Returns
    -------
    array (n_mics, n)
        The microphone signals with their absolute propagation delays ``r_k / c`` (near field)
        or plane-wave delays relative to the first-hit microphone (far field), so ``t_i - t_j``
        is exactly ``MicArray.tdoa(source)`` (or ``tdoa_far``).
    """
    pos = _mic_positions(mics)
    c = speed_of_sound or (mics.speed_of_sound if isinstance(mics, MicArray) else 343.0)
    s = np.asarray(source, dtype=float)
    if s.shape != (3,) or not np.all(np.isfinite(s)):
        raise GeometryError(f"source must be a finite [x, y, z] point, got {source!r}")
    if far_field:
        u = s / np.linalg.norm(s)
        t = -(pos @ u) / c
        t = t - t.min()
        gains = np.ones(len(pos))
    else:
        r = np.linalg.norm(pos - s, axis=1)
        if np.any(r < 1e-3):
            raise GeometryError("the source coincides with a microphone")
        t = r / c
        gains = 1.0 / r
    y = delay_signals(signal, t, fs, gains)
    return add_noise(y, snr_db, rng)
