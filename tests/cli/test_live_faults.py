"""The live paths' failure modes, through a fake ``sounddevice`` (no hardware, no PortAudio):
``hearsee run`` (and ``--dry-run``) and ``hearsee track --device``.

Each user-facing fault -- sounddevice or PortAudio missing, a device that does not exist or is
no input, too few input channels, a sample rate the device refuses, a PortAudio error when the
stream starts, blocks of another shape -- is one line on stderr and exit 2, never a traceback,
and nothing the user gave is written over; input overflows are counted and the run goes on;
Ctrl-C ends a live run cleanly with what was written kept.

The fake follows sounddevice's behaviour: ``query_devices(device, kind)`` raises ValueError for
a name that matches no input device or a device without inputs and PortAudioError for an index
that does not exist; ``check_input_settings`` and opening an ``InputStream`` raise
PortAudioError for a channel count or rate the device does not support; the stream calls
``callback(indata (frames, channels) float32, frames, time_info, status)`` from its own thread
once started, ``status.input_overflow`` set where PortAudio discarded input.
"""

from __future__ import annotations

import _thread
import gc
import json
import signal
import sys
import threading
import time
import types
from pathlib import Path

import numpy as np
import pytest
import yaml

from hearsee.cli import main

FS = 16000
DEVICES = [{"name": "Built-in Microphone", "max_input_channels": 2, "max_output_channels": 2},
           {"name": "HDMI Output", "max_input_channels": 0, "max_output_channels": 8},
           {"name": "USB 6ch Array", "max_input_channels": 6, "max_output_channels": 0}]


class _Flags:
    """sounddevice.CallbackFlags look-alike."""

    def __init__(self, overflow: bool) -> None:
        self.input_overflow = overflow

    def __bool__(self) -> bool:
        return self.input_overflow


class FakeSoundDevice(types.ModuleType):
    """sounddevice with ``DEVICES`` that accept 16 and 48 kHz.

    open_error / start_error : PortAudio's message when the stream is opened / started
    close_error : PortAudio's message when the stream stops (its exit raises, as
        sounddevice's stop() does; the stream is stopped all the same)
    deliver_channels : channels of every delivered block (default: those opened)
    overflow_at : blocks flagged ``input_overflow``
    interrupt_at : before this block, wait until the consumer is idle, then press Ctrl-C
        (``_thread.interrupt_main``); the stream goes on delivering until it is closed
    """

    class PortAudioError(Exception):
        pass

    def __init__(self, open_error=None, start_error=None, deliver_channels=None,
                 overflow_at=(), interrupt_at=None, speed=20.0, close_error=None) -> None:
        super().__init__("sounddevice")
        self.default = types.SimpleNamespace(device=[0, -1])
        self.open_error, self.start_error = open_error, start_error
        self.close_error = close_error
        self.deliver_channels, self.overflow_at = deliver_channels, set(overflow_at)
        self.interrupt_at, self.speed = interrupt_at, speed
        self.n_streams_closed = 0
        self.opened: list[int] = []  # the device index of every InputStream opened

    def query_devices(self, device=None, kind=None):
        if device is None and kind is None:
            return [dict(d) for d in DEVICES]
        if device is None:
            device = self.default.device[0]
        if isinstance(device, str):
            hits = [i for i, d in enumerate(DEVICES) if device.lower() in d["name"].lower()
                    and (kind is None or d[f"max_{kind}_channels"] > 0)]
            if not hits:
                raise ValueError(f"No {kind} device matching {device!r}")
            device = hits[0]
        if not 0 <= device < len(DEVICES):
            raise self.PortAudioError(f"Error querying device {device}")
        d = dict(DEVICES[device])
        if kind is not None and d[f"max_{kind}_channels"] < 1:
            raise ValueError(f"Not an {kind} device: {d['name']!r}")
        return d

    def _check(self, device, channels, samplerate, what=""):
        if channels > DEVICES[device]["max_input_channels"]:
            raise self.PortAudioError(f"{what}Invalid number of channels [PaErrorCode -9998]")
        if samplerate not in (16000, 48000):
            raise self.PortAudioError(f"{what}Invalid sample rate [PaErrorCode -9997]")

    def check_input_settings(self, device=None, channels=None, dtype=None, extra_settings=None,
                             samplerate=None):
        self._check(device, channels, samplerate)

    def InputStream(self, device=None, channels=None, samplerate=None, blocksize=None,
                    dtype=None, callback=None):
        index = self.query_devices(device, "input")["name"]
        index = next(i for i, d in enumerate(DEVICES) if d["name"] == index)
        self.opened.append(index)
        self._check(index, channels, samplerate, "Error opening InputStream: ")
        if self.open_error is not None:
            raise self.PortAudioError(f"Error opening InputStream: {self.open_error}")
        return _Stream(self, channels, blocksize, callback)


