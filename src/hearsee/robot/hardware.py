"""Real hardware: ``hearsee run --config robot.yaml`` -- live microphones, cameras, pan-tilt head.

The robot file (YAML) says which devices to open and where the sensors sit on the head. Every
field is checked when the file is loaded; an unknown or bad field, impossible geometry or a
missing calibration raises :class:`hearsee.errors.ConfigError` whose one-line message names the
file and the field, e.g. ``robot.yaml: audio.device: no input device named 'ReSpeaker'
(available: 0 'HDA Intel PCH: ALC3246 Analog (hw:0,0)' (2 in), ...)``. Relative paths are
relative to the robot file's folder.

Schema (defaults in brackets)::

    audio:                              # required
      device: "ReSpeaker" | 2           [default input]  input device: name substring or index
      fs: 16000                         [16000]  sample rate, Hz
      channels: [1, 2, 3, 4]            [0 .. n_mics-1]  input channel (0-based) of microphone k
      array: respeaker-4 | mics.yaml    [three-mic]  array preset or YAML file (array frame):
                                        spread out horizontally, or a masked pair (a bare
                                        pair such as two-mic has a front/back mirror)
      block_ms: 100                     [100]  audio block read from the device, ms
      frame_ms: 64                      [64]   TDOA analysis frame, ms (hop = frame / 2; one
                                        update, one JSON line, per hop)
      method: phat                      [phat] GCC weighting (phat, scot, roth, ml, cc)
    cameras:                            # optional: without it the robot only hears
      left: 0 | /dev/video0 | file.mp4 | rtsp://...   VideoCapture index, path or URL (a
                                                      video file plays at its own frame rate)
      right: 1                                        (left + right) ...
      stereo: 0                                       ... or ONE side-by-side device
                                                      (left image | right image)
      thermal: 2                        [none]  optional thermal camera: 8-bit grey video,
                                        white = warm (colour palettes are converted to grey,
                                        which is only right for grey-scale output)
      calib: rig.yaml                   required: rig YAML from `hearsee calibrate` (with a
                                        thermal block when `thermal` is given)
      rate_hz: 2                        [2]    human detection rate, frames per second
      num_disparities: 96               [64]   the stereo matcher's search, pixels: people
                                        nearer than f B / (num_disparities - 1) are flagged
                                        beyond_search (64 at f B = 60 px m: 0.95 m)
      mount_m: [0.05, 0.06, 0.10]       [[0, 0, 0]]  left camera's optical centre from the
                                        head pivot, head frame (x fwd, y left, z up), metres;
                                        the cameras look along the head's +x axis
    head:
      pivot_m: [0, 0, 1.2]              [[0, 0, 1.2]]  pan-tilt pivot in the robot frame, m
      offset_m: [0, 0, 0.08]            [[0, 0, 0]]    array origin from the pivot, head frame, m
                                        (the audio bearing is heard from it)
      pan_limits_deg: [-170, 170]       [[-170, 170]]  the commanded pan stays within these
                                        (a target beyond them: the nearer limit)
      tilt_limits_deg: [-30, 60]        [[-90, 90]]    the commanded tilt (+ = gaze up) stays
                                        within these; the camera must stay above the floor
                                        over the whole range
      pose_deg: [0, 0]                  [[0, 0]]   pan, tilt the head is at (driver none: it
                                        stays there; only the desired command is printed)
      driver: none                      [none]     only `none` is implemented: the desired
                                        pan/tilt command is printed and logged, nothing moves
                                        (a real driver is passed to run_robot(head=...); the
                                        loop follows its pose, see PrintHeadDriver)
    output:
      jsonl: run.jsonl                  [hearsee-run/updates.jsonl]  one JSON line per update
      report: hearsee-run               [hearsee-run]  report folder (index.html, log.json, ...)

Frames follow REP 103 (x forward, y left, z up). Azimuths in the log are in the ROBOT frame
(the head pose is applied); positions are metres in the robot frame.

``--dry-run`` (:func:`check_devices`) opens every device once: PortAudio is there, the input
device exists with enough channels and accepts the sample rate (``sd.check_input_settings``),
each camera opens and delivers a frame of the calibrated size (within
:data:`~hearsee.stream.video.FIRST_FRAME_TIMEOUT_S`), the calibration loads. In the live loop a
camera device or stream that stops delivering does not stall the audio: its reads give up after
:data:`CAMERA_READ_TIMEOUT_S`, and after three failed reads the loop goes on with audio only,
trying the cameras again every :data:`CAMERA_RETRY_S` seconds of audio until they deliver.
"""

from __future__ import annotations

import json
import math
import sys
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from hearsee.audio.arrays import MicArray, load_array_beside
from hearsee.audio.signals import microphone_channels
from hearsee.config import (
    as_float_array,
    as_path,
    check_keys,
    expand_path,
    finite_number,
    load_yaml,
    number,
    same_file,
    whole_number,
)
from hearsee.errors import AudioInputError, ConfigError, GeometryError, HearseeError
from hearsee.stream.device import (  # (import_sounddevice, resolve_input_device: re-exported)
    import_sounddevice,
    resolve_input_device,
)
from hearsee.stream.pipeline import MappedSource  # (re-exported: its home was here)
from hearsee.stream.video import (  # (read_frame re-exported: its home was here)
    FIRST_FRAME_TIMEOUT_S,
    FileFrameClock,
    TimedCapture,
    read_frame,
)

if TYPE_CHECKING:  # imported when run_robot runs (the simulated loop's heavier imports)
    from hearsee.robot.pipeline import RunResult

__all__ = [
    "AudioConfig",
    "CameraConfig",
    "Check",
    "HeadConfig",
    "OutputConfig",
    "RobotConfig",
    "check_devices",
    "check_outputs",
    "import_sounddevice",
    "load_robot_config",
    "lowest_camera_m",
    "open_capture",
    "report_scenario",
    "resolve_input_device",
    "robot_config_from_dict",
    "run_robot",
    "verify_audio_device",
    "write_run_report",
]

DRIVERS = ("none",)
_TOP = ("audio", "cameras", "head", "output")
_AUDIO = ("device", "fs", "channels", "array", "block_ms", "frame_ms", "method")
_CAMERAS = ("left", "right", "stereo", "thermal", "calib", "rate_hz", "mount_m",
            "num_disparities")
_HEAD = ("pivot_m", "offset_m", "pan_limits_deg", "tilt_limits_deg", "pose_deg", "driver")
_OUTPUT = ("jsonl", "report")
DeviceSpec = int | str


# ---------------------------------------------------------------------------------------------
# Configuration
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AudioConfig:
    """Microphones: ``device`` (index, name substring or None = default input), ``fs`` Hz,
    ``channels`` (input channel of each microphone), the ``array`` geometry and its
    ``array_spec`` (its YAML file's absolute path, or its preset's name), ``block_ms`` (the
    device's block), ``frame_ms`` (TDOA frame; one update per hop = frame / 2) and the GCC
    ``method``."""

    device: DeviceSpec | None
    fs: int
    channels: tuple[int, ...]
    array: MicArray
    array_spec: str
    block_ms: float = 100.0
    frame_ms: float = 64.0
    method: str = "phat"

    @property
    def n_open(self) -> int:
        """Number of input channels to open (the highest mapped channel + 1)."""
        return max(self.channels) + 1

    @property
    def block_len(self) -> int:
        return max(int(round(self.block_ms * 1e-3 * self.fs)), 1)


@dataclass(frozen=True)
class CameraConfig:
    """Cameras: ``left``/``right`` or one side-by-side ``stereo`` device, optional ``thermal``,
    the calibrated ``rig`` (from ``calib``), the detection ``rate_hz``, the left camera's
    ``mount_m`` (head frame, metres) and the matcher's ``num_disparities`` (None: the
    detector's default, :data:`hearsee.vision.fusion.DEFAULT_STEREO_OPTIONS`)."""

    left: DeviceSpec | None
    right: DeviceSpec | None
    stereo: DeviceSpec | None
    thermal: DeviceSpec | None
    calib: Path
    rig: Any  # hearsee.vision.camera.StereoRig
    rate_hz: float = 2.0
    mount_m: NDArray = field(default_factory=lambda: np.zeros(3))
    num_disparities: int | None = None

    def stereo_options(self) -> dict[str, Any] | None:
        """The disparity options the live loop's detector gets (None: its defaults)."""
        return None if self.num_disparities is None else {
            "num_disparities": self.num_disparities}

    def devices(self) -> dict[str, DeviceSpec]:
        """``{"cameras.left": spec, ...}`` of the devices to open."""
        out = {}
        for name in ("left", "right", "stereo", "thermal"):
            v = getattr(self, name)
            if v is not None:
                out[f"cameras.{name}"] = v
        return out

    def expected_size(self, name: str) -> tuple[int, int]:
        """``(width, height)`` a device must deliver (side-by-side: twice the width)."""
        rig = self.rig
        if name == "thermal":
            return rig.thermal.size
        w, h = (rig.left if name != "right" else rig.right).size
        return (2 * w, h) if name == "stereo" else (w, h)


@dataclass(frozen=True)
class HeadConfig:
    """The pan-tilt head: ``pivot_m`` (robot frame), ``offset_m`` (array origin, head frame),
    ``pan_limits_deg``, the current ``pose_deg`` (pan, tilt), the ``driver`` and
    ``tilt_limits_deg`` (degrees, + = gaze up)."""

    pivot_m: NDArray
    offset_m: NDArray
    pan_limits_deg: tuple[float, float] = (-170.0, 170.0)
    pose_deg: tuple[float, float] = (0.0, 0.0)
    driver: str = "none"
    tilt_limits_deg: tuple[float, float] = (-90.0, 90.0)


@dataclass(frozen=True)
class OutputConfig:
    jsonl: Path
    report: Path


@dataclass(frozen=True)
class RobotConfig:
    """A validated robot file (see the module docstring)."""

    path: Path
    audio: AudioConfig
    cameras: CameraConfig | None
    head: HeadConfig
    output: OutputConfig

    def input_files(self) -> list[Path]:
        """Files the run reads (never to be overwritten by its outputs)."""
        files = [self.path]
        a = Path(self.audio.array_spec)  # (a file's absolute path, or a preset's name)
        if a.is_absolute() and a.is_file():
            files.append(a)
        if self.cameras is not None:
            files.append(self.cameras.calib)
            files += [Path(v) for v in self.cameras.devices().values()
                      if isinstance(v, str) and Path(v).is_file()]
        return files

    def with_output(self, folder: str | Path) -> RobotConfig:
        """A copy writing the report to ``folder`` and the JSON lines to folder/updates.jsonl."""
        f = Path(folder)
        return RobotConfig(self.path, self.audio, self.cameras, self.head,
                           OutputConfig(f / "updates.jsonl", f))


def _mapping(d: Mapping[str, Any], key: str, where: str, required: bool = False
             ) -> Mapping[str, Any] | None:
    if key not in d or d[key] is None:
        if required:
            raise ConfigError(f"{where}: missing required key {key!r}")
        return None
    v = d[key]
    if not isinstance(v, Mapping):
        # (it was "robot.yaml.audio: ...", as if the section were part of the file name)
        raise ConfigError(f"{where}: {key}: expected a mapping, got {type(v).__name__}")
    return v


