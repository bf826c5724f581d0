"""Thermal filter: radiometric band, 8-bit relative band, loading, overlay."""

import re
import warnings

import cv2
import numpy as np
import pytest

from hearsee.errors import CalibrationError, ConfigError, ImageInputError, InputFileError
from hearsee.vision.thermal import (
    counts_to_celsius,
    load_thermal,
    overlay_thermal,
    relative_warm_mask,
    thermal_mask,
    warm_mask_celsius,
)


def _room(rng, h=60, w=80):
    t = 21.0 + rng.normal(0, 0.1, (h, w)).astype(np.float32)
    t[20:50, 30:40] = 31.0  # a clothed person
    t[12:20, 32:38] = 34.0  # the face
    t[40:55, 60:75] = 55.0  # a radiator
    t[5:8, 5:8] = 33.0  # a 3x3 warm speck: removed by the opening
    return t


def test_radiometric_band_and_morphology():
    t = _room(np.random.default_rng(0))
    m = warm_mask_celsius(t, (26.0, 40.0), open_px=5, close_px=3)
    assert m[30, 35] and m[15, 35]
    assert not m[45, 65]  # radiator above the band
    assert not m[6, 6]  # speck removed
    assert not m[2, 70]  # room
    with pytest.raises(ValueError):
        warm_mask_celsius(t, (40.0, 26.0))
    with pytest.raises(ImageInputError):
        warm_mask_celsius(np.zeros((3, 3, 3)))


def test_counts_and_dispatch():
    t = _room(np.random.default_rng(1))
    ck = np.rint((t + 273.15) * 100).astype(np.uint16)
    assert np.allclose(counts_to_celsius(ck), t, atol=0.006)
    assert np.array_equal(thermal_mask(ck), thermal_mask(t))
    t8 = cv2.normalize(t, None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)
    m8 = thermal_mask(t8)
    assert m8[30, 35] and not m8[2, 70]
    with pytest.raises(ImageInputError):
        thermal_mask(np.zeros((4, 4), np.int64))
    with pytest.raises(ImageInputError):
        thermal_mask(np.full((4, 4), np.nan, np.float32))


def test_relative_band_8bit_without_temperatures():
    """AGC 8-bit: the person stands out from the background even though temperatures are
    unknown; a room-temperature object does not."""
    rng = np.random.default_rng(2)
    t = _room(rng)
    t[20:50, 10:18] = 21.6  # a mannequin, 0.6 degC above the room
    lo, hi = np.percentile(t, [1, 99.5])
    t8 = np.clip((t - lo) / (hi - lo) * 255, 0, 255).astype(np.uint8)
    m = relative_warm_mask(t8)
    assert m[30, 35] and not m[30, 14] and not m[2, 70]
    # colour (3-channel grey) images are accepted
    assert np.array_equal(relative_warm_mask(cv2.cvtColor(t8, cv2.COLOR_GRAY2BGR)), m)


def test_load_thermal(tmp_path):
    t = _room(np.random.default_rng(3))
    np.save(tmp_path / "t.npy", t)
    assert np.array_equal(load_thermal(tmp_path / "t.npy", expected_size=(80, 60)), t)
    t8 = np.clip(t * 4, 0, 255).astype(np.uint8)  # an 8-bit frame: non-radiometric, kept
    np.save(tmp_path / "t8.npy", t8)
    got = load_thermal(tmp_path / "t8.npy", expected_size=(80, 60))
    assert got.dtype == np.uint8 and np.array_equal(got, t8)
    with pytest.raises(ImageInputError, match="80x60"):
        load_thermal(tmp_path / "t.npy", expected_size=(160, 120))
    with pytest.raises(InputFileError):
        load_thermal(tmp_path / "missing.npy")
    (tmp_path / "bad.npy").write_bytes(b"not numpy")
    with pytest.raises(ImageInputError):
        load_thermal(tmp_path / "bad.npy")
    np.save(tmp_path / "nan.npy", np.full((4, 4), np.nan))
    with pytest.raises(ImageInputError):
        load_thermal(tmp_path / "nan.npy")
    with open(tmp_path / "z.npy", "wb") as f:  # an .npz archive named .npy (AttributeError)
        np.savez(f, a=t)
    with pytest.raises(ImageInputError, match="npz archive"):
        load_thermal(tmp_path / "z.npy")
    for bad in (5, (80,), (80.5, 60), (0, 60)):  # (5 was a TypeError)
        with pytest.raises(CalibrationError, match="expected_size"):
            load_thermal(tmp_path / "t.npy", expected_size=bad)
    ck = np.rint((t + 273.15) * 100).astype(np.uint16)
    cv2.imwrite(str(tmp_path / "t16.png"), ck)
    got = load_thermal(tmp_path / "t16.png")
    assert got.dtype == np.uint16 and np.array_equal(got, ck)


