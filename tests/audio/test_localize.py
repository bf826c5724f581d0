import numpy as np
import pytest

from hearsee.audio.arrays import MicArray, closure_rms, pair_closure_projector
from hearsee.audio.localize import (
    CLOSURE_STD_FACTOR,
    DEFAULT_TOL_S,
    MAX_POSITION_REL_STD,
    array_geometry,
    cone_points,
    far_field_planar,
    fits_position,
    hyperboloid_points,
    localize_recording,
    localize_tdoa,
    near_field_in_plane,
    near_field_position,
    three_mic_curve,
)
from hearsee.audio.propagation import simulate_free_field
from hearsee.audio.signals import white_noise
from hearsee.errors import ConfigError, GeometryError
from hearsee.geometry import unit_vector_deg, wrap_deg

TWO = MicArray.from_preset("two-mic")
THREE = MicArray.from_preset("three-mic")


def _az(c):
    return [round(a, 6) for a, _ in c]


@pytest.mark.parametrize("az", [30.0, -60.0, 150.0, 0.0, 89.0])
def test_two_mic_azimuth_and_front_back_twin(az):
    loc = localize_tdoa(TWO.tdoa_far(unit_vector_deg(az, 0.0)), TWO)
    front = np.degrees(np.arcsin(np.sin(np.radians(az))))
    twin = 180.0 - front if front >= 0 else -180.0 - front
    assert loc.elevation_deg is None and loc.feasible
    assert loc.n_solutions == 2 and len(loc.candidates) == 2
    assert loc.azimuth_deg == pytest.approx(front, abs=1e-6)  # the front twin first
    got = sorted(_az(loc.candidates))
    assert got == pytest.approx(sorted([front, twin]), abs=1e-6)


def test_two_mic_endfire_single_solution():
    loc = localize_tdoa(TWO.tdoa_far(unit_vector_deg(90.0, 0.0)), TWO)
    assert loc.n_solutions == 1 and loc.azimuth_deg == pytest.approx(90.0)


def test_two_mic_impossible_tdoa_is_infeasible():
    loc = localize_tdoa([1.2 * TWO.max_tdoa()[0]], TWO)
    assert not loc.feasible and loc.n_solutions == 0
    assert loc.azimuth_deg == pytest.approx(90.0)  # t0 > t1: nearest is end-fire at mic 1 (+y)


@pytest.mark.parametrize("az,el", [(30.0, 20.0), (150.0, -40.0), (-100.0, 60.0)])
def test_three_mic_two_mirror_solutions(az, el):
    loc = localize_tdoa(THREE.tdoa_far(unit_vector_deg(az, el)), THREE)
    assert loc.feasible and loc.n_solutions == 2
    assert loc.azimuth_deg == pytest.approx(az, abs=1e-6)
    assert loc.elevation_deg == pytest.approx(abs(el), abs=1e-6)  # above the plane first
    assert sorted(e for _, e in loc.candidates) == pytest.approx([-abs(el), abs(el)], abs=1e-6)


def test_three_mic_in_plane_single_solution():
    loc = localize_tdoa(THREE.tdoa_far(unit_vector_deg(-135.0, 0.0)), THREE)
    assert loc.feasible and loc.n_solutions == 1
    assert loc.candidates[0] == pytest.approx((-135.0, 0.0), abs=1e-3)


def test_three_mic_inconsistent_tdoas_flagged():
    # |u_p| > 1: too large for any direction -> nearest feasible, in the plane
    tau = 1.5 * THREE.tdoa_far(unit_vector_deg(40.0, 0.0))
    loc = localize_tdoa(tau, THREE)
    assert not loc.feasible and loc.n_solutions == 0
    # the least-residual in-plane direction: 40 deg to 3e-5 (the preset's six-decimal
    # coordinates are equilateral to ~1e-6, so it is not exactly u_p / |u_p|)
    assert loc.azimuth_deg == pytest.approx(_least_residual_in_plane_az(THREE, THREE.pairs, tau)[0],
                                            abs=1e-4)
    assert loc.azimuth_deg == pytest.approx(40.0, abs=1e-4) and loc.elevation_deg == 0.0
    # violated closure t01 + t12 != t02
    loc = localize_tdoa([2e-4, -2e-4, 2e-4], THREE)
    assert not loc.feasible and loc.n_solutions == 0 and loc.candidates


def test_three_mic_exact_tdoas_of_near_in_plane_sources_are_one_solution():
    """A talker in the array plane 1-5 m away: the curved wavefront puts the in-plane least
    squares |u_p| a little above 1 at some azimuths (up to ~1.02); exact TDOAs are still one
    feasible solution, near the true azimuth (they were flagged infeasible at 15 of 36)."""
    norms = []
    for r in (1.0, 2.0, 5.0):
        for az in range(-180, 180, 10):
            loc = localize_tdoa(THREE.tdoa(r * unit_vector_deg(az, 0.0)), THREE)
            norms.append(loc.extra["in_plane_norm"])
            assert loc.feasible and loc.n_solutions >= 1, (r, az)
            assert abs(wrap_deg(loc.azimuth_deg - az)) < 1.5, (r, az)  # far-field model
    assert max(norms) > 1.0 + 1e-3  # the branch this test is about was taken


def test_planar_array_in_vertical_plane_mirrors_about_that_plane():
    arr = MicArray(np.array([[0.0, 0.1, 0.0], [0.0, -0.1, 0.0], [0.0, 0.0, 0.12]]))
    geo = array_geometry(arr)
    assert geo.kind == "planar" and abs(geo.normal[0]) == pytest.approx(1.0)
    loc = localize_tdoa(arr.tdoa_far(unit_vector_deg(30.0, 10.0)), arr)
    assert loc.n_solutions == 2
    cands = sorted(loc.candidates)
    assert cands[0] == pytest.approx((30.0, 10.0), abs=1e-6)
    assert cands[1] == pytest.approx((150.0, 10.0), abs=1e-6)


def test_collinear_generic_axis():
    arr = MicArray(np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.25, 0.0, 0.0]]))
    assert array_geometry(arr).kind == "linear"
    loc = localize_tdoa(arr.tdoa_far(unit_vector_deg(40.0, 0.0)), arr)
    assert sorted(_az(loc.candidates)) == pytest.approx([-40.0, 40.0], abs=1e-6)
    vert = MicArray(np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.2]]))
    loc = localize_tdoa(vert.tdoa_far(unit_vector_deg(70.0, 25.0)), vert)
    assert loc.azimuth_deg is None and loc.elevation_deg == pytest.approx(25.0)


def test_volume_array_direction_and_position():
    pos = np.vstack([THREE.positions, [[0.0, 0.0, 0.12]], [[0.02, 0.03, -0.1]]])
    arr = MicArray(pos)
    src = np.array([1.0, 0.6, 0.4])
    loc = localize_tdoa(arr.tdoa(src), arr)
    assert loc.geometry == "volume" and loc.n_solutions == 1
    np.testing.assert_allclose(loc.position_m, src, atol=1e-4)
    far = localize_tdoa(arr.tdoa_far(unit_vector_deg(-70.0, 35.0)), arr)
    assert (far.azimuth_deg, far.elevation_deg) == pytest.approx((-70.0, 35.0), abs=1e-4)
    p, r = near_field_position(arr.tdoa(src), arr, x0=[1.0, 0.0, 0.0])
    np.testing.assert_allclose(p, src, atol=1e-4)
    assert r < 1e-8


def _tetra_and_centre(side: float = 0.15) -> MicArray:
    tet = side / np.sqrt(8) * np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]])
    return MicArray(np.vstack([tet, [[0.0, 0.0, 0.0]]]))


def test_volume_array_direction_from_the_wavefront_curvature():
    """Five or more microphones: a near source's direction comes from the fitted position
    when the point source explains the TDOAs significantly better than a plane wave;
    a plane wave keeps the plane wave's answer; four microphones take a reported position's
    direction unless it is within NEAR_DIRECTION_MIN_RANGE_M of the array centre."""
    from hearsee.audio.localize import far_field_volume
    from hearsee.geometry import angle_between

    arr = _tetra_and_centre()
    src = 0.7 * unit_vector_deg(130.0, 20.0)  # 0.7 m from the 15 cm array
    plane = far_field_volume(arr.tdoa(src), arr)
    assert np.degrees(angle_between(plane.direction, unit_vector_deg(130.0, 20.0))) > 0.5
    loc = localize_tdoa(arr.tdoa(src), arr)
    assert loc.extra["direction_model"] == "position"
    assert (loc.azimuth_deg, loc.elevation_deg) == pytest.approx((130.0, 20.0), abs=1e-4)
    assert loc.candidates == [(loc.azimuth_deg, loc.elevation_deg)] and loc.feasible
    assert loc.residual_s < 1e-9 and loc.extra["far_field"]["residual_s"] > 1e-7
    assert loc.extra["far_field"]["azimuth_deg"] == pytest.approx(plane.azimuth_deg)
    # a plane wave: the plane wave's exact answer
    far = localize_tdoa(arr.tdoa_far(unit_vector_deg(-60.0, -25.0)), arr)
    assert far.extra["direction_model"] == "plane_wave" and "far_field" not in far.extra
    assert (far.azimuth_deg, far.elevation_deg) == pytest.approx((-60.0, -25.0), abs=1e-6)
    # four microphones: three TDOAs fit a position exactly, so its direction is taken only
    # where the position is reported (until 2026-12-07 the plane wave always stayed)
    tet = MicArray(arr.positions[:4])
    four = localize_tdoa(tet.tdoa(src), tet)
    assert four.position_m is not None and four.extra["direction_model"] == "position"
    assert (four.azimuth_deg, four.elevation_deg) == pytest.approx((130.0, 20.0), abs=1e-4)
    assert four.extra["far_field"]["azimuth_deg"] == pytest.approx(
        far_field_volume(tet.tdoa(src), tet).azimuth_deg)
    assert abs(four.extra["far_field"]["elevation_deg"] - 20.0) > 1.0  # (what it corrects)
    # ... and farther than NEAR_DIRECTION_MIN_RANGE_M from the centre: a position 0.2 m away
    # (outside the 9 cm array) keeps the plane wave (reflections pull fits toward the array);
    # a plane wave reports no position
    from hearsee.audio.localize import NEAR_DIRECTION_MIN_RANGE_M

    assert NEAR_DIRECTION_MIN_RANGE_M > 0.2
    close = localize_tdoa(tet.tdoa(0.2 * unit_vector_deg(130.0, 20.0)), tet)
    assert close.position_m is not None and close.extra["direction_model"] == "plane_wave"
    far4 = localize_tdoa(tet.tdoa_far(unit_vector_deg(-60.0, -25.0)), tet)
    assert far4.position_m is None and far4.extra["direction_model"] == "plane_wave"
    # five microphones, but pairs among four of them (microphone 3 left out): three independent
    # TDOAs, the four microphones' rule (these four pairs report no position: the plane wave)
    sub = [(0, 4), (1, 4), (2, 4), (0, 1)]
    few = localize_tdoa(arr.tdoa(src, sub), arr, sub)
    assert few.position_m is None and few.extra["direction_model"] == "plane_wave"
    # a position inside the array's extent is not taken for a talker's (noise pulls far
    # sources' fits there): a point 3 cm from the centre of the 15 cm array keeps the plane wave
    inside = localize_tdoa(arr.tdoa(0.03 * unit_vector_deg(40.0, 10.0)), arr)
    assert np.linalg.norm(inside.position_m) == pytest.approx(0.03, abs=1e-4)
    assert inside.extra["direction_model"] == "plane_wave"
    # without near_field nothing is fitted
    assert localize_tdoa(arr.tdoa(src), arr, near_field=False).position_m is None
    # the direction is the frame's (from its origin, as ground_truth), not the centroid's: a
    # hexagon with a microphone above has its centroid 11 mm above the origin
    ring = [[0.05 * np.cos(a), 0.05 * np.sin(a), 0.0] for a in np.radians(np.arange(0, 360, 60))]
    hex_top = MicArray(np.vstack([ring, [[0.0, 0.0, 0.08]]]))
    near = 0.6 * unit_vector_deg(-100.0, 30.0)
    loc = localize_tdoa(hex_top.tdoa(near), hex_top)
    assert loc.extra["direction_model"] == "position"
    assert (loc.azimuth_deg, loc.elevation_deg) == pytest.approx((-100.0, 30.0), abs=1e-4)


