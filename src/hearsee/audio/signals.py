"""Source signals for simulation and tests, and reading/writing multichannel recordings.

* :func:`white_noise` -- unit-variance Gaussian noise.
* :func:`synthetic_voice` -- a voiced, speech-like source (male F0 ~120 Hz, female ~220 Hz):
  a glottal pulse train with jitter and an intonation contour, shaped by vowel formants, cut
  into syllables separated by pauses, plus a little aspiration noise.
* :func:`load_wav` -- any audio file, mixed down to mono and resampled with
  :func:`scipy.signal.resample_poly`.
* :func:`make_signal` -- one of the above from a short text spec (``"noise"``, ``"male"``,
  ``"female"`` or a file path).
* :func:`read_recording` / :func:`write_recording` -- validated multichannel I/O (channel k is
  microphone k) with hearsee's typed errors.

Amplitudes are dimensionless (full scale = 1.0), durations in seconds, sample rates in Hz.
Multichannel arrays are ``(n_channels, n_samples)``.
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Callable, Iterable, Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hearsee.config import (
    as_path,
    as_rng,
    check_rng,
    finite_number,
    input_file,
    is_real,
    output_file,
    real_entries,
    replacing,
    same_file,
    true_or_false,
    whole_number,
)
from hearsee.errors import (
    AudioInputError,
    ClippingWarning,
    ConfigError,
    DegenerateInputWarning,
    HearseeError,
    InputFileError,
    TruncatedFileWarning,
)

__all__ = [
    "HUM_TOP_HZ",
    "MIN_SAMPLES",
    "MIN_SIGNAL_FILE_FS_HZ",
    "SIGNAL_KINDS",
    "VOICE_F0_HZ",
    "as_samples",
    "channel_faults",
    "check_fs",
    "duplicate_channels",
    "hum_harmonics",
    "load_wav",
    "mains_hum",
    "make_signal",
    "microphone_channels",
    "read_recording",
    "resample",
    "synthetic_voice",
    "unit_peak_scale",
    "white_noise",
    "write_recording",
]

#: :func:`make_signal` refuses a file whose mono mixdown is this far below its channels' power
#: (-60 dB): channels that cancel, not a source
MONO_CANCEL = 1e-6

#: Built-in source signal names accepted by :func:`make_signal` (anything else is a file path).
SIGNAL_KINDS = ("noise", "male", "female")

#: The fewest samples of audio hearsee works with: a recording (:func:`read_recording`'s
#: default) and a source signal file (:func:`make_signal`, which loops a shorter one: fewer
#: samples repeat so fast that no delay can be told from the next repetition; one sample
#: loops into a constant).
MIN_SAMPLES = 64

#: Lowest sample rate of a source signal file (:func:`make_signal`), Hz. No audio format in
#: use records below it (telephone speech is 8 kHz); a lower rate is a wrong header (a script
#: that wrote ``samplerate=1``), and resampling such a file to the simulation's rate multiplied
#: its length by up to fs / rate: a 200000-sample file at 1 Hz asked for 23.8 GiB.
MIN_SIGNAL_FILE_FS_HZ = 1000

#: Nominal (mean) fundamental frequency of the synthetic voices, Hz.
VOICE_F0_HZ = {"male": 120.0, "female": 220.0}

#: Formant frequencies F1-F3 (Hz) and bandwidths of the vowels /a/ /i/ /u/ /e/ /o/
#: (Peterson & Barney 1952, adult male and female averages).
_FORMANTS = {
    "male": np.array([[730, 1090, 2440], [270, 2290, 3010], [300, 870, 2240],
                      [530, 1840, 2480], [570, 840, 2410]], dtype=float),
    "female": np.array([[850, 1220, 2810], [310, 2790, 3310], [370, 950, 2670],
                        [610, 2330, 2990], [590, 920, 2710]], dtype=float),
}
_BANDWIDTHS = np.array([80.0, 100.0, 140.0])

#: Lowest sample rate of :func:`synthetic_voice`, Hz (as the analysis's MIN_FS_HZ).
MIN_VOICE_FS_HZ = 4000.0
#: A sample at or above this magnitude counts as clipped (full scale is 1.0). In a channel
#: whose samples go beyond full scale (a float file: no clipping at 1.0) the level is this
#: fraction of the channel's own peak instead, and only the samples equal to a neighbour count:
#: flat tops wherever they are, not every sample of a loud float recording nor the crests of
#: a smooth wave.
CLIP_LEVEL = 0.999
#: Fraction of clipped samples above which :func:`read_recording` warns.
CLIP_FRACTION = 1e-3
#: :func:`read_recording` warns of a channel whose level (the 90th percentile of its samples'
#: distance from their median) is this many dB below the loudest channel's: a disconnected or
#: muted microphone (preamplifier noise only) -- 100 dB below gave no direction and no word
#: (2026-12-03). Far beyond real gain mismatches (a few dB) and a mask's shadow (tens of dB
#: only at some frequencies, not over the whole band)
QUIET_CHANNEL_DB = 40.0
#: :func:`read_recording` warns of two channels whose zero-lag correlation coefficient is
#: within this of +-1: one signal recorded on both (a mono input copied to every channel, as
#: many sound cards and USB microphones present it; a channel routed twice). Their TDOA is 0
#: whatever the source's direction: a two-microphone recording copied from mono read as a
#: source straight ahead, confidence high, without a word (2026-12-04). Separate microphones
#: stay far from it -- the real two-microphone 'alexa' recording 0.33, the measured 32-mic
#: impulse responses with ARCTIC speech >= 0.021 on every pair; a noise-free simulated voice
#: at two microphones 1 cm apart, 5 deg off their bisecting plane, 3.2e-5. A copy at 30 % gain
#: re-quantised to 16 bits gave 6.9e-8; one re-quantised far below full scale (its rounding
#: within 60 dB of the signal) escapes this test, and the rounding test of
#: :func:`duplicate_channels` (integer PCM files) names it instead.
DUPLICATE_CHANNEL_TOL = 1e-6
#: Largest positive sample (read as float) of the file subtypes whose full scale is below
#: 1.0; :data:`CLIP_LEVEL` applies to it instead of 1.0 (8-bit files stop at 127/128 = 0.992,
#: so their flat tops went unnoticed, and mu-law / A-law files never reach 0.999 at all).
_FULL_SCALE = {"PCM_U8": 127 / 128, "PCM_S8": 127 / 128, "ULAW": 32124 / 32768,
               "ALAW": 32256 / 32768}


def white_noise(duration_s: float, fs: float,
                rng: np.random.Generator | int | None = None) -> NDArray:
    """Unit-variance Gaussian white noise of ``duration_s`` seconds at ``fs`` Hz."""
    n = _check_duration(duration_s, fs)
    return as_rng(rng).standard_normal(n)


#: :func:`mains_hum`'s highest harmonic, Hz (the buzz of a ground loop or of a cheap power supply
#: reaches a few kHz)
HUM_TOP_HZ = 2500.0


def hum_harmonics(f0_hz: float, fs: float, top_hz: float = HUM_TOP_HZ) -> NDArray:
    """The harmonic numbers 1, 2, ... of a hum of fundamental ``f0_hz`` (Hz) that
    :func:`mains_hum` makes at ``fs`` Hz: those up to ``top_hz`` and below fs / 2. A
    ConfigError when ``f0_hz``, ``top_hz`` or ``fs`` is not a number > 0 or no harmonic fits
    (an ``fs`` of NaN, inf or text "16000" gave every harmonic up to ``top_hz``, None a
    builtin TypeError)."""
    f0_hz = finite_number("f0_hz", f0_hz, 0.0, lo_open=True)
    fs = finite_number("fs (Hz)", fs, 0.0, lo_open=True)
    top = min(finite_number("top_hz", top_hz, 0.0, lo_open=True), fs / 2 * 0.999)
    k = np.arange(1, int(top // f0_hz) + 1)
    if not k.size:
        raise ConfigError(f"no harmonic of {f0_hz:g} Hz lies below {top:g} Hz")
    return k


def mains_hum(duration_s: float, fs: float, f0_hz: float = 50.0,
              rng: np.random.Generator | int | None = None,
              top_hz: float = HUM_TOP_HZ) -> NDArray:
    """Mains hum as electrical pickup gives it: every harmonic of ``f0_hz`` (50 or 60 Hz) up
    to ``top_hz`` (and below fs / 2), harmonic k at amplitude 1 / sqrt(k) with a random phase;
    unit RMS, ``duration_s`` seconds at ``fs`` Hz. The same waveform on every channel is what
    a ground loop puts there (:mod:`hearsee.audio.hum` takes it out)."""
    n = _check_duration(duration_s, fs)
    k = hum_harmonics(f0_hz, fs, top_hz)
    f0_hz = float(f0_hz)
    phase = as_rng(rng).uniform(0.0, 2 * np.pi, k.size)
    t = np.arange(n) / float(fs)
    x = np.zeros(n)
    for kk, ph in zip(k, phase, strict=True):
        x += np.sin(2 * np.pi * kk * f0_hz * t + ph) / np.sqrt(kk)
    return x / np.sqrt(np.mean(x**2))


# ---------------------------------------------------------------------------- synthetic voice
#: Longest signal the generators make, seconds (longer scenes: simulate them in pieces; the
#: bound keeps a mistyped duration from asking for terabytes)
MAX_SIGNAL_S = 600.0
#: Most samples per channel the generators and the resampler make: :data:`MAX_SIGNAL_S` at
#: 192 kHz (a sample rate of 1e12 Hz asked for terabytes: a MemoryError)
MAX_SIGNAL_SAMPLES = int(MAX_SIGNAL_S * 192_000)


#: The highest sample rate an audio file can declare (Hz): libsndfile keeps it in a C int.
MAX_FILE_FS_HZ = 2**31 - 1


def check_fs(fs: float) -> float:
    """``fs`` (Hz) as a float when it is a finite real number > 0 and at most
    :data:`MAX_FILE_FS_HZ` (:func:`config.is_real`: not a string, a bool or a 1-element
    array), else an AudioInputError (``write_recording(..., 1e10)`` was a builtin
    OverflowError)."""
    if not (is_real(fs) and 0 < fs <= MAX_FILE_FS_HZ):
        raise AudioInputError(f"sample rate must be a positive number of Hz (at most "
                              f"{MAX_FILE_FS_HZ}), got {fs!r}")
    return float(fs)


def unit_peak_scale(peak: float) -> float:
    """The power of two that brings a recording's largest |sample| ``peak`` (> 0) into
    [0.5, 1): multiplying by it is exact, so a scale-free estimate is the same bit for bit at
    any level (1 for a peak that is not finite). Used by
    :func:`hearsee.audio.mask.localize_mask` and
    :class:`hearsee.stream.pipeline.ArraySource`."""
    return math.ldexp(1.0, -math.frexp(peak)[1])


def as_samples(x: ArrayLike, what: str = "recording", *, finite: bool = True) -> NDArray:
    """``x`` as a float array of audio samples (any shape: the caller checks it), else an
    AudioInputError naming ``what``.

    Samples are real numbers: floats, or integer PCM counts (int16, int32, uint8, ...) taken as
    they are -- every estimate of hearsee is scale-free. Booleans, complex numbers, text and
    None are refused: numpy's float conversion read ``True`` as 1.0 and ``"0.5"`` as 0.5, and
    dropped an imaginary part (with a mere ComplexWarning). NaN and infinite samples are
    refused too (``finite=False`` lets them through, for a caller that names them itself). The
    one check of a recording given to the library's estimators
    (:func:`hearsee.audio.tdoa.estimate_tdoas`, :func:`hearsee.audio.tdoa.gcc`,
    :func:`hearsee.audio.mask.localize_mask`, :class:`hearsee.stream.pipeline.ArraySource`) and
    of a signal given to the simulation's helpers (:func:`resample` and
    :mod:`hearsee.audio.propagation`'s ``delay_signals`` and ``add_noise``)."""
    if not real_entries(x):
        got = f"a {x.dtype} array" if isinstance(x, np.ndarray) else repr(x)[:60]
        raise AudioInputError(f"{what}: samples must be real numbers (floats or integer PCM "
                              f"counts), got {got}")
    a = np.asarray(x, dtype=float)
    if finite and not np.all(np.isfinite(a)):
        raise AudioInputError(f"{what} contains NaN or infinite samples")
    return a


