"""Rigid-body BEM (hearsee.audio.bem) against the exact rigid-sphere series.

Tolerance (stated in hearsee.audio.bem and tested here): with a coarse 320-panel geodesic sphere
of radius 8.75 cm (about 9 panels per wavelength at 1.5 kHz), the BEM reproduces the Rayleigh
series (Duda & Martens 1998) at two antipodal "ears" for sources all around, up to 2 kHz
(including the first fictitious frequency ka = pi, 1.96 kHz, cured by CHIEF points):
|IID error| < 0.5 dB and |ITD (phase delay) error| < 10 us, far field and d0 = 0.5 m.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import eval_legendre, spherical_jn, spherical_yn

from hearsee.audio import bem
from hearsee.errors import ConfigError, GeometryError

A = 0.0875
C = 343.0


def _series_scipy(f, a, ct, r0=None, n_terms=80):
    """Independent evaluation of the same series with scipy's special functions."""
    mu = 2 * np.pi * f * a / C
    tot = 0
    for m in range(n_terms):
        dh = spherical_jn(m, mu, derivative=True) + 1j * spherical_yn(m, mu, derivative=True)
        if r0 is None:
            t = (2 * m + 1) * (-1j) ** (m + 1) / dh
        else:
            x = mu * r0 / a
            t = (2 * m + 1) * (spherical_jn(m, x) + 1j * spherical_yn(m, x)) / dh
        tot = tot + t[:, None] * eval_legendre(m, ct)[None]
    if r0 is None:
        return -tot / mu[:, None] ** 2
    rho = r0 / a
    return -(rho / mu[:, None]) * np.exp(-1j * mu[:, None] * rho) * tot


def test_sphere_series_matches_scipy_special_functions():
    f = np.array([100.0, 1000.0, 4000.0])
    ct = np.cos(np.deg2rad([0, 45, 90, 135, 180]))
    for r0 in (None, 0.5, 1.0):
        got = bem.sphere_transfer(f, A, ct, r0)
        np.testing.assert_allclose(got, _series_scipy(f, A, ct, r0), rtol=1e-8, atol=1e-10)


def test_sphere_series_limits():
    # low frequency: no scattering (H -> 1 everywhere); far distance -> plane wave
    h = bem.sphere_transfer([5.0], A, np.array([1.0, 0.0, -1.0]))
    np.testing.assert_allclose(np.abs(h), 1.0, atol=2e-3)
    far = bem.sphere_transfer([1000.0], A, np.array([1.0, -1.0]))
    near = bem.sphere_transfer([1000.0], A, np.array([1.0, -1.0]), distance=200.0)
    np.testing.assert_allclose(near, far, atol=2e-3)
    # the lit side is louder than the shadow side at 3 kHz (head shadow)
    h = bem.sphere_transfer([3000.0], A, np.array([1.0, -1.0]))
    assert abs(h[0, 0]) > 1.5 * abs(h[0, 1])


def _potential_flow(f, a, ct, r0):
    """The rigid sphere near a point source at low frequency, to first order in ka.

    ka -> 0 is potential flow (Laplace's equation, rigid = Neumann): h_m(z) ~ -i (2m-1)!! /
    z^(m+1) turns the series into sum_m (2m+1)/(m+1) t^m P_m(cos theta), t = a / r0, which is
    2 / R - ln((t - c + R) / (1 - c)) / t with R = sqrt(1 - 2 t c + t^2) (Kelvin's image source
    and line sink; generating function of P_m and its integral). The next order, i k (r0 - r0 H0):
    the free field's uniform i k / (4 pi) term, which a rigid body does not scatter, minus the
    reference's e^(i k r0). What is left is O((ka)^2)."""
    t = a / r0
    c = np.asarray(ct, dtype=float)
    root = np.sqrt(1 - 2 * t * c + t * t)
    with np.errstate(divide="ignore", invalid="ignore"):  # each form is 0/0 at one pole
        log = np.where(c > 0, np.log((1 + c) / (root - t + c)), np.log((t - c + root) / (1 - c)))
    h0 = 2 / root - log / t
    x = 2 * np.pi * np.asarray(f, dtype=float)[:, None] * a / C
    return h0[None] + 1j * x * (r0 / a) * (1 - h0[None])