def _resolve(p: str | Path, base: Path, where: str) -> Path:
    """``p`` (the robot file's path ``where``) expanded (:func:`~hearsee.config.expand_path`)
    and, when relative, taken from the robot file's folder ``base``."""
    q = expand_path(p, where)
    return q if q.is_absolute() else expand_path(base / q, where)


def _device(v: Any, where: str, base: Path, *, camera: bool) -> DeviceSpec:
    """An input device: an index (int or digit string), a name substring (audio) or a
    path/URL (cameras; paths must exist)."""
    if isinstance(v, bool) or v is None:
        raise ConfigError(f"{where}: expected a device index or name, got {v!r}")
    if isinstance(v, int):
        if v < 0:
            raise ConfigError(f"{where}: device index must be >= 0, got {v}")
        return v
    if not isinstance(v, str) or not v.strip():
        raise ConfigError(f"{where}: expected a device index or name, got {v!r}")
    s = v.strip()
    if s.isascii() and s.isdigit():  # (int("²") raised a builtin ValueError)
        return int(s)
    if not camera:
        return s
    if "://" in s:
        return s
    p = _resolve(s, base, where)
    if not p.exists():
        raise ConfigError(f"{where}: no such camera device or video file {s!r}")
    return str(p)


def _same_device(a: DeviceSpec, b: DeviceSpec) -> bool:
    """Whether two camera specs (:func:`_device`'s) name one device: the same index, URL or
    file (:func:`hearsee.config.same_file`: also through a symlink such as
    /dev/v4l/by-id/...)."""
    if isinstance(a, int) or isinstance(b, int) or "://" in a or "://" in b:
        return a == b
    return same_file(a, b)


def _array(spec: Any, where: str, base: Path) -> tuple[MicArray, str]:
    """``audio.array`` (``where``): the array and its spec -- the absolute path of a YAML file
    (relative to the robot file's folder ``base``) or the name of a preset shipped with
    hearsee (:func:`hearsee.audio.arrays.load_array_beside`, the rule of every file's array:
    a name is a preset only when no such file is in ``base`` and it has neither a folder nor
    a YAML suffix, any case; never looked up in the working directory). Any error is a
    ConfigError naming the field."""
    try:
        return load_array_beside(spec, base, where)
    except HearseeError as exc:
        raise ConfigError(str(exc)) from None


def _audio(d: Mapping[str, Any], where: str, base: Path) -> AudioConfig:
    check_keys(d, _AUDIO, where)
    dev = d.get("device")
    device = None if dev is None else _device(dev, f"{where}.device", base, camera=False)
    fs = number(d, "fs", 16000, where, 4000, 384000, integer=True)
    array, spec = _array(d.get("array", "three-mic"), f"{where}.array", base)
    from hearsee.stream.pipeline import check_trackable

    try:  # (the live loop's stream cannot use a vertical line: say so now)
        check_trackable(array)
    except ConfigError as exc:
        raise ConfigError(f"{where}.array: {exc}") from None
    from hearsee.robot.scenario import check_hears_front_and_back

    # (accepted: a bare pair, or an upright face plate, heard a talker at 150 deg at 30 deg --
    # the stream reports the front one of the mirror pair -- and the head was sent there,
    # without a word; the scenario file's rule)
    check_hears_front_and_back(array, f"{where}.array", "the robot")
    ch = d.get("channels")
    channels = (tuple(range(array.n_mics)) if ch is None
                else microphone_channels(ch, array.n_mics, f"{where}.channels"))
    block_ms = number(d, "block_ms", 100.0, where, 10.0, 2000.0)
    frame_ms = number(d, "frame_ms", 64.0, where, 8.0, 1000.0)
    from hearsee.audio.tdoa import check_frame_for_array, normalize_method

    check_frame_for_array(frame_ms, array, f"{where}.frame_ms")
    method = d.get("method", "phat")
    if not isinstance(method, str):  # (a null was "unknown GCC method 'None'", as if the file
        # had named a method "None"; a number was quoted as a name too)
        from hearsee.audio.tdoa import METHODS

        got = "null (no value)" if method is None else f"{method!r} ({type(method).__name__})"
        raise ConfigError(f"{where}.method: expected a GCC weighting name, one of "
                          f"{', '.join(METHODS)} (or gcc-<name>; leave the key out for phat), "
                          f"got {got}")
    try:
        method = normalize_method(method)
    except ConfigError as exc:
        raise ConfigError(f"{where}.method: {exc}") from None
    return AudioConfig(device, int(fs), channels, array, spec, block_ms, frame_ms, method)


def _cameras(d: Mapping[str, Any], where: str, base: Path) -> CameraConfig:
    check_keys(d, _CAMERAS, where)
    dev = {k: (None if d.get(k) is None else _device(d[k], f"{where}.{k}", base, camera=True))
           for k in ("left", "right", "stereo", "thermal")}
    if dev["stereo"] is not None and (dev["left"] is not None or dev["right"] is not None):
        raise ConfigError(f"{where}: give either left + right or one side-by-side stereo "
                          "device, not both")
    if dev["stereo"] is None and (dev["left"] is None or dev["right"] is None):
        missing = "left" if dev["left"] is None else "right"
        raise ConfigError(f"{where}.{missing}: missing (give left + right, or stereo for one "
                          "side-by-side device)")
    # (one device given twice was accepted: left = right made a "stereo pair" of one view,
    # whose zero disparity put everything at infinity and found no one, without a word)
    given = [k for k in ("stereo", "left", "right", "thermal") if dev[k] is not None]
    for i, k in enumerate(given):
        for first in given[:i]:
            if _same_device(dev[k], dev[first]):
                raise ConfigError(f"{where}.{k}: {d[k]!r} is the device of cameras.{first}; "
                                  "each camera needs its own device (one side-by-side stereo "
                                  "device: cameras.stereo)")
    if "calib" not in d or d["calib"] is None:
        raise ConfigError(f"{where}.calib: missing: the cameras need a rig calibration file "
                          "(create one with `hearsee calibrate`)")
    if not isinstance(d["calib"], str):
        raise ConfigError(f"{where}.calib: expected a file path, got {d['calib']!r}")
    calib = _resolve(d["calib"], base, f"{where}.calib")
    if not calib.exists():  # (a folder: load_rig's InputFileError says so, below)
        raise ConfigError(f"{where}.calib: calibration file {d['calib']!r} not found "
                          "(create one with `hearsee calibrate`)")
    from hearsee.vision.camera import load_rig

    try:
        rig = load_rig(calib)
    except HearseeError as exc:
        raise ConfigError(f"{where}.calib: {exc}") from None
    if dev["thermal"] is not None and rig.thermal is None:
        raise ConfigError(f"{where}.thermal: the calibration {d['calib']!r} has no thermal "
                          "camera (add a 'thermal:' block or leave out cameras.thermal)")
    rate = number(d, "rate_hz", 2.0, where, 0.1, 60.0)
    from hearsee.geometry import check_camera_mount

    mount = check_camera_mount(d.get("mount_m", [0.0, 0.0, 0.0]), f"{where}.mount_m",
                               ConfigError)
    nd = d.get("num_disparities")
    if nd is not None:  # checked here, not by the first detection of a live run
        from hearsee.vision.stereo import search_range_px

        try:
            nd = whole_number("num_disparities", nd, 1)
            hi = search_range_px(rig.left.size[0], nd)[1]
        except HearseeError as exc:
            raise ConfigError(f"{where}.num_disparities: {exc}") from None
        if hi >= rig.left.size[0]:  # (search_range_px refuses one beyond SGBM's reach)
            raise ConfigError(f"{where}.num_disparities: {nd} searches disparities up to "
                              f"{hi:g} px, beyond the {rig.left.size[0]}-pixel-wide images")
    return CameraConfig(dev["left"], dev["right"], dev["stereo"], dev["thermal"], calib, rig,
                        rate, mount, nd)


def _pair(d: Mapping[str, Any], key: str, default: tuple[float, float], where: str
          ) -> tuple[float, float]:
    a = as_float_array(d.get(key, list(default)), f"{where}.{key}", shape=(2,))
    return float(a[0]), float(a[1])


def _head(d: Mapping[str, Any], where: str) -> HeadConfig:
    from hearsee.geometry import check_head_offset, check_head_pivot

    check_keys(d, _HEAD, where)
    pivot = check_head_pivot(d.get("pivot_m", [0.0, 0.0, 1.2]), f"{where}.pivot_m", ConfigError)
    if not pivot[2] > 0:  # (passed: the live loop then gave the detector a camera under the floor)
        raise ConfigError(f"{where}.pivot_m: the pivot must be above the floor (z > 0 m; the "
                          f"robot frame's origin is on the floor), got z = {pivot[2]:g} m")
    offset = check_head_offset(d.get("offset_m", [0.0, 0.0, 0.0]), f"{where}.offset_m",
                               ConfigError)
    lo, hi = pan_limits_deg(_pair(d, "pan_limits_deg", (-170.0, 170.0), where),
                            f"{where}.pan_limits_deg")
    t_lo, t_hi = tilt_limits_deg(_pair(d, "tilt_limits_deg", (-90.0, 90.0), where),
                                 f"{where}.tilt_limits_deg")
    pan, tilt = _pair(d, "pose_deg", (0.0, 0.0), where)
    if not lo <= pan <= hi:
        raise ConfigError(f"{where}.pose_deg: pan {pan} is outside pan_limits_deg [{lo}, {hi}]")
    if not t_lo <= tilt <= t_hi:
        raise ConfigError(f"{where}.pose_deg: tilt {tilt} is outside tilt_limits_deg "
                          f"[{t_lo:g}, {t_hi:g}]")
    driver = d.get("driver", "none")
    if driver is None:
        driver = "none"
    if driver not in DRIVERS:
        raise ConfigError(f"{where}.driver: {driver!r} is not supported (available: "
                          f"{', '.join(DRIVERS)}: print the desired pan/tilt command only)")
    return HeadConfig(pivot, offset, (lo, hi), (pan, tilt), str(driver), (t_lo, t_hi))


def lowest_camera_m(pivot_m: Any, mount_m: Any,
                    tilt_limits: tuple[float, float] = (-90.0, 90.0)) -> tuple[float, float]:
    """``(z_m, tilt_deg)``: the lowest height (robot-frame z, metres above the floor) that
    the left camera's centre -- ``mount_m`` from the pivot ``pivot_m`` (head frame and robot
    frame, metres) -- reaches over the head's tilts ``tilt_limits`` (degrees, + = gaze up;
    the robot file's ``head.tilt_limits_deg``: the loop's commands are clipped to them), and
    that tilt.
    The pan turns about z and leaves the height alone; over tilt b it is pivot_z + mount_x
    sin b + mount_z cos b, lowest at a tilt limit or, for a camera below the pivot
    (mount_z < 0), at b = atan(mount_x / mount_z), where the camera swings lowest."""
    from hearsee.geometry import array_to_robot

    mx, mz = float(mount_m[0]), float(mount_m[2])
    lo, hi = (float(b) for b in tilt_limits)
    swing = math.degrees(math.atan(mx / mz)) + 0.0 if mz < 0 else None
    tilts = [lo, hi] + ([swing] if swing is not None and lo < swing < hi else [])
    heights = [float(array_to_robot(np.zeros(3), (0.0, b), pivot_m, mount_m)[2]) for b in tilts]
    k = int(np.argmin(heights))
    return heights[k], tilts[k]


