"""``hearsee run``: dry-run checks and a live run through a fake sounddevice (no hardware).

The fake module lists devices, checks settings and streams a simulated recording through an
``InputStream`` callback thread, like PortAudio does; cameras are video files.
"""

from __future__ import annotations

import json
import sys
import threading
import time
import types
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from hearsee.cli import main

FS = 16000


class FakeInputStream:
    """Calls ``callback(indata (frames, channels) float32, frames, time, status)`` from a thread,
    block by block, ``speed`` times faster than real time."""

    def __init__(self, recording, device=None, channels=None, samplerate=None, blocksize=None,
                 dtype=None, callback=None, speed=4.0):
        assert recording.shape[0] >= channels and samplerate == FS and dtype == "float32"
        self.x = recording[:channels].astype(np.float32)
        self.blocksize, self.callback, self.speed = int(blocksize), callback, speed
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._play, daemon=True)

    def _play(self):
        for start in range(0, self.x.shape[1] - self.blocksize + 1, self.blocksize):
            if self._stop.is_set():
                return
            block = np.ascontiguousarray(self.x[:, start:start + self.blocksize].T)
            self.callback(block, self.blocksize, None, None)
            time.sleep(self.blocksize / FS / self.speed)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join(timeout=2.0)


class FakeSoundDevice(types.ModuleType):
    class PortAudioError(Exception):
        pass

    def __init__(self, devices, recording=None):
        super().__init__("sounddevice")
        self.devices = devices
        self.default = types.SimpleNamespace(device=[0, -1])
        self.recording = recording

    def query_devices(self, device=None, kind=None):
        if device is None and kind is None:
            return [dict(d) for d in self.devices]
        d = dict(self.devices[device])
        if kind == "input" and d["max_input_channels"] == 0:
            raise ValueError("not an input device")
        return d

    def check_input_settings(self, device=None, channels=None, dtype=None, extra_settings=None,
                             samplerate=None):
        if samplerate not in (16000, 48000):
            raise self.PortAudioError("Invalid sample rate")

    def InputStream(self, **kw):
        return FakeInputStream(self.recording, **kw)


DEVICES = [{"name": "Built-in Microphone", "max_input_channels": 2, "max_output_channels": 0},
           {"name": "USB 6ch Array", "max_input_channels": 6, "max_output_channels": 0}]


def _video(path: Path, img: np.ndarray, n: int = 3) -> None:
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"FFV1"), 5.0,
                         (img.shape[1], img.shape[0]), True)
    for _ in range(n):
        vw.write(img)
    vw.release()


@pytest.fixture
def robot_dir(tmp_path):
    from hearsee.sim.scenes import default_rig
    from hearsee.vision.camera import save_rig

    save_rig(default_rig(160, 120, thermal_size=(80, 60)), tmp_path / "rig.yaml")
    img = np.random.default_rng(1).integers(0, 255, (120, 160, 3), dtype=np.uint8)
    _video(tmp_path / "left.avi", img)
    _video(tmp_path / "right.avi", img)
    _video(tmp_path / "thermal.avi", img[:60, :80])
    return tmp_path


def _config(folder: Path, device="USB 6ch", cameras=True, **extra) -> Path:
    data = {"audio": {"device": device, "fs": FS, "array": "three-mic", "channels": [1, 2, 3]},
            "head": {"pivot_m": [0.0, 0.0, 1.2], "driver": "none"},
            "output": {"report": "report"}, **extra}
    if cameras:
        data["cameras"] = {"left": "left.avi", "right": "right.avi", "thermal": "thermal.avi",
                           "calib": "rig.yaml"}
    p = folder / "robot.yaml"
    p.write_text(yaml.safe_dump(data), encoding="utf-8")
    return p


def test_dry_run_all_checks_pass(robot_dir, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES))
    code = main(["run", "--config", str(_config(robot_dir)), "--dry-run"])
    out = capsys.readouterr()
    assert code == 0, out.err
    for name in ("audio.device", "cameras.calib", "cameras.left", "cameras.right",
                 "cameras.thermal"):
        assert name in out.out
    assert "FAIL" not in out.out and "all 6 checks passed" in out.out
    assert not (robot_dir / "report").exists()  # a dry run writes nothing


