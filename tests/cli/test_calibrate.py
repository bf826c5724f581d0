"""Tests of ``hearsee calibrate`` on rendered chessboards (known rig) and on bad input."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from hearsee.cli import main
from hearsee.vision import calibration as C
from hearsee.vision.camera import Camera, StereoRig, load_rig

PATTERN = (9, 6)
SQUARE = 0.025


@pytest.fixture(scope="module")
def board_dir(tmp_path_factory):
    """Six stereo + thermal views of a 9x6 board, rendered with a known rig."""
    d = tmp_path_factory.mktemp("boards")
    cam = Camera(K=np.array([[300.0, 0, 159.5], [0, 300.0, 119.5], [0, 0, 1]]),
                 dist=[-0.1, 0.02, 0.0, 0.0, 0.0], width=320, height=240)
    th = Camera.from_fov(50.0, 160, 120)
    truth = StereoRig.ideal(cam, 0.08, thermal=th, thermal_offset_m=(0.04, -0.04, 0.0))
    rays = {"l": C._subpixel_rays(cam, 2), "t": C._subpixel_rays(th, 2)}
    rng = np.random.default_rng(11)
    center = np.array([4 * SQUARE, 2.5 * SQUARE, 0.0])
    for i in range(6):
        Rb = cv2.Rodrigues(rng.uniform(-0.45, 0.45, 3) * np.array([1.0, 1.0, 0.3]))[0]
        pos = np.array([0.04 + rng.uniform(-0.05, 0.05), rng.uniform(-0.04, 0.04),
                        rng.uniform(0.42, 0.52)])
        tb = pos - Rb @ center
        for key, R, T, kw in (("left", np.eye(3), np.zeros(3), {}),
                              ("right", truth.R, truth.T, {}),
                              ("thermal", truth.R_thermal, truth.T_thermal,
                               dict(invert=True, blur_px=0.7))):
            c = th if key == "thermal" else cam
            img = C.render_chessboard(c, R @ Rb, R @ tb + T, PATTERN, SQUARE, noise=2.0,
                                      rng=rng, rays=rays["t" if key == "thermal" else "l"],
                                      **kw)
            cv2.imwrite(str(d / f"{key}{i:02d}.png"), img)
    return d, truth


def _write_sequence(fs, name, values):
    """A plain FileStorage sequence (as OpenCV's calibration sample writes grid_points)."""
    fs.startWriteStruct(name, cv2.FileNode_SEQ)
    for v in values:
        fs.write("", v)
    fs.endWriteStruct()


def _args(d, out, *extra):
    return ["calibrate", "--left", str(d / "left*.png"), "--right", str(d / "right*.png"),
            "--board", "9x6", "--square", str(SQUARE), "-o", str(out), *extra]


@pytest.mark.slow
def test_calibrate_writes_rig_and_prints_errors(board_dir, tmp_path, capsys):
    d, truth = board_dir
    out = tmp_path / "calib.yaml"
    assert main(_args(d, out, "--thermal", str(d / "thermal*.png"))) == 0
    text = capsys.readouterr().out
    assert "RMS reprojection error" in text and "left00.png" in text and "thermal" in text
    rig = load_rig(out)
    assert rig.left.fx == pytest.approx(300.0, rel=0.01)
    assert rig.baseline_m == pytest.approx(0.08, rel=0.02)
    assert rig.thermal is not None
    np.testing.assert_allclose(rig.thermal_center_m, truth.thermal_center_m, atol=0.006)
    assert rig.rms_px is not None and rig.rms_px < 0.5
    # existing output: refused without --force, overwritten with it (JSON output)
    assert main(_args(d, out)) == 2
    assert "--force" in capsys.readouterr().err
    ref = tmp_path / "reference.yml"
    fs = cv2.FileStorage(str(ref), cv2.FILE_STORAGE_WRITE)
    fs.write("M1", truth.left.K)
    _write_sequence(fs, "grid_points", [0.0, 0.0, 0.0, SQUARE, 0.0, 0.0])  # read, not compared
    fs.release()
    assert main(_args(d, out, "--force", "--json", "--reference", str(ref))) == 0
    data = json.loads(capsys.readouterr().out)
    assert len(data["views"]) == 6 and data["rms_px"]["stereo"] < 0.5
    assert abs(data["reference"]["left"]["fx_diff_pct"]) < 1.0
    assert load_rig(out).thermal is None
    # the reference file is an input too
    assert main(_args(d, ref, "--force", "--reference", str(ref))) == 2


@pytest.mark.parametrize("case", ["no_match", "no_board", "count_mismatch", "unreadable",
                                  "overwrite_input", "bad_board", "huge_board", "thin_board",
                                  "bad_square",
                                  "sizes_differ", "reference_without_m1",
                                  "reference_zero_m1", "reference_nan_m2"])
def test_calibrate_bad_input_exits_2_with_one_line(case, board_dir, tmp_path, capsys):
    d, _ = board_dir
    out = tmp_path / "c.yaml"
    if case == "no_match":
        args = _args(tmp_path, out)
        expect = "no left images matched"
    elif case == "no_board":
        for i in range(3):
            for side in ("left", "right"):
                cv2.imwrite(str(tmp_path / f"{side}{i}.png"), np.full((60, 80), 128, np.uint8))
        args = _args(tmp_path, out)
        expect = "not found in any image"
    elif case == "count_mismatch":
        args = _args(d, out)
        args[4] = str(d / "right0[0-3].png")
        expect = "6 left images but 4 right images"
    elif case == "unreadable":
        for i in range(3):
            for side in ("left", "right"):
                (tmp_path / f"{side}{i}.png").write_bytes(b"not an image")
        args = _args(tmp_path, out)
        expect = "not a readable image"
    elif case == "overwrite_input":
        args = _args(d, d / "left00.png", "--force")
        expect = "refusing to overwrite an input"
    elif case == "bad_board":
        args = _args(d, out)
        args[6] = "nine"
        expect = "9x6"
    elif case == "huge_board":  # (a builtin MemoryError for 6.5 TiB of corners before)
        args = _args(d, out)
        args[6] = "99999999999x6"
        expect = "at most 1000 inner corners"
    elif case == "thin_board":  # (OpenCV's detectors raised cv2.error: a traceback)
        args = _args(d, out)
        args[6] = "2x5"
        expect = "at least 3x3 inner corners"
    elif case == "bad_square":
        args = _args(d, out)
        args[8] = "-1"
        expect = "--square"
    elif case == "reference_without_m1":
        # a single-camera file of OpenCV's calibration sample: a sequence node and a plain map
        # are skipped (no OpenCV error), and the missing M1/M2 is reported before calibrating
        ref = tmp_path / "camera.yml"
        fs = cv2.FileStorage(str(ref), cv2.FILE_STORAGE_WRITE)
        fs.write("camera_matrix", np.eye(3))
        _write_sequence(fs, "grid_points", [0.0, 0.0, 0.0, SQUARE, 0.0, 0.0])
        fs.startWriteStruct("board", cv2.FileNode_MAP)
        fs.write("width", 9)
        fs.endWriteStruct()
        fs.release()
        args = _args(d, out, "--reference", str(ref))
        expect = "no M1 or M2 camera matrix"
    elif case in ("reference_zero_m1", "reference_nan_m2"):
        # (exit 0 with divide-by-zero warnings and an inf / null comparison before)
        ref = tmp_path / "ref.yml"
        fs = cv2.FileStorage(str(ref), cv2.FILE_STORAGE_WRITE)
        good = np.array([[500.0, 0, 320], [0, 500.0, 240], [0, 0, 1]])
        fs.write("M1", np.zeros((3, 3)) if case == "reference_zero_m1" else good)
        fs.write("M2", good if case == "reference_zero_m1" else np.full((3, 3), np.nan))
        fs.release()
        args = _args(d, out, "--reference", str(ref))
        expect = ": M1: camera K" if case == "reference_zero_m1" else ": M2: camera K"
    else:  # sizes_differ
        for i in range(3):
            cv2.imwrite(str(tmp_path / f"left{i}.png"), np.full((60, 80), 128, np.uint8))
            cv2.imwrite(str(tmp_path / f"right{i}.png"), np.full((60, 90), 128, np.uint8))
        args = _args(tmp_path, out)
        expect = "right images are 90x60"
    assert main(args) == 2
    err = capsys.readouterr().err
    assert expect in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err
    if case != "overwrite_input":
        assert not out.exists()


@pytest.mark.parametrize("case", ["parent_is_a_file", "output_is_a_folder"])
def test_calibrate_unwritable_output_is_refused_before_calibrating(case, board_dir, tmp_path,
                                                                    capsys):
    """An output inside a regular file (NotADirectoryError) or naming a folder with --force
    (IsADirectoryError) ended in a traceback, after the whole calibration had been done."""
    d, _ = board_dir
    (tmp_path / "afile").write_text("not a folder")
    if case == "parent_is_a_file":
        args, expect = _args(d, tmp_path / "afile" / "c.yaml"), "afile"
    else:
        args, expect = _args(d, tmp_path, "--force"), "is a folder"
    assert main(args) == 2
    err = capsys.readouterr().err
    assert expect in err and len(err.strip().splitlines()) == 1
    assert (tmp_path / "afile").read_text() == "not a folder"


def test_report_marks_views_the_thermal_calibration_rejected(capsys, tmp_path, monkeypatch):
    """ViewReport.rejected_thermal (a thermal view left out of the thermal intrinsics or
    extrinsics) was computed but never shown: the table printed its error like a used view's."""
    from types import SimpleNamespace

    from hearsee.cli.calibrate import _print_report
    from hearsee.vision.calibration import ViewReport
    from hearsee.vision.camera import Camera, StereoRig

    rig = StereoRig.ideal(Camera.from_fov(60.0, 640, 480), 0.08,
                          thermal=Camera.from_fov(50.0, 160, 120))
    monkeypatch.setenv("COLUMNS", "200")  # (one table row per line)
    views = [ViewReport(f"l{i}.png", f"r{i}.png", found_left=True, found_right=True,
                        found_thermal=True,
                        err_left=0.1, err_right=0.1, err_thermal=0.2 + i,
                        rejected_thermal=i == 1) for i in range(2)]
    res = SimpleNamespace(rig=rig, views=views, rms_left_px=0.1, rms_right_px=0.1,
                          rms_stereo_px=0.1, rms_thermal_px=0.2, rms_thermal_extrinsics_px=0.3)
    _print_report(res, tmp_path / "rig.yaml", None)
    rows = {line.split()[1]: line for line in capsys.readouterr().out.splitlines()
            if line.lstrip("│ ").startswith("l") and ".png" in line}
    assert "(rejected)" not in rows["l0.png"]
    assert "(rejected)" in rows["l1.png"]


def test_report_prints_file_names_as_written(capsys, tmp_path, monkeypatch):
    """File names are text, not rich markup: 'l[1].png' was shown as 'l.png' in the table and
    the rig written to 'rig[v2].yaml' as 'wrote .../rig.yaml'."""
    from types import SimpleNamespace

    from hearsee.cli.calibrate import _print_report
    from hearsee.vision.calibration import ViewReport
    from hearsee.vision.camera import Camera, StereoRig

    rig = StereoRig.ideal(Camera.from_fov(60.0, 640, 480), 0.08)
    monkeypatch.setenv("COLUMNS", "200")
    views = [ViewReport("l[1].png", "r[b]1.png", found_left=True, found_right=True,
                        err_left=0.1, err_right=0.1)]
    res = SimpleNamespace(rig=rig, views=views, rms_left_px=0.1, rms_right_px=0.1,
                          rms_stereo_px=0.1)
    out = tmp_path / "rig[v2].yaml"
    _print_report(res, out, None)
    text = capsys.readouterr().out
    assert "l[1].png" in text and "r[b]1.png" in text and f"wrote {out}" in text


@pytest.mark.parametrize("square", ["1e300", "1e-300", "nan", "2.5"])
def test_calibrate_square_outside_any_board_is_one_line(square, board_dir, tmp_path, capsys):
    """--square 1e300 or 1e-300 reached OpenCV: a numpy RuntimeWarning and an OpenCV
    "(-215:Assertion failed)" line. Now one line naming the option and its range."""
    d, _ = board_dir
    args = _args(d, tmp_path / "c.yaml")
    args[8] = square
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("hearsee: error: --square must be the side of one square in metres") \
        and err.count("\n") == 1, err
    assert not (tmp_path / "c.yaml").exists()


def test_calibrate_force_keeps_the_earlier_rig_when_the_write_fails(board_dir, tmp_path, capsys,
                                                                   file_size_limit):
    """`calibrate -o rig.yaml --force` wrote the rig in place: a write that failed part way (a
    full disk, here a file size limit; Ctrl-C) left a truncated rig.yaml where the user's
    earlier calibration was, with the message "File too large" naming no file. Now the new
    file replaces it only when complete: the earlier rig stays, one line names it, no
    temporary file is left; without the limit the same run writes a loadable rig."""
    d, truth = board_dir
    out = tmp_path / "rig.yaml"
    out.write_text("# my earlier calibration\n", encoding="utf-8")
    with file_size_limit(600):  # (a rig is ~1.5 kB)
        code = main(_args(d, out, "--force"))
    captured = capsys.readouterr()
    assert code == 2 and captured.out == ""
    assert captured.err == f"hearsee: error: {out}: cannot write (File too large)\n"
    assert out.read_text(encoding="utf-8") == "# my earlier calibration\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rig.yaml"]
    assert main(_args(d, out, "--force")) == 0
    assert abs(load_rig(out).baseline_m - truth.baseline_m) < 0.005


