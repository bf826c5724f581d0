"""Benchmark: Neighborhood Linear Embedding (thesis ch. 6) vs scikit-learn's manifold learners.

Peers, all with K = 12 neighbours and 2 output dimensions, on the same inputs:
scikit-learn ``LocallyLinearEmbedding`` (standard, modified, hessian, ltsa; ``eigen_solver``
"dense" for the quality parts (n <= 2040) and "arpack" for the scaling runs -- "dense" cannot
hold n = 20,000; until 2026-11-24's seventh session ARPACK was used throughout, and it fails
where dense LAPACK does not: Hessian LLE and LTSA "failed" on the faces and the two rolls),
``Isomap`` and ``SpectralEmbedding``; hearsee's
``NeighborhoodLinearEmbedding`` (NLE, K = 12 candidates) and, on the two rolls, ``ClusteredNLE``
(CNLE, K = 8 candidates).

1. **Quality** at n = 2000 (``--quick``: 1000, two rolls always 2000) on the swiss roll (with
   and without noise), the S-curve, two rolls wound together (``make_two_rolls``: noise 0.1,
   2 % outliers between them) and
   the faces (the 100 faces of ``skimage.data.lfw_subset``, no ground-truth coordinate -- its
   other 100 images are not faces; until 2026-11-24's seventh session all 200 were used -- and 400
   rendered head-pose images with known yaw/pitch). Trustworthiness and continuity with k = 12
   (continuity = trustworthiness with the roles of input and embedding swapped), Spearman rank
   correlation between the true manifold coordinate (roll angle / arc length, yaw) and the best
   embedding axis, and on the two rolls the ARI of a clustering: k-means (k = 2) on the embedding
   for every method, CNLE's own ``labels_`` for CNLE (ARI over the non-outlier points). CNLE's
   per-cluster embeddings are laid side by side before the quality metrics; the rank correlation
   on the two rolls is per sheet, averaged.
2. **Two-rolls K sweep**: LLE with every fixed K in 5, 10, ..., 30: how many large components its
   K-NN graph has and the k-means ARI of its embedding, vs CNLE.
3. **Scaling** on the swiss roll at n = 2000, 5000, 20000, 100000: wall time of
   ``fit_transform`` and memory (a fresh subprocess per method and size: its peak resident set
   (``VmHWM``), and how much the fit raised it above the peak reached by the imports and the
   data), with trustworthiness / rank correlation on a random subsample of 2000 points
   (sklearn's trustworthiness is O(n^2)). Each run has a time limit (``--timeout``, default
   300 s); a method that timed out, or whose time at the previous size projects (linearly)
   beyond the limit, is skipped at the next size, and Isomap at n = 100,000 (a dense 80 GB
   geodesic matrix) is not run; the table says which.

Run ``python bench/nle.py`` (about 20 min on a shared 2-core machine) or ``--quick`` (2 min).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import RESULTS, markdown_table, print_table, write_markdown  # noqa: E402

K = 12
SUBSAMPLE = 2000
METHODS = ("nle", "lle", "mlle", "hlle", "ltsa", "isomap", "spectral")
LABEL = {
    "nle": "NLE (hearsee)", "cnle": "CNLE (hearsee)", "lle": "LLE standard",
    "mlle": "LLE modified", "hlle": "LLE hessian", "ltsa": "LTSA", "isomap": "Isomap",
    "spectral": "SpectralEmbedding",
}


# --------------------------------------------------------------------------- data and methods


def dataset(name: str, n: int, seed: int = 0):
    """(X, true coordinate (n,) or None, cluster labels or None)."""
    from sklearn.datasets import make_s_curve, make_swiss_roll

    from hearsee.learn import make_head_pose_images, make_two_rolls

    if name == "swiss":
        X, t = make_swiss_roll(n, random_state=seed)
        return X, t, None
    if name == "swiss_noise":
        X, t = make_swiss_roll(n, noise=0.5, random_state=seed)
        return X, t, None
    if name == "scurve":
        X, t = make_s_curve(n, random_state=seed)
        return X, t, None
    if name == "two_rolls":
        # always 2000 points: at 1000 the sheets are sampled too sparsely to be told apart
        X, lab, t = make_two_rolls(max(n, 2000), noise=0.1, outliers=0.02, random_state=seed)
        return X, t[:, 0], lab
    if name == "heads":
        X, pose = make_head_pose_images(min(n, 400), random_state=seed)
        return X, pose[:, 0], None
    if name == "lfw":
        from skimage.data import lfw_subset

        X = lfw_subset()[:100].reshape(100, -1).astype(float)  # the faces (then 100 non-faces)
        return X, None, None
    raise ValueError(name)


def make_method(name: str, n_neighbors: int = K, eigen_solver: str = "arpack"):
    from sklearn.manifold import Isomap, LocallyLinearEmbedding, SpectralEmbedding

    from hearsee.learn import ClusteredNLE, NeighborhoodLinearEmbedding

    lle = dict(n_neighbors=n_neighbors, n_components=2, eigen_solver=eigen_solver,
               random_state=0)
    return {
        "nle": lambda: NeighborhoodLinearEmbedding(2, n_neighbors=n_neighbors, random_state=0),
        "cnle": lambda: ClusteredNLE(2, random_state=0),
        "lle": lambda: LocallyLinearEmbedding(method="standard", **lle),
        "mlle": lambda: LocallyLinearEmbedding(method="modified", **lle),
        "hlle": lambda: LocallyLinearEmbedding(method="hessian", **lle),
        "ltsa": lambda: LocallyLinearEmbedding(method="ltsa", **lle),
        "isomap": lambda: Isomap(n_neighbors=n_neighbors, n_components=2),
        "spectral": lambda: SpectralEmbedding(2, n_neighbors=n_neighbors, random_state=0),
    }[name]()


# --------------------------------------------------------------------------- metrics


def continuity(X, Y, k=K):
    from sklearn.manifold import trustworthiness

    return trustworthiness(Y, X, n_neighbors=k)


def quality(X, Y, t, lab, rng, sub=SUBSAMPLE):
    """trustworthiness, continuity, rank correlation on (a subsample of) the points."""
    from scipy.stats import spearmanr
    from sklearn.manifold import trustworthiness

    idx = np.arange(len(X)) if len(X) <= sub else rng.choice(len(X), sub, replace=False)
    good = np.isfinite(Y).all(axis=1)
    if not good.all():
        return float("nan"), float("nan"), float("nan")
    T = trustworthiness(X[idx], Y[idx], n_neighbors=K)
    C = continuity(X[idx], Y[idx])
    rho = float("nan")
    if t is not None:
        if lab is None:
            rho = max(abs(spearmanr(Y[idx, j], t[idx])[0]) for j in range(Y.shape[1]))
        else:  # per manifold, then averaged
            rs = []
            for c in np.unique(lab[lab >= 0]):
                m = lab == c
                rs.append(max(abs(spearmanr(Y[m, j], t[m])[0]) for j in range(Y.shape[1])))
            rho = float(np.mean(rs))
    return T, C, rho


def side_by_side(Y, labels, margin=1.0):
    """CNLE's clusters share axes but not a frame: lay them out side by side along axis 0 (as
    one would plot separate components) before computing whole-set quality metrics."""
    Y = Y.copy()
    x = 0.0
    for c in np.unique(labels):
        m = labels == c
        Y[m, 0] += x - Y[m, 0].min()
        x = Y[m, 0].max() + margin * max(np.ptp(Y[m, 0]), 1e-9)
    return Y


def kmeans_ari(Y, lab):
    from sklearn.cluster import KMeans
    from sklearn.metrics import adjusted_rand_score

    pred = KMeans(2, n_init=10, random_state=0).fit_predict(Y)
    g = lab >= 0
    return adjusted_rand_score(lab[g], pred[g])


# --------------------------------------------------------------------------- parts


def part_quality(n: int, rng) -> tuple[list, list]:
    from sklearn.metrics import adjusted_rand_score

    rows = []
    names = ["swiss", "swiss_noise", "scurve", "two_rolls", "heads", "lfw"]
    for ds in names:
        X, t, lab = dataset(ds, n)
        for meth in METHODS + (("cnle",) if ds == "two_rolls" else ()):
            t0 = time.perf_counter()
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    est = make_method(meth, eigen_solver="dense").fit(X)
                    Y = est.embedding_
                    if meth == "cnle":
                        Y = side_by_side(Y, est.labels_)
            except Exception as exc:  # a peer that fails on this input: say so
                msg = f"{type(exc).__name__}: {str(exc).splitlines()[0][:60]}"
                rows.append([ds, LABEL[meth], len(X), "failed", "", "", "", "", msg])
                continue
            dt = time.perf_counter() - t0
            T, C, rho = quality(X, Y, t, lab, rng)
            ari = ""
            if lab is not None:
                ari = kmeans_ari(Y, lab)
                if meth == "cnle":
                    g = lab >= 0
                    ari = adjusted_rand_score(lab[g], est.labels_[g])
            rows.append([ds, LABEL[meth], len(X), T, C, rho, ari, dt, ""])
            print(f"  quality {ds:12s} {meth:9s} T={T:.4f} C={C:.4f} rho={rho:.3f} {dt:.1f}s",
                  flush=True)
    return rows, names


def part_sweep(n: int) -> list:
    from scipy.sparse.csgraph import connected_components
    from sklearn.manifold import LocallyLinearEmbedding
    from sklearn.metrics import adjusted_rand_score
    from sklearn.neighbors import kneighbors_graph

    from hearsee.learn import ClusteredNLE

    X, t, lab = dataset("two_rolls", n)  # 2000 + 40 outliers
    rows = []
    for k in (5, 10, 15, 20, 25, 30):
        G = kneighbors_graph(X, k)
        _, comp = connected_components(G + G.T)
        n_big = int((np.bincount(comp) >= 20).sum())
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            Y = LocallyLinearEmbedding(n_neighbors=k, n_components=2, eigen_solver="dense",
                                       random_state=0).fit_transform(X)
        rows.append([f"LLE K={k}", n_big, kmeans_ari(Y, lab)])
        print(f"  sweep K={k} components={n_big} ARI={rows[-1][2]:.3f}", flush=True)
    m = ClusteredNLE(random_state=0).fit(X)
    g = lab >= 0
    rows.append(["CNLE (K<=8 adaptive)", m.n_clusters_, adjusted_rand_score(lab[g], m.labels_[g])])
    return rows


def _peak_rss_mb() -> float:
    """Peak resident set of this process [MB]: VmHWM (reset by exec, unlike ru_maxrss, which a
    child started by fork + exec inherits from its parent), or ru_maxrss where /proc is absent."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return float(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _worker(meth: str, n: int) -> None:
    """Subprocess body: fit one method on the swiss roll, print a JSON line."""
    rng = np.random.default_rng(1)
    X, t, lab = dataset("swiss", n)
    est = make_method(meth)
    before = _peak_rss_mb()
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        Y = est.fit_transform(X)
    dt = time.perf_counter() - t0
    after = _peak_rss_mb()
    T, C, rho = quality(X, Y, t, None, rng)
    print(json.dumps({"time_s": dt, "rss_mb": after, "extra_mb": max(after - before, 0.0),
                      "T": T, "C": C, "rho": rho}))


