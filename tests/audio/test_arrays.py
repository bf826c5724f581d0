import numpy as np
import pytest

from hearsee.audio.arrays import MicArray, list_presets, load_array
from hearsee.errors import ConfigError, GeometryError, InputFileError


def test_presets_exist_and_match_the_thesis():
    names = list_presets()
    for n in ("two-mic", "three-mic", "respeaker-4", "respeaker-6"):
        assert n in names
    two = MicArray.from_preset("two-mic")
    np.testing.assert_allclose(two.positions, [[0, -0.075, 0], [0, 0.075, 0]])
    three = MicArray.from_preset("three-mic")
    np.testing.assert_allclose(three.pair_distance(), [0.15, 0.15, 0.15], atol=1e-5)
    np.testing.assert_allclose(three.centre, 0, atol=1e-6)
    assert three.pairs == [(0, 1), (0, 2), (1, 2)]
    assert three.pair_labels == ["0-1", "0-2", "1-2"]


def test_tdoa_sign_and_far_field_limit():
    two = MicArray.from_preset("two-mic")
    # source on the left (+y): it reaches mic 1 (left) first, so t_0 - t_1 > 0
    left = two.tdoa([0.0, 2.0, 0.0])
    assert left[0] > 0
    assert left[0] == pytest.approx((2.075 - 1.925) / 343.0)
    # far away the near-field TDOA tends to the plane-wave one
    u = np.array([np.cos(0.3), np.sin(0.3), 0.0])
    np.testing.assert_allclose(two.tdoa(1e4 * u), two.tdoa_far(u), rtol=1e-5)
    assert two.max_tdoa()[0] == pytest.approx(0.15 / 343.0)


def test_tdoa_jacobian_matches_central_differences():
    three = MicArray.from_preset("three-mic")
    p = np.array([0.9, -0.4, 0.3])
    h = 1e-6
    num = np.stack([(three.tdoa(p + h * e) - three.tdoa(p - h * e)) / (2 * h)
                    for e in np.eye(3)], axis=1)  # (n_pairs, 3)
    jac = three.tdoa_jacobian(p)
    assert jac.shape == (3, 3)
    np.testing.assert_allclose(jac, num, rtol=1e-6, atol=1e-12)
    # one pair, in the order asked for (the reversed pair flips the sign)
    np.testing.assert_allclose(three.tdoa_jacobian(p, [(2, 1)]), -num[[2]], rtol=1e-6,
                               atol=1e-12)
    with pytest.raises(GeometryError):
        three.tdoa_jacobian(three.positions[1])


def test_yaml_round_trip(tmp_path):
    a = MicArray.from_preset("three-mic")
    p = tmp_path / "a.yaml"
    import yaml

    p.write_text(yaml.safe_dump(a.to_dict()))
    b = load_array(p)
    np.testing.assert_allclose(a.positions, b.positions)
    assert b.speed_of_sound == 343.0 and b.name == "three-mic"


@pytest.mark.parametrize(
    "text, exc, words",
    [
        ("microphones: [[0,0,0]]", GeometryError, "at least 2"),
        ("microphones: [[0,0,0],[0,0,0.0001]]", GeometryError, "coincide"),
        ("microphones: [[0,0],[1,0]]", ConfigError, "shape"),
        ("micro: [[0,0,0],[1,0,0]]", ConfigError, "unknown key 'micro'"),
        ("name: x", ConfigError, "missing required key 'microphones'"),
        ("microphones: [[0,0,0],[1,0,0]]\nspeed_of_sound: -3", GeometryError, "speed_of_sound"),
        # (1e12 m/s made every TDOA ~0: a confident answer 180 deg off; 34.3: cm/ms mixed up)
        ("microphones: [[0,0,0],[1,0,0]]\nspeed_of_sound: 1e12", GeometryError,
         "speed_of_sound must be 100 to 2000 m/s"),
        ("microphones: [[0,0,0],[1,0,0]]\nspeed_of_sound: 34.3", GeometryError,
         "speed_of_sound must be 100 to 2000 m/s"),
        ("microphones: [[0,0,0], [1, 0, .nan]]", ConfigError, "finite"),
        # (true read as 1 m, '0.5' as 0.5 m; a 400-digit int was a builtin OverflowError)
        ("microphones: [[0,0,0], [true, 0, 0]]", ConfigError, "microphones: expected numbers"),
        ("microphones: [[0,0,0], ['0.5', 0, 0]]", ConfigError, "microphones: expected numbers"),
        ("microphones: [[0,0,0], [1" + "0" * 400 + ", 0, 0]]", ConfigError,
         "microphones: expected numbers"),
        ("microphones: [[0,0,0", ConfigError, "invalid YAML"),
    ],
)
def test_bad_array_files(tmp_path, text, exc, words):
    p = tmp_path / "bad.yaml"
    p.write_text(text)
    with pytest.raises(exc, match=words):
        MicArray.from_yaml(p)


