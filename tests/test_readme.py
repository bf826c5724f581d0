"""The README's examples run as written: its Python blocks, and the command-line tour in the
order the README gives it (the commands that need no outside files and no mask model), each
checked against the ground truth its own simulation wrote."""

from __future__ import annotations

import json
import re
import shlex
import subprocess
from pathlib import Path

import numpy as np
import yaml
from sklearn.metrics import adjusted_rand_score

from hearsee.cli import main
from hearsee.geometry import wrap_deg

README = Path(__file__).resolve().parents[1] / "README.md"
#: tour commands run here (``calibrate``/``detect`` need images, ``demo``/``eval``/``run`` are
#: tested on their own, a mask array solves its diffraction model on first use: minutes)
TOUR = ("arrays", "simulate", "localize", "localize3d", "track")


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"^```{lang}\n(.*?)^```", README.read_text(encoding="utf-8"),
                      re.S | re.M)


def _commands() -> list[str]:
    """Shell lines of the README's bash blocks (continuations joined, comments dropped)."""
    out = []
    for block in _blocks("bash"):
        for line in block.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            if words:
                out.append(line)
    return out


def _azimuth_error(a: float, b: float) -> float:
    return abs(float(wrap_deg(a - b)))


def test_readme_python_blocks_run_and_agree_with_their_truth(capsys):
    blocks = _blocks("python")
    assert len(blocks) >= 2
    tour = {}
    exec(blocks[0], tour)  # the ten-line tour: a simulated talker in a room
    assert capsys.readouterr().out.split()[0] == str(tour["loc"].azimuth_deg)
    assert _azimuth_error(tour["loc"].azimuth_deg, tour["truth"]["azimuth_deg"]) < 5.0
    nle = {}
    exec(blocks[1], nle)  # NLE on a swiss roll, ClusteredNLE on two rolls
    assert nle["Y"].shape == (len(nle["X"]), 2) and np.all(np.isfinite(nle["Y"]))
    assert adjusted_rand_score(nle["sheet"], nle["labels"]) > 0.9


def test_readme_command_line_tour(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    ran = []
    for line in _commands():
        words = shlex.split(line, comments=True)
        if words[0] == "printf":  # the tour writes its trajectory with the shell
            subprocess.run(["bash", "-c", line], cwd=tmp_path, check=True)
            continue
        if words[0] != "hearsee" or words[1] not in TOUR or any("mask2" in w for w in words):
            continue
        code = main(words[1:])
        out, err = capsys.readouterr()
        assert code == 0, f"{line}\n{err}"
        ran.append((words, out))
    assert {w[1] for w, _ in ran} == set(TOUR)
    # the recording's summary azimuth against the truth simulate wrote beside it
    truth = json.loads((tmp_path / "rec.json").read_text())
    loc = json.loads(next(o for w, o in ran if w[1:3] == ["localize", "rec.wav"]
                          and "json" in w))
    assert _azimuth_error(loc["summary"]["azimuth_deg"], truth["azimuth_deg"]) < 5.0
    # three head poses give the distance too (localize3d's own truth is in the capture file)
    cap = yaml.safe_load((tmp_path / "cap.yaml").read_text())["truth"]
    l3 = json.loads(next(o for w, o in ran if w[1] == "localize3d"))
    assert _azimuth_error(l3["azimuth_deg"], cap["azimuth_deg"]) < 3.0
    assert abs(l3["elevation_deg"] - cap["elevation_deg"]) < 3.0
    assert abs(l3["distance_m"] / cap["distance_m"] - 1.0) < 0.2
    # the tracked talker at the end of the walk: (2, 1.5, 0.3) m heard from the array
    last = json.loads(next(o for w, o in ran if w[1] == "track").strip().splitlines()[-1])
    assert _azimuth_error(last["azimuth_deg"], np.degrees(np.arctan2(1.5, 2.0))) < 10.0


RESULTS = README.parent / "bench" / "results"


def _table(name: str, header_start: str) -> list[dict[str, str]]:
    """Rows of the first table of ``bench/results/<name>`` whose header line starts so."""
    def cells(line: str) -> list[str]:
        return [c.strip() for c in re.split(r"(?<!\\)\|", line.strip().strip("|"))]

    lines = (RESULTS / name).read_text(encoding="utf-8").splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith(header_start))
    header, rows = cells(lines[i]), []
    for line in lines[i + 2:]:
        if not line.startswith("|"):
            break
        rows.append(dict(zip(header, cells(line), strict=True)))
    return rows


def _signed(x: float, fmt: str = ".1f") -> str:
    return format(x, fmt).replace("-", "−")


def test_readme_quotes_the_committed_benchmark_results():
    """Numbers the README's benchmark rows quote, recomputed from bench/results/*.md."""
    text = " ".join(README.read_text(encoding="utf-8").split())
    # four_mics part 1: cells where hearsee's answer is worse than the plane wave
    cells = _table("four_mics.md", "| array | size m |")
    worse = [r for r in cells
             if float(r["hearsee RMSE deg"]) > float(r["plane wave RMSE deg"])]
    words = {1: "one", 2: "two", 3: "three", 4: "four", 5: "five"}
    assert f"TDOA level: {words.get(len(worse), len(worse))} of {len(cells)} cells worse" in text
    # tracking part A: the pooled lag on turning walks
    lags = [float(r["pooled lag frames, turning walks"])
            for r in _table("tracking.md", "| signal | SNR dB | per-frame RMSE")]
    assert (f"pooled lag on turning walks {_signed(min(lags))} to {_signed(max(lags))} frames"
            in text)
    # nle scaling: n = 20,000, hearsee's NLE against standard LLE
    times = {r["method"]: float(r["time [s]"])
             for r in _table("nle.md", "| n | method | time [s]") if r["n"] == "20000"}
    assert (f"n = 20,000 in {times['NLE (hearsee)']:.1f} s vs {times['LLE standard']:.1f} s"
            in text)
    # doa: CPU per second of audio against the recording's length
    rows = _table("doa.md", "| array | signal | 2 s:")
    ranges = []
    for col in ("2 s", "8 s", "32 s"):
        key = next(k for k in rows[0] if k.startswith(col + ":"))
        x = [float(re.search(r"\(([0-9.]+)x\)", r[key]).group(1)) for r in rows]
        ranges.append(f"{min(x):.1f}–{max(x):.1f}x")
    added = [float(r["per added s: speed-up"]) for r in rows]
    assert (f"hearsee is {ranges[0]} cheaper at 2 s, {ranges[1]} at 8 s and {ranges[2]} at "
            f"32 s, and each further second costs it {min(added):.2g}–{max(added):.2g}x less"
            in text)