SKIP = {  # (method, n) that cannot fit this machine: not run
    ("isomap", 100000): "O(n^2) memory: the dense 100000^2 geodesic matrix is 80 GB",
}


def _run_child(meth: str, n: int, timeout: float) -> dict:
    cmd = [sys.executable, __file__, "--worker", meth, str(n)]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                           env={**os.environ, "PYTHONWARNINGS": "ignore"})
    except subprocess.TimeoutExpired:
        return {"timeout": True}
    if p.returncode != 0:
        return {"error": (p.stderr.strip().splitlines() or ["?"])[-1][:80]}
    return json.loads(p.stdout.strip().splitlines()[-1])


def part_scaling(sizes, timeout: float) -> list:
    rows = []
    last: dict[str, tuple[int, float | None]] = {}  # method -> (n, time or None if timed out)
    for n in sizes:
        ref = None
        for meth in METHODS:
            reason = SKIP.get((meth, n))
            if reason is None and meth in last:
                n0, t0 = last[meth]
                if t0 is None:
                    reason = f"timed out at n = {n0}"
                elif t0 * n / n0 > timeout:  # at least linear growth
                    reason = f"projected > {t0 * n / n0:.0f} s (linear from {t0:.0f} s at n = {n0})"
            if reason is not None:
                rows.append([n, LABEL[meth], "skipped: " + reason, "", "", "", "", "", ""])
                continue
            r = _run_child(meth, n, timeout)
            last[meth] = (n, None if r.get("timeout") else r.get("time_s"))
            if r.get("timeout"):
                rows.append([n, LABEL[meth], f"timeout > {timeout:.0f} s", "", "", "", "", "", ""])
                print(f"  scaling n={n} {meth}: timeout", flush=True)
                continue
            if "error" in r:
                rows.append([n, LABEL[meth], "failed: " + r["error"], "", "", "", "", "", ""])
                print(f"  scaling n={n} {meth}: {r['error']}", flush=True)
                continue
            if meth == "nle":
                ref = r["time_s"]
            ratio = r["time_s"] / ref if ref else float("nan")
            rows.append([n, LABEL[meth], r["time_s"], ratio, r["extra_mb"], r["rss_mb"], r["T"],
                         r["C"], r["rho"]])
            print(f"  scaling n={n} {meth}: {r['time_s']:.1f}s +{r['extra_mb']:.0f} MB "
                  f"(peak {r['rss_mb']:.0f} MB) T={r['T']:.4f}", flush=True)
    return rows


