"""Tests of hearsee.vision.stereo on synthetic scenes with known depth."""

from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest

from hearsee.errors import CalibrationError, ConfigError, GeometryError, ImageInputError
from hearsee.vision.camera import Camera, StereoRig
from hearsee.vision.stereo import (
    compute_disparity,
    depth_from_disparity,
    disparity_from_depth,
    fill_disparity_holes,
    lr_consistency,
    points_from_disparity,
    points_to_left_frame,
    rectification_maps,
    rectify_pair,
    refine_subpixel,
    search_range_px,
    stereo_frame,
)


def _texture(seed: int = 0, size: int = 512) -> np.ndarray:
    """A random multi-scale texture (uint8), good for matching."""
    rng = np.random.default_rng(seed)
    tex = np.zeros((size, size), np.float32)
    for s in (4, 16, 64):
        small = rng.uniform(0, 1, (size // s, size // s)).astype(np.float32)
        tex += cv2.resize(small, (size, size), interpolation=cv2.INTER_CUBIC)
    tex = cv2.normalize(tex, None, 0, 255, cv2.NORM_MINMAX)
    return tex.astype(np.uint8)


def _render_plane(cam: Camera, R: np.ndarray, T: np.ndarray, tex: np.ndarray,
                  n_left: np.ndarray, z0: float, extent: float = 3.0) -> np.ndarray:
    """Render the plane {X : n . X = z0} (left frame) textured over [-extent, extent]^2 (x, y)
    as seen by ``cam`` whose pose is X_cam = R X_left + T."""
    uu, vv = np.meshgrid(np.arange(cam.width, dtype=float), np.arange(cam.height, dtype=float))
    rays_cam = cam.pixel_rays(np.c_[uu.ravel(), vv.ravel()])
    c = -R.T @ T  # camera centre in the left frame
    rays = rays_cam @ R  # to the left frame
    s = (z0 - n_left @ c) / (rays @ n_left)
    X = c[None, :] + s[:, None] * rays
    size = tex.shape[0]
    mx = ((X[:, 0] + extent) / (2 * extent) * (size - 1)).reshape(cam.height, cam.width)
    my = ((X[:, 1] + extent) / (2 * extent) * (size - 1)).reshape(cam.height, cam.width)
    return cv2.remap(tex, mx.astype(np.float32), my.astype(np.float32), cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REFLECT)


def test_depth_disparity_roundtrip():
    z = np.array([0.5, 1.0, 4.0, -1.0, np.nan])
    d = disparity_from_depth(z, 500.0, 0.1)
    np.testing.assert_allclose(d[:3], [100.0, 50.0, 12.5])
    assert np.all(np.isnan(d[3:]))
    np.testing.assert_allclose(depth_from_disparity(d, 500.0, 0.1)[:3], z[:3])
    assert np.isnan(depth_from_disparity(np.array([0.0]), 500.0, 0.1)[0])


def test_points_from_disparity_match_opencv_reproject():
    rig = StereoRig.ideal(Camera.from_fov(60.0, 64, 48), 0.12)
    rng = np.random.default_rng(3)
    d = rng.uniform(5, 30, (48, 64)).astype(np.float32)
    d[0, 0] = np.nan
    pts = points_from_disparity(d, rig.Q)
    ref = cv2.reprojectImageTo3D(np.nan_to_num(d, nan=0.0), rig.Q)
    np.testing.assert_allclose(pts[1:], ref[1:], rtol=1e-5)
    assert np.all(np.isnan(pts[0, 0]))
    np.testing.assert_allclose(pts[..., 2][1:], (rig.focal_px * 0.12 / d)[1:], rtol=1e-6)
    # (an audit: a swapped rig's Q, T_x > 0, or a negative focal length put every point behind
    # the camera, Z < 0, without a word)
    for r, c, v in ((3, 2, -rig.Q[3, 2]), (2, 3, -rig.Q[2, 3])):
        Q = rig.Q.copy()
        Q[r, c] = v
        with pytest.raises(ConfigError, match=r"Q\[2, 3\] = f > 0 and Q\[3, 2\] = -1/T_x > 0"):
            points_from_disparity(d, Q)
    Q = rig.Q.copy()
    Q[3, 3] = -1.0  # (W = d / B - 1 <= 0 for d <= B px: at or behind the camera there)
    pts = points_from_disparity(np.array([[0.06, 0.12, 0.24]]), Q)
    assert np.all(np.isnan(pts[0, :2])) and pts[0, 2, 2] > 0


def test_shifted_texture_gives_its_shift_with_subpixel_accuracy():
    tex = _texture(1)[:120, :200]
    M = np.float32([[1, 0, 9.5], [0, 1, 0]])  # left = right shifted by 9.5 px
    left = cv2.warpAffine(tex, M, (200, 120), flags=cv2.INTER_CUBIC,
                          borderMode=cv2.BORDER_REFLECT)
    d = compute_disparity(left, tex, num_disparities=32)
    core = d[10:-10, 20:-10]
    assert np.mean(np.isfinite(core)) > 0.95
    assert np.nanmedian(core) == pytest.approx(9.5, abs=0.15)
    # padding gives disparities in the leftmost columns too
    assert np.mean(np.isfinite(d[10:-10, 12:32])) > 0.8
    plain = compute_disparity(left, tex, num_disparities=32, pad_left=False)
    assert np.all(np.isnan(plain[:, :31]))


def _shifted(shift: float) -> tuple[np.ndarray, np.ndarray]:
    """(left, right) of a texture whose left image is the right shifted by ``shift`` px."""
    tex = _texture(1)[:120, :240]
    M = np.float32([[1, 0, shift], [0, 1, 0]])
    return cv2.warpAffine(tex, M, (240, 120), flags=cv2.INTER_CUBIC,
                          borderMode=cv2.BORDER_REFLECT), tex


SHIFTS_PX = (9.1, 9.25, 9.4, 9.5, 9.6, 9.75, 9.9, 12.35)


def test_refinement_removes_sgbms_pixel_locking():
    """A texture shifted by known sub-pixel amounts: SGBM's own estimate locks toward whole
    pixels (its median errs by up to ~0.27 px here); one Lucas-Kanade step brings every
    median within 0.06 px of the shift."""
    worst_sgbm, worst_refined = 0.0, 0.0
    for shift in SHIFTS_PX:
        left, right = _shifted(shift)
        raw = compute_disparity(left, right, num_disparities=32)[10:-10, 20:-10]
        fine = compute_disparity(left, right, num_disparities=32,
                                 subpixel="refine")[10:-10, 20:-10]
        np.testing.assert_array_equal(np.isfinite(fine), np.isfinite(raw))  # same pixels
        assert np.nanmean(np.abs(fine - shift)) < 0.11
        worst_sgbm = max(worst_sgbm, abs(float(np.nanmedian(raw)) - shift))
        worst_refined = max(worst_refined, abs(float(np.nanmedian(fine)) - shift))
    assert worst_refined < 0.06
    assert worst_refined < worst_sgbm / 3


def test_refinement_is_blind_to_exposure_and_works_with_scale_and_filling():
    left, right = _shifted(9.4)
    brighter = np.clip(right.astype(int) + 25, 0, 255).astype(np.uint8)  # exposure offset
    d = compute_disparity(left, brighter, num_disparities=32, subpixel="refine")
    assert np.nanmedian(d[10:-10, 20:-10]) == pytest.approx(9.4, abs=0.06)
    # at half resolution SGBM errs in half-resolution pixels (~0.5 px here); one step, at full
    # resolution, moves at most REFINE_MAX_STEP_PX toward the shift
    coarse = compute_disparity(left, right, num_disparities=32, scale=0.5)[10:-10, 20:-10]
    half = compute_disparity(left, right, num_disparities=32, scale=0.5,
                             subpixel="refine")[10:-10, 20:-10]
    assert abs(np.nanmedian(half) - 9.4) < min(0.12, abs(np.nanmedian(coarse) - 9.4) - 0.2)
    # filled pixels are the background's guess: refinement leaves them as filling made them
    left[40:60, 100:140] = 128  # a blank patch: no match there
    raw = compute_disparity(left, right, num_disparities=32)
    holes = ~np.isfinite(raw)
    assert holes.sum() > 100
    filled = compute_disparity(left, right, num_disparities=32, fill_holes=True)
    both = compute_disparity(left, right, num_disparities=32, fill_holes=True,
                             subpixel="refine")
    np.testing.assert_array_equal(both[holes], filled[holes])
    assert not np.array_equal(both[~holes], filled[~holes])


def test_refine_subpixel_keeps_nan_and_checks_its_input():
    left, right = _shifted(9.6)
    d = np.full(left.shape, 9.5, np.float32)
    d[:, :50] = np.nan
    out = refine_subpixel(left, right, d)
    assert out.dtype == np.float32
    assert np.all(np.isnan(out[:, :50]))
    assert np.nanmedian(out[10:-10, 60:-10]) == pytest.approx(9.6, abs=0.03)
    with pytest.raises(ConfigError, match="window"):
        refine_subpixel(left, right, d, window=4)
    with pytest.raises(ConfigError, match="window"):
        refine_subpixel(left, right, d, window=1)
    with pytest.raises(ImageInputError, match="disparity map"):
        refine_subpixel(left, right, d[:, :100])
    with pytest.raises(ImageInputError, match="differ in size"):
        refine_subpixel(left, right[:, :100], d)
    with pytest.raises(ConfigError, match="subpixel"):
        compute_disparity(left, right, subpixel="yes")


def test_search_range_is_what_the_matcher_can_report():
    """search_range_px names the disparities compute_disparity searches: a shift inside it is
    measured, one beyond it never gets a disparity above its end (SGBM answers the end or
    nothing), and a num_disparities that is no multiple of 16 searches to the next one."""
    assert search_range_px(240, num_disparities=32) == (0.0, 31.0)
    assert search_range_px(240, num_disparities=40) == (0.0, 47.0)  # rounded up to 48
    assert search_range_px(240, num_disparities=64, scale=0.5) == (0.0, 62.0)
    assert search_range_px(240, num_disparities=32, min_disparity=8) == (8.0, 39.0)
    inside = compute_disparity(*_shifted(40.0), num_disparities=40)[10:-10, 60:-10]
    assert np.nanmedian(inside) == pytest.approx(40.0, abs=0.15)
    beyond = compute_disparity(*_shifted(40.0), num_disparities=32)[10:-10, 60:-10]
    assert np.nanmax(beyond) <= 31.0
    # its defaults are compute_disparity's, and stereo_frame reports the search it ran
    import inspect

    sig = inspect.signature(compute_disparity).parameters
    assert search_range_px(240) == search_range_px(
        240, sig["num_disparities"].default, sig["min_disparity"].default, sig["scale"].default)
    rig = StereoRig.ideal(Camera.from_fov(60.0, 240, 120), baseline_m=0.1)
    f = stereo_frame(*_shifted(20.0), rig, num_disparities=24)
    assert f.search_px == (0.0, 31.0)
    assert f.min_depth_m == pytest.approx(f.focal_px * 0.1 / 31.0)
    for kw in ({"width": 0}, {"width": 2.5}, {"num_disparities": 0}, {"min_disparity": -1},
               {"scale": 0.0}, {"num_disparities": float("nan")},
               {"num_disparities": 2049}):  # (beyond SGBM's reach: compute_disparity's rule)
        with pytest.raises(ConfigError):
            search_range_px(**{"width": 240, **kw})


def test_slanted_plane_through_distorted_rotated_rig_recovers_depth():
    """Render a textured slanted plane through a rig with distortion, rotation and vertical
    offset; after rectification the depth of every valid pixel matches the true plane."""
    K = np.array([[260.0, 0, 158.0], [0, 262.0, 121.0], [0, 0, 1]])
    left = Camera(K=K, dist=[-0.15, 0.03, 0.0005, -0.0005, 0.0], width=320, height=240)
    K2 = K.copy()
    K2[0, 2], K2[1, 1] = 163.0, 259.0
    right = Camera(K=K2, dist=[-0.12, 0.02, 0.0, 0.0005, 0.0], width=320, height=240)
    R = cv2.Rodrigues(np.array([0.01, -0.03, 0.008]))[0]
    T = -R @ np.array([0.12, 0.004, 0.002])  # right centre 12 cm to the right
    rig = StereoRig(left, right, R, T)
    n = np.array([0.0, 0.0, 1.0]) + np.array([0.35, 0.0, 0.0])
    n = n / np.linalg.norm(n)
    z0 = 1.8 * n[2]  # plane through (0, 0, 1.8), slanted in x
    tex = _texture(2, 1024)
    L = _render_plane(left, np.eye(3), np.zeros(3), tex, n, z0)
    Rimg = _render_plane(right, R, T, tex, n, z0)
    f = stereo_frame(L, Rimg, rig, num_disparities=48)
    pts = f.points(frame="left")
    ok = np.isfinite(pts[..., 2])
    assert ok.mean() > 0.6
    resid = pts[ok] @ n - z0  # distance to the true plane, metres
    # dZ = Z^2 / (f B) * dd: at 1.8 m a 0.1 px disparity error (SGBM's sub-pixel "pixel
    # locking") is ~1 cm
    assert np.median(np.abs(resid)) < 0.015
    assert np.percentile(np.abs(resid), 90) < 0.05
    # depth in the rectified frame agrees with Z from the 3D points there
    zr = f.points()[..., 2]
    np.testing.assert_allclose(f.depth()[ok], zr[ok], rtol=1e-6)


def test_lr_consistency_and_hole_filling():
    dl = np.full((4, 20), 5.0, np.float32)
    dr = np.full((4, 20), 5.0, np.float32)
    dr[1, 5] = 9.0  # the right image disagrees at the pixel matched by (row 1, u = 10)
    out = lr_consistency(dl, dr, 1.0)
    assert np.isnan(out[1, 10]) and np.isfinite(out[1, 11])
    assert np.all(np.isnan(out[:, :5]))  # matches fall outside the right image
    d = np.array([[3, 3, np.nan, np.nan, 8, 8, np.nan]], np.float32)
    filled = fill_disparity_holes(d, median=0)
    np.testing.assert_array_equal(filled, [[3, 3, 3, 3, 8, 8, 8]])
    np.testing.assert_array_equal(fill_disparity_holes(np.full((2, 3), np.nan)).shape, (2, 3))


@pytest.mark.parametrize("median", [3, 5])
def test_hole_filling_median_does_not_read_unmatched_rows_as_zero(median):
    """Rows without any valid pixel stay NaN and are no disparity of 0 in the median of the
    filled pixels: a 2-px hole in a one-row band (two rows for the 5x5 median) between such
    rows came out 0 -- a point at infinity -- between neighbours of 20 px."""
    d = np.full((9, 12), np.nan, np.float32)
    band = slice(4, 5) if median == 3 else slice(3, 5)
    d[band] = 20.0
    d[band, 5:7] = np.nan
    out = fill_disparity_holes(d, median=median)
    np.testing.assert_array_equal(out[band], 20.0)
    assert np.isnan(out[:3]).all() and np.isnan(out[5:]).all()


def test_fill_makes_dense_and_full_lr_check_runs():
    tex = _texture(4)[:96, :160]
    left = np.roll(tex, 6, axis=1)
    for kw in (dict(fill_holes=True), dict(lr_check="full", fill_holes=True), dict(scale=0.5)):
        d = compute_disparity(left, tex, num_disparities=16, **kw)
        assert d.shape == tex.shape and d.dtype == np.float32
        assert np.nanmedian(d[:, 20:]) == pytest.approx(6.0, abs=0.3)
        if kw.get("fill_holes"):
            assert np.isfinite(d).all()


def _occlusion_pair() -> tuple[np.ndarray, np.ndarray, slice]:
    """A background at 4 px disparity behind a foreground block at 20 px (columns 100-159 of
    the left image); the 16 background columns just left of the block, seen by the left
    camera only, are returned as the occluded band."""
    bg, fg = _texture(11, 256)[:120, :256], _texture(12, 256)[:120, :256]
    right = bg.copy()
    right[:, 80:140] = fg[:, 80:140]             # the block at columns 80-139 in the right view
    left = np.roll(bg, 4, axis=1)                 # background: d = 4
    left[:, 100:160] = fg[:, 80:140]              # block: d = 20 (covers 100-159)
    return left, right, slice(86, 98)             # visible in the left image only


def test_lr_check_none_keeps_occluded_pixels_and_full_honours_its_tolerance():
    """"none" switches SGBM's own left-right check off: OpenCV reads a tolerance below 1 as
    1 px, so "none" was "internal" with 1 px (occluded pixels removed), and "full" ran that
    1-px check before its own tolerance."""
    left, right, occ = _occlusion_pair()
    none = compute_disparity(left, right, num_disparities=32, lr_check="none")
    internal = compute_disparity(left, right, num_disparities=32, lr_check="internal")
    keep_all = compute_disparity(left, right, num_disparities=32, lr_check="internal",
                                 lr_max_diff=64)
    # the scene: background 4 px, block 20 px, wherever both checks keep a pixel
    assert np.nanmedian(internal[:, 40:80]) == pytest.approx(4.0, abs=0.3)
    assert np.nanmedian(internal[:, 110:150]) == pytest.approx(20.0, abs=0.3)
    np.testing.assert_array_equal(none, keep_all)
    assert np.isfinite(none[:, occ]).mean() > np.isfinite(internal[:, occ]).mean() + 0.3
    # "full" with a 64-px tolerance keeps the occluded pixels "none" keeps (it still drops
    # pixels whose right-to-left match has no disparity); with its default 1 px, none of them
    full_loose = compute_disparity(left, right, num_disparities=32, lr_check="full",
                                   lr_max_diff=64)
    full_tight = compute_disparity(left, right, num_disparities=32, lr_check="full")
    np.testing.assert_array_equal(full_loose[:, occ], none[:, occ])
    assert np.isfinite(full_tight[:, occ]).mean() < np.isfinite(none[:, occ]).mean() - 0.3


def test_bad_inputs():
    tex = _texture(5)[:60, :80]
    with pytest.raises(ImageInputError, match="differ in size"):
        compute_disparity(tex, tex[:, :70])
    with pytest.raises(ImageInputError, match="8-bit"):
        compute_disparity(tex.astype(np.uint16), tex.astype(np.uint16))
    rig = StereoRig.ideal(Camera.from_fov(60.0, 320, 240), 0.1)
    with pytest.raises(ImageInputError, match="calibration expects 320x240"):
        rectify_pair(tex, tex, rig)
    swapped = StereoRig(rig.left, rig.right, np.eye(3), [0.1, 0.0, 0.0])
    img = _texture(6)[:240, :320]
    with pytest.raises(CalibrationError, match="swap"):
        rectify_pair(img, img, swapped)
    with pytest.raises(ValueError, match="block_size"):
        compute_disparity(tex, tex, block_size=4)


def test_textureless_images_have_no_disparity():
    """Two blank frames (a lens cap, a saturated sensor) match at every disparity equally
    well; SGBM answered a full map of zeros (points at infinity) as if measured."""
    blank = np.full((60, 80), 128, np.uint8)
    assert np.isnan(compute_disparity(blank, blank)).all()
    tex = _texture(5)[:60, :80]
    assert np.isnan(compute_disparity(tex, blank)).all()
    assert np.isfinite(compute_disparity(tex, tex)).mean() > 0.5  # texture: still matched


@pytest.mark.shared
def test_middlebury_teddy_quality(shared_data):
    """The tuned matcher stays well ahead of default-ish SGBM (24 % bad-2.0) on teddy."""
    from hearsee.vision.io import read_image, read_pair

    d = shared_data / "vision" / "middlebury2003" / "teddy"
    if not d.is_dir():
        pytest.skip("middlebury2003 not present")
    left, right = read_pair(d / "im2.png", d / "im6.png", "bgr")
    gt = read_image(d / "disp2.pgm", "unchanged").astype(np.float32) / 4.0
    valid = gt > 0
    disp = compute_disparity(left, right, num_disparities=64, fill_holes=True)
    bad = np.mean(~(np.abs(disp[valid] - gt[valid]) <= 2.0))  # NaN counts as bad
    assert bad < 0.10
    raw = compute_disparity(left, right, num_disparities=64)
    est = valid & np.isfinite(raw)
    assert est.sum() / valid.sum() > 0.88
    assert np.mean(np.abs(raw[est] - gt[est]) > 2.0) < 0.07


def test_depth_conversions_check_focal_and_baseline_and_accept_scalars():
    """f or B <= 0 or NaN gave negative or all-NaN depths; a scalar disparity raised a
    TypeError (0-d assignment)."""
    for f, b in ((0.0, 0.1), (-500.0, 0.1), (np.nan, 0.1), (500.0, -0.1), (500.0, np.inf)):
        with pytest.raises(CalibrationError, match="focal_px|baseline_m"):
            depth_from_disparity([[1.0, 2.0]], f, b)
        with pytest.raises(CalibrationError, match="focal_px|baseline_m"):
            disparity_from_depth([[1.0, 2.0]], f, b)
    z = depth_from_disparity(5.0, 500.0, 0.1)
    assert z.shape == () and float(z) == pytest.approx(10.0)
    assert np.isnan(depth_from_disparity(0.0, 500.0, 0.1))
    d = disparity_from_depth(2.0, 500.0, 0.1)
    assert d.shape == () and float(d) == pytest.approx(25.0)
    assert np.isnan(disparity_from_depth(-1.0, 500.0, 0.1))
    assert depth_from_disparity(np.ones((3, 4)), 500.0, 0.1).shape == (3, 4)
    assert depth_from_disparity(np.zeros((0, 0)), 500.0, 0.1).shape == (0, 0)
    with pytest.raises(ConfigError, match="min_disparity"):
        depth_from_disparity([1.0], 500.0, 0.1, min_disparity=np.nan)


@pytest.mark.parametrize("kw", [dict(num_disparities=np.nan), dict(min_disparity=np.nan),
                                dict(lr_max_diff=np.nan), dict(lr_max_diff=np.inf),
                                dict(block_size=3.0), dict(block_size="3"),
                                dict(num_disparities="64")])
def test_non_numeric_matcher_settings_are_config_errors(kw):
    """NaN settings reached int(np.ceil(nan)) (builtin ValueError), an infinite lr_max_diff
    int(inf) (OverflowError), a float block_size cv2.StereoSGBM_create (TypeError), a string
    num_disparities the comparison (TypeError)."""
    tex = _texture(7)[:60, :80]
    with pytest.raises(ConfigError, match=next(iter(kw))):
        compute_disparity(np.roll(tex, 4, axis=1), tex, **kw)


@pytest.mark.parametrize("kw, match", [
    (dict(num_disparities=4096), "num_disparities"),  # cv2.error (a 1.8e19-byte buffer)
    (dict(num_disparities=10**6), "num_disparities"),  # (a 640x480 pair: cv2.error, no memory)
    (dict(min_disparity=2**40), "num_disparities"),  # cv2.error (not a C int)
    (dict(num_disparities=96, pad_left=False), "too narrow"),  # wider than the image: cv2.error
    (dict(block_size=21, min_disparity=6, pad_left=False), "too narrow"),  # 10 columns
    (dict(p1=100, p2=10), "p2 must be greater than p1"),  # OpenCV used P2 = P1 + 1
    (dict(p1=0), "p1"), (dict(p2=-5), "p2"),  # OpenCV used 2 and 5
    (dict(p1=np.nan), "p1"), (dict(p1=8.7), "p1"), (dict(p2=40000), "p2"),
    (dict(block_size=33), "p2 .default 32 . block_size"),  # P2 wrapped to 16 bits: no pixel
    (dict(block_size=257, p1=8, p2=32), "block_size"),
    (dict(block_size=2**31 + 1), "block_size"),  # builtin ValueError (not a C int)
    (dict(uniqueness_ratio=100, mode="sgbm"), "uniqueness_ratio"),  # no pixel (3-way: SIGFPE)
    (dict(uniqueness_ratio=-1), "uniqueness_ratio"),  # OpenCV used 10
    (dict(uniqueness_ratio=2.5), "uniqueness_ratio"),  # builtin TypeError
    (dict(pre_filter_cap=5), "pre_filter_cap"),  # OpenCV used 15
    (dict(pre_filter_cap=200), "pre_filter_cap"),  # beyond SGBM's 8-bit pre-filter table
    (dict(speckle_range=-1), "speckle_range"),  # removed every pixel
    (dict(speckle_window=10**12), "speckle_window"),  # builtin ValueError
    (dict(lr_max_diff=-1), "lr_max_diff"),  # OpenCV used 1
    (dict(scale="1"), "scale"),  # builtin TypeError
    (dict(mode=["sgbm"]), "mode"),  # builtin TypeError (unhashable)
])
def test_sgbm_settings_opencv_cannot_take_are_config_errors(kw, match):
    """Every matcher setting reached cv2.StereoSGBM as given: a search beyond 2048 pixels (the
    largest disparity of SGBM's 16-bit fixed-point output) or wider than the image raised
    cv2.error or asked for terabytes, P1 > P2 was silently replaced by P2 = P1 + 1, floats,
    NaN and ints beyond C's raised builtin errors, and other out-of-range values were
    silently replaced or gave no disparity at all."""
    tex = _texture(7)[:60, :80]
    with pytest.raises(ConfigError, match=match):
        compute_disparity(np.roll(tex, 4, axis=1), tex, **kw)


def test_sgbm_settings_at_their_limits_still_match():
    """The limits refuse nothing SGBM can do: a 2048-pixel search, uniqueness 99 and cap 127
    still find the shift; a tolerance beyond float's range (1e300 raised a builtin
    OverflowError, and a numpy RuntimeWarning with lr_check="full") keeps what one of 10**6
    pixels keeps."""
    tex = _texture(8)[:64, :160]
    left = np.roll(tex, 6, axis=1)
    for kw in (dict(num_disparities=2048), dict(num_disparities=2032, min_disparity=4),
               dict(uniqueness_ratio=99), dict(pre_filter_cap=127)):
        d = compute_disparity(left, tex, **kw)
        assert np.nanmedian(d[:, 20:]) == pytest.approx(6.0, abs=0.5), kw
    for check in ("internal", "full"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            far = compute_disparity(left, tex, lr_check=check, lr_max_diff=1e300)
        np.testing.assert_array_equal(
            far, compute_disparity(left, tex, lr_check=check, lr_max_diff=1e6))


def test_disparity_helpers_check_their_settings_and_shapes():
    """Bad-input sweep of the public API: lr_consistency with a NaN or negative max_diff set
    every pixel invalid without a word; fill_disparity_holes took median 4, 3.0 or NaN when
    the map had no hole (and a 1-D map raised a builtin ValueError); points_to_left_frame of
    (N, 2) points raised numpy's matmul ValueError; StereoFrame.points('Left') answered in the
    rectified frame."""
    dl = np.full((4, 20), 5.0, np.float32)
    for bad in (np.nan, -1.0, "1"):
        with pytest.raises(ConfigError, match="max_diff"):
            lr_consistency(dl, dl, bad)
    for bad in (4, 3.0, np.nan, True):
        with pytest.raises(ConfigError, match="median"):
            fill_disparity_holes(dl, median=bad)
    with pytest.raises(ImageInputError, match="disparity map"):
        fill_disparity_holes(np.ones(10))
    rig = StereoRig.ideal(Camera.from_fov(60.0, 160, 120), baseline_m=0.1)
    right = np.random.default_rng(1).integers(0, 255, (120, 160), dtype=np.uint8)
    f = stereo_frame(np.roll(right, 8, axis=1), right, rig, num_disparities=16)
    with pytest.raises(GeometryError, match="3 coordinates"):
        points_to_left_frame(np.ones((5, 2)), f.rectification)
    with pytest.raises(CalibrationError, match="expected a Rectification"):
        points_to_left_frame(np.ones((5, 3)), f.rectification.R1)  # (was AttributeError)
    with pytest.raises(ConfigError, match="frame"):
        f.points("Left")
    # the rectified and left frames of an ideal rig are one frame: same points
    np.testing.assert_array_equal(f.points("left"), f.points("rectified"))


def test_rig_and_rectification_settings_are_checked():
    """Bad-input sweep of the public API: StereoRig.rectify took alpha NaN or 5 and a size
    (0, 0) into OpenCV without a word; rectify_pair / stereo_frame with no rig (None) raised a
    builtin AttributeError."""
    rig = StereoRig.ideal(Camera.from_fov(60.0, 160, 120), baseline_m=0.1)
    for kw in ({"alpha": np.nan}, {"alpha": 5.0}, {"size": (0, 0)}, {"size": (160.5, 120)},
               {"size": 160}):
        with pytest.raises(ConfigError, match="alpha|size"):
            rig.rectify(**kw)
    img = np.zeros((120, 160), np.uint8)
    for call in (lambda: rectify_pair(img, img, None), lambda: stereo_frame(img, img, "rig.yaml")):
        with pytest.raises(CalibrationError, match="StereoRig"):
            call()
    r = rig.rectify(alpha=1.0, size=(160, 120))  # valid settings: the ideal rig's identity
    np.testing.assert_array_equal(r.R1, np.eye(3))


def test_disparity_helpers_refuse_text_and_ragged_maps():
    """lr_consistency, fill_disparity_holes and points_from_disparity read a disparity map of
    text through numpy (a builtin ValueError, or numbers from text such as "3") and raised
    numpy's ValueError on a ragged list; a Q of text likewise. Now ImageInputError for the
    maps, ConfigError for Q; numbers give the same answers as before."""
    d = np.full((4, 6), 2.0, np.float32)
    d[1, 2] = np.nan
    # OpenCV's Q for f = 100 px, baseline 0.1 m, principal point (0, 0): Z = f B / d = 5 m
    Q = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 0, 100.0], [0, 0, 10.0, 0]])
    for bad in (d.astype(str), [[2.0, 2.0], [2.0]]):
        with pytest.raises(ImageInputError, match="^disp_left must hold numbers"):
            lr_consistency(bad, d)
        with pytest.raises(ImageInputError, match="^disp_right must hold numbers"):
            lr_consistency(d, bad)
        with pytest.raises(ImageInputError, match="^disparity must hold numbers"):
            fill_disparity_holes(bad)
        with pytest.raises(ImageInputError, match="^disparity must hold numbers"):
            points_from_disparity(bad, Q)
    with pytest.raises(ConfigError, match="^Q must be a 4x4 matrix of numbers"):
        points_from_disparity(d, Q.astype(str))
    np.testing.assert_array_equal(lr_consistency(d.tolist(), d), lr_consistency(d, d))
    np.testing.assert_array_equal(fill_disparity_holes(d.tolist()), fill_disparity_holes(d))
    pts = points_from_disparity(d, Q)
    np.testing.assert_allclose(pts[2, 4], [4 / 20, 2 / 20, 5.0])  # (u, v) / (d / B), Z
    assert np.all(np.isnan(pts[1, 2]))  # the invalid disparity


