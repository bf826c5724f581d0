"""Scenarios for the robot pipeline: a room, the robot head, people, human-like objects, noise.

A scenario is a YAML file (or the built-in default, :func:`default_scenario`). Positions are
metres in the ROOM frame (x, y on the floor, z up, origin in a room corner); the robot's own frame
follows REP 103 (x forward, y left, z up) and is placed by ``robot.position_m`` and
``robot.heading_deg``. Every field is checked; an unknown or bad field raises
:class:`hearsee.errors.ConfigError` naming it (e.g. ``scenario.people[0].path_m``).

Schema (defaults in brackets)::

    name: str                      [custom]
    seed: int                      [0]      0 to 2**32 - 1 (MAX_SEED)
    duration_s: float              [6.0]    simulated time
    audio: {fs: int [16000], snr_db: float [20], frame_ms: float [64]}
                                   (frame_ms: TDOA frame length, 8-200 ms: at most one
                                   0.2 s control step)
    room: {size_m: [L, W, H] [7, 6, 3], rt60_s: float [0.3]}
    robot:
      position_m: [x, y]           [room centre]    base position on the floor
      heading_deg: float           [0]              robot x axis, from room +x toward +y
      head_height_m: float         [1.25]           pan/tilt pivot height above the floor
      array: str                   [three-mic]      preset name or YAML path: 3+ microphones
                                                    not on a line seen from above (x, y), or a
                                                    masked pair (mask2-asym)
      pan_speed_dps: float         [120]            maximum pan rate
      camera_rate_hz: float        [5]              stereo + thermal frames per second (at
                                                    most 5: one per 0.2 s control step)
      stereo: {baseline_m [0.12], focal_px [500], width [640], height [480]}
                                                    (each talker must come farther than
                                                    the nearest depth the stereo search
                                                    reaches: f B / its largest disparity)
      thermal: {width [160], height [120], hfov_deg [72]}   (mounted 7 cm above the left camera)
    people:                        [one walking speaker]
      - {name, path_m: [[x, y], ...] (waypoints, walked at constant speed over the run),
         height_m [1.72] (1.2-2.2: the detector's standing adult), voice: male|female
         [female],
         speaking: [[t0, t1], ...] [the first person: the whole run; the others: never],
         facing: toward-robot|path [toward-robot]}
      (every person is heard while they speak, in their own voice; people take turns: no
      two people's intervals may overlap inside the run, as the simulated robot attends to
      one talker at a time. The ground truth follows the current talker -- the person
      speaking, or between turns the last one who spoke; before the first word, the first
      to speak (:meth:`Scenario.talker_at`). The first person must speak during the run: an
      interval with t0 < duration_s; a silent or empty ``speaking`` is refused, as the
      robot would have nothing to turn to. Until 2026-12-06 only the first person was
      heard and the others' voice and speaking were read but not used)
    objects:                       [a mannequin]
      - {kind: mannequin|poster|coat, position_m: [x, y], yaw_deg [0], height_m [1.75]}
      (yaw_deg: the turn away from facing the robot, degrees; a poster, a flat cut-out, is
      turned by 0.3 of it, as hearsee.sim.scenes renders posters)

Every waypoint and object keeps ``WALL_CLEARANCE_M`` from the walls, every person and object
is lower than the ceiling, no two bodies (people and objects) come closer than
``MIN_BODY_SEPARATION_M`` (centre to centre: a person all along their walk, two people at the
same moment), and every path (each segment between waypoints) and object keeps
``ROBOT_CLEARANCE_M`` from the robot base; the robot keeps its cameras inside the room
however the head pans (:func:`hearsee.robot.pipeline.sensor_reach_m`: a wide stereo baseline
needs the robot farther from the walls), and its microphones at least
``hearsee.audio.propagation.MIN_WALL_DISTANCE_M`` inside it (walls, floor and ceiling; a large
array needs the robot farther from the walls). The
default speaker and mannequin (those of :func:`default_scenario`) are checked the same way
when ``people`` or ``objects`` is left out: with another room or robot position they may not
fit, and the error says which key to set.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from hearsee.audio.propagation import image_sources
from hearsee.config import (
    check_keys,
    finite_number,
    is_real,
    load_yaml,
    name_text,
    number,
    real_entries,
    whole_number,
)
from hearsee.errors import ConfigError

__all__ = [
    "MAX_DURATION_S",
    "MAX_FRAME_MS",
    "MAX_SEED",
    "MIN_BODY_SEPARATION_M",
    "MIN_DURATION_S",
    "ObjectSpec",
    "PersonSpec",
    "RobotSpec",
    "Scenario",
    "default_scenario",
    "load_scenario",
    "random_conversation",
    "random_scenario",
    "scenario_from_dict",
]

OBJECT_KINDS = ("mannequin", "poster", "coat")
VOICES = ("male", "female")
#: Minimum clearance (m) between the robot base and a person or object.
ROBOT_CLEARANCE_M = 0.6
#: Minimum distance (m) of people and objects from the walls.
WALL_CLEARANCE_M = 0.3
#: Minimum distance (m) between the centres of two bodies of a scenario (people and objects;
#: a walking person's path from an object, two people at the same moment): twice the
#: half-width of the body :mod:`hearsee.sim.scenes` renders, 0.30 m -- its hands, at
#: ``0.24 * build`` m from the body's axis with a 0.035 m radius, build up to 1.1 (the
#: renderer's random build, 0.9-1.1, which the robot's people and mannequins get) -- and
#: wider than a coat stand (sleeves to 0.25 m) or a poster (a print of a build-1 body).
#: Closer, the footprints overlap and the bodies stand in each other: until 2026-12-03 a
#: person on the spot of a mannequin was accepted and the demo ran without a word about it
#: (one blob for the detector; the mannequin was reported as a person).
MIN_BODY_SEPARATION_M = 0.6
#: A scenario's simulated length, seconds: the range of a scenario file's ``duration_s``, of
#: :func:`random_scenario` and of ``hearsee eval --duration`` (:func:`hearsee.robot.evaluate.
#: evaluate`). A 1 s scenario runs; it is too short for most speakers to be verified.
MIN_DURATION_S = 1.0
#: The simulated loop renders at most one camera frame per control step
#: (:data:`hearsee.robot.pipeline.CONTROL_DT`, 0.2 s), so ``camera_rate_hz`` is at most 5.
MAX_CAMERA_RATE_HZ = 5.0
#: ... and localizes each step's 0.2 s of audio (with one frame of the step before): the
#: first step has no history, so ``audio.frame_ms`` is at most one step, 200 ms. (8-512 ms was
#: accepted, and a frame over 200 ms failed at the first step with an audio-input error that
#: named no scenario field.)
MAX_FRAME_MS = 200.0
MAX_DURATION_S = 120.0
#: A scenario's seed: a whole number 0 to 2**32 - 1, in a scenario file, in
#: :func:`random_scenario` and in ``hearsee eval --seed`` (every seed of the evaluation). The
#: last two had no upper bound, so an eval scenario seeded 2**32 could not be saved and re-run
#: as a scenario file.
MAX_SEED = 2**32 - 1


@dataclass(frozen=True)
class PersonSpec:
    name: str
    path_m: np.ndarray  # (k, 2) waypoints on the floor, room frame
    height_m: float = 1.72
    voice: str = "female"
    speaking: tuple[tuple[float, float], ...] = ()
    facing: str = "toward-robot"


@dataclass(frozen=True)
class ObjectSpec:
    kind: str
    position_m: np.ndarray  # (2,) room frame
    yaw_deg: float = 0.0
    height_m: float = 1.75


@dataclass(frozen=True)
class RobotSpec:
    position_m: np.ndarray  # (2,) base on the floor, room frame
    heading_deg: float = 0.0
    head_height_m: float = 1.25
    array: str = "three-mic"
    pan_speed_dps: float = 120.0
    camera_rate_hz: float = 5.0
    baseline_m: float = 0.12
    focal_px: float = 500.0
    width: int = 640
    height: int = 480
    thermal_width: int = 160
    thermal_height: int = 120
    thermal_hfov_deg: float = 72.0


@dataclass(frozen=True)
class Scenario:
    name: str
    seed: int
    duration_s: float
    fs: int
    snr_db: float
    frame_ms: float
    room_size_m: np.ndarray  # (3,)
    rt60_s: float
    robot: RobotSpec
    people: tuple[PersonSpec, ...]
    objects: tuple[ObjectSpec, ...]

    # ------------------------------------------------------------------ kinematics
    def person_position(self, k: int, t: float | np.ndarray) -> np.ndarray:
        """Floor position (room frame, metres) of person k at time(s) t: (..., 2)."""
        return _walk_position(self.people[k].path_m, self.duration_s, t)

    def talker_at(self, t: float) -> int:
        """Index of the current talker at time ``t`` (seconds): the person speaking then, or
        between turns the last one who spoke (the latest interval start at or before ``t``);
        before anyone speaks, the first to speak. People take turns (no two intervals of
        different people overlap inside the run), so the answer is unique. The robot's
        ground truth follows this person."""
        starts = self.speech_starts()
        if not starts:  # (refused by the parser: the first person speaks during the run)
            return 0
        begun = [k for a, k in starts if a <= t]  # (in time order)
        return begun[-1] if begun else starts[0][1]

    def speech_starts(self) -> list[tuple[float, int]]:
        """``(t0, k)`` of every speaking interval that starts inside the run (seconds, person
        index), in time order: one place for the turns' bookkeeping."""
        return sorted((a, k) for k, p in enumerate(self.people) for a, _ in p.speaking
                      if a < self.duration_s)

    def talkers(self) -> list[int]:
        """Indices of the people who speak during the run, ascending (the parser makes the
        first person one of them; a Scenario built around it may not)."""
        return sorted({k for _, k in self.speech_starts()})

    def person_speed_mps(self, k: int) -> float:
        path = self.people[k].path_m
        return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum() / self.duration_s)

    def to_dict(self) -> dict[str, Any]:
        r = self.robot
        return {
            "name": self.name,
            "seed": self.seed,
            "duration_s": self.duration_s,
            "audio": {"fs": self.fs, "snr_db": self.snr_db, "frame_ms": self.frame_ms},
            "room": {"size_m": self.room_size_m.tolist(), "rt60_s": self.rt60_s},
            "robot": {
                "position_m": r.position_m.tolist(),
                "heading_deg": r.heading_deg,
                "head_height_m": r.head_height_m,
                "array": r.array,
                "pan_speed_dps": r.pan_speed_dps,
                "camera_rate_hz": r.camera_rate_hz,
                "stereo": {"baseline_m": r.baseline_m, "focal_px": r.focal_px,
                           "width": r.width, "height": r.height},
                "thermal": {"width": r.thermal_width, "height": r.thermal_height,
                            "hfov_deg": r.thermal_hfov_deg},
            },
            "people": [
                {"name": p.name, "path_m": p.path_m.tolist(), "height_m": p.height_m,
                 "voice": p.voice, "speaking": [list(s) for s in p.speaking], "facing": p.facing}
                for p in self.people
            ],
            "objects": [
                {"kind": o.kind, "position_m": o.position_m.tolist(), "yaw_deg": o.yaw_deg,
                 "height_m": o.height_m}
                for o in self.objects
            ],
        }


