"""Image points of the sound source for the tracking stream: from a CSV sidecar or a video.

The camera-ray + ITD fusion (:func:`hearsee.fusion.audiovisual.locate_on_ray`) needs, per audio
frame, the pixel ``(u, v)`` where the source appears. Two providers, both callables
``points(t_seconds) -> (u, v) or None``:

* :class:`CsvImagePoints` reads ``t,u,v`` rows (seconds, pixels; empty u and v = not seen),
  e.g. written by a simulation or an external detector, and interpolates linearly between rows
  that are at most ``max_gap_s`` apart. An infinite pixel, a row with only one of u and v,
  or (given the calibrated camera) a pixel outside its image by more than
  :data:`IMAGE_POINT_MARGIN` of the image's larger side or one its lens model gives no ray
  for, is refused with an error naming the file and line, like any other row it cannot use.
* :class:`VideoImagePoints` reads a video file (which must deliver a first frame: a corrupt or
  empty one is refused) or a camera (OpenCV ``VideoCapture``) and runs a simple detector on
  the frame nearest time t: OpenCV's HOG people detector (Dalal & Triggs 2005; ``detector="hog"``,
  image point = 12 % down the person box, about the mouth of a standing person) or the Haar
  frontal-face cascade that ships in ``cv2.data`` (Viola & Jones 2001; ``detector="face"``,
  image point = 65 % down the face box). These are honest baselines, not
  state-of-the-art detectors: they miss people seen from the side or partly out of view
  (then the tracker falls back to direction-only updates), and with several people they
  pick the strongest detection, which need not be the speaker.

A video file's frame carries its own time (:class:`FileFrameClock`: OpenCV's
``CAP_PROP_POS_MSEC`` from the first frame's, which counts the frames a capture tool dropped --
frame index / fps only where the file gives no usable timestamp, or with an explicit
``fps``); the image point at t is that of the frame nearest t (the earlier at a tie; frames
are read forward only, one ahead). A live camera is read in its own
thread which keeps the latest detection; ``points(t)`` then returns that (the audio and
camera clocks are not synchronised beyond "latest frame", about one camera frame period).
Either way an image point
goes stale: a file's is None when its frame is more than two frame periods from t, a live
camera's when the camera has ended or its latest frame is more than two frame periods old on
the wall clock (the period being the longer of 1/fps and the camera thread's last
read-and-detect cycle, since the detector may be slower than the camera).
"""

from __future__ import annotations

import csv
import math
import os
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hearsee.config import finite_number, input_file, is_real, whole_number
from hearsee.errors import ConfigError, ImageInputError

__all__ = ["FIRST_FRAME_TIMEOUT_S", "IMAGE_POINT_MARGIN", "CsvImagePoints", "TimedCapture",
           "FileFrameClock", "VideoImagePoints", "detect_source_point", "read_frame",
           "save_image_points"]

#: How far outside the camera image (a fraction of its larger side, e.g. 64 px of a 640 x 480
#: image) an image point of a CSV may lie: a detector's point just past the edge is still a
#: usable ray, one farther off is a wrong column, a swapped u/v or another camera's pixels.
IMAGE_POINT_MARGIN = 0.1


#: How long a live camera or stream may take to deliver its first frame (seconds) before
#: ``hearsee run --dry-run`` reports it as delivering none: a device that opens and then blocks
#: in every read (a camera held by a stalled driver, a network stream that stopped) otherwise
#: hung the check forever. Cameras take up to a second or two to start streaming.
FIRST_FRAME_TIMEOUT_S = 5.0


