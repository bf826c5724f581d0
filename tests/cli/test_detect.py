"""``hearsee detect``: JSON/table output on a generated scene and clear errors for bad input."""

import json

import cv2
import numpy as np
import pytest

from hearsee.cli import main
from hearsee.sim.scenes import (
    Entity,
    SceneSpec,
    default_rig,
    pitched_view,
    render_scene,
    write_scene,
)
from hearsee.vision.camera import StereoRig, save_rig
from hearsee.vision.stereo import rectify_pair


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    rig = default_rig(320, 240, thermal_size=(80, 60))
    spec = SceneSpec(entities=[Entity("person", -0.6, 3.0, 0.0, 1.8),
                               Entity("mannequin", 0.8, 3.5, 0.0, 1.75)],
                     width_left_m=3.0, width_right_m=3.0, depth_m=7.0, seed=11)
    scene = render_scene(spec, rig)
    out = write_scene(scene, tmp_path_factory.mktemp("scene"))
    return out, scene


def _args(d, *extra, thermal="thermal_radiometric.png"):
    a = ["detect", "--left", str(d / "left.png"), "--right", str(d / "right.png"),
         "--calib", str(d / "calib.yaml")]
    if thermal:
        a += ["--thermal", str(d / thermal)]
    return a + list(extra)


def test_json_output_matches_ground_truth(folder, capsys):
    d, scene = folder
    assert main(_args(d)) == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["humans"]) == 1
    h = out["humans"][0]
    person = scene.objects[0]
    assert np.linalg.norm(np.array(h["position_m"]) - person.position_m) < 0.15
    x, y, w, hh = h["box"]
    px, py, pw, ph = person.box
    assert abs(x - px) <= 4 and abs(y - py) <= 4 and abs(w - pw) <= 8
    assert 0.5 <= h["score"] <= 1.0 and h["thermal_support"] > 0.5
    assert h["truncated"] is False  # in full view
    rej = [r for r in out["rejected"] if r["reason"].startswith("thermal")]
    assert len(rej) == 1  # the mannequin
    assert np.linalg.norm(np.array(rej[0]["position_m"]) - scene.objects[1].position_m) < 0.3


@pytest.mark.parametrize("thermal", ["thermal.png", "thermal_c.npy"])
def test_other_thermal_formats(folder, capsys, thermal):
    d, _ = folder
    assert main(_args(d, thermal=thermal)) == 0
    assert len(json.loads(capsys.readouterr().out)["humans"]) == 1


def test_an_8bit_npy_is_a_non_radiometric_frame(folder, capsys, tmp_path):
    """The scene's 8-bit AGC frame saved as .npy was read as degC: its grey levels 26-40 were
    the "human band", and the person (bright) was rejected while the mannequin (dark) was
    accepted, exit 0. Now it is read as the same frame as a PNG (and as detect_humans reads
    the array): the person accepted, the mannequin rejected."""
    d, scene = folder
    t8 = cv2.imread(str(d / "thermal.png"), cv2.IMREAD_UNCHANGED)
    assert t8.dtype == np.uint8
    np.save(tmp_path / "t8.npy", t8)
    found = []
    for path in (d / "thermal.png", tmp_path / "t8.npy"):
        assert main(_args(d, thermal=None) + ["--thermal", str(path)]) == 0
        out = json.loads(capsys.readouterr().out)
        found.append([h["position_m"] for h in out["humans"]])
    assert found[0] == found[1] and len(found[0]) == 1
    assert np.linalg.norm(np.array(found[1][0]) - scene.objects[0].position_m) < 0.15


def test_the_same_image_as_left_and_right_is_refused(folder, capsys):
    """--right naming the left image (a slip of tab completion) printed "0 human(s)" and exited
    0: the pair has zero disparity everywhere. Now one line, exit 2."""
    d, _ = folder
    args = _args(d, thermal=None)
    args[args.index("--right") + 1] = str(d / "left.png")
    assert main(args) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "are the same image" in err, err


