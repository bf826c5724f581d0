"""Tests of hearsee.learn.nle: NLE / CNLE estimators, the shadow rule, bad input."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.stats import spearmanr
from sklearn.datasets import make_s_curve, make_swiss_roll
from sklearn.manifold import trustworthiness
from sklearn.metrics import adjusted_rand_score
from sklearn.utils.estimator_checks import parametrize_with_checks

from hearsee.errors import ConfigError, HearseeError
from hearsee.learn import (
    ClusteredNLE,
    DisconnectedGraphWarning,
    ManifoldInputError,
    NeighborhoodLinearEmbedding,
    adaptive_neighbors,
    make_head_pose_images,
    make_two_rolls,
    reconstruction_weights,
)


def _expected_failed_checks(estimator):
    return {
        "check_positive_only_tag_during_fit": (
            "fits the iris data, which holds duplicate rows (101 and 142); NLE rejects duplicate "
            "points on purpose (their reconstruction weights are undefined)"
        ),
    }


# n_neighbors=5 and min_cluster_size=5: scikit-learn's checks fit data sets of 10 samples
@parametrize_with_checks(
    [
        NeighborhoodLinearEmbedding(n_neighbors=5, random_state=0),
        ClusteredNLE(n_neighbors=5, min_cluster_size=5, random_state=0),
    ],
    expected_failed_checks=_expected_failed_checks,
)
def test_sklearn_compatible(estimator, check):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DisconnectedGraphWarning)
        check(estimator)


# --------------------------------------------------------------------------- the shadow rule


def test_shadow_rule_drops_collinear_candidate():
    # center at 0; candidates at 1 and 2 on the same ray, and at -1.5 on the other side
    X = np.array([[0.0, 0.0], [1.0, 0.0], [1.5, 0.0], [-1.8, 0.0], [0.0, 3.0]])
    ind = np.array([[1, 2, 3, 4]])
    dist = np.linalg.norm(X[ind[0]] - X[0], axis=1)[None, :]
    mask = adaptive_neighbors(X, ind, dist, shadow=0.5, min_neighbors=1, centers=X[:1])
    # x=1.5 is shadowed by x=1 (|1.5-1| = 0.5 < 0.5 * 1.5); x=-1.8 and (0,3) open new directions
    np.testing.assert_array_equal(mask[0], [True, False, True, True])
    # shadow=0 keeps every candidate (plain LLE)
    assert adaptive_neighbors(X, ind, dist, 0.0, 1, centers=X[:1]).all()
    # min_neighbors adds back the nearest rejected candidate
    mask4 = adaptive_neighbors(X, ind, dist, shadow=0.5, min_neighbors=4, centers=X[:1])
    assert mask4.all()


def test_reconstruction_weights_sum_to_one_and_reconstruct_a_plane_point():
    rng = np.random.default_rng(0)
    nb = rng.normal(size=(6, 2))
    x = nb[:3].mean(axis=0)  # inside the convex hull of three neighbours
    X = np.vstack([x, nb])
    ind = np.arange(1, 7)[None, :]
    mask = np.zeros((1, 6), bool)
    mask[0, :3] = True
    W = reconstruction_weights(X, ind, mask, reg=1e-9, centers=X[:1])
    assert W[0, 3:].tolist() == [0.0, 0.0, 0.0]
    assert W.sum() == pytest.approx(1.0)
    np.testing.assert_allclose(W[0] @ X[1:], x, atol=1e-6)


def test_nle_picks_fewer_neighbours_than_candidates():
    X, _ = make_swiss_roll(400, random_state=1)
    m = NeighborhoodLinearEmbedding(n_neighbors=12, random_state=0).fit(X)
    assert m.n_neighbors_.min() >= 3
    assert m.n_neighbors_.mean() < 12
    assert m.adjacency_.shape == (400, 400)
    np.testing.assert_allclose(np.asarray(m.adjacency_.sum(axis=1)).ravel(), 1.0)


# --------------------------------------------------------------------------- embedding quality


@pytest.mark.parametrize("maker, k", [(make_swiss_roll, 8), (make_s_curve, 12)])
def test_nle_unrolls_the_manifold(maker, k):
    # 500 points undersample the swiss roll: K = 8 candidates (scikit-learn's LLE reaches
    # trustworthiness 0.87 here with K = 12)
    X, t = maker(500, random_state=0)
    Y = NeighborhoodLinearEmbedding(n_neighbors=k, random_state=0).fit_transform(X)
    assert Y.shape == (500, 2)
    np.testing.assert_allclose(Y.mean(axis=0), 0.0, atol=1e-6)
    rho = max(abs(spearmanr(Y[:, 0], t)[0]), abs(spearmanr(Y[:, 1], t)[0]))
    assert rho > 0.98
    assert trustworthiness(X, Y, n_neighbors=12) > 0.96


def test_axis_scaling():
    X, _ = make_s_curve(500, random_state=0)
    unit = NeighborhoodLinearEmbedding(axis_scaling="unit", random_state=0).fit(X)
    np.testing.assert_allclose(unit.embedding_.std(axis=0), 1.0, rtol=1e-6)
    edges = NeighborhoodLinearEmbedding(random_state=0).fit(X)
    # same directions, other scales
    ratio = edges.embedding_ / unit.embedding_
    np.testing.assert_allclose(ratio, np.broadcast_to(np.median(ratio, axis=0), ratio.shape),
                               rtol=1e-6)
    # neighbour distances come back in the units of X
    A = edges.adjacency_.tocoo()
    dx = np.linalg.norm(X[A.row] - X[A.col], axis=1)
    dy = np.linalg.norm(edges.embedding_[A.row] - edges.embedding_[A.col], axis=1)
    assert 0.8 < np.median(dy / dx) < 1.2


def test_dense_and_arpack_solvers_agree():
    X, _ = make_swiss_roll(300, random_state=0)
    Yd = NeighborhoodLinearEmbedding(eigen_solver="dense", random_state=0).fit_transform(X)
    Ya = NeighborhoodLinearEmbedding(eigen_solver="arpack", random_state=0).fit_transform(X)
    np.testing.assert_allclose(np.abs(Yd), np.abs(Ya), atol=1e-4)


def test_transform_new_points_lands_near_the_training_embedding():
    X, t = make_s_curve(500, random_state=0)
    X_new, t_new = make_s_curve(50, random_state=1)
    m = NeighborhoodLinearEmbedding(n_neighbors=12, random_state=0).fit(X)
    np.testing.assert_allclose(m.transform(X), m.embedding_, atol=1e-12)  # exact training points
    Y_new = m.transform(X_new)
    # the roll coordinate t is a monotone function of the unrolled axis: compare by interpolation
    axis = int(np.argmax([abs(spearmanr(m.embedding_[:, k], t)[0]) for k in range(2)]))
    assert abs(spearmanr(Y_new[:, axis], t_new)[0]) > 0.98


# --------------------------------------------------------------------------- CNLE


def test_two_rolls_data_set():
    X, lab, t = make_two_rolls(300, outliers=0.1, random_state=0)
    assert X.shape == (330, 3) and lab.shape == (330,) and t.shape == (330, 2)
    assert set(np.unique(lab)) == {-1, 0, 1}
    assert np.isnan(t[lab == -1]).all()


def _two_sheets_with_noise_bridges(seed: int = 0, gap: float = 6.0, n_out: int = 40):
    """Two jittered 15 x 15 grids (spacing 1) ``gap`` apart, plus ``n_out`` noise points
    scattered between them (label -1)."""
    rng = np.random.default_rng(seed)
    g = np.stack(np.meshgrid(np.arange(15.0), np.arange(15.0)), -1).reshape(-1, 2)
    a = np.c_[g + rng.uniform(-0.3, 0.3, g.shape), np.zeros(len(g))]
    b = np.c_[g + rng.uniform(-0.3, 0.3, g.shape), np.full(len(g), gap)]
    o = rng.uniform([0, 0, 0.5], [14, 14, gap - 0.5], (n_out, 3))
    lab = np.r_[np.zeros(len(g), int), np.ones(len(g), int), -np.ones(n_out, int)]
    return np.vstack([a, b, o]), lab


@pytest.mark.parametrize("seed", [0, 1])
def test_cnle_separates_sheets_that_a_fixed_k_graph_joins_through_noise(seed):
    from scipy.sparse.csgraph import connected_components
    from sklearn.neighbors import kneighbors_graph

    X, lab = _two_sheets_with_noise_bridges(seed)
    G = kneighbors_graph(X, 5)
    n_comp, comp = connected_components(G + G.T)
    assert np.bincount(comp).max() > 450  # LLE's K=5 graph joins the sheets through the noise
    m = ClusteredNLE(random_state=0).fit(X)
    good = lab >= 0
    assert m.n_clusters_ == 2
    assert adjusted_rand_score(lab[good], m.labels_[good]) == 1.0
    assert m.embedding_.shape == (X.shape[0], 2)
    for c in range(2):  # each sheet is embedded on its own: centred, in the units of X (~15)
        Yc = m.embedding_[m.labels_ == c]
        np.testing.assert_allclose(Yc.mean(axis=0), 0.0, atol=1e-6)
        assert 2.0 < Yc.std(axis=0).max() < 8.0
    np.testing.assert_array_equal(m.predict(X), m.labels_)
    np.testing.assert_allclose(m.transform(X), m.embedding_, atol=1e-12)
    np.testing.assert_array_equal(m.fit_predict(X), m.labels_)


def test_nle_warns_on_a_disconnected_graph():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(100, 3))
    X = np.vstack([a, a + 100.0])
    with pytest.warns(DisconnectedGraphWarning, match="ClusteredNLE"):
        NeighborhoodLinearEmbedding(n_neighbors=6, random_state=0).fit(X)


# --------------------------------------------------------------------------- bad input


def test_nan_input_is_rejected():
    X, _ = make_swiss_roll(100, random_state=0)
    X[3, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        NeighborhoodLinearEmbedding().fit(X)


@pytest.mark.parametrize("cls", [NeighborhoodLinearEmbedding, ClusteredNLE])
def test_data_scikit_learn_refuses_is_a_manifold_input_error(cls):
    """NaN, inf, empty, 1-D, complex or text data, and new points with another feature
    count, raised scikit-learn's plain ValueError: now ManifoldInputError (still a
    ValueError, with scikit-learn's message), in fit, transform and predict alike."""
    X, _ = make_swiss_roll(120, random_state=0)
    bad_fit = [np.where(np.arange(X.size).reshape(X.shape) == 4, np.nan, X),
               np.where(np.arange(X.size).reshape(X.shape) == 4, np.inf, X),
               X[:0], X[:, 0], X + 0j, X.astype(str).astype(object) + "x"]
    for B in bad_fit:
        with pytest.raises(ManifoldInputError):
            cls(n_neighbors=10).fit(B)
    est = cls(n_neighbors=10).fit(X)
    methods = [est.transform] + ([est.predict] if hasattr(est, "predict") else [])
    for method in methods:
        for B in (X[:5, :2], np.full((2, 3), np.nan)):
            with pytest.raises(ManifoldInputError) as exc:
                method(B)
            assert isinstance(exc.value, ValueError)