# ---------------------------------------------------------------------- parsing helpers
def _vec(v: Any, n: int | None, where: str) -> np.ndarray:
    # (YAML's yes/on/true was read as 1.0 m and "7" as 7 m, as the single-number fields refuse)
    if not real_entries(v):
        raise ConfigError(f"{where}: expected numbers, got {v!r}")
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: expected numbers, got {v!r}") from None
    if n is not None and a.shape != (n,):
        raise ConfigError(f"{where}: expected {n} numbers, got {v!r}")
    if not np.all(np.isfinite(a)):
        raise ConfigError(f"{where}: values must be finite")
    return a


def _section(d: Mapping[str, Any], key: str, where: str) -> Mapping[str, Any]:
    v = d.get(key, {})
    if v is None:
        v = {}
    if not isinstance(v, Mapping):
        raise ConfigError(f"{where}.{key}: expected a mapping, got {type(v).__name__}")
    return v


def _inside(xy: np.ndarray, room: np.ndarray, where: str) -> None:
    lo, hi = WALL_CLEARANCE_M, room[:2] - WALL_CLEARANCE_M
    if np.any(xy < lo) or np.any(xy > hi):
        raise ConfigError(
            f"{where}: {np.round(xy, 3).tolist()} is outside the room or closer than "
            f"{WALL_CLEARANCE_M} m to a wall (room {room[:2].tolist()} m)"
        )


