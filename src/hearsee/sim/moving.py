"""Moving sound sources: trajectories, free-field and room propagation with time-varying delays.

pyroomacoustics has no moving sources, so hearsee has its own simulator, written once:

* **Free field** (:func:`simulate_moving_free_field`): every microphone receives the source
  signal at its *retarded* emission time ``t_e`` with ``t = t_e + |p(t_e) - m| / c`` (solved by
  fixed-point iteration, which converges because the source is much slower than sound), scaled
  by ``1 / |p(t_e) - m|``. The per-sample fractional delay is applied with a Kaiser-windowed sinc
  interpolator (32 taps each side), vectorised over chunks of output samples -- there is no
  Python loop per sample. A constant radial velocity then shows the exact Doppler factor
  ``c / (c + v_r)``.
* **Rooms** (:func:`simulate_moving_room`): the image-source impulse responses are computed at the
  trajectory's positions at most every ``block_s`` seconds, and closer wherever a microphone
  pair's TDOA would otherwise move by more than ``max_tdoa_step_samples`` between updates
  (:func:`hearsee.audio.propagation.room_impulse_responses`, i.e. pyroomacoustics' ISM). The source
  signal is split by triangular (linear-interpolation) weights centred on the block times, which
  sum to one everywhere; each weighted piece is convolved with its block's responses and the
  results are overlap-added. This is the usual crossfaded block-wise time-varying convolution
  (block-wise time-varying convolution with crossfades, as in Vorlaender, *Auralization*,
  Springer 2008, ch. on moving sources): for a static source it reduces exactly to one
  convolution.

Frames: trajectories are in the array frame (metres, x forward, y left, z up). Rooms follow
:func:`hearsee.audio.propagation.simulate_room`: the array origin sits at ``array_at`` in room
coordinates, axes parallel to the room's.

Trajectory files are CSV with a header ``t,x,y,z`` (seconds, metres).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable
from dataclasses import dataclass
from decimal import Decimal, localcontext
from pathlib import Path
from typing import Any

import numpy as np
import scipy.fft as sfft
import scipy.signal as ss
from numpy.typing import ArrayLike, NDArray

from hearsee.audio.arrays import MicArray
from hearsee.audio.propagation import add_noise, check_heard, check_snr_db, speed_of_sound_of
from hearsee.audio.signals import as_samples, check_fs
from hearsee.config import (
    MAX_TIME_LIMIT_S,
    as_float_array,
    check_rng,
    finite_number,
    input_file,
    is_real,
    output_file,
    real_entries,
    true_or_false,
    whole_number,
    write_file,
)
from hearsee.errors import AudioInputError, ConfigError, GeometryError, InputFileError
from hearsee.geometry import as_point, vector_length

__all__ = [
    "MAX_SPEED_FRACTION",
    "Trajectory",
    "fractional_delay",
    "linear_trajectory",
    "load_trajectory",
    "mask_itd_track",
    "retarded_delays",
    "save_trajectory",
    "simulate_moving_free_field",
    "simulate_moving_masked",
    "simulate_moving_recording",
    "simulate_moving_room",
    "waypoint_trajectory",
]

#: Half-width (taps each side) of the windowed-sinc fractional-delay interpolator.
SINC_HALF_WIDTH = 32
#: Kaiser window shape parameter of the interpolator (about -80 dB side lobes).
SINC_KAISER_BETA = 8.6
#: The widest interpolator :func:`fractional_delay` accepts (taps on each side); 32 is already
#: near -80 dB, and the tap matrix grows as ``chunk * 2 * half_width``.
MAX_SINC_HALF_WIDTH = 1024
#: Image-source order up to which :func:`simulate_moving_room` renders a moving source's
#: reflections on the finer schedule of :data:`EARLY_BLOCK_S` (see there): at RT60 0.3 s in a
#: 7 x 6 x 3 m room these early reflections carry ~90 % of the response's energy, and
#: pyroomacoustics computes them ~25x faster than the whole response (2.3 vs 58 ms).
EARLY_ORDER = 3
#: Largest spacing (s) of the early reflections' updates: at 1.5 m/s an image source's delay
#: changes by at most ~0.7 sample (16 kHz) between two.
EARLY_BLOCK_S = 0.005


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A source path: positions at increasing times, linearly interpolated in between.

    Parameters
    ----------
    t : array (n,)
        Strictly increasing times in seconds (n >= 1), consecutive ones at most
        :data:`hearsee.config.MAX_TIME_LIMIT_S` (1e9 s, 31.7 years) apart -- the trackers' rule
        for their frames: the step from -1e308 to 1e308 s overflowed to inf, and every speed
        over it read as 0 m/s.
    positions : array (n, 3)
        Positions in metres (array frame unless said otherwise).

    Both must hold real numbers (text such as "1" was read as 1 s / 1 m, True as 1).
    Outside ``[t[0], t[-1]]`` the source stands still at the first / last position.
    """

    t: NDArray
    positions: NDArray

    def __post_init__(self) -> None:
        for what, v in (("times", self.t), ("positions", self.positions)):
            if not real_entries(v):
                raise GeometryError(f"trajectory {what} must be real numbers (seconds, metres), "
                                    f"got {v!r:.80}")
        t = np.atleast_1d(np.asarray(self.t, dtype=float))
        p = np.atleast_2d(np.asarray(self.positions, dtype=float))
        if t.ndim != 1 or p.ndim != 2 or p.shape != (t.size, 3):
            raise GeometryError(
                f"trajectory needs times (n,) and positions (n, 3); got {t.shape} and "
                f"{np.shape(self.positions)}"
            )
        if t.size < 1:
            raise GeometryError("trajectory needs at least one point")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))):
            raise GeometryError("trajectory times and positions must be finite")
        with np.errstate(over="ignore"):  # (-1e308 -> 1e308: an inf step, refused below)
            steps = np.diff(t)
        if np.any(steps <= 0):
            raise GeometryError("trajectory times must be strictly increasing")
        if np.any(steps > MAX_TIME_LIMIT_S):
            k = int(np.argmax(steps))
            raise GeometryError(f"trajectory times jump {steps[k]:.3g} s (t = {t[k]:g} s -> "
                                f"{t[k + 1]:g} s); its points are at most "
                                f"{MAX_TIME_LIMIT_S:g} s apart")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "positions", p)

    @property
    def duration(self) -> float:
        """Time span in seconds."""
        return float(self.t[-1] - self.t[0])

    def at(self, times: ArrayLike) -> NDArray:
        """Positions ``(..., 3)`` at ``times`` (seconds), linear interpolation, clamped ends."""
        tq = _times(times)
        if self.t.size == 1:
            return np.broadcast_to(self.positions[0], tq.shape + (3,)).copy()
        flat = tq.ravel()
        out = np.stack([np.interp(flat, self.t, self.positions[:, k]) for k in range(3)], axis=-1)
        return out.reshape(tq.shape + (3,))

    def heard_at(self, times: ArrayLike, point: ArrayLike = (0.0, 0.0, 0.0),
                 speed_of_sound: float = 343.0) -> NDArray:
        """Positions ``(..., 3)`` whose sound reaches ``point`` (metres, same frame) at
        ``times`` (seconds): ``p(t - tau)`` with the retarded delay ``tau = |p(t - tau) -
        point| / c`` of :func:`retarded_delays`.

        The ground truth for anything estimated from sound received at ``t`` (a tracker's
        direction at frame time ``t`` describes where the talker was ``r / c`` earlier: 3-12 ms
        at 1-4 m, up to ``|v_tangential| / c`` rad of azimuth, ~0.25 deg at walking speed);
        a camera's image at ``t`` shows :meth:`at` ``(t)``.
        """
        tq = _times(times)
        m = np.asarray(point, dtype=float).reshape(-1) if real_entries(point) else np.zeros(0)
        if m.shape != (3,) or not np.all(np.isfinite(m)):
            raise GeometryError(f"point must be 3 finite numbers (metres), got {point!r}")
        if not (is_real(speed_of_sound) and speed_of_sound > 0):  # (text: a builtin TypeError)
            raise GeometryError(f"speed_of_sound must be > 0 m/s, got {speed_of_sound!r}")
        tau, _ = retarded_delays(self, m[None, :], tq.ravel(), float(speed_of_sound))
        return self.at(tq.ravel() - tau[0]).reshape(tq.shape + (3,))

    def velocity(self, times: ArrayLike) -> NDArray:
        """Velocities ``(..., 3)`` in m/s at ``times`` (piecewise constant; zero outside; NaN
        at a NaN time where :meth:`at` is NaN -- it was the last segment's velocity,
        2026-12-02)."""
        tq = _times(times)
        if self.t.size == 1:
            return np.zeros(tq.shape + (3,))
        v_seg = np.diff(self.positions, axis=0) / np.diff(self.t)[:, None]
        k = np.clip(np.searchsorted(self.t, tq, side="right") - 1, 0, len(v_seg) - 1)
        v = v_seg[k]
        outside = (tq < self.t[0]) | (tq > self.t[-1])
        v[outside] = 0.0
        v[np.isnan(tq)] = np.nan
        return v

    def acceleration(self, times: ArrayLike) -> NDArray:
        """Accelerations ``(..., 3)`` in m/s^2 by central differences of :meth:`velocity` (5 ms)."""
        tq = _times(times)
        h = 5e-3
        return (self.velocity(tq + h) - self.velocity(tq - h)) / (2 * h)


