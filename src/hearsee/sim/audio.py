"""Simulated microphone-array recordings with their ground truth (behind ``hearsee simulate``).

:func:`simulate_recording` = source signal (:func:`hearsee.audio.signals.make_signal`) ->
propagation (:func:`render`: free field or a pyroomacoustics shoebox room) -> sensor noise ->
ground truth (:func:`ground_truth`). :func:`save_recording` writes the WAV (channel k =
microphone k) and the truth JSON next to it.

Frames: the source is given in the ARRAY frame (metres, x forward, y left, z up). In a room the
array origin sits at ``room["array_at"]`` (room coordinates, axes parallel to the walls; default:
the room centre).

Extending: masked arrays, moving heads (poses) and moving sources (trajectories) plug in at
:func:`render` (one propagation step for one static geometry) and at :func:`ground_truth`; keep
:func:`simulate_recording` the single entry point.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hearsee.audio.arrays import MicArray, load_array
from hearsee.audio.propagation import add_noise, check_snr_db, simulate_free_field, simulate_room
from hearsee.audio.signals import (
    SIGNAL_KINDS,
    hum_harmonics,
    mains_hum,
    make_signal,
    write_recording,
)
from hearsee.config import (
    finite_number,
    is_real,
    output_file,
    same_file,
    to_jsonable,
    true_or_false,
    whole_number,
    write_file,
)
from hearsee.errors import ConfigError, GeometryError, InputFileError
from hearsee.geometry import as_point, cart_to_sph

__all__ = [
    "EXAMPLE_RECORDING",
    "example_recording_path",
    "ground_truth",
    "normalize_room",
    "render",
    "save_recording",
    "simulate_recording",
]

#: File name of the bundled example recording (in ``hearsee/data/examples/``).
EXAMPLE_RECORDING = "three-mic-speech.wav"

_ROOM_KEYS = ("room_dim", "rt60", "array_at", "max_order")


def example_recording_path() -> Path:
    """Path of the bundled example: three-mic preset, female voice at azimuth 60 deg,
    elevation 10 deg, 2 m, shoebox room 6 x 5 x 3 m, RT60 0.3 s, SNR 20 dB, 16 kHz.

    Its ground truth is the ``.json`` file next to it.
    """
    p = Path(str(resources.files("hearsee") / "data" / "examples" / EXAMPLE_RECORDING))
    if not p.is_file():
        raise InputFileError(
            f"{p}: bundled example recording missing; regenerate it with "
            "examples/make_example_recording.py"
        )
    return p


#: Highest sample rate the simulators accept, Hz (the highest common audio-interface rate)
MAX_SIM_FS_HZ = 384_000


def check_sim_fs(fs: float | None) -> int:
    """``fs`` as a whole number of Hz within [:data:`hearsee.audio.tdoa.MIN_FS_HZ`,
    :data:`MAX_SIM_FS_HZ`] (the rates hearsee analyses), else a ConfigError."""
    from hearsee.audio.tdoa import MIN_FS_HZ

    if not is_real(fs) or fs <= 0 or int(round(fs)) != fs:  # (a string: numpy's TypeError)
        raise ConfigError(f"sample rate must be a positive whole number of Hz, got {fs!r}")
    if not MIN_FS_HZ <= fs <= MAX_SIM_FS_HZ:
        raise ConfigError(f"sample rate must be within {MIN_FS_HZ:g}-{MAX_SIM_FS_HZ} Hz, got "
                          f"{fs:g} Hz")
    return int(fs)


def _check_array(array: MicArray) -> None:
    """GeometryError unless ``array`` is a MicArray (a preset name or path reached
    ``array.mask`` / ``array.tdoa``: a builtin AttributeError; :func:`simulate_recording` is
    the entry point that loads them)."""
    if not isinstance(array, MicArray):
        raise GeometryError(f"array: expected a MicArray (hearsee.audio.arrays.load_array), "
                            f"got {type(array).__name__}")


def _mic_positions(array: MicArray, mic_positions: ArrayLike) -> NDArray:
    """``mic_positions`` as a finite float array of ``array.positions``' shape (one row per
    microphone), else a GeometryError."""
    try:
        mp = np.asarray(mic_positions, dtype=float)
    except (TypeError, ValueError):
        mp = None
    if mp is None or mp.shape != array.positions.shape or not np.all(np.isfinite(mp)):
        shape = "not numeric" if mp is None else f"shape {mp.shape}"
        raise GeometryError(f"mic_positions must be finite {array.n_mics} x 3 (one row per "
                            f"microphone of {array.name!r}), got {shape}")
    return mp


def normalize_room(room: Mapping[str, Any] | None) -> dict[str, Any] | None:
    """Validate a room mapping and fill its defaults.

    Keys: ``room_dim`` [L, W, H] m (required), ``rt60`` s (required; 0 = anechoic),
    ``array_at`` [x, y, z] m in room coordinates (default: the room centre), ``max_order``
    (optional image-source order override). Returns a plain JSON-able dict or None.
    """
    if room is None:
        return None
    if not isinstance(room, Mapping):
        raise ConfigError(f"room must be a mapping with keys {', '.join(_ROOM_KEYS)}")
    for key in room:
        if key not in _ROOM_KEYS:
            raise ConfigError(
                f"room: unknown key {key!r} (expected one of: {', '.join(_ROOM_KEYS)})"
            )
    if "room_dim" not in room:
        raise ConfigError("room: missing 'room_dim' ([length, width, height] in metres)")
    if "rt60" not in room or room["rt60"] is None:
        raise ConfigError("room: missing 'rt60' (reverberation time in seconds; 0 = anechoic)")
    dim = as_point(room["room_dim"], "room_dim")
    if np.any(dim <= 0):
        raise GeometryError(
            f"room_dim must be three positive lengths in metres, got {dim.tolist()}"
        )
    # (float() read true as 1 s and "0.3" as 0.3 s; NaN reached the room simulation)
    rt60 = finite_number("room: rt60 (seconds; 0 = anechoic)", room["rt60"], 0.0)
    at = room.get("array_at")
    out: dict[str, Any] = {
        "room_dim": dim.tolist(),
        "rt60": rt60,
        "array_at": (dim / 2).tolist() if at is None else as_point(at, "array_at").tolist(),
    }
    order = room.get("max_order")
    if order is not None:
        ok = isinstance(order, (int, np.integer, float)) and not isinstance(order, bool)
        if not (ok and float(order).is_integer() and order >= 0):
            raise ConfigError(f"room: max_order must be a non-negative integer, got {order!r}")
        out["max_order"] = int(order)
    return out


def render(signal: ArrayLike, fs: float, array: MicArray, source: ArrayLike,
           room: Mapping[str, Any] | None = None,
           mic_positions: ArrayLike | None = None, far_field: bool = False) -> NDArray:
    """Noise-free microphone signals ``(n_mics, n)`` for one static geometry.

    ``source`` and ``mic_positions`` (default ``array.positions``) are in the array frame;
    ``room`` as in :func:`normalize_room` (None = free field: near-field spherical waves, or a
    plane wave from the source's direction with ``far_field=True``). Sample 0 is the emission
    time, so direct-path TDOAs equal ``MicArray.tdoa(source)`` (``tdoa_far`` in far field).
    """
    _check_array(array)
    room = normalize_room(room)
    src = as_point(source, "source")
    far_field = true_or_false("far_field", far_field)  # ("no" with a room: "free field only")
    if mic_positions is not None:
        mic_positions = _mic_positions(array, mic_positions)
    if far_field and room is not None:
        raise ConfigError("far_field applies to free field only; omit the room or far_field")
    if array.mask is not None:  # masked two-microphone array: the mask's diffraction (BEM)
        from hearsee.audio.mask import simulate_masked, simulate_masked_room

        if mic_positions is not None:
            raise ConfigError(f"array {array.name!r} has a mask: masked arrays are simulated "
                              "with the head fixed (no turned microphones)")
        if room is None:
            return simulate_masked(signal, fs, array, src, far_field=far_field)
        return simulate_masked_room(signal, fs, array, src, room["room_dim"], room["rt60"],
                                    room["array_at"], max_order=room.get("max_order"))
    if room is None:
        mics = array.positions if mic_positions is None else mic_positions
        return simulate_free_field(signal, fs, mics, src, speed_of_sound=array.speed_of_sound,
                                   far_field=far_field)
    return simulate_room(signal, fs, array, src, room["room_dim"], room["rt60"],
                         room["array_at"], mic_positions=mic_positions,
                         max_order=room.get("max_order"))


def ground_truth(array: MicArray, source: ArrayLike,
                 mic_positions: ArrayLike | None = None,
                 far_field: bool = False) -> dict[str, Any]:
    """Geometric truth of a static source in the array frame.

    Returns ``source_m`` [x, y, z] m, ``azimuth_deg``, ``elevation_deg``, ``distance_m`` (from
    the array-frame origin) and ``tdoa_s`` {"i-j": t_i - t_j seconds} for every pair (exact
    near-field values, ``MicArray.tdoa``, or plane-wave values, ``MicArray.tdoa_far``, with
    ``far_field=True``; with ``mic_positions`` for those positions). A source at the origin
    has no direction: azimuth and elevation are None (and ``far_field`` a GeometryError).
    A masked array (its head fixed) adds ``mask_itd_s`` {"0-1": s}: the ITD its mask gives
    the source (:meth:`hearsee.audio.mask.MaskModel.itd_at`) -- what ``hearsee localize``
    measures there, unlike the free-field ``tdoa_s`` of the bare microphones (a source at
    26.6 deg, 1.1 m away: 195 us free field, 298 us through ``mask2-asym``; added 2026-12-04).
    """
    _check_array(array)
    src = as_point(source, "source")
    # ("no" is truthy: the plane-wave TDOAs of a near source were its truth)
    far_field = true_or_false("far_field", far_field)
    geo = array if mic_positions is None else MicArray(
        _mic_positions(array, mic_positions), array.speed_of_sound, array.name)
    az, el, r = cart_to_sph(src)
    at_origin = not r > 0
    tdoa = geo.tdoa_far(src) if far_field else geo.tdoa(src)  # far field at the origin: error
    truth = {
        "source_m": src.tolist(),
        "azimuth_deg": None if at_origin else float(np.degrees(az)),
        "elevation_deg": None if at_origin else float(np.degrees(el)),
        "distance_m": float(r),
        "tdoa_s": {lab: float(t) for lab, t in zip(array.pair_labels, tdoa, strict=True)},
    }
    if array.mask is not None and mic_positions is None:
        from hearsee.audio.mask import MaskModel

        itd = MaskModel(array).itd_at(src, far_field)[0]
        truth["mask_itd_s"] = {array.pair_labels[0]: float(itd)}
    return truth


def simulate_recording(
    array: MicArray | str | Path,
    source: ArrayLike,
    signal: str | Path = "noise",
    duration_s: float = 2.0,
    fs: float = 16000,
    snr_db: float | None = None,
    room: Mapping[str, Any] | None = None,
    seed: int | None = 0,
    mic_positions: ArrayLike | None = None,
    far_field: bool = False,
    hum_db: float | None = None,
    hum_hz: float = 50.0,
) -> tuple[NDArray, dict[str, Any]]:
    """Simulate what ``array`` records from a static source, with its ground truth.

    Parameters
    ----------
    array : MicArray, preset name or YAML path
    source : array (3,)
        Source position in the array frame, metres.
    signal : ``"noise"``, ``"male"``, ``"female"`` or an audio file path
        See :func:`hearsee.audio.signals.make_signal`.
    duration_s, fs : float
        Length in seconds and sample rate in Hz.
    snr_db : float, optional
        Per-channel SNR of white sensor noise in dB, relative to the mean received signal power,
        within [:data:`~hearsee.audio.propagation.MIN_SNR_DB`,
        :data:`~hearsee.audio.propagation.MAX_SNR_DB`] (None = no noise).
    room : mapping, optional
        ``{"room_dim": [L, W, H], "rt60": s, "array_at": [x, y, z]}`` (see
        :func:`normalize_room`); None = free field.
    seed : int
        Seeds the signal and the noise.
    mic_positions : array (n_mics, 3), optional
        Microphone positions in the array frame overriding ``array.positions`` (a turned
        head, e.g. from ``hearsee.geometry.mic_positions_at``); the truth uses them too.
    far_field : bool
        Free field only: a plane wave from the source's direction (equal amplitudes, truth
        TDOAs from ``MicArray.tdoa_far``).
    hum_db : float, optional
        Mains hum picked up by the wiring (:func:`~hearsee.audio.signals.mains_hum`: every
        harmonic of ``hum_hz`` up to 2.5 kHz, the same waveform on every channel) at this
        level in dB relative to the mean received signal power, -60 to 60; None (default):
        none.
    hum_hz : float
        The hum's fundamental, Hz (50 or 60 where the mains are).

    Returns
    -------
    x : array (n_mics, n)
        The recording, channel k = microphone k (not normalised; see :func:`save_recording`).
    truth : dict
        JSON-able: ``source_m``, ``azimuth_deg``, ``elevation_deg``, ``distance_m``,
        ``tdoa_s`` {"i-j": s}, ``fs``, ``duration_s``, ``array`` (``MicArray.to_dict``),
        ``signal``, ``snr_db``, ``room`` (filled in, or None), ``seed``; with hum ``hum_db``
        and ``hum_hz``.

    Examples
    --------
    >>> x, truth = simulate_recording("two-mic", [1.0, 1.0, 0.0], duration_s=0.1)
    >>> x.shape, round(truth["azimuth_deg"])
    ((2, 1600), 45)
    """
    array = load_array(array)
    src = as_point(source, "source")
    fs = check_sim_fs(fs)
    snr_db = check_snr_db(snr_db)  # (before the simulation: add_noise checks it at its end)
    if hum_db is not None:  # (before the simulation, as the SNR)
        hum_db = finite_number("hum_db", hum_db, -60.0, 60.0)
        hum_hz = finite_number("hum_hz", hum_hz, 0.0, lo_open=True)
        hum_harmonics(hum_hz, fs)  # (a fundamental without a harmonic below fs / 2)
    room = normalize_room(room)
    if seed is not None:  # (-1 or 1.5 raised numpy's ValueError / TypeError)
        seed = whole_number("seed", seed, lo=0)
    if mic_positions is not None:  # (the wrong count raised zip()'s ValueError in the truth)
        mic_positions = _mic_positions(array, mic_positions)
    rng = np.random.default_rng(seed)
    s = make_signal(signal, duration_s, fs, rng)
    clean = render(s, fs, array, src, room, mic_positions=mic_positions, far_field=far_field)
    x = add_noise(clean, snr_db, rng)
    if hum_db is not None:
        hum = mains_hum(duration_s, fs, hum_hz, rng)[: x.shape[1]]
        x = x + hum * np.sqrt(np.mean(clean**2) * 10 ** (hum_db / 10.0))
    truth = ground_truth(array, src, mic_positions=mic_positions, far_field=far_field)
    if mic_positions is not None:
        truth["mic_positions"] = np.asarray(mic_positions, dtype=float).tolist()
    if far_field:
        truth["far_field"] = True
    if hum_db is not None:
        truth.update({"hum_db": float(hum_db), "hum_hz": float(hum_hz)})
    truth.update({
        "fs": fs,
        "duration_s": float(duration_s),
        "array": array.to_dict(),
        "signal": str(signal) if str(signal) in SIGNAL_KINDS else str(Path(signal)),
        "snr_db": None if snr_db is None else float(snr_db),
        "room": room,
        "seed": seed,  # (whole_number above: a plain int, JSON-able also from a numpy seed)
    })
    return x, truth


def save_recording(out: str | Path, x: ArrayLike, truth: Mapping[str, Any],
                   subtype: str = "FLOAT", peak: float = 0.5,
                   protect: list[str | Path] | None = None) -> tuple[Path, Path]:
    """Write ``x`` as ``OUT.wav`` (scaled to ``peak`` full scale) and the truth as ``OUT.json``.

    The common gain applied to all channels is stored as ``truth["gain"]`` (it does not change
    any TDOA). ``protect`` lists input files that must not be overwritten. Returns both paths.
    ``truth`` must be a mapping with the sample rate ``"fs"`` (Hz) the WAV is written at
    (ConfigError: without it, a builtin KeyError).
    """
    if not isinstance(truth, Mapping) or "fs" not in truth:
        raise ConfigError("truth must be a mapping that gives the sample rate 'fs' (Hz) of the "
                          f"recording, got {type(truth).__name__} with keys "
                          f"{list(truth)[:8] if isinstance(truth, Mapping) else None}")
    wav = Path(out)
    if wav.suffix.lower() not in (".wav", ".flac"):
        raise ConfigError(f"{wav}: output must end in .wav (or .flac)")
    js = wav.with_suffix(".json")
    # (the WAV first, so that a missing folder is named as the path the user gave; the truth
    # beside it said "is a directory" where every other output check says "is a folder")
    output_file(wav)
    output_file(js)
    y = np.asarray(x, dtype=float)
    m = float(np.max(np.abs(y))) if y.size else 0.0
    # (-0.5 inverted the polarity, 0 wrote silence, the text "0.5" raised numpy's TypeError)
    if not (is_real(peak) and np.isfinite(peak) and 0 < peak <= 1):
        raise ConfigError(f"peak must be in (0, 1] of full scale, got {peak}")
    gain = peak / m if m > 0 else 1.0
    for q in protect or []:
        if same_file(q, js):
            raise ConfigError(f"{js}: refusing to overwrite the input file {q}; "
                              "choose another output path")
    if wav.suffix.lower() == ".flac" and subtype.upper() in ("FLOAT", "DOUBLE"):
        subtype = "PCM_24"  # FLAC stores integers only
    doc = {**truth, "gain": gain, "wav": wav.name}
    text = json.dumps(to_jsonable(doc), indent=2) + "\n"  # before the WAV: both or neither
    write_recording(wav, y * gain, truth["fs"], subtype=subtype, protect=protect)
    write_file(js, text)  # (replaced once complete, as the WAV: config.replacing)
    return wav, js
