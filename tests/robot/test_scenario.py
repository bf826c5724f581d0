import numpy as np
import pytest
import yaml

from hearsee.errors import ConfigError
from hearsee.robot.scenario import (
    default_scenario,
    load_scenario,
    random_scenario,
    scenario_from_dict,
)


def test_default_round_trips_through_yaml(tmp_path):
    sc = default_scenario()
    p = tmp_path / "s.yaml"
    p.write_text(yaml.safe_dump(sc.to_dict()))
    back = load_scenario(p)
    assert back.to_dict() == sc.to_dict()


def test_person_walks_the_path_at_constant_speed():
    sc = scenario_from_dict({"duration_s": 4.0, "people": [{"path_m": [[1, 1], [3, 1]]}],
                             "objects": []})
    np.testing.assert_allclose(sc.person_position(0, [0.0, 2.0, 4.0]), [[1, 1], [2, 1], [3, 1]])
    assert sc.person_speed_mps(0) == pytest.approx(0.5)


@pytest.mark.parametrize("data, field", [
    ({"robt": {}}, "unknown key 'robt'"),
    ({"robot": {"arrays": "three-mic"}}, "scenario.robot: unknown key 'arrays'"),
    ({"robot": {"array": "five-mic"}}, "scenario.robot.array"),
    ({"robot": {"array": "two-mic"}}, "scenario.robot.array: 'two-mic' cannot be simulated"),
    ({"robot": {"array": "mask2"}}, "scenario.robot.array: 'mask2' cannot be simulated"),
    ({"robot": {"head_height_m": 3.5}}, "scenario.robot.head_height_m"),
    ({"room": {"size_m": [1, 5, 3]}}, "scenario.room.size_m"),
    ({"room": {"rt60_s": "long"}}, "scenario.room.rt60_s"),
    ({"people": [{"height_m": 1.7}]}, r"scenario.people\[0\]: missing required key 'path_m'"),
    ({"people": [{"path_m": [[9, 9]]}]}, r"scenario.people\[0\].path_m"),
    ({"people": [{"path_m": [[3.5, 3.0]]}]}, "within 0.6 m of the robot"),
    ({"people": [{"path_m": [[1, 1]], "voice": "robot"}]}, r"scenario.people\[0\].voice"),
    ({"objects": [{"kind": "statue", "position_m": [1, 1]}]}, r"scenario.objects\[0\].kind"),
    ({"objects": [{"kind": "poster"}]}, r"scenario.objects\[0\]: missing required key"),
    ({"audio": {"fs": 44100.5}}, "scenario.audio.fs"),
])
def test_bad_scenarios_name_the_field(data, field):
    with pytest.raises(ConfigError, match=field):
        scenario_from_dict(data)


def test_random_scenarios_are_valid_and_deterministic():
    for seed in range(30):
        sc = random_scenario(seed)
        again = scenario_from_dict(sc.to_dict())  # passes every validation rule
        assert again.to_dict() == random_scenario(seed).to_dict()
        d = np.linalg.norm(sc.people[0].path_m - sc.robot.position_m, axis=1)
        assert np.all(d > 1.0)
