"""Synthetic indoor scenes for stereo + thermal human detection, with ground truth (thesis ch. 7).

A scene is a room (floor, walls, ceiling) with furniture boxes, radiators and warm appliances,
people as articulated 3D bodies (head, hair, neck, shoulders, torso, pelvis, upper arms,
forearms, hands, thighs, shins, feet -- all ellipsoids) and human-like objects: a *mannequin*
(the same body at room temperature), a *poster* (a flat, life-size printed cut-out of a person
on a stand) and a *coat on a stand* (pole, coat, sleeves and a hat). Every surface carries a
procedural texture fixed to the surface, so the left and right views are consistent and stereo
matching works.

Everything is rendered by a vectorised ray caster in numpy (analytic ray-ellipsoid, ray-box and
ray-plane intersections, each primitive only over the pixels of its projected bounding sphere)
into:

* a rectified stereo pair (default 640x480, f = 500 px, baseline 0.12 m) and the ground-truth
  disparity of the left view,
* a radiometric thermal image in degC from a separate, lower-resolution thermal camera
  (default 160x120, 72 deg HFOV, wider than the stereo pair's 65 deg so it sees all of
  its view; mild barrel distortion) mounted above the stereo rig, with its
  own extrinsics, optics blur, vignetting, fixed-pattern and temporal noise, and an 8-bit
  automatic-gain-controlled (non-radiometric) version of it,
* person and object boxes (left-image pixels, from the visible pixels) and 3D positions.

Frames: every 3D coordinate is in the **left camera's optical frame** (x right, y down,
z forward, metres). The camera looks level at ``camera_height_m`` above the floor, so a point
``h`` metres above the floor has ``y = camera_height_m - h``. An object's ``position_m`` is its
torso centre (people, mannequins, coats; for posters the printed figure's torso,
:data:`hearsee.vision.humans.TORSO_HEIGHT_FRACTION` of its height above the floor, like a
person's).

Everything is deterministic from the seed. The renderer is simple on purpose (Lambertian
shading from one directional light, one ray per pixel, no shadows or inter-reflections); it is
a test bed for the geometry of ch. 7, not a photo-realistic simulator.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from hearsee.config import (
    as_path,
    finite_number,
    is_real,
    real_entries,
    true_or_false,
    whole_number,
)
from hearsee.errors import ConfigError, GeometryError, ImageInputError, InputFileError
from hearsee.vision.camera import Camera, StereoRig, save_rig
from hearsee.vision.humans import TORSO_HEIGHT_FRACTION

__all__ = [
    "HUMAN_LIKE_KINDS",
    "Entity",
    "Scene",
    "SceneObject",
    "SceneSpec",
    "default_rig",
    "generate_scene",
    "pitched_view",
    "random_spec",
    "render_scene",
    "thermal_to_8bit",
    "view_pitch_deg",
    "write_scene",
]

#: Kinds of human-shaped objects that are not people.
HUMAN_LIKE_KINDS = ("mannequin", "poster", "coat_stand")
_ENTITY_KINDS = ("person", *HUMAN_LIKE_KINDS, "box", "radiator", "appliance")
#: A poster (a flat cut-out facing the room roughly) is turned by this fraction of its
#: entity's ``yaw_deg``; its ground truth reports the turn it is rendered at.
_POSTER_YAW_FRACTION = 0.3
#: Entity.params the renderer reads as numbers: key -> (lower bound, bound excluded); degC
#: temperatures are above absolute zero, sizes (metres) and a body's build factor > 0.
_NUMERIC_PARAMS: dict[str, tuple[float | None, bool]] = {
    **{k: (-273.15, True) for k in ("temp_c", "skin_c", "clothing_c", "legs_c", "hair_c")},
    "build": (0.0, True), "width_m": (0.0, True), "depth_m": (0.0, True),
    "lift_m": (0.0, False), "arm_swing_deg": (None, False)}
#: Entity.params the renderer reads as flags (True / False).
_FLAG_PARAMS = ("covered_head", "short_sleeves")
#: The Entity.params each kind's renderer reads (any other key is a ConfigError: a person's
#: ``temp_c`` or a box's ``width`` was ignored silently and the scene rendered with defaults).
_KIND_PARAMS: dict[str, tuple[str, ...]] = {
    "person": ("build", "skin_c", "clothing_c", "legs_c", "hair_c", "covered_head",
               "short_sleeves", "arm_swing_deg"),
    "mannequin": ("build", "temp_c", "covered_head", "arm_swing_deg"),
    "poster": ("temp_c",), "coat_stand": ("temp_c",),
    **{k: ("width_m", "depth_m", "lift_m", "temp_c") for k in ("box", "radiator", "appliance")}}


# ---------------------------------------------------------------------------------------------
# Rig
# ---------------------------------------------------------------------------------------------
def default_rig(width: int = 640, height: int = 480, *, focal_px: float | None = None,
                baseline_m: float = 0.12, thermal_size: tuple[int, int] = (160, 120),
                thermal_hfov_deg: float = 72.0, camera_height_m: float = 1.4) -> StereoRig:
    """The simulated rig: a rectified stereo pair plus a thermal camera.

    ``focal_px`` defaults to ``500 * width / 640`` (f = 500 px at 640x480). The thermal camera
    (``thermal_size`` pixels, ``thermal_hfov_deg`` degrees, k1 = -0.05) sits 6 cm right of and
    7 cm above the left camera, turned by a fraction of a degree, like a camera bolted on top of
    the rig. ``camera_height_m`` (height of the left camera above the floor, metres, finite
    and > 0; else a ConfigError) is stored in ``rig.info`` so detectors can use it as a prior
    (:func:`render_scene` returns the rig with the height it rendered at).

    Sizes are whole numbers of pixels >= 1, ``focal_px`` (pixels) finite and > 0,
    ``thermal_hfov_deg`` in (0, 180) degrees; else a ConfigError naming the argument (text
    for a size was a builtin TypeError, a 1-tuple thermal size a ValueError, a 180 deg
    thermal view a focal length of 5e-15 px). A bad ``baseline_m`` is StereoRig's
    CalibrationError.
    """
    # (NaN or -1 was stored, and the calib.yaml of write_scene was refused by load_rig)
    height_m = finite_number("camera_height_m", camera_height_m, 0.0, lo_open=True)
    width, height = whole_number("width", width), whole_number("height", height)
    tw, th = _pixel_size("thermal_size", thermal_size)
    hfov_t = finite_number("thermal_hfov_deg", thermal_hfov_deg, 0.0, lo_open=True)
    if not hfov_t < 180.0:
        raise ConfigError(f"thermal_hfov_deg must be in (0, 180) degrees, got "
                          f"{thermal_hfov_deg!r}")
    f = 500.0 * width / 640.0 if focal_px is None else \
        finite_number("focal_px", focal_px, 0.0, lo_open=True)
    K = np.array([[f, 0, (width - 1) / 2.0], [0, f, (height - 1) / 2.0], [0, 0, 1.0]])
    cam = Camera(K=K, width=width, height=height, name="left")
    tf = (tw / 2.0) / np.tan(np.radians(hfov_t) / 2.0)
    Kt = np.array([[tf, 0, (tw - 1) / 2.0], [0, tf, (th - 1) / 2.0], [0, 0, 1.0]])
    thermal = Camera(K=Kt, dist=np.array([-0.05, 0.0, 0.0, 0.0]), width=tw, height=th,
                     name="thermal")
    R_t = cv2.Rodrigues(np.array([0.006, -0.004, 0.002]))[0]
    rig = StereoRig.ideal(cam, baseline_m, thermal=thermal, thermal_offset_m=(0.06, -0.07, 0.0),
                          thermal_rotation=R_t)
    return StereoRig(rig.left, rig.right, rig.R, rig.T, rig.thermal, rig.R_thermal,
                     rig.T_thermal, None, {"camera_height_m": height_m,
                                           "source": "hearsee.sim.scenes"})


def _pixel_size(name: str, size: Any) -> tuple[int, int]:
    """``size`` as (width, height) whole numbers of pixels >= 1, else a ConfigError naming
    ``name``."""
    if not isinstance(size, tuple | list | np.ndarray) or len(size) != 2:
        raise ConfigError(f"{name} must be (width, height) in pixels, got {size!r:.60}")
    return whole_number(f"{name}[0]", size[0]), whole_number(f"{name}[1]", size[1])


def _rig_as_rendered(rig: StereoRig, camera_height_m: float,
                   R_view: NDArray | None = None) -> StereoRig:
    """``rig`` with ``info["camera_height_m"]`` = ``camera_height_m`` (metres above the floor;
    the rest of its info kept) and, given the left camera's orientation ``R_view`` (scene frame,
    y down, into the optical frame), ``info["camera_pitch_deg"]`` = its optical axis's pitch
    above the horizontal (degrees, + = looking up; :func:`view_pitch_deg`), dropped when the
    view rolls the camera or pitches it beyond what that field can hold."""
    info = {**rig.info, "camera_height_m": float(camera_height_m)}
    if R_view is not None:
        pitch = view_pitch_deg(R_view)
        if pitch is None:
            info.pop("camera_pitch_deg", None)
        else:
            info["camera_pitch_deg"] = pitch
    return StereoRig(rig.left, rig.right, rig.R, rig.T, rig.thermal, rig.R_thermal,
                     rig.T_thermal, rig.rms_px, info)


def view_pitch_deg(R: ArrayLike) -> float | None:
    """The pitch (degrees above the horizontal, + = looking up) of a camera whose rotation
    ``R`` takes scene-frame vectors (x right, y down, z forward) into its optical frame -- the
    ``camera_pitch_deg`` of :func:`render_scene`'s rig info. None when the camera is rolled
    (its x axis leaves the horizontal plane by more than 1e-6, which a pitch alone cannot
    describe) or pitched beyond :data:`hearsee.vision.humans.MAX_CAMERA_PITCH_DEG`.

    >>> view_pitch_deg(pitched_view(15.0)[0])
    15.0
    """
    from hearsee.vision.humans import MAX_CAMERA_PITCH_DEG

    R = np.asarray(R, dtype=float)
    if abs(R[0, 1]) > 1e-6:  # the optical x axis in the scene frame is R's first row
        return None
    pitch = float(np.degrees(np.arcsin(np.clip(-R[2, 1], -1.0, 1.0))))  # axis: the third row
    return round(pitch, 9) + 0.0 if abs(pitch) <= MAX_CAMERA_PITCH_DEG else None  # (no -0.0)


# ---------------------------------------------------------------------------------------------
# Scene description
# ---------------------------------------------------------------------------------------------
@dataclass
class Entity:
    """One thing in the room, standing on the floor.

    ``x`` (lateral, + right) and ``z`` (forward) place it in the left camera frame (metres);
    ``yaw_deg`` turns it about the vertical (0 = facing the camera, 90 = side, 180 = back);
    ``height_m`` is its height. ``params`` holds kind-specific options: temperatures in degC
    (``temp_c``; for people ``skin_c``, ``clothing_c``, ``legs_c``, ``hair_c``), sizes in
    metres (``width_m``, ``depth_m`` > 0, ``lift_m`` >= 0), a body's ``build`` factor (> 0)
    and ``arm_swing_deg``, and the flags ``covered_head``, ``short_sleeves`` (True / False);
    a bad one, or one the kind does not use (:data:`_KIND_PARAMS`), is a ConfigError naming
    its key.
    """

    kind: str
    x: float
    z: float
    yaw_deg: float = 0.0
    height_m: float = 1.75
    params: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        _check_entity(self)


def _check_entity(e: Entity) -> None:
    """ConfigError unless ``e``'s kind is known, its placement finite, its height > 0 and its
    params valid for its kind (:func:`_check_params`, :data:`_KIND_PARAMS`). Run when an
    Entity is made and again by render_scene (its fields and params dict can be edited)."""
    if e.kind not in _ENTITY_KINDS:
        raise ConfigError(f"entity kind must be one of {_ENTITY_KINDS}, got {e.kind!r}")
    for name in ("x", "z", "yaw_deg"):
        finite_number(f"entity {name}", getattr(e, name))
    finite_number("entity height_m", e.height_m, 0.0, lo_open=True)
    _check_params(e.params)
    unused = sorted(set(e.params) - set(_KIND_PARAMS[e.kind]), key=str)
    if unused:
        raise ConfigError(f"entity params {unused!r:.80} are not options of a {e.kind} (it "
                          f"reads {', '.join(_KIND_PARAMS[e.kind])})")


def _check_params(params: Any) -> None:
    """ConfigError naming the key unless ``params`` is a mapping whose numeric options
    (:data:`_NUMERIC_PARAMS`) are finite numbers within their bounds and whose flags
    (:data:`_FLAG_PARAMS`) are True or False: a build of 0 rendered NaN bodies, a negative box
    width an inside-out box, text a builtin ValueError, a NaN temperature a NaN thermal image,
    and "no" for a flag read as True. (Keys the entity's kind does not read: Entity's check.)"""
    if not isinstance(params, Mapping):
        raise ConfigError(f"entity params must be a mapping of options, got {params!r:.60}")
    for key, value in params.items():
        if key in _NUMERIC_PARAMS:
            lo, lo_open = _NUMERIC_PARAMS[key]
            finite_number(f"entity params[{key!r}]", value, lo, lo_open=lo_open)
        elif key in _FLAG_PARAMS:
            true_or_false(f"entity params[{key!r}]", value)


@dataclass
class SceneSpec:
    """A room (metres; the camera is at x = 0, z = 0) and the entities in it.

    The room spans ``x in [-width_left_m, width_right_m]``, ``z in [-back_m, depth_m]`` and the
    ceiling is ``ceiling_m`` above the floor. ``room_c`` is the air/wall temperature (degC).
    """

    entities: list[Entity] = field(default_factory=list)
    width_left_m: float = 4.0
    width_right_m: float = 4.0
    depth_m: float = 10.0
    back_m: float = 0.5
    ceiling_m: float = 2.8
    room_c: float = 21.5
    camera_height_m: float = 1.4
    seed: int = 0


@dataclass
class SceneObject:
    """Ground truth of one entity.

    ``box`` is ``[x, y, w, h]`` of its visible pixels in the left image (None when not visible);
    ``position_m`` its reference point in the left optical frame (metres; torso centre for
    bodies); ``visible_fraction`` = visible pixels / pixels it would cover unoccluded in the
    left image; ``truncated`` = it touches the image border; ``yaw_deg`` the turn it is
    rendered at (degrees about the vertical, 0 = facing the camera; for a poster a fraction of
    its entity's ``yaw_deg``).
    """

    index: int
    kind: str
    position_m: NDArray
    box: list[int] | None
    visible_fraction: float
    truncated: bool
    yaw_deg: float
    height_m: float
    pixels: int

    @property
    def distance_m(self) -> float:
        """Euclidean distance from the left camera to ``position_m``, metres."""
        return float(np.linalg.norm(self.position_m))

    @property
    def human_like(self) -> bool:
        return self.kind in HUMAN_LIKE_KINDS

    def to_dict(self) -> dict[str, Any]:
        return {"index": self.index, "kind": self.kind,
                "position_m": [round(float(v), 4) for v in self.position_m],
                "distance_m": round(self.distance_m, 4), "box": self.box,
                "visible_fraction": round(float(self.visible_fraction), 4),
                "truncated": bool(self.truncated), "yaw_deg": float(self.yaw_deg),
                "height_m": float(self.height_m), "pixels": int(self.pixels)}


@dataclass
class Scene:
    """A rendered scene: images, ground truth and the rig that saw it.

    ``left``/``right``: (H, W, 3) uint8 BGR rectified pair; ``disparity``: (H, W) float32
    ground-truth disparity of the left view, pixels; ``labels``: (H, W) int16 entity index per
    left pixel (-1 = room); ``thermal_c``: (h, w) float32 radiometric thermal image, degC;
    ``thermal_8bit``: the same with automatic gain control, uint8; ``rig``: the rig with
    ``info["camera_height_m"]`` the height (metres above the floor) of the left camera that
    rendered the scene; ``camera_height_m``: that height (None: ``spec.camera_height_m``).
    """

    left: NDArray
    right: NDArray
    disparity: NDArray
    labels: NDArray
    thermal_c: NDArray
    thermal_8bit: NDArray
    rig: StereoRig
    objects: list[SceneObject]
    spec: SceneSpec
    camera_height_m: float | None = None

    @property
    def people(self) -> list[SceneObject]:
        return [o for o in self.objects if o.kind == "person"]

    @property
    def human_like(self) -> list[SceneObject]:
        return [o for o in self.objects if o.human_like]

    def truth(self) -> dict[str, Any]:
        """The ground truth as a JSON-able dict (what ``truth.json`` holds)."""
        return {
            "frame": "left camera optical frame (x right, y down, z forward), metres",
            "seed": self.spec.seed,
            "camera_height_m": (self.spec.camera_height_m if self.camera_height_m is None
                                else self.camera_height_m),
            "room_c": self.spec.room_c,
            "people": [o.to_dict() for o in self.people],
            "objects": [o.to_dict() for o in self.objects if o.kind != "person"],
        }


# ---------------------------------------------------------------------------------------------
# Materials and primitives
# ---------------------------------------------------------------------------------------------
@dataclass
class _Material:
    color: NDArray  # BGR in [0, 1]
    contrast: float  # texture contrast
    temp_c: float
    temp_var_c: float = 0.3  # spatial temperature variation (texture-driven)
    fine: float = 0.5  # weight of the fine texture near the camera


class _Builder:
    """Collects primitives: ellipsoids, boxes and cut-out planes, each with material and owner."""

    def __init__(self) -> None:
        self.materials: list[_Material] = []
        self.ellipsoids: list[tuple[NDArray, NDArray, NDArray, int, int]] = []
        self.boxes: list[tuple[NDArray, NDArray, int, int]] = []
        self.cutouts: list[tuple[NDArray, NDArray, NDArray, NDArray, NDArray, int, int]] = []

    def material(self, color: Any, contrast: float, temp_c: float, temp_var_c: float = 0.3,
                 fine: float = 0.5) -> int:
        self.materials.append(_Material(np.asarray(color, float), contrast, temp_c, temp_var_c,
                                        fine))
        return len(self.materials) - 1

    def ellipsoid(self, center: Any, radii: Any, rot: NDArray, mat: int, owner: int) -> None:
        self.ellipsoids.append((np.asarray(center, float), np.asarray(radii, float), rot, mat,
                                owner))

    def box(self, lo: Any, hi: Any, mat: int, owner: int) -> None:
        self.boxes.append((np.asarray(lo, float), np.asarray(hi, float), mat, owner))


def _rot_y(yaw_deg: float) -> NDArray:
    """Rotation about the optical y axis (vertical), degrees."""
    a = np.radians(yaw_deg)
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _body_parts(height: float, build: float) -> list[tuple[str, tuple, tuple]]:
    """Body parts as (part, centre (lateral, height above floor, forward), radii (x, y, z)) in
    the body's local frame (forward = towards the viewer when yaw = 0)."""
    H, w = height, build
    parts = [
        ("head", (0.0, H - 0.115, 0.0), (0.078, 0.115, 0.095)),
        ("hair", (0.0, H - 0.085, -0.02), (0.082, 0.09, 0.095)),
        ("neck", (0.0, H - 0.25, 0.0), (0.052, 0.07, 0.05)),
        ("shoulders", (0.0, 0.815 * H, 0.0), (0.205 * w, 0.055, 0.1)),
        ("torso", (0.0, TORSO_HEIGHT_FRACTION * H, 0.0), (0.17 * w, 0.17 * H, 0.11)),
        ("pelvis", (0.0, 0.515 * H, 0.0), (0.16 * w, 0.09 * H, 0.11)),
    ]
    for sgn in (-1.0, 1.0):
        parts += [
            ("upper_arm", (sgn * 0.215 * w, 0.7 * H, 0.0), (0.05, 0.095 * H, 0.055)),
            ("forearm", (sgn * 0.235 * w, 0.52 * H, 0.01), (0.043, 0.085 * H, 0.045)),
            ("hand", (sgn * 0.24 * w, 0.405 * H, 0.02), (0.035, 0.048, 0.028)),
            ("thigh", (sgn * 0.085 * w, 0.375 * H, 0.0), (0.075, 0.115 * H, 0.08)),
            ("shin", (sgn * 0.085 * w, 0.15 * H, -0.01), (0.055, 0.12 * H, 0.06)),
            ("foot", (sgn * 0.085 * w, 0.03, 0.05), (0.05, 0.035, 0.12)),
        ]
    return parts


_SKIN = ("head", "neck", "hand")


def _add_body(b: _Builder, e: Entity, owner: int, cam_h: float, rng: np.random.Generator,
              room_c: float, mannequin: bool) -> NDArray:
    """Add a person or mannequin; returns its torso centre (left frame)."""
    p = e.params
    build = float(p.get("build", rng.uniform(0.9, 1.1)))
    R = _rot_y(e.yaw_deg)
    base = np.array([e.x, cam_h, e.z])
    if mannequin:
        t_skin = t_cloth = t_legs = t_hair = float(p.get("temp_c", room_c + rng.uniform(-0.4, 0.4)))
        skin_col = np.array([0.75, 0.8, 0.85]) * rng.uniform(0.8, 1.0)
    else:
        t_skin = float(p.get("skin_c", rng.uniform(33.0, 35.0)))
        t_cloth = float(p.get("clothing_c", rng.uniform(28.5, 31.0)))
        t_legs = float(p.get("legs_c", t_cloth - rng.uniform(0.5, 2.0)))
        t_hair = float(p.get("hair_c", t_skin - rng.uniform(2.0, 4.0)))
        skin_col = np.array([0.55, 0.65, 0.85]) * rng.uniform(0.5, 1.0)
    m_skin = b.material(skin_col, 0.25, t_skin, 0.4, fine=0.8)
    m_hair = b.material(rng.uniform(0.05, 0.4, 3), 0.4, t_hair, 0.5)
    m_shirt = b.material(rng.uniform(0.15, 0.95, 3), rng.uniform(0.35, 0.6), t_cloth, 0.6)
    m_legs = b.material(rng.uniform(0.1, 0.6, 3), rng.uniform(0.35, 0.6), t_legs, 0.5)
    m_shoe = b.material(rng.uniform(0.05, 0.3, 3), 0.3, t_legs - 3.0 if not mannequin else t_legs,
                        0.3)
    covered = bool(p.get("covered_head", False))
    m_head = b.material(rng.uniform(0.1, 0.5, 3), 0.5, t_cloth, 0.4) if covered else m_skin
    short_sleeves = (not mannequin) and bool(p.get("short_sleeves", rng.random() < 0.3))
    mats = {"head": m_head, "hair": m_head if covered else m_hair, "neck": m_head,
            "shoulders": m_shirt, "torso": m_shirt, "upper_arm": m_shirt,
            "forearm": m_skin if short_sleeves else m_shirt, "hand": m_skin, "pelvis": m_legs,
            "thigh": m_legs, "shin": m_legs, "foot": m_shoe}
    swing = float(p.get("arm_swing_deg", rng.uniform(-12, 12)))
    torso = None
    for part, c, r in _body_parts(e.height_m, build):
        c = np.array(c, float)
        rot = R
        if part in ("upper_arm", "forearm", "hand"):  # small arm swing about the shoulder
            a = np.radians(swing * np.sign(c[0]))
            sh = np.array([c[0], 0.8 * e.height_m, 0.0])
            d = c - sh
            c = sh + np.array([d[0], d[1] * np.cos(a), -d[1] * np.sin(a)])
            ca, sa = np.cos(a), np.sin(a)
            rot = R @ np.array([[1, 0, 0], [0, ca, sa], [0, -sa, ca]])
        world = base + R @ np.array([c[0], -c[1], -c[2]])  # local forward -> towards camera
        b.ellipsoid(world, r, rot, mats[part], owner)
        if part == "torso":
            torso = world
    assert torso is not None
    return torso


@lru_cache(maxsize=4)
def _cutout_print(height: float, seed: int) -> tuple[NDArray, NDArray]:
    """A printed person (front view) on a 1 cm grid: (mask (h, w) bool, colour (h, w, 3))."""
    rng = np.random.default_rng(seed)
    res = 0.01
    W, Hn = int(0.7 / res), int(height / res) + 2
    xs = (np.arange(W) - (W - 1) / 2) * res
    hs = (Hn - 1 - np.arange(Hn)) * res
    X, Hh = np.meshgrid(xs, hs)
    mask = np.zeros((Hn, W), bool)
    col = np.zeros((Hn, W, 3))
    palette = {"head": [0.5, 0.6, 0.8], "hair": rng.uniform(0.05, 0.3, 3),
               "shirt": rng.uniform(0.2, 0.9, 3), "legs": rng.uniform(0.1, 0.5, 3)}
    for part, c, r in _body_parts(height, 1.0):
        inside = ((X - c[0]) / r[0]) ** 2 + ((Hh - c[1]) / r[1]) ** 2 <= 1.0
        key = ("head" if part in _SKIN else "hair" if part == "hair" else
               "shirt" if part in ("shoulders", "torso", "upper_arm", "forearm") else "legs")
        col[inside & ~mask] = palette[key]  # earlier parts stay in front (face before hair)
        mask |= inside
    return mask, col


def _rendered_yaw_deg(e: Entity) -> float:
    """The turn (degrees about the vertical, 0 = facing the camera) ``e`` is rendered at:
    its ``yaw_deg``, a fraction of it for a poster (:data:`_POSTER_YAW_FRACTION`)."""
    return e.yaw_deg * _POSTER_YAW_FRACTION if e.kind == "poster" else e.yaw_deg


def _add_entity(b: _Builder, e: Entity, owner: int, spec: SceneSpec,
                rng: np.random.Generator) -> NDArray:
    """Add an entity's primitives; returns its reference position (left frame)."""
    cam_h, room = spec.camera_height_m, spec.room_c
    p = e.params
    if e.kind == "person":
        return _add_body(b, e, owner, cam_h, rng, room, mannequin=False)
    if e.kind == "mannequin":
        return _add_body(b, e, owner, cam_h, rng, room, mannequin=True)
    if e.kind == "poster":
        mask, col = _cutout_print(round(e.height_m, 2), int(rng.integers(1 << 30)))
        t = float(p.get("temp_c", room + rng.uniform(-0.3, 0.5)))
        m = b.material([1, 1, 1], 0.25, t, 0.2)
        R = _rot_y(_rendered_yaw_deg(e))  # a cut-out faces the room roughly
        center = np.array([e.x, cam_h - (mask.shape[0] - 1) * 0.005, e.z])
        b.cutouts.append((center, R[:, 0], np.array([0.0, 1.0, 0.0]), mask, col, m, owner))
        # a small stand at the back (invisible from the front mostly)
        m_st = b.material([0.3, 0.3, 0.3], 0.4, t, 0.2)
        foot = center + R[:, 2] * 0.15
        b.box(foot + [-0.15, cam_h - foot[1] - 0.05, -0.1], foot + [0.15, cam_h - foot[1], 0.1],
              m_st, owner)
        return np.array([e.x, cam_h - TORSO_HEIGHT_FRACTION * e.height_m, e.z])
    if e.kind == "coat_stand":
        t = float(p.get("temp_c", room + rng.uniform(-0.5, 0.3)))
        H = e.height_m
        m_pole = b.material([0.2, 0.25, 0.3], 0.3, t, 0.2)
        m_coat = b.material(rng.uniform(0.1, 0.6, 3), 0.5, t, 0.3)
        m_hat = b.material(rng.uniform(0.1, 0.5, 3), 0.5, t, 0.3)
        R = _rot_y(e.yaw_deg)
        base = np.array([e.x, cam_h, e.z])
        b.box(base + [-0.02, -H + 0.05, -0.02], base + [0.02, 0.0, 0.02], m_pole, owner)
        b.ellipsoid(base + [0, -0.02, 0], (0.22, 0.02, 0.22), np.eye(3), m_pole, owner)
        parts = [((0, H - 0.12, 0), (0.11, 0.09, 0.12), m_hat),
                 ((0, 0.84 * H, 0), (0.2, 0.05, 0.09), m_coat),
                 ((0, 0.64 * H, 0.02), (0.19, 0.21 * H, 0.1), m_coat),
                 ((-0.2, 0.66 * H, 0.0), (0.05, 0.17 * H, 0.05), m_coat),
                 ((0.2, 0.66 * H, 0.0), (0.05, 0.17 * H, 0.05), m_coat)]
        for c, r, m in parts:
            b.ellipsoid(base + R @ np.array([c[0], -c[1], -c[2]]), r, R, m, owner)
        return base + np.array([0.0, -0.64 * H, 0.0])
    if e.kind in ("box", "radiator", "appliance"):
        w = float(p.get("width_m", 0.8))
        d = float(p.get("depth_m", 0.5))
        lift = float(p.get("lift_m", 0.0))
        if e.kind == "radiator":
            t, col, con = float(p.get("temp_c", rng.uniform(45, 60))), [0.85, 0.85, 0.85], 0.2
        elif e.kind == "appliance":
            t, col, con = float(p.get("temp_c", rng.uniform(34, 42))), [0.15, 0.15, 0.15], 0.3
        else:
            t = float(p.get("temp_c", room + rng.uniform(-0.8, 0.8)))
            col, con = rng.uniform(0.2, 0.9, 3), rng.uniform(0.4, 0.7)
        m = b.material(col, con, t, 0.3)
        lo = np.array([e.x - w / 2, cam_h - lift - e.height_m, e.z - d / 2])
        hi = np.array([e.x + w / 2, cam_h - lift, e.z + d / 2])
        b.box(lo, hi, m, owner)
        return (lo + hi) / 2
    raise ConfigError(f"unknown entity kind {e.kind!r}")  # pragma: no cover


# ---------------------------------------------------------------------------------------------
# Textures
# ---------------------------------------------------------------------------------------------
_TEX_N = 512


@lru_cache(maxsize=1)
def _textures() -> tuple[NDArray, NDArray]:
    """Two wrap-around noise textures (float32, zero mean, unit-ish std): coarse (features of
    2-20 cm at 1 cm/texel) and fine (features of ~1 cm at 0.25 cm/texel)."""
    rng = np.random.default_rng(12345)

    def band(sigma: float) -> NDArray:
        z = rng.standard_normal((_TEX_N, _TEX_N)).astype(np.float32)
        z = ndimage.gaussian_filter(z, sigma, mode="wrap")
        return z / z.std()

    coarse = 0.6 * band(1.5) + 0.6 * band(4.0) + 0.5 * band(12.0)
    blobs = np.tanh(2.0 * band(6.0))  # blob-like patches
    coarse = (coarse + 0.6 * blobs) / np.std(coarse + 0.6 * blobs)
    fine = band(1.2)
    return coarse.astype(np.float32), fine.astype(np.float32)


def _sample(tex: NDArray, u: NDArray, v: NDArray) -> NDArray:
    mu = np.mod(u.astype(np.float32), np.float32(_TEX_N))
    mv = np.mod(v.astype(np.float32), np.float32(_TEX_N))
    shape = mu.shape
    n = mu.size
    cols = 1024
    pad = (-n) % cols
    mu = np.pad(mu.ravel(), (0, pad)).reshape(-1, cols)
    mv = np.pad(mv.ravel(), (0, pad)).reshape(-1, cols)
    out = cv2.remap(tex, mu, mv, cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)
    return out.ravel()[:n].reshape(shape)


def _triplanar(P: NDArray, N: NDArray, texel_m: float, tex: NDArray, offset: NDArray) -> NDArray:
    """Texture value at surface points ``P`` (H, W, 3) with normals ``N`` (blend of the three
    axis-aligned projections, weighted by the normal's components)."""
    w = np.square(np.square(N.astype(np.float32)))
    w /= w.sum(axis=-1, keepdims=True) + np.float32(1e-12)
    q = P.astype(np.float32) * np.float32(1.0 / texel_m)
    out = w[..., 0] * _sample(tex, q[..., 2], q[..., 1])
    out += w[..., 1] * _sample(tex, q[..., 0], q[..., 2])
    out += w[..., 2] * _sample(tex, q[..., 0], q[..., 1])
    return out


# ---------------------------------------------------------------------------------------------
# Ray casting
# ---------------------------------------------------------------------------------------------
@dataclass
class _Hits:
    t: NDArray  # (H, W) ray parameter (distance along unit ray), inf = none
    normal: NDArray  # (H, W, 3)
    mat: NDArray  # (H, W) material index
    owner: NDArray  # (H, W) entity index (-1 room)
    print_col: NDArray  # (H, W, 3) print colour for cut-outs (nan elsewhere)
    raw: dict[int, NDArray]  # entity -> (H, W) bool hit regardless of occlusion


def _camera_rays(cam: Camera) -> NDArray:
    """Unit rays (H*W, 3) float32 of every pixel of ``cam`` (cached per camera)."""
    key = (cam.width, cam.height, cam.K.tobytes(), cam.dist.tobytes())
    rays = _RAY_CACHE.get(key)
    if rays is None:
        uu, vv = np.meshgrid(np.arange(cam.width, dtype=float), np.arange(cam.height, dtype=float))
        rays = cam.pixel_rays(np.stack([uu.ravel(), vv.ravel()], axis=1)).astype(np.float32)
        if len(_RAY_CACHE) > 8:
            _RAY_CACHE.clear()
        _RAY_CACHE[key] = rays
    return rays


_RAY_CACHE: dict[tuple, NDArray] = {}


def _pixel_box(cam: Camera, R: NDArray, C: NDArray, center: NDArray, radius: float
               ) -> tuple[int, int, int, int] | None:
    """Conservative pixel box (u0, u1, v0, v1) of a bounding sphere seen by camera (R, C)."""
    pc = R @ (center - C)
    if pc[2] + radius <= 0.0:
        return None
    if pc[2] - radius <= 0.05:
        return 0, cam.width, 0, cam.height
    uv = cam.project(pc[None])[0]
    # angular radius -> pixels (with a margin for distortion)
    rad = 1.25 * max(cam.fx, cam.fy) * radius / np.sqrt(max(pc[2] ** 2 - radius ** 2, 1e-6))
    u0, u1 = int(np.floor(uv[0] - rad)), int(np.ceil(uv[0] + rad)) + 1
    v0, v1 = int(np.floor(uv[1] - rad)), int(np.ceil(uv[1] + rad)) + 1
    u0, v0 = max(u0, 0), max(v0, 0)
    u1, v1 = min(u1, cam.width), min(v1, cam.height)
    if u0 >= u1 or v0 >= v1:
        return None
    return u0, u1, v0, v1


def _cast(cam: Camera, R: NDArray, C: NDArray, b: _Builder, spec: SceneSpec,
          room_mats: tuple[int, int, int], track_raw: bool) -> tuple[_Hits, NDArray]:
    """Ray-cast the scene from a camera with rotation ``R`` (camera-from-left) and centre ``C``
    (left frame). Returns the hits and the unit rays (H, W, 3) in the left frame."""
    H, W = cam.height, cam.width
    D = (_camera_rays(cam) @ R.astype(np.float32)).reshape(H, W, 3)  # left frame (R^T d)
    # room interior: exit of the axis-aligned room box
    lo = np.array([-spec.width_left_m, spec.camera_height_m - spec.ceiling_m, -spec.back_m])
    hi = np.array([spec.width_right_m, spec.camera_height_m, spec.depth_m])
    tbest = np.full((H, W), np.inf, np.float32)
    axis = np.zeros((H, W), np.int8)
    pos = np.zeros((H, W), bool)
    for k in range(3):
        dk = D[..., k]
        with np.errstate(divide="ignore", invalid="ignore"):
            tk = np.where(dk > 0, np.float32(hi[k] - C[k]) / dk, np.float32(lo[k] - C[k]) / dk)
        tk[~(tk > 0)] = np.inf
        better = tk < tbest
        tbest = np.where(better, tk, tbest)
        axis[better] = k
        pos = np.where(better, dk > 0, pos)
    n = np.zeros((H, W, 3), np.float32)
    for k in range(3):
        n[..., k] = np.where(axis == k, np.where(pos, -1.0, 1.0), 0.0)
    hits = _Hits(t=tbest, normal=n, mat=np.zeros((H, W), np.int32),
                 owner=np.full((H, W), -1, np.int32),
                 print_col=np.full((H, W, 3), np.nan, np.float32), raw={})
    floor_m, wall_m, ceil_m = room_mats
    hits.mat = np.where(axis == 1, np.where(pos, floor_m, ceil_m), wall_m).astype(np.int32)

    def update(sl: tuple[slice, slice], t: NDArray, normal: NDArray, mat: int, owner: int,
               col: NDArray | None = None) -> None:
        hit = np.isfinite(t)
        if track_raw and owner >= 0 and np.any(hit):
            raw = hits.raw.setdefault(owner, np.zeros((H, W), bool))
            raw[sl] |= hit
        closer = hit & (t < hits.t[sl])
        if not np.any(closer):
            return
        hits.t[sl] = np.where(closer, t, hits.t[sl])
        hits.normal[sl] = np.where(closer[..., None], normal, hits.normal[sl])
        hits.mat[sl] = np.where(closer, mat, hits.mat[sl])
        hits.owner[sl] = np.where(closer, owner, hits.owner[sl])
        if col is not None:
            hits.print_col[sl] = np.where(closer[..., None], col, hits.print_col[sl])

    for center, radii, rot, mat, owner in b.ellipsoids:
        bb = _pixel_box(cam, R, C, center, float(radii.max()))
        if bb is None:
            continue
        u0, u1, v0, v1 = bb
        sl = (slice(v0, v1), slice(u0, u1))
        d = D[sl]
        Rl = (rot.T / radii[:, None]).astype(np.float32)  # world -> unit-sphere coordinates
        o = Rl @ (C - center).astype(np.float32)
        dl = d @ Rl.T
        a = np.einsum("...i,...i", dl, dl)
        bq = 2.0 * (dl @ o)
        cq = float(o @ o) - 1.0
        disc = bq * bq - 4 * a * cq
        ok = disc >= 0
        sq = np.sqrt(np.where(ok, disc, 0.0))
        t = (-bq - sq) / (2 * a)
        t = np.where(ok & (t > 1e-6), t, np.inf)
        pl = o + dl * np.where(np.isfinite(t), t, 0.0)[..., None]
        normal = (pl / radii.astype(np.float32)) @ rot.T.astype(np.float32)
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True) + 1e-12
        update(sl, t, normal, mat, owner)

    for blo, bhi, mat, owner in b.boxes:
        center = (blo + bhi) / 2
        bb = _pixel_box(cam, R, C, center, float(np.linalg.norm(bhi - blo) / 2))
        if bb is None:
            continue
        u0, u1, v0, v1 = bb
        sl = (slice(v0, v1), slice(u0, u1))
        d = D[sl]
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = (blo - C).astype(np.float32) / d
            t2 = (bhi - C).astype(np.float32) / d
        t1 = np.nan_to_num(t1, nan=-np.inf)
        t2 = np.nan_to_num(t2, nan=np.inf)
        tmin = np.minimum(t1, t2)
        tmax = np.maximum(t1, t2)
        ax = np.argmax(tmin, axis=-1)
        tn = np.take_along_axis(tmin, ax[..., None], -1)[..., 0]
        tf = tmax.min(axis=-1)
        t = np.where((tn <= tf) & (tn > 1e-6), tn, np.inf)
        sg = -np.sign(np.take_along_axis(d, ax[..., None], -1)[..., 0])
        normal = np.zeros(d.shape, np.float32)
        np.put_along_axis(normal, ax[..., None], sg[..., None], -1)
        update(sl, t, normal, mat, owner)

    for center, e1, e2, mask, col, mat, owner in b.cutouts:
        hgt, wid = mask.shape[0] * 0.01, mask.shape[1] * 0.01
        bb = _pixel_box(cam, R, C, center, float(np.hypot(hgt, wid) / 2))
        if bb is None:
            continue
        u0, u1, v0, v1 = bb
        sl = (slice(v0, v1), slice(u0, u1))
        d = D[sl]
        nrm = np.cross(e2, e1)  # faces -z (towards the camera) for e1 = +x, e2 = +y
        denom = d @ nrm
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((center - C) @ nrm) / denom
        t = np.where(np.isfinite(t) & (t > 1e-6), t, np.inf)
        P = C + d * np.where(np.isfinite(t), t, 0.0)[..., None]
        a = (P - center) @ e1 / 0.01 + (mask.shape[1] - 1) / 2
        bq = (P - center) @ e2 / 0.01 + (mask.shape[0] - 1) / 2
        ia, ib = np.rint(a).astype(int), np.rint(bq).astype(int)
        inside = (ia >= 0) & (ia < mask.shape[1]) & (ib >= 0) & (ib < mask.shape[0])
        ia, ib = np.clip(ia, 0, mask.shape[1] - 1), np.clip(ib, 0, mask.shape[0] - 1)
        inside &= mask[ib, ia]
        t = np.where(inside, t, np.inf)
        normal = np.where((denom > 0)[..., None], -nrm, nrm) * np.ones(d.shape)
        update(sl, t, normal, mat, owner, col[ib, ia])
    return hits, D


