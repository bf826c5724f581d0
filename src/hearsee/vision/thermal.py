"""Thermal filter (thesis 7.3): keep the pixels whose temperature fits a human, then morphology.

Reconstruction (only the section titles survive; figs. 7.11-7.12 show the filter's output).
Two kinds of thermal image are handled:

* **Radiometric** images (float degC, or 16-bit counts converted with
  :func:`counts_to_celsius`): a pixel is "warm" when its temperature lies in the band of human
  skin and clothing, by default 26-40 degC (skin ~ 33-35 degC, clothing surface 27-31 degC in a
  20-23 degC room; radiators and hot appliances above 40 degC are excluded). The band follows the
  skin/clothing temperatures used in thermal people detection (e.g. Fernandez-Caballero et al.,
  "Real-time human segmentation in infrared videos", Expert Syst. Appl. 2011; Davis & Sharma,
  OTCBVS 2004).
* **Non-radiometric 8-bit** images (automatic gain control, as in LLVIP): temperatures are
  unknown, so the band is relative to the image's own statistics -- a pixel is warm when it is
  ``k_sigma`` robust standard deviations (1.4826 * MAD) above the median background level,
  but at least ``min_gap`` and at most ``max_gap`` of the (median -> 99.5th percentile) range;
  outdoors, where pavement and walls are as bright as people, the local background (a white
  top-hat) is subtracted first.

Both masks are cleaned by a morphological opening (removes isolated noisy pixels) and closing
(fills small gaps), with elliptical kernels of ``open_px``/``close_px`` pixels.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from hearsee.config import as_path, finite_number, input_file, whole_number
from hearsee.errors import ConfigError, ImageInputError
from hearsee.vision.io import as_detector_image, bool_mask, check_image, numeric_map, to_gray

__all__ = [
    "counts_to_celsius",
    "load_thermal",
    "overlay_thermal",
    "relative_warm_mask",
    "thermal_mask",
    "warm_mask_celsius",
]

#: Default human skin/clothing band in degC.
HUMAN_BAND_C = (26.0, 40.0)

#: A radiometric frame of a robot's surroundings has its median pixel below the upper bound
#: (degC) and its warmest above the lower one; a frame outside is in other units: kelvin read
#: as degC (a 20 degC room is 293), or raw counts of another scale. (The median, not the
#: coldest pixel: one dead pixel or a border of 0 -- undistorted or registered frames have
#: one -- let a kelvin frame through as degC, and every person had "thermal support 0.00".)
SCENE_C = (-60.0, 100.0)

#: A radiometric frame whose warmest and coldest pixels are less than this apart (degC) is
#: flat (shutter, lens cap, frozen stream): no scene, no warm pixels (:func:`thermal_mask`).
#: Sensor noise (NETD 0.03-0.1 degC) can spread a capped lens's frame beyond it: the rule
#: catches frames flat to the digit (a frozen stream, a constant), not every lens cap, and
#: never a frame with anything warmer in it, however small.
FLAT_SPREAD_C = 0.1

#: The largest float32 (the type of :func:`counts_to_celsius`'s arithmetic).
_F32_MAX = float(np.finfo(np.float32).max)


#: Absolute zero in degrees Celsius: no radiometric reading is colder.
ABSOLUTE_ZERO_C = -273.15

#: No radiometric pixel is hotter (degC): industrial thermal cameras read up to 2000-3000
#: degC. A hotter one is no temperature (1e300 in a .npy passed every check until
#: 2026-12-03, and its cast to float32 reported "NaN or infinite values").
MAX_PIXEL_C = 3000.0


def counts_to_celsius(counts: NDArray, scale: float = 0.01, offset: float = -273.15) -> NDArray:
    """Convert raw radiometric counts to degC: ``T = counts * scale + offset``.

    The defaults read 16-bit images stored in centi-kelvin (FLIR "TLinear" high resolution,
    also what :func:`hearsee.sim.scenes.write_scene` writes to ``thermal_radiometric.png``).
    ``scale`` (degC per count, > 0) and ``offset`` must be finite float32 numbers (ConfigError:
    a NaN scale gave an all-NaN image, a string was parsed); ``counts`` numbers
    (ImageInputError). Counts that convert to below absolute zero (-273.15 degC; negative
    counts of a signed image, or a wrong scale or offset) are an ImageInputError: they were
    returned as such temperatures without a word.
    """
    # (numpy's ValueError on text and ragged lists, True read as 1)
    c = numeric_map("counts", counts, np.float32)
    # (checked, not converted: a numpy scalar stays what it was, and so does the result)
    finite_number("scale", scale, 0.0, _F32_MAX, lo_open=True)
    finite_number("offset", offset, -_F32_MAX, _F32_MAX)
    out = c * np.float32(scale) + np.float32(offset)
    # (float32 rounding of 0 * 0.01 - 273.15 stays within 1e-3 of it)
    if out.size and np.nanmin(out, initial=np.inf) < ABSOLUTE_ZERO_C - 1e-3:
        raise ImageInputError(
            f"counts convert to {float(np.nanmin(out)):.2f} degC, below absolute zero "
            f"({ABSOLUTE_ZERO_C} degC): negative counts (a signed image?) or a wrong scale "
            f"({scale}) or offset ({offset})")
    return out


def _kernel_px(name: str, value: object, shape: tuple[int, ...]) -> int:
    """A morphology kernel size in pixels (0 or 1 = none), ConfigError unless it is an integer
    from 0 to the image's larger side: a float or NaN reached cv2 (a builtin TypeError) or
    skipped the step, a negative one skipped it too, 10**6 asked OpenCV for a terabyte."""
    return whole_number(name, value, 0, max(shape))


def _kernels(n: int) -> tuple[NDArray, tuple[int, int], NDArray, tuple[int, int]]:
    """An ``n`` x ``n`` elliptical kernel with its anchor, and its point reflection with the
    reflected anchor. cv2.erode and cv2.dilate both read the pixels at (kernel - anchor)
    offsets, so a true opening/closing dilates with the reflected kernel; cv2.morphologyEx
    does not, and with an even ``n`` (not symmetric about its anchor) shifted the mask."""
    k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (n, n))
    a = n // 2
    return k, (a, a), np.ascontiguousarray(k[::-1, ::-1]), (n - 1 - a, n - 1 - a)


def _clean(mask: NDArray, open_px: int, close_px: int) -> NDArray:
    m = mask.astype(np.uint8)
    if open_px > 1:
        k, a, kr, ar = _kernels(open_px)
        m = cv2.dilate(cv2.erode(m, k, anchor=a), kr, anchor=ar)
    if close_px > 1:
        k, a, kr, ar = _kernels(close_px)
        m = cv2.erode(cv2.dilate(m, kr, anchor=ar), k, anchor=a)
    return m.astype(bool)


def warm_mask_celsius(thermal_c: NDArray, band_c: tuple[float, float] = HUMAN_BAND_C, *,
                      open_px: int = 2, close_px: int = 3) -> NDArray:
    """Pixels of a radiometric image (degC, (h, w)) inside ``band_c``, after morphology.

    >>> t = np.full((20, 20), 21.0, np.float32); t[5:15, 8:12] = 33.0; t[0:3, 0:3] = 55.0
    >>> m = warm_mask_celsius(t)
    >>> bool(m[10, 10]), bool(m[1, 1]), int(m.sum())
    (True, False, 39)
    """
    t = numeric_map("thermal image", thermal_c, np.float32)
    if t.ndim != 2 or t.size == 0:  # (an empty one was OpenCV's assertion in erode)
        raise ImageInputError(f"thermal image must be single-channel (h, w) and not empty, got "
                              f"{t.shape}")
    open_px = _kernel_px("open_px", open_px, t.shape)
    close_px = _kernel_px("close_px", close_px, t.shape)
    try:
        lo, hi = band_c
    except (TypeError, ValueError):
        lo = hi = None
    if not (_degrees(lo) and _degrees(hi) and lo < hi):
        raise ConfigError(f"band_c must be (low, high) in degC with low < high, got {band_c!r}")
    with np.errstate(invalid="ignore"):
        m = (t >= lo) & (t <= hi)
    return _clean(m, open_px, close_px)


def _degrees(v: object) -> bool:
    """A real number, not NaN (an infinite bound leaves that side of the band open)."""
    return (isinstance(v, int | float | np.integer | np.floating) and not isinstance(v, bool)
            and not np.isnan(v))


def relative_warm_mask(image: NDArray, *, k_sigma: float = 6.0, min_gap: float = 0.15,
                       max_gap: float = 0.6, background_px: int | None = None,
                       open_px: int = 2, close_px: int = 3) -> NDArray:
    """Warm pixels of a non-radiometric (8-bit AGC) thermal image, relative to its statistics.

    ``threshold = median + clip(k_sigma * 1.4826 * MAD, min_gap * r, max_gap * r)`` with
    ``r = p99.5 - median``; pixels at or above it are warm. With ``background_px`` the image's
    local background (grey opening with a disk of that diameter, i.e. a white top-hat) is
    subtracted first, so that warm people stand out of a warm pavement or wall (outdoor AGC
    imagery). Returns a bool mask after morphology. Works for any single-channel image in which
    warmer = brighter.

    A warm pixel is always at least one grey level (integer images; a relative 1e-6 of the
    level for float images) above the median: a flat frame -- shutter closed, lens cap on, a
    frozen or saturated camera -- has no warm pixels at all (an all-False mask, so that no
    stereo candidate is "thermally verified" by it), and a small warm blob on an otherwise flat
    background is warm while the background is not.

    ``k_sigma``, ``min_gap`` and ``max_gap`` are finite numbers >= 0 with ``min_gap <=
    max_gap``, the kernel sizes integers from 0 or 1 (none) to the image's larger side
    (ConfigError: a NaN gap or k_sigma gave an empty or a wrong mask without a word); an image
    with NaN or inf pixels is an ImageInputError (as in :func:`thermal_mask`).
    """
    # (one NaN pixel made the median NaN: an all-False mask without a word)
    im = numeric_map("thermal image", image, None, finite=True)
    if im.ndim == 3:
        im = to_gray(im)  # ImageInputError for channel counts or pixel types OpenCV cannot convert
    if im.ndim != 2 or im.size == 0:
        raise ImageInputError(f"thermal image must be a non-empty single-channel (h, w) array, "
                              f"got {im.shape}")
    finite_number("k_sigma", k_sigma, 0.0)  # (checked, not converted: see counts_to_celsius)
    if finite_number("min_gap", min_gap, 0.0) > finite_number("max_gap", max_gap, 0.0):
        # (the clip's bounds reversed: min_gap silently won)
        raise ConfigError(f"min_gap must be <= max_gap, got {min_gap} and {max_gap}")
    if background_px is not None:
        background_px = _kernel_px("background_px", background_px, im.shape)
    open_px = _kernel_px("open_px", open_px, im.shape)
    close_px = _kernel_px("close_px", close_px, im.shape)
    # float64: in float32, med + a tiny gap rounds back to med and a flat frame was all warm
    x = im.astype(np.float64)
    if background_px is not None and background_px > 1:
        # a true opening (as _clean's): cv2.morphologyEx's shifted the background of an even
        # kernel by a pixel, and a warm wall's edge row or column was "warm"; a 1-px disk is
        # no background (it took the whole image, and the mask was empty)
        k, a, kr, ar = _kernels(background_px)
        x = x - cv2.dilate(cv2.erode(x, k, anchor=a), kr, anchor=ar)
    med = float(np.median(x))
    mad = float(np.median(np.abs(x - med))) * 1.4826
    r = float(np.percentile(x, 99.5)) - med
    thr = med + max(min(k_sigma * mad, max_gap * r), min_gap * r, _grey_level(im.dtype, med))
    return _clean(x >= thr, open_px, close_px)


def _grey_level(dtype: np.dtype, level: float) -> float:
    """Smallest gap above the median that counts as warmer: one grey level of an integer image,
    a relative 1e-6 of a float one. On the 12 real LLVIP 8-bit frames of the shared data the
    statistical gap of :func:`relative_warm_mask` is 64-97 grey levels (36-80 after the top-hat
    of 101 px), on the simulated 8-bit frames 98: this floor only decides flat or nearly flat
    (>= 99.5 % one value) frames, where MAD and the percentile range are both 0."""
    if np.dtype(dtype).kind in "uib":
        return 1.0
    return 1e-6 * max(1.0, abs(level))


def thermal_mask(image: NDArray, *, band_c: tuple[float, float] = HUMAN_BAND_C,
                 radiometric: bool | None = None, **kwargs) -> NDArray:
    """The thermal filter: warm-pixel mask of a thermal image of any supported kind.

    float images are degC (radiometric), uint16 images centi-kelvin counts
    (:func:`counts_to_celsius`), uint8 images non-radiometric (relative band). ``radiometric``
    overrides the guess for float/uint16 images. Extra keyword arguments go to
    :func:`warm_mask_celsius` or :func:`relative_warm_mask`.

    A flat frame (shutter closed, lens cap on, frozen camera) gives an all-False mask rather
    than an error: on a live robot "nobody is thermally verified" is the safe answer for that
    frame. For 8-bit frames see :func:`relative_warm_mask`; a radiometric frame is flat when all
    its pixels lie within :data:`FLAT_SPREAD_C`. Radiometric
    frames must hold a scene's temperatures in degC (:data:`SCENE_C`; ImageInputError
    otherwise, as :func:`load_thermal`): a frame in kelvin or raw 14-bit counts rejected every
    person ("thermal support 0.00") without a word. ``radiometric`` is True, False or None and
    the keyword arguments those of the filter the image goes to (ConfigError: ``k_sigma`` for
    a radiometric frame was a builtin TypeError, ``radiometric="no"`` read as True).
    """
    if radiometric is not None and not isinstance(radiometric, bool | np.bool_):
        # ("no" was read as True)
        raise ConfigError(f"radiometric must be True, False or None, got {radiometric!r:.40}")
    im = numeric_map("thermal image", image, None)
    if im.ndim == 3:
        if im.dtype != np.uint8:
            raise ImageInputError("a multi-channel thermal image must be 8-bit")
        im = to_gray(im)  # ImageInputError for 2 channels or an empty image
    if im.ndim != 2 or im.size == 0:
        raise ImageInputError(f"thermal image must be a non-empty (h, w) array, got {im.shape}")
    if im.dtype.kind == "f" and not np.all(np.isfinite(im)):  # (both bands: NaN medians)
        raise ImageInputError("thermal image contains NaN or infinite values")
    relative = im.dtype == np.uint8 or (radiometric is not None and not radiometric)
    _check_filter_options(kwargs, relative)
    if relative:
        return relative_warm_mask(im, **kwargs)
    if im.dtype == np.uint16:
        t = counts_to_celsius(im)
        spread = _check_scene_celsius(t, "16-bit thermal images are centi-kelvin (degC = "
                                      "value / 100 - 273.15)")
    elif im.dtype.kind == "f":
        t = im
        spread = _check_scene_celsius(t, "float thermal images are degC")
    else:
        raise ImageInputError(f"unsupported thermal pixel type {im.dtype} (use uint8, uint16 or "
                              "float)")
    m = warm_mask_celsius(t, band_c, **kwargs)  # (checks the band and kernels, flat or not)
    if spread < FLAT_SPREAD_C:
        # (a flat 30-34 degC frame -- a lens cap on a warm camera, a frozen stream -- was warm
        # everywhere: every candidate, mannequins and coat stands too, "thermally verified")
        m[:] = False
    return m


#: The keyword options of each thermal filter (:func:`thermal_mask` passes them on).
_RELATIVE_OPTIONS = ("k_sigma", "min_gap", "max_gap", "background_px", "open_px", "close_px")
_CELSIUS_OPTIONS = ("open_px", "close_px")


def _check_filter_options(kwargs: dict, relative: bool) -> None:
    """ConfigError naming the options of ``kwargs`` that the filter :func:`thermal_mask` chose
    does not take (they were a builtin TypeError: ``k_sigma`` given for a radiometric frame)."""
    allowed = _RELATIVE_OPTIONS if relative else _CELSIUS_OPTIONS
    unknown = sorted(set(kwargs) - set(allowed))
    if unknown:
        kind = ("non-radiometric (relative band)" if relative else
                "radiometric (degC band, band_c)")
        raise ConfigError(f"thermal filter option(s) {', '.join(unknown)} do not apply to a "
                          f"{kind} thermal image; it takes {', '.join(allowed)}")


def load_thermal(path: str | Path, expected_size: tuple[int, int] | None = None) -> NDArray:
    """Read a thermal image: ``.npy`` (float degC, (h, w); an 8-bit one is a non-radiometric
    frame, returned as uint8 as an 8-bit image file is), or any image file through
    :func:`hearsee.vision.io.read_thermal` (8-bit non-radiometric, 16-bit centi-kelvin counts,
    float TIFF degC). ``expected_size`` is (width, height).

    (An 8-bit .npy was read as degC: the AGC grey levels 26-40 were the "human band", so
    ``hearsee detect`` accepted a dark mannequin and rejected the bright person that the same
    array passed to :func:`~hearsee.vision.fusion.detect_humans` got right.)"""
    from hearsee.vision.io import image_size, read_thermal

    p = as_path(path, "the thermal file's path")
    if expected_size is not None:  # (a bare number was a TypeError)
        expected_size = image_size(expected_size)
    if p.suffix.lower() == ".npy":
        input_file(p, "thermal file")
        try:
            arr = np.load(p, allow_pickle=False)
        except (ValueError, OSError) as exc:
            raise ImageInputError(f"{p}: not a readable .npy array ({exc})") from None
        if not isinstance(arr, np.ndarray):  # (np.load reads an .npz archive whatever its name)
            arr.close()
            raise ImageInputError(f"{p}: an .npz archive of arrays, not one .npy array of degC")
        if arr.ndim != 2 or arr.dtype.kind not in "fiu" or arr.size == 0:
            raise ImageInputError(f"{p}: expected a 2-D numeric array of degC, got {arr.shape} "
                                  f"{arr.dtype}")
        if expected_size is not None and (arr.shape[1], arr.shape[0]) != tuple(expected_size):
            raise ImageInputError(
                f"{p}: thermal image is {arr.shape[1]}x{arr.shape[0]} pixels but the calibration "
                f"expects {expected_size[0]}x{expected_size[1]}"
            )
        if arr.dtype == np.uint8:  # non-radiometric, as thermal_mask reads it
            return np.ascontiguousarray(arr)
        # (checked before the cast to float32: a finite 1e300 became inf there, with numpy's
        # overflow warning, and was reported as "NaN or infinite values")
        arr = arr.astype(np.float64)
        if not np.all(np.isfinite(arr)):
            raise ImageInputError(f"{p}: thermal image contains NaN or infinite values")
        _check_scene_celsius(arr, f"{p}: .npy thermal images are degC")
        return arr.astype(np.float32)
    img = read_thermal(p, expected_size)
    if img.dtype == np.uint16:
        _check_scene_celsius(counts_to_celsius(img), f"{p}: 16-bit thermal images are "
                             "centi-kelvin (degC = value / 100 - 273.15)")
    elif img.dtype.kind == "f":
        _check_scene_celsius(img, f"{p}: float thermal images are degC")
    return img


def _check_scene_celsius(t: NDArray, what: str) -> float:
    """ImageInputError unless the temperatures ``t`` (degC) can be a scene's (:data:`SCENE_C`,
    nothing below absolute zero or above :data:`MAX_PIXEL_C`): a .npy in kelvin (293 "degC"
    for a 20 degC room) gave "thermal support 0.00" for every person, without a word. Returns
    the frame's spread (warmest - coldest, degC)."""
    lo, hi = float(np.min(t)), float(np.max(t))
    med = float(np.median(t)) if lo <= SCENE_C[1] else lo  # (the median only when it matters)
    if lo < ABSOLUTE_ZERO_C or med > SCENE_C[1] or hi < SCENE_C[0] or hi > MAX_PIXEL_C:
        hint = (" (is it in kelvin?)" if SCENE_C[1] < med < SCENE_C[1] + 273.15 else
                ", and nothing is below absolute zero" if lo < ABSOLUTE_ZERO_C else
                f", and no thermal camera reads above {MAX_PIXEL_C:g} degC" if hi > MAX_PIXEL_C
                else "")
        middle = f", median {med:.4g}" if lo <= SCENE_C[1] < med else ""  # (when it decided)
        raise ImageInputError(f"{what}, but this one spans {lo:.4g} to {hi:.4g} degC{middle}"
                              f"{hint}; convert it to degC")
    return hi - lo