def _series_rescaled(f, a, ct, r0, n_terms):
    """The series of bem.sphere_transfer by the textbook upward recursion of the Hankel
    functions themselves (h_{m+1} = (2m+1)/z h_m - h_{m-1}, h_m' = h_{m-1} - (m+1)/z h_m) and
    scipy's Legendre polynomials, a fixed number of terms; h_m(ka) and h_m(k r0) are divided by
    a common factor whenever they grow past 1e200 (their ratio, all the series uses, stays)."""
    out = np.zeros((len(f), len(ct)), dtype=complex)
    for i, fi in enumerate(f):
        x = 2 * np.pi * fi * a / C
        y = x * r0 / a
        hx = [np.exp(1j * x) / (1j * x), np.exp(1j * x) * (-1 / x - 1j / x**2)]
        hy = [np.exp(1j * y) / (1j * y), np.exp(1j * y) * (-1 / y - 1j / y**2)]
        tot = -hy[0] / hx[1] * np.ones(len(ct))
        for m in range(1, n_terms):
            tot = tot + (2 * m + 1) * eval_legendre(m, ct) * hy[1] / (hx[0] - (m + 1) / x * hx[1])
            hx = [hx[1], (2 * m + 1) / x * hx[1] - hx[0]]
            hy = [hy[1], (2 * m + 1) / y * hy[1] - hy[0]]
            if abs(hx[1]) > 1e200:
                s = abs(hx[1])
                hx, hy = [h / s for h in hx], [h / s for h in hy]
        out[i] = -(r0 / a / x) * np.exp(-1j * y) * tot
    return out


def test_sphere_series_near_source_matches_the_potential_flow_limit():
    # audit p03: h_m(ka) overflowed (inf / inf = NaN) for the many terms a source near the
    # sphere needs, and the stop test took the largest term over all frequencies, so one such
    # frequency kept every row summing into NaN. Before: all NaN for 1 Hz and 12 kHz asked
    # together (1.25 cm off the sphere), NaN at 0.5 mm off it.
    ct = np.array([1.0, 0.5, 0.0, -0.5, -1.0])
    for r0 in (0.1, 0.088):
        got = bem.sphere_transfer([1.0, 2.0, 12000.0], A, ct, r0)
        exact = _potential_flow([1.0, 2.0], A, ct, r0)
        # (the O((ka)^2) left: 1.4e-6 and 5.6e-6 of the largest |H| at 1 and 2 Hz)
        np.testing.assert_allclose(got[:2], exact, rtol=0, atol=1e-5 * np.abs(exact).max())
        assert abs(got[0, 0]) > 13.6  # the lit side: ~2 a / (r0 - a) times the free field
    # 12 kHz (ka = 19), 1.25 cm off: scipy's Hankel functions stay finite over the terms needed
    got = bem.sphere_transfer([1.0, 12000.0], A, ct, 0.1)[1:]
    ref = _series_scipy(np.array([12000.0]), A, ct, 0.1, n_terms=230)
    assert np.all(np.isfinite(ref))
    np.testing.assert_allclose(got, ref, rtol=1e-8)


def test_sphere_series_near_source_matches_the_rescaled_textbook_recursion():
    # audit p03: 1 kHz with the source 2.5 mm off the sphere gave -3.104-68.211j on the lit side
    # (the sum cut at 400 terms, 1 % off, no warning); 50-12000 Hz 1.25 cm off: all NaN.
    ct = np.array([1.0, 0.0, -1.0])
    ref_ok = _series_rescaled([1000.0, 4000.0], A, ct, 0.5, 80)  # the reference itself
    np.testing.assert_allclose(ref_ok, _series_scipy(np.array([1000.0, 4000.0]), A, ct, 0.5),
                               rtol=1e-10)
    f = np.array([50.0, 500.0, 2000.0, 12000.0])
    np.testing.assert_allclose(bem.sphere_transfer(f, A, ct, 0.1),
                               _series_rescaled(f, A, ct, 0.1, 400), rtol=1e-8)
    got = bem.sphere_transfer([1000.0], A, ct, 0.09)
    ref = _series_rescaled([1000.0], A, ct, 0.09, 1400)  # (a / r0)^1400 = 1e-17
    np.testing.assert_allclose(got, ref, rtol=1e-8)
    assert abs(ref[0, 0] - (-3.159 - 68.917j)) < 1e-3
    # a cap that the sum needs more terms than is an error, not a truncated sum
    with pytest.raises(ConfigError, match="not converged within 300 terms at 1000 Hz"):
        bem.sphere_transfer([1000.0], A, ct, 0.09, max_terms=300)


def test_sphere_series_converges_at_high_ka():
    # audit p11: the sum stopped at max_terms=400 whatever ka, so above ka ~ 350 it was cut
    # while its terms were still large: a = 0.3 m at 96 kHz (ka = 528) gave |H| = 4.158 on the
    # lit side, where a large rigid sphere doubles the pressure (geometric acoustics: 2.000).
    ct = np.array([1.0, 0.0, -1.0])
    for f, a in ((96e3, 0.3), (1e6, A)):  # ka = 528 and 1603
        ka = 2 * np.pi * f * a / C
        n_ref = int(ka) + 200  # past ka the terms fall faster than exponentially
        for r0 in (None, 3 * a):
            got = bem.sphere_transfer([f], a, ct, r0)
            ref = _series_scipy(np.array([f]), a, ct, r0, n_terms=n_ref)
            assert np.all(np.isfinite(ref))
            np.testing.assert_allclose(got, ref, rtol=1e-8, atol=1e-10)
        assert abs(bem.sphere_transfer([f], a, [1.0])[0, 0]) == pytest.approx(2.0, abs=0.01)
    # more terms than MAX_SERIES_TERMS (a source 30 um off the sphere): an error, not minutes
    with pytest.raises(GeometryError, match="too close to the sphere or the frequency too high"):
        bem.sphere_transfer([100.0], A, [1.0], A + 30e-6)