def _check_duration(duration_s: float, fs: float) -> int:
    if not (is_real(duration_s) and duration_s > 0):  # (a string: numpy's TypeError)
        raise ConfigError(f"duration must be a positive number of seconds, got {duration_s!r}")
    if duration_s > MAX_SIGNAL_S:
        raise ConfigError(f"duration must be at most {MAX_SIGNAL_S:g} s (simulate longer scenes "
                          f"in pieces), got {duration_s:g} s")
    if not (is_real(fs) and fs > 0):
        raise ConfigError(f"sample rate must be a positive number of Hz, got {fs!r}")
    n = int(round(duration_s * fs))
    if n < 1:
        raise ConfigError(f"duration {duration_s} s at {fs} Hz is shorter than one sample")
    if n > MAX_SIGNAL_SAMPLES:
        raise ConfigError(f"{duration_s:g} s at {fs:g} Hz is {n:.3g} samples, more than the "
                          f"generators make ({MAX_SIGNAL_SAMPLES}: {MAX_SIGNAL_S:g} s at 192 "
                          "kHz); use a lower sample rate or a shorter signal")
    return n


def _syllable_plan(n: int, fs: float, rng: np.random.Generator) -> tuple[NDArray, NDArray]:
    """Syllable onsets/offsets (samples): 0.12-0.32 s syllables, 0.04-0.30 s pauses."""
    starts, stops = [], []
    t = int(rng.uniform(0.02, 0.08) * fs)
    while t < n:
        length = max(int(rng.uniform(0.12, 0.32) * fs), 1)
        starts.append(t)
        stops.append(min(t + length, n))
        # mostly short gaps between syllables, now and then a longer phrase pause
        gap = rng.uniform(0.15, 0.30) if rng.random() < 0.25 else rng.uniform(0.04, 0.10)
        t += length + int(gap * fs)
    return np.array(starts), np.array(stops)


def _resonator_cascade(x: NDArray, formants: NDArray, fs: float) -> NDArray:
    """Filter ``x`` through two-pole resonators (unit gain at DC) at ``formants`` Hz."""
    from scipy.signal import sosfilt

    keep = formants < 0.45 * fs
    f = formants[keep]
    bw = _BANDWIDTHS[: len(formants)][keep]
    r = np.exp(-np.pi * bw / fs)
    a1 = -2 * r * np.cos(2 * np.pi * f / fs)
    a2 = r**2
    sos = np.column_stack([1 + a1 + a2, np.zeros_like(f), np.zeros_like(f),
                           np.ones_like(f), a1, a2])
    return sosfilt(sos, x) if len(sos) else x.copy()


