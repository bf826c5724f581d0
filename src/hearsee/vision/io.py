"""Reading and checking images (visible, stereo pairs, thermal) with clear errors.

Every reader raises :class:`hearsee.errors.InputFileError` for a missing file and
:class:`hearsee.errors.ImageInputError` for a file OpenCV cannot decode, an image of the wrong
size or type, or a left/right pair that does not match. Images follow OpenCV conventions:
``(height, width)`` or ``(height, width, 3)`` numpy arrays, BGR channel order.
"""

from __future__ import annotations

import glob
import re
import threading
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Literal

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from hearsee.config import input_file, open_replaced, output_file, real_entries, replacing
from hearsee.errors import (
    CalibrationError,
    ConfigError,
    DegenerateInputWarning,
    ImageInputError,
    InputFileError,
)

__all__ = [
    "as_detector_image",
    "check_image",
    "check_pair",
    "glob_images",
    "image_size",
    "read_image",
    "read_pair",
    "read_thermal",
    "to_8_bits",
    "to_gray",
    "video_capture",
    "write_image",
]

ColorMode = Literal["gray", "bgr", "unchanged"]

#: OpenCV's decoding flags of each read mode. None of them applies a JPEG's EXIF orientation
#: tag ("unchanged" never does): "gray" and "bgr" rotated such a file and "unchanged" (so
#: read_thermal) did not, so calibration (grey) and detection saw the same file 90 or 180 deg
#: apart. Pixels are taken as stored.
_IMREAD = {
    "gray": cv2.IMREAD_GRAYSCALE | cv2.IMREAD_IGNORE_ORIENTATION,
    "bgr": cv2.IMREAD_COLOR | cv2.IMREAD_IGNORE_ORIENTATION,
    "unchanged": cv2.IMREAD_UNCHANGED,
}


def video_capture(source: int | str) -> cv2.VideoCapture:
    """``cv2.VideoCapture(source)`` (a camera index, a file, a URL) with OpenCV's own log
    silenced while it opens (errors too for a camera index): a camera that is not there printed
    two ``[ WARN ]`` lines of its backends (V4L2, FFMPEG) on stderr before hearsee's one-line
    message, and OpenCV 4.8 and 4.10 also two ``[ERROR:0@...] global
    obsensor_uvc_stream_channel.cpp ... Camera index out of range`` lines of their Orbbec
    backend, which probes every index (until 2026-12-03 the log was only lowered to errors).
    The caller checks ``isOpened()`` and reports a failure itself. An index beyond a C int
    gives a capture that is not opened (OpenCV's own TypeError, a traceback, for
    ``--camera-device 99999999999999999999`` or ``cameras.left: 99999999999999999999``
    before), so that the caller's "cannot open" names it.
    A negative index or a bool is a ConfigError (OpenCV's "any camera" -1 ended the
    interpreter with a segmentation fault where no camera backend answered; True was a raw
    cv2.error). A file or URL opens with the process's stderr silenced too
    (:func:`_codec_stderr_off`): FFmpeg printed "[mov,mp4,... @ 0x...] moov atom not found"
    there before hearsee's one line on a corrupt or truncated video."""
    if isinstance(source, bool) or (isinstance(source, int | np.integer) and source < 0):
        raise ConfigError(f"camera index must be a whole number >= 0, got {source!r}")
    if isinstance(source, int | np.integer):
        if source >= 2**31:
            return cv2.VideoCapture()
        with _opencv_log("silent"):
            return cv2.VideoCapture(int(source))
    with _opencv_log("error"), _codec_stderr_off():
        return cv2.VideoCapture(source)


@contextmanager
def _opencv_log(level: str) -> Iterator[None]:
    """OpenCV's own log at ``level`` (``"error"``: its warnings off; ``"silent"``: all off)
    for the block, restored after it: messages hearsee reports as its own error, or that
    would precede it."""
    get, set_ = opencv_log_functions()
    before = get()
    set_({"error": 2, "silent": 0}[level])  # (OpenCV's LOG_LEVEL_ERROR, LOG_LEVEL_SILENT)
    try:
        yield
    finally:
        set_(before)


def opencv_log_functions() -> tuple[Callable[[], int], Callable[[int], None]]:
    """OpenCV's (get, set) of its log level (0 silent, 2 error, 3 warning, ...): the Python
    API is ``cv2.utils.logging`` in recent releases and ``cv2.getLogLevel`` /
    ``cv2.setLogLevel`` in older ones such as 4.8 and 4.11 (pyproject's lower bound), which have no
    ``cv2.utils.logging`` (every image read was a ModuleNotFoundError there)."""
    try:
        import cv2.utils.logging as cv_log

        return cv_log.getLogLevel, cv_log.setLogLevel
    except ImportError:
        import cv2

        return cv2.getLogLevel, cv2.setLogLevel


