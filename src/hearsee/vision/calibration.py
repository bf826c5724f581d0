"""Camera calibration (thesis appendix A and 7.4.1): chessboards, intrinsics, stereo extrinsics
and the extrinsics between a stereo rig and a thermal camera.

Reconstruction. Appendix A follows Zhang ("A flexible new technique for camera calibration",
PAMI 2000): several views of a planar chessboard give the intrinsics K, the lens distortion and
one board pose per view, refined by minimising the reprojection error (``cv2.calibrateCamera``).
The stereo extrinsics (R, T) come from boards seen by both cameras (``cv2.stereoCalibrate``:
first with the intrinsics fixed, then a joint refinement with the same distortion model and
aspect-ratio constraint, keeping the refinement only when it lowers the RMS error). The
thermal-to-stereo extrinsics (7.4.1) use a board visible to both (in practice a heated or
back-lit board): for each view the board's 3D corners in the left camera frame come from the
left camera's board pose, ``cv2.solvePnP`` gives the board pose in the thermal camera, each
view yields one thermal-from-left transform, those are averaged robustly (rotation mean after
rejecting views far from the median, median translation), and a final PnP over the corners of
all views jointly refines the transform.

All lengths (square size, translations) are metres; pixel errors are RMS pixels.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from hearsee.config import (
    as_float_array,
    as_rng,
    finite_number,
    is_real,
    real_entries,
    true_or_false,
    whole_number,
)
from hearsee.errors import CalibrationError, ConfigError
from hearsee.vision.camera import MIN_BASELINE_M, Camera, StereoRig, _check_rotation
from hearsee.vision.io import to_gray

__all__ = [
    "MAX_FOCAL_REL_STD",
    "MAX_RMS_PX",
    "CameraCalibration",
    "RigCalibration",
    "StereoCalibration",
    "ThermalExtrinsics",
    "board_points",
    "calibrate_camera",
    "calibrate_rig",
    "calibrate_stereo",
    "calibrate_thermal_extrinsics",
    "check_pattern",
    "find_corners",
    "match_labeling",
    "parse_board",
    "render_chessboard",
]

#: :func:`calibrate_rig` refuses a calibration whose RMS reprojection error (pixels; each
#: camera's intrinsics and the stereo fit) exceeds this. Good chessboard calibrations reach
#: 0.1-0.5 px (the real XIMEA pairs of the shared data: 0.17 / 0.17 / 0.19 px); a --board that
#: is a sub-grid of the real board (3x3 on a 9x6 board) is still "found" in every image, at a
#: different place in each, and gave 5.7-9.4 px intrinsics and 15-74 px stereo errors with a
#: focal length off by a factor of 3-6 -- written as the rig, with exit status 0, until
#: 2026-11-25's sixteenth session. :func:`calibrate_thermal_extrinsics` refuses a median
#: per-view error above it.
MAX_RMS_PX = 3.0

#: :func:`calibrate_camera` refuses a calibration whose focal length has a relative standard
#: deviation (1 sigma, from the Jacobian at the solution; the larger of fx, fy) above this.
#: Measured: the real XIMEA pairs of the shared data 0.16 % with all 25 views, 0.64/0.70 %
#: with the 6 of the tests, <= 1.33 % for any 4 consecutive views; the rendered boards of the
#: tests 0.12-0.70 % (thermal 160x120 included). Boards parallel to each other: 200 % for 8
#: rendered fronto-parallel views (fx 693 px for 300), 20-450 % for exact fronto-parallel
#: corners (fx off by 10x), 4-11 % for boards tilted by only +-5 deg (fx ~6 % off). Only
#: 3-view real sets come near: 2 of 46 consecutive triples exceed 3 % (3.2 %, 3.5 %; their fx
#: were 10.8 % and 8.9 % off the 25-view value), and of all 2 x 2300 triples the 1.7-2.6 %
#: above 3 % had fx 7-9 % off (median).
MAX_FOCAL_REL_STD = 0.03

#: The fewest inner corners per side of a board (OpenCV's chessboard detectors need more than 2)
MIN_BOARD_CORNERS = 3
#: :func:`parse_board` refuses more inner corners than this per side: no printed board has
#: them, and ``99999999999x6`` asked :func:`board_points` for 6.5 TiB (a builtin MemoryError).
MAX_BOARD_CORNERS = 1000

#: :func:`render_chessboard` refuses a blur sigma beyond this share of the image's larger side
#: (a blur that wide greys the whole board already): OpenCV's Gaussian kernel grows with the
#: sigma, and 1e6 px made it allocate 20 GB; max(width, height) took 5 minutes and 1.7 GB for
#: a 1280x960 image, an eighth of it 6 s and 45 MB (measured).
MAX_BLUR_SHARE = 0.125

#: Distortion models: number of coefficients and calibrateCamera flags.
_MODELS = {
    "radial": cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3 | cv2.CALIB_ZERO_TANGENT_DIST,  # k1 only
    "simple": cv2.CALIB_FIX_K3,                       # k1, k2, p1, p2
    "standard": 0,                                    # k1, k2, p1, p2, k3
    "rational": cv2.CALIB_RATIONAL_MODEL,             # + k4, k5, k6
}

#: Indices of the distortion coefficients each model estimates (the others are fixed).
_FREE_DIST = {"radial": [0], "simple": [0, 1, 2, 3], "standard": [0, 1, 2, 3, 4],
              "rational": [0, 1, 2, 3, 4, 5, 6, 7]}


def parse_board(text: str) -> tuple[int, int]:
    """``"9x6"`` -> ``(9, 6)``: inner corners per row x per column (OpenCV ``patternSize``)."""
    try:
        a, b = (int(v) for v in str(text).lower().replace("*", "x").split("x"))
    except ValueError:
        raise CalibrationError(
            f"board must look like 9x6 (inner corners per row x per column), got {text!r}"
        ) from None
    return check_pattern((a, b), text)


def check_pattern(pattern: Any, text: Any = None) -> tuple[int, int]:
    """``pattern`` (inner corners per row, per column) as two ints from
    :data:`MIN_BOARD_CORNERS` to :data:`MAX_BOARD_CORNERS`, else a CalibrationError quoting
    ``text`` (default the pattern). The board check of :func:`parse_board`,
    :func:`board_points`, :func:`find_corners` and :func:`match_labeling` (a pattern of (0, 0)
    or "9x6" reached OpenCV: cv2.error; (-2, 3) and (2.5, 3) numpy's ValueError / TypeError;
    2x5 passed and OpenCV's detectors raised cv2.error: they need 3 corners a side)."""
    shown = pattern if text is None else text
    try:
        a, b = pattern
    except (TypeError, ValueError):
        a = b = None
    if not all(isinstance(v, int | np.integer) and not isinstance(v, bool) for v in (a, b)):
        raise CalibrationError(f"board must be two whole numbers of inner corners (per row, per "
                               f"column), e.g. (9, 6), got {shown!r}")
    if a < MIN_BOARD_CORNERS or b < MIN_BOARD_CORNERS:
        raise CalibrationError(f"board needs at least {MIN_BOARD_CORNERS}x{MIN_BOARD_CORNERS} "
                               f"inner corners, got {shown!r}")
    if max(a, b) > MAX_BOARD_CORNERS:
        raise CalibrationError(f"board has at most {MAX_BOARD_CORNERS} inner corners per side, "
                               f"got {shown!r}")
    return int(a), int(b)


def board_points(pattern: tuple[int, int], square_m: float) -> NDArray:
    """3D corners ``(cols*rows, 3)`` float32 of a chessboard in its own frame (z = 0), metres,
    in OpenCV's order (along rows of ``pattern[0]`` corners)."""
    if not (is_real(square_m) and square_m > 0):  # (inf gave inf / NaN corners)
        raise CalibrationError(f"square size must be a finite number > 0 metres, got {square_m}")
    nx, ny = check_pattern(pattern)
    g = np.zeros((ny * nx, 3), np.float32)
    g[:, :2] = np.mgrid[0:nx, 0:ny].T.reshape(-1, 2) * square_m
    return g


# ---------------------------------------------------------------------------------------------
# Corners
# ---------------------------------------------------------------------------------------------
def _labelings(corners: NDArray, pattern: tuple[int, int]) -> list[NDArray]:
    """The four relabelings of a detected grid that keep rows of ``pattern[0]`` corners."""
    nx, ny = pattern
    g = corners.reshape(ny, nx, 2)
    out = [g, g[:, ::-1], g[::-1, :], g[::-1, ::-1]]
    if nx == ny:  # square grids can also be transposed
        t = g.transpose(1, 0, 2)
        out += [t, t[:, ::-1], t[::-1, :], t[::-1, ::-1]]
    return [np.ascontiguousarray(x.reshape(-1, 2)) for x in out]


def _canonical(corners: NDArray, pattern: tuple[int, int]) -> NDArray:
    """Relabel so that corner 0 is the outer corner nearest the image's top-left."""
    return min(_labelings(corners, pattern), key=lambda c: float(c[0, 0] + c[0, 1]))


def match_labeling(reference: NDArray, corners: NDArray, pattern: tuple[int, int]) -> NDArray:
    """Relabel ``corners`` (another camera's view of the same board) to match ``reference``:
    among the grid's relabelings, the one best explained by a scale + translation of the
    reference corners (cameras of a rig are roughly aligned, never rolled 180 deg apart).
    CalibrationError unless both hold the pattern's corners as finite pixels (a NaN was
    numpy's LinAlgError, another count a reshape ValueError)."""
    pattern = check_pattern(pattern)
    n = pattern[0] * pattern[1]
    for what, c in (("reference", reference), ("corners", corners)):
        if not real_entries(c) or np.size(c) != 2 * n or not np.all(np.isfinite(c)):
            raise CalibrationError(f"match_labeling: {what} must be the board's {n} corners as "
                                   f"finite pixels (n, 2), got {np.shape(c)}")
    ref = np.asarray(reference, float).reshape(-1, 2)
    best, best_res = None, np.inf
    for cand in _labelings(np.asarray(corners, np.float32), pattern):
        A = np.zeros((2 * len(ref), 3))
        A[0::2, 0], A[0::2, 1] = ref[:, 0], 1.0
        A[1::2, 0], A[1::2, 2] = ref[:, 1], 1.0
        b = cand.astype(float).reshape(-1)
        sol, *_ = np.linalg.lstsq(A, b, rcond=None)
        res = float(np.sum((A @ sol - b) ** 2)) if sol[0] > 0 else np.inf
        if res < best_res:
            best, best_res = cand, res
    return best


#: :func:`find_corners` enlarges an image to at most this many pixels on a side (a 4K frame
#: is 3840 wide; the thermal cameras it enlarges are a few hundred)
MAX_UPSCALED_PX = 8192
#: OpenCV's classic chessboard detector (the fallback of :func:`find_corners`) raises on an
#: image smaller than this on a side; such an image holds no board it could find
MIN_CLASSIC_SIDE_PX = 15


def _outlier_views(idx: Sequence[int], errs: NDArray, factor: float) -> list[int]:
    """The views ``idx`` whose reprojection error ``errs`` (px) exceeds ``factor`` times the
    median and 0.5 px -- among 6 or more, and only where at least 3 stay; none otherwise (or
    with ``factor`` 0). One rule for the intrinsics and the stereo pairs."""
    if not factor or len(idx) < 6:
        return []
    thr = max(factor * float(np.median(errs)), 0.5)
    out = [i for i, e in zip(idx, errs, strict=True) if e > thr]
    return out if len(idx) - len(out) >= 3 else []


def find_corners(image: NDArray, pattern: tuple[int, int], *, try_inverted: bool = False,
                 upscale: int | None = None) -> NDArray | None:
    """Inner chessboard corners ``(N, 2)`` float32 in pixels, or None when the board is not
    found.

    Uses ``cv2.findChessboardCornersSB`` (sub-pixel by design) and falls back to the classic
    detector + ``cv2.cornerSubPix``. Small images (thermal cameras) are first enlarged by the
    integer factor ``upscale`` (default: the smallest making them at least 640 px wide), which
    makes the sub-pixel estimate several times more accurate on blurry low-resolution boards.
    ``try_inverted`` also tries the inverted image (thermal images of a heated board). Corners
    are relabelled so that corner 0 is the outer corner nearest the top-left of the image.
    ``upscale`` must be an integer >= 1 (ConfigError): 0 gave infinite corners; one that makes
    the image larger than :data:`MAX_UPSCALED_PX` on a side, a ConfigError too (10**6 was
    OpenCV's out-of-memory error).
    """
    pattern = check_pattern(pattern)
    # ("no" was truthy: the inverted image tried too, without a word)
    try_inverted = true_or_false("try_inverted", try_inverted, error=CalibrationError)
    if upscale is not None:
        upscale = whole_number("upscale", upscale)
    g = to_gray(image)
    if g.dtype != np.uint8:
        g = cv2.normalize(g, None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)
    up = int(upscale) if upscale is not None else max(1, int(np.ceil(640 / g.shape[1])))
    if up * max(g.shape) > MAX_UPSCALED_PX and up > 1:
        raise ConfigError(f"upscale {up} makes the {g.shape[1]}x{g.shape[0]} image larger than "
                          f"{MAX_UPSCALED_PX} px on a side; choose a smaller factor")
    if up > 1:
        g = cv2.resize(g, None, fx=up, fy=up, interpolation=cv2.INTER_CUBIC)
    candidates = [g, 255 - g] if try_inverted else [g]
    for img in candidates:
        ok, c = cv2.findChessboardCornersSB(img, pattern, cv2.CALIB_CB_ACCURACY)
        # (the classic detector's adaptive threshold needs a block of round(0.1 * the smaller
        # side) | 1 > 1 pixels: an image under 15 px on a side, e.g. 640x8, was cv2.error)
        if not ok and min(img.shape[:2]) >= MIN_CLASSIC_SIDE_PX:
            flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
            ok, c = cv2.findChessboardCorners(img, pattern, flags)
            if ok:
                crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 1e-3)
                w = 2 * up + 3
                c = cv2.cornerSubPix(img, c, (w, w), (-1, -1), crit)
        if ok and c is not None and len(c) == pattern[0] * pattern[1]:
            c = c.reshape(-1, 2).astype(np.float64)
            c = (c + 0.5) / up - 0.5  # back to original pixel centres
            return _canonical(c.astype(np.float32), pattern)
    return None


