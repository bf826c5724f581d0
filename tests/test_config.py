"""hearsee.config: numbers from mappings and plain-Python conversion for YAML/JSON."""

import numpy as np
import pytest

from hearsee.config import (
    as_float_array,
    finite_number,
    is_real,
    load_yaml,
    number,
    save_yaml,
    time_limit,
    to_jsonable,
    whole_number,
)
from hearsee.errors import ConfigError, EstimationError, GeometryError, InputFileError


def test_number_takes_numpy_scalars_and_refuses_non_numbers():
    d = {"a": np.int64(7), "b": np.float32(0.5), "c": True, "d": np.bool_(True), "e": "3",
         "f": float("nan"), "g": 2.5}
    assert number(d, "a", 0, "x", integer=True) == 7  # np.int64 was refused
    assert number(d, "b", 0.0, "x") == pytest.approx(0.5)
    for key in ("c", "d", "e", "f"):
        with pytest.raises(ConfigError, match=f"x.{key}: expected a number"):
            number(d, key, 0, "x")
    with pytest.raises(ConfigError, match="whole number"):
        number(d, "g", 0, "x", integer=True)
    with pytest.raises(ConfigError, match="must be <= 2"):
        number(d, "a", 0, "x", hi=2)
    assert number({}, "missing", 4, "x") == 4.0


def test_is_real_and_finite_number():
    for v in (1, 2.5, np.float32(0.5), np.int64(-3), np.array(4.0)):
        assert is_real(v), v
    for v in (True, np.bool_(False), "3", float("nan"), np.float32("inf"), None, [1.0],
              np.array([1.0]), 1 + 2j):
        assert not is_real(v), v
    assert finite_number("a", np.float32(0.25), 0.0, 1.0) == 0.25
    assert isinstance(finite_number("a", np.int64(3)), float)
    cases = [(0.0, dict(lo=0.0, lo_open=True), "a must be a finite number > 0, got 0.0"),
             (-1, dict(lo=0.0), "a must be a finite number >= 0, got -1"),
             (2.0, dict(lo=0.0, hi=1.0), r"a must be a finite number in \[0, 1\], got 2.0"),
             (0.0, dict(lo=0.0, hi=1.0, lo_open=True), r"in \(0, 1\]"),
             (5, dict(hi=4.0), "a must be a finite number <= 4, got 5"),
             ("1", {}, "a must be a finite number, got '1'"),
             (float("nan"), dict(lo=0.0), "got nan")]
    for value, kw, msg in cases:
        with pytest.raises(ConfigError, match=msg):
            finite_number("a", value, **kw)
    with pytest.raises(EstimationError, match="b must be"):  # the caller's own exception type
        finite_number("b", float("inf"), error=EstimationError)


def test_whole_number_bounds_and_none_as_no_bound():
    """lo=None is no lower bound (as in finite_number), not a builtin TypeError comparing the
    value with None; the other bounds keep their rule and message."""
    assert whole_number("n", 3) == 3 and isinstance(whole_number("n", np.int64(3)), int)
    assert whole_number("n", -7, lo=None) == -7
    assert whole_number("n", -7, lo=None, hi=5) == -7
    assert whole_number("n", 0, lo=0, hi=0) == 0
    cases = [(0, {}, r"n must be an integer >= 1, got 0"),
             (6, dict(lo=2, hi=5), r"n must be an integer in \[2, 5\], got 6"),
             (6, dict(lo=None, hi=5), r"n must be an integer <= 5, got 6"),
             (2.5, dict(lo=None), r"n must be an integer, got 2.5"),
             ("3", dict(lo=None), r"n must be an integer, got '3'"),
             (None, dict(lo=None), r"n must be an integer, got None"),
             (True, dict(lo=None, hi=5), r"n must be an integer <= 5, got True")]
    for value, kw, msg in cases:
        with pytest.raises(ConfigError, match=msg):
            whole_number("n", value, **kw)
    with pytest.raises(GeometryError, match="n_mics must be an integer"):
        whole_number("n_mics", "two", lo=None, error=GeometryError)


