"""OpenCV's HOG people detector on small images: one rule, in vision.humans.detect_people_hog,
for the HOG baseline and the stream's image-point detector (stream.video.detect_source_point).

An image in which no 64x128 detection window fits, even with the search's 8-pixel padding on
each side (under 48 pixels wide or 112 high), has no detection; OpenCV read and wrote past
its buffers there. The baseline refused every image under 64x128 (ImageInputError) while the
stream answered None from 48x112 down: the same frame was an error in one and a search or
"nobody" in the other."""

import subprocess
import sys

import numpy as np
import pytest

from hearsee.errors import ImageInputError
from hearsee.stream.video import detect_source_point
from hearsee.vision import humans
from hearsee.vision.humans import detect_people_hog


class _FakeHog:
    """Stands in for the shared HOG descriptor: records the image sizes it searched and finds
    two fixed boxes [x, y, w, h] (the second one the stronger)."""

    def __init__(self) -> None:
        self.searched: list[tuple[int, ...]] = []

    def detectMultiScale(self, img, **kw):  # noqa: N802 (OpenCV's name)
        self.searched.append(img.shape[:2])
        return np.array([[4, 2, 40, 100], [10, 6, 64, 128]]), np.array([[0.5], [1.5]])


@pytest.fixture
def fake_hog(monkeypatch):
    fake = _FakeHog()
    monkeypatch.setattr(humans, "hog_people_detector", lambda: fake)
    return fake


@pytest.mark.parametrize("shape", [(50, 40), (50, 40, 3), (40, 50, 1), (111, 300), (300, 47)])
def test_an_image_no_hog_window_fits_has_no_detection_in_both(fake_hog, shape):
    img = np.full(shape, 90, np.uint8)
    assert detect_people_hog(img) == []
    assert detect_source_point(img, "hog") is None
    assert fake_hog.searched == []  # OpenCV never sees it


@pytest.mark.parametrize("shape", [(112, 48), (112, 48, 3), (127, 63), (128, 64),
                                   (480, 640, 3)])
def test_an_image_a_padded_window_fits_is_searched_by_both(fake_hog, shape):
    img = np.full(shape, 90, np.uint8)
    assert detect_people_hog(img, shrink=False) == [([4, 2, 40, 100], 0.5),
                                                    ([10, 6, 64, 128], 1.5)]
    # the stream's point: 12 % down the strongest box, at its centre column
    assert detect_source_point(img, "hog") == (10 + 64 / 2.0, 6 + 0.12 * 128)
    assert fake_hog.searched == [shape[:2]] * 2


def test_small_images_with_opencvs_detector():
    """The real detector on the sizes around the rule (in a child process: OpenCV crashed on
    images smaller than its padded window)."""
    code = (
        "import numpy as np\n"
        "from hearsee.stream.video import detect_source_point as point\n"
        "from hearsee.vision.humans import detect_people_hog as hog\n"
        "for s in [(50, 40), (50, 40, 3), (10, 10), (111, 300), (300, 47), (112, 48),\n"
        "          (127, 64), (128, 63), (120, 100, 3), (160, 120)]:\n"
        "    img = np.full(s, 90, np.uint8)\n"
        "    assert hog(img) == [] and hog(img, win_stride=4) == [], s\n"
        "    assert point(img, 'hog') is None, s\n"
        "print('ok')\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-2000:]


def test_an_empty_image_is_an_error_in_both():
    for shape in [(0, 0), (0, 80, 3)]:
        with pytest.raises(ImageInputError, match="empty"):
            detect_people_hog(np.zeros(shape, np.uint8))
        with pytest.raises(ImageInputError, match="empty"):
            detect_source_point(np.zeros(shape, np.uint8), "hog")


def test_a_ragged_or_text_image_is_an_error_in_both():
    """A ragged list was numpy's builtin ValueError and an image of text reached the dtype
    test as '<U1'; both are ImageInputErrors naming what the detector needs."""
    for bad in ([[1, 2], [3]], [["a"] * 64] * 128):
        with pytest.raises(ImageInputError, match="HOG must hold numbers"):
            detect_people_hog(bad)
        with pytest.raises(ImageInputError):
            detect_source_point(bad, "hog")
