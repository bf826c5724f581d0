"""Thesis ch. 6, fig. 6.13 regenerated (reconstruction): NLE of a motion sequence.

    python examples/ch6_motion.py [--out DIR] [--video PATH]      # default examples/out/

Each frame (grey, downsampled to 36 x 48) is one point; NLE embeds the sequence in 2-D and the
path through the embedding, coloured by time, shows the motion's structure. Frames come from the
real pedestrian clip ``../shared/data/vision/pedestrian_video/vtest.avi`` when it is present
(``--video`` to name another file; one that OpenCV reads 12 or fewer distinct frames from is
skipped), and always from a generated sequence: a walker-like figure crossing the image with a
periodic leg swing, whose embedding should trace a drifting loop. Writes ``ch6_motion.png``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hearsee.learn import NeighborhoodLinearEmbedding  # noqa: E402

SHAPE = (36, 48)  # rows, cols
DEFAULT_VIDEO = (Path(__file__).resolve().parents[2] / "shared" / "data" / "vision"
                 / "pedestrian_video" / "vtest.avi")


def video_frames(path: Path, max_frames: int = 400) -> np.ndarray:
    """Grey frames of a video, downsampled to SHAPE, as rows of an array in [0, 1]."""
    import cv2

    cap = cv2.VideoCapture(str(path))
    frames = []
    while len(frames) < max_frames:
        ok, f = cap.read()
        if not ok:
            break
        g = cv2.cvtColor(f, cv2.COLOR_BGR2GRAY)
        frames.append(cv2.resize(g, SHAPE[::-1], interpolation=cv2.INTER_AREA).ravel() / 255.0)
    cap.release()
    return np.array(frames)


def walker_frames(n: int = 300, seed: int = 0) -> np.ndarray:
    """A stick figure walking left to right with a leg/arm swing period of 20 frames."""
    rs = np.random.default_rng(seed)
    rows, cols = SHAPE
    v, u = np.mgrid[0:rows, 0:cols]
    out = np.zeros((n, rows * cols))

    def segment(img, p, q, w=1.2):
        d = q - p
        s = np.clip(((u - p[0]) * d[0] + (v - p[1]) * d[1]) / (d @ d), 0, 1)
        dist = np.hypot(u - p[0] - s * d[0], v - p[1] - s * d[1])
        np.maximum(img, np.exp(-(dist / w) ** 2), out=img)

    for k in range(n):
        img = np.zeros(SHAPE)
        x = 6 + (cols - 12) * k / (n - 1)
        ph = 2 * np.pi * k / 20
        hip, neck = np.array([x, 22.0]), np.array([x, 12.0])
        segment(img, hip, neck)
        segment(img, neck + [0, -3], neck + [0, -3.5], w=2.2)  # head
        for sgn in (1, -1):
            segment(img, hip, hip + [6 * np.sin(ph) * sgn, 11.0])  # legs
            segment(img, neck, neck + [-4 * np.sin(ph) * sgn, 8.0])  # arms
        out[k] = img.ravel()
    return out + rs.normal(scale=0.01, size=out.shape)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description="NLE of a motion sequence (thesis fig. 6.13)")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "out"),
                    help="output folder (default: examples/out)")
    ap.add_argument("--video", default=str(DEFAULT_VIDEO))
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    video = Path(a.video)
    sets = []
    frames = video_frames(video) if video.is_file() else None
    n_distinct = 0 if frames is None or not len(frames) else len(np.unique(frames, axis=0))
    if n_distinct > 12:  # (NLE's 12 candidate neighbours)
        sets.append((f"video {video.name} (first {len(frames)} frames)", frames))
    elif frames is not None:  # (an unreadable file was NLE's ManifoldInputError traceback)
        print(f"{video}: {n_distinct} distinct frames read, too few for NLE: using the "
              "generated sequence only")
    else:
        print(f"{video} not found: using the generated sequence only")
    sets.append(("generated walker (300 frames)", walker_frames()))

    fig, axes = plt.subplots(len(sets), 2, figsize=(12, 5 * len(sets)), squeeze=False)
    for (name, F), ax in zip(sets, axes, strict=True):
        _, first = np.unique(F, axis=0, return_index=True)
        keep = np.sort(first)  # drop repeated (identical) frames, keep time order
        F = F[keep]
        Y = NeighborhoodLinearEmbedding(2, n_neighbors=12, random_state=0).fit_transform(F)
        sc = ax[0].scatter(Y[:, 0], Y[:, 1], c=keep, s=8, cmap="viridis")
        ax[0].plot(Y[:, 0], Y[:, 1], "-", lw=0.3, color="grey")
        fig.colorbar(sc, ax=ax[0], label="frame")
        ax[0].set_title(f"NLE of {name}")
        idx = np.linspace(0, len(F) - 1, 6).astype(int)
        ax[1].imshow(np.hstack([F[i].reshape(SHAPE) for i in idx]), cmap="gray")
        ax[1].set_title("frames " + ", ".join(str(int(keep[i])) for i in idx))
        ax[1].axis("off")
    fig.tight_layout()
    fig.savefig(out / "ch6_motion.png", dpi=100)
    plt.close(fig)
    print(f"wrote {out / 'ch6_motion.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