def _circle(n: int, radius: float) -> MicArray:
    phi = 2.0 * np.pi * np.arange(n) / n
    return MicArray(np.c_[radius * np.cos(phi), radius * np.sin(phi), np.zeros(n)])


@pytest.mark.parametrize("el", [1.5, -1.5, 20.0, -35.0])
def test_planar_array_position_up_to_its_mirror(el):
    """A planar array fixes a near source's position up to its mirror image about the array
    plane: the fit returns the image on the normal's side (+z for a horizontal array). A fit
    started in the plane (a far-field answer there, the spherical interpolation's minimum-norm
    solution) used to stay in it: the distance from the plane has no gradient there."""
    from hearsee.audio.localize import _spherical_interpolation

    arr = _circle(8, 0.10)
    src = 0.6 * unit_vector_deg(40.0, el)
    above = src * [1.0, 1.0, -1.0] if el < 0 else src
    p, r = near_field_position(arr.tdoa(src), arr)
    np.testing.assert_allclose(p, above, atol=1e-6)
    assert r < 1e-10
    # the spherical interpolation completes the distance from the plane from its range
    np.testing.assert_allclose(_spherical_interpolation(arr.tdoa(src), arr,
                                                        arr.checked_pairs(None)), above, atol=1e-9)
    # a start in the plane (x0) is lifted off it
    p, _ = near_field_position(arr.tdoa(src), arr, x0=[0.3, 0.3, 0.0])
    np.testing.assert_allclose(p, above, atol=1e-6)


def test_planar_array_direction_from_the_wavefront_curvature():
    """Planar arrays of five or more microphones take a near source's direction from its
    position as volume arrays do (the 1 % likelihood-ratio test), with the mirror image's
    direction as the second candidate (four microphones: a reported position's); a plane
    wave and ``in_plane`` keep their answers."""
    arr = _circle(6, 0.15)
    src = 0.7 * unit_vector_deg(-120.0, 12.0)
    plane = far_field_planar(arr.tdoa(src), arr)
    assert abs(plane.elevation_deg - 12.0) > 0.5  # the curved wavefront misleads the plane wave
    loc = localize_tdoa(arr.tdoa(src), arr)
    assert loc.geometry == "planar" and loc.extra["direction_model"] == "position"
    np.testing.assert_allclose(loc.candidates, [(-120.0, 12.0), (-120.0, -12.0)], atol=1e-5)
    assert (loc.azimuth_deg, loc.elevation_deg) == loc.candidates[0]
    assert loc.n_solutions == 2 and loc.feasible and loc.residual_s < 1e-10
    np.testing.assert_allclose(loc.position_m, src, atol=1e-6)
    assert loc.extra["far_field"]["elevation_deg"] == pytest.approx(plane.elevation_deg)
    # below the plane: the same answer (the array cannot tell), position on the +z side
    below = localize_tdoa(arr.tdoa(src * [1.0, 1.0, -1.0]), arr)
    np.testing.assert_allclose(below.candidates, loc.candidates, atol=1e-5)
    # a plane wave keeps the plane wave's answer
    far = localize_tdoa(arr.tdoa_far(unit_vector_deg(75.0, 30.0)), arr)
    assert far.extra["direction_model"] == "plane_wave" and "far_field" not in far.extra
    np.testing.assert_allclose(far.candidates, [(75.0, 30.0), (75.0, -30.0)], atol=1e-6)
    # a far source with 20 us of TDOA noise: the test keeps the plane wave
    rng = np.random.default_rng(33)
    tau = arr.tdoa(4.0 * unit_vector_deg(10.0, 20.0)) + rng.normal(0.0, 20e-6, 15)
    noisy = localize_tdoa(tau, arr)
    assert noisy.extra["direction_model"] == "plane_wave"
    assert noisy.candidates == far_field_planar(tau, arr).candidates
    # four microphones: the reported position's direction and its mirror image's (the plane
    # wave until 2026-12-07)
    four = _circle(4, 0.15)
    loc4 = localize_tdoa(four.tdoa(src), four)
    assert loc4.extra["direction_model"] == "position" and loc4.position_m is not None
    np.testing.assert_allclose(loc4.candidates, [(-120.0, 12.0), (-120.0, -12.0)], atol=1e-5)
    assert loc4.extra["far_field"]["elevation_deg"] == pytest.approx(
        far_field_planar(four.tdoa(src), four).elevation_deg)
    # in_plane (a source at the array's height) and near_field=False: unchanged
    assert localize_tdoa(arr.tdoa(src), arr, near_field=False).position_m is None
    assert "direction_model" not in localize_tdoa(arr.tdoa(0.7 * unit_vector_deg(50.0)), arr,
                                                  in_plane=True).extra


def test_position_only_where_the_tdoas_determine_the_distance():
    """A 4.5 cm array's TDOAs with 5 us of noise cannot tell a source 2-4 m away from a plane
    wave: no position (every fit used to be reported, most off by more than half the
    distance); the fit stays in ``extra``. A larger array's near source gets one, and a
    declared TDOA error that explains the curvature away withdraws it."""

    small = MicArray.from_preset("respeaker-4")
    rng = np.random.default_rng(34)
    for _ in range(20):
        src = rng.uniform(2.0, 4.0) * unit_vector_deg(rng.uniform(-180, 180), rng.uniform(-30, 30))
        loc = localize_tdoa(small.tdoa(src) + rng.normal(0.0, 5e-6, 6), small)
        assert loc.position_m is None and loc.position_covariance_m2 is None
        assert loc.extra["position_fit_m"].shape == (3,)
        assert loc.distance_rel_std > MAX_POSITION_REL_STD
        assert loc.to_dict()["position_m"] is None
    four = _circle(4, 0.15)  # exact TDOAs of a source 0.7 m from a 30 cm square
    src = 0.7 * unit_vector_deg(-120.0, 12.0)
    loc = localize_tdoa(four.tdoa(src), four)
    np.testing.assert_allclose(loc.position_m, src, atol=1e-6)
    std = np.sqrt(np.diag(loc.position_covariance_m2))
    assert np.all((std > 1e-3) & (std < 0.5)) and loc.distance_rel_std < MAX_POSITION_REL_STD
    # 50 us per pair would explain its curvature (~20 us from the plane wave) away
    loose = localize_tdoa(four.tdoa(src), four, tdoa_std_s=50e-6)
    assert loose.position_m is None
    np.testing.assert_allclose(loose.extra["position_fit_m"], src, atol=1e-6)
    # without near_field nothing is fitted or reported
    none = localize_tdoa(four.tdoa(src), four, near_field=False)
    assert none.distance_rel_std is None and none.to_dict()["position_covariance_m2"] is None
    for bad in (0.0, -1e-6, float("nan"), "5us", 1e200, 1.5):  # (1e200: OverflowError)
        with pytest.raises(GeometryError, match="tdoa_std_s"):
            localize_tdoa(four.tdoa(src), four, tdoa_std_s=bad)
    for bad in (-1.0, float("inf"), None):
        with pytest.raises(GeometryError, match="closure_std_factor"):
            localize_tdoa(four.tdoa(src), four, closure_std_factor=bad)
    # exact TDOAs close every cycle: the declared error is the one used
    assert loc.position_tdoa_std_s == 5e-6 and loose.position_tdoa_std_s == 50e-6


def _cube_8() -> MicArray:
    """A 20 cm cube of eight microphones."""
    return MicArray(0.1 * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1)
                                    for z in (-1, 1)], dtype=float))


def test_position_covariance_matches_the_scatter():
    """A 20 cm cube of eight, sources 1-2 m away, 5 us of i.i.d. TDOA noise declared as such
    (and as independent between pairs: no closure factor): nearly every source gets a
    position, and the truth lies inside the covariance's 95 % ellipsoid about 95 % of the
    time."""
    from scipy.stats import chi2

    cube = _cube_8()
    rng = np.random.default_rng(341)
    inside, n = [], 200
    for _ in range(n):
        src = rng.uniform(1.0, 2.0) * unit_vector_deg(rng.uniform(-180, 180),
                                                      rng.uniform(-30, 30))
        loc = localize_tdoa(cube.tdoa(src) + rng.normal(0.0, 5e-6, 28), cube,
                            closure_std_factor=0.0)
        assert loc.position_tdoa_std_s == 5e-6
        if loc.position_m is not None:
            d = loc.position_m - src
            inside.append(float(d @ np.linalg.solve(loc.position_covariance_m2, d))
                          <= chi2.ppf(0.95, 3))
    assert len(inside) >= 0.95 * n  # (a curvature the noise hides: no position, rarely)
    assert 0.90 <= np.mean(inside) <= 0.99


