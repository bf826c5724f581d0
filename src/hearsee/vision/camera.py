"""Pinhole cameras with lens distortion, stereo(+thermal) rigs and their calibration files.

Conventions
-----------
* **Optical frame** (OpenCV): x right, y down, z forward (along the optical axis), metres.
  Pixels ``(u, v)``: u right (column), v down (row); the centre of the top-left pixel is
  ``(0, 0)``.
* **Intrinsics** ``K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]`` in pixels; distortion ``dist``
  in OpenCV order ``(k1, k2, p1, p2[, k3[, k4, k5, k6[, s1, s2, s3, s4[, tx, ty]]]])`` with
  4, 5, 8, 12 or 14 coefficients (empty = no distortion).
* **Extrinsics** ``(R, T)`` map points of one camera's optical frame into another's:
  ``X_right = R @ X_left + T`` (the convention of ``cv2.stereoCalibrate``). ``T`` is in metres.
  For a usual horizontal rig the right camera sits at ``+B`` along the left camera's x axis, so
  ``T = [-B, 0, 0]`` and disparities ``d = u_left - u_right`` are positive.
* **Body frame** (ROS REP 103): x forward, y left, z up. :data:`OPTICAL_FROM_BODY` rotates body
  vectors into the optical frame of a camera looking along body +x; :func:`camera_pose` places
  a camera on the robot (e.g. on the pan-tilt head).

Calibration file format (YAML, one format for cameras and rigs; metres, pixels)
------------------------------------------------------------------------------
A single camera::

    kind: camera            # optional
    name: left              # optional
    width: 640              # pixels
    height: 480
    K: [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]
    dist: [k1, k2, p1, p2, k3]    # OpenCV order; [] = none
    rms_px: 0.21            # optional: RMS reprojection error of the calibration

A stereo rig, optionally with a thermal camera::

    kind: stereo_rig
    left:  {width: .., height: .., K: .., dist: ..}
    right: {width: .., height: .., K: .., dist: ..}
    R: [[...], [...], [...]]   # right-from-left rotation: X_right = R X_left + T
    T: [tx, ty, tz]            # metres
    thermal:                   # optional
      camera: {width: .., height: .., K: .., dist: ..}
      R: [[...], [...], [...]] # thermal-from-left: X_thermal = R X_left + T
      T: [tx, ty, tz]          # metres
    rms_px: 0.3                # optional, stereo RMS reprojection error
    info: {...}                # optional free-form metadata (board, square size, image count)

:func:`load_camera` also reads one camera out of a rig file (``which="left"|"right"|"thermal"``).
OpenCV ``FileStorage`` files (``%YAML:1.0`` with ``!!opencv-matrix``) are read with
:func:`read_opencv_yaml`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import yaml
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from hearsee.config import (
    YamlDumper,
    as_float_array,
    check_keys,
    finite_number,
    input_file,
    is_real,
    load_yaml,
    output_file,
    real_entries,
    require,
    to_plain,
    whole_number,
    write_file,
)
from hearsee.errors import CalibrationError, ConfigError, GeometryError
from hearsee.geometry import MAX_ANGLE_DEG, as_point, norm_scale

__all__ = [
    "MAX_BASELINE_M",
    "MIN_BASELINE_M",
    "OPTICAL_FROM_BODY",
    "Camera",
    "Rectification",
    "StereoRig",
    "camera_pose",
    "check_rig",
    "check_size",
    "fold_radius",
    "head_camera_pose",
    "load_camera",
    "load_rig",
    "read_opencv_yaml",
    "rig_from_opencv",
    "save_camera",
    "save_rig",
    "transform_points",
]

#: Rotation taking REP-103 body vectors (x forward, y left, z up) to the optical frame of a
#: camera looking forward (x right, y down, z forward): ``p_optical = OPTICAL_FROM_BODY @ p_body``.
OPTICAL_FROM_BODY: NDArray = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
OPTICAL_FROM_BODY.setflags(write=False)

_DIST_LENGTHS = (0, 4, 5, 8, 12, 14)

#: A stereo baseline (metres) below this is refused. The same image files given for both
#: cameras calibrate to |T| ~ 5e-15 m; the narrowest real stereo pairs are about 10 mm apart
#: (phone dual cameras; depth cameras 18-120 mm; the robot scenarios allow 20 mm and up), so
#: 1 mm is a safe floor that still reads as "the two images come from one place".
MIN_BASELINE_M = 1e-3
#: A stereo baseline or a thermal camera's offset from the left camera (metres) above this is
#: refused: no robot's head is that wide, and a file written in millimetres (T: [-120, 0, 0])
#: gave depths 1000x too large -- "0 humans", without a word. Robot scenarios allow up to 1 m.
MAX_BASELINE_M = 5.0


#: The smallest focal length a camera may have, as a share of its image width (and height):
#: tan of the half field of view at most 1 / (2 * 0.05) = 10, 169 deg across as a pinhole.
#: Fisheye lenses of 180 deg and more calibrate to ~0.3 of the width; a focal length of
#: 1e-6 px (a matrix in metres, a typo) was accepted and every detection came out empty.
MIN_FOCAL_SHARE = 0.05

#: The most a stereo rig's two optical axes may diverge, degrees: convergent rigs toe in by a
#: few degrees; beyond this the two views barely overlap (R = 180 deg about y, cameras back to
#: back, rectified and gave depths).
MAX_AXES_ANGLE_DEG = 45.0


def _check_rotation(R: ArrayLike, what: str) -> NDArray:
    if not real_entries(R):  # (numpy read text as the numbers it spells, True as 1)
        raise CalibrationError(f"{what}: expected real numbers, got {R!r:.80}")
    R = np.array(R, dtype=float)  # (a copy: the rig must not share the caller's array)
    if R.shape == (3,) or R.shape == (3, 1) or R.shape == (1, 3):  # Rodrigues vector
        R = cv2.Rodrigues(R.reshape(3, 1))[0]
    if R.shape != (3, 3) or not np.all(np.isfinite(R)):
        raise CalibrationError(
            f"{what}: expected a finite 3x3 rotation matrix, got shape {R.shape}"
        )
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-5) or np.linalg.det(R) < 0:
        raise CalibrationError(f"{what}: not a rotation matrix (R R^T != I or det(R) < 0)")
    R.setflags(write=False)
    return R


def _check_translation(T: ArrayLike, what: str) -> NDArray:
    if not real_entries(T):
        raise CalibrationError(f"{what}: expected real numbers (metres), got {T!r:.80}")
    T = np.array(T, dtype=float)  # (a copy, as _check_rotation)
    if T.shape not in ((3,), (3, 1), (1, 3)) or not np.all(np.isfinite(T)):
        # (any shape of 3 numbers was flattened: a (1, 3, 1) T was taken)
        raise CalibrationError(f"{what}: expected 3 finite numbers (metres) of shape (3,), "
                               f"(3, 1) or (1, 3), got shape {T.shape}")
    T = T.reshape(3)
    T.setflags(write=False)
    return T


@dataclass(frozen=True, eq=False)
class Camera:
    """A pinhole camera with OpenCV lens distortion.

    Parameters
    ----------
    K : (3, 3) array
        Intrinsic matrix in pixels, ``[[fx, s, cx], [0, fy, cy], [0, 0, 1]]``; the skew ``s`` is
        usually 0 (OpenCV calibrations never estimate it) but is honoured by :meth:`project`,
        :meth:`normalized` and the thermal extrinsic calibration; stereo rectification and
        stereo calibration refuse it (:meth:`require_no_skew`: OpenCV would ignore it).
    dist : (k,) array
        Distortion coefficients in OpenCV order, k in {0, 4, 5, 8, 12, 14}; a (1, k) or
        (k, 1) array (OpenCV's shapes) is read as (k,), any other 2-D shape refused.
    width, height : int
        Image size in pixels.
    name : str
        Optional label ("left", "thermal", ...).

    Examples
    --------
    >>> cam = Camera.from_fov(60.0, 640, 480)
    >>> np.round(cam.project([[0.0, 0.0, 2.0]]), 3)
    array([[319.5, 239.5]])
    """

    K: NDArray
    dist: NDArray = field(default_factory=lambda: np.zeros(0))
    width: int = 640
    height: int = 480
    name: str = ""

    def __post_init__(self) -> None:
        for what, v in (("K", self.K), ("dist", self.dist)):
            # (numpy read text as the numbers it spells, True as 1, and dropped an imaginary
            # part)
            if v is not None and not real_entries(v):
                raise CalibrationError(f"camera {what}: expected real numbers, got {v!r}")
        # (copies: freezing them read-only must not freeze the caller's arrays)
        K = np.array(self.K, dtype=float)
        if K.shape != (3, 3) or not np.all(np.isfinite(K)):
            raise CalibrationError(f"camera K: expected a finite 3x3 matrix, got shape {K.shape}")
        if not np.allclose(K[2], [0.0, 0.0, 1.0]) or K[1, 0] != 0 or K[0, 0] <= 0 or K[1, 1] <= 0:
            raise CalibrationError(
                "camera K: expected [[fx, s, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0"
            )
        d = np.array(self.dist if self.dist is not None else [], dtype=float)
        if d.ndim > 2 or (d.ndim == 2 and 1 not in d.shape):
            # (flattened: a (2, 7) table was read as 14 coefficients, its second row as
            # thin-prism and tilt terms)
            raise CalibrationError(f"camera dist: expected one row or column of coefficients "
                                   f"((k,), (1, k) or (k, 1), as OpenCV's), got shape {d.shape}")
        d = d.reshape(-1)
        if d.size not in _DIST_LENGTHS or not np.all(np.isfinite(d)):
            raise CalibrationError(
                f"camera dist: expected 0, 4, 5, 8, 12 or 14 finite coefficients, got {d.size}"
            )
        if np.all(d == 0):
            d = np.zeros(0)
        w, h = check_size(self.width, self.height)
        if K[0, 0] < MIN_FOCAL_SHARE * w or K[1, 1] < MIN_FOCAL_SHARE * h:
            raise CalibrationError(
                f"camera K: focal lengths fx = {K[0, 0]:.4g}, fy = {K[1, 1]:.4g} px for a "
                f"{w}x{h} image, a field of view near 180 deg (at least {MIN_FOCAL_SHARE:g} x "
                "the image size expected; is K in pixels, and for this image size?)")
        if not (-w <= K[0, 2] <= 2 * w and -h <= K[1, 2] <= 2 * h):
            raise CalibrationError(
                f"camera K: principal point ({K[0, 2]:.4g}, {K[1, 2]:.4g}) px lies more than "
                f"one image size outside the {w}x{h} image (is the calibration for this image "
                "size?)")
        K.setflags(write=False)
        d.setflags(write=False)
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "dist", d)
        object.__setattr__(self, "width", w)
        object.__setattr__(self, "height", h)

    # -- construction ---------------------------------------------------------------------
    @classmethod
    def from_fov(cls, hfov_deg: float, width: int, height: int, *, vfov_deg: float | None = None,
                 name: str = "") -> Camera:
        """An ideal (distortion-free) camera with horizontal field of view ``hfov_deg`` degrees.

        Square pixels unless ``vfov_deg`` is given; principal point at the image centre
        ``((width - 1) / 2, (height - 1) / 2)``.
        """
        # (True was read as 1 deg; text and a text size raised builtin TypeErrors)
        if not (is_real(hfov_deg) and 0.0 < hfov_deg < 180.0):
            raise CalibrationError(f"hfov_deg must be in (0, 180), got {hfov_deg!r}")
        check_size(width, height)
        fx = (width / 2.0) / np.tan(np.radians(hfov_deg) / 2.0)
        if vfov_deg is None:
            fy = fx
        else:
            if not (is_real(vfov_deg) and 0.0 < vfov_deg < 180.0):
                raise CalibrationError(f"vfov_deg must be in (0, 180), got {vfov_deg!r}")
            fy = (height / 2.0) / np.tan(np.radians(vfov_deg) / 2.0)
        K = np.array([[fx, 0.0, (width - 1) / 2.0], [0.0, fy, (height - 1) / 2.0], [0, 0, 1.0]])
        return cls(K=K, dist=np.zeros(0), width=width, height=height, name=name)

    # -- properties -----------------------------------------------------------------------
    @property
    def fx(self) -> float:
        """Focal length along u, pixels."""
        return float(self.K[0, 0])

    @property
    def fy(self) -> float:
        """Focal length along v, pixels."""
        return float(self.K[1, 1])

    @property
    def cx(self) -> float:
        return float(self.K[0, 2])

    @property
    def cy(self) -> float:
        return float(self.K[1, 2])

    @property
    def size(self) -> tuple[int, int]:
        """``(width, height)`` in pixels (the order OpenCV functions take)."""
        return (self.width, self.height)

    @property
    def shape(self) -> tuple[int, int]:
        """``(height, width)``: the numpy shape of a single-channel image from this camera."""
        return (self.height, self.width)

    @property
    def hfov_deg(self) -> float:
        """Horizontal field of view of the pinhole (ignoring distortion), degrees."""
        return float(np.degrees(2 * np.arctan2(self.width / 2.0, self.fx)))

    @property
    def vfov_deg(self) -> float:
        """Vertical field of view of the pinhole (ignoring distortion), degrees."""
        return float(np.degrees(2 * np.arctan2(self.height / 2.0, self.fy)))

    @property
    def has_distortion(self) -> bool:
        return self.dist.size > 0

    def with_size(self, width: int, height: int) -> Camera:
        """The same camera resampled to ``width x height`` pixels (K scaled; dist unchanged)."""
        check_size(width, height)  # (text: a builtin TypeError)
        sx, sy = width / self.width, height / self.height
        S = np.diag([sx, sy, 1.0])
        K = S @ self.K
        # keep pixel-centre convention: u' + 0.5 = sx (u + 0.5)
        K[0, 2] = sx * (self.cx + 0.5) - 0.5
        K[1, 2] = sy * (self.cy + 0.5) - 0.5
        return Camera(K=K, dist=self.dist.copy(), width=width, height=height, name=self.name)

    # -- geometry -------------------------------------------------------------------------
    def project(self, points: ArrayLike) -> NDArray:
        """Project 3D points ``(N, 3)`` in this camera's optical frame (metres) to pixels.

        Returns ``(N, 2)`` float ``(u, v)`` including lens distortion; points with ``z <= 0``
        (behind the camera) give NaN, as do points so nearly sideways that the distortion
        polynomial overflows (``|x / z|`` beyond ~1e50: RuntimeWarnings and NaN before, now NaN
        alone). Pixels may lie outside the image: see :meth:`in_image`.
        """
        P = _as_points(points, "project")
        z = P[:, 2]
        front = z > 0
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(front, P[:, 0] / np.where(front, z, 1.0), np.nan)
            y = np.where(front, P[:, 1] / np.where(front, z, 1.0), np.nan)
        if self._tilted:  # tilted sensor: defer to OpenCV
            xd = np.full(len(P), np.nan)
            yd = np.full(len(P), np.nan)
            if np.any(front):
                xd[front], yd[front] = _distort_tilted(P[front], self.dist)
        else:
            with np.errstate(over="ignore", invalid="ignore"):
                xd, yd = _distort(x, y, self.dist)
            xd, yd = (np.where(np.isfinite(xd) & np.isfinite(yd), v, np.nan) for v in (xd, yd))
        return self._pixels(xd, yd)

    @property
    def _tilted(self) -> bool:
        """Whether the distortion has tilted-sensor terms (``tx``, ``ty``: OpenCV's own)."""
        return self.dist.size == 14 and bool(np.any(self.dist[12:] != 0))

    def _distorted(self, x: NDArray, y: NDArray) -> tuple[NDArray, NDArray]:
        """Distorted normalised coordinates of undistorted ones ``(x, y)``: the model of
        :meth:`project` without K."""
        if self._tilted:
            return _distort_tilted(np.stack([x, y, np.ones_like(x)], axis=1), self.dist)
        return _distort(x, y, self.dist)

    def _distort_with_jacobian(self, x: NDArray, y: NDArray
                               ) -> tuple[NDArray, NDArray, NDArray]:
        """Distorted normalised coordinates ``(xd, yd)`` of undistorted ones ``(x, y)`` (the
        model of :meth:`project`, tilt terms included) and the Jacobian ``(N, 2, 2)``
        ``d(xd, yd) / d(x, y)``: analytic, central differences for a tilted sensor."""
        if not self._tilted:
            return _distort_jacobian(x, y, self.dist)
        f = self._distorted
        xd, yd = f(x, y)
        h = 1e-6 * np.maximum(1.0, np.hypot(x, y))
        J = np.empty((len(x), 2, 2))
        for j, (dx, dy) in enumerate(((h, 0.0), (0.0, h))):
            xp, yp = f(x + dx, y + dy)
            xm, ym = f(x - dx, y - dy)
            J[:, 0, j] = (xp - xm) / (2 * h)
            J[:, 1, j] = (yp - ym) / (2 * h)
        return xd, yd, J

    def _pixels(self, xd: NDArray, yd: NDArray) -> NDArray:
        """Pixels ``(N, 2)`` of distorted normalised coordinates: ``K @ [xd, yd, 1]`` with K's
        skew ``K[0, 1]``."""
        K = self.K
        u = K[0, 0] * xd + K[0, 1] * yd + K[0, 2]
        v = K[1, 1] * yd + K[1, 2]
        return np.stack([u, v], axis=1)

    def normalized(self, uv: ArrayLike) -> NDArray:
        """Undistorted normalised image coordinates ``(N, 2)`` (x/z, y/z in the optical frame)
        of pixels ``(N, 2)``; the inverse of :meth:`project` (K's skew included).

        With lens distortion: OpenCV's ``undistortPointsIter``, then each result is projected
        back and, where it misses its pixel by more than 1e-9 px (OpenCV's fixed-point
        iteration stops early near :func:`fold_radius`) or lies at or beyond the fold, refined
        by Newton steps on the distortion model kept inside the fold. A pixel that still misses
        by more than 1e-6 px has no direction within the lens field (normalised radius below
        :func:`fold_radius`) that projects to it -- the radial model peaks below its distorted
        radius (k1 = -0.28 at f 520 px cannot reach the corners of 640x480), or it is too far
        out for the model's squares -- and gives NaN (OpenCV returned a point that reprojected
        up to 200 px away). Both tolerances grow with the pixel's distance from the principal
        point beyond 1000 px (1e-12 relative: float precision). A non-finite pixel (NaN or
        infinite coordinate) gives a NaN row, with or without distortion.
        """
        p = _as_pixels(uv)
        if len(p) == 0:
            return np.zeros((0, 2))
        if not self.has_distortion:
            with np.errstate(invalid="ignore"):  # (inf - inf, 0 * inf: rows set NaN below)
                y = (p[:, 1] - self.cy) / self.fy
                x = (p[:, 0] - self.cx - self.K[0, 1] * y) / self.fx
            xy = np.stack([x, y], axis=1)
            # (an infinite pixel gave (inf, 0): pixel_rays made it [nan, 0, 0] and warned)
            xy[~np.isfinite(p).all(axis=1)] = np.nan
            return xy
        K0, p0 = self._without_skew(p)
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-10)
        xy = cv2.undistortPointsIter(p0.reshape(-1, 1, 2), K0, self.dist, None, None, crit)
        return self._refine_normalized(xy.reshape(-1, 2).astype(float), p)

    def _refine_normalized(self, xy: NDArray, p: NDArray) -> NDArray:
        """Check (and Newton-refine) undistorted normalised coordinates ``xy`` ``(N, 2)`` of
        pixels ``p`` ``(N, 2)``; NaN rows where no direction inside the lens field reaches
        the pixel (see :meth:`normalized`)."""
        fx, fy, s, cx, cy = self.fx, self.fy, self.K[0, 1], self.cx, self.cy
        fold = fold_radius(self.dist)
        finite = np.isfinite(p).all(axis=1)
        q = np.where(finite[:, None], p, 0.0)  # (non-finite rows: NaN at the end, no warning)
        yt = (q[:, 1] - cy) / fy  # target distorted normalised coordinates
        xt = (q[:, 0] - cx - s * yt) / fx
        scale = np.maximum(1.0, np.maximum(np.abs(q[:, 0] - cx), np.abs(q[:, 1] - cy)) / 1e3)

        def residual_px(x: NDArray, y: NDArray, i: NDArray) -> tuple[NDArray, ...]:
            xd, yd, J = self._distort_with_jacobian(x, y)
            ex, ey = xt[i] - xd, yt[i] - yd
            return np.hypot(fx * ex + s * ey, fy * ey), ex, ey, J

        with np.errstate(all="ignore"):
            x, y = xy[:, 0].copy(), xy[:, 1].copy()
            res = np.full(len(p), np.inf)
            idx = np.flatnonzero(finite)
            xd, yd = self._distorted(x[idx], y[idx])
            res[idx] = np.hypot(fx * (xt[idx] - xd) + s * (yt[idx] - yd), fy * (yt[idx] - yd))
            inside = np.hypot(x, y) < fold
            act = np.flatnonzero(finite & ~((res <= 1e-9 * scale) & inside))
            if act.size:
                # restart outside the fold (or NaN) from the distorted point, pulled inside
                t = np.hypot(xt[act], yt[act])
                shrink = np.minimum(1.0, 0.9 * fold / np.where(t > 0, t, 1.0))
                redo = ~(inside[act] & np.isfinite(res[act]))
                x[act] = np.where(redo, xt[act] * shrink, x[act])
                y[act] = np.where(redo, yt[act] * shrink, y[act])
                self._newton(x, y, act, res, scale, fold, residual_px)
            ok = finite & (res <= 1e-6 * scale) & (np.hypot(x, y) < fold)
        out = np.stack([x, y], axis=1)
        out[~ok] = np.nan
        return out

    @staticmethod
    def _newton(x: NDArray, y: NDArray, act: NDArray, res: NDArray, scale: NDArray,
                fold: float, residual_px: Any, steps: int = 50) -> None:
        """Newton iterations on the pixels ``act`` (in place on ``x``, ``y``, ``res``): each
        step halved (up to 40 times) until it lowers the residual and stays inside ``fold``;
        a pixel stops at 1e-12 px (times ``scale``) or when no step helps."""
        res[act], ex, ey, J = residual_px(x[act], y[act], act)
        for _ in range(steps):
            keep = (res[act] > 1e-12 * scale[act]) & np.isfinite(res[act])
            act, ex, ey, J = act[keep], ex[keep], ey[keep], J[keep]
            if act.size == 0:
                return
            det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
            dx = (J[:, 1, 1] * ex - J[:, 0, 1] * ey) / det
            dy = (J[:, 0, 0] * ey - J[:, 1, 0] * ex) / det
            lam = np.ones(act.size)
            todo = np.isfinite(dx) & np.isfinite(dy)
            moved = np.zeros(act.size, bool)
            ex2, ey2, J2 = np.empty(act.size), np.empty(act.size), np.empty((act.size, 2, 2))
            for _ in range(40):
                if not todo.any():
                    break
                i = np.flatnonzero(todo)
                xn, yn = x[act[i]] + lam[i] * dx[i], y[act[i]] + lam[i] * dy[i]
                rn, exn, eyn, Jn = residual_px(xn, yn, act[i])
                good = (rn < res[act[i]]) & (np.hypot(xn, yn) < fold)
                g = i[good]
                x[act[g]], y[act[g]] = xn[good], yn[good]
                res[act[g]] = rn[good]
                ex2[g], ey2[g], J2[g] = exn[good], eyn[good], Jn[good]
                moved[g] = True
                todo[g] = False
                lam[i[~good]] *= 0.5
            act, ex, ey, J = act[moved], ex2[moved], ey2[moved], J2[moved]

    def require_no_skew(self, what: str) -> None:
        """CalibrationError when ``K[0, 1] != 0``: ``what`` (an OpenCV routine that ignores the
        skew) would silently give wrong results."""
        if self.K[0, 1] != 0:
            label = f"camera {self.name!r}" if self.name else "a camera"
            raise CalibrationError(
                f"{what} does not support a skewed intrinsic matrix ({label} has K[0][1] = "
                f"{self.K[0, 1]:g} px; OpenCV would ignore it); recalibrate without skew")

    def _without_skew(self, uv: NDArray) -> tuple[NDArray, NDArray]:
        """``(K0, uv0)``: K without its skew and the pixels ``(N, 2)`` that K0 gives for the
        same distorted normalised coordinates (``u0 = u - s (v - cy) / fy``, ``v0 = v``).

        OpenCV's point functions ignore ``K[0, 1]``; this removes the skew exactly while keeping
        the units of pixels (undistortPointsIter's stopping threshold is in pixels). With no
        skew, ``(self.K, uv)`` unchanged.
        """
        s = self.K[0, 1]
        if s == 0:
            return self.K, uv
        K0 = self.K.copy()
        K0[0, 1] = 0.0
        uv0 = uv.copy()
        uv0[:, 0] -= s * (uv[:, 1] - self.cy) / self.fy
        return K0, uv0

    def pixel_rays(self, uv: ArrayLike, *, unreachable: str = "raise") -> NDArray:
        """Unit viewing rays ``(N, 3)`` in the optical frame through pixels ``uv`` ``(N, 2)``
        (lens distortion removed); a NaN or infinite pixel gives no ray (NaN entries).

        Every finite pixel gives a unit ray that :meth:`project` maps back onto it (to 1e-6 px)
        and that lies in the lens field (:meth:`in_lens_field`): the length is taken without
        overflow (:func:`hearsee.geometry.norm_scale`; a pixel at u = 1e300 gave the ray
        [0, 0, 0] and an overflow warning, now the pinhole's ray almost perpendicular to the
        optical axis). A finite pixel no direction of the lens field projects to (see
        :meth:`normalized`: the distortion model folds back before reaching it, e.g. the
        corners of a 640x480 image with k1 = -0.28 at f 520 px, or its squares overflow, from
        about 1e155 px) is a GeometryError with ``unreachable="raise"`` (OpenCV's ray for
        pixel (0, 0) there reprojected 21.9 px away), a NaN ray with ``unreachable="nan"``:
        the choice of callers that map whole images (rendering), where such pixels see
        nothing."""
        if unreachable not in ("raise", "nan"):
            raise GeometryError(f"pixel_rays: unreachable must be 'raise' or 'nan', got "
                                f"{unreachable!r:.40}")
        p = _as_pixels(uv)
        xy = self.normalized(p)
        lost = np.isfinite(p).all(axis=1) & ~np.isfinite(xy).all(axis=1)
        if np.any(lost) and unreachable == "raise":
            u, v = p[np.argmax(lost)]
            where = (f"pixel ({u:.6g}, {v:.6g}) of the {self.width}x{self.height} image is "
                     "beyond the reach of the lens model: no direction inside its field "
                     f"(normalised radius < fold_radius = {fold_radius(self.dist):.4g}) "
                     "projects there (the distortion folds back before it)"
                     if self.in_image(p[np.argmax(lost)])[0] else
                     f"pixel ({u:.6g}, {v:.6g}) lies too far outside the "
                     f"{self.width}x{self.height} image for the camera model to give its ray")
            raise GeometryError(where)
        rays = np.concatenate([xy, np.ones((len(xy), 1))], axis=1)
        rays = rays / norm_scale(rays)
        return rays / np.linalg.norm(rays, axis=1, keepdims=True)

    def in_lens_field(self, points: ArrayLike) -> NDArray:
        """Boolean mask ``(N,)`` of points ``(N, 3)`` (this camera's optical frame, metres) in
        front of the camera whose direction the lens model maps to pixels one to one: normalised
        radius below :func:`fold_radius` of the distortion. Beyond it the radial polynomial
        folds back and :meth:`project` (like OpenCV's projectPoints) can put a point far
        outside the field of view inside the image: a point 60 deg off the axis of a 60-deg
        lens with k1 = -0.35 landed at u = 67 of 160. Use it with :meth:`in_image` to ask
        whether the camera sees a point."""
        P = _as_points(points, "in_lens_field")
        z = P[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.hypot(P[:, 0], P[:, 1]) / z
            return (z > 0) & (r < fold_radius(self.dist))

    def in_image(self, uv: ArrayLike, margin: float = 0.0) -> NDArray:
        """Boolean mask ``(N,)``: pixel lies inside the image (shrunk by ``margin`` pixels).
        ``uv`` is one pixel ``(2,)`` or ``(N, 2)`` (an ``(N, 3)`` array was silently re-read as
        pairs of numbers: GeometryError, as :meth:`normalized`); ``margin`` a finite number of
        pixels (a NaN one made every pixel "outside")."""
        p = _as_pixels(uv)
        finite_number("margin (pixels)", margin, error=GeometryError)  # (kept as given)
        with np.errstate(invalid="ignore"):
            return ((p[:, 0] >= -0.5 + margin) & (p[:, 0] <= self.width - 0.5 - margin)
                    & (p[:, 1] >= -0.5 + margin) & (p[:, 1] <= self.height - 0.5 - margin))

    # -- io ---------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """The YAML mapping of this camera (see module docstring)."""
        d: dict[str, Any] = {}
        if self.name:
            d["name"] = self.name
        d.update(width=self.width, height=self.height, K=self.K.tolist(),
                 dist=self.dist.tolist())
        return d

    @classmethod
    def from_dict(cls, data: Any, where: str = "camera") -> Camera:
        """Build a camera from a YAML mapping; ConfigError names the bad field."""
        if not isinstance(data, dict):
            raise ConfigError(f"{where}: expected a mapping with width, height, K, dist")
        check_keys(data, ["kind", "name", "width", "height", "K", "dist", "rms_px", "info"], where)
        width = require(data, "width", where)
        height = require(data, "height", where)
        for key, val in (("width", width), ("height", height)):
            if isinstance(val, bool) or not isinstance(val, int) or val <= 0:
                raise ConfigError(f"{where}: {key} must be a positive integer, got {val!r}")
        K = as_float_array(require(data, "K", where), f"{where}: K", (3, 3))
        dist = as_float_array(data.get("dist", []) or [], f"{where}: dist")  # (shape: Camera)
        if dist.size not in _DIST_LENGTHS:
            raise ConfigError(
                f"{where}: dist must have 0, 4, 5, 8, 12 or 14 coefficients, got {dist.size}"
            )
        name = data.get("name")
        if isinstance(name, list | dict):  # (["a"] was named "['a']")
            raise ConfigError(f"{where}: name must be text, got {name!r:.40}")
        try:
            # (an empty "name:" is YAML's null: the camera was named "None")
            return cls(K=K, dist=dist, width=width, height=height,
                       name="" if name is None else str(name))
        except CalibrationError as exc:
            raise ConfigError(f"{where}: {exc}") from None


def check_size(width: Any, height: Any, what: str = "camera size") -> tuple[int, int]:
    """``(width, height)`` in pixels as ints when both are whole numbers > 0 (640.0 too; not a
    bool or text), else a CalibrationError naming ``what``: the one image-size rule of
    :class:`Camera`, :meth:`Camera.from_fov`, :meth:`Camera.with_size` and
    :func:`rig_from_opencv` (NaN or None raised int()'s builtin ValueError / TypeError)."""
    whole = all(is_real(v) and not isinstance(v, bool) and v == int(v) and v > 0
                for v in (width, height))
    if not whole:
        raise CalibrationError(
            f"{what}: width and height must be positive integers, got {width!r}x{height!r}")
    return int(width), int(height)


def _as_points(points: ArrayLike, what: str) -> NDArray:
    """3D points as a float array ``(N, 3)`` (one point ``(3,)`` becomes ``(1, 3)``), else a
    GeometryError naming ``what``: numbers only (numpy read text as the numbers it spells, True
    as 1), three coordinates each. The point check of :meth:`Camera.project` and
    :meth:`Camera.in_lens_field`."""
    return _as_rows(points, 3, what, "points as numbers (metres)", "points of shape")


def _as_pixels(uv: ArrayLike) -> NDArray:
    """Pixels as a float array ``(N, 2)`` (one pixel ``(2,)`` becomes ``(1, 2)``), else a
    GeometryError: numbers only (:func:`hearsee.config.real_entries`; numpy read ("320",
    "240") as a pixel and True as 1), two coordinates each. The pixel check of
    :meth:`Camera.normalized`, :meth:`Camera.pixel_rays` and :meth:`Camera.in_image`."""
    return _as_rows(uv, 2, "pixel coordinates", "numbers", "shape")


def _as_rows(value: ArrayLike, width: int, what: str, numbers: str, shape: str) -> NDArray:
    """``value`` as a float array ``(N, width)`` (one row becomes ``(1, width)``), else a
    GeometryError ``"{what}: expected {numbers}, got ..."`` or ``"{what}: expected {shape}
    (N, width), got ..."``: the one check of :func:`_as_points` and :func:`_as_pixels`."""
    if not real_entries(value):
        raise GeometryError(f"{what}: expected {numbers}, got {value!r:.80}")
    p = np.asarray(value, dtype=float)
    if p.ndim == 1:
        p = p[None, :]
    if p.ndim != 2 or p.shape[1] != width:
        raise GeometryError(f"{what}: expected {shape} (N, {width}), got {p.shape}")
    return p


#: :func:`fold_radius` searches normalised radii up to at most this (tan of 89.94 deg)
MAX_FOLD_RADIUS = 1000.0


def fold_radius(dist: ArrayLike, r_max: float = MAX_FOLD_RADIUS) -> float:
    """The normalised image radius (``sqrt(x^2 + y^2) / z``) up to which OpenCV's radial
    distortion ``r (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)`` keeps
    increasing: beyond it the model folds back and two directions share a pixel. ``inf`` when it
    increases up to ``r_max`` (default :data:`MAX_FOLD_RADIUS`, 89.94 deg off the axis; until
    2026-12-08 it was 5, 79 deg, and a mild lens, k1 = -0.01, that folds at 5.77 had no fold:
    a point 84.3 deg off its axis was "in the lens field" and landed on the principal point).
    Tangential and thin-prism terms are left out (they are small). Computed on a 0.001 grid up
    to 5 and on steps of 0.02 % beyond, cached per coefficient set.

    ``dist`` must hold 0, 4, 5, 8, 12 or 14 finite numbers (OpenCV order, a row or a column)
    and ``r_max`` be a finite number > 0, else a CalibrationError (text was a builtin
    ValueError, a NaN coefficient gave 0.0: every direction "outside the lens field")."""
    if not real_entries(dist):
        raise CalibrationError(f"fold_radius: dist must hold real numbers, got {dist!r:.80}")
    d = np.asarray(dist, dtype=float)
    if (d.ndim > 2 or (d.ndim == 2 and 1 not in d.shape) or d.size not in _DIST_LENGTHS
            or not np.all(np.isfinite(d))):
        raise CalibrationError(f"fold_radius: dist must be 0, 4, 5, 8, 12 or 14 finite "
                               f"coefficients, got {d.size} of shape {d.shape}")
    # (the search grid is r_max / 1e-3 points: 1e300 was numpy's "maximum allowed size
    # exceeded", 1e6 eight gigabytes; 1000 is 89.94 deg off the axis)
    r_max = finite_number("fold_radius: r_max", r_max, 0.0, MAX_FOLD_RADIUS, lo_open=True,
                          error=CalibrationError)
    c = np.zeros(8)
    d = d.ravel()[:8]
    c[: d.size] = d
    return _fold_radius(tuple(float(v) for v in c), float(r_max))


@lru_cache(maxsize=64)
def _fold_radius(c: tuple[float, ...], r_max: float) -> float:
    k1, k2, _, _, k3, k4, k5, k6 = c
    if not any((k1, k2, k3, k4, k5, k6)):
        return float("inf")
    r = np.arange(0.0, min(r_max, 5.0) + 5e-4, 1e-3)
    if r_max > 5.0:  # (a 0.001 grid to 1000 was a million points: 0.2-0.5 s per lens)
        n = int(np.ceil(np.log(r_max / 5.0) / np.log1p(2e-4))) + 1
        r = np.concatenate([r[r < 5.0], np.geomspace(5.0, r_max, n)])
    r2 = r * r
    with np.errstate(all="ignore"):
        rd = r * (1 + k1 * r2 + k2 * r2**2 + k3 * r2**3) / (1 + k4 * r2 + k5 * r2**2 + k6 * r2**3)
        bad = ~(np.diff(rd) > 0) | ~np.isfinite(rd[1:])
    return float(r[int(np.argmax(bad))]) if bad.any() else float("inf")


def _distort_tilted(P: NDArray, d: NDArray) -> tuple[NDArray, NDArray]:
    """OpenCV's distortion with tilt terms of points ``(N, 3)`` (z > 0): distorted normalised
    ``(xd, yd)`` (``cv2.projectPoints`` with an identity K: OpenCV ignores K's skew, so K is
    applied by the caller)."""
    if len(P) == 0:
        return np.zeros(0), np.zeros(0)
    xyd, _ = cv2.projectPoints(np.asarray(P, float).reshape(-1, 1, 3), np.zeros(3), np.zeros(3),
                               np.eye(3), d)
    return xyd.reshape(-1, 2).T


def _distort_jacobian(x: NDArray, y: NDArray, d: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """:func:`_distort` and its Jacobian ``(N, 2, 2)`` ``d(xd, yd) / d(x, y)`` (normalised
    coordinates; without the tilt terms)."""
    c = np.zeros(12)
    c[: min(d.size, 12)] = d[:12]
    k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4 = c
    r2 = x * x + y * y
    r4 = r2 * r2
    a = 1 + k1 * r2 + k2 * r4 + k3 * r4 * r2
    b = 1 + k4 * r2 + k5 * r4 + k6 * r4 * r2
    radial = a / b
    da = k1 + 2 * k2 * r2 + 3 * k3 * r4
    db = k4 + 2 * k5 * r2 + 3 * k6 * r4
    dradial = (da * b - a * db) / (b * b)  # d radial / d r2
    xd, yd = _distort(x, y, d)
    J = np.empty((len(x), 2, 2))
    J[:, 0, 0] = radial + 2 * x * x * dradial + 2 * p1 * y + 6 * p2 * x + 2 * x * (s1 + 2 * s2 * r2)
    J[:, 0, 1] = 2 * x * y * dradial + 2 * p1 * x + 2 * p2 * y + 2 * y * (s1 + 2 * s2 * r2)
    J[:, 1, 0] = 2 * x * y * dradial + 2 * p1 * x + 2 * p2 * y + 2 * x * (s3 + 2 * s4 * r2)
    J[:, 1, 1] = radial + 2 * y * y * dradial + 6 * p1 * y + 2 * p2 * x + 2 * y * (s3 + 2 * s4 * r2)
    return xd, yd, J


def _distort(x: NDArray, y: NDArray, d: NDArray) -> tuple[NDArray, NDArray]:
    """OpenCV distortion model on normalised coordinates (without the tilt terms)."""
    if d.size == 0:
        return x, y
    c = np.zeros(12)
    c[: min(d.size, 12)] = d[:12]
    k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4 = c
    r2 = x * x + y * y
    r4 = r2 * r2
    r6 = r4 * r2
    radial = (1 + k1 * r2 + k2 * r4 + k3 * r6) / (1 + k4 * r2 + k5 * r4 + k6 * r6)
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) + s1 * r2 + s2 * r4
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y + s3 * r2 + s4 * r4
    return xd, yd


@dataclass(frozen=True, eq=False)
class Rectification:
    """Rectification of a stereo rig (``cv2.stereoRectify``) for images of ``size`` (w, h).

    ``R1``/``R2`` rotate the left/right optical frames into the common rectified frame (that of
    the rectified left camera), ``P1``/``P2`` are the 3x4 rectified projections and ``Q`` the
    4x4 disparity-to-depth matrix: ``[X Y Z W]^T = Q [u v d 1]^T`` in the rectified left frame
    (metres, since T is in metres).
    """

    R1: NDArray
    R2: NDArray
    P1: NDArray
    P2: NDArray
    Q: NDArray
    size: tuple[int, int]
    roi_left: tuple[int, int, int, int]
    roi_right: tuple[int, int, int, int]

    @property
    def focal_px(self) -> float:
        """Focal length of the rectified cameras, pixels."""
        return float(self.P1[0, 0])

    @property
    def baseline_m(self) -> float:
        """Signed rectified baseline, metres: positive when the right camera is to the right
        (then disparities ``u_left - u_right`` are positive)."""
        return float(-self.P2[0, 3] / self.P2[0, 0])

    @property
    def cx(self) -> float:
        return float(self.P1[0, 2])

    @property
    def cy(self) -> float:
        return float(self.P1[1, 2])

    @property
    def camera(self) -> Camera:
        """The ideal (distortion-free) rectified left camera."""
        return Camera(K=self.P1[:, :3].copy(), dist=np.zeros(0), width=self.size[0],
                      height=self.size[1], name="rectified")


@dataclass(frozen=True, eq=False)
class StereoRig:
    """Two cameras (and optionally a thermal camera) with their extrinsics.

    Parameters
    ----------
    left, right : Camera
    R, T : (3, 3), (3,)
        Right-from-left: ``X_right = R @ X_left + T`` (metres); ``|T|`` must be at least
        :data:`MIN_BASELINE_M` (1 mm) and at most :data:`MAX_BASELINE_M` (5 m; as ``|T_thermal|``).
    thermal : Camera, optional
    R_thermal, T_thermal : (3, 3), (3,), optional
        Thermal-from-left: ``X_thermal = R_thermal @ X_left + T_thermal`` (metres).
    rms_px : float, optional
        RMS reprojection error of the stereo calibration (pixels), when known: a finite
        number >= 0 (else a CalibrationError, as :meth:`from_dict`'s ConfigError).
    info : dict
        Free-form metadata saved with the rig; ``camera_height_m`` (metres above the floor
        of the left camera), when present, a finite number > 0, and ``camera_pitch_deg``
        (its pitch above the horizontal, + = looking up) within +-80 degrees (else a
        CalibrationError).
    """

    left: Camera
    right: Camera
    R: NDArray
    T: NDArray
    thermal: Camera | None = None
    R_thermal: NDArray | None = None
    T_thermal: NDArray | None = None
    rms_px: float | None = None
    info: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.left, Camera) or not isinstance(self.right, Camera):
            raise CalibrationError("StereoRig: left and right must be Camera instances")
        R = _check_rotation(self.R, "rig R (right-from-left)")
        T = _check_translation(self.T, "rig T (right-from-left)")
        # the right camera's optical axis in the left frame is R^T z: stereo needs both to look
        # the same way (a rig of cameras 180 deg apart rectified and gave depths)
        axes_deg = float(np.degrees(np.arccos(np.clip(R[2, 2], -1.0, 1.0))))
        if axes_deg > MAX_AXES_ANGLE_DEG:
            raise CalibrationError(
                f"rig R: the cameras' optical axes are {axes_deg:.0f} deg apart (at most "
                f"{MAX_AXES_ANGLE_DEG:g}): they do not look at the same scene")
        if not np.linalg.norm(T) >= MIN_BASELINE_M:
            raise CalibrationError(
                f"rig T: the baseline is {np.linalg.norm(T):.3g} m, below "
                f"{MIN_BASELINE_M * 1000:g} mm: both cameras at one point (left and right images "
                "are the same or taken from the same place?)"
            )
        if np.linalg.norm(T) > MAX_BASELINE_M:
            raise CalibrationError(
                f"rig T: the baseline is {np.linalg.norm(T):.4g} m, above {MAX_BASELINE_M:g} m "
                "(is the translation in millimetres? hearsee's rig files are in metres)")
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "T", T)
        # (the rules of from_dict: a NaN or negative rms_px and a NaN camera height were saved
        # into files load_rig refused; rms_px "abc" was a builtin ValueError in save_rig, "0.3"
        # read as a number; info ["ab"] was saved as {"a": "b"})
        if self.rms_px is not None:
            if not (is_real(self.rms_px) and self.rms_px >= 0):
                raise CalibrationError(
                    f"rig rms_px must be None or a finite number of pixels >= 0 (the stereo "
                    f"RMS reprojection error), got {self.rms_px!r:.40}")
            object.__setattr__(self, "rms_px", float(self.rms_px))
        if not isinstance(self.info, dict):
            raise CalibrationError(f"rig info must be a dict (free-form metadata), got "
                                   f"{type(self.info).__name__}")
        try:
            _info_camera_height(self.info, "rig info")
            _info_camera_pitch(self.info, "rig info")
        except ConfigError as exc:
            raise CalibrationError(str(exc)) from None
        if self.thermal is not None:
            if not isinstance(self.thermal, Camera):
                raise CalibrationError("StereoRig: thermal must be a Camera")
            if self.R_thermal is None or self.T_thermal is None:
                raise CalibrationError(
                    "StereoRig: a thermal camera needs R_thermal and T_thermal (thermal-from-left)"
                )
            object.__setattr__(self, "R_thermal",
                               _check_rotation(self.R_thermal, "rig R_thermal (thermal-from-left)"))
            Tt = _check_translation(self.T_thermal, "rig T_thermal")
            if np.linalg.norm(Tt) > MAX_BASELINE_M:
                raise CalibrationError(
                    f"rig T_thermal: the thermal camera is {np.linalg.norm(Tt):.4g} m from the "
                    f"left camera, above {MAX_BASELINE_M:g} m (is the translation in "
                    "millimetres? hearsee's rig files are in metres)")
            object.__setattr__(self, "T_thermal", Tt)

    # -- construction ---------------------------------------------------------------------
    @classmethod
    def ideal(cls, camera: Camera, baseline_m: float, *, thermal: Camera | None = None,
              thermal_offset_m: ArrayLike = (0.0, 0.0, 0.0),
              thermal_rotation: ArrayLike | None = None) -> StereoRig:
        """A rectified rig of two identical cameras ``baseline_m`` metres apart (right camera at
        ``+baseline_m`` along the left camera's x axis); optional thermal camera whose optical
        centre is at ``thermal_offset_m`` in the left optical frame (rotation thermal-from-left
        ``thermal_rotation``, default identity)."""
        if not (is_real(baseline_m) and baseline_m > 0):  # (True was 1 m, text a TypeError)
            raise CalibrationError(f"baseline_m must be a finite number > 0 (metres), got "
                                   f"{baseline_m!r}")
        right = Camera(K=camera.K.copy(), dist=camera.dist.copy(), width=camera.width,
                       height=camera.height, name="right")
        left = Camera(K=camera.K.copy(), dist=camera.dist.copy(), width=camera.width,
                      height=camera.height, name="left")
        kw: dict[str, Any] = {}
        if thermal is not None:
            Rt = (np.eye(3) if thermal_rotation is None
                  else _check_rotation(thermal_rotation, "thermal_rotation"))
            c = as_point(thermal_offset_m, "thermal_offset_m", CalibrationError)
            kw = dict(thermal=thermal, R_thermal=Rt, T_thermal=-Rt @ c)
        return cls(left=left, right=right, R=np.eye(3), T=np.array([-baseline_m, 0.0, 0.0]),
                   **kw)

    # -- geometry -------------------------------------------------------------------------
    @property
    def baseline_m(self) -> float:
        """Distance between the two optical centres, metres (``|T|``)."""
        return float(np.linalg.norm(self.T))

    @property
    def camera_height_m(self) -> float | None:
        """Height of the left camera above the floor, metres, from ``info: {camera_height_m}``
        (None when absent). ConfigError when it is not a finite number > 0: a NaN or negative
        height silently removed every person from the detections."""
        return _info_camera_height(self.info, "rig info")

    @property
    def camera_pitch_deg(self) -> float | None:
        """Pitch of the (rectified) left camera's optical axis above the horizontal, degrees
        (+ = looking up, no roll), from ``info: {camera_pitch_deg}`` (None when absent): the
        floor's prior with ``camera_height_m``. ConfigError when it is not a finite number
        within +-80 degrees."""
        return _info_camera_pitch(self.info, "rig info")

    @property
    def right_center_m(self) -> NDArray:
        """Optical centre of the right camera in the left optical frame, metres."""
        return -self.R.T @ self.T

    @property
    def thermal_center_m(self) -> NDArray | None:
        """Optical centre of the thermal camera in the left optical frame, metres."""
        if self.thermal is None:
            return None
        return -self.R_thermal.T @ self.T_thermal

    @property
    def is_rectified(self) -> bool:
        """True when images need no rectification: no distortion, identical K and size,
        square pixels (``fx == fy`` to 1e-9, as OpenCV's rectified cameras have), R = I and T
        along x (so disparity is purely horizontal).

        A pair of ideal cameras with ``fx != fy`` (``Camera.from_fov(..., vfov_deg=...)``) is
        not: its rectification (``cv2.stereoRectify``) resamples to square pixels, the form
        :attr:`Rectification.focal_px` and ``Q`` assume (kept as is, Y = (v - cy) B / d came
        out fx / fy times too large: -0.476 m for a true -0.40 m)."""
        fx, fy = self.left.K[0, 0], self.left.K[1, 1]
        return bool(
            not self.left.has_distortion and not self.right.has_distortion
            and np.allclose(self.left.K, self.right.K) and self.left.size == self.right.size
            and abs(fx - fy) <= 1e-9 * fx
            and np.allclose(self.R, np.eye(3), atol=1e-9)
            and abs(self.T[1]) < 1e-9 * self.baseline_m and abs(self.T[2]) < 1e-9 * self.baseline_m
        )

    @cached_property
    def rectification(self) -> Rectification:
        """Rectification at full image size with ``alpha = 0`` (only valid pixels kept)."""
        return self.rectify(alpha=0.0)

    def rectify(self, alpha: float = 0.0, size: tuple[int, int] | None = None) -> Rectification:
        """``cv2.stereoRectify`` (CALIB_ZERO_DISPARITY) of this rig.

        ``alpha`` in [0, 1]: 0 keeps only valid pixels, 1 keeps all source pixels. ``size`` is
        the output (w, h), default the left image size. For an already rectified rig
        (:attr:`is_rectified`: square pixels among others) the result is the identity with the
        left K; ``Q`` maps ``[u v d 1]`` (pixels) to the rectified left frame (metres). A NaN
        or out-of-range ``alpha`` and a size that is not two whole numbers > 0 are a
        ConfigError (they reached OpenCV unchecked: an alpha of NaN or 5 and a size of (0, 0)
        gave a rectification without a word); a rig whose cameras are not side by side
        (``|T_x|`` not T's largest component) a CalibrationError.
        """
        finite_number("alpha", alpha, 0.0, 1.0)
        if size is not None:
            try:
                w, h = size
            except (TypeError, ValueError):
                w = h = None
            for v in (w, h):
                whole_number("rectified size (w, h)", v)
        if self.left.size != self.right.size:
            raise CalibrationError(
                f"left and right images differ in size ({self.left.size} vs {self.right.size}); "
                "rectification needs equal sizes"
            )
        for cam in (self.left, self.right):  # (the rectification maps would drop it too)
            cam.require_no_skew("stereo rectification")
        if abs(self.T[0]) < max(abs(self.T[1]), abs(self.T[2])):
            # (stereoRectify then made a vertical or forward pair: the error named the LEFT
            # camera's side, T_x > 0, or a negative focal length, neither the cause)
            raise CalibrationError(
                f"rig T = {np.round(self.T, 4).tolist()} m: the cameras are not side by side "
                "(the baseline is mostly vertical or along the optical axis); hearsee's stereo "
                "needs |T_x| to be T's largest component")
        out_size = tuple(size) if size is not None else self.left.size
        if self.is_rectified and out_size == self.left.size:
            K = self.left.K
            P1 = np.hstack([K, np.zeros((3, 1))])
            P2 = P1.copy()
            P2[0, 3] = self.T[0] * K[0, 0]
            f, B = K[0, 0], -self.T[0]
            a = f / K[1, 1]  # 1 (to 1e-9: is_rectified): Y = (v - cy) Z / fy exactly
            Q = np.array([[1, 0, 0, -K[0, 2]], [0, a, 0, -K[1, 2] * a], [0, 0, 0, f],
                          [0, 0, 1.0 / B, 0]], dtype=float)
            roi = (0, 0, self.left.width, self.left.height)
            return Rectification(np.eye(3), np.eye(3), P1, P2, Q, self.left.size, roi, roi)
        R1, R2, P1, P2, Q, roi1, roi2 = cv2.stereoRectify(
            self.left.K, self.left.dist, self.right.K, self.right.dist, self.left.size,
            self.R, self.T.reshape(3, 1), flags=cv2.CALIB_ZERO_DISPARITY, alpha=alpha,
            newImageSize=out_size,
        )
        return Rectification(R1, R2, P1, P2, Q, (int(out_size[0]), int(out_size[1])),
                             tuple(int(v) for v in roi1), tuple(int(v) for v in roi2))

    @property
    def focal_px(self) -> float:
        """Focal length of the rectified pair, pixels (used in Z = f B / d)."""
        return self.rectification.focal_px

    @property
    def Q(self) -> NDArray:
        """4x4 disparity-to-depth matrix of the default rectification (:class:`Rectification`)."""
        return self.rectification.Q

    def left_to_right(self, points: ArrayLike) -> NDArray:
        """Points ``(N, 3)`` from the left optical frame to the right one (metres)."""
        return transform_points(self.R, self.T, points)

    def left_to_thermal(self, points: ArrayLike) -> NDArray:
        """Points ``(N, 3)`` from the left optical frame to the thermal camera's (metres)."""
        if self.thermal is None:
            raise CalibrationError("this rig has no thermal camera (add a 'thermal:' block)")
        return transform_points(self.R_thermal, self.T_thermal, points)

    def project_thermal(self, points: ArrayLike) -> NDArray:
        """Pixels ``(N, 2)`` in the thermal image of points ``(N, 3)`` in the left frame."""
        return self.thermal_camera.project(self.left_to_thermal(points))

    @property
    def thermal_camera(self) -> Camera:
        if self.thermal is None:
            raise CalibrationError("this rig has no thermal camera (add a 'thermal:' block)")
        return self.thermal

    def swapped(self) -> StereoRig:
        """The same rig with the roles of the two cameras exchanged (exact: ``R' = R^T``,
        ``T' = -R^T T``); for a rig calibrated with its image sets swapped (``T_x > 0``). A
        thermal camera is re-referenced to the new left camera."""
        Rs = self.R.T
        Ts = -Rs @ self.T
        kw: dict[str, Any] = {}
        if self.thermal is not None:
            # X_t = Rt X_l + Tt and X_l = R^T X_r - R^T T  ->  X_t = Rt R^T X_r + (Tt + Rt Ts)
            kw = dict(thermal=self.thermal, R_thermal=self.R_thermal @ Rs,
                      T_thermal=self.T_thermal + self.R_thermal @ Ts)
        left = Camera(self.right.K, self.right.dist, self.right.width, self.right.height,
                      "left")
        right = Camera(self.left.K, self.left.dist, self.left.width, self.left.height, "right")
        return StereoRig(left, right, Rs, Ts, rms_px=self.rms_px, info=dict(self.info), **kw)

    def with_thermal(self, thermal: Camera, R_thermal: ArrayLike,
                     T_thermal: ArrayLike) -> StereoRig:
        """A copy of this rig with a thermal camera (thermal-from-left extrinsics)."""
        return StereoRig(self.left, self.right, self.R, self.T, thermal, np.asarray(R_thermal),
                         np.asarray(T_thermal), self.rms_px, dict(self.info))

    # -- io ---------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {
            "kind": "stereo_rig",
            "left": self.left.to_dict(),
            "right": self.right.to_dict(),
            "R": self.R.tolist(),
            "T": self.T.tolist(),
        }
        if self.thermal is not None:
            d["thermal"] = {"camera": self.thermal.to_dict(), "R": self.R_thermal.tolist(),
                            "T": self.T_thermal.tolist()}
        if self.rms_px is not None:
            d["rms_px"] = float(self.rms_px)
        if self.info:
            d["info"] = dict(self.info)
        return d

    @classmethod
    def from_dict(cls, data: Any, where: str = "rig") -> StereoRig:
        if not isinstance(data, dict):
            raise ConfigError(f"{where}: expected a mapping")
        check_keys(data, ["kind", "left", "right", "R", "T", "thermal", "rms_px", "info"], where)
        left = Camera.from_dict(require(data, "left", where), f"{where}: left")
        right = Camera.from_dict(require(data, "right", where), f"{where}: right")
        R = as_float_array(require(data, "R", where), f"{where}: R", (3, 3))
        T = as_float_array(require(data, "T", where), f"{where}: T")  # (shape: StereoRig)
        kw: dict[str, Any] = {}
        if data.get("thermal") is not None:
            th = data["thermal"]
            w = f"{where}: thermal"
            if not isinstance(th, dict):
                raise ConfigError(f"{w}: expected a mapping with camera, R, T")
            check_keys(th, ["camera", "R", "T"], w)
            kw["thermal"] = Camera.from_dict(require(th, "camera", w), f"{w}: camera")
            kw["R_thermal"] = as_float_array(require(th, "R", w), f"{w}: R", (3, 3))
            kw["T_thermal"] = as_float_array(require(th, "T", w), f"{w}: T")
        rms = data.get("rms_px")
        if rms is not None and not (is_real(rms) and rms >= 0):
            # (a string escaped as a bare ValueError, a NaN was loaded as the RMS error)
            raise ConfigError(f"{where}: rms_px must be a finite number of pixels >= 0 (the "
                              f"stereo RMS reprojection error), got {rms!r}")
        info = data.get("info") or {}
        if not isinstance(info, dict):
            raise ConfigError(f"{where}: info must be a mapping")
        _info_camera_height(info, f"{where}: info")
        _info_camera_pitch(info, f"{where}: info")
        try:
            return cls(left=left, right=right, R=R, T=T,
                       rms_px=None if rms is None else float(rms), info=info, **kw)
        except CalibrationError as exc:
            raise ConfigError(f"{where}: {exc}") from None


