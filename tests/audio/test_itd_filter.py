import numpy as np
import pytest

from hearsee.audio.itd_filter import ItdKalman, confidence_r_scale, pair_matrix
from hearsee.errors import ConfigError, GeometryError

TRUE = np.array([1e-4, 2.5e-4, 1.5e-4])  # pairs 0-1, 0-2, 1-2 (consistent: t01 + t12 = t02)


def _noisy(n, seed=0, std=2e-5):
    return TRUE + np.random.default_rng(seed).normal(0.0, std, (n, 3))


def test_pair_matrix_maps_reference_state():
    H = pair_matrix(3, [(0, 1), (0, 2), (1, 2)], ref=0)
    s = np.array([-1e-4, -2.5e-4])  # t1 - t0, t2 - t0
    np.testing.assert_allclose(H @ s, TRUE)
    H1 = pair_matrix(3, [(0, 1), (2, 1)], ref=1)
    np.testing.assert_allclose(H1 @ np.array([1e-4, 1.5e-4 * -1]), [1e-4, -1.5e-4])


def test_filter_converges_and_state_is_inspectable():
    kf = ItdKalman(3, q_std_s=1e-6, r_std_s=2e-5)
    out, acc = kf.filter(_noisy(60))
    assert acc.all()
    np.testing.assert_allclose(kf.x, [-1e-4, -2.5e-4], atol=8e-6)  # state: t_k - t_0
    np.testing.assert_allclose(out[-1], TRUE, atol=8e-6)
    assert kf.P.shape == (2, 2) and np.all(np.linalg.eigvalsh(kf.P) > 0)
    assert np.trace(kf.P) < (2e-5) ** 2  # tighter than one measurement
    # filtered error is smaller than the raw measurement error
    raw = np.sqrt(np.mean((_noisy(60)[30:] - TRUE) ** 2))
    filt = np.sqrt(np.mean((out[30:] - TRUE) ** 2))
    assert filt < 0.5 * raw
    # textbook names are there
    for name in ("x", "P", "F", "H", "Q", "R"):
        assert hasattr(kf.kf, name)


def test_gating_rejects_injected_outlier():
    Z = _noisy(40, seed=1)
    Z[25] = [-3e-4, 4e-4, 1e-4]  # an anomalous GCC peak
    kf = ItdKalman(3, q_std_s=1e-6, r_std_s=2e-5)
    out, acc = kf.filter(Z)
    assert not acc[25] and acc[26:].all()
    assert kf.n_rejected == 1
    np.testing.assert_allclose(out[25], TRUE, atol=2e-5)  # state not pulled to the outlier


def test_missing_frames_predict_only_and_covariance_grows():
    kf = ItdKalman(2, q_std_s=5e-6, r_std_s=2e-5)
    for z in _noisy(10)[:, :1]:
        kf.step(z)
    p_before = kf.P.copy()
    x_before = kf.x.copy()
    assert kf.step(None) is False
    assert kf.step([np.nan]) is False
    np.testing.assert_allclose(kf.x, x_before)
    assert kf.P[0, 0] > p_before[0, 0]


def test_reinitialises_after_repeated_rejections():
    kf = ItdKalman(2, q_std_s=1e-6, r_std_s=1e-5, max_rejects=3)
    for _ in range(10):
        kf.step([1e-4])
    for _ in range(3):
        kf.step([-2e-4])  # the source jumped
    assert kf.pair_tdoas()[0] == pytest.approx(-2e-4, abs=1e-6)


def test_bad_parameters():
    with pytest.raises(GeometryError):
        ItdKalman(1)
    with pytest.raises(ConfigError):
        ItdKalman(3, q_std_s=0.0)
    # NaN and inf passed the "<= 0" test: NaN TDOAs, or an SVD that did not converge; 1e-200
    # squared to a singular R (numpy's LinAlgError at the first step), 1e200 overflowed
    for kw in ({"q_std_s": np.nan}, {"q_std_s": np.inf}, {"r_std_s": np.nan},
               {"r_std_s": np.inf}, {"p0_std_s": np.nan}, {"r_std_s": 1e-200},
               {"q_std_s": 1e200}):
        with pytest.raises(ConfigError, match="must be numbers from 1e-09 to 1 seconds"):
            ItdKalman(3, **kw)
    with pytest.raises(ConfigError, match="r_scale must be numbers from 1e-06 to 1e"):
        ItdKalman(3).step([0.0, 0.0, 0.0], r_scale=[1e-200] * 3)
    for bad in ("abc", None):  # (numpy's ValueError; None read as the largest scale)
        with pytest.raises(ConfigError, match="confidence must be numbers"):
            confidence_r_scale(bad)
    with pytest.raises(ConfigError):
        ItdKalman(3, gate_prob=1.5)
    with pytest.raises(GeometryError, match="do not determine"):
        ItdKalman(3, pairs=[(0, 1)])
    kf = ItdKalman(3)
    with pytest.raises(GeometryError, match="expected 3"):
        kf.step([0.0, 0.0])