def overlay_thermal(visible: NDArray, thermal: NDArray, warm: NDArray | None = None, *,
                    alpha: float = 0.6) -> NDArray:
    """Visible/thermal overlay of a *registered* pair (same geometry, as LLVIP's): the thermal
    image in a colour map blended over the visible image where ``warm`` (default: everywhere),
    the rest of the visible image darkened; the thermal image is resized to the visible one.
    ``alpha`` (the thermal image's weight) is in [0, 1] (ConfigError: NaN gave a black
    overlay). ``visible`` is an 8-bit grey, BGR or BGRA image, ``thermal`` any non-empty
    image (colour ones uint8, uint16 or float32) and ``warm`` a bool mask (ImageInputError
    otherwise: an empty or float visible image failed inside OpenCV). Returns BGR uint8."""
    finite_number("alpha", alpha, 0.0, 1.0)  # (checked, not converted: see counts_to_celsius)
    vis = check_image(as_detector_image(visible, "visible"), "visible")
    if vis.ndim == 2:
        vis = cv2.cvtColor(vis, cv2.COLOR_GRAY2BGR)
    th = to_gray(numeric_map("thermal", thermal, None), "thermal")
    if th.dtype != np.uint8:
        th = cv2.normalize(th.astype(np.float32), None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)
    size = (vis.shape[1], vis.shape[0])
    col = cv2.applyColorMap(cv2.resize(th, size), cv2.COLORMAP_INFERNO)
    if warm is None:
        m = np.ones(vis.shape[:2], bool)
    else:
        w8 = bool_mask(warm, "warm").astype(np.uint8)
        if w8.size == 0:
            raise ImageInputError(f"warm mask is empty (shape {w8.shape})")
        m = cv2.resize(w8, size, interpolation=cv2.INTER_NEAREST).astype(bool)
    out = (0.55 * vis).astype(np.uint8)
    blend = cv2.addWeighted(vis, 1.0 - alpha, col, alpha, 0.0)
    out[m] = blend[m]
    return out
