"""Stationary tonal noise (mains hum, a motor's whine): found, removed, and the TDOAs of what
remains right (hearsee.audio.hum and estimate_tdoas' tonal_noise)."""

import warnings

import numpy as np
import pytest

from hearsee.audio import hum
from hearsee.audio.arrays import MicArray
from hearsee.audio.signals import hum_harmonics, mains_hum
from hearsee.audio.tdoa import estimate_tdoas
from hearsee.errors import ConfigError, TonalNoiseWarning
from hearsee.sim.audio import simulate_recording

FS = 16000


@pytest.fixture(scope="module")
def voice():
    """A male voice 2 m away at azimuth 56 deg (three-mic, free field, 20 dB SNR, 4 s) and its
    truth."""
    src = 2.0 * np.array([np.cos(np.radians(56.0)), np.sin(np.radians(56.0)), 0.3])
    return simulate_recording("three-mic", src, signal="male", duration_s=4.0, fs=FS,
                              snr_db=20, seed=3)


def _with_hum(db: float, array: str = "three-mic", az: float = 56.0) -> tuple:
    """The voice of :func:`voice` (or at ``az`` deg, elevation 0, through ``array``) with a
    60-Hz hum ``db`` dB above it on every channel (``simulate_recording(hum_db=)``)."""
    el = 0.3 if array == "three-mic" else 0.0
    src = 2.0 * np.array([np.cos(np.radians(az)), np.sin(np.radians(az)), el])
    return simulate_recording(array, src, signal="male", duration_s=4.0 if el else 3.0,
                              fs=FS, snr_db=20, seed=3 if el else 5, hum_db=db, hum_hz=60.0)


def test_tonal_bins_flag_a_line_on_every_channel_only():
    """A steady line in bin 10 on both channels is a line; exponential noise bins, a line on
    one channel only, a line below 40 Hz and too few frames are not."""
    rng = np.random.default_rng(12)
    p = rng.exponential(size=(2, 60, 64))
    hz = np.arange(64) * 20.0  # bin 1 = 20 Hz
    p[:, :, 10] = 50.0 * (1 + 0.05 * rng.random((2, 60)))  # a line, both channels
    p[0, :, 20] = 50.0  # one channel only
    p[:, :, 1] = 50.0  # at 20 Hz
    line = hum.tonal_bins(p, hz)
    assert np.flatnonzero(line).tolist() == [10]
    assert not hum.tonal_bins(p[:, :hum.TONAL_MIN_FRAMES - 1], hz).any()
    with pytest.raises(ConfigError, match="n_ch, n_frames, n_bins"):
        hum.tonal_bins(p[0], hz)


def test_line_frequencies_complete_a_comb_and_refine_a_single_line():
    """Runs of line bins become lines at the recording's spectral peaks: three harmonics of
    50.3 Hz (1, 10, 20 of 21) give every harmonic, the 21st too (it peaks out of the noise),
    within 0.05 Hz and no other line; a lone line at 1234.5 Hz itself."""
    n = 4 * FS
    t = np.arange(n) / FS
    rng = np.random.default_rng(13)
    x = 0.01 * rng.standard_normal((2, n)) + mains_hum(4.0, FS, 50.3, rng, top_hz=1100.0)
    hz = np.arange(513) * FS / 1024
    line = np.zeros(513, dtype=bool)
    for f in (50.3, 503.0, 1005.9):  # harmonics 1, 10, 20 only
        line[int(np.round(f / hz[1]))] = True
    got = hum.line_frequencies(x, FS, line, hz)
    assert len(got) == 21 and np.max(np.abs(got - 50.3 * np.arange(1, 22))) < 0.05
    y = 0.01 * rng.standard_normal((2, n)) + np.sin(2 * np.pi * 1234.5 * t)
    one = np.zeros(513, dtype=bool)
    one[int(np.round(1234.5 / hz[1]))] = True
    assert hum.line_frequencies(y, FS, one, hz) == pytest.approx([1234.5], abs=0.1)
    assert hum.line_frequencies(y, FS, np.zeros(513, dtype=bool), hz).size == 0