@pytest.mark.parametrize("name, image, needle", [
    ("kelvin.npy", lambda t: t + 273.15, "(is it in kelvin?)"),
    ("below_zero.npy", lambda t: t - 400.0, "below absolute zero"),
    ("counts.png", lambda t: np.rint(t * 10).astype(np.uint16), "centi-kelvin"),  # dK counts
])
def test_load_thermal_refuses_temperatures_in_other_units(tmp_path, name, image, needle):
    """A .npy written in kelvin (the room at 293 "degC"), one below absolute zero, or 16-bit
    counts of another scale (deci-kelvin read as centi-kelvin: -250 degC) were read as is:
    the person had "thermal support 0.00" and was rejected, exit 0. The room's own image
    (20-35 degC) and its centi-kelvin PNG are read as before (test_load_thermal)."""
    t = _room(np.random.default_rng(3))
    img = image(t)
    if name.endswith(".npy"):
        np.save(tmp_path / name, img)
    else:
        cv2.imwrite(str(tmp_path / name), img)
    with pytest.raises(ImageInputError, match=re.escape(needle)):
        load_thermal(tmp_path / name)


def test_a_kelvin_frame_with_a_dead_pixel_or_a_zero_border_is_refused(tmp_path):
    """A frame in kelvin with one dead pixel of 0, or the border of 0 an undistorted or
    registered frame has, had its coldest pixel at 0 "degC" and passed as degC: the person
    (304 "degC") was no warm pixel, "thermal support 0.00", exit 0. The median decides now;
    the degC room with the same dead pixel or border is read as before."""
    t = _room(np.random.default_rng(3))
    for zero in ((0, 0), (slice(None), slice(0, 4))):
        k = t + np.float32(273.15)
        k[zero] = 0.0
        with pytest.raises(ImageInputError, match=re.escape("median 294.2 (is it in kelvin?)")):
            thermal_mask(k)
        np.save(tmp_path / "k.npy", k)
        with pytest.raises(ImageInputError, match=re.escape("(is it in kelvin?)")):
            load_thermal(tmp_path / "k.npy")
        c = t.copy()
        c[zero] = 0.0  # (0 degC: ice, a cold window)
        assert thermal_mask(c)[30, 35]
        np.save(tmp_path / "c.npy", c)
        assert np.array_equal(load_thermal(tmp_path / "c.npy"), c)


def test_a_finite_value_beyond_float32_is_named_as_it_is(tmp_path):
    """One pixel of 1e300 degC: the cast to float32 made it inf, with numpy's overflow
    warning, and the file was refused for "NaN or infinite values" it does not hold."""
    t = _room(np.random.default_rng(3)).astype(np.float64)
    t[0, 0] = 1e300
    np.save(tmp_path / "hot.npy", t)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ImageInputError,
                           match=r"spans .* to 1e\+300 degC, and no thermal camera"):
            load_thermal(tmp_path / "hot.npy")


