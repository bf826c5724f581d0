import csv
import io
import json
import warnings

import numpy as np
import pytest
import soundfile as sf

from hearsee.audio.arrays import MicArray
from hearsee.audio.propagation import simulate_free_field
from hearsee.audio.signals import white_noise
from hearsee.audio.tdoa import estimate_tdoas
from hearsee.cli import main
from hearsee.geometry import unit_vector_deg, wrap_deg

FS = 16000


@pytest.fixture(scope="module")
def rec3(tmp_path_factory):
    arr = MicArray.from_preset("three-mic")
    src = 2.0 * unit_vector_deg(-120.0, 0.0)
    s = white_noise(0.8, FS, rng=1)
    s[int(0.5 * FS):] = 0.0  # the last 0.3 s: sensor noise only
    x = simulate_free_field(s, FS, arr, src, snr_db=25, rng=2)
    path = tmp_path_factory.mktemp("rec") / "three.wav"
    sf.write(path, (x / np.abs(x).max() * 0.5).T, FS, subtype="FLOAT")
    return path


def _run(capsys, *args):
    code = main(["localize", *map(str, args)])
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def test_json_contract(rec3, capsys):
    code, out, _ = _run(capsys, rec3, "--array", "three-mic", "--format", "json")
    assert code == 0
    doc = json.loads(out)
    assert doc["array"]["name"] == "three-mic" and doc["sample_rate"] == FS
    assert set(doc) >= {"array", "sample_rate", "frames", "summary"}
    f = doc["frames"][4]
    assert set(f) >= {"t", "tdoa_s", "azimuth_deg", "elevation_deg", "candidates", "confidence"}
    assert set(f["tdoa_s"]) == {"0-1", "0-2", "1-2"}
    assert f["azimuth_deg"] == pytest.approx(-120.0, abs=3.0)
    assert len(f["candidates"]) in (1, 2)
    assert {"azimuth_deg", "elevation_deg"} == set(f["candidates"][0])
    # frames after the source stopped: no estimate, nulls
    late = [g for g in doc["frames"] if g["t"] > 0.6]
    assert late and all(g["azimuth_deg"] is None and g["tdoa_s"]["0-1"] is None for g in late)
    s = doc["summary"]
    assert s["azimuth_deg"] == pytest.approx(-120.0, abs=2.0)
    assert set(s["tdoa_s"]) == {"0-1", "0-2", "1-2"} and s["candidates"]


def test_two_mic_elevation_null_and_twins(tmp_path, capsys):
    arr = MicArray.from_preset("two-mic")
    x = simulate_free_field(white_noise(0.5, FS, rng=3), FS, arr, 2.0 * unit_vector_deg(40, 0),
                            snr_db=25, rng=4)
    p = tmp_path / "two.wav"
    sf.write(p, (0.3 * x / np.abs(x).max()).T, FS, subtype="FLOAT")
    code, out, _ = _run(capsys, p, "--array", "two-mic", "--method", "gcc-scot", "--no-kalman")
    assert code == 0
    s = json.loads(out)["summary"]
    assert s["elevation_deg"] is None
    azs = sorted(c["azimuth_deg"] for c in s["candidates"])
    assert azs == pytest.approx([40.0, 140.0], abs=2.0)
    # the CSV's one null is an empty cell, in the candidates too ("40.00/-" until 2026-12-03)
    code, out, _ = _run(capsys, p, "--array", "two-mic", "--method", "gcc-scot", "--no-kalman",
                        "--format", "csv")
    rows = list(csv.DictReader(io.StringIO(out)))
    assert code == 0 and rows
    for r in rows:
        assert r["elevation_deg"] == ""
        pairs = [c.split("/") for c in r["candidates"].split(";")]
        assert [el for _, el in pairs] == ["", ""]
        assert sorted(float(az) for az, _ in pairs) == pytest.approx([40.0, 140.0], abs=3.0)


@pytest.mark.parametrize("fmt", ["csv", "table"])
def test_other_formats(rec3, capsys, fmt):
    code, out, _ = _run(capsys, rec3, "--array", "three-mic", "--format", fmt)
    assert code == 0
    if fmt == "csv":
        lines = out.strip().splitlines()
        assert lines[0].startswith("t_s,tdoa_0-1_s,tdoa_0-2_s,tdoa_1-2_s,azimuth_deg")
        assert len(lines) > 10
    else:
        assert "summary: azimuth" in out
        # (rich read "[s]", "[us]" and "[deg]" as style tags: the header had no units)
        assert "t [s]" in out and "tdoa 0-1 [us]" in out and "azimuth [deg]" in out


@pytest.mark.parametrize("name", ["respeaker[v2]", "x[/b]"])
def test_table_title_keeps_an_array_name_in_brackets(rec3, tmp_path, capsys, name):
    # the array's own name in the title: rich read "[v2]" as a style tag (titled "respeaker")
    # and "[/b]" as a closing tag with nothing open (MarkupError, a traceback)
    yml = tmp_path / "rig.yaml"
    pos = MicArray.from_preset("three-mic").positions.tolist()
    yml.write_text(f'name: "{name}"\nmicrophones: {pos}\n')
    code, out, _ = _run(capsys, rec3, "--array", yml, "--format", "table")
    assert code == 0
    assert f"hearsee localize ({name}, phat)" in out


def test_csv_times_are_those_of_the_json(rec3, capsys):
    """The CSV's t_s was written to 0.1 ms: with a hop of one sample (0.0625 ms at 16 kHz)
    frames at 32.0625 and 32.125 ms were both 0.0321."""
    args = ("--array", "three-mic", "--hop-ms", "0.0625", "--no-kalman")
    code, out, _ = _run(capsys, rec3, *args, "--format", "csv")
    assert code == 0
    got = [float(r["t_s"]) for r in csv.DictReader(io.StringIO(out))]
    code, out, _ = _run(capsys, rec3, *args, "--format", "json")
    want = [f["t"] for f in json.loads(out)["frames"]]
    assert len(got) == len(want) and len(set(got)) == len(got)
    np.testing.assert_allclose(got, want, rtol=0, atol=6e-7)  # (to the microsecond)


def _bad(tmp_path, name, data, fs=FS, subtype="FLOAT"):
    p = tmp_path / name
    sf.write(p, data, fs, subtype=subtype)
    return p