def _info_camera_height(info: Any, where: str) -> float | None:
    """``info["camera_height_m"]`` (metres) as a float, None when absent; ConfigError naming
    the field when it is not a finite number > 0."""
    h = info.get("camera_height_m") if isinstance(info, dict) else None
    if h is None:
        return None
    if not (is_real(h) and h > 0):
        raise ConfigError(
            f"{where}: camera_height_m must be a finite number of metres > 0, got {h!r}"
        )
    return float(h)


def _info_camera_pitch(info: Any, where: str) -> float | None:
    """``info["camera_pitch_deg"]`` (degrees, + = looking up) as a float, None when absent;
    ConfigError naming the field when :func:`hearsee.vision.humans.check_camera_pitch`
    refuses it (a finite number within +-80 degrees)."""
    from hearsee.vision.humans import check_camera_pitch

    v = info.get("camera_pitch_deg") if isinstance(info, dict) else None
    try:  # (the detector's own rule, as a ConfigError naming the file's field)
        return check_camera_pitch(v, "camera_pitch_deg")
    except GeometryError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def transform_points(R: ArrayLike, t: ArrayLike, points: ArrayLike) -> NDArray:
    """Apply ``X' = R X + t`` to points ``(N, 3)`` (or one point ``(3,)``); metres.

    GeometryError for any other shape (a flat ``(6,)`` array used to be read as two points and
    silently lose the second) or an ``R`` / ``t`` that is not 3x3 / 3 numbers; text or bools
    in any of them too (numpy read "1" as 1 m, True as 1)."""
    for name, v in (("R", R), ("t", t), ("points", points)):
        if not real_entries(v):
            raise GeometryError(f"transform_points: {name} must hold numbers, got {v!r:.80}")
    P = np.asarray(points, dtype=float)
    Rm = np.asarray(R, dtype=float)
    tv = np.asarray(t, dtype=float)
    if Rm.shape != (3, 3):
        raise GeometryError(f"transform_points: R must be 3x3, got shape {Rm.shape}")
    if tv.size != 3:
        raise GeometryError(f"transform_points: t must have 3 numbers, got shape {tv.shape}")
    if P.shape != (3,) and (P.ndim != 2 or P.shape[1] != 3):
        raise GeometryError(
            f"transform_points: expected points of shape (N, 3) or (3,), got {P.shape}"
        )
    one = P.ndim == 1
    out = P.reshape(-1, 3) @ Rm.T + tv.reshape(1, 3)
    return out[0] if one else out