def test_remove_lines_takes_the_hum_out_and_keeps_the_delay():
    """Noise 3 samples later on channel 1 plus one buzz on both: after the notches the buzz's
    lines are > 30 dB down and the GCC finds the 3-sample delay to 0.05 sample (zero-phase
    notches, the same on every channel, move no TDOA)."""
    rng = np.random.default_rng(14)
    n = 3 * FS
    s = rng.standard_normal(n + 3)
    x = np.stack([s[3:], s[:-3]]) * 0.1
    b = mains_hum(3.0, FS, 60.0, rng, top_hz=2400.0) * np.sqrt(np.mean(x ** 2))  # (as loud)
    dirty = x + b
    clean = hum.remove_lines(dirty, FS, 60.0 * np.arange(1, 41))
    # (the notches are linear: what is left of the buzz is the buzz through them)
    spec = np.abs(np.fft.rfft(hum.remove_lines(b, FS, 60.0 * np.arange(1, 41)) * np.hanning(n)))
    spec_b = np.abs(np.fft.rfft(b * np.hanning(n)))
    k = np.round(60.0 * np.arange(1, 41) * n / FS).astype(int)
    assert 20 * np.log10(np.max(spec[k] / spec_b[k])) < -30
    two = MicArray.from_dict({"microphones": [[0, -0.1, 0], [0, 0.1, 0]]})
    after = estimate_tdoas(clean, FS, two, tonal_noise=False).summary_tdoa_s * FS
    assert after[0] == pytest.approx(-3.0, abs=0.05)  # (channel 0 hears it first)
    assert np.array_equal(hum.remove_lines(x, FS, [FS / 2]), x)  # (at Nyquist: nothing)