@pytest.mark.slow
def test_bem_reproduces_rigid_sphere_itd_iid():
    mesh = bem.sphere_mesh(A, 4)
    assert mesh.n_panels == 320
    mics = np.array([[0.0, -A, 0.0], [0.0, A, 0.0]])
    freqs = np.array([300.0, 1000.0, 1960.0])  # 1960 Hz: ka = pi, first fictitious frequency
    sol = bem.solve_adjoint(mesh, freqs, mics, C, on_surface_tol=1e-3)
    az = np.deg2rad(np.arange(0, 360, 30))
    u = np.c_[np.cos(az), np.sin(az), np.zeros_like(az)]
    for dist in (None, 0.5):
        src = u if dist is None else u * dist
        h = bem.transfer_functions(sol, src, far_field=dist is None, speed_of_sound=C)  # S,2,F
        # exact: angle between source direction and each ear, seen from the centre
        if dist is None:
            ct0, ct1 = u @ (mics[0] / A), u @ (mics[1] / A)
        else:
            ct0, ct1 = (src @ mics[0]) / (dist * A), (src @ mics[1]) / (dist * A)
        e0 = bem.sphere_transfer(freqs, A, ct0, dist, C).T
        e1 = bem.sphere_transfer(freqs, A, ct1, dist, C).T
        iid_b = 20 * np.log10(np.abs(h[:, 0] / h[:, 1]))
        iid_e = 20 * np.log10(np.abs(e0 / e1))
        itd_b = np.angle(h[:, 0] * np.conj(h[:, 1])) / (2 * np.pi * freqs)
        itd_e = np.angle(e0 * np.conj(e1)) / (2 * np.pi * freqs)
        assert np.max(np.abs(iid_b - iid_e)) < 0.5
        assert np.max(np.abs(itd_b - itd_e)) < 10e-6
        # and the head shadow is really there (IID of several dB at 90 deg, 1.96 kHz)
        assert abs(iid_e[3, 2]) > 3.0


def _cube():
    v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return v, f


def test_closed_mesh_checks():
    v, f = _cube()
    bem.check_closed_mesh(v, f)  # a valid closed cube
    with pytest.raises(GeometryError, match="open"):
        bem.check_closed_mesh(v, f[:-1])
    g = f.copy()
    g[0] = g[0][::-1]
    with pytest.raises(GeometryError, match="oriented"):
        bem.check_closed_mesh(v, g)
    with pytest.raises(GeometryError, match="inward"):
        bem.check_closed_mesh(v, f[:, ::-1])
    with pytest.raises(GeometryError, match="degenerate"):
        bem.check_closed_mesh(np.vstack([v, v[:1]]), np.vstack([f, [[0, 8, 1]]]))


def test_geodesic_sphere_is_closed_and_winding_number():
    v, f = bem.geodesic_sphere(3)
    assert len(f) == 180
    bem.check_closed_mesh(v, f)
    mesh = bem.TriMesh(v, f)
    w = mesh.winding_number([[0, 0, 0], [2, 0, 0], [0.3, 0.2, -0.1]])
    np.testing.assert_allclose(w, [1, 0, 1], atol=1e-9)
    q, d, _ = mesh.closest_points([[2.0, 0, 0]])
    assert 1.0 - 1e-9 < d[0] < 1.05 and np.linalg.norm(q[0]) <= 1.0 + 1e-9


def test_geodesic_sphere_and_sphere_mesh_refuse_bad_sizes():
    # found in the 2026-12-02 audit: int(n) took 1.5 as 1 (20 panels instead of an error), "2"
    # and True as numbers, raised builtin ValueError/TypeError/OverflowError on text, None,
    # NaN and inf, and 10**6 asked for 2e13 triangles (the process was killed, out of memory);
    # sphere_mesh turned its faces inward for a negative radius and raised numpy's ValueError
    # on text
    for n in (0, -1, 1.5, "2", True, None, float("nan"), float("inf"),
              bem.MAX_GEODESIC_SUBDIVISION + 1, 10**6):
        with pytest.raises(GeometryError, match="geodesic sphere subdivision"):
            bem.geodesic_sphere(n)
    for r in (-A, 0.0, "a", np.nan):
        with pytest.raises(GeometryError, match="sphere radius"):
            bem.sphere_mesh(r, 2)
    with pytest.raises(GeometryError, match="sphere centre"):
        bem.sphere_mesh(A, 2, centre=(0.0, 0.0))
    v, f = bem.geodesic_sphere(np.int64(2))  # numpy integers are integers
    assert len(f) == 80
    m = bem.sphere_mesh(A, 2, centre=(0, 0, 1))
    np.testing.assert_array_equal(m.vertices, v * A + [0.0, 0.0, 1.0])


