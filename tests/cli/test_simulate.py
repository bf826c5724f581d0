import json

import numpy as np
import pytest

from hearsee.audio.arrays import MicArray
from hearsee.audio.signals import read_recording, write_recording
from hearsee.cli import main
from hearsee.sim.audio import simulate_recording


def test_simulate_round_trip(tmp_path, capsys, gcc_phat_ref):
    out = tmp_path / "rec.wav"
    args = ["simulate", str(out), "--array", "three-mic", "--source", "1.0,-2.0,0.5",
            "--signal", "female", "--duration", "0.5", "--fs", "16000", "--snr", "25",
            "--seed", "3"]
    assert main(args) == 0
    assert "wrote" in capsys.readouterr().err
    arr = MicArray.from_preset("three-mic")
    x, fs = read_recording(out, arr, fs=16000)
    assert x.shape == (3, 8000)
    truth = json.loads((tmp_path / "rec.json").read_text())
    src = np.array([1.0, -2.0, 0.5])
    assert truth["source_m"] == [1.0, -2.0, 0.5]
    assert truth["azimuth_deg"] == pytest.approx(np.degrees(np.arctan2(-2.0, 1.0)))
    assert truth["elevation_deg"] == pytest.approx(np.degrees(np.arctan2(0.5, np.sqrt(5))))
    assert truth["distance_m"] == pytest.approx(np.linalg.norm(src))
    np.testing.assert_allclose(list(truth["tdoa_s"].values()), arr.tdoa(src))
    assert truth["array"]["name"] == "three-mic" and truth["fs"] == 16000
    assert truth["signal"] == "female" and truth["snr_db"] == 25.0 and truth["seed"] == 3
    # the WAV is exactly the library's simulation times the recorded gain
    ref, _ = simulate_recording(arr, src, "female", 0.5, 16000, snr_db=25.0, seed=3)
    np.testing.assert_allclose(x, ref * truth["gain"], atol=1e-6)
    est = [gcc_phat_ref(x[i], x[j], fs, 0.0005) for i, j in arr.pairs]
    np.testing.assert_allclose(np.array(est) * fs, arr.tdoa(src) * fs, atol=0.2)


def test_simulate_room_yaml_array_and_wav_signal(tmp_path):
    yaml_path = tmp_path / "pair.yaml"
    yaml_path.write_text("name: pair\nmicrophones: [[0, 0.1, 0], [0, -0.1, 0]]\n")
    sig = tmp_path / "speech.wav"
    write_recording(sig, 0.3 * np.sin(np.arange(4000) * 0.3), 8000)
    out = tmp_path / "room.wav"
    assert main(["simulate", str(out), "--array", str(yaml_path), "--source", "2,1,0",
                 "--signal", str(sig), "--duration", "0.3", "--room", "6x5x3", "--rt60", "0.2",
                 "--pcm16"]) == 0
    truth = json.loads(out.with_suffix(".json").read_text())
    assert truth["room"] == {"room_dim": [6.0, 5.0, 3.0], "rt60": 0.2,
                             "array_at": [3.0, 2.5, 1.5]}
    assert truth["array"]["name"] == "pair" and truth["signal"] == str(sig)
    x, fs = read_recording(out, n_channels=2, fs=16000)
    assert x.shape == (2, 4800)
    assert main(["simulate", str(tmp_path / "at.wav"), "--array", "two-mic", "--source",
                 "1,0,0", "--duration", "0.1", "--room", "6x5x3", "--rt60", "0",
                 "--array-at", "1,1,1"]) == 0
    truth = json.loads((tmp_path / "at.json").read_text())
    assert truth["room"]["array_at"] == [1.0, 1.0, 1.0]


@pytest.mark.parametrize("extra, message", [
    (["--source", "1,a,3"], "--source: expected comma-separated numbers"),
    (["--source", "1,2"], "--source: expected 3 numbers"),
    (["--source", "1,0,0", "--room", "6x5x3"], "--room needs --rt60"),
    (["--source", "1,0,0", "--rt60", "0.3"], "need --room"),
    (["--source", "1,0,0", "--room", "6x5", "--rt60", "0.3"], "--room: expected 3 numbers"),
    (["--source", "9,0,0", "--room", "6x5x3", "--rt60", "0.3"], "outside the room"),
    (["--source", "1,0,0", "--room", "40x40x10", "--rt60", "0.05"], "too short"),
    (["--source", "1,0,0", "--signal", "pink"], "unknown signal"),
    (["--source", "1,0,0", "--signal", "missing.wav"], "file not found"),
    (["--source", "1,0,0", "--duration", "-1"], "duration"),
    (["--source", "1,0,0", "--duration", "1e9"], "at most 600 s"),  # (not 116 TiB)
    (["--source", "1,0,0", "--fs", "10"], "within 4000-384000 Hz, got 10 Hz"),
    (["--source", "1,0,0", "--fs", "1000000000"], "within 4000-384000 Hz"),
    (["--source", "1,0,0", "--room", "6x5x3", "--rt60", "0", "--far-field"], "free field only"),
    (["--source", "0,0,0", "--far-field"], "needs a direction"),
    # (a silent or sinc-tail recording written with this truth, exit 0, before)
    (["--source", "100,0,0"], "its sound takes 0.2915 s to arrive, longer than the 0.1 s"),
    (["--source", "1,0,0", "--room", "1e9x4x3", "--rt60", "0.3"],
     "impulse responses up to"),  # (a MemoryError traceback before)
])
def test_simulate_bad_options(tmp_path, capsys, extra, message):
    code = main(["simulate", str(tmp_path / "o.wav"), "--array", "two-mic", "--duration", "0.1",
                 *extra])
    assert code == 2
    err = capsys.readouterr().err
    assert message in err
    assert "Traceback" not in err
    assert not (tmp_path / "o.wav").exists() and not (tmp_path / "o.json").exists()


