"""Benchmark: two talkers at once, hearsee (``hearsee localize --sources 2``) and
pyroomacoustics' SRP-PHAT, MUSIC and NormMUSIC side by side on the same recordings.

Recordings: the three-mic and two-mic presets; two talkers 1-2.5 m away in the array plane at
random azimuths at least 30 deg apart (two-mic: 30 deg apart in angle from the pair's
broadside, what a pair can tell), each a synthetic male and female voice
(``signals.synthetic_voice``: speech-like, with pauses) or, with the shared data, two CMU
ARCTIC utterances of different speakers; 3 s; free field or bench/doa.py's 8 x 7 x 3 m room
at RT60 0.3 / 0.6 s (pyroomacoustics' image sources, ``simulate_recording``); white sensor
noise 20 dB below the mixture. Also one-talker recordings made the same way, to count how often
hearsee names a second, false source.

hearsee: ``localize_recording(kalman=False, max_sources=2, band_hz=(300, 3500))`` -- it is told
at most two, and decides how many (``hearsee.audio.sources``). Peers: pyroomacoustics'
DOA methods told that there are two (``num_src=2``), given what bench/doa.py gives them (1024-
sample Hann STFT at 50 % overlap, the same band, the array plane (``dim=2``), in-plane points
2 m away for the triangle and far-field steering for the pair, whose grid is its front half:
a pair's response is the same at an azimuth and at its mirror) on a 0.5-deg grid; MUSIC and
NormMUSIC only where there are more microphones than talkers (``peer_applies``: the pair's
noise subspace is empty -- "n/a"; until 2026-12-07 their meaningless answers were scored,
0-7 % both found). Scored:
both talkers found within 10 deg (the estimates matched to the talkers so that the larger
error is smallest; two-mic angles from broadside, modulo front/back) and the matched errors'
median; a talker without an estimate counts as 180 deg off (90 for the pair). CPU: process
time per second of audio, hearsee's whole ``localize_recording`` against SRP-PHAT's STFT and
search.

The default seed (260) was not used to build or tune ``hearsee.audio.sources``: its choices
were made on dev seeds 254-257 and 261-265 (``DEFAULT_MIN_SHARE``, ``_from_broadside``,
``sources_from_spectra``); it was re-run after each change to the module that day.

Usage: python bench/sources.py [--trials 12] [--seed 260] [--data ../shared/data]
"""

from __future__ import annotations

import argparse
import itertools
import re
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

from hearsee.audio.arrays import MicArray  # noqa: E402
from hearsee.audio.localize import localize_recording  # noqa: E402
from hearsee.audio.propagation import add_noise  # noqa: E402
from hearsee.sim.audio import simulate_recording  # noqa: E402

FS = 16000
ARRAYS = ("three-mic", "two-mic")
RT60S = (0.0, 0.3, 0.6)
PEERS = ("SRP", "MUSIC", "NormMUSIC")
METHODS = ("hearsee", *PEERS)
BAND = (300.0, 3500.0)
DURATION_S = 3.0
SNR_DB = 20.0
HIT_DEG = 10.0
MIN_APART_DEG = 30.0
GRID_DEG = 0.5


def broadside(az: float) -> float:
    """A y-axis pair's angle from broadside (deg) of azimuth ``az``: front/back folded."""
    return float(np.degrees(np.arcsin(np.clip(np.sin(np.radians(az)), -1.0, 1.0))))


def angle_error(est: float | None, true: float, two: bool) -> float:
    if est is None or not np.isfinite(est):
        return 90.0 if two else 180.0
    if two:
        return abs(broadside(est) - broadside(true))
    return abs((est - true + 180.0) % 360.0 - 180.0)


def matched_errors(est: list[float], truth: list[float], two: bool) -> list[float]:
    """Errors of ``est`` matched to the talkers ``truth``: the assignment whose larger error is
    smallest (a missing estimate counts as a miss)."""
    est = list(est) + [None] * (len(truth) - len(est))
    best = None
    for perm in itertools.permutations(range(len(est)), len(truth)):
        e = [angle_error(est[p], t, two) for p, t in zip(perm, truth, strict=True)]
        if best is None or max(e) < max(best):
            best = e
    return best


def _speaker(p: Path) -> str:
    m = re.search(r"us_([a-z]+)_", p.name)
    return m.group(1) if m else p.stem