def test_too_many_neighbours_is_rejected():
    X, _ = make_swiss_roll(30, random_state=0)
    with pytest.raises(ManifoldInputError, match="n_neighbors=30 must be smaller") as exc:
        NeighborhoodLinearEmbedding(n_neighbors=30).fit(X)
    assert isinstance(exc.value, ValueError) and isinstance(exc.value, HearseeError)


def test_a_minimum_cluster_size_above_the_sample_count_is_rejected():
    """min_cluster_size > n_samples can never be met: every point became one cluster, without
    a word. Now the error n_neighbors >= n_samples gets; n_samples itself is fine."""
    X, _ = make_swiss_roll(30, random_state=0)
    with pytest.raises(ManifoldInputError, match=r"^min_cluster_size=31 must not exceed the "
                                                 r"number of samples \(n_samples = 30\)") as exc:
        ClusteredNLE(n_neighbors=6, min_cluster_size=31).fit(X)
    assert isinstance(exc.value, ValueError) and isinstance(exc.value, HearseeError)
    with pytest.raises(ManifoldInputError, match="min_cluster_size=20 must not exceed"):
        ClusteredNLE(n_neighbors=6).fit_predict(X[:19])  # (the default, 20)
    m = ClusteredNLE(n_neighbors=6, min_cluster_size=30, random_state=0).fit(X)
    assert m.labels_.shape == (30,) and m.n_clusters_ == 1


