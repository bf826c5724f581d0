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
from hearsee.errors import GeometryError

A = 0.0875
C = 343.0


def _series_scipy(f, a, ct, r0=None):
    """Independent evaluation of the same series with scipy's special functions."""
    mu = 2 * np.pi * f * a / C
    tot = 0
    for m in range(80):
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
