"""Shared plumbing of the benchmark scripts: paths, tables, markdown and timing.

Every ``bench/<name>.py`` runs hearsee and its peer on the same inputs in one process, prints a
table, and writes ``bench/results/<name>.md`` plus a PNG plot. Real data are read from
``--data`` (default ``../shared/data``); where it is absent those parts are skipped, not failed.
"""

from __future__ import annotations

import os
import platform
import subprocess
import time
from collections.abc import Callable, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "bench" / "results"
#: the installed packages whose versions a benchmark's numbers depend on (hearsee's numerical
#: stack, its peers, the stereo matcher): a fresh install takes their newest releases. With
#: the processor (:func:`environment`) they say where a result can be reproduced to the digit:
#: bench/robot's closed loop moves with the CPU's last bits (README: the demo's median 3D error
#: 4.5 cm on an AVX2 machine, 4.6 cm with AVX-512; on 2026-12-06 an AVX2 machine read 4.47 cm
#: where robot.md, of the session before, reads 4.58 as the AVX-512 machine did, and its
#: phantom frames were in seeds 20 and 107 instead of that session's 20, 28 and 179)
ENV_PACKAGES = ("numpy", "scipy", "pyroomacoustics", "opencv-python-headless", "scikit-image",
                "scikit-learn", "filterpy", "acoular")


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


def _git(*args: str) -> str | None:
    """``git args`` in the repository, its stripped output; None without git or a checkout."""
    try:
        out = subprocess.run(["git", "-C", str(REPO), *args], capture_output=True, text=True,
                             timeout=10, check=True)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip()


def _cpu_model() -> str:
    """The processor's model name and its widest x86 vector extension (AVX-512 / AVX2, from
    /proc/cpuinfo on Linux; numpy's and OpenCV's kernels dispatch on it), else
    :func:`platform.processor`."""
    try:
        info = Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines()
    except OSError:
        info = []
    model = next((ln.split(":", 1)[1].strip() for ln in info if ln.startswith("model name")),
                 None)
    flags = next((set(ln.split(":", 1)[1].split()) for ln in info if ln.startswith("flags")),
                 set())
    simd = "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else None
    name = model or platform.processor() or platform.machine() or "unknown"
    return f"{name} ({simd})" if simd else name


def environment() -> str:
    """One markdown paragraph saying what a result was produced with: hearsee's commit (with
    "+ uncommitted changes" when ``src/`` or ``bench/`` differ from it, results aside; and
    where the imported package lives when that is not this checkout's ``src/``), Python,
    the machine's processor and core count, and the version of each :data:`ENV_PACKAGES`
    package installed ("not installed" otherwise). CPU ratios and the vision numbers depend on
    them: a benchmark re-run reads "identical to the digit" only on the same set."""
    from importlib.metadata import PackageNotFoundError, version

    commit = _git("rev-parse", "--short", "HEAD")
    if commit is None:
        rev = "unknown (no git checkout)"
    else:
        dirty = _git("status", "--porcelain", "--", "src", "bench", ":!bench/results")
        rev = f"`{commit}`" + (" + uncommitted changes" if dirty else "")
    import hearsee  # (the package the benchmark ran: another checkout's, if it came from there)

    src = Path(hearsee.__file__).resolve().parents[1]
    if src != REPO.resolve() / "src":
        rev += f" (the hearsee package imported from {src})"
    pkgs = []
    for name in ENV_PACKAGES:
        try:
            pkgs.append(f"{name} {version(name)}")
        except PackageNotFoundError:
            pkgs.append(f"{name} not installed")
    return (f"hearsee at {rev}; Python {platform.python_version()}; {_cpu_model()}, "
            f"{os.cpu_count()} cores; " + ", ".join(pkgs) + ".")


def write_markdown(name: str, sections: Sequence[tuple[str, str]], intro: str = "") -> Path:
    """Write ``bench/results/<name>.md`` from (heading, body) sections, and a last section
    "Environment" (:func:`environment`); returns the path."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    parts = [f"# {name}", ""]
    if intro:
        parts += [intro, ""]
    for heading, body in [*sections, ("Environment", environment())]:
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
