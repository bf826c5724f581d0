"""``hearsee eval``: option errors are one line naming the flag, before any scenario runs."""

import pytest

from hearsee.cli import main


@pytest.mark.parametrize("value", ["inf", "nan", "-inf", "1.5", "200"])
def test_eval_duration_error_names_the_flag(value, capsys, tmp_path, monkeypatch):
    """A review reported `hearsee eval --duration inf` as "random_scenario duration_s must be
    ..." (random_scenario's parameter, 1-120 s); evaluate's own check (2-120 s) answers first,
    naming the flag. A guard (the rule's words are evaluate's): inf is not "no limit" here -- a
    simulated scenario has a length."""
    monkeypatch.chdir(tmp_path)
    assert main(["eval", "-n", "1", "--workers", "1", "--duration", value]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith("hearsee: error: --duration must be ") and err.count("\n") == 1, err
    assert err.endswith(f", got {float(value)}\n") and "duration_s" not in err, err
    assert list(tmp_path.iterdir()) == []