def _shade(hits: _Hits, D: NDArray, C: NDArray, b: _Builder, rng: np.random.Generator,
           tex_offsets: NDArray) -> NDArray:
    """Lambertian shading with surface-fixed textures -> BGR float image in [0, 1]."""
    coarse, fine = _textures()
    P = C.astype(np.float32) + D * hits.t[..., None]
    mats = b.materials
    color = np.array([m.color for m in mats], np.float32)[hits.mat]
    contrast = np.array([m.contrast for m in mats], np.float32)[hits.mat]
    fine_w = np.array([m.fine for m in mats], np.float32)[hits.mat]
    off = tex_offsets.astype(np.float32)[hits.mat]
    tc = _triplanar(P + off, hits.normal, 0.01, coarse, 0.0)
    dist = hits.t
    fw = fine_w * np.clip((3.0 - dist) / 2.0, 0.0, 1.0)
    texv = 1.0 + contrast * (0.45 * tc)
    near = fw > 0
    if np.any(near):
        tf = _triplanar((P + off)[near][None], hits.normal[near][None], 0.0025, fine, 0.0)[0]
        texv[near] += contrast[near] * 0.35 * fw[near] * tf
    has_print = np.isfinite(hits.print_col[..., 0])
    color = np.where(has_print[..., None], hits.print_col, color)
    light = np.array([0.35, -0.8, -0.5], np.float32)
    light /= np.linalg.norm(light)
    lam = 0.45 + 0.55 * np.clip(hits.normal @ light, 0.0, 1.0)
    img = color * (texv * lam)[..., None]
    return np.clip(img, 0.0, 1.0)