def test_duplicate_points_are_rejected():
    X, _ = make_swiss_roll(100, random_state=0)
    X[7] = X[42]
    with pytest.raises(ManifoldInputError, match="duplicate.*rows (7 and 42|42 and 7)"):
        NeighborhoodLinearEmbedding().fit(X)
    with pytest.raises(ManifoldInputError, match="duplicate"):
        ClusteredNLE().fit(X)


def test_identical_points_in_many_dimensions_are_duplicates_and_map_to_themselves():
    """With more than 15 features scikit-learn's brute-force search takes
    ``|x|^2 + |y|^2 - 2 x.y``: identical points came out up to ~1e-5 apart, so fit let some
    duplicates through (30 of 40 found here) and transform moved training points off their
    embedding (91 of 400)."""
    X, _ = make_swiss_roll(400, random_state=0)
    Q = np.linalg.qr(np.random.default_rng(0).normal(size=(40, 3)))[0]  # (40, 3) orthonormal
    X40 = X @ Q.T
    for cls in (NeighborhoodLinearEmbedding, ClusteredNLE):
        m = cls(random_state=0).fit(X40)
        np.testing.assert_array_equal(m.transform(X40), m.embedding_)
        with pytest.raises(ManifoldInputError, match="X contains 40 points that duplicate"):
            cls().fit(np.vstack([X40, X40[:20]]))


def test_bad_parameters_are_rejected():
    X, _ = make_swiss_roll(100, random_state=0)
    with pytest.raises(ValueError, match="shadow"):
        NeighborhoodLinearEmbedding(shadow=1.5).fit(X)
    with pytest.raises(ValueError, match="eigen_solver"):
        NeighborhoodLinearEmbedding(eigen_solver="magic").fit(X)
    # with more neighbours than features every local Gram matrix is singular: reg must be > 0
    # (reg=0 passed the check and ended in numpy's LinAlgError)
    for est in (NeighborhoodLinearEmbedding, ClusteredNLE):
        with pytest.raises(ValueError, match="reg"):
            est(reg=0.0).fit(X)


def test_transform_checks_the_feature_count():
    X, _ = make_swiss_roll(100, random_state=0)
    m = NeighborhoodLinearEmbedding().fit(X)
    with pytest.raises(ValueError, match="features"):
        m.transform(X[:, :2])


# --------------------------------------------------------------------------- degenerate graphs


@pytest.mark.parametrize("n_neighbors, n_components", [(1, 2), (2, 2), (2, 5)])
def test_n_neighbors_must_exceed_n_components(n_neighbors, n_components):
    # before: a neighbourhood graph in pieces, coordinates of std 1e12-1e15 and only a warning
    X, _ = make_swiss_roll(50, random_state=0)
    for est in (NeighborhoodLinearEmbedding, ClusteredNLE):
        with pytest.raises(
            ManifoldInputError,
            match=f"n_neighbors={n_neighbors} must be > n_components={n_components}",
        ):
            est(n_components, n_neighbors=n_neighbors, random_state=0).fit(X)


@pytest.mark.parametrize("solver", ["dense", "arpack"])
def test_disconnected_graph_gives_separating_axes_in_data_units(solver):
    # two parallel sheets far apart: the first axis is constant on each sheet and tells them
    # apart, the second unfolds one sheet. Before, the first axis was "scaled" by the ratio of
    # edge lengths to eigensolver noise (std 1e8-1e9)
    rng = np.random.default_rng(0)
    g = np.stack(np.meshgrid(np.arange(15.0), np.arange(15.0)), -1).reshape(-1, 2)
    X = np.vstack([np.c_[g + rng.uniform(-0.3, 0.3, g.shape), np.full(len(g), z)]
                   for z in (0.0, 50.0)])
    nle = NeighborhoodLinearEmbedding(n_neighbors=8, eigen_solver=solver, random_state=0)
    with pytest.warns(DisconnectedGraphWarning, match="2 connected components"):
        Y = nle.fit_transform(X)
    assert np.isfinite(Y).all() and np.abs(Y).max() < 30.0  # a sheet is 15 x 15
    assert np.ptp(Y[:225, 0]) == 0.0 and np.ptp(Y[225:, 0]) == 0.0 and Y[0, 0] != Y[225, 0]
    assert max(np.ptp(Y[:225, 1]), np.ptp(Y[225:, 1])) > 10.0
    np.testing.assert_allclose(Y.mean(axis=0), 0.0, atol=1e-9)