def test_flat_radiometric_frame_has_no_warm_pixels_and_units_are_checked():
    """A flat frame at a skin temperature (a lens cap on a warm camera, a frozen stream) was
    warm everywhere, so every stereo candidate -- mannequins, coat stands -- was "thermally
    verified"; a frame in kelvin or in raw 14-bit counts made every person "thermal support
    0.00". Now: no warm pixel, and ImageInputError naming the units (as load_thermal)."""
    for flat in (np.full((60, 80), 30.0, np.float32), np.full((60, 80), 34.0),
                 np.full((60, 80), round((33.0 + 273.15) * 100), np.uint16)):
        assert not thermal_mask(flat).any()
    room = np.full((60, 80), 21.0, np.float32)
    room[30:32, 40:41] = 33.0  # two warm pixels: not flat (no morphology, to keep them)
    m = thermal_mask(room, open_px=0, close_px=0)
    assert m[30, 40] and m[31, 40] and m.sum() == 2
    t = _room(np.random.default_rng(3))
    assert thermal_mask(t).any()  # the room's own frame, as before
    for bad, needle in ((t + 273.15, "is it in kelvin?"),
                        (np.full((60, 80), 8000, np.uint16), "centi-kelvin")):
        with pytest.raises(ImageInputError, match=re.escape(needle)):
            thermal_mask(bad)


def test_overlay_shape():
    vis = np.full((120, 160, 3), 100, np.uint8)
    th = np.zeros((60, 80), np.uint8)
    th[20:40, 30:50] = 255
    warm = th > 0
    out = overlay_thermal(vis, th, warm)
    assert out.shape == vis.shape and out.dtype == np.uint8
    assert not np.array_equal(out[60, 80], out[5, 5])


def test_local_background_for_outdoor_agc_images():
    """A warm pavement as bright as a person: the global band fails, the top-hat one works."""
    x = np.tile(np.linspace(60, 230, 200, dtype=np.float32), (150, 1))  # bright gradient
    x[40:110, 50:70] += 60.0  # a person, warmer than the pavement around it
    img = np.clip(x, 0, 255).astype(np.uint8)
    m = relative_warm_mask(img, background_px=41)
    assert m[75, 60] and not m[75, 150] and not m[10, 120]
    assert not relative_warm_mask(img)[75, 60]  # global band: the pavement is brighter


def test_local_background_is_a_true_opening_for_every_kernel_size():
    """The top-hat's opening was cv2.morphologyEx's, which with an even disk is shifted by a
    pixel (as _clean's was): a warm wall's left column and top row, 90 grey levels above the
    floor and far wider than the disk, were "warm". A 1-px disk took the whole image as the
    background: an empty mask, the person lost. Odd disks give the opening they gave."""
    for wall in (np.s_[:, 100:], np.s_[70:, :]):  # a warm wall, a warm floor
        im = np.full((120, 160), 60, np.uint8)
        im[wall] = 150  # far wider than the disk
        im[20:60, 30:42] = 220  # a person, 12 px wide
        for bg in (30, 31):
            m = relative_warm_mask(im, background_px=bg, open_px=0, close_px=0)
            assert m[40, 35] and m.sum() == 40 * 12, bg  # the person, and nothing else
        none = relative_warm_mask(im, open_px=0, close_px=0)
        assert np.array_equal(relative_warm_mask(im, background_px=1, open_px=0, close_px=0),
                              none) and none[40, 35]


def test_flat_8bit_frame_has_no_warm_pixels():
    """A shutter-closed or frozen 8-bit frame has MAD = 0 and no percentile range: the threshold
    ``median + 1e-6``, compared in float32, rounded back to the median and EVERY pixel was warm
    (so every stereo candidate was "thermally supported"). Now a flat frame gives an all-False
    mask, and a small warm blob on a flat background is warm while the background is not."""
    for level in (0, 17, 100, 128, 255):
        flat = np.full((60, 80), level, np.uint8)
        assert not thermal_mask(flat).any(), level
        assert not relative_warm_mask(flat, background_px=15).any(), level
    assert not thermal_mask(np.full((60, 80), 21.5, np.float32), radiometric=False).any()
    # 99.7 % of the frame at one value, a 15x15 warm blob (0.29 %: below the 99.5th percentile)
    im = np.full((240, 320), 100, np.uint8)
    im[100:115, 150:165] = 220
    m = thermal_mask(im)
    assert m[107, 157] and m[100:115, 150:165].mean() > 0.8
    assert m.sum() <= 15 * 15  # nothing of the background
    # the same blob on a frozen frame at another level, and dark blobs are not warm
    im[100:115, 150:165] = 40
    assert not thermal_mask(im).any()