def test_depth_conversions_refuse_what_is_not_a_disparity_and_q_that_cannot_reproject():
    """An infinite disparity gave a depth of 0 m, complex disparities lost their imaginary
    part and bools were read as 1 px; a NaN or all-zero Q gave an all-NaN point cloud. Now
    inf is no measurement (NaN), the others an ImageInputError / ConfigError; an infinite
    depth is still 0 px of disparity."""
    np.testing.assert_array_equal(
        np.isnan(depth_from_disparity(np.array([np.inf, -np.inf, 20.0]), 500.0, 0.1)),
        [True, True, False])
    assert disparity_from_depth(np.array([np.inf]), 500.0, 0.1)[0] == 0.0
    for bad in (np.array([20.0 + 1j]), np.array([True]), "20"):
        with pytest.raises(ImageInputError, match="^disparity must hold numbers"):
            depth_from_disparity(bad, 500.0, 0.1)
        with pytest.raises(ImageInputError, match="^depth_m must hold numbers"):
            disparity_from_depth(bad, 500.0, 0.1)
    d = np.full((4, 6), 2.0)
    Q = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 0, 100.0], [0, 0, 10.0, 0]])
    assert np.all(np.isfinite(points_from_disparity(d, Q)))
    for Qb in (np.zeros((4, 4)), np.where(np.eye(4) > 0, np.nan, Q)):
        with pytest.raises(ConfigError, match="^Q must be a finite reprojection matrix"):
            points_from_disparity(d, Qb)


