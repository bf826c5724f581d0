"""Tests of hearsee.vision.camera: projection, rays, rigs, poses and calibration files."""

from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest

from hearsee.errors import CalibrationError, ConfigError, GeometryError, InputFileError
from hearsee.vision.camera import (
    OPTICAL_FROM_BODY,
    Camera,
    StereoRig,
    camera_pose,
    head_camera_pose,
    load_camera,
    load_rig,
    read_opencv_yaml,
    rig_from_opencv,
    save_camera,
    save_rig,
    transform_points,
)

K = np.array([[500.0, 0.0, 320.0], [0.0, 505.0, 240.0], [0.0, 0.0, 1.0]])


def _points(n: int = 200, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.c_[rng.uniform(-1.0, 1.0, (n, 2)), rng.uniform(1.0, 6.0, n)]


@pytest.mark.parametrize("dist", [
    [],
    [-0.25, 0.08, 0.001, -0.002],
    [-0.25, 0.08, 0.001, -0.002, -0.01],
    [-0.25, 0.08, 0.001, -0.002, -0.01, 0.1, 0.02, 0.003],
    [-0.2, 0.05, 0.001, -0.002, 0.01, 0.1, 0.02, 0.003, 0.001, 0.002, -0.001, 0.0005],
    [-0.2, 0.05, 0.001, -0.002, 0.01, 0.1, 0.02, 0.003, 0.0, 0.0, 0.0, 0.0, 0.01, -0.02],
])
def test_project_matches_opencv_and_rays_invert_it(dist):
    cam = Camera(K=K, dist=np.array(dist), width=640, height=480)
    P = _points()
    uv = cam.project(P)
    ref, _ = cv2.projectPoints(P.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K,
                               np.array(dist, float))
    np.testing.assert_allclose(uv, ref.reshape(-1, 2), atol=1e-6)
    rays = cam.pixel_rays(uv)
    np.testing.assert_allclose(np.linalg.norm(rays, axis=1), 1.0)
    np.testing.assert_allclose(rays, P / np.linalg.norm(P, axis=1, keepdims=True), atol=1e-7)


def test_pixel_rays_of_pixels_far_outside_the_image_are_unit_rays_or_refused():
    """A pixel at u = 1e300 gave the ray [0, 0, 0] (its length overflowed, a RuntimeWarning);
    with lens distortion OpenCV's NaN became a NaN ray that failed far from the cause. The
    pinhole's ray of (u, v) is [(u - cx) / fx, (v - cy) / fy, 1]: for u = 1e300 almost the
    optical x axis, for (-1e300, 1e300) the diagonal (-1 / fx, 1 / fy, 0) normalised."""
    cam = Camera(K=K, width=640, height=480)
    uv = [[1e300, 240.0], [-1e300, 1e300], [1e6, 240.0], [np.nan, 240.0]]
    diag = np.array([-1 / 500.0, 1 / 505.0, 0.0])
    far = np.array([1e6 - 320.0, 0.0, 500.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (no overflow warning either)
        rays = cam.pixel_rays(uv)
    np.testing.assert_allclose(rays[:3], [[1.0, 0.0, 0.0], diag / np.linalg.norm(diag),
                                          far / np.linalg.norm(far)], rtol=0, atol=1e-15)
    assert np.all(np.isnan(rays[3]))  # a pixel that is not finite: a NaN ray, as before
    lens = Camera(K=K, dist=np.array([-0.25, 0.08, 0.001, -0.002]), width=640, height=480)
    for bad in ([1e300, 240.0], [[320.0, 240.0], [-1e300, 1e300]]):
        with pytest.raises(GeometryError, match="too far outside the 640x480 image"):
            lens.pixel_rays(bad)
    assert np.all(np.isnan(lens.pixel_rays([np.nan, 240.0])))
    np.testing.assert_allclose(lens.pixel_rays([320.0, 240.0]), [[0.0, 0.0, 1.0]],
                               atol=1e-12)


@pytest.mark.parametrize("dist", [[], [-0.25, 0.08, 0.001, -0.002]])
def test_infinite_pixels_give_all_nan_rays_without_warnings(dist):
    """Without distortion, pixel (inf, 240) gave the ray [nan, 0, 0] and two RuntimeWarnings
    (inf / inf, 0 / inf); a distorted camera gave [nan, nan, nan], the documented "no ray"."""
    cam = Camera(K=K, dist=dist, width=640, height=480)
    uv = [[np.inf, 240.0], [320.0, -np.inf], [np.inf, np.nan], [320.0, 240.0]]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rays = cam.pixel_rays(uv)
        xy = cam.normalized(uv)
    assert np.all(np.isnan(rays[:3])) and np.all(np.isnan(xy[:3]))
    np.testing.assert_allclose(rays[3], [0.0, 0.0, 1.0], atol=1e-12)


def test_pixel_rays_past_the_lens_fold_are_refused_and_near_it_exact():
    """A 640x480 camera, f 520 px, k1 = -0.28: the radial map rd = r (1 + k1 r^2) peaks at
    r_f = 1 / sqrt(-3 k1) = 1.0911 with rd_max = 2 r_f / 3 = 0.7274, below the corners'
    0.768: no direction reaches them, yet OpenCV's ray for pixel (0, 0) reprojected 21.9 px
    away (2164 such pixels), and directions at 0.95-0.999 r_f came back up to 0.34 deg off."""
    f, k1 = 520.0, -0.28
    cam = Camera(np.array([[f, 0, 319.5], [0, f, 239.5], [0, 0, 1]]), [k1, 0, 0, 0], 640, 480)
    r_f = 1.0 / np.sqrt(-3.0 * k1)
    rd_max = 2.0 * r_f / 3.0
    with pytest.raises(GeometryError, match=r"pixel \(0, 0\) of the 640x480 image is beyond"):
        cam.pixel_rays([[320.0, 240.0], [0.0, 0.0]])
    u, v = np.meshgrid(np.arange(640.0), np.arange(480.0))
    uv = np.c_[u.ravel(), v.ravel()]
    rd = np.hypot(uv[:, 0] - 319.5, uv[:, 1] - 239.5) / f
    rays = cam.pixel_rays(uv, unreachable="nan")
    lost = np.isnan(rays).any(axis=1)
    assert np.array_equal(lost, np.isnan(cam.normalized(uv)).any(axis=1))
    assert np.all(lost[rd > rd_max + 1e-9]) and not np.any(lost[rd < rd_max - 1e-6])
    assert lost.sum() > 2000
    np.testing.assert_allclose(cam.project(rays[~lost]), uv[~lost], rtol=0, atol=1e-6)
    assert np.all(cam.in_lens_field(rays[~lost]))
    # directions just inside the fold: recovered exactly
    rng = np.random.default_rng(1)
    r = rng.uniform(0.95, 0.999, 300) * r_f
    a = rng.uniform(0.0, 2 * np.pi, 300)
    P = np.c_[r * np.cos(a), r * np.sin(a), np.ones_like(r)]
    px = cam.project(P)
    back = cam.pixel_rays(px)
    np.testing.assert_allclose(back, P / np.linalg.norm(P, axis=1, keepdims=True), atol=1e-9)
    np.testing.assert_allclose(cam.project(back), px, rtol=0, atol=1e-6)
    with pytest.raises(GeometryError, match="unreachable must be"):
        cam.pixel_rays(px, unreachable="zero")


def test_points_behind_camera_are_nan_and_in_image_mask():
    cam = Camera.from_fov(90.0, 640, 480)
    uv = cam.project([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0], [10.0, 0.0, 1.0]])
    assert np.all(np.isnan(uv[0]))
    np.testing.assert_allclose(uv[1], [319.5, 239.5])
    assert cam.in_image(uv).tolist() == [False, True, False]
    assert cam.in_image([319.5, 239.5]).tolist() == [True]  # one pixel
    # an (N, 3) array was re-read as 3 pixels (x, y), (z, x), (y, z): [True, False, True] here
    with pytest.raises(GeometryError, match=r"\(N, 2\)"):
        cam.in_image([[100.0, 100.0, 1.0], [2000.0, 100.0, 1.0]])


def test_from_fov_geometry():
    cam = Camera.from_fov(60.0, 640, 480)
    assert cam.hfov_deg == pytest.approx(60.0)
    # a point on the edge of the horizontal field of view lands on the image border
    u = cam.project([[np.tan(np.radians(30.0)), 0.0, 1.0]])[0, 0]
    assert u == pytest.approx(cam.cx + 320.0)
    half = cam.with_size(320, 240)
    assert half.fx == pytest.approx(cam.fx / 2)
    assert half.hfov_deg == pytest.approx(60.0)
    np.testing.assert_allclose(half.project([[0.0, 0.0, 1.0]]), [[159.5, 119.5]])


@pytest.mark.parametrize("kwargs, match", [
    (dict(K=np.eye(2)), "3x3"),
    (dict(K=-K), "fx, fy > 0"),
    (dict(K=K, dist=[0.1, 0.2, 0.3]), "dist"),
    (dict(K=K, width=0), "positive integers"),
])
def test_bad_camera_raises(kwargs, match):
    kw = dict(width=640, height=480)
    kw.update(kwargs)
    with pytest.raises(CalibrationError, match=match):
        Camera(**kw)


def test_optical_from_body_and_camera_pose():
    # body forward -> optical z, body left -> optical -x, body up -> optical -y
    np.testing.assert_allclose(OPTICAL_FROM_BODY @ [1, 0, 0], [0, 0, 1])
    np.testing.assert_allclose(OPTICAL_FROM_BODY @ [0, 1, 0], [-1, 0, 0])
    np.testing.assert_allclose(OPTICAL_FROM_BODY @ [0, 0, 1], [0, -1, 0])
    R, t = camera_pose((0.1, 0.0, 1.2), pan_deg=90.0)
    np.testing.assert_allclose(R @ np.array([0.1, 2.0, 1.2]) + t, [0, 0, 2], atol=1e-12)
    R, t = camera_pose((0.0, 0.0, 0.0), tilt_deg=30.0)
    d = np.array([np.cos(np.radians(30)), 0.0, np.sin(np.radians(30))])
    np.testing.assert_allclose(R @ d + t, [0, 0, 1], atol=1e-12)
    R, t = camera_pose((0.0, 0.0, 0.0), roll_deg=90.0)
    # rolled +90 deg about forward: camera top points right, world up appears at image left
    np.testing.assert_allclose(R @ np.array([0.0, 0.0, 1.0]), [-1, 0, 0], atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0)


def test_ideal_rig_rectification_and_depth_formula():
    cam = Camera.from_fov(60.0, 640, 480)
    rig = StereoRig.ideal(cam, 0.12)
    assert rig.is_rectified
    assert rig.baseline_m == pytest.approx(0.12)
    assert rig.focal_px == pytest.approx(cam.fx)
    X = np.array([[0.3, -0.2, 2.5]])
    ul = cam.project(X)
    ur = rig.right.project(rig.left_to_right(X))
    d = ul[0, 0] - ur[0, 0]
    assert d == pytest.approx(cam.fx * 0.12 / 2.5)
    h = rig.Q @ np.array([ul[0, 0], ul[0, 1], d, 1.0])
    np.testing.assert_allclose(h[:3] / h[3], X[0], atol=1e-9)


@pytest.mark.parametrize("cam", [Camera.from_fov(60.0, 640, 480, vfov_deg=40.0),
                                 Camera(K=K, width=640, height=480)])
def test_ideal_rig_with_non_square_pixels_recovers_y(cam):
    """An ideal rig with fx != fy took the identity shortcut with the left K as is: Q's
    Y = (v - cy) B / d assumes fx = fy, so Y came out fx / fy times too large (-0.476 m for a
    true -0.40 m at fx 554 / fy 659; 1 % with fx 500 / fy 505). Ground truth: the raw pixels
    of a known point, taken through OpenCV's own undistortPoints with the rig's R1/P1, R2/P2,
    then Q and R1^T back to the left frame."""
    rig = StereoRig.ideal(cam, 0.12)
    rect = rig.rectification
    X = np.array([[0.3, -0.4, 2.5], [-0.5, 0.6, 4.0]])
    ul = cam.project(X)
    ur = rig.right.project(rig.left_to_right(X))
    pl = cv2.undistortPoints(ul.reshape(-1, 1, 2), cam.K, None, R=rect.R1, P=rect.P1)
    pr = cv2.undistortPoints(ur.reshape(-1, 1, 2), cam.K, None, R=rect.R2, P=rect.P2)
    pl, pr = pl.reshape(-1, 2), pr.reshape(-1, 2)
    np.testing.assert_allclose(pl[:, 1], pr[:, 1], atol=1e-9)  # same rows
    d = pl[:, 0] - pr[:, 0]
    np.testing.assert_allclose(d, rect.focal_px * 0.12 / X[:, 2], rtol=1e-12)
    h = np.c_[pl, d, np.ones(len(d))] @ rect.Q.T
    np.testing.assert_allclose((h[:, :3] / h[:, 3:]) @ rect.R1, X, atol=1e-9)
    # Y from the rectified camera's one focal length (humans' expected rows): the truth too
    np.testing.assert_allclose((pl[:, 1] - rect.cy) / rect.focal_px * X[:, 2], X[:, 1],
                               atol=1e-9)
    assert rect.camera.fx == rect.camera.fy == rect.focal_px
    assert not rig.is_rectified  # (non-square pixels: the images need resampling)


def test_ideal_rig_shortcut_q_is_the_square_pixel_formula():
    """With square pixels the identity shortcut stays: R1 = R2 = I, P1 = [K | 0] and
    Q = [[1, 0, 0, -cx], [0, 1, 0, -cy], [0, 0, 0, f], [0, 0, 1 / B, 0]] exactly."""
    cam = Camera.from_fov(60.0, 640, 480)
    rig = StereoRig.ideal(cam, 0.12)
    assert rig.is_rectified
    rect = rig.rectification
    f = cam.fx
    np.testing.assert_array_equal(rect.R1, np.eye(3))
    np.testing.assert_array_equal(rect.P1[:, :3], cam.K)
    np.testing.assert_array_equal(rect.Q, [[1, 0, 0, -cam.cx], [0, 1, 0, -cam.cy], [0, 0, 0, f],
                                           [0, 0, 1 / 0.12, 0]])


def test_general_rig_rectification_matches_opencv():
    cam = Camera(K=K, dist=[-0.1, 0.01, 0.0, 0.0], width=640, height=480)
    R = cv2.Rodrigues(np.array([0.01, -0.02, 0.005]))[0]
    rig = StereoRig(cam, cam, R, [-0.1, 0.002, 0.001])
    assert not rig.is_rectified
    rect = rig.rectification
    assert rect.baseline_m == pytest.approx(0.1, rel=1e-3)
    # a point projected into both rectified images lies on the same row, at the disparity
    # f B / Z of its depth Z in the rectified frame. P2 takes rectified-LEFT-frame points
    # (its 4th column holds the baseline): P2 [R2 X_right, 1] applied the baseline twice
    # (d 33.5 px for a true 16.75).
    X = np.array([[0.2, 0.1, 3.0]])
    pl = rect.P1 @ np.r_[rect.R1 @ X[0], 1.0]
    pr = rect.P2 @ np.r_[rect.R1 @ X[0], 1.0]
    assert pl[1] / pl[2] == pytest.approx(pr[1] / pr[2], abs=1e-6)
    d = pl[0] / pl[2] - pr[0] / pr[2]
    Z = (rect.R1 @ X[0])[2]
    assert d == pytest.approx(rect.focal_px * rect.baseline_m / Z, rel=1e-12)
    # the same from the raw distorted pixels, through OpenCV's own undistortion
    ul = cam.project(X).reshape(-1, 1, 2)
    ur = cam.project(rig.left_to_right(X)).reshape(-1, 1, 2)
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-12)
    ql = cv2.undistortPointsIter(ul, K, cam.dist, rect.R1, rect.P1, crit).reshape(2)
    qr = cv2.undistortPointsIter(ur, K, cam.dist, rect.R2, rect.P2, crit).reshape(2)
    assert ql[1] == pytest.approx(qr[1], abs=1e-6)
    assert ql[0] - qr[0] == pytest.approx(rect.focal_px * rect.baseline_m / Z, abs=1e-6)
    h = rect.Q @ np.r_[ql, ql[0] - qr[0], 1.0]
    np.testing.assert_allclose(rect.R1.T @ (h[:3] / h[3]), X[0], atol=1e-6)


def test_rig_roundtrip_with_thermal(tmp_path):
    cam = Camera(K=K, dist=[-0.1, 0.01, 0.001, 0.0, 0.002], width=640, height=480)
    th = Camera.from_fov(45.0, 160, 120, name="thermal")
    Rt = cv2.Rodrigues(np.array([0.0, 0.05, 0.0]))[0]
    rig = StereoRig.ideal(cam, 0.09).with_thermal(th, Rt, [-0.045, 0.05, 0.0])
    path = tmp_path / "rig.yaml"
    save_rig(rig, path)
    back = load_rig(path)
    np.testing.assert_allclose(back.left.K, cam.K)
    np.testing.assert_allclose(back.left.dist, cam.dist)
    np.testing.assert_allclose(back.R_thermal, Rt)
    np.testing.assert_allclose(back.T, [-0.09, 0, 0])
    X = _points(5)
    np.testing.assert_allclose(back.project_thermal(X), rig.project_thermal(X))
    assert load_camera(path, "thermal").width == 160
    assert load_camera(path, "right").fx == pytest.approx(500.0)
    cpath = tmp_path / "cam.yaml"
    save_camera(th, cpath, rms_px=0.2)
    assert load_camera(cpath).fx == pytest.approx(th.fx)


def test_missing_and_bad_calibration_files(tmp_path):
    with pytest.raises(InputFileError, match="hearsee calibrate"):
        load_rig(tmp_path / "nope.yaml")
    cam = Camera.from_fov(60.0, 640, 480)
    path = tmp_path / "rig.yaml"
    save_rig(StereoRig.ideal(cam, 0.1), path)
    text = path.read_text()
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace("T: [-0.1, 0.0, 0.0]", "T: [-0.1, 0.0]"))
    with pytest.raises(ConfigError, match="T"):
        load_rig(bad)
    bad.write_text(text.replace("width: 640", "width: -3", 1))
    with pytest.raises(ConfigError, match="left: width"):
        load_rig(bad)
    bad.write_text(text.replace("kind: stereo_rig", "kind: stereo_rig\nfoo: 1"))
    with pytest.raises(ConfigError, match="unknown key 'foo'"):
        load_rig(bad)
    bad.write_text("\n".join(line for line in text.splitlines() if not line.startswith("R:")
                             and not line.startswith("- [")))
    with pytest.raises(ConfigError, match="missing required key 'R'"):
        load_rig(bad)
    bad.write_text("%YAML:1.0\n---\nM1: 1\n")
    with pytest.raises(ConfigError, match="FileStorage"):
        load_rig(bad)
    with pytest.raises(CalibrationError, match="no thermal camera"):
        load_rig(path).left_to_thermal([[0, 0, 1]])