def synthetic_voice(kind: str = "male", duration_s: float = 2.0, fs: float = 16000,
                    rng: np.random.Generator | int | None = None) -> NDArray:
    """A voiced, speech-like test signal of ``duration_s`` seconds at ``fs`` Hz.

    Source-filter synthesis (Fant 1960; Klatt 1980, simplified):

    * **Excitation**: a glottal pulse train whose instantaneous F0 follows an intonation
      contour -- a slow declination (+6 % to -6 %) plus a ~0.7 Hz melodic swing (+-8 %) and a
      rise/fall per syllable -- around the nominal F0 (:data:`VOICE_F0_HZ`: 120 Hz male, 220 Hz
      female), with 1 % cycle-to-cycle jitter. Pulses are shaped by a two-pole glottal low-pass
      (spectral tilt) and the lip radiation (first difference).
    * **Vocal tract**: cascaded formant resonators F1-F3 for the vowels /a/ /i/ /u/ /e/ /o/
      (Peterson & Barney 1952 values, male or female); each syllable gets a random vowel and
      the outputs are cross-faded so the formants glide between syllables.
    * **Prosody**: syllables of 0.12-0.32 s with a smooth attack/decay envelope, separated by
      silent pauses of 0.04-0.30 s (the signal is exactly zero there), and aspiration noise
      (-26 dB, high-passed) during the syllables.

    Returns
    -------
    array (n,)
        ``n = round(duration_s * fs)``, scaled to unit mean power over the whole signal (like
        :func:`white_noise`), so SNRs are comparable across signal kinds.
    """
    from scipy.signal import fftconvolve, lfilter

    # (a list or a dict was a builtin TypeError, "unhashable type")
    if not isinstance(kind, str) or kind not in VOICE_F0_HZ:
        raise ConfigError(f"unknown voice kind {kind!r} (expected 'male' or 'female')")
    n = _check_duration(duration_s, fs)
    if fs < MIN_VOICE_FS_HZ:  # (at 1 Hz its syllables rounded to 0 samples: an endless loop)
        raise ConfigError(f"a synthetic voice needs a sample rate of at least "
                          f"{MIN_VOICE_FS_HZ:g} Hz (its formants reach 3.3 kHz), got {fs:g} Hz")
    rng = as_rng(rng)
    f0 = VOICE_F0_HZ[kind]
    t = np.arange(n) / fs
    T = max(duration_s, 1e-9)

    starts, stops = _syllable_plan(n, fs, rng)
    if len(starts) == 0:  # the first syllable would start after the end
        raise ConfigError(f"duration {duration_s} s is too short for a synthetic voice")
    # ---- envelope: raised-cosine attack (30 ms) and decay (60 ms) per syllable
    idx = np.arange(n)
    k = np.clip(np.searchsorted(starts, idx, side="right") - 1, 0, None)
    inside = (idx >= starts[k]) & (idx < stops[k])
    pos = (idx - starts[k]) / fs
    rem = (stops[k] - idx) / fs
    env = np.where(inside, np.minimum(1.0, np.minimum(pos / 0.03, rem / 0.06)), 0.0)
    env = np.sin(0.5 * np.pi * np.clip(env, 0.0, 1.0)) ** 2
    env *= np.where(inside, rng.uniform(0.6, 1.0, len(starts))[k], 0.0)  # syllable stress

    # ---- intonation: declination + melodic swing + per-syllable rise or fall
    syl_len = np.maximum(stops - starts, 1) / fs
    slope = rng.choice([-1.0, 1.0], len(starts))[k] * 0.05
    contour = (1 + 0.06 * (1 - 2 * t / T)
               + 0.08 * np.sin(2 * np.pi * 0.7 * t + rng.uniform(0, 2 * np.pi))
               + np.where(inside, slope * (pos / syl_len[k] - 0.5), 0.0))
    # jitter: a random factor per ~period, held piecewise constant
    n_cycles = int(np.ceil(T * f0 * 1.5)) + 2
    jitter = 1 + 0.01 * rng.standard_normal(n_cycles)
    phase = np.cumsum(f0 * contour / fs)
    inst_f0 = f0 * contour * jitter[np.minimum(phase.astype(int), n_cycles - 1)]
    phase = np.cumsum(inst_f0 / fs)
    pulses = np.zeros(n)
    pulses[1:][np.diff(np.floor(phase)) > 0] = 1.0

    # ---- glottal shaping (two real poles ~ -12 dB/oct tilt) and lip radiation (+6 dB/oct)
    p = np.exp(-2 * np.pi * 100.0 / fs)
    glottal = lfilter([1.0], np.convolve([1, -p], [1, -p]), pulses)
    glottal = lfilter([1.0, -1.0], [1.0], glottal)

    # ---- vowels: one per syllable, cross-faded between syllables
    table = _FORMANTS[kind]
    vowel_of_syllable = rng.integers(0, len(table), len(starts))
    weights = np.zeros((len(table), n))
    weights[vowel_of_syllable[k], idx] = 1.0
    win = max(int(0.04 * fs), 1)
    kernel = np.hanning(win + 2)[1:-1]
    kernel /= kernel.sum()
    weights = fftconvolve(weights, kernel[None, :], mode="same", axes=1)
    voiced = np.zeros(n)
    for v in np.unique(vowel_of_syllable):  # at most 5 vowels: a loop per vowel, not per sample
        voiced += weights[v] * _resonator_cascade(glottal, table[v], fs)
    voiced /= np.sqrt(np.mean(voiced[inside] ** 2)) if np.any(inside) else 1.0

    # ---- aspiration noise (high-passed white noise, -26 dB)
    asp = np.diff(rng.standard_normal(n + 1)) / np.sqrt(2)
    y = env * (voiced + 0.05 * asp)
    power = np.mean(y**2)
    if power <= 0:
        raise ConfigError(f"duration {duration_s} s is too short for a synthetic voice")
    return y / np.sqrt(power)


# ---------------------------------------------------------------------------- files
def _resample(x: ArrayLike, fs_in: float, fs_out: float) -> NDArray:
    """Resample ``x`` (last axis) from ``fs_in`` to ``fs_out`` Hz with a polyphase filter."""
    from scipy.signal import resample_poly

    x = as_samples(x, "signal", finite=False)  # (text was read as numbers; NaN: the caller's)
    if x.ndim == 0:  # (a single number: scipy's builtin IndexError)
        raise AudioInputError(f"signal must hold samples along its last axis, got the single "
                              f"number {float(x)!r}")
    for rate in (fs_in, fs_out):  # (0 divided by zero, NaN and inf raised numpy errors)
        check_fs(rate)
    if fs_in == fs_out:
        return x.copy()
    ratio = Fraction(float(fs_out) / float(fs_in)).limit_denominator(1000)
    if ratio.numerator == 0 or abs(float(ratio) * fs_in - fs_out) > 1e-6 * fs_out:
        raise AudioInputError(
            f"cannot resample {fs_in} Hz to {fs_out} Hz: the ratio needs a polyphase filter "
            "of more than 1000 phases; resample to a common rate (e.g. 16000 or 48000 Hz) first"
        )
    # (upsampling to 1e9 Hz was a MemoryError; a long file taken down to a lower rate never
    # grows, so it is not limited)
    n_out = x.shape[-1] * ratio.numerator // ratio.denominator
    if n_out > max(MAX_SIGNAL_SAMPLES, x.shape[-1]):
        raise AudioInputError(f"resampling {x.shape[-1]} samples from {fs_in:g} to {fs_out:g} "
                              f"Hz makes {n_out:.3g} samples per channel, more than "
                              f"{MAX_SIGNAL_SAMPLES} ({MAX_SIGNAL_S:g} s at 192 kHz)")
    return resample_poly(x, ratio.numerator, ratio.denominator, axis=-1)


