"""Source direction and position from TDOAs: 2-, 3- and N-microphone solvers (thesis 2.3, 2.4).

Model (house conventions): ``tdoa[i,j] = t_i - t_j`` seconds. In the far field a plane wave from
unit direction ``u`` reaches microphone ``M_k`` at ``-M_k . u / c0``, so every pair gives one
linear equation ``-(M_i - M_j) . u = c0 tdoa[i,j]``; in the near field
``|P - M_i| - |P - M_j| = c0 tdoa[i,j]`` (a hyperboloid with foci M_i, M_j).

What one set of TDOAs can tell depends only on the span of the microphone positions, so
:func:`localize_tdoa` dispatches on geometry, not on presets:

- **linear** (two microphones, or all collinear): the locus is a hyperboloid (near field) /
  cone (far field) about the array axis ``a``: ``a . u = cos(theta)``. In the horizontal plane of
  the array frame this is an azimuth and its mirror about the axis -- for the thesis's pair on the
  y axis, ``alpha`` and ``180 - alpha`` (front/back twins). Elevation is unresolvable (None).
- **planar** (three microphones, or all coplanar): the TDOAs fix the in-plane part ``u_p`` of
  ``u`` by least squares; the out-of-plane part is ``+-sqrt(1 - |u_p|^2)``: two mirror solutions
  about the array plane, one when the source is in the plane (``|u_p| = 1``), none when the TDOAs
  are inconsistent (``|u_p| > 1`` or a pair residual above ``tol_s``) -- then the nearest feasible
  direction is returned with ``feasible=False``. Near field: two hyperboloids intersect in a 3D
  curve (:func:`three_mic_curve`, thesis fig. 2.6); a source known to lie in the array plane
  gets a spherical-wavefront azimuth (:func:`near_field_in_plane`, ``localize_tdoa(...,
  in_plane=True)``), free of the far-field model's bias for nearby sources.
- **volume** (>= 4 non-coplanar microphones): a unique far-field direction (least squares on
  the unit sphere with a robust loss) and a near-field position (spherical interpolation,
  Smith & Abel 1987, as initialiser when >= 5 microphones, then robust nonlinear least squares).

Angles: azimuth from +x toward +y, elevation from the xy-plane toward +z, degrees in the
:class:`Localization` fields; positions in metres in the array frame.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hearsee.audio.arrays import (
    DEFAULT_TDOA_STD_S,
    MAX_MICS,
    MicArray,
    _linearised_covariance,
    _pair_index,
    check_pairs,
    check_tdoa_std,
    closure_rms,
    load_array,
    pair_closure_projector,
    pair_tdoa,
    pair_tdoa_jacobian,
    position_uncertainty,
    residual_scaled_variance,
    span_dimension,
)
from hearsee.config import (
    check_settings,
    finite_number,
    is_real,
    real_entries,
    true_or_false,
    whole_number,
)
from hearsee.errors import ConfigError, DeadMicrophoneWarning, GeometryError
from hearsee.geometry import unit_vector_deg, wrap_deg

__all__ = [
    "MAX_LOCUS_POINTS",
    "Localization",
    "array_geometry",
    "cone_points",
    "far_field_linear",
    "far_field_planar",
    "far_field_volume",
    "fits_position",
    "hyperboloid_points",
    "localize_recording",
    "localize_tdoa",
    "near_field_in_plane",
    "near_field_position",
    "position_tdoa_std",
    "three_mic_curve",
]

#: Default TDOA consistency tolerance (seconds): ~1 cm of path difference.
DEFAULT_TOL_S = 3e-5

#: Factor on the pairs' closure RMS (:func:`hearsee.audio.arrays.closure_rms`) that
#: :func:`position_tdoa_std` takes as a lower bound on the TDOA error. Independently measured
#: pair TDOAs of one recording disagree (closure ``t_ij + t_jk != t_ik``) by about as much as they
#: err, but part of their error is consistent -- shared by a microphone's pairs, as a reflection
#: or sensor noise at that microphone is -- and the closure cannot see it. Such a shared part
#: also does not average out over the pairs: for a complete set of n microphones' pairs the
#: position's true covariance is that of independent pair errors of ``n sigma_mic^2 +
#: sigma_pair^2``, not of their per-pair ``2 sigma_mic^2 + sigma_pair^2`` (sqrt(n / 2), 2x for
#: eight microphones). Whole recordings in ``bench/nmic.py``'s room (20 cm cube of eight, 15 cm
#: tetrahedron and its centre, 8-mic 10 cm circle; 2026-11-27, seeds 351-354, 204 recordings
#: per array and RT60) erred in their consistent part by 2.1-2.7x the closure RMS anechoic
#: (median per seed and cell), 0.6-1.5x at RT60 0.3 / 0.6 s (90th percentile 0.9-3.2x), their
#: logarithms correlated by 0.85-0.97; 3 (one factor for 5-8 microphones) held the rooms' reported
#: positions in their 95 % ellipsoids 77-100 % of the time on those seeds (pooled 93.5 %;
#: sqrt(n / 2) x 2 held 97 % but reported 15 % fewer). Anechoic the declared 5 us is larger.
CLOSURE_STD_FACTOR = 3.0


@dataclass
class Localization:
    """The answer of one localization.

    azimuth_deg : float or None     primary azimuth (None when the geometry cannot resolve it)
    elevation_deg : float or None   primary elevation (None for linear arrays)
    candidates : list of (az, el)   every solution consistent with the TDOAs (degrees; el None
                                    where unresolvable); the primary is ``candidates[0]``
    n_solutions : int               exact solutions: 1 or 2 (mirror twins), 0 when the TDOAs are
                                    inconsistent (``candidates`` then holds the nearest feasible)
    feasible : bool                 False when the TDOAs admit no direction exactly
    position_m : array (3,) or None near-field position (arrays of >= 4 microphones, not
                                    linear; with >= 5 the primary direction may be its
                                    direction, see :func:`localize_tdoa`); for a planar array
                                    the one on the normal's side (its mirror image about the
                                    array plane fits the TDOAs equally). None where the TDOAs
                                    do not determine the distance (the fit is then in
                                    ``extra["position_fit_m"]``)
    position_covariance_m2 : array (3, 3) or None
                                    linearised covariance of ``position_m`` (m^2, array frame)
    distance_rel_std : float or None relative 1-sigma of the fitted position's distance from
                                    the array centre (None when no position was fitted)
    position_tdoa_std_s : float or None
                                    the TDOA standard deviation (seconds) behind the
                                    position's test and covariance: the declared one, raised
                                    where the pairs' closure shows larger errors (see
                                    :func:`position_tdoa_std`); None when no position was fitted
    direction : array (3,) or None  unit vector of the primary candidate (None for linear arrays)
    residual_s : float              RMS TDOA residual of the primary solution, seconds
    geometry : str                  "linear", "planar" or "volume"
    """

    azimuth_deg: float | None
    elevation_deg: float | None
    candidates: list[tuple[float | None, float | None]]
    n_solutions: int
    feasible: bool
    position_m: NDArray | None = None
    direction: NDArray | None = None
    residual_s: float = 0.0
    geometry: str = "planar"
    extra: dict[str, Any] = field(default_factory=dict)
    position_covariance_m2: NDArray | None = None
    distance_rel_std: float | None = None
    position_tdoa_std_s: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON form (degrees; None where unresolvable)."""
        return {
            "azimuth_deg": self.azimuth_deg,
            "elevation_deg": self.elevation_deg,
            "candidates": [{"azimuth_deg": a, "elevation_deg": e} for a, e in self.candidates],
            "n_solutions": self.n_solutions,
            "feasible": self.feasible,
            "position_m": None if self.position_m is None else list(map(float, self.position_m)),
            "position_covariance_m2": (None if self.position_covariance_m2 is None
                                       else np.asarray(self.position_covariance_m2).tolist()),
            "distance_rel_std": (None if self.distance_rel_std is None
                                 else float(self.distance_rel_std)),
            "position_tdoa_std_s": (None if self.position_tdoa_std_s is None
                                    else float(self.position_tdoa_std_s)),
        }


# ---------------------------------------------------------------------------------- geometry
@dataclass(frozen=True)
class ArrayGeometry:
    """Span of the microphone positions: ``kind`` and an orthonormal basis.

    axis : (3,) for linear arrays (unit, from the first toward the last microphone)
    basis : (2, 3) in-plane basis and normal (3,) for planar arrays. The normal's sign makes
    its largest component positive (ties: z, then x, then y): "above the plane" (the first
    of two mirror candidates, the side a planar position is reported on) is +z for a
    horizontal array or one tilted less than 45 deg, +x for one in a vertical plane facing
    forward. Before 2026-12-02 the sign of any z component above 1e-9 decided, so a vertical
    array tilted by 0.001 deg (a z component of 2e-5) turned its primary answer of a source
    in front (30 deg) to the mirror behind (150 deg); now sign flips only where two components
    are equal in size (planes at 45 deg), far from level or upright mountings.
    """

    kind: str
    centre: NDArray
    axis: NDArray | None = None
    basis: NDArray | None = None
    normal: NDArray | None = None


def array_geometry(array: MicArray | NDArray, rel_tol: float = 1e-6) -> ArrayGeometry:
    """Classify microphone positions ``(n, 3)`` as linear, planar or volume.

    Positions given as an array are checked as a :class:`MicArray`'s (an N x 3 table of finite
    numbers, at least two distinct microphones): a NaN position raised numpy's LinAlgError
    ("SVD did not converge"), an infinite one a RuntimeWarning and a made-up answer.
    A direction counts as flat when no far-field direction's part along it changes a pair's
    TDOA by more than :data:`hearsee.audio.arrays.FLAT_TDOA_S` (10 us, 3.4 mm at 343 m/s), or
    when its singular value is below ``rel_tol`` times the largest
    (:func:`hearsee.audio.arrays.span_dimension`: until 2026-12-02 the ratio alone decided,
    and micrometre-rounded positions went to the wrong solver). ``rel_tol`` must be a finite
    number in (0, 1]: NaN (and 0) classified every array as "volume", text raised a builtin
    TypeError."""
    if isinstance(array, MicArray) and rel_tol == 1e-6:
        return _geometry_cached(array)
    finite_number("rel_tol", rel_tol, 0.0, 1.0, lo_open=True, error=GeometryError)
    arr = array if isinstance(array, MicArray) else MicArray(array)
    return _classify(arr.positions, rel_tol, arr.speed_of_sound)


@lru_cache(maxsize=64)
def _geometry_cached(array: MicArray) -> ArrayGeometry:
    # (MicArray is immutable: frozen, read-only)
    geo = _classify(array.positions, 1e-6, array.speed_of_sound)
    for v in (geo.centre, geo.axis, geo.basis, geo.normal):  # shared by every caller: read-only
        if v is not None:
            v.setflags(write=False)
    return geo


def _classify(pos: NDArray, rel_tol: float, speed_of_sound: float) -> ArrayGeometry:
    dim, c, vt = span_dimension(pos, speed_of_sound, rel_tol)
    if dim == 1:
        axis = vt[0]
        if np.dot(axis, pos[-1] - pos[0]) < 0:
            axis = -axis
        return ArrayGeometry("linear", c, axis=axis)
    if dim == 2:
        n = np.cross(vt[0], vt[1])
        n = n / np.linalg.norm(n)
        # orientation: the largest component positive (ties: z, then x, then y)
        if n[max((2, 0, 1), key=lambda k: abs(n[k]))] < 0:
            n = -n
        e1 = vt[0]
        e2 = np.cross(n, e1)
        return ArrayGeometry("planar", c, basis=np.stack([e1, e2]), normal=n)
    return ArrayGeometry("volume", c)


#: No TDOA is longer than this (seconds; sound travels 1235 km in an hour). Larger values are
#: no measured delay, and beyond ~1e150 s their squares overflowed the solvers (a NaN
#: elevation, scipy's builtin ValueError); up to it an impossible TDOA is answered as any other,
#: ``feasible=False``.
MAX_TDOA_S = 3600.0


def check_real_tdoas(tdoa_s: Any, error: type[Exception] = GeometryError) -> None:
    """``error`` unless every entry of ``tdoa_s`` (any shape) is a real number of seconds, NaN
    and inf included (:func:`hearsee.config.real_entries`): numpy read text such as ``"1e-4"``
    as 1e-4 s, ``True`` as 1 s and dropped an imaginary part. The one message of every TDOA
    input (localization, the ITD filter, the audio-visual fusion); each passes its own
    exception type."""
    if not real_entries(tdoa_s):
        raise error(f"TDOAs must be real numbers of seconds, got {tdoa_s!r:.80}")


def as_tdoas(tdoa_s: ArrayLike, n_pairs: int, error: type[Exception] = GeometryError
             ) -> NDArray:
    """The TDOA vector (seconds, one per microphone pair) as floats, or ``error`` for entries
    that are no real numbers (:func:`check_real_tdoas`), a count other than ``n_pairs`` or an
    entry beyond :data:`MAX_TDOA_S`. NaN and inf entries pass (the callers decide)."""
    n_pairs = whole_number("n_pairs", n_pairs, lo=0, error=error)
    if tdoa_s is not None:  # (None: "got 1 TDOAs" below)
        check_real_tdoas(tdoa_s, error)
    tau = np.asarray(tdoa_s, dtype=float).reshape(-1)
    if tau.shape[0] != n_pairs:
        raise error(f"got {tau.shape[0]} TDOAs for {n_pairs} microphone pairs")
    check_tdoa_magnitude(tau, error)
    return tau


def check_tdoa_magnitude(tau: NDArray, error: type[Exception] = GeometryError) -> None:
    """``error`` naming the (first) TDOA vector of ``tau`` ((n_pairs,) or (n_frames, n_pairs)
    floats, seconds) with a finite entry beyond :data:`MAX_TDOA_S` in magnitude; NaN and inf
    pass (the callers decide)."""
    big = np.isfinite(tau) & (np.abs(tau) > MAX_TDOA_S)
    if big.any():
        row = tau if tau.ndim == 1 else tau[int(np.flatnonzero(big.any(axis=1))[0])]
        raise error(f"TDOAs must be at most {MAX_TDOA_S:g} s in magnitude, got "
                    f"{row.tolist()!r:.80}")


