"""Values of the wrong kind (text, None, a number for a path, a ragged list, an empty array for
a number) given to the library's lower-level functions: each is hearsee's own error naming
what was wrong, where numpy or Python raised a builtin TypeError / ValueError / AttributeError
before. Well-formed calls next to them keep their results."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from hearsee.errors import (
    AudioInputError,
    ConfigError,
    GeometryError,
    ImageInputError,
    InputFileError,
)


@pytest.mark.parametrize("path", [float("nan"), None, 3, "", ["a.wav"]])
def test_paths_must_be_file_names(path, tmp_path):
    from hearsee.audio.signals import read_recording, write_recording
    from hearsee.config import input_file, output_file
    from hearsee.sim.moving import linear_trajectory, load_trajectory, save_trajectory
    from hearsee.vision.thermal import load_thermal

    for call in (lambda: input_file(path), lambda: output_file(path),
                 # (read_recording takes a list of files, one per microphone: a list in it
                 # is no file name)
                 lambda: read_recording(path if path != ["a.wav"] else [path]),
                 lambda: load_thermal(path),
                 lambda: load_trajectory(path),
                 lambda: write_recording(path, np.zeros((2, 160)), 16000),
                 lambda: save_trajectory(linear_trajectory([1, 0, 0], [0, 1, 0], 1.0), path)):
        with pytest.raises(InputFileError, match="must be a file name"):
            call()
    # a file name is still one, and a trajectory still goes to a folder that exists
    out = tmp_path / "t.csv"
    save_trajectory(linear_trajectory([1, 0, 0], [0, 1, 0], 1.0), out)
    np.testing.assert_allclose(load_trajectory(out).at(np.array([0.5])), [[1.0, 0.5, 0.0]])
    with pytest.raises(InputFileError, match="does not exist"):
        save_trajectory(linear_trajectory([1, 0, 0], [0, 1, 0], 1.0), tmp_path / "no" / "t.csv")


def test_simulation_helpers_refuse_what_is_no_number():
    from hearsee.audio.propagation import add_noise, image_sources
    from hearsee.sim.moving import fractional_delay

    x = np.ones((2, 64))
    for snr in (np.array([]), "10", [10.0]):
        with pytest.raises(ConfigError, match="SNR must be a finite number"):
            add_noise(x, snr, 0)
    with pytest.raises(ConfigError, match="RT60 must be a non-negative number"):
        image_sources("0.3", (5.0, 4.0, 3.0))
    with pytest.raises(ConfigError, match="max_order must be a non-negative integer"):
        image_sources(0.3, (5.0, 4.0, 3.0), max_order="2")
    with pytest.raises(GeometryError, match="room dimensions"):
        image_sources(0.3, "5x4x3")
    assert image_sources(0.0, (5.0, 4.0, 3.0)) == (None, 0)
    with pytest.raises(AudioInputError, match="signal: samples must be real numbers"):
        fractional_delay("chirp", np.zeros(4))
    with pytest.raises(GeometryError, match="delays: expected numbers"):
        fractional_delay(np.ones(8), ["a"] * 8)
    y = fractional_delay(np.arange(16.0), np.full(16, 2.0))
    np.testing.assert_allclose(y[4:12], np.arange(2.0, 10.0), atol=1e-3)


def test_geometry_and_localization_helpers_refuse_what_is_no_number():
    from hearsee.audio.localize import as_tdoas
    from hearsee.geometry import mic_positions_at, norm_scale

    with pytest.raises(GeometryError, match="microphone positions: expected numbers"):
        mic_positions_at("three-mic", (0.0, 0.0))
    with pytest.raises(GeometryError, match="microphone positions: values must be finite"):
        mic_positions_at([[np.nan, 0, 0]], (0.0, 0.0))
    np.testing.assert_allclose(mic_positions_at([[0.1, 0, 0]], (90.0, 0.0)), [[0, 0.1, 0]],
                               atol=1e-12)
    for v, match in (([], r"vectors \(\.\.\., 3\)"), ("x", "vector: expected numbers"),
                     (np.zeros((2, 2)), r"vectors \(\.\.\., 3\)")):
        with pytest.raises(GeometryError, match=match):
            norm_scale(v)
    np.testing.assert_array_equal(norm_scale([[1e300, 0, 0], [1.0, 2.0, 3.0]]), [[1e300], [1.0]])
    with pytest.raises(GeometryError, match="n_pairs must be an integer"):
        as_tdoas([0.0], np.array([]))
    np.testing.assert_array_equal(as_tdoas([1e-4, -2e-4], 2), [1e-4, -2e-4])


def test_framing_and_solver_entry_points_refuse_other_kinds():
    from hearsee.audio.active import one_mic_arrival_differences, solve_range_differences
    from hearsee.audio.tdoa import dominant_sample, frame_spectra, windowed_frames

    win = np.hanning(8).astype(np.float32)
    with pytest.raises(AudioInputError, match="frames: samples must be real numbers"):
        windowed_frames("abc", win)
    with pytest.raises(AudioInputError, match="window: samples must be real numbers"):
        windowed_frames(np.zeros((2, 8)), "hann")
    with pytest.raises(ConfigError, match="window must be as long as a frame"):
        frame_spectra(np.zeros((2, 8)), np.hanning(7), 16)
    with pytest.raises(ConfigError, match="window must be as long as a frame"):
        windowed_frames(np.float64(1.0), win)
    frames = [[0.0, 1.0, 0.0, -1.0, 0.0, 1.0, 0.0, -1.0]]  # (a list of numbers is fine)
    X = frame_spectra(frames, np.ones(8), 8)
    assert X.shape == (1, 5) and abs(X[0, 2]) == pytest.approx(4.0)
    with pytest.raises(AudioInputError, match="samples must be real numbers"):
        dominant_sample("x")
    with pytest.raises(AudioInputError, match="n_channels, n_samples"):
        dominant_sample(np.zeros((2, 3, 4)))
    x = np.full((2, 50_000), 0.1)
    x[1, 7] = 1e30  # one corrupt sample
    assert dominant_sample(x)[:2] == (1, 7)
    with pytest.raises(GeometryError, match="one entry per pose"):
        solve_range_differences(float("nan"), float("nan"), float("nan"))
    with pytest.raises(AudioInputError, match="captures must be a list"):
        one_mic_arrival_differences(float("nan"), 16000, np.eye(2, 3))


def test_head_shoulder_score_refuses_a_ragged_mask():
    from hearsee.vision.humans import head_shoulder_score

    with pytest.raises(ImageInputError, match="mask must be a bool silhouette"):
        head_shoulder_score([[1, 0], [1]], 2.0, 500.0)


def test_array_parameters_take_a_micarray_or_a_preset_and_nothing_else():
    """The localizers, min_frame_ms and facing_pair read attributes of their ``array``
    argument: a number there was an AttributeError. They now go through load_array, which
    also takes a preset name: the same answers as with the MicArray."""
    from hearsee.audio.active import facing_pair
    from hearsee.audio.arrays import load_array
    from hearsee.audio.localize import (
        far_field_linear,
        far_field_planar,
        near_field_in_plane,
        near_field_position,
    )
    from hearsee.audio.tdoa import min_frame_ms
    from hearsee.geometry import unit_vector_deg

    three, two = load_array("three-mic"), load_array("two-mic")
    tau3 = three.tdoa_far(unit_vector_deg(40.0, 0.0))
    tau2 = two.tdoa_far(unit_vector_deg(40.0, 0.0))
    near3 = three.tdoa(2.0 * unit_vector_deg(40.0, 0.0))  # (in the plane, 2 m: its model)
    for fn, arr, tau in ((far_field_planar, three, tau3), (near_field_in_plane, three, near3),
                         (far_field_linear, two, tau2)):
        with pytest.raises(ConfigError, match="expected a MicArray"):
            fn(tau, float("nan"))
        by_name = fn(tau, arr.name)
        assert by_name.azimuth_deg == pytest.approx(fn(tau, arr).azimuth_deg)
        assert by_name.azimuth_deg == pytest.approx(40.0, abs=0.5)
    with pytest.raises(ConfigError, match="expected a MicArray"):
        near_field_position(tau3, 3)
    with pytest.raises(ConfigError, match="expected a MicArray"):
        min_frame_ms(None)
    assert min_frame_ms("three-mic") == min_frame_ms(three) > 0
    with pytest.raises(ConfigError, match="expected a MicArray"):
        facing_pair(0.0)
    assert facing_pair("three-mic") == facing_pair(three) == (1, 2)


def _rng_calls():
    """(name, call(rng)) of the library's functions that draw random numbers from ``rng``."""
    from hearsee.audio import active, bem, mask, propagation, signals
    from hearsee.audio.arrays import MicArray
    from hearsee.fusion.audiovisual import AudioVisualRig, simulate_av_samples
    from hearsee.vision.camera import Camera

    arr = MicArray.from_preset("three-mic")
    sig = signals.white_noise(0.1, 8000, 0)
    rig = AudioVisualRig.mounted(arr, Camera.from_fov(70.0, 64, 48), (0.0, 0.2, 0.0))
    return [
        ("white_noise", lambda r: signals.white_noise(0.01, 8000, r)),
        ("synthetic_voice", lambda r: signals.synthetic_voice("male", 0.5, 8000, r)),
        ("make_signal", lambda r: signals.make_signal("noise", 0.01, 8000, r)),
        ("add_noise", lambda r: propagation.add_noise(np.ones((2, 64)), 10.0, r)),
        ("add_noise without noise", lambda r: propagation.add_noise(np.ones((2, 64)), None, r)),
        ("simulate_free_field",
         lambda r: propagation.simulate_free_field(sig, 8000, arr, [1, 0.5, 0], 10.0, r)),
        ("simulate_room", lambda r: propagation.simulate_room(
            sig, 8000, arr, [1, 0.5, 0], [5, 4, 3], 0.0, [2, 2, 1.2], 10.0, r)),
        ("simulate_masked", lambda r: mask.simulate_masked(sig, 8000, "mask2", [1, 0.5, 0],
                                                           10.0, r, far_field=True)),
        ("simulate_pose_captures", lambda r: active.simulate_pose_captures(
            sig, 8000, arr, [1, 0.5, 0.2], [(0, 0)], snr_db=10.0, rng=r)),
        ("simulate_turning_capture", lambda r: active.simulate_turning_capture(
            sig, 8000, arr, [1, 0.5, 0.2], lambda t: (0, 0), snr_db=10.0, rng=r)),
        ("make_pose_training_set",
         lambda r: active.make_pose_training_set(arr, [(0, 0)], 4, rng=r)),
        ("simulate_av_samples", lambda r: simulate_av_samples(rig, 4, rng=r)),
        ("chief_points", lambda r: bem.chief_points(bem.sphere_mesh(0.1, 4), 4, r)),
    ]


