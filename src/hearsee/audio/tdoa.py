"""Time differences of arrival (ITD/TDOA) by generalized cross-correlation (thesis 2.2.1).

The GCC of microphones i and j (thesis eqs. 2.8-2.10, Knapp & Carter 1976)::

    R_ij(tau) = IFFT{ psi(w) G_ij(w) },   G_ij = X_i conj(X_j),   tau* = argmax_tau R_ij(tau)

peaks at ``tau* = t_i - t_j`` (arrival at i minus arrival at j, the house TDOA sign). The
weightings ``psi`` (Knapp & Carter 1976, table I):

``phat``  1 / |G_ij|                              phase transform (thesis eq. 2.9)
``scot``  1 / sqrt(G_ii G_jj)                     smoothed coherence transform
``roth``  1 / G_jj                                Roth processor (j = reference microphone)
``ml``    |g|^2 / (|G_ij| (1 - |g|^2))            Hannan-Thomson / maximum likelihood, with the
                                                  magnitude-squared coherence |g|^2 estimated by
                                                  averaging spectra over ``smooth_frames`` frames
``cc``    1                                       plain cross-correlation

SCOT, ROTH and ML need spectral-density *estimates*; a single frame's periodogram makes every
coherence 1, so their auto/cross spectra are averaged over ``smooth_frames`` neighbouring frames
(a moving average along time). PHAT uses each frame's own cross spectrum.

Lag search is bounded by each pair's physical maximum ``|M_i - M_j| / c0`` plus a margin of
``margin_samples`` samples. The integer peak is refined below one sample either by a parabola
through the three samples around it (``refine="parabolic"``) or -- the default -- by Newton
iterations on the band-limited correlation function evaluated exactly from its spectrum
(``refine="interp"``: frequency-domain interpolation; ``bench/doa.py`` measures both: the
parabola is biased by ~0.1 sample, the interpolation reaches the Cramer-Rao bound with ML).

SNR weighting (``snr_weight=True``, default; reconstruction after ManyEars/ODAS, Valin et al.
2007): the weighting is multiplied per bin by a coherence estimate from each channel's
a-priori SNR against the noise spectrum of the recording's quiet frames, so bins between the
harmonics of a voice and above its band stop counting as much as bins with the source.

Confidence is the peak-to-second-peak ratio: the height of the chosen peak divided by the highest
value of the whole correlation function outside the peak's main lobe (all lags; the lobe is
``max(2, ceil(fs / bandwidth))`` samples either side). A coherent source gives a ratio well
above 1; uncorrelated noise gives a peak in the narrow physical window that is usually lower
than some spurious peak elsewhere (ratio < 1). It is a ratio, not a probability: its range is
0 (a frame without energy, or no positive peak) to :data:`MAX_CONFIDENCE` = 1000 (nothing
above zero outside the lobe: two exact copies of a signal; larger ratios are capped). A voice
in free field at 30 dB SNR gave a median of 4.6 per pair and frame (up to 17), in a room of
RT60 0.3 s at 20 dB 1.3 (up to 3); noise-only frames 0.2-1.2 (three-mic, 64 ms frames).

Frames without a source give no estimate (``valid=False``, TDOA NaN) when either
- their energy is within ``vad_db`` dB of the recording's noise floor (10th percentile of frame
  energies) while the recording has louder frames (a dynamic range above ``vad_db`` + 3 dB;
  when the broadband energy shows no such range, the energy within ``band_hz`` is tested the
  same way, see ``band_vad``), or the frame is digital silence; or
- any pair's confidence is below ``min_confidence``.

The whole-recording estimate (``summary_tdoa_s``) takes the peak of the weighted cross spectra
averaged over the valid frames (more robust than averaging per-frame TDOAs). With three or more
microphones the pairs' peaks are chosen jointly -- nearest the TDOAs of the direction whose
summed correlations are largest -- so that a reflection topping one pair's correlation loses to
the direct path the other pairs agree on (but where the pairs' own peaks close and correlate
better -- a near source, whose curved wavefront no plane wave fits -- the own peaks are kept:
:func:`_closed_own_peaks`); the closure ``t_ij + t_jk = t_ik`` of the pairs' own peaks is the
test that tells a source from uncorrelated noise.

Performance: frames in single precision, all frames and pairs per FFT call, only the band's bins
weighted; refinement only for active frames.

Units: seconds for TDOAs and frame times, Hz for sample rates; frames are the analysis frames of
``frame_ms`` milliseconds every ``hop_ms`` milliseconds.
"""

from __future__ import annotations

import functools
import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import scipy.fft as sfft
from numpy.typing import ArrayLike, NDArray

from hearsee.audio import hum
from hearsee.audio.arrays import MicArray, closure_rms, load_array, pair_closure_projector
from hearsee.audio.localize import IN_PLANE_RANGE_M, _inplane_tdoa, array_geometry
from hearsee.audio.signals import as_samples, check_fs
from hearsee.config import finite_number, is_real, true_or_false, whole_number
from hearsee.errors import (
    AudioInputError,
    ChannelSyncWarning,
    ConfigError,
    DeadMicrophoneWarning,
    DegenerateInputWarning,
    InvertedPolarityWarning,
)
from hearsee.geometry import fibonacci_sphere

__all__ = [
    "ALIAS_LEVEL",
    "DEFAULT_MARGIN_SAMPLES",
    "DEFAULT_SMOOTH_FRAMES",
    "DEFAULT_WINDOW",
    "METHODS",
    "MAX_CONFIDENCE",
    "MAX_FRAME_MS",
    "MAX_PCM_RANGE",
    "MAX_SUMMARY_UPSAMPLE",
    "MAX_UNSCALED_PEAK",
    "MIN_FS_HZ",
    "MIN_UNSCALED_PEAK",
    "REVERB_COHERENCE_GAIN",
    "GccResult",
    "TdoaFrames",
    "band_alias_level",
    "check_analysis_fs",
    "check_frame_for_array",
    "check_frame_ms",
    "check_recording_length",
    "dead_microphones",
    "dead_microphones_text",
    "desynchronized_pairs",
    "dominant_sample",
    "estimate_tdoas",
    "frame_geometry",
    "frame_signals",
    "frame_spectra",
    "gcc",
    "gcc_weighting",
    "inverted_microphones",
    "min_frame_ms",
    "normalize_method",
    "pair_polarity",
    "windowed_frames",
]

#: Weighting names accepted everywhere (CLI spellings ``gcc-phat`` etc. are aliases).
METHODS = ("phat", "scot", "roth", "ml", "cc")
_ALIASES = {
    "gcc-phat": "phat", "gcc-scot": "scot", "gcc-roth": "roth", "gcc-ml": "ml", "gcc-ht": "ml",
    "ht": "ml", "gcc": "phat", "xcorr": "cc",
}
_REFINE = ("interp", "parabolic", "none")
_TINY = 1e-30
#: Largest GCC confidence (peak-to-second-peak ratio; module docstring): the ratio where nothing
#: outside the peak's main lobe is above zero, and the cap of larger ratios.
MAX_CONFIDENCE = 1e3
#: Longest analysis frame and hop, milliseconds (a frame updating less often than this follows
#: nothing that moves; the bound also keeps a mistyped length from allocating gigabytes)
MAX_FRAME_MS = 10_000.0
#: Lowest sample rate accepted (Hz): below it the band holds too little of a voice to time.
MIN_FS_HZ = 4000.0
#: Fewer confident frames than this: the summary averages all frames with energy instead.
_MIN_SUMMARY_FRAMES = 3
#: Largest ``summary_upsample`` of :func:`estimate_tdoas`: the upsampled correlation has
#: ``summary_upsample`` x the frame's FFT length (10**6 asked for 8 GiB with 64 ms frames);
#: beyond a few times the Newton refinement that follows gains nothing.
MAX_SUMMARY_UPSAMPLE = 64
#: Largest ``vad_db`` of :func:`estimate_tdoas`, dB: a frame's energy that far above the
#: recording's noise floor is beyond any microphone's dynamic range (~120 dB for 24 bits).
MAX_VAD_DB = 200.0
#: Bytes of band spectra (complex64, with their float32 power) of a recording's frames that
#: :func:`estimate_tdoas` keeps, so that its activity test, noise spectrum and frame loop share
#: one transform: ~7 minutes of three channels at 16 kHz with a 300-3500 Hz band. Longer
#: recordings are transformed again per ``chunk_frames`` block (memory stays bounded).
SPECTRA_CACHE_BYTES = 64 * 2**20
#: ``coherence_gain`` above which a recording without a noise reference counts as reverberant
#: (``reverb_method``). White noise 1-3 m from the two- and three-mic presets (2 s, 64 ms
#: frames, 300-7500 Hz, seed 901, 8 per cell, widest pair): free field 0.87-1.00 at SNR 0-20
#: dB, RT60 0.3 s 1.03-1.69, RT60 0.6 s 1.39-2.10. Speech, whose spectrum changes from frame
#: to frame, reads lower and spreads more (three-mic, 300-3500 Hz, seed 902, 5 per cell: free
#: field 0.61-1.10, RT60 0.3 s 0.50-1.62), so a talker without pauses rarely switches -- and
#: in free field about as rarely wrongly.
REVERB_COHERENCE_GAIN = 1.1
#: ... and, without redundant pairs, its confidence must exceed this multiple of
#: ``min_confidence``.
_FALLBACK_CONFIDENCE = 1.5
#: ``first_arrival`` of :func:`estimate_tdoas`: relative height within which a correlation peak
#: further from zero lag (on the same side) counts as the direct path of the highest one's
#: family of reflections
FIRST_ARRIVAL = 0.1
#: ... a peak that counts must stand out of the highest one's lobe: its correlation dips by
#: at least this share of the highest's height between them (:func:`_col_depth`). At 48 kHz a
#: voice's main lobe is many samples wide and carries ripples 2 samples from its top, within
#: 4-6 % of its height and dipping by 0.3-2 % (two microphones, free field, 14 of 32 voice
#: summaries moved 2 samples off, 2026-12-07); reflections' peaks dip by 12-93 % (16 kHz,
#: bench/doa's rooms) and 20-50 % (48 kHz, RT60 0.6 s).
FIRST_ARRIVAL_PROMINENCE = 0.05
#: :func:`estimate_tdoas` settings of the whole-recording estimate that ``bench/doa.py`` measures
#: against pyroomacoustics and acoular (bench/results/doa.md): ML (Hannan-Thomson) weighting,
#: switched to PHAT when the recording measures as reverberant, Hann frames (64 ms every 32,
#: the defaults), onsets weighted 3x, frames valid from a peak ratio of 0.8. Tuned for the
#: summary: the per-frame TDOAs are those of ML weighting. ``hearsee localize --summary-tuned``
#: (with ``--in-plane`` for a talker at a planar array's height, as the benchmark) gives the
#: benchmarked summary; the bench's other settings (``refine="none"``, no per-frame detection
#: test) only save CPU, the summary is the same (162 recordings of the bench's kinds checked,
#: 2026-11-27). ``joint="auto"`` changes nothing for the benchmark's two- and three-microphone
#: arrays; it serves planar arrays of four or more (``respeaker-4/6``) in reverberant rooms.
SUMMARY_TUNED: dict[str, Any] = {"method": "ml", "window": "hann", "min_confidence": 0.8,
                                 "onset_weight": 3.0, "reverb_method": "phat", "joint": "auto"}
#: ``joint="auto"`` steers the in-plane search (``"steered"``) for planar arrays of at least this
#: many microphones (see ``joint`` of :func:`estimate_tdoas`)
AUTO_STEERED_MIN_MICS = 4
#: :func:`_joint_peaks`' whole-sphere grid: 4000 directions (~3.2 deg apart) for arrays whose
#: longest pair spans at most this many samples, which then lie within ~0.8 sample of some
#: direction's TDOAs; a longer pair (a wide array, a high sample rate) gets proportionally
#: more directions (their number grows with the square of its length), at most
#: :data:`_MAX_GRID_DIRECTIONS`. With 4000 at any length the grid missed the narrow main lobes of
#: 192 kHz recordings: the three-mic preset's summary 6.5 samples off (every frame right).
_GRID_LAG_SAMPLES = 24.0
_GRID_DIRECTIONS = 4000
_MAX_GRID_DIRECTIONS = 250_000
#: Frames over which SCOT, ROTH and ML average their spectral statistics (``smooth_frames``
#: of :func:`estimate_tdoas`; a stream carries this many minus one as context)
DEFAULT_SMOOTH_FRAMES = 5
#: Samples added to each pair's physical lag bound (``margin_samples`` of
#: :func:`estimate_tdoas`; the stream's :class:`~hearsee.stream.pipeline.FrameGcc` sizes its
#: transforms with it)
DEFAULT_MARGIN_SAMPLES = 1.0
#: Analysis window of :func:`estimate_tdoas` (``window``; the stream's noise spectra are of its
#: frames): Tukey with 25 % tapers
DEFAULT_WINDOW = ("tukey", 0.25)
#: Largest RMS violation (samples) of t_ij + t_jk = t_ik accepted for a summary estimate.
_CLOSURE_TOL_SAMPLES = 2.0
#: Two refined peaks of one pair's whole-recording correlation closer than this (samples) are
#: the same lobe (:func:`_closed_own_peaks`): the local maxima of a correlation band-limited
#: to ``fs / 2`` lie at least ~1.4 samples apart (a sinc's side lobes), refined ones of the
#: same lobe within ~1e-3 sample of each other.
_SAME_LOBE_SAMPLES = 0.5
#: Largest closure residual (samples, per pair: the pair values less their least-squares fit
#: by arrival times) of the pairs' own whole-recording peaks that :func:`_closed_own_peaks`
#: takes for one source's. A pair on another lobe than the others leaves a third of its offset
#: (>= ~1.4 samples) in every residual (three microphones; ``1 - 2 / n`` of it in its own with
#: all pairs of ``n``): >= ~0.47 sample.
_OWN_CLOSURE_SAMPLES = 0.25
#: Lags whose noise-only correlation has less than this share of the zero-lag standard
#: deviation (the frames' windows overlap little there) are left out of the noise floor.
_FLOOR_MIN_PROFILE = 0.8


def normalize_method(method: str) -> str:
    """Canonical weighting name (``"gcc-phat"`` -> ``"phat"``); ConfigError when unknown."""
    m = str(method).lower().strip()
    m = _ALIASES.get(m, m)
    if m not in METHODS:
        raise ConfigError(
            f"unknown GCC method {method!r} (choose one of: {', '.join(METHODS)} or gcc-<name>)"
        )
    return m


# ---------------------------------------------------------------------------------- framing
def min_frame_ms(array: MicArray | str) -> float:
    """The shortest analysis frame, milliseconds, that the stream and the robot accept for
    ``array``: four times its largest pair delay. In a frame not much longer than a pair's
    delay the window leaves the far lags a few overlapping samples and biases the peaks toward
    lag 0: with 1 ms frames (16 samples at 16 kHz; the three-mic preset's largest delay is 7
    samples) the stream tracked a clean white-noise source 149 deg off, 2 ms gave 0.6 deg.
    (:func:`estimate_tdoas` itself only needs the delays inside half a frame.) ``array``: a
    MicArray, a preset name or a YAML path."""
    return 4e3 * float(np.max(load_array(array).max_tdoa()))


def check_frame_for_array(frame_ms: float, array: MicArray, what: str = "frame_ms") -> None:
    """ConfigError naming ``what`` (a file's field) when a frame of ``frame_ms`` milliseconds
    is shorter than :func:`min_frame_ms` of ``array``: the rule of the robot file's and the
    scenario's ``audio.frame_ms``."""
    shortest = min_frame_ms(array)
    if frame_ms < shortest:
        raise ConfigError(f"{what}: {frame_ms} ms is too short for the array's largest "
                          f"delay ({shortest / 4:.2f} ms); use >= "
                          # (rounded up: the nearest would be a refused value)
                          f"{math.ceil(shortest)}{array.units_hint()}")


def check_frame_ms(frame_ms: float, hop_ms: float, *,
                   names: tuple[str, str] = ("frame", "hop")) -> None:
    """ConfigError unless frame length and hop (ms) are both in (0, :data:`MAX_FRAME_MS`].

    ``names`` are what the message calls them (the CLI passes its option names, so that it can
    check them before reading a recording)."""
    what = f"{names[0]} and {names[1]}"
    for name, v in zip(names, (frame_ms, hop_ms), strict=True):
        # (NaN and inf are numbers: the range checks below name them; text or an array was a
        # builtin TypeError or ValueError of the comparison)
        if not (is_real(v) or isinstance(v, float | np.floating)):
            raise ConfigError(f"{name} must be a number of milliseconds, got {v!r}")
    if not (frame_ms > 0 and hop_ms > 0):
        raise ConfigError(f"{what} must be > 0 ms, got {frame_ms} and {hop_ms}")
    if not (frame_ms <= MAX_FRAME_MS and hop_ms <= MAX_FRAME_MS):
        raise ConfigError(f"{what} must be at most {MAX_FRAME_MS:.0f} ms, "
                          f"got {frame_ms} and {hop_ms}")


def check_analysis_fs(fs: float) -> float:
    """``fs`` (Hz, :func:`hearsee.audio.signals.check_fs`) as a float, else an AudioInputError
    when it is below :data:`MIN_FS_HZ`: the one rate check of :func:`estimate_tdoas` and the
    stream (whose 100 Hz file failed on its SRP band instead, "band ... holds too few
    frequency bins")."""
    fs = check_fs(fs)
    if fs < MIN_FS_HZ:
        raise AudioInputError(
            f"sample rate {fs:g} Hz is too low for time-delay estimation (need >= "
            f"{MIN_FS_HZ:g} Hz; 16 kHz or more recommended)"
        )
    return fs


def frame_geometry(fs: float, frame_ms: float, hop_ms: float) -> tuple[int, int]:
    """Frame length and hop in samples for ``frame_ms`` / ``hop_ms`` milliseconds at ``fs`` Hz
    (at least 8 and 1 samples): the one rounding rule of :func:`estimate_tdoas`, the stream and
    the CLI. Both must be in (0, :data:`MAX_FRAME_MS`] (:func:`check_frame_ms`); ``fs`` a
    sample rate (:func:`hearsee.audio.signals.check_fs`)."""
    check_frame_ms(frame_ms, hop_ms)
    fs = check_fs(fs)
    return max(int(round(frame_ms * 1e-3 * fs)), 8), max(int(round(hop_ms * 1e-3 * fs)), 1)


def check_recording_length(n_samples: int, frame_len: int) -> None:
    """AudioInputError unless a recording of ``n_samples`` holds one frame of ``frame_len``
    samples (:func:`frame_signals`; the stream checks a file before streaming it). Both are
    sample counts (ConfigError for anything else)."""
    n_samples = whole_number("n_samples", n_samples, lo=0)
    frame_len = whole_number("frame_len", frame_len)
    if n_samples < frame_len:
        raise AudioInputError(
            f"recording too short: {n_samples} samples, one frame needs {frame_len}; "
            "use a longer recording or a shorter frame (--frame-ms)"
        )


def _float_samples(x: ArrayLike, what: str) -> NDArray:
    """``x`` as it is when it is a float array (its precision kept: the analysis runs in
    float32), else :func:`hearsee.audio.signals.as_samples`' float64 samples (AudioInputError
    naming ``what`` for what is no number). NaN passes: the callers' own checks name it."""
    if isinstance(x, np.ndarray) and x.dtype.kind == "f":
        return x
    return as_samples(x, what, finite=False)


def frame_signals(x: ArrayLike, frame_len: int, hop: int) -> NDArray:
    """Cut signals into overlapping frames.

    Parameters
    ----------
    x : array (n_ch, n) or (n,)
        Signals, one row per channel.
    frame_len, hop : int
        Frame length and hop in samples.

    Returns
    -------
    array (n_ch, n_frames, frame_len)
        A read-only strided view: frame f of channel c is ``x[c, f*hop : f*hop + frame_len]``.
        Trailing samples that do not fill a frame are dropped.
    """
    a = _float_samples(x, "signals")
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2:
        raise AudioInputError(f"signals must be (n_channels, n_samples), got shape {a.shape}")
    # (a fraction was truncated: a frame length of 10.7 cut frames of 10 samples)
    if not all(is_real(v) and float(v).is_integer() for v in (frame_len, hop)):
        raise ConfigError(f"frame length and hop must be whole numbers of samples, got "
                          f"{frame_len!r} and {hop!r}")
    frame_len, hop = int(frame_len), int(hop)
    if frame_len < 2 or hop < 1:
        raise ConfigError(f"frame length must be >= 2 and hop >= 1 samples, got {frame_len}, {hop}")
    check_recording_length(a.shape[1], frame_len)
    # (sliding_window_view(a, frame_len, axis=-1)[:, ::hop] at a third of its overhead)
    n_frames = (a.shape[1] - frame_len) // hop + 1
    return np.lib.stride_tricks.as_strided(
        a, (a.shape[0], n_frames, frame_len), (a.strides[0], hop * a.strides[1], a.strides[1]),
        writeable=False)