def _under_ceiling(height: float, room: np.ndarray, where: str) -> float:
    """``height`` (m) when it is below the room's ceiling, else ConfigError naming ``where``."""
    if height >= room[2]:
        raise ConfigError(f"{where}: {height} m does not fit under the {room[2]} m ceiling")
    return height


def _path_distance(path: np.ndarray, p: np.ndarray) -> float:
    """Smallest distance (m) from point ``p`` to the polyline ``path`` ((k, 2) waypoints; one
    waypoint: the distance to it)."""
    if len(path) == 1:
        return float(np.linalg.norm(path[0] - p))
    a, b = path[:-1], path[1:]
    ab = b - a
    L2 = np.einsum("ij,ij->i", ab, ab)
    u = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.where(L2 > 0, L2, 1.0), 0.0, 1.0)
    return float(np.min(np.linalg.norm(a + u[:, None] * ab - p, axis=1)))


def _walk_position(path: np.ndarray, duration: float, t: float | np.ndarray) -> np.ndarray:
    """Floor position (m) at time(s) ``t`` (s) of a person walking the waypoints ``path``
    ((k, 2), metres) at constant speed over ``duration`` seconds: (..., 2)."""
    if len(path) == 1:
        return np.broadcast_to(path[0], np.shape(t) + (2,)).copy()
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    s_cum = np.concatenate([[0.0], np.cumsum(seg)])
    s = np.clip(np.asarray(t, dtype=float) / duration, 0.0, 1.0) * s_cum[-1]
    return np.stack([np.interp(s, s_cum, path[:, 0]), np.interp(s, s_cum, path[:, 1])], -1)


def _closest_approach(a: np.ndarray, b: np.ndarray, duration: float) -> tuple[float, float]:
    """(distance (m), time (s)) of the closest approach of two people walking the waypoints
    ``a`` and ``b`` ((k, 2), metres) over the same ``duration`` seconds: between the times at
    which either passes a waypoint both move in straight lines at constant speeds, so their
    offset is a polyline in time, and its closest point to zero is the answer (exact)."""
    def knots(path: np.ndarray) -> np.ndarray:
        s_cum = np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))
        return s_cum / s_cum[-1] * duration if len(s_cum) and s_cum[-1] > 0 else s_cum[:0]

    t = np.unique(np.concatenate([[0.0, duration], knots(a), knots(b)]))
    rel = _walk_position(a, duration, t) - _walk_position(b, duration, t)
    if len(t) == 1:  # (a duration of 0 s; the parser refuses it)
        return float(np.linalg.norm(rel[0])), 0.0
    d0, d = rel[:-1], np.diff(rel, axis=0)
    L2 = np.einsum("ij,ij->i", d, d)
    u = np.clip(-np.einsum("ij,ij->i", d0, d) / np.where(L2 > 0, L2, 1.0), 0.0, 1.0)
    dist = np.linalg.norm(d0 + u[:, None] * d, axis=1)
    k = int(np.argmin(dist))
    return float(dist[k]), float(t[k] + u[k] * (t[k + 1] - t[k]))


def _check_turns(people: tuple[PersonSpec, ...], duration: float, where: str) -> None:
    """ConfigError naming two people whose speaking intervals overlap inside the run
    (``duration`` seconds): the simulated robot attends to one talker at a time
    (:meth:`Scenario.talker_at`), so a scenario's people take turns. Touching intervals
    ([1, 2] and [2, 3]) are turns."""
    for k in range(len(people)):
        for j in range(k + 1, len(people)):
            for a, b in people[k].speaking:
                for c, d in people[j].speaking:
                    lo, hi = max(a, c), min(b, d, duration)
                    if lo < hi:
                        raise ConfigError(
                            f"{where}.people[{j}].speaking: [{c:g}, {d:g}] overlaps "
                            f"people[{k}]'s [{a:g}, {b:g}] ({lo:g}-{hi:g} s); the simulated "
                            "robot follows one talker at a time, so people take turns")


def _check_bodies_apart(people: tuple[PersonSpec, ...], objects: tuple[ObjectSpec, ...],
                        duration: float, where: str, defaults: tuple[bool, bool]) -> None:
    """ConfigError naming two bodies whose centres come closer than
    :data:`MIN_BODY_SEPARATION_M` (metres): two people at the same moment of the run
    (``duration`` seconds), a person anywhere along their walk and an object, two objects.
    ``defaults``: whether ``people`` / ``objects`` are the defaults (not in the file), which
    the message then says."""
    sep = MIN_BODY_SEPARATION_M
    tol = 1e-9  # (0.6 m written in the file, 4.6 - 4.0, is 0.5999999999999996 in floats)

    def person(k: int) -> str:
        return (f"{where}.people[{k}] ({people[k].name!r}"
                + (f"; the default, {where}.people not given)" if defaults[0] else ")"))

    def obj(k: int) -> str:
        o = objects[k]
        return (f"{where}.objects[{k}] ({o.kind} at {np.round(o.position_m, 3).tolist()}"
                + (f"; the default, {where}.objects not given)" if defaults[1] else ")"))

    def refuse(a: str, b: str, how: str) -> None:
        raise ConfigError(
            f"{a} and {b} {how} (centre to centre); bodies need {sep} m "
            f"(MIN_BODY_SEPARATION_M), else they stand in each other: move one of them")

    for k in range(len(people)):
        for j in range(k + 1, len(people)):
            d, t = _closest_approach(people[k].path_m, people[j].path_m, duration)
            if d < sep - tol:
                refuse(person(k), person(j), f"come within {d:.2f} m of each other at t = "
                                             f"{t:.2f} s")
    for k, p in enumerate(people):
        for j, o in enumerate(objects):
            d = _path_distance(p.path_m, o.position_m)
            if d < sep - tol:
                refuse(person(k), obj(j), f"come within {d:.2f} m of each other"
                       if len(p.path_m) > 1 else f"stand {d:.2f} m apart")
    for k in range(len(objects)):
        for j in range(k + 1, len(objects)):
            d = float(np.linalg.norm(objects[k].position_m - objects[j].position_m))
            if d < sep - tol:
                refuse(obj(k), obj(j), f"stand {d:.2f} m apart")


