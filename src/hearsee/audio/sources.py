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

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hearsee.config import as_float_array, check_settings, finite_number, whole_number
from hearsee.errors import ConfigError

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


def _wrap(a: NDArray | float) -> NDArray | float:
    """Degrees wrapped to ``(-180, 180]``."""
    return 180.0 - (180.0 - np.asarray(a)) % 360.0


def _circular_mean(az: NDArray, w: NDArray) -> tuple[float, float]:
    """Weighted circular mean and standard deviation (degrees) of azimuths ``az``."""
    z = np.sum(w * np.exp(1j * np.radians(az))) / np.sum(w)
    r = min(float(abs(z)), 1.0)
    # (max: log(1.0) is -0.0 for one frame, and the JSON said "spread_deg": -0.0)
    std = float(np.degrees(np.sqrt(max(0.0, -2.0 * np.log(r))))) if r > 0 else 180.0
    return float(_wrap(np.degrees(np.angle(z)))), std


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
    d = _wrap(grid)  # (the kernel's offsets on the circle)
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
        left[np.abs(_wrap(grid - grid[g])) < sep] = 0.0
    radius = sep / 2.0
    clusters = []
    for _ in range(20):  # mean shift of every peak within its radius, until they settle
        moved = []
        for p in peaks:
            near = np.abs(_wrap(az - p)) < radius
            moved.append(_circular_mean(az[near], w[near])[0] if np.any(w[near] > 0) else p)
        done = all(abs(_wrap(a - b)) < 1e-6 for a, b in zip(moved, peaks, strict=True))
        peaks = moved
        if done:
            break
    kept: list[float] = []  # (two maxima the shifts brought within min_separation: one)
    for p in peaks:
        if all(abs(_wrap(p - q)) >= sep for q in kept):
            kept.append(p)
    peaks = kept[:max_sources]  # (the highest maxima first)
    if peaks:
        dist = np.abs(_wrap(az[:, None] - np.array(peaks)[None, :]))  # (frames, peaks)
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
    from hearsee.audio.localize import array_geometry, localize_tdoa

    check_settings(direction_clusters, cluster_kwargs,
                   skip=("angle_deg", "weight", "max_sources"))
    tau = as_float_array(tdoa_s, "tdoa_s", finite=False)
    ok = np.asarray(valid)
    if ok.dtype != bool:  # (text or numbers read as bools: "no" was a valid frame)
        raise ConfigError(f"valid must hold one bool per frame, got {valid!r:.60}")
    if tau.ndim != 2 or ok.shape != (tau.shape[0],) or tau.shape[1] != len(pairs):
        raise ConfigError(f"localize_sources needs tdoa_s (n_frames, {len(pairs)}) and valid "
                          f"(n_frames,), got {tau.shape} and {ok.shape}")
    w_all = np.ones(len(tau)) if weight is None else as_float_array(weight, "weight",
                                                                         finite=False)
    if w_all.shape != ok.shape:
        raise ConfigError(f"weight must hold one number per frame ({len(ok)}), got shape "
                          f"{w_all.shape}")
    if locs is not None and len(locs) != len(tau):
        raise ConfigError(f"locs must hold one localization (or None) per frame ({len(tau)}), "
                          f"got {len(locs)}")
    arr = load_array(array)
    geo = array_geometry(arr)
    near = bool(in_plane) and geo.kind == "planar"  # (as localize_recording's frames)
    rows, angle, key = [], [], []  # (the frames' angles, and what is clustered)
    for n in np.flatnonzero(ok & np.all(np.isfinite(tau), axis=1)):
        loc = (localize_tdoa(tau[n], arr, pairs, near_field=near, in_plane=in_plane)
               if locs is None else locs[n])
        if loc is None:
            continue
        if geo.kind == "linear":  # (any axis: a vertical one has no azimuth, a tilted one
            # puts every cone that misses the horizontal plane on its own azimuth)
            a, k = _from_broadside(loc.extra["cos_theta"])
        elif loc.azimuth_deg is not None and np.isfinite(loc.azimuth_deg):
            a = k = loc.azimuth_deg
        else:
            continue
        rows.append(n)
        angle.append(a)
        key.append(k)
    rows_a = np.array(rows, dtype=int)
    clusters = direction_clusters(np.array(key, dtype=float), w_all[rows_a], max_sources,
                                  **cluster_kwargs)
    which = np.full(len(tau), -1)
    sources = []
    for k, c in enumerate(clusters):
        frames = rows_a[c.frames]
        which[frames] = k
        sources.append({
            **_direction(np.median(tau[frames], axis=0), arr, pairs, in_plane),
            "share": c.share,
            "n_frames": c.n_frames,
            "spread_deg": _circular_mean(np.array(angle)[c.frames], w_all[frames])[1],
        })
    return sources, which


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
