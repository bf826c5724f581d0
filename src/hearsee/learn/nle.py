"""Neighborhood Linear Embedding (NLE) and its clustering (CNLE), thesis ch. 6.

Reconstruction
--------------
The thesis text of chapter 6 is not available; only its title, section titles and figure list
are (the project's design notes, ``../shared/design/reconstruction.md``, outside this
repository). What follows is a reconstruction from the
literature, not a transcription:

* The embedding follows Locally Linear Embedding (LLE): Roweis & Saul, "Nonlinear dimensionality
  reduction by locally linear embedding", Science 290 (2000); Saul & Roweis, "Think globally, fit
  locally", JMLR 4 (2003). Each point is written as an affine combination of its neighbours
  (weights summing to one, Tikhonov-regularised local Gram matrix); the embedding is given by the
  bottom eigenvectors of ``M = (I - W)^T (I - W)`` after the constant one.
* NLE's change is the neighbourhood. Instead of LLE's fixed ``K`` nearest neighbours, each point
  selects its neighbours from its ``n_neighbors`` nearest candidates by a similarity test on the
  local geometry, in the spirit of the adaptive-neighbourhood literature: Wang, Zhang & Zha,
  "Adaptive manifold learning", NIPS 17 (2005); Zhang & Wang, "MLLE: modified locally linear
  embedding using multiple weights", NIPS 19 (2007). The rule reconstructed here is the
  *shadow rule* known from the relative neighbourhood graph (Toussaint 1980) and the sparse
  neighbourhood graph of Arya & Mount (1993):

      candidates ``x_j`` are visited in order of distance to ``x_i``; ``x_j`` is accepted unless it
      is *shadowed* by an already accepted, closer neighbour ``x_k``:
      ``||x_j - x_k|| < shadow * ||x_j - x_i||``.

  A shadowed candidate lies "behind" an accepted neighbour as seen from ``x_i``: it adds little
  new direction to the reconstruction and, on a curved or multi-sheet data set, is the kind of
  point that short-circuits the manifold. ``shadow = 0`` turns the rule off (plain LLE);
  ``shadow = 1`` is the relative-neighbourhood test, which keeps about ``d + 1`` neighbours on a
  ``d``-dimensional manifold and leaves ``M`` nearly singular (measured on the 2000-point swiss
  roll with 12 candidates: 3.1 neighbours on average). NLE's default ``0.3`` keeps 9.6 (5-12),
  CNLE's ``0.5`` keeps 7.4 (4-11). Dropping neighbours with negative weights and refitting, the
  other rule the adaptive-LLE literature uses, was tried and lowered trustworthiness on the swiss
  roll and S-curve (0.97-0.98 vs 0.995), so it is not used. Every point keeps
  at least ``min(n_components + 1, n_neighbors)`` neighbours: when the rule leaves fewer, the
  nearest rejected candidates are added back.
* CNLE (thesis 6.1.2): the adaptive neighbourhood graph falls apart into one connected
  component per manifold once bridges are removed. The guards reconstructed here:

  1. *mutual* edges only (``j`` chose ``i`` and ``i`` chose ``j``): a point of a sparse or noisy
     region that reaches into a dense neighbouring sheet is rarely chosen back;
  2. an edge is cut when it is longer than ``bridge_ratio`` times the local scale (median
     accepted-neighbour distance) of either end;
  3. only *core* points link clusters: at least ``d + 1`` mutual neighbours and a locally
     ``d``-dimensional neighbourhood (at most ``max_off_plane`` of the energy of the offsets
     ``x_j - x_i`` outside their best ``d``-dimensional subspace). A noise point floating between
     two sheets has neighbours on both sides, fails this test and cannot chain them together.

  Components of core points with at least ``min_cluster_size`` points are the clusters; every
  other point (noise, boundary points, small pieces) takes the majority label of its adaptive
  neighbours, spreading outwards from the clusters. A connected component of the neighbourhood
  graph that no cluster reaches (none of its points is a core point: noisy or
  higher-dimensional data, a curve with ``d = 2``) is a cluster of its own when it has at least
  ``min_cluster_size`` points; the points still unlabelled take the label of their nearest
  labelled point. Each cluster is then embedded by NLE on its own (when its graph falls apart,
  its largest piece, the others placed by the out-of-sample map of ``transform``). The guards
  are in the spirit of mutual-kNN graphs and density-based clustering (DBSCAN's core points,
  Ester et al. 1996); their combination and thresholds are this reconstruction's choice.

The thesis author's own paper on the method (Ge, Guan, Pan & Loh, "Neighborhood linear embedding
for intrinsic structure discovery", Machine Vision and Applications, 2010) was not available to
this reconstruction; any difference from it is ours.

Solver: ``M`` is assembled in ``scipy.sparse`` (memory ``O(n k^2)`` for ``M``, ``O(n k)`` for the
neighbourhoods and weights; the neighbour computations run in chunks) and its bottom eigenvectors
are found by ARPACK in shift-invert mode around 0, with a sparse LU factorisation (SuperLU,
COLAMD ordering) as the inverse operator. Small problems (``n <= 200``) use a dense eigensolver.
"""

from __future__ import annotations

import functools
import warnings
from numbers import Integral, Real

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph
from sklearn.base import BaseEstimator, ClassNamePrefixFeaturesOutMixin, TransformerMixin
from sklearn.exceptions import NotFittedError
from sklearn.neighbors import NearestNeighbors
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import Interval, InvalidParameterError, StrOptions
from sklearn.utils.validation import check_is_fitted, validate_data

from hearsee.config import finite_number, whole_number
from hearsee.errors import ConfigError, EstimationError, HearseeError

__all__ = [
    "ClusteredNLE",
    "DisconnectedGraphWarning",
    "ManifoldInputError",
    "ManifoldInputTypeError",
    "ManifoldNotFittedError",
    "ManifoldParameterError",
    "NeighborhoodLinearEmbedding",
    "adaptive_neighbors",
    "make_head_pose_images",
    "make_two_rolls",
    "reconstruction_weights",
]

# Bytes of scratch memory one chunk of the neighbourhood computations may use.
_CHUNK_BYTES = 64 * 2**20

# Largest extent of the data (norm of the per-feature ranges) the distance computations accept:
# squared distances and the local Gram matrices (sums of them) must stay far below the float64
# maximum (1.8e308).
_MAX_SPAN = 1e150
# ... and the smallest: below it squared distances underflow (to subnormals or 0, 1e-308) and
# distinct points looked like duplicates.
_MIN_SPAN = 1e-150

# An axis scaled to the units of X ("edges") may span at most this many times the total edge
# length of the neighbourhood graph (its minimum spanning tree) of a connected component. A
# faithful unfolding spans at most about 1 (a path of the tree joins any two points; an evenly
# sampled curve reaches 1.0); degenerate embeddings, where a group of points is barely tied to
# the rest, reach 1e2 to 1e12 (measured on swiss rolls, helices, circles and planes with
# n_neighbors = n_components + 1 .. 5).
_MAX_AXIS_EXTENT = 10.0


class ManifoldInputError(HearseeError, ValueError):
    """Data a manifold learner cannot use (duplicate points, too few samples for the neighbours,
    values too large, a degenerate neighbourhood graph), bad arguments of the building blocks
    (:func:`adaptive_neighbors`, :func:`reconstruction_weights`), or a model saved by an older
    hearsee that lacks state :meth:`~NeighborhoodLinearEmbedding.transform` needs and that cannot
    be rebuilt (re-fit it).

    Derives from ``ValueError`` like scikit-learn's own input errors."""


class ManifoldInputTypeError(ManifoldInputError, TypeError):
    """X of a kind the learners do not take (a sparse matrix, an array of objects): hearsee's
    ManifoldInputError and the TypeError scikit-learn raises (that alone before 2026-12-03)."""


class ManifoldParameterError(ManifoldInputError, InvalidParameterError):
    """A hyperparameter of :class:`NeighborhoodLinearEmbedding` / :class:`ClusteredNLE` out of
    its range (``n_neighbors=0``, a NaN ``shadow``): hearsee's ManifoldInputError and
    scikit-learn's ``InvalidParameterError`` at once (that alone, before 2026-12-03)."""


class ManifoldNotFittedError(ManifoldInputError, NotFittedError):
    """``transform`` / ``predict`` before ``fit``: hearsee's ManifoldInputError and
    scikit-learn's ``NotFittedError`` at once (that alone, before 2026-12-03), as the
    regressors' :class:`hearsee.errors.RegressorNotFittedError`."""


def _check_params(est) -> None:
    """``est._validate_params()`` with its errors as :class:`ManifoldParameterError`; a bool
    where a whole number is asked is refused too (scikit-learn's ``Interval(Integral, ...)``
    takes True as 1: ``n_neighbors=True`` passed, then failed as "n_neighbors=True must be >
    n_components")."""
    try:
        est._validate_params()
    except InvalidParameterError as exc:
        raise ManifoldParameterError(str(exc)) from None
    for name, rules in est._parameter_constraints.items():
        value = getattr(est, name, None)
        if isinstance(value, bool | np.bool_) and any(
                isinstance(r, Interval) and r.type is Integral for r in rules):
            raise ManifoldParameterError(f"the {name!r} parameter of {type(est).__name__} must "
                                         f"be a whole number, got {value!r}")


def _check_fitted(est, attribute: str) -> None:
    """``check_is_fitted`` with its error as :class:`ManifoldNotFittedError`."""
    try:
        check_is_fitted(est, attribute)
    except NotFittedError as exc:
        raise ManifoldNotFittedError(str(exc)) from None


