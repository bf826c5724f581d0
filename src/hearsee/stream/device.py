"""The live-audio backend, sounddevice (PortAudio), imported on first use.

One importer for every live path (``hearsee track --device``, ``hearsee run`` and its
``--dry-run``): the package is an optional extra and needs the system's PortAudio library, and
either missing is one :class:`~hearsee.errors.AudioInputError` naming what to install.
"""

from __future__ import annotations

from typing import Any

from hearsee.errors import AudioInputError

__all__ = ["import_sounddevice"]


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
