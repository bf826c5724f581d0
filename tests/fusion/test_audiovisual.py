import numpy as np
import pytest

from hearsee.audio.arrays import MicArray
from hearsee.errors import EstimationError, GeometryError
from hearsee.fusion.audiovisual import (
    RAY_COVARIANCE_SCALE,
    RAY_SIGMA_TDOA_S,
    AudioVisualRegressor,
    AudioVisualRig,
    RayFix,
    RayTdoaTracker,
    RayTracker,
    frame_fix,
    locate_on_ray,
    ray_residuals,
    simulate_av_samples,
    track_on_rays,
)
from hearsee.vision.camera import Camera


@pytest.fixture(scope="module")
def rig():
    arr = MicArray.from_preset("three-mic")
    K = np.array([[500.0, 0, 330.0], [0, 505.0, 235.0], [0, 0, 1]])
    cam = Camera(K, np.array([-0.12, 0.05, 0.001, -0.0005, 0.0]), 640, 480)
    return AudioVisualRig.mounted(arr, cam, (0.05, 0.0, 0.12), pan_deg=5.0, tilt_deg=-3.0)


def test_rig_projection_roundtrip(rig):
    p = np.array([[1.5, 0.3, -0.1], [0.8, -0.2, 0.2]])
    uv = rig.project(p)
    o, d = rig.rays(uv)
    # the rays pass through the points
    v = p - o
    cross = np.cross(v, d)
    assert np.abs(cross).max() < 1e-6
    np.testing.assert_allclose(o, [0.05, 0.0, 0.12], atol=1e-12)


@pytest.mark.parametrize("point", [[0.6, 0.1, 0.0], [1.5, -0.4, 0.3], [2.8, 0.5, -0.2]])
def test_noise_free_ray_and_itds_give_the_exact_position(rig, point):
    p = np.array(point)
    uv = rig.project(p)[0]
    fix = locate_on_ray(rig, uv, rig.array.tdoa(p))
    assert np.linalg.norm(fix.position_m - p) < 1e-3
    assert fix.residual_s < 1e-8 and fix.consistent
    # TDOAs of the other sign (a pair written j - i) meet the ray nowhere: the least-bad
    # point came out like any fix until it was flagged
    bad = locate_on_ray(rig, uv, -rig.array.tdoa(p))
    assert not bad.consistent and bad.residual_s > 6 * 2e-5
    # the covariance is elongated along the ray (ITDs fix range poorly, the pixel fixes bearing)
    w, V = np.linalg.eigh(fix.covariance)
    assert abs(V[:, -1] @ fix.direction) > 0.99
    assert w[-1] > 10 * w[0]


def test_cost_along_ray_has_its_minimum_at_the_source(rig):
    p = np.array([1.2, 0.2, 0.1])
    o, d = rig.rays(rig.project(p))
    s_true = np.linalg.norm(p - o)
    s = np.linspace(0.3, 4.0, 500)
    J = np.sum(ray_residuals(rig.array, o, d[0], s, rig.array.tdoa(p)) ** 2, axis=1)
    assert s[np.argmin(J)] == pytest.approx(s_true, abs=0.01)


def test_ray_residuals_refuses_arguments_of_other_shapes(rig):
    """A direction of 2 numbers, an origin of 4, ranges (1, 2) or 2 TDOAs for 3 pairs raised
    numpy's builtin broadcast ValueError; now GeometryErrors. The residuals of valid arguments
    are the TDOAs of the points on the ray minus the measured ones, pair by pair."""
    arr = rig.array
    o, d = np.array([0.05, 0.0, 0.12]), np.array([0.6, 0.8, 0.0])
    z = arr.tdoa(o + 1.5 * d)
    for kw, match in (({"direction": [1.0, 0.0]}, r"origin and direction .* \(3,\) and \(2,\)"),
                      ({"origin": [0.0, 0.0, 0.0, 0.0]}, r"got \(4,\) and \(3,\)"),
                      ({"direction": d[None, :]}, r"\(1, 3\)"),
                      ({"s": [[1.0, 2.0]]}, r"s must be one range"),
                      ({"tdoa_s": z[:2]}, "got 2 TDOAs for 3 microphone pairs"),
                      ({"tdoa_s": np.r_[z, 0.0]}, "got 4 TDOAs for 3 microphone pairs"),
                      ({"tdoa_s": z, "pairs": [(0, 1)]}, "got 3 TDOAs for 1 microphone pairs"),
                      # (a zero direction put every range at the origin, without a word)
                      ({"direction": [0.0, 0.0, 0.0]}, "direction a finite, non-zero vector"),
                      ({"origin": [0.0, np.inf, 0.0]}, "origin must be finite")):
        args = {"array": arr, "origin": o, "direction": d, "s": [1.0], "tdoa_s": z, **kw}
        with pytest.raises(GeometryError, match=match):
            ray_residuals(**args)
    F = ray_residuals(arr, o, d, [1.0, 1.5], z)
    np.testing.assert_allclose(F, [arr.tdoa(o + d) - z, np.zeros(3)], rtol=0, atol=1e-15)
    F1 = ray_residuals(arr, o, d, 1.0, z[:1], pairs=[arr.pairs[0]])
    np.testing.assert_allclose(F1, [arr.tdoa(o + d)[:1] - z[:1]], rtol=0, atol=1e-15)


def test_itd_noise_gives_errors_mostly_along_the_ray(rig):
    rng = np.random.default_rng(0)
    p = np.array([1.0, 0.1, 0.0])
    uv = rig.project(p)[0]
    errs = []
    for _ in range(30):
        z = rig.array.tdoa(p) + 3e-6 * rng.standard_normal(3)
        errs.append(locate_on_ray(rig, uv, z).position_m - p)
    errs = np.array(errs)
    o, d = rig.rays(uv[None])
    along = errs @ d[0]
    across = np.linalg.norm(errs - along[:, None] * d[0], axis=1)
    assert np.std(along) > 5 * across.max()


def test_a_wrongly_told_camera_position_moves_the_fix_but_not_the_itd_residual():
    """Why hearsee cannot flag a wrong --camera-at: with exact TDOAs and pixels, a camera told
    10 cm off sideways puts the fix 0.4-1 m along the ray while the three TDOAs still fit a
    point on that ray to within 0.1 sample at 16 kHz (rooms leave more than that on a correct
    rig; bench/mounting.py)."""
    cam = Camera.from_fov(70.0, 640, 480)
    arr = MicArray.from_preset("three-mic")
    true = AudioVisualRig.mounted(arr, cam, (0.0, 0.2, 0.0))
    for p in ([1.5, 0.3, 0.1], [1.0, -0.3, -0.1], [1.8, 0.5, 0.0]):
        p = np.array(p)
        uv, z = true.project(p)[0], arr.tdoa(p)
        exact = locate_on_ray(true, uv, z)
        assert np.linalg.norm(exact.position_m - p) < 1e-3
        for dy in (0.1, -0.1):
            told = AudioVisualRig.mounted(arr, cam, (0.0, 0.2 + dy, 0.0))
            fix = locate_on_ray(told, uv, z)
            assert np.linalg.norm(fix.position_m - p) > 0.4
            assert fix.residual_s * 16000 < 0.1


def test_bad_fusion_input(rig):
    with pytest.raises(EstimationError, match="TDOAs"):
        locate_on_ray(rig, [320, 240], [0.0, 0.0])
    with pytest.raises(EstimationError, match="finite"):
        locate_on_ray(rig, [320, 240], [0.0, np.nan, 0.0])
    with pytest.raises(EstimationError, match="image point"):
        locate_on_ray(rig, [320], [0.0, 0.0, 0.0])
    with pytest.raises(EstimationError, match="range_m"):
        locate_on_ray(rig, [320, 240], [0.0, 0.0, 0.0], range_m=(2.0, 1.0))
    # TDOAs 50x the physical maximum (e.g. samples or ms for seconds) gave a confident fix
    big = 50 * rig.array.max_tdoa()
    with pytest.raises(EstimationError, match="seconds"):
        locate_on_ray(rig, [320, 240], big)
    edge = rig.array.max_tdoa() + 6.25e-5  # a GCC peak at its lag bound plus one sample
    fix = locate_on_ray(rig, [320, 240], edge)
    assert np.isfinite(fix.residual_s)
    # a fix that is not finite does not start (and poison) the tight-coupling tracker
    trk = RayTdoaTracker(rig)
    for bad in (RayFix(np.array([np.nan, 0.0, 1.0]), 1.0, 0.0, fix.covariance, fix.direction),
                RayFix(fix.position_m, 1.0, 0.0, np.full((3, 3), np.nan), fix.direction)):
        with pytest.raises(EstimationError, match="RayFix"):
            trk.update_measurements(0.0, None, None, bad)
        assert not trk.initialized
    with pytest.raises(GeometryError):
        AudioVisualRig(rig.array, rig.camera, np.eye(3) * 2, np.zeros(3))


