import numpy as np
import pytest

from hearsee.audio.arrays import MicArray
from hearsee.audio.propagation import delay_signals, simulate_free_field
from hearsee.audio.signals import white_noise
from hearsee.audio.tdoa import (
    METHODS,
    SUMMARY_TUNED,
    _frame_energy,
    _median_last,
    _percentiles,
    _take_last,
    dominant_sample,
    estimate_tdoas,
    frame_signals,
    gcc,
    normalize_method,
)
from hearsee.errors import AudioInputError, ConfigError, GeometryError

FS = 16000


@pytest.fixture(scope="module")
def three():
    return MicArray.from_preset("three-mic")


@pytest.fixture(scope="module")
def recording(three):
    src = np.array([1.2, 0.8, 0.3])
    s = white_noise(1.0, FS, rng=1)
    return simulate_free_field(s, FS, three, src, snr_db=20, rng=2), three.tdoa(src)


def test_frame_signals_shape_and_content():
    x = np.arange(20.0).reshape(2, 10)
    f = frame_signals(x, 4, 3)
    assert f.shape == (2, 3, 4)
    np.testing.assert_array_equal(f[1, 2], x[1, 6:10])


def test_frame_signals_too_short():
    with pytest.raises(AudioInputError, match="too short"):
        frame_signals(np.zeros((2, 10)), 16, 8)


def test_gcc_integer_and_fractional_delay():
    s = white_noise(0.5, FS, rng=3)
    for d in (3.0, -2.4, 0.37):
        y = delay_signals(s, [max(d, 0) / FS, max(-d, 0) / FS], FS)  # y0 lags y1 by d samples
        r = gcc(y[0], y[1], FS, max_tau_s=10 / FS)
        assert r.tdoa_s * FS == pytest.approx(d, abs=0.02)
        assert r.confidence > 2


@pytest.mark.parametrize("method", METHODS)
def test_estimate_tdoas_known_delays_all_methods(recording, three, method):
    x, true = recording
    tf = estimate_tdoas(x, FS, three, method=method)
    assert tf.tdoa_s.shape == (len(tf.t), 3) and tf.pairs == three.pairs
    assert tf.valid.all()
    np.testing.assert_allclose(np.median(tf.tdoa_s, axis=0), true, atol=0.05 / FS)
    np.testing.assert_allclose(tf.summary_tdoa_s, true, atol=0.05 / FS)


def test_interp_refinement_beats_parabolic(recording, three):
    x, true = recording
    e = {}
    for refine in ("interp", "parabolic", "none"):
        tf = estimate_tdoas(x, FS, three, refine=refine)
        e[refine] = np.sqrt(np.mean((tf.tdoa_s - true) ** 2)) * FS
    assert e["interp"] < e["parabolic"] < e["none"]
    assert e["interp"] < 0.02


def test_lag_search_bounded_by_geometry(three):
    # mic 0 hears the source 40 samples late (impossible for a 15 cm array) plus a weak copy
    # 1 sample late (possible): the search stays inside the bound and finds the weak copy, and
    # the confidence (a stronger peak outside the bound) marks the frames as unreliable.
    # The whole recording's correlations then name microphone 0 as out of sync (2026-12-04).
    from hearsee.errors import ChannelSyncWarning

    s = white_noise(1.0, FS, rng=4)
    y = delay_signals(s, [40 / FS, 0.0, 2 / FS], FS)
    y[0] += 0.3 * delay_signals(s, [1 / FS], FS)[0]
    sync = "microphone 0 seems out of sync with the others: pairs 0-1 at "
    with pytest.warns(ChannelSyncWarning, match=sync):
        tf = estimate_tdoas(y, FS, three, min_confidence=0.0)
    assert np.all(np.abs(tf.tdoa_s) <= tf.max_tdoa_s + 1e-12)
    assert np.median(tf.tdoa_s[:, 0]) * FS == pytest.approx(1.0, abs=0.1)
    assert np.all(tf.confidence[:, 0] < 1.0)
    with pytest.warns(ChannelSyncWarning, match=sync):
        assert estimate_tdoas(y, FS, three).n_valid == 0