def test_read_opencv_yaml(tmp_path):
    p = tmp_path / "intr.yml"
    fs = cv2.FileStorage(str(p), cv2.FILE_STORAGE_WRITE)
    fs.write("M1", K)
    fs.write("rms", 0.25)
    fs.release()
    data = read_opencv_yaml(p)
    np.testing.assert_allclose(data["M1"], K)
    assert data["rms"] == pytest.approx(0.25)


def test_swapped_rig_is_the_same_geometry():
    cam = Camera(K=K, dist=[-0.1, 0.01, 0.0, 0.0], width=640, height=480)
    R = cv2.Rodrigues(np.array([0.01, -0.02, 0.005]))[0]
    rig = StereoRig(cam, Camera.from_fov(55.0, 640, 480), R, [0.1, 0.002, 0.001]).with_thermal(
        Camera.from_fov(40.0, 160, 120), np.eye(3), [0.02, 0.05, 0.0])
    sw = rig.swapped()
    X = _points(10)
    # a point in the old left frame, seen from the new left (old right) camera
    Xr = rig.left_to_right(X)
    np.testing.assert_allclose(sw.left_to_right(Xr), X, atol=1e-12)
    np.testing.assert_allclose(sw.project_thermal(Xr), rig.project_thermal(X), atol=1e-9)
    assert sw.rectification.baseline_m == pytest.approx(-rig.rectify().baseline_m, rel=1e-6)


