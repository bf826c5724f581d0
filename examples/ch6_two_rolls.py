"""Thesis ch. 6, figs. 6.6-6.9 regenerated (reconstruction): two rolls, LLE vs NLE vs CNLE.

    python examples/ch6_two_rolls.py [--out DIR]      # default examples/out/

Two swiss-roll sheets wound together, one six times denser than the other
(``hearsee.learn.make_two_rolls``, 2000 points, noise 0.1,
2 % outliers between the sheets). Writes ``ch6_two_rolls_data.png`` (fig. 6.7),
``ch6_two_rolls_embeddings.png`` (LLE and NLE mix the sheets, fig. 6.8; CNLE separates them and
unrolls each, fig. 6.9) and ``ch6_two_rolls_sweep.png`` (k-means ARI of LLE for K = 5, 10, ... up to
30 vs CNLE's clusters).
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from sklearn.cluster import KMeans  # noqa: E402
from sklearn.manifold import LocallyLinearEmbedding  # noqa: E402
from sklearn.metrics import adjusted_rand_score  # noqa: E402

from hearsee.learn import ClusteredNLE, NeighborhoodLinearEmbedding, make_two_rolls  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "out",
                    help="output folder (default: examples/out)")
    out = ap.parse_args(argv).out
    out.mkdir(parents=True, exist_ok=True)
    X, lab, t = make_two_rolls(2000, noise=0.1, outliers=0.02, random_state=0)
    good = lab >= 0
    colours = np.array(["tab:blue", "tab:orange", "lightgrey"])[np.where(lab < 0, 2, lab)]

    fig = plt.figure(figsize=(6, 5))
    ax = fig.add_subplot(projection="3d")
    ax.scatter(X[:, 0], X[:, 1], X[:, 2], c=colours, s=3)
    ax.set_title("two rolls: sheet 0 (blue), sheet 1 (orange), outliers (grey)")
    fig.tight_layout()
    fig.savefig(out / "ch6_two_rolls_data.png", dpi=110)
    plt.close(fig)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        Y_lle = LocallyLinearEmbedding(n_neighbors=12, n_components=2, eigen_solver="arpack",
                                       random_state=0).fit_transform(X)
        Y_nle = NeighborhoodLinearEmbedding(2, random_state=0).fit_transform(X)
    cnle = ClusteredNLE(2, random_state=0).fit(X)
    ari = adjusted_rand_score(lab[good], cnle.labels_[good])

    fig, axes = plt.subplots(1, 2 + cnle.n_clusters_, figsize=(5 * (2 + cnle.n_clusters_), 4.5))
    for ax, Y, name in ((axes[0], Y_lle, "LLE, K = 12"), (axes[1], Y_nle, "NLE")):
        ax.scatter(Y[:, 0], Y[:, 1], c=colours, s=3)
        ax.set_title(f"{name}: sheets mixed")
    for c in range(cnle.n_clusters_):
        m = cnle.labels_ == c
        ax = axes[2 + c]
        col = np.where(lab[m] >= 0, t[m, 0], np.nan)
        ax.scatter(*cnle.embedding_[m].T, c=col, s=3, cmap="Spectral")
        ax.set_title(f"CNLE cluster {c} ({m.sum()} pts), colour = arc length")
    fig.suptitle(f"CNLE: {cnle.n_clusters_} clusters, ARI vs the true sheets {ari:.4f}")
    fig.tight_layout()
    fig.savefig(out / "ch6_two_rolls_embeddings.png", dpi=110)
    plt.close(fig)

    ks = list(range(5, 31, 5))
    aris = []
    for k in ks:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            Y = LocallyLinearEmbedding(n_neighbors=k, n_components=2, eigen_solver="arpack",
                                       random_state=0).fit_transform(X)
        pred = KMeans(2, n_init=10, random_state=0).fit_predict(Y)
        aris.append(adjusted_rand_score(lab[good], pred[good]))
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(ks, aris, "o-", label="LLE (fixed K) + k-means")
    ax.axhline(ari, color="tab:green", label="CNLE (adaptive neighbourhoods)")
    ax.set_xlabel("K")
    ax.set_ylabel("ARI vs the true sheets")
    ax.set_ylim(-0.1, 1.05)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "ch6_two_rolls_sweep.png", dpi=110)
    plt.close(fig)
    print(f"CNLE ARI {ari:.4f}; LLE ARI for K={ks}: {np.round(aris, 3).tolist()}")
    print(f"wrote figures to {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
