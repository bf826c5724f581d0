"""Live-input faults of the stream: a device source run twice, a device that goes silent, input
overflows, a late last block, dropped frames in the smoothed steered response, a camera that
stops, and the per-frame directions with the ITD filter.

The fake PortAudio here is synchronous: opening a stream calls the callback for all its blocks
at once (before the consumer reads any), so what the queue holds, drops and loses is known
exactly; channel 0 of every block is a ramp of the true sample index (ground truth for the
block starts and frame times)."""

import functools
import gc
import sys
import threading
import time
import types

import numpy as np
import pytest

from hearsee.audio.arrays import MicArray
from hearsee.errors import AudioInputError, ConfigError
from hearsee.geometry import wrap_deg
from hearsee.sim.moving import linear_trajectory, simulate_moving_free_field
from hearsee.stream import pipeline as pl
from hearsee.stream.pipeline import (
    ArraySource,
    DropoutSource,
    Framer,
    StreamConfig,
    StreamPipeline,
    TrackingProcessor,
)

FS = 16000
BL = 1024


class _Flags:
    """sounddevice.CallbackFlags look-alike."""

    def __init__(self, overflow):
        self.input_overflow = overflow

    def __bool__(self):
        return self.input_overflow


class _TimeInfo:
    def __init__(self, adc):
        self.inputBufferAdcTime = adc


def _fake_portaudio(blocks_per_open, lose=None, adc=True, close_error=None):
    """A sounddevice module whose k-th opened stream delivers ``blocks_per_open[k]`` blocks
    (``BL`` samples; channel 0 = true sample index, the others noise) when it is entered; before
    block i of ``lose`` (i: lost samples) PortAudio discards that many samples and flags the
    block ``input_overflow``. ``adc``: time_info carries inputBufferAdcTime (else 0, as host APIs
    without it report). ``close_error``: PortAudio's message when the stream stops (its exit
    raises PortAudioError, as sounddevice's stop() does)."""
    sd = types.ModuleType("sounddevice")
    sd.PortAudioError = type("PortAudioError", (Exception,), {})
    dev = {"name": "fake", "max_input_channels": 3}  # (the device list without arguments)
    sd.query_devices = lambda device=None, kind=None: (
        [dev] if device is None and kind is None else dev)
    opens = list(blocks_per_open)
    lose = dict(lose or {})

    class InputStream:
        n_entered = 0
        instances = []

        def __init__(self, device, channels, samplerate, blocksize, dtype, callback):
            self.cb, self.ch = callback, channels
            InputStream.instances.append(self)

        def __enter__(self):
            n = opens[InputStream.n_entered]
            InputStream.n_entered += 1
            rng = np.random.default_rng(InputStream.n_entered)
            s = 0
            for i in range(n):
                s += lose.get(i, 0)
                blk = rng.standard_normal((BL, self.ch)).astype(np.float32)
                blk[:, 0] = np.arange(s, s + BL)
                self.cb(blk, BL, _TimeInfo(10.0 + s / FS if adc else 0.0), _Flags(i in lose))
                s += BL
            return self

        def __exit__(self, *exc):
            InputStream.n_exited += 1
            if close_error is not None:
                raise sd.PortAudioError(close_error)
            return False

        n_exited = 0

    sd.InputStream = InputStream
    return sd


def _device(monkeypatch, sd, **kw):
    monkeypatch.setitem(sys.modules, "sounddevice", sd)
    kw = {"block_len": BL, "timeout_s": 0.05, **kw}
    return pl.DeviceSource(0, 3, FS, **kw)


def test_device_source_tells_the_second_of_audio_captured_now(monkeypatch):
    """``audio_time_now``: the end of the newest block plus the time since its capture --
    PortAudio's currentTime less the buffer's end where the host API gives both, else the
    stream's reported latency -- plus the time since its callback (a robot times its head's
    pose reads by it)."""
    src = _device(monkeypatch, _fake_portaudio([0]))
    now = [100.0]
    monkeypatch.setattr(pl.time, "perf_counter", lambda: now[0])
    assert src.audio_time_now() is None  # (no block yet)
    ti = _TimeInfo(5.0)
    ti.currentTime = 5.0 + BL / FS + 0.03  # (the callback 30 ms after the buffer's end)
    src._callback(np.zeros((BL, 3), np.float32), BL, ti, _Flags(False))
    assert src.audio_time_now() == pytest.approx(BL / FS + 0.03)
    now[0] += 0.25
    assert src.audio_time_now() == pytest.approx(BL / FS + 0.28)
    # a host API without times: the stream's reported input latency (here 50 ms)
    src._latency_s = pl._input_latency(types.SimpleNamespace(latency=0.05))
    src._callback(np.zeros((BL, 3), np.float32), BL, _TimeInfo(0.0), _Flags(False))
    assert src.audio_time_now() == pytest.approx(2 * BL / FS + 0.05)
    # times a host API fills inconsistently (the callback before the buffer's end, or a second
    # after it) and latencies that are no number >= 0 are not believed
    for current in (5.0, 5.0 + BL / FS + 2.0, float("nan")):
        ti.currentTime = current
        assert pl._capture_delay(ti, 5.0, BL, FS) is None
    for bad in (float("nan"), -0.01, (0.01, 0.02), None):
        assert pl._input_latency(types.SimpleNamespace(latency=bad)) == 0.0
    assert pl._input_latency(object()) == 0.0


# ------------------------------------------------------------------------- 1. reuse
def test_device_source_run_twice_starts_again_at_sample_zero(monkeypatch):
    """A second run of the same DeviceSource covers its own stream from sample 0: the blocks
    the first run left in the queue (past its duration) and its drop count are not carried
    over."""
    # run 1: 40 blocks at once into a 32-block queue (8 dropped), 8 used; run 2: 8 blocks
    src = _device(monkeypatch, _fake_portaudio([40, 8, 8]), duration_s=8 * BL / FS,
                  queue_size=32)
    pipe = StreamPipeline(MicArray.from_preset("three-mic"))
    pipe.run(src)
    assert pipe.stats.n_blocks == 8 and src.n_dropped == 8
    assert src._q.empty()  # drained when the stream closed
    pipe.run(src)
    st = pipe.stats
    assert st.n_blocks == 8 and st.n_dropped_blocks == 0 and st.n_missing_frames == 0
    assert st.n_frames == (8 * BL - 1024) // 512 + 1 and st.audio_s == 8 * BL / FS
    assert st.status == "ok"
    blocks = list(src.blocks())  # a third run, block by block
    assert [b.seq for b in blocks] == list(range(8))
    assert [b.start for b in blocks] == [int(b.data[0, 0]) for b in blocks] == list(
        range(0, 8 * BL, BL))


def test_device_source_runs_do_not_mix(monkeypatch):
    """A run abandoned mid-way (its generator not yet closed, its stream still open) while a
    new run starts: the old stream's late callbacks and the old generator's end touch nothing
    of the new run."""
    sd = _fake_portaudio([4, 8])
    src = _device(monkeypatch, sd, duration_s=8 * BL / FS)
    g1 = src.blocks()
    assert next(g1).seq == 0  # run 1: stream open, 3 blocks still queued
    g2 = src.blocks()
    first = next(g2)  # run 2 starts
    old_stream = sd.InputStream.instances[0]
    old_stream.cb(np.zeros((BL, 3), np.float32), BL, None, _Flags(True))  # late, overflowed
    g1.close()  # the old generator ends (and drains its own queue only)
    blocks = [first, *g2]
    assert [b.seq for b in blocks] == list(range(8))
    assert [b.start for b in blocks] == [int(b.data[0, 0]) for b in blocks]
    assert src.n_dropped == 0 and src.n_overflows == 0 and not src.stalled