def test_bad_inputs_one_line_exit_2(rec3, tmp_path, capsys):
    rng = np.random.default_rng(0)
    nan = rng.standard_normal((FS, 3)) * 0.1
    nan[100, 1] = np.nan
    yaml_bad = tmp_path / "bad.yaml"
    yaml_bad.write_text("microphones: [[0, 0, 0], [0, 0\n")
    yaml_coinc = tmp_path / "coinc.yaml"
    yaml_coinc.write_text("microphones: [[0, 0, 0], [0, 0, 0]]\n")
    text = tmp_path / "notes.wav"
    text.write_text("this is not audio")
    cases = [
        ([rec3, "--array", "two-mic"], "channel"),  # wrong channel count
        ([_bad(tmp_path, "nan.wav", nan), "--array", "three-mic"], "NaN"),
        ([_bad(tmp_path, "zero.wav", np.zeros((FS, 3))), "--array", "three-mic"], "silent"),
        ([_bad(tmp_path, "short.wav", rng.standard_normal((300, 3)) * 0.1), "--array",
          "three-mic"], "short"),
        ([_bad(tmp_path, "lowfs.wav", rng.standard_normal((800, 3)) * 0.1, fs=400), "--array",
          "three-mic"], ""),  # sample rate too low for one frame vs the array's delays
        ([text, "--array", "three-mic"], ""),
        ([tmp_path / "missing.wav", "--array", "three-mic"], "missing.wav"),
        ([rec3, "--array", str(yaml_bad)], "YAML"),
        ([rec3, "--array", str(yaml_coinc)], "coincide"),
        ([rec3, "--array", "no-such-preset"], "preset"),
        ([rec3, "--array", "three-mic", "--frame-ms", "0.2"], "frame"),
        ([rec3, "--array", "three-mic", "--frame-ms", "inf"], "at most 10000 ms, got inf"),
        ([rec3, "--array", "three-mic", "--tdoa-std-us", "3"], "'three-mic' does not get"),
    ]
    for args, needle in cases:
        code, out, err = _run(capsys, *args)
        assert code == 2, (args, err)
        assert err.startswith("hearsee: error:") and err.count("\n") == 1, err
        assert needle in err, (needle, err)
        assert "Traceback" not in err and out == ""


def test_a_ragged_list_in_the_array_file_is_one_line_exit_2(rec3, tmp_path, capsys):
    """A microphone [0.1, [0, 0]] or a speed of sound [1, [2, 3]] in the array YAML was a
    builtin ValueError traceback (numpy's, from config.is_real)."""
    mics = "[[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]"
    for text, needle in ((f"microphones: [[0.1, [0, 0]], {mics[1:]}\n", "microphones"),
                         (f"speed_of_sound: [1, [2, 3]]\nmicrophones: {mics}\n",
                          "speed_of_sound")):
        path = tmp_path / "ragged.yaml"
        path.write_text(text)
        code, out, err = _run(capsys, rec3, "--array", path)
        assert code == 2 and out == ""
        assert err.startswith("hearsee: error: ") and err.count("\n") == 1, err
        assert f"ragged.yaml: {needle}" in err


def test_bad_method_is_usage_error(rec3, capsys):
    code, _, err = _run(capsys, rec3, "--array", "three-mic", "--method", "music")
    assert code == 2 and "Traceback" not in err


def test_clipped_recording_warns_but_works(tmp_path, capsys):
    arr = MicArray.from_preset("three-mic")
    x = simulate_free_field(white_noise(0.5, FS, rng=5), FS, arr, [1.0, 1.0, 0.0], snr_db=25,
                            rng=6)
    x = np.clip(3.0 * x / np.abs(x).max(), -1.0, 1.0)
    p = _bad(tmp_path, "clip.wav", x.T, subtype="PCM_16")
    code = main(["localize", str(p), "--array", "three-mic"])
    assert code == 0
    out, err = capsys.readouterr()
    # one line, no Python warning chrome (file:line, the source line of the call)
    assert err.startswith(f"hearsee: warning: {p}: ") and "clipped" in err
    assert err.count("\n") == 1 and ".py:" not in err
    az = json.loads(out)["summary"]["azimuth_deg"]
    assert az == pytest.approx(45.0, abs=2.0)  # the source at [1, 1, 0]


def test_in_plane_and_reverb_method_options(rec3, capsys):
    code, out, _ = _run(capsys, rec3, "--array", "three-mic", "--method", "gcc-ml",
                        "--reverb-method", "gcc-phat", "--in-plane", "--format", "json")
    assert code == 0
    s = json.loads(out)["summary"]
    # free field: the coherence is what the noise explains, the ML summary is kept
    assert s["coherence_ratio"] > 0.9 and s["method"] == "ml"
    assert s["coherence_gain"] is None  # only measured without a noise reference
    assert s["azimuth_deg"] == pytest.approx(-120.0, abs=1.0)
    assert len(s["candidates"]) == 1 and s["elevation_deg"] == pytest.approx(0.0, abs=1e-6)
    code, _, err = _run(capsys, rec3, "--array", "three-mic", "--reverb-method", "bogus")
    assert code == 2 and "Traceback" not in err