def _input_attributes_kept_on_error(fit):
    """Decorate ``fit``: when it raises, put back the ``n_features_in_`` / ``feature_names_in_``
    of the previous fit (or none), which validation had already replaced. The other fitted
    attributes are set together at the end of a fit that succeeds; until 2026-12-07 a failed
    refit on data with another number of features left the old model expecting the new count:
    transform refused the features it was fitted on, and the new count went on to a NumPy
    broadcasting ValueError."""

    @functools.wraps(fit)
    def wrapper(self, *args, **kwargs):
        saved = {a: self.__dict__[a] for a in ("n_features_in_", "feature_names_in_")
                 if a in self.__dict__}
        try:
            return fit(self, *args, **kwargs)
        except BaseException:
            for a in ("n_features_in_", "feature_names_in_"):
                self.__dict__.pop(a, None)
            self.__dict__.update(saved)
            raise

    return wrapper


class DisconnectedGraphWarning(UserWarning):
    """The neighbourhood graph falls apart: it has several connected components (a single
    embedding of all points is then not meaningful; use :class:`ClusteredNLE`), or groups of
    points that choose their neighbours only among themselves (the embedding collapses each
    such group to a point)."""


# --------------------------------------------------------------------------- building blocks


def _validated(est, X, **kw) -> np.ndarray:
    """scikit-learn's ``validate_data`` (float64), its ValueErrors (NaN, inf, empty, 1-D,
    text, complex, a wrong feature count) raised as :class:`ManifoldInputError` with the same
    message: still a ValueError, as scikit-learn's conventions want, and hearsee's own type."""
    try:
        return validate_data(est, X, dtype=np.float64, **kw)
    except ManifoldInputError:
        raise
    except TypeError as exc:  # (a sparse matrix, an array of objects)
        raise ManifoldInputTypeError(str(exc)) from None
    except ValueError as exc:
        raise ManifoldInputError(str(exc)) from None


def _check_neighbourhood_args(func: str, X, ind, centers, **same_shape):
    """Common checks of :func:`adaptive_neighbors` / :func:`reconstruction_weights` arguments;
    returns ``X, ind, centers`` as arrays (no copy for float64 ``X`` and integer ``ind``) and the
    ``same_shape`` arrays, each required to have the shape of ``ind``."""
    X = np.asarray(X, dtype=float)
    ind = np.asarray(ind)
    if centers is None and X.ndim == 2 and ind.ndim == 2 and ind.shape[0] <= X.shape[0]:
        centers = X[: ind.shape[0]]  # row i is point i
    centers = X if centers is None else np.asarray(centers, dtype=float)
    if X.ndim != 2 or centers.ndim != 2 or centers.shape[1] != X.shape[1]:
        raise ManifoldInputError(
            f"{func}: X and centers must be 2-D arrays with the same number of columns, got "
            f"shapes {X.shape} and {centers.shape}"
        )
    if ind.ndim != 2 or ind.shape[0] != centers.shape[0]:
        raise ManifoldInputError(
            f"{func}: ind must be a 2-D array with one row per center ({centers.shape[0]}), got "
            f"shape {ind.shape}"
        )
    if ind.size and (not np.issubdtype(ind.dtype, np.integer) or ind.min() < 0
                     or ind.max() >= X.shape[0]):
        raise ManifoldInputError(
            f"{func}: ind must hold integer row indices into X (0..{X.shape[0] - 1})"
        )
    if not (np.isfinite(X).all() and np.isfinite(centers).all()):
        raise ManifoldInputError(f"{func}: X and centers must be finite (no NaN or inf)")
    out = []
    for name, a in same_shape.items():
        a = np.asarray(a)
        if a.shape != ind.shape:
            raise ManifoldInputError(
                f"{func}: {name} must have the shape of ind {ind.shape}, got {a.shape}"
            )
        out.append(a)
    return X, ind, centers, out


