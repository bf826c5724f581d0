"""3D sound localization with a moving head: multiple sampling (thesis ch. 4).

Reconstruction. One pose of a planar three-microphone array fixes a 3D *curve* of candidate
source points (a direction up to the mirror through the array plane, and almost no distance);
two microphones fix only a surface. Turning the pan-tilt head (pan alpha, tilt beta; see
:class:`hearsee.geometry.HeadPose`) and sampling again gives new curves whose intersection is one
3D point: azimuth, elevation AND distance (thesis figs. 4.2-4.3). Following the thesis we
intersect the loci numerically -- as in the TDOA literature (Huang, Benesty & Elko 2001; Gustafsson
& Gunnarsson 2003; Hartley & Zisserman's multi-view triangulation as the analogy) we solve it as
one nonlinear least-squares problem over all poses:

    s* = argmin_s  sum_k sum_(i,j) rho( ((|s - m_ki| - |s - m_kj|) / c - tau_kij)^2 / sigma^2 )

with ``m_ki`` microphone i at pose k in the robot frame (:func:`hearsee.geometry.mic_positions_at`),
``tau_kij`` the measured TDOA ``t_i - t_j`` and ``rho`` a robust loss (``soft_l1`` by default,
scipy.optimize.least_squares). The cost has several local minima (the mirror, front/back and
range valleys), so the solver is multi-start: every direction of a Fibonacci sphere grid times a
geometric grid of distances is scored vectorised, and the best well-separated grid points are
refined (parameters azimuth, elevation, log distance about the head pivot, with distance bounds).

Ambiguity is reported, never hidden:

- distinct refined minima whose cost is within a chi-square gate of the best are all returned as
  ``candidates`` and ``unique=False`` (e.g. pan-only poses of a horizontal planar array keep the
  up/down mirror; a single pose always does);
- when the distance is not determined by the data (relative standard deviation from the
  covariance above ``max_rel_distance_std``, or a single pose) ``distance_m`` and ``position_m``
  are None and only the direction candidates are given.

Covariance: ``C = sigma^2 (J^T J)^-1`` with J the Jacobian of the TDOA model (s/m) with respect to
the cartesian position at the solution and ``sigma^2`` the larger of ``tdoa_std_s^2`` and the
robust residual variance ``(1.4826 MAD)^2 m / (m - 3)`` (m measurements).

Two microphones use the same solver (one TDOA per pose; more poses needed, thesis fig. 4.4). One
microphone (thesis fig. 4.5, :func:`localize_one_mic`): **assumption** -- the source repeats with a
known period T (or is re-triggered at known instants) and every capture is synchronised to that
schedule, so the arrival time of a repetition measured from the start of its own period is
``t_k = t0 + |s - p_k| / c`` with one unknown common offset t0. Differences ``t_k - t_0`` are then
range differences between the known microphone positions p_k: a *virtual array* of K positions,
solved as above.

Also here: a learned mapping from ITDs over poses to source coordinates
(:class:`PoseItdMLP`, thesis figs. 4.10-4.12), continuous sampling while the head turns
(:func:`simulate_turning_capture`, :func:`localize_continuous`, thesis 4.7, fig. 4.14), and an
active alignment loop that turns the head to face the source (:func:`align_head`, figs. 4.15-4.17).

Frames and units: positions in the robot frame (REP 103), metres; TDOAs in seconds; angles in
degrees where the name ends in ``_deg``. Azimuth, elevation and distance are as seen from the head
pivot (``pivot_m``), the fixed point of the pan-tilt head.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from hearsee.audio.arrays import (
    DEFAULT_TDOA_STD_S,
    MicArray,
    check_tdoa_std,
    load_array,
    load_array_beside,
    pair_tdoa,
    position_uncertainty,
)
from hearsee.audio.propagation import check_snr_db, speed_of_sound_of
from hearsee.audio.signals import as_samples, check_fs, microphone_channels
from hearsee.config import (
    as_float_array,
    as_path,
    as_rng,
    check_rng,
    finite_number,
    is_real,
    real_entries,
    same_file,
    whole_number,
)
from hearsee.errors import (
    AudioInputError,
    ConfigError,
    EstimationError,
    GeometryError,
    InconsistentMeasurementWarning,
)
from hearsee.geometry import (
    HeadPose,
    angle_between,
    as_point,
    as_pose,
    check_angle_limits,
    check_head_offset,
    check_head_pivot,
    direction_deg,
    fibonacci_sphere,
    mic_positions_at,
    robot_to_array,
    sph_to_cart,
    unit_vector_deg,
    vector_length,
    wrap_deg,
)

__all__ = [
    "Position3D",
    "PoseItdMLP",
    "AlignmentResult",
    "align_head",
    "align_head_search",
    "capture_tdoas",
    "facing_pair",
    "fibonacci_sphere",
    "localize_continuous",
    "load_pose_manifest",
    "parse_poses",
    "localize_manifest",
    "localize_multipose",
    "localize_one_mic",
    "make_pose_training_set",
    "one_mic_arrival_differences",
    "pose_mic_positions",
    "PoseManifest",
    "simulate_pose_captures",
    "simulate_pose_manifest",
    "simulate_turning_capture",
    "solve_range_differences",
    "train_pose_mlp",
]

#: Largest root-mean-square TDOA residual of a multi-pose solution still called consistent
#: (:attr:`Position3D.consistent`), in units of the solver's ``tdoa_std_s``: 30 us with the
#: default :data:`DEFAULT_TDOA_STD_S`, half a sample at 16 kHz. In a
#: study of 2-5 poses (three-mic on a pan-tilt head, synthetic voices 0.5-3 m away, anechoic and
#: RT60 0.3 / 0.6 s, SNR 0-20 dB; 2026-11-24, seeds 5 and 6) the true-pose solutions had
#: residuals of 2-13 us at 20 dB; those above 30 us were 0 dB captures in rooms, whose
#: direction errors had a median of ~12 deg (2 deg below 10 us). One pose's pan angle told 20
#: deg wrong gave 40-55 us at 20 dB, 5 deg 7-15 us (not flagged); a sign slip, ~300 us.
MAX_RESIDUAL_SIGMAS = 6.0
#: Distance (m) standing in for "infinitely far" in direction-only (far-field) solves.
FAR_DISTANCE_M = 1000.0


# ------------------------------------------------------------------------------- results
@dataclass
class Position3D:
    """A 3D source estimate from several poses.

    Attributes
    ----------
    position_m : array (3,) or None
        Source position in the robot frame (None when the distance is not determined).
    azimuth_deg, elevation_deg : float
        Direction of the best candidate as seen from the reference point (head pivot); when
        the distance is not determined, the far-field direction (the same from any point of
        the head, i.e. as seen from the array).
    distance_m : float or None
        Distance from the reference point; None when the data do not determine it.
    covariance : array (3, 3) or None
        Position covariance in m^2 (robot frame); None when the distance is not determined.
    unique : bool
        True only when one candidate remains AND its distance is determined.
    candidates : list of dict
        Every acceptable solution (best first): ``azimuth_deg``, ``elevation_deg``,
        ``distance_m`` (or None), ``position_m`` (or None), ``cost``.
    direction_std_deg : float
        1-sigma angular uncertainty of the best candidate's direction.
    distance_rel_std : float
        1-sigma relative distance uncertainty (inf when undetermined).
    condition : float
        Condition number of the Jacobian at the solution (its columns are all in metres, so
        it is not scaled).
    cost : float
        Robust cost of the best candidate (residuals in units of ``tdoa_std_s``).
    residual_rms_s : float
        Root-mean-square TDOA residual of the best candidate, seconds: how well one source
        explains every pose's measurements.
    consistent : bool
        False when ``residual_rms_s`` exceeds the solver's ``max_residual_rms_s`` (default 6x
        its ``tdoa_std_s``, 30 us): the
        measurements contradict each other (wrong pose angles, swapped channels, two
        sources, strong reflections), and the position should not be trusted. False too when
        the best fit sits at the near end of the solver's ``distance_bounds_m``: the source
        is nearer than it searches, and the fit at the bound is off.
    n_poses : int
        Number of poses (microphone sets) used.
    """

    position_m: NDArray | None
    azimuth_deg: float
    elevation_deg: float
    distance_m: float | None
    covariance: NDArray | None
    unique: bool
    candidates: list[dict[str, Any]] = field(default_factory=list)
    direction_std_deg: float = float("nan")
    distance_rel_std: float = float("inf")
    condition: float = float("inf")
    cost: float = float("nan")
    residual_rms_s: float = float("nan")
    consistent: bool = True
    n_poses: int = 0

    @property
    def direction(self) -> NDArray:
        """Unit vector of the best candidate's direction (robot frame)."""
        return unit_vector_deg(self.azimuth_deg, self.elevation_deg)

    def to_dict(self) -> dict[str, Any]:
        """JSON form (the ``hearsee localize3d`` output)."""
        return {
            "position_m": None if self.position_m is None else self.position_m.tolist(),
            "azimuth_deg": self.azimuth_deg,
            "elevation_deg": self.elevation_deg,
            "distance_m": self.distance_m,
            "covariance": None if self.covariance is None else self.covariance.tolist(),
            "unique": bool(self.unique),
            "candidates": self.candidates,
            "direction_std_deg": self.direction_std_deg,
            "distance_rel_std": self.distance_rel_std,
            "condition": self.condition,
            "residual_rms_s": self.residual_rms_s,
            "consistent": bool(self.consistent),
            "n_poses": self.n_poses,
        }


# ------------------------------------------------------------------------------- helpers
def pose_mic_positions(array: MicArray | str, poses: Sequence[HeadPose | Sequence[float]],
                       pivot_m: ArrayLike = (0.0, 0.0, 0.0),
                       offset_m: ArrayLike = (0.0, 0.0, 0.0)) -> list[NDArray]:
    """Microphone positions ``(n_mics, 3)`` in the robot frame for each pose; ``pivot_m``
    within :data:`~hearsee.geometry.MAX_HEAD_PIVOT_M` of the origin
    (:func:`~hearsee.geometry.check_head_pivot`)."""
    arr = load_array(array)
    pivot = check_head_pivot(pivot_m)
    # (an offset of 1e160 m overflowed the solver's residuals: scipy's ValueError)
    offset = check_head_offset(offset_m)
    return [mic_positions_at(arr, p, pivot, offset) for p in pose_list(poses)]


def pose_list(poses: Any) -> list[HeadPose]:
    """``poses`` (a sequence of :class:`~hearsee.geometry.HeadPose` or (pan, tilt) degrees) as a
    list of HeadPose, at least one; a GeometryError otherwise (None or a number raised a
    builtin TypeError, an empty list numpy's "need at least one array")."""
    if isinstance(poses, str | bytes) or not isinstance(poses, Sequence | np.ndarray):
        raise GeometryError(f"poses must be a sequence of head poses (pan, tilt) in degrees, "
                            f"got {poses!r:.60}")
    out = [as_pose(p) for p in poses]
    if not out:
        raise GeometryError("at least one head pose is needed")
    return out


def facing_pair(array: MicArray | str) -> tuple[int, int] | None:
    """The pair of microphones mirror-symmetric about the array's x-z plane (their TDOA
    vanishes when the head faces the source), or None. For ``three-mic`` it is (1, 2).
    ``array``: a MicArray, a preset name or a YAML path."""
    array = load_array(array)
    p = array.positions
    best, err = None, np.inf
    for i, j in array.pairs:
        m = p[j] * [1.0, -1.0, 1.0]
        e = float(np.linalg.norm(p[i] - m))
        if e < err and abs(p[i, 1]) > 1e-3:
            best, err = (i, j), e
    return best if err < 1e-3 else None