# ---------------------------------------------------------------------------------------------
# Thermal
# ---------------------------------------------------------------------------------------------
def thermal_to_8bit(thermal_c: NDArray, low_pct: float = 1.0, high_pct: float = 99.5) -> NDArray:
    """Automatic gain control: map the [low_pct, high_pct] percentiles of a radiometric image
    (degC) linearly to 0..255 (uint8), like a non-radiometric thermal camera's video output.
    ``0 <= low_pct < high_pct <= 100``."""
    lo_p = finite_number("low_pct", low_pct, 0.0, 100.0)
    hi_p = finite_number("high_pct", high_pct, 0.0, 100.0)
    if not lo_p < hi_p:
        raise ConfigError(f"low_pct must be below high_pct, got {low_pct} and {high_pct}")
    from hearsee.vision.io import numeric_map

    # (text or bools let numpy's TypeError escape; numbers of any dtype are mapped as before)
    thermal_c = numeric_map("thermal_to_8bit: the thermal image", thermal_c, None)
    if thermal_c.size == 0:
        raise ImageInputError("thermal_to_8bit: the thermal image is empty")
    if not np.all(np.isfinite(thermal_c)):
        raise ImageInputError("thermal_to_8bit: the thermal image must hold finite temperatures "
                              "(degC); it has NaN or inf pixels")
    lo, hi = np.percentile(thermal_c, [lo_p, hi_p])
    if hi - lo < 1e-6:
        hi = lo + 1.0
    return np.clip((thermal_c - lo) / (hi - lo) * 255.0 + 0.5, 0, 255).astype(np.uint8)