@pytest.mark.parametrize("option", ["--left", "--thermal"])
def test_calibrate_empty_image_pattern_is_refused(option, board_dir, tmp_path, capsys,
                                                  monkeypatch):
    """`--thermal ""` (an unset "$T") was taken as no thermal images: a rig without its thermal
    camera, exit 0, without a word; an empty --left listed the working folder (here "6 left
    images but ..." of whatever files were there). Now one line naming what is missing."""
    d, _ = board_dir
    monkeypatch.chdir(d)
    out = tmp_path / "rig.yaml"
    args = _args(d, out, "--thermal", str(d / "thermal*.png"))
    args[args.index(option) + 1] = ""
    assert main(args) == 2
    captured = capsys.readouterr()
    what = "left images" if option == "--left" else "thermal images"
    assert captured.out == "" and captured.err == (f"hearsee: error: no {what} given: the "
                                                   "pattern is empty\n")
    assert not out.exists()


def test_calibrate_warnings_are_hearsee_warning_lines(board_dir, tmp_path, capsys):
    """Every other command prints a warning as `hearsee: warning: <message>` (cli.main); the
    calibration's own warnings (too few views, rejected views) came as `warning: <message>`,
    which a log filter for hearsee's warnings missed. Now the same form, on stderr, stdout
    kept for the result (--json: one JSON document)."""
    d, _ = board_dir
    assert main(_args(d, tmp_path / "rig.yaml", "--json")) == 0
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert doc["warnings"] and err == "".join(f"hearsee: warning: {w}\n" for w in doc["warnings"])