def test_save_yaml_and_json_take_numpy_values(tmp_path):
    data = {"name": np.str_("rig"), "K": np.eye(2), "n": np.int32(3), "ok": np.bool_(True),
            "bad": np.float64("nan")}
    save_yaml(data, tmp_path / "a.yaml")  # np.str_ made YAML raise RepresenterError
    back = load_yaml(tmp_path / "a.yaml")
    assert back["name"] == "rig" and back["K"] == [[1.0, 0.0], [0.0, 1.0]] and back["n"] == 3
    assert back["ok"] is True
    assert to_jsonable(data)["bad"] is None and to_jsonable(data)["name"] == "rig"
    # text load_yaml would read as a number comes back as text (a bare 2e5 was 200000.0)
    save_yaml({"name": "2e5", "serial": "1E6", "x": 2e5}, tmp_path / "b.yaml")
    assert load_yaml(tmp_path / "b.yaml") == {"name": "2e5", "serial": "1E6", "x": 2e5}


def test_load_yaml_reads_exponent_numbers_without_a_dot(tmp_path):
    """YAML 1.1 (PyYAML's default) reads ``1e9`` as a string; an array file with
    ``speed_of_sound: 1e3`` failed with "must be a number, got '1e3'"."""
    from hearsee.audio.arrays import load_array

    p = tmp_path / "a.yaml"
    p.write_text("a: 1e9\nb: 5E-3\nc: -2.5e+1\nd: 12\ne: 1.5\nf: '1e9'\ng: 1e\nh: .5e1\n")
    d = load_yaml(p)
    assert d == {"a": 1e9, "b": 0.005, "c": -25.0, "d": 12, "e": 1.5, "f": "1e9", "g": "1e",
                 "h": 5.0}
    assert isinstance(d["d"], int) and isinstance(d["a"], float)
    p.write_text("microphones: [[0, 0, 0], [1e-1, 0, 0]]\nspeed_of_sound: 3.4e2\n")
    arr = load_array(p)
    assert arr.speed_of_sound == 340.0 and arr.positions[1, 0] == 0.1


def test_load_yaml_refuses_a_key_given_twice(tmp_path):
    """PyYAML kept the last of two equal keys of a mapping without a word (a second ``head:``
    block of a robot file dropped the first's pivot, offset and limits). load_yaml refuses
    it, naming the key, the file and both lines; a key that overrides one a merge (``<<``)
    brings in is no duplicate, and keys in different mappings never are."""
    p = tmp_path / "robot.yaml"
    p.write_text("audio:\n  array: three-mic\nhead:\n  pivot_m: [0, 0, 1.4]\n"
                 "output: {report: out}\nhead:\n  pose_deg: [30, 0]\n", encoding="utf-8")
    with pytest.raises(ConfigError) as exc:
        load_yaml(p)
    assert str(exc.value) == (f"{p}: invalid YAML at line 6, column 1: duplicate key 'head' "
                              "(first given at line 3; a key may be given once)")
    for text, key, line in (("a:\n  b: 1\n  c: 2\n  b: 3\n", "'b'", 2),
                            ("a: [{x: 1, y: 2, x: 1}]\n", "'x'", 1),
                            ("a: {1: 2, 1.0: 3}\n", "1.0", 1)):
        p.write_text(text, encoding="utf-8")
        with pytest.raises(ConfigError, match=f"duplicate key {key} \\(first given at line "
                                              f"{line};"):
            load_yaml(p)
    p.write_text("base: &b {array: three-mic, fs: 8000}\naudio: {<<: *b, fs: 16000}\n"
                 "x: [{k: 1}, {k: 2}]\ny: {k: 3}\n", encoding="utf-8")
    assert load_yaml(p) == {"base": {"array": "three-mic", "fs": 8000},
                            "audio": {"array": "three-mic", "fs": 16000},
                            "x": [{"k": 1}, {"k": 2}], "y": {"k": 3}}


def test_load_yaml_nested_too_deeply_is_a_config_error(tmp_path):
    """PyYAML's parser recurses once per level: a file nested a few hundred levels deep
    raised a builtin RecursionError (a traceback from `hearsee run`). It is a ConfigError;
    a deep but ordinary nesting still loads."""
    p = tmp_path / "deep.yaml"
    for text in ("audio: " + "[" * 3000 + "]" * 3000 + "\n",
                 "a:\n" + "".join("  " * k + "b:\n" for k in range(1, 3000))):
        p.write_text(text, encoding="utf-8")
        with pytest.raises(ConfigError) as exc:
            load_yaml(p)
        assert str(exc.value) == f"{p}: invalid YAML: nested too deeply"
    p.write_text("a: " + "[" * 50 + "1" + "]" * 50 + "\n", encoding="utf-8")
    v = load_yaml(p)["a"]
    for _ in range(50):
        v = v[0]
    assert v == 1