def test_graph_with_more_components_than_axes_maps_each_to_a_point():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(60, 3))
    X = np.vstack([a, a + 100.0, a - 100.0])
    with pytest.warns(DisconnectedGraphWarning, match="3 connected components"):
        Y = NeighborhoodLinearEmbedding(n_neighbors=6, random_state=0).fit_transform(X)
    assert np.abs(Y).max() < 10.0  # was 6e9
    assert len(np.unique(Y, axis=0)) == 3


def test_degenerate_embedding_is_refused():
    X, _ = make_swiss_roll(300, random_state=0)
    # connected, but 3 groups of points choose their neighbours only among themselves: the
    # embedding collapses them; before: an axis of std 1.8e8 and no warning at all
    with pytest.warns(DisconnectedGraphWarning, match="3 groups of points"):
        with pytest.raises(ManifoldInputError, match="degenerate embedding"):
            NeighborhoodLinearEmbedding(n_neighbors=4, random_state=0).fit(X)
    # no such group, but a few points barely tied to the rest (before: std 9e3, silently)
    with pytest.raises(ManifoldInputError, match="degenerate embedding.*very few"):
        NeighborhoodLinearEmbedding(n_neighbors=5, random_state=0).fit(X)
    # two copies of the roll with 3 candidates (before: axis std 7.7e7)
    X2 = np.vstack([X[:150], X[:150] + 1000.0])
    with pytest.warns(DisconnectedGraphWarning), pytest.raises(ManifoldInputError,
                                                               match="degenerate embedding"):
        NeighborhoodLinearEmbedding(eigen_solver="dense", n_neighbors=3).fit(X2)
    # LLE's own normalisation stays available, with the warning
    nle = NeighborhoodLinearEmbedding(n_neighbors=4, axis_scaling="unit", random_state=0)
    with pytest.warns(DisconnectedGraphWarning, match="collapses each group to a point"):
        Y = nle.fit_transform(X)
    assert np.isfinite(Y).all() and np.abs(Y).max() < 100.0


def test_values_too_large_for_float64_distances_are_refused():
    X, _ = make_swiss_roll(300, random_state=0)
    with pytest.raises(ManifoldInputError, match="values too large"):  # was "cannot reshape"
        NeighborhoodLinearEmbedding(random_state=0).fit(X * 1e200)
    m = NeighborhoodLinearEmbedding(random_state=0).fit(X)
    with pytest.raises(ManifoldInputError, match="values too large"):  # was NaN coordinates
        m.transform(np.array([[1e200, 0.0, 0.0]]))
    with pytest.raises(ManifoldInputError, match="values too small"):  # was "duplicate points"
        NeighborhoodLinearEmbedding(random_state=0).fit(X * 1e-200)
    # large but representable data still work, in their own units
    Y = NeighborhoodLinearEmbedding(random_state=0).fit_transform(X * 1e100) / 1e100
    np.testing.assert_allclose(Y, m.embedding_, atol=1e-6 * np.abs(m.embedding_).max())


@pytest.mark.parametrize("cls", [NeighborhoodLinearEmbedding, ClusteredNLE])
def test_more_axes_than_features_is_refused(cls):
    """Five axes for points in 3D were computed without a word (an embedding of points in a
    D-dimensional space has at most D meaningful axes)."""
    X, _ = make_swiss_roll(200, random_state=0)
    with pytest.raises(ManifoldInputError, match="n_features = 3"):
        cls(n_components=5, n_neighbors=10, random_state=0).fit(X)
    assert cls(n_components=3, n_neighbors=10, random_state=0).fit_transform(X).shape == (200, 3)


def test_building_blocks_refuse_bad_arguments():
    from sklearn.neighbors import NearestNeighbors

    X, _ = make_swiss_roll(100, random_state=0)
    dist, ind = NearestNeighbors(n_neighbors=6).fit(X).kneighbors(X)
    dist, ind = dist[:, 1:], ind[:, 1:]
    mask = adaptive_neighbors(X, ind, dist)
    # NaN weights, LinAlgError, or silently accepted before
    for reg in (np.nan, np.inf, 0.0, -1e-3):
        with pytest.raises(ManifoldInputError, match="reg"):
            reconstruction_weights(X, ind, mask, reg=reg)
    with pytest.raises(ManifoldInputError, match="mask must be bool"):  # (strings: all True)
        reconstruction_weights(X, ind, np.where(mask, "yes", "no"))
    # reg * trace(C) overflowing float64: NaN weights before (and a RuntimeError from SuperLU
    # in fit)
    with pytest.raises(ManifoldInputError, match="reg"), np.errstate(all="ignore"):
        reconstruction_weights(X, ind, mask, reg=1e307)
    with pytest.raises(ManifoldInputError, match="reg"), np.errstate(all="ignore"):
        NeighborhoodLinearEmbedding(n_neighbors=5, reg=1e308, random_state=0).fit(X)
    with pytest.raises(ManifoldInputError, match="accept no neighbour"):  # was NaN weights
        reconstruction_weights(X, ind, np.zeros_like(mask))
    with pytest.raises(ManifoldInputError, match="finite"):
        reconstruction_weights(np.where(X > 5.0, np.nan, X), ind, mask)
    with pytest.raises(ManifoldInputError, match="shape of ind"):
        reconstruction_weights(X, ind, mask[:, :2])
    for shadow in (np.nan, 1.5, -0.1):  # NaN accepted every candidate
        with pytest.raises(ManifoldInputError, match="shadow"):
            adaptive_neighbors(X, ind, dist, shadow=shadow)
    with pytest.raises(ManifoldInputError, match="row indices"):
        adaptive_neighbors(X, ind + 1000, dist)
    for k in (0, -3, 2.0, True):  # 0 and -3 were silently taken as 1
        with pytest.raises(ManifoldInputError, match="min_neighbors must be an integer >= 1"):
            adaptive_neighbors(X, ind, dist, min_neighbors=k)
    # valid calls are unchanged, also with the first rows of X as the centers
    W = reconstruction_weights(X, ind, mask)
    np.testing.assert_allclose(W.sum(axis=1), 1.0)
    np.testing.assert_array_equal(adaptive_neighbors(X, ind[:5], dist[:5]), mask[:5])