def test_swapped_images_and_a_flat_thermal_image_are_warned_about(folder, capsys, tmp_path):
    """Left and right swapped, or a flat thermal frame (lens cap, frozen camera), printed
    "0 human(s)" without a word. Now a warning names the likely cause (the answer stays: it
    is what the input gives); the correct pair and a real thermal image warn nothing."""
    d, _ = folder
    assert main(_args(d)) == 0
    assert capsys.readouterr().err == ""
    args = _args(d, thermal=None)
    i, j = args.index("--left") + 1, args.index("--right") + 1
    args[i], args[j] = args[j], args[i]
    assert main(args) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["humans"] == []
    assert err.startswith("hearsee: warning: only ") and "swapped" in err and \
        err.count("\n") == 1, err
    flat = tmp_path / "flat.npy"
    np.save(flat, np.full((60, 80), 21.0, np.float32))
    assert main(_args(d, thermal=None) + ["--thermal", str(flat)]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["humans"] == []
    assert "thermal image is flat" in err and err.count("\n") == 1, err


@pytest.mark.parametrize("kind", ["npy", "png16"])
def test_a_thermal_image_flat_to_the_filter_is_warned_about(folder, capsys, tmp_path, kind):
    """A radiometric frame whose pixels all lie within FLAT_SPREAD_C (one pixel 0.05 degC off a
    lens cap's 21 degC) is flat to the thermal filter, which empties its warm mask: every
    person was rejected ("thermal support 0.00") and only a frame flat to the digit was
    warned about. Now both are."""
    d, _ = folder
    t = np.full((60, 80), 21.0)
    t[0, 0] = 21.05
    if kind == "npy":
        path = tmp_path / "flat.npy"
        np.save(path, t.astype(np.float32))
    else:
        path = tmp_path / "flat.png"
        cv2.imwrite(str(path), np.rint((t + 273.15) * 100).astype(np.uint16))
    assert main(_args(d, thermal=None) + ["--thermal", str(path)]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["humans"] == []
    assert "thermal image is flat" in err and err.count("\n") == 1, err


def test_stereo_only_table_and_overlay(folder, capsys, tmp_path):
    d, _ = folder
    ov = tmp_path / "ov.png"
    assert main(_args(d, "--format", "table", "--overlay", str(ov), thermal=None)) == 0
    text = capsys.readouterr().out
    assert "2 human(s)" in text  # without thermal the mannequin passes
    img = cv2.imread(str(ov))
    assert img is not None and img.shape == (240, 320, 3)


def test_an_overlay_in_jpeg_2000_is_written(folder, capsys, tmp_path):
    """--overlay out.jp2 was refused before the detection, "cannot encode the image as .jp2":
    the check encoded a 2x2 probe, which OpenCV's JPEG 2000 encoder cannot (it needs 32 px),
    though it encodes the 320x240 overlay. Written now, the size of the left image."""
    d, _ = folder
    ov = tmp_path / "ov.jp2"
    assert main(_args(d, "--overlay", str(ov), thermal=None)) == 0
    capsys.readouterr()
    img = cv2.imread(str(ov))
    assert img is not None and img.shape == (240, 320, 3)


def test_a_person_cut_by_the_image_border_is_flagged(tmp_path, capsys):
    """A person 1.3 m away at the right edge of the view (the renderer's box reaches the
    border): JSON "truncated": true, and the table says so; a person in full view is not."""
    rig = default_rig(320, 240, thermal_size=(80, 60))
    spec = SceneSpec(entities=[Entity("person", 0.0, 3.0, 0.0, 1.8),
                               Entity("person", 0.9, 1.3, 0.0, 1.8)],
                     width_left_m=3.0, width_right_m=3.0, depth_m=7.0, seed=5)
    scene = render_scene(spec, rig)
    assert sum(o.box[0] + o.box[2] >= 320 for o in scene.objects) == 1
    d = write_scene(scene, tmp_path)
    assert main(_args(d, thermal=None)) == 0
    out = json.loads(capsys.readouterr().out)
    cands = out["humans"] + out["rejected"]
    for obj in scene.objects:
        c = min(cands, key=lambda h: np.linalg.norm(np.array(h["position_m"]) - obj.position_m))
        assert c["truncated"] is bool(obj.box[0] + obj.box[2] >= 320)
    assert main(_args(d, "--format", "table", thermal=None)) == 0
    assert capsys.readouterr().out.count("(cut by the image border)") == sum(
        h["truncated"] for h in cands)


def test_overlay_is_the_rectified_left_image_the_boxes_refer_to(tmp_path, capsys):
    """A rig whose right camera is toed in by 4 deg (rendered exactly: a camera rotation is the
    homography K R K^-1), so rectification also turns the left image. The person's true box is
    known in the rectified left image; the JSON box must match it and --overlay must draw it on
    that rectified image (not on the raw left image, where the person is elsewhere)."""
    ideal = default_rig(320, 240, thermal_size=(80, 60))
    spec = SceneSpec(entities=[Entity("person", -0.9, 3.0, 0.0, 1.75)], width_left_m=3.0,
                     width_right_m=3.0, depth_m=7.0, seed=3)
    scene = render_scene(spec, ideal)
    K = ideal.left.K
    Rrot = cv2.Rodrigues(np.array([0.0, np.radians(-4.0), 0.0]))[0]
    right = cv2.warpPerspective(scene.right, K @ Rrot @ np.linalg.inv(K), (320, 240),
                                flags=cv2.INTER_LINEAR)
    rig = StereoRig(ideal.left, ideal.right, Rrot @ ideal.R, Rrot @ ideal.T,
                    info=dict(ideal.info))
    for name, img in (("left.png", scene.left), ("right.png", right)):
        cv2.imwrite(str(tmp_path / name), img)
    save_rig(rig, tmp_path / "calib.yaml")
    ov = tmp_path / "ov.png"
    assert main(_args(tmp_path, "--overlay", str(ov), thermal=None)) == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["humans"]) == 1
    # ground truth: the person's pixels, rectified like the images
    mask = (scene.labels == 0).astype(np.uint8) * 255
    mask_r, _, _ = rectify_pair(mask, mask, rig, interpolation=cv2.INTER_NEAREST)
    ys, xs = np.nonzero(mask_r)
    truth = [xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1]
    x, y, w, h = out["humans"][0]["box"]
    assert abs(x - truth[0]) <= 4 and abs(y - truth[1]) <= 4 and abs(w - truth[2]) <= 8
    ys0, xs0 = np.nonzero(scene.labels == 0)
    assert xs0.min() - x > 10  # the raw left image has the person elsewhere
    # the overlay is the rectified left image, changed only on the drawn boxes and labels
    rect_left, _, _ = rectify_pair(cv2.imread(str(tmp_path / "left.png")), right, rig)
    img = cv2.imread(str(ov))
    drawn = np.zeros(img.shape[:2], bool)
    for b in out["humans"] + out["rejected"]:
        bx, by, bw, bh = b["box"]
        drawn[max(0, by - 18): by + bh + 3, max(0, bx - 3): bx + max(bw, 200) + 3] = True
    changed = np.any(img != rect_left, axis=2)
    assert changed[drawn].any() and not changed[~drawn].any()
    np.testing.assert_array_equal(img[y + h // 2, x], [0, 200, 0])  # green left edge of the box


def _err(capsys):
    err = capsys.readouterr().err
    assert err.startswith("hearsee: error:") and "Traceback" not in err
    return err


def test_sizes_differ(folder, capsys, tmp_path):
    d, scene = folder
    small = tmp_path / "right_small.png"
    cv2.imwrite(str(small), scene.right[:200])
    args = _args(d, thermal=None)
    args[args.index("--right") + 1] = str(small)
    assert main(args) == 2
    assert "differ in size" in _err(capsys)


def test_images_do_not_match_calibration(folder, capsys, tmp_path):
    d, scene = folder
    for name in ("l.png", "r.png"):
        cv2.imwrite(str(tmp_path / name), cv2.resize(scene.left, (160, 120)))
    args = ["detect", "--left", str(tmp_path / "l.png"), "--right", str(tmp_path / "r.png"),
            "--calib", str(d / "calib.yaml")]
    assert main(args) == 2
    assert "calibration expects 320x240" in _err(capsys)


def test_help_puts_the_positions_in_the_raw_left_cameras_frame(capsys):
    """The positions are in the left camera's own optical frame (the command's help above,
    classify_candidates): --camera-pitch's help called the rectified left camera's frame "the
    frame the positions are in" (1.7 deg of turn: 8.7 cm at 3 m)."""
    main(["detect", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "the frame the positions are in;" not in text
    assert "raw left camera's, whose frame the positions are in" in text


def test_camera_pitch_option(capsys, tmp_path):
    """--camera-pitch: the camera's pitch (degrees, + = up) as the floor's prior, over the
    calibration's info.camera_pitch_deg. A camera pitched up 15 deg found nobody when taken
    as level (--camera-pitch 0); with the option, or with the pitch the written scene's
    calib.yaml now carries, the person is found where they stand. Out of [-80, 80] (NaN too):
    one line, exit 2."""
    rig = default_rig(320, 240, thermal_size=(80, 60))
    spec = SceneSpec(entities=[Entity("person", -0.6, 3.5, 0.0, 1.8)], width_left_m=3.0,
                     width_right_m=3.0, depth_m=8.0, seed=11)
    scene = render_scene(spec, rig, view=pitched_view(15.0))
    d = write_scene(scene, tmp_path / "up15")
    assert main(_args(d, "--camera-pitch", "0")) == 0
    assert json.loads(capsys.readouterr().out)["humans"] == []
    for extra in (["--camera-pitch", "15"], []):
        assert main(_args(d, *extra)) == 0
        out = json.loads(capsys.readouterr().out)
        assert len(out["humans"]) == 1
        assert out["floor"]["camera_pitch_deg"] == pytest.approx(15.0, abs=1.0)
        assert np.linalg.norm(np.array(out["humans"][0]["position_m"])
                              - scene.objects[0].position_m) < 0.15
    for bad in ("95", "-81", "nan"):
        assert main(_args(d, "--camera-pitch", bad)) == 2
        err = capsys.readouterr().err
        assert err.startswith("hearsee detect: error: ") and "Traceback" not in err
        assert "--camera-pitch must be in [-80, 80] degrees" in err and err.count("\n") == 1


def test_unreadable_and_missing_files(folder, capsys, tmp_path):
    d, _ = folder
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"\x89PNG garbage")
    args = _args(d, thermal=None)
    args[args.index("--left") + 1] = str(bad)
    assert main(args) == 2
    assert "not a readable image" in _err(capsys)
    args[args.index("--left") + 1] = str(tmp_path / "nope.png")
    assert main(args) == 2
    assert "not found" in _err(capsys)


def test_missing_and_broken_calibration(folder, capsys, tmp_path):
    d, _ = folder
    args = _args(d, thermal=None)
    args[args.index("--calib") + 1] = str(tmp_path / "none.yaml")
    assert main(args) == 2
    assert "calibration file not found" in _err(capsys)
    broken = tmp_path / "broken.yaml"
    broken.write_text("left: {width: 320, height: 240, K: [[1, 2]]}\n")
    args[args.index("--calib") + 1] = str(broken)
    assert main(args) == 2
    assert "K" in _err(capsys)


def test_min_support_needs_a_thermal_image(folder, capsys):
    """--min-support without --thermal was ignored: exit 0 and the mannequin accepted as a
    person by stereo alone, whatever support was asked for; now one error line. With
    --thermal it still decides: support 1.0 is more than anyone's, so nobody is accepted."""
    d, _ = folder
    assert main(_args(d, "--min-support", "0.9", thermal=None)) == 2
    assert _err(capsys) == ("hearsee: error: --min-support is the thermal support a candidate "
                            "needs: give --thermal with it (without a thermal image the "
                            "stereo detector alone decides)\n")
    assert main(_args(d)) == 0
    assert len(json.loads(capsys.readouterr().out)["humans"]) == 1  # the person, not the dummy
    assert main(_args(d, "--min-support", "1")) == 0
    assert json.loads(capsys.readouterr().out)["humans"] == []


def test_thermal_without_thermal_camera(folder, capsys, tmp_path):
    d, scene = folder
    rig = scene.rig
    plain = tmp_path / "plain.yaml"
    save_rig(StereoRig(rig.left, rig.right, rig.R, rig.T), plain)
    args = _args(d)
    args[args.index("--calib") + 1] = str(plain)
    assert main(args) == 2
    assert "no thermal camera" in _err(capsys)


def test_thermal_wrong_size_and_overlay_over_input(folder, capsys, tmp_path):
    d, scene = folder
    th = tmp_path / "th.png"
    cv2.imwrite(str(th), cv2.resize(scene.thermal_8bit, (40, 30)))
    args = _args(d, thermal=None) + ["--thermal", str(th)]
    assert main(args) == 2
    assert "80x60" in _err(capsys)
    args = _args(d, "--overlay", str(d / "left.png"))
    assert main(args) == 2
    assert "overwrite" in _err(capsys)


def test_overlay_suffix_is_checked_before_the_detection(folder, capsys, tmp_path, monkeypatch):
    """An --overlay OpenCV cannot encode fails at once: it used to fail only after the whole
    detection had run (write_image's refusal at the end)."""
    from hearsee.vision import fusion

    d, _ = folder

    def not_now(*_, **__):
        raise AssertionError("the detection ran before the overlay path was checked")

    monkeypatch.setattr(fusion, "detect_humans", not_now)
    for name in ("out.txt", "out"):
        assert main(_args(d, "--overlay", str(tmp_path / name), thermal=None)) == 2
        err = _err(capsys)
        assert "OpenCV cannot write" in err and "Traceback" not in err
        assert not (tmp_path / name).exists()
    # formats OpenCV writes, but not an 8-bit colour overlay (they were refused only after
    # the detection: grey-only PGM / PBM, float-only Radiance HDR / PFM)
    for name, words in (("out.pgm", "cannot encode the image as .pgm"),
                        ("out.pbm", "cannot encode the image as .pbm"),
                        ("out.hdr", ".hdr cannot hold uint8 pixels"),
                        ("out.pfm", ".pfm cannot hold uint8 pixels")):
        assert main(_args(d, "--overlay", str(tmp_path / name), thermal=None)) == 2
        err = _err(capsys)
        assert words in err and "Traceback" not in err
        assert not (tmp_path / name).exists()


def test_overlay_in_a_disabled_codec_is_one_line(folder, capfd, tmp_path, monkeypatch):
    """--overlay out.exr: OpenCV's wheels build the OpenEXR codec but disable it, and
    cv2.haveImageWriter raised cv2.error -- OpenCV's "[ WARN ]" line and a traceback, exit 1.
    Now the one-line refusal of any suffix OpenCV cannot write, before the detection (the
    descriptor-level capture: OpenCV's log writes there)."""
    from hearsee.vision import fusion

    try:
        cv2.haveImageWriter("probe.exr")
    except cv2.error:
        pass
    else:
        pytest.skip("this OpenCV build writes OpenEXR")
    d, _ = folder

    def not_now(*_, **__):
        raise AssertionError("the detection ran before the overlay path was checked")

    monkeypatch.setattr(fusion, "detect_humans", not_now)
    capfd.readouterr()
    assert main(_args(d, "--overlay", str(tmp_path / "out.exr"), thermal=None)) == 2
    out, err = capfd.readouterr()
    assert out == "" and err.startswith("hearsee: error: ") and "OpenCV cannot write .exr" in err
    assert err.count("\n") == 1, err
    assert not (tmp_path / "out.exr").exists()


def test_existing_overlay_is_kept_unless_forced(folder, capsys, tmp_path):
    d, _ = folder
    ov = tmp_path / "mine.png"
    ov.write_bytes(b"not yours")
    assert main(_args(d, "--overlay", str(ov), thermal=None)) == 2
    err = _err(capsys)
    assert "file exists; pass --force" in err and "Traceback" not in err
    assert ov.read_bytes() == b"not yours"
    assert main(_args(d, "--overlay", str(ov), "--force", thermal=None)) == 0
    assert cv2.imread(str(ov)) is not None


class _TouchOnLoad:
    """Unpickling this creates ``marker``: shows whether a file was unpickled."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (self.marker.touch, ())


@pytest.mark.parametrize("option, name", [("--thermal", "model.npy"), ("--thermal", "model.pkl"),
                                          ("--calib", "model.pkl")])
def test_a_pickle_given_for_a_file_is_one_line_and_never_unpickled(folder, capsys, tmp_path,
                                                                  option, name):
    """No hearsee command loads pickles (saved models included): a pickle given for the
    thermal image or the calibration is refused in one line, exit 2, without running it."""
    import pickle

    from hearsee.learn import ClusteredNLE

    d, _ = folder
    marker = tmp_path / "unpickled"
    (tmp_path / name).write_bytes(pickle.dumps([ClusteredNLE(), _TouchOnLoad(marker)]))
    args = _args(d)
    args[args.index(option) + 1] = str(tmp_path / name)
    assert main(args) == 2
    err = _err(capsys)
    assert name in err and err.count("\n") == 1
    assert not marker.exists()


def test_a_truncated_image_file_is_one_line_on_stderr(folder, tmp_path, capfd):
    """A PNG or TIFF cut short (a copy interrupted) printed OpenCV's own "[ WARN ]" (PNG) or
    two "[ERROR]" lines (TIFF) on stderr before hearsee's one-line error; now the one line
    alone, exit 2 -- for the stereo images and the thermal image alike."""
    d, scene = folder
    for name, image in (("cut.png", scene.left), ("cut.tif", scene.left)):
        ok, buf = cv2.imencode(name[-4:], image)
        assert ok
        (tmp_path / name).write_bytes(buf.tobytes()[: len(buf) // 3])
        capfd.readouterr()
        args = ["detect", "--left", str(tmp_path / name), "--right", str(d / "right.png"),
                "--calib", str(d / "calib.yaml")]
        assert main(args) == 2
        err = capfd.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("hearsee: error:") and name in err[0]
    assert main(_args(d, thermal=None) + ["--thermal", str(tmp_path / "cut.tif")]) == 2
    err = capfd.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a readable image" in err[0]


def test_overlay_force_keeps_the_earlier_file_when_the_write_fails(folder, capsys, tmp_path,
                                                                   file_size_limit):
    """`detect --overlay ov.png --force` wrote the image in place: a write that failed part way
    (a full disk, here a file size limit; Ctrl-C) left a truncated PNG where the user's
    earlier file was. Now the new image replaces it only when complete: the earlier file
    stays, one line names it, no temporary file is left, nothing on stdout; without the limit
    the same run writes the overlay."""
    d, _ = folder
    ov = tmp_path / "ov.png"
    ov.write_bytes(b"my earlier overlay")
    with file_size_limit(20_000):  # (the 320x240 overlay is ~150 kB)
        code = main(_args(d, "--overlay", str(ov), "--force"))
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.startswith(f"hearsee: error: {ov}: cannot write the image (") and \
        err.count("\n") == 1, err
    assert ov.read_bytes() == b"my earlier overlay"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ov.png"]
    assert main(_args(d, "--overlay", str(ov), "--force")) == 0
    assert cv2.imread(str(ov)).shape == (240, 320, 3)


@pytest.mark.parametrize(("option", "message"), [
    ("--thermal", ".: is a folder, expected an image file"),
    ("--overlay", ".: is a folder, expected an output file name")])
def test_an_empty_thermal_or_overlay_is_refused(option, message, folder, capsys, tmp_path,
                                                monkeypatch):
    """`--thermal ""` (an unset variable in a script, `--thermal "$T"`) was taken as no thermal
    image: exit 0, people accepted on stereo alone, the mannequin too, without a word; an empty
    --overlay was dropped the same way. Now each is the path it names, refused in one line as
    every other empty path is, before the detection."""
    d, _ = folder
    monkeypatch.chdir(tmp_path)
    args = _args(d, thermal=None) + [option, ""]
    assert main(args) == 2
    out, err = capsys.readouterr()
    assert out == "" and err == f"hearsee: error: {message}\n"


def test_a_binary_image_is_warned_about(folder, tmp_path, capsys):
    """A 1-bit PNG as --left (a scan, a thresholded export) gave a false human beside the
    real one without a word: stereo matching and the template need grey levels. One warning
    line names it; the rendered pair itself warns nothing."""
    d, _ = folder
    code = main(_args(d))
    assert code == 0 and "two grey levels" not in capsys.readouterr().err
    left = cv2.imread(str(d / "left.png"), cv2.IMREAD_GRAYSCALE)
    binary = tmp_path / "left_1bit.png"
    assert cv2.imwrite(str(binary), np.where(left > 100, 255, 0).astype(np.uint8),
                       [cv2.IMWRITE_PNG_BILEVEL, 1])
    args = _args(d)
    args[args.index("--left") + 1] = str(binary)
    code = main(args)
    err = capsys.readouterr().err
    assert code == 0 and err.count("holds only two grey levels") == 1
    assert err.startswith(f"hearsee: warning: {binary} holds only two grey levels")
