import copy

import numpy as np
import pytest

from hearsee.audio.tracking import (
    ELEVATION_ACCEL_RATIO,
    LOST_AZIMUTH_SD_DEG,
    DirectionIMM,
    DirectionKalman,
    MotionKalman,
    track_directions,
    track_positions,
)
from hearsee.errors import EstimationError
from hearsee.geometry import wrap_deg

DT = 0.032


def _err(a, b):
    return np.abs(wrap_deg(np.asarray(a) - np.asarray(b)))


def test_tracking_halves_error_of_noisy_constant_rate_motion():
    rng = np.random.default_rng(0)
    t = np.arange(200) * DT
    az_true = -60 + 30 * t  # 30 deg/s
    el_true = 10 + 5 * t
    az = az_true + 5 * rng.standard_normal(t.size)
    el = el_true + 5 * rng.standard_normal(t.size)
    tr = track_directions(t, az, el, sigma_meas_deg=5.0, sigma_accel_dps2=30.0)
    s = slice(30, None)
    raw = np.sqrt(np.mean(_err(az, az_true)[s] ** 2))
    trk = np.sqrt(np.mean(_err(tr.azimuth_deg, az_true)[s] ** 2))
    assert trk < 0.5 * raw
    assert np.sqrt(np.mean((tr.elevation_deg - el_true)[s] ** 2)) < 0.5 * 5
    assert np.median(tr.rate_dps[s, 0]) == pytest.approx(30.0, abs=3.0)
    # no lag: mean signed error is near zero
    assert abs(np.mean(wrap_deg(tr.azimuth_deg - az_true)[s])) < 1.0


def test_wraps_through_180_without_a_jump():
    rng = np.random.default_rng(1)
    t = np.arange(150) * DT
    az_true = wrap_deg(150 + 40 * t)  # crosses +180 -> -180 at t = 0.75 s
    az = wrap_deg(az_true + 3 * rng.standard_normal(t.size))
    tr = track_directions(t, az, sigma_meas_deg=3.0, sigma_accel_dps2=30.0)
    e = _err(tr.azimuth_deg, az_true)
    assert e[10:].max() < 6.0
    assert np.all(tr.accepted[1:])
    assert np.all(np.abs(tr.azimuth_deg) <= 180.0)
    assert tr.rate_dps[-1, 0] == pytest.approx(40.0, abs=5.0)


def test_gate_rejects_outliers_and_missing_frames_predict():
    rng = np.random.default_rng(2)
    t = np.arange(200) * DT
    az_true = 20 + 15 * np.sin(0.5 * t)
    az = az_true + 2 * rng.standard_normal(t.size)
    outl = rng.random(t.size) < 0.15
    outl[:5] = False
    az[outl] = rng.uniform(-180, 180, outl.sum())
    az[100:110] = np.nan  # missing frames
    tr = track_directions(t, az, sigma_meas_deg=2.0, sigma_accel_dps2=20.0)
    far = outl & (_err(az, az_true) > 30)
    assert not np.any(tr.accepted[far])
    assert not np.any(tr.accepted[100:110])
    assert _err(tr.azimuth_deg, az_true)[5:].max() < 8.0
    raw = np.sqrt(np.nanmean(_err(az, az_true) ** 2))
    assert np.sqrt(np.mean(_err(tr.azimuth_deg, az_true)[5:] ** 2)) < 0.1 * raw


def test_restart_after_consecutive_rejections():
    kf = DirectionKalman(sigma_meas_deg=2.0, max_rejects=3)
    for k in range(20):
        kf.update(k * DT, (10.0, 0.0))
    results = [kf.update((20 + k) * DT, (-120.0, 0.0)) for k in range(3)]
    assert results == [False, False, True]
    assert kf.azimuth_deg == pytest.approx(-120.0)


def test_after_a_pause_fewer_rejections_restart_the_track():
    """People taking turns: after more than ``pause_s`` without a measurement,
    ``pause_max_rejects`` rejections restart the track (a new talker elsewhere), not
    ``max_rejects``; without a pause -- or with the rule off -- the full count; a lone outlier
    after a pause followed by the old direction does not move the track, and the next jump
    needs the full count again."""
    def run(pause_s, gap_s, after):
        kf = DirectionKalman(sigma_meas_deg=2.0, max_rejects=4, pause_s=pause_s)
        for k in range(20):
            kf.update(k * DT, (10.0, 0.0))
        t0 = 19 * DT + gap_s
        return kf, [kf.update(t0 + k * DT, (a, 0.0)) for k, a in enumerate(after)]

    kf, res = run(0.15, 0.5, [-120.0] * 4)
    assert res[:2] == [False, True] and kf.azimuth_deg == pytest.approx(-120.0, abs=1.0)
    for pause_s, gap_s in ((None, 0.5), (0.15, 0.1)):  # rule off / a gap shorter than a pause
        kf, res = run(pause_s, gap_s, [-120.0] * 4)
        assert res == [False, False, False, True]
    kf, res = run(0.15, 0.5, [-120.0, 10.0, -120.0, -120.0, -120.0, -120.0])
    assert res == [False, True, False, False, False, True]
    kf = DirectionKalman(pause_s=0.15)
    kf.update(0.0, (10.0, 0.0))
    for k in range(1, 20):  # frames without a measurement count toward the pause
        kf.update(k * DT, None)
    assert kf.last_measured_t == 0.0
    for bad in (0, -1.0, np.nan, "1"):
        with pytest.raises(EstimationError, match="pause_s"):
            DirectionKalman(pause_s=bad)
    for bad in (0, 1.5):
        with pytest.raises(EstimationError, match="pause_max_rejects"):
            DirectionKalman(pause_max_rejects=bad)


def test_candidates_resolve_front_back_twin():
    kf = DirectionKalman(sigma_meas_deg=3.0)
    for k in range(60):
        a = 30.0 + 0.5 * k
        # measurement order alternates: the twin (180 - a) comes first half of the time
        pair = [(a, None), (180.0 - a, None)]
        if k % 2 and k > 0:
            pair = pair[::-1]
        kf.update(k * DT, pair[0], candidates=pair[1:])
    assert kf.azimuth_deg == pytest.approx(30.0 + 0.5 * 59, abs=2.0)
    assert np.isnan(kf.elevation_deg)


def test_constant_acceleration_motion_is_recovered():
    rng = np.random.default_rng(3)
    t = np.arange(150) * 0.05
    a = np.array([0.2, -0.1, 0.0])
    v0 = np.array([0.5, 0.8, 0.0])
    p0 = np.array([1.0, -1.0, 0.3])
    p = p0 + t[:, None] * v0 + 0.5 * t[:, None] ** 2 * a
    z = p + 0.02 * rng.standard_normal(p.shape)
    z[60:65] = np.nan
    tr = track_positions(t, z, sigma_meas_m=0.02, sigma_jerk=0.1)
    s = slice(40, None)
    v_true = v0 + t[:, None] * a
    assert np.sqrt(np.mean((tr.velocity[s] - v_true[s]) ** 2)) < 0.08
    assert np.abs(tr.acceleration[-20:].mean(axis=0) - a).max() < 0.1
    pos_err = np.linalg.norm(tr.position[s] - p[s], axis=1)
    raw_err = np.linalg.norm(z[s] - p[s], axis=1)
    assert np.nanmean(pos_err) < np.nanmean(raw_err)
    assert not np.any(tr.accepted[60:65])


def test_velocity_is_known_once_the_fixes_determine_it_and_again_after_a_restart():
    """A new track's velocity is its prior, 0 m/s: velocity_known is False at the first fix
    and turns True when the fixes bring every axis's standard deviation below
    VELOCITY_KNOWN_FRACTION of init_vel_sigma (here the second fix, 0.2 s and 0.7 m later);
    it stays known while the track coasts, and a restart forgets it."""
    from hearsee.audio.tracking import VELOCITY_KNOWN_FRACTION

    kf = MotionKalman(sigma_meas_m=0.05, sigma_jerk=5.0, init_vel_sigma=1.5)
    assert not kf.velocity_known
    kf.update(0.0, [1.0, 0.0, 1.2])
    assert kf.initialized and not kf.velocity_known
    np.testing.assert_array_equal(kf.velocity, 0.0)
    kf.update(0.2, [1.7, 0.0, 1.2])
    sd = np.sqrt(np.diag(kf.P)[kf._VEL])
    assert np.all(sd < VELOCITY_KNOWN_FRACTION * 1.5) and kf.velocity_known
    assert kf.velocity[0] > 1.0  # 3.5 m/s between the fixes, shrunk toward the prior
    kf.predict(0.6)  # coasting: the covariance grows, the velocity stays an estimate
    assert kf.velocity_known
    for k in range(kf.max_rejects):  # fixes far outside the gate restart the track
        kf.update(0.7 + 0.1 * k, [100.0, 100.0, 1.2])
    np.testing.assert_allclose(kf.position, [100.0, 100.0, 1.2])  # restarted there
    assert kf.initialized and not kf.velocity_known
    kf.reset()
    assert not kf.velocity_known