def test_missing_file_and_unknown_preset(tmp_path):
    with pytest.raises(InputFileError):
        load_array(tmp_path / "nope.yaml")
    with pytest.raises(ConfigError, match="unknown array preset"):
        load_array("five-mic")
    # (both were "unknown array preset" before 2026-11-26)
    with pytest.raises(InputFileError, match="is a folder"):
        load_array(tmp_path)
    # "" is Path("."), a folder: it was ": is a folder" before 2026-12-03
    for empty in ("", "  "):
        with pytest.raises(ConfigError, match="array: empty; expected a preset name .*two-mic"):
            load_array(empty)
    with pytest.raises(InputFileError, match="no such array file"):
        load_array(tmp_path / "my-array")
    # a YAML suffix in any case names a file (config.names_a_file), never a preset: a missing
    # "mics.YAML" was "unknown array preset 'mics.YAML'"
    for name in ("mics.YAML", "mics.Yml", "nope.yaml"):
        with pytest.raises(InputFileError, match="no such array file"):
            load_array(name)


def test_array_mapping_name_and_speed_of_sound():
    """An empty ``name:`` named the array "None"; a numpy float speed of sound was refused as
    "not a number", a NaN one passed to the array's own check."""
    mics = [[0.0, -0.1, 0.0], [0.0, 0.1, 0.0]]
    assert MicArray.from_dict({"microphones": mics, "name": None}).name == "custom"
    assert MicArray.from_dict({"microphones": mics, "name": 7}).name == "7"
    arr = MicArray.from_dict({"microphones": mics, "speed_of_sound": np.float64(340.0)})
    assert arr.speed_of_sound == 340.0
    for bad in (float("nan"), "343", True):
        with pytest.raises(ConfigError, match="speed_of_sound must be a finite number"):
            MicArray.from_dict({"microphones": mics, "speed_of_sound": bad})


def test_pair_indices_are_checked_everywhere():
    """Bad-input sweep (2026-11-26): a negative index wrapped around (pair (0, -1) was (0, 2)),
    (1, 1) gave 0 s, an index past the end raised an IndexError, no pairs an IndexError."""
    arr = MicArray.from_preset("three-mic")
    for pairs, msg in (([(0, -1)], "invalid microphone pair"), ([(1, 1)], "invalid"),
                       ([(0, 7)], "invalid"), ([], "no microphone pairs")):
        for call in (lambda p: arr.tdoa([1.0, 0.0, 0.0], p), lambda p: arr.max_tdoa(p),
                     lambda p: arr.tdoa_far([1.0, 0.0, 0.0], p),
                     lambda p: arr.tdoa_jacobian([1.0, 0.0, 0.0], p)):
            with pytest.raises(GeometryError, match=msg):
                call(pairs)
    assert arr.tdoa([1.0, 0.0, 0.0], [(0, 2)]) == pytest.approx(arr.tdoa([1.0, 0.0, 0.0])[1])