def _check_camera_above_floor(cameras: CameraConfig, head: HeadConfig, where: str) -> None:
    """ConfigError naming ``where`` (``cameras.mount_m``) unless the left camera's centre stays
    above the floor at every tilt the head can take (:func:`lowest_camera_m`). Only the
    pivot was checked: a camera mounted below it passed the load and the dry run, and the
    live run died at its first frame (the detector's camera height below the floor)."""
    lo, hi = head.tilt_limits_deg
    z, tilt = lowest_camera_m(head.pivot_m, cameras.mount_m, (lo, hi))
    if not z > 0:
        raise ConfigError(f"{where}: the left camera's centre, {cameras.mount_m.tolist()} m "
                          f"from head.pivot_m {head.pivot_m.tolist()} m (head frame), comes "
                          f"down to z = {z:.3f} m at head tilt {tilt:+.1f} deg; it must stay "
                          f"above the floor (z > 0 m) at every tilt in head.tilt_limits_deg "
                          f"[{lo:g}, {hi:g}] (narrow them if the head cannot tilt that far)")


def _output(d: Mapping[str, Any], where: str, base: Path) -> OutputConfig:
    check_keys(d, _OUTPUT, where)
    for k in _OUTPUT:
        if k in d and (not isinstance(d[k], str) or not d[k].strip()):
            raise ConfigError(f"{where}.{k}: expected a path, got {d[k]!r}")
    report = _resolve(d.get("report", "hearsee-run"), base, f"{where}.report")
    jsonl = (_resolve(d["jsonl"], base, f"{where}.jsonl") if "jsonl" in d
             else report / "updates.jsonl")
    if jsonl.suffix.lower() not in (".jsonl", ".ndjson", ".json"):
        raise ConfigError(f"{where}.jsonl: expected a .jsonl file name, got {d['jsonl']!r}")
    return OutputConfig(jsonl, report)


def robot_config_from_dict(data: Mapping[str, Any], where: str = "robot.yaml",
                           base_dir: str | Path | None = ".", *,
                           check_output: bool = True) -> RobotConfig:
    """Validate a robot mapping (see the module docstring). ``where`` prefixes every error;
    relative paths are resolved against ``base_dir`` (None: the current folder, as
    :func:`hearsee.robot.scenario.scenario_from_dict`; anything but a path is an
    InputFileError). ``check_output=False``: the ``output`` section's keys and types are
    checked, but not its paths on disk (:func:`check_outputs`) -- for a caller that replaces
    the outputs (:meth:`RobotConfig.with_output`, ``hearsee run --out``) and checks those."""
    if not isinstance(data, Mapping):
        raise ConfigError(f"{where}: expected a mapping at top level")
    base = Path(".") if base_dir is None else as_path(base_dir, "base_dir")
    check_keys(data, _TOP, where)
    audio = _audio(_mapping(data, "audio", where, required=True), f"{where}: audio", base)
    cams = _mapping(data, "cameras", where)
    cameras = None if cams is None else _cameras(cams, f"{where}: cameras", base)
    head = _head(_mapping(data, "head", where) or {}, f"{where}: head")
    if cameras is not None:
        _check_camera_above_floor(cameras, head, f"{where}: cameras.mount_m")
    output = _output(_mapping(data, "output", where) or {}, f"{where}: output", base)
    cfg = RobotConfig(Path(where), audio, cameras, head, output)
    if check_output:
        check_outputs(cfg, where)
    return cfg


def check_outputs(cfg: RobotConfig, where: str) -> None:
    """ConfigError (prefixed ``where``) when ``output.report`` (or the folder it would be made
    in) is a file or not writable, ``output.jsonl`` names the same path or a folder, or the
    run's outputs would overwrite an input file: ``output.jsonl`` or ``output.report`` is
    one, the report would write over one (:func:`hearsee.robot.report.report_overwrites`), or
    the JSON lines are one of the report's own files. Checked when a robot file is loaded and
    again for ``run --out``."""
    from hearsee.robot.report import (
        REPORT_FILES,
        report_blocker_reason,
        report_folder_blocker,
        report_folder_unwritable,
        report_makes_folder,
        report_overwrites,
    )

    blocker = report_folder_blocker(cfg.output.report)
    if blocker is not None:  # (found only when the report was written, after the live run)
        raise ConfigError(f"{where}: output.report: {report_blocker_reason(blocker)}; "
                          "choose a report folder")
    locked = report_folder_unwritable(cfg.output.report)
    if locked is not None:  # (likewise: a PermissionError after the live run)
        raise ConfigError(f"{where}: output.report: folder {locked} is not writable; choose "
                          "another")
    if same_file(cfg.output.jsonl, cfg.output.report):
        raise ConfigError(f"{where}: output.jsonl and output.report are both "
                          f"{cfg.output.report}: the report is a folder, the JSON lines a file")
    ins = {p.resolve() for p in cfg.input_files() if p.exists()}
    for name, p in (("output.jsonl", cfg.output.jsonl), ("output.report", cfg.output.report)):
        if any(same_file(p, q) for q in ins):
            raise ConfigError(f"{where}: {name}: {p} is an input file; choose another path")
    hit = report_overwrites(cfg.output.report, sorted(ins))
    if hit is not None:
        raise ConfigError(f"{where}: output.report: writing {cfg.output.report.resolve()} "
                          f"would overwrite the input file {hit}; choose another folder")
    if cfg.output.jsonl.is_dir():  # (passed the dry run; the run failed when it started)
        raise ConfigError(f"{where}: output.jsonl: {cfg.output.jsonl} is a folder; the JSON "
                          "lines are a file: choose a file name")
    from hearsee.robot.report import file_in_the_way

    above = file_in_the_way(cfg.output.jsonl.parent)
    if above is not None:  # (likewise: "cannot write ...: Not a directory" when the run
        # started, after a dry run whose checks all passed)
        raise ConfigError(f"{where}: output.jsonl: {cfg.output.jsonl}: {above} is a file, not "
                          "a folder; choose another folder for the JSON lines")
    if jsonl_foreign_file(cfg.output.jsonl):
        raise _foreign_jsonl_error(cfg.output.jsonl, f"{where}: ")
    if report_overwrites(cfg.output.report, [cfg.output.jsonl]) is not None:
        raise ConfigError(f"{where}: output.jsonl: {cfg.output.jsonl} is one of the report's "
                          f"files (output.report {cfg.output.report} writes "
                          f"{', '.join(REPORT_FILES)} and PNGs in plots/ and frames/); "
                          "choose another file name")
    # (the two outputs nested in each other passed, and the report failed after the live run:
    # jsonl out/run.jsonl with report out/run.jsonl/rep, "cannot create report folder ...:
    # Not a directory"; jsonl out/index.html/u.jsonl made the report's page a folder)
    if report_makes_folder(cfg.output.report, cfg.output.jsonl):
        raise ConfigError(f"{where}: output.jsonl: {cfg.output.jsonl}: output.report "
                          f"{cfg.output.report} needs this path as a folder (the report "
                          "folder, a folder above it, or its plots/ or frames/); the JSON "
                          "lines are a file: choose another file name")
    hit = report_overwrites(cfg.output.report, list(cfg.output.jsonl.parents))
    if hit is not None:
        raise ConfigError(f"{where}: output.jsonl: {cfg.output.jsonl} would make {hit} a "
                          f"folder, where output.report {cfg.output.report} writes a file; "
                          "choose another folder for the JSON lines")


def load_robot_config(path: str | Path, *, check_output: bool = True) -> RobotConfig:
    """Load and validate a robot file; errors name the file and the field (a ``path`` that is
    no file name, e.g. None, an InputFileError). ``check_output``: as
    :func:`robot_config_from_dict`'s (False where the outputs are replaced: ``hearsee run
    --out``; the file's own output.report or output.jsonl, which that run does not write,
    refused it until 2026-12-07)."""
    p = as_path(path, "the robot file's path")
    data = load_yaml(p)
    cfg = robot_config_from_dict(data, where=str(p), base_dir=p.resolve().parent,
                                 check_output=check_output)
    return RobotConfig(p, cfg.audio, cfg.cameras, cfg.head, cfg.output)


# ---------------------------------------------------------------------------------------------
# Devices
# ---------------------------------------------------------------------------------------------
def open_capture(spec: DeviceSpec, where: str) -> Any:
    """``cv2.VideoCapture(spec)``, opened, or ConfigError naming ``where``."""
    from hearsee.vision.io import video_capture

    cap = video_capture(spec)
    if not cap.isOpened():
        cap.release()
        raise ConfigError(f"{where}: cannot open camera {spec!r} (check the index, path or URL "
                          "and that no other program uses it)")
    return cap


def verify_audio_device(cfg: RobotConfig, sd: Any = None) -> dict[str, Any]:
    """The input device of ``cfg.audio``, checked: it exists, has enough input channels and
    accepts the sample rate (``sounddevice.check_input_settings``). ConfigError names the field;
    a missing PortAudio library is an AudioInputError."""
    a = cfg.audio
    sd = import_sounddevice() if sd is None else sd
    dev = resolve_input_device(sd, a.device, f"{cfg.path}: audio.device")
    field_name = "audio.channels" if a.channels != tuple(range(a.array.n_mics)) \
        else "audio.device"
    if dev["max_input_channels"] < a.n_open:
        raise ConfigError(f"{cfg.path}: {field_name}: device {dev['index']} {dev['name']!r} has "
                          f"{dev['max_input_channels']} input channels; the array needs "
                          f"{a.n_open} (channels {list(a.channels)})")
    try:
        sd.check_input_settings(device=dev["index"], channels=a.n_open, samplerate=a.fs,
                                dtype="float32")
    except Exception as exc:  # sounddevice raises PortAudioError or ValueError
        raise ConfigError(f"{cfg.path}: audio.fs: device {dev['index']} {dev['name']!r} "
                          f"does not accept {a.n_open} channels at {a.fs} Hz ({exc})") from None
    return dev


@dataclass
class Check:
    """One dry-run check: ``name`` (the config field), ``ok``, ``detail`` (what was found or the
    error message) and the ``error`` itself when it failed."""

    name: str
    ok: bool
    detail: str
    error: HearseeError | None = None


def _check(name: str, fn: Callable[[], str]) -> Check:
    try:
        return Check(name, True, fn())
    except HearseeError as exc:
        return Check(name, False, str(exc), exc)