# ------------------------------------------------------------------------- 2. dead device
@pytest.mark.parametrize("threaded", [False, True])
def test_device_that_goes_silent_ends_the_run_as_stalled(monkeypatch, threaded):
    """A device that stops delivering (10 blocks, then nothing) ends the run after its
    timeout_s with status "stalled", also behind a wrapper; one that reaches its duration
    ends "ok"."""
    src = _device(monkeypatch, _fake_portaudio([10, 10, 10]))
    pipe = StreamPipeline(MicArray.from_preset("three-mic"))
    pipe.run(src, threaded=threaded)
    assert pipe.stats.status == "stalled" and pipe.stats.n_blocks == 10 and src.stalled
    pipe.run(DropoutSource(src, drop=[3]), threaded=threaded)
    assert pipe.stats.n_blocks == 9 and pipe.stats.status == "stalled"
    src.duration_s = 10 * BL / FS
    pipe.run(src, threaded=threaded)
    assert not src.stalled and pipe.stats.status == "ok"


def test_track_cli_reports_a_dead_device_like_a_pipeline_stall(monkeypatch, capsys):
    """`hearsee track --device`: a device that goes silent ends with the stall warning on stderr
    (the end-of-run summary with "status stalled"), as a pipeline stall does, and exit code 1
    (as `hearsee run`); the updates printed before the stall stay."""
    from hearsee.cli import main

    monkeypatch.setitem(sys.modules, "sounddevice", _fake_portaudio([10]))
    monkeypatch.setattr(pl, "DeviceSource", functools.partial(pl.DeviceSource, timeout_s=0.05))
    assert main(["track", "--device", "0", "--array", "three-mic"]) == 1
    cap = capsys.readouterr()
    assert len(cap.out.splitlines()) == (10 * BL - 1024) // 512 + 1
    assert "status stalled" in cap.err and "stopped delivering" in cap.err


# ------------------------------------------------------------------------- 5. overflows
def _frames_follow_the_ramp(blocks, frame_len=1024):
    """Frame the blocks; every complete frame's samples must be consecutive sample indices
    (no frame straddles lost samples) and its time the true time of its centre."""
    fr = Framer(3, FS, 64, 32)
    n_missing = 0
    for b in blocks:
        batch = fr.push(b)
        if batch is None:
            continue
        n_missing += int(batch.missing.sum())
        if batch.segment is None:
            continue
        ok_t = batch.t[~batch.missing]
        for n, t in enumerate(ok_t):
            ramp = batch.segment[0, n * fr.hop: n * fr.hop + frame_len]
            np.testing.assert_array_equal(np.diff(ramp), 1.0)
            assert t == pytest.approx((ramp[0] + frame_len / 2) / FS)
    return fr, n_missing


def test_input_overflow_leaves_a_gap_at_the_adc_time(monkeypatch):
    """PortAudio discards 2048 samples before block 10 and flags it: the block (and all later
    ones) start at their true sample index (from inputBufferAdcTime), the framer sees a gap of
    two blocks, and the run reports the overflow."""
    sd = _fake_portaudio([20, 20], lose={10: 2048})
    src = _device(monkeypatch, sd, duration_s=(20 * BL + 2048) / FS)
    blocks = list(src.blocks())
    assert [b.start for b in blocks] == [int(b.data[0, 0]) for b in blocks]
    assert blocks[10].start == 12 * BL and blocks[10].seq == 12  # 2048 samples = 2 blocks
    assert src.n_overflows == 1 and src.n_dropped == 2
    fr, n_missing = _frames_follow_the_ramp(blocks)
    assert fr.n_dropped == 2 and n_missing > 0
    pipe = StreamPipeline(MicArray.from_preset("three-mic"))
    pipe.run(src)
    st = pipe.stats
    assert st.n_overflows == 1 and st.n_dropped_blocks == 2 and st.n_missing_frames == n_missing
    assert st.audio_s == (20 * BL + 2048) / FS


def test_input_overflow_without_adc_time_is_a_one_block_gap(monkeypatch):
    """Without inputBufferAdcTime the amount lost is unknown: the flagged block follows a gap of
    one block (a sequence gap and a sample gap), so that no frame mixes samples from before and
    after the loss; an overflow flag on the first block leaves no gap (nothing precedes it)."""
    sd = _fake_portaudio([20, 5], lose={0: 0, 10: 300}, adc=False)
    src = _device(monkeypatch, sd, duration_s=21 * BL / FS)
    blocks = list(src.blocks())
    assert blocks[0].start == 0 and blocks[0].seq == 0  # flagged first block: no gap
    assert [b.start for b in blocks[:10]] == list(range(0, 10 * BL, BL))
    assert [b.seq for b in blocks[10:]] == list(range(11, 21))
    assert [b.start for b in blocks[10:]] == list(range(11 * BL, 21 * BL, BL))
    assert src.n_overflows == 2 and src.n_dropped == 1
    fr, n_missing = _frames_follow_the_ramp([b for b in blocks[:10]])  # before: exact
    fr = Framer(3, FS, 64, 32)
    out = [fr.push(b) for b in blocks]
    assert fr.n_dropped == 1 and sum(int(o.missing.sum()) for o in out if o is not None) > 0
    for o in out:  # no complete frame straddles the 300 lost samples (ramp step != 1)
        if o is not None and o.segment is not None:
            for n in range(int((~o.missing).sum())):
                assert np.all(np.diff(o.segment[0, n * fr.hop: n * fr.hop + fr.frame_len]) == 1)


def test_track_cli_stats_report_input_overflows(monkeypatch, capsys):
    from hearsee.cli import main

    monkeypatch.setitem(sys.modules, "sounddevice", _fake_portaudio([20], lose={10: 2048}))
    assert main(["track", "--device", "0", "--array", "three-mic", "--duration",
                 str(20 * BL / FS), "--stats", "--format", "json"]) == 0
    cap = capsys.readouterr()
    assert "1 input overflows" in cap.err and "2 dropped" in cap.err
    import json

    assert json.loads(cap.out)["stats"]["input_overflows"] == 1


def test_device_duration_ends_at_its_sample(monkeypatch, capsys):
    """``duration_s`` ends the run's samples there, as MappedSource's does: the last block was
    yielded whole, up to a block past it -- ``hearsee track --device 0 --duration 1`` streamed
    1.024 s (31 frames) and the same with ``--channels 0,1,2`` 1.00 s (30 frames). After an
    overflow's gap past the limit no block is yielded."""
    import json

    from hearsee.cli import main

    src = _device(monkeypatch, _fake_portaudio([20]), duration_s=1.0)
    blocks = list(src.blocks())
    assert sum(b.data.shape[1] for b in blocks) == FS and blocks[-1].data.shape[1] == FS % BL
    src = _device(monkeypatch, _fake_portaudio([20], lose={5: 4 * BL}), duration_s=7 * BL / FS)
    assert [b.start for b in src.blocks()] == [0, BL, 2 * BL, 3 * BL, 4 * BL]
    frames = {}
    monkeypatch.setitem(sys.modules, "sounddevice", _fake_portaudio([20, 20]))
    for extra in ([], ["--channels", "0,1,2"]):
        assert main(["track", "--device", "0", "--array", "three-mic", "--duration", "1",
                     "--format", "json", *extra]) == 0
        frames[bool(extra)] = json.loads(capsys.readouterr().out)["stats"]
        assert frames[bool(extra)]["audio_s"] == 1.0
    assert frames[False]["frames"] == frames[True]["frames"] == (FS - 1024) // 512 + 1


# ------------------------------------------------------------------------- 7a. late last block
def test_dropout_source_delivers_a_late_last_block():
    y = np.random.default_rng(0).standard_normal((3, 10 * BL))
    for late in ([9], [8, 9]):
        src = DropoutSource(ArraySource(y, FS, BL), late=late)
        assert [b.seq for b in src.blocks()] == list(range(10))
        pipe = StreamPipeline("three-mic")
        pipe.run(DropoutSource(ArraySource(y, FS, BL), late=late))
        st = pipe.stats
        # nothing overtook the held blocks: in order, so used (not late, not dropped)
        assert st.n_blocks == 10 and st.n_late_blocks == 0 and st.n_dropped_blocks == 0
        assert st.audio_s == 10 * BL / FS and st.n_frames == (10 * BL - 1024) // 512 + 1


