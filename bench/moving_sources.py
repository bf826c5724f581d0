"""Benchmark: two talkers, one of them walking -- hearsee's tracks (``hearsee localize
--sources 2 --moving``) and its stream (``hearsee track --sources 2``) against
pyroomacoustics' SRP-PHAT, MUSIC and NormMUSIC on sliding one-second blocks, side by side on
the same recordings.

Recordings: the three-mic and two-mic presets; 6 s; one talker walks a straight line at 0.5-1.5
m/s (starting 1-2.5 m away in a random direction, staying 0.7-3.5 m from the array and 0.5 m
from the walls), the other stands 1-2.5 m away; the two at least 30 deg apart throughout (the
pair: in angle from its broadside, what it can tell); a synthetic male and female voice
(``signals.synthetic_voice``: speech-like, with pauses) or, with the shared data, two CMU ARCTIC
speakers; free field (``simulate_moving_free_field``: time-varying fractional delays) or
bench/doa.py's 8 x 7 x 3 m room at RT60 0.3 s (``simulate_moving_room``: block-wise image
sources, crossfaded; the standing talker by ``simulate_recording``); white sensor noise 20 dB
below the mixture. Also the walker alone, to count false second tracks, and scenes where the
walker crosses the still talker's direction halfway (``crossing_scene``), scored while the two
are at least 30 deg apart.

Scored every 0.5 s from t = 1 s to 5.5 s: the directions each method gives for that moment,
matched to where the two talkers were heard from then (``Trajectory.heard_at``; the
assignment whose larger error is smallest, a missing estimate 180 deg off, 90 for the pair,
whose angles are from broadside, modulo front/back): "both within 10 deg" and the matched
errors' median. hearsee (tracks): one ``localize_recording(kalman=False, max_sources=2,
moving=True)`` of the whole recording; at each moment the tracks alive then (first to last
frame) give their angle at the nearest frame -- an angle from that frame and the ones before,
but which tracks are reported, and where each ends, is decided on the whole recording (an
offline answer, as the blocks' 0.5 s ahead is). hearsee (stream): ``hearsee track --sources
2`` (``StreamConfig(max_sources=2)``, its defaults) over the recording as a file; at each
moment the talkers reported by its last update whose frame had ended then -- causal, what a
robot listening live knew then (:class:`hearsee.audio.sources.SourceTracker`). hearsee
(stream, one filter): the same with the offline tracks' one filter and gate
(``StreamConfig(talker_modes_dps2=None)``, the stream's before 2026-12-07; the default's tracks
are IMMs of a quiet and a walking mode, :data:`~hearsee.audio.sources.TALKER_MODES_DPS2`, which
keep up with a walker). The crossing scenes also score
identity: whether the tracks (offline: a source of the document; stream: the reported ``id``)
name each talker under the same identity before and after the crossing. hearsee (blocks):
``localize_recording(max_sources=2)`` (the still talkers' clustering) of the one-second block
centred on the moment. Peers: the same blocks, told there are two talkers (``num_src=2``),
set up as bench/sources.py sets them up (1024-sample Hann STFT at 50 % overlap, 300-3500 Hz,
the array plane, a 0.5-deg grid, a pair's front half; MUSIC and NormMUSIC not on the pair,
whose noise subspace two talkers leave empty: "n/a", scored until 2026-12-07).

The default seed (280) was not used to choose :func:`hearsee.audio.sources.track_sources`'
settings (chosen on dev seeds 270-273, see its constants) nor the stream's reporting rules
(:class:`~hearsee.audio.sources.SourceTracker`'s, on dev seeds 281-282; its take-over rule,
:data:`~hearsee.audio.sources.REPORT_SUCCESSOR_DEG`, held out on seeds 291-292) nor the merge
of tracks running side by side (:data:`~hearsee.audio.sources.TRACK_MERGE_DEG`, offline and in
the stream: dev seeds 281-282, held out on 293-294) nor the bar on their paths' spread
(:data:`~hearsee.audio.sources.TRACK_MERGE_SPREAD_DEG`: dev 281-282 and crossing scenes of a
scratch seed 400, held out on 295-296 and 401-402; this bench's crossing scenes draw from
``[seed, 2]``) nor the stream's second direction per frame
(:data:`~hearsee.audio.sources.TALKER_PEAK_RATIO`: dev 281 and crossing ``[400, 2]``, held out
on 297 and crossing ``[403, 2]``) nor the stream's IMM tracks
(:data:`~hearsee.audio.sources.TALKER_MODES_DPS2`: dev 281 and crossing ``[400, 2]``, held out
on crossing ``[405, 2]`` and on ``[407, 2]``, ``[408, 2]`` and seed 300) nor the offline tracks'
linking of a broken track's pieces (:data:`~hearsee.audio.sources.TRACK_LINK_GAP_S`: dev 281
and crossing ``[400, 2]``, held out on 301 and crossing ``[409, 2]``).

Usage: python bench/moving_sources.py [--trials 10] [--seed 280] [--data ../shared/data]
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import (  # noqa: E402
    RESULTS,
    arctic_files,
    markdown_table,
    print_table,
    shared_data_dir,
    write_markdown,
)
from doa import ARRAY_AT, ROOM, peer_applies, pra_azimuths  # noqa: E402
from sources import angle_error, matched_errors, room_spec, talker_specs  # noqa: E402

from hearsee.audio.arrays import MicArray  # noqa: E402
from hearsee.audio.localize import localize_recording  # noqa: E402
from hearsee.audio.propagation import add_noise  # noqa: E402
from hearsee.sim.audio import simulate_recording  # noqa: E402
from hearsee.sim.moving import linear_trajectory, simulate_moving_recording  # noqa: E402
from hearsee.stream.pipeline import ArraySource, StreamConfig, StreamPipeline  # noqa: E402

FS = 16000
ARRAYS = ("three-mic", "two-mic")
RT60S = (0.0, 0.3)
PEERS = ("SRP", "MUSIC", "NormMUSIC")
#: hearsee's: the offline tracks, the stream (default), the stream with the offline tracks'
#: one filter (``StreamConfig(talker_modes_dps2=None)``), the blocks
METHODS = ("hearsee (tracks)", "hearsee (stream)", "hearsee (stream, one filter)",
           "hearsee (blocks)", *PEERS)
#: the methods that name identities (tracks)
TRACKED = METHODS[:3]
BAND = (300.0, 3500.0)
DURATION_S = 6.0
SNR_DB = 20.0
HIT_DEG = 10.0
MIN_APART_DEG = 30.0
GRID_DEG = 0.5
BLOCK_S = 1.0
#: the moments scored (s)
TIMES_S = np.arange(1.0, DURATION_S - 0.5 + 1e-9, 0.5)
#: the walker's bounds: distance from the array (m), margin from the walls (m)
NEAR_M, FAR_M, WALL_M = 0.7, 3.5, 0.5


def _azimuth(p: np.ndarray) -> np.ndarray:
    return np.degrees(np.arctan2(p[..., 1], p[..., 0]))


def _walk(start: np.ndarray, v: np.ndarray) -> np.ndarray | None:
    """A straight walk's path (61 points over :data:`DURATION_S`, array frame, metres) from
    ``start`` at velocity ``v`` (m/s), or None when it comes nearer than :data:`NEAR_M` to the
    array, farther than :data:`FAR_M` or within :data:`WALL_M` of a wall."""
    lo = -np.asarray(ARRAY_AT[:2]) + WALL_M
    hi = np.asarray(ROOM[:2]) - np.asarray(ARRAY_AT[:2]) - WALL_M
    path = start[None, :] + np.linspace(0.0, DURATION_S, 61)[:, None] * v[None, :]
    r = np.linalg.norm(path[:, :2], axis=1)
    if (r.min() < NEAR_M or r.max() > FAR_M or np.any(path[:, :2] < lo)
            or np.any(path[:, :2] > hi)):
        return None
    return path


def scene(two: bool, rng: np.random.Generator) -> tuple:
    """A walker's :class:`~hearsee.sim.moving.Trajectory` and a still talker's position
    (array frame, metres), drawn until both stay within bounds and apart (see the module's
    docstring)."""
    while True:
        az0, head = rng.uniform(-180.0, 180.0, 2)
        start = rng.uniform(1.0, 2.5) * np.array([np.cos(np.radians(az0)),
                                                  np.sin(np.radians(az0)), 0.0])
        v = rng.uniform(0.5, 1.5) * np.array([np.cos(np.radians(head)),
                                              np.sin(np.radians(head)), 0.0])
        path = _walk(start, v)
        if path is None:
            continue
        azs = rng.uniform(-180.0, 180.0)
        still = rng.uniform(1.0, 2.5) * np.array([np.cos(np.radians(azs)),
                                                  np.sin(np.radians(azs)), 0.0])
        if all(angle_error(a, azs, two) >= MIN_APART_DEG for a in _azimuth(path)):
            return linear_trajectory(start, v, DURATION_S), still


def crossing_scene(two: bool, rng: np.random.Generator) -> tuple:
    """A walker who crosses a still talker's direction halfway through the recording: the
    still talker 1-2.5 m away, the walker passing 0.5-1.5 m nearer or farther at 0.5-1.5 m/s
    across the line of sight; drawn until the walker stays within bounds (the still talker,
    at most 2.5 m from the array in the room's middle, always is) and the two are at least
    :data:`MIN_APART_DEG` apart at the first and the last moment scored."""
    while True:
        az, ds, dw = rng.uniform(-180.0, 180.0), *rng.uniform(1.0, 2.5, 2)
        if not 0.5 <= abs(dw - ds) <= 1.5:
            continue
        u = np.array([np.cos(np.radians(az)), np.sin(np.radians(az)), 0.0])
        v = rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 1.5) * np.array([-u[1], u[0], 0.0])
        start = dw * u - v * DURATION_S / 2
        still = ds * u
        if _walk(start, v) is None:
            continue
        ends = _azimuth(start + np.array([TIMES_S[0], TIMES_S[-1]])[:, None] * v)
        if all(angle_error(a, az, two) >= MIN_APART_DEG for a in ends):
            return linear_trajectory(start, v, DURATION_S), still


def recording(arr: MicArray, kind: str, rt60: float, rng: np.random.Generator,
              speech: list[Path], alone: bool = False,
              crossing: bool = False) -> tuple[np.ndarray, object, np.ndarray]:
    """The two talkers' recording (``alone``: the walker's only; ``crossing``: the walker
    crosses the still talker's direction, :func:`crossing_scene`), the walker's trajectory and
    the still talker's position."""
    two = arr.n_mics == 2
    traj, still = (crossing_scene if crossing else scene)(two, rng)
    room = room_spec(rt60)
    walker_sig, still_sig = talker_specs(kind, 2, rng, speech)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        x, _ = simulate_moving_recording(arr, traj, signal=walker_sig, duration_s=DURATION_S,
                                         fs=FS, room=room, seed=int(rng.integers(2**31)))
        if not alone:
            xs, _ = simulate_recording(arr, still, signal=still_sig, duration_s=DURATION_S,
                                       fs=FS, room=room, seed=int(rng.integers(2**31)))
            n = min(x.shape[1], xs.shape[1])
            x = x[:, :n] + xs[:, :n]
    return add_noise(x, SNR_DB, rng), traj, still


def track_labels(doc: dict, tau: float) -> list[tuple[int, float]]:
    """The tracks alive at ``tau`` (s): each one's index in ``doc["sources"]`` (its identity)
    and azimuth (deg) at its nearest frame."""
    out = []
    for i, src in enumerate(doc["sources"]):
        if src["t_start_s"] <= tau <= src["t_end_s"]:
            ts = np.array(src["path"]["t_s"])
            a = src["path"]["azimuth_deg"][int(np.argmin(np.abs(ts - tau)))]
            if a is not None:
                out.append((i, a))
    return out


def track_estimates(doc: dict, tau: float) -> list[float]:
    """The azimuths (deg) of the tracks alive at ``tau`` (s), each at its nearest frame."""
    return [a for _, a in track_labels(doc, tau)]


def streamed(x: np.ndarray, arr: MicArray, **cfg) -> tuple[np.ndarray, list]:
    """hearsee's stream with several talkers as ``hearsee track --sources 2`` runs it
    (``StreamConfig(max_sources=2)``, its defaults: the GCC over the whole band -- on the dev
    recordings the 300-3500 Hz band of the other methods put a false second talker beside a
    lone walker twice as often; ``cfg``: other StreamConfig settings): the updates' times (s)
    and each one's reported talkers, (id, azimuth in deg)."""
    ups: list = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        StreamPipeline(arr, StreamConfig(max_sources=2, **cfg)).run(ArraySource(x, FS),
                                                                     ups.append)
    return (np.array([u.t for u in ups]),
            [[(s["id"], s["azimuth_deg"]) for s in u.sources if s["azimuth_deg"] is not None]
             for u in ups])


#: the stream's frame length (s, StreamConfig's default): an update at frame-centre time t has
#: heard the audio up to t plus half of it
STREAM_FRAME_S = StreamConfig().frame_ms / 1e3


def stream_labels(streamed_out: tuple[np.ndarray, list], tau: float
                  ) -> list[tuple[int, float]]:
    """The talkers (id, azimuth in deg) the stream reported at its last update whose frame had
    ended by ``tau`` (s): what a robot listening live knew then."""
    t, talkers = streamed_out
    k = int(np.searchsorted(t + STREAM_FRAME_S / 2, tau + 1e-9)) - 1
    return talkers[k] if k >= 0 else []


def stream_estimates(streamed_out: tuple[np.ndarray, list], tau: float) -> list[float]:
    """The azimuths (deg) of :func:`stream_labels`."""
    return [a for _, a in stream_labels(streamed_out, tau)]


def nearest_label(labelled: list[tuple[int, float]], truth: float, two: bool) -> int | None:
    """The identity of the estimate nearest ``truth`` (deg) if it is within :data:`HIT_DEG`,
    else None."""
    e, i = min(((angle_error(a, truth, two), i) for i, a in labelled), default=(180.0, None))
    return i if e < HIT_DEG else None


def kept_identity(found: dict[float, int | None], at_s: float) -> list[bool]:
    """For every pair of scored moments, one before ``at_s`` (s) and one after, at both of
    which a talker was found (``found``: moment -> the identity it was found under, or None),
    whether it was found under the same identity: a tracker that follows the talker through
    the crossing keeps it."""
    before = [i for tau, i in found.items() if tau < at_s and i is not None]
    after = [i for tau, i in found.items() if tau > at_s and i is not None]
    return [a == b for a in before for b in after]


def _localized(x: np.ndarray, arr: MicArray) -> dict:
    """hearsee's tracks of a recording: ``localize_recording``'s document."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return localize_recording(x, FS, arr, kalman=False, max_sources=2, moving=True,
                                  band_hz=BAND)


def run_alone(trials: int, seed: int, speech: list[Path]) -> dict:
    """The walker alone (its own random numbers): per (array, RT60, signal, "tracks", "stream"
    or "stream one filter") and moment, how many tracks were alive (the offline tracks) or
    reported (the stream) and the nearest one's error (deg; 180 without one)."""
    rng = np.random.default_rng([seed, 1])
    kinds = ["voices"] + (["arctic"] if speech else [])
    out: dict = {}
    for array, rt60, kind in itertools.product(ARRAYS, RT60S, kinds):
        arr = MicArray.from_preset(array)
        two = arr.n_mics == 2
        for _ in range(trials):
            x, traj, _ = recording(arr, kind, rt60, rng, speech, alone=True)
            doc = _localized(x, arr)
            live = streamed(x, arr)
            live_one = streamed(x, arr, talker_modes_dps2=None)
            for tau in TIMES_S:
                truth = float(_azimuth(traj.heard_at(tau)))
                for m, est in (("tracks", track_estimates(doc, tau)),
                               ("stream", stream_estimates(live, tau)),
                               ("stream one filter", stream_estimates(live_one, tau))):
                    e = min((angle_error(a, truth, two) for a in est), default=180.0)
                    out.setdefault((array, rt60, kind, m), []).append((len(est), e))
    return out


def alone_table(alone: dict) -> tuple[list, list]:
    headers = ["array", "RT60 s", "signal", "hearsee", "recordings x moments",
               f"one track, within {HIT_DEG:g} deg %", "two tracks %", "no track %"]
    rows = []
    for key, v in alone.items():
        n = np.array([a for a, _ in v])
        e = np.array([b for _, b in v])
        rows.append([*key, len(v), f"{100 * np.mean((n == 1) & (e < HIT_DEG)):.0f}",
                     f"{100 * np.mean(n >= 2):.0f}", f"{100 * np.mean(n == 0):.0f}"])
    return headers, rows


def run(trials: int, seed: int, speech: list[Path],
        crossing: bool = False) -> tuple[dict, dict, dict]:
    """Matched errors per (array, RT60, signal, method) -- one row per recording and moment --,
    hearsee's number of tracks per recording, and whether hearsee's tracks and streams kept
    each talker's identity (:func:`kept_identity`, per (array, RT60, signal, method, "walker"
    or "still"); the peers name no identities). ``crossing``: the walker crosses the still
    talker's direction (:func:`crossing_scene`; its own random numbers) at ``DURATION_S / 2``,
    scored only at the moments the two are at least :data:`MIN_APART_DEG` apart."""
    rng = np.random.default_rng([seed, 2] if crossing else seed)
    kinds = ["voices"] + (["arctic"] if speech else [])
    err: dict = {}
    n_tracks: dict = {}
    kept: dict = {}
    half = int(BLOCK_S * FS / 2)
    for array, rt60, kind in itertools.product(ARRAYS, RT60S, kinds):
        arr = MicArray.from_preset(array)
        two = arr.n_mics == 2
        key = (array, rt60, kind)
        for _ in range(trials):
            x, traj, still = recording(arr, kind, rt60, rng, speech, crossing=crossing)
            doc = _localized(x, arr)
            live = streamed(x, arr)
            live_one = streamed(x, arr, talker_modes_dps2=None)
            n_tracks.setdefault(key, []).append(len(doc["sources"]))
            found: dict = {}  # (method, who) -> {moment: identity or None}
            for tau in TIMES_S:
                truth = [float(_azimuth(traj.heard_at(tau))), float(_azimuth(still))]
                if angle_error(truth[0], truth[1], two) < MIN_APART_DEG:
                    continue  # (at the crossing: closer than the other scenes keep them)
                labels = dict(zip(TRACKED, (track_labels(doc, tau), stream_labels(live, tau),
                                            stream_labels(live_one, tau)), strict=True))
                for m, lab in labels.items():
                    for who, az in zip(("walker", "still"), truth, strict=True):
                        found.setdefault((m, who), {})[tau] = nearest_label(lab, az, two)
                c = int(round(tau * FS))
                blk = x[:, c - half: c + half]
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    bdoc = localize_recording(blk, FS, arr, kalman=False, max_sources=2,
                                              band_hz=BAND)
                est = {m: [a for _, a in lab] for m, lab in labels.items()}
                est["hearsee (blocks)"] = [s["azimuth_deg"] for s in bdoc["sources"]]
                for m in (m for m in PEERS if peer_applies(m, arr.n_mics, 2)):
                    est[m] = pra_azimuths(blk, FS, arr, m, BAND, 2, grid_deg=GRID_DEG,
                                          front_half=two)
                for m, e in est.items():
                    err.setdefault((*key, m), []).append(matched_errors(e, truth, two))
            for (m, who), f in found.items():
                kept.setdefault((*key, m, who), []).extend(kept_identity(f, DURATION_S / 2))
        print(f"  {array} RT60 {rt60} {kind}{' (crossing)' if crossing else ''}: done",
              flush=True)
    return err, n_tracks, kept


def both_found(err: dict, key: tuple, m: str) -> float:
    """The share (%) of a cell's moments at which method ``m`` had both talkers within
    :data:`HIT_DEG`."""
    return 100 * float(np.mean(np.array(err[(*key, m)]).max(axis=1) < HIT_DEG))


def wins(err: dict, n_tracks: dict) -> str:
    """The cells where hearsee's tracks (and its stream) found both talkers at least as often
    as the best pyroomacoustics method, in a line."""
    def won(method: str) -> int:
        return sum(both_found(err, k, method) >= max(both_found(err, k, m) for m in PEERS
                                                     if (*k, m) in err)
                   for k in n_tracks)

    return (f"hearsee (tracks) found both talkers at least as often as the best pyroomacoustics "
            f"method in {won(METHODS[0])} of {len(n_tracks)} cells, hearsee (stream) in "
            f"{won(METHODS[1])}, hearsee (stream, one filter) in {won(METHODS[2])}")


def tables(err: dict, n_tracks: dict, kept: dict | None = None) -> tuple[list, list]:
    """The table of both talkers found; with ``kept`` (crossing scenes) also the share (%) of
    the pairs of moments, one before the crossing and one after, at which hearsee's tracks
    and stream named the walker (and the still talker) under the same identity."""
    headers = ["array", "RT60 s", "signals", "recordings x moments",
               *(f"{m}: both within {HIT_DEG:g} deg % / median deg" for m in METHODS),
               "hearsee tracks per recording (mean)"]
    if kept is not None:
        headers += [f"{m}: walker / still talker keep their id % (pairs)"
                    for m in TRACKED]
    rows = []
    for key in n_tracks:
        cells = []
        for m in METHODS:
            cells.append(f"{both_found(err, key, m):.0f} / {np.median(err[(*key, m)]):.2f}"
                         if (*key, m) in err else "n/a")  # (peer_applies)
        row = [*key, len(err[(*key, METHODS[0])]), *cells, np.mean(n_tracks[key])]
        if kept is not None:
            for m in TRACKED:
                w, st = (kept.get((*key, m, who), []) for who in ("walker", "still"))
                row.append(" / ".join(f"{100 * np.mean(v):.0f}" if v else "-" for v in (w, st))
                           + f" ({len(w)} / {len(st)})")
        rows.append(row)
    return headers, rows


def kept_line(kept: dict) -> str:
    """hearsee's tracks' and stream's identities kept across the crossing, pooled over the
    cells, in a line."""
    parts = []
    for m in TRACKED:
        pooled = {who: [b for k, v in kept.items() if k[-2:] == (m, who) for b in v]
                  for who in ("walker", "still")}
        parts.append(f"{m} kept the walker's identity across the crossing in "
                     f"{100 * np.mean(pooled['walker']):.0f} % of the pairs of moments and the "
                     f"still talker's in {100 * np.mean(pooled['still']):.0f} %")
    return "; ".join(parts)


def plot(err: dict, n_tracks: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = list(n_tracks)
    fig, ax = plt.subplots(figsize=(max(6.0, 1.1 * len(keys)), 3.6))
    w = 0.8 / len(METHODS)
    for j, m in enumerate(METHODS):
        hit = [both_found(err, k, m) if (*k, m) in err else 0.0 for k in keys]  # (n/a: 0)
        ax.bar(np.arange(len(keys)) + (j - (len(METHODS) - 1) / 2) * w, hit, w, label=m)
    ax.set_xticks(np.arange(len(keys)),
                  [f"{a}\nRT60 {r:g}\n{k}" for a, r, k in keys], fontsize=7)
    ax.set_ylabel(f"both talkers within {HIT_DEG:g} deg (%)")
    ax.set_title("Two talkers, one walking")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, default=10, help="recordings per array, room and "
                    "signal kind")
    ap.add_argument("--seed", type=int, default=280)
    ap.add_argument("--data", default=None, help="the shared data folder (for CMU ARCTIC; "
                    "default ../shared/data; skipped without it)")
    ap.add_argument("--no-write", action="store_true", help="print only (dev runs)")
    args = ap.parse_args(argv)
    speech = arctic_files(shared_data_dir(args.data))
    t_wall = time.time()
    with threadpool_limits(1):  # (as bench/sources.py)
        err, n_tracks, _ = run(args.trials, args.seed, speech)
        alone = run_alone(args.trials, args.seed, speech)
        x_err, x_tracks, x_kept = run(args.trials, args.seed, speech, crossing=True)
    headers, rows = tables(err, n_tracks)
    print_table("Two talkers, one walking: both found (%) / median matched error (deg)",
                headers, rows)
    print(wins(err, n_tracks))
    x_headers, x_rows = tables(x_err, x_tracks, x_kept)
    print_table("Two talkers, the walker crossing the other's direction: both found (%) / "
                "median matched error (deg), moments 30+ deg apart", x_headers, x_rows)
    print(wins(x_err, x_tracks))
    print(kept_line(x_kept))
    a_headers, a_rows = alone_table(alone)
    print_table("One talker walking alone: hearsee's tracks and stream (told at most two)",
                a_headers,
                a_rows)
    if args.no_write:
        return 0
    RESULTS.mkdir(parents=True, exist_ok=True)
    png = RESULTS / "moving_sources.png"
    plot(err, n_tracks, png)
    data = "CMU ARCTIC from the shared data" if speech else "no shared data: voices only"
    out = write_markdown("moving_sources", [
        ("Two talkers, one walking", markdown_table(headers, rows) + "\n\n"
         f"{wins(err, n_tracks)}. Each cell: `--trials` {args.trials} recordings x "
         f"{len(TIMES_S)} moments; seed {args.seed}; {data}. Plot: {png.name}. Wall time "
         f"{time.time() - t_wall:.0f} s."),
        ("Two talkers, the walker crossing the other's direction",
         markdown_table(x_headers, x_rows) + "\n\n"
         f"{wins(x_err, x_tracks)}. The walker crosses the still talker's line of sight at "
         f"t = {DURATION_S / 2:g} s, 0.5-1.5 m nearer or farther than it "
         "(`crossing_scene`); scored at the moments the two are at least "
         f"{MIN_APART_DEG:g} deg apart, as the other scenes keep them ('recordings x "
         "moments' counts those). Each cell: `--trials` "
         f"{args.trials} recordings, their own random numbers.\n\n"
         "Identity (the last columns): at each scored moment the track (offline: the "
         "source in `localize_recording`'s document; stream: the reported `id`) nearest each "
         f"talker within {HIT_DEG:g} deg; over every pair of moments, one before the crossing "
         "and one after, at which a talker was found both times, the share where it was "
         "found under the same identity (pairs counted in brackets). A tracker that swaps the "
         "two talkers at the crossing, or loses the walker and starts a new track, scores "
         "low. The peers' blocks name no identities. "
         f"{kept_line(x_kept)}."),
        ("One talker walking alone", markdown_table(a_headers, a_rows) + "\n\n"
         "The same scenes without the still talker (their own random numbers): at each moment, "
         "whether hearsee's tracks alive then (or the talkers its stream reported by then) are "
         "one, within 10 deg of the walker, or two "
         "(a false second source), or none."),
    ], intro=__doc__.split("\n\n")[0])
    print(f"wrote {out} and {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
