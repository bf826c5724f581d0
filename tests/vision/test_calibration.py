"""Tests of hearsee.vision.calibration on synthetic chessboard renders with known ground truth
(intrinsics, distortion, stereo and thermal extrinsics) and on the real chessboard set."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from hearsee.errors import CalibrationError, ConfigError
from hearsee.vision import calibration as C
from hearsee.vision.camera import Camera, StereoRig, read_opencv_yaml
from hearsee.vision.io import read_image

PATTERN = (9, 6)
SQUARE = 0.025


def _rot_deg(R1: np.ndarray, R2: np.ndarray) -> float:
    return float(np.degrees(np.linalg.norm(cv2.Rodrigues(R1 @ R2.T)[0])))


@pytest.fixture(scope="module")
def synthetic():
    """Ten views of a 9x6 board seen by a distorted stereo pair and a low-res thermal camera."""
    left = Camera(K=np.array([[300.0, 0, 158.0], [0, 301.5, 122.0], [0, 0, 1]]),
                  dist=[-0.22, 0.07, 0.0006, -0.0004, 0.0], width=320, height=240)
    right = Camera(K=np.array([[296.0, 0, 163.0], [0, 297.0, 118.0], [0, 0, 1]]),
                   dist=[-0.2, 0.05, -0.0005, 0.0003, 0.0], width=320, height=240)
    R = cv2.Rodrigues(np.array([0.012, -0.035, 0.006]))[0]
    T = -R @ np.array([0.10, 0.002, -0.003])  # right centre 10 cm to the right
    thermal = Camera(K=np.array([[160.0, 0, 81.0], [0, 160.0, 59.0], [0, 0, 1]]),
                     dist=[-0.1, 0.0, 0.0, 0.0, 0.0], width=160, height=120)
    Rt = cv2.Rodrigues(np.array([-0.02, 0.03, 0.01]))[0]
    c_t = np.array([0.05, 0.045, 0.01])  # thermal centre in the left frame
    Tt = -Rt @ c_t
    truth = StereoRig(left, right, R, T, thermal, Rt, Tt)
    rng = np.random.default_rng(7)
    rays = {k: C._subpixel_rays(c, 2) for k, c in
            (("l", left), ("r", right), ("t", thermal))}
    obj = C.board_points(PATTERN, SQUARE)
    center = np.array([4 * SQUARE, 2.5 * SQUARE, 0.0])
    views = []
    for _ in range(10):
        rv = rng.uniform(-0.5, 0.5, 3) * np.array([1.0, 1.0, 0.3])
        Rb = cv2.Rodrigues(rv)[0]
        pos = np.array([0.05 + rng.uniform(-0.06, 0.06), 0.02 + rng.uniform(-0.05, 0.05),
                        rng.uniform(0.38, 0.5)])
        tb = pos - Rb @ center
        imgs = {}
        for key, cam, Rc, Tc, kw in (
            ("l", left, np.eye(3), np.zeros(3), dict(blur_px=0.5, noise=2.0)),
            ("r", right, R, T, dict(blur_px=0.5, noise=2.0)),
            ("t", thermal, Rt, Tt, dict(blur_px=0.9, noise=3.0, invert=True)),
        ):
            imgs[key] = C.render_chessboard(cam, Rc @ Rb, Rc @ tb + Tc, PATTERN, SQUARE,
                                            rng=rng, rays=rays[key], **kw)
        views.append(imgs)
    return truth, obj, views


@pytest.fixture(scope="module")
def corners(synthetic):
    """Detected corners per view (left, right and thermal relabelled to match the left)."""
    _, _, views = synthetic
    lp, rp, tp = [], [], []
    for v in views:
        a = C.find_corners(v["l"], PATTERN)
        b = C.find_corners(v["r"], PATTERN)
        t = C.find_corners(v["t"], PATTERN, try_inverted=True)
        assert a is not None and b is not None and t is not None
        lp.append(a)
        rp.append(C.match_labeling(a, b, PATTERN))
        tp.append(C.match_labeling(a, t, PATTERN))
    return lp, rp, tp


def test_board_helpers():
    assert C.parse_board("9x6") == (9, 6)
    with pytest.raises(CalibrationError, match="9x6"):
        C.parse_board("nine by six")
    for small in ("1x6", "2x5", "5x2"):  # (2 passed, and OpenCV's detectors raised cv2.error)
        with pytest.raises(CalibrationError, match="at least 3x3"):
            C.parse_board(small)
    assert C.parse_board("1000x6") == (1000, 6)
    for huge in ("99999999999x6", "6x1001"):  # (a builtin MemoryError in board_points before)
        with pytest.raises(CalibrationError, match="at most 1000 inner corners"):
            C.parse_board(huge)
    p = C.board_points((3, 3), 0.1)
    np.testing.assert_allclose(p[:4], [[0, 0, 0], [0.1, 0, 0], [0.2, 0, 0], [0, 0.1, 0]])
    with pytest.raises(CalibrationError, match="square"):
        C.board_points((3, 3), 0.0)
    for bad in (np.inf, np.nan):  # inf gave inf / NaN corners before 2026-11-26
        with pytest.raises(CalibrationError, match="square"):
            C.board_points((3, 3), bad)
    # the building blocks check the pattern too: (0, 0) and "9x6" were cv2.error, (-2, 3)
    # and (2.5, 3) numpy's errors; match_labeling's NaN a LinAlgError, a wrong count a
    # reshape ValueError
    img = np.full((60, 80), 128, np.uint8)
    for pat, words in (((0, 0), "at least 3x3"), ((-2, 3), "at least 3x3"),
                       ((2.5, 3), "whole numbers"), ("9x6", "whole numbers"),
                       ((3,), "whole numbers"), ((5, 1001), "at most 1000")):
        for func, args in ((C.board_points, (pat, 0.1)), (C.find_corners, (img, pat)),
                           (C.match_labeling, (np.zeros((9, 2)), np.zeros((9, 2)), pat))):
            with pytest.raises(CalibrationError, match=words):
                func(*args)
    assert C.check_pattern(np.array([9, 6])) == (9, 6)
    ref = C.board_points((3, 3), 10.0)[:, :2] + 50.0
    np.testing.assert_array_equal(C.match_labeling(ref, ref, (3, 3)), ref)
    for bad in (np.where(np.arange(18).reshape(9, 2) == 3, np.nan, ref), ref[:8]):
        with pytest.raises(CalibrationError, match="match_labeling"):
            C.match_labeling(ref, bad, (3, 3))


def test_corners_are_subpixel_accurate(synthetic):
    truth, obj, views = synthetic
    img = views[0]["l"]
    c = C.find_corners(img, PATTERN)
    assert c is not None and c.shape == (54, 2)
    # the true corners: find the pose that rendered them by matching the labelling
    found = []
    for cand in C._labelings(c, PATTERN):
        ok, rv, tv = cv2.solvePnP(obj, cand, truth.left.K, truth.left.dist)
        uv = truth.left.project(obj @ cv2.Rodrigues(rv)[0].T + tv.ravel())
        found.append(np.sqrt(np.mean(np.sum((cand - uv) ** 2, axis=1))))
    # with the true camera, the detected corners fit a board pose to a small fraction of a pixel
    assert min(found) < 0.2
    # no board -> None
    assert C.find_corners(np.full((120, 160), 128, np.uint8), PATTERN) is None


def test_full_chain_recovers_ground_truth(synthetic, corners):
    truth, obj, views = synthetic
    lp, rp, tp = corners
    cl = C.calibrate_camera(lp, obj, truth.left.size, name="left")
    cr = C.calibrate_camera(rp, obj, truth.right.size, name="right")
    ct = C.calibrate_camera(tp, obj, truth.thermal.size, model="simple", name="thermal")
    assert cl.rms_px < 0.3 and cr.rms_px < 0.3 and ct.rms_px < 0.3
    # focal lengths determined to +-0.1-0.4 % (measured): far from the degeneracy limit
    assert max(cl.focal_rel_std, cr.focal_rel_std, ct.focal_rel_std) < 0.006
    assert cl.per_view_px.shape == (10,)
    for est, ref in ((cl, truth.left), (cr, truth.right), (ct, truth.thermal)):
        assert est.camera.fx == pytest.approx(ref.fx, rel=0.006)
        assert est.camera.fy == pytest.approx(ref.fy, rel=0.006)
        assert est.camera.cx == pytest.approx(ref.cx, abs=2.0)
        assert est.camera.cy == pytest.approx(ref.cy, abs=2.0)
        assert est.camera.dist[0] == pytest.approx(ref.dist[0], abs=0.03)
    st = C.calibrate_stereo(lp, rp, obj, cl.camera, cr.camera)
    assert st.rms_px < 0.3
    assert st.per_view_px.shape == (10, 2)
    assert st.rig.baseline_m == pytest.approx(truth.baseline_m, rel=0.01)
    np.testing.assert_allclose(st.rig.T, truth.T, atol=0.002)
    assert _rot_deg(st.rig.R, truth.R) < 0.3  # ~1 px of principal-point uncertainty
    # rectified rig: focal and baseline sane, disparity positive
    rect = st.rig.rectification
    assert rect.baseline_m == pytest.approx(truth.baseline_m, rel=0.01)
    # thermal extrinsics, with the board triangulated by the stereo rig and without
    for right_points in (rp, None):
        te = C.calibrate_thermal_extrinsics(st.rig, ct.camera, lp, tp, obj,
                                            right_points=right_points)
        assert len(te.used) >= 8
        assert te.rms_px < 0.5
        assert _rot_deg(te.R, truth.R_thermal) < 0.6  # 1 thermal pixel = 0.36 deg
        np.testing.assert_allclose(-te.R.T @ te.T, truth.thermal_center_m, atol=0.005)


def test_thermal_extrinsics_survive_missing_and_outlier_views(synthetic, corners):
    truth, obj, views = synthetic
    lp, _, tp = corners
    tp = list(tp)
    tp[1] = None  # board not seen by the thermal camera
    tp[2] = tp[2] + np.float32([6.0, -4.0])  # a badly detected view
    rig = truth  # ground-truth stereo calibration
    te = C.calibrate_thermal_extrinsics(rig, truth.thermal, lp, tp, obj)
    assert 1 not in te.used and 2 not in te.used
    np.testing.assert_allclose(-te.R.T @ te.T, truth.thermal_center_m, atol=0.003)
    with pytest.raises(CalibrationError, match="not found in any"):
        C.calibrate_thermal_extrinsics(rig, truth.thermal, lp, [None] * len(lp), obj)


def test_thermal_extrinsics_refuse_degenerate_corners_and_limits(synthetic, corners):
    """Every thermal corner at one pixel gave T ~ [-23, -945, -7905] m with rms NaN, and a
    negative or NaN max_rotation_deg silently kept every view: CalibrationErrors now."""
    truth, obj, _ = synthetic
    lp, _, tp = corners
    flat = [np.full_like(np.asarray(tp[0]), 80.0)] * len(lp)
    with pytest.raises(CalibrationError, match="do not span a pixel"):
        C.calibrate_thermal_extrinsics(truth, truth.thermal, lp, flat, obj)
    for bad in (-1.0, np.nan):
        with pytest.raises(CalibrationError, match="max_rotation_deg"):
            C.calibrate_thermal_extrinsics(truth, truth.thermal, lp, tp, obj,
                                           max_rotation_deg=bad)
    with pytest.raises(CalibrationError, match="max_translation_m"):
        C.calibrate_thermal_extrinsics(truth, truth.thermal, lp, tp, obj, max_translation_m=0.0)


def test_thermal_extrinsics_honour_a_skewed_thermal_camera(synthetic):
    # exact projections of board poses into the left camera and a thermal camera whose K has a
    # skew of 8 px: the extrinsics must come back exactly (OpenCV's PnP ignores the skew)
    truth, obj, _ = synthetic
    K = truth.thermal.K.copy()
    K[0, 1] = 8.0
    thermal = Camera(K=K, dist=truth.thermal.dist, width=160, height=120, name="thermal")
    rig = StereoRig(truth.left, truth.right, truth.R, truth.T, thermal, truth.R_thermal,
                    truth.T_thermal)
    rng = np.random.default_rng(11)
    lp, tp = [], []
    for _ in range(6):
        Rb = cv2.Rodrigues(rng.uniform(-0.4, 0.4, 3))[0]
        X = obj @ Rb.T + np.array([0.0, 0.0, rng.uniform(0.4, 0.5)]) - Rb @ obj.mean(axis=0)
        lp.append(truth.left.project(X).astype(np.float32))
        tp.append(thermal.project(X @ truth.R_thermal.T + truth.T_thermal))
    te = C.calibrate_thermal_extrinsics(rig, thermal, lp, tp, obj)
    assert len(te.used) == 6 and te.rms_px < 0.05
    assert _rot_deg(te.R, truth.R_thermal) < 0.05
    np.testing.assert_allclose(-te.R.T @ te.T, truth.thermal_center_m, atol=5e-4)


def test_stereo_routines_refuse_a_skewed_camera(synthetic, corners):
    truth, obj, _ = synthetic
    lp, rp, _ = corners
    K = truth.right.K.copy()
    K[0, 1] = 3.0
    right = Camera(K=K, dist=truth.right.dist, width=320, height=240, name="right")
    rig = StereoRig(truth.left, right, truth.R, truth.T)
    with pytest.raises(CalibrationError, match="skewed"):
        rig.rectify()
    with pytest.raises(CalibrationError, match="skewed"):
        C.calibrate_stereo(lp, rp, obj, truth.left, right)
    # an already rectified rig too: its remap would drop the skew just the same (square
    # pixels: with fx != fy a rig is not already rectified)
    Ksq = K.copy()
    Ksq[1, 1] = Ksq[0, 0]
    pinhole = Camera(K=Ksq, width=320, height=240)
    rectified = StereoRig(pinhole, pinhole, np.eye(3), np.array([-0.1, 0.0, 0.0]))
    assert rectified.is_rectified
    with pytest.raises(CalibrationError, match="skewed"):
        rectified.rectify()


def test_too_few_views_and_mismatch_raise(synthetic, corners):
    truth, obj, views = synthetic
    lp = corners[0][:2]
    with pytest.raises(CalibrationError, match="at least 3 images"):
        C.calibrate_camera(lp, obj, truth.left.size)
    with pytest.raises(CalibrationError, match="right views"):
        C.calibrate_stereo(lp, lp[:1], obj, truth.left, truth.right)
    # a NaN reject factor rejected nothing without a word; complex corners lost their
    # imaginary part
    lp3 = list(corners[0][:3])
    for bad in (np.nan, -1.0):
        with pytest.raises(CalibrationError, match="reject_factor"):
            C.calibrate_camera(lp3, obj, truth.left.size, reject_factor=bad)
    for bad in (lp3[0] + 0j, np.where(np.arange(lp3[0].size).reshape(lp3[0].shape) == 0, np.nan,
                                       lp3[0])):
        with pytest.raises(CalibrationError, match="finite real pixel"):
            C.calibrate_camera([bad, *lp3[1:]], obj, truth.left.size)


def _board_views(n: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """``n`` random poses ``(R_board, t_board)`` (board -> left optical frame, metres) of the
    9x6 board 0.4-0.5 m in front of the left camera."""
    rng = np.random.default_rng(seed)
    center = np.array([4 * SQUARE, 2.5 * SQUARE, 0.0])
    poses = []
    for _ in range(n):
        Rb = cv2.Rodrigues(rng.uniform(-0.5, 0.5, 3) * np.array([1.0, 1.0, 0.3]))[0]
        pos = np.array([0.05 + rng.uniform(-0.05, 0.05), 0.02 + rng.uniform(-0.04, 0.04),
                        rng.uniform(0.4, 0.5)])
        poses.append((Rb, pos - Rb @ center))
    return poses


@pytest.mark.parametrize("model, true_dist, n_free", [
    ("radial", [-0.2, 0.0, 0.0, 0.0, 0.0], 1),        # k1 only
    ("simple", [-0.2, 0.05, 0.001, -0.0008, 0.0], 4),  # k1, k2, p1, p2 (k3 fixed)
])
def test_stereo_refinement_keeps_the_distortion_model(model, true_dist, n_free):
    """Exact corners (+0.05 px noise) of known boards seen through known lenses of the chosen
    model: the joint refinement must not free the coefficients the model fixes at zero."""
    left = Camera(K=np.array([[300.0, 0, 158.0], [0, 301.5, 122.0], [0, 0, 1]]),
                  dist=true_dist, width=320, height=240)
    right = Camera(K=np.array([[296.0, 0, 163.0], [0, 297.0, 118.0], [0, 0, 1]]),
                   dist=true_dist, width=320, height=240)
    R = cv2.Rodrigues(np.array([0.012, -0.035, 0.006]))[0]
    T = -R @ np.array([0.10, 0.002, -0.003])
    obj = C.board_points(PATTERN, SQUARE).astype(float)
    rng = np.random.default_rng(1)
    lp, rp = [], []
    for Rb, tb in _board_views(8, seed=2):
        X = obj @ Rb.T + tb
        for cam, pts, Xc in ((left, lp, X), (right, rp, X @ R.T + T)):
            pts.append(cam.project(Xc) + rng.normal(0.0, 0.05, (len(obj), 2)))
    cl = C.calibrate_camera(lp, obj, left.size, model=model, name="left")
    cr = C.calibrate_camera(rp, obj, right.size, model=model, name="right")
    st = C.calibrate_stereo(lp, rp, obj, cl.camera, cr.camera, model=model)
    assert st.refined  # the joint refinement was run and kept
    for est, ref in ((st.rig.left, left), (st.rig.right, right)):
        np.testing.assert_array_equal(est.dist[n_free:], 0.0)
        assert est.dist[0] == pytest.approx(ref.dist[0], abs=0.01)
        assert est.fx == pytest.approx(ref.fx, rel=0.003)
        assert est.fy == pytest.approx(ref.fy, rel=0.003)
    np.testing.assert_allclose(st.rig.T, T, atol=0.001)
    with pytest.raises(CalibrationError, match="model must be"):
        C.calibrate_stereo(lp, rp, obj, cl.camera, cr.camera, model="fisheye")


def _k1_rig_files(tmp_path, n_views: int = 6):
    """PNG files of ``n_views`` 9x6 boards rendered through a stereo pair of known k1-only
    lenses with square pixels: ``(left files, right files, left camera, right camera, T)``."""
    left = Camera(K=np.array([[300.0, 0, 158.0], [0, 300.0, 122.0], [0, 0, 1]]),
                  dist=[-0.2, 0.0, 0.0, 0.0, 0.0], width=320, height=240)
    right = Camera(K=np.array([[296.0, 0, 163.0], [0, 296.0, 118.0], [0, 0, 1]]),
                   dist=[-0.18, 0.0, 0.0, 0.0, 0.0], width=320, height=240)
    R = cv2.Rodrigues(np.array([0.012, -0.035, 0.006]))[0]
    T = -R @ np.array([0.10, 0.002, -0.003])
    rng = np.random.default_rng(7)
    files: dict[str, list] = {"left": [], "right": []}
    for i, (Rb, tb) in enumerate(_board_views(n_views, seed=7)):
        for key, cam, Rc, Tc in (("left", left, np.eye(3), np.zeros(3)), ("right", right, R, T)):
            img = C.render_chessboard(cam, Rc @ Rb, Rc @ tb + Tc, PATTERN, SQUARE, rng=rng,
                                      rays=C._subpixel_rays(cam, 2), blur_px=0.5, noise=2.0)
            f = tmp_path / f"{key}{i}.png"
            cv2.imwrite(str(f), img)
            files[key].append(f)
    return files["left"], files["right"], left, right, T


def test_calibrate_rig_keeps_model_and_aspect_in_the_stereo_refinement(tmp_path):
    """`hearsee calibrate --model radial --fix-aspect`: boards rendered through known k1-only
    lenses with square pixels; the written rig must keep fx = fy and k2 = p1 = p2 = k3 = 0."""
    lf, rf, left, right, T = _k1_rig_files(tmp_path)
    res = C.calibrate_rig(lf, rf, PATTERN, SQUARE, model="radial", fix_aspect=True)
    for est, ref in ((res.rig.left, left), (res.rig.right, right)):
        assert est.fy == pytest.approx(est.fx, rel=1e-12)
        np.testing.assert_array_equal(est.dist[1:], 0.0)
        assert est.fx == pytest.approx(ref.fx, rel=0.02)
        assert est.dist[0] == pytest.approx(ref.dist[0], abs=0.03)
    assert res.rig.baseline_m == pytest.approx(np.linalg.norm(T), rel=0.02)


def test_a_board_size_that_is_a_sub_grid_of_the_real_board_is_refused(tmp_path):
    """--board 3x3 or 4x3 on a 9x6 board: OpenCV finds such a sub-grid in every image, at a
    different place in each, and the fit was written as the rig (RMS 6-9 px, fx a third of the
    truth). The right size calibrates to a fraction of a pixel."""
    lf, rf, left, _, _ = _k1_rig_files(tmp_path, n_views=8)
    for wrong in ((3, 3), (4, 3)):
        with pytest.raises(CalibrationError, match=rf"RMS reprojection error left .* px.*"
                                                   rf"{wrong[0]}x{wrong[1]} inner corners"):
            C.calibrate_rig(lf, rf, wrong, SQUARE)
    res = C.calibrate_rig(lf, rf, PATTERN, SQUARE)
    assert max(res.rms_left_px, res.rms_right_px, res.rms_stereo_px) < 0.3 < C.MAX_RMS_PX
    assert res.rig.left.fx == pytest.approx(left.fx, rel=0.02)


@pytest.mark.shared
def test_real_chessboard_pairs_close_to_reference(shared_data):
    d = shared_data / "vision" / "chessboard_stereo"
    if not d.is_dir():
        pytest.skip("chessboard_stereo not present")
    ids = ["01", "04", "07", "10", "13", "16"]
    lp, rp = [], []
    for i in ids:
        a = C.find_corners(read_image(d / f"left{i}.jpg"), PATTERN)
        b = C.find_corners(read_image(d / f"right{i}.jpg"), PATTERN)
        if a is not None and b is not None:
            lp.append(a)
            rp.append(C.match_labeling(a, b, PATTERN))
    assert len(lp) >= 5
    obj = C.board_points(PATTERN, 1.0)
    size = (640, 512)
    cl = C.calibrate_camera(lp, obj, size, fix_aspect=True)
    cr = C.calibrate_camera(rp, obj, size, fix_aspect=True)
    # measured 0.64 % / 0.70 %: well inside the degeneracy limit
    assert max(cl.focal_rel_std, cr.focal_rel_std) < 0.01 < C.MAX_FOCAL_REL_STD
    ref = read_opencv_yaml(d / "reference_intrinsics.yml")
    assert cl.camera.fx == pytest.approx(ref["M1"][0, 0], rel=0.10)
    assert cr.camera.fx == pytest.approx(ref["M2"][0, 0], rel=0.10)
    assert cl.rms_px < 1.0
    st = C.calibrate_stereo(lp, rp, obj, cl.camera, cr.camera)
    ref_T = read_opencv_yaml(d / "reference_extrinsics.yml")["T"].ravel()
    # the reference was computed in its own (unknown) square units: compare directions
    cos = st.rig.T @ ref_T / (np.linalg.norm(st.rig.T) * np.linalg.norm(ref_T))
    assert cos > 0.98


def test_corners_in_16bit_thermal_image(synthetic, corners):
    """Raw 16-bit thermal counts (heated board = warm squares) are normalised before detection."""
    _, _, views = synthetic
    raw = views[0]["t"].astype(np.uint16) * 40 + 29000
    c = C.find_corners(raw, PATTERN, try_inverted=True)
    assert c is not None
    c = C.match_labeling(corners[0][0], c, PATTERN)
    np.testing.assert_allclose(c, corners[2][0], atol=0.05)


def _projected_views(tilt_deg: float, n: int = 8, seed: int = 0) -> tuple[Camera, list]:
    """Exact corners (+0.1 px noise) of ``n`` 9x6 boards 0.55-0.76 m in front of a known
    camera (fx = 300 px), tilted by up to ``tilt_deg`` about x and y (any in-plane roll)."""
    cam = Camera(K=np.array([[300.0, 0, 159.5], [0, 300.0, 119.5], [0, 0, 1]]),
                 dist=[-0.1, 0.02, 0.0, 0.0, 0.0], width=320, height=240)
    obj = C.board_points(PATTERN, SQUARE)
    rng = np.random.default_rng(seed)
    views = []
    for i in range(n):
        ax, ay = np.radians(tilt_deg) * rng.uniform(-1, 1, 2)
        Rb = cv2.Rodrigues(np.array([ax, ay, rng.uniform(-0.2, 0.2)]))[0]
        tb = np.array([0.0, 0.0, 0.55 + 0.03 * i]) - Rb @ np.array([4 * SQUARE, 2.5 * SQUARE, 0])
        views.append(cam.project(obj @ Rb.T + tb) + rng.normal(0.0, 0.1, (len(obj), 2)))
    return cam, views


def test_image_size_given_as_height_width_is_refused():
    """image_size (480, 640) for a 640x480 camera was accepted: the camera came back 480 px
    wide with a 33-deg field of view for a 44-deg lens (K itself right). Corners outside the
    image now refuse it, with the hint when they fit the swapped size."""
    cam, views = _projected_views(35.0)
    views = [v + [80.0, 0.0] for v in views]  # (boards right of the centre: u up to ~300)
    assert max(v[:, 0].max() for v in views) > cam.height + 1
    obj = C.board_points(PATTERN, SQUARE)
    with pytest.raises(CalibrationError, match=r"lie outside the 240x320 image .*image_size "
                       r"is \(width, height\)"):
        C.calibrate_camera(views, obj, (cam.height, cam.width))
    with pytest.raises(CalibrationError, match="image_size must be"):
        C.calibrate_camera(views, obj, (0, 240))


def test_boards_parallel_to_each_other_are_refused():
    """Zhang's degenerate case: boards that never tilt (all facing the camera) fit to a
    fraction of a pixel with any focal length -- fx came out 700-3000 px for 300. OpenCV's own
    stdDeviationsIntrinsics hides it (pseudo-inverse: +-0.1 %); the Schur-complement
    covariance does not. Boards tilted +-5 deg give fx +-6 %: refused too; +-30 deg: +-0.5 %."""
    obj = C.board_points(PATTERN, SQUARE)
    for tilt in (0.0, 5.0):
        cam, views = _projected_views(tilt)
        with pytest.raises(CalibrationError, match=r"focal length poorly determined .*tilt the "
                                                   r"board more"):
            C.calibrate_camera(views, obj, cam.size, name="left")
        with pytest.raises(CalibrationError, match="poorly determined"):
            C.calibrate_camera(views, obj, cam.size, model="radial", fix_aspect=True)
    cam, views = _projected_views(30.0)
    res = C.calibrate_camera(views, obj, cam.size)
    assert res.focal_rel_std < 0.01
    assert abs(res.camera.fx / 300.0 - 1.0) < 3 * res.focal_rel_std  # the std is honest
    # the same number as OpenCV's when the problem is well posed
    out = cv2.calibrateCameraExtended([obj.reshape(-1, 1, 3)] * 8,
                                      [v.astype(np.float32).reshape(-1, 1, 2) for v in views],
                                      cam.size, None, None)
    sd = out[5].ravel()
    assert res.focal_rel_std == pytest.approx(max(sd[0] / out[1][0, 0], sd[1] / out[1][1, 1]),
                                              rel=0.02)
    # the limit can be relaxed
    _, views = _projected_views(5.0)
    assert C.calibrate_camera(views, obj, cam.size, max_focal_rel_std=0.5).focal_rel_std > 0.03


def test_rendered_fronto_parallel_boards_are_refused():
    """The sweep's reproducer: 8 rendered boards facing the camera, shifted sideways, gave RMS
    0.05 px and fx 693 px for a 300 px camera."""
    cam = Camera(K=np.array([[300.0, 0, 159.5], [0, 300.0, 119.5], [0, 0, 1]]),
                 dist=[-0.1, 0.02, 0.0, 0.0, 0.0], width=320, height=240)
    pattern, square = (7, 5), 0.03
    rays = C._subpixel_rays(cam, 2)
    rng = np.random.default_rng(1)
    views = []
    for i in range(8):
        img = C.render_chessboard(cam, np.eye(3), np.array([-0.09 + 0.01 * i, -0.06, 0.6]),
                                  pattern, square, rays=rays, blur_px=0.6, noise=1.0, rng=rng)
        views.append(C.find_corners(img, pattern))
    with pytest.raises(CalibrationError, match="focal length poorly determined"):
        C.calibrate_camera(views, C.board_points(pattern, square), cam.size)


def test_identical_left_and_right_views_are_refused(synthetic, corners):
    """The same corners (the same image files) for both cameras calibrated to a rig with a
    baseline of ~5e-15 m and no error."""
    truth, obj, _ = synthetic
    lp, _, _ = corners
    with pytest.raises(CalibrationError, match="the left and right images are the same"):
        C.calibrate_stereo(lp, lp, obj, truth.left, truth.left)


def test_find_corners_upscale_must_be_a_positive_integer(synthetic):
    """upscale=0 returned infinite corners, a negative one garbage."""
    img = synthetic[2][0]["l"]
    for bad in (0, -2, 1.5, True, "2"):
        with pytest.raises(ConfigError, match=r"upscale must be an integer >= 1"):
            C.find_corners(img, PATTERN, upscale=bad)
    c = C.find_corners(img, PATTERN, upscale=np.int64(1))
    assert c is not None and np.all(np.isfinite(c))
    # a factor beyond MAX_UPSCALED_PX on a side: one line, not OpenCV's out-of-memory error
    with pytest.raises(ConfigError, match=r"upscale 1000000 makes the"):
        C.find_corners(img, PATTERN, upscale=10**6)


def test_thermal_extrinsics_refuse_views_that_do_not_match():
    """Fewer right views than left ones raised a bare IndexError, a view with another number
    of corners than the board a cv2.error from solvePnP; exact synthetic views still give the
    thermal camera's known position."""
    cam = Camera.from_fov(60.0, 320, 240)
    th = Camera.from_fov(40.0, 160, 120)
    rig = StereoRig.ideal(cam, 0.1, thermal=th, thermal_offset_m=(0.05, 0.04, 0.0))
    obj = C.board_points(PATTERN, SQUARE)
    rng = np.random.default_rng(1)
    lp, rp, tp = [], [], []
    for _ in range(5):
        X = obj @ cv2.Rodrigues(rng.uniform(-0.4, 0.4, 3))[0].T + np.array([-0.1, -0.06, 0.5])
        lp.append(cam.project(X))
        rp.append(rig.right.project(rig.left_to_right(X)))
        tp.append(rig.project_thermal(X))
    te = C.calibrate_thermal_extrinsics(rig, th, lp, tp, obj, right_points=rp)
    np.testing.assert_allclose(-te.R.T @ te.T, [0.05, 0.04, 0.0], atol=1e-6)
    with pytest.raises(CalibrationError, match="right views"):
        C.calibrate_thermal_extrinsics(rig, th, lp, tp, obj, right_points=rp[:3])
    for which in ("left", "thermal", "right"):
        pts = {"left": list(lp), "thermal": list(tp), "right": list(rp)}
        pts[which][1] = pts[which][1][:20]
        with pytest.raises(CalibrationError, match=f"{which} view 1 has 20 corners"):
            C.calibrate_thermal_extrinsics(rig, th, pts["left"], pts["thermal"], obj,
                                           right_points=pts["right"])


