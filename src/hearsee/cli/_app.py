"""The typer app and the small helpers every command shares.

Commands live in sibling modules (``hearsee/cli/<command>.py``) that import :data:`app` and
decorate their functions with ``@app.command()``; :mod:`hearsee.cli` imports them. Commands are
thin: they parse options, call library functions and print. Heavy imports (OpenCV, scikit-learn,
pyroomacoustics) happen inside the command functions so that ``hearsee --help`` stays fast.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from enum import Enum, StrEnum
from pathlib import Path
from typing import Any

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from typer.core import TyperGroup

from hearsee.config import to_jsonable


class Interrupted(Exception):
    """Ctrl-C inside a command, carried out of typer to :func:`hearsee.cli.main`, which prints
    ``hearsee: interrupted`` and exits 130."""


class _Group(TyperGroup):
    """hearsee's command group: a KeyboardInterrupt in a command leaves it as
    :class:`Interrupted`. typer (0.2x) turns a KeyboardInterrupt into a silent ``Exit(130)``:
    Ctrl-C ended a command without a word, and the CLI's "hearsee: interrupted" was never
    printed."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except KeyboardInterrupt:
            raise Interrupted() from None


app = typer.Typer(
    name="hearsee",
    cls=_Group,
    help="Ears and eyes for a mobile robot with very few sensors.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)

#: Human-facing messages and progress go to stderr; results go to stdout. A message is one
#: line whatever the width (rich wrapped at 80 columns when stderr is not a terminal: the
#: stats line of ``track`` came out as three lines in a log).
# (markup off: a file name such as take[bold]2.wav lost its "[bold]" in the messages; the
# progress bars' own columns parse theirs)
err_console = Console(stderr=True, soft_wrap=True, markup=False)


class OutputFormat(str, Enum):  # noqa: UP042 (typer choices)
    json = "json"
    csv = "csv"
    table = "table"


class GccMethod(StrEnum):
    """GCC weightings offered by the audio commands (see hearsee.audio.tdoa)."""

    phat = "gcc-phat"
    scot = "gcc-scot"
    roth = "gcc-roth"
    ml = "gcc-ml"
    cc = "cc"


def emit_json(obj: Any, *, indent: int | None = 2) -> None:
    """Print ``obj`` as one JSON document on stdout."""
    sys.stdout.write(json.dumps(to_jsonable(obj), indent=indent) + "\n")


def echo_done(lines: Iterable[str], written: Iterable[str | Path | None]) -> None:
    """The lines a command prints when it is done (``report: ...``), on standard output --
    or on standard error when one of the files it ``written`` is standard output's own
    (``--mcap /dev/stdout > run.mcap``: the line appended after the MCAP's footer made it
    unreadable, until 2026-12-07)."""
    from hearsee.config import goes_to_stdout

    to_err = any(goes_to_stdout(p) for p in written if p is not None)
    for line in lines:
        typer.echo(line, err=to_err)


def refuse_overwrite(outputs: Iterable[str | Path | None], inputs: Iterable[str | Path | None],
                     force: bool) -> None:
    """Before a command does its work, each output file it will write: one that is also an
    input is refused always, one that exists unless ``force`` (the command's ``--force``), and
    so are a folder and a file whose folder does not exist (which failed only once the work
    was done). Nothing the user gave is overwritten, and a refusal writes nothing. A FIFO, a
    device or the file standard output goes to (:func:`hearsee.config.written_through`)
    needs no ``force``: it is written into, not replaced."""
    from hearsee.config import output_file, same_file, written_through
    from hearsee.errors import InputFileError

    ins = [Path(q) for q in inputs if q is not None]
    for p in (Path(o) for o in outputs if o is not None):
        if any(same_file(p, q) for q in ins):
            raise InputFileError(f"{p}: refusing to overwrite an input file; choose another "
                                 "output path")
        output_file(p)
        # (a pipe, a device or standard output's file, e.g. "-o /dev/stdout | jq", is written
        # through, not replaced: it was refused as "file exists" until 2026-12-03)
        if p.exists() and not force and not written_through(p):
            raise InputFileError(f"{p}: file exists; pass --force to overwrite it")


def check_exports(rerun: Path | None, mcap: Path | None,
                  inputs: Iterable[str | Path | None], force: bool) -> list[tuple[str, str]]:
    """Before ``hearsee demo`` / ``run`` does its work, the optional ``--rerun`` / ``--mcap``
    files: :func:`refuse_overwrite`, then each one's extra is installed and its folder exists
    (:func:`hearsee.robot.export.check_export`). Returns ``(option, description)`` of each."""
    from hearsee.errors import InputFileError
    from hearsee.robot.export import check_export

    if rerun is not None and mcap is not None and Path(rerun).resolve() == Path(mcap).resolve():
        raise InputFileError(f"{mcap}: --rerun and --mcap name the same file; the second "
                             "export would replace the first")
    refuse_overwrite([rerun, mcap], inputs, force)
    return [(f"--{kind}", check_export(kind, p))
            for kind, p in (("rerun", rerun), ("mcap", mcap)) if p is not None]


def folder_path(value: str | Path) -> Path:
    """A report folder option's value as a Path (typer's ``parser``): an empty one is refused.
    As a plain Path option, ``--out ""`` became ``.`` and the report went into the current
    folder (an unset shell variable, not a choice); ``--out .`` still means it."""
    if isinstance(value, Path):  # (the default, or a value typer has converted already)
        return value
    if not str(value).strip():
        raise typer.BadParameter(f"must name a report folder, got {value!r}")
    return Path(value)


def parse_floats(text: str, n: int | None, what: str) -> list[float]:
    """Parse ``"1,2,3"`` into floats; raise typer.BadParameter with a clear message."""
    try:
        vals = [float(v) for v in text.replace(" ", "").split(",") if v != ""]
    except ValueError:
        raise typer.BadParameter(
            f"{what}: expected comma-separated numbers, got {text!r}") from None
    if n is not None and len(vals) != n:
        raise typer.BadParameter(f"{what}: expected {n} numbers, got {len(vals)} in {text!r}")
    if not all(math.isfinite(v) for v in vals):
        raise typer.BadParameter(f"{what}: numbers must be finite, got {text!r}")
    return vals


def parse_band(text: str, what: str = "--band-hz") -> tuple[float, float]:
    """``"LOW,HIGH"`` in Hz as a band ``(low, high)`` with ``0 <= low < high``;
    typer.BadParameter otherwise."""
    lo, hi = parse_floats(text, 2, what)
    if not 0.0 <= lo < hi:
        raise typer.BadParameter(f"{what}: expected LOW,HIGH in Hz with 0 <= LOW < HIGH, got "
                                 f"{text!r}")
    return lo, hi


def parse_channels(text: str | None, n_mics: int, what: str = "--channels"
                   ) -> tuple[int, ...] | None:
    """``"1,2,3,4"``: the input channel (0-based) of each of ``n_mics`` microphones
    (:func:`hearsee.audio.signals.microphone_channels`); None for None. typer.BadParameter
    for text that is no list of integers, ConfigError for a wrong count or repeats."""
    from hearsee.audio.signals import microphone_channels

    if text is None:
        return None
    vals = parse_floats(text, None, what)
    if not vals or not all(v.is_integer() for v in vals):
        raise typer.BadParameter(f"{what}: expected comma-separated channel indices such as "
                                 f"1,2,3,4, got {text!r}")
    return microphone_channels([int(v) for v in vals], n_mics, what)


#: ``--channels``' help, the same for every command that reads microphones
CHANNELS_HELP = ("The input channel (0-based, comma-separated) of each microphone, e.g. "
                 "1,2,3,4 for a 6-channel ReSpeaker 4-mic array recording; the other channels "
                 "are left out. Default: channel k is microphone k.")


def note_empty_band(where: object, used: Sequence[float] | None,
                    asked: tuple[float, float] | None, fs: float) -> None:
    """One line on stderr when the GCC's band ``used`` (Hz) ends well below the band ``asked``
    for (None: up to ``fs / 2``) because the recording ``where`` holds nothing above it: below
    :data:`hearsee.audio.tdoa.EMPTY_BAND_NATIVE` of it, where the GCC ends the band of an
    upsampled recording (not a converter's own anti-alias edge)."""
    from hearsee.audio.tdoa import EMPTY_BAND_NATIVE

    if used is None:
        return
    top = fs / 2.0 if asked is None else min(asked[1], fs / 2.0)
    if used[1] < EMPTY_BAND_NATIVE * top:
        err_console.print(f"hearsee: note: {where}: the top of the spectrum is empty "
                          f"(upsampled from a lower rate?): the GCC uses {used[0]:.0f}-"
                          f"{used[1]:.0f} Hz", highlight=False)


def print_summary(title: str, summary: dict[str, Any]) -> None:
    """A two-column rich table (metric, value) of a summary dict on stderr."""
    from rich.table import Table

    t = Table(title=title)
    t.add_column("metric")
    t.add_column("value", justify="right")
    for k, v in summary.items():
        if isinstance(v, float):
            v = f"{v:.3g}"
        elif isinstance(v, list):
            v = "[" + ", ".join(f"{x:.2f}" if isinstance(x, float) else str(x) for x in v) + "]"
        t.add_row(str(k), str(v))
    err_console.print(t)


def _bars() -> Progress:
    """The CLI's rich progress display on stderr (cleared when done)."""
    return Progress(
        TextColumn("[progress.description]{task.description}"),
        BarColumn(),
        TextColumn("{task.completed:.0f}/{task.total:.0f}"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=err_console,
        transient=True,
    )


@contextmanager
def progress(description: str, total: float | None, *, enabled: bool = True) -> Iterator[Any]:
    """A rich progress bar on stderr; yields a callable ``advance(n=1)``."""
    if not enabled or not sys.stderr.isatty():
        yield lambda n=1: None
        return
    with _bars() as bar:
        task = bar.add_task(description, total=total)
        yield lambda n=1: bar.advance(task, n)


@contextmanager
def stage_progress(description: str, *, enabled: bool = True) -> Iterator[Any]:
    """Rich progress bars on stderr, one per stage of a job; yields a callable
    ``report(stage, done, total)`` (the library's :data:`hearsee.sim.moving.Progress`) that
    adds a bar "description: stage" the first time it hears of a stage and moves it after."""
    if not enabled or not sys.stderr.isatty():
        yield lambda stage, done, total: None
        return
    with _bars() as bar:
        tasks: dict[str, Any] = {}

        def report(stage: str, done: int, total: int) -> None:
            if stage not in tasks:
                tasks[stage] = bar.add_task(f"{description}: {stage}", total=total)
            bar.update(tasks[stage], completed=done, total=total)

        yield report


def _version_callback(value: bool) -> None:
    if value:
        from hearsee import __version__

        typer.echo(f"hearsee {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version_callback, is_eager=True, help="Print the version."
    ),
) -> None:
    """Ears and eyes for a mobile robot with very few sensors."""