def test_constructor_refuses_non_numeric_input_with_a_geometry_error():
    """MicArray(...) is public: ragged or non-numeric positions raised numpy's ValueError, a
    speed of sound of None or 'fast' float()'s TypeError / ValueError."""
    for pos in ([[0, 0, 0], [1, 0]], [["a", 0, 0], [1, 0, 0]], None):
        with pytest.raises(GeometryError, match="positions"):
            MicArray(pos)
    for c in (None, "fast", [343.0]):
        with pytest.raises(GeometryError, match="speed_of_sound"):
            MicArray([[0, 0, 0], [0.1, 0, 0]], c)
    assert MicArray([[0, 0, 0], [0.1, 0, 0]], np.float32(340.0)).speed_of_sound == 340.0


def test_a_pair_must_be_two_whole_indices():
    """checked_pairs' docstring promises a GeometryError for a pair that is not two indices:
    one pair given bare, (0, 1) instead of [(0, 1)], raised TypeError ("object of type 'int'
    has no len()") and fractional indices were truncated, (0.7, 1.9) silently meaning (0, 1)."""
    arr = MicArray.from_preset("three-mic")
    src = [1.0, 0.5, 0.0]
    for pairs in ((0, 1), [(0.7, 1.9)], [(0, np.nan)], [(0, np.inf)], 3):
        with pytest.raises(GeometryError, match="pair"):
            arr.tdoa(src, pairs)
    want = arr.tdoa(src)[[1]]
    for ok in ([(0, 2)], [(np.int64(0), np.int64(2))], np.array([[0, 2]]), [(0.0, 2.0)]):
        np.testing.assert_allclose(arr.tdoa(src, ok), want)


def test_far_field_direction_must_be_finite():
    """tdoa_far([inf, 0, 0]) returned NaN TDOAs without a word, and a NaN direction was
    refused as 'the zero vector'."""
    two = MicArray.from_preset("two-mic")
    for bad in ([np.inf, 0.0, 0.0], [1.0, np.nan, 0.0], [[1.0, 0.0, 0.0], [0.0, -np.inf, 0.0]]):
        with pytest.raises(GeometryError, match="finite"):
            two.tdoa_far(bad)
    # any finite non-zero length is just a direction
    np.testing.assert_allclose(two.tdoa_far([0.0, 5.0, 0.0]), [0.15 / 343.0])


def test_tdoa_source_must_be_finite():
    """tdoa of a NaN or infinite source returned NaN TDOAs without a word (tdoa_far checks);
    a batch with one bad point names how many and the first."""
    three = MicArray.from_preset("three-mic")
    for bad in ([np.nan, 0.0, 1.0], [1.0, np.inf, 0.0], [0.0, 0.0, -np.inf]):
        with pytest.raises(GeometryError, match=r"^source must be finite \[x, y, z\] in metres"):
            three.tdoa(bad)
    batch = np.ones((4, 2, 3))
    batch[2, 1, 0] = np.nan
    batch[3, 0, 2] = np.inf
    with pytest.raises(GeometryError, match=r"got 2 of 8 points, e\.g\. \[nan, 1\.0, 1\.0\]$"):
        three.tdoa(batch, [(0, 1)])
    good = np.ones((4, 2, 3))
    np.testing.assert_array_equal(three.tdoa(good[2, 1]), three.tdoa(good)[2, 1])


def test_points_that_are_not_xyz_are_a_geometry_error():
    """A 2-D point raised numpy's ValueError from tdoa (broadcast), tdoa_far (matmul) and
    tdoa_jacobian (reshape)."""
    three = MicArray.from_preset("three-mic")
    for bad in ([1.0, 0.0], [[1.0, 0.0], [0.0, 1.0]], 1.0):
        for call in (three.tdoa, three.tdoa_far, three.tdoa_jacobian):
            with pytest.raises(GeometryError, match=r"\[x, y, z\]"):
                call(bad)
    assert three.tdoa(np.ones((4, 2, 3))).shape == (4, 2, 3)  # batches still work
    assert three.tdoa_far(np.ones((5, 3))).shape == (5, 3)


