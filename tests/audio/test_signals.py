import os
import warnings

import numpy as np
import pytest
import soundfile as sf

from hearsee.audio.arrays import MicArray
from hearsee.audio.signals import (
    VOICE_F0_HZ,
    load_wav,
    make_signal,
    read_recording,
    synthetic_voice,
    white_noise,
    write_recording,
)
from hearsee.errors import (
    AudioInputError,
    ClippingWarning,
    ConfigError,
    DegenerateInputWarning,
    HearseeError,
    InputFileError,
    TruncatedFileWarning,
)

FS = 16000


def _f0_autocorr(y, fs, frame=1024):
    """Median F0 (Hz) of the loud frames from the autocorrelation peak in 70-400 Hz."""
    ests = []
    lo, hi = int(fs / 400), int(fs / 70)
    for s in range(0, len(y) - frame, frame // 2):
        f = y[s:s + frame] - y[s:s + frame].mean()
        if np.mean(f**2) < 0.3:
            continue
        r = np.correlate(f, f, "full")[frame - 1:]
        ests.append(fs / (lo + np.argmax(r[lo:hi])))
    return float(np.median(ests))


@pytest.mark.parametrize("kind", ["male", "female"])
def test_voice_f0_power_and_pauses(kind):
    y = synthetic_voice(kind, 2.0, FS, rng=3)
    assert y.shape == (2 * FS,)
    assert np.mean(y**2) == pytest.approx(1.0)
    assert _f0_autocorr(y, FS) == pytest.approx(VOICE_F0_HZ[kind], rel=0.10)
    silent = np.mean(y == 0.0)
    assert 0.05 < silent < 0.6  # pauses between syllables, but mostly voiced


def test_voice_is_deterministic_and_has_formant_energy():
    a = synthetic_voice("female", 1.0, FS, rng=7)
    b = synthetic_voice("female", 1.0, FS, rng=7)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, synthetic_voice("female", 1.0, FS, rng=8))
    spec = np.abs(np.fft.rfft(a)) ** 2
    f = np.fft.rfftfreq(len(a), 1 / FS)
    # speech-like: most energy below 4 kHz, yet some above 1 kHz (F2/F3)
    assert spec[f < 4000].sum() / spec.sum() > 0.9
    assert spec[(f > 1000) & (f < 4000)].sum() / spec.sum() > 0.02


def test_voice_bad_args():
    with pytest.raises(ConfigError):
        synthetic_voice("child", 1.0, FS)
    for kind in (["male"], {"kind": "male"}):  # (builtin TypeError "unhashable type")
        with pytest.raises(ConfigError, match="unknown voice kind"):
            synthetic_voice(kind, 1.0, FS)
    with pytest.raises(ConfigError):
        synthetic_voice("male", -1.0, FS)
    # (a numeric string raised numpy's TypeError before 2026-11-26)
    for dur, fs in (("1.0", FS), (True, FS), (1.0, "16000"), (1.0, None)):
        with pytest.raises(ConfigError, match="duration|sample rate"):
            white_noise(dur, fs, rng=0)