#: Public name of the polyphase resampler (``read_recording`` has a ``resample`` flag).
resample = _resample


#: libsndfile's lossy subtypes: :func:`read_recording` warns (DegenerateInputWarning) -- a
#: two-microphone recording saved as Vorbis (channels coded jointly) gave a TDOA of 0.1 us
#: where it was 364 us, azimuth 0 deg for 56, without a word (2026-12-07)
LOSSY_SUBTYPES = frozenset({"VORBIS", "OPUS", "MPEG_LAYER_I", "MPEG_LAYER_II",
                            "MPEG_LAYER_III"})


def _subtype(path: str | Path) -> str | None:
    """The audio file's subtype ("PCM_16", "FLOAT", ...), None when it cannot be told."""
    import soundfile as sf

    if not Path(path).is_file():  # (a pipe, read already: opened again, a FIFO waits forever)
        return None
    try:
        return str(sf.info(os.fsencode(path)).subtype)
    except Exception:  # noqa: BLE001 (the file was read already; only warnings depend on it)
        return None


#: One quantisation step of the integer PCM subtypes, read as floats in [-1, 1)
_PCM_STEP = {"PCM_S8": 2.0**-7, "PCM_U8": 2.0**-7, "PCM_16": 2.0**-15, "PCM_24": 2.0**-23,
             "PCM_32": 2.0**-31}


def _wav_data_shortfall(path: Path) -> tuple[int, int] | None:
    """``(declared, present)`` bytes of a RIFF/WAVE or RF64 file's data chunk when the file
    ends before the size its header declares, else None (other formats, intact files, and the
    unknown size 0xFFFFFFFF of a recorder that streamed to a pipe). libsndfile reads such a
    file without a word, as the samples present. An RF64 file (the WAV of more than 4 GiB that
    recorders and libsndfile write, suffix .wav) declares the size in its ds64 chunk: until
    2026-12-07 it was not looked at, so a cut one was read without a word. None for what is
    no regular file (a pipe, read already)."""
    if not path.is_file():
        return None
    try:
        with open(path, "rb") as f:
            head = f.read(12)
            if len(head) < 12 or head[:4] not in (b"RIFF", b"RF64") or head[8:12] != b"WAVE":
                return None
            size = os.fstat(f.fileno()).st_size
            ds64 = None  # (RF64: the data chunk's 64-bit size)
            while True:
                chunk = f.read(8)
                if len(chunk) < 8:
                    return None
                n = int.from_bytes(chunk[4:], "little")
                if chunk[:4] == b"ds64" and head[:4] == b"RF64" and n >= 16:
                    ds64 = int.from_bytes(f.read(16)[8:], "little")
                    n -= 16
                if chunk[:4] == b"data":
                    present = size - f.tell()
                    if n == 0xFFFFFFFF and ds64 is not None:
                        n = ds64
                    return (n, present) if n != 0xFFFFFFFF and n > present else None
                f.seek(n + (n & 1), os.SEEK_CUR)
    except OSError:
        return None


def _read_stream(f: Any, frames: int) -> NDArray:
    """``frames`` frames (-1: all) of the open, non-seekable soundfile ``f``, read in blocks
    until it ends: (n, n_channels) float64."""
    parts, left = [], frames
    while left != 0:
        block = f.read(1 << 16 if left < 0 else min(left, 1 << 16), dtype="float64",
                       always_2d=True)
        if not len(block):
            break
        parts.append(block)
        left = left - len(block) if left > 0 else left
    return np.concatenate(parts) if parts else np.zeros((0, f.channels))


def _read_file(path: str | Path,
               frames_at: Callable[[int], int] | None = None) -> tuple[NDArray, int]:
    """Read any libsndfile format -> ``(x (n_ch, n) float64, fs)`` with typed errors.

    ``frames_at(fs)``, given the file's sample rate (Hz) before any sample is read, returns how
    many frames to read from the start (-1: all; it may also raise to refuse the rate);
    default: the whole file."""
    import soundfile as sf

    p = input_file(path, "audio file")
    try:
        # (what sf.read does, with the rate known first; the name as the system's bytes:
        # soundfile encodes a str as strict UTF-8, and a name that is not refused the file)
        with sf.SoundFile(os.fsencode(p)) as f:
            fs = f.samplerate
            frames = -1 if frames_at is None else frames_at(int(fs))
            if f.seekable():
                data = f.read(frames, dtype="float64", always_2d=True)
            else:  # (a pipe, e.g. <(sox ...): soundfile reads it only by a count of frames --
                # "frames must be specified", read as "not an audio file" until 2026-12-07)
                data = _read_stream(f, frames)
    except HearseeError:  # frames_at's refusal (an AudioInputError is a ValueError too)
        raise
    except (RuntimeError, sf.LibsndfileError, TypeError, ValueError) as exc:
        # (libsndfile's own words; its message repeats the file's name, as bytes)
        why = getattr(exc, "error_string", None) or exc
        if p.is_file():  # (a file the system will not open -- no permission -- was "not an
            # audio file ... (System error.)" until 2026-12-07: libsndfile says no more)
            try:
                open(p, "rb").close()
            except OSError as err:
                raise InputFileError(f"{p}: cannot be read ({err.strerror or err})") from None
        raise AudioInputError(
            f"{p}: not an audio file or a format libsndfile cannot read ({why}); "
            "use a WAV or FLAC file"
        ) from None
    except OSError as exc:
        raise InputFileError(f"{p}: cannot be read ({exc.strerror or exc})") from None
    return np.ascontiguousarray(data.T), int(fs)


def load_wav(path: str | Path, fs: float | None = None) -> tuple[NDArray, int]:
    """Load an audio file as a mono signal.

    Channels are averaged; with ``fs`` the signal is resampled to ``fs`` Hz (polyphase,
    :func:`scipy.signal.resample_poly`). Returns ``(x (n,), fs)``. An ``fs`` that is no
    positive number is an AudioInputError (:func:`check_fs`).
    """
    if fs is not None:  # (NaN, inf and text were builtin ValueError / OverflowError / TypeError)
        fs = check_fs(fs)
    x, fs_in = _read_file(path)
    if x.shape[1] == 0:
        raise AudioInputError(f"{path}: the file contains no samples")
    mono = x.mean(axis=0)
    if fs is None or int(round(fs)) == fs_in:
        return mono, fs_in
    return _resample(mono, fs_in, fs), int(round(fs))


