"""Thesis appendix A regenerated: Zhang calibration of a real stereo rig from chessboard images
(figs. A.1-A.2, table A.1), compared with an independent reference calibration.

    python examples/appA_calibration.py [--data ../shared/data] [--square 0.025] [--figure out.png]

Uses ``../shared/data/vision/chessboard_stereo`` (25 pairs, 640x512, 9x6 inner corners) when
present: prints the calibration (RMS reprojection errors, intrinsics, extrinsics), compares
the focal lengths with ``reference_intrinsics.yml`` (the data author's OpenCV stereo_calib
result, read with cv2.FileStorage) and checks the rectification (vertical misalignment of
corresponding corners after rectification). The square size of that board is not documented;
lengths (baseline) scale with ``--square``. Without the data, the same chain runs on rendered
boards with a known rig and prints the recovery errors instead.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

from hearsee.vision import calibration as C
from hearsee.vision.camera import Camera, StereoRig, read_opencv_yaml
from hearsee.vision.io import read_image

PATTERN = (9, 6)


def rectified_row_error(rig: StereoRig, lp: list[np.ndarray], rp: list[np.ndarray]) -> tuple:
    """RMS and max |v_left - v_right| (pixels) of corresponding corners after rectification,
    and the median disparity; the rig must have its right camera on the right."""
    rect = rig.rectification
    dv, du = [], []
    for a, b in zip(lp, rp, strict=True):
        ra = cv2.undistortPoints(a.reshape(-1, 1, 2), rig.left.K, rig.left.dist, R=rect.R1,
                                 P=rect.P1).reshape(-1, 2)
        rb = cv2.undistortPoints(b.reshape(-1, 1, 2), rig.right.K, rig.right.dist, R=rect.R2,
                                 P=rect.P2).reshape(-1, 2)
        dv.append(ra[:, 1] - rb[:, 1])
        du.append(ra[:, 0] - rb[:, 0])
    dv = np.concatenate(dv)
    return float(np.sqrt(np.mean(dv ** 2))), float(np.abs(dv).max()), float(np.median(
        np.concatenate(du)))


def _pnp_rms(corners: np.ndarray, obj: np.ndarray, cam: Camera) -> float:
    """RMS reprojection error (px) of the best board pose for ``cam``'s intrinsics."""
    ok, rv, tv = cv2.solvePnP(obj, corners, cam.K, cam.dist)
    rv, tv = cv2.solvePnPRefineLM(obj, corners, cam.K, cam.dist, rv, tv)
    uv = cam.project(obj @ cv2.Rodrigues(rv)[0].T + tv.ravel())
    return float(np.sqrt(np.mean(np.sum((uv - corners) ** 2, axis=1))))