def test_tdoa_jacobian_takes_one_finite_point():
    """tdoa_jacobian reshaped a (1, 3) point (and any 3 numbers) into one, gave NaN rows for
    an infinite point, blamed a NaN one on "a microphone's position", read True and "0.5" as
    numbers and raised a builtin OverflowError on a huge int."""
    three = MicArray.from_preset("three-mic")
    p = [0.9, -0.4, 0.3]
    for bad in ([p], [0.9, np.inf, 0.3], [0.9, np.nan, 0.3], [True, -0.4, 0.3],
                ["0.9", "-0.4", "0.3"], [10**400, 0.0, 0.0]):
        with pytest.raises(GeometryError, match=r"^source must be a finite \[x, y, z\]"):
            three.tdoa_jacobian(bad)
    np.testing.assert_array_equal(three.tdoa_jacobian(tuple(p)), three.tdoa_jacobian(np.array(p)))


def test_positions_and_speed_of_sound_must_be_real_numbers():
    """Bad-input sweep of the public API: MicArray read complex positions without their
    imaginary part, bools as 0/1 m and text ('0.1') as the numbers it spells; a speed of sound
    '343' as 343 m/s; positions of 1e200 m made an array of aperture inf (every TDOA NaN)."""
    ok = [[0, 0, 0], [0.1, 0, 0]]
    for bad in (np.array(ok, dtype=complex), np.array(ok, dtype=bool),
                [["0", "0", "0"], ["0.1", "0", "0"]], [[0, 0, 0], [True, 0, 0]]):
        with pytest.raises(GeometryError, match="table of numbers"):
            MicArray(bad)
    for c in ("343", True):
        with pytest.raises(GeometryError, match="speed_of_sound"):
            MicArray(ok, c)
    with pytest.raises(GeometryError, match="overflow"):
        MicArray([[0, 0, 0], [1e200, 0, 0], [0, 1e200, 0]])
    with pytest.raises(ConfigError, match="mapping"):
        MicArray.from_dict(None)
    assert MicArray(np.array([[0, 0, 0], [1, 0, 0]], dtype=np.int64)).aperture == 1.0


def test_far_field_direction_of_any_length_and_too_distant_source():
    """tdoa_far([1e300, 1e300, 0]) gave TDOAs of 0 (u / inf) and [1e-300, 0, 0] was refused as
    the zero vector; tdoa of a source 1e300 m away gave NaN TDOAs. Directions of any finite
    non-zero length are the same direction now; a source that far is a GeometryError."""
    three = MicArray.from_preset("three-mic")
    for scale in (1e300, 1e-300, 1e-160, 1e160):
        np.testing.assert_allclose(three.tdoa_far(np.array([1.0, 1.0, 0.0]) * scale),
                                   three.tdoa_far([1.0, 1.0, 0.0]), rtol=1e-12, atol=0)
    d = np.array([[3.0, -4.0, 0.0], [0.0, 0.0, 2.0]])  # ordinary lengths: bit-identical
    np.testing.assert_array_equal(three.tdoa_far(d), three.tdoa_far(d / 5.0 * [[1], [2.5]]))
    with pytest.raises(GeometryError, match="too far"):
        three.tdoa([1e300, 0.0, 0.0])
    np.testing.assert_allclose(three.tdoa([1e6, 1e6, 0.0]), three.tdoa_far([1.0, 1.0, 0.0]),
                               atol=1e-12)


def test_an_array_spec_that_is_no_name_is_refused():
    """An array of positions where a MicArray or a name belongs (estimate_tdoas(x, fs,
    positions)) was read as a file name: an OSError "File name too long", or for a short one an
    "unknown array preset" named after numpy's printout. Now one ConfigError naming what came."""
    for bad in (np.zeros((3, 3)), 3, None, [[0.0, 0.1, 0.0], [0.0, -0.1, 0.0]]):
        with pytest.raises(ConfigError, match="^array: expected a MicArray, a preset name or a"):
            load_array(bad)
    assert load_array("two-mic").n_mics == 2 and load_array(MicArray.from_preset("two-mic"))