def test_tdoa_tracker_refuses_a_fix_that_is_no_ray_fix(side_rig):
    """update_measurements read fix.alternatives of whatever it was given (found by an audit,
    2026-12-02): a text fix, a position array or a RayFix whose alternatives are a number or
    positions raised a builtin AttributeError / TypeError. Now an EstimationError naming the
    RayFix, the tracker as it was; the real fix still starts the track."""
    rig = side_rig
    p = np.array([1.2, 0.2, 0.05])
    uv, z = rig.project(p)[0], rig.array.tdoa(p)
    fix = locate_on_ray(rig, uv, z, sigma_tdoa_s=RAY_SIGMA_TDOA_S)
    trk = RayTdoaTracker(rig)
    for bad in ("fix", p, RayFix(p, 1.0, 0.0, fix.covariance, fix.direction, 5),
                RayFix(p, 1.0, 0.0, fix.covariance, fix.direction, [p])):
        with pytest.raises(EstimationError, match="RayFix"):
            trk.update_measurements(0.0, uv, z, bad)
        assert not trk.initialized and trk.t is None
    assert trk.update_measurements(0.0, uv, z, fix)
    np.testing.assert_array_equal(trk.position, fix.position_m)


def test_tdoa_tracker_refuses_a_fix_covariance_ray_tracker_refuses(side_rig):
    """RayTdoaTracker started (or restarted) on the fix's covariance unchecked: -I was taken
    and position_cov became -4 I (RayTracker refuses the same fix), a 2x2 one raised numpy's
    ValueError, and an alternative's bad covariance went into the gate. Now RayTracker's
    EstimationError, the tracker as it was; a good fix still starts the track on its own
    position and covariance."""
    rig = side_rig
    p = np.array([1.2, 0.2, 0.05])
    uv, z = rig.project(p)[0], rig.array.tdoa(p)
    fix = locate_on_ray(rig, uv, z, sigma_tdoa_s=RAY_SIGMA_TDOA_S)
    bads = [RayFix(p, 1.0, 0.0, -np.eye(3), fix.direction),
            RayFix(p, 1.0, 0.0, np.eye(2), fix.direction),
            RayFix(p, 1.0, 0.0, np.diag([1e-4, 1e-4, 0.0]), fix.direction),
            RayFix(p[:2], 1.0, 0.0, fix.covariance, fix.direction),
            RayFix(p, 1.0, 0.0, fix.covariance, fix.direction,
                   [RayFix(p, 1.0, 0.0, -np.eye(3), fix.direction)])]
    for bad in bads:
        with pytest.raises(EstimationError):
            RayTracker().update(0.0, bad.position_m, bad.covariance,
                                [(a.position_m, a.covariance) for a in bad.alternatives])
        trk = RayTdoaTracker(rig)
        with pytest.raises(EstimationError, match="RayFix"):
            trk.update_measurements(0.0, uv, z, bad)
        assert not trk.initialized
    trk, frames = _settled(rig, 11, 32)  # a restart checks the fix as well
    t, _, uv2, z2, fix2 = frames[30]
    trk.n_rejects = trk.max_rejects
    before = (trk.x.copy(), trk.P.copy())
    for bad in bads:
        with pytest.raises(EstimationError, match="RayFix"):
            trk.update_measurements(t, uv2, z2, bad)
        np.testing.assert_array_equal(trk.x, before[0])
        np.testing.assert_array_equal(trk.P, before[1])
    assert trk.update_measurements(t, uv2, z2, fix2)
    np.testing.assert_array_equal(trk.position, fix2.position_m)
    np.testing.assert_allclose(trk.position_cov, RAY_COVARIANCE_SCALE * fix2.covariance,
                               rtol=1e-12)


def test_text_image_points_and_tdoas_are_refused(rig, side_rig):
    """numpy read the text ("320", "240") as a pixel, "1e-4" as a TDOA and True as 1 in
    locate_on_ray, the rig's rays, RayTdoaTracker.update_measurements and the regressor's
    features: a fix from text, no error. The same numbers as numbers still work."""
    p = np.array([1.4, 0.2, 0.1])
    uv, z = rig.project(p)[0], rig.array.tdoa(p)
    for bad_uv in (("320", "240"), [True, 240.0], ["a", "b"]):
        with pytest.raises(EstimationError, match="image point"):
            locate_on_ray(rig, bad_uv, z)
        with pytest.raises(GeometryError, match="pixel coordinates"):
            rig.rays([bad_uv])
    with pytest.raises(EstimationError, match="TDOAs must be real numbers"):
        locate_on_ray(rig, uv, [str(v) for v in z])
    np.testing.assert_allclose(locate_on_ray(rig, uv, z).position_m, p, atol=1e-6)
    trk, frames = _settled(side_rig, 10, 32)
    t, _, uv2, z2, fix = frames[30]
    with pytest.raises(EstimationError, match="image point"):
        trk.update_measurements(t, [str(v) for v in uv2], z2, fix)
    with pytest.raises(EstimationError, match="TDOAs must be real numbers"):
        trk.update_measurements(t, uv2, [str(v) for v in z2], fix)
    assert trk.update_measurements(t, uv2, z2, fix)
    X, y = simulate_av_samples(rig, 40, rng=np.random.default_rng(0))
    reg = AudioVisualRegressor(hidden_layer_sizes=(4,), max_iter=20).fit(X, y)
    with pytest.raises(EstimationError, match="features must be numbers"):
        reg.predict(X.astype(str))


def test_an_absurd_pixel_gives_a_unit_ray_or_a_geometry_error(rig):
    """uv = (1e300, 240) gave the ray direction [0, 0, 0] and a 'fix' at the camera centre
    (only an overflow warning); with lens distortion a misleading 'source must be finite'.
    Without distortion the pinhole's ray is the optical x axis (R^T [1, 0, 0] in the array
    frame), a unit vector; with distortion the camera refuses the pixel."""
    p = np.array([1.2, 0.2, 0.05])
    z = rig.array.tdoa(p)
    pinhole = AudioVisualRig(rig.array, Camera(rig.camera.K, np.zeros(5), 640, 480), rig.R,
                             rig.t)
    o, d = pinhole.rays([1e300, 240.0])
    np.testing.assert_allclose(d[0], rig.R.T @ [1.0, 0.0, 0.0], rtol=0, atol=1e-12)
    fix = locate_on_ray(pinhole, [1e300, 240.0], z)
    assert np.linalg.norm(fix.direction) == pytest.approx(1.0)
    assert np.linalg.norm(fix.position_m - o) == pytest.approx(fix.range_m) and fix.range_m > 0
    with pytest.raises(GeometryError, match="too far outside"):
        locate_on_ray(rig, [1e300, 240.0], z)


def test_rig_parts_must_be_a_mic_array_and_a_camera(rig):
    """AudioVisualRig('three-mic', None, I, 0) was built, and locate_on_ray then failed with a
    builtin AttributeError; a MicArray and a Camera (subclasses included) still make a rig."""
    for array, camera, match in (("three-mic", rig.camera, "rig array must be a MicArray"),
                                 (rig.array.positions, rig.camera, "rig array must be a"),
                                 (rig.array, None, "rig camera must be a Camera"),
                                 (rig.array, rig.camera.K, "rig camera must be a Camera"),
                                 ("three-mic", None, "rig array")):
        with pytest.raises(GeometryError, match=match):
            AudioVisualRig(array, camera, np.eye(3), np.zeros(3))

    class MyCamera(Camera):
        pass

    mine = MyCamera(rig.camera.K, rig.camera.dist, 640, 480)
    same = AudioVisualRig(rig.array, mine, rig.R, rig.t)
    p = np.array([1.2, 0.2, 0.05])
    np.testing.assert_array_equal(same.project(p), rig.project(p))


def test_a_mirrored_mounting_is_not_a_rotation(rig):
    """R @ R.T = I also holds for a reflection (det -1): such a 'mounting' was accepted and
    every pixel then mirrored its ray, so the fixes were silently wrong."""
    R = rig.R.copy()
    R[0] *= -1.0  # optical x flipped: orthogonal, det -1
    assert np.allclose(R @ R.T, np.eye(3)) and np.linalg.det(R) < 0
    with pytest.raises(GeometryError, match="rotation"):
        AudioVisualRig(rig.array, rig.camera, R, rig.t)
    AudioVisualRig(rig.array, rig.camera, rig.R, rig.t)  # the proper rotation is fine