def test_load_yaml_unreadable_file_is_a_typed_error(tmp_path, deny_reading):
    """A file without read permission (PermissionError) escaped load_yaml as a builtin OSError:
    a traceback in every CLI command that reads a YAML file."""
    from hearsee.errors import InputFileError

    p = tmp_path / "array.yaml"
    p.write_text("microphones: [[0, 0, 0]]\n")
    deny_reading("read_text")
    with pytest.raises(InputFileError, match="Permission denied"):
        load_yaml(p)


def test_a_ragged_list_is_not_a_finite_number():
    """is_real let numpy's ValueError out of a ragged list ([1, [2, 3]]: numpy cannot make an
    array of it), so finite_number, number and the entries of as_float_array / as_point (a
    microphone [0.1, [0, 0]]) raised it instead of hearsee's error."""
    for ragged in ([1, [2, 3]], [[1, 2], [3]], [[1, [2]], 3]):
        assert not is_real(ragged)
    with pytest.raises(ConfigError, match=r"^a must be a finite number, got \[1, \[2, 3\]\]$"):
        finite_number("a", [1, [2, 3]])
    with pytest.raises(ConfigError, match=r"^w\.k: expected a number, got \[1, \[2, 3\]\]$"):
        number({"k": [1, [2, 3]]}, "k", 1.0, "w")


def test_an_integer_too_large_for_a_float_is_not_a_finite_number():
    """is_real said True for a 400-digit int (a YAML integer literal), so finite_number and
    number raised a builtin OverflowError from float() instead of their ConfigError."""
    huge = 10**400
    assert not is_real(huge) and not is_real(-huge)
    assert is_real(10**300) and is_real(2**1023)
    with pytest.raises(ConfigError, match="a must be a finite number > 0"):
        finite_number("a", huge, 0.0, lo_open=True)
    with pytest.raises(ConfigError, match="w.k: expected a number"):
        number({"k": huge}, "k", 1.0, "w")


def test_time_limit_reads_none_and_inf_as_no_limit():
    """The one rule behind DeviceSource's and the robot's MappedSource's duration_s."""
    assert time_limit("duration_s", None) is None
    assert time_limit("duration_s", float("inf")) is None
    assert time_limit("duration_s", np.float64("inf")) is None
    assert time_limit("duration_s", 2) == 2.0 and time_limit("duration_s", np.float32(0.5)) == 0.5
    for bad in (0, -1.0, float("nan"), -float("inf"), "inf", True, [1.0]):
        with pytest.raises(ConfigError, match="duration_s"):
            time_limit("duration_s", bad)
    with pytest.raises(EstimationError):
        time_limit("duration_s", 0.0, error=EstimationError)


def test_time_limit_error_says_inf_means_no_limit():
    """It accepts inf (no limit) but said "must be a finite number > 0", as if inf were refused;
    the message names both choices (and the value as given)."""
    rule = "--duration must be a number of seconds > 0, or inf for no limit, got "
    for bad, shown in ((0, "0"), (-2.5, "-2.5"), (float("nan"), "nan"), (-float("inf"), "-inf"),
                       ("inf", "'inf'"), (True, "True")):
        with pytest.raises(ConfigError) as exc:
            time_limit("--duration", bad)
        assert str(exc.value) == rule + shown


def test_a_time_limit_no_run_reaches_is_no_limit():
    """1e306 s passed the check and overflowed the sample count (int(d * fs)) into a builtin
    OverflowError once a live stream started; from MAX_TIME_LIMIT_S (31.7 years) on it is no
    limit (the stream's DeviceSource: tests/stream/test_pipeline.py)."""
    from hearsee.config import MAX_TIME_LIMIT_S

    assert time_limit("duration_s", 1e306) is None
    assert time_limit("duration_s", MAX_TIME_LIMIT_S) is None
    assert time_limit("duration_s", MAX_TIME_LIMIT_S / 2) == MAX_TIME_LIMIT_S / 2


def test_as_float_array_refuses_entries_that_are_not_real_numbers():
    """numpy's float conversion read True as 1.0 and "0.5" as 0.5 (a microphone, a head offset,
    a pan limit), converted a bool or complex array (the imaginary part dropped) and raised a
    builtin OverflowError on an int beyond float's range; each is now the typed error."""
    for bad in ([True, 0, 0], [[0.1, 0, 0], [0, np.bool_(False), 0]], ["0.5", 0, 0],
                [10**400, 0, 0], np.array([True, False, True]), np.array(["1", "2", "3"]),
                np.array([1 + 1j, 0, 0]), np.array([1.0, True, 0.0], dtype=object), None):
        with pytest.raises(ConfigError, match="^w: expected numbers, got "):
            as_float_array(bad, "w")
    with pytest.raises(ConfigError, match="^w: values must be finite numbers$"):
        as_float_array([0.0, np.nan, 1.0], "w")  # (a float entry: finite is the next check)