def _tdoa_vector(tdoa_s: ArrayLike, prs: list[tuple[int, int]], tol_s: float) -> NDArray:
    """:func:`as_tdoas`, or a GeometryError for a tolerance ``tol_s`` that is not a finite
    number > 0 (0 divided by zero in the in-plane fit). NaN entries pass:
    :func:`localize_tdoa` answers them with an empty result."""
    tau = as_tdoas(tdoa_s, len(prs))
    if not (is_real(tol_s) and tol_s > 0):
        raise GeometryError(f"tol_s must be a finite number > 0 seconds, got {tol_s}")
    return tau


def _tdoas(tdoa_s: ArrayLike, prs: list[tuple[int, int]], tol_s: float) -> NDArray:
    """:func:`_tdoa_vector` of a public solver, which also refuses NaN/inf entries (the solvers
    returned NaN directions or raised scipy errors for them)."""
    tau = _tdoa_vector(tdoa_s, prs, tol_s)
    if not np.all(np.isfinite(tau)):
        raise GeometryError("TDOAs must be finite numbers of seconds (localize_tdoa gives an "
                            "empty result for NaN ones)")
    return tau


#: The robust losses of scipy.optimize.least_squares (the volume solvers' ``loss``).
_LOSSES = ("linear", "huber", "soft_l1", "cauchy", "arctan")


def _check_loss(loss: Any) -> None:
    """ConfigError unless ``loss`` is one of :data:`_LOSSES` or a callable (scipy raised its
    own ValueError)."""
    if not (callable(loss) or (isinstance(loss, str) and loss in _LOSSES)):
        raise ConfigError(f"loss must be one of {', '.join(_LOSSES)} (or a callable), "
                          f"got {loss!r}")


def _design(array: MicArray, prs: list[tuple[int, int]]) -> NDArray:
    """Rows ``-(M_i - M_j) / c`` so that ``A @ u = tdoa`` in the far field."""
    p = array.positions
    return -np.array([p[i] - p[j] for i, j in prs]) / array.speed_of_sound


def _azel(u: NDArray) -> tuple[float, float]:
    """Azimuth in (-180, 180] and elevation (degrees) of direction ``u``; + 0.0 turns the
    -0.0 of a -0.0 component (an in-plane solution's z) into 0.0, as cart_to_sph does."""
    az = float(np.degrees(np.arctan2(u[1], u[0]))) + 0.0
    el = float(np.degrees(np.arcsin(np.clip(u[2] / np.linalg.norm(u), -1.0, 1.0)))) + 0.0
    return (180.0 if az == -180.0 else az), el


def _rms(r: NDArray) -> float:
    return float(np.sqrt(np.mean(np.square(r)))) if r.size else 0.0


# ---------------------------------------------------------------------------------- linear
def far_field_linear(tdoa_s: ArrayLike, array: MicArray | str,
                     pairs: Sequence[tuple[int, int]] | None = None,
                     tol_s: float = DEFAULT_TOL_S) -> Localization:
    """Two microphones (or a collinear array): cone about the axis; azimuth and mirror twin.

    ``cos(theta) = a . u`` is solved by least squares over the pairs (``a`` the array axis). The
    azimuths are where the cone meets the horizontal plane of the array frame (sources assumed
    at elevation 0, the thesis's "half horizontal plane"): ``phi_a +- acos(cos(theta) / |a_xy|)``
    with ``phi_a`` the axis azimuth -- for the y-axis pair, ``alpha`` and ``180 - alpha``. The
    front candidate (|az| <= 90) comes first. A vertical axis resolves only the elevation.

    Where the cone misses the horizontal plane (a tilted axis and a source well above or below
    it) the answer is the horizontal direction nearest it, on the axis azimuth (one candidate),
    and ``residual_s`` and ``feasible`` are that direction's, as everywhere the primary
    solution's: within ``tol_s`` it is a solution (``n_solutions=1``), beyond it not;
    ``extra["off_horizontal"]`` is True. Before 2026-12-02 such TDOAs were always
    ``feasible=False``, ``n_solutions=0``, with the cone's residual (0 for exact TDOAs).
    """
    array = load_array(array)  # (a MicArray, or a preset name / YAML path)
    prs = array.checked_pairs(pairs)
    tau = _tdoas(tdoa_s, prs, tol_s)
    geo = array_geometry(array)
    if geo.kind != "linear":
        raise GeometryError("far_field_linear needs collinear microphones")
    a = geo.axis
    A = _design(array, prs) @ a  # tdoa = A * cos(theta)
    cos_t = float(np.dot(A, tau) / np.dot(A, A))
    cos_c = float(np.clip(cos_t, -1.0, 1.0))
    # feasible when the nearest cone (end-fire for |cos| > 1) explains the TDOAs within tol_s,
    # as far_field_planar decides (a TDOA a hair past end-fire used to be infeasible, 0
    # solutions, whatever tol_s)
    resid = _rms(A * cos_c - tau)
    feasible = resid <= tol_s
    axy = float(np.hypot(a[0], a[1]))
    extra = {"cos_theta": cos_t, "cone_half_angle_deg": float(np.degrees(np.arccos(cos_c)))}
    if axy < 1e-6:  # vertical axis: elevation only
        el = float(np.degrees(np.arcsin(cos_c * np.sign(a[2]))))
        return Localization(None, el, [(None, el)], 1 if feasible else 0, feasible,
                            residual_s=resid, geometry="linear", extra=extra)
    phi_a = np.arctan2(a[1], a[0])
    ratio = cos_c / axy
    # (1e-9: an axis computed as 0.9999999999999999 long made an exact end-fire TDOA's ratio
    # exceed 1 -- "infeasible, 0 solutions" for the true direction in 18-26 % of random
    # horizontal line orientations)
    if abs(ratio) > 1.0 + 1e-9:  # the cone misses the horizontal plane: nearest azimuth on the axis
        ratio = float(np.sign(ratio))
        resid = _rms(A * (axy * ratio) - tau)  # (that horizontal direction's; the cone's was 0)
        feasible = resid <= tol_s
        extra["off_horizontal"] = True
    d = np.arccos(np.clip(ratio, -1.0, 1.0))
    azs = [float(np.degrees(phi_a + d)), float(np.degrees(phi_a - d))]
    azs = [float(wrap_deg(v)) for v in azs]
    # one solution at end-fire: the twins meet (1e-5 deg, since arccos near 1 turns the
    # ratio's rounding, ~1e-16, into ~1e-6 deg: two "solutions" 2e-6 deg apart)
    if abs(float(wrap_deg(azs[0] - azs[1]))) < 1e-5:
        azs = azs[:1]
    azs.sort(key=lambda v: (abs(v) > 90.0 + 1e-9, -np.cos(np.radians(v))))
    cands = [(v, None) for v in azs]
    n_sol = len(cands) if feasible else 0
    return Localization(cands[0][0], None, cands, n_sol, feasible, residual_s=resid,
                        geometry="linear", extra=extra)


# ---------------------------------------------------------------------------------- planar
def far_field_planar(tdoa_s: ArrayLike, array: MicArray | str,
                     pairs: Sequence[tuple[int, int]] | None = None,
                     tol_s: float = DEFAULT_TOL_S, in_plane_tol: float = 1e-3) -> Localization:
    """Three (or coplanar) microphones, far field: closed form with all solutions (thesis 2.4).

    ``u = u_p + w n`` with ``u_p`` in the array plane from least squares on
    ``-(M_i - M_j) . u_p = c0 tdoa[i,j]`` and ``w = +-sqrt(1 - |u_p|^2)``:

    - ``|u_p| < 1``: two mirror solutions about the array plane (the one above, ``w > 0``,
      first); ``n_solutions=2``;
    - ``|u_p| = 1`` (within ``in_plane_tol``, a number in (0, 0.5]: elevations below
      ``asin(sqrt(2 in_plane_tol))``, 2.6 deg by default, count as in the plane; 0.5 puts
      every direction but the normal there): one solution in the plane;
    - ``|u_p| > 1``: the nearest direction, the in-plane unit vector ``v`` of least TDOA
      residual ``|B v - tdoa|`` (``B`` the in-plane part of the design; the boundary solution
      of the trust-region problem, ``(B^T B + lambda I) v = B^T tdoa`` with ``lambda > 0`` such
      that ``|v| = 1``, Nocedal & Wright, *Numerical Optimization*, 2nd ed., 4.3). A source in
      the array plane a few metres away gives that with exact TDOAs (its curved wavefront puts
      ``|u_p|`` up to ~1.02 for the 15 cm triangle at 1-5 m, depending on the azimuth), so
      it is one solution (``n_solutions=1``) when its TDOA residual is within ``tol_s``.
      Before 2026-12-02 this was ``u_p / |u_p|``, the nearest only where ``B^T B`` is
      isotropic (an equilateral triangle with all pairs, regular polygons): a 40 x 3 cm
      L-shaped array answered -31.35 deg for a source at -25 deg with 45 us of residual,
      flagged infeasible, where -25.36 deg fits within 7.5 us. The ``three-mic`` preset's
      answers move by less than 1e-4 deg (its six-decimal coordinates are equilateral to
      ~1e-6);
    - a TDOA residual above ``tol_s`` (inconsistent ITDs): no exact solution; the nearest
      direction is returned, ``feasible=False``, ``n_solutions=0``.
    """
    array = load_array(array)  # (a MicArray, or a preset name / YAML path)
    prs = array.checked_pairs(pairs)
    tau = _tdoas(tdoa_s, prs, tol_s)
    # (text raised a builtin TypeError; -1 or 0.5 answered a source 10 deg above the plane
    # as in it)
    in_plane_tol = finite_number("in_plane_tol", in_plane_tol, 0.0, 0.5, lo_open=True,
                                 error=GeometryError)
    geo = array_geometry(array)
    if geo.kind != "planar":
        raise GeometryError("far_field_planar needs coplanar (and not collinear) microphones")
    A, B_pinv, B = _planar_solver(array, tuple(prs))
    q = B_pinv @ tau  # least squares in the array plane
    norm_p = float(np.linalg.norm(q))
    extra = {"in_plane_norm": norm_p}
    if norm_p > 1.0 + in_plane_tol:
        u = _nearest_unit(B, tau, q) @ geo.basis
        resid = _rms(A @ u - tau)
        feasible = resid <= tol_s
        az, el = _azel(u)
        return Localization(az, el, [(az, el)], int(feasible), feasible, direction=u,
                            residual_s=resid, geometry="planar", extra=extra)
    w = float(np.sqrt(max(0.0, 1.0 - min(norm_p, 1.0) ** 2)))
    up = q if norm_p <= 1.0 else _nearest_unit(B, tau, q)
    base = up @ geo.basis
    if w < np.sqrt(2 * in_plane_tol):  # in the plane: one solution
        us = [base / np.linalg.norm(base)]
    else:
        us = [base + w * geo.normal, base - w * geo.normal]
    resid = _rms(A @ us[0] - tau)
    feasible = resid <= tol_s
    cands = [_azel(u) for u in us]
    n_sol = len(us) if feasible else 0
    return Localization(cands[0][0], cands[0][1], cands, n_sol, feasible, direction=us[0],
                        residual_s=resid, geometry="planar", extra=extra)


@lru_cache(maxsize=64)
def _planar_solver(array: MicArray, prs: tuple[tuple[int, int], ...]
                   ) -> tuple[NDArray, NDArray, NDArray]:
    """The geometry-only part of :func:`far_field_planar`, once per array and pair set (a
    stream localizes every frame with the same ones): the design ``A``, the pseudo-inverse
    of its in-plane part and that part ``B`` (seconds per unit direction: rows ``-(M_i -
    M_j) / c0`` in the plane basis)."""
    A = _design(array, list(prs))
    B = A @ array_geometry(array).basis.T  # (n_pairs, 2)
    if np.linalg.matrix_rank(B, tol=1e-9 * np.abs(B).max()) < 2:
        raise GeometryError("the pairs given do not span the array plane (need two independent)")
    A.flags.writeable = False
    B_pinv = np.linalg.pinv(B)
    B_pinv.flags.writeable = False
    B.flags.writeable = False
    return A, B_pinv, B


def _nearest_unit(B: NDArray, tau: NDArray, q: NDArray) -> NDArray:
    """The unit vector ``v`` (2,) minimising ``|B v - tau|`` (``B`` (n_pairs, 2) seconds per
    unit direction, ``tau`` seconds) when the unconstrained least squares ``q`` lies outside
    the unit circle: ``v = (H + lambda I)^-1 g`` with ``H = B^T B``, ``g = B^T tau`` and the
    ``lambda > 0`` at which ``|v| = 1`` -- the trust-region boundary solution (Nocedal &
    Wright, *Numerical Optimization*, 2nd ed., 4.3: with ``|q| > 1`` and ``H`` positive
    definite it is the global minimum on the circle). ``lambda`` by Newton's method on
    ``1 / |v(lambda)| - 1`` from 0 (their algorithm 4.3: increasing and concave there, so the
    iterates rise monotonically to the root), in ``H``'s eigenbasis. An isotropic ``H`` gives
    ``q / |q|``."""
    h, V = np.linalg.eigh(B.T @ B)
    a = V.T @ (B.T @ tau)
    lam = 0.0
    for _ in range(100):
        x = a / (h + lam)
        nx = float(np.linalg.norm(x))
        if nx <= 1.0 + 1e-15:
            break
        dx = -float(np.sum(x * x / (h + lam))) / nx  # d|x| / d lambda
        step = -(1.0 / nx - 1.0) / (-dx / nx**2)  # Newton on 1/|x| - 1
        if not step > 1e-15 * (lam + float(h[-1])):
            break
        lam += step
    v = V @ (a / (h + lam))
    return v / np.linalg.norm(v)