class _Stream:
    def __init__(self, sd, channels, blocksize, callback):
        self.sd, self.channels, self.bs, self.cb = sd, channels, int(blocksize), callback
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._play, daemon=True)

    def _play(self):
        sd = self.sd
        rng = np.random.default_rng(0)
        k = 0
        while not self._stop.is_set() and k < 2000:  # (a test gone wrong ends: stalled)
            if k == sd.interrupt_at:
                time.sleep(0.3)  # the consumer has handled every block and waits for one
                _thread.interrupt_main()
            block = 0.1 * rng.standard_normal((self.bs, sd.deliver_channels or self.channels))
            self.cb(block.astype(np.float32), self.bs, None, _Flags(k in sd.overflow_at))
            k += 1
            time.sleep(self.bs / FS / sd.speed)

    def __enter__(self):
        if self.sd.start_error is not None:
            raise self.sd.PortAudioError(f"Error starting stream: {self.sd.start_error}")
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.sd.n_streams_closed += 1
        if self.sd.close_error is not None:
            raise self.sd.PortAudioError(f"Error stopping stream: {self.sd.close_error}")


@pytest.fixture
def fake_sd(monkeypatch):
    # Ctrl-C is _thread.interrupt_main(): it needs Python's SIGINT handler (a test runner
    # may have replaced it)
    old = signal.signal(signal.SIGINT, signal.default_int_handler)

    def install(**kw):
        sd = FakeSoundDevice(**kw)
        monkeypatch.setitem(sys.modules, "sounddevice", sd)
        return sd

    yield install
    signal.signal(signal.SIGINT, old)


#: A previous run's report folder (its index.html titled as hearsee's reports are, which a
#: new report may replace; report_foreign_file) and its JSON lines (a run's update records,
#: which a new run may replace; jsonl_foreign_file).
PREVIOUS = {"updates.jsonl": '{"t": 0.032, "phase": "listening", "note": "previous run"}\n',
            "summary.json": "previous summary.json",
            "index.html": "<title>hearsee report: previous</title> previous index.html"}


@pytest.fixture
def robot(tmp_path):
    """``robot(**audio)``: an audio-only robot file in tmp_path (the USB array's channels 1-3
    by default), its report folder holding a previous run's files."""
    prev = tmp_path / "report"
    prev.mkdir()
    for name, text in PREVIOUS.items():
        (prev / name).write_text(text, encoding="utf-8")

    def make(**audio):
        data = {"audio": {"device": "USB 6ch", "fs": FS, "array": "three-mic",
                          "channels": [1, 2, 3], **audio},
                "head": {"pivot_m": [0.0, 0.0, 1.2], "driver": "none"},
                "output": {"report": "report"}}
        p = tmp_path / "robot.yaml"
        p.write_text(yaml.safe_dump(data), encoding="utf-8")
        return p

    return make


def _untouched(cfg: Path) -> None:
    """The robot file and the previous run's report are as they were; nothing else was
    written."""
    folder = cfg.parent
    assert sorted(p.name for p in folder.iterdir()) == ["report", "robot.yaml"]
    assert yaml.safe_load(cfg.read_text(encoding="utf-8"))["audio"]["array"] == "three-mic"
    for name, text in PREVIOUS.items():
        assert (folder / "report" / name).read_text(encoding="utf-8") == text
    assert sorted(p.name for p in (folder / "report").iterdir()) == [
        "index.html", "summary.json", "updates.jsonl"]


def _one_line(capsys, code: int, want: str, *, stdout_empty: bool = True) -> str:
    """The command exited 2 with one line on stderr, ``hearsee: error: `` + ``want``..."""
    out = capsys.readouterr()
    assert code == 2, out.err
    lines = out.err.strip().splitlines()
    assert len(lines) == 1, out.err
    assert lines[0].startswith("hearsee: error: " + want), lines[0]
    if stdout_empty:
        assert out.out == ""
    return lines[0]