def check_devices(cfg: RobotConfig) -> list[Check]:
    """Open every device of ``cfg`` once (``--dry-run``); one :class:`Check` per item.

    Audio: PortAudio present, the input device exists, has enough channels and accepts
    ``audio.fs`` (``sounddevice.check_input_settings``). Cameras: the calibration loads (done
    when the file was loaded), each device opens and delivers a frame of the calibrated size.
    """
    a = cfg.audio
    checks = [Check("config", True, f"{cfg.path}: {a.array.name} array ({a.array.n_mics} mics), "
                    f"head driver {cfg.head.driver}")]

    def audio() -> str:
        dev = verify_audio_device(cfg)
        return (f"device {dev['index']} {dev['name']!r}: {a.n_open} of "
                f"{dev['max_input_channels']} channels at {a.fs} Hz")

    checks.append(_check("audio.device", audio))
    cams = cfg.cameras
    if cams is not None:
        rig = cams.rig
        th = "" if rig.thermal is None else f" + thermal {rig.thermal.width}x{rig.thermal.height}"
        checks.append(Check("cameras.calib", True,
                            f"{cams.calib.name}: stereo {rig.left.width}x{rig.left.height}, "
                            f"baseline {rig.baseline_m:.3f} m{th}"))
        for field_name, spec in cams.devices().items():
            name = field_name.split(".")[1]

            def camera(where: str = f"{cfg.path}: {field_name}", spec: DeviceSpec = spec,
                       name: str = name) -> str:
                # (a device that opens and then blocks in every read hung the check)
                cap = TimedCapture(open_capture(spec, where), FIRST_FRAME_TIMEOUT_S)
                try:
                    size = cams.expected_size(name)
                    frame = read_frame(cap, spec, where, size)
                finally:
                    cap.release()
                return f"{spec!r}: {frame.shape[1]}x{frame.shape[0]} frame"

            checks.append(_check(field_name, camera))
    return checks


def first_failure(checks: Sequence[Check]) -> Check | None:
    """The first failed check, or None when all passed."""
    return next((c for c in checks if not c.ok), None)


# ---------------------------------------------------------------------------------------------
# Live sources
# ---------------------------------------------------------------------------------------------
def open_audio_source(cfg: RobotConfig, duration_s: float | None = None) -> MappedSource:
    """The live microphones of ``cfg`` (checked with :func:`verify_audio_device`) as a stream
    source: :class:`hearsee.stream.pipeline.DeviceSource` behind :class:`MappedSource`
    (:func:`hearsee.stream.pipeline.mapped_device`)."""
    from hearsee.stream.pipeline import mapped_device

    dev = verify_audio_device(cfg)
    a = cfg.audio
    return mapped_device(dev["index"], a.channels, a.fs, duration_s=duration_s,
                         channels_where="audio.channels", block_len=a.block_len,
                         queue_size=max(32, int(np.ceil(4000.0 / a.block_ms))))


@dataclass
class CameraFrames:
    """One set of camera frames: ``left``/``right`` BGR uint8 (calibrated size) and the
    ``thermal`` frame as grey uint8 (or None)."""

    left: NDArray
    right: NDArray
    thermal: NDArray | None = None


#: How long the live loop waits for one frame of a camera device or stream (seconds) before
#: it counts the read as failed (:class:`~hearsee.stream.video.TimedCapture`): a device that
#: blocks in its read stalled the loop, and with it the audio, forever. Three failed reads in a
#: row and the loop goes on with audio only; reads resume when the device delivers again
#: (tried every :data:`CAMERA_RETRY_S`).
CAMERA_READ_TIMEOUT_S = 1.0

#: Seconds of audio between the live loop's reads of cameras that stopped delivering (three
#: failed reads in a row): on the first read that delivers, reads go on at ``rate_hz``. Until
#: 2026-12-07 the loop never read them again: a camera's hiccup of three reads (1.5 s at
#: 2 Hz) left the rest of the run without vision.
CAMERA_RETRY_S = 1.0


class Cameras:
    """The cameras of a robot file, read through OpenCV ``VideoCapture``.

    :meth:`read` returns the next :class:`CameraFrames` (a side-by-side device is split into its
    halves), or None when a video file has ended or a device stopped delivering frames. Every
    frame is checked against the calibrated size.

    A video FILE plays at its own frame rate: ``read(t)`` takes from it the frame shown at
    ``t`` seconds (the latest frame whose time is at or before t, the first frame before
    that; frame times from :class:`hearsee.stream.video.FileFrameClock`: the file's
    timestamps, which keep the gaps of dropped frames, else frame k at ``k / CAP_PROP_FPS``),
    skipping the frames in between (a 30 fps file read every 0.1 s: frames 0, 3, 6, ...) or
    giving the same frame again while the file has no newer one (a file slower than the
    reads; None once its last frame's period is over). Devices and streams give their newest
    frame; so does a file of unknown frame rate; ``read()`` without ``t`` takes a file's next
    frame.
    """

    def __init__(self, cfg: CameraConfig, where: str = "") -> None:
        import cv2

        self.cfg = cfg
        self.where = where
        self.caps: dict[str, Any] = {}
        self.fps: dict[str, float] = {}  #: frame rate of each video file (Hz)
        self.last: dict[str, NDArray] = {}  #: each file's latest frame read
        self.last_t: dict[str, float] = {}  #: its time in the file (s)
        self._pending_t: dict[str, float] = {}  # a file's frame grabbed ahead: its time (s)
        self._clocks: dict[str, FileFrameClock] = {}  # each file's frame clock
        self.n_failures = 0  #: reads that delivered no frame
        self.n_consecutive_failures = 0
        try:
            for field_name, spec in cfg.devices().items():
                name = field_name.split(".")[1]
                cap = open_capture(spec, f"{where}{field_name}")
                is_file = isinstance(spec, str) and Path(spec).is_file()
                if not is_file:  # a device or stream, whose read may block: see TimedCapture
                    cap = TimedCapture(cap, CAMERA_READ_TIMEOUT_S)
                self.caps[name] = cap
                # a live device, by index or by path (/dev/video0; until 2026-12-07 only an
                # index): keep only the newest frame
                if isinstance(spec, int) or (not is_file and "://" not in spec):
                    cap.set(cv2.CAP_PROP_BUFFERSIZE, 1)
                fps = cap.get(cv2.CAP_PROP_FPS)
                if is_file and np.isfinite(fps) and fps > 0:
                    self.fps[name] = float(fps)
                    self._clocks[name] = FileFrameClock(fps)
        except BaseException:
            self.close()
            raise

    def _file_frame(self, name: str, t: float | None) -> NDArray | None:
        """A video file's frame shown at ``t`` seconds (its next frame for None; see the class
        notes), or None when the file has ended. Frames are grabbed one ahead to learn their
        time; a grabbed frame is decoded (retrieved) once it is due."""
        cap, fps, clock = self.caps[name], self.fps[name], self._clocks[name]
        eps = 1e-6 / fps  # (a frame due at t up to rounding)
        while True:
            if name not in self._pending_t:
                if not cap.grab():  # ended: the last frame until its period is over
                    last_t = self.last_t.get(name)
                    due = t is not None and last_t is not None and t + eps < last_t + 1.0 / fps
                    return self.last[name] if due else None
                self._pending_t[name] = clock(cap)
            if t is not None and name in self.last and self._pending_t[name] > t + eps:
                return self.last[name]  # the next frame is not due yet
            ok, frame = cap.retrieve()
            frame_t = self._pending_t.pop(name)
            if not ok or frame is None:
                return None
            self.last[name], self.last_t[name] = frame, frame_t
            if t is None:
                return frame

    def _grab(self, name: str, t: float | None = None) -> NDArray | None:
        if name in self.fps:  # a video file: its frame at t seconds
            frame = self._file_frame(name, t)
        else:
            ok, frame = self.caps[name].read()
            frame = frame if ok else None
        if frame is None:
            return None
        w, h = self.cfg.expected_size(name)
        if (frame.shape[1], frame.shape[0]) != (w, h):
            raise ConfigError(f"{self.where}cameras.{name}: camera delivers "
                              f"{frame.shape[1]}x{frame.shape[0]} frames but the calibration "
                              f"expects {w}x{h}")
        return frame

    def read(self, t: float | None = None) -> CameraFrames | None:
        """The frames at ``t`` seconds since the run began (video files; see the class notes),
        or the next ones; None when a source delivered none."""
        fr = self._read(t)
        if fr is None:
            self.n_failures += 1
            self.n_consecutive_failures += 1
        else:
            self.n_consecutive_failures = 0
        return fr

    def _read(self, t: float | None) -> CameraFrames | None:
        import cv2

        if "stereo" in self.caps:
            f = self._grab("stereo", t)
            if f is None:
                return None
            w = f.shape[1] // 2
            left, right = f[:, :w], f[:, w:]
        else:
            left, right = self._grab("left", t), self._grab("right", t)
            if left is None or right is None:
                return None
        thermal = None
        if "thermal" in self.caps:
            thermal = self._grab("thermal", t)
            if thermal is None:
                return None
            if thermal.ndim == 3:
                thermal = cv2.cvtColor(thermal, cv2.COLOR_BGR2GRAY)
        return CameraFrames(np.ascontiguousarray(left), np.ascontiguousarray(right), thermal)

    def close(self) -> None:
        for cap in self.caps.values():
            cap.release()
        self.caps = {}

    def __enter__(self) -> Cameras:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


#: The live loop rebuilds its head geometry when the driver's reported pose differs from the
#: one it was built for by more than this (degrees): encoder jitter is no head turn.
POSE_TOLERANCE_DEG = 0.5

#: The fastest head motion (degrees per second of audio) the live loop's stream hears through:
#: a head that moves no faster -- following a walker -- is heard, the stream told the head's pan
#: at every frame (``StreamPipeline.run(array_pan=)``: its direction tracker turns back with
#: the head instead of taking the head's turning for the talker's motion); a faster move is a
#: turn, after which the stream restarts once the head has settled. Judged over one frame plus
#: one audio block, the audio a move can reach. Until 2026-12-05 every move above
#: :data:`POSE_TOLERANCE_DEG` was a turn: a head following a person heard nothing while it
#: moved. Measured by ``bench/live_head.py`` (a closed loop: a 60 deg/s servo head following
#: walkers; bench/results/live_head.md): against that rule the share of updates with a
#: bearing rose ~4x and the head pointed closer to the talker; heard without telling the
#: stream the pans, the tracker lagged and overshot and the head swung about the talker
#: (worse pointing than before). The simulated loop's masked ears keep their state below the
#: same rate (:data:`hearsee.robot.pipeline.MASK_TURN_RESET_DEG` per 0.2-s step).
FOLLOW_RATE_DPS = 50.0

#: Seconds of audio over which the live loop keeps its reads of the head's pose, to place each
#: frame's audio at the pose of its time (``_pose_at``): a live source's blocks can wait in
#: the stream's queue (behind a slow update) for longer than one frame plus one block.
POSE_HISTORY_S = 2.0


def pan_change_deg(a_deg: float, b_deg: float) -> float:
    """``|a - b|`` of two pans (degrees) the short way round, in [0, 180]: 179.9 and -179.9
    are 0.2 deg apart, not 359.8. A pan that is not a finite number is a GeometryError (a NaN
    change compared False with every threshold: a NaN pose read as no head move)."""
    from hearsee.geometry import wrap_deg

    a = finite_number("pan_deg", a_deg, error=GeometryError)
    b = finite_number("pan_deg", b_deg, error=GeometryError)
    return abs(float(wrap_deg(a - b)))


def pan_limits_deg(limits_deg: Any, where: str = "pan_limits_deg") -> tuple[float, float]:
    """``limits_deg`` as the head's ``(min, max)`` pan in degrees (robot frame), checked:
    two finite numbers with ``-180 <= min < max <= 180``; else ConfigError naming ``where``.
    The one rule of the robot file's ``head.pan_limits_deg`` and of :func:`limit_pan_deg`."""
    from hearsee.geometry import check_angle_limits

    return check_angle_limits(limits_deg, where, 180.0, ConfigError)