def test_rig_from_opencv_files(tmp_path):
    intr, extr = tmp_path / "intrinsics.yml", tmp_path / "extrinsics.yml"
    R = cv2.Rodrigues(np.array([0.01, 0.02, 0.0]))[0]
    fs = cv2.FileStorage(str(intr), cv2.FILE_STORAGE_WRITE)
    for k, v in (("M1", K), ("D1", np.zeros((1, 5))), ("M2", K), ("D2", np.zeros((1, 14)))):
        fs.write(k, v)
    fs.release()
    fs = cv2.FileStorage(str(extr), cv2.FILE_STORAGE_WRITE)
    fs.write("R", R)
    fs.write("T", np.array([[-120.0], [1.0], [0.5]]))
    fs.release()
    rig = rig_from_opencv(intr, extr, (640, 480), scale_to_m=0.001)
    assert rig.baseline_m == pytest.approx(np.linalg.norm([0.12, 0.001, 0.0005]))
    np.testing.assert_allclose(rig.R, R)
    with pytest.raises(ConfigError, match="missing matrix 'R'"):
        rig_from_opencv(intr, intr, (640, 480))


@pytest.mark.shared
def test_rig_from_opencv_reference_files(shared_data):
    d = shared_data / "vision" / "chessboard_stereo"
    if not d.is_dir():
        pytest.skip("chessboard_stereo not present")
    rig = rig_from_opencv(d / "reference_intrinsics.yml", d / "reference_extrinsics.yml",
                          (640, 512), scale_to_m=0.001)
    assert rig.left.fx == pytest.approx(518.05, abs=0.01)
    assert rig.left.dist.size == 14
    assert rig.baseline_m == pytest.approx(0.0921, abs=0.001)


def test_head_camera_pose_follows_head_kinematics():
    from hearsee.geometry import HeadPose, array_to_robot

    pivot, offset = np.array([0.0, 0.0, 1.0]), np.array([0.05, 0.03, 0.1])
    pose = HeadPose(30.0, 15.0)
    R, t = head_camera_pose(pose, pivot, offset)
    centre = array_to_robot(offset, pose, pivot)  # where the head carries the camera
    np.testing.assert_allclose(R @ centre + t, 0.0, atol=1e-12)
    # a point straight along the gaze lands on the optical axis
    target = centre + 3.0 * pose.gaze
    np.testing.assert_allclose(R @ target + t, [0.0, 0.0, 3.0], atol=1e-12)
    # a point above the gaze (head +z) appears above the image centre (optical -y)
    up = array_to_robot(offset + np.array([3.0, 0.0, 0.5]), pose, pivot)
    assert (R @ up + t)[1] < 0


