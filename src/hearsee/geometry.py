"""Frames, spherical <-> cartesian conversions and rotations.

Conventions (ROS REP 103, see README "Conventions"): x forward, y left, z up. Azimuth is measured
from +x toward +y (0 = front, 90 deg = left, 180 deg = back), elevation from the xy-plane toward
+z. Functions here work in radians unless their name ends in ``_deg``; distances are metres.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hearsee.errors import GeometryError

__all__ = [
    "angle_between",
    "cart_to_sph",
    "direction_deg",
    "sph_to_cart",
    "unit_vector_deg",
    "wrap_deg",
    "wrap_rad",
]


def sph_to_cart(azimuth: ArrayLike, elevation: ArrayLike, distance: ArrayLike = 1.0) -> NDArray:
    """Spherical (radians, metres) -> cartesian points, shape ``(..., 3)``.

    >>> np.round(sph_to_cart(np.pi / 2, 0.0, 2.0), 6)
    array([0., 2., 0.])
    """
    az = np.asarray(azimuth, dtype=float)
    el = np.asarray(elevation, dtype=float)
    r = np.asarray(distance, dtype=float)
    ce = np.cos(el)
    return np.stack(np.broadcast_arrays(r * ce * np.cos(az), r * ce * np.sin(az), r * np.sin(el)),
                    axis=-1)


def cart_to_sph(xyz: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
    """Cartesian points ``(..., 3)`` -> (azimuth rad in (-pi, pi], elevation rad, distance m)."""
    p = np.asarray(xyz, dtype=float)
    if p.shape[-1] != 3:
        raise GeometryError(f"expected points with 3 coordinates, got shape {p.shape}")
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    r = np.sqrt(x * x + y * y + z * z)
    az = np.arctan2(y, x)
    el = np.arctan2(z, np.hypot(x, y))
    return az, el, r


def unit_vector_deg(azimuth_deg: ArrayLike, elevation_deg: ArrayLike = 0.0) -> NDArray:
    """Unit direction vector(s) ``(..., 3)`` for azimuth/elevation in degrees."""
    return sph_to_cart(np.radians(azimuth_deg), np.radians(elevation_deg), 1.0)


def direction_deg(xyz: ArrayLike) -> tuple[NDArray, NDArray]:
    """Azimuth and elevation in degrees of point(s) or direction(s) ``(..., 3)``."""
    az, el, _ = cart_to_sph(xyz)
    return np.degrees(az), np.degrees(el)


def wrap_rad(angle: ArrayLike) -> NDArray:
    """Wrap angle(s) in radians to (-pi, pi]."""
    a = np.asarray(angle, dtype=float)
    w = np.mod(a + np.pi, 2 * np.pi) - np.pi
    return np.where(w == -np.pi, np.pi, w)


def wrap_deg(angle: ArrayLike) -> NDArray:
    """Wrap angle(s) in degrees to (-180, 180]."""
    a = np.asarray(angle, dtype=float)
    w = np.mod(a + 180.0, 360.0) - 180.0
    return np.where(w == -180.0, 180.0, w)


def angle_between(u: ArrayLike, v: ArrayLike) -> NDArray:
    """Angle in radians between direction vectors ``(..., 3)`` (need not be unit length)."""
    a = np.asarray(u, dtype=float)
    b = np.asarray(v, dtype=float)
    na = np.linalg.norm(a, axis=-1)
    nb = np.linalg.norm(b, axis=-1)
    if np.any(na == 0) or np.any(nb == 0):
        raise GeometryError("angle between a zero-length vector and another is undefined")
    c = np.sum(a * b, axis=-1) / (na * nb)
    return np.arccos(np.clip(c, -1.0, 1.0))
