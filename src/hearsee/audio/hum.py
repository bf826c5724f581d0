"""Stationary tonal noise on every microphone: find it and take it out of a recording.

Mains hum that the wiring picks up (50 or 60 Hz and its harmonics, identical on every channel),
a motor's or a fan's whine: a line that lasts the whole recording is one coherent source all
along -- electrical pickup is a source at TDOA 0 on every pair -- and GCC-PHAT gives each bin
the same weight whatever its level, so a comb of them outvotes a voice. A 60-Hz buzz of 39
harmonics 3 dB louder than a male voice turned a three-mic summary to a source overhead
(elevation 85 deg, azimuth -83 instead of 56): it also fills the voice's pauses, so the energy
activity test finds no quiet frame and the SNR weighting has no noise spectrum. Leaving the
lines' bins out of the GCC was not enough -- the analysis window spreads every line over its
neighbours, which stay coherent at lag 0 -- so the lines are filtered out of the recording
itself (:func:`remove_lines`) before the GCC sees it.

Reconstruction (not in the thesis): detection after the minimum statistics of noise power
estimation (Martin 2001, "Noise power spectral density estimation based on optimal smoothing
and minimum statistics", IEEE Trans. Speech Audio Process. 9(5)); removal by second-order IIR
notches (``scipy.signal.iirnotch``), run forward and backward so that every channel is
filtered alike with zero phase (the TDOAs of what remains are untouched).

Units: Hz for frequencies and sample rates.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.fft as sfft
import scipy.signal as ss
from numpy.typing import ArrayLike, NDArray

from hearsee.audio.signals import as_samples, check_fs
from hearsee.config import finite_number, real_entries, whole_number
from hearsee.errors import AudioInputError, ConfigError, TonalNoiseWarning

__all__ = [
    "COMB_SHARE",
    "COMB_TOL_HZ",
    "HARMONIC_PROMINENCE",
    "HARMONIC_TOP_HZ",
    "LINE_SPECTRUM_S",
    "LineFilter",
    "MAX_ROUNDS",
    "NOTCH_BANDWIDTH_HZ",
    "SETTLE_S",
    "TONAL_FRAME_MS",
    "TONAL_MIN_FRAMES",
    "TONAL_MIN_HZ",
    "TONAL_STATIONARITY",
    "check_lines",
    "filter_lines",
    "find_lines",
    "line_frequencies",
    "remove_lines",
    "tonal_bins",
    "warn_lines",
]

#: A frequency bin holds a line when, on every microphone, its power in no frame falls below
#: this fraction of its mean over the frames (:func:`tonal_bins`). A line at least as strong as
#: whatever else shares its bin does that; noise or a voice does not (its power in a bin swings
#: from frame to frame): 432 simulated recordings (two-mic, three-mic, respeaker-6; white noise,
#: synthetic and ARCTIC voices; free field, RT60 0.3 / 0.6 s; SNR 0-20 dB; 1.5-6 s; 64 ms
#: frames) reached at most 0.13, the bundled example 0.03, the real 'alexa' recordings 0.11
TONAL_STATIONARITY = 0.5
#: ... tested only with at least this many frames that are not digital silence (~1.3 s at a 32
#: ms hop): over fewer, a noise bin's smallest power is too often near its mean
TONAL_MIN_FRAMES = 40
#: ... and only above this frequency (Hz): the mains' fundamental is 50 or 60 Hz
TONAL_MIN_HZ = 40.0
#: ... on frames at least this long (ms; the length :data:`TONAL_STATIONARITY` was measured
#: with), whatever frame the analysis itself uses: at 16 ms a bin is ~63 Hz wide, a 60-Hz
#: line shares it with a voice's lowest harmonics and swings with them, and a hum 3 dB above a
#: male voice was found on none of three arrays (two-mic, three-mic, respeaker-4; the summary
#: TDOAs 2.6-6.4 samples off), where 32- and 64-ms frames found it
TONAL_FRAME_MS = 64.0
#: Lines within this many Hz of the multiples of one fundamental are a harmonic comb
#: (:func:`line_frequencies`): every harmonic up to the highest line found is removed, also
#: those a voice's harmonics hid from the test
COMB_TOL_HZ = 1.5
#: A multiple of a found hum's fundamental is removed too where the recording's spectrum (as
#: :func:`line_frequencies` reads it) peaks this many times above its median within half a
#: fundamental around it: a steady line is a few bins wide there, a voice's harmonics glide and
#: smear, noise stays near its median (10x found a false line in white noise, ~1 in 150
#: harmonics; the hum's hidden harmonics stood far higher). A run of :func:`tonal_bins`' line
#: bins is a line only where that spectrum peaks this many times above its median over the
#: run (and a bin each side) too: a strong line's leakage through the frames' Tukey window
#: holds steady in bins far from it, and their peak was noise (a 20-Hz line 37 dB above white
#: noise gave 'lines' at 32.9, 109.5 and 162.3 Hz, peaking 7-10x above their median; the
#: 1953 runs of bench/hum.py's recordings, with voices, peaked 659x or more)
HARMONIC_PROMINENCE = 100.0
#: ... up to this frequency (Hz)
HARMONIC_TOP_HZ = 8000.0
#: ... when at least this share of them (and three) do; the others are removed as well (a
#: voice's harmonic beside a hum line can move a line's peak off the comb)
COMB_SHARE = 2.0 / 3.0
#: :func:`line_frequencies` reads the lines' frequencies off the spectrum of a recording's first
#: this many seconds (~0.02 Hz resolution; a whole hour would be a 2**28-point transform)
LINE_SPECTRUM_S = 30.0
#: :func:`remove_lines` extends a recording by this many seconds at each end for its notches to
#: settle in (the 2-Hz notches' hum residue is ~40 dB down after 0.7 s)
SETTLE_S = 1.0
#: -3 dB width of each notch (Hz): ~40 lines of mains hum take ~80 Hz out of a voice's band
NOTCH_BANDWIDTH_HZ = 2.0


def tonal_bins(power: ArrayLike, bin_hz: ArrayLike) -> NDArray:
    """The frequency bins that hold stationary tonal noise on every microphone.

    A bin whose power on every microphone stays, in every frame, at least
    :data:`TONAL_STATIONARITY` of its mean over the frames holds a line stronger than anything
    else there; a voice or noise in a bin swings far below its mean in some frame.

    Parameters
    ----------
    power : array (n_ch, n_frames, n_bins)
        Each frame's power spectrum ``|X|^2`` per microphone (frames that are not digital
        silence).
    bin_hz : array (n_bins,)
        The bins' frequencies, Hz, ascending; bins below :data:`TONAL_MIN_HZ` are never
        lines.

    Returns
    -------
    array (n_bins,) of bool
        True at the lines' bins (the window's main lobe around each line too); all False with
        fewer than :data:`TONAL_MIN_FRAMES` frames.
    """
    p = np.asarray(power)
    f = np.asarray(bin_hz, dtype=float)
    if p.ndim != 3 or f.shape != p.shape[2:]:
        raise ConfigError(f"tonal_bins needs power (n_ch, n_frames, n_bins) and bin_hz "
                          f"(n_bins,), got {p.shape} and {f.shape}")
    line = np.zeros(p.shape[2], dtype=bool)
    n_frames = p.shape[1]
    if n_frames < TONAL_MIN_FRAMES:
        return line
    start = int(f.searchsorted(TONAL_MIN_HZ))  # (ascending)
    cand = None
    for ch in p:  # (channel by channel, on the bins still in question: the first channel
        # usually leaves none, and the others cost nothing then)
        q = ch[:, start:] if cand is None else ch[:, cand]
        # smallest >= fraction x mean, as min x F > fraction x sum (a bin all zero: no line)
        keep = q.min(axis=0) * n_frames > TONAL_STATIONARITY * q.sum(axis=0)
        if not keep.any():
            return line
        cand = keep.nonzero()[0] + start if cand is None else cand[keep]
    line[cand] = True
    return line


def _runs(mask: NDArray) -> list[tuple[int, int]]:
    """(start, stop) of each run of True in a 1-D bool array."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], mask.astype(np.int8), [0]))))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