def test_dry_run_missing_device_is_one_line_naming_the_field(robot_dir, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES))
    cfg = _config(robot_dir, device="ReSpeaker")
    code = main(["run", "--config", str(cfg), "--dry-run"])
    out = capsys.readouterr()
    assert code == 2
    err = out.err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith(f"hearsee: error: {cfg}: audio.device: no input device named "
                             "'ReSpeaker' (available: 0 'Built-in Microphone' (2 in), "
                             "1 'USB 6ch Array' (6 in))")
    assert "FAIL" in out.out and "Traceback" not in out.err


def test_dry_run_without_portaudio(robot_dir, monkeypatch, capsys):
    class NoPortAudio:
        def find_spec(self, name, path=None, target=None):
            if name == "sounddevice":
                raise OSError("PortAudio library not found")

    monkeypatch.delitem(sys.modules, "sounddevice", raising=False)
    monkeypatch.setattr(sys, "meta_path", [NoPortAudio(), *sys.meta_path])
    code = main(["run", "--config", str(_config(robot_dir)), "--dry-run"])
    out, err = capsys.readouterr()
    assert code == 2
    assert err.strip() == ("hearsee: error: live audio input needs the sounddevice package and "
                           "the PortAudio library (PortAudio library not found): pip install "
                           "'hearsee[live]' (Debian/Ubuntu also: apt-get install libportaudio2)")
    # the table's install hint too (rich read "[live]" as markup and printed 'hearsee')
    assert "install 'hearsee[live]'" in out  # (the table: rich took "[live]" for markup)


