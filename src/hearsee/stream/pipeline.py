"""Real-time tracking: source -> framer -> TDOA -> ITD filter -> localizer -> tracker -> sink.

Modelled on ODAS (Grondin & Michaud, "Lightweight and optimized sound source localization and
tracking methods for open and closed microphone array configurations", Robotics and Autonomous
Systems 113, 2019): small stages with explicit configuration, connected by a bounded queue.

* **Sources** yield :class:`Block` s of samples with their absolute start sample, their sequence
  number and the wall-clock time they became available. :class:`ArraySource` / :class:`WavSource`
  read memory or a file (optionally paced in real time), :class:`DeviceSource` reads a live
  microphone through sounddevice/PortAudio (imported lazily; a missing PortAudio library is a
  clear :class:`~hearsee.errors.AudioInputError`). A device callback never blocks: when the bounded
  queue is full the block is dropped and counted, which shows downstream as a gap in the
  sequence numbers. :class:`DropoutSource` simulates dropped, late and stalled blocks.
* :class:`Framer` cuts the block stream into analysis frames (``frame_ms`` every ``hop_ms``).
  Frames that would need samples of a dropped block are emitted as *missing* (the trackers then
  predict through them); a block that arrives after its samples were declared lost is *late* and
  is discarded. Frames are emitted in batches (all complete frames of a block) so that the
  stages run vectorised over the batch.
* :class:`FrameGcc` (each frame's own GCC TDOAs: :func:`hearsee.audio.tdoa.estimate_tdoas`
  without its whole-recording summary, each frame's activity decided causally by
  :class:`FrameActivity`, so that no result depends on the block size) and
  :class:`SmoothedSrp` (recursively smoothed cross spectra steered over a direction grid,
  its steering matrix precomputed once, single precision) are the measurement stages; a
  masked pair (thesis ch. 3) has :class:`SmoothedMask` instead of the steered response: the
  mask's front/back decision (:func:`hearsee.audio.mask.localize_spectra`) on recursively
  averaged spectra puts each frame's ITD in its half (since 2026-12-05; refused before).
* :class:`TrackingProcessor` holds the TDOA, ITD-filter
  (:class:`~hearsee.audio.itd_filter.ItdKalman`), localizer
  (:func:`~hearsee.audio.localize.localize_tdoa`) and tracker stages
  (:class:`~hearsee.audio.tracking.DirectionKalman`; with a calibrated camera and image points,
  the camera-ray + ITD fix of :func:`~hearsee.fusion.audiovisual.locate_on_ray` and the gated
  constant-velocity :class:`~hearsee.fusion.audiovisual.RayTracker`, or with
  ``motion_model="ca"`` the constant-acceleration :class:`~hearsee.audio.tracking.MotionKalman`).
* :class:`StreamPipeline` runs them: in-line (fastest, for files) or with the source in its own
  thread behind a bounded queue (live input). The consumer waits at most ``stall_timeout_s`` for
  a block; a source that stays silent longer than ``max_stall_s`` ends the run with
  ``stats.status == "stalled"`` instead of hanging, and so does a source that gives up on a
  silent device itself (:class:`DeviceSource` after its ``timeout_s``). Each :class:`Update`
  carries its latency: wall-clock time from the arrival of the block that completed the frame
  to its emission.

Performance (three-mic preset, 16 kHz, 64 ms frames every 32 ms, ``bench/tracking.py`` part C):
per batch the work is a few numpy calls on (frames x pairs x bins) arrays; what remains per
frame in Python is the closed-form localizer and the Kalman step. BLAS is held to one thread
during a run (small products; thread hand-off on a busy machine cost more than it gave).

Units: seconds, degrees, metres; frame times are frame centres from the start of the stream.
"""

from __future__ import annotations

import contextlib
import math
import queue
import threading
import time
import warnings
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hearsee.audio.arrays import MicArray, load_array
from hearsee.audio.hum import LineFilter, check_lines, filter_lines, find_lines, warn_lines
from hearsee.audio.itd_filter import ITD_STD_RANGE_S, ItdKalman
from hearsee.audio.localize import array_geometry, localize_tdoa
from hearsee.audio.signals import (
    as_samples,
    channel_faults,
    check_fs,
    duplicate_channels,
    duplicate_channels_text,
    microphone_channels,
    quiet_channels_text,
    stuck_channels_text,
    unit_peak_scale,
)
from hearsee.audio.sources import TALKER_MODES_DPS2, TALKER_PEAK_RATIO
from hearsee.audio.tdoa import (
    DEFAULT_MARGIN_SAMPLES,
    DEFAULT_SMOOTH_FRAMES,
    DEFAULT_WINDOW,
    EMPTY_BAND_DB,
    MAX_UNSCALED_PEAK,
    MIN_UNSCALED_PEAK,
    TdoaFrames,
    _peak_level,
    check_analysis_fs,
    check_frame_ms,
    check_recording_length,
    estimate_tdoas,
    frame_geometry,
    frame_signals,
    frame_spectra,
    gcc_nfft,
    min_frame_ms,
    normalize_method,
)
from hearsee.audio.tracking import (
    DIRECTION_ANGLE_NOISE_RATIO,
    DIRECTION_RATE_TAU_S,
    ELEVATION_ACCEL_RATIO,
    IMM_MODES_DPS2,
    MAX_DELAY_S,
    NOISE_RANGE,
    DirectionIMM,
    DirectionKalman,
    MotionKalman,
)
from hearsee.config import (
    as_float_array,
    finite_number,
    is_real,
    real_entries,
    time_limit,
    true_or_false,
    whole_number,
)
from hearsee.errors import (
    AudioInputError,
    ConfigError,
    DegenerateInputWarning,
    EstimationError,
    GeometryError,
)
from hearsee.geometry import wrap_deg
from hearsee.stream.device import import_sounddevice, resolve_input_device

__all__ = [
    "ArraySource",
    "Block",
    "DeviceSource",
    "DropoutSource",
    "FrameBatch",
    "Framer",
    "StreamConfig",
    "StreamPipeline",
    "StreamStats",
    "TrackingProcessor",
    "Update",
    "WavSource",
    "wiring_estimate",
]


# ---------------------------------------------------------------------------- data
@dataclass
class Block:
    """A block of samples from a source.

    seq : int            sequence number (0, 1, 2, ...); a gap means blocks were dropped
    start : int          absolute index of the first sample (sample 0 = start of the stream)
    data : (n_ch, n)     samples, row k = microphone k
    arrival : float      ``time.perf_counter()`` when the block became available
    """

    seq: int
    start: int
    data: NDArray
    arrival: float


def block_samples(data: ArrayLike, n_channels: int) -> NDArray:
    """A block's samples as a float (n_channels, n) array; AudioInputError when it has another
    shape (a source or device delivering other channels than it declared)."""
    a = np.asarray(data, dtype=float)
    if a.ndim != 2 or a.shape[0] != n_channels:
        raise AudioInputError(f"block has shape {a.shape}; expected {n_channels} channels")
    return a


@dataclass
class FrameBatch:
    """Consecutive analysis frames produced by one block.

    ``t`` (k,) frame-centre times in seconds; ``missing`` (k,) True where the frame lost samples
    to a dropped block; ``segment`` (n_ch, frame_len + (m - 1) * hop) holds the m complete
    frames (the non-missing ones, which come last) or None.
    """

    t: NDArray
    missing: NDArray
    segment: NDArray | None
    arrival: float


@dataclass
class Update:
    """One tracker output per analysis frame (the JSON line of ``hearsee track``).

    ``azimuth_deg``/``elevation_deg`` (deg), ``position_m`` (m), ``velocity_mps``,
    ``acceleration_mps2`` and ``covariance`` (2x2 deg^2 for a direction, 3x3 m^2 for a position)
    are the trackers' filtered estimates; ``velocity_mps`` is None until the 3D track's
    measurements have determined it (:attr:`~hearsee.audio.tracking.MotionKalman.velocity_known`:
    a new track's velocity is its prior, 0 m/s), ``acceleration_mps2`` likewise and always
    with the default constant-velocity 3D tracker, which does not estimate one
    (``motion_model="ca"`` does). The direction covariance is the tracker's own and
    conservative: its measurement noise is declared several times the measurements' actual
    error (see ``StreamConfig.sigma_srp_deg``), so on ``bench/tracking.py``'s room walks (RT60
    0.3 s, 10 / 20 dB; measured 2026-11-27) the actual azimuth error was 0.2-0.45 times the
    reported standard deviation for voices and 0.7 times for white noise. The default 3D
    tracker's position covariance is its filter's own scaled by
    :data:`~hearsee.fusion.audiovisual.RAY_COVARIANCE_SCALE`: 95 % ellipsoids held the truth
    for 0.87-0.94 of the frames of held-out part-B room walks at 20 dB (the filter's own
    0.61-0.70), but only 0.57-0.75 at 10 dB (own 0.25-0.40). The opt-in 3D trackers report
    their own, unscaled: on 24 such walks at 20 dB (seeds 8 / 9) 0.59 / 0.72
    (``ray_measurements="fix"``) and 0.78 / 0.76 (``motion_model="ca"``). ``raw_*``
    are this frame's own measurements (None when the frame gave none):
    ``raw_azimuth_deg``/``raw_elevation_deg`` the direction of its own GCC TDOAs, also with
    ``itd_filter``; ``itd_azimuth_deg``/``itd_elevation_deg`` the direction of the
    ITD-filtered TDOAs (None without ``itd_filter`` and on frames whose TDOAs the filter did
    not take -- none, or rejected by its gate). Neither is necessarily what the direction
    tracker receives: it takes the frame's own direction (the ITD-filtered one with
    ``itd_filter``) only from a confident frame (``StreamConfig.prefer_frame``, or a GCC
    confidence of at least ``prefer_frame_confidence``) or with ``spectrum_alpha=0``; with
    the default ``spectrum_alpha`` (0.5) any other frame gives it the smoothed steered
    response's candidate (with its age as measurement delay) or nothing, and ``measured``
    says whether it took a measurement. (Until 2026-12-02 this said the tracker receives
    ``itd_*``.) ``confidence`` is the frame's GCC peak-to-second-peak ratio (the smallest
    pair's; 0 when the frame gave no TDOAs): 0 to :data:`hearsee.audio.tdoa.MAX_CONFIDENCE`
    (1000), above 1 where the peak stands out, not a probability. ``latency_s`` is the
    wall-clock time from the arrival of the block that completed the frame to the update.
    ``masked``: the array is a masked pair; then ``front_probability`` is its stream's
    front/back decision (:class:`SmoothedMask`; the score of
    :attr:`hearsee.audio.mask.MaskLocalization.front_probability`, None before the first),
    and the JSON line carries it (other arrays' lines do not have the key). ``sources``
    (with ``StreamConfig.max_sources``, else None and not in the JSON line): the talkers
    reported at this frame by :class:`hearsee.audio.sources.SourceTracker` on the frames' own
    directions (and their steered responses' second maxima, ``talker_peak_ratio``), the
    most weight of recent frames first, each ``{"id"`` (the track's number: the same for as
    long as it is followed, never another talker's in one stream, also where the stream
    leaves a dead microphone out and goes on with a new :class:`TrackingProcessor`)
    ``, "azimuth_deg"`` (a pair's front twin: its
    mirror is as likely) ``, "rate_dps"`` (None for a pair, whose track is in its angle's sine)
    ``, "last_heard_s"`` (the time of its last frame; it is predicted through a pause)
    ``, "n_frames"}``. The single-talker fields above are the one direction tracker's, as
    without it.
    """

    t: float
    azimuth_deg: float | None
    elevation_deg: float | None
    position_m: list[float] | None
    velocity_mps: list[float] | None
    acceleration_mps2: list[float] | None
    covariance: list[list[float]] | None
    confidence: float
    rate_dps: list[float] | None = None
    measured: bool = False
    missing: bool = False
    latency_s: float = float("nan")
    raw_azimuth_deg: float | None = None
    raw_elevation_deg: float | None = None
    raw_position_m: list[float] | None = None
    itd_azimuth_deg: float | None = None
    itd_elevation_deg: float | None = None
    front_probability: float | None = None
    masked: bool = False
    sources: list[dict[str, Any]] | None = None

    @property
    def bearing_decided(self) -> bool:
        """Whether ``azimuth_deg`` is a direction to act on: given, and for a masked pair
        once its stream has decided a half (``front_probability`` not None) -- before that
        the tracker follows either mirror candidate (a talker at 150 deg was tracked at 20 deg
        for the first 0.13 s, and the live robot turned toward it)."""
        return self.azimuth_deg is not None and (not self.masked
                                                 or self.front_probability is not None)

    def to_json(self) -> dict[str, Any]:
        """The JSON object of the CLI contract (plus ``rate_dps``, ``measured``, ``missing``,
        ``latency_ms``)."""
        return {
            "t": round(self.t, 6),
            "azimuth_deg": self.azimuth_deg,
            "elevation_deg": self.elevation_deg,
            "position_m": self.position_m,
            "velocity_mps": self.velocity_mps,
            "acceleration_mps2": self.acceleration_mps2,
            "covariance": self.covariance,
            "confidence": self.confidence,
            "rate_dps": self.rate_dps,
            "measured": self.measured,
            "missing": self.missing,
            "latency_ms": None if not np.isfinite(self.latency_s) else self.latency_s * 1e3,
            # (a masked pair's: the stream's front/back decision, null before its first one;
            # absent for other arrays)
            **({"front_probability": self.front_probability} if self.masked else {}),
            # (with StreamConfig.max_sources: the talkers reported at this frame)
            **({"sources": self.sources} if self.sources is not None else {}),
        }


@dataclass
class StreamStats:
    """What happened during a run.

    ``n_blocks`` blocks processed; ``n_dropped_blocks`` blocks that never arrived (gaps in the
    sequence numbers and the device's own count of blocks it dropped, each block once);
    ``n_late_blocks`` blocks that arrived too late to be used (not also counted as dropped);
    ``n_frames`` updates, ``n_missing_frames`` of them frames that lost samples to a dropped or
    late block; ``n_stalls`` waits of ``stall_timeout_s`` without a block; ``n_overflows`` input
    overflows the device reported (PortAudio discarded samples; the blocks' worth of samples lost
    count as dropped blocks); ``audio_s`` seconds of audio received (the end of the newest
    block, also during the run: a sink reads the audio clock's present there); ``status``
    ``"ok"``, ``"stalled"`` (the source went silent: for longer than the pipeline's
    ``max_stall_s``, or the source gave up itself, as
    :class:`DeviceSource` does after its ``timeout_s``) or ``"interrupted"`` (Ctrl-C: the run
    re-raises the KeyboardInterrupt; the stats describe what was processed until then, as they
    do after an error); ``tonal_lines_hz`` the lines of stationary tonal noise (mains hum)
    notched out of the input (Hz; the pipeline's ``tonal_lines_hz``, or those the live input's
    check found), empty when none; ``dead_microphones`` those the live input's check found
    dead and the stream left out from then on (the other microphones localize as an array of
    their own; empty when none).
    """

    n_blocks: int = 0
    n_frames: int = 0
    n_missing_frames: int = 0
    n_dropped_blocks: int = 0
    n_late_blocks: int = 0
    n_stalls: int = 0
    n_overflows: int = 0
    audio_s: float = 0.0
    wall_s: float = 0.0
    cpu_s: float = 0.0
    latencies_s: list[float] = field(default_factory=list)
    status: str = "ok"
    tonal_lines_hz: tuple[float, ...] = ()
    dead_microphones: tuple[int, ...] = ()

    @property
    def real_time_factor(self) -> float:
        """Seconds of audio processed per second of wall-clock time."""
        return self.audio_s / self.wall_s if self.wall_s > 0 else float("inf")

    @property
    def cpu_real_time_factor(self) -> float:
        """Seconds of audio per second of process CPU time (fair on a loaded machine)."""
        return self.audio_s / self.cpu_s if self.cpu_s > 0 else float("inf")

    def latency_summary(self) -> dict[str, float]:
        """Mean, median, 95th percentile and max per-frame latency in milliseconds."""
        if not self.latencies_s:
            return {"mean_ms": float("nan"), "median_ms": float("nan"),
                    "p95_ms": float("nan"), "max_ms": float("nan")}
        a = np.asarray(self.latencies_s) * 1e3
        return {"mean_ms": float(a.mean()), "median_ms": float(np.median(a)),
                "p95_ms": float(np.percentile(a, 95)), "max_ms": float(a.max())}


# ---------------------------------------------------------------------------- sources
class Source(Protocol):
    fs: float
    n_channels: int

    def blocks(self) -> Iterator[Block]: ...


#: The sample magnitudes :class:`ArraySource` streams as they are; beyond, it scales the
#: recording by a power of two (the stages work in single precision: 3.4e38 at most, 1.2e-38
#: the smallest normal number)
_SINGLE_SAFE = (1e-30, 1e30)


class ArraySource:
    """Blocks of an in-memory recording ``x`` (n_ch, n) at ``fs`` Hz.

    ``realtime=True`` paces the blocks at the sample rate (a file played like a device).
    """

    def __init__(self, x: ArrayLike, fs: float, block_len: int = 2048,
                 realtime: bool = False) -> None:
        a = as_samples(x)
        if a.ndim != 2 or a.shape[1] == 0:
            raise AudioInputError(f"recording must be (n_channels, n_samples), got {a.shape}")
        # (NaN raised numpy's ValueError; 2.5 was truncated to 2 -- DeviceSource's rule: a
        # float, 2.0 included, is refused rather than rounded)
        block_len = whole_number("block_len", block_len)
        # samples beyond single precision's comfortable range (float files: 1e200, 1e-300) are
        # scaled by a power of two -- exact, and every stage is scale-free: the stages' single
        # precision made 1e200 infinite ("NaN or infinite samples") and 1e-300 zero
        peak = float(np.max(np.abs(a), initial=0.0))
        if peak > 0.0 and not _SINGLE_SAFE[0] <= peak <= _SINGLE_SAFE[1]:
            a = a * unit_peak_scale(peak)
        # (a rate of 0 divided by zero in the stream; a negative one read as "frame too short")
        self.x, self.fs, self.block_len = a, check_fs(fs), block_len
        self.n_channels = a.shape[0]
        self.realtime = bool(realtime)

    @property
    def end_sample(self) -> int:
        """Samples the stream covers (the recording's length): where it ends, also when a
        wrapper (:class:`DropoutSource`) loses its last blocks."""
        return int(self.x.shape[1])

    def blocks(self) -> Iterator[Block]:
        t0 = time.perf_counter()
        for seq, start in enumerate(range(0, self.x.shape[1], self.block_len)):
            data = self.x[:, start:start + self.block_len]
            if self.realtime:
                due = t0 + (start + data.shape[1]) / self.fs
                delay = due - time.perf_counter()
                if delay > 0:
                    time.sleep(delay)
            yield Block(seq, start, data, time.perf_counter())


class WavSource(ArraySource):
    """Blocks of a multichannel audio file, or of one file per microphone (their channels
    file by file), validated by :func:`hearsee.audio.signals.read_recording` (``channels``:
    the input channel of each microphone, as there). ``paths``: the files; ``path``: the
    first one."""

    def __init__(self, path: str | Path | Sequence[str | Path],
                 n_channels: int | Any | None = None,
                 block_len: int = 2048, realtime: bool = False, fs: float | None = None,
                 channels: Sequence[int] | NDArray | None = None) -> None:
        from hearsee.audio.signals import read_recording, recording_paths

        x, rate = read_recording(path, n_channels=n_channels, fs=fs, channels=channels)
        super().__init__(x, rate, block_len, realtime)
        self.paths = recording_paths(path)
        self.path = self.paths[0]


class MappedSource:
    """A stream source seen through a channel map: picks the input channel of each microphone
    (``channels``), ends after ``duration_s`` seconds of audio (> 0; None or inf = when the
    source ends) or as soon as ``stop`` (a ``threading.Event``) is set. The source's ``fs``
    (Hz, finite, > 0) and ``n_channels`` (an integer >= 1) are checked: AudioInputError
    otherwise; ``where`` is what messages call the channel map (the robot file's
    ``audio.channels``, ``hearsee track``'s ``--channels``). The live robot's source
    (:func:`hearsee.robot.hardware.open_audio_source`) and ``hearsee track --device
    --channels``."""

    def __init__(self, source: Any, channels: Sequence[int], duration_s: float | None = None,
                 stop: Any = None, where: str = "channels") -> None:
        self.source = source
        # (a NaN rate was a builtin ValueError once the stream started, None a TypeError)
        self.fs = finite_number("audio source fs", source.fs, 0.0, lo_open=True,
                                error=AudioInputError)  # Hz
        self.n_in = n_in = whole_number("audio source n_channels", source.n_channels, 1,
                                        error=AudioInputError)
        # (-1 took the last channel without a word, [] was a builtin ValueError)
        self.channels = list(microphone_channels(channels, None, where))
        if max(self.channels) >= n_in:
            raise AudioInputError(f"{where}: channel {max(self.channels)} requested but the "
                                  f"input has {n_in} channels")
        self.n_channels = len(self.channels)
        duration_s = time_limit("duration_s", duration_s)  # (inf: no limit, as DeviceSource)
        self.limit = None if duration_s is None else int(round(duration_s * self.fs))
        self.stop = stop

    @property
    def n_dropped(self) -> int:
        return int(getattr(self.source, "n_dropped", 0))

    def audio_time_now(self) -> float | None:
        """The source's ``audio_time_now()`` (seconds of audio being captured now, e.g.
        :meth:`hearsee.stream.pipeline.DeviceSource.audio_time_now`), or None where it has
        none (a file: its audio has no 'now') or gives None (no block yet); anything else than
        a finite number is an AudioInputError."""
        clock = getattr(self.source, "audio_time_now", None)
        now = None if clock is None else clock()
        if now is None:
            return None
        return finite_number("audio source audio_time_now()", now, error=AudioInputError)

    def blocks(self) -> Any:
        """The source's blocks, mapped; the source's own iterator is closed when they end (a
        device's error while stopping is raised, unless another error ends the run)."""
        blocks = self.source.blocks()
        try:
            for blk in blocks:
                if self.stop is not None and self.stop.is_set():
                    break
                # (a block of fewer channels than the source declared was an IndexError)
                data = block_samples(blk.data, self.n_in)[self.channels]
                if self.limit is not None:
                    if blk.start >= self.limit:
                        break
                    data = data[:, : self.limit - blk.start]
                yield Block(blk.seq, blk.start, data, blk.arrival)
                if self.limit is not None and blk.start + data.shape[1] >= self.limit:
                    break
        except BaseException as exc:  # (GeneratorExit: our consumer ended the run normally)
            close_blocks(blocks, quiet=not isinstance(exc, GeneratorExit))
            raise
        # (the device's stream used to stop only when its generator was garbage collected:
        # a PortAudioError there was printed as "Exception ignored in", the run went on)
        close_blocks(blocks)