def _finite(values: Any, n: int) -> NDArray | None:
    """``values`` as ``n`` finite floats, or None when they are not (text or bools included:
    :func:`hearsee.config.real_entries`; numpy read "30" as 30 deg and True as 1)."""
    if not real_entries(values):
        return None
    a = np.asarray(values, dtype=float).reshape(-1)
    return a if a.size == n and np.all(np.isfinite(a)) else None


def check_rig(rig: Any, what: str) -> StereoRig:
    """``rig`` when it is a :class:`StereoRig`, else a CalibrationError naming ``what`` (None or
    a file name raised a builtin AttributeError in rectification or detection)."""
    if not isinstance(rig, StereoRig):
        raise CalibrationError(f"{what} needs a StereoRig (e.g. hearsee.vision.camera.load_rig"
                               f"(path)), got {type(rig).__name__}")
    return rig


def camera_pose(position_m: ArrayLike = (0.0, 0.0, 0.0), pan_deg: float = 0.0,
                tilt_deg: float = 0.0, roll_deg: float = 0.0) -> tuple[NDArray, NDArray]:
    """Pose of a camera on the robot: returns ``(R, t)`` with ``p_optical = R @ p_body + t``.

    The camera's optical centre is at ``position_m`` (body frame, metres, REP 103). With all
    angles zero it looks along body +x with image "up" = body +z. ``pan_deg`` turns it toward
    +y (left, like azimuth), ``tilt_deg`` raises it (like elevation), ``roll_deg`` rotates it
    about its viewing axis by the right-hand rule about body +x (the top of the camera turns
    toward the robot's right, so the scene appears rotated counter-clockwise in the image).

    >>> R, t = camera_pose((0.0, 0.0, 1.2))
    >>> np.round(R @ np.array([3.0, 0.5, 1.2]) + t, 6) + 0.0  # 3 m ahead, 0.5 m left, eye height
    array([-0.5,  0. ,  3. ])
    """
    angles = _finite((pan_deg, tilt_deg, roll_deg), 3)
    # (1e300 deg was taken, as a HeadPose refuses it: MAX_ANGLE_DEG)
    if angles is None or np.any(np.abs(angles) > MAX_ANGLE_DEG):
        raise GeometryError(
            f"camera_pose: pan, tilt and roll must be finite degrees within "
            f"+-{MAX_ANGLE_DEG:g}, got {(pan_deg, tilt_deg, roll_deg)}"
        )
    c = _finite(position_m, 3)
    if c is None:
        raise GeometryError(
            f"camera_pose: position_m must be 3 finite numbers (metres), got {position_m!r}"
        )
    # body-from-mount: mount axes are body axes turned by pan (about z), tilt, roll (about x)
    mount = Rotation.from_euler("ZYX", [pan_deg, -tilt_deg, roll_deg], degrees=True).as_matrix()
    R = OPTICAL_FROM_BODY @ mount.T
    return R, -R @ c


