"""Frames, spherical <-> cartesian conversions and rotations.

Conventions (ROS REP 103, see README "Conventions"): x forward, y left, z up. Azimuth is measured
from +x toward +y (0 = front, 90 deg = left, 180 deg = back), elevation from the xy-plane toward
+z. Functions here work in radians unless their name ends in ``_deg``; distances are metres.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from hearsee.config import (
    all_real,
    as_float_array,
    is_real,
    object_entries,
    real_entries,
    whole_number,
)
from hearsee.errors import GeometryError

__all__ = [
    "MAX_ANGLE_DEG",
    "HeadPose",
    "angle_between",
    "array_to_robot",
    "as_pose",
    "cart_to_sph",
    "check_angle_limits",
    "check_camera_mount",
    "check_head_offset",
    "check_head_pivot",
    "direction_deg",
    "fibonacci_sphere",
    "head_rotation",
    "mic_positions_at",
    "norm_scale",
    "robot_to_array",
    "sph_to_cart",
    "unit_vector_deg",
    "vector_length",
    "wrap_deg",
    "wrap_rad",
]


def sph_to_cart(azimuth: ArrayLike, elevation: ArrayLike, distance: ArrayLike = 1.0) -> NDArray:
    """Spherical (radians, metres) -> cartesian points, shape ``(..., 3)``; the three arguments
    broadcast together (GeometryError when their shapes do not).

    >>> np.round(sph_to_cart(np.pi / 2, 0.0, 2.0), 6)
    array([0., 2., 0.])
    """
    az, el, r = (_reals(v, what) for v, what in ((azimuth, "azimuth"), (elevation, "elevation"),
                                                  (distance, "distance")))
    try:  # (numpy's broadcast ValueError before, e.g. two azimuths and three elevations)
        np.broadcast_shapes(az.shape, el.shape, r.shape)
    except ValueError:
        raise GeometryError(f"sph_to_cart: azimuth, elevation and distance must have "
                            f"broadcastable shapes, got {az.shape}, {el.shape} and "
                            f"{r.shape}") from None
    ce = np.cos(el)
    return np.stack(np.broadcast_arrays(r * ce * np.cos(az), r * ce * np.sin(az), r * np.sin(el)),
                    axis=-1)


#: A coordinate beyond this magnitude (metres) is scaled down before squares are summed (the
#: square of 1.4e154 already overflows float), and a vector whose largest coordinate is below
#: its inverse is scaled up (the squares of 1e-160 underflow to zero).
_SQUARE_SAFE = 1e150


def _reals(value: Any, what: str) -> NDArray:
    """``value`` as a float array of any shape when every entry is a real number (NaN and the
    infinities pass through, as numpy would map them); GeometryError naming ``what`` for text,
    bools, complex numbers, None or a ragged list (numpy raised a builtin TypeError or
    ValueError, or read ``True`` as 1). A float (Python's or numpy's float64) is taken as it
    is."""
    if isinstance(value, float):
        return np.asarray(value)
    return as_float_array(value, what, finite=False, error=GeometryError)


def norm_scale(v: ArrayLike) -> NDArray:
    """The factor ``(..., 1)`` to divide vector(s) ``(..., 3)`` by before a Euclidean norm: the
    largest |coordinate| of a vector with one beyond 1e150 or with none above 1e-150 (and not
    all zero), else 1.0 (``v / 1.0`` is ``v`` bit for bit, so every ordinary result stays as
    it was). ``v / k`` has the direction of ``v`` and squares that cannot overflow or vanish:
    its norm gives the direction of (1e300, 1e300, 0), which ``np.linalg.norm`` made inf (a
    RuntimeWarning, then zero TDOAs), and of (1e-300, 0, 0), which it made 0; ``k * |v / k|``
    is the length. A non-finite vector is left as it is (1.0). The one guard of
    :func:`cart_to_sph`, the far-field directions of
    :meth:`hearsee.audio.arrays.MicArray.tdoa_far` and the free-field and masked
    simulators."""
    p = _reals(v, "vector")
    if p.shape[-1:] != (3,):
        raise GeometryError(f"norm_scale needs vectors (..., 3), got shape {p.shape}")
    big = np.max(np.abs(p), axis=-1, keepdims=True)
    scale = np.isfinite(big) & ((big > _SQUARE_SAFE) | ((big > 0) & (big < 1.0 / _SQUARE_SAFE)))
    return np.where(scale, big, 1.0)


def vector_length(v: ArrayLike) -> NDArray:
    """Euclidean lengths ``(...)`` of vectors ``(..., 3)`` without overflow or underflow
    (:func:`norm_scale`): 1.41e300 for (1e300, 1e300, 0), not inf; ordinary vectors' lengths
    bit for bit as ``np.linalg.norm``'s."""
    k = norm_scale(v)
    return k[..., 0] * np.linalg.norm(np.asarray(v, dtype=float) / k, axis=-1)