def line_frequencies(x: ArrayLike, fs: float, line: ArrayLike, bin_hz: ArrayLike) -> NDArray:
    """The frequencies (Hz) to remove from the recording ``x`` (n_ch, n) for the line bins
    ``line`` (bool, as :func:`tonal_bins`) at ``bin_hz``.

    Each run of line bins is one line, its frequency the peak of the channels' summed
    spectrum of the recording's first :data:`LINE_SPECTRUM_S` seconds (Hann window, 2x zero
    padding: ~fs / 2n resolution) within a bin of the run, refined by a parabola through the log
    power; a run where that peak stands less than :data:`HARMONIC_PROMINENCE` times above the
    spectrum's median there is no line (a stronger line's leakage). When three or more lines,
    and :data:`COMB_SHARE` of them, lie within :data:`COMB_TOL_HZ` of the multiples of one
    fundamental (the lowest line, or it over a whole number, :func:`_divided`), they are a
    harmonic comb -- mains hum --
    and every multiple of the fundamental fitted to them (least squares through 0) up to the
    highest line is returned, with the lines off the comb. Then every multiple of the fundamental
    (the comb's, else the lowest line's or, when the lines are its multiples, it over a
    whole number)
    where that spectrum peaks :data:`HARMONIC_PROMINENCE` times above its surroundings is
    added: a hum's harmonics under a voice's, which the test of :func:`tonal_bins` misses.
    """
    a = np.asarray(x, dtype=float)[..., :int(LINE_SPECTRUM_S * fs)]
    f = np.asarray(bin_hz, dtype=float)
    runs = _runs(np.asarray(line, dtype=bool))
    if not runs:
        return np.zeros(0)
    n = a.shape[-1]
    nfft = sfft.next_fast_len(2 * n, real=True)
    spec = np.abs(sfft.rfft(a.sum(axis=0) * np.hanning(n), nfft)) ** 2
    df = fs / nfft
    step = f[1] - f[0] if len(f) > 1 else fs
    lines = []
    for lo, hi in runs:
        # within a bin of the run's ends: a line between two bins may pass the test on the
        # farther one only (the nearer one's power swings with a neighbouring line's leakage),
        # up to a bin from it; half a bin took a noise peak beside the line for it (the 600-Hz
        # harmonic of a 60-Hz hum, found at bin 609.4 Hz only, was a line at 611.9 Hz)
        k0 = max(int(np.floor((f[lo] - step) / df)), 1)
        k1 = min(int(np.ceil((f[hi - 1] + step) / df)), len(spec) - 2)
        k = k0 + int(np.argmax(spec[k0:k1 + 1]))
        if spec[k] >= HARMONIC_PROMINENCE * np.median(spec[k0:k1 + 1]):
            lines.append(_peak_hz(spec, k, df))
    if not lines:
        return np.zeros(0)
    lines_a = np.unique(lines)  # (two runs a bin apart find the same line)
    comb = _comb(lines_a)
    lines_a = lines_a if comb is None else comb
    # (a hum's harmonics that a voice hid from the test, or beyond the highest)
    more = _apart(_prominent_harmonics(spec, df, _fundamental(lines_a), fs), lines_a)
    return np.sort(np.concatenate((lines_a, more))) if more.size else lines_a


