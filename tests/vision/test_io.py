"""Tests of hearsee.vision.io: image reading with validation."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from hearsee.errors import CalibrationError, ConfigError, ImageInputError, InputFileError
from hearsee.vision.io import (
    check_image,
    check_pair,
    glob_images,
    read_image,
    read_pair,
    read_thermal,
    to_8_bits,
    to_gray,
    video_capture,
    write_image,
)


def _img(h: int = 48, w: int = 64, c: int | None = None, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    shape = (h, w) if c is None else (h, w, c)
    return rng.integers(0, 256, shape, dtype=np.uint8)


def test_roundtrip_gray_and_color(tmp_path):
    g = _img()
    write_image(tmp_path / "g.png", g)
    np.testing.assert_array_equal(read_image(tmp_path / "g.png"), g)
    c = _img(c=3)
    write_image(tmp_path / "c.png", c)
    np.testing.assert_array_equal(read_image(tmp_path / "c.png", "bgr"), c)
    assert read_image(tmp_path / "c.png").shape == (48, 64)
    np.testing.assert_array_equal(to_gray(c), cv2.cvtColor(c, cv2.COLOR_BGR2GRAY))


def test_missing_corrupt_and_empty_files(tmp_path):
    with pytest.raises(InputFileError, match="not found"):
        read_image(tmp_path / "none.png")
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"this is not a png")
    with pytest.raises(ImageInputError, match="not a readable image"):
        read_image(bad)
    empty = tmp_path / "empty.jpg"
    empty.write_bytes(b"")
    with pytest.raises(ImageInputError, match="not a readable image"):
        read_image(empty)
    # a PNG cut in half cannot be decoded
    ok, buf = cv2.imencode(".png", _img(c=3))
    trunc = tmp_path / "trunc.png"
    trunc.write_bytes(buf.tobytes()[: len(buf) // 2])
    with pytest.raises(ImageInputError):
        read_image(trunc)


def _damaged(ext: str) -> bytes:
    """An encoded image with bytes 40, 47, ... (up to 400) flipped: libpng stops on a bad
    chunk header, libjpeg on corrupt entropy-coded data."""
    ok, buf = cv2.imencode(ext, _img(64, 80, 3))
    data = bytearray(buf.tobytes())
    for i in range(40, min(len(data), 400), 7):
        data[i] ^= 0x5A
    return bytes(data)


@pytest.mark.parametrize("name, noise", [("bad.png", "libpng error"),
                                         ("bad.jpg", "Corrupt JPEG data")])
@pytest.mark.parametrize("mode", ["gray", "bgr", "unchanged"])
def test_a_damaged_image_is_one_typed_error_and_nothing_on_stderr(tmp_path, capfd, name,
                                                                  noise, mode):
    """The codecs under OpenCV print such a file's trouble on file descriptor 2 themselves,
    whatever OpenCV's log level (checked here first: the ground truth that there is noise to
    silence); read_image gives the one ImageInputError and leaves stderr empty."""
    from hearsee.vision.io import opencv_log_functions

    get_level, set_level = opencv_log_functions()
    data = _damaged(name[-4:])
    before = get_level()
    set_level(0)  # (silent)
    try:
        capfd.readouterr()
        assert cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED) is None
        assert noise in capfd.readouterr().err
    finally:
        set_level(before)
    (tmp_path / name).write_bytes(data)
    with pytest.raises(ImageInputError) as e:
        read_image(tmp_path / name, mode)
    assert str(e.value) == (f"{tmp_path / name}: not a readable image (corrupt or unsupported "
                            "format; expected PNG, JPEG, TIFF or PGM)")
    assert capfd.readouterr().err == ""


def test_reads_in_two_threads_leave_stderr_as_it_was(tmp_path, capfd, monkeypatch):
    """Each read saved file descriptor 2, pointed it at the null device and put the saved one
    back: a second thread's read that started while the first decoded saved the null device
    and, ending last, left it as the process's stderr -- everything written to stderr
    afterwards was lost. The reads now share one redirection; here thread A decodes, B starts
    and decodes, A ends, then B ends (forced by a stand-in imdecode), and stderr works."""
    import os
    import threading

    write_image(tmp_path / "a.png", _img())
    decode = cv2.imdecode
    a_in, b_in, a_done = threading.Event(), threading.Event(), threading.Event()

    def interleaved(data, flags):
        if threading.current_thread().name == "A":
            a_in.set()
            b_in.wait(5)
        else:
            b_in.set()
            a_done.wait(5)
        return decode(data, flags)

    monkeypatch.setattr(cv2, "imdecode", interleaved)
    images = {}

    def read(name):
        images[name] = read_image(tmp_path / "a.png")
        if name == "A":
            a_done.set()

    ta = threading.Thread(target=read, args=("A",), name="A")
    tb = threading.Thread(target=read, args=("B",), name="B")
    ta.start()
    assert a_in.wait(5)
    tb.start()
    ta.join(10)
    tb.join(10)
    assert b_in.is_set() and a_done.is_set()  # (the order forced: B began before A ended)
    for name in ("A", "B"):
        np.testing.assert_array_equal(images[name], _img())
    capfd.readouterr()
    os.write(2, b"stderr still works\n")
    assert capfd.readouterr().err == "stderr still works\n"


def test_wrong_size_and_mismatched_pair(tmp_path):
    write_image(tmp_path / "l.png", _img(48, 64))
    write_image(tmp_path / "r.png", _img(48, 60))
    with pytest.raises(ImageInputError, match="64x48 pixels but the calibration expects 32x24"):
        read_image(tmp_path / "l.png", expected_size=(32, 24))
    with pytest.raises(ImageInputError, match="differ in size"):
        read_pair(tmp_path / "l.png", tmp_path / "r.png")
    write_image(tmp_path / "r2.png", _img(48, 64, seed=1))
    L, R = read_pair(tmp_path / "l.png", tmp_path / "r2.png", expected_size=(64, 48))
    assert L.shape == R.shape == (48, 64)
    for bad in ((1,), 64, (64, -48), (64.5, 48), "64x48"):  # ((1,) was an IndexError)
        with pytest.raises(CalibrationError, match="expected_size"):
            read_pair(tmp_path / "l.png", tmp_path / "r2.png", expected_size=bad)
    with pytest.raises(ImageInputError, match="channels"):
        check_pair(_img(), _img(c=3))
    # the same view twice: zero disparity, no candidate at all -- refused (read as a pair before)
    write_image(tmp_path / "copy.png", _img(48, 64))
    for right in ("l.png", "copy.png"):
        with pytest.raises(ImageInputError, match="are the same image"):
            read_pair(tmp_path / "l.png", tmp_path / right)


@pytest.mark.parametrize("bad, match", [
    (np.zeros((0, 5), np.uint8), "empty"),
    (np.zeros((4, 4, 2), np.uint8), "shape"),
    (np.full((4, 4), np.nan), "NaN"),
    (np.zeros((4, 4), bool), "pixel type"),
    ([[1, 2]], "numpy image"),
])
def test_check_image_rejects(bad, match):
    with pytest.raises(ImageInputError, match=match):
        check_image(bad)


def test_read_thermal_keeps_depth_and_collapses_replicated_gray(tmp_path):
    t16 = (np.arange(48 * 64, dtype=np.uint16).reshape(48, 64) * 7)
    write_image(tmp_path / "t16.png", t16)
    out = read_thermal(tmp_path / "t16.png")
    assert out.dtype == np.uint16
    np.testing.assert_array_equal(out, t16)
    g = _img()
    write_image(tmp_path / "t3.png", np.dstack([g, g, g]))
    out = read_thermal(tmp_path / "t3.png")
    assert out.ndim == 2
    np.testing.assert_array_equal(out, g)


def test_glob_images(tmp_path):
    for name in ("left2.png", "left1.png", "right1.png"):
        write_image(tmp_path / name, _img())
    files = glob_images(str(tmp_path / "left*.png"))
    assert [f.name for f in files] == ["left1.png", "left2.png"]
    with pytest.raises(InputFileError, match="no images matched"):
        glob_images(str(tmp_path / "nothing*.jpg"))


def test_glob_images_pairs_numbered_views_whatever_their_padding(tmp_path):
    """left1 ... left12 and right01 ... right12: sorted as text the pairs were (left1,
    right01), (left10, right02), ... and the stereo calibration blamed the cameras. In
    natural order each view pairs with its own number, in a folder or through a pattern."""
    (tmp_path / "L").mkdir()
    for k in range(1, 13):
        (tmp_path / "L" / f"left{k}.png").write_bytes(b"")
        (tmp_path / f"right{k:02d}.png").write_bytes(b"")
    lf = glob_images(tmp_path / "L")
    rf = glob_images(str(tmp_path / "right*.png"))
    num = [int(f.stem[4:]) for f in lf]
    assert num == list(range(1, 13))
    assert [int(f.stem[5:]) for f in rf] == num


def test_a_folder_s_hidden_files_are_no_images(tmp_path):
    """A folder copied from a Mac holds a .DS_Store: glob_images of the folder listed it
    (first, in natural order) where 'DIR/*' does not, and `hearsee calibrate --left DIR`
    failed on "DIR/.DS_Store: not a readable image" (or "4 left images but 3 right images"
    when only one folder had it). The folder now lists what 'DIR/*' lists: the 3 images."""
    for k in (1, 2, 3):
        write_image(tmp_path / f"left{k}.png", _img(seed=k))
    (tmp_path / ".DS_Store").write_bytes(b"\x00\x00\x00\x01Bud1")
    (tmp_path / ".left1.png.swp").write_bytes(b"")
    names = ["left1.png", "left2.png", "left3.png"]
    assert [f.name for f in glob_images(tmp_path)] == names
    assert [f.name for f in glob_images(str(tmp_path / "*"))] == names
    (tmp_path / "only").mkdir()  # (hidden files only: nothing, as for an empty folder)
    (tmp_path / "only" / ".DS_Store").write_bytes(b"")
    with pytest.raises(InputFileError, match="no images matched"):
        glob_images(tmp_path / "only")


def test_to_gray_names_colour_pixel_types_opencv_cannot_convert():
    """check_image accepts e.g. float64 or int32 colour images, but cv2.cvtColor raised a bare
    cv2.error on them (reached through compute_disparity and find_corners)."""
    for dtype in (np.float64, np.float16, np.int8, np.int32, np.int64, np.uint32):
        for c in (3, 4):
            with pytest.raises(ImageInputError, match=f"unsupported pixel type {np.dtype(dtype)}"):
                to_gray(np.zeros((4, 4, c), dtype))
    for dtype in (np.uint8, np.uint16, np.float32):
        assert to_gray(np.zeros((4, 4, 3), dtype)).shape == (4, 4)
    assert to_gray(np.zeros((4, 4), np.float64)).dtype == np.float64  # grey kept as it is
    from hearsee.vision.stereo import compute_disparity

    bgr = np.zeros((48, 64, 3))
    with pytest.raises(ImageInputError, match="float64"):
        compute_disparity(bgr, bgr)


def test_write_image_unknown_format_is_an_image_input_error(tmp_path):
    """The docstring promises ImageInputError "when OpenCV cannot" encode; an unknown suffix
    (``hearsee detect --overlay out.txt``) raised a bare cv2.error, a CLI traceback, and wrote
    nothing."""
    with pytest.raises(ImageInputError, match=r"out\.txt.*\.txt"):
        write_image(tmp_path / "out.txt", _img())
    assert list(tmp_path.iterdir()) == []
    # a folder where the file should go: a bare OSError (IsADirectoryError) before; then
    # "cannot write the image (Is a directory)"; now config.output_file's wording
    (tmp_path / "taken.png").mkdir()
    with pytest.raises(InputFileError, match=r"taken\.png: is a folder, expected an output "
                                             "file name$"):
        write_image(tmp_path / "taken.png", _img())
    assert (tmp_path / "taken.png").is_dir()


def test_write_image_checks_its_path_as_every_output_does(tmp_path):
    """write_image had its own parent check: a FILE where the folder should be was reported
    as "folder D does not exist". It is config.output_file now (the one output-path check),
    whose messages say what is wrong."""
    (tmp_path / "f").write_text("a file", encoding="utf-8")
    with pytest.raises(InputFileError, match=r"x\.png: .*f is not a folder$"):
        write_image(tmp_path / "f" / "x.png", _img())
    with pytest.raises(InputFileError, match=r"x\.png: folder .*no does not exist$"):
        write_image(tmp_path / "no" / "x.png", _img())
    assert write_image(tmp_path / "x.png", _img()) == tmp_path / "x.png"


def _jpeg_with_orientation(img: np.ndarray, orientation: int) -> bytes:
    """``img`` as a JPEG (quality 98) with an EXIF APP1 segment holding only the orientation
    tag (0x0112, SHORT) = ``orientation`` (3: rotate 180 deg to display, 6: 90 deg)."""
    import struct

    data = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 98])[1].tobytes()
    ifd = struct.pack("<H", 1) + struct.pack("<HHIHH", 0x0112, 3, 1, orientation, 0) + \
        struct.pack("<I", 0)
    app1 = b"Exif\x00\x00" + b"II*\x00" + struct.pack("<I", 8) + ifd
    return data[:2] + b"\xff\xe1" + struct.pack(">H", len(app1) + 2) + app1 + data[2:]


@pytest.mark.parametrize("orientation", [3, 6])
def test_every_read_mode_gives_a_jpeg_s_pixels_as_stored(tmp_path, orientation):
    """'gray' and 'bgr' applied a JPEG's EXIF orientation and 'unchanged' (read_thermal)
    did not: calibration (grey) and detection (read_thermal) saw the same file 180 deg apart
    (orientation 6: 90 deg, transposed sizes). Every mode now gives the stored pixels: a ramp
    dark at the left, bright at the right, 64x48."""
    ramp = np.tile((np.arange(64) * 4).astype(np.uint8), (48, 1))
    path = tmp_path / "exif.jpg"
    path.write_bytes(_jpeg_with_orientation(np.dstack([ramp] * 3), orientation))
    stored = cv2.imdecode(np.fromfile(str(path), np.uint8), cv2.IMREAD_UNCHANGED)
    assert stored.shape == (48, 64, 3)  # ground truth: the pixels in the file
    gray, bgr = read_image(path, "gray"), read_image(path, "bgr")
    unchanged, thermal = read_image(path, "unchanged"), read_thermal(path)
    np.testing.assert_array_equal(bgr, stored)
    np.testing.assert_array_equal(unchanged, stored)
    assert gray.shape == thermal.shape == (48, 64)
    assert np.abs(gray.astype(int) - ramp).max() <= 3
    assert np.abs(thermal.astype(int) - ramp).max() <= 3
    assert read_image(path, "gray", expected_size=(64, 48)).shape == (48, 64)


def test_read_thermal_refuses_a_false_colour_image(tmp_path):
    """A false-colour export (a palette over temperature) was converted to its luminance
    without a word: with JET the hottest pixels came back darker than warm ones (luminance
    peaks at rank 159 of 255). Colour files whose channels differ are refused; a grey image
    with a slight colour cast (channels 1-2 levels apart) is still read as grey."""
    ramp = np.tile(np.arange(256, dtype=np.uint8), (20, 1))  # temperature rank, cold -> hot
    for cmap in (cv2.COLORMAP_JET, cv2.COLORMAP_HOT, cv2.COLORMAP_INFERNO):
        write_image(tmp_path / "false.png", cv2.applyColorMap(ramp, cmap))
        with pytest.raises(ImageInputError, match=r"false\.png: a colour thermal image"):
            read_thermal(tmp_path / "false.png")
    jet16 = cv2.applyColorMap(ramp, cv2.COLORMAP_JET).astype(np.uint16) * 257
    write_image(tmp_path / "false16.png", jet16)
    with pytest.raises(ImageInputError, match="colour thermal image"):
        read_thermal(tmp_path / "false16.png")
    cast = np.dstack([ramp, ramp, ramp]).astype(np.int16)
    cast[:, :, 0] += 2  # a bluish grey
    cast[:, :, 2] -= 1
    write_image(tmp_path / "cast.png", np.clip(cast, 0, 255).astype(np.uint8))
    out = read_thermal(tmp_path / "cast.png")
    assert out.shape == (20, 256) and np.all(np.diff(out[0].astype(int)) >= 0)
    # a grey export with a red crosshair (2 % of the pixels) is a grey image: read, and its
    # grey pixels are the ramp (the largest channel difference alone refused it)
    marked = cv2.cvtColor(np.tile(np.arange(256, dtype=np.uint8), (60, 1)), cv2.COLOR_GRAY2BGR)
    marked[29:31, 100:156] = (0, 0, 255)
    marked[10:50, 127:129] = (0, 0, 255)
    write_image(tmp_path / "marked.png", marked)
    out = read_thermal(tmp_path / "marked.png")
    assert out.shape == (60, 256) and np.array_equal(out[0], np.arange(256))


@pytest.mark.parametrize("name, image", [
    ("f32.png", np.linspace(0.0, 1.0, 12, dtype=np.float32).reshape(3, 4)),  # all 0 back
    ("f32.png", np.linspace(20.0, 40.0, 12, dtype=np.float32).reshape(3, 4)),  # rounded
    ("u16.jpg", np.arange(12, dtype=np.uint16).reshape(3, 4) * 5000),  # clipped at 255
    ("i16.png", np.arange(12, dtype=np.int16).reshape(3, 4) * 1000 - 5000),  # negatives 0
    ("i32.png", np.arange(12, dtype=np.int32).reshape(3, 4) * 100000),
    ("u16.webp", np.arange(12 * 3, dtype=np.uint16).reshape(3, 4, 3) * 1000),
])
def test_write_image_refuses_a_pixel_type_the_format_cannot_hold(tmp_path, name, image):
    """OpenCV's encoders wrote what they cannot hold as 8 bits without a word (a float32
    0..1 image as all 0, uint16 in a JPEG clipped at 255, negative int16 as 0): the file read
    back other numbers than were written. Nothing is written now."""
    with pytest.raises(ImageInputError, match=f"cannot hold {image.dtype} pixels"):
        write_image(tmp_path / name, image)
    assert list(tmp_path.iterdir()) == []


_GREY = np.arange(16 * 20, dtype=np.uint8).reshape(16, 20)


@pytest.mark.parametrize("name, image", [
    ("grey.sr", _GREY),  # (Sun raster: read back all 0)
    ("grey.ras", _GREY),
    ("bgra.sr", np.dstack([_GREY, _GREY, _GREY, _GREY])),  # (its alpha dropped)
    ("neg.hdr", np.array([[-5.0, 1.0, 20.5, 36.6]], np.float32)),  # (negatives 0; rounded)
])
def test_write_image_refuses_a_format_that_would_change_the_values(tmp_path, name, image):
    """The pixel type of the file read back was checked, not its values: a grey uint8 image
    written as .sr read back as uint8 -- all 0 --, a float32 map of degC as .hdr read back
    float32 with -5 as 0 and 36.6 as 36.5, a BGRA image as .sr without its alpha. Nothing
    is written now; what reads back as written still is, a grey image also where the format
    stores three equal channels (.webp, .hdr)."""
    with pytest.raises(ImageInputError, match="does not keep this image's pixel values"):
        write_image(tmp_path / name, image)
    assert list(tmp_path.iterdir()) == []
    for ok_name, ok in (("grey.webp", _GREY), ("bgr.sr", np.dstack([_GREY, _GREY // 2, _GREY])),
                        ("ones.hdr", np.array([[0.5, 1.0, 2.0, 4.0]], np.float32))):
        back = read_image(write_image(tmp_path / ok_name, ok), "unchanged")
        np.testing.assert_array_equal(back if back.ndim == ok.ndim else back[:, :, 0], ok)


@pytest.mark.parametrize("name, image", [
    ("u16.png", np.arange(12, dtype=np.uint16).reshape(3, 4) * 5000),
    ("u16.pgm", np.arange(12, dtype=np.uint16).reshape(3, 4) * 5000),
    ("f32.tif", np.linspace(20.0, 40.0, 12, dtype=np.float32).reshape(3, 4)),
    ("f64.tif", np.linspace(20.0, 40.0, 12).reshape(3, 4)),
    ("i16.tif", np.arange(12, dtype=np.int16).reshape(3, 4) * 1000 - 5000),
    ("bgr.png", np.arange(36, dtype=np.uint8).reshape(3, 4, 3)),
])
def test_write_image_keeps_a_pixel_type_the_format_holds(tmp_path, name, image):
    write_image(tmp_path / name, image)
    np.testing.assert_array_equal(read_image(tmp_path / name, "unchanged"), image)


def _tiff(img: np.ndarray, orientation: int | None = None) -> bytes:
    """An uncompressed little-endian TIFF of ``img`` ((H, W) or (H, W, 2) unsigned integers,
    interleaved samples, minimum-is-black, one strip; a second sample is an unspecified
    extra sample), with an Orientation tag (274) when ``orientation`` is given."""
    import struct

    h, w = img.shape[:2]
    spp, bits = (1 if img.ndim == 2 else img.shape[2]), img.dtype.itemsize * 8
    data = np.ascontiguousarray(img).astype(img.dtype.newbyteorder("<")).tobytes()
    turn = [] if orientation is None else [(274, 3, 1, orientation)]
    entries = [(256, 4, 1, w), (257, 4, 1, h), (258, 3, spp, bits), (259, 3, 1, 1),
               (262, 3, 1, 1), (273, 4, 1, 8), *turn, (277, 3, 1, spp), (278, 4, 1, h),
               (279, 4, 1, len(data)), (284, 3, 1, 1)] + ([(338, 3, 1, 0)] if spp == 2 else [])
    ifd = struct.pack("<H", len(entries))
    for tag, kind, count, value in entries:
        packed = struct.pack("<I", value) if kind == 4 else struct.pack("<HH", value,
                                                                        value if count == 2
                                                                        else 0)
        ifd += struct.pack("<HHI", tag, kind, count) + packed
    return b"II*\x00" + struct.pack("<I", 8 + len(data)) + data + ifd + struct.pack("<I", 0)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
@pytest.mark.parametrize("orientation", [2, 3, 4, 5, 6, 7, 8])
def test_every_read_mode_gives_a_tiff_s_pixels_as_stored(tmp_path, orientation, dtype):
    """OpenCV's TIFF decoder turns or mirrors a TIFF by its Orientation tag whatever the read
    flags: a 64x48 TIFF tagged 6 came back 48x64 (turned 90 deg) in every mode, one tagged 3
    upside down, where a JPEG with the same EXIF tag gives its pixels as stored. Ground truth:
    the array written, distinct in every pixel (a 12-bit ramp for uint16)."""
    stored = (np.arange(48 * 64).reshape(48, 64) % (256 if dtype == np.uint8 else 4096)
              ).astype(dtype)
    path = tmp_path / "turned.tif"
    path.write_bytes(_tiff(stored, orientation))
    np.testing.assert_array_equal(read_image(path, "unchanged"), stored)
    np.testing.assert_array_equal(read_thermal(path), stored)
    grey = stored if dtype == np.uint8 else (stored >> 4).astype(np.uint8)  # (to_8_bits)
    np.testing.assert_array_equal(read_image(path, "gray"), grey)
    np.testing.assert_array_equal(read_image(path, "bgr"), np.dstack([grey] * 3))
    plain = tmp_path / "plain.tif"  # (no tag, or tag 1: as before)
    for tag in (None, 1):
        plain.write_bytes(_tiff(stored, tag))
        np.testing.assert_array_equal(read_image(plain, "unchanged"), stored)


def test_a_tiff_whose_depth_or_channels_opencv_drops_is_refused(tmp_path):
    """A 16-bit 2-channel TIFF (radiometric counts and a second plane) came back from
    read_thermal / read_image 'unchanged' as one uint8 channel (the counts' high bytes)
    without a word, though both promise the stored bit depth. A 16-bit 1-channel TIFF written
    the same way reads back exactly."""
    t16 = (np.arange(48 * 64, dtype=np.uint32).reshape(48, 64) * 20 + 1000).astype(np.uint16)
    one = tmp_path / "one.tif"
    one.write_bytes(_tiff(t16))
    np.testing.assert_array_equal(read_thermal(one), t16)
    two = tmp_path / "two.tif"
    two.write_bytes(_tiff(np.dstack([t16, t16 // 2])))
    with pytest.raises(ImageInputError, match=r"two\.tif: a TIFF of 2 channel\(s\) of 16 bits"):
        read_thermal(two)
    with pytest.raises(ImageInputError, match="2 channel"):
        read_image(two, "unchanged")
    assert read_image(two, "gray").dtype == np.uint8  # (grey asked for: converted, as before)


def test_a_corrupt_video_opens_without_a_word_on_stderr(tmp_path, capfd):
    """FFmpeg wrote "[mov,mp4,... @ 0x...] moov atom not found" to the process's stderr
    (descriptor 2, past OpenCV's log level) before hearsee's one-line "cannot be opened"."""
    p = tmp_path / "v.mp4"
    p.write_text("hello, not a video\n")
    cap = video_capture(str(p))
    assert not cap.isOpened()
    out, err = capfd.readouterr()
    assert out == "" and err == ""


@pytest.mark.parametrize("index", [-1, -5, True, np.int64(-1)])
def test_a_negative_or_bool_camera_index_is_refused(index):
    """-1 (OpenCV's "any camera") ended the interpreter with a segmentation fault where no
    backend answered; True was a raw cv2.error."""
    with pytest.raises(ConfigError, match="camera index must be a whole number >= 0"):
        video_capture(index)


def test_a_float_tiff_read_as_a_visible_image_is_named(tmp_path):
    """A float32 TIFF (a thermal frame in degC) given as a visible image was "corrupt or
    unsupported format"; it is read as stored with mode "unchanged"."""
    p = tmp_path / "t.tiff"
    t = np.random.default_rng(2).uniform(20, 35, (24, 32)).astype(np.float32)
    assert cv2.imwrite(str(p), t)
    for mode in ("gray", "bgr"):
        with pytest.raises(ImageInputError, match=r"holds floating-point pixels \(float32; "):
            read_image(p, mode)
    np.testing.assert_array_equal(read_image(p, "unchanged"), t)


def test_opencv_log_level_without_cv2_utils_logging(monkeypatch):
    """OpenCV 4.8 (pyproject's lower bound) has no ``cv2.utils.logging``, only
    ``cv2.getLogLevel`` / ``cv2.setLogLevel``: every image read was a ModuleNotFoundError
    there. The log is now set through whichever exists, and restored after the block."""
    import sys

    import cv2

    from hearsee.vision.io import _opencv_log

    level = {"now": 4}
    calls = []

    def set_level(v):
        calls.append(v)
        level["now"] = v

    monkeypatch.setitem(sys.modules, "cv2.utils.logging", None)  # (import: ImportError)
    monkeypatch.setattr(cv2, "getLogLevel", lambda: level["now"], raising=False)
    monkeypatch.setattr(cv2, "setLogLevel", set_level, raising=False)
    with _opencv_log("silent"):
        assert level["now"] == 0
    with _opencv_log("error"):
        assert level["now"] == 2
    assert calls == [0, 4, 2, 4] and level["now"] == 4


def test_sixteen_bit_images_keep_their_significant_bits(tmp_path):
    """A 12-bit camera's frames in 16-bit PNGs, read as grey or colour: OpenCV kept the top 8 of
    16 bits (0-15 of 0-255); now shifted by the bits in use -- the 8-bit pixels exactly. A pair
    whose views differ in brightness gets one shift (the same gain); 8-bit values in a 16-bit
    file are kept; a float TIFF is named, not read."""
    g = _img(48, 64)
    c = _img(48, 64, c=3, seed=1)
    cv2.imwrite(str(tmp_path / "g12.png"), g.astype(np.uint16) << 4)
    cv2.imwrite(str(tmp_path / "c12.png"), c.astype(np.uint16) << 4)
    np.testing.assert_array_equal(read_image(tmp_path / "g12.png", "gray"), g)
    np.testing.assert_array_equal(read_image(tmp_path / "c12.png", "bgr"), c)
    # (grey from 16-bit colour, then shifted: the 8-bit conversion's value or one below)
    diff = cv2.cvtColor(c, cv2.COLOR_BGR2GRAY).astype(int) - read_image(tmp_path / "c12.png",
                                                                         "gray")
    assert set(np.unique(diff)) <= {0, 1}
    assert read_image(tmp_path / "g12.png", "unchanged").dtype == np.uint16
    cv2.imwrite(str(tmp_path / "g8in16.png"), g.astype(np.uint16))
    np.testing.assert_array_equal(read_image(tmp_path / "g8in16.png", "gray"), g)
    # a darker right view (its brightest pixel below 2048): the left view's shift, not its own
    dark = (g // 2).astype(np.uint16) << 4
    cv2.imwrite(str(tmp_path / "dark12.png"), dark)
    L, R = read_pair(tmp_path / "g12.png", tmp_path / "dark12.png")
    np.testing.assert_array_equal(L, g)
    np.testing.assert_array_equal(R, g // 2)
    a, b = to_8_bits(g.astype(np.uint16) << 4, dark)
    assert np.array_equal(a, g) and np.array_equal(b, g // 2)
    assert to_8_bits(g)[0] is g  # (8-bit images as they are)
    t = np.random.default_rng(2).uniform(20, 35, (24, 32)).astype(np.float32)
    assert cv2.imwrite(str(tmp_path / "t.tiff"), t)
    with pytest.raises(ImageInputError, match="floating-point pixels"):
        read_pair(tmp_path / "t.tiff", tmp_path / "t.tiff")


def test_to_8_bits_refuses_what_is_no_image():
    """None was an AttributeError."""
    from hearsee.errors import ImageInputError
    from hearsee.vision.io import to_8_bits

    with pytest.raises(ImageInputError, match="to_8_bits"):
        to_8_bits(np.zeros((2, 2), np.uint8), None)
    out = to_8_bits(np.full((2, 2), 4095, np.uint16), np.zeros((2, 2), np.uint16))
    assert out[0].dtype == np.uint8 and out[0].max() == 255


@pytest.mark.parametrize("mode", ["gray", "bgr", "unchanged"])
def test_an_openexr_file_is_one_typed_error_and_nothing_on_stderr(tmp_path, capfd, mode):
    """OpenEXR (a float format thermal and depth images come in): OpenCV's wheels build the
    codec but disable it, and cv2.imdecode raised cv2.error -- a traceback from read_image,
    read_thermal, load_thermal, `hearsee detect --thermal t.exr` and `hearsee calibrate`.
    Now an ImageInputError naming the file and the reason, stderr kept quiet. (A file with
    OpenEXR's magic number is enough to choose the codec; with the codec enabled it is
    "not a readable image".)"""
    from hearsee.vision.thermal import load_thermal

    path = tmp_path / "t.exr"
    path.write_bytes(bytes([0x76, 0x2F, 0x31, 0x01, 2, 0, 0, 0]) + bytes(100))
    capfd.readouterr()
    for read in (lambda p: read_image(p, mode), read_thermal, load_thermal):
        with pytest.raises(ImageInputError, match=r"t\.exr: (OpenCV cannot decode this image "
                                                  r"\(.*OpenEXR|not a readable image)"):
            read(path)
    assert capfd.readouterr().err == ""


def test_an_image_beyond_opencv_s_pixel_limit_is_one_typed_error(tmp_path):
    """A PNG whose header claims 60000 x 60000 pixels (beyond OpenCV's CV_IO_MAX_IMAGE_PIXELS):
    cv2.imdecode raised cv2.error's "(-215:Assertion failed)", a traceback. Now an
    ImageInputError naming the file and the limit."""
    import struct
    import zlib

    def chunk(kind: bytes, body: bytes) -> bytes:
        return (struct.pack(">I", len(body)) + kind + body
                + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))

    ihdr = struct.pack(">IIBBBBB", 60000, 60000, 8, 0, 0, 0, 0)
    path = tmp_path / "huge.png"
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
                     + chunk(b"IDAT", zlib.compress(bytes(60001))) + chunk(b"IEND", b""))
    with pytest.raises(ImageInputError, match=r"huge\.png: OpenCV cannot decode this image "
                                              r"\(its header claims more pixels than OpenCV's "
                                              r"limit, CV_IO_MAX_IMAGE_PIXELS\)$"):
        read_image(path)


def test_glob_images_takes_names_with_digits_no_decimal(tmp_path):
    """'²' is a digit to str.isdigit but no decimal digit to the natural order's split: a
    name such as take1²0 made int('²') raise a builtin ValueError (a traceback). Such a part
    is text; the numbers still sort as numbers."""
    for name in ("take1²0.png", "take10.png", "take2.png"):
        (tmp_path / name).write_bytes(b"")
    assert [f.name for f in glob_images(tmp_path)] == ["take1²0.png", "take2.png",
                                                       "take10.png"]
