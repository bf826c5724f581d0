"""``hearsee calibrate``: stereo (+ thermal) calibration from chessboard images."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from hearsee.cli._app import app, emit_json, err_console, progress, refuse_overwrite


def _fmt(v: float | None) -> str:
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.3f}"


@app.command("calibrate")
def calibrate_cmd(
    left: str = typer.Option(..., "--left", help="Left images: a quoted glob ('DIR/left*.jpg') "
                             "or a folder."),
    right: str = typer.Option(..., "--right", help="Right images (paired in natural order: "
                              "left2 before left10)."),
    output: str = typer.Option(..., "-o", "--output", help="Rig YAML file to write."),
    board: str = typer.Option("9x6", "--board", help="Inner corners per row x per column."),
    square: float = typer.Option(..., "--square", help="Side of one square, metres, 0.001-2 "
                                 "(e.g. 0.025 for 25 mm)."),
    thermal: str | None = typer.Option(None, "--thermal", help="Thermal images of the same "
                                       "board (one per pair): adds the thermal camera."),
    model: str = typer.Option("standard", "--model",
                              help="Distortion model: radial, simple, standard or rational."),
    fix_aspect: bool = typer.Option(False, "--fix-aspect", help="Force fx = fy."),
    reference: str | None = typer.Option(None, "--reference", help="OpenCV FileStorage YAML "
                                          "with camera matrices M1 / M2 (as OpenCV's "
                                          "stereo_calib writes): the focal lengths and "
                                          "principal points are compared with them."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output file."),
    json_out: bool = typer.Option(False, "--json", help="Print the result as JSON."),
) -> None:
    """Calibrate a stereo rig (and optionally a thermal camera) from chessboard images.

    Prints the RMS reprojection error and the error of every image, and writes the rig in
    hearsee's calibration YAML format (see hearsee.vision.camera).
    """
    from hearsee.errors import CalibrationError, ConfigError
    from hearsee.vision.calibration import calibrate_rig, parse_board
    from hearsee.vision.camera import save_rig
    from hearsee.vision.io import glob_images, read_image

    # (1e300 or 1e-300 reached OpenCV: a RuntimeWarning and an "Assertion failed" message)
    if not 1e-3 <= square <= 2.0:
        raise CalibrationError(f"--square must be the side of one square in metres, 0.001 to 2 "
                               f"(e.g. 0.025 for 25 mm), got {square}")
    if model not in ("radial", "simple", "standard", "rational"):
        raise ConfigError(f"--model must be radial, simple, standard or rational, got {model!r}")
    pattern = parse_board(board)
    lf = glob_images(left, "left images")
    rf = glob_images(right, "right images")
    # (an empty --thermal was taken as none: a rig without its thermal camera, without a word)
    tf = glob_images(thermal, "thermal images") if thermal is not None else None
    out = Path(output)
    refuse_overwrite([out], [*lf, *rf, *(tf or []), reference], force)
    # read the reference first: a bad file fails before the calibration and the output
    ref_cams = (_read_reference(Path(reference), read_image(lf[0]).shape[::-1])
                if reference is not None else None)

    total = len(lf) + len(rf) + (len(tf) if tf else 0)
    with progress("detecting chessboards", total) as advance:
        res = calibrate_rig(lf, rf, pattern, square, thermal_files=tf, model=model,
                            fix_aspect=fix_aspect, progress=advance)
    save_rig(res.rig, out)

    comparison = _compare(res.rig, ref_cams) if ref_cams is not None else None
    if json_out:
        emit_json({
            "output": str(out),
            "rms_px": {"left": res.rms_left_px, "right": res.rms_right_px,
                       "stereo": res.rms_stereo_px, "thermal": res.rms_thermal_px,
                       "thermal_extrinsics": res.rms_thermal_extrinsics_px},
            "baseline_m": res.rig.baseline_m,
            "left": res.rig.left.to_dict(), "right": res.rig.right.to_dict(),
            "views": [vars(v) for v in res.views],
            "reference": comparison,
            "warnings": res.warnings,
        })
    else:
        _print_report(res, out, comparison)
    for w in res.warnings:
        # (the CLI's one form of a warning, cli.main: "warning: ..." alone was not it)
        err_console.print(f"hearsee: warning: {w}", style="yellow", markup=False, highlight=False)


def _read_reference(reference: Path, size: tuple[int, int]) -> dict:
    """The camera matrices ``{"M1": K, "M2": K}`` (3x3, pixels) of an OpenCV
    stereo_calib-style FileStorage file (at least one of them), each checked as a camera of the
    images' ``size`` (width, height; the file holds none: checked against 640x480, a 4K
    camera's principal point was "outside the image")."""
    from hearsee.errors import CalibrationError, ConfigError
    from hearsee.vision.camera import Camera, read_opencv_yaml

    ref = read_opencv_yaml(reference)
    out = {}
    for key in ("M1", "M2"):
        if key not in ref:
            continue
        if getattr(ref[key], "shape", None) != (3, 3):
            raise ConfigError(f"{reference}: {key} is not a 3x3 matrix")
        try:  # (an all-zero or NaN matrix gave divide warnings and an inf/null comparison)
            Camera(ref[key], width=size[0], height=size[1])
        except CalibrationError as exc:
            raise ConfigError(f"{reference}: {key}: {exc}") from None
        out[key] = ref[key]
    if not out:
        raise ConfigError(f"{reference}: no M1 or M2 camera matrix to compare with")
    return out


