"""``hearsee track``: track a moving speaker from a recording or live microphones (+ camera)."""

from __future__ import annotations

import json
import math
import sys
import warnings
from collections.abc import Sequence
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from hearsee.cli._app import (
    CHANNELS_HELP,
    GccMethod,
    app,
    emit_json,
    err_console,
    note_empty_band,
    parse_band,
    parse_channels,
    parse_floats,
    to_jsonable,
)
from hearsee.stream.video import IMAGE_POINT_MARGIN


class TrackFormat(StrEnum):
    jsonl = "jsonl"
    json = "json"


class Tracker(StrEnum):
    cv = "cv"
    imm = "imm"


class MotionModel(StrEnum):
    cv = "cv"
    ca = "ca"


class Detector(StrEnum):
    hog = "hog"
    face = "face"


#: How far (m) the camera's optical centre may be from the array's centre (mean microphone
#: position): the rig is one robot head or body, where a camera sits well within a metre or
#: two of its microphones; 5 m leaves room for any real robot, while a position beyond it is a
#: wrong unit (cm, mm) or a swapped coordinate, which gave no 3D fix without a word.
CAMERA_MAX_OFFSET_M = 5.0


def _camera_pose(camera_at: str | None, pan: float | None, tilt: float | None,
                 array_centre: Sequence[float]) -> tuple[list[float], float, float]:
    """--camera-at, --camera-pan, --camera-tilt checked (defaults 0,0,0 / 0 / 0): pan in
    [-180, 180] deg, tilt in [-90, 90] deg, the centre within :data:`CAMERA_MAX_OFFSET_M` of
    the array's centre; typer.BadParameter otherwise (a pan of 1e300, a tilt of 95 or a
    camera 100 m away gave no 3D fix and no message)."""
    pos = parse_floats("0,0,0" if camera_at is None else camera_at, 3, "--camera-at")
    pan = 0.0 if pan is None else pan
    tilt = 0.0 if tilt is None else tilt
    if not -180.0 <= pan <= 180.0:
        raise typer.BadParameter(f"--camera-pan must be in [-180, 180] degrees, got {pan:g}")
    if not -90.0 <= tilt <= 90.0:
        raise typer.BadParameter(f"--camera-tilt must be in [-90, 90] degrees, got {tilt:g}")
    off = math.dist(pos, array_centre)
    if not off <= CAMERA_MAX_OFFSET_M:
        raise typer.BadParameter(
            f"--camera-at: {camera_at} is {off:.3g} m from the array's centre; the camera must "
            f"be within {CAMERA_MAX_OFFSET_M:g} m of its microphones (metres, array frame)")
    return pos, pan, tilt


def _stream_band(asked: tuple[float, float] | None, x, fs: float, frame_ms: float
                 ) -> tuple[float, float] | None:
    """The stream's GCC band (Hz): ``asked`` (--band-hz; None = the whole band) less the
    empty top band of a file's samples ``x`` (None for live input, which cannot be looked at
    ahead) -- :func:`hearsee.audio.tdoa.empty_band_top_hz`, as ``hearsee localize`` leaves it
    out; ConfigError when nothing of ``asked`` is left."""
    from hearsee.audio.tdoa import empty_band_top_hz
    from hearsee.errors import ConfigError

    top = None if x is None else empty_band_top_hz(x, fs, frame_ms)
    if top is None or (asked is not None and asked[1] <= top):
        return asked
    lo = 0.0 if asked is None else asked[0]
    if top <= lo:
        what = "the recording" if asked is None else f"--band-hz {asked[0]:g},{asked[1]:g}"
        raise ConfigError(f"{what}: nothing there (the recording's spectrum is empty above "
                          f"about {top:.0f} Hz: upsampled from a lower rate?); choose a band "
                          "below that")
    return lo, top


#: :func:`_check_wiring` looks at up to this many seconds of a file
WIRING_SCAN_S = 30.0