def test_motion_filter_jerk_per_axis():
    """sigma_jerk may be given per axis (x, y, z): the same three values are the scalar model,
    a small z value keeps a noisy height from turning into vertical speed."""
    from filterpy.common import Q_discrete_white_noise

    F, Q = MotionKalman(sigma_jerk=(2.0, 2.0, 2.0))._model(0.1)
    np.testing.assert_allclose(Q, Q_discrete_white_noise(dim=3, dt=0.1, var=4.0, block_size=3,
                                                         order_by_dim=True))
    # the documented meaning: the acceleration's white increment per update step (m/s^2),
    # whatever the step -- not a jerk in m/s^3, whose increment would grow with dt
    for dt in (0.016, 0.064, 0.2):
        Qa = MotionKalman(sigma_jerk=0.5)._model(dt)[1][np.ix_([2, 5, 8], [2, 5, 8])]
        np.testing.assert_allclose(Qa, 0.25 * np.eye(3))
    vz = {}
    for jz in (2.0, 0.05):
        rng = np.random.default_rng(3)  # the same fixes for both
        kf = MotionKalman(sigma_meas_m=0.05, sigma_jerk=(2.0, 2.0, jz))
        v = []
        for k in range(50):  # walking along x at 1 m/s, height 1.1 m measured +-5 cm
            t = 0.1 * k
            kf.update(t, [t, 0.0, 1.1 + rng.normal(0.0, 0.05)])
            v.append(kf.velocity)
        v = np.array(v[10:])
        vz[jz] = float(np.sqrt(np.mean(v[:, 2] ** 2)))  # the truth is 0
        assert np.sqrt(np.mean((v[:, 0] - 1.0) ** 2)) < 0.3
    assert vz[0.05] < 0.12 and vz[0.05] < 0.5 * vz[2.0]
    for bad in ((1.0, 2.0), (1.0, 1.0, -1.0), "2", np.nan, ["a", "b", "c"], None):
        with pytest.raises(EstimationError, match="sigma_jerk"):
            MotionKalman(sigma_jerk=bad)


def test_motion_filter_refuses_bad_gates_and_covariances():
    """A NaN or out-of-range gate_prob made the gate NaN (every fix accepted); a negative R gave
    a negative position covariance, a NaN R a NaN state, a zero R a singular innovation
    covariance (LinAlgError) at the second fix of a frame time."""
    for g in (np.nan, 1.5, 0.0):
        with pytest.raises(EstimationError, match="gate_prob"):
            MotionKalman(gate_prob=g)
    with pytest.raises(EstimationError, match="init_vel_sigma"):
        MotionKalman(init_vel_sigma=np.inf)
    kf = MotionKalman(0.05, 5.0)
    assert kf.update(0.0, [1.0, 2.0, 0.5])
    for R in (-0.01 * np.eye(3), np.full((3, 3), np.nan), np.zeros((3, 3)),
              np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]) * 1e-3, np.eye(2)):
        with pytest.raises(EstimationError, match="covariance"):
            kf.update(0.0, [1.0, 2.0, 0.5], R)
    assert kf.update(0.1, [1.0, 2.0, 0.5], 1e-4 * np.eye(3))
    assert np.all(np.linalg.eigvalsh(kf.position_cov) > 0)


def test_motion_gate_rejects_a_wild_fix():
    kf = MotionKalman(sigma_meas_m=0.02, sigma_jerk=1.0)
    for k in range(30):
        kf.update(k * 0.05, [1.0 + 0.05 * k, 0.0, 0.0])
    assert not kf.update(30 * 0.05, [5.0, 3.0, 0.0])
    assert kf.velocity[0] == pytest.approx(1.0, abs=0.05)


def test_bad_input():
    kf = DirectionKalman()
    kf.update(1.0, (0.0, 0.0))
    with pytest.raises(EstimationError, match="backwards"):
        kf.update(0.5, (0.0, 0.0))
    with pytest.raises(EstimationError):
        track_directions([0, 1], [0.0], [0.0])
    with pytest.raises(EstimationError):
        DirectionKalman(sigma_meas_deg=0)
    with pytest.raises(EstimationError):
        track_positions([0, 1], np.zeros((3, 3)))


def test_track_directions_checks_the_valid_mask_before_using_it():
    """The shape check came after ``valid & isfinite(az)``: a mask of another length raised
    numpy's broadcast ValueError, and a one-element mask was broadcast over every frame."""
    t, az = np.arange(4) * 0.1, np.zeros(4)
    with pytest.raises(EstimationError, match="equal 1-D"):
        track_directions(t, az, valid=[True, False, True])
    with pytest.raises(EstimationError, match="equal 1-D"):
        track_directions(t, az, valid=[False])
    tr = track_directions(t, az, valid=[True, False, True, True])
    assert tr.accepted.tolist() == [True, False, True, True]


def test_motion_fixes_and_covariances_of_the_wrong_shape_are_refused():
    """A two-element fix raised numpy's reshape ValueError from MotionKalman.update, and an R
    that is neither 3x3 nor (n, 3, 3) numpy's broadcast ValueError from track_positions."""
    kf = MotionKalman()
    with pytest.raises(EstimationError, match="x, y, z"):
        kf.update(0.0, [1.0, 2.0])
    with pytest.raises(EstimationError, match="x, y, z"):
        kf.update(0.0, None, candidates=[([1.0, 2.0, 3.0, 4.0], None)])
    assert not kf.initialized
    t, z = np.arange(3) * 0.1, np.zeros((3, 3))
    with pytest.raises(EstimationError, match="3x3"):
        track_positions(t, z, R=np.eye(2))
    with pytest.raises(EstimationError, match="3x3"):
        track_positions(t, z, R=np.stack([np.eye(3)] * 2))
    assert track_positions(t, z, R=np.stack([np.eye(3) * 0.01] * 3)).accepted.all()


def test_singer_decay_damps_acceleration_through_a_gap():
    from hearsee.errors import EstimationError as EE

    t = np.arange(40) * 0.05
    p = np.c_[0.5 * t**2, np.zeros_like(t), np.zeros_like(t)]  # a = 1 m/s^2 along x
    for tau, expect_decay in ((None, False), (0.2, True)):
        kf = MotionKalman(sigma_meas_m=0.01, sigma_jerk=0.5, accel_tau_s=tau)
        for tk, pk in zip(t, p, strict=True):
            kf.update(tk, pk)
        a_before = kf.acceleration[0]
        kf.update(t[-1] + 1.0)  # one second without measurements
        if expect_decay:
            assert kf.acceleration[0] < 0.01 * a_before
        else:
            assert kf.acceleration[0] == pytest.approx(a_before)
    with pytest.raises(EE):
        MotionKalman(accel_tau_s=0.0)


def test_measurement_delay_removes_the_lag_of_old_evidence():
    # measurements show the direction 0.128 s ago (averaged spectra); 20 deg/s walk
    rng = np.random.default_rng(3)
    delay = 0.128
    err = {}
    for d in (0.0, delay):
        kf = DirectionKalman(10.0, 100.0)
        e = []
        for k in range(150):
            t = k * DT
            kf.update(t, (20.0 * (t - delay) + rng.normal(0.0, 3.0), None), delay_s=d)
            e.append(kf.azimuth_deg - 20.0 * t)
        err[d] = np.mean(e[50:])
    assert err[0.0] < -1.5  # lags by ~ 20 deg/s * 0.128 s = 2.6 deg without the model
    assert abs(err[delay]) < 1.0


def test_closed_form_small_inverse_and_scalar_wrap_match_numpy():
    from hearsee.audio.tracking import _inv_small, _wrap1

    rng = np.random.default_rng(7)
    for n in (1, 2, 3):
        A = rng.standard_normal((n, n))
        S = A @ A.T + n * np.eye(n)
        np.testing.assert_allclose(_inv_small(S), np.linalg.inv(S), rtol=1e-12, atol=1e-12)
    for a in [-900.0, -540.0, -180.0, -179.5, 0.0, 179.9, 180.0, 359.0, 540.0, 725.25]:
        assert _wrap1(a) == float(wrap_deg(a))


# ---------------------------------------------------------------------------- IMM
def _run(trk, t, az, el=None, delay=0.0, sigma=None):
    """The track's azimuth per frame; NaN azimuths are frames without a measurement, ``sigma``
    the noise (deg) each measurement declares (None: the tracker's own)."""
    out = np.full(t.size, np.nan)
    for k in range(t.size):
        meas = None if not np.isfinite(az[k]) else (az[k], None if el is None else el[k])
        trk.update(t[k], meas, sigma_meas_deg=sigma if meas else None, delay_s=delay)
        out[k] = trk.azimuth_deg
    return out


def test_imm_with_equal_modes_is_the_single_kalman_filter():
    rng = np.random.default_rng(5)
    t = np.arange(120) * DT
    az = wrap_deg(170 + 25 * t + 3 * rng.standard_normal(t.size))  # crosses +-180
    el = 5 + 3 * rng.standard_normal(t.size)
    az[40:50] = np.nan
    kf = DirectionKalman(sigma_meas_deg=3.0, sigma_accel_dps2=80.0)
    imm = DirectionIMM(sigma_meas_deg=3.0, sigma_accel_dps2=(80.0, 80.0))
    for k in range(t.size):
        meas = None if not np.isfinite(az[k]) else (az[k], el[k])
        assert imm.update(t[k], meas, delay_s=0.02) == kf.update(t[k], meas, delay_s=0.02)
        np.testing.assert_allclose(wrap_deg(imm.x[0] - kf.x[0]), 0.0, atol=1e-9)
        np.testing.assert_allclose(imm.x[1:], kf.x[1:], atol=1e-9)
        np.testing.assert_allclose(imm.P, kf.P, rtol=1e-9, atol=1e-9)


