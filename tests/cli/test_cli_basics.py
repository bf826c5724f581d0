import pytest

from hearsee.cli import main


def test_arrays_lists_presets(capsys):
    assert main(["arrays"]) == 0
    out = capsys.readouterr().out
    assert "three-mic" in out and "two-mic" in out
    # the masked presets say so (the list gave no hint which of them resolve front/back)
    lines = {ln.split()[0]: ln for ln in out.splitlines()}
    assert "rigid egg mask" in lines["mask2"] and "turned 25 deg" in lines["mask2-asym"]
    assert "mask" not in lines["two-mic"] and "mask" not in lines["three-mic"]


def test_unknown_command_is_usage_error(capsys):
    assert main(["no-such-command"]) == 2
    err = capsys.readouterr().err
    assert err == "hearsee: error: No such command 'no-such-command'. (see 'hearsee --help')\n"


# (the usage errors click reports are worded by typer / click: "No such option: --bogus" with
# typer 0.2x, "No such option '--bogus'." with 0.18; the contract is hearsee's prefix, one
# line, exit code 2 and the option named)
@pytest.mark.parametrize(("argv", "needle"), [
    (["track"], "--array"),  # (a required option: typer 0.16 with click >= 8.3 ran the command)
    (["localize", "--bogus", "x"], "--bogus"),
    (["simulate", "o.wav", "--array", "two-mic", "--source", "1,2"], "expected 3 numbers"),
    (["simulate", "o.wav", "--array", "two-mic", "--source", "1,1,0", "--seed", "-1"], "--seed"),
    (["eval", "--seed", "-5"], "--seed"),
])
def test_usage_errors_are_one_line(argv, needle, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # nothing may be written, wherever the command points
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, err
    assert err.startswith(f"hearsee {argv[0]}: error: ") and needle in err, err
    assert err.rstrip().endswith(f"(see 'hearsee {argv[0]} --help')") and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_bare_command_prints_help(capsys):
    assert main([]) == 2  # click's convention for no_args_is_help
    assert "Commands" in capsys.readouterr().err


def test_version(capsys):
    assert main(["--version"]) == 0
    assert "hearsee" in capsys.readouterr().out


@pytest.mark.parametrize("argv", [
    ["localize", "missing.wav", "--array", "three-mic", "--frame-ms", "0"],
    ["track", "missing.wav", "--array", "three-mic", "--hop-ms", "-1"],
    ["localize3d", "missing.yaml", "--frame-ms", "1e9"],
])
def test_frame_options_checked_before_reading(argv, capsys, tmp_path, monkeypatch):
    # the files do not exist: the option error must come first and name the options
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("hearsee: error: --frame-ms and --hop-ms must be ") and \
        err.count("\n") == 1, err


def test_exit_codes_of_commands_pass_through(monkeypatch, capsys):
    """A command that ends with typer.Exit(n) (``run`` when the audio device stalls) exits n."""
    import typer

    import hearsee.cli as cli

    app = typer.Typer()

    @app.command()
    def stall(code: int = 1) -> None:
        raise typer.Exit(code)

    @app.command()
    def fine() -> None:
        pass

    monkeypatch.setattr(cli, "app", app)
    assert cli.main(["stall", "--code", "3"]) == 3
    assert cli.main(["fine"]) == 0


def test_files_the_system_refuses_are_one_line_not_a_traceback(monkeypatch, capsys):
    """An OSError a command did not foresee (no read permission on a calibration file, a
    folder that became read-only, a full disk) printed a traceback; now one line naming the
    file, exit 2. Out of memory: one line, exit 1."""
    import errno

    import typer

    import hearsee.cli as cli

    app = typer.Typer()

    @app.command()
    def denied() -> None:
        raise PermissionError(errno.EACCES, "Permission denied", "calib.yaml")

    @app.command()
    def full() -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    @app.command()
    def huge() -> None:
        raise MemoryError

    monkeypatch.setattr(cli, "app", app)
    for argv, code, line in ((["denied"], 2, "hearsee: error: calib.yaml: Permission denied"),
                             (["full"], 2, "hearsee: error: No space left on device"),
                             (["huge"], 1, "hearsee: error: out of memory")):
        capsys.readouterr()
        assert cli.main(argv) == code
        err = capsys.readouterr().err
        assert err.startswith(line) and err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.parametrize("argv", [["arrays"], ["localize", "rec.wav", "--array", "three-mic"]])
def test_ctrl_c_is_one_line_and_exit_130(argv, monkeypatch, capsys, tmp_path):
    """Ctrl-C in a command ended it with exit 130 and nothing on stderr: typer (0.2x) turns a
    KeyboardInterrupt into a silent Exit(130) before main's handler sees it, so its
    "hearsee: interrupted" was never printed. Now that line, exit 130, nothing on stdout."""
    import hearsee.audio.arrays as arrays

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(arrays, "list_presets", interrupt)
    monkeypatch.setattr(arrays, "load_array", interrupt)
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 130
    out, err = capsys.readouterr()
    assert out == "" and err == "hearsee: interrupted\n"


def _option_help(capsys, command: str, option: str) -> str:
    """The help text of ``option`` in ``hearsee COMMAND --help``, its lines joined."""
    assert main([command, "--help"]) == 0
    lines = capsys.readouterr().out.splitlines()
    start = next(i for i, s in enumerate(lines) if s.strip().startswith(option))
    text = [lines[start].strip()]
    for s in lines[start + 1:]:
        if s.strip().startswith("-"):
            break
        text.append(s.strip())
    return " ".join(" ".join(text).split())


def test_option_help_states_the_ranges_the_code_enforces(capsys):
    """Options whose values the code bounds said nothing of the bounds (simulate --fs, --snr,
    --duration; eval -n, --duration; calibrate --square; detect --camera-height; the frame
    options), and two said what is not so: --pcm16 "instead of float32" (a .flac is 24-bit
    PCM without it) and calibrate --reference "with M1/M2 (and D1/D2) to compare against"
    (D1/D2 are not compared). Each now states the rule, from the constants that enforce it."""
    from hearsee.audio.propagation import MAX_SNR_DB, MIN_SNR_DB
    from hearsee.audio.signals import MAX_SIGNAL_S
    from hearsee.audio.tdoa import MAX_FRAME_MS, MIN_FS_HZ
    from hearsee.robot.evaluate import MAX_SCENARIOS
    from hearsee.robot.scenario import MAX_DURATION_S, MIN_DURATION_S
    from hearsee.sim.audio import MAX_SIM_FS_HZ

    h = lambda c, o: _option_help(capsys, c, o)  # noqa: E731
    assert f"{MIN_FS_HZ:g}-{MAX_SIM_FS_HZ}" in h("simulate", "--fs")
    assert f"{MIN_SNR_DB:g} to {MAX_SNR_DB:g}" in h("simulate", "--snr")
    assert f"at most {MAX_SIGNAL_S:g}" in h("simulate", "--duration")
    assert ".flac: instead of 24-bit PCM" in h("simulate", "--pcm16")
    assert f"1-{MAX_SCENARIOS}" in h("eval", "-n, --scenarios")
    assert f"{MIN_DURATION_S:g}-{MAX_DURATION_S:g}" in h("eval", "--duration")
    assert "0.001-2" in h("calibrate", "--square")
    assert "D1" not in h("calibrate", "--reference")
    assert "0.1-5" in h("detect", "--camera-height")
    for command in ("localize", "localize3d", "track"):
        for option in ("--frame-ms", "--hop-ms"):
            assert f"at most {MAX_FRAME_MS:g}" in h(command, option)
