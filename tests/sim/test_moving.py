import re
import warnings

import numpy as np
import pytest
import scipy.signal as ss

from hearsee.audio.arrays import MicArray
from hearsee.audio.propagation import simulate_free_field
from hearsee.errors import AudioInputError, ConfigError, GeometryError, InputFileError
from hearsee.sim.moving import (
    Trajectory,
    fractional_delay,
    linear_trajectory,
    load_trajectory,
    retarded_delays,
    save_trajectory,
    simulate_moving_free_field,
    simulate_moving_recording,
    simulate_moving_room,
    waypoint_trajectory,
)

FS = 16000


def _bandlimited_noise(n, seed):
    x = np.random.default_rng(seed).standard_normal(n)
    return np.convolve(x, ss.firwin(255, 0.8), "same")


def test_fractional_delay_refuses_bad_options_and_takes_huge_delays():
    """half_width=0 and a negative chunk returned silence, a NaN beta NaNs, a NaN signal NaNs,
    a 1e12-sample delay asked for terabytes of padding (bad-input sweep)."""
    x = _bandlimited_noise(1000, 2)
    d = np.full(1000, 3.5)
    for kw in (dict(half_width=0), dict(half_width=-3), dict(half_width=2.5),
               dict(half_width=10**7), dict(beta=np.nan), dict(beta=-1.0), dict(chunk=0),
               dict(chunk=-5)):
        with pytest.raises(ConfigError, match=next(iter(kw))):
            fractional_delay(x, d, **kw)
    with pytest.raises(ConfigError, match="n_out"):
        fractional_delay(x, np.zeros(0), n_out=-1)
    with pytest.raises(AudioInputError, match="NaN"):
        fractional_delay(np.full(100, np.nan), np.ones(100))
    with pytest.raises(GeometryError, match="n_ch, n_out"):
        fractional_delay(x, np.zeros((1, 2, 3)))
    far = np.full(10, 1e12)  # beyond the signal: silence, at once
    assert np.array_equal(fractional_delay(x, far), np.zeros(10))
    # a delay just past the output's reach gives the same silence as the clipped one
    edge = np.concatenate([np.full(5, 20.0), np.full(5, 1e6)])
    y = fractional_delay(x, edge, half_width=8)
    np.testing.assert_array_equal(y[5:], 0.0)
    np.testing.assert_allclose(y[:5], fractional_delay(x, np.full(5, 20.0), half_width=8),
                               atol=1e-12)


def test_constant_fractional_delay_matches_frequency_domain_shift():
    x = _bandlimited_noise(4000, 1)
    d = 7.37
    y = fractional_delay(x, np.full(4000, d))
    X = np.fft.rfft(np.concatenate([x, np.zeros(100)]))
    f = np.fft.rfftfreq(4100)
    ref = np.fft.irfft(X * np.exp(-2j * np.pi * f * d), 4100)[:4000]
    err = y[200:-200] - ref[200:-200]
    assert np.sqrt(np.mean(err**2) / np.mean(ref**2)) < 1e-3