def test_as_float_array_keeps_numbers_as_they_were():
    """Lists of Python / numpy numbers and numeric arrays convert as np.asarray(value, float)
    did; a float array is returned as it is (no copy, no entry-by-entry check)."""
    pos = np.array([[0.1, 0.0, 0.0], [-0.05, 0.0866, 0.0], [-0.05, -0.0866, 0.0]])
    assert as_float_array(pos, "w", (None, 3)) is pos
    for good in ([1, 2.5, -3], [np.float32(0.1), np.int64(2), 3], (0.3, 0.1, 1e300),
                 np.array([1, 2, 3]), np.array([0.5, 2], dtype=object), pos.tolist(), []):
        got = as_float_array(good, "w")
        want = np.asarray(good, dtype=float)
        assert got.dtype == want.dtype and got.tobytes() == want.tobytes()


# as_float_array and hearsee.geometry.as_point share one entry-by-entry check (all_real): the
# outcome of both on each input, recorded from the code before they did. Per row: as_float_array
# (value, "w"), as_float_array(value, "w", (3,)), as_point(value, "p"); a list or number is the
# float64 array returned, a string the message raised (ConfigError; as_point: GeometryError, or
# the class it is given), "{v}" standing for repr(value).
_NUM = "w: expected numbers, got {v}"
_FIN = "w: values must be finite numbers"
_P = "p must be a finite [x, y, z] in metres"
_P_SHAPE = _P + ": expected shape 3, got "
_P_REAL = _P + " (3 real numbers), got {v}"


class _Opaque:
    """An object that is no number (numpy keeps it as an object)."""

    def __repr__(self):
        return "_Opaque()"