#: The state of :func:`_codec_stderr_off`, shared by every thread: its lock, how many blocks
#: are inside it, and the descriptor of the process's stderr it restores when the last ends.
_STDERR_OFF: dict = {"lock": threading.Lock(), "depth": 0, "saved": None}


@contextmanager
def _codec_stderr_off() -> Iterator[None]:
    """The process's stderr (file descriptor 2) sent to the null device for the block: the
    image codecs under OpenCV write their messages there directly, past OpenCV's log level
    (libpng's "libpng error: ...", libjpeg's "Corrupt JPEG data: ..."; measured with
    OpenCV 4.14 and its log silent). Python's own ``sys.stderr`` is flushed first; where
    descriptor 2 cannot be redirected the block runs as is.

    Descriptor 2 belongs to the process, not to a thread, so blocks of several threads share
    one redirection: the first to enter redirects, the last to leave restores. (Until
    2026-12-02 each block saved and restored descriptor 2 itself: two reads in two threads,
    the second starting while the first decoded, saved the null device as "stderr" and put
    it back last -- the process's stderr stayed silenced for good.) What it cannot avoid:
    while any thread is inside, whatever else the process writes to descriptor 2 -- another
    thread's ``sys.stderr`` output, a C library's message -- goes to the null device too."""
    import os
    import sys

    state = _STDERR_OFF
    with state["lock"]:
        if state["depth"] == 0:
            try:
                sys.stderr.flush()
                saved = os.dup(2)
            except (OSError, ValueError, AttributeError):
                saved = None
            if saved is not None:
                try:
                    null = os.open(os.devnull, os.O_WRONLY)
                    try:
                        os.dup2(null, 2)
                    finally:
                        os.close(null)
                except OSError:
                    os.close(saved)
                    saved = None
            state["saved"] = saved
        state["depth"] += 1
    try:
        yield
    finally:
        with state["lock"]:
            state["depth"] -= 1
            if state["depth"] == 0 and state["saved"] is not None:
                os.dup2(state["saved"], 2)
                os.close(state["saved"])
                state["saved"] = None


def numeric_map(name: str, value: ArrayLike, dtype: type | None = np.float64, *,
                copy: bool = False, finite: bool = False) -> NDArray:
    """``value`` (an image-shaped map: disparities, temperatures, counts, a mask, points) as an
    array of ``dtype`` (None: its own; a copy with ``copy``) when it holds real numbers
    (:func:`hearsee.config.real_entries`), else an ImageInputError naming it: numpy read a map
    of text as numbers, True as 1, and raised its builtin ValueError on a ragged list. An array
    of numbers costs one dtype test. With ``finite``, NaN or inf entries are an ImageInputError
    too (for maps where they mean nothing: counts, filter responses, heights). The "numbers
    only" rule of :mod:`hearsee.vision`'s map functions."""
    if not real_entries(value):
        got = value.dtype if isinstance(value, np.ndarray) else f"{value!r:.60}"
        raise ImageInputError(f"{name} must hold numbers, got {got}")
    out = np.array(value, dtype=dtype, copy=True) if copy else np.asarray(value, dtype=dtype)
    if finite and out.dtype.kind == "f" and not np.all(np.isfinite(out)):
        raise ImageInputError(f"{name} must hold finite numbers, got NaN or inf entries")
    return out


def bool_mask(mask: ArrayLike, name: str = "mask") -> NDArray:
    """``mask`` as a bool (H, W) array, or an ImageInputError naming it unless it is one of
    bools or numbers (numpy took a mask of text as all True; a ragged list was its builtin
    ValueError). The mask check of :mod:`hearsee.vision` (silhouettes, warm-pixel masks)."""
    try:
        m = np.asarray(mask)
    except (TypeError, ValueError):  # (a ragged list)
        raise ImageInputError(f"{name} must be a bool silhouette (H, W), got {mask!r:.60}"
                              ) from None
    if m.dtype.kind not in "biuf":
        raise ImageInputError(f"{name} must be a bool silhouette, got {m.dtype}")
    if m.ndim != 2:
        raise ImageInputError(f"{name} must be a bool silhouette (H, W), got shape {m.shape}")
    return m.astype(bool, copy=False)


def _size_text(size: tuple[int, int]) -> str:
    return f"{size[0]}x{size[1]}"