def _parse_person(p: Any, k: int, pw: str, size: np.ndarray, robot_xy: np.ndarray,
                  duration: float) -> PersonSpec:
    if not isinstance(p, Mapping):
        raise ConfigError(f"{pw}: expected a mapping")
    check_keys(p, ("name", "path_m", "height_m", "voice", "speaking", "facing"), pw)
    if "path_m" not in p:
        raise ConfigError(f"{pw}: missing required key 'path_m'")
    path = _vec(p["path_m"], None, f"{pw}.path_m")
    if path.ndim == 1 and path.shape == (2,):
        path = path[None, :]
    if path.ndim != 2 or path.shape[1] != 2 or len(path) == 0:
        raise ConfigError(f"{pw}.path_m: expected a list of [x, y] waypoints")
    for w in path:
        _inside(w, size, f"{pw}.path_m")
    d = _path_distance(path, robot_xy)
    if d < ROBOT_CLEARANCE_M:
        raise ConfigError(f"{pw}.path_m: passes within {ROBOT_CLEARANCE_M} m of the robot "
                          f"at {np.round(robot_xy, 3).tolist()} (closest {d:.2f} m)")
    voice = p.get("voice", "female")
    if voice not in VOICES:
        raise ConfigError(f"{pw}.voice: expected one of {VOICES}, got {voice!r}")
    speaking = p.get("speaking", [[0.0, duration]] if k == 0 else [])
    # (only pairs of numbers: ["06"] was unpacked into (0.0, 6.0), [[false, true]] read as
    # (0.0, 1.0))
    if not isinstance(speaking, list | tuple) or not all(
            isinstance(s, list | tuple) and len(s) == 2 and all(is_real(v) for v in s)
            for s in speaking):
        raise ConfigError(f"{pw}.speaking: expected [[t0, t1], ...] in seconds, got "
                          f"{speaking!r:.60}")
    spk = tuple((float(a), float(b)) for a, b in speaking)
    if any(not (0 <= a < b) for a, b in spk):
        raise ConfigError(f"{pw}.speaking: each interval needs 0 <= t0 < t1")
    if k == 0 and not any(a < duration for a, _ in spk):
        # (a run in which the first person never spoke heard nothing, saw nothing and
        # summarized to nulls, exit 0, when they were the only one heard)
        raise ConfigError(
            f"{pw}.speaking: the first person must speak, and they never "
            f"speak during the run ({duration:g} s): "
            + ("an empty list" if not spk else f"every interval starts at or after {duration:g} s")
            + f"; give an interval [t0, t1] with t0 < {duration:g}")
    facing = p.get("facing", "toward-robot")
    if facing not in ("toward-robot", "path"):
        raise ConfigError(f"{pw}.facing: expected 'toward-robot' or 'path'")
    height = _under_ceiling(number(p, "height_m", 1.72, pw, 1.0, 2.2), size, f"{pw}.height_m")
    from hearsee.vision.humans import HumanDetectorParams

    shortest = HumanDetectorParams.min_top_m
    if height < shortest:  # (accepted, a 1.0-1.19 m person was heard, never seen: the run
        # failed, each time, with nothing said)
        raise ConfigError(
            f"{pw}.height_m: {height:g} m is below the {shortest:g} m the people detector "
            "takes for a standing adult's top (HumanDetectorParams.min_top_m): the robot "
            f"would hear them but never see them; give {shortest:g}-2.2 m")
    return PersonSpec(name=name_text(p.get("name", f"person{k}"), pw), path_m=path, height_m=height,
                      voice=voice, speaking=spk, facing=facing)


def _parse_object(o: Any, ow: str, size: np.ndarray, robot_xy: np.ndarray) -> ObjectSpec:
    if not isinstance(o, Mapping):
        raise ConfigError(f"{ow}: expected a mapping")
    check_keys(o, ("kind", "position_m", "yaw_deg", "height_m"), ow)
    kind = o.get("kind")
    if kind not in OBJECT_KINDS:
        raise ConfigError(f"{ow}.kind: expected one of {OBJECT_KINDS}, got {kind!r}")
    if "position_m" not in o:
        raise ConfigError(f"{ow}: missing required key 'position_m'")
    pos = _vec(o["position_m"], 2, f"{ow}.position_m")
    _inside(pos, size, f"{ow}.position_m")
    if np.linalg.norm(pos - robot_xy) < ROBOT_CLEARANCE_M:
        raise ConfigError(f"{ow}.position_m: closer than {ROBOT_CLEARANCE_M} m to the robot "
                          f"at {np.round(robot_xy, 3).tolist()}")
    return ObjectSpec(kind=kind, position_m=pos,
                      yaw_deg=number(o, "yaw_deg", 0.0, ow, -360, 360),
                      height_m=_under_ceiling(number(o, "height_m", 1.75, ow, 0.5, 2.2), size,
                                              f"{ow}.height_m"))


def _default_entries(key: str, noun: str, entries: list[dict[str, Any]], where: str,
                     parse: Callable[[Any, int, str], Any]) -> tuple[Any, ...]:
    """Parse the default ``people`` / ``objects`` with the checks of user entries; when one
    does not fit this room or robot position, say so and which key to set."""
    out = []
    for k, e in enumerate(entries):
        label = f"{where}.{key}[{k}]"
        try:
            out.append(parse(e, k, label))
        except ConfigError as exc:
            msg = str(exc)
            detail = msg[len(label):].lstrip(".: ") if msg.startswith(label) else msg
            what = e.get("name") or e.get("kind")
            raise ConfigError(
                f"{where}.{key}: not given, and the default {noun} {what!r} does not fit this "
                f"scenario ({detail}); set {where}.{key}"
                + (" (an empty list for none)" if key == "objects" else "")) from None
    return tuple(out)