# ---------------------------------------------------------------------------------------------
# Intrinsics
# ---------------------------------------------------------------------------------------------
@dataclass
class CameraCalibration:
    """Result of :func:`calibrate_camera`.

    ``rms_px`` is the overall RMS reprojection error, ``per_view_px`` the RMS error of each view
    (pixels); ``rvecs``/``tvecs`` are the board poses (board -> camera, Rodrigues, metres);
    ``used`` the indices (into the input lists) of the views kept after outlier rejection;
    ``focal_rel_std`` the relative standard deviation of the focal length (the larger of fx,
    fy; 0.01 = +-1 %).
    """

    camera: Camera
    rms_px: float
    per_view_px: NDArray
    rvecs: list[NDArray]
    tvecs: list[NDArray]
    used: list[int]
    rejected: list[int] = field(default_factory=list)
    focal_rel_std: float = float("nan")


def calibrate_camera(image_points: Sequence[NDArray], object_points: NDArray | Sequence[NDArray],
                     image_size: tuple[int, int], *, model: str = "standard",
                     fix_aspect: bool = False, reject_factor: float = 3.0,
                     max_focal_rel_std: float = MAX_FOCAL_REL_STD,
                     name: str = "") -> CameraCalibration:
    """Zhang calibration of one camera (``cv2.calibrateCamera``).

    Parameters
    ----------
    image_points : per view, the corners ``(N, 2)`` in pixels.
    object_points : the board's 3D corners ``(N, 3)`` (same for every view) or one per view.
    image_size : (width, height) pixels.
    model : "radial" (k1 only: low-resolution cameras such as thermal ones), "simple"
        (k1, k2, p1, p2), "standard" (+ k3) or "rational" (+ k4..k6).
    fix_aspect : force fx = fy (True or False).
    reject_factor : views whose RMS error exceeds ``reject_factor`` times the median (and
        0.5 px) are dropped and the calibration rerun once; 0 disables.
    max_focal_rel_std : CalibrationError when the focal length's relative standard deviation
        exceeds this (:data:`MAX_FOCAL_REL_STD`): the views do not determine it (Zhang's
        degenerate case: boards parallel to each other, e.g. all facing the camera). A number
        > 0 (0.03 = +-3 %), or inf for no limit.

    Inputs that are none of these are a CalibrationError naming the argument (``image_points``
    or ``object_points`` of None or text were a builtin TypeError / ValueError; a
    ``max_focal_rel_std`` of NaN, 0 or below refused every calibration as "poorly
    determined").
    """
    if model not in _MODELS:
        raise CalibrationError(f"model must be one of {', '.join(_MODELS)}, got {model!r}")
    # (text such as "no" was truthy: fx = fy forced without a word)
    fix_aspect = true_or_false("fix_aspect", fix_aspect, error=CalibrationError)
    n = _view_count(image_points, "image_points")
    if n < 3:
        raise CalibrationError(
            f"need the board in at least 3 images to calibrate, found it in {n}; add views of "
            "the board at different angles"
        )
    # (a NaN factor rejected no view without a word; complex corners lost their imaginary part)
    finite_number("reject_factor", reject_factor, 0.0, error=CalibrationError)
    _check_max_focal_rel_std(max_focal_rel_std)
    _check_view_shapes(image_points)
    objs = _per_view(object_points, n)
    imgs = [np.asarray(p, np.float32).reshape(-1, 1, 2) for p in image_points]
    _check_corners_in_image(imgs, image_size)
    flags = _MODELS[model] | (cv2.CALIB_FIX_ASPECT_RATIO if fix_aspect else 0)
    idx = list(range(n))

    def run(ix: list[int]) -> tuple:
        K0 = None
        if fix_aspect:
            K0 = np.eye(3)
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-9)
        try:
            return cv2.calibrateCameraExtended(
                [objs[i] for i in ix], [imgs[i] for i in ix], tuple(image_size), K0, None,
                flags=flags, criteria=crit)
        except cv2.error as exc:
            raise CalibrationError(f"OpenCV calibration failed: {exc.msg.strip()}") from None

    out = run(idx)
    rejected = _outlier_views(idx, np.asarray(out[7]).reshape(-1), reject_factor)
    if rejected:
        idx = [i for i in idx if i not in rejected]
        out = run(idx)
    rms, K, dist, rvecs, tvecs, _, _, per_view = out
    rel_std = _focal_rel_std([objs[i] for i in idx], [imgs[i] for i in idx], K, dist, rvecs,
                             tvecs, model, fix_aspect)
    cam = Camera(K=K, dist=np.asarray(dist).reshape(-1), width=int(image_size[0]),
                 height=int(image_size[1]), name=name)
    res = CameraCalibration(cam, float(rms), np.asarray(per_view).reshape(-1),
                            [np.asarray(r).reshape(3) for r in rvecs],
                            [np.asarray(t).reshape(3) for t in tvecs], idx, rejected, rel_std)
    _check_focal(res, max_focal_rel_std)
    return res


