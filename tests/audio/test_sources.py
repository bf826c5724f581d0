"""Several sources at once (hearsee.audio.sources, localize_recording(max_sources=),
``hearsee localize --sources``): clusters of constructed angles, and talkers simulated at
known directions."""

import csv
import io
import json

import numpy as np
import pytest
import soundfile as sf

from hearsee.audio.arrays import MicArray
from hearsee.audio.localize import localize_recording
from hearsee.audio.propagation import simulate_free_field
from hearsee.audio.signals import synthetic_voice
from hearsee.audio.sources import (
    MAX_SOURCES,
    SourceTracker,
    azimuth_keys,
    direction_clusters,
    localize_moving_sources,
    localize_sources,
    second_direction,
    track_sources,
)
from hearsee.audio.tdoa import estimate_tdoas
from hearsee.cli import main
from hearsee.errors import ConfigError
from hearsee.geometry import unit_vector_deg

FS = 16000


def _ang(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


def _fold(a):
    """A two-microphone (y-axis) array's angle from broadside of azimuth ``a`` (degrees)."""
    return float(np.degrees(np.arcsin(np.sin(np.radians(a)))))


# ------------------------------------------------------------------------ constructed angles
def test_two_piles_among_scattered_frames():
    rng = np.random.default_rng(250)
    a = np.concatenate([30.0 + rng.normal(0, 2.0, 40), -100.0 + rng.normal(0, 2.0, 30),
                        rng.uniform(-180, 180, 10)])
    got = direction_clusters(a, max_sources=2)
    assert len(got) == 2
    assert _ang(got[0].angle_deg, 30.0) < 1.0 and _ang(got[1].angle_deg, -100.0) < 1.0
    # each pile's frames, and the scattered frames that happen to fall within its radius
    near = [np.sum(np.abs((a - c + 180) % 360 - 180) < 10.0) for c in (30.0, -100.0)]
    assert [c.n_frames for c in got] == near
    assert got[0].share == pytest.approx(near[0] / len(a))
    assert 1.0 < got[0].spread_deg < 4.0
    assert set(got[0].frames) >= set(range(40)) and set(got[1].frames) >= set(range(40, 70))


def test_a_pile_across_the_wrap_is_one_source():
    rng = np.random.default_rng(251)
    a = (180.0 + rng.normal(0, 2.0, 50) + 180.0) % 360.0 - 180.0  # around +-180
    got = direction_clusters(a, max_sources=3)
    assert len(got) == 1 and _ang(got[0].angle_deg, 180.0) < 1.0 and got[0].n_frames == 50


def test_small_piles_and_weights():
    rng = np.random.default_rng(252)
    a = np.concatenate([10.0 + rng.normal(0, 1.0, 60), 120.0 + rng.normal(0, 1.0, 6)])
    assert len(direction_clusters(a, max_sources=2)) == 1  # 6 of 66 frames: below 0.15
    assert len(direction_clusters(a, max_sources=2, min_share=0.05)) == 2
    # weights: the small pile's frames counting 20 times as much make it the first source
    w = np.r_[np.ones(60), np.full(6, 20.0)]
    got = direction_clusters(a, w, max_sources=2)
    assert _ang(got[0].angle_deg, 120.0) < 1.0 and got[0].share == pytest.approx(120 / 180)
    # sources closer than min_separation_deg are one
    b = np.concatenate([0.0 + rng.normal(0, 1.0, 40), 12.0 + rng.normal(0, 1.0, 40)])
    assert len(direction_clusters(b, max_sources=2, min_separation_deg=30.0)) == 1
    assert len(direction_clusters(b, max_sources=2, min_separation_deg=10.0,
                                  bandwidth_deg=2.0)) == 2
    assert direction_clusters([], max_sources=2) == []
    assert direction_clusters([1.0, 2.0], [0.0, 0.0]) == []


def test_a_broad_pile_is_one_source():
    """Frames spread evenly over 30 deg: the second maximum, 20 deg from the first, shifts
    toward it (every point of the pile's middle is a mean of its neighbours) and is dropped
    rather than splitting the pile in two."""
    a = np.linspace(0.0, 30.0, 301)
    got = direction_clusters(a, max_sources=2)
    assert len(got) == 1 and got[0].share > 0.6 and 5.0 < got[0].angle_deg < 25.0


def test_a_pile_beside_a_broad_one_is_found_with_two_asked_for():
    """A broad pile (sd 12 deg) throws up two maxima that the mean shift merges; the next
    maximum, a real second pile holding 17 % of the frames, must take the freed place."""
    rng = np.random.default_rng(95)
    a = np.r_[rng.normal(0, 12, 200), rng.normal(100, 3, 40)]
    got = direction_clusters(a, max_sources=2)
    assert len(got) == 2 and _ang(got[1].angle_deg, 100.0) < 2.0
    assert got[1].n_frames == 40 and got[1].share == pytest.approx(40 / 240)


def test_one_frame_has_no_spread():
    got = direction_clusters([42.0], max_sources=2, min_share=0.0)
    assert len(got) == 1 and got[0].angle_deg == pytest.approx(42.0)
    assert got[0].spread_deg == 0.0 and not np.signbit(got[0].spread_deg)


@pytest.mark.parametrize("kw", [
    {"angle_deg": [1.0, np.nan]}, {"angle_deg": [[1.0]]}, {"weight": [1.0, -1.0]},
    {"weight": [1.0]}, {"max_sources": 0}, {"max_sources": MAX_SOURCES + 1},
    {"max_sources": 2.5}, {"bandwidth_deg": 0.0}, {"min_separation_deg": 1.0},
    {"min_share": 1.0}, {"min_share": np.nan}, {"angle_deg": ["a", "b"]},
    {"angle_deg": ["10", "10"]}, {"angle_deg": [1j, 2.0]}, {"angle_deg": [True, 2.0]},
    {"weight": ["1", "1"]}, {"angle_deg": [[1.0, 2.0], [3.0]]},
])
def test_bad_settings_are_config_errors(kw):
    args = {"angle_deg": [1.0, 2.0], **kw}
    with pytest.raises(ConfigError):
        direction_clusters(**args)


# ------------------------------------------------------------------------ simulated talkers
def _talkers(arr, azimuths, seed, duration=3.0):
    """Free-field recording of a male and a female voice (in turn, each with its pauses)
    from ``azimuths`` (deg) 1.5 m away, 25 dB."""
    x = 0.0
    for k, az in enumerate(azimuths):
        s = synthetic_voice(("male", "female")[k % 2], duration, FS, seed + k)
        x = x + simulate_free_field(s, FS, arr, 1.5 * unit_vector_deg(az, 0.0), snr_db=25,
                                    rng=seed + 10 + k)
    return x


@pytest.fixture(scope="module")
def two3():
    return _talkers(MicArray.from_preset("three-mic"), (40.0, -110.0), 253)


def test_two_talkers_three_microphones(two3):
    arr = MicArray.from_preset("three-mic")
    tf = estimate_tdoas(two3, FS, arr, band_hz=(300, 3500))
    src, which = localize_sources(tf.tdoa_s, tf.valid, arr, tf.pairs, 2)
    assert len(src) == 2
    assert sorted(round(s["azimuth_deg"] / 10) for s in src) == [-11, 4]
    for s in src:
        truth = min((40.0, -110.0), key=lambda t: _ang(t, s["azimuth_deg"]))
        assert _ang(s["azimuth_deg"], truth) < 2.0
        assert s["share"] > 0.2 and s["n_frames"] == int(np.sum(which == src.index(s)))
    assert set(np.unique(which)) <= {-1, 0, 1} and np.all(which[~tf.valid] == -1)
    # the frames' localizations given (as localize_recording has them): the same sources;
    # frames given none are left out
    from hearsee.audio.localize import localize_tdoa

    locs = [localize_tdoa(t, arr, tf.pairs, near_field=False) if v else None
            for t, v in zip(tf.tdoa_s, tf.valid, strict=True)]
    assert localize_sources(tf.tdoa_s, tf.valid, arr, tf.pairs, 2, locs=locs)[0] == src
    none, none_which = localize_sources(tf.tdoa_s, tf.valid, arr, tf.pairs, 2,
                                        locs=[None] * len(locs))
    assert none == [] and np.all(none_which == -1)
    # one talker: one source
    one = _talkers(arr, (75.0,), 254)
    tf1 = estimate_tdoas(one, FS, arr, band_hz=(300, 3500))
    src1, _ = localize_sources(tf1.tdoa_s, tf1.valid, arr, tf1.pairs, 3)
    assert len(src1) == 1 and _ang(src1[0]["azimuth_deg"], 75.0) < 2.0


def test_two_talkers_two_microphones():
    arr = MicArray.from_preset("two-mic")
    x = _talkers(arr, (25.0, -50.0), 255)
    doc = localize_recording(x, FS, arr, kalman=False, max_sources=2, band_hz=(300, 3500))
    src = doc["sources"]
    assert len(src) == 2
    for s, truth in zip(sorted(src, key=lambda s: _fold(s["azimuth_deg"])), (-50.0, 25.0),
                        strict=True):
        assert abs(_fold(s["azimuth_deg"]) - truth) < 3.0
        # the cone's twins: the truth and its mirror about the pair's axis
        assert any(_ang(c["azimuth_deg"], truth) < 3.0 for c in s["candidates"])
        assert s["elevation_deg"] is None
    # a talker and its mirror about the pair's axis are one direction to a pair
    mirrored = _talkers(arr, (30.0, 150.0), 256)
    doc = localize_recording(mirrored, FS, arr, kalman=False, max_sources=2,
                             band_hz=(300, 3500))
    assert len(doc["sources"]) == 1 and abs(_fold(doc["sources"][0]["azimuth_deg"]) - 30) < 3


def test_localize_recording_document(two3):
    arr = MicArray.from_preset("three-mic")
    doc = localize_recording(two3, FS, arr, kalman=False, max_sources=2)
    assert {"sources"} <= set(doc) and len(doc["sources"]) == 2
    counts = [sum(f["source"] == k for f in doc["frames"]) for k in range(2)]
    assert counts == [s["n_frames"] for s in doc["sources"]]
    assert all(f["source"] is None for f in doc["frames"] if not f["valid"])
    assert set(doc["sources"][0]) == {"azimuth_deg", "elevation_deg", "candidates", "tdoa_s",
                                      "share", "n_frames", "spread_deg"}
    assert "sources" not in localize_recording(two3, FS, arr, kalman=False)
    assert "source" not in localize_recording(two3, FS, arr)["frames"][0]
    with pytest.raises(ConfigError, match="kalman=False"):
        localize_recording(two3, FS, arr, max_sources=2)
    with pytest.raises(ConfigError, match="max_sources"):
        localize_recording(two3[:2], FS, "mask2-asym", kalman=False, max_sources=2)
    with pytest.raises(ConfigError):
        localize_recording(two3, FS, arr, kalman=False, max_sources=0)


# ------------------------------------------------------------------------------------ CLI
@pytest.fixture(scope="module")
def two3_wav(two3, tmp_path_factory):
    path = tmp_path_factory.mktemp("src") / "two.wav"
    sf.write(path, (two3 / np.abs(two3).max() * 0.5).T, FS, subtype="FLOAT")
    return path


def _run(capsys, *args):
    code = main(["localize", *map(str, args)])
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def test_cli_sources(two3_wav, capsys):
    code, out, err = _run(capsys, two3_wav, "--array", "three-mic", "--sources", "2")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["kalman"] is False and len(doc["sources"]) == 2
    assert sorted(round(s["azimuth_deg"] / 10) for s in doc["sources"]) == [-11, 4]
    # (two talkers' averaged correlations name no one source: no warning when sources did)
    assert "no direction for the whole recording" not in err
    code, out, _ = _run(capsys, two3_wav, "--array", "three-mic", "--sources", "2",
                        "--format", "csv")
    rows = list(csv.DictReader(io.StringIO(out)))
    assert code == 0 and "source" in rows[0]
    assert {r["source"] for r in rows} <= {"", "0", "1"} and {"0", "1"} <= {r["source"]
                                                                             for r in rows}
    code, out, _ = _run(capsys, two3_wav, "--array", "three-mic", "--sources", "2",
                        "--format", "table")
    assert code == 0 and "source 0: azimuth" in out and "source 1: azimuth" in out


@pytest.mark.parametrize("args, words", [
    (("--array", "three-mic", "--sources", "2", "--kalman-tuned"), "--kalman-tuned"),
    (("--array", "three-mic", "--sources", "0"), "--sources"),
    (("--array", "three-mic", "--sources", "9"), "--sources"),
])
def test_cli_sources_refusals(two3_wav, capsys, args, words):
    code, out, err = _run(capsys, two3_wav, *args)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and words in lines[0] and "Traceback" not in err


def test_cli_sources_masked_array_refused(tmp_path, capsys):
    path = tmp_path / "m.wav"
    sf.write(path, np.random.default_rng(257).standard_normal((8000, 2)) * 0.1, FS)
    code, _, err = _run(capsys, path, "--array", "mask2-asym", "--sources", "2")
    assert code == 2 and "masked array" in err and len(err.strip().splitlines()) == 1


def test_sources_without_a_dead_microphone():
    """A microphone that hears only its own noise (unplugged): the other two localize the
    talkers, and the sources' TDOAs are named in the array's own pairs (its pairs null).
    Talkers at 90 and 0 deg: 30 and -60 deg from the broadside of microphones 0-1 (40 and
    -110 deg, the other tests' talkers, are -20 and -10 deg from it: one source to that pair)."""
    arr = MicArray.from_preset("three-mic")
    x = _talkers(arr, (90.0, 0.0), 259)
    x[2] = np.random.default_rng(258).standard_normal(x.shape[1]) * np.std(x[2])
    with pytest.warns(Warning):
        doc = localize_recording(x, FS, "three-mic", kalman=False, max_sources=2)
    assert doc["summary"]["dead_microphones"] == [2]
    src = doc["sources"]
    assert len(src) == 2
    for s in src:
        assert s["tdoa_s"]["0-2"] is None and s["tdoa_s"]["1-2"] is None
        assert s["tdoa_s"]["0-1"] is not None
    # mics 0 and 1 of the triangle: a pair whose broadside angles are the truth's
    axis = arr.positions[1] - arr.positions[0]
    axis /= np.linalg.norm(axis)

    def broadside(az):
        u = unit_vector_deg(az, 0.0)
        return float(np.degrees(np.arcsin(np.clip(u @ axis, -1, 1))))

    got = sorted(broadside(s["azimuth_deg"]) for s in src)
    want = sorted(broadside(a) for a in (90.0, 0.0))
    assert np.allclose(got, want, atol=3.0)


def test_localize_sources_refuses_bad_input():
    arr = MicArray.from_preset("three-mic")
    pairs = arr.pairs
    ok = np.ones(2, bool)
    for tau in ([["a", "b", "c"], ["a", "b", "c"]], [[0.0, 0.0, 0.0], [0.0, 0.0]],
                np.zeros((2, 2))):
        with pytest.raises(ConfigError):
            localize_sources(tau, ok, arr, pairs, 2)
    with pytest.raises(ConfigError, match="locs"):
        localize_sources(np.zeros((2, 3)), ok, arr, pairs, 2, locs=[None])
    for locs in (5, "ab"):  # (5: len()'s builtin TypeError)
        with pytest.raises(ConfigError, match="locs must be a list"):
            localize_sources(np.zeros((2, 3)), ok, arr, pairs, 2, locs=locs)
    for locs in ([1, 1], ["x", None]):  # (a builtin AttributeError: no 'azimuth_deg')
        with pytest.raises(ConfigError, match="locs must hold one Localization"):
            localize_sources(np.zeros((2, 3)), ok, arr, pairs, 2, locs=locs)
    with pytest.raises(ConfigError, match="valid"):
        localize_sources(np.zeros((2, 3)), ["yes", "no"], arr, pairs, 2)
    with pytest.raises(ConfigError, match="unknown direction_clusters setting 'foo'"):
        localize_sources(np.zeros((2, 3)), ok, arr, pairs, 2, foo=1)


@pytest.mark.parametrize("tilt_deg, cone_deg", [(90.0, (50.0, 110.0)), (60.0, (10.0, 50.0))])
def test_a_vertical_or_tilted_pair_clusters_its_cones(tmp_path, tilt_deg, cone_deg):
    """A pair whose axis is vertical (no azimuth at all) or tilted 60 deg up (cones of 10 and
    50 deg about it miss the horizontal plane, and both land on the axis azimuth): its frames
    are clustered by their cones, so two talkers on two cones are two sources, each reported
    with its cone's TDOA (exact TDOAs with 2-us noise)."""
    a = np.array([0.0, np.cos(np.radians(tilt_deg)), np.sin(np.radians(tilt_deg))])
    path = tmp_path / "pair.yaml"
    mics = [[float(v) for v in m] for m in (-0.1 * a, 0.1 * a)]
    path.write_text(f"name: slanted\nmicrophones: {mics}\n")
    arr = MicArray.from_yaml(path)
    rng = np.random.default_rng(259)
    cones = np.r_[np.full(50, cone_deg[0]), np.full(50, cone_deg[1])]
    # tdoa_0-1 = -(M_0 - M_1) . u / c = 0.2 cos(cone) / c, u on the cone about a
    tau = (0.2 * np.cos(np.radians(cones)) / arr.speed_of_sound
           + rng.normal(0, 2e-6, 100))[:, None]
    src, which = localize_sources(tau, np.ones(100, bool), arr, arr.pairs, 2)
    assert len(src) == 2 and sorted(s["n_frames"] for s in src) == [50, 50]
    got = sorted(float(np.degrees(np.arccos(s["tdoa_s"]["0-1"] * arr.speed_of_sound / 0.2)))
                 for s in src)
    assert np.allclose(got, cone_deg, atol=1.5)
    assert set(which[:50]) != set(which[50:])


# ----------------------------------------------------------------------- moving talkers
def _two_talker_angles(seed, n=190, hop=0.032, outliers=0.05):
    """Frames of a walker (-60 -> +30 deg at 15 deg/s) and a still talker (80 deg) by turns,
    a third of the frames without a direction, ``outliers`` of them anywhere; 3-deg noise.
    Returns ``t, angles, who`` (0 walker, 1 still, 2 none or an outlier)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * hop
    who = rng.integers(0, 3, n)
    a = np.where(who == 0, -60.0 + 15.0 * t, 80.0) + rng.normal(0, 3.0, n)
    a[who == 2] = np.nan
    out = rng.random(n) < outliers
    a[out] = rng.uniform(-180, 180, out.sum())
    who[out] = 2
    return t, a, who


def test_a_walker_and_a_still_talker_are_two_tracks():
    t, a, who = _two_talker_angles(268)
    tracks, which = track_sources(t, a, max_sources=2)
    assert len(tracks) == 2
    walker = next(k for k, tr in enumerate(tracks) if abs(tr.angle_deg[-1] - 80.0) > 20)
    still = 1 - walker
    # nearly every frame of each talker joins its track (the first ones start it)
    assert np.mean(which[who == 0] == walker) > 0.9 and np.mean(which[who == 1] == still) > 0.9
    assert set(which[np.isnan(a)]) == {-1}
    for k, truth in ((walker, lambda tt: -60.0 + 15.0 * tt), (still, lambda tt: 80.0)):
        tr = tracks[k]
        settled = tr.t > tr.t[0] + 0.5  # (after its first half second)
        err = np.abs((tr.angle_deg[settled] - truth(tr.t[settled]) + 180) % 360 - 180)
        assert np.median(err) < 2.0 and err.max() < 8.0
        assert np.array_equal(tr.frames, np.flatnonzero(which == k))
        assert tr.t[0] == t[tr.frames[0]] and tr.t[-1] == t[tr.frames[-1]]
    assert sum(tr.share for tr in tracks) == pytest.approx(
        np.sum(which >= 0) / np.sum(np.isfinite(a)))


def test_a_walker_across_the_wrap_is_one_track():
    rng = np.random.default_rng(269)
    t = np.arange(150) * 0.032
    truth = 160.0 + 12.0 * t  # 160 -> 217.6 = -142.4 deg
    a = (truth + rng.normal(0, 2.0, 150) + 180.0) % 360.0 - 180.0
    a[rng.random(150) < 0.4] = np.nan
    tracks, which = track_sources(t, a, max_sources=2)
    assert len(tracks) == 1 and np.all(which[np.isfinite(a)][3:] == 0)
    assert _ang(tracks[0].angle_deg[-1], truth[-1]) < 4.0


def test_a_talker_whose_track_broke_is_one_source():
    """A walker at 25 deg/s, silent for 2.5 s: the track coasts on a relaxing rate and falls
    ~27 deg behind, so the walker's next frames start a new track; the two pieces, whose
    straight-line extrapolations meet, are linked into one source (TRACK_LINK_GAP_S). A talker
    who stops and another who starts 1 s later 90 deg away stay two."""
    linked = 0
    for seed in range(334, 342):
        rng = np.random.default_rng(seed)
        t = np.arange(0.0, 7.0, 0.032)
        a = -80.0 + 25.0 * t + rng.normal(0, 2.0, t.size)
        a[(rng.random(t.size) < 0.35) | ((t > 2.0) & (t < 4.5))] = np.nan
        apart, which_apart = track_sources(t, a, link_gap_s=0.0)
        assert len(apart) == 2  # (the broken track, each piece its own source)
        tracks, which = track_sources(t, a)
        if len(tracks) == 1:
            linked += 1
            assert np.array_equal(which == 0, which_apart >= 0)  # (both pieces' frames)
            assert tracks[0].share == pytest.approx(1.0)
            assert _ang(tracks[0].angle_deg[-1], -80.0 + 25.0 * t[tracks[0].frames[-1]]) < 6.0
        b = np.where(t < 3.0, 0.0, np.where(t > 4.0, 90.0, np.nan)) + rng.normal(0, 2.0, t.size)
        b[rng.random(t.size) < 0.35] = np.nan
        assert len(track_sources(t, b)[0]) == 2
    assert linked >= 6  # (a line fitted to 0.6 s of noisy frames misses now and then)


def test_at_most_max_sources_at_once_and_small_tracks_dropped():
    t, a, who = _two_talker_angles(270)
    one, which = track_sources(t, a, max_sources=1)
    # one at a time: the talker with the larger share, every frame of the other none
    assert len(one) == 1
    assert np.all(which[who == 1] == -1) or np.all(which[who == 0] == -1)
    # a burst of 5 frames at 150 deg holds under 5 % of the frames: not a source
    b = a.copy()
    b[100:105] = 150.0
    tracks, which = track_sources(t, b, max_sources=3)
    assert len(tracks) == 2 and np.all(which[100:105] == -1)
    kept, _ = track_sources(t, b, max_sources=3, min_share=0.0)
    assert len(kept) == 3 and any(_ang(tr.angle_deg[-1], 150.0) < 3 for tr in kept)
    # scattered frames pile up nowhere (chance would put as many in a gate: max_chance): of
    # 20 such recordings, every frame or half of them located, at most one gives a track
    rng = np.random.default_rng(271)
    none, which = track_sources(t, rng.uniform(-180, 180, len(t)), max_sources=2)
    assert none == [] and np.all(which == -1)
    found = []
    for _ in range(20):
        r = rng.uniform(-180, 180, len(t))
        r[rng.random(len(t)) < 0.5] = np.nan
        found.append(len(track_sources(t, r, max_sources=2)[0]))
    assert sum(found) <= 1, found
    # the same frames with the chance test off: tracks of chance frames
    loose = [len(track_sources(t, np.where(rng.random(len(t)) < 0.5, np.nan,
                                           rng.uniform(-180, 180, len(t))),
                               max_sources=2, max_chance=1.0)[0]) for _ in range(20)]
    assert sum(loose) >= 5, loose
    empty, which = track_sources(t, np.full(len(t), np.nan))
    assert empty == [] and np.all(which == -1)


def _split_talker_angles(seed, beside_deg, n=190, hop=0.032):
    """Frames of one talker walking from -40 deg at 10 deg/s, each at random either from its
    direction or from ``beside_deg`` beside it (its frames split by a reflection), 2-deg
    noise, a third of the frames without a direction. Returns ``t, angles, truth``."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * hop
    truth = -40.0 + 10.0 * t
    a = truth + np.where(rng.random(n) < 0.5, beside_deg, 0.0) + rng.normal(0, 2.0, n)
    a[rng.random(n) < 0.33] = np.nan
    return t, a, truth


def _crossing_angles(seed, start_deg, rate_dps, noise_deg, n=190, hop=0.032):
    """Frames of a walker at ``start_deg + rate_dps * t`` and a talker standing at 0 deg: each
    frame at random the walker's, the still talker's or without a direction (a third each),
    with ``noise_deg`` of noise. Returns ``t, angles``."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * hop
    who = rng.integers(0, 3, n)
    a = np.where(who == 0, start_deg + rate_dps * t, 0.0) + rng.normal(0, noise_deg, n)
    a[who == 2] = np.nan
    return t, a


@pytest.mark.parametrize("seed", [300, 302])
def test_a_talker_split_between_two_side_by_side_tracks_is_one_source(seed):
    t, a, truth = _split_talker_angles(seed, 17.0)
    located = np.isfinite(a)
    # two tracks 17 deg apart for the whole recording, each with about half the frames
    apart, which = track_sources(t, a, merge_deg=0.0)
    assert len(apart) == 2 and all(0.35 < tr.share < 0.65 for tr in apart)
    # closer than TRACK_MERGE_DEG (20): one talker, every located frame its
    tracks, which = track_sources(t, a)
    assert len(tracks) == 1 and tracks[0].share == pytest.approx(1.0)
    assert np.array_equal(which >= 0, located) and set(which[located]) == {0}
    assert np.array_equal(tracks[0].frames, np.flatnonzero(located))
    # its path: the heavier track's, from the first frame to the last, on the talker's side
    heavier = max(apart, key=lambda tr: tr.share)
    assert tracks[0].t[0] == t[located][0] and tracks[0].t[-1] == t[located][-1]
    on = np.isin(tracks[0].t, heavier.t)
    assert np.array_equal(tracks[0].angle_deg[on], heavier.angle_deg)
    err = tracks[0].angle_deg - np.interp(tracks[0].t, t, truth)
    assert np.all((err > -8.0) & (err < 17.0 + 8.0))
    # 25 deg apart they stay two (two talkers walking side by side), unless the bar is wider
    t, a, _ = _split_talker_angles(seed, 25.0)
    assert len(track_sources(t, a)[0]) == 2
    assert len(track_sources(t, a, merge_deg=30.0)[0]) == 1


def test_two_talkers_whose_paths_cross_are_not_merged():
    # a walker crossing in front of a still talker (0 deg), within 20 deg of it for a quarter
    # of the time: two sources, as without the merge (the merge looks at the median distance)
    t, a = _crossing_angles(310, -75.0, 25.0, 3.0)
    tracks, which = track_sources(t, a)
    _, unmerged = track_sources(t, a, merge_deg=0.0)
    assert len(tracks) == 2 and np.array_equal(which, unmerged)
    for tau in (1.0, 5.0):  # (away from the crossing: one track on each talker)
        assert all(tr.t[0] <= tau <= tr.t[-1] for tr in tracks)
        at = [float(np.interp(tau, tr.t, tr.angle_deg)) for tr in tracks]
        assert min(_ang(at[0], -75.0 + 25.0 * tau), _ang(at[1], -75.0 + 25.0 * tau)) < 8.0
        assert min(_ang(at[0], 0.0), _ang(at[1], 0.0)) < 8.0


def test_a_slow_walker_crossing_a_still_talker_is_not_merged_with_it():
    # a walker at 10 deg/s crossing a still talker (0 deg) mid-recording: within 20 deg of it
    # for two thirds of the time, so the median distance alone merges them; their difference
    # spreads over tens of degrees (TRACK_MERGE_SPREAD_DEG): two sources, as without the merge
    t, a = _crossing_angles(312, -30.0, 10.0, 2.0)
    tracks, which = track_sources(t, a)
    _, unmerged = track_sources(t, a, merge_deg=0.0)
    assert len(tracks) == 2 and np.array_equal(which, unmerged)
    for tau in (0.6, 1.2):  # (before the crossing: one track on each talker)
        at = [float(np.interp(tau, tr.t, tr.angle_deg)) for tr in tracks
              if tr.t[0] <= tau <= tr.t[-1]]
        assert len(at) == 2
        w = -30.0 + 10.0 * tau
        assert min(_ang(at[0], w), _ang(at[1], w)) < 8.0
        assert min(_ang(at[0], 0.0), _ang(at[1], 0.0)) < 8.0
    # with no bar on the spread, the median alone merges the walker into the still talker
    merged, _ = track_sources(t, a, merge_spread_deg=360.0)
    assert len(merged) == 1 and merged[0].share == pytest.approx(1.0)


@pytest.mark.parametrize("args, kw, words", [
    (([0.0, 0.1, 0.05], [1.0, 2.0, 3.0]), {}, "non-decreasing"),
    (([0.0, np.nan], [1.0, 2.0]), {}, "non-decreasing"),
    (([0.0, 0.1], [1.0, np.inf]), {}, "angle_deg"),
    (([0.0, 0.1], [1.0, 2.0, 3.0]), {}, "angle_deg"),
    (([0.0, 0.1], ["a", "b"]), {}, "angle_deg"),
    (([[0.0, 0.1]], [1.0, 2.0]), {}, "t: expected shape N,"),
    (([0.0, 0.1], [1.0, 2.0], [1.0, -1.0]), {}, "weight"),
    (([0.0, 0.1], [1.0, 2.0]), {"max_sources": 9}, "max_sources"),
    (([0.0, 0.1], [1.0, 2.0]), {"confirm_hits": 0}, "confirm_hits"),
    (([0.0, 0.1], [1.0, 2.0]), {"max_jump_deg": 0.0}, "max_jump_deg"),
    (([0.0, 0.1], [1.0, 2.0]), {"max_coast_s": np.nan}, "max_coast_s"),
    (([0.0, 0.1], [1.0, 2.0]), {"min_share": 1.0}, "min_share"),
    (([0.0, 0.1], [1.0, 2.0]), {"max_chance": 0.0}, "max_chance"),
    (([0.0, 0.1], [1.0, 2.0]), {"span_deg": 400.0}, "span_deg"),
    (([0.0, 0.1], [1.0, 2.0]), {"merge_deg": -1.0}, "merge_deg"),
    (([0.0, 0.1], [1.0, 2.0]), {"merge_deg": 181.0}, "merge_deg"),
    (([0.0, 0.1], [1.0, 2.0]), {"merge_deg": np.nan}, "merge_deg"),
    (([0.0, 0.1], [1.0, 2.0]), {"merge_spread_deg": -1.0}, "merge_spread_deg"),
    (([0.0, 0.1], [1.0, 2.0]), {"merge_spread_deg": np.inf}, "merge_spread_deg"),
    (([0.0, 0.1], [1.0, 2.0]), {"merge_spread_deg": 361.0}, "merge_spread_deg"),
    (([0.0, 0.1], [1.0, 2.0]), {"merge_spread_deg": np.nan}, "merge_spread_deg"),
    (([0.0, 0.1], [1.0, 2.0]), {"link_gap_s": -1.0}, "link_gap_s"),
    (([0.0, 0.1], [1.0, 2.0]), {"link_gap_s": np.inf}, "link_gap_s"),
    (([0.0, 0.1], [1.0, 2.0]), {"link_deg": 181.0}, "link_deg"),
    (([0.0, 0.1], [1.0, 2.0]), {"link_deg": np.nan}, "link_deg"),
    # (the Kalman filter's own ranges: its EstimationError came at the first located frame)
    (([0.0, 0.1], [1.0, 2.0]), {"sigma_accel_dps2": 1e300}, "sigma_accel_dps2"),
    (([0.0, 0.1], [np.nan, np.nan]), {"sigma_accel_dps2": 1e300}, "sigma_accel_dps2"),
    (([0.0, 0.1], [1e300, 2.0]), {}, "angle_deg"),
])
def test_track_sources_refuses_bad_input(args, kw, words):
    with pytest.raises(ConfigError, match=words):
        track_sources(*args, **kw)


def _walk_and_stand(arr, seed, duration=4.0):
    """Free field: a male voice walking from -60 deg (2 m away) at 0.6 m/s across the front,
    a female voice standing at 110 deg 1.5 m away, 25 dB. Returns the recording and the
    walker's trajectory."""
    from hearsee.sim.moving import linear_trajectory, simulate_moving_recording

    start = 2.0 * unit_vector_deg(-60.0, 0.0)
    traj = linear_trajectory(start, [0.0, 0.6, 0.0], duration)
    xw, _ = simulate_moving_recording(arr, traj, "male", duration, FS, seed=seed)
    s = synthetic_voice("female", duration, FS, seed + 1)
    xs = simulate_free_field(s, FS, arr, 1.5 * unit_vector_deg(110.0, 0.0), rng=seed + 2)
    n = min(xw.shape[1], xs.shape[1])
    from hearsee.audio.propagation import add_noise

    return add_noise(xw[:, :n] + xs[:, :n], 25.0, seed + 3), traj


@pytest.mark.parametrize("preset", ["three-mic", "two-mic"])
def test_localize_recording_follows_a_walking_talker(preset):
    arr = MicArray.from_preset(preset)
    two = arr.n_mics == 2
    x, traj = _walk_and_stand(arr, 272)
    doc = localize_recording(x, FS, arr, kalman=False, max_sources=2, moving=True,
                             band_hz=(300, 3500))
    src = doc["sources"]
    assert 2 <= len(src) <= 3
    assert set(src[0]) == {"azimuth_deg", "elevation_deg", "candidates", "tdoa_s", "share",
                           "n_frames", "t_start_s", "t_end_s", "path"}
    counts = [sum(f["source"] == k for f in doc["frames"]) for k in range(len(src))]
    assert counts == [s["n_frames"] for s in src]

    def err(est, truth):
        return abs(_fold(est) - _fold(truth)) if two else _ang(est, truth)

    # every half second from 1 s: each talker within 8 deg of a track alive then
    hits = []
    for tau in np.arange(1.0, 3.6, 0.5):
        walker = float(np.degrees(np.arctan2(*traj.heard_at(tau)[1::-1])))
        est = [s["path"]["azimuth_deg"][int(np.argmin(np.abs(np.array(s["path"]["t_s"]) - tau)))]
               for s in src if s["t_start_s"] <= tau <= s["t_end_s"]]
        hits.append([any(err(e, truth) < 8.0 for e in est) for truth in (walker, 110.0)])
    assert np.mean(hits) >= 0.8, hits
    # where it was last heard: the walker's track ends near its last position
    last = max(src, key=lambda s: s["t_end_s"] if err(s["azimuth_deg"], 110.0) > 20 else -1)
    end = float(np.degrees(np.arctan2(*traj.heard_at(last["t_end_s"])[1::-1])))
    assert err(last["azimuth_deg"], end) < 8.0


def test_moving_needs_several_sources(two3):
    arr = MicArray.from_preset("three-mic")
    with pytest.raises(ConfigError, match="max_sources >= 2"):
        localize_recording(two3, FS, arr, kalman=False, moving=True)
    with pytest.raises(ConfigError, match="moving must be True or False"):
        localize_recording(two3, FS, arr, kalman=False, max_sources=2, moving="yes")
    with pytest.raises(ConfigError, match="unknown track_sources setting 'bandwidth_deg'"):
        tf = estimate_tdoas(two3, FS, arr)
        localize_moving_sources(tf.t, tf.tdoa_s, tf.valid, arr, tf.pairs, 2, bandwidth_deg=4)


def test_cli_moving(two3_wav, capsys):
    code, out, err = _run(capsys, two3_wav, "--array", "three-mic", "--sources", "2",
                          "--moving")
    assert code == 0, err
    doc = json.loads(out)
    # two still talkers, tracked: two sources at their directions, each path on it
    assert sorted(round(s["azimuth_deg"] / 10) for s in doc["sources"]) == [-11, 4]
    for s in doc["sources"]:
        path = np.array([a for a in s["path"]["azimuth_deg"]])
        assert np.all([_ang(p, s["azimuth_deg"]) < 6.0 for p in path])
        assert len(s["path"]["t_s"]) == len(path) and s["t_start_s"] == s["path"]["t_s"][0]
    code, out, _ = _run(capsys, two3_wav, "--array", "three-mic", "--sources", "2",
                        "--moving", "--format", "table")
    assert code == 0 and "source 0: azimuth" in out and "heard 0." in out
    code, out, err = _run(capsys, two3_wav, "--array", "three-mic", "--moving")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "--sources" in err and "Traceback" not in err


def test_overlapping_tracks_under_the_cap_and_a_wide_jump_gate():
    """Two talkers whose lives overlap (30 deg for 0-3 s, -60 deg for 2-5 s, the first with
    more frames): one at a time keeps the larger whole, two keep both; a jump gate of 180 deg
    (none) leaves the chi-square gate, and the chance test counts that one (it had counted
    +-180 deg, and every source was dropped)."""
    rng = np.random.default_rng(273)
    t = np.arange(160) * 0.032
    a = np.full(len(t), np.nan)
    first = (t < 3.0) & (rng.random(len(t)) < 0.6)
    second = (t >= 2.0) & ~first & (rng.random(len(t)) < 0.5)
    a[first] = 30.0 + rng.normal(0, 2.0, first.sum())
    a[second] = -60.0 + rng.normal(0, 2.0, second.sum())
    assert first.sum() > second.sum()
    one, which = track_sources(t, a, max_sources=1)
    assert len(one) == 1 and _ang(one[0].angle_deg[-1], 30.0) < 4.0
    assert np.all(which[second] == -1)
    two, _ = track_sources(t, a, max_sources=2)
    assert sorted(round(tr.angle_deg[-1] / 10) for tr in two) == [-6, 3]
    wide, _ = track_sources(t, a, max_sources=2, max_jump_deg=180.0)
    assert sorted(round(tr.angle_deg[-1] / 10) for tr in wide) == [-6, 3]


def test_an_x_axis_pair_keeps_its_path_on_one_side(tmp_path):
    """A pair along x: the twins of a cone are +-a (both in front or both behind), and the
    path took either by rounding, frame to frame; it keeps to one now (exact TDOAs of a still
    talker at 40 deg with 2-us noise)."""
    path = tmp_path / "xpair.yaml"
    path.write_text("name: xpair\nmicrophones: [[0.075, 0, 0], [-0.075, 0, 0]]\n")
    arr = MicArray.from_yaml(path)
    rng = np.random.default_rng(273)
    n = 120
    # tdoa_0-1 = -(M_0 - M_1) . u / c
    tau = (-0.15 * np.cos(np.radians(40.0)) / arr.speed_of_sound
           + rng.normal(0, 2e-6, n))[:, None]
    src, _ = localize_moving_sources(np.arange(n) * 0.032, tau, np.ones(n, bool), arr,
                                     arr.pairs, 2)
    assert len(src) == 1
    az = np.array(src[0]["path"]["azimuth_deg"])
    assert np.all(np.sign(az) == np.sign(az[0])) and np.all(np.abs(np.abs(az) - 40.0) < 3.0)


def test_a_track_that_coasted_does_not_take_a_precise_neighbours_frame():
    """A talker at 0 deg heard all along and one at 20 deg silent since 1 s: at 3.4 s a frame
    at 8 deg is the first's (10 deg of innovation against its ~6-deg spread) though the
    second's prediction, grown through 2.4 s of silence, explains it by fewer of its own
    standard deviations -- the ln S of the association cost (without it the frame went to the
    coasted track)."""
    t = np.arange(125) * 0.032
    a = np.full(len(t), np.nan)
    a[::2] = 0.0
    early = (t < 1.0) & (np.arange(len(t)) % 2 == 1)
    a[early] = 20.0
    k = int(np.argmin(np.abs(t - 3.4)))
    a[k] = 8.0
    tracks, which = track_sources(t, a, max_sources=2, min_share=0.0)
    assert len(tracks) == 2
    first = int(which[0])
    assert _ang(tracks[first].angle_deg[0], 0.0) < 1.0 and which[k] == first


# ------------------------------------------------------------- online (SourceTracker)
def _online(t, a, **kw):
    """Each frame's reported talkers ``[(id, angle_deg), ...]`` from a SourceTracker."""
    trk = SourceTracker(**kw)
    out = []
    for ti, ai in zip(t, a, strict=True):
        trk.step(ti, ai)
        out.append([(tr.id, tr.angle_deg) for tr in trk.reported()])
    return out


def test_source_tracker_follows_a_walker_and_a_still_talker_online():
    t, a, who = _two_talker_angles(268)
    rep = _online(t, a, max_sources=2)
    assert all(len(r) <= 2 for r in rep)
    # from 1 s on, each talker has a reported track within 6 deg, the same one throughout
    ids = {0: set(), 1: set()}
    for ti, r in zip(t, rep, strict=True):
        if ti < 1.0:
            continue
        for k, truth in ((0, -60.0 + 15.0 * ti), (1, 80.0)):
            near = [i for i, ang in r if _ang(ang, truth) < 6.0]
            assert len(near) == 1, (ti, r)
            ids[k].add(near[0])
    assert len(ids[0]) == len(ids[1]) == 1 and ids[0] != ids[1]
    # nothing is reported before a track has its confirming frames
    first = next(i for i, r in enumerate(rep) if r)
    assert np.count_nonzero(np.isfinite(a[:first + 1])) >= 4


def test_source_tracker_matches_track_sources_frames():
    """The online tracks are track_sources' own: the frames of each offline track are those
    that joined one online track."""
    t, a, _ = _two_talker_angles(269)
    tracks, which = track_sources(t, a, max_sources=2)
    trk = SourceTracker(max_sources=2)
    joined = np.array([trk.step(ti, ai) for ti, ai in zip(t, a, strict=True)])
    # the offline tracks are some of the online ones: the same frames, the same partition
    for k, tr in enumerate(tracks):
        ids = set(joined[which == k])
        assert len(ids) == 1 and set(np.flatnonzero(joined == ids.pop())) == set(tr.frames)
    assert len(tracks) == 2 and set(joined[np.isnan(a)]) == {-1}


def test_source_tracker_reports_the_recently_heard_part_of_a_broken_track():
    """A talker at 30 deg for 2 s whose frames then come from -40 deg (its track broke: a
    turn faster than the track predicts) while another talks at 120 deg throughout, at most
    two reported: the live -40 deg track and the 120 deg one, not the 30 deg track coasting on
    its old frames (by their whole weight it outranked the -40 deg one for 3 s)."""
    rng = np.random.default_rng(270)
    t = np.arange(110) * 0.032
    a = np.where(np.arange(110) % 2 == 0, np.where(t < 2.0, 30.0, -40.0), 120.0)
    a = a + rng.normal(0, 1.0, len(t))
    rep = _online(t, a, max_sources=2)
    end = sorted(round(ang) for _, ang in rep[-1])
    assert len(end) == 2 and abs(end[0] + 40) < 4 and abs(end[1] - 120) < 4, rep[-1]
    # with ranking by the whole weight (a decay over 1000 s) the stale track is still reported
    stale = _online(t, a, max_sources=2, rank_tau_s=1000.0)
    assert any(abs(ang - 30) < 4 for _, ang in stale[-1]), stale[-1]


def test_source_tracker_reports_little_from_scattered_frames():
    """Frames at random angles (no talker): a reported talker at under 8 % of the frames in
    20 tries (4.7 %; 12 % with a bar of 1e-3); with the chance test off (max_chance=1) at
    most of them."""
    rng = np.random.default_rng(271)
    on, off = [], []
    for _ in range(20):
        t = np.arange(190) * 0.032
        a = rng.uniform(-180, 180, len(t))
        on.append(np.mean([bool(r) for r in _online(t, a, max_sources=2)]))
        off.append(np.mean([bool(r) for r in _online(t, a, max_sources=2, max_chance=1.0,
                                                      min_share=0.0)]))
    assert np.mean(on) < 0.08 and np.mean(off) > 0.3, (np.mean(on), np.mean(off))


def test_source_tracker_names_a_second_talker_from_its_first_frames():
    """A talker at 50 deg on every other frame; from 2 s another at -70 deg on every sixth.
    The chance test counts only the frames no other source took: the second is reported by
    its 5th frame (with every frame of its life counted, the first talker's too: its 14th,
    at 4.6 s)."""
    rng = np.random.default_rng(273)
    i = np.arange(150)
    t = i * 0.032
    a = np.where(i % 2 == 0, 50.0, np.nan)
    second = (t >= 2.0) & (i % 6 == 1)
    a[second] = -70.0
    a = a + rng.normal(0, 1.0, len(a))
    rep = _online(t, a, max_sources=2)
    k = next(n for n, r in enumerate(rep) if any(_ang(ang, -70.0) < 5 for _, ang in r))
    assert np.count_nonzero(second[:k + 1]) <= 5 and t[k] < 3.0
    assert all(any(_ang(ang, 50.0) < 5 for _, ang in r) for r in rep[k:])


def test_source_tracker_min_ratio():
    """A talker on 9 frames of 10 and a weaker direction on the tenth: both reported with
    min_ratio 0, the weaker one not with the default (its decayed weight ~1/9 of the first's,
    under 0.15)."""
    rng = np.random.default_rng(274)
    i = np.arange(200)
    t = i * 0.032
    a = np.where(i % 10 == 0, -100.0, 20.0) + rng.normal(0, 1.0, len(i))
    both = _online(t, a, max_sources=2, min_ratio=0.0)[-1]
    one = _online(t, a, max_sources=2)[-1]
    assert sorted(round(ang / 10) for _, ang in both) == [-10, 2]
    assert [round(ang / 10) for _, ang in one] == [2]


def test_source_tracker_names_a_walker_passing_near_once():
    """A talker walking at 1.5 m/s past the array 0.6 m away turns at up to 143 deg/s, faster
    than the tracks follow: its frames break away and start a new track. The old track,
    coasting, is not named beside the new one (two talkers at most 3 % of the frames, the
    walker alone and within 10 deg at > 80 %); without the take-over rule (successor_deg=0)
    it was, at > 20 % of the frames."""
    rng = np.random.default_rng(276)
    t = np.arange(190) * 0.032
    truth = np.degrees(np.arctan2(0.6, -3.0 + 1.5 * t))
    a = truth + rng.normal(0, 2.0, len(t))
    a[rng.random(len(t)) < 0.3] = np.nan  # (the pauses between words)
    for kw in ({}, {"successor_deg": 0.0}):
        rep = _online(t, a, max_sources=2, **kw)
        two = np.mean([len(r) >= 2 for r in rep])
        alone = np.mean([len(r) == 1 and _ang(r[0][1], tr) < 10 for r, tr in
                         zip(rep, truth, strict=True)])
        # (the track did break: more than one id named over the walk)
        assert len({i for r in rep for i, _ in r}) >= 2
        if kw:
            assert two > 0.2 and alone < 0.7, (two, alone)
        else:
            assert two <= 0.03 and alone > 0.8, (two, alone)


@pytest.mark.parametrize("apart_deg, named_in_pause", [(60.0, True), (25.0, False)])
def test_source_tracker_take_over_needs_a_start_near_the_quiet_talker(apart_deg,
                                                                      named_in_pause):
    """A talker at 10 deg speaks on every frame for 2 s, then pauses for 1 s while another
    speaks at 10 + ``apart_deg`` deg, then speaks again. 60 deg away the second is another
    talker: the first is named through its pause. 25 deg away (within successor_deg) the
    second began where the first was predicted: it took over, and the first is not named
    once quiet for successor_quiet_s -- until it speaks again."""
    rng = np.random.default_rng(277)
    t = np.arange(125) * 0.032
    first = (t < 2.0) | (t >= 3.0)
    a = np.where(first, 10.0, 10.0 + apart_deg) + rng.normal(0, 1.0, len(t))
    rep = _online(t, a, max_sources=2)
    pause = (t >= 2.0 + 0.3) & (t < 3.0)
    named = [any(_ang(ang, 10.0) < 5 for _, ang in r) for r in rep]
    assert all(n == named_in_pause for n, p in zip(named, pause, strict=True) if p)
    # (the first named again once it speaks -- its frames join its coasting track -- and
    # the second named through the pause either way)
    assert all(named[k] for k in np.flatnonzero(t >= 3.1))
    assert all(any(_ang(ang, 10.0 + apart_deg) < 5 for _, ang in r)
               for r, p in zip(rep, pause, strict=True) if p)


def test_source_tracker_names_a_talker_split_between_two_tracks_once():
    # one talker's frames split 17 deg apart (see the offline test): two tracks side by side,
    # both named at most frames without the rule, one with it -- the heavier, on the talker
    t, a, truth = _split_talker_angles(300, 17.0)
    apart = _online(t, a, merge_deg=0.0)
    assert np.mean([len(r) == 2 for r in apart]) > 0.5
    rep = _online(t, a)
    assert np.mean([len(r) == 2 for r in rep]) <= 0.02
    assert np.mean([len(r) == 1 for r in rep]) > 0.9
    err = np.array([ang - tr for r, tr in zip(rep, truth, strict=True) for _, ang in r])
    assert np.all((err > -8.0) & (err < 17.0 + 8.0))
    # 25 deg apart: two talkers walking side by side, both named
    t, a, _ = _split_talker_angles(300, 25.0)
    assert np.mean([len(r) == 2 for r in _online(t, a)]) > 0.5


def test_source_tracker_rotate_and_reset():
    trk = SourceTracker(max_sources=2)
    for i in range(10):
        trk.step(0.032 * i, 40.0)
    assert [round(tr.angle_deg) for tr in trk.reported()] == [40]
    trk.rotate(-50.0)  # the array turned 50 deg left: the talker is now at -10 deg
    assert [round(tr.angle_deg) for tr in trk.reported()] == [-10]
    assert trk.step(0.32, -10.0) == trk.reported()[0].id
    first = trk.reported()[0].id
    trk.reset()
    assert trk.reported() == [] and trk.live == []
    # (time starts again after a reset; the ids go on counting: a client keying on them
    # would otherwise merge two talkers)
    assert trk.step(0.0, 5.0) > first


@pytest.mark.parametrize("modes", [None, (5.0, 40.0)])
def test_a_linear_arrays_source_tracker_holds_its_tracks_within_endfire(modes):
    """span_deg=180 (a linear array's sines from broadside times 90): a talker at 20 deg
    and a second one that moved at 60 deg/s to ~66 deg and fell silent while the first went
    on. The silent one's coasting track stops at 90 (it ran on to ~137 and more: 0.6 s
    after its last frame, 21 deg from the first talker, the stream named it at endfire,
    where nobody was); with the IMM's constant rates (the stream's) and without."""
    kw = {} if modes is None else {"modes_dps2": modes, "rate_tau_s": None}
    trk = SourceTracker(max_sources=2, span_deg=180.0, **kw)
    dt, angles = 0.032, []
    for i in range(int(3.0 / dt)):
        t = dt * i
        trk.step(t, 75.0)
        if t < 1.1:
            trk.step(t, 60.0 * t)
        angles.append([tr.angle_deg for tr in trk.live])
    assert all(-90.0 <= a <= 90.0 for row in angles for a in row)
    assert max(a for row in angles for a in row) == 90.0
    assert [round(tr.angle_deg) for tr in trk.reported()] == [75]
    with pytest.raises(ConfigError, match="span_deg 360"):
        trk.rotate(10.0)


def test_a_source_tracker_that_replaces_another_goes_on_with_its_ids():
    old = SourceTracker()
    assert old.next_id == 0
    ids = {old.step(0.0, 40.0), old.step(0.1, -60.0), old.step(0.2, 150.0)}
    assert ids == {0, 1, 2} and old.next_id == 3
    new = SourceTracker(first_id=old.next_id)
    assert new.step(0.0, 40.0) == 3 and new.next_id == 4
    for bad in (-1, 1.5, "3", True, None):
        with pytest.raises(ConfigError, match="first_id"):
            SourceTracker(first_id=bad)


def test_source_tracker_filters():
    """The offline tracks' one filter (its rate relaxing over TRACK_RATE_TAU_S, the stream's
    single-talker value) or, with ``modes_dps2``, an IMM of those modes."""
    from hearsee.audio.sources import TRACK_RATE_TAU_S
    from hearsee.audio.tracking import DIRECTION_RATE_TAU_S, DirectionIMM, DirectionKalman

    assert TRACK_RATE_TAU_S == DIRECTION_RATE_TAU_S
    one, imm = SourceTracker(), SourceTracker(modes_dps2=(5, 40.0), rate_tau_s=None,
                                              mode_dwell_s=2.0)
    for trk in (one, imm):
        for i in range(6):
            trk.step(0.032 * i, 30.0 + 0.5 * i)
    (a,), (b,) = one.live, imm.live
    assert type(a.kf) is DirectionKalman and a.kf.rate_tau_s == TRACK_RATE_TAU_S
    assert type(b.kf) is DirectionIMM and b.kf.sigma_accel_dps2.tolist() == [5.0, 40.0]
    assert b.kf.mode_dwell_s == 2.0 and b.kf._mix.rate_tau_s is None
    assert b.angle_deg == pytest.approx(32.5, abs=1.5)  # (on the frames, 30-32.5 deg)


def _crossing_ids(trk, seed):
    """Frames of a still talker at 0 deg and a walker turning at 25 deg/s from -75 deg through
    it (at 3 s) to 75 deg, each frame the walker's (35 %), the still talker's (35 %) or none
    (30 %; 2-deg noise): the ids ``trk`` reported each talker under, before and after the crossing,
    at the frames the two are 30 deg or more apart."""
    rng = np.random.default_rng(seed)
    ids = {(who, after): set() for who in "ws" for after in (False, True)}
    for ti in np.arange(0.0, 6.0, 0.032):
        walker = -75.0 + 25.0 * ti
        r = rng.random()
        trk.step(ti, np.nan if r < 0.3 else (0.0 if r < 0.65 else walker) + rng.normal(0, 2.0))
        for who, truth in (("w", walker), ("s", 0.0)):
            e, i = min(((_ang(s.angle_deg, truth), s.id) for s in trk.reported()),
                       default=(180.0, None))
            if abs(walker) >= 30.0 and e < 10.0:
                ids[(who, ti > 3.0)].add(i)
    return ids


def test_imm_talker_tracks_keep_their_ids_where_they_cross():
    """The stream's IMM tracks (TALKER_MODES_DPS2, constant rates; ``StreamConfig.
    talker_modes_dps2``) keep the walker and the still talker under one id each across the
    crossing; the offline tracks' one slow filter lags the walker, and the still talker's track
    takes the walker's frames past the crossing in some of the same runs."""
    from hearsee.audio.sources import talker_tracker_settings

    kept = []
    for seed in range(322, 330):
        for stream in (True, False):
            kw = talker_tracker_settings() if stream else talker_tracker_settings(None)
            ids = _crossing_ids(SourceTracker(2, **kw), seed)
            assert all(len(v) >= 1 for v in ids.values()), ids  # (each found both times)
            kept.append((stream, all(len(ids[(w, False)] | ids[(w, True)]) == 1
                                     for w in "ws")))
    assert all(k for stream, k in kept if stream), kept
    assert not all(k for stream, k in kept if not stream), kept


@pytest.mark.parametrize("kw, words", [
    ({"max_sources": 0}, "max_sources"),
    ({"rank_tau_s": 0.0}, "rank_tau_s"),
    ({"rank_tau_s": np.inf}, "rank_tau_s"),
    ({"history": "yes"}, "history must be True or False"),
    ({"min_ratio": 1.5}, "min_ratio"),
    ({"successor_deg": -1.0}, "successor_deg"),
    ({"successor_deg": 200.0}, "successor_deg"),
    ({"successor_quiet_s": -0.1}, "successor_quiet_s"),
    ({"successor_quiet_s": np.nan}, "successor_quiet_s"),
    ({"merge_deg": -1.0}, "merge_deg"),
    ({"merge_deg": np.inf}, "merge_deg"),
    ({"span_deg": 400.0}, "span_deg"),
    ({"rate_tau_s": 0.0}, "rate_tau_s"),
    ({"rate_tau_s": np.nan}, "rate_tau_s"),
    ({"rate_tau_s": "2"}, "rate_tau_s"),
    ({"modes_dps2": (5.0,)}, "modes_dps2"),
    ({"modes_dps2": 40.0}, "modes_dps2"),
    ({"modes_dps2": "5,40"}, "modes_dps2"),
    ({"modes_dps2": (5.0, np.nan)}, "modes_dps2"),
    ({"modes_dps2": (0.0, 40.0)}, "modes_dps2"),
    ({"modes_dps2": (5.0, True)}, "modes_dps2"),
    ({"modes_dps2": [[5.0, 40.0]]}, "modes_dps2"),
    ({"mode_dwell_s": 0.0}, "mode_dwell_s"),
])
def test_source_tracker_refuses_bad_settings(kw, words):
    with pytest.raises(ConfigError, match=words):
        SourceTracker(**kw)


@pytest.mark.parametrize("frames, words", [
    ([(1.0, 10.0), (0.5, 10.0)], "non-decreasing"),
    ([(np.nan, 10.0)], "non-decreasing"),
    ([(0.0, np.inf)], "angle_deg"),
    ([(0.0, 2e9)], "angle_deg"),
])
def test_source_tracker_refuses_bad_frames(frames, words):
    trk = SourceTracker()
    with pytest.raises(ConfigError, match=words):
        for ti, ai in frames:
            trk.step(ti, ai)
    with pytest.raises(ConfigError, match="weight"):
        SourceTracker().step(0.0, 10.0, -1.0)


@pytest.mark.parametrize("args, words", [
    ((0.0, "a"), "angle_deg"), ((0.0, None), "angle_deg"), ((0.0, [1.0, 2.0]), "angle_deg"),
    ((0.0, True), "angle_deg"), ((None, 1.0), "t must"), (("0", 1.0), "t must"),
    ((0.0, 1.0, "x"), "weight"), ((0.0, 1.0, np.nan), "weight"),
])
def test_source_tracker_step_refuses_what_is_not_a_number(args, words):
    # (text, None or a list had been float()'s ValueError or TypeError; True was 1 deg)
    with pytest.raises(ConfigError, match=words):
        SourceTracker().step(*args)


# --------------------------------------------------------------- several talkers, streamed
def _streamed(x, arr, **kw):
    from hearsee.stream.pipeline import ArraySource, StreamConfig, StreamPipeline

    ups = []
    StreamPipeline(arr, StreamConfig(**kw)).run(ArraySource(x, FS), ups.append)
    return ups


@pytest.mark.parametrize("preset", ["three-mic", "two-mic"])
def test_stream_follows_a_walker_and_a_still_talker(preset):
    """``StreamConfig(max_sources=2)``: each update's sources, causal -- from 2.5 s on, each
    talker within 8 deg of a reported source (a pair modulo front/back) at >= 80 % of the
    frames, the still talker's under one id throughout."""
    arr = MicArray.from_preset(preset)
    two = arr.n_mics == 2
    x, traj = _walk_and_stand(arr, 272)
    ups = _streamed(x, arr, max_sources=2)

    def err(est, truth):
        return abs(_fold(est) - _fold(truth)) if two else _ang(est, truth)

    hits, still_ids = [], set()
    for u in ups:
        assert u.sources is not None and len(u.sources) <= 2
        assert all(set(s) == {"id", "azimuth_deg", "rate_dps", "last_heard_s", "n_frames"}
                   for s in u.to_json()["sources"])
        assert all((s["rate_dps"] is None) == two for s in u.sources)
        if u.t < 2.5:
            continue
        walker = float(np.degrees(np.arctan2(*traj.heard_at(u.t)[1::-1])))
        hits.append([any(err(s["azimuth_deg"], truth) < 8.0 for s in u.sources)
                     for truth in (walker, 110.0)])
        still_ids |= {s["id"] for s in u.sources if err(s["azimuth_deg"], 110.0) < 8.0}
        assert all(s["last_heard_s"] <= u.t for s in u.sources)
    assert np.mean(hits, axis=0).min() >= 0.8, np.mean(hits, axis=0)
    assert len(still_ids) == 1


def _bumps(peaks):
    """A steered-response profile over azimuths -180 ... 178 deg (2-deg grid) with a bump of
    height h at each (azimuth, h) of ``peaks`` (3-deg wide)."""
    az = np.arange(-180.0, 180.0, 2.0)
    prof = sum(h * np.exp(-0.5 * (_ang(az, a) / 3.0) ** 2) for a, h in peaks)
    return az, prof


def test_second_direction_is_the_strongest_other_maximum_far_enough():
    az, prof = _bumps([(40.0, 1.0), (52.0, 0.95), (-100.0, 0.9), (170.0, 0.5)])
    # 52 deg is within 20 deg of the frame's own 40: the next strongest, -100
    assert second_direction(prof, az, 40.0) == pytest.approx(-100.0)
    # own direction at -100: 40 is the strongest maximum far enough
    assert second_direction(prof, az, -100.0) == pytest.approx(40.0)
    # own direction off every maximum (a GCC peak the response does not share): its top
    assert second_direction(prof, az, 100.0) == pytest.approx(40.0)
    # the share asked: -100 holds 0.9 of the top, 170 only 0.5
    assert second_direction(prof, az, 40.0, ratio=0.95) is None
    assert second_direction(prof, az, 40.0, ratio=0.4) == pytest.approx(-100.0)
    # how far from the frame's own: -100 lies 140 deg from 40, 170 only 130
    assert second_direction(prof, az, 40.0, ratio=0.4, min_apart_deg=135.0) == (
        pytest.approx(-100.0))
    assert second_direction(prof, az, 40.0, ratio=0.4, min_apart_deg=145.0) is None
    # wrap-around: a maximum at -178 is 8 deg from an own direction at 174
    az2, prof2 = _bumps([(-178.0, 1.0), (90.0, 0.85)])
    assert second_direction(prof2, az2, 174.0) == pytest.approx(90.0)
    # nothing to take: an empty, all-zero, negative or NaN response
    for bad in (np.zeros(180), -np.ones(180), np.full(180, np.nan), np.zeros(0)):
        assert second_direction(bad, az[:bad.size], 40.0) is None


def test_azimuth_keys_are_what_the_tracker_tracks():
    az = np.array([-150.0, 0.0, 30.0, 90.0, 150.0])
    assert np.array_equal(azimuth_keys(az), az)  # (azimuths: themselves, exactly)
    # a pair along y: 90 sin(azimuth), front/back twins alike (the tracker's linear keys)
    got = azimuth_keys(az, [0.0, 1.0, 0.0])
    assert np.allclose(got, [-45.0, 0.0, 45.0, 90.0, 45.0])
    assert np.allclose(got, [90.0 * np.sin(np.radians(_fold(a))) for a in az])


@pytest.mark.parametrize("preset", ["three-mic", "two-mic"])
def test_the_steered_response_keys_agree_with_the_frames_own(preset, monkeypatch):
    """One white-noise source at -60 deg: the stream's steered response peaks, in what the
    talkers' tracker tracks (a pair's sines from broadside), where each frame's own direction
    is -- a sign or axis slip would put every second direction at the mirror."""
    from hearsee.audio.sources import frame_angle
    from hearsee.stream.pipeline import TrackingProcessor

    arr = MicArray.from_preset(preset)
    x = simulate_free_field(np.random.default_rng(316).standard_normal(FS), FS, arr,
                            1.5 * unit_vector_deg(-60.0, 0.0), snr_db=30, rng=317)
    seen = []
    step = TrackingProcessor._talkers_step

    def spy(self, t, loc, profile=None):
        ak = frame_angle(loc, self._talker_design is not None)
        if ak is not None and profile is not None:
            seen.append((ak[1], self._talker_keys[int(np.argmax(profile))]))
        return step(self, t, loc, profile)

    monkeypatch.setattr(TrackingProcessor, "_talkers_step", spy)
    _streamed(x, arr, max_sources=2)
    own, top = np.array(seen).T
    truth = -60.0 if preset == "three-mic" else 90.0 * np.sin(np.radians(-60.0))
    assert len(seen) >= 20 and np.all(np.abs(own - truth) < 2.0), own
    assert np.all(np.abs(top - own) < 2.0), top - own


def test_stream_names_a_talker_the_frames_own_directions_miss():
    """Two white-noise talkers at once, the one at -100 deg 2 dB quieter: each frame's GCC
    peaks name the louder one, so the frames' own directions alone never name the quieter
    (talker_peak_ratio=None); the second maximum of each frame's steered response does."""
    arr = MicArray.from_preset("three-mic")
    rng = np.random.default_rng(315)
    x = 0.0
    for k, (az, gain) in enumerate(((40.0, 1.0), (-100.0, 10 ** (-2.0 / 20)))):
        s = rng.standard_normal(3 * FS) * gain
        x = x + simulate_free_field(s, FS, arr, 1.5 * unit_vector_deg(az, 0.0), snr_db=30,
                                    rng=320 + k)
    for ratio, want in ((0.8, (40.0, -100.0)), (None, (40.0,))):
        ups = [u for u in _streamed(x, arr, max_sources=2, talker_peak_ratio=ratio)
               if u.t >= 1.0]
        for truth in (40.0, -100.0):
            named = np.mean([any(_ang(s["azimuth_deg"], truth) < 5.0 for s in u.sources)
                             for u in ups])
            assert (named >= 0.9) if truth in want else (named == 0.0), (ratio, truth, named)


def test_stream_sources_settings(two3):
    from hearsee.stream.pipeline import StreamConfig, TrackingProcessor

    arr = MicArray.from_preset("three-mic")
    ups = _streamed(two3[:, :FS], arr)  # (without max_sources: no "sources")
    assert all(u.sources is None and "sources" not in u.to_json() for u in ups)
    for bad in (1, 9, 2.0, True, "2"):
        with pytest.raises(ConfigError, match="max_sources"):
            StreamConfig(max_sources=bad)
    for bad in (0.0, -0.5, 1.5, float("nan"), float("inf"), "0.8", True):
        with pytest.raises(ConfigError, match="talker_peak_ratio"):
            StreamConfig(talker_peak_ratio=bad)
    assert StreamConfig(talker_peak_ratio=None).talker_peak_ratio is None
    assert StreamConfig(talker_peak_ratio=1).talker_peak_ratio == 1
    for bad in ((40.0,), 40.0, "5,40", (5.0, np.nan), (0.0, 40.0), (5.0, "40"), True):
        with pytest.raises(ConfigError, match="talker_modes_dps2"):
            StreamConfig(talker_modes_dps2=bad)
    # the default: IMM tracks (TALKER_MODES_DPS2); None: the offline tracks' filter and gate
    from hearsee.audio.sources import TALKER_MAX_JUMP_DEG, TALKER_MODES_DPS2, TRACK_MAX_JUMP_DEG
    from hearsee.audio.tracking import DirectionIMM, DirectionKalman

    assert StreamConfig().talker_modes_dps2 == TALKER_MODES_DPS2

    for modes, kind, jump in (((5.0, 40.0), DirectionIMM, TALKER_MAX_JUMP_DEG),
                              (None, DirectionKalman, TRACK_MAX_JUMP_DEG)):
        proc = TrackingProcessor(arr, FS, StreamConfig(max_sources=2, talker_modes_dps2=modes))
        proc.talkers.step(0.0, 10.0)
        assert type(proc.talkers.live[0].kf) is kind and proc.talkers.max_jump_deg == jump
    with pytest.raises(ConfigError, match="masked pair"):
        TrackingProcessor(MicArray.from_preset("mask2-asym"), FS, StreamConfig(max_sources=2))


def test_track_cli_sources(two3_wav, capsys):
    code = main(["track", str(two3_wav), "--array", "three-mic", "--sources", "2"])
    cap = capsys.readouterr()
    assert code == 0, cap.err
    rows = [json.loads(s) for s in cap.out.strip().splitlines()]
    last = rows[-1]["sources"]
    # two still talkers at 40 and -110 deg, both reported at the end
    assert sorted(round(s["azimuth_deg"] / 10) for s in last) == [-11, 4]
    assert all("sources" in r for r in rows)
    for bad in (["--sources", "9"], ["--sources", "0"]):
        code = main(["track", str(two3_wav), "--array", "three-mic", *bad])
        cap = capsys.readouterr()
        assert code == 2 and cap.out == "" and len(cap.err.strip().splitlines()) == 1
        assert "--sources" in cap.err and "Traceback" not in cap.err
    code = main(["track", str(two3_wav), "--array", "mask2-asym", "--sources", "2"])
    cap = capsys.readouterr()
    assert code == 2 and "masked" in cap.err and "Traceback" not in cap.err


def test_a_pairs_lone_talker_in_a_room_is_not_named_twice():
    """Two piles of a pair's frames (the talker's direct path, his reflections) whose averaged
    spectra (sources_from_spectra) both name the talker were two sources a degree apart (36.1
    and 34.9 deg, 58 and 21 % of the frames; RT60 0.6 s): one source, its frames and share
    both piles', each frame's source renumbered."""
    import warnings

    from hearsee.sim.audio import simulate_recording

    x, truth = simulate_recording("two-mic", [1.2, 0.9, 0.2], "male", 3.0, snr_db=20, seed=1,
                                  room={"room_dim": [6, 5, 3], "rt60": 0.6,
                                        "array_at": [3, 2.5, 1.5]})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        doc = localize_recording(x, FS, "two-mic", kalman=False, max_sources=4)
    (src,) = doc["sources"]
    assert abs(src["azimuth_deg"] - truth["azimuth_deg"]) < 3.0
    which = [f["source"] for f in doc["frames"]]
    assert set(which) == {None, 0} and which.count(0) == src["n_frames"]
    assert src["share"] == pytest.approx(0.79, abs=0.02) and src["spread_deg"] > 5.0
