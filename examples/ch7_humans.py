"""Thesis ch. 7 regenerated: robust human detection with stereo and thermal cameras.

    python examples/ch7_humans.py [--out DIR | --figure PATH] [--scene-dir DIR]  # examples/out/

Builds one synthetic room (``hearsee.sim.scenes``) with a person, a mannequin, a poster
cut-out of a person and a coat on a stand, and runs

1. the stereo detector alone (P(y,d) -> scale-adaptive filter -> segmentation -> head-shoulder
   template, thesis 7.2): it accepts the human-shaped objects too (figs. 7.20-7.21);
2. stereo + thermal fusion (7.3-7.4): only the warm candidate survives;
3. the failure cases of fig. 7.22: a person just in from the cold (coat at 22 degC, hood and
   scarf covering the head) is rejected, and a mannequin warmed to 33 degC by a radiator is
   accepted.

With ``--scene-dir`` the first scene is also written as files, so that the CLI can be tried:
``hearsee detect --left DIR/left.png --right DIR/right.png --thermal DIR/thermal.png
--calib DIR/calib.yaml --format table``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

from hearsee.errors import ImageInputError
from hearsee.sim.scenes import Entity, SceneSpec, default_rig, render_scene, write_scene
from hearsee.vision.fusion import detect_humans, draw_detections
from hearsee.vision.io import check_image_writable


def room(person: dict | None = None, mannequin_c: float | None = None) -> SceneSpec:
    """The example room: a person, a mannequin, a poster cut-out and a coat on a stand."""
    man = {} if mannequin_c is None else {"temp_c": mannequin_c}
    return SceneSpec(
        entities=[Entity("person", -1.2, 3.2, 10.0, 1.78, dict(person or {})),
                  Entity("mannequin", -0.1, 4.2, 160.0, 1.75, man),
                  Entity("poster", 0.9, 2.6, 0.0, 1.8),
                  Entity("coat_stand", -2.3, 4.6, 30.0, 1.75),
                  Entity("radiator", -0.1, 5.4, 0.0, 0.6, {"width_m": 1.2, "depth_m": 0.1,
                                                          "lift_m": 0.12, "temp_c": 55.0})],
        width_left_m=3.5, width_right_m=3.5, depth_m=5.5, room_c=21.0, seed=7)


def report(title: str, scene, res) -> None:
    print(f"\n== {title}")
    names = {o.index: o.kind for o in scene.objects}
    for h in res.humans + res.rejected:
        # which ground-truth entity is it?
        near = min(scene.objects, key=lambda o: np.linalg.norm(o.position_m - h.position_m))
        if np.linalg.norm(near.position_m - h.position_m) > 0.4:
            continue  # walls, furniture
        what = names[near.index]
        sup = "-" if h.thermal_support is None else f"{h.thermal_support:.2f}"
        verdict = "HUMAN   " if h.accepted else "rejected"
        print(f"  {verdict} {what:10s} at {h.distance_m:4.1f} m  score {h.score:.2f}  "
              f"thermal {sup:>4s}  {h.reason}")


def main() -> None:
    ap = argparse.ArgumentParser(description="thesis ch. 7: stereo + thermal human detection")
    ap.add_argument("--out", default=str(Path(__file__).parent / "out"),
                    help="output folder (default: examples/out), as every example's")
    ap.add_argument("--figure", default=None,
                    help="output figure (PNG; default: ch7_humans.png in --out)")
    ap.add_argument("--scene-dir", default=None, help="also write the scene files here")
    args = ap.parse_args()
    if args.figure is None:
        args.figure = str(Path(args.out) / "ch7_humans.png")
    else:  # (cv2.imwrite raised, after every scene)
        try:
            check_image_writable(args.figure, like=np.zeros((2, 2, 3), np.uint8))
        except ImageInputError as exc:
            ap.error(f"--figure {exc}")
    cv2.setNumThreads(1)
    rig = default_rig()
    normal = render_scene(room(), rig)
    if args.scene_dir:
        write_scene(normal, args.scene_dir)
        print(f"scene written to {args.scene_dir}")
    stereo = detect_humans(normal.left, normal.right, rig)
    report("stereo only (7.2): human-shaped objects pass", normal, stereo)
    fused = detect_humans(normal.left, normal.right, rig, normal.thermal_c)
    report("stereo + thermal (7.4): only the warm one is human", normal, fused)
    cold = render_scene(room(person={"clothing_c": 22.5, "legs_c": 22.0, "covered_head": True}),
                        rig)
    cold_res = detect_humans(cold.left, cold.right, rig, cold.thermal_c)
    report("failure 1 (7.22): cold coat, covered head -> the person is missed", cold, cold_res)
    warm = render_scene(room(mannequin_c=33.0), rig)
    warm_res = detect_humans(warm.left, warm.right, rig, warm.thermal_c)
    report("failure 2 (7.22): mannequin warmed to 33 degC -> accepted", warm, warm_res)

    def thermal_view(scene):
        t = cv2.applyColorMap(scene.thermal_8bit, cv2.COLORMAP_INFERNO)
        return cv2.resize(t, (scene.left.shape[1], scene.left.shape[0]),
                          interpolation=cv2.INTER_NEAREST)

    def label(img, text):
        img = img.copy()
        cv2.putText(img, text, (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (255, 255, 255), 2,
                    cv2.LINE_AA)
        return img

    rows = [
        np.hstack([label(draw_detections(normal.left, stereo), "stereo only"),
                   label(draw_detections(normal.left, fused), "stereo + thermal")]),
        np.hstack([label(thermal_view(normal), "thermal (160x120, AGC)"),
                   label(draw_detections(cold.left, cold_res), "failure: cold coat")]),
        np.hstack([label(thermal_view(warm), "thermal: warm mannequin"),
                   label(draw_detections(warm.left, warm_res), "failure: warm mannequin")]),
    ]
    Path(args.figure).parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(args.figure, np.vstack(rows)):  # (False, not an error, on a bad path)
        sys.exit(f"could not write {args.figure}")
    print(f"\nfigure written to {args.figure}")


if __name__ == "__main__":
    main()