_ENTRY_TABLE = [
    (True, _NUM, _NUM, _P_SHAPE + "{v}"),
    (np.True_, _NUM, _NUM, _P_SHAPE + "{v}"),
    ("0.5", _NUM, _NUM, _P_SHAPE + "{v}"),
    (10**400, _NUM, _NUM, _P_SHAPE + "{v}"),
    (float("nan"), _FIN, "w: expected shape 3, got ()", _P_SHAPE + "{v}"),
    (float("inf"), _FIN, "w: expected shape 3, got ()", _P_SHAPE + "{v}"),
    (0.5, 0.5, "w: expected shape 3, got ()", _P_SHAPE + "{v}"),
    (3, 3.0, "w: expected shape 3, got ()", _P_SHAPE + "{v}"),
    (np.float64(2.0), 2.0, "w: expected shape 3, got ()", _P_SHAPE + "{v}"),
    (np.array(2.0), 2.0, "w: expected shape 3, got ()", _P_SHAPE + "{v}"),
    (None, _NUM, _NUM, _P_SHAPE + "{v}"),
    (1 + 2j, _NUM, _NUM, _P_SHAPE + "{v}"),
    ({"x": 1}, _NUM, _NUM, _P_SHAPE + "{v}"),
    ({1, 2, 3}, _NUM, _NUM, _P_SHAPE + "{v}"),
    (range(3), [0.0, 1.0, 2.0], [0.0, 1.0, 2.0], [0.0, 1.0, 2.0]),
    ([1, 2.5, -3], [1.0, 2.5, -3.0], [1.0, 2.5, -3.0], [1.0, 2.5, -3.0]),
    ((np.float32(0.5), np.int64(2), np.uint8(7)), [0.5, 2.0, 7.0], [0.5, 2.0, 7.0],
     [0.5, 2.0, 7.0]),
    ([int(np.finfo(float).max), 0, 0], [1.7976931348623157e308, 0.0, 0.0],
     [1.7976931348623157e308, 0.0, 0.0], [1.7976931348623157e308, 0.0, 0.0]),
    ([True, 0.0, 1.2], _NUM, _NUM, _P_REAL),
    ([0.0, np.bool_(False), 1.0], _NUM, _NUM, _P_REAL),
    (["0", "0", "1.2"], _NUM, _NUM, _P_REAL),
    (["0.5", 0, 0], _NUM, _NUM, _P_REAL),
    ([10**400, 0, 0], _NUM, _NUM, _P_REAL),
    ([0.0, np.nan, 1.2], _FIN, _FIN, _P_REAL),
    ([0.0, 0.0, np.inf], _FIN, _FIN, _P_REAL),
    ([np.float32("nan"), 0.0, 1.0], _FIN, _FIN, _P_REAL),
    ([1 + 1j, 0, 0], _NUM, _NUM, _P_REAL),
    ([None, 0, 0], _NUM, _NUM, _P_REAL),
    ([_Opaque(), 0, 0], _NUM, _NUM, _P_REAL),
    ([0.0, 1.2], [0.0, 1.2], "w: expected shape 3, got (2,)", _P_SHAPE + "shape (2,)"),
    ([0, 0, 0, 0], [0.0] * 4, "w: expected shape 3, got (4,)", _P_SHAPE + "shape (4,)"),
    ([], [], "w: expected shape 3, got (0,)", _P_SHAPE + "shape (0,)"),
    ([[0.0, 0.0, 1.2]], [[0.0, 0.0, 1.2]], "w: expected shape 3, got (1, 3)",
     _P_SHAPE + "shape (1, 3)"),
    ([[1, 2, 3], [4, 5, 6]], [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]],
     "w: expected shape 3, got (2, 3)", _P_SHAPE + "shape (2, 3)"),
    ([[1], [2], [3]], [[1.0], [2.0], [3.0]], "w: expected shape 3, got (3, 1)",
     _P_SHAPE + "shape (3, 1)"),
    ([[0.1, 0, 0], [0, True, 0]], _NUM, _NUM, _P_SHAPE + "shape (2, 3)"),
    ([[1, 2], [3]], _NUM, _NUM, _P_SHAPE + "shape (2,)"),  # ragged
    ([[1, 2], [3], 4], _NUM, _NUM, _P_REAL),
    ([[1, [2, 3]], 4, 5], _NUM, _NUM, _P_REAL),  # numpy's ValueError, from is_real, before
    (np.array([0.0, 0.0, 1.2]), [0.0, 0.0, 1.2], [0.0, 0.0, 1.2], [0.0, 0.0, 1.2]),
    (np.array([1, 2, 3]), [1.0, 2.0, 3.0], [1.0, 2.0, 3.0], [1.0, 2.0, 3.0]),
    (np.array([0.5, 1.5, 2.5], dtype=np.float32), [0.5, 1.5, 2.5], [0.5, 1.5, 2.5],
     [0.5, 1.5, 2.5]),
    (np.array([0.0, np.nan, 1.0]), _FIN, _FIN, _P_REAL),
    (np.array([[1.0, 2.0, 3.0]]), [[1.0, 2.0, 3.0]], "w: expected shape 3, got (1, 3)",
     _P_SHAPE + "shape (1, 3)"),
    (np.array([True, False, True]), _NUM, _NUM, _P_REAL),
    (np.array([[True], [False], [True]]), _NUM, _NUM, _P_SHAPE + "shape (3, 1)"),
    (np.array(["1", "2", "3"]), _NUM, _NUM, _P_REAL),
    (np.array([1 + 1j, 0, 0]), _NUM, _NUM, _P_REAL),
    (np.array([1, 2, 3], dtype=complex), _NUM, _NUM, _P_REAL),
    (np.array(["2020-01-01"] * 3, dtype="datetime64[D]"), _NUM, _NUM, _P_REAL),
    (np.array([1.0, True, 0.0], dtype=object), _NUM, _NUM, _P_REAL),
    (np.array([0.5, 2, np.float32(3)], dtype=object), [0.5, 2.0, 3.0], [0.5, 2.0, 3.0],
     [0.5, 2.0, 3.0]),
    (np.array([0.5, np.nan, 3], dtype=object), _FIN, _FIN, _P_REAL),
    (np.array([10**400, 0, 0], dtype=object), _NUM, _NUM, _P_REAL),
    (np.array([[1, 2], [3], None], dtype=object)[:2], _NUM, _NUM, _P_SHAPE + "shape (2,)"),
]