# ------------------------------------------------------------------------------- core solver
def _stack(mic_sets: Sequence[ArrayLike], pairs: Sequence[Sequence[tuple[int, int]]],
           tdoa_s: Sequence[ArrayLike]) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Stack per-set measurements into global microphone rows (a, b) and values."""
    try:
        counts = (len(mic_sets), len(pairs), len(tdoa_s))
    except TypeError:  # (a number where a list of poses belongs)
        counts = None
    if counts is None or not (counts[0] == counts[1] == counts[2]):
        raise GeometryError("mic_sets, pairs and tdoa_s must have one entry per pose")
    mics, a_idx, b_idx, vals = [], [], [], []
    base = 0
    for k, (m, prs, t) in enumerate(zip(mic_sets, pairs, tdoa_s, strict=True)):
        m = as_float_array(m, f"pose {k}: microphone positions", finite=False, error=GeometryError)
        if m.ndim != 2 or m.shape[1] != 3 or not np.all(np.isfinite(m)):
            raise GeometryError(f"pose {k}: microphone positions must be finite N x 3")
        t = np.atleast_1d(as_float_array(t, f"pose {k}: TDOAs", finite=False,
                                         error=GeometryError))
        prs = _index_pairs(prs, k)
        if t.ndim != 1 or len(t) != len(prs):
            raise GeometryError(f"pose {k}: {t.size} TDOAs for {len(prs)} pairs")
        for (i, j), v in zip(prs, t, strict=True):
            if not (0 <= i < len(m) and 0 <= j < len(m)) or i == j:
                raise GeometryError(f"pose {k}: invalid pair ({i}, {j}) for {len(m)} microphones")
            if np.isinf(v):  # (NaN is "not measured"; an infinite one was dropped silently)
                raise EstimationError(f"pose {k}: TDOA of pair ({i}, {j}) is {v}; give NaN "
                                      "for a pair that was not measured")
            if np.isfinite(v):
                a_idx.append(base + i)
                b_idx.append(base + j)
                vals.append(v)
        mics.append(m)
        base += len(m)
    if not vals:
        raise EstimationError("no finite TDOA measurement to localize from")
    M, a, b = np.vstack(mics), np.array(a_idx), np.array(b_idx)
    if not np.any(np.linalg.norm(M[a] - M[b], axis=1) > 1e-6):
        # (every pair's TDOA is then 0 wherever the source is: a direction was returned anyway)
        raise GeometryError("the microphone positions of every measured pair coincide: their "
                            "TDOAs say nothing about the source")
    return M, a, b, np.array(vals)


def _index_pairs(prs: Any, k: int) -> list[tuple[int, int]]:
    """Pose ``k``'s pairs as a list of (i, j) microphone indices; GeometryError for anything
    else (a pair of text, floats or three numbers was a builtin TypeError or ValueError)."""
    try:
        out = [tuple(p) for p in prs]
    except TypeError:
        out = None
    if out is None or not all(
            len(p) == 2 and all(isinstance(i, int | np.integer) and not isinstance(i, bool)
                                for i in p) for p in out):
        raise GeometryError(f"pose {k}: pairs must be (i, j) microphone indices, got "
                            f"{repr(prs)[:80]}")
    return [(int(i), int(j)) for i, j in out]


def _rho(z: NDArray, loss: str) -> NDArray:
    """scipy's robust loss rho(z) of squared residuals z (f_scale applied by the caller)."""
    if loss == "linear":
        return z
    if loss == "soft_l1":
        return 2.0 * (np.sqrt(1.0 + z) - 1.0)
    if loss == "huber":
        return np.where(z <= 1.0, z, 2.0 * np.sqrt(z) - 1.0)
    if loss == "cauchy":
        return np.log1p(z)
    if loss == "arctan":
        return np.arctan(z)
    raise GeometryError(f"unknown loss {loss!r} (linear, soft_l1, huber, cauchy, arctan)")


def _mirror_images(p: NDArray, mic_sets: Sequence[ArrayLike]) -> list[NDArray]:
    """Mirror images of the point ``p`` (metres) through the plane of each planar pose's
    microphones (three, or more in one plane); a planar array cannot tell them from ``p``."""
    out = []
    for mset in mic_sets:
        mset = np.asarray(mset, dtype=float)
        if len(mset) < 3:
            continue
        cen = mset.mean(axis=0)
        _, sv, vt = np.linalg.svd(mset - cen)
        if sv[-1] > 1e-6 * sv[0] and len(mset) > 3:
            continue  # not planar: no mirror
        nrm = vt[-1]
        out.append(p - 2.0 * ((p - cen) @ nrm) * nrm)
    return out


def solve_range_differences(
    mic_sets: Sequence[ArrayLike],
    pairs: Sequence[Sequence[tuple[int, int]]],
    tdoa_s: Sequence[ArrayLike],
    speed_of_sound: float = 343.0,
    *,
    reference_m: ArrayLike = (0.0, 0.0, 0.0),
    tdoa_std_s: float = DEFAULT_TDOA_STD_S,
    loss: str = "soft_l1",
    f_scale: float = 3.0,
    distance_bounds_m: tuple[float, float] = (0.2, 20.0),
    n_directions: int = 800,
    n_distances: int = 12,
    n_starts: int = 8,
    min_separation_deg: float = 5.0,
    ambiguity_gate: float = 9.0,
    ambiguity_ratio: float = 0.5,
    max_rel_distance_std: float = 0.5,
    max_residual_rms_s: float | None = None,
    resolve_distance: bool = True,
) -> Position3D:
    """Source position from TDOAs of several microphone sets (poses) by robust least squares.

    Parameters
    ----------
    mic_sets : list of arrays (n_k, 3)
        Microphone positions of each pose in the robot frame, metres.
    pairs : list of lists of (i, j)
        Pairs measured at each pose (indices into that pose's microphones).
    tdoa_s : list of arrays (n_pairs_k,)
        Measured ``t_i - t_j`` in seconds; NaN entries are skipped.
    speed_of_sound : float
        m/s.
    reference_m : (3,)
        Point the azimuth/elevation/distance are measured from (the head pivot), robot frame.
    tdoa_std_s : float
        Expected TDOA standard deviation (s); residuals are measured in this unit.
    loss, f_scale : str, float
        Robust loss of scipy.optimize.least_squares and its soft threshold (in units of
        ``tdoa_std_s``).
    distance_bounds_m : (min, max)
        Search range of the distance from ``reference_m``.
    n_directions, n_distances, n_starts : int
        Multi-start grid (Fibonacci directions x geometric distances) and refined starts.
    min_separation_deg : float
        Candidates closer than this in direction (and within 25 % in distance) are one solution.
    ambiguity_gate, ambiguity_ratio : float
        A distinct minimum is an acceptable alternative when its chi-square
        (sum of squared normalised residuals) is within ``max(ambiguity_gate,
        ambiguity_ratio * chi2_best)`` of the best.
    max_rel_distance_std : float
        Above this relative 1-sigma distance uncertainty the distance is reported as unknown;
        so is a distance held at the far end of ``distance_bounds_m`` (only a lower bound).
    max_residual_rms_s : float, optional
        Above this root-mean-square TDOA residual (s) of the best candidate the answer is
        flagged ``consistent=False``; default :data:`MAX_RESIDUAL_SIGMAS` x ``tdoa_std_s``.
    resolve_distance : bool
        False forces a direction-only answer (used for a single pose).

    Returns
    -------
    Position3D
    """
    M, a, b, y = _stack(mic_sets, pairs, tdoa_s)
    c = speed_of_sound_of(None, speed_of_sound)  # (a negative c mirrored the direction)
    ref = as_point(reference_m, "reference_m")
    f_scale = finite_number("f_scale", f_scale, 0.0, lo_open=True, error=GeometryError)
    n_directions, n_distances, n_starts = (
        whole_number(name, v, error=GeometryError) for name, v in
        (("n_directions", n_directions), ("n_distances", n_distances), ("n_starts", n_starts)))
    sig = check_tdoa_std(tdoa_std_s)
    # (unchecked until 2026-12-02: a NaN min_separation_deg refined one start only, a NaN
    # max_rel_distance_std never reported a distance, a NaN or negative max_residual_rms_s
    # called every answer inconsistent, a NaN gate kept every minimum; text raised builtin
    # TypeErrors and ValueErrors)
    min_separation_deg = finite_number("min_separation_deg", min_separation_deg, 0.0, 180.0,
                                       error=GeometryError)
    ambiguity_gate = finite_number("ambiguity_gate", ambiguity_gate, 0.0, error=GeometryError)
    ambiguity_ratio = finite_number("ambiguity_ratio", ambiguity_ratio, 0.0,
                                    error=GeometryError)
    for name, v in (("max_rel_distance_std", max_rel_distance_std),
                    ("max_residual_rms_s", max_residual_rms_s)):
        if v is None and name == "max_residual_rms_s":
            continue
        if isinstance(v, bool) or not ((is_real(v) or v == np.inf) and v > 0):
            raise GeometryError(f"{name} must be a number > 0 (inf: no limit), got {v!r}")
    bounds = as_float_array(distance_bounds_m, "distance_bounds_m", finite=False,
                            error=GeometryError)
    if bounds.shape != (2,) or not (0 < bounds[0] < bounds[1] < np.inf):
        raise GeometryError(f"distance_bounds_m must be 0 < min < max, got {distance_bounds_m}")
    rmin, rmax = float(bounds[0]), float(bounds[1])
    fs2 = f_scale * f_scale
    far = not resolve_distance
    if far:  # direction only: a source 1 km away is a plane wave to within 1e-7 s
        rmin, rmax = FAR_DISTANCE_M, FAR_DISTANCE_M * (1 + 1e-9)

    # --- multi-start grid, scored vectorised
    dirs = fibonacci_sphere(n_directions)
    dists = (np.array([FAR_DISTANCE_M]) if far
             else np.geomspace(rmin * 1.05, rmax / 1.05, n_distances))
    pts = ref + dists[None, :, None] * dirs[:, None, :]  # (D, R, 3)
    z = ((pair_tdoa(pts, M, a, b, c) - y) / sig) ** 2
    grid_cost = 0.5 * fs2 * np.sum(_rho(z / fs2, loss), axis=-1)  # (D, R)
    best_r = np.argmin(grid_cost, axis=1)
    dir_cost = grid_cost[np.arange(len(dirs)), best_r]
    order = np.argsort(dir_cost)
    starts: list[int] = []
    cos_sep = np.cos(np.radians(max(3 * min_separation_deg, 15.0)))
    for k in order:
        if all(dirs[k] @ dirs[j] < cos_sep for j in starts):
            starts.append(int(k))
        if len(starts) >= n_starts:
            break

    # --- refine each start in (az, el, log r) about the reference
    def resid(theta: NDArray) -> NDArray:
        p = ref + sph_to_cart(theta[0], theta[1], np.exp(theta[2]))
        return (pair_tdoa(p, M, a, b, c) - y) / sig

    lo = np.array([-np.inf, -np.pi / 2, np.log(rmin)])
    hi = np.array([np.inf, np.pi / 2, np.log(rmax)])

    def refine(x0: NDArray) -> tuple[float, float, NDArray, NDArray]:
        if far:
            res = least_squares(lambda t: resid(np.append(t, np.log(FAR_DISTANCE_M))),
                                x0[:2], bounds=(lo[:2], hi[:2]), loss=loss,
                                f_scale=f_scale, x_scale=np.array([0.1, 0.1]), max_nfev=200)
            res.x = np.append(res.x, np.log(FAR_DISTANCE_M))
        else:
            res = least_squares(resid, x0, bounds=(lo, hi), loss=loss, f_scale=f_scale,
                                x_scale=np.array([0.1, 0.1, 0.5]), max_nfev=200)
        th = res.x
        p = ref + sph_to_cart(th[0], th[1], np.exp(th[2]))
        return float(res.cost), float(np.sum(res.fun**2)), p, th

    sols = []
    for k in starts:
        az, el = np.arctan2(dirs[k, 1], dirs[k, 0]), np.arcsin(np.clip(dirs[k, 2], -1, 1))
        x0 = np.array([az, el, np.log(dists[best_r[k]])])
        sols.append(refine(np.clip(x0, lo + 1e-9, hi - 1e-9)))
    if not sols:
        raise EstimationError("the multi-pose solver found no solution")
    sols.sort(key=lambda s: s[0])

    # the mirror images of the best point through each planar pose's array plane are
    # explicit starts too (the grid cannot separate a mirror pair close to the plane)
    for q in _mirror_images(sols[0][2], mic_sets):
        v = q - ref
        rq = float(np.clip(np.linalg.norm(v), rmin * 1.0001, rmax / 1.0001))
        x0 = np.array([np.arctan2(v[1], v[0]), np.arcsin(np.clip(v[2] / np.linalg.norm(v), -1, 1)),
                       np.log(rq)])
        x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)
        sols.append(refine(x0))
    sols.sort(key=lambda s: s[0])

    best_chi2 = sols[0][1]
    gate = max(ambiguity_gate, ambiguity_ratio * best_chi2)
    kept: list[tuple[float, float, NDArray, bool]] = []
    cos_min = np.cos(np.radians(min_separation_deg))
    info = {}
    for cost, chi2, p, th in sols:
        if chi2 - best_chi2 > gate:
            continue
        cov, rel, ang, cond = position_uncertainty(p, M, a, b, c, y, sig, ref,
                                                   max_rel_distance_std)
        # a distance held at the search's far bound is the bound, not a measurement: the data
        # say only "at least this far" (sources 25-100 m away, a head offset of 0.3-0.6 m,
        # were reported 20.0 m away, unique, with a relative 1-sigma of 0.2-0.46)
        at_far_bound = bool(th[2] >= np.log(rmax) - 1e-6)
        known = resolve_distance and rel <= max_rel_distance_std and not at_far_bound
        u = (p - ref) / np.linalg.norm(p - ref)
        r = np.linalg.norm(p - ref)
        dup = False
        for (_c2, _x2, q, kn2) in kept:
            v = (q - ref) / np.linalg.norm(q - ref)
            if u @ v >= cos_min and (
                not (known and kn2) or abs(np.log(r / np.linalg.norm(q - ref))) < 0.25
            ):
                dup = True
                break
        if dup:
            continue
        kept.append((cost, chi2, p, known))
        info[len(kept) - 1] = (cov, np.inf if at_far_bound else rel, ang, cond)

    cands = []
    for (cost, _chi2, p, known) in kept:
        az, el = direction_deg(p - ref)
        r = float(np.linalg.norm(p - ref))
        cands.append({
            "azimuth_deg": float(az),
            "elevation_deg": float(el),
            "distance_m": r if known else None,
            "position_m": p.tolist() if known else None,
            "cost": float(cost),
        })
    cov, rel, ang, cond = info[0]
    cost0, chi0, p0, known0 = kept[0]
    if not known0 and not far:
        # the data do not fix the distance: answer with the far-field direction(s) instead of
        # points spread along the range valley
        kw = dict(reference_m=ref, tdoa_std_s=sig, loss=loss, f_scale=f_scale,
                  n_directions=n_directions, n_starts=n_starts,
                  min_separation_deg=min_separation_deg, ambiguity_gate=ambiguity_gate,
                  ambiguity_ratio=ambiguity_ratio, max_residual_rms_s=max_residual_rms_s,
                  resolve_distance=False)
        out = solve_range_differences(mic_sets, pairs, tdoa_s, speed_of_sound, **kw)
        out.distance_rel_std = rel
        return out
    az0, el0 = direction_deg(p0 - ref)
    rms = sig * float(np.sqrt(chi0 / y.size))  # chi0: the best fit's sum of squared residuals / sig
    # a best fit held at the search's near bound: the source is nearer than the model is
    # searched (exact TDOAs of a source 0.15 m from the pivot: 0.200 m, 6.6 deg off, called
    # unique and consistent; found by a review helper)
    at_near_bound = not far and bool(sols[0][3][2] <= np.log(rmin) + 1e-6)
    return Position3D(
        position_m=p0 if known0 else None,
        azimuth_deg=float(az0),
        elevation_deg=float(el0),
        distance_m=float(np.linalg.norm(p0 - ref)) if known0 else None,
        covariance=cov if known0 else None,
        unique=bool(len(kept) == 1 and known0),
        candidates=cands,
        direction_std_deg=ang,
        distance_rel_std=rel,
        condition=cond,
        cost=float(cost0),
        residual_rms_s=rms,
        consistent=bool(rms <= (MAX_RESIDUAL_SIGMAS * sig if max_residual_rms_s is None
                                else float(max_residual_rms_s))) and not at_near_bound,
        n_poses=len(mic_sets),
    )


