"""Stereo + thermal fusion: human-like objects are rejected, people kept; the failure cases."""

import numpy as np
import pytest

from hearsee.errors import CalibrationError, ConfigError, GeometryError, ImageInputError
from hearsee.sim.scenes import Entity, SceneSpec, default_rig, render_scene
from hearsee.vision.camera import StereoRig
from hearsee.vision.fusion import detect_humans, draw_detections, thermal_support
from hearsee.vision.thermal import warm_mask_celsius

RIG = default_rig(320, 240, thermal_size=(80, 60))


def _spec(seed=3, **person):
    return SceneSpec(entities=[Entity("person", -0.9, 3.0, 0.0, 1.75, dict(person)),
                               Entity("mannequin", 0.2, 3.4, 20.0, 1.75),
                               Entity("poster", 1.3, 3.0, 0.0, 1.75)],
                     width_left_m=3.0, width_right_m=3.0, depth_m=7.0, seed=seed)


@pytest.fixture(scope="module")
def scene():
    return render_scene(_spec(), RIG)


def _nearest(items, p):
    return min(items, key=lambda h: np.linalg.norm(h.position_m - p))


def test_fusion_keeps_the_person_and_rejects_human_like_objects(scene):
    res = detect_humans(scene.left, scene.right, RIG, scene.thermal_c)
    person, mannequin, poster = scene.objects
    assert len(res.humans) == 1
    h = res.humans[0]
    assert np.linalg.norm(h.position_m - person.position_m) < 0.05 * person.distance_m
    assert h.thermal_support > 0.6 and h.score >= 0.5
    # the box reaches the floor under the body (the renderer's box: the toes, a little nearer
    # than the legs); the silhouette's own stopped 14 px above it, at min_height_m
    assert abs(h.box[1] + h.box[3] - person.box[1] - person.box[3]) <= 5
    assert h.box[1] == person.box[1]
    for obj in (mannequin, poster):
        r = _nearest(res.rejected, obj.position_m)
        assert np.linalg.norm(r.position_m - obj.position_m) < 0.3
        assert r.thermal_support < 0.1 and r.reason.startswith("thermal support")
    d = res.to_dict()
    assert d["humans"][0]["box"] == h.box and d["thermal"] == "radiometric"
    assert d["humans"][0]["truncated"] is False  # in full view


def test_stereo_only_accepts_the_human_shaped_objects(scene):
    res = detect_humans(scene.left, scene.right, RIG)  # no thermal image
    assert len(res.humans) == 3  # person, mannequin, poster all look human to stereo
    assert all(h.thermal_support is None for h in res.humans)


def test_8bit_thermal_gives_the_same_decision(scene):
    res = detect_humans(scene.left, scene.right, RIG, scene.thermal_8bit)
    assert len(res.humans) == 1 and res.info["thermal"] == "relative"
    assert res.humans[0].thermal_support > 0.6


def test_failure_cases():
    """Fig. 7.22: a person in a cold coat with a covered head is rejected; a mannequin warmed
    to skin temperature is accepted."""
    cold = render_scene(_spec(clothing_c=22.5, legs_c=22.0, covered_head=True), RIG)
    res = detect_humans(cold.left, cold.right, RIG, cold.thermal_c)
    p = cold.objects[0].position_m
    assert all(np.linalg.norm(h.position_m - p) > 0.5 for h in res.humans)
    spec = _spec()
    spec.entities[1].params["temp_c"] = 33.0
    warm = render_scene(spec, RIG)
    res = detect_humans(warm.left, warm.right, RIG, warm.thermal_c)
    m = warm.objects[1].position_m
    assert any(np.linalg.norm(h.position_m - m) < 0.3 for h in res.humans)