def test_simulate_refuses_bad_outputs(tmp_path, capsys):
    sig = tmp_path / "in.wav"
    write_recording(sig, 0.3 * np.sin(np.arange(1600) * 0.2), 16000)
    before = sig.read_bytes()
    base = ["--array", "two-mic", "--source", "1,0,0", "--duration", "0.1"]
    assert main(["simulate", str(sig), *base, "--signal", str(sig)]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert sig.read_bytes() == before
    assert main(["simulate", str(tmp_path / "nodir" / "o.wav"), *base]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["simulate", str(tmp_path / "o.mp4"), *base]) == 2
    assert "must end in .wav" in capsys.readouterr().err
    assert main(["simulate", str(tmp_path / "o.wav"), "--array", "nine-mic", "--source",
                 "1,0,0"]) == 2
    assert "unknown array preset" in capsys.readouterr().err


@pytest.mark.parametrize("mode", ["static", "moving", "poses"])
def test_simulate_keeps_existing_outputs_unless_forced(tmp_path, capsys, mode):
    """A second run to the same name is refused (every file it would write is checked first,
    nothing is touched); --force replaces them."""
    out = tmp_path / ("rec.yaml" if mode == "poses" else "rec.wav")
    args = ["simulate", str(out), "--array", "two-mic", "--duration", "0.1", "--seed", "1"]
    if mode == "moving":
        csv = tmp_path / "walk.csv"
        csv.write_text("t,x,y,z\n0,1.5,-0.5,0.2\n1,1.5,0.5,0.2\n")
        args += ["--trajectory", str(csv)]
    else:
        args += ["--source", "1,0.5,0"]
    if mode == "poses":
        args += ["--poses", "0,0;30,0"]
    assert main(args) == 0
    written = sorted(p for p in tmp_path.iterdir() if p.name.startswith("rec"))
    assert len(written) == {"static": 2, "moving": 3, "poses": 5}[mode]
    # any one existing output is enough to refuse, and then nothing is written
    for victim in written:
        for p in written:
            p.unlink(missing_ok=True)
        victim.write_bytes(b"mine")
        capsys.readouterr()
        assert main([*args, "--seed", "2"]) == 2
        err = capsys.readouterr().err
        assert f"{victim.name}: file exists; pass --force" in err and "Traceback" not in err
        assert sorted(p for p in tmp_path.iterdir() if p.name.startswith("rec")) == [victim]
        assert victim.read_bytes() == b"mine"
    assert main([*args, "--seed", "2", "--force"]) == 0
    assert victim.read_bytes() != b"mine"
    assert sorted(p for p in tmp_path.iterdir() if p.name.startswith("rec")) == written


def test_simulate_far_field_source_1e300_m_away(tmp_path, capsys):
    """`simulate --far-field --source 1e300,1e300,0` printed three numpy RuntimeWarning lines
    and wrote TDOAs of -0.0 and a null distance; the direction (45 deg) is well defined. Now
    the truth is that of --source 1,1,0 (its distance 1.41e300 m), without a warning."""
    base = ["--array", "respeaker-4", "--duration", "0.1", "--far-field"]
    assert main(["simulate", str(tmp_path / "far.wav"), *base, "--source", "1e300,1e300,0"]) == 0
    err = " ".join(capsys.readouterr().err.split())  # (the console wraps long lines)
    assert "Warning" not in err and "distance 1.41e+300 m" in err
    assert main(["simulate", str(tmp_path / "one.wav"), *base, "--source", "1,1,0"]) == 0
    far = json.loads((tmp_path / "far.json").read_text())
    one = json.loads((tmp_path / "one.json").read_text())
    assert far["tdoa_s"] == one["tdoa_s"] and far["azimuth_deg"] == one["azimuth_deg"] == 45.0
    assert far["distance_m"] == pytest.approx(2**0.5 * 1e300)
    assert "distance 1.41 m" in " ".join(capsys.readouterr().err.split())


def test_simulate_refuses_a_one_sample_signal(tmp_path, capsys):
    """A 1-sample --signal WAV was looped into a constant signal and written (exit 0) with a
    truth its recording does not carry; now one line, exit 2, nothing written."""
    sig = tmp_path / "one.wav"
    write_recording(sig, np.array([0.5]), 16000)
    out = tmp_path / "o.wav"
    assert main(["simulate", str(out), "--array", "two-mic", "--source", "1,0,0",
                 "--signal", str(sig), "--duration", "0.1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"hearsee: error: {sig}: the signal is too short to simulate: 1 sample")
    assert len(err.splitlines()) == 1 and not out.exists()