def test_closure_rms_measures_independent_pair_errors():
    """The closure RMS of pair TDOAs is zero for any consistent set of arrival times and, for
    errors independent between pairs, their standard deviation; pairs without a cycle have
    none."""
    cube = _cube_8()
    prs = cube.checked_pairs(None)
    rng = np.random.default_rng(3501)
    t = rng.normal(0.0, 1e-3, 8)  # arbitrary arrival times: consistent pair differences
    i, j = np.array(prs).T
    assert closure_rms(t[i] - t[j], prs, 8) == pytest.approx(0.0, abs=1e-15)
    noise = [closure_rms(rng.normal(0.0, 7e-6, len(prs)), prs, 8) for _ in range(400)]
    assert np.sqrt(np.mean(np.square(noise))) == pytest.approx(7e-6, rel=0.05)
    star = [(0, k) for k in range(1, 8)]  # n - 1 pairs sharing microphone 0: no cycle
    assert closure_rms(rng.normal(0.0, 7e-6, 7), star, 8) is None
    with pytest.raises(GeometryError, match="pair"):
        closure_rms(np.zeros(2), [(0, 8), (1, 2)], 8)
    with pytest.raises(GeometryError, match="one value per pair"):
        closure_rms(np.zeros(3), prs, 8)
    with pytest.raises(GeometryError, match="pair"):
        pair_closure_projector(((0, 1), (1, 1), (0, 2)), 3)


def test_disagreeing_pairs_raise_the_position_error():
    """TDOAs that err like whole-recording GCC peaks in a room -- a part shared by each
    microphone's pairs (3 us per microphone) and a part of each pair's own (5 us), ~6.6 us per
    pair in all -- while 5 us is declared, as independent errors: taken at their word the
    covariance is overconfident (the truth outside the 95 % ellipsoid for ~40 % of the
    sources: errors shared by a microphone's 7 pairs do not average out over 28 pairs). The
    pairs' closure shows the per-pair part; the default raises the TDOA standard deviation to
    3x it, which covers the truth for nearly every reported position."""
    from scipy.stats import chi2

    cube = _cube_8()
    i, j = np.array(cube.checked_pairs(None)).T
    rng = np.random.default_rng(3502)
    naive, raised, used = [], [], []
    for _ in range(150):
        src = rng.uniform(0.8, 1.6) * unit_vector_deg(rng.uniform(-180, 180),
                                                      rng.uniform(-30, 30))
        e = rng.normal(0.0, 3e-6, 8)
        tau = cube.tdoa(src) + e[i] - e[j] + rng.normal(0.0, 5e-6, 28)
        for out, factor in ((naive, 0.0), (raised, CLOSURE_STD_FACTOR)):
            loc = localize_tdoa(tau, cube, closure_std_factor=factor)
            if factor:
                used.append(loc.position_tdoa_std_s)
            if loc.position_m is not None:
                d = loc.position_m - src
                out.append(float(d @ np.linalg.solve(loc.position_covariance_m2, d))
                           <= chi2.ppf(0.95, 3))
    assert np.median(used) == pytest.approx(3 * 5e-6, rel=0.1)
    assert len(naive) > 140 and np.mean(naive) < 0.75
    assert len(raised) > 100 and np.mean(raised) >= 0.95


def test_in_plane_position_only_when_the_range_is_fitted():
    """``in_plane`` assumes the range (2 m) unless asked to fit it: the assumed point is not a
    position (it was reported as one, every source 2 m away)."""
    src = np.array([0.5, 0.3, 0.0])
    loc = localize_tdoa(THREE.tdoa(src), THREE, in_plane=True)
    assert loc.position_m is None and loc.to_dict()["position_m"] is None
    assumed = loc.extra["assumed_position_m"]
    assert np.linalg.norm(assumed) == pytest.approx(2.0, abs=1e-5)
    assert np.degrees(np.arctan2(assumed[1], assumed[0])) == pytest.approx(loc.azimuth_deg)
    fitted = near_field_in_plane(THREE.tdoa(src), THREE, range_m=None)
    np.testing.assert_allclose(fitted.extra["position_fit_m"], src, atol=1e-3)
    # ... but a 15 cm triangle's two TDOAs do not fix the distance at 5 us: no position
    assert fitted.position_m is None and fitted.distance_rel_std > MAX_POSITION_REL_STD
    exact = near_field_in_plane(THREE.tdoa(src), THREE, range_m=None, tdoa_std_s=1e-8)
    np.testing.assert_allclose(exact.position_m, src, atol=1e-3)


def test_in_plane_fitted_position_reported_where_the_distance_is_fixed():
    """A circle of eight, 15 cm radius, sources in its plane 0.5-2 m away: its 28 TDOAs fix
    the distance (a few per cent at 5 us); the covariance holds the position in the plane
    (zero along the normal) and its in-plane 95 % ellipse covers noisy fits about 95 % of the
    time (noise independent between pairs, declared as such)."""
    from scipy.stats import chi2

    a = 2 * np.pi * np.arange(8) / 8
    c8 = MicArray(np.c_[0.15 * np.cos(a), 0.15 * np.sin(a), 0 * a])
    rng = np.random.default_rng(3530)
    inside, n = [], 200
    for _ in range(n):
        src = rng.uniform(0.5, 2.0) * unit_vector_deg(rng.uniform(-180, 180), 0.0)
        loc = near_field_in_plane(c8.tdoa(src) + rng.normal(0.0, 5e-6, 28), c8, range_m=None,
                                  closure_std_factor=0.0)
        assert loc.position_tdoa_std_s == 5e-6 and loc.position_m is not None
        cov = loc.position_covariance_m2
        np.testing.assert_allclose(cov[2], 0.0, atol=1e-15)  # held in the plane z = 0
        d = (loc.position_m - src)[:2]
        inside.append(float(d @ np.linalg.solve(cov[:2, :2], d)) <= chi2.ppf(0.95, 2))
    assert 0.90 <= np.mean(inside) <= 0.99
    with pytest.raises(GeometryError, match="tdoa_std_s"):
        near_field_in_plane(c8.tdoa(src), c8, range_m=None, tdoa_std_s=-1.0)
    with pytest.raises(GeometryError, match="closure_std_factor"):
        near_field_in_plane(c8.tdoa(src), c8, range_m=None, closure_std_factor=float("nan"))


def test_fits_position_says_where_localize_tdoa_fits_one():
    """fits_position is True exactly where localize_tdoa returns a fitted position (the cube,
    respeaker-4 without in_plane), False for three microphones, a mask, four in a line."""
    cube = MicArray(0.1 * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1)
                                    for z in (-1, 1)], dtype=float))
    line = MicArray(np.c_[0.05 * np.arange(4), np.zeros(4), np.zeros(4)])
    for arr, in_plane, want in ((cube, False, True), ("respeaker-4", False, True),
                                ("respeaker-4", True, False), (THREE, False, False),
                                ("mask2", False, False), (line, False, False)):
        assert fits_position(arr, in_plane) is want, (arr, in_plane)
    src = np.array([0.4, 0.3, 0.2])
    assert "position_fit_m" in localize_tdoa(cube.tdoa(src), cube).extra
    assert "position_fit_m" not in localize_tdoa(THREE.tdoa(src), THREE).extra
    assert "position_fit_m" not in localize_tdoa(line.tdoa(src), line).extra
    r4 = MicArray.from_preset("respeaker-4")
    assert "position_fit_m" in localize_tdoa(r4.tdoa(src), r4).extra
    assert "position_fit_m" not in localize_tdoa(r4.tdoa(src), r4, in_plane=True).extra


def test_in_plane_fitted_position_of_a_source_off_the_plane_is_not_confident():
    """Sources 20-40 deg above an 8-mic circle's plane break the in-plane model; their exact
    TDOAs misfit it (28 pairs, 7 independent, 2 unknowns) and the residual widens the
    covariance: a reported position's 95 % ellipse holds the source's projection on the plane
    (without the residual scaling all 60 were reported, 8 ellipses held it and 32 fits were
    more than 20 % off; now 7). The three-mic triangle's exact fit has no residual: its
    covariance is the TDOA error's alone."""
    from scipy.stats import chi2

    a = 2 * np.pi * np.arange(8) / 8
    c8 = MicArray(np.c_[0.15 * np.cos(a), 0.15 * np.sin(a), 0 * a])
    rng = np.random.default_rng(3604)
    reported = 0
    for _ in range(60):
        src = rng.uniform(0.5, 2.0) * unit_vector_deg(rng.uniform(-180, 180),
                                                      rng.uniform(20, 40))
        loc = near_field_in_plane(c8.tdoa(src), c8, range_m=None)
        fit = loc.extra["position_fit_m"]
        assert abs(loc.azimuth_deg - np.degrees(np.arctan2(src[1], src[0]))) < 0.05
        if loc.position_m is None:
            assert loc.distance_rel_std > MAX_POSITION_REL_STD
            continue
        reported += 1
        d = (fit - src)[:2]  # the projection of src on the plane z = 0
        assert float(d @ np.linalg.solve(loc.position_covariance_m2[:2, :2], d)) <= chi2.ppf(
            0.95, 2)
    assert 3 <= reported <= 30
    # TDOAs whose pairs disagree by ~5 us, the closure ignored (factor 0): the three-mic
    # triangle's relative distance 1-sigma is proportional to the declared error alone, the
    # circle's is held up by its residual at the smaller declared error
    noise = np.random.default_rng(3605).normal(0.0, 5e-6, 28)
    for arr, scaled in ((THREE, False), (c8, True)):
        tau = arr.tdoa(0.6 * unit_vector_deg(40.0, 0.0)) + noise[:len(arr.checked_pairs())]
        rel = [near_field_in_plane(tau, arr, range_m=None, tdoa_std_s=s,
                                   closure_std_factor=0.0).distance_rel_std for s in (1e-6, 2e-6)]
        assert (rel[1] / rel[0] < 1.9) if scaled else rel[1] / rel[0] == pytest.approx(2.0)


def test_near_model_needs_a_significant_likelihood_ratio():
    from hearsee.audio.localize import _near_model_wins

    n = 4  # five microphones: the point source must explain the TDOAs by more than
    margin = np.exp(6.63 / (2 * n))  # chi-square(1) at 1 %: n ln(RSS ratio) > 6.63
    assert _near_model_wins(1e-6, 0.0, n)  # exact point source, inexact plane wave
    assert not _near_model_wins(0.0, 0.0, n)  # both exact: the plane wave
    assert not _near_model_wins(1e-5, 1e-5 / margin * 1.001, n)
    assert _near_model_wins(1e-5, 1e-5 / margin * 0.999, n)