def localize_multipose(
    tdoa_s: ArrayLike | Sequence[ArrayLike],
    poses: Sequence[HeadPose | Sequence[float]],
    array: MicArray | str,
    *,
    pairs: Sequence[tuple[int, int]] | None = None,
    pivot_m: ArrayLike = (0.0, 0.0, 0.0),
    offset_m: ArrayLike = (0.0, 0.0, 0.0),
    **kwargs: Any,
) -> Position3D:
    """Source position in the robot frame from TDOAs measured at K head poses.

    Parameters
    ----------
    tdoa_s : array (K, n_pairs) or list of K arrays
        TDOAs ``t_i - t_j`` (s) of ``pairs`` measured with the head at each pose (NaN = missing).
    poses : list of HeadPose or (pan_deg, tilt_deg)
        The head pose of each capture.
    array : MicArray or preset name
        The microphones in the array (head) frame; 2, 3 or more microphones.
    pairs : list of (i, j), optional
        Default: all pairs of the array.
    pivot_m, offset_m : (3,)
        Head pivot in the robot frame and array origin relative to it in the head frame
        (:func:`hearsee.geometry.mic_positions_at`).
    **kwargs
        Passed to :func:`solve_range_differences` (``tdoa_std_s``, ``loss``, ...).

    A single pose never reports a distance (direction candidates only, mirror included).

    >>> arr = load_array("three-mic")
    >>> src = np.array([1.2, 0.8, 0.5])
    >>> poses = [(0, 0), (40, 25), (-40, -20)]
    >>> tau = [MicArray(mic_positions_at(arr, p, offset_m=(0.1, 0, 0))).tdoa(src) for p in poses]
    >>> est = localize_multipose(tau, poses, arr, offset_m=(0.1, 0, 0))
    >>> est.unique, np.round(est.position_m, 3).tolist()
    (True, [1.2, 0.8, 0.5])
    """
    arr = load_array(array)
    prs = list(arr.pairs if pairs is None else pairs)
    poses = pose_list(poses)
    if isinstance(tdoa_s, str | bytes) or not isinstance(tdoa_s, Sequence | np.ndarray):
        raise GeometryError(f"tdoa_s must be one TDOA vector (s) per pose, got {tdoa_s!r:.60}")
    t = [np.atleast_1d(as_float_array(v, f"pose {k}: TDOAs", finite=False, error=GeometryError))
         for k, v in enumerate(tdoa_s)]
    if len(t) != len(poses):
        raise GeometryError(f"{len(t)} TDOA vectors for {len(poses)} poses")
    mic_sets = pose_mic_positions(arr, poses, pivot_m, offset_m)
    if "speed_of_sound" in kwargs:  # (a builtin "multiple values" TypeError)
        raise ConfigError("localize_multipose takes the speed of sound from the array "
                          "(its speed_of_sound); do not pass it")
    kwargs.setdefault("reference_m", np.asarray(pivot_m, dtype=float))
    if len(poses) == 1:
        kwargs["resolve_distance"] = False
    return solve_range_differences(mic_sets, [prs] * len(poses), t, arr.speed_of_sound, **kwargs)


def localize_one_mic(
    arrival_times_s: ArrayLike,
    mic_positions_m: ArrayLike,
    speed_of_sound: float = 343.0,
    **kwargs: Any,
) -> Position3D:
    """Source position from ONE microphone moved to K known positions (thesis fig. 4.5).

    Assumption (documented in the module): the source repeats with a known period (or is
    re-triggered at known instants) and each capture is synchronised to it, so
    ``arrival_times_s[k]`` -- the arrival time of the repetition heard at position k, measured
    from the start of that repetition -- equals ``t0 + |s - p_k| / c`` with one unknown t0. The
    differences to position 0 are range differences of a virtual array of K positions.

    Parameters
    ----------
    arrival_times_s : array (K,)
        Seconds, see above (any common offset cancels).
    mic_positions_m : array (K, 3)
        The microphone's positions in the robot frame, metres (K >= 4 for a 3D point).
    **kwargs
        Passed to :func:`solve_range_differences`.
    """
    t = as_float_array(arrival_times_s, "arrival_times_s", finite=False,
                       error=GeometryError).ravel()
    P = as_float_array(mic_positions_m, "mic_positions_m", finite=False, error=GeometryError)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) != len(t):
        raise GeometryError(
            f"need one [x, y, z] microphone position per arrival time, got {P.shape} for {len(t)}"
        )
    if len(t) < 3:
        raise GeometryError("one-microphone localization needs at least 3 positions")
    prs = [(k, 0) for k in range(1, len(t))]
    kwargs.setdefault("reference_m", P.mean(axis=0))
    res = solve_range_differences([P], [prs], [t[1:] - t[0]], speed_of_sound, **kwargs)
    res.n_poses = len(t)
    return res


def one_mic_arrival_differences(captures: Sequence[ArrayLike], fs: float,
                                mic_positions_m: ArrayLike, speed_of_sound: float = 343.0,
                                **kwargs: Any) -> NDArray:
    """Arrival-time differences ``t_k - t_0`` (s, shape ``(K-1,)``) of a repeating source heard
    by ONE microphone at K known positions (input of :func:`localize_one_mic`).

    Each capture must be synchronised to one repetition of the source (same start offset within
    the period -- the assumption of :func:`localize_one_mic`). The K captures are treated as the
    channels of a virtual array at ``mic_positions_m`` and their GCC-PHAT summary TDOAs against
    capture 0 are returned (``**kwargs`` go to :func:`hearsee.audio.tdoa.estimate_tdoas`).
    """
    from hearsee.audio.tdoa import estimate_tdoas

    P = as_float_array(mic_positions_m, "mic_positions_m", finite=False, error=GeometryError)
    if not isinstance(captures, list | tuple) and not (
            isinstance(captures, np.ndarray) and captures.ndim == 2):
        raise AudioInputError(f"captures must be a list of 1-D recordings, got "
                              f"{type(captures).__name__}")
    caps = [as_samples(c, f"capture {k}").ravel() for k, c in enumerate(captures)]
    if P.ndim != 2 or len(caps) != len(P) or len(caps) < 2:
        raise GeometryError(f"need one [x, y, z] position per capture (>= 2), got positions of "
                            f"shape {P.shape} for {len(caps)} captures")
    n = min(len(c) for c in caps)
    virt = MicArray(P, speed_of_sound, name="one-mic-virtual")
    fr = estimate_tdoas(np.stack([c[:n] for c in caps]), fs, virt,
                        pairs=[(k, 0) for k in range(1, len(caps))], **kwargs)
    tau = np.asarray(fr.summary_tdoa_s, dtype=float)
    if not np.all(np.isfinite(tau)):
        raise EstimationError("no common source found in the one-microphone captures")
    return tau


