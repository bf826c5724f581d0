"""Thesis ch. 6, fig. 6.10 regenerated (reconstruction): NLE on face images.

    python examples/ch6_faces.py [--out DIR]      # default examples/out/

Two sets: 400 rendered 32 x 32 images of a rotating head with known yaw and pitch
(``hearsee.learn.make_head_pose_images``; the thesis used a real face-pose sequence) and the 100
real 25 x 25 faces of ``skimage.data.lfw_subset()`` (its first 100 images; the other 100 are
non-face crops, which this example embedded with the faces until 2026-12-02). Writes
``ch6_head_pose.png`` (NLE embedding coloured by yaw and by pitch, with thumbnails) and
``ch6_lfw.png`` (the LFW faces placed at their NLE coordinates).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.offsetbox import AnnotationBbox, OffsetImage  # noqa: E402
from scipy.stats import spearmanr  # noqa: E402

from hearsee.learn import NeighborhoodLinearEmbedding, make_head_pose_images  # noqa: E402


def thumbnails(ax, Y, images, side, n_show=40, zoom=1.0, seed=0):
    """Draw up to ``n_show`` images at their embedded positions, spread out."""
    rng = np.random.default_rng(seed)
    shown: list[np.ndarray] = []
    span = np.ptp(Y, axis=0).max()
    for i in rng.permutation(len(Y)):
        if all(np.linalg.norm(Y[i] - s) > 0.12 * span for s in shown):
            shown.append(Y[i])
            box = OffsetImage(images[i].reshape(side, side), cmap="gray", zoom=zoom)
            ax.add_artist(AnnotationBbox(box, Y[i], frameon=False))
        if len(shown) >= n_show:
            break


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "out",
                    help="output folder (default: examples/out)")
    out = ap.parse_args(argv).out
    out.mkdir(parents=True, exist_ok=True)

    X, pose = make_head_pose_images(400, random_state=0)
    Y = NeighborhoodLinearEmbedding(2, n_neighbors=12, random_state=0).fit_transform(X)
    fig, axes = plt.subplots(1, 3, figsize=(16, 5))
    for ax, j, name in ((axes[0], 0, "yaw"), (axes[1], 1, "pitch")):
        rho = max(abs(spearmanr(Y[:, k], pose[:, j])[0]) for k in range(2))
        sc = ax.scatter(Y[:, 0], Y[:, 1], c=pose[:, j], s=10, cmap="coolwarm")
        fig.colorbar(sc, ax=ax, label=f"{name} [deg]")
        ax.set_title(f"NLE, colour = {name} (|rank corr.| {rho:.3f})", fontsize=10)
    axes[2].scatter(Y[:, 0], Y[:, 1], s=2, c="lightgrey")
    thumbnails(axes[2], Y, X, 32, zoom=1.0)
    axes[2].set_title("images at their NLE coordinates")
    fig.tight_layout()
    fig.savefig(out / "ch6_head_pose.png", dpi=100)
    plt.close(fig)

    from skimage.data import lfw_subset

    faces = lfw_subset()[:100].reshape(100, -1).astype(float)  # (then 100 non-faces)
    Yf = NeighborhoodLinearEmbedding(2, n_neighbors=12, random_state=0).fit_transform(faces)
    fig, ax = plt.subplots(figsize=(8, 7))
    ax.scatter(Yf[:, 0], Yf[:, 1], s=2, c="lightgrey")
    thumbnails(ax, Yf, faces, 25, n_show=60, zoom=1.2)
    ax.set_title("NLE of the 100 LFW faces of skimage.data.lfw_subset")
    fig.tight_layout()
    fig.savefig(out / "ch6_lfw.png", dpi=100)
    plt.close(fig)
    print(f"wrote figures to {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