def test_near_field_position_does_not_flip_to_the_far_side():
    # found by a property check (2026-11-27): started from the spherical interpolation only,
    # noisy TDOAs of a five-microphone array (a 15 cm tetrahedron and its centre) could land
    # the fit hundreds of metres away on the far side of the array; both starts (that one and
    # the far-field direction at 2 m) keep the better fit
    from hearsee.audio.localize import _spherical_interpolation

    arr = _tetra_and_centre()
    rng = np.random.default_rng(2785)
    src = np.array([rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-0.5, 0.5)])
    tau = arr.tdoa(src) + rng.normal(0.0, 20e-6, 10)  # 20 us of TDOA noise on 10 pairs
    p_si, r_si = near_field_position(tau, arr, x0=_spherical_interpolation(
        tau, arr, arr.checked_pairs(None)))
    assert p_si @ src < 0 and r_si > DEFAULT_TOL_S  # the failure this guards against
    p, r = near_field_position(tau, arr)
    cos = p @ src / np.linalg.norm(p) / np.linalg.norm(src)
    assert np.degrees(np.arccos(min(cos, 1.0))) < 5.0 and r <= DEFAULT_TOL_S
    # a line of five microphones has a circle of positions, not one: the spherical
    # interpolation used to return one of them with zero residual (0.71 m off here)
    line = MicArray(np.c_[np.linspace(-0.2, 0.2, 5), np.zeros(5), np.zeros(5)])
    with pytest.raises(GeometryError, match="linear"):
        near_field_position(line.tdoa(np.array([1.0, 1.0, 0.0])), line)


def test_nan_tdoa_gives_empty_localization():
    loc = localize_tdoa([np.nan, 0.0, 0.0], THREE)
    assert loc.azimuth_deg is None and loc.candidates == [] and not loc.feasible


def test_wrong_tdoa_count():
    with pytest.raises(GeometryError, match="TDOAs"):
        localize_tdoa([0.0, 0.0], THREE)
    with pytest.raises(GeometryError):
        far_field_planar([0.0], TWO)


def test_loci_lie_on_their_equations():
    src = np.array([1.0, 0.7, 0.4])
    tau = TWO.tdoa(src)[0]
    h = hyperboloid_points(tau, *TWO.positions, c=TWO.speed_of_sound).reshape(-1, 3)
    d = np.linalg.norm(h - TWO.positions[0], axis=1) - np.linalg.norm(h - TWO.positions[1], axis=1)
    np.testing.assert_allclose(d / TWO.speed_of_sound, tau, atol=1e-9)
    cone = cone_points(tau, *TWO.positions, c=TWO.speed_of_sound)[1:].reshape(-1, 3)
    u = cone / np.linalg.norm(cone, axis=1, keepdims=True)
    np.testing.assert_allclose(TWO.tdoa_far(u)[:, 0], tau, atol=1e-9)
    branches = three_mic_curve(THREE.tdoa(src), THREE)
    assert len(branches) == 2
    for b in branches:
        np.testing.assert_allclose(THREE.tdoa(b), np.broadcast_to(THREE.tdoa(src), (len(b), 3)),
                                   atol=1e-7)
    # the true source lies on (one branch of) the curve
    dmin = min(np.min(np.linalg.norm(b - src, axis=1)) for b in branches)
    assert dmin < 0.1


def test_localize_recording_document():
    src = 2.0 * unit_vector_deg(60.0, 0.0)
    x = simulate_free_field(white_noise(0.6, 16000, 7), 16000, THREE, src, snr_db=20, rng=8)
    doc = localize_recording(x, 16000, THREE)
    assert doc["summary"]["azimuth_deg"] == pytest.approx(60.0, abs=2.0)
    assert len(doc["frames"]) > 10
    f = doc["frames"][3]
    assert set(f["tdoa_s"]) == {"0-1", "0-2", "1-2"} and f["valid"]
    assert f["azimuth_deg"] == pytest.approx(60.0, abs=3.0)


def test_localize_recording_four_microphones_summary_from_the_position():
    """Four microphones 0.5 m wide (a small robot's corners), a talker 1.5 m away: the plane
    wave's azimuth is 1.7 deg off (the frames'); the summary takes the reported near-field
    position's direction (since 2026-12-07) and says so (``direction_from_position``)."""
    from hearsee.sim.audio import simulate_recording

    arr = MicArray(np.array([[0.2, 0, 0], [-0.1, 0.25, 0], [-0.1, -0.25, 0], [0, 0, 0.2]]))
    src = 1.5 * unit_vector_deg(18.0, 10.0)
    x, truth = simulate_recording(arr, src, signal="noise", duration_s=1.0, fs=16000,
                                  snr_db=30, seed=342)
    assert (truth["azimuth_deg"], truth["elevation_deg"]) == pytest.approx((18.0, 10.0))
    doc = localize_recording(x, 16000, arr)
    s = doc["summary"]
    assert s["direction_from_position"] is True and s["position_m"] is not None
    np.testing.assert_allclose(s["position_m"], src, atol=0.05)
    assert (s["azimuth_deg"], s["elevation_deg"]) == pytest.approx((18.0, 10.0), abs=0.2)
    frames = [f for f in doc["frames"] if f["valid"]]
    assert len(frames) > 20
    assert abs(np.median([f["azimuth_deg"] for f in frames]) - 18.0) > 1.0  # (plane waves)
    # a three-mic array never localizes from a position
    x3 = simulate_free_field(white_noise(0.6, 16000, 7), 16000, THREE, src, snr_db=20, rng=8)
    assert localize_recording(x3, 16000, THREE)["summary"]["direction_from_position"] is False


def test_localize_recording_in_plane_also_steers_the_summary_search_in_plane():
    """``in_plane`` reaches the whole-recording peak search (estimate_tdoas(source_in_plane)),
    as in bench/doa.py's benchmarked setting, unless the caller sets it. A female voice in the
    array plane of a reverberant room (RT60 0.6 s, 10 dB), placed by the test: the whole-sphere
    search lands on a reflection (~11 deg off), the in-plane one on the talker."""
    from hearsee.audio.propagation import add_noise, room_impulse_responses
    from hearsee.audio.signals import synthetic_voice
    from hearsee.audio.tdoa import estimate_tdoas

    rng = np.random.default_rng(0)
    az, dist = rng.uniform(-180, 180), rng.uniform(1, 3)
    at = np.array([3.5, 3.0, 1.2])
    src = dist * unit_vector_deg(az, 0.0)
    h = room_impulse_responses(16000, THREE.positions + at, src + at, np.array([8.0, 7.0, 3.0]),
                               0.6, speed_of_sound=THREE.speed_of_sound)
    s = synthetic_voice("female", 1.0, 16000, rng)
    x = add_noise(np.array([np.convolve(s, hh)[: len(s)] for hh in h]), 10, rng)
    doc = localize_recording(x, 16000, THREE, in_plane=True)
    sphere = localize_recording(x, 16000, THREE, in_plane=True, source_in_plane=False)
    for flag, d in ((True, doc), (False, sphere)):
        tf = estimate_tdoas(x, 16000, THREE, source_in_plane=flag)
        assert list(d["summary"]["tdoa_s"].values()) == pytest.approx(tf.summary_tdoa_s,
                                                                      abs=1e-9)
    assert abs(wrap_deg(doc["summary"]["azimuth_deg"] - az)) < 2.0
    assert abs(wrap_deg(sphere["summary"]["azimuth_deg"] - az)) > 5.0


def test_in_plane_solutions_report_elevation_plus_zero():
    """The in-plane solver's direction has z = -0.0, reported as elevation -0.0 (printed
    "elevation -0.0 deg" by ``hearsee localize --format table``): now +0.0."""
    src = np.array([-1.2, 1.5, 0.0])
    r = np.linalg.norm(src - THREE.positions, axis=1)
    tau = [(r[i] - r[j]) / THREE.speed_of_sound for i, j in THREE.pairs]
    loc = localize_tdoa(tau, THREE, in_plane=True)
    assert loc.elevation_deg == 0.0 and not np.signbit(loc.elevation_deg)
    assert loc.candidates == [(loc.azimuth_deg, 0.0)]
    assert loc.azimuth_deg == pytest.approx(np.degrees(np.arctan2(1.5, -1.2)), abs=0.05)


def _in_plane_sources(n, seed):
    """Exact near-field TDOAs of in-plane sources 1-3 m from the three-mic centre."""
    rng = np.random.default_rng(seed)
    az = rng.uniform(-180, 180, n)
    r = rng.uniform(1.0, 3.0, n)
    src = r[:, None] * np.stack([np.cos(np.radians(az)), np.sin(np.radians(az)), 0 * az], 1)
    d = np.linalg.norm(src[:, None, :] - THREE.positions[None], axis=-1)
    tau = np.stack([(d[:, i] - d[:, j]) for i, j in THREE.pairs], 1) / THREE.speed_of_sound
    return az, r, tau


def _wrap_err(a, b):
    return np.abs((np.asarray(a) - np.asarray(b) + 180.0) % 360.0 - 180.0)


def test_near_field_in_plane_removes_far_field_bias():
    az, r, tau = _in_plane_sources(200, 3)
    far = [localize_tdoa(t, THREE, near_field=False).azimuth_deg for t in tau]
    default = [localize_tdoa(t, THREE).azimuth_deg for t in tau]  # default: unchanged
    assumed = [localize_tdoa(t, THREE, in_plane=True).azimuth_deg for t in tau]  # 2 m assumed
    exact_r = [near_field_in_plane(t, THREE, range_m=ri).azimuth_deg
               for t, ri in zip(tau, r, strict=True)]
    rms = lambda e: float(np.sqrt(np.mean(e**2)))  # noqa: E731
    e_far = rms(_wrap_err(far, az))
    assert 0.3 < e_far < 0.8  # the plane-wave model's bias for a 15 cm triangle at 1-3 m
    assert np.allclose(default, far)
    assert rms(_wrap_err(assumed, az)) < 0.45 * e_far
    assert _wrap_err(exact_r, az).max() < 1e-4  # the true range: exact azimuth


def test_near_field_in_plane_fitted_range():
    az, r, tau = _in_plane_sources(100, 4)
    locs = [near_field_in_plane(t, THREE, range_m=None) for t in tau]
    err = _wrap_err([lo.azimuth_deg for lo in locs], az)
    assert max(lo.residual_s for lo in locs) < 1e-8  # two TDOAs, two unknowns: exact fit
    assert np.median(err) < 1e-3
    inv = np.array([lo.extra["inverse_range_per_m"] for lo in locs])
    good = err < 1e-3
    assert np.allclose(inv[good], 1.0 / r[good], atol=1e-3)
    pos = locs[int(np.argmax(good))].extra["position_fit_m"]
    k = int(np.argmax(good))
    assert np.linalg.norm(pos[:2]) == pytest.approx(r[k], rel=1e-3) and abs(pos[2]) < 1e-9


def test_near_field_in_plane_fitted_range_fits_close_sources_exactly():
    """Sources 0.5-1 m away: a joint step that would take the range past its bound used to be
    clipped while keeping the angle step made for the unclipped range, so the fit stopped off
    the exact solution (residuals of microseconds, azimuths degrees off) and called it
    feasible. Two TDOAs, two unknowns: the fit is exact at every azimuth."""
    worst = 0.0
    for r in (0.5, 0.7, 1.0):
        for az in np.arange(-180.0, 180.0, 2.5):
            tau = THREE.tdoa(r * unit_vector_deg(az, 0.0))
            loc = near_field_in_plane(tau, THREE, range_m=None)
            worst = max(worst, loc.residual_s)
            assert loc.feasible
    assert worst < 1e-9