def test_winding_number_is_one_half_on_the_surface():
    # audit p15: a point on a face got 0 or 1 by the rounding of its own face's solid angle
    # (+-2 pi across the face): 5 of 20 centroids and 3 of 20 barycentric points read "inside"
    mesh = bem.sphere_mesh(A, 3)
    c = mesh.corners[:40]
    on = {"centroid": mesh.centroids[:40], "barycentric": c.transpose(0, 2, 1) @ [0.2, 0.3, 0.5],
          "edge midpoint": 0.5 * (c[:, 0] + c[:, 1]), "vertex": c[:, 2]}
    for what, p in on.items():
        np.testing.assert_array_equal(mesh.winding_number(p), 0.5, err_msg=what)
    # just off the faces (1e-7 of the radius): exactly 0 outside and 1 inside, as before
    n = mesh.normals[:40]
    np.testing.assert_allclose(mesh.winding_number(on["barycentric"] + 1e-7 * A * n), 0.0,
                               atol=1e-9)
    np.testing.assert_allclose(mesh.winding_number(on["barycentric"] - 1e-7 * A * n), 1.0,
                               atol=1e-9)


def test_solve_adjoint_at_panel_centroids_with_the_default_tolerance():
    # audit p15/p16: with on_surface_tol = 0 (the default) a point on a panel (dist 1e-17 m)
    # whose winding rounded to 1 was "inside the body", and at a panel centroid one of the 8x8
    # quadrature points of its own panel coincided with it: free term c ~ 1e27 instead of 1/2
    mesh = bem.sphere_mesh(A, 4)
    x = mesh.centroids[:6]
    freqs = np.array([500.0, 1500.0])
    sol = bem.solve_adjoint(mesh, freqs, x, C)
    # on a flat face the free term is exactly 1/2 (the quadrature of the neighbours: 0.13 %)
    np.testing.assert_allclose(sol.c, 0.5, atol=2e-3)
    # a plane wave from straight above each centroid: the lit side of a rigid sphere of the
    # centroid's radius (the mesh is inscribed in the 8.75 cm sphere)
    for e in range(len(x)):
        u = x[e] / np.linalg.norm(x[e])
        h = bem.transfer_functions(sol, [u], True, C)[0, e]
        exact = bem.sphere_transfer(freqs, np.linalg.norm(x[e]), [1.0], None, C)[:, 0]
        np.testing.assert_allclose(np.abs(h), np.abs(exact), rtol=5e-3)


def test_solve_adjoint_refuses_non_finite_frequencies_and_speed():
    # found in review: only "f <= 0" was tested, so NaN or inf frequencies and a zero or NaN
    # speed of sound gave an all-NaN solution (transfer functions NaN) without a word
    mesh = bem.sphere_mesh(A, 4)
    mics = np.array([[0.0, -A, 0.0], [0.0, A, 0.0]])
    for freqs in ([np.nan], [300.0, np.inf], [0.0], [-300.0]):
        with pytest.raises(GeometryError, match="frequencies"):
            bem.solve_adjoint(mesh, freqs, mics, C, on_surface_tol=1e-3)
    for c in (0.0, -C, np.nan, np.inf):
        with pytest.raises(GeometryError, match="speed of sound"):
            bem.solve_adjoint(mesh, [300.0], mics, c, on_surface_tol=1e-3)
    # progress that cannot be called: a TypeError after the first frequency was solved
    with pytest.raises(ConfigError, match="^solve_adjoint: progress must be a callable"):
        bem.solve_adjoint(mesh, [300.0], mics, C, on_surface_tol=1e-3, progress="x")


def test_solve_adjoint_refuses_malformed_evaluation_points_and_speed():
    # found in the 2026-12-02 audit: a NaN evaluation point raised scipy's "'x' must be
    # finite" ValueError, no point or [x, y] numpy's broadcasting ValueError, a speed of sound
    # given as text numpy's TypeError
    mesh = bem.sphere_mesh(A, 4)
    for pts in ([[0.0, np.nan, 0.0]], np.zeros((0, 3)), [[0.0, 0.1]], "abc"):
        with pytest.raises(GeometryError, match="evaluation points"):
            bem.solve_adjoint(mesh, [300.0], pts, C)
    with pytest.raises(GeometryError, match="speed of sound"):
        bem.solve_adjoint(mesh, [300.0], [[0.0, 0.1, 0.0]], "343")
    assert bem.solve_adjoint(mesh, [300.0], [[0.0, 0.1, 0.0]], C).v.shape[:2] == (1, 1)