class TimedCapture:
    """An OpenCV capture whose :meth:`read` gives up after ``timeout_s`` seconds.

    ``cv2.VideoCapture.read`` of a live device or a network stream can block forever (a camera
    that opens and then delivers nothing, a stream whose server stopped), which stalled the
    robot's loop and ``hearsee run --dry-run``. Each read runs in a daemon thread; when it has
    not returned within ``timeout_s``, :meth:`read` returns ``(False, None)`` -- "no frame", as a
    capture that ended -- and the capture counts as :attr:`stuck` until that read returns (its
    late frame is dropped): no second read is started on the same capture meanwhile, and
    :meth:`release` leaves a stuck capture alone (releasing it under a blocked read is not
    safe in OpenCV; the daemon thread does not keep the process alive). Other attributes
    (``get``, ``set``, ``grab``, ``isOpened``) are the capture's own. Video files do not need
    this (their reads do not block) and are read directly, deterministically.
    """

    def __init__(self, cap: Any, timeout_s: float) -> None:
        self.cap = cap
        self.timeout_s = finite_number("camera read timeout", timeout_s, 0.0, lo_open=True)
        self._pending: Any = None  # the thread of a read that has not returned yet

    @property
    def stuck(self) -> bool:
        """True while a read that timed out has still not returned."""
        return self._pending is not None and self._pending.is_alive()

    def read(self) -> tuple[bool, Any]:
        import threading

        if self.stuck:
            return False, None
        box: list[Any] = [(False, None)]

        def run() -> None:
            try:
                box[0] = self.cap.read()
            except BaseException as exc:  # (raised in the caller's thread below)
                box[0] = exc

        th = threading.Thread(target=run, daemon=True, name="hearsee-camera-read")
        th.start()
        th.join(self.timeout_s)
        if th.is_alive():
            self._pending = th
            return False, None
        self._pending = None
        if isinstance(box[0], BaseException):
            raise box[0]
        return box[0]

    def release(self) -> None:
        if not self.stuck:
            self.cap.release()

    def __getattr__(self, name: str) -> Any:
        return getattr(self.cap, name)


def read_frame(cap: Any, spec: Any, where: str, size: tuple[int, int] | None = None
               ) -> NDArray:
    """One frame from an open OpenCV capture ``cap`` (of the camera or file ``spec``; a
    :class:`TimedCapture` for a device that may block); ConfigError prefixed ``where`` when
    none comes (in time) or it has the wrong size (``size`` = (width, height), pixels). The one
    "delivers frames" check of ``hearsee run --dry-run`` and ``hearsee track --video``. The
    message says "video file" when ``spec`` is the path of a file (it said "camera" for those
    too), else "camera"."""
    # (a device such as /dev/video0 or a URL is no regular file)
    is_file = isinstance(spec, str | Path) and os.path.isfile(spec)
    what = f"video file {str(spec)!r}" if is_file else f"camera {spec!r}"
    ok, frame = cap.read()
    if isinstance(cap, TimedCapture) and cap.stuck:
        raise ConfigError(f"{where}: {what} opened but delivered no frame within "
                          f"{cap.timeout_s:g} s")
    if not ok or frame is None:
        raise ConfigError(f"{where}: {what} opened but delivered no frame")
    if size is not None and (frame.shape[1], frame.shape[0]) != tuple(size):
        raise ConfigError(f"{where}: {what} delivers {frame.shape[1]}x{frame.shape[0]} "
                          f"frames but the calibration expects {size[0]}x{size[1]}")
    return frame


class FileFrameClock:
    """The times (seconds) of a video FILE's frames, called once per frame as a capture reads
    or grabs them: the first frame at 0 s, each later one at its timestamp (OpenCV's
    ``CAP_PROP_POS_MSEC``) minus the first frame's. A capture tool records a dropped frame as an
    empty chunk, which OpenCV skips, and the timestamps keep that gap where frame index / fps
    put every later frame one period early per drop. Only differences count: containers may
    start their clock elsewhere (the pedestrian clip of the shared data reads 0.2 s at its
    first frame), and the video starts with the recording. A frame without a usable timestamp
    (not finite, or not after the frame before: a backend without them) is at index / ``fps``
    (frames per second > 0), or one period after the frame before where that is not later.
    The one frame clock of :class:`VideoImagePoints` and the robot's video-file cameras."""

    def __init__(self, fps: float) -> None:
        self.fps = finite_number("fps", fps, 0.0, lo_open=True)
        self.index = 0  # frames timed so far
        self.previous = -np.inf  # the last frame's time (s)
        self._origin: float | None = None  # the first frame's timestamp (s; NaN: none)

    def __call__(self, cap: Any) -> float:
        """Time (s) of the frame ``cap`` has just read or grabbed."""
        import cv2

        pos = cap.get(cv2.CAP_PROP_POS_MSEC)
        stamp = pos / 1000.0 if is_real(pos) and np.isfinite(pos) else np.nan
        if self._origin is None:
            self._origin = stamp
        t = stamp - self._origin
        if not (np.isfinite(t) and t >= 0.0 and t > self.previous):
            t = self.index / self.fps
            if not t > self.previous:
                t = self.previous + 1.0 / self.fps
        self.index += 1
        self.previous = float(t)
        return self.previous