def test_rng_arguments_take_a_generator_a_seed_or_none_and_nothing_else():
    """numpy's default_rng raised its own TypeError (text, 1.5) or ValueError (-1), took True
    as the seed 1 and a list as a seed sequence; add_noise without noise (snr_db None), and
    make_signal, never looked at it. Each is a ConfigError naming rng now, and valid rngs draw
    exactly what default_rng(rng) draws."""
    from hearsee.audio.signals import white_noise
    from hearsee.config import as_rng, check_rng

    for _name, call in _rng_calls():
        for bad in ("a", 1.5, -1, True, [1, 2], np.random.RandomState(0)):
            with pytest.raises(ConfigError, match="rng must be a numpy Generator, an integer "
                                                  "seed >= 0 or None"):
                call(bad)
        for good in (None, 3, np.int64(3), np.random.default_rng(3)):
            call(good)
    # the stream: as numpy's for a seed, the caller's own for a Generator
    np.testing.assert_array_equal(white_noise(0.01, 8000, np.uint8(5)),
                                  np.random.default_rng(5).standard_normal(80))
    g = np.random.default_rng(9)
    assert as_rng(g) is g and check_rng(7) == 7 and check_rng(None) is None
    first = white_noise(0.01, 8000, g)
    np.testing.assert_array_equal(np.concatenate([first, white_noise(0.01, 8000, g)]),
                                  np.random.default_rng(9).standard_normal(160))