def test_max_rejects_below_one_is_refused():
    # found in review: max_rejects=0 (or negative) was accepted and re-initialised the filter on
    # every rejected measurement, i.e. switched the gate off: a 4e-4 s jump after a steady 1e-4 s
    # was taken as the state at once
    kf = ItdKalman(2, q_std_s=1e-6, r_std_s=1e-5, max_rejects=1)
    for _ in range(5):
        kf.step([1e-4])
    assert kf.step([5e-4]) is True  # max_rejects=1: the first rejection re-initialises
    assert kf.pair_tdoas()[0] == pytest.approx(5e-4)
    for bad in (0, -2, 1.5, np.nan, "5"):
        with pytest.raises(ConfigError, match="max_rejects"):
            ItdKalman(2, max_rejects=bad)


def test_parameters_that_are_not_numbers_are_config_errors():
    # found in review: a string noise or gate raised numpy's/Python's TypeError, n_mics=2.5 a
    # TypeError from range(), and ref=1.5 was truncated to microphone 1 without a word
    for kw in ({"q_std_s": "1e-5"}, {"r_std_s": None}, {"p0_std_s": "1e-3"},
               {"gate_prob": "0.99"}, {"gate_prob": None}):
        with pytest.raises(ConfigError):
            ItdKalman(3, **kw)
    for n_mics in (2.5, None, "3"):
        with pytest.raises(GeometryError, match="n_mics"):
            ItdKalman(n_mics)
    for ref in (1.5, -1, 3, None):
        with pytest.raises(GeometryError, match="ref"):
            ItdKalman(3, ref=ref)
    kf = ItdKalman(np.int64(3), ref=np.int64(2))  # numpy integers are fine
    assert kf.n_mics == 3 and kf.ref == 2


def test_step_refuses_tdoas_that_are_no_real_numbers_or_absurd():
    """Bad-input sweep of the public API: step(['a', 'b', 'c']) raised numpy's builtin
    ValueError, and a TDOA of 1e300 s made the gate distance NaN, which passed the gate: the
    state became 1e300 s."""
    kf = ItdKalman(3)
    truth = np.array([1e-4, 2e-4, 1e-4])  # pairs 0-1, 0-2, 1-2: t0 - t1 = 1e-4, t0 - t2 = 2e-4
    assert kf.step(truth)
    for bad in (["a", "b", "c"], [True, False, True], [1e300, 2e-4, 1e-4]):
        with pytest.raises(GeometryError, match="TDOAs"):
            kf.step(bad)
    assert not kf.step([np.nan, 2e-4, 1e-4])  # missing: predict only
    np.testing.assert_allclose(kf.pair_tdoas(), truth, atol=1e-12)


def test_filter_refuses_what_step_refuses():
    """filter() converted its frames with numpy first: [["1e-4", ...]] was read as seconds and
    True as 1 s, which step() refuses; a ragged list raised numpy's builtin ValueError."""
    frames = [[1e-4, 2e-4, 1e-4]] * 3
    for bad in ([["1e-4", "2e-4", "1e-4"]] * 3, [[True, 2e-4, 1e-4]] * 3,
                [[1e-4, 2e-4, 1e-4], [1e-4]]):
        with pytest.raises(GeometryError, match="TDOAs must be real numbers"):
            ItdKalman(3).filter(bad)
    out, acc = ItdKalman(3).filter(frames)
    np.testing.assert_allclose(out[-1], frames[0], atol=1e-12)
    assert acc.all()