class CsvImagePoints:
    """Image points from a CSV file with header ``t,u,v`` (seconds, pixels).

    Rows with empty ``u`` and ``v`` mean "source not visible"; a row with only one of them
    (``0.5,195,``) is ambiguous -- a lost column or a typo -- and a ConfigError naming the file
    and line. ``points(t)`` interpolates between
    the two rows around t when they are at most ``max_gap_s`` apart, returns the nearest row
    within ``max_gap_s / 2`` otherwise, else None.

    ``camera`` (a :class:`hearsee.vision.camera.Camera`; ``hearsee track`` passes the
    calibrated one) bounds the pixels: a point outside its image by more than
    :data:`IMAGE_POINT_MARGIN` of the larger side is a ConfigError naming the file and line
    (it was used as a ray through no pixel of the camera), and so is a pixel the lens model
    gives no ray for (:meth:`hearsee.vision.camera.Camera.pixel_rays`: near the corners of an
    image whose radial distortion folds back before them). An infinite pixel (``inf``,
    ``1e400``) is one always; empty cells (or NaN) mean "not visible".
    :meth:`visible_within` tells whether any visible row can be used in a time span (``hearsee
    track`` warns when none lies within the recording).
    """

    def __init__(self, path: str | Path, max_gap_s: float = 0.2, camera: Any = None) -> None:
        # (a NaN or negative gap silently gave no image point at all, not even at a row's time)
        max_gap_s = finite_number("max_gap_s", max_gap_s, 0.0)
        p = input_file(path, "image-point file")
        try:
            with p.open(newline="", encoding="utf-8-sig") as fh:  # (a spreadsheet's BOM)
                reader = csv.reader(fh)  # (its line_num: the file's line, blank ones counted)
                rows = [(reader.line_num, r) for r in reader if r and any(c.strip() for c in r)]
        except UnicodeDecodeError:
            raise ConfigError(f"{p}: not a text CSV file") from None
        if not rows or [c.strip().lower() for c in rows[0][1]] != ["t", "u", "v"]:
            raise ConfigError(f"{p}: header must be 't,u,v' (seconds, pixels)")
        data, lines = [], []
        for k, r in rows[1:]:
            if len(r) != 3:
                raise ConfigError(f"{p}: line {k}: expected 3 values t,u,v")
            try:
                t = float(r[0])
                u = float(r[1]) if r[1].strip() else np.nan
                v = float(r[2]) if r[2].strip() else np.nan
            except ValueError:
                raise ConfigError(f"{p}: line {k}: non-numeric value in {','.join(r)!r}") from None
            _check_pixel(p, k, u, v, camera)
            data.append((t, u, v))
            lines.append(k)
        if not data:
            raise ConfigError(f"{p}: no image points after the header")
        a = np.array(data)
        if camera is not None:
            _check_reach(p, lines, a[:, 1:], camera)
        if np.any(np.diff(a[:, 0]) <= 0) or not np.all(np.isfinite(a[:, 0])):
            raise ConfigError(f"{p}: times must be finite and strictly increasing")
        self.t, self.uv = a[:, 0], a[:, 1:]
        self.max_gap_s = float(max_gap_s)
        self._seen_t = self.t[np.all(np.isfinite(self.uv), axis=1)]  # times of visible rows

    def __call__(self, t: float) -> tuple[float, float] | None:
        t = _point_time(t)
        k = int(np.searchsorted(self.t, t))
        lo, hi = max(k - 1, 0), min(k, len(self.t) - 1)
        t0, t1 = self.t[lo], self.t[hi]
        p0, p1 = self.uv[lo], self.uv[hi]
        if lo != hi and t1 - t0 <= self.max_gap_s and np.all(np.isfinite(p0)) and np.all(
                np.isfinite(p1)) and t0 <= t <= t1:
            w = (t - t0) / (t1 - t0)
            p = (1 - w) * p0 + w * p1
            return float(p[0]), float(p[1])
        best = lo if abs(t - t0) <= abs(t1 - t) else hi
        if abs(self.t[best] - t) <= self.max_gap_s / 2 and np.all(np.isfinite(self.uv[best])):
            return float(self.uv[best, 0]), float(self.uv[best, 1])
        return None

    def visible_within(self, t_start: float, t_end: float) -> bool:
        """Whether ``points(t)`` can give an image point for some t in ``[t_start, t_end]``:
        a visible row (finite u, v) lies within ``max_gap_s / 2`` of the span (interpolation
        needs two visible rows, the nearer of which is that close)."""
        seen, half = self._seen_t, self.max_gap_s / 2
        return bool(np.any((seen >= t_start - half) & (seen <= t_end + half)))

    def visible_span(self) -> tuple[float, float] | None:
        """Times (s) of the first and last visible rows, or None when no row is visible."""
        seen = self._seen_t
        return (float(seen[0]), float(seen[-1])) if len(seen) else None


