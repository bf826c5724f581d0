"""Regenerate hearsee's bundled example recording (``hearsee/data/examples/three-mic-speech.wav``).

Three-mic preset, synthetic female voice at azimuth 60 deg, elevation 10 deg, 2 m from the array
centre, in a 6 x 5 x 3 m shoebox room (RT60 0.3 s, array at the room centre), SNR 20 dB,
16 kHz, 3 s, 16-bit PCM. The ground truth goes to the ``.json`` file next to it.

    python examples/make_example_recording.py            # rewrites the bundled files
    python examples/make_example_recording.py OUT.wav    # writes elsewhere
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from hearsee.geometry import sph_to_cart
from hearsee.sim.audio import EXAMPLE_RECORDING, save_recording, simulate_recording

BUNDLED = Path(__file__).resolve().parents[1] / "src" / "hearsee" / "data" / "examples"


def main(out: Path) -> None:
    source = sph_to_cart(np.radians(60.0), np.radians(10.0), 2.0)
    x, truth = simulate_recording(
        "three-mic",
        source,
        signal="female",
        duration_s=3.0,
        fs=16000,
        snr_db=20.0,
        room={"room_dim": [6.0, 5.0, 3.0], "rt60": 0.3, "array_at": [3.0, 2.5, 1.5]},
        seed=0,
    )
    Path(out).parent.mkdir(parents=True, exist_ok=True)  # (as every other example's --out)
    wav, js = save_recording(out, x, truth, subtype="PCM_16")
    print(f"wrote {wav} ({wav.stat().st_size / 1000:.0f} kB) and {js}")
    print(f"truth: azimuth {truth['azimuth_deg']:.1f} deg, elevation "
          f"{truth['elevation_deg']:.1f} deg, TDOAs (s) {truth['tdoa_s']}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", nargs="?", type=Path, default=BUNDLED / EXAMPLE_RECORDING,
                    help="output .wav (default: the bundled example, rewritten)")
    main(ap.parse_args().out)
