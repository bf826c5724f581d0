"""``hearsee track`` on bad input: a video that delivers no frame, image points that cannot be
used, a missing or doubled audio source, camera-pose options without a camera or out of range.
Each was run without a word (exit 0, no 3D fix) or with a wrong message before."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hearsee.audio.arrays import MicArray
from hearsee.audio.signals import write_recording
from hearsee.cli import main
from hearsee.errors import ConfigError
from hearsee.fusion.audiovisual import AudioVisualRig
from hearsee.sim.moving import linear_trajectory, simulate_moving_free_field
from hearsee.stream.video import CsvImagePoints, VideoImagePoints, save_image_points
from hearsee.vision.camera import Camera, save_camera

FS = 16000
DUR = 0.5
CAM_AT = (0.0, 0.0, 0.25)


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """A 0.5 s recording of a talker 1.2 m ahead (wide three-mic array), a 640x480 camera at
    CAM_AT and the talker's image points every 1/30 s (projected through the same rig)."""
    d = tmp_path_factory.mktemp("track_bad")
    arr = MicArray(np.array([[0.2, 0.0, 0.0], [-0.1, 0.25, 0.0], [-0.1, -0.25, 0.0]]),
                   name="wide")
    traj = linear_trajectory([1.2, -0.3, 0.1], [0.0, 0.4, 0.0], DUR)
    x = 0.05 * np.random.default_rng(0).standard_normal(int(DUR * FS))
    wav = d / "rec.wav"
    write_recording(wav, simulate_moving_free_field(x, FS, arr, traj, snr_db=25, rng=1), FS)
    cam = Camera.from_fov(70.0, 640, 480)
    cam_file = d / "cam.yaml"
    save_camera(cam, cam_file)
    t = np.arange(0, DUR, 1 / 30)
    pts = d / "points.csv"
    save_image_points(pts, t, AudioVisualRig.mounted(arr, cam, CAM_AT).project(traj.at(t)))
    arr_file = d / "wide.yaml"
    arr_file.write_text("name: wide\nmicrophones:\n" + "".join(
        f"  - [{p[0]}, {p[1]}, {p[2]}]\n" for p in arr.positions))
    base = ["track", str(wav), "--array", str(arr_file), "--camera", str(cam_file)]
    return {"wav": wav, "cam": cam_file, "pts": pts, "array": arr_file, "base": base,
            "centre": arr.centre}


def _positions(out: str) -> list:
    return [json.loads(s)["position_m"] for s in out.strip().splitlines()]


def _write_video(path, n_frames, size=(640, 480)):
    import cv2

    w = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, size)
    for _ in range(n_frames):
        w.write(np.full((size[1], size[0], 3), 90, np.uint8))
    w.release()


