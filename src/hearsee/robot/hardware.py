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
      array: respeaker-4 | mics.yaml    [three-mic]  array preset or YAML file (array frame)
      block_ms: 100                     [100]  one update (one JSON line) per block, ms
      frame_ms: 64                      [64]   TDOA analysis frame, ms (hop = frame / 2)
      method: phat                      [phat] GCC weighting (phat, scot, roth, ml, cc)
    cameras:                            # optional: without it the robot only hears
      left: 0 | /dev/video0 | file.mp4 | rtsp://...   VideoCapture index, path or URL
      right: 1                                        (left + right) ...
      stereo: 0                                       ... or ONE side-by-side device
                                                      (left image | right image)
      thermal: 2                        [none]  optional thermal camera (8-bit video)
      calib: rig.yaml                   required: rig YAML from `hearsee calibrate` (with a
                                        thermal block when `thermal` is given)
      rate_hz: 2                        [2]    human detection rate, frames per second
      mount_m: [0.05, 0.06, 0.10]       [[0, 0, 0]]  left camera's optical centre from the
                                        head pivot, head frame (x fwd, y left, z up), metres;
                                        the cameras look along the head's +x axis
    head:
      pivot_m: [0, 0, 1.2]              [[0, 0, 1.2]]  pan-tilt pivot in the robot frame, m
      offset_m: [0, 0, 0.08]            [[0, 0, 0]]    array origin from the pivot, head frame, m
      pan_limits_deg: [-170, 170]       [[-170, 170]]  commanded pan is clipped to this
      pose_deg: [0, 0]                  [[0, 0]]   pan, tilt the head is at (driver none: it
                                        stays there; only the desired command is printed)
      driver: none                      [none]     only `none` is implemented: the desired
                                        pan/tilt command is printed and logged, nothing moves
    output:
      jsonl: run.jsonl                  [hearsee-run/updates.jsonl]  one JSON line per update
      report: hearsee-run               [hearsee-run]  report folder (index.html, log.json, ...)

Frames follow REP 103 (x forward, y left, z up). Azimuths in the log are in the ROBOT frame
(the head pose is applied); positions are metres in the robot frame.

``--dry-run`` (:func:`check_devices`) opens every device once: PortAudio is there, the input
device exists with enough channels and accepts the sample rate (``sd.check_input_settings``),
each camera opens and delivers a frame of the calibrated size, the calibration loads.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hearsee.audio.arrays import MicArray, load_array
from hearsee.config import as_float_array, check_keys, load_yaml
from hearsee.errors import AudioInputError, ConfigError, GeometryError, HearseeError

__all__ = [
    "AudioConfig",
    "CameraConfig",
    "Check",
    "HeadConfig",
    "OutputConfig",
    "RobotConfig",
    "check_devices",
    "import_sounddevice",
    "load_robot_config",
    "open_capture",
    "resolve_input_device",
    "robot_config_from_dict",
]

DRIVERS = ("none",)
_TOP = ("audio", "cameras", "head", "output")
_AUDIO = ("device", "fs", "channels", "array", "block_ms", "frame_ms", "method")
_CAMERAS = ("left", "right", "stereo", "thermal", "calib", "rate_hz", "mount_m")
_HEAD = ("pivot_m", "offset_m", "pan_limits_deg", "pose_deg", "driver")
_OUTPUT = ("jsonl", "report")

DeviceSpec = int | str