# ------------------------------------------------------------------------------- measurement
def capture_tdoas(x: ArrayLike, fs: float, array: MicArray | str, *,
                  frame_ms: float = 64.0, hop_ms: float = 32.0, method: str = "phat",
                  **kwargs: Any) -> NDArray:
    """Whole-recording TDOAs ``(n_pairs,)`` of one capture (CORE's summary GCC estimate).

    Raises EstimationError when no frame holds a source.
    """
    from hearsee.audio.tdoa import estimate_tdoas

    fr = estimate_tdoas(x, fs, array, frame_ms=frame_ms, hop_ms=hop_ms, method=method, **kwargs)
    tau = np.asarray(fr.summary_tdoa_s, dtype=float)
    if not np.all(np.isfinite(tau)):
        raise EstimationError("no frame of the capture holds a source; cannot measure TDOAs")
    return tau


def simulate_pose_captures(
    signal: ArrayLike,
    fs: float,
    array: MicArray | str,
    source_m: ArrayLike,
    poses: Sequence[HeadPose | Sequence[float]],
    *,
    pivot_m: ArrayLike = (0.0, 0.0, 0.0),
    offset_m: ArrayLike = (0.0, 0.0, 0.0),
    snr_db: float | None = None,
    rng: np.random.Generator | int | None = None,
    room_dim: ArrayLike | None = None,
    rt60: float = 0.0,
    robot_at: ArrayLike | None = None,
) -> list[NDArray]:
    """One capture ``(n_mics, n)`` per head pose of a static source (robot frame, metres).

    Free field by default (:func:`hearsee.audio.propagation.simulate_free_field`); with
    ``room_dim`` a pyroomacoustics shoebox room (:func:`hearsee.audio.propagation.simulate_room`)
    of reverberation time ``rt60`` s in which the robot frame's origin sits at ``robot_at``
    (room coordinates, axes parallel to the room's) -- the head turns between captures, the
    room stays.
    """
    from hearsee.audio import propagation as prop

    arr = load_array(array)
    rng = as_rng(rng)
    # (np.asarray read True as 1 m and "0.5" as 0.5 m, text was numpy's ValueError; poses None
    # a builtin TypeError, [] an empty list of captures)
    src = as_point(source_m, "source_m")
    out = []
    for pose in pose_list(poses):
        mics = mic_positions_at(arr, pose, pivot_m, offset_m)
        if room_dim is None:
            y = prop.simulate_free_field(signal, fs, mics, src, snr_db=snr_db, rng=rng,
                                         speed_of_sound=arr.speed_of_sound)
        else:
            at = np.zeros(3) if robot_at is None else np.asarray(robot_at, dtype=float)
            y = prop.simulate_room(signal, fs, arr, src, room_dim, rt60, at, snr_db, rng,
                                   mic_positions=mics)
        out.append(np.asarray(y))
    return out


# ------------------------------------------------------------------------ learned mapping
def make_pose_training_set(
    array: MicArray | str,
    poses: Sequence[HeadPose | Sequence[float]],
    n: int,
    *,
    pivot_m: ArrayLike = (0.0, 0.0, 0.0),
    offset_m: ArrayLike = (0.0, 0.0, 0.0),
    distance_range_m: tuple[float, float] = (0.5, 3.0),
    elevation_range_deg: tuple[float, float] = (-30.0, 60.0),
    azimuth_range_deg: tuple[float, float] = (-180.0, 180.0),
    tdoa_std_s: float = DEFAULT_TDOA_STD_S,
    rng: np.random.Generator | int | None = 0,
) -> tuple[NDArray, NDArray]:
    """Simulated training data for :class:`PoseItdMLP`: free-field TDOAs over ``poses`` plus
    Gaussian TDOA noise of ``tdoa_std_s`` (the GCC error level), for sources drawn uniformly in
    azimuth, sin(elevation) and distance (pivot-centred, robot frame).

    Returns ``X (n, K * n_pairs)`` seconds and ``Y (n, 3)`` source positions in metres.
    """
    arr = load_array(array)
    # (text, or three numbers, raised a builtin ValueError / TypeError until 2026-12-02)
    for name, v in (("distance_range_m", distance_range_m),
                    ("elevation_range_deg", elevation_range_deg),
                    ("azimuth_range_deg", azimuth_range_deg)):
        if as_float_array(v, name, finite=False, error=GeometryError).shape != (2,):
            raise GeometryError(f"{name} must be two numbers (low, high), got {v!r}")
    lo, hi = (float(v) for v in distance_range_m)
    if not (0 < lo < hi and np.isfinite(hi)):
        raise GeometryError(f"distance_range_m must be 0 < near < far metres, got "
                            f"{distance_range_m!r}")
    # (NaN made every sample NaN)
    tdoa_std_s = check_tdoa_std(tdoa_std_s, "tdoa_std_s (seconds)", zero_ok=True)
    if not all(np.all(np.isfinite(v)) for v in (elevation_range_deg, azimuth_range_deg)):
        raise GeometryError("elevation_range_deg and azimuth_range_deg must be finite degrees")
    e_lo, e_hi = (float(v) for v in elevation_range_deg)
    if not -90.0 <= e_lo <= e_hi <= 90.0:  # (-100 deg folded over the pole without a word)
        raise GeometryError(f"elevation_range_deg must be (low, high) with -90 <= low <= high "
                            f"<= 90 degrees, got {elevation_range_deg!r}")
    a_lo, a_hi = (float(v) for v in azimuth_range_deg)
    if not a_lo <= a_hi:
        raise GeometryError(f"azimuth_range_deg must be (low, high) with low <= high degrees, "
                            f"got {azimuth_range_deg!r}")
    n = whole_number("n (training samples)", n, 0)
    rng = as_rng(rng)
    az = np.radians(rng.uniform(*azimuth_range_deg, n))
    s_lo, s_hi = np.sin(np.radians(elevation_range_deg))
    el = np.arcsin(rng.uniform(s_lo, s_hi, n))
    r = rng.uniform(*distance_range_m, n)
    Y = np.asarray(pivot_m, dtype=float) + sph_to_cart(az, el, r)
    cols = []
    for mics in pose_mic_positions(arr, poses, pivot_m, offset_m):
        cols.append(MicArray(mics, arr.speed_of_sound).tdoa(Y))
    X = np.hstack(cols)
    X = X + rng.normal(0.0, tdoa_std_s, X.shape)
    return X, Y


#: The fewest training samples :meth:`PoseItdMLP.fit` takes: early stopping holds out a
#: tenth of them for validation, and scikit-learn refused 5 ("validation set is too small").
MIN_MLP_SAMPLES = 20