def test_static_trajectory_equals_static_free_field():
    arr = MicArray.from_preset("three-mic")
    x = _bandlimited_noise(FS // 2, 2)
    src = np.array([1.5, 0.7, 0.3])
    y = simulate_moving_free_field(x, FS, arr, Trajectory([0.0], [src]))
    y0 = simulate_free_field(x, FS, arr, src)
    e = y[:, 300:-300] - y0[:, 300:-300]
    assert np.sqrt(np.mean(e**2) / np.mean(y0**2)) < 1e-3


def test_receding_source_shows_doppler_and_spreading():
    f0, v, c = 1000.0, 20.0, 343.0
    t = np.arange(FS) / FS
    x = np.sin(2 * np.pi * f0 * t)
    traj = linear_trajectory([1.0, 0.0, 0.0], [v, 0.0, 0.0], 1.0)
    y = simulate_moving_free_field(x, FS, np.zeros((1, 3)), traj, speed_of_sound=c)[0]
    seg = slice(2000, 14000)
    phase = np.unwrap(np.angle(ss.hilbert(y)))[seg]
    f_meas = np.polyfit(t[seg], phase, 1)[0] / (2 * np.pi)
    assert f_meas == pytest.approx(f0 * c / (c + v), rel=2e-4)
    # amplitude follows 1/r at the emission time: at reception t, r = (1 + v t) c / (c + v)
    env = np.abs(ss.hilbert(y))[8000]
    r_expected = (1.0 + v * 0.5) * c / (c + v)
    assert env == pytest.approx(1.0 / r_expected, rel=0.01)


def test_moving_source_delay_follows_trajectory():
    # a pulse emitted at t_e arrives at t_e + r(t_e)/c
    c = 343.0
    x = np.zeros(FS)
    x[8000] = 1.0
    traj = linear_trajectory([2.0, 0.0, 0.0], [0.0, 3.0, 0.0], 1.0)
    y = simulate_moving_free_field(x, FS, np.zeros((1, 3)), traj, speed_of_sound=c)[0]
    r = np.linalg.norm(traj.at(0.5))
    arrival = (0.5 + r / c) * FS  # samples, fractional
    n = np.arange(int(arrival) - 10, int(arrival) + 11)
    expected = np.sinc(n - arrival) / r
    np.testing.assert_allclose(y[n], expected, atol=0.02 / r)
    # a 0.2-sample error in the arrival time would be visible
    assert np.max(np.abs(np.sinc(n - arrival - 0.2) / r - y[n])) > 0.1 / r


def _delay_rir(mics_room, c=343.0, length=400):
    def rir(src_room):
        h = np.zeros((len(mics_room), length))
        for k, m in enumerate(mics_room):
            d = np.linalg.norm(src_room - m) / c * FS
            h[k] = np.sinc(np.arange(length) - d) * np.hanning(length + 2)[1:-1]
            h[k, :] = h[k] / np.linalg.norm(src_room - m)
        return h
    return rir


def test_room_static_trajectory_is_a_single_convolution():
    arr = MicArray.from_preset("two-mic")
    at = np.array([2.0, 2.0, 1.2])
    rir = _delay_rir(arr.positions + at)
    x = _bandlimited_noise(FS // 2, 3)
    src = np.array([1.0, 0.5, 0.0])
    y = simulate_moving_room(x, FS, arr, Trajectory([0.0], [src]), [5, 4, 3], 0.3, at,
                             rir_fn=rir, block_s=0.03)
    h = rir(src + at)
    ref = ss.fftconvolve(x[None, :], h, axes=-1)[:, : x.size]
    np.testing.assert_allclose(y, ref, atol=1e-9 * np.abs(ref).max())


def test_heard_at_is_the_retarded_position():
    """A source at a fast (to make it count) 30 m/s passing a point 1.5 m away: the
    position heard at time t is p(t_e) with t - t_e = |p(t_e) - point| / c, solved here in
    closed form (a quadratic in t_e for straight-line motion)."""
    c = 343.0
    p0, v = np.array([1.5, -2.0, 0.3]), np.array([0.0, 30.0, 0.0])
    traj = linear_trajectory(p0, v, 0.1)
    point = np.array([0.1, 0.2, 0.0])
    t = np.array([[0.03, 0.05], [0.07, 0.09]])
    got = traj.heard_at(t, point, c)
    assert got.shape == (2, 2, 3)
    for tk, g in zip(t.ravel(), got.reshape(-1, 3), strict=True):
        # |p0 + v te - m|^2 = c^2 (t - te)^2, te < t
        w = p0 - point
        a, b, cc = v @ v - c**2, 2 * (w @ v) + 2 * c**2 * tk, w @ w - c**2 * tk**2
        te = [r for r in np.roots([a, b, cc]).real if r < tk][0]
        np.testing.assert_allclose(g, p0 + v * te, atol=1e-6)
        assert np.linalg.norm(g - traj.at(tk)) > 0.1  # 30 m/s x ~5 ms: not the position at t
    # a standing source is heard where it stands
    still = linear_trajectory(p0, [0.0, 0.0, 0.0], 1.0)
    np.testing.assert_allclose(still.heard_at([0.2, 0.5]), [p0, p0])
    with pytest.raises(GeometryError, match="point"):
        traj.heard_at(0.05, (0.0, 0.0))
    with pytest.raises(GeometryError, match="speed_of_sound"):
        traj.heard_at(0.05, point, 0.0)


def test_a_trajectory_faster_than_a_tenth_of_the_speed_of_sound_is_refused():
    """A CSV whose source jumps 100 m in 10 ms (10 km/s, supersonic) was simulated without a
    word: the retarded-time iteration does not converge there, so the delays were garbage."""
    fs = 8000
    mics = MicArray.from_preset("three-mic")
    x = np.random.default_rng(0).standard_normal(fs)
    jump = Trajectory([0.0, 0.01, 1.0], [[1.0, 0.0, 0.0], [101.0, 0.0, 0.0], [101.0, 1.0, 0.0]])
    with pytest.raises(GeometryError, match=r"moves at 1e\+04 m/s between t = 0 and 0.01 s.*"
                                            r"34.3 m/s"):
        simulate_moving_free_field(x, fs, mics, jump)
    with pytest.raises(GeometryError, match="slower than 0.1 times the speed of sound"):
        jump.heard_at(0.5)
    ok = Trajectory([0.0, 1.0], [[1.0, 0.0, 0.0], [1.0, 34.0, 0.0]])  # just below the limit
    assert np.all(np.isfinite(simulate_moving_free_field(x, fs, mics, ok)))


def test_an_absurd_trajectory_step_is_reported_at_its_true_speed():
    """A 1e300 m jump was reported as "moves at inf m/s" (np.linalg.norm squares the step and
    overflows), and so was 1 m in 1e-310 s. The message now gives the step's true figure,
    computed in decimal arithmetic (beyond float's range too), without a RuntimeWarning."""
    mics = [[0.0, 0.0, 1.0]]
    for t1, p1, want in ((0.01, [1e300, 0.0, 0.0], "1e+302"),
                         (1.0, [1e300, 1e300, 0.0], "1.414e+300"),
                         (1e-300, [1e300, 0.0, 0.0], "1e+600"),
                         (1e-310, [1.0, 0.0, 0.0], "1e+310")):
        traj = Trajectory([0.0, t1], [[0.0, 0.0, 0.0], p1])
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(GeometryError, match=rf"^the trajectory moves at {re.escape(want)}"
                                                    r" m/s between t = 0 and "):
                retarded_delays(traj, mics, [0.0], 343.0)
    wide = Trajectory([0.0, 1.0], [[-1e308, 0.0, 0.0], [1e308, 0.0, 0.0]])
    with pytest.raises(GeometryError, match=r"moves at 2e\+308 m/s"):
        retarded_delays(wide, mics, [0.0], 343.0)
    # a source standing 1e200 m away: its distance squared to inf (a RuntimeWarning, then
    # "beyond float range" from the simulator); now its true distance, without a warning
    far = Trajectory([0.0], [[1e200, 0.0, 0.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tau, r = retarded_delays(far, mics, [0.0], 343.0)
    assert r[0, 0] == pytest.approx(1e200) and tau[0, 0] == pytest.approx(1e200 / 343.0)


def test_room_moving_source_delay_tracks_trajectory():
    arr = MicArray(np.array([[0.0, 0.0, 0.0], [0.0, 0.3, 0.0]]))
    at = np.array([2.0, 2.0, 1.2])
    rir = _delay_rir(arr.positions + at)
    x = _bandlimited_noise(FS, 4)
    traj = linear_trajectory([1.5, -1.0, 0.0], [0.0, 2.0, 0.0], 1.0)
    y = simulate_moving_room(x, FS, arr, traj, [5, 4, 3], 0.3, at, rir_fn=rir, block_s=0.02)
    for tc in (0.25, 0.75):
        s = slice(int(tc * FS) - 512, int(tc * FS) + 512)
        cc = ss.correlate(y[0, s], y[1, s], "full")
        lag = (np.argmax(cc) - 1023) / FS
        true = arr.tdoa(traj.at(tc))[0]
        assert lag == pytest.approx(true, abs=1.5 / FS)


def test_room_updates_follow_the_tdoas_of_a_fast_crossing_source():
    """A source crossing 0.6 m in front of the three-mic array at 1 m/s, direct path only: with
    responses every 0.1 s the crossfade mixes copies whose TDOAs differ by ~0.5 sample and the
    per-frame GCC TDOAs stray from the truth; with updates bounded by a 0.1-sample TDOA step
    they stay within 0.15 sample of it (truth at the retarded emission time)."""
    from hearsee.audio.tdoa import estimate_tdoas

    arr = MicArray.from_preset("three-mic")
    at = np.array([3.0, 3.0, 1.2])
    rir = _delay_rir(arr.positions + at)
    x = _bandlimited_noise(int(1.5 * FS), 5)
    traj = linear_trajectory([0.6, -0.75, 0.0], [0.0, 1.0, 0.0], 1.5)
    err = {}
    for step in (None, 0.1):
        y = simulate_moving_room(x, FS, arr, traj, [6, 6, 3], 0.3, at, rir_fn=rir, block_s=0.1,
                                 max_tdoa_step_samples=step, max_delay_step_samples=None)
        tf = estimate_tdoas(y, FS, arr, 64.0, 16.0, "phat", refine="interp",
                            whole_recording=False, snr_weight=False)
        keep = (tf.t > 0.1) & (tf.t < 1.4)
        t = tf.t[keep]
        heard = traj.heard_at(t, (0.0, 0.0, 0.0), arr.speed_of_sound)
        err[step] = np.abs(tf.tdoa_s[keep] - arr.tdoa(heard)) * FS
    assert np.all(np.isfinite(err[0.1]))
    assert np.median(err[0.1]) < 0.02 and err[0.1].max() < 0.15
    assert np.median(err[None]) > 3 * np.median(err[0.1]) and err[None].max() > 0.3


def test_room_update_times_bound_spacing_and_tdoa_steps():
    from hearsee.sim.moving import _update_times

    arr = MicArray.from_preset("three-mic")
    n = 2 * FS
    fast = linear_trajectory([0.6, -0.5, 0.0], [0.0, 0.5, 0.0], 2.0)
    c = _update_times(fast, arr.positions, 343.0, FS, n, 0.1, 0.1)
    assert c[0] == 0 and c[-1] == n - 1 and np.all(np.diff(c) > 0)
    assert np.diff(c).max() <= 0.1 * FS + 1
    tau = arr.tdoa(fast.at(c / FS)) * FS
    assert np.abs(np.diff(tau, axis=0)).max() <= 0.1 + 1e-6
    assert len(c) > 40  # closer than every 0.1 s (21 updates) where the source crosses fast
    still = Trajectory([0.0], [[2.0, 0.5, 0.0]])
    np.testing.assert_array_equal(_update_times(still, arr.positions, 343.0, FS, n, 0.1, 0.1),
                                  _update_times(still, arr.positions, 343.0, FS, n, 0.1, None))
    with pytest.raises(GeometryError):
        simulate_moving_room(np.ones(FS), FS, arr, fast, [6, 6, 3], 0.3, [3, 3, 1.2],
                             max_tdoa_step_samples=0.0)


def test_room_update_times_keep_the_tdoa_bound_for_a_fast_close_source():
    """A source at 3 m/s passing 0.3 m in front of the three-mic array moves its TDOAs by
    0.12 sample in 2 ms; the updates were never closer than that 2 ms grid, so consecutive
    updates were 0.119 sample apart against the promised 0.1. The grid steps above the bound
    are now split. A bound that updates every sample cannot keep is a GeometryError."""
    from hearsee.sim.moving import _update_times

    arr = MicArray.from_preset("three-mic")
    traj = linear_trajectory([0.3, -1.0, 0.0], [0.0, 3.0, 0.0], 0.7)
    n = int(0.66 * FS)
    for block_s, delay in ((0.05, None), (0.005, 0.5)):  # whole responses; the early part
        c = _update_times(traj, arr.positions, 343.0, FS, n, block_s, 0.1, delay)
        assert c[0] == 0 and c[-1] == n - 1 and np.all(np.diff(c) >= 1)
        tau = arr.tdoa(traj.at(c / FS)) * FS
        assert np.abs(np.diff(tau, axis=0)).max() <= 0.1 + 1e-3  # (update times: whole samples)
    # 30 m/s grazing the array: its TDOAs move ~0.1 sample per sample
    graze = linear_trajectory([0.05, -3.0, 0.0], [0.0, 30.0, 0.0], 0.2)
    with pytest.raises(GeometryError, match="too fast near the array at t = 0.1"):
        _update_times(graze, arr.positions, 343.0, FS, int(0.2 * FS), 0.05, 0.01)


def _counting_rir(arr, at):
    """A rir_fn (the delays-only responses of _delay_rir) that records each source position
    it is called with in the returned list."""
    calls = []

    def counted(src):
        calls.append(src)
        return _delay_rir(arr.positions + at)(src)

    return calls, counted


def _counted_walk(noise_seed, duration_s):
    """The three-mic array 2 m into a room, band-limited noise (FS / 4 samples of seed
    ``noise_seed``), a walk past it lasting ``duration_s`` s and a counting rir_fn:
    ``(arr, at, x, traj, calls, counted)``."""
    arr = MicArray.from_preset("three-mic")
    at = np.array([2.0, 2.0, 1.2])
    x = _bandlimited_noise(FS // 4, noise_seed)
    traj = linear_trajectory([1.0, -0.2, 0.0], [0.0, 0.5, 0.0], duration_s)
    return (arr, at, x, traj, *_counting_rir(arr, at))


def test_moving_simulators_check_rir_fn_and_rng_before_any_work():
    """A rir_fn that is no function raised a builtin TypeError at the first block, one that
    returned text numpy's ValueError, NaN responses made a NaN recording without a word; a
    bad rng raised numpy's TypeError / ValueError only in add_noise, after the whole
    simulation. GeometryError / ConfigError now, rir_fn and rng before any block."""
    arr, at, x, traj, calls, counted = _counted_walk(3, 0.3)

    def room(**kw):
        return simulate_moving_room(x, FS, arr, traj, [5, 4, 3], 0.3, at, **kw)

    for fn in (5, "rir", np.ones((3, 10))):
        with pytest.raises(GeometryError, match="rir_fn must be a function"):
            room(rir_fn=fn)
    for fn, msg in ((lambda s: "abc", "rir_fn must return"), (lambda s: None, "rir_fn must"),
                    (lambda s: np.ones((2, 10)), r"shape \(2, 10\) for 3 mics"),
                    (lambda s: np.ones((3, 0)), r"shape \(3, 0\)"),
                    (lambda s: np.full((3, 10), np.nan), "NaN or infinite")):
        with pytest.raises(GeometryError, match=msg):
            room(rir_fn=fn)
    for bad in ("a", 1.5, -1):
        with pytest.raises(ConfigError, match="rng must be"):
            room(rir_fn=counted, snr_db=10.0, rng=bad)
        with pytest.raises(ConfigError, match="rng must be"):
            simulate_moving_free_field(x, FS, arr, traj, snr_db=10.0, rng=bad)
    assert calls == []  # (no block was rendered)
    y = room(rir_fn=counted, snr_db=10.0, rng=np.random.default_rng(1))
    assert y.shape == (3, x.size) and np.all(np.isfinite(y)) and calls


def test_moving_simulators_check_the_snr_before_any_work():
    """simulate_moving_free_field and simulate_moving_room left a bad SNR to add_noise, after
    the whole rendering (a 2-s walk in a room of RT60 0.3 s: 10.6 s of impulse responses,
    then "SNR must be within -60 to 200 dB"); the masked renderers checked it first. Now
    before any block or chunk: no response computed, no progress reported."""
    arr, at, x, traj, calls, counted = _counted_walk(3, 0.3)
    reports = []

    def progress(stage, done, total):
        reports.append((stage, done, total))

    for bad in (500.0, -100.0, "10", [10.0]):
        with pytest.raises(ConfigError, match="SNR must be"):
            simulate_moving_room(x, FS, arr, traj, [5, 4, 3], 0.3, at, rir_fn=counted,
                                 snr_db=bad, progress=progress)
        with pytest.raises(ConfigError, match="SNR must be"):
            simulate_moving_free_field(x, FS, arr, traj, snr_db=bad, progress=progress)
    assert calls == [] and reports == []
    # a good SNR: the noise it asks for (relative to the mean received power)
    clean = simulate_moving_free_field(x, FS, arr, traj)
    noisy = simulate_moving_free_field(x, FS, arr, traj, snr_db=20.0, rng=1)
    assert 10 * np.log10(np.mean(clean**2) / np.mean((noisy - clean) ** 2)) == pytest.approx(
        20.0, abs=0.2)


def test_trajectory_interpolation_velocity_and_csv_roundtrip(tmp_path):
    traj = waypoint_trajectory([[1, 0, 0], [1, 1, 0], [0, 1, 0]], speed_mps=0.5)
    assert traj.duration == pytest.approx(4.0)
    np.testing.assert_allclose(traj.at(1.0), [1, 0.5, 0])
    np.testing.assert_allclose(traj.velocity(3.0), [-0.5, 0, 0])
    np.testing.assert_allclose(traj.at(-1.0), [1, 0, 0])
    p = tmp_path / "traj.csv"
    save_trajectory(traj, p)
    back = load_trajectory(p)
    np.testing.assert_allclose(back.positions, traj.positions, atol=1e-6)
    with pytest.raises(GeometryError, match="expected a Trajectory"):
        save_trajectory(traj.positions, tmp_path / "other.csv")  # (was AttributeError)
    assert not (tmp_path / "other.csv").exists()
    # (an audit: knots 1e-7 s apart were written as one time, "0.000000", and NaN or unsorted
    # times as rows load_trajectory refused; times are written in full precision now)
    close = Trajectory([0.0, 1e-7, 1.0], [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    save_trajectory(close, p)
    np.testing.assert_array_equal(load_trajectory(p).t, close.t)
    for bad in ([np.nan], [0.0, np.inf], [0.5, 0.2]):
        with pytest.raises(GeometryError, match="times must be finite and strictly increasing"):
            save_trajectory(close, tmp_path / "bad.csv", bad)
    assert not (tmp_path / "bad.csv").exists()


def test_bad_trajectories(tmp_path):
    with pytest.raises(GeometryError):
        Trajectory([0.0, 0.0], [[0, 0, 0], [1, 0, 0]])
    with pytest.raises(GeometryError):
        Trajectory([0.0, 1.0], [[0, 0, 0]])
    with pytest.raises(InputFileError):
        load_trajectory(tmp_path / "missing.csv")
    bad = tmp_path / "bad.csv"
    bad.write_text("time,x,y\n0,1,2\n")
    with pytest.raises(ConfigError, match="header"):
        load_trajectory(bad)
    bad.write_text("t,x,y,z\n0,1,2,abc\n")
    with pytest.raises(ConfigError, match="non-numeric"):
        load_trajectory(bad)
    bad.write_text("t,x,y,z\n1,1,2,3\n0,1,2,3\n")
    with pytest.raises(ConfigError, match="increasing"):
        load_trajectory(bad)
    with pytest.raises(GeometryError):
        simulate_moving_free_field(np.ones(100), FS, np.zeros((1, 3)),
                                   Trajectory([0.0], [[0.0, 0.0, 0.0]]))


@pytest.mark.slow
def test_room_with_image_source_rirs_static_and_moving():
    from hearsee.audio.propagation import room_impulse_responses

    arr = MicArray.from_preset("three-mic")
    at = np.array([2.5, 2.0, 1.2])
    dim = [5.0, 4.0, 3.0]
    x = _bandlimited_noise(FS // 4, 5)
    src = np.array([1.2, 0.4, 0.2])
    y = simulate_moving_room(x, FS, arr, Trajectory([0.0], [src]), dim, 0.2, at, block_s=0.05)
    h = room_impulse_responses(FS, arr.positions + at, src + at, dim, 0.2)
    ref = ss.fftconvolve(x[None, :], h, axes=-1)[:, : x.size]
    np.testing.assert_allclose(y, ref, atol=1e-9 * np.abs(ref).max())
    # a moving source: direct-path TDOA of pair 0-1 follows the trajectory
    traj = linear_trajectory([1.5, -0.6, 0.0], [0.0, 2.4, 0.0], 0.5)
    x = _bandlimited_noise(FS // 2, 6)
    y = simulate_moving_room(x, FS, arr, traj, dim, 0.2, at, block_s=0.02)
    # 32 ms windows: at 4.8 m/s the direct path's TDOA sweeps several samples in 64 ms, which
    # smears its peak down to the level of the side wall's reflection 0.7 m away at t = 0.4 s
    for tc in (0.1, 0.25, 0.4):
        s = slice(int(tc * FS) - 256, int(tc * FS) + 256)
        Y0, Y1 = np.fft.rfft(y[0, s], 4096), np.fft.rfft(y[1, s], 4096)
        G = Y0 * np.conj(Y1)
        cc = np.fft.irfft(G / (np.abs(G) + 1e-12), 4096)
        cc = np.concatenate([cc[-20:], cc[:21]])
        lag = (np.argmax(cc) - 20) / FS
        assert lag == pytest.approx(arr.tdoa(traj.at(tc))[0], abs=1.5 / FS)


def test_simulate_moving_recording_free_field_truth():
    from hearsee.sim.moving import simulate_moving_recording

    traj = linear_trajectory([1.0, -0.5, 0.0], [0.0, 1.0, 0.0], 0.5)
    x, truth = simulate_moving_recording("two-mic", traj, "noise", fs=8000, snr_db=30, seed=1)
    assert x.shape == (2, 4000)
    assert truth["moving"] is True and truth["duration_s"] == pytest.approx(0.5)
    np.testing.assert_allclose(truth["source_m"], [1.0, -0.5, 0.0])
    assert len(truth["trajectory"]["t"]) == 2
    with pytest.raises(ConfigError, match="duration"):
        simulate_moving_recording("two-mic", Trajectory([0.0], [[1.0, 0.0, 0.0]]))


def test_cli_simulate_trajectory_writes_truth_beside_the_wav(tmp_path, capsys):
    import json

    from hearsee.audio.signals import read_recording
    from hearsee.cli import main

    csv_in = tmp_path / "walk.csv"
    save_trajectory(linear_trajectory([1.5, -0.5, 0.2], [0.0, 1.0, 0.0], 1.0), csv_in)
    out = tmp_path / "walk.wav"
    assert main(["simulate", str(out), "--array", "three-mic", "--trajectory", str(csv_in),
                 "--duration", "0.5", "--fs", "8000", "--snr", "30"]) == 0
    x, fs = read_recording(out)
    assert x.shape == (3, 4000) and fs == 8000
    truth = json.loads(out.with_suffix(".json").read_text())
    assert truth["moving"] and truth["trajectory_csv"] == "walk.trajectory.csv"
    gt = load_trajectory(tmp_path / "walk.trajectory.csv")
    np.testing.assert_allclose(gt.at(0.25), [1.5, -0.25, 0.2], atol=1e-6)
    assert csv_in.read_text().startswith("t,x,y,z")  # the input is untouched
    # without --duration the whole trajectory is rendered (it was always 2 s)
    longer = tmp_path / "walk3.csv"
    save_trajectory(linear_trajectory([1.5, -0.5, 0.2], [0.0, 0.5, 0.0], 3.0), longer)
    assert main(["simulate", str(tmp_path / "w3.wav"), "--array", "three-mic", "--trajectory",
                 str(longer), "--fs", "8000"]) == 0
    x3, _ = read_recording(tmp_path / "w3.wav")
    assert x3.shape == (3, 24000)
    gt3 = load_trajectory(tmp_path / "w3.trajectory.csv")
    assert gt3.t[-1] == pytest.approx(3.0)  # (the recording's end: the 10 ms grid stopped at 2.99)
    capsys.readouterr()
    # bad combinations are one clear line, exit 2
    assert main(["simulate", str(out), "--array", "three-mic"]) == 2
    assert "--trajectory" in capsys.readouterr().err
    assert main(["simulate", str(out), "--array", "three-mic", "--trajectory", str(csv_in),
                 "--source", "1,0,0"]) == 2
    capsys.readouterr()
    assert main(["simulate", str(out), "--array", "three-mic", "--trajectory", str(csv_in),
                 "--far-field"]) == 2
    assert "far-field" in capsys.readouterr().err
    # the truth CSV would overwrite the input trajectory: refused, input untouched
    before = (tmp_path / "walk.trajectory.csv").read_text()
    assert main(["simulate", str(out), "--array", "three-mic",
                 "--trajectory", str(tmp_path / "walk.trajectory.csv")]) == 2
    assert "overwrite" in capsys.readouterr().err
    assert (tmp_path / "walk.trajectory.csv").read_text() == before


def test_moving_room_honours_the_arrays_speed_of_sound_and_max_order():
    """The room renderer of moving sources uses what the static one uses: the array's speed
    of sound (a 0.4 m pair at c = 300 m/s has a TDOA 2.2 samples longer than at 343) and the
    room's max_order (0 = the direct path only, whatever the RT60)."""
    from hearsee.audio.propagation import room_impulse_responses
    from hearsee.sim.moving import simulate_moving_recording

    arr = MicArray([[0.0, -0.2, 0.0], [0.0, 0.2, 0.0]], speed_of_sound=300.0, name="slow")
    at = np.array([2.5, 2.0, 1.2])
    dim = [5.0, 4.0, 3.0]
    src = np.array([0.6, 1.2, 0.0])
    x = _bandlimited_noise(FS // 4, 7)
    y = simulate_moving_room(x, FS, arr, Trajectory([0.0], [src]), dim, 0.0, at)
    h = room_impulse_responses(FS, arr.positions + at, src + at, dim, 0.0, speed_of_sound=300.0)
    ref = ss.fftconvolve(x[None, :], h, axes=-1)[:, : x.size]
    np.testing.assert_allclose(y, ref, atol=1e-9 * np.abs(ref).max())
    G = np.fft.rfft(y[0], 8192) * np.conj(np.fft.rfft(y[1], 8192))
    cc = np.fft.irfft(G / (np.abs(G) + 1e-12), 8192)
    lag = int(np.argmax(np.concatenate([cc[-40:], cc[:41]]))) - 40
    assert lag == round(arr.tdoa(src)[0] * FS)
    assert abs(lag - round(arr.tdoa(src)[0] * 300.0 / 343.0 * FS)) >= 2
    # max_order 0 in a reverberant room: exactly the anechoic room's recording
    traj = linear_trajectory([1.0, -0.5, 0.0], [0.5, 1.0, 0.0], 0.3)
    room = {"room_dim": dim, "array_at": at.tolist()}
    direct, truth = simulate_moving_recording(arr, traj, "noise", fs=FS, seed=2,
                                              room={**room, "rt60": 0.5, "max_order": 0})
    anechoic, _ = simulate_moving_recording(arr, traj, "noise", fs=FS, seed=2,
                                            room={**room, "rt60": 0.0})
    reverberant, _ = simulate_moving_recording(arr, traj, "noise", fs=FS, seed=2,
                                               room={**room, "rt60": 0.5})
    assert truth["room"]["max_order"] == 0
    np.testing.assert_allclose(direct, anechoic, atol=1e-9 * np.abs(anechoic).max())
    assert np.linalg.norm(reverberant - anechoic) > 0.3 * np.linalg.norm(anechoic)


def test_room_responses_refuse_reflections_without_rt60():
    """(A masked array's moving source in a room was refused here until 2026-12-05;
    tests/audio/test_mask.py has its simulation.)"""
    from hearsee.audio.propagation import room_impulse_responses

    # RT60 0 is anechoic; image sources of order 3 would need walls that reflect everything
    with pytest.raises(ConfigError, match="anechoic"):
        room_impulse_responses(FS, [[2.0, 2.0, 1.0], [2.1, 2.0, 1.0]], [3.0, 3.0, 1.0],
                               [5.0, 4.0, 3.0], 0.0, max_order=3)
    h = room_impulse_responses(FS, [[2.0, 2.0, 1.0], [2.1, 2.0, 1.0]], [3.0, 3.0, 1.0],
                               [5.0, 4.0, 3.0], 0.0, max_order=0)
    assert np.count_nonzero(np.abs(h[0]) > 1e-3 * np.abs(h[0]).max()) < 80  # one direct path


def test_unreadable_trajectory_file_is_a_typed_error(tmp_path, deny_reading):
    """A CSV without read permission (PermissionError) escaped load_trajectory as a builtin
    OSError (a traceback from ``hearsee simulate --trajectory``)."""
    p = tmp_path / "traj.csv"
    p.write_text("t,x,y,z\n0,1,0,0\n")
    deny_reading("open")
    with pytest.raises(InputFileError, match="Permission denied"):
        load_trajectory(p)


def test_room_updates_are_at_most_block_s_apart_below_the_tdoa_grid():
    """With the TDOA step bound on (the default), the updates were picked on a fixed 2 ms grid,
    so a block_s under 2 ms (1 ms = 16 samples) still updated only every 32 samples."""
    from hearsee.sim.moving import _update_times

    arr = MicArray.from_preset("three-mic")
    slow = linear_trajectory([2.0, 0.0, 0.0], [0.0, 0.1, 0.0], 1.0)
    for block_s in (0.001, 0.0015):
        hop = round(block_s * FS)
        for step in (0.1, None):
            c = _update_times(slow, arr.positions, 343.0, FS, FS, block_s, step)
            assert c[0] == 0 and c[-1] == FS - 1
            assert np.diff(c).max() <= hop, (block_s, step)


def test_a_moving_source_never_heard_within_the_signal_is_refused():
    """A walker 1000 m away (2.9 s of delay) in 1 s of signal was simulated as all zeros (and
    written as a silent WAV with a truth): now a GeometryError, free field and room alike.
    One that comes into earshot before the end is simulated."""
    x = _bandlimited_noise(FS, 4)  # 1 s
    arr = MicArray(np.array([[0.0, -0.1, 0.0], [0.0, 0.1, 0.0]]), name="pair")
    far = linear_trajectory([1000.0, 0.0, 0.0], [-1.0, 0.0, 0.0], 1.0)
    with pytest.raises(GeometryError, match="longer than the 1 s simulated"):
        simulate_moving_free_field(x, FS, arr, far)
    with pytest.raises(GeometryError, match="longer than the 1 s simulated"):
        simulate_moving_room(x, FS, arr, far, [1200.0, 4.0, 3.0], 0.0, [2.0, 2.0, 1.5],
                             max_tdoa_step_samples=None, block_s=0.5)
    near = linear_trajectory([300.0, 0.0, 0.0], [-1.0, 0.0, 0.0], 1.0)  # heard from ~0.87 s
    y = simulate_moving_free_field(x, FS, arr, near)
    assert not np.any(y[:, : int(0.8 * FS)]) and np.any(y[:, int(0.95 * FS):])


@pytest.mark.parametrize(("text", "message"), [
    ("t,x,y,z\n0,1,0,0\n1,1,1\n", "line 3: expected 4 values t,x,y,z, got 3: '1,1,1'"),
    ("t,x,y,z\n\n0,1,0,0\n1,1,1,0,5\n", "line 4: expected 4 values t,x,y,z, got 5: '1,1,1,0,5'"),
    ("t,x,y,z\n0,1,0,0\n1,1,1,abc\n", "line 3: non-numeric value in '1,1,1,abc'"),
])
def test_a_ragged_trajectory_row_is_named(tmp_path, capsys, text, message):
    """A row of 3 or 5 values showed numpy's internal text ('setting an array element with a
    sequence. The requested array has an inhomogeneous shape after 1 dimensions...') as a
    'non-numeric value'. Now one line naming the file and the line (blank lines counted)."""
    from hearsee.cli import main

    bad = tmp_path / "bad.csv"
    bad.write_text(text)
    with pytest.raises(ConfigError) as exc:
        load_trajectory(bad)
    assert str(exc.value) == f"{bad}: {message}"
    assert main(["simulate", str(tmp_path / "o.wav"), "--array", "two-mic", "--trajectory",
                 str(bad), "--duration", "0.1"]) == 2
    assert capsys.readouterr().err == f"hearsee: error: {bad}: {message}\n"


def test_trajectory_numbers_must_be_numbers_and_steps_bounded(tmp_path):
    """Trajectory read times ("0", "1") as 0 and 1 s and positions of text or bools as metres
    (and so did linear_trajectory, waypoint_trajectory, at, velocity, heard_at and
    retarded_delays); text speeds and durations raised builtin TypeErrors. Times from -1e308 to
    1e308 s made np.diff overflow to an inf step: velocity() read the 2e308 m move over it as
    0 m/s. Now GeometryErrors (ConfigError naming the file in load_trajectory); knots at most
    MAX_TIME_LIMIT_S (1e9 s) apart, the trackers' rule; Unix-epoch times stay valid."""
    p2 = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
    for t, p in ((["0", "1"], p2), ([0.0, True], p2), ([0.0, 1.0], [["0", 0, 0], [1, 0, 0]]),
                 ([0.0, 1.0], [[False, 0.0, 0.0], [1.0, 0.0, 0.0]])):
        with pytest.raises(GeometryError, match="^trajectory (times|positions) must be real"):
            Trajectory(t, p)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (np.diff's overflow RuntimeWarning)
        for t in ([-1e308, 1e308], [0.0, 1e300], [0.0, 1.0, 1.0 + 2e9]):
            with pytest.raises(GeometryError, match=r"^trajectory times jump .* at most 1e\+09 s"):
                Trajectory(t, [[0.0, 0.0, 0.0]] * len(t))
    path = tmp_path / "far.csv"
    path.write_text("t,x,y,z\n-1e308,0,0,0\n1e308,1,0,0\n")
    with pytest.raises(ConfigError, match=r"far.csv: trajectory times jump"):
        load_trajectory(path)
    epoch = Trajectory([1.7e9, 1.7e9 + 1e9], p2)  # exactly the bound: kept
    np.testing.assert_allclose(epoch.velocity(1.7e9 + 5e8), [1e-9, 0.0, 0.0])
    traj = Trajectory([0.0, 1.0], p2)
    for f in (traj.at, traj.velocity, traj.acceleration, traj.heard_at):
        with pytest.raises(GeometryError, match="^times must be real numbers of seconds"):
            f(["0.5"])
    with pytest.raises(GeometryError, match="point must be 3 finite numbers"):
        traj.heard_at(0.5, ("0", "0", "0"))
    with pytest.raises(GeometryError, match="speed_of_sound must be > 0"):
        traj.heard_at(0.5, (0.0, 0.0, 0.0), "343")
    mics = [[0.0, 0.0, 1.0]]
    with pytest.raises(GeometryError, match="^microphone positions must be real numbers"):
        retarded_delays(traj, [["0", "0", "1"]], [0.5], 343.0)
    with pytest.raises(GeometryError, match="^times must be real numbers"):
        retarded_delays(traj, mics, ["0.5"], 343.0)
    with pytest.raises(GeometryError, match=r"^c \(m/s\) must be a finite number > 0"):
        retarded_delays(traj, mics, [0.5], "343")
    for args, msg in ((([1, 0, 0], [0, 1, 0], "1"), "duration must be > 0 s"),
                      (([1, 0, 0], [0, 1, 0], True), "duration must be > 0 s"),
                      ((["1", 0, 0], [0, 1, 0], 1.0), "start must be a finite"),
                      (([1, 0, 0], [0, "1", 0], 1.0), "velocity must be real numbers"),
                      (([1, 0, 0], [0, 1, 0], 1.0, 2.7), "n_points must be an integer"),
                      (([1, 0, 0], [0, 1, 0], 1.0, "3"), "n_points must be an integer")):
        with pytest.raises(GeometryError, match=msg):
            linear_trajectory(*args)
    w = [[1, 0, 0], [1, 1, 0]]
    for args, msg in (((w, "0.5"), "speed must be > 0"), ((w, True), "speed must be > 0"),
                      (([["1", 0, 0], [1, 1, 0]], 0.5), "waypoints must be real numbers"),
                      ((w, 0.5, "1"), r"t0 \(s\) must be a finite number")):
        with pytest.raises(GeometryError, match=msg):
            waypoint_trajectory(*args)
    # the same values as numbers: unchanged
    a = linear_trajectory([1, 0, 0], [0, 1, 0], 1.0, 5)
    np.testing.assert_array_equal(a.t, np.linspace(0.0, 1.0, 5))
    np.testing.assert_array_equal(a.positions[-1], [1.0, 1.0, 0.0])
    assert linear_trajectory([1, 0, 0], [0, 1, 0], 1.0, 1).t.size == 2
    b = waypoint_trajectory(w, 0.5, np.float32(2.0))
    np.testing.assert_array_equal(b.t, [2.0, 4.0])
    np.testing.assert_array_equal(traj.at([0.5, 2]), traj.at(np.array([0.5, 2.0])))


def test_room_reflections_of_a_fast_source_converge_with_the_early_split():
    """A source moving at 1.5 m/s in a reverberant room: whole responses every 0.1 s render
    each reflection as two crossfaded copies at the two updates' delays (the direct path's
    TDOA bound does not cover reflections); updating the early reflections (order <= 3) every
    5 ms brings the waveform near the reference rendered with whole responses every 4 ms."""
    arr = MicArray.from_preset("three-mic")
    at, dim = np.array([2.5, 2.0, 1.2]), [5.0, 4.0, 3.0]
    x = np.random.default_rng(3).standard_normal(FS // 2)
    traj = linear_trajectory([0.8, 0.3, 0.2], [1.5, 0.3, 0.0], 0.5)
    ref = simulate_moving_room(x, FS, arr, traj, dim, 0.25, at, block_s=0.004, early_order=None)
    whole = simulate_moving_room(x, FS, arr, traj, dim, 0.25, at, block_s=0.1, early_order=None,
                                 max_delay_step_samples=None)  # (every 0.1 s, as before)
    split = simulate_moving_room(x, FS, arr, traj, dim, 0.25, at, block_s=0.1)

    def rel(y):
        return np.linalg.norm(y - ref) / np.linalg.norm(ref)

    assert rel(split) < 0.4 and rel(whole) > 2.5 * rel(split)
    # a static source: the two parts add up to the one response's convolution
    src = Trajectory([0.0], [[1.0, 0.5, 0.2]])
    both = simulate_moving_room(x[:2000], FS, arr, src, dim, 0.25, at)
    one = simulate_moving_room(x[:2000], FS, arr, src, dim, 0.25, at, early_order=None)
    np.testing.assert_allclose(both, one, atol=1e-9 * np.abs(one).max())


@pytest.mark.parametrize("kw", [{"early_block_s": 0.0}, {"early_block_s": "5 ms"},
                                {"early_order": -1}, {"early_order": 2.5}, {"block_s": 0.0},
                                {"block_s": "0.1"}, {"block_s": float("inf")}])
def test_room_early_split_options_are_checked(kw):
    arr = MicArray.from_preset("two-mic")
    with pytest.raises(GeometryError):
        simulate_moving_room(np.ones(800), FS, arr, Trajectory([0.0], [[1.0, 0.5, 0.0]]),
                             [5.0, 4.0, 3.0], 0.25, [2.5, 2.0, 1.2], **kw)


def test_truth_csv_holds_the_corners_and_the_end(tmp_path):
    """The CLI's truth CSV sampled the trajectory on a 10 ms grid that stopped before the end
    and cut its corners: a 1 m/s walk turning at t = 0.505 s was 9.9 mm off at the end and
    3.5 mm at the corner. Now the grid, the knots and the end, each exact."""
    from hearsee.cli import main
    from hearsee.sim.moving import truth_times

    walk = Trajectory([0.0, 0.505, 1.0], [[1.0, 0.0, 0.0], [1.505, 0.0, 0.0], [1.505, 0.495, 0.0]])
    t = truth_times(walk, 1.0)
    assert t[0] == 0.0 and t[-1] == 1.0 and 0.505 in t and np.all(np.diff(t) > 0)
    assert np.max(np.diff(t)) <= 0.01 + 1e-12 and len(t) == 102  # 0..1 by 10 ms + the corner
    csv_in = tmp_path / "turn.csv"
    save_trajectory(walk, csv_in)
    out = tmp_path / "turn.wav"
    assert main(["simulate", str(out), "--array", "two-mic", "--trajectory", str(csv_in),
                 "--fs", "8000"]) == 0
    gt = load_trajectory(tmp_path / "turn.trajectory.csv")
    for tk in (0.0, 0.3, 0.505, 0.77, 1.0):  # the written truth interpolates the true path
        np.testing.assert_allclose(gt.at(tk), walk.at(tk), atol=2e-6)
    # a duration off the grid and knots beyond the recording: the end is written, once
    t2 = truth_times(walk, 0.0731)
    assert t2[-1] == pytest.approx(0.0731) and np.sum(t2 > 0.07) == 1


def test_truth_times_refuses_absurdly_many_times():
    """step_s=1e-12 asked numpy for 1e12 times (a MemoryError), a 1e300 s duration for 1e302
    (numpy's "maximum allowed size exceeded" ValueError); a step below the CSV's microsecond
    made rows that merged anyway. Now GeometryErrors; the largest grid still works."""
    from hearsee.sim.moving import MAX_TRUTH_TIMES, truth_times

    walk = Trajectory([0.0, 1.0], [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]])
    with pytest.raises(GeometryError, match="step_s must be a finite number >= 1e-06"):
        truth_times(walk, 1.0, 1e-12)
    with pytest.raises(GeometryError, match="more than 10000000; give a larger step_s"):
        truth_times(walk, 1e300)
    with pytest.raises(GeometryError, match="more than"):
        truth_times(walk, 100.0, 1e-5)  # exactly MAX_TRUTH_TIMES
    t = truth_times(walk, 1.0, 1e-6)  # the finest grid: a million times
    assert len(t) == 1_000_001 < MAX_TRUTH_TIMES and t[-1] == 1.0


def test_a_trajectory_csv_with_a_byte_order_mark_loads(tmp_path):
    """Excel's "CSV UTF-8" starts the file with a byte-order mark: its first header cell read
    "\ufefft" and the file was refused."""
    path = tmp_path / "bom.csv"
    path.write_bytes("t,x,y,z\n0,1,0,0\n1,1,1,0\n".encode("utf-8-sig"))
    traj = load_trajectory(path)
    np.testing.assert_allclose(traj.at(0.5), [1.0, 0.5, 0.0])


def _sim_calls():
    from hearsee.sim.moving import simulate_moving_recording

    arr = MicArray.from_preset("two-mic")
    traj = Trajectory([0.0, 0.2], [[1.0, 0.0, 0.0], [1.0, 0.1, 0.0]])
    room = ([5.0, 4.0, 3.0], 0.0, [2.5, 2.0, 1.2])
    sig = np.ones(800)
    return {
        "seed -1": lambda: simulate_moving_recording(arr, traj, seed=-1),
        "seed 1.5": lambda: simulate_moving_recording(arr, traj, seed=1.5),
        "duration list": lambda: simulate_moving_recording(arr, traj, duration_s=[0.1]),
        "duration text": lambda: simulate_moving_recording(arr, traj, duration_s="0.1"),
        "array_at 2-D": lambda: simulate_moving_room(sig, FS, arr, traj, room[0], room[1],
                                                     [2.0, 2.0]),
        "room text": lambda: simulate_moving_room(sig, FS, arr, traj, "5x4x3", *room[1:]),
        "step text": lambda: simulate_moving_room(sig, FS, arr, traj, *room,
                                                  max_tdoa_step_samples="0.1"),
        "mics N x 2": lambda: simulate_moving_room(sig, FS, arr, traj, *room,
                                                   mic_positions=np.zeros((2, 2))),
        "signal text": lambda: simulate_moving_free_field(["a"] * 800, FS, arr, traj),
        "signal bools": lambda: simulate_moving_free_field([True] * 800, FS, arr, traj),
        "trajectory None": lambda: simulate_moving_free_field(sig, FS, arr, None),
        "room trajectory None": lambda: simulate_moving_room(sig, FS, arr, None, *room),
        "n_iter 0": lambda: retarded_delays(traj, arr.positions, [0.1], 343.0, n_iter=0),
        "one mic as (3,)": lambda: retarded_delays(traj, [0.0, 0.0, 0.0], [0.1], 343.0),
        "times text": lambda: save_trajectory(traj, "unused.csv", times=["a"]),
        "velocity 2-D": lambda: linear_trajectory([1.0, 0.0, 0.0], [1.0, 0.0], 1.0),
    }


@pytest.mark.parametrize("case", sorted(_sim_calls()))
def test_moving_simulation_bad_arguments_are_typed_errors(case, tmp_path, monkeypatch):
    """Each raised a builtin ValueError, TypeError, IndexError, AttributeError or
    UnboundLocalError (or, text durations and boolean samples, was taken as a number)."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises((ConfigError, GeometryError, AudioInputError)):
        _sim_calls()[case]()
    assert list(tmp_path.iterdir()) == []


def test_save_trajectory_takes_one_time_and_save_recording_a_text_peak_is_refused(tmp_path):
    from hearsee.sim.audio import save_recording

    traj = Trajectory([0.0, 1.0], [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]])
    save_trajectory(traj, tmp_path / "one.csv", times=0.25)  # (a builtin TypeError before)
    np.testing.assert_allclose(load_trajectory(tmp_path / "one.csv").positions,
                               [[1.0, 0.25, 0.0]])
    with pytest.raises(ConfigError, match="peak"):
        save_recording(tmp_path / "r.wav", np.ones((2, 100)), {"fs": 16000}, peak="0.5")
    assert not (tmp_path / "r.wav").exists()


def test_room_renders_a_receding_source_without_a_comb():
    """A source receding at 1 m/s barely changes the TDOAs, so the updates were 50 ms apart and
    the crossfade summed two copies 2.3 samples apart: a 3.43 kHz tone (the comb's first notch)
    fell to 0.13 of its level between updates in a room without reflections. With the direct
    path's delay bounded too (MAX_DELAY_STEP_SAMPLES) the envelope follows the exact free-field
    rendering; updates are at most 0.5 sample of delay apart."""
    import scipy.signal as ss

    from hearsee.sim.moving import MAX_DELAY_STEP_SAMPLES, _update_times

    arr = MicArray([[0.0, -0.1, 0.0], [0.0, 0.1, 0.0]], name="pair")
    n = int(0.6 * FS)
    away = linear_trajectory([1.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.6)
    step = 0.05 / 343.0 * FS  # delay change over one 50 ms block
    x = np.sin(2 * np.pi * FS / (2 * step) * np.arange(n) / FS)
    ff = simulate_moving_free_field(x, FS, arr, away)[0]
    room = simulate_moving_room(x, FS, arr, away, [8.0, 6.0, 3.0], 0.0, [1.0, 3.0, 1.5])[0]
    k = slice(int(0.1 * FS), n - 400)
    env_ff, env_room = np.abs(ss.hilbert(ff))[k], np.abs(ss.hilbert(room))[k]
    assert np.min(env_room / env_ff) > 0.85  # (0.18 before)
    c = _update_times(away, arr.positions, 343.0, FS, n, 0.05, 0.1, MAX_DELAY_STEP_SAMPLES)
    d = np.linalg.norm(away.at(c / FS)[:, None] - arr.positions[None], axis=-1) / 343.0 * FS
    assert np.abs(np.diff(d, axis=0)).max() <= MAX_DELAY_STEP_SAMPLES + 1e-6
    with pytest.raises(GeometryError, match="max_delay_step_samples"):
        simulate_moving_room(x, FS, arr, away, [8.0, 6.0, 3.0], 0.0, [1.0, 3.0, 1.5],
                             max_delay_step_samples=-1.0)


def test_every_microphone_must_hear_the_moving_or_room_source():
    """Only the nearest microphone's direct sound had to arrive within the signal: with
    microphones 1 m and 6 m from the source and 10 ms of signal (3.4 m of sound), the far
    channel held no direct sound, and its recording came with a ground truth it did not hold."""
    from hearsee.audio.propagation import simulate_room

    arr = MicArray([[0.0, 0.0, 0.0], [-5.0, 0.0, 0.0]], name="far pair")
    x = np.ones(int(0.01 * FS))
    still = Trajectory([0.0], [[1.0, 0.0, 0.0]])
    for run in (lambda: simulate_moving_free_field(x, FS, arr, still),
                lambda: simulate_moving_room(x, FS, arr, still, [9.0, 4.0, 3.0], 0.2,
                                             [6.5, 2.0, 1.5]),
                lambda: simulate_room(x, FS, arr, [1.0, 0.0, 0.0], [9.0, 4.0, 3.0], 0.2,
                                      [6.5, 2.0, 1.5])):
        with pytest.raises(GeometryError, match="from the farthest microphone"):
            run()
    long = np.ones(int(0.03 * FS))  # 10.3 m of sound: both hear it
    assert simulate_moving_free_field(long, FS, arr, still).shape == (2, long.size)


def test_free_field_microphones_are_checked_as_the_static_simulators_are():
    """simulate_moving_free_field read its microphones with np.asarray (found by an audit,
    2026-12-02): a preset name raised numpy's builtin ValueError, True was read as 1 m, and a
    NaN coordinate was reported as a source "too far (beyond float range)". The static
    simulate_free_field refuses all three with a GeometryError about the microphones; so
    does this one now, and N x 3 numbers still give the same recording as the MicArray."""
    traj = linear_trajectory([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.5)
    x = np.random.default_rng(0).standard_normal(8000)
    for bad in ("three-mic", [[0.0, 0.0, True], [0.1, 0.0, 0.0]],
                [[0.0, 0.0, np.nan], [0.1, 0.0, 0.0]]):
        with pytest.raises(GeometryError, match="microphone positions"):
            simulate_moving_free_field(x, 16000, bad, traj)
    arr = MicArray.from_preset("three-mic")
    as_list = simulate_moving_free_field(x, 16000, arr.positions.tolist(), traj)
    np.testing.assert_array_equal(as_list, simulate_moving_free_field(x, 16000, arr, traj))


def test_velocity_at_a_nan_time_is_nan_as_the_position():
    """Trajectory.velocity(NaN) was the last segment's velocity (found by an audit,
    2026-12-02): searchsorted puts NaN after every knot and NaN is neither before the start nor
    after the end, so a NaN time read as a time on the last segment -- while at(NaN) is NaN,
    and acceleration(NaN) was 0 m/s^2. Now NaN rows for NaN times; other times unchanged."""
    traj = waypoint_trajectory([[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]], 0.5)
    v = traj.velocity([1.0, np.nan, 3.0, 5.0])
    np.testing.assert_array_equal(v[[0, 2, 3]], [[0.0, 0.5, 0.0], [-0.5, 0.0, 0.0], [0.0] * 3])
    assert np.all(np.isnan(v[1])) and np.all(np.isnan(traj.at(np.nan)))
    assert np.all(np.isnan(traj.velocity(np.nan))) and np.all(np.isnan(traj.acceleration(np.nan)))


def test_a_trajectory_that_ends_before_the_recording_names_its_end():
    """A trajectory at t = -1 .. -0.5 s without a duration was refused with "a one-point
    trajectory needs an explicit duration" (found by an audit, 2026-12-02): it has two points,
    and a one-point trajectory at t = 0.5 s gets a default duration. The message now names the
    trajectory's end; an explicit duration of 0 says so."""
    traj = Trajectory([-1.0, -0.5], [[1.0, 0.0, 0.0], [1.0, 0.5, 0.0]])
    with pytest.raises(ConfigError, match=r"trajectory ends at t = -0.5 s") as exc:
        simulate_moving_recording("three-mic", traj)
    assert "one-point" not in str(exc.value)
    with pytest.raises(ConfigError, match=r"duration must be > 0 s, got 0 s"):
        simulate_moving_recording("three-mic", traj, duration_s=0.0)
    x, truth = simulate_moving_recording("three-mic", Trajectory([0.5], [[1.0, 0.2, 0.0]]))
    assert truth["duration_s"] == 0.5 and x.shape == (3, 8000)


def _stages(reports):
    """{stage: [(done, total), ...]} of progress(stage, done, total) reports, and the stages
    announced (done = 0) before the first step of any was reported done."""
    first_step = next((i for i, (_, done, _t) in enumerate(reports) if done), len(reports))
    announced = [stage for stage, done, _ in reports[:first_step] if done == 0]
    by_stage = {}
    for stage, done, total in reports:
        by_stage.setdefault(stage, []).append((done, total))
    return by_stage, announced


def test_room_renderer_reports_each_stage_of_its_work():
    """simulate_moving_room(progress=...): every stage announced before any work, then one
    report per impulse-response update, counting up to the stage's total; the totals are the
    updates the renderer computes (counted here through a rir_fn); the recording is the same
    with or without the reports. A progress that cannot be called is refused before any
    work (a TypeError came after the first update's)."""
    arr, at, x, traj, calls, counted = _counted_walk(5, 0.25)

    reports = []
    y = simulate_moving_room(x, FS, arr, traj, [5, 4, 3], 0.3, at, rir_fn=counted,
                             progress=lambda *r: reports.append(r))
    by_stage, announced = _stages(reports)
    assert announced == ["room responses"] and list(by_stage) == ["room responses"]
    steps = by_stage["room responses"]
    assert steps[-1] == (len(calls), len(calls)) and len(calls) >= 6
    assert [d for d, _ in steps] == list(range(len(calls) + 1))  # one report per update
    calls.clear()
    np.testing.assert_array_equal(
        simulate_moving_room(x, FS, arr, traj, [5, 4, 3], 0.3, at, rir_fn=counted), y)
    for bad in ("x", 3):
        calls.clear()
        with pytest.raises(ConfigError, match="progress must be a callable"):
            simulate_moving_room(x, FS, arr, traj, [5, 4, 3], 0.3, at, rir_fn=counted,
                                 progress=bad)
        assert calls == []
    # the default responses, split: the later reflections' and the early part's updates,
    # each stage named with its image-source orders
    reports.clear()
    z = simulate_moving_room(x, FS, arr, traj, [5, 4, 3], 0.2, at, max_order=6,
                             early_order=2, progress=lambda *r: reports.append(r))
    by_stage, announced = _stages(reports)
    assert announced == ["later reflections (orders 3-6)",
                         "direct path and early reflections (orders 0-2)"]
    early, late = by_stage[announced[1]], by_stage[announced[0]]
    # early updates every 5 ms at most, later ones every 50 ms at most, over 0.25 s
    assert early[-1][0] == early[-1][1] >= 50 and 5 <= late[-1][1] < early[-1][1]
    np.testing.assert_array_equal(
        z, simulate_moving_room(x, FS, arr, traj, [5, 4, 3], 0.2, at, max_order=6,
                                early_order=2))


def test_free_field_and_recording_report_progress():
    """simulate_moving_free_field reports its interpolator's chunks (4096 output samples per
    microphone), and simulate_moving_recording hands its progress to the renderer; the
    recordings are those without reports."""
    arr = MicArray.from_preset("three-mic")
    x = _bandlimited_noise(10000, 6)
    traj = linear_trajectory([1.0, -0.2, 0.0], [0.0, 0.5, 0.0], 0.7)
    reports = []
    y = simulate_moving_free_field(x, FS, arr, traj, progress=lambda *r: reports.append(r))
    by_stage, announced = _stages(reports)
    assert announced == ["direct path (fractional delays)"]
    total = 3 * int(np.ceil(10000 / 4096))  # 3 microphones x 3 chunks
    assert by_stage[announced[0]] == [(k, total) for k in range(total + 1)]
    np.testing.assert_array_equal(y, simulate_moving_free_field(x, FS, arr, traj))
    reports.clear()
    room = dict(room_dim=[5, 4, 3], rt60=0.2, array_at=[2.0, 2.0, 1.2], max_order=4)
    r, _ = simulate_moving_recording("three-mic", traj, duration_s=0.3, room=room,
                                     progress=lambda *a: reports.append(a))
    assert _stages(reports)[1] == ["later reflections (order 4)",
                                   "direct path and early reflections (orders 0-3)"]
    np.testing.assert_array_equal(
        r, simulate_moving_recording("three-mic", traj, duration_s=0.3, room=room)[0])
    with pytest.raises(ConfigError, match="progress must be a callable"):
        simulate_moving_recording("three-mic", traj, duration_s=0.3, progress="bar")


def test_cli_stage_progress_shows_a_bar_per_stage(monkeypatch):
    """The CLI's stage_progress: on a terminal, a bar per stage named "description: stage",
    each at its count; elsewhere (pipes, files) nothing is drawn."""
    import io

    from rich.console import Console

    from hearsee.cli import _app

    out = io.StringIO()
    monkeypatch.setattr(_app, "err_console", Console(file=out, force_terminal=True, width=120))
    monkeypatch.setattr(_app.sys.stderr, "isatty", lambda: True, raising=False)
    with _app.stage_progress("simulating") as report:
        report("early reflections (orders 1-3)", 0, 40)
        report("later reflections (orders 4-9)", 0, 8)
        report("early reflections (orders 1-3)", 40, 40)
        report("later reflections (orders 4-9)", 3, 8)
    text = out.getvalue()
    assert "simulating: early reflections (orders 1-3)" in text and "40/40" in text
    assert "simulating: later reflections (orders 4-9)" in text and "3/8" in text
    monkeypatch.setattr(_app.sys.stderr, "isatty", lambda: False, raising=False)
    out.truncate(0)
    with _app.stage_progress("simulating") as report:
        report("early reflections (orders 1-3)", 5, 40)
    assert out.getvalue() == ""