# ---------------------------------------------------------------------------------------------
# Configuration
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AudioConfig:
    """Microphones: ``device`` (index, name substring or None = default input), ``fs`` Hz,
    ``channels`` (input channel of each microphone), the ``array`` geometry, ``block_ms`` (one
    update per block), ``frame_ms`` (TDOA frame) and the GCC ``method``."""

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
    the calibrated ``rig`` (from ``calib``), the detection ``rate_hz`` and the left camera's
    ``mount_m`` (head frame, metres)."""

    left: DeviceSpec | None
    right: DeviceSpec | None
    stereo: DeviceSpec | None
    thermal: DeviceSpec | None
    calib: Path
    rig: Any  # hearsee.vision.camera.StereoRig
    rate_hz: float = 2.0
    mount_m: NDArray = field(default_factory=lambda: np.zeros(3))

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
    ``pan_limits_deg``, the current ``pose_deg`` (pan, tilt) and the ``driver``."""

    pivot_m: NDArray
    offset_m: NDArray
    pan_limits_deg: tuple[float, float] = (-170.0, 170.0)
    pose_deg: tuple[float, float] = (0.0, 0.0)
    driver: str = "none"


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
        a = Path(self.audio.array_spec)
        if a.is_file():
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


def _number(d: Mapping[str, Any], key: str, default: float, where: str, lo: float | None = None,
            hi: float | None = None, integer: bool = False) -> float:
    v = d.get(key, default)
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise ConfigError(f"{where}.{key}: expected a number, got {v!r}")
    if integer and int(v) != v:
        raise ConfigError(f"{where}.{key}: expected a whole number, got {v!r}")
    if lo is not None and v < lo:
        raise ConfigError(f"{where}.{key}: must be >= {lo}, got {v}")
    if hi is not None and v > hi:
        raise ConfigError(f"{where}.{key}: must be <= {hi}, got {v}")
    return int(v) if integer else float(v)


def _mapping(d: Mapping[str, Any], key: str, where: str, required: bool = False
             ) -> Mapping[str, Any] | None:
    if key not in d or d[key] is None:
        if required:
            raise ConfigError(f"{where}: missing required key {key!r}")
        return None
    v = d[key]
    if not isinstance(v, Mapping):
        raise ConfigError(f"{where}.{key}: expected a mapping, got {type(v).__name__}")
    return v


def _vec3(d: Mapping[str, Any], key: str, default: Sequence[float], where: str) -> NDArray:
    return as_float_array(d.get(key, list(default)), f"{where}.{key}", shape=(3,))


def _resolve(p: str | Path, base: Path) -> Path:
    q = Path(p).expanduser()
    return q if q.is_absolute() else base / q


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
    if s.isdigit():
        return int(s)
    if not camera:
        return s
    if "://" in s:
        return s
    p = _resolve(s, base)
    if not p.exists():
        raise ConfigError(f"{where}: no such camera device or video file {s!r}")
    return str(p)