def test_an_image_that_is_not_8_bit_is_named_with_its_type():
    """An 8-bit left image and a float32 right one gave "stereo images must be 8-bit (got
    uint8)": the left image's type, which is fine. The message names the offending image and
    its type."""
    rng = np.random.default_rng(3)
    img = rng.integers(0, 255, (40, 80), dtype=np.uint8)
    with pytest.raises(ImageInputError, match="right image is float32"):
        compute_disparity(img, img.astype(np.float32))
    with pytest.raises(ImageInputError, match="left image is uint16"):
        compute_disparity(img.astype(np.uint16), img)


def test_disparity_flags_must_be_booleans():
    """pad_left="no" padded the images and fill_holes="no" filled the holes (any non-empty
    text is true); 0 and 1 were read as False and True. Flags are True or False (numpy's
    too)."""
    rng = np.random.default_rng(4)
    right = rng.integers(0, 255, (40, 100), dtype=np.uint8)
    left = np.roll(right, 6, axis=1)
    for name in ("pad_left", "fill_holes"):
        for bad in ("no", "False", 0, 1, None):
            with pytest.raises(ConfigError, match=name):
                compute_disparity(left, right, num_disparities=16, **{name: bad})
    unpadded = compute_disparity(left, right, num_disparities=16, pad_left=np.False_)
    assert np.isnan(unpadded[:, :10]).all()  # the leftmost columns unmatched, as pad_left=False
    padded = compute_disparity(left, right, num_disparities=16, pad_left=np.True_)
    assert np.nanmedian(padded[:, 20:]) == 6.0