def _fake_image_files(monkeypatch, corners: dict, sizes: dict) -> None:
    """Make :func:`C.calibrate_rig` read ``corners[name]`` (None: no board) as the corners
    found in the "image file" ``name`` of camera ``name.rstrip('0123456789')`` (image size
    ``sizes[camera]``), instead of reading and searching real images."""
    found = {}

    def read_image(path, mode="bgr", expected_size=None):  # (read_thermal's call too)
        name = str(path)
        w, h = sizes[name.rstrip("0123456789")]
        img = np.zeros((h, w), np.uint8)
        found[id(img)] = corners[name]
        return img

    monkeypatch.setattr("hearsee.vision.io.read_image", read_image)
    monkeypatch.setattr(C, "find_corners", lambda img, pattern, **kw: found[id(img)])


def _rig_corners(truth: StereoRig, n: int = 8, seed: int = 0) -> dict:
    """Corners (+0.05 px noise) of ``n`` known 9x6 boards 0.4-0.5 m in front of the stereo +
    thermal rig ``truth``, keyed ``left{i}``, ``right{i}``, ``thermal{i}`` (pixels, float32)."""
    obj = C.board_points(PATTERN, SQUARE)
    center = np.array([4 * SQUARE, 2.5 * SQUARE, 0.0])
    rng = np.random.default_rng(seed)
    corners = {}
    for i in range(n):
        Rb = cv2.Rodrigues(rng.uniform(-0.5, 0.5, 3) * np.array([1.0, 1.0, 0.3]))[0]
        X = obj @ Rb.T + np.array([0.02, 0.0, rng.uniform(0.4, 0.5)]) - Rb @ center
        for key, uv in (("left", truth.left.project(X)),
                        ("right", truth.right.project(truth.left_to_right(X))),
                        ("thermal", truth.project_thermal(X))):
            corners[f"{key}{i}"] = (uv + rng.normal(0.0, 0.05, uv.shape)).astype(np.float32)
    return corners


