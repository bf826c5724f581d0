"""``hearsee localize3d``: 3D source position from captures taken at several head poses."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from hearsee.cli._app import GccMethod, app, emit_json, progress


@app.command("localize3d")
def localize3d_cmd(
    manifest: Annotated[Path, typer.Argument(
        help="Pose manifest YAML: array, optional channels and head {pivot_m, offset_m}, "
        "and captures "
        "[{file (or a list of files, one per microphone), pan_deg, tilt_deg}] (see "
        "hearsee.audio.active.PoseManifest; "
        "`hearsee simulate OUT.yaml --poses ...` writes one).")],
    frame_ms: float = typer.Option(64.0, "--frame-ms", help="GCC frame length in ms, at most "
                                   "10000."),
    hop_ms: float = typer.Option(32.0, "--hop-ms", help="GCC hop in ms, at most 10000."),
    method: GccMethod = typer.Option(GccMethod.phat, "--method", help="GCC weighting."),
) -> None:
    """Localize a static source in 3D (robot frame) from captures at several head poses.

    Prints JSON: position_m [x, y, z] (null when the poses do not fix the distance),
    azimuth_deg, elevation_deg, distance_m (from the head pivot), covariance (m^2), unique,
    every candidate when the answer is not unique (a single pose: the mirror pair, no distance),
    residual_rms_s and consistent (false, with a warning on stderr, when no single source
    explains the captures at the manifest's poses: a wrong pose angle, channel order or array).
    """
    from hearsee.audio.active import localize_manifest
    from hearsee.audio.tdoa import check_frame_ms

    check_frame_ms(frame_ms, hop_ms, names=("--frame-ms", "--hop-ms"))
    with progress("localizing", total=1) as advance:
        est = localize_manifest(manifest, frame_ms=frame_ms, hop_ms=hop_ms, method=method.value)
        advance()
    emit_json(est.to_dict())