def real(data: Path, square: float, figure: Path | None) -> None:
    d = data / "vision" / "chessboard_stereo"
    lf = sorted(d.glob("left*.jpg"))
    rf = sorted(d.glob("right*.jpg"))
    res = C.calibrate_rig(lf, rf, PATTERN, square)
    rig = res.rig
    print(f"Calibration of {len(lf)} real stereo pairs ({d}):")
    n_found = sum(v.found_left and v.found_right for v in res.views)
    print(f"  board found in {n_found}/{len(lf)} pairs; rejected views: "
          f"{[Path(v.left).name for v in res.views if v.rejected] or 'none'}")
    print(f"  RMS reprojection error: left {res.rms_left_px:.3f} px, right "
          f"{res.rms_right_px:.3f} px, stereo {res.rms_stereo_px:.3f} px")
    errs = np.array([[v.err_stereo_left, v.err_stereo_right] for v in res.views])
    print(f"  per-image stereo RMS: median {np.nanmedian(errs):.3f} px, max "
          f"{np.nanmax(errs):.3f} px ({Path(res.views[int(np.nanargmax(errs.max(1)))].left).name})")
    for w in res.warnings:
        print(f"  note: {w}")
    ref = read_opencv_yaml(d / "reference_intrinsics.yml")
    ref_ext = read_opencv_yaml(d / "reference_extrinsics.yml")
    print("\nTable A.1 -- intrinsics vs the reference (OpenCV stereo_calib, rational model, "
          "fx = fy, same focal both cameras)")
    print(f"  {'camera':7s} {'fx':>8s} {'fy':>8s} {'cx':>8s} {'cy':>8s}   {'ref f':>8s} "
          f"{'ref cx':>8s} {'ref cy':>8s}   {'fx diff':>8s}")
    for name, cam, key in (("left", rig.left, "M1"), ("right", rig.right, "M2")):
        M = ref[key]
        print(f"  {name:7s} {cam.fx:8.2f} {cam.fy:8.2f} {cam.cx:8.2f} {cam.cy:8.2f}   "
              f"{M[0, 0]:8.2f} {M[0, 2]:8.2f} {M[1, 2]:8.2f}   "
              f"{100 * (cam.fx / M[0, 0] - 1):+7.2f} %")
    for name, cam, key in (("left", rig.left, "D1"), ("right", rig.right, "D2")):
        print(f"  {name} distortion (k1 k2 p1 p2 k3): {np.round(cam.dist, 4).tolist()}   "
              f"reference (k1 k2 p1 p2 k3 k4 k5 k6): {np.round(ref[key].ravel()[:8], 4).tolist()}")
    # how well does each calibration explain the detected corners? (one PnP pose per view)
    obj = C.board_points(PATTERN, square)
    for name, files, cam, key in (("left", lf, rig.left, "1"), ("right", rf, rig.right, "2")):
        ref_cam = Camera(ref["M" + key], ref["D" + key].ravel(), cam.width, cam.height)
        corners = [C.find_corners(read_image(f), PATTERN) for f in files]
        fits = [_pnp_rms(c, obj, k) for k in (cam, ref_cam) for c in corners if c is not None]
        n = len(fits) // 2
        print(f"  {name}: corners fit with a free pose per view: this calibration "
              f"{np.sqrt(np.mean(np.square(fits[:n]))):.3f} px RMS, reference "
              f"{np.sqrt(np.mean(np.square(fits[n:]))):.3f} px RMS")
    T_ref = ref_ext["T"].ravel()
    cos = float(rig.T @ T_ref / (np.linalg.norm(rig.T) * np.linalg.norm(T_ref)))
    ang = np.degrees(np.linalg.norm(cv2.Rodrigues(rig.R @ ref_ext["R"].T)[0]))
    print(f"\nExtrinsics: T = {np.round(rig.T, 4).tolist()} m (square {square * 1000:.1f} mm), "
          f"|T| = {rig.baseline_m * 1000:.1f} mm; reference T = {np.round(T_ref, 2).tolist()} "
          f"(author's units)")
    print(f"  direction agreement cos = {cos:.4f}; rotation differs from the reference by "
          f"{ang:.2f} deg; the reference |T| in mm would mean "
          f"{square * np.linalg.norm(T_ref) / rig.baseline_m:.1f} mm squares")
    work = rig.swapped() if rig.rectify().baseline_m < 0 else rig
    both = [i for i, v in enumerate(res.views) if v.found_left and v.found_right]
    lp, rp = [], []
    for i in both:
        a = C.find_corners(read_image(lf[i]), PATTERN)
        b = C.match_labeling(a, C.find_corners(read_image(rf[i]), PATTERN), PATTERN)
        lp.append(a)
        rp.append(b)
    if work is not rig:
        lp, rp = rp, lp
        print("  (the 'right' images come from the camera on the left: rectifying the swapped "
              "rig)")
    rms_v, max_v, med_d = rectified_row_error(work, lp, rp)
    rect = work.rectification
    print(f"Rectification: f = {rect.focal_px:.1f} px, baseline {rect.baseline_m * 1000:.1f} mm;"
          f" corresponding corners differ by {rms_v:.3f} px RMS (max {max_v:.2f} px) "
          f"vertically; median disparity {med_d:.1f} px")
    if figure is not None:
        _figure(work, lf, rf, both[0], work is not rig, figure)