def head_camera_pose(pose: Any, pivot_m: ArrayLike = (0.0, 0.0, 0.0),
                     offset_m: ArrayLike = (0.0, 0.0, 0.0),
                     roll_deg: float = 0.0) -> tuple[NDArray, NDArray]:
    """Pose ``(R, t)`` (``p_optical = R @ p_robot + t``) of a camera carried by the pan-tilt
    head: optical centre at ``offset_m`` from the head pivot in the head frame, looking along
    the head's gaze (+x). ``pose`` is a :class:`hearsee.geometry.HeadPose` or
    ``(pan_deg, tilt_deg)``; ``pivot_m`` is in the robot frame (metres). Same kinematics as
    :func:`hearsee.geometry.array_to_robot`."""
    from hearsee.geometry import array_to_robot, as_pose

    p = as_pose(pose)
    centre = array_to_robot(np.zeros(3), p, pivot_m, offset_m)
    return camera_pose(centre, p.pan_deg, p.tilt_deg, roll_deg)


# ---------------------------------------------------------------------------------------------
# Files
# ---------------------------------------------------------------------------------------------
def _load_calib_yaml(path: str | Path) -> dict[str, Any]:
    p = input_file(path, "calibration file", " (create one with `hearsee calibrate`)")
    head = p.read_bytes()[:16]
    if head.startswith(b"%YAML:1.0") or head.startswith(b"%YAML 1.0"):
        raise ConfigError(
            f"{p}: this is an OpenCV FileStorage file, not a hearsee calibration file; read it "
            "with hearsee.vision.camera.read_opencv_yaml"
        )
    return load_yaml(p)


