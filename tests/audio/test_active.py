"""Multiple sampling with a moving head (hearsee.audio.active, thesis ch. 4)."""

import numpy as np
import pytest

from hearsee.audio.active import (
    PoseItdMLP,
    align_head,
    capture_tdoas,
    facing_pair,
    localize_continuous,
    localize_multipose,
    localize_one_mic,
    make_pose_training_set,
    simulate_pose_captures,
    simulate_turning_capture,
    solve_range_differences,
    train_pose_mlp,
)
from hearsee.audio.arrays import MicArray, load_array
from hearsee.audio.signals import white_noise
from hearsee.errors import AudioInputError, ConfigError, EstimationError, GeometryError
from hearsee.geometry import (
    HeadPose,
    angle_between,
    direction_deg,
    mic_positions_at,
    unit_vector_deg,
)

ARR = load_array("three-mic")
OFF = (0.1, 0.0, 0.05)
POSES3 = [(0, 0), (45, 25), (-45, -20)]


def true_tdoas(array, src, poses, offset=OFF, pivot=(0, 0, 0)):
    return [MicArray(mic_positions_at(array, p, pivot, offset)).tdoa(src) for p in poses]


def test_three_poses_give_a_unique_3d_point():
    src = np.array([-0.9, 1.4, 0.6])
    est = localize_multipose(true_tdoas(ARR, src, POSES3), POSES3, ARR, offset_m=OFF)
    assert est.unique and len(est.candidates) == 1
    np.testing.assert_allclose(est.position_m, src, atol=2e-3)
    assert est.distance_m == pytest.approx(np.linalg.norm(src), rel=1e-3)
    az, el = direction_deg(src)
    assert est.azimuth_deg == pytest.approx(float(az), abs=0.1)
    assert est.elevation_deg == pytest.approx(float(el), abs=0.1)
    w = np.linalg.eigvalsh(est.covariance)
    assert est.covariance.shape == (3, 3) and np.all(w > 0)
    d = est.to_dict()
    assert d["unique"] is True and len(d["position_m"]) == 3


@pytest.mark.parametrize("pan_error_deg", [0.0, 30.0, -90.0])
def test_contradicting_poses_are_flagged_inconsistent(pan_error_deg):
    # exact TDOAs of a source seen from three poses; the solver is told one pose's pan
    # angle wrong by pan_error_deg: a single source cannot explain all nine TDOAs then
    src = np.array([1.2, 0.8, 0.5])
    taus = true_tdoas(ARR, src, POSES3)
    told = [POSES3[0], (POSES3[1][0] + pan_error_deg, POSES3[1][1]), POSES3[2]]
    est = localize_multipose(taus, told, ARR, offset_m=OFF)
    if pan_error_deg == 0.0:
        assert est.consistent and est.residual_rms_s < 1e-6
        np.testing.assert_allclose(est.position_m, src, atol=2e-3)
    else:
        assert not est.consistent and est.residual_rms_s > 30e-6
        # the threshold is 6 x tdoa_std_s by default, or given
        loose = localize_multipose(taus, told, ARR, offset_m=OFF,
                                   max_residual_rms_s=2 * est.residual_rms_s)
        assert loose.consistent and loose.residual_rms_s == pytest.approx(est.residual_rms_s)
        assert localize_multipose(taus, told, ARR, offset_m=OFF,
                                  tdoa_std_s=est.residual_rms_s).consistent
    d = est.to_dict()
    assert d["consistent"] is est.consistent
    assert d["residual_rms_s"] == pytest.approx(est.residual_rms_s)


def test_a_source_nearer_than_the_search_is_not_called_consistent():
    """Exact TDOAs of a source 0.15 m from the pivot, inside the solver's 0.2 m near bound: the
    fit held at the bound (0.200 m, 6.6 deg off) was called unique and consistent. At 0.21 m
    the answer is exact and consistent."""
    poses = [(0, 0), (40, 25), (-40, -20)]
    for r, ok in ((0.21, True), (0.15, False)):
        src = r * unit_vector_deg(45.0, 10.0)
        out = localize_multipose(true_tdoas(ARR, src, poses, offset=(0, 0, 0)), poses, ARR)
        assert out.consistent is ok
        assert out.residual_rms_s < 3e-5  # (within the residual test: the bound decides)
        if ok:
            np.testing.assert_allclose(out.position_m, src, atol=1e-6)
        else:
            assert out.distance_m == pytest.approx(0.2)


def test_single_pose_reports_mirror_and_no_distance():
    src = np.array([1.0, 0.5, 0.7])
    est = localize_multipose(true_tdoas(ARR, src, [(0, 0)]), [(0, 0)], ARR, offset_m=OFF)
    assert not est.unique
    assert est.distance_m is None and est.position_m is None and est.covariance is None
    els = sorted(c["elevation_deg"] for c in est.candidates)
    # without a distance the answer is a far-field direction: seen from the array centre
    centre = mic_positions_at(ARR, (0, 0), offset_m=OFF).mean(axis=0)
    az_true, el_true = (float(v) for v in direction_deg(src - centre))
    assert len(els) == 2
    np.testing.assert_allclose(els, [-el_true, el_true], atol=1.0)
    for c in est.candidates:
        assert c["azimuth_deg"] == pytest.approx(az_true, abs=1.0)
        assert c["distance_m"] is None


def test_pan_only_poses_keep_the_mirror():
    """A horizontal planar array turned only in pan can never tell up from down."""
    src = np.array([1.5, -0.5, 0.8])
    poses = [(0, 0), (40, 0), (-40, 0)]
    est = localize_multipose(true_tdoas(ARR, src, poses, offset=(0.1, 0, 0)), poses, ARR,
                             offset_m=(0.1, 0, 0))
    assert not est.unique
    els = [c["elevation_deg"] for c in est.candidates]
    assert min(els) < -20 and max(els) > 20


def test_noisy_estimate_within_covariance():
    rng = np.random.default_rng(4)
    src = np.array([1.2, 0.4, 0.5])
    poses = POSES3 + [(30, -25), (-30, 25)]
    sig = 5e-6
    errs = []
    for _ in range(6):
        tau = [t + rng.normal(0, sig, 3) for t in true_tdoas(ARR, src, poses, offset=(0.2, 0, 0.1))]
        est = localize_multipose(tau, poses, ARR, offset_m=(0.2, 0, 0.1), tdoa_std_s=sig)
        assert est.unique
        e = est.position_m - src
        errs.append(float(e @ np.linalg.solve(est.covariance, e)))  # Mahalanobis^2, chi2(3)
        assert float(np.degrees(angle_between(est.direction, src))) < 3.0
    assert np.median(errs) < 12.0


def test_two_microphones_need_more_poses():
    two = load_array("two-mic")
    src = np.array([0.8, 1.0, 0.4])
    poses = [(0, 0), (40, 30), (-40, -25), (70, -20), (-70, 30), (10, 45)]
    tau = true_tdoas(two, src, poses, offset=(0.15, 0, 0.1))
    est = localize_multipose(tau, poses, two, offset_m=(0.15, 0, 0.1), tdoa_std_s=1e-6)
    assert est.unique
    np.testing.assert_allclose(est.position_m, src, atol=0.02)
    one = localize_multipose(true_tdoas(two, src, poses[:1]), poses[:1], two)
    assert not one.unique and one.distance_m is None


def test_one_microphone_repeating_source():
    """One microphone on the head (mic 0 of three-mic) visited at 7 poses; the source repeats
    with a known period so the per-period arrival times differ by range differences."""
    src = np.array([1.3, -0.6, 0.4])
    poses = [(0, 0), (60, 0), (-60, 0), (120, 20), (-120, -20), (0, 45), (30, -40)]
    P = np.array([mic_positions_at(ARR, p, offset_m=(0.1, 0, 0))[0] for p in poses])
    t0 = 0.0123  # unknown emission offset: cancels
    t = t0 + np.linalg.norm(P - src, axis=1) / 343.0
    est = localize_one_mic(t, P)
    assert est.unique
    np.testing.assert_allclose(est.position_m, src, atol=0.02)
    with pytest.raises(GeometryError):
        localize_one_mic(t[:2], P[:2])