def image_size(size: Any, what: str = "expected_size") -> tuple[int, int]:
    """``size`` as ``(width, height)`` in pixels, two ints, by the camera's image-size rule
    (:func:`hearsee.vision.camera.check_size`: whole numbers > 0), else a CalibrationError
    naming ``what`` (a 1-tuple raised IndexError, a bare number TypeError)."""
    from hearsee.vision.camera import check_size

    try:
        w, h = size
    except (TypeError, ValueError):
        raise CalibrationError(f"{what} must be (width, height) in pixels, got {size!r:.60}"
                               ) from None
    return check_size(w, h, what)


def check_image(image: NDArray, name: str = "image",
                expected_size: tuple[int, int] | None = None) -> NDArray:
    """Validate an image array: 2-D or 3-D with 1, 3 or 4 channels, non-empty, numeric, finite.

    ``expected_size`` is ``(width, height)`` in pixels (OpenCV order; :func:`image_size`).
    Returns the array.
    """
    if expected_size is not None:
        expected_size = image_size(expected_size)
    if not isinstance(image, np.ndarray):
        raise ImageInputError(f"{name}: expected a numpy image array, got {type(image).__name__}")
    if image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] not in (1, 3, 4)):
        raise ImageInputError(
            f"{name}: expected an (H, W) or (H, W, 1|3|4) image, got shape {image.shape}"
        )
    if image.shape[0] == 0 or image.shape[1] == 0:
        raise ImageInputError(f"{name}: image is empty (shape {image.shape})")
    if image.dtype.kind not in "uif" or image.dtype == np.bool_:
        raise ImageInputError(f"{name}: unsupported pixel type {image.dtype}")
    if image.dtype.kind == "f" and not np.all(np.isfinite(image)):
        raise ImageInputError(f"{name}: image contains NaN or infinite values")
    if expected_size is not None:
        w, h = image.shape[1], image.shape[0]
        if (w, h) != tuple(expected_size):
            raise ImageInputError(
                f"{name}: image is {w}x{h} pixels but the calibration expects "
                f"{_size_text(expected_size)} (resize the image or recalibrate)"
            )
    return image


def check_pair(left: NDArray, right: NDArray, names: tuple[str, str] = ("left", "right"),
               expected_size: tuple[int, int] | None = None) -> tuple[NDArray, NDArray]:
    """Validate a stereo pair: both valid images of the same size and channel count."""
    check_image(left, names[0], expected_size)
    check_image(right, names[1], expected_size)
    if left.shape[:2] != right.shape[:2]:
        raise ImageInputError(
            f"{names[0]} and {names[1]} images differ in size "
            f"({left.shape[1]}x{left.shape[0]} vs {right.shape[1]}x{right.shape[0]}); "
            "a stereo pair must come from the same rig at the same resolution"
        )
    if left.ndim != right.ndim or (left.ndim == 3 and left.shape[2] != right.shape[2]):
        raise ImageInputError(
            f"{names[0]} and {names[1]} images differ in channels ({left.shape} vs {right.shape})"
        )
    return left, right


def read_image(path: str | Path, mode: ColorMode = "gray",
               expected_size: tuple[int, int] | None = None) -> NDArray:
    """Read an image file.

    Parameters
    ----------
    path : file name (any format OpenCV decodes: PNG, JPEG, TIFF, PGM, ...).
    mode : "gray" (uint8 (H, W)), "bgr" (uint8 (H, W, 3)) or "unchanged" (bit depth and
        channels as stored, e.g. 16-bit PGM/PNG). In every mode the pixels are those stored:
        a JPEG's EXIF orientation tag is not applied, nor a TIFF's Orientation tag (which
        OpenCV applies: undone, :func:`_tiff_as_stored`). A 16-bit file read as "gray" or "bgr"
        keeps its 8 most significant bits in use (:func:`to_8_bits`: a 12-bit camera's
        0-4095 shifted right by 4); OpenCV's own conversion kept the top 8 of 16 bits, which
        left a 10- or 12-bit image nearly black.
    expected_size : (width, height) in pixels, checked when given.

    A file OpenCV cannot decode is one ImageInputError and nothing else: OpenCV's log and
    the codecs' own messages on stderr are silenced while it decodes. The codecs (libpng,
    libjpeg) write to the process's file descriptor 2 directly -- OpenCV's log level
    (``cv2.utils.logging``) does not reach them, and decoding bytes with ``cv2.imdecode``
    (as here) prints them too -- so descriptor 2 is pointed at the null device for the
    decode (a few milliseconds). Limitation: descriptor 2 is the whole process's, so
    anything another thread writes to stderr during a decode is lost; concurrent reads are
    safe (they share the redirection, and stderr is restored when the last one ends).
    """
    img, p = _decode(path, mode)
    return check_image(img if mode == "unchanged" else to_8_bits(img)[0], str(p), expected_size)