@pytest.mark.parametrize(
    "name, value",
    [("gap", np.nan), ("noise", np.nan), ("noise", -1.0), ("height", np.nan), ("height", 0.0),
     ("density_ratio", -1.0), ("density_ratio", np.inf), ("outliers", np.nan),
     ("n_samples", -5), ("n_samples", 10.5), ("gap", -4.7)],
)
def test_make_two_rolls_refuses_bad_parameters(name, value):
    kwargs = {"n_samples": 50, "random_state": 0, name: value}
    with pytest.raises(ConfigError, match=name):
        make_two_rolls(**kwargs)


def _arc_length_on_offset_spiral(points_xz: np.ndarray, offset: float) -> tuple:
    """Arc length (from the inner end) of the nearest point of the spiral r = t, t in
    [1.5 pi, 3.5 pi], pushed ``offset`` along its outward normal, and the distance to it; the
    curve as a polyline of 200,001 vertices with numerical normals."""
    from scipy.spatial import cKDTree

    tt = np.linspace(1.5 * np.pi, 3.5 * np.pi, 200_001)
    c = np.c_[tt * np.cos(tt), tt * np.sin(tt)]
    d = np.gradient(c, tt, axis=0)
    nrm = np.c_[d[:, 1], -d[:, 0]] / np.linalg.norm(d, axis=1)[:, None]
    nrm *= np.sign(np.mean(np.sum(nrm * c, axis=1)))  # outward
    P = c + offset * nrm
    L = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))]
    dist, i = cKDTree(P).query(points_xz)
    return L[i], dist, L[-1]


@pytest.mark.parametrize("gap", [np.pi, -2.0])
def test_make_two_rolls_sheets_are_uniform_by_area(gap):
    """Sheet 1 (the spiral pushed along its normal) was sampled uniformly in sheet 0's arc
    length: 1.26 times denser in its outer tenth than in its inner one, chi^2 = 55 over ten
    equal-area bands (9 degrees of freedom; p = 1e-8); inside sheet 0 (gap -2) 1.35 times
    denser in its inner tenth, chi^2 = 90. Both sheets must be uniform by area (now chi^2 =
    10.2 and 5.7 at the default gap), and t[:, 0] the arc length along the point's own sheet."""
    from scipy.stats import chi2

    X, lab, t = make_two_rolls(20000, density_ratio=1.0, gap=gap, random_state=0)
    for sheet, offset in ((0, 0.0), (1, gap)):
        m = lab == sheet
        s, dist, length = _arc_length_on_offset_spiral(X[m][:, [0, 2]], offset)
        assert dist.max() < 1e-3  # on the sheet (no noise)
        # ten bands of equal arc length (the sheet is a ruled surface: equal areas)
        counts = np.histogram(s, bins=10, range=(0.0, length))[0]
        expected = m.sum() / 10
        stat = float(np.sum((counts - expected) ** 2 / expected))
        assert chi2.sf(stat, 9) > 0.001, (sheet, counts)
        assert counts.max() / counts.min() < 1.15
        np.testing.assert_allclose(t[m, 0], s, atol=1e-3)


def test_make_two_rolls_with_an_empty_sheet_warns_nothing():
    # n_samples=0 and density_ratio=0 are valid; an empty sheet raised numpy's "Mean of empty
    # slice" RuntimeWarning (an error under -W error)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        X, lab, t = make_two_rolls(10, density_ratio=0.0, random_state=0)
        assert X.shape == (10, 3) and (lab == 1).all() and np.isfinite(X).all()
        X, lab, t = make_two_rolls(0, random_state=0)
        assert X.shape == (0, 3) and lab.shape == (0,) and t.shape == (0, 2)


@pytest.mark.parametrize(
    "name, value",
    [("yaw_range_deg", (np.nan, 0.0)), ("pitch_range_deg", (0.0, np.inf)), ("yaw_range_deg", 5.0),
     ("noise", np.nan), ("noise", -0.1), ("size", 0), ("n_samples", -1)],
)
def test_make_head_pose_images_refuses_bad_parameters(name, value):
    kwargs = {"n_samples": 3, "size": 8, "random_state": 0, name: value}
    with pytest.raises(ConfigError, match=name):
        make_head_pose_images(**kwargs)


def test_make_head_pose_images_shapes():
    images, pose = make_head_pose_images(3, size=8, yaw_range_deg=(10, -10), random_state=0)
    assert images.shape == (3, 64) and pose.shape == (3, 2)
    assert np.all(np.abs(pose[:, 0]) <= 10.0)