def make_signal(spec: str | Path, duration_s: float, fs: float,
                rng: np.random.Generator | int | None = None) -> NDArray:
    """A source signal of ``round(duration_s * fs)`` samples from a short text spec.

    ``spec`` is ``"noise"`` (white noise), ``"male"`` / ``"female"`` (:func:`synthetic_voice`)
    or the path of an audio file (mono mixdown, resampled to ``fs``, looped or trimmed to the
    duration and scaled to unit mean power). A file shorter than :data:`MIN_SAMPLES` samples
    at ``fs`` is an AudioInputError: looped, it repeats faster than a delay can be measured
    (a 1-sample file was looped into a constant signal, recorded and localized as noise). So is
    a file sampled below :data:`MIN_SIGNAL_FILE_FS_HZ` (1000 Hz). Only the part of a long file
    that the duration needs is read and resampled (the samples are those of the whole file
    resampled: the part read extends past the duration by the resampler's filter length).
    """
    n = _check_duration(duration_s, fs)
    check_rng(rng)  # (an audio file draws nothing: a bad rng passed unnoticed)
    s = str(spec)
    if s == "noise":
        return white_noise(duration_s, fs, rng)
    if s in VOICE_F0_HZ:
        return synthetic_voice(s, duration_s, fs, rng)
    p = Path(s)
    if not p.exists() and p.suffix == "":
        raise ConfigError(
            f"unknown signal {s!r}: expected 'noise', 'male', 'female' or an audio file path"
        )
    fs_out = int(round(fs))

    def frames_at(fs_in: int) -> int:
        """The file's first frames that make the signal: the whole file would be resampled
        before the trim to ``n`` (a 10-minute file for a 2 s simulation). Its margin, twice
        resample_poly's filter half-length (10 * max(up, down) output samples = 10 * max(1,
        fs_in / fs) input samples) plus 64, leaves the ``n`` samples used bit-identical to
        those of the whole file resampled (checked for 44.1k/48k/8k -> 16k, 1k -> 384k and
        384k -> 4k Hz; each needs about half this margin). At least MIN_SAMPLES output samples
        are kept, so the length check below still sees a long file as long."""
        if fs_in < MIN_SIGNAL_FILE_FS_HZ:
            raise AudioInputError(
                f"{p}: the file's sample rate is {fs_in} Hz, below the {MIN_SIGNAL_FILE_FS_HZ} Hz "
                "a source signal needs (a wrong header?); resample it to e.g. 16000 Hz")
        if fs_in == fs_out:
            asked[0] = max(n, MIN_SAMPLES)
        else:
            margin = int(np.ceil(20 * max(1.0, fs_in / fs))) + 64
            asked[0] = int(np.ceil(max(n, MIN_SAMPLES) * fs_in / fs)) + margin
        return asked[0]

    asked = [0]
    x, fs_in = _read_file(p, frames_at)
    if x.shape[1] == 0:
        raise AudioInputError(f"{p}: the file contains no samples")
    whole = x.shape[1] < asked[0]  # (else the file may go on past the part read)
    each = float(np.mean(x**2)) if np.all(np.isfinite(x)) else 0.0  # (NaN: refused below)
    x = x.mean(axis=0)
    mixed = float(np.mean(x**2)) if x.size else 0.0
    if each > 0 and mixed < MONO_CANCEL * each:
        # (a stereo file whose channels are each other inverted left rounding residue that
        # was scaled to full level and simulated as the source, without a word)
        db = 10 * np.log10(max(mixed, 1e-300) / each)
        raise AudioInputError(
            f"{p}: its channels cancel when mixed to mono ({db:.0f} dB below them: one channel "
            "the other inverted?); give a file of one of its channels")
    if fs_in != fs_out:
        x = _resample(x, fs_in, fs)
    if len(x) < MIN_SAMPLES:
        raise AudioInputError(
            f"{p}: the signal is too short to simulate: {len(x)} sample"
            f"{'s' if len(x) != 1 else ''} at {fs:g} Hz; it is looped to the duration, and "
            f"fewer than {MIN_SAMPLES} repeat too fast to localize (give at least "
            f"{MIN_SAMPLES / fs * 1000:.3g} ms of sound)")
    if not np.all(np.isfinite(x)):
        raise AudioInputError(f"{p}: the file contains NaN or infinite samples")
    if not np.any(x):
        raise AudioInputError(f"{p}: the file is silent (all samples are zero)" if whole else
                              f"{p}: the first {duration_s} s of the file are silent")
    x = np.tile(x, int(np.ceil(n / len(x))))[:n]
    power = np.mean(x**2)
    if power <= 0:  # the looped/trimmed part is silent
        raise AudioInputError(f"{p}: the first {duration_s} s of the file are silent")
    return x / np.sqrt(power)


