"""Loading and validating YAML files (arrays, cameras, scenes, robots) with typed errors.

Every problem is raised as :class:`hearsee.errors.ConfigError` whose message names the file and
the field, e.g. ``robot.yaml: unknown key 'microphone' (expected one of: array, camera)``.
"""

from __future__ import annotations

import contextlib
import inspect
import math
import os
import re
import secrets
import stat
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
import yaml

from hearsee.errors import ConfigError, InputFileError

__all__ = [
    "YamlDumper", "all_real", "as_float_array", "as_rng", "check_keys", "check_rng",
    "check_settings",
    "expand_path", "finite_number", "input_file", "is_real", "load_yaml", "names_a_file", "number",
    "object_entries", "open_replaced", "output_file", "refused_name", "replacing", "require",
    "save_yaml", "time_limit", "to_jsonable", "to_plain", "whole_number", "write_file",
    "write_into",
]


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader reading ``1e9`` / ``5E-3`` as numbers: YAML 1.1's float needs a dot
    (``1.0e9``), so ``speed_of_sound: 1e9`` used to be the string '1e9' and its error
    "must be a number, got '1e9'" read like nonsense. The YAML 1.2 core schema's floats.

    A key given twice in one mapping is refused (:meth:`flatten_mapping`): PyYAML kept the
    last silently, so a second ``head:`` block dropped every field of the first."""

    def __init__(self, stream: Any) -> None:
        super().__init__(stream)
        self._checked: set[int] = set()  # ids of the mapping nodes checked for duplicates

    def flatten_mapping(self, node: yaml.MappingNode) -> None:
        """Check the keys written in ``node`` (before a merge ``<<`` adds its keys, which a
        key written there may override) once, then merge as PyYAML does."""
        if id(node) not in self._checked:
            self._checked.add(id(node))
            self._refuse_duplicate_keys(node)
        super().flatten_mapping(node)

    def _refuse_duplicate_keys(self, node: yaml.MappingNode) -> None:
        """A ConstructorError at the second of two equal keys of ``node``, naming the key and
        the line of the first (load_yaml reports it with the file and the line)."""
        first: dict[Any, Any] = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue
            key = self.construct_object(key_node)
            try:
                seen = first.setdefault(key, key_node)
            except TypeError:  # (an unhashable key: PyYAML's own error says so)
                continue
            if seen is not key_node:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r} (first given at line "
                    f"{seen.start_mark.line + 1}; a key may be given once)",
                    key_node.start_mark)


_EXPONENT_FLOAT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$")
_Loader.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT_FLOAT,
                              list("-+0123456789."))


class YamlDumper(yaml.SafeDumper):
    """PyYAML's safe dumper with :class:`_Loader`'s extra float rule: a string that reader
    would take for a number (``"2e5"``, ``"1E6"``) is written quoted. With the plain
    SafeDumper a camera named "2e5" was saved unquoted and loaded back as 200000.0."""


YamlDumper.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT_FLOAT,
                                 list("-+0123456789."))


def as_path(path: Any, what: str = "path") -> Path:
    """``path`` as a Path when it is a string or a path-like object, else InputFileError
    naming ``what`` (Path() raised its builtin TypeError on a number or None). The type check
    of :func:`input_file`, :func:`output_file` and every reader that looks at a path's suffix
    before it opens the file."""
    if not isinstance(path, str | os.PathLike) or (isinstance(path, str) and not path):
        raise InputFileError(f"{what} must be a file name, got {path!r:.60}")
    return Path(path)


def input_file(path: str | Path, kind: str = "file", hint: str = "") -> Path:
    """``path`` as a Path when it names something to read, else InputFileError: ``"P: is a
    folder, expected a <kind>"`` for a folder, ``"P: <kind> not found<hint>"`` when nothing is
    there (``kind`` e.g. "trajectory file", ``hint`` e.g. " (create one with ...)").

    The one check of hearsee's input files (YAML, audio, captures, calibration, images,
    thermal arrays, trajectories, videos, image points): most said "not found" for a folder.
    A file that exists but is not a regular one (a FIFO, ``/dev/stdin``) is left to the
    reader, whose own typed error reports what it cannot read."""
    p = as_path(path, f"the {kind}'s path")
    with refused_name(p):
        if p.is_dir():
            article = "an" if kind[:1].lower() in "aeiou" else "a"
            raise InputFileError(f"{p}: is a folder, expected {article} {kind}")
        if not p.exists():
            raise InputFileError(f"{p}: {kind} not found{hint}")
    return p


def _shown(name: str) -> str:
    """A path's text for a message, cut to 60 characters (a name the system refuses may be
    thousands long)."""
    return name if len(name) <= 60 else name[:57] + "..."


def expand_path(path: str | Path, what: str, error: type[Exception] = ConfigError) -> Path:
    """``path`` with a leading ``~`` / ``~user`` expanded, as a Path the system can look at,
    else ``error`` naming ``what``: a NUL character (os.stat's "embedded null byte"
    ValueError), a ``~user`` without a home folder (pathlib's RuntimeError) and a name the
    system refuses (too long: an OSError) were tracebacks of the robot file's and the
    scenario's paths."""
    text = str(path)
    shown = _shown(text)
    if "\0" in text:
        raise error(f"{what}: {shown!r} holds a NUL character: not a file name")
    try:
        p = Path(text).expanduser()
    except RuntimeError:
        raise error(f"{what}: {shown!r}: no such user's home folder") from None
    with refused_name(text, what, error):
        p.exists()
    return p


@contextlib.contextmanager
def refused_name(path: str | Path, what: str | None = None,
                 error: type[Exception] = InputFileError) -> Iterator[None]:
    """An OSError of looking at ``path`` (a name too long for the system: Path.is_dir and
    exists raise ENAMETOOLONG rather than answer False) as ``error``, prefixed by ``what``
    when given, its name cut to 60 characters: a bare OSError from the library before."""
    try:
        yield
    except InputFileError:  # (one of the checks' own: an OSError too)
        raise
    except OSError as exc:
        where = "" if what is None else f"{what}: "
        raise error(f"{where}{_shown(str(path))}: the system refuses this path "
                    f"({exc.strerror or exc})") from None


def same_file(a: str | Path, b: str | Path) -> bool:
    """Whether paths ``a`` and ``b`` name one file: the same inode where both exist (hard
    links, symlinks, ``..``), else the same resolved path. The one test behind every "refusing
    to overwrite an input file" (a hard link to an input passed the resolved-path test and
    was overwritten)."""
    a, b = Path(a), Path(b)
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return a.resolve() == b.resolve()


def output_file(path: str | Path) -> Path:
    """``path`` as a Path when a file can be written there, else InputFileError: ``"P: is a
    folder, expected an output file name"`` for a folder, ``"P: folder D does not exist"`` or
    ``"P: D is not a folder"`` for its parent ``D``, and ``"P: the file is not writable"`` /
    ``"P: folder D is not writable"`` where the system would refuse to write it. The
    counterpart of :func:`input_file`: the check of an output path made before the work
    that ends by writing it (the CLI's ``refuse_overwrite``, ``save_wav``, the robot's
    exports, ``write_image`` and the simulator's ground-truth file)."""
    p = as_path(path, "the output path")
    with refused_name(p):
        if p.is_dir():
            raise InputFileError(f"{p}: is a folder, expected an output file name")
        if not p.parent.is_dir():
            raise InputFileError(f"{p}: folder {p.parent} does not exist"
                                 if not p.parent.exists() else f"{p}: {p.parent} is not a folder")
        # (a PermissionError came only once the work was done, e.g. after a whole evaluation)
        if p.exists() and not os.access(p, os.W_OK):
            raise InputFileError(f"{p}: the file is not writable")
        if not p.exists() and not os.access(p.parent, os.W_OK | os.X_OK):
            raise InputFileError(f"{p}: folder {p.parent} is not writable")
        if p.is_symlink() and not p.exists():
            # (a dangling link: the output is made at its target, :func:`replacing`; a target
            # in a missing folder passed here and failed once the work was done -- `hearsee
            # eval -o` after the whole evaluation, until 2026-12-07)
            real = Path(os.path.realpath(p))
            if not real.parent.is_dir():
                raise InputFileError(f"{p}: links to {real}, whose folder {real.parent} "
                                     "does not exist")
            if not os.access(real.parent, os.W_OK | os.X_OK):
                raise InputFileError(f"{p}: links to {real}, whose folder {real.parent} "
                                     "is not writable")
    return p


def written_through(path: str | Path) -> bool:
    """Whether an output at ``path`` is written through (appended to) rather than replaced:
    it exists (after following symlinks) and is no regular file -- a FIFO, a pipe such as
    ``/dev/stdout`` in ``hearsee eval -o /dev/stdout | jq``, a device such as ``/dev/null``
    -- or it is the file this process's standard output or error goes to (``-o /dev/stdout
    > results.json``: replaced, the file the shell had opened was unlinked and what the
    command printed afterwards was lost; ``>>`` had its earlier lines cut). Such a target
    holds nothing the command would destroy, so the CLI's ``--force`` rule does not apply to
    it (``refuse_overwrite``), and :func:`replacing` writes into it."""
    try:  # (os.stat follows /dev/stdout -> /proc/self/fd/1 -> "pipe:[N]", which realpath
        st = os.stat(path)  # cannot: it made a nonexistent path of it)
    except (OSError, ValueError):
        return False
    if stat.S_ISDIR(st.st_mode):
        return False
    return not stat.S_ISREG(st.st_mode) or _standard_stream_fd(st) is not None


def goes_to_stdout(path: str | Path) -> bool:
    """Whether writing ``path`` writes what this process's standard output goes to:
    ``/dev/stdout``, or the pipe, device or file the shell connected it to (``--mcap
    /dev/stdout > run.mcap``)."""
    try:
        return os.path.samestat(os.stat(path), os.fstat(1))
    except (OSError, ValueError):  # (no such file, or a closed standard output)
        return False


def _standard_stream_fd(st: os.stat_result) -> int | None:
    """1 or 2 when the file of ``st`` is the one this process's standard output or error
    goes to (a regular file the shell opened: ``> results.json``), else None."""
    if not stat.S_ISREG(st.st_mode):  # (a pipe or device has no offset to share)
        return None
    for fd in (1, 2):
        try:
            if os.path.samestat(st, os.fstat(fd)):
                return fd
        except OSError:  # (a closed standard stream)
            continue
    return None


@contextlib.contextmanager
def replacing(path: str | Path) -> Iterator[Path]:
    """A temporary file name beside ``path`` (its folder: the same file system) for an output
    to write instead of ``path``; when the block ends without error the file replaces
    ``path`` in one step (``os.replace``, keeping the permissions of a file it replaces),
    and on any error it is removed and ``path`` is left as it was. An output written in place
    that failed part way (a frame an export could not describe, a full disk, Ctrl-C)
    truncated the previous file and left a corrupt one. A symlink's target is replaced, as
    writing through it did. A target :func:`written_through` names -- a FIFO another
    program reads, a device such as ``/dev/null``, the file standard output goes to -- is
    yielded itself and written through (appended, :func:`open_replaced`): until 2026-12-02
    the robot's exports replaced it by a regular file (``--mcap /dev/null --force`` run as
    root turned the system's /dev/null into a 20 MB file; a pipe's reader got nothing). The
    temporary name ends in ``.tmp`` (a writer that picks its format by the suffix must be
    told the format). The one rule of the robot's exports, its report folder
    and ``hearsee eval -o`` (moved here from hearsee.robot.export on 2026-12-02). A ``path``
    that is no file name (None, a number) is InputFileError (:func:`as_path`; os.stat's
    builtin TypeError until 2026-12-03)."""
    path = as_path(path, "the output path")
    if written_through(path):  # (opened by its own name: a pipe's realpath is no path)
        yield Path(path)
        return
    target = Path(os.path.realpath(path))
    tmp = target.with_name(f".{target.name}.{os.getpid()}-{secrets.token_hex(4)}.tmp")
    try:
        yield tmp
        if target.exists():
            os.chmod(tmp, stat.S_IMODE(target.stat().st_mode))
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def write_file(path: str | Path, data: str | bytes) -> Path:
    """Write ``data`` (text as UTF-8, or bytes) to ``path`` through :func:`replacing`: an
    existing file is replaced only once the new one is complete (a FIFO or device is written
    through). Returns ``path``; InputFileError naming it when the system refuses the write."""
    with replacing(path) as tmp:
        write_into(tmp, data, path)
    return Path(path)


def open_replaced(dest: Path) -> BinaryIO:
    """``dest``, the file :func:`replacing` yielded, opened for writing bytes: ``"xb"`` for
    the fresh temporary file (nothing else may have made it), ``"ab"`` where the target is
    written through (a FIFO, a device, the file standard output goes to: appended, as the
    command's own printing is). The one rule of every output written through
    :func:`replacing` as a stream (:func:`write_into`, the MCAP export, images). InputFileError
    for a ``dest`` that is no file name (:func:`as_path`: None was a builtin AttributeError)."""
    dest = as_path(dest, "the output file")
    try:
        fd = _standard_stream_fd(os.stat(dest))
    except (OSError, ValueError):
        fd = None
    if fd is not None:
        # (through the standard stream's own file description, sharing its offset: opened
        # anew, "ab" wrote at the end while the stream's offset stayed where it was, and what
        # the command printed afterwards -- `hearsee eval -o /dev/stdout > results.json`: the
        # summary -- overwrote the start of the file, the MCAP export's header likewise;
        # until 2026-12-07)
        import sys

        with contextlib.suppress(Exception):  # (what Python buffered goes first)
            (sys.stdout if fd == 1 else sys.stderr).flush()
        return os.fdopen(os.dup(fd), "ab")
    return open(dest, "ab" if dest.exists() else "xb")


def write_into(dest: Path, data: str | bytes, name: str | Path) -> None:
    """Write ``data`` (text as UTF-8, or bytes) into ``dest``, the file :func:`replacing`
    yielded for the output ``name``: a fresh temporary file, or the FIFO/device written
    through. A write the system refuses (a full disk, a file size limit) is InputFileError
    naming ``name``, the user's path, not the temporary file (whose OSError named nothing).
    ``data`` that is neither text nor bytes (None: a builtin TypeError) is ConfigError naming
    ``name``, raised before ``dest`` is opened."""
    if not isinstance(data, str | bytes | bytearray | memoryview):
        raise ConfigError(f"{name}: the data to write must be text or bytes, got "
                          f"{type(data).__name__}")
    try:
        with open_replaced(dest) as fh:
            fh.write(data.encode("utf-8") if isinstance(data, str) else data)
    except OSError as exc:
        raise InputFileError(f"{name}: cannot write ({exc.strerror or exc})") from None


def names_a_file(spec: str) -> bool:
    """Whether an array spec (``--array``, :func:`hearsee.audio.arrays.load_array`, the robot
    file's ``audio.array``, a scenario's ``robot.array``) names a file rather than a preset:
    it has a folder or a YAML suffix, in any case (``.yaml``, ``.yml``, ``.YAML``, ...).
    Preset names have neither. In the robot file and a scenario a file name is looked up next
    to that file, never in the working directory. ``spec``: text or a path-like object, else
    ConfigError (None was a builtin TypeError), as :func:`hearsee.audio.arrays.load_array`
    says for an array spec of any other kind."""
    if not isinstance(spec, str | os.PathLike):
        raise ConfigError(f"array: expected a preset name or a YAML path, got "
                          f"{type(spec).__name__}")
    spec = os.fspath(spec)
    if isinstance(spec, bytes):
        spec = os.fsdecode(spec)
    return "/" in spec or "\\" in spec or spec.lower().endswith((".yaml", ".yml"))


def load_yaml(path: str | Path) -> dict[str, Any]:
    """Read a YAML mapping from ``path``; raise typed errors for missing files and bad YAML."""
    p = input_file(path, "YAML file")
    try:
        data = yaml.load(p.read_text(encoding="utf-8"), Loader=_Loader)  # noqa: S506 (safe)
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{p}: not a text YAML file ({exc.reason})") from None
    except RecursionError:  # (PyYAML's parser recurses per level: a builtin error escaped)
        raise ConfigError(f"{p}: invalid YAML: nested too deeply") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or "invalid YAML"
        raise ConfigError(f"{p}: invalid YAML{where}: {problem}") from None
    except OSError as exc:  # (e.g. no read permission: a builtin PermissionError before)
        raise InputFileError(f"{p}: cannot be read ({exc.strerror or exc})") from None
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
    """Write ``data`` as YAML (numpy arrays and scalars converted to lists and floats) that
    :func:`load_yaml` reads back as written (:class:`YamlDumper`: text such as "2e5" quoted;
    the plain safe dumper wrote it bare and it came back as the number 200000.0)."""
    # (replaced once complete, :func:`replacing`: written in place, a write that failed part
    # way truncated the earlier file)
    data = _mapping(data, f"{path}: the data to save as YAML")
    write_file(path, yaml.dump(to_plain(dict(data)), Dumper=YamlDumper, sort_keys=False))


def name_text(value: Any, where: str) -> str:
    """A file's ``name:`` field as text: a string, or a number written as one (``name: 7``);
    ConfigError naming ``where`` for a list, a mapping or a bool (printed as the name until
    2026-12-03: "hearsee localize ([1, 2], phat)"). The one rule of array YAMLs and
    scenarios."""
    if isinstance(value, bool) or not isinstance(value, str | int | float):
        raise ConfigError(f"{where}: name must be text, got {type(value).__name__} "
                          f"{value!r:.40}")
    return str(value)


def _mapping(data: Any, where: str) -> Mapping[str, Any]:
    """``data`` when it is a mapping, else ConfigError "``where``: expected a mapping, got
    <type>": the one check of the mapping :func:`check_keys`, :func:`require`, :func:`number`
    and :func:`save_yaml` take (None was a builtin TypeError or AttributeError in each)."""
    if not isinstance(data, Mapping):
        raise ConfigError(f"{where}: expected a mapping, got {type(data).__name__}")
    return data


def check_settings(target: Any, params: Iterable[str], skip: Iterable[str] = (),
                   error: type[Exception] = ConfigError) -> None:
    """An ``error`` naming the first of ``params`` (setting names, in their order) that the
    function or class ``target`` takes no keyword of (``skip``: its keywords the caller sets
    itself), with the ones it takes; a misspelt setting passed on as ``**kwargs`` was the
    builtin TypeError of the call."""
    skip = set(skip)
    known = [n for n in inspect.signature(target).parameters if n != "self" and n not in skip]
    for key in params:
        if key not in known:
            raise error(f"unknown {target.__name__} setting {key!r} (expected one of: "
                        f"{', '.join(known)})")


def check_keys(data: Mapping[str, Any], allowed: Iterable[str], where: str) -> None:
    """Raise ConfigError naming the first key of ``data`` not in ``allowed`` (key names), or
    ``where`` when ``data`` is no mapping or ``allowed`` no collection of names."""
    if isinstance(allowed, str | bytes) or not isinstance(allowed, Iterable):
        raise ConfigError(f"{where}: the allowed keys must be a list of names, got "
                          f"{allowed!r:.60}")
    allowed = list(allowed)
    for key in _mapping(data, where):
        if key not in allowed:
            raise ConfigError(
                f"{where}: unknown key {key!r} (expected one of: {', '.join(allowed)})"
            )


_FLOAT_MAX = int(np.finfo(float).max)


def is_real(v: Any) -> bool:
    """True for a finite real number: a Python or numpy scalar of any precision, or a 0-d
    array; not a bool, a string, NaN, an infinity or a list (a ragged one included). The one
    test behind every "must be a finite number" check of hearsee's settings."""
    if type(v) is float:  # the common case, without numpy
        return math.isfinite(v)
    if type(v) is int:  # (one beyond float's range, a 400-digit YAML literal: OverflowError)
        return abs(v) <= _FLOAT_MAX
    try:
        a = np.asarray(v)
    except (TypeError, ValueError):  # (numpy's ValueError on a ragged list, [1, [2, 3]])
        return False
    return a.ndim == 0 and a.dtype.kind in "iuf" and bool(np.isfinite(a))


def object_entries(value: Any) -> np.ndarray | None:
    """``value`` as an object array of any shape with its entries as given (no number converted,
    so that :func:`all_real` can check each one); None where numpy cannot form one."""
    try:
        return np.asarray(value, dtype=object)
    except (TypeError, ValueError):
        return None


def all_real(entries: np.ndarray, *, finite: bool = True) -> bool:
    """True when every entry of the object array ``entries`` (:func:`object_entries`) is a real
    number (:func:`is_real`): not a bool, a string, a complex number, None, a list (of a ragged
    nesting) or an int beyond float's range. With ``finite=False`` NaN and infinite floats
    count too (for a caller whose next check reports them as not finite). The one
    entry-by-entry check of :func:`as_float_array` and :func:`hearsee.geometry.as_point`.
    Anything else is first made an object array by :func:`object_entries` (None, which is no
    number: False; it was a builtin AttributeError), False where none can be made."""
    if not isinstance(entries, np.ndarray):
        entries = object_entries(entries)
        if entries is None:
            return False
    return all((not finite and isinstance(v, float | np.floating)) or is_real(v)
               for v in entries.flat)


def real_entries(value: Any) -> bool:
    """True when every entry of ``value`` (an array, a list or tuple of any nesting, a scalar)
    is a real number, NaN and the infinities included (the caller's own finiteness check names
    them): a numpy array of integers or floats at once, any other numpy array never (bools,
    strings, complex numbers, dates), lists, tuples and object arrays entry by entry
    (:func:`all_real`; numpy's float conversion read ``True`` as 1.0, ``"0.5"`` as 0.5 and
    dropped an imaginary part). The one "numbers only" rule of :func:`as_float_array`, the
    microphone table of :class:`hearsee.audio.arrays.MicArray`, audio samples
    (:func:`hearsee.audio.signals.as_samples`) and TDOA vectors (:mod:`hearsee.audio.localize`)."""
    if isinstance(value, np.ndarray) and value.dtype.kind != "O":
        return value.dtype.kind in "iuf"
    items = object_entries(value)
    return items is not None and all_real(items, finite=False)


def finite_number(name: str, value: Any, lo: float | None = None, hi: float | None = None, *,
                  lo_open: bool = False, error: type[Exception] = ConfigError) -> float:
    """``value`` as a float when it is a finite real number (:func:`is_real`) within
    ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``; None = unbounded), else ``error`` naming
    ``name`` and the rule, e.g. "sigma_meas_deg must be a finite number > 0, got nan". The
    library's modules pass their own exception type (EstimationError for tracker settings,
    GeometryError for geometry, ...)."""
    below = lo is not None and is_real(value) and (value <= lo if lo_open else value < lo)
    if not is_real(value) or below or (hi is not None and value > hi):
        if lo is not None and hi is not None:
            rule = f" in {'(' if lo_open else '['}{lo:g}, {hi:g}]"
        elif lo is not None:
            rule = f" {'>' if lo_open else '>='} {lo:g}"
        elif hi is not None:
            rule = f" <= {hi:g}"
        else:
            rule = ""
        raise error(f"{name} must be a finite number{rule}, got {value!r}")
    return float(value)


#: A run's time limit at or beyond this many seconds (31.7 years) is no limit (:func:`time_limit`).
MAX_TIME_LIMIT_S = 1e9


def time_limit(name: str, value: Any, *, error: type[Exception] = ConfigError) -> float | None:
    """A run's optional time limit in seconds: None, +inf or at least :data:`MAX_TIME_LIMIT_S`
    -> None (no limit), else a finite real number > 0 (:func:`is_real`) as a float; ``error``
    otherwise, naming ``name`` and both choices, e.g. "--duration must be a number of seconds
    > 0, or inf for no limit, got nan" (the rule of :func:`finite_number` alone, "a finite
    number > 0", read as if inf were refused)."""
    if value is None or (isinstance(value, float | np.floating) and value == math.inf):
        return None
    if not is_real(value) or value <= 0:
        raise error(f"{name} must be a number of seconds > 0, or inf for no limit, got "
                    f"{value!r}")
    # (a limit no run reaches is none; 1e306 s overflowed the sample count, int(d * fs), into a
    # builtin OverflowError once the stream started)
    return None if value >= MAX_TIME_LIMIT_S else float(value)


def whole_number(name: str, value: Any, lo: int | None = 1, hi: int | None = None, *,
                 error: type[Exception] = ConfigError) -> int:
    """``value`` as an int when it is a Python or numpy integer (not a bool) within
    ``[lo, hi]`` (None = unbounded on that side, as in :func:`finite_number`), else ``error``
    naming ``name`` (counts, strides, steps, lengths in samples or pixels; a float such as 2.5
    is refused rather than rounded). ``lo=None`` compared the value with None: a builtin
    TypeError whatever the value."""
    ok = isinstance(value, int | np.integer) and not isinstance(value, bool)
    if not ok or (lo is not None and value < lo) or (hi is not None and value > hi):
        if lo is not None and hi is not None:
            rule = f" in [{lo}, {hi}]"
        elif lo is not None:
            rule = f" >= {lo}"
        else:
            rule = f" <= {hi}" if hi is not None else ""
        raise error(f"{name} must be an integer{rule}, got {value!r}")
    return int(value)


def true_or_false(name: str, value: Any, *, error: type[Exception] = ConfigError) -> bool:
    """``value`` as a bool when it is True or False (a numpy bool too), else ``error`` naming
    ``name``: text such as "no" is truthy, and a flag taken by its truth turned it on without a
    word."""
    if not isinstance(value, bool | np.bool_):
        raise error(f"{name} must be True or False, got {value!r:.60}")
    return bool(value)


def check_rng(rng: Any, name: str = "rng") -> Any:
    """``rng`` itself when it is what hearsee's random functions take -- a numpy ``Generator``
    (drawn from: the caller's stream advances), an integer seed >= 0 (Python or numpy, not a
    bool) or None (fresh entropy) -- else a ConfigError naming ``name``. numpy's
    ``default_rng`` raised its own TypeError / ValueError on text, 1.5 or -1, and took True
    as the seed 1 and a list as a seed sequence. For a caller that passes ``rng`` on
    unchanged (so its seeded output stays what it was) but must check it before any work;
    :func:`as_rng` makes the Generator."""
    if rng is None or isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, int | np.integer) and not isinstance(rng, bool) and rng >= 0:
        return rng
    raise ConfigError(f"{name} must be a numpy Generator, an integer seed >= 0 or None, "
                      f"got {rng!r}")


