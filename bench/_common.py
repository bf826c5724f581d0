"""Shared plumbing of the benchmark scripts: paths, tables, markdown and timing.

Every ``bench/<name>.py`` runs hearsee and its peer on the same inputs in one process, prints a
table, and writes ``bench/results/<name>.md`` plus a PNG plot. Real data are read from
``--data`` (default ``../shared/data``); where it is absent those parts are skipped, not failed.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "bench" / "results"


def shared_data_dir(option: str | os.PathLike | None = None) -> Path | None:
    """The real-data folder (``option``, ``$HEARSEE_SHARED_DATA`` or ``../shared/data``), or
    None when it does not exist."""
    cand = option or os.environ.get("HEARSEE_SHARED_DATA") or REPO.parent / "shared" / "data"
    p = Path(cand)
    return p if p.is_dir() else None


def arctic_files(data: Path | None) -> list[Path]:
    """The dry CMU ARCTIC utterances in ``data/audio/speech`` (not the dish-washing noise),
    sorted; empty without the data."""
    if data is None:
        return []
    d = data / "audio" / "speech"
    return sorted(p for p in d.glob("*.wav") if "dishes" not in p.name) if d.is_dir() else []


def fmt(v: Any, digits: int = 3) -> str:
    if isinstance(v, float):
        if v != v:  # NaN
            return "n/a"
        return f"{v:.{digits}g}" if abs(v) < 1e4 else f"{v:.3e}"
    return str(v)


def markdown_table(headers: Sequence[str], rows: Sequence[Sequence[Any]], digits: int = 3) -> str:
    """A GitHub markdown table (a '|' inside a cell, e.g. "max |lag|", is escaped: it would
    start a new column)."""
    def row(cells: Sequence[str]) -> str:
        return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"

    out = [row(headers), "|" + "|".join("---" for _ in headers) + "|"]
    out += [row([fmt(v, digits) for v in r]) for r in rows]
    return "\n".join(out)


def print_table(title: str, headers: Sequence[str], rows: Sequence[Sequence[Any]],
                digits: int = 3) -> None:
    """Print a table on stdout (rich when available)."""
    try:
        from rich.console import Console
        from rich.table import Table
    except ImportError:  # pragma: no cover
        print(title)
        print(markdown_table(headers, rows, digits))
        return
    t = Table(title=title)
    for h in headers:
        t.add_column(str(h))
    for r in rows:
        t.add_row(*(fmt(v, digits) for v in r))
    Console(width=200).print(t)


def write_markdown(name: str, sections: Sequence[tuple[str, str]], intro: str = "") -> Path:
    """Write ``bench/results/<name>.md`` from (heading, body) sections; returns the path."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    parts = [f"# {name}", ""]
    if intro:
        parts += [intro, ""]
    for heading, body in sections:
        parts += [f"## {heading}", "", body, ""]
    path = RESULTS / f"{name}.md"
    path.write_text("\n".join(parts), encoding="utf-8")
    return path


@contextmanager
def cpu_timer() -> Any:
    """Measure process CPU time (seconds) of the block: ``with cpu_timer() as t: ...; t()``."""
    start = time.process_time()
    box: dict[str, float] = {}
    yield lambda: box.get("dt", time.process_time() - start)
    box["dt"] = time.process_time() - start


def timed(fn: Callable[[], Any], repeat: int = 1) -> tuple[Any, float]:
    """Run ``fn`` ``repeat`` times; return (last result, best wall-clock seconds)."""
    best = float("inf")
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return out, best