def test_nan_in_a_float_image_is_refused_on_the_relative_path_too():
    """A float image with one NaN (a dead pixel) raised ImageInputError as radiometric, but with
    ``radiometric=False`` the NaN made the median and percentile NaN and the mask silently all
    False: the warm person in it was lost."""
    t = np.full((60, 80), 21.0, np.float32)
    t[20:50, 30:40] = 33.0
    assert thermal_mask(t, radiometric=False)[35, 35]  # finite: the person is warm
    t[0, 0] = np.nan
    for radiometric in (None, True, False):
        with pytest.raises(ImageInputError, match="NaN"):
            thermal_mask(t, radiometric=radiometric)
    # relative_warm_mask itself (public) refused it too: it gave an all-False mask
    for bad in (np.nan, np.inf):
        t[0, 0] = bad
        with pytest.raises(ImageInputError, match="NaN or inf"):
            relative_warm_mask(t)


@pytest.mark.parametrize("bad", [
    np.zeros((60, 80, 2), np.uint8),  # two channels: cv2.cvtColor raised cv2.error
    np.zeros((0, 80, 3), np.uint8),  # empty colour image: cv2.error
    np.zeros((0, 80), np.uint8),  # empty: numpy's IndexError (percentile of nothing)
])
def test_unusable_shapes_are_image_input_errors(bad):
    """Both public masks raise the library's ImageInputError, not OpenCV's or numpy's."""
    with pytest.raises(ImageInputError):
        relative_warm_mask(bad)
    with pytest.raises(ImageInputError):
        thermal_mask(bad)


def test_relative_mask_of_a_float_colour_image_is_an_image_input_error():
    """A float64 3-channel image reached cv2.cvtColor, which cannot convert it (cv2.error)."""
    with pytest.raises(ImageInputError, match="float64"):
        relative_warm_mask(np.zeros((60, 80, 3)))
    # replicated grey channels in a pixel type OpenCV converts: same mask as the grey image
    g = np.full((60, 80), 20.0, np.float32)
    g[20:40, 30:40] = 200.0
    np.testing.assert_array_equal(relative_warm_mask(np.dstack([g, g, g])), relative_warm_mask(g))


def test_morphology_does_not_shift_the_mask():
    """OpenCV's erode and dilate apply a kernel at the same offsets, so cv2.morphologyEx with
    an even-sized kernel (the default ``open_px=2``) is not an opening: it shifted the warm
    mask one pixel down and right, marking room-temperature pixels below and right of a person
    as warm. The cleaned mask of a solid warm block stays inside the block's pixels and keeps
    its extent, whatever the kernel sizes."""
    t = np.full((40, 50), 21.0, np.float32)
    t[10:30, 15:25] = 33.0
    band = (t >= 26.0) & (t <= 40.0)
    for open_px, close_px in ((2, 3), (2, 2), (4, 3), (3, 4), (5, 5)):
        m = warm_mask_celsius(t, open_px=open_px, close_px=close_px)
        assert not (m & ~band).any(), (open_px, close_px)  # nothing outside the warm block
        rows, cols = np.nonzero(m)
        assert (rows.min(), rows.max(), cols.min(), cols.max()) == (10, 29, 15, 24)
        assert m.sum() >= band.sum() - 8  # at most the corners trimmed


@pytest.mark.parametrize("band", [(40.0, 26.0), (np.nan, 40.0), (26.0,), (26.0, 33.0, 40.0),
                                  "hot", None, ("26", "40"), (True, 40.0)])
def test_malformed_band_is_a_config_error(band):
    """A reversed band raised a builtin ValueError (the CLI's one-line errors catch only
    hearsee's own), a one- or three-number band the unpacking ValueError, None a TypeError,
    strings numpy's UFuncNoLoopError. An open band such as (26, inf) stays valid."""
    t = np.full((20, 20), 30.0, np.float32)
    with pytest.raises(ConfigError, match="band_c"):
        warm_mask_celsius(t, band)
    with pytest.raises(ConfigError, match="band_c"):
        thermal_mask(t, band_c=band)
    assert warm_mask_celsius(t, (26.0, np.inf)).all()