def to_8_bits(*images: NDArray) -> tuple[NDArray, ...]:
    """``images`` as uint8, the 16-bit ones shifted right by as many bits as their largest
    value needs beyond 8 -- one shift for all of them, so the two views of a stereo pair keep
    the same gain (a 12-bit pair: >> 4 on both, whatever each one's brightest pixel). 8-bit
    images come back as they are; 8-bit values in a 16-bit file are not shifted. Anything
    but numpy arrays is an ImageInputError (None was an AttributeError)."""
    for im in images:
        if not isinstance(im, np.ndarray):
            raise ImageInputError(f"to_8_bits: expected image arrays, got {type(im).__name__}")
    deep = [im for im in images if im.dtype == np.uint16]
    top = max((int(im.max(initial=0)) for im in deep), default=0)
    shift = max(top.bit_length() - 8, 0)
    return tuple((im >> shift).astype(np.uint8) if im.dtype == np.uint16 else im
                 for im in images)


def _decode(path: str | Path, mode: ColorMode) -> tuple[NDArray, Path]:
    """(the image file ``path`` decoded in ``mode`` (:func:`read_image`), its checked path):
    "gray" and "bgr" keep a 16-bit file's depth (OpenCV's ANYDEPTH: uint8 or uint16)."""
    if mode not in _IMREAD:
        raise ImageInputError(f"mode must be one of {', '.join(_IMREAD)}, got {mode!r}")
    p = input_file(path, "image file")
    try:
        data = np.fromfile(str(p), dtype=np.uint8)
    except OSError as exc:
        raise InputFileError(f"{p}: cannot read file ({exc.strerror})") from None
    # (OpenCV's log and the codecs' own messages silenced: a truncated PNG printed a
    # "[ WARN ]" or a "libpng error" line, a truncated TIFF two "[ERROR]" lines, on stderr
    # before hearsee's one-line error below)
    flags = _IMREAD[mode] if mode == "unchanged" else _IMREAD[mode] | cv2.IMREAD_ANYDEPTH
    img = _imdecode(data, flags, p) if data.size else None
    if img is None and mode != "unchanged" and data.size:
        # (a float TIFF decodes in colour only as it is stored: named below, not "corrupt")
        raw = _imdecode(data, cv2.IMREAD_UNCHANGED, p)
        img = raw if raw is not None and raw.dtype not in (np.uint8, np.uint16) else None
    if img is None:
        raise ImageInputError(
            f"{p}: not a readable image (corrupt or unsupported format; expected PNG, JPEG, "
            "TIFF or PGM)"
        )
    if mode != "unchanged" and img.dtype not in (np.uint8, np.uint16):
        # (a float TIFF: "corrupt or unsupported format" before ANYDEPTH, now its own words)
        kind = "floating-point" if img.dtype.kind == "f" else f"{img.dtype.itemsize * 8}-bit"
        raise ImageInputError(
            f"{p}: holds {kind} pixels ({img.dtype}; a thermal or depth image?), which a "
            f"{mode} image cannot take: give an 8- or 16-bit image")
    if mode == "unchanged":
        _check_tiff_kept(p, data, img)
    return _tiff_as_stored(data, img), p


def _imdecode(data: NDArray, flags: int, p: Path) -> NDArray | None:
    """``cv2.imdecode`` of the bytes ``data`` of the file ``p`` with OpenCV's log and the
    codecs' stderr off (:func:`read_image`); None when OpenCV cannot decode them, an
    ImageInputError naming ``p`` when it refuses to, where imdecode raised cv2.error -- a
    traceback: an OpenEXR file (the codec is built into OpenCV's wheels but disabled) or a
    header claiming more pixels than OpenCV's limit (``CV_IO_MAX_IMAGE_PIXELS``, 2**30 by
    default)."""
    with _opencv_log("silent"), _codec_stderr_off():
        try:
            return cv2.imdecode(data, flags)
        except cv2.error as exc:
            why = str(exc.err).split(" Refer for details")[0].strip()
            if "OpenEXR" in why:
                hint = ("; convert it to TIFF or, for a thermal image in degC, .npy")
            elif "CV_IO_MAX_IMAGE_PIXELS" in why:
                why, hint = ("its header claims more pixels than OpenCV's limit, "
                             "CV_IO_MAX_IMAGE_PIXELS"), ""
            else:
                hint = ""
            raise ImageInputError(f"{p}: OpenCV cannot decode this image ({why}){hint}") \
                from None