SKEW_DISTS = [
    [],
    [-0.2, 0.05, 0.001, -0.002, 0.0],
    [-0.25, 0.08, 0.001, -0.002, -0.01, 0.1, 0.02, 0.003],
    [-0.2, 0.05, 0.001, -0.002, 0.01, 0.1, 0.02, 0.003, 0.0, 0.0, 0.0, 0.0, 0.01, -0.02],  # tilt
]


@pytest.mark.parametrize("dist", SKEW_DISTS)
def test_skewed_camera_project_and_normalized_invert_each_other(dist):
    """A skewed K is a skew-free K followed by the pixel shear u += s (v - cy) / fy: known
    points, known lens, so both directions have an exact ground truth."""
    s = 2.0
    Ks = K.copy()
    Ks[0, 1] = s
    cam = Camera(K=Ks, dist=np.array(dist), width=640, height=480)
    plain = Camera(K=K, dist=np.array(dist), width=640, height=480)
    P = _points()
    uv0 = plain.project(P)
    truth = uv0 + np.c_[s * (uv0[:, 1] - K[1, 2]) / K[1, 1], np.zeros(len(uv0))]
    uv = cam.project(P)
    np.testing.assert_allclose(uv, truth, atol=1e-9)
    np.testing.assert_allclose(cam.normalized(uv), P[:, :2] / P[:, 2:], atol=1e-9)
    np.testing.assert_allclose(cam.pixel_rays(uv), P / np.linalg.norm(P, axis=1, keepdims=True),
                               atol=1e-9)


@pytest.mark.parametrize("dist", SKEW_DISTS[1:])
def test_without_skew_normalized_is_opencv_bit_for_bit(dist):
    """Where OpenCV's own answer maps back onto its pixel (1e-9 px) inside the lens field,
    normalized is that answer bit for bit. Elsewhere (the rational lens folds at r = 1.47:
    13 of these pixels outside the image have no ray, and OpenCV's reprojected up to 41 px
    away; 18 more stopped early, up to 0.027 px off) it is the ray that maps back to 1e-9 px,
    or NaN where OpenCV's answer was wrong."""
    cam = Camera(K=K, dist=np.array(dist), width=640, height=480)
    rng = np.random.default_rng(3)
    uv = np.c_[rng.uniform(-40, 680, 500), rng.uniform(-40, 520, 500)]
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-10)
    ref = cv2.undistortPointsIter(uv.reshape(-1, 1, 2), K, np.array(dist), None, None, crit)
    ref = ref.reshape(-1, 2)
    got = cam.normalized(uv)

    def reprojection_px(xy, at):
        return np.linalg.norm(cam.project(np.c_[xy, np.ones(len(xy))]) - at, axis=1)

    ref_ok = ((reprojection_px(ref, uv) <= 1e-9)
              & cam.in_lens_field(np.c_[ref, np.ones(len(ref))]))
    np.testing.assert_array_equal(got[ref_ok], ref[ref_ok])
    found = np.isfinite(got).all(axis=1)
    assert np.all(reprojection_px(got[found], uv[found]) < 1e-9)
    assert np.all(cam.in_lens_field(np.c_[got[found], np.ones(found.sum())]))
    assert not np.any(ref_ok & ~found)


def test_read_opencv_yaml_skips_what_it_does_not_read(tmp_path):
    """A file like OpenCV's calibration sample writes: sequences of numbers (grid_points) are
    read as arrays; sequences of strings and plain maps are skipped, not an OpenCV error."""
    p = tmp_path / "camera.yml"
    fs = cv2.FileStorage(str(p), cv2.FILE_STORAGE_WRITE)
    fs.write("calibration_time", "Mon Jan 1")
    fs.write("image_width", 640)
    fs.write("camera_matrix", K)
    fs.write("avg_reprojection_error", 0.3)
    grid = [0.0, 0.0, 0.0, 0.025, 0.0, 0.0]
    fs.startWriteStruct("grid_points", cv2.FileNode_SEQ)
    for v in grid:
        fs.write("", v)
    fs.endWriteStruct()
    fs.startWriteStruct("images", cv2.FileNode_SEQ)
    for v in ("left01.jpg", "left02.jpg"):
        fs.write("", v)
    fs.endWriteStruct()
    fs.startWriteStruct("settings", cv2.FileNode_MAP)
    fs.write("rows", 6)
    fs.endWriteStruct()
    fs.startWriteStruct("views", cv2.FileNode_SEQ)
    fs.write("", K)
    fs.endWriteStruct()
    fs.release()
    data = read_opencv_yaml(p)
    assert set(data) == {"calibration_time", "image_width", "camera_matrix",
                         "avg_reprojection_error", "grid_points"}
    assert data["calibration_time"] == "Mon Jan 1" and data["image_width"] == 640.0
    np.testing.assert_array_equal(data["camera_matrix"], K)
    np.testing.assert_array_equal(data["grid_points"], grid)
    assert data["grid_points"].dtype == float


@pytest.mark.parametrize("rows, dt, n", [(3, "d", 5), (-3, "d", 9), (3, "q", 9)])
def test_read_opencv_yaml_names_a_broken_matrix(tmp_path, rows, dt, n):
    """A matrix node OpenCV cannot read (5 values for 3x3, rows -3, dt q) was skipped, and
    calibrate --reference said there was no M1 at all; now a ConfigError names the node."""
    p = tmp_path / "intrinsics.yml"
    values = ", ".join(f"{v:g}." for v in K.reshape(-1)[:n])
    p.write_text(f"%YAML:1.0\n---\nM1: !!opencv-matrix\n   rows: {rows}\n   cols: 3\n"
                 f"   dt: {dt}\n   data: [ {values} ]\n")
    with pytest.raises(ConfigError, match=r"M1: a malformed !!opencv-matrix"):
        read_opencv_yaml(p)
    p.write_text(p.read_text().replace(f"rows: {rows}", "rows: 3").replace(f"dt: {dt}", "dt: d")
                 .replace(f"[ {values} ]", "[ " + ", ".join(f"{v:g}." for v in K.reshape(-1))
                          + " ]"))
    np.testing.assert_array_equal(read_opencv_yaml(p)["M1"], K)


def test_a_baseline_below_one_millimetre_is_refused(tmp_path):
    """The same images for both cameras calibrate to |T| ~ 5e-15 m, which was accepted as a
    rig; real stereo pairs are >= 10 mm apart."""
    cam = Camera.from_fov(60.0, 640, 480)
    for T in ([-5e-15, 0.0, 0.0], [-0.0009, 0.0, 0.0], [0.0, 0.0, 0.0]):
        with pytest.raises(CalibrationError, match="baseline .* below 1 mm"):
            StereoRig(cam, cam, np.eye(3), T)
    with pytest.raises(CalibrationError, match="below 1 mm"):
        StereoRig.ideal(cam, 0.0005)
    assert StereoRig(cam, cam, np.eye(3), [-0.0011, 0.0, 0.0]).baseline_m == pytest.approx(0.0011)
    path = tmp_path / "rig.yaml"
    save_rig(StereoRig.ideal(cam, 0.1), path)
    path.write_text(path.read_text().replace("T: [-0.1, 0.0, 0.0]", "T: [-1.0e-14, 0.0, 0.0]"))
    with pytest.raises(ConfigError, match=r"rig.yaml: rig T: the baseline .* below 1 mm"):
        load_rig(path)