@pytest.mark.parametrize("name", ["[1, 2]", "{a: 1}", "true"])
def test_an_array_name_that_is_no_text_is_refused(tmp_path, name):
    """A list or a mapping was printed as the array's name ("hearsee localize ([1, 2],
    phat)"); a number is read as its text."""
    p = tmp_path / "a.yaml"
    p.write_text(f"name: {name}\nmicrophones: [[0, -0.1, 0], [0, 0.1, 0]]\n")
    with pytest.raises(ConfigError, match="name must be text"):
        load_array(p)
    p.write_text("name: 7\nmicrophones: [[0, -0.1, 0], [0, 0.1, 0]]\n")
    assert load_array(p).name == "7"


@pytest.mark.parametrize("positions", [None, [], np.zeros((3, 2)), [[0, 0, np.nan], [1, 0, 0]],
                                       "abc"])
def test_span_dimension_refuses_what_is_no_set_of_positions(positions):
    """None was numpy's AxisError, an empty set a LinAlgError."""
    from hearsee.audio.arrays import span_dimension

    with pytest.raises(GeometryError, match="positions must be"):
        span_dimension(positions, 343.0)
    assert span_dimension([[0, 0, 0], [1, 0, 0]], 343.0)[0] == 1


def test_closure_rms_refuses_values_that_are_no_numbers():
    """Text was numpy's builtin ValueError, and numbers written as text were read as numbers
    (["1", "2", "3"] gave a closure of 1.15)."""
    from hearsee.audio.arrays import closure_rms

    pairs = [(0, 1), (0, 2), (1, 2)]
    for values in ("abc", ["1", "2", "3"], [1e-4, "2e-4", 1e-4], None):
        with pytest.raises(GeometryError, match="^closure_rms: values must be numbers"):
            closure_rms(values, pairs, 3)
    with pytest.raises(GeometryError, match="one value per pair"):
        closure_rms([1e-4, 2e-4], pairs, 3)
    assert closure_rms([1e-4, 2e-4, 2e-4], pairs, 3) == pytest.approx(1e-4 / np.sqrt(3))
    assert closure_rms(np.array([1e-4, 2e-4]), [(0, 1), (0, 2)], 3) is None


def test_pair_closure_projector_takes_a_list_or_an_array_of_pairs():
    """A list of pairs (the other functions' type) or an integer array was lru_cache's builtin
    TypeError, "unhashable type"; a bad pair is a GeometryError."""
    from hearsee.audio.arrays import pair_closure_projector

    as_tuple = pair_closure_projector(((0, 1), (0, 2), (1, 2)), 3)
    for pairs in ([(0, 1), (0, 2), (1, 2)], [[0, 1], [0, 2], [1, 2]], np.array([[0, 1], [0, 2],
                                                                                  [1, 2]])):
        P, dof = pair_closure_projector(pairs, 3)
        assert dof == 1 and P is as_tuple[0]  # (the same cached projector)
    # its residual: consistent values t_i - t_j pass, a closure error does not
    t = np.array([0.0, 1e-4, 3e-4])
    consistent = np.array([t[0] - t[1], t[0] - t[2], t[1] - t[2]])
    np.testing.assert_allclose(P @ consistent, 0.0, atol=1e-18)
    assert np.linalg.norm(P @ (consistent + [0.0, 0.0, 3e-5])) > 1e-5
    assert pair_closure_projector([(0, 1), (0, 2)], 3) is None  # no cycle
    with pytest.raises(GeometryError, match="invalid microphone pair"):
        pair_closure_projector([(0, 1), (0, 3)], 3)