def test_pair_matrix_checks_its_arguments_as_the_filter_does():
    """pair_matrix is public: n_mics 0 raised numpy's builtin ValueError, a reference of 9 for
    3 microphones gave a matrix as if no microphone were the reference, and the filter
    truncated a pair (0.7, 1.9) to (0, 1)."""
    for kw, msg in (({"n_mics": 0}, "n_mics"), ({"ref": 9}, "ref"),
                    ({"pairs": [(0.7, 1.9)]}, "pair"), ({"pairs": [(0, 3)]}, "pair")):
        args = {"n_mics": 3, "pairs": [(0, 1), (0, 2)], "ref": 0} | kw
        with pytest.raises(GeometryError, match=msg):
            pair_matrix(**args)
    with pytest.raises(GeometryError, match="pair"):
        ItdKalman(3, pairs=[(0.7, 1.9), (0, 2)])
    np.testing.assert_array_equal(pair_matrix(3, [(0, 1), (1, 2), (0, 2)], ref=0),
                                  [[-1, 0], [1, -1], [0, -1]])


def test_no_state_is_reported_before_the_first_measurement():
    """pair_tdoas() and x returned the prior's zeros (broadside, 0 s) before any measurement, as
    if estimated; they refuse now, as the direction trackers' gate_distance does without a
    track. Missing frames do not start the filter; the first measurement does (ground truth:
    the TDOAs it was given)."""
    from hearsee.errors import EstimationError

    kf = ItdKalman(3, q_std_s=1e-6, r_std_s=2e-5)
    for _ in range(2):
        with pytest.raises(EstimationError, match="before its first measurement"):
            kf.pair_tdoas()
        with pytest.raises(EstimationError, match="before its first measurement"):
            _ = kf.x
        assert kf.step(None) is False and not kf.initialized
    assert kf.P.shape == (2, 2)  # the prior's covariance stays readable
    assert kf.step([1e-4, 2e-4, 1e-4])
    np.testing.assert_allclose(kf.pair_tdoas(), [1e-4, 2e-4, 1e-4], atol=1e-12)
    np.testing.assert_allclose(kf.x, [-1e-4, -2e-4], atol=1e-12)


def test_smoother_lowers_noise_and_lag():
    """Rauch-Tung-Striebel over a whole sequence: a static source's TDOAs get less noise than
    the filter leaves, and a source moving at a constant rate none of the filter's lag (the
    filter trails a ramp by a steady offset; the smoother, using later frames too, does not)."""
    n = 200
    Z = _noisy(n, seed=3)
    kw = {"q_std_s": 2e-6, "r_std_s": 2e-5}
    f, acc_f = ItdKalman(3, **kw).filter(Z)
    s, acc_s = ItdKalman(3, **kw).smooth(Z)
    assert np.array_equal(acc_f, acc_s)
    e_raw, e_f, e_s = (np.sqrt(np.mean((a[20:] - TRUE) ** 2)) for a in (Z, f, s))
    assert e_s < 0.85 * e_f and e_f < 0.5 * e_raw
    # a ramp: pair 0-1 grows 1 us per frame (0-2 with it, 1-2 constant)
    ramp = np.outer(np.arange(n) * 1e-6, [1.0, 1.0, 0.0])
    Zr = TRUE + ramp + np.random.default_rng(4).normal(0.0, 2e-5, (n, 3))
    kw = {"q_std_s": 1e-6, "r_std_s": 2e-5, "gate_prob": 0.9999}
    f, _ = ItdKalman(3, **kw).filter(Zr)
    s, _ = ItdKalman(3, **kw).smooth(Zr)
    mid = slice(50, 150)
    lag_f = np.mean((f - TRUE - ramp)[mid, 0])
    lag_s = np.mean((s - TRUE - ramp)[mid, 0])
    assert lag_f < -3e-6 and abs(lag_s) < 1e-6  # (the filter trails the ramp)