def test_a_baseline_in_millimetres_is_refused(tmp_path):
    """A rig file written in millimetres (T: [-120, 0, 0]) gave depths 1000x too large and
    "0 humans" without a word; baselines and thermal offsets above 5 m are refused."""
    cam = Camera.from_fov(60.0, 640, 480)
    assert StereoRig.ideal(cam, 5.0).baseline_m == pytest.approx(5.0)
    path = tmp_path / "rig.yaml"
    save_rig(StereoRig.ideal(cam, 0.12, thermal=cam, thermal_offset_m=(0.05, 0.0, 0.0)), path)
    text = path.read_text()
    assert "\nT: [-0.12, 0.0, 0.0]" in text and "\n  T: [-0.05, 0.0, 0.0]" in text
    path.write_text(text.replace("\nT: [-0.12, 0.0, 0.0]", "\nT: [-120.0, 0.0, 0.0]"))
    with pytest.raises(ConfigError, match=r"rig T: the baseline is 120 m, above 5 m \(is the "
                                          r"translation in millimetres"):
        load_rig(path)
    path.write_text(text.replace("\n  T: [-0.05, 0.0, 0.0]", "\n  T: [-50.0, 0.0, 0.0]"))
    with pytest.raises(ConfigError, match=r"thermal camera is 50 m from the left camera"):
        load_rig(path)


def test_camera_height_in_the_rig_info_is_checked_when_loaded(tmp_path):
    cam = Camera.from_fov(60.0, 640, 480)
    path = tmp_path / "rig.yaml"
    rig = StereoRig(cam, cam, np.eye(3), [-0.1, 0.0, 0.0], info={"camera_height_m": 1.2})
    save_rig(rig, path)
    text = path.read_text()
    for bad in (".nan", "-1.2", "0", "abc", "true", "[1.2]"):
        path.write_text(text.replace("camera_height_m: 1.2", f"camera_height_m: {bad}"))
        with pytest.raises(ConfigError, match=r"rig.yaml: info: camera_height_m must be a finite"):
            load_rig(path)
    path.write_text(text)
    assert load_rig(path).camera_height_m == pytest.approx(1.2)
    assert StereoRig.ideal(cam, 0.1).camera_height_m is None
    # the camera's pitch (degrees, + = up; since 2026-12-03 the floor's prior too)
    rig = StereoRig(cam, cam, np.eye(3), [-0.1, 0.0, 0.0], info={"camera_pitch_deg": -20})
    save_rig(rig, path)
    text = path.read_text()
    for bad in (".nan", "81", "-95", "abc", "true", "[10]"):
        path.write_text(text.replace("camera_pitch_deg: -20", f"camera_pitch_deg: {bad}"))
        with pytest.raises(ConfigError, match=r"rig.yaml: info: camera_pitch_deg \(camera "
                                              r"pitch .*\) must be a finite number of degrees "
                                              r"within \+-80"):
            load_rig(path)
    path.write_text(text)
    assert load_rig(path).camera_pitch_deg == -20.0
    assert StereoRig.ideal(cam, 0.1).camera_pitch_deg is None


def test_read_opencv_yaml_refuses_files_that_are_not_filestorage(tmp_path):
    """An empty, plain-YAML or binary file made cv2.FileStorage raise SystemError."""
    cases = {"empty.yml": b"", "plain.yaml": b"a: 1\nb: [1, 2]\n",
             "garbage.yml": bytes(range(256)) * 2, "broken.yml": b"%YAML:1.0\n---\nM1: [1, 2\n"}
    for name, content in cases.items():
        p = tmp_path / name
        p.write_bytes(content)
        with pytest.raises(ConfigError, match="not a readable OpenCV FileStorage file") as exc:
            read_opencv_yaml(p)
        assert "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match="empty"):
        read_opencv_yaml(tmp_path / "empty.yml")
    with pytest.raises(ConfigError, match="line 3"):
        read_opencv_yaml(tmp_path / "broken.yml")


def test_camera_pose_and_transform_points_refuse_bad_input():
    """camera_pose with a NaN angle returned NaN R, t; transform_points read a flat (6,) array
    as two points and silently dropped the second."""
    for args in (((0, 0, 1), np.nan), ((0, 0, 1), 0.0, np.inf), ((0, 0, 1), 0, 0, "x"),
                 ((0.0, 1.0),), ((0, 0, np.nan),), ((0, 0, 1), 1e300)):  # (1e300: as HeadPose)
        with pytest.raises(GeometryError, match="camera_pose"):
            camera_pose(*args)
    R, t = camera_pose((0.0, 0.0, 1.2), 30.0)
    assert np.all(np.isfinite(R)) and np.all(np.isfinite(t))
    for pts in ([1, 2, 3, 4, 5, 6], [[1.0, 2.0]], np.zeros((2, 2, 3)), [[1, 2, 3, 4]]):
        with pytest.raises(GeometryError, match="points of shape"):
            transform_points(np.eye(3), [0, 0, 1], pts)
    with pytest.raises(GeometryError, match="R must be 3x3"):
        transform_points(np.eye(2), [0, 0, 1], [1, 2, 3])
    np.testing.assert_allclose(transform_points(np.eye(3), [0, 0, 1], [1, 2, 3]), [1, 2, 4])
    assert transform_points(np.eye(3), [0, 0, 1], [[1, 2, 3]]).shape == (1, 3)
    assert transform_points(np.eye(3), [0, 0, 1], np.zeros((0, 3))).shape == (0, 3)


def test_load_camera_which_on_a_single_camera_file(tmp_path):
    """Asking a single-camera file for the thermal camera returned whatever camera it held."""
    path = tmp_path / "cam.yaml"
    save_camera(Camera.from_fov(60.0, 640, 480), path)
    assert load_camera(path).width == 640
    for which in ("thermal", "left", "right"):
        with pytest.raises(ConfigError, match=f"single-camera file .* no '{which}' camera"):
            load_camera(path, which)
    named = tmp_path / "thermal.yaml"
    save_camera(Camera.from_fov(40.0, 160, 120, name="thermal"), named)
    assert load_camera(named, "thermal").width == 160
    with pytest.raises(ConfigError, match="holding camera 'thermal'"):
        load_camera(named, "left")
    rig = tmp_path / "rig.yaml"
    save_rig(StereoRig.ideal(Camera.from_fov(60.0, 320, 240), 0.1), rig)
    assert load_camera(rig).width == 320 and load_camera(rig, "right").width == 320


def test_an_empty_camera_name_in_a_file_is_no_name(tmp_path):
    """An empty ``name:`` (YAML's null) named the camera "None": save_camera wrote
    ``name: None`` back, and asking the file for the left camera said it held "camera
    'None'"; a list was named "['a']"."""
    path = tmp_path / "cam.yaml"
    body = "width: 640\nheight: 480\nK: [[500, 0, 320], [0, 500, 240], [0, 0, 1]]\n"
    path.write_text("name:\n" + body)
    assert load_camera(path).name == ""
    with pytest.raises(ConfigError, match="an unnamed camera"):
        load_camera(path, "left")
    out = tmp_path / "out.yaml"
    save_camera(load_camera(path), out)
    assert "name" not in out.read_text()
    path.write_text("name: [a]\n" + body)
    with pytest.raises(ConfigError, match="name must be text"):
        load_camera(path)
    path.write_text("name: thermal\n" + body)
    assert load_camera(path, "thermal").name == "thermal"


def test_saving_a_value_yaml_cannot_hold_is_a_calibration_error(tmp_path):
    """A Path in a rig's free-form info (or as a camera's name) was PyYAML's builtin
    RepresenterError from save_rig / save_camera; now a CalibrationError naming the value, and
    an earlier file at the path is left as it was. Plain info still round-trips."""
    from pathlib import Path

    cam = Camera.from_fov(60.0, 320, 240)
    path = tmp_path / "rig.yaml"
    path.write_text("earlier\n")
    rig = StereoRig(cam, cam, np.eye(3), [-0.1, 0.0, 0.0], info={"images": Path("left")})
    with pytest.raises(CalibrationError, match="PosixPath|WindowsPath"):
        save_rig(rig, path)
    with pytest.raises(CalibrationError, match="cannot hold"):
        save_camera(Camera(cam.K, width=320, height=240, name=Path("left")), path)
    assert path.read_text() == "earlier\n"
    save_rig(StereoRig(cam, cam, np.eye(3), [-0.1, 0.0, 0.0], info={"images": "left"}), path)
    assert load_rig(path).info == {"images": "left"}