class PoseItdMLP:
    """Learned mapping from TDOAs over K head poses to the source position (thesis 4.6,
    figs. 4.10-4.12), with the scikit-learn estimator contract.

    Reconstruction: the thesis trained a feed-forward network on (ITDs over poses -> source
    coordinates). Here a :class:`sklearn.neural_network.MLPRegressor` maps TDOAs scaled by the
    pair's maximum ``|m_i - m_j| / c`` to ``[u_x, u_y, u_z, log r]`` (unit direction and log
    distance from the pivot), which keeps the targets well scaled for 0.5-3 m sources.

    Parameters
    ----------
    hidden_layer_sizes : tuple of int
    alpha : float
        L2 penalty.
    max_iter : int
    random_state : int
    tdoa_scale_s : float
        TDOAs are divided by this before the network (default 0.15 m / 343 m/s).
    reference_m : (3,)
        The pivot the targets are expressed about.
    """

    def __init__(self, hidden_layer_sizes: tuple[int, ...] = (64, 64), alpha: float = 1e-4,
                 max_iter: int = 300, random_state: int = 0, tdoa_scale_s: float = 0.15 / 343.0,
                 reference_m: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
        self.hidden_layer_sizes = hidden_layer_sizes
        self.alpha = alpha
        self.max_iter = max_iter
        self.random_state = random_state
        self.tdoa_scale_s = tdoa_scale_s
        self.reference_m = reference_m

    def get_params(self, deep: bool = True) -> dict[str, Any]:
        return {k: getattr(self, k) for k in ("hidden_layer_sizes", "alpha", "max_iter",
                                               "random_state", "tdoa_scale_s", "reference_m")}

    def set_params(self, **params: Any) -> PoseItdMLP:
        for k, v in params.items():
            setattr(self, k, v)
        return self

    def fit(self, X: ArrayLike, Y: ArrayLike) -> PoseItdMLP:
        """Fit on TDOAs ``X (n, K*n_pairs)`` (s) and positions ``Y (n, 3)`` (m, robot frame)."""
        from sklearn.exceptions import ConvergenceWarning
        from sklearn.neural_network import MLPRegressor
        from threadpoolctl import threadpool_limits

        X, Y = _mlp_samples(X, Y, "fit")
        # (the settings scikit-learn would refuse with its own ValueErrors, and the two it
        # does not see: a zero scale made every TDOA infinite, a 2-vector reference a
        # broadcast error)
        finite_number("PoseItdMLP: tdoa_scale_s (seconds)", self.tdoa_scale_s, 0.0,
                      lo_open=True)
        ref = (np.asarray(self.reference_m, dtype=float) if real_entries(self.reference_m)
               else None)
        if ref is None or ref.shape != (3,) or not np.all(np.isfinite(ref)):
            raise ConfigError(f"PoseItdMLP: reference_m must be one finite [x, y, z] in "
                              f"metres, got {self.reference_m!r:.60}")
        if len(X) < MIN_MLP_SAMPLES:  # (early stopping's validation set needs some)
            raise EstimationError(f"PoseItdMLP.fit needs at least {MIN_MLP_SAMPLES} samples, "
                                  f"got {len(X)}")
        v = Y - ref
        r = np.linalg.norm(v, axis=1)
        if not np.all(r > 0):  # (direction and log-distance targets: scikit-learn's ValueError)
            raise EstimationError(f"PoseItdMLP.fit: {int(np.sum(~(r > 0)))} training positions "
                                  "lie at the reference point (no direction, log(0) distance)")
        T = np.column_stack([v / r[:, None], np.log(r)])
        self.target_mean_ = T.mean(axis=0)
        self.target_std_ = T.std(axis=0) + 1e-12
        self.mlp_ = MLPRegressor(hidden_layer_sizes=self.hidden_layer_sizes, alpha=self.alpha,
                                 max_iter=self.max_iter, random_state=self.random_state,
                                 early_stopping=True, n_iter_no_change=15, tol=1e-5)
        # small dense layers: one BLAS thread is much faster than an oversubscribed pool
        with warnings.catch_warnings(), threadpool_limits(1):
            warnings.simplefilter("ignore", ConvergenceWarning)
            try:
                self.mlp_.fit(X / self.tdoa_scale_s, (T - self.target_mean_) / self.target_std_)
            except (TypeError, ValueError) as exc:  # bad hidden_layer_sizes, alpha, max_iter
                del self.mlp_
                raise ConfigError(f"PoseItdMLP settings: {exc}") from None
        self.n_features_in_ = X.shape[1]
        return self

    def predict(self, X: ArrayLike) -> NDArray:
        """Positions ``(n, 3)`` in the robot frame for TDOAs ``X (n, K*n_pairs)``;
        :class:`hearsee.errors.RegressorNotFittedError` before :meth:`fit`."""
        if not hasattr(self, "mlp_"):
            # (scikit-learn's NotFittedError too, as AudioVisualRegressor's: a plain
            # EstimationError did not tell sklearn's tools the estimator was unfitted)
            from hearsee.errors import RegressorNotFittedError

            raise RegressorNotFittedError("PoseItdMLP is not fitted; call fit() first")
        if not real_entries(X):  # (text: numpy's ValueError)
            raise EstimationError(f"PoseItdMLP.predict needs TDOAs (s), got {X!r:.60}")
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if X.ndim != 2 or X.shape[1] != self.n_features_in_ or len(X) == 0:
            raise EstimationError(
                f"expected {self.n_features_in_} TDOAs per sample (K poses x pairs), "
                f"got shape {X.shape}"
            )
        if not np.all(np.isfinite(X)):  # (scikit-learn's ValueError)
            raise EstimationError("PoseItdMLP.predict needs finite TDOAs (a NaN or inf one "
                                  "was given: the MLP needs every pose's pairs)")
        from threadpoolctl import threadpool_limits

        with threadpool_limits(1):
            T = self.mlp_.predict(X / self.tdoa_scale_s) * self.target_std_ + self.target_mean_
        T = np.atleast_2d(T)
        u = T[:, :3] / np.maximum(np.linalg.norm(T[:, :3], axis=1, keepdims=True), 1e-12)
        return np.asarray(self.reference_m, dtype=float) + u * np.exp(T[:, 3:4])

    def score(self, X: ArrayLike, Y: ArrayLike) -> float:
        """Negative median 3D error in metres (higher is better); X and Y as for :meth:`fit`
        (a NaN Y scored NaN, fit refused it)."""
        X, Y = _mlp_samples(X, Y, "score")
        return -float(np.median(np.linalg.norm(self.predict(X) - Y, axis=1)))


def _mlp_samples(X: ArrayLike, Y: ArrayLike, what: str) -> tuple[NDArray, NDArray]:
    """``(X, Y)`` of :class:`PoseItdMLP` as float arrays, TDOAs ``X (n, n_features)`` and
    positions ``Y (n, 3)``, all finite; an EstimationError naming ``what`` otherwise."""
    ok = real_entries(X) and real_entries(Y)
    X = np.asarray(X, dtype=float) if ok else np.zeros(0)
    Y = np.asarray(Y, dtype=float) if ok else np.zeros(0)
    if (X.ndim != 2 or Y.shape != (len(X), 3) or not np.all(np.isfinite(X))
            or not np.all(np.isfinite(Y))):
        raise EstimationError(f"PoseItdMLP.{what} needs finite X (n, n_features) and Y (n, 3)")
    return X, Y


@functools.lru_cache(maxsize=16)
def _train_cached(array_key: tuple, c: float, poses: tuple, pivot: tuple, offset: tuple,
                  n: int, tdoa_std_s: float, seed: int, hidden: tuple) -> PoseItdMLP:
    arr = MicArray(np.array(array_key), c)
    X, Y = make_pose_training_set(arr, poses, n, pivot_m=pivot, offset_m=offset,
                                  tdoa_std_s=tdoa_std_s, rng=seed)
    return PoseItdMLP(hidden_layer_sizes=hidden, random_state=seed,
                      tdoa_scale_s=arr.aperture / c, reference_m=pivot).fit(X, Y)


def train_pose_mlp(array: MicArray | str, poses: Sequence[HeadPose | Sequence[float]], *,
                   pivot_m: ArrayLike = (0.0, 0.0, 0.0), offset_m: ArrayLike = (0.0, 0.0, 0.0),
                   n: int = 10000, tdoa_std_s: float = DEFAULT_TDOA_STD_S, seed: int = 0,
                   hidden_layer_sizes: tuple[int, ...] = (64, 64)) -> PoseItdMLP:
    """Train (or fetch from the in-memory cache) a :class:`PoseItdMLP` for this array, pose set
    and head geometry on ``n`` simulated samples (a few seconds; no model file is written).
    ``n``: a whole number >= :data:`MIN_MLP_SAMPLES`, else GeometryError before any
    simulation (fewer failed only in :meth:`PoseItdMLP.fit`, once the set was simulated)."""
    arr = load_array(array)
    key = tuple(map(tuple, arr.positions.tolist()))
    # checked before the cache key's conversions (float() read True as 1 m or 1 s, int() 2.5
    # training samples as 2)
    return _train_cached(key, arr.speed_of_sound,
                         tuple(p.as_tuple() for p in pose_list(poses)),
                         tuple(as_point(pivot_m, "pivot_m").tolist()),
                         tuple(as_point(offset_m, "offset_m").tolist()),
                         whole_number("n (training samples)", n, MIN_MLP_SAMPLES,
                                      error=GeometryError),
                         check_tdoa_std(tdoa_std_s, "tdoa_std_s (seconds)", zero_ok=True),
                         whole_number("seed", seed, 0, error=GeometryError),
                         tuple(hidden_layer_sizes))


# ------------------------------------------------------------------------ continuous sampling
def _check_pose_at(pose_at: Any) -> None:
    """GeometryError unless ``pose_at`` is a callable ``t -> pose`` (a pose itself was called
    and raised a builtin TypeError: "'tuple' object is not callable")."""
    if not callable(pose_at):
        raise GeometryError(f"pose_at must be a function of time t (s) returning the head pose "
                            f"(pan_deg, tilt_deg), got {pose_at!r:.60}")


def simulate_turning_capture(
    signal: ArrayLike,
    fs: float,
    array: MicArray | str,
    source_m: ArrayLike,
    pose_at: Callable[[float], HeadPose | Sequence[float]],
    *,
    block_s: float = 0.064,
    pivot_m: ArrayLike = (0.0, 0.0, 0.0),
    offset_m: ArrayLike = (0.0, 0.0, 0.0),
    snr_db: float | None = None,
    rng: np.random.Generator | int | None = None,
    room_dim: ArrayLike | None = None,
    rt60: float = 0.0,
    robot_at: ArrayLike | None = None,
) -> NDArray:
    """A capture ``(n_mics, n)`` of a static source while the head turns (thesis 4.7).

    Block-wise: the head is frozen at ``pose_at(t_block_centre)`` for each ``block_s`` block;
    the block is cut from the full-length simulation at that pose (so there are no onset gaps),
    which makes the microphone positions -- and the delays -- vary over time. Noise is added
    once to the assembled capture.
    """
    from hearsee.audio.propagation import add_noise

    # (before any work: fs=0 divided by zero, warned, and failed on the infinite pose)
    check_fs(fs)
    check_rng(rng)
    _check_pose_at(pose_at)
    block_s = finite_number("block_s (seconds)", block_s, 0.0, lo_open=True, error=GeometryError)
    sig = as_samples(signal, "signal")
    n = len(sig)
    nb = max(int(round(block_s * fs)), 1)
    starts = np.arange(0, n, nb)
    poses = [as_pose(pose_at((s + min(nb, n - s) / 2) / fs)) for s in starts]
    uniq: dict[tuple[float, float], int] = {}
    for p in poses:
        uniq.setdefault(p.as_tuple(), len(uniq))
    caps = simulate_pose_captures(sig, fs, array, source_m, [HeadPose(*k) for k in uniq],
                                  pivot_m=pivot_m, offset_m=offset_m, snr_db=None, rng=rng,
                                  room_dim=room_dim, rt60=rt60, robot_at=robot_at)
    length = min(c.shape[1] for c in caps)
    out = np.zeros((caps[0].shape[0], length))
    for s, p in zip(starts, poses, strict=True):
        if s >= length:
            break
        e = min(s + nb, length)
        out[:, s:e] = caps[uniq[p.as_tuple()]][:, s:e]
    return add_noise(out, snr_db, as_rng(rng))


def localize_continuous(
    x: ArrayLike,
    fs: float,
    array: MicArray | str,
    pose_at: Callable[[float], HeadPose | Sequence[float]],
    *,
    pivot_m: ArrayLike = (0.0, 0.0, 0.0),
    offset_m: ArrayLike = (0.0, 0.0, 0.0),
    frame_ms: float = 64.0,
    hop_ms: float = 32.0,
    group_frames: int = 4,
    **kwargs: Any,
) -> tuple[Position3D, NDArray, NDArray]:
    """Continuous multiple sampling (thesis 4.7, fig. 4.14): 3D position from one capture taken
    while the head turns along ``pose_at(t)``.

    Every valid frame is a sample at the pose of its centre time. The frames are averaged in
    groups of ``group_frames`` consecutive frames (one pose sample each: median TDOA, mean pose);
    all samples are then solved together by :func:`localize_multipose`.

    Returns
    -------
    (Position3D, sample_times (S,), running_mean_positions (S, 3))
        The running mean of the per-sample estimates cumulated over the capture (each estimate
        from all samples so far) -- the thesis's "averaged source coordinates" curve; NaN rows
        until the position is determined.
    """
    from hearsee.audio.tdoa import estimate_tdoas

    group_frames = whole_number("group_frames", group_frames, 1, error=GeometryError)
    _check_pose_at(pose_at)
    arr = load_array(array)
    fr = estimate_tdoas(x, fs, arr, frame_ms=frame_ms, hop_ms=hop_ms)
    idx = np.flatnonzero(fr.valid)
    if len(idx) == 0:
        raise EstimationError("no frame of the capture holds a source")
    groups = [idx[i:i + group_frames] for i in range(0, len(idx), group_frames)]
    taus, poses, times = [], [], []
    for g in groups:
        taus.append(np.nanmedian(fr.tdoa_s[g], axis=0))
        ps = [as_pose(pose_at(float(t))) for t in fr.t[g]]
        pans = np.array([p.pan_deg for p in ps])  # averaged unwrapped (178 and -178 -> 180)
        pan = float(pans[0] + np.mean(wrap_deg(pans - pans[0])))
        poses.append(HeadPose(pan, float(np.mean([p.tilt_deg for p in ps]))))
        times.append(float(np.mean(fr.t[g])))
    est = localize_multipose(taus, poses, arr, pivot_m=pivot_m, offset_m=offset_m, **kwargs)
    running = np.full((len(taus), 3), np.nan)
    for s in range(1, len(taus)):
        e = localize_multipose(taus[: s + 1], poses[: s + 1], arr, pivot_m=pivot_m,
                               offset_m=offset_m, **kwargs)
        if e.position_m is not None:
            running[s] = e.position_m
    return est, np.array(times), running


# ------------------------------------------------------------------------ active alignment
@dataclass
class AlignmentResult:
    """Outcome of :func:`align_head`.

    ``poses`` are the poses measured (the first is the start pose), ``tdoas`` the TDOAs measured
    at each, ``moves`` the number of head moves made, ``final_pose`` the pose the head ended at,
    ``facing_tdoa_s`` the TDOA of the facing pair at each pose (must vanish when facing),
    ``estimates`` the direction estimate (az, el) after each measurement.
    """

    poses: list[HeadPose]
    tdoas: list[NDArray]
    moves: int
    final_pose: HeadPose
    facing_tdoa_s: list[float]
    estimates: list[tuple[float, float]]
    converged: bool

    def error_deg(self, source_m: ArrayLike, pivot_m: ArrayLike = (0.0, 0.0, 0.0),
                  offset_m: ArrayLike = (0.0, 0.0, 0.0)) -> float:
        """Angle between the final gaze (the array's +x axis) and the true source direction
        seen from the array origin at the final pose -- the direction in which the facing ITDs
        vanish."""
        from hearsee.geometry import array_to_robot

        origin = array_to_robot(np.zeros(3), self.final_pose, pivot_m, offset_m)
        v = np.asarray(source_m, dtype=float) - origin
        return float(np.degrees(angle_between(self.final_pose.gaze, v)))


def _aim_at(point: NDArray, pivot_m: ArrayLike, offset_m: ArrayLike) -> tuple[float, float]:
    """Pan/tilt (deg) that put ``point`` on the array's +x axis (through the array origin),
    by a few fixed-point iterations on the pose-dependent array origin, then, where those have
    not converged, a least-squares solve for the pose that zeroes the point's array-frame y
    and z. The iterations converge slowly (linearly) when the offset is large for the
    distance: with offset (0.2, 0, 0.1) m and points 0.5-0.9 m away five of them left the
    axis 0.01-2.5 deg off the point, and up to 28 deg below the head (found 2026-12-02 by an
    audit of align_head with exact TDOAs)."""
    from scipy.optimize import least_squares

    from hearsee.geometry import array_to_robot, robot_to_array

    p = np.asarray(point, dtype=float)
    az, el = (float(v) for v in direction_deg(p - np.asarray(pivot_m)))
    for _ in range(5):
        origin = array_to_robot(np.zeros(3), (az, float(np.clip(el, -90, 90))), pivot_m,
                                offset_m)
        az, el = (float(v) for v in direction_deg(p - origin))
    el = float(np.clip(el, -90, 90))

    def off_axis(v: NDArray) -> NDArray:
        """The point's array-frame (y, z) over its distance at pose v = (pan, tilt) deg."""
        q = robot_to_array(p, (float(v[0]), float(v[1])), pivot_m, offset_m)
        return q[1:] / max(float(np.linalg.norm(q)), 1e-12)

    miss = float(np.linalg.norm(off_axis(np.array([az, el]))))
    if miss > 1e-9:
        sol = least_squares(off_axis, [az, float(np.clip(el, -89.9, 89.9))],
                            bounds=([-np.inf, -90.0], [np.inf, 90.0]), xtol=1e-14,
                            ftol=1e-14, gtol=1e-14)
        q = robot_to_array(p, (float(sol.x[0]), float(sol.x[1])), pivot_m, offset_m)
        if q[0] > 0 and float(np.linalg.norm(off_axis(sol.x))) < miss:
            az, el = float(wrap_deg(sol.x[0])), float(sol.x[1])
    return az, el


def _alignment_settings(max_moves: Any, tol_deg: Any, probe_deg: Any,
                        tilt_limits_deg: Any) -> tuple[float, float]:
    """Check the alignment loops' settings (GeometryError naming the bad one); returns the
    tilt limits ``(low, high)`` in degrees. Reversed limits (60, -60) clipped every tilt to
    -60 deg and ended "converged" there; a NaN tolerance never converged, a NaN probe aimed
    the head at a NaN tilt, text raised numpy's errors (until 2026-12-02)."""
    whole_number("max_moves", max_moves, 0, error=GeometryError)
    finite_number("tol_deg", tol_deg, 0.0, lo_open=True, error=GeometryError)
    finite_number("probe_deg", probe_deg, 0.0, lo_open=True, error=GeometryError)
    return check_angle_limits(tilt_limits_deg, "tilt_limits_deg", 90.0)  # (the robot's rule)


def _measure_pose(measure: Any, pose: Any, arr: MicArray) -> NDArray:
    """Call the alignment loops' ``measure(pose)`` and check it returned one TDOA per pair
    (seconds, numbers: text or a mapping was a builtin ValueError / TypeError)."""
    got = measure(pose)
    if not real_entries(got):
        raise AudioInputError(f"measure() must return one TDOA (s) per pair as numbers, got "
                              f"{got!r:.60}")
    tau = np.asarray(got, dtype=float)
    if tau.shape != (len(arr.pairs),):
        raise AudioInputError(f"measure() returned {tau.shape} TDOAs, expected "
                              f"{len(arr.pairs)} (one per pair)")
    return tau


def align_head(
    measure: Callable[[HeadPose], ArrayLike],
    array: MicArray | str,
    *,
    start: HeadPose | Sequence[float] = (0.0, 0.0),
    pivot_m: ArrayLike = (0.0, 0.0, 0.0),
    offset_m: ArrayLike = (0.0, 0.0, 0.0),
    max_moves: int = 8,
    tol_deg: float = 1.0,
    probe_deg: float = 20.0,
    max_std_deg: float = 1.0,
    tilt_limits_deg: tuple[float, float] = (-60.0, 75.0),
    **kwargs: Any,
) -> AlignmentResult:
    """Active alignment: turn the head (pan alpha, tilt beta) until it faces the source.

    Reconstruction of thesis 4.7 (figs. 4.15-4.17). The thesis searched alpha for the zero of
    the range difference of the symmetric pair ([dd_12]^2 -> 0) and beta for the extreme of
    dd_13. Here every capture so far is pooled by :func:`localize_multipose` (so earlier poses
    keep constraining the direction) and the head turns straight to the pooled direction
    estimate; the step in alpha is the Newton step on dd_12 and the step in beta the one that
    puts the source into the array plane. A planar array cannot tell up from down at one pose
    (and the elevation is least sensitive when the source is in the array plane), so when the
    estimate is still ambiguous the first tilt goes to the upper candidate plus a ``probe_deg``
    excursion that makes the next capture informative (also whenever the poses so far differ
    only in pan and the direction is uncertain, 1-sigma above ``max_std_deg``). Stops when the
    suggested move is below ``tol_deg`` and the direction is unique -- and, while the poses
    differ only in pan, certain (1-sigma within ``max_std_deg``; once the tilt has varied, a
    settled but noisier direction also ends the search, ``converged=True``; its
    ``direction_std_deg`` is that of :func:`localize_multipose` on the result's poses and
    TDOAs) -- or after ``max_moves`` moves. While the distance is too uncertain to report
    (``localize_multipose`` returns no position), the head still aims at the best-fit point of
    the pooled captures (of several near-field minima, the one seen nearest the far-field
    direction), which corrects the parallax of an array origin off the pivot; with exact TDOAs
    the gaze ends within 0.05 deg of the source. ``tol_deg`` bounds the last
    suggested move, not the gaze error, which follows the TDOA noise.

    A pair whose axis stays horizontal at every pan and tilt (``two-mic`` on this head) cannot
    tell up from down at any pose: its mirror never resolves, and the search ends after
    ``max_moves`` with ``converged=False`` (15 sources checked, 2026-12-07: 12-104 deg off).

    Parameters
    ----------
    measure : callable HeadPose -> TDOAs (n_pairs,)
        Moves the head to the pose and returns the measured TDOAs (s) of all array pairs.
    """
    lo_t, hi_t = _alignment_settings(max_moves, tol_deg, probe_deg, tilt_limits_deg)
    finite_number("max_std_deg", max_std_deg, 0.0, lo_open=True, error=GeometryError)
    arr = load_array(array)
    pair = facing_pair(arr)
    kwargs.setdefault("tdoa_std_s", DEFAULT_TDOA_STD_S)
    pose = as_pose(start)
    poses: list[HeadPose] = []
    taus: list[NDArray] = []
    facing: list[float] = []
    ests: list[tuple[float, float]] = []
    moves = 0
    converged = False
    n_probes = 0
    while True:
        tau = _measure_pose(measure, pose, arr)
        poses.append(pose)
        taus.append(tau)
        facing.append(float(tau[arr.pairs.index(pair)]) if pair else float("nan"))
        est = localize_multipose(taus, poses, arr, pivot_m=pivot_m, offset_m=offset_m, **kwargs)
        # direction candidates that differ in direction (the mirror)
        dirs = [(c["azimuth_deg"], c["elevation_deg"]) for c in est.candidates]
        ambiguous = len(dirs) > 1
        below = None
        if ambiguous:
            # the upper mirror candidate first -- unless the head has been there already: a
            # capture at a pose already held adds nothing (a near-field minimum at the pose
            # just probed held the head there for every remaining move: 6 and 17 of 30 noisy
            # alignments to a source straight ahead at 2 and 1 m ended 23-26 deg off)
            def held(d: tuple[float, float]) -> bool:
                g = HeadPose(float(d[0]), float(np.clip(d[1], lo_t, hi_t))).gaze
                return any(np.degrees(angle_between(g, p.gaze)) < tol_deg for p in poses)

            order = sorted(dirs, key=lambda d: -d[1])
            fresh = [d for d in order if not held(d)]
            az, el = fresh[0] if fresh else order[0]
            # every candidate's pose captured and still two candidates (a near-field minimum
            # beside the source): look from below the lowest, a view that tells them apart
            below = None if fresh else order[-1]
        elif est.position_m is not None:
            az, el = _aim_at(est.position_m, pivot_m, offset_m)
        else:
            az, el = est.azimuth_deg, est.elevation_deg
            if len(poses) > 1:
                # distance too uncertain to report, but the best-fit point still corrects the
                # parallax of an array origin off the pivot (aiming along the direction seen
                # from the pivot assumes an infinitely far source: 1.1 deg off at 2.5 m for a
                # 0.1 m offset)
                near = localize_multipose(taus, poses, arr, pivot_m=pivot_m,
                                          offset_m=offset_m,
                                          **{**kwargs, "max_rel_distance_std": np.inf})
                # a second near-field minimum (a point ~0.3 m away, ~20 deg off) does not
                # cancel the correction: aim at the candidate seen nearest the far-field
                # direction (until 2026-12-02 two candidates dropped it, 3 of 40 random
                # sources with exact TDOAs ended 1.1-2.2 deg off)
                pts = [c for c in near.candidates if c["position_m"] is not None]
                if pts:
                    c = min(pts, key=lambda c: float(angle_between(
                        unit_vector_deg(c["azimuth_deg"], c["elevation_deg"]), est.direction)))
                    az, el = _aim_at(np.asarray(c["position_m"]), pivot_m, offset_m)
        ests.append((float(az), float(el)))
        target = HeadPose(float(az), float(np.clip(el, lo_t, hi_t)))
        if below is not None:  # (set only when ambiguous)
            target = HeadPose(float(below[0]), float(np.clip(below[1] - probe_deg, lo_t, hi_t)))
        tilts = [p.tilt_deg for p in poses]
        uncertain = ambiguous or not est.direction_std_deg <= max_std_deg
        pan_only = max(tilts) - min(tilts) < probe_deg / 2
        if uncertain and pan_only:
            # probe: poses differing only in pan cannot tell up from down, and the elevation
            # is least sensitive near the array plane -- overshoot the tilt so that the next
            # capture sees the source well off the array plane
            sign = 1.0 if n_probes % 2 == 0 else -1.0
            target = HeadPose(target.pan_deg,
                              float(np.clip(el + sign * probe_deg, lo_t, hi_t)))
            n_probes += 1
        step = float(np.degrees(angle_between(target.gaze, pose.gaze)))
        if step < tol_deg and not ambiguous and not (uncertain and pan_only):
            converged = True
            break
        if moves >= max_moves:
            break
        pose = target
        moves += 1
    return AlignmentResult(poses, taus, moves, pose, facing, ests, converged)


def _acos_deg(g: float) -> float:
    """Angle in degrees whose cosine is ``g`` (clipped to 1)."""
    return float(np.degrees(np.arccos(min(float(g), 1.0))))


def align_head_search(
    measure: Callable[[HeadPose], ArrayLike],
    array: MicArray | str,
    *,
    start: HeadPose | Sequence[float] = (0.0, 0.0),
    max_moves: int = 8,
    tol_deg: float = 1.0,
    probe_deg: float = 12.0,
    tilt_limits_deg: tuple[float, float] = (-60.0, 75.0),
) -> AlignmentResult:
    """Active alignment by the thesis's search (4.7, figs. 4.15-4.17), from the TDOAs alone.

    Reconstruction for an array whose microphones lie in the head's horizontal plane (e.g.
    ``three-mic``). Far field, the TDOAs give the in-plane part ``(u_x, u_y)`` of the source
    direction in the head frame by least squares (``tau_ij = -(m_i - m_j) . u / c``):

    - alpha: ``atan2(u_y, u_x)`` is the pan error -- the Newton step that drives the symmetric
      pair's range difference dd_12 to zero (fig. 4.15, [dd_12]^2 has its minimum there), with
      the front/back sign resolved by the other pairs;
    - beta: ``g = |(u_x, u_y)| = cos(elevation in the head frame)`` is largest when the head
      faces the source (fig. 4.16: dd_13 reaches its extreme). Its size gives |beta error| but
      not its sign: the first tilt move tries ``+acos(g)`` and turns back if ``g`` fell; near
      the top, where ``g`` is flat, the last three tilt samples are fitted by a parabola whose
      vertex is the next tilt (a probe of ``probe_deg`` is taken when no bracketing sample
      exists).

    Pan and tilt are corrected together at every move (fig. 4.17, simultaneous search). Stops
    when both corrections are below ``tol_deg`` or after ``max_moves`` moves.

    Limitation: ``atan2(u_y, u_x)`` is the pan error exactly at tilt 0; with the head tilted by
    ``beta`` and the source at elevation ``e`` a small pan error ``a`` reads about ``a cos(e) /
    cos(beta - e)``. Level starts (the default) settle the pan at tilt 0 first; a start tilted
    far from the source (``cos(beta - e) < cos(e) / 2``, e.g. 75 deg above a talker at the
    array's height) overshoots and may not converge (``converged=False``). The exact step needs
    ``u_z``, whose sign a planar array cannot tell.
    """
    lo_t, hi_t = _alignment_settings(max_moves, tol_deg, probe_deg, tilt_limits_deg)
    arr = load_array(array)
    z = arr.positions[:, 2]
    if np.ptp(z) > 1e-6:
        raise GeometryError("align_head_search needs microphones in the head's horizontal plane")
    pair = facing_pair(arr)
    D = np.array([(arr.positions[i] - arr.positions[j])[:2] for i, j in arr.pairs])
    if np.linalg.matrix_rank(D, tol=1e-6) < 2:
        raise GeometryError("align_head_search needs two non-collinear microphone baselines in "
                            "the head's horizontal plane (e.g. three-mic); use align_head")
    c = arr.speed_of_sound
    pose = as_pose(start)
    poses: list[HeadPose] = []
    taus: list[NDArray] = []
    facing: list[float] = []
    ests: list[tuple[float, float]] = []
    gs: list[float] = []
    moves = 0
    converged = False
    while True:
        tau = _measure_pose(measure, pose, arr)
        bad = [k for k in range(len(tau)) if not np.isfinite(tau[k])]
        if bad:  # (the least-squares pan became NaN and HeadPose named the pose, not this)
            i, j = arr.pairs[bad[0]]
            raise AudioInputError(
                f"measure({pose}) returned TDOA {tau[bad[0]]} for pair ({i}, {j}): "
                "align_head_search needs a finite TDOA of every pair at every pose (align_head "
                "takes NaN as a pair not measured)")
        poses.append(pose)
        taus.append(tau)
        facing.append(float(tau[arr.pairs.index(pair)]) if pair else float("nan"))
        uxy = np.linalg.lstsq(D, -c * tau, rcond=None)[0]
        # not clipped at 1: a nearby source's curved wavefront gives |u_xy| a little above 1
        # at every tilt near the right one, and clipping made those samples tie
        g = float(np.linalg.norm(uxy))
        gs.append(g)
        d_pan = float(np.degrees(np.arctan2(uxy[1], uxy[0])))
        # tilt: samples at (nearly) the current pan, i.e. taken since the pan settled
        same = [k for k in range(len(poses)) if abs(poses[k].pan_deg - pose.pan_deg) < 3.0]
        b = np.array([poses[k].tilt_deg for k in same])
        gv = np.array([gs[k] for k in same])
        e_mag = _acos_deg(g)
        if len(same) == 1:
            new_tilt = pose.tilt_deg + max(e_mag, probe_deg)  # first try: upward
            if min(new_tilt, hi_t) - pose.tilt_deg < tol_deg:
                # at the upper limit the upward try is no move (read as converged): go down
                new_tilt = pose.tilt_deg - max(e_mag, probe_deg)
        else:
            kb = int(np.argmax(gv))
            lower, upper = b[b < b[kb]], b[b > b[kb]]
            # a sample at (nearly) the best one's tilt -- the head back at a tilt it measured
            # before its pan settled -- is no neighbour while another lies beyond it: the
            # parabola through two equal tilts was ill-conditioned (a source level with the
            # head: back at tilt 0, the vertex went to 6 deg, and the search ended 1.5 deg
            # off, "converged"). Only such repeats: a noisy sample a few tenths of a degree
            # away is a neighbour still (dropped for one far away, the fit was worse)
            gap = 1e-3 * tol_deg
            far_l, far_u = lower[lower <= b[kb] - gap], upper[upper >= b[kb] + gap]
            lower = far_l if len(far_l) else lower
            upper = far_u if len(far_u) else upper
            if len(lower) and len(upper):
                # bracketed maximum: parabola through the best sample and its neighbours
                bl, bu = lower.max(), upper.min()
                gl, gu = gv[b == bl][0], gv[b == bu][0]
                x = np.array([bl, b[kb], bu])
                A = np.polyfit(x, [gl, gv[kb], gu], 2)
                new_tilt = float(-A[1] / (2 * A[0])) if A[0] < 0 else float(b[kb])
                new_tilt = float(np.clip(new_tilt, bl, bu))
            elif len(lower):  # best is the highest tilt so far: go further up
                new_tilt = b[kb] + max(_acos_deg(gv[kb]), probe_deg)
            else:  # best is the lowest tilt so far: go further down
                new_tilt = b[kb] - max(_acos_deg(gv[kb]), probe_deg)
            if kb != len(same) - 1 and len(same) == 2 and b[1] >= b[0]:
                # the upward try made g fall: the source is below
                new_tilt = b[kb] - max(_acos_deg(gv[kb]), probe_deg)
        new_tilt = float(np.clip(new_tilt, lo_t, hi_t))
        if abs(d_pan) >= 3.0:
            new_tilt = pose.tilt_deg  # settle the pan first (tilt samples need a fixed pan)
        target = HeadPose(pose.pan_deg + d_pan, new_tilt)
        if (len(poses) >= 2 and abs(d_pan) > 90.0 and poses[-1].tilt_deg > poses[-2].tilt_deg
                and abs(poses[-1].pan_deg - poses[-2].pan_deg) < 3.0):
            # the upward tilt try put the source behind the head (it is more than 45 deg below
            # the gaze: tilting up by its elevation's size turned it ~2x that away): not a pan
            # error but the wrong tilt sign -- back, and down. Read as a 180-deg pan error, the
            # head spun 3.5 turns without tilting (every source 46-60 deg below a level start)
            p0 = poses[-2]
            target = HeadPose(p0.pan_deg, float(np.clip(
                p0.tilt_deg - max(_acos_deg(gs[-2]), probe_deg), lo_t, hi_t)))
        ests.append((target.pan_deg, target.tilt_deg))
        if abs(d_pan) < tol_deg and abs(new_tilt - pose.tilt_deg) < tol_deg:
            converged = True
            break
        if moves >= max_moves:
            break
        pose = target
        moves += 1
    return AlignmentResult(poses, taus, moves, pose, facing, ests, converged)


# ------------------------------------------------------------------------ pose manifests
#: Keys of a pose manifest (``hearsee localize3d``, written by ``hearsee simulate --poses``).
MANIFEST_KEYS = ("array", "channels", "head", "captures", "tdoa_std_s", "truth")
_HEAD_KEYS = ("pivot_m", "offset_m")
_CAPTURE_KEYS = ("file", "pan_deg", "tilt_deg")


@dataclass
class PoseManifest:
    """A set of captures of one static source, each with the head pose it was taken at.

    YAML schema (paths relative to the manifest's folder)::

        array: three-mic            # preset name, array YAML path, or an inline array mapping
        channels: [1, 2, 3]         # optional: each microphone's input channel of the files
        head:                       # optional
          pivot_m: [0, 0, 0]        # pan-tilt pivot, robot frame, metres
          offset_m: [0.1, 0, 0.05]  # array origin relative to the pivot, head frame, metres
        tdoa_std_s: 5.0e-6          # optional expected TDOA error, seconds
        captures:
          - {file: pose0.wav, pan_deg: 0, tilt_deg: 0}
          - {file: pose1.wav, pan_deg: 45, tilt_deg: 25}
          - {file: [p2_mic0.wav, p2_mic1.wav, p2_mic2.wav], pan_deg: 0, tilt_deg: 30}
        truth: {...}                # optional ground truth (ignored by localize3d)

    A capture's ``file`` is one multichannel file or a list of files, one per microphone
    (their channels file by file, :func:`hearsee.audio.signals.read_recording`); ``files``
    holds a Path or a list of Paths per capture. ``channels`` (0-based, one per microphone)
    picks the microphones of a device that records other channels too (default: channel k is
    microphone k), the same for every capture.
    """

    array: MicArray
    files: list[Any]
    poses: list[HeadPose]
    pivot_m: NDArray
    offset_m: NDArray
    tdoa_std_s: float = DEFAULT_TDOA_STD_S
    truth: dict[str, Any] | None = None
    channels: tuple[int, ...] | None = None


def load_pose_manifest(path: Any) -> PoseManifest:
    """Read and validate a pose manifest; ConfigError / InputFileError name the problem."""
    from pathlib import Path

    from hearsee.config import (
        as_float_array,
        as_path,
        check_keys,
        input_file,
        load_yaml,
        require,
    )
    from hearsee.errors import ConfigError, InputFileError

    p = as_path(path, "the pose manifest's path")
    data = load_yaml(p)
    where = str(p)
    check_keys(data, MANIFEST_KEYS, where)
    spec = require(data, "array", where)
    if isinstance(spec, dict):
        arr = MicArray.from_dict(spec, where=f"{where}: array")
    elif isinstance(spec, str):  # (next to the manifest, else a preset: a name that was no
        # file there was read from the working directory -- a file named like the preset, or
        # like the array file, gave another array without a word)
        arr = load_array_beside(spec, p.parent, f"{where}: array")[0]
    else:
        raise ConfigError(f"{where}: array must be a preset name, a YAML path or a mapping")
    if arr.mask is not None:  # (its captures were solved as the bare pair's: cone twins)
        raise ConfigError(f"{where}: array {arr.name!r} has a mask; the poses are solved with "
                          "the bare microphones' free-field delays, which a mask changes (use "
                          "the bare pair's preset or file)")
    head = data.get("head") or {}
    if not isinstance(head, dict):
        raise ConfigError(f"{where}: head must be a mapping with pivot_m and/or offset_m")
    check_keys(head, _HEAD_KEYS, f"{where}: head")
    pivot = check_head_pivot(
        as_float_array(head.get("pivot_m", [0, 0, 0]), f"{where}: head.pivot_m", (3,)),
        f"{where}: head.pivot_m", ConfigError)
    offset = check_head_offset(
        as_float_array(head.get("offset_m", [0, 0, 0]), f"{where}: head.offset_m", (3,)),
        f"{where}: head.offset_m", ConfigError)
    caps = require(data, "captures", where)
    if not isinstance(caps, list) or not caps:
        raise ConfigError(f"{where}: captures must be a non-empty list of "
                          "{file, pan_deg, tilt_deg} entries")
    files, poses = [], []
    for k, c in enumerate(caps):
        w = f"{where}: captures[{k}]"
        if not isinstance(c, dict):
            raise ConfigError(f"{w}: expected a mapping with file, pan_deg, tilt_deg")
        check_keys(c, _CAPTURE_KEYS, w)
        name = require(c, "file", w)
        names = name if isinstance(name, list) and name else [name]
        found = []
        for one in names:
            if not isinstance(one, str) or not one.strip():
                # ('' was Path("."), the manifest's folder: ".: is a folder"; a list its text)
                raise ConfigError(f"{w}: file must be a capture file's name or a list of "
                                  f"them (one per microphone), got {name!r:.60}")
            f = Path(one)
            f = f if f.is_absolute() else p.parent / f
            try:
                input_file(f, "capture file")
            except InputFileError as exc:
                raise InputFileError(f"{w}: {exc}") from None
            found.append(f)
        pose_vals = []
        for key in ("pan_deg", "tilt_deg"):
            v = require(c, key, w)
            if isinstance(v, bool) or not isinstance(v, int | float) or not is_real(v):
                # (a 400-digit integer raised float()'s OverflowError; NaN went to HeadPose)
                raise ConfigError(f"{w}: {key} must be a finite number of degrees, got {v!r}")
            pose_vals.append(float(v))
        try:
            poses.append(HeadPose(*pose_vals))
        except GeometryError as exc:
            raise ConfigError(f"{w}: {exc}") from None
        files.append(found[0] if isinstance(name, str) else found)
    std = data.get("tdoa_std_s", DEFAULT_TDOA_STD_S)
    std = check_tdoa_std(std, f"{where}: tdoa_std_s", error=ConfigError)  # (seconds)
    truth = data.get("truth")
    ch = data.get("channels")
    if ch is not None:
        ch = microphone_channels(ch, arr.n_mics, f"{where}: channels")
    return PoseManifest(arr, files, poses, pivot, offset, float(std),
                        truth if isinstance(truth, dict) else None, ch)


def localize_manifest(path: Any, *, frame_ms: float = 64.0, hop_ms: float = 32.0,
                      method: str = "phat") -> Position3D:
    """3D source position from the captures of a pose manifest (``hearsee localize3d``).

    Each capture is read and validated (:func:`hearsee.audio.signals.read_recording`), its
    whole-recording TDOAs measured (:func:`capture_tdoas`) and all poses solved together
    (:func:`localize_multipose`). Warns (:class:`~hearsee.errors.InconsistentMeasurementWarning`)
    when the result is not ``consistent``.
    """
    from hearsee.audio.signals import read_recording, recording_label

    man = load_pose_manifest(path)
    taus = []
    for f in man.files:
        try:
            x, fs = read_recording(f, n_channels=man.array, channels=man.channels)
        except AudioInputError as exc:
            # (the remedy named `hearsee localize`'s --channels, an option localize3d has not:
            # a manifest picks its microphones with its channels key)
            raise AudioInputError(str(exc).replace(
                "with --channels)", "with the manifest's channels: list)")) from None
        try:
            taus.append(capture_tdoas(x, fs, man.array, frame_ms=frame_ms, hop_ms=hop_ms,
                                      method=method))
        except EstimationError as exc:
            raise EstimationError(f"{recording_label(f)}: {exc}") from None
    est = localize_multipose(taus, man.poses, man.array, pivot_m=man.pivot_m,
                             offset_m=man.offset_m, tdoa_std_s=man.tdoa_std_s)
    if not est.consistent:
        warnings.warn(
            f"no single source explains the captures at the manifest's poses (TDOA residual "
            f"{est.residual_rms_s * 1e6:.0f} us rms); check the pose angles, the channel order "
            "and the array file, or whether the source moved", InconsistentMeasurementWarning,
            stacklevel=2)
    return est


def parse_poses(text: str) -> list[HeadPose]:
    """Parse ``"PAN,TILT;PAN,TILT;..."`` (degrees) into head poses; ConfigError when malformed.

    >>> [p.as_tuple() for p in parse_poses("0,0; 45,25")]
    [(0.0, 0.0), (45.0, 25.0)]
    """
    from hearsee.errors import ConfigError

    poses = []
    for item in str(text).split(";"):
        if not item.strip():
            continue
        try:
            pan, tilt = (float(v) for v in item.split(","))
            poses.append(HeadPose(pan, tilt))
        except (ValueError, GeometryError):
            raise ConfigError(
                f"--poses: {item.strip()!r} is not PAN,TILT in degrees (tilt within +-90); "
                "write e.g. --poses '0,0;45,25;-45,-20'"
            ) from None
    if not poses:
        raise ConfigError("--poses: no pose given; write e.g. --poses '0,0;45,25;-45,-20'")
    return poses


def simulate_pose_manifest(
    out: Any,
    array: MicArray | str,
    source_m: ArrayLike,
    poses: Sequence[HeadPose | Sequence[float]],
    *,
    signal: str = "noise",
    duration_s: float = 2.0,
    fs: int = 16000,
    snr_db: float | None = None,
    room: dict[str, Any] | None = None,
    seed: int = 0,
    pivot_m: ArrayLike = (0.0, 0.0, 0.0),
    offset_m: ArrayLike = (0.0, 0.0, 0.0),
    subtype: str = "FLOAT",
    protect: Sequence[Any] = (),
) -> tuple[Any, list[Any]]:
    """Simulate one capture per head pose of a static source and write a pose manifest.

    ``out`` is the manifest path (``.yaml``); captures go next to it as ``<stem>_pose<k>.wav``
    (+ ``.json`` truth each, in the array's frame at that pose as ``hearsee simulate``'s of one
    recording, with ``source_robot_m`` the robot frame's position). ``source_m`` is in the
    ROBOT frame; ``room`` as in
    :func:`hearsee.sim.audio.normalize_room`, with ``array_at`` = the robot-frame origin in room
    coordinates. The same source signal is used for every pose; sensor noise is independent.
    The manifest's ``truth`` holds the source position, its azimuth/elevation/distance from the
    pivot, and the true TDOAs per pose. Returns (manifest path, capture paths).
    ``source_m``, ``pivot_m`` (robot frame) and ``offset_m`` (head frame, from the pivot; as in
    :func:`~hearsee.geometry.mic_positions_at`) are each one finite ``[x, y, z]`` in metres,
    else GeometryError (:func:`~hearsee.geometry.as_point`).
    """

    from hearsee.audio.propagation import add_noise
    from hearsee.audio.signals import make_signal
    from hearsee.config import save_yaml
    from hearsee.errors import ConfigError
    from hearsee.sim.audio import ground_truth, normalize_room, render, save_recording

    man = as_path(out, "the manifest's path")  # (None was a builtin TypeError)
    if man.suffix.lower() not in (".yaml", ".yml"):
        raise ConfigError(f"{man}: with --poses the output is a manifest; use a .yaml name")
    for q in protect:
        if same_file(q, man):
            raise ConfigError(f"{man}: refusing to overwrite the input file {q}")
    arr = load_array(array)
    # (each read as np.asarray(float): True as 1 m, "0.5" as 0.5 m, a huge int an OverflowError)
    snr_db = check_snr_db(snr_db)  # (before the simulation of every pose)
    src = as_point(source_m, "source_m")
    pivot = check_head_pivot(pivot_m)
    offset = check_head_offset(offset_m)
    poses = [as_pose(p) for p in poses]
    if not poses:
        raise ConfigError("--poses needs at least one PAN,TILT pose")
    room = normalize_room(room)
    if seed is not None:  # (-1, 1.5 or text raised numpy's ValueError / TypeError)
        seed = whole_number("seed", seed, 0)
    rng = np.random.default_rng(seed)
    sig = make_signal(signal, duration_s, fs, rng)
    # Every capture is rendered before any file is written: written as each was rendered, an
    # interruption (Ctrl-C during a slow room) left some captures without a manifest, and with
    # --force an earlier manifest then named a mix of new and old captures (until 2026-12-03).
    rendered = []
    for pose in poses:
        mics = mic_positions_at(arr, pose, pivot, offset)
        clean = render(sig, fs, arr, src, room, mic_positions=mics)
        x = add_noise(clean, snr_db, rng)
        # each capture's truth in the array's frame at its pose, as a single recording's
        # (what `hearsee localize` of that capture measures; the TDOAs are the same in any
        # frame): it was the robot frame's, unlabelled -- a capture localized at -6 deg
        # against its truth's 33.7 (a review helper, 2026-12-07)
        truth = ground_truth(arr, robot_to_array(src, pose, pivot, offset))
        truth["source_robot_m"] = src.tolist()
        truth.update({"fs": int(fs), "pan_deg": pose.pan_deg, "tilt_deg": pose.tilt_deg,
                      "signal": str(signal), "snr_db": snr_db, "room": room, "seed": seed})
        rendered.append((x, truth))
    files, true_tdoas = [], []
    for k, (x, truth) in enumerate(rendered):
        wav, _ = save_recording(man.with_name(f"{man.stem}_pose{k}.wav"), x, truth,
                                subtype=subtype, protect=list(protect))
        files.append(wav)
        true_tdoas.append(dict(truth["tdoa_s"]))
    az, el = direction_deg(src - pivot)
    dist = float(vector_length(src - pivot))
    # a source at the pivot has no direction: None, as each capture's truth has for a source
    # at the robot-frame origin (ground_truth); it was written as azimuth and elevation 0.0
    az, el = (None, None) if not dist > 0 else (float(az), float(el))
    doc = {
        "array": arr.to_dict(),
        "head": {"pivot_m": pivot.tolist(), "offset_m": offset.tolist()},
        "captures": [{"file": f.name, "pan_deg": p.pan_deg, "tilt_deg": p.tilt_deg}
                     for f, p in zip(files, poses, strict=True)],
        "truth": {
            "source_m": src.tolist(),
            "azimuth_deg": az,
            "elevation_deg": el,
            "distance_m": dist,
            "tdoa_s": true_tdoas,
            "signal": str(signal), "snr_db": snr_db, "room": room, "fs": int(fs),
            "duration_s": float(duration_s), "seed": seed,
        },
    }
    save_yaml(doc, man)
    return man, files
