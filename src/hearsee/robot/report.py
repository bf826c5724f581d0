"""The report folder of a robot run: ``index.html`` with plots, ``log.json`` and ``summary.json``.

Everything in the report comes from the run's own log (no canned values): the plots are drawn
from ``log`` records, the overlays are the camera frames the pipeline saw.

Folder layout::

    index.html        the page (relative links only, opens from disk)
    log.json          every estimate, one record per control step (see hearsee.robot.pipeline)
    summary.json      the summary metrics
    plots/*.png       top view, error over time, head angle over time
    frames/*.png      detection overlays (left camera) and thermal views
"""

from __future__ import annotations

import contextlib
import html
import io
import json
import os
import re
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from hearsee.errors import InputFileError

#: ``put(rel, data)``: stage the file ``rel`` of the report folder (text or bytes)
_Put = Callable[[str, "str | bytes"], None]

__all__ = ["REPORT_FILES", "file_in_the_way", "report_blocker_reason", "report_folder_blocker",
           "report_folder_unwritable", "report_foreign_file", "report_makes_folder",
           "report_overwrites", "write_report"]

#: The files :func:`write_report` writes in its folder itself; it also writes PNGs into the
#: folder's ``plots/`` and ``frames/`` (named after the plots and the images it is given).
REPORT_FILES = ("index.html", "log.json", "summary.json")
_REPORT_SUBFOLDERS = ("plots", "frames")
#: A report image's file stem (:func:`_check_images`): no separators, no leading dot.
_STEM = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9_.-]*")


def report_folder_blocker(folder: str | Path) -> Path | None:
    """The path that keeps :func:`write_report` from making ``folder`` or writing into it --
    the folder itself, one of its parents, or its ``plots`` or ``frames`` is a file; or one of
    :data:`REPORT_FILES` there, or a ``*.png`` in its ``plots/`` or ``frames/``, is a folder --
    or None (:func:`report_blocker_reason` says which). Checked before a run (``hearsee demo
    -o``, a robot file's ``output.report``), not found only once the whole run is done (a file
    named ``plots`` in the folder failed the report after the run, with log.json and
    summary.json already written; until 2026-12-02; a folder named ``index.html`` failed it
    with IsADirectoryError naming a temporary file, until 2026-12-07)."""
    blocker = file_in_the_way(folder)
    if blocker is not None:
        return blocker
    f = Path(folder)
    hit = next((f / sub for sub in _REPORT_SUBFOLDERS
                if (f / sub).exists() and not (f / sub).is_dir()), None)
    if hit is None:
        hit = next((f / name for name in REPORT_FILES if (f / name).is_dir()), None)
    if hit is None:
        hit = next((q for q in _report_pngs(f) if q.is_dir()), None)
    return hit


def _report_pngs(folder: Path) -> Iterator[Path]:
    """The entries named ``*.png`` in ``folder``'s ``plots/`` and ``frames/`` (where a report
    writes its PNGs), in order."""
    return (q for sub in _REPORT_SUBFOLDERS if (folder / sub).is_dir()
            for q in sorted((folder / sub).iterdir()) if q.suffix.lower() == ".png")


def report_blocker_reason(blocker: Path) -> str:
    """What is wrong with :func:`report_folder_blocker`'s answer, for an error message."""
    if blocker.is_dir():
        return f"{blocker} is a folder where the report writes a file"
    return f"{blocker} is a file, not a folder"


def file_in_the_way(folder: str | Path) -> Path | None:
    """The file that keeps ``folder`` from being made: the folder itself or the nearest of its
    parents that exists, when that is no folder (past a dangling link, at its target); else
    None. The report folder's rule (:func:`report_folder_blocker`) and the robot file's JSON
    lines' folder."""
    above = _nearest_existing(folder)
    return above if above is not None and not above.is_dir() else None