def _check_outcome(call, value, want, error):
    """``call()`` gives ``want`` (see _ENTRY_TABLE), raising ``error`` if it raises, and warns
    nothing."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        if isinstance(want, str):
            with pytest.raises(error) as exc:
                call()
            assert type(exc.value) is error
            assert str(exc.value) == want.replace("{v}", repr(value))
        else:
            got = call()
            assert got.dtype == np.float64 and got.shape == np.shape(want)
            np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("value, many, three, point", _ENTRY_TABLE,
                         ids=[repr(r[0])[:40] for r in _ENTRY_TABLE])
def test_as_float_array_and_as_point_outcomes_on_every_kind_of_entry(value, many, three, point):
    from hearsee.errors import GeometryError
    from hearsee.geometry import as_point

    _check_outcome(lambda: as_float_array(value, "w"), value, many, ConfigError)
    _check_outcome(lambda: as_float_array(value, "w", (3,)), value, three, ConfigError)
    _check_outcome(lambda: as_point(value, "p"), value, point, GeometryError)
    _check_outcome(lambda: as_point(value, "p", ConfigError), value, point, ConfigError)


def _manifest_with_a_folder(d):
    import yaml

    (d / "cap.wav").mkdir()
    m = d / "m.yaml"
    m.write_text(yaml.safe_dump({"array": "three-mic", "captures": [
        {"file": "cap.wav", "pan_deg": 0, "tilt_deg": 0}]}))
    return m


def _loaders():
    """(call on a folder, what its error must name) of each input-file loader."""
    from hearsee.audio.active import load_pose_manifest
    from hearsee.audio.signals import read_recording
    from hearsee.sim.moving import load_trajectory
    from hearsee.stream.video import CsvImagePoints, VideoImagePoints
    from hearsee.vision.camera import load_camera, load_rig, read_opencv_yaml
    from hearsee.vision.io import read_image
    from hearsee.vision.thermal import load_thermal

    return [
        (lambda d: load_yaml(d / "x.yaml"), "x.yaml: is a folder, expected a YAML file"),
        (lambda d: read_recording(d / "x.wav"), "x.wav: is a folder, expected an audio file"),
        (lambda d: load_pose_manifest(_manifest_with_a_folder(d)),
         "m.yaml: captures[0]: {d}/cap.wav: is a folder, expected a capture file"),
        (lambda d: load_camera(d / "x.yaml"), "x.yaml: is a folder, expected a calibration file"),
        (lambda d: load_rig(d / "x.yaml"), "x.yaml: is a folder, expected a calibration file"),
        (lambda d: read_opencv_yaml(d / "x.yml"), "x.yml: is a folder, expected a file"),
        (lambda d: read_image(d / "x.png"), "x.png: is a folder, expected an image file"),
        (lambda d: load_thermal(d / "x.npy"), "x.npy: is a folder, expected a thermal file"),
        (lambda d: load_trajectory(d / "x.csv"), "x.csv: is a folder, expected a trajectory file"),
        (lambda d: VideoImagePoints(d / "x.avi"), "x.avi: is a folder, expected a video file"),
        (lambda d: CsvImagePoints(d / "x.csv"),
         "x.csv: is a folder, expected an image-point file"),
    ]


@pytest.mark.parametrize("k", range(11))
def test_an_input_file_that_is_a_folder_says_so(tmp_path, k):
    """Capture files, calibrations, images, thermal arrays, trajectories, videos and image
    points said '<name>: ... file not found' for a folder of that name (YAML and audio files
    'is a directory'); config.input_file is now the one check, saying 'is a folder, expected
    a <kind> file'. A missing file is still 'not found'."""
    call, want = _loaders()[k]
    for name in ("x.yaml", "x.wav", "x.yml", "x.png", "x.npy", "x.csv", "x.avi"):
        (tmp_path / name).mkdir()
    with pytest.raises(InputFileError) as exc:
        call(tmp_path)
    assert str(exc.value).endswith(want.format(d=tmp_path)) and "\n" not in str(exc.value)
    for name in ("x.yaml", "x.wav", "x.yml", "x.png", "x.npy", "x.csv", "x.avi", "cap.wav"):
        if (tmp_path / name).is_dir():
            (tmp_path / name).rmdir()
    if k != 2:  # (the manifest's capture: the manifest itself is written by the call)
        with pytest.raises(InputFileError, match="not found"):
            call(tmp_path)


def test_input_file_names_the_kind():
    from hearsee.config import input_file

    assert input_file(__file__, "test file").name == "test_config.py"
    with pytest.raises(InputFileError, match=r"^nowhere\.csv: trajectory file not found \(hint\)$"):
        input_file("nowhere.csv", "trajectory file", " (hint)")


def test_a_name_too_long_for_the_system_is_an_input_file_error():
    """Path.is_dir / exists raise ENAMETOOLONG rather than answer: load_array('x' * 5000) was
    a bare OSError (the CLI's net caught it; the library's callers got no typed error)."""
    from hearsee.audio.arrays import load_array
    from hearsee.config import input_file, output_file

    for check in (input_file, output_file, load_array):
        with pytest.raises(InputFileError, match=r"^x{57}\.\.\.: the system refuses this path"):
            check("x" * 5000)