def scenario_from_dict(data: Mapping[str, Any], where: str = "scenario",
                       base_dir: str | Path | None = None) -> Scenario:
    """Validate a scenario mapping (see module docstring) and build a :class:`Scenario`. A
    relative ``robot.array`` file path is resolved against ``base_dir`` (the scenario file's
    folder when loaded by :func:`load_scenario`; None = the working directory), as the robot
    file's paths are. ConfigError unless ``data`` is a mapping (an empty YAML's None and a
    list were builtin TypeError / AttributeError)."""
    if not isinstance(data, Mapping):
        raise ConfigError(f"{where}: expected a mapping of sections (name, seed, duration_s, "
                          f"audio, room, robot, people, objects), got {type(data).__name__}")
    check_keys(data, ("name", "seed", "duration_s", "audio", "room", "robot", "people", "objects"),
               where)
    base = default_scenario()
    audio = _section(data, "audio", where)
    check_keys(audio, ("fs", "snr_db", "frame_ms"), f"{where}.audio")
    room = _section(data, "room", where)
    check_keys(room, ("size_m", "rt60_s"), f"{where}.room")
    size = _vec(room.get("size_m", base.room_size_m.tolist()), 3, f"{where}.room.size_m")
    if np.any(size < 2.0) or np.any(size > 50.0):
        raise ConfigError(f"{where}.room.size_m: each side must be 2-50 m, got {size.tolist()}")
    rt60 = number(room, "rt60_s", base.rt60_s, f"{where}.room", 0.0, 2.0)
    try:  # the room's RT60 checked here, where the error can name the field
        image_sources(rt60, size)
    except ConfigError as e:
        raise ConfigError(f"{where}.room.rt60_s: {e}") from None
    duration = number(data, "duration_s", base.duration_s, where, MIN_DURATION_S,
                      MAX_DURATION_S)

    rob = _section(data, "robot", where)
    rw = f"{where}.robot"
    check_keys(rob, ("position_m", "heading_deg", "head_height_m", "array", "pan_speed_dps",
                     "camera_rate_hz", "stereo", "thermal"), rw)
    stereo = _section(rob, "stereo", rw)
    check_keys(stereo, ("baseline_m", "focal_px", "width", "height"), f"{rw}.stereo")
    thermal = _section(rob, "thermal", rw)
    check_keys(thermal, ("width", "height", "hfov_deg"), f"{rw}.thermal")
    robot_xy = _vec(rob.get("position_m", (size[:2] / 2).tolist()), 2, f"{rw}.position_m")
    _inside(robot_xy, size, f"{rw}.position_m")
    head_h = number(rob, "head_height_m", base.robot.head_height_m, rw, 0.2)
    if head_h > size[2] - 0.2:
        raise ConfigError(f"{rw}.head_height_m: {head_h} m does not fit under the "
                          f"{size[2]} m ceiling")
    array = rob.get("array", base.robot.array)
    if not isinstance(array, str):
        raise ConfigError(f"{rw}.array: expected a preset name or file path, got {array!r}")
    from hearsee.audio.arrays import load_array_beside

    # a file next to the scenario (base_dir; the robot file's rule), else a preset: a name that
    # was no file there was looked up in the working directory, where a file or folder named
    # like the preset (or the file) was read instead or refused (a "~/..." was not expanded);
    # the spec kept is the file's absolute path or the preset's name (run_scenario reads it)
    arr, array = load_array_beside(array, base_dir, f"{rw}.array")
    # (masked pairs: refused until 2026-12-05, when the room audio learned to turn the mask
    # with the head; the mask resolves the pair's front/back mirror. A planar array standing
    # upright -- a face plate, ears and forehead -- passed a linear-only check, and a speaker
    # straight behind the robot was heard straight ahead)
    check_hears_front_and_back(arr, f"{rw}.array", "the simulated robot")
    robot = RobotSpec(
        position_m=robot_xy,
        heading_deg=number(rob, "heading_deg", 0.0, rw, -360, 360),
        head_height_m=head_h,
        array=array,
        pan_speed_dps=number(rob, "pan_speed_dps", base.robot.pan_speed_dps, rw, 1.0, 2000.0),
        # (at most one frame per control step: up to 60 was accepted, and above 5 Hz the
        # simulated loop gave 5)
        camera_rate_hz=number(rob, "camera_rate_hz", base.robot.camera_rate_hz, rw, 0.5,
                              MAX_CAMERA_RATE_HZ),
        baseline_m=number(stereo, "baseline_m", 0.12, f"{rw}.stereo", 0.02, 1.0),
        focal_px=number(stereo, "focal_px", 500.0, f"{rw}.stereo", 50.0, 5000.0),
        width=number(stereo, "width", 640, f"{rw}.stereo", 64, 4096, integer=True),
        height=number(stereo, "height", 480, f"{rw}.stereo", 48, 4096, integer=True),
        thermal_width=number(thermal, "width", 160, f"{rw}.thermal", 16, 2048, integer=True),
        thermal_height=number(thermal, "height", 120, f"{rw}.thermal", 12, 2048, integer=True),
        thermal_hfov_deg=number(thermal, "hfov_deg", 72.0, f"{rw}.thermal", 10.0, 150.0),
    )

    _check_rig_clear_of_walls(robot, size, rw)
    _check_mics_in_room(robot, arr, size, rw)
    from hearsee.audio.tdoa import check_frame_for_array

    # (as the robot file's: a 1 m array's 8 ms frames, its shortest 12.1, left the demo's
    # talker heard 144 deg off, with nothing said)
    frame_ms = _frame_ms(audio, f"{where}.audio")
    check_frame_for_array(frame_ms, arr, f"{where}.audio.frame_ms")
    defaults = base.to_dict()

    def person(p: Any, k: int, pw: str) -> PersonSpec:
        return _parse_person(p, k, pw, size, robot_xy, duration)

    def obj(o: Any, k: int, ow: str) -> ObjectSpec:
        return _parse_object(o, ow, size, robot_xy)

    people_raw = data.get("people", None)
    if people_raw is None:
        people = _default_entries("people", "person", defaults["people"], where, person)
    else:
        if not isinstance(people_raw, list) or not people_raw:
            raise ConfigError(f"{where}.people: expected a non-empty list")
        people = tuple(person(p, k, f"{where}.people[{k}]") for k, p in enumerate(people_raw))

    objects_raw = data.get("objects", None)
    if objects_raw is None:
        objects = _default_entries("objects", "object", defaults["objects"], where, obj)
    else:
        if not isinstance(objects_raw, list):
            raise ConfigError(f"{where}.objects: expected a list")
        objects = tuple(obj(o, k, f"{where}.objects[{k}]") for k, o in enumerate(objects_raw))
    _check_bodies_apart(people, objects, duration, where,
                        (people_raw is None, objects_raw is None))
    _check_turns(people, duration, where)
    _check_talkers_in_stereo_reach(people, robot, duration, where, rw)

    name = data.get("name", "custom")
    seed = number(data, "seed", 0, where, 0, MAX_SEED, integer=True)
    return Scenario(
        name=name_text(name, where), seed=int(seed), duration_s=duration,
        fs=int(number(audio, "fs", 16000, f"{where}.audio", 8000, 96000, integer=True)),
        snr_db=number(audio, "snr_db", 20.0, f"{where}.audio", -20.0, 80.0),
        frame_ms=frame_ms,
        room_size_m=size, rt60_s=rt60, robot=robot, people=people, objects=objects,
    )