def _point_time(t: Any) -> float:
    """``points(t)``'s time as a float (seconds), or a ConfigError unless it is a finite real
    number: text (``"0.1"``) or None let a builtin TypeError escape, and a NaN time compared
    False with every frame time."""
    return finite_number("image-point time t (s)", t)


def _check_pixel(path: Path, line: int, u: float, v: float, camera: Any) -> None:
    """ConfigError naming ``path`` and ``line`` unless the pixel ``(u, v)`` is not visible
    (both NaN: empty cells) or finite and, with ``camera``, within :data:`IMAGE_POINT_MARGIN`
    of its image (:meth:`hearsee.vision.camera.Camera.in_image`). Only one of u and v given
    is an error too (a half-empty row was silently read as "not visible")."""
    if np.isnan(u) and np.isnan(v):
        return
    if np.isnan(u) or np.isnan(v):
        raise ConfigError(f"{path}: line {line}: only one of u and v is given ({u:g}, {v:g}); "
                          "give both, or leave both empty where the source is not visible")
    if not (np.isfinite(u) and np.isfinite(v)):
        raise ConfigError(f"{path}: line {line}: image point ({u:g}, {v:g}) is not a finite "
                          "pixel (leave u and v empty where the source is not visible)")
    if camera is None:
        return
    margin = IMAGE_POINT_MARGIN * max(camera.width, camera.height)
    if not camera.in_image((u, v), margin=-margin)[0]:
        raise ConfigError(
            f"{path}: line {line}: image point ({u:g}, {v:g}) px is outside the calibrated "
            f"{camera.width}x{camera.height} image by more than {margin:g} px (check the "
            "columns, and that the points are of this camera)")


def _check_reach(path: Path, lines: list[int], uv: NDArray, camera: Any) -> None:
    """ConfigError naming ``path`` and the line of the first visible pixel of ``uv`` (n, 2)
    (rows of file ``lines``) that the ``camera``'s lens model gives no ray for
    (:meth:`hearsee.vision.camera.Camera.pixel_rays`: near the corners of an image whose
    radial distortion folds back before them). Such a row was read, and the run then aborted
    at its frame with the camera's GeometryError, which named no file or line."""
    seen = np.flatnonzero(np.all(np.isfinite(uv), axis=1))
    if not len(seen):
        return
    rays = camera.pixel_rays(uv[seen], unreachable="nan")
    lost = seen[~np.all(np.isfinite(rays), axis=1)]
    if len(lost):
        u, v = uv[lost[0]]
        raise ConfigError(
            f"{path}: line {lines[lost[0]]}: image point ({u:g}, {v:g}) px is beyond the "
            "reach of the calibrated camera's lens model: no direction it maps to pixels "
            "projects there (its distortion folds back before it; check the points and the "
            "calibration)")