def test_smoother_does_not_smear_across_a_reinitialisation_or_before_the_first_frame():
    """A source that jumps (another talker): the filter re-initialises after max_rejects
    rejections; the smoother treats the stretches on either side apart, so frames before the
    jump keep the old TDOAs -- and, since 2026-12-04, the rejected frames that led to the
    re-initialisation (60, 61; missing frames among them passed over) start the new stretch
    instead of taking the old one's values. Frames before the first measurement stay NaN."""
    Z = _noisy(120, seed=5, std=1e-6)
    Z[60:] += 2e-4  # pair 0-1 and 0-2 move by 200 us, 1-2 keeps its TDOA
    Z[60:, 2] -= 2e-4
    Z[:5] = np.nan
    Z[61] = np.nan  # (a pause inside the run)
    kf = ItdKalman(3, q_std_s=1e-7, r_std_s=2e-6, max_rejects=3)
    s, acc = kf.smooth(Z)
    assert np.all(np.isnan(s[:5])) and not acc[:5].any()
    np.testing.assert_allclose(s[5:60], np.broadcast_to(TRUE, (55, 3)), atol=1e-6)
    np.testing.assert_allclose(s[60:], np.broadcast_to(TRUE + [2e-4, 2e-4, 0.0], (60, 3)),
                               atol=1e-6)
    assert acc[60] and acc[62:].all() and kf.n_inits == 2  # (first frame, the jump)
    assert kf.n_rejected == 0  # (the run's rejections were undone by the look-back)
    # the filter alone cannot look back: its rejected frames keep the old TDOAs
    f, facc = ItdKalman(3, q_std_s=1e-7, r_std_s=2e-6, max_rejects=3).filter(Z)
    np.testing.assert_allclose(f[60], TRUE, atol=1e-6)
    assert not facc[60] and not facc[62] and facc[63]


def test_smoother_leaves_out_rejected_peaks_that_do_not_fit_the_new_stretch():
    """The backtracking of a re-initialisation stops at the first rejected measurement that
    does not fit the new state: a reflection's peak (frame 60, 300 us off both positions)
    before a source's jump (frame 61 on) keeps the old stretch's value, the jump's first
    frames start the new one."""
    Z = _noisy(120, seed=6, std=1e-6)
    new = TRUE + [2e-4, 2e-4, 0.0]
    Z[61:] += new - TRUE
    Z[60] = TRUE + [-3e-4, 0.0, 3e-4]
    kf = ItdKalman(3, q_std_s=1e-7, r_std_s=2e-6, max_rejects=3)
    s, acc = kf.smooth(Z)
    np.testing.assert_allclose(s[:61], np.broadcast_to(TRUE, (61, 3)), atol=1e-6)
    np.testing.assert_allclose(s[61:], np.broadcast_to(new, (59, 3)), atol=1e-6)
    assert not acc[60] and acc[61:].all() and kf.n_rejected == 1  # (the reflection's)


def test_smoother_of_a_filter_that_has_a_state_smooths_every_frame():
    """Found in review (2026-12-07): ``smooth`` on a filter with a state already (after a step,
    ``filter`` or an earlier ``smooth`` -- a recording in chunks) cut its stretches only at
    re-initialisations, so the frames before the first of them were never written: every frame
    NaN, though all were measured and accepted."""
    Z = _noisy(40, seed=8)
    for warm in ("step", "filter", "smooth"):
        kf = ItdKalman(3, q_std_s=1e-6, r_std_s=2e-5)
        if warm == "step":
            kf.step(Z[0])
        else:
            getattr(kf, warm)(Z[:20])
        s, acc = kf.smooth(Z[20:])
        assert acc.all() and np.all(np.isfinite(s)), warm
        np.testing.assert_allclose(s, np.broadcast_to(TRUE, s.shape), atol=2e-5)
        np.testing.assert_allclose(s[-1], kf.pair_tdoas())  # (the last frame: the filter's)


def test_smooth_refuses_what_filter_refuses():
    kf = ItdKalman(3)
    with pytest.raises(GeometryError, match="expected \\(n_frames, n_pairs\\)"):
        kf.smooth(np.zeros(3))


@pytest.mark.parametrize("run", ["filter", "smooth", "log_likelihood"])
def test_a_bad_frame_is_refused_before_the_filter_changes(run):
    """The frames are checked once, up front (since 2026-12-04; each step checked its own
    before): a frame of 1e300 s or of two TDOAs among good ones is refused with step()'s
    message, and the filter has not moved -- it had taken the frames before the bad one."""
    good = [[1e-4, 2e-4, 1e-4]] * 4
    args = (BOX,) if run == "log_likelihood" else ()
    for bad, msg in (([1e300, 2e-4, 1e-4], "at most 3600 s"), ([1e-4, 2e-4], "expected 3")):
        kf = ItdKalman(3)
        frames = good + [bad] + good if len(bad) == 3 else np.array(good)[:, :2]
        with pytest.raises(GeometryError, match=msg):
            getattr(kf, run)(frames, *args)
        assert not kf.initialized and kf.n_inits == 0
    first, second = getattr(ItdKalman(3), run)(good, *args)  # (the good frames alone)
    if run == "log_likelihood":
        assert second == 3 and np.isfinite(first)  # (every frame after the first scored)
    else:
        np.testing.assert_allclose(first[-1], good[0], atol=1e-12)
        assert second.all()


