"""Microphones + one camera: the 3D position of a nearby sound source (thesis 5.3, 5.4).

Reconstruction (the thesis's ch. 5 text is lost; the project's design
notes, ``../shared/design/reconstruction.md``, lie outside this repository; the literature
followed is cited below).

**With camera calibration (5.4, figs. 5.12-5.17).** The image point ``(u, v)`` of the source fixes
a ray from the camera centre ``o`` along ``d`` (lens distortion removed with the calibrated
intrinsics of :class:`hearsee.vision.camera.Camera`). Every microphone pair (i, j) adds an ITD
equation; along the ray ``p(s) = o + s d`` its residual is::

    F_k(s) = (|p(s) - m_i| - |p(s) - m_j|) / c - tdoa_k

and the source sits where ``J(s) = sum_k F_k(s)^2`` (the thesis's F1^2 + F2^2 for three
microphones) is smallest. :func:`locate_on_ray` evaluates J on a log-spaced grid of ranges, then
refines the best grid point with a bounded Brent search (scipy ``minimize_scalar``) -- the ITD
equations are non-convex along the ray far from the source, so a 1-D global search followed by
local refinement is both robust and cheap. The fix comes with a covariance: along the ray from
the curvature of J (Gauss-Newton, ``var(s) = sigma_tdoa^2 / sum_k F_k'(s)^2``), across it from the
pixel noise (``s * sigma_px / f``). That covariance is the measurement noise R of the
constant-acceleration filter (:class:`hearsee.audio.tracking.MotionKalman`, thesis 5.4.3) or of
the constant-velocity :class:`RayTracker`: a single fix's range scatters by several centimetres
in a room (early reflections, TDOA noise; ~0 median, not an offset), and at walking speed the
range changes slowly, so averaging many frames is what brings the 3D error down
(``bench/tracking.py`` part B). :func:`track_on_rays` and the stream run
:class:`RayTdoaTracker` by default, which fuses the image point and each pair's TDOA as
separate measurements (each TDOA with its own gate) and uses the fix to gate the frame and to
start the track.

**The mounting must be measured, not guessed.** The range along the ray comes from the parallax
between camera and array, so an error in the camera's position or pan moves every fix along
its ray, and the ITDs cannot tell: a planar array measures the azimuth and little else, and the
wrong ray still crosses the measured azimuth somewhere. ``bench/mounting.py`` (seed 0, 8 walks
of 2 s per condition, talkers 0.5-2 m away, RT60 0.3 s room or free field, exact pixels + 1 px
noise; median error of the per-frame fixes) measures it: with the camera 0.2 m beside the
three-mic preset, where the true mounting gives 0.06-0.10 m at 20 dB, a camera position told 5
cm off sideways gives 0.26-0.40 m, 10 cm 0.53-0.79 m, 30 cm 1.7-2.3 m, 10 cm along x or z
0.12-0.19 m, and a pan 5 deg off 0.42-2.4 m; with the camera 0.5 m aside (true 0.025-0.04 m)
10 cm gives 0.26 m and 5 deg 0.22-0.46 m. The fixes' median ITD residual moves by at most
0.06 sample, while between conditions the true mounting's own ranges from 0.03 (white noise) to
0.71 sample (10 dB voice), so no run-level check can flag a wrong mounting. Only gross errors
on the 0.2 m rig show: the camera told on the other side of the array (+0.49-0.87 sample,
96-99.5 % of the fixes rejected by ``max_residual_samples``) or a pan told 10 deg too far
toward the camera's side, +y (+0.20-0.44 sample, 24-77 % rejected); on the 0.5 m rig not even
those.

**Without camera calibration (5.3, figs. 5.7-5.11).** The camera's intrinsics and its pose
relative to the microphones are unknown; the image point still carries relative direction
information. :class:`AudioVisualRegressor` learns the mapping (ITDs, image point) -> 3D position
with a multi-layer perceptron (scikit-learn ``MLPRegressor`` behind a ``StandardScaler``), trained
on simulated examples (:func:`simulate_av_samples`) -- the thesis's neural network, 5.3.3.

Frames: positions are in the ARRAY frame (REP 103: x forward, y left, z up, metres). The camera's
mounting is ``p_optical = R @ p_array + t`` (:func:`hearsee.vision.camera.camera_pose` builds it
from a position and pan/tilt on the head).

References: Knapp & Carter (1976) for the ITD model; Hartley & Zisserman, *Multiple View
Geometry* (2003), ch. 6 for the back-projected ray; Brent (1973) for the bounded 1-D search.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize_scalar
from sklearn.base import BaseEstimator, RegressorMixin

from hearsee.audio.arrays import MicArray
from hearsee.audio.localize import as_tdoas
from hearsee.audio.tracking import MotionKalman, _covariance
from hearsee.config import as_rng, finite_number, is_real, real_entries, whole_number
from hearsee.errors import EstimationError, GeometryError, RegressorNotFittedError
from hearsee.geometry import as_points
from hearsee.vision.camera import Camera, camera_pose

#: TDOA noise (s) that :func:`locate_on_ray` assumes by default for a fix's covariance, and
#: the one the stream's constant-acceleration 3D tracker (``motion_model="ca"``) was tuned with;
#: the constant-velocity :class:`RayTracker` uses :data:`RAY_SIGMA_TDOA_S` instead
FIX_SIGMA_TDOA_S = 2e-5

#: A camera-ray fix whose RMS ITD residual exceeds this many ``sigma_tdoa_s`` (taken as at
#: least 1 us) is flagged ``consistent=False`` (:class:`RayFix`); as the multi-pose solver's
#: :data:`hearsee.audio.active.MAX_RESIDUAL_SIGMAS`.
MAX_RAY_RESIDUAL_SIGMAS = 6.0

#: TDOA noise (s) behind the camera-ray fixes' covariance for :class:`RayTracker`'s defaults,
#: at any sample rate. Chosen on the seed-100 walks of ``bench/tracking.py`` part B (three-mic
#: preset + camera 0.2 m aside, RT60 0.3 s, 20 dB; tracked median error): at 16 kHz, synthetic
#: male voice, 8 us 6.5 cm, 4 us 9.5 cm. From 2026-11-24 (third session) 48 kHz used 4 us,
#: which suited the synthetic voice (1.4 cm; 8 us 2.2 cm) because its aspiration noise fills
#: the band up to 24 kHz -- but not real speech, which has little energy above 8 kHz: CMU
#: ARCTIC speech at 48 kHz 7.5 cm with 4 us, 4.1 cm with 8 us (16 walks; at 16 kHz 6.9 cm), a
#: real 48 kHz recording 7.9 vs 8.4 cm. So 8 us at every rate (held-out seed 0, 32 walks, 48
#: kHz, 4 -> 8 us: ARCTIC 10.3 -> 9.8 cm, the real recording 8.1 -> 5.5 cm, synthetic voice 1.5
#: -> 3.0 cm); set ``sigma_tdoa_s`` lower only for sources known to be broadband.
RAY_SIGMA_TDOA_S = 8e-6

#: Factor on the position covariance that :class:`RayTdoaTracker` reports (``position_cov``,
#: the ``covariance`` of ``hearsee track``'s 3D updates) over its filter's own. The filter
#: takes every frame's TDOAs as independent news, but consecutive frames (64 ms at a 16 ms hop)
#: share 3/4 of their samples and a room's reflections bias them alike, and three pairs of
#: three microphones hold two independent TDOAs: its own covariance was overconfident. Measured
#: 2026-11-27 on ``bench/tracking.py`` part B's walks (three-mic + camera 0.2 m aside, RT60 0.3
#: s, 20 dB, synthetic male voice, 2-s walks, half turning by 60-150 deg; 95 % chi-square
#: coverage of the 3D error after 0.35 s): the filter's own covariance held the truth for
#: 0.60-0.62 of the frames (dev seeds 6 / 7; an 8-walk first look, seed 5: 0.46), 4 x it for
#: 0.94 pooled; held out (seeds 8 / 9, 24 walks each, rule written before): 0.65 / 0.70 -> 0.92
#: / 0.94. Not everywhere (after the choice): seeds 11 / 12 at 20 dB 0.61-0.63 -> 0.92 / 0.87;
#: the same walks in free field 0.96 (seed 10); at 10 dB in the room 0.25-0.40 -> 0.57-0.75
#: (seeds 8-12), still overconfident -- a scale that grows with the frames' closure (the
#: TDOAs' own disagreement, as :func:`hearsee.audio.localize.position_tdoa_std`) raised that
#: to 0.85-0.89 but failed both of its rules (35th session's closing note). The scale leaves the
#: filter alone -- its gains and gates are those of R, Q and P0 all scaled by the same factor
#: -- so every estimate is unchanged. One room and one voice: a calibration, not a model.
RAY_COVARIANCE_SCALE = 4.0

#: :class:`RayTdoaTracker` starts anew at a frame's fix when its prediction to the frame is
#: less certain than the fix by more than this factor in variance in every direction (the
#: smallest generalised eigenvalue of the predicted position covariance over the fix's): the
#: prediction then holds at most 1 % of the fix's information in any direction, and linearised
#: at a point that far off, the image point's and the TDOAs' EKF updates put the track metres
#: from an exact fix (a walker who stopped while the camera lost them, exact measurements, 10 s
#: gap: 3.5 m, 100 s: 668 m, where :class:`RayTracker` fused the fix to 0.1 mm; found by a
#: review helper, 2026-12-07). While tracking, the ratio stays near 1 (at most 1.1 on
#: free-field walks at 0 and 20 dB). The gap it takes depends on the walk (6 s there) and on
#: how it is stepped: the white acceleration is per step, so a tracker predicted through every
#: 16-ms frame of the gap (:func:`track_on_rays`, the stream) grows its covariance far slower
#: than one fed only when there is a measurement, and its gate refuses the first fixes instead.
RAY_LOST_VARIANCE_RATIO = 100.0

__all__ = [
    "AudioVisualRegressor",
    "AudioVisualRig",
    "FIX_SIGMA_TDOA_S",
    "MAX_RAY_RESIDUAL_SIGMAS",
    "RAY_COVARIANCE_SCALE",
    "RAY_LOST_VARIANCE_RATIO",
    "RAY_SIGMA_TDOA_S",
    "RayFix",
    "RayTdoaTracker",
    "RayTrack",
    "RayTracker",
    "RegressorNotFittedError",
    "locate_on_ray",
    "feed_tracker",
    "frame_fix",
    "ray_residuals",
    "simulate_av_samples",
    "track_on_rays",
]


@dataclass(frozen=True, eq=False)
class AudioVisualRig:
    """A microphone array and a camera rigidly mounted together.

    Parameters
    ----------
    array : MicArray
        Microphones (array frame); anything else is a GeometryError (a preset name:
        :func:`hearsee.audio.arrays.load_array` first).
    camera : Camera
        Calibrated pinhole camera (intrinsics, distortion); anything else a GeometryError.
    R, t : arrays (3, 3), (3,)
        Mounting: ``p_optical = R @ p_array + t`` (metres).
    """

    array: MicArray
    camera: Camera
    R: NDArray
    t: NDArray

    def __post_init__(self) -> None:
        # (any object was taken: AudioVisualRig("three-mic", None, I, 0) built, and the first
        # fix failed with an AttributeError; as StereoRig, the parts must be what they are)
        if not isinstance(self.array, MicArray):
            raise GeometryError(f"rig array must be a MicArray (hearsee.audio.arrays.load_array "
                                f"makes one of a preset name or a file), got "
                                f"{type(self.array).__name__} {self.array!r:.40}")
        if not isinstance(self.camera, Camera):
            raise GeometryError(f"rig camera must be a Camera (hearsee.vision.camera), got "
                                f"{type(self.camera).__name__} {self.camera!r:.40}")
        # (numpy read text as the numbers it spells and True as 1)
        # (copies, frozen: the rig must not share -- or freeze -- the caller's arrays)
        R = np.array(self.R, dtype=float) if real_entries(self.R) else np.zeros(0)
        t = np.array(self.t, dtype=float).reshape(-1) if real_entries(self.t) else np.zeros(0)
        if (R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-6)
                or not np.linalg.det(R) > 0):  # (a reflection, det -1, mirrors every ray)
            raise GeometryError("rig mounting R must be a 3x3 rotation matrix")
        if t.shape != (3,) or not np.all(np.isfinite(t)):
            raise GeometryError("rig mounting t must be 3 finite numbers (metres)")
        R.setflags(write=False)
        t.setflags(write=False)
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "t", t)

    @classmethod
    def mounted(cls, array: MicArray, camera: Camera, position_m: ArrayLike = (0.0, 0.0, 0.0),
                pan_deg: float = 0.0, tilt_deg: float = 0.0) -> AudioVisualRig:
        """Camera centre at ``position_m`` in the array frame, looking along +x turned by
        ``pan_deg`` (toward +y) and ``tilt_deg`` (up)."""
        R, t = camera_pose(position_m, pan_deg, tilt_deg)
        return cls(array, camera, R, t)

    @property
    def camera_centre(self) -> NDArray:
        """Optical centre in the array frame, metres."""
        return -self.R.T @ self.t

    def to_optical(self, points: ArrayLike) -> NDArray:
        """Array-frame points ``(N, 3)`` -> camera optical frame (GeometryError for anything
        but numbers ``(..., 3)``: :func:`hearsee.geometry.as_points`)."""
        return np.atleast_2d(as_points(points)) @ self.R.T + self.t

    def project(self, points: ArrayLike) -> NDArray:
        """Pixels ``(N, 2)`` of array-frame points ``(N, 3)`` (NaN behind the camera)."""
        return self.camera.project(self.to_optical(points))

    def rays(self, uv: ArrayLike) -> tuple[NDArray, NDArray]:
        """Back-projected rays of pixels ``(N, 2)``: (origin (3,), unit directions (N, 3)),
        array frame. Pixels that are no numbers or not ``(N, 2)``: the camera's GeometryError
        (:meth:`hearsee.vision.camera.Camera.pixel_rays`)."""
        d_opt = self.camera.pixel_rays(uv)
        return self.camera_centre, d_opt @ self.R  # R^T d for each row


def _check_rig(rig: Any, what: str) -> AudioVisualRig:
    """``rig`` when it is an :class:`AudioVisualRig`, else a GeometryError naming ``what`` (None
    or a preset name raised a builtin AttributeError at the first use of ``rig.array``,
    2026-12-02)."""
    if not isinstance(rig, AudioVisualRig):
        raise GeometryError(f"{what} needs an AudioVisualRig (microphones + calibrated camera, "
                            f"e.g. AudioVisualRig.mounted), got {type(rig).__name__} "
                            f"{rig!r:.40}")
    return rig


@dataclass
class RayFix:
    """A 3D fix from one image point and the ITDs.

    Attributes
    ----------
    position_m : array (3,)
        Estimated source position, array frame, metres.
    range_m : float
        Distance from the camera centre along the ray, metres.
    residual_s : float
        RMS of the ITD residuals ``F_k`` at the fix, seconds.
    covariance : array (3, 3)
        Position covariance, m^2 (along-ray from the ITD noise, across from the pixel noise).
    direction : array (3,)
        Unit ray direction (array frame).
    alternatives : list of RayFix
        Other local minima along the ray that explain the ITDs almost as well.
    consistent : bool
        ``residual_s`` is at most :data:`MAX_RAY_RESIDUAL_SIGMAS` x the fix's
        ``sigma_tdoa_s`` (at least 1 us of it): False when the ITDs meet the ray nowhere within
        the search (TDOAs of the other sign, another source's, a reflection's), and the fix is
        only the least-bad point, often at the search's end (until 2026-12-03 nothing said so).
    """

    position_m: NDArray
    range_m: float
    residual_s: float
    covariance: NDArray
    direction: NDArray
    alternatives: list[RayFix] = field(default_factory=list)
    consistent: bool = True


def ray_residuals(array: MicArray, origin: ArrayLike, direction: ArrayLike, s: ArrayLike,
                  tdoa_s: ArrayLike, pairs: Sequence[tuple[int, int]] | None = None) -> NDArray:
    """ITD residuals ``F_k(s)`` (seconds) of the points ``origin + s * direction``.

    ``origin`` and ``direction`` (3,) in the array frame (metres), ``s`` one range or (n,)
    ranges in metres, ``tdoa_s`` one TDOA per pair of ``pairs`` (default all pairs of
    ``array``), seconds; returns ``(n, n_pairs)``. ``sum(F**2, axis=1)`` is the cost J(s)
    plotted in the thesis's figs. 5.14-5.16. Arguments that are no numbers (numpy read text as
    the numbers it spells, True as 1) or of other shapes (numpy's broadcast ValueError) are a
    GeometryError, and so are a zero or non-finite ``direction`` and an ``array`` that is no
    MicArray.
    """
    if not isinstance(array, MicArray):  # (a builtin AttributeError, 2026-12-02)
        raise GeometryError(f"ray_residuals: array must be a MicArray (hearsee.audio.arrays."
                            f"load_array), got {type(array).__name__} {array!r:.40}")
    for name, v in (("origin", origin), ("direction", direction), ("s", s),
                    ("tdoa_s", tdoa_s)):
        if not real_entries(v):
            raise GeometryError(f"ray_residuals: {name} must hold numbers, got {v!r:.80}")
    o, d = np.asarray(origin, dtype=float), np.asarray(direction, dtype=float)
    if o.shape != (3,) or d.shape != (3,):
        raise GeometryError(f"ray_residuals: origin and direction must be [x, y, z] each, shape "
                            f"(3,), got {o.shape} and {d.shape}")
    if not (np.all(np.isfinite(o)) and np.all(np.isfinite(d)) and np.linalg.norm(d) > 0):
        # (a zero direction put every range at the origin and gave residuals without a word)
        raise GeometryError(f"ray_residuals: origin must be finite and direction a finite, "
                            f"non-zero vector, got {o.tolist()} and {d.tolist()}")
    if np.ndim(s) > 1:
        raise GeometryError(f"ray_residuals: s must be one range or ranges (n,) in metres, got "
                            f"shape {np.shape(s)}")
    prs = array.checked_pairs(pairs)
    z = np.asarray(tdoa_s, dtype=float).reshape(-1)
    if z.size != len(prs):
        raise GeometryError(f"ray_residuals: got {z.size} TDOAs for {len(prs)} microphone pairs")
    return _ray_residuals(array, o, d, s, z, prs)


def _ray_residuals(array: MicArray, origin: ArrayLike, direction: ArrayLike, s: ArrayLike,
                   tdoa_s: ArrayLike, pairs: Sequence[tuple[int, int]] | None) -> NDArray:
    """:func:`ray_residuals` of checked arguments (the fix's search and refinement call it per
    grid point)."""
    o = np.asarray(origin, dtype=float)
    d = np.asarray(direction, dtype=float)
    ss_ = np.atleast_1d(np.asarray(s, dtype=float))
    pts = o[None, :] + ss_[:, None] * d[None, :]
    return array.tdoa(pts, list(pairs) if pairs is not None else None) - np.asarray(tdoa_s, float)


def _ray_range(range_m: Any, *, equal_ok: bool = False) -> tuple[float, float]:
    """``range_m`` (near, far) of a search along a camera ray, metres, as floats;
    EstimationError unless 0 < near < far (near <= far where ``equal_ok``), both finite."""
    try:
        near, far = range_m[0], range_m[1]
    except (TypeError, IndexError, KeyError):
        near = far = None
    # (float() read ("0.1", "10") as numbers and True as 1 m)
    if not (is_real(near) and is_real(far) and 0 < near and (near <= far if equal_ok
                                                             else near < far)):
        raise EstimationError(f"range_m must satisfy 0 < near {'<=' if equal_ok else '<'} far "
                              f"(finite), got {range_m!r}")
    return float(near), float(far)


def _image_point(uv: ArrayLike, finite: bool) -> NDArray:
    """The image point ``(u, v)`` in pixels as a float array (2,), or an EstimationError: two
    real numbers (:func:`hearsee.config.real_entries`; numpy read ("320", "240") as a pixel and
    True as 1, and text that spells no number was a builtin ValueError), finite where
    ``finite``. The image-point check of :func:`locate_on_ray` and
    :meth:`RayTdoaTracker.update_measurements`."""
    p = np.asarray(uv, dtype=float).reshape(-1) if real_entries(uv) else None
    if p is None or p.shape != (2,) or (finite and not np.all(np.isfinite(p))):
        raise EstimationError(f"the image point must be two {'finite ' if finite else ''}pixel "
                              f"coordinates (u, v), got {uv!r:.80}")
    return p


#: The most ranges :func:`locate_on_ray` scans along the camera ray (its grid is refined
#: around the best anyway: 256 by default).
MAX_RAY_GRID = 100_000


def locate_on_ray(
    rig: AudioVisualRig,
    uv: ArrayLike,
    tdoa_s: ArrayLike,
    pairs: Sequence[tuple[int, int]] | None = None,
    range_m: tuple[float, float] = (0.1, 10.0),
    n_grid: int = 256,
    sigma_tdoa_s: float = FIX_SIGMA_TDOA_S,
    sigma_px: float = 1.0,
    max_candidates: int = 3,
) -> RayFix:
    """Fuse an image point with the ITDs: the point on the camera ray that best explains them.

    Parameters
    ----------
    rig : AudioVisualRig
        Calibrated camera + microphones.
    uv : array (2,)
        Image point of the source, pixels.
    tdoa_s : array (n_pairs,)
        Measured ``t_i - t_j`` in seconds for ``pairs`` (default: all pairs of the array);
        finite, and within twice each pair's physical maximum plus 0.1 ms (EstimationError).
    range_m : (near, far)
        Search interval along the ray, metres from the camera centre.
    n_grid : int
        Log-spaced grid points of the global search, 2 to :data:`MAX_RAY_GRID`.
    sigma_tdoa_s, sigma_px : float
        Measurement noise used for the returned covariance (seconds, pixels).
    max_candidates : int
        Local minima of J examined.

    Returns
    -------
    RayFix
        The best fix; ``alternatives`` holds other local minima whose ITD residual is within
        4x the best or ``sigma_tdoa_s``, whichever is larger (an exact best fix would keep
        none) (a planar array cannot tell a point from its mirror image in the array
        plane, so a ray that crosses that plane has two exact solutions) -- a tracker picks
        among them with its prediction.
    """
    # (a number such as pairs=5 raised list()'s builtin TypeError; as ray_residuals)
    prs = _check_rig(rig, "locate_on_ray").array.checked_pairs(pairs)
    z = as_tdoas(tdoa_s, len(prs), EstimationError)
    if not np.all(np.isfinite(z)):
        raise EstimationError("TDOAs must be finite to fuse with the camera ray")
    bound = 2.0 * rig.array.max_tdoa(prs) + 1e-4
    if np.any(np.abs(z) > bound):
        # (50x the physical maximum gave a confident fix at the near end of the ray; a GCC
        # peak is within its lag bound plus a sample, so only a unit mistake reaches here)
        k = int(np.argmax(np.abs(z) / bound))
        raise EstimationError(
            f"TDOA of pair {prs[k]} is {z[k]:.3g} s, more than twice that pair's physical "
            f"maximum {rig.array.max_tdoa([prs[k]])[0]:.3g} s: TDOAs are seconds (not samples "
            "or milliseconds)")
    p = _image_point(uv, finite=True)
    near, far = _ray_range(range_m)
    # (10**8 points was a MemoryError: a residual per point and pair)
    n_grid = whole_number("n_grid", n_grid, 2, MAX_RAY_GRID, error=EstimationError)
    max_candidates = whole_number("max_candidates", max_candidates, 1, error=EstimationError)
    sigma_tdoa_s = finite_number("sigma_tdoa_s", sigma_tdoa_s, 0.0, error=EstimationError)
    sigma_px = finite_number("sigma_px", sigma_px, 0.0, error=EstimationError)
    o, d = rig.rays(p[None, :])
    d = d[0]
    grid = np.geomspace(near, far, n_grid)
    J = np.sum(_ray_residuals(rig.array, o, d, grid, z, prs) ** 2, axis=1)
    # every local minimum of the grid is a candidate (e.g. the mirror image of the source in
    # the plane of a planar array when the ray crosses that plane); best first
    interior = np.r_[J[0] <= J[1], (J[1:-1] <= J[:-2]) & (J[1:-1] <= J[2:]), J[-1] <= J[-2]]
    idx = np.flatnonzero(interior)
    idx = idx[np.argsort(J[idx])][:max_candidates]
    fixes = [_refine_on_ray(rig, o, d, z, prs, grid, J, int(k), sigma_tdoa_s, sigma_px, p)
             for k in idx]
    fixes.sort(key=lambda f: f.residual_s)
    best = fixes[0]
    # keep alternatives that explain the ITDs nearly as well as the best one
    tol = max(4.0 * best.residual_s, sigma_tdoa_s)
    best.alternatives = [f for f in fixes[1:] if f.residual_s <= tol]
    return best


def _refine_on_ray(rig: AudioVisualRig, o: NDArray, d: NDArray, z: NDArray,
                   prs: list[tuple[int, int]], grid: NDArray, J: NDArray, k: int,
                   sigma_tdoa_s: float, sigma_px: float, uv: NDArray) -> RayFix:
    """The fix at the ``k``-th grid minimum of J along the ray ``o + s d`` of pixel ``uv``,
    refined, with its covariance (m^2): the TDOA noise moves it along the ray by
    ``sigma_tdoa_s / |dF/ds|``, and a pixel's noise moves the ray sideways and, through the
    TDOA surface the shifted ray meets at another range, along it too (``dp/du = s dd/du +
    d ds/du``, ``ds/du = -(dF/ds . dF/du) / |dF/ds|^2``: the implicit function F(s; u, v) =
    0). Before 2026-12-02 the pixel moved it sideways only, which made the fixes
    overconfident wherever the TDOA noise is small (0.5 us, 1 px, camera 0.2 m aside: mean
    NEES 7.2 instead of 3, found by an audit)."""
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]

    def cost(s: float) -> float:
        return float(np.sum(_ray_residuals(rig.array, o, d, [s], z, prs) ** 2))

    s_hat = float(grid[k])
    if hi > lo:
        res = minimize_scalar(cost, bounds=(lo, hi), method="bounded", options={"xatol": 1e-6})
        if res.fun <= J[k]:
            s_hat = float(res.x)
    F = _ray_residuals(rig.array, o, d, [s_hat], z, prs)[0]
    h = 1e-4 * max(s_hat, 1e-2)
    dF = (_ray_residuals(rig.array, o, d, [s_hat + h], z, prs)[0]
          - _ray_residuals(rig.array, o, d, [s_hat - h], z, prs)[0]) / (2 * h)
    g = max(float(dF @ dF), 1e-30)
    span2 = (grid[-1] - grid[0]) ** 2  # (no parallax: the range is only known to the search)
    var_s = min(sigma_tdoa_s**2 / g, span2)
    cov = var_s * np.outer(d, d)
    if sigma_px > 0:
        hp = 0.5  # pixels: the rays of uv +- hp along each image axis
        offsets = np.array([[hp, 0.0], [-hp, 0.0], [0.0, hp], [0.0, -hp]])
        # (a probe the lens model cannot reach -- next to the corner a radial calibration
        # folds back before -- is a NaN ray: that side's difference is taken from uv's own
        # ray d instead; it raised the camera's GeometryError for a pixel that sees the source)
        d4 = rig.camera.pixel_rays(np.asarray(uv, dtype=float)[None, :] + offsets,
                                   unreachable="nan") @ rig.R
        lat = []
        for a in (0, 2):
            ends = [(d4[a], hp), (d4[a + 1], -hp)]
            (dp, up), (dm, um) = ((e, w) if np.all(np.isfinite(e)) else (d, 0.0)
                                  for e, w in ends)
            if up == um:  # (neither side reaches: no pixel noise along this axis)
                continue
            dd = (dp - dm) / (up - um)  # ray direction per pixel
            dFdu = (_ray_residuals(rig.array, o, dp, [s_hat], z, prs)[0]
                    - _ray_residuals(rig.array, o, dm, [s_hat], z, prs)[0]) / (up - um)
            ds = -float(dF @ dFdu) / g
            ds = float(np.clip(ds, -np.sqrt(span2) / sigma_px, np.sqrt(span2) / sigma_px))
            lat.append(s_hat * dd + ds * d)
        cov = cov + sigma_px**2 * sum(np.outer(j, j) for j in lat)
    rms = float(np.sqrt(np.mean(F**2)))
    return RayFix(o + s_hat * d, s_hat, rms, cov, d,
                  consistent=rms <= MAX_RAY_RESIDUAL_SIGMAS * max(sigma_tdoa_s, 1e-6))


# ----------------------------------------------------------------- tracking along the rays
class RayTracker(MotionKalman):
    """Constant-velocity Kalman filter on the 3D position of a source on the camera's rays.

    The camera fixes the direction to the source in every frame almost exactly (a pixel of
    noise is a few millimetres across the ray at 1-2 m); the range along the ray comes from the
    ITDs and scatters by several centimetres per frame (early reflections, TDOA noise). At
    walking speed the range changes slowly, so the filter accumulates that evidence over many
    frames: state ``[x, vx, y, vy, z, vz]`` (m, m/s; filterpy's ``order_by_dim`` layout), white-
    acceleration process noise (``Q_discrete_white_noise``), each fix fused with its own
    covariance from :func:`locate_on_ray` (elongated along the ray), and fixes whose innovation
    fails a chi-square gate are rejected (a reflection that captured a GCC peak).

    A :class:`hearsee.audio.tracking.MotionKalman` (same ``update(t, position, R, candidates)``,
    gating, restart, ``position``, ``velocity``, ``position_cov``) with the constant-velocity
    model instead of constant acceleration: it averages over more frames
    (``bench/tracking.py`` part B measures both on the same fixes). Fixes with a non-finite
    covariance are ignored.

    Parameters
    ----------
    sigma_accel : float
        Standard deviation of the white acceleration, m/s^2 (0.2 chosen on the seed-100 walks
        of ``bench/tracking.py`` part B, with fixes made with ``sigma_tdoa_s=8e-6``), held
        constant over each prediction step (filterpy's ``Q_discrete_white_noise``): over a gap
        the covariance grows less when it is predicted in many short steps than in one.
    gate_prob : float
        Chi-square gate probability (3 degrees of freedom).
    max_rejects : int
        Consecutive gated fixes after which the track restarts at the newest fix.
    init_vel_sigma : float
        Initial velocity standard deviation, m/s.

    References: Bar-Shalom, Li & Kirubarajan, *Estimation with Applications to Tracking and
    Navigation* (2001), ch. 6 (white-acceleration model) and 5.4 (gating).
    """

    _DIM = 6
    estimates_acceleration = False  # (constant velocity: its acceleration is the model's 0)
    _POS = np.array([0, 2, 4])
    _VEL = np.array([1, 3, 5])

    def __init__(self, sigma_accel: float = 0.2, gate_prob: float = 0.99, max_rejects: int = 4,
                 init_vel_sigma: float = 1.0) -> None:
        # (an infinite sigma_accel made the state NaN, True was 1 m/s^2, text and
        # max_rejects='a' builtin errors; init_vel_sigma and max_rejects: MotionKalman's rules)
        finite_number("sigma_accel", sigma_accel, 0.0, lo_open=True, error=EstimationError)
        if not (is_real(gate_prob) and 0 < gate_prob < 1):
            raise EstimationError(f"gate_prob must be in (0, 1), got {gate_prob!r}")
        self.sigma_accel = float(sigma_accel)
        super().__init__(sigma_meas_m=0.05, gate_prob=gate_prob, max_rejects=max_rejects,
                         init_vel_sigma=init_vel_sigma)
        self.H = np.zeros((3, 6))
        self.H[[0, 1, 2], self._POS] = 1.0

    def _model(self, dt: float) -> tuple[NDArray, NDArray]:
        """Constant velocity with white acceleration over ``dt`` seconds: ``(F, Q)``."""
        from filterpy.common import Q_discrete_white_noise

        return (np.kron(np.eye(3), np.array([[1.0, dt], [0.0, 1.0]])),
                Q_discrete_white_noise(dim=2, dt=dt, var=self.sigma_accel**2, block_size=3,
                                       order_by_dim=True))

    def _start(self, z: NDArray, R: NDArray) -> None:
        self.x = np.zeros(6)
        self.x[self._POS] = z
        self.P = np.diag(np.tile([1.0, self.init_vel_sigma**2], 3))
        self.P[np.ix_(self._POS, self._POS)] = R
        self.initialized = True
        self.n_rejects = 0
        self._velocity_known = False

    def update(self, t: float, position: ArrayLike | None = None, R: ArrayLike | None = None,
               candidates: Sequence[tuple[ArrayLike, ArrayLike | None]] | None = None) -> bool:
        """One frame: predict to ``t`` (seconds) and fuse the fix ``position`` (m, array frame)
        with covariance ``R`` (3x3, m^2; default 5 cm per axis); ``candidates`` are ambiguous
        alternatives (see :meth:`MotionKalman.update`). Returns True when a fix was fused."""
        try:
            extra = [] if candidates is None else list(candidates)
        except TypeError:  # (a number: list()'s builtin TypeError; MotionKalman's message)
            return super().update(t, position, R, candidates)

        def void(c: Any) -> bool:
            """A (position, R) candidate whose covariance is numbers but not all finite.
            Anything else is passed on for MotionKalman's checks: a covariance that is no
            numbers (np.isfinite's builtin TypeError), a candidate that is no pair ([x, y, z]
            alone: a builtin 'too many values to unpack', 2026-12-02)."""
            if isinstance(c, str | bytes):
                return False
            try:
                _, Rc = c
            except (TypeError, ValueError):
                return False
            return Rc is not None and real_entries(Rc) and not np.all(np.isfinite(Rc))

        cands = ([] if position is None else [(position, R)]) + extra
        return super().update(t, None, None, [c for c in cands if not void(c)])

    @property
    def acceleration(self) -> NDArray:
        """Zero (constant-velocity model), m/s^2; NaN before the first fix."""
        return np.zeros(3) if self.initialized else np.full(3, np.nan)


class RayTdoaTracker(RayTracker):
    """:class:`RayTracker` fed with the raw measurements instead of the fixes (tight coupling).

    Each frame's image point (pixels) and each pair's TDOA (seconds) are separate measurements
    of an extended Kalman filter on the same constant-velocity state: the pixel through the
    rig's projection (1 px noise, Jacobian by central differences), then each TDOA through
    ``(|p - m_i| - |p - m_j|) / c`` with its own chi-square gate (1 degree of freedom). The
    camera-ray fix of the frame (:func:`locate_on_ray`) still starts the track, restarts it after
    ``max_rejects`` consecutive rejected frames (image point or fix outside its gate, or no TDOA
    inside its own; as :class:`RayTracker` does with gated fixes) or when the prediction holds
    no position beside the fix (:data:`RAY_LOST_VARIANCE_RATIO`), and decides whether the
    frame's TDOAs are used at all (no fix, or a fix that fails the gate: none).

    Why: a reflection that pulls one pair's GCC peak (a few tenths of a sample) moves a fix
    along the ray by centimetres, and the fix's 3-dof gate keeps or drops all three TDOAs
    together; here the one pair falls out of its own gate while the other two still measure the
    range. Because single outliers no longer reach the state, the filter can also average over
    more frames (a lower ``sigma_accel``) without drifting. On the dev walks of
    ``bench/tracking.py`` part B (three-mic preset + camera 0.2 m aside, RT60 0.3 s, 20 dB,
    seeds 100-400, 128 straight walks of 2 s) the pooled median 3D error went from 6.19 cm
    (:class:`RayTracker`, 0.2 m/s^2) to 4.81 cm (this filter, 0.1 m/s^2; paired walk bootstrap
    -1.4 cm [-2.4, -0.4]); on 64 walks that turn by 60-150 deg at once halfway 8.62 -> 7.66 cm.
    The fix-based :class:`RayTracker` gains nothing from 0.1 m/s^2 (6.32 cm). Without the
    per-pair gates the TDOA updates were worse than the fixes (7.04 cm); without the fix gate a
    turn left the track behind (15 cm on the turning walks); the pixel gate (a frame whose image
    point is off counts toward the restart, as a gated fix does) took the turning walks from
    8.31 to 7.66 cm. On held-out seeds 777/778/779 the position gain mostly did not carry over:
    96 straight walks 5.48 -> 5.26 cm (per seed 5.59/5.11/5.73 -> 5.26/5.74/4.66), 96 turning
    walks 7.81 -> 7.82 cm (7.12/11.5/5.80 -> 7.09/9.42/7.40), a tie; the velocity RMSE fell
    on both (0.31 -> 0.25 and 0.58 -> 0.49 m/s). All 224 straight walks: 5.87 -> 5.00 cm
    (-0.9 [-1.7, -0.1]). Real speech at 16 kHz (same rig and room, 16 straight walks per seed;
    2026-11-25, twelfth session): CMU ARCTIC dev seeds 100/200 9.37 cm against
    :class:`RayTracker`'s 6.42 (paired -2.8 [-4.5, -1.0] in the fixes' favour), held-out
    777/778 8.14 against 8.83; the real 'alexa' recording dev 8.98 against 8.59, held-out 6.38
    against 10.86 (+4.2 [+1.0, +7.3] in this filter's favour): no consistent winner, walks
    differ by more than the filters. A looser white acceleration (0.15, 0.2 m/s^2) gave a
    higher median on all four real-speech sets (+0.4 to +1.5 cm; 4 of the 8 paired intervals
    above zero), so real speech does not call for a setting of its own.

    Parameters
    ----------
    rig : AudioVisualRig
        The calibrated camera + microphones whose measurements are fused.
    pairs : list of (i, j), optional
        Microphone pairs of the TDOAs, default all pairs of the array.
    sigma_accel : float
        White acceleration, m/s^2, per prediction step (as :class:`RayTracker`).
    sigma_tdoa_s : float
        Standard deviation of one pair's TDOA, seconds.
    sigma_px : float
        Standard deviation of the image point per axis, pixels.
    gate_prob, pair_gate_prob, pixel_gate_prob : float
        Chi-square gate probabilities of the fix (3 dof), of each TDOA (1 dof) and of the image
        point (2 dof; a detection on someone else). A frame whose image point fails its gate
        fuses nothing; one whose fix fails its gate fuses its image point (which passed its
        own) but none of its TDOAs; either counts toward ``max_rejects``.
    max_rejects, init_vel_sigma :
        As :class:`RayTracker`.
    covariance_scale : float
        Factor of the reported ``position_cov`` over the filter's own ``P`` block
        (:data:`RAY_COVARIANCE_SCALE`; 1 = the filter's own, which was overconfident). The
        filter, its gates and its estimates do not depend on it.

    References: Bar-Shalom, Li & Kirubarajan (2001), ch. 10 (the extended Kalman filter) and 5.4
    (gating); Groves, *Principles of GNSS, Inertial, and Multisensor Integrated Navigation
    Systems* (2013), ch. 14 (tightly coupled integration: ranging measurements into the
    navigation filter rather than position fixes).
    """

    def __init__(self, rig: AudioVisualRig, pairs: Sequence[tuple[int, int]] | None = None,
                 sigma_accel: float = 0.1, sigma_tdoa_s: float = RAY_SIGMA_TDOA_S,
                 sigma_px: float = 1.0, gate_prob: float = 0.99, pair_gate_prob: float = 0.99,
                 pixel_gate_prob: float = 0.9999, max_rejects: int = 4,
                 init_vel_sigma: float = 1.0,
                 covariance_scale: float = RAY_COVARIANCE_SCALE) -> None:
        _check_rig(rig, "RayTdoaTracker")
        super().__init__(sigma_accel=sigma_accel, gate_prob=gate_prob, max_rejects=max_rejects,
                         init_vel_sigma=init_vel_sigma)
        # (inf was taken and True was 1; text raised builtin TypeErrors)
        finite_number("sigma_tdoa_s", sigma_tdoa_s, 0.0, lo_open=True, error=EstimationError)
        finite_number("sigma_px", sigma_px, 0.0, lo_open=True, error=EstimationError)
        self.covariance_scale = finite_number("covariance_scale", covariance_scale, 0.0,
                                              lo_open=True, error=EstimationError)
        if not all(is_real(g) and 0 < g < 1 for g in (pair_gate_prob, pixel_gate_prob)):
            raise EstimationError(f"pair_gate_prob and pixel_gate_prob must be in (0, 1), got "
                                  f"{pair_gate_prob!r} and {pixel_gate_prob!r}")
        from scipy.stats import chi2

        self.rig = rig
        # (a pair (0, 9) was taken unchecked: IndexError at the first frame; 0.7 truncated)
        self.pairs = rig.array.checked_pairs(pairs)
        self.sigma_tdoa_s, self.sigma_px = float(sigma_tdoa_s), float(sigma_px)
        self._pair_gate = float(chi2.ppf(pair_gate_prob, 1))
        self._pixel_gate = float(chi2.ppf(pixel_gate_prob, 2))

    def update_measurements(self, t: float, uv: ArrayLike | None = None,
                            tdoa_s: ArrayLike | None = None, fix: RayFix | None = None) -> bool:
        """One frame at ``t`` (seconds): the image point ``uv`` (pixels; None = not seen), the
        TDOAs ``tdoa_s`` (seconds, one per pair; NaN = none) and the frame's camera-ray ``fix``
        (None where the TDOAs gave none or it was discarded; it and its alternatives need a
        finite position and a finite, symmetric, positive definite covariance, as
        :class:`RayTracker`'s fixes: EstimationError). Returns True when a TDOA or a (re)start
        fix was fused."""
        if uv is not None:
            uv = _image_point(uv, finite=False)  # (NaN: not seen in this frame)
        if tdoa_s is not None:
            tdoa_s = as_tdoas(tdoa_s, len(self.pairs), EstimationError)
        cands = [] if fix is None else _fix_candidates(fix)
        self.predict(t)  # (the time's checks: finite, not before the last frame)
        if fix is not None and (not self.initialized or self.n_rejects >= self.max_rejects
                                or self._lost(cands[0][1])):
            self._start(*cands[0])
            self.t = self.last_fused_t = float(t)
            return True
        if not self.initialized:
            return False
        if uv is not None and not self._fuse_pixel(uv):
            self.n_rejects += 1
            return False
        if fix is None or tdoa_s is None:
            return False
        # the fix (or an alternative) against the prediction: MotionKalman's position gate
        if min(self._innovation(pos, self.H, cov, None)[2] for pos, cov in cands) > self._gate:
            self.n_rejects += 1
            return False
        z = np.asarray(tdoa_s, dtype=float).reshape(-1)
        arr = self.rig.array
        R = np.array([[self.sigma_tdoa_s**2]])
        fused = 0
        for k in np.flatnonzero(np.isfinite(z)):
            # relinearised at the state each earlier pair has already corrected
            pair, p = [self.pairs[k]], self.x[self._POS]
            H = np.zeros((1, self._DIM))
            H[0, self._POS] = arr.tdoa_jacobian(p, pair)[0]
            y, S, dd = self._innovation(np.array([z[k] - arr.tdoa(p, pair)[0]]) + H[0] @ self.x,
                                        H, R, None)
            if dd > self._pair_gate:
                continue
            self._correct(y, S, H, R)
            fused += 1
        self.n_rejects = 0 if fused else self.n_rejects + 1
        if fused:
            self.last_fused_t = self.t
        return fused > 0

    def _lost(self, R: NDArray) -> bool:
        """Whether the predicted position is :data:`RAY_LOST_VARIANCE_RATIO` times less certain
        than a fix of covariance ``R`` (m^2) in every direction."""
        from scipy.linalg import eigh

        P = self.P[np.ix_(self._POS, self._POS)]
        return bool(eigh(P, R, eigvals_only=True)[0] > RAY_LOST_VARIANCE_RATIO)

    @property
    def position_cov(self) -> NDArray:
        """The position covariance (m^2, array frame): ``covariance_scale`` times the filter's
        own ``P`` block (see :data:`RAY_COVARIANCE_SCALE`)."""
        return self.covariance_scale * super().position_cov

    def reset(self) -> None:
        """Forget the track."""
        super().reset()
        #: time (seconds) of the last measurement fused -- an image point, a TDOA or a
        #: (re)start fix -- or None: the stream drops a track that has gone without one for
        #: its ``max_coast_s`` (update_measurements' result counts TDOAs and starts only)
        self.last_fused_t: float | None = None

    def _fuse_pixel(self, uv: NDArray) -> bool:
        """EKF update with the image point (pixels). False when it fails the gate; skipped (True)
        where it or the prediction's projection is not finite."""
        p = self.x[self._POS]
        h = 1e-4 * max(float(np.linalg.norm(p - self.rig.camera_centre)), 0.1)
        pts = np.vstack([p, p + h * np.eye(3), p - h * np.eye(3)])
        q = self.rig.project(pts)
        if not np.all(np.isfinite(q)) or not np.all(np.isfinite(uv)):
            return True
        H = np.zeros((2, self._DIM))
        H[:, self._POS] = ((q[1:4] - q[4:7]) / (2 * h)).T
        R = np.eye(2) * self.sigma_px**2
        y, S, d2 = self._innovation(uv - q[0] + H @ self.x, H, R, None)
        if d2 > self._pixel_gate:
            return False
        self._correct(y, S, H, R)
        self.last_fused_t = self.t
        return True


def _fix_candidates(fix: Any) -> list[tuple[NDArray, NDArray]]:
    """A frame's fix and its alternatives as checked ``(position, covariance)`` pairs
    (:func:`_checked_fix`), or an EstimationError unless ``fix`` is a :class:`RayFix` whose
    ``alternatives`` are RayFixes (anything else raised a builtin AttributeError or TypeError,
    2026-12-02)."""
    items = None
    if isinstance(fix, RayFix):
        try:
            items = [fix, *fix.alternatives]
        except TypeError:
            pass
    if items is None or not all(isinstance(f, RayFix) for f in items):
        raise EstimationError(f"a frame's fix must be a RayFix (locate_on_ray) whose "
                              f"alternatives are RayFixes, or None; got {fix!r:.80}")
    return [_checked_fix(f) for f in items]


def _checked_fix(fix: RayFix) -> tuple[NDArray, NDArray]:
    """A fix's position (3,) in metres and covariance (3, 3) in m^2 as float arrays, or an
    EstimationError naming the RayFix unless the position is three finite numbers and the
    covariance finite, symmetric and positive definite (:class:`RayTracker`'s rule; a NaN fix
    started the track at NaN, a covariance of -I gave a negative position_cov and a 2x2 one a
    builtin ValueError). The fix check of :meth:`RayTdoaTracker.update_measurements`."""
    pos = (np.asarray(fix.position_m, dtype=float).reshape(-1)
           if real_entries(fix.position_m) else np.zeros(0))
    if pos.shape != (3,) or not np.all(np.isfinite(pos)):
        raise EstimationError(f"a RayFix must have a finite position [x, y, z] in metres, got "
                              f"{fix.position_m!r:.80}")
    try:
        cov = _covariance(fix.covariance, 3)
    except EstimationError as exc:
        raise EstimationError(f"a RayFix's covariance: {exc}") from None
    return pos, cov


def _check_tracker(tracker: Any, where: str, *, state: bool = False) -> None:
    """An EstimationError unless ``tracker`` has a callable ``update_measurements`` or
    ``update`` (and, with ``state``, ``position`` and ``velocity``): text, a number or None
    raised a builtin AttributeError -- in :func:`track_on_rays` after the whole recording's
    GCC-PHAT (2026-12-02)."""
    ok = any(callable(getattr(tracker, m, None)) for m in ("update_measurements", "update"))
    if ok and state:  # (looked up on the class: a property of an empty track may raise)
        ok = all(hasattr(type(tracker), a) or a in getattr(tracker, "__dict__", {})
                 for a in ("position", "velocity"))
    if not ok:
        raise EstimationError(
            f"{where}: tracker must be a 3D tracker with update_measurements(t, uv, tdoa_s, fix) "
            f"or update(t, position, R, candidates)" + (" and position, velocity" if state else "")
            + f" (RayTdoaTracker, RayTracker, MotionKalman), got {type(tracker).__name__}")


def feed_tracker(tracker: Any, t: float, uv: ArrayLike | None, tdoa_s: ArrayLike | None,
                 fix: RayFix | None) -> bool:
    """One frame into a 3D tracker: one with ``update_measurements`` (:class:`RayTdoaTracker`)
    gets the image point (pixels), the TDOAs (seconds) and the fix; any other
    (:class:`RayTracker`, :class:`hearsee.audio.tracking.MotionKalman`) the fix and its
    alternatives, or a prediction to ``t`` (seconds) without one. Returns the tracker's answer
    (True when something was fused). Anything else is an EstimationError."""
    _check_tracker(tracker, "feed_tracker")
    if fix is not None and not isinstance(fix, RayFix):  # (a builtin AttributeError)
        raise EstimationError(f"fix must be a RayFix or None, got {type(fix).__name__}")
    if hasattr(tracker, "update_measurements"):
        return tracker.update_measurements(t, uv, tdoa_s, fix)
    if fix is None:
        return tracker.update(t, None)
    return tracker.update(t, fix.position_m, fix.covariance,
                          [(a.position_m, a.covariance) for a in fix.alternatives])


def _check_image_points(image_points: Any) -> None:
    """An EstimationError unless ``image_points`` is callable, ``t -> (u, v) or None`` (an array
    of points raised a builtin TypeError at the first frame -- in :func:`track_on_rays` after
    the whole recording's GCC-PHAT; 2026-12-02)."""
    if not callable(image_points):
        raise EstimationError(f"image_points must be a function t (s) -> (u, v) pixels or None, "
                              f"got {type(image_points).__name__} {image_points!r:.40}")


def _seen(uv: Any) -> Any:
    """An ``image_points`` answer as :func:`frame_fix` uses it: None (not seen) for None or a
    point with a NaN or infinite coordinate (a NaN point aborted the whole run with
    locate_on_ray's EstimationError), else the point as given; anything but two pixel
    coordinates is an EstimationError (:func:`_image_point`)."""
    if uv is None or not np.all(np.isfinite(_image_point(uv, finite=False))):
        return None
    return uv


def _no_ray(uv: Any, camera: Camera) -> bool:
    """Whether the ``camera``'s lens model gives the pixel ``uv`` (2,) no ray
    (:meth:`hearsee.vision.camera.Camera.pixel_rays`: near the corners of a radial calibration
    whose distortion folds back before them)."""
    p = np.asarray(uv, dtype=float).reshape(1, 2)
    return not np.all(np.isfinite(camera.pixel_rays(p, unreachable="nan")))


def frame_fix(rig: AudioVisualRig, image_points: Callable[[float], Any], t: float,
              tdoa_s: ArrayLike | None, pairs: Sequence[tuple[int, int]], tracker: Any = None,
              *, range_m: tuple[float, float], sigma_tdoa_s: float, sigma_px: float,
              max_residual_s: float) -> tuple[Any, RayFix | None]:
    """One frame's image point and camera-ray fix, both of the same instant.

    The TDOAs of the frame centred at ``t`` (s) describe where the source was when it emitted
    that sound, ``r / c`` earlier; the camera sees it at once. So the image point is taken at
    ``t - r / c``, with ``r`` the distance from the array centre to the ``tracker``'s position
    (when it has one) or else to the frame's own first fix (made with the image at ``t``).
    Taken at ``t`` the image described a point a few millimetres further along the walk, and
    the camera-array parallax turned that into a range error about range / baseline times
    larger (1-3.5 cm at 0.5-1.5 m/s, 1.3 m, camera 0.2 m aside; found by an audit).

    ``image_points`` answers None, or a point with a NaN or infinite coordinate (as
    :meth:`RayTdoaTracker.update_measurements` reads NaN), when the camera does not see the
    source; anything else must be two pixel coordinates (EstimationError). A pixel the
    camera's lens model gives no ray for (see :meth:`hearsee.vision.camera.Camera.pixel_rays`)
    counts as not seen.

    Returns ``(uv, fix)``: the image point (None when the camera has none) and the fix (None
    without TDOAs or image point, or when the fix's RMS ITD residual exceeds
    ``max_residual_s``). ``fix.position_m`` is therefore where the source was when it emitted
    the frame's sound.
    """
    c = _check_rig(rig, "frame_fix").array.speed_of_sound
    _check_image_points(image_points)
    # (NaN kept every fix, the inconsistent ones too; text was a builtin TypeError)
    max_residual_s = finite_number("max_residual_s", max_residual_s, 0.0, error=EstimationError)
    t = finite_number("t", t, error=EstimationError)
    if tdoa_s is not None and not real_entries(tdoa_s):  # (text: a builtin TypeError)
        raise EstimationError(f"tdoa_s must be numbers (seconds) or None, got {tdoa_s!r:.60}")
    centre = rig.array.positions.mean(axis=0)
    r = None
    if getattr(tracker, "initialized", False):
        p = np.asarray(tracker.position, dtype=float)
        if np.all(np.isfinite(p)):
            r = float(np.linalg.norm(p - centre))
    uv = _seen(image_points(t if r is None else t - r / c))
    ok = tdoa_s is not None and np.all(np.isfinite(tdoa_s))
    if uv is None or not ok:
        return (None if uv is not None and _no_ray(uv, rig.camera) else uv), None

    def fix_at(point: Any) -> RayFix | None:
        try:
            return locate_on_ray(rig, point, tdoa_s, pairs, range_m=range_m,
                                 sigma_tdoa_s=sigma_tdoa_s, sigma_px=sigma_px)
        except GeometryError:
            # a pixel the lens model gives no ray for (a detection in the corner of a radial
            # calibration that folds back before it) is not seen: it aborted the whole run
            if _no_ray(point, rig.camera):
                return None
            raise

    fix = fix_at(uv)
    if fix is None:
        return None, None
    if r is None:  # no track yet: the image at the first fix's emission time
        uv2 = _seen(image_points(t - float(np.linalg.norm(fix.position_m - centre)) / c))
        fix2 = None if uv2 is None else fix_at(uv2)
        if fix2 is not None:
            uv, fix = uv2, fix2
    if fix.residual_s > max_residual_s:
        fix = None
    return uv, fix


@dataclass
class RayTrack:
    """Output of :func:`track_on_rays`: per frame ``t`` (s), the per-frame fixes ``raw`` (m,
    NaN where none), their ``fixes`` (:class:`RayFix` or None), and the tracker's ``position``
    (m) and ``velocity`` (m/s), all ``(n_frames, 3)``, array frame."""

    t: NDArray
    raw: NDArray
    fixes: list[RayFix | None]
    position: NDArray
    velocity: NDArray


def track_on_rays(rig: AudioVisualRig, x: ArrayLike, fs: float, image_points: Callable,
                  frame_ms: float = 64.0, hop_ms: float = 16.0,
                  range_m: tuple[float, float] = (0.2, 4.0), sigma_tdoa_s: float | None = None,
                  sigma_px: float = 1.0, min_confidence: float = 1.0,
                  max_residual_samples: float = 0.5, tracker: Any = None) -> RayTrack:
    """Track a source in 3D from a recording and its image points (thesis 5.4.3).

    Per frame: GCC-PHAT TDOAs with exact band-limited peak interpolation
    (:func:`hearsee.audio.tdoa.estimate_tdoas`, ``min_confidence``), the camera-ray fix
    (:func:`locate_on_ray`, covariance from ``sigma_tdoa_s`` and ``sigma_px``), fixes whose RMS
    ITD residual exceeds ``max_residual_samples`` discarded (three TDOAs that do not close),
    then the ``tracker``: by default :class:`RayTdoaTracker` (with ``sigma_tdoa_s`` and
    ``sigma_px``), which takes each frame's image point, TDOAs and fix; a tracker without
    ``update_measurements`` but with ``update(t, position, R, candidates)`` and
    ``position``/``velocity`` gets the fixes (e.g. :class:`RayTracker`,
    :class:`hearsee.audio.tracking.MotionKalman`).

    Parameters
    ----------
    rig : AudioVisualRig
    x : array (n_mics, n)
        Microphone signals.
    fs : float
        Sample rate, Hz.
    image_points : callable ``t -> (u, v) or None``
        Image point of the source at time t (seconds); called at each frame centre minus the
        source's propagation delay (:func:`frame_fix`), so the fixes, the track and ``raw``
        are where the source was when it emitted each frame's sound.
    frame_ms, hop_ms : float
        Analysis frames, milliseconds. The 16 ms hop (75 % overlap) gives the tracker twice
        as many, partly independent fixes as the stream's 32 ms: on the seed-100 walks of
        ``bench/tracking.py`` part B (three-mic rig, RT60 0.3 s) the tracked median error fell
        from about 6 to 4 cm.
    range_m : (near, far)
        Search interval along the camera ray, metres.
    sigma_tdoa_s, sigma_px : float
        Measurement noise behind each fix's covariance and the default tracker's measurements
        (seconds, pixels; > 0, EstimationError before any frame); ``sigma_tdoa_s`` None =
        :data:`RAY_SIGMA_TDOA_S` (8 us, chosen with :class:`RayTracker`'s defaults).
    min_confidence : float
        Frames whose GCC confidence is below this in any pair give no fix.
    max_residual_samples : float
        Fixes whose RMS ITD residual exceeds this many samples are discarded.
    tracker : optional
        The filter (default ``RayTdoaTracker(rig, sigma_tdoa_s=..., sigma_px=...)``).

    Returns
    -------
    RayTrack
    """
    from hearsee.audio.tdoa import estimate_tdoas

    _check_rig(rig, "track_on_rays")
    _check_image_points(image_points)
    if tracker is not None:
        _check_tracker(tracker, "track_on_rays", state=True)
    # (NaN kept every fix -- residual > NaN is False -- and text raised a builtin TypeError)
    finite_number("max_residual_samples", max_residual_samples, 0.0, error=EstimationError)
    # (checked by locate_on_ray only once a frame had an image point and TDOAs: a bad range
    # or sigma ran the whole GCC-PHAT first, and a recording without a fix never raised)
    _ray_range(range_m)
    # (> 0, as the stream's: 0 gave every fix a singular covariance, which a fix-based tracker
    # refused -- the run aborted at the first fix, after the GCC-PHAT -- and a recording
    # without a fix took silently; the default tracker refused it only after the GCC-PHAT)
    if sigma_tdoa_s is not None:
        finite_number("sigma_tdoa_s", sigma_tdoa_s, 0.0, lo_open=True, error=EstimationError)
    finite_number("sigma_px", sigma_px, 0.0, lo_open=True, error=EstimationError)
    prs = list(rig.array.pairs)
    tf = estimate_tdoas(x, fs, rig.array, frame_ms, hop_ms, "phat", prs, refine="interp",
                        min_confidence=min_confidence)
    if sigma_tdoa_s is None:
        sigma_tdoa_s = RAY_SIGMA_TDOA_S
    trk = (RayTdoaTracker(rig, prs, sigma_tdoa_s=sigma_tdoa_s, sigma_px=sigma_px)
           if tracker is None else tracker)
    n = len(tf.t)
    raw, pos, vel = (np.full((n, 3), np.nan) for _ in range(3))
    fixes: list[RayFix | None] = []
    for k, t in enumerate(tf.t):
        z = tf.tdoa_s[k]
        uv, fix = frame_fix(rig, image_points, float(t), z, prs, trk, range_m=range_m,
                            sigma_tdoa_s=sigma_tdoa_s, sigma_px=sigma_px,
                            max_residual_s=max_residual_samples / fs)
        fixes.append(fix)
        if fix is not None:
            raw[k] = fix.position_m
        feed_tracker(trk, float(t), uv, z, fix)
        pos[k], vel[k] = trk.position, trk.velocity
    return RayTrack(np.asarray(tf.t, dtype=float), raw, fixes, pos, vel)


# ---------------------------------------------------------------------------- learned (5.3)
def simulate_av_samples(rig: AudioVisualRig, n: int, range_m: tuple[float, float] = (0.5, 3.0),
                        sigma_tdoa_s: float = 0.0, sigma_px: float = 0.0,
                        margin_px: float = 10.0,
                        rng: np.random.Generator | int | None = None
                        ) -> tuple[NDArray, NDArray]:
    """Training/test examples for the uncalibrated mapping (thesis 5.3).

    Draws ``n`` source positions uniformly in the camera's view (pixel uniform in the image,
    among the pixels its lens model gives a ray for, range uniform in ``range_m`` metres from
    the camera centre), computes their exact TDOAs
    (all pairs) and pixels, and adds Gaussian noise (``sigma_tdoa_s`` seconds,
    ``sigma_px`` pixels). ``range_m`` is (near, far) in metres, 0 < near <= far; ``margin_px``
    the pixels kept clear of the image border (negative: beyond it), at most
    (min(width, height) - 1) / 2.

    Returns
    -------
    X : array (n, n_pairs + 2)
        Features ``[tdoa_s ..., u, v]``.
    Y : array (n, 3)
        True positions, array frame, metres.
    """
    _check_rig(rig, "simulate_av_samples")
    n = whole_number("n", n, 1, error=EstimationError)
    # ((1.0,) raised a builtin IndexError)
    near, far = _ray_range(range_m, equal_ok=True)
    sigma_tdoa_s = finite_number("sigma_tdoa_s", sigma_tdoa_s, 0.0, error=EstimationError)
    sigma_px = finite_number("sigma_px", sigma_px, 0.0, error=EstimationError)
    cam = rig.camera
    margin_px = _image_margin(margin_px, cam)
    rng = as_rng(rng)
    # pixels the lens model gives no ray for are drawn again (near the corners of a radial
    # calibration that folds back before them: the camera's GeometryError, at margin 0 for
    # k1 -0.28 at f 520 px, 640x480, whatever n)
    rays = np.zeros((0, 3))
    for _ in range(MAX_PIXEL_DRAWS):
        uv = np.column_stack([rng.uniform(margin_px, cam.width - 1 - margin_px, n),
                              rng.uniform(margin_px, cam.height - 1 - margin_px, n)])
        r = cam.pixel_rays(uv, unreachable="nan")
        rays = np.vstack([rays, r[np.all(np.isfinite(r), axis=1)]])
        if len(rays) >= n:
            break
    else:
        raise EstimationError(f"simulate_av_samples: the camera's lens model gives a ray for "
                              f"too few of the pixels drawn with margin_px = {margin_px:g} "
                              f"({MAX_PIXEL_DRAWS} draws did not give {n}; its distortion "
                              "folds back before them)")
    o, d = rig.camera_centre, rays[:n] @ rig.R
    s = rng.uniform(near, far, n)
    Y = o[None, :] + s[:, None] * d
    tdoa = rig.array.tdoa(Y) + sigma_tdoa_s * rng.standard_normal((n, len(rig.array.pairs)))
    uv_n = rig.project(Y) + sigma_px * rng.standard_normal((n, 2))
    return np.column_stack([tdoa, uv_n]), Y


#: :func:`simulate_av_samples` draws its pixels at most this many times over (the pixels its
#: camera's lens model gives no ray for are drawn again)
MAX_PIXEL_DRAWS = 20


def _image_margin(margin_px: Any, camera: Camera) -> float:
    """``margin_px`` (pixels kept clear of the image border; negative: beyond it) as a float,
    or an EstimationError unless it is a finite number that leaves part of the ``camera``'s
    image, at most (min(width, height) - 1) / 2, and at least -1e300 (NaN was numpy's builtin
    OverflowError, text a TypeError, 400 px of a 640x480 image its ValueError 'high - low <
    0', -1e308 its OverflowError)."""
    most = (min(camera.width, camera.height) - 1) / 2
    return finite_number("margin_px", margin_px, -1e300, most, error=EstimationError)


def _layer_sizes(sizes: Any) -> tuple[Any, ...]:
    """``hidden_layer_sizes`` as a tuple for MLPRegressor: one whole number >= 1 is one hidden
    layer, as MLPRegressor takes it (tuple() raised a builtin TypeError on 16); a sequence is
    passed on for MLPRegressor's own checks (fit's EstimationError); anything else (text, a
    bool, None) an EstimationError."""
    if isinstance(sizes, str) or not isinstance(sizes, Iterable):
        return (whole_number("hidden_layer_sizes", sizes, 1, error=EstimationError),)
    try:
        return tuple(sizes)
    except TypeError:  # (a 0-d array)
        raise EstimationError(f"hidden_layer_sizes must be an integer >= 1 or a sequence of "
                              f"them, got {sizes!r:.80}") from None


#: :class:`AudioVisualRegressor` takes image points within this many pixels of the image origin
MAX_PIXEL = 1e6


class AudioVisualRegressor(RegressorMixin, BaseEstimator):
    """(ITDs, image point) -> 3D position by a multi-layer perceptron (thesis 5.3.3).

    A scikit-learn regressor (``fit``/``predict``/``score``/``get_params``): features are
    ``[tdoa_s for each pair..., u_px, v_px]`` as made by :func:`simulate_av_samples`; targets are
    positions in metres. Internally ``StandardScaler -> MLPRegressor``; TDOAs are rescaled to
    milliseconds first so that the scaler sees well-conditioned numbers.

    Parameters
    ----------
    hidden_layer_sizes : int or tuple of int
        Hidden layers of the MLP (one int: one layer of that many units, as MLPRegressor).
    alpha : float
        L2 penalty.
    solver : str
        MLP solver; ``"lbfgs"`` (default) converges fastest on these small smooth problems.
    max_iter : int
        Maximum iterations (lbfgs) or epochs (adam).
    random_state : int or None
        Seed of the weight initialisation.
    """

    def __init__(self, hidden_layer_sizes: tuple[int, ...] = (32, 32), alpha: float = 1e-4,
                 solver: str = "lbfgs", max_iter: int = 500,
                 random_state: int | None = 0) -> None:
        self.hidden_layer_sizes = hidden_layer_sizes
        self.alpha = alpha
        self.solver = solver
        self.max_iter = max_iter
        self.random_state = random_state

    @staticmethod
    def _features(X: ArrayLike) -> NDArray:
        if not real_entries(X):  # (text read as TDOAs and pixels, True as 1)
            raise EstimationError("features must be numbers [tdoas..., u, v]")
        A = np.asarray(X, dtype=float)
        if A.ndim != 2 or A.shape[1] < 3:
            raise EstimationError(
                f"features must be (n_samples, n_pairs + 2) [tdoas..., u, v], got {A.shape}")
        if not np.all(np.isfinite(A)):
            raise EstimationError("features contain NaN or inf")
        # (1e306 s overflowed the milliseconds below after this check: scikit-learn's ValueError)
        if np.any(np.abs(A[:, :-2]) > 1.0) or np.any(np.abs(A[:, -2:]) > MAX_PIXEL):
            raise EstimationError(f"features out of range: TDOAs are seconds (|t| <= 1) and image "
                                  f"points pixels (|u|, |v| <= {MAX_PIXEL:g})")
        A = A.copy()
        A[:, :-2] *= 1e3  # seconds -> milliseconds
        return A

    @staticmethod
    def _targets(y: ArrayLike, n: int) -> NDArray:
        """Positions ``y`` (n, 3) in metres as floats, all finite, else an EstimationError."""
        if not real_entries(y):  # (text read as metres, True as 1 m)
            raise EstimationError("targets must be numbers (n_samples, 3) positions in metres")
        Y = np.asarray(y, dtype=float)
        if Y.shape != (n, 3):
            raise EstimationError(f"targets must be (n_samples, 3) positions, got {Y.shape}")
        if not np.all(np.isfinite(Y)):  # (scikit-learn's ValueError)
            raise EstimationError("targets contain NaN or inf")
        return Y

    def fit(self, X: ArrayLike, y: ArrayLike) -> AudioVisualRegressor:
        from sklearn.exceptions import ConvergenceWarning
        from sklearn.neural_network import MLPRegressor
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler

        A = self._features(X)
        Y = self._targets(y, A.shape[0])
        if A.shape[0] < 2:
            raise EstimationError(f"fit needs at least 2 samples, got {A.shape[0]}")
        self.model_ = make_pipeline(
            StandardScaler(),
            MLPRegressor(hidden_layer_sizes=_layer_sizes(self.hidden_layer_sizes),
                         alpha=self.alpha,
                         solver=self.solver,  # (int() read 2.5 as 2 and "500" as 500)
                         max_iter=whole_number("max_iter", self.max_iter,
                                               error=EstimationError),
                         random_state=self.random_state, tol=1e-7),
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            try:
                self.model_.fit(A, Y)
            except (TypeError, ValueError) as exc:  # bad hidden_layer_sizes, alpha, solver
                del self.model_
                raise EstimationError(f"AudioVisualRegressor settings: {exc}") from None
        self.n_features_in_ = A.shape[1]
        return self

    def predict(self, X: ArrayLike) -> NDArray:
        """Positions ``(n, 3)`` in metres (array frame) of features ``(n, n_pairs + 2)``;
        :class:`RegressorNotFittedError` before :meth:`fit`."""
        if not hasattr(self, "model_"):
            raise RegressorNotFittedError("AudioVisualRegressor is not fitted; call fit() first")
        A = self._features(X)
        if A.shape[1] != self.n_features_in_:
            raise EstimationError(
                f"expected {self.n_features_in_} features, got {A.shape[1]}")
        if A.shape[0] == 0:  # (scikit-learn's ValueError for no sample)
            return np.zeros((0, 3))
        return self.model_.predict(A)

    def score(self, X: ArrayLike, y: ArrayLike, sample_weight: ArrayLike | None = None
              ) -> float:
        """R^2 of :meth:`predict` against positions ``y`` (n, 3) in metres (scikit-learn's
        ``RegressorMixin.score``; a ``y`` of another shape was its ValueError)."""
        Y = self._targets(y, self._features(X).shape[0])
        return super().score(X, Y, sample_weight=sample_weight)