def test_thermal_support_projection_and_weights():
    warm = np.zeros(RIG.thermal.shape, bool)
    warm[:, : RIG.thermal.width // 2] = True  # left half of the thermal image is warm
    # points 3 m ahead, left of centre (x < 0) and right of centre
    left_pts = np.array([[-0.8, y, 3.0] for y in np.linspace(-0.3, 0.9, 40)])
    right_pts = left_pts * [-1, 1, 1]
    h = np.linspace(1.7, 0.5, 40)
    assert thermal_support(left_pts, h, RIG, warm) == pytest.approx(1.0)
    assert thermal_support(right_pts, h, RIG, warm) == pytest.approx(0.0)
    # upper (head) points weigh more
    mixed = np.vstack([left_pts[:10], right_pts[10:]])
    s = thermal_support(mixed, h, RIG, warm)
    assert s > 10 / 40
    # behind the camera / outside the thermal view -> NaN
    assert np.isnan(thermal_support(left_pts * [1, 1, -1], h, RIG, warm))
    # ... also with min_points=0 (the robust top of no points: a builtin IndexError)
    assert np.isnan(thermal_support(left_pts * [1, 1, -1], h, RIG, warm, min_points=0))
    with pytest.raises(ImageInputError):
        thermal_support(left_pts, h, RIG, warm[:10])
    # (a NaN head band silently switched the head weighting off: s fell to the plain 10 / 40)
    for kw in ({"head_band_m": np.nan}, {"head_band_m": -0.1}, {"max_points": 0},
               {"max_points": 2.5}, {"min_points": -1}, {"min_points": np.nan}):
        with pytest.raises(ConfigError):
            thermal_support(mixed, h, RIG, warm, **kw)
    # max_points below min_points kept too few points ever to reach min_points: NaN for every
    # candidate without a word; equal is fine
    with pytest.raises(ConfigError, match=r"max_points \(10\) must be >= min_points \(20\)"):
        thermal_support(left_pts, h, RIG, warm, max_points=10, min_points=20)
    assert thermal_support(left_pts, h, RIG, warm, max_points=10, min_points=10) == 1.0


def test_bad_inputs(scene):
    no_thermal = StereoRig(RIG.left, RIG.right, RIG.R, RIG.T)
    with pytest.raises(CalibrationError, match="no thermal camera"):
        detect_humans(scene.left, scene.right, no_thermal, scene.thermal_c)
    with pytest.raises(ImageInputError, match="thermal"):
        detect_humans(scene.left, scene.right, RIG, scene.thermal_c[:30])
    with pytest.raises(ImageInputError):
        detect_humans(scene.left, scene.right[:100], RIG, scene.thermal_c)


def test_draw(scene):
    res = detect_humans(scene.left, scene.right, RIG, scene.thermal_c)
    img = draw_detections(scene.left, res)
    assert img.shape == scene.left.shape and not np.array_equal(img, scene.left)
    assert warm_mask_celsius(scene.thermal_c).shape == RIG.thermal.shape
    # grey and BGRA images are drawn in colour too; other pixel types and empty images are
    # refused (int64 failed inside OpenCV)
    grey = scene.left[..., 1].copy()
    for im in (grey, grey[..., None], np.dstack([scene.left, grey])):
        drawn = draw_detections(im, res)
        assert drawn.shape == scene.left.shape and np.any(drawn != scene.left)
    with pytest.raises(ImageInputError, match="8-bit"):
        draw_detections(grey.astype(np.int64), res)
    with pytest.raises(ImageInputError, match="empty"):
        draw_detections(np.zeros((0, 0), np.uint8), res)
    with pytest.raises(ImageInputError, match="image must hold numbers"):
        draw_detections([[1, 2], [3]], res)  # (a ragged list: numpy's ValueError)


def test_rig_that_needs_rectification(scene):
    """A calibrated (not yet rectified) rig goes through rectification; positions come back in
    the left camera's own frame."""
    import cv2

    R = cv2.Rodrigues(np.array([0.0, 0.002, 0.0]))[0]
    rig = StereoRig(RIG.left, RIG.right, R, RIG.T, RIG.thermal, RIG.R_thermal, RIG.T_thermal,
                    info=dict(RIG.info))
    assert not rig.is_rectified
    res = detect_humans(scene.left, scene.right, rig, scene.thermal_c)
    person = scene.objects[0]
    near = [h for h in res.humans if np.linalg.norm(h.position_m - person.position_m) < 0.5]
    assert len(near) == 1


def test_candidates_of_a_rig_that_needs_rectification_meet_the_thermal_camera_in_its_frame():
    """The stereo points are in the rectified left frame; the thermal extrinsics refer to the
    left camera's own frame. With a rig rotated by 4 deg (test_rig_that_needs_rectification's
    0.11 deg could not tell the frames apart), a person's points carried back to the left frame
    land on their warm pixels in the thermal image and the position comes back in the left
    frame; read in the rectified frame they are 2 deg (10 cm at 3 m) off."""
    import cv2

    from hearsee.vision.fusion import classify_candidates
    from hearsee.vision.humans import BodySegment, HumanCandidate, StereoDetection

    R = cv2.Rodrigues(np.array([0.0, np.radians(4.0), 0.0]))[0]
    rig = StereoRig(RIG.left, RIG.right, R, RIG.T, RIG.thermal, RIG.R_thermal, RIG.T_thermal,
                    info=dict(RIG.info))
    rect = rig.rectify()
    assert np.degrees(np.arccos((np.trace(rect.R1) - 1) / 2)) > 1.5  # (the premise)
    # a person-sized slab of points 3 m ahead, 0.2 m right, in the left camera's own frame
    g = np.stack(np.meshgrid(np.linspace(-0.2, 0.2, 9), np.linspace(-0.5, 1.0, 31)), -1)
    X = np.column_stack([g[..., 0].ravel() + 0.2, g[..., 1].ravel(), np.full(g[..., 0].size, 3.0)])
    warm = np.zeros(rig.thermal.shape, bool)
    uv = np.rint(rig.project_thermal(X)).astype(int)
    warm[uv[:, 1], uv[:, 0]] = True
    warm = cv2.dilate(warm.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    Xr = X @ rect.R1.T  # the stereo's frame
    seg = BodySegment([0, 0, 1, 1], np.ones((1, 1), bool), Xr, 1.2 - Xr[:, 1], 3.0,
                      float(1.2 - Xr[:, 1].min()), 0.4, Xr.mean(axis=0))
    det = StereoDetection([HumanCandidate(0, 0, 1.0, seg, accepted=True)], None, None, None,
                          None)
    humans, rejected = classify_candidates(det, rig, rect, warm)
    assert len(humans) == 1 and not rejected
    assert humans[0].thermal_support > 0.95
    np.testing.assert_allclose(humans[0].position_m, X.mean(axis=0), atol=1e-9)


def test_a_point_outside_a_distorting_thermal_lens_view_is_not_seen():
    """A 60-deg thermal lens with k1 = -0.35: its radial model r (1 - 0.35 r^2) peaks at
    r = 1/sqrt(1.05) (44.3 deg off the axis) and folds back beyond, so a point 60 deg off the
    axis projected to u = 67 of 160, inside the image, and a candidate standing there got
    thermal support 1.0 from the warm person in the middle of the view. Now it is not seen."""
    from hearsee.vision.camera import Camera, fold_radius

    assert fold_radius([-0.35, 0, 0, 0]) == pytest.approx(1 / np.sqrt(1.05), abs=2e-3)
    assert fold_radius([0.1, 0, 0, 0, 0]) == np.inf and fold_radius([]) == np.inf
    f = 80 / np.tan(np.radians(30))
    th = Camera(np.array([[f, 0, 79.5], [0, f, 59.5], [0, 0, 1]]), np.array([-0.35, 0, 0, 0]),
                160, 120)
    rig = RIG.with_thermal(th, np.eye(3), np.zeros(3))
    warm = np.zeros(th.shape, bool)
    warm[:, 55:105] = True  # a warm person in the middle of the thermal view
    ys = np.linspace(-0.3, 1.0, 60)
    for ang, want in ((60.0, None), (0.0, 1.0)):
        pts = np.column_stack([np.full(60, 3 * np.tan(np.radians(ang))), ys, np.full(60, 3.0)])
        if ang == 60.0:
            assert th.in_image(th.project(pts)).all()  # (the fold: "inside" the image)
            assert not th.in_lens_field(pts).any()
        got = thermal_support(pts, 1.4 - ys, rig, warm)
        assert np.isnan(got) if want is None else got == want
    with pytest.raises(GeometryError, match=r"shape \(N, 3\)"):
        th.in_lens_field(np.ones((5, 2)))
    with pytest.raises(GeometryError, match="numbers"):
        th.in_lens_field("1, 2, 3")


def test_frozen_8bit_thermal_frame_verifies_nobody(scene):
    """A flat (shutter closed / frozen) 8-bit thermal frame used to make every pixel warm, so
    the person, the mannequin and the poster were all accepted; now nobody is verified."""
    frozen = np.full_like(scene.thermal_8bit, 128)
    res = detect_humans(scene.left, scene.right, RIG, frozen)
    assert res.humans == [] and not res.warm_mask.any()
    stereo_ok = [h for h in res.rejected if h.reason.startswith("thermal support")]
    assert len(stereo_ok) == 3 and all(h.thermal_support == 0.0 for h in stereo_ok)


def test_thermal_support_refuses_a_0_255_mask_and_bad_weights():
    """A 0/255 uint8 mask gave a "fraction" of 255; a negative head weight a meaningless one."""
    warm = np.zeros(RIG.thermal.shape, bool)
    warm[:, : RIG.thermal.width // 2] = True
    pts = np.array([[-0.8, y, 3.0] for y in np.linspace(-0.3, 0.9, 40)])
    h = np.linspace(1.7, 0.5, 40)
    with pytest.raises(ImageInputError, match="0/255"):
        thermal_support(pts, h, RIG, warm.astype(np.uint8) * 255)
    # 0/1 numbers are a mask too
    assert thermal_support(pts, h, RIG, warm.astype(np.uint8)) == pytest.approx(1.0)
    assert thermal_support(pts, h, RIG, warm.astype(float).tolist()) == pytest.approx(1.0)
    for w in (0.0, -1.0, np.nan):
        with pytest.raises(ConfigError, match="head_weight"):
            thermal_support(pts, h, RIG, warm, head_weight=w)
    with pytest.raises(GeometryError, match="heights"):
        thermal_support(pts, h[:5], RIG, warm)
    # a (H, W, 1) mask was "20x15 pixels but the thermal camera is 20x15"
    with pytest.raises(ImageInputError, match=r"must be \(H, W\) = .* got shape \(\d+, \d+, 1\)"):
        thermal_support(pts, h, RIG, warm[..., None])


def test_bad_camera_height_is_refused_before_matching(scene):
    """A NaN or negative camera height (argument or the calibration's info) silently removed
    every person (or, as a string, raised a bare ValueError)."""
    for bad in (np.nan, -1.4, 0.0):
        with pytest.raises(GeometryError, match="camera_height_m"):
            detect_humans(scene.left, scene.right, RIG, camera_height_m=bad)
    for bad in ("abc", np.nan, -1.0):
        # refused when the rig is built (StereoRig checks its info since the rule of load_rig)
        with pytest.raises(CalibrationError, match="info: camera_height_m"):
            StereoRig(RIG.left, RIG.right, RIG.R, RIG.T, info={"camera_height_m": bad})
        # and by the detector when the (mutable) info dict is edited afterwards
        rig = StereoRig(RIG.left, RIG.right, RIG.R, RIG.T, info={"camera_height_m": 1.4})
        rig.info["camera_height_m"] = bad
        with pytest.raises(ConfigError, match="info: camera_height_m"):
            detect_humans(scene.left, scene.right, rig)


def test_detect_humans_refuses_bad_thermal_images_params_and_options_before_matching(
        scene, monkeypatch):
    """A thermal 'image' of text or a number was an IndexError, params given as a dict an
    AttributeError, an unknown stereo option a builtin TypeError; each is hearsee's own error
    now, before the stereo matching (which is made to fail the test if reached)."""
    import hearsee.vision.fusion as fusion
    from hearsee.vision.humans import HumanDetectorParams
    from hearsee.vision.stereo import stereo_frame

    def never(*args, **kwargs):
        raise AssertionError("the stereo matching ran before the inputs were checked")

    monkeypatch.setattr(fusion, "stereo_frame", never)
    for bad in ("abc", 5.0, np.zeros(7)):
        with pytest.raises(ImageInputError, match="thermal image"):
            detect_humans(scene.left, scene.right, RIG, bad, camera_height_m=1.4)
    with pytest.raises(ImageInputError, match="thermal image is"):
        detect_humans(scene.left, scene.right, RIG, scene.thermal_c[:-1], camera_height_m=1.4)
    with pytest.raises(ConfigError, match="HumanDetectorParams"):
        detect_humans(scene.left, scene.right, RIG, params={"tm": 0.5}, camera_height_m=1.4)
    # stereo options that are no mapping of names: a builtin TypeError (a list of pairs was
    # taken as the mapping it spells)
    for bad in ([1], [("num_disparities", 16)], {16: "num_disparities"}, "scale"):
        with pytest.raises(ConfigError, match="stereo_options"):
            detect_humans(scene.left, scene.right, RIG, stereo_options=bad, camera_height_m=1.4)
    monkeypatch.undo()
    with pytest.raises(ConfigError, match="unknown disparity option.*foo"):
        stereo_frame(scene.left, scene.right, RIG, foo=1)
    with pytest.raises(ConfigError, match="unknown disparity option"):
        detect_humans(scene.left, scene.right, RIG, stereo_options={"foo": 1},
                      params=HumanDetectorParams(), camera_height_m=1.4)


def test_detect_humans_refuses_a_colour_float_thermal_image_before_matching(scene, count_calls):
    """An (H, W, 3) float thermal image of the right height and width passed the early check
    (height and width only) and was refused by the thermal filter only after the stereo
    matching had run; now before it (the matcher records its calls)."""
    import hearsee.vision.fusion as fusion

    calls = count_calls(fusion, "stereo_frame")
    colour = np.repeat(scene.thermal_c[:, :, None], 3, axis=2).astype(float)
    with pytest.raises(ImageInputError, match="multi-channel thermal image must be 8-bit"):
        detect_humans(scene.left, scene.right, RIG, colour, camera_height_m=1.4)
    with pytest.raises(ConfigError, match="band_c"):  # a bad band too
        detect_humans(scene.left, scene.right, RIG, scene.thermal_c, camera_height_m=1.4,
                      band_c=(37.0, 30.0))
    assert calls == []


def test_a_nan_thermal_threshold_is_refused(scene):
    """min_support=NaN rejected every candidate (support >= NaN is False) without a word."""
    from hearsee.errors import ConfigError

    for bad in (np.nan, -0.1, 1.5):
        with pytest.raises(ConfigError, match="min_support"):
            detect_humans(scene.left, scene.right, RIG, scene.thermal_c, camera_height_m=1.4,
                          min_support=bad)


def test_thermal_support_head_band_ignores_one_stray_high_point():
    """The head band is counted down from the silhouette's robust top (as BodySegment.top_m),
    not its highest point: one stray point 2.6 m up (a wall pixel in the depth band) moved the
    band onto itself, the warm head lost its double weight and the support fell from
    120 / 362 = 0.331 to 60 / 302 = 0.199, below the default min_support of 0.3 (the stray
    point, above the top, weighs double either way)."""
    warm = np.zeros(RIG.thermal.shape, bool)
    warm[:, : RIG.thermal.width // 2] = True  # left half of the thermal image is warm
    cam_h, z = 1.4, 3.0
    head_h = np.linspace(1.36, 1.75, 60)  # top 0.4 m: warm (left of centre)
    body_h = np.linspace(0.3, 1.3, 240)  # cold (right of centre)
    h = np.concatenate([head_h, body_h])
    x = np.concatenate([np.full(60, -0.8), np.full(240, 0.8)])
    pts = np.column_stack([x, cam_h - h, np.full(len(h), z)])
    expected = 2 * 60 / (2 * 60 + 240)
    assert thermal_support(pts, h, RIG, warm) == pytest.approx(expected)
    stray = np.array([[0.8, cam_h - 2.6, z]])  # cold, inside the thermal view
    pts1, h1 = np.vstack([pts, stray]), np.append(h, 2.6)
    assert thermal_support(pts1, h1, RIG, warm) == pytest.approx(2 * 60 / (2 * 60 + 240 + 2))


def test_detect_humans_needs_a_rig():
    """detect_humans(left, right, None) raised a builtin AttributeError."""
    img = np.zeros((120, 160), np.uint8)
    with pytest.raises(CalibrationError, match="StereoRig"):
        detect_humans(img, img, None)


def test_thermal_support_points_must_be_numbers():
    """thermal_support read silhouette points and heights of text as metres (a support from
    text). Now a GeometryError; the same numbers give the same support."""
    warm = np.zeros(RIG.thermal.shape, bool)
    warm[:, : RIG.thermal.width // 2] = True
    pts = np.array([[-0.8, y, 3.0] for y in np.linspace(-0.3, 0.9, 40)])
    h = np.linspace(1.7, 0.5, 40)
    for P, hh in ((pts.astype(str), h), (pts, h.astype(str)), (pts.tolist(), [True] * 40)):
        with pytest.raises(GeometryError, match="points and heights must be numbers"):
            thermal_support(P, hh, RIG, warm)
    assert thermal_support(pts.tolist(), h.tolist(), RIG, warm) == \
        thermal_support(pts, h, RIG, warm) == pytest.approx(1.0)