# ------------------------------------------------------- the noise model tuned to the recording
FS_T = 16000.0
BOX = np.array([4.4e-4, 4.4e-4, 4.4e-4])  # the three-mic preset's lag bound per pair (s)


def _walk(n, q_s, r_s, seed, outliers=0.0):
    """Pair TDOAs (n, 3) of a state (t1 - t0, t2 - t0) walking with steps of std ``q_s``,
    measured with noise ``r_s``; a share ``outliers`` of frames replaced by uniform peaks
    within BOX. Returns (measured, true)."""
    rng = np.random.default_rng(seed)
    s = np.cumsum(rng.normal(0.0, q_s, (n, 2)), axis=0) + [-1e-4, -2.5e-4]
    true = s @ pair_matrix(3, [(0, 1), (0, 2), (1, 2)]).T
    z = true + rng.normal(0.0, r_s, true.shape)
    bad = rng.random(n) < outliers
    z[bad] = rng.uniform(-BOX, BOX, (int(bad.sum()), 3))
    return z, true


@pytest.mark.parametrize("q_samples, r_samples", [(1.0, 0.3), (0.03, 3.0), (0.3, 1.0)])
def test_tune_itd_noise_finds_the_noise_that_made_the_frames(q_samples, r_samples):
    from hearsee.audio.itd_filter import tune_itd_noise

    z, _ = _walk(400, q_samples / FS_T, r_samples / FS_T, seed=int(10 * q_samples))
    q, r = tune_itd_noise(z, 3, [(0, 1), (0, 2), (1, 2)], FS_T, BOX)
    assert q * FS_T == pytest.approx(q_samples) and r * FS_T == pytest.approx(r_samples)


def test_tuned_smoother_follows_precise_frames_of_a_moving_source():
    """Precise frames of a source that moves (white noise: 0.05 samples of error, the state
    walking a sample per frame): the former fixed model (q a quarter sample, r one sample)
    lagged it by 25-35 times the frames' own error; the tuned one stays within 3x of them
    (not below: the grid's smallest r is 0.3 samples, which voices' frames need)."""
    from hearsee.audio.itd_filter import tune_itd_noise

    z, true = _walk(300, 1.0 / FS_T, 0.05 / FS_T, seed=3)
    noise = tune_itd_noise(z, 3, [(0, 1), (0, 2), (1, 2)], FS_T, BOX)
    tuned = ItdKalman(3, q_std_s=noise[0], r_std_s=noise[1]).smooth(z)[0]
    fixed = ItdKalman(3, q_std_s=0.25 / FS_T, r_std_s=1.0 / FS_T).smooth(z)[0]
    rms = lambda a: float(np.sqrt(np.mean((a - true) ** 2)))  # noqa: E731
    assert noise[0] * FS_T == pytest.approx(1.0)
    assert rms(tuned) < 3 * rms(z) and rms(fixed) > 10 * rms(z)


def test_tuned_smoother_still_rejects_a_reflections_peaks():
    """A still source whose frames hold 10 % anomalous peaks: the outlier term keeps them
    from deciding the model (a small random walk is chosen) and the smoother's RMSE is far
    below the frames'."""
    from hearsee.audio.itd_filter import tune_itd_noise

    z, true = _walk(300, 1e-9, 0.5 / FS_T, seed=4, outliers=0.1)
    q, r = tune_itd_noise(z, 3, [(0, 1), (0, 2), (1, 2)], FS_T, BOX)
    assert q * FS_T <= 0.1
    out = ItdKalman(3, q_std_s=q, r_std_s=r).smooth(z)[0]
    rms = lambda a: float(np.sqrt(np.mean((a - true) ** 2)))  # noqa: E731
    assert rms(out) < 0.1 * rms(z) and rms(out) < 0.5 / FS_T