def test_bad_robot_files_and_options(robot_dir, capsys):
    bad = robot_dir / "bad.yaml"
    bad.write_text("audio: {}\ncamera: {left: 0}\n", encoding="utf-8")
    assert main(["run", "--config", str(bad), "--dry-run"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown key 'camera'" in err[0] and str(bad) in err[0]
    assert main(["run", "--config", str(robot_dir / "none.yaml")]) == 2
    assert "file not found" in capsys.readouterr().err
    assert main(["run", "--config", str(robot_dir)]) == 2
    assert "is a folder, expected a YAML file" in capsys.readouterr().err
    assert main(["run", "--config", str(_config(robot_dir)), "--duration", "0"]) == 2
    assert capsys.readouterr().err == ("hearsee: error: --duration must be a number of seconds "
                                       "> 0, or inf for no limit, got 0.0\n")
    # --out must not write the report over an input (here a calibration named summary.json)
    (robot_dir / "prev").mkdir()
    (robot_dir / "prev" / "summary.json").write_bytes((robot_dir / "rig.yaml").read_bytes())
    data = yaml.safe_load(_config(robot_dir).read_text(encoding="utf-8"))
    data["cameras"]["calib"] = "prev/summary.json"
    (robot_dir / "robot2.yaml").write_text(yaml.safe_dump(data), encoding="utf-8")
    assert main(["run", "--config", str(robot_dir / "robot2.yaml"), "--dry-run",
                 "--out", str(robot_dir / "prev")]) == 2
    assert "would overwrite the input file" in capsys.readouterr().err
    # a head pivot at or below the floor passed the dry run (the detector then got a camera
    # height below the floor)
    for z in (-5.0, 0.0):
        below = {**yaml.safe_load(_config(robot_dir).read_text(encoding="utf-8"))}
        below["head"] = {**below.get("head", {}), "pivot_m": [0.0, 0.0, z]}
        (robot_dir / "below.yaml").write_text(yaml.safe_dump(below), encoding="utf-8")
        assert main(["run", "--config", str(robot_dir / "below.yaml"), "--dry-run"]) == 2
        err = capsys.readouterr().err
        assert "pivot must be above the floor" in err and err.count("\n") == 1
    # --mcap / --rerun over an input (the calibration) or an existing file: refused before the
    # devices are opened (no sounddevice is faked here, so a run would fail differently)
    calib = robot_dir / "rig.yaml"
    before = calib.read_bytes()
    assert main(["run", "--config", str(_config(robot_dir)), "--mcap", str(calib)]) == 2
    assert "refusing to overwrite an input file" in capsys.readouterr().err
    assert calib.read_bytes() == before
    (robot_dir / "old.rrd").write_bytes(b"keep")
    assert main(["run", "--config", str(_config(robot_dir)), "--rerun",
                 str(robot_dir / "old.rrd")]) == 2
    assert "file exists; pass --force" in capsys.readouterr().err
    assert (robot_dir / "old.rrd").read_bytes() == b"keep"


def test_robot_file_nested_too_deeply_is_one_line(tmp_path, capsys):
    """A robot file nested 3000 levels deep: a RecursionError traceback and exit 1 before;
    now one line naming the file, exit 2."""
    deep = tmp_path / "deep.yaml"
    deep.write_text("audio: " + "[" * 3000 + "]" * 3000 + "\n", encoding="utf-8")
    assert main(["run", "--config", str(deep), "--dry-run"]) == 2
    assert capsys.readouterr().err == f"hearsee: error: {deep}: invalid YAML: nested too deeply\n"


def test_a_camera_below_the_floor_fails_the_dry_run(robot_dir, monkeypatch, capsys):
    """The audit's robot file: pivot 0.1 m up, camera mounted 0.15 m below it. It passed the
    dry run and the live run died at its first frame; now one line naming cameras.mount_m."""
    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES))
    data = yaml.safe_load(_config(robot_dir).read_text(encoding="utf-8"))
    data["head"]["pivot_m"] = [0.0, 0.0, 0.1]
    data["cameras"]["mount_m"] = [0.0, 0.0, -0.15]
    cfg = robot_dir / "under.yaml"
    cfg.write_text(yaml.safe_dump(data), encoding="utf-8")
    assert main(["run", "--config", str(cfg), "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"hearsee: error: {cfg}: cameras.mount_m: the left camera's centre")
    assert "z = -0.050 m at head tilt +0.0 deg" in err and err.count("\n") == 1


def test_exports_are_checked_before_listening(robot_dir, monkeypatch, capsys):
    """--rerun / --mcap whose extra is missing or whose folder does not exist fail at once,
    before any device is opened (no sounddevice is faked: a run would fail differently) and
    without writing anything; the dry run lists the exports it checked."""
    from hearsee.robot import export

    cfg = _config(robot_dir)
    monkeypatch.setitem(export._EXTRAS, "mcap", ("hearsee_no_such_module", "--mcap needs ROS"))
    assert main(["run", "--config", str(cfg), "--mcap", str(robot_dir / "run.mcap")]) == 2
    assert capsys.readouterr().err.strip() == "hearsee: error: --mcap needs ROS"
    monkeypatch.setitem(export._EXTRAS, "rerun", ("json", "--rerun needs Rerun"))  # present
    assert main(["run", "--config", str(cfg), "--rerun", str(robot_dir / "no" / "r.rrd"),
                 "--dry-run"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.endswith("folder " + str(robot_dir / "no") + " does not exist")
    assert not (robot_dir / "report").exists() and not (robot_dir / "run.mcap").exists()
    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES))
    assert main(["run", "--config", str(cfg), "--rerun", str(robot_dir / "r.rrd"),
                 "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert "--rerun" in out and "all 7 checks passed" in out
    assert not (robot_dir / "r.rrd").exists()
    # both exports to one file: the MCAP would have replaced the Rerun recording at the end
    assert main(["run", "--config", str(cfg), "--rerun", str(robot_dir / "x.out"), "--mcap",
                 str(robot_dir / "." / "x.out"), "--dry-run"]) == 2
    assert "name the same file" in capsys.readouterr().err


@pytest.mark.slow
def test_live_run_through_sounddevice(robot_dir, monkeypatch, capsys):
    """Audio only: a simulated three-mic recording on channels 1-3 of a 6-channel device."""
    from hearsee.sim.audio import simulate_recording

    x, truth = simulate_recording("three-mic", [-1.5, 1.8, 0.3], signal="male", duration_s=2.0,
                                  fs=FS, snr_db=25.0, seed=5)
    rec = np.zeros((6, x.shape[1]))
    rec[1:4] = x / np.abs(x).max() * 0.5
    rec[[0, 4, 5]] = np.random.default_rng(0).normal(0, 0.05, (3, x.shape[1]))
    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES, rec))
    out_dir = robot_dir / "run1"
    code = main(["run", "--config", str(_config(robot_dir, cameras=False)), "--duration", "1.5",
                 "--out", str(out_dir), "--quiet", "--mcap", str(robot_dir / "run.mcap")])
    out = capsys.readouterr()
    assert code == 0, out.err
    assert f"report: {out_dir / 'index.html'}" in out.out
    lines = (out_dir / "updates.jsonl").read_text(encoding="utf-8").splitlines()
    recs = [json.loads(s) for s in lines]
    summary = json.loads((out_dir / "summary.json").read_text(encoding="utf-8"))
    assert summary["status"] == "ok" and summary["audio_s"] == pytest.approx(1.5)
    assert summary["success"] is False  # no cameras: heard, but never seen nor tracked
    assert summary["dropped_blocks"] == 0 and len(recs) == summary["updates"] > 20
    # the azimuth the robot reports is that of the simulated talker (robot frame, head at 0)
    assert abs(summary["azimuth_deg_median"] - truth["azimuth_deg"]) < 3.0
    measured = [r["audio"]["azimuth_deg"] for r in recs if r["audio"] and r["audio"]["measured"]]
    assert len(measured) > 10 and abs(np.median(measured) - truth["azimuth_deg"]) < 3.0
    # head driver none: the desired command is printed, the head is not moved
    assert "(driver none: not moved)" in out.err
    assert all(r["head_pan_deg"] == 0.0 for r in recs)
    assert recs[-1]["head_command"]["pan_deg"] == pytest.approx(truth["azimuth_deg"], abs=3.0)
    # the same outputs as the demo: ROS 2 messages in MCAP, one head angle per update
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(robot_dir / "run.mcap", "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        pans = [msg.data for _, _, _, msg in
                reader.iter_decoded_messages(topics=["/hearsee/head_pan"])]
    assert pans == [r["head_pan_deg"] for r in recs]


def test_bad_duration_is_one_line_not_a_traceback(robot_dir, monkeypatch, capsys):
    """--duration inf once passed the '> 0' check and then raised OverflowError (int(inf * fs))
    as a traceback once the audio device was opened (inf is now no limit: next test); a NaN,
    zero or negative duration is one line before any device is opened."""
    rec = np.zeros((6, FS))
    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES, rec))
    cfg = _config(robot_dir, cameras=False)
    for bad in ("nan", "-1", "0", "-inf"):
        assert main(["run", "--config", str(cfg), "--duration", bad, "--quiet"]) == 2
        want = ("hearsee: error: --duration must be a number of seconds > 0, or inf for no "
                f"limit, got {float(bad)!r}\n")
        assert capsys.readouterr().err == want
    assert not (robot_dir / "report").exists()


