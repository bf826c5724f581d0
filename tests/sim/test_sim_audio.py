import json

import numpy as np
import pytest
import soundfile as sf

from hearsee.audio.arrays import MicArray
from hearsee.audio.signals import read_recording
from hearsee.errors import AudioInputError, ConfigError, GeometryError
from hearsee.geometry import sph_to_cart
from hearsee.sim.audio import (
    example_recording_path,
    ground_truth,
    normalize_room,
    save_recording,
    simulate_recording,
)

FS = 16000


def test_free_field_truth_and_tdoa(gcc_phat_ref):
    arr = MicArray.from_preset("three-mic")
    src = sph_to_cart(np.radians(-130.0), np.radians(20.0), 1.5)
    x, truth = simulate_recording(arr, src, duration_s=0.5, fs=FS, seed=1)
    assert x.shape == (3, FS // 2)
    assert truth["azimuth_deg"] == pytest.approx(-130.0)
    assert truth["elevation_deg"] == pytest.approx(20.0)
    assert truth["distance_m"] == pytest.approx(1.5)
    assert truth["source_m"] == pytest.approx(list(src))
    assert list(truth["tdoa_s"]) == ["0-1", "0-2", "1-2"]
    np.testing.assert_allclose(list(truth["tdoa_s"].values()), arr.tdoa(src))
    assert truth["array"] == arr.to_dict()
    assert truth["fs"] == FS and truth["signal"] == "noise" and truth["room"] is None
    json.dumps(truth)  # JSON-able as is
    est = [gcc_phat_ref(x[i], x[j], FS, 0.0005) for i, j in arr.pairs]
    np.testing.assert_allclose(np.array(est) * FS, arr.tdoa(src) * FS, atol=0.05)


@pytest.mark.parametrize("snr_db", [0.0, 20.0])
def test_snr_accuracy_and_determinism(snr_db):
    clean, _ = simulate_recording("two-mic", [1.0, 0.5, 0.0], "male", 1.0, FS, seed=4)
    noisy, truth = simulate_recording("two-mic", [1.0, 0.5, 0.0], "male", 1.0, FS,
                                      snr_db=snr_db, seed=4)
    snr = 10 * np.log10(np.mean(clean**2) / np.mean((noisy - clean) ** 2))
    assert snr == pytest.approx(snr_db, abs=0.1)
    assert truth["snr_db"] == snr_db and truth["signal"] == "male"
    again, _ = simulate_recording("two-mic", [1.0, 0.5, 0.0], "male", 1.0, FS,
                                  snr_db=snr_db, seed=4)
    np.testing.assert_array_equal(noisy, again)


def test_room_recording_default_array_at_and_tdoa(gcc_phat_ref):
    arr = MicArray.from_preset("three-mic")
    src = np.array([1.5, -1.0, 0.2])
    x, truth = simulate_recording(arr, src, "noise", 0.5, FS,
                                  room={"room_dim": [5, 4, 3], "rt60": 0.2}, seed=2)
    assert truth["room"] == {"room_dim": [5.0, 4.0, 3.0], "rt60": 0.2,
                             "array_at": [2.5, 2.0, 1.5]}
    est = [gcc_phat_ref(x[i], x[j], FS, 0.0005) for i, j in arr.pairs]
    np.testing.assert_allclose(np.array(est) * FS, arr.tdoa(src) * FS, atol=0.25)


def test_bad_inputs():
    with pytest.raises(GeometryError, match="source"):
        simulate_recording("two-mic", [1.0, 2.0], duration_s=0.1)
    with pytest.raises(GeometryError, match="source"):
        simulate_recording("two-mic", [1.0, np.nan, 0.0], duration_s=0.1)
    with pytest.raises(ConfigError, match="sample rate"):
        simulate_recording("two-mic", [1.0, 0.0, 0.0], duration_s=0.1, fs=-8000)
    with pytest.raises(ConfigError, match="SNR"):
        simulate_recording("two-mic", [1.0, 0.0, 0.0], duration_s=0.1, snr_db=float("inf"))
    with pytest.raises(ConfigError, match="unknown array preset"):
        simulate_recording("nine-mic", [1.0, 0.0, 0.0], duration_s=0.1)
    with pytest.raises(GeometryError, match="outside the room"):
        simulate_recording("two-mic", [4.0, 0.0, 0.0], duration_s=0.1,
                           room={"room_dim": [5, 4, 3], "rt60": 0.2})
    with pytest.raises(ConfigError, match="unknown key 'rt'"):
        normalize_room({"room_dim": [5, 4, 3], "rt": 0.2})
    with pytest.raises(ConfigError, match="missing 'rt60'"):
        normalize_room({"room_dim": [5, 4, 3]})
    with pytest.raises(ConfigError, match="missing 'room_dim'"):
        normalize_room({"rt60": 0.3})
    with pytest.raises(GeometryError, match="positive"):
        normalize_room({"room_dim": [5, 0, 3], "rt60": 0.3})
    for bad in ("x", -1, 2.5, True):  # ('x' was a ValueError, 2.5 silently became 2)
        with pytest.raises(ConfigError, match="max_order"):
            normalize_room({"room_dim": [5, 4, 3], "rt60": 0.3, "max_order": bad})
    assert normalize_room({"room_dim": [5, 4, 3], "rt60": 0.3, "max_order": 3.0})["max_order"] == 3
    # (float() read true as 1 s and "0.3" as 0.3 s before 2026-11-26; NaN and -1 passed here)
    for bad in (True, "0.3", float("nan"), -1.0, [0.3]):
        with pytest.raises(ConfigError, match="rt60"):
            normalize_room({"room_dim": [5, 4, 3], "rt60": bad})
    with pytest.raises(ConfigError, match="too short"):
        simulate_recording("two-mic", [1.0, 0.0, 0.0], duration_s=0.1,
                           room={"room_dim": [30, 30, 10], "rt60": 0.05})


def test_ground_truth_with_moved_microphones():
    arr = MicArray.from_preset("two-mic")
    moved = arr.positions[:, [1, 0, 2]]
    src = [1.0, 0.3, 0.0]
    t = ground_truth(arr, src, mic_positions=moved)
    r = np.linalg.norm(moved - np.array(src), axis=1)
    assert t["tdoa_s"]["0-1"] == pytest.approx((r[0] - r[1]) / 343.0)


def test_save_recording(tmp_path):
    x, truth = simulate_recording("two-mic", [1.0, 1.0, 0.0], duration_s=0.2, seed=0)
    wav, js = save_recording(tmp_path / "r.wav", x, truth, subtype="PCM_16")
    assert js == tmp_path / "r.json"
    doc = json.loads(js.read_text())
    y, fs = read_recording(wav, n_channels=2, fs=FS)
    assert np.max(np.abs(y)) == pytest.approx(0.5, abs=1e-4)
    np.testing.assert_allclose(y, x * doc["gain"], atol=1e-4)
    assert doc["tdoa_s"] == truth["tdoa_s"] and doc["wav"] == "r.wav"
    with pytest.raises(ConfigError, match=".wav"):
        save_recording(tmp_path / "r.txt", x, truth)
    with pytest.raises(ConfigError, match="refusing to overwrite"):
        save_recording(wav, x, truth, protect=[wav])
    with pytest.raises(ConfigError, match="refusing to overwrite"):
        save_recording(tmp_path / "in.wav", x, truth, protect=[tmp_path / "in.json"])


def test_bundled_example(gcc_phat_ref):
    p = example_recording_path()
    assert p.stat().st_size < 300_000
    info = sf.info(str(p))
    assert (info.channels, info.samplerate, info.subtype) == (3, 16000, "PCM_16")
    truth = json.loads(p.with_suffix(".json").read_text())
    arr = MicArray.from_preset("three-mic")
    assert truth["azimuth_deg"] == pytest.approx(60.0)
    assert truth["elevation_deg"] == pytest.approx(10.0)
    assert truth["distance_m"] == pytest.approx(2.0)
    assert truth["room"]["rt60"] == 0.3 and truth["snr_db"] == 20.0
    assert truth["signal"] == "female"
    src = sph_to_cart(np.radians(60.0), np.radians(10.0), 2.0)
    np.testing.assert_allclose(list(truth["tdoa_s"].values()), arr.tdoa(src), atol=1e-12)
    x, fs = read_recording(p, arr, fs=16000)
    est = [gcc_phat_ref(x[i], x[j], fs, 0.0005, interp=16) for i, j in arr.pairs]
    np.testing.assert_allclose(np.array(est) * fs, arr.tdoa(src) * fs, atol=0.5)


def test_far_field_and_turned_head(gcc_phat_ref):
    arr = MicArray.from_preset("three-mic")
    src = sph_to_cart(np.radians(75.0), np.radians(-15.0), 3.0)
    x, truth = simulate_recording(arr, src, duration_s=0.5, seed=5, far_field=True)
    assert truth["far_field"] is True
    np.testing.assert_allclose(list(truth["tdoa_s"].values()), arr.tdoa_far(src))
    np.testing.assert_allclose(np.std(x, axis=1), np.std(x[0]), rtol=0.01)  # plane wave
    est = [gcc_phat_ref(x[i], x[j], FS, 0.0005) for i, j in arr.pairs]
    np.testing.assert_allclose(np.array(est) * FS, arr.tdoa_far(src) * FS, atol=0.05)
    with pytest.raises(ConfigError, match="far_field"):
        simulate_recording(arr, src, duration_s=0.1, far_field=True,
                           room={"room_dim": [8, 8, 3], "rt60": 0.0})
    # a head turned by 90 deg: mics rotated, the source fixed in the (original) array frame
    c, s = np.cos(np.pi / 2), np.sin(np.pi / 2)
    turned = arr.positions @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T
    src = np.array([1.5, 0.5, 0.0])
    x, truth = simulate_recording(arr, src, duration_s=0.5, seed=6, mic_positions=turned)
    r = np.linalg.norm(turned - src, axis=1)
    want = np.array([r[i] - r[j] for i, j in arr.pairs]) / arr.speed_of_sound
    np.testing.assert_allclose(list(truth["tdoa_s"].values()), want)
    np.testing.assert_allclose(truth["mic_positions"], turned)
    est = [gcc_phat_ref(x[i], x[j], FS, 0.0005) for i, j in arr.pairs]
    np.testing.assert_allclose(np.array(est) * FS, want * FS, atol=0.05)


def test_save_flac(tmp_path):
    x, truth = simulate_recording("two-mic", [1.0, 1.0, 0.0], duration_s=0.2, seed=0)
    wav, _ = save_recording(tmp_path / "r.flac", x, truth)
    assert sf.info(str(wav)).subtype == "PCM_24"
    y, _ = read_recording(wav, 2)
    np.testing.assert_allclose(y, x * 0.5 / np.abs(x).max(), atol=1e-6)


def test_ground_truth_of_a_source_at_the_origin_has_no_direction():
    """Between the microphones of a triangle: the distances (and TDOAs) are defined, the
    direction is not -- None, not a made-up 0 deg; a plane wave from there is an error."""
    arr = MicArray.from_preset("three-mic")
    t = ground_truth(arr, [0.0, 0.0, 0.0])
    assert t["azimuth_deg"] is None and t["elevation_deg"] is None
    assert t["distance_m"] == 0.0
    np.testing.assert_allclose(list(t["tdoa_s"].values()), 0.0, atol=1e-8)  # equidistant
    with pytest.raises(GeometryError, match="needs a direction"):
        ground_truth(arr, [0.0, 0.0, 0.0], far_field=True)


def test_bad_peak_rates_and_microphone_counts_are_refused(tmp_path):
    """Bad-input sweep (2026-11-26): save_recording's peak -0.5 inverted the polarity and 0
    wrote a silent file; resample with a zero or NaN rate raised numpy errors; mic_positions
    of the wrong count raised zip()'s ValueError while writing the truth."""
    x, truth = simulate_recording("two-mic", [1.0, 1.0, 0.0], duration_s=0.1, seed=1)
    for peak in (-0.5, 0.0, 1.5, np.nan):
        with pytest.raises(ConfigError, match="peak"):
            save_recording(tmp_path / "r.wav", x, truth, peak=peak)
    assert not (tmp_path / "r.wav").exists()
    from hearsee.audio.signals import resample

    for a, b in ((0.0, 16000.0), (16000.0, np.nan), (16000.0, np.inf)):
        with pytest.raises(AudioInputError, match="sample rate"):
            resample(x, a, b)
    with pytest.raises(GeometryError, match="mic_positions"):
        simulate_recording("two-mic", [1.0, 1.0, 0.0], duration_s=0.1,
                           mic_positions=np.zeros((3, 3)))


def test_mic_positions_of_the_wrong_shape_are_a_geometry_error():
    """ground_truth and render are public too: ground_truth with three rows for a two-mic
    array raised zip()'s ValueError, ragged rows numpy's ValueError (also from
    simulate_recording), and render returned three channels for the two-mic array."""
    from hearsee.sim.audio import render

    arr = MicArray.from_preset("two-mic")
    src = [1.0, 0.5, 0.0]
    three_rows = [[0.0, -0.075, 0.0], [0.0, 0.075, 0.0], [0.1, 0.0, 0.0]]
    ragged = [[0.0, -0.075, 0.0], [0.0, 0.075]]
    for mp in (three_rows, ragged, [[0.0, -0.075, 0.0], [0.0, np.inf, 0.0]]):
        with pytest.raises(GeometryError, match="mic_positions"):
            ground_truth(arr, src, mic_positions=mp)
        with pytest.raises(GeometryError, match="mic_positions"):
            render(np.ones(100), FS, arr, src, mic_positions=mp)
        with pytest.raises(GeometryError, match="mic_positions"):
            simulate_recording(arr, src, duration_s=0.1, mic_positions=mp)
    # the right shape still works, and its truth is that of the given positions
    moved = np.array([[0.0, 0.075, 0.0], [0.0, -0.075, 0.0]])
    t = ground_truth(arr, src, mic_positions=moved)
    assert t["tdoa_s"]["0-1"] == pytest.approx(-arr.tdoa(src)[0])
    assert render(np.ones(100), FS, arr, src, mic_positions=moved).shape == (2, 100)


def test_truth_with_a_numpy_seed_is_json():
    """simulate_recording promises a JSON-able truth, but kept a numpy integer seed as is
    (json.dumps: 'Object of type int64 is not JSON serializable')."""
    x, truth = simulate_recording("two-mic", [1.0, 1.0, 0.0], duration_s=0.1,
                                  seed=np.int64(3))
    json.dumps(truth)
    assert truth["seed"] == 3 and type(truth["seed"]) is int
    x3, _ = simulate_recording("two-mic", [1.0, 1.0, 0.0], duration_s=0.1, seed=3)
    np.testing.assert_array_equal(x, x3)


def test_save_recording_writes_both_files_or_neither(tmp_path):
    """save_recording wrote the WAV before the JSON could fail: a truth holding numpy scalars
    (json.dumps TypeError) or a directory at OUT.json (IsADirectoryError) left a recording
    without its truth, and the error was a builtin one."""
    from hearsee.errors import InputFileError

    x, truth = simulate_recording("two-mic", [1.0, 1.0, 0.0], duration_s=0.1, seed=3)
    wav, js = save_recording(tmp_path / "a.wav", x, {**truth, "seed": np.int64(3),
                                                      "distance_m": np.float32(1.5)})
    doc = json.loads(js.read_text())
    assert doc["seed"] == 3 and doc["distance_m"] == 1.5
    (tmp_path / "b.json").mkdir()
    # ('is a directory' before: now config.output_file's wording, as every output path's)
    with pytest.raises(InputFileError, match=r"b\.json: is a folder, expected an output file "
                                             "name$"):
        save_recording(tmp_path / "b.wav", x, truth)
    assert not (tmp_path / "b.wav").exists()
    # a missing folder is named for the WAV the caller gave, before any work
    with pytest.raises(InputFileError, match=r"c\.wav: folder .*no does not exist$"):
        save_recording(tmp_path / "no" / "c.wav", x, truth)


def test_non_numeric_rate_and_snr_are_config_errors():
    """A sample rate or SNR given as a string (e.g. read from a text file) raised numpy's
    TypeError ("ufunc 'isfinite' not supported for the input types")."""
    from hearsee.sim.audio import check_sim_fs

    for fs in ("16000", [16000], True):
        with pytest.raises(ConfigError, match="sample rate"):
            simulate_recording("two-mic", [1.0, 0.0, 0.0], duration_s=0.1, fs=fs)
    assert check_sim_fs(np.float64(16000.0)) == 16000
    for snr in ("10", [10.0]):
        with pytest.raises(ConfigError, match="SNR"):
            simulate_recording("two-mic", [1.0, 0.0, 0.0], duration_s=0.1, snr_db=snr)


def test_bad_seed_is_a_config_error():
    """A negative, fractional or text seed raised numpy's ValueError / TypeError ('expected
    non-negative integer', 'SeedSequence expects int ...')."""
    for seed in (-1, 1.5, "a"):
        with pytest.raises(ConfigError, match="seed"):
            simulate_recording("two-mic", [1.0, 0.0, 0.0], duration_s=0.1, seed=seed)
    assert simulate_recording("two-mic", [1.0, 0.0, 0.0], duration_s=0.1, seed=None)[1][
        "seed"] is None


@pytest.mark.parametrize("bad", [[True, 1.0, 0.0], ["1", "1", "0"], [10**400, 0.0, 0.0]])
def test_source_and_room_coordinates_are_numbers(bad):
    """simulate_recording / ground_truth read True as 1 m and "1" as 1 m (a recording of a
    source the caller never meant) and raised a builtin OverflowError on an int beyond float's
    range; room_dim and array_at the same. All GeometryErrors naming the argument now."""
    arr = MicArray.from_preset("two-mic")
    with pytest.raises(GeometryError, match=r"^source must be a finite \[x, y, z\]"):
        simulate_recording(arr, bad, duration_s=0.1)
    with pytest.raises(GeometryError, match=r"^source must be a finite \[x, y, z\]"):
        ground_truth(arr, bad)
    for key, room in (("room_dim", {"room_dim": [bad[0], 4.0, 3.0], "rt60": 0.2}),
                      ("array_at", {"room_dim": [5, 4, 3], "rt60": 0.2, "array_at": bad})):
        with pytest.raises(GeometryError, match=rf"^{key} must be a finite \[x, y, z\]"):
            normalize_room(room)


@pytest.mark.parametrize("array", ["respeaker-4", "mask2"])
def test_a_far_field_source_1e300_m_away_has_its_direction(array):
    """A far-field source is a direction: (1e300, 1e300, 0) is 45 deg. np.linalg.norm summed
    its squares to inf: RuntimeWarnings, every truth TDOA -0.0 and the distance inf (null in
    the JSON), the recording that of no direction at all (all channels in phase; the masked
    array's too). Now the recording and the truth TDOAs are those of (1, 1, 0), bit for bit,
    and the distance is the point's own, 1.41e300 m."""
    import math
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        x, truth = simulate_recording(array, [1e300, 1e300, 0.0], duration_s=0.1,
                                      far_field=True)
    x1, truth1 = simulate_recording(array, [1.0, 1.0, 0.0], duration_s=0.1, far_field=True)
    np.testing.assert_array_equal(x, x1)
    assert truth["tdoa_s"] == truth1["tdoa_s"]
    assert truth.get("mask_itd_s") == truth1.get("mask_itd_s")  # (the masked array's ITD)
    assert ("mask_itd_s" in truth) == (array == "mask2")
    assert any(t != 0 for t in truth["tdoa_s"].values())
    assert truth["azimuth_deg"] == pytest.approx(45.0) and truth["elevation_deg"] == 0.0
    assert truth["distance_m"] == math.hypot(1e300, 1e300) != math.inf


def test_a_source_beyond_float_range_is_refused():
    """(1.7e308, 1.7e308, 0) is 2.4e308 m away: beyond float's range, no distance or truth can
    hold it (it was written with distance inf, TDOAs -0.0, after RuntimeWarnings). A
    GeometryError names it, near or far field."""
    for far_field in (False, True):
        with pytest.raises(GeometryError, match=r"^source: \[1\.7e\+308, 1\.7e\+308, 0\.0\] is "
                                                "farther from the origin than a float can hold"):
            simulate_recording("respeaker-4", [1.7e308, 1.7e308, 0.0], duration_s=0.1,
                               far_field=far_field)


@pytest.mark.parametrize("snr", [1e6, -500.0, float("nan")])
def test_the_simulators_refuse_an_snr_before_any_work(snr, monkeypatch, tmp_path):
    """simulate_recording, simulate_moving_recording and simulate_pose_manifest checked the
    SNR only in add_noise, after the whole clean simulation (1e6 dB: an OverflowError there
    before that check existed). Now at once: the source signal is never made."""
    import hearsee.audio.signals as signals
    from hearsee.audio.active import simulate_pose_manifest
    from hearsee.sim.moving import linear_trajectory, simulate_moving_recording

    def never(*args, **kwargs):
        raise AssertionError("the simulation started before the SNR was checked")

    monkeypatch.setattr(signals, "make_signal", never)
    traj = linear_trajectory([1.0, 0.0, 0.0], [1.0, 1.0, 0.0], 1.0)
    calls = (lambda: simulate_recording("three-mic", [1.0, 1.0, 0.0], snr_db=snr),
             lambda: simulate_moving_recording("three-mic", traj, snr_db=snr),
             lambda: simulate_pose_manifest(tmp_path / "m.yaml", "three-mic", [1.0, 1.0, 0.0],
                                            [(0.0, 0.0), (30.0, 0.0)], snr_db=snr))
    for call in calls:
        with pytest.raises(ConfigError, match="SNR"):
            call()
    assert list(tmp_path.iterdir()) == []


def test_save_recording_needs_the_truths_sample_rate(tmp_path):
    """A truth without "fs" was a builtin KeyError, after the output checks; nothing is
    written, and with "fs" the WAV is at that rate."""
    import soundfile as sf

    from hearsee.sim.audio import save_recording

    x = np.ones((2, 160)) * np.linspace(-1.0, 1.0, 160)
    for truth in ({"source_m": [1.0, 0.0, 0.0]}, [("fs", 16000)], None):
        with pytest.raises(ConfigError, match="'fs'"):
            save_recording(tmp_path / "r.wav", x, truth)
    assert not (tmp_path / "r.wav").exists() and not (tmp_path / "r.json").exists()
    wav, _ = save_recording(tmp_path / "r.wav", x, {"fs": 8000})
    assert sf.info(str(wav)).samplerate == 8000


@pytest.mark.parametrize("array", ["three-mic", "mask2"])
def test_far_field_in_a_room_is_refused(array):
    """A plane wave has no place in a room's image sources: ConfigError for bare and masked
    arrays alike (the masked branch had its own copy of the check)."""
    from hearsee.sim.audio import render

    room = {"room_dim": [6.0, 5.0, 3.0], "rt60": 0.3}
    with pytest.raises(ConfigError, match="far_field applies to free field only"):
        render(np.ones(1600), 16000, MicArray.from_preset(array), [1.0, 1.0, 0.0], room,
               far_field=True)


def test_far_field_that_is_no_bool_is_refused_by_the_truth_and_render():
    """ground_truth took far_field by its truth: "no" gave a near source (0.3, 0.5, 0) m the
    plane-wave TDOA of two-mic (375.00 us) for its exact one (374.17 us), without a word; in a
    room render said "far_field applies to free field only" for "no". Both are ConfigErrors
    naming far_field; False and True keep their values."""
    from hearsee.sim.audio import render

    arr = MicArray.from_preset("two-mic")
    src = np.array([0.3, 0.5, 0.0])
    near = ground_truth(arr, src, far_field=False)["tdoa_s"]["0-1"]
    assert near == pytest.approx(float(arr.tdoa(src)[0]))
    assert ground_truth(arr, src, far_field=np.True_)["tdoa_s"]["0-1"] == pytest.approx(
        float(arr.tdoa_far(src)[0]))
    for bad in ("no", 0, None):
        with pytest.raises(ConfigError, match="far_field must be True or False"):
            ground_truth(arr, src, far_field=bad)
    with pytest.raises(ConfigError, match="far_field must be True or False"):
        render(np.ones(1600), FS, arr, src, {"room_dim": [6.0, 5.0, 3.0], "rt60": 0.0},
               far_field="no")


@pytest.mark.parametrize("array", ["two-mic", None, {"microphones": [[0, 0.075, 0]]}])
def test_render_and_ground_truth_refuse_an_array_that_is_no_micarray(array):
    """render and ground_truth read array.mask / array.tdoa: a preset name was a builtin
    AttributeError (simulate_recording loads names; these take a MicArray). GeometryError
    naming the array, as simulate_room's; a MicArray gives the same truth as before."""
    from hearsee.sim.audio import render

    with pytest.raises(GeometryError, match="expected a MicArray"):
        render(np.ones(1600), FS, array, [1.0, 1.0, 0.0])
    with pytest.raises(GeometryError, match="expected a MicArray"):
        ground_truth(array, [1.0, 1.0, 0.0])
    arr = MicArray.from_preset("two-mic")
    assert ground_truth(arr, [1.0, 1.0, 0.0])["azimuth_deg"] == pytest.approx(45.0)