def test_summary_tuned_is_the_benchmarked_summary(tmp_path, capsys):
    """--summary-tuned --in-plane runs bench/doa.py's benchmarked whole-recording estimate
    (hearsee.audio.tdoa.SUMMARY_TUNED): a voice 2 m away in a reverberant room (RT60 0.6 s),
    whose truth the test places; the document's summary is the library's, and frames after the
    voice stopped still give no estimate."""
    from hearsee.audio.localize import localize_recording
    from hearsee.audio.propagation import add_noise, room_impulse_responses
    from hearsee.audio.signals import synthetic_voice
    from hearsee.audio.tdoa import SUMMARY_TUNED

    arr = MicArray.from_preset("three-mic")
    at = np.array([3.5, 3.0, 1.2])
    src = 2.0 * unit_vector_deg(130.0, 0.0)
    h = room_impulse_responses(FS, arr.positions + at, src + at, np.array([8.0, 7.0, 3.0]), 0.6,
                               speed_of_sound=arr.speed_of_sound)
    rng = np.random.default_rng(5)
    s = synthetic_voice("male", 1.5, FS, rng)
    s[int(1.2 * FS):] = 0.0  # the last 0.3 s: sensor noise only
    x = add_noise(np.array([np.convolve(s, hh)[: len(s)] for hh in h]), 20, rng)
    x = (0.5 * x / np.abs(x).max()).astype(np.float32)
    p = tmp_path / "room.wav"
    sf.write(p, x.T, FS, subtype="FLOAT")
    code, out, _ = _run(capsys, p, "--array", "three-mic", "--summary-tuned", "--in-plane")
    assert code == 0
    doc = json.loads(out)
    ref = localize_recording(x.astype(float), FS, arr, in_plane=True, **SUMMARY_TUNED)
    assert doc["method"] == "ml" and doc["summary"]["tdoa_s"] == ref["summary"]["tdoa_s"]
    assert doc["summary"]["azimuth_deg"] == pytest.approx(130.0, abs=3.0)
    late = [g for g in doc["frames"] if g["t"] > 1.35]
    assert late and all(g["azimuth_deg"] is None for g in late)
    # it sets the weightings itself: giving them too is a one-line usage error
    for extra in (["--method", "gcc-phat"], ["--reverb-method", "gcc-roth"]):
        code, out, err = _run(capsys, p, "--array", "three-mic", "--summary-tuned", *extra)
        assert code == 2 and out == "" and err.count("\n") == 1
        assert f"--summary-tuned sets {extra[0]} itself" in err
        assert err.rstrip().endswith("leave it out")
    # a masked pair (ch. 3) runs its own pipeline, which takes none of these settings
    code, out, err = _run(capsys, p, "--array", "mask2-asym", "--summary-tuned")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "--summary-tuned: the masked array 'mask2-asym'" in err


def test_in_plane_is_refused_for_a_masked_array(tmp_path, capsys):
    """--in-plane with a masked pair (ch. 3) was dropped without a word: the mask's pipeline
    has no in-plane model, and the output was byte for byte that without it. It is now a
    one-line usage error, before the recording is read (the file here does not exist)."""
    code, out, err = _run(capsys, tmp_path / "none.wav", "--array", "mask2-asym", "--in-plane")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "--in-plane: the masked array 'mask2-asym'" in err and "leave it out" in err


def test_the_itd_filter_follows_a_moving_white_noise_source(tmp_path, capsys):
    """White noise circling the three-mic array at 90 deg/s (free field, 20 dB): its frames
    err by ~1 us, and the fixed ITD filter (the default until 2026-12-04) lagged them by ~10
    us. The default now scales each frame's measurement noise by its GCC confidence and
    chooses the random walk from the frames, at most the ITD change per frame of a 90 deg/s
    turn; --kalman-tuned chooses both noises from a grid. Both stay near the frames' error,
    and the JSON says what was used."""
    from hearsee.sim.moving import Trajectory, retarded_delays, simulate_moving_free_field

    arr = MicArray.from_preset("three-mic")
    t = np.linspace(0.0, 2.0, 101)
    az = np.radians(30.0 + 90.0 * t)
    traj = Trajectory(t, 1.5 * np.stack([np.cos(az), np.sin(az), 0.0 * t], axis=1))
    x = simulate_moving_free_field(white_noise(2.0, FS, rng=7), FS, arr, traj, snr_db=20, rng=8)
    p = tmp_path / "moving.wav"
    sf.write(p, (0.5 * x / np.abs(x).max()).T, FS, subtype="FLOAT")
    errs = {}
    cap = 0.15 / arr.speed_of_sound * np.radians(90.0) * 0.032  # (15 cm sides, 32 ms hop)
    for extra in ([], ["--kalman-tuned"], ["--no-kalman"]):
        code, out, _ = _run(capsys, p, "--array", "three-mic", *extra)
        assert code == 0
        doc = json.loads(out)
        tt = np.array([f["t"] for f in doc["frames"]])
        tau, _ = retarded_delays(traj, arr.positions, tt, arr.speed_of_sound)
        got = np.array([[f["tdoa_s"][k] if f["tdoa_s"][k] is not None else np.nan
                         for k in ("0-1", "0-2", "1-2")] for f in doc["frames"]])
        truth = np.stack([tau[0] - tau[1], tau[0] - tau[2], tau[1] - tau[2]], axis=1)
        ok = np.isfinite(got).all(axis=1)
        assert ok.sum() > 0.8 * len(ok)
        errs[tuple(extra)] = float(np.sqrt(np.mean((got[ok] - truth[ok]) ** 2)))
        if extra == ["--kalman-tuned"]:
            assert doc["kalman_q_std_s"] * FS == pytest.approx(0.3)  # (the grid's, samples)
            assert doc["kalman_noise"] == "tuned"
        elif not extra:
            assert doc["kalman_noise"] == "adaptive" and doc["kalman_r_std_s"] * FS == 1.0
            assert doc["kalman_q_std_s"] <= cap and doc["kalman_q_std_s"] * FS in (0.03, 0.1, 0.3)
        else:
            assert doc["kalman_q_std_s"] is None and doc["kalman_noise"] is None
    raw, adaptive, tuned = errs[("--no-kalman",)], errs[()], errs[("--kalman-tuned",)]
    assert adaptive < 1.5 * raw and tuned < 2 * raw
    code, out, err = _run(capsys, p, "--array", "three-mic", "--kalman-tuned", "--no-kalman")
    assert code == 2 and out == "" and "--kalman-tuned tunes" in err and err.count("\n") == 1


def test_a_dead_microphone_is_named(rec3, tmp_path, capsys):
    """A channel stuck at one value: a one-line error, exit 2; one 100 dB below the others: a
    one-line warning naming it (both gave "no frame holds a detectable source" or nothing)."""
    x, fs = sf.read(rec3, always_2d=True)
    stuck = x.copy()
    stuck[:, 2] = 0.003
    p = tmp_path / "stuck.wav"
    sf.write(p, stuck, fs, subtype="FLOAT")
    code, out, err = _run(capsys, p, "--array", "three-mic")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "channel 2 holds one constant value throughout" in err
    quiet = x.copy()
    quiet[:, 1] *= 1e-5
    q = tmp_path / "quiet.wav"
    sf.write(q, quiet, fs, subtype="FLOAT")
    code, out, err = _run(capsys, q, "--array", "three-mic")
    assert code == 0 and json.loads(out)["summary"]
    lines = [ln for ln in err.splitlines() if "below the loudest channel" in ln]
    assert len(lines) == 1 and lines[0].startswith(f"hearsee: warning: {q}: channel 1 is at "
                                                   "least 10")  # (100-101 dB: the pause)