def _check_tiff_kept(p: Path, data: NDArray, img: NDArray) -> None:
    """ImageInputError when ``data`` is a TIFF whose first image has more samples per pixel
    or more bits per sample than OpenCV's decoding ``img`` kept: a 16-bit 2-channel TIFF (e.g.
    radiometric counts and a second plane) came back as one 8-bit channel without a word."""
    layout = _tiff_layout(data)
    if layout is None:
        return
    samples, bits = layout
    channels = 1 if img.ndim == 2 else img.shape[2]
    if samples > channels or bits > 8 * img.dtype.itemsize:
        raise ImageInputError(
            f"{p}: a TIFF of {samples} channel(s) of {bits} bits that OpenCV reads as "
            f"{channels} channel(s) of {img.dtype}: its values would not be kept; save it "
            "with 1, 3 or 4 channels (e.g. one 16-bit plane per file)")


#: How to undo the Orientation (TIFF tag 274) of a TIFF that OpenCV's TIFF decoder applied
#: to its pixels, by orientation: flips and turns of the (rows, columns) axes.
_UNDO_TIFF_ORIENTATION: dict[int, Callable[[NDArray], NDArray]] = {
    2: lambda a: a[:, ::-1],  # (mirrored left-right)
    3: lambda a: a[::-1, ::-1],  # (turned 180 deg)
    4: lambda a: a[::-1],  # (mirrored top-bottom)
    5: lambda a: a.swapaxes(0, 1),  # (transposed)
    6: lambda a: np.rot90(a, 1),  # (turned 90 deg clockwise)
    7: lambda a: a.swapaxes(0, 1)[::-1, ::-1],  # (transposed across the other diagonal)
    8: lambda a: np.rot90(a, -1),  # (turned 90 deg counter-clockwise)
}


def _tiff_as_stored(data: NDArray, img: NDArray) -> NDArray:
    """``img``, OpenCV's decoding of the file ``data``, with its pixels as stored: OpenCV's
    TIFF decoder turns or mirrors the image by the file's Orientation tag whatever the read
    flags (IMREAD_IGNORE_ORIENTATION and IMREAD_UNCHANGED too; measured with OpenCV 4.14),
    so a TIFF tagged e.g. 3 (180 deg) came back turned where a JPEG with the same EXIF tag
    did not (:data:`_IMREAD`). Other files come back as they are."""
    tags = _tiff_tags(data, {274: 1})  # Orientation
    undo = None if tags is None else _UNDO_TIFF_ORIENTATION.get(tags[274])
    return img if undo is None else np.ascontiguousarray(undo(img))


def _tiff_layout(data: NDArray) -> tuple[int, int] | None:
    """(samples per pixel, bits per sample) of the first image of the TIFF file ``data``
    (uint8 bytes), from its first IFD (TIFF 6.0 defaults: 1 and 1); None when ``data`` is
    not a classic TIFF or the directory cannot be read."""
    found = _tiff_tags(data, {277: 1, 258: 1})  # SamplesPerPixel, BitsPerSample
    return None if found is None else (found[277], found[258])


def _tiff_tags(data: NDArray, defaults: dict[int, int]) -> dict[int, int] | None:
    """The first values of the SHORT or LONG tags ``defaults`` names (tag: its value when the
    file has none) in the first IFD of the TIFF file ``data`` (uint8 bytes); None when
    ``data`` is not a classic TIFF or the directory cannot be read."""
    import struct

    order = {b"II*\x00": "<", b"MM\x00*": ">"}.get(data[:4].tobytes())
    if order is None:
        return None
    try:
        (ifd,) = struct.unpack(order + "I", data[4:8].tobytes())
        (n,) = struct.unpack(order + "H", data[ifd:ifd + 2].tobytes())
        found = dict(defaults)
        for k in range(n):
            entry = data[ifd + 2 + 12 * k:ifd + 14 + 12 * k].tobytes()
            tag, kind, count = struct.unpack(order + "HHI", entry[:8])
            size = {3: 2, 4: 4}.get(kind)  # SHORT, LONG
            if tag not in found or size is None:
                continue
            if count * size > 4:  # the values elsewhere: the first one is enough
                (at,) = struct.unpack(order + "I", entry[8:12])
                raw = data[at:at + size].tobytes()
            else:
                raw = entry[8:8 + size]
            (found[tag],) = struct.unpack(order + ("H" if size == 2 else "I"), raw)
    except struct.error:  # (a directory cut short: OpenCV decoded what it could)
        return None
    return found


