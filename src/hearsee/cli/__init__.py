"""The ``hearsee`` command line: a thin shell over the library.

Every command module below registers itself on :data:`hearsee.cli._app.app`. Errors that the
library raises on purpose (:class:`hearsee.errors.HearseeError`) become one line on stderr and
exit code 2 -- never a traceback.
"""

from __future__ import annotations

import importlib
import sys

from hearsee.cli._app import app
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


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``hearsee`` console script.

    With ``argv=None`` (the console script) it exits the process; with a list (tests, embedding)
    it returns the exit code instead. Usage errors exit 2 (typer), hearsee errors print
    ``hearsee: error: <message>`` on stderr and exit 2.
    """
    try:
        app(args=argv, prog_name="hearsee")  # standalone mode: raises SystemExit
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except HearseeError as exc:
        print(f"hearsee: error: {exc}", file=sys.stderr)
        code = 2
    except KeyboardInterrupt:
        print("hearsee: interrupted", file=sys.stderr)
        code = 130
    if argv is None:
        sys.exit(code)
    return code


__all__ = ["app", "main"]
