import numpy as np
import pytest

from hearsee.audio.arrays import MicArray
from hearsee.audio.propagation import (
    MAX_IMAGE_ORDER,
    MIN_WALL_DISTANCE_M,
    add_noise,
    delay_signals,
    room_impulse_responses,
    simulate_free_field,
    simulate_room,
    sum_responses,
)
from hearsee.audio.signals import synthetic_voice, white_noise
from hearsee.errors import AudioInputError, ConfigError, GeometryError


def test_integer_delay_is_exact_shift():
    x = white_noise(0.1, 16000, rng=1)
    y = delay_signals(x, [0.0, 5 / 16000], 16000)
    np.testing.assert_allclose(y[0], x, atol=1e-9)
    np.testing.assert_allclose(y[1, 5:], x[:-5], atol=1e-9)


def test_fractional_delay_matches_cross_spectrum_phase():
    fs = 16000
    x = white_noise(1.0, fs, rng=2)
    tau = 2.37 / fs
    y = delay_signals(x, [0.0, tau], fs)
    n = 4096
    X0, X1 = np.fft.rfft(y[0, 2000:2000 + n]), np.fft.rfft(y[1, 2000:2000 + n])
    f = np.fft.rfftfreq(n, 1 / fs)
    band = (f > 100) & (f < 4000)
    phase = np.unwrap(np.angle(X1[band] * np.conj(X0[band])))
    slope = np.polyfit(2 * np.pi * f[band], phase, 1)[0]
    assert -slope == pytest.approx(tau, rel=0.02)


def test_free_field_spreading_and_noise():
    arr = MicArray.from_preset("two-mic")
    x = white_noise(0.5, 16000, rng=3)
    src = np.array([0.0, 1.0, 0.0])
    y = simulate_free_field(x, 16000, arr, src)
    r = np.linalg.norm(arr.positions - src, axis=1)
    ratio = np.std(y[1, 200:]) / np.std(y[0, 200:])
    assert ratio == pytest.approx(r[0] / r[1], rel=0.02)
    noisy = add_noise(y, 10.0, rng=4)
    snr = 10 * np.log10(np.mean(y**2) / np.mean((noisy - y) ** 2))
    assert snr == pytest.approx(10.0, abs=0.3)
    with pytest.raises(GeometryError):
        simulate_free_field(x, 16000, arr, arr.positions[0])


# ---------------------------------------------------------------------------- rooms
ROOM = [6.0, 5.0, 3.0]
AT = [3.0, 2.5, 1.4]


@pytest.mark.parametrize("rt60", [0.0, 0.3])
def test_room_gcc_tdoa_matches_geometry(rt60, gcc_phat_ref):
    fs = 16000
    arr = MicArray.from_preset("three-mic")
    src = np.array([1.2, 0.9, 0.3])
    y = simulate_room(white_noise(0.5, fs, rng=0), fs, arr, src, ROOM, rt60, AT)
    truth = arr.tdoa(src)
    est = np.array([gcc_phat_ref(y[i], y[j], fs, 0.0006) for i, j in arr.pairs])
    tol = 0.1 if rt60 == 0 else 0.25  # samples
    np.testing.assert_allclose(est * fs, truth * fs, atol=tol)


def test_room_rirs_aligned_and_scaled():
    fs = 16000
    arr = MicArray.from_preset("two-mic")
    src = np.array([2.0, -0.5, 0.0])
    h = room_impulse_responses(fs, arr.positions + AT, src + AT, ROOM, 0.0)
    r = np.linalg.norm(arr.positions - src, axis=1)
    # direct path peak at r/c (the fractional-delay latency is removed) with 1/r amplitude
    np.testing.assert_array_equal(np.argmax(h, axis=1), np.round(r / 343.0 * fs).astype(int))
    lp = np.array([np.sum(hk[int(rk / 343 * fs) - 3: int(rk / 343 * fs) + 5])
                   for hk, rk in zip(h, r, strict=True)])
    np.testing.assert_allclose(lp, 1 / r, rtol=0.1)
    # anechoic room == free field below 5 kHz
    from scipy.signal import butter, sosfiltfilt

    x = white_noise(0.4, fs, rng=1)
    yr = simulate_room(x, fs, arr, src, ROOM, 0.0, AT)
    yf = simulate_free_field(x, fs, arr, src)
    sos = butter(8, 5000, fs=fs, output="sos")
    a, b = sosfiltfilt(sos, yf), sosfiltfilt(sos, yr)
    assert np.std(a - b) / np.std(a) < 0.03


