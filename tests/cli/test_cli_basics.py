from hearsee.cli import main


def test_arrays_lists_presets(capsys):
    assert main(["arrays"]) == 0
    out = capsys.readouterr().out
    assert "three-mic" in out and "two-mic" in out


def test_unknown_command_is_usage_error(capsys):
    assert main(["no-such-command"]) == 2


def test_version(capsys):
    assert main(["--version"]) == 0
    assert "hearsee" in capsys.readouterr().out