def test_make_signal_kinds_and_file(tmp_path):
    assert make_signal("noise", 0.5, FS, rng=1).shape == (FS // 2,)
    np.testing.assert_array_equal(make_signal("noise", 0.5, FS, rng=1), white_noise(0.5, FS, 1))
    assert make_signal("male", 0.5, FS, rng=1).shape == (FS // 2,)
    # a 0.3 s 44.1 kHz stereo file -> looped to 1 s at 16 kHz, unit power
    t = np.arange(int(0.3 * 44100)) / 44100
    tone = 0.5 * np.sin(2 * np.pi * 440 * t)
    path = tmp_path / "tone.wav"
    sf.write(path, np.column_stack([tone, tone]), 44100)
    y = make_signal(path, 1.0, FS)
    assert y.shape == (FS,)
    assert np.mean(y**2) == pytest.approx(1.0)
    spec = np.abs(np.fft.rfft(y[:4800]))
    assert np.fft.rfftfreq(4800, 1 / FS)[np.argmax(spec)] == pytest.approx(440, abs=5)
    with pytest.raises(ConfigError, match="unknown signal"):
        make_signal("pink", 1.0, FS)
    with pytest.raises(InputFileError):
        make_signal(tmp_path / "missing.wav", 1.0, FS)


def test_load_wav_resamples(tmp_path):
    path = tmp_path / "a.wav"
    x = 0.3 * np.sin(2 * np.pi * 1000 * np.arange(48000) / 48000)
    sf.write(path, x, 48000)
    y, fs = load_wav(path, fs=16000)
    assert fs == 16000 and len(y) == 16000
    ref = 0.3 * np.sin(2 * np.pi * 1000 * np.arange(16000) / 16000)
    np.testing.assert_allclose(y[200:-200], ref[200:-200], atol=2e-3)
    y2, fs2 = load_wav(path)
    assert fs2 == 48000 and len(y2) == 48000


def _write(path, x, fs=FS, subtype="FLOAT"):
    sf.write(path, np.asarray(x).T, fs, subtype=subtype)
    return path


def test_read_write_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    x = 0.1 * rng.standard_normal((3, 4000))
    p = write_recording(tmp_path / "r.wav", x, FS)
    y, fs = read_recording(p, n_channels=3, fs=FS)
    assert fs == FS and y.dtype == np.float64 and y.shape == (3, 4000)
    np.testing.assert_allclose(y, x, atol=1e-7)
    write_recording(tmp_path / "p.wav", x, FS, subtype="PCM_16")
    assert sf.info(str(tmp_path / "p.wav")).subtype == "PCM_16"
    y16, _ = read_recording(tmp_path / "p.wav", MicArray.from_preset("three-mic"))
    np.testing.assert_allclose(y16, x, atol=1 / 32768 + 1e-9)


def test_a_file_name_that_is_not_utf8_is_read_and_written(tmp_path):
    """A Linux file name is bytes: soundfile encoded a str name as strict UTF-8, and a
    recording named b"x\xff.wav" was "not an audio file" (and could not be written)."""
    p = tmp_path / os.fsdecode(b"x\xff.wav")
    x = 0.1 * np.random.default_rng(1).standard_normal((2, 800))
    write_recording(p, x, FS, subtype="PCM_16")
    assert os.fsencode(p.name) in os.listdir(os.fsencode(tmp_path))
    y, fs = read_recording(p, n_channels=2, fs=FS)
    assert fs == FS and y.shape == (2, 800)
    np.testing.assert_allclose(y, x, atol=1 / 32768 + 1e-9)


def test_read_recording_bad_inputs(tmp_path):
    good = 0.1 * np.random.default_rng(1).standard_normal((2, 2000))
    with pytest.raises(InputFileError, match="not found"):
        read_recording(tmp_path / "nope.wav")
    with pytest.raises(InputFileError, match="is a folder, expected an audio file"):
        read_recording(tmp_path)
    text = tmp_path / "notes.wav"
    text.write_text("this is not audio\n" * 50)
    with pytest.raises(AudioInputError, match="not an audio file"):
        read_recording(text)
    p = _write(tmp_path / "two.wav", good)
    with pytest.raises(AudioInputError,
                       match="recording has 2 channels but array 'three-mic' has 3 microphones"):
        read_recording(p, MicArray.from_preset("three-mic"))
    with pytest.raises(AudioInputError, match="2 channels but 4 were expected"):
        read_recording(p, n_channels=4)
    with pytest.raises(AudioInputError, match="sampled at 16000 Hz but 48000 Hz"):
        read_recording(p, fs=48000)
    y, fs = read_recording(p, fs=48000, resample=True)
    assert fs == 48000 and y.shape == (2, 6000)
    with pytest.raises(AudioInputError, match="too short"):
        read_recording(_write(tmp_path / "short.wav", good[:, :10]))
    with pytest.raises(AudioInputError, match="too short"):
        read_recording(p, min_samples=5000)
    with warnings.catch_warnings():  # an empty file: the one error, no numpy warning first
        warnings.simplefilter("error")
        with pytest.raises(AudioInputError, match=r"too short \(0 samples"):
            read_recording(_write(tmp_path / "empty.wav", good[:, :0]))
    bad = good.copy()
    bad[1, 7] = np.nan
    with pytest.raises(AudioInputError, match="NaN"):
        read_recording(_write(tmp_path / "nan.wav", bad))
    bad[1, 7] = np.inf
    with pytest.raises(AudioInputError, match="NaN or infinite"):
        read_recording(_write(tmp_path / "inf.wav", bad))
    with pytest.raises(AudioInputError, match="silent"):
        read_recording(_write(tmp_path / "zero.wav", np.zeros((2, 2000)), subtype="PCM_16"))
    dead = good.copy()
    dead[1] = 0
    with pytest.raises(AudioInputError, match="channel 1 silent"):
        read_recording(_write(tmp_path / "dead.wav", dead))
    # every one of them is a HearseeError (the CLI's one-line error path)
    assert issubclass(AudioInputError, HearseeError) and issubclass(InputFileError, HearseeError)


def test_a_constant_or_far_too_quiet_channel_is_named(tmp_path):
    """A channel holding one constant value (an input with an offset and no microphone) read
    as "no frame holds a detectable source"; one 100 dB below the others (a disconnected
    microphone's preamplifier noise) gave no direction and no word."""
    from hearsee.errors import DegenerateInputWarning

    rng = np.random.default_rng(11)
    x = 0.1 * rng.standard_normal((3, 8000))
    flat = x.copy()
    flat[2] = 0.01
    with pytest.raises(AudioInputError, match="channel 2 holds one constant value throughout"):
        read_recording(_write(tmp_path / "flat.wav", flat))
    flat[0] = -0.2
    with pytest.raises(AudioInputError, match="channels 0, 2 hold one constant value"):
        read_recording(_write(tmp_path / "flat2.wav", flat))
    quiet = x.copy()
    quiet[1] *= 1e-5  # 100 dB down
    with pytest.warns(DegenerateInputWarning, match="channel 1 is at least 100 dB below the "
                                                    "loudest channel: a disconnected"):
        read_recording(_write(tmp_path / "quiet.wav", quiet))
    # a gain mismatch of 30 dB and a few corrupt samples are not a dead microphone
    fine = x.copy()
    fine[1] *= 10 ** (-30 / 20)
    fine[2, 100:105] = 1e6
    with warnings.catch_warnings():
        warnings.simplefilter("error", DegenerateInputWarning)
        got, _ = read_recording(_write(tmp_path / "fine.wav", fine))
    np.testing.assert_allclose(got, fine, rtol=1e-6)


def test_a_disconnected_input_flipping_a_bit_now_and_then_is_named_without_inf(tmp_path):
    """A disconnected 16-bit input: zeros but for a 1-LSB flip in one sample of 20 (not
    constant, so not stuck). Its level (90th percentile of |x - median|) is 0: the warning
    read "at least inf dB below the loudest channel", after numpy's RuntimeWarning (divide by
    zero), which the CLI printed as a warning of its own."""
    from hearsee.errors import DegenerateInputWarning

    rng = np.random.default_rng(0)
    x = np.zeros((2, 2 * FS))
    x[0] = 0.1 * rng.standard_normal(2 * FS)
    flip = rng.random(2 * FS) < 0.05
    x[1, flip] = rng.choice([-1.0, 1.0], flip.sum()) / 32768
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        read_recording(_write(tmp_path / "dead.wav", x, subtype="PCM_16"), 2)
    said = [str(w.message) for w in got]
    assert [w.category for w in got] == [DegenerateInputWarning], said
    assert "channel 1 is nearly silent beside the loudest channel" in said[0]
    assert "inf" not in said[0]


def test_two_channels_holding_one_signal_are_named(tmp_path):
    """A mono input copied to two channels (as many sound cards present a mono microphone)
    gave a two-microphone pair a TDOA of 0 -- a source straight ahead, confidence high --
    without a word. A copy at any gain or polarity, re-quantised to 16 bits, is named; two
    microphones 2 cm apart hearing a source 5 deg off their bisecting plane (noise-free) are
    not."""
    from hearsee.audio.arrays import MicArray
    from hearsee.audio.signals import duplicate_channels
    from hearsee.errors import DegenerateInputWarning
    from hearsee.sim.audio import simulate_recording

    rng = np.random.default_rng(12)
    x = 0.1 * rng.standard_normal((4, 8000))
    x[3] = -0.3 * x[1]
    with pytest.warns(DegenerateInputWarning, match="channels 1 and 3 hold the same signal"):
        read_recording(_write(tmp_path / "copy.wav", x, subtype="PCM_16"))
    assert duplicate_channels(x) == [(1, 3)]
    y = x.copy()
    y[2] = y[0]
    assert duplicate_channels(y) == [(0, 2), (1, 3)]
    close = MicArray([[0.0, -0.01, 0.0], [0.0, 0.01, 0.0]], name="close")
    a = np.radians(5.0)
    z, _ = simulate_recording(close, [2 * np.cos(a), 2 * np.sin(a), 0.0], signal="male",
                              duration_s=1.0, seed=1)
    assert duplicate_channels(z) == []
    with warnings.catch_warnings():
        warnings.simplefilter("error", DegenerateInputWarning)
        read_recording(_write(tmp_path / "close.wav", z))
    # a quiet copy re-quantised to 16 bits: named by its rounding (the coefficient alone
    # missed copies peaking below about -25 dBFS); the two-mic preset's microphones (15 cm)
    # hearing a source 3 deg off their bisecting plane at that level are not
    quiet = np.stack([z[0], 0.7 * z[0]]) / np.abs(z[0]).max() * 10 ** (-45 / 20)
    with pytest.warns(DegenerateInputWarning, match="channels 0 and 1 hold the same signal"):
        read_recording(_write(tmp_path / "quiet-copy.wav", quiet, subtype="PCM_16"))
    a3 = np.radians(3.0)
    w, _ = simulate_recording("two-mic", [2 * np.cos(a3), 2 * np.sin(a3), 0.0], signal="male",
                              duration_s=1.0, seed=1)
    w = w / np.abs(w).max() * 10 ** (-45 / 20)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DegenerateInputWarning)
        read_recording(_write(tmp_path / "quiet-pair.wav", w, subtype="PCM_16"))
    # float samples of any size: a copy at 1e200 is named, and nothing overflows (squared in
    # the norm, they were numpy's RuntimeWarning, which the CLI printed)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        assert duplicate_channels(1e200 * x) == [(1, 3)]
        assert duplicate_channels(1e200 * y) == [(0, 2), (1, 3)]
    # one channel, constant channels: nothing to pair
    assert duplicate_channels(x[:1]) == []
    c = np.vstack([x[:1], np.full((2, 8000), 0.02)])
    assert duplicate_channels(c) == []


def test_read_recording_warns_on_clipping(tmp_path):
    x = np.clip(2.0 * np.random.default_rng(2).standard_normal((2, 4000)), -1, 1)
    p = _write(tmp_path / "clip.wav", x, subtype="PCM_16")
    with pytest.warns(ClippingWarning, match="clipped"):
        read_recording(p)
    ok = _write(tmp_path / "ok.wav", 0.1 * x)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_recording(ok)
    # read at another rate: the clipping is in the file's samples, before resampling (whose
    # low-pass smooths the flat tops below full scale)
    rng = np.random.default_rng(3)
    y = np.clip(0.3 * rng.standard_normal((2, 48000)), -1, 1)  # ~0.1 % beyond +-1 ...
    y[:, ::200] = np.sign(y[:, ::200] + 1e-9)  # ... plus 0.5 % set to full scale
    p48 = _write(tmp_path / "clip48.wav", y, fs=48000, subtype="PCM_16")
    with pytest.warns(ClippingWarning, match="clipped"):
        read_recording(p48, fs=16000, resample=True)


def test_loud_float_recordings_are_not_called_clipped(tmp_path):
    """A float file may go beyond +-1 without clipping: a noise at RMS 3 (~75 % of its samples
    beyond 1) warned before 2026-11-26. Flat tops at its own peak still warn."""
    x = 3.0 * np.random.default_rng(4).standard_normal((2, 8000))
    p = _write(tmp_path / "loud.wav", x, subtype="FLOAT")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        y, _ = read_recording(p)
    np.testing.assert_allclose(y, x.astype(np.float32), rtol=0, atol=0)
    flat = _write(tmp_path / "loud_clipped.wav", np.clip(x, -4.0, 4.0), subtype="FLOAT")
    with pytest.warns(ClippingWarning, match="clipped"):
        read_recording(flat)


def test_a_loud_float_chirp_is_not_called_clipped(tmp_path):
    """A float file's smooth wave beyond full scale has no flat top, but near its crests its
    samples pass 0.999 of its peak: an unclipped chirp (200 Hz - 6 kHz) at amplitude 2 read
    "2.77 % of the samples are clipped". The same chirp clipped at 1.5 still warns."""
    from scipy.signal import chirp

    t = np.arange(2 * FS) / FS
    s = 2.0 * chirp(t, 200, 2, 6000)
    x = np.stack([np.concatenate([np.zeros(3), s[:-3]]), s])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_recording(_write(tmp_path / "chirp.wav", x))
    with pytest.warns(ClippingWarning, match="clipped"):
        read_recording(_write(tmp_path / "clipped.wav", np.clip(x, -1.5, 1.5)))


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_a_wav_file_through_a_pipe_is_read(tmp_path):
    """A WAV file given through a pipe (a named FIFO, or the shell's <(sox ...)): soundfile
    reads a stream that cannot seek only by a count of frames, so it was refused as "not an
    audio file or a format libsndfile cannot read (frames must be specified for non-seekable
    files)". Read in blocks it gives the file's samples."""
    import threading

    x = 0.1 * np.random.default_rng(8).standard_normal((2, 3000))
    data = _write(tmp_path / "x.wav", x, subtype="PCM_16").read_bytes()
    fifo = tmp_path / "pipe.wav"
    os.mkfifo(fifo)

    def feed():
        with open(fifo, "wb") as f:
            f.write(data)

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    got, fs = read_recording(fifo, 2)
    writer.join(5)
    want, _ = read_recording(tmp_path / "x.wav", 2)
    assert fs == FS
    np.testing.assert_array_equal(got, want)


def test_synthetic_voice_too_short_is_a_config_error():
    for seed in range(4):  # the first syllable starts 20-80 ms in
        with pytest.raises(ConfigError, match="too short"):
            synthetic_voice("male", 0.01, 16000, rng=seed)
        with pytest.raises(ConfigError, match="too short"):
            make_signal("female", 0.015, 16000, np.random.default_rng(seed))


def test_read_recording_checks_min_samples_and_resample(tmp_path):
    """min_samples "x", None or NaN were builtin ValueError / TypeError (int()); resample="no"
    was taken by its truth and resampled."""
    p = _write(tmp_path / "r.wav", 0.1 * np.random.default_rng(3).standard_normal((2, 800)))
    for bad in ("x", None, float("nan"), -1, 2.5):
        with pytest.raises(ConfigError, match="min_samples must be an integer >= 0"):
            read_recording(p, 2, min_samples=bad)
    with pytest.raises(ConfigError, match="resample must be True or False"):
        read_recording(p, 2, fs=8000, resample="no")
    assert read_recording(p, 2, min_samples=np.int64(800))[0].shape == (2, 800)


def test_write_recording_refusals(tmp_path):
    x = 0.1 * np.ones((2, 100))
    src = _write(tmp_path / "in.wav", x)
    with pytest.raises(ConfigError, match="refusing to overwrite"):
        write_recording(src, x, FS, protect=[src])
    with pytest.raises(ConfigError, match="refusing to overwrite"):
        write_recording(tmp_path / "." / "in.wav", x, FS, protect=str(src))
    with pytest.raises(InputFileError, match="does not exist"):
        write_recording(tmp_path / "no" / "out.wav", x, FS)
    with pytest.raises(AudioInputError, match="full scale"):
        write_recording(tmp_path / "loud.wav", 20 * x, FS, subtype="PCM_16")
    with pytest.raises(AudioInputError, match="NaN"):
        write_recording(tmp_path / "nan.wav", x * np.nan, FS)
    with pytest.raises(InputFileError, match="a protected input's path must be a file name"):
        write_recording(tmp_path / "sub.wav", x, FS, protect=3)  # (a builtin TypeError)
    for subtype in (None, 16):  # (a builtin AttributeError: 'NoneType' has no 'upper')
        with pytest.raises(AudioInputError, match="subtype must be a soundfile subtype name"):
            write_recording(tmp_path / "sub.wav", x, FS, subtype=subtype)
    assert not (tmp_path / "sub.wav").exists()
    assert sf.info(str(src)).channels == 2  # untouched


def test_write_recording_refuses_samples_by_channels(tmp_path):
    """(n, 2) data, the layout transposed, was soundfile's misleading "Format not recognised"."""
    for ext in ("wav", "flac"):
        with pytest.raises(AudioInputError, match=r"\(n_channels, n_samples\).*\(16000, 2\)"):
            write_recording(tmp_path / f"t.{ext}", 0.1 * np.ones((16000, 2)), FS)
        assert not (tmp_path / f"t.{ext}").exists()
    x = 0.1 * np.ones((1024, 4))  # as many channels as a WAV file holds: written as before
    assert sf.info(str(write_recording(tmp_path / "wide.wav", x, FS))).channels == 1024


def test_a_file_without_read_permission_is_an_input_file_error():
    """read_recording's InputFileError for a file that "cannot be opened": libsndfile names no
    reason for a file the system refuses (no read permission), so it was an AudioInputError,
    "not an audio file or a format libsndfile cannot read (System error.); use a WAV or FLAC
    file". Run as root every file is readable: a child process drops to user nobody."""
    import tempfile

    import soundfile  # noqa: F401 (imported before the child drops its rights)

    with tempfile.TemporaryDirectory() as d:  # (under /tmp: other users may reach it)
        os.chmod(d, 0o755)
        p = _write(os.path.join(d, "locked.wav"), 0.1 * np.ones((2, 800)))
        os.chmod(p, 0)
        if os.geteuid() != 0:
            with pytest.raises(InputFileError, match=r"locked.wav: cannot be read \(Perm"):
                read_recording(p, 2)
            return
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child, as user nobody
            try:
                os.setgid(65534)
                os.setuid(65534)
                try:
                    read_recording(p, 2)
                    said = b"read"
                except Exception as exc:  # noqa: BLE001
                    said = f"{type(exc).__name__}: {exc}".encode()
                os.write(w, said)
            finally:
                os._exit(0)
        os.close(w)
        said = os.read(r, 4096).decode()
        os.close(r)
        os.waitpid(pid, 0)
    assert said == f"InputFileError: {p}: cannot be read (Permission denied)", said


def test_load_wav_and_make_signal_bad_files(tmp_path):
    junk = tmp_path / "junk.wav"
    junk.write_bytes(b"RIFF\x00\x00garbage" * 10)
    with pytest.raises(AudioInputError, match="not an audio file"):
        load_wav(junk)
    with pytest.raises(AudioInputError, match="not an audio file"):
        make_signal(junk, 0.5, FS)
    silent = _write(tmp_path / "silent.wav", np.zeros((1, 800)))
    with pytest.raises(AudioInputError, match="silent"):
        make_signal(silent, 0.5, FS)
    nan = np.ones((1, 800))
    nan[0, 10] = np.nan
    sf.write(tmp_path / "nan.wav", nan.T, FS, subtype="FLOAT")
    with pytest.raises(AudioInputError, match="nan.wav: the file contains NaN"):
        make_signal(tmp_path / "nan.wav", 0.5, FS)
    # a stereo file whose channels cancel in the mono mixdown: its rounding residue was scaled
    # to full level and simulated as the source; a stereo file of two voices is a source
    v = np.random.default_rng(7).standard_normal(8000) * 0.1
    sf.write(tmp_path / "cancel.wav", np.c_[v, -v], FS, subtype="PCM_16")
    with pytest.raises(AudioInputError, match="cancel when mixed to mono"):
        make_signal(tmp_path / "cancel.wav", 0.5, FS)
    sf.write(tmp_path / "two.wav", np.c_[v, np.roll(v, 100)], FS, subtype="PCM_16")
    assert np.mean(make_signal(tmp_path / "two.wav", 0.5, FS) ** 2) == pytest.approx(1.0)
    empty = tmp_path / "empty.wav"
    sf.write(empty, np.zeros((0, 1)), FS)
    with pytest.raises(AudioInputError, match="no samples"):
        load_wav(empty)


def test_resampling_an_odd_rate_ratio_says_what_to_do():
    from hearsee.audio.signals import resample

    with pytest.raises(AudioInputError, match="common rate"):
        resample(np.zeros((1, 4799)), 47999, 16000)
    assert resample(np.zeros((1, 4800)), 48000, 16000).shape == (1, 1600)


@pytest.mark.parametrize("subtype", ["PCM_U8", "ULAW", "ALAW"])
def test_read_recording_warns_on_a_file_clipped_below_one(subtype, tmp_path):
    """An 8-bit WAV's largest positive sample reads as 127/128 = 0.992, a mu-law one's as
    0.980 (A-law 0.984), below the 0.999 clip level: a recording flat-topped there (here
    ~30 % of the samples) gave no warning."""
    t = np.arange(16000) / 16000
    x = np.clip(1.5 * np.sin(2 * np.pi * 200 * t), -0.9, 1.0)  # only the positive tops clip
    x = np.stack([x, np.roll(x, 3)])  # (a delayed copy: two microphones, not one twice)
    p = _write(tmp_path / "clip8.wav", x, subtype=subtype)
    with pytest.warns(ClippingWarning, match="clipped"):
        read_recording(p)
    ok = _write(tmp_path / "ok8.wav", 0.5 * x, subtype=subtype)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_recording(ok)


def test_write_recording_refuses_a_bad_sample_rate_before_writing(tmp_path):
    """fs=inf raised a builtin OverflowError from int(round(fs)); a NaN or a string went to
    libsndfile. Nothing is written."""
    x = 0.1 * np.ones((2, 100))
    # (16000.7: a header of 16001 Hz, written without a word)
    for fs in (float("inf"), float("nan"), "16000", -16000.0, 1e10, 16000.7):
        out = tmp_path / "out.wav"
        with pytest.raises(AudioInputError, match="sample rate"):
            write_recording(out, x, fs)
        assert not out.exists()
    assert sf.info(write_recording(tmp_path / "whole.wav", x, 16000.0)).samplerate == 16000


def test_a_wav_cut_short_is_read_with_a_warning(tmp_path, capsys):
    """A WAV whose data chunk ends before its header's size (a recording cut short, a copy
    interrupted) was read as the samples present without a word; now with a
    TruncatedFileWarning (and `hearsee localize` prints it as one line). Intact files and the
    streaming size 0xFFFFFFFF of a recorder writing to a pipe give no warning."""
    from hearsee.cli import main

    s = np.random.default_rng(5).uniform(-0.5, 0.5, 8002)
    x = np.stack([s[2:], s[:-2]])  # one source, 2 samples (125 us) closer to microphone 0
    full = write_recording(tmp_path / "full.wav", x, FS, subtype="FLOAT")
    data = full.read_bytes()
    cut = tmp_path / "cut.wav"
    cut.write_bytes(data[: 44 + 2 * 4 * 3000 + 58])  # 3000 frames after a <= 58-byte header
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        y, fs = read_recording(full, 2)  # intact: no warning
        np.testing.assert_allclose(y, x, atol=1e-7)
        i = data.index(b"data")
        stream = tmp_path / "stream.wav"
        stream.write_bytes(data[: i + 4] + b"\xff\xff\xff\xff" + data[i + 8:])
        assert read_recording(stream, 2)[0].shape == (2, 8000)
    with pytest.warns(TruncatedFileWarning, match="cut short: its header declares 64000 bytes"
                      ) as told:
        y, fs = read_recording(cut, 2)
    assert told[0].filename == __file__  # (it points at the caller of read_recording)
    assert fs == FS and 3000 <= y.shape[1] < 8000
    np.testing.assert_allclose(y, x[:, : y.shape[1]], atol=1e-7)
    assert main(["localize", str(cut), "--array", "two-mic"]) == 0
    err = capsys.readouterr().err
    assert err.startswith(f"hearsee: warning: {cut}: the file is cut short") and \
        err.count("\n") == 1, err


def test_an_rf64_wav_cut_short_is_read_with_a_warning(tmp_path):
    """An RF64 file (the WAV of more than 4 GiB, suffix .wav; libsndfile writes one with
    format="RF64") declares its data size in the ds64 chunk, its data chunk's own size
    0xFFFFFFFF: cut short, it was read as the samples present without a word. Intact, no
    warning."""
    x = 0.1 * np.random.default_rng(6).standard_normal((2, 8000))
    full = tmp_path / "full.wav"
    sf.write(full, x.T, FS, format="RF64", subtype="PCM_16")
    assert full.read_bytes()[:4] == b"RF64"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_recording(full, 2)[0].shape == (2, 8000)
    cut = tmp_path / "cut.wav"
    cut.write_bytes(full.read_bytes()[:16000])
    with pytest.warns(TruncatedFileWarning, match="cut short: its header declares 32000 bytes"):
        y, _ = read_recording(cut, 2)
    assert 3000 < y.shape[1] < 4000


def test_a_signal_file_too_short_to_loop_is_refused(tmp_path):
    """make_signal loops a short file to the duration: a 1-sample file became a constant (DC)
    signal, simulated and localized as if it were sound. Fewer than MIN_SAMPLES (64, a
    recording's minimum too) samples at the simulation rate are refused; 64 samples of noise
    still loop, repeating exactly."""
    rng = np.random.default_rng(4)
    for n in (1, 2, 63):
        p = _write(tmp_path / f"s{n}.wav", 0.3 * rng.standard_normal((1, n)))
        with pytest.raises(AudioInputError, match=rf"^{p}: the signal is too short to simulate: "
                                                  rf"{n} samples? at 16000 Hz; it is looped"):
            make_signal(p, 0.5, FS)
    with pytest.raises(AudioInputError, match="too short to simulate: 3 samples at 48000 Hz"):
        make_signal(tmp_path / "s1.wav", 0.5, 48000)  # (resampled first)
    from hearsee.audio.signals import MIN_SAMPLES

    assert MIN_SAMPLES == 64
    x = 0.3 * rng.standard_normal(MIN_SAMPLES)
    y = make_signal(_write(tmp_path / "ok.wav", x[None]), 0.5, FS)
    assert y.shape == (FS // 2,) and np.mean(y**2) == pytest.approx(1.0)
    np.testing.assert_allclose(y[MIN_SAMPLES:2 * MIN_SAMPLES], y[:MIN_SAMPLES])
    np.testing.assert_allclose(y[:MIN_SAMPLES] / y[0], x / x[0], rtol=1e-5)


def test_a_signal_file_below_1000_hz_is_refused(tmp_path):
    """A signal file at 1 Hz (a wrong header) was resampled to the simulation's rate: 100
    samples became 1.6 million (and 200000 asked for 23.8 GiB). 1000 Hz is the least."""
    from hearsee.audio.signals import MIN_SIGNAL_FILE_FS_HZ

    assert MIN_SIGNAL_FILE_FS_HZ == 1000
    x = 0.3 * np.random.default_rng(3).standard_normal(100)
    for rate in (1, 999):
        p = tmp_path / f"r{rate}.wav"
        sf.write(p, x, rate)
        with pytest.raises(AudioInputError, match=rf"^{p}: the file's sample rate is {rate} Hz, "
                                                  "below the 1000 Hz a source signal needs"):
            make_signal(p, 0.1, FS)
    sf.write(tmp_path / "r1000.wav", x, 1000)
    assert make_signal(tmp_path / "r1000.wav", 0.1, FS).shape == (1600,)


@pytest.mark.parametrize("rate, fs", [(44100, 16000), (8000, 16000), (16000, 16000),
                                      (48000, 4000)])
def test_make_signal_resamples_only_the_part_of_a_long_file_it_uses(tmp_path, monkeypatch,
                                                                    rate, fs):
    """The whole file was resampled before the trim to the duration (a long file: all of it,
    for 0.1 s). Now only the part used plus the resampler's margin is read and resampled, and
    the signal is the same as from the whole file resampled (scipy's resample_poly here)."""
    from fractions import Fraction

    from scipy.signal import resample_poly

    import hearsee.audio.signals as signals

    stereo = 0.3 * np.random.default_rng(6).standard_normal((20 * rate, 2))  # 20 s
    p = tmp_path / "long.wav"
    sf.write(p, stereo, rate, subtype="DOUBLE")
    sizes = []
    real = signals._resample

    def spy(x, fs_in, fs_out):
        sizes.append(np.shape(x)[-1])
        return real(x, fs_in, fs_out)

    monkeypatch.setattr(signals, "_resample", spy)
    y = make_signal(p, 0.1, fs)
    n = int(0.1 * fs)
    mono = stereo.mean(axis=1)
    r = Fraction(fs, rate)
    ref = resample_poly(mono, r.numerator, r.denominator)[:n] if rate != fs else mono[:n]
    ref = ref / np.sqrt(np.mean(ref**2))
    assert y.shape == (n,)
    np.testing.assert_allclose(y, ref, rtol=1e-12, atol=1e-12)
    # at most the 0.1 s used and a margin of 20 * max(1, rate / fs) + 64 samples went through
    assert all(k <= 0.1 * rate + 20 * max(1, rate / fs) + 66 for k in sizes), sizes


@pytest.mark.parametrize("fs", [float("nan"), float("inf"), "16000", -16000.0])
def test_read_recording_and_load_wav_check_fs(tmp_path, fs):
    """A sample rate that is no positive number: NaN, inf and text were builtin ValueError,
    OverflowError and TypeError (``int(round(fs))`` against the file's rate)."""
    p = _write(tmp_path / "r.wav", 0.1 * np.random.default_rng(1).standard_normal((2, 2000)))
    for resample in (False, True):
        with pytest.raises(AudioInputError, match="sample rate"):
            read_recording(p, 2, fs, resample=resample)
    with pytest.raises(AudioInputError, match="sample rate"):
        load_wav(p, fs)


@pytest.mark.parametrize("n", ["a", 2.5, 0, True])
def test_read_recording_checks_n_channels(tmp_path, n):
    """A channel count that is no whole number >= 1: "a" was a builtin ValueError, 2.5 was
    taken as 2 (a 2-channel file passed)."""
    p = _write(tmp_path / "r.wav", 0.1 * np.random.default_rng(1).standard_normal((2, 2000)))
    with pytest.raises(ConfigError, match="n_channels"):
        read_recording(p, n)


def test_channel_faults_and_write_recording_refuse_what_is_no_recording(tmp_path):
    """channel_faults of an empty or 1-D array was numpy's ValueError / AxisError (NaN gave
    garbage levels); write_recording of text numpy's ValueError. A silent channel beside a
    sounding one is still found."""
    from hearsee.audio.signals import channel_faults, write_recording

    for x in (np.zeros((4, 0)), np.zeros(100), [["a"]]):
        with pytest.raises(AudioInputError):
            channel_faults(x)
    with pytest.raises(AudioInputError, match="NaN"):
        channel_faults(np.array([[0.0, np.nan, 1.0]] * 2))
    with pytest.raises(AudioInputError, match="real numbers"):
        write_recording(tmp_path / "x.wav", "x", 16000)
    flat, quiet, _ = channel_faults(np.vstack([np.zeros(100),
                                               np.random.default_rng(1).standard_normal(100)]))
    assert flat.tolist() == [0] and quiet.size == 0


def test_generators_and_the_resampler_refuse_absurd_sample_counts():
    """A rate of 1e12 Hz asked the generators for terabytes, resampling to 1e9 Hz likewise (a
    MemoryError); now a typed error before any allocation. Ordinary rates still work."""
    from hearsee.audio.signals import mains_hum, resample, synthetic_voice

    for make in (lambda: white_noise(0.5, 1e12, rng=0), lambda: mains_hum(0.5, 1e12),
                 lambda: synthetic_voice("male", 0.5, 1e12, rng=0)):
        with pytest.raises(ConfigError, match="more than the generators make"):
            make()
    with pytest.raises(AudioInputError, match="samples per channel"):
        resample(np.zeros(16000), 16000, 1e9)
    assert resample(np.zeros((2, 16000)), 16000, 48000).shape == (2, 48000)
    assert resample(np.zeros(48000), 48000, 16000).shape == (16000,)
    for one in (np.float64(0.5), 0.5):  # (no samples axis: scipy's builtin IndexError)
        with pytest.raises(AudioInputError, match="single number"):
            resample(one, 16000, 8000)


# ------------------------------------------------------------ one file per microphone
def _per_mic_files(tmp_path, x, fs=FS, subtype="FLOAT", split=(1, 1, 1)):
    """``x`` (n_ch, n) written as files of ``split`` channels each; their paths."""
    paths, k = [], 0
    for i, n in enumerate(split):
        p = tmp_path / f"mic{i}.wav"
        sf.write(p, x[k:k + n].T, fs, subtype=subtype)
        paths.append(p)
        k += n
    return paths


def test_one_file_per_microphone_is_the_multichannel_recording(tmp_path):
    rng = np.random.default_rng(241)
    s = rng.standard_normal(FS + 7) * 0.1
    x = np.stack([s[7:], s[3:-4], s[:-7]])  # known delays of 0, 4 and 7 samples
    whole = tmp_path / "whole.wav"
    sf.write(whole, x.T, FS, subtype="FLOAT")
    ref, fs = read_recording(whole, 3)
    for split in ((1, 1, 1), (1, 2), (2, 1)):
        (tmp_path / "s").mkdir(exist_ok=True)
        paths = _per_mic_files(tmp_path / "s", x, split=split)
        got, fs2 = read_recording(paths, 3)
        assert fs2 == fs == FS
        np.testing.assert_array_equal(got, ref)  # the files' channels in the order given
        got, _ = read_recording([str(p) for p in paths[::-1]], 3)  # names as text, reversed
        assert not np.array_equal(got, ref)
    # one file in a list is that file
    np.testing.assert_array_equal(read_recording([whole], 3)[0], ref)


def test_one_file_per_microphone_refusals(tmp_path):
    rng = np.random.default_rng(242)
    x = rng.standard_normal((2, FS)) * 0.1
    a, b = _per_mic_files(tmp_path, x, split=(1, 1))
    sf.write(tmp_path / "short.wav", x[1, :-5], FS, subtype="FLOAT")
    with pytest.raises(AudioInputError, match=r"different numbers of samples \(.*mic0.wav "
                       rf"{FS}, .*short.wav {FS - 5}\)"):
        read_recording([a, tmp_path / "short.wav"])
    sf.write(tmp_path / "b8k.wav", x[1, ::2], FS // 2, subtype="FLOAT")
    with pytest.raises(AudioInputError, match="different rates .*b8k.wav 8000 Hz"):
        read_recording([a, tmp_path / "b8k.wav"])
    with pytest.raises(AudioInputError, match="2 channels but array 'three-mic' has 3 "
                       "microphones .*file by file"):
        read_recording([a, b], MicArray.from_preset("three-mic"))
    sf.write(tmp_path / "zero.wav", np.zeros(FS), FS, subtype="FLOAT")
    with pytest.raises(AudioInputError, match=r"zero.wav: recording is silent"):
        read_recording([a, tmp_path / "zero.wav"])
    with pytest.raises(InputFileError, match="nothere.wav: audio file not found"):
        read_recording([a, tmp_path / "nothere.wav"])
    with pytest.raises(InputFileError, match="one audio file or more"):
        read_recording([])
    # resampled to one rate when asked: both at 16 kHz, as long as each other
    sf.write(tmp_path / "a8k.wav", x[0, ::2], FS // 2, subtype="FLOAT")
    got, fs = read_recording([tmp_path / "a8k.wav", tmp_path / "b8k.wav"], 2, fs=FS,
                             resample=True)
    assert fs == FS and got.shape == (2, FS)


def test_one_file_per_microphone_compares_the_files_channels(tmp_path):
    rng = np.random.default_rng(243)
    x = rng.standard_normal((2, FS)) * 0.1
    a, b = _per_mic_files(tmp_path, x, split=(1, 1))
    with pytest.warns(DegenerateInputWarning, match=r"mic0.wav \+ .*mic0.wav: channels 0 and 1 "
                      "hold the same signal"):
        read_recording([a, a])
    sf.write(tmp_path / "faint.wav", x[1] * 1e-4, FS, subtype="FLOAT")
    with pytest.warns(DegenerateInputWarning, match=r"mic0.wav \+ .*faint.wav: channel 1 is "
                      "at least"):
        read_recording([a, tmp_path / "faint.wav"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_recording([a, b])  # two microphones of their own: no word


@pytest.mark.shared
def test_the_real_two_file_recording_reads_as_one(shared_data):
    """The real 'alexa' pair (one 48 kHz PCM_16 file per microphone, tdoa_2mic) reads as a
    two-channel recording, sample for sample, without any warning (no copy, no quiet channel,
    no clipping: two working microphones)."""
    files = [shared_data / "audio" / "tdoa_2mic" / f"alexa-0{k}.wav" for k in (1, 2)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        x, fs = read_recording(files, 2)
    assert fs == 48000
    for k, f in enumerate(files):
        y, _ = sf.read(f)
        np.testing.assert_array_equal(x[k], y)


# ------------------------------------------------------------ a device's other channels
def test_channels_pick_the_microphones_of_a_larger_recording(tmp_path):
    """A 6-channel ReSpeaker-style file (0: a beam, 1-4: the microphones, 5: a silent playback
    channel): ``channels=[1, 2, 3, 4]`` gives the four microphones, in that order, and the
    silent channel is no error; without it the count is refused, naming ``channels``."""
    rng = np.random.default_rng(244)
    mics = rng.standard_normal((4, FS)) * 0.1
    six = np.vstack([mics.mean(axis=0), mics, np.zeros((1, FS))])
    p = tmp_path / "six.wav"
    sf.write(p, six.T, FS, subtype="FLOAT")
    arr = MicArray.from_preset("respeaker-4")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        x, fs = read_recording(p, arr, channels=[1, 2, 3, 4])
    np.testing.assert_array_equal(x, mics.astype(np.float32))
    x, _ = read_recording(p, arr, channels=(4, 3, 2, 1))
    np.testing.assert_array_equal(x, mics[::-1].astype(np.float32))
    x, _ = read_recording(p, arr, channels=np.arange(1, 5))
    np.testing.assert_array_equal(x, mics.astype(np.float32))
    with pytest.raises(AudioInputError, match="6 channels but array 'respeaker-4' has 4 "
                       "microphones.*choose the microphones' with --channels"):
        read_recording(p, arr)
    for bad, msg in (([1, 2, 3], "3 channels for an array of 4 microphones"),
                     ([1, 2, 2, 3], "must be distinct and >= 0"),
                     ([1, 2, 3, -1], "must be distinct and >= 0"),
                     ([1, 2, 3, 4.0], "expected a list of channel indices"),
                     ([1, 2, 3, 2**63], "is beyond any input"),
                     ("1234", "expected a list of channel indices")):
        with pytest.raises(ConfigError, match=msg):
            read_recording(p, arr, channels=bad)
    with pytest.raises(AudioInputError, match=r"channel 6 asked for, but the recording has 6 "
                       r"channels \(0-5\)"):
        read_recording(p, arr, channels=[1, 2, 3, 6])
    # the checks name the input channels: the silent one picked, a copy picked twice
    with pytest.raises(AudioInputError, match="six.wav: channel 5 silent"):
        read_recording(p, arr, channels=[1, 2, 3, 5])
    six[3] = six[2]
    sf.write(p, six.T, FS, subtype="FLOAT")
    with pytest.warns(DegenerateInputWarning, match="channels 2 and 3 hold the same signal"):
        read_recording(p, arr, channels=[1, 2, 3, 4])


def test_channels_over_several_files(tmp_path):
    """Two stereo files are input channels 0-3, file by file: ``channels=[3, 0]`` is the second
    file's right channel, then the first file's left one; a file none of whose channels is
    asked for is not checked (its silence is no error)."""
    rng = np.random.default_rng(245)
    x = rng.standard_normal((4, FS)) * 0.1
    a, b = tmp_path / "a.wav", tmp_path / "b.wav"
    sf.write(a, x[:2].T, FS, subtype="FLOAT")
    sf.write(b, x[2:].T, FS, subtype="FLOAT")
    got, _ = read_recording([a, b], 2, channels=[3, 0])
    np.testing.assert_array_equal(got, x[[3, 0]].astype(np.float32))
    # the checks name input channels, over the files: b.wav's right channel is channel 3
    sf.write(b, np.column_stack([x[2], np.zeros(FS)]), FS, subtype="FLOAT")
    with pytest.raises(AudioInputError, match=r"b.wav: channel 3 silent"):
        read_recording([a, b])
    sf.write(b, np.zeros((FS, 2)), FS, subtype="FLOAT")
    got, _ = read_recording([a, b], 2, channels=[1, 0])
    np.testing.assert_array_equal(got, x[[1, 0]].astype(np.float32))
    with pytest.raises(AudioInputError, match=r"b.wav: recording is silent"):
        read_recording([a, b])
    with pytest.raises(AudioInputError, match=r"b.wav: channel 2 silent"):  # (only it taken)
        read_recording([a, b], 2, channels=[1, 2])


def test_clipping_over_several_files_is_one_warning(tmp_path):
    """Clipping is measured over every sample taken, as of one file holding them all: three
    clipped mono files give one warning (they gave one each), with the share their
    multichannel file gives."""
    rng = np.random.default_rng(249)
    x = 0.1 * rng.standard_normal((3, FS))  # (10 sigma from full scale: no sample clips)
    x[:, :40] = 1.0  # 0.25 % of each channel at full scale
    files = []
    for k in range(3):
        files.append(tmp_path / f"m{k}.wav")
        sf.write(files[-1], x[k], FS, subtype="PCM_16")
    sf.write(tmp_path / "all.wav", x.T, FS, subtype="PCM_16")
    for rec in (files, tmp_path / "all.wav"):
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            read_recording(rec, 3)
        clip = [w for w in got if issubclass(w.category, ClippingWarning)]
        assert len(clip) == 1 and "0.25 % of the samples are clipped" in str(clip[0].message)


def test_a_lossy_compressed_recording_is_warned_about(tmp_path):
    """A two-microphone recording saved as Ogg Vorbis (its channels coded jointly): localized
    at 0 deg for 56 (a TDOA of 0.1 us for 364 us) without a word. Lossy codecs are told;
    FLAC, lossless, is not."""
    if "OGG" not in sf.available_formats():
        pytest.skip("this libsndfile writes no Ogg")
    s = np.random.default_rng(346).standard_normal(16000)
    x = 0.1 * np.stack([s, np.roll(s, 6)])  # microphone 1 six samples later
    sf.write(tmp_path / "rec.ogg", x.T, 16000, format="OGG", subtype="VORBIS")
    sf.write(tmp_path / "rec.flac", x.T, 16000)
    with pytest.warns(DegenerateInputWarning, match=r"rec\.ogg: lossy-compressed \(VORBIS\): "
                      "the codec can change the time differences"):
        read_recording(tmp_path / "rec.ogg", 2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got, fs = read_recording(tmp_path / "rec.flac", 2)
    assert fs == 16000 and np.allclose(got, x, atol=1e-4)
    with pytest.warns(DegenerateInputWarning, match=r"rec\.ogg \(VORBIS\) is lossy-compressed"):
        read_recording([tmp_path / "rec.flac", tmp_path / "rec.ogg"], 4)