# ------------------------------------------------------------------- sounddevice missing
class _Refuse:
    """A meta-path finder that makes ``import sounddevice`` fail with ``exc``."""

    def __init__(self, exc):
        self.exc = exc

    def find_spec(self, name, path=None, target=None):
        if name == "sounddevice":
            raise self.exc
        return None


@pytest.mark.parametrize("exc", [ModuleNotFoundError("No module named 'sounddevice'"),
                                 OSError("PortAudio library not found")])
def test_missing_sounddevice_is_one_message_on_every_live_path(robot, monkeypatch, capsys,
                                                                exc):
    """Two importers said it two ways ('audio: the sounddevice package is not installed' /
    'audio: PortAudio library not found (apt-get install libportaudio2)' for `run`, 'live
    microphone input needs ...' for `track --device`); one importer now, one message naming
    the extra to install and the cause."""
    from hearsee.robot import hardware
    from hearsee.stream import device

    assert hardware.import_sounddevice is device.import_sounddevice
    monkeypatch.delitem(sys.modules, "sounddevice", raising=False)
    monkeypatch.setattr(sys, "meta_path", [_Refuse(exc), *sys.meta_path])
    cfg = robot()
    want = (f"live audio input needs the sounddevice package and the PortAudio library ({exc}):"
            " pip install 'hearsee[live]' (Debian/Ubuntu also: apt-get install libportaudio2)")
    for args in (["run", "--config", str(cfg), "--quiet"],
                 ["track", "--device", "0", "--array", "three-mic"]):
        line = _one_line(capsys, main(args), want)
        assert line == "hearsee: error: " + want
    main(["run", "--config", str(cfg), "--dry-run"])
    assert capsys.readouterr().err == "hearsee: error: " + want + "\n"
    _untouched(cfg)


# ------------------------------------------------------------------- the device
def test_a_device_name_of_non_ascii_digits_is_a_name(robot, fake_sd, capsys):
    """'²' (str.isdigit but not int()) raised a builtin ValueError in both readers of a
    device index; it is a name now (that no device has)."""
    fake_sd()
    cfg = robot(device="²")
    _one_line(capsys, main(["run", "--config", str(cfg), "--quiet"]),
              f"{cfg}: audio.device: no input device named '²' (available: ")
    for spec in ("²", "--1"):
        _one_line(capsys, main(["track", "--device", spec, "--array", "three-mic"]),
                  f"--device: no input device named {spec!r} (available: ")


@pytest.mark.parametrize("device, want", [
    ("ReSpeaker", "audio.device: no input device named 'ReSpeaker' (available: 0 'Built-in "
                  "Microphone' (2 in), 2 'USB 6ch Array' (6 in))"),
    (7, "audio.device: no device with index 7"),
    (1, "audio.device: device 1 'HDMI Output' has no input channels"),
])
def test_run_device_not_found_is_one_line(robot, fake_sd, capsys, device, want):
    fake_sd()
    cfg = robot(device=device)
    _one_line(capsys, main(["run", "--config", str(cfg), "--quiet"]), f"{cfg}: {want}")
    _untouched(cfg)


@pytest.mark.parametrize("device, want", [
    ("ReSpeaker", "--device: no input device named 'ReSpeaker' (available: 0 'Built-in "
                  "Microphone' (2 in), 2 'USB 6ch Array' (6 in))"),
    ("7", "--device: no device with index 7"),
    ("1", "--device: device 1 'HDMI Output' has no input channels"),
    ("-1", "--device: no device with index -1"),
])
def test_track_device_not_found_is_one_line(fake_sd, capsys, device, want):
    """The same messages as `run` (one function, stream.device.resolve_input_device); track
    said "audio input device 'ReSpeaker' not found or not an input (No input device matching
    'ReSpeaker'); available: ..." (PortAudio's wording in the parentheses)."""
    fake_sd()
    line = _one_line(capsys, main(["track", "--device", device, "--array", "three-mic"]),
                     want)
    assert line.endswith("(available: 0 'Built-in Microphone' (2 in), 2 'USB 6ch Array' (6 in))")