def test_output_file_refuses_folders_and_missing_or_file_parents(tmp_path):
    """config.output_file, the one output-path check of refuse_overwrite, save_wav and the
    robot's exports (each had its own copy)."""
    from hearsee.config import output_file

    assert output_file(tmp_path / "out.wav") == tmp_path / "out.wav"
    with pytest.raises(InputFileError, match=r"out: is a folder, expected an output file name$"):
        (tmp_path / "out").mkdir()
        output_file(tmp_path / "out")
    with pytest.raises(InputFileError, match=r"x\.wav: folder .*no does not exist$"):
        output_file(tmp_path / "no" / "x.wav")
    (tmp_path / "f").write_text("a file", encoding="utf-8")
    with pytest.raises(InputFileError, match=r"x\.wav: .*f is not a folder$"):
        output_file(tmp_path / "f" / "x.wav")


def test_output_file_follows_a_dangling_link_to_its_missing_folder(tmp_path):
    """An output path that is a link to a file not there yet is written at the link's target
    (replacing): a target in a missing folder passed the up-front check and failed only once
    the work was done (`hearsee eval -o` after the whole evaluation: "cannot write")."""
    from hearsee.config import output_file, write_file

    link = tmp_path / "results.json"
    link.symlink_to(tmp_path / "gone" / "results.json")
    with pytest.raises(InputFileError, match=r"results\.json: links to .*gone.*does not exist"):
        output_file(link)
    ok = tmp_path / "ok.json"  # a dangling link into an existing folder: made there
    ok.symlink_to(tmp_path / "target.json")
    assert output_file(ok) == ok
    write_file(ok, "x")
    assert (tmp_path / "target.json").read_text() == "x" and ok.is_symlink()


def test_output_file_refuses_what_the_system_would_not_let_it_write(tmp_path, monkeypatch):
    """A read-only output file or folder raised PermissionError only once the work was done
    (a whole evaluation, a calibration). The tests run as root, where permissions do not stop
    writes: os.access is made to answer as for another user."""
    import os

    from hearsee.config import output_file

    (tmp_path / "old.json").write_text("{}", encoding="utf-8")
    monkeypatch.setattr(os, "access", lambda path, mode: False)
    with pytest.raises(InputFileError, match=r"old\.json: the file is not writable$"):
        output_file(tmp_path / "old.json")
    with pytest.raises(InputFileError, match=r"new\.json: folder .* is not writable$"):
        output_file(tmp_path / "new.json")


def test_same_file_sees_hard_links_and_refuse_overwrite_uses_it(tmp_path):
    """A hard link to an input passed the resolved-path test: `hearsee detect --overlay
    LINK --force` overwrote the left image it was reading."""
    import os

    from hearsee.cli._app import refuse_overwrite
    from hearsee.config import same_file

    src = tmp_path / "left.png"
    src.write_bytes(b"image")
    os.link(src, tmp_path / "hard.png")
    (tmp_path / "other.png").write_bytes(b"image")
    assert same_file(tmp_path / "hard.png", src)
    assert same_file(tmp_path / "sub" / ".." / "left.png", src)
    assert not same_file(tmp_path / "other.png", src)
    assert not same_file(tmp_path / "missing.png", src)
    with pytest.raises(InputFileError, match="refusing to overwrite an input file"):
        refuse_overwrite([tmp_path / "hard.png"], [src], force=True)
    refuse_overwrite([tmp_path / "other.png"], [src], force=True)
    assert src.read_bytes() == b"image"


def test_refuse_overwrite_lets_pipes_and_devices_through(tmp_path):
    """A FIFO or device is written into, not replaced (config.replacing): it needs no --force.
    `hearsee eval -o /dev/stdout | jq` was refused as "file exists" until 2026-12-03. A
    regular file reached through a symlink still needs --force."""
    import os

    from hearsee.cli._app import refuse_overwrite
    from hearsee.config import write_file, written_through

    reg = tmp_path / "results.json"
    reg.write_text("mine")
    link = tmp_path / "link.json"
    link.symlink_to(reg)
    for p in (reg, link):
        assert not written_through(p)
        with pytest.raises(InputFileError, match="file exists; pass --force"):
            refuse_overwrite([p], [], force=False)
    assert not written_through(tmp_path / "missing.json")
    if os.path.exists("/dev/null"):
        assert written_through("/dev/null")
        refuse_overwrite(["/dev/null"], [], force=False)
    if hasattr(os, "mkfifo"):
        fifo = tmp_path / "pipe"
        os.mkfifo(fifo)
        assert written_through(fifo)
        refuse_overwrite([fifo], [], force=False)
    if os.path.isdir("/proc/self/fd"):  # (what /dev/stdout is in `hearsee eval -o /dev/stdout
        r, w = os.pipe()                 # | jq`: a link to "pipe:[N]", which realpath cannot
        try:                             # follow -- "cannot write (No such file ...)" before)
            name = f"/proc/self/fd/{w}"
            assert written_through(name)
            refuse_overwrite([name], [], force=False)
            write_file(name, "through the pipe")
            assert os.read(r, 100) == b"through the pipe"
        finally:
            os.close(r)
            os.close(w)
    assert reg.read_text() == "mine"


