"""Sound propagation from a point source to microphones.

Free field: exact fractional delays applied in the frequency domain (a linear phase on an
FFT zero-padded past the longest delay, so the delayed signal does not wrap around), 1/r
spherical spreading, near and far field alike. Known limitation (review of 2026-11-26): the
band-limited interpolation of a fractional delay has long tails, and those of the signal's
abrupt end do wrap onto its start -- for 2 s of white noise delayed by 46.6 samples, -34 dB
relative to the signal over the first 47 output samples (before the sound arrives) and -45 dB
over the first 0.3 s; below -70 dB for band-limited signals. A longer pad would remove it but
change every free-field simulation (and benchmark table) slightly; not done yet.
Rooms: pyroomacoustics' image-source model (see :func:`simulate_room`).

Frames: ``source`` and ``mics`` must be given in the same frame, metres. Room functions take
room coordinates (origin at a corner, axes along the walls) or, for :func:`simulate_room`, the
array frame plus the array origin ``array_at`` in room coordinates (axes parallel to the room's).

Timing: every simulator here returns signals whose sample 0 is the emission time, so the arrival
time at microphone k is ``r_k / c`` and ``t_i - t_j`` equals ``MicArray.tdoa(source)``
exactly -- pyroomacoustics' fractional-delay filter latency is removed.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
from numpy.typing import ArrayLike, NDArray

from hearsee.audio.arrays import MicArray
from hearsee.audio.signals import as_samples, check_fs
from hearsee.config import (
    as_float_array,
    check_rng,
    finite_number,
    is_real,
    real_entries,
    true_or_false,
    whole_number,
)
from hearsee.errors import AudioInputError, ConfigError, GeometryError
from hearsee.geometry import as_point, norm_scale, vector_length

__all__ = [
    "MAX_IMAGE_ORDER",
    "MAX_RIR_SAMPLES",
    "MAX_SNR_DB",
    "MIN_SNR_DB",
    "MIN_WALL_DISTANCE_M",
    "add_noise",
    "check_heard",
    "check_snr_db",
    "delay_signals",
    "image_sources",
    "room_impulse_responses",
    "simulate_free_field",
    "sum_responses",
    "simulate_room",
    "speed_of_sound_of",
]

#: Sources and microphones must be at least this far (metres) from every wall of a room.
MIN_WALL_DISTANCE_M = 0.05

#: The largest image-source order :func:`room_impulse_responses` asks pyroomacoustics for.
#: Its memory grows with the cube of the order (~4/3 N^3 images; 3 microphones, measured
#: 2026-11-25: order 60 0.19 GB, 100 0.49 GB, 140 1.16 GB, so ~3.4 GB at 200): a long RT60 in
#: a small room (Sabine: 5 s in a 3 m cube needs order 808) ended in a MemoryError traceback.
MAX_IMAGE_ORDER = 200

#: The longest impulse response :func:`room_impulse_responses` asks pyroomacoustics for, in
#: samples (bounded by ``(order + 1) x`` the room's diagonal: no image of that order is
#: farther). 2**25 is 35 min at 16 kHz, 87 s at 384 kHz, ~0.4 GB per microphone; a 1e9 m room
#: with RT60 0.3 s asked for 7 TiB (a MemoryError traceback).
MAX_RIR_SAMPLES = 2**25

#: The range of sensor-noise SNRs (dB) :func:`add_noise` accepts, ``[MIN_SNR_DB, MAX_SNR_DB]``.
#: Below -60 dB no source is detectable in any recording hearsee simulates: the cross-correlation
#: peak of two channels stands ~``sqrt(n) * 10**(snr/10)`` noise deviations high, under 0.02 at
#: -60 dB even for the longest simulation (600 s at 384 kHz, n = 2.3e8 samples) -- such a
#: recording is pure noise (-500 dB was written, exit 0, with a source gain of 1e-26). Above
#: 200 dB the noise (10 orders of magnitude below the signal's amplitude) is far below the
#: rounding of the written file (float32: ~-150 dB, 16-bit PCM: ~-98 dB), so the recording is the
#: one without noise (leave the SNR out); ``10**(snr/10)`` overflowed beyond ~3083 dB.
MIN_SNR_DB = -60.0
MAX_SNR_DB = 200.0


def _mic_positions(mics: MicArray | ArrayLike) -> NDArray:
    """``mics`` as finite (N, 3) positions in metres, N >= 1, else a GeometryError (no
    microphone was numpy's ValueError of an empty reduction, text its ValueError, a NaN
    coordinate "too far (beyond float range)")."""
    if isinstance(mics, MicArray):
        return mics.positions
    p = as_float_array(mics, "microphone positions", finite=False, error=GeometryError)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 1:
        raise GeometryError(f"microphone positions must be N x 3 with N >= 1, got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise GeometryError("microphone positions must be finite numbers (metres)")
    return p


def check_heard(distance_m: float, speed_of_sound: float, n_samples: int, fs: float,
                which: str = "nearest") -> None:
    """GeometryError unless the direct sound of a source ``distance_m`` metres from the
    ``which`` microphone (the nearest one unless said, the message names it) arrives within a
    simulated signal of ``n_samples`` at ``fs`` Hz (sample 0 is the emission time). A source
    farther than ``c * n / fs`` is not heard at all: its recording was silence, or the sinc
    tails of the delay filter that :func:`hearsee.sim.audio.save_recording` then scaled up to
    full scale -- written with a ground truth it does not hold (and a source 1e8 m away asked
    the delay filter for more memory than the machine had)."""
    delay_s = distance_m / speed_of_sound
    if not delay_s * fs < n_samples:
        far = f"{distance_m:.4g} m" if np.isfinite(distance_m) else "too far (beyond float range)"
        raise GeometryError(
            f"the source is {far} from the {which} microphone: its sound takes "
            f"{delay_s:.4g} s to arrive, longer than the {n_samples / fs:.4g} s simulated, so "
            "the recording would not hold it; move the source closer or simulate longer")


def speed_of_sound_of(mics: MicArray | ArrayLike, speed_of_sound: float | None) -> float:
    """The speed of sound to use, m/s: ``speed_of_sound`` when given (a finite number > 0, else
    a GeometryError), otherwise the MicArray's own, otherwise 343."""
    if speed_of_sound is None:
        return float(mics.speed_of_sound) if isinstance(mics, MicArray) else 343.0
    return finite_number("speed_of_sound (m/s)", speed_of_sound, 0.0, lo_open=True,
                         error=GeometryError)


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
        Amplitude factor per channel: finite numbers, one for all or one per delay.
    n_out : int, optional
        Output length in samples (default: ``n``).

    Returns
    -------
    array (n_ch, n_out)
        ``y[k](t) = gains[k] * signal(t - delays_s[k])`` with band-limited interpolation.

    Raises
    ------
    GeometryError
        No delay, a negative or non-finite one.
    ConfigError
        A delay longer than :data:`MAX_RIR_SAMPLES` samples (the FFT is padded past it: more
        memory than a simulation should take), gains that are not finite numbers or not one
        per delay, a bad ``n_out`` (or one more than :data:`MAX_RIR_SAMPLES` past the
        signal's length).
    """
    x = as_samples(signal, "signal")  # (text was read as numbers; NaN gave a NaN recording)
    if x.ndim != 1:
        raise AudioInputError(f"signal must be one-dimensional, got shape {x.shape}")
    fs = check_fs(fs)
    # (text was numpy's ValueError, "0.5" read as 0.5 s)
    d = np.atleast_1d(np.asarray(delays_s, dtype=float)) if real_entries(delays_s) else None
    if d is None or d.size == 0 or np.any(d < 0) or not np.all(np.isfinite(d)):
        raise GeometryError("delays must be one or more finite, non-negative numbers of seconds")
    if d.max() * fs > MAX_RIR_SAMPLES:  # (1e12 samples: a MemoryError traceback)
        raise ConfigError(
            f"a delay of {d.max():.4g} s is {d.max() * fs:.4g} samples at {fs:g} Hz, more "
            f"memory than a simulation should take (the limit is {MAX_RIR_SAMPLES} samples, as "
            "for room impulse responses); move the source closer or use a lower sample rate")
    # (a wrong count was numpy's broadcast ValueError, NaN a NaN recording)
    g = as_float_array(gains, "gains")
    if g.ndim > 1 or g.size not in (1, d.size):
        raise ConfigError(f"gains must be one number or one per delay ({d.size}), got shape "
                          f"{g.shape}")
    n_out = len(x) if n_out is None else whole_number("n_out", n_out, 0)
    if n_out > len(x) + MAX_RIR_SAMPLES:  # (1e12 samples: a MemoryError traceback)
        raise ConfigError(
            f"n_out = {n_out} samples is more than {MAX_RIR_SAMPLES} samples (the limit for "
            f"room impulse responses) past the signal's {len(x)}: more memory than a "
            "simulation should take")
    # (an n_out past the delayed signal's end used to return only n_fft samples)
    n_fft = sfft.next_fast_len(max(len(x), n_out) + int(np.ceil(d.max() * fs)) + 1, real=True)
    X = sfft.rfft(x, n_fft)
    f = np.arange(X.shape[0]) / n_fft  # cycles per sample
    phase = np.exp(-2j * np.pi * f[None, :] * (d[:, None] * fs))
    Y = X[None, :] * phase
    # keep the Nyquist bin real so that odd fractional delays stay real-valued signals
    if n_fft % 2 == 0:
        Y[:, -1] = Y[:, -1].real
    y = sfft.irfft(Y, n_fft, axis=-1)[:, :n_out]
    return y * np.broadcast_to(g.ravel(), d.shape)[:, None]


def check_snr_db(snr_db: float | None) -> float | None:
    """``snr_db`` (dB) as a float within [:data:`MIN_SNR_DB`, :data:`MAX_SNR_DB`] (None: no
    noise, returned as is), else a ConfigError. The check of :func:`add_noise`, which the
    simulators reach only once the clean signals are computed: a caller with expensive work
    before it (``hearsee simulate``) checks the SNR first with this."""
    if snr_db is None:
        return None
    if not is_real(snr_db):  # (an array was numpy's ambiguous truth value, text a TypeError)
        raise ConfigError(f"SNR must be a finite number of dB, got {snr_db!r}")
    if not MIN_SNR_DB <= snr_db <= MAX_SNR_DB:
        raise ConfigError(
            f"SNR must be within {MIN_SNR_DB:g} to {MAX_SNR_DB:g} dB, got {float(snr_db):g} dB "
            f"(below {MIN_SNR_DB:g} dB the recording is noise only; above {MAX_SNR_DB:g} dB the "
            "noise is below the rounding of the samples: leave the SNR out for no noise)")
    return float(snr_db)


def add_noise(x: ArrayLike, snr_db: float | None, rng: np.random.Generator | int | None = None,
              reference_power: float | None = None) -> NDArray:
    """Add uncorrelated white Gaussian sensor noise at ``snr_db`` (dB) per channel.

    The SNR is relative to ``reference_power`` (default: the mean power of ``x`` over all
    channels, in squared sample units). ``snr_db=None`` returns a copy of ``x``; otherwise it
    must be within [:data:`MIN_SNR_DB`, :data:`MAX_SNR_DB`] dB (:func:`check_snr_db`), else a
    ConfigError.
    """
    y = np.array(as_samples(x, "signal", finite=False), dtype=float)  # (text: read as numbers)
    snr_db = check_snr_db(snr_db)
    check_rng(rng)  # (numpy's TypeError / ValueError on text, 1.5, -1; unchecked without noise)
    if snr_db is None:
        return y
    rng = np.random.default_rng(rng)
    if reference_power is not None:  # (float() read the text "1" as 1.0)
        p = finite_number("reference_power", reference_power, 0.0, lo_open=True)
    elif y.size == 0:  # (its mean power was NaN: "signal contains NaN or inf samples")
        raise AudioInputError("cannot set an SNR for an empty signal (no samples)")
    else:
        p = float(np.mean(y**2))
    if not np.isfinite(p):
        raise AudioInputError("signal contains NaN or inf samples")
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
        Per-channel SNR of added white sensor noise in dB (relative to the mean received
        power), within [:data:`MIN_SNR_DB`, :data:`MAX_SNR_DB`]; None = no noise.
    speed_of_sound : float, optional
        Defaults to the MicArray's value or 343 m/s.

    Returns
    -------
    array (n_mics, n)
        The microphone signals with their absolute propagation delays ``r_k / c`` (near field)
        or plane-wave delays relative to the first-hit microphone (far field), so ``t_i - t_j``
        is exactly ``MicArray.tdoa(source)`` (or ``tdoa_far``).

    Raises
    ------
    GeometryError
        Near field: a source at a microphone, or one whose direct sound reaches the farthest
        microphone only after the signal's ``n`` samples (:func:`check_heard`).
    """
    pos = _mic_positions(mics)
    c = speed_of_sound_of(mics, speed_of_sound)
    check_rng(rng)  # (before the work: add_noise draws from it at the end)
    far_field = true_or_false("far_field", far_field)  # ("no" gave a plane wave)
    # (text was numpy's ValueError)
    s = np.asarray(source, dtype=float) if real_entries(source) else np.zeros(0)
    if s.shape != (3,) or not np.all(np.isfinite(s)):
        raise GeometryError(f"source must be a finite [x, y, z] point, got {source!r:.60}")
    if far_field:
        s = s / norm_scale(s)  # (the direction of a source 1e300 m away, without overflow)
        if not np.linalg.norm(s) > 0:
            raise GeometryError("a far-field (plane-wave) source needs a direction; the source is "
                                "at the array-frame origin")
        u = s / np.linalg.norm(s)
        t = -(pos @ u) / c
        t = t - t.min()
        gains = np.ones(len(pos))
    else:
        d = pos - s
        r = vector_length(d)  # (a source 1e300 m away: that distance, refused just below)
        if np.any(r < 1e-3):
            raise GeometryError("the source coincides with a microphone")
        # every microphone must hear it: the farthest one's direct sound arriving after the
        # signal's end left that channel without it (the nearest one was checked)
        # (the signal checked first: np.size of the text "abc" is 1, a source "too far")
        x = as_samples(signal, "signal")
        if x.ndim != 1:
            raise AudioInputError(f"signal must be one-dimensional, got shape {x.shape}")
        check_heard(float(r.max()), c, x.size, check_fs(fs), "farthest")
        t = r / c
        gains = 1.0 / r
    y = delay_signals(signal, t, fs, gains)
    return add_noise(y, snr_db, rng)


# ---------------------------------------------------------------------------- rooms
def _room_dim(room_dim: ArrayLike) -> NDArray:
    d = as_float_array(room_dim, "room dimensions", finite=False, error=GeometryError)
    if d.shape != (3,) or not np.all(np.isfinite(d)) or np.any(d <= 0):
        raise GeometryError(
            f"room dimensions must be three positive lengths [L, W, H] in metres, got {room_dim!r}"
        )
    return d


def _check_inside(points: NDArray, dim: NDArray, what: str) -> None:
    """GeometryError unless every point (n, 3) is >= MIN_WALL_DISTANCE_M inside the room."""
    margin = np.minimum(points, dim - points).min(axis=-1)
    bad = np.flatnonzero(margin < MIN_WALL_DISTANCE_M)
    if bad.size:
        k = int(bad[0])
        where = "outside the room" if margin[k] < 0 else "too close to a wall"
        label = f"{what} {k}" if len(points) > 1 else what
        raise GeometryError(
            f"{label} at {np.round(points[k], 3).tolist()} m (room coordinates) is {where} "
            f"{np.round(dim, 3).tolist()} m; keep it at least {MIN_WALL_DISTANCE_M} m "
            "from every wall"
        )


def _fractional_delay_latency() -> int:
    """Samples by which pyroomacoustics' fractional-delay filters delay every RIR."""
    import pyroomacoustics as pra

    return int(pra.constants.get("frac_delay_length")) // 2


def image_sources(rt60: float, room_dim: ArrayLike, speed_of_sound: float = 343.0,
                  max_order: int | None = None) -> tuple[float | None, int]:
    """Wall energy absorption and image-source order for a shoebox room of reverberation time
    ``rt60`` (seconds) and size ``room_dim`` (metres), from Sabine's formula
    (``pyroomacoustics.inverse_sabine``); ``(None, 0)`` for an anechoic room (``rt60`` 0).
    ``max_order`` overrides the order. The one place where a room's RT60 is checked:
    :func:`room_impulse_responses` and the robot scenario files use it.

    Raises
    ------
    ConfigError
        A negative or non-finite RT60, one the room cannot have (too short for its size), a
        bad ``max_order``, or an order above :data:`MAX_IMAGE_ORDER` (too much memory).
    GeometryError
        Room dimensions that are no three positive lengths, a speed of sound that is no
        finite number > 0 (m/s).
    """
    import pyroomacoustics as pra

    dim = _room_dim(room_dim)
    # (text was a builtin TypeError inside pyroomacoustics, 0 or NaN "RT60 too short")
    speed_of_sound = speed_of_sound_of(None, speed_of_sound)
    if not is_real(rt60) or rt60 < 0:
        raise ConfigError(f"RT60 must be a non-negative number of seconds, got {rt60!r}")
    rt60 = float(rt60)
    if max_order is not None and (not is_real(max_order) or int(max_order) != max_order
                                  or max_order < 0):
        raise ConfigError(f"max_order must be a non-negative integer, got {max_order!r}")
    if rt60 == 0 and max_order:
        # (pyroomacoustics' default walls reflect everything: the images would come back)
        raise ConfigError(f"max_order {max_order} with RT60 0: an anechoic room has no "
                          "reflections; give an RT60 > 0 or leave max_order out")
    if rt60 == 0:
        return None, 0
    try:
        e_absorption, order = pra.inverse_sabine(rt60, dim, c=speed_of_sound)
    except ValueError:
        raise ConfigError(
            f"RT60 {rt60} s is too short for a {'x'.join(f'{v:g}' for v in dim)} m room "
            "(it would need walls absorbing more than all incident sound); "
            "use a longer RT60 or a smaller room"
        ) from None
    except OverflowError:
        # (pyroomacoustics' order int(ceil(c RT60 / R - 1)) is infinite where a side of
        # 1e300 m overflows its square, R = 0, or c RT60 overflows: a traceback before)
        raise ConfigError(
            f"RT60 {rt60:g} s in a {'x'.join(f'{v:g}' for v in dim)} m room: the image-source "
            "order overflows (infinite); use a smaller room or a shorter RT60") from None
    if max_order is not None:
        order = int(max_order)
    if order > MAX_IMAGE_ORDER:
        # (an RT60 of 1e300 s gave an order of 300 digits, whose image count overflowed a
        # float: an OverflowError traceback instead of this message)
        images = (f"~{4 / 3 * float(order) ** 3:.1e}" if order < 1e100 else "over 1e+300")
        raise ConfigError(
            f"RT60 {rt60:g} s in a {'x'.join(f'{v:g}' for v in dim)} m room needs image sources "
            f"up to order {order if order < 1e9 else f'{float(order):.3g}'} ({images} images, "
            f"more memory than a simulation should take; the limit is order {MAX_IMAGE_ORDER}); "
            "use a shorter RT60 or a larger room"
            + (", or a smaller max_order" if max_order is not None else ""))
    return float(e_absorption), int(order)


def sum_responses(parts: list[NDArray]) -> NDArray:
    """Impulse responses of different lengths -- (n_mics, L_k) each, sample 0 the same
    instant -- added into one (n_mics, max L_k) array (the shorter ones end in zeros): the
    parts of a response rendered apart (a masked room's early and late reflections). None, or
    parts that are no 2-D arrays of as many microphones, are a GeometryError."""
    if not parts or any(not isinstance(p, np.ndarray) or p.ndim != 2 for p in parts) \
            or len({p.shape[0] for p in parts}) != 1:
        raise GeometryError("sum_responses: expected one or more (n_mics, n_samples) arrays of "
                            "the same n_mics, got shapes "
                            f"{[getattr(p, 'shape', type(p).__name__) for p in parts or []]}")
    out = np.zeros((parts[0].shape[0], max(p.shape[1] for p in parts)))
    for p in parts:
        out[:, :p.shape[1]] += p
    return out


def room_impulse_responses(
    fs: float,
    mic_positions_room: ArrayLike,
    source_room: ArrayLike,
    room_dim: ArrayLike,
    rt60: float,
    max_order: int | None = None,
    speed_of_sound: float = 343.0,
    align: bool = True,
    directivities: list | None = None,
) -> NDArray:
    """Room impulse responses of a shoebox room from pyroomacoustics' image-source model.

    Parameters
    ----------
    fs : float
        Sample rate in Hz.
    mic_positions_room : array (n_mics, 3)
        Microphone positions in room coordinates (metres, origin at a corner).
    source_room : array (3,)
        Source position in room coordinates, metres.
    room_dim : array (3,)
        Room length, width, height in metres.
    rt60 : float
        Reverberation time in seconds; ``0`` gives the anechoic direct path only. The wall
        absorption and image order come from Sabine's formula (``pra.inverse_sabine``).
    max_order : int, optional
        Override the image-source order (e.g. to trade accuracy for speed).
    speed_of_sound : float
        c0 in m/s (the array's, so room TDOAs match ``MicArray.tdoa``).
    align : bool
        Remove the fractional-delay filter latency so that sample 0 is the emission time (the
        direct path to microphone k peaks at ``r_k / c * fs``). The filters' pre-ringing
        before time 0 is then cut off (affects only sources closer than ~40 samples * c).
    directivities : list, optional
        One pyroomacoustics directivity per microphone (e.g. a
        ``pyroomacoustics.directivities.MeasuredDirectivity`` of impulse responses, applied
        to each image source by its direction of arrival; the masked arrays' reflections,
        :func:`hearsee.audio.mask.simulate_masked_room`); None = omnidirectional.

    Returns
    -------
    array (n_mics, L)
        Impulse responses; the direct path has amplitude ``1 / r`` (as :func:`simulate_free_field`).

    Raises
    ------
    GeometryError
        A point outside the room or closer than :data:`MIN_WALL_DISTANCE_M` to a wall.
    ConfigError
        A negative RT60, or one the room cannot have (too short for its size).
    """
    import pyroomacoustics as pra

    dim = _room_dim(room_dim)
    # (text, a ragged list or no microphone was numpy's or pyroomacoustics' ValueError)
    mics = np.atleast_2d(as_float_array(mic_positions_room, "microphone positions",
                                        finite=False, error=GeometryError))
    src = as_float_array(source_room, "source", finite=False, error=GeometryError)
    if mics.ndim != 2 or mics.shape[1] != 3 or len(mics) < 1 or not np.all(np.isfinite(mics)):
        raise GeometryError(f"microphone positions must be finite N x 3, got shape {mics.shape}")
    if src.shape != (3,) or not np.all(np.isfinite(src)):
        raise GeometryError(f"source must be a finite [x, y, z] point, got {source_room!r}")
    _check_inside(mics, dim, "microphone")
    _check_inside(src[None, :], dim, "source")
    if np.any(np.linalg.norm(mics - src, axis=1) < 1e-3):
        raise GeometryError("the source coincides with a microphone")
    fs = check_fs(fs)
    speed_of_sound = speed_of_sound_of(None, speed_of_sound)
    e_absorption, order = image_sources(rt60, dim, speed_of_sound, max_order)
    n_rir = (order + 1) * float(np.linalg.norm(dim)) / speed_of_sound * fs
    if n_rir > MAX_RIR_SAMPLES:
        raise ConfigError(
            f"a {'x'.join(f'{v:g}' for v in dim)} m room (image order {order}) has impulse "
            f"responses up to {n_rir / fs:.3g} s long ({n_rir:.3g} samples at {fs:g} Hz, more "
            f"memory than a simulation should take; the limit is {MAX_RIR_SAMPLES} samples); "
            "use a smaller room, a shorter RT60 or a lower sample rate")
    materials = None if e_absorption is None else pra.Material(e_absorption)
    room = pra.ShoeBox(dim, fs=int(round(fs)), materials=materials, max_order=int(order))
    room.set_sound_speed(float(speed_of_sound))
    room.add_source(src)
    if directivities is None:
        room.add_microphone_array(mics.T.copy())
    else:
        if not isinstance(directivities, list | tuple) or len(directivities) != len(mics):
            got = (len(directivities) if isinstance(directivities, list | tuple)
                   else type(directivities).__name__)
            raise ConfigError(f"expected one directivity per microphone ({len(mics)}), got {got}")
        room.add_microphone_array(pra.MicrophoneArray(mics.T.copy(), room.fs,
                                                      directivity=list(directivities)))
    room.compute_rir()
    rirs = [np.asarray(room.rir[m][0], dtype=float) for m in range(len(mics))]
    out = np.zeros((len(rirs), max(len(h) for h in rirs)))
    for m, h in enumerate(rirs):
        out[m, : len(h)] = h
    if align:
        out = out[:, _fractional_delay_latency():]
    return out


def simulate_room(
    signal: ArrayLike,
    fs: float,
    array: MicArray,
    source: ArrayLike,
    room_dim: ArrayLike,
    rt60: float,
    array_at: ArrayLike,
    snr_db: float | None = None,
    rng: np.random.Generator | int | None = None,
    mic_positions: ArrayLike | None = None,
    max_order: int | None = None,
) -> NDArray:
    """Record ``signal`` emitted at ``source`` by ``array`` placed in a shoebox room.

    Parameters
    ----------
    signal : array (n,)
        Source waveform (at 1 m from the source).
    fs : float
        Sample rate in Hz.
    array : MicArray
        The microphones (array frame) and speed of sound.
    source : array (3,)
        Source position in the ARRAY frame, metres.
    room_dim : array (3,)
        Room length, width, height in metres.
    rt60 : float
        Reverberation time in seconds (0 = anechoic room, direct path only).
    array_at : array (3,)
        Position of the array-frame origin in room coordinates; the array axes are parallel
        to the room's.
    snr_db : float, optional
        Per-channel SNR of added white sensor noise in dB (relative to the mean received
        power), within [:data:`MIN_SNR_DB`, :data:`MAX_SNR_DB`]; None = no noise.
    mic_positions : array (n_mics, 3), optional
        Microphone positions in the array frame overriding ``array.positions`` (e.g. a rotated
        head from ``hearsee.geometry.mic_positions_at``).
    max_order : int, optional
        Image-source order override (see :func:`room_impulse_responses`).

    Returns
    -------
    array (n_mics, n)
        Sample 0 is the emission time: the direct path reaches microphone k at ``r_k / c``,
        so the direct-path TDOAs equal ``MicArray.tdoa(source)``.
    """
    from scipy.signal import fftconvolve

    # (as delay_signals for the free field: text was numpy's ValueError, booleans were read as
    # 0/1, and a NaN or infinite sample gave an all-NaN recording without a word)
    x = as_samples(signal, "signal")
    if x.ndim != 1 or x.size == 0:
        raise AudioInputError(f"signal must be a non-empty 1-D array, got shape {x.shape}")
    check_rng(rng)  # (before the work: add_noise draws from it at the end)
    if not isinstance(array, MicArray):  # (a preset name was a builtin AttributeError)
        raise GeometryError(f"array: expected a MicArray, got {type(array).__name__}")
    pos = array.positions if mic_positions is None else _mic_positions(mic_positions)
    if len(pos) != array.n_mics:
        raise GeometryError(
            f"mic_positions has {len(pos)} rows but array {array.name!r} has {array.n_mics} "
            "microphones"
        )
    # (text or a ragged list was numpy's ValueError, True read as 1 m)
    at = as_point(array_at, "array_at")
    src = as_point(source, "source")
    # (every microphone must hear it: only the nearest one was checked)
    check_heard(float(np.linalg.norm(pos - src, axis=1).max()), array.speed_of_sound, x.size,
                check_fs(fs), "farthest")
    h = room_impulse_responses(fs, pos + at, src + at, room_dim, rt60, max_order=max_order,
                               speed_of_sound=array.speed_of_sound, align=False)
    lat = _fractional_delay_latency()
    y = fftconvolve(x[None, :], h, axes=-1)[:, lat: lat + len(x)]
    if y.shape[1] < len(x):  # signal shorter than the latency: pad the end
        y = np.pad(y, ((0, 0), (0, len(x) - y.shape[1])))
    return add_noise(y, snr_db, rng)