def _figure(rig: StereoRig, lf, rf, i: int, swapped: bool, figure: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from hearsee.vision.stereo import rectify_pair

    L, R = read_image(lf[i], "bgr"), read_image(rf[i], "bgr")
    if swapped:
        L, R = R, L
    a = C.find_corners(L, PATTERN)
    b = C.find_corners(R, PATTERN)
    lr, rr, _ = rectify_pair(L, R, rig)
    fig, ax = plt.subplots(2, 2, figsize=(11, 8.5))
    for k, (img, c, title) in enumerate(((L, a, "left + corners"), (R, b, "right + corners"))):
        vis = cv2.drawChessboardCorners(img.copy(), PATTERN, c.reshape(-1, 1, 2), True)
        ax[0, k].imshow(cv2.cvtColor(vis, cv2.COLOR_BGR2RGB))
        ax[0, k].set_title(title)
    both = np.hstack([lr, rr])
    ax[1, 0].remove()
    ax[1, 1].remove()
    axb = fig.add_subplot(2, 1, 2)
    axb.imshow(cv2.cvtColor(both, cv2.COLOR_BGR2RGB))
    for y in range(20, both.shape[0], 40):
        axb.axhline(y, color="lime", lw=0.6)
    axb.set_title("rectified pair: corresponding points lie on the same row")
    for a_ in fig.axes:
        a_.set_xticks([])
        a_.set_yticks([])
    fig.tight_layout()
    Path(figure).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(figure, dpi=80)
    plt.close(fig)
    print(f"wrote {figure}")


def synthetic() -> None:
    """The same chain on rendered boards with a known rig."""
    cam = Camera(K=np.array([[300.0, 0, 158.0], [0, 301.0, 121.0], [0, 0, 1]]),
                 dist=[-0.2, 0.05, 0.0, 0.0, 0.0], width=320, height=240)
    truth = StereoRig.ideal(cam, 0.09)
    rays = C._subpixel_rays(cam, 2)
    rng = np.random.default_rng(0)
    obj = C.board_points(PATTERN, 0.025)
    lp, rp = [], []
    for _ in range(12):
        Rb = cv2.Rodrigues(rng.uniform(-0.5, 0.5, 3) * [1, 1, 0.3])[0]
        tb = np.array([0.045 + rng.uniform(-0.05, 0.05), rng.uniform(-0.04, 0.04),
                       rng.uniform(0.4, 0.5)]) - Rb @ np.array([0.1, 0.0625, 0])
        a = C.find_corners(C.render_chessboard(cam, Rb, tb, PATTERN, 0.025, rays=rays), PATTERN)
        b = C.find_corners(C.render_chessboard(cam, truth.R @ Rb, truth.R @ tb + truth.T,
                                               PATTERN, 0.025, rays=rays), PATTERN)
        if a is not None and b is not None:
            lp.append(a)
            rp.append(C.match_labeling(a, b, PATTERN))
    cl = C.calibrate_camera(lp, obj, cam.size)
    cr = C.calibrate_camera(rp, obj, cam.size)
    st = C.calibrate_stereo(lp, rp, obj, cl.camera, cr.camera)
    print(f"Synthetic rig ({len(lp)} views): RMS {st.rms_px:.3f} px; fx {st.rig.left.fx:.2f} "
          f"(true 300.00), baseline {st.rig.baseline_m * 1000:.2f} mm (true 90.00)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default=None, help="shared data folder (default ../shared/data)")
    ap.add_argument("--square", type=float, default=0.025, help="square size, metres")
    ap.add_argument("--figure", type=Path, default=None, help="write a PNG (figs. A.1-A.2)")
    args = ap.parse_args()
    data = Path(args.data) if args.data else Path(__file__).resolve().parents[1].parent / \
        "shared" / "data"
    cv2.setNumThreads(1)
    d = data / "vision" / "chessboard_stereo"
    need = [d / "left01.jpg", d / "reference_intrinsics.yml", d / "reference_extrinsics.yml"]
    if all(f.is_file() for f in need):
        real(data, args.square, args.figure)
    else:
        missing = next(f for f in need if not f.is_file())
        print(f"{missing} not found: running on synthetic boards"
              + (f" (no figure: {args.figure} needs the real images)" if args.figure else ""))
    synthetic()


if __name__ == "__main__":
    main()