def as_rng(rng: Any, name: str = "rng") -> np.random.Generator:
    """``np.random.default_rng(rng)`` after :func:`check_rng`: the same stream as before for
    every valid ``rng`` (a Generator is returned as it is)."""
    return np.random.default_rng(check_rng(rng, name))


def require(data: Mapping[str, Any], key: str, where: str) -> Any:
    """Return ``data[key]`` or raise ConfigError saying the field is missing (or, naming
    ``where``, that ``data`` is no mapping)."""
    if key not in _mapping(data, where):
        raise ConfigError(f"{where}: missing required key {key!r}")
    return data[key]


def as_float_array(value: Any, where: str,
                   shape: tuple[int | None, ...] | None = None, *, finite: bool = True,
                   error: type[Exception] = ConfigError) -> np.ndarray:
    """Convert ``value`` to a finite float array, checking ``shape`` (None = any length);
    ``error`` (ConfigError unless the caller's module has its own type) naming ``where``
    otherwise. With ``finite=False`` NaN and infinities pass (numpy-style helpers such as
    :func:`hearsee.geometry.wrap_deg` map them as numpy does); only non-numbers are refused.

    Every entry must be a real number: a bool, a string (``"0.5"``), an int beyond float's
    range or a complex number is refused -- numpy's float conversion read ``True`` as 1.0 and
    ``"0.5"`` as 0.5, and raised a builtin OverflowError on a 400-digit int. A numpy array of
    integers or floats is converted at once (no element-wise check); lists, tuples and object
    arrays have their entries checked one by one (:func:`all_real`; NaN and inf then get the
    "must be finite" error). The many-number counterpart of
    :func:`hearsee.geometry.as_point`."""
    if not real_entries(value):
        raise error(f"{where}: expected numbers, got {value!r}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise error(f"{where}: expected numbers, got {value!r}") from None
    if shape is not None:
        if arr.ndim != len(shape) or any(
            s is not None and s != a for s, a in zip(shape, arr.shape, strict=True)
        ):
            want = "x".join("N" if s is None else str(s) for s in shape)
            raise error(f"{where}: expected shape {want}, got {arr.shape}")
    if finite and not np.all(np.isfinite(arr)):
        raise error(f"{where}: values must be finite numbers")
    return arr


def number(d: Mapping[str, Any], key: str, default: float, where: str, lo: float | None = None,
           hi: float | None = None, integer: bool = False) -> float:
    """``d[key]`` (or ``default``) as a finite number within ``[lo, hi]``; ConfigError naming
    ``where.key`` otherwise. With ``integer=True`` the value must be whole and an int is
    returned. ConfigError naming ``where`` when ``d`` is no mapping."""
    v = _mapping(d, where).get(key, default)
    if not is_real(v):
        raise ConfigError(f"{where}.{key}: expected a number, got {v!r}")
    v = v.item() if isinstance(v, np.generic | np.ndarray) else v  # numpy as Python numbers
    if integer and int(v) != v:
        raise ConfigError(f"{where}.{key}: expected a whole number, got {v!r}")
    if lo is not None and v < lo:
        raise ConfigError(f"{where}.{key}: must be >= {lo}, got {v}")
    if hi is not None and v > hi:
        raise ConfigError(f"{where}.{key}: must be <= {hi}, got {v}")
    return int(v) if integer else float(v)
