"""Loading and validating YAML files (arrays, cameras, scenes, robots) with typed errors.

Every problem is raised as :class:`hearsee.errors.ConfigError` whose message names the file and
the field, e.g. ``robot.yaml: unknown key 'microphone' (expected one of: array, camera)``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from hearsee.errors import ConfigError, InputFileError

__all__ = ["check_keys", "load_yaml", "require", "as_float_array", "save_yaml"]


def load_yaml(path: str | Path) -> dict[str, Any]:
    """Read a YAML mapping from ``path``; raise typed errors for missing files and bad YAML."""
    p = Path(path)
    if not p.is_file():
        raise InputFileError(f"{p}: file not found")
    try:
        data = yaml.safe_load(p.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{p}: not a text YAML file ({exc.reason})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or "invalid YAML"
        raise ConfigError(f"{p}: invalid YAML{where}: {problem}") from None
    if data is None:
        raise ConfigError(f"{p}: file is empty")
    if not isinstance(data, dict):
        raise ConfigError(f"{p}: expected a mapping at top level, got {type(data).__name__}")
    return data


def save_yaml(data: Mapping[str, Any], path: str | Path) -> None:
    """Write ``data`` as YAML (numpy arrays and scalars converted to lists and floats)."""

    def plain(v: Any) -> Any:
        if isinstance(v, np.ndarray):
            return v.tolist()
        if isinstance(v, np.generic):
            return v.item()
        if isinstance(v, Mapping):
            return {str(k): plain(x) for k, x in v.items()}
        if isinstance(v, list | tuple):
            return [plain(x) for x in v]
        return v

    Path(path).write_text(yaml.safe_dump(plain(dict(data)), sort_keys=False), encoding="utf-8")


def check_keys(data: Mapping[str, Any], allowed: Iterable[str], where: str) -> None:
    """Raise ConfigError naming the first key of ``data`` not in ``allowed``."""
    allowed = list(allowed)
    for key in data:
        if key not in allowed:
            raise ConfigError(
                f"{where}: unknown key {key!r} (expected one of: {', '.join(allowed)})"
            )


def require(data: Mapping[str, Any], key: str, where: str) -> Any:
    """Return ``data[key]`` or raise ConfigError saying the field is missing."""
    if key not in data:
        raise ConfigError(f"{where}: missing required key {key!r}")
    return data[key]


def as_float_array(value: Any, where: str, shape: tuple[int | None, ...] | None = None) -> np.ndarray:
    """Convert ``value`` to a finite float array, checking ``shape`` (None = any length)."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: expected numbers, got {value!r}") from None
    if shape is not None:
        if arr.ndim != len(shape) or any(
            s is not None and s != a for s, a in zip(shape, arr.shape, strict=True)
        ):
            want = "x".join("N" if s is None else str(s) for s in shape)
            raise ConfigError(f"{where}: expected shape {want}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ConfigError(f"{where}: values must be finite numbers")
    return arr
