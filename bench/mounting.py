"""Benchmark: how a wrongly measured camera mounting moves the camera-ray + ITD fixes (issue 5).

The 3D fixes of :func:`hearsee.fusion.audiovisual.locate_on_ray` take their range along the
camera ray from the parallax between the camera and the microphone array, so the camera's
position and pan on the head (``hearsee track --camera-at / --camera-pan``) enter every fix.
This script renders walks as ``bench/tracking.py`` part B does (three-mic preset, camera 0.2 m
or 0.5 m to its side, a room 7 x 6 x 3 m with RT60 0.3 s or free field, talkers 0.5-2 m away
in the camera's view at 0.5-1 m/s, 2 s walks, image points = true projection + 1 px noise),
measures per-frame GCC-PHAT TDOAs once, and fuses the same TDOAs and pixels with the TRUE
mounting and with mountings told wrong by a few centimetres or degrees. Per told mounting:
the median 3D error of the fixes that pass the ITD-closure test (0.5 sample, as the stream),
the median RMS ITD residual of all fixes (samples), and the share of fixes that test rejects.

The question is whether a wrong mounting can be told from the audio: it cannot, unless it is
gross. A planar array measures the azimuth (and little else), and a wrong ray still crosses
the measured azimuth somewhere, so the residual hardly moves while the fix slides along the
ray. No peer fuses microphones with a camera, so there is no side-by-side column.

Run: ``.venv/bin/python bench/mounting.py [--walks N] [--seed S]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import RESULTS, markdown_table, print_table, write_markdown  # noqa: E402
from tracking import ARRAY_AT, FS, ROOM, RT60, _signal, view_walk  # noqa: E402

from hearsee.audio.arrays import MicArray  # noqa: E402
from hearsee.audio.tdoa import estimate_tdoas  # noqa: E402
from hearsee.fusion.audiovisual import AudioVisualRig, locate_on_ray  # noqa: E402
from hearsee.sim.moving import simulate_moving_free_field, simulate_moving_room  # noqa: E402
from hearsee.vision.camera import Camera  # noqa: E402

#: (label, position error (m, array frame), pan error (deg)) of the told mountings
ERRORS = [("correct", (0.0, 0.0, 0.0), 0.0),
          ("y +5 cm", (0.0, 0.05, 0.0), 0.0), ("y -5 cm", (0.0, -0.05, 0.0), 0.0),
          ("y +10 cm", (0.0, 0.10, 0.0), 0.0), ("y +30 cm", (0.0, 0.30, 0.0), 0.0),
          ("y -30 cm", (0.0, -0.30, 0.0), 0.0), ("x +10 cm", (0.10, 0.0, 0.0), 0.0),
          ("x +30 cm", (0.30, 0.0, 0.0), 0.0), ("z +10 cm", (0.0, 0.0, 0.10), 0.0),
          ("pan +5 deg", (0.0, 0.0, 0.0), 5.0), ("pan -5 deg", (0.0, 0.0, 0.0), -5.0),
          ("pan +10 deg", (0.0, 0.0, 0.0), 10.0), ("pan -10 deg", (0.0, 0.0, 0.0), -10.0)]
#: (camera offset beside the array (m), signal, SNR dB, room?) per condition
CONDITIONS = [(0.2, "male", 20.0, True), (0.2, "female", 20.0, True),
              (0.2, "noise", 20.0, True), (0.2, "male", 10.0, True),
              (0.2, "male", 20.0, False), (0.5, "male", 20.0, True),
              (0.5, "noise", 20.0, True)]
MAX_RESIDUAL_SAMPLES = 0.5
HEAD = ["camera aside m", "signal", "SNR dB", "field", "told mounting", "fixes",
        "fix median error m", "median ITD residual samples", "fixes rejected %"]


def condition(aside: float, kind: str, snr: float, room: bool, walks: int,
              rng: np.random.Generator) -> list[list]:
    """Rows of one condition: every told mounting on the same walks, TDOAs and pixels."""
    cam = Camera.from_fov(70.0, 640, 480)
    arr = MicArray.from_preset("three-mic")
    true = AudioVisualRig.mounted(arr, cam, (0.0, aside, 0.0))
    told = [AudioVisualRig.mounted(arr, cam, np.add((0.0, aside, 0.0), dp), pan)
            for _, dp, pan in ERRORS]
    res: list[list[float]] = [[] for _ in ERRORS]
    err: list[list[float]] = [[] for _ in ERRORS]
    for _ in range(walks):
        traj = view_walk(rng, true, 2.0)
        x = _signal(kind, 2.0, rng, FS)
        if room:
            # (the renderer's defaults: early reflections updated every 5 ms; before
            # 2026-11-27 this benchmark rendered whole responses every 0.1 s, early_order=None,
            # which doubled each reflection -- see simulate_moving_room)
            y = simulate_moving_room(x, FS, arr, traj, ROOM, RT60, ARRAY_AT, snr_db=snr,
                                     rng=rng, block_s=0.1)
        else:
            y = simulate_moving_free_field(x, FS, arr, traj, snr_db=snr, rng=rng)
        tf = estimate_tdoas(y, FS, arr, 64.0, 16.0, "phat", refine="interp",
                            min_confidence=1.0)
        for t, z in zip(tf.t, tf.tdoa_s, strict=True):
            if not np.all(np.isfinite(z)):
                continue
            # the camera sees the talker where they are now (audio: r / c earlier, <= 6 ms)
            p = traj.at(float(t))
            uv = true.project(p)[0] + rng.standard_normal(2)
            for k, rig in enumerate(told):
                fix = locate_on_ray(rig, uv, z, range_m=(0.2, 4.0))
                r = fix.residual_s * FS
                res[k].append(r)
                if r <= MAX_RESIDUAL_SAMPLES:
                    err[k].append(float(np.linalg.norm(fix.position_m - p)))
    field = "room" if room else "free field"
    return [[aside, kind, snr, field, label, len(r), float(np.median(e)) if e else np.nan,
             float(np.median(r)), 100.0 * float(np.mean(np.asarray(r) > MAX_RESIDUAL_SAMPLES))]
            for (label, _, _), r, e in zip(ERRORS, res, err, strict=True)]


def plot(rows: list[list], path: Path) -> None:
    """Fix error and ITD residual per told mounting, one line per condition."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [e[0] for e in ERRORS]
    fig, ax = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    for i in range(0, len(rows), len(ERRORS)):
        block = rows[i:i + len(ERRORS)]
        name = f"{block[0][0]} m aside, {block[0][1]} {block[0][2]:.0f} dB, {block[0][3]}"
        ax[0].plot(labels, [r[6] for r in block], "o-", label=name)
        ax[1].plot(labels, [r[7] for r in block], "o-", label=name)
    ax[0].set(yscale="log", ylabel="fix median error [m]",
              title="camera-ray + ITD fixes with the camera mounting told wrong")
    ax[1].axhline(MAX_RESIDUAL_SAMPLES, color="k", ls="--", lw=1, label="rejection threshold")
    ax[1].set(ylabel="median ITD residual [samples]", xlabel="told mounting")
    ax[0].legend(fontsize=7)
    ax[1].legend(fontsize=7)
    plt.setp(ax[1].get_xticklabels(), rotation=30, ha="right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--walks", type=int, default=8, help="walks per condition")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    t0 = time.time()
    rng = np.random.default_rng(args.seed)
    rows = [row for c in CONDITIONS for row in condition(*c, args.walks, rng)]
    print_table("camera mounting told wrong: camera-ray + ITD fixes", HEAD, rows)
    RESULTS.mkdir(parents=True, exist_ok=True)
    png = RESULTS / "mounting.png"
    plot(rows, png)
    intro = (f"`python bench/mounting.py --walks {args.walks} --seed {args.seed}`; wall time "
             f"{time.time() - t0:.0f} s. ![mounting](mounting.png)\n\n"
             + __doc__.split("\n\n", 1)[1])
    write_markdown("mounting", [("Fixes with the mounting told wrong",
                                 markdown_table(HEAD, rows))], intro=intro)
    print(f"wrote {RESULTS / 'mounting.md'} and {png}")


if __name__ == "__main__":
    main()