@pytest.mark.slow
def test_calibrate_reads_deep_images_at_their_depth(board_dir, tmp_path, capsys):
    """12-bit visible boards in 16-bit PNGs and 16-bit radiometric thermal boards (centi-kelvin,
    the board 10 K apart from its squares): read as grey, OpenCV kept each file's top 8 bits --
    the visible boards nearly black (0.25 px RMS instead of 0.06 in the audit), the thermal board
    3 grey levels, found in no image. Now the rig is the one the 8-bit files give."""
    d, truth = board_dir
    for i in range(6):
        for side in ("left", "right"):
            img = cv2.imread(str(d / f"{side}{i:02d}.png"), cv2.IMREAD_UNCHANGED)
            cv2.imwrite(str(tmp_path / f"{side}{i:02d}.png"), img.astype(np.uint16) << 4)
        t8 = cv2.imread(str(d / f"thermal{i:02d}.png"), cv2.IMREAD_UNCHANGED).astype(float)
        counts = np.rint((20.0 + 10.0 * t8 / 255.0 + 273.15) * 100.0).astype(np.uint16)
        cv2.imwrite(str(tmp_path / f"thermal{i:02d}.png"), counts)
    deep, flat = tmp_path / "deep.yaml", tmp_path / "flat.yaml"
    assert main(_args(tmp_path, deep, "--thermal", str(tmp_path / "thermal*.png"))) == 0
    assert main(_args(d, flat, "--thermal", str(d / "thermal*.png"))) == 0
    capsys.readouterr()
    a, b = load_rig(deep), load_rig(flat)
    # (12 bits >> 4: the 8-bit pixels; OpenCV's solver agrees with itself to ~1e-10 px)
    np.testing.assert_allclose(a.left.K, b.left.K, rtol=1e-8)
    np.testing.assert_allclose(a.T, b.T, atol=1e-9)
    assert a.thermal is not None
    np.testing.assert_allclose(a.thermal_center_m, truth.thermal_center_m, atol=0.006)


def test_the_reference_is_checked_against_the_images_size(tmp_path):
    """The reference file holds no image size: its matrices were checked as 640x480 cameras, so
    a 4K camera's (principal point 1920, 1080) was refused as "outside the image". Checked
    against the calibrated images' size: the 4K matrix is a 3840x2160 camera, and a 320x240
    camera's principal point 1000 px out is still refused."""
    from hearsee.cli.calibrate import _read_reference
    from hearsee.errors import ConfigError

    ref = tmp_path / "intrinsics.yml"
    fs = cv2.FileStorage(str(ref), cv2.FILE_STORAGE_WRITE)
    k4 = np.array([[2800.0, 0, 1920.0], [0, 2800.0, 1080.0], [0, 0, 1]])
    fs.write("M1", k4)
    fs.release()
    np.testing.assert_array_equal(_read_reference(ref, (3840, 2160))["M1"], k4)
    with pytest.raises(ConfigError, match="outside the 320x240 image"):
        _read_reference(ref, (320, 240))