def test_pose_manifest_seed_is_checked_before_any_work(tmp_path):
    """A negative, fractional or text seed raised numpy's ValueError / TypeError."""
    from hearsee.audio.active import simulate_pose_manifest

    for seed in (-1, 1.5, "a", True):
        with pytest.raises(ConfigError, match="seed must be an integer >= 0"):
            simulate_pose_manifest(tmp_path / "m.yaml", "three-mic", [1.0, 0.5, 0.2], [(0, 0)],
                                   duration_s=0.1, seed=seed)
    assert not list(tmp_path.iterdir())


def _config_calls(tmp: Path) -> list[tuple[str, Any, type, str]]:
    """(label, call with None for one required argument, error, message start) for the
    helpers of hearsee.config; the well-formed call of each is in the test below."""
    from hearsee import config as C

    out = tmp / "out.txt"
    return [
        ("check_keys(data)", lambda: C.check_keys(None, ("a",), "w"), ConfigError,
         "w: expected a mapping, got NoneType"),
        ("check_keys(allowed)", lambda: C.check_keys({"a": 1}, None, "w"), ConfigError,
         "w: the allowed keys must be a list of names"),
        ("number(d)", lambda: C.number(None, "a", 1.0, "w"), ConfigError,
         "w: expected a mapping, got NoneType"),
        ("require(data)", lambda: C.require(None, "a", "w"), ConfigError,
         "w: expected a mapping, got NoneType"),
        ("save_yaml(data)", lambda: C.save_yaml(None, out), ConfigError,
         f"{out}: the data to save as YAML: expected a mapping, got NoneType"),
        ("save_yaml(path)", lambda: C.save_yaml({"a": 1}, None), InputFileError,
         "the output path must be a file name, got None"),
        ("write_file(path)", lambda: C.write_file(None, "x"), InputFileError,
         "the output path must be a file name, got None"),
        ("write_file(data)", lambda: C.write_file(out, None), ConfigError,
         f"{out}: the data to write must be text or bytes, got NoneType"),
        ("write_into(data)", lambda: C.write_into(out, None, "o.txt"), ConfigError,
         "o.txt: the data to write must be text or bytes, got NoneType"),
        ("write_into(dest)", lambda: C.write_into(None, "x", "o.txt"), InputFileError,
         "o.txt: cannot write (the output file must be a file name, got None)"),
        ("open_replaced(dest)", lambda: C.open_replaced(None), InputFileError,
         "the output file must be a file name, got None"),
        ("replacing(path)", lambda: C.replacing(None).__enter__(), InputFileError,
         "the output path must be a file name, got None"),
        ("names_a_file(spec)", lambda: C.names_a_file(None), ConfigError,
         "array: expected a preset name or a YAML path, got NoneType"),
    ]