def limit_pan_deg(pan_deg: float, limits_deg: tuple[float, float]) -> float:
    """The pan to command (degrees, robot frame, + = left) for a desired ``pan_deg`` (any
    finite angle): wrapped to (-180, 180], and when outside ``limits_deg`` ([min, max] within
    [-180, 180]), the limit angularly nearest to it. The head cannot turn through the arc
    beyond its limits, so that limit is as near the target as it can look (a plain clip
    chose ``max`` for a desired 190 deg, the same direction as -170 deg, and ``min`` for -170
    deg with limits [0, 170], 20 deg from ``max``).

    A desired pan that is not a finite number is a GeometryError and bad limits a ConfigError
    (:func:`pan_limits_deg`): NaN and inf fell through every comparison to ``max``."""
    from hearsee.geometry import wrap_deg

    pan = float(wrap_deg(finite_number("desired pan_deg", pan_deg, error=GeometryError)))
    lo, hi = pan_limits_deg(limits_deg)
    if lo <= pan <= hi:
        return pan
    return lo if pan_change_deg(pan, lo) < pan_change_deg(pan, hi) else hi


def tilt_limits_deg(limits_deg: Any, where: str = "tilt_limits_deg") -> tuple[float, float]:
    """``limits_deg`` as the head's ``(min, max)`` tilt in degrees (+ = gaze up), checked: two
    finite numbers with ``-90 <= min < max <= 90``; else ConfigError naming ``where``. The
    one rule of the robot file's ``head.tilt_limits_deg`` and of :func:`limit_tilt_deg`."""
    from hearsee.geometry import check_angle_limits

    return check_angle_limits(limits_deg, where, 90.0, ConfigError)


def limit_tilt_deg(tilt_deg: float, limits_deg: tuple[float, float] = (-90.0, 90.0)) -> float:
    """The tilt to command (degrees, + = gaze up) for a desired ``tilt_deg``: clipped to the
    head's ``limits_deg`` (:func:`tilt_limits_deg`; default [-90, 90]); not a finite number:
    GeometryError (a NaN went to the driver as it was)."""
    tilt = finite_number("desired tilt_deg", tilt_deg, error=GeometryError)
    lo, hi = tilt_limits_deg(limits_deg)
    return float(np.clip(tilt, lo, hi))


class PrintHeadDriver:
    """Head driver ``none``: the head stays at ``pose_deg``; each desired pan/tilt command
    (pan wrapped and limited by :func:`limit_pan_deg`, tilt clipped by :func:`limit_tilt_deg`;
    either not a finite number: GeometryError) is logged and printed to ``stream`` when it
    changes by at least ``min_change_deg`` (degrees, finite, >= 0; else ConfigError).

    The driver protocol :func:`run_robot` uses (a real pan-tilt driver implements the same):
    ``pose_deg`` -- the head's actual (pan, tilt) in degrees, read at every update (it may
    change while the head turns); ``command(t, pan_deg, tilt_deg)`` -- the desired pose at
    time ``t`` (seconds of audio), returning what was sent as ``{"pan_deg", "tilt_deg"}``;
    optionally ``n_printed`` -- how many commands were issued (the summary's count)."""

    def __init__(self, head: HeadConfig, stream: Any = None, min_change_deg: float = 2.0) -> None:
        self.head = head
        self.stream = stream
        # (NaN printed the first command only: every change compared False with it)
        self.min_change_deg = finite_number("min_change_deg", min_change_deg, 0.0)  # degrees
        self.last: tuple[float, float] | None = None
        self.n_printed = 0

    @property
    def pose_deg(self) -> tuple[float, float]:
        """The head's actual (pan, tilt): it does not move."""
        return self.head.pose_deg

    def command(self, t: float, pan_deg: float, tilt_deg: float) -> dict[str, float]:
        pan = limit_pan_deg(pan_deg, self.head.pan_limits_deg)
        tilt = limit_tilt_deg(tilt_deg, self.head.tilt_limits_deg)
        if self.last is None or max(pan_change_deg(pan, self.last[0]),
                                    abs(tilt - self.last[1])) >= self.min_change_deg:
            self.last = (pan, tilt)
            if self.stream is not None:
                print(f"head: t={t:.2f} s pan {pan:+.1f} deg tilt {tilt:+.1f} deg "
                      "(driver none: not moved)", file=self.stream, flush=True)
            self.n_printed += 1
        return {"pan_deg": pan, "tilt_deg": tilt}


# ---------------------------------------------------------------------------------------------
# The live loop
# ---------------------------------------------------------------------------------------------
class _Head:
    """Sensor geometry on the head at a fixed pose (robot frame, metres)."""

    def __init__(self, cfg: RobotConfig, pose: tuple[float, float]) -> None:
        from hearsee.geometry import array_to_robot, head_rotation
        from hearsee.vision.camera import OPTICAL_FROM_BODY

        self.pose = pose
        self.R = head_rotation(*pose).as_matrix()  # head -> robot
        self.pivot = np.asarray(cfg.head.pivot_m, float)
        mount = cfg.cameras.mount_m if cfg.cameras is not None else np.zeros(3)
        self.cam_centre = array_to_robot(np.zeros(3), pose, self.pivot, mount)
        if cfg.cameras is not None and not self.cam_centre[2] > 0:
            # (a geometry built in code skips the robot file's check: the detector then
            # refused a camera height below the floor, naming neither the pose nor the file)
            raise GeometryError(f"{cfg.path}: head pose pan {pose[0]:g} deg, tilt {pose[1]:g} "
                                f"deg puts the left camera's centre at z = "
                                f"{self.cam_centre[2]:.3f} m, not above the floor "
                                f"(cameras.mount_m {mount.tolist()} m from head.pivot_m "
                                f"{self.pivot.tolist()} m)")
        self.R_cam = OPTICAL_FROM_BODY @ self.R.T  # robot -> left optical
        #: the left camera's pitch above the horizontal (degrees, + = up): the elevation of
        #: its optical axis R_cam^T e_z in the robot frame, the head's tilt -- the detector's
        #: floor prior (it took every camera as level until 2026-12-03: a head tilted 15 deg
        #: up lost most people). Clipped to the prior's +-80 deg (a camera looking further
        #: up or down sees no floor to speak of).
        from hearsee.vision.humans import MAX_CAMERA_PITCH_DEG

        self.camera_pitch_deg = round(float(np.clip(  # (rounded: a level head gives 0, not
            np.degrees(np.arcsin(np.clip(self.R_cam[2, 2], -1.0, 1.0))),  # 1e-15 deg)
            -MAX_CAMERA_PITCH_DEG, MAX_CAMERA_PITCH_DEG)), 9)
        #: the microphone array's origin, ``head.offset_m`` from the pivot in the head frame:
        #: where the audio bearing is heard from (it was taken as heard from the pivot)
        self.array_origin = array_to_robot(np.zeros(3), pose, self.pivot, cfg.head.offset_m)
        #: a flat array's plane normal (head frame) where the plane lies within 45 deg of the
        #: head's horizontal, else None: its elevation's sign is unknown (see
        #: :meth:`direction_to_robot`)
        from hearsee.audio.localize import array_geometry

        geo = array_geometry(cfg.audio.array)
        self.mirror_normal = (geo.normal if geo.kind == "planar"
                              and abs(float(geo.normal[2])) >= np.sqrt(0.5) else None)

    def direction_to_robot(self, az_deg: float, el_deg: float | None) -> tuple[float, float | None]:
        """The head-frame direction ``(az_deg, el_deg)`` (degrees; el None: unknown, taken as
        0) as the robot frame's (azimuth, elevation), degrees. A flat array cannot tell on
        which side of its plane a talker is (the stream reports the upper side): with the head
        tilted, the two sides are two robot azimuths, and of them the one nearer the robot's
        horizontal is taken -- right for every talker nearer the horizontal than its mirror in
        the array's plane, e.g. every talker below the array's plane when the head tilts up.
        It took the upper side: with the head tilted 30 deg up, a talker at the pivot's height
        at azimuth 60 deg was logged at 74.8 deg (a review helper's rig, 2026-12-07)."""
        from hearsee.geometry import direction_deg, unit_vector_deg

        u = unit_vector_deg(az_deg, 0.0 if el_deg is None else el_deg)
        if el_deg is not None and self.mirror_normal is not None:
            n = self.mirror_normal
            m = u - 2.0 * float(u @ n) * n
            if abs(float((self.R @ m)[2])) < abs(float((self.R @ u)[2])) - 1e-9:
                u = m
        az, el = direction_deg(self.R @ u)
        return float(az), (None if el_deg is None else float(el))

    def camera_to_robot(self, p_cam: NDArray) -> NDArray:
        return self.R_cam.T @ np.asarray(p_cam, float) + self.cam_centre

    def bearing_deg(self, p: NDArray) -> tuple[float, float]:
        """Azimuth in (-180, 180] and elevation, degrees, of the robot-frame point ``p``
        (metres) seen from the head pivot (:func:`hearsee.geometry.direction_deg`)."""
        from hearsee.geometry import direction_deg

        az, el = direction_deg(np.asarray(p, float) - self.pivot)
        return float(az), float(el)

    def heard_azimuth_deg(self, p: NDArray) -> float:
        """Azimuth in (-180, 180], degrees, of the robot-frame point ``p`` (metres) seen from
        the array origin, where the audio bearing is heard."""
        from hearsee.geometry import direction_deg

        return float(direction_deg(np.asarray(p, float) - self.array_origin)[0])


def _pose(head: Any) -> tuple[float, float]:
    """The driver's actual (pan, tilt), degrees, as floats; GeometryError when that is no head
    pose (:class:`hearsee.geometry.HeadPose`: finite, tilt within [-90, 90]). Checked at every
    read: a NaN tilt during the run compared as no head move and was never noticed, a pose
    that was no pair of numbers a builtin TypeError or ValueError."""
    from hearsee.geometry import as_pose

    pose = head.pose_deg
    try:
        pan, tilt = (float(v) for v in pose)
    except (TypeError, ValueError):
        raise GeometryError(f"head driver pose_deg must be (pan_deg, tilt_deg) in degrees, got "
                            f"{pose!r}") from None
    try:
        return as_pose((pan, tilt)).as_tuple()
    except GeometryError as exc:
        raise GeometryError(f"head driver pose_deg: {exc}") from None


def _pose_change_deg(a: tuple[float, float], b: tuple[float, float]) -> float:
    """The larger of the pan change (the short way round) and the tilt change between two
    (pan, tilt) poses, degrees."""
    return max(pan_change_deg(a[0], b[0]), abs(a[1] - b[1]))


def _pose_at(t: float, poses: Sequence[tuple[float, tuple[float, float]]]) -> tuple[float, float]:
    """The head's (pan, tilt) at ``t`` seconds of audio, linearly interpolated between the
    reads ``poses`` ((seconds, (pan, tilt)), times increasing; pans the short way round from
    the newest), held at the first or last read outside them."""
    from hearsee.geometry import wrap_deg

    ts = [tp for tp, _ in poses]
    pan0 = poses[-1][1][0]
    pans = [pan0 + float(wrap_deg(p[0] - pan0)) for _, p in poses]
    pan = float(wrap_deg(np.interp(t, ts, pans)))
    return pan, float(np.interp(t, ts, [p[1] for _, p in poses]))


