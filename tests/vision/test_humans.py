"""Stereo human candidates: P(y,d), scale-adaptive filter, floor, segmentation, head-shoulder."""

import cv2
import numpy as np
import pytest

from hearsee.errors import (
    CalibrationError,
    ConfigError,
    EstimationError,
    GeometryError,
    ImageInputError,
)
from hearsee.sim.scenes import Entity, SceneSpec, default_rig, pitched_view, render_scene
from hearsee.vision.fusion import detect_humans
from hearsee.vision.humans import (
    TOP_PERCENTILE,
    TORSO_HEIGHT_FRACTION,
    FloorPlane,
    HumanDetectorParams,
    _iou,
    cut_by_border,
    detect_candidates,
    detect_people_hog,
    disparity_band_px,
    estimate_floor,
    find_peaks,
    head_shoulder_score,
    robust_top_m,
    scale_adaptive_filter,
    segment_band_m,
    segment_body,
    u_disparity,
    upper_contour,
)
from hearsee.vision.stereo import points_from_disparity

F, B = 250.0, 0.12


def test_u_disparity_counts():
    d = np.full((10, 6), np.nan, np.float32)
    d[2:9, 1] = 5.0  # 7 pixels at disparity 5 in column 1
    d[0:3, 4] = 2.2  # 3 pixels at disparity 2 in column 4
    P = u_disparity(d, max_disparity=8)
    assert P.shape == (9, 6)
    assert P[5, 1] == 7 and P[2, 4] == 3 and P.sum() == 10
    mask = np.zeros_like(d, bool)
    mask[:5] = True
    assert u_disparity(d, mask, max_disparity=8)[5, 1] == 3
    with pytest.raises(ImageInputError):
        u_disparity(np.zeros(5))


def test_u_disparity_refuses_impossible_disparities_and_bad_options():
    """A disparity wider than the image asked for terabytes of counts (MemoryError); a
    negative max_disparity and a mask of another shape failed inside numpy."""
    d = np.full((4, 6), 3.0, np.float32)
    d[1, 2] = 1e12
    with pytest.raises(ImageInputError, match="exceeds the image width"):
        u_disparity(d)
    d[1, 2] = 6.0  # as wide as the image: still possible (sub-pixel), counted
    assert u_disparity(d)[6, 2] == 1
    for bad in (-5, 2.5, 10**9):
        with pytest.raises(ConfigError, match="max_disparity"):
            u_disparity(d, max_disparity=bad)
    with pytest.raises(ImageInputError, match="mask must have"):
        u_disparity(d, mask=np.ones((3, 3), bool))