# ---------------------------------------------------------------------------------- weighting
def gcc_weighting(method: str, G: NDArray, Gii: NDArray | None = None,
                  Gjj: NDArray | None = None, Gij_avg: NDArray | None = None) -> NDArray:
    """The GCC weighting ``psi(w)`` (real, same shape as ``G``) for cross spectrum ``G``.

    ``Gii``, ``Gjj`` (auto spectra) and ``Gij_avg`` (averaged cross spectrum) are the
    spectral-density estimates SCOT, ROTH and ML need (ignored by PHAT and CC).
    """
    method = normalize_method(method)
    if method == "cc":
        return np.ones(G.shape)
    if method == "phat":
        mag = np.abs(G)
        # 1 / max(|G|, floor), in place (the same bits, no temporaries)
        np.maximum(mag, _TINY + 1e-12 * mag.max(initial=0.0), out=mag)
        return np.divide(1.0, mag, out=mag)
    if Gii is None or Gjj is None:
        raise ConfigError(f"GCC-{method.upper()} needs the auto spectra G_ii and G_jj")
    floor = _TINY + 1e-12 * max(float(Gii.max(initial=0.0)), float(Gjj.max(initial=0.0)))
    # (the floor of products of two spectra; at least the spectra's smallest normal number:
    # _TINY squared is 0 in single precision, and a block of frames of digital silence -- a
    # recorder's lead-in -- got 1 / 0 and 0 / 0 weights, numpy's RuntimeWarnings)
    floor2 = floor * floor
    if isinstance(Gii, np.ndarray) and Gii.dtype.kind == "f":
        floor2 = max(floor2, float(np.finfo(Gii.dtype).tiny))
    if method == "scot":
        return 1.0 / np.sqrt(np.maximum(Gii * Gjj, floor2))
    if method == "roth":
        return 1.0 / np.maximum(Gjj, floor)
    # ml / Hannan-Thomson
    Gc = G if Gij_avg is None else Gij_avg
    mag = np.abs(Gc)
    den = Gii * Gjj
    np.maximum(den, floor2, out=den)
    if den.dtype != mag.dtype or den.shape != mag.shape:  # (numpy's promotions as written)
        coh = np.clip(mag**2 / den, 0.0, 0.99)
        return coh / ((1.0 - coh) * np.maximum(mag, floor))
    # the same in place (one dtype and shape: the same bits, a third of the allocations)
    coh = mag * mag
    coh /= den
    np.clip(coh, 0.0, 0.99, out=coh)
    np.subtract(1.0, coh, out=den)
    den *= np.maximum(mag, floor, out=mag)
    coh /= den
    return coh


# ---------------------------------------------------------------------------------- peaks
def _bin_phase(k: NDArray, nfft: int) -> tuple[NDArray, NDArray]:
    """Angular frequencies (rad per sample) of the rfft bins ``k`` of ``nfft``-point frames and
    irfft's one-sided bin weights (1/2 at DC and Nyquist, 1 elsewhere): the band-limited
    correlation between samples is ``R(tau) = sum_k cw_k Re(P_k exp(j w_k tau))``."""
    return 2.0 * np.pi * k / nfft, np.where((k == 0) | (2 * k == nfft), 0.5, 1.0)


def _refine_interp(P: NDArray, tau0: NDArray, nfft: int, n_iter: int = 3,
                   bins: NDArray | None = None) -> NDArray:
    """Newton iterations for the maximum of ``R(tau) = sum_k c_k Re(P_k exp(j w_k tau))``.

    ``P`` (m, n) weighted spectra at the rfft bin indices ``bins`` (default ``0..n-1``),
    ``tau0`` (m,) start lags in samples. The correlation is evaluated exactly between
    samples (frequency-domain interpolation of the band-limited GCC); the phases are evaluated
    in single precision (error ~1e-6 rad, far below the estimation noise).
    """
    k = np.arange(P.shape[-1]) if bins is None else np.asarray(bins)
    w, cw = _bin_phase(k, nfft)
    Pc = P * cw
    wr = (w * Pc.real).astype(np.float32)
    wi = (w * Pc.imag).astype(np.float32)
    w2r, w2i = (w * wr).astype(np.float32), (w * wi).astype(np.float32)
    w32 = w.astype(np.float32)
    tau = tau0.astype(float).copy()
    for _ in range(n_iter):
        ph = np.outer(tau.astype(np.float32), w32)
        c, s = np.cos(ph), np.sin(ph)
        # Q = Pc e^{j ph}: Im Q = Pr s + Pi c, Re Q = Pr c - Pi s
        d1 = -(np.einsum("mk,mk->m", wr, s) + np.einsum("mk,mk->m", wi, c)).astype(float)
        d2 = -(np.einsum("mk,mk->m", w2r, c) - np.einsum("mk,mk->m", w2i, s)).astype(float)
        ok = d2 < 0
        step = np.where(ok, -d1 / np.where(ok, d2, -1.0), 0.0)
        tau = tau + np.clip(step, -0.5, 0.5)
    # never move more than one sample away from the integer peak
    return np.clip(tau, np.round(tau0) - 1.0, np.round(tau0) + 1.0)


def _take_last(a: NDArray, idx: NDArray) -> NDArray:
    """``a[..., idx]`` elementwise: ``a`` (..., n), ``idx`` (...) integer -> (...). The same as
    ``np.take_along_axis(a, idx[..., None], axis=-1)[..., 0]`` without its per-call overhead,
    which dominates on the few rows of one recording's frames."""
    flat = a.reshape(-1, a.shape[-1])
    return flat[np.arange(flat.shape[0]), idx.reshape(-1)].reshape(idx.shape)


def _lag_window(r: NDArray, max_lag: NDArray, up: int = 1,
                reach: NDArray | None = None) -> tuple[NDArray, NDArray]:
    """The admissible part of circular correlations ``r`` (..., n_pairs, n) sampled ``up``
    times per sample: the grid lags ``-L .. L`` and ``r`` at them (..., n_pairs, 2L+1),
    ``-inf`` beyond each pair's ``+-max_lag`` (samples) -- except the grid lag nearest each
    pair's physical maximum ``reach`` (samples; default none), which is admitted even when it
    is beyond ``max_lag`` (the callers clip the refined lag to ``max_lag``). A source at the
    physical maximum (a pair's axis pointing at it: 6.997 samples) with no margin (bound
    6.997) otherwise had its peak searched on the lobe's flank at lag 6, which the refinement
    does not climb: every frame 0.8-1 sample off, or none valid."""
    lim = max_lag * up
    if reach is not None:
        lim = np.maximum(lim, np.round(np.asarray(reach, dtype=float) * up))
    L = int(np.floor(lim.max()))
    lags = np.arange(-L, L + 1)
    win = r[..., lags % r.shape[-1]]
    outside = np.abs(lags)[None, :] > lim[:, None]  # (n_pairs, 2L+1)
    return lags, np.where(outside, -np.inf, win)


def _peaks(r: NDArray, P: NDArray, nfft: int, max_lag: NDArray, refine: str,
           main_lobe: int, bins: NDArray | None = None,
           need: NDArray | None = None,
           reach: NDArray | None = None) -> tuple[NDArray, NDArray]:
    """Bounded peak search + refinement + confidence.

    ``r`` (..., n_pairs, nfft) circular correlations, ``P`` their spectra, ``max_lag``
    (n_pairs,) largest admissible |lag| in samples, ``reach`` (n_pairs,) the physical maximum
    (samples, :func:`_lag_window`); ``need`` (...) bool selects the rows that get the
    interpolation refinement (others: parabolic). Returns (lag in samples, confidence).
    """
    lags, win = _lag_window(r, max_lag, reach=reach)
    k = np.argmax(win, axis=-1)
    peak = _take_last(win, k)
    lag_i = lags[k]
    lag = lag_i.astype(float)
    if refine != "none":
        # parabolic fit on the integer samples around the peak (values from the full circle)
        ym = _take_last(r, (lag_i - 1) % nfft)
        yp = _take_last(r, (lag_i + 1) % nfft)
        den = ym - 2.0 * peak + yp
        with np.errstate(divide="ignore", invalid="ignore"):
            delta = np.where(den < 0, 0.5 * (ym - yp) / den, 0.0)
        lag = lag + np.clip(delta, -0.5, 0.5)
        if refine != "parabolic":  # "interp": Newton steps from the parabolic peak
            sel = np.ones(lag.shape[:-1], bool) if need is None else np.asarray(need, bool)
            if sel.any():
                n_p = lag.shape[-1]
                Ps = P[sel].reshape(-1, P.shape[-1])
                lag[sel] = _refine_interp(Ps, lag[sel].reshape(-1), nfft,
                                          bins=bins).reshape(-1, n_p)
    lag = np.clip(lag, -max_lag, max_lag)
    # confidence: peak over the highest value of the correlation outside the main lobe (the
    # lobe is ~fs / bandwidth wide, so outside it only competing peaks and side lobes remain)
    lobe = (lag_i.reshape(-1, 1) + np.arange(-main_lobe, main_lobe + 1)) % nfft
    R = r.reshape(-1, nfft)  # a view of r when contiguous; restored below either way
    rows = np.arange(R.shape[0])[:, None]
    saved = R[rows, lobe]
    R[rows, lobe] = -np.inf
    second = R.max(axis=-1).reshape(k.shape)
    R[rows, lobe] = saved
    with np.errstate(divide="ignore", invalid="ignore"):
        conf = np.where(second > 0, peak / second, np.where(peak > 0, MAX_CONFIDENCE, 0.0))
    return lag, np.minimum(conf, MAX_CONFIDENCE)


# ---------------------------------------------------------------------------------- one pair
@dataclass(frozen=True)
class GccResult:
    """Whole-signal GCC of one pair.

    tdoa_s : float          ``t_i - t_j`` in seconds (refined peak within the lag bound)
    confidence : float      peak-to-second-peak ratio, 0 to :data:`MAX_CONFIDENCE` (module
                            docstring; not a probability)
    lags_s : array (m,)     lags of ``r`` in seconds (centred, -nfft/2 .. nfft/2-1 samples)
    r : array (m,)          the weighted cross-correlation function
    """

    tdoa_s: float
    confidence: float
    lags_s: NDArray
    r: NDArray


def _lag_noise_profile(win: NDArray, nfft: int) -> NDArray:
    """Relative standard deviation per circular lag (nfft,) of the correlation of two
    independent whitened noises framed by ``win``: ``sqrt(sum w^2[n] w^2[n+L] / sum w^4)``.
    Far lags overlap less of the two windowed frames and fluctuate less."""
    w2 = np.zeros(nfft)
    w2[: len(win)] = np.asarray(win, float) ** 2
    v = sfft.irfft(np.abs(sfft.rfft(w2)) ** 2, nfft)
    return np.sqrt(np.clip(v / v[0], 0.0, None))


def _peak_snr(r: NDArray, lag: NDArray, max_lag: NDArray, main_lobe: int,
              profile: NDArray) -> NDArray:
    """Height of each correlation peak over the correlation's noise floor.

    ``r`` (..., n_pairs, nfft) circular correlations, ``lag`` (..., n_pairs) their peaks
    (samples); returns (..., n_pairs).
    The floor is a robust standard deviation (1.4826 x median absolute deviation) of the
    correlation at the lags no source can reach (beyond ``max_lag`` plus a main lobe), each
    scaled by the window's :func:`_lag_noise_profile`; a few outlying lags (the pitch period
    of a voice) barely move it. A constant-false-alarm-rate detector (e.g. Richards,
    *Fundamentals of Radar Signal Processing*, ch. 7)."""
    nfft = r.shape[-1]
    alag = np.abs(np.fft.fftfreq(nfft, 1.0 / nfft))
    usable = profile >= _FLOOR_MIN_PROFILE
    out = np.zeros(r.shape[:-1])
    for p in range(r.shape[-2]):
        idx = np.flatnonzero((alag > max_lag[p] + main_lobe) & usable)
        if idx.size == 0:
            raise ConfigError(
                f"band_hz is too narrow for {nfft}-point frames: the correlation's main lobe "
                f"({main_lobe} samples) leaves no lag to measure its noise floor; widen the "
                "band, lengthen the frames or set min_peak_snr and min_frame_peak_snr to 0")
        rp = r[..., p, :]
        ref = rp[..., idx] * (1.0 / profile[idx])
        ref -= _median_last(ref)[..., None]
        np.abs(ref, out=ref)
        sig = 1.4826 * _median_last(ref)
        peak = _take_last(rp, np.round(lag[..., p]).astype(int) % nfft)
        with np.errstate(divide="ignore", invalid="ignore"):
            out[..., p] = np.where(sig > 0, peak / sig, np.where(peak > 0, np.inf, 0.0))
    return out


def _median_last(a: NDArray) -> NDArray:
    """``np.median(a, axis=-1)`` by one partial sort: a third of np.median's time on the
    small arrays of :func:`_peak_snr`, where the per-call overhead dominates."""
    n = a.shape[-1]
    m = n // 2
    part = np.partition(a, m, axis=-1)
    if n % 2:
        return part[..., m]
    return 0.5 * (part[..., :m].max(axis=-1) + part[..., m])


def _band_mask(n_bins: int, nfft: int, fs: float, band_hz: tuple[float, float] | None) -> NDArray:
    if band_hz is None:
        return np.ones(n_bins)
    try:  # (a single number was a builtin TypeError, three numbers used the first two)
        lo, hi = band_hz
    except (TypeError, ValueError):
        lo = hi = None
    if not (is_real(lo) and (is_real(hi) or hi == np.inf) and 0 <= lo < hi):
        raise ConfigError(f"band_hz must be (low, high) with 0 <= low < high, got {band_hz}")
    f = np.arange(n_bins) * fs / nfft
    m = ((f >= lo) & (f <= hi)).astype(float)
    if not m.any():
        raise ConfigError(f"band_hz {band_hz} contains no frequency bin at fs={fs} Hz")
    return m


#: :func:`estimate_tdoas` warns of a band whose correlation repeats within the array's delays at
#: this share of its peak or more (:func:`band_alias_level`): 5000-5200 Hz (0.997) gave the
#: three-mic preset a confident direction 31 deg off, 7000-8000 Hz (0.97) 21 deg off; a speech
#: band of 300-3500 Hz repeats at 0.16
ALIAS_LEVEL = 0.9


def band_alias_level(lo_hz: float, hi_hz: float, max_tdoa_s: float) -> float:
    """How high a GCC over the band ``lo_hz``..``hi_hz`` (Hz) repeats its peak within the delays
    ``+-max_tdoa_s`` (seconds) a pair can have: the correlation of a flat band is its carrier
    at the centre frequency ``fc`` under an envelope ``sinc(B tau)`` of the bandwidth ``B``, so
    the first repeat, ``1 / fc`` from the peak, stands at ``|sinc(B / fc)|`` of it -- when
    ``1 / fc`` fits within the ``2 max_tdoa_s`` the bounded peak search spans (else 0: no
    repeat to take). A narrow band high above the spacing's ``c / 2d`` is spatially aliased:
    its direction can jump to a repeat (0 to 1; ~1: the peaks cannot be told apart)."""
    fc, bw = 0.5 * (lo_hz + hi_hz), hi_hz - lo_hz
    if fc <= 0 or 1.0 / fc > 2.0 * max_tdoa_s:
        return 0.0
    return float(abs(np.sinc(bw / fc)))


def _warn_aliasing(lo_hz: float, hi_hz: float, max_tdoa_s: float) -> None:
    """A :class:`~hearsee.errors.DegenerateInputWarning` when the band ``lo_hz``..``hi_hz``
    (Hz) is spatially aliased for delays up to ``max_tdoa_s`` (:func:`band_alias_level` at
    least :data:`ALIAS_LEVEL`)."""
    level = band_alias_level(lo_hz, hi_hz, max_tdoa_s)
    if level >= ALIAS_LEVEL:
        warnings.warn(
            f"band {lo_hz:.0f}-{hi_hz:.0f} Hz is narrow for its frequencies: its correlation "
            f"repeats every {2e3 / (lo_hz + hi_hz):.3g} ms at {100 * level:.0f} % of its peak "
            f"within the +-{max_tdoa_s * 1e3:.2f} ms the microphones' spacing allows, so the "
            "direction can jump to a repeat (spatial aliasing); widen the band or move it "
            "lower (e.g. 300-3500 Hz for speech)", DegenerateInputWarning, stacklevel=3)


def _main_lobe(bins: NDArray, nfft: int, fs: float, band_hz: Any) -> int:
    """Half-width (samples) of the GCC's main lobe over the contiguous rfft ``bins`` of an
    ``nfft``-point transform at ``fs`` Hz; ConfigError when it leaves no lag outside it."""
    bw = (bins[-1] - bins[0] + 1) * fs / nfft
    main_lobe = max(2, int(np.ceil(fs / bw)))
    if 2 * main_lobe + 1 >= nfft:
        # (nothing outside the main lobe: every confidence was 1e3, "certain", and noise-only
        # recordings gave valid frames and a summary with three or more microphones)
        raise ConfigError(
            f"band_hz {band_hz} is too narrow: {len(bins)} frequency "
            f"bin{'s' * (len(bins) != 1)} of {nfft}-point frames, whose correlation's main "
            f"lobe ({main_lobe} samples either side) covers every lag, so no peak can be told "
            "from a side lobe; widen the band or lengthen the frames")
    return main_lobe


#: How far (dB) below the loudest part of a recording's spectrum its top band must lie, in every
#: bin, for :func:`estimate_tdoas` to leave it out of the GCC (``empty_band_db``). A recording
#: upsampled after it was made (an 8 kHz file read at 16 kHz, a sound server's resampling) holds
#: nothing there but the resampler's mirror images, 80-100 dB down (scipy's polyphase filter) --
#: which PHAT and ML whiten to full weight, and whose cross spectra point at mirrored delays:
#: 8 kHz voices and noise upsampled to 16 kHz came out 11-13 deg off in azimuth (three-mic
#: preset, free field, 20 dB, 2026-12-03), 0.4-0.5 deg with the band left out. A recording
#: made at its rate keeps a noise floor: synthetic voices without any sensor noise lie 38-46
#: dB down at 16 kHz, sensor noise at 0-30 dB SNR far less.
EMPTY_BAND_DB = 60.0
#: Where :func:`estimate_tdoas` ends the band of an upsampled recording. Everything above the old
#: Nyquist frequency is the resampler's image, also in its transition band, just below where the
#: images fall under :data:`EMPTY_BAND_DB` (6-40 dB down there): scipy's polyphase filter (8 to
#: 16 kHz) is empty from 4.7-5.1 kHz, an FFT resampler from the old Nyquist frequency itself. So
#: the band ends at the Nyquist frequency ``f_n`` of the highest standard rate
#: (:data:`STANDARD_RATES_HZ`) at most :data:`EMPTY_BAND_TRANSITION` times below the empty band's
#: edge whose smoothed spectrum at ``f_n`` lies within :data:`EMPTY_BAND_STEP_DB` of the spectrum
#: at 0.9 ``f_n`` (the old Nyquist frequency passes half the amplitude, a standard rate's above
#: it, in the transition band, far less: 22.05 and 24 kHz rates both fit below an upsampled
#: 22.05 kHz recording's edge); with no such rate, at :data:`EMPTY_BAND_GUARD` of the edge.
#: White noise and a synthetic voice at 8, 11.025, 12, 16, 22.05, 24 and 32 kHz upsampled to
#: 16-96 kHz by scipy's polyphase and FFT resamplers (2026-12-03): the old Nyquist frequency
#: found in 98 of 104 cases (within a bin). Missed: scipy's polyphase 12 -> 16 and 32 -> 44.1 kHz
#: (white noise) and 44.1 -> 48 kHz keep images above -60 dB; the FFT resampler's 44.1 -> 48 kHz
#: edge lies above 0.9 of the new Nyquist frequency and is taken for a converter's own (the band
#: keeps 0.2-0.4 kHz of images there). Pass ``band_hz`` for those. 8 kHz white noise read at
#: 16 kHz (three-mic, 20 dB): summary TDOAs 0.1-0.3 us off with the band up to 4.0 kHz, 9 us up
#: to 4.3 kHz, 65-86 us with every bin.
#: An empty band that begins above :data:`EMPTY_BAND_NATIVE` of the Nyquist frequency is a
#: converter's own anti-alias filter, not an upsampler's (CMU ARCTIC's 16 kHz files are empty from
#: 7.4-7.8 kHz): there is no image below it, and the band ends at its edge.
STANDARD_RATES_HZ = (8000, 11025, 12000, 16000, 22050, 24000, 32000, 44100, 48000, 88200,
                     96000, 176400, 192000)
EMPTY_BAND_TRANSITION = 1.4
EMPTY_BAND_STEP_DB = 10.0
EMPTY_BAND_GUARD = 0.85
EMPTY_BAND_NATIVE = 0.9
#: :func:`empty_top_band` smooths the power spectrum over this share of its bins (at least 1)
_EMPTY_BAND_SMOOTH = 1.0 / 64.0


