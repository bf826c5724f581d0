"""Optional exports of a robot run: a Rerun recording and an MCAP file of ROS 2 messages.

Both are behind extras (``pip install 'hearsee[rerun]'``, ``'hearsee[ros]'``); a missing extra is a
clear :class:`hearsee.errors.ConfigError`. Positions are in the ROOM frame of a simulated run
(ROS frame id ``room``) and in the robot's own frame for a live run (``hearsee run``, frame id
``robot``); times are seconds from the start of the run.

ROS 2 messages written to MCAP (open in Foxglove or ``ros2 bag``):

- ``/hearsee/speaker`` geometry_msgs/msg/PointStamped: the tracked speaker position;
- ``/hearsee/truth`` geometry_msgs/msg/PointStamped: the ground truth (simulation only): the
  current talker's position, so it jumps where people take turns (the log's
  ``truth.talker`` names them);
- ``/hearsee/head_pan`` std_msgs/msg/Float64: the head pan angle in degrees;
- ``/hearsee/overlay`` sensor_msgs/msg/Image (bgr8): the left camera with detections.
"""

from __future__ import annotations

import importlib.util
import re
from collections.abc import Mapping, Sequence
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _dist_version
from pathlib import Path
from typing import Any

import numpy as np

from hearsee.config import finite_number, open_replaced, output_file, same_file
from hearsee.config import replacing as _replacing  # (its home was here)
from hearsee.errors import ConfigError

__all__ = ["check_export", "check_export_targets", "write_mcap", "write_rerun"]

#: each export's module and the error when its extra is not installed
_EXTRAS = {"rerun": ("rerun", "--rerun needs the Rerun extra: pip install 'hearsee[rerun]'"),
           "mcap": ("mcap_ros2", "--mcap needs the ROS extra: pip install 'hearsee[ros]'")}

#: The oldest rerun-sdk whose API :func:`write_rerun` uses (``RecordingStream(app_id)``,
#: ``set_time(duration=)``, ``rr.Scalars``: 0.23). The extra asked for ``>=0.20`` until
#: 2026-12-07: with 0.20-0.22 a run ended in an AttributeError traceback once it was done.
RERUN_MIN_VERSION = (0, 23)


def _check_rerun_version() -> None:
    """ConfigError when the installed rerun-sdk is older than :data:`RERUN_MIN_VERSION`, the
    API :func:`write_rerun` uses (nothing when its version is unknown)."""
    try:
        v = str(_dist_version("rerun-sdk"))
    except PackageNotFoundError:
        return
    m = re.match(r"(\d+)\.(\d+)", v)
    if m and tuple(map(int, m.groups())) < RERUN_MIN_VERSION:
        need = ".".join(map(str, RERUN_MIN_VERSION))
        raise ConfigError(f"--rerun needs rerun-sdk {need} or later, found {v}: "
                          "pip install --upgrade 'hearsee[rerun]'")


_POINT_STAMPED = """std_msgs/Header header
geometry_msgs/Point point
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z"""

_IMAGE = """std_msgs/Header header
uint32 height
uint32 width
string encoding
uint8 is_bigendian
uint32 step
uint8[] data
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec"""

_FLOAT64 = "float64 data"


#: The latest time an MCAP export takes, seconds from the start of the run: a ROS 2 stamp's
#: seconds are an int32 (and an MCAP log time uint64 nanoseconds, so no time is negative).
MAX_STAMP_S = float(2**31 - 1)


def _time_s(t: Any, what: str) -> float:
    """``t`` (seconds) when it is a finite number in [0, :data:`MAX_STAMP_S`], else a
    ConfigError naming ``what``: a negative or huge time was struct.error "argument out of
    range" from the MCAP writer, NaN a builtin ValueError, a record without ``t`` a
    KeyError."""
    return finite_number(what, t, 0.0, MAX_STAMP_S)