def test_a_mono_input_copied_to_both_channels_is_named(tmp_path, capsys):
    """A two-microphone recording whose second channel is a copy of the first (a mono input):
    the summary reads a source straight ahead (TDOA 0) whatever the source; the run now says
    why in one warning line and still prints its document."""
    from hearsee.sim.audio import simulate_recording

    x, _ = simulate_recording("two-mic", [1.0, 1.0, 0.0], signal="male", duration_s=1.0,
                              snr_db=20.0, seed=3)
    p = tmp_path / "mono.wav"
    sf.write(p, np.stack([x[0], x[0]], axis=1), FS, subtype="PCM_16")
    code, out, err = _run(capsys, p, "--array", "two-mic", "--format", "json")
    assert code == 0 and abs(json.loads(out)["summary"]["tdoa_s"]["0-1"]) < 1e-6
    lines = [ln for ln in err.splitlines() if "hold the same signal" in ln]
    assert len(lines) == 1 and lines[0].startswith(f"hearsee: warning: {p}: channels 0 and 1 ")
    q = tmp_path / "stereo.wav"  # the two microphones themselves: no word
    sf.write(q, x.T, FS, subtype="PCM_16")
    code, out, err = _run(capsys, q, "--array", "two-mic", "--format", "json")
    assert code == 0 and "same signal" not in err
    assert abs(json.loads(out)["summary"]["tdoa_s"]["0-1"]) > 1e-4


@pytest.mark.parametrize("channels", [[2], [0, 1, 2]])
def test_a_corrupt_sample_is_named(rec3, tmp_path, capsys, channels):
    """One float sample of 1e30 in a recording of a source at ~0.5: the analysis scales the
    recording to its loudest sample, every other frame fell below single precision and the
    run said "no frame holds a detectable source (silence or uncorrelated noise)"; on every
    channel at once, it read as "channels hold the same signal" beside a source overhead.
    It now names the sample (index, channel, time, value, its ratio to the median |sample|),
    alone; a recording of uncorrelated noise keeps the old words."""
    x, fs = sf.read(rec3, always_2d=True)
    x[9000, channels] = 1e30
    p = tmp_path / "spike.wav"
    sf.write(p, x, fs, subtype="FLOAT")
    code, out, err = _run(capsys, p, "--array", "three-mic", "--format", "json")
    assert code == 0
    assert err.strip().splitlines() == [err.strip()]
    assert err.startswith(f"hearsee: warning: {p}: sample 9000 of channel {channels[0]} "
                          f"({9000 / FS:.3f} s) is 1e+30, ")
    assert "integer PCM" in err and "uncorrelated" not in err and "same signal" not in err
    noise = np.random.default_rng(7).standard_normal((FS, 3)) * 0.1  # no source at all
    q = tmp_path / "noise.wav"
    sf.write(q, noise, FS, subtype="FLOAT")
    code, out, err = _run(capsys, q, "--array", "three-mic", "--format", "json")
    assert code == 0 and json.loads(out)["summary"]["n_valid_frames"] == 0
    assert err == (f"hearsee: warning: {q}: no frame holds a detectable source (silence or "
                   "uncorrelated noise)\n")


def test_eight_mic_circle_table_and_position(tmp_path, capsys):
    """A planar circle of eight: the summary gives the near source's position (on the +z side
    of the array plane, where this one is) in JSON and in the table's summary line; the table
    shows the seven pairs with microphone 0, not 28 squeezed columns."""
    import re

    phi = np.radians(np.arange(0, 360, 45))
    pos = np.c_[0.1 * np.cos(phi), 0.1 * np.sin(phi), np.zeros(8)]
    yml = tmp_path / "circle8.yaml"
    yml.write_text("microphones:\n" + "".join(f"  - [{x}, {y}, {z}]\n" for x, y, z in pos))
    src = np.array([0.5, -0.4, 0.2])
    x = simulate_free_field(white_noise(1.0, FS, rng=3), FS, MicArray(pos), src, snr_db=30,
                            rng=4)
    rec = tmp_path / "c8.wav"
    sf.write(rec, (x / np.abs(x).max() * 0.5).T, FS, subtype="FLOAT")
    code, out, _ = _run(capsys, rec, "--array", yml, "--format", "json")
    assert code == 0
    s = json.loads(out)["summary"]
    np.testing.assert_allclose(s["position_m"], src, atol=0.01)
    # the covariance of the declared 5 us per pair: a few centimetres, the truth inside 3 sigma
    std = np.sqrt(np.diag(s["position_covariance_m2"]))
    assert np.all((std > 1e-3) & (std < 0.1)) and np.all(np.abs(s["position_m"] - src) < 3 * std)
    assert 0 < s["distance_rel_std"] < 0.3
    # free field at 30 dB: the pairs agree to well under 5 / 3 us, so the declared 5 us is used
    assert s["position_tdoa_std_s"] == pytest.approx(5e-6)
    assert [c["elevation_deg"] for c in s["candidates"]] == pytest.approx(
        [17.35, -17.35], abs=0.2)
    # declared TDOA errors of 200 us explain the curvature away: no position, the fit's
    # distance uncertainty still reported
    code, out, _ = _run(capsys, rec, "--array", yml, "--format", "json", "--tdoa-std-us", "200")
    s200 = json.loads(out)["summary"]
    assert code == 0 and s200["position_m"] is None and s200["position_covariance_m2"] is None
    assert s200["distance_rel_std"] > 0.3
    code, out, err = _run(capsys, rec, "--array", yml, "--tdoa-std-us", "-1")
    assert code == 2 and out == "" and err.count("\n") == 1 and "--tdoa-std-us" in err
    # where no position is fitted the option sets nothing: said, not silently taken
    code, out, err = _run(capsys, rec, "--array", yml, "--tdoa-std-us", "3", "--in-plane")
    assert code == 2 and out == "" and err.count("\n") == 1 and "--in-plane" in err
    code, out, _ = _run(capsys, rec, "--array", yml, "--format", "table")
    assert code == 0
    heads = re.findall(r"tdoa (\d-\d)", out)
    assert heads == [f"0-{k}" for k in range(1, 8)]
    assert "TDOAs of 7 of 28 pairs" in out
    assert re.search(r"position \(0\.50, -0\.40, 0\.20\) m \+- \(0\.0\d, 0\.0\d, 0\.0\d\) "
                     r"\(TDOA error 5\.0 us\); direction from the position,", out)
    assert s["direction_from_position"] is True