def talker_specs(kind: str, n: int, rng: np.random.Generator, speech: list[Path]
                 ) -> list[str | Path]:
    """``simulate_recording`` signals of ``n`` talkers: synthetic voices by turns, or ARCTIC
    utterances of different speakers (each file looped or trimmed to the duration and scaled
    to unit power, ``signals.make_signal``: talkers of equal level)."""
    if kind == "voices":
        return [("male", "female")[i % 2] for i in range(n)]
    speakers = sorted({_speaker(q) for q in speech})
    who = rng.choice(speakers, size=n, replace=len(speakers) < n)
    return [rng.choice([q for q in speech if _speaker(q) == w]) for w in who]


def room_spec(rt60: float) -> dict | None:
    """``simulate_recording``'s room: bench/doa.py's, at ``rt60`` seconds (0: free field)."""
    return None if rt60 == 0 else {"room_dim": list(ROOM), "rt60": rt60,
                                   "array_at": list(ARRAY_AT)}


def recording(arr: MicArray, azimuths: list[float], kind: str, rt60: float,
              rng: np.random.Generator, speech: list[Path]) -> np.ndarray:
    """The talkers at ``azimuths`` (deg, in the array plane, 1-2.5 m away), summed, with
    sensor noise :data:`SNR_DB` below the mixture."""
    room = room_spec(rt60)
    x = 0.0
    for az, spec in zip(azimuths, talker_specs(kind, len(azimuths), rng, speech), strict=True):
        d = rng.uniform(1.0, 2.5)
        src = [d * np.cos(np.radians(az)), d * np.sin(np.radians(az)), 0.0]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            y, _ = simulate_recording(arr, src, signal=spec, duration_s=DURATION_S, fs=FS,
                                      room=room, seed=int(rng.integers(2**31)))
        x = x + y
    return add_noise(x, SNR_DB, rng)


def talker_azimuths(n: int, two: bool, rng: np.random.Generator) -> list[float]:
    """``n`` random azimuths (deg) pairwise at least :data:`MIN_APART_DEG` apart (a pair:
    in angle from broadside)."""
    while True:
        az = list(rng.uniform(-180.0, 180.0, n))
        if all(angle_error(a, b, two) >= MIN_APART_DEG
               for a, b in itertools.combinations(az, 2)):
            return az


def run(trials: int, seed: int, speech: list[Path]) -> tuple[dict, dict, dict]:
    """Matched errors per (array, RT60, signal, n talkers, method), hearsee's source counts,
    and CPU seconds (hearsee, SRP) with the audio seconds."""
    rng = np.random.default_rng(seed)
    kinds = ["voices"] + (["arctic"] if speech else [])
    err: dict = {}
    found: dict = {}
    cpu = {"hearsee": 0.0, "SRP": 0.0, "audio_s": 0.0}
    for array, rt60, kind in itertools.product(ARRAYS, RT60S, kinds):
        arr = MicArray.from_preset(array)
        two = arr.n_mics == 2
        for n_talk, _ in itertools.product((2, 1), range(trials)):
            truth = talker_azimuths(n_talk, two, rng)
            x = recording(arr, truth, kind, rt60, rng, speech)
            t0 = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                doc = localize_recording(x, FS, arr, kalman=False, max_sources=2,
                                         band_hz=BAND)
            t1 = time.process_time()
            est = {"hearsee": [s["azimuth_deg"] for s in doc["sources"]]}
            found.setdefault((array, rt60, kind, n_talk), []).append(len(doc["sources"]))
            if n_talk == 2:
                cpu["hearsee"] += t1 - t0
                cpu["audio_s"] += x.shape[1] / FS
                for m in (m for m in PEERS if peer_applies(m, arr.n_mics, 2)):
                    t0 = time.process_time()
                    est[m] = pra_azimuths(x, FS, arr, m, BAND, 2, grid_deg=GRID_DEG,
                                          front_half=two)
                    if m == "SRP":
                        cpu["SRP"] += time.process_time() - t0
            for m, e in est.items():
                err.setdefault((array, rt60, kind, n_talk, m), []).append(
                    matched_errors(e, truth, two))
        print(f"  {array} RT60 {rt60} {kind}: done", flush=True)
    return err, found, cpu


