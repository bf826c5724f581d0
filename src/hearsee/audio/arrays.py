"""Microphone arrays: positions, pairs, physical TDOA bounds and presets.

Positions are metres in the array frame (x forward, y left, z up; README "Conventions"). Rows are
microphones: ``positions[k]`` is microphone k, which is channel k of a multichannel recording.
TDOA sign: ``tdoa(i, j) = t_i - t_j`` (arrival at i minus arrival at j, thesis eq. 2.7).

Array files are YAML::

    name: my-array            # optional
    speed_of_sound: 343.0     # optional, m/s
    microphones:              # metres, array frame
      - [0.0, -0.075, 0.0]
      - [0.0,  0.075, 0.0]
    mask: {...}               # optional, masked two-microphone arrays (hearsee.audio.mask)

Presets are such files shipped in ``hearsee/data/arrays/``: see :func:`list_presets`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hearsee.config import (
    as_float_array,
    check_keys,
    finite_number,
    is_real,
    load_yaml,
    name_text,
    names_a_file,
    real_entries,
    refused_name,
    require,
    whole_number,
)
from hearsee.errors import ConfigError, GeometryError, HearseeError, InputFileError

__all__ = ["FLAT_TDOA_S", "MAX_MICS", "MAX_TDOA_STD_S", "SPEED_OF_SOUND_RANGE_MPS", "MicArray",
           "check_pairs", "check_tdoa_std", "closure_rms",
           "list_presets", "load_array", "load_array_beside", "pair_closure_projector",
           "pair_matrix", "pair_tdoa",
           "pair_tdoa_jacobian", "position_uncertainty", "residual_scaled_variance",
           "span_dimension"]

#: The most microphones an array (and the pair helpers' ``n_mics``) may have: a pair table or
#: ITD filter of 10**9 microphones hung building its pairs, and the array's distance table
#: grows with the square (4096 microphones: ~0.4 GB).
MAX_MICS = 4096

#: Default TDOA standard deviation (s): whole-capture GCC-PHAT summaries of 1-2 s of speech at
#: 16 kHz measured 1-2 us rms at SNR 20 dB in RT60 0.3 s rooms, ~6 us at SNR 10 dB (anechoic)
#: (the multi-pose study of :mod:`hearsee.audio.active`, three-mic). Arrays of 4-8 microphones
#: in ``bench/nmic.py``'s room (sources 0.5-3 m, 2 s, 10 / 20 dB; 2026-11-27): median per
#: condition 0.4-1 us anechoic, 4-14 us at RT60 0.3 s, 13-35 us at RT60 0.6 s.
DEFAULT_TDOA_STD_S = 5e-6
#: The largest TDOA standard deviation any function takes, seconds: 1 s, a thousand times any
#: array's largest delay, where no position is ever reported. Larger values overflowed where
#: they were squared (1e200 s: OverflowError from the position solvers; the CLI's
#: ``--tdoa-std-us`` was bounded, the library was not).
MAX_TDOA_STD_S = 1.0


def check_tdoa_std(value: Any, name: str = "tdoa_std_s", *, zero_ok: bool = False,
                   error: type[Exception] = GeometryError) -> float:
    """``value`` (seconds) as a float when it is a finite number in ``(0, MAX_TDOA_STD_S]``
    (``[0, ...]`` with ``zero_ok``, for noise levels), else ``error`` naming ``name``."""
    return finite_number(name, value, 0.0, MAX_TDOA_STD_S, lo_open=not zero_ok, error=error)


#: Two microphones closer than this (metres) are treated as coincident.
MIN_SPACING_M = 1e-3
#: An array wider than this (metres) whose delays outgrow a frame is asked whether its
#: positions are in metres (:meth:`MicArray.units_hint`): a robot's head spans centimetres, an
#: array file written in centimetres metres.
UNIT_HINT_APERTURE_M = 2.0

#: Largest TDOA (seconds) that the microphones' offsets from their best-fitting line (plane)
#: may add to any pair for the array to count as linear (planar): 10 us, 3.4 mm at 343 m/s, a
#: third of the localizers' default ``tol_s`` (30 us) -- the model error the lower-dimensional
#: solver then accepts leaves their feasibility test meaningful. Rule and study:
#: :func:`span_dimension`.
FLAT_TDOA_S = 1e-5

#: Range of an array's ``speed_of_sound`` (m/s): air from -100 to +250 degC (250-480),
#: helium (~970) and water (~1480) fit; outside it the value is a unit or typing mistake
#: (1e12 m/s made every TDOA ~0: `hearsee localize` answered -136 deg with confidence 1000
#: for a source at 45 deg).
SPEED_OF_SOUND_RANGE_MPS = (100.0, 2000.0)
_KEYS = ("name", "speed_of_sound", "microphones", "mask")


def _preset_dir() -> Path:
    return Path(str(resources.files("hearsee") / "data" / "arrays"))


def list_presets() -> list[str]:
    """Names of the array presets shipped with hearsee (e.g. ``two-mic``, ``three-mic``)."""
    return sorted(p.stem for p in _preset_dir().glob("*.yaml"))


@dataclass(frozen=True, eq=False)
class MicArray:
    """A rigid set of microphones.

    Parameters
    ----------
    positions : array (n_mics, 3)
        Microphone positions in metres, array frame.
    speed_of_sound : float
        c0 in m/s, within :data:`SPEED_OF_SOUND_RANGE_MPS`.
    name : str
        Label used in reports and JSON.
    mask : mapping or None
        Raw ``mask:`` block of a masked two-microphone array; interpreted by
        :mod:`hearsee.audio.mask`.
    """

    positions: NDArray
    speed_of_sound: float = 343.0
    name: str = "custom"
    mask: Mapping[str, Any] | None = field(default=None)

    def __post_init__(self) -> None:
        # (None printed as the array's name in every message and output; a mask given as text
        # failed later inside hearsee.audio.mask with a builtin AttributeError)
        if not isinstance(self.name, str):
            raise ConfigError(f"MicArray name must be text, got {self.name!r:.40}")
        if self.mask is not None and not isinstance(self.mask, Mapping):
            raise ConfigError(f"array {self.name!r}: mask must be a mapping (the YAML's mask: "
                              f"block) or None, got {self.mask!r:.40}")
        # (numpy read True as 1 m, "0.1" as 0.1 m and dropped an imaginary part)
        pos = np.array(self.positions, dtype=float) if real_entries(self.positions) else None
        if pos is None:
            raise GeometryError(f"array {self.name!r}: microphone positions must be an N x 3 "
                                f"table of numbers (metres), got {self.positions!r}") from None
        if pos.ndim != 2 or pos.shape[1] != 3:
            raise GeometryError(
                f"array {self.name!r}: microphone positions must be N x 3, got shape {pos.shape}"
            )
        if pos.shape[0] < 2:
            raise GeometryError(
                f"array {self.name!r}: needs at least 2 microphones, got {pos.shape[0]}"
            )
        if pos.shape[0] > MAX_MICS:
            raise GeometryError(f"array {self.name!r}: at most {MAX_MICS} microphones, got "
                                f"{pos.shape[0]}")
        if not np.all(np.isfinite(pos)):
            raise GeometryError(f"array {self.name!r}: microphone positions must be finite")
        with np.errstate(over="ignore"):
            d = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=-1)
        if not np.all(np.isfinite(d)):  # (an aperture of inf: every TDOA NaN or inf)
            raise GeometryError(f"array {self.name!r}: microphone positions too large: their "
                                f"distances overflow float64 (metres expected)")
        iu = np.triu_indices(len(pos), 1)
        k = int(np.argmin(d[iu]))
        if d[iu][k] < MIN_SPACING_M:
            i, j = iu[0][k], iu[1][k]
            raise GeometryError(
                f"array {self.name!r}: microphones {i} and {j} coincide "
                f"({d[iu][k] * 1000:.2f} mm apart, minimum {MIN_SPACING_M * 1000:.0f} mm)"
            )
        c = self.speed_of_sound
        if not is_real(c):  # (float() read "343" as 343 m/s and True as 1 m/s)
            raise GeometryError(f"array {self.name!r}: speed_of_sound must be a number > 0 "
                                f"(m/s), got {c!r}")
        c = float(c)
        lo, hi = SPEED_OF_SOUND_RANGE_MPS
        if not lo <= c <= hi:
            raise GeometryError(f"array {self.name!r}: speed_of_sound must be {lo:g} to "
                                f"{hi:g} m/s (air: about 343), got {c}")
        pos.setflags(write=False)
        object.__setattr__(self, "positions", pos)
        object.__setattr__(self, "speed_of_sound", c)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_dict(cls, data: Mapping[str, Any], where: str = "array") -> MicArray:
        """Build from a mapping with the YAML schema above; ConfigError names bad fields."""
        if not isinstance(data, Mapping):  # (None: a builtin TypeError in check_keys)
            raise ConfigError(f"{where}: expected a mapping with 'microphones', got {data!r}")
        check_keys(data, _KEYS, where)
        mics = as_float_array(require(data, "microphones", where), f"{where}: microphones",
                              shape=(None, 3))
        c = data.get("speed_of_sound", 343.0)
        if not is_real(c):  # (a numpy float was refused, NaN reached the array's own check)
            raise ConfigError(f"{where}: speed_of_sound must be a finite number, got {c!r}")
        mask = data.get("mask")
        if mask is not None and not isinstance(mask, Mapping):
            raise ConfigError(f"{where}: mask must be a mapping")
        name = data.get("name")  # (an empty "name:" named the array "None")
        if isinstance(name, str) and not name.strip():  # ('name: ""' titled its reports
            name = None  # "hearsee localize (, phat)"): as no name, the file's stem
        name = name_text(name, where) if name is not None else (
            Path(where).stem if where != "array" else "custom")
        try:
            arr = cls(mics, float(c), name, mask)
        except GeometryError as exc:
            raise GeometryError(f"{where}: {exc}") from None
        if mask is not None:  # bad mask geometry is a clear error at load (hearsee.audio.mask)
            from hearsee.audio.mask import mask_geometry

            try:
                mask_geometry(arr)
            except HearseeError as exc:  # (named the array's name only, not its file)
                if where == name:
                    raise
                raise type(exc)(f"{where}: {exc}") from None
        return arr

    @classmethod
    def from_yaml(cls, path: str | Path) -> MicArray:
        """Load an array file (see module docstring)."""
        return cls.from_dict(load_yaml(path), where=str(path))

    @classmethod
    def from_preset(cls, name: str) -> MicArray:
        """Load a preset shipped with hearsee by name (see :func:`list_presets`): a plain name,
        never a path ("/abs/file" or "../arrays/two-mic" read a file outside the presets'
        folder; :func:`load_array` takes paths)."""
        path = _preset_dir() / f"{name}.yaml"
        if str(name) not in list_presets() or not path.is_file():
            raise ConfigError(
                f"unknown array preset {name!r} (presets: {', '.join(list_presets())})"
            )
        return cls.from_dict(load_yaml(path), where=name)

    def to_dict(self) -> dict[str, Any]:
        """The YAML/JSON form of this array."""
        out: dict[str, Any] = {
            "name": self.name,
            "speed_of_sound": self.speed_of_sound,
            "microphones": self.positions.tolist(),
        }
        if self.mask is not None:
            out["mask"] = dict(self.mask)
        return out

    # ------------------------------------------------------------------ geometry
    @property
    def n_mics(self) -> int:
        return int(self.positions.shape[0])

    @property
    def R(self) -> NDArray:
        """Positions as a ``(3, n_mics)`` array (pyroomacoustics' layout)."""
        return self.positions.T.copy()

    @property
    def centre(self) -> NDArray:
        """Centroid of the microphones, metres."""
        return self.positions.mean(axis=0)

    @cached_property
    def pairs(self) -> list[tuple[int, int]]:
        """All microphone pairs ``(i, j)`` with ``i < j``, in a fixed order."""
        return [(i, j) for i in range(self.n_mics) for j in range(i + 1, self.n_mics)]

    @property
    def pair_labels(self) -> list[str]:
        """JSON keys of :attr:`pairs`, e.g. ``["0-1", "0-2", "1-2"]``."""
        return [f"{i}-{j}" for i, j in self.pairs]

    def checked_pairs(self, pairs: Sequence[tuple[int, int]] | None = None
                      ) -> list[tuple[int, int]]:
        """``pairs`` (default: all of :attr:`pairs`) as a list of ``(i, j)`` microphone indices,
        or a GeometryError for an empty list, a pair that is not two indices of this array
        (a negative index used to wrap around to the last microphones) or ``i == j``."""
        if pairs is None:
            return list(self.pairs)
        return check_pairs(pairs, self.n_mics)

    def pair_distance(self, pairs: list[tuple[int, int]] | None = None) -> NDArray:
        """Distance in metres between the microphones of each pair."""
        pairs = self.checked_pairs(pairs)
        p = self.positions
        return np.array([np.linalg.norm(p[i] - p[j]) for i, j in pairs])

    def max_tdoa(self, pairs: list[tuple[int, int]] | None = None) -> NDArray:
        """Largest physically possible |TDOA| per pair in seconds: spacing / c0."""
        return self.pair_distance(pairs) / self.speed_of_sound

    @property
    def aperture(self) -> float:
        """Largest microphone spacing in metres."""
        return float(self.pair_distance().max())

    def units_hint(self) -> str:
        """`` (the array spans 15 m: are its microphone positions in metres?)`` for an array
        wider than :data:`UNIT_HINT_APERTURE_M`, else ``""``: what the messages that find its
        delays too long for a frame add (a 15 cm pair written in centimetres asked for frames
        of 175 ms and more, without a word of the unit)."""
        if self.aperture <= UNIT_HINT_APERTURE_M:
            return ""
        return f" (the array spans {self.aperture:.3g} m: are its microphone positions in metres?)"

    @property
    def is_planar(self) -> bool:
        """True when all microphones lie in one plane (always true for 2 or 3 microphones), to
        within what TDOAs resolve: :func:`span_dimension` at most 2 (a line is planar too)."""
        if self.n_mics <= 3:
            return True
        return span_dimension(self.positions, self.speed_of_sound)[0] <= 2

    def tdoa(self, source: ArrayLike, pairs: list[tuple[int, int]] | None = None) -> NDArray:
        """Exact (near-field) TDOAs ``t_i - t_j`` in seconds for source point(s) ``(..., 3)``
        in metres, in the array frame.

        Returns shape ``(..., n_pairs)``. A non-finite coordinate is a GeometryError (it gave
        NaN TDOAs without a word), as in :meth:`tdoa_far`.
        """
        from hearsee.geometry import as_points  # (here: geometry imports scipy, `info` need not)

        i, j = _pair_index(self.checked_pairs(pairs))
        p = as_points(source, "source")
        finite = np.isfinite(p).all(axis=-1)
        if not finite.all():
            n_bad, first = int(np.count_nonzero(~finite)), p[~finite][0].tolist()
            which = f"{n_bad} of {finite.size} points, e.g. " if p.ndim > 1 else ""
            raise GeometryError(f"source must be finite [x, y, z] in metres, got {which}{first}")
        with np.errstate(over="ignore", invalid="ignore"):
            tau = pair_tdoa(p, self.positions, i, j, self.speed_of_sound)
        if not np.all(np.isfinite(tau)):  # (1e300 m: inf - inf, NaN TDOAs without a word)
            raise GeometryError("source too far: its distances to the microphones overflow "
                                "float64 (metres expected; a source at infinity: tdoa_far)")
        return tau

    def tdoa_jacobian(self, source: ArrayLike,
                      pairs: list[tuple[int, int]] | None = None) -> NDArray:
        """Derivative of :meth:`tdoa` with respect to the source position at one point
        ``(3,)`` (metres): shape ``(n_pairs, 3)``, seconds per metre."""
        from hearsee.geometry import as_point  # (here: geometry imports scipy, `info` need not)

        i, j = _pair_index(self.checked_pairs(pairs))
        p = as_point(source, "source")
        return pair_tdoa_jacobian(p, self.positions, i, j, self.speed_of_sound)

    def tdoa_far(self, direction: ArrayLike, pairs: list[tuple[int, int]] | None = None) -> NDArray:
        """Far-field TDOAs ``t_i - t_j`` in seconds for unit direction(s) ``(..., 3)``.

        A plane wave from direction u reaches microphone m at time ``-m . u / c0``. A zero
        direction is a GeometryError (it was a silent NaN), and so is a non-finite one.
        """
        from hearsee.geometry import as_points, norm_scale

        pairs = self.checked_pairs(pairs)
        u = as_points(direction, "direction")
        if not np.all(np.isfinite(u)):  # (inf gave NaN TDOAs, NaN read as "the zero vector")
            raise GeometryError(f"a far-field direction must be finite, got {direction!r}")
        # ([1e300, 1e300, 0]: its norm overflowed, TDOAs of 0; [1e-300, 0, 0] was refused as
        # the zero vector)
        u = u / norm_scale(u)
        norm = np.linalg.norm(u, axis=-1, keepdims=True)
        if not np.all(norm > 0):
            raise GeometryError("a far-field (plane-wave) source needs a direction; got the zero "
                                "vector (a source at the array-frame origin)")
        u = u / norm
        proj = u @ self.positions.T  # (..., n_mics)
        i = np.array([p[0] for p in pairs])
        j = np.array([p[1] for p in pairs])
        return -(proj[..., i] - proj[..., j]) / self.speed_of_sound

    def __repr__(self) -> str:
        return f"MicArray(name={self.name!r}, n_mics={self.n_mics}, aperture={self.aperture:.3f} m)"


def span_dimension(positions: NDArray, speed_of_sound: float, rel_tol: float = 1e-6
                   ) -> tuple[int, NDArray, NDArray]:
    """How many dimensions microphone positions ``(n, 3)`` (metres) span as TDOAs see them: 1
    (linear), 2 (planar) or 3 (volume), with their centroid and the right singular vectors
    ``vt`` (3, 3) of the centred positions (rows by decreasing spread: ``vt[0]`` the line's
    direction, ``vt[:2]`` the plane's).

    The positions lie on a line (in a plane) when every pair's offset from the best-fitting
    line (plane) is at most ``c0 * FLAT_TDOA_S`` metres long (:data:`FLAT_TDOA_S`, 10 us: 3.4
    mm at 343 m/s) -- no far-field direction's out-of-line (out-of-plane) part changes a pair's
    TDOA by more -- or when the thinnest spread's singular value is below ``rel_tol`` times
    the largest (the rule alone until 2026-12-02, with 1e-6). With the ratio alone, positions
    written with six decimals (micrometres) sent a 4-mic line along azimuth 30 deg to the
    planar solver and a ``respeaker-6`` tilted by 30 deg to the volume solver, whose extra
    direction was then fixed by micrometres of geometry and swamped by the TDOA noise (2 us:
    median errors 88.6 and 8 deg, up to 109).

    Why 10 us: an extent ``e`` puts at most ``e / c0`` of model error on the lower-dimensional
    solver, while the higher-dimensional one's error along that direction grows as ``sigma c0
    / e`` for TDOA noise ``sigma``. Far-field sources within +-30 deg of the plane (300 per
    cell, i.i.d. noise; 2026-12-02), RMS error of the best candidate, planar solver vs volume
    solver: ``respeaker-6`` with one microphone raised by e, at 1 / 2 / 5 us of noise, 0.9 vs
    7.4 / 1.5 vs 16.6 / 2.9 vs 25.3 deg at e = 1 mm, 0.9 vs 1.8 / 1.5 vs 4.0 / 2.9 vs 12.7 at
    3.4 mm, 0.9 vs 1.1 / 1.5 vs 2.6 / 3.0 vs 7.9 at 5 mm, 0.9 vs 0.6 / 1.5 vs 1.4 / 3.0 vs 3.9
    at 1 cm, 1.1 vs 0.4 / 1.7 vs 0.8 / 3.0 vs 2.1 at 2 cm (the three-mic triangle with a fourth
    microphone e above its plane alike); three microphones on a 15 cm line with the middle one
    e off it, horizontal sources, linear vs planar solver at 2 us: 0.9 vs 21 deg at 1 mm, 0.9
    vs 4.1 at 5 mm. The planar solver's twin candidates flatter it (the volume solver gives
    one answer, mirror resolved), so the bound sits below the crossing (5-15 mm): extents of
    1 cm and more (>= 29 us) stay volume.

    Geometry of the lower dimension is the solvers' model: a near-flat array's answers carry
    up to ``FLAT_TDOA_S`` of model error per pair. GeometryError unless ``positions`` are
    finite numbers ``(n, 3)``, n >= 1 (None was numpy's AxisError, an empty set a LinAlgError),
    ``speed_of_sound`` a finite number > 0 m/s and ``rel_tol`` one in (0, 1] (None was a builtin
    TypeError for both)."""
    c0 = finite_number("speed_of_sound (m/s)", speed_of_sound, 0.0, lo_open=True,
                       error=GeometryError)
    finite_number("rel_tol", rel_tol, 0.0, 1.0, lo_open=True, error=GeometryError)
    if not real_entries(positions):
        raise GeometryError(f"positions must be numbers (n, 3) metres, got {positions!r:.60}")
    pos = np.asarray(positions, dtype=float)
    if pos.ndim != 2 or pos.shape[1] != 3 or len(pos) == 0 or not np.all(np.isfinite(pos)):
        raise GeometryError(f"positions must be finite (n, 3) metres with n >= 1, got shape "
                            f"{pos.shape}")
    c = pos.mean(axis=0)
    _, s, vt = np.linalg.svd(pos - c)
    s = np.concatenate([s, np.zeros(3 - len(s))])
    scale = max(s[0], 1e-12)
    flat_m = FLAT_TDOA_S * c0
    for dim in (1, 2):
        off = (pos - c) @ vt[dim:].T  # offsets from the line (dim 1) or plane (dim 2)
        widest = float(np.max(np.linalg.norm(off[:, None, :] - off[None, :, :], axis=-1)))
        if s[dim] < rel_tol * scale or widest <= flat_m:
            return dim, c, vt
    return 3, c, vt


def check_pairs(pairs: Sequence[tuple[int, int]], n_mics: int) -> list[tuple[int, int]]:
    """``pairs`` as a list of ``(i, j)`` indices of ``n_mics`` microphones, or a GeometryError
    for an empty list, a pair that is not an ordered sequence of two whole numbers (0.7 used
    to be truncated to index 0; a bool or a set is none), an index outside ``[0, n_mics)`` (a
    negative one used to wrap around to the last microphones) or ``i == j``; also for
    ``n_mics`` that is no whole number >= 2 (None was a builtin TypeError) and for text
    (``"01"`` was read character by character: "a pair is two microphone indices, got '0'").
    The one rule of :meth:`MicArray.checked_pairs` and
    :class:`hearsee.audio.itd_filter.ItdKalman`."""
    n_mics = whole_number("n_mics", n_mics, lo=2, hi=MAX_MICS, error=GeometryError)
    try:
        items = None if isinstance(pairs, str | bytes) else list(pairs)
    except TypeError:
        items = None
    if items is None:
        raise GeometryError(f"pairs must be a list of (i, j) microphone index pairs, got "
                            f"{pairs!r}")
    out = []
    for p in items:
        # (an ordered pair: a set or a mapping was a builtin TypeError / KeyError -- and a set
        # has no order, its sign was the hash's; a bool is no index: (True, False) was (1, 0))
        try:  # two whole numbers
            ok = (isinstance(p, Sequence | np.ndarray) and not isinstance(p, str | bytes)
                  and len(p) == 2
                  and all(not isinstance(v, bool | np.bool_) and int(v) == v for v in p))
        except (TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise GeometryError(f"a pair is two microphone indices, got {p!r}")
        i, j = int(p[0]), int(p[1])
        if i == j or not (0 <= i < n_mics and 0 <= j < n_mics):
            raise GeometryError(
                f"invalid microphone pair {p!r} for an array of {n_mics} microphones"
            )
        out.append((i, j))
    if not out:
        raise GeometryError("no microphone pairs given")
    return out


def _pair_index(pairs: list[tuple[int, int]]) -> tuple[NDArray, NDArray]:
    """The pairs' first and second microphone indices as two integer arrays."""
    return (np.array([p[0] for p in pairs], dtype=int), np.array([p[1] for p in pairs], dtype=int))


def pair_matrix(n_mics: int, pairs: Sequence[tuple[int, int]], ref: int = 0) -> NDArray:
    """``H`` (n_pairs, n_mics - 1) mapping the reference ITD state to pair TDOAs ``t_i - t_j``.
    GeometryError for fewer than 2 microphones, a reference that is not one of them, or pairs
    :func:`check_pairs` refuses (n_mics 0 was numpy's builtin ValueError, a reference of 9 for
    3 microphones a matrix as if there were none). The ITD Kalman filter's measurement matrix
    (:mod:`hearsee.audio.itd_filter`) and the closure of :func:`pair_closure_projector`."""
    n_mics = whole_number("n_mics", n_mics, lo=2, hi=MAX_MICS, error=GeometryError)
    ref = whole_number("ref", ref, lo=0, hi=n_mics - 1, error=GeometryError)
    pairs = check_pairs(pairs, n_mics)
    others = [k for k in range(n_mics) if k != ref]
    col = {k: c for c, k in enumerate(others)}
    H = np.zeros((len(pairs), n_mics - 1))
    for r, (i, j) in enumerate(pairs):
        if i != ref:
            H[r, col[i]] += 1.0
        if j != ref:
            H[r, col[j]] -= 1.0
    return H


def pair_closure_projector(pairs: Sequence[tuple[int, int]], n_mics: int
                           ) -> tuple[NDArray, int] | None:
    """``(I - H H^+, n_pairs - rank H)`` for the pair matrix ``H`` (:func:`pair_matrix`),
    i.e. the residual of a least-squares fit of consistent ``t_i - t_j`` to pair values, and its
    degrees of freedom; None when the pairs hold no redundancy (no closed cycle ``t_ij + t_jk =
    t_ik``). Cached per pair set; the projector is read-only. GeometryError for pairs
    :func:`check_pairs` refuses (a list of pairs or an array was lru_cache's builtin
    TypeError, "unhashable type")."""
    return _closure_projector(tuple(check_pairs(pairs, n_mics)), int(n_mics))


@lru_cache(maxsize=64)
def _closure_projector(pairs: tuple[tuple[int, int], ...], n_mics: int
                       ) -> tuple[NDArray, int] | None:
    """:func:`pair_closure_projector` of checked ``pairs`` (a tuple of tuples of ints)."""
    H = pair_matrix(n_mics, pairs)
    rank = int(np.linalg.matrix_rank(H))
    if len(pairs) <= rank:
        return None
    P = np.eye(len(pairs)) - H @ np.linalg.pinv(H)
    P.flags.writeable = False
    return P, len(pairs) - rank


def closure_rms(values: ArrayLike, pairs: Sequence[tuple[int, int]], n_mics: int
                ) -> float | None:
    """RMS closure residual of pair values ``t_i - t_j`` (any unit; returned in the same): the
    part of them that no set of arrival times ``t_k`` explains, per degree of freedom of
    :func:`pair_closure_projector`. Independently measured pair TDOAs (one GCC peak per pair)
    disagree by it; None when the pairs hold no closed cycle (e.g. ``n - 1`` pairs sharing a
    reference microphone). GeometryError for pairs :func:`check_pairs` refuses or values that
    are not numbers, one per pair (text was numpy's builtin ValueError, and a list of numbers
    written as text, ``["1", "2", "3"]``, was read as numbers)."""
    prs = tuple(check_pairs(pairs, n_mics))
    if not real_entries(values):
        raise GeometryError(f"closure_rms: values must be numbers, one per pair, got "
                            f"{values!r:.60}")
    v = np.asarray(values, dtype=float)
    if v.shape != (len(prs),):
        raise GeometryError(f"closure_rms needs one value per pair ({len(prs)}), got shape "
                            f"{v.shape}")
    proj = pair_closure_projector(prs, n_mics)
    if proj is None:
        return None
    P, dof = proj
    return float(np.sqrt(np.sum((P @ v) ** 2) / dof))


def _given(func: str, **args: Any) -> None:
    """GeometryError naming ``func`` and the first of ``args`` (argument name -> value) that
    is None or text (a ``str`` or ``bytes``). The numeric kernels below (:func:`pair_tdoa`,
    :func:`pair_tdoa_jacobian`, :func:`position_uncertainty`,
    :func:`residual_scaled_variance`) run inside the solvers' loops and check no more than
    this (a fraction of a microsecond): None made numpy's or Python's builtin TypeError /
    IndexError, and as a pair index or residuals a wrong answer without an error (an extra
    axis; sig^2 alone); text made numpy's ValueError / UFuncTypeError / IndexError, and
    position_uncertainty took a text ``max_rel_distance_std`` without a word. Entries of a
    list are not looked at (the kernels' callers pass arrays they made)."""
    for name, value in args.items():
        if value is None:
            raise GeometryError(f"{func}: {name} must be given, got None")
        if isinstance(value, str | bytes):
            raise GeometryError(f"{func}: {name} must be numeric, got text {value!r:.40}")


def pair_tdoa(points: ArrayLike, positions: NDArray, i: NDArray, j: NDArray,
              speed_of_sound: float) -> NDArray:
    """Exact (near-field) TDOAs ``t_i - t_j`` in seconds of point(s) ``(..., 3)`` (metres) at
    microphones ``positions`` ``(n, 3)`` (metres), for the pairs ``(i[k], j[k])``: shape
    ``(..., n_pairs)``. The one place of this model: :meth:`MicArray.tdoa`, the near-field
    fits of :mod:`hearsee.audio.localize`, the moving-head solver (:mod:`hearsee.audio.active`,
    whose poses stack several placements of the array) and the 3D tracker
    (:class:`hearsee.fusion.audiovisual.RayTdoaTracker`) use it. GeometryError for an
    argument that is None."""
    _given("pair_tdoa", points=points, positions=positions, i=i, j=j,
           speed_of_sound=speed_of_sound)
    d = np.linalg.norm(np.asarray(points, dtype=float)[..., None, :] - positions, axis=-1)
    return (d[..., i] - d[..., j]) / speed_of_sound


def pair_tdoa_jacobian(point: ArrayLike, positions: NDArray, i: NDArray, j: NDArray,
                       speed_of_sound: float) -> NDArray:
    """Derivative of :func:`pair_tdoa` with respect to one point ``(3,)`` (metres): ``(u_i -
    u_j) / c`` per pair, ``u_k`` the unit vector from microphone k to the point; shape
    ``(n_pairs, 3)``, seconds per metre. A point on a microphone has none (GeometryError), nor
    has an argument that is None."""
    _given("pair_tdoa_jacobian", point=point, positions=positions, i=i, j=j,
           speed_of_sound=speed_of_sound)
    u = np.asarray(point, dtype=float).reshape(3) - positions
    n = np.linalg.norm(u, axis=1, keepdims=True)
    if not np.all(n > 0):
        raise GeometryError("the TDOA has no derivative at a microphone's position")
    u = u / n
    return (u[i] - u[j]) / speed_of_sound


def position_uncertainty(p: NDArray, M: NDArray, a: NDArray, b: NDArray, c: float, y: NDArray,
                         sig: float, ref: NDArray, max_rel_distance_std: float
                         ) -> tuple[NDArray, float, float, float]:
    """Linearised uncertainty of a source position ``p`` (metres) fitted to TDOAs ``y``
    (seconds) of the pairs ``(a[k], b[k])`` of microphones ``M`` (n, 3) (metres), speed of
    sound ``c`` (m/s): position covariance (m^2), relative 1-sigma distance from ``ref``,
    angular 1-sigma seen from ``ref`` (degrees; conditional on the distance when its relative
    1-sigma exceeds ``max_rel_distance_std``; inf where the TDOAs leave a cone of directions,
    e.g. one pair) and the Jacobian's condition number.

    ``C = s^2 (J^T J)^-1`` with J = :func:`pair_tdoa_jacobian` at ``p`` (per-pair TDOA errors
    taken as independent) and ``s^2`` the larger of ``sig^2`` (the declared TDOA standard
    deviation, seconds) and the robust residual variance ``(1.4826 MAD)^2 m / (m - 3)`` of
    the ``m`` TDOAs. The one place of this model: the multi-pose solver
    (:func:`hearsee.audio.active.solve_range_differences`, ``M`` stacking every pose's
    microphones) and the one-pose near-field position of
    :func:`hearsee.audio.localize.localize_tdoa` use it. A linearisation: where the distance
    is poorly determined (relative 1-sigma above ~0.3) it is optimistic. A position at ``ref``
    itself has no distance or direction seen from it: both 1-sigmas are inf. GeometryError for
    an argument that is None."""
    _given("position_uncertainty", p=p, M=M, a=a, b=b, c=c, y=y, sig=sig, ref=ref,
           max_rel_distance_std=max_rel_distance_std)
    J = pair_tdoa_jacobian(p, M, a, b, c)
    s2 = residual_scaled_variance(pair_tdoa(p, M, a, b, c) - y, sig, 3)
    JtJ = J.T @ J
    w = np.linalg.eigvalsh(JtJ)
    cond = float(np.sqrt(w[-1] / max(w[0], 1e-300)))
    v = p - ref
    r = float(np.linalg.norm(v))
    if not r > 0:  # (p at ref: u = 0 / 0, a RuntimeWarning, then numpy's LinAlgError "SVD
        # did not converge" from the NaN projector below)
        return _linearised_covariance(JtJ, s2, v)[0], float("inf"), float("inf"), cond
    u = v / r
    cov, rel = _linearised_covariance(JtJ, s2, v)
    # angular std: perpendicular spread, conditional on the distance when it is unknown
    P = np.eye(3) - np.outer(u, u)
    if np.isfinite(rel) and rel <= max_rel_distance_std:
        ang = np.sqrt(max(np.trace(P @ cov @ P), 0.0)) / r
    else:
        E = np.linalg.svd(P)[0][:, :2]  # basis orthogonal to u
        Jt = J @ E
        wt = np.linalg.eigvalsh(Jt.T @ Jt)
        try:
            # a rank-deficient J^T J (one pair, or poses turned only about its axis: a cone of
            # directions) has no inverse; inverted in floating point it gave 0 deg (a cone
            # called exact) or 1e8 deg, by rounding
            if not wt[0] > 1e-10 * wt[-1]:
                raise np.linalg.LinAlgError
            ang = np.sqrt(max(np.trace(s2 * np.linalg.inv(Jt.T @ Jt)), 0.0)) / r
        except np.linalg.LinAlgError:
            ang = np.inf
    return cov, float(rel), float(np.degrees(ang)), cond


def residual_scaled_variance(residual_s: ArrayLike, sig: float, n_params: int) -> float:
    """The measurement variance (s^2) behind a fitted position's covariance: the declared
    ``sig^2`` (seconds), or the robust residual variance ``(1.4826 MAD)^2 m / (m - n_params)``
    of the fit's ``m`` TDOA residuals (seconds) where that is larger (MAD: outliers that a
    robust loss down-weighted must not inflate it); ``sig^2`` alone when ``m <= n_params``.
    Used with the 3-D position (``n_params`` 3, :func:`position_uncertainty`) and the in-plane
    one (2, :func:`hearsee.audio.localize.near_field_in_plane`). GeometryError for an
    argument that is None, and for a ``sig`` that is not > 0."""
    _given("residual_scaled_variance", residual_s=residual_s, sig=sig, n_params=n_params)
    if not sig > 0:  # (0 divided the residuals by zero: a NaN variance; NaN passed through)
        raise GeometryError(f"residual_scaled_variance: sig must be a TDOA standard deviation "
                            f"> 0 s, got {sig!r}")
    r = np.asarray(residual_s, dtype=float).ravel()
    m = r.size
    if m <= n_params:
        return sig**2
    scale = 1.4826 * float(np.median(np.abs(r / sig)))
    return sig**2 * max(1.0, scale**2 * m / (m - n_params))


def _linearised_covariance(JtJ: NDArray, s2: float, v: NDArray,
                           basis: NDArray | None = None) -> tuple[NDArray, float]:
    """``(C, rel)``: the covariance ``C = s2 (J^T J)^-1`` (m^2) of a position fitted by least
    squares to measurements of variance ``s2`` with Jacobian ``J`` (given as ``J^T J``), and
    the relative 1-sigma of the length of ``v`` (the position from its reference point,
    metres) under it; with ``basis`` (k, 3) orthonormal rows, ``J`` was taken along them
    (``J B^T``: the position held in their span) and ``C = B^T s2 (J^T J)^-1 B`` (zero across
    it). A singular ``J^T J`` (to rounding: smallest eigenvalue at most 1e-12 of the largest)
    gives an infinite C and rel, and ``v = 0`` an infinite rel. The step shared by
    :func:`position_uncertainty` and the in-plane fit of
    :func:`hearsee.audio.localize.near_field_in_plane`."""
    w = np.linalg.eigvalsh(JtJ)
    if not w[0] > 1e-12 * w[-1]:
        # (singular in all but rounding -- one microphone moved along a line, a circle of
        # sources -- np.linalg.inv did not raise: a covariance with an eigenvalue of -1e12 m^2,
        # a direction 1-sigma of 0 deg and a distance called known)
        return np.full((3, 3), np.inf), float("inf")
    try:
        cov = s2 * np.linalg.inv(JtJ)
    except np.linalg.LinAlgError:
        return np.full((3, 3), np.inf), float("inf")
    if basis is not None:
        cov = basis.T @ cov @ basis
    r = float(np.linalg.norm(v))
    if not r > 0:  # v = 0: no length to be relative to
        return cov, float("inf")
    u = v / r
    var_r = float(u @ cov @ u)
    return cov, (float(np.sqrt(var_r)) / r if np.isfinite(var_r) and var_r >= 0
                 else float("inf"))


def load_array(spec: str | Path | MicArray) -> MicArray:
    """A MicArray from a preset name, a YAML path, or an existing MicArray."""
    if isinstance(spec, MicArray):
        return spec
    if not isinstance(spec, str | Path):  # (an array of positions was read as a file name)
        raise ConfigError(f"array: expected a MicArray, a preset name or a YAML path, got "
                          f"{type(spec).__name__} {spec!r:.60}")
    s = str(spec)
    if not s.strip():  # ("" is Path("."), which was called "a folder" until 2026-12-03)
        raise ConfigError(f"array: empty; expected a preset name ({', '.join(list_presets())}) "
                          f"or an array YAML file")
    with refused_name(s):  # (a name too long for the system: its OSError)
        if Path(s).is_dir():  # (a folder or a missing path read as an unknown preset name)
            raise InputFileError(f"{s}: is a folder; expected an array YAML file or a preset "
                                 "name")
        is_file = Path(s).is_file()
    if is_file:
        return MicArray.from_yaml(s)
    # (the rule of the robot file and the scenarios, config.names_a_file: a folder or a YAML
    # suffix in any case -- a missing "mics.YAML" was called an unknown preset until
    # 2026-12-02; preset names have neither)
    if names_a_file(s):
        raise InputFileError(f"{s}: no such array file")
    return MicArray.from_preset(s)


def load_array_beside(spec: Any, base_dir: str | Path | None, where: str = "array"
                      ) -> tuple[MicArray, str]:
    """The array a file's field ``where`` names (a scenario's ``robot.array``, a pose
    manifest's ``array``) and its spec: a YAML path, ``~`` expanded and taken from the file's
    folder ``base_dir`` when relative (None: the working directory), or a preset's name -- a
    name with neither a folder nor a YAML suffix (:func:`hearsee.config.names_a_file`) that
    is nothing in that folder. Returned spec: the file's absolute path, or the preset's name.
    The rule of the robot file's ``audio.array``: until 2026-12-07 a name that was no file
    beside a scenario or manifest was looked up in the working directory (:func:`load_array`):
    a file there named like the preset, or like the array file, was read instead (another
    array, without a word), and a folder named like the preset refused a scenario that did
    not name an array at all. ConfigError / InputFileError naming ``where``."""
    if not isinstance(spec, str) or not spec.strip():
        raise ConfigError(f"{where}: expected a preset name or a YAML path, got {spec!r:.60}")
    from hearsee.config import expand_path

    path = expand_path(spec, where)
    if base_dir is not None and not path.is_absolute():
        path = expand_path(Path(base_dir) / path, where)
    try:
        if path.exists():  # (a folder: load_array's InputFileError says so)
            path = path.absolute()
            return load_array(path), str(path)
        if names_a_file(spec):
            raise InputFileError(f"{path}: no such array file")
        return MicArray.from_preset(spec), spec
    except HearseeError as exc:
        raise type(exc)(f"{where}: {exc}") from None