@pytest.mark.parametrize("call, match", [
    (lambda im, t: counts_to_celsius(t, scale=np.nan), "scale"),  # an all-NaN image
    (lambda im, t: counts_to_celsius(t, scale="0.01"), "scale"),  # parsed as 0.01
    (lambda im, t: counts_to_celsius(t, scale=0.0), "scale"),  # every pixel -273.15
    (lambda im, t: counts_to_celsius(t, scale=1e300), "scale"),  # RuntimeWarning, inf
    (lambda im, t: counts_to_celsius(t, offset=np.inf), "offset"),
    (lambda im, t: overlay_thermal(im, im, alpha=np.nan), "alpha"),  # a black overlay
    (lambda im, t: overlay_thermal(im, im, alpha=2.0), "alpha"),
    (lambda im, t: overlay_thermal(im, im, alpha="0.5"), "alpha"),  # builtin TypeError
    (lambda im, t: relative_warm_mask(im, k_sigma=np.nan), "k_sigma"),  # an empty mask
    (lambda im, t: relative_warm_mask(im, k_sigma="6"), "k_sigma"),  # builtin TypeError
    (lambda im, t: relative_warm_mask(im, min_gap=np.nan), "min_gap"),
    (lambda im, t: relative_warm_mask(im, max_gap=np.inf), "max_gap"),  # an empty mask
    (lambda im, t: relative_warm_mask(im, min_gap=0.7, max_gap=0.6), "min_gap must be <="),
    (lambda im, t: relative_warm_mask(im, background_px=-3), "background_px"),  # cv2.error
    (lambda im, t: relative_warm_mask(im, background_px=np.nan), "background_px"),
    (lambda im, t: relative_warm_mask(im, open_px=np.nan), "open_px"),  # step skipped
    (lambda im, t: relative_warm_mask(im, open_px=10**6), "open_px"),  # cv2.error, memory
    (lambda im, t: relative_warm_mask(im, close_px=-4), "close_px"),  # step skipped
    (lambda im, t: warm_mask_celsius(t, open_px="3"), "open_px"),  # builtin TypeError
    (lambda im, t: warm_mask_celsius(t, close_px=2**40), "close_px"),  # builtin TypeError
    (lambda im, t: thermal_mask(im, open_px=2.5), "open_px"),  # builtin TypeError
])
def test_thermal_settings_are_config_errors(call, match):
    """The float settings of the thermal filter reached numpy and OpenCV unchecked: NaN gave
    all-NaN temperatures, an empty mask or a black overlay without a word, strings and floats
    builtin TypeErrors, huge or negative kernels cv2.error."""
    rng = np.random.default_rng(5)
    im = rng.integers(0, 120, (40, 50), dtype=np.uint8)
    im[10:20, 10:20] = 250
    t = _room(rng)
    with pytest.raises(ConfigError, match=match):
        call(im, t)


def test_counts_must_be_numbers():
    """Text counts raised numpy's ValueError; a ragged list raised it while the error message
    was being written."""
    for bad in (np.array([["30000", "abc"]]), [[30000, 30100], [30200]]):
        with pytest.raises(ImageInputError, match="^counts must hold numbers"):
            counts_to_celsius(bad)
    ck = np.array([[29315, 30315]], np.uint16)  # 20 and 30 degC in centi-kelvin
    np.testing.assert_allclose(counts_to_celsius(ck), [[20.0, 30.0]], atol=1e-3)


@pytest.mark.parametrize("fn", [warm_mask_celsius, relative_warm_mask, thermal_mask])
def test_thermal_images_of_text_or_ragged_rows_are_refused(fn):
    """A thermal image of text or a ragged list of rows was numpy's builtin ValueError (or a
    mask computed from text); now the module's ImageInputError. Numbers still work."""
    t = np.full((20, 20), 21.0, np.float32)
    t[5:15, 8:12] = 33.0
    for bad in (t.astype(str), [[21.0, 22.0], [21.0]]):
        with pytest.raises(ImageInputError, match="^thermal image must hold numbers"):
            fn(bad)
    assert fn(t).shape == t.shape and fn(t.tolist()).shape == t.shape


