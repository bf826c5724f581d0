import numpy as np
import pytest

from hearsee.audio.arrays import MicArray
from hearsee.errors import EstimationError, GeometryError
from hearsee.fusion.audiovisual import (
    AudioVisualRegressor,
    AudioVisualRig,
    locate_on_ray,
    ray_residuals,
    simulate_av_samples,
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
    assert fix.residual_s < 1e-8
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


def test_bad_fusion_input(rig):
    with pytest.raises(EstimationError, match="TDOAs"):
        locate_on_ray(rig, [320, 240], [0.0, 0.0])
    with pytest.raises(EstimationError, match="finite"):
        locate_on_ray(rig, [320, 240], [0.0, np.nan, 0.0])
    with pytest.raises(EstimationError, match="image point"):
        locate_on_ray(rig, [320], [0.0, 0.0, 0.0])
    with pytest.raises(EstimationError, match="range_m"):
        locate_on_ray(rig, [320, 240], [0.0, 0.0, 0.0], range_m=(2.0, 1.0))
    with pytest.raises(GeometryError):
        AudioVisualRig(rig.array, rig.camera, np.eye(3) * 2, np.zeros(3))


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
