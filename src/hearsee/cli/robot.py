"""``hearsee demo``, ``hearsee run`` and ``hearsee eval``: the robot pipeline (issue 8)."""

from __future__ import annotations

from pathlib import Path

import typer

from hearsee.cli._app import (
    app,
    check_exports,
    echo_done,
    emit_json,
    folder_path,
    print_summary,
    progress,
    refuse_overwrite,
)


@app.command("demo")
def demo_cmd(
    scenario: Path = typer.Option(None, "--scenario", help="Scenario YAML (default: built-in)."),
    out: Path = typer.Option(Path("hearsee-report"), "--out", "-o", help="Report folder.",
                             parser=folder_path, metavar="<path>"),
    rerun: Path = typer.Option(None, "--rerun", help="Also write a Rerun recording (.rrd)."),
    mcap: Path = typer.Option(None, "--mcap", help="Also write ROS 2 messages to an MCAP file."),
    force: bool = typer.Option(False, "--force",
                               help="Overwrite existing --rerun / --mcap files, and report files "
                                    "in --out that an earlier hearsee report did not write."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar or summary table."),
) -> None:
    """Hear a person, turn to them, see and verify them, track them in 3D; write a report.

    Runs a simulated scenario end to end (the built-in default: a room, the robot head, a woman
    speaking while walking behind the robot, a mannequin nearby) and writes OUT/index.html, the
    JSON log of every estimate and a summary.
    """
    from hearsee.errors import ConfigError
    from hearsee.robot.export import check_export_targets
    from hearsee.robot.pipeline import run_scenario
    from hearsee.robot.report import (
        report_blocker_reason,
        report_folder_blocker,
        report_folder_unwritable,
        report_foreign_file,
        report_overwrites,
        write_report,
    )
    from hearsee.robot.scenario import default_scenario, load_scenario

    sc = load_scenario(scenario) if scenario else default_scenario()
    # the files the run reads: the scenario and the array file it names (not a preset)
    inputs = [scenario, *([Path(sc.robot.array)] if Path(sc.robot.array).is_file() else [])]
    blocker = report_folder_blocker(out)  # (found only after the whole scenario before)
    if blocker is not None:
        raise ConfigError(f"--out {out}: {report_blocker_reason(blocker)}; choose a report "
                          "folder")
    locked = report_folder_unwritable(out)
    if locked is not None:  # (a PermissionError traceback after the whole scenario)
        raise ConfigError(f"--out {out}: folder {locked} is not writable; choose another")
    hit = report_overwrites(out, inputs)
    if hit is not None:
        raise ConfigError(f"--out {out}: the report would overwrite the input {hit}; choose "
                          "another folder")
    # (--force let the export replace the report's log.json: a broken report)
    check_export_targets((("--rerun", rerun), ("--mcap", mcap)), out, f"--out {out}")
    foreign = report_foreign_file(out)
    if foreign is not None and not force:
        raise ConfigError(f"--out {out}: {foreign} exists and is not a hearsee report's; "
                          "choose another folder or pass --force to overwrite it")
    check_exports(rerun, mcap, inputs, force)
    with progress(f"scenario {sc.name}", total=sc.duration_s, enabled=not quiet) as advance:
        result = run_scenario(sc, progress=advance)
    index = write_report(out, sc.to_dict(), result.log, result.summary, result.images,
                         result.captions)
    if rerun is not None:
        from hearsee.robot.export import write_rerun

        write_rerun(rerun, sc.to_dict(), result.log, result.frames)
    if mcap is not None:
        from hearsee.robot.export import write_mcap

        write_mcap(mcap, result.log, result.frames)
    if not quiet:  # (the talker rows only when people took turns; summary.json has them all)
        turns = result.summary.get("talker_changes", 0)
        print_summary("hearsee demo summary", {
            k: v for k, v in result.summary.items()
            if turns or k not in ("talker_changes", "talker_changes_followed",
                                  "time_to_follow_median_s")})
    echo_done([f"report: {index}"], [rerun, mcap])


@app.command("eval")
def eval_cmd(
    scenarios: int = typer.Option(20, "--scenarios", "-n", help="Number of random scenarios, "
                                  "1-1000000."),
    seed0: int = typer.Option(0, "--seed", min=0, help="Seed of the first scenario."),
    workers: int = typer.Option(0, "--workers", help="Local processes (0 = all cores; at most "
                                "1024)."),
    scheduler: str = typer.Option(None, "--scheduler", help="Dask scheduler address (tcp://...)."),
    out: Path = typer.Option(None, "--out", "-o", help="Write per-scenario results (JSON)."),
    duration: float = typer.Option(6.0, "--duration", help="Simulated seconds per scenario, "
                                   "1-120."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing --out file."),
    array: str = typer.Option(None, "--array", help="The robot's microphone array in every "
                              "scenario: a preset or YAML file (default three-mic), e.g. "
                              "mask2-asym for the thesis's masked pair."),
    talkers: int = typer.Option(1, "--talkers", help="1: one speaker; 2: the same scenes with "
                                "a second talker, the two taking turns (try --duration 10)."),
) -> None:
    """Run many random scenarios and summarise success rate and error percentiles (JSON).

    Uses all cores of this machine, or a Dask cluster with --scheduler tcp://HOST:PORT. The
    same seeds give identical numbers either way.
    """
    from hearsee.robot.evaluate import evaluate

    # (before the scenarios run, not after; the array file every scenario reads is an input:
    # `-o` naming it replaced it with the results, given --force, until 2026-12-07)
    refuse_overwrite([out], [Path(array)] if array and Path(array).is_file() else [], force)
    with progress("scenarios", total=scenarios) as advance:
        res = evaluate(scenarios, seed0=seed0, workers=workers or None, scheduler=scheduler,
                       progress=advance, duration_s=duration, array=array, talkers=talkers)
    if out is not None:
        import json

        from hearsee.config import to_jsonable, write_file

        # (beside it, then moved over it: written in place, a failure part way -- a full disk,
        # Ctrl-C -- left half a file where the user's earlier results were)
        write_file(out, json.dumps(to_jsonable({"summary": res.summary, "runs": res.runs}),
                                   indent=1))
    emit_json(res.summary)
