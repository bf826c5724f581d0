"""Thesis ch. 6, figs. 6.2-6.5 regenerated (reconstruction): NLE on the swiss roll.

    python examples/ch6_swiss_roll.py [--out DIR]      # default examples/out/

Writes ``ch6_neighbourhood.png`` (the shadow rule for one point: accepted vs shadowed
candidates), ``ch6_swiss_roll.png`` (the data, NLE and LLE embeddings coloured by the roll
coordinate) and ``ch6_neighbour_counts.png`` (how many neighbours each point keeps).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from sklearn.datasets import make_swiss_roll  # noqa: E402
from sklearn.manifold import LocallyLinearEmbedding, trustworthiness  # noqa: E402
from sklearn.neighbors import NearestNeighbors  # noqa: E402

from hearsee.learn import NeighborhoodLinearEmbedding, adaptive_neighbors  # noqa: E402


def fig_neighbourhood(X: np.ndarray, out: Path, k: int = 12, shadow: float = 0.3) -> None:
    """Fig. 6.2: one point's K candidates, split by the shadow rule."""
    i = int(np.argmin(np.abs(X[:, 1] - 10.0) + np.abs(X[:, 0] - 5.0)))
    dist, ind = NearestNeighbors(n_neighbors=k + 1).fit(X).kneighbors(X[i : i + 1])
    dist, ind = dist[:, 1:], ind[:, 1:]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.5))
    for ax, sh in zip(axes, (shadow, 0.5), strict=True):
        mask = adaptive_neighbors(X, ind, dist, sh, min_neighbors=3, centers=X[i : i + 1])[0]
        # local 2-D frame of the neighbourhood (PCA)
        P = X[ind[0]] - X[i]
        _, _, vt = np.linalg.svd(P, full_matrices=False)
        q = P @ vt[:2].T
        ax.scatter(0, 0, c="k", s=80, marker="*", label="x_i")
        ax.scatter(*q[mask].T, c="tab:green", s=50, label=f"accepted ({mask.sum()})")
        ax.scatter(*q[~mask].T, c="tab:red", marker="x", s=50, label=f"shadowed ({(~mask).sum()})")
        for p in q[mask]:
            ax.plot([0, p[0]], [0, p[1]], "g-", lw=0.8)
        for r, p in enumerate(q):
            ax.annotate(str(r + 1), p, fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.set_aspect("equal")
        ax.set_title(f"shadow = {sh}: {k} candidates, numbered by distance", fontsize=10)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "ch6_neighbourhood.png", dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "out",
                    help="output folder (default: examples/out)")
    out = ap.parse_args(argv).out
    out.mkdir(parents=True, exist_ok=True)
    X, t = make_swiss_roll(2000, random_state=0)
    fig_neighbourhood(X, out)

    nle = NeighborhoodLinearEmbedding(2, n_neighbors=12, random_state=0)
    Y = nle.fit_transform(X)
    Yl = LocallyLinearEmbedding(n_neighbors=12, n_components=2, eigen_solver="arpack",
                                random_state=0).fit_transform(X)
    fig = plt.figure(figsize=(14, 4.5))
    ax = fig.add_subplot(1, 3, 1, projection="3d")
    ax.scatter(X[:, 0], X[:, 1], X[:, 2], c=t, s=4, cmap="Spectral")
    ax.set_title("swiss roll (n = 2000)")
    for j, (Z, name) in enumerate(((Y, "NLE"), (Yl, "LLE, K = 12")), start=2):
        ax = fig.add_subplot(1, 3, j)
        ax.scatter(Z[:, 0], Z[:, 1], c=t, s=4, cmap="Spectral")
        ax.set_title(f"{name}: trustworthiness {trustworthiness(X, Z, n_neighbors=12):.4f}")
    fig.tight_layout()
    fig.savefig(out / "ch6_swiss_roll.png", dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.hist(nle.n_neighbors_, bins=np.arange(2.5, 13.5), rwidth=0.85)
    ax.set_xlabel("accepted neighbours (of 12 candidates)")
    ax.set_ylabel("points")
    ax.set_title(f"NLE neighbourhood sizes, mean {nle.n_neighbors_.mean():.1f}")
    fig.tight_layout()
    fig.savefig(out / "ch6_neighbour_counts.png", dpi=110)
    plt.close(fig)
    print(f"wrote figures to {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