def test_rms_in_a_rig_file_must_be_a_number(tmp_path):
    # a non-numeric rms_px escaped as a bare ValueError / TypeError (a traceback from
    # `hearsee detect --calib`); a NaN or negative one was loaded as the rig's RMS error
    cam = Camera.from_fov(60.0, 640, 480)
    path = tmp_path / "rig.yaml"
    save_rig(StereoRig(cam, cam, np.eye(3), [-0.1, 0.0, 0.0], rms_px=0.25), path)
    text = path.read_text()
    assert "rms_px: 0.25" in text
    for bad in ("abc", "[0.2, 0.3]", ".nan", "-0.5", "true"):
        path.write_text(text.replace("rms_px: 0.25", f"rms_px: {bad}"))
        with pytest.raises(ConfigError, match=r"rig.yaml: rms_px must be a finite number"):
            load_rig(path)
    path.write_text(text)
    assert load_rig(path).rms_px == pytest.approx(0.25)


def test_rig_from_opencv_refuses_nodes_that_are_not_matrices(tmp_path):
    """A D2 or T node holding a plain number or a string raised a bare AttributeError
    ('float' object has no attribute 'ravel')."""
    intr, extr = tmp_path / "intrinsics.yml", tmp_path / "extrinsics.yml"

    def write(path, **nodes):
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
        for k, v in nodes.items():
            fs.write(k, v)
        fs.release()

    write(intr, M1=K, D1=np.zeros((1, 5)), M2=K, D2=np.zeros((1, 5)))
    write(extr, R=np.eye(3), T=np.array([[-0.1], [0.0], [0.0]]))
    assert rig_from_opencv(intr, extr, (640, 480)).baseline_m == pytest.approx(0.1)
    write(intr, M1=K, D1=np.zeros((1, 5)), M2=K, D2=0.0)
    with pytest.raises(ConfigError, match="D2"):
        rig_from_opencv(intr, extr, (640, 480))
    write(intr, M1=K, D1=np.zeros((1, 5)), M2=K, D2=np.zeros((1, 5)))
    write(extr, R=np.eye(3), T="abc")
    with pytest.raises(ConfigError, match="'T'"):
        rig_from_opencv(intr, extr, (640, 480))


def test_camera_numbers_must_be_real_and_sizes_whole():
    """Bad-input sweep of the public API: Camera read a K of text ('277.1') as numbers, dropped
    a complex K's imaginary part, and a NaN width raised int()'s builtin ValueError (None a
    TypeError)."""
    good = Camera.from_fov(60.0, 320, 240)
    for K in (good.K.astype(str), good.K + 1j, good.K.astype(bool)):
        with pytest.raises(CalibrationError, match="camera K"):
            Camera(K, width=320, height=240)
    with pytest.raises(CalibrationError, match="camera dist"):
        Camera(good.K, dist=["0.1", "0", "0", "0"], width=320, height=240)
    for w in (np.nan, None, "320", True, 320.5):
        with pytest.raises(CalibrationError, match="camera size"):
            Camera(good.K, width=w, height=240)
    same = Camera(good.K.tolist(), width=320.0, height=np.int64(240))
    assert (same.width, same.height) == (320, 240) and isinstance(same.width, int)
    np.testing.assert_array_equal(same.K, good.K)


def test_pixels_points_and_settings_must_be_numbers():
    """Bad-input sweep of Camera's siblings: numpy read text as the numbers it spells and True
    as 1 -- ("320", "240") was a pixel for normalized / pixel_rays / in_image, ("0", "0", "1")
    a point for project and transform_points, "30" an angle for camera_pose, True a 1 deg
    field of view and a 1 m baseline, "640" an image size for rig_from_opencv; text sizes,
    baselines and margins raised builtin TypeErrors and a NaN margin put every pixel outside.
    The same values as numbers give the same results as before."""
    cam = Camera(K=K, dist=np.array([-0.25, 0.08, 0.001, -0.002]), width=640, height=480)
    for bad in (("320", "240"), [[True, 240.0]], [["a", "b"]], [320.0 + 1j, 240.0]):
        for f in (cam.normalized, cam.pixel_rays, cam.in_image):
            with pytest.raises(GeometryError, match="^pixel coordinates: expected numbers"):
                f(bad)
    for bad in (("0", "0", "1"), [[0.0, True, 2.0]]):
        with pytest.raises(GeometryError, match="^project: expected points as numbers"):
            cam.project(bad)
        with pytest.raises(GeometryError, match="^transform_points: points must hold numbers"):
            transform_points(np.eye(3), [0, 0, 1], bad)
    with pytest.raises(GeometryError, match="^transform_points: R must hold numbers"):
        transform_points(np.eye(3).astype(str), [0, 0, 1], [1, 2, 3])
    with pytest.raises(GeometryError, match="^transform_points: t must hold numbers"):
        transform_points(np.eye(3), ["0", "0", "1"], [1, 2, 3])
    for margin in (np.nan, "5", None):
        with pytest.raises(GeometryError, match=r"^margin \(pixels\) must be a finite number"):
            cam.in_image([320.0, 240.0], margin)
    for args in ((("0", "0", "1"),), ((0, 0, 1), "30"), ((0, 0, 1), 0.0, True)):
        with pytest.raises(GeometryError, match="camera_pose"):
            camera_pose(*args)
    for hfov in (True, "60", None):
        with pytest.raises(CalibrationError, match="hfov_deg must be in"):
            Camera.from_fov(hfov, 640, 480)
    with pytest.raises(CalibrationError, match="vfov_deg must be in"):
        Camera.from_fov(60.0, 640, 480, vfov_deg="45")
    for w in ("640", np.nan, True):
        with pytest.raises(CalibrationError, match="camera size"):
            Camera.from_fov(60.0, w, 480)
        with pytest.raises(CalibrationError, match="camera size"):
            cam.with_size(w, 240)
    for b in (True, "0.1", np.nan, 0.0):
        with pytest.raises(CalibrationError, match="baseline_m must be a finite number > 0"):
            StereoRig.ideal(cam, b)
    with pytest.raises(CalibrationError, match="thermal_offset_m"):
        StereoRig.ideal(cam, 0.1, thermal=cam, thermal_offset_m=("0.05", 0, 0))
    with pytest.raises(CalibrationError, match="thermal_rotation: expected real numbers"):
        StereoRig.ideal(cam, 0.1, thermal=cam, thermal_rotation=np.eye(3).astype(str))
    with pytest.raises(CalibrationError, match=r"rig R \(right-from-left\): expected real"):
        StereoRig(cam, cam, np.eye(3).astype(str), [-0.1, 0.0, 0.0])
    with pytest.raises(CalibrationError, match=r"rig T \(right-from-left\): expected real"):
        StereoRig(cam, cam, np.eye(3), ["-0.1", "0", "0"])
    # the same values as numbers: unchanged
    P = _points(20)
    uv = cam.project(P)
    np.testing.assert_array_equal(cam.project(P.tolist()), uv)
    np.testing.assert_allclose(cam.pixel_rays(uv), P / np.linalg.norm(P, axis=1, keepdims=True),
                               atol=1e-7)
    assert cam.in_image([320, 240], margin=np.float32(10.0)).tolist() == [True]
    assert cam.in_image([[-0.6, 0.0], [0.0, 0.0]]).tolist() == [False, True]
    R, t = camera_pose([0, 0, 1], 30, 0, 0)
    np.testing.assert_allclose(R @ np.array([np.cos(np.radians(30)), np.sin(np.radians(30)),
                                             1.0]) + t, [0, 0, 1], atol=1e-12)
    rig = StereoRig.ideal(cam, 0.1, thermal=cam, thermal_offset_m=[0.05, 0, 0],
                          thermal_rotation=np.eye(3))
    np.testing.assert_allclose(rig.thermal_center_m, [0.05, 0.0, 0.0])
    assert Camera.from_fov(60.0, 640.0, 480).size == (640, 480)