def _check_corners_in_image(imgs: list[NDArray], image_size: tuple[int, int]) -> None:
    """CalibrationError when more than 1 % of the corners lie outside a ``image_size`` =
    (width, height) image (by more than a pixel): a size given as (height, width) was accepted
    (17 of 540 corners outside), the camera came back with the wrong size and field of view
    (33 deg instead of 44) while K looked right. Detected corners are always inside; the 1 %
    lets a projected (synthetic) set graze the border."""
    try:
        w, h = (float(v) for v in image_size)
    except (TypeError, ValueError):
        raise CalibrationError(f"image_size must be (width, height) in pixels, got "
                               f"{image_size!r}") from None
    if not (w >= 1 and h >= 1):
        raise CalibrationError(f"image_size must be (width, height) in pixels, got "
                               f"{image_size!r}")
    p = np.concatenate([im.reshape(-1, 2) for im in imgs]) if imgs else np.zeros((0, 2))

    def outside(w_: float, h_: float) -> int:
        return int(np.sum((p[:, 0] < -1.5) | (p[:, 0] > w_ + 0.5)
                          | (p[:, 1] < -1.5) | (p[:, 1] > h_ + 0.5)))

    bad = outside(w, h)
    if bad > 0.01 * len(p):
        hint = (f"; they all fit a {h:g}x{w:g} image: image_size is (width, height)"
                if outside(h, w) == 0 else "")
        raise CalibrationError(f"{bad} of {len(p)} corners lie outside the {w:g}x{h:g} image "
                               f"(image_size = (width, height)){hint}")


def _view_count(points: Any, name: str) -> int:
    """How many views ``points`` (a sequence of each view's corners) holds; CalibrationError
    naming ``name`` for None, a number, text or a 0-d array (len() raised a builtin
    TypeError)."""
    try:
        n = None if isinstance(points, str | bytes) else len(points)
    except TypeError:
        n = None
    if n is None:
        raise CalibrationError(f"{name} must be a list of views, each the board's corners "
                               f"(N, 2) in pixels, got {points!r:.60}")
    return n


def _check_view_shapes(views: Sequence[Any]) -> None:
    """CalibrationError unless every view holds finite real pixel coordinates, in pairs (an
    even count of numbers: numpy's reshape to (N, 1, 2) raised its ValueError)."""
    if not all(real_entries(p) and np.all(np.isfinite(np.asarray(p, float))) for p in views):
        raise CalibrationError("image points must be finite real pixel coordinates")
    if any(np.size(p) % 2 for p in views):
        raise CalibrationError("image points must be (N, 2) pixel coordinates per view, got "
                               f"{[np.shape(p) for p in views if np.size(p) % 2][0]}")


def _check_max_focal_rel_std(value: Any) -> None:
    """CalibrationError unless ``value`` is a real number > 0 or +inf (no limit; what
    :func:`calibrate_rig` passes): NaN refused every calibration, 0 or below even a perfect
    one ("focal length poorly determined (+-0.0 %)")."""
    if isinstance(value, float | np.floating) and value == np.inf:
        return
    if not (is_real(value) and value > 0):
        raise CalibrationError(f"max_focal_rel_std must be a number > 0 (0.03 = +-3 %), or inf "
                               f"for no limit, got {value!r:.60}")


def _check_focal(calib: CameraCalibration, max_rel_std: float) -> None:
    """CalibrationError when the focal length's relative standard deviation exceeds
    ``max_rel_std``: Zhang's degenerate views (boards parallel to each other)."""
    rel = calib.focal_rel_std
    if rel <= max_rel_std:
        return
    label = f"{calib.camera.name} camera" if calib.camera.name else "camera"
    spread = "not at all" if np.isinf(rel) else f"+-{100 * rel:.1f} %"
    raise CalibrationError(
        f"{label}: focal length poorly determined ({spread}, fx {calib.camera.fx:.0f} px, RMS "
        f"{calib.rms_px:.2f} px): the board views are too alike (boards parallel to each "
        "other, e.g. all facing the camera); tilt the board more (30-45 deg, in different "
        "directions) between views"
    )