def _thermal_image(hits: _Hits, D: NDArray, C: NDArray, b: _Builder, cam: Camera,
                   rng: np.random.Generator, tex_offsets: NDArray,
                   column_fpn: NDArray | None = None) -> NDArray:
    """Radiometric thermal image (degC). ``rng`` draws the temporal noise (NETD, 0.08 degC)
    and, when ``column_fpn`` (a (1, w) column offset, degC) is None, first the column
    fixed-pattern noise (0.05 degC)."""
    coarse, _ = _textures()
    P = C.astype(np.float32) + D * hits.t[..., None]
    mats = b.materials
    temp = np.array([m.temp_c for m in mats])[hits.mat]
    var = np.array([m.temp_var_c for m in mats])[hits.mat]
    tc = _triplanar(P + tex_offsets[hits.mat], hits.normal, 0.02, coarse, 0.0)
    # surfaces seen at grazing angles radiate a bit less (emissivity falls off)
    cosang = np.abs(np.einsum("...i,...i", hits.normal, D))
    img = temp + var * tc - 0.6 * (1.0 - cosang) ** 2 * np.clip(temp - 20.0, 0, None) / 14.0
    img = cv2.GaussianBlur(img.astype(np.float32), (0, 0), 0.7)  # optics / detector PSF
    h, w = img.shape
    yy, xx = np.mgrid[0:h, 0:w]
    r2 = ((xx - cam.cx) / (w / 2)) ** 2 + ((yy - cam.cy) / (h / 2)) ** 2
    img = img - 1.2 * r2 / 2.0  # vignetting: corners read ~1.2 degC colder
    fpn = rng.normal(0, 0.05, (1, w)) if column_fpn is None else column_fpn
    img = img + fpn + rng.normal(0, 0.08, (h, w))  # column FPN + NETD
    return img.astype(np.float32)