def _on_comb(lines: NDArray, f0: float) -> NDArray:
    """Which ``lines`` (Hz) lie within :data:`COMB_TOL_HZ` of a multiple of ``f0``."""
    return np.abs(lines - np.round(lines / f0) * f0) <= COMB_TOL_HZ


def _fit_fundamental(lines: NDArray, f0: float) -> float:
    """The fundamental (Hz) near ``f0`` that fits ``lines``, each a multiple of it, best
    (least squares through 0)."""
    k = np.round(lines / f0)
    return float(np.sum(k * lines) / np.sum(k * k))


def _apart(cand: NDArray, known: NDArray) -> NDArray:
    """The lines of ``cand`` (Hz) farther than :data:`COMB_TOL_HZ` from every one of ``known``."""
    return cand[np.min(np.abs(cand[:, None] - known[None]), axis=1, initial=np.inf)
                > COMB_TOL_HZ]


def _peak_hz(spec: NDArray, k: int, df: float) -> float:
    """The frequency (Hz) of the peak of ``spec`` (bins ``df`` Hz apart) at bin ``k``: a
    parabola through the log power of it and its neighbours."""
    if not 0 < k < len(spec) - 1:
        return k * df
    la, lb, lc = np.log(spec[k - 1:k + 2] + 1e-300)
    den = la - 2 * lb + lc
    return (k + (0.5 * (la - lc) / den if den < 0 else 0.0)) * df