def _chunks(n: int, k: int, n_features: int):
    per_point = 8 * k * (max(n_features, k) + 2 * k)
    step = max(1, min(n, _CHUNK_BYTES // max(per_point, 1)))
    for s in range(0, n, step):
        yield s, min(n, s + step)


def adaptive_neighbors(
    X: np.ndarray,
    ind: np.ndarray,
    dist: np.ndarray,
    shadow: float = 0.5,
    min_neighbors: int = 3,
    centers: np.ndarray | None = None,
) -> np.ndarray:
    """Apply the NLE shadow rule to candidate neighbourhoods.

    Parameters
    ----------
    X : (n_train, n_features) array
        The points the candidates index into.
    ind, dist : (n, K) arrays
        Candidate neighbour indices into ``X`` and their distances to each center, sorted by
        distance (as ``NearestNeighbors.kneighbors`` returns them).
    shadow : float in [0, 1]
        Candidate ``j`` is rejected when an already accepted neighbour ``k`` satisfies
        ``||x_j - x_k|| < shadow * ||x_j - x_i||``. 0 accepts all candidates (plain LLE).
    min_neighbors : int
        Every row keeps at least this many (>= 1; the nearest rejected candidates are added
        back; at most all ``K`` candidates).
    centers : (n, n_features) array, optional
        The points whose neighbourhoods these are; default ``X`` (row ``i`` is point ``i``).

    Returns
    -------
    mask : (n, K) bool array
        True where the candidate is accepted.

    Raises
    ------
    ManifoldInputError
        ``shadow`` outside [0, 1] or NaN, ``min_neighbors`` not an integer >= 1, non-finite ``X``,
        ``centers`` or ``dist``, or arrays of inconsistent shapes.
    """
    X, ind, centers, (dist,) = _check_neighbourhood_args("adaptive_neighbors", X, ind, centers,
                                                        dist=dist)
    if not np.isfinite(dist).all():
        raise ManifoldInputError("adaptive_neighbors: dist must be finite (no NaN or inf)")
    shadow = finite_number("shadow", shadow, 0.0, 1.0, error=ManifoldInputError)
    # (0 and negative counts were silently taken as 1 until 2026-12-02)
    if (isinstance(min_neighbors, bool) or not isinstance(min_neighbors, Integral)
            or min_neighbors < 1):
        raise ManifoldInputError(f"min_neighbors must be an integer >= 1, got {min_neighbors!r}")
    n, K = ind.shape
    mask = np.zeros((n, K), dtype=bool)
    if K == 0:
        return mask
    min_neighbors = int(min(min_neighbors, K))
    s2 = shadow**2
    for s, e in _chunks(n, K, X.shape[1]):
        P = X[ind[s:e]] - centers[s:e, None, :]  # (c, K, D) candidate offsets
        G = np.einsum("ckd,cld->ckl", P, P)
        sq = dist[s:e] ** 2
        # squared candidate-candidate distances ||x_j - x_k||^2
        Djk = np.diagonal(G, axis1=1, axis2=2)[:, :, None] + np.diagonal(G, axis1=1, axis2=2)[
            :, None, :
        ] - 2.0 * G
        m = np.zeros((e - s, K), dtype=bool)
        m[:, 0] = True
        if s2 > 0:
            for j in range(1, K):
                shadowed = ((Djk[:, j, :j] < s2 * sq[:, j, None]) & m[:, :j]).any(axis=1)
                m[:, j] = ~shadowed
        else:
            m[:] = True
        # add back the nearest rejected candidates where too few were kept
        short = m.sum(axis=1) < min_neighbors
        if short.any():
            mm = m[short]
            rank = np.cumsum(~mm, axis=1)  # 1 for the nearest rejected candidate, ...
            need = min_neighbors - mm.sum(axis=1)
            mm |= (~mm) & (rank <= need[:, None])
            m[short] = mm
        mask[s:e] = m
    return mask


def reconstruction_weights(
    X: np.ndarray,
    ind: np.ndarray,
    mask: np.ndarray,
    reg: float = 1e-3,
    centers: np.ndarray | None = None,
) -> np.ndarray:
    """LLE reconstruction weights of each center from its accepted neighbours.

    Solves, for each point ``i`` with accepted neighbours ``N(i)``,
    ``min ||x_i - sum_j w_j x_j||^2`` subject to ``sum_j w_j = 1`` via the local Gram matrix
    ``C_jk = (x_j - x_i).(x_k - x_i)`` regularised as ``C + reg * trace(C) * I`` (Roweis & Saul
    2000; the same regularisation as scikit-learn's LLE).

    Returns
    -------
    W : (n, K) array
        Weights aligned with ``ind``; 0 where ``mask`` is False. Rows sum to 1.

    Raises
    ------
    ManifoldInputError
        ``reg`` not a finite number > 0 (with more neighbours than features the Gram matrix is
        singular without it) or so large that the regularised Gram matrix overflows, a row of
        ``mask`` without any accepted neighbour, non-finite ``X`` or ``centers``, or arrays of
        inconsistent shapes.
    """
    X, ind, centers, (mask,) = _check_neighbourhood_args("reconstruction_weights", X, ind,
                                                        centers, mask=mask)
    if mask.dtype.kind not in "biuf":  # (a mask of strings was all True)
        raise ManifoldInputError(f"reconstruction_weights: mask must be bool, got {mask.dtype}")
    mask = mask.astype(bool, copy=False)
    reg = finite_number("reg", reg, 0.0, lo_open=True, error=ManifoldInputError)
    empty = ~mask.any(axis=1)
    if ind.shape[1] and empty.any():
        raise ManifoldInputError(
            f"reconstruction_weights: {int(empty.sum())} rows of mask accept no neighbour (e.g. "
            f"row {int(np.flatnonzero(empty)[0])}); every point needs at least one"
        )
    n, K = ind.shape
    W = np.zeros((n, K))
    idx = np.arange(K)
    for s, e in _chunks(n, K, X.shape[1]):
        m = mask[s:e]
        P = X[ind[s:e]] - centers[s:e, None, :]
        P *= m[:, :, None]
        C = np.einsum("ckd,cld->ckl", P, P)
        tr = np.trace(C, axis1=1, axis2=2)
        R = np.where(tr > 0, reg * tr, reg)
        C[:, idx, idx] += np.where(m, R[:, None], 1.0)
        try:
            w = np.linalg.solve(C, m.astype(float)[:, :, None])[:, :, 0]
        except np.linalg.LinAlgError:
            raise ManifoldInputError(
                f"reconstruction_weights: a local Gram matrix is singular at reg={reg:g}; use a "
                "larger reg"
            ) from None
        w /= w.sum(axis=1, keepdims=True)
        if not np.isfinite(w).all():  # reg * trace(C) overflowed float64
            raise ManifoldInputError(
                f"reconstruction_weights: reg={reg:g} is too large, the regularised local Gram "
                "matrices overflow float64; use a smaller reg"
            )
        W[s:e] = w
    return W


def _bottom_eigenvectors(
    M: sparse.spmatrix,
    k: int,
    solver: str,
    tol: float,
    random_state: np.random.RandomState,
) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` smallest eigenpairs of the symmetric PSD sparse matrix ``M``."""
    n = M.shape[0]
    if solver == "dense":
        from scipy.linalg import eigh

        vals, vecs = eigh(M.toarray(), subset_by_index=(0, k - 1))
        return vals, vecs
    from scipy.sparse.linalg import ArpackError, ArpackNoConvergence, LinearOperator, eigsh, splu

    Mc = sparse.csc_matrix(M)
    try:
        lu = splu(Mc)
    except RuntimeError:  # exactly singular: shift by a tiny multiple of the scale
        eps = 1e-12 * max(float(np.abs(Mc.diagonal()).max()), 1e-300)
        lu = splu(sparse.csc_matrix(Mc + eps * sparse.eye(n)))
    op_inv = LinearOperator((n, n), matvec=lu.solve, dtype=float)
    v0 = random_state.uniform(-1, 1, n)
    try:
        vals, vecs = eigsh(Mc, k=k, sigma=0.0, which="LM", OPinv=op_inv, tol=tol,
                           v0=v0)
    except (ArpackNoConvergence, ArpackError) as exc:
        raise EstimationError(
            f"the sparse eigensolver did not converge ({exc}); try eigen_solver='dense' for small "
            "data, a larger tol, or a larger reg"
        ) from exc
    order = np.argsort(vals)
    return vals[order], vecs[:, order]


def _off_plane_fraction(X: np.ndarray, ind: np.ndarray, mask: np.ndarray, d: int) -> np.ndarray:
    """Fraction of the energy of each point's accepted-neighbour offsets ``x_j - x_i`` that lies
    outside their best ``d``-dimensional subspace (0 on a flat d-manifold; large for a point
    floating between two sheets, whose neighbours lie on both sides)."""
    n, K = ind.shape
    out = np.zeros(n)
    for s, e in _chunks(n, K, X.shape[1]):
        P = (X[ind[s:e]] - X[s:e, None, :]) * mask[s:e, :, None]
        G = np.einsum("ckd,cld->ckl", P, P)  # K x K Gram: same non-zero spectrum as P^T P
        ev = np.linalg.eigvalsh(G)[:, ::-1]
        tot = ev.sum(axis=1)
        out[s:e] = np.where(tot > 0, ev[:, d:].clip(min=0).sum(axis=1) / np.where(tot > 0, tot, 1),
                            0.0)
    return out


def _scale_axes_to_edges(X: np.ndarray, Y: np.ndarray, Wm: sparse.spmatrix,
                         min_cos: float = 0.9) -> np.ndarray:
    """Rescale each embedding axis to the units of the data, from the neighbourhood-graph edges.

    LLE's constraint ``Y^T Y = n I`` fixes the axis scales arbitrarily (every axis gets unit
    variance, whatever the manifold's aspect ratio). For axis ``k``, take the edges ``(i, j)``
    whose embedded direction lies within ``arccos(min_cos)`` (25 deg) of that axis; the scale is
    the median of ``||x_i - x_j|| / |y_ik - y_jk|`` over them (a median, so that the non-uniform
    stretch LLE-type embeddings show along an axis does not dominate, as a least-squares fit over
    all edges let it do at n = 20,000). Axes with fewer than 10 aligned edges take the median
    ratio over all edges. Returns ``Y`` unchanged when no finite positive scale can be formed."""
    E = sparse.triu(Wm + Wm.T, k=1).tocoo()
    i, j = E.row, E.col
    if i.size == 0:
        return Y
    dx = np.linalg.norm(X[i] - X[j], axis=1)
    dy = Y[i] - Y[j]
    ny = np.linalg.norm(dy, axis=1)
    ok = ny > 0
    if not ok.any():
        return Y
    overall = float(np.median(dx[ok] / ny[ok]))
    scales = np.empty(Y.shape[1])
    for k in range(Y.shape[1]):
        a = ok & (np.abs(dy[:, k]) > min_cos * ny)
        scales[k] = np.median(dx[a] / np.abs(dy[a, k])) if a.sum() >= 10 else overall
    if not np.all(np.isfinite(scales)) or np.any(scales <= 0):
        return Y
    return Y * scales


def _pattern(Wm: sparse.spmatrix) -> sparse.csr_matrix:
    """The neighbourhood graph's edges (``i -> j`` when ``j`` is an accepted neighbour of
    ``i``) as a 0/1 matrix, whatever the weights (which may be negative or cancel)."""
    Wm = sparse.csr_matrix(Wm)
    return sparse.csr_matrix((np.ones(Wm.indices.size), Wm.indices, Wm.indptr), shape=Wm.shape)


def _graph_parts(Wm: sparse.spmatrix) -> tuple[int, np.ndarray, np.ndarray]:
    """Structure of the directed neighbourhood graph (``i -> j`` when ``j`` is an accepted
    neighbour of ``i``).

    Returns the number of weakly connected components, the component of each point, and the
    sizes of the *closed groups*: strongly connected sets of points that choose their neighbours
    only among themselves (no edge leaves them). Each component holds at least one. As every row
    of ``W`` sums to one, a vector that is constant on each closed group and extended to the
    other points by ``y_i = sum_j W_ij y_j`` has zero LLE cost: the null space of
    ``M = (I - W)^T (I - W)`` has one dimension per closed group, and with more than one the
    bottom eigenvectors collapse each group to a point instead of unfolding anything."""
    P = _pattern(Wm)
    n_comp, comp = csgraph.connected_components(P, directed=True, connection="weak")
    n_scc, scc = csgraph.connected_components(P, directed=True, connection="strong")
    E = P.tocoo()
    leaves = np.ones(n_scc, dtype=bool)
    leaves[scc[E.row[scc[E.row] != scc[E.col]]]] = False
    return n_comp, comp, np.bincount(scc, minlength=n_scc)[leaves]


def _component_basis(comp: np.ndarray, n_comp: int, k: int) -> np.ndarray:
    """The first ``min(k, n_comp)`` vectors of an orthonormal basis of the vectors constant on
    each component: the constant vector, then contrasts of the components in decreasing order of
    size. Entries are exactly equal within a component."""
    sizes = np.bincount(comp, minlength=n_comp).astype(float)
    order = np.argsort(-sizes, kind="stable")
    rank = np.empty(n_comp, dtype=int)
    rank[order] = np.arange(n_comp)
    s = sizes[order]
    A = np.eye(n_comp)[:, :-1]
    Q, _ = np.linalg.qr(np.column_stack([np.sqrt(s / s.sum()), A]))
    B = Q[:, :k] / np.sqrt(s)[:, None]  # orthonormal on the points: sum_c s_c B_cj B_cl = d_jl
    return B[rank[comp]]


def _axis_extent(X: np.ndarray, Y: np.ndarray, Wm: sparse.spmatrix, comp: np.ndarray,
                 n_comp: int) -> tuple[int, float, float]:
    """The axis whose extent within a connected component is largest relative to the total edge
    length of that component's neighbourhood graph (its minimum spanning tree): returns
    ``(axis, extent, tree length)``."""
    n = X.shape[0]
    P = _pattern(Wm)
    E = sparse.triu(P + P.T, k=1).tocoo()
    d = np.linalg.norm(X[E.row] - X[E.col], axis=1)
    T = csgraph.minimum_spanning_tree(sparse.csr_matrix((d, (E.row, E.col)), shape=(n, n)))
    T = T.tocoo()
    length = np.bincount(comp[T.row], weights=T.data, minlength=n_comp)
    lo = np.full((n_comp, Y.shape[1]), np.inf)
    hi = np.full((n_comp, Y.shape[1]), -np.inf)
    np.minimum.at(lo, comp, Y)
    np.maximum.at(hi, comp, Y)
    extent = hi - lo
    ratio = np.where(length[:, None] > 0, extent / np.where(length > 0, length, 1.0)[:, None],
                     0.0)
    c, k = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
    return int(k), float(extent[c, k]), float(length[c])


def _fix_signs(Y: np.ndarray) -> np.ndarray:
    """Make the largest-magnitude entry of each column positive (deterministic output)."""
    if Y.size == 0:
        return Y
    i = np.argmax(np.abs(Y), axis=0)
    signs = np.sign(Y[i, np.arange(Y.shape[1])])
    signs[signs == 0] = 1.0
    return Y * signs


def _sizes(sizes: np.ndarray, show: int = 5) -> str:
    """``"13, 19, 21"`` (at most ``show`` values, then ``", ..."``)."""
    s = ", ".join(str(int(v)) for v in sizes[:show])
    return s + (", ..." if sizes.size > show else "")


def _coincident(centers: np.ndarray, X: np.ndarray, dist: np.ndarray,
                ind: np.ndarray) -> np.ndarray:
    """Rows whose nearest candidate ``X[ind[:, 0]]`` is the same point as the center. Not from
    ``dist`` alone: scikit-learn's brute-force search (more than 15 features) takes
    ``|x|^2 + |y|^2 - 2 x.y``, which leaves identical points up to ~1e-5 apart (until
    2026-12-07 an exact duplicate in 1024-pixel images passed fit one time in eight, and
    transform moved 125 of 300 training images off their embedding)."""
    same = dist[:, 0] <= 0.0 if ind.shape[1] else np.zeros(ind.shape[0], dtype=bool)
    for s, e in _chunks(ind.shape[0] if ind.shape[1] else 0, 1, X.shape[1]):
        same[s:e] |= (X[ind[s:e, 0]] == centers[s:e]).all(axis=1)
    return same


def _weight_matrix(ind: np.ndarray, W: np.ndarray, mask: np.ndarray, n: int) -> sparse.csr_matrix:
    rows = np.repeat(np.arange(ind.shape[0]), ind.shape[1])
    f = mask.ravel()
    return sparse.csr_matrix((W.ravel()[f], (rows[f], ind.ravel()[f])), shape=(ind.shape[0], n))


# --------------------------------------------------------------------------- estimator


class NeighborhoodLinearEmbedding(ClassNamePrefixFeaturesOutMixin, TransformerMixin, BaseEstimator):
    """Neighborhood Linear Embedding: LLE with adaptively chosen neighbourhoods (thesis ch. 6).

    Reconstruction; see the module docstring for the rule and the literature followed. Each point
    takes its neighbours from its ``n_neighbors`` nearest candidates by the *shadow rule*
    (candidate ``x_j`` is dropped when an accepted closer neighbour ``x_k`` has
    ``||x_j - x_k|| < shadow * ||x_j - x_i||``), is reconstructed from them with constrained,
    regularised least-squares weights ``W``, and the embedding ``Y`` minimises
    ``sum_i ||y_i - sum_j W_ij y_j||^2`` with ``Y^T Y = n I`` and ``sum_i y_i = 0``: it is given by
    eigenvectors 2..d+1 (in increasing order of eigenvalue) of ``M = (I - W)^T (I - W)``, scaled
    to unit variance per coordinate and then (``axis_scaling="edges"``) per axis to the data's
    units.

    Parameters
    ----------
    n_components : int, default 2
        Dimension ``d`` of the embedding.
    n_neighbors : int, default 12
        Number of candidate neighbours per point (the largest neighbourhood allowed); must be
        larger than ``n_components``.
    shadow : float in [0, 1], default 0.3
        Strength of the shadow rule; 0 gives plain LLE with ``n_neighbors`` neighbours.
    reg : float > 0, default 1e-3
        Regularisation of the local Gram matrices, relative to their trace (with more
        neighbours than features a Gram matrix is singular, so 0 is not allowed).
    eigen_solver : {"auto", "arpack", "dense"}, default "auto"
        "arpack": ARPACK shift-invert around 0 with a sparse LU inverse (scales to 10^5 points);
        "dense": LAPACK on the dense ``M`` (n <= a few thousand); "auto": dense for n <= 200.
    tol : float, default 1e-6
        ARPACK tolerance.
    axis_scaling : {"edges", "unit"}, default "edges"
        "unit": LLE's normalisation, every coordinate zero-mean with unit variance. "edges": then
        rescale each axis so that the lengths of the neighbourhood-graph edges in the embedding
        match those in the input (median length ratio of the edges aligned with the axis): the
        embedding keeps the manifold's aspect ratio, in the units of X. This step, not the
        neighbour rule, is what lifts trustworthiness above scikit-learn's LLE variants on the
        swiss roll and S-curve (0.9997 / 0.9998 vs 0.9970 / 0.9965 at n = 2000, see
        bench/nle.py); it would help any LLE-type embedding alike. On a badly undersampled
        manifold it changes little (500-point swiss roll: 0.8485 vs 0.8498 with "unit").
        An axis that would span more than 10 times the total edge length of the neighbourhood
        graph (its minimum spanning tree) is the mark of a degenerate embedding, where a group
        of points is barely tied to the rest, and raises :class:`ManifoldInputError`. So does a
        graph with more groups of points that choose their neighbours only among themselves
        than connected components (see below), whatever the coordinates (until 2026-12-03 only
        when they spanned that much, which depended on the eigensolver's basis of the null
        space: scipy 1.11 let one through).
    random_state : int, RandomState or None
        Seeds ARPACK's start vector.
    n_jobs : int or None
        Parallel jobs of the neighbour search (``sklearn.neighbors.NearestNeighbors``).

    A neighbourhood graph that falls apart is reported by a :class:`DisconnectedGraphWarning`.
    With several connected components the embedding separates them instead of unfolding them:
    its first axes are constant on each component (contrasts of the components, largest first),
    the rest are the next eigenvectors. Groups of points that choose their neighbours only among
    themselves (more of them than components) leave the LLE cost without a tie between them, and
    the embedding collapses each group to a point (``axis_scaling="unit"``, with the warning;
    ``"edges"`` raises :class:`ManifoldInputError`).

    Attributes
    ----------
    embedding_ : (n_samples, n_components) array
        The embedding of the training points (zero mean; per-axis scale as ``axis_scaling``).
    adjacency_ : sparse (n_samples, n_samples) CSR matrix
        Reconstruction weights; row ``i`` holds the weights of point ``i``'s accepted neighbours.
    n_neighbors_ : (n_samples,) int array
        Number of accepted neighbours per point.
    reconstruction_error_ : float
        Sum of the ``n_components`` eigenvalues used (the LLE cost of the unscaled embedding).
    n_features_in_ : int
    nbrs_ : NearestNeighbors
        Fitted on the (centred) training data; used by :meth:`transform`.
    training_data_ : (n_samples, n_features) array
        The training points less ``offset_`` (centred since 2026-12-02, see
        :meth:`_centred`; a model saved before has no ``offset_`` and uncentred points).
    offset_ : (n_features,) array
        The training points' mean, subtracted from X in fit and from new points in
        :meth:`transform` (and ClusteredNLE's :meth:`predict`).

    Examples
    --------
    >>> from sklearn.datasets import make_swiss_roll
    >>> from hearsee.learn import NeighborhoodLinearEmbedding
    >>> X, t = make_swiss_roll(1000, random_state=0)
    >>> Y = NeighborhoodLinearEmbedding(n_components=2, random_state=0).fit_transform(X)
    >>> Y.shape
    (1000, 2)
    """

    _parameter_constraints: dict = {
        "n_components": [Interval(Integral, 1, None, closed="left")],
        "n_neighbors": [Interval(Integral, 1, None, closed="left")],
        "shadow": [Interval(Real, 0, 1, closed="both")],
        "reg": [Interval(Real, 0, None, closed="neither")],
        "eigen_solver": [StrOptions({"auto", "arpack", "dense"})],
        "tol": [Interval(Real, 0, None, closed="left")],
        "axis_scaling": [StrOptions({"edges", "unit"})],
        "random_state": ["random_state"],
        # (0 passed and joblib refused it at fit: "n_jobs == 0 in Parallel has no meaning")
        "n_jobs": [Interval(Integral, None, -1, closed="right"),
                   Interval(Integral, 1, None, closed="left"), None],
    }

    def __init__(
        self,
        n_components: int = 2,
        *,
        n_neighbors: int = 12,
        shadow: float = 0.3,
        reg: float = 1e-3,
        eigen_solver: str = "auto",
        tol: float = 1e-6,
        axis_scaling: str = "edges",
        random_state=None,
        n_jobs: int | None = None,
    ) -> None:
        self.n_components = n_components
        self.n_neighbors = n_neighbors
        self.shadow = shadow
        self.reg = reg
        self.eigen_solver = eigen_solver
        self.tol = tol
        self.axis_scaling = axis_scaling
        self.random_state = random_state
        self.n_jobs = n_jobs

    # -- validation ---------------------------------------------------------------------------

    def _validate_fit_input(self, X) -> np.ndarray:
        _check_params(self)
        if self.n_neighbors <= self.n_components:
            raise ManifoldInputError(
                f"n_neighbors={self.n_neighbors} must be > n_components={self.n_components}: a "
                f"point is reconstructed from its neighbours, and {self.n_components + 1} of them "
                f"are needed to span a {self.n_components}-dimensional patch"
            )
        X = _validated(self, X, ensure_min_samples=2)
        with np.errstate(over="ignore", invalid="ignore"):
            r = np.ptp(X, axis=0)
            top = float(np.max(r))  # scaled, so that a span of 1e-200 does not underflow to 0
            span = top * float(np.linalg.norm(r / top)) if 0.0 < top < np.inf else top
        if not span <= _MAX_SPAN:
            raise ManifoldInputError(
                f"values too large: the points of X span {span:.3g}, squared distances between "
                f"them overflow float64 beyond {_MAX_SPAN:.0e}; rescale X, e.g. "
                "X / np.abs(X).max()"
            )
        if 0.0 < span < _MIN_SPAN:
            raise ManifoldInputError(
                f"values too small: the points of X span {span:.3g}, squared distances between "
                f"them underflow float64 below {_MIN_SPAN:.0e}; rescale X, e.g. "
                "X / np.abs(X).max()"
            )
        if self.n_components > X.shape[1]:
            raise ManifoldInputError(
                f"n_components={self.n_components} must not exceed the data's dimension "
                f"(n_features = {X.shape[1]}): an embedding has at most as many axes as the "
                "space the points lie in"
            )
        n = X.shape[0]
        if self.n_neighbors >= n:
            raise ManifoldInputError(
                f"n_neighbors={self.n_neighbors} must be smaller than the number of samples "
                f"(n_samples = {n}); lower n_neighbors or give more points"
            )
        if self.n_components >= n:
            raise ManifoldInputError(
                f"n_components={self.n_components} must be smaller than the number of samples "
                f"(n_samples = {n})"
            )
        return X

    @staticmethod
    def _check_duplicates(X: np.ndarray, dist: np.ndarray, ind: np.ndarray) -> None:
        zero = _coincident(X, X, dist, ind)
        if zero.any():
            i = int(np.flatnonzero(zero)[0])
            raise ManifoldInputError(
                f"X contains {int(zero.sum())} points that duplicate another point (e.g. rows {i} "
                f"and {int(ind[i, 0])}); reconstruction weights are undefined for them. Remove "
                "duplicates first, e.g. X = np.unique(X, axis=0)"
            )

    # -- core ---------------------------------------------------------------------------------

    def _neighbourhoods(self, X: np.ndarray, n_neighbors: int):
        """Fit the candidate search on X; return (nbrs, dist, ind, mask) without self."""
        nbrs = NearestNeighbors(n_neighbors=n_neighbors + 1, n_jobs=self.n_jobs).fit(X)
        dist, ind = nbrs.kneighbors(X)
        # drop self: it is normally column 0, but ties may reorder it
        is_self = ind == np.arange(X.shape[0])[:, None]
        keep = ~is_self
        keep[keep.sum(axis=1) > n_neighbors, -1] = False
        dist = dist[keep].reshape(X.shape[0], n_neighbors)
        ind = ind[keep].reshape(X.shape[0], n_neighbors)
        self._check_duplicates(X, dist, ind)
        mask = adaptive_neighbors(X, ind, dist, self.shadow,
                                  min_neighbors=self.n_components + 1)
        return nbrs, dist, ind, mask

    def _embed(self, X, ind, W, mask, n, random_state, warn=True, where=""):
        """Embedding from the weights; returns (Y, W sparse, error).

        A neighbourhood graph with several connected components gives exact zero-cost vectors,
        constant on each component; they are set explicitly (contrasts of the components, so
        the corresponding axes separate the components and carry no noise within them) and the
        remaining axes are the next eigenvectors of the components, each on its own component
        (see :meth:`_split_eigenvectors`). ``warn`` controls the disconnected-graph warning;
        ``where`` prefixes the messages (e.g. the cluster of ClusteredNLE)."""
        Wm = _weight_matrix(ind, W, mask, n)
        n_comp, comp, closed = _graph_parts(Wm)
        if warn and n_comp > 1:
            warnings.warn(
                f"{where}the neighbourhood graph has {n_comp} connected components; the "
                "embedding separates them instead of unfolding them. Use ClusteredNLE to embed "
                "each component, or raise n_neighbors / lower shadow",
                DisconnectedGraphWarning,
                stacklevel=3,
            )
        degenerate = closed.size > n_comp
        if degenerate:
            warnings.warn(
                f"{where}{closed.size} groups of points (sizes {_sizes(closed)}) choose their "
                f"neighbours only among themselves, more than the {n_comp} connected "
                "component(s) of the neighbourhood graph: the LLE cost does not tie them "
                "together and the embedding collapses each group to a point. Raise n_neighbors "
                "or lower shadow",
                DisconnectedGraphWarning,
                stacklevel=3,
            )
        if degenerate and self.axis_scaling == "edges":
            # (decided from the graph, not from the coordinates: the eigensolver returns an
            # arbitrary basis of the null space, which scipy 1.11 happened to spread over only
            # 2.4 times the edge length where 1.17 gave 2.7e6, so the extent test below let it
            # through)
            raise ManifoldInputError(
                f"{where}degenerate embedding: {closed.size} groups of points (sizes "
                f"{_sizes(closed)}) choose their neighbours only among themselves, more than the "
                f"{n_comp} connected component(s) of the neighbourhood graph, which leaves their "
                "placement free (the LLE cost has a null vector per group). Raise n_neighbors or "
                "lower shadow (axis_scaling='unit' returns LLE's unscaled coordinates)"
            )
        A = sparse.eye(n, format="csr") - Wm
        M = (A.T @ A).tocsr()
        k = self.n_components + 1
        if n_comp == 1:
            vals, vecs = _bottom_eigenvectors(M, k, self._solver(n, k), self.tol, random_state)
        else:
            vals, vecs = self._split_eigenvectors(M, comp, n_comp, k, random_state)
        Y = _fix_signs(vecs[:, 1:k] * np.sqrt(n))
        if self.axis_scaling == "edges":
            Y = _scale_axes_to_edges(X, Y, Wm)
            axis, extent, length = _axis_extent(X, Y, Wm, comp, n_comp)
            if extent > _MAX_AXIS_EXTENT * length:
                raise ManifoldInputError(
                    f"{where}degenerate embedding: axis {axis + 1} spans {extent:.3g} in the "
                    f"units of X, more than {_MAX_AXIS_EXTENT:g} times the total edge length of "
                    f"the neighbourhood graph ({length:.3g}); some points are tied to the rest "
                    "by very few or very weak edges. Raise n_neighbors or lower shadow "
                    "(axis_scaling='unit' returns LLE's unscaled coordinates)"
                )
        return Y, Wm, float(np.sum(vals[1:k]))

    def _solver(self, n: int, k: int) -> str:
        """The eigensolver for ``k`` eigenpairs of an ``n x n`` matrix."""
        solver = self.eigen_solver
        if solver == "auto":
            solver = "dense" if n <= 200 else "arpack"
        if solver == "arpack" and k >= n - 1:
            solver = "dense"
        return solver

    def _split_eigenvectors(self, M, comp: np.ndarray, n_comp: int, k: int, random_state):
        """The ``k`` bottom eigenpairs of the block-diagonal ``M`` of a graph with ``n_comp``
        components: first the exact null vectors constant on each component (the constant, then
        the contrasts), then the lowest non-constant eigenvectors of the blocks, each computed on
        its own block and zero elsewhere (a solver run on the whole of ``M`` returns an arbitrary,
        noisy basis of the null space and mixes blocks whose eigenvalues coincide)."""
        n = M.shape[0]
        vecs = [_component_basis(comp, n_comp, min(k, n_comp))]
        m = k - n_comp  # non-constant vectors needed
        if m <= 0:
            return np.zeros(k), vecs[0]
        cand_vals, cand_vecs = [], []
        for c in range(n_comp):
            idx = np.flatnonzero(comp == c)
            kc = min(m + 1, idx.size)
            if kc < 2:
                continue
            Mc = M[idx][:, idx]
            _, V = _bottom_eigenvectors(Mc, kc, self._solver(idx.size, kc), self.tol,
                                        random_state)
            # drop the block's constant null vector; Rayleigh-Ritz on the rest of the span
            U = np.linalg.svd(V - V.mean(axis=0), full_matrices=False)[0][:, : kc - 1]
            H = U.T @ (Mc @ U)
            rv, rV = np.linalg.eigh(0.5 * (H + H.T))
            for j in range(kc - 1):
                v = np.zeros(n)
                v[idx] = U @ rV[:, j]
                cand_vals.append(rv[j])
                cand_vecs.append(v)
        order = np.argsort(cand_vals, kind="stable")[:m]
        vals = np.r_[np.zeros(n_comp), np.asarray(cand_vals)[order]]
        return vals, np.column_stack(vecs + [cand_vecs[i] for i in order])

    def _fit_embedding(self, X: np.ndarray, random_state) -> None:
        # the fitted attributes are set together at the end: a fit that raises leaves the
        # previous fit whole (transform indexes embedding_ by nbrs_'s neighbours)
        n = X.shape[0]
        nbrs, dist, ind, mask = self._neighbourhoods(X, self.n_neighbors)
        W = reconstruction_weights(X, ind, mask, self.reg)
        Y, Wm, err = self._embed(X, ind, W, mask, n, random_state)
        self.nbrs_, self.training_data_ = nbrs, X
        self.embedding_, self.adjacency_, self.reconstruction_error_ = Y, Wm, err
        self.n_neighbors_ = mask.sum(axis=1)

    @_input_attributes_kept_on_error
    def fit(self, X, y=None):
        """Compute the embedding of X (n_samples, n_features). ``y`` is ignored."""
        X = self._validate_fit_input(X)
        offset = X.mean(axis=0)
        self._fit_embedding(X - offset, check_random_state(self.random_state))
        self.offset_ = offset
        return self

    def _centred(self, X: np.ndarray) -> np.ndarray:
        """``X`` less the training data's mean ``offset_``: fit works on centred data (the
        embedding does not depend on a translation). scikit-learn's brute-force neighbour
        search (more than 15 features) takes ``|x|^2 + |y|^2 - 2 x.y``, which cancels to 0 for
        nearby points far from the origin: a swiss roll in 60 dimensions moved by 1e6 had "6
        points that duplicate another point" (its nearest pair is 0.049 apart)."""
        return X - getattr(self, "offset_", 0.0)

    def fit_transform(self, X, y=None) -> np.ndarray:
        """Fit and return ``embedding_``."""
        return self.fit(X).embedding_

    def _reconstruct(self, X: np.ndarray, train: np.ndarray, nbrs: NearestNeighbors):
        """Out-of-sample neighbourhoods and weights of X among the training points ``train``
        (``nbrs`` is fitted on them): the same candidate search, shadow rule and weights as in
        fit. Returns ``(ind, W, mask)``, ``ind`` indexing ``train``."""
        k = min(self.n_neighbors, train.shape[0])
        dist, ind = nbrs.kneighbors(X, n_neighbors=k)
        far = ~(dist[:, -1] <= _MAX_SPAN)
        if far.any():
            raise ManifoldInputError(
                f"values too large: {int(far.sum())} points of X (e.g. row "
                f"{int(np.flatnonzero(far)[0])}) lie farther than {_MAX_SPAN:.0e} from the "
                "training data, where squared distances overflow float64"
            )
        mask = adaptive_neighbors(train, ind, dist, self.shadow,
                                  min_neighbors=self.n_components + 1, centers=X)
        W = reconstruction_weights(train, ind, mask, self.reg, centers=X)
        exact = _coincident(X, train, dist, ind)  # a training point: use its embedding
        W[exact] = 0.0
        W[exact, 0] = 1.0
        mask[exact] = False
        mask[exact, 0] = True
        return ind, W, mask

    @property
    def _n_features_out(self) -> int:
        """The embedding's dimensions, for ``get_feature_names_out``: the class's name in
        lower case and the axis (``neighborhoodlinearembedding0``, ...), as scikit-learn's
        ``LocallyLinearEmbedding`` names its own (without it, ``set_output(transform="pandas")``
        was an AttributeError)."""
        return self.embedding_.shape[1]

    def transform(self, X) -> np.ndarray:
        """Embed new points: reconstruct each from its adaptive neighbourhood among the training
        points (the same shadow rule and weights as in fit) and apply the weights to the training
        embedding, ``y = sum_j w_j y_j`` (LLE's out-of-sample map, Saul & Roweis 2003, sec. 6.1).
        """
        _check_fitted(self, "embedding_")
        self._restore_fitted_state()
        X = self._centred(_validated(self, X, reset=False))
        ind, W, mask = self._reconstruct(X, self.training_data_, self.nbrs_)
        return np.einsum("nk,nkd->nd", W * mask, self.embedding_[ind])

    # -- models saved by older versions -------------------------------------------------------

    def _restore_fitted_state(self) -> None:
        """Fill in the fitted attributes :meth:`transform` needs that a model saved (pickled,
        joblib) by an older hearsee lacks, rebuilt exactly from what the model stores:
        ``training_data_`` (kept since 2026-11-22; before, transform read the same array from
        ``nbrs_``, where ``NearestNeighbors`` keeps its training points). Rebuilt on the first
        transform and kept.

        Raises
        ------
        ManifoldInputError
            An attribute is missing and cannot be rebuilt: the model must be re-fitted.
        """
        if not hasattr(self, "training_data_"):
            train = getattr(self.nbrs_, "_fit_X", None)
            if train is None:
                raise self._refit_error("training_data_")
            self.training_data_ = train

    def _refit_error(self, attribute: str) -> ManifoldInputError:
        return ManifoldInputError(
            f"this {type(self).__name__} was saved by an older hearsee and lacks {attribute}, "
            "which transform needs; re-fit the model"
        )

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.transformer_tags.preserves_dtype = ["float64"]
        return tags


class ClusteredNLE(NeighborhoodLinearEmbedding):
    """Clustered NLE (CNLE, thesis 6.1.2): split the data into the connected components of the
    adaptive neighbourhood graph and embed each component with NLE.

    Reconstruction; see the module docstring for the three bridge guards (mutual edges, an edge
    length limit relative to the local scale of both ends, and core points with a locally
    ``d``-dimensional neighbourhood) and how non-core points are assigned. Each cluster is embedded
    separately, so the coordinates of different clusters share axes but not a frame: read them
    together with ``labels_``. An estimator of its own (not an option of
    :class:`NeighborhoodLinearEmbedding`) because it adds ``labels_``, :meth:`predict` and
    :meth:`fit_predict`. Its defaults differ: ``n_neighbors=8`` and ``shadow=0.5`` (smaller,
    sparser neighbourhoods bridge less; measured on the two rolls of :func:`make_two_rolls`).

    Limitation (found 2026-12-07, not solved): curves (``n_components=1``) sampled at random
    split at their wider gaps -- a gap longer than the span of the ``n_neighbors`` candidates
    on its far side is chosen from one end only, and guard 1 cuts it. Two random helices of
    500 points each, 20 apart, gave 10-14 clusters (adjusted Rand index 0.18-0.29;
    ``n_neighbors=12``: 4-6), evenly spaced ones 2; surfaces (``n_components=2``) of random
    points were not split.

    Parameters
    ----------
    n_components, n_neighbors, shadow, reg, eigen_solver, tol, axis_scaling, random_state, n_jobs
        As in :class:`NeighborhoodLinearEmbedding` (defaults ``n_neighbors=8``, ``shadow=0.5``).
        ``n_components`` is also the dimension ``d`` of the core-point test.
    min_cluster_size : int, default 20
        Components of core points with fewer points do not form clusters of their own. At
        most the number of samples fitted: a larger one can never be met, and ``fit`` raises
        :class:`ManifoldInputError` naming both numbers (as for ``n_neighbors``; until
        2026-12-03 every point silently became one cluster).
    bridge_ratio : float, default 3.0
        A mutual edge longer than this many times the median accepted-neighbour distance of
        either end is cut.
    max_off_plane : float in [0, 1], default 0.3
        Core-point test: the largest fraction of a point's neighbour-offset energy allowed outside
        its best ``n_components``-dimensional subspace.

    Attributes
    ----------
    labels_ : (n_samples,) int array
        Cluster of each training point, 0..n_clusters_-1, in decreasing order of cluster size.
    n_clusters_ : int
    embedding_ : (n_samples, n_components) array
        Per-cluster NLE coordinates (each cluster zero-mean, axes scaled as ``axis_scaling``).
    cluster_nbrs_ : list of NearestNeighbors or None
        Per cluster, the search fitted on its training points (in the order of
        ``np.flatnonzero(labels_ == c)``; None for a cluster too small to embed); used by
        :meth:`transform`.
    adjacency_, n_neighbors_, reconstruction_error_, nbrs_, training_data_, n_features_in_
        As in :class:`NeighborhoodLinearEmbedding` (``adjacency_`` holds the per-cluster weights;
        the error is summed over clusters).

    Examples
    --------
    >>> from hearsee.learn import ClusteredNLE, make_two_rolls
    >>> X, sheet, _ = make_two_rolls(2000, noise=0.1, outliers=0.02, random_state=0)
    >>> cnle = ClusteredNLE(random_state=0).fit(X)
    >>> cnle.n_clusters_
    2
    """

    _parameter_constraints: dict = {
        **NeighborhoodLinearEmbedding._parameter_constraints,
        "min_cluster_size": [Interval(Integral, 1, None, closed="left")],
        "bridge_ratio": [Interval(Real, 0, None, closed="neither")],
        "max_off_plane": [Interval(Real, 0, 1, closed="both")],
    }

    def __init__(
        self,
        n_components: int = 2,
        *,
        n_neighbors: int = 8,
        shadow: float = 0.5,
        reg: float = 1e-3,
        eigen_solver: str = "auto",
        tol: float = 1e-6,
        axis_scaling: str = "edges",
        random_state=None,
        n_jobs: int | None = None,
        min_cluster_size: int = 20,
        bridge_ratio: float = 3.0,
        max_off_plane: float = 0.3,
    ) -> None:
        super().__init__(
            n_components,
            n_neighbors=n_neighbors,
            shadow=shadow,
            reg=reg,
            eigen_solver=eigen_solver,
            tol=tol,
            axis_scaling=axis_scaling,
            random_state=random_state,
            n_jobs=n_jobs,
        )
        self.min_cluster_size = min_cluster_size
        self.bridge_ratio = bridge_ratio
        self.max_off_plane = max_off_plane

    def _cluster(self, X, dist, ind, mask) -> np.ndarray:
        n = X.shape[0]
        rows = np.repeat(np.arange(n), ind.shape[1])
        f = mask.ravel()
        r, c, d = rows[f], ind.ravel()[f], dist.ravel()[f]
        # local scale: median accepted-neighbour distance
        dm = np.where(mask, dist, np.nan)
        scale = np.nanmedian(dm, axis=1)
        A = sparse.csr_matrix((np.ones(r.size), (r, c)), shape=(n, n))
        mutual = A.multiply(A.T).tocoo()
        keep = mutual.row < mutual.col
        i, j = mutual.row[keep], mutual.col[keep]
        dij = np.linalg.norm(X[i] - X[j], axis=1)
        ok = dij <= self.bridge_ratio * np.minimum(scale[i], scale[j])
        i, j = i[ok], j[ok]
        # core points: at least d + 1 mutual neighbours and a locally d-dimensional neighbourhood;
        # the rest (noise, points between sheets) only join a cluster afterwards
        degree = np.bincount(i, minlength=n) + np.bincount(j, minlength=n)
        core = (degree >= self.n_components + 1) & (
            _off_plane_fraction(X, ind, mask, self.n_components) <= self.max_off_plane
        )
        both = core[i] & core[j]
        G = sparse.csr_matrix((np.ones(int(both.sum())), (i[both], j[both])), shape=(n, n))
        del d
        _, comp = csgraph.connected_components(G, directed=False)
        sizes = np.bincount(comp)
        min_size = max(self.min_cluster_size, self.n_components + 2)
        big = (sizes[comp] >= min_size) & core
        comp = np.where(big, comp, -1)
        # the others (noise, small pieces) take the majority label of their accepted neighbours,
        # spreading outwards from the large components; a component of the neighbourhood graph
        # that no cluster reaches is a cluster of its own when large enough; what is still
        # unreached takes the label of its nearest labelled point
        rows = np.repeat(np.arange(n), ind.shape[1])
        f = mask.ravel()
        S = sparse.csr_matrix((np.ones(int(f.sum())), (rows[f], ind.ravel()[f])), shape=(n, n))
        S = (S + S.T).tocsr()
        n_lab = int(comp.max()) + 1
        for _ in range(50):
            todo = comp < 0
            if not todo.any():
                break
            onehot = sparse.csr_matrix(
                (np.ones(int((~todo).sum())), (np.flatnonzero(~todo), comp[~todo])),
                shape=(n, n_lab),
            )
            votes = (S[todo] @ onehot).toarray()
            has = votes.sum(axis=1) > 0
            if not has.any():
                break
            idx = np.flatnonzero(todo)[has]
            comp[idx] = np.argmax(votes[has], axis=1)
        todo = comp < 0
        if todo.any():
            # (a component without core points -- noisy or higher-dimensional data, a curve with
            # n_components=2 -- took the nearest cluster's label until 2026-12-08, and without
            # any core point all points formed one cluster: two blobs 100 apart in 10-D, ARI 0)
            _, part = csgraph.connected_components(S, directed=False)
            reached = np.zeros(int(part.max()) + 1, dtype=bool)
            reached[part[~todo]] = True
            new = todo & ~reached[part] & (np.bincount(part)[part] >= min_size)
            comp[new] = n_lab + part[new]
            todo = comp < 0
        if todo.all():
            return np.zeros(n, dtype=int)
        if todo.any():
            nn = NearestNeighbors(n_neighbors=1, n_jobs=self.n_jobs).fit(X[~todo])
            _, near = nn.kneighbors(X[todo])
            comp[todo] = comp[np.flatnonzero(~todo)[near[:, 0]]]
        # relabel 0..k-1 by decreasing size
        uniq, inv, counts = np.unique(comp, return_inverse=True, return_counts=True)
        order = np.argsort(-counts, kind="stable")
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        return rank[inv]

    def _validate_fit_input(self, X) -> np.ndarray:
        X = super()._validate_fit_input(X)
        n = X.shape[0]
        if self.min_cluster_size > n:
            raise ManifoldInputError(
                f"min_cluster_size={self.min_cluster_size} must not exceed the number of "
                f"samples (n_samples = {n}): no cluster can be that large, and every point "
                "would fall into one cluster; lower min_cluster_size or give more points"
            )
        return X

    @_input_attributes_kept_on_error
    def fit(self, X, y=None):
        """Cluster X by the adaptive neighbourhood graph and embed each cluster."""
        X = self._validate_fit_input(X)
        offset = X.mean(axis=0)  # (centred, see NeighborhoodLinearEmbedding._centred)
        X = X - offset
        rs = check_random_state(self.random_state)
        n = X.shape[0]
        # the fitted attributes are set together at the end (see _fit_embedding)
        nbrs, dist, ind, mask = self._neighbourhoods(X, self.n_neighbors)
        labels = self._cluster(X, dist, ind, mask)
        n_clusters = int(labels.max()) + 1
        Y = np.zeros((n, self.n_components))
        blocks = []
        cluster_nbrs: list[NearestNeighbors | None] = []
        counts = np.zeros(n, dtype=int)
        err = 0.0
        for c in range(n_clusters):
            idx = np.flatnonzero(labels == c)
            m = idx.size
            Xc = X[idx]
            nn = self._cluster_search(Xc)
            cluster_nbrs.append(nn)
            if nn is None:
                blocks.append(sparse.csr_matrix((m, n)))
                continue
            dc, ic = nn.kneighbors(Xc)
            dc, ic = dc[:, 1:], ic[:, 1:]
            mc = adaptive_neighbors(Xc, ic, dc, self.shadow, min_neighbors=self.n_components + 1)
            Wc = reconstruction_weights(Xc, ic, mc, self.reg)
            Yc, Wmc, e, kept = self._embed_cluster(Xc, ic, Wc, mc, rs, where=f"cluster {c}: ")
            Y[idx] = Yc
            err += e
            counts[idx] = kept
            Wmc = Wmc.tocoo()
            blocks.append((idx[Wmc.row], idx[Wmc.col], Wmc.data))
        r = np.concatenate([b[0] for b in blocks if isinstance(b, tuple)] or [np.zeros(0, int)])
        c = np.concatenate([b[1] for b in blocks if isinstance(b, tuple)] or [np.zeros(0, int)])
        v = np.concatenate([b[2] for b in blocks if isinstance(b, tuple)] or [np.zeros(0)])
        self.nbrs_, self.training_data_ = nbrs, X
        self.labels_, self.n_clusters_, self.cluster_nbrs_ = labels, n_clusters, cluster_nbrs
        self.adjacency_ = sparse.csr_matrix((v, (r, c)), shape=(n, n))
        self.embedding_ = Y
        self.n_neighbors_ = counts
        self.reconstruction_error_ = err
        self.offset_ = offset
        return self

    def _embed_cluster(self, Xc, ic, Wc, mc, rs, where):
        """NLE of one cluster from its neighbourhoods; returns ``(Y, W sparse, error, accepted
        neighbour counts)``. When the cluster's neighbourhood graph falls apart (a small piece
        far away took the cluster's label, see :meth:`_cluster`), the largest piece is embedded
        alone and the others are placed by the out-of-sample map of :meth:`transform`: embedded
        together, the first axis only told the pieces apart and the cluster itself kept one
        axis (until 2026-12-08)."""
        m = Xc.shape[0]
        n_pc, pc = csgraph.connected_components(_pattern(_weight_matrix(ic, Wc, mc, m)),
                                                directed=True, connection="weak")
        sizes = np.bincount(pc)
        if n_pc == 1 or sizes.max() <= self.n_components + 1:
            return (*self._embed(Xc, ic, Wc, mc, m, rs, warn=False, where=where), mc.sum(axis=1))
        main = pc == np.argmax(sizes)
        keep, rest = np.flatnonzero(main), np.flatnonzero(~main)
        pos = np.zeros(m, dtype=int)
        pos[keep] = np.arange(keep.size)  # (the main piece's accepted neighbours are its own)
        Ym, Wm, err = self._embed(Xc[keep], pos[ic[keep]], Wc[keep], mc[keep], keep.size, rs,
                                  warn=False, where=where)
        nn = NearestNeighbors(n_jobs=self.n_jobs).fit(Xc[keep])
        ir, Wr, mr = self._reconstruct(Xc[rest], Xc[keep], nn)
        Y = np.zeros((m, self.n_components))
        Y[keep] = Ym
        Y[rest] = np.einsum("nk,nkd->nd", Wr * mr, Ym[ir])
        Y -= Y.mean(axis=0)  # (each cluster zero-mean, as documented)
        Wm, Wr = Wm.tocoo(), _weight_matrix(ir, Wr, mr, keep.size).tocoo()
        W = sparse.csr_matrix((np.r_[Wm.data, Wr.data], (np.r_[keep[Wm.row], rest[Wr.row]],
                                                         keep[np.r_[Wm.col, Wr.col]])),
                              shape=(m, m))
        kept = np.zeros(m, dtype=int)
        kept[keep], kept[rest] = mc[keep].sum(axis=1), mr.sum(axis=1)
        return Y, W, err, kept

    def _cluster_search(self, Xc: np.ndarray) -> NearestNeighbors | None:
        """The candidate search of one cluster's training points ``Xc`` as fit builds it (its
        ``n_neighbors`` nearest, self excluded); None for a cluster too small to embed."""
        m = Xc.shape[0]
        if m <= self.n_components + 1:
            return None
        k = min(self.n_neighbors, m - 1)
        return NearestNeighbors(n_neighbors=k + 1, n_jobs=self.n_jobs).fit(Xc)

    def _restore_fitted_state(self) -> None:
        """As in :class:`NeighborhoodLinearEmbedding`, and ``cluster_nbrs_`` (kept since
        2026-11-26): rebuilt from ``training_data_`` and ``labels_`` as fit builds it (with the
        parameters the model holds, those it was fitted with unless changed since)."""
        super()._restore_fitted_state()
        if not hasattr(self, "cluster_nbrs_"):
            self.cluster_nbrs_ = [self._cluster_search(self.training_data_[self.labels_ == c])
                                  for c in range(self.n_clusters_)]

    def fit_predict(self, X, y=None) -> np.ndarray:
        """Fit and return ``labels_``."""
        return self.fit(X).labels_

    def predict(self, X) -> np.ndarray:
        """Cluster of new points: that of their nearest training point."""
        _check_fitted(self, "labels_")
        X = self._centred(_validated(self, X, reset=False))
        _, ind = self.nbrs_.kneighbors(X, n_neighbors=1)
        return self.labels_[ind[:, 0]]

    def transform(self, X) -> np.ndarray:
        """Embed new points in the frame of their cluster (see :meth:`predict`): reconstruct each
        from its adaptive neighbourhood among that cluster's training points, as fit embedded
        the cluster (NLE on the cluster alone): the ``n_neighbors`` nearest candidates of the
        cluster, then the shadow rule among them. Points of a cluster too small to embed (its
        coordinates are 0) get 0.

        Until 2026-11-26 the candidates were the nearest of all training points and the shadow rule
        ran over them before the other clusters' points were dropped: those took candidate
        places and shadowed the cluster's own points, leaving points near another cluster
        (a sparse sheet beside a dense one) with fewer or other neighbours than fit gives them.
        """
        _check_fitted(self, "embedding_")
        self._restore_fitted_state()
        X = self._centred(_validated(self, X, reset=False))
        _, near = self.nbrs_.kneighbors(X, n_neighbors=1)
        lab = self.labels_[near[:, 0]]
        Y = np.zeros((X.shape[0], self.n_components))
        for c in np.unique(lab):
            nbrs = self.cluster_nbrs_[c]
            if nbrs is None:
                continue
            q = lab == c
            idx = np.flatnonzero(self.labels_ == c)
            ind, W, mask = self._reconstruct(X[q], self.training_data_[idx], nbrs)
            Y[q] = np.einsum("nk,nkd->nd", W * mask, self.embedding_[idx][ind])
        return Y


# --------------------------------------------------------------------------- data


def _angle_range(name: str, value) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        msg = f"{name} must be two numbers (low, high) in degrees, got {value!r}"
        raise ConfigError(msg) from None
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise ConfigError(f"{name} must be two finite numbers in degrees, got {value!r}")
    return lo, hi


def make_two_rolls(
    n_samples: int = 2000,
    *,
    density_ratio: float = 6.0,
    gap: float = np.pi,
    noise: float = 0.0,
    outliers: float = 0.0,
    height: float = 10.0,
    random_state=None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two swiss-roll sheets wound together (thesis fig. 6.7, reconstruction of the data set).

    Sheet 0 follows the spiral ``r = t`` (``t`` from 1.5 pi to 3.5 pi, one full turn), sheet 1
    the same spiral pushed ``gap`` outwards along its normal (the default, pi, puts it halfway
    between the turns of sheet 0). Points are uniform by area on each sheet (uniform in the
    sheet's own arc length and in height; until 2026-11-26 sheet 1 was uniform in the arc length
    of sheet 0, up to 1.3 times denser at its outer end than at its inner one); sheet 0 holds
    ``density_ratio`` times as many points as sheet 1 (sheet 1 is 1.4 times larger at the
    default gap), and ``outliers`` adds noise points uniform in the
    bounding box (label -1) that chain the sheets together in any fixed-K neighbour graph.

    Parameters
    ----------
    n_samples : int
        Number of points on the two sheets (outliers come on top).
    density_ratio : float
        Ratio of the number of points on sheet 0 to sheet 1.
    gap : float
        Normal distance between the sheets (same units as the spiral radius); negative: sheet 1
        inside sheet 0, by less than the spiral's smallest radius of curvature (4.6).
    noise : float
        Standard deviation of isotropic Gaussian noise added to the sheet points.
    outliers : float
        Number of extra noise points, as a fraction of ``n_samples``.
    height : float
        Extent along the roll axis (y).
    random_state : int, RandomState or None

    Returns
    -------
    X : (n_samples + n_outliers, 3) array
    labels : (n_samples + n_outliers,) int array
        Sheet of each point (0 dense, 1 sparse, -1 outlier).
    t : (n_samples + n_outliers, 2) array
        Intrinsic coordinates: arc length along the point's sheet (from the sheet's inner end)
        and height (NaN for outliers). Until 2026-11-26 sheet 1's arc length was that of
        sheet 0 at the same spiral parameter.

    Raises
    ------
    ConfigError
        ``n_samples`` not an integer >= 0, a NaN or infinite parameter, a negative
        ``density_ratio``, ``noise`` or ``outliers``, ``height <= 0``, or ``gap`` at or below
        minus the spiral's smallest radius of curvature (-4.6).
    """
    n_samples = whole_number("n_samples", n_samples, 0)
    density_ratio = finite_number("density_ratio", density_ratio, 0.0)
    gap = finite_number("gap", gap)
    noise = finite_number("noise", noise, 0.0)
    outliers = finite_number("outliers", outliers, 0.0)
    height = finite_number("height", height, 0.0, lo_open=True)
    t_lo, t_hi = 1.5 * np.pi, 3.5 * np.pi
    max_curvature = (t_lo**2 + 2) / (t_lo**2 + 1) ** 1.5  # of the spiral, at its inner end
    if not gap > -1.0 / max_curvature:
        raise ConfigError(
            f"gap must be > {-1.0 / max_curvature:.3f} (an inward offset beyond the spiral's "
            f"radius of curvature folds sheet 1 onto itself), got {gap}"
        )
    rs = check_random_state(random_state)
    n0 = int(round(n_samples * density_ratio / (1.0 + density_ratio)))
    n1 = n_samples - n0

    def arclen(t):
        return 0.5 * (t * np.sqrt(1 + t * t) + np.arcsinh(t))

    def heading(t):  # direction angle of the spiral's tangent: polar angle + atan(r / r')
        return t + np.arctan(t)

    grid = np.linspace(t_lo, t_hi, 4096)

    def sheet(m, offset):
        # arc length of the curve pushed `offset` along the outward normal: ds (1 + offset k)
        # with k ds = d(heading) (k: the spiral's curvature); uniform in it is uniform by area
        s_grid = arclen(grid) - arclen(t_lo) + offset * (heading(grid) - heading(t_lo))
        s = rs.uniform(0, s_grid[-1], m)
        t = np.interp(s, s_grid, grid)
        # outward normal of the spiral (t cos t, t sin t): its tangent (tx, tz) turned clockwise
        # (the spiral turns counterclockwise as t grows)
        tx, tz = np.cos(t) - t * np.sin(t), np.sin(t) + t * np.cos(t)
        nrm = np.hypot(tx, tz)
        nx, nz = tz / nrm, -tx / nrm
        x = t * np.cos(t) + offset * nx
        z = t * np.sin(t) + offset * nz
        y = rs.uniform(0, height, m)
        return np.column_stack([x, y, z]), np.column_stack([s, y])

    X0, t0 = sheet(n0, 0.0)
    X1, t1 = sheet(n1, gap)
    X = np.vstack([X0, X1])
    labels = np.r_[np.zeros(n0, int), np.ones(n1, int)]
    t = np.vstack([t0, t1])
    if noise > 0:
        X = X + rs.normal(scale=noise, size=X.shape)
    n_out = int(round(outliers * n_samples))
    if n_out:
        lo, hi = X.min(axis=0), X.max(axis=0)
        X = np.vstack([X, rs.uniform(lo, hi, size=(n_out, 3))])
        labels = np.r_[labels, -np.ones(n_out, int)]
        t = np.vstack([t, np.full((n_out, 2), np.nan)])
    perm = rs.permutation(X.shape[0])
    return X[perm], labels[perm], t[perm]


def make_head_pose_images(
    n_samples: int = 400,
    *,
    size: int = 32,
    yaw_range_deg: tuple[float, float] = (-75.0, 75.0),
    pitch_range_deg: tuple[float, float] = (-30.0, 30.0),
    noise: float = 0.01,
    random_state=None,
) -> tuple[np.ndarray, np.ndarray]:
    """Rendered grey-level images of a rotating head (a stand-in for the thesis's face-pose
    sequence, fig. 6.10): a textured sphere (skin, hair on top and at the back, eyes, eyebrows,
    nose, mouth) seen by an orthographic camera, shaded by a light at the camera.

    Parameters
    ----------
    n_samples : int
        Number of images; yaw and pitch are drawn uniformly from the ranges.
    size : int
        Image side in pixels.
    yaw_range_deg, pitch_range_deg : (float, float)
        Head rotation about the vertical axis (positive: the face turns towards the image right) and
        about the horizontal axis (positive: the face looks down, its nose lower in the image;
        said "up" until 2026-12-02, the images did not change), degrees.
    noise : float
        Standard deviation of additive Gaussian pixel noise (intensities are in [0, 1]).
    random_state : int, RandomState or None

    Returns
    -------
    images : (n_samples, size * size) array
        Flattened images, row-major.
    pose : (n_samples, 2) array
        (yaw, pitch) of each image in degrees.

    Raises
    ------
    ConfigError
        ``n_samples`` not an integer >= 0, ``size`` not an integer >= 1, a range that is not two
        finite numbers, or ``noise`` negative or not finite.
    """
    n_samples = whole_number("n_samples", n_samples, 0)
    size = whole_number("size", size, 1)
    yaw_range_deg = _angle_range("yaw_range_deg", yaw_range_deg)
    pitch_range_deg = _angle_range("pitch_range_deg", pitch_range_deg)
    noise = finite_number("noise", noise, 0.0)
    rs = check_random_state(random_state)
    yaw = rs.uniform(*yaw_range_deg, n_samples)
    pitch = rs.uniform(*pitch_range_deg, n_samples)
    c = (np.arange(size) + 0.5) / size * 2.2 - 1.1
    u, v = np.meshgrid(c, -c)  # u right, v up
    inside = u**2 + v**2 < 1.0
    z = np.sqrt(np.clip(1.0 - u**2 - v**2, 0.0, None))
    P = np.stack([u[inside], v[inside], z[inside]])  # camera frame, z towards the camera
    shade = 0.35 + 0.65 * z[inside]

    def blob(lon, lat, lon0, lat0, s_lon, s_lat):
        return np.exp(-(((lon - lon0) / s_lon) ** 2) - ((lat - lat0) / s_lat) ** 2)

    out = np.zeros((n_samples, size * size))
    for k in range(n_samples):
        a, b = np.radians(yaw[k]), np.radians(pitch[k])
        # camera -> head frame: undo pitch (about x), then yaw (about y)
        cb, sb, ca, sa = np.cos(b), np.sin(b), np.cos(a), np.sin(a)
        x1, y1, z1 = P[0], cb * P[1] + sb * P[2], -sb * P[1] + cb * P[2]
        xh, yh, zh = ca * x1 - sa * z1, y1, sa * x1 + ca * z1
        lon = np.degrees(np.arctan2(xh, zh))  # 0 at the nose, + to the head's left side
        lat = np.degrees(np.arcsin(np.clip(yh, -1, 1)))
        tex = np.full(lon.shape, 0.75)
        hair = (lat > 35) | (np.abs(lon) > 95) | ((np.abs(lon) > 75) & (lat > 0))
        tex[hair] = 0.2
        tex -= 0.55 * (blob(lon, lat, 28, 12, 9, 6) + blob(lon, lat, -28, 12, 9, 6))  # eyes
        tex -= 0.3 * (blob(lon, lat, 28, 24, 14, 3) + blob(lon, lat, -28, 24, 14, 3))  # brows
        tex += 0.2 * blob(lon, lat, 0, -2, 7, 12)  # nose
        tex -= 0.45 * blob(lon, lat, 0, -30, 22, 5)  # mouth
        img = np.zeros((size, size))
        img[inside] = np.clip(tex, 0, 1) * shade
        out[k] = img.ravel()
    if noise > 0:
        out += rs.normal(scale=noise, size=out.shape)
    return out, np.column_stack([yaw, pitch])
