"""Stereo + thermal human detection (thesis 7.4): a stereo candidate is a human only when the
thermal camera sees it warm.

Reconstruction. The stereo detector (:mod:`hearsee.vision.humans`) finds person-shaped
candidates; each candidate's 3D silhouette points are moved from the (rectified) left frame into
the thermal camera's frame with the rig's extrinsics (``X_thermal = R_thermal X_left +
T_thermal``, calibrated as in 7.4.1 / :mod:`hearsee.vision.calibration`), projected with the
thermal camera's intrinsics and distortion (fig. 7.13), and looked up in the thermal filter's
warm mask (:mod:`hearsee.vision.thermal`). The *thermal support* is the weighted fraction of
the projected points that land on warm pixels, with the head and shoulders (the top 0.4 m of
the silhouette) weighted ``head_weight`` times more -- faces are the most reliably warm part of
a clothed person. A candidate is accepted when stereo verification passed and
``support >= min_support``. This rejects human-shaped objects at room temperature (mannequins,
posters, coats on stands; figs. 7.20-7.21). It fails (fig. 7.22) when a person's visible
surface is cold (a heavy coat and a covered head just in from outside) or when a human-shaped
object is warm (a mannequin heated by a radiator or the sun): see ``examples/ch7_humans.py``.

Because the thermal camera sits elsewhere on the rig, projecting 3D points -- not pixels --
handles the parallax: the same image offset would be wrong at 1 m and at 8 m.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hearsee.config import finite_number, is_real, real_entries, whole_number
from hearsee.errors import CalibrationError, ConfigError, GeometryError, ImageInputError
from hearsee.vision.camera import Rectification, StereoRig, check_rig
from hearsee.vision.humans import (
    HumanCandidate,
    HumanDetectorParams,
    StereoDetection,
    check_camera_height,
    check_camera_pitch,
    check_params,
    detect_candidates,
    robust_top_m,
)
from hearsee.vision.io import check_image, numeric_map
from hearsee.vision.stereo import StereoFrame, points_to_left_frame, stereo_frame
from hearsee.vision.thermal import HUMAN_BAND_C, thermal_mask

__all__ = [
    "DetectionResult",
    "Human",
    "classify_candidates",
    "detect_humans",
    "draw_detections",
    "thermal_support",
]

#: Disparity options used by the detector (64 disparities: people from ~0.95 m at f B = 60 px m;
#: nearer ones are flagged Human.beyond_search when their silhouette is broken up).
DEFAULT_STEREO_OPTIONS: dict[str, Any] = {"num_disparities": 64, "block_size": 3}


@dataclass
class Human:
    """One detection (accepted or rejected).

    ``box`` [x, y, w, h] in rectified left-image pixels (``DetectionResult.frame.left``),
    down to the floor under the body (:attr:`~hearsee.vision.humans.BodySegment.body_box`;
    until 2026-12-03 it stopped 0.12 m above the feet);
    ``position_m`` torso centre in the left camera's own optical frame (metres); ``score`` the
    head-shoulder score; ``thermal_support`` in [0, 1] (None without a thermal image, NaN when
    the thermal camera does not see the candidate); ``reason`` why it was rejected (empty when
    accepted); ``truncated`` when the silhouette is cut by the top, left or right image border,
    so that its position and height describe the visible part only; ``beyond_search`` when
    part of the body stands nearer than the disparity search reaches and the silhouette is
    broken up, so that its position may be tens of cm off
    (:class:`~hearsee.vision.humans.BodySegment`).
    """

    box: list[int]
    position_m: NDArray
    score: float
    thermal_support: float | None
    height_m: float
    accepted: bool
    reason: str = ""
    truncated: bool = False
    beyond_search: bool = False

    @property
    def distance_m(self) -> float:
        return float(np.linalg.norm(self.position_m))

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {
            "box": [int(v) for v in self.box],
            "position_m": [round(float(v), 3) for v in self.position_m],
            "distance_m": round(self.distance_m, 3),
            "height_m": round(float(self.height_m), 3),
            "score": round(float(self.score), 3),
            "thermal_support": (None if self.thermal_support is None else
                                round(float(self.thermal_support), 3)),
            "truncated": bool(self.truncated),
            "beyond_search": bool(self.beyond_search),
        }
        if not self.accepted:
            d["reason"] = self.reason
        return d


@dataclass
class DetectionResult:
    """Output of :func:`detect_humans`: accepted ``humans``, ``rejected`` candidates, and the
    intermediate results (stereo frame, stereo detection, thermal warm mask)."""

    humans: list[Human]
    rejected: list[Human]
    frame: StereoFrame
    stereo: StereoDetection
    warm_mask: NDArray | None = None
    info: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"humans": [h.to_dict() for h in self.humans],
                "rejected": [h.to_dict() for h in self.rejected], **self.info}


def thermal_support(points_left: NDArray, heights: NDArray, rig: StereoRig, warm: NDArray, *,
                    head_weight: float = 2.0, head_band_m: float = 0.4, max_points: int = 2000,
                    min_points: int = 15) -> float:
    """Weighted fraction of a candidate's 3D points that project onto warm thermal pixels.

    ``points_left`` ``(N, 3)``: silhouette points in the left optical frame (metres);
    ``heights`` ``(N,)`` their heights above the floor (the top ``head_band_m`` metres get weight
    ``head_weight`` > 0); ``warm`` the thermal filter's mask (thermal image size; bool, or 0/1
    numbers -- a 0/255 image is refused, it gave "fractions" up to 255). Points projecting
    outside the thermal image are ignored; NaN when fewer than ``min_points`` remain
    (``max_points`` >= ``min_points``, ConfigError otherwise).

    The head band is counted down from the robust top of the points the thermal camera sees
    (:func:`~hearsee.vision.humans.robust_top_m`, as
    :attr:`~hearsee.vision.humans.BodySegment.top_m`); before 2026-11-26 it was counted from
    the highest point, so one stray point above the head (a wall pixel that passed the depth
    band) moved the band off the head.
    """
    cam = rig.thermal_camera
    warm = _check_mask(warm)
    if not (is_real(head_weight) and head_weight > 0):
        raise ConfigError(f"head_weight must be a finite number > 0, got {head_weight!r}")
    # (a NaN head band switched the head weighting off; a NaN or negative count raised
    # numpy's errors or kept no point)
    finite_number("head_band_m", head_band_m, 0.0)
    max_points = whole_number("max_points", max_points)
    min_points = whole_number("min_points", min_points, 0)
    if max_points < min_points:  # (kept fewer points than it needed: NaN whatever the points)
        raise ConfigError(f"max_points ({max_points}) must be >= min_points ({min_points})")
    if warm.ndim != 2:  # ((15, 20, 1) was "20x15 pixels but ... is 20x15")
        raise ImageInputError(f"thermal mask must be (H, W) = {cam.shape}, got shape "
                              f"{warm.shape}")
    if warm.shape != cam.shape:
        raise ImageInputError(
            f"thermal image is {warm.shape[1]}x{warm.shape[0]} pixels but the calibration's "
            f"thermal camera is {cam.width}x{cam.height}"
        )
    if not (real_entries(points_left) and real_entries(heights)):  # (text read as metres)
        raise GeometryError("thermal_support: points and heights must be numbers (metres)")
    P = np.asarray(points_left, dtype=float)
    h = np.asarray(heights, dtype=float)
    if P.ndim != 2 or P.shape[1] != 3 or h.shape != (len(P),):
        raise GeometryError(f"thermal_support: expected points (N, 3) and heights (N,), got "
                            f"{P.shape} and {h.shape}")
    if len(P) > max_points:  # deterministic subsample
        idx = np.linspace(0, len(P) - 1, max_points).astype(int)
        P, h = P[idx], h[idx]
    if len(P) == 0:
        return float("nan")
    P_t = rig.left_to_thermal(P)
    uv = cam.project(P_t)
    # (in the image, and where the lens model is one to one: a strongly distorting lens's
    # polynomial folds points far outside its view back into the image)
    ok = cam.in_image(uv) & cam.in_lens_field(P_t)
    if ok.sum() < max(min_points, 1):  # (none: no top, no fraction)
        return float("nan")
    uv, h = uv[ok], h[ok]
    u = np.clip(np.rint(uv[:, 0]).astype(int), 0, cam.width - 1)
    v = np.clip(np.rint(uv[:, 1]).astype(int), 0, cam.height - 1)
    w = np.where(h >= robust_top_m(h) - head_band_m, head_weight, 1.0)
    return float((w * warm[v, u]).sum() / w.sum())


def _check_mask(warm: NDArray) -> NDArray:
    """The warm mask as bool; ImageInputError unless it is bool or holds only 0 and 1."""
    m = np.asarray(warm)
    if m.dtype == np.bool_:
        return m
    if m.dtype.kind not in "uif" or not np.all((m == 0) | (m == 1)):
        raise ImageInputError(
            f"warm mask must be bool (or 0/1), got {m.dtype} with values "
            f"{np.unique(m)[:4].tolist() if m.dtype.kind in 'uif' else '?'} (a 0/255 image? use "
            "mask > 0)"
        )
    return m.astype(bool)


def _to_human(c: HumanCandidate, support: float | None, accepted: bool, reason: str) -> Human:
    seg = c.segment
    assert seg is not None
    return Human(seg.body_box, seg.position_m, c.score, support, seg.top_m, accepted, reason,
                 seg.truncated, seg.beyond_search)


def classify_candidates(det: StereoDetection, rig: StereoRig, rect: Rectification,
                        warm: NDArray | None, *, min_support: float = 0.3
                        ) -> tuple[list[Human], list[Human]]:
    """Turn stereo candidates into accepted humans and rejected candidates.

    Without ``warm`` (the thermal filter's mask) the stereo decision stands (stereo-only
    detection); with it, stereo-accepted candidates also need ``thermal_support >= min_support``.
    Duplicates and empty segmentations are dropped. Positions are returned in the left camera's
    own optical frame.
    """
    if not (is_real(min_support) and 0 <= min_support <= 1):
        # (NaN rejected every candidate: support >= NaN is False)
        raise ConfigError(f"min_support must be a thermal support in [0, 1], got {min_support!r}")
    needs_rect = not rig.is_rectified
    humans, rejected = [], []
    for c in det.candidates:
        if c.segment is None or c.reason.startswith("duplicate"):
            continue
        support = None
        if warm is not None:
            pts = c.segment.points
            if needs_rect:
                pts = points_to_left_frame(pts, rect)
            support = thermal_support(pts, c.segment.heights, rig, warm)
        if not c.accepted:
            rejected.append(_to_human(c, support, False, c.reason))
        elif support is not None and not support >= min_support:
            why = ("not seen by the thermal camera" if np.isnan(support) else
                   f"thermal support {support:.2f} < {min_support}")
            rejected.append(_to_human(c, support, False, why))
        else:
            humans.append(_to_human(c, support, True, ""))
    if needs_rect:  # positions back to the left camera's own frame
        for h in humans + rejected:
            h.position_m = points_to_left_frame(h.position_m, rect)
    humans.sort(key=lambda h: h.distance_m)
    return humans, rejected


def detect_humans(left: NDArray, right: NDArray, rig: StereoRig, thermal: NDArray | None = None,
                  *, params: HumanDetectorParams | None = None, min_support: float = 0.3,
                  band_c: tuple[float, float] = HUMAN_BAND_C,
                  camera_height_m: float | None = None,
                  stereo_options: dict[str, Any] | None = None,
                  camera_pitch_deg: float | None = None) -> DetectionResult:
    """Detect humans in a stereo pair, confirmed by a thermal image when one is given.

    Parameters
    ----------
    left, right : stereo images (uint8, grey or BGR) of the rig's size (rectified here if the
        rig needs it).
    rig : the calibrated rig; must have a thermal camera when ``thermal`` is given.
    thermal : thermal image of the rig's thermal camera: float degC, uint16 centi-kelvin or
        uint8 non-radiometric (see :func:`hearsee.vision.thermal.thermal_mask`). An 8-bit
        frame's "warm" is relative to the frame: with nobody warm in view its contrast
        stretch spreads a room-temperature scene over 0-255 and an object's warmest pixels can
        pass (a review helper's 30 rooms with one mannequin, poster or coat stand each and
        nobody else, seeds 100-129: 2 accepted with the 8-bit frame, 0 with degC).
    params : stereo detector parameters (Tm = ``params.tm``).
    min_support : thermal support needed to accept a candidate.
    band_c : radiometric human temperature band (degC).
    camera_height_m : prior for the floor, metres above it (finite, > 0; default
        ``rig.info["camera_height_m"]``).
    camera_pitch_deg : prior for the floor: the left camera's pitch above the horizontal,
        degrees (+ = looking up, no roll; within +-80, GeometryError otherwise; default
        ``rig.info["camera_pitch_deg"]``, else level). A head that tilts passes its tilt: taken
        as level, a camera pitched up 15 deg saw too little floor to fit and lost most people
        (:func:`hearsee.vision.humans.estimate_floor`).
    stereo_options : options of :func:`hearsee.vision.stereo.compute_disparity`, a mapping
        of their names to values (ConfigError otherwise, before the stereo matching).

    Returns
    -------
    :class:`DetectionResult`; boxes in rectified left-image pixels (the image
    ``result.frame.left``), positions in the left camera's own optical frame (metres).
    """
    check_rig(rig, "detect_humans")
    if thermal is not None and rig.thermal is None:
        raise CalibrationError(
            "a thermal image was given but the calibration has no thermal camera: add a "
            "'thermal:' block (camera, R, T) to the calibration file or leave out the thermal image"
        )
    # (a dict was an AttributeError deep in the candidate detector; checked before the stereo
    # matching, edited fields too)
    params = check_params(params)
    th = None
    if thermal is not None:  # checked before the stereo matching, not after it
        th = numeric_map("thermal image", thermal, None)  # (text / a number: IndexError)
        cam = rig.thermal_camera
        if th.ndim not in (2, 3):
            raise ImageInputError(f"thermal image must be (H, W) or (H, W, C), got shape "
                                  f"{th.shape}")
        if th.shape[:2] != cam.shape:
            raise ImageInputError(
                f"thermal image is {th.shape[1]}x{th.shape[0]} pixels but the calibration's "
                f"thermal camera is {cam.width}x{cam.height}"
            )
    # a bad camera height fails before the stereo matching, not after it
    if camera_height_m is None:
        camera_height_m = rig.camera_height_m  # ConfigError when info holds a bad one
    check_camera_height(camera_height_m)
    if camera_pitch_deg is None:
        camera_pitch_deg = rig.camera_pitch_deg  # ConfigError when info holds a bad one
    camera_pitch_deg = check_camera_pitch(camera_pitch_deg)
    if stereo_options is not None and (not isinstance(stereo_options, Mapping) or not all(
            isinstance(k, str) for k in stereo_options)):
        # (a list was dict.update's builtin TypeError or, as pairs, taken; a key of another
        # type the call's "keywords must be strings")
        raise ConfigError(f"stereo_options must be a mapping of compute_disparity's option "
                          f"names to values, got {stereo_options!r:.60}")
    opts = dict(DEFAULT_STEREO_OPTIONS)
    opts.update(stereo_options or {})
    # the thermal filter before the stereo matching: its checks (an (H, W, 3) float image, a
    # float one in kelvin, a bad band_c) refused the image only after the matching had run
    warm = None if th is None else thermal_mask(th, band_c=band_c)
    frame = stereo_frame(left, right, rig, **opts)
    rect = frame.rectification
    det = detect_candidates(frame.disparity, frame.points(), frame.focal_px, frame.baseline_m,
                            rect.cy, camera_height_m=camera_height_m, params=params,
                            search_max_px=frame.search_px[1], camera_pitch_deg=camera_pitch_deg)
    humans, rejected = classify_candidates(det, rig, rect, warm, min_support=min_support)
    info = {"floor": {"source": det.floor.source,
                      "camera_height_m": round(det.floor.camera_height_m, 3),
                      "camera_pitch_deg": round(det.floor.pitch_deg, 2)},
            "thermal": None if thermal is None else
            ("radiometric" if th.dtype != np.uint8 else "relative")}
    return DetectionResult(humans, rejected, frame, det, warm, info)


def draw_detections(image: NDArray, result: DetectionResult, *, show_rejected: bool = True
                    ) -> NDArray:
    """The left image with accepted humans in green (distance, score, support) and, with
    ``show_rejected``, in red the rejected candidates that reached head-shoulder verification
    (thermal or template rejections; walls and furniture that failed the size test are not
    drawn); returns a new BGR uint8 image.

    The boxes are in rectified left-image pixels: pass the rectified left image
    ``result.frame.left`` (the raw left image is the same only for an already rectified rig,
    :attr:`StereoRig.is_rectified`). ImageInputError unless ``image`` is a non-empty 8-bit
    grey, BGR or BGRA image (an int64 or empty one used to fail inside OpenCV)."""
    import cv2

    img = check_image(numeric_map("image", image, None))
    if img.dtype != np.uint8:
        raise ImageInputError(f"draw_detections needs an 8-bit image (the rectified left "
                              f"image), got pixel type {img.dtype}")
    if img.ndim == 3 and img.shape[2] == 4:
        out = cv2.cvtColor(img, cv2.COLOR_BGRA2BGR)
    elif img.ndim == 3 and img.shape[2] == 3:
        out = img.copy()
    else:
        out = cv2.cvtColor(img.reshape(img.shape[:2]), cv2.COLOR_GRAY2BGR)
    items = [(h, (0, 200, 0)) for h in result.humans]
    if show_rejected:
        items += [(h, (0, 0, 230)) for h in result.rejected if h.score > 0]
    for h, col in items:
        x, y, w, hh = h.box
        cv2.rectangle(out, (x, y), (x + w - 1, y + hh - 1), col, 2)
        sup = "" if h.thermal_support is None else f" T{h.thermal_support:.2f}"
        label = f"{h.distance_m:.1f}m s{h.score:.2f}{sup}"
        if not h.accepted:
            label = h.reason[:28]
        cv2.putText(out, label, (x, max(10, y - 4)), cv2.FONT_HERSHEY_SIMPLEX, 0.38, col, 1,
                    cv2.LINE_AA)
    return out