def test_near_field_in_plane_noisy_tdoas():
    az, _, tau = _in_plane_sources(200, 5)
    rng = np.random.default_rng(6)
    noisy = tau + 2e-6 * rng.standard_normal(tau.shape)  # ~0.03 samples at 16 kHz
    far = [localize_tdoa(t, THREE, near_field=False).azimuth_deg for t in noisy]
    near = [localize_tdoa(t, THREE, in_plane=True).azimuth_deg for t in noisy]
    assert np.sqrt(np.mean(_wrap_err(near, az) ** 2)) < 0.8 * np.sqrt(
        np.mean(_wrap_err(far, az) ** 2))


def test_near_field_in_plane_bad_input():
    with pytest.raises(GeometryError):
        near_field_in_plane([1e-4], TWO)
    with pytest.raises(GeometryError):
        near_field_in_plane(np.zeros(3), THREE, range_m=0.0)
    with pytest.raises(GeometryError):
        near_field_in_plane(np.zeros(3), THREE, range_m=None, max_inverse_range=-1.0)
    # linear arrays ignore in_plane (their locus is a cone either way)
    tau = TWO.tdoa_far(unit_vector_deg(40.0, 0.0))
    assert localize_tdoa(tau, TWO, in_plane=True).candidates == localize_tdoa(tau, TWO).candidates


def test_public_solvers_refuse_nan_wrong_length_and_bad_tolerance():
    """Bad-input sweep (2026-11-26): the solvers returned NaN azimuths for NaN TDOAs (or raised
    scipy's ValueError), numpy errors for a wrong length, and tol_s 0 divided by zero in the
    in-plane fit. localize_tdoa keeps its documented empty result for NaN TDOAs."""
    two, three = MicArray.from_preset("two-mic"), MicArray.from_preset("three-mic")
    src = 2.0 * unit_vector_deg(30.0, 0.0)  # the in-plane model's assumed range: exact
    t3 = three.tdoa(src)
    assert localize_tdoa(t3, three, in_plane=True).azimuth_deg == pytest.approx(30.0, abs=0.01)
    from hearsee.audio.localize import far_field_linear

    for call in (lambda t: far_field_planar(t, three), lambda t: near_field_in_plane(t, three)):
        for bad, msg in ((np.r_[t3[:2], np.nan], "finite"), (t3[:2], "2 TDOAs for 3")):
            with pytest.raises(GeometryError, match=msg):
                call(bad)
    with pytest.raises(GeometryError, match="finite"):
        far_field_linear([np.nan], two)
    for tol in (0.0, -1e-6, np.nan):
        with pytest.raises(GeometryError, match="tol_s"):
            localize_tdoa(t3, three, tol_s=tol, in_plane=True)
    empty = localize_tdoa([np.nan] * 3, three)
    assert empty.azimuth_deg is None and empty.candidates == []


def test_locus_plots_refuse_degenerate_input():
    """Bad-input sweep (2026-11-26): a zero-length pair gave an all-NaN cone, NaN or negative
    speeds, extents or ranges NaN or degenerate grids, NaN ranges a scipy ValueError."""
    m_i, m_j = [0.0, -0.075, 0.0], [0.0, 0.075, 0.0]
    for f in (hyperboloid_points, cone_points):
        assert np.all(np.isfinite(f(1e-4, m_i, m_j)))
        for args, kw in (((1e-4, m_i, m_i), {}), ((np.nan, m_i, m_j), {}),
                         ((1e-4, m_i, m_j), {"c": 0.0}), ((1e-4, m_i, m_j), {"c": np.nan}),
                         ((1e-4, m_i, m_j), {"extent_m": -3.0}), ((1e-4, [np.nan] * 3, m_j), {}),
                         # (float() read these before 2026-11-26; numpy warns on the array)
                         ((np.array([1e-4]), m_i, m_j), {}), ((1e-4, m_i, m_j), {"c": "343"})):
            with pytest.raises(GeometryError):
                f(*args, **kw)
    three = MicArray.from_preset("three-mic")
    t = three.tdoa([1.0, 0.5, 0.2])
    for ranges in ([np.nan, 1.0], [-1.0, 1.0], []):
        with pytest.raises(GeometryError, match="ranges_m"):
            three_mic_curve(t, three, ranges_m=ranges)


@pytest.mark.parametrize("kw", [{"band_hz": (300.0, 3500.0)}, {"reverb_method": "phat"},
                                {"pairs": [(1, 0)]}, {"in_plane": True}])
def test_localize_recording_refuses_options_a_masked_array_would_ignore(kw):
    """A masked array goes through the mask's own pipeline, which takes none of these: a band,
    a reverberation weighting, pairs or in_plane were dropped without a word (the answer
    silently the default one). None values (the CLI's defaults) still pass. (The ITD filter's
    noises are taken since 2026-12-04: tests/audio/test_mask.py.)"""
    from hearsee.errors import ConfigError

    mask = MicArray.from_preset("mask2")
    x = white_noise(0.3, 16000, 7)
    x = np.stack([x, np.roll(x, 2)])
    with pytest.raises(ConfigError, match="mask"):
        localize_recording(x, 16000, mask, **kw)
    doc = localize_recording(x, 16000, mask, reverb_method=None, in_plane=False)
    assert doc["frames"]


def test_localize_recording_names_a_misspelt_setting():
    """A setting estimate_tdoas does not take (a typo) was its builtin TypeError; now a
    ConfigError naming it and listing the settings. A right one still works."""
    from hearsee.errors import ConfigError

    three = MicArray.from_preset("three-mic")
    x = white_noise(0.3, 16000, 7)
    x = np.stack([x, np.roll(x, 1), np.roll(x, 2)])
    with pytest.raises(ConfigError, match="'min_confidense'.*min_confidence"):
        localize_recording(x, 16000, three, min_confidense=2.0)
    assert localize_recording(x, 16000, three, min_confidence=2.0)["frames"]


def test_volume_solvers_refuse_a_bad_start_or_loss():
    """A NaN, short or non-numeric start position raised scipy's or numpy's ValueError
    ("Initial guess is outside of provided bounds", a broadcast error), an unknown loss
    scipy's ValueError."""
    from hearsee.audio.localize import far_field_volume
    from hearsee.errors import ConfigError

    arr = MicArray(np.vstack([THREE.positions, [[0.0, 0.0, 0.12]], [[0.02, 0.03, -0.1]]]))
    tau = arr.tdoa(np.array([1.0, 0.6, 0.4]))
    for x0 in ([np.nan, 0.0, 0.0], [1.0, 0.0], "abc"):
        with pytest.raises(GeometryError, match="x0"):
            near_field_position(tau, arr, x0=x0)
    with pytest.raises(ConfigError, match="loss"):
        near_field_position(tau, arr, loss="bogus")
    with pytest.raises(ConfigError, match="loss"):
        far_field_volume(tau, arr, loss="bogus")
    p, _ = near_field_position(tau, arr, x0=(1, 0, 0), loss="huber")  # ints and a tuple pass
    np.testing.assert_allclose(p, [1.0, 0.6, 0.4], atol=1e-4)


def test_two_mic_tdoa_just_past_end_fire_is_feasible_within_tol():
    """A pair's TDOA a little beyond its physical maximum (noise at end-fire) was infeasible
    with 0 solutions whatever tol_s, unlike far_field_planar's rule: within tol_s it is the one
    end-fire direction, beyond it infeasible (the azimuth still the nearest, end-fire)."""
    from hearsee.audio.localize import DEFAULT_TOL_S, far_field_linear

    two = MicArray.from_preset("two-mic")
    t_max = two.tdoa_far([0.0, 1.0, 0.0])[0]  # source on the axis (+y, azimuth 90 deg)
    assert abs(t_max) == pytest.approx(float(two.max_tdoa()[0]))
    for excess, ok in ((0.0, True), (0.5 * DEFAULT_TOL_S, True), (2.0 * DEFAULT_TOL_S, False)):
        loc = far_field_linear([t_max + np.sign(t_max) * excess], two)
        assert loc.feasible is ok and loc.n_solutions == (1 if ok else 0)
        assert loc.azimuth_deg == pytest.approx(90.0, abs=1e-6)
        assert [a for a, _ in loc.candidates] == pytest.approx([90.0], abs=1e-6)


def test_cached_array_geometry_is_read_only():
    """array_geometry caches one ArrayGeometry per array for every caller: its arrays were
    writable, so one caller editing (say) the centre changed every later localization."""
    from hearsee.audio.localize import array_geometry

    geo = array_geometry(MicArray.from_preset("three-mic"))
    for v in (geo.centre, geo.basis, geo.normal):
        with pytest.raises(ValueError):
            v[0] = 1.0
    assert not array_geometry(MicArray.from_preset("two-mic")).axis.flags.writeable


_SOLVERS = [localize_tdoa, near_field_position, three_mic_curve]


@pytest.mark.parametrize("solver", _SOLVERS)
@pytest.mark.parametrize("bad", [["1e-4", "2e-4", "0"], [True, False, True],
                                 np.array([1e-4, 2e-4, 0.0]) + 0j])
def test_tdoas_that_are_no_real_numbers_are_refused(solver, bad):
    """Bad-input sweep of the public API: the solvers read text as the numbers it spells, True
    as a TDOA of 1 s and dropped an imaginary part, and answered; a list of words raised
    numpy's builtin ValueError."""
    with pytest.raises(GeometryError, match="real numbers"):
        solver(bad, MicArray.from_preset("three-mic"))


@pytest.mark.parametrize("solver", _SOLVERS)
def test_absurdly_long_tdoas_are_refused(solver):
    """TDOAs of 1e160 s overflowed: localize_tdoa answered a NaN elevation, near_field_position
    and three_mic_curve raised numpy's / scipy's builtin ValueError. Up to an hour an
    impossible TDOA is still answered (feasible=False)."""
    three = MicArray.from_preset("three-mic")
    true = three.tdoa([1.0, 1.7, 0.35])
    with pytest.raises(GeometryError, match="at most 3600 s"):
        solver(true * 1e163, three)
    loc = localize_tdoa(true * 1e3, three)
    assert not loc.feasible and np.isfinite(loc.elevation_deg)
    as_list = localize_tdoa(list(true), three)  # a list of floats is as good as an array
    np.testing.assert_array_equal(as_list.direction, localize_tdoa(true, three).direction)
    assert as_list.azimuth_deg == pytest.approx(np.degrees(np.arctan2(1.7, 1.0)), abs=0.1)