def _check_talkers_in_stereo_reach(people: tuple[PersonSpec, ...], robot: RobotSpec,
                                   duration: float, where: str, rw: str) -> None:
    """ConfigError naming ``robot.stereo.baseline_m`` when a person who speaks during the run
    stays nearer the robot than the stereo search reaches (``f B`` over its largest disparity,
    :func:`hearsee.vision.stereo.search_range_px` at the rig's width): the robot would hear
    them and never see them. Accepted, a 0.4 m baseline (nothing nearer 3.2 m) failed the demo
    scene, whose talker stays within 2.5 m, with nothing said (0.3 m: verified at 1.2 s)."""
    from hearsee.vision.stereo import search_range_px

    largest = search_range_px(robot.width)[1]  # (pixels)
    nearest = robot.focal_px * robot.baseline_m / largest
    for k, p in enumerate(people):
        if not any(a < duration for a, _ in p.speaking):
            continue
        # (a straight walk's distance from a point is convex: largest at a waypoint)
        far = float(np.linalg.norm(p.path_m - robot.position_m, axis=1).max())
        if far < nearest:
            most = far * largest / robot.focal_px
            raise ConfigError(
                f"{rw}.stereo.baseline_m: a {robot.baseline_m:g} m baseline at "
                f"{robot.focal_px:g} px sees nothing nearer than {nearest:.2f} m (the stereo "
                f"search's largest disparity), and {where}.people[{k}], who speaks, stays "
                f"within {far:.2f} m of the robot: it would hear them and never see them; "
                f"give at most {np.floor(most * 100) / 100:g} m")


def check_hears_front_and_back(array: Any, where: str, who: str) -> None:
    """ConfigError naming ``where`` unless ``array`` (a MicArray on a head that pans in the
    level plane) can tell a talker in front from one behind: a masked pair, or microphones
    that do not lie on a line seen from above (:func:`_level_footprint_is_a_line`). One rule
    for the scenario's and the robot file's arrays; ``who`` is named in the message."""
    if array.mask is None and _level_footprint_is_a_line(array):
        raise ConfigError(
            f"{where}: {array.name!r} cannot give {who} a 360-degree direction, it cannot tell "
            "a talker in front from one behind: its microphones, seen from above (x forward, "
            "y left, z up), lie on a line, so a source and its mirror across the upright plane "
            "through them give the same time differences (a talker at 150 deg is heard at 30 "
            "deg); use an array spread out horizontally, e.g. three-mic, respeaker-4 or "
            "respeaker-6, or a masked pair, e.g. mask2-asym")


def _level_footprint_is_a_line(array: Any) -> bool:
    """Whether the microphones of ``array`` (a MicArray; head frame, z up), projected on the
    level plane the head pans in, lie on a line (or a point) as time differences see them
    (:func:`hearsee.audio.arrays.span_dimension`): then every azimuth has a mirror across the
    upright plane through them -- a linear array's, or an upright planar one's."""
    from hearsee.audio.arrays import span_dimension

    level = np.asarray(array.positions, dtype=float).copy()
    level[:, 2] = 0.0
    if np.ptp(level, axis=0).max() == 0.0:  # (a vertical line: one point from above)
        return True
    return span_dimension(level, array.speed_of_sound)[0] < 2


def _check_rig_clear_of_walls(robot: RobotSpec, size: np.ndarray, rw: str) -> None:
    """ConfigError naming ``robot.stereo.baseline_m`` and ``robot.position_m`` when a camera
    of the panning head (:func:`hearsee.robot.pipeline.sensor_reach_m`, metres from the pan
    axis) can reach behind a wall of the room (``size`` metres). Accepted, such a robot
    failed at its first camera frame, after the audio was simulated, with a renderer error
    naming no scenario field."""
    from hearsee.robot.pipeline import sensor_reach_m

    reach = sensor_reach_m(robot.baseline_m)
    xy = robot.position_m
    clear = float(min(xy.min(), (size[:2] - xy).min()))  # to the nearest wall
    if reach > clear + 1e-9:
        raise ConfigError(
            f"{rw}.stereo.baseline_m: a {robot.baseline_m:g} m stereo rig puts a camera up to "
            f"{reach:.3f} m from the head's pan axis, but the robot at "
            f"{np.round(xy, 3).tolist()} is {clear:.3f} m from a wall: a camera would pan "
            f"behind it; use a shorter baseline or move {rw}.position_m away from the wall")


