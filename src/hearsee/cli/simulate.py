"""``hearsee simulate``: write a simulated N-channel recording and its ground-truth JSON."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from hearsee.cli._app import (
    app,
    err_console,
    parse_floats,
    progress,
    refuse_overwrite,
    stage_progress,
)
from hearsee.errors import ConfigError, InputFileError

#: Length of a static source's recording without ``--duration``, seconds.
DEFAULT_DURATION_S = 2.0


def _room_from_options(room: str | None, rt60: float | None,
                       array_at: str | None) -> dict | None:
    """The ``room`` mapping of :func:`hearsee.sim.audio.simulate_recording` from the options."""
    if room is None:
        if rt60 is not None or array_at is not None:
            raise ConfigError("--rt60 and --array-at need --room LxWxH (room size in metres)")
        return None
    dims = parse_floats(room.lower().replace("x", ","), 3, "--room")
    if rt60 is None:
        raise ConfigError("--room needs --rt60 (reverberation time in seconds; 0 = anechoic)")
    out: dict = {"room_dim": dims, "rt60": rt60}
    if array_at is not None:
        out["array_at"] = parse_floats(array_at, 3, "--array-at")
    return out


def _check_output(out: Path, poses: bool) -> None:
    """Before any work: ``out`` names a file of the right type, else one line. ``.``, ``/`` and
    ``''`` (a folder, with an empty name) crashed deriving OUT.json / OUT_pose<k>.wav from it
    (ValueError traceback); a wrong suffix was refused only after the whole simulation."""
    example = "OUT.yaml" if poses else "OUT.wav"
    if out.is_dir() or out.name in ("", ".", ".."):
        raise InputFileError(f"{out}: is a folder, expected an output file name (e.g. "
                             f"{example})")
    if not poses and out.suffix.lower() not in (".wav", ".flac"):
        raise ConfigError(f"{out}: output must end in .wav (or .flac)")


def _metres(d: float) -> str:
    """A distance in metres for the summary line: centimetres (``1.41``), or 3 significant
    digits beyond 1e6 m (a far-field source 1e300 m away printed 300 digits)."""
    return f"{d:.2f}" if d < 1e6 else f"{d:.3g}"


def _simulate_moving(out: Path, array: str, trajectory: Path, signal: str,
                     duration: float | None,
                     fs: int, snr: float | None, room_spec: dict | None, seed: int,
                     far_field: bool, pcm16: bool, force: bool, protect: list) -> None:
    """``--trajectory``: a moving source (hearsee.sim.moving), truth CSV beside the WAV.
    ``protect``: the input files besides the trajectory that no output may replace."""

    from hearsee.sim.audio import save_recording
    from hearsee.sim.moving import (
        load_trajectory,
        save_trajectory,
        simulate_moving_recording,
        truth_times,
    )

    if far_field:
        raise ConfigError("--far-field applies to a static --source only")
    traj = load_trajectory(trajectory)
    truth_csv = Path(out).with_suffix(".trajectory.csv")
    protect = [*protect, *([trajectory] if Path(trajectory).is_file() else [])]
    refuse_overwrite([Path(out), Path(out).with_suffix(".json"), truth_csv], protect, force)
    with stage_progress("simulating") as report:
        x, truth = simulate_moving_recording(array, traj, signal=signal, duration_s=duration,
                                             fs=fs, snr_db=snr, room=room_spec, seed=seed,
                                             progress=report)
    truth["trajectory_csv"] = truth_csv.name
    wav, js = save_recording(out, x, truth, subtype="PCM_16" if pcm16 else "FLOAT",
                             protect=protect)
    save_trajectory(traj, truth_csv, times=truth_times(traj, truth["duration_s"]))
    err_console.print(
        f"wrote {wav} ({x.shape[0]} channels, {x.shape[1] / fs:.2f} s at {fs} Hz), {js} and "
        f"{truth_csv} (moving source, {len(traj.t)} trajectory points)", highlight=False)


@app.command("simulate")
def simulate_cmd(
    out: Annotated[Path, typer.Argument(help="Output WAV (channel k = microphone k); the ground "
                                        "truth goes to the same name with .json.")],
    array: str = typer.Option(..., "--array", help="Array preset name or YAML file."),
    source: str | None = typer.Option(None, "--source",
                                      help="Source position X,Y,Z in metres, array frame "
                                      "(x forward, y left, z up); or use --trajectory."),
    trajectory: Path | None = typer.Option(
        None, "--trajectory",
        help="Moving source: CSV t,x,y,z (seconds, metres, array frame); the ground-truth "
        "trajectory is written beside the WAV as OUT.trajectory.csv (where the source is at t; "
        "the array hears it r/c later, see hearsee.sim.moving.Trajectory.heard_at)."),
    signal: str = typer.Option("noise", "--signal",
                               help="noise | male | female | PATH to an audio file."),
    duration: float | None = typer.Option(
        None, "--duration", help="Length in seconds, at most 600 (default: 2 s; with "
        "--trajectory, the trajectory's last time)."),
    fs: int = typer.Option(16000, "--fs", help="Sample rate in Hz, 4000-384000."),
    snr: float | None = typer.Option(None, "--snr", help="Sensor-noise SNR in dB, -60 to 200 "
                                     "(default: none)."),
    room: str | None = typer.Option(None, "--room",
                                    help="Shoebox room LxWxH in metres (default: free field)."),
    rt60: float | None = typer.Option(None, "--rt60",
                                      help="Room reverberation time in seconds (0 = anechoic); "
                                      "required with --room."),
    array_at: str | None = typer.Option(None, "--array-at",
                                        help="Array origin X,Y,Z in room coordinates "
                                        "(default: the room centre)."),
    seed: int = typer.Option(0, "--seed", min=0, help="Random seed (signal and noise)."),
    far_field: bool = typer.Option(False, "--far-field",
                                   help="Free field only: a plane wave from the source's "
                                   "direction instead of a spherical wave."),
    pcm16: bool = typer.Option(False, "--pcm16", help="Write 16-bit PCM instead of float32 (a "
                               ".flac: instead of 24-bit PCM, FLAC holds no floats)."),
    force: bool = typer.Option(False, "--force",
                               help="Overwrite output files that already exist."),
    poses: str | None = typer.Option(
        None, "--poses", help="Head poses 'PAN,TILT;PAN,TILT;...' in degrees: one capture per "
        "pose (OUT_pose<k>.wav) and OUT.yaml, a pose manifest with the ground truth for "
        "`hearsee localize3d`. --source is then in the robot frame (head pivot at the origin; "
        "--array-at puts the pivot in the room)."),
    head_offset: str | None = typer.Option(
        None, "--head-offset",
        help="With --poses: array origin relative to the head pivot (head frame), X,Y,Z m "
        "(default 0,0,0)."),
    hum: float | None = typer.Option(
        None, "--hum", help="Static --source: mains hum picked up by the wiring (the same "
        "waveform on every channel, harmonics up to 2.5 kHz) at this level in dB relative to "
        "the signal, -60 to 60 (default: none)."),
    hum_hz: float | None = typer.Option(None, "--hum-hz", help="With --hum: the hum's "
                                        "fundamental in Hz (50 or 60 where the mains are; "
                                        "default 50)."),
) -> None:
    """Simulate a recording of a static source (or a moving one: --trajectory; or one capture per
    head pose: --poses) and write OUT.wav + OUT.json (ground truth)."""
    from hearsee.audio.propagation import check_snr_db
    from hearsee.sim.audio import save_recording, simulate_recording

    if (source is None) == (trajectory is None):
        raise ConfigError("give either --source X,Y,Z (static source) or --trajectory FILE.csv "
                          "(moving source)")
    if trajectory is not None and poses is not None:
        raise ConfigError("--trajectory (moving source) cannot be combined with --poses")
    if head_offset is not None and poses is None:  # (it was ignored, even when malformed)
        raise ConfigError("--head-offset needs --poses (it places the array on the turning "
                          "head of a pose capture)")
    if hum is not None and (trajectory is not None or poses is not None):
        raise ConfigError("--hum applies to a static --source only (not with --trajectory or "
                          "--poses)")
    if hum_hz is not None and hum is None:  # (it was ignored: a recording without hum)
        raise ConfigError("--hum-hz sets the fundamental of the mains hum that --hum DB adds; "
                          "give --hum with it")
    _check_output(out, poses is not None)
    snr = check_snr_db(snr)  # (before the simulation: add_noise checks it only at its end)
    protect = [p for p in (signal, array) if Path(p).is_file()]  # inputs no output may replace
    if trajectory is None and duration is None:
        duration = DEFAULT_DURATION_S
    if poses is not None:
        from hearsee.audio.active import parse_poses, simulate_pose_manifest

        if far_field:
            raise ConfigError("--far-field does not apply with --poses")
        pose_list = parse_poses(poses)
        offset = parse_floats("0,0,0" if head_offset is None else head_offset, 3, "--head-offset")
        caps = [out.with_name(f"{out.stem}_pose{k}.wav") for k in range(len(pose_list))]
        refuse_overwrite([out, *caps, *(c.with_suffix(".json") for c in caps)], protect, force)
        man, files = simulate_pose_manifest(
            out, array, parse_floats(source, 3, "--source"), pose_list, signal=signal,
            duration_s=duration, fs=fs, snr_db=snr, room=_room_from_options(room, rt60, array_at),
            seed=seed, offset_m=offset,
            subtype="PCM_16" if pcm16 else "FLOAT",
            protect=protect)
        err_console.print(f"wrote {man} (pose manifest) and {len(files)} captures",
                          highlight=False)
        return

    if trajectory is not None:
        _simulate_moving(out, array, trajectory, signal, duration, fs, snr,
                         _room_from_options(room, rt60, array_at), seed, far_field, pcm16,
                         force, protect)
        return
    src = parse_floats(source, 3, "--source")
    room_spec = _room_from_options(room, rt60, array_at)
    refuse_overwrite([out, out.with_suffix(".json")], protect, force)
    with progress("simulating", total=1) as advance:
        x, truth = simulate_recording(array, src, signal=signal, duration_s=duration, fs=fs,
                                      snr_db=snr, room=room_spec, seed=seed,
                                      far_field=far_field, hum_db=hum,
                                      hum_hz=50.0 if hum_hz is None else hum_hz)
        advance()
    wav, js = save_recording(out, x, truth, subtype="PCM_16" if pcm16 else "FLOAT",
                             protect=protect)
    if truth["azimuth_deg"] is None:
        where = "direction undefined (source at the array-frame origin)"
    else:
        where = (f"azimuth {truth['azimuth_deg']:.1f} deg, elevation "
                 f"{truth['elevation_deg']:.1f} deg")
    err_console.print(
        f"wrote {wav} ({x.shape[0]} channels, {x.shape[1] / fs:.2f} s at {fs} Hz) and {js}: "
        f"{where}, distance {_metres(truth['distance_m'])} m",
        highlight=False,
    )