# ---------------------------------------------------------------------------------------------
# Rendering
# ---------------------------------------------------------------------------------------------
def _check_room(spec: SceneSpec) -> None:
    """ConfigError unless ``spec`` is a SceneSpec whose room has finite positive extents
    around the camera (which must be inside it: between the floor and the ceiling) and a
    finite temperature, whose entities are a list of valid Entity and whose seed is a whole number
    >= 0 (numpy's generator raised a builtin ValueError for -1 and TypeError for 1.5);
    GeometryError for an entity standing outside the room or reaching above its ceiling."""
    if not isinstance(spec, SceneSpec):
        raise ConfigError(f"render_scene needs a SceneSpec, got {spec!r:.60}")
    if not isinstance(spec.entities, list) or \
            not all(isinstance(e, Entity) for e in spec.entities):
        raise ConfigError(f"scene entities must be a list of Entity, got "
                          f"{spec.entities!r:.60}")
    for e in spec.entities:  # (edited after construction: a params dict is mutable)
        _check_entity(e)
    whole_number("scene seed", spec.seed, 0)
    for name in ("width_left_m", "width_right_m", "depth_m", "ceiling_m"):
        finite_number(f"scene {name}", getattr(spec, name), 0.0, lo_open=True)
    finite_number("scene back_m", spec.back_m, 0.0)
    finite_number("scene room_c", spec.room_c)
    if not (is_real(spec.camera_height_m) and 0 < spec.camera_height_m < spec.ceiling_m):
        raise ConfigError(f"scene camera_height_m must be between the floor and the ceiling "
                          f"(0, {spec.ceiling_m:g}) m, got {spec.camera_height_m!r}")
    for k, e in enumerate(spec.entities):
        # (a person 10 m tall stood through the ceiling, one 20 m beside the room was rendered
        # in the wall's place -- reported invisible, with ground truth of neither)
        top = e.height_m + float(e.params.get("lift_m", 0.0))
        if not (-spec.width_left_m <= e.x <= spec.width_right_m
                and -spec.back_m <= e.z <= spec.depth_m):
            raise GeometryError(
                f"scene entity {k} ({e.kind}) stands at x = {e.x:g}, z = {e.z:g} m, outside "
                f"the room (x in [{-spec.width_left_m:g}, {spec.width_right_m:g}], z in "
                f"[{-spec.back_m:g}, {spec.depth_m:g}] m)")
        if top > spec.ceiling_m:
            raise GeometryError(f"scene entity {k} ({e.kind}) reaches {top:g} m, above the "
                                f"{spec.ceiling_m:g} m ceiling")