@pytest.mark.parametrize("value", ["1e300", "1e7"])
def test_absurd_tdoa_std_is_one_line_naming_the_flag(value, tmp_path, capsys):
    """`--tdoa-std-us 1e300` (a slip of units or a typo) was taken and squared into an
    OverflowError traceback. Now at most 1e6 us (1 s, where no position is ever reported
    anyway): one line naming the flag and its range, exit 2; 1e6 itself is still taken."""
    arr = MicArray.from_preset("respeaker-4")
    x = simulate_free_field(white_noise(0.5, FS, rng=5), FS, arr, np.array([0.6, 0.3, 0.2]),
                            snr_db=30, rng=6)
    rec = tmp_path / "r4.wav"
    sf.write(rec, (x / np.abs(x).max() * 0.5).T, FS, subtype="FLOAT")
    code, out, err = _run(capsys, rec, "--array", "respeaker-4", "--tdoa-std-us", value)
    assert code == 2 and out == ""
    assert err == (f"hearsee: error: --tdoa-std-us must be a finite number in (0, 1e+06], "
                   f"got {float(value)}\n")
    code, out, _ = _run(capsys, rec, "--array", "respeaker-4", "--tdoa-std-us", "1e6")
    assert code == 0 and json.loads(out)["summary"]["position_m"] is None


def test_a_file_name_with_a_line_break_keeps_the_error_on_one_line(tmp_path, capsys):
    """`hearsee localize $'bad\\nname.wav'` printed its error over two lines; the break is
    written as \\n, as the one-line rule for errors and warnings asks."""
    p = tmp_path / "bad\nname.wav"
    p.write_bytes(b"not audio at all")
    code, out, err = _run(capsys, p, "--array", "two-mic")
    assert code == 2 and out == ""
    assert err == (f"hearsee: error: {tmp_path}/bad\\nname.wav: not an audio file or a format "
                   "libsndfile cannot read (Format not recognised.); use a WAV or FLAC file\n")


def _upsampled_wav(path, az_deg, kind="female"):
    """A three-mic free-field voice made at 8 kHz (20 dB sensor noise) and written at 16 kHz
    after upsampling, as a telephone-rate recording read by a 16 kHz system."""
    from scipy.signal import resample_poly

    from hearsee.audio.signals import synthetic_voice

    arr = MicArray.from_preset("three-mic")
    x = simulate_free_field(synthetic_voice(kind, 1.5, 8000, rng=3), 8000, arr,
                            2.0 * unit_vector_deg(az_deg, 0.0), snr_db=20, rng=4)
    y = resample_poly(x, 2, 1, axis=1)
    sf.write(path, (y / np.abs(y).max() * 0.5).T, 2 * 8000, subtype="FLOAT")
    return path


def test_an_upsampled_recording_is_localized_in_the_band_it_holds(tmp_path, capsys):
    """Above 4 kHz an 8 kHz recording read at 16 kHz holds only the resampler's images, which
    PHAT weighed fully: the azimuth came out ~12 deg off. The empty band is left out (the JSON
    says the band used) and a note on stderr says so."""
    p = _upsampled_wav(tmp_path / "up.wav", 70.0)
    code, out, err = _run(capsys, p, "--array", "three-mic")
    assert code == 0
    doc = json.loads(out)
    assert doc["band_hz"][0] == 0.0 and 3950.0 < doc["band_hz"][1] <= 4000.0
    assert doc["summary"]["azimuth_deg"] == pytest.approx(70.0, abs=1.0)
    assert err == (f"hearsee: note: {p}: the top of the spectrum is empty (upsampled from a "
                   f"lower rate?): the GCC uses 0-{doc['band_hz'][1]:.0f} Hz\n")
    # a band asked for inside the empty part: one line, exit 2
    code, out, err = _run(capsys, p, "--array", "three-mic", "--band-hz", "5000,7000")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "holds nothing there" in err and "upsampled" in err


def test_band_hz_option(rec3, tmp_path, capsys):
    code, out, err = _run(capsys, rec3, "--array", "three-mic", "--band-hz", "300,3500")
    assert code == 0 and err == ""  # (a recording made at its rate: no note)
    doc = json.loads(out)
    assert doc["band_hz"] == pytest.approx([300.0, 3500.0], abs=16.0)
    assert doc["summary"]["azimuth_deg"] == pytest.approx(-120.0, abs=2.0)
    code, out, _ = _run(capsys, rec3, "--array", "three-mic")
    assert json.loads(out)["band_hz"] == [0.0, FS / 2]
    for bad, msg in (("3500,300", "0 <= LOW < HIGH"), ("-5,300", "0 <= LOW < HIGH"),
                     ("abc", "comma-separated numbers"), ("300", "expected 2 numbers")):
        code, out, err = _run(capsys, rec3, "--array", "three-mic", "--band-hz", bad)
        assert code == 2 and out == "" and "--band-hz" in err and msg in err
    # the masked pair's pipeline sets its own bands (the file is not read: it does not exist)
    code, out, err = _run(capsys, tmp_path / "none.wav", "--array", "mask2-asym",
                          "--band-hz", "300,3500")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "--band-hz: the masked array 'mask2-asym'" in err


def test_an_inverted_microphone_is_one_warning_line(rec3, tmp_path, capsys):
    x, fs = sf.read(rec3, always_2d=True)
    x[:, 1] *= -1.0
    p = tmp_path / "inv.wav"
    sf.write(p, x, fs, subtype="FLOAT")
    code, out, err = _run(capsys, p, "--array", "three-mic")
    assert code == 0 and json.loads(out)["summary"]["inverted_microphones"] == [1]
    assert err.startswith("hearsee: warning: microphone 1 seems wired with inverted polarity: "
                          "pairs 0-1, 1-2 correlate negatively")
    # (no frame is valid: the warning that says so for silence or noise would mislead here)
    assert err.count("hearsee: warning:") == 1 and err.count("\n") == 1
    code, out, _ = _run(capsys, rec3, "--array", "three-mic")
    assert json.loads(out)["summary"]["inverted_microphones"] == []