def read_pair(left: str | Path, right: str | Path, mode: ColorMode = "gray",
              expected_size: tuple[int, int] | None = None) -> tuple[NDArray, NDArray]:
    """Read a stereo pair and check that both images have the same size (and
    ``expected_size`` = (width, height) when given), and that they are two views: the same
    file twice (or a copy) gave zero disparity everywhere, "no human" without a word."""
    (L, lp), (R, rp) = (_decode(p, mode) for p in (left, right))
    if mode != "unchanged":  # (one shift for both views: the same gain)
        L, R = to_8_bits(L, R)
    check_image(L, str(lp))
    check_image(R, str(rp))
    names = (str(left), str(right))
    check_pair(L, R, names)  # (sizes that differ first, then the calibration's size)
    check_pair(L, R, names, expected_size)
    if np.array_equal(L, R):  # (two cameras' images always differ, by their noise at least)
        raise ImageInputError(f"{left} and {right} are the same image; a stereo pair needs the "
                              "left and the right camera's views")
    for im, name in ((L, left), (R, right)):
        if _two_levels(im):  # (a 1-bit PNG gave a false human without a word)
            warnings.warn(f"{name} holds only two grey levels (a binary image, e.g. a 1-bit "
                          "PNG): stereo matching and the head-shoulder template need the "
                          "camera's grey levels, so the detections may be false",
                          DegenerateInputWarning, stacklevel=2)
    return L, R


def _two_levels(image: NDArray) -> bool:
    """Whether ``image`` holds at most two distinct values (over all its channels)."""
    lo, hi = image.min(), image.max()  # (non-empty: check_image)
    return not np.any((image != lo) & (image != hi))


#: Pixel types OpenCV converts from colour to grey (cv2.cvtColor).
_COLOR_DTYPES = (np.uint8, np.uint16, np.float32)


def to_gray(image: NDArray, name: str = "image") -> NDArray:
    """Single-channel view of an image (BGR/BGRA -> gray by OpenCV's weights; 1 channel kept).

    Colour images must be uint8, uint16 or float32 (what OpenCV converts): other pixel types
    raise ImageInputError naming the type; single-channel images of any type are kept. The
    image is checked first (:func:`check_image`, its messages naming ``name``).
    """
    check_image(image, name)
    if image.ndim == 2:
        return image
    if image.shape[2] == 1:
        return image[:, :, 0]
    if image.dtype not in _COLOR_DTYPES:
        raise ImageInputError(
            f"unsupported pixel type {image.dtype} for a {image.shape[2]}-channel image: colour "
            "images must be uint8, uint16 or float32 (convert it, or pass one grey channel)"
        )
    if image.shape[2] == 4:
        return cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY)
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def as_detector_image(image: NDArray, what: str = "image") -> NDArray:
    """``image`` in the layout OpenCV's detectors (HOG, Haar cascades) and 8-bit video take:
    uint8 grey ``(H, W)`` or BGR ``(H, W, 3)``; ``(H, W, 1)`` is read as grey and BGRA loses its
    alpha. Any other pixel type or channel count is an ImageInputError naming ``what`` (OpenCV
    raised cv2.error or crashed; a ragged list was numpy's ValueError). The size is not
    checked."""
    img = numeric_map(what, image, None)
    if img.dtype != np.uint8 or img.ndim not in (2, 3) or \
            (img.ndim == 3 and img.shape[2] not in (1, 3, 4)):
        raise ImageInputError(
            f"{what} needs an 8-bit grey, BGR or BGRA image, got shape {img.shape} {img.dtype}"
        )
    if img.ndim == 3 and img.shape[2] == 1:
        return img[:, :, 0]
    if img.ndim == 3 and img.shape[2] == 4:
        return np.ascontiguousarray(img[:, :, :3])
    return img


#: A colour thermal file is a grey image when its channels differ by at most this fraction of
#: its pixel type's full scale (a float file: of its value range) -- a grey export's JPEG or
#: colour-cast noise; a false-colour palette (iron, rainbow, JET) differs by far more.
GREY_CHANNEL_TOLERANCE = 0.02
#: ... and it is a false-colour image when more than this share of its pixels differ by more:
#: a grey export with a coloured overlay (a crosshair, a temperature label, a scale bar) is
#: still a grey image, a palette colours most of the picture.
FALSE_COLOUR_SHARE = 0.05