def _nearest_existing(folder: str | Path) -> Path | None:
    """``folder`` itself or its nearest parent that exists (None if none does); past a
    dangling link, its target's (:func:`write_report` makes the folder there)."""
    p = Path(folder)
    for q in (p, *p.parents):
        if q.exists():
            return q
        if q.is_symlink():
            real = Path(os.path.realpath(q))
            return None if real == q else _nearest_existing(real)
    return None


def report_folder_unwritable(folder: str | Path) -> Path | None:
    """The existing folder -- ``folder`` itself or its nearest existing parent -- in which
    :func:`write_report` could not write (no write permission), or None. Checked before a run
    with :func:`report_folder_blocker`: the report was refused only at the end (a
    PermissionError once a whole run, or a live session, was done)."""
    q = _nearest_existing(folder)
    if q is not None and q.is_dir() and not os.access(q, os.W_OK | os.X_OK):
        return q
    return None


def report_foreign_file(folder: str | Path) -> Path | None:
    """The first file in ``folder`` that a report would write over and that an earlier hearsee
    report did not write -- an ``index.html`` whose title is not a hearsee report's, or a
    ``log.json`` / ``summary.json`` / PNG in ``plots/`` or ``frames/`` beside no hearsee
    ``index.html`` -- or None. A report replaces its own earlier files (re-running ``hearsee
    demo``); pointed at a folder of the user's, it overwrote their index.html, log.json and
    summary.json without a word (and, until 2026-12-01, their PNGs in plots/ and frames/)."""
    f = Path(folder)
    index = f / "index.html"
    if index.is_file():
        try:
            with index.open("rb") as fh:
                ours = b"<title>hearsee report:" in fh.read(4096)
        except OSError:
            ours = False
        return None if ours else index
    hit = next((f / name for name in REPORT_FILES[1:] if (f / name).exists()), None)
    if hit is None:
        hit = next(_report_pngs(f), None)
    return hit


def report_overwrites(folder: str | Path, paths: Sequence[str | Path | None]) -> Path | None:
    """The first of ``paths`` (files; None entries skipped) that :func:`write_report` into
    ``folder`` could overwrite -- one of :data:`REPORT_FILES` there, or a PNG in its ``plots/``
    or ``frames/`` -- or None. The one rule behind every "the report would overwrite an input"
    refusal (``hearsee demo``, ``hearsee run --out``, a robot file's ``output``)."""
    f = Path(folder).resolve()
    for p in paths:
        if p is None:
            continue
        q = Path(p).resolve()
        if (q.parent == f and q.name in REPORT_FILES) or (
                q.parent.parent == f and q.parent.name in _REPORT_SUBFOLDERS
                and q.suffix.lower() == ".png"):
            return Path(p)
    return None


def report_makes_folder(folder: str | Path, path: str | Path) -> bool:
    """Whether :func:`write_report` into ``folder`` makes ``path`` a folder (or writes into
    it): ``folder`` itself, a folder above it, or its ``plots/`` or ``frames/``. An output
    file of the same run there (an export, a live run's JSON lines) and the report cannot
    both be written: the one written last failed, after the run. The one rule of
    :func:`hearsee.robot.export.check_export_targets` and
    :func:`hearsee.robot.hardware.check_outputs`."""
    f = Path(folder).resolve()
    q = Path(path).resolve()
    return q == f or q in f.parents or (q.parent == f and q.name in _REPORT_SUBFOLDERS)


_CSS = """
body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1100px;color:#222}
h1{margin-bottom:0} .sub{color:#666;margin-top:.2em}
table{border-collapse:collapse;margin:1em 0}
td,th{border:1px solid #ccc;padding:.3em .7em;text-align:right}
th{background:#f3f3f3} td:first-child,th:first-child{text-align:left}
.grid{display:flex;flex-wrap:wrap;gap:12px} .grid figure{margin:0;width:350px}
.grid img{width:100%;border:1px solid #ddd} figcaption{font-size:.85em;color:#555}
img.plot{max-width:100%;border:1px solid #eee;margin:.5em 0}
.ok{color:#17803d;font-weight:bold} .bad{color:#b3261e;font-weight:bold}
"""