@pytest.mark.parametrize("label", [c[0] for c in _config_calls(Path("unused"))])
def test_config_helpers_given_none_raise_their_typed_errors(label, tmp_path):
    """None for a required argument of hearsee.config's helpers was a builtin TypeError or
    AttributeError (dict(None), os.stat(None), None.get, "/" in None, None.exists()); now the
    error each uses for a bad value of that argument (the shared mapping check, as_path),
    and nothing is written."""
    [(call, error, message)] = [c[1:] for c in _config_calls(tmp_path) if c[0] == label]
    with pytest.raises(error, match="^" + re.escape(message)):
        call()
    assert not list(tmp_path.iterdir()), label


def test_config_helpers_still_take_what_they_took(tmp_path):
    """The well-formed calls next to the None ones; all_real, a yes/no test, says no to None
    (no number) where it raised AttributeError, and takes a list as object_entries makes it."""
    from hearsee import config as C

    C.check_keys({"a": 1}, ("a", "b"), "w")
    assert C.number({"a": 2}, "a", 1.0, "w") == 2.0 and C.require({"a": 3}, "a", "w") == 3
    C.save_yaml({"a": 1}, tmp_path / "a.yaml")
    assert C.load_yaml(tmp_path / "a.yaml") == {"a": 1}
    C.write_file(tmp_path / "b.txt", b"bytes")
    assert (tmp_path / "b.txt").read_bytes() == b"bytes"
    with C.open_replaced(str(tmp_path / "c.txt")) as fh:  # (a str: None.exists() before)
        fh.write(b"c")
    assert C.names_a_file(Path("mics.yaml")) and not C.names_a_file("three-mic")
    assert C.all_real(None) is False and C.all_real([1.0, 2]) and not C.all_real([1.0, "2"])
    assert C.all_real(np.array([1.0, 2.0], dtype=object))