def test_bad_search_parameters_are_an_estimation_error(rig):
    """n_grid < 2, max_candidates < 1 or an infinite far end left no grid minimum to refine:
    an IndexError escaped; a NaN sigma gave a NaN covariance that RayTracker then ignores."""
    p = np.array([1.5, 0.3, 0.1])
    uv, z = rig.project(p)[0], rig.array.tdoa(p)
    for kw, name in (({"n_grid": 1}, "n_grid"), ({"n_grid": 0}, "n_grid"),
                     ({"n_grid": 10**8}, "n_grid"),  # (a MemoryError)
                     ({"max_candidates": 0}, "max_candidates"),
                     ({"range_m": (0.1, np.inf)}, "range_m"),
                     ({"sigma_tdoa_s": np.nan}, "sigma_tdoa_s"),
                     ({"sigma_px": -1.0}, "sigma_px")):
        with pytest.raises(EstimationError, match=name):
            locate_on_ray(rig, uv, z, **kw)
    # the smallest valid search still finds the source
    fix = locate_on_ray(rig, uv, z, n_grid=2, max_candidates=1, sigma_px=0.0)
    assert np.linalg.norm(fix.position_m - p) < 1e-3


def test_learned_mapping_without_calibration(rig):
    X, Y = simulate_av_samples(rig, 400, (0.5, 2.0), sigma_tdoa_s=1e-6, sigma_px=0.5, rng=1)
    Xt, Yt = simulate_av_samples(rig, 100, (0.5, 2.0), sigma_tdoa_s=1e-6, sigma_px=0.5, rng=2)
    model = AudioVisualRegressor(hidden_layer_sizes=(16, 16), max_iter=150).fit(X, Y)
    err = np.linalg.norm(model.predict(Xt) - Yt, axis=1)
    base = np.linalg.norm(Yt - Y.mean(axis=0), axis=1)
    assert np.median(err) < 0.5 * np.median(base)
    assert model.score(Xt, Yt) > 0.6
    assert model.get_params()["hidden_layer_sizes"] == (16, 16)
    with pytest.raises(EstimationError, match="not fitted"):
        AudioVisualRegressor().predict(Xt)
    with pytest.raises(EstimationError, match="features"):
        model.predict(Xt[:, :3])
    # (an API audit: a TDOA of 1e306 s overflowed to inf after the finiteness check, and a
    # y of another shape in score was scikit-learn's ValueError)
    big = Xt[:1].copy()
    big[0, 0] = 1e306
    with pytest.raises(EstimationError, match="features out of range"):
        model.predict(big)
    with pytest.raises(EstimationError, match=r"targets must be \(n_samples, 3\)"):
        model.score(Xt, Yt[:, :2])
    # a fix that is not a RayFix: an AttributeError in feed_tracker
    from hearsee.fusion.audiovisual import feed_tracker

    with pytest.raises(EstimationError, match="fix must be a RayFix or None"):
        feed_tracker(RayTracker(), 0.0, None, None, "fix")


@pytest.mark.parametrize("kw, name", [({"range_m": (-1.0, -0.5)}, "range_m"),
                                      ({"range_m": (0.0, 2.0)}, "range_m"),
                                      ({"n": -1}, "n"), ({"n": 2.5}, "n"),
                                      ({"sigma_tdoa_s": float("nan")}, "sigma_tdoa_s"),
                                      ({"sigma_px": -1.0}, "sigma_px")])
def test_simulate_av_samples_bad_arguments(rig, kw, name):
    """A range behind the camera gave NaN pixels and TDOAs in X without a word; n = -1 let
    numpy's ValueError ('negative dimensions') escape; a NaN sigma made every feature NaN."""
    args = {"n": 5, **kw}
    with pytest.raises(EstimationError, match=name):
        simulate_av_samples(rig, args.pop("n"), rng=0, **args)


def test_simulate_av_samples_refuses_a_margin_without_image_and_a_short_range(rig):
    """margin_px=400 of a 640x480 image raised numpy's ValueError 'high - low < 0', -1e308 its
    OverflowError, range_m=(1.0,) a builtin IndexError. Now EstimationErrors; the largest
    margin (239.5 px: the row v = 239.5) and a range of one distance still give samples, on
    that row and at that distance from the camera centre."""
    for kw, match in (({"margin_px": 400.0}, r"margin_px must be a finite number in "
                       r"\[-1e\+300, 239.5\]"),
                      ({"margin_px": 240}, "margin_px"), ({"margin_px": -1e308}, "margin_px"),
                      ({"range_m": (1.0,)}, "range_m must satisfy 0 < near <= far"),
                      ({"range_m": 1.0}, "range_m"), ({"range_m": (2.0, 1.0)}, "range_m")):
        with pytest.raises(EstimationError, match=match):
            simulate_av_samples(rig, 5, rng=0, **kw)
    X, Y = simulate_av_samples(rig, 5, range_m=(1.5, 1.5), margin_px=239.5, rng=0)
    np.testing.assert_allclose(X[:, -1], 239.5, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(Y - rig.camera_centre, axis=1), 1.5, rtol=1e-12)
    X2, _ = simulate_av_samples(rig, 5, margin_px=-50, rng=0)  # beyond the border: allowed
    assert X2.shape == (5, 5) and np.all(np.isfinite(X2))


def _walk_measurements(rig, rng, n=80, dt=0.016, sigma_tdoa_s=8e-6, sigma_px=1.0, x0=1.3):
    """(t, truth, pixel, TDOAs, fix) of a source walking at constant velocity from
    (x0, -0.3, 0.05) m; pixel noise drawn only when ``sigma_px`` > 0."""
    p0, v = np.array([x0, -0.3, 0.05]), np.array([-0.2, 0.6, 0.0])
    out = []
    for k in range(n):
        p = p0 + v * k * dt
        uv = rig.project(p)[0]
        if sigma_px > 0:
            uv = uv + sigma_px * rng.standard_normal(2)
        z = rig.array.tdoa(p) + sigma_tdoa_s * rng.standard_normal(3)
        out.append((k * dt, p, uv, z, locate_on_ray(rig, uv, z, sigma_tdoa_s=sigma_tdoa_s)))
    return v, out


def _walk_fixes(rig, rng, n=60, dt=0.032, sigma_tdoa_s=5e-7):
    """(t, truth, fix) of :func:`_walk_measurements` with exact pixels, from x = 1.2 m."""
    v, frames = _walk_measurements(rig, rng, n, dt, sigma_tdoa_s, sigma_px=0.0, x0=1.2)
    return v, [(t, p, fix) for t, p, _, _, fix in frames]


def test_ray_tracker_averages_the_range_scatter_and_estimates_velocity(rig):
    v, fixes = _walk_fixes(rig, np.random.default_rng(3))
    trk = RayTracker(sigma_accel=0.2)
    raw, err = [], []
    for t, p, fix in fixes:
        trk.update(t, fix.position_m, fix.covariance)
        raw.append(np.linalg.norm(fix.position_m - p))
        err.append(np.linalg.norm(trk.position - p))
    assert np.median(err[20:]) < 0.6 * np.median(raw[20:])
    assert np.linalg.norm(trk.velocity - v) < 0.15
    np.testing.assert_array_equal(trk.acceleration, np.zeros(3))
    assert trk.position_cov.shape == (3, 3)


def test_ray_tracker_gates_an_outlier_and_restarts_after_repeated_ones(rig):
    _, fixes = _walk_fixes(rig, np.random.default_rng(4), n=30)
    trk = RayTracker(max_rejects=3)
    for t, _, fix in fixes[:25]:
        trk.update(t, fix.position_m, fix.covariance)
    t, p, fix = fixes[25]
    far = fix.position_m + 0.8 * fix.direction  # a reflection's fix, 0.8 m along the ray
    assert not trk.update(t, far, fix.covariance)
    assert np.linalg.norm(trk.position - p) < 0.1
    # the nearer of two candidate fixes is used
    t, p, fix = fixes[26]
    assert trk.update(t, far, fix.covariance, [(fix.position_m, fix.covariance)])
    assert np.linalg.norm(trk.position - p) < 0.1
    for t, _, fix in fixes[27:30]:
        trk.update(t, fix.position_m + 1.5 * fix.direction, fix.covariance)
    last = fixes[29][2]
    assert np.linalg.norm(trk.position - (last.position_m + 1.5 * last.direction)) < 1e-6
    assert trk.update(0.99, None) is False and trk.initialized
    with pytest.raises(EstimationError, match="backwards"):
        trk.update(0.5, None)


def test_ray_tracker_bad_parameters():
    with pytest.raises(EstimationError, match="sigma_accel"):
        RayTracker(sigma_accel=0.0)
    with pytest.raises(EstimationError, match="gate_prob"):
        RayTracker(gate_prob=1.5)
    assert np.all(np.isnan(RayTracker().position))


