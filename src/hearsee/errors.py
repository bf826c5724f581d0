"""The exception types hearsee raises.

Every error the library raises on purpose derives from :class:`HearseeError`; the CLI turns any
of them into one line on stderr and exit code 2. Subclasses also derive from the closest builtin
(``ValueError``, ``FileNotFoundError``) so generic handlers keep working.
"""

from __future__ import annotations

import functools
from typing import Any


class HearseeError(Exception):
    """Base class of every error hearsee raises on purpose."""


class ConfigError(HearseeError, ValueError):
    """A configuration file or value is malformed (bad YAML, unknown or missing field)."""


class GeometryError(HearseeError, ValueError):
    """Degenerate or impossible geometry (coincident microphones, source at a sensor, ...)."""


class AudioInputError(HearseeError, ValueError):
    """Unusable audio: wrong channel count or sample rate, NaN/inf, silence, too short."""


class ImageInputError(HearseeError, ValueError):
    """Images that cannot be used: unreadable, wrong size or type, mismatched pair."""


class CalibrationError(HearseeError, ValueError):
    """Missing or unusable camera calibration (too few views, board not found, bad file)."""


class EstimationError(HearseeError, RuntimeError):
    """An estimate cannot be formed from the data given (no valid frames, no solution)."""


class InputFileError(HearseeError, FileNotFoundError):
    """A file the user named does not exist or cannot be read."""


class ClippingWarning(UserWarning):
    """The recording contains clipped samples; estimates may be biased."""


class TruncatedFileWarning(UserWarning):
    """The audio file ends before the length its header declares (a recording cut short, a
    copy interrupted); only the samples present are used."""


class InconsistentMeasurementWarning(UserWarning):
    """The measurements contradict each other (e.g. TDOAs of several head poses that no single
    source explains); the estimate should not be trusted."""


class InvertedPolarityWarning(UserWarning):
    """A microphone's signal seems inverted (a swapped wire, a phase-inverting preamplifier): its
    pairs correlate negatively, so their TDOAs -- and the direction -- are wrong."""


class ChannelSyncWarning(UserWarning):
    """Two channels seem out of sync (two sound cards, a dropped buffer, a driver's latency) or
    the array description understates their spacing: their averaged correlation peaks beyond
    the lag the described spacing allows, so their TDOAs -- and the direction -- are wrong."""


class DeadMicrophoneWarning(UserWarning):
    """A microphone's channel correlates with no other while the others hear a source (a
    microphone unplugged, broken or covered, its input left to the preamplifier's noise): every
    pair it belongs to has no TDOA, and the direction is missing or wrong."""


class TonalNoiseWarning(UserWarning):
    """The recording holds stationary tonal noise on every microphone (mains hum picked up by
    the wiring, a motor's or fan's whine): its frequencies were left out of the estimate."""


class MaskFitWarning(UserWarning):
    """A masked pair's level and phase differences fit its free-field model poorly (a
    reverberant room, strong noise, a source that moved during the recording, or a recording
    not made through this mask): the 360-degree azimuth and its front/back decision are
    unreliable."""


class DegenerateInputWarning(UserWarning):
    """The input is valid but degenerate for the task (stereo images that barely match, a flat
    thermal frame, image points outside the recording): the answer describes the input more
    than the scene."""


@functools.cache
def _regressor_not_fitted_error() -> type:
    from sklearn.exceptions import NotFittedError

    class RegressorNotFittedError(EstimationError, NotFittedError):
        """``predict`` of a learned mapping
        (:class:`hearsee.fusion.audiovisual.AudioVisualRegressor`,
        :class:`hearsee.audio.active.PoseItdMLP`) before ``fit``:
        hearsee's EstimationError and scikit-learn's ``NotFittedError`` at once
        (scikit-learn's tools and ``check_estimator`` recognise an unfitted estimator by the
        latter). Built on first use, so that importing hearsee's errors does not import
        scikit-learn."""

    RegressorNotFittedError.__module__ = __name__  # (pickled by name: hearsee.errors.X)
    RegressorNotFittedError.__qualname__ = "RegressorNotFittedError"
    return RegressorNotFittedError


def __getattr__(name: str) -> Any:
    if name == "RegressorNotFittedError":
        return _regressor_not_fitted_error()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
