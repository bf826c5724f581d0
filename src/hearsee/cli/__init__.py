"""The ``hearsee`` command line: a thin shell over the library.

Every command module below registers itself on :data:`hearsee.cli._app.app`. Errors that the
library raises on purpose (:class:`hearsee.errors.HearseeError`) and usage errors (a missing or
unknown option, an invalid value) become one line on stderr and exit code 2 -- never a
traceback, never click's three-line usage block.
"""

from __future__ import annotations

import functools
import importlib
import sys
import warnings

import typer

from hearsee.cli._app import Interrupted, app
from hearsee.errors import HearseeError

#: Modules under hearsee.cli that register commands (one line each; keep sorted).
_COMMAND_MODULES = [
    "calibrate",
    "detect",
    "info",
    "localize",
    "localize3d",
    "robot",
    "run",
    "simulate",
    "track",
]

for _name in _COMMAND_MODULES:
    importlib.import_module(f"hearsee.cli.{_name}")


def _click_base(name: str) -> type[Exception]:
    """click's exception class ``name`` among typer.BadParameter's bases: typer >= 0.22 vendors
    its own copy of click, older releases use click itself; typer exports neither directly."""
    return next(c for c in typer.BadParameter.__mro__ if c.__name__ == name)


_UsageError = _click_base("UsageError")
_ClickException = _click_base("ClickException")


def _one_line(message: object) -> str:
    """``message`` with its line breaks written as ``\\n`` / ``\\r``: a file name may hold
    one (``$'bad\\nname.wav'``), and an error or warning is one line on stderr."""
    return str(message).replace("\r", "\\r").replace("\n", "\\n")


def _usage_error_line(exc) -> str:
    """One line for a usage error: the command, the message and where to get help."""
    path = exc.ctx.command_path if exc.ctx is not None else "hearsee"
    message = " ".join(exc.format_message().split())  # click's messages may span lines
    return f"{path}: error: {message} (see '{path} --help')"


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``hearsee`` console script.

    With ``argv=None`` (the console script) it exits the process; with a list (tests, embedding)
    it returns the exit code instead. Usage errors print ``hearsee <command>: error: <message>
    (see 'hearsee <command> --help')``, hearsee errors and files the system refuses (OSError:
    permissions, a full disk) ``hearsee: error: <message>``, each as one line on stderr, and
    exit 2 (out of memory: one line, exit 1). Ctrl-C prints ``hearsee: interrupted`` and
    exits 130 (a live ``track`` or ``run`` ends its run cleanly instead). Warnings (e.g.
    clipped audio) print ``hearsee: warning: <message>`` on stderr and the command goes on.
    """
    with warnings.catch_warnings():  # restores the caller's warning display afterwards
        shown: set[str] = set()
        warnings.showwarning = functools.partial(_warning_line, shown=shown)
        return _main(argv)


def _warning_line(message, category, filename, lineno, file=None, line=None, *,
                  shown: set[str] | None = None) -> None:
    """A warning as one line on stderr, ``hearsee: warning: <message>`` (hearsee's own, e.g.
    clipped audio) or ``hearsee: warning: <Category>: <message>`` (another library's), instead
    of Python's two lines with the file, line number and source of the call. A line already
    in ``shown`` is not printed again (one run's checks of the same input -- ``track``'s look
    ahead and its stream -- told it twice from two places of the code)."""
    own = category.__module__.split(".")[0] == "hearsee"
    text = f"hearsee: warning: {'' if own else category.__name__ + ': '}{_one_line(message)}"
    if shown is not None:
        if text in shown:
            return
        shown.add(text)
    print(text, file=sys.stderr if file is None else file)


def _main(argv: list[str] | None) -> int:
    try:
        # non-standalone: click raises its errors here instead of printing its usage block,
        # and returns the code of a typer.Exit (e.g. `run` when the device stalls)
        rv = app(args=argv, prog_name="hearsee", standalone_mode=False)
        code = rv if isinstance(rv, int) and not isinstance(rv, bool) else 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except _UsageError as exc:
        if type(exc).__name__ == "NoArgsIsHelpError":  # bare ``hearsee``: the help is the message
            print(exc.format_message(), file=sys.stderr)
        else:
            print(_usage_error_line(exc), file=sys.stderr)
        code = exc.exit_code
    except _ClickException as exc:  # e.g. click.FileError: unreadable file option
        print(f"hearsee: error: {' '.join(exc.format_message().split())}", file=sys.stderr)
        code = exc.exit_code
    except HearseeError as exc:
        print(f"hearsee: error: {_one_line(exc)}", file=sys.stderr)
        code = 2
    except OSError as exc:
        # the safety net behind the commands' own checks: a file the system refused (no
        # permission, disk full, ...) is one line, not a traceback (a closed stdout pipe,
        # `hearsee track ... | head`, never gets here: click exits 1 quietly)
        what = f"{exc.filename}: " if exc.filename else ""
        print(f"hearsee: error: {_one_line(what)}{exc.strerror or exc}", file=sys.stderr)
        code = 2
    except MemoryError:
        print("hearsee: error: out of memory (is an option, e.g. a count, duration or sample "
              "rate, far larger than intended?)", file=sys.stderr)
        code = 1
    except (KeyboardInterrupt, Interrupted, typer.Abort):
        print("hearsee: interrupted", file=sys.stderr)
        code = 130
    if argv is None:
        sys.exit(code)
    return code


__all__ = ["app", "main"]
