"""The stream's output does not depend on the block size its input comes in (2026-12-02: the
per-frame GCC stage decided activity and noise over each batch of frames, so one WAV file gave
49 valid frames read in blocks of 1024 and 81 read whole)."""

import numpy as np
import pytest

from hearsee.audio.arrays import load_array
from hearsee.sim.moving import linear_trajectory, simulate_moving_recording
from hearsee.stream import pipeline as pl

FS = 16000


def _run(arr, x, block, cfg=None):
    ups = pl.StreamPipeline(arr, cfg).run(pl.ArraySource(x, FS, block))
    az = np.array([np.nan if u.azimuth_deg is None else u.azimuth_deg for u in ups])
    raw = np.array([np.nan if u.raw_azimuth_deg is None else u.raw_azimuth_deg for u in ups])
    return np.array([u.t for u in ups]), az, raw


@pytest.mark.parametrize("signal,snr_db,method", [("male", 10.0, "phat"), ("noise", 10.0, "phat"),
                                                  ("male", 10.0, "ml")])
def test_stream_output_does_not_depend_on_block_size(signal, snr_db, method):
    arr = load_array("three-mic")
    traj = linear_trajectory([0.5, 2.0, 0.3], [0.0, -1.0, 0.0], 1.5)
    x, _ = simulate_moving_recording(arr, traj, signal, fs=FS, snr_db=snr_db, seed=3)
    cfg = pl.StreamConfig(method=method)
    t0, az0, raw0 = _run(arr, x, x.shape[1], cfg)  # the whole file as one block
    assert np.isfinite(raw0).sum() >= 10 and np.isfinite(az0).sum() >= 10
    for block in (333, 1024, 4096):
        t, az, raw = _run(arr, x, block, cfg)
        np.testing.assert_array_equal(t, t0)
        # the same frames measured, the same directions (float32 rounding of the batch
        # products: ~1e-5 deg)
        np.testing.assert_array_equal(np.isnan(raw), np.isnan(raw0))
        np.testing.assert_array_equal(np.isnan(az), np.isnan(az0))
        np.testing.assert_allclose(raw, raw0, atol=1e-3, equal_nan=True)
        np.testing.assert_allclose(az, az0, atol=1e-3, equal_nan=True)


@pytest.mark.parametrize("cfg", [pl.StreamConfig(), pl.StreamConfig(snr_weight=True),
                                 pl.StreamConfig(method="scot")])
def test_frame_gcc_is_causal_and_batch_free(cfg):
    """FrameGcc on the frames of a recording split into batches anywhere gives the TDOAs of
    one call on all of them, and frame k's result does not change with the frames after it
    (with the SNR weighting's noise spectrum, and SCOT's statistics averaged over frames)."""
    arr = load_array("three-mic")
    rng = np.random.default_rng(5)
    n_frames, L, hop = 40, 1024, 512
    x = 0.01 * rng.standard_normal((3, L + (n_frames - 1) * hop))
    s = rng.standard_normal(x.shape[1])
    for a, b in ((3000, 7000), (12000, 15000)):  # two bursts, known delays (3, 0, 1 samples)
        for ch, d in enumerate((3, 0, 1)):
            x[ch, a:b] += s[a + d:b + d]
    ref, ref_c = pl.FrameGcc(arr, FS, cfg)(x, n_frames)
    assert np.isfinite(ref).all(axis=1).sum() >= 8 and np.isnan(ref).any()
    for cuts in ((1, 2, 3, 7, 20, 33), (13,), tuple(range(1, n_frames))):
        gcc = pl.FrameGcc(arr, FS, cfg)
        got, got_c = [], []
        for f0, f1 in zip((0, *cuts), (*cuts, n_frames), strict=True):
            seg = x[:, f0 * hop: (f1 - 1) * hop + L]
            td, c = gcc(seg, f1 - f0)
            got.append(td)
            got_c.append(c)
        got = np.concatenate(got)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(ref))
        np.testing.assert_allclose(got, ref, atol=1e-8, equal_nan=True)
        np.testing.assert_allclose(np.concatenate(got_c), ref_c, rtol=1e-5, atol=1e-6)
    # causal: the first 20 frames alone give the first 20 results
    head, _ = pl.FrameGcc(arr, FS, cfg)(x[:, : 19 * hop + L], 20)
    np.testing.assert_allclose(head, ref[:20], atol=1e-8, equal_nan=True)
    ok = np.isfinite(ref).all(axis=1)
    want = np.array([-3.0 + 0.0, -3.0 + 1.0, 0.0 + 1.0])  # t_i - t_j, t_k = -d_k
    np.testing.assert_allclose(np.median(ref[ok], axis=0) * FS, want, atol=0.3)


def test_frame_gcc_takes_estimate_tdoas_window_and_margin_from_one_place():
    """FrameGcc repeated estimate_tdoas' defaults as literals (a 1-sample lag margin, a Tukey
    25 % window) to size its transforms and noise spectra: a change of one default would have
    left the stream's noise spectra of other frames. Both now come from the module constants
    that estimate_tdoas' signature uses."""
    import inspect

    from hearsee.audio.tdoa import (
        DEFAULT_MARGIN_SAMPLES,
        DEFAULT_WINDOW,
        _window,
        estimate_tdoas,
        gcc_nfft,
    )

    params = inspect.signature(estimate_tdoas).parameters
    assert params["window"].default is DEFAULT_WINDOW == ("tukey", 0.25)
    assert params["margin_samples"].default is DEFAULT_MARGIN_SAMPLES == 1.0
    arr = load_array("three-mic")
    gcc = pl.FrameGcc(arr, FS, pl.StreamConfig())
    np.testing.assert_array_equal(gcc.activity.win, _window(DEFAULT_WINDOW, gcc.frame_len))
    lag = arr.max_tdoa(arr.pairs) * FS + DEFAULT_MARGIN_SAMPLES
    assert gcc.activity.nfft == gcc_nfft(gcc.frame_len, float(lag.max()))


def test_stream_output_does_not_depend_on_the_recordings_scale():
    """Float recordings beyond single precision's range: at 1e200 the stages' float32 made
    every sample infinite ("recording contains NaN or infinite samples", `hearsee track` of a
    float64 WAV), at 1e-300 zero (no source). ArraySource scales such a recording by a power
    of two: the directions are those of the recording at its own scale."""
    arr = load_array("three-mic")
    traj = linear_trajectory([0.5, 2.0, 0.3], [0.0, -1.0, 0.0], 1.0)
    x, _ = simulate_moving_recording(arr, traj, "noise", fs=FS, snr_db=20.0, seed=345)
    t0, az0, _ = _run(arr, x, 2048)
    assert np.isfinite(az0).sum() >= 10
    for gain in (1e200, 1e-300):
        t, az, _ = _run(arr, gain * x, 2048)
        assert np.array_equal(t, t0) and np.array_equal(np.isfinite(az), np.isfinite(az0))
        np.testing.assert_allclose(az[np.isfinite(az)], az0[np.isfinite(az0)], atol=1e-3)