def test_a_dead_microphone_is_one_warning_line(tmp_path, capsys):
    """Microphone 1 unplugged (its channel preamplifier noise at the others' level): the
    summary was null beside one valid frame, without a word; `track` printed "measured"
    directions 20-30 deg off. Now one warning names it, the JSON summary lists it, and
    neither command adds a second warning."""
    from hearsee.sim.audio import simulate_recording

    x, _ = simulate_recording("three-mic", [1.0, 1.0, 0.0], signal="noise", duration_s=2.0,
                              snr_db=20.0, seed=4)
    x[1] = np.random.default_rng(1).standard_normal(x.shape[1]) * np.std(x[1])
    p = tmp_path / "dead.wav"
    sf.write(p, x.T / np.abs(x).max() * 0.5, FS, subtype="FLOAT")
    code, out, err = _run(capsys, p, "--array", "three-mic", "--format", "json")
    summ = json.loads(out)["summary"]
    assert code == 0 and summ["dead_microphones"] == [1]
    assert err.startswith("hearsee: warning: microphone 1 hears nothing of what the others "
                          "hear") and err.count("\n") == 1
    # (since 2026-12-05 the other two localize: a cone about their axis, both candidates)
    assert "comes from microphones 0, 2 alone" in err and summ["microphones_used"] == [0, 2]
    assert summ["azimuth_deg"] is not None and len(summ["candidates"]) == 2
    assert main(["track", str(p), "--array", "three-mic", "--format", "json"]) == 0
    out, err = capsys.readouterr()
    assert err.count("microphone 1 hears nothing") == 1 and err.count("\n") == 1
    # (the stream leaves it out too: its directions had been built with the dead channel)
    assert "comes from microphones 0, 2 alone" in err
    doc = json.loads(out)
    assert doc["stats"]["microphones_used"] == [0, 2] and doc["array"]["name"] == "three-mic"
    assert any(u["measured"] for u in doc["updates"])
    # an array of four: the other three localize; the stream's directions near the truth
    x, truth = simulate_recording("respeaker-4", [1.2, 1.4, 0.2], signal="male",
                                  duration_s=3.0, snr_db=20.0, seed=7)
    x[3] = np.random.default_rng(2).standard_normal(x.shape[1]) * np.std(x[3])
    p4 = tmp_path / "dead4.wav"
    sf.write(p4, x.T / np.abs(x).max() * 0.5, FS, subtype="FLOAT")
    assert main(["track", str(p4), "--array", "respeaker-4", "--format", "json"]) == 0
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert doc["stats"]["microphones_used"] == [0, 1, 2] and "0, 1, 2 alone" in err
    az = np.array([u["azimuth_deg"] for u in doc["updates"] if u["measured"]])
    assert len(az) > 20 and np.median(np.abs(wrap_deg(az - truth["azimuth_deg"]))) < 5.0


def test_a_warning_told_twice_in_one_run_is_one_line(tmp_path, capsys):
    """`track` looks at a file before streaming it, and both looks told a spatially aliased
    band: the same line twice."""
    from hearsee.sim.audio import simulate_recording

    x, _ = simulate_recording("three-mic", [1.0, 1.0, 0.0], signal="noise", duration_s=2.0,
                              snr_db=20.0, seed=4)
    p = tmp_path / "a.wav"
    sf.write(p, x.T / np.abs(x).max() * 0.5, FS, subtype="FLOAT")
    assert main(["track", str(p), "--array", "three-mic", "--band-hz", "5000,5200"]) == 0
    err = capsys.readouterr().err
    assert err.count("spatial aliasing") == 1 and err.startswith("hearsee: warning: band ")


def test_a_vertical_pairs_elevation_is_a_direction(tmp_path, capsys):
    """A vertical pair tells the elevation alone (its azimuth is always null): a source 25 deg
    up, whose elevation the summary got right, was warned about as "no direction for the whole
    recording"."""
    yml = tmp_path / "vertical.yaml"
    yml.write_text("name: vertical\nmicrophones:\n- [0, 0, -0.075]\n- [0, 0, 0.075]\n")
    arr = MicArray.from_yaml(yml)
    x = simulate_free_field(white_noise(1.0, FS, rng=5), FS, arr,
                            20.0 * unit_vector_deg(30.0, 25.0), snr_db=30, rng=6)
    p = tmp_path / "vertical.wav"
    sf.write(p, (x / np.abs(x).max() * 0.5).T, FS, subtype="FLOAT")
    code, out, err = _run(capsys, p, "--array", yml, "--format", "json")
    assert code == 0
    s = json.loads(out)["summary"]
    assert s["azimuth_deg"] is None and s["elevation_deg"] == pytest.approx(25.0, abs=1.0)
    assert "no direction" not in err


def test_a_summary_without_a_direction_is_said(rec3, monkeypatch, capsys):
    """A summary of nulls beside a few valid frames was printed without a word (only no valid
    frame at all was told)."""
    import hearsee.audio.localize as L

    real = L.localize_recording

    def no_summary(*args, **kwargs):
        doc = real(*args, **kwargs)
        doc["summary"].update(azimuth_deg=None, elevation_deg=None, n_valid_frames=3)
        return doc

    monkeypatch.setattr(L, "localize_recording", no_summary)
    code, out, err = _run(capsys, rec3, "--array", "three-mic", "--format", "json")
    assert code == 0 and json.loads(out)["summary"]["azimuth_deg"] is None
    n = len(json.loads(out)["frames"])
    assert err == (f"hearsee: warning: {rec3}: no direction for the whole recording (its "
                   f"averaged correlations name no source; 3 frames on {n} had one)\n")
    monkeypatch.setattr(L, "localize_recording", real)
    code, out, err = _run(capsys, rec3, "--array", "three-mic", "--format", "json")
    assert code == 0 and err == ""