def test_room_reverberation_time():
    import pyroomacoustics as pra

    fs = 16000
    h = room_impulse_responses(fs, [[3.0, 2.5, 1.5]], [1.0, 1.0, 1.2], ROOM, 0.4)
    assert pra.experimental.measure_rt60(h[0], fs) == pytest.approx(0.4, rel=0.3)


def test_room_rotated_mic_positions_and_snr(gcc_phat_ref):
    fs = 16000
    arr = MicArray.from_preset("two-mic")
    rot = arr.positions[:, [1, 0, 2]]  # mics now on the x axis (head turned 90 deg)
    src = np.array([1.5, 0.4, 0.0])
    x = white_noise(0.5, fs, rng=2)
    clean = simulate_room(x, fs, arr, src, ROOM, 0.0, AT, mic_positions=rot)
    r = np.linalg.norm(rot - src, axis=1)
    est = gcc_phat_ref(clean[0], clean[1], fs, 0.0005)
    assert est * fs == pytest.approx((r[0] - r[1]) / 343.0 * fs, abs=0.1)
    noisy = simulate_room(x, fs, arr, src, ROOM, 0.0, AT, snr_db=5.0, rng=3, mic_positions=rot)
    snr = 10 * np.log10(np.mean(clean**2) / np.mean((noisy - clean) ** 2))
    assert snr == pytest.approx(5.0, abs=0.2)
    with pytest.raises(GeometryError, match="3 rows"):
        simulate_room(x, fs, arr, src, ROOM, 0.0, AT, mic_positions=np.eye(3))


def test_room_bad_geometry_and_rt60():
    fs = 8000
    arr = MicArray.from_preset("two-mic")
    x = white_noise(0.05, fs, rng=0)
    with pytest.raises(GeometryError, match="source .* outside the room"):
        simulate_room(x, fs, arr, [5.0, 0.0, 0.0], ROOM, 0.0, AT)
    with pytest.raises(GeometryError, match="source .* too close to a wall"):
        simulate_room(x, fs, arr, [0.0, 0.0, 1.6 - MIN_WALL_DISTANCE_M / 2], ROOM, 0.0, AT)
    with pytest.raises(GeometryError, match="microphone 0 .* too close to a wall"):
        simulate_room(x, fs, arr, [1.0, 0.0, 0.0], ROOM, 0.0, [3.0, 0.1, 1.0])
    with pytest.raises(GeometryError, match="microphone 1 .* outside the room"):
        simulate_room(x, fs, arr, [1.0, 0.0, 0.0], ROOM, 0.0, [3.0, 4.95, 1.0])
    with pytest.raises(GeometryError, match="room dimensions"):
        simulate_room(x, fs, arr, [1.0, 0.0, 0.0], [6.0, -5.0, 3.0], 0.3, AT)
    with pytest.raises(GeometryError, match="coincides"):
        simulate_room(x, fs, arr, arr.positions[1], ROOM, 0.0, AT)
    with pytest.raises(ConfigError, match="too short for a 20x20x5 m room"):
        simulate_room(x, fs, arr, [1.0, 0.0, 0.0], [20.0, 20.0, 5.0], 0.1, [10, 10, 1])
    with pytest.raises(ConfigError, match="non-negative"):
        simulate_room(x, fs, arr, [1.0, 0.0, 0.0], ROOM, -0.2, AT)
    # Sabine: 5 s in a 3 m cube needs image order 808 (it ran out of memory in pyroomacoustics)
    with pytest.raises(ConfigError, match="order 808 .* shorter RT60 or a larger room$"):
        simulate_room(x, fs, arr, [0.5, 0.5, 0.0], [3.0, 3.0, 3.0], 5.0, [1.5, 1.5, 1.5])
    with pytest.raises(ConfigError, match="order 201 .* or a smaller max_order$"):
        room_impulse_responses(fs, arr.positions + AT, [4.0, 2.5, 1.4], ROOM, 0.3,
                               max_order=MAX_IMAGE_ORDER + 1)