@pytest.mark.parametrize("mode, earlier", [("a", "earlier line\n"), ("w", "")])
def test_output_to_the_file_standard_output_goes_to_is_written_where_it_stands(
        tmp_path, mode, earlier):
    """`-o /dev/stdout >> results.json` or `> results.json`: the file is the process's own
    standard output. It was refused as existing without --force and, forced, replaced by a new
    file: the shell's file was unlinked, what the command printed after it was lost, and `>>`
    lost the earlier lines. Now it is written through standard output's own file description:
    the results go where standard output stands, and what the command prints afterwards
    follows them. (With `>`, opened anew in append mode, the results went to the end while
    standard output's offset stayed at 0: the summary printed afterwards overwrote the start
    of the results -- and of an MCAP export, its header -- until 2026-12-07.)"""
    import subprocess
    import sys

    out = tmp_path / "results.json"
    out.write_text(earlier)
    code = ("from hearsee.cli._app import refuse_overwrite; "
            "from hearsee.config import write_file, written_through; print('before'); "
            "assert written_through('/dev/stdout'); refuse_overwrite(['/dev/stdout'], [], False); "
            "write_file('/dev/stdout', 'the runs, a long results document\\n'); "
            "print('the summary', flush=True)")
    with open(out, mode) as fh:
        r = subprocess.run([sys.executable, "-c", code], stdout=fh, stderr=subprocess.PIPE,
                           text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert out.read_text() == (earlier + "before\nthe runs, a long results document\n"
                               "the summary\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json"]


def test_as_float_array_with_the_callers_error_and_non_finite_values_allowed():
    """finite=False lets NaN and infinities through (only non-numbers are refused) and
    ``error`` is the caller's type."""
    from hearsee.errors import GeometryError

    got = as_float_array([1.0, np.nan, -np.inf], "w", finite=False)
    assert np.isnan(got[1]) and got[2] == -np.inf
    with pytest.raises(GeometryError, match="^w: expected numbers, got "):
        as_float_array(["x"], "w", finite=False, error=GeometryError)
    with pytest.raises(GeometryError, match="^w: values must be finite numbers$"):
        as_float_array([np.nan], "w", error=GeometryError)
    with pytest.raises(GeometryError, match=r"expected shape 3, got \(2,\)"):
        as_float_array([1, 2], "w", (3,), error=GeometryError)


def test_true_or_false():
    from hearsee.config import true_or_false

    assert true_or_false("f", True) is True and true_or_false("f", np.bool_(False)) is False
    for bad in ("no", "True", 1, 0, None, 1.0):
        with pytest.raises(ConfigError, match=r"^f must be True or False, got "):
            true_or_false("f", bad)
    with pytest.raises(GeometryError, match="^g must be True or False"):
        true_or_false("g", "yes", error=GeometryError)


def test_check_settings_names_the_first_unknown_keyword():
    """A misspelt setting passed on as **kwargs is named with the keywords the target takes
    (those the caller sets itself left out); known ones pass. The trackers use it."""
    from hearsee.audio.tracking import track_directions
    from hearsee.config import check_settings

    def target(x, fs, gain=1.0, delay_s=0.0):
        return x

    check_settings(target, ["gain", "delay_s"], skip=("x", "fs"))
    with pytest.raises(ConfigError, match=r"unknown target setting 'gian' \(expected one of: "
                                          r"gain, delay_s\)"):
        check_settings(target, ["delay_s", "gian", "zzz"], skip=("x", "fs"))
    with pytest.raises(EstimationError, match="unknown DirectionKalman setting 'sigma_acel_dps2'"):
        track_directions([0.0, 0.1], [10.0, 11.0], sigma_acel_dps2=30.0)