def test_solve_adjoint_refuses_bad_chief_counts_no_frequency_and_a_bad_tolerance():
    # found in the 2026-12-02 audit: n_chief 0 (and 1-3, below the 4 points chief_points needs)
    # was "mask body too thin for CHIEF interior points", -1 numpy's "negative dimensions"
    # ValueError, 2.5 and text a TypeError; no frequency ran the whole setup and returned an
    # empty solution; text frequencies raised numpy's ValueError; on_surface_tol NaN counted as
    # 0 and text raised numpy's UFuncTypeError
    mesh = bem.sphere_mesh(A, 4)
    mics = [[0.0, -A, 0.0], [0.0, A, 0.0]]
    for n in (0, 1, 3, -1, 2.5, "16", None):
        with pytest.raises(GeometryError, match="n_chief"):
            bem.solve_adjoint(mesh, [500.0], mics, C, n_chief=n, on_surface_tol=1e-3)
    for freqs in ([], np.zeros(0), "abc", ["500"]):
        with pytest.raises(GeometryError, match="frequencies"):
            bem.solve_adjoint(mesh, freqs, mics, C, on_surface_tol=1e-3)
    for tol in (np.nan, -1e-3, "1e-3", np.inf):
        with pytest.raises(GeometryError, match="on_surface_tol"):
            bem.solve_adjoint(mesh, [500.0], mics, C, on_surface_tol=tol)
    with pytest.raises(GeometryError, match="CHIEF points"):
        bem.chief_points(mesh, 0)
    # the smallest count works (a sphere of 320 panels has room for it)
    sol = bem.solve_adjoint(mesh, [500.0], mics, C, n_chief=bem.MIN_CHIEF_POINTS,
                            on_surface_tol=1e-3)
    assert sol.v.shape == (1, 2, mesh.n_panels + bem.MIN_CHIEF_POINTS)


def test_solve_adjoint_refuses_evaluation_points_inside_the_body():
    # found in review: the docstring asks for points on or outside the body, but a point 2 cm
    # from the centre of an 8.75 cm sphere was solved: free-term c ~ 0 and |H| ~ 1.5, while
    # there is no sound field inside a rigid body
    mesh = bem.sphere_mesh(A, 4)
    with pytest.raises(GeometryError, match="inside the body"):
        bem.solve_adjoint(mesh, [500.0], [[0.0, 0.0, 0.02], [0.0, A, 0.0]], C,
                          on_surface_tol=1e-3)
    # on the surface (within the tolerance) and outside stay valid
    sol = bem.solve_adjoint(mesh, [500.0], [[0.0, A, 0.0], [0.0, 0.0, 2 * A]], C,
                            on_surface_tol=1e-3)
    # free term: the exterior solid-angle fraction, 1/2 on a smooth part (a bit more at a convex
    # corner of the mesh, where this point is projected), 1 in the air
    assert 0.5 - 1e-6 < sol.c[0] < 0.75 and sol.c[1] == pytest.approx(1.0, abs=1e-3)


def test_solve_adjoint_refuses_open_and_degenerate_meshes():
    # audit p09: solve_adjoint never checked the mesh: a sphere with a hole (1.3 cm wide at +x,
    # away from the ears) gave |H| = [0.969, 1.361] for the exact [1.108, 1.538] at 1 kHz, an
    # open hemisphere [0.833, 1.252], a zero-area face NaN, all without an error; inverted
    # faces were "too thin for CHIEF interior points"
    v, f = bem.geodesic_sphere(3)
    v = v * A
    mics = np.array([[0.0, -A, 0.0], [0.0, A, 0.0]])
    centre_x = v[f].mean(axis=1)[:, 0]
    bad = {"open": (v, f[centre_x < 0.6 * A]), "open ": (v, f[centre_x < 0.0]),
           "degenerate": (v, np.vstack([f, [[0, 0, 1]]])), "inward": (v, f[:, ::-1]),
           "oriented": (v, np.vstack([f[:1, ::-1], f[1:]]))}
    for what, (vv, ff) in bad.items():
        with pytest.raises(GeometryError, match=f"^BEM mesh: .*{what.strip()}"):
            bem.solve_adjoint(bem.TriMesh(vv, ff), [1000.0], mics, C, on_surface_tol=1e-3)
    with pytest.raises(GeometryError, match="TriMesh"):
        bem.solve_adjoint((v, f), [1000.0], mics, C, on_surface_tol=1e-3)
    sol = bem.solve_adjoint(bem.TriMesh(v, f), [1000.0], mics, C, on_surface_tol=1e-3)
    assert np.all(np.isfinite(sol.v))  # the closed sphere is solved as before