def _audio(d: Mapping[str, Any], where: str, base: Path) -> AudioConfig:
    check_keys(d, _AUDIO, where)
    dev = d.get("device")
    device = None if dev is None else _device(dev, f"{where}.device", base, camera=False)
    fs = _number(d, "fs", 16000, where, 4000, 384000, integer=True)
    spec = d.get("array", "three-mic")
    if not isinstance(spec, str) or not spec.strip():
        raise ConfigError(f"{where}.array: expected a preset name or YAML path, got {spec!r}")
    spec_path = _resolve(spec, base)
    if spec.endswith((".yaml", ".yml")) or spec_path.is_file():
        if not spec_path.is_file():
            raise ConfigError(f"{where}.array: array file {spec!r} not found")
        spec = str(spec_path)
    try:
        array = load_array(spec)
    except (ConfigError, GeometryError) as exc:
        raise ConfigError(f"{where}.array: {exc}") from None
    ch = d.get("channels")
    if ch is None:
        channels = tuple(range(array.n_mics))
    else:
        if not isinstance(ch, list) or not all(isinstance(c, int) and not isinstance(c, bool)
                                               for c in ch):
            raise ConfigError(f"{where}.channels: expected a list of channel indices, got {ch!r}")
        if len(ch) != array.n_mics:
            raise ConfigError(f"{where}.channels: {len(ch)} channels for an array of "
                              f"{array.n_mics} microphones (one input channel per microphone)")
        if any(c < 0 for c in ch) or len(set(ch)) != len(ch):
            raise ConfigError(f"{where}.channels: channels must be distinct and >= 0, got {ch}")
        channels = tuple(ch)
    block_ms = _number(d, "block_ms", 100.0, where, 10.0, 2000.0)
    frame_ms = _number(d, "frame_ms", 64.0, where, 8.0, 1000.0)
    max_delay_ms = float(array.max_tdoa().max()) * 1e3
    if frame_ms < 4 * max_delay_ms:
        raise ConfigError(f"{where}.frame_ms: {frame_ms} ms is too short for the array's "
                          f"largest delay ({max_delay_ms:.2f} ms); use >= {4 * max_delay_ms:.0f}")
    method = d.get("method", "phat")
    from hearsee.audio.tdoa import normalize_method

    try:
        method = normalize_method(str(method))
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
    if "calib" not in d or d["calib"] is None:
        raise ConfigError(f"{where}.calib: missing: the cameras need a rig calibration file "
                          "(create one with `hearsee calibrate`)")
    if not isinstance(d["calib"], str):
        raise ConfigError(f"{where}.calib: expected a file path, got {d['calib']!r}")
    calib = _resolve(d["calib"], base)
    if not calib.is_file():
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
    rate = _number(d, "rate_hz", 2.0, where, 0.1, 60.0)
    mount = _vec3(d, "mount_m", (0.0, 0.0, 0.0), where)
    if np.linalg.norm(mount) > 2.0:
        raise ConfigError(f"{where}.mount_m: {mount.tolist()} is more than 2 m from the pivot")
    return CameraConfig(dev["left"], dev["right"], dev["stereo"], dev["thermal"], calib, rig,
                        rate, mount)


def _pair(d: Mapping[str, Any], key: str, default: tuple[float, float], where: str
          ) -> tuple[float, float]:
    a = as_float_array(d.get(key, list(default)), f"{where}.{key}", shape=(2,))
    return float(a[0]), float(a[1])


def _head(d: Mapping[str, Any], where: str) -> HeadConfig:
    check_keys(d, _HEAD, where)
    pivot = _vec3(d, "pivot_m", (0.0, 0.0, 1.2), where)
    offset = _vec3(d, "offset_m", (0.0, 0.0, 0.0), where)
    if np.linalg.norm(offset) > 1.0:
        raise ConfigError(f"{where}.offset_m: {offset.tolist()} is more than 1 m from the pivot")
    lo, hi = _pair(d, "pan_limits_deg", (-170.0, 170.0), where)
    if not -180.0 <= lo < hi <= 180.0:
        raise ConfigError(f"{where}.pan_limits_deg: need -180 <= min < max <= 180, got "
                          f"[{lo}, {hi}]")
    pan, tilt = _pair(d, "pose_deg", (0.0, 0.0), where)
    if not lo <= pan <= hi:
        raise ConfigError(f"{where}.pose_deg: pan {pan} is outside pan_limits_deg [{lo}, {hi}]")
    if abs(tilt) > 90.0:
        raise ConfigError(f"{where}.pose_deg: tilt must be within [-90, 90], got {tilt}")
    driver = d.get("driver", "none")
    if driver is None:
        driver = "none"
    if driver not in DRIVERS:
        raise ConfigError(f"{where}.driver: {driver!r} is not supported (available: "
                          f"{', '.join(DRIVERS)}: print the desired pan/tilt command only)")
    return HeadConfig(pivot, offset, (lo, hi), (pan, tilt), str(driver))


def _output(d: Mapping[str, Any], where: str, base: Path) -> OutputConfig:
    check_keys(d, _OUTPUT, where)
    for k in _OUTPUT:
        if k in d and (not isinstance(d[k], str) or not d[k].strip()):
            raise ConfigError(f"{where}.{k}: expected a path, got {d[k]!r}")
    report = _resolve(d.get("report", "hearsee-run"), base)
    jsonl = _resolve(d["jsonl"], base) if "jsonl" in d else report / "updates.jsonl"
    if jsonl.suffix.lower() not in (".jsonl", ".ndjson", ".json"):
        raise ConfigError(f"{where}.jsonl: expected a .jsonl file name, got {d['jsonl']!r}")
    return OutputConfig(jsonl, report)