def _check_wiring(x, fs: float, arr, cfg) -> tuple[bool, tuple[float, ...], tuple[int, ...]]:
    """:func:`hearsee.stream.pipeline.wiring_estimate` of a file's first
    :data:`WIRING_SCAN_S` seconds, for its warnings of a microphone wired with inverted
    polarity, channels out of sync, a dead microphone or mains hum, before the file is
    streamed. In ``cfg.band_hz``, which :func:`_stream_band` has already trimmed of an empty
    top band (so no second search for one). (Whether it told of a wiring fault, the lines of
    hum found: the stream notches them out; the dead microphones the stream leaves out when
    two or more others remain -- their warning is :func:`hearsee.audio.localize.
    without_microphones`'s, which says so.)"""
    from hearsee.audio.localize import hold_dead_warning
    from hearsee.stream.pipeline import wiring_estimate

    tf, dead = hold_dead_warning(arr, lambda: wiring_estimate(
        x[:, :int(WIRING_SCAN_S * fs)], fs, arr, cfg, empty_band_db=None))
    return (False, (), ()) if tf is None else (tf.wiring_fault, tf.tonal_lines_hz, dead)


def _srp_band(gcc_band: tuple[float, float] | None, srp_band: tuple[float, float] | None
              ) -> tuple[float, float] | None:
    """The steered response's band (Hz) within the GCC's band ``gcc_band``: ``srp_band``
    (StreamConfig's 300-3500 Hz) where they overlap, else ``gcc_band`` itself."""
    if gcc_band is None or srp_band is None:
        return srp_band if gcc_band is None else gcc_band
    lo, hi = max(gcc_band[0], srp_band[0]), min(gcc_band[1], srp_band[1])
    return (lo, hi) if lo < hi else gcc_band


def _warn_short_video(points, what: object, t_end: float) -> None:
    """A warning when the video (or live camera) ``what`` stopped giving frames more than two
    frames before the last update at ``t_end`` seconds: the updates after it had no image
    point, so no 3D position (they went direction-only without a word)."""
    from hearsee.errors import DegenerateInputWarning

    if not points.ended:
        return
    last = points.frame_time if points.frame_index >= 0 else None
    if last is None:
        warnings.warn(f"{what}: delivered no frame: the run was direction-only",
                      DegenerateInputWarning, stacklevel=2)
    elif not points.live and last + 2.0 / points.fps < t_end:
        warnings.warn(f"{what}: the video ends at {last + 1.0 / points.fps:.2f} s, before the "
                      f"recording ({t_end:.2f} s): no 3D position after it",
                      DegenerateInputWarning, stacklevel=2)
    elif points.live:
        warnings.warn(f"{what}: stopped delivering frames at {last:.2f} s: direction-only "
                      "after it", DegenerateInputWarning, stacklevel=2)


def _device_spec(text: str) -> int | str:
    """--device as an index (ASCII digits, optionally negative: then refused as no device) or
    a name, stripped as ``audio.device`` is (``--1`` and ``²`` raised builtin ValueErrors)."""
    s = text.strip()
    digits = s[1:] if s.startswith("-") else s
    return int(s) if digits.isascii() and digits.isdigit() else s