def test_run_and_track_list_the_devices_alike(robot, fake_sd, capsys):
    """Two listings of the same devices: `run` said ``0 'Built-in Microphone' (2 in), 2 'USB
    6ch Array' (6 in)`` and `track --device` ``0: Built-in Microphone (2 in); 2: USB 6ch Array
    (6 in)``; one function (stream.device.input_devices) now, one wording."""
    fake_sd()
    cfg = robot(device="ReSpeaker")
    run = _one_line(capsys, main(["run", "--config", str(cfg), "--quiet"]), str(cfg))
    track = _one_line(capsys, main(["track", "--device", "ReSpeaker", "--array", "three-mic"]),
                      "--device: no input device named 'ReSpeaker'")
    listing = "0 'Built-in Microphone' (2 in), 2 'USB 6ch Array' (6 in)"  # DEVICES' inputs
    assert run.endswith(f"(available: {listing})") and track.endswith(f"(available: {listing})")


def test_a_name_in_several_devices_is_refused_by_track_as_by_run(robot, fake_sd, capsys):
    """'r' is in 'Built-in Microphone' and 'USB 6ch Array': `run` refused it, `track
    --device` took the first device containing it (PortAudio's look-up); both refuse it now,
    in the same words."""
    fake_sd()
    want = ("'r' matches several input devices (0 'Built-in Microphone', 2 'USB 6ch Array'); "
            "use a longer name or the index")
    cfg = robot(device="r")
    _one_line(capsys, main(["run", "--config", str(cfg), "--quiet"]),
              f"{cfg}: audio.device: {want}")
    _one_line(capsys, main(["track", "--device", "r", "--array", "three-mic"]),
              f"--device: {want}")


def test_an_exact_name_picks_that_device_in_track_as_in_run(robot, fake_sd, capsys,
                                                            monkeypatch):
    """'USB 6ch Array' is the name of device 1 and part of device 0's: `run` took the exact
    name (device 1), `track --device` the first device containing it (device 0); both open
    device 1 now."""
    monkeypatch.setattr(sys.modules[__name__], "DEVICES", [
        {"name": "USB 6ch Array (backup)", "max_input_channels": 6, "max_output_channels": 0},
        {"name": "USB 6ch Array", "max_input_channels": 6, "max_output_channels": 0}])
    sd = fake_sd()
    cfg = robot(device="usb 6ch array")
    assert main(["run", "--config", str(cfg), "--quiet", "--duration", "0.2"]) == 0, \
        capsys.readouterr().err
    assert main(["track", "--device", "USB 6ch Array", "--array", "three-mic",
                 "--duration", "0.2"]) == 0, capsys.readouterr().err
    assert sd.opened == [1, 1]


def test_track_json_names_the_device_it_opened(fake_sd, capsys):
    """`track --device 2 --format json` gave "source": "2" (the spec typed); it is the name
    of the device opened now."""
    fake_sd()
    for spec in ("2", "6ch"):
        assert main(["track", "--device", spec, "--array", "three-mic", "--duration", "0.2",
                     "--format", "json"]) == 0, capsys.readouterr().err
        assert json.loads(capsys.readouterr().out)["source"] == "USB 6ch Array"


def test_too_few_input_channels_is_one_line(robot, fake_sd, capsys):
    fake_sd()
    cfg = robot(channels=[1, 2, 6])  # channel 6 of a 6-channel device
    _one_line(capsys, main(["run", "--config", str(cfg), "--quiet"]),
              f"{cfg}: audio.channels: device 2 'USB 6ch Array' has 6 input channels; the array "
              "needs 7")
    cfg = robot(device="Built-in", channels=None)
    _one_line(capsys, main(["run", "--config", str(cfg), "--quiet"]),
              f"{cfg}: audio.device: device 0 'Built-in Microphone' has 2 input channels; the "
              "array needs 3")
    _untouched(cfg)
    _one_line(capsys, main(["track", "--device", "0", "--array", "three-mic"]),
              "device 'Built-in Microphone' has 2 input channels; the array needs 3")