def test_channels_out_of_sync_are_named_in_one_line(rec3, tmp_path, capsys):
    """Channel 2 recorded 2.3 ms late: "no frame holds a detectable source (silence or
    uncorrelated noise)" was all the run said. Now one warning line names the microphone and
    the JSON summary gives the pairs' offsets; the recording in sync gives none."""
    x, fs = sf.read(rec3, always_2d=True)
    code, out, err = _run(capsys, rec3, "--array", "three-mic", "--format", "json")
    assert code == 0 and json.loads(out)["summary"]["sync_offsets_s"] == {}
    assert "out of sync" not in err
    x[:, 2] = np.roll(x[:, 2], 37)
    p = tmp_path / "late.wav"
    sf.write(p, x, fs, subtype="FLOAT")
    code, out, err = _run(capsys, p, "--array", "three-mic", "--format", "json")
    assert code == 0
    offs = json.loads(out)["summary"]["sync_offsets_s"]
    assert set(offs) <= {"0-2", "1-2"} and offs
    assert all(-37 / fs - 0.5e-3 <= v <= -37 / fs + 0.5e-3 for v in offs.values())
    lines = [ln for ln in err.splitlines() if "out of sync" in ln]
    assert len(lines) == 1 and lines[0].startswith("hearsee: warning: ")
    assert "beyond the +-" in lines[0]
    # no frame was valid because of it: not blamed on "silence or uncorrelated noise" too
    assert json.loads(out)["summary"]["n_valid_frames"] == 0 and "silence" not in err
    assert err.count("\n") == 1


def test_track_names_channels_out_of_sync_once(rec3, tmp_path, capsys):
    """`hearsee track` checks a file before streaming it: channel 2 recorded 2.3 ms late gives
    one sync warning, and no second "no frame held a localizable source" beside it."""
    x, fs = sf.read(rec3, always_2d=True)
    x[:, 2] = np.roll(x[:, 2], 37)
    p = tmp_path / "late.wav"
    sf.write(p, x, fs, subtype="FLOAT")
    assert main(["track", str(p), "--array", "three-mic"]) == 0
    err = capsys.readouterr().err
    assert err.count("seems out of sync") == 1 and "localizable" not in err


def test_mains_hum_is_named_in_one_line_and_filtered_out(tmp_path, capsys):
    """A 50-Hz buzz on every channel, 3 dB above a female voice at azimuth -150 deg: the
    summary was a source overhead. Now one warning line names the hum, the JSON summary lists
    the lines filtered out, and the azimuth is the voice's; the voice alone gives no line."""
    from hearsee.sim.audio import simulate_recording

    src = 2.0 * unit_vector_deg(-150.0, 5.0)
    kw = {"signal": "female", "duration_s": 3.0, "fs": FS, "snr_db": 20, "seed": 8}
    x, truth = simulate_recording("three-mic", src, **kw)
    y, _ = simulate_recording("three-mic", src, hum_db=3.0, hum_hz=50.0, **kw)
    for name, rec, lines in (("voice.wav", x, False), ("hum.wav", y, True)):
        p = tmp_path / name
        sf.write(p, (rec / np.abs(rec).max() * 0.5).T, FS, subtype="FLOAT")
        code, out, err = _run(capsys, p, "--array", "three-mic", "--format", "json")
        s = json.loads(out)["summary"]
        assert code == 0
        assert abs((s["azimuth_deg"] - truth["azimuth_deg"] + 180) % 360 - 180) < 3.0
        assert bool(s["tonal_lines_hz"]) is lines
        warned = [ln for ln in err.splitlines() if "tonal noise" in ln]
        assert len(warned) == int(lines)
    assert abs(s["tonal_lines_hz"][0] - 50.0) < 0.1 and len(s["tonal_lines_hz"]) >= 40
    assert warned[0].startswith("hearsee: warning: stationary tonal noise on every microphone "
                                "at 50.0 Hz and its harmonics up to ")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        off = estimate_tdoas(y, FS, "three-mic", tonal_noise=False).summary_tdoa_s
    want = np.array(list(truth["tdoa_s"].values()))
    assert np.max(np.abs(off - want)) * FS > 3.0  # (the failure the filter fixes)


def _track_updates(capsys) -> list[dict]:
    """`hearsee track`'s JSON lines just printed, but their measured latency."""
    lines = [json.loads(s) for s in capsys.readouterr().out.splitlines()]
    return [{k: v for k, v in u.items() if k != "latency_ms"} for u in lines]