def test_head_pose_directions_are_those_documented():
    """Noise-free 64-px faces: the nose (the brightest pixel) moves to the image right for a
    positive yaw and down for a positive pitch (the face looks down; the docstring said up)."""
    def nose(yaw, pitch):
        img = make_head_pose_images(1, size=64, yaw_range_deg=(yaw, yaw),
                                    pitch_range_deg=(pitch, pitch), noise=0.0,
                                    random_state=0)[0][0].reshape(64, 64)
        return np.unravel_index(np.argmax(img), img.shape)  # (row: down, column: right)

    r0, c0 = nose(0, 0)
    assert nose(40, 0)[1] > c0 + 8 and nose(-40, 0)[1] < c0 - 8
    assert nose(0, 30)[0] > r0 + 8 and nose(0, -30)[0] < r0 - 8


# --------------------------------------------------------------------------- state


@pytest.mark.parametrize("cls, bad_k", [(NeighborhoodLinearEmbedding, 5), (ClusteredNLE, 3)])
def test_failed_refit_leaves_the_fitted_model_consistent(cls, bad_k):
    """A refit that raised (degenerate embedding) had already replaced ``nbrs_`` and
    ``training_data_`` (and ``labels_``) while ``embedding_`` stayed the old one: transform then
    indexed the old embedding with the new training set's neighbours and returned wrong numbers
    without a word."""
    X_good, _ = make_swiss_roll(600, random_state=1)
    X_bad, _ = make_swiss_roll(300, random_state=0)
    m = cls(n_neighbors=10, random_state=0).fit(X_good)
    ref = m.transform(X_good[:20])
    ref_labels = getattr(m, "labels_", None)
    m.set_params(n_neighbors=bad_k)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DisconnectedGraphWarning)
        with pytest.raises(ManifoldInputError, match="degenerate embedding"):
            m.fit(X_bad)
    m.set_params(n_neighbors=10)
    np.testing.assert_array_equal(m.transform(X_good[:20]), ref)
    assert m.training_data_ is not X_bad and m.training_data_.shape == X_good.shape
    if ref_labels is not None:
        np.testing.assert_array_equal(m.labels_, ref_labels)
        np.testing.assert_array_equal(m.predict(X_good), ref_labels)


@pytest.mark.parametrize("cls", [NeighborhoodLinearEmbedding, ClusteredNLE])
def test_failed_refit_on_another_feature_count_keeps_the_model_usable(cls):
    """Validation had already set ``n_features_in_`` to the new count when the refit raised:
    the old model then refused its own 3 features and took 5 on to a NumPy broadcasting
    ValueError (not a hearsee error)."""
    X, _ = make_swiss_roll(600, random_state=1)
    m = cls(n_neighbors=10, random_state=0).fit(X)
    ref = m.transform(X[:20])
    B = np.random.default_rng(0).normal(size=(100, 5))
    B[3] = B[4]
    with pytest.raises(ManifoldInputError, match="duplicate"):
        m.fit(B)
    assert m.n_features_in_ == 3
    np.testing.assert_array_equal(m.transform(X[:20]), ref)
    with pytest.raises(ManifoldInputError, match="X has 5 features"):
        m.transform(B[:3])
    unfitted = cls()
    with pytest.raises(ManifoldInputError, match="duplicate"):
        unfitted.fit(B)
    assert not hasattr(unfitted, "n_features_in_")


def test_cnle_transform_reconstructs_from_the_cluster_alone():
    """A sparse sheet (12 x 12, spacing 1, z = 1.5) above a dense one (40 x 40, spacing 0.3,
    z = 0): CNLE separates them exactly. New points of the sparse sheet, 0.5 off it towards the
    dense one (noise), have mostly dense-sheet points among their 8 nearest training points.
    transform took its candidates among all training points and shadowed them before keeping
    the cluster's: 1-4 neighbours were left (19 of 40 points fewer than the d + 1 = 3 fit keeps) and
    the points landed up to 0.25 (mean 0.062) from where their sheet's embedding puts them;
    from the cluster's own adaptive neighbourhood (as fit embeds it) at most 0.015 (mean
    0.007, measured)."""
    rng = np.random.default_rng(0)

    def grid(n, step):
        g = np.stack(np.meshgrid(np.arange(n) * step, np.arange(n) * step), -1).reshape(-1, 2)
        return g + rng.uniform(-0.2, 0.2, g.shape) * step

    dense = np.c_[grid(40, 0.3), np.zeros(1600)]
    sparse = np.c_[grid(12, 1.0), np.full(144, 1.5)]
    X = np.vstack([dense, sparse])
    m = ClusteredNLE(random_state=0).fit(X)
    assert m.n_clusters_ == 2
    c = m.labels_[1600]
    np.testing.assert_array_equal(m.labels_ == c, np.arange(1744) >= 1600)
    # the sparse sheet is flat: its embedding is an affine image of (x, y), to 0.02 rms
    A = np.c_[sparse[:, :2], np.ones(144)]
    coef, *_ = np.linalg.lstsq(A, m.embedding_[1600:], rcond=None)
    assert np.sqrt(np.mean(np.sum((A @ coef - m.embedding_[1600:]) ** 2, axis=1))) < 0.03
    # new points near the sparse sheet's inner points, 0.5 below it
    inner = sparse[(sparse[:, :2].min(axis=1) > 1.5) & (sparse[:, :2].max(axis=1) < 9.5)]
    q = inner[rng.choice(len(inner), 40, replace=False)] + np.c_[
        rng.uniform(-0.3, 0.3, (40, 2)), np.full(40, -0.5)]
    assert np.all(m.predict(q) == c)
    err = np.linalg.norm(m.transform(q) - np.c_[q[:, :2], np.ones(40)] @ coef, axis=1)
    assert err.max() < 0.06