def _times(times: ArrayLike) -> NDArray:
    """Query times (seconds) as a float array, else a GeometryError: numbers only
    (:func:`hearsee.config.real_entries`; numpy read "0.5" as 0.5 s and True as 1 s)."""
    if not real_entries(times):
        raise GeometryError(f"times must be real numbers of seconds, got {times!r:.80}")
    return np.asarray(times, dtype=float)


def linear_trajectory(start: ArrayLike, velocity: ArrayLike, duration_s: float,
                      n_points: int = 2) -> Trajectory:
    """A straight path from ``start`` (m) at constant ``velocity`` (m/s) for ``duration_s``
    (``n_points`` >= 1 knots, at least 2 used). Text, bools and a fractional ``n_points`` are
    a GeometryError (numpy read "1" as 1 m, int() truncated 2.7 and read "3" as 3)."""
    if not (is_real(duration_s) and duration_s > 0):
        raise GeometryError(f"duration must be > 0 s, got {duration_s!r}")
    n = whole_number("n_points", n_points, 1, error=GeometryError)
    p0 = as_point(start, "start")
    if not real_entries(velocity):
        raise GeometryError(f"velocity must be real numbers (m/s), got {velocity!r:.80}")
    v = np.asarray(velocity, dtype=float)
    if v.shape != (3,):  # ([1, 0] raised numpy's broadcasting ValueError)
        raise GeometryError(f"velocity must be 3 numbers vx, vy, vz (m/s), got shape {v.shape}")
    t = np.linspace(0.0, float(duration_s), max(n, 2))
    return Trajectory(t, p0[None, :] + t[:, None] * v[None, :])


def waypoint_trajectory(waypoints: ArrayLike, speed_mps: float, t0: float = 0.0) -> Trajectory:
    """A polyline through ``waypoints`` (k, 3) walked at constant ``speed_mps`` from ``t0``
    (seconds). Text or bools are a GeometryError (numpy read "1" as 1 m, True as 1 m/s)."""
    if not real_entries(waypoints):
        raise GeometryError(f"waypoints must be real numbers (metres), got {waypoints!r:.80}")
    w = np.asarray(waypoints, dtype=float)
    if w.ndim != 2 or w.shape[1] != 3 or len(w) < 2:
        raise GeometryError(f"waypoints must be k x 3 with k >= 2, got shape {w.shape}")
    if not (is_real(speed_mps) and speed_mps > 0):
        raise GeometryError(f"speed must be > 0 m/s, got {speed_mps!r}")
    finite_number("t0 (s)", t0, error=GeometryError)
    seg = np.linalg.norm(np.diff(w, axis=0), axis=1)
    if np.any(seg <= 0):
        raise GeometryError("consecutive waypoints must differ")
    t = t0 + np.concatenate([[0.0], np.cumsum(seg) / speed_mps])
    return Trajectory(t, w)


def load_trajectory(path: str | Path) -> Trajectory:
    """Read a trajectory CSV with header ``t,x,y,z`` (seconds, metres)."""
    p = input_file(path, "trajectory file")
    try:
        # (utf-8-sig: the byte-order mark of Excel's "CSV UTF-8" stayed in the first header
        # cell, and a valid file was refused)
        with p.open(newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)  # (its line_num: the file's line, blank ones counted)
            rows = [(reader.line_num, r) for r in reader if r and any(c.strip() for c in r)]
    except UnicodeDecodeError:
        raise ConfigError(f"{p}: not a text CSV file") from None
    except OSError as exc:  # (e.g. no read permission: a builtin PermissionError before)
        raise InputFileError(f"{p}: cannot be read ({exc.strerror or exc})") from None
    if not rows:
        raise ConfigError(f"{p}: empty trajectory file (expected header t,x,y,z)")
    header = [c.strip().lower() for c in rows[0][1]]
    if header != ["t", "x", "y", "z"]:
        raise ConfigError(f"{p}: header must be 't,x,y,z', got {','.join(rows[0][1])!r}")
    data = np.array([_trajectory_row(p, line, r) for line, r in rows[1:]], dtype=float)
    if data.shape[0] < 1:
        raise ConfigError(f"{p}: expected rows of 4 numbers t,x,y,z after the header")
    try:
        return Trajectory(data[:, 0], data[:, 1:])
    except GeometryError as exc:
        raise ConfigError(f"{p}: {exc}") from None


def _trajectory_row(path: Path, line: int, row: list[str]) -> list[float]:
    """The 4 numbers t, x, y, z (seconds, metres) of a trajectory CSV row, else a ConfigError
    naming ``path`` and ``line`` (a ragged row showed numpy's 'inhomogeneous shape' text)."""
    if len(row) != 4:
        raise ConfigError(f"{path}: line {line}: expected 4 values t,x,y,z, got {len(row)}: "
                          f"{','.join(row)!r}")
    try:
        return [float(c) for c in row]
    except ValueError:
        raise ConfigError(f"{path}: line {line}: non-numeric value in {','.join(row)!r}"
                          ) from None


def save_trajectory(traj: Trajectory, path: str | Path, times: ArrayLike | None = None) -> None:
    """Write ``traj`` (sampled at ``times`` if given, else its own knots) as CSV ``t,x,y,z``:
    times in full precision (the shortest text that reads back as the same float), positions
    to the micrometre; what :func:`load_trajectory` reads back. The times must be finite and
    strictly increasing (GeometryError): knots 1e-7 s apart were written as one time, and NaN
    times as "nan" rows, files load_trajectory refused."""
    _check_trajectory(traj, "traj")
    # (a scalar time raised a builtin TypeError, text a ValueError)
    t = traj.t if times is None else np.atleast_1d(_times(times)).ravel()
    if not (np.all(np.isfinite(t)) and np.all(np.diff(t) > 0)):
        raise GeometryError("save_trajectory: times must be finite and strictly increasing "
                            "seconds")
    p = traj.at(t)
    buf = io.StringIO(newline="")
    w = csv.writer(buf)
    w.writerow(["t", "x", "y", "z"])
    for ti, pi in zip(t, p, strict=True):
        w.writerow([repr(float(ti)), f"{pi[0]:.6f}", f"{pi[1]:.6f}", f"{pi[2]:.6f}"])
    # (replaced once complete: written in place, a write that failed part way truncated the
    # earlier file; config.replacing)
    write_file(output_file(path), buf.getvalue())


#: Most grid times :func:`truth_times` makes (10 million: a 600 s recording every 60 us);
#: ``step_s=1e-12`` asked for 1e12 and raised a MemoryError.
MAX_TRUTH_TIMES = 10_000_000


def truth_times(traj: Trajectory, duration_s: float, step_s: float = 0.01) -> NDArray:
    """Times (seconds) at which to write a recording's ground-truth trajectory: a ``step_s``
    grid from 0, the trajectory's own knots within the recording (its corners) and the
    recording's end ``duration_s``, rounded to the microsecond the CSV keeps (so that no two
    rows share a time). The 10 ms grid alone stopped up to one step before the end (the truth
    of the last 10 ms was a held position) and cut the trajectory's corners. ``step_s`` is at
    least that microsecond, and the grid at most :data:`MAX_TRUTH_TIMES` times long (else a
    GeometryError)."""
    _check_trajectory(traj)
    dur = finite_number("duration_s", duration_s, 0.0, lo_open=True, error=GeometryError)
    # (below the CSV's microsecond the rows merged anyway)
    step = finite_number("step_s", step_s, 1e-6, error=GeometryError)
    if dur / step >= MAX_TRUTH_TIMES:
        raise GeometryError(f"truth_times: {dur:g} s every {step:g} s is {dur / step:.3g} "
                            f"times, more than {MAX_TRUTH_TIMES}; give a larger step_s")
    grid = np.arange(int(math.floor(dur / step + 1e-9)) + 1) * step
    knots = traj.t[(traj.t > 0.0) & (traj.t < dur)]
    return np.unique(np.round(np.concatenate([grid[grid < dur], knots, [dur]]), 6))