def test_iteration_and_grid_counts_must_be_whole_numbers():
    """near_field_in_plane(n_iter=NaN or 2.5) raised range()'s builtin TypeError and n_iter=-1
    returned the unfitted start; cone_points / hyperboloid_points with n_radial=-1 raised
    numpy's builtin ValueError and 0 returned an empty grid. Now GeometryError naming the
    count; whole counts give the same answers."""
    tau = THREE.tdoa_far(unit_vector_deg(17.0, 0.0))
    for bad in (np.nan, 2.5, -1, 0, True, "8"):
        with pytest.raises(GeometryError, match="^n_iter must be an integer >= 1"):
            near_field_in_plane(tau, THREE, n_iter=bad)
    assert near_field_in_plane(tau, THREE, n_iter=np.int64(8)).azimuth_deg == \
        near_field_in_plane(tau, THREE).azimuth_deg
    mi, mj = [0.0, 0.0, 0.0], [0.1, 0.0, 0.0]
    for f in (cone_points, hyperboloid_points):
        for name in ("n_radial", "n_around"):
            for bad in (-1, 0, 2.5):
                with pytest.raises(GeometryError, match=f"^{name} must be an integer >= 1"):
                    f(1e-4, mi, mj, **{name: bad})
        assert f(1e-4, mi, mj, n_radial=3, n_around=5).shape == (3, 5, 3)


def test_array_geometry_checks_positions_given_as_an_array():
    """A NaN microphone position raised numpy's LinAlgError ("SVD did not converge"), an
    infinite one a RuntimeWarning and a made-up classification, text was read as numbers.
    Positions given as an array are now checked as a MicArray's (GeometryError)."""
    tri = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0]]
    for bad, msg in (([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [np.nan, 0.1, 0.0]], "finite"),
                     ([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [np.inf, 0.1, 0.0]], "finite"),
                     ([[0.0, 0.0, 0.0], ["0.1", 0.0, 0.0], [0.0, 0.1, 0.0]], "numbers"),
                     ([[0.0, 0.0], [0.1, 0.0]], "N x 3")):
        with pytest.raises(GeometryError, match=msg):
            array_geometry(bad)
    geo = array_geometry(np.array(tri))
    assert geo.kind == "planar" and np.array_equal(geo.centre, np.mean(tri, axis=0))


def test_locus_grids_are_bounded_and_rel_tol_checked():
    """cone_points / hyperboloid_points(n_radial=10**9) asked numpy for a grid it could not
    allocate (a builtin MemoryError) and read text microphone positions as numbers;
    array_geometry(rel_tol=NaN) called every array a volume (a line of microphones included)
    and text raised a builtin TypeError. Now GeometryErrors; valid grids and tolerances give
    the same answers."""
    line = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0]]
    for bad in (np.nan, np.inf, "1e-6", True, 0.0, -1e-6, 2.0):
        with pytest.raises(GeometryError, match=r"^rel_tol must be a finite number in \(0, 1\]"):
            array_geometry(line, rel_tol=bad)
    assert array_geometry(line, rel_tol=1e-3).kind == "linear"
    tri = MicArray.from_preset("three-mic")
    assert array_geometry(tri, rel_tol=1e-3).kind == array_geometry(tri).kind == "planar"
    from hearsee.audio.localize import MAX_LOCUS_POINTS

    mi, mj = [0.0, 0.0, 0.0], [0.1, 0.0, 0.0]
    for f in (cone_points, hyperboloid_points):
        for a, b in ((["0", "0", "0"], mj), (mi, [True, 0.0, 0.0])):
            with pytest.raises(GeometryError, match="microphone positions must be finite"):
                f(1e-4, a, b)
        # (just over the bound first: the old code allocated this one, not the others)
        for kw in ({"n_radial": MAX_LOCUS_POINTS + 1, "n_around": 1},
                   {"n_radial": 10**9}, {"n_around": 10**9}):
            with pytest.raises(GeometryError, match=r"points; a locus plot samples at most 1e\+07"):
                f(1e-4, mi, mj, **kw)
        assert f(1e-4, mi, mj, n_radial=MAX_LOCUS_POINTS // 10, n_around=1).shape == (
            MAX_LOCUS_POINTS // 10, 1, 3)
        np.testing.assert_array_equal(f(1e-4, np.array(mi), tuple(mj)), f(1e-4, mi, mj))


def test_exact_end_fire_of_a_horizontal_line_is_feasible():
    """The line's horizontal axis length came out as 0.9999999999999999 for many orientations,
    so an exact end-fire TDOA's cone ratio exceeded 1 by rounding: "infeasible, 0 solutions"
    for the true direction (18-26 % of random orientations with 2-4 microphones)."""
    rng = np.random.default_rng(3)
    for n in (2, 3, 4):
        for _ in range(60):
            phi = rng.uniform(-np.pi, np.pi)
            u = np.array([np.cos(phi), np.sin(phi), 0.0])
            arr = MicArray(np.outer(np.linspace(-0.1, 0.1, n), u))
            for sign in (1.0, -1.0):
                loc = localize_tdoa(arr.tdoa_far(sign * u), arr)
                assert loc.feasible and loc.n_solutions == 1, (n, phi, sign)
                assert abs(wrap_deg(loc.azimuth_deg - np.degrees(np.arctan2(*(sign * u)[1::-1]))
                                    )) < 1e-4


def _rotated(pos, axis: str, deg: float):
    from scipy.spatial.transform import Rotation

    return np.asarray(pos) @ Rotation.from_euler(axis, deg, degrees=True).as_matrix().T


def test_micrometre_rounding_does_not_change_the_array_geometry():
    """Positions written with six decimals (micrometres) are no real geometry: a 4-mic line
    along azimuth 30 deg went to the planar solver (one answer, the front/back twin dropped;
    2 us of noise: median error 88.6 deg) and a respeaker-6 tilted by 30 deg to the volume
    solver (median 8 deg, up to 109). Now a direction counts as flat when it adds at most
    FLAT_TDOA_S to any pair's TDOA; extents of 1-2 cm (29-58 us) stay volume."""
    line = np.round(np.outer(0.05 * np.arange(4), unit_vector_deg(30.0, 0.0)), 6)
    arr = MicArray(line)
    assert array_geometry(arr).kind == "linear" and arr.is_planar
    loc = localize_tdoa(arr.tdoa_far(unit_vector_deg(60.0, 0.0)), arr)
    assert loc.feasible and loc.n_solutions == 2
    assert sorted(_az(loc.candidates)) == pytest.approx([0.0, 60.0], abs=1e-3)

    tilted = MicArray(np.round(_rotated(MicArray.from_preset("respeaker-6").positions, "y",
                                        30.0), 6))
    assert array_geometry(tilted).kind == "planar" and tilted.is_planar
    rng = np.random.default_rng(11)
    errs = []
    for _ in range(40):
        u = unit_vector_deg(rng.uniform(-180, 180), rng.uniform(-30, 30))
        loc = localize_tdoa(tilted.tdoa_far(u) + rng.normal(0, 2e-6, 15), tilted,
                            near_field=False)
        errs.append(min(np.degrees(np.arccos(np.clip(unit_vector_deg(a, e) @ u, -1, 1)))
                        for a, e in loc.candidates))
    assert np.median(errs) < 1.5 and max(errs) < 10.0

    # real extents: a fourth microphone 1 or 2 cm off the three-mic plane, one of respeaker-6's
    # raised by 1 cm, the middle of three 1 cm off their line
    for e in (0.01, 0.02):
        assert array_geometry(MicArray(np.vstack([THREE.positions, [[0.03, 0.02, e]]]))
                              ).kind == "volume"
    raised = MicArray.from_preset("respeaker-6").positions.copy()
    raised[0, 2] = 0.01
    raised = MicArray(raised)
    assert array_geometry(raised).kind == "volume" and not raised.is_planar
    assert array_geometry(np.array([[0.0, -0.075, 0], [0.01, 0, 0], [0.0, 0.075, 0]])
                          ).kind == "planar"
    # the rule's boundary, in seconds of TDOA: just inside linear, just outside planar
    from hearsee.audio.arrays import FLAT_TDOA_S

    c = 343.0
    for f, kind in ((0.99, "linear"), (1.01, "planar")):
        pos = np.array([[0.0, -0.075, 0], [f * FLAT_TDOA_S * c, 0, 0], [0.0, 0.075, 0]])
        assert array_geometry(pos).kind == kind


def _least_residual_in_plane_az(arr, prs, tau):
    """Brute force: the azimuth (deg) of the in-plane (z = 0) unit direction whose far-field
    TDOAs are nearest ``tau`` (RMS), on a 0.01 deg grid refined to 1e-5 deg, and that RMS."""
    A = -np.array([arr.positions[i] - arr.positions[j] for i, j in prs]) / arr.speed_of_sound

    def rms(az_deg):
        th = np.radians(az_deg)
        U = np.stack([np.cos(th), np.sin(th), 0 * th], 1)
        return np.sqrt(np.mean((U @ A.T - tau) ** 2, axis=1))

    grid = np.arange(-180.0, 180.0, 0.01)
    best = grid[np.argmin(rms(grid))]
    fine = best + np.arange(-0.02, 0.02, 1e-5)
    r = rms(fine)
    return float(wrap_deg(fine[np.argmin(r)])), float(r.min())


def test_planar_nearest_direction_is_the_least_residual_one():
    """|u_p| > 1 was answered with u_p / |u_p|, the nearest in-plane direction only for an
    isotropic B^T B: a 40 x 3 cm L-shaped array answered -31.35 deg (45 us residual, flagged
    infeasible) for a source at -25 deg whose TDOAs -25.36 deg fits within 7.5 us."""
    ell = MicArray(np.array([[0.0, 0, 0], [0.40, 0, 0], [0.0, 0.03, 0]]))
    tau = ell.tdoa_far(unit_vector_deg(-25.0, 0.0)) + np.array([-7e-6, -11e-6, -4e-6])
    loc = far_field_planar(tau, ell)
    az, r = _least_residual_in_plane_az(ell, ell.pairs, tau)
    assert loc.extra["in_plane_norm"] > 1.001  # the branch this test is about
    assert loc.azimuth_deg == pytest.approx(az, abs=1e-3) and az == pytest.approx(-25.36, abs=0.01)
    assert loc.residual_s == pytest.approx(r, rel=1e-6) and r < 8e-6
    assert loc.feasible and loc.n_solutions == 1 and loc.elevation_deg == 0.0
    rng = np.random.default_rng(5)
    iso = MicArray(np.array([[0.0, -0.10, 0], [0.0, 0.10, 0], [0.06, 0, 0]]))
    for arr, prs in ((ell, ell.pairs), (iso, iso.pairs), (THREE, [(0, 1), (0, 2)]),
                     (THREE, THREE.pairs)):
        n = 0
        while n < 5:
            tau = arr.tdoa_far(unit_vector_deg(rng.uniform(-180, 180), 0.0), prs)
            tau = tau + rng.normal(0, 10e-6, len(prs))
            loc = far_field_planar(tau, arr, prs)
            if loc.extra["in_plane_norm"] <= 1.001:
                continue
            n += 1
            az, r = _least_residual_in_plane_az(arr, prs, tau)
            assert abs(wrap_deg(loc.azimuth_deg - az)) < 1e-3
            assert loc.residual_s == pytest.approx(r, rel=1e-6)
            assert loc.feasible == (r <= DEFAULT_TOL_S)


def test_near_field_position_needs_three_independent_tdoas():
    """Two independent TDOAs (three microphones; a volume array given two pairs) fix a curve
    of positions, not one: near_field_position returned one point of it with a residual of
    ~0, 1.09 m off for the three-mic preset and a source at (1, 0.5, 0.2), 0.28 m off for a
    cube given two pairs and a start. Now a GeometryError, as for a linear array."""
    src = np.array([1.0, 0.5, 0.2])
    for x0 in (None, [1.0, 0.0, 0.0]):
        with pytest.raises(GeometryError, match="2 independent TDOAs"):
            near_field_position(THREE.tdoa(src), THREE, x0=x0)
    cube = MicArray(np.array([[x, y, z] for x in (-.1, .1) for y in (-.1, .1) for z in (-.1, .1)]))
    for prs in ([(0, 1), (0, 2)], [(0, 1), (1, 2), (0, 2)]):
        with pytest.raises(GeometryError, match="2 independent TDOAs"):
            near_field_position(cube.tdoa(src, prs), cube, pairs=prs, x0=[1.0, 0.0, 0.0])
    line = MicArray(np.c_[np.linspace(-0.2, 0.2, 3), np.zeros(3), np.zeros(3)])
    with pytest.raises(GeometryError, match="linear"):  # (x0 skipped this check)
        near_field_position(line.tdoa(src), line, x0=[1.0, 0.0, 0.0])
    prs = [(0, 1), (0, 2), (0, 4)]  # three independent: the position is fixed
    p, r = near_field_position(cube.tdoa(src, prs), cube, pairs=prs, x0=[1.0, 0.4, 0.1])
    np.testing.assert_allclose(p, src, atol=1e-6)


@pytest.mark.parametrize("tilt", [0.0, 0.001, -0.001, 1.0, -1.0, 20.0, -20.0])
def test_vertical_planar_array_keeps_its_front_side_when_slightly_tilted(tilt):
    """The normal's sign followed any z component above 1e-9: tilting the vertical array of
    test_planar_array_in_vertical_plane_mirrors_about_that_plane by 0.001 deg about y made
    the mirror behind, (150, 10), the primary answer of a source at (30, 10) in front. The
    largest component now decides: +x for this array up to a 45 deg tilt."""
    base = np.array([[0.0, 0.1, 0.0], [0.0, -0.1, 0.0], [0.0, 0.0, 0.12]])
    arr = MicArray(_rotated(base, "y", tilt))
    geo = array_geometry(arr)
    assert geo.kind == "planar" and geo.normal[0] > 0.9
    u = unit_vector_deg(30.0, 10.0)
    loc = localize_tdoa(arr.tdoa_far(u), arr)
    assert loc.n_solutions == 2
    assert np.degrees(np.arccos(min(1.0, loc.direction @ u))) < 1e-6  # the front one first
    flat = MicArray(_rotated(THREE.positions, "y", tilt))  # a horizontal one: +z, as before
    assert array_geometry(flat).normal[2] > 0.9


def test_in_plane_source_of_a_planar_array_is_one_solution_from_the_position():
    """Planar arrays of 5+ microphones take the direction of the near-field position; its fit
    of an in-plane source stops a hair off the plane (elevation ~0.0014 deg), and any height
    above it added the mirror: two "solutions" at +-0.0014 deg where the plane wave of the
    same TDOAs says one. Sources clearly off the plane keep their two mirror solutions."""
    c8 = MicArray(np.array([[0.15 * np.cos(a), 0.15 * np.sin(a), 0.0]
                            for a in np.arange(8) * np.pi / 4]))
    for src in ([1.0, 0.0, 0.0], [-2.0, 0.1, 0.0], [0.4, 0.7, 0.0]):
        loc = localize_tdoa(c8.tdoa(np.array(src)), c8)
        assert loc.extra["direction_model"] == "position"
        assert loc.n_solutions == 1 and len(loc.candidates) == 1 and loc.feasible
        az = np.degrees(np.arctan2(src[1], src[0]))
        assert loc.azimuth_deg == pytest.approx(az, abs=1e-3)
        assert abs(loc.elevation_deg) < 0.01
    for el in (3.0, -10.0):
        src = 1.0 * unit_vector_deg(50.0, el)
        loc = localize_tdoa(c8.tdoa(src), c8)
        assert loc.extra["direction_model"] == "position" and loc.n_solutions == 2
        assert [e for _, e in loc.candidates] == pytest.approx([abs(el), -abs(el)], abs=1e-3)


def test_remaining_parameters_are_checked():
    """Parameters of public solvers that were not checked: far_field_planar(in_plane_tol="1e-3")
    raised a builtin TypeError and -1 or 0.5 answered a source 10 deg above the plane as in
    it; near_field_in_plane(range_m="2") and (max_inverse_range="2") raised builtin
    TypeErrors, True was taken as 1 m and 1e-300 m overflowed; near_field_position(x0=[1e300,
    0, 0]) raised scipy's ValueError; three_mic_curve read ranges_m=["1.5"] as 1.5 m;
    position_tdoa_std raised numpy's ValueError for text TDOAs and returned the declared 5 us
    for NaN ones. Now GeometryErrors; valid values answer as before."""
    from hearsee.audio.localize import position_tdoa_std

    t3 = THREE.tdoa_far(unit_vector_deg(20.0, 10.0))
    for bad in ("0.001", -1.0, 0.0, 0.6, np.nan, True):
        with pytest.raises(GeometryError, match="^in_plane_tol must be a finite number in"):
            far_field_planar(t3, THREE, in_plane_tol=bad)
    loc = far_field_planar(t3, THREE, in_plane_tol=1e-3)
    assert loc.n_solutions == 2 and loc.elevation_deg == pytest.approx(10.0, abs=1e-6)
    for bad in ("2", True, 1e-300, 1e7, np.nan, 0.0, -2.0):
        with pytest.raises(GeometryError, match="^range_m must be a number of metres"):
            near_field_in_plane(t3, THREE, range_m=bad)
    for bad in ("2", True, -1.0, np.inf, 1e300):
        with pytest.raises(GeometryError, match=r"^max_inverse_range \(1/m\) must be"):
            near_field_in_plane(t3, THREE, range_m=None, max_inverse_range=bad)
    assert near_field_in_plane(t3, THREE, range_m=2).azimuth_deg == \
        near_field_in_plane(t3, THREE).azimuth_deg
    tet = MicArray(np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) * 0.05)
    with pytest.raises(GeometryError, match="^x0 too far"):
        near_field_position(tet.tdoa([1.0, 0.0, 0.0]), tet, x0=[1e300, 0.0, 0.0])
    for bad in (["1.5"], [True, 1.0]):
        with pytest.raises(GeometryError, match="^ranges_m must be"):
            three_mic_curve(t3, THREE, ranges_m=bad)
    for bad, msg in ((["a", 0.0, 0.0], "real numbers"), ([np.nan, 0.0, 0.0], "finite"),
                     ([0.0, 0.0], "3 microphone pairs")):
        with pytest.raises(GeometryError, match=msg):
            position_tdoa_std(bad, THREE.pairs, 3, 5e-6)
    for kw in ({"tdoa_std_s": "5e-6"}, {"tdoa_std_s": 0.0}, {"factor": np.nan}):
        with pytest.raises(GeometryError, match=f"^{next(iter(kw))} must be"):
            position_tdoa_std(t3, THREE.pairs, 3, **{"tdoa_std_s": 5e-6, **kw})
    assert position_tdoa_std([1e-4, 2e-4, 1e-4 + 3e-6], THREE.pairs, 3, 5e-6) == \
        pytest.approx(3.0 * 3e-6 / np.sqrt(3))