def _unheard(u: Any) -> Any:
    """A stream update with its audio withheld (the head was turning): no direction, not
    measured."""
    from dataclasses import replace

    return replace(u, azimuth_deg=None, elevation_deg=None, measured=False,
                   raw_azimuth_deg=None, raw_elevation_deg=None, itd_azimuth_deg=None,
                   itd_elevation_deg=None)


def _r(v: Any, nd: int = 4) -> Any:
    if v is None:
        return None
    a = np.asarray(v, dtype=float)
    return np.round(a, nd).tolist() if a.ndim else round(float(a), nd)


def jsonl_foreign_file(path: str | Path) -> bool:
    """Whether ``path`` is an existing, non-empty file that is not a hearsee run's JSON lines
    (its first line is not a JSON object with the keys ``t`` and ``phase``). A run replaces
    its own earlier lines; pointed at a file of the user's (``output.jsonl: notes.json``), it
    replaced that file without a word."""
    p = Path(path)
    if not p.is_file():
        return False
    try:
        with p.open("rb") as fh:
            first = fh.readline(65536)
    except OSError:
        return False  # (unreadable: the write check names it)
    if not first.strip():
        return bool(p.stat().st_size)  # (an empty file is free to use; blank lines are not ours)
    try:
        rec = json.loads(first)
    except (ValueError, UnicodeDecodeError):
        return True
    return not (isinstance(rec, dict) and "t" in rec and "phase" in rec)


def _foreign_jsonl_error(path: Path, where: str) -> ConfigError:
    return ConfigError(f"{where}output.jsonl: {path} exists and is not a hearsee run's JSON "
                       "lines; choose another file (or remove it)")