def _fmt(v: Any) -> str:
    if v is None:
        return "n/a"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return "n/a" if not np.isfinite(v) else f"{v:.3g}"
    return html.escape(str(v))


def _arr(log: Sequence[Mapping[str, Any]], path: Sequence[str],
         dim: int | None = None) -> np.ndarray:
    """Pull a field (nested keys) out of every record; missing -> NaN."""
    out = []
    for rec in log:
        v: Any = rec
        for k in path:
            v = v.get(k) if isinstance(v, Mapping) else None
        if v is None:
            out.append(np.full(dim, np.nan) if dim else np.nan)
        else:
            out.append(np.asarray(v, dtype=float))
    if not out:  # an empty log (a run stopped before its first update): empty plots
        return np.zeros((0, dim) if dim else 0)
    return np.array(out, dtype=float)


def _png(fig: Any) -> bytes:
    """The figure as the PNG bytes ``fig.savefig(path.png, dpi=110)`` writes."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()


def _plots(folder: Path, log: Sequence[Mapping[str, Any]],
           scenario: Mapping[str, Any], put: _Put) -> list[tuple[str, str]]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    (folder / "plots").mkdir(parents=True, exist_ok=True)
    t = _arr(log, ["t"])
    truth = _arr(log, ["truth", "position_m"], 3)
    track = _arr(log, ["track", "position_m"], 3)
    err = _arr(log, ["error_m"])
    pan = _arr(log, ["head_pan_deg"])
    target = _arr(log, ["truth", "azimuth_robot_deg"])
    # (with people taking turns the truth jumps from one talker to the next: no line across)
    talker = np.nan_to_num(_arr(log, ["truth", "talker"]), nan=-1.0)
    cut = np.flatnonzero(np.diff(talker) != 0) + 1
    t_cut = np.insert(t, cut, np.nan)
    truth, target = np.insert(truth, cut, np.nan, axis=0), np.insert(target, cut, np.nan)
    audio_az = _arr(log, ["audio", "azimuth_deg"])
    # (a live run knows no truth: its plots were titled against the ground truth, the error
    # plot empty -- found by a review helper)
    known = bool(np.isfinite(truth).any())
    figs = []

    def save(fig: Any, rel: str, caption: str) -> None:
        fig.tight_layout()
        try:
            put(rel, _png(fig))
        finally:
            plt.close(fig)
        figs.append((rel, caption))

    fig, ax = plt.subplots(figsize=(6.5, 5.5))
    room = scenario["room"]["size_m"]
    ax.add_patch(plt.Rectangle((0, 0), room[0], room[1], fill=False, lw=2, color="k"))
    robot = scenario["robot"]["position_m"]
    ax.plot(*robot, "ks", ms=10, label="robot")
    # (markers: a talker standing still is a point, which a line alone does not draw)
    if known:
        ax.plot(truth[:, 0], truth[:, 1], "g-", marker="o", ms=4, lw=3, alpha=0.6,
                label="speaker (truth)")
    for p in scenario.get("people", []):
        if p.get("speaking"):  # (the people heard, by name: several take turns)
            # (as written: a name with two "$" was read as TeX -- drawn garbled, or, when no
            # valid TeX, failing the report after the whole run with a traceback)
            ax.annotate(str(p.get("name", "")), p["path_m"][0], textcoords="offset points",
                        xytext=(5, -12), color="g", parse_math=False)
    ax.plot(track[:, 0], track[:, 1], "b.-", ms=4, label="track (estimate)")
    for o in scenario.get("objects", []):
        ax.plot(*o["position_m"], "rx", ms=10, mew=2)
        ax.annotate(o["kind"], o["position_m"], textcoords="offset points", xytext=(5, 5),
                    color="r")
    heading = np.radians(scenario["robot"].get("heading_deg", 0.0))
    for p in pan[::max(1, len(t) // 12)]:
        if np.isfinite(p):
            a = heading + np.radians(p)
            ax.plot([robot[0], robot[0] + 0.5 * np.cos(a)], [robot[1], robot[1] + 0.5 * np.sin(a)],
                    color="0.6", lw=1)
    ax.set_aspect("equal")
    # (a live run's positions are in the robot's own frame: its axes were labelled "room")
    if scenario.get("frame") == "robot":
        ax.set_xlabel("robot frame x, forward (m)")
        ax.set_ylabel("robot frame y, left (m)")
    else:
        ax.set_xlabel("room x (m)")
        ax.set_ylabel("room y (m)")
    ax.set_title("Top view: trajectory vs ground truth (grey: head direction)" if known else
                 "Top view: trajectory (grey: head direction)")
    ax.legend(loc="best", fontsize=8)
    save(fig, "plots/top_view.png", "Top view of the room: estimated track vs ground truth."
         if known else "Top view: the estimated track (a live run has no ground truth).")

    if known:
        fig, ax = plt.subplots(figsize=(7, 3.2))
        ax.plot(t, err * 100, "b.-")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("3D position error (cm)")
        ax.set_title("Position error over time")
        ax.grid(alpha=0.3)
        save(fig, "plots/error.png", "3D position error of the track over time.")

    fig, ax = plt.subplots(figsize=(7, 3.2))
    ax.plot(t, pan, "k-", label="head pan")
    if known:
        ax.plot(t_cut, target, "g--", label="speaker direction (truth)")
    ax.plot(t, audio_az, "m.", ms=4, label="audio azimuth estimate")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("azimuth in robot frame (deg)")
    ax.set_title("Head angle over time")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    save(fig, "plots/head.png",
         "Head pan angle, the speaker's true direction and the audio estimates." if known
         else "Head pan angle and the audio estimates.")
    return figs


def _check_images(images: Mapping[str, Any]) -> None:
    """Each of :func:`write_report`'s ``images``: a plain file stem (letters, digits, ``_``,
    ``-``, ``.``; not starting with ``.``) naming a non-empty uint8 image as
    :func:`hearsee.vision.io.check_image` takes them ((H, W) or (H, W, 1|3|4)) -- else
    ConfigError / ImageInputError, before anything is written. An empty image raised cv2's
    error once the report was half staged; a stem such as ``../index`` wrote outside
    ``frames/``, past the rules of :func:`report_overwrites`."""
    from hearsee.errors import ConfigError, ImageInputError
    from hearsee.vision.io import check_image

    for name, img in images.items():
        if not (isinstance(name, str) and _STEM.fullmatch(name)):
            raise ConfigError(f"report image name {name!r:.60}: expected a plain file stem "
                              "(letters, digits, _, - and ., not starting with .)")
        what = f"report image {name!r}"
        check_image(img, what)
        if img.dtype != np.uint8:
            raise ImageInputError(f"{what}: expected uint8 pixels, got {img.dtype}")


def _write_images(folder: Path, images: Mapping[str, np.ndarray], put: _Put) -> list[str]:
    import cv2

    (folder / "frames").mkdir(parents=True, exist_ok=True)
    names = []
    for name, img in images.items():
        rel = f"frames/{name}.png"
        ok, png = cv2.imencode(".png", img)  # (the bytes cv2.imwrite(rel) wrote)
        if not ok:
            raise InputFileError(f"cannot write {folder / rel}")
        put(rel, png.tobytes())
        names.append(rel)
    return names


def write_report(
    folder: str | Path,
    scenario: Mapping[str, Any],
    log: Sequence[Mapping[str, Any]],
    summary: Mapping[str, Any],
    images: Mapping[str, np.ndarray] | None = None,
    captions: Mapping[str, str] | None = None,
) -> Path:
    """Write the report folder; returns the path of ``index.html``.

    ``scenario``'s ``frame`` names the frame of the log's positions: ``"room"`` (default, a
    simulated run) or ``"robot"`` (a live run, :func:`hearsee.robot.hardware.report_scenario`;
    the top view's axes are labelled so).
    ``images`` maps a file stem to a BGR/grey uint8 image (overlays, thermal views);
    ``captions`` maps the same stems to captions.

    Every file is written beside its name and replaces it only once the whole report is
    written (:func:`hearsee.config.replacing`; ``index.html`` last); on an error or Ctrl-C
    the files of an earlier report stay as they were and no temporary file is left. Until
    2026-12-02 each file was written in place as it came: a failure part way (a full disk,
    an image that could not be encoded, Ctrl-C while plotting) left a half-written file or
    the new log.json and summary.json beside the earlier report's plots and page. A file
    that is no regular file (a FIFO) is written through, as the exports do.
    """
    from hearsee.config import replacing, to_jsonable, write_into

    _check_images(images or {})
    out = Path(folder)
    try:
        # (at a link's target: a dangling link, e.g. to a folder on a disk not yet made,
        # passed the checks and failed here once the whole run was done, "File exists")
        Path(os.path.realpath(out)).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputFileError(f"cannot create report folder {out}: {exc.strerror}") from None
    with contextlib.ExitStack() as staged:  # (closed in reverse: the files replace theirs)

        def put(rel: str, data: str | bytes) -> None:
            write_into(staged.enter_context(replacing(out / rel)), data, out / rel)

        index_tmp = staged.enter_context(replacing(out / "index.html"))  # (replaced last)
        put("log.json", json.dumps(to_jsonable(list(log)), indent=1))
        put("summary.json", json.dumps(to_jsonable(dict(summary)), indent=2))
        figs = _plots(out, log, scenario, put)
        image_files = _write_images(out, images or {}, put)
        page = _page(scenario, summary, figs, image_files, captions or {})
        write_into(index_tmp, page, out / "index.html")
    return out / "index.html"


def _page(scenario: Mapping[str, Any], summary: Mapping[str, Any],
          figs: Sequence[tuple[str, str]], image_files: Sequence[str],
          captions: Mapping[str, str]) -> str:
    """The report's ``index.html``."""
    rows = "".join(
        f"<tr><td>{html.escape(str(k))}</td><td>{_fmt(v)}</td></tr>"
        for k, v in summary.items() if not isinstance(v, Mapping | list)
    )
    ok = bool(summary.get("success"))
    verdict = ('<span class="ok">person found, verified and tracked</span>' if ok
               else '<span class="bad">person not tracked</span>')
    imgs = "".join(
        f'<figure><img src="{html.escape(p)}" alt="{html.escape(Path(p).stem)}">'
        f"<figcaption>{html.escape(captions.get(Path(p).stem, Path(p).stem))}</figcaption></figure>"
        for p in image_files
    )
    plots = "".join(
        f'<figure><img class="plot" src="{p}" alt="{Path(p).stem}"><figcaption>{html.escape(c)}'
        f"</figcaption></figure>" for p, c in figs
    )
    name = html.escape(str(scenario.get("name", "")))
    page = f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>hearsee report: {name}</title>
<style>{_CSS}</style></head><body>
<h1>hearsee robot report</h1>
<p class="sub">scenario <b>{name}</b> (seed {_fmt(scenario.get('seed'))}) &mdash;
{verdict}</p>
<h2>Summary</h2>
<table id="summary"><tr><th>metric</th><th>value</th></tr>{rows}</table>
<p>Full log of every estimate: <a href="log.json">log.json</a>;
summary: <a href="summary.json">summary.json</a>.</p>
<h2>Plots</h2>{plots}
<h2>Camera views</h2>
<p>Left camera with detections (green: verified person, red: rejected candidate)
and the thermal view.</p>
<div class="grid">{imgs}</div>
</body></html>
"""
    return page