def test_bad_inputs():
    with pytest.raises(GeometryError):
        localize_multipose([np.zeros(3)], [(0, 0), (10, 0)], ARR)
    with pytest.raises(EstimationError):
        localize_multipose([np.full(3, np.nan)], [(0, 0)], ARR)
    with pytest.raises(GeometryError):
        localize_multipose([np.zeros(2)], [(0, 0)], ARR)
    with pytest.raises(GeometryError):
        solve_range_differences([np.zeros((3, 3))], [[(0, 5)]], [np.zeros(1)])
    with pytest.raises(GeometryError):
        localize_multipose([np.zeros(3)], [(0, 0)], ARR, tdoa_std_s=0.0)
    with pytest.raises(EstimationError):
        PoseItdMLP().predict(np.zeros((1, 9)))
    # ... which is scikit-learn's NotFittedError too (as AudioVisualRegressor's)
    from sklearn.exceptions import NotFittedError

    with pytest.raises(NotFittedError):
        PoseItdMLP().predict(np.zeros((1, 9)))
    # scikit-learn's ValueErrors: a training position at the reference point (log 0), a NaN
    # position, a NaN TDOA to predict from (helper audit)
    rng = np.random.default_rng(0)
    X, Y = rng.normal(0, 1e-4, (40, 9)), rng.uniform(-2, 2, (40, 3))
    for bad_y in (np.vstack([Y[:-1], [0.0, 0.0, 0.0]]), np.vstack([Y[:-1], [np.nan, 0, 1]])):
        with pytest.raises(EstimationError, match="PoseItdMLP.fit"):
            PoseItdMLP(max_iter=5).fit(X, bad_y)
    mlp = PoseItdMLP(max_iter=5).fit(X, Y)
    with pytest.raises(EstimationError, match="finite TDOAs"):
        mlp.predict(np.full((1, 9), np.nan))
    # scikit-learn's own ValueErrors / InvalidParameterError (second helper audit): too few
    # samples for early stopping's validation set, settings it refuses, and the two it does
    # not see (a zero TDOA scale: infinite inputs; a 2-vector reference: a broadcast error)
    with pytest.raises(EstimationError, match="at least 20 samples, got 5"):
        PoseItdMLP(max_iter=5).fit(X[:5], Y[:5])
    for kw, needle in (({"tdoa_scale_s": 0.0}, "tdoa_scale_s"), ({"reference_m": (0, 0)},
                                                                 "reference_m"),
                       ({"hidden_layer_sizes": (0,)}, "settings: hidden_layer_sizes"),
                       ({"alpha": -1.0}, "settings: The 'alpha'"),
                       ({"max_iter": 0}, "settings: The 'max_iter'")):
        with pytest.raises(ConfigError, match=needle):
            PoseItdMLP(**{"max_iter": 5, **kw}).fit(X, Y)
    with pytest.raises(EstimationError, match="got shape"):
        mlp.predict(np.zeros((0, 9)))
    with pytest.raises(AudioInputError):
        align_head(lambda pose: np.zeros(2), ARR)


def test_bad_speed_of_sound_and_coincident_microphones_are_refused():
    """Bad-input sweep (2026-11-26): speed_of_sound -343 returned the mirrored direction (az
    -147 deg for a source at 56), microphones that all coincide returned a direction from
    nothing, f_scale 0 raised scipy's ValueError."""
    arr = load_array("three-mic")
    src = np.array([1.0, 1.5, 0.4])
    good = solve_range_differences([arr.positions], [arr.pairs], [arr.tdoa(src)])
    # atan2(1.5, 1.0) = 56.31 deg; one pose is solved as a plane wave (~0.1 deg off at 1.9 m)
    assert good.azimuth_deg == pytest.approx(56.31, abs=0.3)
    for c in (-343.0, 0.0, np.nan):
        with pytest.raises(GeometryError, match="speed_of_sound"):
            solve_range_differences([arr.positions], [arr.pairs], [arr.tdoa(src)],
                                    speed_of_sound=c)
    with pytest.raises(GeometryError, match="coincide"):
        solve_range_differences([np.zeros((3, 3))], [arr.pairs], [[0.0, 0.0, 0.0]])
    with pytest.raises(GeometryError, match="coincide"):
        localize_one_mic([0.0, 0.0, 0.0, 0.0], [[0.0, 0.0, 0.0]] * 4)
    with pytest.raises(GeometryError, match="f_scale"):
        solve_range_differences([arr.positions], [arr.pairs], [arr.tdoa(src)], f_scale=0.0)


def test_training_set_refuses_nan_noise_and_bad_ranges():
    """tdoa_std_s=NaN returned all-NaN samples; an inverted or negative distance range raised
    numpy's ValueError or was accepted (bad-input sweep, 2026-11-26)."""
    for kw in ({"tdoa_std_s": np.nan}, {"tdoa_std_s": -1.0}, {"tdoa_std_s": 1e200},
               {"distance_range_m": (3.0, 0.5)},
               {"distance_range_m": (-1.0, 2.0)}, {"elevation_range_deg": (np.nan, 10.0)},
               {"elevation_range_deg": (-100.0, 0.0)}, {"elevation_range_deg": (40.0, 10.0)},
               {"azimuth_range_deg": (90.0, -90.0)}):
        with pytest.raises(GeometryError):  # elevation -100 folded over the pole silently
            make_pose_training_set(ARR, POSES3, 10, **kw)
    for n in (-1, 2.5):  # -1 was numpy's "negative dimensions"
        with pytest.raises(ConfigError, match="training samples"):
            make_pose_training_set(ARR, POSES3, n)
    X, Y = make_pose_training_set(ARR, POSES3, 10, tdoa_std_s=0.0)
    assert np.all(np.isfinite(X)) and X.shape == (10, 9)


def test_mlp_maps_tdoas_over_poses_to_positions():
    mlp = train_pose_mlp(ARR, POSES3, offset_m=(0.2, 0, 0.1), n=2000, seed=1,
                         hidden_layer_sizes=(32, 32))
    assert train_pose_mlp(ARR, POSES3, offset_m=(0.2, 0, 0.1), n=2000, seed=1,
                          hidden_layer_sizes=(32, 32)) is mlp  # in-memory cache
    X, Y = make_pose_training_set(ARR, POSES3, 200, offset_m=(0.2, 0, 0.1), rng=99)
    P = mlp.predict(X)
    ang = np.degrees(angle_between(P, Y))
    assert np.median(ang) < 10.0
    assert np.median(np.abs(np.linalg.norm(P, axis=1) / np.linalg.norm(Y, axis=1) - 1)) < 0.3


def test_facing_pair_and_alignment_free_field_geometry():
    assert facing_pair(ARR) == (1, 2)
    rng = np.random.default_rng(7)
    for src in ([1.0, 1.5, 1.2], [-2.0, -0.5, -0.6], [0.5, -2.5, 0.1]):
        src = np.array(src)

        def measure(pose, src=src):
            m = MicArray(mic_positions_at(ARR, pose, offset_m=OFF))
            return m.tdoa(src) + rng.normal(0, 2e-6, 3)

        res = align_head(measure, ARR, offset_m=OFF)
        assert res.converged  # (moves <= 8, asserted before, held by construction)
        assert res.error_deg(src, offset_m=OFF) < 2.0
        assert abs(res.facing_tdoa_s[-1]) < 10e-6  # the symmetric pair's ITD vanishes


@pytest.mark.parametrize("az, el, dist", [(-21.464, 36.821, 2.5), (155.5, -22.0, 3.2),
                                          (28.9, -9.1, 3.0)])
def test_alignment_with_exact_tdoas_corrects_the_offset_parallax(az, el, dist):
    # the array origin sits 0.1 m in front of the pivot: aiming along the far-field direction
    # seen from the pivot (distance unresolved) left the gaze off by the parallax, 0.7-1.2 deg
    src = dist * np.array([np.cos(np.radians(el)) * np.cos(np.radians(az)),
                           np.cos(np.radians(el)) * np.sin(np.radians(az)),
                           np.sin(np.radians(el))])

    def measure(pose):
        return MicArray(mic_positions_at(ARR, pose, offset_m=OFF)).tdoa(src)

    res = align_head(measure, ARR, offset_m=OFF, tol_deg=0.1)
    assert res.converged and res.moves <= 4
    assert res.error_deg(src, offset_m=OFF) < 0.05
    assert abs(res.facing_tdoa_s[-1]) < 0.05e-6


def _exact_alignment_error_deg(src):
    def measure(pose):
        return MicArray(mic_positions_at(ARR, pose, offset_m=OFF)).tdoa(src)

    res = align_head(measure, ARR, offset_m=OFF)
    assert res.converged
    return res.error_deg(src, offset_m=OFF)


# 2026-12-02: when the distance-unlimited fit kept a second, near-field minimum beside the
# source (a point ~0.3 m from the pivot, ~20 deg off), align_head dropped the parallax
# correction and aimed along the far-field direction: these sources ended 1.1-2.2 deg off
# (1.47 for (-2, -0.01, -0.5)), against the documented 0.05 deg
@pytest.mark.parametrize("src", [(-2.0, -0.01, -0.5), (2.0526, 0.2077, -1.3127),
                                 (-1.7871, -0.0648, -0.5789), (-1.3353, 0.0324, -0.4802)])
def test_alignment_with_exact_tdoas_despite_a_near_field_minimum(src):
    assert _exact_alignment_error_deg(np.array(src)) < 0.05


@pytest.mark.slow
def test_alignment_with_exact_tdoas_ends_on_40_random_sources():
    # the random set in which the defect above was found (3 of 40 off by 1.1-2.2 deg)
    rng = np.random.default_rng(1)
    errs = []
    for _ in range(40):
        az = rng.uniform(-np.pi, np.pi)
        el = np.arcsin(rng.uniform(np.sin(-0.8), np.sin(1.0)))
        src = rng.uniform(0.7, 3.5) * np.array([np.cos(el) * np.cos(az),
                                                np.cos(el) * np.sin(az), np.sin(el)])
        errs.append(_exact_alignment_error_deg(src))
    assert max(errs) < 0.05, np.round(errs, 3)