def _textbook_imm(qs, dwell, sigma, t, z, el_ratio):
    """Reference IMM cycle written out per mode with plain numpy (Bar-Shalom, Li &
    Kirubarajan 2001, sec. 11.6.6): mixing, per-mode Kalman prediction and update, mode
    likelihoods, combination. No angle wrapping or gating: the walk stays away from +-180 deg
    and within the gate. The elevation's acceleration noise and initial rate spread are
    ``el_ratio`` times the azimuth's. Returns the combined states (n, 4) and mode
    probabilities (n, m)."""
    from filterpy.common import Q_discrete_white_noise

    m = len(qs)
    H, R = np.eye(2, 4), sigma**2 * np.eye(2)
    x0 = np.array([z[0, 0], z[0, 1], 0.0, 0.0])
    P0 = np.diag([sigma**2, sigma**2, 60.0**2, (60.0 * el_ratio) ** 2])
    xs, Ps, mu = [x0.copy() for _ in qs], [P0.copy() for _ in qs], np.full(m, 1.0 / m)
    out_x, out_mu = [x0], [mu]
    for k in range(1, t.size):
        dt = t[k] - t[k - 1]
        leave = 1.0 - np.exp(-dt / dwell)
        T = np.full((m, m), leave / (m - 1))
        np.fill_diagonal(T, 1.0 - leave)
        c = T.T @ mu
        W = T * mu[:, None] / c[None, :]
        mixed = []
        for j in range(m):
            xm = sum(W[i, j] * xs[i] for i in range(m))
            Pm = sum(W[i, j] * (Ps[i] + np.outer(xs[i] - xm, xs[i] - xm)) for i in range(m))
            mixed.append((xm, Pm))
        F = np.eye(4)
        F[0, 2] = F[1, 3] = dt
        lik = np.empty(m)
        for j, (xm, Pm) in enumerate(mixed):
            q = Q_discrete_white_noise(2, dt, qs[j] ** 2)
            Q = np.zeros((4, 4))
            Q[np.ix_([0, 2], [0, 2])] = q
            Q[np.ix_([1, 3], [1, 3])] = q * el_ratio**2
            xp, Pp = F @ xm, F @ Pm @ F.T + Q
            y = z[k] - H @ xp
            S = H @ Pp @ H.T + R
            K = Pp @ H.T @ np.linalg.inv(S)
            xs[j], Ps[j] = xp + K @ y, (np.eye(4) - K @ H) @ Pp
            lik[j] = (np.exp(-0.5 * y @ np.linalg.solve(S, y))
                      / np.sqrt(np.linalg.det(2 * np.pi * S)))
        mu = c * lik / np.sum(c * lik)
        out_x.append(sum(mu[j] * xs[j] for j in range(m)))
        out_mu.append(mu)
    return np.array(out_x), np.array(out_mu)


def test_imm_with_three_unequal_modes_matches_the_textbook_cycle():
    rng = np.random.default_rng(11)
    t = np.cumsum(rng.uniform(0.02, 0.04, 150))
    rate = np.where(t < 2.5, 30.0, -50.0)  # a turn halfway
    az_true = -40.0 + np.concatenate([[0.0], np.cumsum(rate[:-1] * np.diff(t))])
    z = np.column_stack([az_true + 2.0 * rng.standard_normal(t.size),
                         8.0 + 2.0 * rng.standard_normal(t.size)])
    qs, dwell, sigma = (20.0, 200.0, 1500.0), 0.7, 2.5
    for el_ratio in (ELEVATION_ACCEL_RATIO, 1.0):  # the default, and one model for both angles
        ref_x, ref_mu = _textbook_imm(qs, dwell, sigma, t, z, el_ratio)
        imm = DirectionIMM(sigma, qs, mode_dwell_s=dwell, gate_prob=0.999999,
                           elevation_accel_ratio=el_ratio)
        for k in range(t.size):
            assert imm.update(t[k], (z[k, 0], z[k, 1]))
            np.testing.assert_allclose(imm.x, ref_x[k], rtol=1e-7, atol=1e-7)
            np.testing.assert_allclose(imm.mu, ref_mu[k], rtol=1e-6, atol=1e-9)
    # not a trivial agreement: the quiet mode dominates the straight stretch, the turn not
    assert ref_mu[(t > 1.0) & (t < 2.4), 0].mean() > 0.5 > ref_mu[(t > 2.5) & (t < 3.0), 0].min()


def _turning_walk(seed):
    """A speaker walks past at 40 deg/s, reverses within 0.2 s at t = 4 s and walks back;
    measurements with 3 deg noise every 32 ms. Returns t, truth, measurements, turn, steady."""
    rng = np.random.default_rng(seed)
    t = np.arange(250) * DT
    rate = np.where(t < 4.0, 40.0, -40.0)
    ramp = (t > 3.9) & (t < 4.1)
    rate[ramp] = 40.0 - 400.0 * (t[ramp] - 3.9)  # 40 -> -40 deg/s in 0.2 s
    az_true = -80.0 + np.concatenate([[0.0], np.cumsum(rate[:-1]) * DT])
    az = az_true + 3.0 * rng.standard_normal(t.size)
    return t, az_true, az, (t > 4.0) & (t < 4.6), (t > 1.0) & (t < 3.7)


def test_imm_follows_a_turn_faster_than_the_quiet_filter_and_smooths_more_than_the_agile_one():
    """Pooled over 8 walks (one walk's turn error varies ~2x with the noise draw)."""
    se = {k: {"turn": [], "steady": []} for k in ("quiet", "agile", "imm")}
    for seed in range(8):
        t, az_true, az, turn, steady = _turning_walk(seed)
        for key, trk in (("quiet", DirectionKalman(3.0, 30.0)),
                         ("agile", DirectionKalman(3.0, 1500.0)),
                         ("imm", DirectionIMM(3.0, (30.0, 1500.0), mode_dwell_s=2.0))):
            e = _err(_run(trk, t, az), az_true)
            se[key]["turn"].append(e[turn] ** 2)
            se[key]["steady"].append(e[steady] ** 2)
    rms = {k: {m: float(np.sqrt(np.mean(np.concatenate(v[m])))) for m in v}
           for k, v in se.items()}
    assert rms["imm"]["turn"] < 0.6 * rms["quiet"]["turn"]  # the quiet filter overshoots turns
    assert rms["imm"]["steady"] < 0.75 * rms["agile"]["steady"]  # the agile one passes noise on
    assert rms["imm"]["steady"] < 1.8  # measurements: 3 deg


def test_imm_mode_probabilities_say_which_motion_it_sees():
    mu_steady, mu_turn_min = [], []
    for seed in range(8):
        t, az_true, az, turn, steady = _turning_walk(seed)
        imm = DirectionIMM(3.0, (30.0, 1500.0), mode_dwell_s=2.0)
        mu_quiet = np.empty(t.size)
        for k in range(t.size):
            imm.update(t[k], (az[k], None))
            mu_quiet[k] = imm.mu[0]
            assert imm.mu.sum() == pytest.approx(1.0)
        mu_steady.append(mu_quiet[steady].mean())
        mu_turn_min.append(mu_quiet[turn].min())
    assert np.mean(mu_steady) > 0.8  # a steady walk: the quiet mode explains it
    assert np.mean(mu_turn_min) < 0.4  # the turn: the agile mode takes over


def _sparse_turn(seed: int, every: int, sigma_true: float):
    """A talker turning back at 2 s (+-30 deg/s, 32 ms frames) measured every ``every``-th
    frame with ``sigma_true`` deg of noise: (t, truth, measurement or NaN)."""
    rng = np.random.default_rng(seed)
    t = np.arange(125) * 0.032
    truth = np.where(t < 2.0, 30.0 * t, 60.0 - 30.0 * (t - 2.0))
    meas = np.full(t.size, np.nan)
    k = np.arange(rng.integers(every), t.size, every)
    meas[k] = truth[k] + rng.normal(0.0, sigma_true, k.size)
    return t, truth, meas