@pytest.mark.parametrize("frac", [0.1, 0.25, 0.5, 0.77, 3.33, -1.6])
def test_free_field_fractional_tdoa_accuracy(frac, gcc_phat_ref):
    """Two mics whose path difference is ``frac`` samples: GCC-PHAT recovers it to 0.02."""
    fs = 16000
    d = frac * 343.0 / fs  # metres of path difference
    src = np.array([2.0, 0.0, 0.0])
    mics = np.array([[0.0, 0.0, 0.0], [-d, 0.0, 0.0]])  # mic 1 is d metres farther
    y = simulate_free_field(white_noise(0.5, fs, rng=9), fs, mics, src)
    est = gcc_phat_ref(y[1], y[0], fs, 4.0 / fs)
    assert est * fs == pytest.approx(frac, abs=0.02)


def test_bad_rates_speeds_and_noise_levels_are_refused():
    """Found by a bad-input sweep (2026-11-26); before, each gave numbers without a word:
    speed_of_sound 0 was replaced by 343 m/s (``c or default``), a sample rate of 0 or below
    returned the signal undelayed or at the wrong length, a NaN SNR or an infinite reference
    power gave an all-NaN / all-inf recording, and a 1 Hz synthetic voice never returned."""
    arr = MicArray.from_preset("two-mic")
    s = white_noise(0.1, 16000, rng=0)
    src = [1.0, 1.0, 0.0]
    for c in (0.0, -343.0, float("nan"), float("inf")):
        with pytest.raises(GeometryError,
                           match=r"speed_of_sound \(m/s\) must be a finite number > 0"):
            simulate_free_field(s, 16000, arr.positions, src, speed_of_sound=c)
    with pytest.raises(GeometryError, match="speed_of_sound"):
        room_impulse_responses(16000, arr.positions + [3.0, 3.0, 1.0], [4.0, 4.0, 1.0],
                               [6.0, 6.0, 3.0], 0.0, speed_of_sound=0.0)
    # (a numeric string, a bool and a 1-element array passed float() before 2026-11-26)
    for fs in (0.0, -16000.0, float("nan"), float("inf"), "16000", True, np.array([16000.0])):
        with pytest.raises(AudioInputError, match="sample rate must be a positive number"):
            simulate_free_field(s, fs, arr, src)
        with pytest.raises(AudioInputError, match="sample rate must be a positive number"):
            delay_signals(s, [1e-3], fs)
    with pytest.raises(GeometryError, match="one or more"):
        delay_signals(s, [], 16000)
    with pytest.raises(ConfigError, match="SNR must be a finite number"):
        add_noise(s, float("nan"))
    with pytest.raises(ConfigError, match="SNR must be a finite number"):
        add_noise(s, -float("inf"))
    with pytest.raises(ConfigError, match="reference_power"):
        add_noise(s, 10.0, reference_power=float("inf"))
    with pytest.raises(AudioInputError, match="NaN or inf"):
        add_noise(np.r_[s, np.nan], 10.0)
    with pytest.raises(ConfigError, match="at least 4000 Hz"):
        synthetic_voice("male", 1.0, 1)
    # and the defaults still apply: the array's own speed of sound when none is given
    slow = MicArray(arr.positions, speed_of_sound=300.0)
    y = simulate_free_field(s, 16000, slow, src)
    np.testing.assert_allclose(y, simulate_free_field(s, 16000, arr.positions, src,
                                                      speed_of_sound=300.0))