def _kernel_calls() -> dict[str, tuple[Any, dict[str, Any]]]:
    """Well-formed calls of hearsee.audio.arrays' and hearsee.audio.bem's helpers (function,
    keyword arguments): three microphones, a source 1 m in front of them."""
    from hearsee.audio import arrays as A
    from hearsee.audio import bem as B

    pos = np.array([[0.05, 0.0, 0.0], [-0.025, 0.0433, 0.0], [-0.025, -0.0433, 0.0]])
    i, j = np.array([0, 0, 1]), np.array([1, 2, 2])
    p = np.array([1.0, 0.2, 0.0])
    y = A.pair_tdoa(p, pos, i, j, 343.0)
    return {
        "check_pairs": (A.check_pairs, {"pairs": [(0, 1)], "n_mics": 3}),
        "closure_rms": (A.closure_rms, {"values": [1e-4, 2e-4, 1e-4],
                                        "pairs": [(0, 1), (0, 2), (1, 2)], "n_mics": 3}),
        "pair_tdoa": (A.pair_tdoa, {"points": p, "positions": pos, "i": i, "j": j,
                                    "speed_of_sound": 343.0}),
        "pair_tdoa_jacobian": (A.pair_tdoa_jacobian, {"point": p, "positions": pos, "i": i,
                                                      "j": j, "speed_of_sound": 343.0}),
        "position_uncertainty": (A.position_uncertainty, {
            "p": p, "M": pos, "a": i, "b": j, "c": 343.0, "y": y, "sig": 2e-6,
            "ref": np.zeros(3), "max_rel_distance_std": 0.3}),
        "residual_scaled_variance": (A.residual_scaled_variance, {
            "residual_s": np.array([1e-6, -2e-6, 1e-6, 3e-6]), "sig": 1e-6, "n_params": 2}),
        "span_dimension": (A.span_dimension, {"positions": pos, "speed_of_sound": 343.0,
                                              "rel_tol": 1e-6}),
        "chief_points": (B.chief_points, {"mesh": B.sphere_mesh(0.1, 4), "n": 4}),
    }


@pytest.mark.parametrize("name, argument", [
    (name, arg) for name, (_, kw) in _kernel_calls().items() for arg in kw
    if name != "chief_points" or arg == "mesh"])  # (its n is checked already)
def test_array_and_bem_helpers_given_none_raise_geometry_error(name, argument):
    """None for an argument of the microphone-array and BEM helpers was a builtin TypeError,
    IndexError or AttributeError (pair_tdoa's i and j, and residual_scaled_variance's
    residuals, a wrong answer without one: an extra axis, sig^2 alone); now the modules'
    GeometryError naming the argument. The well-formed call answers as before."""
    func, kw = _kernel_calls()[name]
    func(**kw)
    with pytest.raises(GeometryError, match=rf"\b{argument}\b|one value per pair"):
        func(**{**kw, argument: None})


#: the numeric kernels of hearsee.audio.arrays (of :func:`_kernel_calls`), which refuse text too
_NUMERIC_KERNELS = ("pair_tdoa", "pair_tdoa_jacobian", "position_uncertainty",
                    "residual_scaled_variance")


def _same(a, b):
    """Results equal bit for bit (tuples, arrays, floats alike)."""
    if isinstance(a, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)


@pytest.mark.parametrize("text", ["abc", "0.3", b"1"])
@pytest.mark.parametrize("name, argument", [
    (name, arg) for name, (_, kw) in _kernel_calls().items() for arg in kw
    if name in _NUMERIC_KERNELS])
def test_array_kernels_given_text_raise_geometry_error(name, argument, text):
    """Text for an argument of pair_tdoa, pair_tdoa_jacobian, position_uncertainty or
    residual_scaled_variance was numpy's builtin ValueError ("could not convert string to
    float"), UFuncTypeError or IndexError, or Python's TypeError ('<=' between int and str);
    position_uncertainty took a text max_rel_distance_std without a word. Now a GeometryError
    naming the function and the argument; the well-formed call answers as before."""
    func, kw = _kernel_calls()[name]
    want = func(**kw)
    with pytest.raises(GeometryError, match=rf"^{name}: {argument} must be numeric, got text"):
        func(**{**kw, argument: text})
    assert _same(func(**kw), want)


def test_transfer_functions_needs_a_solution():
    """transfer_functions(None, ...) was a builtin AttributeError ('speed_of_sound')."""
    from hearsee.audio.bem import transfer_functions

    with pytest.raises(GeometryError, match="^transfer_functions needs the AdjointSolution of "
                                            "solve_adjoint, got NoneType"):
        transfer_functions(None, np.array([[1.0, 0.0, 0.0]]))