def test_transfer_functions_refuse_impossible_sources():
    # audit p08: no check at all: a source inside the rigid body gave finite numbers (no sound
    # leaves a closed rigid body), one at the origin H = 0 everywhere (the normalising free
    # field is infinite there), on the surface or at a microphone NaN (RuntimeWarnings only),
    # a far-field direction [0, 0, 0] or a NaN coordinate NaN
    mesh = bem.sphere_mesh(A, 3)
    mics = np.array([[0.0, -A, 0.0], [0.0, 0.0, 2 * A]])  # on the surface, in the air
    sol = bem.solve_adjoint(mesh, [1000.0], mics, C, on_surface_tol=2e-3)  # (mesh 1.8 mm in)
    cases = [([[0.03, 0.0, 0.0]], False, "inside the body"),
             ([[0.0, 0.0, 0.0]], False, "inside the body"),
             ([[1.0, 0.0, 0.0], mesh.centroids[5]], False, "^source 1 .* on the surface of"),
             ([mesh.vertices[7]], False, "on the surface of"),
             ([sol.eval_points[0]], False, "on the surface of"),
             ([sol.eval_points[1]], False, "coincides with evaluation point 1"),
             ([[0.0, 0.0, 0.0]], True, "no direction"),
             ([[np.nan, 0.0, 1.0]], False, "finite"), ([[np.inf, 0.0, 1.0]], True, "finite")]
    for src, far, match in cases:
        with pytest.raises(GeometryError, match=match):
            bem.transfer_functions(sol, src, far, C)
    # incident_field alone: a source at the origin of the frame or at one of its points
    with pytest.raises(GeometryError, match="origin of the frame"):
        bem.incident_field([[0.0, 0.0, 1.0]], [1.0], [[0.0, 0.0, 0.0]])
    with pytest.raises(GeometryError, match="coincides with point 0"):
        bem.incident_field([[0.0, 0.0, 1.0]], [1.0], [[0.0, 0.0, 1.0]])
    # a source 1 mm above a panel is a valid source: its field is the exact point source's
    x = mesh.centroids[5] + 1e-3 * mesh.normals[5]
    h = bem.transfer_functions(sol, [x], False, C)
    assert np.all(np.isfinite(h))
    k = 2 * np.pi * 1000.0 / C
    r, d0 = np.linalg.norm(x - mics[1]), np.linalg.norm(x)
    np.testing.assert_allclose(bem.incident_field(mics[1:], [k], [x])[0, 0, 0],
                               d0 / r * np.exp(1j * k * (r - d0)), rtol=1e-12)


def test_transfer_functions_use_the_solutions_speed_of_sound():
    # audit p20: the solution did not record its speed of sound and transfer_functions took
    # 343 m/s unless told: solved for 330 m/s, the default call was 0.61 dB and 6.2 degrees
    # off the rigid sphere at 1.5 kHz (0.16 dB and 1.8 degrees with the right c)
    c = 330.0
    mesh = bem.sphere_mesh(A, 4)
    mics = np.array([[0.0, -A, 0.0], [0.0, A, 0.0]])
    freqs = np.array([500.0, 1500.0])
    sol = bem.solve_adjoint(mesh, freqs, mics, speed_of_sound=c, on_surface_tol=1e-3)
    u = np.array([[0.0, 1.0, 0.0]])
    exact = bem.sphere_transfer(freqs, A, [-1.0, 1.0], None, c).T  # (2 ears, F)
    h = bem.transfer_functions(sol, u, True)[0]
    assert np.max(np.abs(20 * np.log10(np.abs(h / exact)))) < 0.25
    assert np.max(np.abs(np.degrees(np.angle(h / exact)))) < 2.5
    # the same c given explicitly (as every caller did) is the same answer; another is refused
    np.testing.assert_array_equal(bem.transfer_functions(sol, u, True, c)[0], h)
    with pytest.raises(ConfigError, match="computed for a speed of sound of 330 m/s, not 343"):
        bem.transfer_functions(sol, u, True, 343.0)
    with pytest.raises(GeometryError, match="speed of sound must be a finite number > 0"):
        bem.transfer_functions(sol, u, True, np.nan)