def robot_config_from_dict(data: Mapping[str, Any], where: str = "robot.yaml",
                           base_dir: str | Path = ".") -> RobotConfig:
    """Validate a robot mapping (see the module docstring). ``where`` prefixes every error;
    relative paths are resolved against ``base_dir``."""
    if not isinstance(data, Mapping):
        raise ConfigError(f"{where}: expected a mapping at top level")
    base = Path(base_dir)
    check_keys(data, _TOP, where)
    audio = _audio(_mapping(data, "audio", where, required=True), f"{where}: audio", base)
    cams = _mapping(data, "cameras", where)
    cameras = None if cams is None else _cameras(cams, f"{where}: cameras", base)
    head = _head(_mapping(data, "head", where) or {}, f"{where}: head")
    output = _output(_mapping(data, "output", where) or {}, f"{where}: output", base)
    cfg = RobotConfig(Path(where), audio, cameras, head, output)
    _check_outputs(cfg, where)
    return cfg


def _check_outputs(cfg: RobotConfig, where: str) -> None:
    ins = {p.resolve() for p in cfg.input_files() if p.exists()}
    for name, p in (("output.jsonl", cfg.output.jsonl), ("output.report", cfg.output.report)):
        if p.resolve() in ins:
            raise ConfigError(f"{where}: {name}: {p} is an input file; choose another path")
    report = cfg.output.report.resolve()
    for p in ins:
        if p.is_relative_to(report) and p.name in ("index.html", "log.json", "summary.json"):
            raise ConfigError(f"{where}: output.report: writing {report} would overwrite {p}")


def load_robot_config(path: str | Path) -> RobotConfig:
    """Load and validate a robot file; errors name the file and the field."""
    p = Path(path)
    data = load_yaml(p)
    cfg = robot_config_from_dict(data, where=str(p), base_dir=p.resolve().parent)
    return RobotConfig(p, cfg.audio, cfg.cameras, cfg.head, cfg.output)


# ---------------------------------------------------------------------------------------------
# Devices
# ---------------------------------------------------------------------------------------------
def import_sounddevice() -> Any:
    """Import :mod:`sounddevice` lazily; a missing module or PortAudio library becomes a clear
    :class:`hearsee.errors.AudioInputError`."""
    try:
        import sounddevice
    except ImportError:
        raise AudioInputError("audio: the sounddevice package is not installed "
                              "(pip install 'hearsee[live]')") from None
    except OSError:
        raise AudioInputError("audio: PortAudio library not found "
                              "(apt-get install libportaudio2)") from None
    return sounddevice


def _device_list(sd: Any) -> list[dict[str, Any]]:
    devs = sd.query_devices()
    out = []
    for k, d in enumerate(devs):
        d = dict(d)
        d.setdefault("index", k)
        out.append(d)
    return out


def _describe(devs: Sequence[Mapping[str, Any]]) -> str:
    ins = [f"{d['index']} {d['name']!r} ({d['max_input_channels']} in)" for d in devs
           if d.get("max_input_channels", 0) > 0]
    return ", ".join(ins) if ins else "none"