#: The mains' fundamentals (Hz): a comb's fundamental may be its lowest line over any whole
#: number only near these (within :data:`COMB_TOL_HZ`), else over 1-4 (:func:`_divided`)
MAINS_HZ = (50.0, 60.0)


def _divided(lowest: float, first: int = 1) -> list[float]:
    """The candidate fundamentals (Hz) of lines whose lowest is ``lowest``: it over 1-4 from
    ``first``, and it over any larger whole number that lands within :data:`COMB_TOL_HZ` of
    the mains (:data:`MAINS_HZ`) -- a hum whose harmonics below 1.9 kHz a voice hid from
    :func:`tonal_bins` (32-ms frames, 60 Hz at 3 dB) showed 1920, 2160, 2220, ..., 2460 Hz,
    no comb over 1-4, and the rest of the hum left a three-mic summary 173 deg off (until
    2026-12-07); any whole number took 3-7 % of random sets of three or four lines in 200-3000
    Hz for a comb (0.0-0.2 % over 1-4), and notched every multiple of a 40-Hz fundamental --
    none below :data:`TONAL_MIN_HZ`."""
    out = []
    for m in range(first, int(lowest // TONAL_MIN_HZ) + 1):
        g = lowest / m
        if m <= 4 or min(abs(g - f) for f in MAINS_HZ) <= COMB_TOL_HZ:
            out.append(g)
    return out


def _fundamental(lines: NDArray) -> float:
    """The fundamental (Hz) of ``lines`` (ascending): the lowest line, or the lowest over a
    whole number (:func:`_divided`: the largest such fundamental, not below
    :data:`TONAL_MIN_HZ`) when all of them are its multiples within :data:`COMB_TOL_HZ` (100
    and 150 Hz: 50 Hz; 1920 and 2160 Hz: 60 Hz)."""
    f0 = float(lines[0])
    for g in _divided(float(lines[0]), 2):
        if len(lines) > 1 and _on_comb(lines, g).all() and not _on_comb(lines, f0).all():
            f0 = g
    return f0


def _prominent_harmonics(spec: NDArray, df: float, f0: float, fs: float) -> NDArray:
    """The multiples of ``f0`` (Hz) below fs / 2 and :data:`HARMONIC_TOP_HZ` where the power
    spectrum ``spec`` (bins ``df`` Hz apart) peaks :data:`HARMONIC_PROMINENCE` times above its
    median within +-f0 / 2 (the line's own +-1 Hz left out): each the peak's frequency."""
    top = min(fs / 2 - f0 / 2, HARMONIC_TOP_HZ)
    out = []
    for k in range(1, int(top // f0) + 1):
        c = k * f0
        lo, hi = int((c - f0 / 2) / df), min(int((c + f0 / 2) / df) + 1, len(spec))
        seg = spec[lo:hi]
        f = (lo + np.arange(seg.size)) * df
        near = np.abs(f - c) <= max(1.0, 3 * df)
        if not near.any() or near.all():
            continue
        i = int(np.flatnonzero(near)[np.argmax(seg[near])])
        if seg[i] >= HARMONIC_PROMINENCE * np.median(seg[np.abs(f - c) > 1.0]):
            out.append(_peak_hz(spec, lo + i, df))
    return np.array(out)


def _comb(lines: NDArray) -> NDArray | None:
    """Every multiple of the fundamental of ``lines`` (Hz) up to the highest, with the lines
    off the comb, or None when they are not a harmonic comb (:func:`line_frequencies`). The
    fundamental is the lowest line over a whole number (:func:`_divided`), the largest that
    fits."""
    if len(lines) < 3:
        return None
    for f0 in _divided(float(lines[0])):
        on = _on_comb(lines, f0)
        if on.sum() >= 3 and on.sum() >= COMB_SHARE * len(lines):
            f0 = _fit_fundamental(lines[on], f0)
            comb = f0 * np.arange(1, int(np.round(lines[-1] / f0)) + 1)
            return np.sort(np.concatenate((comb, _apart(lines[~on], comb))))
    return None


def _recording(x: ArrayLike, fs: float, *, two_d: bool = False) -> tuple[NDArray, float]:
    """The checked recording (samples on the last axis; (n_ch, n) with ``two_d``) and sample
    rate (Hz) of the public functions here: finite real samples, at least one, and a rate
    :func:`hearsee.audio.signals.check_fs` takes; AudioInputError else (one NaN sample made a
    whole channel NaN, silently)."""
    a = as_samples(x)
    if (two_d and a.ndim != 2) or a.ndim == 0 or a.shape[-1] == 0:
        shape = "(n_channels, n_samples)" if two_d else "samples along its last axis"
        raise AudioInputError(f"recording must be {shape} with at least one sample, got "
                              f"shape {a.shape}")
    return a, check_fs(fs)


def _bandwidth(bandwidth_hz: float) -> float:
    """A notch's -3 dB bandwidth, Hz: a finite number > 0 (ConfigError else)."""
    return finite_number("bandwidth_hz", bandwidth_hz, 0.0, lo_open=True)


def find_lines(x: ArrayLike, fs: float, frame_ms: float = 64.0) -> NDArray:
    """The lines (Hz) of stationary tonal noise on every channel of the recording ``x``
    (n_ch, n): :func:`tonal_bins` of its frames (``frame_ms`` long but at least
    :data:`TONAL_FRAME_MS` -- ``frame_ms`` itself where those would be fewer than
    :data:`TONAL_MIN_FRAMES` --, every half frame, Tukey window with 25 % tapers as
    :func:`hearsee.audio.tdoa.estimate_tdoas`'; frames silent on every channel left out), then
    :func:`line_frequencies`. Empty when there is none (also for a recording with fewer than
    :data:`TONAL_MIN_FRAMES` such frames). For analyses that do not go through
    ``estimate_tdoas``, which finds them in its own spectra. A recording that is no finite
    (n_ch, n) array of samples, or a bad rate, is an AudioInputError; ``frame_ms`` must be a
    finite number > 0 (ConfigError)."""
    a, fs = _recording(x, fs, two_d=True)
    frame_ms = finite_number("frame_ms", frame_ms, 0.0, lo_open=True)
    for ms in dict.fromkeys((max(frame_ms, TONAL_FRAME_MS), frame_ms)):
        n = max(int(round(ms * 1e-3 * fs)), 2)
        if a.shape[1] < n:
            continue
        f, _, z = ss.stft(a, fs, window=("tukey", 0.25), nperseg=n, noverlap=n - n // 2,
                          boundary=None, padded=False, detrend="constant", axis=-1)
        power = np.moveaxis(np.abs(z) ** 2, -1, 1)  # (n_ch, frames, bins)
        sounding = np.any(power.sum(axis=2) > 0, axis=0)
        if np.count_nonzero(sounding) >= TONAL_MIN_FRAMES:
            line = tonal_bins(power[:, sounding], f)
            return line_frequencies(a, fs, line, f) if line.any() else np.zeros(0)
    return np.zeros(0)


def warn_lines(lines: NDArray, stacklevel: int = 3) -> None:
    """A :class:`~hearsee.errors.TonalNoiseWarning` naming the lines removed (Hz): a harmonic
    comb by its fundamental and highest harmonic. ``stacklevel`` 3: the caller of the
    function that calls this one."""
    on = _on_comb(lines, lines[0])
    if on.sum() >= 3:  # (a harmonic comb: line_frequencies returns it whole)
        off = int(np.count_nonzero(~on))
        what = (f"{lines[0]:.1f} Hz and its harmonics up to {lines[on][-1]:.0f} Hz"
                + (f" (and {off} other line{'s' * (off > 1)})" if off else ""))
    else:
        what = ", ".join(f"{f:.0f}" for f in lines[:6]) + (", ..." * (len(lines) > 6)) + " Hz"
    warnings.warn(f"stationary tonal noise on every microphone at {what} (mains hum picked up "
                  "by the wiring, a motor's or a fan's whine?): filtered out before the TDOAs",
                  TonalNoiseWarning, stacklevel=stacklevel)


def _notch_sos(lines_hz: ArrayLike, fs: float, bandwidth_hz: float) -> NDArray | None:
    """Second-order sections of one notch ``bandwidth_hz`` wide at each line (Hz) below
    fs / 2 - ``bandwidth_hz``; None without any."""
    hz = [float(v) for v in np.atleast_1d(np.asarray(lines_hz, dtype=float))
          if 0 < v < fs / 2 - bandwidth_hz]
    if not hz:
        return None
    return np.vstack([ss.tf2sos(*ss.iirnotch(v, v / bandwidth_hz, fs)) for v in hz])


def remove_lines(x: ArrayLike, fs: float, lines_hz: ArrayLike,
                 bandwidth_hz: float = NOTCH_BANDWIDTH_HZ) -> NDArray:
    """``x`` (n_ch, n) with the lines at ``lines_hz`` filtered out of every channel alike: a
    second-order notch ``bandwidth_hz`` wide (-3 dB) at each, forward and backward (zero
    phase: the TDOAs of everything else are untouched). Lines within ``bandwidth_hz`` of
    fs / 2 or above it are skipped (a notch there has a pole on the unit circle to rounding:
    at 16 kHz a 7999-Hz line stays; found by a review helper).

    A notch takes ~1 / (pi ``bandwidth_hz``) s (0.16 s at 2 Hz) to settle, ~0.7 s to take a
    line 40 dB down, so the recording's first and last second kept much of the hum (-9 dB in
    the first 0.1 s). When most lines are harmonics of one fundamental the hum repeats every
    period, and the recording is extended at both ends by copies of its first and last
    periods (a whole number of periods within 0.05 sample) before it is filtered: the notches
    settle in the extension, which is cut off again (the hum's residue in the first 0.1 s of
    a 50-Hz comb: -9 -> about -35 dB).

    The recording must hold finite samples, at least one (AudioInputError), ``lines_hz``
    numbers > 0 (:func:`check_lines`) and ``bandwidth_hz`` a number > 0 (ConfigError).
    """
    a, fs = _recording(x, fs)
    lines = np.array(check_lines(lines_hz), dtype=float)
    sos = _notch_sos(lines, fs, _bandwidth(bandwidth_hz))
    if sos is None:
        return a.copy()
    period = _hum_period(np.sort(lines), fs)
    pad = int(round(SETTLE_S * fs))
    if period is None or period > a.shape[-1]:
        # (scipy's default padding, 3 (2 sections + 1) samples, refused a shorter recording)
        return ss.sosfiltfilt(sos, a, axis=-1,
                              padlen=min(3 * (2 * sos.shape[0] + 1), a.shape[-1] - 1))
    n = a.shape[-1]
    s = np.arange(1, pad + 1)
    before = (-s) % period  # (copies of the first period, backwards)
    after = n - period + (np.arange(pad) % period)  # (of the last period, forwards)
    ext = np.concatenate((a[..., before[::-1]], a, a[..., after]), axis=-1)
    return ss.sosfiltfilt(sos, ext, axis=-1, padlen=0)[..., pad:pad + n]


def _hum_period(lines: NDArray, fs: float) -> int | None:
    """A whole number of samples (<= :data:`SETTLE_S`) that is a whole number of periods of the
    fundamental of ``lines`` (Hz) within 0.05 sample, when :data:`COMB_SHARE` of them are its
    harmonics within :data:`COMB_TOL_HZ`; else None."""
    if not lines.size:
        return None
    f0 = _fundamental(lines)
    on = _on_comb(lines, f0)
    if on.sum() < COMB_SHARE * len(lines):
        return None
    f0 = _fit_fundamental(lines[on], f0)
    p = fs / f0
    for m in range(1, int(SETTLE_S * f0) + 1):
        if abs(m * p - round(m * p)) <= 0.05:
            return int(round(m * p))
    return None


def check_lines(lines_hz: ArrayLike) -> tuple[float, ...]:
    """Line frequencies (Hz) as a tuple of floats, each a finite number > 0, none or more
    (ConfigError else: text such as "50" was read as 50 Hz)."""
    hz = np.atleast_1d(np.asarray(lines_hz, dtype=float)) if real_entries(lines_hz) else None
    if hz is None or hz.ndim != 1 or not np.all(np.isfinite(hz) & (hz > 0)):
        raise ConfigError(f"line frequencies must be numbers of Hz > 0, got {lines_hz!r}")
    return tuple(float(v) for v in hz)


#: :func:`filter_lines` looks again for lines this many times at most
MAX_ROUNDS = 3


def filter_lines(x: ArrayLike, fs: float, lines_hz: ArrayLike, frame_ms: float = 64.0
                 ) -> tuple[NDArray, NDArray]:
    """``x`` (n_ch, n) without the lines ``lines_hz`` (Hz; :func:`remove_lines`) nor those
    their removal uncovers: a line beside a stronger one (the top harmonic of a comb next to
    the one below) can pass the test only once that one is gone. :func:`find_lines` looks
    again after each removal, up to :data:`MAX_ROUNDS` times; the lines found are joined to
    the others (a harmonic comb completed again, :func:`line_frequencies`). Returns (the
    filtered recording, every line removed, Hz, ascending). Inputs checked as
    :func:`find_lines` and :func:`remove_lines` check them."""
    x, fs = _recording(x, fs, two_d=True)
    lines = np.sort(np.array(check_lines(lines_hz), dtype=float))
    y = remove_lines(x, fs, lines)
    for _ in range(MAX_ROUNDS):
        more = _apart(find_lines(y, fs, frame_ms), lines)
        if not more.size:
            break
        lines = np.sort(np.concatenate((lines, more)))
        comb = _comb(lines)
        lines = lines if comb is None else comb
        y = remove_lines(x, fs, lines)
    return y, lines


class LineFilter:
    """The notches of :func:`remove_lines` for a stream: causal, block after block, with
    their state carried over (a block's filtered samples do not depend on how the stream was
    cut into blocks). The same filter on every channel changes no TDOA -- the cross spectra
    gain ``|H|^2``, a real factor -- though each channel's phase near a notch is shifted; the
    first ~0.3 s after the filter starts still hold some hum (the notches' time constant,
    1 / (pi x ``bandwidth_hz``)).

    Parameters
    ----------
    lines_hz : sequence of float
        The lines to remove, Hz (e.g. ``TdoaFrames.tonal_lines_hz``).
    fs : float
        Sample rate, Hz.
    n_channels : int
        Channels of every block.
    bandwidth_hz : float
        Each notch's -3 dB bandwidth, Hz.

    Bad settings (lines that are no numbers > 0, a bandwidth or channel count that is no
    number > 0) are a ConfigError, a bad rate an AudioInputError.
    """

    def __init__(self, lines_hz: ArrayLike, fs: float, n_channels: int,
                 bandwidth_hz: float = NOTCH_BANDWIDTH_HZ) -> None:
        self.lines_hz = check_lines(lines_hz)
        self.sos = _notch_sos(self.lines_hz, check_fs(fs), _bandwidth(bandwidth_hz))
        n_channels = whole_number("n_channels", n_channels)
        self.zi = (None if self.sos is None
                   else np.zeros((self.sos.shape[0], n_channels, 2)))

    def __call__(self, data: NDArray) -> NDArray:
        """The block ``data`` (n_channels, n) filtered, in its dtype when that is a float."""
        if self.sos is None or data.shape[1] == 0:
            return data
        y, self.zi = ss.sosfilt(self.sos, data, axis=-1, zi=self.zi)
        return y.astype(data.dtype, copy=False) if data.dtype.kind == "f" else y
