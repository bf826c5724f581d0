"""Stereo vision (thesis 7.1.2): rectification, disparity, depth and 3D points.

Reconstruction. The thesis's stereo geometry (figs. 7.2-7.4) is the standard rectified pinhole
pair: a point at depth ``Z`` appears in the left and right rectified images on the same row with
horizontal disparity ``d = u_left - u_right = f B / Z`` (``f`` focal length in pixels, ``B``
baseline in metres). Disparity is computed with OpenCV's semi-global block matching
(Hirschmueller, "Stereo processing by semiglobal matching and mutual information", PAMI 2008;
``cv2.StereoSGBM``) tuned as follows:

* 3-way SGBM (``MODE_SGBM_3WAY``; fast, single core), 3x3 blocks, ``P1 = 8 b^2``,
  ``P2 = 32 b^2`` on grey images, pre-filter cap 15 (a stronger clamp of the Sobel
  pre-filter than OpenCV's usual 63: less sensitive to strong edges and exposure
  differences), uniqueness 10 %, speckle filtering (100 px, 2 px);
* the images are padded on the left by ``num_disparities`` columns so that the leftmost
  columns (which plain SGBM leaves invalid) get disparities too;
* a left-right consistency check (``disp12MaxDiff``, or a full right-to-left match checked in
  numpy with ``lr_check="full"``);
* an optional sub-pixel refinement (``subpixel="refine"``, :func:`refine_subpixel`): SGBM's
  parabola over its Birchfield-Tomasi costs is pixel-locked -- its estimates pile up at whole
  pixels and err by -0.13 to +0.20 px with the true fraction, on real Middlebury pairs as on
  the renders -- so one Lucas-Kanade step on the images themselves moves each measured pixel
  toward the minimum of a zero-mean SSD (Lucas & Kanade 1981; on pixel locking Shimizu &
  Okutomi, "Sub-pixel estimation error cancellation on area-based matching", IJCV 2005).
  Opt-in: judged 2026-12-03 under two rules written before their runs
  (``bench/results/HISTORY.md``), it lowered the rendered people's median disparity error
  60 %, the detector's median 3D error on fresh scenes 1.07 -> 0.68 % of range (beyond 4 m
  about half) and the robot's 3D error p90 and velocity error on fresh scenarios; but the
  first rule's robot median did not improve (95 % CI -0.11 to +0.06 cm) and, adopted under
  the second, bench/robot's median 3D error p95 read 3.39 cm against its 3.28 cm limit, so
  the default stays SGBM's own;
* optional hole filling: each invalid pixel takes the smaller (farther) of the nearest valid
  disparities to its left and right on the same row -- occlusions belong to the background
  (Scharstein & Szeliski 2002, sec. 5.3; Hirschmueller 2008, sec. 3.5) -- then a 5x5 median on
  the filled pixels only.

Conventions: disparities are float32 pixels of the rectified left image, NaN where invalid;
depths are metres along the rectified left camera's optical axis; 3D points are ``(H, W, 3)``
metres in the rectified left optical frame (x right, y down, z forward). For a rig that needs
rectification that frame is rotated by ``rectification.R1`` from the left camera's frame:
:func:`points_to_left_frame` undoes it.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field
from typing import Literal

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from hearsee.config import finite_number, is_real, real_entries, true_or_false, whole_number
from hearsee.errors import CalibrationError, ConfigError, ImageInputError
from hearsee.geometry import as_points
from hearsee.vision.camera import Rectification, StereoRig, check_rig
from hearsee.vision.io import check_pair, numeric_map, to_gray

__all__ = [
    "StereoFrame",
    "check_focal_baseline",
    "compute_disparity",
    "depth_from_disparity",
    "disparity_from_depth",
    "fill_disparity_holes",
    "lr_consistency",
    "points_from_disparity",
    "points_to_left_frame",
    "rectification_maps",
    "rectify_pair",
    "refine_subpixel",
    "search_range_px",
    "stereo_frame",
]

_MODES = {
    "sgbm": cv2.STEREO_SGBM_MODE_SGBM,
    "sgbm3way": cv2.STEREO_SGBM_MODE_SGBM_3WAY,
    "hh": cv2.STEREO_SGBM_MODE_HH,
    "hh4": cv2.STEREO_SGBM_MODE_HH4,
}

_MAPS_CACHE: dict[tuple[int, float, tuple[int, int]], tuple] = {}


# ---------------------------------------------------------------------------------------------
# Rectification
# ---------------------------------------------------------------------------------------------
def rectification_maps(rig: StereoRig, alpha: float = 0.0) -> tuple[Rectification, tuple]:
    """The rectification of ``rig`` and its remap tables ``(map1x, map1y, map2x, map2y)``
    (``cv2.initUndistortRectifyMap``, fixed-point maps), cached per rig.

    ``alpha`` in [0, 1] (:meth:`StereoRig.rectify`: 0 keeps only valid pixels, 1 keeps all
    source pixels); anything else is a ConfigError, checked before the cache key is built
    (None or text were a builtin TypeError / ValueError of ``float(alpha)``)."""
    check_rig(rig, "stereo rectification")
    alpha = finite_number("alpha", alpha, 0.0, 1.0)
    key = (id(rig), alpha, rig.left.size)
    hit = _MAPS_CACHE.get(key)
    if hit is not None and hit[0] is rig:
        return hit[1], hit[2]
    rect = rig.rectification if alpha == 0.0 else rig.rectify(alpha=alpha)
    m1 = cv2.initUndistortRectifyMap(rig.left.K, rig.left.dist, rect.R1, rect.P1, rect.size,
                                     cv2.CV_16SC2)
    m2 = cv2.initUndistortRectifyMap(rig.right.K, rig.right.dist, rect.R2, rect.P2, rect.size,
                                     cv2.CV_16SC2)
    maps = (m1[0], m1[1], m2[0], m2[1])
    if len(_MAPS_CACHE) > 8:
        _MAPS_CACHE.clear()
    _MAPS_CACHE[key] = (rig, rect, maps)
    return rect, maps


#: The interpolation methods ``cv2.remap`` supports (:func:`rectify_pair`).
_REMAP_METHODS = (cv2.INTER_NEAREST, cv2.INTER_LINEAR, cv2.INTER_CUBIC, cv2.INTER_LANCZOS4)


def rectify_pair(left: NDArray, right: NDArray, rig: StereoRig, alpha: float = 0.0,
                 interpolation: int = cv2.INTER_LINEAR) -> tuple[NDArray, NDArray, Rectification]:
    """Rectify a stereo pair with ``rig``: returns (left_rect, right_rect, rectification).

    Images must have the rig's size (``ImageInputError`` otherwise). For an already rectified
    rig (:attr:`StereoRig.is_rectified`) the images are returned unchanged. ``alpha`` in
    [0, 1] as in :func:`rectification_maps` (ConfigError otherwise). ``interpolation`` is one
    of ``cv2.remap``'s methods: ``cv2.INTER_NEAREST``, ``INTER_LINEAR``, ``INTER_CUBIC`` or
    ``INTER_LANCZOS4`` (ConfigError otherwise, for any rig: 99 or "linear" raised cv2.error,
    INTER_AREA -- which remap does not support -- gave INTER_LINEAR's images without a word,
    and a rectified rig took anything).
    """
    if (not isinstance(interpolation, int | np.integer) or isinstance(interpolation, bool)
            or interpolation not in _REMAP_METHODS):
        raise ConfigError(f"interpolation must be one of cv2.remap's methods cv2.INTER_NEAREST, "
                          f"INTER_LINEAR, INTER_CUBIC or INTER_LANCZOS4 "
                          f"({', '.join(map(str, _REMAP_METHODS))}), got {interpolation!r:.40}")
    check_pair(left, right, expected_size=check_rig(rig, "rectify_pair").left.size)
    rect, maps = rectification_maps(rig, alpha)
    if rect.baseline_m <= 0:
        raise CalibrationError(
            "the 'right' camera of this rig is to the LEFT of the 'left' camera (T_x > 0): "
            "swap the left and right images (and recalibrate with --left/--right swapped)"
        )
    if rig.is_rectified and alpha == 0.0:
        return left, right, rect
    lr = cv2.remap(left, maps[0], maps[1], interpolation)
    rr = cv2.remap(right, maps[2], maps[3], interpolation)
    return lr, rr, rect


# ---------------------------------------------------------------------------------------------
# Disparity
# ---------------------------------------------------------------------------------------------
def _sgbm(left: NDArray, right: NDArray, *, min_disparity: int, num_disparities: int,
          block_size: int, p1: int, p2: int, lr_max_diff: int, pre_filter_cap: int,
          uniqueness_ratio: int, speckle_window: int, speckle_range: int, mode: int,
          pad_left: bool) -> NDArray:
    pad = num_disparities + max(min_disparity, 0) if pad_left else 0
    if pad:
        left = cv2.copyMakeBorder(left, 0, 0, pad, 0, cv2.BORDER_REPLICATE)
        right = cv2.copyMakeBorder(right, 0, 0, pad, 0, cv2.BORDER_REPLICATE)
    m = cv2.StereoSGBM_create(
        minDisparity=min_disparity, numDisparities=num_disparities, blockSize=block_size,
        P1=p1, P2=p2, disp12MaxDiff=lr_max_diff, preFilterCap=pre_filter_cap,
        uniquenessRatio=uniqueness_ratio, speckleWindowSize=speckle_window,
        speckleRange=speckle_range, mode=mode,
    )
    raw = m.compute(left, right)
    if pad:
        raw = raw[:, pad:]
    d = raw.astype(np.float32) * (1.0 / 16.0)
    d[raw < (min_disparity * 16)] = np.nan  # OpenCV marks invalid as (minDisparity - 1) * 16
    return d


#: The largest disparity (pixels) SGBM can report: its output is int16 with 4 fractional bits,
#: so ``min_disparity + num_disparities`` may not exceed it (a larger search wrapped to negative
#: values, i.e. no disparity at all, or asked for terabytes of buffer).
_MAX_DISPARITY = 2048
#: SGBM keeps its path costs in 16 bits: the penalties P1 < P2 must fit.
_MAX_PENALTY = 32767
#: The largest matching block (OpenCV's limit of its block matcher StereoBM).
_MAX_BLOCK = 255
_INT_MAX = 2**31 - 1


def _penalties(p1: object, p2: object, b2: int) -> tuple[int, int]:
    """The smoothness penalties ``(P1, P2)`` (defaults ``8 b^2`` and ``32 b^2``), ConfigError
    unless they are integers with ``1 <= P1 < P2 <= 32767``: OpenCV replaced a P1 <= 0 by 2, a
    P2 <= P1 by P1 + 1 and cast both to 16 bits (a default P2 above 32767, blocks of 33 pixels
    or more, wrapped to a negative penalty and no disparity at all)."""
    vals = []
    for name, v, k in (("p1", p1, 8), ("p2", p2, 32)):
        if v is None:
            v = k * b2
            if v > _MAX_PENALTY:
                raise ConfigError(
                    f"{name} (default {k} * block_size**2 = {v}) must be at most {_MAX_PENALTY}, "
                    "the largest of SGBM's 16-bit costs: use a smaller block_size")
        vals.append(whole_number(name, v, 1, _MAX_PENALTY))
    if vals[1] <= vals[0]:
        raise ConfigError(f"p2 must be greater than p1 (SGBM needs P2 > P1), got p1={vals[0]}, "
                          f"p2={vals[1]}")
    return vals[0], vals[1]


def _check_search(num_disparities: float, min_disparity: float, scale: float) -> None:
    """ConfigError unless the search options of :func:`compute_disparity` are numbers in
    range: ``num_disparities`` >= 1, ``min_disparity`` >= 0 (pixels), ``scale`` in (0, 1]."""
    # (checked, not converted, as lr_max_diff: a numpy scalar stays what it was, and so do
    # the sizes computed from it; a string was a builtin TypeError)
    finite_number("scale", scale, 0.0, 1.0, lo_open=True)
    for name, v in (("num_disparities", num_disparities), ("min_disparity", min_disparity)):
        if not is_real(v):  # NaN and inf reached int(np.ceil(.)), strings the comparisons
            raise ConfigError(f"{name} must be a finite number of pixels, got {v!r}")
    if num_disparities < 1 or min_disparity < 0:
        raise ConfigError(
            f"num_disparities must be >= 1 and min_disparity >= 0, got {num_disparities}, "
            f"{min_disparity}"
        )


def _matching_search(width: int, num_disparities: float, min_disparity: float,
                     scale: float) -> tuple[int, float, int, int]:
    """The matching resolution of :func:`compute_disparity` (``Wm`` columns, ``sx = Wm /
    width``) and its search at that resolution: ``md`` the smallest disparity, ``nd`` how
    many (``num_disparities`` rounded up to a multiple of 16), in matching pixels. A search
    beyond SGBM's largest disparity is a ConfigError."""
    Wm = max(8, round(width * scale)) if scale < 1.0 else width
    sx = Wm / width if scale < 1.0 else 1.0
    nd = int(np.ceil(num_disparities * sx / 16.0) * 16)
    md = int(np.floor(min_disparity * sx))
    if md + nd > _MAX_DISPARITY:  # (10**6 ended in cv2.error: out of memory)
        raise ConfigError(
            f"min_disparity + num_disparities must be at most {_MAX_DISPARITY} pixels at the "
            f"matching resolution (OpenCV's disparities are 16-bit with 4 fractional bits; "
            f"num_disparities is rounded up to a multiple of 16), got {md} + {nd}")
    return Wm, sx, md, nd


