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
    # (an OverflowError traceback while the message counted the images, before)
    (["--source", "1,0,0", "--room", "6x5x3", "--rt60", "1e300"],
     "RT60 1e+300 s in a 6x5x3 m room needs image sources up to order 1.33e+302 (over 1e+300 "
     "images, more memory than a simulation should take; the limit is order 200)"),
    # (pyroomacoustics' order overflowed: an OverflowError traceback, before)
    (["--source", "1,0,0", "--room", "1e300x5x3", "--rt60", "0.3"],
     "RT60 0.3 s in a 1e+300x5x3 m room: the image-source order overflows (infinite); use a "
     "smaller room or a shorter RT60"),
    (["--source", "1,0,0", "--room", "6x5x3", "--rt60", "1e308"], "order overflows"),
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
    out, extra = _mode_args(tmp_path, mode, "rec")
    args = ["simulate", str(out), "--array", "two-mic", "--duration", "0.1", "--seed", "1",
            *extra]
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


def _mode_args(tmp_path, mode, stem="o", walk_csv="t,x,y,z\n0,1.5,-0.5,0.2\n1,1.5,0.5,0.2\n"):
    """(output path ``stem``.wav / .yaml, the options of ``simulate`` in ``mode``): static,
    moving (``walk_csv`` written to walk.csv) or poses."""
    if mode == "moving":
        csv = tmp_path / "walk.csv"
        csv.write_text(walk_csv)
        return tmp_path / f"{stem}.wav", ["--trajectory", str(csv)]
    if mode == "poses":
        return tmp_path / f"{stem}.yaml", ["--source", "1,0.5,0", "--poses", "0,0;30,0"]
    return tmp_path / f"{stem}.wav", ["--source", "1,0.5,0"]


def _outputs(tmp_path):
    return sorted(p.name for p in tmp_path.iterdir() if p.name.startswith("o"))