#: :class:`DeviceSource` looks at the first this many seconds of live input in which a channel
#: varies for a stuck or disconnected microphone (:class:`_ChannelWatch`)
CHANNEL_CHECK_S = 2.0


class _FirstWindows:
    """A stream's blocks gathered into windows of ``n`` samples (n_ch, n), each handed to
    :meth:`_check` until it says the check is done: the base of the stream's one-off checks of
    its input (:class:`_ChannelWatch`, :class:`_WiringWatch`)."""

    def __init__(self, n: int) -> None:
        self.n = max(int(n), 1)
        self.parts: list[NDArray] = []
        self.have = 0
        self.done = False

    def add(self, data: NDArray) -> None:
        """Take a block (n_ch, n_samples); check the window once it is full."""
        if self.done:
            return
        self.parts.append(data)
        self.have += data.shape[1]
        if self.have >= self.n:
            self._flush()

    def _flush(self) -> None:
        x = np.concatenate(self.parts, axis=1)
        self.parts, self.have = [], 0
        self.done = self._check(x)

    def _check(self, x: NDArray) -> bool:
        """Check a window (n_ch, n); True when nothing more is to be checked."""
        raise NotImplementedError


class _ChannelWatch(_FirstWindows):
    """The first :data:`CHANNEL_CHECK_S` seconds of a live run in which any channel varies,
    checked once as :func:`hearsee.audio.signals.read_recording` checks a file
    (:func:`~hearsee.audio.signals.channel_faults`,
    :func:`~hearsee.audio.signals.duplicate_channels`): a DegenerateInputWarning naming a
    channel stuck at one value or far quieter than the loudest (a file's stuck channel is an
    error; live input goes on), or two channels holding one signal (a mono device presented
    as several channels). Windows where every channel is constant (an input that has not
    started) are looked past."""

    def __init__(self, name: str, n: int, channels: Sequence[int] | None = None) -> None:
        super().__init__(n)
        self.name = name
        self.channels = None if channels is None else np.asarray(channels, dtype=int)

    def _check(self, x: NDArray) -> bool:
        ch = np.arange(x.shape[0]) if self.channels is None else self.channels
        x = x[ch]
        if not np.all(np.isfinite(x)):
            return False
        flat, quiet, below = channel_faults(x)
        if flat.size == x.shape[0]:
            return False  # (nothing varies yet: look at the next window)
        flat, quiet = ch[flat], ch[quiet]  # (the device's channel numbers)
        where = f"audio input device {self.name!r}: "
        if flat.size:
            warnings.warn(where + stuck_channels_text(flat) + "; check the microphone wiring",
                          DegenerateInputWarning, stacklevel=4)
        if quiet.size:
            warnings.warn(where + quiet_channels_text(quiet, below), DegenerateInputWarning,
                          stacklevel=4)
        if dup := [(int(ch[i]), int(ch[j])) for i, j in duplicate_channels(x)]:
            warnings.warn(where + duplicate_channels_text(dup), DegenerateInputWarning,
                          stacklevel=4)
        return True


#: a stream checks the first this many seconds of its input in which a source is heard for a
#: microphone wired with inverted polarity (:class:`_WiringWatch`)
WIRING_CHECK_S = 10.0
#: ... and, when the input ends before that, what it has, if at least this long
WIRING_CHECK_MIN_S = 2.0


def wiring_estimate(x: NDArray, fs: float, array: MicArray, cfg: StreamConfig,
                    empty_band_db: float | None = EMPTY_BAND_DB, tonal_noise: bool = True
                    ) -> TdoaFrames | None:
    """The whole-recording TDOA estimate of ``x`` (n_mics, n) in the stream's frames, weighting
    and band (``cfg``), for its warning of a microphone wired with inverted polarity
    (:class:`~hearsee.errors.InvertedPolarityWarning`, which
    :func:`~hearsee.audio.tdoa.estimate_tdoas` gives): the stream sees one frame at a time and
    has no averaged correlation to tell it. None when no estimate can be made (too short for a
    frame, silent, NaN samples...: the stream says what it says of them). ``empty_band_db``:
    :func:`~hearsee.audio.tdoa.estimate_tdoas`'s (None where the band was trimmed already),
    as ``tonal_noise`` (False where the hum was looked for already).
    ``hearsee track`` runs it on a file's start before streaming it, :class:`_WiringWatch` on
    live input. The array and the settings are checked first (a ConfigError / GeometryError
    of their own: a None or dict ``cfg`` was a builtin AttributeError, a wrong array None)."""
    from hearsee.errors import HearseeError

    cfg = _stream_config(cfg)
    array = load_array(array)
    margin = DEFAULT_MARGIN_SAMPLES
    if array.mask is not None:  # (a masked pair's ITDs reach past its bare delays)
        from hearsee.audio.mask import MaskModel, itd_margin_samples

        margin = itd_margin_samples(MaskModel(array), fs)
    try:
        return estimate_tdoas(x, fs, array, cfg.frame_ms, cfg.hop_ms, cfg.method,
                              band_hz=cfg.band_hz, margin_samples=margin,
                              empty_band_db=empty_band_db, tonal_noise=tonal_noise)
    except HearseeError:
        return None


#: a live stream looks for mains hum in its first this many seconds (:class:`_HumWatch`)
HUM_CHECK_S = 3.0


class _HumWatch(_FirstWindows):
    """Stationary tonal noise on every channel of a live stream -- mains hum the wiring picks
    up, a motor's whine -- in its first :data:`HUM_CHECK_S` seconds, whether or not a source
    is heard there (:func:`hearsee.audio.hum.find_lines` and
    :func:`~hearsee.audio.hum.filter_lines`, with a
    :class:`~hearsee.errors.TonalNoiseWarning`): the stream notches it out from then on
    (``tonal_lines_hz``). One window: hum that starts later is left to :class:`_WiringWatch`,
    whose estimate finds it as a file's does. (Before, only that estimate looked, after 10 s
    with a source heard: a buzz 3 dB above a voice put the directions ~60 deg off until
    then.)"""

    def __init__(self, fs: float, frame_ms: float) -> None:
        super().__init__(int(round(HUM_CHECK_S * float(fs))))
        self.fs, self.frame_ms = float(fs), float(frame_ms)
        self.tonal_lines_hz: tuple[float, ...] = ()

    def _check(self, x: NDArray) -> bool:
        lines = find_lines(x, self.fs, self.frame_ms)
        if lines.size:
            _, lines = filter_lines(x, self.fs, lines, self.frame_ms)
            warn_lines(lines)
            self.tonal_lines_hz = tuple(float(v) for v in lines)
        return True


class _WiringWatch(_FirstWindows):
    """What ``hearsee localize`` and ``hearsee track`` tell of a file before they use it, told of
    a stream's input once it has heard a source: the whole-recording estimate
    (:func:`hearsee.audio.tdoa.estimate_tdoas`, in the stream's frames, weighting and band) of
    its first :data:`WIRING_CHECK_S` seconds warns of a microphone wired with inverted polarity
    (:class:`~hearsee.errors.InvertedPolarityWarning`: the stream sees one frame at a time and
    has no averaged correlation to tell it; its directions were 30-40 deg off without a word),
    and of channels out of sync (:class:`~hearsee.errors.ChannelSyncWarning`, the same
    estimate's correlations); stationary tonal noise it finds (mains hum,
    :class:`~hearsee.errors.TonalNoiseWarning`) is notched out of the stream from then on
    (``tonal_lines_hz``, :class:`~hearsee.audio.hum.LineFilter`).
    A window where no source is heard (no whole-recording estimate, no inverted microphone) is
    looked past: the next one is checked.

    Not checked: an empty top band (input upsampled from a lower rate), which the file
    commands cut off ahead. The stream's directions barely move with it (three-mic, free field,
    8 kHz noise or voices read at 16 kHz, 20 dB: median error 0.1-1.1 deg with the whole band,
    0.3-0.8 with the band ended at 3.8 kHz, either side ahead by turns), unlike a file's
    whole-recording estimate (11-13 deg off).

    Each check is one whole-recording estimate (~25 ms of CPU for 10 s of three-mic audio at
    16 kHz), run in the stream's own thread between two batches."""

    def __init__(self, array: MicArray, fs: float, cfg: StreamConfig) -> None:
        super().__init__(int(round(WIRING_CHECK_S * float(fs))))
        self.array, self.fs, self.cfg = array, float(fs), cfg
        self.tonal_lines_hz: tuple[float, ...] = ()  # (hum found: the stream notches it out)
        self.tonal_noise = True  # (False once the stream notches hum out)
        # (dead microphones found while two or more others remain: the stream leaves them out,
        # and their warning is hearsee.audio.localize.without_microphones')
        self.dead_mics: tuple[int, ...] = ()

    def finish(self) -> None:
        """The input ended: check what there is, if at least :data:`WIRING_CHECK_MIN_S`."""
        if not self.done and self.have >= WIRING_CHECK_MIN_S * self.fs:
            self._flush()
        self.done = True

    def _check(self, x: NDArray) -> bool:
        from hearsee.audio.localize import hold_dead_warning

        tf, self.dead_mics = hold_dead_warning(self.array, lambda: wiring_estimate(
            x, self.fs, self.array, self.cfg, tonal_noise=self.tonal_noise))
        if tf is not None and tf.tonal_lines_hz:
            self.tonal_lines_hz = tf.tonal_lines_hz
        # (once a fault is told, the check is done: channels out of sync were told again every
        # 10 s, in other digits)
        return tf is not None and (tf.wiring_fault
                                   or bool(np.all(np.isfinite(tf.summary_tdoa_s))))