def test_one_file_per_microphone(tmp_path, capsys):
    """Recorders that write a file per input: `hearsee localize` and `hearsee track` take the
    files in the array's order and answer as for the multichannel file; files of different
    lengths are one line, exit 2."""
    arr = MicArray.from_preset("two-mic")
    x = simulate_free_field(white_noise(0.5, FS, rng=5), FS, arr, 2.0 * unit_vector_deg(-35, 0),
                            snr_db=25, rng=6)
    x = 0.3 * x / np.abs(x).max()
    whole = tmp_path / "two.wav"
    sf.write(whole, x.T, FS, subtype="FLOAT")
    mics = [tmp_path / f"mic{k}.wav" for k in range(2)]
    for k, p in enumerate(mics):
        sf.write(p, x[k], FS, subtype="FLOAT")
    code, out, _ = _run(capsys, *mics, "--array", "two-mic")
    assert code == 0
    doc = json.loads(out)
    assert doc["recording"] == [str(p) for p in mics]
    # the truth: t_0 - t_1 of a plane wave from -35 deg (arrival t_k = -p_k . u / c; the
    # source is 2 m away, the 15 cm pair's far-field error well below the tolerance)
    u = unit_vector_deg(-35, 0)
    tau = -float((arr.positions[0] - arr.positions[1]) @ u) / arr.speed_of_sound
    assert doc["summary"]["tdoa_s"]["0-1"] == pytest.approx(tau, abs=3e-6)
    code, ref, _ = _run(capsys, whole, "--array", "two-mic")
    assert code == 0 and json.loads(ref)["summary"] == doc["summary"]
    assert main(["track", str(whole), "--array", "two-mic"]) == 0
    ref = _track_updates(capsys)
    assert main(["track", *map(str, mics), "--array", "two-mic"]) == 0
    assert _track_updates(capsys) == ref and any(u["measured"] for u in ref)
    # swapped files: the mirror image's TDOA
    code, out, _ = _run(capsys, *mics[::-1], "--array", "two-mic")
    assert json.loads(out)["summary"]["tdoa_s"]["0-1"] == pytest.approx(-tau, abs=3e-6)
    sf.write(mics[1], x[1, :-3], FS, subtype="FLOAT")
    for cmd in ("localize", "track"):
        assert main([cmd, *map(str, mics), "--array", "two-mic"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "different numbers of samples" in err


def test_channels_pick_a_devices_microphones(tmp_path, capsys):
    """A ReSpeaker 4-mic array records 6 channels (0: its processed beam, 1-4: the microphones,
    5: the playback): `--channels 1,2,3,4` localizes the microphones as their own 4-channel
    file does (`hearsee localize` and `hearsee track`); without it, or with text that is no
    channel list, one line and exit 2."""
    arr = MicArray.from_preset("respeaker-4")
    x = simulate_free_field(white_noise(0.5, FS, rng=7), FS, arr, 2.0 * unit_vector_deg(70, 0),
                            snr_db=25, rng=8)
    x = 0.3 * x / np.abs(x).max()
    four, six = tmp_path / "four.wav", tmp_path / "six.wav"
    sf.write(four, x.T, FS, subtype="FLOAT")
    sf.write(six, np.vstack([x.mean(axis=0), x, np.zeros((1, x.shape[1]))]).T, FS,
             subtype="FLOAT")
    code, ref, _ = _run(capsys, four, "--array", "respeaker-4")
    assert code == 0
    ref = json.loads(ref)["summary"]
    assert ref["azimuth_deg"] == pytest.approx(70.0, abs=2.0)
    code, out, _ = _run(capsys, six, "--array", "respeaker-4", "--channels", "1,2,3,4")
    assert code == 0 and json.loads(out)["summary"] == ref
    for cmd in ("localize", "track"):
        for extra, want in (([], "6 channels but array 'respeaker-4' has 4 microphones"),
                            (["--channels", "1,2,x,4"], "--channels: expected comma-separated"),
                            (["--channels", "1,2,3"], "--channels: 3 channels for an array of"),
                            (["--channels", "1,2,3,5"], "six.wav: channel 5 silent"),
                            # (numpy's OverflowError, a traceback)
                            (["--channels", "1,2,3,1e19"], "channel 10000000000000000000 is "
                                                           "beyond any input")):
            assert main([cmd, str(six), "--array", "respeaker-4", *extra]) == 2
            err = capsys.readouterr().err
            assert err.count("\n") == 1 and want in err, err
    assert main(["track", str(four), "--array", "respeaker-4"]) == 0
    ref = _track_updates(capsys)
    assert main(["track", str(six), "--array", "respeaker-4", "--channels", "1,2,3,4"]) == 0
    assert _track_updates(capsys) == ref and any(u["measured"] for u in ref)


def test_an_array_file_in_centimetres_is_asked_about_its_unit(tmp_path, capsys):
    """A 15 cm pair written in centimetres (15 m wide) asked for frames of 175 ms and more
    without a word of the unit; the message now asks whether the positions are in metres. A
    frame too short for a real (0.6 m) array gets no such question."""
    x = 0.1 * np.random.default_rng(246).standard_normal((2, FS))
    rec = tmp_path / "pair.wav"
    sf.write(rec, x.T, FS, subtype="FLOAT")
    for name, y, hint in (("cm", 7.5, True), ("wide", 0.3, False)):
        arr = tmp_path / f"{name}.yaml"
        arr.write_text(f"microphones:\n  - [0, {-y}, 0]\n  - [0, {y}, 0]\n")
        for cmd in ("localize", "track"):
            assert main([cmd, str(rec), "--array", str(arr), "--frame-ms", "2"]) == 2
            err = capsys.readouterr().err
            assert err.count("\n") == 1 and "too short for the array's largest delay" in err
            assert ("are its microphone positions in metres?" in err) is hint, err
            assert ("spans 15 m" in err) is hint


@pytest.mark.shared
@pytest.mark.slow
def test_channels_of_a_real_32_microphone_recording(shared_data, tmp_path, capsys):
    """Real acoustics: dry ARCTIC speech through the measured impulse responses of a 32-mic
    line array (3 cm apart, known source positions), written as one 32-channel file;
    `--channels 8,12` localizes microphones 8 and 12 (12 cm apart, both even: the array's
    even/odd channel latency cancels) as their own two-channel file does, and the TDOA (-9
    samples at 48 kHz for source 1) is the geometry's within 1.5 samples (the data's README:
    offsets of 0-1.1 samples and residuals of 0.6-2.3 between the direct paths and the
    geometry; picking microphone 13 or 7 instead was 2.4-3.0 samples off, 0.5 with 8 and 12);
    `--channels 12,8` the opposite sign."""
    import scipy.io
    from scipy.signal import fftconvolve

    from hearsee.audio.signals import load_wav

    d = shared_data / "audio" / "rirs_ula32"
    fs, c = 48000, 343.0
    h, _ = sf.read(d / "rir_source_1.wav", always_2d=True)
    x, z = scipy.io.loadmat(d / "source_location.mat")["sourceLocation"][0]  # metres
    s, _ = load_wav(shared_data / "audio" / "speech" / "cmu_arctic_us_aew_a0001.wav", fs)
    y = fftconvolve(s[:, None], h, axes=0)[: len(s)]
    y += 1e-3 * np.abs(y).max() * np.random.default_rng(248).standard_normal(y.shape)
    y *= 0.5 / np.abs(y).max()
    sf.write(tmp_path / "ula32.wav", y, fs, subtype="FLOAT")
    sf.write(tmp_path / "pair.wav", y[:, [8, 12]], fs, subtype="FLOAT")
    arr = tmp_path / "pair.yaml"  # (the line along y; the source in the array's plane)
    arr.write_text(f"speed_of_sound: {c}\nmicrophones:\n  - [0, {0.03 * 8}, 0]\n"
                   f"  - [0, {0.03 * 12}, 0]\n")
    src = np.array([x, z, 0.0])
    true = (np.linalg.norm(src - [0, 0.24, 0]) - np.linalg.norm(src - [0, 0.36, 0])) / c
    assert true * fs == pytest.approx(-9.0, abs=0.1)
    code, out, _ = _run(capsys, tmp_path / "ula32.wav", "--array", arr, "--channels", "8,12")
    assert code == 0
    got = json.loads(out)["summary"]
    assert got["tdoa_s"]["0-1"] == pytest.approx(true, abs=1.5 / fs)
    code, ref, _ = _run(capsys, tmp_path / "pair.wav", "--array", arr)
    assert code == 0 and json.loads(ref)["summary"] == got
    code, out, _ = _run(capsys, tmp_path / "ula32.wav", "--array", arr, "--channels", "12,8")
    assert code == 0
    assert json.loads(out)["summary"]["tdoa_s"]["0-1"] == pytest.approx(-true, abs=1.5 / fs)