def test_rectify_pair_checks_its_interpolation_for_every_rig():
    """rectify_pair passed its interpolation to cv2.remap unchecked: 99, -1, 2.5 or "linear"
    raised cv2.error, INTER_AREA (which remap does not support) gave INTER_LINEAR's images,
    and an already rectified rig took any value. A ConfigError for both rigs now; remap's
    own methods give what they gave (nearest: the maps' pixels exactly)."""
    cam = Camera(np.array([[400.0, 0, 160], [0, 400, 120], [0, 0, 1]]), width=320, height=240)
    turned = StereoRig(cam, cam, cv2.Rodrigues(np.array([0.0, 0.02, 0.01]))[0],
                       np.array([-0.1, 0, 0]))
    rectified = StereoRig(cam, cam, np.eye(3), np.array([-0.1, 0, 0]))
    assert not turned.is_rectified and rectified.is_rectified
    img = np.random.default_rng(0).integers(0, 255, (240, 320), dtype=np.uint8)
    for rig in (turned, rectified):
        for bad in (99, -1, 2.5, "linear", None, True, cv2.INTER_AREA):
            with pytest.raises(ConfigError, match="^interpolation must be one of cv2.remap"):
                rectify_pair(img, img, rig, interpolation=bad)
    _, maps = rectification_maps(turned)
    for method in (cv2.INTER_NEAREST, cv2.INTER_LINEAR, np.int64(cv2.INTER_CUBIC),
                   cv2.INTER_LANCZOS4):
        lr, _, _ = rectify_pair(img, img, turned, interpolation=method)
        np.testing.assert_array_equal(lr, cv2.remap(img, maps[0], maps[1], int(method)))