def _blob_P(width_cols: int, d: int, col: int, n_d: int = 40, W: int = 200, rows: float = 50):
    P = np.zeros((n_d, W))
    P[d, col - width_cols // 2: col + width_cols // 2 + 1] = rows
    return P


def test_scale_adaptive_filter_finds_person_width_blob_not_walls():
    d = 20  # Z = f B / d = 1.5 m; a 0.4 m wide person spans 0.4 d / B ~ 67 columns
    w = int(0.4 * d / B)
    P = _blob_P(w, d, 100, W=260)
    rows = np.full(40, 50.0)
    psi = scale_adaptive_filter(P, F, B, expected_rows=rows)
    dd, yy = np.unravel_index(np.argmax(psi), psi.shape)
    assert abs(yy - 100) <= 4 and abs(dd - d) <= 2
    assert psi[dd, yy] > 0.8
    # a wall: the same occupancy along every column cancels out
    wall = np.zeros((40, 260))
    wall[d] = 50.0
    psi_w = scale_adaptive_filter(wall, F, B, expected_rows=rows)
    assert psi_w[d, 30:230].max() < 0.05
    # peaks: the blob, once
    peaks = find_peaks(psi, F, B, threshold=0.3)
    assert len(peaks) >= 1 and abs(peaks[0][0] - 100) <= 4


def test_kernel_width_scales_with_disparity():
    """Two blobs of one metric width at two depths give the same normalised response."""
    rows = np.full(60, 40.0)
    out = []
    for d in (12, 36):
        P = _blob_P(int(0.4 * d / B), d, 200, n_d=60, W=400)
        psi = scale_adaptive_filter(P, F, B, expected_rows=rows)
        out.append(psi[d - 1: d + 2, 195:206].max())
    assert out[0] == pytest.approx(out[1], rel=0.1)


def _plane_points(height: float, tilt_deg: float, H=120, W=160):
    """Points of a floor ``height`` below a camera pitched down by ``tilt_deg``."""
    K = np.array([[F, 0, (W - 1) / 2], [0, F, (H - 1) / 2], [0, 0, 1.0]])
    uu, vv = np.meshgrid(np.arange(W), np.arange(H))
    rays = np.stack([(uu - K[0, 2]) / F, (vv - K[1, 2]) / F, np.ones_like(uu, float)], -1)
    a = np.radians(tilt_deg)
    up = np.array([0.0, -np.cos(a), -np.sin(a)])  # floor normal seen from a pitched-down camera
    denom = rays @ up
    with np.errstate(divide="ignore"):
        t = -height / denom
    pts = rays * t[..., None]
    pts[~(t > 0) | (t > 30)] = np.nan
    return pts, up


def test_estimate_floor_recovers_height_and_tilt():
    pts, up = _plane_points(1.3, 5.0)
    fl = estimate_floor(pts)
    assert fl.source == "ransac"
    assert fl.camera_height_m == pytest.approx(1.3, abs=0.01)
    assert np.degrees(np.arccos(np.clip(fl.normal @ up, -1, 1))) < 0.5
    assert fl.height(np.array([0.0, 0.0, 0.0])) == pytest.approx(1.3, abs=0.01)


@pytest.mark.parametrize("down_deg", [-12.0, 30.0, 45.0])
def test_estimate_floor_with_the_cameras_pitch_as_prior(down_deg):
    """A camera pitched down 30 or 45 deg (a head looking at a person close by) or up 12 deg:
    level taken as the prior, a floor tilted more than max_tilt_deg (20) from level could
    never be found and the level fallback was 30-45 deg wrong. With the pitch as the prior
    RANSAC finds the floor; its pitch_deg reads the pitch back."""
    # (looking up, the 160x120 view's +-13.5 deg shows no floor within 10 m: a taller one)
    pts, up = _plane_points(1.3, down_deg, H=120 if down_deg > 0 else 240)
    fl = estimate_floor(pts, prior_height_m=1.3, prior_pitch_deg=-down_deg)
    assert fl.source == "ransac" and fl.camera_height_m == pytest.approx(1.3, abs=0.01)
    assert np.degrees(np.arccos(np.clip(fl.normal @ up, -1, 1))) < 0.5
    assert fl.pitch_deg == pytest.approx(-down_deg, abs=0.5)
    if abs(down_deg) > 20:  # the level prior refuses the true floor: its fallback is level
        lv = estimate_floor(pts, prior_height_m=1.3)
        assert lv.source == "prior" and lv.pitch_deg == 0.0


def test_floor_of_a_pitched_camera_and_its_fallback():
    """FloorPlane.from_camera: the floor of a camera h m up pitched p deg (+ = up). A floor
    point 4 m ahead seen by a camera pitched up 15 deg is at height 0, the camera's own
    centre at h; with no floor in view the fallback is that floor, not a level one."""
    h, p = 1.2, 15.0
    R, _ = pitched_view(p)  # level -> pitched camera
    floor_pt = R @ np.array([0.3, h, 4.0])  # (a level frame: y down, the floor h below)
    head = R @ np.array([0.0, h - 1.7, 3.0])  # a crown 1.7 m above the floor
    fl = FloorPlane.from_camera(h, p)
    assert fl.height(floor_pt) == pytest.approx(0.0, abs=1e-12)
    assert fl.height(head) == pytest.approx(1.7, abs=1e-12)
    assert fl.height(np.zeros(3)) == pytest.approx(h) and fl.pitch_deg == pytest.approx(p)
    assert FloorPlane.from_camera(h).normal.tolist() == FloorPlane.level(h).normal.tolist() \
        == [0.0, -1.0, 0.0]
    empty = np.full((40, 40, 3), np.nan)
    fb = estimate_floor(empty, prior_height_m=h, prior_pitch_deg=p)
    assert fb.source == "prior" and fb.pitch_deg == pytest.approx(p)
    assert fb.height(floor_pt) == pytest.approx(0.0, abs=1e-12)
    for bad in (np.nan, 81.0, -90.0, "10", True):
        with pytest.raises(GeometryError, match="pitch"):
            FloorPlane.from_camera(h, bad)
        with pytest.raises(GeometryError, match="prior_pitch_deg"):
            estimate_floor(empty, prior_height_m=h, prior_pitch_deg=bad)


@pytest.fixture(scope="module")
def pitched_up_scene():
    """A person and a mannequin seen by a camera 1.4 m up pitched up 15 deg: the nearest
    floor in view is ~6 m out, too little to fit."""
    import dataclasses

    rig = default_rig(320, 240, thermal_size=(80, 60))
    spec = SceneSpec(entities=[Entity("person", -0.6, 3.5, 0.0, 1.8),
                               Entity("mannequin", 0.9, 4.0, 0.0, 1.75)],
                     width_left_m=3.0, width_right_m=3.0, depth_m=8.0, seed=11)
    sc = render_scene(spec, rig, view=pitched_view(15.0))
    return sc, dataclasses.replace(sc.rig, info={**sc.rig.info, "camera_pitch_deg": 0.0})


def test_detect_humans_with_a_pitched_camera(pitched_up_scene):
    """Taken as level (the only choice until 2026-12-03), the camera pitched up 15 deg found
    nobody: the level fallback floor put the person's top 0.7-0.9 m too low. With the pitch
    (an argument, or the calibration's info.camera_pitch_deg, which the rendered scene's rig
    now carries) the person is found where they stand and the mannequin is still rejected by
    its thermal image."""
    sc, rig_level = pitched_up_scene
    person, mannequin = sc.objects
    assert sc.rig.info["camera_pitch_deg"] == pytest.approx(15.0, abs=1e-9)
    level = detect_humans(sc.left, sc.right, rig_level, sc.thermal_c)
    assert level.humans == [] and level.info["floor"]["camera_pitch_deg"] == 0.0
    for det in (detect_humans(sc.left, sc.right, rig_level, sc.thermal_c,
                              camera_pitch_deg=15.0),
                detect_humans(sc.left, sc.right, sc.rig, sc.thermal_c)):
        assert det.info["floor"]["camera_pitch_deg"] == pytest.approx(15.0, abs=1.0)
        assert len(det.humans) == 1
        assert np.linalg.norm(det.humans[0].position_m - person.position_m) < 0.15
        assert det.humans[0].height_m == pytest.approx(person.height_m, abs=0.12)
        near_m = [np.linalg.norm(np.asarray(r.position_m) - mannequin.position_m)
                  for r in det.rejected if r.reason.startswith("thermal")]
        assert near_m and min(near_m) < 0.3
    with pytest.raises(GeometryError, match="camera_pitch_deg"):
        detect_humans(sc.left, sc.right, sc.rig, sc.thermal_c, camera_pitch_deg=95.0)


@pytest.mark.parametrize("pitch_deg", [-15.0, 15.0])
def test_torso_of_a_pitched_camera_is_above_where_the_person_stands(pitch_deg):
    """On exact disparities and the true floor of a camera pitched 15 deg up or down,
    the torso centre lies where the person stands, as with a level camera (within 1 cm). It
    was moved from the visible surface's median height to the torso's along the camera's
    tilted y axis, (0.15-0.2 m) * sin(pitch) off: 4.1 cm too far here pitched down."""
    rig = default_rig(320, 240, thermal_size=(80, 60))
    x, z, tall = 0.3, 3.0, 1.75
    spec = SceneSpec(entities=[Entity("person", x, z, 0.0, tall, {"build": 1.0})],
                     width_left_m=3.0, width_right_m=3.0, depth_m=8.0, seed=3)
    R, _ = pitched_view(pitch_deg)
    sc = render_scene(spec, rig, view=(R, np.zeros(3)), noise_std=0.0)
    rect = sc.rig.rectification
    det = detect_candidates(sc.disparity, points_from_disparity(sc.disparity, rect.Q),
                            rect.focal_px, rect.baseline_m, rect.cy,
                            floor=FloorPlane.from_camera(1.4, pitch_deg))
    (person,) = [c for c in det.candidates if c.accepted]
    torso = R.T @ person.position_m  # back to the level frame: x right, y down, z forward
    truth = np.array([x, 1.4 - TORSO_HEIGHT_FRACTION * tall, z])
    assert np.abs(torso - truth) == pytest.approx(np.zeros(3), abs=0.01)


def _wall_scene(h: float, wall_z: float, f: float = 500.0, B: float = 0.12, W: int = 640,
                H: int = 480, noise_px: float = 0.25, seed: int = 0) -> np.ndarray:
    """Points (H, W, 3) of a level camera ``h`` m above the floor facing a wall ``wall_z`` m
    away (a strip of floor, or none, in view) with a person-sized slab 0.5 m in front of the
    wall; disparity noise ``noise_px``."""
    v, u = np.mgrid[0:H, 0:W].astype(float)
    rx, ry = (u - W / 2) / f, (v - H / 2) / f  # ray (rx, ry, 1), y down
    with np.errstate(divide="ignore"):
        Z = np.minimum(np.full((H, W), wall_z), np.where(ry > 0, h / ry, np.inf))
    zp = wall_z - 0.5
    person = (rx * zp > -0.3) & (rx * zp < 0.2) & (ry * zp > h - 1.75) & (ry * zp < h)
    Z = np.where(person & (zp < Z), zp, Z)
    d = f * B / Z + np.random.default_rng(seed).normal(0.0, noise_px, Z.shape)
    Zn = f * B / d
    return np.dstack([rx * Zn, ry * Zn, Zn])


@pytest.mark.parametrize("wall_z", [2.6, 3.0, 4.0, 5.0])
def test_estimate_floor_facing_a_wall(wall_z):
    """With little or no floor in view, a plane tilted 8-20 deg through the wall's base and the
    person's legs won on inliers alone (hundreds of points below it): the person's feet came
    out 0.33-0.55 m below "the floor" with a wall 2.6 m away. Points below a hypothesis now
    count against it; no floor in view gives the prior."""
    h = 1.25
    fl = estimate_floor(_wall_scene(h, wall_z), prior_height_m=h)
    feet = np.array([0.0, h, wall_z - 0.5])
    assert abs(float(fl.height(feet))) < 0.03
    assert np.degrees(np.arccos(-fl.normal[1])) < 2.0
    if wall_z == 2.6:  # the floor's first visible row is 2.6 m away: no floor in view
        assert fl.source == "prior"


def test_estimate_floor_fallback_and_error():
    empty = np.full((40, 40, 3), np.nan)
    assert estimate_floor(empty, prior_height_m=1.2).camera_height_m == 1.2
    with pytest.raises(EstimationError, match="camera_height_m"):
        estimate_floor(empty)
    for kw in (dict(step=0), dict(step=-1), dict(step=2.0), dict(iterations=0),
               dict(inlier_m=0.0), dict(max_tilt_deg=np.nan), dict(max_tilt_deg=120.0)):
        with pytest.raises(ConfigError, match=next(iter(kw))):  # step 0: numpy's slice error
            estimate_floor(empty, prior_height_m=1.2, **kw)
    with pytest.raises(ImageInputError, match="H, W, 3"):
        estimate_floor(np.zeros((40, 3)), prior_height_m=1.2)
    assert FloorPlane.level(1.4).height(np.array([0.0, 1.4, 3.0])) == pytest.approx(0.0)


def _silhouette(head: bool, depth=3.0, f=F):
    """A body silhouette (bool mask) drawn in metres: head ellipse + shoulders/torso."""
    s = f / depth
    W, H = int(0.9 * s), int(1.0 * s)
    m = np.zeros((H, W), np.uint8)
    cx = W // 2
    top = 2
    if head:
        cv2.ellipse(m, (cx, top + int(0.11 * s)), (int(0.08 * s), int(0.11 * s)), 0, 0, 360, 1, -1)
        cv2.rectangle(m, (cx - int(0.05 * s), top + int(0.18 * s)),
                      (cx + int(0.05 * s), top + int(0.3 * s)), 1, -1)
        sh = top + int(0.27 * s)
    else:
        sh = top
    cv2.rectangle(m, (cx - int(0.2 * s), sh), (cx + int(0.2 * s), H - 1), 1, -1)
    return m.astype(bool)


def test_head_shoulder_template_separates_people_from_boxes():
    person = _silhouette(True)
    box = _silhouette(False)
    sp, params = head_shoulder_score(person, 3.0, F)
    sb, _ = head_shoulder_score(box, 3.0, F)
    assert sp > 0.7 and sb < 0.5
    assert 0.3 <= params["shoulder_width_m"] <= 0.54
    assert params["head_offset_m"] == pytest.approx(0.0, abs=0.03)
    top = upper_contour(person)
    assert np.nanmin(top) == 2


@pytest.fixture(scope="module")
def small_scene():
    rig = default_rig(320, 240, thermal_size=(80, 60))
    spec = SceneSpec(entities=[Entity("person", -0.6, 3.0, 0.0, 1.8),
                               Entity("box", 1.0, 3.5, 0, 0.9, {"width_m": 0.8})],
                     width_left_m=3.0, width_right_m=3.0, depth_m=7.0, seed=5)
    return render_scene(spec, rig)


def test_detect_candidates_on_ground_truth_disparity(small_scene):
    sc = small_scene
    rect = sc.rig.rectification
    pts = points_from_disparity(sc.disparity, rect.Q)
    det = detect_candidates(sc.disparity, pts, rect.focal_px, rect.baseline_m, rect.cy,
                            camera_height_m=1.4)
    assert det.floor.camera_height_m == pytest.approx(1.4, abs=0.02)
    acc = [c for c in det.candidates if c.accepted]
    assert len(acc) == 1
    person = sc.objects[0]
    c = acc[0]
    assert np.linalg.norm(c.position_m - person.position_m) < 0.05 * 3.0
    assert c.segment.top_m == pytest.approx(1.8, abs=0.06)
    # the torso's height: 0.675 of the crown's, not of the robust top's (2.4 cm too low)
    assert abs(c.position_m[1] - person.position_m[1]) < 0.01  # optical y, down
    x, y, w, h = c.box
    px, py, pw, ph = person.box
    assert abs(x - px) <= 3 and abs(y - py) <= 3 and abs(w - pw) <= 6
    # the box is a candidate too, but fails verification (too low / no head)
    assert not any(c.accepted and c.box[0] > 200 for c in det.candidates)
    # Tm = 1 accepts nothing
    det1 = detect_candidates(sc.disparity, pts, rect.focal_px, rect.baseline_m, rect.cy,
                             camera_height_m=1.4, params=HumanDetectorParams(tm=1.0))
    assert not any(c.accepted for c in det1.candidates)


def test_cut_by_border_counts_the_top_left_and_right_borders_only():
    """The rule behind BodySegment.truncated on known boxes in a 640-pixel-wide image: the top,
    left or right border cuts the silhouette; feet cut by the bottom border do not count."""
    for box in ([100, 0, 150, 400], [0, 50, 150, 400], [500, 50, 140, 400]):
        assert cut_by_border(box, 640)
    for box in ([100, 50, 150, 430], [100, 50, 150, 400], [1, 1, 638, 479]):
        assert not cut_by_border(box, 640)  # bottom at 480 / inside


def test_silhouettes_cut_by_the_image_border_are_flagged():
    """A person 1.3 m away at the right edge of the view is cut by the right border: flagged
    truncated, and its torso centre lies toward the visible part (the bias the flag warns of);
    people in full view (centred, and near the left edge) are not."""
    rig = default_rig(320, 240, thermal_size=(80, 60))
    spec = SceneSpec(entities=[Entity("person", 0.0, 3.0, 0.0, 1.8),
                               Entity("person", 0.9, 1.3, 0.0, 1.8),
                               Entity("person", -1.55, 3.2, 0.0, 1.7)],
                     width_left_m=3.0, width_right_m=3.0, depth_m=7.0, seed=5)
    sc = render_scene(spec, rig)
    rect = sc.rig.rectification
    det = detect_candidates(sc.disparity, points_from_disparity(sc.disparity, rect.Q),
                            rect.focal_px, rect.baseline_m, rect.cy, camera_height_m=1.4)
    segs = [c.segment for c in det.candidates if c.segment is not None]
    W = sc.disparity.shape[1]
    for obj in sc.objects:
        seg = min(segs, key=lambda g: np.linalg.norm(g.position_m - obj.position_m))
        x, y, w, _ = obj.box  # the renderer's ground-truth box
        assert seg.truncated == (x <= 0 or y <= 0 or x + w >= W)
        if seg.truncated:
            assert obj.position_m[0] - seg.position_m[0] > 0.05  # biased toward the view
    assert sum(g.truncated for g in segs if g.position_m[2] < 2.0) == 1


def test_people_nearer_than_the_disparity_search_are_flagged():
    """A person facing the camera 0.95 m away (640x480, f B = 60 px m): the default search of
    64 disparities ends at 0.95 m, so the front of the body gets the search's last disparity
    or none, 47 % of the silhouette's box is unmatched and its torso centre comes out 14 cm
    off (a robot's track turned around on such a fix). The detection says so
    (beyond_search); with 96 disparities the same person is seen whole, 2 cm off, and not
    flagged. 1.05 m away the body reaches the search's end too (27 % of the silhouette) but
    is whole (11 % unmatched, as people in full view) and 2 cm off: not flagged."""
    rig = default_rig()
    for z, nd, flagged in ((0.95, 64, True), (0.95, 96, False), (1.05, 64, False)):
        sc = render_scene(SceneSpec(entities=[Entity("person", 0.0, z, 0.0, 1.75)],
                                    depth_m=6.0, seed=3), rig)
        res = detect_humans(sc.left, sc.right, rig, sc.thermal_c,
                            stereo_options={"num_disparities": nd})
        assert res.frame.search_px == (0.0, nd - 1.0)
        truth = sc.people[0].position_m
        near = [h for h in res.humans if np.linalg.norm(h.position_m - truth) < 0.3]
        assert len(near) == 1
        err = np.linalg.norm(near[0].position_m - truth)
        assert near[0].beyond_search == flagged
        assert near[0].to_dict()["beyond_search"] == flagged
        assert (err > 0.1) if flagged else (err < 0.03)


def test_search_end_shares_on_known_maps():
    """near_search_share and unmatched_share on a hand-made disparity map: a 10x10 box whose
    mask covers its left half; of the mask's 50 pixels 10 hold the search's end (63 px), 5
    are NaN (not counted) and the rest 50 px; the right half holds 20 NaN and 5 zero pixels."""
    from hearsee.vision.humans import BodySegment, near_search_share, unmatched_share

    d = np.full((20, 30), 40.0, np.float32)
    box = [5, 4, 10, 10]
    sub = d[4:14, 5:15]
    sub[:, :5] = 50.0
    sub[0:2, :5] = 63.0  # 10 pixels at the end of the search
    sub[2, :5] = np.nan  # 5 unmatched pixels inside the mask
    sub[5:9, 5:10] = np.nan  # 20 unmatched pixels outside it
    sub[9, 5:10] = 0.0  # 5 more
    mask = np.zeros((10, 10), bool)
    mask[:, :5] = True
    seg = BodySegment(box, mask, np.zeros((1, 3)), np.zeros(1), 1.0, 1.7, 0.4, np.zeros(3))
    assert near_search_share(d, seg, 63.0) == pytest.approx(10 / 45)
    assert near_search_share(d, seg, 63.4) == pytest.approx(10 / 45)  # within half a pixel
    assert near_search_share(d, seg, 63.6) == 0.0
    assert unmatched_share(d, box) == pytest.approx(30 / 100)


def test_search_end_must_be_a_positive_number_of_pixels(small_scene):
    """detect_candidates' search_max_px: NaN switched the test off, 0 or a negative value
    rejected everyone."""
    rect = small_scene.rig.rectification
    pts = points_from_disparity(small_scene.disparity, rect.Q)
    for bad in (float("nan"), 0.0, -5.0, "63"):
        with pytest.raises(ConfigError, match="search_max_px"):
            detect_candidates(small_scene.disparity, pts, rect.focal_px, rect.baseline_m,
                              rect.cy, camera_height_m=1.4, search_max_px=bad)


def test_detect_candidates_bad_shapes():
    with pytest.raises(ImageInputError):
        detect_candidates(np.zeros((10, 10)), np.zeros((10, 11, 3)), F, B, 5.0)
    with pytest.raises(ImageInputError, match="empty"):  # was numpy's argmax error
        detect_candidates(np.zeros((0, 0)), np.zeros((0, 0, 3)), F, B, 5.0)


def test_negative_disparities_are_not_matches():
    """OpenCV matchers search negative disparities too; an all-negative map made the count
    array's size negative (ValueError). It holds no match: no candidates, like all-NaN."""
    H, W = 60, 80
    pts = np.full((H, W, 3), np.nan)
    for disparity in (np.full((H, W), -5.0), np.full((H, W), np.nan)):
        det = detect_candidates(disparity, pts, F, B, H / 2, camera_height_m=1.2)
        assert det.candidates == [] and det.P.sum() == 0


def test_hog_baseline():
    assert detect_people_hog(np.zeros((160, 120), np.uint8)) == []
    with pytest.raises(ImageInputError):
        detect_people_hog(np.zeros((160, 120), np.float32))


def test_bad_focal_baseline_and_camera_height_are_refused():
    """A zero, negative or NaN focal length / baseline / camera height silently gave no people
    (or a ValueError deep inside); now a typed error at the top."""
    d = np.full((40, 60), 8.0, np.float32)
    pts = np.zeros((40, 60, 3))
    for f, b in ((0.0, B), (-F, B), (np.nan, B), (F, 0.0), (F, -B), (F, np.nan), (F, np.inf)):
        with pytest.raises(CalibrationError, match="focal_px|baseline_m"):
            detect_candidates(d, pts, f, b, 20.0, camera_height_m=1.4)
    with pytest.raises(CalibrationError, match="cy"):
        detect_candidates(d, pts, F, B, np.nan, camera_height_m=1.4)
    for h in (np.nan, -1.4, 0.0, np.inf):
        with pytest.raises(GeometryError, match="camera_height_m"):
            detect_candidates(d, pts, F, B, 20.0, camera_height_m=h)
        with pytest.raises(GeometryError, match="camera_height_m"):
            FloorPlane.level(h)
        with pytest.raises(GeometryError, match="prior_height_m"):
            estimate_floor(np.full((40, 40, 3), np.nan), prior_height_m=h)
    P = u_disparity(d)
    with pytest.raises(CalibrationError, match="baseline_m"):
        scale_adaptive_filter(P, F, 0.0)
    with pytest.raises(CalibrationError, match="focal_px"):
        find_peaks(P, np.nan, B)


def test_hog_refuses_bad_strides_scales_and_images():
    """win_stride=-8 SEGFAULTED and a 10x10 image corrupted the heap (OpenCV); 2-/4-channel
    images raised cv2.error."""
    img = np.zeros((160, 120), np.uint8)
    for stride in (-8, 0, 8.0, True):
        with pytest.raises(ConfigError, match="win_stride"):
            detect_people_hog(img, win_stride=stride)
    for scale in (1.0, 0.9, np.nan):
        with pytest.raises(ConfigError, match="scale"):
            detect_people_hog(img, scale=scale)
    # (small images: tests/vision/test_hog_small_images.py)
    with pytest.raises(ImageInputError, match="empty"):
        detect_people_hog(np.zeros((0, 0), np.uint8))
    with pytest.raises(ImageInputError, match="BGRA"):
        detect_people_hog(np.zeros((160, 120, 2), np.uint8))
    # BGRA (alpha dropped) and (H, W, 1) images are accepted
    assert detect_people_hog(np.zeros((160, 120, 4), np.uint8)) == []
    assert detect_people_hog(np.zeros((160, 120, 1), np.uint8), win_stride=np.int64(16)) == []


@pytest.mark.parametrize("kw, name", [({"tm": np.nan}, "tm"), ({"tm": 1.5}, "tm"),
                                      ({"tau_m": 0.0}, "tau_m"), ({"max_range_m": 0.0},
                                                                  "max_range_m"),
                                      ({"min_range_m": 0.0}, "min_range_m"),
                                      ({"min_range_m": 10.0}, "min_range_m"),
                                      ({"depth_band_m": -1.0}, "depth_band_m"),
                                      ({"peak_threshold": np.nan}, "peak_threshold"),
                                      ({"person_width_m": np.nan}, "person_width_m"),
                                      ({"max_candidates": 0}, "max_candidates")])
def test_detector_parameters_are_checked_when_made(kw, name):
    """Before 2026-11-26 none was: a NaN tm accepted every candidate that passed the extent
    test, a zero range or tau_m divided by zero, a negative depth band emptied every
    segmentation, a NaN peak threshold found nobody."""
    with pytest.raises(ConfigError, match=name):
        HumanDetectorParams(**kw)
    assert HumanDetectorParams(tm=1.0).tm == 1.0  # the documented range's ends stay allowed


def test_head_shoulder_score_refuses_a_depth_focal_or_tau_that_is_not_positive():
    """A zero depth or tau_m raised a bare ZeroDivisionError, a NaN depth a numpy ValueError,
    and a negative depth or a NaN tau_m returned a score (0.65 for this box, or NaN) as if
    the silhouette had been measured."""
    box = _silhouette(False)
    assert head_shoulder_score(box, 3.0, F)[0] < 0.5
    for depth in (0.0, -3.0, np.nan, np.inf):
        with pytest.raises(GeometryError, match="depth_m"):
            head_shoulder_score(box, depth, F)
    for f in (0.0, -F, np.nan):
        with pytest.raises(CalibrationError, match="focal_px"):
            head_shoulder_score(box, 3.0, f)
    for tau in (0.0, -0.08, np.nan):
        with pytest.raises(ConfigError, match="tau_m"):
            head_shoulder_score(box, 3.0, F, tau_m=tau)
    with pytest.raises(ImageInputError, match="mask"):
        head_shoulder_score(box[0], 3.0, F)


def _two_peaks() -> np.ndarray:
    psi = np.zeros((12, 60))
    psi[8, 40] = 0.8  # strong peak: column 40, disparity 8
    psi[3, 10] = 0.5  # weaker peak: column 10, disparity 3
    return psi


def test_find_peaks_refuses_a_negative_or_nan_min_disparity():
    """A negative min_disparity sliced rows from the END of Psi-hat (ps[:-2] = -inf): both
    peaks below were silently lost; a NaN one raised a bare ValueError."""
    want = [(40, 8, 0.8), (10, 3, 0.5)]
    assert find_peaks(_two_peaks(), F, B, min_disparity=0.0) == want
    for md in (-2.0, np.nan, np.inf):
        with pytest.raises(ConfigError, match="min_disparity"):
            find_peaks(_two_peaks(), F, B, min_disparity=md)


def test_find_peaks_suppresses_a_peak_at_disparity_zero():
    """At d = 0 the depth is infinite and |Z - Z[0]| is NaN, so the peak's own row was never
    suppressed: with min_disparity = 0 the same peak came back max_peaks times."""
    psi = _two_peaks()
    psi[0, 25] = 0.9
    got = find_peaks(psi, F, B, min_disparity=0.0, max_peaks=6)
    assert got == [(25, 0, 0.9), (40, 8, 0.8), (10, 3, 0.5)]


def test_scale_adaptive_filter_refuses_mismatched_maps_and_bad_settings():
    """An ``above`` map of another shape raised a bare IndexError, ``expected_rows`` of
    another length or a 1-D P a bare ValueError; a NaN above_weight or kernel width gave an
    all-zero (or garbage) Psi-hat: nobody found, no error."""
    d = 20
    P = _blob_P(int(0.4 * d / B), d, 100, W=260)
    rows = np.full(40, 50.0)
    ok = scale_adaptive_filter(P, F, B, expected_rows=rows, above=np.zeros_like(P))
    assert ok.max() > 0.8
    with pytest.raises(ImageInputError, match="above"):
        scale_adaptive_filter(P, F, B, above=P[:-1])
    with pytest.raises(ImageInputError, match="expected_rows"):
        scale_adaptive_filter(P, F, B, expected_rows=rows[:-5])
    with pytest.raises(ImageInputError, match="P"):
        scale_adaptive_filter(P[0], F, B)
    for kw in ({"above_weight": np.nan}, {"above_weight": -1.0}, {"person_width_m": np.nan},
               {"surround_m": 0.0}, {"depth_band_m": np.inf}):
        with pytest.raises(ConfigError, match=next(iter(kw))):
            scale_adaptive_filter(P, F, B, expected_rows=rows, above=np.zeros_like(P), **kw)


def test_maps_with_nan_or_inf_are_refused_not_emptied():
    """One NaN (or inf) in P(y,d) made the whole Psi-hat 0 (every person silently lost), one
    in Psi-hat hid every peak from find_peaks, one in a silhouette's heights gave a NaN top:
    each is an ImageInputError now; the clean maps still give the person and both peaks."""
    d = 20
    P = _blob_P(int(0.4 * d / B), d, 100, W=260)
    assert scale_adaptive_filter(P, F, B).max() > 0.8
    assert find_peaks(_two_peaks(), F, B, min_disparity=0.0) == [(40, 8, 0.8), (10, 3, 0.5)]
    assert robust_top_m([1.0, 1.5, 1.7]) == pytest.approx(np.percentile([1.0, 1.5, 1.7],
                                                                         TOP_PERCENTILE))
    for bad in (np.nan, np.inf):
        Pb = P.copy()
        Pb[3, 0] = bad
        with pytest.raises(ImageInputError, match="P must hold finite"):
            scale_adaptive_filter(Pb, F, B)
        with pytest.raises(ImageInputError, match="above must hold finite"):
            scale_adaptive_filter(P, F, B, above=Pb)
        rows = np.full(P.shape[0], 50.0)
        rows[2] = bad
        with pytest.raises(ImageInputError, match="expected_rows must hold finite"):
            scale_adaptive_filter(P, F, B, expected_rows=rows)
        psi = _two_peaks()
        psi[3, 0] = bad
        with pytest.raises(ImageInputError, match="psi must hold finite"):
            find_peaks(psi, F, B)
        with pytest.raises(ImageInputError, match="heights must hold finite"):
            robust_top_m([1.0, bad, 1.7])


def test_floor_plane_refuses_a_normal_that_is_not_a_unit_up_vector():
    """A FloorPlane passed to detect_candidates with a non-unit normal scaled every height
    (|n| = 2: a 0.9 m box measured 1.8 m tall), a downward one turned heights upside down, a
    NaN one made every height NaN -- all silently."""
    pts = np.array([[0.0, 1.2 - 0.9, 3.0]])  # the top of a 0.9 m box, camera 1.2 m high
    assert FloorPlane(np.array([0.0, -1.0, 0.0]), 1.2).height(pts)[0] == pytest.approx(0.9)
    for normal, offset in (([0.0, -2.0, 0.0], 1.2), ([0.0, 1.0, 0.0], 1.2),
                           ([np.nan, -1.0, 0.0], 1.2), ([0.0, -1.0], 1.2),
                           ([0.0, -1.0, 0.0], np.nan)):
        with pytest.raises(GeometryError, match="FloorPlane"):
            FloorPlane(np.asarray(normal), offset)


def _cardboard_person(shape, f, b, cx, cy, *, z_m, x_m=0.0, camera_height_m=1.4, top_m=1.75):
    """Disparity (px) and points (m, left optical frame) of a flat person-shaped cut-out
    ``z_m`` metres ahead of a level rig (NaN elsewhere): a head (ellipse, 0.18 x 0.22 m), a neck,
    a torso 0.44 m wide from the shoulders (0.25 m below the top) to the hips (0.85 m above the
    floor) and two legs."""
    H, W = shape
    v, u = np.mgrid[0:H, 0:W].astype(float)
    X = (u - cx) * z_m / f - x_m
    h = camera_height_m - (v - cy) * z_m / f  # height above the floor
    head = (X / 0.09) ** 2 + ((h - (top_m - 0.11)) / 0.11) ** 2 <= 1.0
    neck = (np.abs(X) <= 0.05) & (h <= top_m - 0.2) & (h > top_m - 0.26)
    torso = (np.abs(X) <= 0.22) & (h <= top_m - 0.25) & (h > 0.85)
    legs = (np.abs(X) >= 0.03) & (np.abs(X) <= 0.17) & (h <= 0.85) & (h >= 0.0)
    body = head | neck | torso | legs
    d = np.where(body, f * b / z_m, np.nan).astype(np.float32)
    Z = np.where(body, z_m, np.nan)
    pts = np.dstack([(u - cx) * Z / f, (v - cy) * Z / f, Z]).astype(np.float32)
    return d, pts, body


def test_segmentation_rows_follow_the_principal_row():
    """A rig whose principal row cy = 60 px is far above the image centre (239.5): the row
    window of segment_body was centred on the image centre, and for a person 6 m away it
    started at row 74, cutting off the head and shoulders (box top 74 instead of 31, height
    1.23 m instead of 1.75 m, candidate rejected). Counted from cy the whole person is
    segmented and accepted."""
    H, W, f, b, cx, cy = 480, 640, 500.0, 0.12, 319.5, 60.0
    d, pts, body = _cardboard_person((H, W), f, b, cx, cy, z_m=6.0)
    floor = FloorPlane.level(1.4)
    heights = floor.height(pts)
    # rows of the body above the floor band that the detector ignores (min_height_m)
    rows = np.nonzero((body & (heights >= HumanDetectorParams().min_height_m)).any(axis=1))[0]
    assert rows[0] == 31  # the test's ground truth: the head top is well inside the image
    det = detect_candidates(d, pts, f, b, cy, floor=floor)
    acc = [c for c in det.candidates if c.accepted]
    assert len(acc) == 1, [c.reason for c in det.candidates]
    c = acc[0]
    x, y, w, h = c.box
    assert y == rows[0] and y + h - 1 == rows[-1]
    assert c.segment.top_m == pytest.approx(1.75, abs=0.03)
    # segment_body itself takes the principal row from its caller, checked like the caller's
    seg = segment_body(c.column, float(c.disparity), d, pts, heights, floor, f, b, cy)
    assert seg is not None and seg.box == c.box
    with pytest.raises(CalibrationError, match="principal row"):
        segment_body(c.column, float(c.disparity), d, pts, heights, floor, f, b, np.nan)


@pytest.mark.parametrize("z_m", [7.0, 8.0])
def test_segmentation_ignores_zero_disparities_of_far_people(z_m):
    """Zero marks an invalid disparity as NaN does (u_disparity, detect_candidates). A far
    person on a short rig (f B = 9.6 px m: 1.37 px at 7 m, 1.2 px at 8 m) has a disparity
    within the peak's disparity band of 0, so the starting strip took the background's zeros
    into its median depth (fb / 0: inf) and the person was not segmented at all."""
    H, W, f, b, cx, cy = 240, 320, 160.0, 0.06, 159.5, 119.5
    d, pts, _ = _cardboard_person((H, W), f, b, cx, cy, z_m=z_m)
    floor = FloorPlane.level(1.4)
    heights = floor.height(pts)
    zeros = np.where(np.isnan(d), 0.0, d).astype(np.float32)
    segs = [segment_body(int(cx), f * b / z_m, dd, pts, heights, floor, f, b, cy)
            for dd in (d, zeros)]
    assert segs[0] is not None and segs[1] is not None
    assert segs[1].box == segs[0].box and segs[1].top_m == segs[0].top_m


def test_segmentation_band_grows_with_the_stereo_depth_noise():
    """segment_band_m: the fixed 0.35 m near, 3 sigma_Z (sigma_Z = Z^2 sigma_d / (f B)) far;
    disparity_band_px: the disparity band Psi-hat sums at d (whole pixels, at least 1)."""
    p = HumanDetectorParams()
    f, b = 500.0, 0.12
    assert segment_band_m(3.0, f, b, p) == pytest.approx(0.35)
    assert segment_band_m(7.4, f, b, p) == pytest.approx(3 * 7.4**2 * 0.21 / (f * b))  # 0.575 m
    assert segment_band_m(7.4, f, b, HumanDetectorParams(disparity_sigma_px=0.0)) == \
        pytest.approx(0.35)
    assert disparity_band_px(np.array([8.0, 20.0, 40.0]), 0.2, f, b).tolist() == [1, 1, 5]
    with pytest.raises(ImageInputError, match="not a disparity"):  # (the int cast wrapped)
        disparity_band_px(1e200, 0.2, f, b)
    for kw in ({"disparity_sigma_px": -0.1}, {"band_sigmas": np.nan}):
        with pytest.raises(ConfigError, match=next(iter(kw))):
            HumanDetectorParams(**kw)


@pytest.mark.parametrize("entities, room", [
    # three people 7-8.2 m away, facing the camera, sideways and away
    ([Entity("person", -1.8, 6.8, 10.0, 1.8), Entity("person", 0.0, 7.5, 90.0, 1.75),
      Entity("person", 1.8, 8.0, 180.0, 1.7)], {"depth_m": 9.5, "seed": 12}),
    # one person 7.5 m away, turned sideways, near the left wall
    ([Entity("person", -2.28, 7.12, 77.0, 1.79)],
     {"width_left_m": 3.15, "width_right_m": 4.39, "depth_m": 9.34, "ceiling_m": 2.74,
      "seed": 2109}),
])
def test_far_people_are_segmented_whole(entities, room):
    """People 7-8.2 m away (SGBM disparity, 640x480, f B = 60 px m): each is detected once,
    with its whole silhouette (IoU >= 0.6 with the renderer's box, height within 0.12 m), and
    nothing else is. With the fixed 0.35 m band (and the strip searched only within it of the
    peak, which is often one disparity too far) the segmentation kept a head or a head and
    torso: a 20x35 px head box 7.8 m away (IoU 0.23) in the second scene, a 37x33 px box
    (IoU 0.29, height 1.42 m for 1.70 m) in the first."""
    rig = default_rig()
    sc = render_scene(SceneSpec(entities=entities, **room), rig)
    res = detect_humans(sc.left, sc.right, rig, sc.thermal_c)
    assert len(res.humans) == len(sc.people)
    for person in sc.people:
        best = max(res.humans, key=lambda h: _iou(h.box, person.box))
        assert _iou(best.box, person.box) >= 0.6, (best.box, person.box)
        assert best.height_m == pytest.approx(person.height_m, abs=0.12)


def _fragment(seg, keep_m: float, focal_px: float):
    """The top ``keep_m`` metres of a silhouette: what segmentation returns when it keeps only
    the head and shoulders of a person (rows and points above top - keep_m)."""
    import dataclasses

    rows = max(3, int(round(keep_m * focal_px / seg.depth_m)))
    sel = seg.heights >= seg.top_m - keep_m
    box = [seg.box[0], seg.box[1], seg.box[2], rows]
    return dataclasses.replace(seg, box=box, mask=seg.mask[:rows], points=seg.points[sel],
                               heights=seg.heights[sel])


def test_head_sized_fragments_fail_the_extent_test(small_scene, monkeypatch):
    """A silhouette must span min_extent_m of height itself, not only reach a person's height
    with its top: the head-and-shoulders fragment (0.3 m) of the scene's person, at the
    person's top (1.8 m) with a head-shoulder score above Tm, used to be accepted."""
    import hearsee.vision.humans as hm

    sc = small_scene
    rect = sc.rig.rectification
    pts = points_from_disparity(sc.disparity, rect.Q)
    real = hm.segment_body

    def run(keep_m):
        def seg(*a, **k):
            s = real(*a, **k)
            return s if s is None or keep_m is None else _fragment(s, keep_m, rect.focal_px)
        monkeypatch.setattr(hm, "segment_body", seg)
        return detect_candidates(sc.disparity, pts, rect.focal_px, rect.baseline_m, rect.cy,
                                 camera_height_m=1.4)

    whole = [c for c in run(None).candidates if c.accepted]
    # (from min_height_m = 0.12 m above the floor to the top at 1.8 m)
    assert len(whole) == 1 and whole[0].segment.extent_m == pytest.approx(1.68, abs=0.1)
    frag = [c for c in run(0.3).candidates
            if c.segment is not None and abs(c.column - whole[0].column) <= 2]
    assert frag and frag[0].segment.top_m == pytest.approx(1.8, abs=0.06)
    assert frag[0].segment.extent_m == pytest.approx(0.3, abs=0.05)
    assert not any(c.accepted for c in frag)
    assert "tall < min_extent_m" in frag[0].reason
    # a person visible from 0.7 m below the top (legs cut off) still passes
    part = [c for c in run(0.7).candidates if c.accepted]
    assert len(part) == 1 and part[0].segment.extent_m == pytest.approx(0.7, abs=0.05)


def _candidate(box, extent_m, score, accepted=True, reason="", depth_m=4.0):
    """A HumanCandidate whose silhouette (box [x, y, w, h] px) spans ``extent_m`` metres
    below a top of 1.75 m."""
    from hearsee.vision.humans import BodySegment, HumanCandidate

    h = np.linspace(1.75 - extent_m, 1.75, 200)
    seg = BodySegment(list(box), np.ones(box[2:][::-1], bool), np.zeros((200, 3)), h, depth_m,
                      1.75, 0.4, np.zeros(3))
    return HumanCandidate(box[0], 15, 0.5, seg, score=score, accepted=accepted, reason=reason)


def test_dedupe_keeps_the_more_complete_silhouette():
    """Two accepted peaks on one person: the higher head-shoulder score used to win even when
    its silhouette was the torso without the head; a silhouette taller by more than
    MORE_COMPLETE_M wins now, within that margin the score still decides, and a rejected
    duplicate keeps why it was rejected."""
    from hearsee.vision.humans import MORE_COMPLETE_M, _dedupe

    headless = _candidate([100, 130, 40, 90], 1.2, 0.9)
    whole = _candidate([100, 100, 40, 120], 1.6, 0.7)
    other = _candidate([300, 100, 40, 120], 1.6, 0.95)  # another person, kept first
    _dedupe([headless, whole, other])
    assert whole.accepted and not headless.accepted and other.accepted
    assert headless.reason == "duplicate of a stronger candidate"
    assert whole.segment.extent_m - headless.segment.extent_m > MORE_COMPLETE_M
    a = _candidate([100, 100, 40, 118], 1.55, 0.9)
    b = _candidate([100, 100, 40, 120], 1.6, 0.7)  # only 5 cm taller: the score decides
    _dedupe([b, a])
    assert a.accepted and not b.accepted
    tall = _candidate([95, 60, 50, 160], 2.3, 0.0, accepted=False,
                      reason="height 2.30 m outside [1.2, 2.2]")
    keep = _candidate([100, 100, 40, 120], 1.6, 0.8)
    _dedupe([tall, keep])
    assert keep.accepted
    assert tall.reason == ("duplicate of a stronger candidate (height 2.30 m outside "
                           "[1.2, 2.2])")
    # a rejected taller silhouette never replaces an accepted one
    assert not tall.accepted


def test_detector_maps_and_peak_settings_must_be_numbers():
    """numpy read a disparity, a count map or Psi-hat of text as numbers (u_disparity,
    scale_adaptive_filter, find_peaks, detect_candidates; a text mask as all True) and a floor
    normal of text was kept as given (every height then a builtin error); find_peaks found no
    peak for a NaN threshold without a word, and a NaN width or a count of 2.5 raised builtin
    errors. Now ImageInputError for the maps, GeometryError for the normal, ConfigError for the
    settings; numbers give the same answers."""
    d = np.full((4, 3), np.nan)
    d[:, 1] = 2.0
    with pytest.raises(ImageInputError, match="^disparity must hold numbers"):
        u_disparity(d.astype(str))
    with pytest.raises(ImageInputError, match="^mask must be a bool silhouette, got <U1"):
        u_disparity(d, mask=np.full(d.shape, "0"))
    np.testing.assert_array_equal(u_disparity(d.tolist()), u_disparity(d))
    P = np.zeros((10, 50))
    P[5, 18:23] = 40.0
    for kw in ({"P": P.astype(str)}, {"above": P.astype(str)},
               {"expected_rows": np.full(10, "5")}, {"P": [[1.0, 2.0], [3.0]]}):
        args = {"P": P, **kw}
        with pytest.raises(ImageInputError, match=f"^{next(iter(kw))} must hold numbers"):
            scale_adaptive_filter(args.pop("P"), 500.0, 0.1, **args)
    psi = np.zeros((10, 50))
    psi[5, 20] = 0.8
    with pytest.raises(ImageInputError, match="^psi must hold numbers"):
        find_peaks(psi.astype(str), 500.0, 0.1)
    with pytest.raises(ImageInputError, match="^psi must be a"):
        find_peaks(psi[0], 500.0, 0.1)
    for kw in ({"threshold": np.nan}, {"threshold": "0.3"}, {"person_width_m": np.nan},
               {"person_width_m": 0.0}, {"depth_sep_m": -1.0}, {"max_peaks": 2.5},
               {"max_peaks": -1}, {"max_peaks": "3"}):
        with pytest.raises(ConfigError, match=f"^{next(iter(kw))} must be"):
            find_peaks(psi, 500.0, 0.1, **kw)
    assert find_peaks(psi.tolist(), 500.0, 0.1) == find_peaks(psi, 500.0, 0.1) == [(20, 5, 0.8)]
    assert find_peaks(psi, 500.0, 0.1, max_peaks=0) == []
    with pytest.raises(GeometryError, match="FloorPlane: normal"):
        FloorPlane(["0", "-1", "0"], 1.2)
    np.testing.assert_array_equal(FloorPlane([0, -1, 0], 1.2).height(np.zeros((1, 3))), [1.2])
    disp = np.full((40, 60), 5.0, np.float32)
    pts = np.zeros((40, 60, 3))
    floor = FloorPlane.level(1.2)
    with pytest.raises(ImageInputError, match="^disparity must hold numbers"):
        detect_candidates(disp.astype(str), pts, 500.0, 0.1, 20.0, floor=floor)
    with pytest.raises(ImageInputError, match="^points must be"):
        detect_candidates(disp, pts.astype(str), 500.0, 0.1, 20.0, floor=floor)


def test_silhouette_helpers_refuse_text_and_builtin_errors():
    """The public per-candidate helpers read text: upper_contour / head_shoulder_score took a
    mask of text as all True, cut_by_border int()ed "3" (and 2.7 to 2), disparity_band_px
    read "20" as 20 px and NaN as the most negative int, robust_top_m and FloorPlane.height
    raised numpy's builtin errors (text, an empty set, points not (..., 3)). Now typed errors;
    numbers give the same answers."""
    mask = np.zeros((30, 20), bool)
    mask[5:, 6:14] = True
    want = np.where(mask.any(axis=0), 5.0, np.nan)
    np.testing.assert_array_equal(upper_contour(mask), want)
    np.testing.assert_array_equal(upper_contour(mask.astype(np.uint8)), want)
    for bad in (np.where(mask, "1", "0"), mask.astype(complex)):
        with pytest.raises(ImageInputError, match="^mask must be a bool silhouette, got "):
            upper_contour(bad)
        with pytest.raises(ImageInputError, match="^mask must be a bool silhouette, got "):
            head_shoulder_score(bad, 2.0, 500.0)
    # a ragged list was numpy's ValueError; a 1-D mask a builtin TypeError (or, empty,
    # "attempt to get argmax of an empty sequence")
    for bad in ([[True, False], [True]], mask[0], np.zeros(0, bool), mask[None]):
        with pytest.raises(ImageInputError, match=r"^mask must be a bool silhouette \(H, W\)"):
            upper_contour(bad)
        with pytest.raises(ImageInputError, match=r"^mask must be a bool silhouette \(H, W\)"):
            u_disparity(np.full((30, 20), 2.0), mask=bad)
    assert np.isnan(upper_contour(np.zeros((0, 4), bool))).all()  # (was a builtin ValueError)
    assert upper_contour(np.zeros((0, 4), bool)).shape == (4,)
    assert cut_by_border([0, 4, 5, 6], 320) and cut_by_border((3, 4, 317, 6), 320)
    assert not cut_by_border(np.array([3, 4, 5, 6]), np.int64(320))
    for box, width, name in (([3, "4", 5, 6], 320, "box y"), ([3, 4, 2.7, 6], 320, "box w"),
                             ([-1, 4, 5, 6], 320, "box x"), ([3, 4, 5, 6], "320", "width"),
                             ([3, 4, 5, 6], 0, "width")):
        with pytest.raises(ImageInputError, match=f"^{name} must be an integer"):
            cut_by_border(box, width)
    for box in ([3, 4, 5], 7, "3456"):
        with pytest.raises(ImageInputError, match="box"):
            cut_by_border(box, 320)
    np.testing.assert_array_equal(disparity_band_px([12.0, 40.0], 0.25, 100.0, 0.1), [4, 40])
    assert disparity_band_px(2.0, 0.25, 100.0, 0.1) == 1
    for d in ("20", [20.0, np.nan], True):
        with pytest.raises(ImageInputError, match="^disparity must"):
            disparity_band_px(d, 0.25, 100.0, 0.1)
    with pytest.raises(ConfigError, match="^depth_band_m must be a finite number"):
        disparity_band_px(20.0, "0.25", 100.0, 0.1)
    with pytest.raises(CalibrationError, match="^focal_px must be"):
        disparity_band_px(20.0, 0.25, np.nan, 0.1)
    h = np.linspace(0.0, 1.8, 200)
    assert robust_top_m(h) == robust_top_m(h.tolist()) == float(np.percentile(h, 99.5))
    for bad, msg in ((h.astype(str), "^heights must hold numbers"),
                     (np.zeros(0), "^heights must hold at least one")):
        with pytest.raises(ImageInputError, match=msg):
            robust_top_m(bad)
    floor = FloorPlane.level(1.2)
    pts = np.array([[0.0, 0.2, 2.0], [0.1, -0.5, 3.0]])
    np.testing.assert_array_equal(floor.height(pts.tolist()), [1.0, 1.7])
    for bad, msg in ((pts.astype(str), "^points must hold numbers"),
                     (pts[:, :2], r"^points must be \(\.\.\., 3\)"), (1.0, "^points must be")):
        with pytest.raises(ImageInputError, match=msg):
            floor.height(bad)


def test_point_images_of_ragged_rows_are_refused():
    """estimate_floor and detect_candidates raised numpy's builtin ValueError on a ragged list
    of points; now the same ImageInputError as for points of the wrong shape."""
    ragged = [[[0.0, 1.0, 2.0], [0.0, 1.0, 2.0]], [[0.0, 1.0, 2.0]]]
    with pytest.raises(ImageInputError, match=r"^points must be \(H, W, 3\) metres"):
        estimate_floor(ragged)
    with pytest.raises(ImageInputError, match=r"^points must be \(H, W, 3\) metres"):
        detect_candidates(np.full((2, 2), 5.0, np.float32), ragged, 500.0, 0.1, 1.0,
                          floor=FloorPlane.level(1.2))


def test_edited_params_are_checked_again():
    """HumanDetectorParams checks its fields when made, but they can be edited afterwards: an
    edited ``tm = nan`` accepted every candidate (a furniture box 3 m away came out as a
    person), a dict was a builtin AttributeError. detect_candidates, segment_body,
    segment_band_m and detect_humans check them again (a ConfigError naming the field)."""
    H, W = 60, 80
    d = np.full((H, W), np.nan, np.float32)
    pts = np.full((H, W, 3), np.nan)
    floor = FloorPlane.level(1.4)
    for field, value in (("tm", np.nan), ("max_top_m", np.nan), ("peak_threshold", 2.0),
                         ("max_candidates", 2.5), ("min_range_m", 20.0)):
        p = HumanDetectorParams()
        setattr(p, field, value)
        with pytest.raises(ConfigError, match=field):
            detect_candidates(d, pts, F, B, H / 2, camera_height_m=1.4, params=p)
        with pytest.raises(ConfigError, match=field):
            segment_body(40, 10.0, d, pts, np.zeros((H, W)), floor, F, B, H / 2, params=p)
        with pytest.raises(ConfigError, match=field):
            segment_band_m(3.0, F, B, p)
    for bad in ({"tm": 0.5}, "default"):
        with pytest.raises(ConfigError, match="HumanDetectorParams"):
            detect_candidates(d, pts, F, B, H / 2, camera_height_m=1.4, params=bad)
        with pytest.raises(ConfigError, match="HumanDetectorParams"):
            segment_band_m(3.0, F, B, bad)
    p = HumanDetectorParams()
    p.tm = np.nan
    rng = np.random.default_rng(0)
    img = rng.integers(0, 255, (H, W), dtype=np.uint8)
    with pytest.raises(ConfigError, match="tm"):
        detect_humans(img, np.roll(img, 4, axis=1), default_rig(W, H), params=p)
    # unedited (or None) parameters work as before
    assert segment_band_m(3.0, F, B, None) == pytest.approx(0.35)
    assert detect_candidates(d, pts, F, B, H / 2, camera_height_m=1.4,
                             params=HumanDetectorParams()).candidates == []


def test_segment_band_m_refuses_bad_depths_and_calibration():
    """A zero focal length or baseline was a builtin ZeroDivisionError; a NaN, negative or
    zero depth gave the near band (0.35 m) without a word."""
    p = HumanDetectorParams()
    for f, b in ((0.0, B), (F, 0.0), (np.nan, B), (F, -B)):
        with pytest.raises(CalibrationError, match="focal_px|baseline_m"):
            segment_band_m(3.0, f, b, p)
    for z in (np.nan, -3.0, 0.0, np.inf, "3"):
        with pytest.raises(GeometryError, match="depth_m"):
            segment_band_m(z, F, B, p)
    # a valid depth: the band as before (3 sigma_Z = 3 * 8^2 * 0.21 / (F B) = 1.344 m at 8 m)
    assert segment_band_m(8.0, F, B, p) == pytest.approx(3 * 64 * 0.21 / (F * B))


def test_segment_body_refuses_bad_candidates_and_maps():
    """A NaN or infinite candidate disparity, a fractional column, a 1-D disparity, a
    disparity of text and a floor that is no FloorPlane were builtin errors (ValueError,
    OverflowError, TypeError, AttributeError); points or heights of another size than the
    disparity gave None, "no silhouette", without a word. The same call with good inputs
    finds the body."""
    H, W, cy = 90, 120, 44.5
    Z, f, b = 3.0, F, B
    d = np.full((H, W), np.nan, np.float32)
    floor = FloorPlane.level(1.4)
    # a 0.4 m wide, 1.7 m tall upright slab at 3 m (rows of heights 0.1-1.7 m)
    v = np.arange(H)[:, None]
    h_row = 1.4 - (v - cy) * Z / f
    body = (h_row >= 0.1) & (h_row <= 1.7) & (np.abs(np.arange(W)[None, :] - 60) <= 17)
    d[body] = f * b / Z
    pts = points_from_disparity(d, np.array([[1, 0, 0, -59.5], [0, 1, 0, -cy], [0, 0, 0, f],
                                             [0, 0, 1 / b, 0]]))
    heights = floor.height(pts)
    good = segment_body(60, f * b / Z, d, pts, heights, floor, f, b, cy)
    assert good is not None and good.depth_m == pytest.approx(Z)
    assert good.box[0] == 60 - 17 and good.box[2] == 35
    args = [60, f * b / Z, d, pts, heights, floor]
    for k, bad, err in ((0, 60.5, ImageInputError), (0, True, ImageInputError),
                        (1, np.nan, ImageInputError), (1, np.inf, ImageInputError),
                        (2, d[0], ImageInputError), (2, d.astype(str), ImageInputError),
                        (3, pts[:10], ImageInputError), (4, heights[:, :50], ImageInputError),
                        (5, None, GeometryError), (5, 1.4, GeometryError)):
        a = list(args)
        a[k] = bad
        with pytest.raises(err):
            segment_body(*a, f, b, cy)
    # a list is read as the numbers it holds; a column outside the image has no silhouette
    assert segment_body(60, f * b / Z, d.tolist(), pts, heights, floor, f, b, cy).box == good.box
    assert segment_body(-50, f * b / Z, d, pts, heights, floor, f, b, cy) is None


def test_empty_maps_give_empty_filters_and_no_peaks():
    """P(y,d) of no disparities (0 rows) was an IndexError in scale_adaptive_filter, and an
    empty Psi-hat (no rows or no columns) numpy's "argmax of an empty sequence" in find_peaks:
    an empty map has an empty response and no peaks."""
    for shape in ((0, 7), (5, 0), (0, 0)):
        psi = scale_adaptive_filter(np.zeros(shape), F, B)
        assert psi.shape == shape
        assert find_peaks(np.zeros(shape), F, B) == []
    # a block of counts one person wide (0.4 m = 33 columns at d = 10) still peaks on it
    P = np.zeros((16, 100))
    P[10, 34:67] = 40.0
    col, disp, _ = find_peaks(scale_adaptive_filter(P, F, B), F, B, threshold=1.0)[0]
    assert abs(col - 50) <= 1 and abs(disp - 10) <= 1


def test_detect_candidates_refuses_a_floor_that_is_no_floor_plane():
    """A floor given as a number, a tuple or a dict was a builtin AttributeError
    (``floor.height``); a FloorPlane (or None) works as before."""
    H, W = 40, 60
    d = np.full((H, W), np.nan, np.float32)
    pts = np.full((H, W, 3), np.nan)
    for bad in (1.4, ((0.0, -1.0, 0.0), 1.4), {"normal": (0, -1, 0), "offset": 1.4}):
        with pytest.raises(GeometryError, match="FloorPlane"):
            detect_candidates(d, pts, F, B, H / 2, floor=bad)
    det = detect_candidates(d, pts, F, B, H / 2, floor=FloorPlane.level(1.3))
    assert det.floor.camera_height_m == 1.3 and det.candidates == []


def test_u_disparity_docstring_example_runs():
    """u_disparity's example put a disparity of 5 px in an image 3 px wide, which the function
    refuses since disparities wider than the image were refused ("exceeds the image width"):
    the documented call raised ImageInputError. The example now runs as written."""
    import doctest

    import hearsee.vision.humans as humans

    finder = doctest.DocTestFinder()
    (test,) = [t for t in finder.find(humans.u_disparity, "u_disparity",
                                      globs={"np": np, "u_disparity": humans.u_disparity})]
    result = doctest.DocTestRunner().run(test, out=lambda s: None)
    assert result.attempted == 2 and result.failed == 0


def test_body_surface_depth_follows_the_silhouette_width():
    """body_surface_depth_m: 0.07 m behind the visible surface for a silhouette as wide as a
    person facing the camera, 0.13 m for one as narrow as a person turned sideways, linear in
    between (monotone), and a typed error for a width that is not a number >= 0."""
    from hearsee.vision.humans import body_surface_depth_m

    assert body_surface_depth_m(0.60) == pytest.approx(0.07)
    assert body_surface_depth_m(0.48) == pytest.approx(0.07)
    assert body_surface_depth_m(0.25) == pytest.approx(0.13)
    assert body_surface_depth_m(0.10) == pytest.approx(0.13)
    assert body_surface_depth_m(0.365) == pytest.approx(0.10)
    w = np.linspace(0.0, 0.7, 50)
    assert np.all(np.diff([body_surface_depth_m(v) for v in w]) <= 0)
    for bad in (float("nan"), -0.1, "0.4", None):
        with pytest.raises(GeometryError, match="width_m"):
            body_surface_depth_m(bad)


@pytest.mark.parametrize("yaw_deg", [0.0, 90.0])
def test_torso_depth_of_a_person_facing_or_turned_sideways(yaw_deg):
    """A person 2 m in front of the camera, facing it or turned sideways (the simulator's
    ground truth: the body axis at z = 2 m): the torso centre's depth within 2.5 cm. With one
    surface-to-axis depth for both (0.09 m, until 2026-12-02) the sideways person came out
    4-6 cm too near (the narrow silhouette's visible surface is the near arm and shoulder,
    0.13 m in front of the axis) and the facing one 2.5 cm too far."""
    rig = default_rig()
    spec = SceneSpec(entities=[Entity("person", 0.0, 2.0, yaw_deg, 1.75)], seed=2)
    scene = render_scene(spec, rig, noise_seed=2)
    truth = next(o for o in scene.objects if o.kind == "person").position_m
    det = detect_humans(scene.left, scene.right, rig, scene.thermal_c)
    assert len(det.humans) == 1
    assert abs(det.humans[0].position_m[2] - truth[2]) < 0.025


@pytest.mark.parametrize("z_m", [3.0, 4.0, 6.0])
def test_the_body_box_reaches_the_floor_and_hidden_legs_do_not(z_m):
    """The silhouette stops at min_height_m (0.12 m) above the floor, so its box left the
    feet out (10-13 px at 2-9 m on bench/humans' scenes). body_box -- the detections' box --
    goes down to the floor under the body: the cut-out's last row. Legs hidden behind
    something (no disparity below 0.6 m) leave the floor unknown and the box the silhouette's."""
    H, W, f, b, cx, cy = 480, 640, 500.0, 0.12, 319.5, 239.5
    d, pts, body = _cardboard_person((H, W), f, b, cx, cy, z_m=z_m)
    floor = FloorPlane.level(1.4)
    heights = floor.height(pts)
    rows = np.nonzero(body.any(axis=1))[0]  # ground truth: the body's rows, feet included
    band = np.nonzero((body & (heights >= HumanDetectorParams().min_height_m)).any(axis=1))[0]
    seg = segment_body(int(cx), f * b / z_m, d, pts, heights, floor, f, b, cy)
    x, y, w, h = seg.box
    assert (y, y + h - 1) == (rows[0], band[-1]) and band[-1] < rows[-1] - 5
    bx, by, bw, bh = seg.body_box
    assert (bx, by, bw) == (x, y, w) and abs(by + bh - 1 - rows[-1]) <= 1
    assert seg.floor_row == by + bh - 1
    hidden = np.where(heights < 0.6, np.nan, d).astype(np.float32)
    seg = segment_body(int(cx), f * b / z_m, hidden, pts, heights, floor, f, b, cy)
    assert seg.floor_row is None and seg.body_box == seg.box
    assert seg.box[1] + seg.box[3] - 1 < rows[-1] - 0.5 * f / z_m  # (legs' 0.6 m left out)


def test_the_body_box_stops_at_the_image_bottom():
    """2.5 m from a rig 1.4 m high the floor under the body is below the image (row 519 of
    480): the box ends at the last row, as the silhouette does."""
    H, W, f, b, cx, cy = 480, 640, 500.0, 0.12, 319.5, 239.5
    d, pts, _ = _cardboard_person((H, W), f, b, cx, cy, z_m=2.5)
    floor = FloorPlane.level(1.4)
    seg = segment_body(int(cx), f * b / 2.5, d, pts, floor.height(pts), floor, f, b, cy)
    assert seg.floor_row == H - 1 and seg.body_box == seg.box
    assert seg.box[1] + seg.box[3] == H


def test_floor_priors_and_filter_maps_of_the_wrong_kind_are_typed_errors():
    """From an API audit: FloorPlane.level(None) and from_camera(1.0, None) raised float()'s
    TypeError (the checks let None through for "no prior"); a ragged expected_rows or above map
    of scale_adaptive_filter numpy's ValueError (its shape was read before converting it)."""
    for call in (lambda: FloorPlane.level(None), lambda: FloorPlane.from_camera(1.0, None)):
        with pytest.raises(GeometryError, match="a floor needs a camera height"):
            call()
    assert FloorPlane.from_camera(1.2, 10.0).pitch_deg == pytest.approx(10.0)
    P = np.ones((4, 6))
    for kw in ({"expected_rows": [[1], [1, 2]]}, {"above": [[1], [1, 2]]}):
        with pytest.raises(ImageInputError):
            scale_adaptive_filter(P, 100.0, 0.1, **kw)