def test_ray_tracker_candidates_that_are_no_list_of_pairs_are_estimation_errors():
    """RayTracker.update read its candidates before MotionKalman's checks (found by an audit,
    2026-12-02): candidates=5 raised list()'s builtin TypeError and [x, y, z] alone (no
    covariance) a builtin 'too many values to unpack'. MotionKalman itself refused both with
    an EstimationError. A fix whose covariance is not finite is still skipped (the next
    candidate is used), and the refused calls leave the track alone."""
    k = RayTracker()
    k.update(0.0, [1.0, 0.0, 0.0], np.eye(3) * 1e-4)
    for bad in (5, [[1.0, 2.0, 3.0]], [(np.zeros(3),)], [(np.zeros(3), None, 1.0)]):
        with pytest.raises(EstimationError, match="candidates"):
            k.update(0.1, [1.0, 0.0, 0.0], None, candidates=bad)
    assert k.t == 0.0
    assert k.update(0.1, [1.0, 0.0, 0.0], np.full((3, 3), np.nan),
                    [([1.02, 0.0, 0.0], np.eye(3) * 1e-4)])
    assert k.position[0] == pytest.approx(1.02, abs=1e-3)  # (its prediction is loose)


@pytest.fixture(scope="module")
def side_rig(rig):
    """The camera 0.2 m beside the three-mic preset (bench/tracking.py part B's first rig)."""
    return AudioVisualRig.mounted(rig.array, rig.camera, (0.0, 0.2, 0.0))


def test_tdoa_tracker_fuses_pixels_and_tdoas_and_estimates_velocity(side_rig):
    rig = side_rig
    v, frames = _walk_measurements(rig, np.random.default_rng(6))
    trk = RayTdoaTracker(rig)
    raw, err = [], []
    fused = []
    for t, p, uv, z, fix in frames:
        fused.append(trk.update_measurements(t, uv, z, fix))
        raw.append(np.linalg.norm(fix.position_m - p))
        err.append(np.linalg.norm(trk.position - p))
    assert np.mean(fused) > 0.9
    assert np.median(err[30:]) < 0.5 * np.median(raw[30:])
    assert np.linalg.norm(trk.velocity - v) < 0.1
    assert trk.n_rejects == 0 and trk.position_cov.shape == (3, 3)
    # the reported covariance is RAY_COVARIANCE_SCALE times the filter's own; the filter, its
    # gates and its estimates do not depend on the scale
    own = RayTdoaTracker(rig, covariance_scale=1.0)
    for t, _, uv, z, fix in frames:
        own.update_measurements(t, uv, z, fix)
    np.testing.assert_array_equal(own.position, trk.position)
    np.testing.assert_allclose(trk.position_cov, RAY_COVARIANCE_SCALE * own.position_cov,
                               rtol=1e-12)
    assert RAY_COVARIANCE_SCALE > 1.0
    with pytest.raises(EstimationError, match="covariance_scale"):
        RayTdoaTracker(rig, covariance_scale=0.0)


def test_tdoa_tracker_drops_one_bad_pair_and_keeps_the_others(side_rig):
    rig = side_rig
    _, frames = _walk_measurements(rig, np.random.default_rng(7), sigma_tdoa_s=1e-6,
                                   sigma_px=0.2)
    trk = RayTdoaTracker(rig, sigma_tdoa_s=2e-6, sigma_px=0.2)
    for t, _, uv, z, fix in frames[:50]:
        trk.update_measurements(t, uv, z, fix)
    for t, _, uv, z, fix in frames[50:]:
        bad = z + np.array([0.0, 12e-6, 0.0])  # a reflection pulls pair 0-2 by 0.2 sample
        assert trk.update_measurements(t, uv, bad, fix)  # the other two pairs were fused
    err = np.linalg.norm(trk.position - frames[-1][1])
    assert err < 0.01
    # the same bad TDOAs in a filter with a wide per-pair gate (7 sigma) pull the track off
    loose = RayTdoaTracker(rig, sigma_tdoa_s=2e-6, sigma_px=0.2, pair_gate_prob=1 - 1e-12)
    for t, _, uv, z, fix in frames:
        loose.update_measurements(t, uv, z + (np.array([0.0, 12e-6, 0.0]) if t >= frames[50][0]
                                              else 0.0), fix)
    assert np.linalg.norm(loose.position - frames[-1][1]) > max(3 * err, 0.01)


def _settled(rig, seed, n):
    """A RayTdoaTracker (max_rejects 3) after the first 30 of n walk frames, and the frames."""
    _, frames = _walk_measurements(rig, np.random.default_rng(seed), n=n)
    trk = RayTdoaTracker(rig, max_rejects=3)
    for t, _, uv, z, fix in frames[:30]:
        trk.update_measurements(t, uv, z, fix)
    return trk, frames


def test_tdoa_tracker_refuses_measurements_of_the_wrong_shape(side_rig):
    """Two TDOAs for the three pairs were fused silently as pairs 0-1 and 0-2 (whatever pairs
    they were measured on), four raised an IndexError, a 3-vector image point a ValueError."""
    rig = side_rig
    trk, frames = _settled(rig, 10, 32)
    t, _, uv, z, fix = frames[30]
    for bad in (z[:2], np.r_[z, 0.0]):
        before = trk.x.copy()
        with pytest.raises(EstimationError, match="TDOAs"):
            trk.update_measurements(t, uv, bad, fix)
        np.testing.assert_array_equal(trk.x, before)
    with pytest.raises(EstimationError, match="image point"):
        trk.update_measurements(t, [320.0, 240.0, 1.0], z, fix)
    assert trk.update_measurements(t, uv, z, fix)


def test_fusion_refuses_tdoas_no_sound_can_take(rig, side_rig):
    """A TDOA of 1e300 s (a corrupt value, no delay) is localization's GeometryError ("at most
    3600 s"); the fusion took it: locate_on_ray searched the ray for it (a fix, no error) and
    RayTdoaTracker.update_measurements fed it to its gate. Now the same rule, as the fusion's
    EstimationError, and the tracker's state untouched."""
    p = np.array([1.4, 0.2, 0.1])
    uv, z = rig.project(p)[0], rig.array.tdoa(p)
    for big in (1e300, -4000.0):
        with pytest.raises(EstimationError, match="at most 3600 s"):
            locate_on_ray(rig, uv, np.r_[z[:2], big])
    trk, frames = _settled(side_rig, 10, 32)
    t, _, uv2, z2, fix = frames[30]
    before = trk.x.copy()
    with pytest.raises(EstimationError, match="at most 3600 s"):
        trk.update_measurements(t, uv2, np.r_[1e300, z2[1:]], fix)
    np.testing.assert_array_equal(trk.x, before)
    assert trk.update_measurements(t, uv2, z2, fix)


def test_tdoa_tracker_restart_keeps_the_time_checks(side_rig):
    """The restart on a fix set the time without the checks of every other frame: a frame
    earlier than the last one, or at a NaN time, restarted the track silently."""
    rig = side_rig
    trk, frames = _settled(rig, 11, 36)
    t, _, uv, z, fix = frames[30]
    trk.n_rejects = trk.max_rejects  # the next fix restarts the track
    for bad in (frames[20][0], np.nan):
        with pytest.raises(EstimationError, match="time"):
            trk.update_measurements(bad, uv, z, fix)
    assert trk.update_measurements(t, uv, z, fix) and trk.t == t
    np.testing.assert_allclose(trk.position, fix.position_m)


def test_ray_trackers_refuse_times_that_are_no_numbers(side_rig):
    """RayTracker.update and RayTdoaTracker.update_measurements (also on the restart path)
    read the time "1.0" and True as 1 s and raised a builtin TypeError on None."""
    trk, frames = _settled(side_rig, 11, 32)
    t, _, uv, z, fix = frames[30]
    ray = RayTracker()
    ray.update(frames[0][0], fix.position_m, fix.covariance)
    for bad in ("1.0", True, None):
        with pytest.raises(EstimationError, match="time"):
            ray.update(bad, fix.position_m, fix.covariance)
        with pytest.raises(EstimationError, match="time"):
            trk.update_measurements(bad, uv, z, fix)
        trk.n_rejects = trk.max_rejects  # the next fix would restart the track
        with pytest.raises(EstimationError, match="time"):
            trk.update_measurements(bad, uv, z, fix)
        trk.n_rejects = 0
    assert ray.t == frames[0][0] and trk.t == frames[29][0]
    assert trk.update_measurements(t, uv, z, fix) and ray.update(t, fix.position_m,
                                                                  fix.covariance)


