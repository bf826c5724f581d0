"""Every example script answers --help with its usage and writes nothing (before, some took
"--help" for their output path); the quick ones also run end to end."""

import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*.py"))


def test_examples_are_found():
    assert len(EXAMPLES) >= 10


@pytest.mark.parametrize("script", EXAMPLES, ids=lambda p: p.stem)
def test_example_help(script, tmp_path):
    r = subprocess.run([sys.executable, str(script), "--help"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("usage:")
    assert list(tmp_path.iterdir()) == []


# The quick examples run end to end (under ~15 s each on the 2-core CI machine): exit 0 and
# write the figures and tables their docstrings name, each a real (non-blank) image or a
# markdown table. The slow ones (ch4_active ~35 s, ch5_tracking ~75 s even with --quick,
# ch6_patches / ch6_two_rolls ~12 s each) are left to their --help test above.
RUNS = {
    "ch2_geometry": ([], ["fig2_3_hyperboloids.png", "fig2_6_three_mic_curve.png",
                          "table2_1_differential_time.md", "table2_1_differential_time.png"]),
    "ch3_mask": (["--trials", "2"], ["fig3_02_mask.png", "fig3_09_itd_iid.png",
                                     "fig3_12_front_back.png", "tables_3_3_3_4.md"]),
    "ch6_swiss_roll": ([], ["ch6_neighbour_counts.png", "ch6_neighbourhood.png",
                            "ch6_swiss_roll.png"]),
    "ch6_faces": ([], ["ch6_head_pose.png", "ch6_lfw.png"]),
    "ch6_motion": ([], ["ch6_motion.png"]),
    "ch7_humans": ([], ["ch7_humans.png"]),
    "two_talkers": ([], ["two_talkers.png"]),
}


def _check_output(path: Path) -> None:
    assert path.is_file() and path.stat().st_size > 0, path
    if path.suffix == ".png":
        import matplotlib.image as mpimg

        img = mpimg.imread(path)
        assert img.ndim == 3 and min(img.shape[:2]) >= 100, (path, img.shape)
        assert float(img[..., :3].std()) > 0.01, f"{path.name} is blank"
    else:
        rows = [r for r in path.read_text().splitlines() if r.startswith("|")]
        assert len(rows) >= 3, f"{path.name} holds no table"


@pytest.mark.parametrize("name", sorted(RUNS))
def test_example_runs(name, tmp_path):
    args, outputs = RUNS[name]
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, str(EXAMPLES[0].parent / f"{name}.py"), *args,
                        "--out", str(out)], cwd=tmp_path, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    for f in outputs:
        _check_output(out / f)


def test_ch7_humans_runs(tmp_path):
    fig = tmp_path / "humans.png"
    r = subprocess.run([sys.executable, str(EXAMPLES[0].parent / "ch7_humans.py"),
                        "--figure", str(fig)], cwd=tmp_path, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    _check_output(fig)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["humans.png"]


def test_make_example_recording_reproduces_the_bundled_example(tmp_path):
    """Written into a folder that does not exist yet, the recording equals the bundled one (to
    one 16-bit step, for other machines' floating-point rounding), and so does its truth."""
    import json

    import numpy as np
    import soundfile as sf

    from hearsee.sim.audio import example_recording_path

    wav = tmp_path / "new" / "rec.wav"
    r = subprocess.run([sys.executable, str(EXAMPLES[0].parent / "make_example_recording.py"),
                        str(wav)], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    bundled = example_recording_path()
    x, fs = sf.read(wav, dtype="int16")
    ref, fs_ref = sf.read(bundled, dtype="int16")
    assert fs == fs_ref and x.shape == ref.shape
    diff = np.abs(x.astype(int) - ref)
    assert diff.max() <= 1 and np.mean(diff > 0) < 1e-3
    truth = json.loads(wav.with_suffix(".json").read_text())
    ref_truth = json.loads(bundled.with_suffix(".json").read_text())
    assert truth.pop("wav") == "rec.wav"
    ref_truth.pop("wav")
    gain, ref_gain = truth.pop("gain"), ref_truth.pop("gain")
    _assert_close(truth, ref_truth)
    # The bundle was rendered with pyroomacoustics 0.10.1. 0.9.0 and 0.10.0 (pyproject's lower
    # bound and the next release) give the same 16-bit samples (checked above) and the same
    # truth, but the simulated signal's peak 6.4e-8 relative apart, and with it the
    # normalising gain (peak / max |x|): measured 2026-12-03, numpy 1.26.0, scipy 1.15.0.
    from importlib.metadata import version

    pra = tuple(int(v) for v in version("pyroomacoustics").split(".")[:3])
    if pra < (0, 10, 1) and gain != pytest.approx(ref_gain, rel=1e-9, abs=1e-15):
        pytest.xfail(f"pyroomacoustics {version('pyroomacoustics')} < 0.10.1: truth.gain "
                     f"{gain!r} vs the bundle's {ref_gain!r} (the samples agree)")
    _assert_close(gain, ref_gain, "truth.gain")


def _assert_close(a, b, where="truth"):
    if isinstance(b, dict):
        assert isinstance(a, dict) and a.keys() == b.keys(), where
        for k in b:
            _assert_close(a[k], b[k], f"{where}.{k}")
    elif isinstance(b, list):
        assert isinstance(a, list) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _assert_close(x, y, f"{where}[{i}]")
    elif isinstance(b, float):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-15), where
    else:
        assert a == b, where


@pytest.mark.parametrize("name, args, message", [
    ("ch2_geometry", ["--fs", "0"], "argument --fs: expected a sample rate > 0 (Hz), got '0'"),
    ("ch2_geometry", ["--fs", "-16000"], "expected a sample rate > 0 (Hz), got '-16000'"),
    ("ch2_geometry", ["--fs", "nan"], "expected a sample rate > 0 (Hz), got 'nan'"),
    ("ch3_mask", ["--trials", "0"], "argument --trials: expected a whole number >= 1, got '0'"),
    ("ch7_humans", ["--figure", "humans.pdf"], "--figure humans.pdf: OpenCV cannot write .pdf"),
    ("ch7_humans", ["--figure", "humans"], "OpenCV cannot write a file without a suffix"),
])
def test_example_refuses_bad_arguments(name, args, message, tmp_path):
    """Refused before any work, in one usage line (exit 2): --fs 0 was a ZeroDivisionError,
    NaN a numpy ValueError and a negative rate a table whose -7 samples were +437.5 us;
    --trials 0 tables of nan means; ch7's --figure without an image suffix a cv2.error
    traceback after every scene had been rendered and detected."""
    r = subprocess.run([sys.executable, str(EXAMPLES[0].parent / f"{name}.py"), *args,
                        "--out", str(tmp_path / "out")], cwd=tmp_path, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 2, r.stderr[-2000:]
    assert message in r.stderr and "Traceback" not in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_ch6_motion_unreadable_video_falls_back(tmp_path):
    """A --video that OpenCV reads no frames from is the generated sequence only, as a missing
    one (was NLE's ManifoldInputError traceback on the empty array)."""
    bad = tmp_path / "clip.avi"
    bad.write_text("not a video\n")
    r = subprocess.run([sys.executable, str(EXAMPLES[0].parent / "ch6_motion.py"), "--video",
                        str(bad), "--out", str(tmp_path / "out")], cwd=tmp_path,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "0 distinct frames read, too few for NLE: using the generated sequence only" in r.stdout
    _check_output(tmp_path / "out" / "ch6_motion.png")