class _JsonLines:
    """The JSON lines file of a live run (``output.jsonl``): one line per update, written and
    flushed as it comes, so that the run can be followed while it goes (``tail -f``).

    Checked when the run starts -- its folder is made, and a path that cannot be written is a
    ConfigError before any device runs -- but not emptied then: the previous run's file is
    replaced at the first update (or, when the run ends without one, at its end: its report
    has no update either). A run that fails before its first update (a device that is busy or
    refuses the rate when its stream starts) thus leaves the previous run's lines as they were,
    beside the previous run's report; it used to leave them empty. (Writing beside the file and
    replacing it at the end would keep it whenever a run fails, but nothing could be followed
    during the run.) :meth:`close` keeps the lines and the run's log records one for one."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.fh: Any = None
        self.starts: list[int] = []  #: offset of each line written
        #: the folders made for the file, deepest first: removed again (when still empty) by a
        #: run that fails before its first line (it left an empty new folder behind)
        self.made = [d for d in (path.parent, *path.parent.parents) if not d.exists()]
        if jsonl_foreign_file(path):
            raise _foreign_jsonl_error(path, "")
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            existed = path.exists() or path.is_symlink()
            with open(path, "a", encoding="utf-8"):  # writable? (appends nothing)
                pass
            if not existed:
                path.unlink()
        except OSError as exc:
            raise self._error(exc) from None

    def _error(self, exc: OSError) -> ConfigError:
        return ConfigError(f"output.jsonl: cannot write {self.path}: {exc.strerror}")

    def _start(self) -> None:
        if self.fh is None:
            try:
                self.fh = open(self.path, "w", encoding="utf-8")  # noqa: SIM115 - see close()
            except OSError as exc:
                raise self._error(exc) from None

    def write(self, line: str) -> None:
        """Append ``line`` (ending in a newline) and flush it."""
        self._start()
        self.starts.append(self.fh.tell())
        self.fh.write(line)
        self.fh.flush()

    def close(self, n_lines: int | None = None) -> None:
        """Close the file. ``n_lines``: the run ended (``ok``, ``stalled`` or Ctrl-C) with that
        many log records; a file not started yet is emptied, and lines beyond them are cut (a
        Ctrl-C that came when a line had been written, before its record was logged). None: the
        run failed; the file stays as it is (the previous run's when no update came), and the
        folders made for a file never started are removed when empty."""
        if n_lines is not None:
            self._start()
            if n_lines < len(self.starts):
                self.fh.truncate(self.starts[n_lines])
        if self.fh is not None:
            self.fh.close()
            return
        for d in self.made:  # a failed run that wrote nothing: the folders made for it
            try:
                d.rmdir()  # (only an empty folder; one the user filled meanwhile stays)
            except OSError:
                break


def run_robot(cfg: RobotConfig, *, duration_s: float | None = None, audio_source: Any = None,
              cameras: Cameras | None = None, head: PrintHeadDriver | None = None,
              jsonl: str | Path | None = None, threaded: bool | None = None,
              progress: Callable[[float], None] | None = None, keep_frames: int = 100,
              stop: Any = None, async_vision: bool | None = None) -> RunResult:
    """Run the robot's perception live until the audio ends, ``duration_s`` or Ctrl-C.

    The same perception as the simulated pipeline (:mod:`hearsee.robot.pipeline`) where it
    applies to a real head:

    1. **Hear**: the microphones through the stream pipeline (:mod:`hearsee.stream.pipeline`:
       framer -> GCC TDOAs -> ITD Kalman filter -> localizer -> direction Kalman filter); the
       array-frame direction is rotated by the head pose into the robot frame.
    2. **Turn**: after a few audio updates the desired head pan/tilt (toward the 3D track once
       there is one, else the robot-frame bearing of the newest update that measured the
       talker -- kept through silences, where the stream's track coasts in the turning
       array's frame and is then lost; within ``head.pan_limits_deg``, see
       :func:`limit_pan_deg`) goes to the head driver -- with ``driver: none`` it is printed
       and logged and the head stays put. The loop reads the driver's actual pose at every
       update (see :class:`PrintHeadDriver` for the protocol a real driver implements): when
       it moves (the short way round, :func:`pan_change_deg`) by more than
       :data:`POSE_TOLERANCE_DEG`, the sensor geometry follows it. A head moving no faster
       than :data:`FOLLOW_RATE_DPS` (following a walker) is heard: the stream is told the
       head's pan at each frame (its direction tracker turns back with the head), and each
       update's direction is turned into the robot frame with the head's pose at its frame's
       time (``summary["head_follows"]`` counts these pose changes); after a faster move (a turn)
       the stream forgets its array-frame state (direction tracker, ITD filter, smoothed
       spectra: their directions were relative to the old pose) and the audio is withheld
       until one frame and one audio block after the head stops (``summary["head_moves"]``
       counts the pose changes of turns; meanwhile, without a 3D track, the head is still sent
       to the newest measured bearing, which withheld updates do not change). The robot-frame
       3D track is kept.
    3. **See and verify**: every ``1 / cameras.rate_hz`` seconds of audio, one set of camera
       frames (of a video file: its frame at that audio time) goes through stereo + thermal
       human detection
       (:func:`hearsee.vision.fusion.detect_humans`), with the camera's height and pitch at
       the head's pose of the capture as the floor's prior.
    4. **Fuse and track**: the verified person nearest the audio bearing (within the pipeline's
       association gate; not one flagged ``beyond_search``:
       :func:`~hearsee.robot.pipeline.fuses_fix`)
       updates a constant-acceleration 3D Kalman filter in the robot frame
       (vision only, as the simulated loop: see the pipeline's ``TRACK_TIMEOUT_S``). A track
       without a visual fix for :func:`~hearsee.robot.pipeline.track_timeout_s` of the
       detector's achieved frame interval (``summary["vision_frame_interval_s"]``: 1 s, or
       2.5 intervals when its results come more than 0.4 s apart -- a slow detector, a low
       ``rate_hz``) since the last fix arrived is dropped (counted in
       ``summary["track_drops"]``) and the head follows the audio bearing again; so is a
       track whose bearing the measured audio bearing has left by more than the association
       gate (at most :data:`~hearsee.robot.pipeline.SPEAKER_CHECK_MAX_DEG`) for
       :data:`~hearsee.robot.pipeline.SPEAKER_CHECK_S` -- by more than
       :data:`~hearsee.robot.pipeline.SPEAKER_CHECK_FAR_DEG` for
       :data:`~hearsee.robot.pipeline.SPEAKER_CHECK_FAR_S`, unless the array is a masked pair
       (someone else took the turn to speak; :func:`~hearsee.robot.pipeline.speaker_check`)
       -- (a silent person taken for the speaker:
       :class:`~hearsee.robot.pipeline.SpeakerCheck`, ``summary["speaker_drops"]``)
       or, in the camera frames, one whose person has been farther from the voice than another
       verified person in view for :data:`~hearsee.robot.pipeline.SPEAKER_SWITCH_S`
       (:func:`~hearsee.robot.pipeline.speaker_checked`, counted there too); the person let go
       is not associated again for a few seconds.

    Parameters
    ----------
    cfg : the validated robot file.
    duration_s : stop after this much audio (None: until the source ends or Ctrl-C).
    audio_source : a stream source (``fs``, ``n_channels``, ``blocks()``) with ``cfg.audio``'s
        input channels; default: the live device (:func:`open_audio_source`). Tests pass an
        :class:`hearsee.stream.pipeline.ArraySource` of a simulated recording. A source with
        ``audio_time_now()`` (the second of audio captured now, as
        :meth:`hearsee.stream.pipeline.DeviceSource.audio_time_now`) times the head's pose
        reads by it.
    cameras : default: :class:`Cameras` of ``cfg.cameras`` (None in the file: audio only);
        any object with its ``read(t)`` (``t``: seconds of audio), ``n_failures`` and
        ``n_consecutive_failures``.
    head : default: :class:`PrintHeadDriver` printing to stderr; any object with its protocol
        (``pose_deg``, ``command``) drives a real head.
    jsonl : the JSON lines file (default ``cfg.output.jsonl``); one line per update, flushed
        (it can be followed during the run). It is emptied at the first update, not when the
        run starts: a run that fails before its first update (a busy device, a refused rate)
        leaves a previous run's file as it was. The lines are the log's records, one for one,
        also after a Ctrl-C.
    threaded : run the source in its own thread (default: only for the live device).
    async_vision : detect humans in a worker thread, applying each result at the first update
        after it is ready (default: only for the live device; otherwise in line, so that runs
        over files are deterministic).
    progress : called with the seconds of audio of each update.
    keep_frames : overlays kept in memory for the exports (the first ones and the latest; 0:
        none); an integer >= 0, else ConfigError.
    stop : a ``threading.Event`` that ends the run cleanly when set.

    Returns
    -------
    :class:`~hearsee.robot.pipeline.RunResult` (as the simulated loop's; ``log`` holds one
    record per update, as written to the JSON lines file); ``summary["status"]`` is ``"ok"``
    (source ended or duration reached),
    ``"interrupted"`` (Ctrl-C) or ``"stalled"`` (the device stopped delivering audio).
    """
    import time
    from concurrent.futures import ThreadPoolExecutor

    from hearsee.config import to_jsonable
    from hearsee.robot.pipeline import (
        MIN_AUDIO_UPDATES,
        RunResult,
        associate,
        association_gate_deg,
        fuses_fix,
        new_person_track,
        speaker_check,
        speaker_checked,
        stereo_position_cov,
        track_record,
        track_timeout_s,
    )
    from hearsee.stream.pipeline import StreamConfig, StreamPipeline

    a = cfg.audio
    # (a HeadConfig built in code skipped the robot file's check; before any device opens)
    pan_limits_deg(cfg.head.pan_limits_deg, f"{cfg.path}: head.pan_limits_deg")
    # (and its tilt limits: bad ones stopped the run at its first head command, after the
    # device had opened and lines were written, naming neither the file nor the field)
    tilt_limits_deg(cfg.head.tilt_limits_deg, f"{cfg.path}: head.tilt_limits_deg")
    # (-1 kept none, 2.5 three, "3" was a builtin TypeError at the first camera frame)
    keep_frames = whole_number("keep_frames", keep_frames, 0)
    if cameras is not None and cfg.cameras is None:  # (a builtin AttributeError at the first
        # frame: the detector had no calibrated rig)
        raise ConfigError(f"{cfg.path}: cameras: run_robot was given cameras, but the robot "
                          "file has no cameras section (the rig calibration, rate_hz and "
                          "mount_m the frames need); add one or leave the cameras out")
    live = audio_source is None
    if live:
        source = open_audio_source(cfg, duration_s)
    else:
        source = MappedSource(audio_source, a.channels, duration_s, stop, "audio.channels")
    if live and stop is not None:
        source.stop = stop
    if abs(source.fs - a.fs) > 1e-6:
        raise AudioInputError(f"audio.fs: the source delivers {source.fs:g} Hz but the robot "
                              f"file says {a.fs} Hz")
    head = head or PrintHeadDriver(cfg.head, sys.stderr)
    geo = _Head(cfg, _pose(head))
    rig = cfg.cameras.rig if cfg.cameras is not None else None
    period = 1.0 / cfg.cameras.rate_hz if cfg.cameras is not None else float("inf")

    scfg = StreamConfig(frame_ms=a.frame_ms, hop_ms=a.frame_ms / 2.0, method=a.method,
                        itd_filter=True)
    pipeline = StreamPipeline(a.array, scfg, queue_size=16, max_stall_s=5.0)
    track = new_person_track()
    speaker = speaker_check(a.array)
    # the cameras last, just before the try that closes them (an error above left them open)
    own_cameras = cameras is None and cfg.cameras is not None
    if own_cameras:
        cameras = Cameras(cfg.cameras, f"{cfg.path}: ")
    try:
        lines = _JsonLines(Path(jsonl) if jsonl is not None else cfg.output.jsonl)
    except ConfigError:
        if own_cameras:
            cameras.close()
        raise

    log: list[dict[str, Any]] = []
    images: dict[str, NDArray] = {}
    captions: dict[str, str] = {}
    frames: list[tuple[float, NDArray]] = []
    state = {"n_audio": 0, "next_cam": 0.0, "phase": "listening", "cam_frames": 0,
             "cam_ended": False, "first_verified": None, "hop": scfg.hop_ms / 1000.0,
             "last_visual": -np.inf, "track_drops": 0, "speaker_drops": 0,
             "heard_from": -np.inf, "head_moves": 0,
             "head_follows": 0, "heard_bearing": None, "last_capture": None,
             "frame_interval": period, "captured": -math.inf}
    # live: detection runs in a worker thread so that the audio keeps flowing; its result is
    # applied at the first update after it is ready (file sources: in line, deterministic)
    use_pool = (live if async_vision is None else async_vision) and cameras is not None
    pool = ThreadPoolExecutor(1, thread_name_prefix="hearsee-vision") if use_pool else None
    pending: list[Any] = [None]
    # the driver's poses read within the last POSE_HISTORY_S: (seconds of audio, (pan, tilt))
    poses: deque[tuple[float, tuple[float, float]]] = deque()
    audio_geo: list[_Head | None] = [None]  # (the last geometry built for a frame's pose)
    t_start = time.perf_counter()

    def grab(t: float) -> CameraFrames | None:
        fr = cameras.read(t)  # (video files: their frame at t, at the file's own rate)
        if fr is None:
            if cameras.n_consecutive_failures >= 3 and not state["cam_ended"]:
                state["cam_ended"] = True
                print("cameras: no more frames; continuing with audio only (trying again "
                      f"every {CAMERA_RETRY_S:g} s)", file=sys.stderr)
            if state["cam_ended"]:  # the next try: the grid's slot a retry after this one's
                slot = state["next_cam"] - period
                while state["next_cam"] < slot + CAMERA_RETRY_S - 1e-9:
                    state["next_cam"] += period
            return None
        if state["cam_ended"]:
            state["cam_ended"] = False
            print(f"cameras: frames again at t = {t:.2f} s", file=sys.stderr)
        state["cam_frames"] += 1
        return fr

    def detect(fr: CameraFrames, g: _Head) -> Any:
        from hearsee.vision.fusion import detect_humans

        thermal = fr.thermal if rig.thermal is not None else None
        return detect_humans(fr.left, fr.right, rig, thermal,
                             camera_height_m=float(g.cam_centre[2]),
                             camera_pitch_deg=g.camera_pitch_deg,
                             stereo_options=cfg.cameras.stereo_options())

    def apply(t: float, t_cap: float, fr: CameraFrames, det: Any, bearing: float | None,
              g: _Head) -> list[dict[str, Any]]:
        """Log (and associate) the detections of the frames captured at ``t_cap`` with the
        head geometry ``g`` of their capture (the head may have turned since)."""
        from hearsee.vision.fusion import draw_detections

        dets: list[dict[str, Any]] = []
        verified = []  # (human, robot-frame position, azimuth heard from the array, index)
        for h in det.humans + det.rejected:
            p = g.camera_to_robot(h.position_m)
            az, el = g.bearing_deg(p)
            dets.append({**h.to_dict(), "position_m": _r(p), "azimuth_deg": _r(az, 2),
                         "elevation_deg": _r(el, 2), "accepted": bool(h.accepted),
                         "speaker": False})
            if fuses_fix(h):  # (compared with the audio bearing: from the array origin)
                verified.append((h, p, g.heard_azimuth_deg(p), len(dets) - 1))
        # the track holds the state of its last fix (the loop reports it predicted to each
        # update's time): the frames' fix is of their capture time, earlier than t by the
        # detector's latency (0.3-0.5 s on 2 cores; applied at t, a walker's track lagged by
        # that much, 0.12-0.25 m at 0.5 m/s)
        # the frame interval the detector achieves, for the track's timeout: the rate's period,
        # or longer -- frames are captured one detection at a time, so at least its latency
        # (t - t_cap: known from the first result on), and the captures' own spacing
        gap = t_cap - state["last_capture"] if state["last_capture"] is not None else 0.0
        state["frame_interval"] = max(period, t - t_cap, gap)
        state["last_capture"] = t_cap
        if track.initialized:
            track.predict(t_cap)
        # (the tracked person still the voice's? not one the audio check let go of lately)
        had_track = track.initialized
        verified = speaker_checked(speaker, t_cap, verified, [v[1] for v in verified],
                                    [v[2] for v in verified], track, bearing,
                                    g.heard_azimuth_deg)
        state["speaker_drops"] += int(had_track and not track.initialized)
        best = associate([v[1] for v in verified], [v[2] for v in verified], track, bearing,
                         association_gate_deg(a.array))
        if best is not None:
            h, p, _, k = verified[best]
            Rc = g.R_cam.T @ stereo_position_cov(np.asarray(h.position_m), rig.focal_px,
                                              rig.baseline_m, truncated=h.truncated) @ g.R_cam
            if track.update(t_cap, p, Rc):
                state["last_visual"] = t  # (when the fix arrived: the timeout counts from
                # there -- from the capture, a 0.5 s latency dropped every track)
            dets[k]["speaker"] = True
            if state["first_verified"] is None:
                state["first_verified"] = t_cap
        # the boxes are in rectified left-image pixels: draw them on the rectified left image;
        # the overlay shows the frames of t_cap (the log's camera_t), not the later t at which
        # their detection was applied (the exports' image stamps were late by its latency)
        overlay = draw_detections(det.frame.left, det)
        if len(frames) < keep_frames:
            frames.append((t_cap, overlay))
        elif keep_frames > 0:
            frames[-1] = (t_cap, overlay)
        slot = "first" if state["cam_frames"] == 1 else "latest"
        images[f"{slot}_overlay"] = overlay
        captions[f"{slot}_overlay"] = (f"t = {t_cap:.1f} s: {len(det.humans)} verified "
                                       f"person(s), {len(det.rejected)} rejected candidate(s)")
        if fr.thermal is not None:
            import cv2

            th = cv2.applyColorMap(fr.thermal, cv2.COLORMAP_INFERNO)
            images[f"{slot}_thermal"] = cv2.resize(th, (overlay.shape[1], overlay.shape[0]),
                                                   interpolation=cv2.INTER_NEAREST)
            captions[f"{slot}_thermal"] = f"t = {t_cap:.1f} s: thermal camera (8-bit, inferno)"
        return dets

    window = (scfg.frame_ms + a.block_ms) / 1000.0  # (seconds a head move can reach)

    def read_pose(t: float) -> tuple[float, float]:
        """The driver's pose now, also kept in ``poses`` (the reads of the last
        :data:`POSE_HISTORY_S`, and one before), timed on the audio's clock: the second of
        audio the microphones capture now where the source tells it (a live device:
        ``audio_time_now()``, its input latency and the blocks queued behind the stream
        included; unheeded, 20-40 ms of latency put a head following at 28 deg/s 0.5-1 deg
        off), else the end of the newest block the stream has taken, or ``t`` if later."""
        pose = _pose(head)
        captured = source.audio_time_now()
        state["captured"] = -math.inf if captured is None else captured
        now = max(float(pipeline.stats.audio_s), t, state["captured"])
        while poses and poses[-1][0] >= now:  # (reads within one block: the latest)
            poses.pop()
        poses.append((now, pose))
        while len(poses) > 2 and poses[1][0] < now - max(window, POSE_HISTORY_S):
            poses.popleft()
        return pose

    def frame_pans(ts: NDArray) -> list[float]:
        """The head's pan at the frames' times ``ts`` (seconds of audio; the stream's
        ``array_pan``, read before it processes them): its direction tracker follows the
        head's turns instead of taking them for the talker's motion."""
        read_pose(float(np.max(ts)) if len(ts) else 0.0)
        return [_pose_at(float(t), poses)[0] for t in ts]

    def follow_head(t: float) -> _Head | None:
        """The head geometry of the audio of the update at ``t`` (a frame's centre, seconds of
        audio), or None when that audio cannot be trusted. The loop's geometry follows the
        driver's pose, read now (:func:`read_pose`). A head moving no faster than
        :data:`FOLLOW_RATE_DPS` over the last frame plus block is heard, the update's
        direction turned into the robot frame with the pose at its frame's time (interpolated
        between the reads: a head following at 28 deg/s read at the block's end put ~0.7 deg
        more into the median error). A faster move (a turn) withholds the audio while it lasts
        and for one frame plus one block after it (frames that began during the turn; a block
        the device had captured before the pose was read), and meanwhile the stream keeps
        forgetting its array-frame state, so its trackers start afresh on the settled head's
        audio."""
        nonlocal geo
        pose = read_pose(t)
        if _pose_change_deg(pose, geo.pose) > POSE_TOLERANCE_DEG:
            geo = _Head(cfg, pose)
            now = poses[-1][0]
            moved = max(_pose_change_deg(pose, p) for tp, p in poses if tp >= now - window)
            if moved > FOLLOW_RATE_DPS * window:
                # (and the audio captured until the read, where a live source's clock tells)
                state["heard_from"] = max(t, state["captured"]) + window
                state["head_moves"] += 1
            else:
                state["head_follows"] += 1
        if t < state["heard_from"]:
            pipeline.reset_array_state()
            return None
        then = _pose_at(t, poses)
        if _pose_change_deg(then, geo.pose) <= POSE_TOLERANCE_DEG:
            return geo
        if audio_geo[0] is None or _pose_change_deg(then, audio_geo[0].pose) > 1e-9:
            audio_geo[0] = _Head(cfg, then)
        return audio_geo[0]

    def sink(u: Any) -> None:
        t = float(u.t)
        ageo = follow_head(t)
        if ageo is None:
            u = _unheard(u)
        if (track.initialized
                and t - state["last_visual"] > track_timeout_s(state["frame_interval"])):
            # no visual fix for the timeout: a coasting track drifts (as in the simulated
            # pipeline); drop the track, the head follows the audio
            track.reset()
            state["track_drops"] += 1
        audio = None
        bearing = None
        if u.bearing_decided:  # (a masked pair's: once it has decided a half)
            az, el = ageo.direction_to_robot(u.azimuth_deg, u.elevation_deg)
            raw = None
            if u.raw_azimuth_deg is not None:  # (the frame's own bearing, logged)
                raw = ageo.direction_to_robot(u.raw_azimuth_deg, u.raw_elevation_deg)[0]
            bearing = az
            audio = {"azimuth_deg": _r(az, 2), "elevation_deg": _r(el, 2),
                     "raw_azimuth_deg": _r(raw, 2), "confidence": _r(u.confidence, 3),
                     "measured": bool(u.measured)}
            if u.measured:
                state["n_audio"] += 1
                state["heard_bearing"] = az
        # the track must stay on the person heard (as the simulated loop: a silent person
        # taken by mistake is let go; :class:`~hearsee.robot.pipeline.SpeakerCheck`)
        now = track.predicted_to(t) if track.initialized else None
        if speaker.observe(t, bearing if u.measured else None,
                           None if now is None else geo.heard_azimuth_deg(now.position)):
            speaker.exclude(t, now.position)
            track.reset()
            state["speaker_drops"] += 1
        dets: list[dict[str, Any]] = []
        camera_t = None
        if (cameras is not None and pending[0] is None
                and t + 1e-9 >= state["next_cam"]):
            # the next read on the grid k / rate_hz seconds of audio, as the simulated loop's
            # (it was t + period: late by up to one update per frame, e.g. 4.46 frames a
            # second for rate_hz 5 with 32 ms updates); slots missed while a detection ran
            # are skipped
            while state["next_cam"] <= t + 1e-9:
                state["next_cam"] += period
            fr = grab(t)
            if fr is not None and pool is not None:
                pending[0] = (t, fr, pool.submit(detect, fr, geo), geo)
            elif fr is not None:
                dets, camera_t = apply(t, t, fr, detect(fr, geo), bearing, geo), t
        if pending[0] is not None and pending[0][2].done():
            t_cap, fr, fut, g = pending[0]
            pending[0] = None
            dets, camera_t = apply(t, t_cap, fr, fut.result(), bearing, g), t_cap
        state["last_t"], state["last_bearing"] = t, bearing
        emit(t, audio, dets, camera_t)
        if progress is not None:
            progress(state["hop"])

    def emit(t: float, audio: dict | None, dets: list[dict[str, Any]],
             camera_t: float | None) -> None:
        """Phase, head command and track of this update; one log record / JSON line. Without
        a track the head is sent to the newest measured bearing, also while the audio is
        withheld (the head turns or settles), silent, or a masked pair's half undecided: the
        head's pose of the moment would stop the turn (it stopped a turn at the first silence
        once the stream's coasting track was gone)."""
        if state["phase"] == "listening" and state["n_audio"] >= MIN_AUDIO_UPDATES:
            state["phase"] = "turning"
        now = track.predicted_to(t)  # (the track's state is its last fix's)
        if now.initialized:
            state["phase"] = "tracking"
        elif state["phase"] == "tracking":  # the track was dropped (it stayed "tracking")
            state["phase"] = "turning"
        command = None
        if state["phase"] != "listening":
            pan, tilt = geo.pose
            if now.initialized:
                pan, tilt = geo.bearing_deg(now.position)
            elif state["heard_bearing"] is not None:  # (set before the phase leaves listening)
                pan = state["heard_bearing"]
            # any driver gets a pan and a tilt within the head's limits (not only
            # PrintHeadDriver); a NaN never reaches it (GeometryError)
            pan = limit_pan_deg(pan, cfg.head.pan_limits_deg)
            tilt = limit_tilt_deg(tilt, cfg.head.tilt_limits_deg)
            command = head.command(t, pan, tilt)
        rec_track = track_record(now)  # (rounded for the JSON line: mm, covariance 1e-6)
        if rec_track is not None:
            rec_track = {k: _r(v, 6 if k == "covariance" else 4) for k, v in rec_track.items()}
        rec = {"t": round(t, 4), "phase": state["phase"], "head_pan_deg": geo.pose[0],
               "head_tilt_deg": geo.pose[1], "head_command": command, "audio": audio,
               "camera_t": camera_t, "detections": dets, "track": rec_track, "truth": None,
               "error_m": None}
        # the line first, then the record (a Ctrl-C in the write left the record logged and
        # its line not written; one after it: lines.close cuts the line)
        lines.write(json.dumps(to_jsonable(rec)) + "\n")
        log.append(rec)

    status = "ok"
    ended = False  # (else the run failed: the JSON lines stay as they are)
    try:
        pipeline.run(source, sink, threaded=live if threaded is None else threaded,
                     array_pan=frame_pans)
        status = pipeline.stats.status
        if pending[0] is not None and "last_t" in state:
            # the audio ended while a detection was running: log its result as a last update
            t_cap, fr, fut, g = pending[0]
            pending[0] = None
            t = state["last_t"]
            emit(t, None, apply(t, t_cap, fr, fut.result(), state["last_bearing"], g), t_cap)
        ended = True
    except KeyboardInterrupt:
        status = "interrupted"
        ended = True
    finally:
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)
        try:
            if own_cameras:
                cameras.close()
        finally:
            lines.close(len(log) if ended else None)
    # the audio processed is the stream's (its stats are filled in after a Ctrl-C too; the
    # source's own count also held the blocks still queued when Ctrl-C came)
    summary = _live_summary(log, pipeline.stats, status, state, cameras, head,
                            time.perf_counter() - t_start)
    return RunResult(log, summary, images, captions, frames)