def test_overlay_refuses_images_opencv_cannot_blend():
    """An empty, float, BGRA or text visible image, an empty thermal image and a warm mask of
    text failed inside OpenCV (cv2.error) or numpy; each is now an ImageInputError. A BGRA or
    (H, W, 1) visible image is blended like its BGR / grey version."""
    vis = np.full((40, 60, 3), 100, np.uint8)
    th = np.zeros((20, 30), np.uint8)
    th[5:15, 10:20] = 255
    warm = th > 0
    for v, t, w, match in ((np.zeros((0, 0, 3), np.uint8), th, warm, "empty"),
                           (vis.astype(np.float64), th, warm, "8-bit"),
                           ([[1, 2], [3]], th, warm, "visible must hold numbers"),
                           (vis, np.zeros((0, 5)), warm, "empty"),
                           (vis, th, [["a"] * 30] * 20, "warm must be a bool silhouette"),
                           (vis, th, np.zeros((0, 4), bool), "warm mask is empty")):
        with pytest.raises(ImageInputError, match=match):
            overlay_thermal(v, t, w)
    ref = overlay_thermal(vis, th, warm)
    bgra = np.dstack([vis, np.full(vis.shape[:2], 7, np.uint8)])
    np.testing.assert_array_equal(overlay_thermal(bgra, th, warm), ref)
    grey = vis[..., 0].copy()
    np.testing.assert_array_equal(overlay_thermal(grey[..., None], th, warm),
                                  overlay_thermal(grey, th, warm))


def test_thermal_mask_checks_its_flag_and_the_chosen_filters_options():
    """``radiometric`` as numpy's False went to the degC band (``is False`` is not true of
    np.False_) and ``"no"`` read as True; an option of the other filter (``k_sigma`` for a
    radiometric frame, ``background_px`` for 16-bit counts) was a builtin TypeError."""
    from hearsee.errors import ConfigError

    t = np.full((30, 30), 21.0, np.float32)
    t[8:22, 10:18] = 45.0  # hot, above the human band: warm only relative to the room
    relative = thermal_mask(t, radiometric=False)
    assert relative[15, 14] and not relative[2, 2]
    assert np.array_equal(thermal_mask(t, radiometric=np.False_), relative)
    assert not thermal_mask(t).any() and not thermal_mask(t, radiometric=np.True_).any()
    for bad in ("no", 0, 1.0):
        with pytest.raises(ConfigError, match="radiometric"):
            thermal_mask(t, radiometric=bad)
    with pytest.raises(ConfigError, match="k_sigma.*radiometric"):
        thermal_mask(t, k_sigma=3.0)
    counts = np.rint((t + 273.15) * 100).astype(np.uint16)
    with pytest.raises(ConfigError, match="background_px"):
        thermal_mask(counts, background_px=5)
    # the options of the chosen filter still reach it
    assert thermal_mask(t, radiometric=False, k_sigma=3.0, open_px=0).sum() == 14 * 8
    assert thermal_mask(t, band_c=(40.0, 50.0), open_px=0, close_px=0).sum() == 14 * 8


def test_counts_below_absolute_zero_are_refused():
    """Centi-kelvin counts: 0 is absolute zero, 30000 is 26.85 degC; a signed image's negative
    counts (-5: -273.20 degC) or an offset that puts 0 counts 10 degC lower were returned as
    temperatures below absolute zero without a word."""
    ok = counts_to_celsius(np.array([[0, 30000]], np.uint16))
    np.testing.assert_allclose(ok, [[-273.15, 26.85]], atol=1e-3)
    with pytest.raises(ImageInputError, match="absolute zero"):
        counts_to_celsius(np.array([[-5, 29000]], np.int16))
    with pytest.raises(ImageInputError, match="absolute zero"):
        counts_to_celsius(np.array([[0, 29000]], np.uint16), offset=-283.15)
    assert np.isnan(counts_to_celsius(np.array([[np.nan]]))).all()  # NaN stays NaN


@pytest.mark.parametrize("shape", [(0, 10), (10, 0)])
def test_an_empty_thermal_image_is_an_image_input_error(shape):
    """OpenCV's "!src.empty()" assertion in erode before (an API audit); the other two masks
    refused it already."""
    with pytest.raises(ImageInputError, match="not empty"):
        warm_mask_celsius(np.zeros(shape, np.float32))