@app.command("track")
def track_cmd(
    recording: Annotated[list[Path] | None, typer.Argument(
        help="Multichannel audio file (channel k = microphone k), or one file per microphone "
        "in the array's order (their channels file by file; one rate and length). Omit with "
        "--device.")] = None,
    array: Annotated[str, typer.Option("--array", help="Array preset name or YAML file.")] = ...,
    channels: Annotated[str | None, typer.Option(
        "--channels", help=CHANNELS_HELP + " Of a file or of the --device.",
        show_default=False)] = None,
    device: Annotated[str | None, typer.Option(
        "--device", help="Live input: PortAudio device index or name.")] = None,
    duration: Annotated[float | None, typer.Option(
        "--duration", help="Live input: stop after this many seconds, > 0; default (or inf): "
        "no limit -- until Ctrl-C or the input stops).")] = None,
    fs: Annotated[int | None, typer.Option(
        "--fs", help="Live input: sample rate in Hz (default 16000; with a camera, 48000 "
        "sharpens the 3D fixes of sources with energy above 8 kHz; bench/tracking.py part B).")
    ] = None,
    video: Annotated[Path | None, typer.Option(
        "--video", help="Video of the scene (needs --camera).")] = None,
    camera_device: Annotated[int | None, typer.Option(
        "--camera-device", help="Live camera index (needs --camera and --device).")] = None,
    image_points: Annotated[Path | None, typer.Option(
        "--image-points", help="CSV t,u,v of the source's image point (needs --camera; "
        "empty u and v = not visible). Only one of u and v, or a point more than "
        f"{IMAGE_POINT_MARGIN:.0%} of the image's larger side outside the camera's image "
        f"({IMAGE_POINT_MARGIN * 640:g} px of 640x480), is an error; a point nearer the edge "
        "is used as it is.")] = None,
    detector: Annotated[Detector | None, typer.Option(
        "--detector", help="Person detector for --video / --camera-device (default hog).",
        show_default=False)] = None,
    camera: Annotated[Path | None, typer.Option(
        "--camera", help="Camera calibration YAML.")] = None,
    camera_at: Annotated[str | None, typer.Option(
        "--camera-at", help="Camera optical centre X,Y,Z in the array frame, metres (needs "
        "--camera; default 0,0,0; at most 5 m from the array's centre). Measure "
        "it (and the pan) carefully: the range comes from the camera-array parallax, 10 cm "
        "off sideways moved the 3D fixes 0.5-0.8 m with the camera 0.2 m aside (0.2-0.3 m "
        "0.5 m aside) in bench/mounting.py, and the audio "
        "cannot tell.")] = None,
    camera_pan: Annotated[float | None, typer.Option(
        "--camera-pan", help="Camera pan (deg, toward +y; -180 to 180; needs --camera; "
        "default 0).")] = None,
    camera_tilt: Annotated[float | None, typer.Option(
        "--camera-tilt", help="Camera tilt (deg, up; -90 to 90; needs --camera; default 0).")
    ] = None,
    frame_ms: Annotated[float, typer.Option(
        "--frame-ms", help="Frame length in milliseconds, at most 10000.")] = 64.0,
    hop_ms: Annotated[float, typer.Option(
        "--hop-ms", help="Frame hop in milliseconds, at most 10000.")] = 32.0,
    method: Annotated[GccMethod, typer.Option("--method", help="GCC weighting.")] = GccMethod.phat,
    itd_filter: Annotated[bool, typer.Option(
        "--itd-filter", help="Smooth TDOAs with the ITD Kalman filter first.")] = False,
    in_plane: Annotated[bool, typer.Option(
        "--in-plane", help="The speaker is at the height of a planar (three-mic) array: "
        "elevation 0, spherical wavefront of a source assumed 2 m away. Not for a masked pair.")
    ] = False,
    motion_model: Annotated[MotionModel, typer.Option(
        "--motion-model", help="3D tracker with a calibrated camera (needs --camera): cv "
        "(constant velocity on "
        "the image point and each pair's TDOA; the default: tracked median 4.3 cm on "
        "bench/tracking's room walks; acceleration_mps2 null) or ca (constant acceleration on "
        "the camera-ray fixes, thesis 5.4.3: also acceleration_mps2; 15 cm there).")
    ] = MotionModel.cv,
    tracker: Annotated[Tracker, typer.Option(
        "--tracker", help="Direction tracker: imm (interacting multiple models: a quiet and a "
        "turning mode; the default) or cv (one Kalman filter instead of the modes).")
    ] = Tracker.imm,
    rate_tau: Annotated[float | None, typer.Option(
        "--rate-tau", help="Time constant (s) with which the direction tracker's angular rate "
        "relaxes toward zero (default: audio.tracking.DIRECTION_RATE_TAU_S, 2 s); inf = "
        "constant velocity (the thesis's model).")
    ] = None,
    gate_coherence: Annotated[float, typer.Option(
        "--gate-coherence", help="Normalised steered power (0-1) that counts as a measurement "
        "inside the running track's gate once it has coasted 0.2 s (tracker-aided detection, "
        "StreamConfig.gated_min_coherence; the grid's own threshold is 0.4). 0.3 lowered a "
        "weak talker's error through pauses in bench/tracking.py but lagged sharp turns by "
        "up to ~2 more frames; 0 = off. Not for a masked pair.")
    ] = 0.0,
    band_hz: Annotated[str | None, typer.Option(
        "--band-hz", help="LOW,HIGH: only this frequency band in Hz for the GCC (and, within "
        "it, the steered response's 300-3500 Hz), e.g. 300,3500. A file's empty band at the "
        "top of the spectrum (upsampled from a lower rate) is left out by itself either way.",
        show_default=False)] = None,
    sources: Annotated[int, typer.Option(
        "--sources", help="Several talkers at once, who may walk (2-8): each update's "
        "\"sources\" names up to this many, each with a track id, azimuth (a pair's front "
        "twin) and when it was last heard; the frames' own directions (and their steered "
        "responses' second maxima) followed by audio.sources.SourceTracker, causally, each "
        "talker's track an IMM of a quiet and a walking mode (a walker keeps its id where it "
        "crosses another talker far more often). 1: one talker (no \"sources\"). Not for a "
        "masked pair.")] = 1,
    fmt: Annotated[TrackFormat, typer.Option(
        "--format", help="jsonl: one JSON line per frame; json: one document.")
    ] = TrackFormat.jsonl,
    stats: Annotated[bool, typer.Option(
        "--stats", help="Print real-time factor and latency on stderr.")] = False,
) -> None:
    """Track the direction (and, with a calibrated camera, the 3D position, velocity and,
    with --motion-model ca, acceleration) of a moving speaker; one update per audio frame.

    Live input (--device) runs for --duration seconds, until the input stops, or until Ctrl-C,
    which ends it cleanly: the updates so far and the stats (status "interrupted") are
    reported, as by `hearsee run`.
    """
    from hearsee.audio.arrays import load_array
    from hearsee.audio.signals import recording_entry, recording_label
    from hearsee.audio.sources import MAX_SOURCES
    from hearsee.audio.tdoa import check_frame_ms
    from hearsee.audio.tracking import DIRECTION_RATE_TAU_S, IMM_MODES_DPS2
    from hearsee.config import time_limit, whole_number
    from hearsee.errors import ConfigError
    from hearsee.stream.pipeline import (
        DeviceSource,
        StreamConfig,
        StreamPipeline,
        WavSource,
        check_trackable,
        mapped_device,
    )

    recording = recording or None  # (no file given: an empty list)
    if recording is None and device is None:
        raise ConfigError("give a recording file or --device (live input)")
    if recording is not None and device is not None:
        raise ConfigError("give either a recording file or --device (live input), not both")
    if recording is not None and (fs is not None or duration is not None):
        # (they were ignored without a word: a file has its own rate and length)
        raise ConfigError("--fs and --duration are for live input (--device); a recording file "
                          "is read at its own sample rate, whole")
    duration = time_limit("--duration", duration)  # (None: no limit; as `hearsee run`)
    visual = [o for o in (video, camera_device, image_points) if o is not None]
    if len(visual) > 1:
        raise ConfigError("use only one of --video, --camera-device and --image-points")
    if visual and camera is None:
        raise ConfigError("--video / --camera-device / --image-points need --camera CAM.yaml "
                          "(a calibrated camera; see `hearsee calibrate`)")
    if camera is not None and not visual:
        raise ConfigError("--camera needs an image-point source: --video, --camera-device or "
                          "--image-points")
    if camera_device is not None and device is None:
        # (a recording streams many times faster than real time: its frames were paired with
        # what the camera sees now -- a walk filmed live in step with it gave no 3D fix, exit 0
        # and no word)
        raise ConfigError("--camera-device is a live camera, for live input (--device); give a "
                          "recording's own video with --video")
    pose = [n for n, o in (("--camera-at", camera_at), ("--camera-pan", camera_pan),
                           ("--camera-tilt", camera_tilt)) if o is not None]
    if pose and camera is None:  # (they were ignored without a word)
        raise ConfigError(f"{' / '.join(pose)} need{'s' if len(pose) == 1 else ''} --camera "
                          "CAM.yaml and an image-point source (they place the camera)")
    if detector is not None and video is None and camera_device is None:
        # (it was ignored without a word: --image-points are the image point itself)
        raise ConfigError("--detector finds the speaker in the images of --video or "
                          "--camera-device; give one of them, or leave it out")
    if motion_model is MotionModel.ca and camera is None:
        # (it was ignored without a word: no 3D track, acceleration_mps2 null on every line)
        raise ConfigError("--motion-model ca chooses the 3D tracker of a calibrated camera's "
                          "fixes: it needs --camera CAM.yaml and an image-point source (without "
                          "them there is no 3D track and no acceleration_mps2)")
    check_frame_ms(frame_ms, hop_ms, names=("--frame-ms", "--hop-ms"))
    whole_number("--sources", sources, 1, MAX_SOURCES)
    band = None if band_hz is None else parse_band(band_hz)
    if rate_tau is None:
        rate_tau = DIRECTION_RATE_TAU_S
    if not rate_tau > 0:
        raise ConfigError(f"--rate-tau must be > 0 s (inf = constant velocity), got {rate_tau}")
    if not 0.0 <= gate_coherence <= 1.0:
        raise ConfigError(f"--gate-coherence must be in [0, 1] (0 = off), got {gate_coherence}")
    arr = load_array(array)
    # (a masked pair's stream has neither: both were ignored without a word, as they are
    # refused by `hearsee localize`)
    if in_plane and arr.mask is not None:
        raise ConfigError(f"--in-plane: the masked pair {arr.name!r} is tracked by its own "
                          "stages (ch. 3; tables of the horizontal plane) without an in-plane "
                          "model; leave it out")
    if gate_coherence > 0 and arr.mask is not None:
        raise ConfigError(f"--gate-coherence: the masked pair {arr.name!r} is tracked by its own "
                          "stages (ch. 3), without the steered response that gated detection "
                          "searches; leave it out")
    chosen = parse_channels(channels, arr.n_mics)
    # (a vertical line, a masked pair with a camera or several talkers: refused before any
    # audio)
    check_trackable(arr, camera=camera is not None, max_sources=sources if sources > 1 else None,
                    setting="--sources")
    rig = points = None
    if camera is not None:
        from hearsee.fusion.audiovisual import AudioVisualRig
        from hearsee.stream.video import CsvImagePoints, VideoImagePoints
        from hearsee.vision.camera import load_camera

        pos, pan, tilt = _camera_pose(camera_at, camera_pan, camera_tilt, arr.centre)
        cam = load_camera(camera)
        rig = AudioVisualRig.mounted(arr, cam, pos, pan, tilt)
        if image_points is not None:
            points = CsvImagePoints(image_points, camera=cam)
        else:  # (a video file that delivers no frame: refused here, before the audio)
            points = VideoImagePoints(camera_device if video is None else video,
                                      detector=(detector or Detector.hog).value,
                                      expected_size=cam.size, where="--video")
    cfg = StreamConfig(frame_ms=frame_ms, hop_ms=hop_ms, method=method.value.replace("gcc-", ""),
                       itd_filter=itd_filter, in_plane=in_plane,
                       direction_modes_dps2=IMM_MODES_DPS2 if tracker is Tracker.imm else None,
                       direction_rate_tau_s=rate_tau,
                       gated_min_coherence=gate_coherence if gate_coherence > 0 else None,
                       max_sources=sources if sources > 1 else None,
                       motion_model=motion_model.value)

    updates: list = []  # (kept by the sink: what a Ctrl-C leaves is still reported)
    told = False  # (a file's wiring check warned: a microphone inverted or out of sync)

    def sink(u: object) -> None:
        updates.append(u)
        if fmt is TrackFormat.jsonl:
            sys.stdout.write(json.dumps(to_jsonable(u.to_json())) + "\n")  # type: ignore[attr-defined]
            sys.stdout.flush()

    try:
        if device is not None:
            rate = 16000 if fs is None else fs
            if chosen is None:
                source = opened = DeviceSource(_device_spec(device), arr.n_mics, rate,
                                               duration_s=duration, where="--device")
            else:  # (the microphones' channels of a larger device)
                source = mapped_device(_device_spec(device), chosen, rate, duration_s=duration,
                                       where="--device", channels_where="--channels")
                opened = source.source
        else:
            source = WavSource(recording, n_channels=arr, block_len=4096, channels=chosen)
        used = _stream_band(band, None if device is not None else source.x, source.fs,
                            frame_ms)
        cfg.band_hz, cfg.srp_band_hz = used, _srp_band(used, cfg.srp_band_hz)
        if used is not None:  # (a device's band is the one asked for: it says nothing)
            note_empty_band(opened.name if device is not None else recording_label(recording),
                            used, band, source.fs)
        lines: tuple[float, ...] = ()
        heard_by = arr  # (the array the stream localizes with: without a dead microphone)
        used_mics = list(range(arr.n_mics))
        if device is None:
            told, lines, dead = _check_wiring(source.x, source.fs, arr, cfg)
            if dead:  # (the directions were built with the dead channel, 20-30 deg off)
                from hearsee.audio.localize import without_microphones
                from hearsee.stream.pipeline import ArraySource

                used_mics, heard_by = without_microphones(arr, dead, stacklevel=2)
                source = ArraySource(source.x[used_mics], source.fs,
                                     block_len=source.block_len)
                if rig is not None:  # (the camera's fixes read the TDOAs with these
                    # microphones: the full array's took microphone 0-1's for 1-2's, 1 m off)
                    from dataclasses import replace

                    rig = replace(rig, array=heard_by)
        # (a file was checked ahead, above; live input once it has heard a source)
        pipe = StreamPipeline(heard_by, cfg, rig=rig, image_points=points,
                              tonal_lines_hz=lines)
        try:
            pipe.run(source, sink, threaded=device is not None)
        except KeyboardInterrupt:
            if device is None:
                raise  # a file: the CLI's 'interrupted' (exit 130)
            # live input runs until Ctrl-C (no --duration): the run ends there, as `hearsee
            # run` does -- the updates so far and the stats (status "interrupted") are
            # reported; --format json printed nothing and --stats no stats
    finally:
        close = getattr(points, "close", None)  # release a video / stop a live camera's thread
        if close is not None:
            close()
    st = pipe.stats
    summary = {"frames": st.n_frames, "missing_frames": st.n_missing_frames,
               "dropped_blocks": st.n_dropped_blocks, "late_blocks": st.n_late_blocks,
               "input_overflows": st.n_overflows, "status": st.status, "audio_s": st.audio_s,
               "real_time_factor": st.real_time_factor,
               "cpu_real_time_factor": st.cpu_real_time_factor, **st.latency_summary(),
               "tonal_lines_hz": list(st.tonal_lines_hz),
               # (live input: those the stream's own check left out, see StreamStats)
               "microphones_used": [m for m in used_mics if m not in st.dead_microphones]}
    if fmt is TrackFormat.json:
        # (a device by the name PortAudio gives it: "--device 2" or a part of a name is not
        # what was opened)
        heard = opened.name if device is not None else recording_entry(recording)
        emit_json({"array": arr.to_dict(), "source": heard,
                   "updates": [u.to_json() for u in updates], "stats": summary})
    if stats or st.status != "ok":
        err_console.print(
            f"track: {st.n_frames} frames, {st.audio_s:.2f} s of audio, "
            f"{st.real_time_factor:.1f}x real time ({st.cpu_real_time_factor:.1f}x in CPU "
            f"time), latency median "
            f"{summary['median_ms']:.1f} ms (p95 {summary['p95_ms']:.1f} ms), "
            f"{st.n_dropped_blocks} dropped / {st.n_late_blocks} late blocks, "
            f"{st.n_overflows} input overflows, status {st.status}",
            highlight=False)
    if not any(u.measured for u in updates) and not told:
        # (after a warning of a microphone inverted or out of sync, which says why)
        err_console.print("hearsee: warning: track: no frame held a localizable source",
                          highlight=False)
    if image_points is not None and updates and not points.visible_within(
            updates[0].t, updates[-1].t):
        # (rows all outside the recording, e.g. times in ms or of another take: no 3D fix
        # and no message)
        from hearsee.errors import DegenerateInputWarning

        span = points.visible_span()
        where = ("the file has no visible point: every u,v is empty" if span is None else
                 f"the file's visible points are from {span[0]:g} s to {span[1]:g} s")
        warnings.warn(f"{image_points}: no image point lies within the recording's time span "
                      f"(0-{st.audio_s:.2f} s; {where}), so no 3D position can be given",
                      DegenerateInputWarning, stacklevel=1)
    if points is not None and image_points is None and updates:
        _warn_short_video(points, video if video is not None else f"camera {camera_device}",
                          updates[-1].t)
    if st.status == "stalled":  # as 'hearsee run': what was printed is valid, the run is not
        err_console.print("hearsee: error: track: the audio input stopped delivering samples",
                          highlight=False)
        raise typer.Exit(1)
