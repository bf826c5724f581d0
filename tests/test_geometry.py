import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from hearsee.errors import GeometryError
from hearsee.geometry import (
    angle_between,
    cart_to_sph,
    direction_deg,
    sph_to_cart,
    unit_vector_deg,
    wrap_deg,
    wrap_rad,
)


def test_axes_follow_rep103():
    np.testing.assert_allclose(unit_vector_deg(0, 0), [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(unit_vector_deg(90, 0), [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(unit_vector_deg(180, 0), [-1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(unit_vector_deg(0, 90), [0, 0, 1], atol=1e-12)
    az, el = direction_deg([0.0, -2.0, 0.0])
    assert az == pytest.approx(-90.0) and el == pytest.approx(0.0)


@given(
    st.floats(-np.pi + 1e-6, np.pi),
    st.floats(-np.pi / 2 + 1e-3, np.pi / 2 - 1e-3),
    st.floats(0.01, 100.0),
)
def test_spherical_round_trip(az, el, r):
    a, e, d = cart_to_sph(sph_to_cart(az, el, r))
    assert float(wrap_rad(a - az)) == pytest.approx(0.0, abs=1e-9)
    assert float(e) == pytest.approx(el, abs=1e-9)
    assert float(d) == pytest.approx(r, rel=1e-12)


def test_wrap():
    np.testing.assert_allclose(wrap_deg([-180, 180, 190, -190, 540, 0]),
                               [180, 180, -170, 170, 180, 0])
    assert float(wrap_rad(3 * np.pi)) == pytest.approx(np.pi)


def test_angle_between_and_errors():
    assert float(angle_between([1, 0, 0], [0, 2, 0])) == pytest.approx(np.pi / 2)
    with pytest.raises(GeometryError):
        angle_between([0, 0, 0], [1, 0, 0])
    with pytest.raises(GeometryError):
        cart_to_sph([1.0, 2.0])


@pytest.mark.parametrize("scale", [1.0, 1e200, 1e300, 1e-200, 1e-300])
@pytest.mark.parametrize("angle", [1e-9, 1e-8, 3e-8, 0.25, np.pi / 4, np.pi - 1e-9])
def test_angle_between_is_accurate_at_every_angle_and_length(angle, scale):
    """The arccos of the cosine returned 0.0 for angles of 1e-9 and 1e-8 rad, NaN for vectors
    of length 1e200 (the norm overflowed) and 'zero-length vector' for 1e-200 (it underflowed).
    The vectors are built at a known angle, the second 3x longer than the first."""
    u = scale * np.array([1.0, 0.0, 0.0])
    v = 3 * scale * np.array([np.cos(angle), np.sin(angle), 0.0])
    assert float(angle_between(u, v)) == pytest.approx(angle, rel=1e-12)
    assert float(angle_between(v, u)) == pytest.approx(angle, rel=1e-12)
    # batches broadcast as before, each vector scaled on its own
    got = angle_between([[1e-200, 0.0, 0.0], [1e200, 0.0, 0.0]], v)
    np.testing.assert_allclose(got, [angle, angle], rtol=1e-12)


def test_sph_to_cart_refuses_shapes_that_do_not_broadcast():
    """Two azimuths and three elevations raised numpy's builtin broadcast ValueError; now a
    GeometryError; shapes that broadcast give the points they gave."""
    with pytest.raises(GeometryError, match="broadcastable shapes"):
        sph_to_cart([0.0, 1.0], [0.0, 1.0, 2.0])
    with pytest.raises(GeometryError, match="broadcastable shapes"):
        sph_to_cart([0.0, 1.0], 0.0, np.ones(3))
    np.testing.assert_allclose(sph_to_cart([[0.0], [np.pi / 2]], [0.0, np.pi / 2], 2.0),
                               [[[2, 0, 0], [0, 0, 2]], [[0, 2, 0], [0, 0, 2]]], atol=1e-12)


def test_fibonacci_sphere_spreads_unit_vectors_evenly():
    from hearsee.geometry import fibonacci_sphere

    U = fibonacci_sphere(500)
    assert U.shape == (500, 3)
    assert np.allclose(np.linalg.norm(U, axis=1), 1.0)
    # even spread: the mean vector is near zero and every direction has a close neighbour
    assert np.linalg.norm(U.mean(axis=0)) < 0.01
    probe = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.6, 0.0, -0.8]])
    nearest = np.degrees(np.arccos(np.clip(probe @ U.T, -1, 1))).min(axis=1)
    assert nearest.max() < 8.0  # 500 points: ~9 deg apart


def test_cart_to_sph_azimuth_is_in_the_half_open_interval():
    from hearsee.geometry import cart_to_sph, direction_deg

    az, _, _ = cart_to_sph(np.array([[-1.0, -0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]))
    np.testing.assert_allclose(az, [np.pi, np.pi, -np.pi / 2])
    assert float(direction_deg([-1.0, -0.0, 0.0])[0]) == 180.0


def test_cart_to_sph_gives_no_negative_zero_angles():
    """A point with -0.0 coordinates (an in-plane solution's z) gave elevation -0.0, printed
    as "elevation -0.0 deg"; the angles are now +0.0, the point's other angles unchanged."""
    from hearsee.geometry import cart_to_sph

    az, el, _ = cart_to_sph(np.array([[1.0, -0.0, -0.0], [2.0, 0.0, 0.0]]))
    assert np.all(az == 0.0) and np.all(el == 0.0)
    assert not np.any(np.signbit(az)) and not np.any(np.signbit(el))
    az, el, _ = cart_to_sph([0.0, -1.0, -1.0])
    assert float(az) == -np.pi / 2 and float(el) == pytest.approx(-np.pi / 4)


def test_head_pose_refuses_an_integer_beyond_float_range():
    """HeadPose(10**400, 0) raised a builtin TypeError from np.isfinite on the huge int."""
    from hearsee.geometry import HeadPose

    with pytest.raises(GeometryError, match="pan_deg must be finite"):
        HeadPose(10**400, 0.0)
    assert HeadPose(np.int64(30), np.float32(10.0)).as_tuple() == (30.0, 10.0)


def test_head_pose_pan_beyond_any_turn_count_is_refused():
    """A pan of 1e300 deg was taken (its wrap names no direction: at 1e17 deg neighbouring
    floats are 16 deg apart); within MAX_ANGLE_DEG a multi-turn pan still points where its
    wrap does."""
    from hearsee.geometry import MAX_ANGLE_DEG, HeadPose

    for big in (1e300, -1e10, np.nextafter(MAX_ANGLE_DEG, np.inf)):
        with pytest.raises(GeometryError, match="pan_deg must be within"):
            HeadPose(big, 0.0)
    np.testing.assert_allclose(HeadPose(720.0 + 30.0, 0.0).gaze, HeadPose(30.0, 0.0).gaze,
                               atol=1e-12)
    assert HeadPose(-MAX_ANGLE_DEG, 0.0).pan_deg == -MAX_ANGLE_DEG


def test_a_scalar_is_not_a_point():
    """cart_to_sph(5.0) and array_to_robot(5.0, ...) raised a builtin IndexError (shape[-1] of a
    0-d array) instead of the GeometryError that a wrong number of coordinates gets."""
    from hearsee.geometry import array_to_robot, robot_to_array

    for f in (cart_to_sph, direction_deg, lambda p: array_to_robot(p, (0.0, 0.0)),
              lambda p: robot_to_array(p, (0.0, 0.0))):
        with pytest.raises(GeometryError, match="3 coordinates"):
            f(5.0)


def test_points_that_are_not_numbers_are_a_geometry_error():
    """cart_to_sph('abc') and array_to_robot of a ragged list raised numpy's ValueError; the
    one batch check (as_points) of geometry and MicArray's TDOAs names the argument."""
    from hearsee.audio.arrays import MicArray
    from hearsee.geometry import array_to_robot, robot_to_array

    for f in (cart_to_sph, direction_deg, lambda p: array_to_robot(p, (0.0, 0.0)),
              lambda p: robot_to_array(p, (0.0, 0.0))):
        for bad in ("abc", [[1.0, 2.0, 3.0], [1.0, 2.0]]):
            with pytest.raises(GeometryError, match=r"3 coordinates \[x, y, z\].*not numbers"):
                f(bad)
    with pytest.raises(GeometryError, match=r"^source: expected points .*not numbers"):
        MicArray.from_preset("three-mic").tdoa("abc")


def test_points_of_text_or_bools_are_refused():
    """as_points read text as the numbers it spells and True as 1 m: cart_to_sph([["1", "0",
    "0"]]) gave azimuth 0, MicArray.tdoa(["1", "0.5", "0"]) TDOAs. Numbers (NaN included, the
    callers' own rule) pass as before."""
    from hearsee.audio.arrays import MicArray
    from hearsee.geometry import array_to_robot, as_points

    arr = MicArray.from_preset("three-mic")
    for bad in ([["1", "0", "0"]], ("1", "0.5", "0"), [True, 0.0, 0.0],
                np.array([1.0, 0.0, 0.0]).astype(object).astype(str)):
        for f in (cart_to_sph, lambda p: array_to_robot(p, (0.0, 0.0)), arr.tdoa, arr.tdoa_far):
            with pytest.raises(GeometryError, match="not numbers"):
                f(bad)
    np.testing.assert_array_equal(as_points([[1, 2, np.nan]]), [[1.0, 2.0, np.nan]])
    np.testing.assert_array_equal(arr.tdoa([1, 0.5, 0]), arr.tdoa(np.array([1.0, 0.5, 0.0])))


# one [x, y, z] in metres: as_point, the one check of every single-point argument
_NOT_POINTS = [
    [True, 0.0, 1.2],  # numpy read True as 1 m
    ["0", "0", "1.2"],  # ... and strings as numbers
    [10**400, 0.0, 0.0],  # a builtin OverflowError
    [[0.0, 0.0, 1.2]],  # shape (1, 3)
    [0.0, np.nan, 1.2], [0.0, 0.0, np.inf], [0.0, 1.2], "abc", None,
]


@pytest.mark.parametrize("bad", _NOT_POINTS)
def test_pivot_and_offset_must_be_one_finite_point(bad):
    """array_to_robot / robot_to_array accepted bools and numeric strings as coordinates and
    raised a builtin OverflowError (an int beyond float's range) or ValueError ('abc')."""
    from hearsee.geometry import array_to_robot, robot_to_array

    for f in (array_to_robot, robot_to_array):
        for key in ("pivot_m", "offset_m"):
            with pytest.raises(GeometryError, match=rf"^{key} must be a finite \[x, y, z\] in "
                                                    "metres"):
                f([0.0, 0.0, 0.0], (0.0, 0.0), **{key: bad})


def test_as_point_keeps_valid_values_and_takes_the_callers_error():
    from hearsee.errors import ConfigError
    from hearsee.geometry import as_point

    for ok in ([1, 2.5, -3], (np.float32(0.1), np.int64(2), 0.0), np.array([0.0, 0.0, 1.2])):
        p = as_point(ok, "x")
        assert p.dtype == float and p.shape == (3,)
        np.testing.assert_array_equal(p, np.asarray(ok, dtype=float))  # same numbers as before
    with pytest.raises(ConfigError, match=r"^r\.yaml: head\.pivot_m must .* got shape \(1, 3\)"):
        as_point([[0, 0, 1]], "r.yaml: head.pivot_m", ConfigError)


def test_distances_and_directions_of_huge_points_do_not_overflow():
    """cart_to_sph summed squares: (1e300, 1e300, 0) was inf metres away (a RuntimeWarning).
    Ordinary points keep their distance bit for bit; a point beyond float's range (its
    distance is inf) is not a point for as_point."""
    import math
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        az, el, r = cart_to_sph([[1e300, 1e300, 0.0], [0.0, -3e200, 4e200]])
        np.testing.assert_allclose(np.degrees(az), [45.0, -90.0])
        np.testing.assert_allclose(np.degrees(el), [0.0, np.degrees(np.arctan2(4, 3))])
        np.testing.assert_allclose(r, [math.hypot(1e300, 1e300), 5e200], rtol=1e-15)
    from hearsee.geometry import as_point, norm_scale

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p = as_point([1e300, 1e300, 0.0], "p")
        k = norm_scale(p)
        np.testing.assert_allclose(p / k / np.linalg.norm(p / k), [0.5**0.5, 0.5**0.5, 0.0])
    pts = np.random.default_rng(0).normal(size=(1000, 3)) * 10.0
    assert np.all(norm_scale(pts) == 1.0)
    x, y, z = pts.T
    assert cart_to_sph(pts)[2].tobytes() == np.sqrt(x * x + y * y + z * z).tobytes()
    assert np.isinf(cart_to_sph([np.inf, 0.0, 0.0])[2])  # (as before)
    with pytest.raises(GeometryError, match=r"^p: \[1e\+308, -1\.5e\+308, 0\.0\] is farther "):
        as_point([1e308, -1.5e308, 0.0], "p")


def test_cart_to_sph_measures_tiny_vectors():
    """norm_scale also scales vectors whose squares underflow: (1e-300, 1e-300, 0) is
    1.414e-300 m away at azimuth 45 deg (its squares summed to 0); ordinary vectors keep every
    bit (a factor of 1.0)."""
    from hearsee.geometry import cart_to_sph, norm_scale

    az, el, r = cart_to_sph([1e-300, 1e-300, 0.0])
    assert r == pytest.approx(np.sqrt(2) * 1e-300, rel=1e-12)
    assert np.degrees(az) == pytest.approx(45.0) and el == 0.0
    assert np.all(norm_scale([[0.3, -2.0, 1e-200], [0.0, 0.0, 0.0]]) == 1.0)


def test_angle_helpers_refuse_what_is_no_number_and_keep_numpy_semantics_otherwise():
    """The numpy-style angle helpers raised numpy's builtin TypeError / ValueError on text, a
    ragged list or vectors of other shapes, and read True as 1; now a GeometryError naming the
    argument. NaN is still mapped as numpy maps it, and numbers give the values they gave."""
    from hearsee.geometry import fibonacci_sphere

    bad_calls = [
        (lambda: wrap_deg("190"), "angle"),
        (lambda: wrap_rad([0.0, "x"]), "angle"),
        (lambda: wrap_deg(np.array([True, False])), "angle"),
        (lambda: sph_to_cart("a", 0.0), "azimuth"),
        (lambda: sph_to_cart(0.0, [[0.1], [0.2, 0.3]]), "elevation"),
        (lambda: sph_to_cart(0.0, 0.0, None), "distance"),
        (lambda: unit_vector_deg(["x"], 0.0), "azimuth_deg"),
        (lambda: angle_between([1.0, 0.0, 0.0], "v"), "v"),
        (lambda: angle_between(np.ones((2, 3)), np.ones((3, 3))), "broadcastable"),
        (lambda: angle_between([1.0, 0.0], [0.0, 1.0]), r"\(\.\.\., 3\)"),
        (lambda: fibonacci_sphere(2.5), "n must be an integer"),
        (lambda: fibonacci_sphere("12"), "n must be an integer"),
        (lambda: fibonacci_sphere(0), "n must be an integer"),
    ]
    for call, match in bad_calls:
        with pytest.raises(GeometryError, match=match):
            call()
    # numbers: the values of the formulas, NaN passing through
    np.testing.assert_array_equal(wrap_deg([190.0, -190.0, 180.0, -180.0]),
                                  [-170.0, 170.0, 180.0, 180.0])
    assert np.isnan(wrap_deg(np.nan)) and np.isnan(wrap_rad(float("nan")))
    assert wrap_deg(np.float64(370.0)) == pytest.approx(10.0)
    np.testing.assert_allclose(sph_to_cart([0.0, np.pi / 2], 0.0, 2), [[2, 0, 0], [0, 2, 0]],
                               atol=1e-12)
    assert angle_between([1, 0, 0], np.array([[0, 1, 0], [1, 0, 0]])) == pytest.approx(
        [np.pi / 2, 0.0])
    u = fibonacci_sphere(np.int64(7))
    assert u.shape == (7, 3)
    np.testing.assert_allclose(np.linalg.norm(u, axis=1), 1.0)