def save_image_points(path: str | Path, t: NDArray, uv: NDArray) -> None:
    """Write ``t,u,v`` rows (``t`` seconds, ``uv`` ``(n, 2)`` pixels; a NaN pixel -- both of a
    row's, for "not visible" -- becomes an empty cell): the file :class:`CsvImagePoints`
    reads. What it would refuse is a ConfigError here, before anything is written: times
    that are not finite and strictly increasing, rows with one NaN of two, infinite pixels,
    t and uv of different lengths (such files were written and refused only when read)."""
    from hearsee.config import as_float_array, output_file

    tt = as_float_array(t, "image-point times t", error=ConfigError).reshape(-1)
    pts = as_float_array(uv, "image points uv", error=ConfigError, finite=False)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) != len(tt):
        raise ConfigError(f"image points: expected uv (n, 2) for n = {len(tt)} times, got shape "
                          f"{pts.shape}")
    if len(tt) and (not np.all(np.isfinite(tt)) or np.any(np.diff(tt) <= 0)):
        raise ConfigError("image points: times must be finite and strictly increasing")
    for k, (u, v) in enumerate(pts):  # the reader's row rule (line k + 2 of the file to be)
        _check_pixel(Path(path), k + 2, float(u), float(v), None)
    with output_file(path).open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["t", "u", "v"])
        for ti, (u, v) in zip(tt, pts, strict=True):
            w.writerow([f"{ti:.6f}", "" if not np.isfinite(u) else f"{u:.3f}",
                        "" if not np.isfinite(v) else f"{v:.3f}"])


_DETECTORS: dict[str, Any] = {}


def detect_source_point(image: NDArray, detector: str = "hog") -> tuple[float, float] | None:
    """Pixel of a speaking person in a BGR or grey 8-bit image (``(h, w, 1)`` grey and BGRA
    accepted too), or None when nobody is found (also in a frame too small for a person).

    ``detector="hog"``: OpenCV HOG people detector
    (:func:`hearsee.vision.humans.detect_people_hog`, its boxes unshrunk, and its rule for
    frames too small for the detection window), point 12 % down the strongest box (head);
    ``detector="face"``: Haar frontal-face cascade from ``cv2.data``, point 65 % down the
    largest face (mouth).
    """
    import cv2

    from hearsee.vision.humans import detect_people_hog
    from hearsee.vision.io import as_detector_image

    img = as_detector_image(image, "the person detector")  # (cv2.error on other layouts)
    if img.size == 0:
        raise ImageInputError(f"the person detector got an empty image, shape {img.shape}")
    if detector == "hog":
        # the HOG baseline's boxes, unshrunk, and its small-frame rule (no window fits: none)
        boxes = detect_people_hog(img, shrink=False)
        if not boxes:
            return None
        (x, y, w, h), _ = max(boxes, key=lambda b: b[1])  # (the first of equal weights)
        return float(x + w / 2.0), float(y + 0.12 * h)
    if detector == "face":
        casc = _DETECTORS.get("face")
        if casc is None:
            casc = cv2.CascadeClassifier(cv2.data.haarcascades
                                         + "haarcascade_frontalface_default.xml")
            _DETECTORS["face"] = casc
        grey = img if img.ndim == 2 else cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
        faces = casc.detectMultiScale(grey, scaleFactor=1.1, minNeighbors=5)
        if len(faces) == 0:
            return None
        x, y, w, h = faces[int(np.argmax([f[2] * f[3] for f in faces]))]
        return float(x + w / 2.0), float(y + 0.65 * h)
    raise ConfigError(f"unknown detector {detector!r} (choose hog or face)")


def _reported_size(cap: Any) -> tuple[int, int] | None:
    """A capture's ``(width, height)`` in pixels from CAP_PROP_FRAME_WIDTH / HEIGHT, or None
    where either is not a finite number (a driver that does not know)."""
    import cv2

    wh = [cap.get(p) for p in (cv2.CAP_PROP_FRAME_WIDTH, cv2.CAP_PROP_FRAME_HEIGHT)]
    return (int(wh[0]), int(wh[1])) if all(is_real(v) and math.isfinite(v) for v in wh) else None


def _reported_fps(value: Any) -> float | None:
    """A capture's ``CAP_PROP_FPS`` as frames per second when it is a finite number > 0, else
    None (drivers report 0, -1 or NaN for "unknown")."""
    return float(value) if is_real(value) and value > 0 else None