def read_recording(
    path: str | Path | Sequence[str | Path],
    n_channels: int | Any | None = None,
    fs: float | None = None,
    *,
    resample: bool = False,
    min_samples: int = MIN_SAMPLES,
    channels: Sequence[int] | NDArray | None = None,
) -> tuple[NDArray, int]:
    """Read and validate a multichannel recording (channel k = microphone k, or
    ``channels[k]``).

    Parameters
    ----------
    path : str or Path, or a list or tuple of them
        Any format libsndfile reads (WAV, FLAC, ...). Several files are one recording made of
        one file per microphone (or per group of microphones), as recorders that write a file
        per input channel: their channels in the order given, file by file (two mono files
        make microphones 0 and 1). They must share the sample rate (or be resampled to ``fs``)
        and hold the same number of samples: files of different lengths are not known to
        start together, and an offset between them is a time difference of its own.
    n_channels : int or MicArray, optional
        Required channel count (a whole number >= 1, else a ConfigError); pass the
        :class:`~hearsee.audio.arrays.MicArray` itself to get its name in the error message.
    fs : float, optional
        Required sample rate in Hz (a positive number, else an AudioInputError). A different
        file rate is an error unless ``resample=True``, which resamples the recording to ``fs``
        (polyphase filter). Upsampled, it holds no sound above the file's Nyquist frequency,
        only the filter's mirror images: limit the GCC band below it (``band_hz`` of
        :func:`hearsee.audio.tdoa.estimate_tdoas`; PHAT over the whole band biased 8 kHz files
        read at 16 kHz by up to 70 us).
    min_samples : int
        Fewer samples per channel than this is an error (e.g. one analysis frame).
    channels : sequence of int, optional
        The input channel (0-based; over several files, their channels file by file) of each
        microphone: a device's recording that holds other channels too, e.g. a 6-channel
        ReSpeaker 4-mic array file (channel 0 its processed beam, 1-4 the microphones, 5 the
        playback: ``channels=[1, 2, 3, 4]``). One per microphone (``n_channels`` of them),
        distinct; the others are neither returned nor checked (a silent playback channel is
        no error). Messages name channels by these input numbers.

    Returns
    -------
    (x, fs) : (array (n_channels, n) float64, int)

    Raises
    ------
    InputFileError
        The file does not exist or cannot be opened; ``path`` is no file name, an empty
        sequence or one holding something that is no file name.
    AudioInputError
        Not an audio file, wrong channel count or sample rate, NaN/inf samples, a silent
        (all-zero) or constant channel, or too short; several files of different sample
        rates or lengths.

    Warns
    -----
    ClippingWarning
        More than 0.1 % of the samples are at full scale (float files beyond full scale:
        at their channel's peak, see :data:`CLIP_LEVEL`).
    TruncatedFileWarning
        A WAV file ends before its header's data size: the samples present are used.
    DegenerateInputWarning
        A channel is more than :data:`QUIET_CHANNEL_DB` below the loudest one: a
        disconnected or muted microphone, whose pairs carry only its noise. Or two channels
        hold one signal (:func:`duplicate_channels`): their TDOA is 0 whatever the direction.
        Or one sample is beyond any integer PCM range of the others
        (:func:`hearsee.audio.tdoa.dominant_sample`: a corrupt float sample), told instead.
    """
    # (checked before the file is read: NaN, inf and text were builtin ValueError /
    # OverflowError / TypeError once compared with the file's rate, "2" a ValueError)
    if fs is not None:
        fs = check_fs(fs)
    # (min_samples "x", None or NaN were builtin ValueError / TypeError from int(); a
    # resample of "no" resampled)
    min_samples = whole_number("min_samples", min_samples, 0)
    resample = true_or_false("resample", resample)
    want = None if n_channels is None else whole_number(
        "n_channels", getattr(n_channels, "n_mics", n_channels))
    paths = recording_paths(path)
    label = recording_label(paths)
    raw = []
    for p in paths:  # (not a comprehension: its own frame moved the warnings' stacklevel)
        raw.append(_read_whole(p))
    counts = [x.shape[0] for x, _ in raw]
    total = sum(counts)
    if channels is not None:
        chosen = np.asarray(microphone_channels(channels, want, "channels"), dtype=int)
        if chosen.max() >= total:
            held = "the recording has" if len(paths) == 1 else "the files hold"
            raise AudioInputError(
                f"{label}: channel {chosen.max()} asked for, but {held} {total} "
                f"channel{'s' if total != 1 else ''} (0-{total - 1})")
    elif want is not None and total != want:
        what = (f"array {n_channels.name!r} has {want} microphones"
                if hasattr(n_channels, "n_mics") else f"{want} were expected")
        held = "recording has" if len(paths) == 1 else "the files hold"
        raise AudioInputError(
            f"{label}: {held} {total} channel{'s' if total != 1 else ''} but {what} "
            f"(channel k must be microphone k{'' if len(paths) == 1 else ', file by file'}; "
            "a device that records other channels too: choose the microphones' with "
            "--channels)")
    else:
        chosen = np.arange(total)
    # each file checked on its own (the channels asked for of it); the input channel numbers
    # (over the files, file by file) of its rows
    files: list[_FilePart] = []
    first = 0
    for p, (x, rate) in zip(paths, raw, strict=True):
        mine = np.unique(chosen[(chosen >= first) & (chosen < first + x.shape[0])])
        if mine.size:  # (a file none of whose channels is asked for is not read further)
            sub = x if mine.size == x.shape[0] else x[mine - first]  # (all: no copy)
            files.append(_checked(p, sub, rate, fs, resample, min_samples, mine,
                                  mine.size == x.shape[0]))
        first += x.shape[0]
    if len({f.fs for f in files}) > 1:
        each = ", ".join(f"{f.path} {f.fs} Hz" for f in files)
        raise AudioInputError(f"{label}: the files are sampled at different rates ({each}); "
                              "one recording needs one rate: resample them to one, or ask "
                              "for resampling")
    if len({f.x.shape[1] for f in files}) > 1:
        each = ", ".join(f"{f.path} {f.x.shape[1]}" for f in files)
        raise AudioInputError(
            f"{label}: the files hold different numbers of samples ({each}): files of one "
            "recording start and end together, and an offset between them would read as a "
            "time difference; trim them to a common start and length")
    if np.array_equal(chosen, np.arange(total)):  # (every channel in order: no copy of one)
        x = files[0].x if len(files) == 1 else np.concatenate([f.x for f in files], axis=0)
    else:
        rows = {int(c): f.x[k] for f in files for k, c in enumerate(f.channels)}
        x = np.stack([rows[int(c)] for c in chosen])
    fs_in = files[0].fs
    _, quiet, below = channel_faults(x)  # (stuck channels were refused file by file)
    if quiet.size:
        warnings.warn(f"{label}: {quiet_channels_text(chosen[quiet], below)}",
                      DegenerateInputWarning, stacklevel=2)
    # (a copy re-quantised to integer PCM differs by its rounding: told by the step, before
    # any resampling spreads it)
    steps = {f.step for f in files}
    step = steps.pop() if len(steps) == 1 else None
    from hearsee.audio.tdoa import dominant_sample

    if spike := dominant_sample(x):
        # (told once, first: the same corrupt sample on every channel also made them read as
        # copies of one another, the only warning there was)
        ch, i, v, ratio = spike
        warnings.warn(
            f"{label}: sample {i} of channel {chosen[ch]} ({i / fs_in:.3f} s) is {v:.3g}, "
            f"{ratio:.2g} times the median |sample|, beyond any integer PCM range (a corrupt "
            "sample?); the analysis scales the recording to its loudest sample, so the rest of "
            "it is nearly lost and its estimates may be wrong", DegenerateInputWarning,
            stacklevel=2)
    elif dup := duplicate_channels(x, step):
        dup = [(int(chosen[i]), int(chosen[j])) for i, j in dup]
        warnings.warn(f"{label}: {duplicate_channels_text(dup)}", DegenerateInputWarning,
                      stacklevel=2)
    lossy = [(f.path, f.subtype) for f in files if f.subtype in LOSSY_SUBTYPES]
    if lossy:
        what = (f"lossy-compressed ({lossy[0][1]})" if len(paths) == 1 else
                ", ".join(f"{q} ({sub})" for q, sub in lossy)
                + f" {'is' if len(lossy) == 1 else 'are'} lossy-compressed")
        warnings.warn(
            f"{label}: {what}: the codec can change the time differences between the channels, "
            "and coding them jointly erase them (a two-channel Vorbis file read 0.1 us for 364 "
            "us); record the microphones to WAV or FLAC", DegenerateInputWarning, stacklevel=2)
    # (over every sample taken, as of one file holding them all)
    clipped = sum(f.clipped for f in files) / max(sum(f.read for f in files), 1)
    if clipped > CLIP_FRACTION:
        warnings.warn(
            f"{label}: {clipped * 100:.2f} % of the samples are clipped (flat at full scale, or "
            "at the channel's peak in a float file beyond it); "
            "estimates may be biased -- lower the input gain",
            ClippingWarning,
            stacklevel=2,
        )
    return x, fs_in


def recording_paths(path: str | Path | Sequence[str | Path]) -> list[Path]:
    """The files of a recording given as one file name or a list or tuple of them (one file per
    microphone or group of microphones, :func:`read_recording`); an InputFileError for an
    empty sequence or anything that is no file name (:func:`hearsee.config.as_path`)."""
    if isinstance(path, list | tuple):
        if not path:
            raise InputFileError("a recording needs one audio file or more, got none")
        return [as_path(p, "an audio file's path") for p in path]
    return [as_path(path, "the audio file's path")]


#: The most input channels a recording or device is taken to have (:func:`microphone_channels`)
MAX_INPUT_CHANNELS = 4096


def microphone_channels(channels: Any, n_mics: int | None, where: str) -> tuple[int, ...]:
    """``channels``, the input channel (0-based) of each microphone, checked: a list, tuple or
    1-D array of distinct integers >= 0, ``n_mics`` of them (None: any number >= 1); a ConfigError
    naming ``where`` else. The one check of :func:`read_recording`'s ``channels``, the CLI's
    ``--channels`` and the robot file's ``audio.channels``."""
    from numbers import Integral

    if isinstance(channels, np.ndarray) and channels.ndim == 1:
        channels = channels.tolist()
    if (not isinstance(channels, list | tuple) or not channels
            or not all(isinstance(c, Integral) and not isinstance(c, bool) for c in channels)):
        raise ConfigError(f"{where}: expected a list of channel indices, got {channels!r:.60}")
    ch = tuple(int(c) for c in channels)
    if n_mics is not None and len(ch) != n_mics:
        raise ConfigError(f"{where}: {len(ch)} channels for an array of {n_mics} microphones "
                          "(one input channel per microphone)")
    if any(c < 0 for c in ch) or len(set(ch)) != len(ch):
        raise ConfigError(f"{where}: channels must be distinct and >= 0, got {list(ch)}")
    if max(ch) >= MAX_INPUT_CHANNELS:  # (1e19 overflowed numpy's integers: a traceback)
        raise ConfigError(f"{where}: channel {max(ch)} is beyond any input (at most "
                          f"{MAX_INPUT_CHANNELS} channels, 0-{MAX_INPUT_CHANNELS - 1})")
    return ch