def _smoothed_power(p: NDArray) -> NDArray:
    """``p`` (n_bins,) averaged over a centred window of ``n_bins * _EMPTY_BAND_SMOOTH`` bins
    (at least 1; the ends over the bins they have)."""
    w = max(1, int(round(p.size * _EMPTY_BAND_SMOOTH)))
    return np.convolve(p, np.ones(w), mode="same") / np.convolve(np.ones(p.size), np.ones(w),
                                                                 mode="same")


def empty_top_band(power: ArrayLike, db: float = EMPTY_BAND_DB) -> int | None:
    """The first bin of the empty band at the top of a power spectrum, or None.

    ``power`` (n_bins,) is a mean power spectrum (any linear scale, e.g. ``|X|^2`` averaged
    over frames and channels; its bins evenly spaced, the last the highest frequency). Smoothed
    by a moving average over ``n_bins / 64`` bins (which moves a sharp edge up by up to half
    that), every bin from the returned index on lies more than ``db`` dB below the smoothed
    spectrum's peak, and the bin before it does not -- the top of a recording upsampled after
    it was made (see :data:`EMPTY_BAND_DB`). None when the top bin is not that low, or the
    spectrum is silent or not finite.

    >>> import numpy as np
    >>> p = np.r_[np.ones(100), np.full(100, 1e-9)]   # nothing from bin 100 on
    >>> empty_top_band(p)  # (the 3-bin smoothing blurs the edge by a bin)
    101
    >>> empty_top_band(np.r_[np.ones(100), np.full(100, 1e-3)]) is None  # 30 dB down: a floor
    True
    """
    p = np.asarray(power, dtype=float)
    db = finite_number("db", db, 0.0, lo_open=True)
    if p.ndim != 1 or p.size < 2:
        raise ConfigError(f"power must be a spectrum of 2 or more bins, got shape {p.shape}")
    if not np.all(np.isfinite(p)) or not p.max() > 0:
        return None
    return _top_edge(_smoothed_power(p), db)


def _top_edge(sm: NDArray, db: float) -> int | None:
    """:func:`empty_top_band` of the smoothed spectrum ``sm`` (finite, its peak > 0)."""
    loud = sm >= sm.max() * 10.0 ** (-db / 10.0)
    if loud[-1]:
        return None
    return int(np.flatnonzero(loud)[-1]) + 1