@pytest.mark.parametrize("threaded", [False, True])
def test_dropped_last_blocks_are_counted_and_their_frames_reported_missing(threaded):
    """Blocks dropped at the end of a stream leave no gap in the sequence numbers: they were
    counted nowhere (0 dropped blocks) and the frames needing them were left out, not reported
    missing (29 updates for the 30 frames of the file, n_missing_frames 0)."""
    n = 10 * BL + 300  # a partial last block
    y = np.random.default_rng(0).standard_normal((3, n))
    L, H = 1024, 512
    starts = np.arange(0, n - L + 1, H)
    for drop in ([10], [9, 10], [3, 10]):
        lost = [(b * BL, min((b + 1) * BL, n)) for b in drop]
        want_missing = [any(a < s0 + L and s0 < b for a, b in lost) for s0 in starts]
        pipe = StreamPipeline("three-mic")
        ups = pipe.run(DropoutSource(ArraySource(y, FS, BL), drop=drop), threaded=threaded)
        np.testing.assert_allclose([u.t for u in ups], (starts + L / 2) / FS)
        assert [u.missing for u in ups] == want_missing
        assert all(u.raw_azimuth_deg is None and not u.measured for u in ups if u.missing)
        st = pipe.stats
        assert st.n_dropped_blocks == len(drop) and st.n_late_blocks == 0
        assert st.n_frames == len(starts) and st.n_missing_frames == sum(want_missing)