def _saved_by_an_older_hearsee(model, *missing):
    """``model`` as pickled by a hearsee whose fit did not keep the ``missing`` attributes."""
    import pickle

    old = pickle.loads(pickle.dumps(model))
    for attribute in missing:
        delattr(old, attribute)
    return pickle.loads(pickle.dumps(old))


@pytest.mark.parametrize("cls, missing", [
    (ClusteredNLE, ("cluster_nbrs_",)),  # saved before 2026-11-26
    (ClusteredNLE, ("cluster_nbrs_", "training_data_")),  # saved before 2026-11-22
    (NeighborhoodLinearEmbedding, ("training_data_",)),
])
def test_a_model_saved_by_an_older_hearsee_transforms_as_a_fresh_fit(cls, missing):
    """Models pickled before ``cluster_nbrs_`` (or ``training_data_``) existed lack them, and
    transform raised a builtin AttributeError. They are rebuilt from what the model stores
    (``labels_``, ``nbrs_``'s training points): the same numbers as a model fitted afresh."""
    X, _ = _two_sheets_with_noise_bridges(0)
    q = X[::7] + np.random.default_rng(1).uniform(-0.4, 0.4, X[::7].shape)
    q[:5] = X[:5]  # some queries coincide with training points
    fresh = cls(random_state=0).fit(X)
    old = _saved_by_an_older_hearsee(cls(random_state=0).fit(X), *missing)
    if cls is ClusteredNLE:
        assert old.n_clusters_ == 2
    np.testing.assert_array_equal(old.transform(q), fresh.transform(q))
    np.testing.assert_array_equal(old.training_data_, fresh.training_data_)
    np.testing.assert_allclose(fresh.training_data_ + fresh.offset_, X, rtol=0, atol=1e-12)


def test_data_far_from_the_origin_in_many_dimensions():
    """A swiss roll in 60 dimensions moved by 1e6: scikit-learn's brute-force neighbour search
    (|x|^2 + |y|^2 - 2 x.y) cancelled nearby distances to 0 and fit refused "6 points that
    duplicate another point" (the nearest pair is 0.049 apart). Fit centres the data: the
    embedding, the out-of-sample map and the clusters are those of the unmoved roll."""
    from sklearn.datasets import make_swiss_roll

    X, _ = make_swiss_roll(800, random_state=0)
    Q = np.linalg.qr(np.random.default_rng(0).normal(size=(60, 3)))[0]  # (60, 3) orthonormal
    X60 = X @ Q.T
    assert np.min(np.linalg.norm(X60[:, None] - X60[None], axis=-1)[np.triu_indices(800, 1)]) > 0.04
    for cls in (NeighborhoodLinearEmbedding, ClusteredNLE):
        near, far = cls(random_state=0).fit(X60), cls(random_state=0).fit(X60 + 1e6)
        # (coordinates span ~50; the eigensolver's answers differ by ~1e-4 of that)
        np.testing.assert_allclose(far.embedding_, near.embedding_, atol=1e-3)
        q = X60[:20] + 0.01
        np.testing.assert_allclose(far.transform(q + 1e6), near.transform(q), atol=1e-3)
        if cls is ClusteredNLE:
            np.testing.assert_array_equal(far.predict(q + 1e6), near.predict(q))


def test_an_old_model_that_cannot_be_rebuilt_asks_for_a_refit():
    """Without ``training_data_`` and without the training points in ``nbrs_`` (where a
    scikit-learn of another version may keep them elsewhere) nothing can be rebuilt: hearsee's
    typed error, one line, saying to re-fit."""
    X, _ = _two_sheets_with_noise_bridges(0)
    old = _saved_by_an_older_hearsee(ClusteredNLE(random_state=0).fit(X), "cluster_nbrs_",
                                     "training_data_")
    del old.nbrs_._fit_X
    with pytest.raises(ManifoldInputError, match="older hearsee.*re-fit the model") as exc:
        old.transform(X[:3])
    assert "\n" not in str(exc.value)


def test_bad_hyperparameters_unfitted_models_and_sparse_input_are_hearsee_errors():
    """scikit-learn's InvalidParameterError, NotFittedError and a builtin TypeError (sparse X)
    reached the user alone; each is now also hearsee's ManifoldInputError, keeping
    scikit-learn's type for its tools."""
    from scipy import sparse
    from sklearn.exceptions import NotFittedError
    from sklearn.utils._param_validation import InvalidParameterError

    from hearsee.learn.nle import ClusteredNLE, ManifoldInputError, NeighborhoodLinearEmbedding

    X = np.random.default_rng(0).normal(size=(60, 3))
    # (a bool as a whole number: n_neighbors=True passed scikit-learn's check as 1)
    for est in (NeighborhoodLinearEmbedding(n_neighbors=0), NeighborhoodLinearEmbedding(
            shadow=float("nan")), ClusteredNLE(min_cluster_size=0),
            NeighborhoodLinearEmbedding(n_neighbors=True), ClusteredNLE(min_cluster_size=True),
            NeighborhoodLinearEmbedding(n_components=np.True_)):
        with pytest.raises(ManifoldInputError, match="parameter of") as info:
            est.fit(X)
        assert isinstance(info.value, InvalidParameterError)
    for call in (NeighborhoodLinearEmbedding().transform, ClusteredNLE().predict):
        with pytest.raises(ManifoldInputError, match="not fitted yet") as info:
            call(X)
        assert isinstance(info.value, NotFittedError)
    with pytest.raises(ManifoldInputError, match="Sparse data") as info:
        NeighborhoodLinearEmbedding().fit(sparse.csr_matrix(X))
    assert isinstance(info.value, TypeError)