def _check_mics_in_room(robot: RobotSpec, array: Any, size: np.ndarray, rw: str) -> None:
    """ConfigError naming ``robot.array`` unless every microphone of ``array`` (a MicArray,
    its origin :data:`hearsee.robot.pipeline.ARRAY_OFFSET_M` from the pivot) stays at least
    :data:`hearsee.audio.propagation.MIN_WALL_DISTANCE_M` inside the room (``size`` metres)
    however the head pans -- the room simulation's rule. The simulated head pans all round
    at a level tilt: a microphone ``r`` metres from the pan axis comes within ``clear - r`` of
    the nearest wall, and its height is ``head_height_m`` + its own. Until 2026-12-02 a large
    array, or a tall one under the ceiling, was accepted and the run failed once the audio
    was simulated -- at the first step, or only when the head turned toward the wall --
    with the simulator's GeometryError naming no scenario field."""
    from hearsee.audio.propagation import MIN_WALL_DISTANCE_M
    from hearsee.robot.pipeline import ARRAY_OFFSET_M

    p = np.asarray(array.positions, dtype=float) + ARRAY_OFFSET_M  # head frame, from the pivot
    if array.mask is not None:  # (the mask's body too: the room simulation keeps it inside)
        from hearsee.audio.mask import mask_geometry

        body = mask_geometry(array).mesh(array.speed_of_sound).vertices
        p = np.vstack([p, body + ARRAY_OFFSET_M])

    def what(k: int) -> str:
        return f"microphone {k}" if k < array.n_mics else "the mask"

    r = np.hypot(p[:, 0], p[:, 1])
    k = int(np.argmax(r))
    xy = robot.position_m
    clear = float(min(xy.min(), (size[:2] - xy).min()))  # to the nearest wall
    if clear - r[k] < MIN_WALL_DISTANCE_M:
        raise ConfigError(
            f"{rw}.array: {what(k)} of {array.name!r} is {r[k]:.3f} m from the head's pan "
            f"axis, but the robot at {np.round(xy, 3).tolist()} is {clear:.3f} m from a wall: "
            f"panning, it would come within {MIN_WALL_DISTANCE_M} m of the wall or go through "
            f"it (the room simulation keeps every microphone {MIN_WALL_DISTANCE_M} m inside "
            f"the room); use a smaller array or move {rw}.position_m away from the wall")
    z = robot.head_height_m + p[:, 2]
    for k in (int(np.argmin(z)), int(np.argmax(z))):
        if not MIN_WALL_DISTANCE_M <= z[k] <= size[2] - MIN_WALL_DISTANCE_M:
            raise ConfigError(
                f"{rw}.array: {what(k)} of {array.name!r} is {z[k]:.3f} m above the floor "
                f"at {rw}.head_height_m {robot.head_height_m:g} m (array origin "
                f"{ARRAY_OFFSET_M[2]:g} m above the pivot), outside the {size[2]:g} m high "
                f"room or within {MIN_WALL_DISTANCE_M} m of its floor or ceiling; change "
                f"{rw}.head_height_m or use a flatter array")


def _frame_ms(audio: Mapping[str, Any], where: str) -> float:
    """``audio.frame_ms`` (ms): 8 to :data:`MAX_FRAME_MS`, else ConfigError naming it."""
    frame_ms = number(audio, "frame_ms", 64.0, where, 8.0)
    if frame_ms > MAX_FRAME_MS:
        raise ConfigError(f"{where}.frame_ms: must be <= {MAX_FRAME_MS:g} ms, one 0.2 s control "
                          f"step (the robot localizes each step's audio), got {frame_ms:g}")
    return frame_ms


def load_scenario(path: str | Path) -> Scenario:
    """Load and validate a scenario YAML file (a relative array path is relative to it)."""
    return scenario_from_dict(load_yaml(path), where=str(path),
                              base_dir=Path(path).resolve().parent)


def default_scenario() -> Scenario:
    """The built-in demo: a 7 x 6 x 3 m room (RT60 0.3 s, SNR 20 dB); the robot faces +x from
    near the room centre; a woman speaks from behind-left of the robot (azimuth about 121 -> 141
    deg, 2.7 m) while walking at 0.15 m/s; a mannequin stands 1.8 m away at azimuth 100 deg, in the
    camera's view once the head has turned to her."""
    room = np.array([7.0, 6.0, 3.0])
    robot_xy = np.array([3.5, 2.6])
    return Scenario(
        name="default", seed=7, duration_s=6.0, fs=16000, snr_db=20.0, frame_ms=64.0,
        room_size_m=room, rt60_s=0.3,
        robot=RobotSpec(position_m=robot_xy),
        people=(PersonSpec(name="speaker", path_m=np.array([[2.1, 4.9], [1.4, 4.3]]),
                           height_m=1.70, voice="female", speaking=((0.0, 6.0),)),),
        objects=(ObjectSpec(kind="mannequin", position_m=np.array([3.1, 4.4]), yaw_deg=-20.0),),
    )


