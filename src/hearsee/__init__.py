"""hearsee: ears and eyes for a mobile robot with very few sensors.

Sub-packages: ``hearsee.audio`` (microphone arrays, TDOA/ITD, localization, mask, active
sampling, tracking), ``hearsee.vision`` (calibration, stereo, human detection, thermal fusion),
``hearsee.learn`` (Neighborhood Linear Embedding), ``hearsee.fusion`` (microphones + camera),
``hearsee.sim`` (scenes and ground truth), ``hearsee.stream`` (real-time pipeline).
"""

from hearsee.errors import (
    AudioInputError,
    CalibrationError,
    ConfigError,
    EstimationError,
    GeometryError,
    HearseeError,
    ImageInputError,
    InputFileError,
)

__version__ = "0.1.0"

__all__ = [
    "AudioInputError",
    "CalibrationError",
    "ConfigError",
    "EstimationError",
    "GeometryError",
    "HearseeError",
    "ImageInputError",
    "InputFileError",
    "__version__",
]
