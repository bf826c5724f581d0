"""Benchmark: localization through mains hum picked up by the wiring, hearsee (its hum filter
on and off) and pyroomacoustics SRP-PHAT side by side on the same recordings.

Mains hum that a ground loop puts on every channel (``hearsee.audio.signals.mains_hum``: 50 or
60 Hz and every harmonic up to 2.5 kHz, one waveform on every channel) is a coherent source at
TDOA 0 on every pair. Recordings: the two-mic, three-mic and respeaker-6 presets; a synthetic
male or female voice or white noise, 3 s, 1.2-2 m away at a random azimuth (elevation 0-17
deg); free field or a 6 x 5 x 3 m room of RT60 0.3 s; sensor noise at 20 dB; hum at -10, 0, +6
dB relative to the signal or none (``simulate_recording(hum_db=, hum_hz=)``; the fundamental
50 or 60 Hz by turns). Scored: the whole-recording azimuth against the truth (two-mic modulo
front/back); a recording without an answer counts as 90 deg (two-mic) or 180 deg off.

hearsee: ``hearsee.audio.localize.localize_recording`` as ``hearsee localize`` runs it (its
filter: ``hearsee.audio.hum``), and the same with ``tonal_noise=False`` (the recording as it
is). Peer: pyroomacoustics SRP-PHAT as bench/doa.py runs it (``pra_azimuth``: 1-deg grid in
the array plane, 300-3500 Hz for voices, 300-7500 Hz for noise).

Also reported: how many hum-free recordings hearsee found hum in (false warnings).

The default seed (21) is not held out: its first run showed the filter's last two changes
(``hearsee.audio.hum``: a found hum's other harmonics from the spectrum's peaks; the
recording extended by whole hum periods so the notches settle before it starts). The form
they gave was then judged on a fresh seed (13): within 5 deg of the hum-free answer in 108 of
108 recordings with hum at 0-6 dB, 58 without the filter.

Usage: python bench/hum.py [--trials 4] [--seed 21]
"""

from __future__ import annotations

import argparse
import itertools
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import RESULTS, markdown_table, print_table, write_markdown  # noqa: E402
from doa import BANDS, az_error, pra_azimuth  # noqa: E402

from hearsee.audio.arrays import MicArray  # noqa: E402
from hearsee.audio.localize import localize_recording  # noqa: E402
from hearsee.errors import TonalNoiseWarning  # noqa: E402
from hearsee.sim.audio import simulate_recording  # noqa: E402

FS = 16000
ARRAYS = ("two-mic", "three-mic", "respeaker-6")
SIGNALS = ("male", "female", "noise")
ROOMS = (None, 0.3)
HUM_DB = (None, -10.0, 0.0, 6.0)
METHODS = ("hearsee", "hearsee, no hum filter", "SRP-PHAT")
ROOM = {"room_dim": [6.0, 5.0, 3.0], "array_at": [3.0, 2.5, 1.2]}


def hearsee_azimuth(x: np.ndarray, arr: MicArray, tonal_noise: bool) -> tuple[float | None, bool]:
    """(``hearsee localize``'s summary azimuth or None, whether it warned of hum)."""
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        doc = localize_recording(x, FS, arr, tonal_noise=tonal_noise)
    warned = any(issubclass(w.category, TonalNoiseWarning) for w in got)
    return doc["summary"]["azimuth_deg"], warned


def run(trials: int, seed: int) -> tuple[dict, dict]:
    """Errors (deg) per (array, hum level, method) and hum warnings per (array, hum level)."""
    rng = np.random.default_rng(seed)
    err: dict = {}
    warned: dict = {}
    for array, sig, rt60 in itertools.product(ARRAYS, SIGNALS, ROOMS):
        arr = MicArray.from_preset(array)
        two = arr.n_mics == 2
        band = BANDS["noise" if sig == "noise" else "speech"]
        for k in range(trials):
            az = rng.uniform(-180.0, 180.0)
            src = rng.uniform(1.2, 2.0) * np.array([np.cos(np.radians(az)),
                                                     np.sin(np.radians(az)),
                                                     rng.uniform(0.0, 0.3)])
            room = None if rt60 is None else {**ROOM, "rt60": rt60}
            sim_seed = int(rng.integers(2**31))
            for db in HUM_DB:
                x, truth = simulate_recording(arr, src, signal=sig, duration_s=3.0, fs=FS,
                                              snr_db=20, room=room, seed=sim_seed, hum_db=db,
                                              hum_hz=(50.0, 60.0)[k % 2])
                key = (array, db)
                a_on, w = hearsee_azimuth(x, arr, True)
                a_off, _ = hearsee_azimuth(x, arr, False)
                a_srp = pra_azimuth(x, FS, arr, "SRP", band)
                for m, a in zip(METHODS, (a_on, a_off, a_srp), strict=True):
                    err.setdefault((array, db, m), []).append(
                        az_error(a, truth["azimuth_deg"], two))
                warned.setdefault(key, []).append(w)
        print(f"  {array} {sig} RT60 {rt60}: done", flush=True)
    return err, warned


def tables(err: dict, warned: dict, trials: int) -> tuple[list, list]:
    headers = ["array", "hum dB", "n", "hum found %",
               *(f"{m}: median / >10 deg %" for m in METHODS)]
    rows = []
    for array, db in itertools.product(ARRAYS, HUM_DB):
        w = np.array(warned[(array, db)])
        cells = []
        for m in METHODS:
            e = np.array(err[(array, db, m)])
            cells.append(f"{np.median(e):.2f} / {100 * np.mean(e > 10):.0f}")
        rows.append([array, "none" if db is None else f"{db:+g}", len(w),
                     f"{100 * w.mean():.0f}", *cells])
    return headers, rows


def plot(err: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(ARRAYS), figsize=(4 * len(ARRAYS), 3.4), sharey=True)
    levels = np.arange(len(HUM_DB))
    for ax, array in zip(axes, ARRAYS, strict=True):
        for m, mk in zip(METHODS, "os^", strict=True):
            share = [100 * np.mean(np.array(err[(array, db, m)]) > 10) for db in HUM_DB]
            ax.plot(levels, share, marker=mk, label=m)
        ax.set_xticks(levels, ["none" if d is None else f"{d:+g} dB" for d in HUM_DB])
        ax.set_title(array)
        ax.set_xlabel("mains hum relative to the signal")
    axes[0].set_ylabel("errors > 10 deg (%)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, default=4, help="recordings per array, signal and "
                    "room (each heard with every hum level)")
    ap.add_argument("--seed", type=int, default=21)
    args = ap.parse_args(argv)
    err, warned = run(args.trials, args.seed)
    headers, rows = tables(err, warned, args.trials)
    print_table("Azimuth error through mains hum (deg)", headers, rows)
    RESULTS.mkdir(parents=True, exist_ok=True)
    png = RESULTS / "hum.png"
    plot(err, png)
    false = sum(sum(warned[(a, None)]) for a in ARRAYS)
    n_clean = sum(len(warned[(a, None)]) for a in ARRAYS)
    out = write_markdown("hum", [
        ("Azimuth error through mains hum", markdown_table(headers, rows) + "\n\n"
         f"Hum found in {false} of {n_clean} hum-free recordings (false warnings). "
         f"Seed {args.seed}, {args.trials} recordings per array, signal and room; each cell "
         f"pools {len(SIGNALS) * len(ROOMS) * args.trials} recordings. Plot: {png.name}."),
    ], intro=__doc__.split("\n\n")[0])
    print(f"wrote {out} and {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