# ---------------------------------------------------------------------------------------------
# 1. a video file that opens but delivers no frame
# ---------------------------------------------------------------------------------------------
def test_track_refuses_a_video_that_delivers_no_frame(scene, tmp_path, capsys):
    """A truncated AVI (header, no frame data) opened, delivered nothing, and the run went on
    audio-only with exit 0. Now the dry-run's check (stream.video.read_frame) refuses it, in
    one line, before any audio is read."""
    import cv2

    full = tmp_path / "full.avi"
    _write_video(full, 5)
    data = full.read_bytes()
    cut = tmp_path / "cut.avi"
    cut.write_bytes(data[:data.index(b"movi") + 4])  # (the header; no frame)
    cap = cv2.VideoCapture(str(cut))  # ground truth: OpenCV opens it and reads nothing
    assert cap.isOpened() and not cap.read()[0]
    cap.release()
    assert main([*scene["base"], "--video", str(cut)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err == f"hearsee: error: --video: video file '{cut}' opened but delivered no frame\n"
    with pytest.raises(ConfigError,
                       match="video file: video file .* opened but delivered no frame"):
        VideoImagePoints(cut, detector="face")
    # the whole file: accepted, and its first frame (read by the check) is frame 0
    vp = VideoImagePoints(full, detector="face")
    assert vp(0.0) is None and vp.frame_index == 0
    assert vp(0.25) is None and vp.frame_index == 2
    assert vp(10.0) is None and vp.frame_index == 4 and vp.ended
    vp.close()


def test_a_still_image_given_as_video_is_a_one_frame_video(tmp_path):
    """OpenCV opens a PNG as a one-frame video (image-sequence reader, 25 fps): it delivers a
    frame, so it passes the check; the image points then cover its first 2/25 s only."""
    import cv2

    png = tmp_path / "still.png"
    cv2.imwrite(str(png), np.full((120, 160, 3), 90, np.uint8))
    vp = VideoImagePoints(png, detector="face")
    assert vp(0.0) is None and vp.frame_index == 0
    assert vp(1.0) is None and vp.ended and vp.frame_index == 0
    vp.close()


# ---------------------------------------------------------------------------------------------
# 2. image points that cannot be used
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("row", ["0.1,195,", "0.1,,190", "0.1,195,nan", "0.1, ,190"])
def test_image_point_row_with_only_u_or_v_is_refused(scene, tmp_path, capsys, row):
    """A row with u but no v (or v but no u) was read as "not visible" without a word; it is
    ambiguous (a lost column, a typo) and now an error naming the file and line. Both empty
    still means "not visible"."""
    p = tmp_path / "half.csv"
    p.write_text(f"t,u,v\n0.0,320,240\n{row}\n0.2,,\n")
    assert main([*scene["base"], "--image-points", str(p)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1
    assert err.startswith(f"hearsee: error: {p}: line 3: only one of u and v is given")
    with pytest.raises(ConfigError, match="line 3: only one of u and v"):
        CsvImagePoints(p)
    ok = tmp_path / "ok.csv"
    ok.write_text("t,u,v\n0.0,320,240\n0.1,,\n0.2,nan,nan\n")
    pts = CsvImagePoints(ok, max_gap_s=0.0)
    assert pts(0.0) == (320.0, 240.0) and pts(0.1) is None and pts(0.2) is None


def test_image_points_help_tells_the_margin_the_file_check_uses(scene, tmp_path, capsys):
    """--help said a point off the camera's image is an error, but points up to
    IMAGE_POINT_MARGIN of the larger side (64 px of 640x480) past the edge are used. The help
    now gives that margin; the check is as it was: 50 px off is used, 80 px off refused."""
    from hearsee.stream.video import IMAGE_POINT_MARGIN

    assert main(["track", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert (f"a point more than {IMAGE_POINT_MARGIN:.0%} of the image's larger side outside "
            "the camera's image (64 px of 640x480), is an error; a point nearer the edge is "
            "used") in text
    near, far = tmp_path / "near.csv", tmp_path / "far.csv"
    near.write_text("t,u,v\n0.0,-50,240\n0.3,690,240\n")
    far.write_text("t,u,v\n0.0,-80,240\n")
    assert main([*scene["base"], "--image-points", str(near)]) == 0
    capsys.readouterr()
    assert main([*scene["base"], "--image-points", str(far)]) == 2
    assert "outside the calibrated 640x480 image by more than 64 px" in capsys.readouterr().err


@pytest.mark.parametrize(("rows", "where"), [
    ("100,320,240\n101,330,240\n", "the file's visible points are from 100 s to 101 s"),
    ("0.0,,\n0.2,,\n", "the file has no visible point: every u,v is empty"),
    ("-5,320,240\n0.1,,\n0.9,320,240\n", "the file's visible points are from -5 s to 0.9 s"),
])
def test_track_warns_when_no_image_point_lies_within_the_recording(scene, tmp_path, capsys,
                                                                   rows, where):
    """Rows all outside the 0.5 s recording (times in ms, another take) or all empty gave exit
    0, no 3D fix and no message; now a warning says why there is no 3D position."""
    p = tmp_path / "far.csv"
    p.write_text(f"t,u,v\n{rows}")
    assert main([*scene["base"], "--image-points", str(p), "--camera-at",
                 ",".join(map(str, CAM_AT))]) == 0
    out, err = capsys.readouterr()
    assert all(pos is None for pos in _positions(out))
    assert err == (f"hearsee: warning: {p}: no image point lies within the recording's time "
                   f"span (0-{DUR:.2f} s; {where}), so no 3D position can be given\n")


def test_image_points_within_the_recording_give_3d_fixes_and_no_warning(scene, tmp_path,
                                                                        capsys):
    """The control: the talker's own image points give 3D fixes and no warning; so does a file
    whose only visible row is near the recording's end (within max_gap_s / 2 of a frame)."""
    assert main([*scene["base"], "--image-points", str(scene["pts"]), "--camera-at",
                 ",".join(map(str, CAM_AT))]) == 0
    out, err = capsys.readouterr()
    assert err == "" and any(pos is not None for pos in _positions(out))
    pts = CsvImagePoints(scene["pts"])
    assert pts.visible_within(0.03, 0.47) and not pts.visible_within(0.7, 1.0)
    late = tmp_path / "late.csv"
    late.write_text("t,u,v\n0.0,,\n0.5,320,240\n")
    assert main([*scene["base"], "--image-points", str(late)]) == 0
    assert "warning" not in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------
# 3. neither or both audio sources
# ---------------------------------------------------------------------------------------------
def test_track_names_a_missing_and_a_doubled_audio_source(scene, capsys):
    """Neither a recording nor --device was reported as "..., not both"."""
    assert main(["track", "--array", "three-mic"]) == 2
    assert capsys.readouterr().err == ("hearsee: error: give a recording file or --device "
                                       "(live input)\n")
    assert main(["track", str(scene["wav"]), "--device", "0", "--array", "three-mic"]) == 2
    assert capsys.readouterr().err == ("hearsee: error: give either a recording file or "
                                       "--device (live input), not both\n")


# ---------------------------------------------------------------------------------------------
# 4. camera-pose options
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("args", "names"), [
    (["--camera-at", "0,0,0.2"], "--camera-at needs"),
    (["--camera-pan", "10"], "--camera-pan needs"),
    (["--camera-tilt", "0"], "--camera-tilt needs"),
    (["--camera-at", "0,0,0", "--camera-pan", "5"], "--camera-at / --camera-pan need"),
])
def test_camera_pose_options_need_a_camera(scene, capsys, args, names):
    """--camera-at / --camera-pan / --camera-tilt without --camera were ignored (exit 0)."""
    assert main(["track", str(scene["wav"]), "--array", str(scene["array"]), *args]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err == (f"hearsee: error: {names} --camera CAM.yaml and an "
                                 "image-point source (they place the camera)\n")


@pytest.mark.parametrize("args", [[], ["--camera", "CAM", "--image-points", "PTS"]])
@pytest.mark.parametrize("name", ["face", "hog"])
def test_detector_needs_a_video_or_a_live_camera(scene, capsys, args, name):
    """--detector without --video / --camera-device (no camera at all, or --image-points,
    which are the image point itself) was ignored, exit 0; now one error line before the
    audio is read."""
    args = [{"CAM": str(scene["cam"]), "PTS": str(scene["pts"])}.get(a, a) for a in args]
    assert main(["track", str(scene["wav"]), "--array", str(scene["array"]), *args,
                 "--detector", name]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err == ("hearsee: error: --detector finds the speaker in the images of "
                                 "--video or --camera-device; give one of them, or leave it "
                                 "out\n")


@pytest.mark.parametrize(("args", "msg"), [
    (["--in-plane"], "--in-plane: the masked pair 'mask2-asym' is tracked by its own stages "
                     "(ch. 3; tables of the horizontal plane) without an in-plane model; leave "
                     "it out"),
    (["--gate-coherence", "0.3"], "--gate-coherence: the masked pair 'mask2-asym' is tracked by "
                                  "its own stages (ch. 3), without the steered response that "
                                  "gated detection searches; leave it out"),
])
def test_options_a_masked_pair_does_not_use_are_refused(tmp_path, capsys, args, msg):
    """--in-plane and --gate-coherence with mask2-asym were ignored: the same lines, to the
    digit, as without them (the masked stages have no in-plane model and no steered
    response), exit 0; `hearsee localize` refuses --in-plane there. Now one error line before
    the recording is read (so before the mask's model is solved); --gate-coherence 0 (off,
    the default) stays accepted."""
    code = main(["track", str(tmp_path / "none.wav"), "--array", "mask2-asym", *args])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err == f"hearsee: error: {msg}\n"
    main(["track", str(tmp_path / "none.wav"), "--array", "mask2-asym", "--gate-coherence",
          "0"])
    assert "gate-coherence" not in capsys.readouterr().err


def test_motion_model_ca_needs_a_camera(scene, capsys):
    """--motion-model ca (the 3D tracker's constant-acceleration model) without --camera was
    ignored: exit 0 and acceleration_mps2 null on every line, where the help and the README
    promise it; now one error line before the audio is read. The default cv without a camera
    stays a direction-only run."""
    wav_args = ["track", str(scene["wav"]), "--array", str(scene["array"])]
    assert main([*wav_args, "--motion-model", "ca"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err == ("hearsee: error: --motion-model ca chooses the 3D tracker of a "
                                 "calibrated camera's fixes: it needs --camera CAM.yaml and an "
                                 "image-point source (without them there is no 3D track and no "
                                 "acceleration_mps2)\n")
    assert main([*wav_args, "--motion-model", "cv"]) == 0
    assert all(json.loads(s)["position_m"] is None
               for s in capsys.readouterr().out.strip().splitlines())


@pytest.mark.parametrize(("args", "msg"), [
    (["--camera-pan", "1e300"], "--camera-pan must be in [-180, 180] degrees, got 1e+300"),
    (["--camera-pan", "-180.5"], "--camera-pan must be in [-180, 180] degrees, got -180.5"),
    (["--camera-pan", "nan"], "--camera-pan must be in [-180, 180] degrees, got nan"),
    (["--camera-tilt", "95"], "--camera-tilt must be in [-90, 90] degrees, got 95"),
    (["--camera-tilt", "-inf"], "--camera-tilt must be in [-90, 90] degrees, got -inf"),
    (["--camera-at", "100,0,0"], "--camera-at: 100,0,0 is 100 m from the array's centre; the "
                                 "camera must be within 5 m of its microphones"),
    (["--camera-at", "0,3,4.01"], "--camera-at: 0,3,4.01 is 5.01 m from the array's centre"),
])
def test_camera_pose_out_of_range_is_a_usage_error(scene, capsys, args, msg):
    """A pan of 1e300, a tilt of 95 deg or a camera 100 m away gave exit 0, no 3D fix and no
    message; now a usage error (one line, exit 2) before the audio is read."""
    assert main([*scene["base"], "--image-points", str(scene["pts"]), *args]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1
    assert err.startswith("hearsee track: error: ") and msg in err


@pytest.mark.parametrize("args", [["--camera-pan", "180", "--camera-tilt", "-90"],
                                  ["--camera-pan", "-180", "--camera-tilt", "90"],
                                  ["--camera-at", "0,3,3.99"]])
def test_camera_pose_limits_are_inclusive(scene, capsys, args):
    """The bounds themselves are accepted (a camera straight up, turned round, 4.99 m off)."""
    assert np.linalg.norm(np.array([0, 3, 3.99]) - scene["centre"]) < 5.0  # (the array's centre)
    assert main([*scene["base"], "--image-points", str(scene["pts"]), *args]) == 0
    assert "error" not in capsys.readouterr().err


def test_a_video_shorter_than_the_recording_is_warned_about(scene, tmp_path, capsys):
    """A 0.2 s video under a 0.5 s recording gave no image point (so no 3D position) after
    0.2 s without a word; now a warning says where the video ends. A video as long as the
    recording warns nothing."""
    short, full = tmp_path / "short.avi", tmp_path / "full.avi"
    _write_video(short, 2)  # 10 fps: frames at 0 and 0.1 s, ends at 0.2 s
    _write_video(full, 6)
    assert main([*scene["base"], "--video", str(short), "--detector", "face"]) == 0
    err = capsys.readouterr().err
    assert "the video ends at 0.20 s, before the recording" in err and err.count("\n") == 1
    assert main([*scene["base"], "--video", str(full), "--detector", "face"]) == 0
    assert "video ends" not in capsys.readouterr().err


def test_track_refuses_a_vertical_line(tmp_path, capsys):
    """A vertical pair hears elevation only, and track dropped every frame ("no localizable
    source"): one line and exit 2, before any audio is read. (A masked pair, refused here too
    until 2026-12-05, is tracked over 360 degrees since: tests/audio/test_mask.py.)"""
    import yaml

    wav = tmp_path / "two.wav"
    write_recording(wav, 0.1 * np.random.default_rng(0).standard_normal((2, 8000)), FS)
    vert = tmp_path / "vert.yaml"
    vert.write_text(yaml.safe_dump({"microphones": [[0, 0, -0.1], [0, 0, 0.1]],
                                    "name": "vertical"}))
    assert main(["track", str(wav), "--array", str(vert)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is a vertical line" in err[0], err
    assert main(["track", str(wav), "--array", "two-mic", "--format", "json"]) == 0
    capsys.readouterr()


def test_a_hop_below_half_a_sample_is_one_sample(tmp_path, capsys):
    """`hearsee track --hop-ms 1e-300` was an OverflowError traceback: the frames' hop is made
    one sample (as `hearsee localize` does), but the stream sized its activity history from
    the 1e-300 ms asked for (1e303 frames). Now the history is in the real hop: the run is
    the one of a one-sample hop (0.0625 ms at 16 kHz), update for update."""
    from hearsee.audio.propagation import simulate_free_field
    from hearsee.audio.signals import white_noise
    from hearsee.geometry import unit_vector_deg

    arr = MicArray.from_preset("three-mic")
    x = simulate_free_field(white_noise(0.1, FS, rng=2), FS, arr, 2.0 * unit_vector_deg(50, 0),
                            snr_db=30, rng=3)
    wav = tmp_path / "r.wav"
    write_recording(wav, 0.5 * x / np.abs(x).max(), FS)
    runs = []
    for hop in ("1e-300", "0.0625"):
        assert main(["track", str(wav), "--array", "three-mic", "--frame-ms", "4",
                     "--hop-ms", hop, "--format", "json"]) == 0
        out, err = capsys.readouterr()
        runs.append([{k: v for k, v in u.items() if k != "latency_ms"}
                     for u in json.loads(out)["updates"]])
    ts = [u["t"] for u in runs[0]]
    assert len(ts) > 1000 and np.allclose(np.diff(ts), 1 / FS, rtol=0, atol=1.1e-6)  # (t in us)
    assert runs[0] == runs[1] and any(u["azimuth_deg"] is not None for u in runs[0])


def test_a_camera_index_beyond_a_c_int_is_one_line(scene, tmp_path, capsys):
    """`--camera-device 99999999999999999999` (and a robot file's `cameras.left` as large)
    reached OpenCV's VideoCapture, whose TypeError was a traceback. Now the camera that
    cannot be opened: one line naming it, exit 2, before any audio."""
    from hearsee.robot.hardware import open_capture

    big = "99999999999999999999"
    assert main(["track", "--device", "0", "--array", str(scene["array"]), "--camera",
                 str(scene["cam"]), "--camera-device", big]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err == (f"hearsee: error: camera {big}: cannot be opened as a video "
                                 "(OpenCV VideoCapture)\n")
    with pytest.raises(ConfigError, match=f"cameras.left: cannot open camera {big}"):
        open_capture(int(big), "cameras.left")


def test_a_recording_without_a_source_is_a_warning_line(tmp_path, capsys):
    """Uncorrelated noise in every channel: no update is measured, and the message is a
    warning like every other (it lacked the "hearsee: warning:" prefix)."""
    wav = tmp_path / "noise.wav"
    write_recording(wav, 0.1 * np.random.default_rng(5).standard_normal((3, FS)), FS)
    assert main(["track", str(wav), "--array", "three-mic", "--format", "jsonl"]) == 0
    out, err = capsys.readouterr()
    assert "hearsee: warning: track: no frame held a localizable source\n" in err
    lines = out.splitlines()
    assert len(lines) > 10 and all(json.loads(u)["azimuth_deg"] is None for u in lines)


def test_track_leaves_out_an_upsampled_files_empty_band(tmp_path, capsys):
    """The stream cannot look ahead, so `hearsee track` looks at a file first: an 8 kHz
    recording read at 16 kHz gets the band below 4 kHz (and a note), as `hearsee localize`."""
    from scipy.signal import resample_poly

    from hearsee.audio.propagation import simulate_free_field
    from hearsee.audio.signals import synthetic_voice
    from hearsee.geometry import unit_vector_deg

    arr = MicArray.from_preset("three-mic")
    x = simulate_free_field(synthetic_voice("female", 1.5, 8000, rng=3), 8000, arr,
                            2.0 * unit_vector_deg(70.0, 0.0), snr_db=20, rng=4)
    y = resample_poly(x, 2, 1, axis=1)
    wav = tmp_path / "up.wav"
    write_recording(wav, 0.5 * y / np.abs(y).max(), FS)
    assert main(["track", str(wav), "--array", "three-mic", "--format", "json"]) == 0
    out, err = capsys.readouterr()
    assert err.startswith(f"hearsee: note: {wav}: the top of the spectrum is empty")
    az = [u["azimuth_deg"] for u in json.loads(out)["updates"][-10:]]
    assert None not in az and np.allclose(az, 70.0, atol=2.0)
    assert main(["track", str(wav), "--array", "three-mic", "--band-hz", "5000,7000"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "--band-hz 5000,7000: nothing there" in err


def test_stream_bands():
    from hearsee.cli.track import _srp_band, _stream_band

    x = np.random.default_rng(0).standard_normal((3, FS))  # made at 16 kHz: nothing empty
    assert _stream_band(None, x, FS, 64.0) is None
    assert _stream_band((300.0, 3500.0), x, FS, 64.0) == (300.0, 3500.0)
    assert _stream_band((300.0, 3500.0), None, FS, 64.0) == (300.0, 3500.0)  # live input
    from scipy.signal import resample_poly

    y = resample_poly(x[:, ::2], 2, 1, axis=1)  # 8 kHz content at 16 kHz
    lo, hi = _stream_band(None, y, FS, 64.0)
    assert lo == 0.0 and 3950.0 < hi <= 4000.0
    assert _stream_band((300.0, 3500.0), y, FS, 64.0) == (300.0, 3500.0)
    assert _stream_band((300.0, 6000.0), y, FS, 64.0) == (300.0, hi)
    with pytest.raises(ConfigError, match="nothing there"):
        _stream_band((5000.0, 7000.0), y, FS, 64.0)
    assert _srp_band(None, (300.0, 3500.0)) == (300.0, 3500.0)
    assert _srp_band((0.0, hi), (300.0, 3500.0)) == (300.0, 3500.0)
    assert _srp_band((1000.0, 2000.0), (300.0, 3500.0)) == (1000.0, 2000.0)
    assert _srp_band((3600.0, 3900.0), (300.0, 3500.0)) == (3600.0, 3900.0)


def test_track_warns_of_an_inverted_microphone(tmp_path, capsys):
    """The stream sees one frame at a time: with microphone 2 wired backwards its directions
    were wrong without a word. `hearsee track` looks at a file's whole-recording correlations
    first, as `hearsee localize` does."""
    from hearsee.audio.propagation import simulate_free_field
    from hearsee.audio.signals import white_noise
    from hearsee.geometry import unit_vector_deg

    arr = MicArray.from_preset("three-mic")
    x = simulate_free_field(white_noise(1.0, FS, rng=5), FS, arr,
                            2.0 * unit_vector_deg(-60.0, 0.0), snr_db=20, rng=6)
    for flip, want in ((1.0, 0), (-1.0, 1)):
        wav = tmp_path / f"r{want}.wav"
        write_recording(wav, 0.5 * x * np.array([[1.0], [1.0], [flip]]) / np.abs(x).max(), FS)
        assert main(["track", str(wav), "--array", "three-mic", "--format", "json"]) == 0
        out, err = capsys.readouterr()
        assert err.count("microphone 2 seems wired with inverted polarity: pairs 0-2, 1-2") == want
        assert len(json.loads(out)["updates"]) > 20
