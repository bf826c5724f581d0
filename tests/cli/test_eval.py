"""``hearsee eval``: option errors are one line naming the flag, before any scenario runs."""

import pytest

from hearsee.cli import main


@pytest.mark.parametrize("value", ["inf", "nan", "-inf", "0.5", "200"])
def test_eval_duration_error_names_the_flag(value, capsys, tmp_path, monkeypatch):
    """A review reported `hearsee eval --duration inf` as "random_scenario duration_s must be
    ..." (random_scenario's parameter); evaluate's own check (the same 1-120 s, a scenario's
    range) answers first, naming the flag. A guard (the rule's words are evaluate's): inf is
    not "no limit" here -- a simulated scenario has a length."""
    monkeypatch.chdir(tmp_path)
    assert main(["eval", "-n", "1", "--workers", "1", "--duration", value]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith("hearsee: error: --duration must be ") and err.count("\n") == 1, err
    assert err.endswith(f", got {float(value)}\n") and "duration_s" not in err, err
    assert list(tmp_path.iterdir()) == []


def test_eval_takes_any_scenario_length(capsys, tmp_path, monkeypatch):
    """`hearsee eval --duration 1.5` was refused ("in [2, 120]") though a scenario file and
    random_scenario take 1-120 s and nothing in a run needs 2 s; one range now
    (hearsee.robot.scenario.MIN_DURATION_S / MAX_DURATION_S). The runs are stubbed: what
    reaches them is checked."""
    import json

    import hearsee.robot.evaluate as ev

    got = []
    monkeypatch.setattr(ev, "run_one", lambda seed, duration_s: got.append((seed, duration_s))
                        or {"success": True, "seed": seed})
    monkeypatch.chdir(tmp_path)
    assert main(["eval", "-n", "2", "--seed", "3", "--workers", "1", "--duration", "1.5"]) == 0
    out, _ = capsys.readouterr()
    assert got == [(3, 1.5), (4, 1.5)]
    assert json.loads(out[out.index("{"):])["scenarios"] == 2


@pytest.mark.parametrize("address", ["not an address", "tcp://"])
def test_eval_bad_scheduler_address_is_one_line(address, capsys, tmp_path, monkeypatch):
    """A --scheduler that distributed cannot parse (no port, nothing) was a builtin ValueError
    traceback; an unreachable one already was one line. Now one ConfigError line naming the
    option, exit 2, nothing written."""
    pytest.importorskip("distributed")
    monkeypatch.chdir(tmp_path)
    assert main(["eval", "-n", "1", "--scheduler", address, "-o", "runs.json"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith(f"hearsee: error: --scheduler {address!r} is not a Dask scheduler "
                          "address (tcp://HOST:PORT)") and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []


def _no_run(*args, **kwargs):
    raise AssertionError("the scenarios ran although --out is refused")


@pytest.mark.parametrize("case", ["missing folder", "folder", "existing file"])
def test_eval_out_is_checked_before_the_scenarios_run(case, capsys, monkeypatch, tmp_path):
    """`hearsee eval -o` wrote the results only after every scenario had run: into a missing
    folder or onto a folder it raised a builtin FileNotFoundError / IsADirectoryError (a
    traceback, the run lost), and an existing file was replaced without a word. Now each is
    refused before any scenario runs, and an existing file is kept unless --force."""
    import hearsee.robot.evaluate as ev

    monkeypatch.setattr(ev, "evaluate", _no_run)
    kept = tmp_path / "results.json"
    kept.write_text("my earlier results\n", encoding="utf-8")
    out, expect = {"missing folder": (tmp_path / "no" / "r.json", "does not exist"),
                   "folder": (tmp_path, "is a folder"),
                   "existing file": (kept, "file exists; pass --force")}[case]
    assert main(["eval", "-n", "1", "--duration", "2", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"hearsee: error: {out}: ") and expect in err, err
    assert err.count("\n") == 1
    assert kept.read_text(encoding="utf-8") == "my earlier results\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json"]


def test_eval_force_overwrites_the_out_file(capsys, monkeypatch, tmp_path):
    """--force: the existing --out file is replaced by the results."""
    import json

    import hearsee.robot.evaluate as ev

    monkeypatch.setattr(ev, "evaluate", lambda *a, **k: ev.EvalResult(
        runs=[{"seed": 0}], summary={"scenarios": 1}))
    out = tmp_path / "results.json"
    out.write_text("old\n", encoding="utf-8")
    assert main(["eval", "-n", "1", "--duration", "2", "-o", str(out), "--force"]) == 0
    assert json.loads(out.read_text(encoding="utf-8"))["summary"] == {"scenarios": 1}
    assert json.loads(capsys.readouterr().out) == {"scenarios": 1}


def test_eval_refuses_to_write_its_results_over_the_array_file(capsys, monkeypatch, tmp_path):
    """`hearsee eval --array mics.yaml -o mics.yaml --force` replaced the user's array file,
    which every scenario reads, with the results (2026-12-07 robot review): an input is now
    refused whatever --force says, as `hearsee demo` refuses its own inputs."""
    import hearsee.robot.evaluate as ev

    monkeypatch.setattr(ev, "evaluate", _no_run)
    mics = tmp_path / "mics.yaml"
    text = "microphones: [[0.075, 0, 0], [-0.075, 0, 0]]\n"
    mics.write_text(text, encoding="utf-8")
    for force in ([], ["--force"]):
        assert main(["eval", "-n", "1", "--duration", "2", "--array", str(mics), "-o",
                     str(mics), *force]) == 2
        assert capsys.readouterr().err == (f"hearsee: error: {mics}: refusing to overwrite an "
                                           "input file; choose another output path\n")
    assert mics.read_text(encoding="utf-8") == text


def test_eval_out_that_fails_part_way_keeps_the_earlier_file(capsys, monkeypatch, tmp_path,
                                                            file_size_limit):
    """`hearsee eval -o results.json --force` wrote the results in place: a full disk (here a
    file size limit) left half a JSON file where the user's earlier results were. Now the
    results are written beside the file and moved over it when complete: the earlier file
    stays, one line names it, no temporary file is left. Over a FIFO they are written through
    (the pipe stays a pipe, its reader gets the results)."""
    import json
    import os
    import stat

    import hearsee.robot.evaluate as ev

    runs = [{"seed": k, "note": "x" * 100} for k in range(1000)]  # (~130 kB of JSON)
    monkeypatch.setattr(ev, "evaluate", lambda *a, **k: ev.EvalResult(
        runs=runs, summary={"scenarios": len(runs)}))
    out = tmp_path / "results.json"
    out.write_text("my earlier results\n", encoding="utf-8")
    with file_size_limit(64_000):
        code = main(["eval", "-n", "2", "-o", str(out), "--force"])
    err = capsys.readouterr().err
    assert code == 2 and err == f"hearsee: error: {out}: cannot write (File too large)\n"
    assert out.read_text(encoding="utf-8") == "my earlier results\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json"]
    assert main(["eval", "-n", "2", "-o", str(out), "--force"]) == 0
    assert json.loads(out.read_text(encoding="utf-8"))["runs"] == runs
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json"]
    if not hasattr(os, "mkfifo"):
        return
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    fd = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # (a reader, so the writer can open)
    try:
        runs[:] = runs[:3]  # (what a pipe's buffer holds without a reader reading)
        first = list(runs)
        assert main(["eval", "-n", "2", "-o", str(fifo), "--force"]) == 0
        data = os.read(fd, 1 << 16)
        # a pipe holds no earlier results: no --force needed (`-o /dev/stdout | jq` was
        # refused as "file exists" until 2026-12-03)
        runs[:] = runs[:2]
        assert main(["eval", "-n", "2", "-o", str(fifo)]) == 0
        data2 = os.read(fd, 1 << 16)
    finally:
        os.close(fd)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and json.loads(data)["runs"] == first
    assert json.loads(data2)["runs"] == runs == first[:2]


@pytest.mark.parametrize("n", ["0", "1000001", "100000000000"])
def test_eval_scenario_count_out_of_range_is_one_line(n, capsys, tmp_path, monkeypatch):
    """`hearsee eval -n 100000000000` built a list of every seed first: a MemoryError
    traceback. The count is checked (1 to MAX_SCENARIOS) before anything runs."""
    from hearsee.robot.evaluate import MAX_SCENARIOS

    assert MAX_SCENARIOS == 1_000_000
    monkeypatch.chdir(tmp_path)
    assert main(["eval", "-n", n, "--workers", "1"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith("hearsee: error: --scenarios must be ") and \
        err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("workers", ["1025", "99999999999999999999"])
def test_eval_absurd_worker_count_is_one_line(workers, capsys, tmp_path, monkeypatch):
    """`hearsee eval --workers 99999999999999999999` reached multiprocessing as a C int: an
    OverflowError traceback. Now at most evaluate.MAX_WORKERS (1024): one line naming the
    flag, exit 2, before any scenario runs or anything is written."""
    import hearsee.robot.evaluate as ev

    monkeypatch.setattr(ev, "run_one", _no_run)
    monkeypatch.chdir(tmp_path)
    assert main(["eval", "-n", "2", "--workers", workers, "-o", "runs.json"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err == (f"hearsee: error: --workers must be an integer in [0, 1024], "
                                 f"got {workers}\n")
    assert list(tmp_path.iterdir()) == []


def test_eval_runs_no_more_workers_than_scenarios(capsys, tmp_path, monkeypatch):
    """--workers 8 for one scenario runs it in this process (one worker is enough): the
    count is never more than the scenarios."""
    import hearsee.robot.evaluate as ev

    got = []
    monkeypatch.setattr(ev, "run_one", lambda seed, duration_s: got.append(seed)
                        or {"success": True, "seed": seed})
    monkeypatch.chdir(tmp_path)
    assert main(["eval", "-n", "1", "--seed", "5", "--workers", "8"]) == 0
    assert got == [5]