def test_tune_itd_noise_with_given_values_and_too_few_frames():
    from hearsee.audio.itd_filter import tune_itd_noise

    z, _ = _walk(100, 1.0 / FS_T, 0.3 / FS_T, seed=5)
    pairs = [(0, 1), (0, 2), (1, 2)]
    assert tune_itd_noise(z, 3, pairs, FS_T, BOX, r_std_s=(2e-5,))[1] == 2e-5
    assert tune_itd_noise(z, 3, pairs, FS_T, BOX, q_std_s=(7e-6,))[0] == 7e-6
    assert tune_itd_noise(z[:2], 3, pairs, FS_T, BOX) is None  # one frame scored
    gaps = np.full_like(z, np.nan)
    gaps[::25] = z[::25]
    assert tune_itd_noise(gaps, 3, pairs, FS_T, BOX) is not None  # (predicts across gaps)
    with pytest.raises(ConfigError, match="fs must be"):
        tune_itd_noise(z, 3, pairs, "16000", BOX)
    assert tune_itd_noise(z, 3, pairs, FS_T, BOX, q_std_s=7e-6)[0] == 7e-6  # (one number)
    for bad in ("7e-6", [], [[]]):
        with pytest.raises(ConfigError, match="q_std_s must be one or more numbers"):
            tune_itd_noise(z, 3, pairs, FS_T, BOX, q_std_s=bad)
    with pytest.raises(ConfigError, match="q_std_s, r_std_s and p0_std_s"):  # (ItdKalman's)
        tune_itd_noise(z, 3, pairs, FS_T, BOX, q_std_s=-1.0)


def test_log_likelihood_refuses_bad_arguments():
    kf = ItdKalman(3)
    z = _noisy(10)
    for bad in (0.0, 1.0, np.nan, "0.1"):
        with pytest.raises(ConfigError, match="outlier_prob"):
            kf.log_likelihood(z, BOX, outlier_prob=bad)
    for box in (BOX[:2], [1e-4, -1e-4, 1e-4], [1e-4, np.nan, 1e-4]):
        with pytest.raises(GeometryError, match="max_tdoa_s"):
            ItdKalman(3).log_likelihood(z, box)
    with pytest.raises(GeometryError, match="n_frames, n_pairs"):
        kf.log_likelihood(z[0], BOX)
    total, n = ItdKalman(3, q_std_s=1e-7, r_std_s=2e-5).log_likelihood(z, BOX)
    assert n == 9 and np.isfinite(total)  # every frame after the first


def test_confidence_r_scale():
    """The measurement noise's scale falls with the square root of the GCC peak's margin over
    its rival (1 at c = 1.3), clipped to [0.1, 10]; no peak (c <= 1, NaN) is the largest."""
    from hearsee.audio.itd_filter import confidence_r_scale

    c = np.array([[1.3, 1.03, 1.0003], [4.0, 1000.0, np.nan], [1.0, 0.0, 31.0]])
    np.testing.assert_allclose(confidence_r_scale(c), [[1.0, np.sqrt(10.0), 10.0],
                                                       [np.sqrt(0.1), 0.1, 10.0],
                                                       [10.0, 10.0, 0.1]])


def test_frames_scaled_by_their_confidence_outweigh_rival_peaks():
    """A source walking a third of a sample per frame, its frames 0.1 sample off, and a third
    of them a reflection's peak 2 samples off (inside the gate) with a low confidence (c =
    1.03, against 3 for the others): scaled by their confidence the reflection frames barely
    count, and the smoother's error is a third of the unscaled one's (0.19 vs 0.53 samples,
    same q and r; the frames 1.2); all scales 1 is no scale at all."""
    from hearsee.audio.itd_filter import confidence_r_scale

    rng = np.random.default_rng(21)
    z, true = _walk(300, 0.3 / FS_T, 0.1 / FS_T, seed=21)
    refl = rng.random(300) < 1 / 3
    z[refl] += rng.choice([-2.0, 2.0], (int(refl.sum()), 1)) / FS_T
    conf = np.where(refl[:, None], 1.03, 3.0) * np.ones((1, 3))
    kw = {"q_std_s": 0.3 / FS_T, "r_std_s": 1.0 / FS_T}
    plain = ItdKalman(3, **kw).smooth(z)[0]
    scaled = ItdKalman(3, **kw).smooth(z, r_scale=confidence_r_scale(conf))[0]
    rms = lambda a: float(np.sqrt(np.mean((a - true) ** 2)))  # noqa: E731
    assert rms(scaled) < 0.4 * rms(plain) and rms(scaled) < 0.3 / FS_T
    ones = np.ones_like(z)
    np.testing.assert_array_equal(ItdKalman(3, **kw).filter(z, r_scale=ones)[0],
                                  ItdKalman(3, **kw).filter(z)[0])
    kf = ItdKalman(3, **kw)
    kf.step(z[0])
    kf.step(z[1], r_scale=[2.0, 2.0, 2.0])
    np.testing.assert_allclose(kf.kf.R, np.eye(3) * (2.0 / FS_T) ** 2)
    kf.step(z[2])
    np.testing.assert_allclose(kf.kf.R, np.eye(3) * (1.0 / FS_T) ** 2)  # (back to r_std_s)