def recording_label(path: str | Path | Sequence[str | Path]) -> str:
    """How messages name a recording of one file or several (``a.wav + b.wav``)."""
    return " + ".join(str(p) for p in recording_paths(path))


def recording_entry(path: str | Path | Sequence[str | Path]) -> str | list[str]:
    """How JSON documents name a recording: its file, or the list of its files."""
    paths = recording_paths(path)
    return str(paths[0]) if len(paths) == 1 else [str(p) for p in paths]


def _read_whole(path: str | Path) -> tuple[NDArray, int]:
    """One file of :func:`read_recording` read (:func:`_read_file`), with a
    TruncatedFileWarning when it ends before its header's data size."""
    x, fs_in = _read_file(path)
    cut = _wav_data_shortfall(Path(path))
    if cut is not None:
        warnings.warn(
            f"{path}: the file is cut short: its header declares {cut[0]} bytes of audio, the "
            f"file holds {cut[1]} ({x.shape[1] / fs_in:.3g} s); only those samples are used",
            TruncatedFileWarning, stacklevel=3)
    return x, fs_in


class _FilePart(NamedTuple):
    """One file's part of a recording (:func:`read_recording`, :func:`_checked`)."""

    path: str | Path
    x: NDArray  #: its channels taken (n, samples), resampled when asked
    fs: int  #: their rate, Hz
    step: float | None  #: the file's integer quantisation step (None: float or resampled)
    clipped: int  #: samples clipped, as read
    read: int  #: samples read (of the channels taken)
    channels: NDArray  #: the input channel numbers (over the files) of ``x``'s rows
    subtype: str | None  #: the file's subtype (:func:`_subtype`), None when it cannot be told


def _checked(path: str | Path, x: NDArray, fs_in: int, fs: float | None, resample: bool,
             min_samples: int, names: NDArray, whole: bool) -> _FilePart:
    """One file of :func:`read_recording` (``x`` (n_ch, n): its channels ``names``, input
    channel numbers over the files, read at ``fs_in`` Hz; ``whole``: every channel of the file)
    checked on its own. The checks that compare channels with one another, and the clipping
    warning, are the caller's."""
    n, read = x.shape[1], x.size
    sub = _subtype(path)  # (its header read once: full scale, quantisation step, lossy codec)
    # clipping is seen on the file's own samples (resampling smooths the flat tops away)
    clipped, resampled = 0, False
    if x.size and np.all(np.isfinite(x)):
        mag = np.abs(x)
        peak = mag.max(axis=1, keepdims=True)
        beyond = peak > 1.0
        # (the largest positive sample of the file's subtype; 1.0 for the others)
        at = mag >= CLIP_LEVEL * np.where(beyond, peak, _FULL_SCALE.get(sub, 1.0))
        if beyond.any():
            # (there only a flat top: a sample equal to a neighbour. Near its peak a smooth
            # unclipped wave passes the level too -- a float file's chirp at amplitude 2 read
            # "2.77 % of the samples are clipped" until 2026-12-07)
            flat = np.zeros_like(at)
            same = x[:, 1:] == x[:, :-1]
            flat[:, 1:] |= same
            flat[:, :-1] |= same
            at &= flat | ~beyond
        clipped = int(np.count_nonzero(at))
    if fs is not None and int(round(fs)) != fs_in:
        if not resample:
            raise AudioInputError(
                f"{path}: recording is sampled at {fs_in} Hz but {int(round(fs))} Hz is required; "
                "resample the file or ask for resampling"
            )
        x = _resample(x, fs_in, fs)
        fs_in = int(round(fs))
        n = x.shape[1]
        resampled = True
    if n < max(int(min_samples), 1):
        raise AudioInputError(
            f"{path}: recording is too short ({n} samples, {n / fs_in * 1000:.1f} ms); "
            f"at least {int(min_samples)} samples are needed"
        )
    finite = np.isfinite(x)
    if not np.all(finite):
        bad = int(np.size(x) - np.count_nonzero(finite))
        raise AudioInputError(f"{path}: recording contains {bad} NaN or infinite samples")
    peak = np.max(np.abs(x), axis=1)
    if whole and np.all(peak == 0):
        raise AudioInputError(f"{path}: recording is silent (all samples are zero)")
    dead = names[peak == 0]
    if dead.size:
        raise AudioInputError(
            f"{path}: channel{'s' if dead.size > 1 else ''} {', '.join(map(str, dead))} "
            "silent (all samples are zero); check the microphone wiring"
        )
    # (one constant value: an input with an offset but no microphone. It read as "no frame
    # holds a detectable source (silence or uncorrelated noise)")
    flat = names[np.ptp(x, axis=1) == 0]
    if flat.size:
        raise AudioInputError(f"{path}: {stuck_channels_text(flat)}; check the microphone "
                              "wiring")
    return _FilePart(path, x, fs_in, None if resampled else _PCM_STEP.get(sub), clipped, read,
                     names, sub)


def channel_faults(x: NDArray) -> tuple[NDArray, NDArray, float]:
    """The channels of a recording ``x`` (n_channels, n) that hold no microphone's signal: (those
    holding one constant value throughout, zeros included; the others more than
    :data:`QUIET_CHANNEL_DB` below the loudest channel; how far below it the loudest of those
    is, dB -- nan when there are none, inf when their level is 0). The level is robust -- a
    few corrupt samples of 1e30 made the others "quiet" -- the 90th percentile of the samples'
    distance from their median, over at most 2**18 evenly spread samples per channel (0.7 s
    for a minute at 48 kHz otherwise). The one rule of :func:`read_recording` (files) and
    :class:`hearsee.stream.pipeline.DeviceSource` (live input). ``x`` must be a 2-D array of
    finite real samples with one or more of each (AudioInputError else: an empty one was
    numpy's ValueError, a 1-D one its AxisError)."""
    x = as_samples(x)  # (real, finite samples)
    if x.ndim != 2 or 0 in x.shape:
        raise AudioInputError(f"recording must be (n_channels, n_samples) with one or more of "
                              f"each, got shape {x.shape}")
    constant = np.ptp(x, axis=1) == 0
    few = x[:, ::max(1, x.shape[1] >> 18)]
    level = np.percentile(np.abs(few - np.median(few, axis=1, keepdims=True)), 90.0, axis=1)
    quiet = np.flatnonzero((level < level.max() * 10.0 ** (-QUIET_CHANNEL_DB / 20.0))
                           & ~constant)
    flat = np.flatnonzero(constant)
    # (inf where the quiet ones' level is 0: nine samples in ten at one value, a disconnected
    # input flipping a bit now and then -- a numpy RuntimeWarning and "inf dB" until 2026-12-07)
    with np.errstate(divide="ignore"):
        below = (20.0 * np.log10(level.max() / level[quiet].max()) if quiet.size
                 else float("nan"))
    return flat, quiet, float(below)


