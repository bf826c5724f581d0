"""Human candidates from stereo: P(y,d), scale-adaptive filtering, body segmentation and
head-shoulder verification (thesis 7.2).

Reconstruction. Only the section titles of thesis ch. 7 survive; this module rebuilds them from
the standard literature:

* **P(y,d)** (7.2.1, fig. 7.5) is the *u-disparity* map: for every image column ``y`` and
  disparity ``d`` the number of pixels of that column with that disparity (Hu, Lamosa & Uchimura,
  "A complete u-v-disparity study for stereovision based 3D driving environment analysis",
  3DIM 2005; Labayrade et al., IV 2002). Pixels of the floor (height above the floor below
  ``min_height_m``), above ``max_height_m`` and beyond ``max_range_m`` are not counted, so the
  map holds only things standing on the floor. The floor plane is estimated from the 3D points
  by RANSAC (Fischler & Bolles 1981), with the camera height in the calibration file
  (``info: {camera_height_m: ..}``) as prior/fallback.
* **Scale-adaptive filtering** (fig. 7.6): a person of width ``W`` metres at disparity ``d``
  spans ``W d / B`` columns and about ``h f / Z = h d / B`` rows, so both the kernel width and
  the normalisation scale with ``d``. Each column count is divided by the number of rows a
  standing person would occupy at that disparity (scale-normalised occupancy), summed over a
  disparity band that corresponds to a fixed body depth (``d^2 / (f B)`` per metre), and filtered
  along ``y`` with a centre-surround kernel whose centre is ``person_width_m * d / B`` columns
  wide: ``Psi-hat(y,d) = mean_centre - min(mean_left_surround, mean_right_surround)``. Walls
  (that extend on both sides) cancel, compact upright blobs of person width stand out. Local
  maxima above ``peak_threshold`` after non-maximum suppression in (column, depth) are the
  candidates; people apart in depth separate here even when they overlap in the image.
* **Body segmentation** (7.2.2): the candidate's column range and disparity band are
  back-projected to the pixels that have them; morphological closing/opening and the connected
  component under the peak give the silhouette, its box and its 3D extent (height above the
  floor, width, position). The depth band is the body's depth or three standard deviations of
  the stereo depth noise ``Z^2 sigma_d / (f B)``, whichever is wider (far people are noisy).
  The silhouette must fit a standing adult: its top 1.2-2.2 m above the floor, 0.12-1.1 m
  wide, and itself at least 0.4 m tall (no head-sized fragments). Two peaks on one
  silhouette keep the more complete one.
* **Head-shoulder verification** (7.2.3, figs. 7.7-7.9): a head-shoulder contour template
  (Zhao & Nevatia, "Stochastic human segmentation from a static camera", 2002/2003; Li, Huang,
  Nevatia et al., "Rapid and robust human detection and tracking based on omega-shape
  features", ICIP 2009) in metric units, deformable in scale (via the measured depth), head
  width, shoulder width, shoulder drop and head offset, is matched to the silhouette's upper
  contour by a truncated vertical chamfer distance; ``score = 1 - mean_distance / tau``. A
  candidate is accepted when ``score >= Tm``.

Frames: pixels are those of the (rectified) left image; 3D points are metres in the rectified
left optical frame (x right, y down, z forward) -- for an already rectified rig (the simulated
one) that is the left camera frame. A person's ``position_m`` is the estimated torso centre.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from hearsee.config import finite_number, is_real, real_entries, whole_number
from hearsee.errors import (
    CalibrationError,
    ConfigError,
    EstimationError,
    GeometryError,
    ImageInputError,
)
from hearsee.vision.io import as_detector_image, bool_mask, numeric_map
from hearsee.vision.stereo import check_focal_baseline

__all__ = [
    "BODY_SURFACE_DEPTH_FACING_M",
    "BODY_SURFACE_DEPTH_SIDEWAYS_M",
    "BODY_WIDTH_FACING_M",
    "BODY_WIDTH_SIDEWAYS_M",
    "BROKEN_BOX_SHARE",
    "BodySegment",
    "FEET_REACH_M",
    "FLOOR_BELOW_M",
    "FloorPlane",
    "HumanCandidate",
    "HumanDetectorParams",
    "MAX_DISPARITY_PX",
    "NEAR_SEARCH_SHARE",
    "StereoDetection",
    "TOP_PERCENTILE",
    "body_surface_depth_m",
    "check_camera_height",
    "check_camera_pitch",
    "check_params",
    "check_principal_row",
    "cut_by_border",
    "detect_candidates",
    "detect_people_hog",
    "disparity_band_px",
    "estimate_floor",
    "find_peaks",
    "head_shoulder_score",
    "hog_people_detector",
    "near_search_share",
    "robust_top_m",
    "scale_adaptive_filter",
    "segment_band_m",
    "segment_body",
    "u_disparity",
    "unmatched_share",
    "upper_contour",
]

#: Depth (metres) of a standing person's body axis behind the median of the visible surface of
#: the whole silhouette, for a person facing the camera (torso ~0.22 m deep, legs and arms
#: ~0.12 m) and for one turned sideways (the near arm and shoulder), and the silhouette widths
#: (metres, 3rd-97th percentile of the points' x) that tell the two apart; measured on
#: hearsee.sim.scenes bodies (adult proportions: 0.45-0.51 m wide facing, 0.17-0.19 m
#: sideways, 0.21-0.35 m at 60 deg). See :func:`body_surface_depth_m`.
BODY_SURFACE_DEPTH_FACING_M = 0.07
BODY_SURFACE_DEPTH_SIDEWAYS_M = 0.13
BODY_WIDTH_FACING_M = 0.48
BODY_WIDTH_SIDEWAYS_M = 0.25


def body_surface_depth_m(width_m: float) -> float:
    """Depth (metres) of a person's body axis behind the median of the silhouette's visible
    surface, from the silhouette's width ``width_m`` (metres, >= 0):
    :data:`BODY_SURFACE_DEPTH_FACING_M` for a silhouette at least :data:`BODY_WIDTH_FACING_M`
    wide (a person facing the camera), :data:`BODY_SURFACE_DEPTH_SIDEWAYS_M` at most
    :data:`BODY_WIDTH_SIDEWAYS_M` wide (turned sideways), linear in between. Until 2026-12-02
    it was 0.09 m for everyone, which put a person facing the camera 2 cm too far and one
    turned sideways 4-6 cm too near: people rendered 1.2-3 m away at yaws 0-90 deg had depth
    errors of -5.7 to +7.1 cm, now -2.3 to +5.9 (what remains, growing with range, is SGBM's
    disparity 0.1-0.25 px low on these renders); adopted under a rule written before its
    held-out run (bench/results/HISTORY.md, bench/robot: fresh random scenarios 680-759, the
    robot's median 3D error 3.27 -> 1.88 cm). Fitted to the simulator's bodies, as the
    constant was. GeometryError unless ``width_m`` is a finite number >= 0."""
    w = finite_number("width_m (silhouette width, metres)", width_m, 0.0, error=GeometryError)
    f = min(max((BODY_WIDTH_FACING_M - w) / (BODY_WIDTH_FACING_M - BODY_WIDTH_SIDEWAYS_M),
                0.0), 1.0)
    return BODY_SURFACE_DEPTH_FACING_M + f * (BODY_SURFACE_DEPTH_SIDEWAYS_M
                                              - BODY_SURFACE_DEPTH_FACING_M)


#: Height (metres) of the crown above a silhouette's robust top (:func:`robust_top_m`, the
#: :data:`TOP_PERCENTILE` percentile of its points' heights): the rounded head puts the last
#: half percent of the points 3.1-4.0 cm below the crown on hearsee.sim.scenes bodies at
#: 1.5-5.5 m. The torso centre is placed at :data:`TORSO_HEIGHT_FRACTION` of
#: ``top + CROWN_ABOVE_TOP_M``; at that fraction of the top itself it was 2.3 cm too low (found
#: by an audit of the robot's 3D errors).
CROWN_ABOVE_TOP_M = 0.035
#: Height of the torso centre (the point a person's ``position_m`` names) as a fraction of the
#: body height, floor to crown: midway between the shoulders (0.818) and the hips (0.530) of
#: Drillis & Contini's segment lengths (as drawn in Winter, *Biomechanics and Motor Control of
#: Human Movement*, anthropometry chapter). One place for the detector, the scene renderer's
#: body model (:mod:`hearsee.sim.scenes`) and the robot's ground truth.
TORSO_HEIGHT_FRACTION = 0.675


#: A point this far below a floor hypothesis (metres) counts against it in
#: :func:`estimate_floor` (the camera cannot see below the floor; 3x the default inlier band,
#: above the stereo noise of floor points within ~6 m).
FLOOR_BELOW_M = 0.12

#: Percentile of a silhouette's point heights taken as its top (:func:`robust_top_m`): one
#: stray point in 200 does not move it.
TOP_PERCENTILE = 99.5

#: How far above the segmentation's height band (``min_height_m``) a silhouette's lowest
#: points may end for its legs to count as reaching the floor (metres): the body's box is
#: then drawn down to the floor (:attr:`BodySegment.floor_row`, :attr:`BodySegment.body_box`).
FEET_REACH_M = 0.1

#: A silhouette with at least this share of its valid disparities at the largest disparity the
#: matcher searched (:func:`near_search_share`) reaches the end of the search: part of the body
#: stands nearer than the search reaches, and SGBM gives it that disparity or none. People in
#: full view of the search had shares 0-0.003, those at its end 0.05-0.75 (counted within 1 px
#: of the end; bench/robot dev scenarios 200-239, 64 disparities at f B = 60 px m: torso
#: centres 1.04-1.12 m away).
NEAR_SEARCH_SHARE = 0.05
#: ... and at least this share of the pixels of its box without a disparity, the silhouette is
#: broken up: the body's nearer parts are not in it, and its position and height describe a
#: remainder (:attr:`BodySegment.beyond_search`). On bench/robot dev scenarios 200-239,
#: silhouettes at the search end with <= 29 % of their box unmatched were 1.1-8 cm off (the
#: body stood just beyond the search); with >= 43 %, 11-52 cm (the body nearer still: heads
#: lost, torsos placed low; a robot track turned around on one such fix, seed 16). People in
#: full view of the search: 7-13 %. The detector flags such silhouettes and does not reject
#: them (they are people); the robot does not fuse them into its track
#: (:func:`hearsee.robot.pipeline.fuses_fix`, adopted 2026-12-02 on held-out scenarios
#: 560-679: mean position p90 0.117 -> 0.062 m). Not fusing every silhouette at the search
#: end instead left scenario 378 worse by 40 cm (its accurate fixes just beyond the search).
BROKEN_BOX_SHARE = 0.4

#: The largest ``max_disparity`` :func:`u_disparity` accepts, pixels: far beyond any matcher
#: (OpenCV's SGBM stores disparities as 16 x int16, at most 2047 px), small enough that the
#: counts of an image 10,000 px wide stay within a few GB.
MAX_DISPARITY_PX = 65535


# ---------------------------------------------------------------------------------------------
# Input checks
# ---------------------------------------------------------------------------------------------
def check_camera_height(camera_height_m: float | None, what: str = "camera_height_m") -> None:
    """GeometryError unless the camera height above the floor (metres) is None or finite > 0."""
    if camera_height_m is None:
        return
    v = camera_height_m
    if not (is_real(v) and v > 0):
        raise GeometryError(
            f"{what} (camera height above the floor) must be a finite number of metres > 0, "
            f"got {v!r}"
        )


#: The largest camera pitch (degrees, either way) a floor prior may have: a camera looking
#: further up or down sees the floor (or nothing of it) edge-on to its rows.
MAX_CAMERA_PITCH_DEG = 80.0


def check_camera_pitch(camera_pitch_deg: float | None, what: str = "camera_pitch_deg"
                       ) -> float | None:
    """``camera_pitch_deg`` as a float (None stays None): the pitch of the (rectified) left
    camera's optical axis above the horizontal, degrees (+ = looking up, the pan-tilt head's
    "+ = gaze up"; no roll), a finite number within +-:data:`MAX_CAMERA_PITCH_DEG`, else a
    GeometryError naming ``what``."""
    if camera_pitch_deg is None:
        return None
    v = camera_pitch_deg
    if not (is_real(v) and abs(v) <= MAX_CAMERA_PITCH_DEG):
        raise GeometryError(f"{what} (camera pitch above the horizontal, + = up) must be a "
                            f"finite number of degrees within +-{MAX_CAMERA_PITCH_DEG:g}, "
                            f"got {v!r}")
    return float(v)


def check_principal_row(cy: float) -> None:
    """CalibrationError unless the principal row ``cy`` (pixels) is a finite number."""
    if not is_real(cy):
        raise CalibrationError(f"cy (principal row) must be a finite number of pixels, got {cy!r}")


def _point_image(points: ArrayLike) -> NDArray:
    """``points`` as an (H, W, 3) array of numbers (metres; its own dtype: no float64 copy of a
    whole image), or an ImageInputError (text was read as metres; a ragged list was numpy's
    builtin ValueError). The check of :func:`estimate_floor` and :func:`detect_candidates`."""
    try:
        p = np.asarray(points)
    except (TypeError, ValueError):  # (a ragged list: named by its shape () below)
        p = np.asarray(None)
    if p.ndim != 3 or p.shape[-1] != 3 or p.dtype.kind not in "fiu":
        raise ImageInputError(f"points must be (H, W, 3) metres, got shape {p.shape} of "
                              f"{p.dtype}")
    return p


# ---------------------------------------------------------------------------------------------
# Parameters
# ---------------------------------------------------------------------------------------------
@dataclass
class HumanDetectorParams:
    """Parameters of the stereo human detector (metres unless noted).

    ``person_width_m``: centre width of the scale-adaptive kernel; ``surround_m``: width of
    each surround; ``depth_band_m``: half depth of the disparity band summed in P(y,d) and used
    for segmentation; ``min_height_m``/``max_height_m``: height band (above the floor) counted in
    P(y,d); ``max_range_m``/``min_range_m``: depth limits; ``peak_threshold``: minimum
    Psi-hat (scale-normalised occupancy, 0..1) of a candidate; ``tm``: head-shoulder score
    threshold Tm; ``tau_m``: chamfer truncation/normalisation of the score; the extent limits
    reject silhouettes too short/tall/narrow/wide for a standing adult: ``min_top_m`` /
    ``max_top_m`` bound the height of the silhouette's top above the floor,
    ``min_width_m`` / ``max_width_m`` its width, and ``min_extent_m`` its own height
    (:attr:`BodySegment.extent_m`: top less bottom). The top alone let head-sized fragments of a
    person through (a 6x8-pixel box at 8.6 m was accepted and confirmed by the thermal camera
    in a 150-scene dev run, seeds 5000-5149, while no silhouette matched to a person spanned
    less than 0.69 m: people close enough for the image's bottom border to cut their legs
    still show 0.7 m or more).

    ``disparity_sigma_px`` (pixels) is the disparity noise of the matcher and ``band_sigmas``
    (a count) how many of the resulting depth standard deviations ``sigma_Z = Z^2 sigma_d /
    (f B)`` metres the segmentation band spans at least (:func:`segment_band_m`): far people are
    noisy in depth. 0.21 px is the robust (MAD) standard deviation of the detector's SGBM
    disparity (``fusion.DEFAULT_STEREO_OPTIONS``) minus the ground truth on the bodies of 40
    hearsee.sim.scenes rooms (seeds 2000-2039; 0.21 px at 2-8.5 m, 0.26 px at 1-2 m).
    """

    person_width_m: float = 0.4
    surround_m: float = 0.3
    depth_band_m: float = 0.2
    min_height_m: float = 0.12
    max_height_m: float = 2.0
    above_m: float = 2.45
    above_weight: float = 3.0
    max_range_m: float = 9.5
    min_range_m: float = 0.7
    peak_threshold: float = 0.3
    tm: float = 0.5
    tau_m: float = 0.08
    min_top_m: float = 1.2
    max_top_m: float = 2.2
    min_width_m: float = 0.12
    max_width_m: float = 1.1
    min_extent_m: float = 0.4
    max_candidates: int = 16
    disparity_sigma_px: float = 0.21
    band_sigmas: float = 3.0

    def __post_init__(self) -> None:
        """ConfigError for a setting out of range (before 2026-11-26 none was checked: a NaN
        ``tm`` accepted every candidate, a zero range or ``tau_m`` divided by zero)."""
        lengths = ("person_width_m", "surround_m", "depth_band_m", "max_height_m", "above_m",
                   "max_range_m", "min_range_m", "tau_m", "max_top_m", "max_width_m")
        for name in lengths:
            v = getattr(self, name)
            if not (is_real(v) and v > 0):
                raise ConfigError(f"HumanDetectorParams.{name} must be a finite number > 0, got "
                                  f"{v!r}")
        for name in ("min_height_m", "above_weight", "min_top_m", "min_width_m",
                     "min_extent_m", "disparity_sigma_px", "band_sigmas"):
            v = getattr(self, name)
            if not (is_real(v) and v >= 0):
                raise ConfigError(f"HumanDetectorParams.{name} must be a finite number >= 0, "
                                  f"got {v!r}")
        for name in ("peak_threshold", "tm"):
            v = getattr(self, name)
            if not (is_real(v) and 0 <= v <= 1):
                raise ConfigError(f"HumanDetectorParams.{name} must be in [0, 1], got {v!r}")
        for lo, hi in (("min_height_m", "max_height_m"), ("min_range_m", "max_range_m"),
                       ("min_top_m", "max_top_m"), ("min_width_m", "max_width_m")):
            if not getattr(self, lo) < getattr(self, hi):
                raise ConfigError(f"HumanDetectorParams: {lo} ({getattr(self, lo)}) must be "
                                  f"below {hi} ({getattr(self, hi)})")
        whole_number("HumanDetectorParams.max_candidates", self.max_candidates)


def check_params(params: HumanDetectorParams | None) -> HumanDetectorParams:
    """``params`` (None: the defaults) checked again, as :class:`HumanDetectorParams` checks
    them when made: its fields can be edited afterwards, and an edited ``tm = nan`` accepted
    every candidate (a furniture box as a person), a ``max_top_m = nan`` none. ConfigError
    for a setting out of range or ``params`` that is not a HumanDetectorParams (a dict was a
    builtin AttributeError deep in the detector). The check of every function that takes
    them."""
    if params is None:
        return HumanDetectorParams()
    if not isinstance(params, HumanDetectorParams):
        raise ConfigError(f"params must be a HumanDetectorParams, got {type(params).__name__}")
    params.__post_init__()
    return params


# ---------------------------------------------------------------------------------------------
# Floor
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FloorPlane:
    """The floor as a plane in the camera frame: ``height(P) = P @ normal + offset`` metres
    above the floor (``normal`` is the unit "up" vector in the optical frame, i.e. about
    ``(0, -1, 0)`` for a level camera; ``offset`` the camera height). ``source`` says where it
    came from ("ransac", "prior")."""

    normal: NDArray
    offset: float
    source: str = "prior"

    def __post_init__(self) -> None:
        """GeometryError unless ``normal`` is a finite unit vector pointing up (``-y``
        component > 0) and ``offset`` finite: any other scaled, inverted or NaN'd every height
        silently."""
        # (a normal of text was kept as given: numpy read it as numbers here and every height
        # failed later with a builtin error)
        n = np.asarray(self.normal, dtype=float) if real_entries(self.normal) else np.zeros(0)
        if (n.shape != (3,) or not np.all(np.isfinite(n)) or abs(np.linalg.norm(n) - 1.0) > 1e-6
                or not n[1] < 0):
            raise GeometryError(f"FloorPlane: normal must be the unit 'up' vector in the optical "
                                f"frame (about (0, -1, 0), y down), got {self.normal!r}")
        if not is_real(self.offset):
            raise GeometryError(f"FloorPlane: offset (camera height, metres) must be finite, "
                                f"got {self.offset!r}")

    @classmethod
    def level(cls, camera_height_m: float) -> FloorPlane:
        """The floor of a level camera ``camera_height_m`` metres (finite, > 0) above it."""
        return cls.from_camera(camera_height_m, 0.0)

    @classmethod
    def from_camera(cls, camera_height_m: float, pitch_deg: float = 0.0) -> FloorPlane:
        """The floor of a camera ``camera_height_m`` metres (finite, > 0) above it whose
        optical axis is pitched ``pitch_deg`` degrees above the horizontal (+ = looking up,
        :func:`check_camera_pitch`), without roll: the up vector in the optical frame (x
        right, y down, z forward) is ``(0, -cos p, sin p)``."""
        # (the checks let None through, for "no prior": here it was float()'s TypeError)
        if camera_height_m is None or pitch_deg is None:
            raise GeometryError(f"a floor needs a camera height (m) and pitch (deg), got "
                                f"{camera_height_m!r} and {pitch_deg!r}")
        check_camera_height(camera_height_m)
        p = np.radians(check_camera_pitch(pitch_deg, "pitch_deg"))
        return cls(_up_vector(p), float(camera_height_m), "prior")

    @property
    def pitch_deg(self) -> float:
        """The camera's pitch above the horizontal this floor implies, degrees (+ = looking
        up): ``atan2(n_z, -n_y)`` of the up vector ``n``; a roll does not enter it."""
        return float(np.degrees(np.arctan2(self.normal[2], -self.normal[1])))

    def height(self, points: NDArray) -> NDArray:
        """Height above the floor (metres) of points ``(..., 3)``; ImageInputError unless they
        are numbers (text raised numpy's UFuncTypeError) of that shape."""
        points = numeric_map("points", points, None)
        if points.ndim == 0 or points.shape[-1] != 3:
            raise ImageInputError(f"points must be (..., 3) metres, got shape {points.shape}")
        return points @ self.normal + self.offset

    @property
    def camera_height_m(self) -> float:
        return float(self.offset)


def _up_vector(pitch_rad: float) -> NDArray:
    """The up vector, in the optical frame, of a camera pitched ``pitch_rad`` up (no roll)."""
    return np.array([0.0, -np.cos(pitch_rad), np.sin(pitch_rad)])


def estimate_floor(points: NDArray, *, prior_height_m: float | None = None, step: int = 8,
                   iterations: int = 500, inlier_m: float = 0.04, max_tilt_deg: float = 20.0,
                   seed: int = 0, prior_pitch_deg: float | None = 0.0) -> FloorPlane:
    """RANSAC floor plane from 3D points ``(H, W, 3)`` (camera frame, metres, NaN invalid).

    ``prior_pitch_deg`` is the camera's pitch above the horizontal (degrees, + = looking up,
    no roll, None = level; :func:`check_camera_pitch`), known from its mounting or the head's
    tilt: "up" and "below the camera" below are measured along that camera's up vector
    (:meth:`FloorPlane.from_camera`), and the fallback is that camera's floor. Until
    2026-12-03 the camera was taken as level: pitched up 15 deg it saw too little floor (the
    nearest visible 6 m out) and fell back to a level floor, which puts a point d metres ahead
    about d sin 15 deg too low or high (on 20 dev scenes 10 of 45 people were found, 35 with
    the camera level); a tilt beyond ``max_tilt_deg`` (a head looking down 25 deg at a person
    0.7 m away) could never be found.

    Only points at least 0.3 m below the camera and nearer than 10 m are used (subsampled every
    ``step`` pixels); planes tilted more than ``max_tilt_deg`` from the prior are refused. Each of
    ``iterations`` three-point hypotheses is scored by its inliers (within ``inlier_m``) MINUS
    the points lying clearly below it (more than :data:`FLOOR_BELOW_M`): a camera cannot see
    through the floor, so a plane with surfaces beneath it is not the floor. The best one is
    refined by least squares on its inliers. Falls back to a level floor at ``prior_height_m``
    when no floor is found (EstimationError when there is no prior either). When a prior is
    given, floors more than 0.5 m from it are refused; the prior must be a finite height > 0
    (GeometryError).

    Before 2026-11-26 hypotheses were scored by inliers alone, from 120 draws: with little
    floor in view (a robot facing a wall 1-3 m away) a plane tilted 10-20 deg through the
    wall's base and a person's legs won (hundreds of points below it), and with 12 % floor
    points the true floor was often never drawn. Heights were then off by up to 0.8 m at the
    person and the robot lost a verified person (bench/robot seed 142). The below-the-plane
    test is the "nothing under the ground" constraint of stereo ground estimation (compare
    the lowest-envelope line of the v-disparity image, Labayrade, Aubert & Tarel 2002).
    """
    check_camera_height(prior_height_m, "prior_height_m")
    points = _point_image(points)  # (no float64 copy of the whole image: it is subsampled)
    step = whole_number("step", step)  # (0 was numpy's "slice step cannot be zero")
    iterations = whole_number("iterations", iterations)
    inlier_m = finite_number("inlier_m", inlier_m, 0.0, lo_open=True)
    max_tilt_deg = finite_number("max_tilt_deg", max_tilt_deg, 0.0, 90.0, lo_open=True)
    pitch = check_camera_pitch(prior_pitch_deg, "prior_pitch_deg")
    if pitch is None:  # (None: the level camera of the default)
        pitch = 0.0
    up = _up_vector(np.radians(pitch))  # ((0, -1, 0) exactly for a level camera)
    P = points[::step, ::step].reshape(-1, 3).astype(float)  # float64 geometry
    P = P[np.all(np.isfinite(P), axis=1)]
    P = P[(-(P @ up) > 0.3) & (P[:, 2] < 10.0)]
    best: FloorPlane | None = None
    if len(P) >= 60:
        rng = np.random.default_rng(seed)
        idx = rng.integers(0, len(P), (iterations, 3))
        a, b, c = P[idx[:, 0]], P[idx[:, 1]], P[idx[:, 2]]
        n = np.cross(b - a, c - a)
        norm = np.linalg.norm(n, axis=1)
        ok = norm > 1e-9
        n = n[ok] / norm[ok, None]
        a = a[ok]
        n *= np.where(n @ up < 0, -1.0, 1.0)[:, None]  # toward the prior's "up" (-y: level)
        off = -np.einsum("ij,ij->i", n, a)
        level = n @ up >= np.cos(np.radians(max_tilt_deg))
        if prior_height_m is not None:
            level &= np.abs(off - prior_height_m) < 0.5
        if np.any(level):
            n, off = n[level], off[level]
            # (N, k) heights above each hypothesis; float32 halves the time of this, the
            # costliest step (2-4 ms for 2000 points x 500 hypotheses)
            h = P.astype(np.float32) @ n.T.astype(np.float32) + off.astype(np.float32)
            inliers = np.abs(h) < inlier_m
            support = inliers.sum(axis=0) - (h < -FLOOR_BELOW_M).sum(axis=0)
            k = int(np.argmax(support))
            if support[k] >= max(40, 0.05 * len(P)):
                inl = P[inliers[:, k]]
                cen = inl.mean(axis=0)
                _, _, vt = np.linalg.svd(inl - cen, full_matrices=False)
                nn = vt[-1]
                nn = -nn if nn @ up < 0 else nn
                if nn @ up >= np.cos(np.radians(max_tilt_deg)):
                    best = FloorPlane(nn, float(-nn @ cen), "ransac")
    if best is not None:
        return best
    if prior_height_m is None:
        raise EstimationError(
            "no floor found in the disparity and no camera height known: add "
            "'info: {camera_height_m: <metres>}' to the calibration file or pass the camera height"
        )
    return FloorPlane.from_camera(prior_height_m, pitch)


# ---------------------------------------------------------------------------------------------
# P(y,d) and the scale-adaptive filter
# ---------------------------------------------------------------------------------------------
def u_disparity(disparity: NDArray, mask: NDArray | None = None, max_disparity: int | None = None
                ) -> NDArray:
    """P(y,d): counts ``(n_d, W)`` of pixels with (rounded) disparity ``d`` in image column ``y``.

    ``disparity`` is ``(H, W)`` float pixels (NaN/<=0 invalid); ``mask`` (H, W) bool selects
    the pixels counted (e.g. not floor); ``n_d = max_disparity + 1`` (default: the largest
    disparity + 1). A disparity larger than the image width cannot come from matching two
    images of that width (ImageInputError: a 1e12 once asked for 29 TiB of counts);
    ``max_disparity`` is an integer in [0, :data:`MAX_DISPARITY_PX`] (ConfigError). A
    disparity or mask that is no numbers (text, read as numbers; a text mask as all True) is
    an ImageInputError.

    >>> d = np.full((4, 8), np.nan); d[:, 1] = 5.0
    >>> u_disparity(d)[5].tolist()
    [0.0, 4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    """
    d = numeric_map("disparity", disparity, np.float32)
    if d.ndim != 2:
        raise ImageInputError(f"disparity must be (H, W), got shape {d.shape}")
    H, W = d.shape
    ok = np.isfinite(d) & (d > 0)
    if np.any(ok) and (top := float(d[ok].max())) > W:
        raise ImageInputError(f"disparity of {top:.4g} px exceeds the image width ({W} px): not "
                              "a disparity map of this image")
    if max_disparity is not None:
        max_disparity = whole_number("max_disparity", max_disparity, 0, MAX_DISPARITY_PX)
    if mask is not None:
        m = bool_mask(mask)
        if m.shape != d.shape:
            raise ImageInputError(f"mask must have the disparity's shape {d.shape}, got "
                                  f"{m.shape}")
        ok &= m
    di = np.rint(d[ok]).astype(np.int64)
    nd = int(max_disparity + 1 if max_disparity is not None else (di.max() + 1 if di.size else 1))
    keep = di < nd
    cols = np.broadcast_to(np.arange(W), (H, W))[ok][keep]
    counts = np.bincount(di[keep] * W + cols, minlength=nd * W)
    return counts.reshape(nd, W).astype(np.float32)


def _expected_rows(n_d: int, height: int, focal_px: float, baseline_m: float, cy: float,
                   floor: FloorPlane, lo_m: float, hi_m: float) -> NDArray:
    """Rows ``(n_d,)`` that an upright body from ``lo_m`` to ``hi_m`` above the floor covers at
    each disparity (in the image centre column)."""
    d = np.arange(n_d, dtype=float)
    with np.errstate(divide="ignore"):
        Z = np.where(d > 0, focal_px * baseline_m / np.maximum(d, 1e-9), np.inf)
    v = np.arange(height, dtype=float)
    Zf = np.where(np.isfinite(Z), Z, 0.0)
    Y = (v[None, :] - cy) / focal_px * Zf[:, None]  # (n_d, H)
    Zb = np.broadcast_to(Zf[:, None], Y.shape)
    h = floor.normal[1] * Y + floor.normal[2] * Zb + floor.offset
    rows = ((h >= lo_m) & (h <= hi_m)).sum(axis=1).astype(float)
    rows[0] = 0.0
    return rows


def disparity_band_px(disparity: NDArray | float, depth_band_m: float, focal_px: float,
                      baseline_m: float) -> NDArray:
    """Half width (whole pixels, at least 1) of the disparity band that ``depth_band_m`` metres
    of depth span at ``disparity`` pixels: ``max(1, rint(d^2 depth_band_m / (f B)))``. Psi-hat
    (:func:`scale_adaptive_filter`) sums P(y,d) over it, so a peak at ``d`` places the body
    only within this many pixels (plus half a pixel of rounding) of ``d``.

    ImageInputError unless ``disparity`` holds finite numbers (text was read as the numbers it
    spells, NaN gave the most negative int); ConfigError unless ``depth_band_m`` is a finite
    number >= 0; CalibrationError for a focal length or baseline that is not finite > 0."""
    d = numeric_map("disparity", disparity)
    if not np.all(np.isfinite(d)):
        raise ImageInputError(f"disparity must be finite pixels, got {disparity!r:.60}")
    depth_band_m = finite_number("depth_band_m", depth_band_m, 0.0)
    check_focal_baseline(focal_px, baseline_m)
    with np.errstate(over="ignore"):
        if not np.all(d * d * depth_band_m / (focal_px * baseline_m) < 2.0**31):
            # (the int cast wrapped: 1e200 px gave the most negative int)
            raise ImageInputError(f"disparity {float(np.max(np.abs(d))):.3g} px gives a band "
                                  "wider than any image: not a disparity")
    return _band_px(d, depth_band_m, focal_px, baseline_m)


def _band_px(d: NDArray | float, depth_band_m: float, focal_px: float, baseline_m: float
             ) -> NDArray:
    """:func:`disparity_band_px` of checked numbers (the detector's per-candidate calls)."""
    d = np.asarray(d, dtype=float)
    return np.maximum(1, np.rint(d * d * depth_band_m / (focal_px * baseline_m))).astype(int)


def scale_adaptive_filter(P: NDArray, focal_px: float, baseline_m: float, *,
                          expected_rows: NDArray | None = None, above: NDArray | None = None,
                          above_weight: float = 3.0, person_width_m: float = 0.4,
                          surround_m: float = 0.3, depth_band_m: float = 0.25) -> NDArray:
    """Psi-hat(y,d): P(y,d) filtered with kernels whose size scales with ``d``.

    1. Sum P over the disparity band ``|d' - d| <= max(1, d^2 depth_band_m / (f B))`` (a body's
       depth) -- minus ``above_weight`` times the same sum of ``above`` (counts of pixels
       just above a standing person's height: walls and tall shelves continue there), clipped
       at 0 -- 2. divide by ``expected_rows[d]`` (rows a standing person covers at ``d``; 1 if
       not given), 3. centre mean over ``person_width_m * d / B`` columns minus the smaller of
       the two surround means (each ``surround_m * d / B`` columns). Returns ``(n_d, W)``.

    An empty ``P`` (no disparities or no columns) gives an empty map. ImageInputError when
    ``P`` is not 2-D, ``above`` not of its shape or ``expected_rows`` not
    ``(n_d,)``, or any of them holds NaN or inf; ConfigError for an ``above_weight`` or
    ``depth_band_m`` that is not a finite number >= 0, or a kernel width that is not finite
    > 0.
    """
    check_focal_baseline(focal_px, baseline_m)
    P = numeric_map("P", P, finite=True)  # (one NaN made the whole map 0: every person lost)
    if P.ndim != 2:
        raise ImageInputError(f"P must be a (n_d, W) map of counts, got shape {P.shape}")
    nd, W = P.shape
    above_weight = finite_number("above_weight", above_weight, 0.0)
    depth_band_m = finite_number("depth_band_m", depth_band_m, 0.0)
    person_width_m = finite_number("person_width_m", person_width_m, 0.0, lo_open=True)
    surround_m = finite_number("surround_m", surround_m, 0.0, lo_open=True)
    # (converted first: a ragged nesting made np.shape raise numpy's ValueError)
    A = None if above is None else numeric_map("above", above, finite=True)
    e = None if expected_rows is None else numeric_map("expected_rows", expected_rows,
                                                       finite=True)
    if A is not None and A.shape != P.shape:
        raise ImageInputError(f"above must have P's shape {P.shape}, got {A.shape}")
    if e is not None and e.shape != (nd,):
        raise ImageInputError(f"expected_rows must have one value per disparity ({nd},), got "
                              f"shape {e.shape}")
    d = np.arange(nd, dtype=float)
    band = _band_px(d, depth_band_m, focal_px, baseline_m)
    cs = np.vstack([np.zeros((1, W)), np.cumsum(P, axis=0)])
    lo = np.clip(np.arange(nd) - band, 0, nd)
    hi = np.clip(np.arange(nd) + band + 1, 0, nd)
    Pb = cs[hi] - cs[lo]
    if A is not None:
        ca = np.vstack([np.zeros((1, W)), np.cumsum(A, axis=0)])
        Pb = np.clip(Pb - above_weight * (ca[hi] - ca[lo]), 0.0, None)
    if e is not None:
        Pb = np.where(e[:, None] > 3, Pb / np.maximum(e[:, None], 1.0), 0.0)
    half = np.maximum(1, np.rint(0.5 * person_width_m * d / baseline_m)).astype(int)[:, None]
    sur = np.maximum(1, np.rint(surround_m * d / baseline_m)).astype(int)[:, None]
    cc = np.hstack([np.zeros((nd, 1)), np.cumsum(Pb, axis=1)])
    y = np.arange(W)[None, :]

    def box_mean(a: NDArray, b: NDArray) -> NDArray:
        a = np.clip(a, 0, W)
        b = np.clip(b, 0, W)
        s = np.take_along_axis(cc, b, 1) - np.take_along_axis(cc, a, 1)
        width = np.broadcast_to(b - a, s.shape)
        return np.where(width > 0, s / np.maximum(width, 1), np.nan)  # NaN: outside the image

    centre = np.nan_to_num(box_mean(y - half, y + half + 1))
    left = box_mean(y - half - sur, y - half)
    right = box_mean(y + half + 1, y + half + 1 + sur)
    both = np.fmin(left, right)  # a surround outside the image is unknown, not empty
    psi = centre - np.nan_to_num(both)
    psi[:1] = 0.0  # (psi[0]: an IndexError for a map of no disparities)
    return psi


def find_peaks(psi: NDArray, focal_px: float, baseline_m: float, *, threshold: float = 0.3,
               min_disparity: float = 1.0, person_width_m: float = 0.4, depth_sep_m: float = 0.5,
               max_peaks: int = 12) -> list[tuple[int, int, float]]:
    """Greedy non-maximum suppression on Psi-hat: returns ``[(column, disparity, value)]``,
    strongest first. Around each peak, columns within ``person_width_m`` (scaled by ``d/B``)
    and depths within ``depth_sep_m`` are suppressed. Disparities below ``min_disparity``
    (pixels, a finite number >= 0: a negative one used to cut rows from the far end, ConfigError)
    are not searched. ``threshold``, ``person_width_m`` (> 0), ``depth_sep_m`` (>= 0) and
    ``max_peaks`` (an integer >= 0) are ConfigErrors otherwise (a NaN threshold found no peak
    without a word; a NaN width, a fractional count or text raised builtin errors), ``psi``
    that is not a 2-D map of finite numbers an ImageInputError; an empty ``psi`` has no peaks."""
    check_focal_baseline(focal_px, baseline_m)
    min_disparity = finite_number("min_disparity", min_disparity, 0.0)
    finite_number("threshold", threshold)
    finite_number("person_width_m", person_width_m, 0.0, lo_open=True)
    finite_number("depth_sep_m", depth_sep_m, 0.0)
    max_peaks = whole_number("max_peaks", max_peaks, 0)
    ps = numeric_map("psi", psi, copy=True, finite=True)  # (a NaN hid every peak: argmax)
    if ps.ndim != 2:
        raise ImageInputError(f"psi must be a (n_d, W) map, got shape {ps.shape}")
    nd, W = ps.shape
    if ps.size == 0:  # (numpy's 'argmax of an empty sequence')
        return []
    ps[: int(np.ceil(min_disparity))] = -np.inf
    d = np.arange(nd, dtype=float)
    with np.errstate(divide="ignore"):
        Z = np.where(d > 0, focal_px * baseline_m / np.maximum(d, 1e-9), np.inf)
    out = []
    for _ in range(max_peaks):
        k = int(np.argmax(ps))
        di, yi = divmod(k, W)
        v = ps[di, yi]
        if not v >= threshold:
            break
        out.append((yi, di, float(v)))
        half = max(2, int(round(person_width_m * di / baseline_m)))
        with np.errstate(invalid="ignore"):
            rows = np.abs(Z - Z[di]) < depth_sep_m
        rows[di] = True  # (at d = 0, inf - inf is NaN: the peak came back every time)
        ps[rows, max(0, yi - half): yi + half + 1] = -np.inf
    return out


# ---------------------------------------------------------------------------------------------
# Segmentation and verification
# ---------------------------------------------------------------------------------------------
@dataclass
class BodySegment:
    """A candidate's silhouette: ``mask`` (bool, shape of ``box`` = [x, y, w, h] in rectified
    left-image pixels), 3D points ``(N, 3)`` of the silhouette (metres, rectified left frame)
    with their heights above the floor, ``top_m`` (the silhouette's robust top,
    :func:`robust_top_m`: metres above the floor, about :data:`CROWN_ABOVE_TOP_M` below the
    crown -- not its highest point, as this docstring said until 2026-12-02), ``width_m``
    and ``position_m`` (torso centre estimate). ``truncated``: the silhouette touches the top,
    left or right border of the image (a person close to the camera, or not yet centred), so
    its ``top_m`` and ``position_m`` describe the visible part only (the torso centre is
    biased toward it: 0.2-0.3 m in bench/robot's seed 16). Feet cut by the bottom border
    (usual at close range) leave the torso in view and do not count. ``beyond_search``: part
    of the body stands nearer than the disparity search reaches and the silhouette is broken
    up (:data:`NEAR_SEARCH_SHARE`, :data:`BROKEN_BOX_SHARE`; set by
    :func:`detect_candidates` when it knows the search), so its position may be tens of cm
    off: widen the search (``num_disparities``)."""

    box: list[int]
    mask: NDArray
    points: NDArray
    heights: NDArray
    depth_m: float
    top_m: float
    width_m: float
    position_m: NDArray
    truncated: bool = False
    beyond_search: bool = False
    floor_row: int | None = None

    @property
    def body_box(self) -> list[int]:
        """``box`` [x, y, w, h] (pixels) extended down to :attr:`floor_row` -- where the body
        stands on the floor -- when that row is known and below the silhouette: the
        silhouette itself stops at ``min_height_m`` (0.12 m) above the floor, so the box
        left the feet out (bottom 9-13 px high at 2-9 m, IoU with the body's visible pixels
        0.81-0.93). The detections' boxes (:class:`hearsee.vision.fusion.Human`); the
        detector's own decisions (holes, duplicates) read ``box``, the silhouette's."""
        x, y, w, h = self.box
        if self.floor_row is None or self.floor_row <= y + h - 1:
            return list(self.box)
        return [x, y, w, self.floor_row - y + 1]

    @cached_property
    def extent_m(self) -> float:
        """The silhouette's own height (metres): its ``top_m`` less the height of its lowest
        points (the ``100 - TOP_PERCENTILE`` percentile of ``heights``, as robust as the
        top). A whole standing person spans 1-1.9 m, a person whose feet the image's bottom
        border cuts 0.7 m or more; a head-sized fragment a few tenths. Computed once (the
        extent test and every duplicate comparison read it)."""
        return self.top_m - float(np.percentile(self.heights, 100.0 - TOP_PERCENTILE))


def robust_top_m(heights: NDArray) -> float:
    """Top of a silhouette, metres above the floor: the :data:`TOP_PERCENTILE` percentile of
    its points' ``heights`` (metres), so that a few stray points above the head (a wall pixel
    that passed the depth band, a matching error) do not move it. :attr:`BodySegment.top_m`
    and the head band of :func:`hearsee.vision.fusion.thermal_support`. ImageInputError
    unless ``heights`` are finite numbers, at least one (text and an empty set raised builtin
    errors, a NaN gave a NaN top)."""
    heights = numeric_map("heights", heights, None, finite=True)  # (a NaN made the top NaN)
    if heights.size == 0:
        raise ImageInputError("heights must hold at least one point")
    return float(np.percentile(heights, TOP_PERCENTILE))


def segment_band_m(depth_m: float, focal_px: float, baseline_m: float,
                   params: HumanDetectorParams) -> float:
    """Half depth (metres) of the band :func:`segment_body` keeps around a candidate
    ``depth_m`` metres away: ``max(depth_band_m + 0.15, band_sigmas * sigma_Z)`` with the stereo
    depth noise ``sigma_Z = Z^2 disparity_sigma_px / (f B)`` metres (``focal_px`` pixels,
    ``baseline_m`` metres).

    The fixed 0.35 m holds a body's depth (about +-0.15 m) plus the noise of near people;
    beyond ~5.8 m (f B = 60 px m, 0.21 px, 3 sigma) the noise is larger, and before 2026-11-26
    people 6-8.5 m away were cut down to the pixels that happened to fall in the band (often
    the head: a head-sized false detection plus a missed person).

    ``params`` must be a :class:`HumanDetectorParams` (ConfigError, :func:`check_params`),
    ``depth_m`` a finite number > 0 (GeometryError: a NaN or negative depth gave the near
    band without a word), ``focal_px`` and ``baseline_m`` finite and > 0 (CalibrationError: a
    zero one was a builtin ZeroDivisionError).
    """
    check_focal_baseline(focal_px, baseline_m)
    depth_m = finite_number("depth_m", depth_m, 0.0, lo_open=True, error=GeometryError)
    return _band_m(depth_m, focal_px, baseline_m, check_params(params))


def _band_m(depth_m: float, focal_px: float, baseline_m: float,
            params: HumanDetectorParams) -> float:
    """:func:`segment_band_m` of checked numbers and parameters (the detector's calls)."""
    sigma_z = depth_m * depth_m * params.disparity_sigma_px / (focal_px * baseline_m)
    return max(params.depth_band_m + 0.15, params.band_sigmas * sigma_z)


def segment_body(column: int, disp: float, disparity: NDArray, points: NDArray,
                 heights: NDArray, floor: FloorPlane, focal_px: float, baseline_m: float,
                 cy: float, *, params: HumanDetectorParams | None = None) -> BodySegment | None:
    """Back-project candidate (column, disparity) to a silhouette (7.2.2); None if empty.

    ``focal_px``, ``baseline_m``, ``cy``: rectified focal length (px), baseline (m) and
    principal row (px) of the rig (CalibrationError unless finite, the first two > 0). Only the
    rows where a body standing on ``floor`` can appear at the candidate's depth are searched,
    counted from the principal row ``cy`` (before 2026-11-26 from the image centre
    ``(H - 1) / 2``: on a rig whose ``cy`` is far from it the window cut heads or feet off).

    Pixels within ``0.6 m`` (scaled by ``d/B``) of the column whose depth is within
    :func:`segment_band_m` of the candidate's, above ``min_height_m`` and below
    ``above_m`` (so walls keep their full height and fail the extent test), closed and opened
    (kernels scaled with ``d``); the connected component under the candidate column is kept
    and the depth band re-centred on its median once. The candidate's depth is first taken
    from the median of the central strip's pixels near the peak: within the band of the
    peak's depth or within the disparity band Psi-hat summed at the peak
    (:func:`disparity_band_px`, plus half a pixel of rounding), whichever is wider -- a far
    person's peak is often one whole disparity off (at 7 m the body at d = 9 px also makes a
    stronger peak at d = 8, 0.8 m farther), and the depth band alone missed the body.

    ``column`` is an integer (pixels; one outside the image has no silhouette), ``disp`` a
    finite number of pixels (ImageInputError), ``disparity`` ``(H, W)`` pixels, ``points``
    ``(H, W, 3)`` metres and ``heights`` ``(H, W)`` metres of numbers (ImageInputError: a 1-D
    map, a list or a NaN ``disp`` were builtin errors, and points or heights of another size
    than the disparity gave None without a word) and ``floor`` a :class:`FloorPlane`
    (GeometryError).
    """
    check_focal_baseline(focal_px, baseline_m)
    check_principal_row(cy)
    p = check_params(params)
    disparity, points, heights = _segment_maps(column, disp, disparity, points, heights, floor)
    column, disp = int(column), float(disp)
    H, W = disparity.shape
    fb = focal_px * baseline_m
    half = int(round(0.6 * disp / baseline_m))
    u0, u1 = max(0, column - half), min(W, column + half + 1)
    if u1 - u0 < 3:
        return None
    Zc = fb / max(disp, 1e-6)
    # rows where a body between the floor and above_m can appear at this depth (level-ish rig)
    band0 = _band_m(Zc, focal_px, baseline_m, p)
    zn = max(Zc - band0, 0.3)
    y_top = (floor.offset - p.above_m) / max(-floor.normal[1], 0.5)
    y_bot = floor.offset / max(-floor.normal[1], 0.5)
    tilt = abs(floor.normal[2]) * focal_px + 0.15 * H
    v0 = int(max(0, np.floor(cy + focal_px * y_top / zn - tilt)))
    v1 = int(min(H, np.ceil(cy + focal_px * y_bot / zn + tilt)))
    if v1 - v0 < 3:
        return None
    sub_d = disparity[v0:v1, u0:u1]
    sub_h = heights[v0:v1, u0:u1]
    H = v1 - v0
    k = max(3, int(round(0.04 * disp / baseline_m)) | 1)
    ker = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
    kopen = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (max(3, k // 2 | 1),) * 2)
    # start from the median depth of the central strip's pixels near the peak disparity
    cw0 = max(1, int(round(0.1 * disp / baseline_m)))
    c0 = column - u0
    strip = sub_d[:, max(0, c0 - cw0): c0 + cw0 + 1]
    dpk = float(_band_px(disp, p.depth_band_m, focal_px, baseline_m)) + 0.5
    s_lo = min(fb / (Zc + band0), disp - dpk)
    s_hi = max(fb / max(Zc - band0, 0.2), disp + dpk)
    with np.errstate(invalid="ignore"):
        # (s_lo <= 0 for a peak within its disparity band of 0: zeros and negative values
        # are invalid disparities, as NaN)
        near_pk = strip[(strip >= s_lo) & (strip <= s_hi) & (strip > 0)]
    if near_pk.size >= 10:
        Zc = float(fb / np.median(near_pk))
    mask = None
    for _ in range(2):
        band = _band_m(Zc, focal_px, baseline_m, p)
        dlo, dhi = fb / (Zc + band), fb / max(Zc - band, 0.2)
        with np.errstate(invalid="ignore"):
            m = (sub_d >= dlo) & (sub_d <= dhi) & (sub_h >= p.min_height_m) & \
                (sub_h <= p.above_m)
        rows = np.nonzero(m.any(axis=1))[0]
        if len(rows) == 0:
            return None
        r0, r1 = max(0, rows[0] - k), min(H, rows[-1] + k + 1)
        m8 = np.zeros(m.shape, np.uint8)
        m8[r0:r1] = cv2.morphologyEx(m[r0:r1].astype(np.uint8), cv2.MORPH_CLOSE, ker)
        m8[r0:r1] = cv2.morphologyEx(m8[r0:r1], cv2.MORPH_OPEN, kopen)
        n, lab = cv2.connectedComponents(m8, connectivity=8)
        if n <= 1:
            return None
        c = column - u0
        cw = max(1, int(round(0.12 * disp / baseline_m)))
        centre = lab[:, max(0, c - cw): c + cw + 1]
        votes = np.bincount(centre.ravel(), minlength=n)
        votes[0] = 0
        best = int(np.argmax(votes))
        if votes[best] == 0:
            return None
        mask = (lab == best) & m  # keep only pixels that really have the disparity
        dm = sub_d[mask]
        Zm = float(fb / np.median(dm[:: max(1, len(dm) // 3000)]))
        if abs(Zm - Zc) < 0.12:
            break
        Zc = Zm
    assert mask is not None
    ys, xs = np.nonzero(mask)
    if len(ys) < 20:
        return None
    x0, x1, y0, y1 = xs.min(), xs.max(), ys.min(), ys.max()
    box = [int(u0 + x0), int(v0 + y0), int(x1 - x0 + 1), int(y1 - y0 + 1)]
    crop = mask[y0: y1 + 1, x0: x1 + 1]
    pts = points[v0:v1, u0:u1][mask]
    hts = sub_h[mask]
    good = np.all(np.isfinite(pts), axis=1)
    pts, hts = pts[good], hts[good]
    if len(pts) < 20:
        return None
    if len(pts) > 4000:  # statistics on a deterministic subsample (speed)
        sel = np.linspace(0, len(pts) - 1, 4000).astype(int)
        pts, hts = pts[sel], hts[sel]
    top = robust_top_m(hts)
    foot = _floor_row(pts, hts, floor, focal_px, cy, p.min_height_m, disparity.shape[0])
    xlo, xhi = np.percentile(pts[:, 0], [3, 97])
    Zm = float(np.median(pts[:, 2]))
    Xm = float(np.median(pts[:, 0]))
    # torso centre: at TORSO_HEIGHT_FRACTION of the body height (the crown, CROWN_ABOVE_TOP_M
    # above the robust top), body_surface_depth_m (of the silhouette's width) behind the
    # median of its visible surface, horizontally (in the floor's plane), and moved to that
    # height along the floor's normal. (Until 2026-12-07 the camera's own x-z plane and its y
    # axis: with the camera pitched, the move from the surface's median height to the torso's
    # -- 0.15-0.2 m -- went along the tilted y axis too, and the torso came out that times
    # sin(pitch) too near or too far: 4-5 cm at -15 deg on exact disparities.)
    n = floor.normal
    m = np.array([Xm, float(np.median(pts[:, 1])), Zm])
    ray = m - (m @ n) * n  # the median's direction from the camera, horizontal
    ray /= np.linalg.norm(ray)
    c = m + body_surface_depth_m(float(xhi - xlo)) * ray
    h_t = TORSO_HEIGHT_FRACTION * (top + CROWN_ABOVE_TOP_M)
    pos = c + (h_t - (c @ n + floor.offset)) * n
    return BodySegment(box, crop, pts, hts, Zm, top, float(xhi - xlo), pos,
                       _cut_by_border(box, disparity.shape[1]), floor_row=foot)


def _floor_row(points: NDArray, heights: NDArray, floor: FloorPlane, focal_px: float,
               cy: float, min_height_m: float, height_px: int) -> int | None:
    """Image row (rectified left pixels, at most ``height_px - 1``) of the floor under a
    silhouette's lowest points (``points`` ``(N, 3)`` metres, their ``heights`` above
    ``floor``), each moved down along the floor's normal by its height and projected with
    ``focal_px`` and the principal row ``cy``; None when those points end more than
    :data:`FEET_REACH_M` above the band's floor ``min_height_m`` (legs hidden behind
    something: the floor there is not the body's) or project behind the camera."""
    low_h = float(np.percentile(heights, 100.0 - TOP_PERCENTILE))
    if low_h > min_height_m + FEET_REACH_M:
        return None
    low = heights <= low_h + 0.05
    feet = points[low] - heights[low, None] * floor.normal
    feet = feet[feet[:, 2] > 0.05]
    if len(feet) == 0:
        return None
    row = float(np.median(cy + focal_px * feet[:, 1] / feet[:, 2]))
    return int(min(round(row), height_px - 1))


def _segment_maps(column: object, disp: object, disparity: ArrayLike, points: ArrayLike,
                  heights: ArrayLike, floor: object) -> tuple[NDArray, NDArray, NDArray]:
    """The checks of :func:`segment_body`'s candidate and maps: returns the maps as arrays."""
    if not isinstance(column, int | np.integer) or isinstance(column, bool):
        raise ImageInputError(f"column must be an image column (an integer, pixels), got "
                              f"{column!r:.40}")
    finite_number("disp (the candidate's disparity, pixels)", disp, error=ImageInputError)
    if not isinstance(floor, FloorPlane):
        raise GeometryError(f"floor must be a FloorPlane (estimate_floor, FloorPlane.level), "
                            f"got {type(floor).__name__}")
    d = numeric_map("disparity", disparity, None)
    pts = _point_image(points)
    h = numeric_map("heights", heights, None)
    if d.ndim != 2 or pts.shape != (*d.shape, 3) or h.shape != d.shape:
        raise ImageInputError(f"disparity (H, W), points (H, W, 3) and heights (H, W) expected, "
                              f"got {d.shape}, {pts.shape} and {h.shape}")
    return d, pts, h


def cut_by_border(box: Sequence[int], width: int) -> bool:
    """Whether a silhouette's ``box`` [x, y, w, h] (pixels) touches the top, left or right
    border of an image ``width`` pixels wide (:attr:`BodySegment.truncated`); the bottom
    border (feet cut at close range, torso in view) does not count. ImageInputError unless the
    box is four whole numbers >= 0 and ``width`` one >= 1 (int() read "3" as 3 and 2.7 as 2)."""
    if not isinstance(box, Sequence | np.ndarray) or len(box) != 4:
        raise ImageInputError(f"box must be [x, y, w, h] pixels, got {box!r}")
    x, y, w, _ = (whole_number(f"box {k}", v, 0, error=ImageInputError)
                  for k, v in zip("xywh", box, strict=True))
    return _cut_by_border([x, y, w, 0], whole_number("width", width, error=ImageInputError))


def _cut_by_border(box: Sequence[int], width: int) -> bool:
    """:func:`cut_by_border` of a box and width of ints (the detector's per-candidate call)."""
    x, y, w, _ = box
    return x <= 0 or y <= 0 or x + w >= width


def upper_contour(mask: NDArray) -> NDArray:
    """Row of the topmost silhouette pixel of each column of a bool mask (NaN where empty);
    ImageInputError unless ``mask`` is bool or numbers (a mask of text read as all True)."""
    m = bool_mask(mask)
    if m.shape[0] == 0:  # (no rows: numpy's "argmax of an empty sequence")
        return np.full(m.shape[1], np.nan)
    has = m.any(axis=0)
    top = np.argmax(m, axis=0).astype(float)
    top[~has] = np.nan
    return top


def head_shoulder_score(mask: NDArray, depth_m: float, focal_px: float, *, tau_m: float = 0.08
                        ) -> tuple[float, dict[str, float]]:
    """Match a deformable head-shoulder template to the silhouette's upper contour (7.2.3).

    ``mask`` is the silhouette (bool, its own box); ``depth_m`` its depth, which fixes the
    template's scale (``focal_px / depth_m`` pixels per metre). The template contour, in metres
    below the top of the head at lateral offset ``x`` from the head centre, is a half ellipse
    for the head (half width ``a``, height 0.2 m) and a shoulder line at drop ``s`` below the
    head top, sloping down 0.12 m/m out to half the shoulder width ``S/2``; beyond the
    shoulders the contour must fall at least 0.12 m below the shoulder line; in the 5 cm
    "neck" beside the head it must lie between 0.1 m below the head top and the shoulder line
    (weighted 3x: this omega notch is what wide boxes lack). The head may be
    offset from the silhouette's highest column. Over all (offset, a, S, s) the mean truncated
    vertical distance between contour and template (a vertical chamfer distance, truncated at
    ``tau_m``) is minimised; ``score = 1 - best / tau_m`` in [0, 1].

    Limitation (measured 2026-12-01): a narrow upright post passes. Flat-topped posts
    0.08-0.3 m wide score 0.53-0.66 (above the default ``tm`` = 0.5), because the narrowest
    template (``S`` = 0.22 m, ``a`` = 0.11 m) has no shoulders and "beyond the shoulders",
    where a contour falling away costs nothing, then covers most of the neck. Stereo alone
    cannot tell such a post from a person seen side-on; the thermal stage
    (:mod:`hearsee.vision.fusion`) rejects it. A stricter template (shoulders never inside
    the neck, weighted 2x) scored the posts 0.40-0.46 and cut other stereo false accepts per
    frame from 0.29 to 0.21 on bench/humans (seed 1000, 300 scenes), but cost 1 point of
    recall (0.988 -> 0.978, stereo and fusion): not adopted.

    Returns ``(score, params)`` with the best ``head_offset_m``, ``head_half_width_m``,
    ``shoulder_width_m``, ``shoulder_drop_m`` and ``chamfer_m``.

    ``mask`` must be 2-D (ImageInputError), ``depth_m`` a finite number of metres > 0
    (GeometryError), ``focal_px`` finite > 0 (CalibrationError), ``tau_m`` finite > 0
    (ConfigError): a zero one divided by zero, a negative depth mirrored the template.
    """
    mask = bool_mask(mask)  # (np.ndim of a ragged list was numpy's ValueError)
    finite_number("depth_m", depth_m, 0.0, lo_open=True, error=GeometryError)
    finite_number("focal_px", focal_px, 0.0, lo_open=True, error=CalibrationError)
    finite_number("tau_m", tau_m, 0.0, lo_open=True)
    top = upper_contour(mask)
    if np.all(np.isnan(top)):
        return 0.0, {}
    s_px = focal_px / depth_m  # pixels per metre
    ncol = len(top)
    prof = (top - np.nanmin(top)) / s_px  # metres below the highest point
    # head column: centre of the columns within 3 cm of the top
    near = np.nonzero(prof <= 0.03)[0]
    hc = 0.5 * (near.min() + near.max())
    xs = np.arange(-0.42, 0.4201, 0.015)  # lateral samples (m)
    offsets = np.arange(-0.06, 0.0601, 0.02)
    a_s = np.array([0.065, 0.08, 0.095, 0.11])
    S_s = np.array([0.22, 0.3, 0.38, 0.46, 0.54])
    s_s = np.array([0.22, 0.26, 0.30, 0.34])
    O, A, S, D = np.meshgrid(offsets, a_s, S_s, s_s, indexing="ij")
    O, A, S, D = O.ravel(), A.ravel(), S.ravel(), D.ravel()
    # observed profile at x + offset
    cols = hc + (xs[None, :] + O[:, None]) * s_px
    ci = np.rint(cols).astype(int)
    inside = (ci >= 0) & (ci < ncol)
    obs = np.where(inside, prof[np.clip(ci, 0, ncol - 1)], np.nan)
    obs = np.where(np.isnan(obs), 10.0, obs)  # empty column: contour far below
    ax = np.abs(xs)[None, :]
    Ac, Sc, Dc = A[:, None], S[:, None], D[:, None]
    head = 0.1 * (1.0 - np.sqrt(np.clip(1.0 - (ax / Ac) ** 2, 0.0, 1.0)))
    shoulder = Dc + 0.12 * np.clip(ax - Ac - 0.05, 0.0, None)
    tpl = np.where(ax <= Ac, head, shoulder)
    # neck transition: between the head and the shoulders the contour may be anywhere between
    neck = (ax > Ac) & (ax <= Ac + 0.05)
    err = np.abs(obs - tpl)
    # neck: the contour must have dropped below the head (>= 0.1 m) but not below the
    # shoulders; this "omega" notch on both sides of the head is what boxes and poles lack
    neck_err = np.where(obs < 0.1, 0.1 - obs + 0.04, np.clip(obs - Dc - 0.03, 0.0, None))
    err = np.where(neck, neck_err, err)
    out = ax > Sc / 2 + 0.03
    # beyond the shoulders: fine if the contour is at/below the shoulder line + 0.12 m
    err = np.where(out, np.clip(Dc + 0.12 - obs, 0.0, None), err)
    err = np.minimum(err, tau_m)
    within = ax <= Sc / 2 + 0.15
    weight = within * np.where(neck, 3.0, 1.0)
    cost = (err * weight).sum(axis=1) / weight.sum(axis=1)
    k = int(np.argmin(cost))
    best = float(cost[k])
    score = float(np.clip(1.0 - best / tau_m, 0.0, 1.0))
    return score, {"head_offset_m": float(O[k]), "head_half_width_m": float(A[k]),
                   "shoulder_width_m": float(S[k]), "shoulder_drop_m": float(D[k]),
                   "chamfer_m": best}


# ---------------------------------------------------------------------------------------------
# The stereo detector
# ---------------------------------------------------------------------------------------------
@dataclass
class HumanCandidate:
    """One P(y,d) peak and what stereo says about it.

    ``column``/``disparity``: the peak (pixels); ``response``: Psi-hat at the peak;
    ``segment``: the body segmentation (None when empty); ``score``: head-shoulder score;
    ``template``: the best template parameters; ``accepted``: passed stereo verification;
    ``reason``: why not (empty when accepted).
    """

    column: int
    disparity: int
    response: float
    segment: BodySegment | None
    score: float = 0.0
    template: dict[str, float] = field(default_factory=dict)
    accepted: bool = False
    reason: str = ""

    @property
    def box(self) -> list[int] | None:
        return None if self.segment is None else self.segment.box

    @property
    def position_m(self) -> NDArray | None:
        return None if self.segment is None else self.segment.position_m


@dataclass
class StereoDetection:
    """Everything :func:`detect_candidates` computed (for plots and fusion)."""

    candidates: list[HumanCandidate]
    floor: FloorPlane
    P: NDArray
    psi: NDArray
    heights: NDArray


def detect_candidates(disparity: NDArray, points: NDArray, focal_px: float, baseline_m: float,
                      cy: float, *, floor: FloorPlane | None = None,
                      camera_height_m: float | None = None,
                      params: HumanDetectorParams | None = None,
                      search_max_px: float | None = None,
                      camera_pitch_deg: float | None = None) -> StereoDetection:
    """Stereo-only human detection (7.2): P(y,d) -> Psi-hat -> peaks -> segmentation ->
    head-shoulder verification.

    Parameters
    ----------
    disparity : (H, W) float32 pixels (NaN invalid) of the rectified left image.
    points : (H, W, 3) metres in the rectified left frame (from the same disparity).
    focal_px, baseline_m, cy : rectified focal length (px), baseline (m), principal row (px).
    floor : the floor plane; estimated (RANSAC, prior ``camera_height_m``) when None.
    camera_height_m : height of the camera above the floor, metres (finite, > 0).
    camera_pitch_deg : the camera's pitch above the horizontal, degrees (+ = looking up; None:
        level), the floor estimate's prior (:func:`estimate_floor`); not used with ``floor``.
    params : :class:`HumanDetectorParams`.
    search_max_px : the largest disparity the matcher searched, pixels
        (:attr:`hearsee.vision.stereo.StereoFrame.search_px`; None: not known). A silhouette
        reaching it (:func:`near_search_share` >= :data:`NEAR_SEARCH_SHARE`) and broken up
        (:func:`unmatched_share` of its box >= :data:`BROKEN_BOX_SHARE`) is flagged
        :attr:`BodySegment.beyond_search`: its position and height describe a remainder.
        ``params.min_range_m`` says where people may stand; this says where the matcher
        can still see them (64 disparities at f B = 60 px m: 0.95 m).

    CalibrationError for a focal length or baseline that is not finite and > 0 or a
    non-finite ``cy``; GeometryError for a camera height that is not finite and > 0 or a
    ``floor`` that is no :class:`FloorPlane`.

    Returns
    -------
    :class:`StereoDetection` whose candidates have ``accepted`` set by the stereo checks
    (3D extent and ``score >= params.tm``).
    """
    check_focal_baseline(focal_px, baseline_m)
    check_principal_row(cy)
    check_camera_height(camera_height_m)
    camera_pitch_deg = check_camera_pitch(camera_pitch_deg)
    p = check_params(params)
    if search_max_px is not None:
        search_max_px = finite_number("search_max_px", search_max_px, 0.0, lo_open=True)
    d = numeric_map("disparity", disparity, np.float32)
    points = _point_image(points)
    if d.ndim != 2 or points.shape != (*d.shape, 3):
        raise ImageInputError(f"disparity (H, W) and points (H, W, 3) expected, got {d.shape} "
                              f"and {points.shape}")
    if d.size == 0:
        raise ImageInputError(f"the disparity image is empty (shape {d.shape})")
    if floor is None:
        floor = estimate_floor(points, prior_height_m=camera_height_m,
                               prior_pitch_deg=camera_pitch_deg)
    elif not isinstance(floor, FloorPlane):  # (a builtin AttributeError on floor.height)
        raise GeometryError(f"floor must be a FloorPlane (estimate_floor, FloorPlane.level) or "
                            f"None, got {type(floor).__name__}")
    with np.errstate(invalid="ignore"):
        heights = floor.height(points).astype(np.float32)
        d_min = focal_px * baseline_m / p.max_range_m
        d_max = focal_px * baseline_m / p.min_range_m
        near = d >= d_min
        counted = (heights >= p.min_height_m) & (heights <= p.max_height_m) & near
        above = (heights > p.max_height_m) & (heights <= p.above_m) & near
    # the largest VALID disparity (NaN, zero and negative ones are not matches)
    valid = d[np.isfinite(d) & (d > 0)]
    nd = int(np.ceil(min(valid.max() if valid.size else 1.0, d_max))) + 1
    # things that continue above a standing person (walls, tall shelves) count against P
    P = u_disparity(d, counted, max_disparity=nd)
    P_above = u_disparity(d, above, max_disparity=nd)
    e = _expected_rows(P.shape[0], d.shape[0], focal_px, baseline_m, cy, floor,
                       max(p.min_height_m, 0.1), 1.6)
    psi = scale_adaptive_filter(P, focal_px, baseline_m, expected_rows=e, above=P_above,
                                above_weight=p.above_weight,
                                person_width_m=p.person_width_m, surround_m=p.surround_m,
                                depth_band_m=p.depth_band_m)
    peaks = find_peaks(psi, focal_px, baseline_m, threshold=p.peak_threshold,
                       min_disparity=d_min, person_width_m=p.person_width_m,
                       max_peaks=p.max_candidates)
    cands: list[HumanCandidate] = []
    fb = focal_px * baseline_m
    for col, disp, val in peaks:
        # a peak on a silhouette already segmented (same column range and depth) is a duplicate
        Zp = fb / max(disp, 1e-6)
        prev = next((c for c in cands if c.segment is not None
                     and c.segment.box[0] <= col < c.segment.box[0] + c.segment.box[2]
                     and abs(c.segment.depth_m - Zp) < 0.3), None)
        if prev is not None:
            cands.append(HumanCandidate(col, disp, val, None, reason="duplicate of a stronger "
                                        "candidate (same silhouette)"))
            continue
        seg = segment_body(col, float(disp), d, points, heights, floor, focal_px, baseline_m,
                           cy, params=p)
        c = HumanCandidate(col, disp, val, seg)
        near = (near_search_share(d, seg, search_max_px)
                if seg is not None and search_max_px is not None else 0.0)
        if seg is None:
            c.reason = "empty segmentation"
        else:
            holes = unmatched_share(d, seg.box) if near >= NEAR_SEARCH_SHARE else 0.0
            seg.beyond_search = holes >= BROKEN_BOX_SHARE
            if not p.min_top_m <= seg.top_m <= p.max_top_m:
                c.reason = f"height {seg.top_m:.2f} m outside [{p.min_top_m}, {p.max_top_m}]"
            elif seg.extent_m < p.min_extent_m:
                c.reason = (f"silhouette {seg.extent_m:.2f} m tall < min_extent_m = "
                            f"{p.min_extent_m}")
            elif not p.min_width_m <= seg.width_m <= p.max_width_m:
                c.reason = f"width {seg.width_m:.2f} m outside [{p.min_width_m}, {p.max_width_m}]"
            else:
                c.score, c.template = head_shoulder_score(seg.mask, seg.depth_m, focal_px,
                                                          tau_m=p.tau_m)
            if c.reason:
                pass
            elif c.score < p.tm:
                c.reason = f"head-shoulder score {c.score:.2f} < Tm = {p.tm}"
            else:
                c.accepted = True
        cands.append(c)
    # one silhouette may yield two peaks (e.g. arms): drop accepted duplicates
    _dedupe(cands)
    return StereoDetection(cands, floor, P, psi, heights)


def near_search_share(disparity: NDArray, segment: BodySegment, search_max_px: float) -> float:
    """The share of a silhouette's valid disparities (pixels of ``disparity`` under
    ``segment``'s mask, finite and > 0) at the end of the matcher's search, within half a
    pixel of ``search_max_px``, its largest disparity: SGBM answers a surface nearer than the
    search with that disparity (or none), so this is the part of the silhouette that may
    stand nearer than the search reaches (:data:`NEAR_SEARCH_SHARE`). 0 for a silhouette
    without a valid disparity."""
    x, y, w, h = segment.box
    v = np.asarray(disparity)[y:y + h, x:x + w][segment.mask]
    v = v[np.isfinite(v) & (v > 0)]
    return float(np.mean(v >= search_max_px - 0.5)) if v.size else 0.0


def unmatched_share(disparity: NDArray, box: Sequence[int]) -> float:
    """The share of the pixels of ``box`` [x, y, w, h] (pixels) in ``disparity`` without a
    disparity (NaN or <= 0): how broken up a silhouette at the end of the search is
    (:data:`BROKEN_BOX_SHARE`)."""
    x, y, w, h = box
    v = np.asarray(disparity)[y:y + h, x:x + w]
    return float(np.mean(~(np.isfinite(v) & (v > 0)))) if v.size else 1.0


def _iou(a: list[int], b: list[int]) -> float:
    ax0, ay0, aw, ah = a
    bx0, by0, bw, bh = b
    iw = max(0, min(ax0 + aw, bx0 + bw) - max(ax0, bx0))
    ih = max(0, min(ay0 + ah, by0 + bh) - max(ay0, by0))
    inter = iw * ih
    union = aw * ah + bw * bh - inter
    return inter / union if union > 0 else 0.0


def _overlap(a: list[int], b: list[int]) -> float:
    """Intersection over the smaller box's area."""
    iw = max(0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    ih = max(0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    small = min(a[2] * a[3], b[2] * b[3])
    return iw * ih / small if small > 0 else 0.0


#: how much taller (metres) an accepted duplicate's silhouette must be than the one kept so
#: far to replace it (:func:`_dedupe`)
MORE_COMPLETE_M = 0.1


def _same_silhouette(a: BodySegment, b: BodySegment) -> bool:
    """One box mostly (> 70 % of the smaller) inside the other at a similar depth."""
    tol = max(0.4, 0.12 * b.depth_m)
    return _overlap(a.box, b.box) > 0.7 and abs(a.depth_m - b.depth_m) < tol


def _mark_duplicate(c: HumanCandidate) -> None:
    """Reject ``c`` as a duplicate, keeping why it was rejected before, if it was."""
    c.reason = ("duplicate of a stronger candidate" if c.accepted or not c.reason else
                f"duplicate of a stronger candidate ({c.reason})")
    c.accepted = False


def _dedupe(cands: list[HumanCandidate]) -> None:
    """Two peaks on one silhouette (:func:`_same_silhouette`): keep the better one (accepted
    first, then higher score) and mark the other as a duplicate -- except that an accepted
    candidate whose silhouette is taller by more than :data:`MORE_COMPLETE_M` than every
    accepted one it duplicates replaces them: it is the more complete view of the person (the
    other is the torso without the head, or the legs without the torso). In a 150-scene dev run
    (seeds 5000-5149) the higher score alone kept the shorter of two accepted silhouettes
    (shorter by more than 0.1 m) in 5 of the 208 duplicate pairs: 3 on people (IoU with the
    person 0.65 vs 0.79, 0.54 vs 0.66, 0.62 vs 0.75; the first two without the head) and 2 on
    objects; in every other pair of accepted silhouettes whose heights differ by more than
    0.1 m it already kept the taller one. (A rejected candidate never replaces an accepted
    one: the taller ones there are mostly a person merged with the wall behind.)"""
    segs = [c for c in cands if c.segment is not None]
    segs.sort(key=lambda c: (not c.accepted, -c.score))
    kept: list[HumanCandidate] = []
    for c in segs:
        sc = c.segment
        assert sc is not None
        dups = [k for k in kept if _same_silhouette(sc, k.segment)]  # type: ignore[arg-type]
        if not dups:
            kept.append(c)
        elif c.accepted and all(
                k.accepted and sc.extent_m > k.segment.extent_m + MORE_COMPLETE_M  # type: ignore[union-attr]
                for k in dups):
            for k in dups:
                _mark_duplicate(k)
            # (by identity: candidates compare their arrays under ==)
            kept = [k for k in kept if not any(k is d for d in dups)] + [c]
        else:
            _mark_duplicate(c)


# ---------------------------------------------------------------------------------------------
# Baseline: OpenCV's HOG people detector
# ---------------------------------------------------------------------------------------------
def detect_people_hog(image: NDArray, *, win_stride: int = 8, scale: float = 1.05,
                      hit_threshold: float = 0.0, shrink: bool = True
                      ) -> list[tuple[list[int], float]]:
    """OpenCV's HOG + linear SVM people detector (Dalal & Triggs, CVPR 2005;
    ``cv2.HOGDescriptor_getDefaultPeopleDetector``) on one image: the monocular baseline.

    Returns ``[(box [x, y, w, h] in pixels, SVM weight)]``. The 64x128 detection window has
    margins around the person; with ``shrink`` the boxes are shrunk by 15 % of the width on
    each side and 5 % of the height at top and bottom (as OpenCV's ``peopledetect.py`` sample
    draws them) so that they can be compared with tight person boxes.

    The search pads the image by 8 pixels on each side (boxes are clipped to the image); an
    image in which no 64x128 window fits even so -- under 48 pixels wide or 112 high -- has no
    detection (``[]``; OpenCV read and wrote past its buffers there: a segmentation fault or
    heap corruption on an 80x60 frame). This is the one small-image rule of the HOG detector:
    the stream's image-point detector (:func:`hearsee.stream.video.detect_source_point`) runs
    through this function.

    The image must be uint8 grey, BGR or BGRA (the alpha channel is dropped) and not empty
    (ImageInputError); ``win_stride`` (pixels) a positive integer and ``scale`` (the pyramid
    step) a finite number > 1 (ConfigError). OpenCV itself crashed the process on a negative
    stride.
    """
    img = _hog_image(image)
    win_stride = whole_number("win_stride (pixels)", win_stride)
    if not (is_real(scale) and scale > 1.0):
        raise ConfigError(f"scale must be a finite number > 1 (pyramid step), got {scale!r}")
    if not is_real(hit_threshold):
        raise ConfigError(f"hit_threshold must be a finite number, got {hit_threshold!r}")
    if img.shape[0] + 2 * _HOG_PAD < _HOG_WIN[1] or img.shape[1] + 2 * _HOG_PAD < _HOG_WIN[0]:
        return []  # no detection window fits the padded image
    hog = hog_people_detector()
    rects, weights = hog.detectMultiScale(img, hitThreshold=hit_threshold,
                                          winStride=(win_stride, win_stride),
                                          padding=(_HOG_PAD, _HOG_PAD), scale=scale)
    out = []
    for (x, y, w, h), wt in zip(np.asarray(rects).reshape(-1, 4),
                                np.asarray(weights).reshape(-1), strict=True):
        if shrink:
            px, py = int(0.15 * w), int(0.05 * h)
            x, y, w, h = x + px, y + py, w - 2 * px, h - 2 * py
        out.append(([int(x), int(y), int(w), int(h)], float(wt)))
    return out


def _hog_image(image: NDArray) -> NDArray:
    """The image as OpenCV's HOG takes it (:func:`~hearsee.vision.io.as_detector_image`, not
    empty)."""
    img = as_detector_image(image, "HOG")
    if img.size == 0:
        raise ImageInputError(f"HOG got an empty image, shape {img.shape}")
    return img


#: Detection window (width, height) of OpenCV's default people detector, pixels.
_HOG_WIN = (64, 128)
#: Padding of the image on each side in the HOG search, pixels (detectMultiScale's ``padding``).
_HOG_PAD = 8
_HOG: list = []


def hog_people_detector() -> cv2.HOGDescriptor:
    """OpenCV's HOG descriptor with its default people detector, made once and shared (this
    module's baseline and the stream's image-point detector)."""
    if not _HOG:
        hog = cv2.HOGDescriptor()
        hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
        _HOG.append(hog)
    return _HOG[0]