@pytest.mark.slow
def test_room_captures_and_alignment_with_audio():
    fs = 16000
    rng = np.random.default_rng(2)
    sig = white_noise(0.5, fs, rng)
    src = np.array([1.0, -1.2, 0.6])
    room = dict(room_dim=(6.0, 6.0, 3.5), rt60=0.3, robot_at=(3.0, 3.0, 1.4))
    caps = simulate_pose_captures(sig, fs, ARR, src, POSES3, offset_m=OFF, snr_db=20, rng=rng,
                                  **room)
    tau = [capture_tdoas(x, fs, ARR) for x in caps]
    for t, g in zip(tau, true_tdoas(ARR, src, POSES3), strict=True):
        np.testing.assert_allclose(t, g, atol=8e-6)
    est = localize_multipose(tau, POSES3, ARR, offset_m=OFF)
    assert float(np.degrees(angle_between(est.direction, src))) < 3.0

    def measure(pose):
        x = simulate_pose_captures(sig, fs, ARR, src, [pose], offset_m=OFF, snr_db=20, rng=rng,
                                   **room)[0]
        return capture_tdoas(x, fs, ARR)

    res = align_head(measure, ARR, offset_m=OFF)
    assert res.converged and res.error_deg(src, offset_m=OFF) < 2.0


def test_continuous_sampling_while_turning():
    fs = 16000
    rng = np.random.default_rng(5)
    sig = white_noise(1.2, fs, rng)
    src = np.array([1.2, 0.9, 0.5])

    def pose_at(t):  # sweep pan -40 -> 40 deg and tilt -20 -> 20 deg over the capture
        f = min(max(t / 1.2, 0.0), 1.0)
        return HeadPose(-40 + 80 * f, -20 + 40 * f)

    x = simulate_turning_capture(sig, fs, ARR, src, pose_at, offset_m=(0.2, 0, 0.1), snr_db=25,
                                 rng=rng)
    assert x.shape == (3, len(sig))
    est, times, running = localize_continuous(x, fs, ARR, pose_at, offset_m=(0.2, 0, 0.1))
    assert float(np.degrees(angle_between(est.direction, src))) < 3.0
    assert est.distance_m is not None
    assert est.distance_m == pytest.approx(np.linalg.norm(src), rel=0.15)
    assert len(times) == len(running) and np.isfinite(running[-1]).all()


def test_continuous_sampling_with_pan_reported_across_180_deg():
    """An encoder reports pan in (-180, 180]: a group of frames at 178 and -178 deg is a head
    facing backward (180), not forward (their plain mean, 0). Same capture, pan reported
    unwrapped and wrapped: the same estimate."""
    from hearsee.geometry import wrap_deg

    fs = 16000
    sig = white_noise(1.2, fs, np.random.default_rng(5))
    src = np.array([-1.2, -0.3, 0.5])  # behind the robot

    def pose_at(t):  # pan 140 -> 220 deg through the back, tilt -20 -> 20 deg
        f = min(max(t / 1.2, 0.0), 1.0)
        return HeadPose(140 + 80 * f, -20 + 40 * f)

    def pose_wrapped(t):
        p = pose_at(t)
        return HeadPose(float(wrap_deg(p.pan_deg)), p.tilt_deg)

    x = simulate_turning_capture(sig, fs, ARR, src, pose_at, offset_m=(0.2, 0, 0.1),
                                 snr_db=25, rng=np.random.default_rng(1))
    ests = [localize_continuous(x, fs, ARR, pa, offset_m=(0.2, 0, 0.1), group_frames=12)[0]
            for pa in (pose_at, pose_wrapped)]
    for est in ests:
        assert float(np.degrees(angle_between(est.direction, src))) < 2.0
        assert est.distance_m == pytest.approx(np.linalg.norm(src), rel=0.15)
    assert ests[1].cost == pytest.approx(ests[0].cost, rel=1e-6, abs=1e-9)


def test_continuous_sampling_refuses_bad_group_and_block_sizes():
    """group_frames 0 raised range()'s ValueError, 2.5 a TypeError and -1 'at least one head
    pose is needed'; a NaN block_s raised int()'s ValueError and a negative one was taken as
    one sample."""
    fs = 16000
    sig = white_noise(0.3, fs, np.random.default_rng(0))
    src = np.array([1.0, 0.8, 0.3])
    x = simulate_turning_capture(sig, fs, ARR, src, lambda t: (0.0, 0.0))
    for g in (0, -1, 2.5, True):
        with pytest.raises(GeometryError, match="group_frames"):
            localize_continuous(x, fs, ARR, lambda t: (0.0, 0.0), group_frames=g)
    for b in (float("nan"), -0.064, 0.0, float("inf")):
        with pytest.raises(GeometryError, match="block_s"):
            simulate_turning_capture(sig, fs, ARR, src, lambda t: (0.0, 0.0), block_s=b)


def test_turning_capture_checks_fs_and_signal_before_any_work():
    """fs=0 divided by zero (a RuntimeWarning), called pose_at at an infinite time and failed
    on the pose ("HeadPose.pan_deg must be finite"); NaN did the same, text raised a builtin
    TypeError. The sample rate and the signal are now checked first: AudioInputError, no
    warning, pose_at never called."""
    import warnings

    from hearsee.errors import AudioInputError

    sig = white_noise(0.3, 16000, np.random.default_rng(0))
    called = []

    def pose_at(t):
        called.append(t)
        return (30.0 * t, 0.0)

    src = np.array([1.0, 0.8, 0.3])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for fs in (0, float("nan"), -16000, "16000"):
            with pytest.raises(AudioInputError, match="sample rate"):
                simulate_turning_capture(sig, fs, ARR, src, pose_at)
        with pytest.raises(AudioInputError, match="signal"):
            simulate_turning_capture(np.full(100, np.nan), 16000, ARR, src, pose_at)
    assert called == []


# ----------------------------------------------------------------------------- manifests + CLI
@pytest.fixture(scope="module")
def pose_manifest(tmp_path_factory):
    from hearsee.audio.active import simulate_pose_manifest

    d = tmp_path_factory.mktemp("poses")
    src = [1.1, -0.7, 0.5]
    man, files = simulate_pose_manifest(d / "cap.yaml", "three-mic", src, POSES3, signal="noise",
                                        duration_s=0.5, fs=16000, snr_db=30, seed=3,
                                        offset_m=(0.2, 0.0, 0.1))
    return man, files, np.array(src)


@pytest.mark.parametrize("method", [[], ["--method", "gcc-scot"]], ids=["default", "scot"])
def test_localize3d_cli_round_trip(pose_manifest, capsys, method):
    import json

    from hearsee.audio.active import load_pose_manifest
    from hearsee.cli import main

    man, files, src = pose_manifest
    assert len(files) == 3 and all(f.is_file() for f in files)
    m = load_pose_manifest(man)
    assert [p.as_tuple() for p in m.poses] == [tuple(map(float, p)) for p in POSES3]
    np.testing.assert_allclose(m.truth["source_m"], src)
    assert main(["localize3d", str(man), *method]) == 0
    out = capsys.readouterr()
    doc = json.loads(out.out)
    assert doc["unique"] is True and doc["consistent"] is True
    assert "warning" not in out.err
    np.testing.assert_allclose(doc["position_m"], src, atol=0.1)
    assert doc["distance_m"] == pytest.approx(np.linalg.norm(src), rel=0.08)
    assert np.array(doc["covariance"]).shape == (3, 3)
    for k in ("azimuth_deg", "elevation_deg", "candidates"):
        assert k in doc


