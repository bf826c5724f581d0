"""``hearsee run --config robot.yaml``: the robot on real hardware (issue 8).

Live microphones through sounddevice, cameras through OpenCV ``VideoCapture``, the same
perception and outputs as ``hearsee demo``: one JSON line per update, a report folder and a
summary. ``--dry-run`` only checks the robot file (and the ``--rerun`` / ``--mcap`` outputs)
and opens every device once. The robot file's
schema is in :mod:`hearsee.robot.hardware`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from hearsee.cli._app import (
    app,
    check_exports,
    echo_done,
    err_console,
    folder_path,
    print_summary,
    progress,
)


@app.command("run")
def run_cmd(
    config: Annotated[Path, typer.Option("--config", "-c",
                                         help="Robot file (YAML): devices, head, outputs.")],
    dry_run: Annotated[bool, typer.Option("--dry-run",
                                          help="Check the robot file and open every device "
                                          "once; exit 0 only if all checks pass.")] = False,
    duration: Annotated[float | None, typer.Option(
        "--duration", "-d", help="Stop after this many seconds of audio, > 0; default (or inf): "
        "no limit -- until Ctrl-C or the input stops).")] = None,
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Report folder (overrides output.report; the JSON lines go to "
        "OUT/updates.jsonl).", parser=folder_path, metavar="<path>")] = None,
    rerun: Annotated[Path | None, typer.Option(
        "--rerun", help="Also write a Rerun recording (.rrd; pip install 'hearsee[rerun]').")
    ] = None,
    mcap: Annotated[Path | None, typer.Option(
        "--mcap", help="Also write ROS 2 messages to an MCAP file (pip install 'hearsee[ros]').")
    ] = None,
    force: Annotated[bool, typer.Option(
        "--force", help="Overwrite existing --rerun / --mcap files, and report files in the "
        "report folder that an earlier hearsee report did not write.")] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q",
                                        help="No progress bar or summary table.")] = False,
) -> None:
    """Hear, turn to, see, verify and track a person with the robot's real sensors.

    Writes one JSON line per update (output.jsonl), then the report folder (index.html,
    log.json, summary.json). Stops cleanly on Ctrl-C or after --duration seconds (inf, like
    no --duration, is no limit: the rule of the robot's and the stream's live sources).
    """
    from hearsee.config import time_limit
    from hearsee.errors import ConfigError
    from hearsee.robot.hardware import (
        Check,
        check_devices,
        check_outputs,
        first_failure,
        load_robot_config,
        run_robot,
        write_run_report,
    )

    duration = time_limit("--duration", duration)  # (None: no limit)
    # (with --out the file's own outputs are not written, so not checked: only --out's are)
    cfg = load_robot_config(config, check_output=out is None)
    if out is not None:
        cfg = cfg.with_output(out)
        check_outputs(cfg, f"--out {out}")
    # the exports are written last: never over the run's own JSON lines or report files
    # (they replaced them, --force or not); checked before listening and in the dry run
    from hearsee.robot.export import check_export_targets

    report_name = f"--out {out}" if out is not None else f"output.report {cfg.output.report}"
    check_export_targets((("--rerun", rerun), ("--mcap", mcap)), cfg.output.report,
                         report_name, cfg.output.jsonl)
    # the exports' extras, folders and overwrite rule before listening (and in the dry run):
    # a live run must not fail only when it writes them at its end
    exports = check_exports(rerun, mcap, cfg.input_files(), force)
    from hearsee.robot.report import report_foreign_file

    foreign = report_foreign_file(cfg.output.report)
    if foreign is not None and not force:  # (the report replaced them after the live run)
        raise ConfigError(f"output.report: {foreign} exists and is not a hearsee report's; "
                          "choose another folder or pass --force to overwrite it")
    if dry_run:
        checks = check_devices(cfg) + [Check(name, True, detail) for name, detail in exports]
        _print_checks(checks)
        bad = first_failure(checks)
        if bad is not None:
            raise bad.error if bad.error is not None else ConfigError(bad.detail)
        typer.echo(f"all {len(checks)} checks passed")
        return
    with progress("listening", total=duration, enabled=not quiet and duration is not None) \
            as advance:
        result = run_robot(cfg, duration_s=duration, progress=advance)
    index = write_run_report(cfg, result)
    if rerun is not None:
        from hearsee.robot.export import write_rerun
        from hearsee.robot.hardware import report_scenario

        write_rerun(rerun, report_scenario(cfg), result.log, result.frames)
    if mcap is not None:
        from hearsee.robot.export import write_mcap

        write_mcap(mcap, result.log, result.frames, frame_id="robot")
    if not quiet:
        print_summary("hearsee run summary", result.summary)
    echo_done([f"updates: {cfg.output.jsonl}", f"report: {index}"],
              [rerun, mcap, cfg.output.jsonl])
    status = result.summary["status"]
    if status == "stalled":
        err_console.print("hearsee: error: audio: the input device stopped delivering samples",
                          highlight=False)
        raise typer.Exit(1)


def _print_checks(checks: list) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    t = Table(title="hearsee run --dry-run")
    t.add_column("check")
    t.add_column("result")
    t.add_column("detail", overflow="fold")
    for c in checks:
        # (escaped: rich took the "[live]" of "pip install 'hearsee[live]'" for markup)
        t.add_row(escape(c.name), "[green]ok[/green]" if c.ok else "[red]FAIL[/red]",
                  escape(c.detail))
    Console(width=140).print(t)