def _compare(rig, ref: dict) -> dict:
    """Focal lengths and principal points (pixels) against the reference camera matrices
    (:func:`_read_reference`)."""
    out = {}
    for key, cam in (("M1", rig.left), ("M2", rig.right)):
        if key not in ref:
            continue
        M = ref[key]
        out["left" if key == "M1" else "right"] = {
            "fx": cam.fx, "fy": cam.fy, "ref_fx": float(M[0, 0]), "ref_fy": float(M[1, 1]),
            "fx_diff_pct": 100.0 * (cam.fx / M[0, 0] - 1.0),
            "fy_diff_pct": 100.0 * (cam.fy / M[1, 1] - 1.0),
            "cx": cam.cx, "cy": cam.cy, "ref_cx": float(M[0, 2]), "ref_cy": float(M[1, 2]),
        }
    return out


def _print_report(res, out: Path, comparison: dict | None) -> None:
    from rich.console import Console
    from rich.table import Table

    # (no markup: file names are text -- 'l[1].png' was shown as 'l.png', and 'rig[v2].yaml'
    # as 'wrote rig.yaml')
    con = Console(soft_wrap=True, markup=False)
    has_t = res.rig.thermal is not None
    t = Table(title="Per-image RMS reprojection error (pixels)")
    for h in ("left image", "right image", "left", "right", "stereo L", "stereo R"):
        t.add_column(h)
    if has_t:
        t.add_column("thermal")
    for v in res.views:
        row = [Path(v.left).name, Path(v.right).name,
               _fmt(v.err_left) if v.found_left else "no board",
               _fmt(v.err_right) if v.found_right else "no board",
               _fmt(v.err_stereo_left), _fmt(v.err_stereo_right)]
        if has_t:
            row.append(_fmt(v.err_thermal) if v.found_thermal else "no board")
        if v.rejected:
            row[2] += " (rejected)"
        if has_t and v.rejected_thermal:  # (left out of the thermal calibration)
            row[-1] += " (rejected)"
        t.add_row(*row)
    con.print(t)
    rig = res.rig
    con.print(f"RMS reprojection error: left {res.rms_left_px:.3f} px, right "
              f"{res.rms_right_px:.3f} px, stereo {res.rms_stereo_px:.3f} px", highlight=False)
    if has_t:
        con.print(f"thermal: intrinsics {res.rms_thermal_px:.3f} px, extrinsics "
                  f"{res.rms_thermal_extrinsics_px:.3f} px", highlight=False)
    for name, cam in (("left", rig.left), ("right", rig.right)):
        con.print(f"{name:5s}: fx {cam.fx:.2f}  fy {cam.fy:.2f}  cx {cam.cx:.2f}  cy {cam.cy:.2f}"
                  f"  dist {[round(float(x), 4) for x in cam.dist]}", highlight=False)
    con.print(f"baseline {rig.baseline_m:.4f} m, T = {[round(float(x), 4) for x in rig.T]} m",
              highlight=False)
    if comparison:
        for side, c in comparison.items():
            con.print(f"vs reference {side}: fx {c['fx']:.2f} vs {c['ref_fx']:.2f} "
                      f"({c['fx_diff_pct']:+.2f} %), fy {c['fy']:.2f} vs {c['ref_fy']:.2f} "
                      f"({c['fy_diff_pct']:+.2f} %)", highlight=False)
    con.print(f"wrote {out}", highlight=False)