def _stamp(t: float) -> dict[str, int]:
    # from the rounded nanoseconds (as log_time): a time just below a whole second carries
    sec, nanosec = divmod(int(round(t * 1e9)), 1_000_000_000)
    return {"sec": sec, "nanosec": nanosec}


def _overlay_bgr(img: np.ndarray, t: float) -> np.ndarray:
    """An overlay frame (H, W) grey or (H, W, 1|3|4) grey/BGR/BGRA as contiguous (H, W, 3) BGR
    uint8 (the layout both exports describe), else an ImageInputError naming the time ``t``."""
    from hearsee.errors import ImageInputError
    from hearsee.vision.io import as_detector_image

    if np.asarray(img).dtype != np.uint8:  # (cast unsafely: uint16 300 -> 44, float 0.7 -> 0)
        raise ImageInputError(f"overlay frame at t = {t} s: expected 8-bit pixels (uint8), got "
                              f"{np.asarray(img).dtype}")
    img = as_detector_image(np.ascontiguousarray(img), f"overlay frame at t = {t} s")
    return np.repeat(img[:, :, None], 3, axis=2) if img.ndim == 2 else img


class _Positioned:
    """A write-only stream that counts its bytes for ``tell()``: the MCAP writer asks for its
    position, which a FIFO cannot tell (OSError: Illegal seek)."""

    def __init__(self, fh: Any) -> None:
        self.fh, self.n = fh, 0

    def write(self, data: bytes) -> int:
        self.fh.write(data)
        self.n += len(data)
        return len(data)

    def tell(self) -> int:
        return self.n

    def flush(self) -> None:
        self.fh.flush()


def check_export(kind: str, path: str | Path) -> str:
    """Before a run that ends by writing export ``kind`` (``"rerun"`` or ``"mcap"``) to
    ``path``: its extra is installed (else :class:`ConfigError`; so is a rerun-sdk older than
    :data:`RERUN_MIN_VERSION`) and its folder exists (else
    :class:`InputFileError`), so a long live run does not fail only at its end. Returns a
    one-line description for ``hearsee run --dry-run``."""
    if kind not in _EXTRAS:  # (a KeyError)
        raise ConfigError(f"export kind must be one of {', '.join(_EXTRAS)}, got {kind!r}")
    module, missing = _EXTRAS[kind]
    if importlib.util.find_spec(module) is None:
        raise ConfigError(missing)
    if kind == "rerun":
        _check_rerun_version()
    return f"{output_file(path)}: {module} installed, folder exists"


def check_export_targets(exports: Sequence[tuple[str, str | Path | None]], report: str | Path,
                         report_name: str, jsonl: str | Path | None = None) -> None:
    """Before a run that writes its report folder ``report`` (and, for ``hearsee run``, its
    JSON lines file ``jsonl``) and then its exports: ConfigError when an export ``(option,
    path)`` (None paths skipped) is one of the run's own outputs -- one of the report's files
    (:func:`hearsee.robot.report.report_overwrites`) or the JSON lines file. The exports are
    written last and replaced them (an MCAP over log.json: a broken report), so this holds
    with ``--force`` too. So is an export path that the report makes a folder: the report
    folder itself, its ``plots/`` or ``frames/``, or a folder above the report folder (until
    2026-12-02 ``--mcap`` naming the ``--out`` folder that did not exist yet passed, the run
    made the folder, and the export failed after the whole run: "is a folder").
    ``report_name`` names the folder in the message, e.g. ``"--out hearsee-report"``. The
    one check of ``hearsee demo`` and ``hearsee run``."""
    from hearsee.robot.report import report_makes_folder, report_overwrites

    for opt, p in exports:
        if p is None:
            continue
        # (an existing folder: check_exports' "is a folder, expected an output file name")
        if not Path(p).resolve().is_dir() and report_makes_folder(report, p):
            raise ConfigError(f"{opt} {p}: the report ({report_name}) writes into this folder "
                              "or makes it; choose a file name outside the report")
        if jsonl is not None and same_file(p, jsonl):
            raise ConfigError(f"{opt} {p} is the run's JSON lines file (output.jsonl "
                              f"{jsonl}); choose another path")
        if report_overwrites(report, [p]) is not None:
            raise ConfigError(f"{opt} {p} is one of the report's own files ({report_name}); "
                              "choose another path")


