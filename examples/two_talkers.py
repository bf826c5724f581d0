"""Two talkers, one walking: their directions tracked through a recording (an extension of
thesis ch. 2 and 5; :func:`hearsee.audio.sources.track_sources`).

    python examples/two_talkers.py [--out DIR] [--array three-mic|two-mic] [--seed N]

A male voice walks past the array at 0.8 m/s (from 2 m away at -70 deg), a female voice stands
1.5 m away at 120 deg; 6 s, free field, 20 dB (``sim.moving.simulate_moving_recording`` and
``sim.audio.simulate_recording``). ``localize_recording(max_sources=2, moving=True)`` -- what
``hearsee localize REC --array A --sources 2 --moving`` runs -- gives each talker a track; the
figure shows every frame's azimuth coloured by the track it joined (grey: none), each track's
path and the two talkers' true azimuths; and, as small crosses, the talkers that the stream
reported at each update (``hearsee track REC --array A --sources 2``,
``StreamConfig(max_sources=2)``: causal, what a robot listening live knows then). A pair's
azimuths are its front candidates (angles from its broadside; a talker behind it reads as its
mirror). Writes ``two_talkers.png``.
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hearsee.audio.localize import localize_recording  # noqa: E402
from hearsee.audio.propagation import add_noise  # noqa: E402
from hearsee.geometry import unit_vector_deg  # noqa: E402
from hearsee.sim.audio import simulate_recording  # noqa: E402
from hearsee.sim.moving import linear_trajectory, simulate_moving_recording  # noqa: E402
from hearsee.stream.pipeline import ArraySource, StreamConfig, StreamPipeline  # noqa: E402

FS = 16000
DURATION_S = 6.0
STILL_AZ_DEG = 120.0


def scene(array: str, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The recording, the frame-time grid (s) and the walker's true azimuth on it (deg)."""
    walk = linear_trajectory(2.0 * unit_vector_deg(-70.0, 0.0), [0.0, 0.8, 0.0], DURATION_S)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (the simulators' notes on clipping-free levels)
        xw, _ = simulate_moving_recording(array, walk, "male", DURATION_S, FS, seed=seed)
        xs, _ = simulate_recording(array, 1.5 * unit_vector_deg(STILL_AZ_DEG, 0.0),
                                   signal="female", duration_s=DURATION_S, fs=FS,
                                   seed=seed + 1)
    n = min(xw.shape[1], xs.shape[1])
    t = np.linspace(0.0, DURATION_S, 121)
    p = walk.heard_at(t)
    return add_noise(xw[:, :n] + xs[:, :n], 20.0, seed + 2), t, np.degrees(
        np.arctan2(p[:, 1], p[:, 0]))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "out")
    ap.add_argument("--array", default="three-mic", choices=["three-mic", "two-mic"])
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    x, t_true, walker = scene(args.array, args.seed)
    doc = localize_recording(x, FS, args.array, kalman=False, max_sources=2, moving=True,
                             band_hz=(300.0, 3500.0))
    two = args.array == "two-mic"

    def shown(az: np.ndarray) -> np.ndarray:  # (a pair sees angles from broadside)
        return np.degrees(np.arcsin(np.sin(np.radians(az)))) if two else np.asarray(az)

    fig, ax = plt.subplots(figsize=(8, 4.2))
    frames = [f for f in doc["frames"] if f["azimuth_deg"] is not None]
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k in [None, *range(len(doc["sources"]))]:
        fs = [f for f in frames if f["source"] == k]
        ax.scatter([f["t"] for f in fs], shown(np.array([f["azimuth_deg"] for f in fs])),
                   s=8, color="0.7" if k is None else colours[k % len(colours)],
                   label="frames, no track" if k is None else f"frames of track {k}")
    for k, src in enumerate(doc["sources"]):
        path = np.array([np.nan if a is None else a for a in src["path"]["azimuth_deg"]])
        ax.plot(src["path"]["t_s"], shown(path), color=colours[k % len(colours)], lw=2)
        print(f"track {k}: {src['t_start_s']:.2f}-{src['t_end_s']:.2f} s, {src['n_frames']} "
              f"frames, last heard at {src['azimuth_deg']:.1f} deg")
    ups: list = []
    StreamPipeline(args.array, StreamConfig(max_sources=2)).run(ArraySource(x, FS), ups.append)
    live = [(u.t, s["azimuth_deg"]) for u in ups for s in u.sources
            if s["azimuth_deg"] is not None]
    if live:
        lt, la = np.array(live).T
        ax.scatter(lt, shown(la), s=6, marker="x", color="k", lw=0.6,
                   label="stream's talkers (causal)")
    print(f"stream: {len(live)} talker reports over {len(ups)} updates, ids "
          f"{sorted({s['id'] for u in ups for s in u.sources})}")
    ax.plot(t_true, shown(walker), "k--", lw=1, label="walker (truth)")
    ax.plot(t_true, shown(np.full_like(t_true, STILL_AZ_DEG)), "k:", lw=1,
            label="still talker (truth)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("angle from broadside (deg)" if two else "azimuth (deg)")
    ax.set_title(f"Two talkers, one walking ({args.array}): hearsee localize --sources 2 "
                 "--moving")
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    args.out.mkdir(parents=True, exist_ok=True)
    png = args.out / "two_talkers.png"
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
