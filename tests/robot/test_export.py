"""Rerun and MCAP exports of a robot log the test constructs."""

from pathlib import Path

import numpy as np
import pytest

from hearsee.errors import ConfigError, ImageInputError, InputFileError
from hearsee.robot import export
from hearsee.robot.export import check_export, write_mcap, write_rerun
from hearsee.robot.scenario import default_scenario


def _log():
    log = []
    for k in range(5):
        t = 0.2 * (k + 1)
        truth = np.array([1.0 + 0.1 * k, 4.0, 1.1])
        log.append({"t": t, "head_pan_deg": 10.0 * k,
                    "truth": {"position_m": truth},
                    "track": None if k == 0 else {"position_m": truth + [0.02, -0.01, 0.0]}})
    frames = [(0.4, np.full((24, 32, 3), 100, np.uint8)), (0.8, np.zeros((24, 32), np.uint8))]
    return log, frames


def test_mcap_round_trip(tmp_path):
    pytest.importorskip("mcap_ros2")
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    log, frames = _log()
    path = write_mcap(tmp_path / "run.mcap", log, frames)
    msgs = {}
    with open(path, "rb") as f:
        for _, channel, _, ros_msg in make_reader(
                f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            msgs.setdefault(channel.topic, []).append(ros_msg)
    assert len(msgs["/hearsee/truth"]) == 5
    assert len(msgs["/hearsee/speaker"]) == 4  # no track in the first step
    assert len(msgs["/hearsee/head_pan"]) == 5 and len(msgs["/hearsee/overlay"]) == 2
    p = msgs["/hearsee/speaker"][-1].point
    assert (p.x, p.y, p.z) == pytest.approx((1.42, 3.99, 1.1))
    assert msgs["/hearsee/head_pan"][2].data == pytest.approx(20.0)
    img = msgs["/hearsee/overlay"][1]
    assert (img.width, img.height, img.encoding, img.step) == (32, 24, "bgr8", 96)
    stamp = msgs["/hearsee/truth"][0].header.stamp
    assert stamp.sec == 0 and stamp.nanosec == 200_000_000
    assert {m.header.frame_id for m in msgs["/hearsee/speaker"]} == {"room"}
    # a live run's positions are in the robot frame (they were labelled room)
    live = write_mcap(tmp_path / "live.mcap", log, frames, frame_id="robot")
    with open(live, "rb") as f:
        ids = {m.header.frame_id for _, ch, _, m in make_reader(
            f, decoder_factories=[DecoderFactory()]).iter_decoded_messages()
            if ch.topic == "/hearsee/speaker"}
    assert ids == {"robot"}


def test_rerun_recording(tmp_path):
    pytest.importorskip("rerun")
    log, frames = _log()
    path = write_rerun(tmp_path / "run.rrd", default_scenario().to_dict(), log, frames)
    assert path.stat().st_size > 1000


def _stand_in_rerun(monkeypatch):
    """A stand-in ``rerun`` module (the real one is an optional extra, often absent here)
    that records what is logged, by entity: images as arrays, the other archetypes as
    (args, kwargs)."""
    import sys
    import types

    logged = {}

    class _Rec:
        def __init__(self, *_):
            pass

        def log(self, name, obj, static=False):
            logged.setdefault(name, []).append(obj)

        def set_time(self, *_, **__):
            pass

        def save(self, path):
            open(path, "wb").close()

        def disconnect(self):
            pass

    fake = types.ModuleType("rerun")
    fake.RecordingStream = _Rec
    fake.Image = lambda a: np.asarray(a)
    for name in ("Boxes3D", "Points3D", "LineStrips3D", "Scalars"):
        setattr(fake, name, lambda *a, **k: (a, k))
    monkeypatch.setitem(sys.modules, "rerun", fake)
    return logged


def test_rerun_lines_break_at_a_change_of_talker_and_a_new_track(tmp_path, monkeypatch):
    """The truth line breaks where the talker changes (it was drawn across the room from one
    talker to the other) and the track's where a new track begins after none; the truth point
    is labelled with the current talker's name."""
    sc = default_scenario().to_dict()
    sc["people"] = [{**sc["people"][0], "name": "Ana"}, {**sc["people"][0], "name": "Ben"}]
    a, b = np.array([1.0, 4.0, 1.1]), np.array([5.0, 1.0, 1.1])
    log = []
    for k in range(6):  # Ana for three steps, then Ben; the track lost at step 3
        who = int(k >= 3)
        p = (a if who == 0 else b) + [0.1 * k, 0.0, 0.0]
        log.append({"t": 0.2 * (k + 1), "truth": {"position_m": p, "talker": who},
                    "track": None if k == 3 else {"position_m": p + 0.01}})
    logged = _stand_in_rerun(monkeypatch)
    write_rerun(tmp_path / "run.rrd", sc, log)
    strips = logged["truth_path"][-1][0][0]
    assert [len(s) for s in strips] == [3, 3]
    assert strips[1][0] == pytest.approx(list(b + [0.3, 0.0, 0.0]))
    assert [len(s) for s in logged["track_path"][-1][0][0]] == [3, 2]
    assert [pt[1]["labels"] for pt in logged["truth"]] == [["Ana"]] * 3 + [["Ben"]] * 3


def test_rerun_paths_are_logged_a_bounded_number_of_times(tmp_path, monkeypatch):
    """Each path was logged whole at every record: the recording grew with the square of the
    run's length. A 2000-record run logs each path at most RERUN_PATH_UPDATES (+1) times, the
    last one complete; the points at every record."""
    from hearsee.robot import export

    n = 2000
    log = [{"t": 0.032 * k, "truth": {"position_m": [2.0, 0.001 * k, 1.1], "talker": 0},
            "track": {"position_m": [2.0, 0.001 * k + 0.01, 1.1]}} for k in range(n)]
    logged = _stand_in_rerun(monkeypatch)
    write_rerun(tmp_path / "run.rrd", default_scenario().to_dict(), log)
    for name in ("truth", "track"):
        assert len(logged[name]) == n
        paths = logged[f"{name}_path"]
        assert len(paths) <= export.RERUN_PATH_UPDATES + 1
        last = paths[-1][0][0]
        assert [len(s) for s in last] == [n]
        assert last[0][-1][1] == pytest.approx(0.001 * (n - 1) + (0.01 if name == "track" else 0))
        assert sum(len(p[0][0][0]) for p in paths) <= (export.RERUN_PATH_UPDATES + 1) * n


def test_rerun_overlay_colours_with_a_stand_in_rerun(tmp_path, monkeypatch):
    """The images write_rerun logs are RGB (H, W, 3) whatever the frame's layout: a BGRA frame
    was reversed whole (ARGB: alpha read as red), grey stayed 2-D. A stand-in ``rerun`` module
    records what is logged (the real one is an optional extra, often absent here)."""
    logged = _stand_in_rerun(monkeypatch)
    bgra = np.zeros((4, 5, 4), np.uint8)
    bgra[..., 0], bgra[..., 2], bgra[..., 3] = 200, 10, 255  # blue, a little red, opaque
    bgr = bgra[..., :3].copy()
    grey = np.full((4, 5), 77, np.uint8)
    log, _ = _log()
    write_rerun(tmp_path / "run.rrd", default_scenario().to_dict(), log,
                [(0.2, bgra), (0.4, bgr), (0.6, grey)])
    overlays = logged["camera/overlay"]
    assert [im.shape for im in overlays] == [(4, 5, 3)] * 3
    for im in overlays[:2]:
        assert (im[0, 0] == [10, 0, 200]).all()  # RGB: red 10, green 0, blue 200
    assert (overlays[2] == 77).all()
    # a frame of another layout is refused, naming its time (neither export can describe it)
    for bad in (np.zeros((4, 5, 2), np.uint8), np.zeros(20, np.uint8)):
        with pytest.raises(ImageInputError, match=r"overlay frame at t = 0\.6 s"):
            write_rerun(tmp_path / "bad.rrd", default_scenario().to_dict(), log, [(0.6, bad)])


def test_missing_folder_is_a_clear_error(tmp_path):
    pytest.importorskip("mcap_ros2")
    log, frames = _log()
    with pytest.raises(InputFileError, match="does not exist"):
        write_mcap(tmp_path / "nope" / "run.mcap", log, frames)


def test_check_export_before_a_run(tmp_path, monkeypatch):
    """The up-front check names a missing extra or folder the way writing at the end would."""
    monkeypatch.setitem(export._EXTRAS, "mcap", ("hearsee_no_such_module", "--mcap needs X"))
    with pytest.raises(ConfigError, match="--mcap needs X"):
        check_export("mcap", tmp_path / "run.mcap")
    monkeypatch.setitem(export._EXTRAS, "rerun", ("json", "--rerun needs Y"))  # present
    assert "json installed" in check_export("rerun", tmp_path / "run.rrd")
    with pytest.raises(InputFileError, match="does not exist"):
        check_export("rerun", tmp_path / "nope" / "run.rrd")
    with pytest.raises(ConfigError, match="export kind must be one of"):  # (a KeyError)
        check_export("foo", tmp_path / "run.foo")
    assert list(tmp_path.iterdir()) == []  # a check writes nothing


def test_a_rerun_sdk_older_than_the_api_used_is_refused_before_the_run(tmp_path, monkeypatch):
    """write_rerun uses rerun 0.23's API (set_time(duration=), rr.Scalars); the extra asked for
    rerun-sdk>=0.20, and with 0.22.1 `hearsee demo --rerun` ran the whole scenario, wrote the
    report and ended in an AttributeError traceback. Now the check before the run, and the
    export itself, say which version is needed."""
    versions = {"rerun-sdk": "0.22.1"}

    def fake_version(name):
        if name not in versions:
            raise export.PackageNotFoundError(name)
        return versions[name]

    monkeypatch.setattr(export, "_dist_version", fake_version)
    monkeypatch.setitem(export._EXTRAS, "rerun", ("json", "--rerun needs Y"))  # (present)
    with pytest.raises(ConfigError, match=r"rerun-sdk 0\.23 or later, found 0\.22\.1"):
        check_export("rerun", tmp_path / "run.rrd")
    _stand_in_rerun(monkeypatch)
    log, _ = _log()
    with pytest.raises(ConfigError, match=r"rerun-sdk 0\.23 or later, found 0\.22\.1"):
        write_rerun(tmp_path / "run.rrd", default_scenario().to_dict(), log)
    assert list(tmp_path.iterdir()) == []
    for ok in ("0.23.0", "0.41.0", "1.0.0"):  # (the version the API appeared in, and later)
        versions["rerun-sdk"] = ok
        assert "json installed" in check_export("rerun", tmp_path / "run.rrd")
    del versions["rerun-sdk"]  # (no metadata: not refused)
    assert "json installed" in check_export("rerun", tmp_path / "run.rrd")
    from importlib.metadata import version as real_version

    monkeypatch.setattr(export, "_dist_version", real_version)
    assert export.RERUN_MIN_VERSION == (0, 23)
    pyproject = (Path(__file__).parents[2] / "pyproject.toml").read_text()
    assert '"rerun-sdk>=0.23"' in pyproject  # (the extra asks for what the code uses)


def test_overlay_frames_that_are_not_8_bit_are_refused():
    """The exports cast any frame to uint8 unsafely: uint16 300 became 44, float 0.7 became
    0 and -1 255. An ImageInputError naming the frame's time now; uint8 frames pass."""
    from hearsee.errors import ImageInputError

    ok = np.full((4, 6, 3), 200, np.uint8)
    np.testing.assert_array_equal(export._overlay_bgr(ok, 0.5), ok)
    for bad in (np.full((4, 6, 3), 300, np.uint16), np.full((4, 6), 0.7)):
        with pytest.raises(ImageInputError, match="t = 0.5 s: expected 8-bit pixels"):
            export._overlay_bgr(bad, 0.5)


def test_mcap_stamp_just_below_a_whole_second(tmp_path):
    """A time a hair below a whole second (0.1 summed ten times = 0.9999999999999999 s) rounds
    to 1 000 000 000 ns: the header stamp wrapped its nanoseconds to 0 without carrying into
    the seconds, i.e. 0.0 s -- one second early, and one second off its own log_time."""
    pytest.importorskip("mcap_ros2")
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    t = sum([0.1] * 10)
    assert t < 1.0
    log = [{"t": t, "head_pan_deg": None, "truth": {"position_m": [1.0, 2.0, 1.1]},
            "track": None}]
    frame_t = float(np.nextafter(3.0, 0.0))
    path = write_mcap(tmp_path / "run.mcap", log, [(frame_t, np.zeros((4, 6, 3), np.uint8))])
    with open(path, "rb") as f:
        got = [(channel.topic, message.log_time, ros_msg.header.stamp)
               for _, channel, message, ros_msg in make_reader(
                   f, decoder_factories=[DecoderFactory()]).iter_decoded_messages()]
    assert len(got) == 2
    for topic, log_time, stamp in got:
        assert stamp.sec * 1_000_000_000 + stamp.nanosec == log_time, topic
    assert (got[0][2].sec, got[0][2].nanosec) == (1, 0)
    assert (got[1][2].sec, got[1][2].nanosec) == (3, 0)


def test_mcap_overlay_of_bgra_and_single_channel_frames_is_bgr8(tmp_path):
    """Only 2-D frames were expanded to 3 channels: a BGRA or (H, W, 1) frame was written as
    "bgr8" with step = 3 * width over 4 or 1 bytes per pixel -- an Image message whose data
    does not match its own step and height."""
    pytest.importorskip("mcap_ros2")
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    rng = np.random.default_rng(0)
    bgr = rng.integers(0, 256, (6, 8, 3), dtype=np.uint8)
    grey = rng.integers(0, 256, (6, 8, 1), dtype=np.uint8)
    bgra = np.dstack([bgr, np.full((6, 8), 255, np.uint8)])
    path = write_mcap(tmp_path / "run.mcap", [], [(0.2, bgra), (0.4, grey)])
    with open(path, "rb") as f:
        imgs = [m for _, _, _, m in make_reader(
            f, decoder_factories=[DecoderFactory()]).iter_decoded_messages()]
    assert len(imgs) == 2
    for img, want in zip(imgs, (bgr, np.repeat(grey, 3, axis=2)), strict=True):
        assert (img.height, img.width, img.step, img.encoding) == (6, 8, 24, "bgr8")
        data = np.frombuffer(bytes(img.data), np.uint8)
        assert data.size == img.step * img.height
        np.testing.assert_array_equal(data.reshape(6, 8, 3), want)


def test_mcap_error_part_way_keeps_the_existing_file(tmp_path):
    """A frame write_mcap cannot describe (16-bit pixels) is found after the messages of the
    log were written: the target had been opened "wb", so the previous MCAP was truncated
    and a corrupt one left (70 bytes). It is now written beside the target and replaces it
    only when complete: the earlier file stays byte for byte, no temporary file is left."""
    pytest.importorskip("mcap_ros2")
    from mcap.reader import make_reader

    log, frames = _log()
    path = tmp_path / "run.mcap"
    write_mcap(path, log, frames)
    path.chmod(0o640)
    before = path.read_bytes()
    with pytest.raises(ImageInputError, match=r"overlay frame at t = 0\.8 s"):
        write_mcap(path, log, [frames[0], (0.8, np.zeros((24, 32, 3), np.uint16))])
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["run.mcap"]
    with open(path, "rb") as f:  # (still a whole MCAP: every message of the first write)
        assert sum(1 for _ in make_reader(f).iter_messages()) == 5 + 4 + 5 + 2
    # a complete rewrite replaces it (fewer frames, same permissions) and leaves nothing else
    write_mcap(path, log, frames[:1])
    with open(path, "rb") as f:
        topics = [ch.topic for _, ch, _ in make_reader(f).iter_messages()]
    assert topics.count("/hearsee/overlay") == 1 and len(topics) == 5 + 4 + 5 + 1
    assert path.stat().st_mode & 0o777 == 0o640
    assert [p.name for p in tmp_path.iterdir()] == ["run.mcap"]


def test_rerun_save_error_keeps_the_existing_file(tmp_path, monkeypatch):
    """write_rerun saved straight into the target: a save that failed part way (here a
    stand-in rerun whose sink writes some bytes, then fails) left them in place of the
    earlier recording. Now the recording is saved beside it, its sink closed, and only then
    moved over the target; on error the earlier file stays and no temporary file is left."""
    import sys
    import types

    events = []

    class _Rec:
        def __init__(self, *_):
            self.path = None

        def log(self, *_, **__):
            pass

        def set_time(self, *_, **__):
            pass

        def save(self, path):
            self.path = path
            with open(path, "wb") as fh:
                fh.write(b"partial")
            if fail:
                raise RuntimeError("disk full")

        def disconnect(self):  # the sink closes: the recording is complete
            with open(self.path, "ab") as fh:
                fh.write(b" complete")
            events.append(("disconnect", self.path))

    fake = types.ModuleType("rerun")
    fake.RecordingStream = _Rec
    for name in ("Image", "Boxes3D", "Points3D", "LineStrips3D", "Scalars"):
        setattr(fake, name, lambda *a, **k: None)
    monkeypatch.setitem(sys.modules, "rerun", fake)
    log, frames = _log()
    path = tmp_path / "run.rrd"
    path.write_bytes(b"earlier recording")
    fail = True
    with pytest.raises(RuntimeError, match="disk full"):
        write_rerun(path, default_scenario().to_dict(), log, frames)
    assert path.read_bytes() == b"earlier recording"
    assert [p.name for p in tmp_path.iterdir()] == ["run.rrd"]
    fail = False
    assert write_rerun(path, default_scenario().to_dict(), log, frames) == path
    assert path.read_bytes() == b"partial complete"
    assert len(events) == 1 and events[0][1] != str(path)  # (closed before the move)
    assert [p.name for p in tmp_path.iterdir()] == ["run.rrd"]


def test_mcap_to_a_fifo_is_written_through_not_replaced(tmp_path):
    """An export over an existing file is written beside it and moved over it; a FIFO (or a
    device, e.g. /dev/null) was thereby replaced by a regular file: the pipe's reader got
    nothing, and `hearsee demo --mcap /dev/null --force` run as root turned /dev/null into a
    20 MB file (found by the 2026-12-02 robot audit). Such a target is now written to."""
    import os
    import stat

    pytest.importorskip("mcap_ros2")
    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs on this system")
    fifo = tmp_path / "run.mcap"
    os.mkfifo(fifo)
    fd = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # (a reader, so the writer can open)
    try:
        log = [{"t": 0.2 * k, "head_pan_deg": 10.0 * k, "truth": {"position_m": [1, 2, 1.1]},
                "track": None} for k in range(3)]
        write_mcap(fifo, log)
        data = b""
        while chunk := os.read(fd, 65536):
            data += chunk
    finally:
        os.close(fd)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert data.startswith(b"\x89MCAP0\r\n") and data.endswith(b"\x89MCAP0\r\n")  # whole
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.mcap"]


@pytest.mark.parametrize("t", [-0.5, float("nan"), 1e11, None])
def test_mcap_time_out_of_a_stamps_range_is_a_config_error(tmp_path, t):
    """A negative time or one past a ROS 2 stamp's int32 seconds was struct.error "argument
    out of range" from the MCAP writer, NaN a builtin ValueError and a record without ``t`` a
    KeyError; now a ConfigError naming the record, and an existing file is kept."""
    pytest.importorskip("mcap_ros2")
    from mcap.reader import make_reader

    old = tmp_path / "run.mcap"
    old.write_bytes(b"earlier")
    log = [{"t": 0.2, "head_pan_deg": 1.0}, {"head_pan_deg": 2.0, **({} if t is None else
                                                                      {"t": t})}]
    with pytest.raises(ConfigError, match=r"log record 1: t .* must be a finite number in \[0"):
        write_mcap(old, log)
    with pytest.raises(ConfigError, match=r"overlay frame 0: t .* must be a finite number"):
        write_mcap(old, log[:1], [(t, np.zeros((4, 6, 3), np.uint8))])
    with pytest.raises(ConfigError, match=r"log record 0: track.position_m must be 3 numbers"):
        write_mcap(old, [{"t": 0.2, "track": {"position_m": [1.0, 2.0]}}])
    assert old.read_bytes() == b"earlier" and [p.name for p in tmp_path.iterdir()] == ["run.mcap"]
    # the range's ends are written: 0 s and the last whole second of an int32 stamp
    log = [{"t": 0.0, "head_pan_deg": 1.0}, {"t": export.MAX_STAMP_S, "head_pan_deg": 2.0}]
    with open(write_mcap(tmp_path / "ends.mcap", log), "rb") as f:
        times = [m.log_time for _, _, m in make_reader(f).iter_messages()]
    assert times == [0, (2**31 - 1) * 1_000_000_000]
