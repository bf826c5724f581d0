"""bench/mask.py's plumbing: the random streams of its free-field cells."""

import importlib.util
import sys
from pathlib import Path

import numpy as np

BENCH = Path(__file__).resolve().parents[1] / "bench"


def _mask_bench(monkeypatch):
    monkeypatch.setattr(sys, "path", list(sys.path))  # (the script puts bench/ first)
    spec = importlib.util.spec_from_file_location("bench_mask", BENCH / "mask.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_negative_snr_cell_has_a_random_stream(monkeypatch):
    """``--snrs=-5,0``: a negative SNR raised numpy's ValueError before any trial; the cells
    of SNRs >= 0 keep the streams of earlier runs."""
    mask = _mask_bench(monkeypatch)
    a = mask.cell_rng(3, "male", "near", -5.0).random(4)
    assert np.all(np.isfinite(a))
    assert not np.allclose(a, mask.cell_rng(3, "male", "near", 0.0).random(4))
    for snr in (0.0, 10.0, 20.0, 30.0):
        old = np.random.default_rng([3, 1, 1, int(snr)]).random(4)
        np.testing.assert_array_equal(mask.cell_rng(3, "male", "near", snr).random(4), old)