def duplicate_channels(x: NDArray, step: float | None = None) -> list[tuple[int, int]]:
    """Pairs ``(i, j)``, i < j, of channels of ``x`` (n_channels, n) that hold one signal: their
    zero-lag correlation coefficient is within :data:`DUPLICATE_CHANNEL_TOL` of +1 or -1 (a
    copy, at any gain or polarity), over the same <= 2**18 evenly spread samples per channel
    as :func:`channel_faults`. With ``step``, the quantisation step of integer samples (a PCM
    file read as floats: 2**-15 for 16 bits), also those where what one channel's best scaled
    copy of the other leaves is no more than that rounding (residual RMS <= 0.4 step x
    sqrt(1 + gain**2); rounding both leaves 0.29, 16-bit copies of a voice gave 0.24-0.29),
    both channels at least 10 steps RMS: a 16-bit copy of a voice peaking at -30 dBFS left
    1 - |rho| = 4e-6, beyond the tolerance; now copies are named down to about -55 dBFS.
    Two noise-free simulated microphones hearing a voice within ~0.5 deg of their bisecting
    plane at -50 dBFS are named too (0.21 there: at that level their TDOA of < 0.05 sample is
    0); 1 deg off gave 0.46, 3 deg 1.2 (real microphones' own noise adds more).
    Constant channels are left to that function. A microphone recorded twice (a mono input
    presented as several channels) gives its pairs a TDOA of 0, i.e. a source on the plane
    that bisects them, whatever the source's direction.

    (A noise-free simulation of a source exactly as far from two microphones gives two equal
    channels too: there the pair's TDOA of 0 is the truth.)"""
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or x.shape[0] < 2:
        return []
    few = x[:, ::max(1, x.shape[1] >> 18)]
    few = few - few.mean(axis=1, keepdims=True)
    # (the norm of samples scaled to a peak of 1: squared, samples of 1e200 overflowed --
    # numpy's RuntimeWarning, printed by the CLI)
    scale = float(np.abs(few).max(initial=0.0)) or 1.0
    norm = np.linalg.norm(few / scale, axis=1) * scale
    ok = norm > 0
    u = np.zeros_like(few)
    u[ok] = few[ok] / norm[ok, None]
    rho = np.clip(np.abs(u @ u.T), 0.0, 1.0)
    dup = rho >= 1.0 - DUPLICATE_CHANNEL_TOL
    if step is not None and step > 0:
        sd = norm / np.sqrt(few.shape[1])  # (n_channels,) RMS about the mean
        with np.errstate(divide="ignore", invalid="ignore"):
            gain = sd[None, :] / sd[:, None]  # [i, j]: channel j ~ gain x channel i
            resid = sd[None, :] * np.sqrt(1.0 - rho**2)  # what fitting j from i leaves
            loud = (sd[:, None] >= 10 * step) & (sd[None, :] >= 10 * step)
            dup |= loud & (resid <= 0.4 * step * np.sqrt(1.0 + gain**2))
    i, j = np.nonzero(np.triu(dup, 1))
    return [(int(a), int(b)) for a, b in zip(i, j, strict=True)]


def duplicate_channels_text(pairs: Sequence[tuple[int, int]]) -> str:
    """What :func:`duplicate_channels`' pairs are, in words."""
    names = ", ".join(f"{i} and {j}" for i, j in pairs)
    return (f"channels {names} hold the same signal (a copy, up to gain and polarity): one "
            "microphone recorded on both, e.g. a mono input presented as several channels? "
            "Such a pair's TDOA is 0 whatever the source's direction")


def _channels(idx: NDArray) -> tuple[str, bool]:
    return f"channel{'s' * (idx.size > 1)} {', '.join(map(str, idx))}", idx.size > 1


def stuck_channels_text(flat: NDArray) -> str:
    """What :func:`channel_faults`' constant channels ``flat`` are, in words."""
    names, many = _channels(flat)
    return (f"{names} hold{'s' * (not many)} one constant value throughout (an offset, no "
            "signal)")


def quiet_channels_text(quiet: NDArray, below: float) -> str:
    """What :func:`channel_faults`' quiet channels are, in words."""
    names, many = _channels(quiet)
    how = (f"at least {below:.0f} dB below the loudest channel" if np.isfinite(below) else
           "nearly silent beside the loudest channel (nine samples in ten at one value)")
    return (f"{names} {'are' if many else 'is'} {how}: a disconnected or muted microphone? "
            "Its pairs' TDOAs, and the direction, rest on its noise alone")


def write_recording(
    path: str | Path,
    x: ArrayLike,
    fs: float,
    subtype: str = "FLOAT",
    protect: Iterable[str | Path] | str | Path | None = None,
) -> Path:
    """Write a multichannel recording ``x (n_channels, n)`` (or mono ``(n,)``) as audio.

    Parameters
    ----------
    subtype : ``"FLOAT"`` (32-bit float WAV, default) or ``"PCM_16"`` (or any soundfile
        subtype). PCM subtypes refuse samples beyond full scale (|x| > 1) instead of clipping.
    protect : path or paths, optional
        Input files that must not be overwritten; writing to one of them is an error.

    ``fs`` is a whole number of Hz (an audio file's header holds no fraction). Returns the path
    written. The format follows the suffix (``.wav``, ``.flac``, ...). An
    existing file is replaced only once the new one is complete
    (:func:`hearsee.config.replacing`): written in place, a write that failed part way (a full
    disk, Ctrl-C) left a truncated file where the earlier one was (``simulate --force``).
    """
    import soundfile as sf

    p = as_path(path, "the output path")
    fs = check_fs(fs)  # (inf: a builtin OverflowError from int(round(fs)) before)
    if fs != round(fs):  # (an audio file's header holds whole Hz: 16000.7 was written as 16001)
        raise AudioInputError(f"an audio file's sample rate is a whole number of Hz, got {fs!r}; "
                              "resample the recording to one")
    if not isinstance(subtype, str):  # (None or 16: a builtin AttributeError from .upper())
        raise AudioInputError(f"subtype must be a soundfile subtype name such as 'FLOAT' or "
                              f"'PCM_16', got {subtype!r}")
    if protect is not None:
        items = ([protect] if isinstance(protect, str | Path | os.PathLike)
                 else list(protect) if isinstance(protect, Iterable) else [protect])
        for q in items:
            if q is not None and same_file(p, as_path(q, "a protected input's path")):
                raise ConfigError(
                    f"{p}: refusing to overwrite the input file {q}; choose another output path"
                )
    output_file(p)
    y = as_samples(x, finite=False)  # (text was numpy's ValueError; NaN is named below)
    if y.ndim == 1:
        y = y[None, :]
    if y.ndim != 2 or y.shape[1] == 0:
        raise AudioInputError(f"recording must be (n_channels, n_samples), got shape {y.shape}")
    if y.shape[0] > 1024:  # (libsndfile's limit; (n, 2) was its misleading "Format not recognised")
        raise AudioInputError(
            f"recording must be (n_channels, n_samples), got shape {y.shape}: {y.shape[0]} "
            "channels is more than an audio file holds (1024); pass x.T if its rows are samples"
        )
    if not np.all(np.isfinite(y)):
        raise AudioInputError("refusing to write NaN or infinite samples")
    if subtype.upper().startswith("PCM") and np.max(np.abs(y)) > 1.0:
        raise AudioInputError(
            f"samples exceed full scale (peak {np.max(np.abs(y)):.3g} > 1) for {subtype}; "
            "scale the recording down or write FLOAT"
        )
    # the format from the user's suffix (the temporary file's is .tmp), as soundfile takes it
    fmt = os.path.splitext(str(p))[1][1:]
    if fmt.upper() not in sf.available_formats():
        raise AudioInputError(f"{p}: cannot write audio (No format specified and unable to get "
                              f"format from file extension: {str(p)!r})")
    try:
        with replacing(p) as tmp:
            sf.write(os.fsencode(tmp), y.T, int(round(fs)), subtype=subtype, format=fmt)
    except (RuntimeError, TypeError, ValueError) as exc:
        raise AudioInputError(f"{p}: cannot write audio ({exc})") from None
    return p