def load_camera(path: str | Path, which: str | None = None) -> Camera:
    """Read the camera of a camera file, or camera ``which`` ("left", "right", "thermal";
    default "left") from a rig file. Raises InputFileError / ConfigError naming the field.

    Given a camera file, ``which`` must be left out or be the camera's own ``name``: asking a
    single-camera file for the thermal camera used to return whatever camera it held.
    """
    data = _load_calib_yaml(path)
    where = str(path)
    if "left" in data or data.get("kind") == "stereo_rig":
        which = "left" if which is None else which
        if which not in ("left", "right", "thermal"):
            raise ConfigError(f"{where}: which must be left, right or thermal, got {which!r}")
        if which == "thermal":
            th = require(data, "thermal", where)
            if not isinstance(th, dict):
                raise ConfigError(f"{where}: thermal must be a mapping")
            return Camera.from_dict(require(th, "camera", f"{where}: thermal"),
                                    f"{where}: thermal: camera")
        return Camera.from_dict(require(data, which, where), f"{where}: {which}")
    cam = Camera.from_dict(data, where)
    if which is not None and which != cam.name:
        held = f"camera {cam.name!r}" if cam.name else "an unnamed camera"
        raise ConfigError(
            f"{where}: a single-camera file (holding {held}) has no {which!r} camera; leave out "
            "which, or give a stereo rig file"
        )
    return cam