def test_imm_angle_random_walk_follows_sparse_measurements_closer():
    """Sparse measurements (every 8th frame) that declare 25 deg of noise but hold 4 deg, as a
    voice's at 10 dB do: the azimuth random walk (angle_noise_ratio) lets them move the
    azimuth more, so the track trails the turn less; dense precise measurements (white noise:
    every frame, 2 deg declared and held) it leaves nearly alone."""
    err = {0.0: [], 8.0: []}
    for seed in range(8):
        t, truth, meas = _sparse_turn(seed, 8, 4.0)
        after = (t > 2.0) & (t < 3.0) & ~np.isnan(meas)
        for ratio in err:
            est = _run(DirectionIMM(angle_noise_ratio=ratio), t, meas, sigma=25.0)
            err[ratio].append(wrap_deg(est - truth)[after])
    rms = {r: float(np.sqrt(np.mean(np.concatenate(v) ** 2))) for r, v in err.items()}
    # after the turn the truth falls: a positive error is the track trailing it
    trail = {r: float(np.mean(np.concatenate(v))) for r, v in err.items()}
    assert trail[0.0] > 2.0 and trail[8.0] < 0.7 * trail[0.0]  # 2.95 -> 1.78 deg
    assert rms[8.0] < rms[0.0]
    t, truth, meas = _sparse_turn(0, 1, 2.0)
    a = _run(DirectionIMM(), t, meas, sigma=2.0)
    b = _run(DirectionIMM(angle_noise_ratio=8.0), t, meas, sigma=2.0)
    rmse_a, rmse_b = (float(np.sqrt(np.mean(wrap_deg(x - truth)[10:] ** 2))) for x in (a, b))
    assert rmse_b < 1.1 * rmse_a  # and well below the 2 deg of one measurement
    assert rmse_b < 1.5
    for bad in (-1.0, np.nan, np.inf, "8"):
        with pytest.raises(EstimationError, match="angle_noise_ratio"):
            DirectionIMM(angle_noise_ratio=bad)


def test_imm_rejects_bad_parameters_and_time_going_backwards():
    with pytest.raises(EstimationError):
        DirectionIMM(sigma_accel_dps2=(100.0,))
    with pytest.raises(EstimationError):
        DirectionIMM(mode_dwell_s=0.0)
    with pytest.raises(EstimationError):
        DirectionIMM(sigma_accel_dps2=(100.0, -1.0))
    imm = DirectionIMM()
    assert not imm.update(0.0, None) and not imm.initialized
    assert imm.update(0.1, (30.0, None)) and imm.azimuth_deg == pytest.approx(30.0)
    assert np.isnan(imm.elevation_deg)
    with pytest.raises(EstimationError):
        imm.update(0.05, (30.0, None))


@pytest.mark.parametrize("cls", [DirectionKalman, DirectionIMM])
def test_nan_times_and_noises_are_refused_and_leave_the_track_intact(cls):
    """A NaN time passed the "time went backwards" test (the IMM's state became NaN for good,
    the single filter skipped a prediction: rate -11.6 instead of ~270 deg/s), and a NaN or
    infinite noise or delay turned the state NaN; all are EstimationErrors now, and the track
    goes on as if the bad call had not happened."""
    kf, ref = cls(), cls()
    for k in range(4):
        kf.update(k * DT, (10.0 + 8.6 * k, 0.0))
        ref.update(k * DT, (10.0 + 8.6 * k, 0.0))
    nan, inf = float("nan"), float("inf")
    # (and, from an audit: a delay of 1e200 s or a noise of 1e-170 deg -- whose square is 0 --
    # turned the state NaN while update answered True; a negative delay passed)
    for bad, words in (({"t": nan}, "finite number"), ({"t": inf}, "finite number"),
                       ({"sigma_meas_deg": nan}, "finite number"),
                       ({"sigma_meas_deg": inf}, "finite number"),
                       ({"sigma_meas_deg": 0.0}, "finite number"),
                       ({"sigma_meas_deg": 1e-170}, r"in \[1e-06, 1e\+06\]"),
                       ({"sigma_meas_deg": (2.0, -1.0)}, "finite number"),
                       ({"delay_s": nan}, "from 0 to 60"), ({"delay_s": inf}, "from 0 to 60"),
                       ({"delay_s": 1e200}, "from 0 to 60"), ({"delay_s": -5.0}, "from 0 to 60")):
        args = {"t": 4 * DT, **bad}
        with pytest.raises(EstimationError, match=words):
            kf.update(args.pop("t"), (44.4, 0.0), **args)
    for k in range(4, 8):
        kf.update(k * DT, (10.0 + 8.6 * k, 0.0))
        ref.update(k * DT, (10.0 + 8.6 * k, 0.0))
    assert np.isfinite(kf.azimuth_deg) and kf.azimuth_deg == pytest.approx(ref.azimuth_deg)


@pytest.mark.parametrize("kw", [{"sigma_meas_deg": float("inf")},
                                {"sigma_accel_dps2": float("inf")},
                                {"elevation_accel_ratio": float("inf")},
                                {"init_rate_sigma_dps": float("nan")},
                                {"init_rate_sigma_dps": 0.0},
                                {"sigma_meas_deg": 1e200}, {"sigma_accel_dps2": 1e300},
                                {"init_rate_sigma_dps": 1e-170}])
def test_infinite_or_nan_settings_are_refused(kw):
    """``> 0`` let inf through (and init_rate_sigma_dps was not checked): each gave NaN
    directions; 1e200 overflowed (OverflowError) and 1e-170 underflowed to a zero variance."""
    words = r"must be a finite number in \[1e-06, 1e\+06\]"
    with pytest.raises(EstimationError, match=words):
        DirectionKalman(**kw)
    if "sigma_accel_dps2" not in kw:
        with pytest.raises(EstimationError, match=words):
            DirectionIMM(**kw)
    for q in (float("inf"), 1e300):
        with pytest.raises(EstimationError, match="must be a number from 1e-06 to 1e"):
            DirectionIMM(sigma_accel_dps2=(50.0, q))


@pytest.mark.parametrize("make", [lambda: DirectionKalman(2.0, 150.0, elevation_accel_ratio=1.0),
                                  lambda: DirectionIMM(2.0, elevation_accel_ratio=1.0)])
def test_coasting_never_carries_the_elevation_over_the_pole(make):
    """A track rising at 100 deg/s up to 80 deg, then silent for 2 s: the prediction stops at
    +90 deg with the elevation rate stopped (it once reported several hundred deg)."""
    trk = make()
    t = np.arange(0.0, 0.8, 0.032)
    for tk in t:
        assert trk.update(tk, (30.0, 100.0 * tk))
    assert trk.rate_dps[1] > 50.0
    for tk in np.arange(t[-1] + 0.032, t[-1] + 2.0, 0.032):
        trk.update(tk, None)
        assert -90.0 <= trk.elevation_deg <= 90.0
    assert trk.elevation_deg == 90.0 and trk.rate_dps[1] == 0.0
    assert trk.azimuth_deg == pytest.approx(30.0, abs=1.0)  # the azimuth was steady


@pytest.mark.parametrize("cls", [DirectionKalman, DirectionIMM])
def test_a_bounded_angle_coasts_to_its_bound_and_stops(cls):
    """angle_bound_deg=90 (a linear array's sines from broadside times 90): a track moving
    at 60 deg/s up to 66 deg, then silent for 1.5 s, stops at +90 with its rate stopped
    (unbounded it coasts on to ~156, and past +180 it would wrap to the other endfire); a
    later frame at 70 deg is fused from there; a turn of the array is refused."""
    free, trk = cls(2.0), cls(2.0, angle_bound_deg=90.0)
    t = np.arange(0.0, 1.1, DT)
    for f in (free, trk):
        for tk in t:
            assert f.update(tk, (60.0 * tk, None))
    assert trk.rate_dps[0] > 40.0
    for tk in np.arange(t[-1] + DT, t[-1] + 1.5, DT):
        trk.update(tk, None)
        free.update(tk, None)
        x, _ = trk.predicted(tk + 0.5)
        assert -90.0 <= trk.azimuth_deg <= 90.0 and -90.0 <= x[0] <= 90.0
    assert free.azimuth_deg > 140.0
    assert trk.azimuth_deg == 90.0 and trk.rate_dps[0] == 0.0
    assert trk.update(t[-1] + 1.5 + DT, (70.0, None))
    assert 70.0 < trk.azimuth_deg < 90.0
    with pytest.raises(EstimationError, match="no azimuth"):
        trk.rotate_azimuth(10.0)
    for bad in (0.0, -5.0, 181.0, float("nan")):
        with pytest.raises(EstimationError, match="angle_bound_deg"):
            cls(2.0, angle_bound_deg=bad)


@pytest.mark.parametrize("cls", [DirectionKalman, DirectionIMM])
def test_a_bounded_angle_predicted_over_one_long_step_stays_at_its_bound(cls):
    """angle_bound_deg=90: a track at 77 deg moving at 40 deg/s, predicted 3 s ahead in one
    step (a prediction to a later frame, or the next update after a silent gap, which the
    stepped coasting above never takes), reaches 197 deg before its bound: it was wrapped
    first, to -163, and clamped to the far endfire, -90, its rate +40 kept -- the filter
    then rejected the talker at 88 deg (the side it went to). Now it stops at +90, rate 0,
    and the measurement at 88 is fused; a measurement at the far endfire from a track at
    the near one is an innovation of -180 deg (it was wrapped to +180)."""
    kw = ({"sigma_accel_dps2": 5.0} if cls is DirectionKalman
          else {"sigma_accel_dps2": (5.0, 20.0)})
    trk = cls(1.0, angle_bound_deg=90.0, **kw)
    t = np.arange(30) * DT
    for tk in t:
        assert trk.update(tk, (40.0 + 40.0 * tk, None))
    assert trk.azimuth_deg == pytest.approx(77.1, abs=0.2)
    assert trk.rate_dps[0] == pytest.approx(40.0, abs=0.5)
    x, _ = trk.predicted(t[-1] + 3.0)
    assert x[0] == 90.0 and x[2] == 0.0
    assert trk.update(t[-1] + 3.0, (88.0, None))
    assert trk.azimuth_deg == pytest.approx(88.0, abs=0.5)
    assert abs(trk.rate_dps[0]) < 5.0
    edge = cls(5.0, angle_bound_deg=90.0, init_rate_sigma_dps=60.0)
    edge.update(0.0, (90.0, None))
    for tk in (0.5, 1.0, 1.5):
        edge.update(tk, (-90.0, None))
        assert edge.azimuth_deg in (90.0, -90.0) or edge.rate_dps[0] < 0.0
    assert edge.azimuth_deg < -80.0 and edge.rate_dps[0] <= 0.0