def write_mcap(path: str | Path, log: Sequence[Mapping[str, Any]],
               frames: Sequence[tuple[float, np.ndarray]] = (), frame_id: str = "room") -> Path:
    """Write the run's estimates (and overlay images ``(t, bgr uint8)``) as ROS 2 messages;
    ``frame_id`` names the frame of the positions: ``"room"`` for a simulated run, ``"robot"``
    for a live one (its log is in the robot frame; it was labelled ``room`` until
    2026-12-01). The file is written beside ``path`` and replaces it only when complete: an
    error leaves an existing file as it was. Each record's ``t`` and each frame's time must be
    seconds in [0, :data:`MAX_STAMP_S`] and each position 3 numbers, else ConfigError."""
    try:
        from mcap_ros2.writer import Writer
    except ImportError:
        raise ConfigError(_EXTRAS["mcap"][1]) from None
    p = output_file(path)
    with _replacing(p) as tmp, open_replaced(tmp) as fh:
        w = Writer(fh if tmp.is_file() else _Positioned(fh))
        s_point = w.register_msgdef("geometry_msgs/msg/PointStamped", _POINT_STAMPED)
        s_image = w.register_msgdef("sensor_msgs/msg/Image", _IMAGE)
        s_float = w.register_msgdef("std_msgs/msg/Float64", _FLOAT64)
        for seq, rec in enumerate(log):
            t = _time_s(rec.get("t"), f"log record {seq}: t (seconds from the run's start)")
            ns = int(round(t * 1e9))
            for topic, key in (("/hearsee/speaker", "track"), ("/hearsee/truth", "truth")):
                pos = (rec.get(key) or {}).get("position_m")
                if pos is not None:
                    if np.shape(pos) != (3,):  # (a 2-D point was an IndexError)
                        raise ConfigError(f"log record {seq}: {key}.position_m must be 3 "
                                          f"numbers (x, y, z in metres), got {pos!r:.60}")
                    w.write_message(topic, s_point, {
                        "header": {"stamp": _stamp(t), "frame_id": frame_id},
                        "point": {"x": float(pos[0]), "y": float(pos[1]), "z": float(pos[2])},
                    }, log_time=ns, publish_time=ns, sequence=seq)
            if rec.get("head_pan_deg") is not None:
                w.write_message("/hearsee/head_pan", s_float, {"data": float(rec["head_pan_deg"])},
                                log_time=ns, publish_time=ns, sequence=seq)
        for seq, (t, img) in enumerate(frames):
            t = _time_s(t, f"overlay frame {seq}: t (seconds from the run's start)")
            img = _overlay_bgr(img, t)
            ns = int(round(t * 1e9))
            w.write_message("/hearsee/overlay", s_image, {
                "header": {"stamp": _stamp(t), "frame_id": "left_camera"},
                "height": img.shape[0], "width": img.shape[1], "encoding": "bgr8",
                "is_bigendian": 0, "step": img.shape[1] * 3, "data": img.tobytes(),
            }, log_time=ns, publish_time=ns, sequence=seq)
        w.finish()
    return p


#: :func:`write_rerun` logs the truth's and the track's paths (each its whole line so far) at
#: most about this many times per run, every ``ceil(len(log) / RERUN_PATH_UPDATES)`` records
#: and at the last: logged at every record, a recording grew with the square of the run's
#: length (a 4-minute live run at 32-ms hops logged 28 million path points, an hour ~6e9)
RERUN_PATH_UPDATES = 200