def save_camera(camera: Camera, path: str | Path, *, rms_px: float | None = None) -> None:
    """Write ``camera`` as a camera YAML file (see the module docstring); ``rms_px`` in
    pixels. InputFileError for a path that cannot be written (checked before writing),
    CalibrationError for a camera that is not a Camera, an rms_px that is not a finite
    number >= 0 or a name YAML cannot represent (nothing is written)."""
    if not isinstance(camera, Camera):
        raise CalibrationError(f"save_camera needs a Camera, got {type(camera).__name__}")
    d = {"kind": "camera", **camera.to_dict()}
    if rms_px is not None:
        if not (is_real(rms_px) and rms_px >= 0):  # (text was a builtin ValueError)
            raise CalibrationError(f"save_camera: rms_px must be None or a finite number of "
                                   f"pixels >= 0, got {rms_px!r:.40}")
        d["rms_px"] = float(rms_px)
    _dump_calib_yaml(d, path, "hearsee camera (see hearsee.vision.camera)")


def load_rig(path: str | Path) -> StereoRig:
    """Read a stereo rig YAML file (see the module docstring)."""
    data = _load_calib_yaml(path)
    if "left" not in data:
        raise ConfigError(f"{path}: missing required key 'left' (is this a single-camera file?)")
    return StereoRig.from_dict(data, str(path))