def test_sphere_series_refuses_impossible_settings():
    # found in review: a negative radius or frequency silently gave the complex conjugate of the
    # answer (the wrong time convention), a source inside the sphere (5 cm < 8.75 cm), a zero
    # radius, frequency or speed of sound NaN
    ok = bem.sphere_transfer([1000.0], A, [1.0, -1.0], 0.5)
    assert np.all(np.isfinite(ok))
    for kw in ({"freqs": [-1000.0]}, {"freqs": [0.0]}, {"freqs": [np.nan]},
               {"radius": -A}, {"radius": 0.0}, {"distance": 0.05}, {"distance": A},
               {"distance": np.nan}, {"speed_of_sound": 0.0}):
        args = {"freqs": [1000.0], "radius": A, "cos_theta": [1.0, -1.0], "distance": 0.5}
        args.update(kw)
        with pytest.raises(GeometryError):
            bem.sphere_transfer(**args)


def test_sphere_series_refuses_empty_and_non_numeric_settings():
    # found in the 2026-12-02 audit: no frequency or no angle raised numpy's "zero-size array
    # to reduction operation" ValueError, a radius, speed of sound, distance or tol given as
    # text (or None) numpy's TypeError, text frequencies or angles its ValueError, and a radius
    # of True was taken as 1 m
    args = {"freqs": [1000.0], "radius": A, "cos_theta": [1.0, -1.0], "distance": 0.5}
    for kw in ({"freqs": []}, {"cos_theta": []}, {"freqs": "abc"}, {"cos_theta": "a"},
               {"radius": "0.1"}, {"radius": None}, {"radius": True}, {"speed_of_sound": "x"},
               {"distance": "2"}):
        with pytest.raises(GeometryError, match="sphere series"):
            bem.sphere_transfer(**{**args, **kw})
    for tol in ("x", None):
        with pytest.raises(ConfigError, match="tol"):
            bem.sphere_transfer(**args, tol=tol)
    # numpy scalars and ints are numbers: the same answer
    np.testing.assert_array_equal(
        bem.sphere_transfer(np.array([1000]), np.float64(A), 1, np.float32(0.5), 343),
        bem.sphere_transfer([1000.0], A, [1.0], float(np.float32(0.5)), 343.0))


@pytest.mark.parametrize("points, k, match", [
    (None, [1.0], r"^incident_field: points: expected points"),
    ("abc", [1.0], r"^incident_field: points: expected points"),
    ([[0.0, 0.1]], [1.0], r"^incident_field: points: expected points .* got shape \(1, 2\)"),
    ([[0.0, 0.0, np.nan]], [1.0], r"^incident_field: points must be finite"),
    (np.zeros((2, 2, 3)) + 0.1, [1.0], r"^incident_field: points must be .* shape \(P, 3\)"),
    ([[0.0, 0.0, 0.1]], None, r"^incident_field: k must be wavenumbers"),
    ([[0.0, 0.0, 0.1]], "abc", r"^incident_field: k must be wavenumbers"),
    ([[0.0, 0.0, 0.1]], ["1.0"], r"^incident_field: k must be wavenumbers"),
    ([[0.0, 0.0, 0.1]], [np.nan], r"^incident_field: k must be .* out of range"),
    ([[0.0, 0.0, 0.1]], [-1.0], r"^incident_field: k must be .* >= 0 .* out of range"),
    ([[0.0, 0.0, 0.1]], [], r"^incident_field: k must be .* one or more .* shape \(0,\)"),
    ([[0.0, 0.0, 0.1]], [[1.0]], r"^incident_field: k must be .* shape \(F,\)"),
])
def test_incident_field_refuses_points_and_wavenumbers_that_are_no_numbers(points, k, match):
    """points=None (or k=None, or a NaN in either) gave NaN without a word; text was numpy's
    builtin ValueError, points of 2 coordinates its broadcasting ValueError, a k of shape
    (1, 1) an output of 4 dimensions. The well-formed call answers as before."""
    src = [[1.0, 0.0, 0.0]]
    with pytest.raises(GeometryError, match=match):
        bem.incident_field(points, k, src)
    x, kk = np.array([[0.0, 0.0, 0.1]]), 2.0
    r = np.linalg.norm(np.array(src[0]) - x[0])
    assert bem.incident_field(x, [kk], src)[0, 0, 0] == 1.0 / r * np.exp(1j * kk * (r - 1.0))
    assert bem.incident_field(x[0], kk, src).shape == (1, 1, 1)


