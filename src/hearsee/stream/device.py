"""The live-audio backend, sounddevice (PortAudio), imported on first use.

One importer for every live path (``hearsee track --device``, ``hearsee run`` and its
``--dry-run``): the package is an optional extra and needs the system's PortAudio library, and
either missing is one :class:`~hearsee.errors.AudioInputError` naming what to install. One rule
for which device a name picks (:func:`resolve_input_device`) on every path too.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from hearsee.errors import AudioInputError, ConfigError, HearseeError

__all__ = ["import_sounddevice", "input_devices", "resolve_input_device"]


def import_sounddevice() -> Any:
    """The :mod:`sounddevice` module; AudioInputError when the package is not installed
    (ImportError) or cannot load the PortAudio library (OSError), the cause in parentheses."""
    try:
        import sounddevice
    except (ImportError, OSError) as exc:
        raise AudioInputError(
            f"live audio input needs the sounddevice package and the PortAudio library ({exc}):"
            " pip install 'hearsee[live]' (Debian/Ubuntu also: apt-get install libportaudio2)"
        ) from None
    return sounddevice


def input_devices(sd: Any) -> str:
    """The input devices of ``sd`` (``sounddevice.query_devices()``) for an error message, one
    wording on every live path: ``0 'Built-in Microphone' (2 in), 2 'USB 6ch Array' (6 in)``
    (index, name, input channels); ``none`` without any, ``(could not list devices)`` when the
    query itself fails (the listing only completes a message about another error)."""
    try:
        ins = [f"{d['index']} {d['name']!r} ({d['max_input_channels']} in)"
               for d in _device_list(sd) if d.get("max_input_channels", 0) > 0]
    except Exception:  # noqa: BLE001 - listing is best effort inside an error message
        return "(could not list devices)"
    return ", ".join(ins) if ins else "none"


def _device_list(sd: Any) -> list[dict[str, Any]]:
    """``sd.query_devices()`` as dicts, each with its ``index`` (PortAudio's position when
    the entry has none)."""
    out = []
    for k, d in enumerate(sd.query_devices()):
        d = dict(d)
        d.setdefault("index", k)
        out.append(d)
    return out


def resolve_input_device(sd: Any, spec: int | str | None, where: str = "audio.device",
                         error: type[HearseeError] = ConfigError) -> dict[str, Any]:
    """The input device (a dict with ``index``, ``name``, ``max_input_channels``, ...) named by
    ``spec``: an index, a name -- the device of exactly that name (case-insensitive), else the
    one device whose name contains it; a name in several devices' names is refused -- or None
    for the default input. The one rule of ``hearsee run`` (``audio.device``) and
    :class:`hearsee.stream.pipeline.DeviceSource` (``hearsee track --device``); PortAudio's own
    look-up took the first device containing the name, so the two could pick different devices.
    Raises ``error`` naming ``where`` and listing the available input devices."""
    if isinstance(spec, np.integer):
        spec = int(spec)
    if (spec is not None and not isinstance(spec, int | str)) or isinstance(spec, bool) \
            or (isinstance(spec, str) and not spec.strip()):
        raise error(f"{where}: expected a device index or name, got {spec!r}")
    try:
        devs = _device_list(sd)
    except (OSError, ValueError, getattr(sd, "PortAudioError", OSError)) as exc:
        raise error(f"{where}: cannot list the audio devices ({exc})") from None
    inputs = [d for d in devs if d.get("max_input_channels", 0) > 0]
    if spec is None:
        default = sd.default.device  # an [input, output] pair, or one value for both
        idx = default
        if not isinstance(default, str | int):
            try:
                idx = default[0]
            except (TypeError, IndexError, KeyError):
                idx = default
        if isinstance(idx, str):
            return resolve_input_device(sd, idx, where, error)
        if not isinstance(idx, int) or idx < 0 or idx >= len(devs):
            raise error(f"{where}: no default input device (available: "
                        f"{input_devices(sd)}); name one")
        dev = devs[idx]
    elif isinstance(spec, int):
        if not 0 <= spec < len(devs):  # (a negative index took a device from the list's end)
            raise error(f"{where}: no device with index {spec} (available: "
                        f"{input_devices(sd)})")
        dev = devs[spec]
    else:
        key = spec.lower()
        exact = [d for d in inputs if str(d["name"]).lower() == key]
        hits = exact or [d for d in inputs if key in str(d["name"]).lower()]
        if not hits:
            raise error(f"{where}: no input device named {spec!r} (available: "
                        f"{input_devices(sd)})")
        if len(hits) > 1:
            names = ", ".join(f"{d['index']} {d['name']!r}" for d in hits)
            raise error(f"{where}: {spec!r} matches several input devices ({names}); "
                        "use a longer name or the index")
        dev = hits[0]
    if dev.get("max_input_channels", 0) <= 0:
        raise error(f"{where}: device {dev['index']} {dev['name']!r} has no input "
                    f"channels (available: {input_devices(sd)})")
    return dev