def test_thermal_outliers_of_the_intrinsics_do_not_feed_the_extrinsics(monkeypatch):
    """Exact corners (+0.05 px noise) of 8 known boards seen by a known stereo + thermal rig;
    one thermal view is smeared: its corners jitter by +-4 px and are off by 2 px. The thermal
    intrinsics drop it as an outlier; the extrinsics used it all the same (its pose is close
    enough to the others' to pass their own outlier test) and put the thermal camera 7.3 mm
    off its true position (measured), 1.5 mm without it. (Corners off by tens of pixels fail
    the extrinsics' own test: those views were already left out.)"""
    cam = Camera.from_fov(60.0, 320, 240)
    th = Camera(K=np.array([[160.0, 0, 81.0], [0, 160.0, 59.0], [0, 0, 1]]),
                dist=[-0.1, 0.0, 0.0, 0.0, 0.0], width=160, height=120)
    truth = StereoRig.ideal(cam, 0.1, thermal=th, thermal_offset_m=(0.05, 0.04, 0.0))
    corners = _rig_corners(truth)
    checker = np.where((np.arange(54) % 9 + np.arange(54) // 9) % 2 == 0, 1.0, -1.0)
    corners["thermal3"] += np.float32([2.0, 0.0]) + 4.0 * np.c_[checker, 0 * checker]
    _fake_image_files(monkeypatch, corners, {"left": cam.size, "right": cam.size,
                                             "thermal": th.size})
    files = {k: [f"{k}{i}" for i in range(8)] for k in ("left", "right", "thermal")}
    res = C.calibrate_rig(files["left"], files["right"], PATTERN, SQUARE,
                          thermal_files=files["thermal"])
    err_mm = 1000 * np.linalg.norm(res.rig.thermal_center_m - truth.thermal_center_m)
    assert err_mm < 2.5
    # the dropped view is reported, and only it; it has no thermal extrinsics error
    assert [v.rejected_thermal for v in res.views] == [i == 3 for i in range(8)]
    assert not any(v.rejected for v in res.views)
    assert np.isnan(res.views[3].err_thermal)
    assert all(np.isfinite(v.err_thermal) for i, v in enumerate(res.views) if i != 3)


_RATIONAL = [-0.25, 0.08, 0.001, -0.0008, -0.01, 0.05, 0.02, 0.003]  # k1 k2 p1 p2 k3 k4 k5 k6
_THIN_PRISM = _RATIONAL + [0.002, -0.001, 0.0015, 0.001]  # + s1 s2 s3 s4


def _exact_stereo_views(dist, n: int = 10):
    """Exact corners (+0.05 px noise) of ``n`` known 9x6 boards seen by a stereo pair whose
    lenses have the distortion ``dist``: ``(left, right, R, T, 3D corners per view (left
    frame), left corners, right corners)``."""
    left = Camera(K=np.array([[300.0, 0, 158.0], [0, 301.5, 122.0], [0, 0, 1]]), dist=dist,
                  width=320, height=240)
    right = Camera(K=np.array([[296.0, 0, 163.0], [0, 297.0, 118.0], [0, 0, 1]]), dist=dist,
                   width=320, height=240)
    R = cv2.Rodrigues(np.array([0.012, -0.035, 0.006]))[0]
    T = -R @ np.array([0.10, 0.002, -0.003])
    obj = C.board_points(PATTERN, SQUARE).astype(float)
    rng = np.random.default_rng(1)
    Xs, lp, rp = [], [], []
    for Rb, tb in _board_views(n, seed=3):
        X = obj @ Rb.T + tb
        Xs.append(X)
        lp.append(left.project(X) + rng.normal(0.0, 0.05, (len(obj), 2)))
        rp.append(right.project(X @ R.T + T) + rng.normal(0.0, 0.05, (len(obj), 2)))
    return left, right, R, T, Xs, lp, rp


def _max_projection_gap_px(rig: StereoRig, left: Camera, right: Camera, R, T, Xs) -> float:
    """Largest pixel distance, over the boards' true 3D corners, between their projections by
    the calibrated rig and by the true cameras (both images)."""
    X = np.vstack(Xs)
    gl = np.linalg.norm(rig.left.project(X) - left.project(X), axis=1)
    gr = np.linalg.norm(rig.right.project(rig.left_to_right(X)) - right.project(X @ R.T + T),
                        axis=1)
    return float(max(gl.max(), gr.max()))


def test_rational_lenses_round_trip_through_camera_and_stereo_calibration():
    """8-coefficient (rational) lenses: calibrate_camera(model='rational') then
    calibrate_stereo(model='rational') give back the rig; only k1..k6, p1, p2 are estimated.
    Measured: T 0.3 mm off, R 0.15 deg, fx 0.1 %, projections within 0.29 px of the truth (the
    rational model's coefficients trade off against each other: the lens function comes back,
    not the coefficients). calibrate_camera refused the right camera ("focal length poorly
    determined (not at all)") until the focal length's uncertainty ignored that trade-off."""
    left, right, R, T, Xs, lp, rp = _exact_stereo_views(_RATIONAL)
    obj = C.board_points(PATTERN, SQUARE)
    cl = C.calibrate_camera(lp, obj, left.size, model="rational", name="left")
    cr = C.calibrate_camera(rp, obj, right.size, model="rational", name="right")
    assert max(cl.rms_px, cr.rms_px) < 0.1
    st = C.calibrate_stereo(lp, rp, obj, cl.camera, cr.camera, model="rational")
    assert st.refined and st.rms_px < 0.1
    for est, ref in ((st.rig.left, left), (st.rig.right, right)):
        assert np.all(est.dist[5:8] != 0.0)  # k4..k6 estimated
        np.testing.assert_array_equal(est.dist[8:], 0.0)  # no thin prism, no tilt
        assert est.fx == pytest.approx(ref.fx, rel=0.003)
        assert est.fy == pytest.approx(ref.fy, rel=0.003)
    np.testing.assert_allclose(st.rig.T, T, atol=0.001)
    assert _rot_deg(st.rig.R, R) < 0.3
    assert _max_projection_gap_px(st.rig, left, right, R, T, Xs) < 0.6
    # it rectifies and survives a rig file
    assert st.rig.rectify().baseline_m == pytest.approx(np.linalg.norm(T), rel=0.01)
    again = StereoRig.from_dict(st.rig.to_dict())
    np.testing.assert_array_equal(again.left.dist, st.rig.left.dist)


def test_stereo_calibration_keeps_the_thin_prism_terms_of_12_coefficient_cameras():
    """Cameras of a calibration file with 12 coefficients (rational + thin prism s1..s4, which
    calibrate_camera does not estimate): calibrate_stereo (model=None: rational) refines k1..k6,
    p1, p2 and the extrinsics and keeps s1..s4 as given. Measured: T 0.2 mm off, R 0.02 deg,
    projections within 0.13 px of the truth."""
    left, right, R, T, Xs, lp, rp = _exact_stereo_views(_THIN_PRISM)
    obj = C.board_points(PATTERN, SQUARE)
    st = C.calibrate_stereo(lp, rp, obj, left, right)
    assert st.refined and st.rms_px < 0.1
    for est in (st.rig.left, st.rig.right):
        np.testing.assert_array_equal(est.dist[8:12], _THIN_PRISM[8:])
        np.testing.assert_array_equal(est.dist[12:], 0.0)
    np.testing.assert_allclose(st.rig.T, T, atol=0.0005)
    assert _rot_deg(st.rig.R, R) < 0.1
    assert _max_projection_gap_px(st.rig, left, right, R, T, Xs) < 0.25
    assert st.rig.rectify().baseline_m == pytest.approx(np.linalg.norm(T), rel=0.01)


def test_rational_model_focal_length_uncertainty_ignores_the_coefficients_trade_off():
    """The rational model's k1..k3 and k4..k6 trade off against each other (the intrinsics'
    information matrix is singular to 1e-16): its focal length was reported as "not at all"
    determined and every rational calibration of boards tilted +-30 deg refused, though fx came
    out within 1.2 % (2 sigma) of the truth. Boards facing the camera are still refused."""
    obj = C.board_points(PATTERN, SQUARE)
    cam, views = _projected_views(30.0)
    res = C.calibrate_camera(views, obj, cam.size, model="rational")
    assert res.focal_rel_std < 0.01  # measured 0.6 %, like the other models' 0.56-0.58 %
    assert abs(res.camera.fx / 300.0 - 1.0) < 3 * res.focal_rel_std
    _, views = _projected_views(0.0)
    with pytest.raises(CalibrationError, match="focal length poorly determined"):
        C.calibrate_camera(views, obj, cam.size, model="rational")


def test_stereo_refinement_of_a_standard_and_a_rational_camera_keeps_both_models():
    """A 5-coefficient (standard) left lens beside an 8-coefficient (rational) right one,
    model=None: OpenCV's flags hold for both cameras. The rational flags freed k4..k6 of the
    standard camera (measured -0.003, 0.029, -0.014: another lens model); the standard ones
    made OpenCV return 5 coefficients for both (the rational camera's k4..k6 dropped: 0.65 px
    off). Now k4..k6 are not refined: 0 and 5 coefficients for the standard camera, as given
    for the rational one; both lenses still project within 0.35 px of the truth."""
    std = [-0.2, 0.05, 0.001, -0.0008, 0.01]
    left, right0, R, T, Xs, lp, _ = _exact_stereo_views(std)
    right = Camera(K=right0.K, dist=_RATIONAL, width=320, height=240)
    rng = np.random.default_rng(5)
    rp = [right.project(X @ R.T + T) + rng.normal(0.0, 0.05, (len(X), 2)) for X in Xs]
    st = C.calibrate_stereo(lp, rp, C.board_points(PATTERN, SQUARE), left, right)
    assert st.refined
    assert st.rig.left.dist.shape == (5,)
    np.testing.assert_array_equal(st.rig.right.dist[5:8], _RATIONAL[5:])
    np.testing.assert_array_equal(st.rig.right.dist[8:], 0.0)
    np.testing.assert_allclose(st.rig.T, T, atol=0.001)
    assert _max_projection_gap_px(st.rig, left, right, R, T, Xs) < 0.35


def test_thermal_view_without_a_left_board_is_not_reported_rejected(monkeypatch):
    """A view whose board the thermal camera found but the left camera did not cannot enter
    the thermal extrinsics (they need the left corners); it was not left out by the thermal
    calibration's outlier tests, so ``rejected_thermal`` stays False (it was True: "i not in
    te.used" held for every view the extrinsics never saw)."""
    cam = Camera.from_fov(60.0, 320, 240)
    th = Camera.from_fov(40.0, 160, 120)
    truth = StereoRig.ideal(cam, 0.1, thermal=th, thermal_offset_m=(0.05, 0.04, 0.0))
    corners = _rig_corners(truth)
    corners["left5"] = None  # board not found in the left image
    _fake_image_files(monkeypatch, corners, {"left": cam.size, "right": cam.size,
                                             "thermal": th.size})
    files = {k: [f"{k}{i}" for i in range(8)] for k in ("left", "right", "thermal")}
    res = C.calibrate_rig(files["left"], files["right"], PATTERN, SQUARE,
                          thermal_files=files["thermal"])
    assert not res.views[5].found_left and res.views[5].found_thermal
    assert not any(v.rejected_thermal for v in res.views)
    assert np.isnan(res.views[5].err_thermal)


def test_render_chessboard_takes_a_seed_as_other_random_functions_do():
    """rng=3 was numpy's AttributeError ('int' object has no attribute 'normal'); text is
    a ConfigError. A seed draws the noise a Generator of that seed draws; None is seed 0."""
    cam = Camera.from_fov(60.0, 64, 48)
    args = (cam, np.eye(3), np.array([-0.05, -0.03, 0.5]), (4, 3), 0.02)
    by_seed = C.render_chessboard(*args, noise=5.0, rng=3)
    by_gen = C.render_chessboard(*args, noise=5.0, rng=np.random.default_rng(3))
    np.testing.assert_array_equal(by_seed, by_gen)
    np.testing.assert_array_equal(C.render_chessboard(*args, noise=5.0),
                                  C.render_chessboard(*args, noise=5.0, rng=0))
    assert np.any(by_seed != C.render_chessboard(*args, noise=5.0, rng=4))
    with pytest.raises(ConfigError, match="rng"):
        C.render_chessboard(*args, noise=5.0, rng="three")


@pytest.mark.parametrize("left, right", [("cb/left*.png", "cb/right*.png"),
                                         ("cb/l*.png", "cb/r*.png"), (None, None)])
def test_calibrate_rig_refuses_a_glob_pattern_and_none(left, right):
    """A pattern string was taken as a list of its characters ("12 left images but 13 right
    images", or, at equal lengths, "c: image file not found"); None a builtin TypeError."""
    with pytest.raises(CalibrationError, match="left_files must be a list of image paths"):
        C.calibrate_rig(left, right, PATTERN, SQUARE)


def test_calibrate_camera_names_points_that_are_not_views():
    """image_points None was a builtin TypeError (len(None)), object_points None a TypeError
    and text numpy's ValueError (float('a')): CalibrationErrors naming the argument now (for
    calibrate_stereo's object_points too). Every accepted form still calibrates, alike."""
    cam, views = _projected_views(30.0)
    obj = C.board_points(PATTERN, SQUARE)
    for bad in (None, 5, "abc", np.float64(3.0)):
        with pytest.raises(CalibrationError, match=r"^image_points must be a list of views"):
            C.calibrate_camera(bad, obj, cam.size)
    with pytest.raises(CalibrationError, match=r"^image points must be \(N, 2\) pixel"):
        C.calibrate_camera([v.reshape(-1)[:-1] for v in views], obj, cam.size)
    for bad, words in ((None, "got None"), ("abc", "got 'abc'"), (["abc"] * 8, "got 'abc'"),
                       (5, "got 5"), (obj[:-1, :2], r"got an array of shape \(53, 2\)"),
                       (np.where(obj == 0, np.nan, obj), "finite numbers")):
        with pytest.raises(CalibrationError, match=rf"^object_points .*{words}"):
            C.calibrate_camera(views, bad, cam.size)
    with pytest.raises(CalibrationError, match=r"^object_points must be the board's 3D"):
        C.calibrate_stereo(views, views, None, cam, cam)
    # calibrate_stereo's views likewise (len(None) was a builtin TypeError)
    with pytest.raises(CalibrationError, match=r"^left_points must be a list of views"):
        C.calibrate_stereo(None, views, obj, cam, cam)
    with pytest.raises(CalibrationError, match=r"^right_points must be a list of views"):
        C.calibrate_stereo(views, 5, obj, cam, cam)
    with pytest.raises(CalibrationError, match=r"^image points must be \(N, 2\) pixel"):
        C.calibrate_stereo(views, [v.reshape(-1)[:-1] for v in views], obj, cam, cam)
    ref = C.calibrate_camera(views, obj, cam.size)  # (OpenCV's threads: equal to ~1e-8)
    for same in ([obj] * 8, tuple(obj for _ in views), (obj for _ in views), np.stack([obj] * 8)):
        np.testing.assert_allclose(C.calibrate_camera(views, same, cam.size).camera.K,
                                   ref.camera.K, rtol=1e-6)
    np.testing.assert_allclose(C.calibrate_camera(np.stack(views), obj, cam.size).camera.K,
                               ref.camera.K, rtol=1e-6)


def test_max_focal_rel_std_must_be_a_positive_number_or_inf():
    """NaN, 0 and negative limits were never checked: any calibration, a perfect one too, was
    refused as "focal length poorly determined (+-0.0 %)". A number > 0 or inf (no limit, as
    calibrate_rig passes) now; anything else a CalibrationError before the calibration runs."""
    cam, views = _projected_views(30.0)
    obj = C.board_points(PATTERN, SQUARE)
    for bad in (np.nan, 0, 0.0, -0.03, -np.inf, "0.03", None, True, [0.03]):
        with pytest.raises(CalibrationError, match=r"^max_focal_rel_std must be a number > 0 "
                                                   r"\(0.03 = \+-3 %\), or inf for no limit"):
            C.calibrate_camera(views, obj, cam.size, max_focal_rel_std=bad)
    ref = C.calibrate_camera(views, obj, cam.size)
    for ok in (np.inf, float("inf"), np.float32(0.5), 1):
        res = C.calibrate_camera(views, obj, cam.size, max_focal_rel_std=ok)
        np.testing.assert_allclose(res.camera.K, ref.camera.K, rtol=1e-6)
        assert res.focal_rel_std == pytest.approx(ref.focal_rel_std, rel=1e-4)
    _, flat = _projected_views(0.0)  # degenerate views: refused by a limit, taken by inf
    with pytest.raises(CalibrationError, match="poorly determined"):
        C.calibrate_camera(flat, obj, cam.size, max_focal_rel_std=0.5)
    assert C.calibrate_camera(flat, obj, cam.size, max_focal_rel_std=np.inf).focal_rel_std > 0.5


def test_render_chessboard_checks_its_arguments():
    """render_chessboard checked nothing: a square of 0 or NaN drew garbage and a negative one
    a mirrored board, noise=NaN meant no noise, background=NaN an undefined cast, a t_board of
    2 numbers and the pattern "9x6" were numpy's / Python's ValueError, and blur_px=1e6
    allocated 20 GB. The board is a CalibrationError (as board_points), the drawing settings
    a ConfigError (as rng), each naming the argument and its rule."""
    cam = Camera.from_fov(60.0, 64, 48)  # blur_px up to 64 / 8 = 8 px
    args = dict(camera=cam, R_board=np.eye(3), t_board=np.array([-0.05, -0.03, 0.5]),
                pattern=(4, 3), square_m=0.02)
    for key, bad, error, words in (
        ("pattern", "9x6", CalibrationError, "board must be two whole numbers"),
        ("pattern", (2, 2), CalibrationError, "board needs at least 3x3"),
        ("square_m", 0.0, CalibrationError, r"square_m must be a finite number > 0, got 0.0"),
        ("square_m", np.nan, CalibrationError, "square_m must be a finite number > 0"),
        ("square_m", -0.02, CalibrationError, "square_m must be a finite number > 0"),
        ("square_m", "0.02", CalibrationError, "square_m must be a finite number > 0"),
        ("R_board", np.eye(2), CalibrationError, r"R_board: expected shape 3x3"),
        ("R_board", np.full((3, 3), np.nan), CalibrationError, "R_board: values must be finite"),
        ("R_board", 2 * np.eye(3), CalibrationError, "R_board: not a rotation matrix"),
        ("R_board", None, CalibrationError, "R_board: expected numbers"),
        ("t_board", [0.0, 0.5], CalibrationError, r"t_board: expected 3 numbers .*shape \(2,\)"),
        ("t_board", [0.0, 0.0, np.nan], CalibrationError, "t_board: values must be finite"),
        ("t_board", "abc", CalibrationError, "t_board: expected numbers"),
        ("camera", None, CalibrationError, "render_chessboard needs a Camera"),
        ("margin_squares", -1.0, ConfigError, "margin_squares must be a finite number >= 0"),
        ("margin_squares", np.nan, ConfigError, "margin_squares must be a finite number >= 0"),
        ("blur_px", 1e6, ConfigError, r"blur_px must be a finite number in \[0, 8\]"),
        ("blur_px", 8.01, ConfigError, r"blur_px must be a finite number in \[0, 8\]"),
        ("blur_px", np.nan, ConfigError, "blur_px must be a finite number"),
        ("blur_px", -0.5, ConfigError, "blur_px must be a finite number"),
        ("noise", np.nan, ConfigError, "noise must be a finite number >= 0"),
        ("noise", np.inf, ConfigError, "noise must be a finite number >= 0"),
        ("noise", -1.0, ConfigError, "noise must be a finite number >= 0"),
        ("background", np.nan, ConfigError, r"background must be a finite number in \[0, 1\]"),
        ("background", 1.5, ConfigError, r"background must be a finite number in \[0, 1\]"),
        ("background", -0.1, ConfigError, r"background must be a finite number in \[0, 1\]"),
        ("invert", "no", ConfigError, "invert must be True or False"),  # ("no" inverted it)
    ):
        with pytest.raises(error, match=f"^{words}"):
            C.render_chessboard(**{**args, key: bad})
    # valid calls: the accepted forms of one board draw the same image; the limits are taken
    ref = C.render_chessboard(**args, blur_px=0.7, noise=2.0, rng=3)
    assert ref.dtype == np.uint8 and ref.shape == (48, 64) and ref.min() < 100 < 200 < ref.max()
    same = C.render_chessboard(cam, np.eye(3).tolist(), [[-0.05], [-0.03], [0.5]],
                               np.array([4, 3]), np.float32(0.02), blur_px=np.float64(0.7),
                               noise=2, rng=np.random.default_rng(3))
    np.testing.assert_array_equal(same, ref)
    assert np.all(C.render_chessboard(**args, blur_px=8.0) > 0)  # (the most blur: all grey)
    # background 0 and 1 (black, white) are taken: only the pixels around the board change
    plain, black, white = (C.render_chessboard(**args, background=bg) for bg in (0.45, 0, 1))
    board = black == white
    assert 0 < board.sum() < board.size
    np.testing.assert_array_equal(plain[board], black[board])
    assert np.all(black[~board] < plain[~board]) and np.all(plain[~board] < white[~board])
    assert black[0, 0] == 0 and plain[0, 0] == 115 and white[0, 0] == 255


def test_calibration_flags_must_be_true_or_false():
    """fix_aspect="no" (a config file's text) was truthy: fx = fy forced without a word -- a
    camera of fx 300, fy 330 px came back as fx = fy = 429 px. So were try_inverted and
    calibrate_stereo's refine. Now a CalibrationError naming the flag; True and False as
    before."""
    cam = Camera(K=np.array([[300.0, 0, 160.0], [0, 330.0, 120.0], [0, 0, 1]]),
                 width=320, height=240)
    obj = C.board_points(PATTERN, SQUARE)
    rng = np.random.default_rng(0)
    views = []
    for _ in range(8):
        Rb = cv2.Rodrigues(rng.uniform(-0.4, 0.4, 3))[0]
        views.append(cam.project(obj @ Rb.T + np.array([-0.1, -0.06, 0.5])
                                 + rng.uniform(-0.03, 0.03, 3)))
    free = C.calibrate_camera(views, obj, cam.size, fix_aspect=False).camera
    assert free.fx == pytest.approx(300.0, rel=1e-4) and free.fy == pytest.approx(330.0, rel=1e-4)
    for bad in ("no", "false", 1, None):
        with pytest.raises(CalibrationError, match="^fix_aspect must be True or False"):
            C.calibrate_camera(views, obj, cam.size, fix_aspect=bad)
        with pytest.raises(CalibrationError, match="^fix_aspect must be True or False"):
            C.calibrate_stereo(views, views, obj, cam, cam, fix_aspect=bad)
        with pytest.raises(CalibrationError, match="^refine must be True or False"):
            C.calibrate_stereo(views, views, obj, cam, cam, refine=bad)
        with pytest.raises(CalibrationError, match="^fix_aspect must be True or False"):
            C.calibrate_rig(["l.png"], ["r.png"], PATTERN, SQUARE, fix_aspect=bad)
        with pytest.raises(CalibrationError, match="^try_inverted must be True or False"):
            C.find_corners(np.zeros((60, 80), np.uint8), PATTERN, try_inverted=bad)
    assert C.find_corners(np.zeros((60, 80), np.uint8), PATTERN, try_inverted=np.bool_(True)) \
        is None


def test_an_image_too_thin_for_a_board_is_not_found(tmp_path):
    """A strip under 15 px high (640x8: at least 640 wide, so not enlarged) reached OpenCV's
    classic detector, whose adaptive threshold raised cv2.error (-215 blockSize > 1): `hearsee
    calibrate` on such files ended in a traceback. No board is found in it: None, and the
    rig calibration's "not found in any image"."""
    rng = np.random.default_rng(0)
    for h, w in ((8, 640), (14, 700), (1, 640), (3, 1000)):
        strip = rng.integers(0, 256, (h, w)).astype(np.uint8)
        assert C.find_corners(strip, PATTERN) is None
        assert C.find_corners(strip, PATTERN, upscale=1, try_inverted=True) is None
    files = {}
    for side in ("left", "right"):
        files[side] = []
        for i in range(3):
            p = tmp_path / f"{side}{i}.png"
            cv2.imwrite(str(p), rng.integers(0, 256, (8, 640)).astype(np.uint8))
            files[side].append(p)
    with pytest.raises(CalibrationError, match="not found in any image"):
        C.calibrate_rig(files["left"], files["right"], PATTERN, SQUARE)


def test_thermal_views_that_disagree_on_the_transform_are_refused():
    """Corners (+0.05 px noise) of 8 known boards with the thermal images mirrored left-right
    (a thermal camera set to flip its picture), relabelled by match_labeling to look like the
    left ones as calibrate_rig does: the per-view transforms scatter, the robust averaging kept
    1 view of 8 and fitted it alone -- rms 0.12 px with the other views 5.5-18.8 px off and the
    thermal camera 24 cm from its place (measured); `hearsee calibrate` wrote it with exit
    status 0 ('extrinsics 0.116 px'). Now a CalibrationError; unmirrored, the same views give
    the true position (to 1 mm)."""
    cam = Camera.from_fov(60.0, 320, 240)
    th = Camera(K=np.array([[160.0, 0, 79.5], [0, 160.0, 59.5], [0, 0, 1]]), width=160,
                height=120)
    truth = StereoRig.ideal(cam, 0.1, thermal=th, thermal_offset_m=(0.05, 0.04, 0.0))
    c = _rig_corners(truth)
    obj = C.board_points(PATTERN, SQUARE)
    lp, rp, tp = ([c[f"{k}{i}"] for i in range(8)] for k in ("left", "right", "thermal"))
    te = C.calibrate_thermal_extrinsics(truth, th, lp, tp, obj, right_points=rp)
    assert np.linalg.norm(-te.R.T @ te.T - truth.thermal_center_m) < 0.001
    assert te.used == list(range(8))
    mirrored = []
    for i in range(8):
        m = tp[i].copy()
        m[:, 0] = th.width - 1 - m[:, 0]
        mirrored.append(C.match_labeling(lp[i], m, PATTERN))
    with pytest.raises(CalibrationError, match="views disagree .* mirrored"):
        C.calibrate_thermal_extrinsics(truth, th, lp, mirrored, obj, right_points=rp)


def test_a_stereo_pair_of_two_moments_is_rejected_or_named(monkeypatch):
    """Corners (+0.05 px noise) of known boards; the right "image" of pair 3 is that of pair
    5 (a dropped frame, a re-shot view): each camera fits the board to 0.07 px, and the
    stereo fit took the pair in -- 1.85 px RMS, T off by 5-7 mm on each axis (measured),
    without a word. It is rejected as the intrinsics' outliers are (and reported), the rig
    true to 1 mm. Every pair shifted by one (a missing first image): 4 px RMS, refused with
    "check --board" -- the board both cameras had just fitted; the error names the pairing."""
    cam = Camera.from_fov(60.0, 320, 240)
    truth = StereoRig.ideal(cam, 0.1, thermal=Camera.from_fov(50.0, 160, 120))
    corners = _rig_corners(truth, n=9)  # (its thermal corners unused)
    sizes = {"left": cam.size, "right": cam.size}
    files = {k: [f"{k}{i}" for i in range(8)] for k in ("left", "right")}
    _fake_image_files(monkeypatch, {**corners, "right3": corners["right5"]}, sizes)
    res = C.calibrate_rig(files["left"], files["right"], PATTERN, SQUARE)
    assert [v.rejected for v in res.views] == [i == 3 for i in range(8)]
    assert np.isnan(res.views[3].err_stereo_right) and res.rms_stereo_px < 0.2
    np.testing.assert_allclose(res.rig.T, truth.T, atol=0.001)
    shifted = {**corners, **{f"right{i}": corners[f"right{i + 1}"] for i in range(8)}}
    _fake_image_files(monkeypatch, shifted, sizes)
    with pytest.raises(CalibrationError, match=r"stereo reprojection error .* board fits each "
                                               r"camera .* worst pair, left\d and right\d"):
        C.calibrate_rig(files["left"], files["right"], PATTERN, SQUARE)