def cart_to_sph(xyz: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
    """Cartesian points ``(..., 3)`` -> (azimuth rad in (-pi, pi], elevation rad, distance m).
    The distance is computed without overflow (:func:`norm_scale`): 1.41e300 m for
    (1e300, 1e300, 0), not inf."""
    p = as_points(xyz)
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    k = norm_scale(p)[..., 0]
    xs, ys, zs = x / k, y / k, z / k
    r = k * np.sqrt(xs * xs + ys * ys + zs * zs)
    az = np.arctan2(y, x)
    az = np.where(az == -np.pi, np.pi, az)  # arctan2(-0.0, -1) = -pi
    el = np.arctan2(z, np.hypot(x, y))
    # + 0.0 turns arctan2's -0.0 (a coordinate of -0.0, e.g. an in-plane solution) into 0.0,
    # which users saw printed as "elevation -0.0"; every other value is unchanged
    return az + 0.0, el + 0.0, r


def unit_vector_deg(azimuth_deg: ArrayLike, elevation_deg: ArrayLike = 0.0) -> NDArray:
    """Unit direction vector(s) ``(..., 3)`` for azimuth/elevation in degrees."""
    return sph_to_cart(np.radians(_reals(azimuth_deg, "azimuth_deg")),
                       np.radians(_reals(elevation_deg, "elevation_deg")), 1.0)


def direction_deg(xyz: ArrayLike) -> tuple[NDArray, NDArray]:
    """Azimuth and elevation in degrees of point(s) or direction(s) ``(..., 3)``."""
    az, el, _ = cart_to_sph(xyz)
    return np.degrees(az), np.degrees(el)


def wrap_rad(angle: ArrayLike) -> NDArray:
    """Wrap angle(s) in radians to (-pi, pi]."""
    a = _reals(angle, "angle")
    w = np.mod(a + np.pi, 2 * np.pi) - np.pi
    return np.where(w == -np.pi, np.pi, w)


def wrap_deg(angle: ArrayLike) -> NDArray:
    """Wrap angle(s) in degrees to (-180, 180]."""
    a = _reals(angle, "angle")
    w = np.mod(a + 180.0, 360.0) - 180.0
    return np.where(w == -180.0, 180.0, w)


#: The most points :func:`fibonacci_sphere` spreads (a 0.06-degree lattice; 240 MB).
MAX_SPHERE_POINTS = 10_000_000


def fibonacci_sphere(n: int) -> NDArray:
    """``n`` nearly uniformly spread unit vectors ``(n, 3)`` (Fibonacci lattice); ``n`` an
    integer from 1 to :data:`MAX_SPHERE_POINTS` (GeometryError otherwise: 2.5 is not
    rounded, 10**9 points was a MemoryError)."""
    n = whole_number("n", n, hi=MAX_SPHERE_POINTS, error=GeometryError)
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5**0.5) * i
    rxy = np.sqrt(1.0 - z * z)
    return np.stack([rxy * np.cos(phi), rxy * np.sin(phi), z], axis=1)


