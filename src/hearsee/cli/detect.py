"""``hearsee detect``: find people in a stereo pair, confirmed by a thermal image (thesis ch. 7)."""

from __future__ import annotations

from pathlib import Path

import typer

from hearsee.cli._app import app, emit_json, refuse_overwrite
from hearsee.errors import ConfigError, ImageInputError


@app.command("detect")
def detect_cmd(
    left: str = typer.Option(..., "--left", help="Left image of the stereo pair (PNG, JPEG...)."),
    right: str = typer.Option(..., "--right", help="Right image of the stereo pair."),
    calib: str = typer.Option(..., "--calib",
                               help="Stereo rig calibration YAML (from `hearsee calibrate`)."),
    thermal: str | None = typer.Option(
        None, "--thermal",
        help="Thermal image of the rig's thermal camera: 8-bit (non-radiometric, relative band), "
             "16-bit PNG (centi-kelvin) or .npy (degC; an 8-bit one non-radiometric)."),
    fmt: str = typer.Option("json", "--format", help="json or table."),
    overlay: str | None = typer.Option(
        None, "--overlay",
        help="Write the rectified left image (the frame of the boxes) with the detections drawn "
             "to this file."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing --overlay file."),
    tm: float = typer.Option(0.5, "--tm", help="Head-shoulder score threshold Tm (0..1)."),
    min_support: float | None = typer.Option(
        None, "--min-support", help="With --thermal: thermal support needed to accept a "
        "candidate (0..1; default 0.3)."),
    camera_height: float | None = typer.Option(
        None, "--camera-height",
        help="Height of the left camera above the floor, metres, 0.1-5 (prior for the floor "
             "plane; default: info.camera_height_m of the calibration file)."),
    camera_pitch: float | None = typer.Option(
        None, "--camera-pitch",
        help="Pitch of the rectified left camera (the frame the floor is fitted in; the raw "
             "left camera's, whose frame the positions are in, is within the rectification's "
             "turn, ~1 deg) above the horizontal, degrees, + = looking up, -80 to 80 (prior "
             "for the floor plane; default: info.camera_pitch_deg of the calibration file, "
             "else level)."),
) -> None:
    """Detect humans: stereo candidates (P(y,d), head-shoulder template) confirmed by thermal.

    Prints {"humans": [{"box": [x, y, w, h], "position_m": [x, y, z], "score", "thermal_support",
    "truncated", "beyond_search"}], "rejected": [...]}: boxes in rectified left-image pixels
    (the image --overlay writes; the same as the raw left image only for a distortion-free,
    already rectified rig), positions in metres in the left camera's own optical frame
    (x right, y down, z forward);
    "truncated": the silhouette is cut by the top, left or right image border, so its position
    and height describe the visible part only; "beyond_search": part of the person stands
    nearer than the disparity search reaches (0.95 m with the default 64 disparities at
    f B = 60 px m) and the silhouette is broken up, so its position may be tens of cm off.
    """
    from hearsee.vision.camera import load_rig
    from hearsee.vision.fusion import detect_humans, draw_detections
    from hearsee.vision.humans import HumanDetectorParams
    from hearsee.vision.io import read_pair, write_image
    from hearsee.vision.thermal import load_thermal

    if fmt not in ("json", "table"):
        raise typer.BadParameter(f"--format must be json or table, got {fmt!r}")
    left_p, right_p, calib_p = Path(left), Path(right), Path(calib)
    # (an empty --thermal or --overlay, e.g. an unset "$THERMAL", was taken as none: people
    # were accepted without the thermal check without a word)
    thermal_p = Path(thermal) if thermal is not None else None
    overlay_p = Path(overlay) if overlay is not None else None
    if not 0.0 <= tm <= 1.0:
        raise typer.BadParameter(f"--tm must be in [0, 1], got {tm}")
    if min_support is not None and not 0.0 <= min_support <= 1.0:
        raise typer.BadParameter(f"--min-support must be in [0, 1], got {min_support}")
    if min_support is not None and thermal is None:  # (it was ignored: stereo alone decided)
        raise ConfigError("--min-support is the thermal support a candidate needs: give "
                          "--thermal with it (without a thermal image the stereo detector "
                          "alone decides)")
    if camera_height is not None and not 0.1 <= camera_height <= 5.0:
        raise typer.BadParameter(f"--camera-height must be in [0.1, 5] metres, got {camera_height}")
    if camera_pitch is not None and not -80.0 <= camera_pitch <= 80.0:  # (NaN fails it too)
        raise typer.BadParameter(f"--camera-pitch must be in [-80, 80] degrees, got "
                                 f"{camera_pitch}")
    refuse_overwrite([overlay_p], [left_p, right_p, calib_p, thermal_p], force)
    if overlay_p is not None:  # (else write_image refuses it only after the whole detection)
        import numpy as np

        from hearsee.vision.io import check_image_writable

        # (an 8-bit colour image, as draw_detections gives: .pgm or .hdr were refused only
        # after the detection; 64 px square: OpenCV's JPEG 2000 encoder cannot encode an
        # image smaller than 32 px, and a 2x2 probe refused --overlay out.jp2)
        check_image_writable(overlay_p, like=np.zeros((64, 64, 3), np.uint8))
    rig = load_rig(calib_p)
    L, R = read_pair(left_p, right_p, "bgr", expected_size=rig.left.size)
    th = None
    if thermal_p is not None:
        if rig.thermal is None:
            raise ImageInputError(
                f"{thermal}: a thermal image was given but {calib} has no thermal camera; add a "
                "'thermal:' block (camera, R, T) to the calibration or leave out --thermal"
            )
        th = load_thermal(thermal_p, expected_size=rig.thermal.size)
    res = detect_humans(L, R, rig, th, params=HumanDetectorParams(tm=tm),
                        **({} if min_support is None else {"min_support": min_support}),
                        camera_height_m=camera_height, camera_pitch_deg=camera_pitch)
    _warn_degenerate(res.frame.disparity, th)
    if overlay_p is not None:
        # the boxes are in rectified left-image pixels: draw them on that image
        write_image(overlay_p, draw_detections(res.frame.left, res))
    if fmt == "table":
        typer.echo(f"{'':9s}{'x':>5s}{'y':>5s}{'w':>5s}{'h':>5s}  {'X m':>7s}{'Y m':>7s}"
                   f"{'Z m':>7s}  {'score':>5s} {'thermal':>7s}  reason")
        for kind, items in (("human", res.humans), ("rejected", res.rejected)):
            for h in items:
                x, y, w, hh = h.box
                sup = "-" if h.thermal_support is None else f"{h.thermal_support:.2f}"
                p = h.position_m
                typer.echo(f"{kind:9s}{x:5d}{y:5d}{w:5d}{hh:5d}  {p[0]:7.2f}{p[1]:7.2f}{p[2]:7.2f}"
                           f"  {h.score:5.2f} {sup:>7s}  {h.reason}"
                           f"{' (cut by the image border)' if h.truncated else ''}"
                           f"{_BEYOND if h.beyond_search else ''}")
        typer.echo(f"{len(res.humans)} human(s), {len(res.rejected)} rejected candidate(s)")
        return
    emit_json(res.to_dict())


#: The table's note on a detection flagged beyond_search.
_BEYOND = " (nearer than the disparity search: position unreliable)"

#: Below this share of stereo-matched pixels ``hearsee detect`` warns. Simulated scenes match
#: 0.91-0.96 of their pixels, the same scenes with left and right swapped 0.18-0.22 (seeds 0-3).
MIN_MATCHED_SHARE = 0.3


def _warn_degenerate(disparity, thermal) -> None:
    """Warnings for inputs that make "0 humans" an answer about the input, not the scene
    (it was printed without a word): few stereo matches (swapped --left / --right, another
    rig's calibration, a textureless view) and a flat thermal image (no one can be verified)."""
    import warnings

    import numpy as np

    from hearsee.errors import DegenerateInputWarning

    matched = float(np.mean(np.isfinite(disparity) & (disparity > 0)))
    if matched < MIN_MATCHED_SHARE:
        warnings.warn(f"only {100 * matched:.0f} % of the pixels found a stereo match: are "
                      "--left and --right swapped, or the calibration another rig's?",
                      DegenerateInputWarning, stacklevel=2)
    if thermal is None:
        return
    if np.ptp(thermal) == 0:
        warnings.warn(f"the thermal image is flat (every pixel {thermal.flat[0]}): nobody can be "
                      "thermally verified", DegenerateInputWarning, stacklevel=2)
    elif thermal.dtype != np.uint8:
        # (a radiometric frame within FLAT_SPREAD_C is flat to the thermal filter too -- its
        # warm mask is emptied -- but only a frame flat to the digit was warned about: one
        # pixel 0.05 degC off and "0 human(s)" came without a word)
        from hearsee.vision.thermal import FLAT_SPREAD_C, counts_to_celsius

        t = counts_to_celsius(thermal) if thermal.dtype == np.uint16 else thermal
        spread = float(np.ptp(t))
        if spread < FLAT_SPREAD_C:
            warnings.warn(f"the thermal image is flat (its pixels span {spread:.3g} degC from "
                          f"{float(np.min(t)):.2f} degC, less than {FLAT_SPREAD_C:g}): nobody can "
                          "be thermally verified", DegenerateInputWarning, stacklevel=2)
