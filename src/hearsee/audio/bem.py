"""Boundary elements for sound scattering by a rigid body, and the rigid-sphere series.

Reconstruction (thesis ch. 3, "Helmholtz-Kirchhoff integral over the mask surface"): the sound
pressure on and around a closed rigid (sound-hard) body is the solution of the Kirchhoff-Helmholtz
boundary integral equation. For a point ``x`` with incident field ``p_inc`` and the body's
outward normal ``n`` (pointing into the air)::

    c(x) p(x) = p_inc(x) + integral_S p(y) dG(x, y)/dn_y dS(y),   G = exp(i k r) / (4 pi r)

with ``c = 1`` in the air, ``1/2`` on a smooth part of the surface and ``0`` inside the body
(time convention ``exp(-i w t)``; rigid: ``dp/dn = 0`` on S). We solve it by collocation with
constant pressure on flat triangles (centroid collocation, centroid quadrature far away,
subdivided quadrature for neighbouring panels; the self term of a flat panel is zero), and remove
the fictitious interior (Dirichlet) frequencies with CHIEF points: interior points where the same
integral must give zero, appended as extra rows of an overdetermined system solved by least
squares (Schenck 1968). The system matrix does not depend on the source, so each frequency is
factorised once (least squares through the normal equations) and the pressure at a few
evaluation points (the microphones) is returned as an *adjoint* row vector ``v``:
``p(x_e) = (p_inc(x_e) + v_e . b) / c_e`` for ANY incident field ``b`` sampled at the
collocation + CHIEF points. Sources at any direction or distance then cost one dot product.

Accuracy (tested in tests/audio/test_bem.py): on a coarse 320-panel sphere of radius 8.75 cm the
BEM matches the exact series to |IID error| < 0.5 dB and |ITD error| < 10 us up to 2 kHz, far
field and d0 = 0.5 m, including the first fictitious frequency (ka = pi).

References: Schenck, H. A. (1968) "Improved integral formulation for acoustic radiation problems",
JASA 44; Burton, A. J. & Miller, G. F. (1971) Proc. R. Soc. A 323 (the alternative cure for
fictitious frequencies); Kirkup, S. (2019) "The Boundary Element Method in Acoustics" (2nd ed.);
Duda, R. O. & Martens, W. L. (1998) "Range dependence of the response of a spherical head model",
JASA 104(5), 3048-3058 (the series :func:`sphere_transfer`, with their recursions).

Units: metres, Hz, m/s. Transfer functions are normalised by the free-field pressure the same
source would produce at the origin of the frame (so far from the body ``H`` -> 1).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from hearsee.config import (
    as_rng,
    finite_number,
    is_real,
    real_entries,
    true_or_false,
    whole_number,
)
from hearsee.errors import ConfigError, GeometryError
from hearsee.geometry import as_point, as_points

__all__ = [
    "MAX_GEODESIC_SUBDIVISION",
    "MAX_SERIES_TERMS",
    "MIN_CHIEF_POINTS",
    "TriMesh",
    "check_closed_mesh",
    "geodesic_sphere",
    "incident_field",
    "solve_adjoint",
    "sphere_mesh",
    "sphere_transfer",
]

_FOUR_PI = 4.0 * np.pi

#: A point closer to a flat panel's plane than this fraction of the panel's size lies in that
#: plane. Coordinates computed on the surface (centroids, barycentric points, projections) are
#: off the plane by rounding only, ~1e-16 of the panel's size; treating them as off it gave a
#: winding number of 0 or 1 at random instead of 1/2, and a near-singular double-layer kernel
#: (y - x).n / r^3 of ~1e27 where a quadrature point coincides with the point.
_PLANE_RTOL = 1e-9


# ---------------------------------------------------------------------------------------- meshes
#: Largest subdivision :func:`geodesic_sphere` makes: 200,000 triangles, far beyond any mesh the
#: dense BEM can solve (a mask's ``mesh_subdivision`` stops at 40; 1e6 asked for 2e13 triangles
#: and the process was killed for want of memory).
MAX_GEODESIC_SUBDIVISION = 100


def geodesic_sphere(n: int) -> tuple[NDArray, NDArray]:
    """Unit geodesic sphere: an icosahedron whose faces are split ``n x n`` (``20 n^2`` triangles).

    ``n`` is an integer in ``[1, MAX_GEODESIC_SUBDIVISION]``, else a GeometryError.
    Returns ``(vertices (V, 3), faces (F, 3) int)``, faces counter-clockwise seen from outside.
    """
    # (int(n) took 1.5 as 1, "2" and True as numbers, and raised builtin errors on NaN or text)
    n = whole_number("geodesic sphere subdivision", n, 1, MAX_GEODESIC_SUBDIVISION,
                     error=GeometryError)
    t = (1.0 + 5**0.5) / 2.0
    ico_v = np.array([(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
                      (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)],
                     dtype=float)
    ico_f = np.array([(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9),
                      (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2),
                      (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
                      (8, 6, 7), (9, 8, 1)])
    # barycentric lattice of one face
    ij = [(i, j) for i in range(n + 1) for j in range(n + 1 - i)]
    index = {p: k for k, p in enumerate(ij)}
    tri = []
    for i in range(n):
        for j in range(n - i):
            tri.append((index[(i, j)], index[(i + 1, j)], index[(i, j + 1)]))
            if i + j + 2 <= n:
                tri.append((index[(i + 1, j)], index[(i + 1, j + 1)], index[(i, j + 1)]))
    tri = np.array(tri)
    lat = np.array(ij, dtype=float) / n  # (L, 2)
    pts, faces = [], []
    for f in ico_f:
        a, b, c = ico_v[f]
        p = a + lat[:, :1] * (b - a) + lat[:, 1:] * (c - a)
        faces.append(tri + len(pts) * len(ij))
        pts.append(p)
    pts = np.concatenate(pts)
    pts /= np.linalg.norm(pts, axis=1, keepdims=True)
    key = np.round(pts, 9)
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    verts = np.zeros((len(uniq), 3))
    verts[inv.ravel()] = pts
    faces = inv.ravel()[np.concatenate(faces)]
    # orient outward
    v = verts[faces]
    nrm = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    flip = np.einsum("ij,ij->i", nrm, v.mean(axis=1)) < 0
    faces[flip] = faces[flip][:, ::-1]
    return verts, faces


def sphere_mesh(radius: float, n: int, centre: ArrayLike = (0.0, 0.0, 0.0)) -> TriMesh:
    """Geodesic triangulation of a sphere of ``radius`` metres (``20 n^2`` panels)."""
    # (a negative radius turned the faces inward without a word, text raised numpy's errors)
    radius = finite_number("sphere radius (metres)", radius, 0.0, lo_open=True,
                           error=GeometryError)
    c = as_point(centre, "sphere centre")
    v, f = geodesic_sphere(n)
    return TriMesh(v * radius + c, f)


def check_closed_mesh(vertices: ArrayLike, faces: ArrayLike, where: str = "mesh") -> None:
    """Raise GeometryError unless the triangulation is a closed (watertight), consistently oriented
    2-manifold enclosing a positive volume with outward-facing triangles (text for either
    was numpy's builtin ValueError)."""
    if not real_entries(vertices):
        raise GeometryError(f"{where}: vertices must be a finite N x 3 array of numbers (metres), "
                            f"got {vertices!r:.60}")
    if not real_entries(faces):
        raise GeometryError(f"{where}: faces must be a non-empty integer M x 3 array, got "
                            f"{faces!r:.60}")
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(faces)
    if v.ndim != 2 or v.shape[1] != 3 or len(v) < 4 or not np.all(np.isfinite(v)):
        raise GeometryError(f"{where}: vertices must be a finite N x 3 array with N >= 4")
    if f.ndim != 2 or f.shape[1] != 3 or len(f) < 1 or not np.issubdtype(f.dtype, np.integer):
        raise GeometryError(f"{where}: faces must be a non-empty integer M x 3 array")
    if f.min() < 0 or f.max() >= len(v):
        raise GeometryError(f"{where}: face indices must lie in 0..{len(v) - 1}")
    area2 = np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
    if np.any(area2 <= 1e-14):
        raise GeometryError(f"{where}: {int(np.sum(area2 <= 1e-14))} degenerate (zero-area) faces")
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    und = np.sort(e, axis=1)
    _, cnt = np.unique(und, axis=0, return_counts=True)
    if np.any(cnt == 1):
        raise GeometryError(
            f"{where}: the surface is open ({int(np.sum(cnt == 1))} boundary edges); the mask must "
            "be a closed (watertight) body"
        )
    if np.any(cnt > 2):
        raise GeometryError(f"{where}: non-manifold surface ({int(np.sum(cnt > 2))} edges shared "
                            "by more than two faces)")
    _, dcnt = np.unique(e, axis=0, return_counts=True)
    if np.any(dcnt > 1):
        raise GeometryError(f"{where}: faces are not consistently oriented")
    vol = np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6.0
    if vol <= 0:
        raise GeometryError(f"{where}: faces point inward (enclosed volume {vol:.3g} m^3 <= 0); "
                            "list the vertices of each face counter-clockwise seen from outside")


@dataclass(frozen=True, eq=False)
class TriMesh:
    """A closed triangulated surface, metres; faces counter-clockwise seen from outside.

    ``vertices`` must be finite numbers ``(V, 3)`` (metres) and ``faces`` integer vertex
    indices ``(F, 3)``, F >= 1, each in ``[0, V)``, else a GeometryError naming the argument
    (``TriMesh(None, None)`` was an empty mesh without a word, text a mesh of as many panels
    as characters, a negative index wrapped around to the last vertices). Whether the surface
    is closed and outward is :func:`check_closed_mesh`'s test (:func:`solve_adjoint` runs it).
    """

    vertices: NDArray
    faces: NDArray

    def __post_init__(self) -> None:
        v = self.vertices  # (a float array is kept as it is: results stay what they were)
        if not (isinstance(v, np.ndarray) and v.dtype.kind == "f"):
            v = np.asarray(v, dtype=float) if real_entries(v) else None
        if v is None or v.ndim != 2 or v.shape[1] != 3 or not np.all(np.isfinite(v)):
            got = "not numbers" if v is None else (
                f"shape {v.shape}" if v.ndim != 2 or v.shape[1] != 3 else "non-finite values")
            raise GeometryError(f"TriMesh: vertices must be finite [x, y, z] points in metres, "
                                f"shape (V, 3), got {got}")
        f = np.asarray(self.faces) if real_entries(self.faces) else None
        if f is None or f.dtype.kind not in "iu" or f.ndim != 2 or f.shape[1] != 3 or not len(f):
            got = "not numbers" if f is None else (
                f"dtype {f.dtype}" if f.dtype.kind not in "iu" else f"shape {f.shape}")
            raise GeometryError(f"TriMesh: faces must be integer vertex indices, shape (F, 3) "
                                f"with F >= 1, got {got}")
        if f.min() < 0 or f.max() >= len(v):
            raise GeometryError(f"TriMesh: faces must index the {len(v)} vertices (0 to "
                                f"{len(v) - 1}), got indices {f.min()} to {f.max()}")
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f)

    @cached_property
    def corners(self) -> NDArray:
        """(F, 3, 3) triangle corner coordinates."""
        return self.vertices[self.faces]

    @cached_property
    def centroids(self) -> NDArray:
        return self.corners.mean(axis=1)

    @cached_property
    def _cross(self) -> NDArray:
        c = self.corners
        return np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])

    @cached_property
    def areas(self) -> NDArray:
        return 0.5 * np.linalg.norm(self._cross, axis=1)

    @cached_property
    def normals(self) -> NDArray:
        """Unit outward normals (F, 3)."""
        return self._cross / (2.0 * self.areas[:, None])

    @cached_property
    def edge_lengths(self) -> NDArray:
        c = self.corners
        return np.linalg.norm(c - np.roll(c, 1, axis=1), axis=2)

    @property
    def n_panels(self) -> int:
        return int(len(self.faces))

    @property
    def size(self) -> float:
        """Mean edge length, metres."""
        return float(self.edge_lengths.mean())

    def winding_number(self, points: ArrayLike) -> NDArray:
        """Generalised winding number of each point (1 inside, 0 outside, 1/2 on the surface).

        Solid angles by Van Oosterom & Strackee (1983): ``tan(omega / 2) = num / den`` with
        ``num = a . (b x c)``, six times the volume of the tetrahedron of the point and the
        triangle. A point on a face (``|num|`` below :data:`_PLANE_RTOL` of ``|a| |b| |c|``,
        and ``den <= 0``: inside the triangle or on its edges and corners) is on the surface:
        exactly 1/2 (its own face's solid angle jumps there from -2 pi to 2 pi, and rounding
        picked either end: 0 or 1).
        """
        w, on_surface = self._winding(_query_points(points, "winding_number"))
        return np.where(on_surface, 0.5, w)

    def _winding(self, points: ArrayLike) -> tuple[NDArray, NDArray]:
        """Winding numbers as summed (P,) and which points lie on a face (P,) bool."""
        p = np.atleast_2d(np.asarray(points, dtype=float))
        a = self.corners[None, :, 0] - p[:, None]
        b = self.corners[None, :, 1] - p[:, None]
        c = self.corners[None, :, 2] - p[:, None]
        la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
        num = np.einsum("pfi,pfi->pf", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("pfi,pfi->pf", a, b) * lc
               + np.einsum("pfi,pfi->pf", b, c) * la + np.einsum("pfi,pfi->pf", c, a) * lb)
        small = _PLANE_RTOL * la * lb * lc
        on_face = (np.abs(num) <= small) & (den <= small)
        return 2.0 * np.arctan2(num, den).sum(axis=1) / _FOUR_PI, on_face.any(axis=1)

    def closest_points(self, points: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
        """Closest surface point to each point: ``(closest (P, 3), distance (P,), face (P,))``."""
        p = _query_points(points, "closest_points")
        out_q, out_d, out_f = [], [], []
        c = self.corners
        a, b, cc = c[:, 0], c[:, 1], c[:, 2]
        for x in p:
            cand = [_project_to_triangles(x, a, b, cc, self.normals)]
            for s, t in ((a, b), (b, cc), (cc, a)):
                cand.append(_closest_on_segments(x, s, t))
            q = np.stack(cand)  # (4, F, 3)
            d = np.linalg.norm(q - x, axis=-1)
            d = np.where(np.isnan(d), np.inf, d)
            k, fi = np.unravel_index(np.argmin(d), d.shape)
            out_q.append(q[k, fi])
            out_d.append(d[k, fi])
            out_f.append(fi)
        return np.array(out_q), np.array(out_d), np.array(out_f)


def _query_points(points: ArrayLike, func: str) -> NDArray:
    """``points`` as finite ``(P, 3)`` metres (one ``(3,)`` point as ``(1, 3)``), else a
    GeometryError naming ``func``: the check of :meth:`TriMesh.winding_number`,
    :meth:`TriMesh.closest_points` and :func:`incident_field`, where None gave NaN (and face 0)
    without a word, text numpy's builtin ValueError."""
    p = np.atleast_2d(as_points(points, f"{func}: points"))
    if p.ndim != 2 or not np.all(np.isfinite(p)):
        raise GeometryError(f"{func}: points must be finite [x, y, z] in metres, shape (P, 3), "
                            f"got " + (f"shape {p.shape}" if p.ndim != 2 else "non-finite values"))
    return p


def _project_to_triangles(x: NDArray, a: NDArray, b: NDArray, c: NDArray, n: NDArray) -> NDArray:
    q = x - np.einsum("fi,fi->f", x - a, n)[:, None] * n
    v0, v1, v2 = b - a, c - a, q - a
    d00 = np.einsum("fi,fi->f", v0, v0)
    d01 = np.einsum("fi,fi->f", v0, v1)
    d11 = np.einsum("fi,fi->f", v1, v1)
    d20 = np.einsum("fi,fi->f", v2, v0)
    d21 = np.einsum("fi,fi->f", v2, v1)
    den = d00 * d11 - d01 * d01
    s = (d11 * d20 - d01 * d21) / den
    t = (d00 * d21 - d01 * d20) / den
    inside = (s >= 0) & (t >= 0) & (s + t <= 1)
    return np.where(inside[:, None], q, np.nan)


def _closest_on_segments(x: NDArray, s: NDArray, t: NDArray) -> NDArray:
    d = t - s
    u = np.clip(np.einsum("fi,fi->f", x - s, d) / np.einsum("fi,fi->f", d, d), 0.0, 1.0)
    return s + u[:, None] * d


# ------------------------------------------------------------------------------ quadrature
def _subtriangle_rule(m: int) -> NDArray:
    """Barycentric (Q, 3) centroids of the m*m equal sub-triangles (weights 1/m^2 each)."""
    pts = []
    for i in range(m):
        for j in range(m - i):
            pts.append(((i + 1 / 3) / m, (j + 1 / 3) / m))
            if i + j + 2 <= m:
                pts.append(((i + 2 / 3) / m, (j + 2 / 3) / m))
    st = np.array(pts)
    return np.column_stack([1.0 - st.sum(axis=1), st])


def _dlp_geometry(x: NDArray, y: NDArray, n: NDArray) -> tuple[NDArray, NDArray]:
    """Distance r and Laplace double-layer kernel dG0/dn_y = -(y - x).n / (4 pi r^3)."""
    d = y - x
    r = np.sqrt(np.einsum("...i,...i->...", d, d))
    rn = np.einsum("...i,...i->...", d, n)
    with np.errstate(divide="ignore", invalid="ignore"):
        lap = np.where(r > 0, -rn / (_FOUR_PI * r**3), 0.0)
    return r, lap


def _helmholtz(r: NDArray, lap: NDArray, k: float) -> NDArray:
    """Helmholtz double-layer kernel from the Laplace one: dG/dn = dG0/dn e^{ikr} (1 - ikr)."""
    return lap * np.exp(1j * k * r) * (1.0 - 1j * k * r)


class _DlpOperator:
    """Double-layer matrices D[t, j] = int_panel_j dG(x_t, y)/dn_y dS for a fixed set of targets.

    Frequency-independent geometry is computed once; :meth:`matrix` costs one complex exponential
    per entry. Centroid rule for far panels, ``m*m`` sub-triangle rule for panels within
    ``radius`` of the target, zero for a target on a flat panel's own plane (within
    :data:`_PLANE_RTOL` of the panel's size: there ``(y - x) . n = 0`` for every ``y`` of the
    panel, and the principal value, which gives the free term 1/2 on a face, is 0).
    """

    def __init__(self, targets: NDArray, mesh: TriMesh, radius: float, m: int,
                 self_rows: bool) -> None:
        r, lap = _dlp_geometry(targets[:, None, :], mesh.centroids[None], mesh.normals[None])
        lap = lap * mesh.areas[None]
        if self_rows:  # flat panel: (y - x) . n = 0 on the panel itself
            np.fill_diagonal(lap, 0.0)
        tree = cKDTree(mesh.centroids)
        lists = tree.query_ball_point(targets, r=radius)
        rows = np.concatenate([np.full(len(lst), i) for i, lst in enumerate(lists)]).astype(int)
        cols = np.concatenate([np.asarray(lst, dtype=int) for lst in lists]).astype(int)
        if self_rows:
            keep = rows != cols
            rows, cols = rows[keep], cols[keep]
        bary = _subtriangle_rule(m)
        y = np.einsum("qk,pki->pqi", bary, mesh.corners[cols])
        nr, nlap = _dlp_geometry(targets[rows][:, None], y, mesh.normals[cols][:, None])
        nlap = nlap * (mesh.areas[cols][:, None] / len(bary))
        # a target in a panel's plane: rounding left (y - x).n ~ 1e-18 m, and where a quadrature
        # point coincides with the target (a panel centroid) r ~ 1e-18 m too: a kernel of 1e27
        h = np.einsum("tfi,fi->tf", targets[:, None, :] - mesh.centroids[None], mesh.normals)
        in_plane = np.abs(h) <= _PLANE_RTOL * np.sqrt(mesh.areas)[None]
        lap[in_plane] = 0.0
        nlap[in_plane[rows, cols]] = 0.0
        lap[rows, cols] = 0.0
        r[rows, cols] = 0.0
        self.r, self.lap = r, lap
        self.rows, self.cols, self.nr, self.nlap = rows, cols, nr, nlap
        self.laplace = lap.copy()
        self.laplace[rows, cols] = nlap.sum(axis=1)

    def matrix(self, k: float) -> NDArray:
        out = _helmholtz(self.r, self.lap, k)
        if len(self.rows):
            out[self.rows, self.cols] = _helmholtz(self.nr, self.nlap, k).sum(axis=1)
        return out


# ---------------------------------------------------------------------------------- solver
@dataclass(frozen=True)
class AdjointSolution:
    """Per-frequency adjoint vectors of a rigid-body BEM problem.

    ``p(eval_points[e], f_i) = (p_inc(eval_points[e]) + v[i, e] . p_inc(row_points)) / c[e]``.
    ``mesh`` is the body (None when unknown: :func:`transfer_functions` then cannot tell a
    source inside the body or on its surface); ``speed_of_sound`` (m/s) the one the
    wavenumbers of ``v`` were computed with (None when unknown: 343 m/s unless told).
    """

    freqs: NDArray  # (F,) Hz
    v: NDArray  # (F, E, R) complex
    c: NDArray  # (E,) free-term coefficient at the evaluation points
    eval_points: NDArray  # (E, 3) metres
    row_points: NDArray  # (R, 3) collocation centroids then CHIEF points, metres
    mesh: TriMesh | None = None
    speed_of_sound: float | None = None


#: Fewest CHIEF interior points :func:`solve_adjoint` takes (``n_chief``): :func:`chief_points`
#: calls a body in which it finds fewer than ``max(4, n // 2)`` too thin for CHIEF.
MIN_CHIEF_POINTS = 4


def _check_mesh(mesh: Any) -> None:
    """GeometryError unless ``mesh`` is a :class:`TriMesh`: the type check of
    :func:`solve_adjoint` and :func:`chief_points` (None: a builtin AttributeError there)."""
    if not isinstance(mesh, TriMesh):
        raise GeometryError(f"BEM mesh must be a TriMesh, got {type(mesh).__name__}")


def chief_points(mesh: TriMesh, n: int = 16, rng: int = 0) -> NDArray:
    """``n`` interior points well inside the body (at least two panel sizes from the surface);
    ``mesh`` a :class:`TriMesh` and ``n`` an integer >= :data:`MIN_CHIEF_POINTS`, else a
    GeometryError."""
    _check_mesh(mesh)
    n = whole_number("number of CHIEF points", n, MIN_CHIEF_POINTS, error=GeometryError)
    gen = as_rng(rng)
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    margin = 2.0 * mesh.size
    out: list[NDArray] = []
    for _ in range(50):
        cand = gen.uniform(lo, hi, size=(8 * n, 3))
        inside = mesh.winding_number(cand) > 0.5
        cand = cand[inside]
        if len(cand):
            d = np.min(np.linalg.norm(cand[:, None] - mesh.centroids[None], axis=-1), axis=1)
            out.extend(cand[d > margin])
        if len(out) >= n:
            break
    if len(out) < max(4, n // 2):
        raise GeometryError("mask body too thin for CHIEF interior points; use a finer mesh")
    return np.array(out[:n])


def solve_adjoint(mesh: TriMesh, freqs: ArrayLike, eval_points: ArrayLike,
                  speed_of_sound: float = 343.0, n_chief: int = 16,
                  on_surface_tol: float = 0.0,
                  progress: Callable[[int], None] | None = None) -> AdjointSolution:
    """Solve the rigid-body BEM once per frequency for pressure at ``eval_points``.

    Parameters
    ----------
    mesh : TriMesh
        Closed body, metres: a watertight, consistently oriented triangulation with outward
        faces and no zero-area face (:func:`check_closed_mesh`, else a GeometryError).
    freqs : array (F,)
        Frequencies in Hz (> 0).
    eval_points : array (E, 3)
        Where the pressure is wanted (the microphones), metres, on or outside the body. Points
        closer than ``on_surface_tol`` (metres, >= 0) to the surface are projected onto it.
    n_chief : int
        CHIEF interior points against the irregular frequencies (>= :data:`MIN_CHIEF_POINTS`).
    progress : callable, optional
        Called with 1 after each frequency.
    """
    _check_mesh(mesh)
    # (until 2026-12-02: n_chief 0-3 said "mask body too thin for CHIEF interior points", -1
    # and 2.5 raised numpy's ValueError / TypeError, no frequency ran the whole setup and gave
    # an empty solution, text frequencies raised numpy's ValueError, a NaN on_surface_tol
    # counted as 0 and a text one raised numpy's UFuncTypeError)
    whole_number("n_chief", n_chief, MIN_CHIEF_POINTS, error=GeometryError)
    if progress is not None and not callable(progress):  # (a TypeError after the first solve)
        raise ConfigError(f"solve_adjoint: progress must be a callable or None, got "
                          f"{progress!r:.40}")
    on_surface_tol = finite_number("on_surface_tol (metres)", on_surface_tol, 0.0,
                                   error=GeometryError)
    if not real_entries(freqs) or np.size(freqs) == 0:
        raise GeometryError(f"BEM frequencies must be one or more numbers (Hz), got {freqs!r}")
    # (an open surface -- a hole, a hemisphere -- gave numbers 10-25 % off without a word, a
    # zero-area face NaN, inverted faces "too thin for CHIEF points")
    check_closed_mesh(mesh.vertices, mesh.faces, "BEM mesh")
    f = np.asarray(freqs, dtype=float).ravel()
    if not np.all(np.isfinite(f) & (f > 0)):  # (NaN and inf passed "<= 0": a NaN solution)
        raise GeometryError("BEM frequencies must be finite numbers > 0 Hz")
    if not (is_real(speed_of_sound) and speed_of_sound > 0):  # (text: numpy's TypeError)
        raise GeometryError(f"speed of sound must be a finite number > 0 m/s, got {speed_of_sound}")
    # (a NaN point raised scipy's "'x' must be finite" ValueError, none or [x, y] a numpy
    # broadcasting ValueError, until 2026-12-02)
    xe = np.atleast_2d(as_points(eval_points, "BEM evaluation points"))
    if xe.ndim != 2 or len(xe) == 0 or not np.all(np.isfinite(xe)):
        raise GeometryError(f"BEM evaluation points must be finite [x, y, z] points in metres, "
                            f"shape (E, 3) with E >= 1, got shape {xe.shape}")
    q, dist, _ = mesh.closest_points(xe)
    inside = (dist > on_surface_tol) & (mesh.winding_number(xe) > 0.5)
    if np.any(inside):  # (no field inside a rigid body: the old answer was garbage)
        raise GeometryError(f"evaluation point(s) {np.flatnonzero(inside).tolist()} lie inside "
                            "the body; put them on its surface or outside it")
    xe = np.where((dist <= on_surface_tol)[:, None], q, xe)
    xc = mesh.centroids
    chief = chief_points(mesh, n_chief)
    radius = 3.0 * mesh.edge_lengths.max()
    op_c = _DlpOperator(xc, mesh, radius, 4, self_rows=True)
    op_h = _DlpOperator(chief, mesh, radius, 4, self_rows=False)
    op_e = _DlpOperator(xe, mesh, radius, 8, self_rows=False)
    c_e = 1.0 + op_e.laplace.sum(axis=1)
    n = mesh.n_panels
    eye = 0.5 * np.eye(n)
    v_all = np.empty((len(f), len(xe), n + len(chief)), dtype=complex)
    for i, fi in enumerate(f):
        k = 2.0 * np.pi * fi / speed_of_sound
        d_cc, d_hc, d_ec = op_c.matrix(k), op_h.matrix(k), op_e.matrix(k)
        sysm = np.vstack([eye - d_cc, -d_hc])  # (n + H, n)
        # least squares by the normal equations (LAPACK QR is ~10x slower here; the CHIEF
        # system is well conditioned): p = G^-1 M^H b, G = M^H M, so the adjoint row of an
        # evaluation point with double-layer row d is v = conj(M G^-1 conj(d)).
        gram = sysm.conj().T @ sysm
        lu = sla.lu_factor(gram, overwrite_a=True, check_finite=False)
        u = sla.lu_solve(lu, d_ec.conj().T, check_finite=False)  # (n, E)
        v_all[i] = (sysm @ u).conj().T
        if progress is not None:
            progress(1)
    return AdjointSolution(f, v_all, c_e, xe, np.vstack([xc, chief]), mesh,
                           float(speed_of_sound))


def _as_sources(source: ArrayLike, far_field: bool) -> NDArray:
    """``source`` as finite (S, 3) positions (metres) or, with ``far_field``, unit directions."""
    s = np.atleast_2d(as_points(source, "sources"))  # (text, ragged lists: GeometryError)
    if s.ndim != 2 or len(s) == 0:
        raise GeometryError(f"sources must be [x, y, z] points in metres, shape (S, 3), got "
                            f"shape {s.shape}")
    if not np.all(np.isfinite(s)):  # (gave NaN)
        i = int(np.flatnonzero(~np.isfinite(s).all(axis=1))[0])
        raise GeometryError(f"source {i} must be a finite [x, y, z] in metres, got "
                            f"{s[i].tolist()}")
    if far_field:
        big = np.abs(s).max(axis=1, keepdims=True)
        if np.any(big == 0):  # (gave NaN)
            raise GeometryError(f"far-field source {int(np.flatnonzero(big == 0)[0])} has no "
                                "direction: [0, 0, 0]")
        s = s / big  # (scaled first: a direction of 1e-200 m does not underflow)
        s = s / np.linalg.norm(s, axis=1, keepdims=True)
    return s


def _check_sources(points: NDArray, s: NDArray, what: str = "point", first: int = 0) -> None:
    """GeometryError unless every point source ``s`` (S, 3) is off the origin of the frame
    (where the transfer functions are normalised by the free field) and off every point (P, 3),
    both within :data:`_PLANE_RTOL` of the coordinates' magnitude (their rounding). The
    message numbers the sources from ``first``."""
    scale = np.abs(points).max(initial=0.0)
    d0 = np.linalg.norm(s, axis=1)
    near = d0 <= _PLANE_RTOL * scale
    if np.any(near):  # (gave H = 0 everywhere)
        raise GeometryError(
            f"source {first + int(np.flatnonzero(near)[0])} is at the origin of the frame, where "
            "the transfer functions are normalised by its free field (infinite there); move it")
    r = np.linalg.norm(s[:, None, :] - points[None], axis=-1)  # (S, P)
    hit = r <= _PLANE_RTOL * np.maximum(scale, d0)[:, None]
    if np.any(hit):  # (gave NaN with RuntimeWarnings)
        i, j = np.argwhere(hit)[0]
        raise GeometryError(f"source {first + i} coincides with {what} {j} at "
                            f"{np.round(points[j], 6).tolist()} m (its field is infinite there)")


def _incident(x: NDArray, k: NDArray, s: NDArray, far_field: bool) -> NDArray:
    if far_field:
        return np.exp(-1j * k[:, None, None] * (s @ x.T)[None])
    d0 = np.linalg.norm(s, axis=1)  # (S,)
    r = np.linalg.norm(s[:, None, :] - x[None], axis=-1)  # (S, P)
    return (d0[:, None] / r)[None] * np.exp(1j * k[:, None, None] * (r - d0[:, None])[None])


def incident_field(points: ArrayLike, k: ArrayLike, source: ArrayLike,
                   far_field: bool = False) -> NDArray:
    """Incident pressure of a unit source, normalised to 1 at the origin (``exp(-i w t)``).

    ``points`` (P, 3) metres; ``k`` (F,) wavenumbers rad/m; ``source`` (S, 3) source positions
    (metres) or, with ``far_field``, directions towards the source. Returns (F, S, P) complex.
    GeometryError for a source that is not finite, a direction [0, 0, 0], or a source at the
    origin or at one of the points (within :data:`_PLANE_RTOL` of the coordinates); and for
    ``points`` or ``k`` that are not finite numbers of those shapes (None gave NaN without a
    word, text numpy's builtin ValueError, points of 2 coordinates its broadcasting error).
    ConfigError for a ``far_field`` that is not True or False.
    """
    x = _query_points(points, "incident_field")
    far_field = true_or_false("incident_field: far_field", far_field)
    s = _as_sources(source, far_field)
    if not real_entries(k):
        raise GeometryError(f"incident_field: k must be wavenumbers (rad/m), finite numbers, "
                            f"got {k!r:.60}")
    k = np.atleast_1d(np.asarray(k, dtype=float))
    if k.ndim != 1 or k.size == 0 or not np.all(np.isfinite(k) & (k >= 0)):
        # (an empty k answered an empty field, a negative one the other time convention's)
        raise GeometryError("incident_field: k must be wavenumbers (rad/m), one or more finite "
                            "numbers >= 0 of shape (F,), got " + (
                                f"shape {k.shape}" if k.ndim != 1 or k.size == 0
                                else "values out of range"))
    if not far_field:
        _check_sources(x, s)
    return _incident(x, k, s, far_field)


def transfer_functions(sol: AdjointSolution, source: ArrayLike, far_field: bool = False,
                       speed_of_sound: float | None = None, chunk: int = 256) -> NDArray:
    """Pressure at the evaluation points for sources ``(S, 3)``: ``(S, E, F)`` complex
    (``exp(-i w t)`` convention, normalised by the free field at the origin).

    ``speed_of_sound`` (m/s) defaults to the solution's (343 m/s for a solution that does not
    know its own); another one than the solution's is a ConfigError, since the incident field
    would be sampled at other wavenumbers than the solution's (solve with c = 330 m/s, then
    343: 1.4 dB and 7 degrees off at 3 kHz).

    ``source``: positions in metres or, with ``far_field``, directions. GeometryError for a
    source that is not finite, a direction [0, 0, 0], and for a point source inside the body
    (no sound reaches the air from there), on its surface, at an evaluation point or at the
    origin of the frame (infinite fields, NaN before); and for a ``sol`` that is no
    :class:`AdjointSolution` (None: a builtin AttributeError). ConfigError for a ``far_field``
    that is not True or False ("no" was truthy: plane waves without a word) and a ``chunk``
    (sources per block) that is no integer >= 1 (None, text or 0 were builtin errors of
    ``range``)."""
    if not isinstance(sol, AdjointSolution):
        raise GeometryError(f"transfer_functions needs the AdjointSolution of solve_adjoint, "
                            f"got {type(sol).__name__}")
    far_field = true_or_false("transfer_functions: far_field", far_field)
    chunk = whole_number("transfer_functions: chunk", chunk, 1)
    c = sol.speed_of_sound
    if speed_of_sound is not None:
        if not (is_real(speed_of_sound) and speed_of_sound > 0):
            raise GeometryError(f"speed of sound must be a finite number > 0 m/s, got "
                                f"{speed_of_sound!r}")
        if c is not None and not np.isclose(speed_of_sound, c, rtol=1e-12, atol=0.0):
            raise ConfigError(
                f"the BEM solution was computed for a speed of sound of {c:g} m/s, not "
                f"{float(speed_of_sound):g} m/s; solve again for {float(speed_of_sound):g} m/s "
                "or leave speed_of_sound out")
        c = float(speed_of_sound)
    c = 343.0 if c is None else c
    s = _as_sources(source, far_field)
    if not far_field:
        for a in range(0, len(s), chunk):  # (in chunks: (S, F) and (S, R) arrays)
            ss = s[a:a + chunk]
            if sol.mesh is not None:
                w, on = sol.mesh._winding(ss)
                for bad, where in ((on, "on the surface of"), (~on & (w > 0.5), "inside")):
                    if np.any(bad):  # (inside: finite numbers; on the surface: NaN)
                        i = a + int(np.flatnonzero(bad)[0])
                        raise GeometryError(f"source {i} at {np.round(s[i], 6).tolist()} m lies "
                                            f"{where} the body; put it outside")
            _check_sources(sol.eval_points, ss, "evaluation point", a)
            _check_sources(sol.row_points, ss, "BEM collocation or CHIEF point", a)
    k = 2.0 * np.pi * sol.freqs / c
    out = np.empty((len(s), len(sol.eval_points), len(k)), dtype=complex)
    for a in range(0, len(s), chunk):
        ss = s[a:a + chunk]
        b = _incident(sol.row_points, k, ss, far_field)  # (F, S, R)
        pe = _incident(sol.eval_points, k, ss, far_field)  # (F, S, E)
        tot = (pe + np.einsum("fer,fsr->fse", sol.v, b)) / sol.c[None, None, :]
        out[a:a + chunk] = tot.transpose(1, 2, 0)
    return out


# ------------------------------------------------------------------------------ exact sphere
#: The most terms :func:`sphere_transfer` sums unless told otherwise (``max_terms``): ~1 s per
#: frequency. A source closer than ~35 um to a sphere of 8.75 cm, or ka above 50000,
#: needs more (a GeometryError).
MAX_SERIES_TERMS = 100_000


def _series_terms(mu: NDArray, rho: float, tol: float) -> int:
    """How many terms :func:`sphere_transfer` may need (an upper bound for its stop test).

    The terms oscillate without decaying up to ``m ~ ka`` and fall faster than exponentially
    past ``2 ka`` for a plane wave or a far source (``2 ka + 60`` is the classic count); a
    source at ``rho = r / a`` near 1 makes them fall only like ``rho**-m``, so reaching ``tol``
    relative to the sum (and the ``rho / (rho - 1)`` of the geometric tail, and a margin e^10
    for sums smaller than their largest terms) takes ``ln(rho / ((rho - 1) tol)) + 10`` over
    ``ln(rho)`` more terms: ~170 at 1.25 cm off a 8.75 cm sphere, ~5000 at 0.5 mm.
    """
    tail = 1.0 if np.isinf(rho) else rho / (rho - 1.0)
    decay = 1.0 if np.isinf(rho) else min(np.log(rho), 1.0)  # per term, at least e^-1
    return int(np.ceil(2.0 * np.max(mu) + 60.0 + (np.log(tail / tol) + 10.0) / decay))


def sphere_transfer(freqs: ArrayLike, radius: float, cos_theta: ArrayLike,
                    distance: float | None = None, speed_of_sound: float = 343.0,
                    tol: float = 1e-10, max_terms: int | None = None) -> NDArray:
    """Pressure on a rigid sphere by Rayleigh's series, normalised by the free field at its centre.

    Duda & Martens (1998), eq. (10): with ``mu = k a`` and ``rho = r / a`` (``r`` the source
    distance from the centre; ``distance=None`` = plane wave)::

        H = -(rho / mu) exp(-i mu rho) sum_m (2m + 1) P_m(cos theta) h_m(mu rho) / h_m'(mu)
        H_far = -(1 / mu^2) sum_m (2m + 1) (-i)^(m+1) P_m(cos theta) / h_m'(mu)

    ``theta`` is the angle between the source direction and the surface point, seen from the
    centre. Written for ``exp(-i w t)`` (``h_m`` = spherical Hankel of the first kind). Returns
    (F, T) complex.

    The Hankel functions are carried as ratios ``h_m(x) / h_{m-1}(x)`` (upward recursion, stable
    for ``h_m``): ``h_m(mu)`` itself overflows past ~100 terms at low ``ka``, and a source close
    to the sphere needs hundreds to thousands of terms (they fall like ``rho**-m``), which gave
    inf / inf = NaN. Each frequency stops on its own once the bound ``(2m + 1) |h_m(mu rho) /
    h_m'(mu)|`` of its terms (``|P_m| <= 1``), times the ``rho / (rho - 1)`` of the geometric
    tail, falls below ``tol`` relative to its largest sum, with ``m > 2 ka + 10``. ``max_terms``
    caps the terms (default: sized from ``ka`` and ``rho``, :func:`_series_terms`, at most
    :data:`MAX_SERIES_TERMS`, else a GeometryError); a frequency not converged within the cap is
    a ConfigError, never a truncated sum.
    Frequencies (Hz), radius (metres) and speed of sound (m/s) must be > 0, the source outside
    the sphere, ``cos_theta`` within [-1, 1], ``tol`` in (0, 1).
    """
    # (text raised numpy's ValueError or TypeError, an empty frequency or angle list the
    # ValueError of a maximum over nothing, a bool radius was 1 m, until 2026-12-02)
    if not (real_entries(freqs) and real_entries(cos_theta)):
        raise GeometryError("sphere series: frequencies and cos_theta must be numbers")
    f = np.atleast_1d(np.asarray(freqs, dtype=float))
    ct = np.atleast_1d(np.asarray(cos_theta, dtype=float))
    if f.size == 0 or ct.size == 0:
        raise GeometryError(f"sphere series: needs at least one frequency and one cos_theta, got "
                            f"{f.size} and {ct.size}")
    # (a negative radius or frequency gave the complex conjugate, zero or a source inside NaN)
    if not np.all(np.isfinite(f) & (f > 0)):
        raise GeometryError("sphere series: frequencies must be finite numbers > 0 Hz")
    if not all(is_real(v) and v > 0 for v in (radius, speed_of_sound)):
        raise GeometryError("sphere series: radius and speed of sound must be finite numbers > 0, "
                            f"got {radius!r} and {speed_of_sound!r}")
    if distance is not None and not (is_real(distance) and distance > radius):
        raise GeometryError(f"sphere series: the source distance ({distance!r} m) must be a "
                            f"number larger than the radius ({radius} m)")
    if not np.all(np.abs(ct) <= 1.0 + 1e-9):  # (NaN included: |P_m| <= 1 bounds the terms)
        raise GeometryError("sphere series: cos_theta must be finite numbers within [-1, 1]")
    if not (is_real(tol) and 0.0 < tol < 1.0):
        raise ConfigError(f"sphere series: tol must be a number in (0, 1), got {tol!r}")
    ct = np.clip(ct, -1.0, 1.0)
    x = 2.0 * np.pi * f * radius / speed_of_sound  # mu = ka, (F,)
    rho = np.inf if distance is None else float(distance) / radius
    if max_terms is None:
        n_terms = _series_terms(x, rho, tol)
        if n_terms > MAX_SERIES_TERMS:
            raise GeometryError(
                f"sphere series: ka up to {np.max(x):.4g}" + ("" if distance is None else
                f" with the source at {rho:.6g} radii") + f" needs ~{n_terms} terms, more than "
                f"{MAX_SERIES_TERMS}; the source is too close to the sphere or the frequency "
                "too high (or give max_terms)")
    else:
        n_terms = whole_number("sphere series: max_terms", max_terms, 1)
    y = x * rho
    tail = 1.0 if np.isinf(rho) else rho / (rho - 1.0)  # (rho inf: also 1e308 m away)
    # m = 0: h_0'(x) / h_0(x) = -h_1(x) / h_0(x), with h_1(x) / h_0(x) = 1/x - i
    rx = 1.0 / x - 1j  # R_m(x) = h_m(x) / h_{m-1}(x), here m = 1
    ry = None if distance is None else 1.0 / y - 1j
    w = np.ones(len(x), dtype=complex)  # h_m(y) h_0(x) / (h_0(y) h_m(x)), or (-i)^m h_0/h_m(x)
    total = (w / -rx)[:, None] * np.ones_like(ct)[None]
    p_prev, p_cur = np.ones_like(ct), ct.copy()  # P_0, P_1
    done = np.zeros(len(x), dtype=bool)
    m_min = 2.0 * x + 10.0
    for m in range(1, n_terms):
        w = w * ((-1j if ry is None else ry) / rx)
        coef = (2 * m + 1) * w / (1.0 / rx - (m + 1) / x)  # h_m'/h_m = 1/R_m - (m+1)/x
        coef = np.where(done, 0.0, coef)
        total += coef[:, None] * p_cur[None]
        bound = np.abs(coef) * tail
        done |= (m > m_min) & (bound < tol * np.max(np.abs(total), axis=1))
        if done.all():
            break
        rx = (2 * m + 1) / x - 1.0 / rx
        if ry is not None:
            ry = (2 * m + 1) / y - 1.0 / ry
        p_prev, p_cur = p_cur, ((2 * m + 1) * ct * p_cur - m * p_prev) / (m + 1)
    if not done.all():
        bad = f[~done]
        raise ConfigError(
            f"sphere series: not converged within {n_terms} terms at {bad.min():g}"
            + (f"-{bad.max():g}" if len(bad) > 1 else "") + " Hz (ka up to "
            f"{np.max(x[~done]):.4g}" + ("" if distance is None else f", r/a = {rho:.6g}")
            + "); give a larger max_terms")
    # both forms: -(e^{-i mu} / mu) sum_m (2m + 1) P_m w_m h_m(mu) / h_m'(mu)
    return -(np.exp(-1j * x) / x)[:, None] * total