def _check_cameras_in_room(spec: SceneSpec, centres: dict[str, NDArray]) -> None:
    """GeometryError unless every camera centre (scene frame, metres; y down, the floor at
    ``y = camera_height_m``) lies in the room, its walls, floor and ceiling included: a camera
    outside saw the room's walls from behind (a picture of nothing with ground truth)."""
    lo = np.array([-spec.width_left_m, spec.camera_height_m - spec.ceiling_m, -spec.back_m])
    hi = np.array([spec.width_right_m, spec.camera_height_m, spec.depth_m])
    for name, c in centres.items():
        if not (np.all(c >= lo - 1e-9) and np.all(c <= hi + 1e-9)):
            raise GeometryError(
                f"render_scene: the {name} camera's centre {np.round(c, 3).tolist()} m (scene "
                f"frame: x right, y down, z forward) is outside the room (x in "
                f"[{lo[0]:g}, {hi[0]:g}], y in [{lo[1]:g}, {hi[1]:g}], z in [{lo[2]:g}, "
                f"{hi[2]:g}]); move the view's C or enlarge the room")


def pitched_view(pitch_deg: float) -> tuple[NDArray, NDArray]:
    """:func:`render_scene`'s ``view`` of the left camera at the scene frame's origin pitched
    ``pitch_deg`` degrees above the horizontal (+ = looking up, no roll): ``R`` rotates the
    scene frame (optical axes of a level camera: x right, y down, z forward) into the pitched
    optical frame, whose up vector is then ``(0, -cos p, sin p)``
    (:meth:`hearsee.vision.humans.FloorPlane.from_camera`). GeometryError unless
    ``pitch_deg`` is a finite number of degrees within +-80."""
    from hearsee.vision.humans import check_camera_pitch

    a = np.radians(check_camera_pitch(pitch_deg, "pitch_deg"))
    R = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(a), np.sin(a)], [0.0, -np.sin(a), np.cos(a)]])
    return R, np.zeros(3)