def test_delay_signals_output_has_the_asked_length():
    """``n_out`` longer than the signal plus its delay returned fewer samples (the FFT length),
    and a negative ``n_out`` silently cut samples off the end (numpy slicing)."""
    fs = 16000
    x = white_noise(100 / fs, fs, rng=3)
    y = delay_signals(x, [150 / fs], fs, gains=0.5, n_out=400)  # whole-sample delay: a shift
    assert y.shape == (1, 400)
    np.testing.assert_allclose(y[0, 150:250], 0.5 * x, atol=1e-9)
    np.testing.assert_allclose(y[0, :150], 0.0, atol=1e-9)
    np.testing.assert_allclose(y[0, 250:], 0.0, atol=1e-9)
    for bad in (-3, 2.5, "10"):
        with pytest.raises(ConfigError, match="n_out"):
            delay_signals(x, [0.0], fs, n_out=bad)
    # a huge n_out: the delays' memory rule, not numpy's MemoryError (10**12 samples)
    with pytest.raises(ConfigError, match=r"n_out = 1000000000000 samples is more than"):
        delay_signals(x, [0.0], fs, n_out=10**12)
    # the default stays the signal's length
    assert delay_signals(x, [0.0, 1e-3], fs).shape == (2, 100)


def test_a_source_whose_sound_arrives_after_the_signal_ends_is_refused():
    """Sample 0 is the emission time: a source 1000 m away (2.9 s) in a 2 s simulation was
    recorded as the delay filter's sinc tails (then scaled to full scale by save_recording and
    written with a truth it does not hold), and one 1e8 m away asked for 10^10 FFT bins. A
    source whose sound arrives before the end is simulated as before: silent until r / c."""
    fs, c = 8000, 343.0
    x = white_noise(0.5, fs, rng=3)
    mics = np.array([[0.0, -0.1, 0.0], [0.0, 0.1, 0.0]])
    for far in (0.51 * c, 1e8, 1e300):  # (the last overflowed r: two RuntimeWarnings first)
        with pytest.raises(GeometryError, match=r"longer than the 0\.5 s simulated"):
            simulate_free_field(x, fs, mics, [far, 0.0, 0.0])
    src = np.array([0.25 * c, 0.0, 0.0])  # heard from ~0.25 s on
    y = simulate_free_field(x, fs, mics, src)
    arrive = int(np.linalg.norm(mics[0] - src) / c * fs)
    assert np.max(np.abs(y[:, arrive + 50:])) > 100 * np.max(np.abs(y[:, :arrive - 50]))
    room = dict(room_dim=[400.0, 4.0, 3.0], rt60=0.0, array_at=[2.0, 2.0, 1.5])
    arr = MicArray(mics, name="pair")
    with pytest.raises(GeometryError, match="its sound takes 0.5"):
        simulate_room(x, fs, arr, [0.51 * c, 0.0, 0.0], **room)


def test_every_microphone_must_hear_the_free_field_source():
    """Audit p21: only the nearest microphone was checked, so with microphones 4 m and 9 m
    from the source and 400 samples at 16 kHz (25 ms, 8.6 m of sound) the far channel got no
    direct sound (arrival at sample 419.8) and no error: RMS 0.0016 of the tails only. Now a
    GeometryError; a far microphone that hears it gets the exact delay and 1 / r."""
    fs, c = 16000, 343.0
    x = white_noise(400 / fs, fs, rng=0)
    with pytest.raises(GeometryError, match=r"9 m from the farthest microphone.*0\.02624 s"):
        simulate_free_field(x, fs, [[0.0, 0.0, 0.0], [5.0, 0.0, 0.0]], [-4.0, 0.0, 0.0])
    r = 300 * c / fs  # 300 samples away: heard from sample 300 to the end
    y = simulate_free_field(x, fs, [[0.0, 0.0, 0.0], [r - 4.0, 0.0, 0.0]], [-4.0, 0.0, 0.0])
    np.testing.assert_allclose(y[1, 300:], x[:100] / r, atol=1e-6)
    np.testing.assert_allclose(y[1, :290], 0.0, atol=1e-3 * np.abs(x).max() / r)