def resolve_input_device(sd: Any, spec: DeviceSpec | None, where: str = "audio.device"
                         ) -> dict[str, Any]:
    """The input device (a dict with ``index``, ``name``, ``max_input_channels``, ...) named by
    ``spec``: an index, a (case-insensitive) name substring, or None for the default input.
    Raises ConfigError naming ``where`` and listing the available input devices."""
    devs = _device_list(sd)
    inputs = [d for d in devs if d.get("max_input_channels", 0) > 0]
    if spec is None:
        default = sd.default.device
        idx = default[0] if isinstance(default, Sequence) and not isinstance(default, str) \
            else default
        if idx is None or int(idx) < 0 or int(idx) >= len(devs):
            raise ConfigError(f"{where}: no default input device (available: "
                              f"{_describe(devs)}); name one in audio.device")
        dev = devs[int(idx)]
    elif isinstance(spec, int):
        if spec >= len(devs):
            raise ConfigError(f"{where}: no device with index {spec} (available: "
                              f"{_describe(devs)})")
        dev = devs[spec]
    else:
        key = spec.lower()
        exact = [d for d in inputs if str(d["name"]).lower() == key]
        hits = exact or [d for d in inputs if key in str(d["name"]).lower()]
        if not hits:
            raise ConfigError(f"{where}: no input device named {spec!r} (available: "
                              f"{_describe(devs)})")
        if len(hits) > 1:
            names = ", ".join(f"{d['index']} {d['name']!r}" for d in hits)
            raise ConfigError(f"{where}: {spec!r} matches several input devices ({names}); "
                              "use a longer name or the index")
        dev = hits[0]
    if dev.get("max_input_channels", 0) <= 0:
        raise ConfigError(f"{where}: device {dev['index']} {dev['name']!r} has no input "
                          f"channels (available: {_describe(devs)})")
    return dev


def open_capture(spec: DeviceSpec, where: str) -> Any:
    """``cv2.VideoCapture(spec)``, opened, or ConfigError naming ``where``."""
    import cv2

    cap = cv2.VideoCapture(spec)
    if not cap.isOpened():
        cap.release()
        raise ConfigError(f"{where}: cannot open camera {spec!r} (check the index, path or URL "
                          "and that no other program uses it)")
    return cap


def read_frame(cap: Any, spec: DeviceSpec, where: str, size: tuple[int, int] | None = None
               ) -> NDArray:
    """One frame from an open capture; ConfigError when none comes or it has the wrong size
    (``size`` = (width, height))."""
    ok, frame = cap.read()
    if not ok or frame is None:
        raise ConfigError(f"{where}: camera {spec!r} opened but delivered no frame")
    if size is not None and (frame.shape[1], frame.shape[0]) != tuple(size):
        raise ConfigError(f"{where}: camera {spec!r} delivers {frame.shape[1]}x{frame.shape[0]} "
                          f"frames but the calibration expects {size[0]}x{size[1]}")
    return frame


@dataclass
class Check:
    """One dry-run check: ``name`` (the config field), ``ok``, ``detail`` (what was found or the
    error message)."""

    name: str
    ok: bool
    detail: str


def _check(name: str, fn: Callable[[], str]) -> Check:
    try:
        return Check(name, True, fn())
    except HearseeError as exc:
        return Check(name, False, str(exc))


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
        sd = import_sounddevice()
        dev = resolve_input_device(sd, a.device, f"{cfg.path}: audio.device")
        where = "audio.channels" if cfg.audio.channels != tuple(range(a.array.n_mics)) \
            else "audio.device"
        where = f"{cfg.path}: {where}"
        if dev["max_input_channels"] < a.n_open:
            raise ConfigError(f"{where}: device {dev['index']} {dev['name']!r} has "
                              f"{dev['max_input_channels']} input channels; the array needs "
                              f"{a.n_open} (channels {list(a.channels)})")
        try:
            sd.check_input_settings(device=dev["index"], channels=a.n_open, samplerate=a.fs,
                                    dtype="float32")
        except Exception as exc:  # sounddevice raises PortAudioError or ValueError
            raise ConfigError(f"{cfg.path}: audio.fs: device {dev['index']} {dev['name']!r} "
                              f"does not accept {a.n_open} channels at {a.fs} Hz ({exc})") from None
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
                cap = open_capture(spec, where)
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


def _log(msg: str) -> None:  # pragma: no cover - trivial
    print(msg, file=sys.stderr)