def read_thermal(path: str | Path, expected_size: tuple[int, int] | None = None) -> NDArray:
    """Read a thermal image as a single channel, keeping its bit depth.

    8-bit files (non-radiometric, AGC-normalised; colour files that replicate one grey channel
    are reduced to it) come back as uint8; 16-bit files (raw radiometric counts) as uint16;
    float TIFFs (e.g. degrees Celsius) as float32. Converting counts to temperature is the
    thermal filter's business (:mod:`hearsee.vision.thermal`).

    A colour file whose channels differ by more than :data:`GREY_CHANNEL_TOLERANCE` in more
    than :data:`FALSE_COLOUR_SHARE` of its pixels (a false-colour palette export) is an
    ImageInputError: its luminance is not monotonic in temperature (JET's hottest pixels are
    darker than its warm ones); nearly grey colour files, and grey ones with a small coloured
    overlay, are converted to grey as before.
    """
    img = read_image(path, "unchanged", expected_size)
    if img.ndim == 3:
        chans = img[:, :, :3] if img.shape[2] >= 3 else img
        if img.dtype == np.uint8 or img.dtype == np.uint16:
            if chans.ndim == 3 and np.array_equal(chans[:, :, 0], chans[:, :, 1]) and \
                    np.array_equal(chans[:, :, 0], chans[:, :, 2]):
                return np.ascontiguousarray(chans[:, :, 0])
        if chans.shape[2] == 3:
            _refuse_false_colour(chans, path)
        img = to_gray(img)
    return img


def _refuse_false_colour(chans: NDArray, path: str | Path) -> None:
    """ImageInputError naming ``path`` when the three channels ``chans`` (H, W, 3) differ by
    more than :data:`GREY_CHANNEL_TOLERANCE` of the full scale in more than
    :data:`FALSE_COLOUR_SHARE` of the pixels: a false-colour thermal image, whose grey
    conversion was silently used as temperatures before. (The largest difference alone refused
    a grey export with a coloured crosshair or label.)"""
    c = chans.astype(np.float64)
    spread = np.max(np.stack([np.abs(c[:, :, i] - c[:, :, j])
                              for i, j in ((0, 1), (0, 2), (1, 2))]), axis=0)  # (H, W)
    if chans.dtype.kind in "iu":
        scale = float(np.iinfo(chans.dtype).max)
    else:
        scale = float(np.max(c) - np.min(c))
    share = float(np.mean(spread > GREY_CHANNEL_TOLERANCE * scale))
    if share > FALSE_COLOUR_SHARE:
        raise ImageInputError(
            f"{path}: a colour thermal image ({share:.0%} of its pixels have channels that "
            f"differ by more than {GREY_CHANNEL_TOLERANCE:.0%} of {scale:g}): a false-colour "
            "palette is not a temperature scale; export the thermal image in grey, as "
            "radiometric 16-bit counts or as float degC")


def check_image_writable(path: str | Path, like: NDArray | None = None) -> Path:
    """``path`` as a Path when OpenCV has an encoder for its suffix -- and, given ``like`` (a
    small image of the pixel type and channels to be written), one that holds such an image
    as :func:`write_image` requires -- else an ImageInputError naming it: checked before the
    work whose image it will hold (:func:`write_image` refuses it only then: an 8-bit colour
    overlay as .pgm, .pbm, .hdr or .pfm). A codec OpenCV builds but disables (OpenEXR in its
    wheels) made ``cv2.haveImageWriter`` raise cv2.error after its own "[ WARN ]" line: a
    traceback."""
    p = Path(path)
    with _opencv_log("silent"):
        try:
            writable = cv2.haveImageWriter(str(p))
        except cv2.error:
            writable = False
    if not writable:
        kind = p.suffix or "a file without a suffix"
        raise ImageInputError(f"{p}: OpenCV cannot write {kind}; use an image suffix such as "
                              ".png or .jpg")
    if like is not None:
        _encoded(p, like)
    return p


def _encoded(p: Path, image: NDArray) -> NDArray:
    """``image`` encoded in the format of ``p``'s suffix (.png without one): the bytes, or an
    ImageInputError when OpenCV cannot encode it or the file would not read back with the
    image's pixel type (see :func:`write_image`)."""
    suffix = p.suffix or ".png"
    with _opencv_log("silent"):  # (its "fallbacked to CV_8U" warning; the error below says it)
        try:
            ok, buf = cv2.imencode(suffix, image)
        except cv2.error:  # e.g. no encoder for the suffix: OpenCV raises rather than returns
            ok = False
        back = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED) if ok else None
    if not ok:
        raise ImageInputError(f"{p}: cannot encode the image as {suffix}")
    if back is not None and back.dtype != image.dtype:
        raise ImageInputError(
            f"{p}: {suffix} cannot hold {image.dtype} pixels (it would be written as "
            f"{back.dtype}); convert the image or use a format that holds them (.tif)")
    if back is not None and suffix.lower() not in _LOSSY_SUFFIXES and not _kept(image, back):
        raise ImageInputError(
            f"{p}: {suffix} does not keep this image's pixel values (a {_layout(image)} image "
            f"would read back as {_layout(back)} with other values); use .png or .tif")
    return buf