def test_infinite_duration_is_no_limit(robot_dir, monkeypatch, capsys):
    """--duration inf means no limit -- until Ctrl-C or the input stops --, as omitting it does:
    the rule (config.time_limit) of the robot's MappedSource, the stream's DeviceSource and
    `hearsee track --duration inf`, which accepted it while `hearsee run` refused it."""
    from hearsee.errors import ConfigError
    from hearsee.robot import hardware

    seen = []

    def fake_run_robot(cfg, *, duration_s=None, progress=None, **kw):
        seen.append(duration_s)
        raise ConfigError("stopped by the test")  # (no device needed)

    monkeypatch.setattr(hardware, "run_robot", fake_run_robot)
    cfg = _config(robot_dir, cameras=False)
    for args in ([], ["--duration", "inf"], ["--duration", "1.5"]):
        assert main(["run", "--config", str(cfg), "--quiet", *args]) == 2
        assert capsys.readouterr().err == "hearsee: error: stopped by the test\n"
    assert seen == [None, None, 1.5]


def test_run_and_track_share_the_duration_rule(robot_dir, capsys):
    """The same words for the same mistake: `hearsee track --duration nan` said 'duration_s
    must be ...' (DeviceSource's parameter), `hearsee run` '--duration must be > 0 seconds and
    finite'; both now name the flag with the one rule of config.time_limit."""
    cfg = _config(robot_dir, cameras=False)
    for bad in ("nan", "-2"):
        want = ("hearsee: error: --duration must be a number of seconds > 0, or inf for no "
                f"limit, got {float(bad)!r}\n")
        assert main(["run", "--config", str(cfg), "--duration", bad]) == 2
        assert capsys.readouterr().err == want
        assert main(["track", "--device", "0", "--array", "three-mic", "--duration", bad]) == 2
        assert capsys.readouterr().err == want