# ---------------------------------------------------------------------------------- volume
def far_field_volume(tdoa_s: ArrayLike, array: MicArray | str,
                     pairs: Sequence[tuple[int, int]] | None = None,
                     tol_s: float = DEFAULT_TOL_S, loss: str = "soft_l1") -> Localization:
    """>= 4 non-coplanar microphones: unique far-field direction.

    Linear least squares ``A u = tdoa`` gives the start; the direction is then refined on the
    unit sphere (azimuth, elevation) with scipy's robust ``least_squares`` (``loss``, scale
    ``tol_s``). ``feasible`` is False when the RMS residual exceeds ``tol_s``.
    """
    array = load_array(array)  # (a MicArray, or a preset name / YAML path)
    from scipy.optimize import least_squares

    prs = array.checked_pairs(pairs)
    tau = _tdoas(tdoa_s, prs, tol_s)
    _check_loss(loss)
    A = _design(array, prs)
    if np.linalg.matrix_rank(A, tol=1e-9 * np.abs(A).max()) < 3:
        raise GeometryError("the pairs given do not span 3D (need three independent pairs)")
    u0, *_ = np.linalg.lstsq(A, tau, rcond=None)
    if np.linalg.norm(u0) < 1e-12:
        u0 = np.array([1.0, 0.0, 0.0])
    az0, el0 = np.radians(_azel(u0))

    def res(p: NDArray) -> NDArray:
        u = np.array([np.cos(p[1]) * np.cos(p[0]), np.cos(p[1]) * np.sin(p[0]), np.sin(p[1])])
        return (A @ u - tau) / tol_s

    sol = least_squares(res, [az0, el0], loss=loss, f_scale=1.0)
    az, el = sol.x
    u = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    resid = _rms(A @ u - tau)
    feasible = resid <= tol_s
    a, e = _azel(u)
    return Localization(a, e, [(a, e)], 1 if feasible else 0, feasible, direction=u,
                        residual_s=resid, geometry="volume",
                        extra={"lls_norm": float(np.linalg.norm(u0))})


