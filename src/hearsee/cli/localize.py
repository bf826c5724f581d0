"""``hearsee localize``: per-frame and whole-recording source direction from a recording."""

from __future__ import annotations

import csv
import io
import math
import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from hearsee.cli._app import (
    CHANNELS_HELP,
    GccMethod,
    OutputFormat,
    app,
    emit_json,
    err_console,
    note_empty_band,
    parse_band,
    parse_channels,
    progress,
)
from hearsee.config import finite_number, whole_number
from hearsee.errors import ConfigError

#: Above this much audio x pairs (seconds) processing takes about a second: show a bar.
_PROGRESS_WORK_S = 60.0


def _fmt(v: Any, digits: int = 1, null: str = "-") -> str:
    """``v`` with ``digits`` decimals, ``null`` where it is None (the JSON's null): "-" in the
    table, "" in the CSV (its one null; the CSV's candidates wrote "-" for an unresolved
    elevation, e.g. "26.52/-", until 2026-12-03)."""
    return null if v is None else f"{v:.{digits}f}"


def _write_csv(doc: dict[str, Any]) -> None:
    """The frames as CSV, one row each; ``candidates`` is ``"az/el;az/el..."`` in degrees, an
    unresolved value (null in the JSON) empty there as in every column: ``"26.52/;153.48/"``
    for a two-microphone array. ``t_s`` to the microsecond (a sample at 192 kHz is 5.2 us):
    to 0.1 ms it gave two frames one time at hops below 0.1 ms (0.0321 for 32.0625 and
    32.125 ms, a one-sample hop at 16 kHz) until 2026-12-07."""
    labels = list(doc["summary"]["tdoa_s"])
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    several = "sources" in doc  # (--sources: each frame's source, its index in them)
    w.writerow(["t_s", *[f"tdoa_{k}_s" for k in labels], "azimuth_deg", "elevation_deg",
                "candidates", "confidence", "valid", *(["source"] if several else [])])
    for f in doc["frames"]:
        cands = ";".join(f"{_fmt(c['azimuth_deg'], 2, '')}/{_fmt(c['elevation_deg'], 2, '')}"
                         for c in f["candidates"])
        w.writerow([f"{f['t']:.6f}", *[_fmt(f["tdoa_s"][k], 9, null="") for k in labels],
                    _fmt(f["azimuth_deg"], 2, null=""), _fmt(f["elevation_deg"], 2, null=""),
                    cands, f"{f['confidence']:.3f}", int(f["valid"]),
                    *([_fmt(f["source"], 0, null="")] if several else [])])
    sys.stdout.write(buf.getvalue())


def _first(values: list[Any]) -> Any:
    """The first of ``values`` that is not None (a moving source's path), else None."""
    return next((v for v in values if v is not None), None)


#: The table shows every pair's TDOA up to this many pairs (four microphones), else only the
#: pairs with microphone 0 (the ITD filter's states): the 28 pairs of eight microphones were
#: squeezed to unreadable one-character columns in 160 characters. JSON and CSV keep them all.
TABLE_MAX_PAIRS = 6


def _table_pairs(labels: list[str]) -> list[str]:
    """The pair labels ("i-j") the table shows (:data:`TABLE_MAX_PAIRS`)."""
    if len(labels) <= TABLE_MAX_PAIRS:
        return labels
    ref = [k for k in labels if k.split("-")[0] == "0"]
    return ref or labels[:TABLE_MAX_PAIRS]