def test_a_buzz_louder_than_the_voice_is_filtered_out(voice):
    """A 60-Hz buzz 3 dB above the voice made the summary a source overhead (TDOAs near 0);
    with the hum filtered out the TDOAs are the truth's within 0.3 sample, with one warning
    naming the comb and its lines in tonal_lines_hz."""
    x, truth = voice
    want = np.array(list(truth["tdoa_s"].values())) * FS
    y, _ = _with_hum(3.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        off = estimate_tdoas(y, FS, "three-mic", tonal_noise=False)
    assert np.max(np.abs(off.summary_tdoa_s * FS - want)) > 3.0  # (the failure it fixes)
    with pytest.warns(TonalNoiseWarning, match=r"60\.0 Hz and its harmonics up to 2460 Hz"):
        tf = estimate_tdoas(y, FS, "three-mic")
    assert np.max(np.abs(tf.summary_tdoa_s * FS - want)) < 0.3
    lines = np.array(tf.tonal_lines_hz)
    on = lines[np.abs(lines / 60.0 - np.round(lines / 60.0)) < 0.01]
    assert len(on) == 41 and np.max(np.abs(on - 60.0 * np.arange(1, 42))) < 0.1
    assert tf.wiring_entries()["tonal_lines_hz"] == list(tf.tonal_lines_hz)


@pytest.mark.parametrize("array", ["two-mic", "three-mic"])
def test_a_buzz_is_found_through_short_frames(array):
    """With 16-ms frames (63-Hz bins) the tonal test ran on the analysis' frames, where a 60-Hz
    line shares its bin with the voice's lowest harmonics: the buzz 3 dB above the voice was
    not found and the summary TDOAs were ~6 samples off. The test runs on 64-ms frames
    (hum.TONAL_FRAME_MS) whatever the analysis' frame: the comb is found, the TDOAs right;
    find_lines, given the same short frame, finds it too."""
    y, truth = _with_hum(3.0, array)
    want = np.array(list(truth["tdoa_s"].values())) * FS
    with pytest.warns(TonalNoiseWarning, match=r"60\.0 Hz and its harmonics"):
        tf = estimate_tdoas(y, FS, array, frame_ms=16.0, hop_ms=8.0)
    assert np.max(np.abs(tf.summary_tdoa_s * FS - want)) < 0.3
    lines = np.array(tf.tonal_lines_hz)
    on = lines[np.abs(lines / 60.0 - np.round(lines / 60.0)) < 0.01]
    assert len(on) >= 40 and np.max(np.abs(on[:40] - 60.0 * np.arange(1, 41))) < 0.1
    found = hum.find_lines(y, FS, frame_ms=16.0)
    assert found.size >= 3 and np.abs(found[0] - 60.0) < 0.1


def test_a_clean_recording_is_left_as_it_is(voice):
    """No tonal noise: no warning, no line, and the same TDOAs as with the test switched off."""
    x, _ = voice
    with warnings.catch_warnings():
        warnings.simplefilter("error", TonalNoiseWarning)
        tf = estimate_tdoas(x, FS, "three-mic")
    assert tf.tonal_lines_hz == () and tf.wiring_entries()["tonal_lines_hz"] == []
    with pytest.raises(ConfigError, match="tonal_noise"):
        estimate_tdoas(x, FS, "three-mic", tonal_noise="no")
    ref = estimate_tdoas(x, FS, "three-mic", tonal_noise=False)
    assert np.array_equal(tf.summary_tdoa_s, ref.summary_tdoa_s)
    assert np.array_equal(tf.tdoa_s, ref.tdoa_s, equal_nan=True)


def test_a_masked_pair_localizes_through_a_buzz():
    """Through mask2-asym a buzz 3 dB above a voice at 130 deg made the 360-degree azimuth
    -1 deg (hum is a source at ITD 0, IID 0 dB); localize_mask finds and filters it (one
    warning) and the azimuth is within 3 deg; told there is none it is still fooled. The
    masked document warns once and lists the lines."""
    from hearsee.audio import mask

    y, _ = _with_hum(3.0, "mask2-asym", 130.0)
    with pytest.warns(TonalNoiseWarning) as got:
        est = mask.localize_mask(y, FS, "mask2-asym")
    assert len(got) == 1 and abs(est.azimuth_deg - 130.0) < 3.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fooled = mask.localize_mask(y, FS, "mask2-asym", tonal_lines_hz=())
    assert abs((fooled.azimuth_deg - 130.0 + 180) % 360 - 180) > 30.0
    with pytest.warns(TonalNoiseWarning) as got:
        doc = mask.localize_recording_mask(y, FS, "mask2-asym")
    assert len(got) == 1 and abs(doc["summary"]["azimuth_deg"] - 130.0) < 3.0
    assert abs(doc["summary"]["tonal_lines_hz"][0] - 60.0) < 0.1
    with pytest.raises(ConfigError, match="line frequencies"):
        mask.localize_mask(y, FS, "mask2-asym", tonal_lines_hz=[-60.0])


def test_mains_hum_is_a_unit_rms_comb_below_the_top_and_nyquist():
    """50 Hz at 16 kHz: harmonics 50..2500 Hz, unit RMS; at 4 kHz sampling only those below
    2 kHz; a fundamental that is not a frequency or has no harmonic below the top: ConfigError."""
    for fs, top in ((FS, 2500), (4000, 1950)):
        h = mains_hum(1.0, fs, 50.0, 3)
        assert np.sqrt(np.mean(h ** 2)) == pytest.approx(1.0)
        spec = np.abs(np.fft.rfft(h))
        assert set(np.flatnonzero(spec > 1e-3 * spec.max())) == set(range(50, top + 1, 50))
    for bad in (0.0, -50.0, float("nan"), 3000.0):
        with pytest.raises(ConfigError):
            mains_hum(1.0, FS, bad)
        with pytest.raises(ConfigError):
            hum_harmonics(bad, FS)
    # the harmonics it makes, without making any (simulate_recording's check of hum_hz)
    assert hum_harmonics(60.0, FS).tolist() == list(range(1, 42))  # 60 .. 2460 Hz
    assert hum_harmonics(50.0, 4000).tolist() == list(range(1, 40))  # below 2 kHz only
    # a sample rate that is no number > 0: no harmonic is below its Nyquist frequency (NaN,
    # inf and "16000" gave all 50 up to 2.5 kHz, None a builtin TypeError)
    for bad_fs in (float("nan"), float("inf"), "16000", None, 0.0, -16000.0):
        with pytest.raises(ConfigError, match="fs"):
            hum_harmonics(50.0, bad_fs)


def test_remove_lines_takes_the_hum_out_at_the_recordings_ends_too():
    """The notches settle in ~0.7 s: the first 0.1 s of a 50- or 60-Hz comb kept the hum at
    -9 dB. Extended by whole periods first, the hum's residue is below -40 dB in every 0.1 s
    of the recording, its first and last too; a lone line (no period) is still notched."""
    for f0 in (50.0, 60.0):
        h = mains_hum(3.0, FS, f0, 16)[None]
        r = hum.remove_lines(h, FS, f0 * np.arange(1, int(2500 // f0) + 1))
        db = 10 * np.log10(np.mean(r[0].reshape(-1, FS // 10) ** 2, axis=1))
        assert db.max() < -40.0
    t = np.arange(3 * FS) / FS
    tone = np.sin(2 * np.pi * 1234.5 * t)[None]
    r = hum.remove_lines(tone, FS, [1234.5])
    assert np.mean(r[0, FS:2 * FS] ** 2) < 1e-6  # (the middle second: settled)


def test_a_recording_too_long_for_the_spectra_cache_is_checked_on_frames_spread_over_it(
        voice, monkeypatch):
    """Without the band spectra kept (SPECTRA_CACHE_BYTES too small, as for a recording of
    minutes), the hum is looked for on frames spread over the recording (here the fewest, 40
    of 124): the same comb found (a line more or less at its top), the TDOAs within 0.05
    sample of those with the cache."""
    from hearsee.audio import tdoa

    y, _ = _with_hum(3.0)
    with pytest.warns(TonalNoiseWarning):
        kept = estimate_tdoas(y, FS, "three-mic")
    monkeypatch.setattr(tdoa, "SPECTRA_CACHE_BYTES", 1000)
    with pytest.warns(TonalNoiseWarning):
        spread = estimate_tdoas(y, FS, "three-mic")
    a, b = np.array(spread.tonal_lines_hz), np.array(kept.tonal_lines_hz)
    assert abs(len(a) - len(b)) <= 1 and abs(a[0] - 60.0) < 0.01 and abs(b[0] - 60.0) < 0.01
    np.testing.assert_allclose(spread.summary_tdoa_s * FS, kept.summary_tdoa_s * FS, atol=0.05)


def test_the_public_hum_helpers_refuse_bad_input():
    """One NaN sample made remove_lines / filter_lines return a whole channel of NaN and
    find_lines find nothing, silently; a bandwidth of 0 or a rate of 0 divided by zero, text
    lines were read as Hz and a recording shorter than scipy's padding raised its ValueError.
    Now: typed errors naming the input, and a short recording is filtered."""
    from hearsee.audio.hum import LineFilter, filter_lines, find_lines, remove_lines
    from hearsee.errors import AudioInputError, ConfigError

    t = np.arange(8000) / 16000.0
    x = np.vstack([np.sin(2 * np.pi * 50.0 * t)] * 2)
    bad = x.copy()
    bad[0, 100] = np.nan
    for call in (lambda: remove_lines(bad, 16000, [50.0]), lambda: find_lines(bad, 16000),
                 lambda: filter_lines(bad, 16000, [50.0])):
        with pytest.raises(AudioInputError, match="finite|NaN"):
            call()
    for fs in (0, float("nan"), "16000"):
        with pytest.raises(AudioInputError, match="sample rate"):
            find_lines(x, fs)
        with pytest.raises(AudioInputError, match="sample rate"):
            LineFilter([50.0], fs, 2)
    with pytest.raises(AudioInputError, match="n_channels, n_samples"):
        find_lines(x[0], 16000)
    with pytest.raises(AudioInputError, match="at least one sample"):
        remove_lines(np.zeros((2, 0)), 16000, [50.0])
    with pytest.raises(ConfigError, match="bandwidth_hz"):
        remove_lines(x, 16000, [50.0], bandwidth_hz=0)
    with pytest.raises(ConfigError, match="bandwidth_hz"):
        LineFilter([50.0], 16000, 2, bandwidth_hz=float("nan"))
    with pytest.raises(ConfigError, match="n_channels"):
        LineFilter([50.0], 16000, -1)
    with pytest.raises(ConfigError, match="frame_ms"):
        find_lines(x, 16000, frame_ms=0)
    for lines in ("50", [-50.0], [float("nan")], [[50.0]], [True]):
        with pytest.raises(ConfigError, match="line frequencies"):
            remove_lines(x, 16000, lines)
    # a recording shorter than the zero-phase filter's padding: filtered, not refused
    short = remove_lines(x[:, :5], 16000, [50.0, 1234.0])
    assert short.shape == (2, 5) and np.all(np.isfinite(short))
    # a valid call is unchanged: the 50-Hz tone taken out (away from the ends)
    y = remove_lines(x, 16000, [50.0])
    assert np.sqrt(np.mean(y[:, 2000:6000] ** 2)) < 0.05 * np.sqrt(np.mean(x ** 2))


def test_a_pairs_sources_are_found_through_a_buzz():
    """``localize_recording(max_sources=2)`` on a two-microphone pair estimates each source
    again from its own frames (``sources_from_spectra``, ``estimate_tdoas(active=...)``), which
    does not look for hum itself: it was given the buzzed recording, and a talker at 59.5 deg
    came out at the hum's TDOA 0 (-1.7 deg) beside a summary of 58 deg."""
    from hearsee.audio.localize import localize_recording

    x, truth = simulate_recording("two-mic", [1.0, 1.7, 0.35], "male", 3.0, snr_db=20, seed=0,
                                  hum_db=0.0, hum_hz=50.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TonalNoiseWarning)
        doc = localize_recording(x, FS, "two-mic", kalman=False, max_sources=2)
    assert doc["summary"]["tonal_lines_hz"]
    assert abs(doc["summary"]["azimuth_deg"] - truth["azimuth_deg"]) < 3.0
    assert [abs(s["azimuth_deg"] - truth["azimuth_deg"]) < 3.0 for s in doc["sources"]] == [True]


def test_a_comb_whose_low_harmonics_a_voice_hides_is_completed():
    """With 32-ms frames the voice hid a 60-Hz hum's harmonics below 1.9 kHz from the test:
    the lines found (1920, 2160, ..., 2460 Hz) were no comb of the lowest over 1-4, the hum's
    other harmonics stayed, and the three-mic summary came out 173 deg off (elevation 86)."""
    lines = 60.0 * np.array([32, 36, 37, 38, 39, 40, 41])
    comb = hum._comb(lines)
    assert comb is not None and np.allclose(comb, 60.0 * np.arange(1, 42))
    assert hum._fundamental(lines) == pytest.approx(60.0)
    x, truth = simulate_recording("three-mic", [1.0, 1.7, 0.35], "male", 3.0, snr_db=20,
                                  seed=1, hum_db=3.0, hum_hz=60.0)
    want = np.array(list(truth["tdoa_s"].values())) * FS
    with pytest.warns(TonalNoiseWarning, match=r"60\.0 Hz and its harmonics"):
        tf = estimate_tdoas(x, FS, "three-mic", frame_ms=32.0, hop_ms=16.0)
    assert np.max(np.abs(tf.summary_tdoa_s * FS - want)) < 0.5


def test_a_line_found_on_its_farther_bin_only_is_found_at_its_frequency():
    """A line between two 64-ms bins may pass the stationarity test on the farther one only
    (the nearer one swings with a neighbouring harmonic's leakage). Its frequency was looked
    for within half a bin of that bin, where only noise is: the 600-Hz harmonic of a 60-Hz
    hum 10 dB above white noise (found at bin 609.4 Hz) came out as an extra line at
    611.9 Hz, a notch beside nothing, and a line at 7998.5 Hz (on bin 7984.4 Hz, the
    Nyquist bin swinging) as 7985.9 Hz, where the notch missed it. Within a bin: the lines."""
    rng = np.random.default_rng(7)
    h = mains_hum(3.0, FS, 60.0, rng)
    x = rng.standard_normal((2, 3 * FS)) + 3.0 * h[None]
    lines = hum.find_lines(x, FS)
    want = 60.0 * hum_harmonics(60.0, FS)
    assert lines.shape == want.shape
    np.testing.assert_allclose(lines, want, atol=0.05)  # (a notch is 2 Hz wide)
    t = np.arange(3 * FS) / FS
    rng = np.random.default_rng(0)
    x = np.sin(2 * np.pi * 7998.5 * t)[None] + 0.1 * rng.standard_normal((2, t.size))
    np.testing.assert_allclose(hum.find_lines(x, FS), [7998.5], atol=0.01)


@pytest.mark.parametrize("f0", [20.0, 30.0, 45.0])
def test_a_strong_lines_leakage_is_no_line(f0):
    # a line 37 dB (amplitude 1) or 17 dB (0.1) above white noise: its leakage through the
    # frames' Tukey window holds steady in bins far from it; their peaks are noise, no lines
    # (20 Hz gave 32.9, 109.5, 162.3 Hz; 45 Hz at 17 dB gave 45 and 124.2 Hz)
    fs = 16000
    t = np.arange(5 * fs) / fs
    rng = np.random.default_rng(349)
    line = np.sin(2 * np.pi * f0 * t)
    for amp in (1.0, 0.1):
        x = amp * np.stack([line, line]) + 0.01 * rng.standard_normal((2, t.size))
        found = hum.find_lines(x, fs)
        # below TONAL_MIN_HZ no line is looked for; above, the line itself and nothing else
        want = [f0] if f0 >= hum.TONAL_MIN_HZ else []
        assert found == pytest.approx(want, abs=0.05), (amp, found)