def near_field_position(tdoa_s: ArrayLike, array: MicArray | str,
                        pairs: Sequence[tuple[int, int]] | None = None,
                        x0: ArrayLike | None = None, loss: str = "soft_l1",
                        tol_s: float = DEFAULT_TOL_S) -> tuple[NDArray, float]:
    """Source position (metres, array frame) from TDOAs by robust nonlinear least squares.

    Residuals ``(|P - M_i| - |P - M_j|) / c0 - tdoa[i,j]``. Start: ``x0``, else the far-field
    direction at 2 m and, when it exists, spherical interpolation (Smith & Abel 1987, needs >= 5
    microphones with all pairs to the reference), keeping the fit of lower cost: from the
    spherical interpolation alone, noisy TDOAs (20 us) of five-microphone arrays put up to 2 %
    of the fits on the far side of the array, 150-175 deg off (flagged only by their
    residual), both starts together none (300 random sources 0.5-4 m away per array,
    2026-11-27). Returns (position, RMS residual in seconds). Meaningful only for arrays whose
    aperture is not tiny compared with the range. A linear array has no position, and neither
    have pairs of fewer than three independent TDOAs (:func:`_independent_tdoas`: three
    microphones, or any array given two pairs): two TDOAs leave a curve of positions
    (:func:`three_mic_curve`, thesis fig. 2.6) for three unknowns. Both are GeometryErrors
    (before 2026-12-02 the second returned one point of the curve with a residual of ~0,
    1.1 m off for the three-mic preset and a source 1.1 m away). Three independent TDOAs
    (four microphones) fit exactly and may fit two positions; the fit returns one.

    A planar array fixes the position up to its mirror image about the array plane (the TDOAs
    are even in the distance from it): the starts are lifted off the plane, where that
    distance's gradient vanishes (a start in it -- the far-field answer of a source within
    ~2.6 deg of the plane, or spherical interpolation's minimum-norm solution -- stayed there),
    the spherical interpolation's distance from the plane is completed from its range, and
    the position returned is the one on the side of the plane's normal.
    """
    array = load_array(array)  # (a MicArray, or a preset name / YAML path)
    prs = array.checked_pairs(pairs)
    tau = _tdoas(tdoa_s, prs, tol_s)
    _check_loss(loss)
    if array_geometry(array).kind == "linear":  # (checked here too: x0 skips the starts)
        raise GeometryError("a linear array cannot fix a source position (only a cone)")
    n_ind = _independent_tdoas(array.n_mics, tuple(prs))
    if n_ind < 3:
        raise GeometryError(f"the pairs give {n_ind} independent TDOAs: they fix a curve of "
                            f"source positions, not one (3 unknowns; see three_mic_curve)")
    if x0 is not None:  # (scipy's or numpy's ValueError for NaN, short or text starts)
        try:
            start = np.asarray(x0, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            start = np.full(0, np.nan)
        if start.shape != (3,) or not np.all(np.isfinite(start)):
            raise GeometryError(f"x0 must be a finite [x, y, z] start position in metres, "
                                f"got {x0!r}")
        with np.errstate(over="ignore", invalid="ignore"):  # ([1e300, 0, 0]: scipy's ValueError)
            at = pair_tdoa(start, array.positions, *_pair_index(prs), array.speed_of_sound)
        if not np.all(np.isfinite(at)):
            raise GeometryError(f"x0 too far: its distances to the microphones overflow "
                                f"float64 (metres expected), got {x0!r}")
        x0 = start
    return _fit_position(tau, array, prs, [x0] if x0 is not None else
                         _position_starts(tau, array, prs), loss, tol_s)


def _position_starts(tau: NDArray, array: MicArray, prs: list[tuple[int, int]],
                     u: NDArray | None = None) -> list[NDArray]:
    """:func:`near_field_position`'s starts: spherical interpolation (when it exists) and the
    far-field direction ``u`` (solved here when None) at 2 m from the array centre."""
    geo = array_geometry(array)
    if geo.kind == "linear":
        raise GeometryError("a linear array cannot fix a source position (only a cone)")
    if u is None:
        solve = far_field_volume if geo.kind == "volume" else far_field_planar
        u = solve(tau, array, prs).direction
    starts = [geo.centre + 2.0 * u]
    si = _spherical_interpolation(tau, array, prs)
    if si is not None:
        starts.insert(0, si)
    return starts


def _fit_position(tau: NDArray, array: MicArray, prs: list[tuple[int, int]],
                  starts: list[NDArray], loss: str, tol_s: float) -> tuple[NDArray, float]:
    """The fit of :func:`near_field_position` from ``starts`` (checked arguments)."""
    from scipy.optimize import least_squares

    pos = array.positions
    c = array.speed_of_sound
    I, J = _pair_index(prs)
    geo = array_geometry(array)
    if geo.kind == "planar":
        starts = [_off_plane(np.asarray(s0, dtype=float), geo) for s0 in starts]

    def res(p: NDArray) -> NDArray:
        return (pair_tdoa(p, pos, I, J, c) - tau) / tol_s

    sol = min((least_squares(res, np.asarray(s0, dtype=float), loss=loss, f_scale=1.0)
               for s0 in starts), key=lambda r: r.cost)  # (the first of equal costs)
    p = sol.x
    if geo.kind == "planar":  # the mirror image on the normal's side: the same residual
        p = p - 2.0 * min(float((p - geo.centre) @ geo.normal), 0.0) * geo.normal
    return p, _rms(pair_tdoa(p, pos, I, J, c) - tau)


#: How far :func:`near_field_position` lifts a planar array's start off the array plane: this
#: fraction of the start's distance from the array centre (~3 deg of elevation), enough for the
#: fit to leave the plane, where the distance from it has no gradient, if the source is not in it.
_PLANE_LIFT = 0.05


def _off_plane(p: NDArray, geo: ArrayGeometry) -> NDArray:
    """Start ``p`` (metres) moved to at least :data:`_PLANE_LIFT` times its range from the
    planar array's plane, on the side it is on (the normal's side when in the plane)."""
    v = p - geo.centre
    h = float(v @ geo.normal)
    lift = max(abs(h), _PLANE_LIFT * float(np.linalg.norm(v)))
    return p + ((lift if h >= 0 else -lift) - h) * geo.normal


def _spherical_interpolation(tau: NDArray, array: MicArray,
                             prs: list[tuple[int, int]]) -> NDArray | None:
    """Smith & Abel (1987) spherical interpolation with microphone 0 as reference, or None."""
    n = array.n_mics
    if n < 5:
        return None
    lookup = {}
    for k, (i, j) in enumerate(prs):
        lookup[(i, j)] = tau[k]
        lookup[(j, i)] = -tau[k]
    if not all((m, 0) in lookup for m in range(1, n)):
        return None
    c = array.speed_of_sound
    m = array.positions[1:] - array.positions[0]
    geo = array_geometry(array)
    d = np.array([lookup[(k, 0)] for k in range(1, n)]) * c  # |P-M_k| - |P-M_0|
    M = np.column_stack([m, d])
    rhs = 0.5 * (np.sum(m * m, axis=1) - d * d)
    sol, *_ = np.linalg.lstsq(M, rhs, rcond=None)
    p = sol[:3] + array.positions[0]
    if geo.kind == "planar":
        # the minimum-norm solution lies in the plane; its range from microphone 0, sol[3],
        # gives the distance from the plane (up to the mirror sign)
        p = p + np.sqrt(max(sol[3] ** 2 - float(np.sum(sol[:3] ** 2)), 0.0)) * geo.normal
    return p if np.all(np.isfinite(p)) else None


# ---------------------------------------------------------------------------------- in-plane
def _inplane_tdoa(theta: NDArray, rho: NDArray, basis: NDArray, d: NDArray, I: NDArray,
                  J: NDArray, c: float) -> NDArray:
    """Pair TDOAs (..., n_pairs) of in-plane sources at angle ``theta`` (rad, in ``basis``) and
    inverse range ``rho`` (1/m, from the array centre); ``d`` (n_mics, 3) microphone offsets
    from the centre. Written so that ``rho = 0`` is the plane-wave limit exactly:
    ``|u/rho - d| = |u - rho d| / rho`` and a difference of square roots as a quotient."""
    u = np.cos(theta)[..., None] * basis[0] + np.sin(theta)[..., None] * basis[1]
    ud = u @ d.T  # (..., n_mics)
    dd = np.sum(d * d, axis=1)
    r = rho[..., None]
    q = np.sqrt(np.maximum(1.0 - 2.0 * r * ud + r * r * dd, 0.0))  # |u - rho d|
    num = -2.0 * (ud[..., I] - ud[..., J]) + r * (dd[I] - dd[J])
    return num / ((q[..., I] + q[..., J]) * c)


#: Ranges (metres) :func:`near_field_in_plane` takes: from the library's microphone spacing
#: floor (:data:`hearsee.audio.arrays.MIN_SPACING_M`, 1 mm) to 1000 km (a plane wave to float
#: precision for any array); beyond them the inverse range over- or underflowed.
_RANGE_M = (1e-3, 1e6)

#: Assumed range (metres from the array centre) of an in-plane source: a person talking to a
#: robot (:func:`near_field_in_plane`; the whole-recording search of ``estimate_tdoas(joint=
#: "auto")`` steers the same wavefront)
IN_PLANE_RANGE_M = 2.0


def near_field_in_plane(tdoa_s: ArrayLike, array: MicArray | str,
                        pairs: Sequence[tuple[int, int]] | None = None,
                        tol_s: float = DEFAULT_TOL_S, range_m: float | None = IN_PLANE_RANGE_M,
                        max_inverse_range: float = 2.0, n_iter: int = 8,
                        tdoa_std_s: float = DEFAULT_TDOA_STD_S,
                        closure_std_factor: float = CLOSURE_STD_FACTOR) -> Localization:
    """Planar array, source known to lie in the array plane: spherical-wavefront azimuth.

    The far-field fit of :func:`far_field_planar` treats the spherical wavefront of a nearby
    source as a plane wave; for the 15 cm ``three-mic`` triangle, whose pair midpoints lie
    4.3 cm off the centre, that alone biases the azimuth of sources 1-3 m away by ~0.5 deg RMS
    (noiseless TDOAs). Here the source is ``P = centre + u(theta) / rho`` in the array plane
    and ``theta`` minimises the squared TDOA residuals ``(|P - M_i| - |P - M_j|) / c0 -
    tdoa[i,j]`` by Gauss-Newton from the far-field direction; the azimuth is that of ``P``
    seen from the array centre.

    range_m : float or None
        Assumed source range in metres (``rho = 1 / range_m``; default 2 m, a person talking to a
        robot), within ``[1e-3, 1e6]`` m (:data:`_RANGE_M`; ``max_inverse_range`` is 1/m in ``[0,
        1e3]``). With sources at 1-3 m this leaves ~1/3 of the far-field bias (noiseless RMS 0.17
        deg instead of 0.5 deg) and adds no noise. ``None`` fits ``rho`` jointly in ``[0,
        max_inverse_range]`` 1/m (0 = plane wave): unbiased on clean TDOAs, but with three
        microphones the two independent TDOAs then fix both unknowns exactly, the range is
        ill-conditioned (within a few degrees of a pair's end-fire direction -- +-30, +-90, +-150
        deg for the three-mic preset -- distinct in-plane points share their TDOAs: exact fits there
        may sit up to ~2 deg (0.5 m), ~1 deg (1 m) or ~0.2 deg (2 m) off in azimuth) and TDOA errors
        reach the azimuth amplified -- on held-out reverberant recordings (``bench/doa.py``, seed
        777) the fitted range multiplied the azimuth RMSE by 3-4, the assumed 2 m lowered it
        (measured before the fix of the clipped range step on 2026-11-24, which halved the azimuth
        RMS of fits on 5-us-noisy TDOAs; not re-run).

    This is the in-plane (``dim=2``) assumption of pyroomacoustics' DOA methods and of the
    thesis's "half horizontal plane"; Gauss-Newton on range-difference equations follows Foy
    (1976). Returns one candidate (in the plane); ``extra["inverse_range_per_m"]`` is ``rho``.
    With the range assumed, ``position_m`` is None (the assumed point is
    ``extra["assumed_position_m"]``: before 2026-11-27 it was ``position_m``, and ``hearsee
    localize --in-plane`` printed every source 2 m away). With the range fitted, ``P`` (also
    ``extra["position_fit_m"]``) is ``position_m`` only where the TDOAs fix the distance, as
    :func:`localize_tdoa` decides for volume arrays: the linearised relative 1-sigma of the
    distance (``distance_rel_std``, for the TDOA error ``position_tdoa_std_s`` of
    :func:`position_tdoa_std` from ``tdoa_std_s`` and ``closure_std_factor``) at most
    :data:`MAX_POSITION_REL_STD`; its covariance (``position_covariance_m2``) is singular
    along the array normal, where the source is held, and grows with the fit's residual where
    the pairs hold more than two independent TDOAs (a source off the plane misfits). Before
    2026-11-27's thirty-fourth session every fit with ``rho > 0`` was reported, without
    covariance: exact TDOAs of the 15 cm three-mic triangle, declared 5 us, fix the distance
    of 32 % of in-plane sources 0.5-0.7 m away, 2 % at 0.7-1 m and none at 1-2 m (300 random
    azimuths each, seed 3531), while an 8-mic circle of 15 cm radius fixes it within a few per
    cent. Three microphones cannot tell that a source is off the plane (their two TDOAs fit
    some in-plane point exactly): of 300 sources 0.4-2 m away and 10-40 deg above the
    triangle, exact TDOAs gave a position for 97-111, of which 80-92 were more than 25 % off the
    source's projection (seeds 3602, 3603, 3606, 3607), most of them fits stopped on the 0.5 m
    range bound; a test dropping such fits failed the rules it was measured against (2026-11-27,
    thirty-fifth session's closing note). Hold the source to the plane only where it is.
    """
    array = load_array(array)  # (a MicArray, or a preset name / YAML path)
    prs = array.checked_pairs(pairs)
    tau = _tdoas(tdoa_s, prs, tol_s)
    geo = array_geometry(array)
    if geo.kind != "planar":
        raise GeometryError("near_field_in_plane needs coplanar (and not collinear) microphones")
    # (text raised builtin TypeErrors, True was 1 m, 1e-300 m overflowed with a warning)
    if range_m is not None and not (is_real(range_m) and _RANGE_M[0] <= range_m <= _RANGE_M[1]):
        raise GeometryError(f"range_m must be a number of metres in [{_RANGE_M[0]:g}, "
                            f"{_RANGE_M[1]:g}] or None, got {range_m!r}")
    max_inverse_range = finite_number("max_inverse_range (1/m)", max_inverse_range, 0.0,
                                      1.0 / _RANGE_M[0], error=GeometryError)
    tdoa_std_s = check_tdoa_std(tdoa_std_s)
    closure_std_factor = finite_number("closure_std_factor", closure_std_factor, 0.0,
                                       error=GeometryError)
    # (NaN or 2.5 raised range()'s builtin TypeError; -1 and 0 gave the unfitted start)
    n_iter = whole_number("n_iter", n_iter, 1, error=GeometryError)
    ff = far_field_planar(tau, array, prs, tol_s)
    c = array.speed_of_sound
    d = array.positions - geo.centre
    I, J = _pair_index(prs)
    u0 = ff.direction
    th = float(np.arctan2(u0 @ geo.basis[1], u0 @ geo.basis[0]))
    fit_range = range_m is None

    def residual(th: float, rho: float) -> float:
        return _rms(_inplane_tdoa(np.array([th]), np.array([rho]), geo.basis, d, I, J, c)[0]
                    - tau)

    def fit(th0: float, rho0: float) -> tuple[float, float]:
        return _fit_in_plane(tau, geo.basis, d, I, J, c, tol_s, th0, rho0, max_inverse_range,
                             fit_range, n_iter)

    if fit_range:
        # Gauss-Newton from a mid range; where it stops on a range bound short of an exact fit,
        # again from other ranges (the best fit wins)
        th, rho = fit(th, min(0.5, max_inverse_range))
        resid = residual(th, rho)
        for rho0 in (0.25, 1.0, 2.0):
            if resid <= 1e-3 * tol_s:
                break
            if rho0 > max_inverse_range:
                continue
            cand = fit(th, rho0)
            r = residual(*cand)
            if r < resid:
                (th, rho), resid = cand, r
    else:
        th, rho = fit(th, 1.0 / float(range_m))
        resid = residual(th, rho)
    u = np.cos(th) * geo.basis[0] + np.sin(th) * geo.basis[1]
    feasible = resid <= tol_s
    az, el = _azel(u)
    pos = geo.centre + u / rho if rho > 0 else None
    extra = {"inverse_range_per_m": rho, "far_field_azimuth_deg": ff.azimuth_deg}
    loc = Localization(az, el, [(az, el)], 1 if feasible else 0, feasible, direction=u,
                       residual_s=resid, geometry="planar", extra=extra)
    if not fit_range:
        extra["assumed_position_m"] = pos
    elif pos is not None:
        extra["position_fit_m"] = pos
        sig = position_tdoa_std(tau, prs, array.n_mics, tdoa_std_s, closure_std_factor)
        cov, rel = _in_plane_uncertainty(pos, array, prs, tau, sig, geo)
        loc.distance_rel_std, loc.position_tdoa_std_s = rel, sig
        if rel <= MAX_POSITION_REL_STD:
            loc.position_m, loc.position_covariance_m2 = pos, cov
    return loc


def _in_plane_uncertainty(p: NDArray, arr: MicArray, prs: list[tuple[int, int]], tau: NDArray,
                          sig: float, geo: ArrayGeometry) -> tuple[NDArray, float]:
    """Linearised covariance (m^2, array frame; zero along the array normal) of an in-plane
    position ``p`` (metres) of a planar array fitted to its pairs' TDOAs ``tau`` (seconds)
    with independent errors of ``sig`` seconds, and the relative 1-sigma of its distance from
    the array centre: :func:`hearsee.audio.arrays.position_uncertainty`'s model with the
    position held in the plane (two unknowns), its residual scaling included
    (:func:`hearsee.audio.arrays.residual_scaled_variance` with two unknowns). Three
    microphones' two independent TDOAs fit the two unknowns exactly (what their pairs
    disagree by is in ``sig``, :func:`position_tdoa_std`), so they are not scaled; a larger
    array's misfit -- a source off the plane, which the model cannot place -- widens the
    covariance. Without it (before 2026-11-27's thirty-fifth session) an 8-mic circle of 15
    cm radius reported every source 0.4-2 m away and 10-40 deg above its plane from exact
    TDOAs, a third of them more than 25 % off the source's projection on the plane, the 95 %
    ellipses holding that projection for 40 %; now 88 of 300 (3 of them > 25 % off, every
    ellipse holding it; held-out seed 3603, rule and study in the thirty-fifth session's
    closing note), with in-plane sources' reports unchanged to within 1 %."""
    i, j = _pair_index(prs)
    M, c = arr.positions, arr.speed_of_sound
    Jp = pair_tdoa_jacobian(p, M, i, j, c) @ geo.basis.T
    s2 = (residual_scaled_variance(pair_tdoa(p, M, i, j, c) - tau, sig, 2)
          if _independent_tdoas(arr.n_mics, tuple(prs)) > 2 else sig**2)
    return _linearised_covariance(Jp.T @ Jp, s2, p - geo.centre, geo.basis)


def _fit_in_plane(tau: NDArray, basis: NDArray, d: NDArray, I: NDArray, J: NDArray, c: float,
                  tol_s: float, th: float, rho: float, max_inverse_range: float,
                  fit_range: bool, n_iter: int) -> tuple[float, float]:
    """Gauss-Newton iterations of :func:`near_field_in_plane` from (``th`` rad, ``rho`` 1/m):
    the in-plane angle alone, or with ``fit_range`` the angle and the inverse range in ``[0,
    max_inverse_range]``. A joint step that leaves that interval is replaced by an angle-only
    step at the bound (the joint step's angle belongs to the unclipped range)."""
    h = 1e-6
    scale = 1.0 / tol_s

    def angle_step(th: float, rho: float) -> float:
        m = _inplane_tdoa(np.array([th, th + h]), np.array([rho, rho]), basis, d, I, J, c)
        r0, g = (m[0] - tau) * scale, (m[1] - m[0]) / h * scale
        return -float(g @ r0) / max(float(g @ g), 1e-300)

    for _ in range(n_iter):
        if fit_range:
            m = _inplane_tdoa(np.array([th, th + h, th]), np.array([rho, rho, rho + h]),
                              basis, d, I, J, c)
            r0 = (m[0] - tau) * scale
            Jm = np.column_stack([(m[1] - m[0]) / h * scale, (m[2] - m[0]) / h * scale])
            step, *_ = np.linalg.lstsq(Jm, -r0, rcond=None)
            d_th, rho_new = float(step[0]), rho + float(step[1])
            if not 0.0 <= rho_new <= max_inverse_range:
                rho_new = float(np.clip(rho_new, 0.0, max_inverse_range))
                d_th = angle_step(th, rho_new)
        else:
            d_th, rho_new = angle_step(th, rho), rho
        d_th = float(np.clip(d_th, -0.17, 0.17))  # at most ~10 deg per step
        done = abs(d_th) < 1e-7 and abs(rho_new - rho) < 1e-7  # 6e-6 deg, 1e-7 1/m
        th, rho = th + d_th, rho_new
        if done:
            break
    return th, rho


# ---------------------------------------------------------------------------------- dispatch
def localize_tdoa(tdoa_s: ArrayLike, array: MicArray | str,
                  pairs: Sequence[tuple[int, int]] | None = None,
                  tol_s: float = DEFAULT_TOL_S, near_field: bool = True,
                  in_plane: bool = False,
                  tdoa_std_s: float = DEFAULT_TDOA_STD_S,
                  closure_std_factor: float = CLOSURE_STD_FACTOR) -> Localization:
    """Localize from one TDOA vector, dispatching on the array's geometry.

    Parameters
    ----------
    tdoa_s : array (n_pairs,)
        ``t_i - t_j`` seconds for each pair of ``pairs`` (default: all ``i < j`` pairs).
    array : MicArray or preset/YAML name
    tol_s : float
        TDOA consistency tolerance in seconds (residual above it -> ``feasible=False``).
    near_field : bool
        For volume and planar arrays of >= 4 microphones also estimate ``position_m`` (a
        planar array's up to its mirror image about the array plane); for planar arrays with
        ``in_plane``, model the spherical wavefront of a source at the assumed range of
        :func:`near_field_in_plane` instead (2 m; the range is not fitted). The position is a
        robust nonlinear fit, ~3-15 ms per call for 4-6 microphones against ~0.1 ms for the
        plane wave (2026-11-27): per-frame callers that need no position pass False, as the
        stream and the simulated robot do.
    in_plane : bool
        The caller knows the source lies in the plane of a planar array (e.g. the three-mic
        preset and a speaker at its height; the ``dim=2`` assumption of pyroomacoustics' DOA).
        With ``near_field`` the spherical wavefront is modelled (removes the ~0.5 deg far-field
        bias of the 15 cm triangle at 1-3 m); without it, the far-field answer. Ignored for
        linear and volume arrays. Default False (unchanged behaviour).
    tdoa_std_s : float
        Expected standard deviation of each pair's TDOA error in seconds (default
        :data:`hearsee.audio.arrays.DEFAULT_TDOA_STD_S`, 5 us: a whole-recording GCC summary);
        a lower bound, raised to :data:`CLOSURE_STD_FACTOR` times the pairs' closure RMS where
        they disagree more (:func:`position_tdoa_std`; ``position_tdoa_std_s`` says which was
        used). Sets the near-field position's covariance and whether it is reported, see
        :func:`_add_position`.
    closure_std_factor : float
        That factor (>= 0; default :data:`CLOSURE_STD_FACTOR`, 3). 0 takes ``tdoa_std_s`` as
        it is: for TDOAs whose errors are known and independent between pairs (the closure
        RMS of such errors is their standard deviation, so 3 would triple it).

    Returns
    -------
    Localization
        NaN TDOAs give ``Localization(None, None, [], 0, False)``. Four microphones (three
        independent TDOAs, which a position always fits exactly, sometimes by the wrong one of
        two points) take the direction of ``position_m`` only where it is reported (the
        wavefront's curvature significant for the declared TDOA noise, its distance well
        determined: :func:`_add_position`) and lies more than :data:`NEAR_DIRECTION_MIN_RANGE_M`
        from the array centre, outside the array; otherwise the far-field (plane-wave) answer.
        Until 2026-12-07 they always kept the plane wave, whose error for a source near a large
        array grows with (aperture / distance)^2 (a 0.5 m array of four 1.5 m from a talker:
        16.5 deg for 18.2; held-out comparison at :data:`NEAR_DIRECTION_MIN_RANGE_M`).
        With five or more
        (:data:`NEAR_DIRECTION_MIN_MICS`, ``near_field``) the direction of ``position_m`` (from
        the array frame's origin, as the simulation's ground truth gives it) is the answer when a
        likelihood-ratio test at the 1 % level prefers the point source to the plane wave and
        the fit lies outside the array's extent (:func:`_near_model_wins`,
        :func:`_outside_array`; ``extra["direction_model"]`` says which, and
        ``extra["far_field"]`` keeps the plane wave's answer then): the wavefront's curvature is
        used where the TDOAs measure it, and ignored where noise would only add the range's
        uncertainty to the direction. Random sources (elevation within +-34 deg, 300 per cell,
        i.i.d. TDOA noise per pair, 2026-11-27), RMS direction error plane wave -> selected: a
        15 cm tetrahedron and its centre, 0.5-1 m, 1.47 -> 0.00 deg (exact TDOAs), 1.49 -> 1.07
        (5 us), 2.68 -> 2.68 (20 us); 2-4 m 0.35 -> 0.00, 0.69 -> 0.69, 2.34 -> 2.34; a 20 cm cube
        of eight, 0.5-1 m, 0.27 -> 0.00, 0.35 -> 0.18, 0.84 -> 0.75; a 5 cm hexagon with a
        microphone 8 cm above its centre (nearly planar: its range is poorly measured), 0.5-1
        m, 2.08 -> 0.00, 2.14 -> 2.11, 3.37 -> 3.37. No cell of three ranges from 0.5 to 4 m,
        three noise levels and these three arrays is worse than the plane wave; over 1500
        random arrays (5-8 microphones, 5-40 cm, sources 0.3-5 m, 0-30 us) RMS 5.06 -> 4.67 deg,
        median 1.21 -> 0.61, none worse by more than 10 deg (``bench/nmic.py``'s seed: 4.49 ->
        3.58, none worse by more than 10 deg, re-run 2026-12-03; 4.39 -> 4.05 and one on
        2026-11-27). A 5 % test gained more where the
        curvature is measured (1.49 -> 0.82 above) but let a far source's noise through 5 % of
        the time (cells up to 2 % worse, two random small arrays 10-15 deg worse).

        Planar arrays of five or more microphones (without ``in_plane``) do the same with the
        position on the normal's side of the plane, and the direction of its mirror image as
        the second candidate (the plane wave's elevation is ill-conditioned near the plane,
        ``|el| = arccos|u_p|``, and its mirror solutions merge within ~2.6 deg of it). Mirror-
        blind RMS error, plane wave -> selected, 200 sources per cell within +-34 deg
        (2026-11-27, seed 3311; rule and numbers in bench/results/HISTORY.md): a 6-mic circle of
        15 cm radius, 0.5-1 m, 2.16 -> 0.00 deg (exact TDOAs), 2.13 -> 0.92 (5 us), 3.48 ->
        3.23 (20 us); an 8-mic circle of 10 cm, 0.5-1 m, 1.16 -> 0.00, 1.58 -> 1.15; exact
        TDOAs 2-4 m away 0.30-0.47 -> 0.00 on these, ``respeaker-6`` (0.38) and a 7 cm
        pentagon; no cell of them (nor of a 30 cm square of four, which keeps the plane wave)
        worse by more than 0.3 %; 1000 random planar arrays (5-8 microphones, 5-40 cm, 0.3-5
        m, 0-30 us) RMS 7.15 -> 6.84, none worse by more than 10 deg.

    >>> arr = MicArray.from_preset("two-mic")
    >>> u = np.array([np.cos(np.radians(30)), np.sin(np.radians(30)), 0.0])
    >>> loc = localize_tdoa(arr.tdoa_far(u), arr)
    >>> [round(a) for a, _ in loc.candidates]
    [30, 150]
    """
    arr = load_array(array)
    prs = arr.checked_pairs(pairs)
    tau = _tdoa_vector(tdoa_s, prs, tol_s)
    tdoa_std_s = check_tdoa_std(tdoa_std_s)
    closure_std_factor = finite_number("closure_std_factor", closure_std_factor, 0.0,
                                       error=GeometryError)
    if not np.all(np.isfinite(tau)):
        return Localization(None, None, [], 0, False, residual_s=float("nan"),
                            geometry=array_geometry(arr).kind)
    geo = array_geometry(arr)
    if geo.kind == "linear":
        return far_field_linear(tau, arr, prs, tol_s)
    if geo.kind == "planar":
        if in_plane and near_field:
            return near_field_in_plane(tau, arr, prs, tol_s)
        loc = far_field_planar(tau, arr, prs, tol_s)
    else:
        loc = far_field_volume(tau, arr, prs, tol_s)
    if near_field and fits_position(arr):
        _add_position(loc, tau, arr, prs, tol_s, tdoa_std_s, closure_std_factor)
    return loc


def fits_position(array: MicArray | str, in_plane: bool = False) -> bool:
    """Whether :func:`localize_tdoa` (``near_field=True``) fits a source position (metres,
    array frame) for ``array``: four or more microphones, not collinear, no mask, and not a
    planar array held to its plane (``in_plane``: the range is assumed there). Only then do
    ``tdoa_std_s`` and ``closure_std_factor`` matter."""
    arr = load_array(array)
    kind = array_geometry(arr).kind
    return (arr.mask is None and arr.n_mics >= 4
            and (kind == "volume" or (kind == "planar" and not in_plane)))


#: Largest relative 1-sigma distance (from the linearised covariance,
#: :func:`hearsee.audio.arrays.position_uncertainty`) at which :func:`localize_tdoa` reports a
#: near-field ``position_m``. Random sources 0.5-4 m away (elevation within +-34 deg, 150 per
#: cell, declared 5 us, TDOA noise 2 / 5 / 20 us; scratch study of 2026-11-27): with 0.5 the
#: reported positions of small arrays were often wrong -- noise pulls the fit toward the array,
#: where the linearised distance looks well determined (``respeaker-6`` 0.5-1 m at 5 us: 13 %
#: reported, 30 % of those off by more than half the distance) -- with 0.3, at most 3 % of
#: ``respeaker-4/6``'s sources got a position and a 15 cm tetrahedron's were within 15 % (median)
#: at 0.5-1 m and 2-5 us, while a 20 cm cube of eight kept 86-100 % (median error 1-9 %) and an
#: 8-mic 10 cm circle 81-100 % within 2 m at 2-5 us. (That study's noise was independent
#: between pairs and taken at its declared 5 us, as ``closure_std_factor=0`` does; the default
#: factor 3 reads such noise as three times larger -- the closure RMS of independent errors is
#: their standard deviation -- so on the same kind of draws (seed 3510) the cube keeps 87-100 %
#: at 2 us but 15-99 % at 5 us and 0-11 % at 20 us, where with 0 it reported 13-92 % and up to a
#: quarter of those off by more than half the distance, its ellipsoids holding the truth for
#: 20-85 %.)
MAX_POSITION_REL_STD = 0.3


def _add_position(loc: Localization, tau: NDArray, arr: MicArray, prs: list[tuple[int, int]],
                  tol_s: float, tdoa_std_s: float,
                  closure_std_factor: float = CLOSURE_STD_FACTOR) -> None:
    """Fit the near-field position of the far-field localization ``loc`` of a planar or volume
    array; make it ``loc.position_m`` (with its covariance) when the TDOAs determine it; take
    its direction when :func:`localize_tdoa`'s test prefers the point source (four
    microphones: when it is reported, see :data:`NEAR_DIRECTION_MIN_RANGE_M`;
    ``extra["direction_model"]`` says which).

    The position is reported when (1) the point source explains the TDOAs significantly
    better than a plane wave (:func:`_curvature_significant`: a plane wave is a source at
    infinite distance, so otherwise no finite distance is supported) and (2) its linearised
    relative distance 1-sigma is at most :data:`MAX_POSITION_REL_STD`. Otherwise
    ``position_m`` is None and the fit stays in ``extra["position_fit_m"]``: a 4.5 cm
    ``respeaker-4`` fitted sources 0.5-4 m away with a median distance error of 57-98 % for
    2-20 us of TDOA noise, and reported every one of them before 2026-11-27.

    Both use the TDOA error of :func:`position_tdoa_std`: the declared ``tdoa_std_s``, raised
    to ``closure_std_factor`` times the pairs' closure RMS where they disagree more. Whole
    recordings (``bench/nmic.py``'s room, recordings and whole-recording TDOAs, sources 0.5-3 m
    away within +-30 deg of elevation, default 5 us; held-out seeds 355/356 of 2026-11-27, 120
    recordings per array and RT60), anechoic / RT60 0.3 s / 0.6 s: a 20 cm cube of eight got a
    position for 88 / 45 / 38 % of them, median distance error 0.8 / 2.9 / 1.8 %; an 8-mic 10 cm
    circle 73 / 25 / 17 %, 2.4 / 3.1 / 2.4 %; a 15 cm tetrahedron and its centre 8 / 11 / 13 %,
    1.4 / 3.3 / 7.2 %; none off by more than half the distance, the 95 % ellipsoids holding the
    truth for 90-100 % of the reported positions per array and RT60. With the declared 5 us
    alone (the rule before the closure bound) the rooms' reports were twice as many (47 % vs
    25 %) but 23 of 340 were off by more than half the distance -- reflections that mimic a
    nearer source, fits pulled toward the array -- and their ellipsoids held the truth for
    only 57-78 %; ``respeaker-4`` and ``respeaker-6`` get none either way (fits 12-90 % off)."""
    # (the far-field direction that near_field_position would solve for again is loc's)
    p, r = _fit_position(tau, arr, prs, _position_starts(tau, arr, prs, loc.direction),
                         "soft_l1", tol_s)
    i, j = _pair_index(prs)
    geo = array_geometry(arr)
    sig = position_tdoa_std(tau, prs, arr.n_mics, tdoa_std_s, closure_std_factor)
    cov, rel, _, _ = position_uncertainty(p, arr.positions, i, j, arr.speed_of_sound, tau,
                                          sig, geo.centre, MAX_POSITION_REL_STD)
    loc.extra["position_fit_m"] = p
    loc.extra["position_residual_s"] = r
    loc.extra["direction_model"] = "plane_wave"
    loc.distance_rel_std = rel
    loc.position_tdoa_std_s = sig
    if _curvature_significant(loc.residual_s, r, len(prs), sig) and \
            rel <= MAX_POSITION_REL_STD:
        loc.position_m, loc.position_covariance_m2 = p, cov
    n_ind = _independent_tdoas(arr.n_mics, tuple(prs))
    if not _outside_array(p, arr):
        return
    if n_ind >= NEAR_DIRECTION_MIN_MICS - 1:
        if _near_model_wins(loc.residual_s, r, n_ind):
            _direction_from_position(loc, p, r, tol_s, geo)
    elif (n_ind == NEAR_DIRECTION_MIN_MICS - 2 and loc.position_m is not None
          and float(np.linalg.norm(p - arr.centre)) > NEAR_DIRECTION_MIN_RANGE_M):
        _direction_from_position(loc, p, r, tol_s, geo)


def position_tdoa_std(tdoa_s: ArrayLike, pairs: Sequence[tuple[int, int]], n_mics: int,
                      tdoa_std_s: float, factor: float = CLOSURE_STD_FACTOR) -> float:
    """The TDOA standard deviation (seconds) behind a near-field position's report and
    covariance: the declared ``tdoa_std_s``, or ``factor`` (:data:`CLOSURE_STD_FACTOR`) times
    the pairs' closure RMS where that is larger -- what the TDOAs themselves show of their
    error (pairs without a closed cycle show none; ``factor`` 0 ignores it).

    Reverberation biases whole-recording TDOAs far beyond a declared 5 us (4-14 us at RT60
    0.3 s, 13-35 us at 0.6 s in ``bench/nmic.py``'s room), and biases that mimic a nearer source
    made :func:`localize_tdoa` report wrong positions with confident covariances. Held out
    (2026-11-27, seeds 355/356, 120 recordings per array and RT60; rule and a first, failed
    held-out run in ``bench/results/HISTORY.md``), declared only -> this: of the rooms' reports,
    positions off by more than half the distance 23 -> 0 (20 cm cube 10 -> 0, 15 cm tetrahedron
    and centre 8 -> 0, 8-mic circle 5 -> 0), 95 % ellipsoids holding the truth 57-78 % -> 90-100 %
    per array and RT60 (pooled 68 -> 97 %), reported share in the rooms 47 -> 25 % (340 -> 179
    of 720); anechoic and every direction unchanged."""
    prs = check_pairs(pairs, whole_number("n_mics", n_mics, 2, MAX_MICS, error=GeometryError))
    tau = as_tdoas(tdoa_s, len(prs))  # (text: numpy's builtin ValueError)
    if not np.all(np.isfinite(tau)):  # (NaN: max(5e-6, nan) returned the declared value)
        raise GeometryError("position_tdoa_std needs finite TDOAs (seconds)")
    tdoa_std_s = check_tdoa_std(tdoa_std_s)
    factor = finite_number("factor", factor, 0.0, error=GeometryError)
    clo = closure_rms(tau, prs, n_mics)
    return tdoa_std_s if clo is None else max(tdoa_std_s, factor * clo)


def _curvature_significant(rms_far_s: float, rms_near_s: float, n_pairs: int,
                           tdoa_std_s: float) -> bool:
    """Whether a point source (3 parameters) fits ``n_pairs`` TDOAs significantly better than
    a plane wave (2), with per-pair errors of standard deviation at least ``tdoa_std_s``
    seconds: ``m (rms_far^2 - rms_near^2) / s^2`` above :data:`NEAR_MODEL_LR_CRITICAL`
    (chi-square, one degree of freedom, 1 %), ``s^2`` the larger of ``tdoa_std_s^2`` and the
    point source's residual variance ``m rms_near^2 / (m - 3)``. Unlike
    :func:`_near_model_wins` (the direction's choice, residual ratio only) it needs the
    declared noise: four microphones' TDOAs consistent with one set of arrival times are
    fitted exactly by a point source, and a ratio then always favours it."""
    m = n_pairs
    s2 = tdoa_std_s**2
    if m > 3:
        s2 = max(s2, m * rms_near_s**2 / (m - 3))
    return bool(m * (rms_far_s**2 - rms_near_s**2) / s2 > NEAR_MODEL_LR_CRITICAL)


@lru_cache(maxsize=64)
def _independent_tdoas(n_mics: int, prs: tuple[tuple[int, int], ...]) -> int:
    """How many of the pairs' TDOAs are independent (the pair matrix's rank), once per set."""
    proj = pair_closure_projector(prs, n_mics)
    return len(prs) if proj is None else len(prs) - proj[1]


#: Volume and planar arrays with at least this many microphones -- TDOAs of at least this many
#: minus one independent pairs -- may take their direction from the near-field position
#: (:func:`_near_model_wins`); four give three independent TDOAs, which the position's three
#: coordinates always fit exactly, often by the wrong one of two points.
NEAR_DIRECTION_MIN_MICS = 5
#: Four microphones (three independent TDOAs, where :func:`_near_model_wins` cannot judge: the
#: point source fits them exactly) take the direction of a REPORTED position (see
#: :func:`_add_position`) outside the array and farther than this from its centre (metres):
#: nearer fits are taken for reflections pulling the fit toward the array. Not in the thesis;
#: chosen 2026-12-07 (scratch; the rule written before the held-out run) on random
#: four-microphone arrays at the TDOA level (planar and volume, 5-50 cm, sources 0.5-4 m,
#: 0-20 us) and recordings in ``bench/nmic.py``'s room (a 15 cm and a 40 cm regular
#: tetrahedron, a 0.5 m array with one microphone 0.2 m up, a 30 cm square; white noise, male
#: and female voices, 10/20 dB, anechoic and RT60 0.3/0.6 s, sources 0.5-3 m). Without the
#: 0.3 m floor the 15 cm tetrahedron lost in the rooms (RT60 0.3 s 1.96 -> 2.24 deg RMS: fits
#: 0.11-0.20 m away for talkers 1.2-2.7 m away); a floor of 2-3 array radii instead dropped
#: the large arrays' near talkers, where the gain is. Held out (fresh seeds), plane wave ->
#: this: every array x RT60 pool at or below the plane wave (pooled 3.67 -> 3.47 deg; anechoic
#: 40 cm tetrahedron 2.03 -> 1.17, 30 cm square 1.90 -> 0.52; the 0.5 m array 1.70 -> 0.97,
#: 2.50 -> 2.28, 3.75 -> 3.46 at RT60 0, 0.3, 0.6 s; the 15 cm tetrahedron 0.90 -> 0.73, 1.92
#: -> 1.89, 4.08 -> 4.08); at the TDOA level 849 of the 858 answers that switched better, none
#: worse by more than 5 deg, no cell worse by more than 1 %. See bench/four_mics.py.
NEAR_DIRECTION_MIN_RANGE_M = 0.3
#: Critical value of the likelihood-ratio test of :func:`_near_model_wins`: chi-square with one
#: degree of freedom (the range) at the 1 % level. At 5 % (3.84) a far source's noise passed
#: the test 5 % of the time, and the direction of such a fit -- pulled toward a small array --
#: could be 10-15 deg worse than the plane wave's (2 of 1500 random arrays, 5-7 cm, 10 us); the
#: structured sweep of :func:`localize_tdoa` had cells up to 2 % worse there, none at 1 %.
NEAR_MODEL_LR_CRITICAL = 6.63


def _outside_array(p: NDArray, arr: MicArray) -> bool:
    """Whether position ``p`` (metres) lies farther from the microphones' centroid than every
    microphone. A point-source fit inside the array's own extent is not taken for a talker's
    position: noisy TDOAs of a far source can pull the fit there (a random-array check,
    2026-11-27: 0.11 m from a 32 cm array's centre for a source 0.33 m away with 30 us of
    noise, its direction 31 deg off where the plane wave's was 8)."""
    c = arr.centre
    return bool(np.linalg.norm(p - c) > np.max(np.linalg.norm(arr.positions - c, axis=1)))


def _near_model_wins(rms_far_s: float, rms_near_s: float, n_independent: int) -> bool:
    """Likelihood-ratio test of the point source (position: 3 parameters) against the plane
    wave (direction: 2; the point source's limit at infinite range) fitted to
    ``n_independent`` independent TDOAs with Gaussian errors: the point source wins when
    ``n ln(RSS_far / RSS_near)`` exceeds :data:`NEAR_MODEL_LR_CRITICAL`, i.e. when its RMS
    residual is below the plane wave's by more than the factor ``exp(6.63 / (2 n))`` (RMS over
    all pairs: the same ratio as over independent ones for residuals consistent with one set
    of arrival times). Noise alone lowers the point source's residual too, by pulling the fit
    toward the array (fitted ranges of 0.07-0.9 m for sources 0.7-4 m away in the hexagon of
    :func:`localize_tdoa`'s numbers), and the direction of such a fit from the frame's origin
    is poor: Akaike's criterion (threshold 2) let those through and was up to 5 % worse than
    the plane wave on noisy TDOAs, and so, rarely, was a 5 % test (see the constant). Ties
    keep the plane wave."""
    return bool(rms_far_s > rms_near_s * math.exp(NEAR_MODEL_LR_CRITICAL / (2.0 * n_independent)))


#: Elevation (rad) above a planar array's plane, seen from its centre, below which a fitted
#: position's mirror image is the same solution (:func:`_direction_from_position`). The fit of
#: a source in the plane stops 1e-5 to 5e-5 of its range off it (the height has no gradient
#: there): an 8-mic 15 cm circle reported in-plane sources as two solutions at +-0.0014 deg
#: before 2026-12-02, where the plane wave gave one. 1e-3 rad (0.057 deg) changes the TDOAs of
#: a 30 cm array by ``(D / c0) el^2 / 2`` = 0.4 ns, far below any TDOA error.
_PLANE_TWIN_RAD = 1e-3


def _direction_from_position(loc: Localization, p: NDArray, rms_s: float,
                             tol_s: float, geo: ArrayGeometry) -> None:
    """Make the direction of ``p`` (metres) from the array frame's origin -- the direction a
    source at ``p`` has in that frame, as :func:`hearsee.sim.audio.ground_truth` gives it --
    the primary answer of the localization ``loc`` (the plane wave's answer kept in
    ``extra``). A planar array's ``p`` off its plane adds the direction of its mirror image
    about the plane as the second candidate, unless ``p``'s elevation above the plane, seen
    from the array centre, is below :data:`_PLANE_TWIN_RAD`: one solution then, as
    :func:`far_field_linear` merges twins closer than rounding."""
    v = np.asarray(p, dtype=float)
    n = float(np.linalg.norm(v))
    if not (np.isfinite(n) and n > 0):
        return
    loc.extra["far_field"] = {"azimuth_deg": loc.azimuth_deg,
                              "elevation_deg": loc.elevation_deg, "residual_s": loc.residual_s}
    points = [v]
    if geo.kind == "planar" and (h := float((v - geo.centre) @ geo.normal)) > \
            _PLANE_TWIN_RAD * float(np.linalg.norm(v - geo.centre)):
        points.append(v - 2.0 * h * geo.normal)
    cands = [_azel(q / np.linalg.norm(q)) for q in points]
    loc.azimuth_deg, loc.elevation_deg = cands[0]
    loc.candidates = cands
    loc.direction = v / n
    loc.residual_s = rms_s
    loc.feasible = rms_s <= tol_s
    loc.n_solutions = len(cands) if loc.feasible else 0
    loc.extra["direction_model"] = "position"


# ---------------------------------------------------------------------------------- loci
def _frame_from_axis(axis: NDArray) -> NDArray:
    """Rows e1, e2, axis: a right-handed orthonormal frame with the given third axis."""
    a = axis / np.linalg.norm(axis)
    t = np.array([0.0, 0.0, 1.0]) if abs(a[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = np.cross(t, a)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(a, e1), a])


#: The most points a locus plot (:func:`cone_points`, :func:`hyperboloid_points`) samples,
#: ``n_radial * n_around``: 10 million (a 240 MB grid, ~0.8 GB and 3 s while it is made; a
#: surface plot shows far fewer). ``n_radial=10**9`` asked numpy for a grid it could not
#: allocate (a builtin MemoryError).
MAX_LOCUS_POINTS = 10**7


def _locus_input(tdoa_s: float, m_i: ArrayLike, m_j: ArrayLike, c: float,
                 extent_m: float, n_radial: int, n_around: int
                 ) -> tuple[NDArray, NDArray, float]:
    """The pair (two finite points, metres, apart) and ``c * tdoa`` (metres) of a locus plot,
    or a GeometryError (NaN inputs, coincident microphones or a non-positive speed or extent
    gave all-NaN or degenerate grids; a negative grid size numpy's builtin ValueError, 0 an
    empty grid, 2.5 a TypeError, a grid beyond :data:`MAX_LOCUS_POINTS` a MemoryError; text
    positions were read as numbers)."""
    nr = whole_number("n_radial", n_radial, 1, error=GeometryError)
    na = whole_number("n_around", n_around, 1, error=GeometryError)
    if nr * na > MAX_LOCUS_POINTS:
        raise GeometryError(f"n_radial x n_around = {nr} x {na} = {nr * na} points; a locus "
                            f"plot samples at most {MAX_LOCUS_POINTS:.0e}")
    ok = real_entries(m_i) and real_entries(m_j)
    mi = np.asarray(m_i, dtype=float).reshape(-1) if ok else np.zeros(0)
    mj = np.asarray(m_j, dtype=float).reshape(-1) if ok else np.zeros(0)
    if mi.shape != (3,) or mj.shape != (3,) or not (np.all(np.isfinite(mi))
                                                   and np.all(np.isfinite(mj))):
        raise GeometryError(f"microphone positions must be finite [x, y, z] points, got {m_i!r}, "
                            f"{m_j!r}")
    if not np.linalg.norm(mi - mj) > 0:
        raise GeometryError("the two microphones coincide: a TDOA has no locus")
    c = finite_number("c (m/s)", c, 0.0, lo_open=True, error=GeometryError)
    finite_number("extent_m", extent_m, 0.0, lo_open=True, error=GeometryError)
    return mi, mj, c * finite_number("tdoa_s", tdoa_s, error=GeometryError)


def hyperboloid_points(tdoa_s: float, m_i: ArrayLike, m_j: ArrayLike, c: float = 343.0,
                       extent_m: float = 3.0, n_radial: int = 40,
                       n_around: int = 48) -> NDArray:
    """Sample the near-field locus of one TDOA: the sheet of the two-sheet hyperboloid
    ``|P - M_i| - |P - M_j| = c tdoa`` (thesis fig. 2.3).

    Returns a grid ``(n_radial, n_around, 3)`` of points (metres) out to ``extent_m`` from the
    pair's centre, ready for ``plot_surface``. A zero TDOA gives the bisecting plane's disc;
    ``|c tdoa| >= |M_i - M_j|`` raises GeometryError (no locus), and so does an ``extent_m``
    that does not reach past the sheet's vertex (``|c tdoa| / 2`` from the centre).
    """
    mi, mj, delta = _locus_input(tdoa_s, m_i, m_j, c, extent_m, n_radial, n_around)
    f = np.linalg.norm(mi - mj) / 2.0
    a = abs(delta) / 2.0
    if a >= f:
        raise GeometryError(f"|c*tdoa| = {2 * a:.4f} m is not below the spacing {2 * f:.4f} m")
    centre = (mi + mj) / 2.0
    # delta > 0: farther from M_i, i.e. the sheet on M_j's side
    axis = (mj - mi) / (2 * f) if delta >= 0 else (mi - mj) / (2 * f)
    R = _frame_from_axis(axis)
    b = np.sqrt(f * f - a * a)
    phi = np.linspace(0.0, 2.0 * np.pi, n_around)
    if a < 1e-12:
        rho = np.linspace(0.0, extent_m, n_radial)
        z = np.zeros_like(rho)
    else:
        # out to extent_m from the centre, |P - centre|^2 = a^2 + f^2 sinh(v)^2 (arcsinh(extent
        # / b) bounded the radius about the axis instead: near end-fire, where b is small, a
        # sheet asked for 3 m reached 16 m along the axis)
        if not extent_m > a:
            raise GeometryError(f"extent_m = {extent_m:g} m does not reach the sheet, whose "
                                f"vertex is {a:.4f} m from the pair's centre")
        vmax = np.arcsinh(np.sqrt(extent_m**2 - a * a) / f)
        v = np.linspace(0.0, vmax, n_radial)
        z, rho = a * np.cosh(v), b * np.sinh(v)
    local = np.stack(np.broadcast_arrays(rho[:, None] * np.cos(phi)[None, :],
                                         rho[:, None] * np.sin(phi)[None, :],
                                         z[:, None] + 0 * phi[None, :]), axis=-1)
    return centre + local @ R


def cone_points(tdoa_s: float, m_i: ArrayLike, m_j: ArrayLike, c: float = 343.0,
                extent_m: float = 3.0, n_radial: int = 20, n_around: int = 48) -> NDArray:
    """Far-field locus of one TDOA: the cone about the pair axis with ``cos(theta) =
    c tdoa / |M_i - M_j|`` (the hyperboloid's asymptote), apex at the pair's centre.

    Returns ``(n_radial, n_around, 3)`` points in metres.
    """
    mi, mj, delta = _locus_input(tdoa_s, m_i, m_j, c, extent_m, n_radial, n_around)
    d = np.linalg.norm(mi - mj)
    cos_t = delta / d
    if abs(cos_t) > 1:
        raise GeometryError("|c*tdoa| exceeds the microphone spacing: no cone")
    axis = (mj - mi) / d  # u . (mj - mi)/d = cos_t for delta = t_i - t_j > 0
    R = _frame_from_axis(axis)
    sin_t = np.sqrt(1 - cos_t**2)
    s = np.linspace(0.0, extent_m, n_radial)
    phi = np.linspace(0.0, 2 * np.pi, n_around)
    local = np.stack(np.broadcast_arrays(s[:, None] * sin_t * np.cos(phi)[None, :],
                                         s[:, None] * sin_t * np.sin(phi)[None, :],
                                         s[:, None] * cos_t + 0 * phi[None, :]), axis=-1)
    return (mi + mj) / 2.0 + local @ R


#: Largest RMS misfit (seconds) of a point of :func:`three_mic_curve` to the consistent part of
#: the TDOAs (10 ns, 3.4 um of path): points of the curve fit it exactly, to the solver's
#: precision; a point that fits to more is a near miss where the sphere of its range misses the
#: curve.
_CURVE_TOL_S = 1e-8


def three_mic_curve(tdoa_s: ArrayLike, array: MicArray | str,
                    pairs: Sequence[tuple[int, int]] | None = None,
                    ranges_m: ArrayLike | None = None) -> list[NDArray]:
    """The near-field 3D curve locus of a three-microphone system (thesis fig. 2.6).

    Two independent TDOAs fix two hyperboloids; their intersection is a curve. It is traced by
    continuation over the range from the array centre: at each range the direction satisfying
    the pair equations is found by least squares, starting from the far-field solution, for each
    mirror branch (above and below the array plane). A far-field solution in the plane (one
    candidate, e.g. a source near the array whose curved wavefront reads as ``|u_p| > 1``)
    starts both branches lifted off the plane (:data:`_PLANE_LIFT`), where the height has no
    gradient.

    Returns a list of branches, each ``(n_points, 3)`` metres, in the order of ``ranges_m``.
    A point is kept where it fits the TDOAs' consistent part (what is left after removing the
    pairs' closure residual, :func:`hearsee.audio.arrays.pair_closure_projector`) to
    :data:`_CURVE_TOL_S`; elsewhere the sphere of that range misses the curve, and that range
    has no point (nor a branch without any). Before 2026-12-02 points were kept up to 10 us of
    residual and an in-plane far-field solution started one branch in the plane, which the
    fit never left: exact TDOAs of a source 0.3 m away, 10 deg above the three-mic preset's
    plane gave one branch of in-plane near misses (1-10 us), none of them within 5 cm of the
    source or its mirror image; an in-plane source 1 m away got in-plane near misses at 0.5 m
    (7.6 us) on both branches.

    The array must be planar and the pairs must hold exactly two independent TDOAs (three
    microphones, or two pairs of a larger planar array); anything else is a GeometryError: a
    linear array's TDOAs fix a surface about its axis (:func:`hyperboloid_points`), three or
    more independent TDOAs fix a point (:func:`near_field_position`). Before 2026-12-02 a
    two-microphone or collinear array got "branches" of arbitrary points of its hyperboloid
    (the least-squares step stopped wherever it started on that surface), and a
    four-microphone array a ray of near misses.
    """
    from scipy.optimize import least_squares

    arr = load_array(array)
    prs = arr.checked_pairs(pairs)
    tau = as_tdoas(tdoa_s, len(prs))
    geo = array_geometry(arr)
    kind = geo.kind
    n_ind = _independent_tdoas(arr.n_mics, tuple(prs))
    if kind != "planar" or n_ind != 2:
        what = ("collinear microphones: their TDOAs fix a surface about the array axis, see "
                "hyperboloid_points" if kind == "linear" else
                f"a {kind} array's pairs with {n_ind} independent TDOA{'s' * (n_ind != 1)}" + (
                    ": they fix points, see near_field_position" if n_ind > 2 else ""))
        raise GeometryError(f"three_mic_curve needs the two independent TDOAs of a planar "
                            f"array (three microphones), got {what}")
    if ranges_m is not None and not real_entries(ranges_m):  # (text was read as numbers)
        raise GeometryError(f"ranges_m must be finite distances > 0 m, got {ranges_m!r}")
    ranges = np.linspace(0.3, 3.0, 40) if ranges_m is None else np.asarray(ranges_m, float)
    if ranges.ndim != 1 or ranges.size == 0 or not np.all(np.isfinite(ranges) & (ranges > 0)):
        raise GeometryError(f"ranges_m must be finite distances > 0 m, got {ranges_m!r}")
    if not np.all(np.isfinite(tau)):
        raise GeometryError("three_mic_curve needs finite TDOAs")
    pos = arr.positions
    c = arr.speed_of_sound
    I = np.array([p[0] for p in prs])
    J = np.array([p[1] for p in prs])
    centre = pos.mean(axis=0)
    # the TDOAs' consistent part (what one point's TDOAs can be): the curve is where it fits
    proj = pair_closure_projector(tuple(prs), arr.n_mics)
    tau_c = tau if proj is None else tau - proj[0] @ tau
    ff = localize_tdoa(tau, arr, prs, near_field=False)
    starts = [unit_vector_deg(a, e) for a, e in ff.candidates]
    if len(starts) == 1:  # in the plane, where the height has no gradient: lift both ways
        up = starts[0] - float(starts[0] @ geo.normal) * geo.normal
        starts = [up + s * _PLANE_LIFT * geo.normal for s in (1.0, -1.0)]
    branches = []
    for u0 in starts:
        p = np.radians(_azel(u0))
        pts = []
        for r in ranges[::-1]:  # from far (where the far-field start is good) to near

            def res(q: NDArray, r: float = r) -> NDArray:
                u = np.array([np.cos(q[1]) * np.cos(q[0]), np.cos(q[1]) * np.sin(q[0]),
                              np.sin(q[1])])
                return (pair_tdoa(centre + r * u, pos, I, J, c) - tau_c) * 1e5

            sol = least_squares(res, p)
            if np.sqrt(np.mean(sol.fun**2)) * 1e-5 <= _CURVE_TOL_S:
                p = sol.x
                q = sol.x
                pts.append(centre + r * np.array([np.cos(q[1]) * np.cos(q[0]),
                                                  np.cos(q[1]) * np.sin(q[0]), np.sin(q[1])]))
        if pts:
            branches.append(np.array(pts[::-1]))
    return branches


# ---------------------------------------------------------------------------------- recordings
def hold_dead_warning(arr: MicArray, estimate: Callable[[], Any], leave_out: bool = True,
                      stacklevel: int = 2) -> tuple[Any, tuple[int, ...]]:
    """``(estimate(), dead)``: a whole-recording estimate (``estimate()`` gives a
    :class:`~hearsee.audio.tdoa.TdoaFrames` or None) run with its warnings held and told
    again after it, in their order -- all but a dead microphone's when ``leave_out`` and two
    or more other microphones remain: ``dead`` then names the dead ones, the caller leaves
    them out and :func:`without_microphones` tells the warning with where the direction comes
    from instead of "missing or wrong" (else ``dead`` is ()). ``stacklevel`` as the caller's
    own ``warnings.warn``. One place for ``hearsee localize``, ``hearsee track``'s look-ahead
    and the live stream's wiring watch."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tf = estimate()
    dead = () if tf is None else tuple(int(m) for m in tf.dead_mics)
    if not (leave_out and dead and arr.n_mics - len(dead) >= 2):
        dead = ()
    for w in caught:
        if not (dead and issubclass(w.category, DeadMicrophoneWarning)):
            warnings.warn(w.message, w.category, stacklevel=stacklevel + 1)
    return tf, dead


def without_microphones(arr: MicArray, dead: Sequence[int], stacklevel: int = 4
                        ) -> tuple[list[int], MicArray]:
    """``(keep, sub)``: the microphones of ``arr`` other than ``dead`` and the array they make
    (numbered 0.. in ``keep``'s order, the same frame), with the
    :class:`~hearsee.errors.DeadMicrophoneWarning` that the direction comes from them alone
    (:func:`localize_recording`, ``hearsee track``)."""
    from hearsee.audio.tdoa import dead_microphones_text

    keep = [m for m in range(arr.n_mics) if m not in dead]
    sub = MicArray(arr.positions[keep], arr.speed_of_sound,
                   f"{arr.name} without microphone {', '.join(map(str, dead))}")
    warnings.warn(dead_microphones_text(dead, (
        f"the direction comes from microphones {', '.join(map(str, keep))} alone"
        + (" (two: a cone about their axis, its mirror image and elevation unresolved)"
           if len(keep) == 2 else ""))), DeadMicrophoneWarning, stacklevel=stacklevel)
    return keep, sub


def _without_dead(x: ArrayLike, fs: float, arr: MicArray, tf: Any,
                  kw: dict[str, Any]) -> dict[str, Any]:
    """:func:`localize_recording`'s document from the microphones that hear the source when
    ``tf`` (its TDOAs) found dead ones (:func:`hearsee.audio.tdoa.dead_microphones`): the
    recording's other channels localized as an array of their own, its pairs and microphone
    numbers put back in ``arr``'s (the dead microphone's pairs null), ``microphones_used`` in
    the summary, and a :class:`~hearsee.errors.DeadMicrophoneWarning` saying so. Until
    2026-12-05 every pair, frame and the summary were null: a six-microphone array with one
    microphone unplugged heard nothing. The other warnings are those of the whole recording
    (the caller's), not told again."""
    from hearsee.audio.signals import as_samples

    dead = sorted(int(m) for m in tf.dead_mics)
    keep, sub = without_microphones(arr, dead)
    with warnings.catch_warnings():
        # (the whole recording's warnings were told, in the array's own numbering: the other
        # microphones' run would tell them again, numbered as its own array's)
        warnings.simplefilter("ignore")
        doc = localize_recording(as_samples(x)[keep], fs, sub, **kw)
    label = {f"{a}-{b}": f"{keep[a]}-{keep[b]}" for a in range(len(keep))
             for b in range(a + 1, len(keep))}

    def tdoas(d: dict[str, Any]) -> dict[str, Any]:
        got = {label[k]: v for k, v in d.items()}
        return {k: got.get(k) for k in tf.pair_labels}

    for f in doc["frames"]:
        f["tdoa_s"] = tdoas(f["tdoa_s"])
    summ = doc["summary"]
    summ["tdoa_s"] = tdoas(summ["tdoa_s"])
    for src in doc.get("sources", []):
        src["tdoa_s"] = tdoas(src["tdoa_s"])
    summ["inverted_microphones"] = [keep[m] for m in summ["inverted_microphones"]]
    summ["dead_microphones"] = sorted(dead + [keep[m] for m in summ["dead_microphones"]])
    summ["sync_offsets_s"] = {label[k]: v for k, v in summ["sync_offsets_s"].items()}
    summ["microphones_used"] = [keep[m] for m in summ["microphones_used"]]
    doc["array"] = arr.to_dict()
    return doc


def localize_recording(
    x: ArrayLike,
    fs: float,
    array: MicArray | str,
    frame_ms: float = 64.0,
    hop_ms: float = 32.0,
    method: str = "phat",
    kalman: bool = True,
    pairs: Sequence[tuple[int, int]] | None = None,
    q_std_s: float | None = None,
    r_std_s: float | None = None,
    tune_kalman: bool = False,
    progress: Any = None,
    in_plane: bool = False,
    tdoa_std_s: float = DEFAULT_TDOA_STD_S,
    max_sources: int = 1,
    moving: bool = False,
    **tdoa_kwargs: Any,
) -> dict[str, Any]:
    """The per-frame pipeline behind ``hearsee localize``: GCC TDOAs -> ITD Kalman -> solver.

    Parameters
    ----------
    x : array (n_mics, n)
        The recording (row k = microphone k), sample rate ``fs`` Hz.
    array : MicArray or preset/YAML name
    frame_ms, hop_ms, method :
        Passed to :func:`hearsee.audio.tdoa.estimate_tdoas` (with ``tdoa_kwargs``).
    kalman : bool
        Smooth the valid frames' TDOAs with :class:`hearsee.audio.itd_filter.ItdKalman`
        (reference microphone 0), forward and backward
        (:meth:`~hearsee.audio.itd_filter.ItdKalman.smooth`). Its noise, by default
        (``kalman_noise`` "adaptive" in the JSON, since 2026-12-04): each frame's measurement
        noise one sample times :func:`~hearsee.audio.itd_filter.confidence_r_scale` of its GCC
        confidence, and the random walk's chosen per recording by the frames' innovation
        likelihood (:func:`~hearsee.audio.itd_filter.tune_itd_noise`) among the grid's values
        up to the ITD change per frame of a source turning at 90 deg/s
        (:func:`~hearsee.audio.itd_filter.max_itd_step_s`; a quarter sample per frame when too
        few frames tell them apart). Adopted under a rule written before its held-out run
        (geometric mean of the per-cell per-frame TDOA RMSE ratio to the former fixed model
        <= 0.8, no cell above 1.25x, >= 24 of 36 cells better): three-mic preset, 4-s
        recordings, free field at 16 and 48 kHz and RT60 0.3 s at 16 kHz, static and 45 / 90
        deg/s talkers 2 m away, male voice and white noise, 10 and 20 dB, two recordings per
        cell (held-out seeds 70/71): geometric mean **0.35**, 30 of 36 cells better, worst
        1.17x (free field 16 kHz, male voice at 90 deg/s, 10 dB: 63.5 -> 74.2 us, the raw
        frames 50); e.g. moving white noise 12.3 -> 1.0 us (16 kHz, 90 deg/s; the raw frames
        1.0), a static voice 5.9 -> 0.7 us (16 kHz, 20 dB), moving voices at 48 kHz 36.9 ->
        3.9 us (45 deg/s, 20 dB), RT60 0.3 s voices at 90 deg/s 70.9 -> 52.9 us (20 dB). The
        former fixed model (q a quarter sample per frame, r one sample, the default from
        2026-12-03, the forward filter alone before) over-smoothed the precise frames of
        moving broadband sources (the raw frames 1 us, smoothed 12). Where a voice turns fast
        in free field (90 deg/s) the default stayed above the raw frames (74 / 40 us against
        50 / 25 at 10 / 20 dB) until the smoother's re-initialisations looked back
        (:meth:`~hearsee.audio.itd_filter.ItdKalman.smooth`, 2026-12-04): 46 / 10 us there
        since, no cell of the benchmark worse (``bench/itd_filter.py``; the fixed model gained
        more on that voice, 64 -> 26 us at 10 dB, so the re-run's ratio there reads 1.75x).
        Given ``q_std_s`` or ``r_std_s`` (the other: a quarter sample per frame / one sample),
        the filter uses them as they are ("fixed"). Frames without a source stay without an
        estimate either way. The JSON's ``kalman_q_std_s`` / ``kalman_r_std_s`` /
        ``kalman_noise`` give what was used (null without the filter).
    tune_kalman : bool
        Choose ``q_std_s`` and ``r_std_s`` (those not given) per recording from a grid of both
        by the frames' innovation likelihood (:func:`hearsee.audio.itd_filter.tune_itd_noise`),
        with one measurement noise for every frame ("tuned"; ``hearsee localize
        --kalman-tuned``; 2026-12-03). On the 2026-12-03 held-out recordings (seeds 30/31, the
        conditions above) it lowered the former fixed model's per-frame TDOA RMSE in 32 of 36
        cells, geometric mean 0.44x, but raised one 1.74x (RT60 0.3 s, male voice at 45 deg/s,
        20 dB); on this default's held-out recordings (``bench/itd_filter.py``) it was worse
        than the default in 13 of 18 voice cells (free field 16 kHz, male at 45 deg/s, 10 dB:
        24.9 against 10.9 us), better where a voice turns at 90 deg/s in free field at 16 kHz
        (10 dB: 20.6 against 74.2 us), worst cell 1.88x the fixed model's. Costs 15 filter
        passes, ~0.07 s of CPU per 4 s of three-mic audio over the fixed model's one (the
        default's 3-4 passes ~0.02-0.03 s).
    progress : callable(n_frames_done), optional
    in_plane : bool
        The source lies in the plane of a planar array: directions model its spherical
        wavefront (:func:`near_field_in_plane`, assumed range 2 m), and the whole-recording
        peak search steers in-plane directions only (``estimate_tdoas(source_in_plane=True)``,
        unless ``tdoa_kwargs`` says otherwise; before 2026-11-27 it searched the whole sphere,
        unlike bench/doa.py's benchmarked setting). Default False. A masked array refuses it
        (ConfigError), as it refuses the other settings its own pipeline does not take;
        linear and volume arrays ignore it (:func:`localize_tdoa`).
    tdoa_std_s : float
        Expected TDOA error (s) of the whole-recording summary, for its near-field position
        (arrays of >= 4 microphones): whether the position is reported and its covariance
        (:func:`localize_tdoa`).
    max_sources : int
        With 2 or more (up to :data:`hearsee.audio.sources.MAX_SOURCES`), up to that many
        sources talking in turn or at once: the frames' directions clustered
        (:func:`hearsee.audio.sources.localize_sources`; a linear array's sources each from
        its frames' averaged spectra, :func:`~hearsee.audio.sources.sources_from_spectra`),
        the document's ``sources`` and each frame's ``source`` (its index there, None for
        none). Needs ``kalman=False``: the ITD filter follows one source and takes another's
        frames for outliers. The ``summary`` stays the whole recording's one estimate. Not
        for masked arrays.
    moving : bool
        With ``max_sources`` >= 2: the sources may walk -- the frames' directions are tracked
        through time instead of clustered (:func:`hearsee.audio.sources.track_sources`), at
        most ``max_sources`` at once, and each source adds ``t_start_s``, ``t_end_s`` and its
        ``path`` (``{"t_s": [...], "azimuth_deg": [...]}``, every frame of its life); its
        direction is where it was last heard
        (:func:`~hearsee.audio.sources.localize_moving_sources`).
    tdoa_kwargs :
        Further :func:`hearsee.audio.tdoa.estimate_tdoas` settings, e.g.
        ``**hearsee.audio.tdoa.SUMMARY_TUNED`` (the benchmarked whole-recording estimate).

    Returns
    -------
    dict
        The JSON document of the CLI contract::

            {"array": {...}, "sample_rate": fs, "method": ..., "kalman": bool,
             "kalman_q_std_s", "kalman_r_std_s" (the ITD filter's noise, s; null without it),
             "kalman_noise" ("adaptive", "tuned" or "fixed": how they were chosen; null),
             "band_hz": [low, high] (the band the GCC used, Hz: TdoaFrames.band_hz),
             "frames": [{"t", "tdoa_s": {"0-1": s}, "azimuth_deg", "elevation_deg",
                         "candidates": [{"azimuth_deg", "elevation_deg"}], "confidence",
                         "valid", "feasible"}],
             "summary": {"tdoa_s", "azimuth_deg", "elevation_deg", "candidates", "n_solutions",
                         "feasible", "confidence", "n_valid_frames", "position_m",
                         "position_covariance_m2", "distance_rel_std",
                         "position_tdoa_std_s", "direction_from_position",
                         "inverted_microphones", "dead_microphones",
                         "sync_offsets_s", "tonal_lines_hz", "microphones_used"},
             "sources": [{"azimuth_deg", "elevation_deg", "candidates", "tdoa_s", "share",
                          "n_frames", "spread_deg"}] (with max_sources >= 2; the frames then
                                                      hold "source"; with moving, "t_start_s",
                                                      "t_end_s" and "path" instead of
                                                      "spread_deg")}

        with None where a quantity is not resolvable (no source in the frame, elevation of a
        linear array, ...). ``microphones_used``: the microphones the directions come from --
        all of them, or, with three or more, all but the dead ones (``dead_microphones``; the
        others localize as an array of their own and the dead one's pairs are null: see
        :func:`_without_dead`). The summary localizes the whole-recording TDOA estimate (weighted
        cross spectra averaged over valid frames), not an average of frame angles. The frames'
        directions are plane waves' (a far-field direction, the same from any point of the
        frame); the summary's of a planar or volume array of four or more microphones may be
        its near-field position's, seen from the array frame's origin
        (``direction_from_position`` true; :func:`localize_tdoa`), which differs from the plane
        wave's for a talker near the array -- by its curvature error, and by parallax where the
        microphones sit away from the origin (the frame's z = 0 on a robot's floor, say).
        ``confidence`` (frames and summary) is the smallest pair's GCC peak-to-second-peak
        ratio: 0 to :data:`hearsee.audio.tdoa.MAX_CONFIDENCE` (1000), not a probability (a
        masked array's summary ``confidence`` is the probability of the chosen front/back
        half instead, 0.5-1: :func:`hearsee.audio.mask.localize_recording_mask`).
    """
    from hearsee.audio.hum import remove_lines
    from hearsee.audio.itd_filter import itd_filter_entries, smooth_recording_itds
    from hearsee.audio.signals import as_samples
    from hearsee.audio.sources import (
        MAX_SOURCES,
        frame_angle,
        localize_moving_sources,
        localize_sources,
        merge_repeated_sources,
        sources_from_spectra,
    )
    from hearsee.audio.tdoa import estimate_tdoas, frame_geometry, normalize_method

    arr = load_array(array)
    # (checked whatever the array: only a fitted position reads it, and -1 or "x" passed
    # without a word on arrays of three microphones or fewer)
    tdoa_std_s = check_tdoa_std(tdoa_std_s)
    max_sources = whole_number("max_sources", max_sources, 1, MAX_SOURCES)
    if max_sources > 1 and kalman:
        raise ConfigError("max_sources > 1 needs kalman=False: the ITD Kalman filter follows "
                          "one source and takes another's frames for outliers")
    moving = true_or_false("moving", moving)
    if moving and max_sources < 2:
        raise ConfigError("moving=True tracks several sources: give max_sources >= 2 (one "
                          "moving source is the Kalman-smoothed frames', or hearsee track)")
    if arr.mask is not None:  # masked two-microphone array: one 360-degree azimuth (ch. 3)
        from hearsee.audio.mask import localize_recording_mask

        # (its pipeline takes none of these: they were dropped without a word)
        # (in_plane too: its tables are of the horizontal plane already, and it has no
        # spherical-wavefront model or in-plane search to switch to)
        ignored = sorted(k for k, v in {"pairs": pairs, "in_plane": in_plane or None,
                                        "max_sources": max_sources if max_sources > 1 else None,
                                        **tdoa_kwargs}.items() if v is not None)
        if ignored:
            raise ConfigError(f"{', '.join(ignored)}: not available for the masked array "
                              f"{arr.name!r} (its mask pipeline sets its own); leave them out")

        return localize_recording_mask(x, fs, arr, frame_ms=frame_ms, hop_ms=hop_ms,
                                       method=method, kalman=kalman, progress=progress,
                                       q_std_s=q_std_s, r_std_s=r_std_s,
                                       tune_kalman=tune_kalman)
    if kalman and pairs is not None:  # (the filter refused them only after the estimation)
        from hearsee.audio.arrays import pair_matrix

        prs = arr.checked_pairs(pairs)
        if np.linalg.matrix_rank(pair_matrix(arr.n_mics, prs)) < arr.n_mics - 1:
            raise ConfigError(f"pairs {[tuple(p) for p in prs]}: they do not connect all "
                              f"{arr.n_mics} microphones, and the ITD Kalman filter's state is "
                              "every microphone's delay; give pairs that do, or kalman=False")
    # (a misspelt setting was estimate_tdoas' builtin TypeError)
    check_settings(estimate_tdoas, sorted(tdoa_kwargs),
                   skip=("x", "fs", "array", "frame_ms", "hop_ms", "method", "pairs", "progress"))
    method = normalize_method(method)
    tdoa_kwargs.setdefault("source_in_plane", bool(in_plane))
    tf, dead = hold_dead_warning(arr, lambda: estimate_tdoas(
        x, fs, arr, frame_ms=frame_ms, hop_ms=hop_ms, method=method, pairs=pairs,
        progress=progress, **tdoa_kwargs), leave_out=pairs is None)
    if dead:
        return _without_dead(x, fs, arr, tf, dict(
            frame_ms=frame_ms, hop_ms=hop_ms, method=method, kalman=kalman, q_std_s=q_std_s,
            r_std_s=r_std_s, tune_kalman=tune_kalman, in_plane=in_plane,
            tdoa_std_s=tdoa_std_s, max_sources=max_sources, moving=moving, **tdoa_kwargs))
    labels = tf.pair_labels
    tdoa = tf.tdoa_s
    noise: tuple[float, float] | None = None  # the filter's (q_std_s, r_std_s)
    model = None  # how they were chosen: "adaptive", "tuned" or "fixed"
    if kalman and tf.n_valid:
        # (the recording is processed whole: the smoother, which uses the later frames too)
        tdoa, noise, model = smooth_recording_itds(
            tdoa, tf.confidence, arr.n_mics, tf.pairs, fs, arr.max_tdoa(tf.pairs),
            frame_geometry(fs, frame_ms, hop_ms)[1] / fs, q_std_s, r_std_s, tune_kalman)
    # the frames' spherical wavefront of in_plane is a planar array's; for other arrays
    # in_plane is ignored, as localize_tdoa says and the stream does -- near_field=True fitted
    # a position to every frame of a volume array (18x slower) and, with five or more
    # microphones, could take the frame's direction from it (before 2026-12-02)
    frame_near = bool(in_plane) and array_geometry(arr).kind == "planar"
    locs = []
    for n in range(len(tf.t)):
        row = tdoa[n]
        ok = bool(tf.valid[n]) and bool(np.all(np.isfinite(row)))
        locs.append(localize_tdoa(row, arr, tf.pairs, near_field=frame_near, in_plane=in_plane)
                    if ok else None)
    # (max_sources > 1 runs without the filter: the frames localized above are the raw ones)
    sources, which = None, None
    if max_sources > 1 and moving:
        sources, which = localize_moving_sources(tf.t, tf.tdoa_s, tf.valid, arr, tf.pairs,
                                                 max_sources, in_plane=in_plane, locs=locs)
    elif max_sources > 1:
        sources, which = localize_sources(tf.tdoa_s, tf.valid, arr, tf.pairs, max_sources,
                                          in_plane=in_plane, locs=locs)
    if sources and not moving and array_geometry(arr).kind == "linear":  # (sources_from_spectra)
        # (estimate_tdoas looks for hum only without ``active``: the recording it filtered,
        # else every two-mic source read as the hum's TDOA 0, ~0 deg for a talker at 59 deg)
        xs = (x if not tf.tonal_lines_hz else
              remove_lines(as_samples(x), fs, tf.tonal_lines_hz))
        sources = sources_from_spectra(sources, which, lambda act: estimate_tdoas(
            xs, fs, arr, frame_ms=frame_ms, hop_ms=hop_ms, method=method, pairs=pairs,
            active=act, **tdoa_kwargs), arr, tf.pairs, in_plane)
        # (two piles of frames whose spectra name one talker: one source, not two a degree
        # apart)
        sources, which = merge_repeated_sources(
            sources, which, [np.nan if loc is None else frame_angle(loc, True)[0]
                             for loc in locs], arr, tf.pairs)
    frames = []
    for n, loc in enumerate(locs):
        row = tdoa[n]
        ok = loc is not None
        frames.append({
            "t": float(tf.t[n]),
            "tdoa_s": {k: (float(v) if ok else None) for k, v in zip(labels, row, strict=True)},
            "azimuth_deg": loc.azimuth_deg if loc else None,
            "elevation_deg": loc.elevation_deg if loc else None,
            "candidates": loc.to_dict()["candidates"] if loc else [],
            "confidence": float(np.min(tf.confidence[n])),
            "valid": ok,
            "feasible": loc.feasible if loc else None,
            **({} if which is None else {"source": int(which[n]) if which[n] >= 0 else None}),
        })
    summ = tf.summary_tdoa_s
    have = bool(np.all(np.isfinite(summ)))
    sloc = (localize_tdoa(summ, arr, tf.pairs, in_plane=in_plane, tdoa_std_s=tdoa_std_s)
            if have else None)
    summary = {
        "tdoa_s": {k: (float(v) if have else None) for k, v in zip(labels, summ, strict=True)},
        "azimuth_deg": sloc.azimuth_deg if sloc else None,
        "elevation_deg": sloc.elevation_deg if sloc else None,
        "candidates": sloc.to_dict()["candidates"] if sloc else [],
        "n_solutions": sloc.n_solutions if sloc else 0,
        "feasible": sloc.feasible if sloc else None,
        "confidence": float(np.min(tf.summary_confidence)) if have else None,
        "n_valid_frames": tf.n_valid,
        **{k: sloc.to_dict()[k] if sloc else None
           for k in ("position_m", "position_covariance_m2", "distance_rel_std",
                     "position_tdoa_std_s")},
        "direction_from_position": (sloc.extra.get("direction_model") == "position"
                                    if sloc else None),
        "method": tf.summary_method,
        "coherence_ratio": (float(tf.coherence_ratio) if np.isfinite(tf.coherence_ratio)
                            else None),
        "coherence_gain": (float(tf.coherence_gain) if np.isfinite(tf.coherence_gain)
                           else None),
        **tf.wiring_entries(),
        "microphones_used": list(range(arr.n_mics)),
    }
    return {
        "array": arr.to_dict(),
        "sample_rate": float(fs),
        "method": method,
        "kalman": bool(kalman),
        **itd_filter_entries(noise, model),
        "band_hz": None if tf.band_hz is None else [float(v) for v in tf.band_hz],
        "frames": frames,
        "summary": summary,
        **({} if sources is None else {"sources": sources}),
    }
