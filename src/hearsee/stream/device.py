"""The live-audio backend, sounddevice (PortAudio), imported on first use.

One importer for every live path (``hearsee track --device``, ``hearsee run`` and its
``--dry-run``): the package is an optional extra and needs the system's PortAudio library, and
either missing is one :class:`~hearsee.errors.AudioInputError` naming what to install.
"""

from __future__ import annotations

from typing import Any

from hearsee.errors import AudioInputError

__all__ = ["import_sounddevice", "input_devices"]


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
        devs = [dict(d) for d in sd.query_devices()]
        ins = [f"{d.get('index', k)} {d['name']!r} ({d['max_input_channels']} in)"
               for k, d in enumerate(devs) if d.get("max_input_channels", 0) > 0]
    except Exception:  # noqa: BLE001 - listing is best effort inside an error message
        return "(could not list devices)"
    return ", ".join(ins) if ins else "none"