@pytest.mark.parametrize("pairs", ["01", b"01", "0-1"])
def test_pairs_given_as_text_name_the_pairs(pairs):
    """Text was read character by character ("a pair is two microphone indices, got '0'")."""
    from hearsee.audio.arrays import check_pairs, pair_matrix

    arr = MicArray.from_preset("three-mic")
    for call in (lambda: check_pairs(pairs, 3), lambda: pair_matrix(3, pairs),
                 lambda: arr.tdoa([1.0, 0.0, 0.0], pairs), lambda: arr.max_tdoa(pairs)):
        with pytest.raises(GeometryError, match=r"^pairs must be a list of \(i, j\) microphone"):
            call()
    assert check_pairs([(0, 1)], 3) == [(0, 1)]


def test_micarray_name_and_mask_types():
    """name=None printed as the array's name everywhere; mask="x" failed later in the mask
    module with a builtin AttributeError."""
    pos = [[0.0, -0.1, 0.0], [0.0, 0.1, 0.0]]
    with pytest.raises(ConfigError, match="^MicArray name must be text, got None"):
        MicArray(pos, name=None)
    with pytest.raises(ConfigError, match="^array 'p': mask must be a mapping"):
        MicArray(pos, name="p", mask="x")
    assert MicArray(pos, name="p").name == "p" and MicArray(pos, mask=None).mask is None


def test_residual_scaled_variance_needs_a_positive_tdoa_std():
    """sig 0 divided the residuals by zero (a NaN variance with a RuntimeWarning), NaN passed
    through; a valid sig keeps the robust rule."""
    from hearsee.audio.arrays import residual_scaled_variance

    r = np.array([1e-5, -2e-5, 3e-5, 0.0, 1e-5])
    for bad in (0.0, -1e-5, float("nan")):
        with pytest.raises(GeometryError, match="sig"):
            residual_scaled_variance(r, bad, 3)
    assert residual_scaled_variance(r, 1e-3, 3) == pytest.approx(1e-6)  # (sig^2 dominates)


def test_microphone_counts_have_a_ceiling():
    """10**9 or 10**20 microphones hung the pair helpers and the ITD filter building their
    pairs; an array of more than MAX_MICS positions would have asked for a distance table of
    their square; 10**9 sphere points was a MemoryError. Now typed errors at once."""
    from hearsee.audio.arrays import MAX_MICS, closure_rms, pair_matrix
    from hearsee.audio.itd_filter import ItdKalman
    from hearsee.geometry import fibonacci_sphere

    with pytest.raises(GeometryError, match="n_mics"):
        pair_matrix(10**20, [(0, 1)])
    with pytest.raises(GeometryError, match="n_mics"):
        closure_rms([0.0], [(0, 1)], 10**20)
    with pytest.raises(GeometryError, match="n_mics"):
        ItdKalman(10**9)
    with pytest.raises(GeometryError, match=f"at most {MAX_MICS} microphones"):
        MicArray(np.random.default_rng(0).uniform(-1, 1, (MAX_MICS + 1, 3)))
    with pytest.raises(GeometryError, match="n must be"):
        fibonacci_sphere(10**9)
    assert pair_matrix(4, [(0, 1), (2, 3)]).shape == (2, 3)
    assert fibonacci_sphere(100).shape == (100, 3)


def test_a_pair_is_an_ordered_sequence_of_two_indices_not_bools_or_a_set():
    """(True, False) was read as the pair (1, 0) without a word, a set {0, 2} raised a builtin
    TypeError ('set' object is not subscriptable; and a set has no order, so no TDOA sign),
    a mapping a builtin KeyError."""
    from hearsee.audio.arrays import check_pairs

    arr = MicArray.from_preset("three-mic")
    src = [1.0, 0.5, 0.0]
    for pairs in ([(True, False)], [(np.True_, np.False_)], np.array([[True, False]]),
                  [{0, 2}], [{0: 1, 2: 3}], [(0, True)]):
        with pytest.raises(GeometryError, match="a pair is two microphone indices"):
            arr.tdoa(src, pairs)
        with pytest.raises(GeometryError, match="a pair is two microphone indices"):
            check_pairs(pairs, 3)
    d = np.linalg.norm(np.asarray(src) - arr.positions, axis=1)  # hand-made truth: t_1 - t_0
    for ok in ([(1, 0)], [[1, 0]], np.array([[1, 0]]), [range(1, -1, -1)]):
        np.testing.assert_allclose(arr.tdoa(src, ok), [(d[1] - d[0]) / 343.0], rtol=1e-12)