def render_scene(spec: SceneSpec, rig: StereoRig | None = None, *, noise_std: float = 2.0,
                 view: tuple[NDArray, NDArray] | None = None,
                 noise_seed: int | None = None) -> Scene:
    """Render ``spec`` with ``rig`` (default :func:`default_rig`): stereo pair, ground-truth
    disparity, thermal images and per-entity ground truth. Deterministic from ``spec.seed``
    (and ``noise_seed``).

    The rig must be rectified (identical distortion-free cameras, right camera at +B on x) and
    carry a thermal camera whose lens model reaches every pixel of its image (a distortion
    that folds back before the corners, e.g. k1 = -0.45 at f 60 px for 160x120, leaves
    pixels no direction projects to: :meth:`Camera.pixel_rays`' GeometryError names the
    first; their rays were wrong and rendered without a word). ``noise_std`` is the standard
    deviation of the stereo images' Gaussian pixel noise (grey levels of 0..255, finite and
    >= 0; else a ConfigError).

    ``noise_seed`` (a whole number >= 0, else a ConfigError) seeds the sensor's temporal
    noise on its own: the stereo images' pixel noise and the thermal image's NETD. The room's
    appearance (materials, colours, temperatures, texture offsets) and the thermal camera's
    column fixed-pattern noise stay those of ``spec.seed``, so frames of one scene rendered
    with different noise seeds differ only by independent noise, as a video's frames do
    (:mod:`hearsee.robot.pipeline` renders every camera frame with its own). None (the
    default) draws the noise from ``spec.seed`` as well, in one stream: the images are those
    rendered before this argument existed.

    ``view`` = ``(R, C)`` places the left camera in the scene's frame (the frame the entities
    and the room are written in): ``R`` rotates scene-frame vectors into the left optical frame
    and ``C`` is the camera centre in the scene frame (metres). The default is the identity at
    the origin. The rig moves rigidly with the left camera; ground-truth disparity and the
    returned ``position_m`` are in the left camera's optical frame. Used to render what a
    panning robot head sees (:mod:`hearsee.robot.pipeline`). Every camera of the rig must be
    in the room (its walls included), else a GeometryError.

    The returned scene's ``rig`` is ``rig`` with ``info["camera_height_m"]`` the height of the
    left camera above the floor that rendered it: ``spec.camera_height_m - C_y`` metres (the
    scene frame's y points down), which the scene's ``truth()`` and :func:`write_scene`'s
    ``calib.yaml`` report too; and ``info["camera_pitch_deg"]`` the pitch of its view
    (:func:`view_pitch_deg`; 0 without a ``view``), which the detector takes as its floor
    prior -- a pitched scene's rig had said nothing of it, so its own detection assumed a
    level camera.
    """
    _check_room(spec)
    # (NaN made both images black without a word, -1 let numpy's ValueError escape)
    noise_std = finite_number("render_scene noise_std", noise_std, 0.0)
    if rig is None:
        rig = default_rig(camera_height_m=spec.camera_height_m)
    if not isinstance(rig, StereoRig):
        raise ConfigError(f"render_scene: rig must be a StereoRig (see default_rig), got "
                          f"{rig!r:.60}")
    if view is None:
        Rv, Cv = np.eye(3), np.zeros(3)
    else:
        # (text was numpy's ValueError, a 1-tuple an IndexError, a number a TypeError)
        if (isinstance(view, str) or not isinstance(view, Sequence) or len(view) != 2
                or not all(real_entries(v) for v in view)):
            raise GeometryError("render_scene: view must be (R, C): a 3x3 rotation and the "
                                f"camera's centre in metres, got {view!r:.60}")
        Rv = np.asarray(view[0], dtype=float)
        Rv = Rv.reshape(3, 3) if Rv.size == 9 else Rv
        Cv = np.asarray(view[1], dtype=float).reshape(-1)
        if (Rv.shape != (3, 3) or not np.all(np.isfinite(Rv))
                or not np.allclose(Rv @ Rv.T, np.eye(3), atol=1e-6) or not np.linalg.det(Rv) > 0):
            raise GeometryError(f"render_scene: view R must be a 3x3 rotation matrix, got "
                                f"{Rv.tolist()}")
        if Cv.shape != (3,) or not np.all(np.isfinite(Cv)):
            raise GeometryError(f"render_scene: view C must be 3 finite numbers (metres), got "
                                f"{Cv.tolist()}")
    if not rig.is_rectified or rig.thermal is None:
        raise GeometryError("render_scene needs a rectified rig with a thermal camera "
                            "(see hearsee.sim.scenes.default_rig)")
    if not rig.right_center_m[0] > 0:  # (else the truth disparity f B / Z has the wrong sign)
        raise GeometryError("render_scene needs the right camera at +baseline on the left "
                            "camera's x axis (T_x < 0); this rig has it on the left: use "
                            "rig.swapped()")
    _check_cameras_in_room(spec, {"left": Cv, "right": Cv + Rv.T @ rig.right_center_m,
                                  "thermal": Cv + Rv.T @ rig.thermal_center_m})
    if noise_seed is not None:
        noise_seed = whole_number("render_scene noise_seed", noise_seed, 0)
    rng = np.random.default_rng(spec.seed)
    b = _Builder()
    floor_m = b.material(rng.uniform(0.3, 0.7, 3), 0.6, spec.room_c - 0.5, 0.3)
    wall_m = b.material(rng.uniform(0.5, 0.9, 3), 0.5, spec.room_c, 0.4)
    ceil_m = b.material([0.9, 0.9, 0.9], 0.35, spec.room_c + 0.7, 0.2)
    refs = [_add_entity(b, e, i, spec, rng) for i, e in enumerate(spec.entities)]
    tex_offsets = rng.uniform(0, 5.0, (len(b.materials), 3))
    column_fpn, noise = None, rng  # (noise_seed None: one stream, as before it existed)
    if noise_seed is not None:  # the sensor's fixed pattern is the scene's, its noise not
        column_fpn = rng.normal(0, 0.05, (1, rig.thermal.width))
        noise = np.random.default_rng(noise_seed)

    cam = rig.left
    views = {}
    for name, (Rc, Cc) in {"left": (Rv, Cv),
                           "right": (rig.R @ Rv, Cv + Rv.T @ rig.right_center_m)}.items():
        hits, D = _cast(cam, Rc, Cc, b, spec, (floor_m, wall_m, ceil_m), name == "left")
        img = _shade(hits, D, Cc, b, rng, tex_offsets)
        img = cv2.GaussianBlur(img.astype(np.float32), (0, 0), 0.5)
        img = img * 255.0 + noise.normal(0, noise_std, img.shape)
        views[name] = (np.clip(img + 0.5, 0, 255).astype(np.uint8), hits, D)
    left, hits_l, D_l = views["left"]
    right = views["right"][0]
    depth = hits_l.t * (D_l @ Rv.T.astype(np.float32))[..., 2]  # along the optical axis
    disparity = (cam.fx * rig.baseline_m / depth).astype(np.float32)

    C_t = Cv + Rv.T @ rig.thermal_center_m
    hits_t, D_t = _cast(rig.thermal, rig.R_thermal @ Rv, C_t, b, spec,
                        (floor_m, wall_m, ceil_m), False)
    thermal_c = _thermal_image(hits_t, D_t, C_t, b, rig.thermal, noise,
                               tex_offsets, column_fpn)

    labels = hits_l.owner.astype(np.int16)
    objects = []
    H, W = labels.shape
    for i, e in enumerate(spec.entities):
        vis = labels == i
        n = int(vis.sum())
        raw = hits_l.raw.get(i)
        total = int(raw.sum()) if raw is not None else 0
        box = None
        trunc = False
        if n > 0:
            ys, xs = np.nonzero(vis)
            x0, x1, y0, y1 = int(xs.min()), int(xs.max()), int(ys.min()), int(ys.max())
            box = [x0, y0, x1 - x0 + 1, y1 - y0 + 1]
            rr = raw if raw is not None else vis
            rys, rxs = np.nonzero(rr)
            trunc = bool(rxs.min() == 0 or rys.min() == 0 or rxs.max() == W - 1
                         or rys.max() == H - 1)
        objects.append(SceneObject(i, e.kind, Rv @ (refs[i] - Cv), box,
                                   n / total if total else 0.0,
                                   trunc, float(_rendered_yaw_deg(e)), float(e.height_m), n))
    height_m = float(spec.camera_height_m - Cv[1])  # (y down: a camera raised has C_y < 0)
    return Scene(left, right, disparity, labels, thermal_c, thermal_to_8bit(thermal_c),
                 _rig_as_rendered(rig, height_m, Rv), objects, spec, height_m)


def _free(x: float, z: float, placed: list[tuple[float, float, float]], r: float) -> bool:
    return all(np.hypot(x - px, z - pz) >= r + pr for px, pz, pr in placed)


def _pair(name: str, value: Any) -> tuple[Any, Any]:
    """``value`` as its two items (low, high), else a ConfigError naming ``name``: a count or
    range given as one number (``n_people=3``, ``range_m=5``) or with one item let a builtin
    TypeError / ValueError / IndexError escape from random_spec."""
    try:
        lo, hi = value
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a pair (low, high), got {value!r:.60}") from None
    return lo, hi