def save_rig(rig: StereoRig, path: str | Path) -> None:
    """Write ``rig`` as a stereo rig YAML file (see the module docstring). InputFileError
    for a path that cannot be written (checked before writing), CalibrationError for a rig
    that is not a StereoRig or whose ``info`` holds a value YAML cannot represent (a Path:
    PyYAML's builtin RepresenterError before; nothing is written)."""
    check_rig(rig, "save_rig")
    _dump_calib_yaml(rig.to_dict(), path, "hearsee stereo rig (see hearsee.vision.camera)")


def _dump_calib_yaml(data: dict[str, Any], path: str | Path, title: str) -> None:
    """YAML with matrices written one row per line (flow style for the innermost lists).
    InputFileError (:func:`hearsee.config.output_file`) when ``path`` cannot be written: a
    folder, a missing folder, not a path (builtin IsADirectoryError, FileNotFoundError and
    TypeError before); CalibrationError, before anything is written, when ``data`` holds a
    value YAML cannot represent (a Path in a rig's info). An existing file is replaced only
    once the new one is complete (:func:`hearsee.config.write_file`): written in place, a write
    that failed part way (a full disk, Ctrl-C) left a truncated calibration where the earlier
    one was (``calibrate --force``), and said only "File too large"."""
    p = output_file(path)
    # (YamlDumper: text such as a name "2e5" is quoted, else load_yaml read it as a number)
    try:
        text = yaml.dump(to_plain(data), Dumper=YamlDumper, sort_keys=False,
                         default_flow_style=None, width=100)
    except yaml.YAMLError as exc:
        # (a Path or another object in a rig's info, or as a camera's name, was PyYAML's
        # builtin RepresenterError; nothing is written)
        bad = exc.args[1] if len(exc.args) > 1 else exc
        raise CalibrationError(
            f"{p}: the calibration holds a value a YAML file cannot hold "
            f"({type(bad).__name__} {bad!r:.60}); give rig info values and camera names as "
            "text, numbers, lists or mappings") from None
    header = (f"# {title}\n# optical frame x right, y down, z forward; K in pixels; "
              "T in metres; X_to = R X_from + T\n")
    write_file(p, header + text)