def _focal_rel_std(objs: list[NDArray], imgs: list[NDArray], K: NDArray, dist: NDArray,
                   rvecs: Sequence[NDArray], tvecs: Sequence[NDArray], model: str,
                   fix_aspect: bool) -> float:
    """Relative standard deviation (1 sigma) of the focal length of a Zhang calibration (the
    larger of fx, fy), ``inf`` when the views do not determine it at all.

    The covariance of the intrinsics is ``sigma^2 S^-1`` with ``S`` the Schur complement of the
    board poses in ``J^T J`` (``J`` from ``cv2.projectPoints``). It equals
    calibrateCameraExtended's ``stdDeviationsIntrinsics`` when the problem is well posed, but
    OpenCV inverts ``J^T J`` with a pseudo-inverse, which drops the null direction of a
    degenerate set and reported +-0.1 % for exactly fronto-parallel boards whose fx was 10x off.
    Here only the focal length's own null direction makes it ``inf``: the other intrinsics may
    have theirs (the rational model's coefficients trade off against each other).
    """
    d = np.asarray(dist, np.float64).reshape(-1)
    free = _FREE_DIST[model]
    n_int = (1 if fix_aspect else 2) + 2 + len(free)
    S = np.zeros((n_int, n_int))
    sq, n_res = 0.0, 0
    for o, im, r, t in zip(objs, imgs, rvecs, tvecs, strict=True):
        p, J = cv2.projectPoints(np.asarray(o, np.float64), np.asarray(r, np.float64),
                                 np.asarray(t, np.float64), K, d)
        e = (p - im).reshape(-1)
        sq += float(e @ e)
        n_res += e.size
        # columns of J: rvec (3), tvec (3), fx, fy, cx, cy, distortion
        Jf = (K[0, 0] / K[1, 1] * J[:, 6] + J[:, 7])[:, None] if fix_aspect else J[:, 6:8]
        Ji = np.hstack([Jf, J[:, 8:10], J[:, 10:][:, free]])
        Je = J[:, :6]
        try:
            S += Ji.T @ Ji - Ji.T @ Je @ np.linalg.solve(Je.T @ Je, Je.T @ Ji)
        except np.linalg.LinAlgError:  # a view whose pose is undetermined
            return float("inf")
    sigma2 = sq / max(n_res - n_int - 6 * len(objs), 1)
    # scale to unit diagonal: fx (~100 px) and k3 (~0.01) differ by orders of magnitude
    diag = np.diag(S)
    if not np.all(diag > 0):
        return float("inf")
    sc = 1.0 / np.sqrt(diag)
    Ss = S * sc[:, None] * sc[None, :]
    # the focal block of S^-1 is the inverse of the focal length's information once the other
    # intrinsics are fitted (the Schur complement of theirs). A pseudo-inverse for those: a
    # combination of them that leaves every projection unchanged (the rational model's k1..k3
    # and k4..k6 trade off: S singular to 1e-16 with fx determined to 0.15 %, measured) says
    # nothing about fx; when fx itself is such a combination, the complement F is singular
    nf = 1 if fix_aspect else 2
    F = Ss[:nf, :nf] - Ss[:nf, nf:] @ np.linalg.pinv(Ss[nf:, nf:], rcond=1e-12,
                                                     hermitian=True) @ Ss[nf:, :nf]
    w, V = np.linalg.eigh(F)
    if not w[0] > 1e-12 * np.linalg.eigvalsh(Ss)[-1]:
        return float("inf")
    var = (V**2 / w).sum(axis=1) * sc[:nf] ** 2 * sigma2
    if fix_aspect:  # one focal parameter, fy (fx = a fy)
        return float(np.sqrt(var[0]) / K[1, 1])
    return float(max(np.sqrt(var[0]) / K[0, 0], np.sqrt(var[1]) / K[1, 1]))


def _per_view(object_points: NDArray | Sequence[NDArray], n: int) -> list[NDArray]:
    """The board's corners ``(N, 1, 3)`` float32 for each of ``n`` views: ``object_points`` is
    one ``(N, 3)`` array for every view or one per view; CalibrationError naming it unless
    they are finite real numbers, 3 per corner (None was a builtin TypeError, text numpy's
    ValueError, a count of numbers not a multiple of 3 its reshape ValueError)."""
    rule = "object_points must be the board's 3D corners (N, 3) in metres (or one such per view)"
    if isinstance(object_points, np.ndarray) and object_points.ndim == 2:
        sets = [object_points]
    elif (object_points.ndim > 0 if isinstance(object_points, np.ndarray)
          else isinstance(object_points, Iterable) and not isinstance(object_points, str | bytes)):
        sets = list(object_points)
    else:
        raise CalibrationError(f"{rule}, got {object_points!r:.60}")
    for o in sets:
        if not real_entries(o):
            raise CalibrationError(f"{rule}, got {o!r:.60}")
        if np.size(o) == 0 or np.size(o) % 3:
            raise CalibrationError(f"{rule}, got an array of shape {np.shape(o)}")
        if not np.all(np.isfinite(np.asarray(o, float))):
            raise CalibrationError("object_points must be finite numbers (metres)")
    if isinstance(object_points, np.ndarray) and object_points.ndim == 2:
        o = np.asarray(object_points, np.float32).reshape(-1, 1, 3)
        return [o] * n
    objs = [np.asarray(o, np.float32).reshape(-1, 1, 3) for o in sets]
    if len(objs) != n:
        raise CalibrationError(f"{len(objs)} object point sets for {n} views")
    return objs


# ---------------------------------------------------------------------------------------------
# Stereo
# ---------------------------------------------------------------------------------------------
@dataclass
class StereoCalibration:
    """Result of :func:`calibrate_stereo`: the rig, the stereo RMS error (pixels, both
    cameras), the per-view RMS errors ``(n_views, 2)`` (left, right) and whether the joint
    refinement of the intrinsics was kept."""

    rig: StereoRig
    rms_px: float
    per_view_px: NDArray
    refined: bool


def calibrate_stereo(left_points: Sequence[NDArray], right_points: Sequence[NDArray],
                     object_points: NDArray | Sequence[NDArray], left: Camera, right: Camera,
                     *, refine: bool = True, model: str | None = None,
                     fix_aspect: bool = False) -> StereoCalibration:
    """Stereo extrinsics (``cv2.stereoCalibrate``) from corners seen in both cameras.

    First R, T with the given intrinsics fixed; then, if ``refine``, a joint refinement of the
    intrinsics and extrinsics started from there, kept only if it lowers the RMS error and
    keeps the focal lengths within 5 % (a guard against over-fitting few views).

    ``model`` and ``fix_aspect`` are those the intrinsics were calibrated with
    (:func:`calibrate_camera`): the refinement keeps that distortion model (coefficients the
    model fixes stay at the given cameras' values, e.g. zero) and, with ``fix_aspect``, each
    camera's ``fx / fy``. ``model=None`` frees the 5 standard coefficients (8 with rational
    cameras, i.e. 8 or more coefficients); the thin-prism and tilt terms of 12- and
    14-coefficient cameras are never estimated and stay as given. Cameras of 8 or more
    coefficients come back with OpenCV's 14 (the terms they did not have are 0), those of fewer
    with 5. A rational camera beside a standard one (``model=None``): k4..k6 are not refined
    (OpenCV's flags hold for both cameras; they stay 0 for the standard camera and as given for
    the rational one).

    Corners are in pixels; returns the rig with ``X_right = R X_left + T`` (metres, as the
    object points).
    """
    if model is not None and model not in _MODELS:
        raise CalibrationError(f"model must be one of {', '.join(_MODELS)}, got {model!r}")
    # (text such as "no" was truthy: each camera's aspect ratio held, or the refinement run)
    fix_aspect = true_or_false("fix_aspect", fix_aspect, error=CalibrationError)
    refine = true_or_false("refine", refine, error=CalibrationError)
    n = _view_count(left_points, "left_points")
    if n != _view_count(right_points, "right_points"):
        raise CalibrationError(f"{n} left views but {len(right_points)} right views")
    for views in (left_points, right_points):  # (as calibrate_camera's image_points)
        _check_view_shapes(views)
    if n < 1:
        raise CalibrationError("need at least one view with the board in both cameras")
    if left.size != right.size:
        raise CalibrationError(f"left and right image sizes differ: {left.size} vs {right.size}")
    for cam in (left, right):
        cam.require_no_skew("stereo calibration")
    objs = _per_view(object_points, n)
    lp = [np.asarray(p, np.float32).reshape(-1, 1, 2) for p in left_points]
    rp = [np.asarray(p, np.float32).reshape(-1, 1, 2) for p in right_points]
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-10)

    def run(K1, d1, K2, d2, flags):
        try:
            return cv2.stereoCalibrateExtended(
                objs, lp, rp, K1.copy(), d1.copy(), K2.copy(), d2.copy(), left.size,
                np.eye(3), np.zeros((3, 1)), flags=flags, criteria=crit)
        except cv2.error as exc:
            raise CalibrationError(f"OpenCV stereo calibration failed: {exc.msg.strip()}") from None

    d1 = _dist5(left.dist)
    d2 = _dist5(right.dist)
    base = _stereo_model_flags(model, (left.dist.size, right.dist.size), fix_aspect)
    out = run(left.K, d1, right.K, d2, cv2.CALIB_FIX_INTRINSIC | base)
    refined = False
    if refine and n >= 3:
        out2 = run(out[1], out[2], out[3], out[4], cv2.CALIB_USE_INTRINSIC_GUESS | base)
        f_ok = all(abs(out2[k][i, i] / out[k][i, i] - 1.0) < 0.05 for k in (1, 3) for i in (0, 1))
        if out2[0] < out[0] and f_ok:
            out, refined = out2, True
    rms, K1, D1, K2, D2, R, T = out[:7]
    if not np.linalg.norm(T) >= MIN_BASELINE_M:
        # identical left and right corners fit perfectly with T ~ 5e-15 (measured)
        raise CalibrationError(
            f"stereo calibration gave a baseline of {np.linalg.norm(T):.2g} m, below "
            f"{MIN_BASELINE_M * 1000:g} mm: the left and right images are the same or taken "
            "from the same place; check the left and right image lists"
        )
    per_view = np.asarray(out[-1]).reshape(n, 2)
    lc = Camera(K=K1, dist=_model_length(D1, left.dist.size), width=left.width,
                height=left.height, name=left.name or "left")
    rc = Camera(K=K2, dist=_model_length(D2, right.dist.size), width=right.width,
                height=right.height, name=right.name or "right")
    rig = StereoRig(lc, rc, R, np.asarray(T).reshape(3), rms_px=float(rms))
    return StereoCalibration(rig, float(rms), per_view, refined)