def test_tdoa_tracker_gates_a_far_fix_and_restarts_after_repeated_ones(side_rig):
    rig = side_rig
    trk, frames = _settled(rig, 8, 40)
    # a frame whose fix fails the gate fuses none of its TDOAs, not even ones that would pass
    # their own gates
    t, p, uv, z, fix = frames[30]
    far = locate_on_ray(rig, uv, rig.array.tdoa(p - 0.6 * fix.direction),
                        sigma_tdoa_s=RAY_SIGMA_TDOA_S)
    assert not trk.update_measurements(t, uv, z, far) and trk.n_rejects == 1
    assert trk.update_measurements(*frames[31][:1], *frames[31][2:]) and trk.n_rejects == 0
    # the talker heard 0.6 m nearer along the ray (a reflection): the fixes fail the gate ...
    moved = []
    for t, p, uv, _, fix in frames[32:35]:
        q = p - 0.6 * fix.direction
        zq = rig.array.tdoa(q)
        fq = locate_on_ray(rig, uv, zq, sigma_tdoa_s=RAY_SIGMA_TDOA_S)
        assert not trk.update_measurements(t, uv, zq, fq)
        assert np.linalg.norm(trk.position - p) < 0.1
        moved.append((t, uv, zq, fq))
    # ... and the next one restarts the track there
    t, p, uv, _, fix = frames[35]
    fq = locate_on_ray(rig, uv, rig.array.tdoa(p - 0.6 * fix.direction),
                       sigma_tdoa_s=RAY_SIGMA_TDOA_S)
    assert trk.update_measurements(t, uv, None, fq)
    np.testing.assert_allclose(trk.position, fq.position_m)
    # a frame without a fix: camera update only, no TDOA fused
    assert trk.update_measurements(frames[36][0], frames[36][2], None, None) is False
    assert trk.initialized
    with pytest.raises(EstimationError, match="sigma_tdoa_s"):
        RayTdoaTracker(rig, sigma_tdoa_s=0.0)
    with pytest.raises(EstimationError, match="pair_gate_prob"):
        RayTdoaTracker(rig, pair_gate_prob=1.0)
    assert not RayTdoaTracker(rig).update_measurements(0.0, (320.0, 240.0), None, None)


@pytest.mark.parametrize("gap_s", [10.0, 100.0])
def test_tdoa_tracker_starts_anew_at_an_exact_fix_after_a_long_gap(side_rig, gap_s):
    # a walker tracked for 1 s (exact pixels and TDOAs) stops while nothing is seen; the
    # frame after the gap predicts the track far off with a covariance that holds no
    # position, and the EKF linearised there kept it metres from the exact fix (this rig:
    # 4.9 m after 10 s, 50 m after 100 s, the exact fix rejected; a pinhole camera: fused, 3.5
    # and 668 m off), where RayTracker fused the same fix to a fraction of a millimetre
    rig = side_rig
    p0, v = np.array([1.5, -0.4, 0.1]), np.array([0.0, 0.5, 0.0])
    trk, fixed = RayTdoaTracker(rig), RayTracker()
    for t in [*np.arange(0.0, 1.0, 0.016), 1.0 + gap_s]:
        p = p0 + v * min(t, 1.0)
        uv, z = rig.project(p)[0], rig.array.tdoa(p)
        fix = locate_on_ray(rig, uv, z, range_m=(0.2, 4.0), sigma_tdoa_s=RAY_SIGMA_TDOA_S)
        fused = trk.update_measurements(t, uv, z, fix)
        fixed.update(t, fix.position_m, fix.covariance)
    assert np.linalg.norm(fixed.position - p) < 1e-3
    assert np.linalg.norm(trk.position - p) < 1e-3 and fused
    assert not trk.velocity_known  # (started anew: the velocity is its prior again)


def test_tdoa_tracker_ignores_a_detection_on_someone_else_then_follows_them(side_rig):
    rig = side_rig
    trk, frames = _settled(rig, 9, 50)
    other = np.array([1.0, 0.6, 0.0])  # another person, heard too (their TDOAs and fix)
    zo, uo = rig.array.tdoa(other), rig.project(other)[0]
    fo = locate_on_ray(rig, uo, zo, sigma_tdoa_s=RAY_SIGMA_TDOA_S)
    for t, p, _, _, _ in frames[30:32]:
        assert not trk.update_measurements(t, uo, zo, fo)  # the image point fails its gate
        assert np.linalg.norm(trk.position - p) < 0.05
    assert not trk.update_measurements(frames[32][0], uo, None, None) and trk.n_rejects == 3
    assert trk.update_measurements(frames[33][0], uo, zo, fo)  # restarted on them
    np.testing.assert_allclose(trk.position, fo.position_m)
    for t, _, _, _, _ in frames[34:40]:
        trk.update_measurements(t, uo, zo, fo)
    assert np.linalg.norm(trk.position - other) < 0.02
    with pytest.raises(EstimationError, match="pixel_gate_prob"):
        RayTdoaTracker(rig, pixel_gate_prob=0.0)


def test_track_on_rays_from_a_recording(rig):
    from hearsee.sim.moving import Trajectory, simulate_moving_free_field

    rng = np.random.default_rng(5)
    fs = 16000
    traj = Trajectory([0.0, 1.0], [[1.0, -0.2, 0.0], [1.0, 0.3, 0.0]])
    x = rng.standard_normal(fs)
    y = simulate_moving_free_field(x, fs, rig.array, traj, snr_db=30.0, rng=rng)
    res = track_on_rays(rig, y, fs, lambda t: rig.project(traj.at(t))[0])
    truth = traj.at(res.t)
    assert np.mean(np.isfinite(res.raw[:, 0])) > 0.8
    err = np.linalg.norm(res.position - truth, axis=1)[10:]
    assert np.median(err) < 0.05
    assert np.linalg.norm(np.nanmean(res.velocity[10:], axis=0) - [0.0, 0.5, 0.0]) < 0.2
    # frames without an image point give no fix; the track coasts
    res2 = track_on_rays(rig, y, fs, lambda t: None if t > 0.5 else rig.project(traj.at(t))[0])
    late = res2.t > 0.5
    assert np.all(np.isnan(res2.raw[late, 0])) and np.all(np.isfinite(res2.position[late, 0]))


