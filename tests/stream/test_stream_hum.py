"""Mains hum in a stream: notched out of every block (hearsee.audio.hum.LineFilter), given
ahead (``tonal_lines_hz``, as `hearsee track` finds it in a file) or found by the live input's
check."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
import scipy.signal as ss

from hearsee.audio import hum
from hearsee.audio.signals import write_recording
from hearsee.cli import main
from hearsee.errors import ConfigError
from hearsee.sim.audio import simulate_recording
from hearsee.stream.pipeline import ArraySource, StreamPipeline

FS = 16000
HUM = 60.0 * np.arange(1, 42)  # the hum's harmonics, Hz


@pytest.fixture(scope="module")
def voice_and_buzz():
    """A male voice 2 m away at azimuth 56 deg (three-mic, free field, 20 dB SNR, 6 s), the
    same with a 60-Hz hum (41 harmonics, one waveform on every channel) 3 dB louder, and the
    true azimuth."""
    src = 2.0 * np.array([np.cos(np.radians(56.0)), np.sin(np.radians(56.0)), 0.3])
    kw = {"signal": "male", "duration_s": 6.0, "fs": FS, "snr_db": 20, "seed": 3}
    x, truth = simulate_recording("three-mic", src, **kw)
    y, _ = simulate_recording("three-mic", src, hum_db=3.0, hum_hz=60.0, **kw)
    return x, y, truth["azimuth_deg"]


def _median_error(updates, az: float, after_s: float = 0.0) -> float:
    a = np.array([u.azimuth_deg for u in updates
                  if u.measured and u.azimuth_deg is not None and u.t > after_s])
    assert a.size > 20
    return float(np.median(np.abs((a - az + 180.0) % 360.0 - 180.0)))


def test_line_filter_does_not_depend_on_the_blocks():
    """Blocks of 100, 1, 2047 and the rest give the samples of one pass (the notches' state
    carries over), in the blocks' float32; bad line frequencies are a ConfigError."""
    x = np.random.default_rng(15).standard_normal((2, 8000)).astype(np.float32)
    f = hum.LineFilter([50.0, 150.0], FS, 2)
    parts = [f(x[:, a:b]) for a, b in ((0, 100), (100, 101), (101, 2148), (2148, 8000))]
    assert all(p.dtype == np.float32 for p in parts)
    sos = np.vstack([ss.tf2sos(*ss.iirnotch(v, v / hum.NOTCH_BANDWIDTH_HZ, FS))
                     for v in (50.0, 150.0)])
    np.testing.assert_allclose(np.concatenate(parts, axis=1), ss.sosfilt(sos, x, axis=-1),
                               atol=1e-5)
    for bad in ([50.0, -1.0], [float("nan")], "hum", [[50.0]]):
        with pytest.raises(ConfigError, match="line frequencies"):
            hum.LineFilter(bad, FS, 2)
    with pytest.raises(ConfigError, match="line frequencies"):
        StreamPipeline("three-mic", tonal_lines_hz=[0.0])


def test_a_stream_with_the_hum_given_notches_it_out(voice_and_buzz):
    """The buzz made the stream's directions follow it (median error > 20 deg); with its lines
    given, the median error is that of the voice alone (< 1 deg), and the stats say so."""
    x, y, az = voice_and_buzz
    assert _median_error(StreamPipeline("three-mic").run(ArraySource(x, FS, 1024)), az) < 1.0
    assert _median_error(StreamPipeline("three-mic").run(ArraySource(y, FS, 1024)), az) > 20.0
    pipe = StreamPipeline("three-mic", tonal_lines_hz=HUM)
    assert _median_error(pipe.run(ArraySource(y, FS, 1024)), az) < 1.0
    assert pipe.stats.tonal_lines_hz == tuple(HUM)


def test_a_live_stream_notches_the_hum_its_check_finds(voice_and_buzz):
    """Live input's first HUM_CHECK_S (3) seconds are looked at for hum: one warning, and the
    stream notches it from then on -- after 4 s the directions are the voice's (< 1 deg; they
    stayed ~60 deg off until the 10-s wiring check, which alone looked before); a clean input
    gets no filter and no warning."""
    x, y, az = voice_and_buzz
    for rec, found in ((y, True), (x, False)):
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            pipe = StreamPipeline("three-mic", check_wiring=True)
            ups = pipe.run(ArraySource(rec, FS, 1024))
        assert sum("tonal noise" in str(w.message) for w in got) == int(found)
        lines = np.array(pipe.stats.tonal_lines_hz)
        assert (lines.size >= 30 and abs(lines[0] - 60.0) < 0.1) if found else lines.size == 0
        assert _median_error(ups, az, after_s=4.0) < 1.0


def test_track_finds_a_files_hum_ahead_and_streams_without_it(voice_and_buzz, tmp_path, capsys):
    """`hearsee track` of the buzzed file: one warning line, the stats list the lines, and
    the directions are the voice's."""
    _, y, az = voice_and_buzz
    wav = tmp_path / "hum.wav"
    write_recording(wav, 0.5 * y / np.abs(y).max(), FS)
    assert main(["track", str(wav), "--array", "three-mic", "--format", "json"]) == 0
    out, err = capsys.readouterr()
    assert err.count("hearsee: warning: stationary tonal noise on every microphone at 60.0 Hz"
                     ) == 1
    doc = json.loads(out)
    assert len(doc["stats"]["tonal_lines_hz"]) >= 30
    a = np.array([u["azimuth_deg"] for u in doc["updates"] if u["azimuth_deg"] is not None])
    assert a.size > 20 and np.median(np.abs((a - az + 180) % 360 - 180)) < 1.5