@pytest.mark.parametrize("mode", ["static", "moving", "poses"])
@pytest.mark.parametrize("snr", ["1e6", "-500", "200.5", "-60.5", "1e308"])
def test_simulate_refuses_an_snr_out_of_range_before_simulating(tmp_path, capsys, monkeypatch,
                                                                 mode, snr):
    """--snr 1e6 raised an OverflowError traceback from add_noise (10**(snr/10)), after the
    whole simulation; --snr -500 wrote pure noise (source gain 1e-26), exit 0. Now one line,
    exit 2, before any simulation (the simulators here fail the test if they are reached)."""
    import hearsee.audio.active
    import hearsee.sim.audio
    import hearsee.sim.moving

    def reached(*args, **kwargs):
        raise AssertionError("the simulation ran before the SNR was checked")

    monkeypatch.setattr(hearsee.sim.audio, "simulate_recording", reached)
    monkeypatch.setattr(hearsee.sim.moving, "simulate_moving_recording", reached)
    monkeypatch.setattr(hearsee.audio.active, "simulate_pose_manifest", reached)
    out, extra = _mode_args(tmp_path, mode)
    assert main(["simulate", str(out), "--array", "two-mic", "--duration", "0.1",
                 "--snr", snr, *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"hearsee: error: SNR must be within -60 to 200 dB, got {float(snr):g}")
    assert len(err.splitlines()) == 1 and _outputs(tmp_path) == []


@pytest.mark.parametrize("snr", [-60.0, 200.0])
def test_simulate_accepts_the_snr_range_ends(tmp_path, snr):
    """The ends of the range are valid, and the noise is at that SNR: at -60 dB the recording
    is 1e6 times the clean one's power of noise, at 200 dB it equals the clean one."""
    out = tmp_path / "o.wav"
    assert main(["simulate", str(out), "--array", "two-mic", "--source", "1,0.5,0",
                 "--duration", "0.1", "--snr", str(snr)]) == 0
    arr = MicArray.from_preset("two-mic")
    x, _ = read_recording(out, arr, fs=16000)
    gain = json.loads(out.with_suffix(".json").read_text())["gain"]
    clean, _ = simulate_recording(arr, [1.0, 0.5, 0.0], "noise", 0.1, 16000, seed=0)
    noise = x / gain - clean
    ratio_db = 10 * np.log10(np.mean(clean**2) / np.mean(noise**2))
    if snr < 0:
        assert ratio_db == pytest.approx(snr, abs=0.2)
    else:  # (float32 rounding of the written file only: -140 dB or so, nowhere near 200)
        assert ratio_db > 120


@pytest.mark.parametrize("mode", ["static", "moving", "poses"])
@pytest.mark.parametrize("out", [".", "./", "/", "", ".."])
def test_simulate_refuses_a_folder_as_output(tmp_path, capsys, monkeypatch, mode, out):
    """`simulate .` (also '/', './', '') raised "ValueError: PosixPath('.') has an empty name"
    deriving OUT.json / OUT_pose<k>.wav from it; '..' was refused in one line. Now all alike."""
    monkeypatch.chdir(tmp_path)
    _, extra = _mode_args(tmp_path, mode)
    assert main(["simulate", out, "--array", "two-mic", "--duration", "0.1", *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("hearsee: error: ") and len(err.splitlines()) == 1, err
    assert "is a folder, expected an output file name (e.g. OUT." in err
    assert _outputs(tmp_path) == []


@pytest.mark.parametrize("mode", ["static", "moving"])
@pytest.mark.parametrize("offset", ["nan,0,0", "5,5", "0,0,0", "0,0.1,0"])
def test_simulate_head_offset_needs_poses(tmp_path, capsys, mode, offset):
    """--head-offset without --poses was ignored, exit 0 -- even a malformed one (nan,0,0 or
    5,5). Now one line, exit 2, nothing written."""
    out, extra = _mode_args(tmp_path, mode)
    assert main(["simulate", str(out), "--array", "two-mic", "--duration", "0.1",
                 "--head-offset", offset, *extra]) == 2
    err = capsys.readouterr().err
    assert err == "hearsee: error: --head-offset needs --poses (it places the array on the " \
                  "turning head of a pose capture)\n"
    assert _outputs(tmp_path) == []


def test_simulate_head_offset_with_poses_still_applies(tmp_path):
    """With --poses, --head-offset is the manifest's offset; without it 0,0,0."""
    import yaml

    out, extra = _mode_args(tmp_path, "poses")
    base = ["simulate", str(out), "--array", "two-mic", "--duration", "0.1", *extra]
    assert main([*base, "--head-offset", "0,0.1,0"]) == 0
    assert yaml.safe_load(out.read_text())["head"]["offset_m"] == [0.0, 0.1, 0.0]
    assert main([*base, "--force"]) == 0
    assert yaml.safe_load(out.read_text())["head"]["offset_m"] == [0.0, 0.0, 0.0]


@pytest.mark.parametrize("rate", [1, 999])
def test_simulate_refuses_a_signal_file_below_1000_hz(tmp_path, capsys, rate):
    """A --signal file at 1 Hz (a wrong header) was resampled to --fs: 100 samples became 1.6
    million, exit 0 (200000 samples asked for 23.8 GiB). Now one line, exit 2."""
    import soundfile as sf

    sig = tmp_path / "slow.wav"
    sf.write(sig, 0.3 * np.random.default_rng(2).standard_normal(100), rate)
    out = tmp_path / "o.wav"
    assert main(["simulate", str(out), "--array", "two-mic", "--source", "1,0,0",
                 "--signal", str(sig), "--duration", "0.1"]) == 2
    err = capsys.readouterr().err
    assert err == (f"hearsee: error: {sig}: the file's sample rate is {rate} Hz, below the 1000 "
                   "Hz a source signal needs (a wrong header?); resample it to e.g. 16000 Hz\n")
    assert not out.exists()


def test_messages_name_the_files_written_even_with_brackets(tmp_path, capsys):
    """Rich read "[bold]" in a file name as markup: 'wrote .../take2.wav' for take[bold]2.wav."""
    out = tmp_path / "take[bold]2.wav"
    assert main(["simulate", str(out), "--array", "two-mic", "--source", "1,0.5,0",
                 "--duration", "0.2"]) == 0
    err = capsys.readouterr().err
    assert out.is_file() and "take[bold]2.wav" in err and "take[bold]2.json" in err


@pytest.mark.parametrize(("mode", "limit", "fails"), [
    ("static", 100, "rec.wav"), ("static", 400, "rec.json"), ("moving", 400, "rec.json"),
    ("poses", 520, "rec.yaml")])
def test_simulate_force_keeps_the_earlier_file_when_a_write_fails(tmp_path, capsys, mode, limit,
                                                                  fails, file_size_limit):
    """`simulate --force` wrote its files in place: a write that failed part way (a full disk,
    here a file size limit; Ctrl-C) left a truncated WAV, JSON or manifest where the user's
    earlier file was, and a failed JSON or manifest said only "File too large". Now each file
    replaces the earlier one only when complete (config.replacing): the one that failed is
    still the earlier file, one line names it, no temporary file is left."""
    import soundfile as sf
    import yaml

    out, extra = _mode_args(tmp_path, mode, "rec", "t,x,y,z\n0,0.5,-0.2,0.1\n1,0.5,0.2,0.1\n")
    args = ["simulate", str(out), "--array", "two-mic", "--duration", "0.004", "--pcm16",
            "--force", *extra]
    names = {"static": ["rec.wav", "rec.json"],
             "moving": ["rec.wav", "rec.json", "rec.trajectory.csv"],
             "poses": ["rec.yaml", "rec_pose0.wav", "rec_pose0.json", "rec_pose1.wav",
                       "rec_pose1.json"]}[mode]
    for n in names:
        (tmp_path / n).write_bytes(b"mine")
    with file_size_limit(limit):
        code = main(args)
    err = capsys.readouterr().err
    assert code == 2 and err == f"hearsee: error: {tmp_path / fails}: cannot write " + (
        "audio (System error.)\n" if fails.endswith(".wav") else "(File too large)\n"), err
    assert (tmp_path / fails).read_bytes() == b"mine"
    for n in names:  # each file is the earlier one or a complete new one, never a part
        data, p = (tmp_path / n).read_bytes(), tmp_path / n
        if data != b"mine":
            if n.endswith(".wav"):
                assert sf.info(p).frames == 64
            elif n.endswith(".json"):
                assert json.loads(data)["fs"] == 16000
            else:
                assert isinstance(yaml.safe_load(data), dict)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [*names, *(["walk.csv"] if mode == "moving" else [])])


def test_simulate_hum_is_the_same_on_every_channel_and_in_the_truth(tmp_path, capsys):
    """--hum 0 --hum-hz 60: the recording less the one without hum (same seed) is one 60-Hz
    harmonic waveform on every channel, as loud as the signal; the truth records it;
    --hum with --trajectory or an out-of-range level is one error line, exit 2."""
    src = "1.0,1.0,0.2"
    out = tmp_path / "h.wav"
    args = ["simulate", str(out), "--array", "two-mic", "--source", src, "--signal", "male",
            "--duration", "1", "--seed", "4"]
    assert main([*args, "--hum", "0", "--hum-hz", "60"]) == 0
    truth = json.loads(out.with_suffix(".json").read_text())
    assert truth["hum_db"] == 0.0 and truth["hum_hz"] == 60.0
    x, _ = simulate_recording("two-mic", [1.0, 1.0, 0.2], signal="male", duration_s=1.0,
                              seed=4)
    y, _ = simulate_recording("two-mic", [1.0, 1.0, 0.2], signal="male", duration_s=1.0,
                              seed=4, hum_db=0.0, hum_hz=60.0)
    h = y - x
    np.testing.assert_allclose(h[0], h[1], atol=1e-12)
    assert np.mean(h ** 2) == pytest.approx(np.mean(x ** 2), rel=1e-9)
    spec = np.abs(np.fft.rfft(h[0]))  # (1 s: 1-Hz bins)
    assert set(np.flatnonzero(spec > 1e-3 * spec.max())) == set(range(60, 2501, 60))
    capsys.readouterr()
    traj = tmp_path / "t.csv"
    traj.write_text("t,x,y,z\n0,1,1,0\n1,1,-1,0\n")
    for extra, msg in (([f"--trajectory={traj}"], "--hum applies to a static --source only"),
                       (["--source", src, "--hum", "70"], "hum_db must be")):
        bad = ["simulate", str(tmp_path / "b.wav"), "--array", "two-mic", *extra]
        if extra[0].startswith("--trajectory"):
            bad += ["--hum", "0"]
        assert main(bad) == 2
        err = capsys.readouterr().err
        assert msg in err and err.count("\n") == 1


def test_simulate_hum_hz_without_a_harmonic_is_refused_before_any_work(tmp_path, capsys):
    """--hum-hz 0 or one whose harmonics all lie above 2.5 kHz: one error line, exit 2, no
    file written."""
    for hz, msg in (("0", "hum_hz must be a finite number > 0"),
                    ("9000", "no harmonic of 9000 Hz lies below 2500 Hz")):
        out = tmp_path / "h.wav"
        assert main(["simulate", str(out), "--array", "two-mic", "--source", "1,1,0",
                     "--hum", "0", "--hum-hz", hz]) == 2
        err = capsys.readouterr().err
        assert msg in err and err.count("\n") == 1 and not out.exists()


def test_simulate_hum_hz_needs_hum(tmp_path, capsys):
    """--hum-hz without --hum was ignored: exit 0 and a recording without any hum (its truth
    without hum_db / hum_hz), where the README's `--hum DB --hum-hz 50|60` pair was meant;
    now one error line, exit 2, no file written. With --hum, --hum-hz defaults to 50 Hz."""
    out = tmp_path / "h.wav"
    base = ["simulate", str(out), "--array", "two-mic", "--source", "1,1,0", "--duration", "1"]
    assert main([*base, "--hum-hz", "60"]) == 2
    out_, err = capsys.readouterr()
    assert err == ("hearsee: error: --hum-hz sets the fundamental of the mains hum that --hum "
                   "DB adds; give --hum with it\n")
    assert list(tmp_path.iterdir()) == []
    assert main([*base, "--hum", "0"]) == 0
    truth = json.loads(out.with_suffix(".json").read_text())
    assert truth["hum_db"] == 0.0 and truth["hum_hz"] == 50.0