def _stereo_model_flags(model: str | None, n_coeffs: tuple[int, int], fix_aspect: bool) -> int:
    """``cv2.stereoCalibrate`` flags keeping a distortion model (see :data:`_MODELS`) and, with
    ``fix_aspect``, each camera's aspect ratio. ``model=None``: standard when both cameras have
    fewer than 8 coefficients (``n_coeffs``: the left and right counts), rational when both
    have 8 or more; one of each: rational with k4..k6 fixed -- OpenCV's flags hold for both
    cameras, and the standard model's flags made it return 5 coefficients for both (the
    rational camera's k4..k6 dropped), the rational ones freed k4..k6 of the standard camera."""
    mixed = False
    if model is None:
        rational = [n >= 8 for n in n_coeffs]
        model = "rational" if any(rational) else "standard"
        mixed = any(rational) and not all(rational)
    flags = _MODELS[model] | (cv2.CALIB_FIX_ASPECT_RATIO if fix_aspect else 0)
    if mixed:
        flags |= cv2.CALIB_FIX_K4 | cv2.CALIB_FIX_K5 | cv2.CALIB_FIX_K6
    return flags


def _model_length(d: NDArray, n_given: int) -> NDArray:
    """Refined distortion ``d`` of a camera given with ``n_given`` coefficients: a camera of
    fewer than 8 (no rational terms) keeps its 5 -- OpenCV returns 14 when the other camera's
    rational model set the flags, with this one's extra terms fixed at 0."""
    d = np.asarray(d, float).reshape(-1)
    return d[:5].copy() if n_given < 8 and d.size > 5 and not np.any(d[5:]) else d


def _dist5(d: NDArray) -> NDArray:
    """Distortion as OpenCV wants it back (at least 5 coefficients)."""
    d = np.asarray(d, float).reshape(-1)
    if d.size >= 5:
        return d.reshape(-1, 1).copy()
    out = np.zeros(5)
    out[: d.size] = d
    return out.reshape(-1, 1)


# ---------------------------------------------------------------------------------------------
# Thermal to stereo
# ---------------------------------------------------------------------------------------------
@dataclass
class ThermalExtrinsics:
    """Result of :func:`calibrate_thermal_extrinsics`: thermal-from-left ``R``, ``T`` (metres),
    the RMS reprojection error in the thermal image over all used views (pixels), the per-view
    RMS errors, and the indices of the views used."""

    R: NDArray
    T: NDArray
    rms_px: float
    per_view_px: NDArray
    used: list[int]


def _board_pose(camera: Camera, obj: NDArray, img: NDArray) -> tuple[NDArray, NDArray]:
    # OpenCV's PnP ignores K's skew: solve with the skew removed from K and the pixels
    K0, uv0 = camera._without_skew(np.asarray(img, np.float64).reshape(-1, 2))
    uv0 = uv0.reshape(-1, 1, 2)
    ok, rvec, tvec = cv2.solvePnP(obj.reshape(-1, 1, 3), uv0, K0, camera.dist,
                                  flags=cv2.SOLVEPNP_IPPE)
    if not ok:
        raise CalibrationError("solvePnP failed for a board view")
    rvec, tvec = cv2.solvePnPRefineLM(obj.reshape(-1, 1, 3), uv0, K0, camera.dist, rvec, tvec)
    return cv2.Rodrigues(rvec)[0], tvec.reshape(3)