def search_range_px(width: int, num_disparities: float = 64, min_disparity: float = 0,
                    scale: float = 1.0) -> tuple[float, float]:
    """The smallest and the largest disparity (pixels of the full-resolution image) that
    :func:`compute_disparity` searches in rectified images ``width`` pixels wide with these
    options (its defaults here too). ``num_disparities`` is rounded up to a multiple of 16 at
    the matching resolution, so the search may reach a little beyond what was asked for.
    A surface nearer than ``f B / largest`` metres is outside the search: SGBM gives it no
    disparity or a wrong one, at most the largest (:func:`hearsee.vision.humans.
    detect_candidates` flags people standing there). ConfigError for options that
    :func:`compute_disparity` refuses (a search beyond SGBM's largest disparity included) or
    a width that is not a whole number >= 1.

    >>> search_range_px(640)
    (0.0, 63.0)
    >>> search_range_px(640, num_disparities=64, scale=0.5)  # 32 matching pixels, doubled
    (0.0, 62.0)
    """
    width = whole_number("width", width, 1)
    _check_search(num_disparities, min_disparity, scale)
    _, sx, md, nd = _matching_search(width, num_disparities, min_disparity, scale)
    return md / sx, (md + nd - 1) / sx


def compute_disparity(
    left: NDArray,
    right: NDArray,
    *,
    num_disparities: int = 64,
    min_disparity: int = 0,
    block_size: int = 3,
    mode: Literal["sgbm", "sgbm3way", "hh", "hh4"] = "sgbm3way",
    p1: int | None = None,
    p2: int | None = None,
    uniqueness_ratio: int = 10,
    speckle_window: int = 100,
    speckle_range: int = 2,
    pre_filter_cap: int = 15,
    lr_check: Literal["internal", "full", "none"] = "internal",
    lr_max_diff: float = 1.0,
    pad_left: bool = True,
    fill_holes: bool = False,
    scale: float = 1.0,
    subpixel: Literal["sgbm", "refine"] = "sgbm",
) -> NDArray:
    """Disparity of a rectified pair with tuned semi-global matching.

    Parameters
    ----------
    left, right : (H, W) or (H, W, 3) uint8 rectified images (colour is converted to grey).
    num_disparities : disparity search range in pixels (rounded up to a multiple of 16;
        ``min_disparity + num_disparities`` at most 2048, the largest disparity SGBM reports).
    min_disparity : smallest disparity searched, pixels (>= 0).
    block_size : odd matching block size in pixels (1 to 255).
    mode : SGBM variant; "sgbm3way" is fastest.
    p1, p2 : smoothness penalties, integers ``1 <= p1 < p2 <= 32767`` (default ``8 b^2`` and
        ``32 b^2``).
    uniqueness_ratio, speckle_window, speckle_range, pre_filter_cap : as in cv2.StereoSGBM
        (integers: uniqueness 0 to 99 percent, speckle settings >= 0, cap 15 to 127). A
        setting out of these ranges is a ConfigError: OpenCV replaced some silently, failed
        on others (a uniqueness ratio of 100 killed the process).
    lr_check : "internal" (SGBM's own disp12MaxDiff check, free), "full" (match right-to-left
        too and keep pixels whose two disparities agree within ``lr_max_diff``; ~2x time) or
        "none". ``lr_max_diff`` is in pixels of the matching resolution: with ``scale`` < 1
        one low-resolution pixel is ``1 / scale`` full-resolution pixels (and the internal
        check rounds it up to a whole pixel).
    pad_left : pad the images so the leftmost ``num_disparities`` columns get disparities.
    fill_holes : fill invalid pixels from the background (see the module docstring); the
        result is then dense. Both flags are True or False (ConfigError: "no" read as True).
    scale : match at ``scale`` times the resolution (e.g. 0.5 for 4x speed) and upsample the
        disparity back (values rescaled to full-resolution pixels).
    subpixel : "sgbm" keeps SGBM's own sub-pixel estimate; "refine" moves every measured
        pixel by one Lucas-Kanade step (:func:`refine_subpixel`, at full resolution, before
        hole filling, which it leaves alone), which removes most of SGBM's pixel locking
        (~9 ms more at 640x480, a third of SGBM's time; not the default: see the module
        docstring). With ``scale`` < 1 SGBM errs in coarse pixels, and the one step moves at
        most :data:`REFINE_MAX_STEP_PX` full-resolution pixels.

    Returns
    -------
    (H, W) float32 disparity in pixels (``u_left - u_right``), NaN where invalid. All NaN
    when either image has no horizontal texture at all (a closed lens cap, a blank or
    saturated frame): every disparity matches such an image equally well, and SGBM used to
    answer a full map of zeros (points at infinity) as if they were measured.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> right = rng.integers(0, 255, (60, 120), dtype=np.uint8)
    >>> left = np.roll(right, 7, axis=1)  # every pixel shifted 7 px to the right
    >>> d = compute_disparity(left, right, num_disparities=16)
    >>> round(float(np.nanmedian(d[:, 20:])), 3)
    7.0
    """
    check_pair(left, right)
    L, R = to_gray(left), to_gray(right)
    for name, img in (("left", L), ("right", R)):  # (the message named the left's type)
        if img.dtype != np.uint8:
            raise ImageInputError(
                f"stereo images must be 8-bit (the {name} image is {img.dtype}); convert with "
                "cv2.normalize or cv2.convertScaleAbs"
            )
    if not isinstance(subpixel, str) or subpixel not in ("sgbm", "refine"):
        raise ConfigError(f"subpixel must be sgbm or refine, got {subpixel!r:.40}")
    if not isinstance(mode, str) or mode not in _MODES:  # (a list: a builtin TypeError)
        raise ConfigError(f"mode must be one of {', '.join(_MODES)}, got {mode!r}")
    if lr_check not in ("internal", "full", "none"):
        raise ConfigError(f"lr_check must be internal, full or none, got {lr_check!r}")
    for name, flag in (("pad_left", pad_left), ("fill_holes", fill_holes)):
        true_or_false(name, flag)  # ("no" was read as True)
    _check_search(num_disparities, min_disparity, scale)
    # (a negative tolerance silently became SGBM's 1 px; inf or NaN a builtin error)
    finite_number("lr_max_diff", lr_max_diff, 0.0)
    if (not isinstance(block_size, int | np.integer) or isinstance(block_size, bool)
            or not 1 <= block_size <= _MAX_BLOCK or block_size % 2 == 0):  # (cv2: ints only)
        raise ConfigError(f"block_size must be an odd integer in [1, {_MAX_BLOCK}], got "
                          f"{block_size!r}")
    b2 = block_size * block_size
    p1, p2 = _penalties(p1, p2, b2)
    # (each reached cv2.StereoSGBM_create as given: a float or NaN was a builtin TypeError, an
    # int beyond C's a ValueError; a negative uniqueness ratio became 10, 100 killed the
    # process with SIGFPE in the 3-way mode and more left no pixel in the others (SGBM tests
    # cost * (100 - ratio)); a cap below 15 became 15 and one above 127 overflows SGBM's 8-bit
    # pre-filter table; a negative speckle range removed every pixel)
    uniqueness_ratio = whole_number("uniqueness_ratio", uniqueness_ratio, 0, 99)
    speckle_window = whole_number("speckle_window", speckle_window, 0, _INT_MAX)
    speckle_range = whole_number("speckle_range", speckle_range, 0, _INT_MAX // 16)
    pre_filter_cap = whole_number("pre_filter_cap", pre_filter_cap, 15, 127)
    H, W = L.shape
    Wm, sx, md, nd = _matching_search(W, num_disparities, min_disparity, scale)
    # SGBM matches the columns right of its largest disparity (all of them when padded), and
    # needs more than half a block of them: fewer raised cv2.error, answered uninitialised
    # memory (3-way: all NaN) or, a search wider than the image, crashed the process
    cols = Wm if pad_left else Wm - md - nd
    if cols <= block_size // 2:
        unpadded = "" if pad_left else f" less min_disparity + num_disparities = {md + nd}"
        raise ConfigError(
            f"the images are too narrow for this search: {cols} column(s) to match (width "
            f"{Wm} at the matching resolution{unpadded}), block_size {block_size} needs more "
            f"than {block_size // 2}; lower num_disparities, min_disparity or block_size"
            + ("" if pad_left else ", or keep pad_left=True"))
    if not (_has_texture(L) and _has_texture(R)):
        return np.full((H, W), np.nan, np.float32)
    L0, R0 = L, R  # (full resolution, for the sub-pixel refinement)
    if scale < 1.0:
        size = (Wm, max(8, round(H * scale)))  # (Wm: the matching width above)
        L = cv2.resize(L, size, interpolation=cv2.INTER_AREA)
        R = cv2.resize(R, size, interpolation=cv2.INTER_AREA)
    kw = dict(
        min_disparity=md, num_disparities=nd, block_size=block_size, p1=p1, p2=p2,
        # SGBM cannot switch its own check off: it reads a tolerance < 1 (the -1 passed here
        # before 2026-11-26's twenty-third session) as 1 px, so "none" was "internal" with
        # 1 px, and "full" ran that 1-px check before its own. A tolerance of the largest
        # disparity keeps every pixel; "internal"'s own is capped there (it fits OpenCV's int)
        lr_max_diff=min(int(np.ceil(lr_max_diff)), _MAX_DISPARITY)
        if lr_check == "internal" else _MAX_DISPARITY,
        pre_filter_cap=pre_filter_cap, uniqueness_ratio=uniqueness_ratio,
        speckle_window=speckle_window, speckle_range=speckle_range, mode=_MODES[mode],
        pad_left=pad_left,
    )
    d = _sgbm(L, R, **kw)
    if lr_check == "full":
        # right-to-left: mirror both images and swap them; the disparity comes out mirrored
        dr = _sgbm(np.ascontiguousarray(R[:, ::-1]), np.ascontiguousarray(L[:, ::-1]), **kw)
        d = lr_consistency(d, dr[:, ::-1], lr_max_diff)
    measured = np.isfinite(d)
    if fill_holes:
        d = fill_disparity_holes(d)
    if scale < 1.0:
        d = cv2.resize(d, (W, H), interpolation=cv2.INTER_NEAREST) / np.float32(sx)
        measured = cv2.resize(measured.view(np.uint8), (W, H),
                              interpolation=cv2.INTER_NEAREST).astype(bool)
    if subpixel == "refine":  # measured pixels only: filled ones are the background's guess
        d = np.where(measured, _refine(L0, R0, np.where(measured, d, np.float32(np.nan))),
                     d).astype(np.float32)
    return d


#: Window (pixels, odd) of :func:`refine_subpixel`'s zero-mean SSD.
REFINE_WINDOW_PX = 7
#: Largest move of one refinement step, pixels (SGBM's locking errs by at most ~0.25 px).
REFINE_MAX_STEP_PX = 0.5


def refine_subpixel(left: NDArray, right: NDArray, disparity: NDArray, *,
                    window: int = REFINE_WINDOW_PX) -> NDArray:
    """One Lucas-Kanade step of a rectified pair's disparity (pixels, ``u_left - u_right``).

    Each finite pixel's disparity ``d`` moves by the Gauss-Newton step that minimises the
    zero-mean sum of squared differences, over the ``window`` x ``window`` pixels around it
    (those with a finite disparity and inside the right image), between the left image and
    the right image sampled at ``u - d`` (bicubic; each pixel of the window at its own
    disparity, so one warp serves the whole image). The step is clipped to
    :data:`REFINE_MAX_STEP_PX` and is zero where the window has no horizontal texture. NaN
    pixels stay NaN.

    Reconstruction (not in the thesis): SGBM's sub-pixel parabola over its sampling-insensitive
    costs is pixel-locked (Shimizu & Okutomi, IJCV 2005): on the real Middlebury motorcycle
    pair its error runs from -0.13 px (true fraction 0.25-0.375) to +0.20 px (0.5-0.625) and
    its estimates pile up at whole pixels; a region's median disparity -- a person's range --
    inherits the locking at its own fraction. The Lucas-Kanade step (Lucas & Kanade, IJCAI
    1981) on the images removes most of it: smooth real 32x32 patches' median error 0.174 /
    0.164 / 0.148 -> 0.114 / 0.131 / 0.116 px (motorcycle, teddy, cones), rendered people's
    0.12 -> 0.04 px, with the per-pixel error unchanged (0.20 / 0.21 / 0.18 px). More steps
    raised the per-pixel error on the real pairs (three: 0.28 / 0.27 / 0.23 px): one it is.

    ``left`` / ``right``: the rectified pair (uint8 grey or colour, converted to grey) of the
    disparity's size; ``window``: odd whole number 3 to 31 (ConfigError). Returns float32.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> base = cv2.GaussianBlur(rng.uniform(0, 255, (40, 200)), (0, 0), 1.5)
    >>> shift = lambda s: cv2.remap(base.astype(np.float32), (np.arange(200) - s).astype(
    ...     np.float32)[None].repeat(40, 0), np.arange(40, dtype=np.float32)[:, None].repeat(
    ...     200, 1), cv2.INTER_CUBIC).clip(0, 255).astype(np.uint8)
    >>> left, right = shift(10.3), shift(0.0)  # true disparity 10.3 px
    >>> d = refine_subpixel(left, right, np.full((40, 200), 10.2, np.float32))  # 0.1 px low
    >>> round(float(np.median(d[10:30, 30:170])), 1)
    10.3
    """
    check_pair(left, right)
    L, R = to_gray(left), to_gray(right)
    d = numeric_map("disparity", disparity, np.float32)
    if d.shape != L.shape:
        raise ImageInputError(f"disparity map is {d.shape[-1]}x{d.shape[0]} but the images are "
                              f"{L.shape[1]}x{L.shape[0]}" if d.ndim == 2 else
                              f"expected an (H, W) disparity map, got shape {d.shape}")
    window = whole_number("window", window, 3, 31)
    if window % 2 == 0:
        raise ConfigError(f"window must be odd, got {window}")
    return _refine(L, R, d, window)


def _refine(L: NDArray, R: NDArray, disparity: NDArray, window: int = REFINE_WINDOW_PX
            ) -> NDArray:
    """:func:`refine_subpixel` on checked (H, W) grey images and float32 disparity."""
    H, W = L.shape
    Lf, Rf = L.astype(np.float32), R.astype(np.float32)
    valid = np.isfinite(disparity)
    d = np.where(valid, disparity, np.float32(0.0)).astype(np.float32)
    u = np.arange(W, dtype=np.float32)[None, :]
    mapx = u - d
    mapy = np.broadcast_to(np.arange(H, dtype=np.float32)[:, None], (H, W)).copy()
    gx = cv2.Sobel(Rf, cv2.CV_32F, 1, 0, ksize=1) * np.float32(0.5)  # central difference
    warped = cv2.remap(Rf, mapx, mapy, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)
    grad = cv2.remap(gx, mapx, mapy, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)
    w = (valid & (mapx >= 1) & (mapx <= W - 2)).astype(np.float32)

    def box(a: NDArray) -> NDArray:
        return cv2.boxFilter(a, -1, (window, window), normalize=False,
                             borderType=cv2.BORDER_CONSTANT)

    n = box(w) + np.float32(1e-6)
    e = Lf - warped
    e -= box(e * w) / n  # zero-mean window: an exposure difference is no disparity
    grad -= box(grad * w) / n
    num, den = box(e * grad * w), box(grad * grad * w)
    ok = valid & (den > np.float32(1e-3 * window * window))
    with np.errstate(divide="ignore", invalid="ignore"):
        step = np.where(ok, -num / den, np.float32(0.0))
    step = np.clip(step, -REFINE_MAX_STEP_PX, REFINE_MAX_STEP_PX)
    return np.where(valid, d + step, np.float32(np.nan)).astype(np.float32)


def _has_texture(gray: NDArray) -> bool:
    """True when some row of ``gray`` changes along x (matching needs horizontal texture)."""
    return bool(np.any(gray[:, 1:] != gray[:, :-1]))


def lr_consistency(disp_left: NDArray, disp_right: NDArray, max_diff: float = 1.0) -> NDArray:
    """Left-right consistency check: keep ``disp_left[v, u]`` only where the right image's
    disparity at the matched pixel ``u - d`` agrees within ``max_diff`` pixels.

    ``disp_right`` is the disparity map of the right image (``u_left - u_right`` at right
    pixels). Returns a copy of ``disp_left`` with inconsistent pixels set to NaN.
    """
    dl = numeric_map("disp_left", disp_left, np.float32)
    dr = numeric_map("disp_right", disp_right, np.float32)
    if dl.shape != dr.shape or dl.ndim != 2:
        raise ImageInputError(f"disparity maps differ in shape: {dl.shape} vs {dr.shape}")
    # (NaN or a negative tolerance silently invalidated every pixel)
    max_diff = finite_number("max_diff", max_diff, 0.0)
    H, W = dl.shape
    u = np.arange(W, dtype=np.float32)[None, :]
    ur = np.rint(u - np.nan_to_num(dl, nan=0.0)).astype(np.int64)
    inside = (ur >= 0) & (ur < W) & np.isfinite(dl)
    rows = np.broadcast_to(np.arange(H)[:, None], (H, W))
    back = np.full_like(dl, np.nan)
    back[inside] = dr[rows[inside], ur[inside]]
    # (over: a tolerance beyond float32's range, 1e300, is inf in the float32 comparison)
    with np.errstate(invalid="ignore", over="ignore"):
        ok = inside & (np.abs(back - dl) <= max_diff)
    return np.where(ok, dl, np.float32(np.nan)).astype(np.float32)


def fill_disparity_holes(disparity: NDArray, median: int = 5) -> NDArray:
    """Fill NaN pixels with the smaller of the nearest valid disparities to their left and
    right on the same row (background fill), then smooth only the filled pixels with a
    ``median`` x ``median`` median filter (3 or 5; 0 to skip). Rows without any valid pixel
    stay NaN. Returns float32 pixels."""
    d = numeric_map("disparity", disparity, np.float32)
    if d.ndim != 2:  # (a builtin ValueError unpacking the shape)
        raise ImageInputError(f"expected an (H, W) disparity map, got shape {d.shape}")
    # (checked first: a map without holes returned early and took any median, 4 or NaN)
    if not (isinstance(median, int | np.integer) and not isinstance(median, bool)
            and median in (0, 3, 5)):
        raise ConfigError(f"median must be 0, 3 or 5, got {median}")
    H, W = d.shape
    valid = np.isfinite(d)
    if valid.all() or not valid.any():
        return d.copy()
    cols = np.arange(W)[None, :]
    left_idx = np.maximum.accumulate(np.where(valid, cols, -1), axis=1)
    right_idx = np.minimum.accumulate(np.where(valid, cols, W)[:, ::-1], axis=1)[:, ::-1]
    rows = np.arange(H)[:, None]
    inf = np.float32(np.inf)
    lv = np.where(left_idx >= 0, d[rows, np.clip(left_idx, 0, W - 1)], inf)
    rv = np.where(right_idx < W, d[rows, np.clip(right_idx, 0, W - 1)], inf)
    filled = np.minimum(lv, rv)
    filled[~np.isfinite(filled)] = np.nan
    out = np.where(valid, d, filled).astype(np.float32)
    if median:
        # the rows still NaN (no valid pixel at all) take their nearest filled row's values in
        # the median's window, as the image's own border rows do in medianBlur: read as 0
        # they outvoted a thin band's rows (a hole in a row between two such rows came out 0,
        # a point at infinity, between neighbours of 20 px)
        good = np.isfinite(out)
        rows_ok = good.any(axis=1)  # (a row is filled whole or not at all)
        r = np.arange(H)
        above = np.maximum.accumulate(np.where(rows_ok, r, -1))
        below = np.minimum.accumulate(np.where(rows_ok, r, H)[::-1])[::-1]
        near = np.where((above >= 0) & ((below >= H) | (r - above <= below - r)), above, below)
        sm = cv2.medianBlur(np.ascontiguousarray(out[near], dtype=np.float32), median)
        out = np.where(valid | ~good, out, sm).astype(np.float32)
    return out


# ---------------------------------------------------------------------------------------------
# Depth and 3D points
# ---------------------------------------------------------------------------------------------
def check_focal_baseline(focal_px: float, baseline_m: float) -> float:
    """``f B`` (pixel metres) of a rectified rig; CalibrationError unless the focal length
    (pixels) and the baseline (metres) are finite numbers > 0 (a negative one gave negative
    depths, a zero or NaN one all-NaN depths or no people at all). The one check of the depth
    conversions and the human detector."""
    for name, v, unit in (("focal_px", focal_px, "pixels"), ("baseline_m", baseline_m, "metres")):
        if not (is_real(v) and v > 0):
            raise CalibrationError(f"{name} must be a finite number of {unit} > 0, got {v!r}")
    return float(focal_px) * float(baseline_m)


def depth_from_disparity(disparity: ArrayLike, focal_px: float, baseline_m: float,
                         min_disparity: float = 0.0) -> NDArray:
    """Depth ``Z = f B / d`` in metres (NaN where ``d <= min_disparity``, NaN or infinite: an
    infinite disparity is no measurement, not a depth of 0 m), same shape as ``disparity``
    (pixels; a scalar gives a 0-d array; ImageInputError unless real numbers: text, bools and
    complex values were read as numbers). ``focal_px`` (pixels) and ``baseline_m`` (metres)
    must be finite and > 0 (CalibrationError)."""
    fb = check_focal_baseline(focal_px, baseline_m)
    if not is_real(min_disparity):
        raise ConfigError(f"min_disparity must be a finite number of pixels, got {min_disparity}")
    d = numeric_map("disparity", disparity)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where((d > max(min_disparity, 0.0)) & np.isfinite(d), fb / d, np.nan)


def disparity_from_depth(depth_m: ArrayLike, focal_px: float, baseline_m: float) -> NDArray:
    """Disparity ``d = f B / Z`` in pixels of depths in metres (NaN where Z <= 0 or NaN; 0 for
    an infinite depth), same shape as ``depth_m`` (a scalar gives a 0-d array; ImageInputError
    unless real numbers). ``focal_px`` (pixels) and ``baseline_m`` (metres) must be finite and
    > 0 (CalibrationError)."""
    fb = check_focal_baseline(focal_px, baseline_m)
    z = numeric_map("depth_m", depth_m)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(z > 0, fb / z, np.nan)


def points_from_disparity(disparity: ArrayLike, Q: ArrayLike) -> NDArray:
    """3D points ``(H, W, 3)`` in metres in the rectified left optical frame,
    ``[X Y Z W]^T = Q [u v d 1]^T`` (``Q`` from :class:`hearsee.vision.camera.Rectification`);
    NaN where the disparity is invalid or non-positive (or puts the point at or behind the
    camera). ConfigError for a ``Q`` that is not a finite 4x4 matrix with a focal length
    ``Q[2, 3] > 0`` and an inverse baseline ``Q[3, 2] > 0`` (a NaN or all-zero Q gave an
    all-NaN cloud without a word, a swapped rig's points behind the camera)."""
    d = numeric_map("disparity", disparity)
    if not real_entries(Q):
        raise ConfigError(f"Q must be a 4x4 matrix of numbers, got {Q!r:.80}")
    Q = np.asarray(Q, dtype=np.float64)
    if d.ndim != 2 or Q.shape != (4, 4):
        raise ConfigError(f"expected (H, W) disparity and 4x4 Q, got {d.shape} and {Q.shape}")
    if not np.all(np.isfinite(Q)) or not (Q[2, 3] > 0 and Q[3, 2] > 0):
        # (a Q of a rig with the cameras swapped -- T_x > 0 -- or a negative focal length put
        # every point behind the camera, Z < 0, without a word)
        raise ConfigError("Q must be a finite reprojection matrix with Q[2, 3] = f > 0 and "
                          "Q[3, 2] = -1/T_x > 0 (the right camera to the right of the left "
                          f"one; see cv2.stereoRectify), got Q[2, 3] = {Q[2, 3]:.4g}, "
                          f"Q[3, 2] = {Q[3, 2]:.4g}")
    H, W = d.shape
    u = np.arange(W, dtype=np.float64)[None, :]
    v = np.arange(H, dtype=np.float64)[:, None]
    X = Q[0, 0] * u + Q[0, 1] * v + Q[0, 2] * d + Q[0, 3]
    Y = Q[1, 0] * u + Q[1, 1] * v + Q[1, 2] * d + Q[1, 3]
    Z = Q[2, 0] * u + Q[2, 1] * v + Q[2, 2] * d + Q[2, 3]
    Wh = Q[3, 0] * u + Q[3, 1] * v + Q[3, 2] * d + Q[3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        pts = np.stack(np.broadcast_arrays(X / Wh, Y / Wh, Z / Wh), axis=-1)
    bad = ~(d > 0) | ~(Wh > 0)  # (W <= 0: a point at or behind the camera)
    pts[bad] = np.nan
    return pts


def points_to_left_frame(points: ArrayLike, rectification: Rectification) -> NDArray:
    """Rotate points ``(..., 3)`` from the rectified left frame back to the (unrectified) left
    camera's optical frame -- the frame the rig's thermal extrinsics refer to."""
    if not isinstance(rectification, Rectification):  # (else a builtin AttributeError)
        raise CalibrationError("rectification: expected a Rectification (stereo_frame(...)."
                               f"rectification), got {type(rectification).__name__}")
    p = as_points(points, "points_to_left_frame")  # (numpy's matmul ValueError for (N, 2))
    return p @ rectification.R1  # R1 maps left -> rectified, so R1^T maps back (row vectors)


# ---------------------------------------------------------------------------------------------
# One call per frame
# ---------------------------------------------------------------------------------------------
@dataclass
class StereoFrame:
    """Result of :func:`stereo_frame`: rectified images, disparity and the rectification.

    ``disparity`` is float32 pixels (NaN invalid) of the rectified left image; :meth:`depth`
    (metres) and :meth:`points` (``(H, W, 3)`` metres, rectified left frame) derive from it.
    ``search_px``: the smallest and largest disparity the matcher searched (pixels,
    :func:`search_range_px`; None when not known): nothing nearer than ``f B / largest``
    metres has a correct disparity.
    """

    left: NDArray
    right: NDArray
    disparity: NDArray
    rectification: Rectification
    search_px: tuple[float, float] | None = None
    _points: NDArray | None = field(default=None, repr=False)

    @property
    def min_depth_m(self) -> float | None:
        """The nearest depth (metres) the disparity search reaches, ``f B / largest
        disparity``; None when the search is not known."""
        if self.search_px is None:
            return None
        return self.focal_px * self.baseline_m / self.search_px[1]

    @property
    def focal_px(self) -> float:
        return self.rectification.focal_px

    @property
    def baseline_m(self) -> float:
        return self.rectification.baseline_m

    def depth(self) -> NDArray:
        """Depth map in metres (NaN invalid)."""
        return depth_from_disparity(self.disparity, self.focal_px, self.baseline_m)

    def points(self, frame: Literal["rectified", "left"] = "rectified") -> NDArray:
        """3D points ``(H, W, 3)`` in metres in the rectified left frame or, with
        ``frame="left"``, the left camera's own optical frame."""
        if frame not in ("rectified", "left"):  # (any other name gave the rectified frame)
            raise ConfigError(f"frame must be 'rectified' or 'left', got {frame!r}")
        if self._points is None:
            self._points = points_from_disparity(self.disparity, self.rectification.Q)
        if frame == "left":
            return points_to_left_frame(self._points, self.rectification)
        return self._points


#: The keyword options of :func:`compute_disparity` (:func:`stereo_frame` checks its own
#: against them once per call, not by inspecting the signature each time).
_DISPARITY_OPTIONS = frozenset(inspect.signature(compute_disparity).parameters) - {"left", "right"}
#: Its defaults of the options that set the search (:func:`stereo_frame`'s ``search_px``).
_SEARCH_DEFAULTS = {k: inspect.signature(compute_disparity).parameters[k].default
                    for k in ("num_disparities", "min_disparity", "scale")}


def stereo_frame(left: NDArray, right: NDArray, rig: StereoRig, **disparity_options) -> StereoFrame:
    """Rectify a pair with ``rig`` and compute its disparity (options of
    :func:`compute_disparity`). The usual per-frame entry point.

    Examples
    --------
    >>> from hearsee.vision.camera import Camera, StereoRig
    >>> rig = StereoRig.ideal(Camera.from_fov(60.0, 160, 120), baseline_m=0.1)
    >>> rng = np.random.default_rng(1)
    >>> right = rng.integers(0, 255, (120, 160), dtype=np.uint8)
    >>> f = stereo_frame(np.roll(right, 8, axis=1), right, rig, num_disparities=16)
    >>> round(float(np.nanmedian(f.depth()[:, 30:])), 3)  # f B / d = 138.56 * 0.1 / 8
    1.732
    """
    unknown = sorted(set(disparity_options) - _DISPARITY_OPTIONS)
    if unknown:  # (a builtin TypeError from compute_disparity's call, after the rectification)
        raise ConfigError(f"unknown disparity option(s) {', '.join(unknown)}; expected some of "
                          f"{', '.join(sorted(_DISPARITY_OPTIONS))}")
    lr, rr, rect = rectify_pair(left, right, rig)
    d = compute_disparity(lr, rr, **disparity_options)
    search = search_range_px(lr.shape[1], **{k: disparity_options.get(k, v)
                                            for k, v in _SEARCH_DEFAULTS.items()})
    return StereoFrame(lr, rr, d, rect, search)