def test_rig_from_opencv_checks_its_size_and_scale(tmp_path):
    """rig_from_opencv read image_size ("640", "480") as 640 x 480 and truncated 640.7 to 640;
    a text scale_to_m was numpy's builtin TypeError and a NaN one blamed the extrinsics file."""
    intr, extr = tmp_path / "intrinsics.yml", tmp_path / "extrinsics.yml"
    for path, nodes in ((intr, dict(M1=K, D1=np.zeros((1, 5)), M2=K, D2=np.zeros((1, 5)))),
                        (extr, dict(R=np.eye(3), T=np.array([[-100.0], [0.0], [0.0]])))):
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
        for k, v in nodes.items():
            fs.write(k, v)
        fs.release()
    for size in (("640", "480"), (640.7, 480), (640,), None, (640, 480, 3), "64", 640):
        with pytest.raises(CalibrationError, match="^image_size: width and height must be"):
            rig_from_opencv(intr, extr, size, scale_to_m=0.001)
    with pytest.raises(CalibrationError, match=r"got \(640, 480, 3\)$"):  # what was given
        rig_from_opencv(intr, extr, (640, 480, 3), scale_to_m=0.001)
    for scale in ("0.001", np.nan, 0.0, True):
        with pytest.raises(ConfigError, match="^scale_to_m must be a finite number > 0"):
            rig_from_opencv(intr, extr, (640, 480), scale_to_m=scale)
    rig = rig_from_opencv(intr, extr, (640.0, np.int64(480)), scale_to_m=0.001)
    assert rig.left.size == (640, 480) and rig.baseline_m == pytest.approx(0.1)


def test_camera_and_rig_keep_copies_of_the_callers_arrays():
    """Building a Camera or a StereoRig neither freezes nor shares the caller's arrays: the
    caller can still write to them, and doing so does not change the (frozen) rig or leave
    its cached rectification stale."""
    K0 = K.copy()
    dist = np.array([-0.25, 0.08, 0.001, -0.002])
    cam = Camera(K0, dist)
    assert K0.flags.writeable and dist.flags.writeable
    K0[0, 0] = 900.0
    dist[0] = 0.0
    assert cam.fx == 500.0 and cam.dist[0] == -0.25
    R = np.eye(3)
    T = np.array([-0.1, 0.0, 0.0])
    rig = StereoRig(cam, cam, R, T)
    assert rig.Q[3, 2] == pytest.approx(10.0)  # 1 / baseline, computed before the edit
    assert R.flags.writeable and T.flags.writeable
    T[0] = -0.5
    R[0, 0] = -1.0
    assert rig.baseline_m == pytest.approx(0.1)
    assert rig.Q[3, 2] == pytest.approx(10.0)
    np.testing.assert_array_equal(rig.R, np.eye(3))
    with pytest.raises(ValueError):
        rig.T[0] = -0.5  # the rig's own arrays are read-only


@pytest.mark.parametrize("T", [[0.0, 1.0, 0.0], [-0.12, 0.12 * 1.5, 0.0], [-0.12, 0.0, 4.0]])
def test_a_rig_whose_cameras_are_not_side_by_side_says_so(T):
    """A vertical or forward baseline was refused as "the right camera is to the LEFT (T_x >
    0)" although T_x <= 0, or with "focal_px must be ... got -67.85": neither the cause."""
    cam = Camera.from_fov(60.0, 640, 480)
    rig = StereoRig(cam, cam, np.eye(3), T)
    with pytest.raises(CalibrationError, match="not side by side"):
        rig.rectify()
    assert StereoRig(cam, cam, np.eye(3), [-0.12, 0.01, 0.02]).rectify().baseline_m > 0


def test_a_rig_of_cameras_that_do_not_look_the_same_way_is_refused():
    """Cameras back to back (R = 180 deg about y) made a rig that rectified and gave depths;
    a rig toed in by 10 deg is a rig."""
    from scipy.spatial.transform import Rotation

    cam = Camera.from_fov(60.0, 640, 480)
    for deg in (180.0, 60.0):
        R = Rotation.from_euler("y", deg, degrees=True).as_matrix()
        with pytest.raises(CalibrationError, match="optical axes are"):
            StereoRig(cam, cam, R, [-0.12, 0.0, 0.0])
    R = Rotation.from_euler("y", -10.0, degrees=True).as_matrix()
    assert StereoRig(cam, cam, R, [-0.12, 0.0, 0.0]).baseline_m == pytest.approx(0.12)


def test_text_that_reads_as_a_number_is_saved_quoted(tmp_path):
    """A camera named "2e5" was written unquoted and load_yaml (which reads 1e3 as a number,
    YAML 1.2) loaded it as 200000.0 (load_camera(path, "2e5") then refused its own file);
    an info serial "1E6" came back as 1000000.0."""
    cam = Camera.from_fov(60.0, 640, 480, name="2e5")
    save_camera(cam, tmp_path / "cam.yaml")
    assert load_camera(tmp_path / "cam.yaml", "2e5").name == "2e5"
    info = {"serial": "1E6", "note": "-3.5e-2", "board": "9x6", "n": 5, "eps": 1e-17}
    rig = StereoRig(Camera(K=K, name="1e3"), Camera(K=K, name="right"), np.eye(3),
                    [-0.1, 0.0, 0.0], info=info)
    save_rig(rig, tmp_path / "rig.yaml")
    back = load_rig(tmp_path / "rig.yaml")
    assert back.info == info and back.left.name == "1e3"
    assert type(back.info["n"]) is int and type(back.info["eps"]) is float


@pytest.mark.parametrize("kw, match", [
    (dict(rms_px=np.nan), "rms_px"), (dict(rms_px=-1.0), "rms_px"), (dict(rms_px="abc"), "rms_px"),
    (dict(rms_px="0.3"), "rms_px"), (dict(rms_px=True), "rms_px"), (dict(info=["ab"]), "info"),
    (dict(info={"camera_height_m": np.nan}), "camera_height_m"),
    (dict(info={"camera_height_m": -1.4}), "camera_height_m"),
    (dict(info={"camera_pitch_deg": np.nan}), "camera_pitch_deg"),
    (dict(info={"camera_pitch_deg": 90.0}), "camera_pitch_deg"),
])
def test_rig_refuses_rms_and_info_its_files_would_refuse(kw, match, tmp_path):
    """StereoRig did not check rms_px or info: NaN / -1 and a NaN camera height made files
    load_rig refused, rms_px "abc" was a builtin ValueError in save_rig, "0.3" was read as a
    number and info ["ab"] was saved as {"a": "b"}."""
    cam = Camera(K=K)
    with pytest.raises(CalibrationError, match=match):
        StereoRig(cam, cam, np.eye(3), [-0.1, 0.0, 0.0], **kw)


def test_rig_with_good_rms_and_info_round_trips(tmp_path):
    cam = Camera(K=K)
    rig = StereoRig(cam, cam, np.eye(3), [-0.1, 0.0, 0.0], rms_px=np.float32(0.25),
                    info={"camera_height_m": 1.4})
    assert type(rig.rms_px) is float
    save_rig(rig, tmp_path / "rig.yaml")
    back = load_rig(tmp_path / "rig.yaml")
    assert back.rms_px == 0.25 and back.camera_height_m == 1.4