def angle_between(u: ArrayLike, v: ArrayLike) -> NDArray:
    """Angle in radians, in [0, pi], between direction vectors ``(..., 3)`` (any length but
    zero: GeometryError).

    Each vector is scaled (:func:`norm_scale`) and made unit length, and the angle is
    ``arctan2(|a x b|, a . b)``: accurate at every angle (the arccos of the cosine returned 0.0
    for 1e-8 rad) and at every length (a norm of (1e200, 1e200, 0) overflowed to inf and gave
    NaN; one of (1e-200, 0, 0) underflowed to 0, 'a zero-length vector'). A vector that is not
    finite gives NaN."""
    a, b = _reals(u, "u"), _reals(v, "v")
    try:
        np.broadcast_shapes(a.shape, b.shape)
        ok = a.shape[-1:] == (3,) and b.shape[-1:] == (3,)
    except ValueError:
        ok = False
    if not ok:
        raise GeometryError(f"angle_between needs vectors (..., 3) of broadcastable shapes, got "
                            f"{a.shape} and {b.shape}")
    ua, ub = _unit_rows(a), _unit_rows(b)
    if ua is None or ub is None:
        raise GeometryError("angle between a zero-length vector and another is undefined")
    return np.arctan2(np.linalg.norm(np.cross(ua, ub), axis=-1), np.sum(ua * ub, axis=-1))


def _unit_rows(v: NDArray) -> NDArray | None:
    """Vectors ``(..., 3)`` scaled to unit length without overflow or underflow
    (:func:`norm_scale`); None when one of them has length zero."""
    s = v / norm_scale(v)
    n = np.linalg.norm(s, axis=-1, keepdims=True)
    if np.any(n == 0):
        return None
    return s / n


def as_points(points: ArrayLike, what: str = "points") -> NDArray:
    """``points`` as a float array ``(..., 3)``: [x, y, z] coordinates in metres (any batch
    shape, in the frame the caller documents), else a GeometryError naming ``what`` (numpy's
    ValueError or IndexError before: a scalar, text, a ragged list, 2 coordinates). Every
    coordinate must be a real number (:func:`hearsee.config.real_entries`; NaN and inf pass,
    the callers decide): numpy read ``"1.2"`` as 1.2 m and True as 1 m. The one batch check of
    :func:`cart_to_sph`, :func:`array_to_robot`, :func:`robot_to_array` and
    :class:`hearsee.audio.arrays.MicArray`'s TDOAs; one point alone: :func:`as_point`."""
    p = np.asarray(points, dtype=float) if real_entries(points) else None
    if p is None or p.ndim == 0 or p.shape[-1] != 3:
        got = "not numbers" if p is None else f"shape {p.shape}"
        raise GeometryError(f"{what}: expected points with 3 coordinates [x, y, z] in metres, "
                            f"shape (..., 3), got {got}")
    return p


def as_point(value: Any, what: str, error: type[Exception] = GeometryError) -> NDArray:
    """``value`` as a float array ``(3,)``: ONE finite ``[x, y, z]`` in metres (a point or an
    offset, in whatever frame the caller documents), else ``error`` (default GeometryError)
    naming ``what``.

    The one check behind hearsee's single-point arguments (the pivot and array offsets here,
    the simulated source and room of :mod:`hearsee.sim.audio`, the point of
    :meth:`hearsee.audio.arrays.MicArray.tdoa_jacobian`, the robot file's ``head`` and
    ``cameras.mount_m`` vectors, which pass ConfigError). Each coordinate must be a finite real
    number (:func:`hearsee.config.all_real`): numpy's float conversion read ``True`` as 1 m and
    ``"0.5"`` as 0.5 m, and raised a builtin OverflowError on an int beyond float's range; any
    other shape, ``(1, 3)`` included, is refused too. So is a point farther from the origin
    than float's range (1.8e308 m: its distance, ``math.hypot``, is inf), which no distance,
    truth or TDOA could hold; (1e300, 1e300, 0), 1.41e300 m away, is a point.

    >>> as_point((1, 2.5, 0), "source")
    array([1. , 2.5, 0. ])
    """
    items = object_entries(value)  # the coordinates as given, each checked below
    if items is None or items.shape != (3,):
        got = f"shape {items.shape}" if items is not None and items.ndim else repr(value)
        raise error(f"{what} must be a finite [x, y, z] in metres: expected shape 3, got {got}")
    if not all_real(items):
        raise error(f"{what} must be a finite [x, y, z] in metres (3 real numbers), got "
                    f"{value!r}")
    p = items.astype(float)
    if not math.isfinite(math.hypot(*p)):
        raise error(f"{what}: {p.tolist()} is farther from the origin than a float can hold "
                    "(its distance overflows); give a point within 1e308 m")
    return p


