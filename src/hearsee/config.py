"""Loading and validating YAML files (arrays, cameras, scenes, robots) with typed errors.

Every problem is raised as :class:`hearsee.errors.ConfigError` whose message names the file and
the field, e.g. ``robot.yaml: unknown key 'microphone' (expected one of: array, camera)``.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from hearsee.errors import ConfigError, InputFileError

__all__ = [
    "as_float_array", "check_keys", "load_yaml", "number", "require", "save_yaml", "to_jsonable",
    "to_plain",
]


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader reading ``1e9`` / ``5E-3`` as numbers: YAML 1.1's float needs a dot
    (``1.0e9``), so ``speed_of_sound: 1e9`` used to be the string '1e9' and its error
    "must be a number, got '1e9'" read like nonsense. The YAML 1.2 core schema's floats."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."))


def load_yaml(path: str | Path) -> dict[str, Any]:
    """Read a YAML mapping from ``path``; raise typed errors for missing files and bad YAML."""
    p = Path(path)
    if p.is_dir():
        raise InputFileError(f"{p}: is a directory, expected a YAML file")
    if not p.is_file():
        raise InputFileError(f"{p}: file not found")
    try:
        data = yaml.load(p.read_text(encoding="utf-8"), Loader=_Loader)  # noqa: S506 (safe)
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


def to_plain(obj: Any, *, json: bool = False) -> Any:
    """Convert numpy arrays and scalars, tuples and nested mappings to plain Python for YAML or
    JSON output. With ``json=True`` non-finite floats become None (JSON has no NaN)."""
    if isinstance(obj, Mapping):
        return {str(k): to_plain(v, json=json) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_plain(v, json=json) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_plain(obj.tolist(), json=json)
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        f = float(obj)
        return None if json and not math.isfinite(f) else f
    if isinstance(obj, np.str_):
        return str(obj)
    return obj


def to_jsonable(obj: Any) -> Any:
    """:func:`to_plain` for JSON: numpy -> Python, NaN/inf -> None."""
    return to_plain(obj, json=True)


def save_yaml(data: Mapping[str, Any], path: str | Path) -> None:
    """Write ``data`` as YAML (numpy arrays and scalars converted to lists and floats)."""
    Path(path).write_text(yaml.safe_dump(to_plain(dict(data)), sort_keys=False),
                          encoding="utf-8")


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


def as_float_array(value: Any, where: str,
                   shape: tuple[int | None, ...] | None = None) -> np.ndarray:
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


def number(d: Mapping[str, Any], key: str, default: float, where: str, lo: float | None = None,
           hi: float | None = None, integer: bool = False) -> float:
    """``d[key]`` (or ``default``) as a finite number within ``[lo, hi]``; ConfigError naming
    ``where.key`` otherwise. With ``integer=True`` the value must be whole and an int is
    returned."""
    v = d.get(key, default)
    if isinstance(v, np.integer | np.floating) and not isinstance(v, np.bool_):
        v = v.item()  # numpy scalars (e.g. from arrays) as their Python number
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise ConfigError(f"{where}.{key}: expected a number, got {v!r}")
    if integer and int(v) != v:
        raise ConfigError(f"{where}.{key}: expected a whole number, got {v!r}")
    if lo is not None and v < lo:
        raise ConfigError(f"{where}.{key}: must be >= {lo}, got {v}")
    if hi is not None and v > hi:
        raise ConfigError(f"{where}.{key}: must be <= {hi}, got {v}")
    return int(v) if integer else float(v)