def random_spec(seed: int, *, n_people: tuple[int, int] = (1, 4),
                n_human_like: tuple[int, int] = (0, 2), range_m: tuple[float, float] = (1.0, 8.0),
                n_furniture: tuple[int, int] = (2, 5), hfov_deg: float = 65.0,
                camera_height_m: float = 1.4) -> SceneSpec:
    """A random room with people and human-like objects, deterministic from ``seed``.

    Counts are inclusive ranges. People and human-like objects stand ``range_m`` metres away
    (forward distance) inside the camera's horizontal field of view ``hfov_deg``; furniture,
    a radiator and sometimes a warm appliance stand along the walls or in the room.
    ``camera_height_m`` is a finite number of metres in (0, 2.5] (ConfigError).
    """
    for name, value in (("n_people", n_people), ("n_human_like", n_human_like),
                        ("n_furniture", n_furniture)):
        lo, hi = _pair(name, value)
        if whole_number(f"{name}[0]", lo, 0) > whole_number(f"{name}[1]", hi, 0):
            raise ConfigError(f"{name} must be an inclusive range (low, high) with low <= high, "
                              f"got {(lo, hi)}")
    range_m = _pair("range_m", range_m)
    near = finite_number("range_m[0]", range_m[0], 0.0, lo_open=True)
    if not near <= finite_number("range_m[1]", range_m[1], 0.0, lo_open=True):
        raise ConfigError(f"range_m must be (near, far) metres with 0 < near <= far, got "
                          f"{range_m}")
    if not 0 < finite_number("hfov_deg", hfov_deg) < 180:
        raise ConfigError(f"hfov_deg must be in (0, 180) degrees, got {hfov_deg}")
    # (NaN, -1 or 5 m passed here and failed later, in render_scene; below the lowest
    # ceiling drawn, 2.6 m, less a head's room)
    camera_height_m = finite_number("camera_height_m", camera_height_m, 0.0, 2.5, lo_open=True)
    rng = np.random.default_rng(whole_number("seed", seed, 0))
    depth = max(range_m[1] + rng.uniform(1.0, 2.5), 4.0)
    wl, wr = rng.uniform(2.8, 4.5), rng.uniform(2.8, 4.5)
    spec = SceneSpec(width_left_m=wl, width_right_m=wr, depth_m=depth,
                     ceiling_m=rng.uniform(2.6, 3.1), room_c=rng.uniform(19.5, 23.5),
                     camera_height_m=camera_height_m, seed=seed)
    tan = np.tan(np.radians(hfov_deg / 2))
    placed: list[tuple[float, float, float]] = []

    def place(radius: float, zr: tuple[float, float], margin: float = 0.3) -> tuple[float, float]:
        for _ in range(200):
            z = rng.uniform(*zr)
            lim = max(min(z * tan * 0.9 - margin, wr - 0.6), 0.0)
            liml = max(min(z * tan * 0.9 - margin, wl - 0.6), 0.0)
            x = rng.uniform(-liml, lim)
            if _free(x, z, placed, radius):
                placed.append((x, z, radius))
                return x, z
        raise GeometryError("could not place an entity without overlap; enlarge the room")

    def yaw() -> float:
        return float(rng.choice([0.0, 90.0, 180.0, -90.0, 30.0, -30.0, 150.0]) +
                     rng.uniform(-15, 15))

    for _ in range(int(rng.integers(n_people[0], n_people[1] + 1))):
        x, z = place(0.35, range_m)
        spec.entities.append(Entity("person", x, z, yaw(), rng.uniform(1.55, 1.92)))
    for _ in range(int(rng.integers(n_human_like[0], n_human_like[1] + 1))):
        kind = str(rng.choice(HUMAN_LIKE_KINDS))
        x, z = place(0.35, range_m)
        h = rng.uniform(1.6, 1.85)
        spec.entities.append(Entity(kind, x, z, yaw() if kind != "poster" else
                                    rng.uniform(-20, 20), h))
    n_bodies = len(placed)  # (the people and human-like objects)
    # one radiator against the left or right side wall (never the far wall): 0.1 m thick with
    # its back 1 cm off the wall, 0.8-1.4 m long, 0.12-0.72 m above the floor, 2 m to
    # depth - 1 m ahead (a warm appliance comes with some cabinets, below)
    side = rng.choice([-1.0, 1.0])
    rz = rng.uniform(2.0, depth - 1.0)
    rx = (wr - 0.06) if side > 0 else (-wl + 0.06)
    spec.entities.append(Entity("radiator", float(rx), float(rz), 0, 0.6,
                                {"width_m": 0.1, "depth_m": rng.uniform(0.8, 1.4),
                                 "lift_m": 0.12}))
    for _ in range(int(rng.integers(n_furniture[0], n_furniture[1] + 1))):
        w, d = rng.uniform(0.4, 1.4), rng.uniform(0.35, 0.8)
        h = float(rng.choice([0.45, 0.75, 0.9, 1.2, 1.9])) * rng.uniform(0.9, 1.1)
        if rng.random() < 0.6:  # along a wall
            z = rng.uniform(1.5, depth - d / 2 - 0.05)
            x = (wr - d / 2 - 0.05) if rng.random() < 0.5 else (-wl + d / 2 + 0.05)
            # its depth along the wall is w: the range above (kept, so that the rooms that
            # were right stay as they were) let one in ~40 stick through the far wall; such
            # a cabinet is moved in, 5 cm from the wall (no draw changes)
            if z + w / 2 > depth:
                z = depth - w / 2 - 0.05
            # nor is it drawn around a person or human-like object (placed before it, with the
            # room each keeps, 0.35 m, from its centre): it stood anywhere along the wall, and
            # ~1 spec in 40 had one through a body (seed 800: a 1.9 m wardrobe through a
            # person). Such a cabinet is left out (no draw changes: the rest stays as it was)
            if any(np.hypot(max(abs(px - x) - d / 2, 0.0), max(abs(pz - z) - w / 2, 0.0)) < pr
                   for px, pz, pr in placed[:n_bodies]):
                continue
            spec.entities.append(Entity("box", float(x), float(z), 0, h,
                                        {"width_m": d, "depth_m": w}))
        else:
            try:
                x, z = place(max(w, d) / 2 + 0.1, (1.5, depth - 0.5), margin=-0.5)
            except GeometryError:
                continue
            spec.entities.append(Entity("box", x, z, 0, h, {"width_m": w, "depth_m": d}))
            if h < 1.0 and rng.random() < 0.3:  # (a warm appliance on 30 % of the low ones)
                spec.entities.append(Entity("appliance", x, z, 0, 0.35,
                                            {"width_m": 0.45, "depth_m": 0.3, "lift_m": h}))
    return spec


#: random_spec's default ``hfov_deg`` (65 deg) stands for the default rig's view, 2 atan(320 /
#: 500) = 65.24 deg; :func:`generate_scene` keeps it for rigs within this many degrees of that.
_DEFAULT_VIEW_TOLERANCE_DEG = 0.05


def generate_scene(seed: int, rig: StereoRig | None = None, **kwargs: Any) -> Scene:
    """Render :func:`random_spec` ``(seed, **kwargs)`` (deterministic from ``seed``) with
    ``rig`` (default :func:`default_rig`).

    Unless ``hfov_deg`` is given, people and human-like objects stand in the rig's own
    horizontal field of view: random_spec's 65 deg for the default rig's 65.24 deg view (and
    any rig within :data:`_DEFAULT_VIEW_TOLERANCE_DEG` of it: those scenes are as before),
    the left camera's ``hfov_deg`` for a rig with another one (65 deg put a narrower rig's
    "people" outside its image).
    """
    if rig is not None and not isinstance(rig, StereoRig):  # (rig.left: an AttributeError)
        raise ConfigError(f"generate_scene: rig must be a StereoRig (see default_rig), got "
                          f"{rig!r:.60}")
    if rig is not None and "hfov_deg" not in kwargs:
        hfov = rig.left.hfov_deg
        if abs(hfov - np.degrees(2.0 * np.arctan2(320.0, 500.0))) > _DEFAULT_VIEW_TOLERANCE_DEG:
            kwargs["hfov_deg"] = hfov
    spec = random_spec(seed, **kwargs)
    return render_scene(spec, rig)


def write_scene(scene: Scene, folder: str | Path) -> Path:
    """Write ``left.png``, ``right.png``, ``thermal.png`` (8-bit AGC),
    ``thermal_radiometric.png`` (16-bit centi-kelvin), ``thermal_c.npy`` (float32 degC),
    ``disparity.npy`` (float32 px), ``calib.yaml`` (the rig) and ``truth.json`` into
    ``folder`` (created if needed). Returns the folder.

    A ``folder`` that is a file or lies below one, or that cannot be created or written, is an
    InputFileError naming it (bare FileExistsError / NotADirectoryError before; a PNG that
    could not be written was skipped without a word).
    """
    from hearsee.vision.io import write_image

    if not isinstance(scene, Scene):
        raise ConfigError(f"write_scene needs a Scene (render_scene's), got {scene!r:.60}")
    out = _scene_folder(folder)
    write_image(out / "left.png", scene.left)
    write_image(out / "right.png", scene.right)
    write_image(out / "thermal.png", scene.thermal_8bit)
    ck = np.clip(np.rint((scene.thermal_c + 273.15) * 100.0), 0, 65535).astype(np.uint16)
    write_image(out / "thermal_radiometric.png", ck)
    try:
        np.save(out / "thermal_c.npy", scene.thermal_c.astype(np.float32))
        np.save(out / "disparity.npy", scene.disparity.astype(np.float32))
        save_rig(scene.rig, out / "calib.yaml")
        (out / "truth.json").write_text(json.dumps(scene.truth(), indent=2), encoding="utf-8")
    except OSError as exc:
        raise InputFileError(f"{out}: cannot write the scene ({exc.strerror or exc})") from None
    return out


def _scene_folder(folder: str | Path) -> Path:
    """``folder`` as a Path, created with its parents if needed; InputFileError naming it when
    it is a file, lies below one, or cannot be created (the messages of
    :func:`hearsee.config.output_file`)."""
    out = as_path(folder, "the scene folder")
    if out.exists() and not out.is_dir():
        raise InputFileError(f"{out}: is a file, expected a folder for the scene")
    above = next((a for a in out.parents if a.exists()), None)
    if above is not None and not above.is_dir():
        raise InputFileError(f"{out}: {above} is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:  # (no permission)
        raise InputFileError(f"{out}: cannot create the folder ({exc.strerror or exc})"
                             ) from None
    return out