def test_sample_rate_the_device_refuses_is_one_line(robot, fake_sd, capsys):
    """`track --device 2 --fs 22050`: PortAudio refuses the rate when the stream opens, in the
    source's thread -- its PortAudioError came out of the CLI as a traceback."""
    fake_sd()
    cfg = robot(fs=22050)
    _one_line(capsys, main(["run", "--config", str(cfg), "--quiet"]),
              f"{cfg}: audio.fs: device 2 'USB 6ch Array' does not accept 4 channels at 22050 Hz "
              "(Invalid sample rate [PaErrorCode -9997])")
    _untouched(cfg)
    _one_line(capsys, main(["track", "--device", "2", "--array", "three-mic", "--fs", "22050"]),
              "audio input device 'USB 6ch Array': cannot record 3 channels at 22050 Hz (Error "
              "opening InputStream: Invalid sample rate [PaErrorCode -9997])")


@pytest.mark.parametrize("where", ["open", "start"])
def test_portaudio_error_at_stream_start_is_one_line(robot, fake_sd, capsys, where):
    """A device another program holds passes the settings check and fails when the stream
    opens or starts: a PortAudioError traceback from `run` and `track --device`."""
    sd = fake_sd(**{f"{where}_error": "Device unavailable [PaErrorCode -9985]"})
    cause = ("Error opening InputStream: " if where == "open" else "Error starting stream: ") \
        + "Device unavailable [PaErrorCode -9985]"
    cfg = robot()
    _one_line(capsys, main(["run", "--config", str(cfg), "--quiet"]),
              f"audio input device 'USB 6ch Array': cannot record 4 channels at 16000 Hz "
              f"({cause})")
    assert not (cfg.parent / "report" / "log.json").exists()  # no report of a run that wasn't
    _one_line(capsys, main(["track", "--device", "USB", "--array", "three-mic"]),
              f"audio input device 'USB 6ch Array': cannot record 3 channels at 16000 Hz "
              f"({cause})")
    assert sd.n_streams_closed == 0  # (none was started)


def test_a_device_that_fails_when_its_stream_starts_keeps_the_previous_run(robot, fake_sd,
                                                                           capsys):
    """`run` emptied output.jsonl before the stream started: a busy device then left the
    previous run's updates.jsonl empty beside its report (summary.json, index.html)."""
    fake_sd(start_error="Device unavailable [PaErrorCode -9985]")
    cfg = robot()
    _one_line(capsys, main(["run", "--config", str(cfg), "--quiet"]),
              "audio input device 'USB 6ch Array': cannot record 4 channels at 16000 Hz")
    _untouched(cfg)


# ------------------------------------------------------------------- the stream
def test_blocks_of_another_shape_are_one_line(robot, fake_sd, capsys):
    """A device delivering 2 channels where 4 were opened: `run` picked the robot's channels
    out of the block with numpy indexing (an IndexError traceback)."""
    sd = fake_sd(deliver_channels=2)
    cfg = robot()
    _one_line(capsys, main(["run", "--config", str(cfg), "--quiet"]),
              "block has shape (2, 1600); expected 4 channels")
    _one_line(capsys, main(["track", "--device", "2", "--array", "three-mic"]),
              "block has shape (2, 1024); expected 3 channels")
    assert sd.n_streams_closed == 2  # each stream was closed


def test_input_overflow_is_counted_and_the_run_goes_on(robot, fake_sd, capsys):
    """PortAudio discarding input (status.input_overflow) is no error: the block after it is
    placed after a gap of one block, whose frames are reported missing."""
    fake_sd(overflow_at={3})
    cfg = robot()
    assert main(["run", "--config", str(cfg), "--quiet", "--duration", "1.0"]) == 0, \
        capsys.readouterr().err
    assert "Traceback" not in capsys.readouterr().err
    summary = json.loads((cfg.parent / "report" / "summary.json").read_text(encoding="utf-8"))
    assert summary["status"] == "ok" and summary["dropped_blocks"] == 1
    # the frames touching the lost samples [4800, 6400): those starting at 4096 ... 6144
    assert summary["missing_frames"] == 5 and summary["audio_s"] == 1.0
    assert main(["track", "--device", "2", "--array", "three-mic", "--duration", "1",
                 "--stats"]) == 0
    out = capsys.readouterr()
    assert "1 dropped / 0 late blocks, 1 input overflows, status ok" in " ".join(out.err.split())
    recs = [json.loads(s) for s in out.out.splitlines()]
    # blocks of 1024: the frames touching the lost samples [3072, 4096) start at 2560 ... 3584
    # (the device's last block is cut at --duration: 1 s, as `run`'s)
    assert sum(r["missing"] for r in recs) == 3 and len(recs) == (16000 - 1024) // 512 + 1