class VideoImagePoints:
    """Image points from a video file or camera via ``cv2.VideoCapture`` + a detector.

    Parameters
    ----------
    source : path or int
        Video file, or camera index for a live camera.
    detector : ``"hog"`` | ``"face"``
        See :func:`detect_source_point`.
    fps : float, optional
        Frame rate override, frames per second > 0 (files whose container lacks it); a file's
        frame k is then at k / fps seconds (its own timestamps are not used).
    expected_size : (width, height), optional
        The calibrated camera's image size in pixels: a video file of another size is refused
        (its image points would be read through the wrong intrinsics). A live camera's driver
        may report its size only once it streams: its frames are checked as they come, and
        ``points(t)`` raises the ImageInputError once one of another size (or one the
        detector cannot take, e.g. 16-bit) has come (its points were used: 800x600 frames
        with a 640x480 calibration put the 3D fixes 1.75 m off, without a word).
    where : str
        Prefix of the error when a video file opens but delivers no frame (a corrupt or
        truncated file; :func:`read_frame`, the check of ``hearsee run --dry-run`` too), e.g.
        ``"--video"``. The first frame is read when the object is made, before any audio is,
        and kept for ``points(t)``. (A still image that OpenCV opens, e.g. a PNG, passes: a
        one-frame video.) A live camera is not read here: its thread does.

    A file's frames are timed by :class:`FileFrameClock` (their timestamps, which keep the
    gaps of dropped frames); ``frame_index`` counts the frames shown (from 0) and
    ``frame_time`` is the shown frame's time in seconds.
    """

    def __init__(self, source: str | Path | int, detector: str = "hog",
                 fps: float | None = None,
                 expected_size: tuple[int, int] | None = None, where: str = "video file") -> None:
        import cv2

        from hearsee.vision.io import video_capture

        if detector not in ("hog", "face"):
            raise ConfigError(f"unknown detector {detector!r} (choose hog or face)")
        if fps is not None:  # (inf gave no image point ever; NaN/negative: 'pass fps=')
            fps = finite_number("fps", fps, 0.0, lo_open=True)
        self.live = isinstance(source, int) and not isinstance(source, bool)
        if self.live:  # (OpenCV's "any camera" -1 crashed the process: a segmentation fault)
            source = whole_number("camera index", source, 0)
        else:
            input_file(source, "video file")
        what = f"camera {source}" if self.live else f"{source}"
        cap = video_capture(int(source) if self.live else str(source))
        if not cap.isOpened():
            raise ImageInputError(f"{what}: cannot be opened as a video (OpenCV VideoCapture)")
        # a file's size against the calibration (a live camera's is not checked here: a driver
        # may report no size, and NaN made int() a builtin ValueError; a file's missing size is
        # its first frame's)
        size = None if self.live else _reported_size(cap)
        if expected_size is not None and size is not None and size != tuple(expected_size):
            cap.release()
            raise ImageInputError(
                f"{what}: frames are {size[0]}x{size[1]} pixels but the calibration expects "
                f"{expected_size[0]}x{expected_size[1]} (use the calibrated camera's video)")
        rate = fps or _reported_fps(cap.get(cv2.CAP_PROP_FPS))
        if not self.live and rate is None:
            cap.release()
            raise ImageInputError(f"{source}: video has no frame rate; pass fps=")
        # (a live camera's driver may report no rate, 0, -1 or NaN: 30 frames/s then; a NaN
        # rate made its image point never go stale when the camera hung)
        self.cap, self.fps, self.detector = cap, float(rate or 30.0), detector
        # a file's timestamps, unless fps overrides them
        self._frame_clock = FileFrameClock(self.fps) if fps is None and not self.live else None
        self._next: tuple[NDArray, float] | None = None  # a file's frame read ahead, its time
        if not self.live:
            # (a corrupt or truncated file opened, delivered nothing, and the run went on
            # audio-only without a word): the dry-run's check, before the audio is read
            try:
                first = read_frame(cap, str(source), where,
                                   expected_size if size is None else None)
            except ConfigError:
                cap.release()
                raise
            self._next = (first, self._time_of(0))
        self.frame_index = -1
        self.frame_time = -np.inf
        self.last_point: tuple[float, float] | None = None
        self._thread = None
        self.ended = False
        self._what = what
        self._expected = None if expected_size is None else tuple(int(n) for n in expected_size)
        self._error: ImageInputError | None = None  # live: a frame of another size came
        self._clock = time.perf_counter  # live camera: wall clock (s) of the frames' ages
        self._frame_wall = -np.inf  # live: wall-clock time of the latest detection
        self._cycle = 0.0  # live: wall-clock seconds between the last two detections

    def _time_of(self, index: int) -> float:
        """Time (s) of the file's frame just read, its ``index``-th (:class:`FileFrameClock`;
        ``index / fps`` with an explicit fps)."""
        if self._frame_clock is not None:
            return self._frame_clock(self.cap)
        return index / self.fps

    def _peek(self) -> tuple[NDArray, float] | None:
        """A file's next frame and its time (s), read ahead once and kept until shown; None
        (and ``ended``) when the file has no more."""
        if self._next is None and not self.ended:
            ok, frame = self.cap.read()
            if not ok or frame is None:
                self.ended = True
                return None
            self._next = (frame, self._time_of(self.frame_index + 1))
        return self._next

    def _advance(self, t: float) -> bool:
        """Show a file's next frame when it is nearer ``t`` (s) than the shown one (the
        earlier at a tie; the first frame always); whether it did."""
        if self.frame_index >= 0 and not t > self.frame_time:
            return False  # (frames only come later: the shown one is the nearest)
        nxt = self._peek()
        if nxt is None or (self.frame_index >= 0 and not (self.frame_time + nxt[1]) / 2 < t):
            return False
        self._frame, self.frame_time = nxt
        self._next = None
        self.frame_index += 1
        return True

    def _live_loop(self) -> None:
        """Live camera: grab frames continuously in a thread, keep the latest detection."""
        t0 = self._clock()
        while not self._stop.is_set():
            ok, frame = self.cap.read()
            if not ok or frame is None:
                with self._lock:
                    self.ended = True
                return
            try:
                size = (frame.shape[1], frame.shape[0])
                if self._expected is not None and size != self._expected:
                    raise ImageInputError(
                        f"delivers {size[0]}x{size[1]} frames but the calibration expects "
                        f"{self._expected[0]}x{self._expected[1]} (use the calibrated camera, "
                        "at its resolution)")
                pt = detect_source_point(frame, self.detector)
            except ImageInputError as exc:  # (a 16-bit camera's frame: the detector's error
                # was a traceback of this thread, and the run went on direction-only)
                with self._lock:
                    self._error = ImageInputError(f"{self._what}: {exc}")
                    self.ended = True
                return
            now = self._clock()
            with self._lock:
                if self.frame_index >= 0:
                    self._cycle = now - self._frame_wall
                self.frame_index += 1
                self.frame_time = now - t0
                self._frame_wall = now
                self.last_point = pt

    def __call__(self, t: float) -> tuple[float, float] | None:
        t = _point_time(t)
        if self.live:
            if self._thread is None:
                import threading

                self._stop = threading.Event()
                self._lock = threading.Lock()
                self._thread = threading.Thread(target=self._live_loop, daemon=True,
                                                name="hearsee-camera")
                self._thread.start()
            with self._lock:
                if self._error is not None:
                    raise self._error
                period = max(1.0 / self.fps, self._cycle)
                if self.ended or self._clock() - self._frame_wall > 2.0 * period:
                    return None  # the camera has stopped: no current image of the source
                return self.last_point
        fresh = False
        # the frame nearest t (the earlier one at a tie); the latest frame at or before t was
        # on average half a frame period old, which a moving talker's camera-ray fix turned
        # into a range error (about 9 cm at 30 fps, 1 m/s, camera 0.2 m aside; an audit)
        while self._advance(t):
            fresh = True
        if fresh:
            self.last_point = detect_source_point(self._frame, self.detector)
        if self.frame_index < 0 or abs(self.frame_time - t) > 2.0 / self.fps:
            return None
        return self.last_point

    def close(self) -> None:
        if self._thread is not None:
            self._stop.set()
            self._thread.join(timeout=1.0)
            if self._thread.is_alive():  # blocked in a read: releasing under it is not safe
                return  # (a daemon thread; see TimedCapture)
        self.cap.release()