# ---------------------------------------------------------------------------------------------
# Pan-tilt head kinematics (thesis ch. 4, fig. 4.1)
# ---------------------------------------------------------------------------------------------
#
# Frames. The *robot* frame is REP 103 (x forward, y left, z up), fixed to the robot body. The
# *array* (head) frame is the frame the microphone positions of a MicArray are written in; at
# pose (0, 0) its axes are parallel to the robot's.
#
# Pan (alpha, ``pan_deg``) turns the head about the robot's +z axis: positive pan turns the gaze
# to the LEFT, exactly like azimuth (pan 90 deg looks along +y).
#
# Tilt (beta, ``tilt_deg``) then turns the head about the *panned* y axis. In REP 103 a positive
# rotation about +y takes +x toward -z (nose DOWN). hearsee defines tilt the other way round so
# that it reads like elevation: **positive tilt raises the gaze** (tilt 90 deg looks straight up).
# The head rotation is therefore ``R = Rz(pan) @ Ry(-tilt)`` and the gaze (array +x axis) points
# at azimuth = pan, elevation = tilt in the robot frame.
#
# Both axes pass through one point, the head *pivot* (``pivot_m``, robot frame). The array
# frame's origin sits at ``offset_m`` from the pivot, written in the head frame (it turns with the
# head); a real head carries its microphones some centimetres in front of / above the pan-tilt
# axes, which moves the array centre when the head turns (useful parallax for distance).
#
#     p_robot = pivot_m + R(pan, tilt) @ (offset_m + p_array)
#     p_array = R(pan, tilt)^T @ (p_robot - pivot_m) - offset_m


#: The array origin is at most this far (metres) from the head pivot: a head carries its
#: microphones centimetres, not metres, from its pan-tilt axes.
MAX_HEAD_OFFSET_M = 1.0


def check_head_offset(offset_m: Any, what: str = "offset_m",
                      error: type[Exception] = GeometryError) -> NDArray:
    """``offset_m`` (the array origin from the head pivot, head frame, metres) as a float array
    ``(3,)`` (:func:`as_point`), else ``error`` naming ``what``; one at most
    :data:`MAX_HEAD_OFFSET_M` from the pivot. The one rule of the robot file's head, a pose
    manifest's and ``hearsee simulate --poses --head-offset``: a 1e300 m offset overflowed the
    robot file's check into a RuntimeWarning and a manifest's localization into scipy's
    builtin ValueError."""
    return _point_within(offset_m, what, error, MAX_HEAD_OFFSET_M, "the pivot")


#: The head pivot is at most this far (metres) from the robot-frame origin: it is a point of
#: the robot (the robot file's default is 1.2 m up).
MAX_HEAD_PIVOT_M = 10.0


def check_head_pivot(pivot_m: Any, what: str = "pivot_m",
                     error: type[Exception] = GeometryError) -> NDArray:
    """``pivot_m`` (the pan-tilt pivot, robot frame, metres) as a float array ``(3,)``
    (:func:`as_point`), else ``error`` naming ``what``; one at most :data:`MAX_HEAD_PIVOT_M`
    from the robot-frame origin. The one rule of the robot file's head, a pose manifest's and
    :func:`hearsee.audio.active.pose_mic_positions` (the moving-head solver's): a pivot 1e300 m
    away put every microphone on the same float (centimetres are below its resolution), and
    ``hearsee localize3d`` reported a wrong direction with only its consistency warning (one
    1e308 m away ran for minutes)."""
    return _point_within(pivot_m, what, error, MAX_HEAD_PIVOT_M,
                         "the robot-frame origin (the head pivot is a point of the robot)")


#: A camera's optical centre is at most this far (metres) from the head pivot (the robot file's
#: ``cameras.mount_m``, head frame).
MAX_CAMERA_MOUNT_M = 2.0