def random_scenario(seed: int, duration_s: float = 6.0, array: str | None = None) -> Scenario:
    """A random scenario for ``hearsee eval``: one speaker walking 0.2-0.8 m/s in any direction
    from 1.5-3.5 m to 1.2-4 m from the robot, never passing within ``ROBOT_CLEARANCE_M`` of it
    (when no straight walk that long fits the room -- runs longer than about 10 s, which also
    favour the slower walks that do fit -- back and forth along a shorter line),
    0-2 human-like objects clear of the walk (:data:`MIN_BODY_SEPARATION_M`), RT60 0.2-0.5 s,
    SNR 10-25 dB. ``seed``: a whole number 0 to :data:`MAX_SEED` (as in a scenario file);
    ``duration_s``: :data:`MIN_DURATION_S` - :data:`MAX_DURATION_S` (as in a scenario file);
    else ConfigError. ``array``: the robot's array (a preset name or YAML path, checked as a
    scenario file's ``robot.array``; default the default scenario's), the same scene
    otherwise -- e.g. ``"mask2-asym"`` for the thesis's masked pair on the same seeds."""
    seed = whole_number("random_scenario seed", seed, 0, MAX_SEED)
    duration = finite_number("random_scenario duration_s", duration_s, MIN_DURATION_S,
                             MAX_DURATION_S)
    rng = np.random.default_rng(seed)
    base = default_scenario()
    room = np.array([rng.uniform(6, 9), rng.uniform(5, 8), rng.uniform(2.6, 3.2)])
    robot_xy = room[:2] / 2 + rng.uniform(-0.4, 0.4, 2)

    def inside(p: np.ndarray) -> bool:
        margin = WALL_CLEARANCE_M + 0.2
        return bool(np.all(p > margin) and np.all(p < room[:2] - margin))

    def free_point(rmin: float, rmax: float, taken: list[np.ndarray],
                   gen: np.random.Generator = rng, path: np.ndarray | None = None) -> np.ndarray:
        # (``path``: also 0.9 m from the speaker's whole walk)
        for _ in range(1000):
            az = gen.uniform(-np.pi, np.pi)
            r = gen.uniform(rmin, rmax)
            p = robot_xy + r * np.array([np.cos(az), np.sin(az)])
            if (inside(p) and all(np.linalg.norm(p - q) > 0.9 for q in taken)
                    and (path is None or _path_distance(path, p) > 0.9)):
                return p
        raise ConfigError(f"random scenario {seed}: could not place an object")

    def walk(start: np.ndarray, length: float) -> np.ndarray | None:
        for _ in range(1000):
            heading = rng.uniform(-np.pi, np.pi)
            end = start + length * np.array([np.cos(heading), np.sin(heading)])
            if (inside(end) and 1.2 < np.linalg.norm(end - robot_xy) < 4.0
                    and _path_distance(np.stack([start, end]), robot_xy) >= ROBOT_CLEARANCE_M):
                return end
        return None

    for _ in range(20):  # another start and speed when no direction fits
        start = free_point(1.5, 3.5, [])
        end = walk(start, rng.uniform(0.2, 0.8) * duration)
        if end is not None:
            path = np.stack([start, end])
            break
    else:
        # no straight walk of that length fits the room (long runs): back and forth along a
        # shorter line, n legs at the same speed (the speaker stood still here: all of 300
        # seeds at 60 s, found by an audit)
        speed, path = rng.uniform(0.2, 0.8), None
        for legs in range(2, 400):
            start = free_point(1.5, 3.5, [])
            end = walk(start, speed * duration / legs)
            if end is not None:
                path = np.stack([end if k % 2 else start for k in range(legs + 1)])
                break
        if path is None:
            raise ConfigError(f"random scenario {seed}: could not place the speaker's walk")
        start, end = path[0], path[1]
    taken = [start, end, (start + end) / 2]
    objects = []
    for _ in range(int(rng.integers(0, 3))):
        kind = str(rng.choice(OBJECT_KINDS))
        pos = free_point(1.2, 4.0, taken)
        taken.append(pos)
        objects.append(ObjectSpec(kind=kind, position_m=pos, yaw_deg=float(rng.uniform(-90, 90))))
    for k, o in enumerate(objects):
        # an object in the speaker's way (free_point keeps it from the walk's ends and middle
        # only; 16 of seeds 0-999 put one within MIN_BODY_SEPARATION_M of the walk, which the
        # parser refuses) is placed again, by a generator of its own: every other draw, and
        # every scenario whose objects were clear of the walk, stays what the seed gave
        if _path_distance(path, o.position_m) < MIN_BODY_SEPARATION_M:
            others = [q.position_m for q in objects if q is not o]
            objects[k] = replace(o, position_m=free_point(
                1.2, 4.0, [start, end, *others], np.random.default_rng([seed, k]), path))
    person = PersonSpec(name="speaker", path_m=path,
                        height_m=float(rng.uniform(1.55, 1.90)),
                        voice=str(rng.choice(VOICES)), speaking=((0.0, duration),))
    sc = replace(
        base, name=f"random-{seed}", seed=int(seed), duration_s=duration,
        snr_db=float(rng.uniform(10, 25)), room_size_m=room, rt60_s=float(rng.uniform(0.2, 0.5)),
        robot=replace(base.robot, position_m=robot_xy,
                      heading_deg=float(rng.uniform(-180, 180))),
        people=(person,), objects=tuple(objects),
    )
    if array is None:
        return sc
    d = sc.to_dict()
    d["robot"]["array"] = array  # (validated with the rest, as in a scenario file)
    return scenario_from_dict(d, where=f"random scenario {seed}")


def random_conversation(seed: int, duration_s: float = 10.0, array: str | None = None,
                        ) -> Scenario:
    """:func:`random_scenario` ``seed`` with a second talker: the two take turns of 1.5-3.5 s
    with 0.2-1 s pauses between them, the walking speaker first (from 0 s); the second
    stands 1.5-3.5 m from the robot, 40-150 deg to either side of where the first starts (so
    the head must turn to them), in a voice of either kind, at least 0.5 m from the walls
    and 0.9 m from the walk and the objects (as :func:`random_scenario` places its speaker
    and objects). Drawn by a generator of its own (``[seed, 4242]``), so the room, the walk
    and the objects are the seed's; a place that fails these or the scenario's checks is
    drawn again. Arguments as :func:`random_scenario`'s (``duration_s`` from
    :data:`MIN_DURATION_S`); ConfigError when no place fits. Not in the thesis: a test of
    the robot attending to whoever speaks (``talker_changes_followed`` of
    :func:`hearsee.robot.pipeline.run_scenario`'s summary)."""
    sc = random_scenario(seed, duration_s, array)
    rng = np.random.default_rng([int(seed), 4242])
    duration = sc.duration_s
    turns: list[list[tuple[float, float]]] = [[], []]
    t, who = 0.0, 0
    while t < duration - 0.2:  # (a last turn of at least 0.2 s)
        end = t + float(rng.uniform(1.5, 3.5))
        turns[who].append((round(t, 3), round(min(end, duration), 3)))
        t, who = end + float(rng.uniform(0.2, 1.0)), 1 - who
    robot = sc.robot.position_m
    start = sc.people[0].path_m[0]
    bearing = np.arctan2(start[1] - robot[1], start[0] - robot[0])
    voice = str(rng.choice(VOICES))
    height = float(rng.uniform(1.55, 1.90))
    d = sc.to_dict()
    d["name"] = f"conversation-{seed}"
    d["people"][0]["speaking"] = [list(s) for s in turns[0]]
    margin = WALL_CLEARANCE_M + 0.2  # (random_scenario's margin for where people start)
    for _ in range(500):
        a = bearing + np.radians(float(rng.choice([-1.0, 1.0]) * rng.uniform(40.0, 150.0)))
        xy = robot + float(rng.uniform(1.5, 3.5)) * np.array([np.cos(a), np.sin(a)])
        if (np.any(xy < margin) or np.any(xy > sc.room_size_m[:2] - margin)
                or _path_distance(sc.people[0].path_m, xy) < 0.9
                or any(np.linalg.norm(o.position_m - xy) < 0.9 for o in sc.objects)):
            continue  # (a person against a wall merged with it in the stereo: 2.4 m tall)
        d["people"] = [d["people"][0], {"name": "second talker", "path_m": [xy.tolist()],
                                        "height_m": height, "voice": voice,
                                        "speaking": [list(s) for s in turns[1]]}]
        try:
            return scenario_from_dict(d, where=f"random conversation {seed}")
        except ConfigError:
            continue
    raise ConfigError(f"random conversation {seed}: no place for the second talker")