@pytest.mark.parametrize("tracker", [None, "ray"])
def test_an_image_point_of_nan_is_not_seen_like_none(rig, tracker):
    """An image_points callback that answered (nan, nan) for frames where the detector lost
    the source aborted the whole track_on_rays run with EstimationError, though None worked
    and RayTdoaTracker reads NaN as 'not seen'. Now a NaN or infinite coordinate is None:
    the same fixes and track, frame for frame, as with None; no fix in those frames."""
    from hearsee.fusion.audiovisual import frame_fix
    from hearsee.sim.moving import Trajectory, simulate_moving_free_field

    rng = np.random.default_rng(5)
    fs = 16000
    traj = Trajectory([0.0, 0.6], [[1.0, -0.2, 0.0], [1.0, 0.1, 0.0]])
    y = simulate_moving_free_field(rng.standard_normal(fs * 6 // 10), fs, rig.array, traj,
                                   snr_db=30.0, rng=rng)

    def points(missing):
        return lambda t: missing if 0.3 < t < 0.4 else rig.project(traj.at(t))[0]

    def run(missing):
        return track_on_rays(rig, y, fs, points(missing),
                             tracker=None if tracker is None else RayTracker())

    ref = run(None)
    lost = (ref.t > 0.3 + 0.01) & (ref.t < 0.4 - 0.01)
    assert lost.sum() >= 4 and np.all(np.isnan(ref.raw[lost]))
    for missing in ((np.nan, np.nan), [np.nan, 240.0], np.array([np.inf, 240.0])):
        res = run(missing)
        np.testing.assert_array_equal(res.raw, ref.raw)
        np.testing.assert_array_equal(res.position, ref.position)
        np.testing.assert_array_equal(res.velocity, ref.velocity)
    # one frame: no image point, no fix; a NaN at the emission time keeps the first answer
    p = traj.at(0.2)
    z, uv = rig.array.tdoa(p), rig.project(p)[0]
    kw = dict(range_m=(0.2, 4.0), sigma_tdoa_s=8e-6, sigma_px=1.0, max_residual_s=1e-4)
    assert frame_fix(rig, lambda t: (np.nan, np.nan), 0.2, z, rig.array.pairs, **kw) == (None,
                                                                                          None)
    calls = iter([uv, (np.nan, np.nan)])
    got, fix = frame_fix(rig, lambda t: next(calls), 0.2, z, rig.array.pairs, **kw)
    assert got is uv and np.linalg.norm(fix.position_m - p) < 1e-3
    with pytest.raises(EstimationError, match="image point"):
        frame_fix(rig, lambda t: (np.nan, 240.0, 1.0), 0.2, z, rig.array.pairs, **kw)
    # (an audit: max_residual_s NaN kept every fix -- the TDOAs negated, 5.7e-4 s of residual,
    # came back -- and text, like a text t or tdoa_s, was a builtin TypeError)
    assert frame_fix(rig, lambda t: uv, 0.2, -z, rig.array.pairs, **kw)[1] is None
    for bad, words in (({"max_residual_s": np.nan}, "max_residual_s"),
                       ({"max_residual_s": "0.1"}, "max_residual_s"), ({"t": "0.5"}, "t must"),
                       ({"tdoa_s": "abc"}, "tdoa_s must be numbers")):
        args = {"t": 0.2, "tdoa_s": -z, **kw, **bad}
        with pytest.raises(EstimationError, match=words):
            frame_fix(rig, lambda t: uv, args.pop("t"), args.pop("tdoa_s"), rig.array.pairs,
                      **args)


def test_track_on_rays_at_48_khz_uses_the_wide_band(rig):
    from hearsee.sim.moving import Trajectory, simulate_moving_free_field

    rng = np.random.default_rng(6)
    traj = Trajectory([0.0, 1.0], [[1.2, 0.2, 0.0], [1.0, -0.2, 0.1]])
    errs = {}
    for fs in (16000, 48000):
        y = simulate_moving_free_field(rng.standard_normal(fs), fs, rig.array, traj,
                                       snr_db=20.0, rng=rng)
        res = track_on_rays(rig, y, fs, lambda t: rig.project(traj.at(t))[0])
        fixes = [f for f in res.fixes if f is not None]
        # the default fix covariance is the one of RAY_SIGMA_TDOA_S along the ray
        f = fixes[len(fixes) // 2]
        ref = locate_on_ray(rig, rig.project(f.position_m)[0], rig.array.tdoa(f.position_m),
                            sigma_tdoa_s=RAY_SIGMA_TDOA_S)
        assert np.linalg.norm(ref.position_m - f.position_m) < 1e-3
        along = float(f.direction @ f.covariance @ f.direction)
        assert along == pytest.approx(float(ref.direction @ ref.covariance @ ref.direction),
                                      rel=0.02)
        errs[fs] = np.median(np.linalg.norm(res.raw - traj.at(res.t), axis=1)[
            np.isfinite(res.raw[:, 0])])
    # a three times wider band: sharper GCC peaks, fixes closer along the ray (here 4.2 vs
    # 6.9 cm; in the room of bench/tracking.py part B the gap is wider)
    assert errs[48000] < 0.75 * errs[16000]


def test_tdoa_tracker_pairs_are_checked_when_it_is_made(side_rig):
    """Bad-input sweep of the public API: RayTdoaTracker(rig, pairs=[(0, 9)]) was accepted (an
    IndexError at the first frame) and (0.7, 1.9) was truncated to (0, 1)."""
    for pairs in ([(0, 9)], [(0.7, 1.9)], [(1, 1)], []):
        with pytest.raises(GeometryError, match="pair"):
            RayTdoaTracker(side_rig, pairs=pairs)
    assert RayTdoaTracker(side_rig, pairs=[(0.0, 1.0)]).pairs == [(0, 1)]


def test_locate_on_ray_pairs_that_are_no_list_are_a_geometry_error(rig):
    """locate_on_ray(..., pairs=5) raised list()'s builtin TypeError (found by an audit,
    2026-12-02); ray_residuals and RayTdoaTracker check their pairs with the array's
    checked_pairs. Valid pairs, in another order, still give the exact fix."""
    p = np.array([1.4, 0.2, 0.1])
    uv = rig.project(p)[0]
    for bad in (5, 2.5, object()):
        with pytest.raises(GeometryError, match="pair"):
            locate_on_ray(rig, uv, [0.0], pairs=bad)
    prs = [(1, 0), (2, 0), (2, 1)]
    fix = locate_on_ray(rig, uv, rig.array.tdoa(p, prs), pairs=prs)
    assert np.linalg.norm(fix.position_m - p) < 1e-3


def test_fusion_functions_refuse_a_rig_that_is_no_audio_visual_rig(rig):
    """locate_on_ray, frame_fix, track_on_rays, simulate_av_samples and RayTdoaTracker used
    rig.array of whatever they were given, and ray_residuals array.checked_pairs (found by an
    audit, 2026-12-02): None or a preset name raised a builtin AttributeError. Now a
    GeometryError naming the function; the real rig still works."""
    p = np.array([1.4, 0.2, 0.1])
    uv, z = rig.project(p)[0], rig.array.tdoa(p)
    x = np.zeros((3, 4096))
    for bad in (None, "three-mic", rig.array):
        calls = {"locate_on_ray": lambda b: locate_on_ray(b, uv, z),
                 "frame_fix": lambda b: frame_fix(b, lambda t: uv, 0.0, z, rig.array.pairs,
                                                  range_m=(0.1, 10.0), sigma_tdoa_s=1e-5,
                                                  sigma_px=1.0, max_residual_s=1e-4),
                 "track_on_rays": lambda b: track_on_rays(b, x, 16000, lambda t: uv),
                 "simulate_av_samples": lambda b: simulate_av_samples(b, 3),
                 "RayTdoaTracker": lambda b: RayTdoaTracker(b)}
        for name, call in calls.items():
            with pytest.raises(GeometryError, match=f"{name} needs an AudioVisualRig"):
                call(bad)
    for bad in (None, "three-mic", rig):
        with pytest.raises(GeometryError, match="array must be a MicArray"):
            ray_residuals(bad, np.zeros(3), [1.0, 0.0, 0.0], 1.0, z)
    assert np.linalg.norm(locate_on_ray(rig, uv, z).position_m - p) < 1e-3


def test_image_points_that_are_no_function_are_an_estimation_error(rig):
    """track_on_rays and frame_fix called image_points as given (found by an audit,
    2026-12-02): an array of pixels raised a builtin TypeError at the first frame, in
    track_on_rays after the whole recording's GCC-PHAT. Now an EstimationError first."""
    p = np.array([1.4, 0.2, 0.1])
    uv, z = rig.project(p)[0], rig.array.tdoa(p)
    x = np.random.default_rng(0).standard_normal((3, 4096))
    for bad in (uv, [uv, uv], None):
        with pytest.raises(EstimationError, match="image_points must be a function"):
            track_on_rays(rig, x, 16000, bad)
        with pytest.raises(EstimationError, match="image_points must be a function"):
            frame_fix(rig, bad, 0.0, z, rig.array.pairs, range_m=(0.1, 10.0),
                      sigma_tdoa_s=1e-5, sigma_px=1.0, max_residual_s=1e-4)
    uv_f, fix = frame_fix(rig, lambda t: uv, 0.0, z, rig.array.pairs, range_m=(0.1, 10.0),
                          sigma_tdoa_s=1e-5, sigma_px=1.0, max_residual_s=1e-4)
    assert np.linalg.norm(fix.position_m - p) < 1e-3


def test_settings_and_geometry_of_the_fusion_must_be_numbers(rig):
    """Bad-input sweep of the public fusion API: numpy and float() read text as the numbers it
    spells and True as 1 -- a rig mounting R / t of text, to_optical's and ray_residuals'
    points, locate_on_ray's range_m ('0.1', '10') and (True, 10), RayTracker(sigma_accel=True),
    targets of text for the regressor; infinite sigma_accel / sigma_px were taken (the state or
    the pixel update NaN or void), text settings raised builtin TypeErrors, NaN
    max_residual_samples kept every fix and a NaN margin_px raised numpy's OverflowError. The
    same values as numbers give the same results."""
    p = np.array([1.4, 0.2, 0.1])
    uv, z = rig.project(p)[0], rig.array.tdoa(p)
    with pytest.raises(GeometryError, match="rig mounting R"):
        AudioVisualRig(rig.array, rig.camera, rig.R.astype(str), rig.t)
    with pytest.raises(GeometryError, match="rig mounting t"):
        AudioVisualRig(rig.array, rig.camera, rig.R, [str(v) for v in rig.t])
    for bad in ([["1.4", "0.2", "0.1"]], [1.4, True, 0.1]):
        with pytest.raises(GeometryError, match="not numbers"):
            rig.to_optical(bad)
        with pytest.raises(GeometryError, match="not numbers"):
            rig.project(bad)
    o, d = rig.rays(uv[None, :])
    args = dict(array=rig.array, origin=o, direction=d[0], s=[1.0], tdoa_s=z)
    for name in ("origin", "direction", "s", "tdoa_s"):
        bad = dict(args, **{name: np.asarray(args[name]).astype(str)})
        with pytest.raises(GeometryError, match=f"^ray_residuals: {name} must hold numbers"):
            ray_residuals(**bad)
    for rng in (("0.1", "10"), (True, 10.0), (0.1, "10"), (0.1,), None):
        with pytest.raises(EstimationError, match="range_m must satisfy"):
            locate_on_ray(rig, uv, z, range_m=rng)
    for kw in ({"sigma_accel": np.inf}, {"sigma_accel": True}, {"sigma_accel": "0.2"},
               {"gate_prob": "0.99"}, {"max_rejects": "4"}, {"init_vel_sigma": np.inf}):
        with pytest.raises(EstimationError, match=next(iter(kw))):
            RayTracker(**kw)
        with pytest.raises(EstimationError, match=next(iter(kw))):
            RayTdoaTracker(rig, **kw)
    for kw in ({"sigma_px": np.inf}, {"sigma_tdoa_s": True}, {"sigma_px": "1"},
               {"pair_gate_prob": "0.99"}, {"pixel_gate_prob": np.nan}):
        with pytest.raises(EstimationError, match=next(iter(kw))):
            RayTdoaTracker(rig, **kw)
    trk = RayTracker()
    with pytest.raises(EstimationError, match="covariance must hold real numbers"):
        trk.update(0.0, p, np.eye(3).astype(str))
    x = np.zeros((3, 1600))
    for bad in (np.nan, "0.5"):
        with pytest.raises(EstimationError, match="max_residual_samples must be a finite"):
            track_on_rays(rig, x, 16000, lambda t: None, max_residual_samples=bad)
    for bad in (np.nan, "10"):
        with pytest.raises(EstimationError, match="margin_px must be a finite"):
            simulate_av_samples(rig, 5, margin_px=bad, rng=0)
    X, Y = simulate_av_samples(rig, 40, rng=np.random.default_rng(0))
    with pytest.raises(EstimationError, match="targets must be numbers"):
        AudioVisualRegressor(hidden_layer_sizes=(4,), max_iter=5).fit(X, Y.astype(str))
    # numbers: the same answers
    fix = locate_on_ray(rig, uv, z, range_m=[0.1, 10])
    np.testing.assert_array_equal(fix.position_m, locate_on_ray(rig, uv, z).position_m)
    np.testing.assert_array_equal(rig.to_optical(p), rig.to_optical(p.tolist()))
    np.testing.assert_array_equal(ray_residuals(**args), ray_residuals(**dict(args, s=1.0)))
    assert trk.update(0.0, p, np.eye(3) * 1e-4)


def test_track_on_rays_checks_its_search_settings_before_any_frame(rig):
    """range_m (and the sigmas) reached locate_on_ray only once a frame had an image point:
    a recording without one took (0.0, -1) and ("0.2", "4") silently. Given a custom
    tracker, nothing else checked the sigmas."""
    x = np.zeros((3, 1600))
    for bad in ((0.0, -1.0), ("0.2", "4"), (4.0, 0.2), None):
        with pytest.raises(EstimationError, match="range_m must satisfy"):
            track_on_rays(rig, x, 16000, lambda t: None, range_m=bad)
    for kw in ({"sigma_px": "1"}, {"sigma_px": np.nan}, {"sigma_tdoa_s": -1e-6}):
        with pytest.raises(EstimationError, match=f"{next(iter(kw))} must be a finite"):
            track_on_rays(rig, x, 16000, lambda t: None, tracker=RayTracker(), **kw)
    res = track_on_rays(rig, x, 16000, lambda t: None, range_m=[0.2, 4])  # numbers: fine
    assert len(res.t) > 0 and np.all(np.isnan(res.raw))


def test_track_on_rays_refuses_zero_noise_before_any_frame(rig):
    """sigma_tdoa_s = 0 or sigma_px = 0 makes every fix's covariance singular, which the
    trackers refuse (RayTracker, MotionKalman: 'a measurement covariance must be ... positive
    definite' at the first fix, after the whole recording's GCC-PHAT; RayTdoaTracker: its own
    'must be > 0', also after it); a recording without a fix took them silently. Refused
    before any frame, as the stream's StreamConfig does."""
    from hearsee.audio.tracking import MotionKalman

    x = np.zeros((3, 1600))
    for kw in ({"sigma_px": 0.0}, {"sigma_tdoa_s": 0.0}):
        for trk in (RayTracker(), MotionKalman(), None):
            with pytest.raises(EstimationError, match=f"{next(iter(kw))} must be a finite "
                                                      "number > 0"):
                track_on_rays(rig, x, 16000, lambda t: None, tracker=trk, **kw)


def test_trackers_of_the_wrong_kind_are_refused_before_any_frame(rig):
    """track_on_rays(tracker="a") ran the whole recording's GCC-PHAT and then raised a builtin
    AttributeError ('str' object has no attribute 'update'), and feed_tracker did at once (None
    too). Both EstimationErrors now, track_on_rays before its first frame; a tracker without
    position / velocity is refused there as well. The library's trackers pass."""
    from hearsee.audio.tracking import MotionKalman
    from hearsee.fusion.audiovisual import feed_tracker

    class NoState:
        def update(self, t, position=None, R=None, candidates=None):
            return False

    x = np.zeros((3, 1600))
    for bad in ("a", 5, None, [1], NoState()):
        if bad is not None:
            with pytest.raises(EstimationError, match="track_on_rays: tracker must be a 3D"):
                track_on_rays(rig, x, 16000, lambda t: None, tracker=bad)
        if not isinstance(bad, NoState):
            with pytest.raises(EstimationError, match="feed_tracker: tracker must be a 3D"):
                feed_tracker(bad, 0.1, None, None, None)
    assert feed_tracker(NoState(), 0.1, None, None, None) is False  # (update is all it needs)
    for good in (RayTracker(), RayTdoaTracker(rig), MotionKalman()):
        res = track_on_rays(rig, x, 16000, lambda t: None, tracker=good)
        assert len(res.t) > 0 and np.all(np.isnan(res.raw))


@pytest.mark.parametrize("max_iter", [2.5, "500", True, 0])
def test_regressor_max_iter_must_be_a_whole_number(rig, max_iter):
    """int(max_iter) read 2.5 as 2, "500" as 500 and True as 1."""
    X, Y = simulate_av_samples(rig, 40, rng=np.random.default_rng(0))
    with pytest.raises(EstimationError, match=r"^max_iter must be an integer >= 1, got "):
        AudioVisualRegressor(hidden_layer_sizes=(4,), max_iter=max_iter).fit(X, Y)


def test_regressor_refuses_what_scikit_learn_would_raise_on(rig):
    """NaN targets, a single sample and settings MLPRegressor refuses (hidden_layer_sizes
    (0,), a NaN alpha, an unknown solver) raised scikit-learn's errors; an empty predict
    its ValueError. EstimationError now (the failed fit leaves no model behind); an empty
    predict gives no positions."""
    X, Y = simulate_av_samples(rig, 40, rng=np.random.default_rng(0))
    Yn = Y.copy()
    Yn[3, 1] = np.nan
    with pytest.raises(EstimationError, match="targets contain NaN"):
        AudioVisualRegressor(hidden_layer_sizes=(4,), max_iter=5).fit(X, Yn)
    with pytest.raises(EstimationError, match="at least 2 samples"):
        AudioVisualRegressor(hidden_layer_sizes=(4,), max_iter=5).fit(X[:1], Y[:1])
    for kw in ({"hidden_layer_sizes": (0,)}, {"alpha": np.nan}, {"solver": "x"}):
        reg = AudioVisualRegressor(max_iter=5, **kw)
        with pytest.raises(EstimationError, match="AudioVisualRegressor settings"):
            reg.fit(X, Y)
        assert not hasattr(reg, "model_")
    reg = AudioVisualRegressor(hidden_layer_sizes=(4,), max_iter=5).fit(X, Y)
    assert reg.predict(X[:0]).shape == (0, 3)


def test_regressor_takes_one_layer_size_as_mlp_regressor_does(rig):
    """hidden_layer_sizes=16 raised a builtin TypeError (tuple(16)) although MLPRegressor
    takes an int as one hidden layer; now the same model as (16,). Text, a bool, None or 0
    are an EstimationError."""
    X, Y = simulate_av_samples(rig, 40, rng=np.random.default_rng(0))
    one = AudioVisualRegressor(hidden_layer_sizes=16, max_iter=20).fit(X, Y)
    ref = AudioVisualRegressor(hidden_layer_sizes=(16,), max_iter=20).fit(X, Y)
    assert [c.shape for c in one.model_[-1].coefs_] == [(5, 16), (16, 3)]
    np.testing.assert_array_equal(one.predict(X), ref.predict(X))
    assert one.get_params()["hidden_layer_sizes"] == 16  # (the parameter as given)
    np.testing.assert_array_equal(
        AudioVisualRegressor(hidden_layer_sizes=np.int64(16), max_iter=20).fit(X, Y).predict(X),
        ref.predict(X))
    for bad in (True, "16", None, 0):
        with pytest.raises(EstimationError, match="hidden_layer_sizes"):
            AudioVisualRegressor(hidden_layer_sizes=bad, max_iter=5).fit(X, Y)


def test_regressor_predict_before_fit_is_scikit_learns_not_fitted_error(rig):
    """predict before fit raised hearsee's EstimationError only, which scikit-learn does not
    recognise (check_estimator's check_estimators_unfitted failed); now an error that is both."""
    from sklearn.exceptions import NotFittedError
    from sklearn.utils.estimator_checks import check_estimators_unfitted

    X, _ = simulate_av_samples(rig, 5, rng=np.random.default_rng(0))
    with pytest.raises(NotFittedError, match="not fitted") as info:
        AudioVisualRegressor().predict(X)
    assert isinstance(info.value, EstimationError)
    check_estimators_unfitted("AudioVisualRegressor", AudioVisualRegressor())
    from hearsee.fusion.audiovisual import RegressorNotFittedError

    assert type(info.value) is RegressorNotFittedError
    # one class, in hearsee.errors (built on first use there), and it pickles by that name
    import pickle

    import hearsee.errors

    assert RegressorNotFittedError is hearsee.errors.RegressorNotFittedError
    assert type(pickle.loads(pickle.dumps(info.value))) is RegressorNotFittedError


def test_rig_keeps_copies_of_the_callers_mounting():
    """AudioVisualRig copies (and freezes) its mounting R, t: editing the caller's arrays
    afterwards does not move the rig's camera."""
    R = np.eye(3)
    t = np.array([0.0, -0.1, 0.0])
    rig = AudioVisualRig(MicArray.from_preset("three-mic"), Camera.from_fov(60.0, 640, 480), R, t)
    centre = rig.camera_centre.copy()
    t[1] = 5.0
    R[0, 0] = -1.0
    assert R.flags.writeable and t.flags.writeable
    np.testing.assert_array_equal(rig.camera_centre, centre)
    np.testing.assert_array_equal(rig.R, np.eye(3))


@pytest.mark.parametrize("path", ["stream", "track_on_rays"])
def test_image_point_is_taken_when_the_heard_sound_left_the_walker(path):
    """A frame's TDOAs describe where the talker was r/c before the frame time; the image at
    the frame time put the fix a few mm further along the walk, which the camera-array
    parallax turned into a range error of 3-3.5 cm at 1.5 m/s (sign set by the walking
    direction). The camera here sees the true position at each instant."""
    from hearsee.sim.moving import Trajectory, simulate_moving_free_field
    from hearsee.stream.pipeline import ArraySource, StreamConfig, StreamPipeline

    arr = MicArray.from_preset("three-mic")
    rig = AudioVisualRig.mounted(arr, Camera.from_fov(100.0, 640, 480), (0, -0.2, 0), 0, 0)
    fs, rng = 16000, np.random.default_rng(7)
    s = rng.standard_normal(2 * fs)
    sign = 1.0 if path == "stream" else -1.0
    traj = Trajectory([0.0, 2.0], [[1.3, -1.5 * sign, 0.3], [1.3, 1.5 * sign, 0.3]])  # 1.5 m/s
    x = simulate_moving_free_field(s, fs, arr, traj) + 1e-3 * rng.standard_normal((3, s.size))

    def points(t):
        return tuple(rig.project(traj.at(t)[None])[0])

    if path == "stream":
        ups = StreamPipeline(arr, StreamConfig(), rig=rig, image_points=points).run(
            ArraySource(x, fs, 4096))
        t = np.array([u.t for u in ups])
        raw = np.array([u.raw_position_m or [np.nan] * 3 for u in ups], dtype=float)
        pos = np.array([u.position_m or [np.nan] * 3 for u in ups], dtype=float)
    else:
        rt = track_on_rays(rig, x, fs, points)
        t, raw, pos = rt.t, rt.raw, rt.position
    centre = arr.positions.mean(axis=0)
    truth = traj.heard_at(t, centre, arr.speed_of_sound)
    ok = np.isfinite(raw[:, 0]) & (t > 0.3) & (t < 1.7)
    assert ok.sum() > 20
    cc = rig.camera_centre
    bias = np.mean(np.linalg.norm(raw[ok] - cc, axis=1) - np.linalg.norm(truth[ok] - cc, axis=1))
    assert abs(bias) < 0.004  # metres (3.3 cm before)
    assert np.median(np.linalg.norm(pos[ok] - truth[ok], axis=1)) < 0.01  # (3.4 cm before)


@pytest.mark.parametrize(("sigma_tdoa_s", "sigma_px"), [(1e-10, 0.05), (5e-7, 1.0), (2e-6, 1.0)])
def test_fix_covariance_holds_the_pixel_noise_along_the_ray(sigma_tdoa_s, sigma_px):
    """A pixel's noise tilts the ray, which then meets the TDOA surface at another range: the
    fix moves along the ray too. The covariance put the pixel noise across the ray only, so
    where the TDOA noise is small the fixes were overconfident (mean NEES ~2e5 with pixel
    noise alone, 7.2 at 0.5 us and 1 px; 3 is right). Monte Carlo against the known source,
    a camera 0.2 m beside the three-mic array and one mounted above it, turned."""
    arr = MicArray.from_preset("three-mic")
    cam = Camera(np.array([[500.0, 0, 320.0], [0, 500.0, 240.0], [0, 0, 1]]), np.zeros(5),
                 640, 480)
    rng = np.random.default_rng(1)
    for mount in (((0.0, 0.2, 0.0),), ((0.05, 0.0, 0.12), 5.0, -3.0)):
        rig = AudioVisualRig.mounted(arr, cam, *mount)
        for p in (np.array([1.0, 0.3, 0.1]), np.array([2.0, -0.4, 0.2])):
            uv0, z0 = rig.project(p)[0], arr.tdoa(p)
            nees = []
            for _ in range(150):
                f = locate_on_ray(rig, uv0 + sigma_px * rng.standard_normal(2),
                                  z0 + sigma_tdoa_s * rng.standard_normal(3),
                                  sigma_tdoa_s=sigma_tdoa_s, sigma_px=sigma_px)
                e = f.position_m - p
                nees.append(e @ np.linalg.solve(f.covariance, e))
            assert 2.3 < np.mean(nees) < 3.9, (mount, p, np.mean(nees))


def test_pixels_at_the_reach_of_a_radial_lens_model():
    """A k1-only calibration of a wide lens (``hearsee calibrate --model radial``) folds back
    before the image corners: no ray reaches them. The fix of a source seen just inside that
    reach raised the camera's GeometryError (its covariance probed the pixel +- 0.5 px, one
    probe beyond the reach), and a detection in the corner aborted the whole stream in
    frame_fix; now the first is a fix with a finite covariance, the second 'not seen'."""
    arr = MicArray.from_preset("three-mic")
    cam = Camera(np.array([[520.0, 0, 319.5], [0, 520.0, 239.5], [0, 0, 1]]),
                 [-0.28, 0.0, 0.0, 0.0, 0.0], 640, 480)
    rig = AudioVisualRig.mounted(arr, cam, (0.0, 0.2, 0.0))
    assert not np.isfinite(cam.pixel_rays([[3.0, 3.0]], unreachable="nan")).any()
    diag = np.arange(0.0, 100.0, 0.01)[:, None] * np.array([[1.0, 0.75]])
    reach = np.isfinite(cam.pixel_rays(diag, unreachable="nan")).all(axis=1)
    uv = diag[np.argmax(reach)]  # the first pixel along the diagonal that has a ray
    assert not reach[np.argmax(reach) - 50]  # (0.5 px up-left of it has none)
    o, d = rig.rays(uv[None])
    src = o + 1.5 * d[0]
    z = arr.tdoa(src)
    fix = locate_on_ray(rig, uv, z)
    assert np.linalg.norm(fix.position_m - src) < 1e-4
    assert np.all(np.isfinite(fix.covariance))
    assert np.all(np.linalg.eigvalsh(fix.covariance) > 0)
    kw = dict(range_m=(0.2, 6.0), sigma_tdoa_s=8e-6, sigma_px=1.0, max_residual_s=1e-4)
    assert frame_fix(rig, lambda t: (3.0, 3.0), 0.2, z, arr.pairs, **kw) == (None, None)
    assert frame_fix(rig, lambda t: (3.0, 3.0), 0.2, None, arr.pairs, **kw) == (None, None)
    got, fix = frame_fix(rig, lambda t: tuple(uv), 0.2, z, arr.pairs, **kw)
    assert np.linalg.norm(fix.position_m - src) < 1e-4


def test_simulate_av_samples_with_a_radial_lens_model():
    """A radial (k1-only) calibration that folds back before the image corners: a pixel drawn
    at margin 0 near them raised the camera's GeometryError (a pixel the caller never gave);
    now such pixels are drawn again, and every sample is in the lens field and exact."""
    arr = MicArray.from_preset("three-mic")
    cam = Camera(np.array([[520.0, 0, 319.5], [0, 520.0, 239.5], [0, 0, 1]]),
                 [-0.28, 0.0, 0.0, 0.0, 0.0], 640, 480)
    rig = AudioVisualRig.mounted(arr, cam, (0.0, 0.2, 0.0))
    X, Y = simulate_av_samples(rig, 500, margin_px=0.0, rng=0)
    assert X.shape == (500, 5) and Y.shape == (500, 3)
    assert cam.in_lens_field(rig.to_optical(Y)).all()
    np.testing.assert_allclose(X[:, :3], arr.tdoa(Y), atol=1e-12)
    np.testing.assert_allclose(X[:, 3:], rig.project(Y), atol=1e-9)
    assert cam.in_image(X[:, 3:], margin=-1e-6).all()