class DeviceSource:
    """Live multichannel input through sounddevice (PortAudio).

    Parameters
    ----------
    device : int or str or None
        PortAudio device index or name (None = default input device).
    n_channels : int
        Channels to record (= microphones of the array).
    fs : float
        Sample rate, Hz.
    block_len : int
        Samples per callback block.
    duration_s : float or None
        Stop after this much audio (None or inf: until interrupted or the device stalls).
    queue_size : int
        Bounded queue between the audio callback and the pipeline; a full queue drops the block
        (counted in :attr:`n_dropped`) -- the callback never blocks.
    timeout_s : float
        A device that delivers nothing for this long ends the stream, with :attr:`stalled` set
        (the pipeline then reports ``status="stalled"``).
    where : str
        What ``device`` is called in messages (``--device`` for ``hearsee track``).

    ``device`` picks the device as ``hearsee run``'s ``audio.device`` does
    (:func:`hearsee.stream.device.resolve_input_device`: an exact name before a unique
    substring, an ambiguous name refused); one that is not found, has no input channels or too
    few is an AudioInputError.

    Each :meth:`blocks` call is one run (one PortAudio stream, sample 0 and sequence number 0 at
    its start) with its own queue: blocks an earlier run left queued are discarded (also when
    its stream closes), and the counters below count the latest run only.

    Attributes
    ----------
    n_dropped : int
        Blocks lost: dropped at the full queue, and the blocks' worth of samples (rounded up)
        that PortAudio discarded in input overflows.
    n_overflows : int
        Callbacks flagged ``input_overflow``: PortAudio discarded input samples before the
        block. The block is placed after a gap (so that the framer emits the frames in it as
        missing, and later timestamps stay on the device's clock): the gap is measured from the
        ``time_info.inputBufferAdcTime`` of this block and the previous one when the host API
        provides them (> 0 and increasing), else it is taken as one block.
    stalled : bool
        The run ended because the device delivered nothing for ``timeout_s``.
    name : str
        The device's name (PortAudio's), for messages.

    :meth:`audio_time_now` tells which second of this run's audio the microphones are
    capturing at the moment it is called (the device's input latency and the blocks still
    queued behind the consumer included): what a robot reading its head's encoders times the
    reading by.

    A channel stuck at one value or far quieter than the others (a disconnected microphone) in
    the run's first :data:`CHANNEL_CHECK_S` seconds of signal is a DegenerateInputWarning
    naming it (:class:`_ChannelWatch`; the run goes on); ``check_channels`` (device channel
    indices; None = all) limits the check to the array's channels of a larger device.

    A stream the device refuses to open or start (a sample rate or channel count it does not
    support, a device another program holds) is an AudioInputError when the run starts; one
    that fails to stop or close, an AudioInputError when the run ends (unless the run is ending
    with another error or Ctrl-C: that stays the error).
    """

    def __init__(self, device: int | str | None, n_channels: int, fs: float = 16000.0,
                 block_len: int = 1024, duration_s: float | None = None, queue_size: int = 32,
                 timeout_s: float = 2.0, where: str = "device",
                 check_channels: Sequence[int] | None = None) -> None:
        # (unchecked, a rate of 0 divided by zero in the stream, a NaN duration or a block of 0
        # samples raised builtin errors only once the stream ran; inf seconds = no limit)
        fs = check_fs(fs)
        block_len = whole_number("block_len", block_len)
        queue_size = whole_number("queue_size", queue_size)
        timeout_s = finite_number("timeout_s", timeout_s, 0.0, lo_open=True)
        duration_s = time_limit("duration_s", duration_s)
        sd = import_sounddevice()
        # (PortAudio's look-up took the first device containing a name, where `hearsee run`
        # refused an ambiguous one and preferred an exact name: one rule now)
        info = resolve_input_device(sd, device, where, AudioInputError)
        if int(info["max_input_channels"]) < n_channels:
            have = int(info["max_input_channels"])
            need = (f"the array needs {n_channels}" if check_channels is None
                    else f"channel {max(check_channels)} asked for")
            raise AudioInputError(f"device {info['name']!r} has {have} input channels; {need}")
        self._sd = sd
        self.name = str(info.get("name", device))  #: the device's name (PortAudio's)
        self.device, self.n_channels, self.fs = device, int(n_channels), float(fs)
        self._index = info["index"]  # (the stream opens the device resolved here, not the name)
        self.block_len, self.duration_s = int(block_len), duration_s
        self.timeout_s = float(timeout_s)
        self._queue_size = int(queue_size)
        # (the channels the stuck / quiet check looks at; a device's unused channels -- a
        # playback loopback, a processed mix -- are no microphone of the array)
        self._check = (None if check_channels is None else
                       [whole_number("check_channels", c, 0, self.n_channels - 1)
                        for c in check_channels])
        if self._check == []:  # (an empty selection failed once the first window was full)
            raise ConfigError("check_channels must name one or more of the device's channels "
                              "(None: all of them)")
        self._run: object | None = None
        self._reset_run()

    def _reset_run(self) -> object:
        """Start a run: a new (empty) queue, sample and sequence counters and loss counters;
        returns the run's token (a stream or generator of an earlier run still alive touches
        nothing of this one)."""
        self._run = run = object()
        self._q: queue.Queue = queue.Queue(maxsize=self._queue_size)
        self._next, self._seq = 0, 0
        self._prev_adc: float | None = None
        self._prev_frames = 0
        self.n_dropped = 0
        self.n_overflows = 0
        self.stalled = False
        # (the newest block's end: its sample index and the time.perf_counter() of its capture)
        self._clock: tuple[int, float] | None = None
        self._latency_s = 0.0  # (the stream's input latency, s, once it is open)
        return run

    def audio_time_now(self) -> float | None:
        """Seconds of this run's audio (sample index / ``fs``) being captured now: the end of
        the newest block the device delivered, plus the time since it was captured -- the
        device's input latency (PortAudio's ``time_info``: the callback's ``currentTime`` less
        the buffer's end, ``inputBufferAdcTime`` + its length; where the host API gives no
        times, the stream's reported ``latency``) and the time since its callback. None before
        the run's first block."""
        clock = self._clock
        if clock is None:
            return None
        end, t_end = clock
        return end / self.fs + max(time.perf_counter() - t_end, 0.0)

    def _callback(self, indata: NDArray, frames: int, time_info: Any, status: Any) -> None:
        adc = _adc_time(time_info)
        if status and getattr(status, "input_overflow", False):
            self.n_overflows += 1
            if self._seq > 0:  # samples were lost after the previous block: leave a gap
                lost = self.block_len  # unknown amount: as if one block was lost
                if adc is not None and self._prev_adc is not None and adc > self._prev_adc:
                    lost = int(round((adc - self._prev_adc) * self.fs)) - self._prev_frames
                lost = max(lost, 1)
                skipped = -(-lost // self.block_len)
                self._next += lost
                self._seq += skipped
                self.n_dropped += skipped
        self._prev_adc, self._prev_frames = adc, int(frames)
        start = self._next
        self._next += frames
        seq = self._seq
        self._seq += 1
        arrival = time.perf_counter()
        delay = _capture_delay(time_info, adc, frames, self.fs)
        self._clock = (self._next, arrival - (self._latency_s if delay is None else delay))
        blk = Block(seq, start, np.array(indata, dtype=float).T, arrival)
        try:
            self._q.put_nowait(blk)
        except queue.Full:
            self.n_dropped += 1

    def blocks(self) -> Iterator[Block]:
        run = self._reset_run()
        q = self._q

        def callback(indata: NDArray, frames: int, time_info: Any, status: Any) -> None:
            if self._run is run:  # (a stream of an earlier run still open: ignored)
                self._callback(indata, frames, time_info, status)

        sd = self._sd
        # (as MappedSource: the run's samples end at the limit -- the last block was yielded
        # whole, up to a block past it: `hearsee track --device --duration 1` streamed 1.024 s
        # and one frame more than with --channels)
        limit = None if self.duration_s is None else int(round(self.duration_s * self.fs))
        try:
            with contextlib.ExitStack() as opened:
                try:  # PortAudio opens the device here and starts it on entering
                    stream = sd.InputStream(
                        device=self._index, channels=self.n_channels, samplerate=self.fs,
                        blocksize=self.block_len, dtype="float32", callback=callback)
                    stream.__enter__()
                    if self._run is run:
                        self._latency_s = _input_latency(stream)
                except (ValueError, sd.PortAudioError) as exc:
                    # (a rate or channel count the device refuses, a device another program
                    # holds: PortAudioError escaped as a traceback)
                    raise AudioInputError(
                        f"audio input device {self.name!r}: cannot record {self.n_channels} "
                        f"channels at {self.fs:g} Hz ({exc})") from None

                def stop_stream(exc_type: Any, exc: Any, tb: Any) -> bool:
                    """The stream's exit (stop, close). PortAudio failing there (a device
                    unplugged) is an AudioInputError when the run ended normally or its
                    consumer closed it (GeneratorExit); while another error propagates (Ctrl-C
                    in the wait for a block, ...) that one stays the error (the PortAudioError
                    hid it, chained to it)."""
                    try:
                        stream.__exit__(exc_type, exc, tb)
                    except sd.PortAudioError as err:
                        if exc_type is None or issubclass(exc_type, GeneratorExit):
                            raise AudioInputError(
                                f"audio input device {self.name!r}: cannot stop the input "
                                f"stream ({err})") from None
                    return False

                opened.push(stop_stream)
                watch = _ChannelWatch(self.name, int(CHANNEL_CHECK_S * self.fs), self._check)
                while True:
                    try:
                        blk = q.get(timeout=self.timeout_s)
                    except queue.Empty:
                        if self._run is run:
                            self.stalled = True
                        return
                    if limit is not None:
                        if blk.start >= limit:  # (after an overflow's gap)
                            return
                        blk = replace(blk, data=blk.data[:, :limit - blk.start])
                    watch.add(blk.data)
                    yield blk
                    if limit is not None and blk.start + blk.data.shape[1] >= limit:
                        return
        finally:
            # the stream is closed: what it queued after the end of the run is discarded
            while True:
                try:
                    q.get_nowait()
                except queue.Empty:
                    break


def mapped_device(device: int | str | None, channels: Sequence[int], fs: float, *,
                  duration_s: float | None = None, where: str = "device",
                  channels_where: str = "channels", **kwargs: Any) -> MappedSource:
    """Live microphones on some of a device's input channels (``channels``, 0-based, one per
    microphone; ``channels_where``: what messages call them): the device opened for its
    channels up to the highest of them, its stuck-channel watch on those only
    (:class:`DeviceSource`'s ``check_channels``; ``kwargs`` go to it too), behind a
    :class:`MappedSource` that picks them. The one way of the live robot
    (:func:`hearsee.robot.hardware.open_audio_source`) and ``hearsee track --device
    --channels``; ``.source`` is the device."""
    channels = microphone_channels(channels, None, channels_where)
    dev = DeviceSource(device, max(channels) + 1, fs, duration_s=duration_s, where=where,
                       check_channels=channels, **kwargs)
    return MappedSource(dev, channels, duration_s, where=channels_where)


def _adc_time(time_info: Any) -> float | None:
    """``time_info.inputBufferAdcTime`` (PortAudio stream time of the block's first sample, s),
    or None where the host API does not provide it (missing, 0 or not finite)."""
    try:
        t = float(getattr(time_info, "inputBufferAdcTime", 0.0))
    except (TypeError, ValueError):
        return None
    return t if np.isfinite(t) and t > 0.0 else None


def _capture_delay(time_info: Any, adc: float | None, frames: int, fs: float) -> float | None:
    """Seconds from the capture of a block's end to its callback: ``time_info.currentTime``
    less (``inputBufferAdcTime`` + ``frames`` / ``fs``), both on PortAudio's stream clock; None
    where the host API does not give both, or the difference is negative or a second or more
    (clocks a host API fills inconsistently)."""
    if adc is None:
        return None
    try:
        now = float(getattr(time_info, "currentTime", 0.0))
    except (TypeError, ValueError):
        return None
    delay = now - (adc + frames / fs)
    return delay if np.isfinite(now) and now > 0.0 and 0.0 <= delay < 1.0 else None


def _input_latency(stream: Any) -> float:
    """The input stream's reported latency, seconds (sounddevice's ``InputStream.latency``);
    0 where it reports none, or no number from 0 to 1 s."""
    try:
        latency = float(getattr(stream, "latency", 0.0))
    except (TypeError, ValueError):
        return 0.0
    return latency if np.isfinite(latency) and 0.0 <= latency < 1.0 else 0.0


class DropoutSource:
    """Wrap a source and simulate a flaky device (for tests and benchmarks).

    Blocks whose sequence numbers are in ``drop`` are lost; those in ``late`` are held back and
    delivered out of order after the following block (too late to be used); a late block that
    no delivered block follows is delivered when the wrapped source ends (in order -- nothing
    overtook it, so it is still used); ``stall_before`` maps a sequence number to seconds of
    silence before that block is delivered.

    ``n_dropped`` counts the blocks the latest :meth:`blocks` run dropped (as a device counts
    its own: the pipeline's stats then count dropped last blocks too, which leave no gap in
    the sequence numbers); ``end_sample`` is the wrapped source's (where the stream ends), so
    that the frames of dropped last blocks are reported missing.
    """

    def __init__(self, source: Any, drop: Sequence[int] = (), late: Sequence[int] = (),
                 stall_before: dict[int, float] | None = None) -> None:
        if not all(hasattr(source, a) for a in ("fs", "n_channels", "blocks")):
            raise ConfigError(f"DropoutSource wraps a stream source (fs, n_channels, "
                              f"blocks()), got {type(source).__name__}")
        self.source = source
        self.fs, self.n_channels = source.fs, source.n_channels
        self.drop, self.late = set(drop), set(late)
        # (a negative or NaN stall was time.sleep's ValueError during the run)
        self.stall_before = {k: finite_number(f"stall_before[{k}] (seconds)", v, 0.0)
                             for k, v in dict(stall_before or {}).items()}
        self.n_dropped = 0

    @property
    def end_sample(self) -> int | None:
        """The wrapped source's ``end_sample`` (None where it has none, e.g. a device)."""
        return getattr(self.source, "end_sample", None)

    def blocks(self) -> Iterator[Block]:
        held: list[Block] = []
        self.n_dropped = 0
        for blk in self.source.blocks():
            if blk.seq in self.stall_before:
                time.sleep(self.stall_before[blk.seq])
            if blk.seq in self.drop:
                self.n_dropped += 1
                continue
            if blk.seq in self.late:
                held.append(blk)
                continue
            yield Block(blk.seq, blk.start, blk.data, time.perf_counter())
            for h in held:
                yield Block(h.seq, h.start, h.data, time.perf_counter())
            held = []
        for h in held:  # held back until the end
            yield Block(h.seq, h.start, h.data, time.perf_counter())


# ---------------------------------------------------------------------------- framer
class Framer:
    """Blocks -> batches of analysis frames, with missing frames where blocks were dropped.

    ``n_dropped`` counts blocks that never arrived (gaps in the sequence numbers), ``n_late``
    blocks that arrived after their samples had been declared lost (counted only there) or
    twice (a repeated block is late but brings no lost block back).
    """

    #: Sequence numbers of declared gaps remembered, to tell a late block from a repeated one.
    _GAP_MEMORY = 4096

    def __init__(self, n_channels: int, fs: float, frame_ms: float, hop_ms: float) -> None:
        self.fs = float(fs)
        self.frame_len, self.hop = frame_geometry(fs, frame_ms, hop_ms)
        # (2.5 was truncated to 2 channels, 0 accepted, "a" a builtin ValueError)
        self.n_channels = whole_number("n_channels", n_channels, 1)
        self.buf = np.zeros((self.n_channels, 0))
        self.buf_start = 0
        self.next_frame = 0  # absolute start sample of the next frame to emit
        self.n_late = 0
        self.n_dropped = 0
        self._expected_seq = 0
        self._gaps: set[int] = set()  # sequence numbers counted in n_dropped (the latest ones)

    def keep_channels(self, keep: Sequence[int]) -> None:
        """From now on frame only the channels ``keep`` (their indices in the blocks so far):
        the samples held keep their place in time, the next blocks must carry those channels
        alone (a live stream leaving a dead microphone out)."""
        self.buf = self.buf[list(keep)]
        self.n_channels = len(self.buf)

    def push(self, blk: Block) -> FrameBatch | None:
        """Add a block; return the frames it completes (or None)."""
        data = block_samples(blk.data, self.n_channels)
        buf_end = self.buf_start + self.buf.shape[1]
        if blk.start < buf_end or blk.seq < self._expected_seq:
            self.n_late += 1  # its samples were already consumed or declared lost
            if blk.seq in self._gaps:  # counted as a gap when its successor came: late, not
                self._gaps.discard(blk.seq)  # lost (a repeat of a delivered block is neither)
                self.n_dropped -= 1
            return None
        if blk.seq > self._expected_seq:
            self.n_dropped += blk.seq - self._expected_seq
            self._gaps.update(range(max(self._expected_seq, blk.seq - self._GAP_MEMORY),
                                    blk.seq))
            if len(self._gaps) > self._GAP_MEMORY:  # keep the latest
                self._gaps = set(sorted(self._gaps)[-self._GAP_MEMORY:])
        self._expected_seq = blk.seq + 1
        missing_t: list[float] = []
        if blk.start > buf_end:  # gap: frames touching it are lost
            while self.next_frame < blk.start:
                missing_t.append((self.next_frame + self.frame_len / 2.0) / self.fs)
                self.next_frame += self.hop
            self.buf = np.zeros((self.n_channels, 0))
            self.buf_start = blk.start
        self.buf = np.concatenate([self.buf, data], axis=1)
        buf_end = self.buf_start + self.buf.shape[1]
        k = 0
        if self.next_frame + self.frame_len <= buf_end:
            k = (buf_end - self.frame_len - self.next_frame) // self.hop + 1
        segment = None
        ok_t = np.zeros(0)
        if k > 0:
            off = self.next_frame - self.buf_start
            segment = self.buf[:, off: off + self.frame_len + (k - 1) * self.hop]
            ok_t = (self.next_frame + np.arange(k) * self.hop + self.frame_len / 2.0) / self.fs
            self.next_frame += k * self.hop
        # drop the samples before the next frame -- but never more than are held: when the next
        # frame starts beyond them (after a gap, or a hop longer than the frame) the buffer ends
        # where the received samples end, so that the next contiguous block is not taken as late
        keep = min(max(self.next_frame - self.buf_start, 0), self.buf.shape[1])
        if keep:
            self.buf = self.buf[:, keep:]
            self.buf_start += keep
        if not missing_t and k == 0:
            return None
        t = np.concatenate([np.asarray(missing_t), ok_t])
        missing = np.concatenate([np.ones(len(missing_t), bool), np.zeros(k, bool)])
        return FrameBatch(t, missing, segment, blk.arrival)

    def finish(self, end_sample: int | None) -> FrameBatch | None:
        """The frames of a stream that ends at sample ``end_sample`` (None: unknown) that no
        block completed, all missing: those within the stream that need samples after the last
        block received (the last blocks were dropped: no later block left a gap to show it);
        None when there are none."""
        if end_sample is None:
            return None
        end = int(end_sample)
        if self.next_frame + self.frame_len > end:
            return None
        k = (end - self.frame_len - self.next_frame) // self.hop + 1
        t = (self.next_frame + np.arange(k) * self.hop + self.frame_len / 2.0) / self.fs
        self.next_frame += k * self.hop
        return FrameBatch(t, np.ones(k, bool), None, time.perf_counter())


# ---------------------------------------------------------------------------- per-frame GCC stage
class FrameActivity:
    """Causal per-frame activity decision and noise spectrum of the stream's GCC stage.

    :func:`~hearsee.audio.tdoa.estimate_tdoas` decides from the recording it is given: which
    frames hold a source (energy within ``vad_db`` dB of the 10th percentile of the frame
    energies, if the 95th percentile shows a range; else the same test on the energy in the
    analysis band) and, for its SNR weighting, the noise spectrum averaged over the inactive
    frames. Called on each batch of a stream, those statistics were the batch's -- and a batch
    is the frames one block completes, so the tracks of one WAV file depended on the block size
    it was read in (male voice at 10 dB: 49 / 54 / 78 / 81 valid frames of 124 in blocks of
    1024 / 4096 / 16384 / the whole file; tracked azimuths 12.8 deg apart between 1024 and 4096).

    Here frame k's decision depends only on frames up to k, never on the batch it arrives in:

    * **activity**: the same rule (:func:`hearsee.audio.tdoa._energy_vad`, and its band-energy
      test when the broadband energy does not decide) applied to the energies of the last
      ``n_history`` frames including k -- a running-quantile noise floor (quantile-based noise
      estimation, Stahl, Fischer & Bippus 2000, "Quantile based noise estimation for spectral
      subtraction and Wiener filtering", ICASSP; the batch rule's percentiles over a sliding
      window of fixed length instead of over the batch);
    * **noise spectrum**: the mean band power spectrum ``|X|^2`` (each channel; windowed frames
      as :func:`estimate_tdoas` takes them) of the inactive, not digitally silent frames among
      those ``n_history``, when there are at least 3 (the batch rule's minimum); otherwise the
      last such mean is held (a talker who does not pause for ``n_history`` frames keeps the
      noise spectrum of the last pause) and before the first one a frame has none (NaN: the
      plain weighting, as a batch without 3 quiet frames had).

    Start of a stream: the window holds the frames seen so far (frame 0 alone: the energy cannot
    decide, the frame counts as active), so the first ``n_history`` frames are decided on a
    shorter history. Missing frames (samples lost to a dropped or late block; the pipeline
    passes only complete frames) neither enter the history nor age it: the window is the last
    ``n_history`` frames received, since the noise floor rarely changes across a dropout.
    Digitally silent frames (a channel all zeros) enter the energy history (their energy is
    excluded by the rule itself) but never the noise spectrum.

    Levels: the decisions are scale-free; the caller passes the samples at one scale
    (:class:`FrameGcc` carries them at :func:`level_scale`, rescaling the history by
    :meth:`rescale` when that changes). Units: energies in squared sample units per sample,
    spectra in ``|X|^2`` of the band's rfft bins ``k0..k1-1``.
    """

    def __init__(self, n_history: int, frame_len: int, win: NDArray, nfft: int, k0: int,
                 k1: int, vad_db: float = 3.0, band_test: bool = True,
                 noise: bool = True) -> None:
        from collections import deque

        self.n_history = whole_number("n_history", n_history)
        self.frame_len, self.win, self.nfft, self.k0, self.k1 = frame_len, win, nfft, k0, k1
        self.vad_db, self.band_test, self.want_noise = float(vad_db), bool(band_test), noise
        keep = self.n_history - 1  # the past frames a new frame's window needs
        self._e: deque = deque(maxlen=keep)  # broadband energies (float)
        self._eb: deque = deque(maxlen=keep)  # band energies (float)
        self._quiet: deque = deque(maxlen=keep)  # inactive and not digitally silent (bool)
        self._power: deque = deque(maxlen=keep)  # band power spectra (n_ch, B) float32
        self.noise: NDArray | None = None  # the held noise spectrum (n_ch, B) float64

    def rescale(self, f: float) -> None:
        """Samples now come multiplied by a further ``sqrt(f)`` (``f`` a power of two: exact):
        carry the history's energies and spectra along."""
        self._e = type(self._e)((e * f for e in self._e), maxlen=self._e.maxlen)
        self._eb = type(self._eb)((e * f for e in self._eb), maxlen=self._eb.maxlen)
        self._power = type(self._power)((None if p is None else p * np.float32(f)
                                         for p in self._power), maxlen=self._power.maxlen)
        if self.noise is not None:
            self.noise = self.noise * f

    def __call__(self, frames: NDArray) -> tuple[NDArray, NDArray | None]:
        """Decide consecutive frames ``frames`` (n_ch, m, frame_len) after those of earlier
        calls: (active (m,) bool, noise spectra (m, n_ch, B) float32 with NaN rows where there
        is no reference yet, or None when the noise spectrum is not wanted)."""
        from hearsee.audio.tdoa import _energy_vad

        n_ch, m = frames.shape[0], frames.shape[1]
        # each frame about its own mean (a DC offset is no energy; causal, unlike a mean over
        # the batch), float64 sums of each frame's own contiguous samples
        f64 = np.ascontiguousarray(np.moveaxis(frames, 1, 0), dtype=float)  # (m, n_ch, L)
        f64 -= f64.mean(axis=2, keepdims=True)
        e = np.einsum("mcl,mcl->m", f64, f64) / (self.frame_len * n_ch)
        silent = ~np.all(np.any(frames != 0, axis=-1), axis=0)
        need_power = self.band_test or self.want_noise
        if need_power:
            X = np.moveaxis(frame_spectra(frames, self.win, self.nfft, self.k0, self.k1), 1, 0)
            power = np.ascontiguousarray(X.real**2 + X.imag**2)  # (m, n_ch, B) float32
            eb = power.reshape(m, -1).sum(axis=1, dtype=float)
        active = np.zeros(m, bool)
        noise = np.full((m, n_ch, self.k1 - self.k0), np.nan, np.float32) if (
            self.want_noise) else None
        for i in range(m):
            # the window: the last n_history - 1 frames received, and this one
            ew = np.append(np.fromiter(self._e, float, len(self._e)), e[i])
            act, decided = _energy_vad(ew, self.vad_db)
            a = bool(act[-1])
            if self.band_test and not decided:
                ebw = np.append(np.fromiter(self._eb, float, len(self._eb)), eb[i])
                band, b_decided = _energy_vad(ebw, self.vad_db)
                a = a and (bool(band[-1]) if b_decided else True)
            active[i] = a
            quiet = not a and not bool(silent[i])
            if self.want_noise:
                pw = [p for p, q in zip(self._power, self._quiet, strict=True) if q]
                if quiet:
                    pw.append(power[i])
                if len(pw) >= 3:  # (estimate_tdoas's minimum of noise-only frames)
                    psd = np.mean(np.stack(pw), axis=0, dtype=float)
                    self.noise = np.maximum(psd, 1e-12 * psd.max(initial=0.0) + 1e-30)
                if self.noise is not None:
                    noise[i] = self.noise
            self._e.append(e[i])  # (a deque of maxlen n_history - 1: the oldest drops out)
            self._eb.append(eb[i] if need_power else 0.0)
            self._quiet.append(quiet)
            self._power.append(power[i] if self.want_noise else None)
        return active, noise


class FrameGcc:
    """Per-frame GCC TDOAs of consecutive frames: :func:`hearsee.audio.tdoa.estimate_tdoas`
    with ``whole_recording=False`` (the same window, lag bounds, peak search and confidence;
    SNR weighting only with ``StreamConfig.snr_weight``; without the whole-recording summary
    that a stream does not use -- its direction search cost about two thirds of each call on
    a batch of eight frames), given each frame's activity (and noise spectrum) by
    :class:`FrameActivity` from the frames up to it (``StreamConfig.activity_history_s``)
    rather than from the batch the frame came in: the TDOAs do not depend on the block size
    of the source.

    State: the activity history and :func:`level_scale` of the largest |sample| seen (the
    samples go to both stages at that scale, a power of two, so that a float recording at 1e9
    does not overflow the single-precision spectra; ordinary levels pass unchanged). Calls
    must come in stream order. Units: seconds; ``segment`` (n_ch, frame_len + (m - 1) * hop)
    samples.
    """

    #: Frames per estimate_tdoas call (bounds memory on a whole file read as one block)
    CHUNK_FRAMES = 128

    def __init__(self, array: MicArray, fs: float, cfg: StreamConfig,
                 margin_samples: float = DEFAULT_MARGIN_SAMPLES) -> None:
        from hearsee.audio.tdoa import _band_mask, _window

        self.array, self.fs, self.cfg = array, float(fs), cfg
        self.margin_samples = float(margin_samples)  # (a masked pair's ITDs reach further)
        self.pairs = list(array.pairs)
        self.frame_len, self.hop = frame_geometry(fs, cfg.frame_ms, cfg.hop_ms)
        # estimate_tdoas's window, transform length and band (its defaults, which the calls
        # below leave in place): the noise spectra must be of its frames' spectra
        max_lag = array.max_tdoa(self.pairs) * self.fs + self.margin_samples
        nfft = gcc_nfft(self.frame_len, float(max_lag.max()))
        n_bins = nfft // 2 + 1
        bins = np.flatnonzero(_band_mask(n_bins, nfft, self.fs, cfg.band_hz))
        k0, k1 = int(bins[0]), int(bins[-1]) + 1
        # (in the frames' real hop: frame_geometry makes a hop shorter than half a sample one
        # sample, and --hop-ms 1e-300 asked for 1e303 frames of history, an OverflowError)
        hop_ms = (cfg.hop_ms if round(cfg.hop_ms * 1e-3 * self.fs) >= 1
                  else self.hop * 1e3 / self.fs)
        n_hist = max(int(round(cfg.activity_history_s * 1e3 / hop_ms)), 1)
        self.activity = FrameActivity(n_hist, self.frame_len, _window(DEFAULT_WINDOW,
                                                                      self.frame_len),
                                      nfft, k0, k1, band_test=k0 > 1 or k1 < n_bins - 1,
                                      noise=bool(cfg.snr_weight))
        self._level = LevelScale()
        # SCOT / ROTH / ML average their statistics over estimate_tdoas's smooth_frames:
        # causally, over this many earlier frames, carried from batch to batch as samples
        # (frames made of whole hops only: with a hop longer than the frame there is none)
        stats = normalize_method(cfg.method) in ("scot", "roth", "ml")
        self.n_context = (DEFAULT_SMOOTH_FRAMES - 1 if stats and self.hop <= self.frame_len
                          else 0)
        self._ctx = np.zeros((array.n_mics, 0), np.float32)  # from the oldest context frame's
        # start to the next frame's start, unscaled

    def skip(self) -> None:
        """Frames were lost: the next ones have no earlier frames to average with."""
        self._ctx = self._ctx[:, :0]

    def __call__(self, segment: NDArray, n_frames: int) -> tuple[NDArray, NDArray]:
        """TDOAs (m, n_pairs) seconds (NaN: no estimate) and confidences (m, n_pairs) of the
        ``m = n_frames`` frames of ``segment``, the stream's next complete frames (after
        :meth:`skip` when frames were lost in between)."""
        cfg, hop, L = self.cfg, self.hop, self.frame_len
        seg = np.asarray(segment, dtype=np.float32)
        factor = self._level.take(seg)  # (the activity history goes to a new level_scale)
        if factor != 1.0:
            self.activity.rescale(factor)
        c0 = self._ctx.shape[1] // hop  # context frames before the segment's first frame
        full = self._level.scaled(np.concatenate([self._ctx, seg], axis=1) if c0 else seg)
        frames = frame_signals(full, L, hop)[:, c0:c0 + n_frames]
        if frames.shape[1] != n_frames:
            raise EstimationError(f"FrameGcc: the segment holds {frames.shape[1]} frames of "
                                  f"{L} samples (hop {hop}), not {n_frames}")
        tdoa = np.full((n_frames, len(self.pairs)), np.nan)
        conf = np.zeros((n_frames, len(self.pairs)))
        for s0 in range(0, n_frames, self.CHUNK_FRAMES):
            s1 = min(s0 + self.CHUNK_FRAMES, n_frames)
            active, noise = self.activity(frames[:, s0:s1])
            cc = min(self.n_context, c0 + s0)  # earlier frames, only for the statistics
            if cc:
                active = np.concatenate([np.zeros(cc, bool), active])
                if noise is not None:
                    noise = np.concatenate([np.full((cc,) + noise.shape[1:], np.nan,
                                                    noise.dtype), noise])
            g0 = c0 + s0 - cc
            part = full[:, g0 * hop: (c0 + s1 - 1) * hop + L]
            tf = estimate_tdoas(part, self.fs, self.array, cfg.frame_ms, cfg.hop_ms,
                                cfg.method, self.pairs, band_hz=cfg.band_hz,
                                refine=cfg.refine, min_confidence=cfg.min_confidence,
                                margin_samples=self.margin_samples, whole_recording=False,
                                snr_weight=bool(cfg.snr_weight),
                                active=active, frame_noise_psd=noise,
                                causal_smoothing=True, chunk_frames=len(active),
                                empty_band_db=None)  # (a band per batch: results would
            # depend on where the batches end; a file's empty band: ``hearsee track`` finds it)
            tdoa[s0:s1], conf[s0:s1] = tf.tdoa_s[cc:], tf.confidence[cc:]
        if self.n_context:  # the samples of the last n_context frames up to the next start
            c = min(self.n_context, c0 + n_frames)
            self._ctx = np.concatenate([self._ctx, seg], axis=1)[
                :, (c0 + n_frames - c) * hop: (c0 + n_frames) * hop].copy()
        return tdoa, conf


# ---------------------------------------------------------------------------- smoothed SRP stage
def level_scale(peak: float) -> float:
    """The power of two by which :class:`SmoothedSrp` multiplies samples once the largest
    |sample| seen is ``peak``: 1 while ``peak`` is within the level range that
    :func:`~hearsee.audio.tdoa.estimate_tdoas` leaves unscaled (1e-6 .. 1e3; and for silence,
    0), else the one bringing ``peak`` to within a factor sqrt(2) of 1. A power of two scales
    floating-point numbers exactly, so a state built at one scale can be carried to another.
    Unitless."""
    if peak == 0.0 or MIN_UNSCALED_PEAK <= peak <= MAX_UNSCALED_PEAK:
        return 1.0
    return math.ldexp(1.0, int(np.clip(-round(math.log2(peak)), -120, 120)))


class LevelScale:
    """A stream stage's running :func:`level_scale`: the largest |sample| seen (``peak``) and
    the power of two the stage multiplies its samples by (``scale``). The one bookkeeping of
    :class:`FrameGcc`, :class:`SmoothedSrp` and :class:`SmoothedMask`, which each had their
    own copy."""

    def __init__(self) -> None:
        self.peak, self.scale = 0.0, 1.0

    def take(self, samples: NDArray) -> float:
        """Take a batch's ``samples`` into the running maximum (an AudioInputError for NaN or
        infinite samples); return the factor -- a power of two, 1 when the scale stays -- that
        carries a state of squared samples from the old scale to the new one. Once a sample is
        non-zero the scale only falls as the maximum grows (a state is never enlarged, so it
        cannot overflow); the one rise, from digital silence (scale 1) to a tiny first level,
        finds a state of zeros."""
        peak = _peak_level(samples)  # (estimate_tdoas' own: NaN / inf come through)
        if not np.isfinite(peak):
            raise AudioInputError("recording contains NaN or infinite samples")
        self.peak = max(self.peak, peak)
        scale = level_scale(self.peak)
        factor = (scale / self.scale) ** 2
        self.scale = scale
        return factor

    def scaled(self, x: NDArray) -> NDArray:
        """``x`` (single precision) at the current scale (``x`` itself at scale 1)."""
        return x if self.scale == 1.0 else x * np.float32(self.scale)


class EvidenceAge:
    """The energy-weighted mean age (frames) of recursively averaged evidence: how long ago,
    on average, the energy in an average ``S <- lam S + e_n`` arrived (a loud syllable keeps
    dominating the average through the quiet frames after it). The one bookkeeping of
    :class:`SmoothedSrp` (its ``age_frames``, the measurement delay of its directions) and
    :class:`SmoothedMask` (the age of the evidence its decisions were made on), which each
    had their own form of the recursion.

    ``energy`` is the averaged energy (the units of what is added: squared samples at the
    stage's :class:`LevelScale`), ``age`` its mean age in frames."""

    def __init__(self) -> None:
        self.energy, self.age = 0.0, 0.0

    def decay(self, factor: float, n: int = 1) -> None:
        """``n`` frames pass and the average is multiplied by ``factor`` (its decay over them):
        the energy shrinks, its age grows by ``n``."""
        self.energy *= factor
        self.age += n

    def add(self, e: float) -> None:
        """Energy ``e`` (>= 0) enters the average now, 0 frames old."""
        total = self.energy + e
        self.age = self.energy * self.age / total if total > 0 else 0.0
        self.energy = total


class SmoothedSrp:
    """Recursively smoothed cross-power spectra -> PHAT -> steered response over directions.

    The tracker's measurement stage (ODAS's SSL module, Grondin & Michaud 2019, sec. 3; HARK's
    MUSIC/GEVD front ends smooth their correlation matrices the same way): per pair the cross
    spectrum ``G_ij(k) = X_i(k) X_j*(k)`` of each frame is averaged recursively,
    ``S <- alpha S + (1 - alpha) G``, before the PHAT weighting, so one estimate holds the evidence
    of about ``(1 + alpha) / (1 - alpha)`` frames (loud frames count more: the raw spectra are
    averaged). The PHAT-weighted, band-limited correlations (upsampled ``up`` times) are summed
    at the TDOAs of a grid of directions (SRP-PHAT on the smoothed spectra), which picks all pair
    peaks jointly -- a reflection that tops one pair's correlation loses to the direction the
    other pairs agree on. The best direction's pair lags are refined on the upsampled
    correlations and returned in seconds together with the normalised steered power
    (``coherence``: 1 = perfectly coherent, ~0 = noise) and a few other local maxima of the
    steered response (alternative directions for the tracker's data association).

    The averaged spectrum lags the source by about ``alpha / (1 - alpha)`` frames; the tracker
    accounts for it in its measurement model (:meth:`DirectionKalman.update` ``delay_s``).

    The direction grid covers the sphere (volume arrays), the upper hemisphere (horizontal
    planar arrays, which cannot tell the elevation's sign) or the horizontal plane only (linear
    arrays; and planar ones with ``in_plane``: a source known to be at the array's height).

    Units: seconds, Hz, degrees. Frames are Hann-windowed ``frame_len`` samples; state persists
    across batches. The recursion runs once per hop: a missing frame (samples lost to a dropped
    block, :meth:`skip`) adds no evidence, like a frame without energy -- the averages decay by
    ``alpha`` and the evidence they hold grows one frame older -- so after a gap of n frames the
    evidence from before it weighs ``alpha**n`` and its age counts the gap.

    The results are scale-free (the PHAT and coherence weightings, the normalised steered
    power and the energy-weighted age are ratios), but the single-precision spectra's fourth
    powers are not: a float recording at 1e9 (raw 32-bit PCM read as floats) overflowed them
    and gave NaN coherences, one at 1e-12 underflowed them. A stream cannot scale by the whole
    recording's peak as :func:`~hearsee.audio.tdoa.estimate_tdoas` does, so the samples are
    multiplied by :func:`level_scale` of the largest |sample| seen so far (1 at ordinary levels,
    which are processed unchanged), and when that scale changes the state is carried to the new
    one (a power of two: exactly).
    """

    def __init__(self, array: MicArray, fs: float, frame_len: int, alpha: float,
                 band_hz: tuple[float, float] | None = (300.0, 3500.0), up: int = 4,
                 grid_deg: float = 2.0, coherence_weight: bool = True,
                 in_plane: bool = False) -> None:
        if not 0.0 <= alpha < 1.0:
            raise ConfigError(f"spectrum smoothing alpha must be in [0, 1), got {alpha}")
        self.array, self.fs, self.alpha, self.up = array, float(fs), float(alpha), int(up)
        self.frame_len = int(frame_len)
        self.pairs = list(array.pairs)
        max_lag = array.max_tdoa(self.pairs) * fs + 1.0
        self.nfft = gcc_nfft(self.frame_len, float(max_lag.max()))
        n_bins = self.nfft // 2 + 1
        f = np.arange(n_bins) * fs / self.nfft
        lo, hi = _number_pair(band_hz, "srp_band_hz", "Hz") if band_hz is not None else (
            0.0, fs / 2.0)
        self.k0 = int(np.searchsorted(f, lo))
        self.k1 = int(np.searchsorted(f, min(hi, fs / 2.0), side="right"))
        if self.k1 - self.k0 < 4:
            raise ConfigError(f"band {band_hz} Hz holds too few frequency bins at fs={fs:g} Hz")
        self.win = np.hanning(self.frame_len).astype(np.float32)
        self.I = np.array([p[0] for p in self.pairs])
        self.J = np.array([p[1] for p in self.pairs])
        # direction grid (unit vectors in the array frame); planar arrays see only |elevation|
        az = np.radians(np.arange(-180.0, 180.0, grid_deg))
        planar = np.ptp(array.positions[:, 2]) < 1e-9
        els = np.radians(np.arange(0.0 if planar else -80.0, 81.0, 20.0 if planar else 10.0))
        cen = array.positions - array.positions.mean(axis=0)
        if np.linalg.svd(cen, compute_uv=False)[1] < 1e-9 or (planar and in_plane):
            # linear array: every elevation on the cone gives the same TDOA; azimuth in the
            # horizontal plane, as the closed-form localizer reports it (planar + in_plane:
            # the source is known to be in that plane)
            els = np.zeros(1)
        self.grid_deg, self.n_az = float(grid_deg), az.size
        self.az_axis = np.degrees(az)
        A, E = np.meshgrid(az, els, indexing="ij")
        self.grid_az = np.degrees(A.ravel())
        self.grid_el = np.degrees(E.ravel())
        U = np.stack([np.cos(E) * np.cos(A), np.cos(E) * np.sin(A), np.sin(E)], -1).reshape(-1, 3)
        pos = array.positions
        tau = -((pos[self.I] - pos[self.J]) @ U.T) / array.speed_of_sound * fs  # (P, D) samples
        self.n_up = self.nfft * self.up
        # the correlations are only ever read at lags within the array's bound (plus the
        # refinement's +-up): evaluate them there directly, r(l) = Re sum_k P_k e^{2 pi j k l /
        # n_up} / n_bins (the band-limited GCC upsampled `up` times; what an irfft of the
        # zero-padded spectrum gives at those lags, without computing all n_up of them)
        self.lag_max = int(np.ceil(np.abs(tau).max() * self.up)) + self.up + 2
        lags = np.arange(-self.lag_max, self.lag_max + 1)
        kk = np.arange(self.k0, self.k1)
        self.E = np.exp(2j * np.pi * np.outer(kk, lags) / self.n_up).astype(np.complex64)
        # column indices into the lag window (lag l -> column l + lag_max)
        self.idx = np.round(tau * self.up).astype(int) + self.lag_max
        # linear interpolation between the upsampled lags (rounding them would leave a ripple
        # of up to 1/(2 up) sample in the steered response, ~1 deg for a 15 cm array)
        fl = np.floor(tau * self.up)
        self.idx0 = fl.astype(int) + self.lag_max
        self.idx1 = self.idx0 + 1
        self.frac = (tau * self.up - fl).astype(np.float32)
        # steering as one matrix: score = r (k, pairs x lags) @ steer, the mean over pairs of
        # each pair's correlation linearly interpolated at the direction's lag
        n_p, n_l, n_d = len(self.pairs), lags.size, tau.shape[1]
        self.steer = np.zeros((n_p * n_l, n_d), dtype=np.float32)
        d = np.arange(n_d)
        for p in range(n_p):
            np.add.at(self.steer, (p * n_l + self.idx0[p], d), (1.0 - self.frac[p]) / n_p)
            np.add.at(self.steer, (p * n_l + self.idx1[p], d), self.frac[p] / n_p)
        # azimuth neighbours and the >30 deg separation of alternative maxima, per grid azimuth
        ia = np.arange(self.n_az)
        self._az_prev, self._az_next = (ia - 1) % self.n_az, (ia + 1) % self.n_az
        self._az_far = np.abs(wrap_deg(self.az_axis[None, :] - self.az_axis[:, None])) > 30.0
        self._decay: dict[int, tuple[NDArray, NDArray]] = {}
        self.coherence_weight = bool(coherence_weight)
        self.S: NDArray | None = None
        self.A: NDArray | None = None
        self._evidence = EvidenceAge()
        self._level = LevelScale()

    def reset(self) -> None:
        self.S = None
        self.A = None
        self._evidence = EvidenceAge()
        self._level = LevelScale()

    def _rescale(self, seg: NDArray) -> None:
        """Take a batch's samples into :class:`LevelScale` and, when the scale changes, carry
        the state (spectra and energies: squares of the samples) to the new one."""
        f = self._level.take(seg)
        if f == 1.0:
            return
        if self.S is not None:
            self.S = self.S * np.float32(f)
        if self.A is not None:
            self.A = self.A * np.float32(f)
        self._evidence.energy *= f

    def skip(self, n_frames: int) -> None:
        """Age the state through ``n_frames`` missing frames: what ``n_frames`` frames of zero
        spectra would do (``S <- alpha**n S``, the same for the auto spectra and the evidence
        weight; the evidence age grows by ``n_frames``)."""
        n = int(n_frames)
        if n <= 0 or self.S is None:
            return
        f = self.alpha ** n
        self.S = self.S * np.float32(f)
        if self.A is not None:
            self.A = self.A * np.float32(f)
        self._evidence.decay(f, n)

    def _smooth(self, G: NDArray, prev: NDArray) -> NDArray:
        """``S_n = alpha S_{n-1} + (1 - alpha) G_n`` for the k frames of ``G`` (k, ...) from
        ``S_{-1} = prev``, as one (k x k) matrix product (no per-frame Python loop)."""
        k = G.shape[0]
        if k not in self._decay:
            a = self.alpha
            n = np.arange(k)
            low = np.tril(a ** np.clip(n[:, None] - n[None, :], 0, None) * (1.0 - a))
            self._decay[k] = (low.astype(np.float32), (a ** (n + 1.0)).astype(np.float32))
        low, carry = self._decay[k]
        flat = G.reshape(k, -1)
        out = low @ flat + carry[:, None] * prev.reshape(1, -1)
        return out.reshape(G.shape)

    def peak_azimuth(self, prof: NDArray, ia: NDArray) -> NDArray:
        """Azimuths (deg, (k,)) of the maxima at grid indices ``ia`` (k,) of azimuth profiles
        ``prof`` (k, n_az), refined by a parabola through each maximum's two neighbours."""
        n_az = self.n_az
        rk = np.arange(len(ia))
        ym, y0, yp = prof[rk, (ia - 1) % n_az], prof[rk, ia], prof[rk, (ia + 1) % n_az]
        den = ym - 2.0 * y0 + yp
        with np.errstate(divide="ignore", invalid="ignore"):
            d = np.where(den < 0, np.clip(0.5 * (ym - yp) / den, -0.5, 0.5), 0.0)
        return wrap_deg(self.az_axis[ia] + d * self.grid_deg)

    def process(self, segment: NDArray, n_frames: int, hop: int) -> dict[str, NDArray]:
        """Smooth and steer ``n_frames`` consecutive frames of ``segment`` (n_ch, n).

        Returns ``tdoa_s`` (k, n_pairs), ``coherence`` (k,), ``age_frames`` (k,) the
        energy-weighted mean age of the averaged evidence in frames, ``az_deg``/``el_deg`` (k,)
        of the grid maximum and ``alt_az_deg`` (k, 2) of the two strongest other local maxima (NaN
        when none) with their ``alt_coherence`` (k, 2).
        """
        seg = np.asarray(segment, dtype=np.float32)
        self._rescale(seg)
        seg = self._level.scaled(seg)
        fr = frame_signals(seg, self.frame_len, hop)[:, :n_frames]
        if fr.shape[1] != n_frames:  # (fewer rows came back without a word)
            raise EstimationError(f"SmoothedSrp.process: the segment holds {fr.shape[1]} frames "
                                  f"of {self.frame_len} samples (hop {hop}), not {n_frames}")
        X = frame_spectra(fr, self.win, self.nfft, self.k0, self.k1)
        X = np.moveaxis(X, 0, 1)  # (k, n_ch, B) complex64
        G = X[:, self.I] * np.conj(X[:, self.J])  # (k, P, B)
        a = self.alpha
        S = self._smooth(G, self.S if self.S is not None else G[0])
        self.S = S[-1].copy()
        # age of the evidence: energy-weighted mean age (frames) of the averaged cross spectra
        # (a loud syllable keeps dominating the average through the quiet frames after it)
        e = np.abs(G).sum(axis=(1, 2)).astype(float)
        age = np.zeros(len(e))
        for n, en in enumerate(e):
            self._evidence.decay(a)
            self._evidence.add((1.0 - a) * en)
            age[n] = self._evidence.age
        mag = np.abs(S)
        floor = 1e-20 + 1e-12 * mag.max(initial=0.0)
        P = S / np.maximum(mag, floor)
        if self.coherence_weight:
            # weight each bin by its smoothed magnitude-squared coherence |S_ij|^2/(S_ii S_jj):
            # PHAT's whitening otherwise gives the noise-only bins between a voice's harmonics
            # the same say as the harmonics (cf. the Hannan-Thomson / ML weighting)
            auto = X.real**2 + X.imag**2
            A = self._smooth(auto, self.A if self.A is not None else auto[0])
            self.A = A[-1].copy()
            msc = mag**2 / np.maximum(A[:, self.I] * A[:, self.J], floor * floor)
            P = P * np.clip(msc, 0.0, 1.0)
            # keep the normalisation (1 = coherent everywhere) per frame and pair
            P = P * (P.shape[-1] / np.maximum(np.clip(msc, 0.0, 1.0).sum(-1, keepdims=True),
                                             1e-9))
        nb = self.k1 - self.k0
        # (k, P, lags) upsampled correlations on the lag window; peak 1 = coherent
        r = (P.astype(np.complex64) @ self.E).real * np.float32(1.0 / nb)
        k = r.shape[0]
        n_p = len(self.pairs)
        score = r.reshape(k, -1) @ self.steer  # (k, directions)
        best = np.argmax(score, axis=1)
        coh = score[np.arange(k), best]
        # refine each pair's lag: parabola through the upsampled correlation around the grid lag
        lag0 = self.idx[:, best].T  # (k, P) upsampled indices
        rows = np.arange(k)[:, None]
        cols = np.arange(n_p)[None, :]
        # local maximum within +-up upsampled samples (one sample) of the grid lag
        offs = np.arange(-self.up, self.up + 1)
        cand = lag0[..., None] + offs
        vals = r[rows[..., None], cols[..., None], cand]
        j = np.argmax(vals, axis=-1)
        jc = np.clip(j, 1, len(offs) - 2)
        ym = np.take_along_axis(vals, (jc - 1)[..., None], -1)[..., 0]
        y0 = np.take_along_axis(vals, jc[..., None], -1)[..., 0]
        yp = np.take_along_axis(vals, (jc + 1)[..., None], -1)[..., 0]
        den = ym - 2.0 * y0 + yp
        with np.errstate(divide="ignore", invalid="ignore"):
            d = np.where(den < 0, 0.5 * (ym - yp) / den, 0.0)
        lag_up = lag0 - self.lag_max + offs[jc] + np.clip(d, -0.5, 0.5)
        tdoa = lag_up / self.up / self.fs
        # azimuth profile (max over elevations); the best azimuth refined by a parabola through
        # the profile's neighbours, other local maxima >= 30 deg away as alternatives
        n_az = self.n_az
        prof = score.reshape(k, n_az, -1).max(axis=2)  # (k, n_az)
        ia = best // (score.shape[1] // n_az)
        best_az = self.peak_azimuth(prof, ia)
        peak = (prof >= prof[:, self._az_prev]) & (prof > prof[:, self._az_next])
        masked = np.where(peak & self._az_far[ia], prof, -np.inf)
        top = np.argsort(masked, axis=1)[:, ::-1][:, :2]
        alt_c = np.take_along_axis(masked, top, 1)
        alt_az = np.where(np.isfinite(alt_c), self.az_axis[top], np.nan)
        alt_c = np.where(np.isfinite(alt_c), alt_c, np.nan)
        return {"tdoa_s": tdoa, "coherence": coh, "az_deg": best_az, "age_frames": age,
                "el_deg": self.grid_el[best], "alt_az_deg": alt_az, "alt_coherence": alt_c,
                "profile": prof}


#: The fewest frames (their effective number, ``(sum w)^2 / sum w^2``) whose averaged spectra
#: :class:`SmoothedMask` decides on: a guard for the stream's first active frames, not tuned
#: (with the default ``mask_tau_s`` of 0.15 s and a 32-ms hop a talker who keeps sounding
#: fills the averages to ~9.4 effective frames).
MASK_MIN_FRAMES = 4.0
#: :class:`SmoothedMask` decides every this many seconds (rounded to whole hops; the frames in
#: between hold the last decision): its averages change little from one hop to the next, and
#: each decision costs about as much as a frame's whole GCC stage.
MASK_DECISION_S = 0.125
#: A masked pair's track within this many degrees of the side axis (+-90 deg) is in neither
#: half for :meth:`TrackingProcessor._wrong_half`: there the two halves' candidates meet.
MASK_SIDE_DEG = 10.0
#: A masked pair's frames without a GCC measurement of their own take the
#: :class:`SmoothedMask` decision's azimuth as their measurement
#: (:meth:`TrackingProcessor._mask_candidates`; False: such frames give none, as before
#: 2026-12-05's sixty-second session). In a reverberant room few frames pass the GCC's
#: ``min_confidence`` (3-s voices at RT60 0.6 s: 0-11 % of the frames had a direction), so the
#: track coasted and was dropped. Adopted under a rule written before its held-out runs
#: (bench/results/HISTORY.md; still sources in random shoebox rooms, 3 s, noise / male / female at
#: 10 and 20 dB, frames from 1 s on with a frame without an azimuth counted wrong): front/back
#: right on fresh rooms 44.0 -> 54.0 % of the frames (mask2-asym; voices 35.5 -> 49.5; every
#: RT60 class of 0.3 / 0.45 / 0.6 s better) and 50.0 -> 62.0 % (mask2); talkers walking round
#: the mask in free field: mean front/back 88.6 -> 89.1 % (male at 10 dB 83.9 -> 79.3, female
#: at 10 dB 77.0 -> 84.2), mean median error 7.4 -> 6.3 deg. Dev: rooms 44.9 -> 56.8 and
#: 44.0 -> 55.9 %; replacing also the frames whose own GCC was not confident
#: (``prefer_frame_confidence``, as the bare arrays' smoothed response does) was the same in
#: rooms and 0.5 points worse in free field.
MASK_SMOOTHED_MEASUREMENT = True
#: :class:`SmoothedMask` decides front/back as :func:`hearsee.audio.mask.localize_spectra` does
#: with ``room_decision=True``: where the averaged spectra's cues do not fit the mask's
#: free-field model, by the band level differences at the ITD's two azimuths
#: (:data:`hearsee.audio.mask.ROOM_DECISION`, its first form: the stream has no onsets) instead
#: of the whole cost, whose interaural phase reverberation spoils first (False: the whole cost,
#: as before 2026-12-05's sixty-third session). Tried and rejected in the sixty-first session
#: (still sources, 59.4 against 62.6 % of the frames) before the decision's azimuth became a
#: measurement (:data:`MASK_SMOOTHED_MEASUREMENT`); adopted under a rule written before its
#: held-out runs (bench/results/HISTORY.md), all five criteria met -- front/back right of the
#: frames from 1 s on, default -> this: talkers walking round mask2-asym in ``bench/mask.py``'s
#: 6 x 5 x 3.2 m room of RT60 0.3 s (8 per cell, 4 s; rendered by
#: :func:`hearsee.sim.moving.simulate_moving_masked_room`) mean of six cells 68.9 -> 84.1 %
#: (white noise 73.9 / 77.4 -> 96.9 / 96.0 at 10 / 20 dB, voices +6 to +24, every cell better);
#: still sources in random rooms (RT60 0.3-0.6 s, 3 s, 10 and 20 dB) 60.6 -> 65.0 %
#: (mask2-asym, no RT60 class worse; 0.6 s 42.5 -> 50.9) and 58.5 -> 60.0 % (mask2); talkers
#: walking round the mask in free field 89.5 -> 92.7 % (white noise 0.5 points worse, voices
#: 2-7 better); pure sensor noise (3 x 60 s) no measured frame, as before. Dev: room walkers
#: 54.9 -> 75.9 %, still sources 56.8 -> 61.4, free field 94.0 -> 96.9.
MASK_ROOM_DECISION = True
#: Frames whose array pans :class:`TrackingProcessor` keeps (``process``'s ``array_pan_deg``)
#: to turn a smoothed measurement by the turn since its evidence: 64 frames, 2 s at the
#: default 32-ms hop, well past the evidence's largest accepted age.
PAN_HISTORY_FRAMES = 64


class SmoothedMask:
    """A masked pair's front/back decision and 360-degree azimuth through a stream (thesis
    ch. 3's mask in ch. 5's stream).

    :func:`hearsee.audio.mask.localize_mask` decides on a whole recording's frame-averaged
    auto- and cross-spectra. Here the same averages run recursively over the stream's frames,
    ``S <- lam S + X X*`` with ``lam = exp(-hop / tau_s)`` (the evidence of about the last
    ``tau_s`` seconds: recursive averaging of the spectra as :class:`SmoothedSrp` and ODAS's
    SSL module), over the frames that :class:`FrameActivity` finds active (the quiet ones only
    decay the averages), with its noise spectrum of the pauses (a continuous source has none:
    the coherent split, as localize_mask without pauses). Every :data:`MASK_DECISION_S`
    (counted in frames from the stream's start, so that the decisions do not depend on the
    blocks the samples came in) the estimate is :func:`hearsee.audio.mask.localize_spectra`
    -- the one cost of the whole-recording decision, and where the averages' cues do not fit
    the free-field model its room decision without onsets (:data:`MASK_ROOM_DECISION`) -- on
    the averages so far, from :data:`MASK_MIN_FRAMES` effective frames on; the frames in
    between hold it.
    Reconstruction (no streaming form in the thesis); the estimate lags a moving source by
    about ``tau_s`` / 2 and a change of half (a talker walking round behind the head) by up
    to ``tau_s``.

    After each :meth:`process`, ``active`` (bool) and ``age_frames`` hold each of its frames'
    activity and the energy-weighted mean age (frames, :class:`SmoothedSrp`'s) of the evidence
    its held decision was made on, missing frames counted: the tracker's gates and delay for
    the decisions it takes as measurements (:data:`MASK_SMOOTHED_MEASUREMENT`).

    Frames: Hann windows of ``frame_len`` samples at the stream's hop, their rfft bins within
    :func:`hearsee.audio.mask.analysis_bins`. Levels: the samples are scaled by
    :func:`level_scale` of the largest |sample| seen (:class:`LevelScale`; the state carried
    along when it changes, as :class:`SmoothedSrp`'s); the decision is scale-free. Units:
    seconds, Hz, degrees.
    """

    def __init__(self, model: Any, fs: float, frame_len: int, hop: int, tau_s: float,
                 history_frames: int) -> None:
        from hearsee.audio.mask import analysis_bins, default_bands

        self.model, self.fs, self.frame_len = model, float(fs), int(frame_len)
        self.nfft = self.frame_len
        self.edges = default_bands(model.f_max)
        f = np.fft.rfftfreq(self.nfft, 1.0 / self.fs)
        bins = np.flatnonzero(analysis_bins(f, self.edges, model))
        if bins.size < 4:
            raise ConfigError(
                f"a {self.frame_len}-sample frame at {fs:g} Hz holds {bins.size} frequency "
                f"bins within the masked pair's bands ({self.edges[0]:g}-{self.edges[-1]:g} Hz, "
                "below 0.9 x its model's f_max); 4 are needed: use a longer frame")
        self.k0, self.k1 = int(bins[0]), int(bins[-1]) + 1
        self.freqs = f[self.k0:self.k1]
        self.win = np.hanning(self.frame_len).astype(np.float32)
        self.lam = math.exp(-hop / self.fs / float(tau_s))
        self.every = max(1, int(round(MASK_DECISION_S * self.fs / hop)))
        self.activity = FrameActivity(history_frames, self.frame_len, self.win, self.nfft,
                                      self.k0, self.k1)
        self._level = LevelScale()
        self._n = 0  # frames since the stream's start (missing ones too)
        self._since = 0  # frames since the held decision was made
        self.active = np.zeros(0, bool)  # the last batch's active frames
        self.age_frames = np.zeros(0)  # ... and the age of each one's decision's evidence
        self.reset()

    def reset(self) -> None:
        """Forget the averaged spectra and the decision (the head turned: they describe the
        old pose); the activity history and the level scale it is kept at stay (the noise
        floor does not turn with the head), and so does the decisions' schedule."""
        self._S = np.zeros((3, self.k1 - self.k0), complex)  # |X0|^2, |X1|^2, X0 X1*
        self._w = self._w2 = 0.0  # sum of the weights and of their squares
        self._last: Any = None  # the decision the frames hold
        # the averages' energy and its mean age (frames), and that age when the held decision
        # was made
        self._evidence = EvidenceAge()
        self._decided_age = 0.0

    def skip(self, n_frames: int) -> None:
        """Age the averages through ``n_frames`` missing frames (they decay, nothing is added;
        they count towards the next decision's time)."""
        n = max(int(n_frames), 0)
        self._decay(n)
        self._since += n
        self._n += n

    def _decay(self, n: int) -> None:
        self._S *= self.lam**n
        self._w *= self.lam**n
        self._w2 *= self.lam ** (2 * n)
        self._evidence.decay(self.lam**n, n)

    def process(self, segment: NDArray, n_frames: int, hop: int) -> list[Any]:
        """Average and decide ``n_frames`` consecutive frames of ``segment`` (2, n): one
        :class:`~hearsee.audio.mask.MaskLocalization` per frame, None where the averages hold
        too few frames or no coherent source."""
        from hearsee.audio.mask import localize_spectra

        seg = np.asarray(segment, dtype=np.float32)  # (single precision, as the other stages)
        factor = self._level.take(seg)  # (the state goes to a new level_scale: exactly)
        if factor != 1.0:
            self._S *= factor
            self._evidence.energy *= factor
            self.activity.rescale(factor)
        seg = self._level.scaled(seg)
        fr = frame_signals(seg, self.frame_len, hop)[:, :n_frames]
        if fr.shape[1] != n_frames:
            raise EstimationError(f"SmoothedMask.process: the segment holds {fr.shape[1]} "
                                  f"frames of {self.frame_len} samples (hop {hop}), not "
                                  f"{n_frames}")
        active, noise = self.activity(fr)
        X = frame_spectra(fr, self.win, self.nfft, self.k0, self.k1)  # (2, k, B)
        out: list[Any] = []
        self.active = np.asarray(active, bool)[:n_frames]
        self.age_frames = np.zeros(n_frames)
        for i in range(n_frames):
            self._decay(1)
            if active[i]:
                x0, x1 = X[0, i], X[1, i]
                p0, p1 = x0.real**2 + x0.imag**2, x1.real**2 + x1.imag**2
                self._S[0] += p0
                self._S[1] += p1
                self._S[2] += x0 * np.conj(x1)
                self._w += 1.0
                self._w2 += 1.0
                self._evidence.add(float(p0.sum() + p1.sum()))
            if self._n % self.every == 0:
                self._last = None
                self._since = 0
                self._decided_age = self._evidence.age
                if self._w > 0 and self._w**2 / self._w2 >= MASK_MIN_FRAMES - 1e-9:
                    S = self._S / self._w
                    nz = None if noise is None or not np.all(np.isfinite(noise[i])) else (
                        noise[i].mean(axis=0).astype(float))
                    self._last = localize_spectra(self.model, self.freqs, S[0].real,
                                                  S[1].real, S[2], self._w**2 / self._w2, nz,
                                                  self.edges, fs=self.fs,
                                                  room_decision=MASK_ROOM_DECISION)
            self.age_frames[i] = self._decided_age + self._since
            self._since += 1
            self._n += 1
            out.append(self._last)
        return out


# ---------------------------------------------------------------------------- processing
@dataclass
class StreamConfig:
    """Explicit configuration of the processing stages (ODAS style).

    frame_ms, hop_ms : analysis frame and hop, milliseconds
    method : GCC weighting (``phat``, ``scot``, ...)
    refine : sub-sample peak refinement of the GCC: ``interp`` (default), exact band-limited
        interpolation, or ``parabolic``, the cheapest (stream ~1.15x faster). A parabola's
        bias towards whole-sample lags varies slowly as a speaker walks, so the tracker cannot
        average it away: on bench/tracking.py part A (room walks of seeds 0, 100 and 200, 24 per
        condition; one constant-velocity filter) ``interp`` raised white noise's per-frame /
        tracked ratio from 1.49-1.53x to 1.57-1.74x, voices unchanged (2.4-3.2x)
    min_confidence : frames whose GCC peak-to-second-peak ratio is below this in any pair give
        no measurement (:func:`~hearsee.audio.tdoa.estimate_tdoas`)
    band_hz : optional frequency band for the GCC, Hz
    itd_filter : smooth the TDOAs with the ITD Kalman filter (thesis 2.2.2) before localizing
    in_plane : the speaker is at the height of a planar array of three or more microphones (a
        robot's head at mouth height): a frame's own direction models the spherical wavefront
        of a source assumed 2 m away in the array plane
        (:func:`~hearsee.audio.localize.near_field_in_plane`) and the smoothed steered response
        scans only that plane, so the elevation is 0 (for a horizontal array). Coplanar
        microphones cannot tell a nearby source's curved wavefront or a floor reflection from
        elevation: a male voice walking 1.2-1.6 m from the three-mic preset at its height
        (2.5 s, RT60 0.3 s, 20 dB, three noise seeds) gave tracked elevations of median
        1.6-10.6 deg (90th percentile 8-25 deg) by default, and with ``in_plane`` a lower
        azimuth error (median 0.9-1.3 -> 0.7-0.8 deg). The per-frame wavefront fit costs
        speed: ~60x real time instead of ~80x (CPU, three-mic at 16 kHz, 10 s file). Ignored
        for linear and volume arrays. Default False
    sigma_meas_deg, sigma_accel_dps2 : direction tracker noise (degrees, deg/s^2);
        ``sigma_meas_deg`` is the measurement noise where no model below applies
    sigma_frame_deg : measurement noise model of a frame's own GCC direction: standard deviation
        ``sigma_frame_deg / confidence`` degrees (confidence = the smallest pair's peak ratio);
        None = ``sigma_meas_deg``
    sigma_srp_deg : ... of a smoothed steered-response direction: ``sigma_srp_deg (1 - c) / c``
        degrees for normalised steered power ``c``; None = ``sigma_meas_deg``
    sigma_min_deg : floor of both models, degrees. The forms follow the measured spread of the
        directions per confidence / coherence bin, and 6 / 20 deg were chosen on the seed-100
        walks of ``bench/tracking.py`` (a fixed 10 deg over-smoothed white noise: every frame
        is good, and turns lagged by several frames). Together with ``spectrum_alpha`` 0.5 and
        ``sigma_accel_dps2`` 200 they trade part of the voices' RMSE margin for less lag: on the
        seed-100/110 walks (room, SNR 10/20 dB) alpha 0.8 / 40 deg / 100 deg/s^2 left the
        voices' tracks 1.3-6 frames behind (median), these settings 0.2-5.6 (free field 0.2-3.6
        instead of 0.7-6) with the tracked RMSE still 3.5-8x below the per-frame one (white
        noise at 10 dB: 1.98x instead of 2.07x). ``sigma_frame_deg`` 4 scored 2.03x there but
        lost one white-noise walk of the seed-0 benchmark run (1.01x): not adopted. Rechecked
        with the faithful moving-source renderer on the seed-100 walks (the noise scales also on
        seed 200):
        ``sigma_frame_deg`` 9 / 12, ``sigma_srp_deg`` 30, ``prefer_frame_confidence`` 1.2 / 2 /
        3 / inf, ``spectrum_alpha`` 0.3 / 0.7, an SRP band up to 6 or 7.9 kHz and a clutter-
        weighted (probabilistic data association) update each helped one condition and hurt
        another, or lengthened the lag; none was adopted.
        The declared noise is several times the measurements' actual spread, on purpose
        (measured 2026-11-27 on part-A-like room walks: median 25 deg declared for the smoothed
        directions of voices at 10 dB, whose robust spread is 4-5 deg): a 10 dB voice gives a
        measurement in only 12-23 % of the frames, and calibrated values (``sigma_srp_deg`` 5)
        let a noisy angular rate carry the track off between syllables (female voice: tracked
        RMSE 8.6 -> 12.2 deg, lag 2.0 -> 0.7 frames; see bench/results/HISTORY.md).
    direction_modes_dps2 : angular acceleration noises (deg/s^2) of the interacting-multiple-
        model :class:`~hearsee.audio.tracking.DirectionIMM`, one constant-velocity mode per
        value (default ``IMM_MODES_DPS2`` = (50, 2000): quiet walking / turning); None tracks
        the direction with one constant-velocity
        :class:`~hearsee.audio.tracking.DirectionKalman` (``sigma_accel_dps2``) instead. The
        IMM is the default since the moving-source renderer became faithful (2026-11-24): on
        bench/tracking.py part A's room walks (seeds 0, 100, 200; 24 per condition, SNR 10/20
        dB) the single filter's median lag on turning walks reached 4.9 frames (female voice,
        10 dB; 1.7-4.9 for the voices), the IMM's (then with a 1000 deg/s^2 turning mode)
        0.3-1.8 (free field 0.3-2.0), with the voices' tracked RMSE still 2.4-3.0x below the
        per-frame one (single filter 2.4-3.2x); the 2000 deg/s^2 mode's numbers are at
        :data:`~hearsee.audio.tracking.IMM_MODES_DPS2`.
        It costs ~0.19 ms per frame (one filter ~0.05): the stream runs ~100x instead of
        ~125x faster than real time (three-mic, 16 kHz, block 4096, process CPU time; 87x in
        bench/tracking.py part C of 2026-11-24)
    mode_dwell_s : the IMM's mean time in one mode, seconds
    direction_rate_tau_s : time constant, seconds, with which the direction tracker's angular
        rates relax toward zero (default
        :data:`~hearsee.audio.tracking.DIRECTION_RATE_TAU_S`; None = constant velocity, the
        default before 2026-11-24's sixth session)
    direction_angle_noise_ratio : the IMM direction tracker's azimuth random walk, times the
        latest measurement's azimuth variance per second (1/s; default
        :data:`~hearsee.audio.tracking.DIRECTION_ANGLE_NOISE_RATIO`; 0 = none; not used by the
        one-filter tracker, ``direction_modes_dps2=None``)
    elevation_accel_ratio : the direction tracker's elevation acceleration noise as a fraction
        of its azimuth's (default
        :data:`~hearsee.audio.tracking.ELEVATION_ACCEL_RATIO` = 0.1: a walking speaker's
        elevation changes slowly; 1 = one model for both angles, the default before
        2026-11-24's fifth session)
    planar_elevation_sigma_scale : a planar array's elevation measurement noise as a multiple
        of its azimuth's. Its TDOAs depend on the elevation only through cos(el), so a speaker
        10-15 deg above its plane is located 4-6x less precisely in elevation than in azimuth
        (cot(el)); treating both alike let noisy elevations steer the gate and the IMM's mode
        weights. With 4 and ``elevation_accel_ratio`` 0.1, on the dev walks of
        bench/tracking.py part A (seeds 100/110, 6 straight and 6 turning walks per condition,
        room, 2026-11-24, fifth session) the tracked elevation's RMSE fell from 16-33 deg to
        9-19 deg; the tracked azimuth's RMSE on the per-frame frames went +3 / +4 / +4 % for
        the synthetic male voice at 10 / 20 dB and the female at 10 dB, +0.4 % for the female at
        20 dB and -5 / -10 % for CMU ARCTIC speech at 10 / 20 dB, pooled lags within 0.5 frames
        (the ratio alone: elevation 12-17 deg, azimuth +0-9 %; a scale from the measured
        elevation, cot(el) up to 10, was worse in elevation). On the held-out seed-0 run (16
        walks per condition) the per-frame / tracked azimuth ratios were 2.28 / 1.99 / 6.11 /
        3.62x for the synthetic voices (male / female, 10 / 20 dB; 2.28 / 1.99 / 6.71 / 3.59x
        before) and white noise 1.24 / 1.37x (1.19 / 1.40x). Applied to horizontal planar
        arrays (plane within 10 deg of level, like the presets) only: volume arrays measure
        both angles alike, linear ones give no elevation
    motion_model : the 3D tracker of the camera + ITD measurements: ``"cv"`` (default),
        constant velocity, or ``"ca"``, the constant-acceleration
        :class:`~hearsee.audio.tracking.MotionKalman` on the camera-ray fixes
    ray_measurements : what the ``"cv"`` tracker fuses: ``"tdoa"`` (default), the image point
        and each pair's TDOA with its own gate
        (:class:`~hearsee.fusion.audiovisual.RayTdoaTracker`), or ``"fix"``, the camera-ray fixes
        (:class:`~hearsee.fusion.audiovisual.RayTracker`, the default before 2026-11-25). With
        the stream's own frames (64/32 ms, 2 px) on part B's dev walks of ``bench/tracking.py``
        (seeds 100/200, 64 walks, first rig) 7.74 -> 7.06 cm pooled median, velocity RMSE 0.31
        -> 0.19 m/s
    sigma_accel : the ``"cv"`` tracker's acceleration noise, m/s^2; None = its own default
        (0.1 for ``"tdoa"``, 0.2 for ``"fix"``)
    sigma_jerk : the ``"ca"`` tracker's process noise: the acceleration's white increment
        per update (hop), m/s^2 (:class:`hearsee.audio.tracking.MotionKalman`)
    accel_tau_s : correlation time of the ``"ca"`` tracker's acceleration (Singer), s; None =
        pure CA
    sigma_tdoa_s, sigma_px : measurement noise of the camera-ray fix (seconds, pixels);
        ``sigma_tdoa_s`` None = the value each tracker was tuned with (``"cv"`` 8 us,
        :data:`~hearsee.fusion.audiovisual.RAY_SIGMA_TDOA_S`; ``"ca"`` 20 us; bench/tracking.py
        part B, seed-100 walks)
    range_m : search interval along the camera ray, metres
    max_fix_residual_samples : a camera-ray fix whose RMS ITD residual exceeds this many samples
        is discarded (with three microphones the three TDOAs must close, t01 + t12 = t02; a
        reflection that captures one pair's GCC peak breaks that and leaves a large residual)
    spectrum_alpha : recursive smoothing factor of the cross-power spectra behind the direction
        tracker's measurements (:class:`SmoothedSrp`); 0 = each frame's own GCC (the per-frame
        TDOAs of ``method``/``refine``). The per-frame (``raw_*``) outputs of an :class:`Update`
        always stay the plain per-frame estimates.
    min_coherence : smoothed measurements whose normalised steered power is below this are not
        used (no source, or diffuse noise and reverberation only). Uncorrelated sensor noise
        alone peaked at 0.24 in 60 s (three-mic, 16 kHz, alpha 0.5). 0.3 was tried on
        bench/tracking.py part A (2026-11-25, 16 walks per condition): on dev seed 100 it
        raised the voices' per-frame / tracked ratios at 10 dB (male 2.32 -> 2.87, female 2.20
        -> 2.94; more measurements where the track otherwise coasts with a stale rate), but on
        held-out seed 777 the female voice's pooled lag at 10 dB went from 0.63 to 2.63 frames
        (beyond the 2-frame target) and the male voice's ratios fell (10 dB 2.98 -> 2.68, tracked
        RMSE 9.5 -> 19.5 deg; 20 dB 7.13 -> 5.96): not adopted
    gated_min_coherence : a lower detection threshold that holds only inside the running
        track's gate (tracker-aided detection: the track's prediction is prior knowledge of
        where the source is, so a weaker peak there is far less likely a false alarm than one
        anywhere on the grid -- Willett, Niu & Bar-Shalom 2001, "Integration of Bayes detection
        with target tracking", IEEE Trans. Signal Processing 49(1)). When a frame has no
        measurement (no confident frame direction, no smoothed one above ``min_coherence``)
        and the track has gone ``gated_after_s`` seconds without one, the steered response's
        largest local maximum within ``gate_sigmas`` standard deviations of the predicted
        azimuth (half-width clipped to ``gate_deg``, degrees) is used when its normalised
        steered power reaches this value, as a smoothed measurement of that power. Needs
        ``spectrum_alpha`` > 0; None = off. Sensor noise alone stays below it (0.24 over the
        whole grid in 60 s, see ``min_coherence``), so a track whose talker has gone silent is
        still dropped after ``max_coast_s``; no track is ever started this way. Default None
        (off): with 0.3 after 0.2 s of coasting (``gated_after_s``), set on dev walks of
        bench/tracking.py part A, the held-out seeds of that benchmark (16 walks per
        condition) gave per-frame / tracked ratios, female voice 10 dB, 2.15 -> 3.22x (seed
        777) and 1.74 -> 2.25x (778); male 10 dB 2.98 -> 2.81x and 2.62 -> 2.63x; 20 dB voices
        7.13 -> 7.19x, 3.53 -> 3.92x, 7.88 -> 8.88x, 4.40 -> 4.87x; ARCTIC speech and white
        noise within 1 % -- but the female voice's pooled lag on turning walks at 10 dB went
        from 0.63 to 1.68 frames (777) and from 0.61 to 2.68 (778), past the 2-frame rule the
        stream's defaults are held to (male 10 dB +0.2 / +0.04, 20 dB +0.1 / +0.2): a peak
        picked near a lagging prediction keeps the track behind in a turn. Detecting in every
        frame without a measurement (``gated_after_s`` 0) measured 3-4x more often and
        lengthened the lag more (dev walks, male voice 10 dB: +0.35 / +1.1 frames at 0.3,
        +1.1 / +1.4 at 0.25). Use it where a lower error through a weak talker's pauses matters
        more than ~1-2 frames (32-64 ms) of lag in sharp turns
    gate_sigmas, gate_deg, gated_after_s : see ``gated_min_coherence``
    activity_history_s : seconds of past frames (rounded to whole hops, this frame included)
        over which the per-frame GCC stage decides a frame's activity and its noise spectrum
        (:class:`FrameActivity`: causal, so the tracks do not depend on the block size the
        input comes in; until 2026-12-02 each batch of frames decided its own). On the dev
        walks of ``bench/tracking.py`` part A (seed 100, 6 straight room walks per condition,
        2026-12-02) 0.5, 1 and 2 s gave the same tracked azimuth RMSE within 0.1 deg (male /
        female voice 10 dB 5.6 / 7.6 deg, 20 dB 3.1 / 2.3, white noise 20 dB 1.1), which is
        what the benchmark's block of 2048 had measured (5.6 / 7.6, 3.1 / 2.2, 1.1) and below
        the CLI's block of 4096 (6.3 / 8.8, 3.2 / 3.3, 1.1); 1 s is the middle
    snr_weight : SNR-weight the per-frame GCC (``snr_weight`` of
        :func:`~hearsee.audio.tdoa.estimate_tdoas`) with the noise spectrum of the inactive
        frames of the last ``activity_history_s`` (:class:`FrameActivity`). Default False:
        on the same dev walks it measured more frames (female voice 10 dB: 45 % instead of
        18 %) but more of them reflections, and the female voice's tracked RMSE at 10 dB rose
        from 7.6 to 19.6 deg (1 s; a track on one of six walks ran off at 50-130 deg; male 10
        dB 5.7 -> 6.1, 20 dB 3.1 -> 3.4, female 20 dB 2.3 -> 2.9). With batches of 2048 samples
        (the benchmark's block) the old batch decision rarely found the 3 quiet frames it
        needs, so the stream was tuned and measured almost without it
    srp_band_hz : frequency band of the smoothed steered response, Hz
    srp_coherence_weight : weight the smoothed PHAT spectra by their magnitude-squared
        coherence (:class:`SmoothedSrp`)
    alt_ratio : other local maxima of the steered response with at least this share of the best
        one's power are offered to the tracker as alternative directions (data association)
    max_alt_ratio : a smoothed measurement whose second local maximum reaches this share of the
        best one's power is ambiguous and not used (1 = no such test)
    max_evidence_age_frames : a smoothed measurement whose evidence is older than this (energy-
        weighted mean age, frames: in a pause the average still holds the last loud frames) is
        not used; younger ones enter the tracker with their age as measurement delay. The same
        for a masked pair's smoothed front/back decisions, which give frames without a GCC
        measurement their azimuth (:data:`MASK_SMOOTHED_MEASUREMENT`; there
        ``mask_min_phase_match`` gates them and ``sigma_srp_deg`` gives their measurement noise)
    prefer_frame : frames whose own GCC gives a confident measurement use it (no delay); only
        the others use the smoothed steered response
    prefer_frame_confidence : the same for frames whose own GCC confidence (smallest pair
        peak ratio) reaches this value (inf = never; 1.5 chosen on the seed-100 walks of
        bench/tracking.py). Tried and rejected (2026-11-26, dev seed 300 of part A, 8 walks per
        condition): using a frame's own direction below this confidence when the smoothed
        response gives none (after 0 or 0.2 s of coasting) -- those frames are mostly
        reflections: per-frame / tracked ratios male 10 dB 2.89 -> 0.83 / 0.80x, female 10 dB
        3.10 -> 0.97 / 1.17x, white noise unchanged
    max_coast_s : seconds the direction track may go without an accepted measurement before it
        is dropped (no azimuth reported until a measurement restarts it: the coasted direction's
        uncertainty has grown past use by then -- ODAS's tracker deletes inactive tracks the
        same way); None = coast for ever
    reacquire_s : seconds of consecutive measurements outside the track's gate after which the
        direction tracker restarts at the newest one (rounded up to whole hops). Short values
        follow a second speaker who talks while the tracked one pauses: in
        ``examples/ch5_tracking.py``'s case III (a walking female voice, a static male
        interferer ~10 dB weaker) 4 frames (0.13 s, the filters' own default) put the track on
        the interferer in 11 % of the frames, 8 frames in 3 %, 0.5 s in none; on
        bench/tracking.py part A's single-speaker walks (seeds 0/100/200, 8 each) the three
        gave the same numbers (the 16-walk seed-0 run: white noise's ratio within 0.02)
    mask_tau_s : masked pairs: time constant (s) of the averaged spectra that decide front or
        back (:class:`SmoothedMask`); longer is steadier, shorter follows a talker walking round
        the head sooner. 0.15 s chosen among 0.1-2 s on dev talkers (seed 170: mask2-asym, free
        field, 8 per signal and SNR, one in four still, the others walking round the array
        at 14-86 deg/s): front/back of the frames from 1 s on, noise / male / female at 10 and
        20 dB, 100 / 100, 95 / 93, 88 / 95 % (1 s: 96 / 96, 88 / 83, 79 / 76 %; the frames
        of ``hearsee localize``, one half for the whole recording: 57 / 57, 40 / 65, 73 / 63)
    mask_decide_confidence : masked pairs: a frame's ITD gives the tracker only the half that
        the front/back decision chose when that decision's confidence (the probability of the
        chosen half, 0.5-1) reaches this; below it, both halves' candidates, the chosen one
        first. A track in the ruled-out half, more than ``MASK_SIDE_DEG`` from the side axis,
        is then restarted at once at the chosen half's candidate (1 = always both: the
        tracker's continuity alone keeps the half -- but for decisions whose confidence
        rounds to 1, which a clear recording's often does)
    mask_min_phase_match : masked pairs: the least phase match (``rho``, the coherence-weighted
        mean cosine of the averaged cross-spectrum's phase against the mask's table at the
        decided azimuth) with which a front/back decision gives its azimuth to a frame without
        a GCC measurement (:data:`MASK_SMOOTHED_MEASUREMENT`; 0.4, ``min_coherence``'s
        default, which gated them when they were adopted). Lower admits more of a
        reverberant room's decisions -- voices at RT60 0.6 s and 10 dB have a median of 0.31 --
        and more of noise's: 0.3 was tried under a rule written first (bench/results/HISTORY.md):
        fresh rooms' frames in the right half 58.3 -> 64.1 % (mask2-asym, every RT60 class
        better), free-field walking talkers unchanged, but 60 of 5622 frames of pure sensor
        noise (3 x 60 s) measured, against none at 0.4 -- a spurious measurement every ~3 s
        of silence; not adopted. A stream that is never long silent may set it lower
    max_sources : several talkers at once, some of whom may walk: the frames' own directions
        (the ``raw_*`` of :class:`Update`; with ``talker_peak_ratio``, also a second one
        per frame) are also followed by :class:`hearsee.audio.sources.SourceTracker`, and
        each update's ``sources`` names up to this many talkers (2 to
        :data:`hearsee.audio.sources.MAX_SOURCES`); None (the default) = one talker, no
        ``sources``. Told the array's pans
        (:meth:`TrackingProcessor.process`' ``array_pan_deg``), the talkers' tracks are turned
        back with the array; a linear array's, tracked in its angles' sines, follow the turn as
        motion. Not for a masked pair
    talker_peak_ratio : with ``max_sources``, a frame that has its own direction also gives
        the talkers' tracker the strongest other maximum of its smoothed steered response
        that reaches this share (0-1] of the response's peak and lies
        :data:`~hearsee.audio.sources.TRACK_MERGE_DEG` or more from the frame's own
        direction (:func:`hearsee.audio.sources.second_direction`; a frame's GCC peaks name
        the louder talker, the response shows both): the default,
        :data:`~hearsee.audio.sources.TALKER_PEAK_RATIO`, was chosen on dev recordings and
        held out; None = the frames' own directions only (as before 2026-12-07), as with
        ``spectrum_alpha=0``, which computes no steered response
    talker_modes_dps2 : with ``max_sources``, each talker's track an IMM of constant-velocity
        modes with these angular acceleration noises (deg/s^2, two or more; the default
        :data:`~hearsee.audio.sources.TALKER_MODES_DPS2`, (5, 40): a quiet and a walking mode),
        its rates not relaxing, and a frame joining a track within
        :data:`~hearsee.audio.sources.TALKER_MAX_JUMP_DEG` of its prediction: a walker's track
        keeps up with the walker, so where the walker crosses another talker's direction each
        keeps its ``id`` far more often (held out: the walker under one id before and after
        the crossing 11 -> 44 % of the pairs of moments, the still talker 51 -> 70 %). None =
        the offline tracks' one filter and gate (:func:`hearsee.audio.sources.track_sources`'
        defaults; the stream's before 2026-12-07)
    """

    frame_ms: float = 64.0
    hop_ms: float = 32.0
    method: str = "phat"
    refine: str = "interp"
    min_confidence: float = 1.0
    band_hz: tuple[float, float] | None = None
    itd_filter: bool = False
    in_plane: bool = False
    sigma_meas_deg: float = 10.0
    sigma_accel_dps2: float = 200.0
    motion_model: str = "cv"
    ray_measurements: str = "tdoa"
    sigma_accel: float | None = None
    sigma_jerk: float = 0.5
    sigma_tdoa_s: float | None = None
    sigma_px: float = 2.0
    range_m: tuple[float, float] = (0.2, 6.0)
    max_fix_residual_samples: float = 0.5
    accel_tau_s: float | None = 0.5
    spectrum_alpha: float = 0.5
    min_coherence: float = 0.4
    srp_band_hz: tuple[float, float] | None = (300.0, 3500.0)
    alt_ratio: float = 0.8
    srp_coherence_weight: bool = True
    max_alt_ratio: float = 1.0
    max_evidence_age_frames: float = 8.0
    prefer_frame: bool = False
    prefer_frame_confidence: float = 1.5
    max_coast_s: float | None = 1.5
    reacquire_s: float = 0.5
    sigma_frame_deg: float | None = 6.0
    sigma_srp_deg: float | None = 20.0
    sigma_min_deg: float = 1.5
    direction_modes_dps2: tuple[float, ...] | None = IMM_MODES_DPS2
    mode_dwell_s: float = 1.0
    direction_rate_tau_s: float | None = DIRECTION_RATE_TAU_S
    direction_angle_noise_ratio: float = DIRECTION_ANGLE_NOISE_RATIO
    elevation_accel_ratio: float = ELEVATION_ACCEL_RATIO
    planar_elevation_sigma_scale: float = 4.0
    gated_min_coherence: float | None = None
    gate_sigmas: float = 3.0
    gate_deg: tuple[float, float] = (6.0, 30.0)
    gated_after_s: float = 0.2
    activity_history_s: float = 1.0
    snr_weight: bool = False
    mask_tau_s: float = 0.15
    mask_decide_confidence: float = 0.9
    mask_min_phase_match: float = 0.4
    max_sources: int | None = None
    talker_peak_ratio: float | None = TALKER_PEAK_RATIO
    talker_modes_dps2: tuple[float, ...] | None = TALKER_MODES_DPS2

    def __post_init__(self) -> None:
        _check_config(self)


#: StreamConfig's numbers that must be finite and > 0 (None allowed for the optional ones)
_POSITIVE = ("sigma_meas_deg", "sigma_accel_dps2", "sigma_jerk", "sigma_px", "sigma_min_deg",
             "max_fix_residual_samples", "max_evidence_age_frames", "reacquire_s",
             "planar_elevation_sigma_scale", "mode_dwell_s", "activity_history_s",
             "mask_tau_s")
_POSITIVE_OR_NONE = ("sigma_accel", "sigma_tdoa_s", "accel_tau_s", "max_coast_s",
                     "sigma_frame_deg", "sigma_srp_deg")
#: ... that must lie in [low, high] (both inclusive; finite)
_WITHIN = {"min_confidence": (0.0, np.inf), "direction_angle_noise_ratio": (0.0, np.inf),
           "min_coherence": (0.0, 1.0),
           "alt_ratio": (0.0, 1.0), "max_alt_ratio": (0.0, 1.0),
           "mask_decide_confidence": (0.5, 1.0), "mask_min_phase_match": (0.0, 1.0)}


def _check_config(cfg: StreamConfig) -> None:
    """ConfigError naming the first out-of-range setting of ``cfg`` (checked when a
    StreamConfig is made: before 2026-11-26 most were not, and a NaN noise put NaN azimuths in
    the output, a negative ``spectrum_alpha`` silently turned the smoothing off, an infinite
    ``reacquire_s`` raised an OverflowError). Settings that depend on the array and the
    sample rate (frame length vs the array's delays) are checked by the stream itself."""
    def bad(name: str, rule: str) -> ConfigError:
        return ConfigError(f"StreamConfig.{name} must be {rule}, got {getattr(cfg, name)!r}")

    check_frame_ms(cfg.frame_ms, cfg.hop_ms, names=("frame_ms", "hop_ms"))
    for name in _POSITIVE + _POSITIVE_OR_NONE:
        v = getattr(cfg, name)
        if v is None and name in _POSITIVE_OR_NONE:
            continue
        if not (is_real(v) and v > 0):
            raise bad(name, "a finite number > 0" + (" or None" if name in _POSITIVE_OR_NONE
                                                      else ""))
        # (noises whose squares leave the normal floats: 1e300 overflowed in the trackers,
        # 1e-170 squared to a zero variance)
        if name.startswith("sigma_"):
            lo, hi = ITD_STD_RANGE_S if name == "sigma_tdoa_s" else NOISE_RANGE
            if not lo <= v <= hi:
                raise bad(name, f"a number in [{lo:g}, {hi:g}]")
    for name, (lo, hi) in _WITHIN.items():
        v = getattr(cfg, name)
        if not (is_real(v) and lo <= v <= hi):
            raise bad(name, f"a number in [{lo:g}, {hi:g}]")
    if not (is_real(cfg.spectrum_alpha) and 0.0 <= cfg.spectrum_alpha < 1.0):
        raise bad("spectrum_alpha", "in [0, 1) (0 = no smoothing)")
    # (the stage passes bool(snr_weight): "no" switched the weighting on, "ml" gave the plain one;
    # in_plane="no" likewise switched the in-plane model on, and so the other switches)
    for name in ("snr_weight", "itd_filter", "in_plane", "srp_coherence_weight",
                 "prefer_frame"):
        if not isinstance(getattr(cfg, name), bool | np.bool_):
            raise bad(name, "True or False")
    if cfg.max_sources is not None:
        from hearsee.audio.sources import MAX_SOURCES

        ms = cfg.max_sources
        if not (isinstance(ms, int | np.integer) and not isinstance(ms, bool)
                and 2 <= ms <= MAX_SOURCES):
            raise bad("max_sources", f"None or a whole number 2 to {MAX_SOURCES}")
    tpr = cfg.talker_peak_ratio
    if tpr is not None and not (is_real(tpr) and 0.0 < tpr <= 1.0):
        raise bad("talker_peak_ratio", "None or in (0, 1]")
    if cfg.talker_modes_dps2 is not None:
        from hearsee.audio.sources import _modes

        try:
            _modes(cfg.talker_modes_dps2, NOISE_RANGE)
        except ConfigError:
            raise bad("talker_modes_dps2", f"None or two or more angular acceleration noises "
                      f"(deg/s^2, {NOISE_RANGE[0]:g} to {NOISE_RANGE[1]:g})") from None
    pfc = cfg.prefer_frame_confidence
    if not ((is_real(pfc) or pfc == math.inf) and pfc > 0):  # (inf = never)
        raise bad("prefer_frame_confidence", "> 0 (inf = never)")
    r = (np.asarray(cfg.range_m, dtype=float).reshape(-1) if real_entries(cfg.range_m)
         else np.zeros(0))  # (text: numpy's ValueError)
    if not (r.size == 2 and np.all(np.isfinite(r)) and 0 < r[0] < r[1]):
        raise bad("range_m", "(near, far) metres with 0 < near < far")
    _check_gating(cfg)


def _stream_config(config: StreamConfig | None) -> StreamConfig:
    """``config``, or the default StreamConfig for None; a ConfigError for anything else (a
    plain dict such as ``{"frame_ms": 32}`` was taken and failed at the first frame with a
    builtin AttributeError, an empty one silently meant the defaults). The package builds its
    StreamConfigs by keyword (``StreamConfig(frame_ms=32)``), never from a mapping."""
    if config is None:
        return StreamConfig()
    if not isinstance(config, StreamConfig):
        raise ConfigError(f"config must be a StreamConfig (e.g. StreamConfig(frame_ms=32)) or "
                          f"None, got {type(config).__name__} {config!r:.60}")
    return config


def _number_pair(value: Any, name: str, unit: str) -> tuple[float, float]:
    """``value`` as two finite numbers ``(low, high)``, else a ConfigError naming ``name``
    (a malformed pair raised Python's unpacking ValueError or numpy's TypeError)."""
    try:
        lo, hi = value
    except (TypeError, ValueError):
        lo = hi = None
    if not (is_real(lo) and is_real(hi)):
        raise ConfigError(f"{name} must be two numbers (low, high) in {unit}, got {value!r}")
    return float(lo), float(hi)


def _check_gating(cfg: StreamConfig) -> None:
    """ConfigError for an out-of-range gated-detection setting of ``cfg``."""
    g = cfg.gated_min_coherence
    if g is not None and not (is_real(g) and 0.0 < g <= 1.0):
        raise ConfigError(f"gated_min_coherence must be in (0, 1] or None, got {g!r}")
    if g is not None and not cfg.spectrum_alpha > 0:
        raise ConfigError("gated_min_coherence needs the smoothed steered response "
                          f"(spectrum_alpha > 0), got spectrum_alpha={cfg.spectrum_alpha}")
    lo, hi = _number_pair(cfg.gate_deg, "gate_deg", "degrees")
    # (text or None: builtin TypeErrors from the comparisons; True read as 1 sigma)
    if not (is_real(cfg.gate_sigmas) and cfg.gate_sigmas > 0 and 0.0 < lo <= hi <= 180.0
            and is_real(cfg.gated_after_s) and cfg.gated_after_s >= 0):
        raise ConfigError(
            "gate_sigmas must be > 0, gate_deg (low, high) with 0 < low <= high <= 180 deg and "
            f"gated_after_s >= 0 s; got {cfg.gate_sigmas}, {cfg.gate_deg}, {cfg.gated_after_s}")


def check_trackable(array: MicArray, camera: bool = False, max_sources: int | None = None,
                    setting: str = "StreamConfig.max_sources") -> None:
    """ConfigError unless the stream can track a direction with ``array`` (and, with
    ``camera``, fuse it with a camera; with ``max_sources``, follow several talkers -- the
    error names ``setting``, e.g. the CLI's ``--sources``): a vertical line of microphones
    hears the elevation only, and the stream's direction trackers follow an azimuth (every
    frame was dropped: "no localizable source"). Masked pairs are tracked
    (:class:`SmoothedMask`) since 2026-12-05 -- until then they were refused here (the stream
    had taken them for the bare pair: a source at -153 deg came out at -29 deg) -- but not
    with a camera: the fusion solves the bare microphones' ITD equations, which the mask
    changes; nor with several talkers: a masked pair's front/back decision is one talker's,
    and its frames tell no several talkers' directions."""
    if array.mask is not None and max_sources is not None:
        raise ConfigError(f"{setting}: the masked pair {array.name!r} tracks one talker (its "
                          "front/back decision is one talker's)")
    if array.mask is not None and camera:
        raise ConfigError(
            f"array {array.name!r} has a mask: a masked pair gives a direction, not the ITD "
            "equations of its bare microphones that the camera fusion solves; track it "
            "without a camera")
    geo = array_geometry(array)
    if geo.kind == "linear" and float(np.hypot(geo.axis[0], geo.axis[1])) < 1e-6:
        raise ConfigError(
            f"array {array.name!r} is a vertical line: it hears the elevation only, and the "
            "stream tracks an azimuth; use hearsee localize (its elevation) or an array with "
            "a horizontal extent")


class TrackingProcessor:
    """TDOA -> ITD filter -> localizer -> tracker(s) for batches of frames.

    Parameters
    ----------
    array : MicArray, a preset name or an array YAML path
        (:func:`hearsee.audio.arrays.load_array`; a preset name was a builtin AttributeError)
    fs : float
        Sample rate, Hz.
    config : StreamConfig
    rig : hearsee.fusion.audiovisual.AudioVisualRig, optional
        Calibrated camera + array; with ``image_points`` the tracker also estimates the 3D
        position, velocity and acceleration.
    image_points : callable ``t -> (u, v) or None``, optional
        Image point of the source at time t (seconds), e.g. from a detector or a CSV file;
        called at each update's ``t`` minus the source's propagation delay
        (:func:`hearsee.fusion.audiovisual.frame_fix`), so ``position_m`` is where the source
        was when it emitted the frame's sound.
    first_talker_id : int
        With ``StreamConfig.max_sources``: the id of the first talker's track (the talkers'
        :class:`~hearsee.audio.sources.SourceTracker`'s ``first_id``): a processor that
        replaces another one in a running stream (a dead microphone left out) goes on from
        the old one's :attr:`next_talker_id`, so that no id names two talkers.
    """

    def __init__(self, array: MicArray | str, fs: float, config: StreamConfig | None = None,
                 rig: Any = None, image_points: Callable[[float], Any] | None = None, *,
                 first_talker_id: int = 0) -> None:
        array = load_array(array)
        self.array, self.fs = array, check_analysis_fs(fs)
        self.cfg = _stream_config(config)
        check_trackable(array, camera=rig is not None, max_sources=self.cfg.max_sources)
        first_talker_id = whole_number("first_talker_id", first_talker_id, 0, None)
        self.rig, self.image_points = rig, image_points
        self.frame_len, self.hop = frame_geometry(fs, self.cfg.frame_ms, self.cfg.hop_ms)
        self.pairs = list(array.pairs)
        # the in-plane model applies to planar arrays only
        geom = array_geometry(array)
        self._in_plane = bool(self.cfg.in_plane) and geom.kind == "planar"
        # a horizontal plane sees elevation only through cos(el): planar_elevation_sigma_scale
        self._level_plane = geom.kind == "planar" and abs(geom.normal[2]) >= np.cos(
            np.radians(10.0))
        self.itd = self._itd_filter()
        self.direction = self._direction_tracker(self.cfg, self.hop / self.fs)
        self._last_measured_t = -np.inf
        # (t, the array's pan) of the last frames told one (process's array_pan_deg), pans
        # unwrapped along them
        self._pans: deque[tuple[float, float]] = deque(maxlen=PAN_HISTORY_FRAMES)
        self.motion, self.sigma_tdoa_s = self._motion_tracker(self.cfg)
        self._motion_measured_t = -np.inf
        model, margin = None, DEFAULT_MARGIN_SAMPLES
        if array.mask is not None:  # (the mask's ITDs exceed the bare pair's delays)
            from hearsee.audio.mask import MaskModel, itd_margin_samples

            model = MaskModel(array)
            margin = itd_margin_samples(model, self.fs)
        self.gcc = FrameGcc(array, fs, self.cfg, margin_samples=margin)
        # a masked pair's front/back decision (its frames' activity history as the GCC's)
        self.mask = None if model is None else SmoothedMask(
            model, fs, self.frame_len, self.hop, self.cfg.mask_tau_s,
            self.gcc.activity.n_history)
        self.talkers, self._talker_design = None, None
        if self.cfg.max_sources is not None:
            self._talkers_init(geom, first_talker_id)
        self.srp = None
        # (a masked pair: no steered response -- its steering is the bare pair's)
        if self.cfg.spectrum_alpha > 0 and self.mask is None:
            self.srp = SmoothedSrp(array, fs, self.frame_len, self.cfg.spectrum_alpha,
                                   self.cfg.srp_band_hz,
                                   coherence_weight=self.cfg.srp_coherence_weight,
                                   in_plane=self._in_plane)
        # (what the talkers' tracker tracks at the response's azimuths: a frame's second
        # direction, cfg.talker_peak_ratio)
        self._talker_keys = None
        if self.talkers is not None and self.srp is not None and (
                self.cfg.talker_peak_ratio is not None):
            from hearsee.audio.sources import azimuth_keys

            self._talker_keys = azimuth_keys(self.srp.az_axis, None if geom.kind != "linear"
                                             else geom.axis)

    @property
    def next_talker_id(self) -> int:
        """The id the talkers' tracker gives its next new track (0 without
        ``StreamConfig.max_sources``): a processor replacing this one starts there."""
        return 0 if self.talkers is None else self.talkers.next_id

    def _talkers_init(self, geom: Any, first_id: int) -> None:
        """The several talkers' tracker (``cfg.max_sources``), its ids from ``first_id``:
        angles are azimuths, or a linear array's sines from broadside times 90 (180 deg of
        span)."""
        from hearsee.audio.sources import SourceTracker, linear_design, talker_tracker_settings

        linear = geom.kind == "linear"
        self.talkers = SourceTracker(self.cfg.max_sources, span_deg=180.0 if linear else 360.0,
                                     first_id=first_id,
                                     **talker_tracker_settings(self.cfg.talker_modes_dps2))
        if linear:
            self._talker_design = linear_design(self.array, self.pairs)
        self._talker_az: dict[int, float] = {}  # (a pair's last azimuth per track: its twin)

    def _talkers_step(self, t: float, loc: Any, profile: NDArray | None = None
                      ) -> list[dict[str, Any]]:
        """Frame ``t`` (s) with its own localization ``loc`` (None: no direction) into the
        talkers' tracker, and where the frame has a direction its steered response
        ``profile`` (:class:`SmoothedSrp`'s, over its azimuths; None: none)'s second direction
        (``cfg.talker_peak_ratio``); the talkers it reports now (:attr:`Update.sources`)."""
        from hearsee.audio.sources import frame_angle, linear_azimuth, second_direction

        linear = self._talker_design is not None
        ak = frame_angle(loc, linear)
        self.talkers.step(t, np.nan if ak is None else ak[1])
        if ak is not None and profile is not None and self._talker_keys is not None:
            k2 = second_direction(profile, self._talker_keys, ak[1],
                                  self.cfg.talker_peak_ratio)
            if k2 is not None:
                self.talkers.step(t, k2)
        out = []
        for tr in self.talkers.reported():
            if linear:
                az = linear_azimuth(tr.angle_deg, self._talker_design, self.array, self.pairs,
                                    self._talker_az.get(tr.id))
                if az is not None:
                    self._talker_az[tr.id] = az
                rate = None
            else:
                az, rate = tr.angle_deg, float(tr.kf.rate_dps[0])
            out.append({"id": tr.id, "azimuth_deg": az, "rate_dps": rate,
                        "last_heard_s": tr.last_t, "n_frames": tr.n_hits})
        live = {tr.id for tr in self.talkers.live}
        for k in [k for k in self._talker_az if k not in live]:
            del self._talker_az[k]
        return out

    def _itd_filter(self) -> ItdKalman | None:
        """A new ITD Kalman filter (thesis 2.2.2) when ``cfg.itd_filter``, else None."""
        if not self.cfg.itd_filter:
            return None
        return ItdKalman(self.array.n_mics, self.pairs, q_std_s=0.5 / self.fs,
                         r_std_s=1.0 / self.fs)

    def reset_array_state(self) -> None:
        """Forget everything held in the array's frame -- the direction and 3D trackers, the
        ITD filter, the smoothed spectra, the several talkers' tracks (``max_sources``; their
        ids go on counting) -- as after the array has turned (a pan-tilt head):
        their estimates describe where the source was relative to the old pose."""
        self.direction.reset()
        self.motion.reset()
        self.itd = self._itd_filter()
        if self.srp is not None:
            self.srp.reset()
        if self.mask is not None:
            self.mask.reset()
        self._last_measured_t = -np.inf
        self._motion_measured_t = -np.inf
        if self.talkers is not None:
            self.talkers.reset()
            self._talker_az.clear()

    def smoothed(self, batch: FrameBatch) -> dict[str, NDArray] | None:
        """The :class:`SmoothedSrp` measurements of the batch's frames (NaN rows for missing
        frames), or None when smoothing is off."""
        if self.srp is None:
            return None
        k = len(batch.t)
        out = {"tdoa_s": np.full((k, len(self.pairs)), np.nan), "coherence": np.zeros(k),
               "az_deg": np.full(k, np.nan), "el_deg": np.full(k, np.nan),
               "age_frames": np.full(k, np.nan),
               "alt_az_deg": np.full((k, 2), np.nan), "alt_coherence": np.full((k, 2), np.nan),
               "profile": np.zeros((k, self.srp.n_az))}
        # the missing frames come first in a batch: the smoothing state ages through them
        self.srp.skip(int(np.count_nonzero(batch.missing)))
        if batch.segment is not None:
            m = int(np.count_nonzero(~batch.missing))
            res = self.srp.process(batch.segment, m, self.hop)
            for key in out:
                out[key][k - m:] = res[key]
        return out

    def tdoas(self, batch: FrameBatch) -> tuple[NDArray, NDArray]:
        """Per-frame TDOAs (k, n_pairs) seconds (NaN = no estimate) and confidences (k,)."""
        k = len(batch.t)
        tdoa = np.full((k, len(self.pairs)), np.nan)
        conf = np.zeros(k)
        if batch.missing.any():  # (missing frames come first in a batch)
            self.gcc.skip()
        if batch.segment is not None:
            m = int(np.count_nonzero(~batch.missing))
            td, c = self.gcc(batch.segment, m)
            tdoa[k - m:] = td
            conf[k - m:] = np.min(c, axis=1)
        return tdoa, conf

    def process(self, batch: FrameBatch, array_pan_deg: ArrayLike | None = None
                ) -> list[Update]:
        """Run all stages on one batch of frames; one :class:`Update` per frame.

        ``array_pan_deg``: the array's pan (degrees, + = turned left about its z axis, any
        fixed reference) at each frame's time, for an array on a turning head: the direction
        tracker's azimuth is turned back by the array's turn between frames
        (:meth:`~hearsee.audio.tracking.DirectionKalman.rotate_azimuth`: ego-motion
        compensation, so that a still talker stays still and the tracker's rate is the
        talker's own), and a smoothed measurement, whose evidence is ``delay`` seconds old, by
        the turn since the time of its evidence (the last frames' pans, interpolated). Exact
        for a level array panning about its z axis; a tilted head's pan is only approximately
        an azimuth shift. The ITD filter and the smoothed spectra are not turned: at a
        following head's rates (tens of deg/s) they move on within a few frames. The 3D motion
        tracker restarts at each turn. None: the array does not turn (or its turns are handled
        with :meth:`reset_array_state`)."""
        pans = None
        if array_pan_deg is not None:
            pans = as_float_array(array_pan_deg, "array_pan_deg", (len(batch.t),),
                                  error=GeometryError)
        if batch.segment is not None:  # single precision once for both measurement stages
            batch = FrameBatch(batch.t, batch.missing, np.asarray(batch.segment, np.float32),
                               batch.arrival)
        tdoa, conf = self.tdoas(batch)
        sm = self.smoothed(batch)
        mk = self.mask_decisions(batch)
        out = []
        for n, t in enumerate(batch.t):
            z = raw_z = tdoa[n]
            have = bool(np.all(np.isfinite(z)))
            # whether the frame's TDOAs measure: with itd_filter only when its gate took them
            # (a rejected frame, an anomalous GCC peak, fed the filter's prediction to the
            # trackers as a fresh measurement: measured=True, the variance shrank, and the
            # max_coast_s timer restarted)
            use = have
            if self.itd is not None:
                use = self.itd.step(z if have else None)
                if use:
                    z = self.itd.pair_tdoas()
            raw_az = raw_el = itd_az = itd_el = raw_loc = None
            cands: list[tuple[float, float | None]] = []
            if have:  # raw_*: the frame's own TDOAs, not the filter's, taken or not
                raw_az, raw_el, raw_cands, raw_loc = self._locate(raw_z, mk[n])
            if use:
                # the tracker's measurement: the (ITD-filtered) TDOAs' direction
                if z is raw_z:
                    cands = raw_cands
                else:
                    itd_az, itd_el, cands, _ = self._locate(z, mk[n])
            delay = 0.0
            own = bool(cands) and (self.cfg.prefer_frame
                                   or conf[n] >= self.cfg.prefer_frame_confidence)
            sigma = self._frame_sigma(float(conf[n])) if cands else None
            if sm is not None and not own:
                cands = self._smoothed_candidates(sm, n)
                c_sm = float(sm["coherence"][n])
                age_s = float(sm["age_frames"][n]) * self.hop / self.fs
                # (not on a missing frame: no evidence, its age NaN -- the prediction to a NaN
                # time was an EstimationError that ended the run at a dropped block)
                if not cands and self.cfg.gated_min_coherence is not None and (
                        not batch.missing[n]) and (
                        float(t) - self._last_measured_t >= self.cfg.gated_after_s):
                    cands, c_sm = self._gated_candidate(sm["profile"][n], float(t) - age_s)
                delay = age_s if cands else 0.0
                sigma = self._srp_sigma(c_sm) if cands else None
            elif self.mask is not None and not cands and MASK_SMOOTHED_MEASUREMENT:
                cands, sigma, delay = self._mask_candidates(mk[n], n)
            if delay > MAX_DELAY_S:  # (evidence older than a tracker takes: no measurement --
                # with long hops its age in frames passed, and the tracker's EstimationError
                # for the delay ended the run)
                cands, sigma, delay = [], None, 0.0
            if pans is not None:
                cands = self._follow_pan(float(t), float(pans[n]), cands, delay)
            if sigma is not None and self._level_plane:
                sigma = (sigma, sigma * self.cfg.planar_elevation_sigma_scale)
            if cands and self._wrong_half(mk[n]):
                self.direction.reset()  # (restarted at the decided half's candidate below)
            measured = self.direction.update(float(t), cands[0] if cands else None, cands[1:],
                                             sigma_meas_deg=sigma, delay_s=delay)
            if measured:
                self._last_measured_t = float(t)
            elif (self.cfg.max_coast_s is not None and self.direction.initialized
                  and float(t) - self._last_measured_t > self.cfg.max_coast_s):
                self.direction.reset()  # lost: no direction until a measurement restarts it
            upd = Update(float(t), None, None, None, None, None, None,
                         float(conf[n]) if have else 0.0, measured=measured,
                         missing=bool(batch.missing[n]), raw_azimuth_deg=raw_az,
                         raw_elevation_deg=raw_el, itd_azimuth_deg=itd_az,
                         itd_elevation_deg=itd_el,
                         front_probability=None if mk[n] is None
                         else mk[n].front_probability, masked=self.mask is not None)
            if self.direction.initialized:
                upd.azimuth_deg = self.direction.azimuth_deg
                el = self.direction.elevation_deg
                upd.elevation_deg = el if np.isfinite(el) else None
                upd.rate_dps = self.direction.rate_dps.tolist()
                upd.covariance = self.direction.P[:2, :2].tolist()
            if self.rig is not None and self.image_points is not None:
                self._fuse(upd, z if use else None)
            if self.talkers is not None:
                upd.sources = self._talkers_step(
                    float(t), raw_loc, None if sm is None else sm["profile"][n])
            out.append(upd)
        return out

    def mask_decisions(self, batch: FrameBatch) -> list[Any]:
        """A masked pair's :class:`SmoothedMask` decision for each of the batch's frames (None
        for missing frames, before enough evidence, and on every frame of a bare array)."""
        k = len(batch.t)
        out: list[Any] = [None] * k
        self._mask_active = np.zeros(k, bool)
        self._mask_age = np.zeros(k)
        if self.mask is None:
            return out
        n_missing = int(np.count_nonzero(batch.missing))  # (missing frames come first)
        self.mask.skip(n_missing)
        if batch.segment is not None:
            out[n_missing:] = self.mask.process(batch.segment, k - n_missing, self.hop)
            self._mask_active[n_missing:] = self.mask.active
            self._mask_age[n_missing:] = self.mask.age_frames
        return out

    def _locate(self, z: NDArray, decision: Any
                ) -> tuple[float | None, float | None, list[tuple[float, float | None]], Any]:
        """A frame's direction from its TDOAs ``z`` (s): ``(azimuth_deg, elevation_deg,
        candidates, localization)`` for the tracker (the first the primary; the
        localization, a bare array's, None for a masked pair's). Bare arrays:
        :func:`~hearsee.audio.localize.localize_tdoa`. A masked pair: the ITD's azimuth in
        each half (:func:`hearsee.audio.mask.itd_candidates`; where it matches twice in a
        half, the match nearest the decision's azimuth or runner-up there, else the track's),
        the half of the :class:`SmoothedMask` ``decision`` first -- alone when its confidence
        reaches ``mask_decide_confidence`` -- and no elevation (two microphones)."""
        if self.mask is None:
            loc = localize_tdoa(z, self.array, self.pairs, near_field=self._in_plane,
                                in_plane=self._in_plane)
            return (loc.azimuth_deg, loc.elevation_deg,
                    [(a, e) for a, e in loc.candidates if a is not None], loc)
        from hearsee.audio.mask import itd_candidates

        p_front = 0.5 if decision is None else decision.front_probability
        if decision is not None:
            best, other = wrap_deg(decision.azimuth_deg), wrap_deg(decision.runner_up_deg)
            prior_f, prior_b = (best, other) if p_front >= 0.5 else (other, best)
        elif self.direction.initialized:  # the track's azimuth and its mirror
            a = float(self.direction.azimuth_deg)
            prior_f, prior_b = (a, wrap_deg(180.0 - a)) if abs(a) < 90 else (
                wrap_deg(180.0 - a), a)
        else:
            prior_f, prior_b = 0.0, 180.0
        a_f, a_b = itd_candidates(self.mask.model, float(z[0]), self.fs, prior_f, prior_b)
        first, second = (a_f, a_b) if p_front >= 0.5 else (a_b, a_f)
        cands: list[tuple[float, float | None]] = [(first, None)]
        if not self._decided(decision):
            cands.append((second, None))
        return first, None, cands, None

    def _wrong_half(self, decision: Any) -> bool:
        """Whether a masked pair's track lies in the half that a confident front/back
        ``decision`` (:class:`SmoothedMask`, confidence >= ``mask_decide_confidence``) rules
        out, more than :data:`MASK_SIDE_DEG` from the side axis (nearer it the halves meet and
        the track's own continuity decides): the track is then restarted at once, not after
        ``reacquire_s`` of rejected measurements (a stream started before the first decision
        took the front candidate: 0.5 s at the mirror)."""
        if not (self._decided(decision) and self.direction.initialized):
            return False
        az = abs(float(self.direction.azimuth_deg))
        return ((az > 90.0 + MASK_SIDE_DEG) if decision.front_probability >= 0.5
                else (az < 90.0 - MASK_SIDE_DEG))

    def _decided(self, decision: Any) -> bool:
        """Whether a :class:`SmoothedMask` decision (or None) is confident enough to rule out
        the other half: its confidence (the chosen half's probability) reaches
        ``mask_decide_confidence``."""
        return decision is not None and decision.confidence >= self.cfg.mask_decide_confidence

    def _frame_sigma(self, confidence: float) -> float:
        """Measurement noise (deg) of a frame's own GCC direction: ``sigma_frame_deg /
        confidence`` (floored at ``sigma_min_deg``), or the fixed ``sigma_meas_deg``."""
        c = self.cfg
        if c.sigma_frame_deg is None or not confidence > 0:
            return c.sigma_meas_deg
        return max(c.sigma_min_deg, c.sigma_frame_deg / confidence)

    def _follow_pan(self, t: float, pan: float, cands: list[tuple[float, float | None]],
                    delay: float) -> list[tuple[float, float | None]]:
        """The array turned to ``pan`` (degrees) at frame time ``t``: the direction tracker
        turned back by the turn since the previous frame, and ``cands`` -- measured on
        evidence ``delay`` seconds old -- by the turn since then (the pan at ``t - delay``
        interpolated between the last :data:`PAN_HISTORY_FRAMES` frames' pans; see
        :meth:`process`). The 3D motion tracker (a camera rig's) restarts instead: a head
        turns its array about the pivot, a point the stream does not know."""
        if self._pans:
            pan0 = self._pans[-1][1]
            turn = float(wrap_deg(pan - pan0))
            pan = pan0 + turn  # (unwrapped along the history)
            if turn:
                self.direction.rotate_azimuth(-turn)
                self.motion.reset()
                # (a pair's tracks are in its angles' sines, which a turn does not shift alike
                # for a talker and its front/back mirror: they follow the turn as motion --
                # forgetting them at each turn left a panning pair no talker at all)
                if self.talkers is not None and self._talker_design is None:
                    self.talkers.rotate(-turn)
        self._pans.append((t, pan))
        if not (cands and delay > 0 and len(self._pans) > 1):
            return cands
        ts, pans = zip(*self._pans, strict=True)
        back = pan - float(np.interp(t - delay, ts, pans))  # (the turn since the evidence)
        if not back:
            return cands
        return [(float(wrap_deg(az - back)), el) for az, el in cands]

    def _mask_candidates(self, decision: Any, n: int
                         ) -> tuple[list[tuple[float, float | None]], float | None, float]:
        """A masked pair's measurement where frame ``n`` has none of its own (no GCC peak
        passed ``min_confidence``): the :class:`SmoothedMask` ``decision``'s azimuth, from the
        spectra averaged over the last ~``mask_tau_s`` -- the masked pair's counterpart of the
        smoothed steered response (:meth:`_smoothed_candidates`) -- while the frame is active,
        the evidence's energy-weighted age is at most ``max_evidence_age_frames`` and the
        averages' phase match ``rho`` reaches ``mask_min_phase_match``; its mirror in the other half
        as an alternative unless the decision is confident (``mask_decide_confidence``).
        Returns ``(candidates, sigma_deg, delay_s)``: ``sigma`` as :meth:`_srp_sigma` of
        ``rho``, the delay that age."""
        age = float(self._mask_age[n])
        if decision is None or not self._mask_active[n] or not (
                decision.phase_match >= self.cfg.mask_min_phase_match
                and age <= self.cfg.max_evidence_age_frames):
            return [], None, 0.0
        cands: list[tuple[float, float | None]] = [(wrap_deg(decision.azimuth_deg), None)]
        if not self._decided(decision):
            cands.append((wrap_deg(decision.runner_up_deg), None))
        return cands, self._srp_sigma(decision.phase_match), age * self.hop / self.fs

    def _srp_sigma(self, coherence: float) -> float:
        """Measurement noise (deg) of a smoothed steered-response direction: ``sigma_srp_deg
        (1 - coherence) / coherence`` (floored at ``sigma_min_deg``), or ``sigma_meas_deg``."""
        c = self.cfg
        if c.sigma_srp_deg is None or not coherence > 0:
            return c.sigma_meas_deg
        return max(c.sigma_min_deg, c.sigma_srp_deg * (1.0 - coherence) / coherence)

    def _smoothed_candidates(self, sm: dict[str, NDArray], n: int
                             ) -> list[tuple[float, float | None]]:
        coh = float(sm["coherence"][n])
        zs = sm["tdoa_s"][n]
        if not (coh >= self.cfg.min_coherence and np.all(np.isfinite(zs))
                and sm["age_frames"][n] <= self.cfg.max_evidence_age_frames):
            return []
        alt = sm["alt_coherence"][n]
        if self.cfg.max_alt_ratio < 1.0 and np.any(np.isfinite(alt)) \
                and np.nanmax(alt) >= self.cfg.max_alt_ratio * coh:
            return []
        # the steered response's own (interpolated) azimuth; elevation on the coarse grid
        el = float(sm["el_deg"][n])
        cands: list[tuple[float, float | None]] = [
            (float(sm["az_deg"][n]), el if np.isfinite(el) else None)]
        for az, c in zip(sm["alt_az_deg"][n], sm["alt_coherence"][n], strict=True):
            if np.isfinite(az) and c >= self.cfg.alt_ratio * coh:
                # an exact twin (front/back of a linear array: the same steered power) goes
                # first when it is the frontal one, as localize_tdoa orders its candidates
                if c >= coh * (1.0 - 1e-4) and abs(az) < abs(cands[0][0]):
                    # (refined as the best one is: the grid's azimuth, up to half a grid step
                    # off, was the pair's measurement -- a talker at -3 deg tracked at -2.0)
                    i = int(np.argmin(np.abs(wrap_deg(self.srp.az_axis - az))))
                    cands.insert(0, (float(self.srp.peak_azimuth(sm["profile"][n][None],
                                                                  np.array([i]))[0]), None))
                else:
                    cands.append((float(az), None))
        return cands

    def _gated_candidate(self, prof: NDArray, t_evidence: float
                         ) -> tuple[list[tuple[float, float | None]], float]:
        """The largest local maximum of the steered response's azimuth profile ``prof``
        (n_az,) within the running track's gate, predicted to ``t_evidence`` (s: the frame
        time less the smoothed evidence's age), when it reaches ``gated_min_coherence``:
        ``([(azimuth, None)], its normalised steered power)``, or ``([], 0.0)``."""
        d = self.direction
        if not d.initialized:
            return [], 0.0
        x, P = d.predicted(t_evidence)  # the tracker's own model: relaxing rate, process noise
        az_pred, var = float(x[0]), float(P[0, 0])
        lo, hi = self.cfg.gate_deg
        half = float(np.clip(self.cfg.gate_sigmas * np.sqrt(max(var, 0.0)), lo, hi))
        axis = self.srp.az_axis
        near = np.abs(wrap_deg(axis - az_pred)) <= half
        if not near.any():
            return [], 0.0
        vals = np.where(near, prof, -np.inf)
        i = int(np.argmax(vals))
        na = axis.size
        # a local maximum of the whole profile, not the gate's edge on a slope
        if not (prof[i] >= prof[(i - 1) % na] and prof[i] >= prof[(i + 1) % na]):
            return [], 0.0
        c = float(prof[i])
        if c < self.cfg.gated_min_coherence:
            return [], 0.0
        return [(float(self.srp.peak_azimuth(prof[None], np.array([i]))[0]), None)], c

    @staticmethod
    def _direction_tracker(cfg: StreamConfig, hop_s: float) -> DirectionKalman | DirectionIMM:
        """The direction tracker: an IMM over ``cfg.direction_modes_dps2``, or with None one
        constant-velocity filter with ``cfg.sigma_accel_dps2``; either restarts after
        ``cfg.reacquire_s`` of consecutive gate rejections (frames of ``hop_s`` seconds)."""
        max_rejects = max(1, int(np.ceil(cfg.reacquire_s / hop_s - 1e-9)))
        try:
            if cfg.direction_modes_dps2 is None:
                return DirectionKalman(cfg.sigma_meas_deg, cfg.sigma_accel_dps2,
                                       max_rejects=max_rejects,
                                       elevation_accel_ratio=cfg.elevation_accel_ratio,
                                       rate_tau_s=cfg.direction_rate_tau_s)
            return DirectionIMM(cfg.sigma_meas_deg, tuple(cfg.direction_modes_dps2),
                                mode_dwell_s=cfg.mode_dwell_s, max_rejects=max_rejects,
                                elevation_accel_ratio=cfg.elevation_accel_ratio,
                                rate_tau_s=cfg.direction_rate_tau_s,
                                angle_noise_ratio=cfg.direction_angle_noise_ratio)
        except EstimationError as exc:
            raise ConfigError("direction tracker (direction_modes_dps2 / mode_dwell_s / "
                              f"elevation_accel_ratio / direction_rate_tau_s): {exc}") from None

    def _motion_tracker(self, cfg: StreamConfig) -> tuple[Any, float]:
        """The 3D tracker of ``cfg.motion_model`` / ``cfg.ray_measurements`` and the TDOA noise
        (seconds) of its camera-ray fixes."""
        if cfg.ray_measurements not in ("tdoa", "fix"):
            raise ConfigError("ray_measurements must be 'tdoa' or 'fix', got "
                              f"{cfg.ray_measurements!r}")
        if cfg.motion_model == "cv":
            from hearsee.fusion.audiovisual import RAY_SIGMA_TDOA_S, RayTdoaTracker, RayTracker

            tdoa = RAY_SIGMA_TDOA_S if cfg.sigma_tdoa_s is None else float(cfg.sigma_tdoa_s)
            acc = {} if cfg.sigma_accel is None else {"sigma_accel": float(cfg.sigma_accel)}
            try:
                if cfg.ray_measurements == "tdoa" and self.rig is not None:
                    return RayTdoaTracker(self.rig, self.pairs, sigma_tdoa_s=tdoa,
                                          sigma_px=cfg.sigma_px, **acc), tdoa
                return RayTracker(**acc), tdoa  # (without a camera: never fed)
            except EstimationError as exc:
                raise ConfigError(f"3D tracker (sigma_accel / sigma_tdoa_s / sigma_px): {exc}"
                                  ) from None
        if cfg.motion_model == "ca":
            from hearsee.fusion.audiovisual import FIX_SIGMA_TDOA_S

            tdoa = FIX_SIGMA_TDOA_S if cfg.sigma_tdoa_s is None else float(cfg.sigma_tdoa_s)
            return MotionKalman(sigma_meas_m=0.05, sigma_jerk=cfg.sigma_jerk,
                                accel_tau_s=cfg.accel_tau_s), tdoa
        raise ConfigError(f"motion_model must be 'cv' or 'ca', got {cfg.motion_model!r}")

    def _fuse(self, upd: Update, z: NDArray | None) -> None:
        from hearsee.fusion.audiovisual import feed_tracker, frame_fix

        uv, fix = frame_fix(self.rig, self.image_points, upd.t, z, self.pairs, self.motion,
                            range_m=self.cfg.range_m, sigma_tdoa_s=self.sigma_tdoa_s,
                            sigma_px=self.cfg.sigma_px,
                            max_residual_s=self.cfg.max_fix_residual_samples / self.fs)
        if fix is not None:
            upd.raw_position_m = fix.position_m.tolist()
        fused = feed_tracker(self.motion, upd.t, uv, z, fix)
        if fused or getattr(self.motion, "last_fused_t", None) == upd.t:
            self._motion_measured_t = upd.t
        elif (self.cfg.max_coast_s is not None and self.motion.initialized
              and upd.t - self._motion_measured_t > self.cfg.max_coast_s):
            # lost, as the direction track after max_coast_s: without image points (or any
            # fused measurement) the 3D state was a constant-velocity extrapolation for the
            # rest of the run (2 m from a talker who had stopped, 4 s after the camera lost
            # them, outside its own covariance)
            self.motion.reset()
        if self.motion.initialized:
            upd.position_m = self.motion.position.tolist()
            # (None until the fixes determine it: a new track's velocity is its 0 m/s prior)
            upd.velocity_mps = (self.motion.velocity.tolist() if self.motion.velocity_known
                                else None)
            # (None for the constant-velocity default, whose 0 is a model assumption, not an
            # estimate -- it read as "not accelerating" for a walker who turned -- and, like
            # the velocity, before the track's measurements determine it)
            upd.acceleration_mps2 = (self.motion.acceleration.tolist()
                                     if self.motion.estimates_acceleration
                                     and self.motion.velocity_known else None)
            upd.covariance = self.motion.position_cov.tolist()


# ---------------------------------------------------------------------------- pipeline
_END = object()


class StreamPipeline:
    """source -> framer -> processor -> sink, in-line or threaded behind a bounded queue.

    Parameters
    ----------
    array : MicArray or preset/YAML name
    config : StreamConfig
    rig, image_points :
        Optional camera fusion (see :class:`TrackingProcessor`).
    queue_size : int
        Bound of the block queue between the source thread and the processing (threaded mode).
    stall_timeout_s : float
        How long the consumer waits for one block before counting a stall.
    max_stall_s : float
        Total silence after which the run ends with ``status="stalled"`` (inf: never). A source
        that ends because its device went silent (its ``stalled`` attribute set, as
        :class:`DeviceSource` does after ``timeout_s``) gives the same status; its input
        overflows (``n_overflows``) go to :attr:`StreamStats.n_overflows`. Both are also read
        from a source that a wrapper exposes as ``.source`` (:class:`DropoutSource`,
        :class:`MappedSource`).
    check_wiring : bool or None
        Check the input's first :data:`WIRING_CHECK_S` seconds in which a source is heard for a
        microphone wired with inverted polarity, with a warning (:class:`_WiringWatch`): what
        a file's whole-recording estimate tells before it is used, told of live input as soon
        as it can be. None (default): live input only -- a source whose chain holds no
        recording (``.x``), as :class:`DeviceSource`; a recording can be checked ahead
        (``hearsee track`` does), and the check's one whole-recording estimate (~25 ms for 10 s
        of three-mic audio at 16 kHz) would add 5-10 % to a 20-s file's stream.
    tonal_lines_hz : sequence of float
        Lines of stationary tonal noise (Hz; mains hum that the wiring picks up, e.g. a file's
        ``TdoaFrames.tonal_lines_hz``, as ``hearsee track`` finds them ahead) to notch out of
        every block before it is framed (:class:`~hearsee.audio.hum.LineFilter`: causal, the
        same on every channel). Empty (default): none -- unless the live input's check finds
        some (``check_wiring``). A 60-Hz buzz 3 dB above a voice made the stream's directions
        follow the buzz.
    """

    def __init__(self, array: MicArray | str, config: StreamConfig | None = None, rig: Any = None,
                 image_points: Callable[[float], Any] | None = None, queue_size: int = 8,
                 stall_timeout_s: float = 0.5, max_stall_s: float = 5.0,
                 check_wiring: bool | None = None, tonal_lines_hz: Sequence[float] = ()) -> None:
        self.array = load_array(array)
        check_trackable(self.array, camera=rig is not None)  # (before any audio)
        self.config = _stream_config(config)
        self.rig, self.image_points = rig, image_points
        # (unchecked, a negative stall_timeout_s was a ValueError of queue.get in the threaded
        # run, a NaN max_stall_s never ended the run on a silent source, a queue_size <= 0 made
        # the bounded queue unbounded)
        self.queue_size = whole_number("queue_size", queue_size)
        self.stall_timeout_s = finite_number("stall_timeout_s", stall_timeout_s, 0.0,
                                             lo_open=True)
        if not (max_stall_s == math.inf or (is_real(max_stall_s) and max_stall_s > 0)):
            raise ConfigError(f"max_stall_s must be a number of seconds > 0 (inf = wait for ever)"
                              f", got {max_stall_s!r}")
        self.max_stall_s = float(max_stall_s)
        self.check_wiring = (None if check_wiring is None
                             else true_or_false("check_wiring", check_wiring))
        self.tonal_lines_hz = check_lines(tonal_lines_hz)
        self.stats = StreamStats()
        self._reset_requested = False

    def reset_array_state(self) -> None:
        """Ask the running stream to forget its array-frame state
        (:meth:`TrackingProcessor.reset_array_state`) before its next batch of frames: call it
        from the sink when the array has moved, e.g. after a head turn. The frames of the
        batch being delivered were measured before the call and keep the old state."""
        self._reset_requested = True

    def _check_source(self, source: Any, sink: Any = None) -> None:
        # (a list of samples or a number: builtin AttributeErrors / TypeErrors at the first
        # block or update)
        if not all(hasattr(source, a) for a in ("n_channels", "fs", "blocks")):
            raise ConfigError(f"source must be a block source (FileSource, ArraySource, "
                              f"DeviceSource, ...), got {type(source).__name__}")
        if sink is not None and not callable(sink):
            raise ConfigError(f"sink must be a function of an Update or None, got "
                              f"{type(sink).__name__}")
        if source.n_channels != self.array.n_mics:
            raise AudioInputError(
                f"the input has {source.n_channels} channels; array {self.array.name!r} has "
                f"{self.array.n_mics} microphones (channel k must be microphone k)"
            )
        frame_len, _ = frame_geometry(source.fs, self.config.frame_ms, self.config.hop_ms)
        x = getattr(source, "x", None)  # a recording (a live device has no length)
        if x is not None:
            check_recording_length(x.shape[1], frame_len)
        shortest = min_frame_ms(self.array)
        if frame_len / source.fs * 1e3 < shortest:
            raise ConfigError(
                f"frame of {self.config.frame_ms:g} ms is too short for the array's largest "
                f"delay ({shortest / 4:.2f} ms); use a frame of at least {shortest:.2f} ms"
                f"{self.array.units_hint()}")

    def run(self, source: Any, sink: Callable[[Update], None] | None = None,
            threaded: bool = False,
            array_pan: Callable[[NDArray], ArrayLike] | None = None) -> list[Update]:
        """Process the whole source; call ``sink(update)`` per frame and return all updates.

        ``array_pan``: for an array on a turning head, called before each batch of frames with
        their times (seconds of audio) and returning the array's pan at each (degrees, + =
        left; :meth:`TrackingProcessor.process`'s ``array_pan_deg``: the direction tracker
        follows the turns instead of taking them for the talker's motion).

        BLAS runs single-threaded meanwhile: the stages' matrices are small (a few frames), and
        a multithreaded BLAS on a busy machine made each product 10-100x slower (thread
        hand-off), never faster.
        """
        from threadpoolctl import threadpool_limits

        if array_pan is not None and not callable(array_pan):
            raise ConfigError(f"array_pan must be a function of the frames' times or None, got "
                              f"{type(array_pan).__name__}")
        with threadpool_limits(1, user_api="blas"):
            return self._run(source, sink, threaded, array_pan)

    def _run(self, source: Any, sink: Callable[[Update], None] | None,
             threaded: bool, array_pan: Callable[[NDArray], ArrayLike] | None = None
             ) -> list[Update]:
        self._check_source(source, sink)
        self._reset_requested = False
        framer = Framer(source.n_channels, source.fs, self.config.frame_ms, self.config.hop_ms)
        proc = TrackingProcessor(self.array, source.fs, self.config, self.rig, self.image_points)
        self.stats = st = StreamStats()
        live = all(getattr(s, "x", None) is None for s in _source_chain(source))
        check = live if self.check_wiring is None else self.check_wiring
        watch = _WiringWatch(self.array, source.fs, self.config) if check else None
        hum = (LineFilter(self.tonal_lines_hz, source.fs, source.n_channels)
               if self.tonal_lines_hz else None)
        hum_watch = (_HumWatch(source.fs, self.config.frame_ms) if check and hum is None
                     else None)
        if watch is not None and hum is not None:
            watch.tonal_noise = False  # (the hum was given: notched from the start)
        st.tonal_lines_hz = self.tonal_lines_hz
        updates: list[Update] = []
        last_sample = 0
        t_start = time.perf_counter()
        c_start = time.process_time()

        def notch(lines: tuple[float, ...]) -> None:
            """Hum found by a watch: notched out of every block from now on, and the track
            built on the hum's directions forgotten (it sat near the pole, where the hum puts
            a source, and took ~2 s of right measurements, most outside its gate, to leave)."""
            nonlocal hum
            hum = LineFilter(lines, source.fs, source.n_channels if keep is None else len(keep))
            st.tonal_lines_hz = lines
            self._reset_requested = True
            if watch is not None:
                watch.tonal_noise = False  # (its estimate need not look for hum again)

        keep: list[int] | None = None  # (the microphones used, once a dead one is left out)

        def leave_out(dead: tuple[int, ...]) -> None:
            """Dead microphones found by the watch: the others localize from the next block
            on, as an array of their own (the framer keeps its place and their samples; a new
            processor: the track starts afresh, the talkers' ids go on counting), the hum
            filter on their channels."""
            from hearsee.audio.localize import without_microphones

            nonlocal keep, proc, hum
            keep, sub = without_microphones(self.array, dead, stacklevel=2)
            framer.keep_channels(keep)
            # (the camera's rig with the same microphones: its fixes read the TDOAs of the
            # new processor's pairs, numbered in ``keep`` -- the whole array's put microphone
            # 0 dead gave no 3D fix or one 1-2 m off)
            rig = None if self.rig is None else replace(self.rig, array=sub)
            proc = TrackingProcessor(sub, source.fs, self.config, rig, self.image_points,
                                     first_talker_id=proc.next_talker_id)
            if hum is not None:
                hum = LineFilter(st.tonal_lines_hz, source.fs, len(keep))
            st.dead_microphones = dead

        def handle(blk: Block) -> None:
            nonlocal last_sample
            st.n_blocks += 1
            last_sample = max(last_sample, blk.start + blk.data.shape[1])
            st.audio_s = last_sample / source.fs  # (the audio clock's now, for the sink)
            if keep is not None:
                blk = replace(blk, data=blk.data[keep])
            if hum is not None:
                blk = replace(blk, data=hum(blk.data))
            emit(framer.push(blk))
            if hum_watch is not None and not hum_watch.done:
                hum_watch.add(blk.data)
                if hum_watch.tonal_lines_hz:
                    notch(hum_watch.tonal_lines_hz)
            if watch is not None and not watch.done:  # (done once it told a fault)
                watch.add(blk.data)  # (without the hum once it is notched out)
                if hum is None and watch.tonal_lines_hz:
                    notch(watch.tonal_lines_hz)
                if watch.dead_mics and keep is None:
                    leave_out(watch.dead_mics)

        def emit(batch: FrameBatch | None) -> None:
            if batch is None:
                return
            if self._reset_requested:
                proc.reset_array_state()
                self._reset_requested = False
            pans = None if array_pan is None else array_pan(np.asarray(batch.t, float))
            for u in proc.process(batch, pans):
                u.latency_s = time.perf_counter() - batch.arrival
                st.latencies_s.append(u.latency_s)
                st.n_frames += 1
                st.n_missing_frames += int(u.missing)
                updates.append(u)
                if sink is not None:
                    sink(u)

        def finish() -> None:
            """The source ended: the frames of its lost last blocks, reported missing
            (not when its device went silent: the stream's end is not known then)."""
            if not any(bool(getattr(s, "stalled", False)) for s in _source_chain(source)):
                emit(framer.finish(getattr(source, "end_sample", None)))
            if watch is not None:
                watch.finish()

        try:
            if not threaded:
                blocks = source.blocks()
                try:
                    for blk in blocks:
                        handle(blk)
                except BaseException:
                    close_blocks(blocks, quiet=True)  # (this error stays the error)
                    raise
                finish()
            else:
                q: queue.Queue = queue.Queue(maxsize=self.queue_size)
                stop = threading.Event()
                errors: list[BaseException] = []

                def produce() -> None:
                    try:
                        blocks = source.blocks()
                        for blk in blocks:
                            while not stop.is_set():
                                try:
                                    q.put(blk, timeout=0.1)
                                    break
                                except queue.Full:
                                    continue
                            if stop.is_set():  # the consumer ended the run (Ctrl-C, a stall,
                                # an error): that is the reason, not the source's while closing
                                close_blocks(blocks, quiet=True)
                                return
                    except BaseException as exc:  # noqa: BLE001 - re-raised in the consumer
                        errors.append(exc)
                    finally:
                        while True:
                            try:
                                q.put(_END, timeout=0.1)
                                break
                            except queue.Full:
                                if stop.is_set():
                                    break

                th = threading.Thread(target=produce, name="hearsee-source", daemon=True)
                th.start()
                silent = 0.0
                try:
                    while True:
                        try:
                            item = q.get(timeout=self.stall_timeout_s)
                        except queue.Empty:
                            st.n_stalls += 1
                            silent += self.stall_timeout_s
                            if silent >= self.max_stall_s:
                                st.status = "stalled"
                                break
                            continue
                        silent = 0.0
                        if item is _END:
                            break
                        handle(item)
                finally:
                    stop.set()
                    th.join(timeout=1.0)
                if errors:
                    raise errors[0]
                if st.status == "ok":
                    finish()
        except KeyboardInterrupt:  # Ctrl-C: the stats still describe what was processed
            st.status = "interrupted"
            raise
        finally:
            st.wall_s = time.perf_counter() - t_start
            st.cpu_s = time.process_time() - c_start
            st.audio_s = last_sample / source.fs
            st.n_late_blocks = framer.n_late
            # a block a device drops shows up twice: in the device's own count and as a gap in the
            # sequence numbers the framer sees -- the same block, counted once (the device's count
            # also holds drops after the last delivered block, which leave no gap)
            st.n_dropped_blocks = max(framer.n_dropped, int(getattr(source, "n_dropped", 0)))
            chain = _source_chain(source)
            st.n_overflows = max(int(getattr(s, "n_overflows", 0) or 0) for s in chain)
            if st.status == "ok" and any(bool(getattr(s, "stalled", False)) for s in chain):
                st.status = "stalled"  # the source ended because its device went silent
        return updates


def close_blocks(blocks: Any, *, quiet: bool = False) -> None:
    """End a source's ``blocks()`` iterator now (a generator's ``close()``: the source releases
    its device there, :class:`DeviceSource` stops its stream) rather than whenever it is garbage
    collected, where an error was only printed as "Exception ignored in". The source's error
    while closing (AudioInputError) is raised -- or, with ``quiet=True``, dropped: for a run
    that ends with another error, Ctrl-C or its consumer's stop, which stays the reason."""
    close = getattr(blocks, "close", None)
    if close is None:
        return
    if not quiet:
        close()
        return
    with contextlib.suppress(Exception):
        close()


def _source_chain(source: Any) -> list[Any]:
    """``source`` and the sources it wraps (each wrapper's ``.source``, a few levels)."""
    chain = [source]
    while len(chain) < 8:
        inner = getattr(chain[-1], "source", None)
        if inner is None or any(inner is c for c in chain):
            break
        chain.append(inner)
    return chain
