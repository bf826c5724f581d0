"""hearsee.config: numbers from mappings and plain-Python conversion for YAML/JSON."""

import numpy as np
import pytest

from hearsee.config import load_yaml, number, save_yaml, to_jsonable
from hearsee.errors import ConfigError


def test_number_takes_numpy_scalars_and_refuses_non_numbers():
    d = {"a": np.int64(7), "b": np.float32(0.5), "c": True, "d": np.bool_(True), "e": "3",
         "f": float("nan"), "g": 2.5}
    assert number(d, "a", 0, "x", integer=True) == 7  # np.int64 was refused
    assert number(d, "b", 0.0, "x") == pytest.approx(0.5)
    for key in ("c", "d", "e", "f"):
        with pytest.raises(ConfigError, match=f"x.{key}: expected a number"):
            number(d, key, 0, "x")
    with pytest.raises(ConfigError, match="whole number"):
        number(d, "g", 0, "x", integer=True)
    with pytest.raises(ConfigError, match="must be <= 2"):
        number(d, "a", 0, "x", hi=2)
    assert number({}, "missing", 4, "x") == 4.0


def test_save_yaml_and_json_take_numpy_values(tmp_path):
    data = {"name": np.str_("rig"), "K": np.eye(2), "n": np.int32(3), "ok": np.bool_(True),
            "bad": np.float64("nan")}
    save_yaml(data, tmp_path / "a.yaml")  # np.str_ made YAML raise RepresenterError
    back = load_yaml(tmp_path / "a.yaml")
    assert back["name"] == "rig" and back["K"] == [[1.0, 0.0], [0.0, 1.0]] and back["n"] == 3
    assert back["ok"] is True
    assert to_jsonable(data)["bad"] is None and to_jsonable(data)["name"] == "rig"