def test_tilted_line_reports_the_horizontal_answers_own_residual():
    """A line whose axis is tilted out of the horizontal plane: when the cone of a source above
    it misses that plane the answer is the horizontal direction on the axis azimuth, but the
    result said residual 0 (the cone's) with feasible=False and 0 solutions, whatever the miss.
    Now the residual and the flags are the answer's: a 1 deg miss fits within tol_s (one
    solution), a 30 deg one does not."""
    axis = unit_vector_deg(0.0, 45.0)
    line = MicArray(np.outer([0.0, 0.2], axis))
    for el, ok in ((1.0, True), (30.0, False), (60.0, False)):
        tau = line.tdoa_far(unit_vector_deg(0.0, el))
        loc = localize_tdoa(tau, line)
        answer = line.tdoa_far(unit_vector_deg(loc.azimuth_deg, 0.0))
        want = float(np.sqrt(np.mean((answer - tau) ** 2)))
        assert loc.azimuth_deg == pytest.approx(0.0, abs=1e-9) and len(loc.candidates) == 1
        assert loc.residual_s == pytest.approx(want, rel=1e-9) and want > 0
        assert loc.feasible is ok and loc.feasible == (want <= DEFAULT_TOL_S)
        assert loc.n_solutions == (1 if ok else 0) and loc.extra["off_horizontal"]
    loc = localize_tdoa(line.tdoa_far(unit_vector_deg(30.0, 0.0)), line)  # meets the plane
    assert loc.feasible and loc.n_solutions == 2 and loc.residual_s < 1e-12
    assert "off_horizontal" not in loc.extra


def test_three_mic_curve_needs_two_independent_tdoas_of_a_planar_array():
    """A two-microphone or collinear array's TDOAs fix a surface about its axis, not a curve:
    three_mic_curve returned "branches" of arbitrary points of that surface (each where the
    least-squares step from the far-field guess stopped), and for a four-microphone array,
    whose TDOAs fix a point, a ray of points near it. Now GeometryErrors; two pairs of a larger
    planar array still trace their curve."""
    src = np.array([1.0, 0.5, 0.3])
    line = MicArray([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0]])
    tet = MicArray(np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) * 0.05)
    r4 = MicArray.from_preset("respeaker-4")
    for arr, match in ((TWO, "collinear"), (line, "collinear"), (r4, "3 independent"),
                       (tet, "3 independent")):
        with pytest.raises(GeometryError, match=match):
            three_mic_curve(arr.tdoa(src), arr)
    prs = [(0, 1), (0, 2)]
    branches = three_mic_curve(r4.tdoa(src, prs), r4, prs, ranges_m=[np.linalg.norm(src)])
    assert min(np.min(np.linalg.norm(b - src, axis=1)) for b in branches) < 1e-6