def test_position_uncertainty_of_a_position_at_its_reference_point():
    """A source at the array centre (a 10 cm tetrahedron has no microphone there) with exact
    TDOAs raised numpy's LinAlgError "SVD did not converge" after a RuntimeWarning (0 / 0);
    seen from the point itself there is no distance or direction: both 1-sigmas are inf, and
    the covariance is the one of any other point, s^2 (J^T J)^-1."""
    import warnings

    from hearsee.audio.arrays import pair_tdoa, pair_tdoa_jacobian, position_uncertainty

    arr = MicArray(0.05 * np.array([[1, 1, 1], [-1, -1, 1], [-1, 1, -1], [1, -1, -1]]))
    M, c = arr.positions, arr.speed_of_sound
    a, b = np.array(arr.pairs).T
    ref = np.zeros(3)
    p = np.zeros(3)  # the source at the reference point
    y = pair_tdoa(p, M, a, b, c)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cov, rel, ang, cond = position_uncertainty(p, M, a, b, c, y, 2e-6, ref, 0.3)
    assert rel == np.inf and ang == np.inf
    J = pair_tdoa_jacobian(p, M, a, b, c)
    np.testing.assert_allclose(cov, 4e-12 * np.linalg.inv(J.T @ J), rtol=1e-9)
    # a point elsewhere is as before: finite, its own covariance
    q = np.array([0.3, 0.2, 0.1])
    cov_q, rel_q, ang_q, _ = position_uncertainty(q, M, a, b, c, pair_tdoa(q, M, a, b, c), 2e-6,
                                                  ref, 0.3)
    Jq = pair_tdoa_jacobian(q, M, a, b, c)
    np.testing.assert_allclose(cov_q, 4e-12 * np.linalg.inv(Jq.T @ Jq), rtol=1e-9)
    assert np.isfinite(rel_q) and np.isfinite(ang_q)


@pytest.mark.parametrize(("blank", "value"), [('""', ""), ("' '", " "), ('"\\t"', "\t")])
def test_a_blank_array_name_is_no_name(tmp_path, blank, value):
    """'name: ""' named the array "" (hearsee localize's table was titled "hearsee localize
    (, phat)"), where an empty 'name:' takes the file's stem."""
    p = tmp_path / "rig.yaml"
    p.write_text(f"name: {blank}\nmicrophones: [[0, -0.1, 0], [0, 0.1, 0]]\n")
    assert load_array(p).name == "rig"
    mics = [[0, -0.1, 0], [0, 0.1, 0]]
    assert MicArray.from_dict({"name": value, "microphones": mics}).name == "custom"
    p.write_text("name:\nmicrophones: [[0, -0.1, 0], [0, 0.1, 0]]\n")
    assert load_array(p).name == "rig"


def test_a_preset_name_is_never_a_path(tmp_path):
    """from_preset("/abs/file") or "../arrays/two-mic" read a file outside the presets' folder
    (the suffix added); a preset is a bundled one's plain name, and load_array takes paths."""
    (tmp_path / "mine.yaml").write_text("microphones: [[0, 0.1, 0], [0, -0.1, 0]]\n")
    for name in (str(tmp_path / "mine"), "../arrays/two-mic", "./two-mic"):
        with pytest.raises(ConfigError, match=r"unknown array preset .*presets: .*two-mic"):
            MicArray.from_preset(name)
    assert load_array(tmp_path / "mine.yaml").n_mics == 2
    assert load_array(str(tmp_path / "mine.yaml")).n_mics == 2
    assert MicArray.from_preset("two-mic").n_mics == load_array("two-mic").n_mics == 2