def test_a_capture_given_as_one_file_per_microphone(pose_manifest, tmp_path, capsys):
    """A manifest's capture may list one file per microphone (a recorder that writes a file
    per input): the same position as the multichannel files; a list whose files differ in
    length is one line, exit 2. Its ``channels`` pick the microphones of larger files."""
    import json

    import soundfile as sf
    import yaml

    from hearsee.audio.active import load_pose_manifest
    from hearsee.cli import main

    man, files, src = pose_manifest
    d = yaml.safe_load(man.read_text())
    x, fs = sf.read(files[1], always_2d=True)
    mics = [tmp_path / f"p1_mic{k}.wav" for k in range(x.shape[1])]
    for k, p in enumerate(mics):
        sf.write(p, x[:, k], fs, subtype=sf.info(files[1]).subtype)
    d["array"] = "three-mic"
    for c, f in zip(d["captures"], files, strict=True):
        c["file"] = str(f)
    d["captures"][1]["file"] = [p.name for p in mics]  # (relative to the manifest's folder)
    split = tmp_path / "split.yaml"
    split.write_text(yaml.safe_dump(d))
    assert load_pose_manifest(split).files[1] == mics
    assert main(["localize3d", str(man)]) == 0
    ref = json.loads(capsys.readouterr().out)
    assert main(["localize3d", str(split)]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["position_m"] == ref["position_m"]
    np.testing.assert_allclose(got["position_m"], src, atol=0.1)
    sf.write(mics[2], x[:-4, 2], fs)
    assert main(["localize3d", str(split)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "different numbers of samples" in err
    d["captures"][1]["file"] = [mics[0].name, 3]
    split.write_text(yaml.safe_dump(d))
    assert main(["localize3d", str(split)]) == 2
    assert "file must be a capture file's name or a list of them" in capsys.readouterr().err
    # a device's other channels: each capture as 5 channels (a mix first, a silent one last),
    # the manifest's channels pick the microphones
    for c, f in zip(d["captures"], files, strict=True):
        y, fs = sf.read(f, always_2d=True)
        five = np.column_stack([y.mean(axis=1), y, np.zeros(len(y))])
        c["file"] = f"five_{f.name}"
        sf.write(tmp_path / c["file"], five, fs, subtype=sf.info(f).subtype)
    d["channels"] = [1, 2, 3]
    split.write_text(yaml.safe_dump(d))
    assert load_pose_manifest(split).channels == (1, 2, 3)
    assert main(["localize3d", str(split)]) == 0
    assert json.loads(capsys.readouterr().out)["position_m"] == ref["position_m"]
    for bad, want in (([1, 2], "split.yaml: channels: 2 channels for an array of 3"),
                      ([1, 2, 4], "channel 4 silent"), ([1, 2, 5], "channel 5 asked for"),
                      (None, "5 channels but array")):
        d["channels"] = bad
        split.write_text(yaml.safe_dump(d))
        assert main(["localize3d", str(split)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and want in err, err


@pytest.mark.parametrize("edit, needle", [
    (lambda d: d.update(extra=1), "unknown key 'extra'"),
    (lambda d: d["captures"][0].pop("tilt_deg"), "missing required key 'tilt_deg'"),
    (lambda d: d["captures"][1].update(file="nope.wav"), "not found"),
    # ('' was the manifest's folder, ".: is a folder"; a list was read as its text)
    (lambda d: d["captures"][1].update(file=""), "captures[1]: file must be a capture file's"),
    # (a list of files is one per microphone: an empty one, or one holding a list, is none)
    (lambda d: d["captures"][1].update(file=[]), "captures[1]: file must be a capture"),
    (lambda d: d["captures"][1].update(file=[["a.wav"]]), "captures[1]: file must be a capture"),
    (lambda d: d["captures"][1].update(file=["a.wav"]), "a.wav: capture file not found"),
    (lambda d: d["captures"][0].update(pan_deg="left"), "pan_deg must be a finite number"),
    # (a 400-digit integer was an OverflowError traceback)
    (lambda d: d["captures"][0].update(pan_deg=10**400), "pan_deg must be a finite number"),
    (lambda d: d["captures"][0].update(tilt_deg=120), "tilt_deg must be within"),
    (lambda d: d.pop("captures"), "missing required key 'captures'"),
    (lambda d: d["head"].update(offset_m=[0, 1]), "offset_m"),
    # (true was read as 1 m and '0.5' as 0.5 m)
    (lambda d: d["head"].update(offset_m=[True, 0, 0]), "head.offset_m: expected numbers"),
    (lambda d: d["head"].update(pivot_m=["0.5", 0, 0]), "head.pivot_m: expected numbers"),
    # (scipy's builtin ValueError 'Residuals are not finite' traceback; the robot file's rule)
    (lambda d: d["head"].update(offset_m=[1e300, 0, 0]),
     "bad.yaml: head.offset_m: [1e+300, 0.0, 0.0] is more than 1 m from the pivot"),
    # (every microphone on one float: a wrong direction with only the consistency warning)
    (lambda d: d["head"].update(pivot_m=[1e300, 0, 0]),
     "bad.yaml: head.pivot_m: [1e+300, 0.0, 0.0] is more than 10 m from the robot-frame origin"),
    # (an infinite noise passed the manifest check; the solver refused it after measuring
    # every capture, without naming the file: "tdoa_std_s must be > 0 seconds, got inf")
    (lambda d: d.update(tdoa_std_s=float("inf")),
     "bad.yaml: tdoa_std_s must be a finite number in (0, 1], got inf"),
    # (1e200 s was taken and overflowed squaring it in the solver: an OverflowError traceback)
    (lambda d: d.update(tdoa_std_s=1e200), "bad.yaml: tdoa_std_s must be a finite number in"),
    (lambda d: d.update(tdoa_std_s=True), "bad.yaml: tdoa_std_s must be a finite number in"),
    # (the captures of a masked pair were solved as the bare pair's: cone azimuths, -30.8 deg
    # for a source at -153 deg)
    (lambda d: d.update(array="mask2-asym"), "bad.yaml: array 'mask2-asym' has a mask"),
])
def test_localize3d_bad_manifest(pose_manifest, tmp_path, capsys, edit, needle):
    import yaml

    from hearsee.cli import main

    man, _files, _src = pose_manifest
    doc = yaml.safe_load(man.read_text())
    for c in doc["captures"]:
        c["file"] = str(man.parent / c["file"])
    edit(doc)
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(doc))
    assert main(["localize3d", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0]


def test_localize3d_warns_when_the_poses_contradict_the_captures(pose_manifest, tmp_path,
                                                                 capsys):
    import json

    import yaml

    from hearsee.cli import main

    man, _files, src = pose_manifest
    doc = yaml.safe_load(man.read_text())
    for c in doc["captures"]:
        c["file"] = str(man.parent / c["file"])
    doc["captures"][1]["pan_deg"] = -doc["captures"][1]["pan_deg"]  # a sign slip
    bad = tmp_path / "slip.yaml"
    bad.write_text(yaml.safe_dump(doc))
    assert main(["localize3d", str(bad)]) == 0
    out = capsys.readouterr()
    assert json.loads(out.out)["consistent"] is False
    err = out.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("hearsee: warning:") and "pose" in err[0]


def test_a_manifest_array_is_never_read_from_the_working_directory(pose_manifest, tmp_path,
                                                                   monkeypatch):
    """A manifest's array named by a preset or a file name that is no file next to the
    manifest was read from the working directory (load_array): a file there named like the
    preset gave another array without a word (a triangle twice the size: the position
    (0.09, 0.07, 0.16) m for a source at (1.2, 0.8, 0.4) m), and "mics.yaml" missing beside
    the manifest was read from there ("paths relative to the manifest's folder")."""
    import yaml

    from hearsee.audio.active import load_pose_manifest
    from hearsee.audio.arrays import MicArray
    from hearsee.errors import InputFileError

    man, _files, _src = pose_manifest
    doc = yaml.safe_load(man.read_text())
    for c in doc["captures"]:
        c["file"] = str(man.parent / c["file"])
    doc["array"] = "three-mic"
    f = tmp_path / "m" / "preset.yaml"
    f.parent.mkdir()
    f.write_text(yaml.safe_dump(doc))
    work = tmp_path / "work"
    work.mkdir()
    big = {"microphones": (2 * MicArray.from_preset("three-mic").positions).tolist()}
    (work / "three-mic").write_text(yaml.safe_dump(big))
    (work / "mics.yaml").write_text(yaml.safe_dump(big))
    monkeypatch.chdir(work)
    arr = load_pose_manifest(f).array
    assert arr.name == "three-mic"
    np.testing.assert_allclose(arr.positions, MicArray.from_preset("three-mic").positions)
    doc["array"] = "mics.yaml"
    f.write_text(yaml.safe_dump(doc))
    with pytest.raises(InputFileError, match=r"array: .*m/mics\.yaml: no such array file"):
        load_pose_manifest(f)


def test_localize3d_missing_manifest(tmp_path, capsys):
    from hearsee.cli import main

    assert main(["localize3d", str(tmp_path / "none.yaml")]) == 2
    assert "not found" in capsys.readouterr().err


def test_parse_poses():
    from hearsee.audio.active import parse_poses
    from hearsee.errors import ConfigError

    assert [p.as_tuple() for p in parse_poses("0,0;45,25; -45,-20")] == [
        (0.0, 0.0), (45.0, 25.0), (-45.0, -20.0)]
    for bad in ("", "0,0,0", "a,b", "0,95"):
        with pytest.raises(ConfigError):
            parse_poses(bad)


def test_one_microphone_from_captures():
    """Simulated captures of a repeating noise burst by one microphone at 7 head poses."""
    from hearsee.audio.active import one_mic_arrival_differences
    from hearsee.audio.propagation import simulate_free_field

    fs = 16000
    rng = np.random.default_rng(11)
    burst = white_noise(0.3, fs, rng)  # one repetition; every capture is synchronised to it
    src = np.array([1.0, 0.6, 0.3])
    poses = [(0, 0), (60, 0), (-60, 0), (120, 20), (-120, -20), (0, 45), (30, -40)]
    P = np.array([mic_positions_at(ARR, p, offset_m=(0.1, 0, 0))[0] for p in poses])
    caps = [simulate_free_field(burst, fs, P[k:k + 1], src, snr_db=30, rng=rng)[0]
            for k in range(len(P))]
    dt = one_mic_arrival_differences(caps, fs, P)
    np.testing.assert_allclose(dt, (np.linalg.norm(P[1:] - src, axis=1)
                                    - np.linalg.norm(P[0] - src)) / 343.0, atol=3e-6)
    est = localize_one_mic(np.r_[0.0, dt], P)
    assert est.unique
    np.testing.assert_allclose(est.position_m, src, atol=0.05)


def test_each_pose_captures_truth_is_in_its_arrays_frame(pose_manifest):
    """Each capture's .json truth is what localizing that capture alone measures: the
    direction in the array's frame at its pose (as `hearsee simulate`'s of one recording),
    with the robot frame's position beside it. It was the robot frame's, unlabelled (a
    capture localized at -6 deg against its truth's 33.7)."""
    import json

    import soundfile as sf

    from hearsee.audio.active import load_pose_manifest
    from hearsee.audio.localize import localize_recording
    from hearsee.geometry import robot_to_array

    man, files, src = pose_manifest
    m = load_pose_manifest(man)
    for k, (f, pose) in enumerate(zip(files, m.poses, strict=True)):
        truth = json.loads(f.with_suffix(".json").read_text())
        np.testing.assert_allclose(truth["source_robot_m"], src)
        p = robot_to_array(src, pose, m.pivot_m, m.offset_m)
        np.testing.assert_allclose(truth["source_m"], p, atol=1e-12)
        assert truth["distance_m"] == pytest.approx(float(np.linalg.norm(p)))
        assert truth["tdoa_s"] == pytest.approx(m.truth["tdoa_s"][k], abs=1e-12)
        x, fs = sf.read(f, always_2d=True)
        loc = localize_recording(x.T, fs, "three-mic")
        az = loc["summary"]["azimuth_deg"]
        assert abs(float(np.degrees(np.angle(np.exp(1j * np.radians(
            az - truth["azimuth_deg"])))))) < 3.0


def test_localize3d_single_pose_reports_ambiguity(tmp_path, capsys):
    import json

    from hearsee.audio.active import simulate_pose_manifest
    from hearsee.cli import main

    src = [1.0, 0.8, 0.6]
    man, _ = simulate_pose_manifest(tmp_path / "one.yaml", "three-mic", src, [(0, 0)],
                                    duration_s=0.4, snr_db=30, seed=1)
    assert main(["localize3d", str(man)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["unique"] is False
    assert doc["distance_m"] is None and doc["position_m"] is None
    els = sorted(c["elevation_deg"] for c in doc["candidates"])
    el_true = float(np.degrees(np.arctan2(src[2], np.hypot(src[0], src[1]))))
    assert len(els) == 2 and els[0] < 0 < els[1]
    assert els[1] == pytest.approx(el_true, abs=4.0)


def test_simulate_pose_manifest_truth_of_a_source_at_the_pivot(tmp_path):
    """A source at the head pivot has no direction from it: the manifest's truth wrote
    azimuth and elevation 0.0 (each capture's own truth, ground_truth, says None for a source
    at its origin). Now None there too; a source 1 m above the pivot keeps 90 deg."""
    import yaml

    from hearsee.audio.active import simulate_pose_manifest

    pivot, off = [0.2, 0.0, 1.2], (0.1, 0.0, 0.0)
    man, _ = simulate_pose_manifest(tmp_path / "at.yaml", "three-mic", pivot, [(0, 0), (40, 20)],
                                    duration_s=0.3, pivot_m=pivot, offset_m=off)
    truth = yaml.safe_load(man.read_text())["truth"]
    assert truth["azimuth_deg"] is None and truth["elevation_deg"] is None
    assert truth["distance_m"] == 0.0
    man, _ = simulate_pose_manifest(tmp_path / "up.yaml", "three-mic", [0.2, 0.0, 2.2],
                                    [(0, 0)], duration_s=0.3, pivot_m=pivot, offset_m=off)
    truth = yaml.safe_load(man.read_text())["truth"]
    assert truth["elevation_deg"] == pytest.approx(90.0)
    assert truth["distance_m"] == pytest.approx(1.0)


def test_simulate_pose_manifest_checks_its_points(tmp_path):
    """source_m, pivot_m and offset_m went through np.asarray(float): True was read as 1 m and
    "0.1" as 0.1 m (a manifest written with the wrong geometry), a huge int was a builtin
    OverflowError. Each is a GeometryError naming the argument, before anything is written."""
    from hearsee.audio.active import simulate_pose_manifest

    good = {"source_m": [1.0, 0.8, 0.6], "pivot_m": (0.0, 0.0, 0.0), "offset_m": (0.1, 0.0, 0.0)}
    for name in good:
        for bad in ([True, 0.0, 0.0], ["0.1", 0.0, 0.0], [10**400, 0.0, 0.0], [0.1, 0.0]):
            kw = good | {name: bad}
            src = kw.pop("source_m")
            with pytest.raises(GeometryError, match=rf"^{name} must be a finite \[x, y, z\]"):
                simulate_pose_manifest(tmp_path / "m.yaml", "three-mic", src, [(0, 0)],
                                       duration_s=0.1, **kw)
    assert not list(tmp_path.iterdir())
    with pytest.raises(GeometryError, match=r"^offset_m: \[1e\+300, 0.0, 0.0\] is more than 1 m"):
        simulate_pose_manifest(tmp_path / "m.yaml", "three-mic", good["source_m"], [(0, 0)],
                               duration_s=0.1, offset_m=(1e300, 0.0, 0.0))  # (RuntimeWarnings)
    assert not list(tmp_path.iterdir())


def test_simulate_pose_manifest_interrupted_writes_nothing(tmp_path, monkeypatch):
    """Captures were written as each pose was rendered: a Ctrl-C during the third pose's
    render left two captures without a manifest and, with --force, an earlier manifest then
    named new captures beside old ones. Now everything is rendered first; an interruption
    leaves the folder (here: an earlier manifest and its captures) as it was."""
    import hearsee.audio.active as active
    import hearsee.sim.audio as sim_audio

    src = [1.0, 0.8, 0.6]
    man, files = active.simulate_pose_manifest(tmp_path / "m.yaml", "three-mic", src, POSES3,
                                               duration_s=0.1, seed=1)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert len(files) == 3 and len(before) == 7  # (3 WAVs, 3 truth JSONs, the manifest)
    real, calls = sim_audio.render, []

    def render(*a, **k):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(sim_audio, "render", render)  # (imported inside the function)
    with pytest.raises(KeyboardInterrupt):
        active.simulate_pose_manifest(man, "three-mic", [2.0, -1.0, 0.3], POSES3,
                                      duration_s=0.1, seed=2)
    assert len(calls) == 3
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_thesis_search_alignment_far_source():
    from hearsee.audio.active import align_head_search

    rng = np.random.default_rng(8)
    for src in ([2.0, 2.0, 1.2], [-3.0, 0.5, -0.8]):
        src = np.array(src)

        def measure(pose, src=src):
            return MicArray(mic_positions_at(ARR, pose)).tdoa(src) + rng.normal(0, 1e-6, 3)

        res = align_head_search(measure, ARR)
        assert res.converged  # (moves <= 8, asserted before, held by construction)
        assert res.error_deg(src) < 2.5
    with pytest.raises(GeometryError):
        align_head_search(lambda p: np.zeros(6),
                          MicArray([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]))
    # one baseline cannot give the in-plane direction (it swung the pan 0 <-> 90 deg)
    with pytest.raises(GeometryError, match="non-collinear"):
        align_head_search(lambda p: np.zeros(1), load_array("two-mic"))


def test_thesis_search_names_a_non_finite_measurement():
    """A NaN TDOA from measure() made the least-squares pan NaN, and the error named the pose
    it was turned into ("HeadPose.pan_deg must be finite, got nan"), not the measurement. It
    now names the pose measured, the pair and the value."""
    from hearsee.audio.active import align_head_search
    from hearsee.errors import AudioInputError

    src = np.array([2.0, 2.0, 1.2])
    calls = []

    def measure(pose):
        tau = MicArray(mic_positions_at(ARR, pose)).tdoa(src)
        calls.append(pose)
        if len(calls) == 2:
            tau[2] = np.nan
        return tau

    with pytest.raises(AudioInputError) as e:
        align_head_search(measure, ARR)
    msg = str(e.value)
    assert f"measure({calls[1]}) returned TDOA nan for pair {ARR.pairs[2]}" in msg
    assert len(calls) == 2 and calls[1].pan_deg != 0.0  # (the second pose, not the start)


@pytest.mark.parametrize("got", ["abc", ["1e-4", "2e-4", "x"], None, {"0-1": 1e-4}])
def test_alignment_refuses_a_measurement_that_is_no_numbers(got):
    """measure() returning text or a mapping was a builtin ValueError / TypeError inside both
    alignment loops; numeric strings were read as TDOAs. One AudioInputError names it."""
    from hearsee.audio.active import align_head, align_head_search
    from hearsee.errors import AudioInputError

    for loop in (align_head, align_head_search):
        with pytest.raises(AudioInputError, match=r"measure\(\) must return one TDOA"):
            loop(lambda pose: got, ARR)


def _search_a_random_source(rng, el_lo: float, el_hi: float):
    """A source at a random azimuth, an elevation in [el_lo, el_hi] deg and 1-4 m from the
    pivot (built here from the angles), and the thesis search's alignment to it from exact
    TDOAs, level start: ``(az, el, source, result)``."""
    from hearsee.audio.active import align_head_search

    az, el, r = rng.uniform(-180, 180), rng.uniform(el_lo, el_hi), rng.uniform(1.0, 4.0)
    src = r * np.array([np.cos(np.radians(el)) * np.cos(np.radians(az)),
                        np.cos(np.radians(el)) * np.sin(np.radians(az)),
                        np.sin(np.radians(el))])
    res = align_head_search(lambda pose: MicArray(mic_positions_at(ARR, pose)).tdoa(src), ARR)
    return az, el, src, res


def test_thesis_search_alignment_nearby_sources():
    """Sources 1-4 m away: the curved wavefront puts |u_xy| a little above 1 at every tilt
    near the right one; clipped at 1 those samples tied and the search stopped up to ~5 deg
    off while saying it had converged. Exact TDOAs, random sources."""
    rng = np.random.default_rng(12)
    errs = []
    for _ in range(20):
        _, _, src, res = _search_a_random_source(rng, -30.0, 40.0)
        errs.append(res.error_deg(src))
    assert max(errs) < 1.0 and np.median(errs) < 0.3


@pytest.mark.parametrize("az", [30.0, 90.0, 150.0])
@pytest.mark.parametrize("r", [2.0, 20.0])
def test_thesis_search_alignment_level_source(az, r):
    """A source level with the head (a talker at its height), left or behind: the search
    settled the pan at tilt 0, tried +-12 deg and came back to tilt 0 -- the source exactly --
    then fitted its parabola through the two samples at tilt 0 and 2.5e-11 deg (numpy's
    RankWarning), went to 6 deg and halved its way back, ending 1.5 deg off with
    converged=True (tol_deg 1). Exact TDOAs, the source built from its angles."""
    import warnings

    from hearsee.audio.active import align_head_search

    src = r * np.array([np.cos(np.radians(az)), np.sin(np.radians(az)), 0.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (the RankWarning)
        res = align_head_search(lambda pose: MicArray(mic_positions_at(ARR, pose)).tdoa(src),
                                ARR)
    assert res.converged
    assert res.error_deg(src) < 0.1
    assert abs(res.final_pose.tilt_deg) < 0.1


@pytest.mark.parametrize("r", [25.0, 40.0, 100.0])
def test_multipose_distance_at_the_far_search_bound_is_not_reported(r):
    """A source beyond the solver's distance range (20 m): the refined distance stopped at
    the bound, and with a head offset of 0.6 m its relative 1-sigma was 0.23-0.36, so the
    answer was "20.0 m, unique" for sources 25-100 m away. A distance held at the bound is
    only a lower bound: no distance, the far-field direction. Exact TDOAs, the source built
    from its angles; one inside the range keeps its distance."""
    poses = [(0, 0), (90, 30), (-90, -30), (180, 0)]
    off = (0.6, 0.0, 0.3)
    u = np.array([np.cos(np.radians(10)) * np.cos(np.radians(30)),
                  np.cos(np.radians(10)) * np.sin(np.radians(30)), np.sin(np.radians(10))])

    def solve(dist):
        tau = [MicArray(mic_positions_at(ARR, p, offset_m=off)).tdoa(dist * u) for p in poses]
        return localize_multipose(tau, poses, ARR, offset_m=off)

    est = solve(r)
    assert est.distance_m is None and est.position_m is None and not est.unique
    assert est.distance_rel_std == np.inf
    assert np.degrees(angle_between(est.direction, u)) < 0.5
    near = solve(10.0)
    assert near.unique and near.distance_m == pytest.approx(10.0, rel=1e-3)


def test_simulate_poses_cli_writes_manifest(tmp_path, capsys):
    import json

    from hearsee.cli import main

    man = tmp_path / "cap.yaml"
    args = ["simulate", str(man), "--array", "three-mic", "--source", "1.0,-0.8,0.5",
            "--poses", "0,0;40,25;-40,-20", "--head-offset", "0.2,0,0.1", "--duration", "0.5",
            "--snr", "30", "--seed", "4"]
    assert main(args) == 0
    assert man.is_file() and (tmp_path / "cap_pose2.wav").is_file()
    capsys.readouterr()
    assert main(["localize3d", str(man)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["unique"] is True
    np.testing.assert_allclose(doc["position_m"], [1.0, -0.8, 0.5], atol=0.1)
    # bad pose list and a non-manifest output name: one clear line, exit 2
    assert main(args[:7] + ["0,0;45", "--duration", "0.2"]) == 2
    assert "--poses" in capsys.readouterr().err
    assert main(["simulate", str(tmp_path / "x.wav")] + args[2:]) == 2
    assert "manifest" in capsys.readouterr().err


def test_thesis_search_from_the_upper_tilt_limit_tries_downward():
    """A head at its upper tilt limit cannot make the search's first (upward) tilt try: the
    clipped move was zero, which read as 'both corrections below tol_deg', and the search
    stopped at once with converged=True, 75 deg above a source straight ahead. Exact TDOAs,
    sources in the pan direction; the first try now goes downward, and a source above the
    limit still ends at the limit."""
    from hearsee.audio.active import align_head_search

    for src, tilt in (([2.0, 0.0, 0.0], None), ([3.0, 0.0, 1.0], None), ([0.3, 0.0, 2.0], 75.0)):
        src = np.array(src)

        def measure(pose, src=src):
            return MicArray(mic_positions_at(ARR, pose)).tdoa(src)

        res = align_head_search(measure, ARR, start=(0.0, 75.0))
        assert res.converged and res.moves >= 2
        if tilt is None:
            assert res.error_deg(src) < 1.0
        else:  # 81 deg up: the head stays at its limit
            assert res.final_pose.tilt_deg == pytest.approx(tilt)


def test_train_pose_mlp_needs_min_mlp_samples_before_simulating(monkeypatch):
    """n = 1 .. 19 passed the argument check and failed in PoseItdMLP.fit, after the training
    set was simulated, with an EstimationError about fit's samples; now the argument error
    names n and the minimum before any simulation."""
    from hearsee.audio import active
    from hearsee.errors import GeometryError

    def simulate(*args, **kwargs):
        raise AssertionError("simulated before n was checked")

    monkeypatch.setattr(active, "make_pose_training_set", simulate)
    for n in (1, active.MIN_MLP_SAMPLES - 1):
        with pytest.raises(GeometryError, match=rf"^n \(training samples\) must be an integer "
                                                rf">= {active.MIN_MLP_SAMPLES}, got {n}$"):
            train_pose_mlp("three-mic", [(0.0, 0.0), (0.0, 30.0)], n=n)
    monkeypatch.undo()
    mlp = train_pose_mlp("three-mic", [(0.0, 0.0), (0.0, 30.0)], n=active.MIN_MLP_SAMPLES,
                         hidden_layer_sizes=(4,))
    assert mlp.predict(np.zeros((1, 6))).shape == (1, 3)


def test_train_pose_mlp_checks_its_settings_before_the_cache_key():
    """The cache key converted them first: float() read True as 1 m (a pivot 1 m off, trained
    without a word), int() 2.5 training samples as 2 and -1 as an empty set."""
    from hearsee.errors import GeometryError

    poses = [(0.0, 0.0), (0.0, 30.0)]
    for kw, what in [({"pivot_m": (True, 0.0, 0.0)}, "pivot_m"),
                     ({"offset_m": ("0.1", 0.0, 0.0)}, "offset_m"),
                     ({"n": 2.5}, "n \\(training samples\\)"), ({"n": 0}, "n \\(training"),
                     ({"tdoa_std_s": True}, "tdoa_std_s"), ({"seed": -1}, "seed")]:
        with pytest.raises(GeometryError, match=f"^{what}"):
            train_pose_mlp("three-mic", poses, **kw)


def test_a_head_pivot_is_a_point_of_the_robot(tmp_path):
    """A pivot 1e300 m from the robot-frame origin put all microphones on one float (their
    centimetres below its resolution): localize_multipose returned a wrong direction, flagged
    only as inconsistent (one 1e308 m away ran for minutes). The pivot must be within 10 m
    (geometry.check_head_pivot); one there localizes as one at the origin does."""
    from hearsee.audio.active import localize_manifest, pose_mic_positions, simulate_pose_manifest

    arr = load_array("three-mic")
    src = np.array([1.5, 0.9, 0.4])
    poses = [(0.0, 0.0), (40.0, 25.0), (-40.0, -20.0)]
    for pivot in ([1e300, 0.0, 0.0], [0.0, 0.0, 10.01]):
        taus = [MicArray(m).tdoa(src) for m in pose_mic_positions(arr, poses)]
        with pytest.raises(GeometryError, match=r"^pivot_m: \[.*\] is more than 10 m from the "
                                                "robot-frame origin"):
            localize_multipose(taus, poses, arr, pivot_m=pivot)
        with pytest.raises(GeometryError, match="^pivot_m: .* more than 10 m"):
            simulate_pose_manifest(tmp_path / "m.yaml", arr, src, poses, duration_s=0.1,
                                   pivot_m=pivot)
    pivot = np.array([0.0, 6.0, 8.0])  # 10 m: still a pivot
    man, _ = simulate_pose_manifest(tmp_path / "m.yaml", arr, pivot + src, poses,
                                    duration_s=0.5, seed=2, pivot_m=pivot)
    est = localize_manifest(man)
    np.testing.assert_allclose([est.azimuth_deg, est.elevation_deg], direction_deg(src),
                               atol=2.0)


def test_range_difference_solvers_refuse_what_is_no_number():
    """The range-difference solvers converted their inputs with numpy and compared them:
    text, a ragged list, a pair of text or of three numbers, a 2.5 grid size were numpy's or
    Python's builtin errors (or read as numbers). Each is now a GeometryError naming what was
    wrong; a distant source in a known direction is still found from the same geometry."""
    from hearsee.audio.active import one_mic_arrival_differences
    from hearsee.geometry import unit_vector_deg

    M = ARR.positions
    prs = [(0, 1), (0, 2), (1, 2)]
    tau = MicArray(M).tdoa_far(unit_vector_deg(26.5, 15.0))  # a plane wave
    good = dict(mic_sets=[M], pairs=[prs], tdoa_s=[tau])
    bad = [
        (dict(pairs=[[("a", 1), (0, 2), (1, 2)]]), "pairs must be"),
        (dict(pairs=[[(0, 1, 2), (0, 2), (1, 2)]]), "pairs must be"),
        (dict(pairs=[5]), "pairs must be"),
        (dict(tdoa_s=[["x", 0.0, 0.0]]), "TDOAs: expected numbers"),
        (dict(mic_sets=[[[0, 0, 0], [1, 0]]]), "microphone positions: expected numbers"),
        (dict(reference_m="origin"), "reference_m"),
        (dict(f_scale="3"), "f_scale must be a finite number"),
        (dict(n_directions=2.5), "n_directions must be an integer"),
        (dict(tdoa_std_s="1e-5"), "tdoa_std_s must be a finite number in"),
        (dict(distance_bounds_m=("a", 5.0)), "distance_bounds_m: expected numbers"),
        (dict(distance_bounds_m=(0.2, 5.0, 9.0)), "distance_bounds_m must be 0 < min < max"),
    ]
    for change, match in bad:
        kw = {**good, **change}
        with pytest.raises(GeometryError, match=match):
            solve_range_differences(kw.pop("mic_sets"), kw.pop("pairs"), kw.pop("tdoa_s"),
                                    **kw)
    est = solve_range_differences(**good, distance_bounds_m=np.array([0.2, 5.0]),
                                  n_directions=np.int64(400))
    # (one planar pose: the azimuth is determined, the elevation's sign is not)
    assert est.azimuth_deg == pytest.approx(26.5, abs=0.2)
    assert abs(est.elevation_deg) == pytest.approx(15.0, abs=0.2)
    with pytest.raises(GeometryError, match="arrival_times_s: expected numbers"):
        localize_one_mic(["0.1", 0.2, 0.3, 0.4], np.eye(4, 3))
    with pytest.raises(GeometryError, match="mic_positions_m: expected numbers"):
        localize_one_mic([0.1, 0.2, 0.3, 0.4], "square")
    with pytest.raises(GeometryError, match="one \\[x, y, z\\] position per capture"):
        one_mic_arrival_differences([np.zeros(64), np.zeros(64)], 16000, 1.0)
    with pytest.raises(AudioInputError, match="capture 1"):
        one_mic_arrival_differences([np.zeros(64), ["a"] * 64], 16000, np.eye(2, 3))


def test_alignment_to_a_source_straight_ahead_is_not_held_by_a_near_field_ghost():
    """A talker 1 m straight ahead of a level head (array 0.1 m ahead of the pivot, 5 us TDOA
    noise): after the level capture and the 20-deg probe, the pooled solve keeps two candidates
    -- the talker and a ghost 0.2 m away at about +20 deg elevation, where the head already is.
    The loop aimed at the upper candidate, the pose already held, and re-measured it for every
    move (7 of these 10 seeds ended 25 deg off, converged False). Now a held candidate is
    skipped, and when both are held the head looks from below them."""
    pivot = np.array([0.0, 0.0, 1.2])
    src = pivot + np.array([1.0, 0.0, 0.0])
    for seed in range(10):
        rng = np.random.default_rng(seed)

        def measure(pose, rng=rng):
            m = MicArray(mic_positions_at(ARR, pose, pivot, OFF))
            return m.tdoa(src) + rng.normal(0.0, 5e-6, 3)

        res = align_head(measure, ARR, pivot_m=pivot, offset_m=OFF)
        assert res.converged, seed
        assert res.error_deg(src, pivot, OFF) < 3.0, seed


def test_thesis_search_finds_a_source_far_below_a_level_start():
    """Sources 46-60 deg below a level head (inside the tilt limits): the search's first tilt
    try (upward, by the elevation's size) puts such a source behind the head, which read as a
    180-deg pan error -- the head spun 3.5 turns without tilting, 0 of 60 converged. Now a
    tilt try that turns the source behind goes back and down."""
    rng = np.random.default_rng(7)
    for _ in range(12):
        az, el, src, res = _search_a_random_source(rng, -60.0, -46.0)
        assert res.converged and res.error_deg(src) < 1.5, (az, el)
        assert abs(res.final_pose.pan_deg - az) < 360.0


def test_infinite_tdoa_and_a_second_speed_of_sound_are_refused():
    """An infinite TDOA was dropped as if the pair had not been measured (only NaN means
    that); a speed_of_sound keyword raised Python's "multiple values" TypeError."""
    src = np.array([1.0, 0.5, 0.3])
    poses = [(0, 0), (40, 20), (-40, -15)]
    taus = true_tdoas(ARR, src, poses)
    taus[1] = taus[1].copy()
    taus[1][0] = np.inf
    with pytest.raises(EstimationError, match=r"pose 1: TDOA of pair \(0, 1\) is inf"):
        localize_multipose(taus, poses, ARR, offset_m=OFF)
    taus[1][0] = np.nan  # not measured: fine
    assert localize_multipose(taus, poses, ARR, offset_m=OFF).position_m is not None
    with pytest.raises(ConfigError, match="speed of sound from the array"):
        localize_multipose(true_tdoas(ARR, src, poses), poses, ARR, offset_m=OFF,
                           speed_of_sound=340.0)


def test_alignment_settings_are_checked():
    from hearsee.audio.active import align_head_search

    # found in the 2026-12-02 audit: reversed tilt limits (60, -60) clipped every tilt to
    # -60 deg and align_head ended "converged" there, ~80 deg from a source 19 deg up; a NaN
    # tolerance never converged (8 moves), a NaN probe aimed at a NaN tilt, text tilt limits
    # raised numpy's UFuncTypeError, max_moves=2.5 was taken
    src = np.array([1.2, 0.8, 0.5])

    def measure(pose):
        return MicArray(mic_positions_at(ARR, pose, offset_m=OFF)).tdoa(src)

    for kw, msg in (({"tilt_limits_deg": (60.0, -60.0)}, "tilt_limits_deg"),
                    ({"tilt_limits_deg": (-100.0, 60.0)}, "tilt_limits_deg"),
                    ({"tilt_limits_deg": "ab"}, "tilt_limits_deg"),
                    ({"tol_deg": np.nan}, "tol_deg"), ({"probe_deg": np.nan}, "probe_deg"),
                    ({"max_moves": 2.5}, "max_moves"), ({"max_moves": -1}, "max_moves")):
        with pytest.raises(GeometryError, match=msg):
            align_head(measure, ARR, offset_m=OFF, **kw)
        with pytest.raises(GeometryError, match=msg):
            align_head_search(measure, ARR, **kw)
    with pytest.raises(GeometryError, match="max_std_deg"):
        align_head(measure, ARR, offset_m=OFF, max_std_deg=np.nan)
    # valid settings: as before
    res = align_head(measure, ARR, offset_m=OFF, tilt_limits_deg=(-60.0, 60.0), max_moves=8)
    assert res.converged and res.error_deg(src, offset_m=OFF) < 0.05


def test_solver_settings_are_checked():
    # found in the 2026-12-02 audit: the solver's gates were used unchecked. A NaN
    # max_residual_rms_s called exact TDOAs inconsistent, a NaN max_rel_distance_std never
    # reported the distance, a NaN min_separation_deg refined a single start; text raised
    # builtin TypeErrors / ValueErrors
    src = np.array([1.2, 0.8, 0.5])
    poses = [(0, 0), (40, 25), (-40, -20)]
    tau = [MicArray(mic_positions_at(ARR, p, offset_m=OFF)).tdoa(src) for p in poses]
    for name in ("min_separation_deg", "ambiguity_gate", "ambiguity_ratio",
                 "max_rel_distance_std", "max_residual_rms_s"):
        for bad in (np.nan, -1.0, "a"):
            with pytest.raises(GeometryError, match=name):
                localize_multipose(tau, poses, ARR, offset_m=OFF, **{name: bad})
    # valid settings: as before, inf meaning no limit
    for kw in ({}, {"max_rel_distance_std": np.inf, "max_residual_rms_s": np.inf}):
        est = localize_multipose(tau, poses, ARR, offset_m=OFF, **kw)
        assert est.unique and est.consistent
        np.testing.assert_allclose(est.position_m, src, atol=1e-3)


def test_training_set_ranges_of_the_wrong_form_are_geometry_errors():
    # found in the 2026-12-02 audit: a range given as text or as three numbers raised a
    # builtin ValueError ("could not convert string to float", "too many values to unpack")
    # or numpy's TypeError (isfinite of text)
    from hearsee.audio.active import make_pose_training_set

    poses = [(0, 0), (40, 25)]
    for kw in ({"distance_range_m": ("a", 2.0)}, {"distance_range_m": (1.0, 2.0, 3.0)},
               {"azimuth_range_deg": ("a", 2.0)}, {"elevation_range_deg": (0.0,)},
               {"elevation_range_deg": 10.0}):
        with pytest.raises(GeometryError, match=next(iter(kw))):
            make_pose_training_set(ARR, poses, 10, **kw)
    X, Y = make_pose_training_set(ARR, poses, 10)
    assert X.shape == (10, 6) and Y.shape == (10, 3)


def test_aim_at_puts_the_point_on_the_array_axis_for_a_large_offset():
    """_aim_at, the pose align_head aims with: the point must lie on the array's +x axis.
    Five fixed-point iterations on the pose-dependent array origin left it 0.01-2.5 deg off
    for points 0.5-0.9 m away with the array 0.2 m ahead of and 0.1 m above the pivot, and up
    to 28 deg for one below the head (found 2026-12-02); the pose is now solved."""
    from hearsee.audio.active import _aim_at
    from hearsee.geometry import robot_to_array, unit_vector_deg

    pivot, offset = np.array([0.0, 0.0, 1.2]), np.array([0.2, 0.0, 0.1])
    rng = np.random.default_rng(0)
    # azimuths all round, elevations within the usual tilt limits (+-60 deg)
    dirs = unit_vector_deg(rng.uniform(-180, 180, 60), rng.uniform(-60, 60, 60))
    pts = pivot + dirs * rng.uniform(0.5, 0.9, (60, 1))
    pts = np.vstack([pts, pivot + [0.032, -0.117, -0.735]])  # (28 deg off before)
    for p in pts:
        az, el = _aim_at(p, pivot, offset)
        q = robot_to_array(p, (az, el), pivot, offset)
        assert q[0] > 0
        assert np.degrees(np.arctan2(np.hypot(q[1], q[2]), q[0])) < 1e-6, p


def test_simulate_pose_manifest_needs_a_path(tmp_path):
    """None was a builtin TypeError."""
    from hearsee.audio.active import simulate_pose_manifest
    from hearsee.errors import InputFileError

    with pytest.raises(InputFileError, match="manifest's path must be a file name"):
        simulate_pose_manifest(None, "three-mic", [2, 1, 0], [(0, 0), (45, 0)])


def test_poses_tdoas_and_offsets_of_the_wrong_kind_are_geometry_errors():
    """From an API audit: None or a number for the poses or the TDOAs raised builtin
    TypeErrors, an empty pose list numpy's "need at least one array", an array offset of
    1e160 m scipy's "residuals are not finite" (1e100: a result of cost inf)."""
    from hearsee.audio.active import pose_mic_positions

    arr = MicArray.from_preset("three-mic")
    poses = [(0.0, 0.0), (40.0, 20.0)]
    tau = [arr.tdoa([1.0, 0.5, 0.3])] * 2
    for bad in (None, 3.0, "0,0"):
        with pytest.raises(GeometryError, match="poses must be a sequence"):
            pose_mic_positions(arr, bad)
        with pytest.raises(GeometryError, match="poses must be a sequence"):
            localize_multipose(tau, bad, arr)
        with pytest.raises(GeometryError, match="tdoa_s must be one TDOA vector"):
            localize_multipose(bad, poses, arr)
    for empty in ([], ()):
        with pytest.raises(GeometryError, match="at least one head pose"):
            make_pose_training_set(arr, empty, 5)
    for far in ((1e160, 0.0, 0.0), (1e100, 0.0, 0.0)):
        with pytest.raises(GeometryError, match="offset_m"):
            localize_multipose(tau, poses, arr, offset_m=far)
    assert len(pose_mic_positions(arr, np.array(poses))) == 2


def test_pose_mlp_scores_and_predicts_only_numbers():
    """``score`` with an all-NaN Y answered NaN (fit refuses it); text TDOAs were numpy's
    ValueError in predict."""
    arr = MicArray.from_preset("three-mic")
    poses = [(0.0, 0.0), (60.0, 20.0)]
    X, Y = make_pose_training_set(arr, poses, 60, rng=3)
    mlp = PoseItdMLP(hidden_layer_sizes=(8,), max_iter=50, random_state=0,
                     tdoa_scale_s=arr.aperture / arr.speed_of_sound).fit(X, Y)
    assert np.isfinite(mlp.score(X, Y))
    with pytest.raises(EstimationError, match=r"PoseItdMLP.score needs finite"):
        mlp.score(X, np.full_like(Y, np.nan))
    with pytest.raises(EstimationError, match=r"PoseItdMLP.predict needs TDOAs"):
        mlp.predict("abc")


@pytest.mark.parametrize("poses", [[(0, 0)], [(0, 0), (0, 0)], [(0, 0), (0, 30), (0, -30)],
                                   [(20, 0), (20, 0), (20, 0)]])
def test_a_cone_of_directions_has_no_finite_direction_std(poses):
    """One microphone pair, at one pose or turned only about its own axis (two-mic's tilt is
    about the pair's y axis), fixes only a cone of directions: its direction 1-sigma is
    infinite. The 2x2 matrix of the far-field direction was inverted in floating point: 0.0
    deg for tilts 0, +-30 (a cone called exact; ``hearsee localize3d`` printed it) and 1.3e8
    deg for the single pose."""
    two = load_array("two-mic")
    src = np.array([1.0, 0.6, 0.4])
    est = localize_multipose(true_tdoas(two, src, poses, offset=(0, 0, 0)), poses, two)
    assert not est.unique and len(est.candidates) > 2
    assert est.direction_std_deg == np.inf
    # a determined direction keeps its finite 1-sigma (pan turns the pair: two mirror cones)
    one = localize_multipose(true_tdoas(ARR, src, [(0, 0)], offset=(0, 0, 0)), [(0, 0)], ARR)
    assert one.direction_std_deg == pytest.approx(1.7134, abs=1e-3)


def test_one_microphone_moved_along_a_line_claims_no_covariance():
    """One microphone moved along a line hears a circle of sources about it (every point of
    the circle has the same range differences): J^T J is singular in all but rounding, which
    np.linalg.inv took -- a covariance with an eigenvalue of -1.2e12 m^2, a direction 1-sigma
    of 0.0 deg and one point of the circle as the position. Unknown instead (the far-field cone
    of directions, each on it)."""
    src = np.array([1.2, -0.7, 0.5])
    P = np.array([[0, 0, 0], [0.1, 0, 0], [0.25, 0, 0], [0.4, 0, 0], [0.6, 0, 0]], float)
    est = localize_one_mic(np.linalg.norm(src - P, axis=1) / 343.0, P)
    assert est.covariance is None and est.position_m is None and not est.unique
    assert est.direction_std_deg == np.inf and est.distance_rel_std == np.inf
    # every candidate direction lies on the cone of the source's angle to the line
    cone = np.degrees(np.arccos((src - P.mean(axis=0))[0] / np.linalg.norm(src - P.mean(0))))
    for c in est.candidates:
        u = unit_vector_deg(c["azimuth_deg"], c["elevation_deg"])
        assert np.degrees(np.arccos(u[0])) == pytest.approx(cone, abs=1.0)
    # a virtual array spanning 3D still gives the point and a positive covariance
    P3 = np.array([[0, 0, 0], [0.3, 0, 0], [0, 0.3, 0], [0, 0, 0.3], [0.2, 0.2, 0.2]], float)
    est = localize_one_mic(np.linalg.norm(src - P3, axis=1) / 343.0, P3)
    np.testing.assert_allclose(est.position_m, src, atol=1e-3)
    assert np.all(np.linalg.eigvalsh(est.covariance) > 0)


def test_simulated_poses_sources_and_pose_functions_of_the_wrong_kind_are_geometry_errors():
    """simulate_pose_captures read its source with np.asarray (True as 1 m, "0.5" as 0.5 m,
    text numpy's ValueError) and iterated its poses (None a builtin TypeError, [] no capture);
    a pose where the turning head's function of time belongs was called: "'tuple' object is not
    callable"; train_pose_mlp's poses None, a TypeError."""
    sig = white_noise(0.2, 8000, 0)
    with pytest.raises(GeometryError, match="source_m"):
        simulate_pose_captures(sig, 8000, ARR, [True, 0.0, 0.0], [(0, 0)])
    with pytest.raises(GeometryError, match="source_m"):
        simulate_pose_captures(sig, 8000, ARR, "abc", [(0, 0)])
    with pytest.raises(GeometryError, match="poses must be a sequence"):
        simulate_pose_captures(sig, 8000, ARR, [1.0, 0.5, 0.2], None)
    with pytest.raises(GeometryError, match="at least one head pose"):
        simulate_pose_captures(sig, 8000, ARR, [1.0, 0.5, 0.2], [])
    with pytest.raises(GeometryError, match="pose_at must be a function"):
        simulate_turning_capture(sig, 8000, ARR, [1.0, 0.5, 0.2], (0, 0))
    with pytest.raises(GeometryError, match="pose_at must be a function"):
        localize_continuous(np.zeros((3, 8000)), 8000, ARR, (0, 0))
    with pytest.raises(GeometryError, match="poses must be a sequence"):
        train_pose_mlp(ARR, None, n=20)
    # the right kinds still simulate the exact delays: the source in the robot frame
    src = np.array([1.0, 0.5, 0.2])
    x = simulate_pose_captures(white_noise(0.5, 16000, 1), 16000, ARR, src, [(30, 10)])[0]
    tau = capture_tdoas(x, 16000, ARR)
    np.testing.assert_allclose(tau, true_tdoas(ARR, src, [(30, 10)], offset=(0, 0, 0))[0],
                               atol=2e-5)


def test_localize3d_names_the_manifests_channels_for_a_capture_of_other_channels(
        pose_manifest, tmp_path, capsys):
    """A capture with more channels than the array's microphones was refused with the remedy
    "choose the microphones' with --channels": an option of `hearsee localize` that localize3d
    has not (typer's "No such option"); the manifest's channels key is the remedy there, and
    with it the same captures localize."""
    import json

    import soundfile as sf
    import yaml

    from hearsee.cli import main

    man, files, src = pose_manifest
    doc = yaml.safe_load(man.read_text())
    for k, c in enumerate(doc["captures"]):  # a device's 4 channels: its playback first
        x, fs = sf.read(files[k], dtype="float32")
        wide = np.column_stack([0.01 * x[:, 0], x])
        c["file"] = str(tmp_path / f"wide{k}.wav")
        sf.write(c["file"], wide, fs, subtype="FLOAT")
    bad = tmp_path / "wide.yaml"
    bad.write_text(yaml.safe_dump(doc))
    assert main(["localize3d", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "has 4 channels" in err[0]
    assert "--channels" not in err[0] and "the manifest's channels: list" in err[0]
    doc["channels"] = [1, 2, 3]
    bad.write_text(yaml.safe_dump(doc))
    assert main(["localize3d", str(bad)]) == 0
    got = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(got["position_m"], src, atol=0.05)