# ---------------------------------------------------------------------------- free field
def fractional_delay(signal: ArrayLike, delays_samples: ArrayLike, n_out: int | None = None,
                     half_width: int = SINC_HALF_WIDTH, beta: float = SINC_KAISER_BETA,
                     chunk: int = 4096,
                     tick: Callable[[int, int], None] | None = None) -> NDArray:
    """Time-varying fractional delay: ``y[n] = x(n - D[n])`` by windowed-sinc interpolation.

    Parameters
    ----------
    signal : array (n,)
        Input samples ``x``; zero outside ``[0, n)``.
    delays_samples : array (n_out,) or (n_ch, n_out)
        Delay ``D`` per output sample, in samples (any non-negative real number).
    half_width : int
        Taps on each side of the interpolation point (Kaiser-windowed sinc), 1 to
        :data:`MAX_SINC_HALF_WIDTH`.
    beta : float
        Kaiser window parameter (finite, >= 0).
    chunk : int
        Output samples interpolated at once (>= 1; memory ~ ``chunk * 2 half_width``).
    tick : callable, optional
        ``tick(done, total)`` after each chunk: chunks finished, over all channels.

    Returns
    -------
    array shaped like ``delays_samples``.

    The interpolator is exact for a band-limited input below about 0.9 x Nyquist (error near
    -80 dB); it is vectorised over chunks of ``chunk`` output samples. A NaN/inf signal,
    negative or non-finite delays are refused (AudioInputError / GeometryError), and so are
    out-of-range options (ConfigError: ``half_width=0`` and a negative ``chunk`` used to
    return silence, a NaN ``beta`` NaNs). A delay longer than the output leaves it silent.
    """
    x = as_samples(signal, "signal", finite=False)
    if x.ndim != 1:
        raise AudioInputError(f"signal must be one-dimensional, got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise AudioInputError("signal contains NaN or infinite samples")
    d = as_float_array(delays_samples, "delays", finite=False, error=GeometryError)
    if d.ndim not in (1, 2):
        raise GeometryError(f"delays must be (n_out,) or (n_ch, n_out), got shape {d.shape}")
    squeeze = d.ndim == 1
    d = np.atleast_2d(d)
    if not np.all(np.isfinite(d)) or np.any(d < 0):
        raise GeometryError("delays must be finite and non-negative")
    n_out = d.shape[1] if n_out is None else whole_number("n_out", n_out, 0)
    if d.shape[1] != n_out:
        raise GeometryError(f"delays must have n_out={n_out} samples, got {d.shape[1]}")
    L = whole_number("half_width", half_width, 1, MAX_SINC_HALF_WIDTH)
    beta = finite_number("beta", beta, 0.0)
    chunk = whole_number("chunk", chunk)
    if tick is not None and not callable(tick):
        raise ConfigError(f"tick must be a callable tick(done, total) or None, got {tick!r:.40}")
    # a delay beyond n_out + L puts every tap before the signal's start: the output is 0
    # there, as it is for the clipped delay (a 1e12-sample delay asked for 7 TiB of padding)
    d = np.minimum(d, n_out + L + 1.0)
    pad_front = int(np.ceil(d.max())) + L + 1 if d.size else L + 1
    xp = np.concatenate([np.zeros(pad_front), x, np.zeros(L + 1)])
    k = np.arange(-L + 1, L + 1)  # 2L taps
    i0_beta = np.i0(beta)
    y = np.zeros((d.shape[0], n_out))
    last = len(xp) - 1
    per_ch = -(-n_out // chunk)
    for ch in range(d.shape[0]):
        for j, s in enumerate(range(0, n_out, chunk)):
            if tick is not None:
                tick(ch * per_ch + j, d.shape[0] * per_ch)
            e = min(s + chunk, n_out)
            pos = np.arange(s, e) - d[ch, s:e] + pad_front  # position in xp
            i0 = np.floor(pos).astype(np.int64)
            frac = pos - i0
            u = frac[:, None] - k[None, :]  # distance from tap to interpolation point
            win = np.i0(beta * np.sqrt(np.clip(1.0 - (u / L) ** 2, 0.0, None))) / i0_beta
            h = np.sinc(u) * win
            idx = i0[:, None] + k[None, :]
            valid = (idx >= 0) & (idx <= last)
            y[ch, s:e] = np.sum(np.where(valid, xp[np.clip(idx, 0, last)], 0.0) * h, axis=1)
    if tick is not None:
        tick(d.shape[0] * per_ch, d.shape[0] * per_ch)
    return y[0] if squeeze else y


#: Moving sources may be at most this fraction of the speed of sound fast (34 m/s at 343 m/s:
#: walkers, robots, drones, cars in town). :func:`retarded_delays`' four fixed-point steps then
#: leave a delay error below ~(0.1)^4 of the first guess's (~0.1 us); a supersonic trajectory
#: (a 100 m jump in 10 ms in a CSV file) used to be simulated without a word, as garbage.
MAX_SPEED_FRACTION = 0.1


def _step_speed(traj: Trajectory, k: int, v: float) -> str:
    """The speed (m/s) of the trajectory's step ``k`` as text: ``v`` (the float figure) to 4
    digits, or where it overflowed (a 1e300 m jump: np.linalg.norm squares it) the step's
    exact figure in decimal arithmetic, which has no float's range (1.414e+300, 2e+618)."""
    if math.isfinite(v):
        return f"{v:.4g}"
    with localcontext() as ctx:
        ctx.prec = 20
        d = [Decimal(b) - Decimal(a) for a, b in zip(traj.positions[k], traj.positions[k + 1],
                                                     strict=True)]
        speed = sum(x * x for x in d).sqrt() / (Decimal(traj.t[k + 1]) - Decimal(traj.t[k]))
        ctx.prec = 4
        return format((+speed).normalize(), "g")


def retarded_delays(traj: Trajectory, mics: ArrayLike, t: ArrayLike, c: float,
                    n_iter: int = 4) -> tuple[NDArray, NDArray]:
    """Propagation delay and distance per microphone for reception times ``t``.

    Solves ``tau = |p(t - tau) - m| / c`` by fixed-point iteration (a contraction with factor
    ``|v| / c``). Returns ``(tau (n_mics, n) seconds, r (n_mics, n) metres at emission)``.
    Raises :class:`GeometryError` when a segment of the trajectory is faster than
    ``MAX_SPEED_FRACTION`` of ``c`` (the iteration's error shrinks by ``|v| / c`` per step),
    and for microphones, times or a speed of sound that are no numbers (text was read as
    numbers, a text ``c`` raised a builtin TypeError).
    """
    if not real_entries(mics):
        raise GeometryError(f"microphone positions must be real numbers (metres), got "
                            f"{mics!r:.80}")
    finite_number("c (m/s)", c, 0.0, lo_open=True, error=GeometryError)
    _check_trajectory(traj)
    # (n_iter 0 raised UnboundLocalError, one microphone given as (3,) numpy's IndexError)
    n_iter = whole_number("n_iter", n_iter, 1, error=GeometryError)
    m = np.asarray(mics, dtype=float)
    if m.ndim != 2 or m.shape[1] != 3 or len(m) == 0:
        raise GeometryError(f"microphone positions must be N x 3 (N >= 1), got shape {m.shape}")
    tq = _times(t)
    if traj.t.size > 1:
        with np.errstate(over="ignore"):  # (a 1e300 m jump: inf m/s, refused just below)
            v = np.linalg.norm(np.diff(traj.positions, axis=0), axis=1) / np.diff(traj.t)
        k = int(np.argmax(v))
        if v[k] > MAX_SPEED_FRACTION * c:
            raise GeometryError(
                f"the trajectory moves at {_step_speed(traj, k, v[k])} m/s between t = "
                f"{traj.t[k]:g} and "
                f"{traj.t[k + 1]:g} s; moving sources must be slower than "
                f"{MAX_SPEED_FRACTION:g} times the speed of sound ({MAX_SPEED_FRACTION * c:.1f} "
                "m/s)")
    tau = _distance(traj.at(tq)[None, :, :] - m[:, None, :]) / c
    for _ in range(n_iter):
        r = _distance(traj.at(tq[None, :] - tau) - m[:, None, :])
        tau = r / c
    return tau, r


def _distance(d: NDArray) -> NDArray:
    """Lengths of the vectors ``d`` (..., 3), metres, without overflow: a source 1e200 m away
    squared to inf with numpy's RuntimeWarning, and was then said to be "beyond float range"
    (:func:`hearsee.geometry.vector_length`; ordinary lengths bit for bit as
    np.linalg.norm's)."""
    if not np.abs(d).max(initial=0.0) > 1e150:  # (the usual case, at one pass's cost)
        return np.linalg.norm(d, axis=-1)
    return vector_length(d)


def _mics_and_c(mics: MicArray | ArrayLike, speed_of_sound: float | None) -> tuple[NDArray, float]:
    """Microphone positions (N, 3) in metres and the speed of sound (m/s), checked as the
    static :func:`hearsee.audio.propagation.simulate_free_field` checks them (a preset name
    raised numpy's builtin ValueError, True was read as 1 m and a NaN coordinate reported as
    a source "too far (beyond float range)"; 2026-12-02)."""
    from hearsee.audio.propagation import _mic_positions

    return _mic_positions(mics), speed_of_sound_of(mics, speed_of_sound)


def _check_signal(signal: ArrayLike, fs: float) -> NDArray:
    # (as_samples: text raised numpy's ValueError, booleans were taken as samples)
    x = as_samples(signal, "signal")
    if x.ndim != 1 or x.size == 0:
        raise AudioInputError(f"signal must be a non-empty 1-D array, got shape {x.shape}")
    check_fs(fs)
    return x


def _check_trajectory(traj: Any, what: str = "trajectory") -> None:
    """A :class:`Trajectory`, else a GeometryError (any other object raised a builtin
    AttributeError deep in the simulators)."""
    if not isinstance(traj, Trajectory):
        raise GeometryError(f"{what}: expected a Trajectory, got {type(traj).__name__}")


def simulate_moving_free_field(
    signal: ArrayLike,
    fs: float,
    mics: MicArray | ArrayLike,
    trajectory: Trajectory,
    snr_db: float | None = None,
    rng: np.random.Generator | int | None = None,
    speed_of_sound: float | None = None,
    progress: Progress | None = None,
) -> NDArray:
    """Record ``signal`` emitted by a source moving along ``trajectory`` in free field.

    Parameters
    ----------
    signal : array (n,)
        Source waveform (at 1 m), sample 0 emitted at t = 0 s.
    fs : float
        Sample rate, Hz.
    mics : MicArray or array (n_mics, 3)
        Microphone positions, metres, same frame as the trajectory.
    trajectory : Trajectory
        Source path (seconds, metres).
    snr_db : float, optional
        Per-channel SNR of added white sensor noise.
    progress : callable, optional
        ``progress(stage, done, total)`` (:data:`Progress`): one stage, the interpolator's
        chunks of 4096 output samples per microphone (~0.2 s of CPU per second of recording
        and microphone at 16 kHz).

    Returns
    -------
    array (n_mics, n)
        Microphone signals: retarded-time fractional delays (Doppler included) and ``1/r``
        gains. For a static trajectory this equals
        :func:`hearsee.audio.propagation.simulate_free_field` to about -70 dB for a signal
        band-limited below ~0.9 x Nyquist (the interpolator's range, :func:`fractional_delay`);
        white noise up to Nyquist differs by -20 to -50 dB overall, all of it in the top ~5 %
        of the band, where the 32-tap interpolator's gain falls with the delay's fraction (0.84
        at 0.48 fs for half a sample; measured 2026-12-07). The TDOAs are not affected.
    """
    x = _check_signal(signal, fs)
    check_rng(rng)  # (before the work: add_noise draws from it at the end)
    snr_db = check_snr_db(snr_db)  # (add_noise refused a bad one only after the work)
    progress = _check_progress(progress)
    pos, c = _mics_and_c(mics, speed_of_sound)
    t = np.arange(x.size) / fs
    tau, r = retarded_delays(trajectory, pos, t, c)
    if np.any(r < 1e-3):
        raise GeometryError("the moving source passes through a microphone")
    # (t - tau grows with t below the speed of sound: heard at all means heard at the end)
    # (every microphone must hear it: only the nearest one was checked)
    check_heard(float(r[:, -1].max()), c, x.size, fs, "farthest")
    y = fractional_delay(x, tau * fs, tick=None if progress is None else (
        lambda done, total: progress("direct path (fractional delays)", done, total))) / r
    return add_noise(y, snr_db, rng)


#: :func:`simulate_moving_masked`'s blocks (s): Hann windows this long at half its hop, each
#: through the transfer functions of the source's position at its centre
MASKED_BLOCK_S = 0.016


def simulate_moving_masked(
    signal: ArrayLike,
    fs: float,
    array: Any,
    trajectory: Trajectory,
    snr_db: float | None = None,
    rng: np.random.Generator | int | None = None,
    far_field: bool = False,
    block_s: float = MASKED_BLOCK_S,
    progress: Progress | None = None,
) -> NDArray:
    """Record ``signal`` emitted by a source moving along ``trajectory`` through a masked
    two-microphone array (ch. 3's mask, ch. 5's moving sources).

    Block-wise: the signal is cut into Hann windows of ``block_s`` seconds at half that hop
    (they sum to one), each block is rendered as
    :func:`hearsee.audio.mask.simulate_masked` renders a static source -- the mask's transfer
    functions (:meth:`hearsee.audio.mask.MaskModel.transfer_at`) of the position the source
    emits it from (its centre's time), times the free-field delay ``d / c`` and gain ``1 / d``
    to the array origin (``far_field``: only the direction counts, a fixed bulk delay of 1 ms,
    gain 1) -- and the blocks are overlap-added: between two blocks' positions the output
    cross-fades. A person walking 1.5 m/s past 1 m away turns ~0.7 deg per 8-ms hop (the
    default blocks'); the mask's model ends at ``f_max`` (4 kHz for the presets). Block-wise
    as :func:`simulate_moving_room` renders rooms, with the mask's diffraction instead of a
    room's image sources (pyroomacoustics has neither masks nor moving sources). For a static
    trajectory it equals :func:`~hearsee.audio.mask.simulate_masked` to -65 dB or better
    (largest difference over the largest sample: -79 / -81 dB for ``mask2-asym`` near / far,
    -71 / -68 dB for a coarse 2-kHz model). Reconstruction beyond the thesis, which recorded
    its moving speakers.

    Parameters
    ----------
    signal : array (n,)
        Source waveform (at 1 m in the near field), sample 0 emitted at t = 0 s.
    fs : float
        Sample rate, Hz.
    array : MicArray, preset name, path or MaskModel
        A masked two-microphone array (e.g. ``"mask2-asym"``).
    trajectory : Trajectory
        Source path in the array frame (seconds, metres; ``far_field``: its directions).
    snr_db : float, optional
        Per-channel SNR of added white sensor noise.
    block_s : float
        Block length, s (at least two samples).
    progress : callable, optional
        ``progress(stage, done, total)`` as the blocks are rendered (:data:`Progress`; one
        stage, :func:`_masked_stage`).

    Returns
    -------
    array (2, n)
    """
    from hearsee.audio.mask import MaskModel

    x = _check_signal(signal, fs)
    fs = float(fs)
    check_rng(rng)  # (before the work: add_noise draws from it at the end)
    snr_db = check_snr_db(snr_db)
    _check_trajectory(trajectory)
    far_field = true_or_false("far_field", far_field)
    progress = _check_progress(progress)
    hop, K = _masked_blocks(x.size, fs, block_s)
    model = array if isinstance(array, MaskModel) else MaskModel(array)
    L = 2 * hop
    n = x.size
    pos = trajectory.at(np.arange(K) * hop / fs)  # (K, 3) emission positions
    if far_field:
        bulk, gain = np.full(K, 1e-3), np.ones(K)
    else:
        d = np.linalg.norm(pos, axis=1)
        if np.any(d < 1e-9):
            raise GeometryError("the moving source passes through the array's origin")
        far = np.linalg.norm(pos[:, None] - model.array.positions[None], axis=-1).max()
        check_heard(float(far), model.c, n, fs, "farthest")
        bulk, gain = d / model.c, 1.0 / d
    # each block's response runs from `pre` samples before its start (the frequency-interpolated
    # transfer functions ring a little before the arrival: wrapped around, that ringing was
    # added to a later stretch of the output) to `tail` after its end
    pre = int(np.ceil(0.01 * fs))
    tail = int(np.ceil((bulk.max() + 2 * model.max_itd() + 0.01) * fs))
    nf = sfft.next_fast_len(pre + L + tail, real=True)
    f = np.fft.rfftfreq(nf, 1.0 / fs)
    w = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(L) / L)  # periodic Hann: sums to one
    xp = np.concatenate([np.zeros(hop), x, np.zeros(L)])
    y = np.zeros((2, pre + K * hop + nf))  # (sample j of the signal at pre + hop + j)
    stage = _masked_stage(block_s)
    _announce(progress, [(stage, K)])
    for k0 in range(0, K, 256):  # (a few hundred blocks of transfer functions at a time)
        ks = np.arange(k0, min(k0 + 256, K))
        h = model.transfer_at(f, pos[ks], far_field)  # (B, 2, F); GeometryError inside the body
        seg = xp[ks[:, None] * hop + np.arange(L)] * w
        spec = (sfft.rfft(seg, nf, axis=-1) * gain[ks, None]
                * np.exp(-2j * np.pi * f * (bulk[ks, None] + pre / fs)))
        yb = sfft.irfft(spec[:, None, :] * np.conj(h), nf, axis=-1)  # (B, 2, nf)
        for b, k in enumerate(ks):
            y[:, k * hop:k * hop + nf] += yb[b]
        if progress is not None:
            progress(stage, int(ks[-1]) + 1, K)
    return add_noise(y[:, pre + hop:pre + hop + n], snr_db, rng)


def _masked_blocks(n: int, fs: float, block_s: Any) -> tuple[int, int]:
    """:func:`simulate_moving_masked`'s hop (samples) and block count for ``n`` samples:
    Hann blocks of ``block_s`` seconds (at least two samples, else a ConfigError) at half
    that hop; block k covers samples [k hop - hop, k hop + hop) of the signal."""
    if not (is_real(block_s) and np.isfinite(block_s) and block_s * fs >= 2):
        raise ConfigError(f"block_s must be a number of seconds of at least two samples, got "
                          f"{block_s!r:.40}")
    hop = max(int(round(block_s * fs / 2)), 1)
    return hop, (n - 1 + hop) // hop + 1


def _masked_stage(block_s: float) -> str:
    """The progress stage of :func:`simulate_moving_masked` (its blocks of ``block_s`` s)."""
    return f"direct path through the mask ({block_s * 1e3:.3g}-ms blocks)"


# ---------------------------------------------------------------------------- rooms
#: Largest change (samples) of a microphone's direct-path delay between two impulse-response
#: updates of :func:`simulate_moving_room` (see its ``max_delay_step_samples``). Between
#: updates the crossfade sums two copies d samples apart, a mid-update loss of
#: ``cos(pi f d / fs)``: with 0.5, under 0.7 dB below fs / 4 and 2.3 dB at 0.45 fs. At
#: walking speed (<= 1.5 m/s) and 16 kHz the early reflections' 5 ms updates already keep
#: within it (0.35 samples), so only rooms without that split (rt60 0, a low ``max_order``, a
#: custom ``rir_fn``) or faster sources and higher rates get more updates.
MAX_DELAY_STEP_SAMPLES = 0.5


#: A renderer's progress report: ``progress(stage, done, total)`` -- ``stage`` names a part of
#: the work (e.g. ``"later reflections (orders 4-17)"``), ``done`` of its ``total`` steps
#: (blocks or impulse-response updates) are finished. Every stage is announced with
#: ``done = 0`` before any work, so a display can show them all from the start; the stages'
#: steps cost very different amounts (a masked walk of 4 s in a room of RT60 0.3 s: ~500
#: direct-path blocks, 2.9 s; ~800 updates of orders 1-3, 6.8 s; ~80 of the rest, 77 s),
#: which is why they are reported apart rather than as one count.
Progress = Callable[[str, int, int], None]


def _check_progress(progress: Any) -> Progress | None:
    """``progress`` None or a callable (a ConfigError otherwise: a TypeError came only after
    the first update's work)."""
    if progress is not None and not callable(progress):
        raise ConfigError(f"progress must be a callable progress(stage, done, total) or None, "
                          f"got {progress!r:.40}")
    return progress


def _orders_stage(label: str, first: int, last: int) -> str:
    """A progress stage's name: ``label`` and the image-source orders it renders (0 = the
    direct path), e.g. ``"later reflections (orders 4-17)"``."""
    return f"{label} (orders {first}-{last})" if last > first else f"{label} (order {first})"


def _update_times(trajectory: Trajectory, mics: NDArray, c: float, fs: float, n: int,
                  block_s: float, max_tdoa_step_samples: float | None,
                  max_delay_step_samples: float | None = None) -> NDArray:
    """Sample times (float sample indices, increasing, from 0 to ``n - 1``) of the impulse-
    response updates of :func:`simulate_moving_room`.

    At most ``block_s`` seconds apart, and closer wherever the source moves fast across the
    array: between two updates no microphone pair's direct-path TDOA changes by more than
    ``max_tdoa_step_samples`` samples and, if given, no microphone's direct-path delay
    (distance / c) by more than ``max_delay_step_samples`` samples (each measured on a 2 ms
    grid, or a ``block_s`` one when that is finer, summed step by step -- an upper bound of
    the change). Where one step of that grid already exceeds a bound (a fast source close to
    the array: 3 m/s passing 0.3 m from the three-mic array moved its TDOAs by 0.12 sample
    in 2 ms), that step is split, down to one sample; a bound that even one-sample updates
    cannot keep is a GeometryError. Both None: every ``block_s`` seconds.
    """
    hop = max(int(round(block_s * fs)), 1)
    bounds = [b for b in (max_tdoa_step_samples, max_delay_step_samples) if b is not None]
    if not bounds:
        centres = np.arange(0, n, hop, dtype=float)
    else:
        def grid_steps(tf: NDArray) -> NDArray:
            """Each bound as a cumulative change that may grow by 1 between two updates:
            its growth over each step of the grid ``tf`` (s), the largest of the bounds'."""
            p = trajectory.at(tf)
            steps = []
            if max_tdoa_step_samples is not None:
                tau = MicArray(mics, speed_of_sound=c).tdoa(p) * fs  # (n_fine, pairs)
                steps.append(np.max(np.abs(np.diff(tau, axis=0)), axis=1)
                             / max_tdoa_step_samples)
            if max_delay_step_samples is not None:
                d = np.linalg.norm(p[:, None, :] - mics[None, :, :], axis=-1) / c * fs
                steps.append(np.max(np.abs(np.diff(d, axis=0)), axis=1) / max_delay_step_samples)
            return np.max(steps, axis=0)

        # (a fixed 2 ms grid spaced the updates 2 ms apart even for a shorter block_s)
        grid = min(0.002, hop / fs)
        tf = np.append(np.arange(0.0, (n - 1) / fs, grid), (n - 1) / fs)
        step = grid_steps(tf)
        # the next update is at least one grid step away: a grid step above the bound broke
        # it (until 2026-12-02). Split such steps (only those: elsewhere the grid is as it
        # was), into pieces of at least one sample
        while True:
            width = np.diff(tf) * fs  # samples
            split = np.flatnonzero((step > 1.0) & (width >= 2.0))
            if not len(split):
                break
            parts = np.minimum(np.ceil(1.25 * step[split]), np.floor(width[split])).astype(int)
            tf = np.sort(np.concatenate([tf, *(
                tf[i] + (tf[i + 1] - tf[i]) * np.arange(1, k) / k
                for i, k in zip(split, parts, strict=True))]))
            step = grid_steps(tf)
        if np.any(step > 1.0):
            i = int(np.argmax(step))
            raise GeometryError(
                f"the source moves too fast near the array at t = {tf[i]:.4g} s for updates "
                f"every sample to keep max_tdoa_step_samples / max_delay_step_samples: the "
                f"change within {np.diff(tf)[i] * fs:.2g} sample(s) is {step[i]:.3g} times the "
                "bound; give a larger bound (or None)")
        D = np.r_[0.0, np.cumsum(step)]
        picked, k = [0], 0
        while k < len(tf) - 1:
            by_step = int(np.searchsorted(D, D[k] + 1.0, "right")) - 1
            by_time = int(np.searchsorted(tf, tf[k] + hop / fs + 1e-12, "right")) - 1
            k = max(min(by_step, by_time), k + 1)
            picked.append(k)
        centres = np.unique(np.round(tf[picked] * fs))
    if centres[-1] < n - 1:
        centres = np.append(centres, n - 1)
    return centres


def _hat_weight(b: int, lo: int, hi: int, centres: NDArray) -> NDArray:
    """Linear-interpolation weight of block ``b`` on samples ``lo:hi``.

    Over all blocks these triangular weights sum to one at every sample (partition of unity).
    """
    onehot = np.zeros(len(centres))
    onehot[b] = 1.0
    return np.interp(np.arange(lo, hi, dtype=float), centres, onehot)


def simulate_moving_room(
    signal: ArrayLike,
    fs: float,
    array: MicArray,
    trajectory: Trajectory,
    room_dim: ArrayLike,
    rt60: float,
    array_at: ArrayLike,
    snr_db: float | None = None,
    rng: np.random.Generator | int | None = None,
    block_s: float = 0.05,
    mic_positions: ArrayLike | None = None,
    rir_fn: Callable[[NDArray], NDArray] | None = None,
    max_tdoa_step_samples: float | None = 0.1,
    max_delay_step_samples: float | None = MAX_DELAY_STEP_SAMPLES,
    max_order: int | None = None,
    early_order: int | None = EARLY_ORDER,
    early_block_s: float = EARLY_BLOCK_S,
    progress: Progress | None = None,
) -> NDArray:
    """Record a moving source in a shoebox room: block-wise image-source RIRs, crossfaded.

    Parameters
    ----------
    signal : array (n,)
        Source waveform, sample 0 emitted at t = 0 s.
    fs : float
        Sample rate, Hz.
    array : MicArray
        The microphones (array frame).
    trajectory : Trajectory
        Source path in the ARRAY frame (seconds, metres).
    room_dim : array (3,)
        Room size in metres.
    rt60 : float
        Reverberation time in seconds (passed to the image-source model).
    array_at : array (3,)
        Array origin in room coordinates (metres); axes parallel to the room's.
    block_s : float
        Largest spacing in seconds of the impulse-response updates (default 50 ms: at 1.5 m/s
        the source moves 7.5 cm between updates, and the linear crossfade interpolates in
        between).
    max_tdoa_step_samples : float or None
        Updates are placed closer than ``block_s`` where needed so that no microphone pair's
        direct-path TDOA moves by more than this many samples between two of them (default
        0.1; None = every ``block_s``). Between updates the crossfade mixes two copies of the
        sound whose TDOAs differ by that step, which biases the correlation peak: for a
        source walking 0.5-2 m from the 15 cm three-mic array at <= 1 m/s (bench/tracking.py
        part B walks, seed 100, direct path only) 0.1 s blocks (TDOA steps up to ~0.5 sample)
        put the camera-ray 3D tracker at 4.9 cm median error, 0.02 s blocks at 3.8 cm, as
        the exact free-field renderer (3.7 cm). The step bound gives that accuracy where
        the geometry needs it without computing responses every 20 ms for slow, distant
        sources. It holds however fast the source crosses (updates down to one sample apart;
        until 2026-12-02 never closer than 2 ms, which let a source at 3 m/s 0.3 m from the
        three-mic array move its TDOAs by 0.12 sample between updates); a bound that even
        updates every sample cannot keep (a source of tens of m/s grazing the microphones,
        a bound of hundredths of a sample) is a GeometryError.

        The bound is on the direct path's TDOAs only; see ``early_order`` for the reflections.
    max_delay_step_samples : float or None
        Likewise for each microphone's direct-path delay (distance / c), on the schedule of the
        part that holds the direct path (the early part when split, else the whole response);
        default :data:`MAX_DELAY_STEP_SAMPLES`. A source moving toward or away from the array
        barely changes the TDOAs, and between two updates the crossfade adds two copies of its
        sound as many samples apart as the delay moved: without this bound a source receding at
        1 m/s in a room without reflections (``rt60=0``, or ``max_order`` <= ``early_order``)
        was rendered with 2.3-sample steps every 50 ms, a comb filter whose mid-update notch
        took a 3.4 kHz tone to 0.13 of its level (now: updates every ~11 ms, the tone within
        a few percent of the exact free-field rendering).
    mic_positions : array (n_mics, 3), optional
        Override the array's microphone positions (array frame), e.g. a rotated head.
    rir_fn : callable, optional
        ``rir_fn(source_room (3,)) -> (n_mics, L)`` impulse responses; default
        :func:`hearsee.audio.propagation.room_impulse_responses` with the room above, the
        array's speed of sound and ``max_order``.
    max_order : int, optional
        Image-source order override of the default ``rir_fn`` (0 = direct path only).
    early_order : int or None
        The default ``rir_fn``'s responses are split in two (since 2026-11-26): the images up to
        this order (the early reflections, direct path included) are updated every
        ``early_block_s`` seconds (and as often as ``max_tdoa_step_samples`` asks), the rest
        (the whole response minus that part, from the same pyroomacoustics model) on the
        schedule above; the two renderings add up. The reflections' delays change faster than
        the direct path's TDOAs (an image source recedes while the source approaches it), and
        between two updates the crossfade renders each reflection as two copies at the two
        updates' delays rather than one moving copy; with 0.1 s updates that changed the
        room's per-frame statistics: on 8 walks of ``bench/tracking.py`` (white noise, RT60
        0.3 s, 10 dB, dev seed 300) the stream's per-frame / tracked azimuth RMSE was 3.29 /
        2.44 deg with whole responses every 0.1 s, 2.40 / 1.36 with this split (early order 3
        every 5 ms), 2.41 / 1.38 with early reflections every 2 ms, and on three of the walks
        whole responses every 3 ms (the reference, 25x the CPU) matched the 2-ms split to
        within 0.04 deg per walk. The direct path alone is rendered faithfully either way
        (``max_order=0``: 0.46-0.47 deg for every spacing, as the free-field renderer). None
        (or a custom ``rir_fn``, or an order not above it) renders whole responses only.
    early_block_s : float
        Largest spacing in seconds of the early reflections' updates (default 5 ms).
    progress : callable, optional
        ``progress(stage, done, total)`` after each impulse-response update (:data:`Progress`;
        the stages: the early and the later responses when split, else the room's responses).

    Returns
    -------
    array (n_mics, n)
    """
    x = _check_signal(signal, fs)
    progress = _check_progress(progress)
    early_order = _check_updates(block_s, early_block_s, early_order)
    for name, bound in (("max_tdoa_step_samples", max_tdoa_step_samples),
                        ("max_delay_step_samples", max_delay_step_samples)):
        if bound is not None and not (is_real(bound) and bound > 0):
            raise GeometryError(f"{name} must be > 0 or None, got {bound!r}")
    check_rng(rng)  # (before the work: add_noise draws from it at the end)
    # (add_noise refused a bad SNR only after the work: 10 s of responses for a 2-s walk)
    snr_db = check_snr_db(snr_db)
    if rir_fn is not None and not callable(rir_fn):  # (a builtin TypeError at the first block)
        raise GeometryError(f"rir_fn must be a function source_room (3,) -> (n_mics, L) impulse "
                            f"responses, got {type(rir_fn).__name__}")
    from hearsee.sim.audio import _mic_positions

    if not isinstance(array, MicArray):
        raise GeometryError(f"array: expected a MicArray, got {type(array).__name__}")
    _check_trajectory(trajectory)
    # (a 2-D array_at, N x 2 microphones or a "5x4x3" room raised numpy's ValueError)
    at = as_point(array_at, "array_at")
    mics = array.positions if mic_positions is None else _mic_positions(array, mic_positions)
    mics_room = mics + at
    dim = as_point(room_dim, "room_dim")
    if np.any(dim <= 0):
        raise GeometryError(f"room_dim must be positive lengths in metres, got {dim.tolist()}")
    early_fn = None
    stages = ["room responses", None]  # (the whole / later part's, the early part's)
    if rir_fn is None:
        from hearsee.audio.propagation import image_sources, room_impulse_responses

        def rir_at(src_room: NDArray, order: int | None) -> NDArray:
            return room_impulse_responses(fs, mics_room, src_room, dim, rt60, max_order=order,
                                          speed_of_sound=array.speed_of_sound)

        order = image_sources(rt60, dim, array.speed_of_sound, max_order)[1]
        stages[0] = _orders_stage("room responses", 0, order)
        if early_order is not None and order > early_order:
            stages = [_orders_stage("later reflections", early_order + 1, order),
                      _orders_stage("direct path and early reflections", 0, early_order)]

            def early_fn(src_room: NDArray) -> NDArray:
                return rir_at(src_room, early_order)

            def rir_fn(src_room: NDArray) -> NDArray:  # the rest: whole minus early
                h, e = rir_at(src_room, max_order), early_fn(src_room)
                h[:, : e.shape[1]] -= e
                return h
        else:
            def rir_fn(src_room: NDArray) -> NDArray:
                return rir_at(src_room, max_order)

    n = x.size
    # the direct sound must reach the array by the last sample (as in the free field)
    r_end = retarded_delays(trajectory, mics, [(n - 1) / fs], array.speed_of_sound)[1]
    check_heard(float(r_end.max()), array.speed_of_sound, n, fs, "farthest")
    out = np.zeros((len(mics), n))
    direct = early_fn if early_fn is not None else rir_fn  # (the part holding the direct path)
    parts = [(fn, _update_times(trajectory, mics, array.speed_of_sound, fs, n, spacing,
                                max_tdoa_step_samples,
                                max_delay_step_samples if fn is direct else None), stage)
             for fn, spacing, stage in ((rir_fn, block_s, stages[0]),
                                        (early_fn, early_block_s, stages[1]))
             if fn is not None]
    _announce(progress, [(stage, len(centres)) for _, centres, stage in parts])
    # positions at the update times, evaluated at the (approximate) emission time
    _render_stages(x, parts, trajectory, at, fs, out, progress)
    return add_noise(out, snr_db, rng)


def _check_updates(block_s: Any, early_block_s: Any, early_order: Any) -> int | None:
    """The room renderers' update settings checked (a GeometryError otherwise): both
    spacings finite seconds > 0, ``early_order`` None or a whole number >= 0 (returned as an
    int). (``block_s`` had only a "> 0" test: a string raised a builtin TypeError, inf an
    OverflowError in the update grid.)"""
    for name, spacing in (("block_s", block_s), ("early_block_s", early_block_s)):
        if not (is_real(spacing) and spacing > 0):
            raise GeometryError(f"{name} must be > 0 seconds, got {spacing!r}")
    if early_order is None:
        return None
    return whole_number("early_order", early_order, 0, error=GeometryError)


def _render_blocks(x: NDArray, centres: NDArray, src_room: NDArray,
                   rir_fn: Callable[[NDArray], NDArray], out: NDArray,
                   tick: Callable[[int, int], None] | None = None) -> None:
    """Add to ``out`` (n_mics, n) the signal ``x`` (n,) through ``rir_fn``'s responses for
    the source at ``src_room`` (room frame, metres) at the update times ``centres`` (sample
    indices), crossfaded by triangular weights in emission time. Several signals along the
    same path: ``x`` (k, n) and ``out`` (k, n_mics, n), each response computed once.
    ``tick(done, total)`` is called after each update with the number finished."""
    n_mics, n = out.shape[-2:]
    for b in range(len(centres)):
        if tick is not None and b:
            tick(b, len(centres))
        lo = int(np.floor(centres[b - 1])) if b > 0 else 0
        hi = int(np.ceil(centres[b + 1])) + 1 if b + 1 < len(centres) else n
        seg = x[..., lo:hi] * _hat_weight(b, lo, hi, centres)
        if not np.any(seg):
            continue
        h = rir_fn(src_room[b])
        # (text raised numpy's ValueError, NaN made a NaN recording without a word)
        if not real_entries(h):
            raise GeometryError(f"rir_fn must return (n_mics, L) impulse responses (numbers), "
                                f"got {type(h).__name__}")
        h = np.atleast_2d(np.asarray(h, dtype=float))
        if h.ndim != 2 or h.shape[0] != n_mics or h.shape[1] == 0:
            raise GeometryError(f"rir_fn returned responses of shape {h.shape} for {n_mics} mics "
                                f"(expected ({n_mics}, L) with L >= 1)")
        if not np.all(np.isfinite(h)):
            raise GeometryError("rir_fn returned NaN or infinite samples")
        y = ss.fftconvolve(seg[..., None, :], h if seg.ndim == 1 else h[None], axes=-1)
        stop = min(n, lo + y.shape[-1])
        out[..., lo:stop] += y[..., : stop - lo]
    if tick is not None:
        tick(len(centres), len(centres))


def _announce(progress: Progress | None, stages: list[tuple[str, int]]) -> None:
    """Report every stage (name, total steps) with nothing done yet, before any work."""
    if progress is not None:
        for stage, total in stages:
            progress(stage, 0, total)


def _render_stages(x: NDArray, parts: list[tuple[Callable[[NDArray], NDArray], NDArray, str]],
                   trajectory: Trajectory, at: NDArray, fs: float, out: NDArray,
                   progress: Progress | None) -> None:
    """:func:`_render_blocks` for each (responses, update times, stage name) of ``parts``,
    the source at ``trajectory`` (array frame) + ``at`` (the array origin in the room),
    reporting each update to ``progress``."""
    for fn, centres, stage in parts:
        tick = None if progress is None else (
            lambda done, total, stage=stage: progress(stage, done, total))
        _render_blocks(x, centres, trajectory.at(centres / fs) + at, fn, out, tick)


def simulate_moving_masked_room(
    signal: ArrayLike,
    fs: float,
    array: Any,
    trajectory: Trajectory,
    room_dim: ArrayLike,
    rt60: float,
    array_at: ArrayLike,
    snr_db: float | None = None,
    rng: np.random.Generator | int | None = None,
    block_s: float = 0.05,
    max_order: int | None = None,
    early_order: int | None = EARLY_ORDER,
    early_block_s: float = EARLY_BLOCK_S,
    direct_block_s: float = MASKED_BLOCK_S,
    progress: Progress | None = None,
) -> NDArray:
    """Record a source moving along ``trajectory`` through a masked two-microphone array
    standing in a shoebox room (head fixed, the array axes parallel to the room's): ch. 3's
    mask, ch. 5's moving sources, in a room.

    The moving counterpart of :func:`hearsee.audio.mask.simulate_masked_room`, put together
    from the two renderers it joins:

    * the direct path as :func:`simulate_moving_masked` renders it (the mask's diffraction
      for the position each ``direct_block_s`` block is emitted from, overlap-added);
    * the reflections (:func:`hearsee.audio.mask.masked_room_reflections`: pyroomacoustics'
      image sources through the mask's far-field responses, the late ones diffusely) as
      :func:`simulate_moving_room` renders a room: responses for the source's position at
      update times, crossfaded by triangular weights -- the images up to ``early_order``
      reflections every ``early_block_s`` seconds, the rest every ``block_s`` (that split,
      and why: :func:`simulate_moving_room`'s ``early_order``). The direct path, rendered
      apart, needs none of that function's TDOA or delay bounds.

    For a still source its reflections equal those of
    :func:`~hearsee.audio.mask.simulate_masked_room` to rounding, and its direct path that of
    :func:`~hearsee.audio.mask.simulate_masked` to -79 dB (the static room's, an impulse
    response's rendering cut at time 0, differs from both by -56 dB). Cost: the reflections'
    responses take ~0.01 s (orders 1-3) and ~0.8 s (the rest, a 6 x 5 x 3.2 m room of RT60
    0.3 s; ~1.3 s at 0.6 s) per update, ~18 s per second of recording at the default
    ``block_s``: several signals along one path (``signal`` (k, n)) share them.
    Reconstruction beyond the thesis, which recorded its moving speakers.

    Parameters
    ----------
    signal : array (n,) or (k, n)
        Source waveform (at 1 m), sample 0 emitted at t = 0 s; k waveforms are k recordings
        of the same path (each with its own sensor noise drawn from ``rng`` in turn).
    fs : float
        Sample rate, Hz.
    array : MicArray, preset name, path or MaskModel
        A masked two-microphone array (e.g. ``"mask2-asym"``).
    trajectory : Trajectory
        Source path in the ARRAY frame (seconds, metres).
    room_dim, rt60, array_at, max_order
        The room as :func:`hearsee.audio.mask.simulate_masked_room` (metres, seconds; the
        array origin in room coordinates).
    snr_db : float, optional
        Per-channel SNR of added white sensor noise.
    block_s, early_order, early_block_s : float, int or None, float
        The reflections' update spacings, seconds, and the order that splits them (None:
        all reflections every ``block_s``).
    direct_block_s : float
        The direct path's block length, seconds (:func:`simulate_moving_masked`).
    progress : callable, optional
        ``progress(stage, done, total)`` as the work goes (:data:`Progress`): the direct
        path's blocks (of every waveform), then the early and the later reflections' updates.

    Returns
    -------
    array (2, n), or (k, 2, n) for k waveforms
    """
    from hearsee.audio.mask import MaskModel, masked_room_reflections
    from hearsee.audio.propagation import _check_inside, _room_dim, image_sources

    x = as_samples(signal, "signal")
    many = x.ndim == 2
    if x.ndim not in (1, 2) or x.size == 0:
        raise AudioInputError(f"signal must be a non-empty (n,) or (k, n) array, got shape "
                              f"{x.shape}")
    fs = float(check_fs(fs))
    check_rng(rng)  # (before the work: add_noise draws from it at the end)
    # (one generator for every waveform: a seed handed to add_noise per waveform gave each
    # the same noise)
    rng = np.random.default_rng(rng)
    snr_db = check_snr_db(snr_db)
    _check_trajectory(trajectory)
    early_order = _check_updates(block_s, early_block_s, early_order)
    progress = _check_progress(progress)
    hop, n_direct = _masked_blocks(x.shape[-1], fs, direct_block_s)
    model = array if isinstance(array, MaskModel) else MaskModel(array)
    at = as_point(array_at, "array_at")
    dim = _room_dim(room_dim)
    order = image_sources(rt60, dim, model.c, max_order)[1]

    def reflections(lo: int, hi: int | None) -> Callable[[NDArray], NDArray]:
        def fn(src_room: NDArray) -> NDArray:
            return masked_room_reflections(fs, model, src_room - at, dim, rt60, at, max_order,
                                           (lo, hi))  # (never None: each range holds orders)
        return fn

    updates = []  # (responses, update times in samples, progress stage)
    if order > 0:
        if early_order is not None and 0 < early_order < order:
            parts = [(reflections(1, early_order), early_block_s,
                      _orders_stage("early reflections", 1, early_order)),
                     (reflections(early_order + 1, None), block_s,
                      _orders_stage("later reflections", early_order + 1, order))]
        else:
            parts = [(reflections(1, None), block_s, _orders_stage("reflections", 1, order))]
        updates = [(fn, _update_times(trajectory, model.array.positions, model.c, fs,
                                      x.shape[-1], spacing, None), stage)
                   for fn, spacing, stage in parts]
    # the room's checks before any rendering (they came with the first reflections, after
    # the whole direct path): the mask inside the room, the talker wherever it is heard (at
    # the reflections' updates; an anechoic room has none, and took a walk through its walls
    # and a mask outside it without a word: there at the direct path's blocks)
    _check_inside(model.mesh.vertices + at, dim, "the mask's vertex")
    t = (np.concatenate([centres for _, centres, _ in updates]) / fs if updates
         else np.arange(n_direct) * hop / fs)
    pos = trajectory.at(t) + at
    k = int(np.argmin(np.minimum(pos, dim - pos).min(axis=1)))  # (the nearest a wall)
    _check_inside(pos[k:k + 1], dim, f"the source (t = {t[k]:.3g} s)")
    xs = np.atleast_2d(x)
    _announce(progress, [(_masked_stage(direct_block_s), len(xs) * n_direct)]
              + [(stage, len(centres)) for _, centres, stage in updates])
    out = np.stack([simulate_moving_masked(
        s, fs, model, trajectory, block_s=direct_block_s,
        progress=None if progress is None else (  # (waveform i's blocks after the others')
            lambda stage, done, total, i=i: progress(stage, i * total + done, len(xs) * total)))
        for i, s in enumerate(xs)])
    _render_stages(xs, updates, trajectory, at, fs, out, progress)
    out = np.stack([add_noise(y, snr_db, rng) for y in out])
    return out if many else out[0]


# ---------------------------------------------------------------------------- recordings
def mask_itd_track(array: Any, trajectory: Trajectory, duration_s: float,
                   step_s: float = 0.01) -> dict[str, list[float]]:
    """A masked array's ITD through a moving source's recording: ``{"t": [...], "0-1":
    [...]}`` (seconds) at :func:`truth_times` (every ``step_s``, the trajectory's corners and
    the recording's end), each the mask's ITD
    (:meth:`hearsee.audio.mask.MaskModel.itd_at`: what the masked pair measures) of the
    position heard at the array's origin at that time (:meth:`Trajectory.heard_at`, r / c
    earlier) -- the truth of ``hearsee localize``'s per-frame ITDs (frame times are the
    frames' centres). ``array``: a masked array (MicArray, preset name, path) or its
    :class:`~hearsee.audio.mask.MaskModel`, as :func:`simulate_moving_masked` takes it."""
    from hearsee.audio.mask import MaskModel

    model = array if isinstance(array, MaskModel) else MaskModel(array)
    t = truth_times(trajectory, duration_s, step_s)
    heard = trajectory.heard_at(t, speed_of_sound=model.array.speed_of_sound)
    return {"t": t.tolist(),
            model.array.pair_labels[0]: [float(v) for v in model.itd_at(heard)]}


def simulate_moving_recording(
    array: MicArray | str | Path,
    trajectory: Trajectory,
    signal: str | Path = "noise",
    duration_s: float | None = None,
    fs: float = 16000,
    snr_db: float | None = None,
    room: dict | None = None,
    seed: int | None = 0,
    block_s: float = 0.05,
    progress: Progress | None = None,
) -> tuple[NDArray, dict]:
    """Simulate a recording of a source moving along ``trajectory`` (array frame), with truth.

    The moving-source counterpart of :func:`hearsee.sim.audio.simulate_recording` (same
    ``signal``, ``room``, ``snr_db`` and ``seed`` conventions): free field by
    :func:`simulate_moving_free_field`, rooms by :func:`simulate_moving_room`, a masked array
    by :func:`simulate_moving_masked` (refused until 2026-12-04) and in a room by
    :func:`simulate_moving_masked_room` (refused until 2026-12-05).
    ``duration_s`` defaults to the trajectory's end time. ``progress(stage, done, total)``
    (:data:`Progress`) follows the renderer's stages.

    Returns
    -------
    x : array (n_mics, n)
    truth : dict
        As :func:`hearsee.sim.audio.ground_truth` for the position at t = 0 (``source_m``,
        ``azimuth_deg``, ...), plus ``moving: True``, ``trajectory`` ({"t": [...],
        "positions_m": [[x, y, z], ...]} knots), ``fs``, ``duration_s``, ``array``, ``signal``,
        ``snr_db``, ``room``, ``seed``; a masked array adds ``mask_itd_track``
        (:func:`mask_itd_track`: the mask's ITD through the recording, which ``mask_itd_s``
        gives at t = 0 only).
    """
    from hearsee.audio.arrays import load_array
    from hearsee.audio.signals import SIGNAL_KINDS, make_signal
    from hearsee.sim.audio import check_sim_fs, ground_truth, normalize_room

    arr = load_array(array)
    _check_trajectory(trajectory)
    # (a list raised float()'s TypeError and the text "0.1" was read as 0.1 s, which the
    # static simulate_recording refuses)
    if duration_s is not None and not is_real(duration_s):
        raise ConfigError(f"duration must be a number of seconds, got {duration_s!r:.60}")
    dur = float(trajectory.t[-1]) if duration_s is None else float(duration_s)
    if not dur > 0:
        # (the hint blamed "a one-point trajectory" whatever the trajectory; what gives no
        # default is one that ends at or before t = 0, the recording's start; 2026-12-02)
        raise ConfigError(
            f"duration must be > 0 s, got {dur:g} s" if duration_s is not None else
            f"the trajectory ends at t = {dur:g} s, at or before the recording's start (t = 0, "
            "its first sample), so it gives no default duration: give one, or times from 0 s")
    if seed is not None:  # (-1 or 1.5 raised numpy's ValueError / TypeError)
        seed = whole_number("seed", seed, lo=0)
    progress = _check_progress(progress)
    fs = check_sim_fs(fs)
    snr_db = check_snr_db(snr_db)  # (before the simulation: add_noise checks it at its end)
    room_n = normalize_room(room)
    rng = np.random.default_rng(seed)
    s = make_signal(signal, dur, fs, rng)
    model = None
    if arr.mask is not None:  # the mask's diffraction, block-wise
        from hearsee.audio.mask import MaskModel

        model = MaskModel(arr)  # (one model for the rendering and the ITD track)
        if room_n is None:
            clean = simulate_moving_masked(s, fs, model, trajectory, progress=progress)
        else:
            clean = simulate_moving_masked_room(s, fs, model, trajectory, room_n["room_dim"],
                                                room_n["rt60"], room_n["array_at"],
                                                block_s=block_s,
                                                max_order=room_n.get("max_order"),
                                                progress=progress)
    elif room_n is None:
        clean = simulate_moving_free_field(s, fs, arr, trajectory, progress=progress)
    else:
        clean = simulate_moving_room(s, fs, arr, trajectory, room_n["room_dim"], room_n["rt60"],
                                     room_n["array_at"], block_s=block_s,
                                     max_order=room_n.get("max_order"), progress=progress)
    x = add_noise(clean, snr_db, rng)
    truth = ground_truth(arr, trajectory.at(0.0))  # (a masked array's ITD: at t = 0)
    if model is not None:
        truth["mask_itd_track"] = mask_itd_track(model, trajectory, dur)
    truth.update({
        "moving": True,
        "trajectory": {"t": trajectory.t.tolist(), "positions_m": trajectory.positions.tolist()},
        "fs": fs,
        "duration_s": dur,
        "array": arr.to_dict(),
        "signal": str(signal) if str(signal) in SIGNAL_KINDS else str(Path(signal)),
        "snr_db": None if snr_db is None else float(snr_db),
        "room": room_n,
        "seed": seed,
    })
    return x, truth