def test_silence_and_noise_give_no_estimate(three):
    rng = np.random.default_rng(5)
    src = np.array([1.0, -1.0, 0.0])
    s = white_noise(1.0, FS, rng)
    s[FS // 2:] = 0.0  # second half: source silent, only sensor noise
    x = simulate_free_field(s, FS, three, src, snr_db=20, rng=rng)
    tf = estimate_tdoas(x, FS, three)
    first, second = tf.t < 0.45, tf.t > 0.55
    assert tf.valid[first].all()
    assert not tf.valid[second].any()
    assert np.isnan(tf.tdoa_s[second]).all()
    # uncorrelated noise only: no frame and no summary estimate
    tf = estimate_tdoas(rng.standard_normal((3, FS)), FS, three)
    assert tf.n_valid == 0 and np.isnan(tf.summary_tdoa_s).all()
    # digital silence
    tf = estimate_tdoas(np.zeros((3, FS // 2)), FS, three)
    assert tf.n_valid == 0 and np.isnan(tf.summary_tdoa_s).all()


def test_two_mic_summary_detects_sources_not_noise():
    """One independent pair has no closure test: the correlation's peak must stand out of its
    own noise floor (min_peak_snr, min_frame_peak_snr). Noise-only two-channel recordings
    give no whole-recording estimate and no frame estimate; a white source at -10 dB does,
    on its true delay."""
    two = MicArray.from_preset("two-mic")
    noise = [np.random.default_rng(s).standard_normal((2, FS)) for s in range(60)]
    strict = [estimate_tdoas(x, FS, two) for x in noise]
    loose = [estimate_tdoas(x, FS, two, min_peak_snr=0, min_frame_peak_snr=0) for x in noise]
    assert not any(np.isfinite(tf.summary_tdoa_s[0]) for tf in strict)
    assert sum(tf.n_valid for tf in strict) == 0
    # the confidence alone lets some noise through: the tests matter
    assert any(np.isfinite(tf.summary_tdoa_s[0]) for tf in loose)
    assert sum(tf.n_valid for tf in loose) > 0
    src = np.array([1.0, 1.0, 0.0])
    for s in range(5):
        x = simulate_free_field(white_noise(1.0, FS, rng=s), FS, two, src, snr_db=-10, rng=s + 9)
        tf = estimate_tdoas(x, FS, two)
        assert tf.summary_tdoa_s[0] * FS == pytest.approx(two.tdoa(src)[0] * FS, abs=0.3)
    with pytest.raises(ConfigError):
        estimate_tdoas(x, FS, two, min_peak_snr=-1)


def test_without_detection_test_is_the_run_without_it():
    """An estimate refused only by the peak-SNR detection test is kept
    (``undetected_summary``): ``without_detection_test()`` gives what ``min_peak_snr=0``
    gives, field by field, for recordings the test refused and for those it did not."""
    two = MicArray.from_preset("two-mic")
    refused = 0
    for s in range(20):
        x = np.random.default_rng(s).standard_normal((2, FS))
        tf = estimate_tdoas(x, FS, two)
        refused += tf.undetected_summary is not None
        relaxed = estimate_tdoas(x, FS, two, min_peak_snr=0)
        for name in ("summary_tdoa_s", "summary_confidence", "tdoa_s", "confidence", "valid"):
            np.testing.assert_array_equal(getattr(tf.without_detection_test(), name),
                                          getattr(relaxed, name))
        assert relaxed.undetected_summary is None
    assert refused  # (the confidence alone lets some of this noise through)


@pytest.mark.parametrize("n", [1, 2, 7, 8, 403, 404])
def test_median_last_is_numpys_median(n):
    """The CFAR floor's partial-sort median equals np.median on odd and even lengths,
    with repeated values too."""
    rng = np.random.default_rng(n)
    a = rng.standard_normal((3, 2, n))
    a[0, 0] = np.round(a[0, 0])  # ties
    np.testing.assert_allclose(_median_last(a.copy()), np.median(a, axis=-1), rtol=0, atol=0)


@pytest.mark.parametrize("n", [1, 2, 3, 20, 31, 200])
def test_percentiles_are_numpys(n):
    """The frame-energy VAD's percentiles equal np.percentile to the bit (lognormal energies
    over many decades, ties included)."""
    rng = np.random.default_rng(n)
    for _ in range(50):
        e = rng.lognormal(0.0, 3.0, n) * 10.0 ** rng.uniform(-12, 3)
        if n > 3:
            e[: n // 4] = e[0]
        assert _percentiles(e, (10.0, 95.0)) == [float(v) for v in np.percentile(e, [10, 95])]


@pytest.mark.parametrize("frame_len,hop", [(512, 512), (512, 256), (512, 128), (500, 200)])
def test_frame_energy_is_each_frames_mean_square(frame_len, hop):
    """Whole-hop frames (block sums) and other hops (running sum) give every frame's mean
    square over all channels, each channel about its mean over the recording (a DC offset
    is no energy), also for frames far quieter than the rest."""
    rng = np.random.default_rng(hop)
    x = rng.standard_normal((3, 9000)) * np.exp(rng.uniform(-9.0, 0.0, 9000))
    x += np.array([0.5, -0.02, 0.0])[:, None]
    x32 = x.astype(np.float32)
    n_frames = (x.shape[1] - frame_len) // hop + 1
    starts = np.arange(n_frames) * hop
    ac = x32.astype(float) - x32.astype(float).mean(axis=1, keepdims=True)
    truth = np.array([np.mean(ac[:, s:s + frame_len] ** 2) for s in starts])
    np.testing.assert_allclose(_frame_energy(x32, frame_len, hop, n_frames), truth, rtol=1e-6)


def test_take_last_is_take_along_axis():
    rng = np.random.default_rng(3)
    a = rng.standard_normal((4, 3, 50))
    idx = rng.integers(0, 50, (4, 3))
    np.testing.assert_array_equal(_take_last(a, idx),
                                  np.take_along_axis(a, idx[..., None], axis=-1)[..., 0])
    np.testing.assert_array_equal(_take_last(a[1, :, :], idx[1]), a[1, np.arange(3), idx[1]])


def test_pairs_subset_and_method_aliases(recording, three):
    x, true = recording
    tf = estimate_tdoas(x, FS, three, pairs=[(2, 0)], method="gcc-scot")
    np.testing.assert_allclose(tf.summary_tdoa_s, [-true[1]], atol=0.05 / FS)
    assert normalize_method("GCC-ML") == "ml"


def test_bad_inputs(three):
    x = np.zeros((2, FS))
    with pytest.raises(AudioInputError, match="needs"):
        estimate_tdoas(x, FS, three)
    bad = np.ones((3, FS))
    bad[0, 5] = np.nan
    with pytest.raises(AudioInputError, match="NaN"):
        estimate_tdoas(bad, FS, three)
    with pytest.raises(ConfigError, match="unknown GCC method"):
        estimate_tdoas(np.ones((3, FS)), FS, three, method="music")
    with pytest.raises(GeometryError):
        estimate_tdoas(np.ones((3, FS)), FS, three, pairs=[(0, 0)])
    with pytest.raises(ConfigError, match="too short for the array"):
        estimate_tdoas(np.ones((3, FS)), FS, three, frame_ms=0.5)
    with pytest.raises(AudioInputError, match="sample rate"):
        estimate_tdoas(np.ones((3, FS)), -1, three)


def test_snr_weighting_helps_a_voice_in_noise(three):
    from hearsee.audio.signals import synthetic_voice

    src = np.array([1.0, -1.5, 0.0])
    s = synthetic_voice("female", 2.0, FS, rng=11)
    x = simulate_free_field(s, FS, three, src, snr_db=0, rng=12)
    true = three.tdoa(src)
    err = {}
    for w in (False, True):
        tf = estimate_tdoas(x, FS, three, snr_weight=w, band_hz=(300, 3500))
        err[w] = np.max(np.abs(tf.summary_tdoa_s - true)) * FS
    assert err[True] < 0.3
    assert err[True] <= err[False] + 0.05


def test_summary_frames_option(recording, three):
    x, true = recording
    tf = estimate_tdoas(x, FS, three, summary_frames="active")
    np.testing.assert_allclose(tf.summary_tdoa_s, true, atol=0.05 / FS)
    with pytest.raises(ConfigError, match="summary_frames"):
        estimate_tdoas(x, FS, three, summary_frames="all")


def test_closure_rejects_noise_only_summary_and_ml_snr_form(three):
    rng = np.random.default_rng(21)
    x = rng.standard_normal((3, FS))
    x[:, FS // 2:] *= 0.3  # louder and quieter noise: the SNR weighting is active
    for mc in (1.0, 0.8):
        tf = estimate_tdoas(x, FS, three, method="ml", min_confidence=mc, snr_weight="ml")
        assert np.isnan(tf.summary_tdoa_s).all()


def test_coherent_refine_recovers_known_direction(three):
    from hearsee.audio.tdoa import _coherent_refine

    nfft = 512
    bins = np.arange(10, 200)
    w = 2 * np.pi * bins / nfft
    I = np.array([i for i, _ in three.pairs])
    J = np.array([j for _, j in three.pairs])
    D = -(three.positions[I] - three.positions[J]) / three.speed_of_sound * FS
    u_true = np.array([np.cos(0.7), np.sin(0.7), 0.0])
    tau_true = D @ u_true
    P = np.exp(-1j * np.outer(tau_true, w))  # correlations peaking exactly at tau_true
    u0 = np.array([np.cos(0.75), np.sin(0.75), 0.0])  # ~3 deg off, like the direction grid
    tau = _coherent_refine(P, bins, nfft, D, u0)
    np.testing.assert_allclose(tau, tau_true, atol=1e-3)


def test_joint_coherent_and_weighting_options_keep_known_delays(three):
    src = 3.0 * np.array([np.cos(-2.0), np.sin(-2.0), 0.0])
    s = white_noise(1.0, FS, rng=5)
    x = simulate_free_field(s, FS, three, src, snr_db=20, rng=6, far_field=True)
    true = three.tdoa_far(src)
    for kw in ({"joint": "coherent"}, {"phat_beta": 0.7}, {"onset_weight": 3.0},
               {"method": "ml", "joint": "coherent", "onset_weight": 3.0}):
        tf = estimate_tdoas(x, FS, three, **kw)
        np.testing.assert_allclose(tf.summary_tdoa_s, true, atol=0.05 / FS)
    tf = estimate_tdoas(x, FS, three, joint="coherent")
    t01, t02, t12 = tf.summary_tdoa_s  # pairs (0,1), (0,2), (1,2): consistent by construction
    assert t01 - t02 + t12 == pytest.approx(0.0, abs=1e-9)
    for bad in ({"joint": "srp"}, {"phat_beta": 1.5}, {"onset_weight": -1.0}):
        with pytest.raises(ConfigError):
            estimate_tdoas(x, FS, three, **bad)


def _voice_in(array, rt60, seed):
    """A female voice (with pauses) 2 m away in the array plane, free field or in a room."""
    from hearsee.audio.propagation import simulate_room
    from hearsee.audio.signals import synthetic_voice

    src = 2.0 * np.array([np.cos(np.radians(50.0)), np.sin(np.radians(50.0)), 0.0])
    s = synthetic_voice("female", 1.5, FS, rng=seed)
    if rt60 == 0:
        return simulate_free_field(s, FS, array, src, snr_db=20, rng=seed + 1), array.tdoa(src)
    x = simulate_room(s, FS, array, src, room_dim=(5.0, 4.0, 3.0), rt60=rt60,
                      array_at=(2.5, 1.8, 1.3), snr_db=20, rng=seed + 1)
    return x, array.tdoa(src)


def test_reverb_method_switches_on_measured_coherence(three):
    free, truth = _voice_in(three, 0.0, 10)
    room, _ = _voice_in(three, 0.4, 10)
    kw = {"method": "ml", "band_hz": (300.0, 3500.0), "hop_ms": 64.0}
    tf_free = estimate_tdoas(free, FS, three, reverb_method="phat", **kw)
    tf_room = estimate_tdoas(room, FS, three, reverb_method="phat", **kw)
    assert tf_free.coherence_ratio > 0.95 and tf_free.summary_method == "ml"
    assert tf_room.coherence_ratio < 0.9 and tf_room.summary_method == "phat"
    # free field: identical to the plain call, and right
    plain = estimate_tdoas(free, FS, three, **kw)
    assert np.array_equal(plain.summary_tdoa_s, tf_free.summary_tdoa_s)
    assert np.isnan(plain.coherence_ratio) and plain.summary_method == "ml"
    assert np.abs(tf_free.summary_tdoa_s - truth).max() * FS < 0.2
    # per-frame estimates never change
    plain_room = estimate_tdoas(room, FS, three, **kw)
    assert np.array_equal(plain_room.tdoa_s, tf_room.tdoa_s, equal_nan=True)
    # the threshold decides
    never = estimate_tdoas(room, FS, three, reverb_method="phat", reverb_coherence=0.0, **kw)
    assert never.summary_method == "ml"
    assert np.array_equal(never.summary_tdoa_s, plain_room.summary_tdoa_s, equal_nan=True)


def test_reverb_method_without_noise_frames_tests_the_coherence_gain(three):
    # a steady white source (no noise-only frames, so no coherence_ratio): the reverberation
    # test is how much the coherence grows with 4x longer frames
    from hearsee.audio.propagation import simulate_room

    src = 2.0 * np.array([np.cos(np.radians(-120.0)), np.sin(np.radians(-120.0)), 0.0])
    s = white_noise(2.0, FS, rng=3)
    free = simulate_free_field(s, FS, three, src, snr_db=10, rng=4)
    room = simulate_room(s, FS, three, src, room_dim=(5.0, 4.0, 3.0), rt60=0.3,
                         array_at=(2.5, 2.2, 1.3), snr_db=10, rng=4)
    kw = {"method": "ml", "band_hz": (300.0, 7500.0), "hop_ms": 64.0, "reverb_method": "phat"}
    tf_free = estimate_tdoas(free, FS, three, **kw)
    tf_room = estimate_tdoas(room, FS, three, **kw)
    assert np.isnan(tf_free.coherence_ratio) and np.isnan(tf_room.coherence_ratio)
    assert tf_free.coherence_gain < 1.02 and tf_free.summary_method == "ml"
    assert tf_room.coherence_gain > 1.2 and tf_room.summary_method == "phat"
    for tf in (tf_free, tf_room):
        assert np.abs(tf.summary_tdoa_s - three.tdoa(src)).max() * FS < 0.5
    # free field: identical to the call without reverb_method
    plain = estimate_tdoas(free, FS, three, **{k: v for k, v in kw.items() if k != "reverb_method"})
    assert np.array_equal(plain.summary_tdoa_s, tf_free.summary_tdoa_s)
    assert np.isnan(plain.coherence_gain)
    # too short for five 256 ms frames: not measured, the summary keeps its method
    short = estimate_tdoas(room[:, :FS], FS, three, **kw)
    assert np.isnan(short.coherence_gain) and short.summary_method == "ml"
    with pytest.raises(ConfigError):
        estimate_tdoas(free, FS, three, reverb_method="bogus")


def test_summary_upsample_finds_the_correlation_maximum():
    """Direct path and an equally strong echo 1.9 samples apart: the averaged correlation
    has two close peaks; the upsampled search returns its true maximum."""
    two = MicArray.from_preset("two-mic")
    s = white_noise(1.0, FS, rng=7)
    direct = delay_signals(s, np.array([0.0, 2.3]) / FS, FS)
    echo = delay_signals(s, np.array([0.0, 0.4]) / FS, FS)
    x = direct + 0.95 * echo + 0.01 * np.random.default_rng(8).standard_normal(direct.shape)
    tf = estimate_tdoas(x, FS, two, method="phat", summary_upsample=8)
    taus = np.linspace(-7.0, 7.0, 2801)  # 0.005 samples apart
    k = tf.summary_bins
    dense = np.real(np.exp(2j * np.pi * np.outer(taus, k / tf.nfft)) @ tf.summary_spectrum[0])
    assert tf.summary_tdoa_s[0] * FS == pytest.approx(taus[np.argmax(dense)], abs=6e-3)
    default = estimate_tdoas(x, FS, two, method="phat")  # summary_upsample=4
    assert default.summary_method == "phat"
    assert default.summary_tdoa_s[0] * FS == pytest.approx(taus[np.argmax(dense)], abs=6e-3)
    integer = estimate_tdoas(x, FS, two, method="phat", summary_upsample=1)
    assert abs(integer.summary_tdoa_s[0] * FS - taus[np.argmax(dense)]) > 0.05


def test_first_arrival_prefers_the_direct_path_over_its_floor_image():
    """Two microphones, a source at azimuth 50 deg in their plane plus an equally strong copy
    2 ms later from its floor image (same azimuth, 60 deg below: same side, half the lag).
    The highest averaged-correlation peak is the image's; ``first_arrival`` (default) takes
    the direct path, 0 the highest peak, and an image clearly stronger than the tolerance
    still wins."""
    from hearsee.geometry import unit_vector_deg

    two = MicArray.from_preset("two-mic")
    s = white_noise(1.0, FS, rng=31)
    u_src, u_img = unit_vector_deg(50.0, 0.0), unit_vector_deg(50.0, -60.0)
    tau_src, tau_img = two.tdoa_far(u_src)[0] * FS, two.tdoa_far(u_img)[0] * FS  # 5.4, 2.7

    def record(gain):
        x = (delay_signals(s, 1e-3 - two.positions @ u_src / two.speed_of_sound, FS)
             + gain * delay_signals(s, 3e-3 - two.positions @ u_img / two.speed_of_sound, FS))
        return x + 0.01 * np.random.default_rng(32).standard_normal(x.shape)

    x = record(1.0)
    assert estimate_tdoas(x, FS, two).summary_tdoa_s[0] * FS == pytest.approx(tau_src, abs=0.1)
    highest = estimate_tdoas(x, FS, two, first_arrival=0.0).summary_tdoa_s[0] * FS
    assert highest == pytest.approx(tau_img, abs=0.1)
    stronger = estimate_tdoas(record(1.1), FS, two).summary_tdoa_s[0] * FS
    assert stronger == pytest.approx(tau_img, abs=0.1)
    for bad in (-0.1, 1.5, float("nan")):
        with pytest.raises(ConfigError, match="first_arrival"):
            estimate_tdoas(x, FS, two, first_arrival=bad)


def test_source_in_plane_joint_search_ignores_elevated_reflection(three):
    """An in-plane source plus a stronger, later copy from 50 deg elevation (a ceiling
    reflection): the whole-sphere joint search locks onto the reflection, the in-plane search
    onto the source."""
    from hearsee.audio.localize import localize_tdoa
    from hearsee.geometry import unit_vector_deg

    s = white_noise(1.0, FS, rng=11)
    u_src, u_refl = unit_vector_deg(40.0, 0.0), unit_vector_deg(-160.0, 50.0)
    x = (delay_signals(s, 1e-3 - three.positions @ u_src / three.speed_of_sound, FS)
         + 1.1 * delay_signals(s, 4e-3 - three.positions @ u_refl / three.speed_of_sound, FS))
    x = x + 0.01 * np.random.default_rng(12).standard_normal(x.shape)
    sphere = estimate_tdoas(x, FS, three)
    plane = estimate_tdoas(x, FS, three, source_in_plane=True)
    az_sphere = localize_tdoa(sphere.summary_tdoa_s, three).azimuth_deg
    az_plane = localize_tdoa(plane.summary_tdoa_s, three, in_plane=True).azimuth_deg
    assert abs(az_sphere - (-160.0)) < 3.0  # the reflection wins on the sphere
    assert abs(az_plane - 40.0) < 2.0
    assert np.abs(plane.summary_tdoa_s - three.tdoa_far(u_src)).max() * FS < 0.15


def test_steered_in_plane_summary_is_the_steered_response_maximum(three):
    """joint="steered": in free field the known azimuth of a source 2 m away (through the
    in-plane localizer with the same range); in a room the TDOAs are those of the in-plane
    point 2 m away at the angle that maximises the steered sum of the averaged correlations,
    checked against a brute-force evaluation of that sum on a 0.002-deg grid."""
    from hearsee.audio.localize import localize_tdoa
    from hearsee.audio.propagation import simulate_room
    from hearsee.geometry import unit_vector_deg

    kw = {"source_in_plane": True, "joint": "steered", "steer_range_m": 2.0}
    for az in (-170.0, -33.0, 64.0, 121.0):
        src = 2.0 * unit_vector_deg(az, 0.0)
        x = simulate_free_field(white_noise(1.0, FS, rng=21), FS, three, src, snr_db=30, rng=22)
        tf = estimate_tdoas(x, FS, three, **kw)
        loc = localize_tdoa(tf.summary_tdoa_s, three, tf.pairs, near_field=True, in_plane=True)
        assert abs((loc.azimuth_deg - az + 180.0) % 360.0 - 180.0) < 0.02
        np.testing.assert_allclose(tf.summary_tdoa_s, three.tdoa(src), atol=0.02 / FS)
    src = 2.2 * unit_vector_deg(147.0, 0.0)
    x = simulate_room(white_noise(1.5, FS, rng=23), FS, three, src, room_dim=(6.0, 5.0, 3.0),
                      rt60=0.5, array_at=(2.0, 2.6, 1.3), snr_db=20, rng=24)
    tf = estimate_tdoas(x, FS, three, **kw)
    w = 2.0 * np.pi * tf.summary_bins / tf.nfft * FS

    def steered(deg):  # (tdoas of the points 2 m away, sum_p Re sum_k P_pk exp(j w_k tau_p))
        th = np.radians(deg)
        pts = 2.0 * np.stack([np.cos(th), np.sin(th), np.zeros_like(th)], axis=1)
        dist = np.linalg.norm(pts[:, None, :] - three.positions[None], axis=-1)
        tau = np.stack([dist[:, i] - dist[:, j] for i, j in tf.pairs], 1) / three.speed_of_sound
        score = sum(np.real(np.exp(1j * np.outer(tau[:, p], w)) @ tf.summary_spectrum[p])
                    for p in range(len(tf.pairs)))
        return tau, score

    deg = np.arange(0.0, 360.0, 0.1)
    deg = deg[np.argmax(steered(deg)[1])] + np.arange(-0.3, 0.3, 0.002)  # then finer
    tau, score = steered(deg)
    np.testing.assert_allclose(tf.summary_tdoa_s, tau[np.argmax(score)], atol=0.01 / FS)
    pairs = estimate_tdoas(x, FS, three, source_in_plane=True)  # not the same estimate
    assert np.abs(pairs.summary_tdoa_s - tau[np.argmax(score)]).max() * FS > 0.05


def test_steered_needs_an_in_plane_search_on_a_planar_array(three):
    x = simulate_free_field(white_noise(0.5, FS, rng=1), FS, three, np.array([1.0, 1.0, 0.0]),
                            snr_db=20, rng=2)
    with pytest.raises(ConfigError, match="source_in_plane"):
        estimate_tdoas(x, FS, three, joint="steered")
    with pytest.raises(ConfigError, match="steer_range_m"):
        estimate_tdoas(x, FS, three, joint="steered", source_in_plane=True, steer_range_m=-1.0)
    tetra = MicArray(np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0],
                               [0.0, 0.0, 0.1]]))
    x4 = simulate_free_field(white_noise(0.5, FS, rng=3), FS, tetra, np.array([1.0, 1.0, 0.0]),
                             snr_db=20, rng=4)
    with pytest.raises(ConfigError, match="planar"):
        estimate_tdoas(x4, FS, tetra, joint="steered", source_in_plane=True)


def test_band_vad_learns_the_noise_of_a_voice_at_0_db(three):
    """A male voice at 0 dB (free field, white sensor noise up to 8 kHz, analysis band
    300-3500 Hz): for some recordings the broadband frame energy looks stationary, no frame is
    inactive, so there is no noise spectrum and no SNR weighting (coherence_ratio NaN) -- the
    summary TDOAs were up to 0.6 samples off. The band's energy finds the pauses: known TDOAs
    within 0.1 samples, several times closer. Recordings the broadband energy already decided
    are unchanged."""
    from hearsee.audio.signals import synthetic_voice

    kw = {"method": "ml", "band_hz": (300.0, 3500.0), "hop_ms": 64.0, "min_confidence": 0.8,
          "reverb_method": "phat", "source_in_plane": True}
    n_fixed = 0
    for seed in range(6):
        az = np.radians(40.0 + 50.0 * seed)
        src = 2.0 * np.array([np.cos(az), np.sin(az), 0.0])
        x = simulate_free_field(synthetic_voice("male", 2.0, FS, rng=seed), FS, three, src,
                                snr_db=0, rng=seed + 100)
        truth = three.tdoa(src) * FS
        plain = estimate_tdoas(x, FS, three, band_vad=False, **kw)
        band = estimate_tdoas(x, FS, three, **kw)  # band_vad=True, the default
        assert np.isfinite(band.coherence_ratio)  # the noise spectrum was learned
        err_band = np.abs(band.summary_tdoa_s * FS - truth).max()
        assert err_band < 0.2
        if np.isfinite(plain.coherence_ratio):  # decided by the broadband energy: unchanged
            assert np.array_equal(plain.summary_tdoa_s, band.summary_tdoa_s)
            assert np.array_equal(plain.tdoa_s, band.tdoa_s, equal_nan=True)
        else:
            n_fixed += 1
            assert err_band < 0.1
            assert np.abs(plain.summary_tdoa_s * FS - truth).max() > 2 * err_band
    assert n_fixed >= 2
    # chunked processing (the band spectra computed twice) gives the same estimates
    one = estimate_tdoas(x, FS, three, band_vad=True, **kw)
    many = estimate_tdoas(x, FS, three, band_vad=True, chunk_frames=7, **kw)
    np.testing.assert_allclose(many.summary_tdoa_s, one.summary_tdoa_s, atol=1e-4 / FS)
    np.testing.assert_allclose(many.tdoa_s, one.tdoa_s, atol=1e-4 / FS)


@pytest.mark.parametrize("band_vad", [True, False])
def test_long_recordings_transform_each_frame_once(three, monkeypatch, band_vad):
    """A recording of more frames than ``chunk_frames`` keeps its band spectra (within
    SPECTRA_CACHE_BYTES): the activity test, the noise spectrum and the frame loop share one
    transform per frame, where each had transformed them again -- with results identical to
    the re-transformed ones (SPECTRA_CACHE_BYTES = 0), bit for bit."""
    import scipy.fft as sfft

    from hearsee.audio import tdoa as tdoa_mod
    from hearsee.audio.signals import synthetic_voice

    az = np.radians(130.0)
    src = 2.0 * np.array([np.cos(az), np.sin(az), 0.0])
    x = simulate_free_field(synthetic_voice("male", 3.0, FS, rng=4), FS, three, src,
                            snr_db=0, rng=5)
    kw = {"method": "scot", "band_hz": (300.0, 3500.0), "chunk_frames": 16,
          "band_vad": band_vad, "reverb_method": "phat"}
    rows = []
    rfft = sfft.rfft

    def counted(a, *args, **kwargs):
        rows.append(int(np.prod(np.shape(a)[:-1])))
        return rfft(a, *args, **kwargs)

    monkeypatch.setattr(tdoa_mod.sfft, "rfft", counted)
    cached = estimate_tdoas(x, FS, three, **kw)
    n_cached = sum(rows)
    rows.clear()
    monkeypatch.setattr(tdoa_mod, "SPECTRA_CACHE_BYTES", 0)
    again = estimate_tdoas(x, FS, three, **kw)
    n_frames = len(cached.t)
    assert n_frames > 3 * kw["chunk_frames"]
    # three channels, each frame once (the empty-band search's loudest frames come from the
    # same transforms)
    assert n_cached == 3 * n_frames
    assert sum(rows) > n_cached  # (the halo of SCOT's statistics alone re-transforms some)
    for a, b in [(cached.tdoa_s, again.tdoa_s), (cached.confidence, again.confidence),
                 (cached.summary_tdoa_s, again.summary_tdoa_s)]:
        assert np.array_equal(a, b, equal_nan=True)
    assert np.isfinite(cached.summary_tdoa_s).all()
    np.testing.assert_allclose(cached.summary_tdoa_s, three.tdoa(src), atol=0.3 / FS)


def test_band_vad_leaves_a_steady_source_alone(three):
    """White noise from a fixed direction: its band energy is as stationary as its broadband
    energy, so the band test decides nothing either and the estimates are the plain ones."""
    src = np.array([1.0, -1.5, 0.0])
    x = simulate_free_field(white_noise(1.0, FS, rng=31), FS, three, src, snr_db=10, rng=32)
    kw = {"method": "ml", "band_hz": (300.0, 7500.0), "hop_ms": 64.0}
    plain = estimate_tdoas(x, FS, three, band_vad=False, **kw)
    band = estimate_tdoas(x, FS, three, **kw)
    assert np.array_equal(plain.summary_tdoa_s, band.summary_tdoa_s)
    assert np.array_equal(plain.tdoa_s, band.tdoa_s, equal_nan=True)
    np.testing.assert_allclose(band.summary_tdoa_s, three.tdoa(src), atol=0.05 / FS)


@pytest.mark.parametrize("snr_weight", [True, "ml"])
def test_digitally_silent_lead_in_is_not_the_noise_floor(three, snr_weight):
    """A recording that starts with a few frames of exact zeros (a recorder's lead-in): those
    frames are inactive, but a noise floor of zero made every SNR infinite and every estimate
    NaN. Known delays: +3 samples on a pair, and a three-mic source at a known position."""
    fs = 16000
    two = MicArray(np.array([[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]]))
    n = delay_signals(white_noise(1.0, fs, rng=1), [3 / fs, 0.0], fs)
    x = np.concatenate([np.zeros((2, 4000)), np.round(0.1 * n * 32767) / 32767], axis=1)
    tf = estimate_tdoas(x, fs, two, snr_weight=snr_weight)
    assert tf.n_valid > 25
    assert tf.summary_tdoa_s[0] * fs == pytest.approx(3.0, abs=0.05)
    src = np.array([1.2, 0.8, 0.3])
    x3 = simulate_free_field(white_noise(1.0, fs, rng=5), fs, three, src, snr_db=None, rng=2)
    x3 = np.concatenate([np.zeros((3, 4000)), x3], axis=1)
    tf = estimate_tdoas(x3, fs, three, snr_weight=snr_weight)
    np.testing.assert_allclose(tf.summary_tdoa_s, three.tdoa(src), atol=0.05 / fs)


def test_a_zero_lead_in_does_not_become_the_noise_floor(three):
    """Speech in bursts, noise throughout, with and without 1 s of exact zeros before it (a
    whole number of hops: the same frames follow). About its mean a zero frame had the
    mean's square as energy, no digital silence to the VAD: the lead-in became the noise
    floor, every frame between the bursts (3 of 44 active without it) was active, the SNR
    weighting lost its noise reference and fewer frames came out right."""
    from hearsee.audio.signals import synthetic_voice
    from hearsee.audio.tdoa import _energy_vad

    n, hop, frame_len = 3 * 16384, 512, 1024
    src = np.array([1.2, 0.8, 0.3])
    on = np.zeros(n)
    for a in (4096, 20480, 36864):
        on[a:a + 8192] = 1.0
    clean = simulate_free_field(synthetic_voice("male", n / FS, FS, rng=4) * on, FS, three,
                                src, snr_db=None)
    y = clean + 0.3 * clean.std() * np.random.default_rng(0).standard_normal(clean.shape)
    x = np.concatenate([np.zeros((3, 16384)), y], axis=1)
    lead = 16384 // hop
    n_frames = (x.shape[1] - frame_len) // hop + 1
    energy = _frame_energy(x.astype(np.float32), frame_len, hop, n_frames)
    assert np.all(energy[:lead - 1] == 0.0)  # (frame lead - 1 holds the noise's first half)
    starts = np.arange(n_frames - lead) * hop
    quiet = np.array([not on[s:s + frame_len].any() for s in starts])
    alone = _energy_vad(_frame_energy(y.astype(np.float32), frame_len, hop, len(starts)),
                        3.0)[0]
    assert alone[quiet].sum() <= 3  # (a burst's tail leaks into its neighbours)
    np.testing.assert_array_equal(_energy_vad(energy, 3.0)[0][lead:], alone)
    a = estimate_tdoas(y, FS, three)
    b = estimate_tdoas(x, FS, three)
    np.testing.assert_array_equal(b.valid[lead:], a.valid)
    # (frame lead - 1, half zeros, joins the noise spectrum: a few hundredths of a sample)
    np.testing.assert_allclose(b.tdoa_s[lead:], a.tdoa_s, atol=0.05 / FS)
    np.testing.assert_allclose(b.summary_tdoa_s, three.tdoa(src), atol=0.1 / FS)


@pytest.mark.parametrize("method", ["scot", "ml"])
def test_a_block_of_digital_silence_gets_finite_weights(method):
    """SCOT's and ML's floor of G_ii G_jj was 1e-60, zero in single precision: a block of
    frames (``chunk_frames``) of exact zeros -- a recorder's lead-in -- got 1 / 0 and 0 / 0
    weights, numpy's RuntimeWarnings on the CLI. Known delay: +3 samples."""
    import warnings

    from hearsee.audio.tdoa import gcc_weighting

    z = np.zeros((4, 1, 9), np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.all(np.isfinite(gcc_weighting(method, z.astype(np.complex64), z, z, z)))
        two = MicArray(np.array([[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]]))
        n = delay_signals(white_noise(1.0, FS, rng=1), [3 / FS, 0.0], FS)
        x = np.concatenate([np.zeros((2, FS)), n], axis=1)
        tf = estimate_tdoas(x, FS, two, method=method, chunk_frames=8)
    assert tf.n_valid > 25
    assert tf.summary_tdoa_s[0] * FS == pytest.approx(3.0, abs=0.05)


def test_band_too_narrow_for_the_noise_floor_is_a_config_error():
    """A 20 Hz band: the correlation's main lobe (~800 samples) covers every lag of a 64 ms
    frame, so the two-microphone detection test has no floor to measure (it was numpy's
    'zero-size array' ValueError); without the test the known delay still comes out."""
    fs = 16000
    two = MicArray(np.array([[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]]))
    x = delay_signals(white_noise(1.0, fs, rng=1), [3 / fs, 0.0], fs)
    with pytest.raises(ConfigError, match="too narrow"):
        estimate_tdoas(x, fs, two, band_hz=(1000.0, 1020.0))
    from hearsee.errors import DegenerateInputWarning

    # (a band this narrow repeats its peak within the pair's +-0.58 ms: told, and here the
    # known delay is still the highest repeat)
    with pytest.warns(DegenerateInputWarning, match="spatial aliasing"):
        tf = estimate_tdoas(x, fs, two, band_hz=(1000.0, 1100.0))
    assert tf.summary_tdoa_s[0] * fs == pytest.approx(3.0, abs=0.1)


def test_whole_signal_gcc_confidence_looks_outside_the_bands_main_lobe():
    """gcc's confidence is the module's peak-to-second-peak ratio: outside the main lobe of
    max(2, ceil(fs / bandwidth)) samples either side. It used 2 samples whatever band_hz, so a
    300-1000 Hz band's own lobe (23 samples) was the "second peak": an exact delayed copy had
    a confidence of 1.4. Known delay: 3 samples; the ratio computed here from gcc's r."""
    s = white_noise(0.5, FS, rng=3)
    y = delay_signals(s, [3 / FS, 0.0], FS)
    for band, lobe in (((300.0, 1000.0), 23), ((1000.0, 1500.0), 32), (None, 2)):
        res = gcc(y[0], y[1], FS, max_tau_s=10 / FS, band_hz=band)
        assert res.tdoa_s * FS == pytest.approx(3.0, abs=0.01)
        r = np.fft.ifftshift(res.r)
        outside = np.ones(r.size, bool)
        outside[np.arange(3 - lobe, 3 + lobe + 1) % r.size] = False
        want = min(r[3] / r[outside].max(), 1e3)
        assert res.confidence == pytest.approx(want, rel=1e-6)
        assert res.confidence > 4
    with pytest.raises(ConfigError, match="too narrow"):  # (estimate_tdoas' rule)
        gcc(y[0, :400], y[1, :400], FS, band_hz=(1000.0, 1010.0))


def test_gcc_refuses_a_negative_lag_bound():
    s = white_noise(0.25, 8000, rng=3)
    with pytest.raises(ConfigError, match="max_tau_s"):
        gcc(s, s, 8000.0, max_tau_s=-1e-3)
    assert gcc(np.roll(s, 2), s, 8000.0, max_tau_s=1e-3).tdoa_s == pytest.approx(2 / 8000, abs=1e-6)


def test_whole_signal_gcc_refuses_what_it_cannot_correlate():
    """gcc() returned lags for these (bad-input sweep, 2026-11-26): a NaN sample (lag -0.25 s,
    all-NaN correlation), silence (-6.2 ms), a negative rate (the sign flipped, full
    confidence); an empty input raised scipy's ValueError."""
    s = white_noise(0.1, 8000, rng=5)
    with pytest.raises(AudioInputError, match="NaN or inf"):
        gcc(np.r_[s[:-1], np.nan], s, 8000.0)
    with pytest.raises(AudioInputError, match="silent"):
        gcc(np.zeros(100), np.zeros(100), 8000.0)
    with pytest.raises(AudioInputError, match="silent"):
        gcc(s, np.full(s.shape, 0.3), 8000.0)
    for fs in (-8000.0, 0.0, float("nan")):
        with pytest.raises(AudioInputError, match="sample rate"):
            gcc(np.roll(s, 2), s, fs)
    with pytest.raises(AudioInputError, match="equal length"):
        gcc(np.array([]), np.array([]), 8000.0)


def test_whole_signal_gcc_ignores_dc_offsets():
    """gcc() on two signals with different DC offsets gives what it gives without them (before
    2026-11-26 the zero-padded offsets leaked into the lowest bins, which PHAT weighs like the
    rest, and moved a low-pass source's peak by 0.18-2.3 samples in each of these 5 trials)."""
    rng = np.random.default_rng(2)
    fs, n = 16000.0, 8000
    for _ in range(5):
        s = np.convolve(rng.standard_normal(n + 200), np.hanning(40), "same")[:n] * 0.01
        a = np.roll(s, 4) + 0.002 * rng.standard_normal(n)
        b = s + 0.002 * rng.standard_normal(n)
        plain = gcc(a, b, fs, max_tau_s=10 / fs)
        offset = gcc(a + 0.5, b - 0.17, fs, max_tau_s=10 / fs)
        assert offset.tdoa_s * fs == pytest.approx(plain.tdoa_s * fs, abs=1e-6)
        assert offset.confidence == pytest.approx(plain.confidence, rel=1e-6)


def test_a_dc_offset_is_no_source(three):
    """A constant offset on every channel (real ADCs have one, often different per channel)
    over a quiet noise floor: its leakage used to put a confident correlation peak at lag 0 in
    every frame, a source straight above the array. Each frame's mean is now removed."""
    rng = np.random.default_rng(7)
    for offsets in ((0.5, 0.5, 0.5), (0.01, 0.01, 0.01), (0.02, -0.01, 0.005)):
        x = 1e-4 * rng.standard_normal((3, FS)) + np.array(offsets)[:, None]
        tf = estimate_tdoas(x, FS, three)
        assert not tf.valid.any()
        assert np.all(np.isnan(tf.summary_tdoa_s))


def test_a_dc_offset_leaves_a_source_where_it_is(recording, three):
    x, true = recording
    tf0 = estimate_tdoas(x, FS, three)
    tf = estimate_tdoas(x + np.array([0.3, -0.2, 0.1])[:, None] * np.std(x), FS, three)
    np.testing.assert_allclose(tf.summary_tdoa_s, true, atol=0.25 / FS)
    np.testing.assert_allclose(tf.summary_tdoa_s, tf0.summary_tdoa_s, atol=0.02 / FS)


def test_a_dc_offset_does_not_hide_a_voices_quiet_frames(three):
    """A voice with pauses plus per-channel offsets: the energy VAD used to see the offsets in
    every frame's energy, so its noise floor rose toward the voice and 4 of 46 valid frames
    were lost. The frame energies are now taken about each channel's mean."""
    from hearsee.audio.signals import synthetic_voice

    src = np.array([1.2, 0.8, 0.3])
    s = synthetic_voice("male", 2.0, FS, np.random.default_rng(3))
    x = simulate_free_field(s, FS, three, src, snr_db=20, rng=4)
    tf0 = estimate_tdoas(x, FS, three)
    assert 30 <= tf0.valid.sum() < tf0.valid.size  # pauses: some frames are not valid
    for scale in (1.0, 100.0):
        tf = estimate_tdoas(x + np.array([0.3, -0.2, 0.1])[:, None] * scale * np.std(x), FS,
                            three)
        np.testing.assert_array_equal(tf.valid, tf0.valid)
        np.testing.assert_allclose(tf.summary_tdoa_s, tf0.summary_tdoa_s, atol=1e-3 / FS)
        np.testing.assert_allclose(tf.summary_tdoa_s, three.tdoa(src), atol=0.05 / FS)


def test_huge_float_samples_are_scaled_not_overflowed(recording, three):
    """A float recording has no full scale: samples of 1e25 (their squares overflow single
    precision) give the same TDOAs as the recording itself, without numpy warnings."""
    import warnings

    x, _ = recording
    tf0 = estimate_tdoas(x, FS, three)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tf = estimate_tdoas(x * 1e25, FS, three)
    np.testing.assert_allclose(tf.summary_tdoa_s, tf0.summary_tdoa_s, atol=1e-3 / FS)
    np.testing.assert_array_equal(tf.valid, tf0.valid)


def test_a_very_quiet_float_recording_is_localized_like_a_loud_one(three, recording):
    """Scaled to a peak of 1e-15 the recording gave no estimate (single-precision powers under
    the spectra's floor); it is now scaled up first, like a huge one is scaled down."""
    x, true = recording
    ref = estimate_tdoas(x, FS, three).summary_tdoa_s
    np.testing.assert_allclose(ref, true, atol=0.1 / FS)
    for scale in (1e-15, 1e-9, 1e15):
        got = estimate_tdoas(x * scale, FS, three).summary_tdoa_s
        np.testing.assert_allclose(got, ref, atol=1e-3 / FS)


@pytest.mark.parametrize("kw, name", [({"min_confidence": np.nan}, "min_confidence"),
                                      ({"onset_weight": np.nan}, "onset_weight"),
                                      ({"margin_samples": np.nan}, "margin_samples"),
                                      ({"margin_samples": -100.0}, "margin_samples"),
                                      ({"min_confidence": "1"}, "min_confidence"),
                                      ({"onset_weight": "3"}, "onset_weight"),
                                      ({"min_peak_snr": "4"}, "min_peak_snr"),
                                      ({"min_frame_peak_snr": np.inf}, "min_frame_peak_snr"),
                                      ({"phat_beta": "0.5"}, "phat_beta"),
                                      ({"phat_beta": np.nan}, "phat_beta"),
                                      ({"window": "bogus"}, "window")])
def test_estimate_tdoas_refuses_nan_and_unknown_options(three, recording, kw, name):
    """A NaN min_confidence / onset_weight gave a NaN summary; a NaN or negative margin and an
    unknown window raised numpy's or scipy's ValueError deep inside, a string confidence or
    onset weight numpy's TypeError. A string peak-SNR threshold or phat_beta passed the check
    (float() read it) and failed later in numpy; an infinite threshold refused every frame."""
    with pytest.raises(ConfigError, match=name):
        estimate_tdoas(recording[0], FS, three, **kw)


@pytest.mark.parametrize("method", ["scot", "ml", "cc"])
def test_int32_scale_samples_do_not_overflow_the_spectral_products(recording, three, method):
    """Raw 32-bit PCM samples as floats (peak 2**31) are below the old 1e12 scaling threshold,
    but SCOT's G_ii G_jj, ML's |G|^2 and the frames' norms are fourth powers of a frame's
    spectrum and overflowed single precision: SCOT kept 13 of 30 frames, 4 samples off, ML
    none, CC no summary. They must give the unit-scale recording's answer."""
    import warnings

    x, true = recording
    ref = estimate_tdoas(x, FS, three, method=method)
    np.testing.assert_allclose(ref.summary_tdoa_s, true, atol=0.05 / FS)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tf = estimate_tdoas(x * (2.0**31 / np.max(np.abs(x))), FS, three, method=method)
    np.testing.assert_array_equal(tf.valid, ref.valid)
    np.testing.assert_allclose(tf.summary_tdoa_s, ref.summary_tdoa_s, atol=1e-3 / FS)


@pytest.mark.parametrize("kw, name", [({"smooth_frames": -1}, "smooth_frames"),
                                      ({"smooth_frames": np.nan}, "smooth_frames"),
                                      ({"chunk_frames": np.nan}, "chunk_frames"),
                                      ({"summary_upsample": np.nan}, "summary_upsample"),
                                      ({"vad_db": np.nan}, "vad_db"),
                                      ({"vad_db": 4000.0}, "vad_db"),  # (an OverflowError)
                                      ({"progress": True}, "progress"),  # (after the work)
                                      ({"reverb_coherence": np.nan, "reverb_method": "phat"},
                                       "reverb_coherence")])
def test_estimate_tdoas_refuses_bad_counts_and_thresholds(three, recording, kw, name):
    """A negative smooth_frames (ML, SCOT, ROTH) sliced the frames' statistics from the wrong
    end (IndexError), a NaN one or a NaN chunk_frames raised int()'s ValueError, and a NaN
    vad_db, reverb_coherence or summary_upsample silently switched their test off; a huge
    vad_db overflowed, and a progress that is no function failed once every frame was done."""
    x, _ = recording
    with pytest.raises(ConfigError, match=name):
        estimate_tdoas(x, FS, three, method="ml", **kw)


def test_onset_weights_after_a_digitally_silent_lead_in():
    """Frames of digital silence (energy 0) were floored at 1e-30, so the first frame with sound
    rose by ~24-30 decades: weight ~75-90 against 1-13 for the real onsets of the same talker
    after a quiet analog lead-in. A zero lead-in now weighs like the quietest heard frame; a
    recording without zero frames keeps its weights."""
    from hearsee.audio.tdoa import _onset_weights

    analog = np.array([1e-6, 1e-6, 1e-6, 1e-6, 1e-2, 1e-2, 1e-3, 1e-2])
    digital = analog.copy()
    digital[:2] = 0.0
    w = _onset_weights(digital, 3.0)
    np.testing.assert_allclose(w, _onset_weights(analog, 3.0))
    np.testing.assert_allclose(w, [1, 1, 1, 1, 13, 1, 1, 4])
    assert np.all(_onset_weights(np.zeros(5), 3.0) == 1.0)  # all silent: no onset at all


def test_first_arrival_ignores_the_search_bound_as_a_peak():
    """The last admissible lag, still rising toward the physical bound, counted as a local
    maximum (its outer neighbour is -inf), so a correlation within 10 % of its highest peak
    there moved the two-mic summary to the bound, i.e. to end-fire. A real peak further out
    still wins."""
    from hearsee.audio.tdoa import _first_arrival_peaks

    lags = np.arange(-12, 13)
    bound = np.abs(lags) > 10  # the pair's admissible window is +-10
    rising = 0.5 + 0.075 * np.clip(lags - 4, 0, None)  # 0.95 at the bound, no peak there
    win = np.where(lags == 4, 1.0, np.where(lags > 4, rising, 0.2))
    win = np.where(bound, -np.inf, win)[None, :]
    k = np.array([int(np.argmax(win[0]))])
    assert lags[k[0]] == 4
    assert lags[_first_arrival_peaks(win, lags, k, 0.1)[0]] == 4
    far = win.copy()
    far[0, lags == 8] = 0.97  # a real local maximum at lag 8 (lower on both sides)
    far[0, lags == 9] = 0.6
    far[0, lags == 10] = 0.55
    assert lags[_first_arrival_peaks(far, lags, k, 0.1)[0]] == 8


def test_first_arrival_ignores_a_ripple_on_the_highest_lobe():
    """A local maximum on the highest lobe's flank (within the 10 % tolerance, dipping by a
    hair before it) is no separate arrival; a peak as high beyond a real dip is."""
    from hearsee.audio.tdoa import _first_arrival_peaks

    lags = np.arange(-20, 21)
    lobe = 1.0 - 0.003 * (lags - 4) ** 2  # a wide main lobe topping at lag 4
    win = lobe.copy()
    win[lags == 11] = 0.895  # a ripple: above lag 10 (0.892) and 12 (0.808), a 0.3 % dip
    k = np.array([int(np.argmax(win))])
    assert lags[k[0]] == 4
    win = win[None, :]
    assert lags[_first_arrival_peaks(win, lags, k, 0.2)[0]] == 4
    deep = win.copy()
    deep[0, (lags >= 7) & (lags <= 10)] = 0.5  # the same peak behind a dip of 40 %
    assert lags[_first_arrival_peaks(deep, lags, k, 0.2)[0]] == 11


@pytest.mark.parametrize(("seed", "signal"), [(346, "male"), (348, "male"), (348, "female")])
def test_first_arrival_at_48_khz_keeps_a_voice_on_its_main_lobe(seed, signal):
    """Two microphones, free field, a voice at 40 deg 2 m away, 48 kHz, 20 dB: the averaged
    correlation's main lobe is many samples wide and its noise-whitened ripples 2 samples out
    were within the 10 % tolerance -- the summary moved 2-4 samples off the truth
    (2026-12-07: 14 of 32 voice summaries)."""
    from hearsee.sim.audio import simulate_recording

    two = MicArray.from_preset("two-mic")
    src = 2.0 * np.array([np.cos(np.radians(40.0)), np.sin(np.radians(40.0)), 0.0])
    x, truth = simulate_recording(two, src, signal=signal, fs=48000, duration_s=2.0,
                                  snr_db=20, seed=seed)
    tf = estimate_tdoas(x, 48000, two, source_in_plane=True, **SUMMARY_TUNED)
    assert (tf.summary_tdoa_s[0] - truth["tdoa_s"]["0-1"]) * 48000 == pytest.approx(0, abs=0.1)


@pytest.mark.parametrize("kind", ["complex", "bool", "text", "none"])
def test_a_recording_of_no_real_numbers_is_refused(recording, kind):
    """Bad-input sweep of the public API: estimate_tdoas and gcc converted any recording with
    numpy's float(): a complex one lost its imaginary part (a ComplexWarning at most), a bool
    one was read as 0/1 samples, text as the numbers it spells -- each gave TDOAs. Now an
    AudioInputError (audio.signals.as_samples). An object array of numbers is still fine."""
    x, _ = recording
    bad = {"complex": x + 1j * x[::-1], "bool": x > 0, "text": x.astype(str),
           "none": np.where(x > 0, x, None)}[kind]
    with pytest.raises(AudioInputError, match="real numbers"):
        estimate_tdoas(bad, FS, "three-mic")
    with pytest.raises(AudioInputError, match="real numbers"):
        gcc(bad[0], x[1], FS)


def test_integer_pcm_and_object_arrays_of_numbers_keep_their_tdoas(recording):
    """Integer PCM counts and an object array of floats are real samples: the same TDOAs as
    the float recording (estimates are scale-free)."""
    x, true_tdoa = recording
    ref = estimate_tdoas(x, FS, "three-mic").summary_tdoa_s
    np.testing.assert_allclose(ref, true_tdoa, atol=1.5 / FS)
    pcm = np.round(x / np.abs(x).max() * 32000).astype(np.int16)
    np.testing.assert_allclose(estimate_tdoas(pcm, FS, "three-mic").summary_tdoa_s, ref,
                               atol=0.05 / FS)
    np.testing.assert_array_equal(
        estimate_tdoas(x.astype(object), FS, "three-mic").summary_tdoa_s, ref)


@pytest.mark.parametrize("kw, msg", [
    ({"band_hz": 300}, "band_hz"), ({"band_hz": (300, 3000, 8000)}, "band_hz"),
    ({"band_hz": ("300", "3000")}, "band_hz"), ({"band_hz": (True, 3000)}, "band_hz"),
    ({"snr_weight": "yes"}, "snr_weight"), ({"snr_weight": None}, "snr_weight"),
    ({"snr_weight": "ML"}, "snr_weight")])
def test_band_and_snr_weight_options_are_checked(recording, kw, msg):
    """Bad-input sweep of the public API: band_hz=300 raised a builtin TypeError, three numbers
    used the first two, text was parsed; any snr_weight other than False/True/'ml' silently
    switched the SNR weighting on (as True) or off (None)."""
    x, _ = recording
    with pytest.raises(ConfigError, match=msg):
        estimate_tdoas(x, FS, "three-mic", **kw)


def test_band_up_to_infinity_is_still_the_whole_upper_band(recording):
    x, _ = recording
    a = estimate_tdoas(x, FS, "three-mic", band_hz=(300, np.inf)).summary_tdoa_s
    b = estimate_tdoas(x, FS, "three-mic", band_hz=(300, FS / 2)).summary_tdoa_s
    np.testing.assert_array_equal(a, b)


def test_dominant_sample_names_a_corrupt_sample_and_no_level(recording, three):
    """The diagnosis behind the localize CLI's message when no frame is valid: a float sample
    of 1e30 among a source at ~1 (every other frame then falls below single precision) is
    named; a recording at any level (raw 32-bit PCM's 2**31, 1e25, 1e-15: hearsee is
    scale-free), integer PCM counts and a mostly silent recording with a click are not."""
    x, _ = recording
    y = x.copy()
    y[1, 4321] = -1e30
    assert estimate_tdoas(y, FS, three).valid.sum() == 0
    ch, i, v, ratio = dominant_sample(y)
    assert (ch, i, v) == (1, 4321, -1e30)
    assert ratio == pytest.approx(1e30 / np.median(np.abs(y)))
    for scale in (2.0**31 / np.max(np.abs(x)), 1e25, 1e-15):
        assert dominant_sample(x * scale) is None
    pcm = np.round(x / np.max(np.abs(x)) * (2**31 - 1)).astype(np.int32)
    assert dominant_sample(pcm) is None
    click = np.zeros((3, FS))
    click[:, 100] = 1.0
    assert dominant_sample(click) is None


def test_frame_moving_mean_is_ndimage_uniform_filter():
    """The statistics' smoothing over frames (_frame_moving_mean, which replaced
    scipy.ndimage.uniform_filter1d(axis=0, mode="nearest") for speed) gives ndimage's window for
    odd and even lengths, recordings shorter than the window and one frame, to single
    precision."""
    from scipy.ndimage import uniform_filter1d

    from hearsee.audio.tdoa import _frame_moving_mean

    rng = np.random.default_rng(0)
    for F in (1, 2, 3, 7, 40):
        a = rng.standard_normal((F, 3, 17)).astype(np.float32) + 2.0
        for k in (1, 2, 3, 4, 5, 8, 17, 60):  # (above 16: the running-sum path)
            np.testing.assert_allclose(_frame_moving_mean(a, k),
                                       uniform_filter1d(a, k, axis=0, mode="nearest"),
                                       rtol=1e-6, atol=1e-6)
    a = rng.standard_normal((6, 2)).astype(np.float32)
    out = _frame_moving_mean(a, 3)
    assert out.dtype == np.float32 and out is not a
    np.testing.assert_allclose(out[0], (2 * a[0] + a[1]) / 3, rtol=1e-6)  # edge frame repeated


def test_frame_spectra_pad_in_place_as_the_transform_would():
    """frame_spectra writes the windowed frames into a zero-padded buffer (no second padding
    copy in the transform): the same spectra as numpy's own padded rfft of frames less their
    means times the window, in float32 and float64; a buffer shorter than a frame is refused."""
    from hearsee.audio.tdoa import frame_spectra, windowed_frames

    rng = np.random.default_rng(5)
    win = np.hanning(64).astype(np.float32)
    for dtype in (np.float32, np.float64):
        frames = (rng.standard_normal((3, 7, 64)) + 2.5).astype(dtype)  # a DC offset
        ref = np.fft.rfft((frames - frames.mean(axis=-1, keepdims=True)) * win, 90, axis=-1)
        got = frame_spectra(frames, win, 90, 3, 40)
        assert got.shape == (3, 7, 37)
        np.testing.assert_allclose(got, ref[..., 3:40], rtol=0, atol=2e-4 * np.abs(ref).max())
        padded = windowed_frames(frames, win, 90)
        assert padded.shape == (3, 7, 90) and not padded[..., 64:].any()
        np.testing.assert_array_equal(padded[..., :64], windowed_frames(frames, win))
    with pytest.raises(ConfigError, match="nfft"):
        windowed_frames(frames, win, 63)


def test_framing_helpers_refuse_what_is_no_number():
    """The framing checks compared text with numbers (builtin TypeError) or took a string
    sample rate into the rounding; the frame cutter read a ragged signal with numpy's
    ValueError. Each is now hearsee's error naming the value; numbers keep their results
    (NaN still gets the range message)."""
    from hearsee.audio.tdoa import check_frame_ms, check_recording_length, frame_geometry

    with pytest.raises(ConfigError, match="--frame-ms must be a number of milliseconds"):
        check_frame_ms("64", 32.0, names=("--frame-ms", "--hop-ms"))
    with pytest.raises(ConfigError, match="hop must be a number of milliseconds"):
        check_frame_ms(64.0, np.array([32.0, 16.0]))
    with pytest.raises(ConfigError, match="must be > 0 ms, got nan"):
        check_frame_ms(float("nan"), 32.0)
    with pytest.raises(AudioInputError, match="sample rate"):
        frame_geometry("16000", 64.0, 32.0)
    assert frame_geometry(16000, 64.0, 32.0) == (1024, 512)
    with pytest.raises(ConfigError, match="n_samples must be an integer"):
        check_recording_length("100", 64)
    with pytest.raises(ConfigError, match="frame_len must be an integer"):
        check_recording_length(100, 64.5)
    with pytest.raises(AudioInputError, match="recording too short: 10 samples"):
        check_recording_length(np.int64(10), 64)
    check_recording_length(64, 64)  # exactly one frame
    with pytest.raises(AudioInputError, match="samples must be real numbers"):
        frame_signals([[0.0, 1.0], [2.0]], 1, 1)
    with pytest.raises(ConfigError, match="numbers of samples"):
        frame_signals(np.zeros((2, 32)), "8", 4)
    fr = frame_signals(np.arange(12, dtype=np.float32).reshape(1, 12), 4, 4)
    assert fr.dtype == np.float32 and fr[0, 2].tolist() == [8.0, 9.0, 10.0, 11.0]


def test_whole_sphere_summary_reaches_each_pairs_peak_of_a_near_source():
    """A 20 cm cube of eight microphones and white noise 0.76 m away in free field (10 dB):
    the whole-sphere grid's plane-wave TDOAs miss the longest pairs' peaks by up to ~1 sample
    (the grid is ~3 deg coarse and the wavefront is curved), and Newton steps from there
    stopped 0.7-0.9 sample short on five pairs. Every pair's whole-recording TDOA is now
    within 0.05 sample of the geometric truth the test constructs."""
    cube = MicArray([[x, y, z] for x in (-0.1, 0.1) for y in (-0.1, 0.1) for z in (-0.1, 0.1)])
    rng = np.random.default_rng(7)
    src = np.array([-0.49, -0.58, 0.10])
    x = simulate_free_field(white_noise(2.0, FS, rng), FS, cube, src, snr_db=10.0, rng=rng)
    tf = estimate_tdoas(x, FS, cube, method="ml", window="hann", band_hz=(300.0, 7500.0))
    err = (tf.summary_tdoa_s - cube.tdoa(src)) * FS
    assert np.max(np.abs(err)) < 0.05


def test_steered_search_on_a_square_array():
    """joint="steered" on the respeaker-4 preset (a square: some pairs are broadside to some
    grid angles, where a TDOA of ~-1e-20 s wrapped to one index past the upsampled correlation
    and raised IndexError): the known azimuth of a source 2 m away in free field."""
    arr = MicArray.from_preset("respeaker-4")
    src = 2.0 * np.array([np.cos(np.radians(40.0)), np.sin(np.radians(40.0)), 0.0])
    x = simulate_free_field(white_noise(1.0, FS, rng=5), FS, arr, src, snr_db=20, rng=6)
    tf = estimate_tdoas(x, FS, arr, joint="steered", source_in_plane=True, steer_range_m=2.0)
    np.testing.assert_allclose(tf.summary_tdoa_s, arr.tdoa(src, tf.pairs), atol=0.1 / FS)


def test_joint_auto_steers_reverberant_recordings_of_larger_planar_arrays(three):
    """joint="auto" (in SUMMARY_TUNED): a male voice in the plane of the respeaker-6 preset,
    placed by the test 1.7 m away in a room with RT60 0.6 s (judged reverberant) gets the
    in-plane steered search at the in-plane localizer's 2 m; in free field (not reverberant),
    and on the three-microphone preset in the room, each pair's own peak ("pairs")."""
    from hearsee.audio.localize import IN_PLANE_RANGE_M, localize_tdoa
    from hearsee.audio.propagation import simulate_room
    from hearsee.audio.signals import synthetic_voice

    six = MicArray.from_preset("respeaker-6")
    az = 65.0
    src = 1.7 * np.array([np.cos(np.radians(az)), np.sin(np.radians(az)), 0.0])
    s = synthetic_voice("male", 1.5, FS, np.random.default_rng(5))
    room = dict(room_dim=[8.0, 7.0, 3.0], rt60=0.6, array_at=[4.0, 3.5, 1.3], snr_db=20.0)
    band = {"band_hz": (300.0, 3500.0), "source_in_plane": True}
    for arr in (six, three):
        x = simulate_room(s, FS, arr, src, rng=4, **room)
        auto = estimate_tdoas(x, FS, arr, **SUMMARY_TUNED, **band)
        assert auto.summary_method == "phat"  # judged reverberant
        kw = {**SUMMARY_TUNED, **band}
        if arr is six:
            kw.update(joint="steered", steer_range_m=IN_PLANE_RANGE_M)
        else:
            kw.update(joint="pairs")
        ref = estimate_tdoas(x, FS, arr, **kw)
        np.testing.assert_array_equal(auto.summary_tdoa_s, ref.summary_tdoa_s)
        loc = localize_tdoa(auto.summary_tdoa_s, arr, auto.pairs, in_plane=True)
        assert abs((loc.azimuth_deg - az + 180.0) % 360.0 - 180.0) < 5.0
    x = simulate_free_field(s, FS, six, src, snr_db=20.0, rng=4)
    auto = estimate_tdoas(x, FS, six, **SUMMARY_TUNED, **band)
    assert auto.summary_method == "ml"
    pairs = estimate_tdoas(x, FS, six, **{**SUMMARY_TUNED, "joint": "pairs"}, **band)
    np.testing.assert_array_equal(auto.summary_tdoa_s, pairs.summary_tdoa_s)
    steered = estimate_tdoas(x, FS, six, **{**SUMMARY_TUNED, "joint": "steered",
                                              "steer_range_m": IN_PLANE_RANGE_M}, **band)
    assert not np.array_equal(auto.summary_tdoa_s, steered.summary_tdoa_s)
    with pytest.raises(ConfigError, match="steer_range_m"):
        estimate_tdoas(x, FS, six, joint="auto", steer_range_m=-1.0)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("side", [1.0, -1.0])
def test_source_at_the_physical_maximum_without_margin(method, side):
    """A plane wave along the pair's axis (TDOA +-6.997 samples, the physical maximum) with
    ``margin_samples=0`` (bound 6.997): the grid lag 7 nearest the peak was left out of the
    search, so the peak was searched on its lobe's flank at lag 6: no frame was valid (and at
    80 deg every frame was 0.9 sample off)."""
    two = MicArray.from_preset("two-mic")
    s = white_noise(0.5, FS, rng=3)
    for az in (90.0, 80.0):
        u = [np.cos(np.radians(az)), side * np.sin(np.radians(az)), 0.0]
        x = simulate_free_field(s, FS, two, u, far_field=True, snr_db=30, rng=4)
        truth = two.tdoa_far(u)[0] * FS
        r = estimate_tdoas(x, FS, two, method=method, margin_samples=0.0)
        assert r.n_valid == len(r.t)
        assert np.max(np.abs(r.tdoa_s[:, 0] * FS - truth)) < 0.05
        assert abs(r.summary_tdoa_s[0] * FS - truth) < 0.05


@pytest.mark.parametrize("delay", [6.6, 6.9, 6.997])
def test_gcc_peak_near_max_tau(delay):
    """gcc with ``max_tau_s`` the physical maximum (6.997 samples): a delay of 6.9 samples
    came out as 6.0, one of 6.997 as 3.96 with confidence 0."""
    s = white_noise(0.5, FS, rng=5)
    y = delay_signals(s, np.array([delay, 0.0]) / FS, FS)
    r = gcc(y[0], y[1], FS, max_tau_s=6.997 / FS)
    assert abs(r.tdoa_s * FS - delay) < 0.05
    assert r.confidence > 2.0


@pytest.mark.parametrize("band", [(1000.0, 1010.0), (1000.0, 1025.0)])
def test_band_whose_main_lobe_covers_every_lag_is_refused(three, band):
    """A band of one or two bins (64 ms frames): the main lobe covered the whole correlation,
    every confidence was 1e3 and noise alone gave valid frames (61 of 61 for 25 Hz) and a
    whole-recording estimate with three microphones."""
    x = np.random.default_rng(0).standard_normal((3, 32000))
    with pytest.raises(ConfigError, match="band_hz"):
        estimate_tdoas(x, FS, three, band_hz=band)
    r = estimate_tdoas(x, FS, three, band_hz=(1000.0, 2000.0))  # a real band: no source
    assert r.n_valid == 0 and np.all(np.isnan(r.summary_tdoa_s))


def test_huge_smoothing_and_upsampling_take_no_huge_memory():
    """smooth_frames=10**6 copied 10**6 frames of spectra (4 GiB for 0.5 s: a MemoryError or
    the process killed) and summary_upsample=10**6 asked for an 8 GiB correlation. The
    smoothing is now counted, not copied (the same moving mean as scipy's uniform_filter1d,
    edges repeated); the upsampling is bounded."""
    from scipy.ndimage import uniform_filter1d

    from hearsee.audio.tdoa import _frame_moving_mean

    rng = np.random.default_rng(0)
    for n_frames, k in [(1, 17), (5, 18), (30, 31), (30, 200), (100, 1001)]:
        a = rng.standard_normal((n_frames, 3, 7)).astype(np.float32)
        ref = uniform_filter1d(a.astype(float), k, axis=0, mode="nearest")
        np.testing.assert_allclose(_frame_moving_mean(a, k), ref, atol=1e-5)
    two = MicArray.from_preset("two-mic")
    s = white_noise(0.5, FS, rng=3)
    x = delay_signals(s, np.array([3.3, 0.0]) / FS, FS)
    r = estimate_tdoas(x, FS, two, method="ml", smooth_frames=10**6)
    assert r.summary_tdoa_s[0] * FS == pytest.approx(3.3, abs=0.05)
    from hearsee.audio.tdoa import MAX_SUMMARY_UPSAMPLE

    with pytest.raises(ConfigError, match="summary_upsample"):
        estimate_tdoas(x, FS, two, summary_upsample=10**6)
    r = estimate_tdoas(x, FS, two, summary_upsample=MAX_SUMMARY_UPSAMPLE)
    assert r.summary_tdoa_s[0] * FS == pytest.approx(3.3, abs=0.05)


def test_bad_lag_bound_window_and_frame_length_are_config_errors(three, recording):
    """gcc's max_tau_s as text was numpy's TypeError and as an array its ambiguous-truth
    ValueError; a window given as an array of weights was lru_cache's TypeError
    (unhashable); frame_signals cut frames of 10 samples for a frame length of 10.7."""
    x, _ = recording
    for bad in ("1e-3", np.array([1e-3, 2e-3])):
        with pytest.raises(ConfigError, match="max_tau_s"):
            gcc(x[0], x[1], FS, max_tau_s=bad)
    for bad in (np.hanning(1024), ("tukey", [0.25])):
        with pytest.raises(ConfigError, match="window"):
            estimate_tdoas(x, FS, three, window=bad)
    with pytest.raises(ConfigError, match="whole numbers of samples"):
        frame_signals(x, 10.7, 3)
    assert frame_signals(x, 10.0, 3.0).shape == frame_signals(x, 10, 3).shape
    r = estimate_tdoas(x, FS, three, window=["tukey", 0.25])  # a list: as the tuple
    np.testing.assert_array_equal(r.tdoa_s, estimate_tdoas(x, FS, three).tdoa_s)


def test_joint_summary_at_a_high_sample_rate_finds_the_peaks(three):
    """At 192 kHz the three-mic preset's pairs span 85 samples and a white source's main lobe
    is about one sample wide: the fixed 4000-direction grid (~3.2 deg apart, TDOAs up to 2.4
    samples from the nearest direction's) missed the lobes and the summary took a side-lobe
    coincidence -- 9 of 16 plane waves more than 0.1 sample off, the worst 4.5 samples (at
    384 kHz 218), while every frame was right. The grid now grows with the pairs' length."""
    fs = 192000
    s = white_noise(0.25, fs, rng=7)
    for az, el in [(20.0, 5.0), (135.0, 30.0), (-100.0, 15.0), (-30.0, 35.0)]:
        a, e = np.radians(az), np.radians(el)
        u = [np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)]
        x = simulate_free_field(s, fs, three, u, far_field=True, snr_db=20, rng=8)
        r = estimate_tdoas(x, fs, three)
        truth = three.tdoa_far(u)
        np.testing.assert_allclose(np.nanmedian(r.tdoa_s, axis=0) * fs, truth * fs, atol=0.05)
        np.testing.assert_allclose(r.summary_tdoa_s * fs, truth * fs, atol=0.05)


def test_joint_summary_of_a_near_source_keeps_the_closing_peaks(three):
    """A near source's curved wavefront fits no plane wave for about half of the azimuths (the
    in-plane part of the fitted direction is longer than 1): the whole-sphere joint search's
    nearest direction then misses the pairs' peaks by ~a^2 / (8 r c0), and its refinement
    (at most a sample) stopped on a side lobe. The three-mic preset at 96 kHz, white noise
    0.5 m away in its plane: 10 of 24 azimuths had two pairs 2.46 samples (26 us) off while
    every frame was right; a 60 cm triangle or a 40 cm square at 16 kHz, sources 0.8-2.2 m
    away, summaries 130-160 us off. The pairs' own peaks close there and correlate better:
    they are kept (probe seed 1, 2026-12-03)."""
    fs = 96000
    for az in (0.0, 105.0, 225.0, 345.0):
        a = np.radians(az)
        src = 0.5 * np.array([np.cos(a), np.sin(a), 0.0])
        x = simulate_free_field(white_noise(0.3, fs, rng=1), fs, three, src, snr_db=30, rng=2)
        r = estimate_tdoas(x, fs, three)
        truth = three.tdoa(src)
        np.testing.assert_allclose(np.nanmedian(r.tdoa_s, axis=0) * fs, truth * fs, atol=0.05)
        np.testing.assert_allclose(r.summary_tdoa_s * fs, truth * fs, atol=0.05)
    # a 60 cm triangle at 16 kHz (two pairs 2.4 samples off before)
    side = 0.6
    tri = MicArray(side / np.sqrt(3) * np.array(
        [[np.cos(t), np.sin(t), 0.0] for t in np.radians([0.0, 120.0, 240.0])]), 343.0, "tri")
    src = 1.2 * np.array([np.cos(np.radians(250.0)), np.sin(np.radians(250.0)), 0.0])
    x = simulate_free_field(white_noise(0.5, FS, rng=3), FS, tri, src, snr_db=30, rng=4)
    r = estimate_tdoas(x, FS, tri)
    np.testing.assert_allclose(r.summary_tdoa_s * FS, tri.tdoa(src) * FS, atol=0.05)


def test_confidence_range_is_the_documented_one():
    """The GCC confidence is a peak ratio whose range was nowhere documented (it exceeds 1 for
    every usable frame; a reader of the JSON took it for a probability). Documented now -- 0
    to MAX_CONFIDENCE (1000), not a probability -- and these are its ends: a silent frame 0,
    exact copies of a signal the cap, noise below 1 in most frames, a source above 1; README
    states the same range."""
    from pathlib import Path

    from hearsee.audio.tdoa import MAX_CONFIDENCE

    arr = MicArray.from_preset("three-mic")
    rng = np.random.default_rng(5)
    s = rng.standard_normal(FS)
    copies = np.stack([s, np.roll(s, 3), np.roll(s, -2)])
    copies[:, : FS // 4] = 0.0  # a silent first quarter
    tf = estimate_tdoas(copies, FS, arr, snr_weight=False)
    assert tf.confidence.min() == 0.0 and tf.confidence.max() == MAX_CONFIDENCE == 1000.0
    assert np.all((tf.summary_confidence > 1.0) & (tf.summary_confidence <= MAX_CONFIDENCE))
    noise = estimate_tdoas(rng.standard_normal((3, FS)), FS, arr).confidence
    assert 0.0 < noise.min() and np.median(noise) < 1.0 < MAX_CONFIDENCE
    source = simulate_free_field(s, FS, arr, [1.0, 1.5, 0.3], snr_db=20, rng=6)
    assert np.median(estimate_tdoas(source, FS, arr).confidence) > 1.0
    readme = " ".join((Path(__file__).parents[2] / "README.md").read_text().split())
    assert ("is the smallest pair's GCC peak-to-second-peak ratio, not a probability: 0 for a "
            "frame without energy") in readme
    assert "at most 1000 (`audio.tdoa.MAX_CONFIDENCE`)" in readme


# ------------------------------------------------------------- an upsampled recording's empty band
def _upsampled(az_deg, rng, f_low=8000, up=2):
    """Three-mic free-field white noise made at ``f_low`` Hz (sensor noise 20 dB included)
    and upsampled ``up`` times afterwards, as a file read at a higher rate; its true TDOAs."""
    from scipy.signal import resample_poly

    from hearsee.geometry import unit_vector_deg

    arr = MicArray.from_preset("three-mic")
    src = 2.0 * unit_vector_deg(az_deg, 0.0)
    x = simulate_free_field(white_noise(1.5, f_low, rng=rng), f_low, arr, src, snr_db=20,
                            rng=rng + 1)
    return resample_poly(x, up, 1, axis=1), arr, arr.tdoa(src)


def test_empty_top_band_finds_the_edge_of_a_silent_top():
    from hearsee.audio.tdoa import empty_top_band

    p = np.r_[np.ones(300), np.full(212, 1e-10)]  # 512 bins, smoothed over 8
    edge = empty_top_band(p)
    assert 300 <= edge <= 304  # the smoothing moves the edge up by at most half its width
    assert empty_top_band(np.r_[np.ones(300), np.full(212, 1e-5)], db=60) is None  # 50 dB
    assert empty_top_band(np.r_[np.ones(300), np.full(212, 1e-5)], db=40) == edge
    assert empty_top_band(np.ones(512)) is None
    assert empty_top_band(np.zeros(512)) is None  # silence: nothing to compare with
    assert empty_top_band(np.r_[np.ones(10), np.nan]) is None
    with pytest.raises(ConfigError, match="power must be a spectrum"):
        empty_top_band(np.ones((2, 5)))
    with pytest.raises(ConfigError, match="db"):
        empty_top_band(np.ones(5), db=-3)


def test_an_upsampled_recording_is_not_biased_by_its_empty_band():
    """8 kHz noise read at 16 kHz: above ~4.7 kHz it holds only the resampler's mirror images,
    80-100 dB down, whose cross spectra point at mirrored delays. PHAT whitened them to full
    weight and the summary TDOAs came out tens of microseconds off (the azimuth ~12 deg); the
    empty band is now left out, and the TDOAs are as good as at 8 kHz."""
    errs, kept, rows = [], [], []
    for k, az in enumerate((-130.0, 20.0, 100.0)):
        y, arr, truth = _upsampled(az, 10 * k + 3)
        tf = estimate_tdoas(y, 2 * 8000, arr)
        full = estimate_tdoas(y, 2 * 8000, arr, empty_band_db=None)
        assert 3950.0 < tf.band_hz[1] <= 4000.0 and tf.band_hz[0] == 0.0  # the old Nyquist
        assert full.band_hz == (0.0, 8000.0)
        errs.append(np.abs(tf.summary_tdoa_s - truth).max())
        kept.append(np.abs(full.summary_tdoa_s - truth).max())
        rows.append(np.abs(tf.tdoa_s[tf.valid] - truth).max())
    assert max(errs) < 1e-6  # (a sample is 62.5 us; at 8 kHz itself 0.07-0.31 us)
    assert min(kept) > 40e-6  # what the empty band did
    assert max(rows) < 5e-6  # every valid frame too


@pytest.mark.parametrize("band_vad", [True, False])
def test_the_empty_band_search_shares_the_band_spectra_transforms(monkeypatch, band_vad):
    """The loudest frames' whole-band power comes from the transforms of the band spectra
    (chunked: the loudest frames lie in several chunks); the same cut, band and TDOAs as
    when they are transformed on their own (SPECTRA_CACHE_BYTES = 0, band_vad=False: no
    band spectra kept), bit for bit."""
    from hearsee.audio import tdoa as tdoa_mod

    y, arr, truth = _upsampled(-40.0, 21)
    kw = {"band_hz": (200.0, 7000.0), "chunk_frames": 8, "band_vad": band_vad}
    shared = estimate_tdoas(y, 16000, arr, **kw)
    monkeypatch.setattr(tdoa_mod, "SPECTRA_CACHE_BYTES", 0)
    alone = estimate_tdoas(y, 16000, arr, **{**kw, "band_vad": False})
    assert 3950.0 < shared.band_hz[1] <= 4000.0 and shared.band_hz == alone.band_hz
    np.testing.assert_array_equal(shared.tdoa_s, alone.tdoa_s)
    np.testing.assert_array_equal(shared.summary_tdoa_s, alone.summary_tdoa_s)
    assert np.abs(shared.summary_tdoa_s - truth).max() < 1e-6


def test_a_band_given_is_trimmed_and_one_inside_the_empty_band_refused():
    y, arr, truth = _upsampled(60.0, 7)
    tf = estimate_tdoas(y, 16000, arr, band_hz=(200.0, 7000.0))
    assert tf.band_hz[0] == pytest.approx(200.0, abs=16.0) and 3950.0 < tf.band_hz[1] <= 4000.0
    assert np.abs(tf.summary_tdoa_s - truth).max() < 1e-6
    with pytest.raises(ConfigError, match=r"band_hz \(5000.0, 7000.0\): the recording holds "
                                          r"nothing there .* upsampled"):
        estimate_tdoas(y, 16000, arr, band_hz=(5000.0, 7000.0))
    assert estimate_tdoas(y, 16000, arr, band_hz=(5000.0, 7000.0),
                          empty_band_db=None).band_hz[0] > 4900.0  # asked for: as asked


def test_a_recording_made_at_its_rate_keeps_every_bin(recording, three):
    """Sensor noise fills the whole band: nothing is left out and nothing changes."""
    x, _ = recording
    a = estimate_tdoas(x, FS, three)
    b = estimate_tdoas(x, FS, three, empty_band_db=None)
    assert a.band_hz == b.band_hz == (0.0, FS / 2)
    np.testing.assert_array_equal(a.tdoa_s, b.tdoa_s)
    np.testing.assert_array_equal(a.summary_tdoa_s, b.summary_tdoa_s)


def test_empty_band_top_hz_of_native_and_upsampled_recordings(recording):
    from hearsee.audio.tdoa import empty_band_top_hz

    x, _ = recording
    assert empty_band_top_hz(x, FS) is None
    assert empty_band_top_hz(np.zeros((3, FS)), FS) is None  # silence
    assert empty_band_top_hz(x[:, :100], FS) is None  # shorter than a frame
    for up, low in ((2, 8000), (3, 16000)):
        y, _, _ = _upsampled(30.0, 5, f_low=low, up=up)
        top = empty_band_top_hz(y, low * up)
        assert 0.5 * low * 0.9 < top < 0.5 * low * 1.1  # about the old Nyquist frequency
    with pytest.raises(AudioInputError, match="n_channels, n_samples"):
        empty_band_top_hz(np.zeros(100), FS)


# ------------------------------------------------- a microphone wired with inverted polarity
def test_pair_polarity_signs():
    from hearsee.audio.tdoa import pair_polarity

    rng = np.random.default_rng(0)
    r = 0.01 * rng.standard_normal((3, 256))
    r[0, 3] = 1.0  # a peak at +3 samples
    r[1, -2] = -1.0  # a trough at -2
    sign, z = pair_polarity(r, [8.0, 8.0, 8.0])
    assert sign.tolist() == [1, -1, 0] and z[0] > 50 and z[1] > 50 and z[2] < 5
    r[0, 20] = 5.0  # beyond the lag bound: not the pair's extremum
    assert pair_polarity(r, [8.0, 8.0, 8.0])[0].tolist() == [1, -1, 0]


@pytest.mark.parametrize("n_mics, signs, want", [
    (3, [-1, 1, -1], [1]),  # pairs 0-1, 0-2, 1-2: microphone 1
    (3, [-1, -1, 1], [0]),
    (3, [-1, 0, -1], [1]),  # one pair without a sign: the other two still tell
    (3, [-1, 1, 0], None),  # one trough alone names no microphone
    (3, [-1, -1, -1], None),  # no polarity pattern explains it
    (3, [1, 1, 1], None),
    (4, [1, -1, 1, -1, 1, -1], [2]),  # 0-1 0-2 0-3 1-2 1-3 2-3
    (4, [-1, -1, 1, 1, -1, -1], [1, 2]),  # 0 and 3 inverted, or 1 and 2: half the array
])
def test_inverted_microphones(n_mics, signs, want):
    from hearsee.audio.tdoa import inverted_microphones

    pairs = [(i, j) for i in range(n_mics) for j in range(i + 1, n_mics)]
    assert inverted_microphones(signs, pairs, n_mics) == want


def test_inverted_microphones_of_two():
    from hearsee.audio.tdoa import POLARITY_PAIR_SIGNIF, inverted_microphones

    assert inverted_microphones([-1], [(0, 1)], 2, [POLARITY_PAIR_SIGNIF]) == [1]  # (or 0)
    assert inverted_microphones([-1], [(0, 1)], 2, [POLARITY_PAIR_SIGNIF - 0.1]) is None
    assert inverted_microphones([1], [(0, 1)], 2, [50.0]) is None


@pytest.mark.parametrize("preset, signal", [("three-mic", "noise"), ("three-mic", "male"),
                                            ("two-mic", "noise"), ("respeaker-4", "female")])
def test_an_inverted_microphone_is_warned_about(preset, signal):
    """Microphone 1 wired backwards: white noise gave a confident wrong direction (three-mic
    26 deg off, every frame "valid"), a voice no estimate at all, without a word. The averaged
    correlations of its pairs hold a trough where the source's peak belongs: a warning names
    the microphone (two microphones cannot tell which); the recording as wired warns nothing."""
    import warnings

    from hearsee.audio.signals import synthetic_voice
    from hearsee.errors import InvertedPolarityWarning
    from hearsee.geometry import unit_vector_deg

    arr = MicArray.from_preset(preset)
    s = white_noise(1.5, FS, rng=3) if signal == "noise" else synthetic_voice(signal, 1.5, FS,
                                                                               rng=3)
    x = simulate_free_field(s, FS, arr, 2.0 * unit_vector_deg(40.0, 5.0), snr_db=20, rng=4)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        estimate_tdoas(x, FS, arr)
    assert not [w for w in caught if issubclass(w.category, InvertedPolarityWarning)]
    x[1] *= -1.0
    who = r"microphone 1 \(or 0\) seems" if preset == "two-mic" else "microphone 1 seems"
    with pytest.warns(InvertedPolarityWarning, match=f"^{who} wired with inverted polarity"):
        tf = estimate_tdoas(x, FS, arr)
    assert tf.inverted_mics == (1,)


def _wiring_recording(preset, signal, room, duration_s, seed):
    """(array, recording, truth): ``signal`` from [1.2, 1.0, 0.1] m at 20 dB, in free field or
    a 6 x 5 x 3 m room of RT60 ``room`` s -- the wiring checks' test recordings."""
    from hearsee.sim.audio import simulate_recording

    arr = MicArray.from_preset(preset)
    rm = None if room is None else {"room_dim": [6.0, 5.0, 3.0], "rt60": room,
                                    "array_at": [2.5, 2.2, 1.2]}
    x, truth = simulate_recording(arr, [1.2, 1.0, 0.1], signal=signal, duration_s=duration_s,
                                  snr_db=20.0, room=rm, seed=seed)
    return arr, x, truth


def _warned(category, fn, *args):
    """(``fn(*args)``, the warnings of ``category`` it gave)."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn(*args)
    return out, [w for w in caught if issubclass(w.category, category)]


@pytest.mark.parametrize("preset, signal, room, dead, level", [
    ("three-mic", "male", None, 1, 1.0), ("three-mic", "female", 0.3, 2, 0.1),
    ("respeaker-4", "noise", 0.6, 0, 0.01), ("respeaker-6", "male", 0.3, 4, 1.0)])
def test_a_dead_microphone_is_warned_about(preset, signal, room, dead, level):
    """A microphone whose channel holds only noise (unplugged, broken; at the channel's level
    or below it) gave no direction, or a wrong one in `track`, without a word. Its pairs peak
    nowhere while the others hear the source: a DeadMicrophoneWarning names it; the recording
    as recorded warns nothing, nor does a two-microphone array (no pair to compare with)."""
    from hearsee.errors import DeadMicrophoneWarning
    from hearsee.sim.audio import simulate_recording

    arr, x, _ = _wiring_recording(preset, signal, room, 2.0, 9)
    tf, caught = _warned(DeadMicrophoneWarning, estimate_tdoas, x, FS, arr)
    assert not caught
    assert tf.dead_mics == () and tf.wiring_entries()["dead_microphones"] == []
    x[dead] = np.random.default_rng(10).standard_normal(x.shape[1]) * np.std(x[dead]) * level
    with pytest.warns(DeadMicrophoneWarning, match=f"^microphone {dead} hears nothing of what "
                                                   "the others hear"):
        tf = estimate_tdoas(x, FS, arr)
    assert tf.dead_mics == (dead,) and tf.wiring_fault
    assert tf.wiring_entries()["dead_microphones"] == [dead]
    two = MicArray.from_preset("two-mic")
    y, _ = simulate_recording(two, [1.2, 1.0, 0.1], signal=signal, duration_s=2.0,
                              snr_db=20.0, seed=9)
    y[1] = np.random.default_rng(10).standard_normal(y.shape[1]) * np.std(y[1])
    tf, caught = _warned(DeadMicrophoneWarning, estimate_tdoas, y, FS, two)
    assert tf.dead_mics == () and not caught


@pytest.mark.parametrize("preset, signal, room", [
    ("three-mic", "male", None), ("two-mic", "female", None), ("three-mic", "female", 0.6),
    ("respeaker-6", "noise", 0.6)])
def test_channels_out_of_sync_are_warned_about(preset, signal, room):
    """The last channel recorded 2.5 ms late (two sound cards, a dropped buffer): a voice gave
    "no frame holds a detectable source" or a wrong direction, without a word. The averaged
    correlations of its pairs peak beyond the lag the spacing allows: a ChannelSyncWarning
    names the pairs (and, with several, their common microphone) at about the offset; the
    recording in sync -- in a room with RT60 0.6 s too -- warns nothing."""
    import warnings

    from hearsee.audio.tdoa import desynchronized_pairs
    from hearsee.errors import ChannelSyncWarning, InvertedPolarityWarning

    arr, x, truth = _wiring_recording(preset, signal, room, 1.5, 8)
    assert not _warned(ChannelSyncWarning, estimate_tdoas, x, FS, arr)[1]
    last = arr.n_mics - 1
    x[last] = np.roll(x[last], 40)  # 40 samples late
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tf = estimate_tdoas(x, FS, arr)
    (msg,) = [str(w.message) for w in caught if issubclass(w.category, ChannelSyncWarning)]
    # no other diagnosis: a pair out of sync has no polarity to read (a voice's trough within
    # the bound named a microphone as inverted)
    assert not [w for w in caught if issubclass(w.category, InvertedPolarityWarning)]
    # the offset read from the whole recording's correlation: 40 samples late plus the TDOA;
    # only pairs with the late microphone named (in the room not always all of them)
    named = []
    for p, (i, j) in enumerate(tf.pairs):
        if np.isfinite(tf.sync_offsets_s[p]):
            assert j == last
            true = truth["tdoa_s"][f"{i}-{j}"] * FS
            assert tf.sync_offsets_s[p] * FS == pytest.approx(true - 40.0, abs=1.5)
            named.append(f"{i}-{j} at {tf.sync_offsets_s[p] * 1e3:+.2f} ms")
    assert named and (room is not None or len(named) == last)
    who = (f"microphone {last} seems out of sync with the others: pairs " if len(named) > 1
           else "pair ")
    assert msg.startswith(who + ", ".join(named) + " correlate")
    assert np.isnan(desynchronized_pairs(np.zeros((1, 64)), [3.0])).all()  # (flat: nothing)


def test_an_array_file_that_understates_the_spacing_is_warned_about():
    """A 0.4 m pair analysed as the 0.15 m two-mic preset: a source 60 or 90 deg off broadside
    has a TDOA (1.0-1.2 ms) beyond the bound the file allows, and the recording gave no
    summary without a word. The sync warning names it with the offset and the possibility."""
    from hearsee.errors import ChannelSyncWarning
    from hearsee.sim.audio import simulate_recording

    wide = MicArray([[0.0, -0.2, 0.0], [0.0, 0.2, 0.0]], name="wide")
    for az in (60.0, 90.0):
        a = np.radians(az)
        x, truth = simulate_recording(wide, [2 * np.cos(a), 2 * np.sin(a), 0.0],
                                      signal="male", duration_s=1.5, snr_db=20.0, seed=2)
        with pytest.warns(ChannelSyncWarning, match="farther apart than the array says"):
            tf = estimate_tdoas(x, FS, "two-mic")
        assert tf.sync_offsets_s[0] == pytest.approx(truth["tdoa_s"]["0-1"], abs=1.5 / FS)


def test_a_spatially_aliased_band_is_warned_about():
    """--band-hz 5000,5200 gave the three-mic preset a confident direction 31 deg off without a
    word: a narrow band far above the spacing's c / 2d correlates in repeats 1 / fc apart at
    nearly the peak's height, and several fit within the pair's delays. The level is the flat
    band's envelope sinc(B / fc) at the first repeat; bands whose repeat lies beyond the
    delays, or that are wide, warn nothing."""
    import warnings

    from hearsee.audio.tdoa import ALIAS_LEVEL, band_alias_level
    from hearsee.errors import DegenerateInputWarning

    tmax = 0.15 / 343.0  # the three-mic preset's side
    assert band_alias_level(5000.0, 5200.0, tmax) == pytest.approx(np.sinc(200 / 5100))
    assert band_alias_level(300.0, 3500.0, tmax) < 0.2
    assert band_alias_level(600.0, 700.0, tmax) == 0.0  # (1 / 650 Hz > 2 x 0.44 ms)
    assert band_alias_level(2000.0, 2500.0, tmax) > ALIAS_LEVEL > band_alias_level(
        1000.0, 2000.0, tmax)
    arr = MicArray.from_preset("three-mic")
    x = simulate_free_field(white_noise(1.0, FS, rng=3), FS, arr, [1.0, 1.0, 0.0], snr_db=20,
                            rng=4)
    with pytest.warns(DegenerateInputWarning, match=r"^band 50\d\d-5200 Hz is narrow .*"
                                                    r"spatial aliasing"):
        estimate_tdoas(x, FS, arr, band_hz=(5000.0, 5200.0))
    for band in ((300.0, 3500.0), None):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            estimate_tdoas(x, FS, arr, band_hz=band)
        assert not [w for w in caught if issubclass(w.category, DegenerateInputWarning)]