def test_a_first_frame_with_per_pair_noise_is_fitted_as_its_covariance_says():
    """The state from a (re)initialising frame is the least-squares fit weighted by the
    frame's per-pair noise, whose covariance ``(H^T R^-1 H)^-1`` it is given. With
    ``r_scale`` (0.1, 10, 10) (pair 0-1 a clean peak, the others weak) the fit was
    unweighted: pair 0-1's TDOA took the others' errors, 4.7 samples off where the
    covariance said 0.1 (NEES 2200 instead of 2 over 2000 seeded first frames), and a still
    source's next frames were rejected -- 31 of 50 per run, 6.8 re-initialisations, pair 0-1
    still 2.3 samples off. Now NEES ~2, and the filter keeps the source."""
    rng = np.random.default_rng(5)
    sc = np.array([0.1, 10.0, 10.0])
    r = 1.0 / FS_T
    H = pair_matrix(3, [(0, 1), (0, 2), (1, 2)], 0)
    s = np.array([3e-4, -2e-4])  # (t1 - t0, t2 - t0), seconds
    nees = []
    for _ in range(500):
        kf = ItdKalman(3, q_std_s=1e-9, r_std_s=r)
        assert kf.step(H @ s + rng.standard_normal(3) * r * sc, r_scale=sc)
        e = kf.x - s
        nees.append(e @ np.linalg.solve(kf.P, e))
    assert 1.6 < np.mean(nees) < 2.4
    Z = H @ s + rng.standard_normal((50, 3)) * r * sc
    kf = ItdKalman(3, q_std_s=0.03 / FS_T, r_std_s=r)
    out, acc = kf.filter(Z, r_scale=np.tile(sc, (50, 1)))
    assert kf.n_inits == 1 and acc.sum() >= 47
    assert np.abs(out[10:, 0] - (H @ s)[0]).max() < 0.2 / FS_T
    # one noise for every pair: the plain least squares, as before
    kf = ItdKalman(3, q_std_s=1e-9, r_std_s=r)
    kf.step(Z[0], r_scale=[3.0, 3.0, 3.0])
    np.testing.assert_array_equal(kf.x, np.linalg.lstsq(H, Z[0], rcond=None)[0])


def test_a_hand_set_r_is_kept_and_scaled():
    """``kf.R`` set by hand (filterpy's name, which the module offers) was overwritten by the
    next step without a word; it is now the base noise that per-frame scales multiply, and a
    bad one is refused. Checked against a filter built with that noise."""
    z = _noisy(40, seed=8)
    a = ItdKalman(3, q_std_s=1e-6, r_std_s=2e-5)
    b = ItdKalman(3, q_std_s=1e-6, r_std_s=5e-5)
    a.step(z[0])
    b.step(z[0])
    a.kf.R = np.eye(3) * 5e-5**2  # (assigned)
    b.kf.P = a.kf.P.copy()  # (the same state to start from)
    for k in range(1, 20):
        assert a.step(z[k]) == b.step(z[k])
    np.testing.assert_allclose(a.x, b.x, rtol=1e-12)
    a.kf.R[:] = np.eye(3) * 1e-5**2  # (edited in place)
    b = ItdKalman(3, q_std_s=1e-6, r_std_s=1e-5)
    b.kf.x, b.kf.P, b.initialized = a.kf.x.copy(), a.kf.P.copy(), True
    for k in range(20, 40):
        a.step(z[k], r_scale=[2.0, 1.0, 1.0])
        b.step(z[k], r_scale=[2.0, 1.0, 1.0])
    np.testing.assert_allclose(a.x, b.x, rtol=1e-12)
    np.testing.assert_allclose(a.kf.R, np.diag([4.0, 1.0, 1.0]) * 1e-5**2)  # (scaled)
    for bad in (np.eye(2), -np.eye(3), np.full((3, 3), np.nan), "1e-9"):
        a.kf.R = bad
        with pytest.raises(ConfigError, match="kf.R"):
            a.step(z[0])