@pytest.mark.parametrize("cls", [DirectionKalman, DirectionIMM])
@pytest.mark.parametrize("tau", [None, float("inf"), 0.8, 1e9])
def test_rate_relaxes_with_rate_tau_through_a_gap(cls, tau):
    """Track a speaker turning at 20 deg/s (elevation rising 2 deg/s), then 1.2 s without a
    measurement: with rate_tau_s the rates decay as exp(-T/tau) and the azimuth advances by
    rate tau (1 - exp(-T/tau)) (the IMM's mixture too: its modes share the transition);
    without, the constant-velocity coast rate T."""
    trk = cls(2.0, rate_tau_s=tau)
    t = np.arange(0.0, 1.0, DT)
    for tk in t:
        assert trk.update(tk, (-40.0 + 20.0 * tk, 10.0 + 2.0 * tk))
    x0 = trk.x.copy()
    assert 12.0 < x0[2] < 24.0 and x0[3] > 0.0  # (the relaxing model reads the rate low)
    gap = np.arange(1, 38) * DT  # 1.18 s of predictions, one per hop
    for g in gap:
        assert not trk.update(t[-1] + g, None)
    T = gap[-1]
    decay, advance = ((1.0, T) if tau is None or np.isinf(tau) else
                      (np.exp(-T / tau), -tau * np.expm1(-T / tau)))
    np.testing.assert_allclose(trk.rate_dps, x0[2:] * decay, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose([trk.azimuth_deg, trk.elevation_deg], x0[:2] + x0[2:] * advance,
                               rtol=1e-9, atol=1e-9)


def test_rate_tau_must_be_positive():
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(EstimationError, match="rate_tau_s"):
            DirectionKalman(rate_tau_s=bad)
        with pytest.raises(EstimationError, match="rate_tau_s"):
            DirectionIMM(rate_tau_s=bad)


@pytest.mark.parametrize("cls", [DirectionKalman, DirectionIMM])
@pytest.mark.parametrize("tau", [None, 2.0])
def test_predicted_is_the_next_coasting_update_without_changing_the_tracker(cls, tau):
    """``predicted(t)`` gives the state and covariance a measurement-free update to ``t`` would
    leave (the tracker's own model: relaxing rate, process noise, the IMM's mode mixing) and
    leaves the tracker as it was; at or before its last time it gives the current state."""
    trk = cls(2.0, rate_tau_s=tau)
    with pytest.raises(EstimationError, match="no track"):
        trk.predicted(0.0)
    t = np.arange(0.0, 1.0, DT)
    for tk in t:
        trk.update(tk, (170.0 + 30.0 * tk, 5.0))  # crosses the 180 deg seam at t = 1/3 s
    x0, P0 = trk.x.copy(), trk.P.copy()
    xs, Ps = trk.predicted(t[-1])
    np.testing.assert_array_equal(xs, x0)
    np.testing.assert_array_equal(Ps, P0)
    for dt in (DT, 0.4):
        xp, Pp = trk.predicted(t[-1] + dt)
        np.testing.assert_array_equal(trk.x, x0)  # nothing moved
        np.testing.assert_array_equal(trk.P, P0)
        assert trk.t == pytest.approx(t[-1])
        # the rate carried the azimuth on, and the uncertainty grew with the gap
        assert 0.0 < wrap_deg(xp[0] - x0[0]) <= 30.0 * dt * 1.05
        assert Pp[0, 0] > P0[0, 0]
        ref = cls(2.0, rate_tau_s=tau)
        for tk in t:
            ref.update(tk, (170.0 + 30.0 * tk, 5.0))
        assert not ref.update(t[-1] + dt, None)
        np.testing.assert_allclose(xp, ref.x, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(Pp, ref.P, rtol=1e-12, atol=1e-9)


def test_trackers_per_step_caches_stay_bounded_under_clock_jitter():
    """Every step length got its own cache entry for good: a wall clock's jitter (a new dt each
    frame) grew the caches by one entry per frame. They are bounded now, and the estimates are
    those of an uncached model."""
    from hearsee.audio import tracking as trk

    rng = np.random.default_rng(3)
    t = np.cumsum(0.032 + rng.uniform(-1e-4, 1e-4, 500))
    kf, imm, mk = DirectionKalman(), DirectionIMM(), MotionKalman()
    for k, tk in enumerate(t):
        kf.update(tk, (10.0 + 0.5 * k, None))
        imm.update(tk, (10.0 + 0.5 * k, None))
        mk.update(tk, [1.0 + 0.01 * k, 0.0, 0.0])
    for cache in (kf._model_cache, imm._model_cache, imm._tpm_cache, mk._model_cache):
        assert 0 < len(cache) <= trk._CACHE_SIZE
    ref = DirectionKalman()
    for k, tk in enumerate(t):
        ref._model_cache.clear()
        ref.update(tk, (10.0 + 0.5 * k, None))
    np.testing.assert_allclose(kf.x, ref.x)


def test_direction_trackers_refuse_impossible_times_elevations_and_settings():
    """predicted(nan) returned the current state silently (update refuses a NaN time); a first
    measurement at 120 deg elevation started the track there (later corrections clip to +-90);
    a single acceleration noise for the IMM raised a TypeError, a NaN max_rejects a ValueError."""
    for f in (DirectionKalman(), DirectionIMM()):
        f.update(0.0, (30.0, 10.0))
        with pytest.raises(EstimationError, match="time"):
            f.predicted(np.nan)
        with pytest.raises(EstimationError, match="elevation"):
            f.update(0.1, (30.0, 120.0))
        f.update(0.2, (31.0, 90.0))  # the pole itself is a direction (the gate may reject it)
        assert f.update(0.3, (31.5, 10.5))
    with pytest.raises(EstimationError, match="one angular acceleration noise per mode"):
        DirectionIMM(sigma_accel_dps2=5.0)
    for bad in (np.nan, 1.5, 0):
        with pytest.raises(EstimationError, match="max_rejects"):
            DirectionKalman(max_rejects=bad)


@pytest.mark.parametrize("cls", [DirectionKalman, DirectionIMM])
def test_direction_measurements_must_be_pairs_of_angles(cls):
    """Bad-input sweep of the public API: update() with three numbers raised a builtin
    ValueError ('too many values to unpack'), text a TypeError, a bool elevation was read as
    1 deg; sigma_meas_deg of three numbers raised numpy's broadcast ValueError."""
    k = cls()
    assert k.update(0.0, (10.0, 5.0))
    for bad in ((1.0, 2.0, 3.0), "ab", (10.0, True), ("10", 5.0), 7.0):
        with pytest.raises(EstimationError, match="direction measurement"):
            k.update(0.1, bad)
    with pytest.raises(EstimationError, match="direction measurement"):
        k.update(0.1, None, candidates=[(10.0,)])
    with pytest.raises(EstimationError, match="sigma_meas_deg"):
        k.update(0.1, (10.0, 5.0), sigma_meas_deg=(1.0, 2.0, 3.0))
    # a missing angle (NaN) and a per-angle noise still work: the track holds 10 deg
    assert not k.update(0.2, (np.nan, 5.0))
    assert k.update(0.3, (10.0, 5.0), sigma_meas_deg=(2.0, 4.0))
    assert k.x[0] == pytest.approx(10.0, abs=1e-6)


@pytest.mark.parametrize("cls, meas", [(DirectionKalman, (10.0, 5.0)),
                                       (DirectionIMM, (10.0, 5.0)),
                                       (MotionKalman, [1.0, 0.0, 0.0])])
def test_a_time_jump_beyond_any_run_is_refused(cls, meas):
    """A step of 1e300 s overflowed the process noise into filterpy's builtin OverflowError (the
    IMM's mixing went NaN from ~1e40 s). Steps up to 1e9 s (31.7 years) are steps; Unix-epoch
    times are fine."""
    k = cls()
    k.update(1.7e9, meas)
    assert k.update(1.7e9 + 0.1, meas)
    with pytest.raises(EstimationError, match="jumped"):
        k.update(1e300, meas)
    if cls is not MotionKalman:
        with pytest.raises(EstimationError, match="jumped"):
            k.predicted(1e300)
    assert k.update(1.7e9 + 0.2, meas)


@pytest.mark.parametrize("cls, meas", [(DirectionKalman, (10.0, 5.0)),
                                       (DirectionIMM, (10.0, 5.0)),
                                       (MotionKalman, [1.0, 0.0, 0.0])])
def test_tracker_times_must_be_real_numbers(cls, meas):
    """float() read the text "1.0" and True as 1 s (a track stepped to t = 1.0 without a word)
    and None raised a builtin TypeError; each is an EstimationError now, the track untouched.
    Numbers of any real type still are times: an int, numpy's float32 and a 0-d array."""
    k = cls()
    assert k.update(0.5, meas)
    before = (k.t, k.x.copy())
    for bad in ("1.0", True, None, [1.0], 1 + 0j):
        with pytest.raises(EstimationError, match="time must be a finite number of seconds"):
            k.update(bad, meas)
        assert k.t == before[0]
        np.testing.assert_array_equal(k.x, before[1])
        if cls is MotionKalman:
            with pytest.raises(EstimationError, match="time"):
                k.predicted_to(bad)
        else:
            with pytest.raises(EstimationError, match="time"):
                k.predicted(bad)
    for good in (1, np.float32(1.5), np.array(2.0)):
        k.update(good, meas)
        assert type(k.t) is float and k.t == float(good)


def test_gate_distance_needs_a_track():
    """gate_distance before any measurement measured from the initial zeros (0.003 for a
    candidate at 10 deg) as if there were a prediction."""
    k = DirectionKalman()
    with pytest.raises(EstimationError, match="no track"):
        k.gate_distance(10.0, 0.0)
    k.update(0.0, (10.0, 0.0))
    assert k.gate_distance(10.0, 0.0) == pytest.approx(0.0, abs=1e-12)


def test_track_directions_refuses_arrays_that_are_not_numbers():
    """Text angles were read as numbers (["10", "20"] tracked as 10 and 20 deg, True as 1 deg),
    a text mask as all True, and "a", a complex number or a ragged list raised numpy's builtin
    ValueError / TypeError. Now an EstimationError naming the array; numbers, NaN and None
    (missing frames) and 0/1 masks are tracked as before."""
    t, az = [0.0, 0.1, 0.2], [10.0, 20.0, 30.0]
    for kwargs, name in (
        (dict(azimuth_deg=["10", "20", "30"]), "azimuth_deg"),
        (dict(azimuth_deg=["a", "b", "c"]), "azimuth_deg"),
        (dict(azimuth_deg=[True, False, True]), "azimuth_deg"),
        (dict(azimuth_deg=[1 + 1j, 2.0, 3.0]), "azimuth_deg"),
        (dict(azimuth_deg=[10.0, [1.0, 2.0], 3.0]), "azimuth_deg"),
        (dict(azimuth_deg=az, elevation_deg=["1", "2", "3"]), "elevation_deg"),
        (dict(t=["0", "0.1", "0.2"], azimuth_deg=az), "t"),
        (dict(azimuth_deg=az, valid=["x", "", "y"]), "valid"),
        # (a mask of other numbers -- 2, 1.0 -- is no 0/1 mask: _flags' `and` made `or`, which
        # took both as True, passed this test)
        (dict(azimuth_deg=az, valid=[2, 1, 0]), "valid"),
        (dict(azimuth_deg=az, valid=[1.0, 0.0, 1.0]), "valid"),
    ):
        with pytest.raises(EstimationError, match=f"^{name} must hold"):
            track_directions(**{"t": t, **kwargs})
    ref = track_directions(t, [10.0, np.nan, 30.0], valid=[True, True, False])
    same = track_directions(np.array(t), [10, None, 30], valid=[1, 1, 0])
    assert np.array_equal(ref.azimuth_deg, same.azimuth_deg)
    assert ref.accepted.tolist() == same.accepted.tolist() == [True, False, False]


def test_track_positions_refuses_arrays_that_are_not_numbers():
    """track_directions' rule for track_positions: text fixes, times or covariances were read
    as numbers ("1" as 1 m) and True as 1 m. Now an EstimationError naming the array; NaN and
    None entries still mark a missing fix."""
    t = [0.0, 0.1, 0.2]
    fixes = [[1.0, 2.0, 3.0], [1.1, 2.0, 3.0], [1.2, 2.0, 3.0]]
    for kwargs, name in ((dict(positions=[["1", "2", "3"]] * 3), "positions"),
                         (dict(positions=[[1.0, 2.0, 3.0], [True, 2.0, 3.0], fixes[2]]),
                          "positions"),
                         (dict(t=["0", "0.1", "0.2"], positions=fixes), "t"),
                         (dict(positions=fixes, R=[["1", 0, 0], [0, 1, 0], [0, 0, 1]]), "R")):
        with pytest.raises(EstimationError, match=f"^{name} must hold real numbers"):
            track_positions(**{"t": t, **kwargs})
    ref = track_positions(t, [fixes[0], [np.nan] * 3, fixes[2]])
    same = track_positions(t, [fixes[0], [None] * 3, fixes[2]])
    assert ref.accepted.tolist() == same.accepted.tolist() == [True, False, True]
    assert np.array_equal(ref.position, same.position)


def test_an_azimuth_beyond_any_turn_count_is_refused():
    """track_directions took an azimuth of 1e300 deg as -170.5 deg (its float wrap) and the
    track followed it; gate_distance gave 648 for it, NaN for a NaN azimuth and numpy's builtin
    error for text. Now azimuths beyond MAX_AZIMUTH_DEG (1e9 deg) are an EstimationError;
    non-finite angles stay missing frames (NaN, inf: the elevation's rule), and unwrapped
    azimuths of many turns are tracked as their wrap, as before."""
    from hearsee.audio.tracking import MAX_AZIMUTH_DEG

    t = np.arange(3) * DT
    for big in (1e300, -1e10, np.nextafter(MAX_AZIMUTH_DEG, np.inf)):
        with pytest.raises(EstimationError, match=r"^azimuth must be within \+-1e\+09 deg"):
            track_directions(t, [10.0, big, 12.0])
        for cls in (DirectionKalman, DirectionIMM):
            k = cls()
            with pytest.raises(EstimationError, match="azimuth must be within"):
                k.update(0.0, (big, None))
            k.update(0.0, (10.0, None))
            with pytest.raises(EstimationError, match="azimuth must be within"):
                k.update(DT, (11.0, None), candidates=[(big, None)])
    turns = 360.0 * 1e6  # a million turns: the same directions
    a = track_directions(t, [10.0, 11.0, 12.0])
    b = track_directions(t, [10.0 + turns, 11.0 - turns, 12.0 + turns])
    np.testing.assert_allclose(b.azimuth_deg, a.azimuth_deg, atol=1e-6)
    for missing in (np.nan, np.inf, -np.inf):
        tr = track_directions(t, [10.0, missing, 12.0])
        assert tr.accepted.tolist() == [True, False, True]
    k = DirectionKalman()
    k.update(0.0, (10.0, 0.0))
    for bad, msg in ((1e300, "azimuth must be within"), (np.nan, "needs a finite azimuth"),
                     ("10", "is \\(azimuth_deg"), (True, "is \\(azimuth_deg")):
        with pytest.raises(EstimationError, match=msg):
            k.gate_distance(bad, 0.0)
    assert k.gate_distance(10.0, np.nan) == k.gate_distance(10.0)


def test_motion_fixes_and_covariances_must_be_numbers():
    """MotionKalman.update read a fix ["1", "2", "3"] as (1, 2, 3) m and a covariance of text
    ("1" as 1 m^2) or bools as numbers. Now an EstimationError; the same numbers fuse as
    before."""
    k = MotionKalman()
    with pytest.raises(EstimationError, match="a position fix must be"):
        k.update(0.0, ["1", "2", "3"])
    with pytest.raises(EstimationError, match="a position fix must be"):
        k.update(0.0, None, candidates=[([True, 2.0, 3.0], None)])
    R = np.eye(3) * 0.01
    for bad in (R.astype(str), np.eye(3, dtype=bool), [["0.01", 0, 0], [0, 0.01, 0], [0, 0, 0.01]]):
        with pytest.raises(EstimationError, match="covariance must hold real numbers"):
            k.update(0.0, [1.0, 2.0, 3.0], bad)
    a, b = MotionKalman(), MotionKalman()
    for j, p in enumerate(([1.0, 2.0, 3.0], [1.1, 2.0, 3.0])):
        a.update(j * DT, p, R)
        b.update(j * DT, np.array(p), R.tolist())
    np.testing.assert_array_equal(a.x, b.x)


def test_motion_filter_predicted_to_leaves_the_track_alone():
    kf = MotionKalman(sigma_meas_m=0.01, sigma_jerk=0.5)
    for k in range(30):  # 1 m/s along x, exact fixes every 0.1 s
        kf.update(0.1 * k, [0.1 * k, 2.0, 1.0])
    x0, P0, t0 = kf.x.copy(), kf.P.copy(), kf.t
    ahead = kf.predicted_to(t0 + 0.5)
    np.testing.assert_allclose(ahead.position, [t0 + 0.5, 2.0, 1.0], atol=0.01)
    assert ahead.t == pytest.approx(t0 + 0.5) and np.trace(ahead.P) > np.trace(P0)
    assert kf.t == t0 and np.array_equal(kf.x, x0) and np.array_equal(kf.P, P0)
    np.testing.assert_array_equal(kf.predicted_to(t0 - 1.0).x, x0)  # the past: as it is
    assert not MotionKalman().predicted_to(1.0).initialized


@pytest.mark.parametrize("cls", [DirectionKalman, DirectionIMM])
def test_a_track_starts_with_the_noise_its_first_measurement_declares(cls):
    """A start (and a restart after max_rejects) took the filter's default sigma_meas_deg (10
    deg here) as the angles' initial sd whatever the frame declared: the stream's planar frames
    declare (s, 4 s). Ground truth: measurements of one direction at one time fuse to their
    inverse-variance weighted mean, with variance 1 / sum(1 / s^2) per angle."""
    k = cls(10.0)
    assert k.update(0.0, (30.0, 20.0), sigma_meas_deg=(25.0, 100.0))
    assert np.diag(k.P)[:2] == pytest.approx([25.0**2, 100.0**2], rel=1e-12)
    zs = [((30.0, 20.0), (25.0, 100.0)), ((36.0, 10.0), (5.0, 20.0)), ((33.0, 40.0), 8.0)]
    k = cls(10.0)
    for z, s in zs:
        assert k.update(0.0, z, sigma_meas_deg=s)
    for i in range(2):
        w = np.array([1.0 / np.broadcast_to(s, 2)[i] ** 2 for _, s in zs])
        v = np.array([z[i] for z, _ in zs])
        assert k.x[i] == pytest.approx(np.sum(w * v) / np.sum(w), abs=1e-9)
        assert k.P[i, i] == pytest.approx(1.0 / np.sum(w), rel=1e-9)
    # an azimuth-only start: the elevation stays unknown (90 deg sd)
    k = cls(10.0)
    assert k.update(0.0, (30.0, None), sigma_meas_deg=2.0)
    assert np.diag(k.P)[:2] == pytest.approx([4.0, 90.0**2], rel=1e-12)
    # the restart after max_rejects takes the restarting frame's noise too
    k = cls(10.0, max_rejects=2)
    for n in range(10):
        k.update(n * DT, (30.0, 20.0), sigma_meas_deg=2.0)
    for n in range(10, 12):
        assert k.update(n * DT, (-120.0, 0.0), sigma_meas_deg=(40.0, 160.0)) == (n == 11)
    assert k.x[:2] == pytest.approx([-120.0, 0.0])
    assert np.diag(k.P)[:2] == pytest.approx([40.0**2, 160.0**2], rel=1e-12)


@pytest.mark.parametrize("cls", [DirectionKalman, DirectionIMM])
@pytest.mark.parametrize("kw", [{"sigma_meas_deg": -1.0}, {"sigma_meas_deg": "abc"},
                                {"sigma_meas_deg": (1.0, np.nan)}, {"delay_s": np.nan}])
def test_the_first_frame_noise_and_delay_are_checked_as_later_ones(cls, kw):
    """The first frame started the track before its sigma_meas_deg / delay_s were checked (a
    negative or text noise and a NaN delay were taken); the second frame refused them."""
    k = cls()
    with pytest.raises(EstimationError, match="sigma_meas_deg|delay_s"):
        k.update(0.0, (10.0, 5.0), **kw)
    assert not k.initialized
    assert k.update(0.0, (10.0, 5.0))
    with pytest.raises(EstimationError, match="sigma_meas_deg|delay_s"):
        k.update(0.1, (10.0, 5.0), **kw)


def test_singer_prediction_does_not_depend_on_how_a_gap_is_stepped():
    """With accel_tau_s only the acceleration decayed: position and velocity integrated it as
    if it stayed constant over the step, so one step over a 1 s gap (predicted_to, or a time
    jump in track_positions) moved the velocity by a dt = 1.65 m/s where 31 small steps gave
    0.74 m/s. Ground truth: Singer's mean propagation, p + v dt + a tau^2 (r - 1 + e^-r),
    v + a tau (1 - e^-r), a e^-r with r = dt / tau (Bar-Shalom et al. 2001, sec. 8.2); the
    process noise's increment goes through the same gains (the constant-acceleration ones fed
    a 1.3 s step 2.6 m/s of velocity noise: a robot track's velocity never became known)."""
    tau = 0.5
    t = np.arange(20) * 0.05
    p = np.c_[0.5 * 1.5 * t**2 + 0.3 * t, 0.2 * t, -0.25 * t**2]  # a = (1.5, 0, -0.5) m/s^2
    kf = MotionKalman(sigma_meas_m=0.01, sigma_jerk=0.5, accel_tau_s=tau)
    for tk, pk in zip(t, p, strict=True):
        kf.update(tk, pk)
    x0, v0, a0 = kf.position, kf.velocity, kf.acceleration
    assert np.all(np.abs(a0[[0, 2]]) > 0.3)  # a fitted acceleration to carry through the gap
    gap = 1.0
    one = kf.predicted_to(t[-1] + gap)
    many = copy.deepcopy(kf)
    rng = np.random.default_rng(3)
    cuts = np.sort(rng.uniform(0.0, gap, 40))  # an irregular partition of the gap
    for c in (*cuts, gap):
        many.update(t[-1] + c)
    e = np.exp(-gap / tau)
    expect = (x0 + v0 * gap + a0 * tau**2 * (gap / tau - 1 + e), v0 + a0 * tau * (1 - e), a0 * e)
    for got in (one, many):
        for value, want in zip((got.position, got.velocity, got.acceleration), expect,
                               strict=True):
            assert value == pytest.approx(want, rel=1e-9, abs=1e-12)
    # the per-step acceleration increment (sd sigma_jerk) is carried by the same gains:
    # Q = sigma^2 g g^T per axis, g = (tau^2 (r - 1 + e^-r), tau (1 - e^-r), e^-r)
    dt = 0.3
    r = dt / tau
    g = np.array([tau**2 * (r - 1 + np.exp(-r)), tau * (1 - np.exp(-r)), np.exp(-r)])
    F, Q = kf._model(dt)
    assert F[:3, :3] == pytest.approx(np.array([[1, dt, g[0]], [0, 1, g[1]], [0, 0, g[2]]]),
                                      rel=1e-12)
    assert Q[:3, :3] == pytest.approx(0.5**2 * np.outer(g, g), rel=1e-12)
    # without accel_tau_s the model stays constant acceleration
    ca = MotionKalman(sigma_meas_m=0.01, sigma_jerk=0.5)
    for tk, pk in zip(t, p, strict=True):
        ca.update(tk, pk)
    x0, v0, a0 = ca.position, ca.velocity, ca.acceleration
    ca.update(t[-1] + gap)
    assert ca.position == pytest.approx(x0 + v0 * gap + 0.5 * a0 * gap**2, rel=1e-12)
    assert ca.velocity == pytest.approx(v0 + a0 * gap, rel=1e-12)


@pytest.mark.parametrize("cls", [DirectionKalman, DirectionIMM])
@pytest.mark.parametrize("gap", [1e7, 1e8, 9.9e8])
def test_a_gap_that_loses_the_direction_restarts_the_track(cls, gap):
    """Time gaps up to 1e9 s are steps, but after ~1e7 s the predicted covariance (~1e40
    deg^2) and the measurement's cancelled in the Joseph update: a negative azimuth variance
    (DirectionKalman, 1e7 s) or a NaN azimuth (DirectionIMM, 1e8 s). A prediction whose azimuth
    sd exceeds LOST_AZIMUTH_SD_DEG holds no direction; the next measurement starts the track
    anew. Ground truth: a static source at (30, 10) deg, measured with 5 deg noise."""
    rng = np.random.default_rng(0)
    k = cls(5.0)
    for n in range(10):
        assert k.update(n * DT, (30.0, 10.0))
    assert not k.lost
    t0 = 9 * DT + gap
    assert not k.update(t0 - 1.0, None)  # coasting: the old direction, with no weight
    assert k.lost and k.azimuth_deg == pytest.approx(30.0, abs=1e-6)
    assert np.sqrt(k.P[0, 0]) > LOST_AZIMUTH_SD_DEG
    assert k.update(t0, (31.0, 12.0), sigma_meas_deg=(4.0, 8.0))  # a first measurement
    assert k.x == pytest.approx([31.0, 12.0, 0.0, 0.0], abs=1e-12)
    assert np.diag(k.P)[:2] == pytest.approx([16.0, 64.0], rel=1e-12)
    for n in range(1, 10):
        assert k.update(t0 + n * DT, tuple(rng.normal([30.0, 10.0], 5.0)))
        assert np.all(np.isfinite(k.x)) and np.linalg.eigvalsh(k.P)[0] > 0
        assert not k.lost
    assert abs(k.azimuth_deg - 30.0) < 3.0 * np.sqrt(k.P[0, 0])
    # a short coast keeps the track: its next measurement is a correction, not a restart
    # (a restart would give the measurement's own variance, 5^2)
    assert k.update(t0 + 10 * DT + 0.2, (35.0, 10.0))
    assert k.P[0, 0] < 5.0**2 - 1.0 and k.x[2] != 0.0 and not k.lost


def test_settings_and_frame_arguments_that_are_not_numbers_are_estimation_errors():
    """Builtin TypeErrors / ValueErrors (a bare ``0 < gate_prob < 1``, ``rate_tau_s > 0``,
    math.isfinite(delay_s), unpacking a motion candidate, an unknown keyword), and bools or text
    read as numbers (rate_tau_s=True as 1 s, a delay True as 1 s, sigma_jerk=True as 1 m/s^2,
    the IMM's modes ("50", "2000") as numbers): each is an EstimationError now. Valid
    spellings still work: numpy scalars, inf time constants, a numpy array of candidates."""
    bad_settings = [
        (DirectionKalman, {"gate_prob": "0.99"}), (DirectionKalman, {"gate_prob": None}),
        (DirectionKalman, {"gate_prob": True}), (DirectionKalman, {"rate_tau_s": "2"}),
        (DirectionKalman, {"rate_tau_s": True}), (DirectionIMM, {"gate_prob": None}),
        (DirectionIMM, {"mode_dwell_s": "1"}), (DirectionIMM, {"mode_dwell_s": None}),
        (DirectionIMM, {"mode_dwell_s": True}),
        (DirectionIMM, {"sigma_accel_dps2": ("50", "2000")}),
        (DirectionIMM, {"sigma_accel_dps2": (50.0, True)}), (MotionKalman, {"gate_prob": "0.99"}),
        (MotionKalman, {"sigma_jerk": True}), (MotionKalman, {"sigma_jerk": (1.0, True, 1.0)}),
    ]
    for cls, kw in bad_settings:
        with pytest.raises(EstimationError, match=next(iter(kw))):
            cls(**kw)
    for cls in (DirectionKalman, DirectionIMM):
        k = cls()
        assert k.update(0.0, (10.0, 5.0))
        for delay in ("0.1", None, True):
            with pytest.raises(EstimationError, match="delay_s"):
                k.update(0.1, (10.0, 5.0), delay_s=delay)
        with pytest.raises(EstimationError, match="candidates"):
            k.update(0.1, (10.0, 5.0), candidates=5)
        assert k.update(0.1, None, candidates=np.array([[10.0, 5.0], [170.0, 5.0]]),
                        delay_s=np.float64(0.01))
        assert k.azimuth_deg == pytest.approx(10.0, abs=1e-6)
    k = DirectionKalman()
    k.update(0.0, (10.0, 5.0))
    for delay in (np.nan, "1", True):
        with pytest.raises(EstimationError, match="delay_s"):
            k.gate_distance(10.0, 5.0, delay_s=delay)
    with pytest.raises(EstimationError, match="covariance"):
        k.gate_distance(10.0, 5.0, R="a")
    assert k.gate_distance(10.0, 5.0, R=np.eye(2), delay_s=np.float32(0.5)) == pytest.approx(0.0)
    m = MotionKalman()
    for cands in ([[1.0, 2.0, 3.0]], [([1.0, 2.0, 3.0],)], 5, [7.0]):
        with pytest.raises(EstimationError, match="candidates"):
            m.update(0.0, None, candidates=cands)
    with pytest.raises(EstimationError, match="time"):
        m.predicted_to("x")
    assert m.update(0.0, None, candidates=[([1.0, 2.0, 3.0], None)])
    with pytest.raises(EstimationError, match="bogus"):
        track_directions([0.0, 0.1], [10.0, 11.0], bogus=1)
    with pytest.raises(EstimationError, match="bogus"):
        track_positions([0.0, 0.1], np.zeros((2, 3)), bogus=1)
    # valid spellings: numpy numbers, an infinite time constant (none)
    assert DirectionKalman(gate_prob=np.float32(0.99), rate_tau_s=float("inf")).rate_tau_s is None
    assert DirectionKalman(rate_tau_s=np.int64(2)).rate_tau_s == 2.0
    assert DirectionIMM(mode_dwell_s=float("inf"), sigma_accel_dps2=np.array([50, 2000])
                        ).mode_dwell_s == float("inf")
    assert MotionKalman(sigma_jerk=np.array([2.0, 2.0, 0.1])).sigma_jerk == (2.0, 2.0, 0.1)
    assert track_directions([0.0, 0.1], [10.0, 11.0], sigma_meas_deg=2.0).accepted.all()


@pytest.mark.parametrize("cls", [DirectionKalman, DirectionIMM])
def test_a_refused_update_leaves_the_tracker_as_it_was(cls):
    """The IMM set its azimuth random walk from a call's noise before refusing the call for its
    time (P_az after the next coasting frame 414 instead of 5.7 deg^2), and the single filter
    predicted to a call's time before refusing its noise (a later frame at an earlier time was
    then "time going backwards"). Ground truth: a twin that never saw the refused calls."""
    kw = {"angle_noise_ratio": 8.0} if cls is DirectionIMM else {}
    k, twin = cls(**kw), cls(**kw)
    for f in (k, twin):
        for n in range(10):
            f.update(n * DT, (10.0 + n, None), sigma_meas_deg=2.0)
    with pytest.raises(EstimationError, match="backwards"):
        k.update(0.0, (10.0, None), sigma_meas_deg=40.0)
    for bad in ({"sigma_meas_deg": -1.0}, {"delay_s": "x"}, {"candidates": 5}):
        with pytest.raises(EstimationError):
            k.update(1.0, (10.0, None), **bad)
    assert k.t == twin.t
    for f in (k, twin):
        assert not f.update(10 * DT, None)  # coasting
        assert f.update(11 * DT, (21.0, None), sigma_meas_deg=2.0)
    np.testing.assert_array_equal(k.x, twin.x)
    np.testing.assert_array_equal(k.P, twin.P)


def test_a_refused_motion_update_leaves_the_track_as_it_was():
    """MotionKalman.update predicted the track to a call's time before refusing its fix or
    covariance (found by an audit, 2026-12-02): the refused call at t = 0.5 s moved the track's
    time and grew its covariance, and the caller's next frame at 0.2 s was then refused as
    "time going backwards". Ground truth: a twin that never saw the refused calls."""
    k, twin = MotionKalman(), MotionKalman()
    for f in (k, twin):
        for n in range(5):
            f.update(n * DT, [1.0 + 0.01 * n, 0.0, 0.0])
    for pos, R in (([1.0, 2.0], None), ("abc", None), ([1.0, 0.0, 0.0], -np.eye(3)),
                   ([1.0, 0.0, 0.0], "abc")):
        with pytest.raises(EstimationError):
            k.update(0.5, pos, R)
    with pytest.raises(EstimationError):
        k.update(0.5, [1.0, 0.0, 0.0], None, candidates=[[1.0, 0.0, 0.0]])
    assert k.t == twin.t
    for f in (k, twin):
        assert f.update(5 * DT, [1.05, 0.0, 0.0])
    np.testing.assert_array_equal(k.x, twin.x)
    np.testing.assert_array_equal(k.P, twin.P)


def test_sigma_jerk_error_states_its_documented_unit():
    """The message said m/s^3 (a jerk); sigma_jerk is the acceleration's increment per update
    step in m/s^2 (the docstring since 2026-12-01)."""
    for bad in ("a", True, (1.0, 2.0)):
        with pytest.raises(EstimationError, match=r"increment per update step, m/s\^2"):
            MotionKalman(sigma_jerk=bad)


@pytest.mark.parametrize("make", [lambda: DirectionKalman(), lambda: DirectionIMM()])
def test_rotate_azimuth_turns_the_track_with_the_frame(make):
    """The frame turned by -d (a head panned): the track's azimuth moves by +d, wrapped, every
    IMM mode with it; rates, elevation and covariance stay; before a track, nothing; NaN is
    refused (it would have wrapped to NaN silently)."""
    f = make()
    f.rotate_azimuth(30.0)
    assert not f.initialized
    for k in range(6):
        f.update(0.032 * k, (170.0 + 2.0 * k, 5.0))
    az, el, rate, P = f.azimuth_deg, f.elevation_deg, f.rate_dps.copy(), f.P.copy()
    modes = f.X.copy() if hasattr(f, "X") else None
    f.rotate_azimuth(25.0)
    assert f.azimuth_deg == pytest.approx(float(wrap_deg(az + 25.0)))
    assert -170.0 < f.azimuth_deg < -150.0  # (across the seam)
    assert f.elevation_deg == el and np.array_equal(f.rate_dps, rate)
    np.testing.assert_array_equal(f.P, P)
    if modes is not None:
        np.testing.assert_allclose(wrap_deg(f.X[:, 0] - modes[:, 0] - 25.0), 0.0, atol=1e-9)
        np.testing.assert_array_equal(f.X[:, 1:], modes[:, 1:])
    with pytest.raises(EstimationError, match="delta_deg"):
        f.rotate_azimuth(float("nan"))


@pytest.mark.parametrize("cls", [DirectionKalman, DirectionIMM])
def test_elevation_is_reported_once_measured_and_kept_through_azimuth_only_frames(cls):
    """A track reports an elevation from the first frame that measured one, and keeps it
    through frames that measured the azimuth alone (NaN only while none ever was). No test held
    it: a track that lost its elevation at an azimuth-only frame, or never took one after an
    azimuth-only start, passed this file."""
    later = cls()
    later.update(0.0, (30.0, None))  # started from the azimuth alone: no elevation yet
    assert np.isnan(later.elevation_deg)
    for k in range(1, 20):  # then measured at 20 deg elevation
        later.update(k * DT, (30.0, 20.0))
    assert later.elevation_deg == pytest.approx(20.0, abs=0.5)
    kept = cls()
    for k in range(10):
        kept.update(k * DT, (30.0, 20.0))
    kept.update(10 * DT, (30.0, None))  # one frame without an elevation
    assert kept.elevation_deg == pytest.approx(20.0, abs=0.5)