def test_run_reports_input_overflows_as_track_does(robot, fake_sd, capsys):
    """The stream counts the callbacks PortAudio flagged ``input_overflow``
    (StreamStats.n_overflows) and `track` reports them; `run`'s summary (and so its report
    and summary table) had only the dropped blocks."""
    fake_sd(overflow_at={3, 7})
    cfg = robot()
    assert main(["run", "--config", str(cfg), "--duration", "1.0"]) == 0
    err = capsys.readouterr().err
    assert "input_overflows" in err  # the summary table
    report = cfg.parent / "report"
    summary = json.loads((report / "summary.json").read_text(encoding="utf-8"))
    assert summary["input_overflows"] == 2 and summary["dropped_blocks"] == 2
    assert "<tr><td>input_overflows</td><td>2</td></tr>" in (
        report / "index.html").read_text(encoding="utf-8")


def test_ctrl_c_ends_a_live_run_cleanly(robot, fake_sd, capsys):
    """Ctrl-C (no --duration) ends `hearsee run` with its report and JSON lines; the report
    counted no dropped block where the device had dropped one (the stream's stats were only
    filled in when the run ended normally)."""
    fake_sd(overflow_at={2}, interrupt_at=12)
    cfg = robot()
    code = main(["run", "--config", str(cfg), "--quiet"])
    err = capsys.readouterr().err
    assert code == 0 and "Traceback" not in err, err
    report = cfg.parent / "report"
    summary = json.loads((report / "summary.json").read_text(encoding="utf-8"))
    assert summary["status"] == "interrupted" and summary["dropped_blocks"] == 1
    lines = (report / "updates.jsonl").read_text(encoding="utf-8").splitlines()
    log = json.loads((report / "log.json").read_text(encoding="utf-8"))
    assert [json.loads(s) for s in lines] == log and len(log) == summary["updates"] > 20
    # 12 blocks of 1600 samples before Ctrl-C and the one lost before the third: 20800
    # samples, frames of 1024 every 512 samples (the last one centred at 19456 + 512)
    n = 13 * 1600
    assert summary["audio_s"] == n / FS
    assert len(log) == (n - 1024) // 512 + 1 and log[-1]["t"] == (19456 + 512) / FS
    # the frames that touch the lost samples [3200, 4800): those starting at 2560 ... 4608
    assert summary["missing_frames"] == 5


_HOST_ERROR = "Unanticipated host error [PaErrorCode -9999]"


def test_portaudio_error_when_the_stream_stops_is_one_line(robot, fake_sd, capsys, unraisable):
    """The stream's stop/close failing at the end of the run (--duration reached): `track`
    died with a PortAudioError traceback; `run` printed "Exception ignored in" with one when
    the device's generator was collected and went on as if nothing happened."""
    sd = fake_sd(close_error=_HOST_ERROR)
    cfg = robot()
    want = ("audio input device 'USB 6ch Array': cannot stop the input stream (Error stopping "
            f"stream: {_HOST_ERROR})")
    line = _one_line(capsys, main(["run", "--config", str(cfg), "--quiet", "--duration", "1"]),
                     want)
    assert line == "hearsee: error: " + want
    assert not (cfg.parent / "report" / "log.json").exists()  # no report of a failed run
    line = _one_line(capsys, main(["track", "--device", "2", "--array", "three-mic",
                                   "--duration", "1"]), want, stdout_empty=False)
    assert line == "hearsee: error: " + want  # (the updates were printed as they came)
    assert sd.n_streams_closed == 2
    gc.collect()
    assert unraisable == []


def test_ctrl_c_stays_the_reason_when_the_stream_then_fails_to_stop(robot, fake_sd, capsys,
                                                                     unraisable):
    """Ctrl-C ends the run; the stream failing to stop afterwards changes nothing (it was
    printed as "Exception ignored in", from the source's thread)."""
    fake_sd(interrupt_at=12, close_error=_HOST_ERROR)
    cfg = robot()
    code = main(["run", "--config", str(cfg), "--quiet"])
    err = capsys.readouterr().err
    assert code == 0 and "Traceback" not in err and "Exception ignored" not in err, err
    summary = json.loads((cfg.parent / "report" / "summary.json").read_text(encoding="utf-8"))
    assert summary["status"] == "interrupted"
    gc.collect()
    assert unraisable == []


