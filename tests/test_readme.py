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