def test_rectification_maps_check_alpha_before_the_cache_key():
    """alpha=None or "x" was a builtin TypeError / ValueError of float(alpha), which built the
    cache key before StereoRig.rectify's range check; a ConfigError naming alpha and its range
    now, from rectify_pair too. Valid alphas give the maps they gave."""
    cam = Camera(np.array([[400.0, 0, 160], [0, 400, 120], [0, 0, 1]]), width=320, height=240)
    rig = StereoRig(cam, cam, np.eye(3), np.array([-0.1, 0, 0]))
    img = np.zeros((240, 320), np.uint8)
    for bad in (None, "x", "0.5", np.nan, np.inf, -0.1, 1.5, True, [0.5]):
        with pytest.raises(ConfigError, match=r"^alpha must be a finite number in \[0, 1\]"):
            rectification_maps(rig, alpha=bad)
        with pytest.raises(ConfigError, match=r"^alpha must be a finite number in \[0, 1\]"):
            rectify_pair(img, img, rig, alpha=bad)
    for alpha in (0.0, 0, np.float32(0.5), 1):
        rect, maps = rectification_maps(rig, alpha=alpha)
        want = rig.rectify(alpha=float(alpha))
        np.testing.assert_array_equal(rect.P1, want.P1)
        m1 = cv2.initUndistortRectifyMap(cam.K, cam.dist, want.R1, want.P1, want.size,
                                         cv2.CV_16SC2)
        np.testing.assert_array_equal(maps[0], m1[0])
        np.testing.assert_array_equal(maps[1], m1[1])