def write_rerun(path: str | Path, scenario: Mapping[str, Any], log: Sequence[Mapping[str, Any]],
                frames: Sequence[tuple[float, np.ndarray]] = ()) -> Path:
    """Write a Rerun recording (``.rrd``): room, robot, truth and track in 3D, and the images.
    The truth follows the current talker (the log's ``truth.talker``, labelled with their
    name): its line breaks where the talker changes, and the track's where a track was let go
    and a new one began (until 2026-12-06 each was one line, drawn across the room at a
    change). The points are logged at every record, the lines up to
    :data:`RERUN_PATH_UPDATES` times (at every record of a run of up to that many). As
    :func:`write_mcap`, the file replaces an existing ``path`` only when complete."""
    try:
        import rerun as rr
    except ImportError:
        raise ConfigError(_EXTRAS["rerun"][1]) from None
    _check_rerun_version()
    p = output_file(path)
    rec = rr.RecordingStream("hearsee")
    room = np.asarray(scenario["room"]["size_m"], dtype=float)
    rec.log("room", rr.Boxes3D(centers=[room / 2], half_sizes=[room / 2]), static=True)
    robot = list(scenario["robot"]["position_m"]) + [scenario["robot"]["head_height_m"]]
    rec.log("robot", rr.Points3D([robot], radii=0.1, labels=["robot"]), static=True)
    for k, o in enumerate(scenario.get("objects", [])):
        pts = rr.Points3D([list(o["position_m"]) + [1.0]], radii=0.15, labels=[o["kind"]],
                          colors=[[220, 40, 40]])
        rec.log(f"objects/{k}", pts, static=True)
    names = [p.get("name") for p in scenario.get("people", [])]
    truth_strips: list[list[list[float]]] = []
    track_strips: list[list[list[float]]] = []
    talker, tracked = None, False
    every = max(1, -(-len(log) // RERUN_PATH_UPDATES))
    grown = {"truth_path": False, "track_path": False}  # (since each was last logged)
    for i, r in enumerate(log):
        rec.set_time("t", duration=float(r["t"]))
        truth = r.get("truth") or {}
        tr = truth.get("position_m")
        es = (r.get("track") or {}).get("position_m")
        if tr is not None:
            k = truth.get("talker")
            if not truth_strips or k != talker:  # (a new talker: a new line, not a jump)
                truth_strips.append([])
            talker = k
            truth_strips[-1].append(list(map(float, tr)))
            label = names[k] if isinstance(k, int) and 0 <= k < len(names) else None
            rec.log("truth", rr.Points3D([truth_strips[-1][-1]], radii=0.06,
                                         colors=[[40, 180, 40]],
                                         labels=None if label is None else [label]))
            grown["truth_path"] = True
        if es is not None:
            if not tracked:  # (a new track after none: a new line)
                track_strips.append([])
            track_strips[-1].append(list(map(float, es)))
            rec.log("track", rr.Points3D([track_strips[-1][-1]], radii=0.06,
                                         colors=[[40, 80, 220]]))
            grown["track_path"] = True
        tracked = es is not None
        if (i + 1) % every == 0 or i == len(log) - 1:
            for name, strips, colour in (("truth_path", truth_strips, [40, 180, 40]),
                                         ("track_path", track_strips, [40, 80, 220])):
                if grown[name]:
                    rec.log(name, rr.LineStrips3D(strips, colors=[colour]))
                    grown[name] = False
        if r.get("head_pan_deg") is not None:
            rec.log("head_pan_deg", rr.Scalars(float(r["head_pan_deg"])))
    for t, img in frames:
        rec.set_time("t", duration=float(t))
        # (BGR to RGB; a BGRA frame reversed whole was logged as ARGB: wrong colours)
        rgb = _overlay_bgr(img, t)[:, :, ::-1]
        rec.log("camera/overlay", rr.Image(np.ascontiguousarray(rgb)))
    with _replacing(p) as tmp:
        rec.save(str(tmp))
        rec.disconnect()  # (the file is complete only once its sink is closed)
    return p