def tables(err: dict, found: dict, trials: int) -> tuple[list, list, list, list]:
    headers = ["array", "RT60 s", "signals", "n",
               *(f"{m}: both within {HIT_DEG:g} deg % / median deg" for m in METHODS)]
    rows = []
    one_headers = ["array", "RT60 s", "signals", "n", "one source named %",
                   f"...and within {HIT_DEG:g} deg %", "two named %"]
    one_rows = []
    for array, rt60, kind in sorted({k[:3] for k in found}, key=lambda k: (
            ARRAYS.index(k[0]), k[1], k[2] != "voices")):
        cells = []
        for m in METHODS:
            if (array, rt60, kind, 2, m) not in err:  # (peer_applies: MUSIC on two mics)
                cells.append("n/a")
                continue
            e = np.array(err[(array, rt60, kind, 2, m)])
            cells.append(f"{100 * np.mean(e.max(axis=1) < HIT_DEG):.0f} / "
                         f"{np.median(e):.2f}")
        rows.append([array, rt60, kind, len(err[(array, rt60, kind, 2, 'hearsee')]), *cells])
        counts = np.array(found[(array, rt60, kind, 1)])
        e1 = np.array(err[(array, rt60, kind, 1, "hearsee")])[:, 0]
        one_rows.append([array, rt60, kind, len(counts), f"{100 * np.mean(counts == 1):.0f}",
                         f"{100 * np.mean((counts == 1) & (e1 < HIT_DEG)):.0f}",
                         f"{100 * np.mean(counts == 2):.0f}"])
    return headers, rows, one_headers, one_rows


def plot(err: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    kinds = sorted({k[2] for k in err}, key=lambda k: k != "voices")
    fig, axes = plt.subplots(1, len(ARRAYS), figsize=(5 * len(ARRAYS), 3.4), sharey=True)
    for ax, array in zip(axes, ARRAYS, strict=True):
        for m, mk in zip(METHODS, "os^v", strict=True):
            if (array, RT60S[0], kinds[0], 2, m) not in err:  # (n/a: peer_applies)
                continue
            for kind, ls in zip(kinds, ("-", "--"), strict=False):
                hit = [100 * np.mean(np.array(err[(array, rt, kind, 2, m)]).max(axis=1)
                                     < HIT_DEG) for rt in RT60S]
                ax.plot(RT60S, hit, marker=mk, ls=ls, label=f"{m} ({kind})")
        ax.set_title(f"{array}: two talkers")
        ax.set_xlabel("RT60 (s; 0 = free field)")
    axes[0].set_ylabel(f"both within {HIT_DEG:g} deg (%)")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, default=12, help="recordings per array, room, "
                    "signal kind and talker count")
    ap.add_argument("--seed", type=int, default=260)
    ap.add_argument("--data", default=None, help="the shared data folder (for CMU ARCTIC; "
                    "default ../shared/data; skipped without it)")
    args = ap.parse_args(argv)
    speech = arctic_files(shared_data_dir(args.data))
    t_wall = time.time()
    # one BLAS thread, as bench/doa.py: process CPU time also counted OpenBLAS's idle worker
    with threadpool_limits(1):
        err, found, cpu = run(args.trials, args.seed, speech)
    headers, rows, one_headers, one_rows = tables(err, found, args.trials)
    print_table("Two talkers: both found (%) / median matched error (deg)", headers, rows)
    print_table("One talker: what hearsee names (told at most two)", one_headers, one_rows)
    ms = {k: cpu[k] / cpu["audio_s"] * 1e3 for k in ("hearsee", "SRP")}
    cpu_line = (f"CPU per second of audio (two-talker recordings): hearsee "
                f"{ms['hearsee']:.2f} ms (its whole localize_recording), SRP-PHAT "
                f"{ms['SRP']:.2f} ms ({ms['SRP'] / ms['hearsee']:.1f}x hearsee's)")
    print(cpu_line)
    RESULTS.mkdir(parents=True, exist_ok=True)
    png = RESULTS / "sources.png"
    plot(err, png)
    out = write_markdown("sources", [
        ("Two talkers", markdown_table(headers, rows) + "\n\n"
         f"Each cell: `--trials` {args.trials} recordings; seed {args.seed}; "
         f"{'CMU ARCTIC from the shared data' if speech else 'no shared data: voices only'}. "
         f"Plot: {png.name}. Wall time {time.time() - t_wall:.0f} s."),
        ("One talker", markdown_table(one_headers, one_rows) + "\n\nThe peers are told "
         "how many talkers there are; hearsee is told at most two and decides."),
        ("CPU", cpu_line),
    ], intro=__doc__.split("\n\n")[0])
    print(f"wrote {out} and {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