@pytest.mark.parametrize("vertices, faces, match", [
    (None, None, r"^TriMesh: vertices must be .* got not numbers"),
    ("abc", "def", r"^TriMesh: vertices must be .* got not numbers"),
    ([[0, 0, 0], [1, 0, 0], [0, 1]], [[0, 1, 2]], r"^TriMesh: vertices must be .* not numbers"),
    (np.eye(3)[:, :2], [[0, 1, 2]], r"^TriMesh: vertices must be .* got shape \(3, 2\)"),
    ([[0, 0, 0], [1, 0, 0], [0, 1, np.nan]], [[0, 1, 2]], r"^TriMesh: vertices .* non-finite"),
    (np.eye(3), None, r"^TriMesh: faces must be integer vertex indices.* got not numbers"),
    (np.eye(3), "012", r"^TriMesh: faces must be integer vertex indices.* got not numbers"),
    (np.eye(3), [[0.0, 1.0, 2.0]], r"^TriMesh: faces must be .* got dtype float64"),
    (np.eye(3), np.zeros((0, 3), int), r"^TriMesh: faces must be .* got shape \(0, 3\)"),
    (np.eye(3), [0, 1, 2], r"^TriMesh: faces must be .* got shape \(3,\)"),
    (np.eye(3), [[0, 1, 3]], r"^TriMesh: faces must index the 3 vertices \(0 to 2\)"),
    (np.eye(3), [[0, 1, -1]], r"^TriMesh: faces must index the 3 vertices"),
])
def test_trimesh_refuses_vertices_and_faces_that_are_no_mesh(vertices, faces, match):
    """TriMesh(None, None) was an empty mesh without a word (n_panels then a builtin
    TypeError), text a mesh of as many panels as characters, a negative index the last
    vertex; now a GeometryError naming the argument. A triangle is still a TriMesh (closure is
    check_closed_mesh's test), and float vertices are kept as given."""
    with pytest.raises(GeometryError, match=match):
        bem.TriMesh(vertices, faces)
    v = np.eye(3)
    tri = bem.TriMesh(v, [[0, 1, 2]])
    assert tri.vertices is v and tri.n_panels == 1 and tri.areas[0] == pytest.approx(3**0.5 / 2)
    assert bem.TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]).vertices.dtype == float


def test_mesh_queries_and_mesh_check_refuse_what_is_no_points():
    """winding_number / closest_points of None gave NaN (and face 0) without a word, of text
    numpy's builtin ValueError; check_closed_mesh of text numpy's ValueError too."""
    mesh = bem.sphere_mesh(A, 2)
    for method in ("winding_number", "closest_points"):
        for points, match in ((None, "expected points"), ("abc", "expected points"),
                              ([[np.nan, 0.0, 0.0]], "must be finite"),
                              (np.zeros((2, 2, 3)), r"shape \(P, 3\)")):
            with pytest.raises(GeometryError, match=rf"^{method}: points"):
                getattr(mesh, method)(points)
            with pytest.raises(GeometryError, match=match):
                getattr(mesh, method)(points)
    np.testing.assert_allclose(mesh.winding_number([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), [1, 0],
                               atol=1e-9)
    assert mesh.closest_points([1.0, 0.0, 0.0])[1][0] == pytest.approx(1.0 - A, abs=A / 10)
    for v, f, match in (("abc", mesh.faces, "^mesh: vertices must be"),
                        (mesh.vertices, "def", "^mesh: faces must be")):
        with pytest.raises(GeometryError, match=match):
            bem.check_closed_mesh(v, f)
    bem.check_closed_mesh(mesh.vertices, mesh.faces)


def test_transfer_functions_and_incident_field_refuse_a_far_field_or_chunk_of_another_kind():
    """far_field="no" was truthy: plane waves from the source's direction without a word
    (None a point source); a chunk of None, text, 2.5 or 0 was a builtin TypeError /
    ValueError of range(). Both flags as bools (numpy's too) and any chunk >= 1 answer alike."""
    mesh = bem.sphere_mesh(A, 3)
    sol = bem.solve_adjoint(mesh, [500.0], [[0.0, -A, 0.0], [0.0, A, 0.0]], C,
                            on_surface_tol=2e-3)
    src = [[1.0, 0.3, 0.0], [0.0, 2.0, 0.5]]
    for flag in ("no", "False", None, 0, 1.0):
        with pytest.raises(ConfigError, match="^transfer_functions: far_field must be True or"):
            bem.transfer_functions(sol, src, flag)
        with pytest.raises(ConfigError, match="^incident_field: far_field must be True or"):
            bem.incident_field([[0.0, 0.0, 0.1]], [1.0], src, flag)
    for chunk in (None, "8", 2.5, 0, -1, True):
        with pytest.raises(ConfigError, match="^transfer_functions: chunk must be an integer"):
            bem.transfer_functions(sol, src, chunk=chunk)
    for far in (False, True):
        want = bem.transfer_functions(sol, src, far)
        # (to rounding: chunks of another length take numpy's vector loops another way -- a
        # last-bit difference with AVX2 kernels, none with AVX-512)
        np.testing.assert_allclose(bem.transfer_functions(sol, src, np.bool_(far), chunk=1),
                                   want, rtol=1e-12, atol=0)
        np.testing.assert_array_equal(bem.incident_field([[0.0, 0.0, 0.1]], [1.0], src,
                                                         np.bool_(far)),
                                      bem.incident_field([[0.0, 0.0, 0.1]], [1.0], src, far))