def check_angle_limits(limits_deg: Any, where: str, bound: float,
                       error: type[Exception] = GeometryError) -> tuple[float, float]:
    """``limits_deg`` as ``(min, max)`` degrees with ``-bound <= min < max <= bound`` (two
    real numbers), else ``error`` naming ``where``: the one rule of a head's pan limits
    (bound 180) and tilt limits (bound 90; + = gaze up), for the robot file
    (:func:`hearsee.robot.hardware.tilt_limits_deg`) and the alignment loops of
    :mod:`hearsee.audio.active` alike."""
    try:
        lo, hi = limits_deg
    except (TypeError, ValueError):
        raise error(f"{where}: expected [min, max] in degrees, got {limits_deg!r}") from None
    if not (is_real(lo) and is_real(hi) and -bound <= lo < hi <= bound):
        raise error(f"{where}: need {-bound:g} <= min < max <= {bound:g}, got [{lo}, {hi}]")
    return float(lo), float(hi)


def check_camera_mount(mount_m: Any, what: str = "mount_m",
                       error: type[Exception] = GeometryError) -> NDArray:
    """``mount_m`` (the left camera's optical centre from the head pivot, head frame, metres)
    as a float array ``(3,)`` (:func:`as_point`), else ``error`` naming ``what``; one at most
    :data:`MAX_CAMERA_MOUNT_M` from the pivot. The rule of the robot file's
    ``cameras.mount_m``: its own ``np.linalg.norm`` test overflowed on [1e300, 0, 0] into a
    RuntimeWarning printed before the (right) error."""
    return _point_within(mount_m, what, error, MAX_CAMERA_MOUNT_M, "the pivot")


def _point_within(value: Any, what: str, error: type[Exception], limit_m: float,
                  origin: str) -> NDArray:
    """:func:`as_point` of ``value``, and ``error`` ("``what``: [x, y, z] is more than
    ``limit_m`` m from ``origin``") unless it lies within ``limit_m`` metres of the origin of
    its frame: the rule of :func:`check_head_offset`, :func:`check_head_pivot` and
    :func:`check_camera_mount`."""
    p = as_point(value, what, error)
    if not math.hypot(*p) <= limit_m:
        raise error(f"{what}: {p.tolist()} is more than {limit_m:g} m from {origin}")
    return p


#: An angle (degrees) that names a direction is at most this large in magnitude: 2.8 million
#: turns, more than any unwrapped run, and a float there still resolves 1.2e-7 deg. Beyond it
#: the wrap to (-180, 180] names no direction (at 1e17 deg neighbouring floats are 16 deg
#: apart). The rule of a head's pan (:class:`HeadPose`) and of a tracked azimuth
#: (:data:`hearsee.audio.tracking.MAX_AZIMUTH_DEG`).
MAX_ANGLE_DEG = 1e9


@dataclass(frozen=True)
class HeadPose:
    """Pose of a pan-tilt head in degrees: ``pan_deg`` (alpha, + = left, about robot +z) and
    ``tilt_deg`` (beta, + = gaze up, about the panned y axis). See the module notes above."""

    pan_deg: float = 0.0
    tilt_deg: float = 0.0

    def __post_init__(self) -> None:
        for name in ("pan_deg", "tilt_deg"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float | np.floating | np.integer):
                raise GeometryError(f"HeadPose.{name} must be a number, got {v!r}")
            if not is_real(v):  # (np.isfinite raised TypeError on an int beyond float range)
                raise GeometryError(f"HeadPose.{name} must be finite, got {v!r}")
            object.__setattr__(self, name, float(v))
        if abs(self.pan_deg) > MAX_ANGLE_DEG:  # (1e300 deg was taken, as its wrap)
            raise GeometryError(f"HeadPose.pan_deg must be within +-{MAX_ANGLE_DEG:g} degrees "
                                f"(beyond, its wrap names no direction), got {self.pan_deg:g}")
        if abs(self.tilt_deg) > 90.0:
            raise GeometryError(
                f"HeadPose.tilt_deg must be within [-90, 90] degrees, got {self.tilt_deg}"
            )

    @property
    def gaze(self) -> NDArray:
        """Unit vector of the head's +x axis (gaze) in the robot frame."""
        return unit_vector_deg(self.pan_deg, self.tilt_deg)

    def as_tuple(self) -> tuple[float, float]:
        return (self.pan_deg, self.tilt_deg)