# ------------------------------------------------------------------------- 3. SRP through gaps
def test_smoothed_srp_ages_its_evidence_through_dropped_frames():
    """Source at +60 deg for 1 s, 0.5 s of blocks dropped, then at -60 deg: no smoothed
    measurement after the gap may still point at +60 deg as if it were fresh (it is either the
    new direction, or old enough to be refused)."""
    arr = MicArray.from_preset("three-mic")
    rng = np.random.default_rng(0)
    a = simulate_moving_free_field(rng.standard_normal(2 * FS), FS, arr,
                                   linear_trajectory([1.0, 1.732, 0.0], [0, 0, 0], 2.0),
                                   snr_db=20, rng=1)
    b = simulate_moving_free_field(rng.standard_normal(2 * FS), FS, arr,
                                   linear_trajectory([1.0, -1.732, 0.0], [0, 0, 0], 2.0),
                                   snr_db=20, rng=2)
    y = np.concatenate([a[:, :FS + FS // 2], b[:, FS + FS // 2:]], axis=1)  # switch at 1.5 s
    cfg = StreamConfig()
    src = DropoutSource(ArraySource(y, FS, BL), drop=range(16, 24))  # 1.024-1.536 s lost
    fr = Framer(3, FS, cfg.frame_ms, cfg.hop_ms)
    proc = TrackingProcessor(arr, FS, cfg)
    after = []
    for blk in src.blocks():
        batch = fr.push(blk)
        if batch is None:
            continue
        sm = proc.smoothed(batch)
        for n, t in enumerate(batch.t):
            if t > 1.5 and not batch.missing[n]:
                after.append((proc._smoothed_candidates(sm, n), sm["age_frames"][n]))
    assert len(after) > 5
    for cands, _ in after:
        assert not cands or abs(wrap_deg(cands[0][0] + 60.0)) < 5.0
    assert after[0][0]  # the new direction is measured at once


def test_tracker_aided_detection_coasts_through_dropped_blocks():
    """With ``gated_min_coherence`` (``hearsee track --gate-coherence``) a block dropped once the
    track has coasted ``gated_after_s`` gave its missing frames the gated search, on evidence of
    NaN age: the prediction to a NaN time was an EstimationError that ended the run. Now the
    missing frames coast on the talker's direction (40 deg: 1 s of noise, then silence)."""
    arr = MicArray.from_preset("three-mic")
    rng = np.random.default_rng(0)
    sig = rng.standard_normal(2 * FS)
    sig[FS:] = 0.0
    x = simulate_moving_free_field(sig, FS, arr, linear_trajectory(
        [2.0 * np.cos(np.radians(40.0)), 2.0 * np.sin(np.radians(40.0)), 0.0], [0, 0, 0], 2.0),
        snr_db=30, rng=1)
    src = DropoutSource(ArraySource(x, FS, BL), drop=[25])  # 1.6-1.664 s: coasting since ~1.2 s
    ups = StreamPipeline(arr, StreamConfig(gated_min_coherence=0.3)).run(src)
    missing = [u for u in ups if u.missing]
    assert len(ups) == 61 and len(missing) == 3
    for u in missing:
        assert not u.measured and abs(wrap_deg(u.azimuth_deg - 40.0)) < 2.0


def test_smoothed_srp_skip_equals_silent_frames():
    """skip(n) does to the state what n frames of zeros do (the model: a missing frame adds no
    evidence): the same outputs afterwards; the evidence weight decays by alpha**n and its
    age grows by n."""
    arr = MicArray.from_preset("three-mic")
    frame_len, hop, n_gap = 1024, 512, 5
    rng = np.random.default_rng(4)
    seg1 = rng.standard_normal((3, frame_len + 7 * hop)).astype(np.float32)
    seg2 = rng.standard_normal((3, frame_len + 3 * hop)).astype(np.float32)
    zeros = np.zeros((3, frame_len + (n_gap - 1) * hop), np.float32)
    s_ref = pl.SmoothedSrp(arr, FS, frame_len, alpha=0.8)
    s_ref.process(seg1, 8, hop)
    s_ref.process(zeros, n_gap, hop)
    ref = s_ref.process(seg2, 4, hop)
    s = pl.SmoothedSrp(arr, FS, frame_len, alpha=0.8)
    s.process(seg1, 8, hop)
    w, age = s._evidence.energy, s._evidence.age
    s.skip(n_gap)
    assert s._evidence.energy == pytest.approx(w * 0.8**n_gap)
    assert s._evidence.age == pytest.approx(age + n_gap)
    got = s.process(seg2, 4, hop)
    np.testing.assert_allclose(got["age_frames"], ref["age_frames"], rtol=1e-6)
    s_no = pl.SmoothedSrp(arr, FS, frame_len, alpha=0.8)  # the same frames without the gap
    s_no.process(seg1, 8, hop)
    no_gap = s_no.process(seg2, 4, hop)
    assert got["age_frames"][0] > no_gap["age_frames"][0] + 1.0  # the gap made it older
    np.testing.assert_allclose(got["coherence"], ref["coherence"], rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(got["az_deg"], ref["az_deg"], atol=0.05)


# ------------------------------------------------------------------------- 7b. raw with ITD
def test_raw_directions_are_the_frames_own_also_with_the_itd_filter():
    arr = MicArray.from_preset("three-mic")
    traj = linear_trajectory([2.0, -1.0, 0.0], [0.0, 1.0, 0.0], 1.0)
    y = simulate_moving_free_field(np.random.default_rng(0).standard_normal(FS), FS, arr, traj,
                                   snr_db=15, rng=1)
    plain = StreamPipeline(arr, StreamConfig()).run(ArraySource(y, FS, 4096))
    itd = StreamPipeline(arr, StreamConfig(itd_filter=True)).run(ArraySource(y, FS, 4096))
    assert [u.raw_azimuth_deg for u in itd] == [u.raw_azimuth_deg for u in plain]
    assert [u.raw_elevation_deg for u in itd] == [u.raw_elevation_deg for u in plain]
    assert all(u.itd_azimuth_deg is None for u in plain)
    filt = [(u.raw_azimuth_deg, u.itd_azimuth_deg) for u in itd if u.itd_azimuth_deg is not None]
    assert len(filt) > 0.8 * len(itd)
    assert sum(abs(wrap_deg(r - f)) > 1e-6 for r, f in filt) > 0.5 * len(filt)


def test_frames_the_itd_gate_rejects_give_the_tracker_no_measurement():
    """The ITD filter's gate rejected a frame's TDOAs (an anomalous GCC peak) and the stream
    fed the filter's prediction to the direction tracker as that frame's measurement: the
    update said measured=True, the azimuth variance shrank and the max_coast_s timer restarted.
    TDOAs injected: a source at 30 deg for 20 frames, then peaks at -100 deg, which the filter
    rejects 4 times (its max_rejects 5 re-initialises on the 5th)."""
    arr = MicArray.from_preset("three-mic")
    proc = TrackingProcessor(arr, FS, StreamConfig(itd_filter=True, spectrum_alpha=0.0))

    def d(az):
        return np.array([np.cos(np.radians(az)), np.sin(np.radians(az)), 0.0])

    n = 26
    Z = np.tile(arr.tdoa_far(d(30.0), proc.pairs), (n, 1))
    Z[20:] = arr.tdoa_far(d(-100.0), proc.pairs)
    k = [0]
    proc.tdoas = lambda batch: (Z[k[0]][None], np.array([3.0]))
    ups, taken = [], []
    for k[0] in range(n):
        t = np.array([k[0] * 0.032])
        ups += proc.process(pl.FrameBatch(t, np.zeros(1, bool), None, 0.0))
        taken.append(proc.itd.last_accepted)
    assert all(taken[:20]) and not any(taken[20:24]) and taken[24]
    assert all(u.measured for u in ups[:20])
    var = [u.covariance[0][0] for u in ups]
    for u in ups[20:24]:
        assert not u.measured
        assert u.itd_azimuth_deg is None
        assert u.raw_azimuth_deg == pytest.approx(-100.0, abs=1e-6)
        assert u.azimuth_deg == pytest.approx(30.0, abs=1e-6)
    assert all(var[i + 1] > var[i] for i in range(19, 23))  # coasting
    assert proc._last_measured_t == pytest.approx(19 * 0.032)
    # the re-initialised filter's direction is taken again (it is the frame's own)
    assert ups[24].itd_azimuth_deg == pytest.approx(-100.0, abs=1e-6)


# ------------------------------------------------------------------------- 4. live camera
def test_live_camera_point_goes_stale_when_the_camera_stops(monkeypatch, fake_camera):
    """A live camera that delivers 5 frames with a detection, then hangs, then fails: the point
    is returned while its frame is fresh and None once it is older than two frame periods or
    the camera has ended (fake clock: 1/30 s per frame)."""
    import hearsee.stream.video as video

    now = [100.0]
    go, hang = threading.Event(), threading.Event()

    def next_frame() -> None:
        now[0] += 1 / 30

    # the first frame comes once the test has looked before it; after 5 frames the camera
    # hangs, then fails
    fake_camera(5, before_read=lambda: go.wait(10.0), on_frame=next_frame,
                on_end=lambda: hang.wait(10.0))
    monkeypatch.setattr(video, "detect_source_point", lambda img, det: (320.0, 240.0))
    vp = video.VideoImagePoints(0, detector="hog")
    vp._clock = lambda: now[0]
    try:
        assert vp(0.0) is None  # starts the thread; no frame yet
        go.set()
        for _ in range(500):
            if vp.frame_index == 4:
                break
            time.sleep(0.01)
        assert vp.frame_index == 4 and not vp.ended
        last = now[0]
        now[0] = last + 0.5 / 30
        assert vp(0.2) == (320.0, 240.0)
        now[0] = last + 3.0 / 30  # hung for three frame periods
        assert vp(0.3) is None
        hang.set()
        for _ in range(500):
            if vp.ended:
                break
            time.sleep(0.01)
        assert vp.ended
        now[0] = last + 0.5 / 30
        assert vp(0.2) is None  # ended: no current image whatever the clock says
    finally:
        go.set()
        hang.set()
        vp.close()


def test_a_live_camera_that_reports_no_frame_size_opens(monkeypatch, fake_camera):
    """A driver reporting CAP_PROP_FRAME_WIDTH / HEIGHT NaN: int(nan) was a builtin ValueError
    before the camera was used at all; a live camera's frames need no reported size."""
    import hearsee.stream.video as video

    fake_camera(2, size=float("nan"))
    monkeypatch.setattr(video, "detect_source_point", lambda img, det: (40.0, 30.0))
    vp = video.VideoImagePoints(0, detector="hog", expected_size=(80, 60))
    try:
        vp(0.0)  # starts the thread
        for _ in range(500):
            if vp.frame_index == 1:
                break
            time.sleep(0.01)
        assert vp.frame_index == 1 and vp.last_point == (40.0, 30.0)
    finally:
        vp.close()


@pytest.mark.parametrize("frame, want", [
    (np.zeros((60, 80, 3), np.uint8), "delivers 80x60 frames but the calibration expects "
                                      "160x120"),
    (np.zeros((120, 160), np.uint16), "the person detector needs an 8-bit grey, BGR or BGRA "
                                      "image, got shape (120, 160) uint16"),
])
def test_a_live_cameras_frames_the_calibration_or_detector_cannot_take_are_refused(
        monkeypatch, tmp_path, capsys, frame, want):
    """A live camera's frames are checked against the calibrated size as they come (its
    driver need not report one): 800x600 frames read through a 640x480 calibration put the
    3D fixes 1.75 m off, exit 0 and no word; a 16-bit camera's frame was the detector's
    ImageInputError as a traceback of the camera's thread, and the run went on
    direction-only. Now ``points(t)`` raises the ImageInputError and ``hearsee track --device
    --camera-device`` exits 2 with it, as a video file of another size and ``hearsee run``'s
    cameras are refused."""
    import re

    import cv2

    from hearsee.cli import main
    from hearsee.errors import ImageInputError
    from hearsee.stream.video import VideoImagePoints
    from hearsee.vision.camera import Camera, save_camera

    class Cap:
        def __init__(self, index):
            pass

        def isOpened(self):
            return True

        def get(self, prop):
            return 30.0 if prop == cv2.CAP_PROP_FPS else float("nan")

        def read(self):
            time.sleep(0.002)
            return True, frame

        def release(self):
            pass

    monkeypatch.setattr(cv2, "VideoCapture", Cap)
    vp = VideoImagePoints(0, detector="hog", expected_size=(160, 120))
    try:
        with pytest.raises(ImageInputError, match=re.escape(f"camera 0: {want}")):
            for _ in range(500):
                vp(0.01)  # (the first call starts the camera's thread)
                time.sleep(0.01)
    finally:
        vp.close()
    save_camera(Camera.from_fov(70.0, 160, 120), tmp_path / "cam.yaml")
    x = 0.1 * np.random.default_rng(0).standard_normal((3, FS))
    monkeypatch.setitem(sys.modules, "sounddevice", _fake_recorder(x))
    monkeypatch.setattr(pl, "StreamPipeline", _SlowStart)
    assert main(["track", "--device", "0", "--duration", "0.9", "--array", "three-mic",
                 "--camera", str(tmp_path / "cam.yaml"), "--camera-device", "0"]) == 2
    err = capsys.readouterr().err
    assert f"camera 0: {want}" in err and "Traceback" not in err


class _SlowStart(pl.StreamPipeline):
    """A stream whose first image point is asked for only once the camera has delivered
    (the fake device's audio is all there at once, before a camera's first frame)."""

    def run(self, source, sink=None, threaded=False, array_pan=None):
        self.image_points(0.0)
        time.sleep(0.2)
        return super().run(source, sink, threaded, array_pan)


@pytest.mark.parametrize("reported", [float("nan"), -1.0, 0.0, float("inf")])
def test_a_live_camera_without_a_usable_frame_rate_counts_30_fps(monkeypatch, fake_camera,
                                                                  reported):
    """A driver reporting CAP_PROP_FPS NaN (or -1, inf) set the camera's rate to it: with NaN
    the staleness test (older than two frame periods) compared False, and the point of a camera
    hung for a second was still returned. Now 30 frames/s unless the rate is finite and > 0
    (fake clock: 1/30 s per frame; 3 frames, then the camera hangs)."""
    import hearsee.stream.video as video

    now, hang = [100.0], threading.Event()

    def next_frame() -> None:
        now[0] += 1 / 30

    fake_camera(3, on_frame=next_frame, on_end=lambda: hang.wait(10.0), fps=reported)
    monkeypatch.setattr(video, "detect_source_point", lambda img, det: (320.0, 240.0))
    vp = video.VideoImagePoints(0, detector="hog")
    vp._clock = lambda: now[0]
    try:
        assert vp.fps == 30.0
        vp(0.0)  # starts the thread
        for _ in range(500):
            if vp.frame_index == 2:
                break
            time.sleep(0.01)
        assert vp.frame_index == 2
        last = now[0]
        now[0] = last + 0.5 / 30
        assert vp(0.1) == (320.0, 240.0)
        now[0] = last + 1.0  # hung for a second
        assert vp(1.1) is None
    finally:
        hang.set()
        vp.close()


# ------------------------------------------------------------------------- 6. CLI closes video
def test_track_cli_closes_its_video_source(monkeypatch, tmp_path, capsys):
    """`hearsee track --video / --camera-device` releases the capture (and stops the live
    camera's thread) when it returns, also when the audio input fails to open."""
    import cv2

    import hearsee.stream.video as video
    from hearsee.audio.signals import write_recording
    from hearsee.cli import main
    from hearsee.vision.camera import Camera, save_camera

    arr = MicArray.from_preset("three-mic")
    y = simulate_moving_free_field(
        0.05 * np.random.default_rng(0).standard_normal(FS // 2), FS, arr,
        linear_trajectory([1.2, -0.5, 0.1], [0, 0.8, 0], 0.5), snr_db=25, rng=1)
    write_recording(tmp_path / "rec.wav", y, FS)
    save_camera(Camera.from_fov(70.0, 160, 120), tmp_path / "cam.yaml")  # the video's size
    vid = tmp_path / "blank.avi"
    w = cv2.VideoWriter(str(vid), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (160, 120))
    for _ in range(6):
        w.write(np.full((120, 160, 3), 90, np.uint8))
    w.release()

    real = cv2.VideoCapture
    opened, released = [], []

    class CountingCap:
        def __init__(self, src):
            self._c = None if isinstance(src, int) else real(src)
            opened.append(src)

        def isOpened(self):
            return True if self._c is None else self._c.isOpened()

        def get(self, p):
            return 30.0 if self._c is None else self._c.get(p)

        def read(self):
            if self._c is not None:
                return self._c.read()
            time.sleep(0.002)
            return True, np.full((120, 160, 3), 90, np.uint8)  # (the calibration's size)

        def release(self):
            released.append(1)
            if self._c is not None:
                self._c.release()

    monkeypatch.setattr(cv2, "VideoCapture", CountingCap)
    monkeypatch.setattr(video, "detect_source_point", lambda img, det: None)
    cam = ["--camera", str(tmp_path / "cam.yaml")]
    monkeypatch.setitem(sys.modules, "sounddevice", _fake_recorder(y))
    for audio, extra in (([str(tmp_path / "rec.wav")], ["--video", str(vid)]),
                         (["--device", "0", "--duration", "0.4"], ["--camera-device", "0"])):
        assert main(["track", *audio, "--array", "three-mic", *cam, *extra]) == 0
        assert len(released) == len(opened)
        assert not [t for t in threading.enumerate() if t.name == "hearsee-camera"]
    # the microphone cannot be opened after the camera was: the camera is still closed
    sd = _fake_portaudio([])
    sd.query_devices = lambda device=None, kind=None: (_ for _ in ()).throw(ValueError("none"))
    monkeypatch.setitem(sys.modules, "sounddevice", sd)
    n = len(opened)
    assert main(["track", "--device", "usb", "--array", "three-mic", *cam,
                 "--camera-device", "0"]) == 2
    assert len(opened) == n + 1 and len(released) == len(opened)
    capsys.readouterr()


def test_array_source_refuses_a_bad_rate_or_block():
    """Bad-input sweep (2026-11-26): a rate of 0 divided by zero in the stream, a negative one
    was reported as 'frame too short', a NaN block length raised numpy's ValueError."""
    x = np.zeros((3, 1600))
    for fs in (0.0, -16000.0, float("nan")):
        with pytest.raises(AudioInputError, match="sample rate"):
            ArraySource(x, fs)
    with pytest.raises(ConfigError, match="block_len"):
        ArraySource(x, 16000, block_len=float("nan"))


def test_array_source_block_len_is_a_whole_number_of_samples():
    """ArraySource(block_len=2.5) truncated the length to 2 samples without a word (DeviceSource
    refused it). Now the same rule as DeviceSource's (config.whole_number): an integer >= 1; a
    float is refused even when whole (2.0), as every count of the package is."""
    x = np.arange(3 * 10, dtype=float).reshape(3, 10)
    for bad in (2.5, 2.0, True, "4", -3):
        with pytest.raises(ConfigError, match=r"^block_len must be an integer >= 1, got"):
            ArraySource(x, 16000, block_len=bad)
    blocks = list(ArraySource(x, 16000, block_len=np.int64(4)).blocks())
    assert [b.data.shape[1] for b in blocks] == [4, 4, 2]
    assert np.array_equal(np.concatenate([b.data for b in blocks], axis=1), x)


@pytest.mark.parametrize("config", [{"frame_ms": 32.0}, {}, "StreamConfig()", 5])
def test_a_stream_config_that_is_no_stream_config_is_refused(config):
    """StreamPipeline / TrackingProcessor(config={"frame_ms": 32.0}) were made and failed at
    the first frame with a builtin AttributeError ('dict' object has no attribute 'frame_ms');
    an empty dict silently meant the defaults. The package builds StreamConfigs by keyword, so
    anything else is a ConfigError naming StreamConfig, when the pipeline is made."""
    arr = MicArray.from_preset("three-mic")
    with pytest.raises(ConfigError, match="^config must be a StreamConfig"):
        StreamPipeline(arr, config=config)
    with pytest.raises(ConfigError, match="^config must be a StreamConfig"):
        TrackingProcessor(arr, FS, config)
    cfg = StreamConfig(frame_ms=32.0)
    assert StreamPipeline(arr, config=cfg).config is cfg
    assert TrackingProcessor(arr, FS, None).cfg == StreamConfig()


@pytest.mark.parametrize("kw, err, msg", [
    ({"fs": 0.0}, AudioInputError, "sample rate"),  # ZeroDivisionError in the stream
    ({"fs": -16000.0}, AudioInputError, "sample rate"),  # 'frame too short'
    ({"duration_s": float("nan")}, ConfigError, "duration"),  # ValueError (int(nan))
    ({"duration_s": -1.0}, ConfigError, "duration"),  # one block, then 'ok'
    ({"block_len": 0}, ConfigError, "block_len"),  # ZeroDivisionError on an overflow
    ({"timeout_s": float("nan")}, ConfigError, "timeout_s"),
    ({"queue_size": 0}, ConfigError, "queue_size"),  # an unbounded queue
])
def test_device_source_refuses_bad_settings(monkeypatch, kw, err, msg):
    """DeviceSource checked none of its numbers: each of these raised a builtin exception (or
    ran wrongly) only once the stream ran."""
    monkeypatch.setitem(sys.modules, "sounddevice", _fake_portaudio([4]))
    with pytest.raises(err, match=msg):
        pl.DeviceSource(0, 3, **{"fs": FS, "block_len": BL, "timeout_s": 0.05, **kw})


def test_device_source_infinite_duration_runs_until_the_device_stops(monkeypatch):
    """duration_s=inf (``hearsee track --duration inf``) means no limit, as None does (it raised
    an OverflowError)."""
    src = _device(monkeypatch, _fake_portaudio([6]), duration_s=float("inf"))
    assert len(list(src.blocks())) == 6 and src.stalled


@pytest.mark.parametrize("args", [["--fs", "0"], ["--duration", "nan"], ["--duration", "-1"]])
def test_track_cli_bad_live_settings_are_one_line(monkeypatch, capsys, args):
    """`hearsee track --device 0 --fs 0` was a ZeroDivisionError traceback, `--duration nan`
    a ValueError one; now one line on stderr and exit 2."""
    from hearsee.cli import main

    monkeypatch.setitem(sys.modules, "sounddevice", _fake_portaudio([4]))
    monkeypatch.setattr(pl, "DeviceSource", functools.partial(pl.DeviceSource, timeout_s=0.05))
    assert main(["track", "--device", "0", "--array", "three-mic", *args]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and len(cap.err.strip().splitlines()) == 1


@pytest.mark.parametrize("kw", [{"stall_timeout_s": -1.0}, {"stall_timeout_s": float("nan")},
                                {"max_stall_s": float("nan")}, {"max_stall_s": 0.0},
                                {"queue_size": 0}, {"queue_size": -1}])
def test_stream_pipeline_refuses_bad_stall_and_queue_settings(kw):
    """A negative stall_timeout_s raised queue's ValueError in a threaded run, a NaN
    max_stall_s never ended a run on a silent source, a queue_size <= 0 made the bounded queue
    unbounded: ConfigError when the pipeline is made."""
    with pytest.raises(ConfigError, match=next(iter(kw))):
        StreamPipeline(MicArray.from_preset("three-mic"), **kw)


def test_stream_pipeline_with_max_stall_inf_still_runs():
    x = np.random.default_rng(0).standard_normal((3, 8000))
    pipe = StreamPipeline(MicArray.from_preset("three-mic"), max_stall_s=float("inf"))
    assert len(pipe.run(ArraySource(x, FS), threaded=True)) == (8000 - 1024) // 512 + 1
    assert pipe.stats.status == "ok"


# ------------------------------------------------------------------------- stopping fails
_STOP = "Error stopping stream: Unanticipated host error [PaErrorCode -9999]"
_STOP_MSG = f"audio input device 'fake': cannot stop the input stream ({_STOP})"


def test_a_stream_that_fails_to_stop_is_an_audio_input_error(monkeypatch):
    """PortAudio failing when the stream stops or closes (the ``with`` exit in
    DeviceSource.blocks) escaped as a PortAudioError: at the run's end (its duration) and when
    its consumer closed it."""
    sd = _fake_portaudio([8, 8, 8], close_error=_STOP)
    src = _device(monkeypatch, sd, duration_s=4 * BL / FS)
    with pytest.raises(AudioInputError) as exc:
        list(src.blocks())
    assert str(exc.value) == _STOP_MSG
    g = src.blocks()
    next(g)
    with pytest.raises(AudioInputError) as exc:
        g.close()  # (the consumer ends the run: the error is the only one)
    assert str(exc.value) == _STOP_MSG and sd.InputStream.n_exited == 2
    with pytest.raises(AudioInputError, match="cannot stop the input stream"):
        StreamPipeline(MicArray.from_preset("three-mic")).run(src)


def test_a_stream_that_fails_to_stop_does_not_hide_the_error_that_ends_the_run(monkeypatch,
                                                                               unraisable):
    """A Ctrl-C in the wait for a block, or an error of the consumer, ends the run: the stream's
    error when it then stops replaced the Ctrl-C, or was printed as "Exception ignored in"
    when the generator was collected."""
    sd = _fake_portaudio([8, 8, 8], close_error=_STOP)
    src = _device(monkeypatch, sd)
    g = src.blocks()
    next(g)
    with pytest.raises(KeyboardInterrupt):
        g.throw(KeyboardInterrupt)
    assert sd.InputStream.n_exited == 1

    def sink(u):
        raise ValueError("the sink's own error")

    for threaded in (False, True):
        with pytest.raises(ValueError, match="the sink's own error"):
            StreamPipeline(MicArray.from_preset("three-mic")).run(src, sink, threaded=threaded)
        gc.collect()
        assert unraisable == [] and sd.InputStream.n_exited == 2 + threaded


# ------------------------------------------------------------------- 4b. a camera read that hangs
def _numbered(n: int) -> np.ndarray:
    """Frame n of a hanging capture: 80x60, every pixel n."""
    return np.full((60, 80, 3), n, np.uint8)


def test_timed_capture_gives_up_on_a_read_that_hangs_and_resumes_when_it_returns(
        hanging_capture):
    """cv2.VideoCapture.read of a device that opened and then delivers nothing blocks forever:
    TimedCapture returns "no frame" after its timeout, starts no second read while the first
    hangs, leaves the capture unreleased while it does (releasing under a blocked read is not
    safe), and reads again once the hung read has returned."""
    from hearsee.stream.video import TimedCapture

    cap = hanging_capture(_numbered)
    timed = TimedCapture(cap, 0.05)
    t0 = time.perf_counter()
    assert timed.read() == (False, None)
    assert 0.05 <= time.perf_counter() - t0 < 5.0
    assert timed.stuck and cap.reads == 1
    assert timed.read() == (False, None) and cap.reads == 1  # no second read meanwhile
    timed.release()
    assert cap.released == 0
    assert timed.get(0) == 30.0  # the capture's own attributes
    cap.go.set()
    timed._pending.join(5.0)
    assert not timed.stuck
    ok, frame = timed.read()  # (the hung read's late frame, number 1, was dropped)
    assert ok and frame[0, 0, 0] == 2 and cap.reads == 2
    timed.release()
    assert cap.released == 1


def test_timed_capture_passes_on_the_read_error_and_refuses_a_bad_timeout():
    import cv2

    from hearsee.stream.video import TimedCapture

    class Broken:
        def read(self):
            raise cv2.error("driver gone")

    with pytest.raises(cv2.error, match="driver gone"):
        TimedCapture(Broken(), 1.0).read()
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ConfigError, match="camera read timeout"):
            TimedCapture(Broken(), bad)


def test_read_frame_names_a_camera_that_delivers_nothing_in_time(hanging_capture):
    from hearsee.stream.video import TimedCapture, read_frame

    with pytest.raises(ConfigError, match=r"^robot\.yaml: cameras\.left: camera 0 opened "
                                          r"but delivered no frame within 0\.05 s$"):
        read_frame(TimedCapture(hanging_capture(_numbered), 0.05), 0, "robot.yaml: cameras.left")
    cap2 = hanging_capture(_numbered)
    cap2.go.set()
    frame = read_frame(TimedCapture(cap2, 5.0), 0, "robot.yaml: cameras.left", (80, 60))
    assert frame.shape == (60, 80, 3)


def test_read_frame_names_a_video_file_as_a_video_file_not_a_camera(tmp_path):
    """A video FILE that opened and delivered nothing (or frames of another size) was called
    "camera 'clip.mp4'"; a file is "video file" now, a device index, device node or URL still
    "camera"."""
    from hearsee.stream.video import read_frame

    class Empty:
        def read(self):
            return False, None

    class Small:
        def read(self):
            return True, np.zeros((60, 80, 3), np.uint8)

    clip = tmp_path / "clip.mp4"
    clip.write_bytes(b"")
    for spec in (str(clip), clip):
        with pytest.raises(ConfigError, match=r"^--video: video file '.*clip\.mp4' opened but "
                                              r"delivered no frame$"):
            read_frame(Empty(), spec, "--video")
        with pytest.raises(ConfigError, match=r"^--video: video file '.*clip\.mp4' delivers "
                                              r"80x60 frames but the calibration expects"):
            read_frame(Small(), spec, "--video", (160, 120))
    for spec, shown in ((0, "0"), ("rtsp://cam/1", "'rtsp://cam/1'"),
                        (str(tmp_path / "gone.mp4"), repr(str(tmp_path / "gone.mp4")))):
        with pytest.raises(ConfigError) as err:
            read_frame(Empty(), spec, "--video")
        assert str(err.value) == f"--video: camera {shown} opened but delivered no frame"


# ------------------------------------------------------- a stuck or disconnected microphone, live
def _fake_recorder(x):
    """A sounddevice module whose stream delivers the recording ``x`` (n_ch, n) in blocks of
    ``BL`` samples when entered."""
    sd = types.ModuleType("sounddevice")
    sd.PortAudioError = type("PortAudioError", (Exception,), {})
    dev = {"name": "fake", "max_input_channels": x.shape[0]}
    sd.query_devices = lambda device=None, kind=None: (
        [dev] if device is None and kind is None else dev)

    class InputStream:
        def __init__(self, device, channels, samplerate, blocksize, dtype, callback):
            self.cb = callback

        def __enter__(self):
            for s in range(0, x.shape[1] - BL + 1, BL):
                self.cb(x[:, s:s + BL].T.astype(np.float32), BL, _TimeInfo(0.0), _Flags(False))
            return self

        def __exit__(self, *exc):
            return False

    sd.InputStream = InputStream
    return sd


@pytest.mark.parametrize("fault, want", [
    ("stuck", "audio input device 'fake': channel 2 holds one constant value throughout"),
    ("quiet", "audio input device 'fake': channel 1 is at least 100 dB below the loudest"),
    ("late quiet", "audio input device 'fake': channel 1 is at least 100 dB below the loudest"),
    ("copy", "audio input device 'fake': channels 0 and 2 hold the same signal"),
    ("none", None),
])
def test_live_input_names_a_stuck_or_disconnected_microphone(monkeypatch, fault, want):
    """Live input had none of a file's checks: a channel stuck at one value or 100 dB down
    gave no direction and no word. The first 2 s in which any channel varies are checked once
    (a silent start is looked past); the run goes on."""
    import warnings

    from hearsee.errors import DegenerateInputWarning

    x = 0.1 * np.random.default_rng(5).standard_normal((3, 6 * FS))
    if fault == "stuck":
        x[2] = 0.01
    elif fault in ("quiet", "late quiet"):
        x[1] *= 1e-5
    if fault == "late quiet":
        x[:, :2 * FS + BL] = 0.0  # the input starts after 2 s of digital silence
    if fault == "copy":  # a mono device presented as several channels
        x[2] = x[0]
    monkeypatch.setitem(sys.modules, "sounddevice", _fake_recorder(x))
    src = pl.DeviceSource(0, 3, FS, block_len=BL, timeout_s=0.05, queue_size=128)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        blocks = list(src.blocks())
    assert sum(b.data.shape[1] for b in blocks) == 6 * FS // BL * BL  # (none held back)
    ours = [str(w.message) for w in got if issubclass(w.category, DegenerateInputWarning)]
    if want is None:
        assert ours == []
    else:
        assert len(ours) == 1 and ours[0].startswith(want)


def test_live_input_checks_only_the_arrays_channels(monkeypatch):
    """A larger device's unused channel (a playback loopback: digital silence) is no
    microphone of the array: with ``check_channels`` it is not named (``hearsee run`` passes
    its robot file's channels); a stuck one among them is, by its device channel number."""
    import warnings

    from hearsee.errors import DegenerateInputWarning

    x = 0.1 * np.random.default_rng(6).standard_normal((4, 3 * FS))
    x[0] = 0.0  # unused loopback
    x[3] = 0.02  # stuck microphone of the array

    def warned(check):
        monkeypatch.setitem(sys.modules, "sounddevice", _fake_recorder(x))
        src = pl.DeviceSource(0, 4, FS, block_len=BL, timeout_s=0.05, queue_size=128,
                              check_channels=check)
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            list(src.blocks())
        return [str(w.message) for w in got if issubclass(w.category, DegenerateInputWarning)]

    assert warned([1, 2]) == []
    (msg,) = warned([1, 2, 3])
    assert "'fake': channel 3 holds one constant value" in msg
    (msg,) = warned(None)
    assert "'fake': channels 0, 3 hold one constant value" in msg
    for bad in ([4], [], ["1"]):
        with pytest.raises(ConfigError, match="check_channels"):
            pl.DeviceSource(0, 4, FS, block_len=BL, check_channels=bad)


# ------------------------------------------------------ a microphone wired backwards, live
class _Live:
    """Live-like input (no recording to look at ahead, as a device) of the samples ``x``."""

    def __init__(self, x):
        self.inner = ArraySource(x, FS, BL)
        self.n_channels, self.fs = x.shape[0], FS

    def blocks(self):
        return self.inner.blocks()


def _noise_then_source(flip: float, quiet_s: float, source_s: float) -> np.ndarray:
    """Three-mic input: ``quiet_s`` seconds of sensor noise alone (no source), then white noise
    from a source 2 m away at azimuth -60 deg for ``source_s`` seconds, 20 dB above it;
    microphone 2's samples times ``flip``."""
    from hearsee.audio.propagation import simulate_free_field
    from hearsee.audio.signals import white_noise
    from hearsee.geometry import unit_vector_deg

    rng = np.random.default_rng(12)
    arr = MicArray.from_preset("three-mic")
    x = simulate_free_field(white_noise(source_s, FS, rng=rng), FS, arr,
                            2.0 * unit_vector_deg(-60.0, 0.0))
    x = np.concatenate([np.zeros((3, int(quiet_s * FS))), x], axis=1)
    x = x + 0.1 * np.std(x[:, int(quiet_s * FS):]) * rng.standard_normal(x.shape)
    return x * np.array([[1.0], [1.0], [flip]])


def _run_live(x, monkeypatch, threaded=False, category=None, **kw):
    """(the stream's updates, the time (s) of the last update before each warning of
    ``category`` -- default InvertedPolarityWarning) of ``x`` as live input, with 2-s wiring
    checks."""
    import warnings

    from hearsee.errors import InvertedPolarityWarning

    category = category or InvertedPolarityWarning

    monkeypatch.setattr(pl, "WIRING_CHECK_S", 2.0)
    seen: list = []  # (each update's time, the warnings raised before it)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        ups = StreamPipeline("three-mic", StreamConfig(), **kw).run(
            _Live(x), lambda u: seen.append((u.t, len(got))), threaded)
    when = []
    for k, w in enumerate(got):
        if issubclass(w.category, category):
            before = [t for t, n in seen if n <= k]
            when.append((str(w.message), before[-1] if before else None))
    return ups, when


@pytest.mark.parametrize("threaded", [False, True])
def test_a_live_stream_warns_of_an_inverted_microphone_once_it_hears_a_source(monkeypatch,
                                                                             threaded):
    """A file's whole-recording correlations tell of a microphone wired backwards before
    `hearsee track` streams it; live input had no such check and its directions were ~30-40
    deg off without a word. The stream checks its first window (2 s here) with a source heard:
    the first window here holds sensor noise only (no source: looked past), the second the
    source with microphone 2 inverted -- one warning, given while the stream runs (after ~4.1
    s of updates), not at its end; microphone 2 wired right: none."""
    ups, when = _run_live(_noise_then_source(-1.0, 2.5, 5.5), monkeypatch, threaded)
    assert len(when) == 1
    msg, t = when[0]
    assert msg.startswith("microphone 2 seems wired with inverted polarity: pairs 0-2, 1-2")
    assert 3.8 <= t <= 4.2 and ups[-1].t > 7.5
    ups, when = _run_live(_noise_then_source(1.0, 2.5, 5.5), monkeypatch, threaded)
    assert when == [] and ups[-1].t > 7.5


def test_a_live_stream_warns_once_of_a_microphone_out_of_sync(monkeypatch):
    """Microphone 2 recorded 40 samples (2.5 ms) late on live input: the first 2-s window
    names it (ChannelSyncWarning) and the check ends there -- no source is localizable, so
    without that the next windows told it again every 2 s; in sync: no such warning."""
    from hearsee.errors import ChannelSyncWarning

    x = _noise_then_source(1.0, 0.0, 8.0)
    ups, when = _run_live(x, monkeypatch, category=ChannelSyncWarning)
    assert when == [] and ups[-1].t > 7.5
    x[2] = np.roll(x[2], 40)
    ups, when = _run_live(x, monkeypatch, category=ChannelSyncWarning)
    assert len(when) == 1 and ups[-1].t > 7.5
    msg, t = when[0]
    assert msg.startswith("microphone 2 seems out of sync with the others: pairs 0-2 at -2.")
    assert t <= 2.2


def test_a_short_live_run_is_checked_when_it_ends_and_the_check_can_be_turned_off(monkeypatch):
    """Input shorter than a check window is checked when it ends (at least
    WIRING_CHECK_MIN_S: 1.9 s is checked with a minimum of 1 s, not with one of 2 s);
    ``check_wiring=False`` checks nothing."""
    x = _noise_then_source(-1.0, 0.0, 1.9)
    monkeypatch.setattr(pl, "WIRING_CHECK_MIN_S", 1.0)
    _, when = _run_live(x, monkeypatch)
    assert len(when) == 1 and when[0][0].startswith("microphone 2 seems wired with inverted")
    monkeypatch.setattr(pl, "WIRING_CHECK_MIN_S", 2.0)
    assert _run_live(x, monkeypatch)[1] == []
    assert _run_live(_noise_then_source(-1.0, 0.0, 6.0), monkeypatch, check_wiring=False)[1] == []


def test_a_recording_is_checked_only_when_asked():
    """A source holding a recording (``.x``: ArraySource, WavSource, also behind DropoutSource)
    can be checked ahead, as `hearsee track` does; the stream checks it only with
    ``check_wiring=True`` (the check's whole-recording estimate would add 5-10 % to a 20-s
    file's stream); anything but a bool or None is refused."""
    import warnings

    from hearsee.errors import InvertedPolarityWarning

    x = _noise_then_source(-1.0, 0.0, 3.0)
    for src, check, want in ((ArraySource(x, FS, BL), None, 0), (ArraySource(x, FS, BL), True, 1),
                             (DropoutSource(ArraySource(x, FS, BL), drop=[3]), None, 0)):
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            StreamPipeline("three-mic", check_wiring=check).run(src)
        assert sum(issubclass(w.category, InvertedPolarityWarning) for w in got) == want
    for bad in ("yes", 2, float("nan")):
        with pytest.raises(ConfigError, match="check_wiring"):
            StreamPipeline("three-mic", check_wiring=bad)


def test_track_cli_warns_of_an_inverted_microphone_on_live_input(monkeypatch, capsys):
    """`hearsee track --device`: one warning line for microphone 2 wired backwards, the run
    goes on to its end (exit 0)."""
    from hearsee.cli import main

    monkeypatch.setattr(pl, "WIRING_CHECK_S", 2.0)
    x = _noise_then_source(-1.0, 0.0, 3.0)
    monkeypatch.setitem(sys.modules, "sounddevice", _fake_recorder(0.3 * x / np.abs(x).max()))
    monkeypatch.setattr(pl, "DeviceSource", functools.partial(pl.DeviceSource, timeout_s=0.05,
                                                              queue_size=128))
    assert main(["track", "--device", "0", "--array", "three-mic", "--duration", "2.9"]) == 0
    cap = capsys.readouterr()
    assert cap.err.count("microphone 2 seems wired with inverted polarity: pairs 0-2, 1-2") == 1
    assert len(cap.out.splitlines()) > 40


def test_a_live_streams_dead_microphone_is_left_out(monkeypatch):
    """A microphone of a live input unplugged: the wiring watch warned of it, and the stream
    went on building directions with its noise (respeaker-4 here: 7 deg off). From the
    watch's check on, the other microphones localize as an array of their own: one warning,
    the directions near the truth, no frame lost at the switch, the stats name it."""
    import warnings

    from hearsee.errors import DeadMicrophoneWarning
    from hearsee.sim.audio import simulate_recording

    monkeypatch.setattr(pl, "WIRING_CHECK_S", 4.0)
    x, truth = simulate_recording("respeaker-4", [1.2, 1.4, 0.2], "male", 8.0, FS, 20.0,
                                  seed=7)
    x[3] = np.random.default_rng(2).standard_normal(x.shape[1]) * np.std(x[3])
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        pipe = StreamPipeline("respeaker-4", check_wiring=True)
        ups = pipe.run(ArraySource(x, FS, BL))
    told = [str(w.message) for w in got if issubclass(w.category, DeadMicrophoneWarning)]
    assert len(told) == 1 and "comes from microphones 0, 1, 2 alone" in told[0]
    assert pipe.stats.dead_microphones == (3,) and pipe.stats.n_missing_frames == 0
    t = np.array([u.t for u in ups])
    assert np.all(np.diff(t) > 0) and len(ups) == len(np.unique(t))  # (one framer throughout)
    err = np.array([abs((u.azimuth_deg - truth["azimuth_deg"] + 180) % 360 - 180)
                    for u in ups if u.measured and u.t > 5.0])
    assert len(err) > 50 and np.median(err) < 3.0
    before = np.array([abs((u.azimuth_deg - truth["azimuth_deg"] + 180) % 360 - 180)
                       for u in ups if u.measured and u.t < 4.0])
    assert np.median(before) > 2 * np.median(err)  # (the dead channel's noise in every pair)


def test_a_live_streams_dead_first_microphone_is_left_out_of_the_camera_fixes_too(monkeypatch):
    """With a camera: the processor that takes over when a dead microphone is left out reads
    its TDOAs through a rig of the remaining microphones. Its pairs are numbered in them, so
    microphone 0 dead made the whole array's rig read pair 1-2's TDOA as 0-1's: 3 frames of
    62 had a position after the switch, 1.8 m off (0.15 m now)."""
    import warnings

    from hearsee.fusion.audiovisual import AudioVisualRig
    from hearsee.sim.audio import simulate_recording
    from hearsee.vision.camera import Camera

    monkeypatch.setattr(pl, "WIRING_CHECK_S", 4.0)
    src = np.array([1.2, 1.4, 0.2])
    x, _ = simulate_recording("respeaker-4", src, "male", 8.0, FS, 20.0, seed=7)
    x[0] = np.random.default_rng(2).standard_normal(x.shape[1]) * np.std(x[0])
    arr = MicArray.from_preset("respeaker-4")
    rig = AudioVisualRig.mounted(arr, Camera.from_fov(70.0, 640, 480), (0.0, -0.2, 0.1), 45.0)
    uv = tuple(rig.project(src[None])[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pipe = StreamPipeline(arr, rig=rig, image_points=lambda t: uv, check_wiring=True)
        ups = pipe.run(ArraySource(x, FS, BL))
    assert pipe.stats.dead_microphones == (0,)
    late = [u for u in ups if u.t > 6.0]
    pos = np.array([u.position_m for u in late if u.position_m is not None])
    assert len(pos) == len(late) > 50
    assert np.median(np.linalg.norm(pos - src, axis=1)) < 0.3


def test_talker_ids_go_on_counting_where_a_dead_microphone_is_left_out(monkeypatch):
    """With several talkers (``max_sources``) the processor that takes over when a dead
    microphone is left out goes on with the old one's talker ids: a client keying on them would
    otherwise take the new tracks (counted from 0 again) for the old ones. (A watch that finds
    microphone 3 dead at its check stands in for an unplugged one whose frames still gave
    directions.)"""
    import warnings

    from hearsee.sim.audio import simulate_recording

    class Unplugged(pl._WiringWatch):
        def _check(self, x):
            self.dead_mics = (3,)
            return True

    monkeypatch.setattr(pl, "WIRING_CHECK_S", 3.0)
    monkeypatch.setattr(pl, "_WiringWatch", Unplugged)
    x, _ = simulate_recording("respeaker-4", [1.2, 1.4, 0.2], "male", 7.0, FS, 20.0, seed=333)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pipe = StreamPipeline("respeaker-4", StreamConfig(max_sources=2), check_wiring=True)
        ups = pipe.run(ArraySource(x, FS, BL))
    assert pipe.stats.dead_microphones == (3,)
    before = {s["id"] for u in ups if u.t < 2.5 for s in u.sources}
    after = {s["id"] for u in ups if u.t > 5.0 for s in u.sources}
    assert before and after and min(after) > max(before)
    proc = pl.TrackingProcessor("three-mic", FS, StreamConfig(max_sources=2), first_talker_id=7)
    assert proc.next_talker_id == 7
    assert pl.TrackingProcessor("three-mic", FS).next_talker_id == 0
    with pytest.raises(ConfigError, match="first_talker_id"):
        pl.TrackingProcessor("three-mic", FS, first_talker_id=-1)


def test_dropout_source_wraps_only_a_stream_source():
    """DropoutSource(None) was an AttributeError."""
    with pytest.raises(ConfigError, match="DropoutSource"):
        DropoutSource(None)