def rig_from_opencv(intrinsics: str | Path, extrinsics: str | Path,
                    image_size: tuple[int, int], *, scale_to_m: float = 1.0) -> StereoRig:
    """A rig from OpenCV ``stereo_calib``-style FileStorage files: ``M1``, ``D1``, ``M2``,
    ``D2`` in ``intrinsics`` and ``R``, ``T`` in ``extrinsics``. Those files do not store the
    image size (``(width, height)``, pixels) nor the length unit of ``T``: ``scale_to_m``
    converts it to metres (0.001 for millimetres)."""
    if isinstance(image_size, str) or not hasattr(image_size, "__len__") or len(image_size) != 2:
        raise CalibrationError(f"image_size: width and height must be positive integers, got "
                               f"{image_size!r:.80}")
    size = check_size(*image_size, what="image_size")
    # (int() read "640" as 640 and truncated 640.7; a text scale was numpy's builtin TypeError)
    scale_to_m = finite_number("scale_to_m", scale_to_m, 0.0, lo_open=True)
    a = read_opencv_yaml(intrinsics)
    b = read_opencv_yaml(extrinsics)
    for src, path, keys in ((a, intrinsics, ("M1", "D1", "M2", "D2")), (b, extrinsics, ("R", "T"))):
        for k in keys:
            if k in src and not isinstance(src[k], np.ndarray):
                # (a number or a string raised a bare AttributeError on .ravel())
                raise ConfigError(f"{path}: {k!r} must be a matrix (!!opencv-matrix), got "
                                  f"{src[k]!r}")
    cams = []
    for src, keys in ((a, ("M1", "D1")), (a, ("M2", "D2"))):
        for k in keys:
            if k not in src:
                raise ConfigError(f"{intrinsics}: missing matrix {k!r}")
        try:
            cams.append(Camera(src[keys[0]], src[keys[1]].ravel(), size[0], size[1],
                               "left" if keys[0] == "M1" else "right"))
        except CalibrationError as exc:
            raise ConfigError(f"{intrinsics}: {keys[0]}/{keys[1]}: {exc}") from None
    for k in ("R", "T"):
        if k not in b:
            raise ConfigError(f"{extrinsics}: missing matrix {k!r}")
    try:
        return StereoRig(cams[0], cams[1], b["R"], b["T"].ravel() * scale_to_m)
    except CalibrationError as exc:
        raise ConfigError(f"{extrinsics}: {exc}") from None


def read_opencv_yaml(path: str | Path) -> dict[str, Any]:
    """Read the top-level nodes of an OpenCV ``FileStorage`` file: matrices (``!!opencv-matrix``)
    and sequences of numbers -> float numpy arrays, numbers -> float, strings -> str. Other
    nodes (plain maps, sequences of strings or of structures) are skipped; a matrix node that
    OpenCV cannot read (rows x cols not its number of values, an unknown dt) is a
    ConfigError naming it."""
    p = input_file(path)
    try:
        fs = cv2.FileStorage(str(p), cv2.FILE_STORAGE_READ)
    except (cv2.error, SystemError) as exc:
        # an empty, plain-YAML or binary file makes the constructor raise SystemError (its
        # cv2.error is only the __cause__)
        raise ConfigError(
            f"{p}: not a readable OpenCV FileStorage file ({_fs_error_text(exc, p)}; expected "
            "'%YAML:1.0' with !!opencv-matrix nodes)"
        ) from None
    if not fs.isOpened():
        raise ConfigError(f"{p}: not a readable OpenCV FileStorage file")
    out: dict[str, Any] = {}
    try:
        root = fs.root()
        for key in root.keys():
            try:
                value = _fs_value(fs.getNode(key))
            except ValueError as exc:
                raise ConfigError(f"{p}: {key}: {exc}") from None
            if value is not None:
                out[key] = value
    except cv2.error as exc:
        raise ConfigError(
            f"{p}: not a readable OpenCV FileStorage file ({exc.msg.strip()})"
        ) from None
    finally:
        fs.release()
    return out


def _fs_error_text(exc: BaseException, path: Path) -> str:
    """A short reason for a FileStorage failure (OpenCV's own text names its source files)."""
    if path.stat().st_size == 0:
        return "the file is empty"
    err = exc if isinstance(exc, cv2.error) else exc.__cause__
    if isinstance(err, cv2.error):
        m = re.search(r"\((\d+)\): (.+)", str(getattr(err, "func", "")))
        if m:  # parse errors: func = "name(line): message"
            return f"line {m.group(1)}: {m.group(2).strip()}"
        return str(getattr(err, "err", "")).strip() or "unreadable"
    return "unreadable"


def _is_number(node: cv2.FileNode) -> bool:
    return node.isReal() or node.isInt()


def _fs_value(node: cv2.FileNode) -> float | str | NDArray | None:
    """The value of one FileStorage node (see :func:`read_opencv_yaml`), None to skip it."""
    if _is_number(node):
        return float(node.real())
    if node.isString():
        return node.string()
    if node.isSeq():
        items = [node.at(i) for i in range(node.size())]
        if all(_is_number(it) for it in items):
            return np.array([it.real() for it in items], dtype=float)
        return None
    if node.isMap():
        try:  # only !!opencv-matrix / !!opencv-nd-matrix maps are matrices
            m = node.mat()
        except cv2.error:
            m = None
        if m is None and {"rows", "cols", "data"} <= set(node.keys()):
            # (a matrix whose rows x cols do not match its data, or whose dt is not a type,
            # was skipped: "no M1 camera matrix" for an M1 that is there, broken)
            raise ValueError("a malformed !!opencv-matrix (rows, cols, dt and the number of "
                             "data values must agree)")
        return None if m is None else np.asarray(m, dtype=float)
    return None