def as_pose(pose: HeadPose | Sequence[float]) -> HeadPose:
    """A :class:`HeadPose` from a HeadPose or a ``(pan_deg, tilt_deg)`` pair."""
    if isinstance(pose, HeadPose):
        return pose
    try:
        pan, tilt = pose  # type: ignore[misc]
    except (TypeError, ValueError):
        raise GeometryError(f"a head pose is (pan_deg, tilt_deg), got {pose!r}") from None
    return HeadPose(pan, tilt)


def head_rotation(pan_deg: float, tilt_deg: float) -> Rotation:
    """Rotation taking array(head)-frame vectors to the robot frame for a pan-tilt pose.

    ``R = Rz(pan) @ Ry(-tilt)``: pan about robot +z (+ = left), then tilt about the panned y
    axis with **+tilt = gaze up** (the opposite of REP 103's right-hand sense about +y, so that
    tilt reads like elevation). The array's +x axis maps to ``unit_vector_deg(pan, tilt)``.

    >>> np.round(head_rotation(90.0, 0.0).apply([1.0, 0.0, 0.0]), 6)
    array([0., 1., 0.])
    >>> np.round(head_rotation(0.0, 90.0).apply([1.0, 0.0, 0.0]), 6)
    array([0., 0., 1.])
    """
    p = HeadPose(pan_deg, tilt_deg)
    return Rotation.from_euler("ZY", [p.pan_deg, -p.tilt_deg], degrees=True)


def array_to_robot(points: ArrayLike, pose: HeadPose | Sequence[float],
                   pivot_m: ArrayLike = (0.0, 0.0, 0.0),
                   offset_m: ArrayLike = (0.0, 0.0, 0.0)) -> NDArray:
    """Points ``(..., 3)`` in the array frame at ``pose`` -> robot frame (metres).

    ``pivot_m`` is the pan-tilt pivot in the robot frame; ``offset_m`` the array origin relative
    to the pivot in the head frame (see the notes above :class:`HeadPose`).
    """
    p = as_pose(pose)
    pts = as_points(points)
    R = head_rotation(p.pan_deg, p.tilt_deg).as_matrix()
    return as_point(pivot_m, "pivot_m") + (pts + as_point(offset_m, "offset_m")) @ R.T


def robot_to_array(points: ArrayLike, pose: HeadPose | Sequence[float],
                   pivot_m: ArrayLike = (0.0, 0.0, 0.0),
                   offset_m: ArrayLike = (0.0, 0.0, 0.0)) -> NDArray:
    """Points ``(..., 3)`` in the robot frame -> array frame at ``pose`` (inverse of
    :func:`array_to_robot`)."""
    p = as_pose(pose)
    pts = as_points(points)
    R = head_rotation(p.pan_deg, p.tilt_deg).as_matrix()
    return (pts - as_point(pivot_m, "pivot_m")) @ R - as_point(offset_m, "offset_m")


def mic_positions_at(array: Any, pose: HeadPose | Sequence[float],
                     pivot_m: ArrayLike = (0.0, 0.0, 0.0),
                     offset_m: ArrayLike = (0.0, 0.0, 0.0)) -> NDArray:
    """Microphone positions ``(n_mics, 3)`` in the robot frame with the head at ``pose``.

    ``array`` is a :class:`hearsee.audio.arrays.MicArray` (or an ``(n_mics, 3)`` array of
    positions in the array frame); ``pivot_m`` is the pan-tilt pivot in the robot frame and
    ``offset_m`` the array origin relative to the pivot in the head frame, metres.

    >>> np.round(mic_positions_at([[0.1, 0, 0]], (90.0, 0.0)), 6)
    array([[0. , 0.1, 0. ]])
    """
    pos = as_float_array(getattr(array, "positions", array), "microphone positions",
                         error=GeometryError)
    if pos.ndim != 2 or pos.shape[1] != 3:
        raise GeometryError(f"microphone positions must be N x 3, got shape {pos.shape}")
    return array_to_robot(pos, pose, pivot_m, offset_m)