#: Suffixes of the formats whose encoders approximate the pixels by design (OpenCV's
#: defaults: JPEG quality 95, JPEG 2000's wavelet rate, AVIF 95; GIF's 256-colour palette);
#: every other format must give back what was written.
_LOSSY_SUFFIXES = (".jpg", ".jpeg", ".jpe", ".jp2", ".avif", ".gif")


def _kept(image: NDArray, back: NDArray) -> bool:
    """Whether ``back`` (the decoding of ``image``'s encoding) holds ``image``'s pixels: the
    same values, a grey image's also in each channel of a colour decoding (WebP, Radiance HDR
    store grey as three equal channels)."""
    img = image[:, :, 0] if image.ndim == 3 and image.shape[2] == 1 else image
    if back.shape == img.shape:
        return bool(np.array_equal(back, img))
    return img.ndim == 2 and back.ndim == 3 and \
        all(np.array_equal(back[:, :, k], img) for k in range(back.shape[2]))


def _layout(image: NDArray) -> str:
    """``"H x W x C dtype"`` of an image, for messages."""
    return " x ".join(str(n) for n in image.shape) + f" {image.dtype}"


def write_image(path: str | Path, image: NDArray) -> Path:
    """Write an image (format from the suffix); raise ImageInputError when OpenCV cannot.

    The format must hold the image's pixel type: OpenCV's encoders converted what they cannot
    hold to 8 bits without a word (float32 0..1 written as all 0, uint16 to a JPEG clipped at
    255, negative int16 to 0), so a pixel type the written file would not read back as is an
    ImageInputError naming both (PNG and PGM hold uint8 and uint16, JPEG uint8, TIFF also
    int8-int32, float32 and float64). So is an image a format other than a lossy one (JPEG,
    JPEG 2000, AVIF, GIF) would not give back as written: Sun raster wrote a grey image that
    read back all 0, Radiance HDR clipped negative float32 values to 0 and rounded the rest
    to 8-bit mantissas, and an alpha channel that a format drops was dropped.
    """
    check_image(image, str(path))
    # (config.output_file: a folder at the path is refused before the encoding -- it was
    # "cannot write the image (Is a directory)" after it -- and a file where the folder should
    # be is "D is not a folder", no longer "folder D does not exist")
    p = output_file(path)
    buf = _encoded(p, image)
    # (replaced once complete, config.replacing: written in place, a write that failed part
    # way -- a full disk, Ctrl-C -- left a truncated image where the earlier file was,
    # `detect --overlay --force`)
    try:
        with replacing(p) as tmp, open_replaced(tmp) as fh:
            fh.write(buf.tobytes())
    except OSError as exc:  # (no permission: a bare OSError before)
        raise InputFileError(f"{p}: cannot write the image ({exc.strerror or exc})") from None
    return p


def _natural_key(path: Path) -> tuple:
    """Sort key of a path with its digit runs compared as numbers (``left2`` before
    ``left10``, ``left01`` beside ``left1``), the text itself breaking ties."""
    parts = re.split(r"(\d+)", str(path))  # (the odd parts are the digit runs: "²" is no
    # decimal digit to the split, though str.isdigit takes it -- int("²") raised ValueError)
    return tuple((0, int(c), "") if i % 2 else (1, 0, c)
                 for i, c in enumerate(parts)), str(path)


def glob_images(pattern: str | Path, what: str = "images") -> list[Path]:
    """Files matching a shell pattern (``'DIR/left*.jpg'``) or in a folder, in natural order
    (numbers in the names compared as numbers: ``left1 ... left10`` pairs with ``right01 ...
    right10``; sorted as text, one side's padding paired left1 with right01 and left10 with
    right02, and the calibration blamed the cameras: "optical axes are 75 deg apart").

    A folder's hidden files (names starting with a dot: macOS's ``.DS_Store``, an editor's
    ``.left1.png.swp``) are left out, as the pattern ``'DIR/*'`` leaves them out: they were
    taken as images -- "DIR/.DS_Store: not a readable image", or "4 left images but 3 right
    images" where only one folder held one.

    Raises InputFileError when nothing matches, and for an empty pattern (it listed the
    working folder).
    """
    text = str(pattern)
    if not text.strip():
        raise InputFileError(f"no {what} given: the pattern is empty")
    p = Path(text).expanduser()
    if p.is_dir():
        files = sorted((f for f in p.iterdir() if f.is_file() and not f.name.startswith(".")),
                       key=_natural_key)
    else:
        files = sorted((Path(f) for f in glob.glob(str(p)) if Path(f).is_file()),
                       key=_natural_key)
    if not files:
        raise InputFileError(f"no {what} matched {text!r} (check the path and quote the pattern)")
    return files