def calibrate_thermal_extrinsics(rig: StereoRig, thermal: Camera,
                                 left_points: Sequence[NDArray | None],
                                 thermal_points: Sequence[NDArray | None],
                                 object_points: NDArray,
                                 right_points: Sequence[NDArray | None] | None = None,
                                 *, max_rotation_deg: float = 2.0,
                                 max_translation_m: float | None = None) -> ThermalExtrinsics:
    """Extrinsics of a thermal camera relative to the stereo rig's left camera (7.4.1).

    Parameters
    ----------
    rig : calibrated stereo rig (its left camera defines the frame).
    thermal : calibrated thermal camera (intrinsics).
    left_points, thermal_points : per view, the board corners in the left and the thermal
        image (None where the board was not found); labelled consistently (see
        :func:`match_labeling`).
    object_points : the board's corners ``(N, 3)`` in metres.
    right_points : optional right-image corners; when given, the board's 3D corners in the
        left frame are triangulated from both stereo views (the rig's own estimate) instead of
        taken from the left camera's PnP pose alone.
    max_rotation_deg, max_translation_m : views whose transform is farther than this from the
        median are rejected before averaging (translation default: 3x the median deviation,
        at least 5 mm).

    Returns
    -------
    ThermalExtrinsics with ``X_thermal = R X_left + T``. CalibrationError when the median of
    the per-view errors under it exceeds :data:`MAX_RMS_PX`: most views contradict it (mirrored
    thermal images, another board).
    """
    # (a negative or NaN rotation limit silently kept every view)
    finite_number("max_rotation_deg", max_rotation_deg, 0.0, lo_open=True,
                  error=CalibrationError)
    if max_translation_m is not None:
        finite_number("max_translation_m", max_translation_m, 0.0, lo_open=True,
                      error=CalibrationError)
    n = len(left_points)
    if len(thermal_points) != n:
        raise CalibrationError(f"{n} left views but {len(thermal_points)} thermal views")
    if right_points is not None and len(right_points) != n:
        raise CalibrationError(f"{n} left views but {len(right_points)} right views")
    obj = np.asarray(object_points, np.float64).reshape(-1, 3)
    views, Rs, Ts, X_all = [], [], [], []
    for i in range(n):
        lp, tp = left_points[i], thermal_points[i]
        if lp is None or tp is None:
            continue
        rp = right_points[i] if right_points is not None else None
        for side, pts in (("left", lp), ("thermal", tp), ("right", rp)):
            if pts is not None and np.size(pts) != 2 * len(obj):
                raise CalibrationError(
                    f"{side} view {i} has {np.size(pts) // 2} corners but the board "
                    f"{len(obj)}: corners and object points must be of the same board"
                )
            if pts is not None and not np.all(np.ptp(np.asarray(pts, float).reshape(-1, 2),
                                                     axis=0) >= 1.0):
                # (every corner at one pixel gave T ~ [-23, -945, -7905] m, rms NaN)
                raise CalibrationError(
                    f"{side} view {i}: the board's corners do not span a pixel in both "
                    "directions (all at one point, or not finite): no pose can be fitted")
        if rp is not None:
            X = _triangulate(rig, lp, rp)
            if not np.all(np.isfinite(X)):  # (they were triangulated from wrong rays)
                raise CalibrationError(
                    f"view {i}: corners of the left or right image lie beyond the reach of "
                    "that camera's lens model (its distortion folds back before them: "
                    "Camera.normalized gives NaN); recalibrate the rig with a lens model that "
                    "covers the whole image")
        else:
            Rb, tb = _board_pose(rig.left, obj, lp)
            X = obj @ Rb.T + tb
        # pose of the (3D, left-frame) corners in the thermal camera = thermal-from-left
        Rt, tt = _board_pose(thermal, obj, tp)
        Rb, tb = _rigid_fit(obj, X)  # board -> left
        R = Rt @ Rb.T
        T = tt - R @ tb
        views.append(i)
        Rs.append(R)
        Ts.append(T)
        X_all.append(X)
    if len(views) < 1:
        raise CalibrationError(
            "the board was not found in any left/thermal image pair; the thermal camera needs "
            "views of a board it can see (heated or back-lit chessboard)"
        )
    rots = Rotation.from_matrix(np.array(Rs))
    Ts_arr = np.array(Ts)
    # robust average: drop views far from the median, then mean rotation / median translation
    r_med = rots[int(np.argmin([np.sum((rots[k].inv() * rots).magnitude())
                                for k in range(len(rots))]))]
    ang = np.degrees((r_med.inv() * rots).magnitude())
    t_med = np.median(Ts_arr, axis=0)
    dev = np.linalg.norm(Ts_arr - t_med, axis=1)
    t_thr = max_translation_m if max_translation_m is not None else max(3 * np.median(dev), 0.005)
    keep = (ang <= max_rotation_deg) & (dev <= t_thr)
    if keep.sum() == 0:
        keep[:] = True
    R0 = rots[keep].mean().as_matrix()
    T0 = np.median(Ts_arr[keep], axis=0)
    # joint refinement: one PnP over all kept views' corners (3D in the left frame)
    used = [v for v, k in zip(views, keep, strict=True) if k]
    X = np.concatenate([X_all[j] for j in range(len(views)) if keep[j]])
    uv = np.concatenate([np.asarray(thermal_points[v], np.float64).reshape(-1, 2) for v in used])
    K0, uv0 = thermal._without_skew(uv)
    rvec, tvec = cv2.solvePnPRefineLM(X.reshape(-1, 1, 3), uv0.reshape(-1, 1, 2), K0,
                                      thermal.dist, cv2.Rodrigues(R0)[0], T0.reshape(3, 1).copy())
    R = cv2.Rodrigues(rvec)[0]
    T = tvec.reshape(3)
    per_view = []
    for j, v in enumerate(views):
        pred = thermal.project(X_all[j] @ R.T + T)
        e = pred - np.asarray(thermal_points[v], float).reshape(-1, 2)
        per_view.append(float(np.sqrt(np.mean(np.sum(e * e, axis=1)))))
    per_view_arr = np.asarray(per_view)
    rms = float(np.sqrt(np.mean(per_view_arr[keep] ** 2)))
    if not (np.isfinite(rms) and np.all(np.isfinite(T))):
        raise CalibrationError("the thermal extrinsics did not converge (reprojection error "
                               f"{rms}): check that the thermal corners are of the same board "
                               "and labelled like the left ones (match_labeling)")
    med = float(np.median(per_view_arr))
    if not med <= MAX_RMS_PX:
        # (mirrored thermal images: 7 of 8 views "rejected", 29-52 px off, the one kept fit
        # at 0.12 px -- a thermal camera 9.7 cm from its place, saved with exit status 0)
        raise CalibrationError(
            f"thermal extrinsics: the views disagree on where the thermal camera is (median "
            f"error {med:.1f} px under the fitted transform, at most {MAX_RMS_PX:g} px expected; "
            f"{len(used)} of {len(views)} views kept): are the thermal images mirrored, or of "
            "another board than the left ones?")
    return ThermalExtrinsics(R, T, rms, per_view_arr, used)


def _triangulate(rig: StereoRig, lp: NDArray, rp: NDArray) -> NDArray:
    """3D points (N, 3) in the left optical frame (metres) from stereo correspondences
    (pixels); NaN rows for pixels a camera's lens model cannot reach
    (:meth:`Camera.normalized`)."""
    xl = rig.left.normalized(np.asarray(lp, float).reshape(-1, 2))
    xr = rig.right.normalized(np.asarray(rp, float).reshape(-1, 2))
    P1 = np.hstack([np.eye(3), np.zeros((3, 1))])
    P2 = np.hstack([rig.R, rig.T.reshape(3, 1)])
    Xh = cv2.triangulatePoints(P1, P2, xl.T, xr.T)
    return (Xh[:3] / Xh[3]).T


def _rigid_fit(A: NDArray, B: NDArray) -> tuple[NDArray, NDArray]:
    """Least-squares rotation R and translation t with B ~ A R^T + t (Kabsch / Umeyama)."""
    ca, cb = A.mean(axis=0), B.mean(axis=0)
    H = (A - ca).T @ (B - cb)
    U, _, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    return R, cb - R @ ca


# ---------------------------------------------------------------------------------------------
# Synthetic boards (tests, examples, simulation)
# ---------------------------------------------------------------------------------------------
def render_chessboard(camera: Camera, R_board: NDArray, t_board: NDArray,
                      pattern: tuple[int, int], square_m: float, *, margin_squares: float = 1.0,
                      invert: bool = False, blur_px: float = 0.0, noise: float = 0.0,
                      background: float = 0.45, rng: np.random.Generator | int | None = None,
                      rays: NDArray | None = None) -> NDArray:
    """Render an anti-aliased chessboard seen by ``camera`` (uint8 grey image).

    The board (``pattern`` inner corners, squares of ``square_m`` metres, a white margin of
    ``margin_squares``) has its corner grid at :func:`board_points`; ``R_board``, ``t_board``
    map board coordinates to the camera's optical frame (metres). Lens distortion is rendered
    exactly (each pixel's ray is intersected with the board plane); each pixel is the average
    over a 4x4 grid of sub-pixel rays. ``invert`` swaps black and white (a heated board in a
    thermal camera); ``blur_px`` is a Gaussian blur sigma in pixels, from 0 (none) to
    :data:`MAX_BLUR_SHARE` of the image's larger side; ``noise`` an additive Gaussian noise
    sigma in grey levels (0-255 scale), >= 0, drawn from ``rng`` (a Generator, an integer seed,
    or None for the seed 0); ``background`` the grey level around the board as a fraction of
    white, in [0, 1] (the board's squares are 0.08 and 0.92). ``rays`` can pass precomputed
    sub-pixel rays for speed.

    The board -- ``pattern`` (:func:`check_pattern`), ``square_m`` (finite > 0), ``R_board``
    (a finite 3x3 rotation) and ``t_board`` (3 finite numbers: shape (3,), (3, 1) or (1, 3))
    -- and ``camera`` (a :class:`Camera`) are a CalibrationError otherwise, as in
    :func:`board_points`; the drawing settings ``margin_squares`` (finite >= 0, in squares),
    ``blur_px``, ``noise``, ``background``, ``invert`` (True or False) and (when ``noise`` >
    0) ``rng`` a ConfigError.
    Unchecked, a square of 0 or NaN drew garbage, a negative one a mirrored board, a NaN noise
    no noise, and a blur of 1e6 px allocated 20 GB.
    """
    if not isinstance(camera, Camera):  # (None was a builtin AttributeError)
        raise CalibrationError(f"render_chessboard needs a Camera, got {type(camera).__name__}")
    nx, ny = check_pattern(pattern)
    finite_number("square_m", square_m, 0.0, lo_open=True, error=CalibrationError)
    R_board = as_float_array(R_board, "R_board", (3, 3), error=CalibrationError)
    R_board = _check_rotation(R_board, "R_board")  # (the rig's rule: R R^T = I, det > 0)
    t_board = as_float_array(t_board, "t_board", error=CalibrationError)
    if t_board.shape not in ((3,), (3, 1), (1, 3)):
        raise CalibrationError(f"t_board: expected 3 numbers (metres) of shape (3,), (3, 1) or "
                               f"(1, 3), got shape {t_board.shape}")
    t_board = t_board.reshape(3)
    finite_number("margin_squares", margin_squares, 0.0)
    finite_number("blur_px", blur_px, 0.0, MAX_BLUR_SHARE * max(camera.width, camera.height))
    finite_number("noise", noise, 0.0)
    finite_number("background", background, 0.0, 1.0)
    invert = true_or_false("invert", invert)  # ("no" inverted the board)
    if rays is None:
        rays = _subpixel_rays(camera)
    # ray p = s * r meets the board plane n . (p - t) = 0 with n = R e_z
    n = R_board[:, 2]
    denom = rays @ n
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (n @ t_board) / denom
        P = s[..., None] * rays - t_board
    local = P @ R_board  # board coordinates (x, y, ~0)
    bx = local[..., 0] / square_m + 1.0  # squares; inner corner (0,0) is at square index 1
    by = local[..., 1] / square_m + 1.0
    inside = ((bx >= -margin_squares) & (bx <= nx + 1 + margin_squares)
              & (by >= -margin_squares) & (by <= ny + 1 + margin_squares) & (s > 0))
    on_squares = (bx >= 0) & (bx < nx + 1) & (by >= 0) & (by < ny + 1)
    black = ((np.floor(bx) + np.floor(by)) % 2 == 0) & on_squares
    val = np.where(black, 0.08, 0.92)
    if invert:
        val = 1.0 - val
    val = np.where(inside, val, background)
    img = val.reshape(camera.height, camera.width, -1).mean(axis=2)
    if blur_px > 0:
        img = cv2.GaussianBlur(img, (0, 0), blur_px)
    if noise > 0:  # (an integer seed was numpy's AttributeError: int has no 'normal')
        rng = np.random.default_rng(0) if rng is None else as_rng(rng)
        img = img + rng.normal(0.0, noise / 255.0, img.shape)
    return np.clip(np.rint(img * 255.0), 0, 255).astype(np.uint8)