@pytest.mark.parametrize("fmt", ["json", "jsonl"])
def test_ctrl_c_ends_live_track_cleanly(fake_sd, capsys, fmt):
    """`track --device` runs until Ctrl-C without --duration: the updates so far and the stats
    are reported (--format json printed nothing at all, and the exit was 130)."""
    fake_sd(overflow_at={2}, interrupt_at=16)
    code = main(["track", "--device", "2", "--array", "three-mic", "--format", fmt])
    out = capsys.readouterr()
    assert code == 0 and "Traceback" not in out.err, out.err
    assert "1 dropped / 0 late blocks, 1 input overflows, status interrupted" in " ".join(
        out.err.split())
    if fmt == "json":
        doc = json.loads(out.out)
        ups, stats = doc["updates"], doc["stats"]
        assert stats["status"] == "interrupted" and stats["dropped_blocks"] == 1
        assert stats["frames"] == len(ups) and stats["audio_s"] == 17 * 1024 / FS
    else:
        ups = [json.loads(s) for s in out.out.splitlines()]
    # 16 blocks of 1024 samples before Ctrl-C and the one lost before the third: frames of
    # 1024 every 512 samples
    assert len(ups) == (17 * 1024 - 1024) // 512 + 1
    # the frames touching the samples lost before the third block, [2048, 3072)
    assert [u["t"] for u in ups if u["missing"]] == [(s + 512) / FS for s in (1536, 2048, 2560)]


def test_track_device_channels_pick_the_microphones(fake_sd, capsys):
    """`track --device 2 --channels 1,2,3`: the 6-channel device opened for its channels 0-3,
    the stream fed channels 1-3 (as the robot file's audio.channels); a channel beyond the
    device, or too few channels for the array, is one line."""
    sd = fake_sd(deliver_channels=4)
    assert main(["track", "--device", "2", "--array", "three-mic", "--channels", "1,2,3",
                 "--duration", "0.2", "--format", "json"]) == 0, capsys.readouterr().err
    doc = json.loads(capsys.readouterr().out)
    assert doc["source"] == "USB 6ch Array" and doc["stats"]["status"] == "ok"
    assert doc["stats"]["microphones_used"] == [0, 1, 2] and doc["stats"]["frames"] > 0
    assert sd.opened == [2]
    _one_line(capsys, main(["track", "--device", "2", "--array", "three-mic", "--channels",
                            "1,2,7"]),
              "device 'USB 6ch Array' has 6 input channels; channel 7 asked for")
    _one_line(capsys, main(["track", "--device", "2", "--array", "three-mic", "--channels",
                            "1,2"]), "--channels: 2 channels for an array of 3 microphones")
    # a band with a device (the recording's name was asked for and there is none: exit 2)
    assert main(["track", "--device", "2", "--array", "three-mic", "--channels", "1,2,3",
                 "--band-hz", "300,3000", "--duration", "0.2"]) == 0, capsys.readouterr().err
    fake_sd()  # (a device delivering the channels opened)
    assert main(["track", "--device", "2", "--array", "three-mic", "--band-hz", "300,3000",
                 "--duration", "0.2"]) == 0, capsys.readouterr().err


def test_live_track_with_several_talkers(fake_sd, capsys):
    """`track --device 2 --channels 1,2,3 --sources 2`: live input runs with the several
    talkers' tracker; every update carries its "sources" (the fake's noise: a list, maybe
    empty); a masked pair is refused before the device is opened."""
    sd = fake_sd(deliver_channels=4)
    assert main(["track", "--device", "2", "--array", "three-mic", "--channels", "1,2,3",
                 "--sources", "2", "--duration", "0.2", "--format", "json"]) == 0, \
        capsys.readouterr().err
    doc = json.loads(capsys.readouterr().out)
    assert doc["stats"]["status"] == "ok" and doc["updates"]
    assert all(isinstance(u["sources"], list) and len(u["sources"]) <= 2
               for u in doc["updates"])
    n_opened = len(sd.opened)
    _one_line(capsys, main(["track", "--device", "0", "--array", "mask2-asym", "--sources",
                            "2", "--duration", "0.2"]), "--sources: the masked pair")
    assert len(sd.opened) == n_opened