@pytest.mark.parametrize("cls", [NeighborhoodLinearEmbedding, ClusteredNLE])
def test_n_jobs_zero_is_refused_with_the_parameters(cls):
    """n_jobs=0 passed the parameter check and joblib refused it at fit ("n_jobs == 0 in
    Parallel has no meaning", a bare ValueError); -1 and 1 still fit."""
    X = np.random.default_rng(0).standard_normal((60, 3))
    with pytest.raises(HearseeError, match="'n_jobs' parameter"):
        cls(n_jobs=0).fit(X)
    assert cls(n_jobs=-1, n_neighbors=8).fit(X).embedding_.shape == (60, 2)


def test_cnle_keeps_graph_components_without_core_points_apart():
    # two 5 x 5 patches 100 apart in 10-D, 0.3 of noise in the 8 other dimensions: no point
    # passes the core test (off-plane energy > 0.3), yet the neighbourhood graph has two
    # components. Before: one cluster (ARI 0), both patches embedded together, a constant
    # contrast axis; and a clean patch beside the noisy one took the noisy patch in
    rng = np.random.default_rng(0)

    def patch(shift, noise):
        P = np.zeros((300, 10))
        P[:, :2] = rng.uniform(0, 5, (300, 2))
        P[:, 2:] = rng.normal(0, noise, (300, 8)) if noise else 0.0
        P[:, 0] += shift
        return P

    truth = np.r_[np.zeros(300, int), np.ones(300, int)]
    for first_noise in (0.3, 0.0):
        X = np.r_[patch(0.0, first_noise), patch(100.0, 0.3)]
        m = ClusteredNLE(random_state=0).fit(X)
        assert m.n_clusters_ == 2
        assert adjusted_rand_score(truth, m.labels_) == 1.0
        for c in range(2):  # each patch unfolded on its own (it spans 5 x 5)
            assert np.ptp(m.embedding_[m.labels_ == c], axis=0).min() > 3.0
    # a connected cloud without core points is still one cluster
    one = ClusteredNLE(random_state=0).fit(patch(0.0, 0.3))
    assert one.n_clusters_ == 1


def test_cnle_small_piece_far_away_does_not_flatten_its_cluster():
    # two 5 x 5 patches 50 apart and a 1 x 1 piece of 15 points 50 from the first, below
    # min_cluster_size: it takes the first patch's label. Before, that cluster was embedded with
    # a disconnected graph: the first axis constant on the patch (only telling the piece apart), the
    # patch squeezed onto one axis (Procrustes error 0.75 of its size); now 0.08
    from scipy.linalg import orthogonal_procrustes

    rng = np.random.default_rng(0)
    T0, T1 = rng.uniform(0, 5, (200, 2)), rng.uniform(0, 5, (200, 2))
    T2 = rng.uniform(0, 1, (15, 2))
    X = np.r_[np.c_[T0, np.zeros(200)], np.c_[T1 + [50, 0], np.zeros(200)],
              np.c_[T2 + [0, 50], np.zeros(15)]]
    m = ClusteredNLE(random_state=0).fit(X)
    assert m.n_clusters_ == 2
    assert (m.labels_[400:] == m.labels_[0]).all() and (m.labels_[:200] == m.labels_[0]).all()
    Y = m.embedding_[:200] - m.embedding_[:200].mean(axis=0)
    T = T0 - T0.mean(axis=0)
    R, _ = orthogonal_procrustes(Y, T)
    assert np.sqrt(((Y @ R - T) ** 2).sum() / (T**2).sum()) < 0.2
    assert np.ptp(m.embedding_[400:], axis=0).max() < 1.0  # the piece stays together
    np.testing.assert_allclose(m.embedding_[m.labels_ == m.labels_[0]].mean(axis=0), 0.0,
                               atol=1e-9)
    np.testing.assert_allclose(m.transform(X), m.embedding_, atol=1e-12)
    np.testing.assert_allclose(np.asarray(m.adjacency_.sum(axis=1)).ravel(), 1.0)
    assert m.n_neighbors_.min() >= 3


def test_output_features_are_named_as_sklearn_names_its_embeddings():
    """get_feature_names_out (scikit-learn's set_output needs it: pandas output was an
    AttributeError): the class's name in lower case and the axis, as LocallyLinearEmbedding's
    'locallylinearembedding0', ...; one name per embedding dimension."""
    from sklearn.manifold import LocallyLinearEmbedding

    X, _ = make_swiss_roll(300, random_state=349)
    lle = LocallyLinearEmbedding(n_neighbors=10, n_components=3).fit(X)
    assert list(lle.get_feature_names_out()) == [f"locallylinearembedding{i}" for i in range(3)]
    for est, prefix in ((NeighborhoodLinearEmbedding(3, n_neighbors=10, random_state=0),
                         "neighborhoodlinearembedding"),
                        (ClusteredNLE(2, random_state=0), "clusterednle")):
        est.fit(X)
        names = list(est.get_feature_names_out())
        assert names == [f"{prefix}{i}" for i in range(est.embedding_.shape[1])]
        assert len(names) == est.n_components