def _subpixel_rays(camera: Camera, k: int = 4) -> NDArray:
    """Unit rays (H, W, k*k, 3) (optical frame) through a k x k grid inside every pixel; NaN
    where no direction of the lens field reaches the sub-pixel (a distortion that folds back
    before the image corners: :meth:`Camera.pixel_rays`), which :func:`render_chessboard`
    draws as background."""
    off = (np.arange(k) + 0.5) / k - 0.5
    ou, ov = np.meshgrid(off, off)
    u, v = np.meshgrid(np.arange(camera.width, dtype=float), np.arange(camera.height, dtype=float))
    U = (u[..., None] + ou.ravel()).ravel()
    V = (v[..., None] + ov.ravel()).ravel()
    rays = camera.pixel_rays(np.c_[U, V], unreachable="nan")
    return rays.reshape(camera.height, camera.width, k * k, 3)


# ---------------------------------------------------------------------------------------------
# From image files to a calibrated rig (behind `hearsee calibrate`)
# ---------------------------------------------------------------------------------------------
@dataclass
class ViewReport:
    """One image pair (or triplet) of a rig calibration: whether the board was found in each
    image and the RMS reprojection errors (pixels; NaN where not used).

    ``rejected``: an outlier of the left or right intrinsics or of the stereo extrinsics,
    left out of the stereo and thermal extrinsics. ``rejected_thermal``: left out of the
    thermal calibration by its own outlier tests (an outlier of the thermal intrinsics, which
    has no ``err_thermal``, or of the thermal extrinsics' robust averaging, whose
    ``err_thermal`` is its error under the final extrinsics)."""

    left: str
    right: str
    thermal: str | None = None
    found_left: bool = False
    found_right: bool = False
    found_thermal: bool = False
    err_left: float = float("nan")
    err_right: float = float("nan")
    err_stereo_left: float = float("nan")
    err_stereo_right: float = float("nan")
    err_thermal: float = float("nan")
    rejected: bool = False
    rejected_thermal: bool = False


@dataclass
class RigCalibration:
    """Result of :func:`calibrate_rig`: the rig (with thermal camera when given), the RMS
    errors in pixels (intrinsics of each camera, stereo, thermal intrinsics and extrinsics),
    one :class:`ViewReport` per image pair, and warnings for the user."""

    rig: StereoRig
    rms_left_px: float
    rms_right_px: float
    rms_stereo_px: float
    views: list[ViewReport]
    rms_thermal_px: float | None = None
    rms_thermal_extrinsics_px: float | None = None
    warnings: list[str] = field(default_factory=list)


def _check_fit(pattern: tuple[int, int], **rms_px: float) -> None:
    """CalibrationError when an RMS reprojection error (pixels, by name) exceeds
    :data:`MAX_RMS_PX`: the detected corners do not fit one flat board of ``pattern``."""
    bad = {k: v for k, v in rms_px.items() if not v <= MAX_RMS_PX}
    if bad:
        errs = ", ".join(f"{k} {v:.2f} px" for k, v in bad.items())
        raise CalibrationError(
            f"calibration failed: RMS reprojection error {errs} (at most {MAX_RMS_PX:g} px "
            f"expected; good ones are below 0.5 px): the corners do not fit one flat board of "
            f"{pattern[0]}x{pattern[1]} inner corners; check --board (the whole board's inner "
            "corners per row x per column, e.g. 9x6 for 10x7 squares) and that the board is flat"
        )