def test_report_folder_that_is_a_file_fails_before_listening(robot_dir, monkeypatch, capsys):
    """output.report (or --out) naming an existing file, with the JSON lines elsewhere: the
    dry run passed and a live run listened to the end, then died writing its report (nothing
    of it written); the robot file is refused at once, the file untouched."""
    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES))
    notes = robot_dir / "notes.txt"
    notes.write_text("keep", encoding="utf-8")
    for out, args in (({"report": "notes.txt/sub", "jsonl": "run.jsonl"}, []),
                      ({"report": "report"}, ["--out", str(notes)])):
        cfg = _config(robot_dir, cameras=False, output=out)
        assert main(["run", "--config", str(cfg), *args, "--dry-run"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "output.report" in err[0] and "not a folder" in err[0], err
    assert notes.read_text(encoding="utf-8") == "keep"


def test_out_replaces_the_robot_files_outputs_which_are_not_checked(robot_dir, monkeypatch,
                                                                     capsys):
    """--out overrides output.report and output.jsonl: the robot file's own, which the run
    does not write, refused it ("output.report: .../hearsee-run is a file", "output.jsonl:
    notes.json exists and is not a hearsee run's JSON lines") -- a robot file whose default
    report folder is blocked could not be run with any --out (2026-12-07 robot review)."""
    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES))
    (robot_dir / "hearsee-run").write_text("not a folder", encoding="utf-8")
    (robot_dir / "notes.json").write_text("my notes\n", encoding="utf-8")
    for output in (None, {"report": "r", "jsonl": "notes.json"}):
        cfg = _config(robot_dir, cameras=False, **({} if output is None else {"output": output}))
        if output is None:  # (_config's report folder: removed, the default 'hearsee-run')
            data = yaml.safe_load(cfg.read_text(encoding="utf-8"))
            del data["output"]
            cfg.write_text(yaml.safe_dump(data), encoding="utf-8")
        assert main(["run", "--config", str(cfg), "--dry-run"]) == 2  # (without --out: refused)
        assert "output." in capsys.readouterr().err
        code = main(["run", "--config", str(cfg), "--out", str(robot_dir / "elsewhere"),
                     "--dry-run"])
        out = capsys.readouterr()
        assert code == 0, out.err
        assert "all 2 checks passed" in out.out
    # --out's own outputs are still checked
    assert main(["run", "--config", str(cfg), "--out", str(robot_dir / "hearsee-run"),
                 "--dry-run"]) == 2
    assert "--out" in capsys.readouterr().err
    assert (robot_dir / "notes.json").read_text(encoding="utf-8") == "my notes\n"
    assert not (robot_dir / "elsewhere").exists()