def plot(qrows, srows, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5))
    ds_names = list(dict.fromkeys(r[0] for r in qrows))
    meths = list(dict.fromkeys(r[1] for r in qrows))
    w = 0.8 / len(meths)
    for j, m in enumerate(meths):
        vals = []
        for d in ds_names:
            v = [r[3] for r in qrows if r[0] == d and r[1] == m and isinstance(r[3], float)]
            vals.append(v[0] if v else np.nan)
        axes[0].bar(np.arange(len(ds_names)) + j * w, vals, w, label=m)
    axes[0].set_xticks(np.arange(len(ds_names)) + 0.4 - w / 2, ds_names, rotation=20)
    axes[0].set_ylim(0.6, 1.0)
    axes[0].set_ylabel("trustworthiness (k=12)")
    axes[0].legend(fontsize=7, ncol=2)
    for m in dict.fromkeys(r[1] for r in srows):
        pts = [(r[0], r[2]) for r in srows if r[1] == m and isinstance(r[2], float)]
        if pts:
            x, y = zip(*pts, strict=True)
            axes[1].loglog(x, y, "o-", label=m)
    axes[1].set_xlabel("n (swiss roll)")
    axes[1].set_ylabel("fit_transform wall time [s]")
    axes[1].legend(fontsize=7)
    axes[1].grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="n=1000 quality, sizes 2000 and 5000")
    ap.add_argument("--timeout", type=float, default=None, help="per-run time limit [s]")
    ap.add_argument("--worker", nargs=2, metavar=("METHOD", "N"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        _worker(a.worker[0], int(a.worker[1]))
        return 0
    t_start = time.perf_counter()
    rng = np.random.default_rng(0)
    n_q = 1000 if a.quick else 2000
    sizes = (2000, 5000) if a.quick else (2000, 5000, 20000, 100000)
    timeout = a.timeout or (60.0 if a.quick else 300.0)

    print("1. quality", flush=True)
    qrows, _ = part_quality(n_q, rng)
    qh = ["data", "method", "n", "trustworthiness", "continuity", "rank corr.", "ARI",
          "time [s]", "note"]
    print_table(f"NLE vs scikit-learn: quality (K = {K}, k = {K})", qh, qrows, 4)

    print("2. two-rolls K sweep", flush=True)
    wrows = part_sweep(n_q)
    wh = ["method", "large K-NN components (LLE) / clusters (CNLE)", "ARI"]
    print_table("Two rolls: LLE with fixed K vs CNLE", wh, wrows, 4)

    print("3. scaling", flush=True)
    srows = part_scaling(sizes, timeout)
    sh = ["n", "method", "time [s]", "time / NLE", "RSS growth in fit [MB]", "peak RSS [MB]",
          "trustworthiness (2000-pt subsample)", "continuity", "rank corr."]
    print_table("Swiss roll: time and memory", sh, srows, 4)

    RESULTS.mkdir(parents=True, exist_ok=True)
    png = RESULTS / "nle.png"
    plot(qrows, srows, png)
    total = time.perf_counter() - t_start
    md = write_markdown(
        "nle",
        [
            (f"Quality at n = {n_q} (faces: 400 rendered heads, 100 LFW faces)",
             markdown_table(qh, qrows, 4)),
            ("Two rolls: LLE with every fixed K vs CNLE", markdown_table(wh, wrows, 4)),
            ("Scaling on the swiss roll (subprocess per run)", markdown_table(sh, srows, 4)),
            ("Plot", f"![nle]({png.name})"),
        ],
        intro=(__doc__.split("\n\n", 1)[1].rsplit("\n\nRun", 1)[0]
               + f"\n\nMachine: {os.cpu_count()} cores (shared). Total run time {total:.0f} s"
               + (" (--quick)." if a.quick else ".")),
    )
    print(f"wrote {md} and {png} in {total:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