def test_saving_to_a_path_that_cannot_be_written_is_an_input_file_error(tmp_path):
    """save_rig / save_camera raised builtin IsADirectoryError, FileNotFoundError and
    TypeError (Path(path).write_text); every other writer checks with output_file first."""
    cam = Camera(K=K)
    rig = StereoRig.ideal(cam, 0.1)
    for path, match in ((tmp_path, "is a folder"), (tmp_path / "no" / "rig.yaml",
                                                     "does not exist"),
                        (123, "must be a file name"), (None, "must be a file name")):
        with pytest.raises(InputFileError, match=match):
            save_rig(rig, path)
        with pytest.raises(InputFileError, match=match):
            save_camera(cam, path)
    with pytest.raises(CalibrationError, match="rms_px"):
        save_camera(cam, tmp_path / "c.yaml", rms_px="abc")
    with pytest.raises(CalibrationError, match="StereoRig"):
        save_rig(cam, tmp_path / "r.yaml")
    assert not (tmp_path / "c.yaml").exists() and not (tmp_path / "r.yaml").exists()


def test_dist_and_t_of_other_shapes_are_refused(tmp_path):
    """dist and T were flattened whatever their shape: a (2, 7) dist table was read as 14
    coefficients (its second row became thin-prism and tilt terms), a (2, 2) one as k1, k2,
    p1, p2, and a T of shape (1, 3, 1) was taken. OpenCV's own shapes still are."""
    d7 = np.array([[-0.1, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0] * 5 + [0.0, 0.01]])
    for bad in (d7, np.full((2, 2), 0.01), np.zeros((1, 1, 4))):
        with pytest.raises(CalibrationError, match="camera dist: expected one row or column"):
            Camera(K=K, dist=bad)
    d = [-0.1, 0.01, 0.001, 0.0, 0.002]
    for ok in (np.array(d), np.array([d]), np.array(d).reshape(5, 1)):
        np.testing.assert_array_equal(Camera(K=K, dist=ok).dist, d)
    cam = Camera(K=K)
    for bad in (np.array([-0.1, 0.0, 0.0]).reshape(1, 3, 1), np.zeros((3, 3)) - 0.1):
        with pytest.raises(CalibrationError, match=r"rig T \(right-from-left\): expected 3"):
            StereoRig(cam, cam, np.eye(3), bad)
        with pytest.raises(CalibrationError, match="rig T_thermal: expected 3"):
            StereoRig(cam, cam, np.eye(3), [-0.1, 0.0, 0.0], cam, np.eye(3), bad)
    for ok in ([[-0.1], [0.0], [0.0]], [[-0.1, 0.0, 0.0]]):
        np.testing.assert_array_equal(StereoRig(cam, cam, np.eye(3), ok).T, [-0.1, 0.0, 0.0])
    # the same through a file: a nested dist table is a ConfigError naming the field
    path = tmp_path / "cam.yaml"
    path.write_text("width: 640\nheight: 480\nK: [[500, 0, 320], [0, 505, 240], [0, 0, 1]]\n"
                    "dist: [[-0.1, 0.01], [0.0, 0.0]]\n")
    with pytest.raises(ConfigError, match="dist: expected one row or column"):
        load_camera(path)


def test_fold_radius_checks_its_input():
    """fold_radius(["a", 0, 0, 0]) was a builtin ValueError and a NaN coefficient gave 0.0,
    which put every direction outside the lens field. The fold of r (1 + k1 r^2) is at
    1 / sqrt(-3 k1) (to its 0.001 grid)."""
    from hearsee.vision.camera import fold_radius

    for bad in (["a", 0, 0, 0], [np.nan, 0, 0, 0], [-0.28, 0, 0], [[-0.28, 0], [0, 0]], None):
        with pytest.raises(CalibrationError, match="fold_radius: dist"):
            fold_radius(bad)
    for r_max in (np.nan, 0.0, "5", 1e300, 1e6):  # (1e300: numpy's "maximum size", 1e6: 8 GB)
        with pytest.raises(CalibrationError, match="r_max"):
            fold_radius([-0.28, 0, 0, 0], r_max)
    assert fold_radius([-0.28, 0, 0, 0]) == pytest.approx(1 / np.sqrt(0.84), abs=1e-3)
    assert fold_radius([]) == np.inf and fold_radius(np.zeros((1, 5))) == np.inf


def test_fold_beyond_79_deg_is_found_and_folded_points_are_outside_the_lens_field():
    """A mild barrel lens, k1 = -0.01, folds at r = 1 / sqrt(0.03) = 5.774 (80.2 deg off the
    axis): the fold was searched only up to r = 5, so it had none, and a point 84.3 deg off
    the axis (r = 10, distorted radius 0) was "in the lens field" and landed on the principal
    point, in the image; points at r = 7-9 landed in the image too."""
    from hearsee.vision.camera import fold_radius

    assert fold_radius([-0.01, 0, 0, 0]) == pytest.approx(1 / np.sqrt(0.03), abs=1e-3)
    assert fold_radius([-0.001, 0, 0, 0]) == pytest.approx(1 / np.sqrt(0.003), rel=1e-3)
    cam = Camera(np.array([[100.0, 0, 319.5], [0, 100, 239.5], [0, 0, 1]]),
                 np.array([-0.01, 0, 0, 0]), 640, 480)
    r = np.array([1.0, 4.0, 5.5, 7.0, 8.0, 9.0, 10.0])
    pts = np.c_[0.8 * r, 0.6 * r, np.ones(len(r))]
    uv = cam.project(pts)
    assert cam.in_image(uv).all()  # (all land in the image: the folded ones too)
    np.testing.assert_allclose(uv[-1], [319.5, 239.5], atol=1e-9)
    np.testing.assert_array_equal(cam.in_lens_field(pts), r < 5.774)
    # the pixel's own ray is the unfolded direction, inside the lens field
    rays = cam.pixel_rays(uv)
    assert cam.in_lens_field(rays).all()
    np.testing.assert_allclose(rays[:3] / rays[:3, 2:], pts[:3], atol=1e-6)


@pytest.mark.parametrize("K, needle", [
    ([[1e-6, 0, 160], [0, 1e-6, 120], [0, 0, 1]], "field of view near 180 deg"),
    ([[300, 0, 160], [0, 5.0, 120], [0, 0, 1]], "field of view near 180 deg"),
    ([[300, 0, 5000], [0, 300, 120], [0, 0, 1]], "principal point"),
    ([[300, 0, 160], [0, 300, -300], [0, 0, 1]], "principal point"),
])
def test_a_camera_matrix_that_cannot_be_this_image_is_refused(K, needle):
    """A focal length of 1e-6 px (a matrix in metres) or a principal point 15 images to the
    right were accepted: `hearsee detect` reported "0 human(s)", exit 0. A fisheye's short
    focal length (0.3 x the width) and a principal point a little off the image stay."""
    with pytest.raises(CalibrationError, match=needle):
        Camera(np.array(K, float), None, 320, 240)
    Camera(np.array([[96.0, 0, 160], [0, 96.0, 120], [0, 0, 1]]), None, 320, 240)
    Camera(np.array([[300.0, 0, 340], [0, 300.0, -20], [0, 0, 1]]), None, 320, 240)


def test_a_point_nearly_sideways_projects_to_nan_without_runtime_warnings():
    """From an API audit: [1, 1, 1e-300] (in front, 90 deg off the axis) overflowed the
    distortion polynomial with RuntimeWarnings; it is NaN alone now, and near points as
    before."""
    import warnings

    cam = Camera(K, np.array([-0.12, 0.05, 0.001, -0.0005, 0.0]), 640, 480)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        uv = cam.project(np.array([[1.0, 1.0, 1e-300], [0.1, 0.2, 1.0]]))
    assert np.all(np.isnan(uv[0])) and np.all(np.isfinite(uv[1]))
    ref = cv2.projectPoints(np.array([[0.1, 0.2, 1.0]]), np.zeros(3), np.zeros(3), K,
                            cam.dist)[0].reshape(2)
    np.testing.assert_allclose(uv[1], ref, atol=1e-6)