def test_report_folder_holding_a_folder_named_index_html_fails_before_listening(
        robot_dir, monkeypatch, capsys):
    """A folder named index.html in output.report passed the dry run; a live run listened
    to the end, then the report died with IsADirectoryError (2026-12-07 robot review)."""
    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES))
    (robot_dir / "report" / "index.html").mkdir(parents=True)
    cfg = _config(robot_dir, cameras=False, output={"report": "report"})
    assert main(["run", "--config", str(cfg), "--dry-run"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "output.report" in err[0] and (
        "index.html is a folder where the report writes a file" in err[0]), err
    assert list((robot_dir / "report").iterdir()) == [robot_dir / "report" / "index.html"]


def test_report_folder_that_cannot_be_written_or_is_the_jsonl_fails_before_listening(
        robot_dir, monkeypatch, capsys):
    """An output.report folder without write permission was refused only when the report was
    written, after the live run (a PermissionError); output.jsonl and output.report naming
    one path passed the dry run. Both are one line before any device opens. (The tests run
    as root, where permissions do not stop writes: os.access answers as for another user.)"""
    import os

    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES))
    same = _config(robot_dir, cameras=False,
                   output={"report": "out.jsonl", "jsonl": "out.jsonl"})
    assert main(["run", "--config", str(same), "--dry-run"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "output.jsonl and output.report are both" in err[0], err
    (robot_dir / "locked").mkdir()
    cfg = _config(robot_dir, cameras=False, output={"report": "locked/report",
                                                    "jsonl": "run.jsonl"})
    real = os.access
    monkeypatch.setattr(os, "access", lambda p, mode: Path(p).name != "locked" and real(p, mode))
    assert main(["run", "--config", str(cfg), "--dry-run"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "locked is not writable" in err[0], err
    assert main(["demo", "-q", "-o", str(robot_dir / "locked" / "r")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "locked is not writable" in err[0], err
    assert list((robot_dir / "locked").iterdir()) == []


def test_report_folder_of_someone_elses_files_is_kept_unless_forced(robot_dir, monkeypatch,
                                                                    capsys):
    """A report folder holding an index.html that no hearsee report wrote was overwritten at
    the end of the live run; now refused before listening (the dry run too), unless --force."""
    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES))
    (robot_dir / "site").mkdir()
    (robot_dir / "site" / "index.html").write_text("<title>mine</title>", encoding="utf-8")
    cfg = _config(robot_dir, cameras=False, output={"report": "site", "jsonl": "run.jsonl"})
    assert main(["run", "--config", str(cfg), "--dry-run"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is not a hearsee report's" in err[0], err
    assert main(["run", "--config", str(cfg), "--dry-run", "--force"]) == 0
    assert (robot_dir / "site" / "index.html").read_text(encoding="utf-8") == "<title>mine</title>"


@pytest.mark.parametrize("option", ["--mcap", "--rerun"])
def test_exports_over_the_runs_own_outputs_are_refused_before_listening(
        robot_dir, monkeypatch, capsys, option):
    """--mcap / --rerun naming the run's JSON lines or one of its report's files were only
    checked against the inputs: the run went ahead and the export, written last, replaced
    them (updates.jsonl / log.json began with MCAP bytes). Refused as `hearsee demo` does,
    --force or not, dry run or not, before any device opens; every earlier file kept."""
    x = np.zeros((6, 2 * FS))  # (a device that would play 2 s, were the run started)
    monkeypatch.setitem(sys.modules, "sounddevice", FakeSoundDevice(DEVICES, x))
    rep = robot_dir / "report"
    rep.mkdir()
    earlier = {rep / "index.html": "<title>hearsee report: earlier</title>",
               rep / "log.json": "[]", rep / "summary.json": "{}",
               rep / "updates.jsonl": '{"t": 0.0, "phase": "listening"}\n',
               robot_dir / "run.jsonl": '{"t": 0.0, "phase": "listening"}\n'}
    for p, text in earlier.items():
        p.write_text(text, encoding="utf-8")
    default = robot_dir / "default.yaml"  # (JSON lines: report/updates.jsonl)
    default.write_bytes(_config(robot_dir, cameras=False).read_bytes())
    cases = [(default, [], rep / "updates.jsonl", "is the run's JSON lines file"),
             (default, [], rep / "log.json", "one of the report's own files (output.report"),
             (default, [], rep / "index.html", "one of the report's own files"),
             (default, ["--out", str(rep)], rep / "summary.json",
              f"one of the report's own files (--out {rep})"),
             (default, ["--out", str(rep)], rep / "updates.jsonl", "JSON lines file"),
             (_config(robot_dir, cameras=False, output={"report": "report", "jsonl": "run.jsonl"}),
              [], robot_dir / "run.jsonl", "JSON lines file (output.jsonl")]
    for cfg, args, target, words in cases:
        for dry in (["--dry-run"], ["--duration", "1"]):
            code = main(["run", "--config", str(cfg), "-q", "--force", *args, *dry,
                         option, str(target)])
            out = capsys.readouterr()
            assert code == 2, (target, dry, out.err)
            assert words in out.err and out.err.count("\n") == 1, out.err
            assert out.err.startswith(f"hearsee: error: {option} {target} ")
    for p, text in earlier.items():
        assert p.read_text(encoding="utf-8") == text, p