def test_delay_signals_and_microphones_refuse_bad_input():
    """Audit p21: a delay of 1e12 s was a MemoryError traceback (114 PiB asked), gains of the
    wrong count numpy's broadcast ValueError, a NaN gain an all-NaN recording, no microphone
    at all numpy's ValueError. Now typed errors; valid gains scale each channel exactly."""
    from hearsee.audio.propagation import MAX_RIR_SAMPLES

    fs = 16000
    x = white_noise(400 / fs, fs, rng=0)
    for d in ([1e12], [0.0, (MAX_RIR_SAMPLES + 1) / fs]):
        with pytest.raises(ConfigError, match=f"the limit is {MAX_RIR_SAMPLES} samples"):
            delay_signals(x, d, fs)
    for g in ([1.0, 2.0, 3.0], np.nan, [1.0, np.inf], "2", [[1.0, 2.0]]):
        with pytest.raises(ConfigError, match="gains"):
            delay_signals(x, [0.001, 0.002], fs, gains=g)
    y = delay_signals(x, [3 / fs, 10 / fs], fs, gains=[0.5, -2.0])  # whole samples: a shift
    np.testing.assert_allclose(y[0, 3:], 0.5 * x[:-3], atol=1e-9)
    np.testing.assert_allclose(y[1, 10:], -2.0 * x[:-10], atol=1e-9)
    np.testing.assert_allclose(delay_signals(x, [3 / fs], fs, gains=[0.5]), y[:1], atol=1e-12)
    for mics, match in ((np.zeros((0, 3)), "N >= 1"), ([[0.0, 0.0, np.nan]], "finite"),
                        ([["a", "b", "c"]], "expected numbers"), ([0.0, 0.0, 0.0], "N x 3")):
        with pytest.raises(GeometryError, match=match):
            simulate_free_field(x, fs, mics, [1.0, 0.0, 0.0])


def test_an_impulse_response_longer_than_memory_allows_is_refused():
    """A 1e9 m long room with RT60 0.3 s (image order 42) asked pyroomacoustics for 7 TiB of
    impulse response: a MemoryError traceback. Now a ConfigError before it is computed."""
    with pytest.raises(ConfigError, match="impulse responses up to .* more memory"):
        room_impulse_responses(16000, [[2.0, 2.0, 1.5]], [3.0, 2.0, 1.5], [1e9, 4.0, 3.0], 0.3)


def test_signal_helpers_refuse_text_and_ragged_signals():
    """delay_signals, add_noise and resample read a signal of text through numpy ("0.5" as
    0.5, True as 1) or raised its builtin ValueError ("x", a ragged list). Now the recording
    check's AudioInputError; a NaN sample in delay_signals too (it gave an all-NaN recording).
    Numbers still work."""
    from hearsee.audio.signals import resample

    s = np.sin(np.arange(400) / 5.0)
    for bad in (s.astype(str), ["x", "y"], [True, False, True], [[1.0, 2.0], [3.0]]):
        for call in (lambda v: delay_signals(v, [1e-4], 16000),
                     lambda v: add_noise(v, 10.0, 0), lambda v: resample(v, 16000, 8000)):
            with pytest.raises(AudioInputError, match="^signal: samples must be real numbers"):
                call(bad)
    with pytest.raises(AudioInputError, match="^signal contains NaN or infinite samples"):
        delay_signals(np.r_[s, np.nan], [1e-4], 16000)
    assert delay_signals(s.tolist(), [1e-4], 16000).shape == (1, 400)
    assert resample(s, 16000, 8000).shape == (200,)
    np.testing.assert_array_equal(add_noise(s, None), s)