def test_r_scale_and_q_max_are_checked():
    from hearsee.audio.itd_filter import max_itd_step_s, tune_itd_noise

    z = _noisy(20)
    for bad in (np.ones((20, 2)), np.zeros((20, 3)), np.full((20, 3), np.nan), "1"):
        with pytest.raises(ConfigError, match="r_scale must be"):
            ItdKalman(3).smooth(z, r_scale=bad)
    with pytest.raises(ConfigError, match="r_scale must be"):
        ItdKalman(3).step(z[0], r_scale=[1.0, -1.0, 1.0])
    with pytest.raises(ConfigError, match="r_scale must be"):
        ItdKalman(3).log_likelihood(z, BOX, r_scale=np.ones((19, 3)))
    pairs = [(0, 1), (0, 2), (1, 2)]
    for bad in (0.0, -1.0, np.nan, "1e-5"):
        with pytest.raises(ConfigError, match="q_max_s"):
            tune_itd_noise(z, 3, pairs, FS_T, BOX, q_max_s=bad)
    # below the grid's smallest q: that one is kept
    assert tune_itd_noise(z, 3, pairs, FS_T, BOX, q_max_s=1e-12)[0] * FS_T == pytest.approx(0.03)
    walk, _ = _walk(300, 1.0 / FS_T, 0.1 / FS_T, seed=6)  # (would pick q = 1 sample)
    assert tune_itd_noise(walk, 3, pairs, FS_T, BOX)[0] * FS_T == pytest.approx(1.0)
    assert tune_itd_noise(walk, 3, pairs, FS_T, BOX, q_max_s=0.5 / FS_T)[0] * FS_T == (
        pytest.approx(0.3))
    # a 15 cm pair turning at 90 deg/s: its ITD moves at most 0.15 / c * pi / 2 per second
    assert max_itd_step_s([1e-4, 0.15 / 343.0], 0.032) == pytest.approx(
        0.15 / 343.0 * np.pi / 2 * 0.032)
    assert max_itd_step_s([0.15 / 343.0], 0.5, rate_dps=45.0) == pytest.approx(
        0.15 / 343.0 * np.pi / 4 * 0.5)
    for bad in ([], [0.0], [np.nan], "1e-4"):
        with pytest.raises(GeometryError, match="max_tdoa_s"):
            max_itd_step_s(bad, 0.032)
    with pytest.raises(ConfigError, match="hop_s and rate_dps"):
        max_itd_step_s([1e-4], 0.0)


def test_helpers_refuse_text_and_malformed_noise():
    """From an API audit: text bounds were numpy's ValueError, a text rate with a given
    q_std_s a builtin TypeError, a 1-tuple noise an IndexError."""
    from hearsee.audio.itd_filter import itd_filter_entries, max_itd_step_s, smooth_recording_itds

    pairs = [(0, 1), (0, 2), (1, 2)]
    with pytest.raises(GeometryError, match="max_tdoa_s must be finite"):
        max_itd_step_s("abc", 0.016)
    with pytest.raises(GeometryError, match="max_tdoa_s must be 3 finite"):
        ItdKalman(3).log_likelihood(_noisy(5), "abc")
    with pytest.raises(ConfigError, match="fs must be a sample rate"):
        smooth_recording_itds(_noisy(5), np.ones((5, 3)), 3, pairs, "x", [4e-4] * 3, 0.032,
                              q_std_s=1e-5)
    with pytest.raises(ConfigError, match=r"noise must be \(q_std_s, r_std_s\)"):
        itd_filter_entries((1e-5,), "fixed")
    assert itd_filter_entries((1e-5, 2e-5), "fixed")["kalman_r_std_s"] == 2e-5
