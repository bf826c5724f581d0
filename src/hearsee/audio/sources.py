"""Several talkers at once: the directions of a recording's frames, clustered.

hearsee's whole-recording summary (:func:`hearsee.audio.localize.localize_recording`) names
one source. Two people talking in turn or over each other are two sources; subspace methods
need more microphones than sources (a pair cannot take two, a triangle barely), and a steered
response over the whole recording lets the louder source's sidelobes hide the other. Speech
is sparse in time and frequency (Rickard & Yilmaz 2002, "On the approximate W-disjoint
orthogonality of speech", ICASSP): most short frames are dominated by one talker, so each
frame's GCC peak points at one of them, and the frames' directions pile up at the sources.
This module finds those piles -- a kernel density of the frames' azimuths, its highest maxima
taken greedily at least ``min_separation_deg`` apart (mean shift, Comaniciu & Meer 2002,
"Mean shift: a robust approach toward feature space analysis", IEEE TPAMI 24(5), for each
maximum's position), as the time-frequency clustering of Araki et al. 2007 ("Underdetermined
blind sparse source separation for arbitrarily arranged multiple sensors", Signal Processing
87(8)) does per bin, here per frame. Not in the thesis (its chapter 5 tracks one speaker
with an interfering source); an extension.

Azimuths are degrees in the array frame (from +x toward +y). A two-microphone array's frames
carry the front/back twin of their cone (:func:`~hearsee.audio.localize.localize_tdoa`):
the sine of their angle from broadside, the same for both twins and proportional to the
TDOA, is clustered instead, and two talkers mirrored about the pair's axis are one source to
it.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hearsee.config import (
    all_real,
    as_float_array,
    check_settings,
    finite_number,
    is_real,
    object_entries,
    true_or_false,
    whole_number,
)
from hearsee.errors import ConfigError
from hearsee.geometry import MAX_ANGLE_DEG, unit_vector_deg, wrap_deg

#: the most sources :func:`direction_clusters` looks for (``hearsee localize --sources``)
MAX_SOURCES = 8
#: width (standard deviation, degrees) of the Gaussian kernel of the frames' azimuth density:
#: of the order of the frames' spread around a talker (``spread_deg`` 2.5 and 4.2 deg for two
#: talkers 1.5 m from the three-mic preset in a 6 x 5 x 3 m room of RT60 0.3 s, 64-ms frames)
DEFAULT_BANDWIDTH_DEG = 4.0
#: two sources closer than this (degrees) are one
DEFAULT_MIN_SEPARATION_DEG = 20.0
#: a pile of frames holding less than this share of the located frames' weight is not a
#: source (a reflection's, or chance's). Chosen on dev seed 257 (scratch, 2026-12-06; 12
#: recordings per cell of one or two talkers 1-2.5 m away, synthetic voices, 3 s, 20 dB,
#: three-mic and two-mic presets, free field and RT60 0.3 / 0.6 s rooms): 0.1 / 0.15 / 0.2 found
#: the one talker of a three-mic RT60 0.6 s recording alone in 75 / 83 / 83 % and both of two
#: in 83 / 83 / 67 %; weighting the frames by their GCC confidence changed nothing that held.
#: Re-checked once merged maxima were dropped (dev seeds 264 / 265, 20 / 30 per cell): 0.12
#: found both of two talkers in up to one recording more per cell and named a lone talker
#: alone in up to three fewer (seed 265: three-mic RT60 0.6 s 97 -> 87 %, two-mic RT60 0.3 s
#: 83 -> 73 %)
DEFAULT_MIN_SHARE = 0.15
#: the density's grid step (degrees)
_GRID_DEG = 0.5


@dataclass(frozen=True)
class DirectionCluster:
    """One pile of frame directions: a source.

    angle_deg : float
        Weighted circular mean of its frames' angles, degrees in ``(-180, 180]``.
    share : float
        Its frames' share of the weight of all the frames given (0-1).
    n_frames : int
        How many frames it holds.
    spread_deg : float
        Weighted circular standard deviation of its frames' angles, degrees.
    frames : array of int
        Indices (into the angles given) of its frames.
    """

    angle_deg: float
    share: float
    n_frames: int
    spread_deg: float
    frames: NDArray


def _circular_mean(az: NDArray, w: NDArray) -> tuple[float, float]:
    """Weighted circular mean and standard deviation (degrees) of azimuths ``az``."""
    z = np.sum(w * np.exp(1j * np.radians(az))) / np.sum(w)
    r = min(float(abs(z)), 1.0)
    # (max: log(1.0) is -0.0 for one frame, and the JSON said "spread_deg": -0.0)
    std = float(np.degrees(np.sqrt(max(0.0, -2.0 * np.log(r))))) if r > 0 else 180.0
    return float(wrap_deg(np.degrees(np.angle(z)))), std


def direction_clusters(angle_deg: ArrayLike, weight: ArrayLike | None = None,
                       max_sources: int = 2, *,
                       bandwidth_deg: float = DEFAULT_BANDWIDTH_DEG,
                       min_separation_deg: float = DEFAULT_MIN_SEPARATION_DEG,
                       min_share: float = DEFAULT_MIN_SHARE) -> list[DirectionCluster]:
    """The sources among frame directions: up to ``max_sources`` piles, the largest share first.

    The frames' angles (degrees on a circle: azimuths -- :func:`localize_sources` gives a
    linear array's sines of the angle from broadside times 90; ``weight`` >= 0 per frame,
    default 1) are binned on a 0.5-deg circle and smoothed by a Gaussian of
    ``bandwidth_deg``; its highest maximum is a source, the density within
    ``min_separation_deg`` of it is set aside, and so on. Each maximum moves to the weighted
    circular mean of the frames within half of ``min_separation_deg`` of it until it settles
    (at most 20 steps; of two that come closer than ``min_separation_deg`` the lower is
    dropped); the ``max_sources`` highest remaining are the sources, each frame joins the
    nearest within that radius (farther frames -- reflections, noise -- join none), and a
    source's angle is its frames' weighted circular mean. Sources
    holding less than ``min_share`` of the total weight are dropped (all of them, when the
    frames scatter: an empty list).

    Raises ConfigError for non-finite angles, negative or non-finite weights, or settings
    outside their ranges (``max_sources`` 1 to :data:`MAX_SOURCES`, ``bandwidth_deg`` in (0,
    45], ``min_separation_deg`` in [``bandwidth_deg``, 180], ``min_share`` in [0, 1)).
    """
    max_sources = whole_number("max_sources", max_sources, 1, MAX_SOURCES)
    bw = finite_number("bandwidth_deg", bandwidth_deg, 0.0, 45.0, lo_open=True)
    sep = finite_number("min_separation_deg", min_separation_deg, bw, 180.0)
    min_share = finite_number("min_share", min_share, 0.0, 1.0)
    if min_share >= 1.0:
        raise ConfigError(f"min_share must be below 1 (a share of the frames), got {min_share}")
    az = as_float_array(angle_deg, "angle_deg", finite=False)
    if az.ndim != 1 or not np.all(np.isfinite(az)):
        raise ConfigError("angle_deg must be a 1-D array of finite degrees, one per frame")
    w = np.ones_like(az) if weight is None else as_float_array(weight, "weight", finite=False)
    if w.shape != az.shape or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ConfigError("weight must hold one finite number >= 0 per angle")
    total = float(w.sum())
    if total <= 0:
        return []
    n_grid = int(round(360.0 / _GRID_DEG))
    grid = np.arange(n_grid) * _GRID_DEG
    hist = np.bincount(np.round(az % 360.0 / _GRID_DEG).astype(int) % n_grid, weights=w,
                       minlength=n_grid)
    d = wrap_deg(grid)  # (the kernel's offsets on the circle)
    kernel = np.exp(-0.5 * (d / bw) ** 2)
    density = np.fft.irfft(np.fft.rfft(hist) * np.fft.rfft(kernel), n_grid)
    peaks: list[float] = []
    left = density.copy()
    # (every maximum, not only max_sources of them: one that the shifts merge into another is
    # replaced by the next -- a second talker beside a broad pile was missed with two asked
    # for and found with three)
    for _ in range(MAX_SOURCES):
        g = int(np.argmax(left))
        if left[g] <= 1e-9 * total:
            break
        peaks.append(float(grid[g]))
        left[np.abs(wrap_deg(grid - grid[g])) < sep] = 0.0
    radius = sep / 2.0
    clusters = []
    for _ in range(20):  # mean shift of every peak within its radius, until they settle
        moved = []
        for p in peaks:
            near = np.abs(wrap_deg(az - p)) < radius
            moved.append(_circular_mean(az[near], w[near])[0] if np.any(w[near] > 0) else p)
        done = all(abs(wrap_deg(a - b)) < 1e-6 for a, b in zip(moved, peaks, strict=True))
        peaks = moved
        if done:
            break
    kept: list[float] = []  # (two maxima the shifts brought within min_separation: one)
    for p in peaks:
        if all(abs(wrap_deg(p - q)) >= sep for q in kept):
            kept.append(p)
    peaks = kept[:max_sources]  # (the highest maxima first)
    if peaks:
        dist = np.abs(wrap_deg(az[:, None] - np.array(peaks)[None, :]))  # (frames, peaks)
        nearest = np.argmin(dist, axis=1)
        joined = dist[np.arange(len(az)), nearest] < radius
        for k in range(len(peaks)):
            idx = np.flatnonzero(joined & (nearest == k))
            share = float(w[idx].sum()) / total
            if not len(idx) or share < min_share or not np.any(w[idx] > 0):
                continue
            mean, spread = _circular_mean(az[idx], w[idx])
            clusters.append(DirectionCluster(mean, share, len(idx), spread, idx))
    return sorted(clusters, key=lambda c: -c.share)


def _from_broadside(cos_theta: float) -> tuple[float, float]:
    """A linear array's view of a frame whose cone about its axis has ``cos_theta`` (the
    cosine of its half angle, :func:`~hearsee.audio.localize.far_field_linear`), the same for
    every direction on that cone: its angle from broadside (degrees, -90 to 90) and that
    angle's sine times 90 -- proportional to the TDOA, whose errors are alike at every angle
    (an angle's grow toward the axis, where a frame's TDOA beyond the pair's reach reads as
    the axis itself and piled up 10-20 deg from a talker near it). Clustered in angles
    instead (dev seed 261, two-mic preset, 30 recordings per cell as bench/sources.py makes
    them): one talker named alone 100 / 70 / 30 % (free field, RT60 0.3 / 0.6 s) against
    100 / 83 / 30 % in sines, both of two talkers 90 / 57 / 17 % against 97 / 57 / 20 %."""
    c = float(np.clip(cos_theta, -1.0, 1.0))
    return float(np.degrees(np.arcsin(c))), 90.0 * c


def localize_sources(tdoa_s: ArrayLike, valid: ArrayLike, array: Any,
                     pairs: Sequence[tuple[int, int]], max_sources: int = 2, *,
                     in_plane: bool = False, weight: ArrayLike | None = None,
                     locs: Sequence[Any] | None = None,
                     **cluster_kwargs: Any) -> tuple[list[dict[str, Any]], NDArray]:
    """Up to ``max_sources`` sources of a recording from its frames' TDOAs.

    ``tdoa_s`` (n_frames, n_pairs) are the frames' own TDOAs in seconds
    (:attr:`hearsee.audio.tdoa.TdoaFrames.tdoa_s`; not smoothed over time: an ITD filter
    follows one source and takes the other's frames for outliers), ``valid`` (n_frames,)
    which hold a source. Each valid frame is localized
    (:func:`~hearsee.audio.localize.localize_tdoa`, ``in_plane`` as there), its azimuth (a
    linear array's: the sine of its cone's angle from broadside, times 90, whatever the
    axis) clustered by
    :func:`direction_clusters`
    (``weight`` per frame and ``cluster_kwargs`` passed on; ``locs``, one per frame with None
    for frames without, are the frames' localizations when the caller has them already, as
    :func:`~hearsee.audio.localize.localize_recording` does: not computed again), and each
    cluster localized again
    from its frames' median TDOA per pair: the source's azimuth, elevation and candidates as
    the array can tell them.

    Returns the sources, the largest share of frames first (``share``: of the weight of the
    frames that got a direction), as dicts ``{"azimuth_deg",
    "elevation_deg", "candidates": [{"azimuth_deg", "elevation_deg"}], "tdoa_s": {"i-j": s},
    "share", "n_frames", "spread_deg"}`` (the JSON's ``sources``), and each frame's source
    (n_frames,) -- its index in that list, -1 for none.
    """
    from hearsee.audio.arrays import load_array

    check_settings(direction_clusters, cluster_kwargs,
                   skip=("angle_deg", "weight", "max_sources"))
    tau, ok, w_all = _frame_inputs("localize_sources", tdoa_s, valid, pairs, weight, locs)
    arr = load_array(array)
    rows_a, angle, key = _frame_angles(tau, ok, arr, pairs, in_plane, locs)
    clusters = direction_clusters(key, w_all[rows_a], max_sources, **cluster_kwargs)
    which = np.full(len(tau), -1)
    sources = []
    for k, c in enumerate(clusters):
        frames = rows_a[c.frames]
        which[frames] = k
        sources.append({
            **_direction(np.median(tau[frames], axis=0), arr, pairs, in_plane),
            "share": c.share,
            "n_frames": c.n_frames,
            "spread_deg": _circular_mean(angle[c.frames], w_all[frames])[1],
        })
    return sources, which


def _frame_inputs(who: str, tdoa_s: ArrayLike, valid: ArrayLike,
                  pairs: Sequence[tuple[int, int]], weight: ArrayLike | None,
                  locs: Sequence[Any] | None) -> tuple[NDArray, NDArray, NDArray]:
    """:func:`localize_sources`' (and :func:`localize_moving_sources`') frame inputs checked:
    ``(tdoa_s (n_frames, n_pairs), valid (n_frames,) bool, weight (n_frames,))``."""
    tau = as_float_array(tdoa_s, "tdoa_s", finite=False)
    ok = np.asarray(valid)
    if ok.dtype != bool:  # (text or numbers read as bools: "no" was a valid frame)
        raise ConfigError(f"valid must hold one bool per frame, got {valid!r:.60}")
    if tau.ndim != 2 or ok.shape != (tau.shape[0],) or tau.shape[1] != len(pairs):
        raise ConfigError(f"{who} needs tdoa_s (n_frames, {len(pairs)}) and valid "
                          f"(n_frames,), got {tau.shape} and {ok.shape}")
    w_all = np.ones(len(tau)) if weight is None else as_float_array(weight, "weight",
                                                                         finite=False)
    if w_all.shape != ok.shape:
        raise ConfigError(f"weight must hold one number per frame ({len(ok)}), got shape "
                          f"{w_all.shape}")
    if locs is not None:
        from hearsee.audio.localize import Localization

        # (a number, 5, was len()'s builtin TypeError; [1, 1] a builtin AttributeError, 'int'
        # has no 'azimuth_deg')
        if not isinstance(locs, Sequence) or isinstance(locs, str):
            raise ConfigError(f"locs must be a list of one Localization (or None) per frame, "
                              f"got {locs!r:.60}")
        if len(locs) != len(tau):
            raise ConfigError(f"locs must hold one localization (or None) per frame "
                              f"({len(tau)}), got {len(locs)}")
        bad = [x for x in locs if x is not None and not isinstance(x, Localization)]
        if bad:
            raise ConfigError(f"locs must hold one Localization (or None) per frame, got "
                              f"{bad[0]!r:.60}")
    return tau, ok, w_all


def _frame_angles(tau: NDArray, ok: NDArray, arr: Any, pairs: Sequence[tuple[int, int]],
                  in_plane: bool, locs: Sequence[Any] | None
                  ) -> tuple[NDArray, NDArray, NDArray]:
    """The frames that get a direction (their indices), their angles (deg: azimuths, or a
    linear array's angles from broadside) and what is clustered or tracked of them (the
    azimuths, or a linear array's sines of that angle times 90: :func:`_from_broadside`)."""
    from hearsee.audio.localize import array_geometry, localize_tdoa

    geo = array_geometry(arr)
    near = bool(in_plane) and geo.kind == "planar"  # (as localize_recording's frames)
    rows, angle, key = [], [], []
    for n in np.flatnonzero(ok & np.all(np.isfinite(tau), axis=1)):
        loc = (localize_tdoa(tau[n], arr, pairs, near_field=near, in_plane=in_plane)
               if locs is None else locs[n])
        ak = frame_angle(loc, geo.kind == "linear")
        if ak is None:
            continue
        a, k = ak
        rows.append(n)
        angle.append(a)
        key.append(k)
    return np.array(rows, dtype=int), np.array(angle, dtype=float), np.array(key, dtype=float)


def frame_angle(loc: Any, linear: bool) -> tuple[float, float] | None:
    """A frame's localization ``loc`` (:class:`~hearsee.audio.localize.Localization`, or
    None) as ``(angle, key)`` in degrees -- its azimuth twice, or a ``linear`` array's angle
    from broadside and what is clustered or tracked of it (:func:`_from_broadside`) -- or
    None when it gives no direction."""
    if loc is None:
        return None
    if linear:  # (any axis: a vertical one has no azimuth, a tilted one puts every cone
        # that misses the horizontal plane on its own azimuth)
        return _from_broadside(loc.extra["cos_theta"])
    if loc.azimuth_deg is not None and np.isfinite(loc.azimuth_deg):
        return loc.azimuth_deg, loc.azimuth_deg
    return None


def linear_design(arr: Any, pairs: Sequence[tuple[int, int]]) -> NDArray:
    """A linear array's pair TDOAs (s) per unit of the cosine of a source's angle from the
    array's axis (the cone that :func:`linear_azimuth` turns a tracked key back into)."""
    from hearsee.audio.localize import _design, array_geometry

    return _design(arr, list(pairs)) @ array_geometry(arr).axis


def linear_azimuth(key: float, design: NDArray, arr: Any, pairs: Sequence[tuple[int, int]],
                   prev: float | None) -> float | None:
    """A linear array's azimuth (degrees) for a tracked ``key`` (its angle's sine from
    broadside times 90): the cone's twin in front (|azimuth| < 90) where there is one, else
    the one nearest ``prev`` (the track's last azimuth; the first twin without one) -- an
    x-axis pair's twins are +-a, and the tie between them was broken by rounding, which
    flipped a path's sign from frame to frame; None where the cone has no azimuth (a
    vertical pair). ``design`` is :func:`linear_design`'s."""
    from hearsee.audio.localize import localize_tdoa

    loc = localize_tdoa(design * np.clip(key / 90.0, -1.0, 1.0), arr, pairs)
    azs = [c[0] for c in loc.candidates if c[0] is not None]
    front = [a for a in azs if abs(a) < 90.0 - 1e-6]
    if not azs:
        return None
    if len(front) == 1 or prev is None:
        return front[0] if len(front) == 1 else azs[0]
    return min(azs, key=lambda a: abs(float(wrap_deg(a - prev))))


def _direction(tau: NDArray, arr: Any, pairs: Sequence[tuple[int, int]], in_plane: bool
               ) -> dict[str, Any]:
    """A source's JSON direction entries from its pair TDOAs ``tau`` (s)."""
    from hearsee.audio.localize import localize_tdoa

    loc = localize_tdoa(tau, arr, pairs, in_plane=in_plane)
    return {"azimuth_deg": loc.azimuth_deg, "elevation_deg": loc.elevation_deg,
            "candidates": loc.to_dict()["candidates"],
            "tdoa_s": {f"{i}-{j}": float(v) for (i, j), v in zip(pairs, tau, strict=True)}}


def sources_from_spectra(sources: list[dict[str, Any]], which: NDArray,
                         estimate: Callable[[NDArray], Any], array: Any,
                         pairs: Sequence[tuple[int, int]], in_plane: bool = False
                         ) -> list[dict[str, Any]]:
    """:func:`localize_sources`' sources again, each from the cross-spectra of its own frames
    averaged: ``estimate(active)`` is the recording's
    :func:`~hearsee.audio.tdoa.estimate_tdoas` with only the frames ``active`` (n_frames,)
    bool, whose whole-recording TDOAs give the direction (a source whose frames give none
    keeps its median one). What :func:`~hearsee.audio.localize.localize_recording` does for
    linear arrays: on dev seeds 262 and 263 (two-mic preset, two talkers as bench/sources.py
    makes them, 30 per cell) both talkers were found within 10 deg in 57 / 30 and 43 / 20 %
    of the recordings at RT60 0.3 / 0.6 s from the frames' median TDOAs, in 70 / 50 and 57 /
    30 % this way (free field: equal); for the three-mic preset it lost at RT60 0.6 s (77 ->
    63 %, seed 262), which keeps the median TDOAs. Each estimate's warnings are those the
    whole recording's run told already: not told again."""
    out = []
    for k, src in enumerate(sources):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tau = estimate(np.asarray(which) == k).summary_tdoa_s
        out.append({**src, **_direction(tau, array, pairs, in_plane)}
                   if np.all(np.isfinite(tau)) else src)
    return out


def merge_repeated_sources(sources: list[dict[str, Any]], which: NDArray,
                           frame_angle_deg: ArrayLike, array: Any, pairs: Sequence[tuple[int, int]],
                           min_separation_deg: float = DEFAULT_MIN_SEPARATION_DEG
                           ) -> tuple[list[dict[str, Any]], NDArray]:
    """:func:`sources_from_spectra`' sources with those that came out as one direction merged:
    two piles of a linear array's frames (at least ``min_separation_deg`` apart, as
    :func:`direction_clusters` finds them) whose averaged spectra both name one talker -- one
    pile his direct path's, the other his reflections' -- were two sources within a degree of
    each other (two-mic preset, one talker in a room of RT60 0.6 s: 36.1 and 34.9 deg with 58
    and 21 % of the frames). A source whose key (its angle's sine from broadside times 90, as
    clustered) lies within ``min_separation_deg`` of a larger one's joins it: its frames and
    share are added to it, its ``spread_deg`` is its frames' (``frame_angle_deg``, the angle
    from broadside of each frame, NaN for none), its direction stays the larger one's. Returns
    the sources and each frame's source (``which`` renumbered, -1 for none)."""
    from hearsee.audio.localize import localize_tdoa

    w = np.asarray(which)
    ang = np.asarray(frame_angle_deg, dtype=float)
    keys = []
    for src in sources:
        tau = np.array([src["tdoa_s"][f"{i}-{j}"] for i, j in pairs], dtype=float)
        loc = localize_tdoa(tau, array, pairs) if np.all(np.isfinite(tau)) else None
        ak = frame_angle(loc, True) if loc is not None and "cos_theta" in loc.extra else None
        keys.append(None if ak is None else ak[1])
    kept: list[int] = []
    into = {}
    for k, key in enumerate(keys):  # (the largest share first)
        home = next((j for j in kept if key is not None and keys[j] is not None
                     and abs(key - keys[j]) < min_separation_deg), None)
        if home is None:
            kept.append(k)
            into[k] = k
        else:
            into[k] = home
    if len(kept) == len(sources):
        return sources, w
    out, new_which = [], np.full(len(w), -1)
    for n, j in enumerate(kept):
        members = [k for k, h in into.items() if h == j]
        frames = np.flatnonzero(np.isin(w, members))
        new_which[frames] = n
        merged = {**sources[j], "share": float(sum(sources[k]["share"] for k in members)),
                  "n_frames": int(sum(sources[k]["n_frames"] for k in members))}
        a = ang[frames]
        a = a[np.isfinite(a)]
        if len(members) > 1 and a.size:
            merged["spread_deg"] = _circular_mean(a, np.ones_like(a))[1]
        out.append(merged)
    return out, new_which


# -- moving talkers ------------------------------------------------------------------------
#: :func:`track_sources`' defaults, chosen on dev recordings (seeds 270-273 of
#: bench/moving_sources.py, scratch, 2026-12-06: 20 recordings x 10 moments per array, room and
#: signal cell; the mean over the 8 cells of "both talkers within 10 deg", 67.8 % with 4 deg,
#: 20 deg/s^2, 15 deg, 4 frames, 3 s, 0.5 s and 0.05 before the chance test, each changed
#: alone). A frame's direction noise, degrees: 3 / 6 / 8 deg gave 63.9 / 68.9 / 68.0 %.
TRACK_SIGMA_MEAS_DEG = 6.0
#: the tracks' angular acceleration noise, deg/s^2: a talker walking at 1.5 m/s 1 m away turns
#: at up to 86 deg/s, but over seconds, and a track must coast through the other talker's
#: turns without drifting onto them (10 / 40 / 80 deg/s^2: 64.6 / 66.2 / 62.9 %)
TRACK_ACCEL_DPS2 = 20.0
#: a frame joins no track whose predicted angle is farther than this (degrees), however
#: uncertain the track: a track that coasted through a pause widens its gate, and took the
#: frames between two talkers (or the other talker's); with the chance test 10 / 20 / 25 deg
#: gave 58.4 / 60.6 / 48.5 % against 65.4 %
TRACK_MAX_JUMP_DEG = 15.0
#: a new track's angular rate spread, deg/s (a talker walking at 1 m/s 2 m away: <= 29 deg/s)
TRACK_INIT_RATE_DPS = 30.0
#: the tracks' angular rates relax toward zero with this time constant (s; ``rate_tau_s``,
#: None = constant rate): :data:`hearsee.audio.tracking.DIRECTION_RATE_TAU_S`'s value, which
#: the offline tracks took from it before the setting existed (a test holds the two equal)
TRACK_RATE_TAU_S = 2.0
#: a new track is a source once this many frames joined it (3 / 6: 67.9 / 65.8 %)
TRACK_CONFIRM_HITS = 4
#: a track that is not yet a source ends after this long (s) without a frame (0.3 / 1 s:
#: 66.8 / 67.3 %)
TRACK_TENTATIVE_S = 0.5
#: a source's track ends after this long (s) without a frame, a talker's pause (1.5 / 5 s:
#: 66.3 / 67.8 %)
TRACK_MAX_COAST_S = 3.0
#: a track holding less than this share of the located frames' weight is not reported, a
#: reflection's or a fragment of a talker's (0.02 / 0.1: 68.1 / 66.8 %)
TRACK_MIN_SHARE = 0.05
#: a track is not reported when frames scattered at random over the angles would put as many
#: frames in its gate (``max_jump_deg`` either side) during its life (first to last frame)
#: with at least this probability (binomial; each frame that joins no track starts one, so
#: the bar is low). Scattered frames (190 frames of 32 ms, every one or half of them located,
#: 100 trials each) gathered into a reported track in 64 % of the trials under a bar of 20 %
#: of the frames of its life, in 0-3 % under this one (10 % with 1e-3); on the dev recordings
#: it cost the two-mic preset (mean over all cells 68.9 -> 65.4 %; 67.0 % with 1e-3), whose
#: angles span 180 deg, where a gate is twice the chance
TRACK_MAX_CHANCE = 1e-4
#: two sources whose paths are closer than this (degrees) at half or more of the frames both
#: lived through (the median distance) are one talker, reported as one (added 2026-12-07;
#: ``merge_deg=0`` disables it): in a room one talker's frames, pulled apart by its
#: reflections, had split between two tracks that ran side by side for seconds, both holding
#: a large share, and the walker alone was reported as two talkers (two tracks of one target:
#: track-to-track association, Bar-Shalom & Li 1995); the still talkers' clustering
#: keeps its peaks 20 deg apart too (:data:`DEFAULT_MIN_SEPARATION_DEG`). The heaviest
#: source first, each joins the first heavier one within the bar; the merged track's angle is
#: the heavier's wherever that one lived. Dev (seeds 281-282 of bench/moving_sources.py's
#: scenes, scratch, 10 recordings x 10 moments per array, room and signal cell; 8-cell means):
#: a false second track beside the lone walker at 10.2 -> 2.5 % of the moments, the walker
#: alone and within 10 deg 85.9 -> 91.4 %, both talkers within 10 deg 63.0 -> 64.4 % (a
#: duplicate no longer fills the second place); the largest distance over the frames both
#: lived through instead of the median, 20 / 25 deg: 8.4 / 5.9 % false; the median at 25 / 30
#: deg: 1.8 / 0.8 % false, both talkers 64.6 / 64.8 %, but two talkers standing closer than that
#: would be one (the scenes keep theirs 30 deg apart). Held out (seeds 293-294, the rule fixed
#: before they were scored): false second track 10.8 -> 2.4 %, the walker alone within 10 deg
#: 85.2 -> 90.7 %, both talkers 64.8 -> 65.2 %, no cell worse. Online (:class:`SourceTracker`, which
#: cannot wait for the paths) the same bar at each frame: a source is not named while its
#: angle is closer than this to one named before it, the heavier by recent weight. The
#: stream's frames of the same scenes: dev, false second talker 1.7 -> 0.5 %, the walker alone
#: 94.4 -> 95.4 %, both talkers 65.2 -> 65.3 %; held out (293-294, fixed before scored):
#: 3.2 -> 0.9 %, 92.2 -> 94.0 %, both talkers 64.1 % unchanged in every cell.
TRACK_MERGE_DEG = 20.0
#: ... and only while the two paths keep their distance: over the frames both lived through,
#: the spread of their signed difference (its 90th minus its 10th percentile, degrees) must
#: be below this (added 2026-12-07, ``merge_spread_deg``). A walker crossing a still talker
#: gives two tracks that close in on each other and part: the median distance alone had
#: merged them, and the still talker went unreported for seconds (one talker's split tracks
#: run side by side, their difference roughly constant; a track that broke and its
#: successor, which share few frames, still merge). Dev (scratch: seed 400, a walker crossing
#: a still talker's direction mid-recording, 10 recordings per array and room, moments at
#: least 0.6 s from the crossing): both talkers within 10 deg 30.4 -> 36.1 % (no merging:
#: 38.9), the still talker found 74.6 -> 76.8 % (80.0); bench/moving_sources.py's scenes
#: (seeds 281-282): false second track beside the lone walker 2.5 -> 2.9 %, the walker alone
#: 91.4 -> 91.2 %, both talkers 64.4 % unchanged. 15 deg was tried first (crossing 38.6 /
#: 77.1 %, false second 3.8 %): held out (seeds 401 crossing, 295 the bench's scenes) the
#: crossing gained as much (both 23.6 -> 35.4 %) but the false second track rose 2.2 -> 4.4 %,
#: beyond the +2 points allowed by the rule written before that run. 20 deg, held out on
#: fresh seeds (402 crossing, 296 the bench's scenes; the same rule): both talkers within 10
#: deg 33.9 -> 40.4 %, the still talker found 77.1 -> 81.8 %; beside the lone walker a false
#: second track 2.9 -> 4.5 %, the walker alone 89.1 -> 87.6 %, both talkers 65.2 % unchanged,
#: no cell worse. The stream's per-frame rule (:meth:`SourceTracker.reported`) is unchanged:
#: naming a close source anyway when the two tracks' rates differ by 5 deg/s gained the
#: crossing 30.7 -> 35.0 % on dev but 34.3 -> 35.7 % held out (seed 401; +2 asked).
TRACK_MERGE_SPREAD_DEG = 20.0

#: :func:`track_sources` links the pieces of one talker's broken track (added 2026-12-07,
#: ``link_gap_s`` / ``link_deg``): a track B that began at most this many seconds after track
#: A's last frame (or up to :data:`TRACK_LINK_OVERLAP_S` before it) continues A when A's last
#: :data:`TRACK_LINK_FIT_S` seconds of frames, extrapolated along a straight line, meet B's
#: first frame within :data:`TRACK_LINK_DEG` AND B's first frames, extrapolated back, meet A's
#: last one within it (track-segment association, Yeom, Kirubarajan & Bar-Shalom 2004; see
#: :data:`REPORT_SUCCESSOR_DEG`), the best-fitting pairs first, one successor and one
#: predecessor each; a chain of such pieces is one source -- its frames joined, its share
#: theirs, beating chance when one of its pieces does. Why: where a walker crosses a still
#: talker's direction its track breaks (its frames blend with the other's there), so before
#: and after the crossing it was two sources: bench/moving_sources.py's crossing scenes named
#: the walker under one identity in 9-16 % of the pairs of moments. Dev (scratch: the inputs
#: of :func:`localize_moving_sources` for bench/moving_sources.py's crossing scenes ``[400,
#: 2]`` and scenes of seed 281, 10 recordings per cell, captured and replayed; 8-cell means):
#: the walker's identity kept 16.2 -> 37.7 %, the still talker's 73.1 -> 71.0 %, crossing
#: talkers both within 10 deg 49.5 -> 50.8 %, two talkers 67.9 -> 69.1 %, the walker alone
#: within 10 deg 89.6 % both, a false second talker 3.9 -> 4.5 %. 1.5 s and 15 deg: walker
#: 31.1 %; 3 s and 30 deg: 44.9 %, but the still talker's 69.1 % and a false second talker
#: 5.4 %. With the stream's IMM tracks (:data:`TALKER_MODES_DPS2`) as well, the walker's 75 %
#: and the still talker's 85 %, but two talkers both found 62.4 % (the walker's track broke
#: into pieces too short to link). Held out (crossing ``[409, 2]`` and scenes of seed 301, the
#: rule written before their recordings were made): the walker's identity 17.4 -> 35.8 %, the
#: still talker's 77.0 -> 76.0 %, crossing talkers both found 47.4 -> 50.1 %, two talkers 58.4
#: -> 59.6 %, the walker alone 84.4 -> 84.9 %, a false second talker 6.4 % both, no cell worse
#: by more than 2 points: adopted. The stream keeps its ids as they are: the same linking online
#: (a young track taking the id of the piece it continues) moved its dev walker 59.0 -> 59.9 %.
TRACK_LINK_GAP_S = 3.0
#: see :data:`TRACK_LINK_GAP_S`: how far (degrees) the two extrapolations may miss
TRACK_LINK_DEG = 20.0
#: see :data:`TRACK_LINK_GAP_S`: the frames (seconds at either end) a straight line is fitted to
TRACK_LINK_FIT_S = 0.6
#: see :data:`TRACK_LINK_GAP_S`: how long (s) two linked pieces may overlap
TRACK_LINK_OVERLAP_S = 0.1

#: A stream frame that has its own direction also gives :class:`SourceTracker` its smoothed
#: steered response's strongest other maximum when that maximum is at least this share of the
#: response's peak (:func:`second_direction`; ``StreamConfig.talker_peak_ratio``; added
#: 2026-12-07). A frame's GCC peaks name the louder talker, so the other is heard in fewer
#: frames: in the two-talker scenes of bench/moving_sources.py (seed 281) the less-heard
#: talker had a median 27 % of the located frames within 10 deg of them, under 20 % in a
#: quarter of the recordings. Two talkers are two maxima of a steered response (SRP-PHAT;
#: DiBiase, Silverman & Brandstein 2001; ODAS likewise scans several potential sources per
#: frame, Grondin & Michaud 2019). Chosen on the stream's frames of dev recordings (scratch:
#: bench/moving_sources.py's scenes of seed 281 and its crossing scenes of seed 400, 10
#: recordings per cell, captured and replayed; 8-cell means; the maximum at least
#: :data:`TRACK_MERGE_DEG` from the frame's own direction, which :meth:`SourceTracker.reported`
#: would not name beside it anyway): both talkers within 10 deg 63.0 % without, 69.6 / 70.4 /
#: 70.8 / 71.2 % with a share of 0.7 / 0.75 / 0.8 / 0.9; a false second talker beside the
#: walker alone 0.4 % without, 1.6 / 1.4 / 1.0 / 0.8 % with (0.5: 15.0 %); the walker alone
#: and within 10 deg 95.1 -> 93.9 % at 0.8; crossing talkers both within 10 deg 58.9 -> 65.1 %
#: (0.9: 61.6 %). Held out (seeds 297 and crossing 403, the rule written before their replay):
#: both talkers 67.5 -> 71.6 %, a false second talker 2.6 -> 3.5 %, the walker alone 91.2 ->
#: 90.4 %, crossing talkers both 56.1 -> 58.6 % and the still one found 79.1 -> 81.0 %, no
#: cell worse by more than 4 points.
TALKER_PEAK_RATIO = 0.8

#: The stream's talkers' tracks (``StreamConfig.talker_modes_dps2``; added 2026-12-07): each an
#: interacting-multiple-model filter (:class:`~hearsee.audio.tracking.DirectionIMM`; Blom &
#: Bar-Shalom 1988) of two constant-velocity modes with these angular acceleration noises (deg/s^2)
#: -- a talker who stands (or walks steadily) and one who walks on or turns --, the rates not
#: relaxing (``rate_tau_s`` None), modes held :data:`TALKER_MODE_DWELL_S` on average, and a frame
#: joining a track within :data:`TALKER_MAX_JUMP_DEG` of its prediction. Why: the offline tracks'
#: one filter (:data:`TRACK_ACCEL_DPS2`, rates relaxing over :data:`TRACK_RATE_TAU_S`) lags a walker
#: (and so did the stream's, which used it before), so where the walker crosses a still talker's
#: direction the still talker's track, nearer than the walker's own, takes the walker's frames:
#: bench/moving_sources.py's crossing scenes name the walker under one identity before and after the
#: crossing in few of the pairs of moments (its identity columns). Dev (the stream's frames of that
#: bench's crossing scenes ``[400, 2]`` and scenes of seed 281, 10 recordings per cell, captured and
#: replayed; 8-cell means): the walker's identity kept 13.1 -> 59.0 %, the still talker's 64.1 ->
#: 73.8 %, both talkers within 10 deg 65.1 -> 64.7 % (crossing) and 70.8 -> 72.8 % (two talkers),
#: the walker alone and within 10 deg 93.9 -> 95.8 %, a false second talker 1.0 % both. Held out
#: (crossing ``[405, 2]`` and scenes of seed 299, the rule written before their replay): walker 5.8
#: -> 36.6 %, still talker 49.1 -> 71.1 %, crossing talkers both found 64.4 -> 63.1 %, two talkers
#: 71.0 -> 71.2 %, the walker alone 92.5 -> 96.5 %, a false second talker 2.6 -> 0.9 %, but one
#: crossing cell (three-mic, RT60 0.3 s, ARCTIC) 73 -> 59 %, beyond the rule's 10-point bar: kept
#: opt-in. A second held-out test under the same bars, disclosed as such and written before its
#: recordings were made (crossing ``[407, 2]`` and ``[408, 2]``, 20 recordings per cell, and the
#: scenes of seed 300): walker 10.7 -> 43.5 %, still talker 51.3 -> 70.1 %, crossing talkers both
#: found 62.4 -> 63.1 % (worst cell -8), two talkers 70.5 -> 71.6 % (worst cell -3), the walker
#: alone 93.2 -> 95.8 %, a false second talker 0.8 -> 0.9 %: the default since. It costs the stream
#: ~15 % more CPU (two voices, three-mic, 16 kHz: 0.39 instead of 0.34 s per 10 s of audio). (One
#: filter of 40 deg/s^2 with constant rates and the same gate, tried first: dev identities 66.0 /
#: 68.7 %; held out on ``[404, 2]`` walker 7.7 -> 41.4 % but still talker 63.6 -> 50.8 %, its track,
#: given a rate by the walker's frames, drifting off; the IMM's quiet mode keeps it: 65.4 % there.)
#: The offline tracks (:func:`track_sources`) keep their filter: the faster filters cost them 4-6
#: points of both talkers found on dev.
TALKER_MODES_DPS2 = (5.0, 40.0)
#: see :data:`TALKER_MODES_DPS2`: the mean time (s) a talker's track stays in one mode
TALKER_MODE_DWELL_S = 1.0
#: see :data:`TALKER_MODES_DPS2`: the gate (degrees) with the two modes; with 15 (the offline
#: tracks' :data:`TRACK_MAX_JUMP_DEG`) dev gave both talkers 68.9 %, identities 68.9 / 77.1 %
TALKER_MAX_JUMP_DEG = 12.0


def talker_tracker_settings(modes_dps2: Sequence[float] | None = TALKER_MODES_DPS2
                            ) -> dict[str, Any]:
    """:class:`SourceTracker`'s settings for the stream's talkers
    (``StreamConfig.talker_modes_dps2``): with ``modes_dps2`` (deg/s^2) IMM tracks of those
    modes, constant rates, :data:`TALKER_MODE_DWELL_S` and the gate
    :data:`TALKER_MAX_JUMP_DEG`; None: none (the offline tracks' defaults)."""
    if modes_dps2 is None:
        return {}
    return {"max_jump_deg": TALKER_MAX_JUMP_DEG, "rate_tau_s": None, "modes_dps2": modes_dps2,
            "mode_dwell_s": TALKER_MODE_DWELL_S}


def _modes(modes: Any, noise_range: tuple[float, float]) -> tuple[float, ...]:
    """``modes`` as an IMM's angular acceleration noises (deg/s^2): two or more finite numbers
    within ``noise_range``; ConfigError otherwise."""
    items = None if isinstance(modes, str) else object_entries(modes)
    if items is None or items.ndim != 1 or items.size < 2 or not all_real(items) or not all(
            noise_range[0] <= float(q) <= noise_range[1] for q in items):
        raise ConfigError(f"modes_dps2 must hold two or more angular acceleration noises "
                          f"(deg/s^2, {noise_range[0]:g} to {noise_range[1]:g}), e.g. (5, 40); "
                          f"got {modes!r:.80}")
    return tuple(float(q) for q in items)


def second_direction(profile: ArrayLike, keys: ArrayLike, own_key: float,
                     ratio: float = TALKER_PEAK_RATIO,
                     min_apart_deg: float = TRACK_MERGE_DEG) -> float | None:
    """A frame's second direction from its steered response: of the local maxima of
    ``profile`` (the response over a circle of azimuths, evenly spaced, as
    :class:`~hearsee.stream.pipeline.SmoothedSrp` gives it) whose value is at least ``ratio``
    times the profile's largest and whose ``keys`` (what :class:`SourceTracker` tracks at
    those azimuths, degrees: the azimuths, or a linear array's sines from broadside times 90,
    :func:`azimuth_keys`) lie ``min_apart_deg`` or more from the frame's own ``own_key``, the
    strongest one's key; None when there is none (or the profile is all zero or not finite).
    See :data:`TALKER_PEAK_RATIO`."""
    from hearsee.audio.tracking import _wrap1

    prof, key = np.asarray(profile, dtype=float), np.asarray(keys, dtype=float)
    top = float(prof.max(initial=0.0)) if prof.size else 0.0
    if not (np.isfinite(top) and top > 0):
        return None
    peak = (prof >= np.roll(prof, 1)) & (prof > np.roll(prof, -1)) & (prof >= ratio * top)
    for i in np.flatnonzero(peak)[np.argsort(-prof[peak], kind="stable")]:
        if abs(_wrap1(float(key[i]) - own_key)) >= min_apart_deg:
            return float(key[i])
    return None


def azimuth_keys(azimuth_deg: ArrayLike, axis: ArrayLike | None = None) -> NDArray:
    """What :class:`SourceTracker` tracks for sources in the horizontal plane at
    ``azimuth_deg`` (degrees, array frame): the azimuths themselves, or for a linear array of
    unit ``axis`` the sines of their angles from broadside times 90 (:func:`_from_broadside`)."""
    if axis is None:
        return np.array(azimuth_deg, dtype=float)
    u = unit_vector_deg(azimuth_deg)
    return 90.0 * np.clip(u @ np.asarray(axis, dtype=float), -1.0, 1.0)


#: :class:`SourceTracker`'s reporting rules, chosen on the stream's frames of dev recordings
#: (seeds 281-282 of bench/moving_sources.py's kind, scratch, 2026-12-06: 10 recordings x 10
#: moments per array, room and signal cell, two talkers and the walker alone; ``hearsee track
#: --sources 2``'s frames). With :func:`track_sources`' rules as they are (ranked by whole
#: weight, the chance test over all the frames of a track's life) the online answer had both
#: talkers within 10 deg at 44 % of the moments (8-cell mean) and a false second talker beside
#: the lone walker at 11 %; each change below, added in turn: 50 / 11, 68 / 14, 65 / 9 %.
#: First, the talkers are ranked by the weight of their frames, each frame's decayed with this
#: time constant (s): a talker heard lately before one heard long ago -- a track that
#: fragmented leaves a coasting stale part, which by its whole weight outranked the live part
#: for up to ``max_coast_s`` (0.5 / 2 s, with all three changes: 60 / 5 and 64 / 12 %).
#: Second, online, the chance test counts only the frames of its life that no other source
#: explains (that did not join a track which had beaten chance): a talker who starts while
#: another talks was held back until its own frames outnumbered chance among the other's
#: (a constructed second talker: reported after its 14th frame, now its 4th) -- the bar
#: stays :data:`TRACK_MAX_CHANCE` (1e-3: 70 / 10 %, but frames scattered at random were then
#: reported at 12 % of the frames, against 5 %)
REPORT_RANK_TAU_S = 1.0
#: Third, a second (third, ...) talker is named only while its decayed weight is at least this
#: share of the first's: a reflection's track gathers a trickle of frames beside a talker's
#: stream of them (0.25: 58 / 7 %)
REPORT_MIN_RATIO = 0.15
#: Fourth (added 2026-12-07), a talker whose track broke is named once, not twice: a source is
#: not named while a younger source has taken over from it -- one that began at most this
#: far (degrees) from its predicted angle, was heard after its last frame, and it has been
#: quiet for :data:`REPORT_SUCCESSOR_QUIET_S`. A walker passing near the array turns faster
#: than the tracks' 20 deg/s^2 follow (:data:`TRACK_ACCEL_DPS2`); the frames fall out of the
#: old track's gate and start a new one beside it, and the old one, coasting on its stale
#: rate, had been named as a second talker for up to ~2 s (track-segment association: a
#: track that ends where another begins is one target's; Yeom, Kirubarajan & Bar-Shalom
#: 2004, "Track segment association, fine-step IMM and initialization with Doppler for
#: improved track performance", IEEE Trans. AES 40(1)). Dev (seeds 281-282 of
#: bench/moving_sources.py's scenes, scratch, 10 recordings per cell, the stream's frames):
#: a false second talker beside the lone walker at 7.7 -> 1.7 % of the moments (8-cell
#: mean), the walker alone and within 10 deg 88.6 -> 94.4 %, both talkers within 10 deg
#: 64.4 -> 65.2 %; 45 deg cost the two talkers (63.8-65.0 %), a quiet time of 0 / 0.5 s gave
#: 1.0 / 2.3 % false and 64.9 / 65.3 % both; a take-over counted only within 1 s of the old
#: track's last frame, 2.4 % false. Held out (seeds 291-292, the rule written before their
#: run): false second talker 10.3 -> 3.8 %, the walker alone within 10 deg 85.2 -> 91.5 %,
#: both talkers 65.1 -> 66.3 %, no cell worse. 0 disables it.
REPORT_SUCCESSOR_DEG = 30.0
#: see :data:`REPORT_SUCCESSOR_DEG`: how long (s) a source must have been quiet before a
#: younger one that took over from it hides it
REPORT_SUCCESSOR_QUIET_S = 0.25


class _Track:
    """One track of :class:`SourceTracker`: its filter and what the reporting rules count."""

    __slots__ = ("id", "kf", "n_hits", "hits", "weight", "last_t", "angle_deg", "located_before",
                 "weight_before", "located_through", "gate_sum", "gate_n", "gate_at_hit",
                 "passed", "path_i", "path_a", "recent_w", "recent_t", "explained_before",
                 "explained_through", "born_angle", "born_near")

    def __init__(self, track_id: int, kf: Any, located_before: int,
                 weight_before: float) -> None:
        self.id, self.kf = track_id, kf
        self.n_hits = 0  # frames that joined it
        self.hits: list[int] = []  # (their indices: kept with the tracker's history only)
        self.weight = 0.0
        self.last_t = self.angle_deg = float("nan")
        # the located frames (and their weight) before its first frame, and through its last
        self.located_before, self.weight_before = located_before, weight_before
        self.located_through = located_before
        # the located frames that joined a source that had beaten chance, before its first
        # frame and through its last (none of them its own while the chance test is judged:
        # that stops once it has passed)
        self.explained_before = self.explained_through = 0
        # its gate's half widths (deg) at the located frames since its first; their sum and
        # count at its last frame
        self.gate_sum, self.gate_n = 0.0, 0
        self.gate_at_hit = (0.0, 0)
        self.passed = False  # (the chance test, once passed, holds)
        self.recent_w, self.recent_t = 0.0, 0.0
        # its first frame's angle (deg) and the other live tracks' predicted angles then
        # (id -> deg): whom it may have taken over from (REPORT_SUCCESSOR_DEG)
        self.born_angle = float("nan")
        self.born_near: dict[int, float] = {}
        self.path_i: list[int] = []
        self.path_a: list[float] = []

    def mean_gate_deg(self, jump: float) -> float:
        """The gate's mean half width (deg) over the located frames of its life (its first to
        its last frame; ``jump`` when it has one frame)."""
        s, n = self.gate_at_hit
        return s / n if n else jump


class SourceTracker:
    """The online core of :func:`track_sources`: one frame at a time, as a stream gets them.

    :meth:`step` takes a frame's time and angle (or NaN) and joins it to a track as
    :func:`track_sources` describes (the same tracks, frame for frame); :meth:`reported`
    names the talkers to act on now -- the live tracks that are sources (``confirm_hits``
    frames), whose frames chance does not explain (``max_chance``, judged at each of their
    frames until it passes, then it holds; the frames of its life counted are those that no
    other source, one that had beaten chance, took) and that hold at least ``min_share`` of
    the weight of the frames located since their first frame; of those the ``max_sources``
    with the most weight of recent frames (each frame's decayed by ``exp(-age /
    rank_tau_s)``), a second or later one only while that weight is at least ``min_ratio``
    times the first's and its angle is ``merge_deg`` or more from those named before it (one
    talker's frames split between two tracks side by side: :data:`TRACK_MERGE_DEG`); and a
    source is not named while a younger one has taken over from it
    (one talker whose track broke: it began within ``successor_deg`` of the source's
    predicted angle and was heard after the source's last frame, and the source has been
    quiet for ``successor_quiet_s``; see :data:`REPORT_SUCCESSOR_DEG`). Unlike
    :func:`track_sources`' answer, decided on the whole recording, this one is causal: a
    talker is reported from the frame that makes it a source, and a talker's track goes on,
    predicted, through a pause of up to ``max_coast_s`` (``last_t`` says when it was last
    heard). The settings are :func:`track_sources`', and the reporting rules
    (:data:`REPORT_RANK_TAU_S`, :data:`REPORT_MIN_RATIO`, :data:`REPORT_SUCCESSOR_DEG`,
    :data:`REPORT_SUCCESSOR_QUIET_S`; chosen on the stream's frames of dev recordings).
    ``history`` keeps the tracks that ended, each track's frames and its angle at every frame
    (what :func:`track_sources` needs; a stream leaves it off, so that memory stays bounded:
    a live track counts its frames). Ids are never given twice by one
    tracker, :meth:`reset` included; they count from ``first_id`` (a tracker replacing
    another one starts at its :attr:`next_id`). Each track's filter is a constant-velocity
    :class:`~hearsee.audio.tracking.DirectionKalman` (``sigma_accel_dps2``, its rates relaxing
    toward zero over ``rate_tau_s`` seconds, None = constant rates), or with ``modes_dps2`` (two
    or more angular acceleration noises, deg/s^2) an IMM of such modes
    (:class:`~hearsee.audio.tracking.DirectionIMM`, ``mode_dwell_s``; ``sigma_accel_dps2`` is
    then not used; the stream's, :data:`TALKER_MODES_DPS2`); below a ``span_deg`` of 360
    (a linear array's angles) the tracks' angles stay within +-``span_deg / 2``. Used by the
    stream
    (``StreamConfig.max_sources``, ``hearsee track --sources N``). Not in the thesis; an
    extension.
    """

    def __init__(self, max_sources: int = 2, *,
                 sigma_meas_deg: float = TRACK_SIGMA_MEAS_DEG,
                 sigma_accel_dps2: float = TRACK_ACCEL_DPS2,
                 max_jump_deg: float = TRACK_MAX_JUMP_DEG,
                 confirm_hits: int = TRACK_CONFIRM_HITS,
                 tentative_s: float = TRACK_TENTATIVE_S,
                 max_coast_s: float = TRACK_MAX_COAST_S,
                 min_share: float = TRACK_MIN_SHARE,
                 max_chance: float = TRACK_MAX_CHANCE,
                 span_deg: float = 360.0, rank_tau_s: float = REPORT_RANK_TAU_S,
                 min_ratio: float = REPORT_MIN_RATIO,
                 successor_deg: float = REPORT_SUCCESSOR_DEG,
                 successor_quiet_s: float = REPORT_SUCCESSOR_QUIET_S,
                 merge_deg: float = TRACK_MERGE_DEG, history: bool = False,
                 rate_tau_s: float | None = TRACK_RATE_TAU_S,
                 modes_dps2: Sequence[float] | None = None,
                 mode_dwell_s: float = TALKER_MODE_DWELL_S, first_id: int = 0) -> None:
        from scipy.stats import chi2

        from hearsee.audio.tracking import NOISE_RANGE

        self.max_sources = whole_number("max_sources", max_sources, 1, MAX_SOURCES)
        # (the ranges DirectionKalman takes: beyond them its EstimationError came at the first
        # located frame, and never without one)
        self.sigma_meas_deg = finite_number("sigma_meas_deg", sigma_meas_deg, NOISE_RANGE[0],
                                            90.0)
        self.sigma_accel_dps2 = finite_number("sigma_accel_dps2", sigma_accel_dps2,
                                              *NOISE_RANGE)
        self.max_jump_deg = finite_number("max_jump_deg", max_jump_deg, 0.0, 180.0,
                                          lo_open=True)
        self.confirm_hits = whole_number("confirm_hits", confirm_hits, 1, None)
        self.tentative_s = finite_number("tentative_s", tentative_s, 0.0, None, lo_open=True)
        self.max_coast_s = finite_number("max_coast_s", max_coast_s, 0.0, None, lo_open=True)
        self.min_share = finite_number("min_share", min_share, 0.0, 1.0)
        if self.min_share >= 1.0:
            raise ConfigError(f"min_share must be below 1 (a share of the frames), got "
                              f"{min_share}")
        self.max_chance = finite_number("max_chance", max_chance, 0.0, 1.0, lo_open=True)
        self.span_deg = finite_number("span_deg", span_deg, 0.0, 360.0, lo_open=True)
        # (below 360, a linear array's angles: its tracks' filters hold them within +-half)
        self._bound_deg = None if self.span_deg == 360.0 else self.span_deg / 2.0
        self.rank_tau_s = finite_number("rank_tau_s", rank_tau_s, 0.0, None, lo_open=True)
        self.min_ratio = finite_number("min_ratio", min_ratio, 0.0, 1.0)
        self.successor_deg = finite_number("successor_deg", successor_deg, 0.0, 180.0)
        self.successor_quiet_s = finite_number("successor_quiet_s", successor_quiet_s, 0.0,
                                               None)
        self.merge_deg = finite_number("merge_deg", merge_deg, 0.0, 180.0)
        self.history = true_or_false("history", history)
        self.rate_tau_s = None if rate_tau_s is None else finite_number(
            "rate_tau_s", rate_tau_s, 0.0, None, lo_open=True)
        self.modes_dps2 = None if modes_dps2 is None else _modes(modes_dps2, NOISE_RANGE)
        self.mode_dwell_s = finite_number("mode_dwell_s", mode_dwell_s, 0.0, None,
                                          lo_open=True)
        self._gate = float(chi2.ppf(0.997, 1))
        # (ids are never given again, reset() included: a client keying on them would merge
        # two talkers; a tracker that replaces another one goes on from its next_id)
        self._next_id = whole_number("first_id", first_id, 0, None)
        self.reset()

    @property
    def next_id(self) -> int:
        """The id the next new track gets (``first_id`` for a tracker that has started none):
        a tracker that takes over from this one starts there (``first_id=``), so that no id
        names two talkers."""
        return self._next_id

    def reset(self) -> None:
        """Forget every track (as after the array has turned by an unknown angle); the ids of
        tracks started afterwards continue the count, and time may start again."""
        self.live: list[_Track] = []
        self.ended: list[_Track] = []
        self.n_frames = 0  # frames stepped
        self.located = 0  # frames with an angle
        self.explained = 0  # ... that joined a source which had beaten chance by then
        self.located_weight = 0.0
        self._t = -np.inf
        self._models: dict[float, Any] = {}  # (the filters' transition and noise per step)
        self._tpms: dict[float, Any] = {}  # (an IMM's mode switching per step)

    def rotate(self, delta_deg: float) -> None:
        """Add ``delta_deg`` (degrees) to every live track's angle (azimuths: the array turned
        by ``-delta_deg`` about its z axis; see
        :meth:`~hearsee.audio.tracking.DirectionKalman.rotate_azimuth`). ConfigError for a
        tracker of angles that are no azimuths (``span_deg`` below 360: a linear array's)."""
        from hearsee.audio.tracking import _wrap1

        if self._bound_deg is not None:
            raise ConfigError("only azimuths (span_deg 360) turn with the array: a linear "
                              "array's angles follow a turn as motion")
        d = finite_number("delta_deg", delta_deg)
        for tr in self.live:
            tr.kf.rotate_azimuth(d)
            tr.angle_deg = _wrap1(tr.angle_deg + d)

    def step(self, t: float, angle_deg: float, weight: float = 1.0) -> int:
        """Take the frame at time ``t`` (s, not before the last) with angle ``angle_deg``
        (degrees, NaN = none) and ``weight`` (>= 0); returns the id of the track it joined, -1
        for none. ConfigError for a time that goes back or is not finite, an infinite angle
        (or beyond +-1e9 deg) or a negative or non-finite weight."""
        from hearsee.audio.tracking import _wrap1

        # (numbers only: text, None or a list had been float()'s ValueError or TypeError)
        if not (is_real(t) and float(t) >= self._t):
            raise ConfigError("t must hold finite, non-decreasing frame times (s)")
        nan = isinstance(angle_deg, float | np.floating) and math.isnan(angle_deg)
        if not (nan or (is_real(angle_deg) and abs(float(angle_deg)) <= MAX_ANGLE_DEG)):
            raise ConfigError(f"angle_deg must hold finite degrees (within "
                              f"+-{MAX_ANGLE_DEG:g}) or NaN (no direction)")
        if not (is_real(weight) and float(weight) >= 0):
            raise ConfigError("weight must hold one finite number >= 0 per frame")
        ti, a, w = float(t), float(angle_deg), float(weight)
        self._t = ti
        i = self.n_frames
        self.n_frames += 1
        for tr in list(self.live):  # (tracks that went quiet too long end)
            if ti - tr.last_t > (self.max_coast_s if tr.n_hits >= self.confirm_hits
                                 else self.tentative_s):
                self.live.remove(tr)
                if self.history:
                    self.ended.append(tr)
        # (each live track's predicted state at this frame, once: the gate and the path)
        pred = {tr.id: tr.kf.predicted(ti) for tr in self.live}
        best: _Track | None = None
        if np.isfinite(a):
            best_cost, R = np.inf, self.sigma_meas_deg**2
            for tr in self.live:
                x, P = pred[tr.id]
                S = float(P[0, 0]) + R
                y = _wrap1(a - float(x[0]))
                d2 = y * y / S
                # (its gate's half width)
                tr.gate_sum += min(self.max_jump_deg, float(np.sqrt(self._gate * S)))
                tr.gate_n += 1
                if d2 <= self._gate and abs(y) <= self.max_jump_deg and (
                        d2 + np.log(S) < best_cost):
                    best, best_cost = tr, d2 + np.log(S)
            if best is None:
                best = _Track(self._next_id, self._new_filter(), self.located,
                              self.located_weight)
                best.explained_before = self.explained
                best.born_angle = a
                best.born_near = {tr.id: _wrap1(float(pred[tr.id][0][0])) for tr in self.live}
                self._next_id += 1
                self.live.append(best)
            self.located += 1
            if best.passed:  # (a frame of a source that beat chance: explained)
                self.explained += 1
            self.located_weight += w
            best.kf.update(ti, (a, None))
            best.n_hits += 1
            if self.history:
                best.hits.append(i)
            best.weight += w
            best.recent_w = self.recent_weight(best, ti) + w
            best.recent_t = ti
            best.last_t = ti
            best.located_through = self.located
            best.explained_through = self.explained
            best.gate_at_hit = (best.gate_sum, best.gate_n)
            if not best.passed and best.n_hits >= self.confirm_hits:
                best.passed = self._beats_chance(best, free=True)
        for tr in self.live:  # (each live track's angle at this frame)
            tr.angle_deg = _wrap1(tr.kf.azimuth_deg if tr is best
                                  else float(pred[tr.id][0][0]))
            if self.history:
                tr.path_i.append(i)
                tr.path_a.append(tr.angle_deg)
        return -1 if best is None else best.id

    def _new_filter(self) -> Any:
        """A new track's filter: one constant-velocity Kalman filter, or with ``modes_dps2``
        an IMM of such modes; its transition and noise per step shared with the other
        tracks' (they share their filters' settings). With a ``span_deg`` below 360 (a
        linear array's angles, -90 to 90) the angle is held within +-``span_deg / 2``
        (``angle_bound_deg``: a track coasting at its last rate does not pass endfire)."""
        from hearsee.audio.tracking import DirectionIMM, DirectionKalman

        bound = self._bound_deg
        if self.modes_dps2 is None:
            kf = DirectionKalman(self.sigma_meas_deg, self.sigma_accel_dps2, gate_prob=0.997,
                                 init_rate_sigma_dps=TRACK_INIT_RATE_DPS,
                                 rate_tau_s=self.rate_tau_s, angle_bound_deg=bound)
        else:
            kf = DirectionIMM(self.sigma_meas_deg, self.modes_dps2, self.mode_dwell_s,
                              gate_prob=0.997, init_rate_sigma_dps=TRACK_INIT_RATE_DPS,
                              rate_tau_s=self.rate_tau_s, angle_bound_deg=bound)
            kf._tpm_cache = self._tpms
        kf._model_cache = self._models
        return kf

    def _beats_chance(self, tr: _Track, free: bool = False) -> bool:
        """Whether frames scattered at random over ``span_deg`` would put as many frames as
        ``tr`` holds in its gate during its life with a probability below ``max_chance``
        (binomial tail); with ``free`` (online) the frames of its life that other sources,
        ones that had beaten chance then, took are not counted."""
        from scipy.special import bdtrc

        during = tr.located_through - tr.located_before
        if free:
            during -= tr.explained_through - tr.explained_before
        half = tr.mean_gate_deg(self.max_jump_deg)  # (max_jump_deg at its first frame)
        p = min(1.0, 2.0 * half / self.span_deg)
        return bool(bdtrc(tr.n_hits - 1, during, p) < self.max_chance)

    def share(self, tr: _Track) -> float:
        """``tr``'s share (0-1) of the weight of the frames located since its first frame."""
        since = self.located_weight - tr.weight_before
        return tr.weight / since if since > 0 else 0.0

    def reported(self) -> list[_Track]:
        """The talkers to act on at the last frame: live sources whose frames beat chance and
        hold ``min_share`` of the weight since their first, at most ``max_sources``, the most
        weight of recent frames first, the second and later ones with at least ``min_ratio``
        of the first's and ``merge_deg`` or more from those before them, none while a younger
        source has taken over from it (see the class).
        Each has ``id``, ``angle_deg`` (its angle at the last frame, degrees), ``last_t`` (when
        a frame last joined it, s) and ``n_hits`` (how many frames joined it)."""
        from hearsee.audio.tracking import _wrap1

        ok = [tr for tr in self.live if tr.n_hits >= self.confirm_hits and tr.passed
              and tr.weight > 0 and self.share(tr) >= self.min_share]
        ok = [tr for tr in ok if not any(self._took_over(new, tr) for new in ok)]
        ranked = sorted(((self.recent_weight(tr, self._t), tr) for tr in ok),
                        key=lambda wt: (-wt[0], wt[1].id))
        named: list[tuple[float, _Track]] = []
        for w, tr in ranked:  # (one talker's two tracks side by side: the heavier named)
            if len(named) < self.max_sources and all(
                    abs(_wrap1(tr.angle_deg - k.angle_deg)) >= self.merge_deg for _, k in named):
                named.append((w, tr))
        return [tr for w, tr in named if w >= self.min_ratio * named[0][0]]

    def _took_over(self, new: _Track, old: _Track) -> bool:
        """Whether ``new`` has taken over from ``old`` (one talker whose track broke; see
        :data:`REPORT_SUCCESSOR_DEG`): it began within ``successor_deg`` of ``old``'s predicted
        angle, was heard after ``old``'s last frame, and ``old`` has been quiet for
        ``successor_quiet_s``."""
        from hearsee.audio.tracking import _wrap1

        start = new.born_near.get(old.id)
        return (self.successor_deg > 0 and start is not None and new.last_t > old.last_t
                and self._t - old.last_t >= self.successor_quiet_s
                and abs(_wrap1(new.born_angle - start)) <= self.successor_deg)

    def recent_weight(self, tr: _Track, t: float) -> float:
        """``tr``'s frames' weight, each decayed by ``exp(-age / rank_tau_s)`` at time ``t``
        (s): what :meth:`reported` ranks by."""
        return tr.recent_w * math.exp(-(t - tr.recent_t) / self.rank_tau_s)


@dataclass(frozen=True)
class SourceTrack:
    """One talker followed through a recording by :func:`track_sources`.

    t : array of float
        Times (s) of the frames from its first to its last frame.
    angle_deg : array of float
        The track's angle at those times (degrees; the filter's estimate, predicted through
        the frames it got no direction from).
    frames : array of int
        Indices (into the frames given) of the frames that joined it.
    share : float
        Its frames' share of the weight of the located frames (0-1).
    """

    t: NDArray
    angle_deg: NDArray
    frames: NDArray
    share: float


def track_sources(t: ArrayLike, angle_deg: ArrayLike, weight: ArrayLike | None = None,
                  max_sources: int = 2, *,
                  sigma_meas_deg: float = TRACK_SIGMA_MEAS_DEG,
                  sigma_accel_dps2: float = TRACK_ACCEL_DPS2,
                  max_jump_deg: float = TRACK_MAX_JUMP_DEG,
                  confirm_hits: int = TRACK_CONFIRM_HITS,
                  tentative_s: float = TRACK_TENTATIVE_S,
                  max_coast_s: float = TRACK_MAX_COAST_S,
                  min_share: float = TRACK_MIN_SHARE,
                  max_chance: float = TRACK_MAX_CHANCE,
                  span_deg: float = 360.0,
                  merge_deg: float = TRACK_MERGE_DEG,
                  merge_spread_deg: float = TRACK_MERGE_SPREAD_DEG,
                  link_gap_s: float = TRACK_LINK_GAP_S,
                  link_deg: float = TRACK_LINK_DEG,
                  ) -> tuple[list[SourceTrack], NDArray]:
    """Several moving talkers: the frames' directions followed through time, one track each.

    :func:`direction_clusters` assumes the talkers stand still; a talker who walks smears
    a pile over tens of degrees. Here every talker has a constant-velocity Kalman filter on
    its angle (:class:`~hearsee.audio.tracking.DirectionKalman`, the rate relaxing over
    :data:`TRACK_RATE_TAU_S`). Speech is sparse (see the module's
    docstring), so each frame's one direction is one talker's: it joins the track whose
    prediction explains it best -- the least ``d^2 + ln S`` (innovation ``y``, its variance
    ``S``, ``d^2 = y^2 / S``) among those whose chi-square gate (99.7 %) it passes and whose
    prediction is within ``max_jump_deg``, global nearest neighbour (Bar-Shalom & Li 1995,
    "Multitarget-multisensor tracking: principles and techniques", ch. 6; the ``ln S`` keeps
    a track that coasted through a pause from taking a precisely tracked neighbour's frames)
    -- or starts a new track. A track that ``confirm_hits`` frames joined is a source; it
    ends after ``max_coast_s`` without a frame (``tentative_s`` before it is one).
    Afterwards, the pieces of one talker's broken track are linked into one (a track that
    begins where another, extrapolated, ended: :data:`TRACK_LINK_GAP_S`), sources holding
    less than ``min_share`` of the located frames' weight, or so few of the frames located
    during their life that chance would explain them (``max_chance``; a linked source's
    pieces: one of them), are dropped, sources whose paths run closer than ``merge_deg`` together
    are merged unless they close in on each other or part (one talker whose frames split
    between two tracks, not two talkers who cross; see :data:`TRACK_MERGE_DEG`,
    :data:`TRACK_MERGE_SPREAD_DEG`), and at most ``max_sources`` are kept at any one time, the
    largest share first. A track's angle at a frame uses that frame and those before it
    (causal); which tracks are reported, and where each ends, is decided on the whole
    recording. Not in the thesis (its chapter 5 tracks one speaker); an extension.

    Parameters
    ----------
    t : array (n,)
        Frame times, seconds, non-decreasing.
    angle_deg : array (n,)
        Each frame's angle (degrees; :func:`localize_sources` gives azimuths, or a linear
        array's sine of the angle from broadside times 90), NaN for a frame without one.
    weight : array (n,), optional
        Each frame's weight >= 0 for the shares (default 1).
    max_sources : int
        The most sources at once (1 to :data:`MAX_SOURCES`).
    sigma_meas_deg, sigma_accel_dps2 : float
        A frame's angle noise (degrees) and the tracks' angular acceleration noise (deg/s^2).
    max_jump_deg : float
        The farthest (degrees) a frame may lie from a track's prediction to join it.
    confirm_hits : int
        Frames that make a track a source.
    tentative_s, max_coast_s : float
        Seconds without a frame after which a track ends, before and after it is a source.
    min_share : float
        Share (0-1) of the located frames' weight a source needs to be reported.
    max_chance : float
        A source is reported only when frames scattered at random over ``span_deg`` would put
        as many frames in its gate (``max_jump_deg`` either side, or the chi-square gate where
        that is narrower: their mean width) during its life (its first to its last frame, of
        the frames located then) with a probability below this (binomial tail).
    span_deg : float
        The range the angles can take (degrees): 360 for azimuths, 180 for a linear array's
        (-90 to 90; below 360, the tracks' angles are held within +-``span_deg / 2``).
    merge_deg : float
        Two sources whose paths are closer than this (degrees) at half or more of the frames
        both lived through are merged into one, the heavier's path kept where it lived (0 to
        180; 0: never).
    merge_spread_deg : float
        ... while their signed difference over those frames spreads less than this (degrees,
        its 90th minus 10th percentile; 0 to 360, 0: never): two talkers who cross are not
        merged.
    link_gap_s, link_deg : float
        A track that begins at most ``link_gap_s`` seconds after another's last frame
        continues it when their straight-line extrapolations meet each other's ends within
        ``link_deg`` degrees (:data:`TRACK_LINK_GAP_S`; either 0: never).

    Returns
    -------
    tracks : list of SourceTrack
        The sources, earliest first.
    which : array (n,) of int
        Each frame's track (its index in ``tracks``), -1 for none.

    Raises ConfigError for inputs of the wrong shape, non-finite or decreasing times, angles
    beyond +-1e9 deg, negative weights or settings outside their ranges (the noises within
    1e-6 to 1e6, as the Kalman filter takes them).
    """
    tracker = SourceTracker(max_sources, sigma_meas_deg=sigma_meas_deg,
                            sigma_accel_dps2=sigma_accel_dps2, max_jump_deg=max_jump_deg,
                            confirm_hits=confirm_hits, tentative_s=tentative_s,
                            max_coast_s=max_coast_s, min_share=min_share,
                            max_chance=max_chance, span_deg=span_deg, merge_deg=merge_deg,
                            history=True)
    spread = finite_number("merge_spread_deg", merge_spread_deg, 0.0, 360.0)
    gap = finite_number("link_gap_s", link_gap_s, 0.0, None)
    link = finite_number("link_deg", link_deg, 0.0, 180.0)
    tt = as_float_array(t, "t", (None,), finite=False)
    az = as_float_array(angle_deg, "angle_deg", tt.shape, finite=False)
    w = np.ones(len(tt)) if weight is None else as_float_array(weight, "weight", tt.shape,
                                                                finite=False)
    for i in range(len(tt)):  # (each frame's time, angle and weight checked there)
        tracker.step(tt[i], az[i], w[i])
    located = float(w[np.isfinite(az)].sum())
    pieces = sorted((tr for tr in tracker.ended + tracker.live
                     if len(tr.hits) >= tracker.confirm_hits), key=lambda tr: tr.hits[0])
    cands = []
    for chain in _linked(pieces, tt, az, gap, link, span_deg == 360.0):
        hits = np.concatenate([pieces[k].hits for k in chain]).astype(int)
        share = float(w[hits].sum()) / located if located > 0 else 0.0
        if share < tracker.min_share or not share > 0:
            continue
        # (the chance test over a piece's whole life: a random frame's chance of falling in
        # its gate, max_jump_deg unless the chi-square gate is tighter, its mean over the life)
        if any(tracker._beats_chance(pieces[k]) for k in chain):
            lives = [_life(pieces[k]) for k in chain]
            pi = np.concatenate([p for p, _ in lives])
            pi, first = np.unique(pi, return_index=True)  # (an overlap: the earlier piece's)
            pa = np.concatenate([a for _, a in lives])[first]
            cands.append(_Candidate(share, np.sort(hits), pi, pa))
    kept: list[_Candidate] = []
    for c in sorted(_merged(cands, tracker.merge_deg, spread, w, located), key=lambda c: -c.share):
        # at most max_sources at once: this one's life with the kept ones' (in frames: two
        # frames at one time, which a caller's times may hold, are not one moment)
        lo, hi = c.hits[0], c.hits[-1]
        spans = [(k.hits[0], k.hits[-1]) for k in kept]
        edges = sorted({lo, hi, *(v for s in spans for v in s if lo <= v <= hi)})
        if all(sum(a <= e <= b for a, b in spans) < max_sources for e in edges):
            kept.append(c)
    kept.sort(key=lambda c: c.hits[0])
    which = np.full(len(tt), -1)
    tracks = []
    for k, c in enumerate(kept):
        which[c.hits] = k
        tracks.append(SourceTrack(tt[c.path_i], c.path_a, c.hits, c.share))
    return tracks, which


def _life(tr: _Track) -> tuple[NDArray, NDArray]:
    """``tr``'s path over its life (its first to its last frame): frame indices and angles."""
    hits, pi = tr.hits, np.array(tr.path_i, dtype=int)
    on = (pi >= hits[0]) & (pi <= hits[-1])
    return pi[on], np.array(tr.path_a, dtype=float)[on]


def _end_line(t: NDArray, a: NDArray, end: bool, wrap: bool) -> tuple[float, float, float]:
    """The straight line fitted to the angles ``a`` (degrees; unwrapped with ``wrap``) of the
    frames at times ``t`` (s) within :data:`TRACK_LINK_FIT_S` of the last (``end``) or first
    one: a time (s), the line's angle then (degrees) and its slope (deg/s); the end frame's
    time and angle and no slope when those frames span under 0.1 s."""
    near = t >= t[-1] - TRACK_LINK_FIT_S if end else t <= t[0] + TRACK_LINK_FIT_S
    ts, aa = t[near], a[near]
    if wrap:
        aa = np.unwrap(aa, period=360.0)
    if np.ptp(ts) < 0.1:
        k = -1 if end else 0
        return float(ts[k]), float(aa[k]), 0.0
    tm = float(ts.mean())
    slope, icpt = np.polyfit(ts - tm, aa, 1)
    return tm, float(icpt), float(slope)


def _linked(pieces: list[_Track], t: NDArray, a: NDArray, gap_s: float, link_deg: float,
            wrap: bool) -> list[list[int]]:
    """The chains of ``pieces`` (tracks, earliest first) that are one talker's
    (:data:`TRACK_LINK_GAP_S`): lists of their indices, each piece in one chain (alone when
    ``gap_s`` or ``link_deg`` is 0). ``t``, ``a``: every frame's time (s) and angle
    (degrees; azimuths when ``wrap``)."""
    def miss(line: tuple[float, float, float], at: float, angle: float) -> float:
        d = line[1] + line[2] * (at - line[0]) - angle  # (the line at ``at`` vs ``angle``)
        return abs(float(wrap_deg(d))) if wrap else abs(d)

    links = []
    if gap_s > 0 and link_deg > 0:
        ends = [(t[tr.hits], a[tr.hits]) for tr in pieces]
        # (each piece's lines through its first and its last frames, fitted once)
        lines = [(_end_line(ti, ai, False, wrap), _end_line(ti, ai, True, wrap))
                 for ti, ai in ends]
        # (the pieces are sorted by their first frames: those that begin near i's end are
        # found by bisection, a window a little wider than the test below, which decides)
        starts = np.array([ti[0] for ti, _ in ends])
        for i, (ti, ai) in enumerate(ends):
            eps = 1e-9 * (1.0 + abs(ti[-1]))
            lo = np.searchsorted(starts, max(ti[0], ti[-1] - TRACK_LINK_OVERLAP_S) - eps)
            hi = np.searchsorted(starts, ti[-1] + gap_s + eps, side="right")
            for j in range(int(lo), int(hi)):
                tj, aj = ends[j]
                # (j begins after i began: a chain's starts increase, so no chain closes
                # on itself)
                if tj[0] > ti[0] and -TRACK_LINK_OVERLAP_S <= tj[0] - ti[-1] <= gap_s:
                    e = (miss(lines[i][1], tj[0], aj[0]), miss(lines[j][0], ti[-1], ai[-1]))
                    if max(e) <= link_deg:
                        links.append((sum(e), i, j))
    after: dict[int, int] = {}
    before: dict[int, int] = {}
    for _, i, j in sorted(links):  # (the best-fitting first; one successor, one predecessor)
        if i not in after and j not in before:
            after[i], before[j] = j, i
    chains = []
    for i in range(len(pieces)):
        if i not in before:
            chains.append([i])
            while chains[-1][-1] in after:
                chains[-1].append(after[chains[-1][-1]])
    return chains


@dataclass
class _Candidate:
    """A source :func:`track_sources` may report: its share, the indices of its frames and
    its path over its life (frame indices and angles, degrees)."""

    share: float
    hits: NDArray
    path_i: NDArray
    path_a: NDArray


def _merged(cands: list[_Candidate], merge_deg: float, spread_deg: float, w: NDArray,
            located: float) -> list[_Candidate]:
    """``cands``, the largest share first, with each merged into the first larger one whose
    path is closer than ``merge_deg`` to its own at the median of the frames both lived through
    (:data:`TRACK_MERGE_DEG`) and whose signed difference from it spreads less than
    ``spread_deg`` over them (90th minus 10th percentile, :data:`TRACK_MERGE_SPREAD_DEG`):
    their frames joined, the larger one's path kept where it lived, the share that of the
    frames joined (``w``: the frames' weights, ``located``: their sum over the located
    frames)."""
    out: list[_Candidate] = []
    for c in sorted(cands, key=lambda c: -c.share):
        for k in out:
            both, ik, ic = np.intersect1d(k.path_i, c.path_i, return_indices=True)
            d = wrap_deg(k.path_a[ik] - c.path_a[ic])
            if len(both) and np.median(np.abs(d)) < merge_deg and (
                    np.subtract(*np.percentile(d, [90, 10])) < spread_deg):
                k.hits = np.union1d(k.hits, c.hits)
                k.share = float(w[k.hits].sum()) / located
                extra = np.ones(len(c.path_i), dtype=bool)  # (its frames beyond k's life)
                extra[ic] = False
                path_i = np.concatenate([k.path_i, c.path_i[extra]])
                order = np.argsort(path_i, kind="stable")
                k.path_i = path_i[order]
                k.path_a = np.concatenate([k.path_a, c.path_a[extra]])[order]
                break
        else:
            out.append(c)
    return out


#: a moving source's direction in :func:`localize_moving_sources` is that of its last this
#: many frames' median TDOAs: where it was last heard
TRACK_LAST_FRAMES = 8


def localize_moving_sources(t: ArrayLike, tdoa_s: ArrayLike, valid: ArrayLike, array: Any,
                            pairs: Sequence[tuple[int, int]], max_sources: int = 2, *,
                            in_plane: bool = False, weight: ArrayLike | None = None,
                            locs: Sequence[Any] | None = None,
                            **track_kwargs: Any) -> tuple[list[dict[str, Any]], NDArray]:
    """Up to ``max_sources`` talkers at once that may move: :func:`localize_sources` for
    talkers who walk.

    The frames (times ``t`` in seconds, the rest as :func:`localize_sources` takes them) are
    localized and their angles (azimuths, or a linear array's sines of the angle from
    broadside times 90) followed by :func:`track_sources` (``track_kwargs`` passed on).

    Returns the sources, the earliest first, as dicts ``{"azimuth_deg", "elevation_deg",
    "candidates", "tdoa_s"`` (from the median TDOAs of its last :data:`TRACK_LAST_FRAMES`
    frames: where it was last heard) ``, "share", "n_frames", "t_start_s", "t_end_s"`` (its
    first and last frame) ``, "path": {"t_s": [...], "azimuth_deg": [...]}}`` (the track at
    every frame of its life; a linear array's front candidate, ``|azimuth| < 90``, its mirror
    as likely -- an x-axis pair, whose twins are both in front or both behind, keeps to one
    side --, a vertical pair's None: it tells no azimuth), and each frame's source
    (n_frames,): its index, -1 for none.
    """
    from hearsee.audio.arrays import load_array
    from hearsee.audio.localize import array_geometry

    check_settings(track_sources, track_kwargs,
                   skip=("t", "angle_deg", "weight", "max_sources"))
    tau, ok, w_all = _frame_inputs("localize_moving_sources", tdoa_s, valid, pairs, weight,
                                   locs)
    tt = as_float_array(t, "t", (len(tau),), finite=False)
    arr = load_array(array)
    rows, _, key = _frame_angles(tau, ok, arr, pairs, in_plane, locs)
    angles = np.full(len(tau), np.nan)
    angles[rows] = key
    geo = array_geometry(arr)
    linear = geo.kind == "linear"
    tracks, which = track_sources(tt, angles, w_all, max_sources,
                                  **{"span_deg": 180.0 if linear else 360.0, **track_kwargs})
    A = linear_design(arr, pairs) if linear else None

    def path(tracked: NDArray) -> list[float | None]:
        """A track's azimuths (deg); a linear array's from its tracked sines
        (:func:`linear_azimuth`, each frame's twin chosen by the path's last azimuth)."""
        if A is None:
            return [float(a) for a in tracked]
        out: list[float | None] = []
        prev = None
        for k in tracked:
            az = linear_azimuth(float(k), A, arr, pairs, prev)
            prev = prev if az is None else az
            out.append(az)  # (a vertical pair: None, no azimuth)
        return out

    sources = []
    for tr in tracks:
        last = tr.frames[-TRACK_LAST_FRAMES:]
        sources.append({
            **_direction(np.median(tau[last], axis=0), arr, pairs, in_plane),
            "share": tr.share,
            "n_frames": len(tr.frames),
            "t_start_s": float(tr.t[0]),
            "t_end_s": float(tr.t[-1]),
            "path": {"t_s": [float(v) for v in tr.t], "azimuth_deg": path(tr.angle_deg)},
        })
    return sources, which