def test_add_noise_refuses_an_snr_out_of_its_range():
    """10**(snr/10) overflowed (OverflowError) at 1e6 dB, and -500 dB drowned the signal in
    noise 1e50 times its power, silently. The range is [-60, 200] dB, its ends included."""
    from hearsee.audio.propagation import MAX_SNR_DB, MIN_SNR_DB, check_snr_db

    assert (MIN_SNR_DB, MAX_SNR_DB) == (-60.0, 200.0)
    s = white_noise(0.1, 16000, rng=1)
    for snr in (1e6, -500.0, 200.001, -60.001, np.float32(1e30), 10**400 // 10**100):
        with pytest.raises(ConfigError, match="SNR must be within -60 to 200 dB"):
            add_noise(s, snr, rng=0)
    for snr in (float("nan"), "10", [10.0]):
        with pytest.raises(ConfigError, match="SNR must be a finite number of dB"):
            check_snr_db(snr)
    assert check_snr_db(None) is None and check_snr_db(np.int64(20)) == 20.0
    # at the ends: the noise is the clean signal's power times 10**(-snr/10)
    low = add_noise(s, -60.0, rng=3) - s
    assert np.mean(low**2) / np.mean(s**2) == pytest.approx(1e6, rel=0.15)
    high = add_noise(s, 200.0, rng=3) - s
    assert np.mean(high**2) / np.mean(s**2) == pytest.approx(1e-20, rel=0.15)


def test_room_refuses_a_signal_that_is_no_real_samples():
    """simulate_room read its signal with np.asarray(float): a NaN or infinite sample gave an
    all-NaN recording without a word, text was numpy's ValueError, booleans were 0/1 (the
    free field, through delay_signals, refused them all)."""
    fs = 8000
    arr = MicArray.from_preset("two-mic")
    x = white_noise(0.05, fs, rng=0)
    for bad in (np.where(np.arange(x.size) == 7, np.nan, x),
                np.where(np.arange(x.size) == 7, np.inf, x), "abc", x > 0):
        with pytest.raises(AudioInputError, match="signal"):
            simulate_room(bad, fs, arr, [1.0, 0.0, 0.0], ROOM, 0.0, AT)
    y = simulate_room(x, fs, arr, [1.0, 0.0, 0.0], ROOM, 0.0, AT)
    assert y.shape == (2, x.size) and np.all(np.isfinite(y))


def test_add_noise_refuses_an_empty_signal_and_a_text_reference_power():
    """An empty signal was said to contain "NaN or inf samples" (its mean power was NaN);
    reference_power="1" was read as 1.0 through float()."""
    with pytest.raises(AudioInputError, match="empty"):
        add_noise(np.zeros((2, 0)), 10.0, rng=0)
    x = white_noise(0.05, 8000, rng=0)
    with pytest.raises(ConfigError, match="reference_power"):
        add_noise(x, 10.0, rng=0, reference_power="1")
    y = add_noise(x, 10.0, rng=0, reference_power=4.0)  # noise power 4 / 10
    assert np.mean((y - x) ** 2) == pytest.approx(0.4, rel=0.1)


def test_far_field_must_be_a_flag():
    """far_field="no" is truthy: it gave a plane wave without a word."""
    arr = MicArray.from_preset("two-mic")
    s = white_noise(0.05, 16000, rng=1)
    with pytest.raises(ConfigError, match="^far_field must be True or False, got 'no'"):
        simulate_free_field(s, 16000, arr, [1.0, 0.0, 0.0], far_field="no")
    a = simulate_free_field(s, 16000, arr, [1.0, 0.0, 0.0], far_field=np.bool_(True))
    np.testing.assert_array_equal(a, simulate_free_field(s, 16000, arr, [1.0, 0.0, 0.0],
                                                         far_field=True))


def test_sum_responses_adds_parts_of_different_lengths_from_the_same_instant():
    a = np.array([[1.0, 2.0, 3.0], [0.0, 1.0, 0.0]])
    b = np.array([[10.0], [20.0]])
    c = np.zeros((2, 5))
    c[:, 4] = [7.0, 8.0]
    np.testing.assert_array_equal(sum_responses([a, b, c]),
                                  [[11.0, 2.0, 3.0, 0.0, 7.0], [20.0, 1.0, 0.0, 0.0, 8.0]])


def test_text_sources_and_delays_and_empty_response_sums_are_refused():
    """A source or delays given as text were numpy's ValueError; sum_responses of nothing its
    IndexError, of parts with different microphone counts a broadcast ValueError."""
    from hearsee.audio.propagation import delay_signals, simulate_free_field, sum_responses

    sig = white_noise(0.1, 16000, 1)
    with pytest.raises(GeometryError, match="source"):
        simulate_free_field(sig, 16000, MicArray.from_preset("three-mic"), "x")
    with pytest.raises(GeometryError, match="delays"):
        delay_signals(sig, "x", 16000)
    for parts in ([], [np.zeros((2, 3)), np.zeros((3, 3))], [np.zeros(3)]):
        with pytest.raises(GeometryError, match="sum_responses"):
            sum_responses(parts)
    total = sum_responses([np.ones((2, 3)), np.ones((2, 5))])
    np.testing.assert_array_equal(total, [[2, 2, 2, 1, 1]] * 2)


def test_room_points_and_settings_that_are_no_numbers_are_typed_errors():
    """The room simulators read their points with numpy's float conversion: text or a ragged
    list was a builtin ValueError, True 1 m, an empty microphone list pyroomacoustics'
    ValueError, a preset name for the array an AttributeError, a text speed of sound in
    image_sources a TypeError (0 m/s "an RT60 too short"); the free field's text signal was
    a source "too far" (np.size("abc") is 1). Now each is a hearsee error, and good
    arguments give the recording they gave."""
    from hearsee.audio.propagation import image_sources

    fs, arr = 16000, MicArray.from_preset("two-mic")
    x = white_noise(0.1, fs, rng=5)
    room = ([5.0, 4.0, 3.0], 0.0)
    for bad in ("2,2,1", [True, 2, 1], [[2, 2], [1]]):
        with pytest.raises(GeometryError, match="array_at"):
            simulate_room(x, fs, arr, [1.0, 0.0, 0.0], *room, bad)
        with pytest.raises(GeometryError, match="source"):
            simulate_room(x, fs, arr, bad, *room, [2.0, 2.0, 1.0])
    with pytest.raises(GeometryError, match="MicArray"):
        simulate_room(x, fs, "two-mic", [1.0, 0.0, 0.0], *room, [2.0, 2.0, 1.0])
    for mics in ("abc", [[2, 2, 1], [1, 1]], np.zeros((0, 3))):
        with pytest.raises(GeometryError, match="microphone positions"):
            room_impulse_responses(fs, mics, [1.0, 1.0, 1.0], *room)
    with pytest.raises(GeometryError, match="source"):
        room_impulse_responses(fs, [[2.0, 2.0, 1.0]], "1,1,1", *room)
    with pytest.raises(ConfigError, match="directivity"):
        room_impulse_responses(fs, [[2.0, 2.0, 1.0]], [1.0, 1.0, 1.0], *room, directivities=3)
    for c in ("343", 0.0, float("nan")):
        with pytest.raises(GeometryError, match="speed_of_sound"):
            image_sources(0.3, [5.0, 4.0, 3.0], c)
    with pytest.raises(AudioInputError, match="signal"):
        simulate_free_field("abc", fs, arr, [1.0, 0.0, 0.0])
    # good arguments: the direct path of the room as before (peak at r / c, amplitude ~1 / r)
    y = simulate_room(x, fs, arr, (1.0, 0.0, 0.0), *room, np.array([2.0, 2.0, 1.0]))
    np.testing.assert_allclose(y, simulate_free_field(x, fs, arr, [1.0, 0.0, 0.0]),
                               atol=0.1 * np.abs(y).max())
    assert image_sources(0.3, [5.0, 4.0, 3.0], 343) == image_sources(0.3, [5.0, 4.0, 3.0])