def calibrate_rig(left_files: Sequence, right_files: Sequence, pattern: tuple[int, int],
                  square_m: float, *, thermal_files: Sequence | None = None,
                  model: str = "standard", thermal_model: str = "radial",
                  fix_aspect: bool = False, progress=None) -> RigCalibration:
    """Calibrate a stereo rig (and optionally a thermal camera) from chessboard image files.

    ``left_files[i]``, ``right_files[i]`` (and ``thermal_files[i]``) are simultaneous views,
    paired by position. Intrinsics of each camera use every image where the board was found,
    the stereo extrinsics the pairs found in both, the thermal extrinsics the views found in
    the left and thermal images (board triangulated by the rig when also found on the right);
    views an intrinsic calibration rejects as outliers are left out of the extrinsics that
    involve that camera, and so are pairs the stereo fit rejects (of 6 or more: an error
    above 3x the median and 0.5 px; see :class:`ViewReport`).
    ``progress`` is an optional callable called once per image read.

    Raises CalibrationError (mismatched counts, board never found, too few views) and
    ImageInputError / InputFileError (unreadable or differently sized images).
    """
    from hearsee.errors import ImageInputError
    from hearsee.vision.io import read_image, read_thermal

    # (checked before the images are read: "no" was truthy and forced fx = fy)
    fix_aspect = true_or_false("fix_aspect", fix_aspect, error=CalibrationError)
    for what, files in (("left_files", left_files), ("right_files", right_files),
                        ("thermal_files", thermal_files)):
        # (a glob pattern was taken as a list of its characters: "12 left images but 13
        # right images", or "c: image file not found"; None was a builtin TypeError)
        if files is None and what == "thermal_files":  # (optional)
            continue
        if isinstance(files, str | bytes) or not isinstance(files, Sequence | np.ndarray):
            raise CalibrationError(
                f"{what} must be a list of image paths, got {files!r:.60} (for a glob pattern "
                "use hearsee.vision.io.glob_images)")
    n = len(left_files)
    if n != len(right_files):
        raise CalibrationError(
            f"{n} left images but {len(right_files)} right images; they are paired in order "
            "(the CLI's patterns: natural order), so both must name the same number of files"
        )
    if thermal_files is not None and len(thermal_files) != n:
        raise CalibrationError(
            f"{len(thermal_files)} thermal images for {n} stereo pairs; give one thermal image "
            "per pair (in the same order)"
        )
    if n == 0:
        raise CalibrationError("no images given")
    obj = board_points(pattern, square_m)
    views: list[ViewReport] = []
    lp: list[NDArray | None] = []
    rp: list[NDArray | None] = []
    tp: list[NDArray | None] = []
    sizes: dict[str, tuple[int, int]] = {}

    def load(path, key: str) -> NDArray:
        # (a thermal image at its depth: find_corners stretches its range to 8 bits -- read
        # as grey, 16-bit radiometric counts kept their top 8 bits: a board 10 K warmer than
        # its squares was 3 grey levels and found in no image)
        img = read_thermal(path) if key == "thermal" else read_image(path, "gray")
        size = (img.shape[1], img.shape[0])
        ref = sizes.setdefault(key, size)
        if size != ref:
            raise ImageInputError(
                f"{path}: image is {size[0]}x{size[1]} but the other {key} images are "
                f"{ref[0]}x{ref[1]}; all images of one camera must have the same size"
            )
        if progress is not None:
            progress()
        return img

    for i in range(n):
        v = ViewReport(str(left_files[i]), str(right_files[i]),
                       None if thermal_files is None else str(thermal_files[i]))
        a = find_corners(load(left_files[i], "left"), pattern)
        b = find_corners(load(right_files[i], "right"), pattern)
        if a is not None and b is not None:
            b = match_labeling(a, b, pattern)
        t = None
        if thermal_files is not None:
            t = find_corners(load(thermal_files[i], "thermal"), pattern, try_inverted=True)
            if t is not None and a is not None:
                t = match_labeling(a, t, pattern)
            elif t is not None and b is not None:
                t = match_labeling(b, t, pattern)
        v.found_left, v.found_right, v.found_thermal = a is not None, b is not None, t is not None
        views.append(v)
        lp.append(a)
        rp.append(b)
        tp.append(t)
    if sizes["left"] != sizes["right"]:
        raise ImageInputError(
            f"left images are {sizes['left'][0]}x{sizes['left'][1]} but right images are "
            f"{sizes['right'][0]}x{sizes['right'][1]}; a stereo rig needs equal sizes"
        )
    warnings: list[str] = []
    n_l = sum(x is not None for x in lp)
    n_r = sum(x is not None for x in rp)
    if n_l == 0 and n_r == 0:
        raise CalibrationError(
            f"the {pattern[0]}x{pattern[1]} chessboard was not found in any image; check --board "
            "(inner corners per row x per column, e.g. 9x6 for a board of 10x7 squares)"
        )
    for side, k in (("left", n_l), ("right", n_r)):
        if k < 3:
            raise CalibrationError(
                f"the board was found in only {k} {side} image(s); at least 3 are needed"
            )
    idx_l = [i for i in range(n) if lp[i] is not None]
    idx_r = [i for i in range(n) if rp[i] is not None]
    # corners that do not fit one board (wrong --board) also leave fx undetermined: the RMS
    # check first, its message names the likely cause
    cl = calibrate_camera([lp[i] for i in idx_l], obj, sizes["left"], model=model,
                          fix_aspect=fix_aspect, max_focal_rel_std=np.inf, name="left")
    cr = calibrate_camera([rp[i] for i in idx_r], obj, sizes["right"], model=model,
                          fix_aspect=fix_aspect, max_focal_rel_std=np.inf, name="right")
    _check_fit(pattern, left=cl.rms_px, right=cr.rms_px)
    for calib in (cl, cr):
        _check_focal(calib, MAX_FOCAL_REL_STD)
    for idx, res, attr in ((idx_l, cl, "err_left"), (idx_r, cr, "err_right")):
        for j, e in zip(res.used, res.per_view_px, strict=True):
            setattr(views[idx[j]], attr, float(e))
        for j in res.rejected:
            views[idx[j]].rejected = True
    rejected = {i for i, v in enumerate(views) if v.rejected}
    both = [i for i in range(n) if lp[i] is not None and rp[i] is not None and i not in rejected]
    if len(both) < 1:
        raise CalibrationError("the board was never found in both images of a pair")
    st = calibrate_stereo([lp[i] for i in both], [rp[i] for i in both], obj, cl.camera,
                          cr.camera, refine=len(both) >= 3, model=model, fix_aspect=fix_aspect)
    # outlier pairs, as the intrinsics' (reject_factor 3): a pair of two moments (a dropped
    # frame) fits each camera but not the rig; kept, one among 8 moved T by 7 mm at 1.9 px RMS
    out = _outlier_views(both, np.max(st.per_view_px, axis=1), 3.0)
    if out:
        for i in out:
            views[i].rejected = True
        rejected.update(out)
        both = [i for i in both if i not in out]
        st = calibrate_stereo([lp[i] for i in both], [rp[i] for i in both], obj, cl.camera,
                              cr.camera, refine=True, model=model, fix_aspect=fix_aspect)
    if not st.rms_px <= MAX_RMS_PX:
        # (the board fits each camera (checked above): _check_fit's "check --board" was the
        # wrong lead when the real pairs after a missing right image were shifted, 15 px)
        j = int(np.argmax(np.max(st.per_view_px, axis=1)))
        raise CalibrationError(
            f"calibration failed: RMS stereo reprojection error {st.rms_px:.2f} px (at most "
            f"{MAX_RMS_PX:g} px expected) although the board fits each camera (left "
            f"{cl.rms_px:.2f} px, right {cr.rms_px:.2f} px): the left and right images are not "
            f"all pairs of one moment; the worst pair, {views[both[j]].left} and "
            f"{views[both[j]].right}, is {np.max(st.per_view_px[j]):.1f} px off. Check that "
            "the images are paired in order (a missing image shifts every pair after it)")
    for j, i in enumerate(both):
        views[i].err_stereo_left, views[i].err_stereo_right = map(float, st.per_view_px[j])
    rig = st.rig
    if rig.rectify().baseline_m < 0:
        warnings.append(
            "the 'right' camera is to the LEFT of the 'left' camera (T_x > 0): swap --left and "
            "--right, otherwise stereo matching will refuse this rig"
        )
    if n_l < 8 or n_r < 8:
        warnings.append(f"only {min(n_l, n_r)} usable views; 10-20 at varied angles are better")
    rms_t = rms_te = None
    if thermal_files is not None:
        idx_t = [i for i in range(n) if tp[i] is not None]
        if len(idx_t) < 3:
            raise CalibrationError(
                f"the board was found in only {len(idx_t)} thermal image(s); at least 3 are "
                "needed (use a heated or back-lit board the thermal camera can see)"
            )
        th = [tp[i] for i in idx_t]
        ct = calibrate_camera(th, obj, sizes["thermal"], model=thermal_model,
                              fix_aspect=fix_aspect, name="thermal")
        # the extrinsics use only the views kept by the stereo and the thermal calibrations: a
        # thermal view whose corners fit no board pose of the thermal camera (an outlier of its
        # intrinsics) can still pass the extrinsics' own test (per-view poses near the median)
        # and pull the thermal camera's position by millimetres
        dropped_t = {idx_t[j] for j in ct.rejected}
        kept = [i not in rejected and i not in dropped_t for i in range(n)]
        te = calibrate_thermal_extrinsics(
            rig, ct.camera, [lp[i] if kept[i] else None for i in range(n)], tp, obj,
            right_points=[rp[i] if kept[i] else None for i in range(n)])
        used_views = [i for i in range(n) if lp[i] is not None and tp[i] is not None and kept[i]]
        for j, i in enumerate(used_views):
            views[i].err_thermal = float(te.per_view_px[j])
        for i in idx_t:  # (a view without left corners never entered the extrinsics)
            views[i].rejected_thermal = i in dropped_t or (i in used_views and i not in te.used)
        rig = rig.with_thermal(ct.camera, te.R, te.T)
        rms_t, rms_te = ct.rms_px, te.rms_px
    info = {"board": f"{pattern[0]}x{pattern[1]}", "square_m": float(square_m),
            "n_views_left": n_l, "n_views_right": n_r, "n_views_stereo": len(both),
            "model": model, "rms_left_px": cl.rms_px, "rms_right_px": cr.rms_px}
    if rms_t is not None:
        info.update(rms_thermal_px=rms_t, rms_thermal_extrinsics_px=rms_te)
    rig = StereoRig(rig.left, rig.right, rig.R, rig.T, rig.thermal, rig.R_thermal,
                    rig.T_thermal, st.rms_px, info)
    return RigCalibration(rig, cl.rms_px, cr.rms_px, st.rms_px, views, rms_t, rms_te, warnings)