def _live_summary(log: list[dict[str, Any]], stats: Any, status: str, state: dict,
                  cameras: Cameras | None, head: PrintHeadDriver, runtime_s: float
                  ) -> dict[str, Any]:
    """Summary metrics from the live log (nothing canned); the audio processed is the
    stream's ``stats.audio_s``."""
    audio_s = stats.audio_s
    from hearsee.geometry import wrap_deg

    az = np.array([r["audio"]["azimuth_deg"] for r in log
                   if r["audio"] is not None and r["audio"]["measured"]], dtype=float)
    az_final = float(az[-1]) if len(az) else float("nan")
    az_med = (float(wrap_deg(np.median(wrap_deg(az - az_final)) + az_final)) if len(az)
              else float("nan"))
    dets = [d for r in log for d in r["detections"]]
    last_track = next((r["track"] for r in reversed(log) if r["track"] is not None), None)
    last_cmd = next((r["head_command"] for r in reversed(log) if r["head_command"]), None)
    tracked = sum(1 for r in log if r["track"] is not None)
    verified = sum(1 for d in dets if d["accepted"])
    out: dict[str, Any] = {
        # the report's verdict: a person was heard, seen, verified and tracked
        "success": bool(verified > 0 and tracked > 0),
        "status": status,
        "audio_s": float(audio_s),
        "updates": len(log),
        "audio_updates": int(len(az)),
        "azimuth_deg_median": az_med,
        "azimuth_deg_final": az_final,
        "camera_frames": int(state["cam_frames"]),
        "person_detections_verified": int(verified),
        "candidates_rejected": int(len(dets) - verified),
        "person_reported": bool(verified > 0),
        "time_to_verify_s": (float(state["first_verified"]) if state["first_verified"]
                             is not None else float("nan")),
        "tracked_updates": int(tracked),
        "track_drops": int(state["track_drops"]),
        "speaker_drops": int(state["speaker_drops"]),
        # (seconds between the frames the detector got through, as the track's timeout uses
        # it: the rate's period, or the detector's latency when it is slower; NaN: no frame)
        "vision_frame_interval_s": (float(state["frame_interval"])
                                    if state["last_capture"] is not None else float("nan")),
        "head_pan_command_deg_final": (float(last_cmd["pan_deg"]) if last_cmd
                                       else float("nan")),
        "head_commands_printed": int(getattr(head, "n_printed", 0)),
        "head_moves": int(state["head_moves"]),
        "head_follows": int(state["head_follows"]),
        "dropped_blocks": int(stats.n_dropped_blocks),
        "input_overflows": int(stats.n_overflows),  # (as `hearsee track`'s stats)
        "missing_frames": int(stats.n_missing_frames),
        "real_time_factor": float(audio_s / runtime_s) if runtime_s > 0 else float("nan"),
        "runtime_s": float(runtime_s),
    }
    if last_track is not None:
        p = np.asarray(last_track["position_m"], float)
        out["track_position_m_final"] = p.tolist()
        out["track_distance_m_final"] = float(np.linalg.norm(p[:2]))
    if cameras is not None:
        out["camera_read_failures"] = int(cameras.n_failures)
    return out


def write_run_report(cfg: RobotConfig, result: RunResult, folder: str | Path | None = None
                     ) -> Path:
    """Write the report folder of a live run with :func:`hearsee.robot.report.write_report`;
    returns ``index.html``. The top view is drawn in the robot frame (robot at the origin,
    facing +x); no room outline and no ground truth are known on real hardware."""
    from hearsee.robot.report import write_report

    return write_report(folder if folder is not None else cfg.output.report,
                        report_scenario(cfg), result.log, result.summary, result.images,
                        result.captions)


def report_scenario(cfg: RobotConfig) -> dict[str, Any]:
    """The scenario mapping the report and the Rerun export expect, for a live run: the robot
    at the origin of its own frame, no room outline (unknown), no objects; ``frame``
    ``"robot"``: the report's top view is labelled in the robot frame, not the room's."""
    return {
        "name": f"live run ({cfg.path.name})",
        "frame": "robot",
        "seed": None,
        "room": {"size_m": [0.0, 0.0, 0.0]},
        "robot": {"position_m": [0.0, 0.0], "heading_deg": 0.0,
                  "head_height_m": float(cfg.head.pivot_m[2]), "array": cfg.audio.array.name},
        "objects": [],
    }