@pytest.mark.parametrize("az,el,r", [(0.0, 10.0, 0.3), (0.0, 10.0, 0.6), (-120.0, 10.0, 0.3),
                                     (60.0, 0.0, 1.0), (40.0, 25.0, 1.5), (150.0, -30.0, 2.0)])
def test_three_mic_curve_holds_the_source_and_only_points_of_the_curve(az, el, r):
    """The curve is where both hyperboloids meet: every point of it fits the TDOAs, and the
    source (or its mirror image about the array plane) is on it. A source near the array has
    an in-plane far-field answer (its curved wavefront reads as |u_p| > 1); the branch
    started there never left the plane (the height has no gradient there), so the source 0.3 m
    away and 10 deg up was missing and in-plane near misses of up to 10 us were returned in
    its place; an in-plane source 1 m away got near misses (7.6 us) at 0.5 m on both
    branches."""
    src = THREE.centre + r * unit_vector_deg(az, el)
    mirror = src * [1.0, 1.0, -1.0]
    tau = THREE.tdoa(src)
    ranges = np.array([0.3, 0.5, 0.6, 1.0, 1.5, 2.0, 3.0])
    branches = three_mic_curve(tau, THREE, ranges_m=ranges)
    assert len(branches) == 2
    for b in branches:
        assert np.max(np.abs(THREE.tdoa(b) - tau)) < 1e-8
    near = min(np.min(np.linalg.norm(b - q, axis=1)) for b in branches for q in (src, mirror))
    assert near < 1e-3 * r


def test_localize_recording_in_plane_is_ignored_by_a_volume_array(count_calls):
    """in_plane models a planar array's in-plane source; localize_tdoa ignores it for other
    arrays. localize_recording also passed it as the frames' near_field, so a volume array's
    every frame got a near-field position fit (18x slower for 55 frames of a 5-mic array) and,
    with five or more microphones, possibly its direction from that fit. Now only the summary
    fits a position, and the frames are those of in_plane=False."""
    import hearsee.audio.localize as L

    tet5 = MicArray(np.vstack([np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]])
                               * 0.053, [[0.0, 0.0, 0.0]]]))
    fs = 16000
    src = 0.8 * unit_vector_deg(50.0, 10.0)
    x = simulate_free_field(white_noise(1.0, fs, rng=3), fs, tet5, src, snr_db=20.0, rng=4)
    fits = count_calls(L, "_add_position")
    doc = localize_recording(x, fs, tet5, in_plane=True)
    assert len(fits) == 1 and doc["summary"]["azimuth_deg"] == pytest.approx(50.0, abs=2.0)
    fits.clear()
    plain = localize_recording(x, fs, tet5)
    assert [f["candidates"] for f in doc["frames"]] == [f["candidates"] for f in plain["frames"]]


def test_tdoa_std_is_bounded_in_every_solver():
    """tdoa_std_s=1e200 s overflowed where it was squared (OverflowError tracebacks from
    localize_tdoa's position fit and solve_range_differences; only the CLI's --tdoa-std-us was
    bounded). Every solver now takes (0, MAX_TDOA_STD_S]; at the bound the direction is still
    found, without overflow, and no position is reported (a 1 s error determines none)."""
    import warnings

    from hearsee.audio.active import solve_range_differences
    from hearsee.audio.arrays import MAX_TDOA_STD_S

    vol = MicArray(np.array([[0, 0, 0], [0.2, 0, 0], [0, 0.2, 0], [0, 0, 0.2], [0.1, 0.1, 0.15]]))
    src = np.array([1.0, 0.8, 0.3])
    for bad in (1e200, np.nextafter(MAX_TDOA_STD_S, 2.0)):
        with pytest.raises(GeometryError, match=r"tdoa_std_s must be a finite number in \(0, 1\]"):
            localize_tdoa(vol.tdoa(src), vol, tdoa_std_s=bad)
        with pytest.raises(GeometryError, match="tdoa_std_s"):
            solve_range_differences([vol.positions], [vol.pairs], [vol.tdoa(src)],
                                    tdoa_std_s=bad)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (the overflow warned before it raised)
        loc = localize_tdoa(vol.tdoa(src), vol, tdoa_std_s=MAX_TDOA_STD_S)
    assert loc.position_m is None
    # atan2(0.8, 1.0) = 38.66 deg
    assert loc.azimuth_deg == pytest.approx(np.degrees(np.arctan2(0.8, 1.0)), abs=0.5)


@pytest.mark.parametrize("array", ["two-mic", "three-mic", "mask2", "respeaker-4"])
def test_localize_recording_checks_the_tdoa_error_on_every_array(array):
    """``tdoa_std_s`` only sets a fitted position's error, which arrays of three microphones
    or fewer never get: -1 or "x" passed there without a word (the CLI refused them)."""
    arr = MicArray.from_preset(array)
    x = white_noise(0.3, 16000, 7)
    x = np.stack([np.roll(x, k) for k in range(arr.n_mics)])
    for bad in (-1.0, "x", float("nan")):
        with pytest.raises(GeometryError, match="tdoa_std_s must be a finite number"):
            localize_recording(x, 16000, arr, tdoa_std_s=bad)


@pytest.mark.parametrize("preset, dead", [("respeaker-6", 1), ("respeaker-4", 3),
                                          ("three-mic", 1)])
def test_a_dead_microphone_is_left_out_and_the_others_localize(preset, dead):
    """One microphone unplugged (its channel only noise) made every pair, frame and the summary
    null -- six microphones with one dead heard nothing. The others now localize as an array of
    their own: the summary's direction is the truth's (two microphones: the truth's cone), the
    dead microphone's pairs stay null, the rest are numbered as the array's, and one warning
    says so."""
    import warnings

    from hearsee.audio.localize import localize_recording
    from hearsee.errors import DeadMicrophoneWarning
    from hearsee.sim.audio import simulate_recording

    arr = MicArray.from_preset(preset)
    src = np.array([1.5, 1.0, 0.3])
    x, truth = simulate_recording(arr, src, "male", 3.0, 16000, 20.0, seed=4,
                                  room={"room_dim": [6, 5, 3], "rt60": 0.3})
    clean = localize_recording(x, 16000, arr)["summary"]
    x[dead] = np.random.default_rng(0).standard_normal(x.shape[1]) * np.std(x[dead])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        doc = localize_recording(x, 16000, arr)
    told = [str(w.message) for w in caught if issubclass(w.category, DeadMicrophoneWarning)]
    keep = [m for m in range(arr.n_mics) if m != dead]
    assert len(told) == 1 and told[0].startswith(f"microphone {dead} hears nothing")
    assert f"the direction comes from microphones {', '.join(map(str, keep))} alone" in told[0]
    s = doc["summary"]
    assert s["dead_microphones"] == [dead] and s["microphones_used"] == keep
    assert clean["microphones_used"] == list(range(arr.n_mics))
    assert doc["array"]["name"] == arr.name and list(s["tdoa_s"]) == arr.pair_labels
    for label, v in s["tdoa_s"].items():
        i, j = map(int, label.split("-"))
        if dead in (i, j):
            assert v is None
        else:  # the direct path's TDOA, within a sample and a half
            assert abs(v - truth["tdoa_s"][label]) < 1.5 / 16000
    assert all(f["tdoa_s"][label] is None for f in doc["frames"] for label in s["tdoa_s"]
               if str(dead) in label.split("-"))
    assert sum(f["azimuth_deg"] is not None for f in doc["frames"]) > 0.5 * len(doc["frames"])
    if len(keep) > 2:
        assert abs(wrap_deg(s["azimuth_deg"] - truth["azimuth_deg"])) < 6.0
    else:  # the pair's cone: its two in-plane candidates mirror about the pair's axis
        assert s["elevation_deg"] is None and len(s["candidates"]) == 2


def test_pairs_that_leave_a_microphone_out_are_refused_before_the_estimation_with_kalman():
    """pairs (0, 1), (1, 2) of a four-microphone array leave microphone 3's delay unknown: the
    ITD Kalman filter (state: every microphone's delay) refused them with a GeometryError only
    after the whole estimation; now a ConfigError before it, naming kalman=False -- with which
    they localize -- and pairs that connect every microphone are taken."""
    from hearsee.sim.audio import simulate_recording

    src = np.array([1.0, 1.0, 0.2])
    x, truth = simulate_recording("respeaker-4", src, "noise", 1.0, snr_db=20, seed=344)
    calls = []
    with pytest.raises(ConfigError, match=r"do not connect all 4 microphones.*kalman=False"):
        localize_recording(x, 16000, "respeaker-4", pairs=[(0, 1), (1, 2)],
                           progress=calls.append)
    assert calls == []  # (nothing estimated)
    out = localize_recording(x, 16000, "respeaker-4", pairs=[(0, 1), (1, 2)], kalman=False)
    want = truth["tdoa_s"]["0-1"]
    assert abs(out["summary"]["tdoa_s"]["0-1"] - want) < 2e-6
    localize_recording(x, 16000, "respeaker-4", pairs=[(0, 1), (1, 2), (2, 3)])


def test_hyperboloid_points_reach_extent_m_from_the_pair_centre():
    """The docstring says points out to extent_m from the pair's centre, as cone_points; the
    sheet was cut at a radius of extent_m about the axis instead: 3.37 m for extent 3 m at
    c tdoa = 0.46 of the spacing, 16.5 m near end-fire (0.98), its far rim off any plot."""
    mi, mj = np.array([0.0, -0.075, 0.0]), np.array([0.0, 0.075, 0.0])
    centre = (mi + mj) / 2
    for frac in (-0.98, -0.5, 0.0, 0.46, 0.8, 0.98):
        tau = frac * 0.15 / 343.0
        h = hyperboloid_points(tau, mi, mj, c=343.0, extent_m=3.0, n_radial=30, n_around=24)
        r = np.linalg.norm(h - centre, axis=-1)
        assert r.max() == pytest.approx(3.0, rel=1e-9)  # the rim is at extent_m
        assert r[-1] == pytest.approx(np.full(24, 3.0), rel=1e-9)
        d = np.linalg.norm(h - mi, axis=-1) - np.linalg.norm(h - mj, axis=-1)
        np.testing.assert_allclose(d, 343.0 * tau, atol=1e-12)  # and still on the sheet
    with pytest.raises(GeometryError, match="does not reach the sheet"):
        hyperboloid_points(0.9 * 0.15 / 343.0, mi, mj, c=343.0, extent_m=0.05)