def gcc(x_i: ArrayLike, x_j: ArrayLike, fs: float, method: str = "phat",
        max_tau_s: float | None = None, refine: str = "interp",
        band_hz: tuple[float, float] | None = None) -> GccResult:
    """GCC of two whole signals (one pair, one "frame"): the peak ``t_i - t_j`` in seconds.

    ``max_tau_s`` bounds the lag search (default: the whole correlation). Each signal loses its
    mean first (a DC offset on real ADCs reads as a peak at lag 0). SCOT/ROTH/ML here use
    the single-periodogram spectra, so prefer :func:`estimate_tdoas` (frame-averaged spectra)
    for those weightings.

    >>> rng = np.random.default_rng(0); s = rng.standard_normal(4000)
    >>> round(gcc(np.roll(s, 3), s, 1000.0).tdoa_s, 6)   # x_i lags x_j by 3 samples
    0.003
    """
    a = as_samples(x_i, "gcc: x_i")
    b = as_samples(x_j, "gcc: x_j")
    if a.ndim != 1 or a.shape != b.shape or a.size < 2:
        raise AudioInputError(
            f"gcc needs two 1-D signals of equal length (2 samples or more), got {a.shape}, "
            f"{b.shape}"
        )
    fs = check_fs(fs)
    if np.ptp(a) == 0 or np.ptp(b) == 0:  # (a constant is silence once its mean is removed)
        raise AudioInputError("gcc: a signal is silent (constant); there is nothing to correlate")
    _check_refine(refine)
    method = normalize_method(method)
    if max_tau_s is not None:  # (text was numpy's TypeError, an array its ambiguous truth value)
        max_tau_s = finite_number("max_tau_s (seconds)", max_tau_s, 0.0)
    n = len(a)
    nfft = sfft.next_fast_len(2 * n, real=True)
    # each signal less its mean, as every framed spectrum (windowed_frames): a DC offset,
    # zero-padded, leaks into the lowest bins, which PHAT weighs like any other: a peak at lag 0
    Xa = sfft.rfft(a - a.mean(), nfft)
    Xb = sfft.rfft(b - b.mean(), nfft)
    G = Xa * np.conj(Xb)
    Gii, Gjj = np.abs(Xa) ** 2, np.abs(Xb) ** 2
    mask = _band_mask(len(G), nfft, fs, band_hz)
    P = G * gcc_weighting(method, G, Gii, Gjj) * mask
    r = sfft.irfft(P, nfft)
    max_lag = (n - 1) if max_tau_s is None else min(max_tau_s * fs, n - 1)
    bound = np.array([float(max_lag)])  # (the bound is the physical maximum here)
    # the confidence looks outside the band's main lobe, as estimate_tdoas' (module docstring):
    # with 2 samples whatever the band, a 300-1000 Hz band's own lobe was the "second peak"
    # (an exact copy's confidence 1.4)
    main_lobe = 2 if band_hz is None else _main_lobe(np.flatnonzero(mask), nfft, fs, band_hz)
    lag, conf = _peaks(r[None, None, :], P[None, None, :], nfft, bound, refine,
                       main_lobe=main_lobe, reach=bound)
    lag, conf = lag[0], conf[0]
    shift = np.fft.fftshift(r)
    lags = (np.arange(nfft) - nfft // 2) / fs
    return GccResult(float(lag[0] / fs), float(conf[0]), lags, shift)


def _check_refine(refine: str) -> None:
    if refine not in _REFINE:
        raise ConfigError(f"unknown refine {refine!r} (choose one of: {', '.join(_REFINE)})")


# ---------------------------------------------------------------------------------- frames
@dataclass(frozen=True)
class TdoaFrames:
    """Framed TDOA estimates of all pairs.

    Attributes
    ----------
    t : array (n_frames,)
        Frame centre times in seconds from the start of the recording.
    tdoa_s : array (n_frames, n_pairs)
        ``t_i - t_j`` in seconds per frame and pair; NaN in invalid frames.
    confidence : array (n_frames, n_pairs)
        Peak-to-second-peak ratio of each GCC: 0 (silent frames) to :data:`MAX_CONFIDENCE`
        (1000), above 1 where the peak stands out (module docstring; not a probability).
    valid : array (n_frames,) bool
        True where the frame holds a source (energy above the noise floor, every pair's
        confidence >= ``min_confidence`` and, for arrays without redundant pairs (two
        microphones), each correlation peak ``min_frame_peak_snr`` above its floor).
    pairs : list of (i, j)
        The microphone pairs, columns of ``tdoa_s``.
    summary_tdoa_s : array (n_pairs,)
        Whole-recording estimate: the peak of the weighted cross spectra averaged over the valid
        frames -- or, when fewer than 3 frames are valid, over all frames with energy. With
        redundant pairs (3+ microphones) the peaks are chosen jointly: each pair's peak
        nearest the TDOAs of the direction that maximises the summed correlations. NaN when
        that average's confidence is below ``min_confidence`` in any pair (below 1.5 x
        ``min_confidence`` when the pairs' own peaks violate ``t_ij + t_jk = t_ik`` by more than
        2 samples RMS), or --
        for a single independent pair averaged over all frames -- when its confidence is below
        1.5 x ``min_confidence``.
    summary_confidence : array (n_pairs,)
        Peak-to-second-peak ratio of the averaged correlation (0 to :data:`MAX_CONFIDENCE`).
    max_tdoa_s : array (n_pairs,)
        The lag bound used per pair (physical maximum plus margin), seconds.
    fs : float
        Sample rate in Hz.
    summary_spectrum : array (n_pairs, n_bins) complex or None
        The averaged weighted cross spectra behind ``summary_tdoa_s`` at the rfft bins
        ``summary_bins`` of an ``nfft``-point transform (None when nothing was averaged);
        ``irfft`` of it is the whole-recording GCC.
    coherence_ratio : float
        How much of the inter-microphone coherence the noise floor explains (see
        ``reverb_method`` of :func:`estimate_tdoas`); ~1 in free field, < 1 in reverberation;
        NaN when it could not be measured (fewer than 3 noise-only frames).
    summary_method : str
        The GCC weighting behind ``summary_tdoa_s``.
    coherence_gain : float
        The reverberation test without a noise reference (see ``reverb_method`` of
        :func:`estimate_tdoas`): the coherence with 4x longer frames over that with the
        analysis frames; ~1 (at most 1.0 in our tests) in free field, 1.03-2.1 in RT60 0.3-0.6
        s rooms; NaN when not measured.
    band_hz : (float, float) or None
        The frequency band the GCC used, Hz (lowest and highest bin): ``band_hz`` of
        :func:`estimate_tdoas` or the whole band, less an empty top band
        (``empty_band_db``). None where not recorded.
    inverted_mics : tuple of int
        Microphones that seem wired with inverted polarity (their pairs' averaged correlations
        hold a trough where a source gives a peak; :func:`inverted_microphones`, with an
        :class:`~hearsee.errors.InvertedPolarityWarning`); empty when none, or without a
        whole-recording estimate.
    sync_offsets_s : array (n_pairs,) or None
        Per pair, the lag (s) beyond its bound at which its averaged correlation peaks when
        that says its channels are out of sync (:func:`desynchronized_pairs`, with a
        :class:`~hearsee.errors.ChannelSyncWarning`), NaN where they look in sync; None
        without a whole-recording estimate.
    tonal_lines_hz : tuple of float
        The lines of stationary tonal noise (mains hum, a motor's whine) found on every
        microphone and filtered out of the recording before the estimate (``tonal_noise`` of
        :func:`estimate_tdoas`), Hz; empty when none.
    dead_mics : tuple of int
        Microphones whose channels correlate with no other while the others hear a source
        (:func:`dead_microphones`, with a :class:`~hearsee.errors.DeadMicrophoneWarning`);
        empty when none, or without a whole-recording estimate.
    undetected_summary : (array (n_pairs,), array (n_pairs,)) or None
        The whole-recording estimate (``summary_tdoa_s``, ``summary_confidence``) that only
        the detection test refused (``min_peak_snr`` of :func:`estimate_tdoas`: a single
        independent pair whose averaged correlation peak does not stand out of its floor), so
        that a caller who wants a best guess rather than an abstention needs no second run
        (:meth:`without_detection_test`); None when that test refused nothing.
    """

    t: NDArray
    tdoa_s: NDArray
    confidence: NDArray
    valid: NDArray
    pairs: list[tuple[int, int]]
    summary_tdoa_s: NDArray
    summary_confidence: NDArray
    max_tdoa_s: NDArray
    fs: float
    summary_spectrum: NDArray | None = None
    summary_bins: NDArray | None = None
    nfft: int = 0
    coherence_ratio: float = float("nan")
    summary_method: str = ""
    coherence_gain: float = float("nan")
    band_hz: tuple[float, float] | None = None
    inverted_mics: tuple[int, ...] = ()
    sync_offsets_s: NDArray | None = None
    tonal_lines_hz: tuple[float, ...] = ()
    dead_mics: tuple[int, ...] = ()
    undetected_summary: tuple[NDArray, NDArray] | None = None

    @property
    def pair_labels(self) -> list[str]:
        return [f"{i}-{j}" for i, j in self.pairs]

    @property
    def n_valid(self) -> int:
        return int(np.count_nonzero(self.valid))

    @property
    def wiring_fault(self) -> bool:
        """Whether the whole-recording correlations told of a microphone wired with inverted
        polarity (``inverted_mics``), of channels out of sync (``sync_offsets_s``) or of a
        dead microphone (``dead_mics``), each with its warning: what a caller that checks the
        wiring ahead needs to know."""
        return bool(self.inverted_mics) or bool(self.dead_mics) or (
            self.sync_offsets_s is not None and bool(np.isfinite(self.sync_offsets_s).any()))

    def without_detection_test(self) -> TdoaFrames:
        """These estimates as :func:`estimate_tdoas` gives them with ``min_peak_snr=0``: the
        summary that only the detection test refused (``undetected_summary``) put in place.
        That test looks at the averaged correlation once it is computed and changes nothing
        else, so this is the relaxed run's result at no second estimate; ``self`` when the
        test refused nothing (``min_peak_snr=0`` then changes nothing)."""
        if self.undetected_summary is None:
            return self
        tdoa_s, confidence = self.undetected_summary
        return replace(self, summary_tdoa_s=tdoa_s, summary_confidence=confidence,
                       undetected_summary=None)

    def wiring_entries(self) -> dict[str, Any]:
        """The ``hearsee localize`` summary's ``inverted_microphones`` (list),
        ``dead_microphones`` (list), ``sync_offsets_s`` ({"i-j": s} of the pairs out of sync;
        {} when none) and ``tonal_lines_hz`` (the lines of hum filtered out, Hz; [] when none)
        -- one place for every array's document."""
        off = self.sync_offsets_s
        return {"inverted_microphones": [int(m) for m in self.inverted_mics],
                "dead_microphones": [int(m) for m in self.dead_mics],
                "sync_offsets_s": {} if off is None else {
                    k: float(v) for k, v in zip(self.pair_labels, off, strict=True)
                    if np.isfinite(v)},
                "tonal_lines_hz": [float(f) for f in self.tonal_lines_hz]}


@functools.lru_cache(maxsize=16)
def _window(window: str | tuple, frame_len: int) -> NDArray:
    """The analysis window (float32, read-only: shared between calls)."""
    from scipy.signal import get_window

    try:
        w = get_window(window, frame_len).astype(np.float32)
    except (ValueError, TypeError) as e:
        raise ConfigError(f"unknown analysis window {window!r} (a scipy.signal.get_window "
                          f"name or tuple, e.g. 'hann' or ('tukey', 0.25)): {e}") from None
    w.flags.writeable = False
    return w


#: The level range :func:`estimate_tdoas` leaves unscaled: a recording whose largest |sample|
#: (unitless sample values) is within ``[MIN_UNSCALED_PEAK, MAX_UNSCALED_PEAK]`` (or 0) is
#: used as it is, any other is scaled to a peak of 1 first (float files have no full scale);
#: the streaming SRP stage (:func:`hearsee.stream.pipeline.level_scale`) keeps the same range.
#: Above: SCOT's G_ii G_jj, ML's |G|^2 and the frames' norms are *fourth* powers of a frame's
#: spectrum (|X| up to ~peak x frame length): in single precision they overflowed from peaks of
#: ~1e7 (64 ms frames; raw 32-bit PCM is 2e9) and, with 10 s frames at 48 kHz, between 1e4 and
#: 1e5. Raw 16-bit PCM (3e4) is scaled too; the results are scale-free
MAX_UNSCALED_PEAK = 1e3
#: ... and below (a float file at 1e-15 gave no estimate: its single-precision powers fell under
#: the spectra's floor). 24-bit PCM's smallest step is 1.2e-7
MIN_UNSCALED_PEAK = 1e-6


def _peak_level(a: NDArray) -> float:
    """The largest |sample| of ``a`` (0 without samples): NaN when a sample is NaN, inf when
    one is infinite -- the recording's finiteness test in the same passes. From its largest
    and smallest sample: no |a| temporary the size of the recording."""
    if a.size == 0:
        return 0.0
    return float(np.maximum(a.max(), -a.min()))  # (np.maximum: NaN propagates)


#: No integer PCM recording spans more than this ratio of its loudest |sample| to its median
#: |sample| when that is not zero: 32-bit PCM's full scale is 2**31 steps, and a median of
#: integers that is not zero is at least half a step (:func:`dominant_sample`).
MAX_PCM_RANGE = 2.0**32


def dominant_sample(x: NDArray) -> tuple[int, int, float, float] | None:
    """``(channel, index, value, ratio)`` of the loudest sample of the recording ``x``
    (n_ch, n) when it is more than :data:`MAX_PCM_RANGE` times the recording's median |sample|
    (``ratio``; a median of 0, a mostly silent recording, is never such), else None.

    A diagnosis, not a check: float recordings have no full scale and every estimate here is
    scale-free (a recording at 1e25 is analysed like one at 1), so no level is refused. But
    :func:`estimate_tdoas` scales a recording to its loudest sample, and one corrupt float
    sample of 1e30 among speech at ~0.1 puts every other frame below single precision's range:
    no frame is valid. The CLI names the sample then, instead of "silence or uncorrelated
    noise"."""
    a = np.abs(as_samples(x, finite=False))
    if a.ndim > 2:
        raise AudioInputError(f"a recording is (n_channels, n_samples), got shape {a.shape}")
    if a.size == 0:
        return None
    k = int(np.argmax(a))
    ch, i = np.unravel_index(k, a.shape) if a.ndim > 1 else (0, k)
    peak, median = float(a.flat[k]), float(np.median(a))
    if not (median > 0 and peak > MAX_PCM_RANGE * median):
        return None
    return int(ch), int(i), float(np.asarray(x).flat[k]), peak / median


def windowed_frames(frames: NDArray, win: NDArray, nfft: int | None = None) -> NDArray:
    """Each frame (..., L) less its own mean, times the analysis window: the spectra's input.
    A DC offset (common on real ADCs, often different per channel) is the same in every
    channel's spectrum and, leaking through the window into the lowest bins, puts a
    correlation peak at lag 0 -- a pure offset read as a source straight above the array.
    Removing each frame's mean drops it (a digitally silent frame stays all zeros).
    ``nfft`` (>= L): the frames zero-padded to (..., nfft), written in place (the transform
    then pads no copy of its own). Frames and window are real samples, the window as long as a
    frame (AudioInputError / ConfigError otherwise)."""
    frames, win = _float_samples(frames, "frames"), _float_samples(win, "window")
    if frames.ndim < 1 or win.shape != frames.shape[-1:]:
        raise ConfigError(f"a window of shape {win.shape} for frames of shape {frames.shape}: "
                          "the window must be as long as a frame")
    mean = frames.mean(axis=-1, keepdims=True, dtype=np.float32)
    if nfft is None:
        return (frames - mean) * win
    L = frames.shape[-1]
    if not (isinstance(nfft, (int, np.integer)) and nfft >= L):
        raise ConfigError(f"nfft must be a whole number of samples >= the frame length {L}, "
                          f"got {nfft!r}")
    dtype = np.result_type(np.result_type(frames.dtype, mean.dtype), win.dtype)
    out = np.empty(frames.shape[:-1] + (int(nfft),), dtype)
    out[..., L:] = 0  # (only the padding: the body is written below)
    body = out[..., :L]
    np.subtract(frames, mean, out=body)
    body *= win
    return out


def frame_spectra(frames: NDArray, win: NDArray, nfft: int, k0: int = 0,
                  k1: int | None = None) -> NDArray:
    """The spectra (..., k1 - k0) at rfft bins ``k0..k1-1`` of ``frames`` (..., L) less their
    means, windowed by ``win`` and zero-padded to ``nfft`` samples (:func:`windowed_frames`)."""
    return sfft.rfft(windowed_frames(frames, win, nfft), axis=-1)[..., k0:k1]


def _spectra_power(frames: NDArray, win: NDArray, nfft: int, k0: int, k1: int
                   ) -> tuple[NDArray, NDArray]:
    """:func:`frame_spectra` of ``frames`` and their power ``|X|^2``: the pair that the
    activity test, the noise spectrum, the spectral statistics and the SNR weights share."""
    return _chunk_spectra(frames, win, nfft, k0, k1, None)[:2]


def _chunk_spectra(frames: NDArray, win: NDArray, nfft: int, k0: int, k1: int,
                   rows: NDArray | None) -> tuple[NDArray, NDArray, NDArray | None]:
    """:func:`_spectra_power` of ``frames`` (n_ch, F, L), and the power over every rfft bin of
    the frames ``rows`` (indices into F; None or empty: None) from the same transform: the
    spectra :func:`_empty_band_cut` looks at, at no transform of their own."""
    full = sfft.rfft(windowed_frames(frames, win, nfft), axis=-1)
    X = full[..., k0:k1]
    top = None
    if rows is not None and rows.size:
        t = full[:, rows, :]
        top = t.real**2 + t.imag**2
    return X, X.real**2 + X.imag**2, top


def _rows_in(rows: NDArray | None, s0: int, n: int) -> NDArray | None:
    """The indices of ``rows`` within frames ``s0..s0+n-1``, counted from ``s0``."""
    return None if rows is None else rows[(rows >= s0) & (rows < s0 + n)] - s0


def frame_activity(x: NDArray, frame_len: int, hop: int, n_frames: int,
                   vad_db: float) -> tuple[NDArray, NDArray]:
    """Energy voice-activity decision per frame.

    ``x`` (n_ch, n) signals framed by ``frame_len``/``hop``. Returns (mean-square energy per
    frame, active bool). The noise floor is the 10th percentile of frame energies; frames within
    ``vad_db`` dB of it are inactive when the recording's dynamic range (95th / 10th percentile)
    exceeds ``vad_db`` + 3 dB (otherwise the recording is stationary and the energy cannot tell
    source from noise; the confidence test decides). Digitally silent frames are always
    inactive.
    """
    energy = _frame_energy(x, frame_len, hop, n_frames)
    return energy, _energy_vad(energy, vad_db)[0]


def _frame_energy(x: NDArray, frame_len: int, hop: int, n_frames: int) -> NDArray:
    """Mean-square energy of each frame of ``x`` (n_ch, n), over all channels, each channel
    taken about its mean over ``x``: a DC offset (real ADCs have one, often different per
    channel) otherwise raised every frame's energy by the same amount, so the noise floor
    rose toward the voice and the energy VAD dropped its quieter frames. A frame of digital
    silence (every sample of every channel exactly 0: a recorder's lead-in, zero padding) has
    energy 0: about the mean it had the mean's square, ~80 dB below a voice and so no silence
    to :func:`_sounding`, and a lead-in became the noise floor -- every pause of the voice
    after it was active and the SNR weighting lost its noise reference."""
    raw = x
    mean = x.sum(axis=1, keepdims=True) / x.shape[1]  # (float32 stays float32)
    x = x - mean
    e = np.einsum("ij,ij->j", x, x)  # per sample, summed over the channels
    if frame_len % hop == 0:  # frames made of whole hops: sum the hops, then the frames
        m = frame_len // hop
        blocks = e[: (n_frames + m - 1) * hop].reshape(-1, hop).sum(axis=1, dtype=float)
        s = blocks if m == 1 else np.convolve(blocks, np.ones(m), mode="valid")
    else:  # (a float64 running sum of ~n samples: ~4 ns each, slower)
        cs = np.zeros(x.shape[1] + 1)
        np.cumsum(e, dtype=float, out=cs[1:])
        start = np.arange(n_frames) * hop
        s = cs[start + frame_len] - cs[start]
    # digital silence: no energy (see above). A sample 0 on every channel has the energy of
    # the mean alone, so only a recording with one that low is looked through sample by sample
    # (a pass over every channel: ~1 % of a short recording's whole estimate)
    if (e.size and float(e.min()) <= 1.001 * float(np.sum(mean.astype(float) ** 2)) + 1e-30
            and not (heard := np.any(raw, axis=0)).all()):
        ch = np.zeros(heard.size + 1, dtype=np.int64)
        np.cumsum(heard, out=ch[1:])
        start = np.arange(n_frames) * hop
        s = np.where(ch[start + frame_len] == ch[start], 0.0, s)
    return np.maximum(s / (frame_len * x.shape[0]), 0.0)


def _energy_vad(energy: NDArray, vad_db: float) -> tuple[NDArray, bool]:
    """The decision of :func:`frame_activity` from frame energies: (active, whether the energy
    decided -- False when the recording looked stationary and only digital silence was
    dropped)."""
    active = _sounding(energy)
    if active.any():
        floor, top = _percentiles(energy[active], (10.0, 95.0))
        if floor > 0 and top > floor * 10 ** ((vad_db + 3.0) / 10.0):
            return active & (energy > floor * 10 ** (vad_db / 10.0)), True
    return active, False


def _sounding(energy: NDArray) -> NDArray:
    """The frames that are not digital silence: energy above 1e-10 of the loudest's."""
    return energy > max(1e-20, 1e-10 * float(energy.max(initial=0.0)))


def _percentiles(v: NDArray, qs: tuple[float, ...]) -> list[float]:
    """``np.percentile(v, qs)`` of a 1-D array (linear interpolation, numpy's lerp; the same
    bits for every length from 1 to 3000 tried) by one sort: a tenth of np.percentile's
    per-call overhead on the few dozen frame energies of a short recording."""
    v = np.sort(v)
    n = len(v)
    out = []
    for q in qs:
        pos = q / 100.0 * (n - 1)
        i = int(pos)
        t = pos - i
        a, b = float(v[i]), float(v[min(i + 1, n - 1)])
        d = b - a
        out.append(b - d * (1.0 - t) if t >= 0.5 else a + d * t)
    return out


def _band_activity(frames: NDArray, win: NDArray, nfft: int, k0: int, k1: int,
                   active: NDArray, vad_db: float, chunk: int, rows: NDArray | None = None
                   ) -> tuple[NDArray, NDArray | None, NDArray | None, NDArray | None]:
    """:func:`frame_activity`'s decision from each frame's energy in the analysis band (bins
    ``k0..k1-1``) instead of the whole spectrum; ``active`` (the broadband decision) where the
    band energy does not decide either. Used when the broadband energy looked stationary: white
    sensor noise outside a voice's band (e.g. 3.5-8 kHz at 16 kHz) can hide the syllables that
    the band's energy still shows, and without inactive frames there is no noise spectrum for
    the SNR weighting. Returns (active, the band spectra (n_ch, F, bins) and their power
    ``|X|^2`` when they fit :data:`SPECTRA_CACHE_BYTES` -- the noise spectrum and the frame
    loop then need no second transform -- else None, None), and the whole-band power of the
    frames ``rows`` (sorted indices; :func:`_chunk_spectra`) or None. Transformed ``chunk``
    frames at a time (:func:`_band_spectra`)."""
    keep = _spectra_fit(frames.shape[0], frames.shape[1], k1 - k0)
    X, power, e, top = _band_spectra(frames, win, nfft, k0, k1, chunk, rows, keep=keep,
                                     energy=True)
    band, decided = _energy_vad(e, vad_db)
    return (active & band if decided else active), X, power, top


def _band_spectra(frames: NDArray, win: NDArray, nfft: int, k0: int, k1: int, chunk: int,
                  rows: NDArray | None = None, keep: bool = True, energy: bool = False
                  ) -> tuple[NDArray | None, NDArray | None, NDArray | None, NDArray | None]:
    """:func:`_spectra_power` of every frame of ``frames`` (n_ch, F, L), transformed ``chunk``
    frames at a time (the full spectra of a long recording would not fit where its band
    does): (the band spectra and their power, both None without ``keep``; with ``energy``
    each frame's band energy (F,), else None; the whole-band power of the frames ``rows``
    (:func:`_chunk_spectra`) or None)."""
    parts, tops = [], []
    e = np.empty(frames.shape[1]) if energy else None
    for s0 in range(0, frames.shape[1], chunk):
        X, power, top = _chunk_spectra(frames[:, s0:s0 + chunk, :], win, nfft, k0, k1,
                                       _rows_in(rows, s0, chunk))
        if e is not None:
            e[s0:s0 + chunk] = np.sum(power, axis=(0, 2))
        if keep:
            parts.append((X, power))
        if top is not None:
            tops.append(top)
    return *(_joined(parts) if keep else (None, None)), e, _joined_rows(tops, rows)


def _joined_rows(tops: list[NDArray], rows: NDArray | None) -> NDArray | None:
    """The whole-band power of every frame of ``rows`` from its chunks, or None."""
    if rows is None or not rows.size:
        return None
    return tops[0] if len(tops) == 1 else np.concatenate(tops, axis=1)


def _joined(parts: list[tuple[NDArray, NDArray]]) -> tuple[NDArray, NDArray]:
    """Chunks of (spectra, power), each (n_ch, F_chunk, bins), joined along the frames."""
    if len(parts) == 1:
        return parts[0]
    return (np.concatenate([p[0] for p in parts], axis=1),
            np.concatenate([p[1] for p in parts], axis=1))


def _tonal_lines(power_all: NDArray | None, frames: NDArray, win: NDArray, nfft: int, k0: int,
                 k1: int, sounding: NDArray, bin_hz: NDArray) -> NDArray | None:
    """The bins k0..k1-1 (bool; at frequencies ``bin_hz``, Hz) that hold stationary tonal noise
    (:func:`hum.tonal_bins`) over the frames that are ``sounding``, or None without any. From
    the band power ``power_all``
    (n_ch, F, bins) when kept, else from as many frames evenly spread over the recording as fit
    :data:`SPECTRA_CACHE_BYTES`."""
    n_sounding = int(np.count_nonzero(sounding))
    if n_sounding < hum.TONAL_MIN_FRAMES:
        return None
    idx = None if n_sounding == len(sounding) else np.flatnonzero(sounding)
    if power_all is not None:
        p = power_all if idx is None else power_all[:, idx]
    else:
        idx = np.arange(len(sounding)) if idx is None else idx
        fit = max(SPECTRA_CACHE_BYTES // (frames.shape[0] * (k1 - k0) * 12),
                  hum.TONAL_MIN_FRAMES)
        idx = idx[np.linspace(0, idx.size - 1, min(fit, idx.size)).astype(int)]
        p = _spectra_power(frames[:, idx, :], win, nfft, k0, k1)[1]
    line = hum.tonal_bins(p, bin_hz)
    return line if line.any() else None


def _band_tonal_lines(a32: NDArray, fs: float, frame_len: int, window: str | tuple,
                      nfft: int, k0: int, k1: int, power_all: NDArray | None, frames: NDArray,
                      win: NDArray, energy: NDArray) -> tuple[NDArray | None, NDArray]:
    """(:func:`_tonal_lines` of the band of bins k0..k1-1 of the analysis' ``nfft``-point
    spectra, their frequencies in Hz). On frames :data:`hum.TONAL_FRAME_MS` long (half-frame
    hop, the analysis' window) where the analysis' ``frame_len`` is shorter and the recording
    ``a32`` (n_ch, n) holds :data:`hum.TONAL_MIN_FRAMES` of them that are not silent, the
    bins of the same band at that resolution; else the analysis' own frames, power
    ``power_all`` and frame ``energy``."""
    n = int(round(hum.TONAL_FRAME_MS * 1e-3 * fs))
    if frame_len < n <= a32.shape[1]:
        hop = n // 2
        count = (a32.shape[1] - n) // hop + 1
        sounding = _sounding(_frame_energy(a32, n, hop, count))
        if np.count_nonzero(sounding) >= hum.TONAL_MIN_FRAMES:
            lo = int(np.ceil(k0 * n / nfft))  # (the band's edges, Hz, in n-point bins)
            hi = int(np.floor((k1 - 1) * n / nfft)) + 1
            bin_hz = np.arange(lo, hi) * fs / n
            return (_tonal_lines(None, frame_signals(a32, n, hop), _window(window, n), n, lo,
                                 hi, sounding, bin_hz), bin_hz)
    bin_hz = np.arange(k0, k1) * fs / nfft
    return _tonal_lines(power_all, frames, win, nfft, k0, k1, _sounding(energy), bin_hz), bin_hz


#: :func:`_empty_band_cut` looks at the spectra of this many of a recording's loudest frames (the
#: same whatever the recording's length or the band asked for: ~1 s of the loudest audio with 64
#: ms frames; a few tenths of a millisecond per call)
_EMPTY_BAND_FRAMES = 16


def _loudest_frames(energy: NDArray) -> NDArray:
    """The sorted indices of the :data:`_EMPTY_BAND_FRAMES` loudest frames (by ``energy``;
    all of them when fewer)."""
    n = min(_EMPTY_BAND_FRAMES, energy.size)
    return np.sort(np.argsort(energy, kind="stable")[-n:]) if n else np.zeros(0, dtype=int)


def _empty_band_cut(frames: NDArray, win: NDArray, nfft: int, fs: float, energy: NDArray,
                    db: float, power: NDArray | None = None) -> int | None:
    """The rfft bin where the GCC's band must end (exclusive), or None: from the edge found by
    :func:`empty_top_band` in the mean power over the channels and the
    :data:`_EMPTY_BAND_FRAMES` loudest ``frames`` (by ``energy``) of the whole band, the old
    Nyquist frequency of an upsampled recording (:data:`EMPTY_BAND_TRANSITION`). ``power``:
    those frames' whole-band power (n_ch, n, nfft // 2 + 1) when already transformed."""
    if power is None:
        loudest = _loudest_frames(energy)
        if loudest.size == 0:
            return None
        power = _spectra_power(frames[:, loudest, :], win, nfft, 0, nfft // 2 + 1)[1]
    mean = power.mean(axis=(0, 1), dtype=float)
    if not np.all(np.isfinite(mean)) or not mean.max() > 0:  # (empty_top_band's None cases)
        return None
    sm = _smoothed_power(mean)
    edge = _top_edge(sm, db)
    if edge is None or edge > EMPTY_BAND_NATIVE * (nfft // 2):
        return edge
    edge_hz = edge * fs / nfft
    for f_n in sorted((r / 2.0 for r in STANDARD_RATES_HZ
                       if edge_hz / EMPTY_BAND_TRANSITION <= r / 2.0 <= edge_hz), reverse=True):
        k_n = int(np.ceil(f_n * nfft / fs - 1e-9))
        if sm[min(k_n, sm.size - 1)] >= sm[int(0.9 * k_n)] * 10.0 ** (-EMPTY_BAND_STEP_DB / 10):
            return k_n
    return int(np.floor(EMPTY_BAND_GUARD * edge))


def _warn_inverted(r: NDArray, max_lag: NDArray, main_lobe: int,
                   pairs: Sequence[tuple[int, int]], n_mics: int) -> tuple[int, ...]:
    """An :class:`~hearsee.errors.InvertedPolarityWarning` when the averaged correlations ``r``
    (n_pairs, nfft) tell of an inverted microphone (:func:`inverted_microphones`); those
    microphones (none: ``()``)."""
    hi, lo = _extrema_within(r, _lag_bounds(max_lag))
    if all(h >= d for h, d in zip(hi, lo, strict=True)):
        return ()  # (no trough deeper than its peak: no pair can have sign -1; the usual case)
    sign, z = pair_polarity(r, max_lag, main_lobe)
    mics = inverted_microphones(sign, pairs, n_mics, z)
    if mics is None:
        return ()
    neg = [f"{i}-{j}" for (i, j), v in zip(pairs, sign, strict=True) if v < 0]
    names = ", ".join(map(str, mics))
    if 2 * len(mics) == n_mics:  # (the other half explains the signs as well)
        rest = ", ".join(str(m) for m in range(n_mics) if m not in mics)
        names += f" (or {rest})"
    who = f"microphone{'s' * (len(mics) > 1)} {names} seem{'s' * (len(mics) == 1)}"
    warnings.warn(f"{who} wired with inverted polarity: pair{'s' * (len(neg) > 1)} "
                  f"{', '.join(neg)} correlate{'s' * (len(neg) == 1)} negatively (a trough where "
                  "a source gives a peak), so their TDOAs and the direction are wrong; invert "
                  "that channel's samples or fix the wiring", InvertedPolarityWarning,
                  stacklevel=3)
    return tuple(mics)


#: :func:`dead_microphones`: a microphone whose pairs' averaged correlations all peak below this
#: many robust noise deviations (:func:`_peak_snr`) while another pair's peaks at least
#: :data:`DEAD_OTHERS_PEAK_SNR` above its floor hears nothing of the others' source. Chosen on
#: dev recordings (seed 2: three-mic, respeaker-4/6; voices and noise; free field, RT60 0.3/0.6
#: s; 0/10/20 dB; 162 each): the best pair of every microphone of a clean recording peaked at
#: least 6.4 (where another reached 8), a channel replaced by noise at most 3.4.
DEAD_PEAK_SNR = 3.5
#: :func:`dead_microphones`: the clear source another pair must hear (see :data:`DEAD_PEAK_SNR`)
DEAD_OTHERS_PEAK_SNR = 8.0
#: :func:`dead_microphones` looks further only at a microphone whose pairs all have a
#: confidence (peak over second peak) below this: a channel of noise had at most 1.23 on the
#: dev recordings, so clean recordings rarely pay for the noise floors
DEAD_MAX_CONFIDENCE = 1.3


@functools.lru_cache(maxsize=16)
def _window_noise_profile(window: str | tuple, frame_len: int, nfft: int) -> NDArray:
    """:func:`_lag_noise_profile` of the analysis window ``window`` of ``frame_len`` samples
    (read-only: shared between calls; every estimate of a recording of one pair computed it
    afresh, and the dead-microphone test reads it too)."""
    p = _lag_noise_profile(_window(window, frame_len), nfft)
    p.flags.writeable = False
    return p


def dead_microphones(r: NDArray, lag: NDArray, confidence: NDArray, max_lag: NDArray,
                     main_lobe: int, pairs: Sequence[tuple[int, int]], n_mics: int,
                     profile: Callable[[], NDArray]) -> tuple[int, ...]:
    """The microphones whose channels correlate with no other while the others hear a
    source: every pair of such a microphone peaks below :data:`DEAD_PEAK_SNR` noise
    deviations of its averaged correlation ``r`` (n_pairs, nfft; peaks at ``lag``, samples,
    with ``confidence`` (n_pairs,)), and some pair without it at least
    :data:`DEAD_OTHERS_PEAK_SNR` (:func:`_peak_snr` with the window's lag ``profile()``).
    Needs three microphones (a pair without the one in question); a microphone none of whose
    pairs is among ``pairs`` is not judged. Reconstruction beyond the thesis."""
    conf = np.asarray(confidence, dtype=float)
    members = [[p for p, pr in enumerate(pairs) if k in pr] for k in range(n_mics)]
    suspects = [k for k, w in enumerate(members)
                if w and len(w) < len(pairs) and np.max(conf[w]) < DEAD_MAX_CONFIDENCE]
    if not suspects:
        return ()
    try:
        snr = _peak_snr(r, np.asarray(lag), max_lag, main_lobe, profile())
    except ConfigError:  # (a band too narrow to measure a floor: nothing to say)
        return ()
    return tuple(k for k in suspects
                 if np.max(snr[members[k]]) < DEAD_PEAK_SNR
                 and np.max(np.delete(snr, members[k])) >= DEAD_OTHERS_PEAK_SNR)


def _warn_dead(*args) -> tuple[int, ...]:
    """A :class:`~hearsee.errors.DeadMicrophoneWarning` naming the microphones
    :func:`dead_microphones` finds (its arguments); those microphones."""
    dead = dead_microphones(*args)
    if dead:
        warnings.warn(dead_microphones_text(dead), DeadMicrophoneWarning, stacklevel=3)
    return dead


def dead_microphones_text(dead: Sequence[int],
                          outcome: str = "the direction is missing or wrong") -> str:
    """The :class:`~hearsee.errors.DeadMicrophoneWarning` line for the microphones ``dead``;
    ``outcome`` says what became of the direction."""
    names = ", ".join(map(str, dead))
    one = len(dead) == 1
    return (f"microphone{'' if one else 's'} {names} hear{'s' if one else ''} nothing of what "
            "the others hear (its channel correlates with no other: unplugged, broken or "
            f"covered?), so its pairs have no TDOA and {outcome}")


def _warn_desync(r: NDArray, max_lag: NDArray, main_lobe: int,
                 pairs: Sequence[tuple[int, int]], fs: float) -> NDArray:
    """A :class:`~hearsee.errors.ChannelSyncWarning` naming the pairs whose averaged
    correlations ``r`` (n_pairs, nfft) peak far beyond their lag bound
    (:func:`desynchronized_pairs`), and the one microphone they share, if any; those lags in
    seconds (NaN for the pairs in sync)."""
    lags = desynchronized_pairs(r, max_lag, main_lobe)
    bad = np.flatnonzero(np.isfinite(lags))
    if not bad.size:
        return lags / fs
    what = ", ".join(f"{pairs[p][0]}-{pairs[p][1]} at {lags[p] / fs * 1e3:+.2f} ms"
                     for p in bad)
    bound = float(np.max(np.asarray(max_lag)[bad])) / fs * 1e3
    common = set(pairs[bad[0]]).intersection(*(pairs[p] for p in bad[1:]))
    who = (f"microphone {common.pop()} seems out of sync with the others: "
           if len(bad) > 1 and len(common) == 1 else "")
    warnings.warn(f"{who}pair{'s' * (bad.size > 1)} {what} correlate{'s' * (bad.size == 1)} "
                  f"best beyond the +-{bound:.2f} ms the microphones' spacing allows: are the "
                  "channels out of sync (two sound cards, a dropped buffer), or the microphones "
                  "farther apart than the array says? Their TDOAs, and the direction, are "
                  "wrong", ChannelSyncWarning, stacklevel=3)
    return lags / fs


def empty_band_top_hz(x: ArrayLike, fs: float, frame_ms: float = 64.0,
                      db: float = EMPTY_BAND_DB) -> float | None:
    """The highest frequency (Hz) :func:`estimate_tdoas` keeps of a recording whose top band
    is empty (``empty_band_db``: upsampled from a lower rate), or None when nothing is empty.

    For callers that set a band of their own before the audio is processed in pieces -- a
    stream, whose batches must share one band: ``hearsee track`` asks it of a file. ``x``
    (n_ch, n) at ``fs`` Hz, looked at in ``frame_ms`` frames (half overlapping); the band
    :func:`estimate_tdoas` keeps may differ by a bin (its transform length depends on the
    array).

    >>> import numpy as np
    >>> from scipy.signal import resample_poly
    >>> x8 = np.random.default_rng(0).standard_normal((2, 8000))  # 1 s of noise at 8 kHz
    >>> empty_band_top_hz(x8, 8000) is None
    True
    >>> empty_band_top_hz(resample_poly(x8, 2, 1, axis=1), 16000)  # read at 16 kHz
    3984.375
    """
    fs = check_analysis_fs(fs)
    db = finite_number("db", db, 0.0, lo_open=True)
    a = as_samples(x)
    if a.ndim != 2:
        raise AudioInputError(f"recording must be (n_channels, n_samples), got {a.shape}")
    frame_len, hop = frame_geometry(fs, frame_ms, frame_ms / 2.0)
    peak = float(np.max(np.abs(a), initial=0.0))
    if not peak > 0 or a.shape[1] < frame_len:
        return None
    a32 = (a / peak).astype(np.float32)
    n_frames = (a32.shape[1] - frame_len) // hop + 1
    frames = frame_signals(a32, frame_len, hop)
    energy = _frame_energy(a32, frame_len, hop, n_frames)
    cut = _empty_band_cut(frames, _window(DEFAULT_WINDOW, frame_len), frame_len, fs,
                          energy, db)
    return None if cut is None else (cut - 1) * fs / frame_len


#: :func:`inverted_microphones`: a pair's averaged correlation counts as a peak (or a trough)
#: where its highest value (or deepest, when deeper than the highest) within its lag bound
#: stands this many robust standard deviations above the correlation at the lags beyond it;
#: two microphones, with no other pair to agree, need :data:`POLARITY_PAIR_SIGNIF`
POLARITY_SIGNIF = 5.0
POLARITY_PAIR_SIGNIF = 8.0
#: arrays up to this many microphones are searched for the inverted ones (2^(n-1) sign patterns)
_POLARITY_MAX_MICS = 12


def pair_polarity(r: ArrayLike, max_lag: ArrayLike, main_lobe: int = 2,
                  signif: float = POLARITY_SIGNIF) -> tuple[NDArray, NDArray]:
    """The sign of each pair's averaged correlation and its significance.

    ``r`` (n_pairs, nfft): circular correlations (lag 0 first, negative lags at the end);
    ``max_lag`` (n_pairs,) samples. Per pair, the extremum within ``+-max_lag`` of largest
    magnitude, over a robust standard deviation (1.4826 median absolute deviation) of ``r`` at
    the lags beyond ``max_lag + main_lobe``. Returns ``(sign, z)``: ``sign`` +1 for a peak, -1
    for a trough, 0 where ``z < signif``; ``z`` that ratio. A source's direct path is a peak in
    every weighting hearsee uses (they are real and positive per bin); a trough is the mark of
    a microphone whose signal is inverted.
    """
    r = np.atleast_2d(np.asarray(r, dtype=float))
    L = _lag_bounds(max_lag)
    his, los = _extrema_within(r, L)
    sign, z = np.zeros(len(r), dtype=int), np.zeros(len(r))
    for p in range(len(r)):
        far = _far_lags(r[p], L[p], main_lobe)
        if far.size < 8:
            continue
        sd = _robust_sd(far)
        hi, lo = his[p], los[p]
        z[p] = max(hi, lo) / sd if sd > 0 else 0.0
        if z[p] >= signif:
            sign[p] = 1 if hi >= lo else -1
    return sign, z


def _far_lags(r: NDArray, L: int, main_lobe: int) -> NDArray:
    """One pair's circular correlation ``r`` (nfft,) at the lags beyond ``+-(L + main_lobe)``
    (from ``L + main_lobe + 1`` up, then the negative ones)."""
    return r[L + main_lobe + 1: r.size - L - main_lobe]


def _robust_sd(v: NDArray) -> float:
    """1.4826 median absolute deviation of ``v`` (0 when empty)."""
    return 1.4826 * float(np.median(np.abs(v - np.median(v)))) if v.size else 0.0


#: :func:`desynchronized_pairs`: a pair counts as out of sync when its averaged correlation's
#: highest value beyond its lag bound stands :data:`DESYNC_SIGNIF` robust standard deviations
#: above the spread there and :data:`DESYNC_RATIO` times above its highest value within the
#: bound. Chosen 2026-12-04 under a rule written before its held-out run (seed 1: two-mic,
#: three-mic, respeaker-6 in free field and RT60 0.3 / 0.6 s rooms at 0-20 dB, white noise and
#: both synthetic voices, 162 recordings): none in sync named (their ratio at most 0.97, the
#: pitch period's peaks of a voice in a room), a channel 2.5 ms late named in 94-100 %, 10 ms
#: late in 56-81 % (the frames that pass the confidence test are those whose in-bound peak
#: stands out by chance); the real 'alexa' pair and 45 pairs of the measured 32-mic responses
#: in sync at most 0.28, 'alexa' 0.8-10 ms late 3.6-7.1. The final form (the in-bound
#: extremum of either sign: a trough's pairs are no longer measured against a low maximum)
#: on seed 2: none of 162 named, 2.5 ms late 89-100 %, 10 ms late 57-83 %. A source's
#: direct path peaks within the bound whatever the room (a reflection's TDOA obeys it too;
#: only the cross terms of two paths fall beyond it, and they are weaker), and a periodic
#: source's repeats at its period are no higher than its peak, so a peak beyond twice as high
#: is a time offset between the channels: two sound cards, a dropped buffer, a driver's
#: latency.
DESYNC_RATIO = 2.0
DESYNC_SIGNIF = 8.0


def desynchronized_pairs(r: ArrayLike, max_lag: ArrayLike, main_lobe: int = 2,
                         signif: float = DESYNC_SIGNIF, ratio: float = DESYNC_RATIO) -> NDArray:
    """Per pair, the lag (samples, signed as ``r``'s circular lags) at which its averaged
    correlation peaks beyond its physical bound when that peak says the pair's channels are
    out of sync (:data:`DESYNC_RATIO` times the largest magnitude within the bound, peak or
    trough, and :data:`DESYNC_SIGNIF`), else NaN.

    ``r`` (n_pairs, nfft): circular correlations (lag 0 first, negative lags at the end), as
    :func:`pair_polarity` takes them; ``max_lag`` (n_pairs,) samples. A lag offset larger than
    about half a frame is not seen (the frames no longer overlap). An array description that
    understates a pair's spacing looks the same (a 0.4 m pair read as the 0.15 m ``two-mic``,
    a source 30 deg or more off broadside: the true TDOA lies beyond the bound).
    """
    r = np.atleast_2d(np.asarray(r, dtype=float))
    L = _lag_bounds(max_lag)
    n = r.shape[1]
    his, los = _extrema_within(r, L)
    out = np.full(len(r), np.nan)
    within = np.maximum(np.maximum(his, los), 0.0)
    for p in range(len(r)):
        far = _far_lags(r[p], L[p], main_lobe)
        if far.size < 8:
            continue
        k = int(np.argmax(far))
        # (against the in-bound extremum of either sign: an inverted microphone's pairs hold
        # a trough there, and a voice's pitch peaks beyond it stood above their low maximum;
        # the robust spread -- two medians -- only for a peak that passes this)
        if far[k] >= ratio * within[p] and (sd := _robust_sd(far)) > 0 and far[k] >= signif * sd:
            idx = k + L[p] + main_lobe + 1
            out[p] = idx if idx <= n // 2 else idx - n
    return out


def _lag_bounds(max_lag: ArrayLike) -> NDArray:
    """Whole-sample lag bounds (n_pairs,) of :func:`pair_polarity`."""
    return np.ceil(np.atleast_1d(np.asarray(max_lag, dtype=float))).astype(int)


def _extrema_within(r: NDArray, L: NDArray) -> tuple[NDArray, NDArray]:
    """Per pair, the highest value and the depth of the deepest trough (``-min``) of the
    circular correlations ``r`` (n_pairs, nfft) within ``+-L`` samples: two (n_pairs,)
    arrays."""
    n = r.shape[1]
    L = np.minimum(np.asarray(L, dtype=int), (n - 1) // 2)
    m = int(L.max(initial=0))
    w = np.concatenate([r[:, n - m:], r[:, :m + 1]], axis=1)  # lags -m..m
    near = np.abs(np.arange(-m, m + 1))[None, :] <= L[:, None]
    return np.where(near, w, -np.inf).max(axis=1), -np.where(near, w, np.inf).min(axis=1)


def inverted_microphones(sign: ArrayLike, pairs: Sequence[tuple[int, int]], n_mics: int,
                         z: ArrayLike | None = None) -> list[int] | None:
    """The microphones whose inversion explains the pairs' correlation signs (of
    :func:`pair_polarity`), or None when none is inverted or the signs do not tell.

    Every pair with a sign must agree with ``p_i p_j`` for one polarity ``p`` per microphone;
    of the patterns that explain them all, the one with the fewest inverted microphones is
    taken. Each inverted microphone needs two or more troughs among its pairs (three or more
    microphones) -- or, with two microphones, the one trough ``z >=``
    :data:`POLARITY_PAIR_SIGNIF`. Where the named microphones are half the array, the other
    half inverted explains the signs as well (the half without microphone 0 is named: ``[1]``
    of two microphones). None for arrays of more than 12 microphones (not searched).
    """
    s = np.asarray(sign, dtype=int)
    if not np.any(s < 0) or n_mics > _POLARITY_MAX_MICS:
        return None
    if n_mics == 2:
        zz = np.inf if z is None else float(np.max(np.asarray(z)[s < 0]))
        return [1] if zz >= POLARITY_PAIR_SIGNIF and np.all(s <= 0) else None
    I = np.array([a for a, _ in pairs])
    J = np.array([b for _, b in pairs])
    has = s != 0
    best = None
    for code in range(2 ** (n_mics - 1)):  # (microphone 0's sign fixed: p and -p agree alike)
        pol = np.ones(n_mics, dtype=int)
        pol[1:] = [(-1 if code >> k & 1 else 1) for k in range(n_mics - 1)]
        if np.all(pol[I[has]] * pol[J[has]] == s[has]):
            # (the minority; on a tie, pol < 0: the half without microphone 0)
            flipped = np.flatnonzero(pol < 0) if np.sum(pol < 0) <= n_mics / 2 else (
                np.flatnonzero(pol > 0))
            if best is None or len(flipped) < len(best):
                best = flipped
    if best is None or len(best) == 0:
        return None
    troughs = [int(np.sum((s < 0) & ((I == m) | (J == m)))) for m in best]
    return [int(m) for m in best] if min(troughs) >= 2 else None


def _spectra_fit(n_ch: int, n_frames: int, n_bins: int) -> bool:
    """Whether the band spectra of ``n_frames`` frames of ``n_ch`` channels (complex64 and
    their float32 power, 12 bytes per bin) fit :data:`SPECTRA_CACHE_BYTES`."""
    return n_ch * n_frames * n_bins * 12 <= SPECTRA_CACHE_BYTES


@functools.lru_cache(maxsize=32)
def _steer_directions(positions: bytes, n_mics: int, n_dirs: int, in_plane: bool) -> NDArray:
    """Unit vectors steered by :func:`_joint_peaks`, once per array geometry: ``n_dirs`` over
    the sphere, or with ``in_plane`` and a planar array the directions of its plane only
    (0.1 deg apart). ``positions`` is the (n_mics, 3) float64 array's bytes (hashable)."""
    pos = np.frombuffer(positions, dtype=float).reshape(n_mics, 3)
    U = fibonacci_sphere(n_dirs)
    geom = array_geometry(pos) if in_plane else None
    if geom is not None and geom.kind == "planar":
        phi = np.radians(np.arange(3600) / 10.0)
        U = np.outer(np.cos(phi), geom.basis[0]) + np.outer(np.sin(phi), geom.basis[1])
    U.flags.writeable = False
    return U


@functools.lru_cache(maxsize=32)
def _steer_lags(positions: bytes, n_mics: int, pairs: tuple[tuple[int, int], ...], n_dirs: int,
                in_plane: bool, c: float, fs: float, up: int, n_up: int
                ) -> tuple[NDArray, NDArray]:
    """The TDOAs (samples, (n_pairs, n_dirs)) of the pairs for :func:`_steer_directions`'
    directions (same arguments) at sound speed ``c`` and rate ``fs``, and their indices into a
    circular correlation of ``n_up`` samples upsampled ``up`` times (the nearest sample): once
    per geometry and transform rather than per recording (read-only arrays)."""
    pos = np.frombuffer(positions, dtype=float).reshape(n_mics, 3)
    U = _steer_directions(positions, n_mics, n_dirs, in_plane)
    I = np.array([p[0] for p in pairs])
    J = np.array([p[1] for p in pairs])
    tau = -((pos[I] - pos[J]) @ U.T) / c * fs
    idx = np.round(tau * up).astype(int) % n_up
    for a in (tau, idx):
        a.flags.writeable = False
    return tau, idx


def _joint_peaks(P: NDArray, bins: NDArray, nfft: int, positions: NDArray,
                 pairs: list[tuple[int, int]], c: float, fs: float, max_lag: NDArray,
                 up: int = 4, n_dirs: int | None = None, coherent: bool = False,
                 in_plane: bool = False, steer_range_m: float | None | bool = False,
                 climb: bool = False) -> NDArray:
    """Pick each pair's GCC peak consistently with one far-field direction.

    The weighted spectra ``P`` (n_pairs, band bins) are turned into correlations upsampled
    ``up`` times; their sum is evaluated at the TDOAs of ``n_dirs`` directions (default:
    :func:`_n_grid_directions` of the longest pair; a steered
    response of the averaged GCCs, as SRP-PHAT does per frame) and each pair's peak is then
    refined from the best direction's TDOA (with ``climb``, from the nearest peak
    :func:`_climb` reaches: what volume arrays get, whose localizer fits the curved wavefront
    that the plane-wave grid misses; with planar arrays in reverberant rooms the climb also
    reached reflections' peaks -- held-out respeaker-6, RT60 0.6 s, whole-sphere search, 4.5 %
    higher RMSE). A reflection that tops one pair's correlation is
    thus not chosen when the other pairs disagree. With ``steer_range_m`` other than False
    (planar array, ``in_plane``) the TDOAs are instead those of the in-plane source maximising
    the steered sum (:func:`_steered_in_plane`). Returns lags in samples (n_pairs,).
    """
    n_up = nfft * up
    full = np.zeros((P.shape[0], n_up // 2 + 1), dtype=complex)
    full[:, bins] = P
    r = sfft.irfft(full, n_up, axis=-1)
    if steer_range_m is not False:
        lag = _steered_in_plane(P, bins, nfft, r, up, positions, pairs, c, fs, steer_range_m)
        return np.clip(lag, -max_lag, max_lag)
    I = np.array([p[0] for p in pairs])
    J = np.array([p[1] for p in pairs])
    pos = np.ascontiguousarray(positions, dtype=float)
    if n_dirs is None:
        longest = float(np.max(np.linalg.norm(pos[I] - pos[J], axis=1))) / c * fs
        n_dirs = _n_grid_directions(longest)
    U = _steer_directions(pos.tobytes(), pos.shape[0], int(n_dirs), bool(in_plane))
    tau, idx = _steer_lags(pos.tobytes(), pos.shape[0], tuple(pairs), int(n_dirs),
                           bool(in_plane), float(c), float(fs), int(up), n_up)
    score = np.take_along_axis(r, idx, axis=1).sum(axis=0)
    tau0 = tau[:, int(np.argmax(score))]
    if coherent:
        D = -(positions[I] - positions[J]) / c * fs  # tau = D @ u (samples)
        lag = _coherent_refine(P, bins, nfft, D, U[int(np.argmax(score))])
    else:
        if climb:
            tau0 = _climb(r, tau0, up)
        lag = _refine_interp(P, tau0, nfft, bins=bins)
    return np.clip(lag, -max_lag, max_lag)


def _closed_own_peaks(own: NDArray, joint: NDArray, pairs: list[tuple[int, int]],
                      n_mics: int, P: NDArray, bins: NDArray, nfft: int) -> NDArray:
    """The whole-recording lags (samples, (n_pairs,)) of a whole-sphere joint search: the
    pairs' own peaks ``own`` where they already close (``t_ij + t_jk = t_ik`` within
    :data:`_OWN_CLOSURE_SAMPLES` on every pair), the joint choice ``joint``
    (:func:`_joint_peaks`) put some pair on another lobe (more than :data:`_SAME_LOBE_SAMPLES`
    away), and ``own`` sum to the higher correlation (of the averaged weighted spectra ``P``
    (n_pairs, bins) at the rfft bins ``bins`` of ``nfft``-point frames); ``joint`` otherwise.

    The joint search looks for the consistent TDOAs with the largest summed correlation, but
    among plane waves only, and a near source's curved wavefront can fit none: for a
    three-microphone array, in-plane TDOAs whose plane-wave fit has an in-plane part longer
    than 1 (about half of all azimuths). The nearest direction's TDOAs then lie off the peaks
    by ``~ a^2 / (8 r c0)`` (aperture ``a``, range ``r``: 2-5 samples for a 1 m triangle at 2-4
    m and 48 kHz, 1.5 for the 15 cm preset at 0.5 m and 96 kHz), and the refinement from there
    (:func:`_refine_interp`, at most a sample) stopped on a side lobe of the broadband peak:
    summaries 2-6 samples off while every frame was right. Closing own peaks are consistent
    TDOAs too; where they also correlate better, they are what the search was after. (A
    reflection that tops one pair's correlation breaks the closure and still loses to the
    joint choice; in reverberant rooms own peaks that close by chance but correlate worse
    than the joint choice are not taken.)"""
    if np.max(np.abs(joint - own), initial=0.0) <= _SAME_LOBE_SAMPLES:
        return joint
    proj = pair_closure_projector(tuple(pairs), n_mics)
    if proj is None or np.max(np.abs(proj[0] @ own), initial=0.0) > _OWN_CLOSURE_SAMPLES:
        return joint
    return own if _summed_corr(P, own, nfft, bins) > _summed_corr(P, joint, nfft, bins) else joint


def _summed_corr(P: NDArray, tau: NDArray, nfft: int, bins: NDArray) -> float:
    """The pairs' band-limited correlations summed at their own lags: ``sum_p R_p(tau_p)``
    with ``R_p(tau) = sum_k c_k Re(P_pk exp(j w_k tau))`` (``P`` (n_pairs, bins) weighted
    spectra at the rfft bins ``bins`` of ``nfft``-point frames, ``tau`` (n_pairs,) samples),
    evaluated exactly between samples."""
    w, cw = _bin_phase(np.asarray(bins), nfft)
    return float(np.sum(np.real(P * cw * np.exp(1j * np.outer(tau, w)))))


def _n_grid_directions(longest_lag: float) -> int:
    """How many whole-sphere directions :func:`_joint_peaks` steers for an array whose longest
    pair spans ``longest_lag`` samples (see :data:`_GRID_LAG_SAMPLES`)."""
    scale = max(float(longest_lag) / _GRID_LAG_SAMPLES, 1.0) ** 2
    return int(min(np.ceil(_GRID_DIRECTIONS * scale), _MAX_GRID_DIRECTIONS))


def _climb(r: NDArray, tau0: NDArray, up: int, max_shift: float = 1.0) -> NDArray:
    """Where :func:`_refine_interp` starts on a whole-sphere direction grid: each pair's lag
    ``tau0`` (samples) moved up its ``up``-times upsampled correlation ``r`` (n_pairs, n)
    toward the nearest local maximum, by at most ``max_shift`` samples (``tau0`` itself where
    it does not move). The grid's TDOAs can miss a pair's peak by most of a sample -- its 4000
    directions are ~3 deg apart, and a near source's curved wavefront fits no plane wave
    exactly (a 20 cm cube, sources 0.5-1 m away: 0.6-1.4 samples on its longest pairs) --
    and Newton steps from there stopped short of a main lobe as narrow as a broadband
    source's: a 20 cm cube of eight microphones, white noise ~1 m away in free field, had
    pairs 0.7-0.9 sample off (``bench/nmic.py``, 2026-11-27). The bound keeps what the joint
    search chose -- the lobe the direction points into, not a reflection's peak further on."""
    n = r.shape[-1]
    rows = np.arange(r.shape[0])
    start = np.round(np.asarray(tau0, dtype=float) * up).astype(int)
    i = start.copy()
    for _ in range(int(round(max_shift * up))):
        here = r[rows, i % n]
        left, right = r[rows, (i - 1) % n], r[rows, (i + 1) % n]
        move = np.where((right > here) & (right >= left), 1, np.where(left > here, -1, 0))
        if not move.any():
            break
        i = i + move
    return np.where(i != start, i / float(up), tau0)


@functools.lru_cache(maxsize=32)
def _inplane_grid(positions: bytes, n_mics: int, pairs: tuple[tuple[int, int], ...], c: float,
                  range_m: float | None, n_grid: int = 3600) -> tuple[NDArray, ...]:
    """In-plane steering of :func:`_steered_in_plane`, once per geometry: the angles ``theta``
    (rad, in the plane basis of :func:`~hearsee.audio.localize.array_geometry`), the
    microphone offsets from the array centre, the basis, the pair indices and the TDOAs
    (s, (n_grid, n_pairs)) of a source ``range_m`` from the centre at each angle."""
    pos = np.frombuffer(positions, dtype=float).reshape(n_mics, 3)
    geo = array_geometry(pos)
    d = pos - geo.centre
    I = np.array([p[0] for p in pairs])
    J = np.array([p[1] for p in pairs])
    theta = np.arange(n_grid) * (2.0 * np.pi / n_grid)
    rho = np.full(n_grid, 0.0 if range_m is None else 1.0 / float(range_m))
    tau = _inplane_tdoa(theta, rho, geo.basis, d, I, J, c)
    for a in (theta, d, tau):
        a.flags.writeable = False
    return theta, d, geo.basis, I, J, tau


def _steered_in_plane(P: NDArray, bins: NDArray, nfft: int, r_up: NDArray, up: int,
                      positions: NDArray, pairs: list[tuple[int, int]], c: float, fs: float,
                      range_m: float | None, n_iter: int = 8,
                      max_shift_deg: float = 1.5) -> NDArray:
    """TDOAs (samples, (n_pairs,)) of the in-plane source that maximises the steered sum of
    the averaged correlations, ``f(theta) = sum_p R_p(tau_p(theta))``.

    The source is ``range_m`` metres from the array centre (a spherical wavefront, the model
    of :func:`~hearsee.audio.localize.near_field_in_plane` with the same ``range_m``, which
    then returns ``theta`` exactly; None: plane waves). ``f`` is searched on a 0.1-deg grid of
    the ``up``-times upsampled correlations ``r_up`` (n_pairs, nfft * up), linearly
    interpolated (which may place the maximum ~0.5 deg off for broadband spectra), and its
    maximum refined by Newton steps on ``theta`` with the correlations evaluated exactly
    (:func:`_corr_derivs`), at most ``max_shift_deg`` from the grid maximum. This is SRP-PHAT's
    estimate (DiBiase et al. 2001) on hearsee's averaged weighted spectra: unlike each pair's
    own peak refined from the grid direction (``joint="pairs"``), or Newton steps on a free
    direction vector (``"coherent"``), the result stays on the source model the localizer
    assumes, so an early reflection that bends one pair's peak cannot pull the others.
    """
    key = np.ascontiguousarray(positions, dtype=float)
    theta, d, basis, I, J, tau_s = _inplane_grid(key.tobytes(), key.shape[0], tuple(pairs),
                                                 float(c), range_m)
    n_up = r_up.shape[-1]
    x = (tau_s * (fs * up)) % n_up  # (n_grid, n_pairs) upsampled lag positions
    fl = np.floor(x)
    frac = x - fl
    # (a TDOA of -1e-20 s -- a pair broadside to the angle, e.g. on a square array -- gives
    # x == n_up after rounding: index 0, not one past the end)
    i0 = fl.astype(int) % n_up
    rows = np.arange(len(pairs))
    score = np.sum(r_up[rows, i0] * (1.0 - frac) + r_up[rows, (i0 + 1) % n_up] * frac, axis=1)
    g = int(np.argmax(score))
    th0 = th = float(theta[g])
    step_max = np.radians(float(max_shift_deg))
    rho = np.full(3, 0.0 if range_m is None else 1.0 / float(range_m))
    h = 1e-4

    def taus(th: float) -> NDArray:
        return _inplane_tdoa(np.array([th - h, th, th + h]), rho, basis, d, I, J, c) * fs

    def value(tau: NDArray) -> float:
        return _summed_corr(P, tau, nfft, bins)

    for _ in range(n_iter):
        tm, t0, tp = taus(th)
        t1, t2 = (tp - tm) / (2 * h), (tp - 2 * t0 + tm) / (h * h)  # dtau/dtheta, d2tau/...
        d1, d2 = _corr_derivs(P, t0, nfft, bins)
        f1 = float(d1 @ t1)
        f2 = float(d2 @ (t1 * t1) + d1 @ t2)
        if f2 >= 0:  # not concave here: keep the grid maximum's neighbourhood
            break
        step = -f1 / f2
        th = float(np.clip(th + step, th0 - step_max, th0 + step_max))
        if abs(step) < 1e-9:
            break
    tau_grid = tau_s[g] * fs
    tau_new = taus(th)[1]
    return tau_new if value(tau_new) >= value(tau_grid) else tau_grid


def _fine_peaks(P: NDArray, bins: NDArray, nfft: int, max_lag: NDArray, up: int,
                first_arrival: float = 0.0, reach: NDArray | None = None) -> NDArray:
    """Each pair's maximum of the band-limited correlation of spectra ``P`` (n_pairs, bins)
    within ``+-max_lag``: searched on an ``up``-times upsampled grid (``reach``: see
    :func:`_lag_window`), then refined (:func:`_refine_interp`). Lags in samples
    (n_pairs,)."""
    n_up = nfft * up
    full = np.zeros((P.shape[0], n_up // 2 + 1), dtype=complex)
    full[:, bins] = P
    r = sfft.irfft(full, n_up, axis=-1)
    lags, win = _lag_window(r, max_lag, up, reach)
    k = np.argmax(win, axis=-1)
    if first_arrival > 0:
        k = _first_arrival_peaks(win, lags, k, first_arrival)
    tau0 = lags[k] / up
    lag = _refine_interp(P, tau0.astype(float), nfft, bins=bins)
    return np.clip(lag, -max_lag, max_lag)


def _first_arrival_peaks(win: NDArray, lags: NDArray, k: NDArray, delta: float) -> NDArray:
    """Indices of each pair's direct-path peak in correlations ``win`` (n_pairs, n_lags) at
    ``lags``, given the indices ``k`` of their maxima: the local maximum furthest from zero
    lag on the side of the highest one whose height is within ``delta`` (relative) of it
    (see ``first_arrival`` of :func:`estimate_tdoas`); ``k`` where the maximum is at lag 0."""
    top = np.take_along_axis(win, k[:, None], axis=1)
    pad = np.full((win.shape[0], 1), -np.inf)
    inside = np.isfinite(win)  # the admissible lags of each pair
    # a local maximum needs an admissible neighbour on each side that is not higher: the last
    # admissible lag, still rising toward the bound, is no peak (it was taken for one)
    left = np.hstack([pad, win[:, :-1]])
    right = np.hstack([win[:, 1:], pad])
    peak = inside & (win >= left) & (win >= right) & np.isfinite(left) & np.isfinite(right)
    side = np.sign(lags[k])[:, None]
    cand = (peak & (win >= top - delta * np.abs(top)) & (side != 0)
            & (lags[None, :] * side >= np.abs(lags[k])[:, None]))
    need = FIRST_ARRIVAL_PROMINENCE * np.abs(top[:, 0])
    for p, i in zip(*np.nonzero(cand), strict=True):  # (a few per recording)
        if i != k[p] and _col_depth(win[p], int(i), int(k[p])) < need[p]:
            cand[p, i] = False
    far = np.argmax(np.where(cand, np.abs(lags)[None, :], -1), axis=1)
    return np.where(cand.any(axis=1), far, k)


def _col_depth(r: NDArray, i: int, k: int) -> float:
    """How far correlation ``r`` dips below its peak at index ``i`` on the way toward index
    ``k`` (the highest, ``r[k] >= r[i]``) before it is as high as ``r[i]`` again: the peak's
    prominence on that side (its col). A ripple on the highest lobe's flank dips by a hair."""
    step = 1 if k > i else -1
    path = r[np.arange(i + step, k + step, step)]
    higher = np.flatnonzero(path >= r[i])
    return float(r[i] - path[: higher[0] + 1].min())


def _corr_derivs(P: NDArray, tau: NDArray, nfft: int, bins: NDArray) -> tuple[NDArray, NDArray]:
    """First and second derivatives (per sample) of each pair's band-limited correlation
    ``R_p(tau) = sum_k c_k Re(P_pk exp(j w_k tau))`` at lags ``tau`` (n_pairs,) samples."""
    w, cw = _bin_phase(np.asarray(bins), nfft)
    Q = P * cw * np.exp(1j * np.outer(tau, w))
    d1 = -np.sum(w * Q.imag, axis=-1)
    d2 = -np.sum(w * w * Q.real, axis=-1)
    return d1, d2


def _coherent_refine(P: NDArray, bins: NDArray, nfft: int, D: NDArray, u0: NDArray,
                     n_iter: int = 6) -> NDArray:
    """TDOAs (samples) of the far-field direction vector maximising the summed correlations.

    Newton iterations on ``f(u) = sum_p R_p((D u)_p)`` (``D`` (n_pairs, 3): rows
    ``-(M_i - M_j) fs / c``), started at the grid direction ``u0``; directions the array cannot
    resolve (e.g. normal to a planar array) are left unchanged (pseudo-inverse). Unlike
    refining each pair's peak on its own, the pairs are fitted coherently -- a pair whose peak
    a reflection has shifted is pulled back by the others, weighted by its peak sharpness,
    like SRP-PHAT's steered sum but evaluated exactly only near the candidate. The result is
    consistent (``t_ij + t_jk = t_ik``) by construction.
    """
    u = np.asarray(u0, dtype=float).copy()
    tau0 = D @ u
    for _ in range(n_iter):
        tau = D @ u
        d1, d2 = _corr_derivs(P, tau, nfft, bins)
        g = D.T @ d1
        H = D.T @ (d2[:, None] * D)
        ev, V = np.linalg.eigh(H)
        scale = np.abs(ev).max(initial=0.0)
        keep = ev < -1e-9 * max(scale, _TINY)
        if not keep.any():
            break
        step = -(V[:, keep] / ev[keep]) @ (V[:, keep].T @ g)
        dt = D @ step
        big = np.abs(dt).max(initial=0.0)
        if big > 0.5:
            step = step * (0.5 / big)
        u = u + step
        if big < 1e-4:
            break
    tau = D @ u
    # a Newton step never leaves the grid direction's main lobe by more than a sample
    return np.clip(tau, tau0 - 1.5, tau0 + 1.5)


def _coherence_ratio(s_cross: NDArray, s_auto: NDArray, n_frames: int, noise_psd: NDArray,
                     I: NDArray, J: NDArray) -> float:
    """Measured coherence relative to the coherence the noise floor allows (see
    ``reverb_method`` of :func:`estimate_tdoas`). ``s_cross`` (n_pairs, bins) and ``s_auto``
    (n_ch, bins) are sums over ``n_frames`` active frames; ``noise_psd`` (n_ch, bins)."""
    xi = np.maximum(s_auto / (n_frames * noise_psd) - 1.0, 0.0)
    g = xi[I] * xi[J] / ((1.0 + xi[I]) * (1.0 + xi[J]))
    msc = np.abs(s_cross) ** 2 / np.maximum(s_auto[I] * s_auto[J], _TINY)
    den = np.sum(g * g, axis=-1)
    ok = den > 0
    if not ok.any():
        return float("nan")
    return float(np.mean(np.sum(g * msc, axis=-1)[ok] / den[ok]))


def _coherence_gain(a: NDArray, frame_len: int, fs: float, band_hz: tuple[float, float],
                    factor: int = 4) -> float:
    """How much two microphones' coherence grows with the frame length: the magnitude-squared
    coherence (MSC) of the two rows of ``a`` (2, n) measured with frames ``factor`` times
    ``frame_len`` over that with frames of ``frame_len`` (each debiased, averaged over the bins
    in ``band_hz`` (Hz); non-overlapping Hann frames). NaN with fewer than 5 long frames.

    The reverberation test of :func:`estimate_tdoas` (on its widest pair) when no inactive
    frame gives a noise reference (a steady source). Uncorrelated sensor noise lowers the
    coherence by the same amount at any frame length, so the gain stays ~1 in free field; a
    reverberant tail longer than a frame decorrelates short frames more than long ones (a
    frame sees the tail of the previous frames' sound), so the gain grows with the
    reverberation. An MSC averaged over n independent frames is biased up by ~(1 - MSC)^2 / n;
    ``(n MSC - 1) / (n - 1)`` (exact for incoherent signals) removes most of it. The
    diffuse-field test of reverberation via the coherence's frame-length dependence is our
    construction; the coherence estimator and its bias are Carter, Knapp & Nuttall (1973),
    "Estimation of the magnitude-squared coherence function via overlapped FFT processing",
    IEEE Trans. Audio Electroacoust. 21(4).
    """
    out = []
    for L in (int(frame_len), int(factor) * int(frame_len)):
        n = a.shape[1] // L
        if n < 5:
            return float("nan")
        b0 = max(int(np.ceil(band_hz[0] * L / fs)), 0)
        b1 = min(int(np.floor(band_hz[1] * L / fs)) + 1, L // 2 + 1)
        if b1 <= b0:
            return float("nan")
        X = frame_spectra(frame_signals(a, L, L), _window("hann", L), L, b0, b1)
        auto = np.sum(X.real**2 + X.imag**2, axis=1)  # (2, bins)
        cross = np.sum(X[0] * np.conj(X[1]), axis=0)  # (bins,)
        msc = (cross.real**2 + cross.imag**2) / np.maximum(auto[0] * auto[1], _TINY)
        out.append(float(np.mean((n * msc - 1.0) / (n - 1.0))))
    return out[1] / out[0] if out[0] > 0 else float("nan")


def _check_options(refine: str, summary_frames: str, joint: str, min_peak_snr: float,
                   min_frame_peak_snr: float, phat_beta: float, onset_weight: float,
                   snr_weight: bool | str) -> None:
    """ConfigError for an out-of-range option of :func:`estimate_tdoas`."""
    _check_refine(refine)
    if summary_frames not in ("valid", "active"):
        raise ConfigError(f"summary_frames must be 'valid' or 'active', got {summary_frames!r}")
    if joint not in ("pairs", "coherent", "steered", "auto"):
        raise ConfigError(f"joint must be 'pairs', 'coherent', 'steered' or 'auto', got {joint!r}")
    finite_number("min_peak_snr", min_peak_snr, 0.0)
    finite_number("min_frame_peak_snr", min_frame_peak_snr, 0.0)
    finite_number("phat_beta", phat_beta, 0.0, 1.0)
    finite_number("onset_weight", onset_weight, 0.0)
    if not (isinstance(snr_weight, bool | np.bool_) or snr_weight == "ml"):
        # (any other value switched the SNR weighting on, as True: "ML", "off", None is False)
        raise ConfigError(f"snr_weight must be True, False or 'ml', got {snr_weight!r}")


def _check_steered(arr: MicArray, source_in_plane: bool, steer_range_m: float | None) -> None:
    """ConfigError unless ``joint="steered"`` can steer: a source in the plane of a planar
    array (two microphones have no joint search: nothing to check) at a positive range."""
    if not source_in_plane:
        raise ConfigError("joint='steered' searches the array plane: it needs "
                          "source_in_plane=True")
    if arr.n_mics >= 3 and array_geometry(arr).kind != "planar":
        raise ConfigError(f"joint='steered' needs a planar array; {arr.name!r} is "
                          f"{array_geometry(arr).kind}")
    if steer_range_m is not None and not (np.isfinite(steer_range_m) and steer_range_m > 0):
        raise ConfigError(f"steer_range_m must be a positive number of metres or None, got "
                          f"{steer_range_m}")


def _onset_weights(energy: NDArray, onset_weight: float) -> NDArray:
    """Frame weights of the whole-recording average: ``1 + onset_weight * max(log10(E_f /
    E_{f-1}), 0)`` (energy rise over the previous frame; see ``onset_weight``). Digitally
    silent frames (a recorder's zero lead-in, energy 0) count at the quietest frame's energy
    that is not zero: against the old 1e-30 floor the first frame with sound rose by ~30
    decades and outweighed ~90 ordinary frames."""
    rise = np.zeros(len(energy))
    if len(energy) > 1:
        e = np.asarray(energy, dtype=float)
        heard = e[e > 0]
        e = np.maximum(e, max(float(heard.min()), _TINY) if heard.size else _TINY)
        rise[1:] = np.clip(np.log10(e[1:] / e[:-1]), 0.0, None)
    return 1.0 + float(onset_weight) * rise


def _unit_frames(P: NDArray) -> NDArray:
    """Each frame's weighted cross spectrum ``P`` (frames, pairs, bins) scaled to unit norm, so
    that every frame counts equally in the whole-recording average."""
    norm = np.sqrt(np.sum(P.real**2 + P.imag**2, axis=-1, keepdims=True))
    return P * (1.0 / np.maximum(norm, _TINY))  # (a real reciprocal: no complex division)


def _noise_spectrum(frames: NDArray, active: NDArray, win: NDArray, nfft: int, k0: int,
                    k1: int, power_all: NDArray | None = None) -> NDArray | None:
    """Each channel's noise power spectrum (n_ch, bins k0..k1-1), averaged over the inactive
    frames of ``frames`` (n_ch, F, L); None with fewer than 3 of them. Frames in which a
    channel is digitally silent (all zeros: a recorder's lead-in, zero padding) are no noise
    sample: a noise floor of zero would make every SNR infinite. ``power_all``: the band power
    spectra ``|X|^2`` (n_ch, F, bins) of every frame when already computed (not repeated)."""
    silent = ~np.all(frames.any(axis=-1), axis=0)  # (F,); (no `frames != 0` temporary)
    quiet = np.flatnonzero(~active & ~silent)
    if quiet.size < _MIN_SUMMARY_FRAMES:
        return None
    pq = (power_all[:, quiet, :] if power_all is not None
          else _spectra_power(frames[:, quiet, :], win, nfft, k0, k1)[1])
    psd = np.mean(pq, axis=1)
    return np.maximum(psd, 1e-12 * psd.max(initial=0.0) + _TINY)


def gcc_nfft(frame_len: int, max_lag: float) -> int:
    """Transform length of :func:`estimate_tdoas`' frames of ``frame_len`` samples whose
    admissible lags reach ``max_lag`` samples: zero padding by twice the largest lag keeps
    them free of circular wrap (a fast real-FFT length)."""
    import scipy.fft as sfft

    return int(sfft.next_fast_len(frame_len + 2 * int(np.ceil(max_lag)) + 2, real=True))


def _spectral_densities(auto: NDArray, G: NDArray, I: NDArray, J: NDArray, smooth_frames: int,
                        causal: bool = False) -> tuple[NDArray, NDArray, NDArray]:
    """Auto spectra of each pair's microphones and the cross spectra ``G`` (frames, pairs,
    bins), averaged over ``smooth_frames`` frames: what SCOT, ROTH and ML weigh with.
    ``auto`` (frames, n_ch, bins): each channel's power spectrum ``|X|^2``."""
    k = max(int(smooth_frames), 1)
    # one mean per channel (not per pair end), and the cross spectra's real and imaginary
    # parts in one pass through their interleaved float view
    A = _frame_moving_mean(auto, k, causal)
    Gc = np.ascontiguousarray(G)
    Gav = _frame_moving_mean(Gc.view(Gc.real.dtype), k, causal).view(Gc.dtype)
    return A[:, I, :], A[:, J, :], Gav


def _frame_moving_mean(a: NDArray, k: int, causal: bool = False) -> NDArray:
    """The mean of ``k`` consecutive frames (axis 0) of ``a`` around each frame, the edge
    frames repeated beyond the ends: ``scipy.ndimage.uniform_filter1d(a, k, axis=0,
    mode="nearest")`` (the same window for even ``k``) as ``k - 1`` sums of shifted slices in
    ``a``'s precision. ndimage copies every (channel, bin) line of a few dozen frames through a
    line buffer in double precision: ~2.5x slower on a recording's spectra; single precision
    differs from it by ~1 ulp of each sum. A long window (``k`` > 16): running sums in double
    precision, the repeated edge frames counted rather than copied (memory O(F) whatever
    ``k``: ``smooth_frames=10**6`` copied 10**6 frames of spectra, 4 GiB for a 0.5 s
    recording). ``causal``: the ``k`` frames ending at each frame instead (the first frame
    repeated before the start)."""
    F = a.shape[0]
    if k <= 1 or F == 0:
        return a.copy()
    # (causal: the k frames ending at each frame, the first frame repeated before the start)
    lo, hi = (k - 1, 0) if causal else (k // 2, (k - 1) // 2)
    if k > 16:
        c = np.zeros((F + 1,) + a.shape[1:])
        np.cumsum(a, axis=0, dtype=float, out=c[1:])
        first = np.arange(F) - lo  # window of frame f: frames first[f] .. first[f] + k - 1
        inner = c[np.minimum(first + k, F)] - c[np.maximum(first, 0)]
        shape = (F,) + (1,) * (a.ndim - 1)
        before = np.maximum(-first, 0).astype(float).reshape(shape)  # copies of frame 0
        after = np.maximum(first + k - F, 0).astype(float).reshape(shape)  # of frame F - 1
        return ((inner + before * a[0] + after * a[F - 1]) / k).astype(a.dtype)
    s = np.empty_like(a)
    for j in range(k):  # frame f adds frame f + j - lo, clipped to the ends
        _add_shifted(s, a, j - lo, first=j == 0)
    s *= s.dtype.type(1.0 / k)
    return s


def _add_shifted(s: NDArray, a: NDArray, d: int, first: bool) -> None:
    """``s[f] += a[clip(f + d, 0, F - 1)]`` for every frame ``f`` (axis 0; ``first``: ``=``
    instead of ``+=``): the middle frames from a slice of ``a``, those beyond an end from its
    edge frame by broadcasting -- no copy of ``a`` with its edges repeated (each sum adds the
    same terms in the same order: the same bits)."""
    F = a.shape[0]
    m0, m1 = min(max(-d, 0), F), max(min(F - d, F), 0)  # frames whose f + d is inside
    parts = ((slice(0, m0), a[0]), (slice(m0, m1), a[m0 + d:m1 + d]), (slice(m1, F), a[F - 1]))
    for rows, src in parts:
        if rows.stop > rows.start:
            if first:
                s[rows] = src
            else:
                s[rows] += src


def _snr_coherence(power: NDArray, noise_psd: NDArray, I: NDArray, J: NDArray,
                   hannan_thomson: bool) -> NDArray:
    """Per-bin coherence estimate ``xi_i xi_j / ((1 + xi_i)(1 + xi_j))`` of each pair from the
    channels' a-priori SNRs over ``noise_psd`` (see ``snr_weight``); in the Hannan-Thomson form
    ``g / (1 - g)`` when asked. ``power`` (F', n_ch, B): the channels' ``|X|^2``."""
    xi = power / noise_psd  # (F', n_ch, B)
    xi -= 1.0
    # (a product of two must not overflow float32; coh ~ 1 anyway)
    np.clip(xi, 0.0, 1e15, out=xi)
    xi1 = xi + 1.0  # (per channel, not per pair end; the same bits)
    coh = xi[:, I] * xi[:, J]
    coh /= xi1[:, I] * xi1[:, J]
    if hannan_thomson:  # gamma^2 / (1 - gamma^2)
        np.minimum(coh, 0.99, out=coh)
        coh /= 1.0 - coh
    return coh


def _given_activity(active: ArrayLike, n_frames: int) -> NDArray:
    """``active`` of :func:`estimate_tdoas` as a (n_frames,) bool array (ConfigError for
    another shape or non-boolean values)."""
    a = np.asarray(active)
    if a.shape != (n_frames,) or a.dtype != bool:
        raise ConfigError(f"active must be {n_frames} booleans (one per frame), got "
                          f"{a.dtype} of shape {a.shape}")
    return a


def _given_noise(noise: ArrayLike, shape: tuple[int, int, int], gain: float) -> NDArray:
    """``frame_noise_psd`` of :func:`estimate_tdoas` (``shape`` = frames, channels, band
    bins) in single precision, times ``gain**2`` (the samples' level normalisation); rows may
    be NaN (no reference), other values must be finite and > 0 (ConfigError)."""
    n = np.asarray(noise, dtype=float)
    if n.shape != shape:
        raise ConfigError(f"frame_noise_psd must have shape {shape} (frames, microphones, band "
                          f"bins), got {n.shape}")
    none = np.isnan(n).all(axis=(1, 2))
    if not (np.all(np.isfinite(n[~none])) and np.all(n[~none] > 0)):
        raise ConfigError("frame_noise_psd must be finite and > 0 (a NaN row: no reference)")
    return (n * gain**2).astype(np.float32)


def _mean_rows(noise: NDArray) -> NDArray | None:
    """The mean of the frames' noise spectra (F, n_ch, B) that are not NaN; None if all are."""
    ok = ~np.isnan(noise).all(axis=(1, 2))
    return noise[ok].mean(axis=0) if ok.any() else None


def estimate_tdoas(
    x: ArrayLike,
    fs: float,
    array: MicArray | str,
    frame_ms: float = 64.0,
    hop_ms: float = 32.0,
    method: str = "phat",
    pairs: Sequence[tuple[int, int]] | None = None,
    *,
    refine: str = "interp",
    band_hz: tuple[float, float] | None = None,
    smooth_frames: int = DEFAULT_SMOOTH_FRAMES,
    margin_samples: float = DEFAULT_MARGIN_SAMPLES,
    vad_db: float = 3.0,
    min_confidence: float = 1.0,
    window: str | tuple = DEFAULT_WINDOW,
    snr_weight: bool | str = True,
    summary_frames: str = "valid",
    joint: str = "pairs",
    steer_range_m: float | None = None,
    phat_beta: float = 1.0,
    onset_weight: float = 0.0,
    reverb_method: str | None = None,
    reverb_coherence: float = 0.9,
    summary_upsample: int = 4,
    source_in_plane: bool = False,
    first_arrival: float = FIRST_ARRIVAL,
    whole_recording: bool = True,
    min_peak_snr: float = 5.5,
    min_frame_peak_snr: float = 4.5,
    band_vad: bool = True,
    chunk_frames: int = 128,
    progress: Callable[[int], None] | None = None,
    active: ArrayLike | None = None,
    frame_noise_psd: ArrayLike | None = None,
    causal_smoothing: bool = False,
    empty_band_db: float | None = EMPTY_BAND_DB,
    tonal_noise: bool = True,
) -> TdoaFrames:
    """Framed GCC TDOAs of all microphone pairs at once.

    Parameters
    ----------
    x : array (n_mics, n)
        The recording; row k is microphone k.
    fs : float
        Sample rate in Hz.
    array : MicArray or preset/YAML name
        Microphone geometry (for the lag bounds and the pairs).
    frame_ms, hop_ms : float
        Frame length and hop in milliseconds.
    method : str
        GCC weighting: ``phat``, ``scot``, ``roth``, ``ml`` (Hannan-Thomson) or ``cc``
        (``gcc-phat`` etc. accepted).
    pairs : list of (i, j), optional
        Microphone pairs (default: all ``i < j``).
    refine : ``"interp"`` | ``"parabolic"`` | ``"none"``
        Sub-sample peak refinement (see module docstring).
    band_hz : (low, high), optional
        Only use this frequency band in Hz (e.g. ``(300, 3500)`` for speech). A recording
        upsampled from a lower rate (an 8 kHz file read at 16 kHz with
        ``read_recording(resample=True)``, or by a sound server) holds nothing above its old
        Nyquist frequency but the resampler's mirror images of the band below, whose
        cross-spectra point at mirrored delays; PHAT and ML weigh those bins like any other
        (the SNR weights take the images for signal). Since 2026-12-03 such an empty top band
        is found and left out by itself (``empty_band_db``); before, 8 kHz recordings
        upsampled to 16 kHz (free field, 20 dB) gave summaries 4-70 us off and azimuths 6-15
        deg RMS (up to 33), 0.3-0.5 deg with ``(0, 3800)``, as at 8 kHz. A band given here is
        trimmed the same way where it reaches into the empty band.
    smooth_frames : int
        Frames averaged for the spectral densities of SCOT, ROTH and ML.
    margin_samples : float
        Added to each pair's physical lag bound.
    vad_db, min_confidence : float
        Thresholds deciding which frames hold a source (module docstring).
    window : str or tuple
        Analysis window (scipy.signal.get_window spec; ConfigError for anything else, e.g. an
        array of weights). The default Tukey window with 25 %
        tapers keeps most of each frame at full weight: with a Hann window the TDOA variance
        is ~1.7x larger (bench/doa.py, white noise vs the Cramer-Rao bound). Each frame's
        mean is removed before windowing (:func:`windowed_frames`): a DC offset is no source.
    snr_weight : bool or "ml"
        Multiply the weighting by a per-bin coherence estimate ``xi_i xi_j / ((1 + xi_i)
        (1 + xi_j))`` from each channel's a-priori SNR ``xi = max(|X|^2 / N - 1, 0)``, with the
        noise spectrum ``N`` averaged over the recording's inactive (noise-only) frames
        (reconstruction of the SNR-weighted PHAT of ManyEars/ODAS, Valin et al. 2007). Bins that
        hold only noise then no longer count as much as bins with the source. ``"ml"`` uses the
        Hannan-Thomson form ``g / (1 - g)`` of that coherence estimate ``g`` instead (with
        PHAT this is Knapp & Carter's ML processor with the coherence taken from the noise
        floor). Ignored when the recording has fewer than 3 inactive frames (nothing to learn
        the noise from; e.g. a steady source), which then gets the plain weighting.
    summary_frames : ``"valid"`` | ``"active"``
        Which frames the whole-recording estimate averages: the valid ones (default) or every
        frame with energy (then weighted by the GCC weighting alone -- useful with
        ``snr_weight``, which already down-weights unreliable bins).
    joint : ``"pairs"`` | ``"coherent"`` | ``"steered"`` | ``"auto"``
        With 3+ microphones, how the whole-recording peaks are refined after the direction
        grid search: each pair's peak on its own (``"pairs"``, default) or jointly by Newton
        iterations on the far-field direction maximising the *sum* of the pairs' averaged
        correlations (``"coherent"``: an SRP-style steered sum evaluated exactly, only near the
        grid candidate; the TDOAs are then consistent by construction). On held-out reverberant
        recordings (bench seed 777) ``"coherent"`` did not lower the azimuth error (paired mean
        +0.07 deg at RT60 0.3 s, +0.02 deg at 0.6 s, three-mic), so it is not the default.
        ``"steered"`` (needs ``source_in_plane`` and a planar array): the TDOAs of the in-plane
        source ``steer_range_m`` away that maximises the steered sum of the averaged
        correlations, refined by Newton steps on its angle (SRP-PHAT's estimate on these
        spectra, see :func:`_steered_in_plane`); consistent, and on the source model of
        ``localize_tdoa(in_plane=True)`` with the same range. On held-out recordings of
        ``bench/doa.py`` (seeds 777 and 778, three-mic, 32 per condition, 2 m range) it
        lowered the azimuth RMSE against ``"pairs"`` in 19 of 36 conditions and raised it in
        17 (reverberant ARCTIC speech worse, e.g. RT60 0.6 s 10 dB 2.3 -> 2.9 deg; male voice
        and white noise in reverberation better, e.g. RT60 0.6 s 20 dB 2.7 -> 1.9 and 1.4 ->
        1.1 deg), so the benchmark keeps ``"pairs"``. ``"auto"`` (in
        :data:`SUMMARY_TUNED`): ``"steered"`` when the recording is judged reverberant (see
        ``reverb_method``; it needs one), the source is in the plane (``source_in_plane``) of
        a planar array of at least :data:`AUTO_STEERED_MIN_MICS` microphones, at
        ``steer_range_m`` or else :data:`~hearsee.audio.localize.IN_PLANE_RANGE_M`;
        ``"pairs"`` otherwise. With more pairs the steered sum outvotes a reflection that
        bends one pair's peak, and in free field each pair's own peak is the better estimate
        (``respeaker-4``: 0.44 -> 0.53 and 0.45 -> 0.64 deg steered everywhere). Held out
        under a rule written first (2026-11-27; seeds 23/24, ``bench/doa.py``'s recordings and
        setting, 8 sources per room x 4 signals x 10/20 dB): ``respeaker-6`` RT60 0.3 s
        1.84 -> 1.78 and 1.50 -> 1.44 deg, 0.6 s 2.78 -> 2.57 and 3.91 -> 3.44; ``respeaker-4``
        0.3 s 1.26 -> 1.27 and 2.24 -> 2.25, 0.6 s 3.09 -> 2.92 and 3.22 -> 2.92; anechoic
        unchanged (no recording judged reverberant).
    steer_range_m : float or None
        With ``joint="steered"``: the assumed source range in metres from the array centre
        (spherical wavefront; use the ``range_m`` of the in-plane localization, 2 m by
        default there); None steers plane waves. Default None (with ``"auto"``:
        :data:`~hearsee.audio.localize.IN_PLANE_RANGE_M`).
    phat_beta : float in [0, 1]
        Partial whitening for PHAT and ML: the weighting is multiplied by ``|G|^(1 - beta)``
        (``beta = 1``: unchanged, default; PHAT-beta of Donohue et al. 2007). Values of 0.6-0.8
        raised the azimuth error on held-out reverberant recordings.
    onset_weight : float >= 0
        Weights each frame's spectrum in the whole-recording average by ``1 + onset_weight *
        max(log10(E_f / E_{f-1}), 0)`` -- frames whose energy rises (onsets, where the direct
        path dominates the reverberation: precedence effect) count more. 0 (default) weights
        frames equally; ``bench/doa.py`` uses 3 (chosen on held-out seeds). Per-frame TDOAs
        are unaffected.
    reverb_method : str, optional
        A second GCC weighting for the whole-recording estimate of *reverberant* recordings
        (e.g. ``"roth"``; default None: ``method`` always). Reverberation is measured, not
        assumed: over the active frames, the magnitude-squared coherence ``MSC_k`` of each
        pair's averaged cross spectrum is compared with the coherence the noise floor alone
        allows, ``g_k = xi_i xi_j / ((1 + xi_i)(1 + xi_j))`` (``xi`` each channel's SNR over the
        noise spectrum of the inactive frames): ``coherence_ratio = sum g MSC / sum g^2``,
        averaged over the pairs. It stays ~1 in free field at any SNR (noise explains all the
        lost coherence) and drops below 1 when a diffuse reverberant tail, longer than a frame,
        decorrelates the microphones (held-out bench recordings, 64 ms frames: anechoic >= 0.98,
        RT60 0.3-0.6 s at 10-20 dB 0.45-0.87). Below ``reverb_coherence`` the summary uses
        ``reverb_method``: the ML weighting is optimal for uncorrelated noise but
        over-weights the strong low-frequency bins that reverberation corrupts, where a
        whitening weighting (ROTH/SCOT/PHAT) wins. Per-frame TDOAs and the frames' validity
        still use ``method``. With fewer than 3 inactive frames (a steady source: no noise
        reference) the test is instead how much the coherence grows with the frame length
        (``coherence_gain``, :func:`_coherence_gain`; reverberant above
        :data:`REVERB_COHERENCE_GAIN`), and the second weighting's frames count equally.
    reverb_coherence : float
        The ``coherence_ratio`` threshold (default 0.9).
    summary_upsample : int
        Without redundant pairs (two microphones, or pairs that share no triangle), the
        whole-recording peak is searched on the averaged correlation upsampled this many times
        before the sub-sample refinement (default 4; 1 = on the integer lags; at most
        :data:`MAX_SUMMARY_UPSAMPLE`). A broadband
        correlation oscillates within ~2 samples; with two close peaks (direct path and an
        early reflection) the integer samples can peak *between* them and the refinement then
        stops in the valley -- upsampling finds the true maximum (three or more microphones
        already choose their peaks on a 4x upsampled grid). On held-out two-microphone
        recordings of ``bench/doa.py`` (seed 777, 30 each) it cut the azimuth RMSE of white
        noise in the RT60 0.6 s room from 8.0 to 4.9 deg (10 dB) and 5.4 to 4.9 deg (20 dB)
        and left every other condition unchanged (seed 778: anechoic and RT60 0.3 s, voices
        and noise, 0-20 dB); it costs one upsampled inverse FFT per recording.
    first_arrival : float in [0, 1]
        Without redundant pairs (two microphones), the whole-recording peak is the local
        maximum of the averaged correlation *furthest from zero lag* on the side of the highest
        one, among those within ``first_arrival`` (relative) of its height (0: the highest;
        only with ``summary_upsample`` > 1). Reflections off planes parallel to the pair's axis
        (the floor, the ceiling and for a horizontal pair two of the walls) keep the source's
        offset along the axis but travel further, so they arrive from the same side at a
        shorter lag: the direct path is the furthest of that family (the first wavefront of
        the precedence effect). In a reverberant recording the averaged correlation can peak
        on one of them, biasing the azimuth toward broadside. Reconstruction choice, measured
        2026-11-26 on ``bench/doa.py``'s two-microphone rooms (RT60 0.3/0.6 s, 0-20 dB, four
        signals, 10 recordings per cell): 0.1 chosen on seeds 777/778 (pooled azimuth RMSE
        13.8 -> 13.8 and 19.4 -> 17.8 deg; 0.02 and 0.05 rescued fewer), then held out on seeds
        779/780: 11.6 -> 11.0 and 12.7 -> 12.5 deg, no cell worse, a few recordings moved off
        a reflection (e.g. white noise RT60 0.6 s 10 dB 10.5 -> 7.5 deg); measured impulse
        responses (part 3): 3 of 1512 pair recordings changed, median error unchanged.
        The reasoning holds for a level pair (axis horizontal, as two ears are at any pan and
        tilt of hearsee's head); for a pair standing upright the floor's and ceiling's images
        arrive at LONGER lags and this rule can pick one of them: pass 0 there.
        A peak counts only where it stands out of the highest one's lobe (the correlation dips
        by :data:`FIRST_ARRIVAL_PROMINENCE` of the height between them; since 2026-12-07: at
        48 kHz a voice's wide main lobe carries ripples 2 samples from its top, which moved a
        third of free-field two-microphone voice summaries 2-4 samples off).
    source_in_plane : bool
        With a planar array of 3+ microphones, the joint whole-recording peak search
        (``joint``) steers only directions in the array plane instead of the whole sphere --
        for a source known to be at the array's height (the ``dim=2`` assumption of
        pyroomacoustics' DOA; use with ``localize_tdoa(in_plane=True)``). Floor and ceiling
        reflections then cannot win the search. Default False.
    min_peak_snr : float
        Detection threshold of a whole-recording estimate without redundant pairs (two
        microphones): besides its confidence, the averaged correlation's peak must stand this
        many robust standard deviations above the correlation's floor at lags no source can
        reach (:func:`_peak_snr`; 0 = no such test). With three or more microphones the pairs'
        closure decides instead. Two-microphone recordings, free field: of 300 noise-only
        recordings of 2 s the confidence alone let 20 through; with this test none of 800
        (2 s) and of 1200 (0.5, 1 and 4 s; at 5.0: 2 of the 1-s ones). Detected, 2 s, 40
        each: a white source at -10 dB 40 (before 40), at -15 dB 9 (before 23, some of them
        2 samples off), a male voice at 0 / -5 dB 40 / 34 (before 40 / 40), a female voice
        40 / 6 (before 40 / 37): the price of the test is the weakest voices. An estimate
        that only this test refused is kept in ``undetected_summary`` of the result.
    min_frame_peak_snr : float
        The same test for each frame's own estimate without redundant pairs (0 = off). Of
        100 two-microphone noise-only recordings (2 s) the confidence alone let 2.1 % of the
        frames through, whose peaks reached at most 4.2; of the frames a voice at 10 dB left
        valid (free field, 20 recordings each) 99.9 % (male) and 98.9 % (female) pass 4.5,
        at 0 dB (male) 72 %. The whole-recording estimate still averages every frame the
        confidence admits (its own test is ``min_peak_snr``): in reverberation the frames
        this test drops still carry part of the direct path.
    whole_recording : bool
        Compute the whole-recording estimate (default). ``False`` gives the per-frame results
        only (``summary_tdoa_s`` all NaN): what a stream needs for each batch of frames, at
        a fraction of the cost of the summary's direction search.
    band_vad : bool
        When the broadband frame energies look stationary (no frame inactive), decide the
        frames' activity again from their energy within ``band_hz`` (:func:`_band_activity`;
        default True; nothing changes without a band). White sensor noise outside a voice's
        band can hide its pauses from the broadband energy; without inactive frames there is no
        noise spectrum for ``snr_weight`` (nor a measured ``coherence_ratio``). Reconstruction
        choice, measured on held-out recordings of ``bench/doa.py`` (seeds 777 and 778, 16 per
        condition, both arrays): only 0 dB recordings changed; the azimuth RMSE fell in 14 of the
        18 conditions touched (three-mic anechoic: ARCTIC 0.71 -> 0.33 deg, male voice 1.73 ->
        0.49; two-mic anechoic ARCTIC 2.46 -> 0.70) and rose in 4 (two-mic RT60 0.6 s female
        voice 21.1 -> 25.7 deg); conditions at or below the best pyroomacoustics method 36 -> 41
        of 72 (the benchmark's own seed 0, run afterwards: 41 -> 45). A steady source's band
        energy is as stationary as its broadband energy, so it is left as before. The frame
        loop reuses the band spectra (no second transform) within
        :data:`SPECTRA_CACHE_BYTES`.
    chunk_frames : int
        Frames processed per vectorised block (bounds the memory of the transforms and
        correlations; the band spectra of every frame are kept up to
        :data:`SPECTRA_CACHE_BYTES`); ``progress(n)`` is called after each block with the
        number of frames done.
    active : array (n_frames,) of bool, optional
        The frames' activity decided by the caller: replaces the energy and band activity
        tests over ``x`` (``vad_db``, ``band_vad``), and the noise spectrum of ``snr_weight``
        is then taken from ``frame_noise_psd`` only. For a stream, whose batches of frames
        must not decide anything (:class:`hearsee.stream.pipeline.FrameActivity`). Default
        None: decided from ``x`` as described above.
    frame_noise_psd : array (n_frames, n_mics, band bins), optional
        With ``active``: each frame's noise power spectrum for ``snr_weight``, in units of
        ``|X|^2`` of the frames of ``x`` as given (Tukey-windowed frames less their means,
        zero-padded FFT; the band's bins), e.g. averaged over earlier noise-only frames; a row
        of NaN gives that frame the plain weighting (no noise reference yet). Scaled with
        ``x`` when the recording's level is normalised. None (with ``active``): no SNR
        weighting.
    causal_smoothing : bool
        SCOT, ROTH and ML average their spectral statistics over the ``smooth_frames`` frames
        *ending* at each frame (the first frame repeated before the start) instead of the
        frames centred on it: a stream prepends its earlier frames as context (inactive,
        ``active``) and so gets results that do not depend on where its batches end. Default
        False.
    empty_band_db : float or None
        Leave out of the GCC the band at the top of the spectrum that lies more than this many
        dB below the recording's loudest part in every bin (:func:`empty_top_band` of the
        frames' mean power; default :data:`EMPTY_BAND_DB`, 60): the empty band of a recording
        upsampled after it was made, which otherwise biases PHAT and ML (see ``band_hz``).
        ``TdoaFrames.band_hz`` says the band used. Recordings made at their rate, with any
        noise floor, keep every bin. None keeps every bin always (a stream does: its batches
        must not each decide on a band of their own). A band left with nothing but the empty
        part is a ConfigError.
    tonal_noise : bool
        Find stationary tonal noise on every microphone -- mains hum the wiring picks up, a
        motor's or a fan's whine (:func:`hearsee.audio.hum.tonal_bins`, on frames at least
        :data:`hearsee.audio.hum.TONAL_FRAME_MS` long whatever ``frame_ms``) -- and, where there
        is some, filter its lines out of the recording (:func:`hearsee.audio.hum.filter_lines`:
        a hum's every harmonic, zero-phase notches) and estimate from what remains, with a
        :class:`~hearsee.errors.TonalNoiseWarning` and ``TdoaFrames.tonal_lines_hz``. A hum
        3 dB louder than a voice turned a three-mic summary to a source overhead (identical on
        every channel, it is a source at TDOA 0). Not with ``active`` (a stream decides its
        frames itself). False: the recording as it is.

    Returns
    -------
    TdoaFrames
    """
    call = dict(locals())  # (the arguments, for the run on a recording without tonal noise)
    tonal_noise = true_or_false("tonal_noise", tonal_noise)
    arr = load_array(array)
    a = as_samples(x, finite=False)  # (finiteness: from the peak, below)
    peak = _peak_level(a)
    if not np.isfinite(peak):  # (as_samples' check and message)
        raise AudioInputError("recording contains NaN or infinite samples")
    if a.ndim != 2 or a.shape[0] != arr.n_mics:
        raise AudioInputError(
            f"recording has shape {a.shape}; array {arr.name!r} needs ({arr.n_mics}, n_samples) "
            "(one row per microphone)"
        )
    if frame_noise_psd is not None and active is None:
        raise ConfigError("frame_noise_psd needs active (the frames it was measured with)")
    fs = check_analysis_fs(fs)
    frame_len, hop = frame_geometry(fs, frame_ms, hop_ms)
    method = normalize_method(method)
    if reverb_method is not None:
        reverb_method = normalize_method(reverb_method)
    _check_options(refine, summary_frames, joint, min_peak_snr, min_frame_peak_snr, phat_beta,
                   onset_weight, snr_weight)
    first_arrival = finite_number("first_arrival", first_arrival, 0.0, 1.0)
    min_confidence = finite_number("min_confidence", min_confidence, 0.0)
    margin_samples = finite_number("margin_samples", margin_samples, 0.0)
    # (a negative smooth_frames sliced the statistics' halo from the wrong end; NaN thresholds
    # switched their tests off)
    smooth_frames = whole_number("smooth_frames", smooth_frames)
    chunk_frames = whole_number("chunk_frames", chunk_frames)
    summary_upsample = whole_number("summary_upsample", summary_upsample,
                                    hi=MAX_SUMMARY_UPSAMPLE)
    # (above ~3000 dB its power ratio overflowed: a builtin OverflowError)
    vad_db = finite_number("vad_db", vad_db, 0.0, MAX_VAD_DB)
    if progress is not None and not callable(progress):  # (called only after the work)
        raise ConfigError(f"progress must be a function of the frames done, or None; got "
                          f"{progress!r:.60}")
    reverb_coherence = finite_number("reverb_coherence", reverb_coherence, 0.0)
    prs = arr.checked_pairs(pairs)
    if joint == "steered":
        _check_steered(arr, source_in_plane, steer_range_m)
    elif joint == "auto" and steer_range_m is not None:
        finite_number("steer_range_m", steer_range_m, 0.0, lo_open=True)
    # (float32 fourth powers of the spectra overflow, tiny powers vanish; every test here is
    # scale-free)
    gain = 1.0  # (of the samples, for a given frame_noise_psd)
    if peak > MAX_UNSCALED_PEAK or 0 < peak < MIN_UNSCALED_PEAK:
        a = a / peak
        gain = 1.0 / peak
    # single precision from here on: twice as fast, and its ~1e-7 relative error is far below
    # any sensor noise
    a32 = a.astype(np.float32)
    frames = frame_signals(a32, frame_len, hop)  # (n_ch, F, L)
    n_frames = frames.shape[1]
    reach = arr.max_tdoa(prs) * fs  # the physical maximum (samples)
    max_lag = reach + float(margin_samples)
    if max_lag.max() >= frame_len // 2:
        raise ConfigError(
            f"frame of {frame_ms} ms is too short for the array's largest delay "
            f"({max_lag.max() / fs * 1e3:.2f} ms); use a longer --frame-ms{arr.units_hint()}"
        )
    # zero padding by twice the largest lag keeps the admissible lags free of circular wrap
    nfft = gcc_nfft(frame_len, float(max_lag.max()))
    n_bins = nfft // 2 + 1
    bins = np.flatnonzero(_band_mask(n_bins, nfft, fs, band_hz))
    main_lobe = _main_lobe(bins, nfft, fs, band_hz)
    if band_hz is not None:  # (the whole band is wide: nothing to say)
        _warn_aliasing(bins[0] * fs / nfft, bins[-1] * fs / nfft, float(reach.max()) / fs)
    if empty_band_db is not None:
        empty_band_db = finite_number("empty_band_db", empty_band_db, 0.0, lo_open=True)
    if isinstance(window, list):
        window = tuple(window)
    try:
        hash(window)  # (an array, or a tuple holding a list, was lru_cache's TypeError)
    except TypeError:
        raise ConfigError(f"window must be a scipy.signal.get_window name or tuple (e.g. "
                          f"'hann' or ('tukey', 0.25)), got a {type(window).__name__}") from None
    win = _window(window, frame_len)
    energy = _frame_energy(a32, frame_len, hop, n_frames)
    given = active is not None
    if not given:
        active, decided = _energy_vad(energy, vad_db)  # frame_activity's decision
    else:  # the caller's decision (a stream's, from its own history of frames)
        active, decided = _given_activity(active, n_frames), True
    # (single precision, as the spectra they weigh: a float64 weight made each block complex128)
    frame_w = _onset_weights(energy, onset_weight).astype(np.float32)
    I = np.array([p[0] for p in prs])
    J = np.array([p[1] for p in prs])
    n_pairs = len(prs)
    need_stats = method in ("scot", "roth", "ml") or (
        whole_recording and reverb_method in ("scot", "roth", "ml"))
    halo = ((int(smooth_frames) - 1 if causal_smoothing else int(smooth_frames) // 2)
            if need_stats else 0)

    k0, k1 = int(bins[0]), int(bins[-1]) + 1  # the band is one contiguous run of bins
    band_bins = np.arange(k0, k1)
    nb = k1 - k0
    # the band spectra of every frame, when they fit SPECTRA_CACHE_BYTES: one transform for
    # the band activity, the noise spectrum and the frame loop
    X_all = power_all = top = None
    chunk = max(int(chunk_frames), 1)
    # (the empty-band search's loudest frames, whole band, from the same transforms)
    loudest = _loudest_frames(energy) if empty_band_db is not None else None
    if band_vad and (k0 > 1 or k1 < n_bins - 1) and not decided:
        active, X_all, power_all, top = _band_activity(frames, win, nfft, k0, k1, active,
                                                       vad_db, chunk, loudest)
    elif _spectra_fit(arr.n_mics, n_frames, k1 - k0):
        X_all, power_all, _, top = _band_spectra(frames, win, nfft, k0, k1, chunk, loudest)
    cut = (_empty_band_cut(frames, win, nfft, fs, energy, empty_band_db, top)
           if empty_band_db is not None else None)
    if cut is not None and cut < k1:
        if cut <= k0:
            raise ConfigError(
                f"band_hz {band_hz}: the recording holds nothing there (its spectrum is "
                f"more than {empty_band_db:g} dB below its loudest part from about "
                f"{cut * fs / nfft:.0f} Hz up: upsampled from a lower rate?); choose a band "
                "below that")
        X_all = None if X_all is None else X_all[..., :cut - k0]
        power_all = None if power_all is None else power_all[..., :cut - k0]
        k1 = cut
        band_bins = np.arange(k0, k1)
        nb = k1 - k0
        main_lobe = _main_lobe(band_bins, nfft, fs, band_hz)
    if tonal_noise and not given:
        line, bin_hz = _band_tonal_lines(a32, fs, frame_len, window, nfft, k0, k1, power_all,
                                         frames, win, energy)
        if line is not None:  # filter the lines out of the recording and start again with it
            y, lines = hum.filter_lines(a, fs, hum.line_frequencies(a, fs, line, bin_hz),
                                        frame_ms)
            hum.warn_lines(lines)
            call.update(x=y, array=arr, tonal_noise=False)
            return replace(estimate_tdoas(**call), tonal_lines_hz=tuple(map(float, lines)))
    if frame_noise_psd is None:
        noise_psd = (_noise_spectrum(frames, active, win, nfft, k0, k1, power_all)
                     if snr_weight and not given else None)
    else:  # per frame, NaN rows without a reference: see _snr_coherence's use below
        noise_psd = (_given_noise(frame_noise_psd, (n_frames, arr.n_mics, k1 - k0), gain)
                     if snr_weight else None)
    # (one spectrum for the whole-recording reverberation test: the frames' mean)
    noise_ref = noise_psd if noise_psd is None or noise_psd.ndim == 2 else _mean_rows(noise_psd)

    redundant = pair_closure_projector(tuple(prs), arr.n_mics) is not None  # a closed cycle
    frame_cfar = not redundant and min_frame_peak_snr > 0
    noise_profile = _window_noise_profile(window, frame_len, nfft) if not redundant else None

    def corr(Pb: NDArray) -> NDArray:
        full = np.empty(Pb.shape[:-1] + (n_bins,), dtype=Pb.dtype)
        full[..., :k0] = 0  # (only the bins outside the band: no pass over the whole array)
        full[..., k1:] = 0
        full[..., k0:k1] = Pb
        return sfft.irfft(full, nfft, axis=-1)

    tdoa = np.full((n_frames, n_pairs), np.nan)
    conf = np.zeros((n_frames, n_pairs))
    acc = np.zeros((n_pairs, nb), dtype=complex)
    n_acc = 0
    acc_active = np.zeros((n_pairs, nb), dtype=complex)
    n_active = 0
    # second weighting for reverberant recordings, and the coherence statistics deciding it
    use_rev = reverb_method is not None and whole_recording
    coherence_gain = float("nan")
    if use_rev and noise_ref is None:  # no noise reference: decide by the frame-length test
        # on the widest pair (a diffuse field decorrelates it most); all pairs together
        # separated free field from rooms no better (white noise, seed 901, 8 per cell: free
        # field <= 0.998 either way, rooms >= 1.03)
        w = int(np.argmax(np.linalg.norm(arr.positions[I] - arr.positions[J], axis=1)))
        coherence_gain = _coherence_gain(a32[[I[w], J[w]]], frame_len, fs,
                                         (k0 * fs / nfft, (k1 - 1) * fs / nfft))
        use_rev = coherence_gain > REVERB_COHERENCE_GAIN
    rev_decided = use_rev and noise_ref is None
    acc2 = np.zeros((n_pairs, nb), dtype=complex)
    acc2_active = np.zeros((n_pairs, nb), dtype=complex)
    s_cross = np.zeros((n_pairs, nb), dtype=complex)
    s_auto = np.zeros((arr.n_mics, nb))
    for s0 in range(0, n_frames, chunk):
        s1 = min(s0 + chunk, n_frames)
        h0, h1 = max(s0 - halo, 0), min(s1 + halo, n_frames)
        # -> (F', n_ch, band bins)
        X, power = (np.moveaxis(a, 0, 1) for a in (
            (X_all[:, h0:h1], power_all[:, h0:h1]) if X_all is not None
            else _spectra_power(frames[:, h0:h1, :], win, nfft, k0, k1)))
        G = X[:, I, :] * np.conj(X[:, J, :])  # (F', P, band bins)
        stats = (_spectral_densities(power, G, I, J, smooth_frames, causal_smoothing)
                 if need_stats
                 else (None,) * 3)
        W = gcc_weighting(method, G, *stats)
        if phat_beta != 1.0 and method in ("phat", "ml"):
            W = W * np.abs(G) ** (1.0 - float(phat_beta))
        if noise_psd is not None:
            if noise_psd.ndim == 2:
                coh = _snr_coherence(power, noise_psd, I, J, snr_weight == "ml")
            else:  # each frame's own noise spectrum; a NaN one: the plain weighting
                coh = np.nan_to_num(_snr_coherence(power, noise_psd[h0:h1], I, J,
                                                   snr_weight == "ml"), nan=1.0)
            W = W * coh
        sl = slice(s0 - h0, s0 - h0 + (s1 - s0))
        P = G[sl] * W[sl].astype(np.float32, copy=False)
        act = active[s0:s1]
        Pa = P if act.all() else P[act]  # only frames with a source get a correlation
        lag = np.zeros((s1 - s0, n_pairs))
        c = np.zeros((s1 - s0, n_pairs))  # (an inactive frame has confidence 0)
        if len(Pa):
            r = corr(Pa)
            lag[act], c[act] = _peaks(r, Pa, nfft, max_lag, refine, main_lobe, band_bins,
                                      reach=reach)
        ok = act & np.all(c >= min_confidence, axis=1)
        ok_conf = ok.copy()  # the summary averages these; it has its own detection test
        if frame_cfar and ok.any():  # one independent pair: no closure to test, so CFAR
            ok[ok] = np.all(_peak_snr(r[ok[act]], lag[ok], max_lag, main_lobe, noise_profile)
                            >= min_frame_peak_snr, axis=-1)
        tdoa[s0:s1] = np.where(ok[:, None], lag / fs, np.nan)
        conf[s0:s1] = c
        # normalise each frame's weighted spectrum so that every frame counts equally
        if whole_recording and act.any():
            n_active += int(act.sum())
            okk = ok_conf[act]
            n_acc += int(okk.sum())
            onset = frame_w[s0:s1][act][:, None, None] if onset_weight else None
            if not rev_decided:  # (else the summary is reverb_method's: skip this one)
                # (with SNR weights, they already say how much each frame and bin counts)
                Pn = Pa if noise_psd is not None else _unit_frames(Pa)
                if onset is not None:  # (in place: Pa is needed no more)
                    Pn *= onset
                acc_active += np.sum(Pn, axis=0)
                if okk.any():
                    acc += np.sum(Pn[okk], axis=0)
            if use_rev:
                ia = np.flatnonzero(act) + (s0 - h0)  # active frames, chunk indices
                Ga = G[ia]
                W2 = gcc_weighting(reverb_method, Ga, *(
                    None if A is None or reverb_method in ("phat", "cc") else A[ia]
                    for A in stats))
                if noise_ref is not None:  # SNR weights, and the statistics of the test
                    s_cross += np.sum(Ga, axis=0)
                    s_auto += np.sum(power[ia], axis=0)
                    P2 = Ga * (W2 * coh[ia]).astype(np.float32, copy=False)
                else:  # every frame counts equally, as in the first weighting's sum
                    P2 = _unit_frames(Ga * W2.astype(np.float32, copy=False))
                if onset is not None:
                    P2 *= onset
                acc2_active += np.sum(P2, axis=0)
                if okk.any():
                    acc2 += np.sum(P2[okk], axis=0)
        if progress is not None:
            progress(s1 - s0)
    valid = ~np.isnan(tdoa).any(axis=1)
    coherence_ratio = float("nan")
    summary_method = method
    reverberant = False  # (judged only with a reverb_method)
    if use_rev and n_active:
        reverberant = True  # decided above by the frame-length test when there is no noise
        if noise_ref is not None:
            coherence_ratio = _coherence_ratio(s_cross, s_auto, n_active, noise_ref, I, J)
            reverberant = coherence_ratio < float(reverb_coherence)
        if reverberant:
            acc, acc_active, summary_method = acc2, acc2_active, reverb_method
    summary, summary_conf = np.full(n_pairs, np.nan), np.zeros(n_pairs)
    inverted: tuple[int, ...] = ()
    dead: tuple[int, ...] = ()
    offsets: NDArray | None = None
    need = min_confidence
    fallback = False
    detection_refused = False  # only the peak-SNR test (min_peak_snr) refused the summary
    undetected: tuple[NDArray, NDArray] | None = None
    if summary_frames == "active" and n_active:
        acc, n_acc = acc_active, n_active
    elif n_acc < _MIN_SUMMARY_FRAMES and n_active > n_acc:
        # too few confident frames (low SNR, strong reverberation): a weak but steady source
        # still builds up a peak in the average over all frames with energy
        acc, n_acc = acc_active, n_active
        fallback = True
    if n_acc and whole_recording:
        r_sum = corr(acc)  # the averaged correlation, (n_pairs, nfft)
        # the exact peak: the closure test needs it; one pair with upsampling re-estimates it
        # below and takes only its sample (CFAR) from here
        fine = redundant or summary_upsample <= 1
        lag, c = _peaks(r_sum[None], acc[None], nfft, max_lag, "interp" if fine else "parabolic",
                        main_lobe, band_bins, reach=reach)
        own_peaks, own_conf = lag[0], c[0]  # (each pair's own: the dead-microphone test's)
        resid = closure_rms(lag[0], prs, arr.n_mics)
        if resid is not None:
            # redundant pairs (>= 3 microphones). Detection: the pairs' own peaks of
            # uncorrelated noise are random and violate t_ij + t_jk = t_ik; a source's do not.
            # Estimate: the peaks chosen jointly, consistent with one direction (a reflection
            # that tops one pair's correlation then loses to the direct path)
            # Independent peaks that violate the closure (reverberation) need clearer peaks
            # (noise-only recordings reached a minimum pair confidence of 0.74 in 40 trials,
            # reverberant voices at 20 dB at least 1.5).
            need_c = min_confidence if resid <= _CLOSURE_TOL_SAMPLES else (
                _FALLBACK_CONFIDENCE * min_confidence)
            ok = np.all(c[0] >= need_c)
            kind = array_geometry(arr).kind
            steer: float | None | bool = steer_range_m if joint == "steered" else False
            if (joint == "auto" and reverberant and source_in_plane
                    and arr.n_mics >= AUTO_STEERED_MIN_MICS and kind == "planar"):
                steer = IN_PLANE_RANGE_M if steer_range_m is None else steer_range_m
            own = lag[0]
            lag = _joint_peaks(acc, band_bins, nfft, arr.positions, prs, arr.speed_of_sound,
                               fs, max_lag, coherent=joint == "coherent",
                               in_plane=bool(source_in_plane), steer_range_m=steer,
                               climb=kind == "volume")[None]
            # (not for the in-plane search: an elevated reflection's peaks close too, and
            # keeping them out is its purpose; a near source there stays a limitation)
            if steer is False and not source_in_plane:
                lag = _closed_own_peaks(own, lag[0], prs, arr.n_mics, acc, band_bins,
                                        nfft)[None]
        else:
            # one independent pair: only the confidence can tell (noise-only recordings reach
            # ~1.25 in 40 trials, a -15 dB white source 0.8-2.4)
            ok = np.all(c[0] >= (_FALLBACK_CONFIDENCE * need if fallback else need))
            if ok and min_peak_snr > 0:
                ok = bool(np.all(_peak_snr(r_sum, lag[0], max_lag, main_lobe, noise_profile)
                                 >= min_peak_snr))
                detection_refused = not ok
            if summary_upsample > 1:
                lag = _fine_peaks(acc, band_bins, nfft, max_lag, int(summary_upsample),
                                  first_arrival, reach)[None]
        if ok:
            summary, summary_conf = lag[0] / fs, c[0]
        elif detection_refused:  # (kept for TdoaFrames.without_detection_test)
            undetected = (lag[0] / fs, c[0])
        offsets = _warn_desync(r_sum, max_lag, main_lobe, prs, fs)
        if not np.isfinite(offsets).any():  # (a pair out of sync has no polarity to read: a
            # voice's trough within its bound named a microphone as inverted)
            inverted = _warn_inverted(r_sum, max_lag, main_lobe, prs, arr.n_mics)
            if not inverted:  # (an inverted microphone's pairs peak nowhere either)
                dead = _warn_dead(r_sum, own_peaks, own_conf, max_lag, main_lobe, prs,
                                  arr.n_mics,
                                  lambda: _window_noise_profile(window, frame_len, nfft))
    t = (np.arange(n_frames) * hop + frame_len / 2.0) / fs
    return TdoaFrames(t, tdoa, conf, valid, prs, summary, summary_conf, max_lag / fs, fs,
                      acc / max(n_acc, 1) if n_acc else None, band_bins, nfft,
                      coherence_ratio, summary_method, coherence_gain,
                      (k0 * fs / nfft, (k1 - 1) * fs / nfft), inverted, offsets,
                      dead_mics=dead, undetected_summary=undetected)
