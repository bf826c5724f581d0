"""``hearsee arrays``: list the microphone-array presets."""

from __future__ import annotations

import typer

from hearsee.cli._app import app, emit_json


@app.command("arrays")
def arrays_cmd(
    json_out: bool = typer.Option(False, "--json", help="Print the presets as JSON."),
) -> None:
    """List the microphone-array presets shipped with hearsee."""
    from hearsee.audio.arrays import MicArray, list_presets

    arrays = [MicArray.from_preset(n) for n in list_presets()]
    if json_out:
        emit_json({a.name: a.to_dict() for a in arrays})
        return
    for a in arrays:
        body = ""
        if a.mask is not None:  # (which presets resolve front/back: said nowhere in the list)
            yaw = float(a.mask.get("yaw_deg", 0.0))
            body = (f", rigid {a.mask.get('shape', 'egg')} mask between them"
                    + (f" turned {yaw:g} deg (left/right asymmetric)" if yaw else "")
                    + ": front/back resolved (ch. 3)")
        typer.echo(f"{a.name:14s} {a.n_mics} mics, aperture {a.aperture * 100:.1f} cm{body}")