def _print_table(doc: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    every = list(doc["summary"]["tdoa_s"])
    labels = _table_pairs(every)
    # (the array's name escaped too: a YAML name "respeaker[v2]" was titled "respeaker", and
    # "x[/b]" was rich's MarkupError, a traceback)
    t = Table(title=f"hearsee localize ({escape(doc['array']['name'])}, {doc['method']})",
              caption=None if labels == every else
              f"TDOAs of {len(labels)} of {len(every)} pairs; --format json or csv has all")
    # (escaped: rich read "[s]", "[us]" and "[deg]" as style tags and dropped the units)
    t.add_column(escape("t [s]"))
    for k in labels:
        t.add_column(escape(f"tdoa {k} [us]"))
    for h in ("azimuth [deg]", "elevation [deg]", "candidates", "confidence"):
        t.add_column(escape(h))
    for f in doc["frames"]:
        t.add_row(f"{f['t']:.3f}",
                  *[_fmt(None if f["tdoa_s"][k] is None else f["tdoa_s"][k] * 1e6) for k in labels],
                  _fmt(f["azimuth_deg"]), _fmt(f["elevation_deg"]),
                  ", ".join(f"({_fmt(c['azimuth_deg'])}, {_fmt(c['elevation_deg'])})"
                            for c in f["candidates"]),
                  f"{f['confidence']:.2f}")
    con = Console(file=sys.stdout, width=160)
    con.print(t)
    s = doc["summary"]
    cands = ", ".join(f"({_fmt(c['azimuth_deg'])}, {_fmt(c['elevation_deg'])})"
                      for c in s["candidates"]) or "none"
    pos, cov = s.get("position_m"), s.get("position_covariance_m2")
    where = "" if pos is None else f", position ({', '.join(_fmt(v, 2) for v in pos)}) m"
    if pos is not None and cov is not None:
        where += f" +- ({', '.join(_fmt(math.sqrt(max(cov[k][k], 0.0)), 2) for k in range(3))})"
        if s.get("position_tdoa_std_s") is not None:
            where += f" (TDOA error {s['position_tdoa_std_s'] * 1e6:.1f} us)"
    if s.get("direction_from_position"):  # (the frames' are plane waves': they may differ)
        where += "; direction from the position"
    con.print(f"summary: azimuth {_fmt(s['azimuth_deg'])} deg, elevation "
              f"{_fmt(s['elevation_deg'])} deg, candidates {cands}{where}, "
              f"{s['n_valid_frames']} valid frames", highlight=False, soft_wrap=True)
    for k, src in enumerate(doc.get("sources", [])):
        cands = ", ".join(f"({_fmt(c['azimuth_deg'])}, {_fmt(c['elevation_deg'])})"
                          for c in src["candidates"])
        how = (f"spread {src['spread_deg']:.1f} deg" if "spread_deg" in src else
               f"heard {src['t_start_s']:.2f}-{src['t_end_s']:.2f} s, azimuth "
               f"{_fmt(_first(src['path']['azimuth_deg']))} -> "
               f"{_fmt(_first(src['path']['azimuth_deg'][::-1]))} deg")
        con.print(f"source {k}: azimuth {_fmt(src['azimuth_deg'])} deg, elevation "
                  f"{_fmt(src['elevation_deg'])} deg, candidates {cands}, {src['n_frames']} "
                  f"frames ({src['share']:.0%}), {how}", highlight=False, soft_wrap=True)
    if "sources" in doc and not doc["sources"]:
        con.print("sources: none (the frames' directions do not pile up anywhere)",
                  highlight=False)


@app.command("localize")
def localize_cmd(
    recording: Annotated[list[Path], typer.Argument(
        help="Multichannel audio file (channel k is microphone k of the array), or one file "
        "per microphone in the array's order (their channels file by file; one rate and "
        "length).")],
    array: Annotated[str, typer.Option("--array", help="Array preset name or YAML file.")],
    channels: Annotated[str | None, typer.Option(
        "--channels", help=CHANNELS_HELP, show_default=False)] = None,
    frame_ms: Annotated[float, typer.Option(
        "--frame-ms", help="Frame length in milliseconds, at most 10000.")] = 64.0,
    hop_ms: Annotated[float, typer.Option(
        "--hop-ms", help="Frame hop in milliseconds, at most 10000.")] = 32.0,
    method: Annotated[GccMethod | None, typer.Option(
        "--method", help="GCC weighting (gcc-ml = Hannan-Thomson); default gcc-phat, or gcc-ml "
        "with --summary-tuned.", show_default=False)] = None,
    no_kalman: Annotated[bool, typer.Option(
        "--no-kalman", help="Report the raw per-frame TDOAs (no ITD Kalman filter).")] = False,
    kalman_tuned: Annotated[bool, typer.Option(
        "--kalman-tuned", help="Choose both of the ITD Kalman filter's noises (random walk "
        "and one measurement noise for every frame) from a grid by the frames' innovation "
        "likelihood, instead of the default (each frame's measurement noise from its GCC "
        "confidence, the random walk by the likelihood, at most a 90 deg/s turn's); the JSON's "
        "kalman_q_std_s / kalman_r_std_s / kalman_noise say what was used.")] = False,
    fmt: Annotated[OutputFormat, typer.Option("--format", help="Output format.")] = (
        OutputFormat.json),
    reverb_method: Annotated[GccMethod | None, typer.Option(
        "--reverb-method", help="Weighting of the whole-recording estimate when the recording "
        "measures as reverberant (coherence below what the noise explains or, for a steady "
        "source with no pause, growing with the frame length), e.g. gcc-phat with --method "
        "gcc-ml.")] = None,
    in_plane: Annotated[bool, typer.Option(
        "--in-plane", help="The source is in the plane of a planar (three-mic) array: model "
        "its spherical wavefront (assumed 2 m away) instead of a plane wave, and search the "
        "whole-recording peak among in-plane directions only. Not for masked arrays.")] = False,
    summary_tuned: Annotated[bool, typer.Option(
        "--summary-tuned", help="The whole-recording estimate's settings that bench/doa.py "
        "measures against pyroomacoustics (hearsee.audio.tdoa.SUMMARY_TUNED: gcc-ml, gcc-phat "
        "when reverberant, Hann frames, onset weighting; with --in-plane and a planar array of "
        "4+ microphones the steered in-plane search when reverberant); with --in-plane the "
        "benchmarked settings but for the benchmark's band limits and its best guess where "
        "hearsee abstains. Sets --method and --reverb-method itself.")] = False,
    band_hz: Annotated[str | None, typer.Option(
        "--band-hz", help="LOW,HIGH: only this frequency band in Hz for the GCC, e.g. 300,3500 "
        "for speech. An empty band at the top of the spectrum (a recording upsampled from a "
        "lower rate) is left out by itself either way; the JSON's band_hz says the band used.",
        show_default=False)] = None,
    tdoa_std_us: Annotated[float | None, typer.Option(
        "--tdoa-std-us", help="Expected error of the whole-recording TDOAs in microseconds, for "
        "the source position of arrays of 4+ microphones: the position is reported (with its "
        "covariance) only where these errors cannot explain the wavefront's curvature away. A "
        "lower bound: raised to 3x the pairs' disagreement (closure) where that is larger, "
        "as in reverberant rooms (the JSON summary's position_tdoa_std_s). Default 5, at most "
        "1e6 (1 s).",
        show_default=False)
    ] = None,
    sources: Annotated[int, typer.Option(
        "--sources", help="Look for up to this many sources talking in turn or at once (1-8): "
        "the frames' directions clustered; the JSON's sources (direction, share of the located "
        "frames) and each frame's source. Above 1 the frames are not smoothed (the ITD Kalman "
        "filter follows one source). Not for masked arrays.")] = 1,
    moving: Annotated[bool, typer.Option(
        "--moving", help="With --sources: the sources may walk -- the frames' directions are "
        "tracked through time instead of clustered; each source adds its first and last frame "
        "(t_start_s, t_end_s) and its path (azimuth at every frame of its life), its direction "
        "is where it was last heard.")] = False,
) -> None:
    """Estimate TDOAs and the source direction per frame and for the whole recording."""
    from hearsee.audio.arrays import MAX_TDOA_STD_S, load_array
    from hearsee.audio.localize import fits_position, localize_recording
    from hearsee.audio.signals import read_recording, recording_entry, recording_label
    from hearsee.audio.sources import MAX_SOURCES
    from hearsee.audio.tdoa import SUMMARY_TUNED, check_frame_ms, dominant_sample, frame_geometry

    check_frame_ms(frame_ms, hop_ms, names=("--frame-ms", "--hop-ms"))
    band = None if band_hz is None else parse_band(band_hz)
    if tdoa_std_us is not None:
        # (the library's bound, in microseconds: 1e300 overflowed squaring it, a traceback)
        finite_number("--tdoa-std-us", tdoa_std_us, 0.0, MAX_TDOA_STD_S * 1e6, lo_open=True)
    if summary_tuned:
        given = [name for name, v in (("--method", method), ("--reverb-method", reverb_method))
                 if v is not None]
        if given:
            raise ConfigError(f"--summary-tuned sets {' and '.join(given)} itself (method "
                              f"{SUMMARY_TUNED['method']}, reverb method "
                              f"{SUMMARY_TUNED['reverb_method']}): leave "
                              f"{'it' if len(given) == 1 else 'them'} out")
        settings = dict(SUMMARY_TUNED)
    else:
        settings = {"method": (method or GccMethod.phat).value,
                    "reverb_method": None if reverb_method is None else reverb_method.value}
    if kalman_tuned and no_kalman:
        raise ConfigError("--kalman-tuned tunes the ITD Kalman filter that --no-kalman turns "
                          "off; give one of them")
    whole_number("--sources", sources, 1, MAX_SOURCES)
    if kalman_tuned and sources > 1:
        raise ConfigError("--kalman-tuned tunes the ITD Kalman filter, which follows one source: "
                          "with --sources above 1 the frames are not smoothed; give one of them")
    if moving and sources < 2:
        raise ConfigError("--moving tracks several sources: give --sources 2 or more with it "
                          "(one moving source: hearsee track)")
    arr = load_array(array)
    if summary_tuned and arr.mask is not None:
        raise ConfigError(f"--summary-tuned: the masked array {arr.name!r} has a pipeline of its "
                          "own (ch. 3) that takes none of those settings; leave it out")
    if band is not None and arr.mask is not None:
        raise ConfigError(f"--band-hz: the masked array {arr.name!r} has a pipeline of its own "
                          "(ch. 3) that sets its bands itself; leave it out")
    if sources > 1 and arr.mask is not None:
        raise ConfigError(f"--sources: the masked array {arr.name!r} has a pipeline of its own "
                          "(ch. 3) that names one source; leave it out")
    if in_plane and arr.mask is not None:
        raise ConfigError(f"--in-plane: the masked array {arr.name!r} has a pipeline of its own "
                          "(ch. 3; tables of the horizontal plane) without an in-plane model; "
                          "leave it out")
    if tdoa_std_us is not None and not fits_position(arr, in_plane):
        # (it was taken and did nothing: only a fitted position uses it)
        why = ("--in-plane does not fit (it assumes the range)" if fits_position(arr)
               else f"array {arr.name!r} does not get (that needs 4+ microphones, not in a "
               "line, without a mask)")
        raise ConfigError(f"--tdoa-std-us sets the TDOA error behind the source position, which "
                          f"{why}; leave it out")
    x, fs = read_recording(recording, arr, channels=parse_channels(channels, arr.n_mics))
    name = recording_label(recording)  # (the file, or the files joined by " + ")
    frame_len, hop = frame_geometry(fs, frame_ms, hop_ms)
    n_frames = max((x.shape[1] - frame_len) // hop + 1, 0)
    work = x.shape[1] / fs * len(arr.pairs)
    with progress("localizing", n_frames, enabled=work > _PROGRESS_WORK_S) as advance:
        doc = localize_recording(x, fs, arr, frame_ms=frame_ms, hop_ms=hop_ms,
                                 kalman=not no_kalman and sources == 1,
                                 tune_kalman=kalman_tuned, progress=advance, in_plane=in_plane,
                                 max_sources=sources, moving=moving,
                                 **settings, **({} if tdoa_std_us is None else
                                                {"tdoa_std_s": tdoa_std_us * 1e-6}),
                                 **({} if band is None else {"band_hz": band}))
    doc["recording"] = recording_entry(recording)
    if fmt is OutputFormat.json:
        emit_json(doc)
    elif fmt is OutputFormat.csv:
        _write_csv(doc)
    else:
        _print_table(doc)
    note_empty_band(name, doc.get("band_hz"), band, fs)
    summ = doc["summary"]
    # (an inverted or dead microphone, channels out of sync and a corrupt sample have their own
    # warnings: nothing was found because of them -- "silence or uncorrelated noise" misled)
    told = dominant_sample(x) is not None or any(summ.get(k) for k in (
        "inverted_microphones", "dead_microphones", "sync_offsets_s"))
    if not told and summ["n_valid_frames"] == 0:
        err_console.print(f"hearsee: warning: {name}: no frame holds a detectable source "
                          "(silence or uncorrelated noise)", highlight=False)
    elif (not told and summ.get("azimuth_deg") is None and summ.get("elevation_deg") is None
          and not doc.get("sources")):
        # (a vertical pair's direction is its elevation alone: its azimuth is always null, and
        # a talker 25 deg up, found within 0.01 deg, was "no direction for the whole recording")
        # (with --sources the sources found say where the frames point: two talkers' averaged
        # correlations name neither)
        # (a summary of nulls beside a few valid frames was printed without a word)
        n = summ["n_valid_frames"]
        err_console.print(f"hearsee: warning: {name}: no direction for the whole recording "
                          f"(its averaged correlations name no source; {n} frame"
                          f"{'' if n == 1 else 's'} on {len(doc['frames'])} had one)",
                          highlight=False)
