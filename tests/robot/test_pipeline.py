"""The robot loop end to end on a short scenario whose ground truth the test sets up."""

import json

import numpy as np
import pytest

from hearsee.cli import main
from hearsee.robot.pipeline import run_scenario
from hearsee.robot.report import write_report
from hearsee.robot.scenario import scenario_from_dict

# robot at (3.5, 2.6) facing +x; the speaker stands 2.2 m away at azimuth ~50 deg and walks
# slowly; a mannequin 1.6 m away at azimuth ~80 deg is in view once the head has turned
SHORT = {
    "name": "short", "seed": 3, "duration_s": 3.0,
    "robot": {"position_m": [3.5, 2.6]},
    "people": [{"path_m": [[4.9, 4.3], [4.6, 4.4]], "voice": "male"}],
    "objects": [{"kind": "mannequin", "position_m": [3.8, 4.2]}],
}


@pytest.fixture(scope="module")
def short_run():
    sc = scenario_from_dict(SHORT)
    return sc, run_scenario(sc)


@pytest.mark.slow
def test_hears_turns_verifies_and_tracks(short_run):
    sc, res = short_run
    s = res.summary
    truth_az = res.log[0]["truth"]["azimuth_robot_deg"]
    assert 40 < truth_az < 60
    # the first audio bearing is within a few degrees of the truth (full 360-degree azimuth)
    assert s["azimuth_error_initial_deg"] < 5.0
    # the head turned toward the person
    assert abs(res.log[-1]["head_pan_deg"] - res.log[-1]["truth"]["azimuth_robot_deg"]) < 5.0
    # verified by stereo + thermal and tracked in 3D within 15 cm (room frame, torso centre)
    assert s["success"] and s["tracked_steps"] >= 5
    assert s["position_error_median_m"] < 0.15
    # the mannequin was seen and never reported as a person
    assert s["human_like_objects_rejected"] >= 1
    assert s["false_person_objects"] == 0
    # errors in the log are the distance between the track and the truth
    rec = next(r for r in res.log if r["track"] is not None)
    d = np.linalg.norm(np.asarray(rec["track"]["position_m"]) - rec["truth"]["position_m"])
    assert rec["error_m"] == pytest.approx(d)


@pytest.mark.slow
def test_report_holds_the_run_numbers(short_run, tmp_path):
    sc, res = short_run
    index = write_report(tmp_path / "rep", sc.to_dict(), res.log, res.summary, res.images,
                         res.captions)
    html = index.read_text()
    assert f"{res.summary['position_error_median_m']:.3g}" in html
    for f in ("plots/top_view.png", "plots/error.png", "plots/head.png", "log.json",
              "summary.json"):
        assert (index.parent / f).stat().st_size > 0
    assert any(p.name.endswith("_overlay.png") for p in (index.parent / "frames").iterdir())
    log = json.loads((index.parent / "log.json").read_text())
    assert len(log) == len(res.log) and log[-1]["t"] == pytest.approx(3.0)


def test_demo_rejects_a_broken_scenario(tmp_path, capsys):
    bad = tmp_path / "s.yaml"
    bad.write_text("robot:\n  position_m: [3.5, 2.6]\n  heigth: 1.2\n")
    assert main(["demo", "--scenario", str(bad), "-o", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "unknown key 'heigth'" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_demo_will_not_write_over_its_input(tmp_path, capsys):
    sc = tmp_path / "s.yaml"
    sc.write_text("name: x\n")
    assert main(["demo", "--scenario", str(sc), "-o", str(tmp_path), "-q"]) == 2
    assert "overwrite" in capsys.readouterr().err
    assert sc.read_text() == "name: x\n"


def test_associate_picks_the_nearest_person_inside_the_gate():
    """The one association rule of the simulated and the live loop: before a 3D track, the
    verified person nearest the audio bearing within ASSOCIATION_GATE_DEG (wrapping at 180
    deg); with a track, the one nearest its position within TRACK_GATE_M."""
    from hearsee.audio.tracking import MotionKalman
    from hearsee.robot.pipeline import ASSOCIATION_GATE_DEG, TRACK_GATE_M, associate

    kf = MotionKalman()
    people = [np.array([1.0, 0.0, 1.2]), np.array([0.0, 2.0, 1.2]), np.array([-2.0, 0.1, 1.2])]
    bearings = [0.0, 90.0, 177.0]
    # no track: by bearing; -178 deg is 5 deg from 177 across the wrap
    assert associate(people, bearings, kf, -178.0) == 2
    assert associate(people, bearings, kf, 80.0) == 1
    assert associate(people, bearings, kf, 45.0) is None  # 45 deg from both neighbours
    assert associate(people, bearings, kf, ASSOCIATION_GATE_DEG + 0.5) is None
    assert associate(people, bearings, kf, None) is None
    assert associate([], [], kf, 0.0) is None
    # with a track at (0, 1.6, 1.2): the person at (0, 2, 1.2) is 0.4 m away, whatever the
    # audio says; moved TRACK_GATE_M + 0.1 m away, nobody is associated
    kf.update(0.0, [0.0, 1.6, 1.2])
    assert kf.initialized
    assert associate(people, bearings, kf, 0.0) == 1
    far = [p + [0.0, 0.4 + TRACK_GATE_M + 0.1, 0.0] for p in people]
    assert associate(far, bearings, kf, 90.0) is None
